"""Does the test the report suggests reveal effects the measurements missed?

For the surrogate-generated effect sets of `diagnosis_validation.py` (same seeds, same draws)
whose effect the diagnosis did not name, one more test is made at the set's truth (surrogate
values + the nets' error + one run's seed scatter + lab noise, as the set's other rows) and the
set diagnosed again: (a) the test the report suggests for the hidden effect's candidate
(`detectable[effect]["measure_next"]`), (b) as a control, a test drawn at random from the same
list (`detectability.candidate_tests`). The user does not know which effect is hidden: (a) uses
the suggestion for the true one, so it answers "if you suspect this effect, does the suggested
test find it more often than another test would?"

    .venv/bin/python studies/diagnosis_next_test.py --preset default --sets 30

Writes studies/results/diagnosis_next_test_<preset>.json and prints the table."""
from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import effect_set_args  # noqa: E402
import results_json  # noqa: E402
from pydem.calibration import synthetic  # noqa: E402
from pydem.calibration.detectability import candidate_tests  # noqa: E402
from pydem.calibration.diagnose import diagnose  # noqa: E402


def with_test(setup, truth, obs, rows, rng):
    """The set's rows plus one more test made at the truth the way the set was."""
    extra, _ = synthetic.surrogate_set_and_means(setup.nets, setup.candidates, truth, rng, rows, True)
    return obs + extra


def main() -> int:
    args, setup = effect_set_args.parse_and_load(__doc__)
    quiet = {"say": lambda *a: None}
    t0 = time.perf_counter()
    rows = []
    for c, k, truth, obs in synthetic.effect_sets(setup, args.sets, args.seed):
        d = diagnose(f"{c.name}-{k}", obs, setup.nets, setup.ranges, setup.candidates, **quiet)
        if d.effect == c.name:
            continue
        tests = dict(candidate_tests(obs, setup.nets))
        suggested = (d.detectable.get(c.name) or {}).get("measure_next")
        extra_rng = np.random.default_rng([args.seed, 77, sum(map(ord, c.name)), k])
        control = list(tests)[int(extra_rng.integers(len(tests)))]
        row = {"effect": c.name, "set": k, "strength": truth.strength, "verdict": d.verdict,
               "suggested": suggested and suggested["test"], "control": control}
        for key, label in (("named_suggested", row["suggested"]), ("named_control", control)):
            if label is None:
                row[key] = None
                continue
            # the same draw for both tests' noise: only the test differs
            more = with_test(setup, truth, obs, tests[label], np.random.default_rng([args.seed, 78, k]))
            row[key] = diagnose(f"{c.name}-{k}+", more, setup.nets, setup.ranges, setup.candidates, **quiet).effect == c.name
        rows.append(row)
        print(f"  {c.name:14s} #{k:2d} {d.verdict:17s} + {row['suggested']}: {row['named_suggested']}   "
              f"+ {control}: {row['named_control']}", flush=True)
    table = {c.name: {"missed": sum(r["effect"] == c.name for r in rows),
                      "named_with_suggested": sum(bool(r["named_suggested"]) for r in rows if r["effect"] == c.name),
                      "named_with_control": sum(bool(r["named_control"]) for r in rows if r["effect"] == c.name)}
             for c in setup.candidates}
    return results_json.report(
        f"diagnosis_next_test_{args.preset}", table, rows, t0,
        "\nof the sets whose effect was missed, named after one more test:",
        lambda _, t: f"missed {t['missed']}: the suggested test {t['named_with_suggested']}, "
                     f"a random one {t['named_with_control']}")


if __name__ == "__main__":
    sys.exit(main())
