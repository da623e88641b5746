"""What produced a result: pydem and libdem versions, the git commit (with "+changes" when the
checkout differs from it), the machine, the command line and the time. Recorded in campaign
stores, rig result files and diagnosis reports."""
from __future__ import annotations

import os
import platform
import subprocess
import sys
import time
from pathlib import Path


def provenance() -> dict:
    from . import LIBDEM_VERSION, __version__
    root = Path(__file__).resolve().parents[1]
    commit = "unknown"
    try:
        commit = subprocess.run(["git", "-C", str(root), "rev-parse", "HEAD"], capture_output=True, text=True,
                                timeout=10).stdout.strip() or "unknown"
        dirty = subprocess.run(["git", "-C", str(root), "status", "--porcelain", "--untracked-files=no"],
                               capture_output=True, text=True, timeout=10).stdout.strip()
        commit += "+changes" if dirty else ""
    except (OSError, subprocess.SubprocessError):
        pass
    return {"pydem": __version__, "libdem": LIBDEM_VERSION, "git_commit": commit, "host": platform.node(),
            "machine": f"{platform.machine()}, {os.cpu_count()} cores", "python": platform.python_version(),
            "command": " ".join(sys.argv), "created": time.strftime("%Y-%m-%d %H:%M:%S %z")}
