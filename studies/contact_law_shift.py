"""How much the libdem 0.2 Coulomb-cap rule moved the rigs' metrics (CHANGELOG 2026-11-24):
each rig's tiny preset at several seeds, and points of the shipped aor_default campaign at the
default preset, with the pydem of a given checkout (old: a worktree of the last 0.1 commit).

    .venv/bin/python studies/contact_law_shift.py --root /tmp/old --label libdem-0.1
    .venv/bin/python studies/contact_law_shift.py --root . --label libdem-0.2
    .venv/bin/python studies/contact_law_shift.py --compare libdem-0.1 libdem-0.2

Rows go to studies/results/contact_law_shift.jsonl (appended; a finished row is not run again)."""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parents[1]
OUT = HERE / "studies/results/contact_law_shift.jsonl"
SEEDS = (1, 2, 3, 4)
TINY = {"aor": {}, "ring-shear": {}, "hopper": {}}
DEFAULT_POINTS = (0, 1, 2)  # design points of data/campaigns/aor_default.h5


def done() -> set:
    if not OUT.exists():
        return set()
    return {(r["label"], r["case"], r["seed"]) for r in map(json.loads, OUT.read_text().splitlines())}


def run(root: Path, label: str):
    sys.path.insert(0, str(root))
    import pydem
    from pydem.campaign import Campaign
    from pydem.rigs import RIGS, load
    assert Path(pydem.__file__).resolve().is_relative_to(root.resolve()), pydem.__file__
    have = done()
    jobs = [(f"{rig} tiny", rig, "tiny", {}, s) for rig in TINY for s in SEEDS]
    store = Campaign.open(HERE / "data/campaigns/aor_default.h5").store
    for p in DEFAULT_POINTS:  # three seeds per point: one run differs from another by chaos alone
        values = dict(zip(store.spec.names, map(float, store.params[p])))
        jobs += [(f"aor default point {p}", "aor", "default", values, int(store.seeds[p]) + k) for k in range(3)]
    for case, rig, preset, params, seed in jobs:
        if (label, case, seed) in have:
            continue
        cfg = load(RIGS[rig][1], preset, None, [f"{k}={v!r}" for k, v in params.items()])
        cfg.num_threads = 1
        res = RIGS[rig][0](cfg).run(seed=seed)
        row = {"label": label, "libdem": pydem.LIBDEM_VERSION, "case": case, "seed": seed, "params": params,
               "metrics": {k: m.value for k, m in res.metrics.items() if isinstance(m.value, float)}}
        with open(OUT, "a") as fh:
            fh.write(json.dumps(row) + "\n")
        print(case, seed, {k: round(v, 4) for k, v in row["metrics"].items()}, flush=True)


def compare(a: str, b: str):
    import numpy as np
    rows = [json.loads(x) for x in OUT.read_text().splitlines()]
    cases = sorted({r["case"] for r in rows})
    print(f"| case | metric | {a} mean | {b} mean | shift | seed sd | shift / sd |")
    print("|---|---|---|---|---|---|---|")
    for case in cases:
        ra = {r["seed"]: r["metrics"] for r in rows if r["case"] == case and r["label"] == a}
        rb = {r["seed"]: r["metrics"] for r in rows if r["case"] == case and r["label"] == b}
        seeds = sorted(set(ra) & set(rb))
        if not seeds:
            continue
        for m in ra[seeds[0]]:
            if m not in rb[seeds[0]] or m in ("inertial_number",):
                continue
            va = np.array([ra[s][m] for s in seeds])
            vb = np.array([rb[s][m] for s in seeds])
            sd = float(np.std(np.concatenate([va - va.mean(), vb - vb.mean()]), ddof=2)) if len(seeds) > 1 else float("nan")
            shift = float(vb.mean() - va.mean())
            print(f"| {case} ({len(seeds)} seeds) | {m} | {va.mean():.4g} | {vb.mean():.4g} | {shift:+.3g} | "
                  f"{sd:.3g} | {shift / sd if sd > 0 else float('nan'):+.2f} |")


if __name__ == "__main__":
    ap = argparse.ArgumentParser()
    ap.add_argument("--root", type=Path)
    ap.add_argument("--label")
    ap.add_argument("--compare", nargs=2)
    a = ap.parse_args()
    if a.compare:
        compare(*a.compare)
    else:
        run(a.root, a.label)
