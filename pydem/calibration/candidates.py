"""The candidate effects of the diagnosis: what the base model assumes, and the parameter that
relaxes the assumption.

Each candidate has one parameter (a campaign key), a unit, a neutral value (the base model's
assumption) and a side: "+" when only values above neutral are physical (cohesion cannot be
negative), "+-" when both are. The neutral value may depend on the base parameters: the base
model gives walls the particles' friction (one friction coefficient for every contact), so the
candidate `wall_friction` is "the wall's friction differs from the particles'".

Every libdem effect is a candidate automatically (pydem.effects(): its parameters with their
neutral values); the Python-side ones are the rig knobs below. A candidate takes part once a
campaign store varies its parameter."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

from ..domain import effects

BASE_PARAMETERS = ("friction", "rolling_friction", "restitution")


@dataclass(frozen=True)
class Candidate:
    name: str
    parameter: str               # the campaign key it varies
    unit: str
    neutral: Callable[[dict], float]  # base parameters -> the neutral value
    side: str                    # "+" or "+-"
    assumption: str              # what the base model assumes, in words

    def neutral_value(self, theta: dict) -> float:
        return float(self.neutral(theta))


def _const(v):
    return lambda theta: v


def registry() -> list[Candidate]:
    """Every candidate: the rig-level ones and every parameter of every libdem effect."""
    out = [
        Candidate("wall_friction", "wall_friction", "", lambda th: th["friction"], "+-",
                  "walls have the particles' sliding friction (one friction coefficient)"),
        Candidate("size_spread", "size_spread", "", _const(0.1), "+-",
                  "diameters uniform in d (1 +- 0.1), the rigs' default"),
    ]
    for eff in effects():
        for p in eff["params"]:
            side = "+" if p["neutral"] == 0.0 else "+-"
            out.append(Candidate(eff["name"], f"effects.{eff['name']}.{p['name']}", p["unit"], _const(p["neutral"]), side,
                                 f"no {eff['name']} ({p['name']} = {p['neutral']:g}): {eff['summary']}"))
    return out
