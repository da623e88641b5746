"""Plausibility sweeps of the rigs (issue 4), with committed results and plots.

    .venv/bin/python studies/plausibility.py aor          # angle vs mu_r and vs mu_s
    .venv/bin/python studies/plausibility.py ring-shear   # mu_ie-ps vs mu_s; cohesion -> intercept
    .venv/bin/python studies/plausibility.py hopper       # Beverloo over slot widths
    .venv/bin/python studies/plausibility.py plot         # redraw the plots from the CSVs

Each finished point is appended to studies/results/plausibility/<sweep>.jsonl at once, and points
already there are skipped: a killed sweep resumes where it stopped.
"""
from __future__ import annotations

import json
import math
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
OUT = ROOT / "studies" / "results" / "plausibility"

from pydem.rigs import (AngleOfRepose, AorConfig, Hopper, HopperConfig, RingShear, RingShearConfig,  # noqa: E402
                        beverloo_fit, load)


def rows(name: str) -> list[dict]:
    """The finished points of a sweep (JSON lines: rigs report different metrics per point)."""
    p = OUT / f"{name}.jsonl"
    return [json.loads(line) for line in open(p)] if p.exists() else []


def append(path: Path, row: dict):
    with open(path, "a") as f:
        f.write(json.dumps(row) + "\n")


def sweep(name: str, points: list[tuple[str, object, list[str], dict]]):
    """points: (key, rig class, config class, preset, overrides) -> one CSV row of metrics each."""
    OUT.mkdir(parents=True, exist_ok=True)
    path = OUT / f"{name}.jsonl"
    have = {r["key"] for r in rows(name)}
    for key, rig, cfg_cls, preset, overrides in points:
        if key in have:
            continue
        t0 = time.perf_counter()
        res = rig(load(cfg_cls, preset, overrides=overrides)).run(seed=1)
        row = {"key": key, "overrides": " ".join(overrides), "wall_s": round(time.perf_counter() - t0, 1)}
        for k, m in res.metrics.items():
            row[k], row[k + "_se"] = m.value, m.uncertainty
        row["info"] = {k: v for k, v in res.info.items() if k in ("particles", "steps", "emptied", "at_rest",
                                                                  "slot_width")}
        append(path, row)
        print(f"{name}: {key}: " + ", ".join(f"{k} {m}" for k, m in res.metrics.items()), flush=True)


def aor():
    pts = [(f"mu_r={v}", AngleOfRepose, AorConfig, "default", [f"rolling_friction={v}"]) for v in (0.0, 0.05, 0.1, 0.2, 0.4)]
    pts += [(f"mu_s={v}", AngleOfRepose, AorConfig, "default", [f"friction={v}"]) for v in (0.2, 0.35, 0.8)]
    sweep("aor", pts)


def ring_shear():
    pts = [(f"mu_s={v}", RingShear, RingShearConfig, "tiny", [f"friction={v}"]) for v in (0.1, 0.3, 0.5, 0.8, 1.2)]
    pts += [(f"coh={c}", RingShear, RingShearConfig, "tiny",
             ["shear_points=[0.4,0.8]", f"effects.cohesion_sjkr.cohesion_energy_density={c}"]) for c in (0.0, 5e4)]
    sweep("ring_shear", pts)


def hopper():
    pts = [(f"b={b}", Hopper, HopperConfig, "default", [f"slot_width={b}", "packing=A", "fine_fraction=0.0"])
           for b in (0.036, 0.045, 0.054, 0.066, 0.08)]
    sweep("hopper", pts)


def plot():
    from pydem.plotting import pyplot
    plt = pyplot()

    fig, axes = plt.subplots(1, 3, figsize=(13, 3.8))
    r = rows("aor")
    for tag, ax_label, col in (("mu_r", "rolling friction mu_r", "tab:blue"), ("mu_s", "sliding friction mu_s", "tab:orange")):
        pts = sorted((float(x["key"].split("=")[1]), float(x["angle_of_repose"]), float(x["angle_of_repose_se"]))
                     for x in r if x["key"].startswith(tag))
        if pts:
            axes[0].errorbar([p[0] for p in pts], [p[1] for p in pts], [p[2] for p in pts], marker="o", label=ax_label, color=col)
    axes[0].set(xlabel="friction coefficient", ylabel="angle of repose (deg)", title="static AoR (default preset)")
    axes[0].legend()
    r = rows("ring_shear")
    pts = sorted((float(x["key"].split("=")[1]), float(x["mu_ie_ps"]), float(x["mu_ie_ps_se"]))
                 for x in r if x["key"].startswith("mu_s"))
    if pts:
        axes[1].errorbar([p[0] for p in pts], [p[1] for p in pts], [p[2] for p in pts], marker="o", label="mu_ie-ps")
    for x in r:
        if x["key"].startswith("coh"):
            axes[1].annotate(f"{x['key']}: intercept {float(x['yield_locus_intercept']):.0f} Pa",
                             (0.05, 0.9 - 0.08 * float(x["key"].split("=")[1] != "0.0")), xycoords="axes fraction", fontsize=8)
    axes[1].set(xlabel="sliding friction mu_s", ylabel="mu_ie-ps", title="ring shear (tiny preset)")
    r = rows("hopper")
    if r:
        b = [float(x["key"].split("=")[1]) for x in r]
        w = [float(x["mass_flow_rate"]) for x in r]
        rho = sum(float(x["bulk_density"]) for x in r) / len(r)
        fit = beverloo_fit(b, w, 9e-3, rho, 0.04)
        bb = [min(b) + (max(b) - min(b)) * i / 50 for i in range(51)]
        wf = [fit["C"] * rho * math.sqrt(9.81) * 0.04 * max(x - fit["k"] * 9e-3, 0) ** 1.5 for x in bb]
        axes[2].plot([x * 1e3 for x in b], w, "o", label="DEM")
        axes[2].plot([x * 1e3 for x in bb], wf, "-", label=f"Beverloo C={fit['C']:.2f} k={fit['k']:.2f}")
        axes[2].set(xlabel="slot width b (mm)", ylabel="mass flow rate (kg/s)", title="wedge hopper, 9 mm spheres")
        axes[2].legend()
        (OUT / "beverloo_fit.json").write_text(json.dumps(fit, indent=1))
    fig.tight_layout()
    fig.savefig(OUT / "plausibility.png", dpi=110)
    print("plots:", OUT / "plausibility.png")


if __name__ == "__main__":
    cmd = sys.argv[1] if len(sys.argv) > 1 else "plot"
    {"aor": aor, "ring-shear": ring_shear, "hopper": hopper, "plot": plot}[cmd]()
    if cmd != "plot":
        plot()
