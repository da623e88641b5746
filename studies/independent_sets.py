"""Diagnosis sets made by the rigs independently of the stores' making (docs/diagnosis.md, "Sets
the stores never saw"): other seeds, another programme of conditions, truths drawn off the
stores' design points, a wall friction a little off the particle friction as real materials
have, single effects between half and twice the detection limit the diagnosis states for the
set's programme, and sets with two effects at once.

Two steps, so the expensive part runs once. `run` draws each set's truth and runs the rigs on
the programme, appending one line per set to a journal (resumable: a rerun does the sets the
journal lacks; `--part i/n` splits the sets over n processes, each with its own journal).
`diagnose` adds lab-like noise (seeded per set), writes each set as a measurement file and runs
`pydem diagnose` of a given checkout on it (so the rules of an earlier commit can be scored on
the same files), keeping what the verdicts need in one JSON; `summary` tabulates false alarms,
top-1, error fall and coverage (the truth inside the final model's 95 % intervals).

    .venv/bin/python studies/independent_sets.py run --journal studies/results/independent_sets_1.jsonl --part 1/2
    .venv/bin/python studies/independent_sets.py diagnose --journals studies/results/independent_sets_*.jsonl \
        --label new --out studies/results/independent_sets.new.json [--checkout DIR] [--no-origin]
    .venv/bin/python studies/independent_sets.py summary studies/results/independent_sets.*.json

With `--refine N --runs DIR` the diagnose step refines each set (`pydem diagnose --refine N`, the
runs kept in DIR/set<k>.refine, so an interrupted validation resumes run by run) and keeps both
passes; `summary` then scores the first pass too (the refinement's validation, docs/diagnosis.md §8):

    .venv/bin/python studies/independent_sets.py diagnose --journals studies/results/independent_sets_*.jsonl \
        --label refined16 --out studies/results/independent_sets.refined16.json --refine 16 --runs build/refine_runs16
    (and --refine-design fixed --runs build/refine_runs_fixed for the simple alternative on the same budget;
    `summary A.json B.json --common` scores both on the sets they share)

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
from pydem.calibration.verdicts import ALARMS  # noqa: E402
from pydem.quantity_table import TEST_OF_RIG  # noqa: E402

PRESHEAR = (1000.0, 2000.0, 5000.0)
FRACTIONS = (0.45, 0.7)
SLOTS = (0.036, 0.047, 0.059, 0.070)
WALL_OFFSET = 0.05  # |wall friction - particle friction| of a null material, at most
# the sets, in journal order: 12 nulls, 3 of each single effect, 3 with two effects
KINDS = (["null"] * 12 + ["cohesion_sjkr"] * 3 + ["wall_friction"] * 3 + ["size_spread"] * 3
         + ["cohesion_sjkr+wall_friction", "cohesion_sjkr+size_spread", "wall_friction+size_spread"])
SEED = 7000
# the order the sets are run in, so that a run cut short still has every kind: eight nulls, then
# the effect sets interleaved (one of each single effect and a two-effect set per round), then the
# last four nulls; `--part i/n` takes every n-th set of this order
ORDER = list(range(8)) + [12, 21, 15, 18, 13, 22, 16, 19, 14, 23, 17, 20] + [8, 9, 10, 11]
# the order sets are diagnosed in when each costs DEM runs (--refine): the twelve first (three
# nulls and three of each single effect, one of each per round), then the two-effect sets, then the
# other nulls, so a validation cut short has scored a balanced share
REFINE_ORDER = [0, 12, 15, 18, 1, 13, 16, 19, 2, 14, 17, 20, 21, 22, 23] + list(range(3, 12))


def programme(nets) -> list[Observation]:
    return synthetic.programme(nets, preshear=PRESHEAR, fractions=FRACTIONS, slots=SLOTS)


def detection_limits(setup, theta: dict, obs: list[Observation], inputs: dict) -> dict:
    """The smallest detectable effect of every candidate, as the diagnosis would state it for this
    programme at this truth: its base model fitted to the surrogates' noise-free values there."""
    values = synthetic.surrogate_values(setup.nets, setup.candidates, synthetic.Truth(theta, None, None, None), obs)
    clean = [Observation(o.quantity, dict(o.conditions), values[i], synthetic.noise_sd(o.quantity.metric, values[i]),
                         o.label, origin="dem") for i, o in enumerate(obs)]
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
    for k in ORDER[part - 1::parts]:
        kind = KINDS[k]
        if k in done:
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


def measurement_file(path: Path, row: dict, origin: bool):
    """The set as a measurement file: each rig value with lab-like noise (synthetic.noise_sd; the
    same draw whatever the rules scored), the noise as its uncertainty, and with `origin` the
    column saying each row is one DEM run."""
    rng = np.random.default_rng(SEED + 1000 + row["set"])
    lines = [f"# independent set {row['set']} ({row['kind']}): truth {row['inputs']}",
             "material,test,quantity,value,uncertainty,unit,conditions,use,source" + (",origin" if origin else "")]
    for r in row["rows"]:
        if r["value"] is None:
            continue
        n = synthetic.noise_sd(r["metric"], r["value"])
        v = max(r["value"] + rng.normal(0.0, n), 1e-3 * abs(r["value"]))
        cond = ";".join(f"{k}={x:.6g}" for k, x in r["conditions"].items())
        lines.append(f"set{row['set']},{TEST_OF_RIG[r['rig']]},{r['metric']},{v:.8g},{n:.6g},,{cond},calibrate,independent"
                     + (",dem" if origin else ""))
    path.write_text("\n".join(lines) + "\n")


def diagnose(args):
    """Each journal's sets diagnosed by `pydem diagnose` of the checkout; one JSON of the results."""
    import subprocess
    import tempfile
    checkout = Path(args.checkout).resolve()
    rows = sorted((json.loads(x) for j in args.journals for x in Path(j).read_text().splitlines()),
                  key=lambda r: REFINE_ORDER.index(r["set"]) if args.refine else r["set"])
    out = {"label": args.label, "checkout": str(checkout), "origin_column": not args.no_origin, "sets": []}
    if Path(args.out).exists():  # resumable: the sets diagnosed already are kept
        out["sets"] = [s for s in json.loads(Path(args.out).read_text())["sets"] if "error" not in s]
    done = {s["set"] for s in out["sets"]}
    if args.sets:  # these sets only (e.g. those whose refinement runs are done, scored by another checkout)
        rows = [r for r in rows if r["set"] in args.sets]
    with tempfile.TemporaryDirectory() as tmp:
        for row in rows:
            if row["set"] in done:
                continue
            meas = Path(tmp) / f"set{row['set']}.csv"
            measurement_file(meas, row, not args.no_origin)
            res = (Path(args.runs) if args.refine else Path(tmp)) / f"set{row['set']}"
            refine = (["--refine", str(args.refine), "--workers", str(args.workers), "--refine-design", args.refine_design]
                      if args.refine else [])
            t0 = time.perf_counter()
            run_ = subprocess.run([sys.executable, "-m", "pydem", "diagnose", str(meas), "--material", f"set{row['set']}",
                                   "--out", str(res), *refine], cwd=checkout, capture_output=True, text=True,
                                  env={**__import__("os").environ, "PYTHONPATH": str(checkout)})
            if run_.returncode != 0:
                out["sets"].append({"set": row["set"], "kind": row["kind"], "error": run_.stderr[-500:]})
                continue
            d = json.loads((res / "diagnosis.json").read_text())
            effects = d.get("effects") or ([d["effect"]] if d.get("effect") else [])
            cover = covered({n: (p.get("lo"), p.get("hi")) for n, p in d["parameters"].items()}, row["inputs"])
            out["sets"].append({"set": row["set"], "kind": row["kind"], "truth_effects": row["effects"], "verdict": d["verdict"],
                                "effects": effects, "p_best": d["candidates"][0]["p_value"] if d["candidates"] else None,
                                "best": d["candidates"][0]["effect"] if d["candidates"] else None,
                                "rmse_before": d["before"]["rmse_relative"],
                                "rmse_after": d["after"]["rmse_relative"] if d.get("after") else None,
                                "chi2_before": d["before"]["chi2_per_dof"], "covered": cover,
                                "seconds": time.perf_counter() - t0})
            ref = d["context"].get("refinement")
            if ref:  # the first pass, scored as the sets were before refinement
                first = ref["first_pass"]
                out["sets"][-1]["first_pass"] = {"verdict": first["verdict"], "effects": first["effects"],
                                                 "rmse_before": first.get("rmse_before"), "rmse_after": first.get("rmse_after"),
                                                 "covered": covered(first.get("intervals", {}), row["inputs"])}
                out["sets"][-1]["refinement"] = refinement_record(ref)
            s = out["sets"][-1]
            print(f"set {row['set']:2d} {row['kind']:28s} -> {s['verdict']:18s} {'+'.join(effects) or '-':28s} "
                  f"covered {sum(cover.values())}/{len(cover)}", flush=True)
            Path(args.out).write_text(json.dumps(out, indent=1))


def refinement_record(ref: dict) -> dict:
    """What the validation keeps of a diagnosis's refinement: runs, failures, CPU, the per-quantity
    check of the correction, and each row's surrogate error in both passes beside its uncertainty."""
    return {"runs": ref["runs"], "failed": len(ref["failed"]), "cpu_seconds": ref["cpu_seconds"],
            "quantities": ref["quantities"],
            "rows": [{k: x[k] for k in ("label", "uncertainty", "net_error_first", "net_error_second")} for x in ref["rows"]]}


def rows_with_u(s: dict) -> list[dict]:
    """A refined set's recorded rows that state a measurement uncertainty."""
    return [x for x in s["refinement"].get("rows", []) if x["uncertainty"]]


def rows_below_u(rows: list[dict]) -> tuple[int, int]:
    """How many rows' surrogate error is below their uncertainty: (first pass, refined)."""
    return tuple(sum(x[k] < x["uncertainty"] for x in rows) for k in ("net_error_first", "net_error_second"))


def surrogate_error(refined: list[dict]) -> str:
    """The rows' surrogate error against their measurement uncertainty, first pass and refined: how
    many rows it is below, and the median refined / first ratio, in all and per quantity (the sets
    that recorded rows)."""
    rows = [x for s in refined for x in rows_with_u(s)]
    if not rows:
        return "  (no per-row surrogate errors recorded)"

    def figures(xs) -> str:
        below = rows_below_u(xs)
        ratio = np.median([x["net_error_second"] / x["net_error_first"] for x in xs if x["net_error_first"] > 0])
        return f"below u in {below[0]} -> {below[1]} of {len(xs)} rows, refined / first {ratio:.2f}"
    per_quantity = {}
    for x in rows:
        per_quantity.setdefault(x["label"].split(" (")[0], []).append(x)
    return (f"  surrogate error (first pass -> refined, {sum('rows' in s['refinement'] for s in refined)} sets): "
            f"{figures(rows)}\n" + "\n".join(f"    {q}: {figures(xs)}" for q, xs in sorted(per_quantity.items())))


def covered(intervals: dict, truth: dict) -> dict:
    """{parameter: the truth inside its 95 % interval} for the parameters with both."""
    return {n: bool(lo <= truth[n] <= hi) for n, (lo, hi) in intervals.items()
            if truth.get(n) is not None and lo is not None}


EFFECTS = ("cohesion_sjkr", "wall_friction", "size_spread")


def score(sets: list[dict]) -> dict:
    """One pass's figures over scored sets (each with kind, verdict, effects, rmse_before/after,
    covered): false alarms on the nulls with their 95 % interval, top-1 per single effect, two-effect
    sets with both named, the median error after / before, and coverage per parameter."""
    from scipy import stats
    nulls = [s for s in sets if s["kind"] == "null"]
    fa = sum(bool(s["effects"]) or s["verdict"] in ALARMS for s in nulls)
    interval = (stats.beta.ppf(0.025, fa, len(nulls) - fa + 1) if fa else 0.0,
                stats.beta.ppf(0.975, fa + 1, len(nulls) - fa) if fa < len(nulls) else 1.0)
    top1 = {e: [s["effects"][:1] == [e] for s in sets if s["kind"] == e] for e in EFFECTS}
    double = [sorted(s["effects"]) == sorted(s["kind"].split("+")) for s in sets if "+" in s["kind"]]
    ratio = [s["rmse_after"] / s["rmse_before"] for s in sets
             if s["kind"] != "null" and s.get("rmse_after") and s.get("rmse_before")]
    names = sorted({n for s in sets for n in s["covered"]})
    return {"nulls": len(nulls), "false_alarms": fa, "false_alarm_interval": interval,
            "top1": {e: (sum(v), len(v)) for e, v in top1.items()}, "both": (sum(double), len(double)),
            "error_ratio": float(np.median(ratio)) if ratio else None,
            "coverage": {n: (sum(s["covered"][n] for s in sets if n in s["covered"]),
                             sum(n in s["covered"] for s in sets)) for n in names}}


def score_line(label: str, sc: dict) -> str:
    cov = sum(a for a, _ in sc["coverage"].values()), sum(b for _, b in sc["coverage"].values())
    lo, hi = sc["false_alarm_interval"]
    return (f"{label}: false alarms {sc['false_alarms']}/{sc['nulls']} (95 % interval {lo:.2f}-{hi:.2f}); top-1 "
            + ", ".join(f"{e} {a}/{b}" for e, (a, b) in sc["top1"].items())
            + f"; two-effect sets with both {sc['both'][0]}/{sc['both'][1]}; error after/before median "
            + (f"{sc['error_ratio']:.2f}" if sc["error_ratio"] is not None else "-")
            + f"; coverage {cov[0]}/{cov[1]} ({100 * cov[0] / max(cov[1], 1):.0f} %): "
            + ", ".join(f"{n} {a}/{b}" for n, (a, b) in sc["coverage"].items()))


def summary(args):
    """Each results file scored (score); for a refined validation the first pass of the same sets
    too, the runs and CPU time per set, and with --markdown a per-set table. With --common, only the
    sets every file holds (two designs compared on the same sets)."""
    files = [json.loads(Path(path).read_text()) for path in args.results]
    common = set.intersection(*({s["set"] for s in r["sets"]} for r in files))
    table = []  # the refined sets' Markdown lines, every file's
    for r in files:
        sets = [s for s in r["sets"] if "error" not in s and (not args.common or s["set"] in common)]
        print(score_line(r["label"], score(sets)) + f"; failed sets {sum('error' in s for s in r['sets'])}"
              + (f"; sets {' '.join(str(s['set']) for s in sets)}" if args.common else ""))
        refined = [s for s in sets if "first_pass" in s]
        if not refined:
            continue
        first = [s | s["first_pass"] for s in refined]
        print(score_line("  their first pass", score(first)))
        runs = [s["refinement"]["runs"] for s in refined]
        cpu = [s["refinement"]["cpu_seconds"] / 3600 for s in refined]
        print(f"  refinement runs per set {np.median(runs):.0f} (median; {sum(s['refinement']['failed'] for s in refined)} "
              f"failed in all), their CPU {np.median(cpu):.2f} h per set (median, max {max(cpu):.2f}); whole refined "
              f"diagnosis {np.median([s['seconds'] for s in refined]) / 3600:.2f} h of wall time per set (median)")
        print(surrogate_error(refined))
        table += [markdown_row(r["label"], s) for s in refined]
    if args.markdown and table:
        head = ["| results | set | kind | first pass | refined | error after/before: first, refined | coverage: first, "
                "refined | rows with surrogate error < u: first, refined | runs (failed) | run CPU (h) | wall (h) |",
                "|---|---|---|---|---|---|---|---|---|---|---|"]
        Path(args.markdown).write_text("\n".join(head + table) + "\n")
        print(f"per-set table: {args.markdown}")


def markdown_row(label: str, s: dict) -> str:
    """One refined set's line of the summary's Markdown table."""
    f = s["first_pass"]
    ratio = lambda d: f"{d['rmse_after'] / d['rmse_before']:.2f}" if d.get("rmse_after") else "-"  # noqa: E731
    cov = lambda c: f"{sum(c.values())}/{len(c)}"  # noqa: E731
    rows = rows_with_u(s)
    below = ", ".join(f"{n}/{len(rows)}" for n in rows_below_u(rows)) if rows else "-"
    return (f"| {label} | {s['set']} | {s['kind']} | {'+'.join(f['effects']) or f['verdict']} | "
            f"{'+'.join(s['effects']) or s['verdict']} | {ratio(f)}, {ratio(s)} | {cov(f['covered'])}, "
            f"{cov(s['covered'])} | {below} | {s['refinement']['runs']} ({s['refinement']['failed']}) | "
            f"{s['refinement']['cpu_seconds'] / 3600:.2f} | {s['seconds'] / 3600:.2f} |")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("run")
    r.add_argument("--journal", required=True)
    r.add_argument("--part", default="1/1", help="i/n: every n-th set of ORDER, from the i-th")
    dg = sub.add_parser("diagnose")
    dg.add_argument("--journals", nargs="+", required=True)
    dg.add_argument("--label", required=True)
    dg.add_argument("--out", required=True)
    dg.add_argument("--checkout", default=str(ROOT), help="the pydem to score (default: this one)")
    dg.add_argument("--no-origin", action="store_true", help="files without the origin column (older readers)")
    dg.add_argument("--refine", type=int, default=0, help="refinement runs per set (pydem diagnose --refine)")
    dg.add_argument("--runs", default="build/refine_runs", help="where each set's output and refinement runs are kept")
    dg.add_argument("--workers", type=int, default=2, help="worker processes of each set's refinement runs")
    dg.add_argument("--refine-design", default="greedy", choices=("greedy", "fixed"), help="pydem diagnose --refine-design")
    dg.add_argument("--sets", nargs="+", type=int, help="these sets only")
    sm = sub.add_parser("summary")
    sm.add_argument("results", nargs="+")
    sm.add_argument("--markdown", help="a refined validation's per-set table, as Markdown, into this file")
    sm.add_argument("--common", action="store_true", help="only the sets every results file holds")
    args = ap.parse_args()
    {"run": run, "diagnose": diagnose, "summary": summary}[args.cmd](args)
    return 0


if __name__ == "__main__":
    sys.exit(main())
