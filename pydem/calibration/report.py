"""Renders a Diagnosis: `report.html` (self-contained, plots embedded), `report.md` (the same
tables, plots as PNG files beside it) and `diagnosis.json`. Renders only: every number comes
from the Diagnosis object."""
from __future__ import annotations

import html
import json
import math
from pathlib import Path

import numpy as np

from .. import report_page as page
from ..quantity_table import metric_spec
from ..rigs.result import strict_json
from .diagnose import ALPHA, Diagnosis
from .reach import sentence as reach_sentence
from .verdicts import ACCEPT, TEXT


def verdict_line(d: Diagnosis) -> str:
    sig = [c.effect for c in d.candidates if c.p_value < ALPHA and c.effect != d.effect]
    text = TEXT["effects" if d.verdict == "effect" and d.added else d.verdict]
    line = text.format(effect=d.effect, others=", ".join(sig) or "another candidate", effects=" + ".join(d.effects),
                       n=len(d.observations), k=len(d.base.names))
    if d.reach:
        line += " " + reach_sentence(d.reach)
    if not d.testable and d.verdict != "not_testable":
        line += (f" With {len(d.observations)} measurement(s) for {len(d.base.names)} base parameters no candidate "
                 f"effect could be tested: measure more conditions.")
    if d.verdict == "no_effect_needed" and d.detectable:
        hidden = [f"{name} {_limits(info)}" for name, info in d.detectable.items()]
        line += (" It does not rule out effects these measurements cannot show (below their 90 % detection limits): "
                 + "; ".join(hidden) + ".")
    final = d.after if d.after is not None else d.base
    edges = [n for n, p in final.posterior.get("parameters", {}).items()
             if p.get("at_edge") and n not in {r["parameter"] for r in d.reach}]
    if edges:
        line += (f" The {'final' if d.after is not None else 'base'} model's estimate or interval reaches the edge of "
                 f"the campaign range for {', '.join(edges)} (the misfit does not fall past it: a bound, not a "
                 f"shortfall).")
    return line


def calibration_line(c) -> str:
    """The calibration report's opening line: its verdict in words, and the caveats that qualify it."""
    f = c.fit
    line = TEXT[c.verdict].format(p=f.p_value, accept=ACCEPT, n=f.n, k=len(f.names))
    if c.reach:
        line += " " + reach_sentence(c.reach)
    if f.n <= len(f.names) and c.verdict != "not_testable":
        line += (f" With {f.n} measurement(s) for {len(f.names)} parameters the posterior is the prior narrowed along "
                 f"a few directions only: measure more conditions.")
    return line


def _limits(info: dict) -> str:
    """'0.05-0.31' / 'below 2e4': where an effect would go unseen (detectability.py's limits about
    the neutral value, the campaign range's edges where a side has none)."""
    lo = info["neutral"] if "below" not in info else info["below"] if info["below"] is not None else info["range"][0]
    hi = info["above"] if info.get("above") is not None else info["range"][1]
    if "below" not in info:
        return f"below {hi:.3g}"
    return f"{lo:.3g}–{hi:.3g}"


def _axis_condition(q) -> str | None:
    return {"ring-shear": "preshear_stress", "hopper": "slot_width"}.get(q.rig)


MODEL_COLOURS = ("C0", "C3", "C2")  # base model blue, the model with the effect(s) red


def plot_measured_vs_model(observations, models: dict[str, tuple[np.ndarray, np.ndarray]]) -> bytes:
    """Measured (black, error bars: each row's stated uncertainty) and each model's predictions with a
    band of +-1 sigma of measured - model at that model's estimate ({label: (values, sigma)}; one
    colour per model, the first dashed; a quantity's series, e.g. its shear fractions, told apart
    by marker) against each quantity's condition, one panel per quantity. Each
    model carries its own sigma: the seed scatter and the nets' error change with the parameters
    (a cohesive estimate scatters more), so a band drawn from the base model's sigma would misstate
    the fit with the effect."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import matplotlib.ticker
    quantities = sorted({o.quantity for o in observations}, key=lambda q: q.key)
    n = len(quantities)
    cols = min(3, n)
    rows = int(math.ceil(n / cols))
    fig, axes = plt.subplots(rows, cols, figsize=(4.6 * cols, 3.6 * rows), squeeze=False, layout="constrained")
    for ax, q in zip(axes.flat, quantities):
        idx = [i for i, o in enumerate(observations) if o.quantity == q]
        cname = _axis_condition(q)
        series = {}
        for i in idx:
            o = observations[i]
            key = f"f = {o.conditions['shear_fraction']:g}" if "shear_fraction" in o.conditions else ""
            series.setdefault(key, []).append(i)
        for k, (label, ii) in enumerate(sorted(series.items())):
            x = np.array([observations[i].conditions.get(cname, k) if cname else k for i in ii], dtype=float)
            order = np.argsort(x)
            x = x[order]
            ii = [ii[j] for j in order]
            marker = "osD^v"[k % 5]
            u = [observations[i].uncertainty if observations[i].uncertainty_given else 0.0 for i in ii]
            ax.errorbar(x, [observations[i].value for i in ii], yerr=u, fmt=marker, color="k", capsize=3,
                        label=f"measured {label}".strip(), zorder=3)
            for m, (name, (pred, sigma)) in enumerate(models.items()):
                col = MODEL_COLOURS[m % len(MODEL_COLOURS)]
                y, sd = pred[ii], sigma[ii]
                xm = x if len(x) > 1 else x + 0.25 * (m + 1)  # one point: each model beside the measurement
                ax.plot(xm, y, ("--" if m == 0 else "-") + marker, color=col, mfc="none", ms=6,
                        label=f"{name} {label}".strip())
                if len(x) > 1:
                    ax.fill_between(x, y - sd, y + sd, color=col, alpha=0.12, lw=0)
                else:  # one point: the band as an error bar
                    ax.errorbar(xm, y, yerr=sd, fmt="none", color=col, alpha=0.7, capsize=3)
        ax.set_title(q.key, fontsize=10)
        unit = metric_spec(q.metric).unit  # the one quantity table's
        ax.set_ylabel(q.metric.replace("_", " ") + (f" ({unit})" if unit else ""))
        if cname == "preshear_stress":
            ax.set_xscale("log")
            ax.set_xticks(sorted({observations[i].conditions[cname] for i in idx}))
            ax.xaxis.set_major_formatter(matplotlib.ticker.FuncFormatter(lambda v, _: f"{v:g}"))
            ax.xaxis.set_minor_locator(matplotlib.ticker.NullLocator())
        elif cname is None:
            ax.set_xticks([])
            ax.set_xlim(-0.4, 0.25 * len(models) + 0.4)
        ax.set_xlabel({"preshear_stress": "pre-shear stress (Pa)", "slot_width": "slot width (m)"}.get(cname, ""))
        ax.legend(fontsize=6)
    for ax in list(axes.flat)[n:]:
        ax.set_visible(False)
    fig.suptitle("measured (bars: stated uncertainty) vs model (bands: ±1 sigma of measured − model at that "
                 "model's estimate: the row's noise by its origin and the nets' error)", fontsize=9)
    return page.png(fig)


def plot_parameters(fit, window: dict | None) -> bytes:
    """Every pair of free parameters over the campaign box: posterior draws (grey), seed 000's
    admissible combinations (blue, when there are any; said so when there are none) and the
    best estimate (red star)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    names, draws = fit.names, fit.posterior.get("draws")
    k = len(names)
    pts = (window or {}).get("points")
    pts = pts[:: max(1, len(pts) // 2000)] if pts is not None and len(pts) else None
    fig, axes = plt.subplots(k - 1, k - 1, figsize=(2.9 * (k - 1), 2.7 * (k - 1)), squeeze=False, layout="constrained")
    for i in range(1, k):
        for j in range(k - 1):
            ax = axes[i - 1][j]
            if j >= i:
                ax.set_visible(False)
                continue
            if draws is not None:
                ax.scatter(draws[:, j], draws[:, i], s=3, color="0.55", alpha=0.5, label="posterior draws")
            if pts is not None:
                ax.scatter(pts[:, j], pts[:, i], s=3, color="C0", alpha=0.5, label="within the window")
            ax.plot(fit.best[j], fit.best[i], "*", color="C3", ms=12, label="best estimate")
            ax.set_xlim(fit.lo[j], fit.hi[j])
            ax.set_ylim(fit.lo[i], fit.hi[i])
            ax.set_xlabel(names[j].split(".")[-1], fontsize=8)
            ax.set_ylabel(names[i].split(".")[-1], fontsize=8)
            ax.tick_params(labelsize=7)
    axes[0][0].legend(fontsize=6, loc="best")
    n_adm = (window or {}).get("admissible")
    note = "" if n_adm is None else (f"; {n_adm:,} of {window['samples']:,} combinations within ±{100 * window['window']:g} %"
                                      if n_adm else f"; no combination within ±{100 * window['window']:g} % of every value")
    fig.suptitle(f"parameters over the campaign box{note}", fontsize=10)
    return page.png(fig)


def nets_section(nets: dict) -> tuple[str, str, str]:
    """The surrogates' quality: cross-validated R^2 and RMSE against single runs, and how that RMSE
    splits into the rig's seed scatter and the net's own error (docs/diagnosis.md §3)."""
    rows = [[q.key, n.runs, ", ".join(x.split(".")[-1] for x in n.input_names), _g(n.r2, ".3f"), _g(n.rmse, ".3g"),
             _g(n.seed_sd, ".3g") + ("" if math.isfinite(n.scatter) else " (all of the RMSE)"), _g(n.net_error, ".3g")]
            for q, n in sorted(nets.items(), key=lambda kv: kv[0].key)]
    md, h = page.table(rows, ["quantity", "rows", "inputs", "CV R²", "CV RMSE", "seed scatter", "net error"])
    return "Surrogates", md, h


def plot_residuals(d: Diagnosis) -> dict[str, bytes]:
    """The measured-vs-model plot (base model, and with the effect) and the candidates' statistics."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    models = {"base model": (d.base_model.predict(d.base.best), d.base_model.sigma)}
    if d.after is not None:
        models[f"with {d.effect or 'best candidate'}"] = (d.after_model.predict(d.after.best), d.after_model.sigma)
    out = {"residuals.png": plot_measured_vs_model(d.observations, models)}
    if not d.candidates:  # no plot without bars: the candidates section says why
        return out
    fig, ax = plt.subplots(figsize=(5.5, 0.5 + 0.45 * max(len(d.candidates), 1)))
    names = [c.effect for c in d.candidates][::-1]
    vals = [c.statistic for c in d.candidates][::-1]
    from scipy import stats
    ax.barh(names, vals, color=["C3" if c.p_value < ALPHA else "C0" for c in d.candidates][::-1])
    ax.axvline(float(stats.chi2.isf(2 * ALPHA, 1)), color="k", ls=":", label=f"p = {ALPHA:g}, one-sided (cohesion)")
    ax.axvline(float(stats.chi2.isf(ALPHA, 1)), color="k", ls="--", label=f"p = {ALPHA:g}, two-sided")
    ax.set_xlabel("profile-likelihood ratio (chi^2 base - chi^2 with the effect)")
    ax.legend(fontsize=7)
    out["candidates.png"] = page.png(fig)
    return out


def _g(x, fmt=".4g"):
    return "-" if x is None or (isinstance(x, float) and not math.isfinite(x)) else format(x, fmt)


def write(d: Diagnosis, out: str | Path, context: dict | None = None) -> Path:
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    data = d.as_dict()
    data["context"] = context or {}
    (out / "diagnosis.json").write_text(json.dumps(strict_json(data), indent=1, allow_nan=False))
    plots = plot_residuals(d)
    for name, png in plots.items():
        (out / name).write_bytes(png)
    sections = []  # (title, markdown, html)
    sections.append(("Verdict", f"**{d.verdict}** — {verdict_line(d)}", f"<p class='verdict'><b>{d.verdict}</b> — "
                     f"{html.escape(verdict_line(d))}</p>"))
    b, a = data["before"], data["after"]
    first = d.candidates[0] if a and d.candidates else None
    rows = [["base model", _g(d.base.chi2, ".2f"), _g(b["chi2_per_dof"], ".2f"), b["dof"], _g(b["p_value"], ".2g"),
             _g(b["rmse_relative"], ".3f"), _g(b["loco_rmse_relative"], ".3f")]]
    if a:
        rows.append([f"with {' + '.join(d.effects) or (first.effect + ' (not enough)')}",
                     _g(first.fit.chi2, ".2f") + f" (with {first.effect})", _g(a["chi2_per_dof"], ".2f"), a["dof"],
                     _g(a["p_value"], ".2g"), _g(a["rmse_relative"], ".3f"), _g(a["loco_rmse_relative"], ".3f")])
    md, h = page.table(rows, ["model", "chi^2 in the test (the base's noise model)", "chi^2/dof (its own noise model)",
                              "dof", "p-value", "RMSE of relative residuals", "leave-one-condition-out RMSE"])
    note = ("The test compares both models with one noise model, the base model's at its optimum (fixed before any "
            "candidate is tried): LR is the drop of that chi^2. Each model's own fit — its intervals, chi^2/dof and "
            "p-value — takes the noise model where it lands (the nets' error models vary over the campaign box)."
            if a else "")
    sections.append(("Before and after", md + (f"\n\n{note}" if note else ""), h + (f"<p>{html.escape(note)}</p>" if note else "")))
    if data["context"].get("refinement"):
        sections.append(refinement_section(data["context"]["refinement"]))
    rows = [[c.effect, c.parameter, _g(d.base.chi2, ".2f"), _g(c.fit.chi2, ".2f"),
             _g(c.statistic, ".2f"), _g(c.p_value, ".2g"), _g(c.delta_bic, ".1f"),
             _g(c.score, ".2f"), f"{_g(c.estimate)} {c.unit}".strip(), f"{_g(c.neutral)} {c.unit}".strip()]
            for c in d.candidates]
    md, h = page.table(rows, ["candidate", "parameter", "chi^2 base", "chi^2 with it", "LR statistic", "p-value", "dBIC",
                              "score", "estimate", "neutral"])
    extra = ("\n\nLR = chi^2 base - chi^2 with it, both with the base model's noise model (the verdict uses exactly "
             "these numbers); p from chi^2 with one degree of freedom (half of it for a one-sided candidate such as "
             "cohesion).")
    for a in d.added:
        extra += (f"\n\nOn top of {', '.join(d.effects[:d.effects.index(a.effect)])}: {a.effect} LR {a.statistic:.2f}, "
                  f"p {a.p_value:.2g}, estimate {_g(a.estimate)} {a.unit} (95 % interval {_g(a.estimate_lo)}–"
                  f"{_g(a.estimate_hi)}) — added (p < {ALPHA:g}, the same level as the first step).")
    if d.not_covered:
        extra = f"\n\nNot covered by these campaigns: {', '.join(d.not_covered)}."
    if not d.candidates:
        extra += (f"\n\nNo candidate effect was tested: {len(d.observations)} measurement(s) for {len(d.base.names)} "
                  f"base parameters leave nothing to test with." if not d.testable else
                  "\n\nNo candidate effect was tested: none is varied by the campaigns of these measurements.")
    sims = "; ".join(f"{k.replace('|', ' vs ')}: {v:.2f}" for k, v in d.similarity.items())
    if sims:
        extra += f"\n\nCosine of the candidates' projected signatures (1: these conditions cannot tell them apart): {sims}."
    for k, s in d.separating.items():
        if s:
            extra += (f"\n\n{k.replace('|', ' and ')} are told apart best by measuring {s['quantity']} at "
                      + ", ".join(f"{kk}={vv:.4g}" for kk, vv in s["conditions"].items())
                      + f" (the two explanations differ there by {s['difference_in_sigma']:.1f} sigma).")
    sections.append(("Candidate effects", md + extra, h + "".join(f"<p>{html.escape(x)}</p>" for x in extra.split("\n\n") if x)))
    if d.detectable:
        sections.append(detectable_section(d.detectable, {c.effect: c.unit for c in d.candidates}))
    sections.append(parameter_section(data["parameters"], data.get("admissible_window"),
                                      "Parameters" + (f" (with {d.effect})" if d.after is not None else "")))
    for title, key in (("Residuals, base model", "residuals_before"), ("Residuals, with the effect", "residuals_after")):
        if data.get(key):
            sections.append(residual_section(data[key], title))
    if d.groups:
        names = list(d.groups[0]["estimate"])
        rows = [[g["condition"], g["rows"]] + [_g(g["estimate"][n], ".3g") for n in names] for g in d.groups]
        md, h = page.table(rows, ["condition group", "rows"] + names)
        sections.append(("Base model recalibrated per condition group (a parameter drifting with a condition points "
                         "at a missing effect)", md, h))
    if data["context"].get("confirm"):
        sections.append(confirm_section(data["context"]["confirm"]))
    if d.notes:
        sections.append(notes_section(d.notes))
    sections.append(glossary_section(DIAGNOSIS_TERMS))
    sections.append(provenance_section(data["context"]))
    return page.write_page(out, f"Diagnosis: {d.material}", sections, plots, head=2)


def detectable_section(detectable: dict, units: dict) -> tuple[str, str, str]:
    """What these measurements can see: per candidate, the smallest effect on each side that the
    test finds with 90 % probability (detectability.py)."""
    def side(v, info, key):
        if key not in info:
            return "(one-sided)"
        if v is None and key not in info["signal_at_edge"]:  # the neutral value sits on that edge
            return "none: the neutral value is the range's edge"
        return _g(v) if v is not None else f"not within the range (signal at its edge {info['signal_at_edge'][key]:.1f})"
    def next_test(info):
        n = info.get("measure_next")
        return f"{n['test']} (limits × {n['limit_ratio']:.2f})" if n else "-"
    rows = [[name, f"{_g(info['neutral'])} {units.get(name, '')}".strip(), side(info.get("below"), info, "below"),
             side(info.get("above"), info, "above"), next_test(info)] for name, info in detectable.items()]
    md, h = page.table(rows, ["candidate", "neutral (base model)", "detectable below", "detectable above",
                          "one more test that would lower the limits most"])
    any_info = next(iter(detectable.values()))
    needed = " or ".join(sorted({f"{i['signal_needed']:.1f}" for i in detectable.values()}))
    line = (f"The smallest effect each test finds with {100 * any_info['power']:g} % probability at p = "
            f"{any_info['alpha']:g}, at the base model's fit and with these rows' uncertainties (a likelihood-ratio "
            f"signal of {needed}): an effect closer to the neutral value than this can hide in these "
            f"measurements, so a clean verdict does not rule it out. The last column: the one extra test (a run of a "
            f"rig at one condition, all its quantities) that would lower the limits most, in the linearised view "
            f"(limits scale as the test's information to the power -1/2); a test that pins the base parameters "
            f"down where the effect is small can help as much as one where it is large.")
    return ("What these measurements can see", md + "\n\n" + line, h + f"<p>{html.escape(line)}</p>")


def parameter_section(params: dict, window: dict | None, title: str) -> tuple[str, str, str]:
    rows = [[k, _g(v["estimate"]), f"{_g(v['lo'])} – {_g(v['hi'])}"
             + ("" if v.get("interval", "central") == "central" else f" ({v['interval']})"), _g(v["sd"]),
             "yes" if v["at_edge"] else ""] for k, v in params.items()]
    md, h = page.table(rows, ["parameter", "most probable value", "95 % credible interval", "posterior sd",
                              "at range edge"])
    line = ("The most probable value is the best fit (the posterior's mode for a uniform prior on the campaign box); "
            "the interval holds 95 % of the posterior, central, or from the range's edge when the posterior piles "
            "against it and the most probable value lies outside the central one. In a diagnosis the posterior is "
            "taken with every candidate effect not named free within its detection limits (the effects these "
            "measurements cannot rule out), so the intervals also hold what such an effect would move.")
    md += "\n\n" + line
    h += f"<p>{html.escape(line)}</p>"
    if window:
        line = (f"Seed 000's view: {window['admissible']:,} of {window['samples']:,} combinations of the box (scrambled "
                f"Sobol, screened natively) predict every measured value within ±{100 * window['window']:g} %"
                + (": " + ", ".join(f"{k} {v[0]:.3g}–{v[1]:.3g}" for k, v in window["ranges"].items())
                   if window["ranges"] else "") + ".")
        md += "\n\n" + line
        h += f"<p>{html.escape(line)}</p>"
    return title, md, h


def residual_section(rows: list[dict], title: str) -> tuple[str, str, str]:
    table = [[r["label"], _g(r["measured"]), _g(r["u_measured"], ".3g"), _g(r["model"]), _g(r["sigma"], ".3g"),
              _g(r["z"], "+.2f")] for r in rows]
    md, h = page.table(table, ["measurement", "measured", "u", "model", "sigma (all)", "z"])
    return title, md, h


def refinement_section(r: dict) -> tuple[str, str, str]:
    """The two passes side by side, the runs, and each row's surrogate error against its measurement's
    uncertainty before and after the refinement (refine.summary)."""
    a, b = r["first_pass"], r["second_pass"]
    names = list(dict.fromkeys([*a.get("final_estimate", a["estimate"]), *b.get("final_estimate", b["estimate"])]))
    rows = [[name, _g(p["chi2_per_dof"], ".2f"), p["verdict"] + (f" ({' + '.join(p['effects'])})" if p["effects"] else ""),
             *[_g(p.get("final_estimate", p["estimate"]).get(n), ".3g") if n in p.get("final_estimate", p["estimate"])
               else "-" for n in names]] for name, p in (("first pass (shipped stores)", a), ("second pass (refined)", b))]
    md1, h1 = page.table(rows, ["pass", "base chi^2/dof", "verdict", *[f"{n.split('.')[-1]} (final model)" for n in names]])
    rows = [[x["label"], _g(x["uncertainty"]) if x["uncertainty"] is not None else "not given",
             _g(x["net_error_first"]), _g(x["net_error_second"])] for x in r["rows"]]
    md2, h2 = page.table(rows, ["measurement", "its uncertainty", "surrogate error, first pass", "after refinement"])
    rows = [[q, v["runs"], _g(v["net_rmse"]), _g(v["corrected_loo_rmse"]), _g(v.get("seed_sd")),
             f"x{v['seed_scale']:.2f} ({v['repeat_dof']} dof)" if v.get("repeat_dof") else "-",
             f"x{v['error_scale']:.2f}" if "error_scale" in v else "-"]
            for q, v in r["quantities"].items()]
    md3, h3 = page.table(rows, ["quantity", "runs", "global net's RMSE at the runs", "corrected, leave one out",
                                "one run's seed scatter there (the floor of both)",
                                "seed scatter from the repeats, on the nets'",
                                "net error near the material, from the runs' residuals, on the error model's"])
    failed = "; ".join(f"run {f['index']} ({f['rig']}): {f['error']}" for f in r["failed"]) or "none"
    text = (f"{r['runs']} refinement runs ({r['cpu_seconds']:.0f} s of CPU; failed: {failed}), kept in {r['folder']}. "
            f"The second pass uses the surrogates corrected by them (docs/diagnosis.md §8); the rest of this report is "
            f"the second pass.")
    md = "\n\n".join([text, md1, md2, md3])
    h = f"<p>{html.escape(text)}</p>" + h1 + h2 + h3
    return "Refinement: first and second pass", md, h


def confirm_section(rows: list[dict]) -> tuple[str, str, str]:
    table = [[r["label"], _g(r["measured"]), _g(r["dem"]), f"{100 * r['relative']:+.1f} %"] for r in rows]
    md, h = page.table(table, ["measurement", "measured", "DEM at the estimate", "(measured - DEM) / measured"])
    return "Confirming DEM runs", md, h


COMMON_TERMS = {
    "chi^2, chi^2/dof": "the sum of squared residuals, each in units of its row's sigma (rows correlated where their "
                        "noise is shared); per degree of freedom (rows minus fitted parameters) it is about 1 when the "
                        "model fits as well as the noise allows.",
    "p-value (of a fit)": "the chance of a chi^2 at least this large if the model were right; below 0.001 the fit is "
                          "rejected.",
    "sigma, z": "a row's standard deviation of measured minus model: the measurement's uncertainty (or one rig run's "
                "seed scatter where none is stated, and both for a DEM-made row) and the surrogate's error; z is the "
                "residual in these units.",
    "surrogate": "the small neural network that stands in for the DEM rig, trained on a campaign store's runs; its "
                 "cross-validated error enters sigma.",
}
DIAGNOSIS_TERMS = COMMON_TERMS | {
    "LR (likelihood ratio)": "how much chi^2 falls when a candidate's parameter is freed and every parameter refitted, "
                             "both fits with one noise model (the base model's): under the base model it is chi^2 with "
                             "1 degree of freedom, so a large LR is evidence for the effect.",
    "p-value (of a candidate)": "the chance of an LR at least this large if the effect were absent; an effect is named "
                                f"below {ALPHA:g} (one-sided candidates such as cohesion: half the two-sided value).",
    "dBIC": "the change of the Bayesian information criterion when the effect is added (negative favours it; below -2 "
            "worth a mention, below -10 strong).",
    "score": "the same test taken as a slope at the neutral value (no refit): quick, but it understates strong effects; "
             "the verdict uses LR.",
    "projected signature, cosine": "how a candidate moves the predictions once the base parameters have re-adjusted; "
                                   "two candidates whose signatures have a cosine near 1 cannot be told apart with "
                                   "these conditions.",
    "detection limit": "the smallest effect these measurements would show with 90 % probability at the test's level.",
    "leave-one-condition-out RMSE": "the relative error of predicting each condition's rows from a fit without them.",
}
CALIBRATION_TERMS = COMMON_TERMS | {
    "admissible set (seed 000's view)": "the combinations of the box whose predictions lie within the window of every "
                                        "measured value, screened over scrambled Sobol points.",
}


def glossary_section(terms: dict) -> tuple[str, str, str]:
    return ("What the numbers mean", "\n".join(f"- **{k}**: {v}" for k, v in terms.items()),
            "<ul>" + "".join(f"<li><b>{html.escape(k)}</b>: {html.escape(v)}</li>" for k, v in terms.items()) + "</ul>")


def material_text(material: dict) -> str:
    """The material as its file gave it and as the comparison took it (similarity.Scaling.as_dict)."""
    rho_s = material.get("store_particle_density", float("nan"))
    given = {k: v for k, v in (material.get("given") or {}).items() if v not in (None, [])}
    if not given:
        return f"not described: the stores' material assumed (particle density {rho_s:.6g} kg/m^3)"
    parts = [f"sieve table of {len(v)} classes" if k == "sieve" else f"{k} {v:.6g}" for k, v in given.items()]
    text = ", ".join(parts) + f"; compared with stores at particle density {rho_s:.6g} kg/m^3, scale {material.get('factor', 1.0):.4g}"
    if material.get("mean_diameter") is not None:
        text += f"; mean diameter {1e3 * material['mean_diameter']:.4g} mm, stores' spheres " + ", ".join(
            f"{rig} {1e3 * d:.3g} mm" for rig, d in sorted((material.get("store_diameters") or {}).items()))
    if material.get("size_spread") is not None:
        text += f"; size spread {material['size_spread']:.3g}"
    return text


def provenance_section(context: dict) -> tuple[str, str, str]:
    """What made this report: pydem, libdem, commit, machine, command, time, the measurement file and
    every store (its path, runs and the libdem that ran them)."""
    prov = dict(context.get("provenance", {}))
    rows = [[k, str(v)] for k, v in prov.items()]
    if context.get("measurements"):
        rows.append(["measurement file", context["measurements"]])
    material = context.get("material") or {}
    rows.append(["the material (its file's `material` rows)", material_text(material)])
    for rig, s in (context.get("stores") or {}).items():
        rows.append([f"store ({rig})", f"{s['path']} (made by commit {s.get('commit')}, libdem {s.get('libdem')})"
                     + (f"; pooled: {', '.join(s['pooled'])}" if s.get("pooled") else "")])
    md, h = page.table(rows, ["item", "value"])
    return "Provenance", md, h


def notes_section(notes: list[str]) -> tuple[str, str, str]:
    return ("Notes", "\n".join(f"- {n}" for n in notes),
            "<ul>" + "".join(f"<li>{html.escape(n)}</li>" for n in notes) + "</ul>")


def write_calibration(c, out: str | Path, context: dict | None = None) -> Path:
    """report.html / report.md / calibration.json of a calibration.Calibration, the measured-vs-model
    plot, and the admissible set as CSV (the points and nothing else)."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    data = c.as_dict()
    data["context"] = context or {}
    (out / "calibration.json").write_text(json.dumps(strict_json(data), indent=1, allow_nan=False))
    plots = {"residuals.png": plot_measured_vs_model(c.observations,
                                                      {"calibrated model": (c.model.predict(c.fit.best), c.model.sigma)}),
             "parameters.png": plot_parameters(c.fit, c.screening)}
    for name, png in plots.items():
        (out / name).write_bytes(png)
    pts = c.screening.get("points")
    if pts is not None:
        np.savetxt(out / "admissible.csv", pts, delimiter=",", header=",".join(c.screening["names"]), comments="",
                   fmt="%.10g")
    f = data["fit"]
    line = (f"chi^2/dof {f['chi2_per_dof']:.2f} over {f['n']} measurements ({f['dof']} dof, p = {_g(f['p_value'], '.2g')}), "
            f"RMSE of relative residuals {f['rmse_relative']:.3f}.")
    verdict = calibration_line(c)
    sections = [("Verdict", f"**{c.verdict}** — {verdict}", f"<p class='verdict'><b>{c.verdict}</b> — "
                 f"{html.escape(verdict)}</p>"),
                ("Fit", line, f"<p>{html.escape(line)}</p>"),
                parameter_section(data["parameters"], data["admissible_window"], "Parameters (posterior)"),
                residual_section(data["residuals"], "Residuals")]
    sections.append(nets_section({o.quantity: n for o, n in zip(c.observations, c.model.nets)}))
    names = data["correlation"]["names"] or []
    if names:
        rows = [[a] + [_g(v, "+.2f") for v in row] for a, row in zip(names, data["correlation"]["matrix"])]
        md, h = page.table(rows, ["correlation"] + names)
        sections.append(("Posterior correlations", md, h))
    if data["context"].get("confirm"):
        sections.append(confirm_section(data["context"]["confirm"]))
    if c.notes:
        sections.append(notes_section(c.notes))
    sections.append(glossary_section(CALIBRATION_TERMS))
    sections.append(provenance_section(data["context"]))
    return page.write_page(out, f"Calibration: {c.material}", sections, plots, head=3)
