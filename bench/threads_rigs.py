"""Rig runs on 1 and 2 threads, on a quiet machine and beside a busy process, old checkout
against new: the thread governor and the wait policy (issue: rigs at engine speed; a contended
run must degrade to about the 1-thread speed, not 3-9x below it).

    .venv/bin/python bench/threads_rigs.py OLD_CHECKOUT NEW_CHECKOUT --rig hopper [--preset default] \\
        [--rounds 2] [--out bench/results/threads_rigs_hopper.txt]

Each round runs every (checkout, threads, machine) once, one run at a time, the order
alternating between rounds; "busy" runs beside `sh -c 'while :; do :; done'`, which takes one
of the two cores for the run's whole length. A run is the rig at the campaign box's centre
(friction 0.5, rolling friction 0.3, restitution 0.55), seed 1; each checkout's own default
OpenMP settings (pydem's import sets them), as a user gets them. Prints each run's wall time
and whether its metrics equal the first run's bitwise (they must: results do not depend on the
thread count or the checkout here); then the medians per configuration."""
from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from ab_rigs import RUN, header, save  # noqa: E402

CENTRE = ["friction=0.5", "rolling_friction=0.3", "restitution=0.55"]


def one_run(checkout: Path, rig: str, preset: str, threads: int, busy: bool) -> dict:
    env = {k: v for k, v in os.environ.items() if k not in ("OMP_WAIT_POLICY", "GOMP_SPINCOUNT", "OMP_NUM_THREADS")}
    env["PYTHONPATH"] = str(checkout)
    hog = subprocess.Popen(["sh", "-c", "while :; do :; done"]) if busy else None
    try:
        p = subprocess.run([sys.executable, "-c", RUN, rig, preset, "1", str(threads), *CENTRE], env=env, cwd=checkout,
                           capture_output=True, text=True)
    finally:
        if hog:
            hog.kill()
            hog.wait()
    if p.returncode != 0:
        raise SystemExit(f"{checkout} failed:\n{p.stderr[-2000:]}")
    return json.loads(p.stdout.strip().splitlines()[-1])


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("old", type=Path)
    ap.add_argument("new", type=Path)
    ap.add_argument("--rig", required=True)
    ap.add_argument("--preset", default="default")
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--out", type=Path)
    args = ap.parse_args()
    sides = {"old": args.old.resolve(), "new": args.new.resolve()}
    lines = [header(f"{args.rig} {args.preset}", sides["old"], sides["new"])]
    print(lines[0], flush=True)
    configs = [(side, threads, busy) for busy in (False, True) for threads in (1, 2) for side in ("old", "new")]
    walls: dict[tuple, list[float]] = {c: [] for c in configs}
    reference = None
    for r in range(args.rounds):
        for side, threads, busy in (configs if r % 2 == 0 else configs[::-1]):
            res = one_run(sides[side], args.rig, args.preset, threads, busy)
            reference = reference or res["metrics"]
            same = res["metrics"] == reference
            walls[(side, threads, busy)].append(res["wall"])
            lines.append(f"round {r + 1}: {side} {threads} thread(s) {'busy' if busy else 'quiet'}: {res['wall']:.2f} s, "
                         f"metrics {'bitwise equal' if same else 'DIFFER'}")
            print(lines[-1], flush=True)
    lines.append("| machine | threads | old (s) | new (s) | old / new |")
    lines.append("|---|---|---|---|---|")
    for busy in (False, True):
        for threads in (1, 2):
            o, n = statistics.median(walls[("old", threads, busy)]), statistics.median(walls[("new", threads, busy)])
            lines.append(f"| {'busy' if busy else 'quiet'} | {threads} | {o:.2f} | {n:.2f} | {o / n:.2f} |")
    print("\n".join(lines[-6:]))
    save(lines, args.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
