"""Hidden-effect sets made by the rigs themselves at their default presets, in two steps so the
expensive part runs once: `run` draws a truth per set (base parameters uniform in the campaign
box, the named effect at a random strength, or none), runs the rigs on the validation
programme (ring shear at 1, 2, 5 kPa with shear points 40/60/80 %, the angle of repose, the
hopper at three slot widths) and appends the raw values to a journal (resumable: one line per
set); `diagnose` adds the lab noise, writes each set as a measurement file and runs the
diagnosis on the given stores.

    .venv/bin/python studies/diagnosis_dem_sets.py run --kinds null cohesion_sjkr --journal studies/results/dem_sets_default.jsonl
    .venv/bin/python studies/diagnosis_dem_sets.py diagnose --journal studies/results/dem_sets_default.jsonl
    .venv/bin/python studies/diagnosis_dem_sets.py diagnose --journal studies/results/dem_sets_default.jsonl --kinds null \
        --density-factor 1.25 --out studies/results/dem_sets_default.density125.diagnosed.json
    .venv/bin/python studies/diagnosis_dem_sets.py rerun --rig aor --journal studies/results/dem_sets_default.jsonl
    .venv/bin/python studies/diagnosis_dem_sets.py summary      (every studies/results/dem_sets_default*.diagnosed.json)
"""
from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from pydem.calibration import confirm, synthetic  # noqa: E402
from pydem.calibration.quantities import Observation, Quantity  # noqa: E402
from pydem.calibration.setup import DEFAULT_STORES, load_setup  # noqa: E402
from pydem.quantity_table import metric_spec  # noqa: E402



# Physical effects that no store varies, so the diagnosis cannot name them: a set with one on is
# the protocol's "effect that is not a candidate" made by the rigs themselves (beside the
# density mismatch, a scaling). The range: twisting friction over the rolling friction's
# campaign range, 0.1-0.6 (docs/effects.md; mu_t 0.6 moved the heap by -3 deg, docs/rigs.md).
NOT_CANDIDATES = {"twisting_resistance": ("effects.twisting_resistance.twisting_friction", (0.1, 0.6))}


def run(args):
    setup = load_setup(args.stores, say=lambda *_: None)
    journal = Path(args.journal)
    done = len(journal.read_text().splitlines()) if journal.exists() else 0
    for k, kind in enumerate(args.kinds):
        if k < done:
            continue
        rng = np.random.default_rng(args.seed + k)
        hidden = NOT_CANDIDATES.get(kind)
        truth = synthetic.draw_truth(rng, setup.ranges, setup.candidates, None if kind == "null" or hidden else kind)
        extra = {}
        if hidden:  # the base model's truth, plus an effect no candidate represents
            parameter, (lo, hi) = hidden
            truth = synthetic.Truth(truth.theta, kind, parameter, float(rng.uniform(lo, hi)))
            extra = {parameter: truth.strength}
        obs = synthetic.programme(setup.nets)
        values = confirm.rig_values(setup.stores, truth.inputs(setup.candidates), obs, seed=1000 + k, threads=1,
                                      extra=extra)
        row = {"kind": kind, "truth": {"theta": truth.theta, "effect": truth.effect, "parameter": truth.parameter,
                                        "strength": truth.strength},
               "rows": [{"rig": o.quantity.rig, "metric": o.quantity.metric, "conditions": o.conditions,
                         "label": o.label, "value": values.get(i)} for i, o in enumerate(obs)]}
        with open(journal, "a") as f:
            f.write(json.dumps(row) + "\n")
        print(f"set {k} ({kind}) done: {sum(r['value'] is not None for r in row['rows'])} of {len(obs)} rows", flush=True)


def rerun(args):
    """Runs one rig's rows of every set again at the rig's current preset (after a preset change:
    the angle of repose's slow lift), same truths and seeds; the other rows are kept. The journal
    is rewritten whole after each set (resumable: a set already rerun at this preset is skipped)."""
    from pydem.calibration.candidates import registry
    from pydem.calibration.setup import open_stores
    from pydem.campaign.runner import resolved_config
    stores = open_stores(args.stores)  # the stores' presets only: no nets needed
    journal = Path(args.journal)
    lines = [json.loads(x) for x in journal.read_text().splitlines()]
    for k, row in enumerate(lines):
        rig = args.rig
        stamp = resolved_config(stores[rig].spec)
        if row.get("rerun", {}).get(rig) == stamp:
            continue
        t = row["truth"]
        truth = synthetic.Truth(t["theta"], t["effect"], t["parameter"], t["strength"])
        idx = [i for i, r in enumerate(row["rows"]) if r["rig"] == rig]
        obs = [Observation(Quantity(rig, row["rows"][i]["metric"]), row["rows"][i]["conditions"], math.nan, math.nan,
                           row["rows"][i]["label"]) for i in idx]
        values = confirm.rig_values(stores, truth.inputs(registry()), obs, seed=1000 + k, threads=1)
        for j, i in enumerate(idx):
            row["rows"][i]["value"] = values.get(j)
        row.setdefault("rerun", {})[rig] = stamp
        tmp = journal.with_suffix(".tmp")
        tmp.write_text("".join(json.dumps(x) + "\n" for x in lines))
        tmp.replace(journal)
        print(f"set {k} ({row['kind']}): {rig} rows rerun: " + ", ".join(f"{obs[j].quantity.metric} {values.get(j)}"
                                                                         for j in range(len(obs))), flush=True)


def dem_errors(row: dict, truth, setup, noisy: list, d) -> dict:
    """The fitted model's relative RMSE against the rigs' own values (before lab noise) before and
    after the chosen effect, and the floor the rigs' seed scatter puts under it (one run per test:
    the nets' error model at the truth). error_clean_*: the scatter's share taken out in quadrature,
    an estimate of the error against the rigs' mean response, as the surrogate sets measure it."""
    by_label = {r["label"]: r["value"] for r in row["rows"]}
    raw = {i: by_label[o.label] for i, o in enumerate(noisy)}
    xs = synthetic.row_inputs(setup.nets, setup.candidates, truth, noisy)
    floor = float(np.sqrt(np.mean([(synthetic.seed_sd_at(setup.nets[o.quantity], x) / raw[i]) ** 2
                                   for i, (o, x) in enumerate(zip(noisy, xs))])))
    out = {"scatter_floor": floor}
    for when, model, fit in (("before", d.base_model, d.base), ("after", d.after_model, d.after)):
        e = synthetic.model_error(model, fit, raw) if fit is not None else None
        out[f"error_{when}"] = e
        out[f"error_clean_{when}"] = None if e is None else float(np.sqrt(max(e * e - floor * floor, 0.0)))
    return out


def diagnose(args):
    from pydem.calibration.diagnose import diagnose as run_diagnosis
    setup = load_setup(args.stores, say=lambda *_: None)
    out = []
    for k, line in enumerate(Path(args.journal).read_text().splitlines()):
        row = json.loads(line)
        if args.kinds and row["kind"] not in args.kinds:
            continue
        rng = np.random.default_rng(5000 + k)
        # rows of the given stores' rigs only
        truth, noisy = synthetic.journal_set(row, setup.nets, setup.candidates, rng,
                                         keep=lambda r: Quantity(r["rig"], r["metric"]) in setup.nets
                                         and r["rig"] not in args.skip_rigs)
        if args.density_factor is not None:  # a discrepancy no candidate represents (synthetic.density_mismatch)
            noisy = synthetic.density_mismatch(noisy, args.density_factor)
            row = {**row, "rows": [{**r, "value": r["value"] * args.density_factor
                                    if metric_spec(r["metric"]).scales_with_density and r["value"] is not None
                                    else r["value"]} for r in row["rows"]]}
        d = run_diagnosis(f"dem set {k}", noisy, setup.nets, setup.ranges, setup.candidates, say=lambda *_: None)
        t = row["truth"]
        errors = dem_errors(row, truth, setup, noisy, d)
        out.append({"set": k, "kind": row["kind"], "truth": t, "verdict": d.verdict, "effect": d.effect,
                    "chi2_before": d.base.chi2_per_dof, "chi2_after": d.after.chi2_per_dof if d.after else None,
                    **errors,
                    "best": [(c.effect, round(c.statistic, 2), c.p_value) for c in d.candidates[:2]],
                    "outliers": [o["label"] for o in d.outliers]})
        print(f"set {k}: {row['kind']:14s} truth {t['effect']}={t['strength']}  -> {d.verdict} {d.effect or ''}  "
              f"chi2/dof {d.base.chi2_per_dof:.2f}" + (f" -> {d.after.chi2_per_dof:.2f}" if d.after else "")
              + "".join(f"  (outlier set aside: {o['label']})" for o in d.outliers)
              + (f"  error vs the rigs {errors['error_before']:.3f} -> {errors['error_after']:.3f} (scatter floor "
                 f"{errors['scatter_floor']:.3f})" if errors["error_after"] is not None else ""), flush=True)
    Path(args.out or Path(args.journal).with_suffix(".diagnosed.json")).write_text(json.dumps(out, indent=1, default=float))
    print(error_fall_text(out))


def error_fall_text(sets: list[dict]) -> str:
    """Median error after / before over the sets whose hidden effect was named, per effect."""
    lines = []
    for kind in sorted({s["kind"] for s in sets} - {"null"}):
        hit = [s for s in sets if s["kind"] == kind and s["effect"] == kind and s.get("error_after") is not None]
        if hit:
            raw = np.median([s["error_after"] / s["error_before"] for s in hit])
            clean = [s["error_clean_after"] / s["error_clean_before"] for s in hit if s["error_clean_before"] > 0]
            lines.append(f"{kind}: {len(hit)} named; error vs the rigs after/before, median {raw:.2f}; scatter taken out "
                         + (f"{np.median(clean):.2f}" if clean else "n/a (the error before at the scatter floor)"))
    return "\n".join(lines)


def summary(args):
    """Top-1 per kind, false alarms, the error fall and the density-mismatch verdicts over every
    diagnosed journal matching the pattern (the density-mismatch files counted apart)."""
    files = sorted(Path(ROOT / "studies" / "results").glob(args.pattern))
    plain = [f for f in files if ".density" not in f.name]
    sets = [s for f in plain for s in json.loads(f.read_text())]
    print(f"{len(sets)} sets in {len(plain)} files")
    for kind in sorted({s["kind"] for s in sets}):
        mine = [s for s in sets if s["kind"] == kind]
        verdicts = {v: sum(s["verdict"] == v for s in mine) for v in ("no_effect_needed", "effect", "indistinguishable", "unexplained")}
        if kind == "null":
            print(f"null: clean {verdicts['no_effect_needed']}/{len(mine)}, an effect named {verdicts['effect']}, "
                  f"indistinguishable {verdicts['indistinguishable']}, unexplained {verdicts['unexplained']}")
            continue
        if kind in NOT_CANDIDATES:
            named = sorted({s["effect"] for s in mine if s["verdict"] == "effect"})
            print(f"{kind} (not a candidate): unexplained {verdicts['unexplained']}/{len(mine)}, no effect needed "
                  f"{verdicts['no_effect_needed']}, a candidate named {verdicts['effect']} ({', '.join(named) or '-'}), "
                  f"indistinguishable {verdicts['indistinguishable']}")
            continue
        hit = sum(s["verdict"] == "effect" and s["effect"] == kind for s in mine)
        wrong = sum(s["verdict"] == "effect" and s["effect"] != kind for s in mine)
        print(f"{kind}: top-1 {hit}/{len(mine)}; no effect needed {verdicts['no_effect_needed']}, another effect {wrong}, "
              f"indistinguishable {verdicts['indistinguishable']}, unexplained {verdicts['unexplained']}")
    named = [s for s in sets if s["kind"] != "null" and s["verdict"] == "effect" and s["effect"] == s["kind"]
             and s.get("error_after") is not None]
    clean = [s["error_clean_after"] / s["error_clean_before"] for s in named if s["error_clean_before"] > 0]
    if named:
        print(f"error after/before against the rigs over {len(named)} named: median {np.median(clean):.2f} with the "
              f"seed scatter taken out ({len(clean)} sets), {np.median([s['error_after'] / s['error_before'] for s in named]):.2f} raw")
    dens = [s for f in files if ".density" in f.name for s in json.loads(f.read_text())]
    if dens:
        print(f"density mismatch on the nulls: unexplained {sum(s['verdict'] == 'unexplained' for s in dens)}/{len(dens)}")


def main() -> int:
    ap = argparse.ArgumentParser()
    sub = ap.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("run")
    r.add_argument("--kinds", nargs="+", required=True, help="null, a candidate effect's name, or one of NOT_CANDIDATES; one per set")
    r.add_argument("--journal", required=True)
    r.add_argument("--seed", type=int, default=300)
    r.add_argument("--stores", nargs="+", default=[str(ROOT / s) for s in DEFAULT_STORES])
    d = sub.add_parser("diagnose")
    d.add_argument("--journal", required=True)
    d.add_argument("--stores", nargs="+", default=[str(ROOT / s) for s in DEFAULT_STORES])
    d.add_argument("--skip-rigs", nargs="*", default=[], help="leave these rigs' rows out (e.g. rows made at an older preset)")
    d.add_argument("--out", help="verdicts file (default: the journal's name with .diagnosed.json)")
    d.add_argument("--kinds", nargs="*", help="only the sets of these kinds (e.g. null)")
    d.add_argument("--density-factor", type=float, help="every bulk density and mass flow rate times this factor: a "
                   "solid density the model does not know, a discrepancy no candidate explains (expected: unexplained)")
    e = sub.add_parser("rerun", help="run one rig's rows again at its current preset")
    e.add_argument("--journal", required=True)
    e.add_argument("--rig", required=True)
    e.add_argument("--stores", nargs="+", default=[str(ROOT / s) for s in DEFAULT_STORES])
    m = sub.add_parser("summary", help="the figures over every diagnosed journal")
    m.add_argument("--pattern", default="dem_sets_default*.diagnosed.json", help="files in studies/results")
    args = ap.parse_args()
    {"run": run, "diagnose": diagnose, "rerun": rerun, "summary": summary}[args.cmd](args)
    return 0


if __name__ == "__main__":
    sys.exit(main())
