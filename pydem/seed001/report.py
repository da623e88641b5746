"""The seed 001 report: the grey relational analysis, the four-CNN comparison (Table 2), AlexNet-FC
point to point on both splits, the CNN-LSTM process prediction per packing pattern, each beside
its physics baseline and the seed's own numbers, and the CPU-time accounting; report.html
(self-contained) and report.md with the plots as PNG files (pydem.report_page).

    .venv/bin/python -m pydem.seed001 report --store STORE --results DIR --out DIR"""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from .. import report_page as page
from .gra import PARAMETERS, gra_tables
from .store import FrameStore

# seed 001's own figures (its Table 2, Fig. 3c, Fig. 6 and Section 4)
SEED_TABLE2 = {"alexnet": (46.617, 61.286, 0.997), "resnet50": (358.937, 513.528, 0.714),
               "vgg16": (50.336, 71.685, 0.995), "vgg19": (62.751, 90.607, 0.994)}  # MAE, RMSE (ms), R^2
SEED_GRA = {"diameter": 11.14, "youngs_modulus": 7.17}  # highest and lowest mean weights, %
SEED_FC = "R^2 >= 0.997 for every packing, worst average relative error 0.063 (random frames)"
SEED_LSTM = "average relative error >= 0.082 (A, B2, B3), above 0.39 for B1 and B4"


def _load(path: Path) -> dict | None:
    return json.loads(path.read_text()) if path.exists() else None


def _f(v, fmt=".3g") -> str:
    return "–" if v is None or (isinstance(v, float) and not np.isfinite(v)) else format(v, fmt)


def gra_section(store, plots: dict):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    s = FrameStore(store)
    discharge = {c: float(s.read_case(c)["discharge_time"]) for c in s.cases()}
    tables = gra_tables(discharge)
    rows = [[p] + [_f(t[p], ".2f") for t in tables.values()] + [_f(SEED_GRA.get(p), ".2f")] for p in PARAMETERS]
    md, h = page.table(rows, ["parameter (weight %)"] + list(tables) + ["seed 001, mean"])
    fig, ax = plt.subplots(figsize=(9, 3.6))
    width = 0.8 / max(len(tables), 1)
    for i, (name, t) in enumerate(tables.items()):
        ax.bar(np.arange(len(PARAMETERS)) + i * width, [t[p] for p in PARAMETERS], width, label=name)
    ax.set_xticks(np.arange(len(PARAMETERS)) + 0.4 - width / 2, PARAMETERS, rotation=40, ha="right")
    ax.set_ylabel("GRA weight (%)")
    ax.set_ylim(min(min(t.values()) for t in tables.values()) - 0.5, max(max(t.values()) for t in tables.values()) + 0.5)
    ax.legend(ncol=6, fontsize=8)
    plots["gra.png"] = page.png(fig)
    top = max(tables["all"], key=tables["all"].get) if "all" in tables else None
    low = min(tables["all"], key=tables["all"].get) if "all" in tables else None
    line = (f"Over {len(discharge)} cases: highest {top} ({tables['all'][top]:.2f} %), lowest {low} "
            f"({tables['all'][low]:.2f} %); seed 001: diameter highest (11.14 %), Young's modulus lowest (7.17 %).") if top else ""
    return ("Grey relational analysis (discharge time)", line + "\n\n" + md, f"<p>{line}</p>" + h), discharge


def compare_section(res: dict):
    rows = []
    for name, r in res["models"].items():
        seed = SEED_TABLE2.get(name, (None,) * 3)
        rows.append([name, _f(1e3 * r["mae"]), _f(1e3 * r["rmse"]), _f(r["r2"]), _f(seed[0]), _f(seed[1]), _f(seed[2]),
                     str(r.get("epochs_run", res["settings"]["epochs"])), f"{r['train_seconds']:.0f}",
                     _f(r["predict_ms_per_frame"])])
    b = res["baseline"]
    rows.append(["Beverloo x fill fraction", _f(1e3 * b["mae"]), _f(1e3 * b["rmse"]), _f(b["r2"]), "", "", "", "", "", ""])
    md, h = page.table(rows, ["network", "MAE (ms)", "RMSE (ms)", "R^2", "seed MAE", "seed RMSE", "seed R^2", "epochs",
                          "train s", "predict ms/frame"])
    st = res["settings"]
    budget = f" or {st['time_budget_s']:.0f} s of training, whichever came first" if "time_budget_s" in st else ""
    line = (f"{st['frames']} frames at {st['size']} x {st['size']}, {st['split']}, up to {st['epochs']} epochs{budget}, "
            f"batch {st['batch']}, Adam lr {st['lr']}; {res['machine']}.")
    return "Four CNNs on the remaining discharge time (seed 001 Table 2)", line + "\n\n" + md, f"<p>{line}</p>" + h


def point_to_point_section(res: dict, plots: dict):
    import matplotlib.pyplot as plt
    rows = []
    for split, r in res["splits"].items():
        rows.append([split, "all", _f(r["all"]["r2"]), _f(r["all"]["relative_error"]), _f(r["baseline_all"]["r2"]),
                     _f(r["baseline_all"]["relative_error"])])
        for pk, p in r["per_packing"].items():
            rows.append([split, pk, _f(p["net"]["r2"]), _f(p["net"]["relative_error"]), _f(p["baseline"]["r2"]),
                         _f(p["baseline"]["relative_error"])])
    md, h = page.table(rows, ["split", "packing", "AlexNet-FC R^2", "relative error", "baseline R^2", "baseline relative error"])
    fig, axes = plt.subplots(1, len(res["splits"]), figsize=(5 * len(res["splits"]), 4.2), squeeze=False)
    for ax, (split, r) in zip(axes[0], res["splits"].items()):
        t = r["test"]
        y = np.array(t["remaining"])
        for pk in ("A", "B1", "B2", "B3", "B4"):
            m = np.array([c.split("-")[0] == pk for c in t["case"]])
            if m.any():
                ax.plot(y[m], np.array(t["predicted"])[m], ".", ms=3, label=pk)
        ax.plot([0, y.max()], [0, y.max()], "k-", lw=0.8)
        ax.set_title(f"{split}: R^2 {r['all']['r2']:.3f}", fontsize=10)
        ax.set_xlabel("remaining discharge time, DEM (s)")
        ax.set_ylabel("AlexNet-FC (s)")
        ax.legend(fontsize=7, markerscale=3)
    plots["parity.png"] = page.png(fig)
    st = res["settings"]
    line = (f"{st['frames']} frames at {st['size']} x {st['size']}, {st['epochs']} epochs; leave-cases-out tests on "
            f"{', '.join(st['test_cases'])} (validation {', '.join(st['validation_cases'])}). Seed 001: {SEED_FC}.")
    return "AlexNet-FC point to point", line + "\n\n" + md, f"<p>{line}</p>" + h


def process_section(res: dict, plots: dict):
    import matplotlib.pyplot as plt
    zero = any("zero_shot" in v for v in res["per_packing"].values())
    # the gauges each run has (older runs lack one or both)
    gauges = [g for g in ("fill_level", "species") if all(g in v for v in res["per_packing"].values())]
    rows = [[pk, _f(v["net"])] + ([_f(v["zero_shot"])] if zero else []) + [_f(v["baseline"])]
            + [_f(v[g]) for g in gauges] for pk, v in res["per_packing"].items()]
    md, h = page.table(rows, ["packing", "CNN-LSTM relative error"] + (["zero-shot (no frame of the case)"] if zero else [])
                   + ["constant-rate relative error"] + [f"{g.replace('_', '-')} gauge relative error" for g in gauges])
    fig, axes = plt.subplots(1, 5, figsize=(13, 2.8), sharey=True)
    for ax, pk in zip(axes, ("A", "B1", "B2", "B3", "B4")):
        cases = [c for c in res["cases"] if c.split("-")[0] == pk]
        if not cases:
            continue
        r = res["cases"][cases[0]]
        ax.plot(r["time"], r["nrrp"], "k-", label="DEM")
        ax.plot(r["time"], r["predicted"], "C0--", label="CNN-LSTM")
        ax.plot(r["time"], r["baseline_nrrp"], "C1:", label="constant rate")
        for g, style in (("fill_level", "C2-."), ("species", "C3-.")):
            if f"{g}_nrrp" in r:
                ax.plot(r["time"], r[f"{g}_nrrp"], style, label=f"{g.replace('_', '-')} gauge")
        ax.set_title(cases[0], fontsize=9)
        ax.set_xlabel("t (s)")
    axes[0].set_ylabel("NRRP")
    axes[0].legend(fontsize=7)
    plots["nrrp.png"] = page.png(fig)
    st = res["settings"]
    if st.get("protocol", "per-case") == "pretrained":
        how = (f"Pretrained on other cases' whole discharges (leave-fold-out, {st['epochs']} epochs), fine-tuned on "
               f"each case's first {st['fraction']:.0%} ({st['finetune_epochs']} epochs)")
    else:
        how = f"Per case: trained on the first {st['fraction']:.0%} of its frames, {st['epochs']} epochs"
    seen = " (two channels: fine and coarse spheres)" if st.get("inputs") == "species" else ""
    line = f"{how}; windows of {st['window']}, frames {st['size']} x {st['size']}{seen}. Seed 001: {SEED_LSTM}."
    return "CNN-LSTM process prediction (NRRP)", line + "\n\n" + md, f"<p>{line}</p>" + h


def write(store, results, out) -> Path:
    results, out = Path(results), Path(out)
    out.mkdir(parents=True, exist_ok=True)
    plots: dict[str, bytes] = {}
    gra, _ = gra_section(store, plots)
    sections = [gra]
    for name, build in (("compare.json", lambda r: compare_section(r)),
                        ("point_to_point.json", lambda r: point_to_point_section(r, plots)),
                        ("process.json", lambda r: process_section(r, plots))):
        r = _load(results / name)
        if r is not None:
            sections.append(build(r))
    for name, png in plots.items():
        (out / name).write_bytes(png)
    return page.write_page(out, "Seed 001: hopper images", sections, plots, head=len(sections))
