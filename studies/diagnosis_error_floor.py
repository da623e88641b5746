"""How far can the error fall? The floor the surrogates' own error sets for the diagnosis's
"error after / before" (the fitted model against a set's noise-free values, RMSE of relative
errors over the programme's rows).

For truths drawn as the validation draws them (synthetic.draw_truth, the validation programme),
per candidate effect: the effect's own size (RMS over the rows of the relative shift it makes,
f(truth) / f(truth without it) - 1), the nets' error at the truth (the error model's net part,
RMS of e / f over the rows: what even a perfect fit keeps), each quantity's share of that floor,
and the ratio a perfect diagnosis would reach, floor / sqrt(shift^2 + floor^2) (medians over
the draws).

    .venv/bin/python studies/diagnosis_error_floor.py [--stores ...] [--draws 150] [--label default]

Writes studies/results/diagnosis_error_floor_<label>.txt. ~30 s on one core."""
from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from pydem.calibration import synthetic  # noqa: E402
from pydem.calibration.setup import DEFAULT_STORES, load_setup  # noqa: E402


def floor_table(setup, draws: int, seed: int = 1) -> list[str]:
    obs = synthetic.programme(setup.nets)
    rng = np.random.default_rng(seed)
    lines = []
    for cand in setup.candidates:
        share: dict[str, list[float]] = {}
        floors, shifts = [], []
        for _ in range(draws):
            truth = synthetic.draw_truth(rng, setup.ranges, setup.candidates, cand.name)
            base = synthetic.Truth(truth.theta, None, None, None)
            v1 = synthetic.surrogate_values(setup.nets, setup.candidates, truth, obs)
            v0 = synthetic.surrogate_values(setup.nets, setup.candidates, base, obs)
            xs = synthetic.row_inputs(setup.nets, setup.candidates, truth, obs)
            e2 = []
            for i, o in enumerate(obs):
                e = float(setup.nets[o.quantity].errors_at(xs[i])[1][0]) / abs(v1[i])
                e2.append(e * e)
                share.setdefault(o.quantity.key, []).append(e * e)
            floors.append(math.sqrt(np.mean(e2)))
            shifts.append(math.sqrt(np.mean([(v1[i] / v0[i] - 1.0) ** 2 for i in range(len(obs))])))
        f, s = np.array(floors), np.array(shifts)
        lines.append(f"{cand.name}: effect's shift {np.median(s):.4f}, nets' error floor {np.median(f):.4f}, "
                     f"best after/before {np.median(f / np.sqrt(s * s + f * f)):.2f} (medians over {draws} truths)")
        total = sum(np.sum(v) for v in share.values())
        for q, v in sorted(share.items()):
            lines.append(f"    {q:28s} share of the floor {np.sum(v) / total:5.2f}   RMS e/f {math.sqrt(np.mean(v)):.4f}")
    return lines


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--stores", nargs="+", default=[str(ROOT / s) for s in DEFAULT_STORES])
    ap.add_argument("--draws", type=int, default=150)
    ap.add_argument("--label", default="default")
    args = ap.parse_args()
    setup = load_setup(args.stores, say=lambda *_: None)
    lines = floor_table(setup, args.draws)
    out = ROOT / f"studies/results/diagnosis_error_floor_{args.label}.txt"
    out.write_text("\n".join(lines) + "\n")
    print("\n".join(lines))
    print(f"-> {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
