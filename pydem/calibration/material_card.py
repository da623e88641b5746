"""The material card: a calibration's parameters as input for the code the user runs —
`material_card.json` (every parameter with its 95 % interval, the fixed ones, the models),
`material_card.liggghts` (fix property/global + pair_style gran: hertz, tangential history,
EPSD2 rolling friction, SJKR cohesion — the same models as libdem) and
`material_card.lammps` (pair_style granular: the nearest models LAMMPS has, the differences
said in its comments). Atom type 1 = the particles, type 2 = the walls."""
from __future__ import annotations

import json
from pathlib import Path

from ..rigs.result import strict_json


CLEAN_VERDICTS = ("calibrated", "no_effect_needed", "effect")


def card(material: str, setup, fit, candidates, verdict: str, verdict_line: str, scaling=None) -> dict:
    """The parameters of a fitted model: the free ones at their estimates (with the posterior's
    95 % interval), the candidates not freed at their neutral values, and the solid and wall
    constants the campaign stores hold fixed; with the report's verdict and the caveats that
    qualify the numbers (a verdict that is not clean, estimates at a range edge, one-sided
    intervals), which the LIGGGHTS and LAMMPS files repeat as comments above the numbers. With a
    `scaling` (similarity.Scaling: the material's own particle density) the card is in the
    material's terms: its density, the model's Young's modulus that keeps the stores' stiffness
    number, and the cohesion energy density scaled back."""
    est = fit.as_dict()
    post = fit.posterior.get("parameters", {})
    values = {c.parameter: c.neutral_value(est) for c in candidates}
    values.update(est)
    store = next(iter(setup.stores.values()))
    fixed = store.spec.config({}).params  # the campaigns' solid and wall constants
    caveats = [] if verdict in CLEAN_VERDICTS else [f"verdict {verdict}: {verdict_line}"]
    for name, p in post.items():
        if p.get("at_edge"):
            caveats.append(f"{name} = {est[name]:.4g} sits at the edge of its campaign range {p['range']}: a bound, not "
                           f"an estimate")
        elif p.get("interval", "central") != "central":
            caveats.append(f"{name}: its 95 % interval is {p['interval']} ({p['lo']:.4g}-{p['hi']:.4g})")
    params = {}
    for name, v in values.items():
        p = post.get(name, {})
        params[name] = {"value": float(v), "interval_95": [p.get("lo"), p.get("hi")] if p else None,
                        "calibrated": name in est}
    for name in ("youngs_modulus", "poisson_ratio", "density", "wall_restitution", "wall_rolling_friction"):
        params.setdefault(name, {"value": float(getattr(fixed, name)), "interval_95": None, "calibrated": False})
    if scaling is not None and scaling.factor != 1.0:
        params["density"]["value"] = float(scaling.material.particle_density)
        params["youngs_modulus"]["value"] = float(scaling.model_modulus)
        coh = params.get("effects.cohesion_sjkr.cohesion_energy_density")
        if coh is not None:
            coh["value"] = scaling.cohesion_to_material(coh["value"])
            if coh["interval_95"] and None not in coh["interval_95"]:
                coh["interval_95"] = [scaling.cohesion_to_material(x) for x in coh["interval_95"]]
        caveats.append(f"scaled from the stores' particle density {scaling.store_density:g} kg/m^3 by similarity "
                       f"(docs/diagnosis.md §1): density, Young's modulus and cohesion energy density in this "
                       f"material's terms")
    coh = params.get("effects.cohesion_sjkr.cohesion_energy_density")
    if scaling is not None and coh is not None:  # Bo = k_c / (rho_p g d): the dimensionless cohesion the stores serve
        coh["bond_number"] = scaling.bond_number(coh["value"] * scaling.factor)
    if scaling is not None and scaling.material.mean_diameter is not None:
        sizes = ", ".join(f"{rig} {1e3 * d:.3g} mm" for rig, d in sorted(scaling.store_diameters.items()))
        caveats.append(f"the model's spheres are the stores' coarse-grained ones ({sizes}), not the material's "
                       f"{1e3 * scaling.material.mean_diameter:.4g} mm mean: give the particles those sizes")
    return {"material": material, "verdict": verdict, "caveats": caveats, "models": {"normal": "Hertz", "damping": "restitution-based (seed 000)",
                                             "tangential": "Mindlin history, Coulomb cap", "rolling": fixed.rolling_model,
                                             "effects": sorted({c.name for c in candidates if c.parameter.startswith("effects.")})},
            "parameters": params, "units": "SI", "from_stores": {r: str(s.path) for r, s in setup.stores.items()}}


def _v(c: dict, name: str, default: float = 0.0) -> float:
    p = c["parameters"].get(name)
    return float(p["value"]) if p else default


def liggghts(c: dict) -> str:
    mu, mur, e = _v(c, "friction"), _v(c, "rolling_friction"), _v(c, "restitution")
    muw = _v(c, "wall_friction", mu)
    ew, murw = _v(c, "wall_restitution", e), _v(c, "wall_rolling_friction", mur)
    kc = _v(c, "effects.cohesion_sjkr.cohesion_energy_density")
    E, nu = _v(c, "youngs_modulus"), _v(c, "poisson_ratio")

    def pair(pp, pw):  # 2 x 2, row-major: particle-particle, particle-wall, wall-particle, wall-wall
        return f"2 {pp:.6g} {pw:.6g} {pw:.6g} {pw:.6g}"
    lines = [f"# {c['material']}: calibrated by pydem (material_card.json has the intervals). Type 1: particles, 2: walls.",
             *_caveat_lines(c),
             f"# solid density {_v(c, 'density'):.6g} kg/m^3: set it on the particles (e.g. create_atoms / fix insert)",
             f"fix m1 all property/global youngsModulus peratomtype {E:.6g} {E:.6g}",
             f"fix m2 all property/global poissonsRatio peratomtype {nu:.6g} {nu:.6g}",
             f"fix m3 all property/global coefficientRestitution peratomtypepair {pair(e, ew)}",
             f"fix m4 all property/global coefficientFriction peratomtypepair {pair(mu, muw)}",
             f"fix m5 all property/global coefficientRollingFriction peratomtypepair {pair(mur, murw)}"]
    style = "pair_style gran model hertz tangential history rolling_friction epsd2"
    if kc > 0:
        lines.append(f"fix m6 all property/global cohesionEnergyDensity peratomtypepair {pair(kc, kc)}")
        style += " cohesion sjkr"
    tw = _v(c, "effects.twisting_resistance.twisting_friction")
    if tw > 0:
        lines.append(f"# twisting resistance mu_t = {tw:.6g} (libdem's twisting_resistance): LIGGGHTS' nearest is the "
                     "epsd2 option torsionTorque on, which uses the rolling coefficient")
    return "\n".join(lines + [style, "pair_coeff * *", ""])


def lammps(c: dict) -> str:
    mu, mur, e = _v(c, "friction"), _v(c, "rolling_friction"), _v(c, "restitution")
    muw = _v(c, "wall_friction", mu)
    ew, murw = _v(c, "wall_restitution", e), _v(c, "wall_rolling_friction", mur)
    E, nu = _v(c, "youngs_modulus"), _v(c, "poisson_ratio")
    kc = _v(c, "effects.cohesion_sjkr.cohesion_energy_density")
    lines = [f"# {c['material']}: calibrated by pydem (material_card.json has the intervals). Type 1: particles, 2: walls.",
             *_caveat_lines(c),
             "# Nearest LAMMPS models: hertz/material with coeff_restitution damping and mindlin tangential are",
             "# libdem's; rolling sds is a spring-dashpot-slider with a constant stiffness k_roll, where libdem's EPSD2",
             "# uses k_t R*^2: k_roll below is that value for the given diameter (set it) and mean overlap 1e-3 d.",
             "variable d equal 3e-3",
             f"variable kroll equal {8 * E / (4 * (2 - nu) * (1 + nu)):.6g}*sqrt(0.5*v_d/2*1e-3*v_d)*(v_d/4)^2",
             "pair_style granular"]
    tw = _v(c, "effects.twisting_resistance.twisting_friction")
    twist = " twisting marshall" if tw > 0 else ""  # libdem's twisting_resistance ~ marshall (mu from tangential)
    for (a, b), (ee, mm, rr) in (((1, 1), (e, mu, mur)), ((1, 2), (ew, muw, murw)), ((2, 2), (ew, muw, murw))):
        lines.append(f"pair_coeff {a} {b} hertz/material {E:.6g} {ee:.6g} {nu:.6g} damping coeff_restitution "
                     f"tangential mindlin NULL 1.0 {mm:.6g} rolling sds ${{kroll}} 0.0 {rr:.6g}{twist}")
    if kc > 0:
        lines.append(f"# cohesion: libdem's SJKR energy density {kc:.6g} J/m^3 has no LAMMPS granular model; "
                     "the nearest is the jkr normal model with a surface energy fitted to the same pull-off force")
    return "\n".join(lines + [""])


def _caveat_lines(c: dict) -> list[str]:
    return [f"# CAVEAT: {x}" for x in c.get("caveats", [])]


def write(c: dict, out: str | Path) -> list[Path]:
    out = Path(out)
    files = [out / "material_card.json", out / "material_card.liggghts", out / "material_card.lammps"]
    files[0].write_text(json.dumps(strict_json(c), indent=1))
    files[1].write_text(liggghts(c))
    files[2].write_text(lammps(c))
    return files
