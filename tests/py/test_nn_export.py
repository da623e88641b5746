"""Export of a trained net: the weights file round-trips exactly through libdem (load, save,
read back), libdem's inference (reference and blocked paths) and the standalone C99 pair agree
with torch float64 within 1e-12 relative on random inputs (DESIGN section 7; agreement is
~1e-15: different summation order, tanh within an ulp or two), and native screening keeps
exactly the rows numpy keeps."""
import subprocess

import numpy as np
import pytest

from nn.export import arrays_of, read_weights, weights_text, write_c, write_weights
from nn.mlp import select_net
from pydem.errors import DemFormatError, DemIOError
from pydem.mlp import NativeMLP, screen

NAMES = ["friction", "rolling_friction", "restitution"]


@pytest.fixture(scope="module")
def net():
    rng = np.random.default_rng(0)
    x = rng.uniform([0.05, 0.0, 0.2], [1.0, 0.6, 0.9], size=(80, 3))
    y = 0.35 + 0.25 * np.tanh(2 * x[:, 0]) + 0.3 * x[:, 1] + 0.01 * x[:, 2]
    n, _ = select_net("mu_ie_ps", NAMES, x, y, sizes=[6], restarts=1)
    return n


@pytest.fixture(scope="module")
def inputs():
    return np.random.default_rng(1).uniform([-0.2, -0.1, 0.0], [1.3, 0.8, 1.0], size=(5000, 3))


def test_weights_round_trip_exact(net, tmp_path):
    path = write_weights(net, tmp_path / "a.mlp")
    native = NativeMLP(path)
    assert (native.name, native.hidden, native.input_names) == ("mu_ie_ps", net.hidden, NAMES)
    native.save(tmp_path / "b.mlp")
    back = read_weights(tmp_path / "b.mlp")
    a, b = arrays_of(net), arrays_of(back)
    for k in ("lo", "hi", "y_lo", "y_hi", "w1", "b1", "w2", "b2"):
        assert np.array_equal(getattr(b, k), getattr(a, k)), k
    assert weights_text(back) == weights_text(net)
    in_memory = NativeMLP(text=weights_text(net))  # dem_mlp_parse: the same net without a file
    x = np.random.default_rng(0).uniform(0, 1, (50, 3))
    assert np.array_equal(in_memory(x), native(x))
    for a, b in ((net.x_scaler, back.x_scaler), (net.y_scaler, back.y_scaler)):
        assert np.array_equal(a.lo, b.lo) and np.array_equal(a.hi, b.hi)


def test_native_inference_matches_torch(net, inputs, tmp_path):
    native = NativeMLP(write_weights(net, tmp_path / "n.mlp"))
    ref = net.predict(inputs)
    for got in (native.eval_reference(inputs), native(inputs, 1), native(inputs, 2)):
        assert np.max(np.abs(got - ref) / np.abs(ref)) < 1e-12
    assert np.array_equal(native(inputs, 1), native(inputs, 2))  # rows are independent: bitwise


def test_standalone_c_matches_torch(net, inputs, tmp_path):
    h, c = write_c(net, tmp_path)
    main = tmp_path / "main.c"
    main.write_text(f'#include "{h.name}"\n#include <stdio.h>\nint main(void) {{ double x[3];\n'
                    '  while (scanf("%la %la %la", &x[0], &x[1], &x[2]) == 3) printf("%a\\n", mlp_mu_ie_ps(x));\n'
                    '  return 0; }\n')
    exe = tmp_path / "run"
    subprocess.run(["gcc", "-std=c99", "-Wall", "-Wextra", "-Wpedantic", "-Werror", "-O2", str(main), str(c),
                    "-o", str(exe), "-lm"], check=True)
    text = "\n".join(" ".join(float(v).hex() for v in row) for row in inputs[:500])
    out = subprocess.run([str(exe)], input=text, capture_output=True, text=True, check=True).stdout.split()
    got = np.array([float.fromhex(v) for v in out])
    ref = net.predict(inputs[:500])
    assert np.max(np.abs(got - ref) / np.abs(ref)) < 1e-12


def test_screen_matches_numpy(net, inputs, tmp_path):
    a = NativeMLP(write_weights(net, tmp_path / "a.mlp"))
    ref = net.predict(inputs)
    target = float(np.median(ref))
    keep, pred = screen([a, a], [target, target], [0.05, 0.2], inputs, num_threads=2)
    assert np.array_equal(keep, np.abs(pred[:, 0] - target) <= 0.05 * abs(target))
    assert 0 < keep.sum() < len(keep)


def test_bad_weights_files(tmp_path):
    with pytest.raises(DemIOError, match="missing.mlp"):
        NativeMLP(tmp_path / "missing.mlp")
    bad = tmp_path / "bad.mlp"
    bad.write_text("dem-mlp 1\nname x\nunit -\ninputs 2 a b\nhidden 2\ninput_lo 0 0\ninput_hi 1 oops\n")
    with pytest.raises(DemFormatError, match=r"line 7 \(input_hi\): expected 2 numbers, found 1"):
        NativeMLP(bad)
