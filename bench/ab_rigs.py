"""A/B of two checkouts on one rig run: the old and the new pydem run the same rig, preset,
parameters and seed side by side (one process each, one thread each), so both see the same
machine at the same moment (this VM's speed drifts by up to 2x over minutes; a paired ratio
does not); each round checks that the metrics are bitwise equal, or reports which differ.

    .venv/bin/python bench/ab_rigs.py OLD_CHECKOUT NEW_CHECKOUT --rig ring-shear --preset default \\
        --set friction=0.5 --set effects.cohesion_sjkr.cohesion_energy_density=5e4 --rounds 2 \\
        [--out bench/results/ab_rigs_NAME.txt]

A checkout is a directory holding a built pydem (`git worktree add DIR COMMIT`, then
`make pydem` there). Prints, per round, each side's wall and CPU time and the ratio old/new of
the CPU times (the speed-up), then the geometric mean over the rounds. Run it on a quiet machine:
other processes on the two cores disturb both sides, but not equally."""
from __future__ import annotations

import argparse
import json
import math
import os
import platform
import subprocess
import sys
import time
from pathlib import Path

RUN = """
import json, os, resource, sys, time
import pydem
if not pydem.__file__.startswith(os.getcwd() + os.sep):
    raise SystemExit(f"pydem imported from {pydem.__file__}, not from {os.getcwd()}")
from pydem.rigs import RIGS
from pydem.rigs.config import set_value
rig, preset, seed, threads = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4])
cls, cfg_cls = RIGS[rig]
cfg = cfg_cls.preset(preset)
for item in sys.argv[5:]:
    key, value = item.split("=", 1)
    set_value(cfg, key, value)
cfg.num_threads = threads
t0, c0 = time.perf_counter(), resource.getrusage(resource.RUSAGE_SELF).ru_utime
res = cls(cfg).run(seed=seed)
metrics = {k: getattr(m, "value", m) for k, m in res.metrics.items()}
print(json.dumps({"wall": time.perf_counter() - t0, "cpu": resource.getrusage(resource.RUSAGE_SELF).ru_utime - c0,
                  "steps": res.info.get("steps"), "metrics": {k: repr(v) for k, v in metrics.items()}}))
"""


def commit_of(checkout: Path) -> str:
    """The checkout's commit, with '+' when its tracked files differ from it."""
    try:
        head = subprocess.run(["git", "-C", str(checkout), "rev-parse", "--short", "HEAD"], capture_output=True,
                              text=True, check=True).stdout.strip()
        dirty = subprocess.run(["git", "-C", str(checkout), "diff", "--quiet", "HEAD", "--", "libdem", "pydem", "include"]).returncode
        return head + ("+" if dirty else "")
    except (OSError, subprocess.CalledProcessError):
        return "no git"


def header(what: str, old: Path, new: Path) -> str:
    """The first line of a results file: when, which machine, what ran, which two checkouts."""
    return (f"# {time.strftime('%Y-%m-%d %H:%M')} {platform.machine()}, {len(os.sched_getaffinity(0))} cores: "
            f"{what}; old {old} ({commit_of(old)}), new {new} ({commit_of(new)})")


def save(lines: list[str], out: Path | None):
    """Append the lines to `out` (results accumulate across invocations)."""
    if out:
        with open(out, "a") as fh:
            fh.write("\n".join(lines) + "\n")


def start(checkout: Path, args) -> subprocess.Popen:
    # `python -c` puts the working directory first on sys.path: run in the checkout, so that its
    # pydem is the one imported (an editable install or PYTHONPATH alone would not decide it)
    env = dict(os.environ, PYTHONPATH=str(checkout), OMP_NUM_THREADS="1")
    cmd = [sys.executable, "-c", RUN, args.rig, args.preset, str(args.seed), "1", *args.set]
    return subprocess.Popen(cmd, env=env, cwd=checkout, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def finish(p: subprocess.Popen, name: str) -> dict:
    out, err = p.communicate()
    if p.returncode != 0:
        raise SystemExit(f"{name} failed:\n{err[-2000:]}")
    return json.loads(out.strip().splitlines()[-1])


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("old", type=Path)
    ap.add_argument("new", type=Path)
    ap.add_argument("--rig", required=True)
    ap.add_argument("--preset", default="default")
    ap.add_argument("--set", action="append", default=[], help="KEY=VALUE, as `pydem rig --set`")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--out", type=Path, help="append the lines to this file as well")
    args = ap.parse_args()
    args.old, args.new = args.old.resolve(), args.new.resolve()
    for c in (args.old, args.new):
        if not (c / "pydem").is_dir():
            raise SystemExit(f"{c}: no pydem checkout there")
    lines = [header(f"{args.rig} {args.preset} seed {args.seed} {' '.join(args.set)}", args.old, args.new)]
    print(lines[0], flush=True)
    ratios = []
    for r in range(args.rounds):
        # both at once, the one started first alternating
        first, second = (args.old, args.new) if r % 2 == 0 else (args.new, args.old)
        procs = {first: start(first, args), second: start(second, args)}
        old, new = finish(procs[args.old], "old"), finish(procs[args.new], "new")
        same = old["metrics"] == new["metrics"]
        differ = [k for k in old["metrics"] if old["metrics"][k] != new["metrics"].get(k)]
        ratio = old["cpu"] / new["cpu"]
        ratios.append(ratio)
        line = (f"round {r + 1}: old {old['wall']:.1f} s wall {old['cpu']:.1f} s CPU, new {new['wall']:.1f} s wall "
                f"{new['cpu']:.1f} s CPU, steps {old['steps']}/{new['steps']}, speed-up {ratio:.3f}, metrics "
                + ("bitwise equal" if same else f"DIFFER: {', '.join(differ)}"))
        print(line, flush=True)
        lines.append(line)
    lines.append(f"geometric-mean speed-up (old CPU / new CPU) {math.exp(sum(map(math.log, ratios)) / len(ratios)):.3f} "
                 f"over {len(ratios)} rounds")
    print(lines[-1])
    save(lines, args.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
