"""Refinement runs for one material (docs/diagnosis.md §8): after a first pass on the shipped
stores, up to N DEM runs of the rigs the measurement file uses, placed where the surrogates'
error decides the answer, then the surrogates corrected by them (local_correction.py) and the
diagnosis run again.

Where the runs go. What decides a diagnosis is the rows' σ, and near a material the net's error
is most of it. The refinement therefore runs the rigs at the points whose predictions the verdict
uses — the base model's estimate and draws from its posterior (and the final model's, when an
effect is named), each covered candidate at its refit's estimate and at its detection limit — at the measured conditions, and picks the runs one
at a time, greedily, by how much each lowers the net-error variance summed over those target
predictions, each weighted by 1 / σ_row² (its weight in χ²). The net-error variance left after a
set of runs is the local correction's posterior variance, which does not depend on the runs'
results, so the whole plan is made before any run (and a resumed refinement runs the same plan).
A target picked twice is a replicate: the kernel's noise term (the run's seed scatter) gives it a
smaller but real gain. The simple alternative — a fixed design over the posterior box — spends
runs where no row is predicted.

Runs go to `<out>.refine/` beside the output: the plan, and one journal line per finished run
(its metrics, or its error), appended as each run ends. A refinement interrupted and started
again runs only what the journal lacks; a failed run is kept with its reason. Local workers or a
Dask cluster (`--dask ADDRESS`), as campaigns run."""
from __future__ import annotations

import dataclasses
import hashlib
import json
import math
import time
from pathlib import Path

import numpy as np

from ..campaign.runner import sample_seed, simulate
from ..campaign.workers import run_dask, run_local
from ..quantity_table import per_fraction_metric
from .store_data import DISCHARGE_METRICS
from .local_correction import CorrectedNet, left_variance
from .quantities import Observation, test_conditions

POSTERIOR_DRAWS = 6  # posterior draws among the target points
PLAN_SEED = 2101
# runs kept for repeats of the plan's first run (its highest gain), other seeds: the seed scatter
# where the material is, measured; one in eight of the budget, at least two (with a budget of 4+)
REPLICATE_SHARE = 8
PRIOR_DOF = 4  # the nets' seed scatter counts as this many degrees of freedom beside the repeats' own


@dataclasses.dataclass
class Target:
    """A parameter point the diagnosis predicts at, and why."""
    why: str
    point: dict  # every parameter of the box: base parameters and the candidates' values


def target_points(d, candidates, ranges) -> list[Target]:
    """The base estimate and posterior draws, the final model's when an effect was named, and per
    covered candidate its refit and its detection limit."""
    base_names = list(d.base.names)

    def full(theta: dict, extra: dict | None = None) -> dict:
        p = dict(theta)
        for c in candidates:
            if c.parameter in ranges:
                p[c.parameter] = float(np.clip(c.neutral_value(theta), *ranges[c.parameter]))
        p.update(extra or {})
        return p

    def model_points(fit, which: str) -> list[Target]:  # a fit's estimate and draws from its posterior
        def split(p: dict) -> dict:
            return full({n: p[n] for n in base_names}, {n: v for n, v in p.items() if n not in base_names})
        pts = [Target(f"the {which} model's estimate", split(fit.as_dict()))]
        draws = fit.posterior.get("draws")
        if draws is not None and len(draws):
            pts += [Target(f"a draw from the {which} posterior ({k})", split(dict(zip(fit.names, map(float, draws[k])))))
                    for k in np.linspace(0, len(draws) - 1, POSTERIOR_DRAWS).astype(int)]
        return pts

    est = d.base.as_dict()
    out = model_points(d.base, "base")
    if d.after is not None:  # an effect named: the final model's estimate and posterior decide its numbers
        out += model_points(d.after, "final")
    for c in d.candidates:
        if c.fit is not None:
            theta = dict(zip(base_names, map(float, c.fit.best[:len(base_names)])))
            out.append(Target(f"{c.effect} at its refit's estimate", full(theta, {c.parameter: float(c.estimate)})))
        lim = d.detectable.get(c.effect, {})
        for side in ("above", "below"):
            if lim.get(side) is not None:
                out.append(Target(f"{c.effect} at its detection limit ({side})", full(est, {c.parameter: float(lim[side])})))
    return out


def condition_groups(obs: list[Observation]) -> list[tuple[str, dict, list[float]]]:
    """(rig, the run's conditions, the shear fractions measured) per rig test of the file."""
    groups: dict = {}
    for o in obs:
        key = (o.quantity.rig, test_conditions(o))
        groups.setdefault(key, set())
        if "shear_fraction" in o.conditions:
            groups[key].add(o.conditions["shear_fraction"])
    return [(rig, dict(cond), sorted(fr)) for (rig, cond), fr in groups.items()]


def _net_inputs(net, point: dict, conditions: dict) -> np.ndarray:
    return np.array([conditions[n] if n in conditions else point[n] for n in net.input_names], float)


def run_rows(nets: dict, rig: str, point: dict, conditions: dict, fractions: list[float]) -> list:
    """[(quantity, inputs, metric name)] that one run of `rig` measures: each of the rig's nets at
    the run's conditions (and each shear fraction)."""
    out = []
    for q, net in nets.items():
        if q.rig != rig:
            continue
        if "shear_fraction" in net.input_names:
            for f in fractions:
                out.append((q, _net_inputs(net, point, conditions | {"shear_fraction": f}), per_fraction_metric(f)))
        else:
            out.append((q, _net_inputs(net, point, conditions), q.metric))
    return out


def plan(d, obs: list[Observation], nets: dict, candidates, ranges, budget: int) -> list[dict]:
    """The refinement's runs, chosen greedily (module text): [{rig, point, conditions, fractions, why}]."""
    targets = target_points(d, candidates, ranges)
    groups = condition_groups(obs)
    sigma = {i: float(s) for i, s in enumerate(d.base_model.sigma)}
    # the target predictions: (quantity, inputs, weight 1 / sigma_row^2)
    tq: dict = {}
    for t in targets:
        for i, o in enumerate(obs):
            net = nets[o.quantity]
            tq.setdefault(o.quantity, []).append((_net_inputs(net, t.point, o.conditions), 1.0 / sigma[i] ** 2))
    options = [(t, g) for t in targets for g in groups]
    option_rows = [run_rows(nets, g[0], t.point, g[1], g[2]) for t, g in options]
    chosen: dict = {q: [] for q in tq}  # per quantity: the inputs of the runs picked so far

    def left(q, xs) -> float:
        """Weighted net-error variance left at q's targets after runs at xs."""
        x_t = np.array([x for x, _ in tq[q]])
        w = np.array([w for _, w in tq[q]])
        return float(np.sum(w * left_variance(nets[q], np.array(xs), x_t)))

    now = {q: left(q, []) for q in tq}
    picked = []
    repeats = max(2, budget // REPLICATE_SHARE) if budget >= 4 else 0
    for _ in range(budget - repeats):
        best, gain, best_left = None, 0.0, None
        for j, rows in enumerate(option_rows):
            new = dict(now)
            for q in {q for q, _, _ in rows if q in tq}:
                new[q] = left(q, chosen[q] + [x for qq, x, _ in rows if qq == q])
            g = sum(now.values()) - sum(new.values())
            if g > gain:
                best, gain, best_left = j, g, new
        if best is None:
            break
        t, (rig, cond, fractions) = options[best]
        for q, x, _ in option_rows[best]:
            if q in chosen:
                chosen[q].append(x)
        now = best_left
        picked.append({"rig": rig, "point": t.point, "conditions": cond, "fractions": fractions, "why": t.why,
                       "gain": gain})
    if picked:
        picked += [dict(picked[0], why="a repeat of run 0 with another seed (the seed scatter there)", gain=None)
                   for _ in range(repeats)]
    return picked


def plan_fixed(d, obs: list[Observation], candidates, ranges, budget: int, seed: int = PLAN_SEED) -> list[dict]:
    """The simple alternative the greedy plan is compared with (docs/diagnosis.md §8): a scrambled
    Sobol design over the final model's 95 % posterior box (its base parameters and named effects;
    the other candidates neutral), the points dealt to the measured rig tests in turn."""
    from scipy.stats import qmc
    final = d.after if d.after is not None else d.base
    post = final.posterior.get("parameters", {})
    names = list(final.names)
    lo = np.array([post[n]["lo"] if n in post else final.lo[j] for j, n in enumerate(names)])
    hi = np.array([post[n]["hi"] if n in post else final.hi[j] for j, n in enumerate(names)])
    pts = qmc.scale(qmc.Sobol(len(names), scramble=True, seed=seed).random(budget), lo, np.maximum(hi, lo + 1e-12))
    groups = condition_groups(obs)
    base_names = list(d.base.names)
    out = []
    for k, x in enumerate(pts):
        p = dict(zip(names, map(float, x)))
        theta = {n: p[n] for n in base_names}
        point = {c.parameter: float(np.clip(c.neutral_value(theta), *ranges[c.parameter]))
                 for c in candidates if c.parameter in ranges} | p
        rig, cond, fractions = groups[k % len(groups)]
        out.append({"rig": rig, "point": point, "conditions": cond, "fractions": fractions,
                    "why": f"fixed design point {k}", "gain": None})
    return out


def plan_key(obs: list[Observation], budget: int, stores: dict, design: str = "greedy") -> str:
    """What a plan was made for: the rows, the budget and the stores (a resumed refinement must match)."""
    text = json.dumps([[o.label, o.value, o.uncertainty] for o in obs] + [budget] +
                      sorted(s.path.name for s in stores.values()) + ([] if design == "greedy" else [design]),
                      sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def run_plan(runs: list[dict], stores: dict, folder: Path, workers: int, say=print, dask: str | None = None) -> list[dict]:
    """Runs what the journal (folder/runs.jsonl) lacks — in local worker processes (the campaigns'
    pool: a killed worker is retried once, Ctrl-C lets the running ones finish) or on a Dask
    cluster — appending each run to the journal as it ends; returns every journal entry (finished
    or failed, with the reason) in plan order."""
    journal = folder / "runs.jsonl"
    done = {}
    if journal.exists():
        for line in journal.read_text().splitlines():
            if line.strip():
                r = json.loads(line)
                done[r["index"]] = r
    todo = [i for i in range(len(runs)) if i not in done]
    if not todo:
        return [done[i] for i in range(len(runs))]
    where = f"on the Dask cluster {dask}" if dask else f"{workers} worker{'s' if workers > 1 else ''}"
    say(f"  refinement: {len(runs) - len(todo)} of {len(runs)} runs in {journal}, running {len(todo)} ({where})")
    jobs = {}
    for i in todo:
        r = runs[i]
        spec = stores[r["rig"]].spec
        fixed = dict(spec.fixed, num_threads=1)
        if r["fractions"]:
            fixed["shear_points"] = list(r["fractions"])
        values = {k: v for k, v in (r["point"] | r["conditions"]).items() if k in spec.ranges}
        jobs[i] = (dataclasses.replace(spec, fixed=fixed).to_json(), values, sample_seed(PLAN_SEED, i))
    t0, finished, failed = time.perf_counter(), 0, 0

    def on_result(i: int, res: dict):
        nonlocal finished, failed
        entry = {"index": i, **runs[i], "seed": jobs[i][2], "wall": res.get("wall"), "cpu": res.get("cpu")}
        if "error" in res:
            entry["error"] = res["error"]
            failed += 1
        else:
            entry["metrics"] = {k: v[0] for k, v in res["metrics"].items()}
        finished += 1
        with journal.open("a") as f:
            f.write(json.dumps(entry) + "\n")
        done[i] = entry
        rate = (time.perf_counter() - t0) / finished
        say(f"  refinement: {len(done)}/{len(runs)} runs, {failed} failed, ~{rate * (len(todo) - finished):.0f} s left"
            + (f" (run {i}: {entry['error']})" if "error" in entry else ""))

    if dask:
        run_dask(dask, jobs, simulate, on_result, "pydem-refine")
    else:
        run_local(jobs, simulate, max(1, min(workers, len(jobs))), on_result, say)
    missing = [i for i in range(len(runs)) if i not in done]
    if missing:  # interrupted (Ctrl-C): what ran is in the journal; the rest runs when started again
        raise KeyboardInterrupt(f"refinement interrupted: {len(missing)} runs left, kept in {journal}")
    return [done[i] for i in range(len(runs))]


def corrected_nets(nets: dict, entries: list[dict]) -> dict:
    """Each net with a correction from the runs that measured its quantity (nets no run measured:
    as they were), its seed scatter rescaled by what repeated runs measure (local_seed_scale)."""
    data: dict = {}
    for e in entries:
        if "metrics" not in e:
            continue
        m = e["metrics"]
        jammed = e["rig"] == "hopper" and not math.isfinite(m.get("discharge_time", math.nan))
        where = json.dumps([e["rig"], e["point"], e["conditions"]], sort_keys=True)
        for q, x, metric in run_rows(nets, e["rig"], e["point"], e["conditions"], e["fractions"]):
            v = m.get(metric)
            if v is None or not math.isfinite(v) or (jammed and q.metric in DISCHARGE_METRICS):
                continue
            xs, ys, keys = data.setdefault(q, ([], [], []))
            xs.append(x)
            ys.append(v)
            keys.append(where + metric)
    out = {}
    for q, net in nets.items():
        if q in data:
            x, y = np.array(data[q][0]), np.array(data[q][1])
            out[q] = CorrectedNet(net, x, y, seed_scale=local_seed_scale(net, x, y, data[q][2]))
        else:
            out[q] = net
    return out


def local_seed_scale(net, x: np.ndarray, y: np.ndarray, keys: list[str]) -> tuple[float, int]:
    """(factor on the net's seed scatter, the repeats' degrees of freedom): the pooled variance of
    runs repeated at one point (same key), against the net's seed scatter at those runs, with the
    net's own counted as PRIOR_DOF degrees of freedom; (1, 0) without repeats."""
    groups: dict = {}
    for i, k in enumerate(keys):
        groups.setdefault(k, []).append(i)
    repeated = [idx for idx in groups.values() if len(idx) > 1]
    if not repeated:
        return 1.0, 0
    ss = sum(float(np.sum((y[idx] - y[idx].mean()) ** 2)) for idx in repeated)
    dof = sum(len(idx) - 1 for idx in repeated)
    at = x[[i for idx in repeated for i in idx]]
    prior = float(np.mean(net.errors_at(at)[0] ** 2)) if hasattr(net, "errors_at") else float(net.seed_sd) ** 2
    if prior <= 0:
        return 1.0, dof
    return float(np.sqrt((ss + PRIOR_DOF * prior) / (dof + PRIOR_DOF) / prior)), dof


def saved_plan(folder: Path, obs, budget: int, stores: dict, design: str = "greedy") -> list[dict] | None:
    """The plan in folder/plan.json when it was made for these rows, budget and stores; None when
    there is none; ValueError when the folder holds another refinement (never mixed). Checked
    before any work."""
    f = folder / "plan.json"
    if not f.exists():
        return None
    saved = json.loads(f.read_text())
    if saved.get("key") != plan_key(obs, budget, stores, design):
        raise ValueError(f"{folder} holds a refinement made for other rows, budget, stores or design; remove it or "
                         f"choose another --out")
    return saved["runs"]


def save_plan(folder: Path, runs: list[dict], obs, budget: int, stores: dict, design: str = "greedy"):
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "plan.json").write_text(json.dumps({"key": plan_key(obs, budget, stores, design), "design": design,
                                                  "runs": runs}, indent=1))


def summary(first, second, entries: list[dict], nets: dict, obs: list[Observation]) -> dict:
    """What the report shows of a refinement: runs used and failed, their CPU time, each quantity's
    error at the runs before (the global net) and after (leave one out), and per row the
    measurement's uncertainty beside the net's error at the first and the second pass's estimate."""
    per_q = {}
    for q, net in nets.items():
        if isinstance(net, CorrectedNet):
            per_q[q.key] = {"runs": len(net.y), "net_rmse": net.raw_rmse(), "corrected_loo_rmse": net.loo_rmse(),
                            "seed_sd": float(np.sqrt(np.mean(net.noise))), "seed_scale": net.seed_scale[0],
                            "repeat_dof": net.seed_scale[1], "error_scale": net.error_scale,
                            "mahalanobis": net.mahalanobis}
    rows = [{"label": o.label, "uncertainty": o.uncertainty if o.uncertainty_given else None,
             "net_error_first": float(a), "net_error_second": float(b)}
            for o, a, b in zip(obs, first.base_model.net_errors, second.base_model.net_errors)]
    return {"runs": len(entries), "failed": [{"index": e["index"], "rig": e["rig"], "error": e["error"]}
                                             for e in entries if "error" in e],
            # the runs' CPU time (journals written before it was recorded: their wall time)
            "cpu_seconds": float(sum(e.get("cpu") or e.get("wall") or 0.0 for e in entries)),
            "wall_seconds": float(sum(e.get("wall") or 0.0 for e in entries)),
            "quantities": per_q, "rows": rows,
            "first_pass": _pass(first), "second_pass": _pass(second)}


def _pass(d) -> dict:
    """One pass as the report compares it: verdict, base fit, and the final model's estimates."""
    final = d.after if d.after is not None else d.base
    post = final.posterior.get("parameters", {})
    return {"verdict": d.verdict, "effects": d.effects, "estimate": d.base.as_dict(),
            "chi2_per_dof": d.base.chi2_per_dof, "final_estimate": final.as_dict(),
            "intervals": {n: [post[n].get("lo"), post[n].get("hi")] for n in final.names if n in post},
            "rmse_before": d.summary_of(d.base, d.base_model)["rmse_relative"],
            "rmse_after": d.summary_of(d.after, d.after_model)["rmse_relative"] if d.after is not None else None}
