"""The binding under valgrind: domains with particles, walls, snapshots, renders and errors
created and dropped from Python must leave no definitely-lost block and no invalid access
in libdem or the binding (Python's own allocations are not judged). valgrind is installed
by scripts/setup.sh; its absence is a failure, not a skip."""
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]

SCRIPT = r"""
import numpy as np, pydem, tempfile, os
tmp = tempfile.mkdtemp()
for k in range(40):
    d = pydem.Domain(hi=(0.01, 0.01, 0.01))
    m = d.add_material()
    d.set_pair(m, m, rolling_friction=0.1)
    d.set_effect(m, m, "cohesion_sjkr", 1e3)
    d.add_plane_wall(material=m)
    w = d.add_mesh_wall(os.path.join(%(root)r, "data/geometry/open_box_40mm.stl"), material=m, scale=2e-4)
    d.add_particles([[0.003, 0.003, 0.002], [0.0055, 0.003, 0.002]], 1e-3, m)
    d.step(20)
    w.set_servo(target_force=1e-3)
    d.step(5)
    d.region_stress("box", lo=(0, 0, 0), hi=(0.01, 0.01, 0.01))
    d.write_snapshot(os.path.join(tmp, "s.h5"))
    e = pydem.Domain.from_snapshot(os.path.join(tmp, "s.h5"))
    e.step(3)
    img = d.render(width=40, height=20)
    try:
        d.add_particles([[0.003, 0.003, 0.002]], 1e-3, m)
    except pydem.DemOverlapError:
        pass
    try:
        d.add_mesh_wall(os.path.join(%(root)r, "tests/data/stl_corpus/truncated_binary.stl"))
    except pydem.DemFormatError:
        pass
    del d, e, w
print("done")
"""


@pytest.mark.slow
def test_no_leaks_or_invalid_access_under_valgrind(tmp_path):
    valgrind = shutil.which("valgrind")
    assert valgrind, "valgrind is missing: run scripts/setup.sh"
    script = tmp_path / "churn.py"
    script.write_text(SCRIPT % {"root": str(ROOT)})
    env = {"PYTHONMALLOC": "malloc", "PYTHONPATH": str(ROOT), "PATH": "/usr/bin:/bin", "OMP_NUM_THREADS": "1"}
    r = subprocess.run([valgrind, "--leak-check=full", "--show-leak-kinds=definite", "--num-callers=30",
                        sys.executable, str(script)], capture_output=True, text=True, env=env, timeout=900)
    assert r.returncode == 0 and "done" in r.stdout, r.stderr[-3000:]
    # split the report into records; judge those whose stack passes through a libdem function
    # or its cffi wrapper (the one-time module object cffi makes at import is not ours)
    records = re.split(r"\n==\d+== \n", r.stderr)
    ours = lambda rec: re.search(r"\bdem_\w+|_cffi_f_dem_\w+", rec)  # noqa: E731
    lost = [rec for rec in records if "definitely lost" in rec and ours(rec)]
    invalid = [rec for rec in records if re.search(r"Invalid (read|write|free)|uninitialised", rec) and ours(rec)]
    assert not lost, lost[0][:3000]
    assert not invalid, invalid[0][-3000:]
