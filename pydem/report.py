"""The calibration report: PNG plots and a Markdown page (report.md) a user can read."""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from . import compare as cmp
from .plotting import pyplot


def plot_r2(tables: dict, path: Path):
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(6, 3.6))
    for key, table in tables.items():
        ax.plot([r["hidden"] for r in table], [r["best_holdout_r2"] for r in table], "o-", ms=3, label=key)
    ax.axhline(0.95, color="grey", ls=":", lw=1)
    ax.set_xlabel("hidden units")
    ax.set_ylabel("hold-out R² (best of restarts)")
    ax.set_ylim(max(-0.1, min(min(r["best_holdout_r2"] for r in t) for t in tables.values()) - 0.05), 1.0)
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def plot_parity(meta: dict, path: Path):
    plt = pyplot()
    fig, axes = plt.subplots(1, len(meta), figsize=(3.2 * len(meta), 3.2), squeeze=False)
    for ax, (key, m) in zip(axes[0], meta.items()):
        s, p = np.array(m["parity"]["simulated"]), np.array(m["parity"]["predicted"])
        lo, hi = min(s.min(), p.min()), max(s.max(), p.max())
        ax.plot([lo, hi], [lo, hi], "k:", lw=1)
        ax.plot(s, p, "o", ms=3)
        ax.set_title(f"{key}\nR² {m['holdout_r2']:.3f}, hidden {m['hidden']}", fontsize=8)
        ax.set_xlabel("simulated (hold-out)", fontsize=8)
        ax.set_ylabel("MLP", fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def plot_admissible(sc, path: Path):
    plt = pyplot()
    names = sc.names
    pairs = [(i, j) for i in range(len(names)) for j in range(i + 1, len(names))]
    fig, axes = plt.subplots(1, len(pairs), figsize=(3.6 * len(pairs), 3.4), squeeze=False)
    rng = np.random.default_rng(0)
    for ax, (i, j) in zip(axes[0], pairs):
        for k, (idx, colour) in enumerate(zip(sc.admissible, ("tab:blue", "tab:red", "tab:green"))):
            sub = idx if len(idx) <= 20000 else rng.choice(idx, 20000, replace=False)
            ax.plot(sc.points[sub, i], sc.points[sub, j], ".", ms=1.5, color=colour, alpha=0.5,
                    label=f"after {sc.stages[k].name} ({len(idx):,})")
        ax.set_xlim(*sc.ranges[names[i]])
        ax.set_ylim(*sc.ranges[names[j]])
        ax.set_xlabel(names[i])
        ax.set_ylabel(names[j])
    axes[0][0].legend(fontsize=7, markerscale=6, loc="upper right")
    fig.suptitle(f"admissible combinations of {len(sc.points):,} screened (pair projections)", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def plot_predicted_vs_measured(sc, nets, meas, window: float, path: Path):
    """Per screened quantity: the surrogate's predictions over the final admissible set (and over
    all combinations), against the measured value and the window."""
    plt = pyplot()
    if not nets:
        return False
    fig, axes = plt.subplots(1, len(nets), figsize=(3.4 * len(nets), 3.2), squeeze=False)
    final = sc.admissible[-1]
    rng = np.random.default_rng(1)
    allidx = rng.choice(len(sc.points), min(len(sc.points), 50000), replace=False)
    for ax, net, m in zip(axes[0], nets, meas):
        ax.hist(net(sc.points[allidx]), bins=60, color="lightgrey", density=True, label="all combinations")
        if len(final):
            ax.hist(net(sc.points[final]), bins=30, color="tab:red", alpha=0.7, density=True, label="admissible")
        ax.axvline(m.value, color="k", label="measured")
        ax.axvspan(m.value * (1 - window), m.value * (1 + window), color="k", alpha=0.08, label=f"±{100 * window:g} %")
        ax.set_title(m.label, fontsize=8)
        ax.set_yticks([])
    axes[0][0].legend(fontsize=6)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return True


def _fmt_range(r):
    return "—" if any(math.isnan(v) for v in r) else f"{r[0]:.3g} – {r[1]:.3g}"


def write(out: Path, summary: dict, trained: dict, sc, cnets, res_sur, res_dem, meas, stores) -> Path:
    from .mlp import NativeMLP
    plot_r2(trained["tables"], out / "r2_vs_hidden.png")
    plot_parity(trained["meta"], out / "parity_holdout.png")
    plot_admissible(sc, out / "admissible.png")
    calib = [m for st in sc.stages for m in st.measurements]
    has_pvm = plot_predicted_vs_measured(sc, cnets, calib, summary["window"], out / "predicted_vs_measured.png")
    cmp.plot(res_sur, out / "comparison.png", f"{summary['material']}: model at the best estimate vs measurements",
             extra={"DEM (confirming run)": res_dem} if res_dem else None)
    L = [f"# Calibration report: {summary['material']}", ""]
    L += [f"Measurements: `{summary['measurements']}`. Campaigns: " +
          ", ".join(f"{rig} `{p}` ({stores[rig].counts()['done']} runs, preset {stores[rig].spec.preset})"
                    for rig, p in summary["campaigns"].items()) + ".", ""]
    L += ["Parameters screened (the campaigns' common box): " +
          ", ".join(f"{n} [{lo:g}, {hi:g}]" for n, (lo, hi) in summary["ranges"].items()) + ".", ""]
    L += ["## Surrogates (one MLP per bulk property)", "",
          "Tanh hidden layer, linear output, inputs/targets scaled to [−1, 1], scaled conjugate gradient in float64 with "
          "early stopping; sizes 2–40 are compared on a fixed, seeded 15 % hold-out (so the hold-out R² is slightly "
          "optimistic: it also chose the size). Selection rule: " +
          ("the smallest size within one standard error of the best hold-out R² (the curve is flat within its noise; "
           "small nets screen faster)" if summary.get("selection") == "one-se"
           else "the size with the best hold-out R²") + ".", "",
          "Where design points were run more than once (different seeds), the nets fit the replicate means; "
          "the noise ceiling is the R² a perfect net would reach on those means (1 − pooled replicate variance "
          "/ replicates / variance of the means). Without replicates it comes from the runs' own standard errors "
          "(repeated shear points, blocks of a steady flow), marked \"within-run\": a lower bound on the "
          "run-to-run noise, so an upper bound on the ceiling.", "",
          "| net | points (runs) | hidden | hold-out R² | train R² | hold-out RMSE | best size: hidden, R² ± SE | noise ceiling |",
          "|---|---|---|---|---|---|---|---|"]
    for k, m in trained["meta"].items():
        ceiling = m.get("r2_noise_ceiling", float("nan"))
        L.append(f"| {k} | {m['samples']} ({m.get('runs', m['samples'])}) | {m['hidden']} | {m['holdout_r2']:.4f} | {m['train_r2']:.4f} | "
                 f"{m['holdout_rmse']:.4g} {m['unit']} | {m['best_hidden']}, {m['best_holdout_r2']:.4f} ± "
                 f"{m['holdout_r2_se']:.4f} | {'—' if ceiling != ceiling else f'{ceiling:.3f}'}"
                 f"{' (within-run)' if m.get('noise_source') == 'within-run' else ''} |")
    low = [(k, m) for k, m in trained["meta"].items() if m["holdout_r2"] < 0.95]
    if low:
        def why(m):  # within the hold-out's SE of the noise ceiling: only less noise helps
            ceiling, se = m.get("r2_noise_ceiling", float("nan")), m.get("holdout_r2_se", 0.0)
            if not math.isfinite(ceiling):
                return "no noise estimate (no replicates or run uncertainties)"
            if ceiling < 0.95:
                return (f"its noise ceiling {ceiling:.3f} is below the target whatever the net: more replicates per "
                        "design point (or a less noisy rig) raise it, more design points do not")
            if m["holdout_r2"] >= ceiling - se:
                return (f"at its noise ceiling {ceiling:.3f}: more replicates per design point (or a less noisy rig) "
                        "raise it, more design points do not")
            return f"below its noise ceiling {ceiling:.3f} by more than the hold-out SE: more design points should help"
        L += ["", "**Below the R² ≥ 0.95 target:**", ""] + [f"- {k}: {why(m)}" for k, m in low]
    L += ["", "![R² vs hidden size](r2_vs_hidden.png)", "", "![hold-out parity](parity_holdout.png)", ""]
    L += ["## Screening", "",
          f"{summary['samples']:,} combinations (scrambled Sobol, seed 7) evaluated natively by libdem "
          f"(OpenMP); kept when every prediction lies within ±{100 * summary['window']:g} % of the measured value.", "",
          "| stage | measured values | rows in | admissible | time |", "|---|---|---|---|---|"]
    for st in summary["stages"]:
        L.append(f"| {st['name']} | {', '.join(st['measured']) or 'none for this material'} | {st['rows']:,} | "
                 f"{st['admissible']:,} | {1e3 * st['seconds']:.1f} ms |")
    L += ["", "| parameter | box | " + " | ".join(f"after {st['name']}" for st in summary["stages"]) + " |",
          "|---|---|" + "---|" * len(summary["stages"])]
    for n, r in summary["ranges"].items():
        L.append(f"| {n} | {_fmt_range(r)} | " + " | ".join(_fmt_range(st["ranges"][n]) for st in summary["stages"]) + " |")
    first, last = summary["stages"][0]["admissible"], summary["stages"][-1]["admissible"]
    if len(summary["stages"]) > 1 and summary["stages"][0]["measured"] and first:
        if summary["stages"][-1]["measured"]:
            L += ["", f"The angle-of-repose nets narrowed the admissible set from {first:,} to {last:,} combinations "
                  f"({100 * (1 - last / first) if first else 0:.1f} % removed)."]
        else:
            L += ["", "**Not narrowed:** the measurement file has no angle-of-repose value for this material, so the "
                  "validation step of seed 000 cannot be applied; below are the AoR nets' predictions over the "
                  "admissible set — what a heap test should find if the calibration holds."]
    for k in trained["meta"]:
        if k.startswith("aor__") and len(sc.admissible[-1]):
            y = NativeMLP(out / "nets" / f"{k}.mlp")(sc.points[sc.admissible[-1]])
            L.append(f"- {k}: predicted {np.percentile(y, 5):.4g} – {np.percentile(y, 95):.4g} (5–95 %) over the "
                     f"admissible set")
    reach = []
    for net, m in zip(cnets, calib):
        y = net(sc.points[np.random.default_rng(2).choice(len(sc.points), min(len(sc.points), 100000), replace=False)])
        reach.append(f"- {m.label}: measured {m.value:.4g}; the surrogate reaches {y.min():.4g} – {y.max():.4g} over the box")
    if reach:
        L += ["", "Reachable by the model (surrogate over the screening box):", ""] + reach
    if summary["skipped_measurements"]:
        L += ["", "Measured values without a net (not screened): " + ", ".join(summary["skipped_measurements"])]
    L += ["", "![admissible region](admissible.png)", ""]
    if has_pvm:
        L += ["![predicted vs measured](predicted_vs_measured.png)", ""]
    if len(sc.admissible[-1]):
        L += ["## Best estimate", "", "The admissible combination with the least misfit (sum of squared residuals over "
              "the measured uncertainties):", ""]
    else:
        L += ["## Best estimate", "", "**No combination is admissible.** Shown instead: the combination of least misfit "
              "over the whole box — the model cannot reproduce the measurements within the window there (see the "
              "reachable ranges below): a sign of a missing physical effect or too narrow a box.", ""]
    L += [f"- **{k}** = {v:.4g}" for k, v in summary["best"].items()]
    L += ["", "## Model vs measurements", "", "### Surrogate at the best estimate", "", cmp.table_markdown(res_sur), ""]
    if res_dem:
        L += ["### Confirming DEM runs at the best estimate", "", cmp.table_markdown(res_dem), ""]
        L += [f"Note — {n}." for n in summary.get("protocol_notes", [])] + ([""] if summary.get("protocol_notes") else [])
    L += ["![comparison](comparison.png)", ""]
    L += ["Nets exported to `nets/` (libdem weights files, `*.mlp`) and `nets/c/` (standalone C99 source/header); "
          "R² against hidden size in `r2_vs_hidden.csv`; everything above in `summary.json`."]
    path = out / "report.md"
    path.write_text("\n".join(L) + "\n")
    return path
