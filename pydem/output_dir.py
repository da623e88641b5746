"""Where a command's output goes, checked before any work: a rig's result file and frame folders
(check_writable), and the output directory of `pydem diagnose` and `calibrate`, written whole or
not at all.

check() runs before any work: the directory must be new, empty, or an earlier output of pydem (it
holds one of MARKERS), and its parent writable — a mistyped --out is found in a second, not after
the computation, and a directory of the user's own files is never replaced. staged() gives a
fresh directory beside it to write into; only when everything is written is it moved into place
(the earlier output set aside first and removed last), so a failure — a full disk, an error
while rendering — leaves the earlier output as it was, or nothing."""
from __future__ import annotations

import os
import shutil
import tempfile
from contextlib import contextmanager
from pathlib import Path
from typing import Iterator

MARKERS = ("diagnosis.json", "calibration.json")


class OutputError(OSError):
    pass


def check(out: str | Path) -> Path:
    """Raises OutputError naming the path when the output cannot go there; creates missing parents."""
    out = Path(out).absolute()
    if out.exists() and not out.is_dir():
        raise OutputError(f"--out {out}: a file is in the way (the output is a directory)")
    if out.is_dir() and any(out.iterdir()) and not any((out / m).exists() for m in MARKERS):
        raise OutputError(f"--out {out}: a directory with other files in it, not an earlier pydem output; choose a "
                          f"new or empty directory")
    try:
        out.parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise OutputError(f"--out {out}: cannot create its parent ({exc.strerror})") from None
    if not os.access(out.parent, os.W_OK | os.X_OK) or (out.is_dir() and not os.access(out, os.W_OK | os.X_OK)):
        raise OutputError(f"--out {out}: permission denied")
    return out


@contextmanager
def staged(out: str | Path) -> Iterator[Path]:
    """Yields an empty directory beside `out`; on leaving without an error it becomes `out`."""
    out = check(out)
    tmp = Path(tempfile.mkdtemp(prefix=f".{out.name}.partial-", dir=out.parent))
    try:
        umask = os.umask(0)
        os.umask(umask)
        tmp.chmod(0o777 & ~umask)  # mkdtemp's 0700 would hide the report from the user's group
        yield tmp
        old = None
        if out.exists():
            old = out.parent / f".{out.name}.old-{os.getpid()}"
            out.rename(old)
        try:
            tmp.rename(out)
        except OSError:
            if old is not None:
                old.rename(out)
            raise
        if old is not None:
            shutil.rmtree(old, ignore_errors=True)
    finally:
        if tmp.exists():
            shutil.rmtree(tmp, ignore_errors=True)


def check_writable(path: str, directory: bool):
    """Raises OSError naming the path when it cannot be written (a directory is created)."""
    p = Path(path)
    d = p if directory else (p.parent if str(p.parent) else Path("."))
    if directory:
        p.mkdir(parents=True, exist_ok=True)
    if not d.is_dir():
        raise OSError(f"{d}: no such directory")
    if not os.access(d, os.W_OK) or (p.exists() and not directory and not os.access(p, os.W_OK)):
        raise OSError(f"{path}: permission denied")
