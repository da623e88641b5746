"""Writes the golden MLP fixture for tests/c/test_mlp.c: a seeded random net (3 inputs, 9 tanh
units) in the dem-mlp weights format and 64 random inputs with torch float64 outputs, all as
hex floats. Regenerate: .venv/bin/python scripts/make_mlp_fixture.py"""
from pathlib import Path

import numpy as np
import torch

from nn.export import write_weights
from nn.mlp import MLP, PropertyNet, Scaler

out = Path(__file__).resolve().parents[1] / "tests" / "data" / "mlp"
out.mkdir(parents=True, exist_ok=True)
torch.manual_seed(11)
model = MLP(3, 9)
with torch.no_grad():
    for p in model.parameters():
        p.mul_(3.0)  # pre-activations well into tanh's curved and saturated parts
net = PropertyNet("golden", ["friction", "rolling_friction", "restitution"],
                  Scaler(np.array([0.05, 0.0, 0.2]), np.array([1.0, 0.6, 0.9])), Scaler(np.array([0.3]), np.array([0.8])),
                  model, "-")
write_weights(net, out / "golden.mlp")
x = np.random.default_rng(12).uniform([-0.5, -0.3, 0.0], [1.5, 0.9, 1.1], size=(64, 3))  # also outside the box
y = net.predict(x)
with open(out / "golden_io.txt", "w") as fh:
    fh.write("# x0 x1 x2 y (torch float64), hex floats\n")
    for row, v in zip(x, y):
        fh.write(" ".join(float(a).hex() for a in row) + " " + float(v).hex() + "\n")
print(f"written {out}")
