"""DEM evidence for the material rules of pydem/calibration/similarity.py at the default presets
(the shipped diagnosis stores' rigs): at two points of the campaign box, each rig is run at the
stores' material (2500 kg/m^3, E = 5 MPa, the preset's sphere size) and at five others:

  rho x0.5, rho x1.6  particle density with Young's modulus, cohesion energy density and the
                      pre-shear stress scaled with it (exact similarity: the same motion)
  E x4                a four times stiffer model (stiffness number / 4; not a similarity)
  d x0.8, d x1.25     spheres 0.8 / 1.25 times the preset's, in the same cell (particle count
                      scaled by 1/lambda^3: the same bed volume; the hopper's slot scaled with
                      the spheres, so the slot over the sphere size is the store's)

Each row is one run; the program appends to --out (JSON lines) and skips the runs already there,
so a killed run resumes. One core per run (num_threads = 1), runs one after the other.
bench/similarity_report.py turns the file into the table of bench/README.md.

    .venv/bin/python bench/similarity_default.py --out bench/results/similarity_default.jsonl
"""
from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from pydem.rigs import RIGS, load  # noqa: E402

COHESION = "effects.cohesion_sjkr.cohesion_energy_density"
# two points of the diagnosis box: a free-flowing one and a rough, cohesive one
POINTS = {
    "free": {"friction": 0.4, "rolling_friction": 0.1, "restitution": 0.5, "wall_friction": 0.4, COHESION: 0.0},
    "rough": {"friction": 0.7, "rolling_friction": 0.3, "restitution": 0.4, "wall_friction": 0.6, COHESION: 3e4},
}
# variant -> (density factor k, modulus factor, size factor lambda)
VARIANTS = {"store": (1.0, 1.0, 1.0), "rho x0.5": (0.5, 0.5, 1.0), "rho x1.6": (1.6, 1.6, 1.0),
            "E x4": (1.0, 4.0, 1.0), "d x0.8": (1.0, 1.0, 0.8), "d x1.25": (1.0, 1.0, 1.25)}
# each rig's store settings (data/campaigns/diag_<rig>_default.toml [set]) and the store's condition
RIG_SET = {"hopper": ["density_boxes=below_surface", "num_threads=1", "slot_width=0.054"],
           "ring-shear": ["num_threads=1", "shear_points=[0.3, 0.6, 0.9]", "preshear_stress=2000.0"],
           "aor": ["num_threads=1"]}


def overrides(rig: str, point: dict, variant: str) -> list[str]:
    k, e, lam = VARIANTS[variant]
    cls, cfg_cls = RIGS[rig]
    base = load(cfg_cls, "default", None, RIG_SET[rig])
    out = list(RIG_SET[rig])
    out += [f"{'params.' if n in ('friction', 'rolling_friction', 'restitution', 'wall_friction') else ''}{n}="
            f"{v * (k if n == COHESION else 1.0)}" for n, v in point.items()]
    out += [f"params.density={base.params.density * k}", f"params.youngs_modulus={base.params.youngs_modulus * e}"]
    if rig == "ring-shear":
        out.append(f"preshear_stress={base.preshear_stress * k}")
    if lam != 1.0:
        out.append(f"particles={round(base.particles / lam ** 3)}")
        if rig == "hopper":
            out += [f"d_small={base.d_small * lam}", f"d_large={base.d_large * lam}", f"slot_width={base.slot_width * lam}"]
        else:
            out.append(f"diameter={base.diameter * lam}")
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", required=True)
    ap.add_argument("--seeds", type=int, nargs="+", default=[1])
    ap.add_argument("--rigs", nargs="+", default=["hopper", "ring-shear", "aor"])
    args = ap.parse_args()
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    done = set()
    if out.exists():
        for line in out.read_text().splitlines():
            r = json.loads(line)
            done.add((r["rig"], r["point"], r["variant"], r["seed"]))
    for seed in args.seeds:
        for point_name, point in POINTS.items():
            for rig in args.rigs:
                for variant in VARIANTS:
                    if (rig, point_name, variant, seed) in done:
                        continue
                    cls, cfg_cls = RIGS[rig]
                    over = overrides(rig, point, variant)
                    t0 = time.perf_counter()
                    row = {"rig": rig, "point": point_name, "variant": variant, "seed": seed, "overrides": over}
                    try:
                        r = cls(load(cfg_cls, "default", None, over)).run(seed=seed)
                        row["metrics"] = {m: v.value for m, v in r.metrics.items()}
                    except Exception as exc:  # kept with its reason, never dropped
                        row["error"] = f"{type(exc).__name__}: {exc}"
                    row["seconds"] = time.perf_counter() - t0
                    with out.open("a") as f:
                        f.write(json.dumps(row) + "\n")
                    print(rig, point_name, variant, seed, f"{row['seconds']:.0f} s", row.get("error", ""), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
