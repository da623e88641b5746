"""Where a rig run's time goes: each rig's `default` run (and seed 001's largest hopper case,
A-4) under `perf record -e cpu-clock` (a timer sample every 4 ms of CPU, so it works on VMs
without hardware counters), every sample's function mapped to a phase through the object file
that defines it (`nm build/obj/*.o`) or its library (Python, numpy, libc):

    pair sweep       sweep.c, pair_batch.c, plane_contact.c, step.c (forces, kicks, drift, plane walls)
    mesh contacts    mesh_contact.c, triangle.h (closest points, contact selection, the batched wall law)
    mesh candidates  mesh_bins.c (triangles binned into cells, per-particle candidates)
    list builds      neighbor.c, cell_grid.c, balance.c (cells, sort, Verlet list, histories)
    mesh motion      mesh_motion.c, mesh_forces.c, wall_mean_force.c (moving walls, servo, wall forces)
    python           the interpreter, numpy, cffi: the rigs' protocol logic between engine calls
    other            the rest (libc, libgomp's waiting, stress, rendering, snapshots)

    .venv/bin/python bench/rig_profile.py [--rigs ring-shear aor hopper hopper-A-4] [--threads 1]
        -> bench/results/rig_profile.{json,md}

The parameters are the campaign box's centre (friction 0.5, rolling friction 0.3, restitution
0.55), one seed; the engine's own profile (neighbour builds, sweep) is printed beside it.
Needs `perf` (apt-get install linux-perf)."""
from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from collections import defaultdict
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PHASES = {
    "pair sweep": ("sweep", "pair_batch", "plane_contact", "step"),
    "mesh contacts": ("mesh_contact",),
    "mesh candidates": ("mesh_bins",),
    "list builds": ("neighbor", "cell_grid", "balance"),
    "mesh motion": ("mesh_motion", "mesh_forces", "wall_mean_force"),
}
ORDER = list(PHASES) + ["python", "other"]
RUN = """
import json, sys, time
from pydem.rigs import RIGS
rig, preset, case, threads = sys.argv[1], sys.argv[2], sys.argv[3], int(sys.argv[4])
cls, cfg_cls = RIGS[rig]
cfg = cfg_cls.preset(preset)
if case:
    from pydem.rigs.hopper import apply_case
    apply_case(cfg, case)
cfg.num_threads = threads
t0 = time.perf_counter()
res = cls(cfg).run({"friction": 0.5, "rolling_friction": 0.3, "restitution": 0.55}, seed=1)
print(json.dumps({"wall_s": time.perf_counter() - t0, "engine": res.info.get("engine_profile"),
                  "steps": res.info.get("steps")}, default=str))
"""


def symbol_files() -> dict[str, str]:
    """{function symbol: its source file's stem} from the library's object files."""
    out = {}
    for obj in sorted((ROOT / "build/obj").glob("*.o")):
        text = subprocess.run(["nm", str(obj)], capture_output=True, text=True, check=True).stdout
        for line in text.splitlines():
            parts = line.split()
            if len(parts) == 3 and parts[1] in "tTW":
                out[parts[2].split(".")[0]] = obj.stem
    return out


def phase_of(sym: str, dso: str, files: dict[str, str]) -> str:
    base = sym.split(".")[0]
    if base in files:
        stem = files[base]
        for phase, stems in PHASES.items():
            if stem in stems:
                return phase
        if stem == "triangle":
            return "mesh contacts"
        return "other"
    if dso.startswith(("python", "libpython")) or "numpy" in dso or "_cffi" in dso or "libffi" in dso \
            or base.startswith(("_Py", "Py")):
        return "python"
    return "other"


def profile(rig: str, preset: str, case: str, threads: int, files: dict[str, str]) -> dict:
    with tempfile.TemporaryDirectory() as tmp:
        data = Path(tmp) / "perf.data"
        env = dict(os.environ, PYTHONPATH=str(ROOT), OMP_NUM_THREADS=str(threads))
        t0 = time.perf_counter()
        run = subprocess.run(["perf", "record", "-q", "-e", "cpu-clock", "-F", "250", "-o", str(data), "--",
                              sys.executable, "-c", RUN, rig, preset, case, str(threads)],
                             capture_output=True, text=True, env=env)
        if run.returncode != 0:
            raise SystemExit(f"{rig}: {run.stderr[-2000:]}")
        info = json.loads(run.stdout.strip().splitlines()[-1])
        rep = subprocess.run(["perf", "report", "-i", str(data), "--no-children", "--sort", "dso,symbol",
                              "--stdio", "-q", "--percent-limit", "0"], capture_output=True, text=True, check=True)
    shares = defaultdict(float)
    for line in rep.stdout.splitlines():
        parts = line.split()
        if len(parts) < 4 or not parts[0].endswith("%"):
            continue
        pct, dso = float(parts[0][:-1]), parts[1]
        sym = parts[parts.index("[.]") + 1] if "[.]" in parts else parts[-1]
        shares[phase_of(sym, dso, files)] += pct
    info["shares"] = {p: round(shares.get(p, 0.0), 1) for p in ORDER}
    info["profile_wall_s"] = time.perf_counter() - t0
    return info


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--rigs", nargs="+", default=["ring-shear", "aor", "hopper", "hopper-A-4"])
    ap.add_argument("--threads", type=int, default=1)
    args = ap.parse_args()
    if not shutil.which("perf"):
        print("rig_profile: needs perf (apt-get install linux-perf)", file=sys.stderr)
        return 2
    files = symbol_files()
    rows = {}
    for name in args.rigs:
        rig, case = (name.split("-A-")[0], "A-" + name.split("-A-")[1]) if "-A-" in name else (name, "")
        rows[name] = profile(rig, "default", case, args.threads, files)
        r = rows[name]
        print(f"{name:12s} {r['wall_s']:7.1f} s  " + "  ".join(f"{p} {r['shares'][p]:4.1f} %" for p in ORDER),
              flush=True)
    out = ROOT / "bench/results/rig_profile.json"
    out.write_text(json.dumps({"threads": args.threads, "machine": os.uname().nodename, "rigs": rows}, indent=1))
    lines = ["| run | wall (s) | " + " | ".join(ORDER) + " |", "|---|---|" + "---|" * len(ORDER)]
    for name, r in rows.items():
        lines.append(f"| {name} default | {r['wall_s']:.0f} | " + " | ".join(f"{r['shares'][p]:.1f} %" for p in ORDER) + " |")
    out.with_suffix(".md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    sys.exit(main())
