"""Diagnosis sets made by the rigs independently of the stores' making (docs/diagnosis.md, "Sets
the stores never saw"): other seeds, another programme of conditions, truths drawn off the
stores' design points, a wall friction a little off the particle friction as real materials
have, single effects between half and twice the detection limit the diagnosis states for the
set's programme, and sets with two effects at once.

Two steps, so the expensive part runs once. `run` draws each set's truth and runs the rigs on
the programme, appending one line per set to a journal (resumable: a rerun does the sets the
journal lacks; `--part i/n` splits the sets over n processes, each with its own journal).
`diagnose` adds lab-like noise and scores the diagnosis (studies/independent_sets_score.py).

    .venv/bin/python studies/independent_sets.py run --journal studies/results/independent_sets.jsonl --part 1/2

The programme: ring shear at pre-shear 1, 2 and 5 kPa with shear points at 45 and 70 % (the
stores shear at 30, 60 and 90 %), the angle of repose with its poured bulk density, the hopper at
slot widths 36, 47, 59 and 70 mm. Seeds 7000 + set: no store ran them."""
from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from pydem.calibration import confirm, synthetic  # noqa: E402
from pydem.calibration.calibrate import fit_base  # noqa: E402
from pydem.calibration.candidates import BASE_PARAMETERS  # noqa: E402
from pydem.calibration.detectability import detectable_effects  # noqa: E402
from pydem.calibration.diagnose import ALPHA  # noqa: E402
from pydem.calibration.quantities import Observation  # noqa: E402
from pydem.calibration.setup import DEFAULT_STORES, load_setup  # noqa: E402

PRESHEAR = (1000.0, 2000.0, 5000.0)
FRACTIONS = (0.45, 0.7)
SLOTS = (0.036, 0.047, 0.059, 0.070)
WALL_OFFSET = 0.05  # |wall friction - particle friction| of a null material, at most
# the sets, in journal order: 12 nulls, 3 of each single effect, 3 with two effects
KINDS = (["null"] * 12 + ["cohesion_sjkr"] * 3 + ["wall_friction"] * 3 + ["size_spread"] * 3
         + ["cohesion_sjkr+wall_friction", "cohesion_sjkr+size_spread", "wall_friction+size_spread"])
SEED = 7000


def programme(nets) -> list[Observation]:
    return synthetic.programme(nets, preshear=PRESHEAR, fractions=FRACTIONS, slots=SLOTS)


def detection_limits(setup, theta: dict, obs: list[Observation], inputs: dict) -> dict:
    """The smallest detectable effect of every candidate, as the diagnosis would state it for this
    programme at this truth: its base model fitted to the surrogates' noise-free values there."""
    values = synthetic.surrogate_values(setup.nets, setup.candidates, synthetic.Truth(theta, None, None, None), obs)
    clean = [Observation(o.quantity, dict(o.conditions), values[i], synthetic.noise_sd(o.quantity.metric, values[i]),
                         o.label) for i, o in enumerate(obs)]
    model, fit = fit_base(clean, setup.nets, setup.ranges, setup.candidates)
    return detectable_effects(model, fit, setup.candidates, setup.nets, setup.ranges, setup.candidates, ALPHA)


def draw(setup, k: int, kind: str, obs: list[Observation]) -> dict:
    """One set's truth: base parameters uniform in the box, a null's wall friction within
    WALL_OFFSET of its particle friction; each named effect at f x its detection limit's distance
    from neutral (f log-uniform in [0.5, 2] for one effect, [1, 2] for two), on the side a real
    material has (cohesion and a wider size spread above, wall friction either side)."""
    rng = np.random.default_rng(SEED + k)
    ranges = setup.ranges
    theta = {n: float(rng.uniform(*ranges[n])) for n in BASE_PARAMETERS}
    inputs = dict(theta)
    for c in setup.candidates:
        inputs[c.parameter] = c.neutral_value(theta)
    lo, hi = ranges["wall_friction"]
    inputs["wall_friction"] = float(np.clip(theta["friction"] + rng.uniform(-WALL_OFFSET, WALL_OFFSET), lo, hi))
    effects = [] if kind == "null" else kind.split("+")
    limits = detection_limits(setup, theta, obs, inputs) if effects else {}
    named = {}
    for name in effects:
        c = next(c for c in setup.candidates if c.name == name)
        lim = limits[name]
        sides = [s for s in ("above", "below") if lim.get(s) is not None] if name == "wall_friction" else ["above"]
        side = sides[int(rng.integers(len(sides)))] if sides else "above"
        neutral = c.neutral_value(theta)
        lo, hi = ranges[c.parameter]
        edge = hi if side == "above" else lo
        limit = lim.get(side)
        f = float(np.exp(rng.uniform(math.log(0.5) if len(effects) == 1 else 0.0, math.log(2.0))))
        value = neutral + f * ((limit if limit is not None else edge) - neutral)
        inputs[c.parameter] = named[name] = float(np.clip(value, lo, hi))
    return {"set": k, "kind": kind, "theta": theta, "inputs": inputs, "effects": named,
            "limits": {n: {s: limits[n].get(s) for s in ("below", "above")} for n in limits}}


def run(args):
    setup = load_setup([ROOT / s for s in DEFAULT_STORES], say=lambda *_: None)
    obs = programme(setup.nets)
    part, parts = (int(x) for x in args.part.split("/"))
    journal = Path(args.journal)
    done = {json.loads(x)["set"] for x in journal.read_text().splitlines()} if journal.exists() else set()
    for k, kind in enumerate(KINDS):
        if k % parts != part - 1 or k in done:
            continue
        t0 = time.perf_counter()
        truth = draw(setup, k, kind, obs)
        values = confirm.rig_values(setup.stores, truth["inputs"], obs, seed=SEED + k, threads=1, say=lambda *_: None)
        truth["rows"] = [{"rig": o.quantity.rig, "metric": o.quantity.metric, "conditions": o.conditions,
                          "label": o.label, "value": values.get(i)} for i, o in enumerate(obs)]
        truth["dem_seconds"] = time.perf_counter() - t0
        with open(journal, "a") as f:
            f.write(json.dumps(truth) + "\n")
        print(f"set {k} ({kind}) {truth['effects']}: {sum(r['value'] is not None for r in truth['rows'])} of "
              f"{len(obs)} rows, {truth['dem_seconds']:.0f} s", flush=True)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("run")
    r.add_argument("--journal", required=True)
    r.add_argument("--part", default="1/1", help="i/n: the sets k with k mod n = i - 1")
    args = ap.parse_args()
    run(args)
    return 0


if __name__ == "__main__":
    sys.exit(main())
