"""Model against measurements (the first half of the diagnosis loop, DESIGN section 9): a
residual table with z-scores, plots of measured and model values per quantity and condition,
and the overall error (RMSE of relative residuals, chi^2 per measured value with an uncertainty).

A model is a mapping "rig:metric" -> (value, uncertainty): from the surrogate nets at a
parameter set (`surrogate_model`) or from confirming DEM runs (`dem_model`)."""
from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .measurements import Measurement


@dataclass
class Residual:
    m: Measurement
    model: float  # NaN: the model has no such quantity
    model_unc: float

    @property
    def residual(self) -> float:
        return self.model - self.m.value

    @property
    def z(self) -> float:
        """Residual over the combined standard uncertainty (NaN without a measured uncertainty)."""
        u = math.hypot(self.m.uncertainty, self.model_unc if self.model_unc == self.model_unc else 0.0)
        return self.residual / u if u > 0 else math.nan

    @property
    def relative(self) -> float:
        return self.residual / abs(self.m.value) if self.m.value else math.nan


def compare(measurements: list[Measurement], model: dict[str, tuple[float, float]]) -> list[Residual]:
    out = []
    for m in measurements:
        v, u = model.get(f"{m.rig}:{m.metric}", (math.nan, math.nan))
        out.append(Residual(m, float(v), float(u)))
    return out


def overall(res: list[Residual]) -> dict:
    rel = np.array([r.relative for r in res if r.model == r.model])
    z = np.array([r.z for r in res if r.z == r.z])
    return {"rows": len(res), "modelled": int(rel.size),
            "rmse_relative": float(np.sqrt(np.mean(rel ** 2))) if rel.size else math.nan,
            "chi2_per_value": float(np.mean(z ** 2)) if z.size else math.nan, "chi2_values": int(z.size)}


def table_markdown(res: list[Residual]) -> str:
    lines = ["| quantity | measured | model | residual | z | relative | use |", "|---|---|---|---|---|---|---|"]
    for r in res:
        u = f" ± {r.m.uncertainty:.4g}" if r.m.uncertainty == r.m.uncertainty else ""
        mu = f" ± {r.model_unc:.3g}" if r.model_unc == r.model_unc and r.model_unc > 0 else ""
        model = f"{r.model:.4g}{mu}" if r.model == r.model else "not modelled"
        z = f"{r.z:+.2f}" if r.z == r.z else "n/a"
        rel = f"{100 * r.relative:+.1f} %" if r.relative == r.relative else "n/a"
        unit = f" {r.m.unit}" if r.m.unit else ""
        lines.append(f"| {r.m.label} | {r.m.value:.4g}{u}{unit} | {model} | {r.residual:+.3g} | {z} | {rel} | {r.m.use} |")
    o = overall(res)
    lines.append("")
    chi2 = f"{o['chi2_per_value']:.2f}" if o["chi2_values"] else "n/a"
    lines.append(f"Overall: RMSE of relative residuals {100 * o['rmse_relative']:.2f} % over {o['modelled']} modelled values; "
                 f"chi^2 per value {chi2} over the {o['chi2_values']} values with uncertainties "
                 "(no degrees of freedom subtracted: the parameters are an admissible set, not a least-squares fit).")
    return "\n".join(lines)


def plot(res: list[Residual], path: str | Path, title: str = "model vs measurements", extra: dict | None = None):
    """One panel per quantity: measured (with uncertainty) and model values against the condition.
    extra: other models to overlay, {label: list[Residual]}."""
    from .plotting import pyplot
    plt = pyplot()
    groups: dict[str, list[int]] = {}
    for i, r in enumerate(res):
        groups.setdefault(f"{r.m.test}:{r.m.quantity}", []).append(i)
    fig, axes = plt.subplots(1, len(groups), figsize=(3.6 * len(groups), 3.4), squeeze=False)
    for ax, (name, idx) in zip(axes[0], groups.items()):
        labels = [", ".join(f"{k}={v}" for k, v in res[i].m.conditions.items()) or "-" for i in idx]
        xs = np.arange(len(idx))
        meas = [res[i].m.value for i in idx]
        err = [res[i].m.uncertainty if res[i].m.uncertainty == res[i].m.uncertainty else 0 for i in idx]
        ax.errorbar(xs - 0.1, meas, yerr=err, fmt="o", color="k", capsize=4, label="measured")
        sets = {"model": res, **(extra or {})}
        for (lab, rr), mk in zip(sets.items(), ("s", "^", "D", "v")):
            ax.errorbar(xs + 0.1, [rr[i].model for i in idx],
                        yerr=[rr[i].model_unc if rr[i].model_unc == rr[i].model_unc else 0 for i in idx],
                        fmt=mk, capsize=3, label=lab)
        ax.set_xticks(xs, labels, rotation=20, fontsize=7)
        unit = res[idx[0]].m.unit
        ax.set_title(name + (f" [{unit}]" if unit else ""), fontsize=9)
        ax.set_xlim(-0.6, len(idx) - 0.4)
    axes[0][0].legend(fontsize=7)
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def net_key(rig: str, metric: str) -> str:
    """File stem of an exported property net: ring-shear, mu_ie_ps -> ring_shear__mu_ie_ps."""
    return f"{rig.replace('-', '_')}__{metric}"


def surrogate_model(nets_dir: str | Path, params: dict[str, float]) -> dict[str, tuple[float, float]]:
    """Every exported net in nets_dir (files '<rig>__<metric>.mlp') at one parameter set (libdem
    inference). The uncertainty given is the net's hold-out RMSE when recorded (nets.json)."""
    from .mlp import NativeMLP
    nets_dir = Path(nets_dir)
    meta = json.loads((nets_dir / "nets.json").read_text()) if (nets_dir / "nets.json").exists() else {}
    out = {}
    for f in sorted(nets_dir.glob("*__*.mlp")):
        net = NativeMLP(f)
        missing = [n for n in net.input_names if n not in params]
        if missing:
            raise ValueError(f"{f.name} needs parameter(s) {', '.join(missing)}")
        rig, metric = f.stem.split("__", 1)
        rig = meta.get(f.stem, {}).get("rig", rig.replace("_", "-"))  # file names use ring_shear for ring-shear
        x = np.array([[params[n] for n in net.input_names]])
        out[f"{rig}:{metric}"] = (float(net(x)[0]), float(meta.get(f.stem, {}).get("holdout_rmse", math.nan)))
    return out


def dem_model(result_files: list[str | Path]) -> dict[str, tuple[float, float]]:
    """Metrics of rig results saved as JSON (`pydem rig ... --out r.json`)."""
    out = {}
    for f in result_files:
        d = json.loads(Path(f).read_text())
        for k, m in d["metrics"].items():
            out[f"{d['rig']}:{k}"] = (float(m["value"]), float(m["uncertainty"]) if m["uncertainty"] is not None else math.nan)
    return out
