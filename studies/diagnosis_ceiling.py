"""The best top-1 rate any method can reach on the hidden-effect protocol (docs/diagnosis.md §7).

For each surrogate-generated set of `diagnosis_validation.py` (same seeds, same draws) it takes
the set's *signal*: the base model's chi^2 at its best fit to the set's noise-free values, the
noncentrality of the likelihood-ratio test of the true effect. An oracle that knows which effect
is hidden and tests only it, at the loop's level (alpha = 0.01; one-sided for cohesion), finds it
with probability P(noncentral chi^2_1(signal) > critical value): the Neyman-Pearson bound for one
parameter. Summed over the sets it is the expected top-1 count no diagnosis can beat at that false-
alarm level. Two versions:

- with the likelihood's sigma (the rows' uncertainty, the rig's seed scatter and the nets' own
  error): the ceiling with these surrogates;
- with the nets' own error set to zero: the ceiling of the protocol itself (its conditions, its
  lab noise and the rigs' seed scatter), whatever the surrogates.

    .venv/bin/python studies/diagnosis_ceiling.py --preset default --sets 30
    .venv/bin/python studies/diagnosis_ceiling.py --preset default --sets 30 --floor 0   # strengths from 0
    .venv/bin/python studies/diagnosis_ceiling.py --preset default --dem   # the DEM-made sets' truths

With --dem, the sets are those of the committed DEM-made journals (`dem_sets_default*.jsonl`): each
set's signal is taken on the surrogates at its truth with its rows' stated uncertainties (the
rigs' own mean response is unknown), and the oracle is set beside the verdicts in
`*.diagnosed.json`.

Writes studies/results/diagnosis_ceiling_<label>.json and prints the table."""
from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np
from scipy import stats

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import results_json  # noqa: E402
from pydem.calibration import synthetic  # noqa: E402
from pydem.calibration.setup import load_setup, shipped_stores  # noqa: E402
from pydem.calibration.surrogates import QuantityNet  # noqa: E402

ALPHA = 0.01


def oracle_power(signal: float, one_sided: bool) -> float:
    """P(the true effect's LR test rejects at ALPHA) for noncentrality `signal`."""
    crit = stats.chi2.isf(2 * ALPHA if one_sided else ALPHA, 1)
    return float(stats.ncx2.sf(crit, 1, max(signal, 1e-12)))


def without_net_error(fn):
    """Runs fn() with every net's own error at (almost) zero: sigma = max(u, seed scatter)."""
    original = QuantityNet.errors_at

    def seed_only(self, x):
        seed, err = original(self, x)
        return seed, 1e-6 * err
    QuantityNet.errors_at = seed_only
    try:
        return fn()
    finally:
        QuantityNet.errors_at = original


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--preset", default="default")
    ap.add_argument("--sets", type=int, default=30, help="sets per candidate effect")
    ap.add_argument("--seed", type=int, default=1, help="as diagnosis_validation.py's --seed: the same sets")
    ap.add_argument("--floor", type=float, default=None,
                    help="smallest strength as a fraction of neutral-to-edge (default: the protocol's)")
    ap.add_argument("--label", help="results name (default: the preset, with the floor when given)")
    ap.add_argument("--dem", action="store_true", help="the DEM-made journals' sets instead of surrogate ones")
    args = ap.parse_args()
    stores = [ROOT / s for s in shipped_stores(args.preset)]
    setup = load_setup([s for s in stores if s.exists()], say=lambda *a: None)
    if args.dem:
        return dem_ceiling(setup, args)
    t0 = time.perf_counter()
    rows = []
    floor = 0.2 if args.floor is None else args.floor  # draw_truth's default: the protocol's
    for c, k, truth, obs in synthetic.effect_sets(setup, args.sets, args.seed, min_fraction=floor):
        s_nets = synthetic.signal(setup, truth, obs)
        s_exact = without_net_error(lambda: synthetic.signal(setup, truth, obs))
        one = c.side == "+"
        rows.append({"effect": c.name, "set": k, "strength": truth.strength, "signal": s_nets,
                     "signal_without_net_error": s_exact,
                     "power": oracle_power(s_nets, one), "power_without_net_error": oracle_power(s_exact, one)})
        print(f"  {c.name:14s} #{k:2d} strength {truth.strength:9.4g}  signal {s_nets:7.1f} "
              f"(exact nets {s_exact:7.1f})  oracle {rows[-1]['power']:.2f} / {rows[-1]['power_without_net_error']:.2f}",
              flush=True)
    table = {}
    for c in setup.candidates:
        r = [x for x in rows if x["effect"] == c.name]
        table[c.name] = {"sets": len(r), "oracle_top1": sum(x["power"] for x in r),
                         "oracle_top1_without_net_error": sum(x["power_without_net_error"] for x in r),
                         "median_signal": float(np.median([x["signal"] for x in r])),
                         "median_signal_without_net_error": float(np.median([x["signal_without_net_error"] for x in r]))}
    label = args.label or (args.preset if args.floor is None else f"{args.preset}_floor{args.floor:g}")
    return results_json.report(
        f"diagnosis_ceiling_{label}", table, rows, t0,
        f"\nexpected top-1 of an oracle at alpha {ALPHA} ({args.sets} sets per effect):",
        lambda _, t: f"with these nets {t['oracle_top1']:5.1f} ({t['oracle_top1'] / t['sets']:.0%})   "
                     f"nets exact {t['oracle_top1_without_net_error']:5.1f} ({t['oracle_top1_without_net_error'] / t['sets']:.0%})   "
                     f"median signal {t['median_signal']:.1f} / {t['median_signal_without_net_error']:.1f}")


def dem_ceiling(setup, args) -> int:
    """The oracle's expected top-1 on the DEM-made sets' truths, beside the loop's verdicts."""
    from pydem.calibration.quantities import Quantity
    t0 = time.perf_counter()
    rows = []
    for journal in sorted((ROOT / "studies/results").glob("dem_sets_default*.jsonl")):
        diagnosed = journal.with_suffix(".diagnosed.json")
        if not diagnosed.exists():
            continue
        verdicts = {v["set"]: v for v in json.loads(diagnosed.read_text())}
        for k, line in enumerate(journal.read_text().splitlines()):
            row = json.loads(line)
            c = next((c for c in setup.candidates if c.name == row["kind"]), None)
            if c is None or k not in verdicts:
                continue
            v = verdicts[k]
            truth, obs = synthetic.journal_set(row, setup.nets, setup.candidates, np.random.default_rng(5000 + k),
                                               keep=lambda r: Quantity(r["rig"], r["metric"]) in setup.nets)
            s = synthetic.signal(setup, truth, obs)
            rows.append({"journal": journal.name, "set": k, "effect": c.name, "strength": truth.strength, "signal": s,
                         "power": oracle_power(s, c.side == "+"), "named": v["effect"] == c.name})
    table = {c.name: {"sets": sum(r["effect"] == c.name for r in rows),
                      "oracle_top1": sum(r["power"] for r in rows if r["effect"] == c.name),
                      "loop_top1": sum(r["named"] for r in rows if r["effect"] == c.name)} for c in setup.candidates}
    return results_json.report(
        f"diagnosis_ceiling_{args.label or args.preset}_dem", table, rows, t0,
        f"DEM-made sets: expected top-1 of an oracle at alpha {ALPHA} (signal on the surrogates) and the loop's:",
        lambda _, t: f"{t['sets']} sets: oracle {t['oracle_top1']:.1f}, loop {t['loop_top1']}")


if __name__ == "__main__":
    sys.exit(main())
