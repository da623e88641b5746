"""Does the report's "smallest detectable effect" tell which hidden effects get named?

For the surrogate-generated sets of `diagnosis_validation.py` (same seeds, same draws) it runs the
diagnosis and compares each set's true strength with the smallest effect of its kind that the
set's own measurements would detect (detectability.py, at the set's base fit): a set whose
effect lies beyond that limit should be named in about 90 % of cases or more, one inside it
rarely.

    .venv/bin/python studies/diagnosis_detectability.py --preset default --sets 30

Writes studies/results/diagnosis_detectability_<preset>.json and prints the table."""
from __future__ import annotations

import sys
import time
from pathlib import Path


ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import effect_set_args  # noqa: E402
import results_json  # noqa: E402
from pydem.calibration import synthetic  # noqa: E402
from pydem.calibration.diagnose import diagnose  # noqa: E402


def beyond(strength: float, info: dict) -> bool:
    """The true strength lies at or beyond the smallest detectable effect on its side."""
    if strength >= info["neutral"]:
        return info.get("above") is not None and strength >= info["above"]
    return info.get("below") is not None and strength <= info["below"]


def main() -> int:
    args, setup = effect_set_args.parse_and_load(__doc__)
    t0 = time.perf_counter()
    rows = []
    for c, k, truth, obs in synthetic.effect_sets(setup, args.sets, args.seed):
        d = diagnose(f"{c.name}-{k}", obs, setup.nets, setup.ranges, setup.candidates, say=lambda *a: None)
        info = d.detectable[c.name]
        rows.append({"effect": c.name, "set": k, "strength": truth.strength, "named": d.effect == c.name,
                     "verdict": d.verdict, "detectable": info, "beyond": beyond(truth.strength, info)})
        print(f"  {c.name:14s} #{k:2d} strength {truth.strength:9.4g}  limits {info.get('below')} / {info.get('above')}"
              f"  beyond {rows[-1]['beyond']!s:5s}  named {rows[-1]['named']}", flush=True)
    table = {}
    for c in setup.candidates:
        r = [x for x in rows if x["effect"] == c.name]
        out = [x for x in r if x["beyond"]]
        inn = [x for x in r if not x["beyond"]]
        table[c.name] = {"beyond": [sum(x["named"] for x in out), len(out)], "within": [sum(x["named"] for x in inn), len(inn)]}
    return results_json.report(
        f"diagnosis_detectability_{args.preset}", table, rows, t0,
        "\nnamed / sets, by whether the true effect lies beyond the smallest detectable one:",
        lambda _, t: f"beyond {t['beyond'][0]}/{t['beyond'][1]}   within {t['within'][0]}/{t['within'][1]}")


if __name__ == "__main__":
    sys.exit(main())
