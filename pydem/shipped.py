"""Where the shipped data lives — the campaign stores with their cached nets and the example
measurement files — so the commands work from any directory and from an installed wheel:
$PYDEM_DATA when it is set, else the copy a wheel carries inside the package (pydem/data), else
the source checkout's data/ beside the package (an editable install). Paths are asked for as the
repository names them: "data/campaigns/diag_aor_default.h5"."""
from __future__ import annotations

import os
from pathlib import Path

PACKAGE = Path(__file__).resolve().parent


def data_dirs() -> list[Path]:
    """The places searched, in order."""
    env = os.environ.get("PYDEM_DATA")
    return ([Path(env)] if env else []) + [PACKAGE / "data", PACKAGE.parent / "data"]


def shipped_path(name: str | os.PathLike) -> Path:
    """The shipped file `name` ("data/..." or relative to data/); FileNotFoundError naming every
    place searched when none has it."""
    rel = Path(name)
    if rel.parts and rel.parts[0] == "data":
        rel = Path(*rel.parts[1:])
    for d in data_dirs():
        if (d / rel).exists():
            return d / rel
    places = ", ".join(str(d) for d in data_dirs())
    raise FileNotFoundError(f"{rel}: not among the shipped data (searched {places}; set PYDEM_DATA to the folder "
                            f"that holds campaigns/ and measurements/)")
