"""One results file for the diagnosis benches: studies/results/<name>.json with when, where, the
command and how long it took, beside the table and every set."""
from __future__ import annotations

import json
import os
import platform
import sys
import time
from pathlib import Path
from typing import Callable

RESULTS = Path(__file__).resolve().parent / "results"


def write(name: str, table: dict, sets: list, started: float) -> Path:
    """Writes the file (started: time.perf_counter() at the start) and returns its path."""
    meta = {"date": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()),
            "machine": f"{platform.machine()}, {len(os.sched_getaffinity(0))} cores",
            "seconds": time.perf_counter() - started, "command": " ".join(sys.argv)}
    out = RESULTS / f"{name}.json"
    out.write_text(json.dumps({"meta": meta, "table": table, "sets": sets}, indent=1, default=float))
    return out


def report(name: str, table: dict, sets: list, started: float, heading: str, line: Callable[[str, dict], str]) -> int:
    """write(), then the table on the terminal: the heading, line(effect, row) per effect, the path.
    Returns 0 (a bench's exit status)."""
    out = write(name, table, sets, started)
    print(heading)
    for effect, row in table.items():
        print(f"  {effect:14s} {line(effect, row)}")
    print(f"-> {out}")
    return 0
