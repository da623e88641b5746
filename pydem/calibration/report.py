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

VERDICT_TEXT = {
    "no_effect_needed": "The base model is consistent with the measurements: no candidate effect is needed.",
    "effect": "One missing effect explains the measurements significantly better than the base model: {effect}.",
    "effects": "Missing effects explain the measurements significantly better than the base model, each on top of "
               "the one before: {effects}.",
    "indistinguishable": "Missing effects explain the measurements significantly better than the base model, but "
                         "{effect} and {others} about equally well with these conditions.",
    "unexplained": "The base model fails, and none of the candidate effects explains the misfit.",
}


def verdict_line(d: Diagnosis) -> str:
    sig = [c.effect for c in d.candidates if c.p_value < ALPHA and c.effect != d.effect]
    text = VERDICT_TEXT["effects" if d.verdict == "effect" and d.added else d.verdict]
    line = text.format(effect=d.effect, others=", ".join(sig) or "another candidate", effects=" + ".join(d.effects))
    if not d.testable:
        line += (f" But with {len(d.observations)} measurement(s) for {len(d.base.names)} base parameters no candidate "
                 f"effect could be tested: measure more conditions.")
    if d.verdict == "no_effect_needed" and d.detectable:
        hidden = [f"{name} {_limits(info)}" for name, info in d.detectable.items()]
        line += (" It does not rule out effects these measurements cannot show (below their 90 % detection limits): "
                 + "; ".join(hidden) + ".")
    edges = [n for n, p in d.base.posterior.get("parameters", {}).items() if p.get("at_edge")]
    if edges:
        line += f" The base estimate sits at the edge of the campaign range for {', '.join(edges)}."
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


def plot_measured_vs_model(observations, models: dict[str, tuple[np.ndarray, np.ndarray]]) -> bytes:
    """Measured (error bars: each row's stated uncertainty) and each model's predictions with a band
    of +-1 sigma of measured - model at that model's estimate ({label: (values, sigma)}; the first
    dashed, the others solid) against each quantity's condition, one panel per quantity. Each
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
            col = f"C{k}"
            u = [observations[i].uncertainty if observations[i].uncertainty_given else 0.0 for i in ii]
            ax.errorbar(x, [observations[i].value for i in ii], yerr=u, fmt="o", color=col, capsize=3,
                        label=f"measured {label}".strip(), zorder=3)
            for m, (name, (pred, sigma)) in enumerate(models.items()):
                y, sd = pred[ii], sigma[ii]
                xm = x if len(x) > 1 else x + 0.25 * (m + 1)  # one point: each model beside the measurement
                ax.plot(xm, y, "--x" if m == 0 else "-+", color=col, alpha=0.8 if m == 0 else 1.0,
                        ms=6 if m == 0 else 10, label=f"{name} {label}".strip())
                if len(x) > 1:
                    ax.fill_between(x, y - sd, y + sd, color=col, alpha=0.08 if m == 0 else 0.18, lw=0)
                else:  # one point: the band as an error bar
                    ax.errorbar(xm, y, yerr=sd, fmt="none", color=col, alpha=0.5 if m == 0 else 0.9, capsize=3)
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
    fig, ax = plt.subplots(figsize=(5.5, 0.5 + 0.45 * max(len(d.candidates), 1)))
    names = [c.effect for c in d.candidates][::-1]
    vals = [c.statistic for c in d.candidates][::-1]
    from scipy import stats
    ax.barh(names, vals, color=["C3" if c.p_value < ALPHA else "C0" for c in d.candidates][::-1])
    ax.axvline(float(stats.chi2.isf(2 * ALPHA, 1)), color="k", ls=":", label=f"p = {ALPHA:g}, one-sided (cohesion)")
    ax.axvline(float(stats.chi2.isf(ALPHA, 1)), color="k", ls="--", label=f"p = {ALPHA:g}, two-sided")
    ax.set_xlabel("profile-likelihood ratio (chi^2 base - chi^2 with the effect)")
    ax.legend(fontsize=7)
    if not names:
        ax.text(0.5, 0.5, "no candidate covered by these campaigns", ha="center", transform=ax.transAxes)
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
    return page.write_page(out, f"Diagnosis: {d.material}", sections, plots, head=2)


def detectable_section(detectable: dict, units: dict) -> tuple[str, str, str]:
    """What these measurements can see: per candidate, the smallest effect on each side that the
    test finds with 90 % probability (detectability.py)."""
    def side(v, info, key):
        if key not in info:
            return "(one-sided)"
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
    rows = [[k, _g(v["estimate"]), f"{_g(v['lo'])} – {_g(v['hi'])}", _g(v["sd"]), "yes" if v["at_edge"] else ""]
            for k, v in params.items()]
    md, h = page.table(rows, ["parameter", "estimate", "95 % credible interval", "posterior sd", "at range edge"])
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


def confirm_section(rows: list[dict]) -> tuple[str, str, str]:
    table = [[r["label"], _g(r["measured"]), _g(r["dem"]), f"{100 * r['relative']:+.1f} %"] for r in rows]
    md, h = page.table(table, ["measurement", "measured", "DEM at the estimate", "(measured - DEM) / measured"])
    return "Confirming DEM runs", md, h


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
    if f["p_value"] < 0.001:
        line += " The model does not fit these measurements: run `pydem diagnose` to find which effect is missing."
    sections = [("Fit", line, f"<p class='verdict'>{html.escape(line)}</p>"),
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
    return page.write_page(out, f"Calibration: {c.material}", sections, plots, head=2)
