"""More hoppers per packing, drawn like Table 1's, as a data set of their own: seed 001's networks
and image gauges pretrain and calibrate on them and never test on them (the 25 Table 1 cases stay
the test set). The measured reason (docs/seed001.md): within one discharge the frames fix the
count, and what fails is carrying the image-to-count law to a new hopper from three others.

Each hopper is a Table 1-style row drawn by pydem.rigs.table1.draw_like_table1 (named
<packing>-x01, -x02 ...; the same draws for a given seed whatever the count asked), run at full
size with a frame every `frame_interval` s in its own worker process (campaign.workers.run_local:
a killed worker costs its own run only), and written whole into one frame store per packing as it
ends. A rerun does the hoppers the store lacks; a hopper that failed is kept in the store with its
reason (FrameStore.failures) and reported, and run again only when asked."""
from __future__ import annotations

import json
import time

import numpy as np

from .store import FrameStore

PACKINGS = ("A", "B1", "B2", "B3", "B4")


def run_one(name: str, row: list, packing: str, frame_interval: float) -> dict:
    """One hopper's frames (a worker process): {"frames", "time", "discharge_time", "nrrp", "wall"}
    or {"error": reason}."""
    from ..rigs import RIGS, load
    from ..rigs.hopper import apply_row
    from ..rigs.table1 import row_from_json
    cls, cfg_cls = RIGS["hopper"]
    cfg = load(cfg_cls, "default", None, [f"frame_interval={frame_interval}", "num_threads=1"])
    apply_row(cfg, row_from_json(row), packing)
    t0 = time.perf_counter()
    try:
        res = cls(cfg).run(seed=0, images=True)
    except Exception as exc:  # a runaway overlap, a jam: kept with its reason
        return {"error": f"the run failed ({exc})", "wall": time.perf_counter() - t0}
    t_dis = res.metrics["discharge_time"].value
    if not np.isfinite(t_dis):
        return {"error": f"did not empty ({res.metrics['discharge_time'].note})", "wall": time.perf_counter() - t0}
    return {"frames": np.asarray(res.images, np.uint8), "time": res.series["frame_time"], "discharge_time": t_dis,
            "nrrp": res.series["frame_nrrp"], "particles": res.info["particles"], "wall": time.perf_counter() - t0}


def drawn(packing: str, hoppers: int, seed: int, volume_scale: float = 1.0) -> dict[str, list]:
    """{name: row} of the hoppers asked, rows as JSON-ready lists."""
    from ..rigs.table1 import draw_like_table1, row_as_json
    return {k: row_as_json(v) for k, v in draw_like_table1(packing, hoppers, seed, volume_scale).items()}


def run_hoppers(store_path, packing: str, hoppers: int, seed: int = 1, frame_interval: float = 0.001,
                workers: int = 2, volume_scale: float = 1.0, retry_failed: bool = False, say=print) -> dict:
    """Runs the hoppers the store lacks; returns {"stored": [...], "failed": {name: reason}}.
    A store drawn with another seed, volume scale or frame interval is refused (its names would
    mean other hoppers)."""
    if packing not in PACKINGS:
        raise ValueError(f"packing: one of {', '.join(PACKINGS)}, got {packing!r}")
    if hoppers < 1 or not np.isfinite(frame_interval) or frame_interval <= 0 or not 0 < volume_scale <= 1:
        raise ValueError(f"hoppers >= 1, frame_interval > 0 and 0 < volume_scale <= 1 are needed "
                         f"(got {hoppers}, {frame_interval}, {volume_scale})")
    store = FrameStore(store_path)
    rows = drawn(packing, hoppers, seed, volume_scale)
    settings = {"packing": packing, "draw_seed": seed, "frame_interval": frame_interval, "volume_scale": volume_scale}
    stored, failures = set(store.cases()), store.failures()
    for name, got in [(c, store.attrs_of(c)) for c in stored] + list(failures.items()):
        if any(got.get(k) != v for k, v in settings.items()) or (name in rows and json.loads(got["row"]) != rows[name]):
            made = ", ".join(f"{k} {np.asarray(got.get(k)).tolist()}" for k in settings)
            raise ValueError(f"{store_path}: {name} was made with other settings ({made}); use another store for "
                             + ", ".join(f"{k} {v}" for k, v in settings.items()))
    failed = {k: str(v["reason"]) for k, v in failures.items() if k in rows}
    todo = [k for k in rows if k not in stored and (retry_failed or k not in failed)]
    say(f"{packing}: {len(rows)} hoppers asked, {len(stored & set(rows))} stored, {len(failed)} failed before"
        + (" (run again)" if retry_failed and failed else (" (kept; --retry-failed runs them again)" if failed else ""))
        + f"; running {len(todo)}, {workers} at a time")
    for name, reason in failed.items():
        if name not in todo:
            say(f"  {name}: failed before: {reason}")
    run_into_store(store, {k: (rows[k], packing) for k in todo}, frame_interval, workers,
                   {k: settings | {"row": json.dumps(rows[k])} for k in todo}, failed, say)
    return {"stored": sorted(set(store.cases()) & set(rows)), "failed": failed}


def run_into_store(store: FrameStore, jobs: dict, frame_interval: float, workers: int, attrs: dict, failed: dict,
                   say=print):
    """Runs each job {name: (Table 1-style row, packing)} in a worker process, `workers` at a time,
    and writes each into the store as it ends, with attrs[name] and its DEM time: a case whole, or
    a failure with its reason (also into `failed`), a progress line each."""
    from ..campaign.workers import run_local
    from ..rigs.table1 import row_as_json
    names = list(jobs)
    t0, ended = time.perf_counter(), 0

    def on_result(i: int, res: dict):
        nonlocal ended
        name = names[i]
        ended += 1
        a = attrs.get(name, {}) | {"dem_seconds": float(res.get("wall") or 0.0)}
        if "error" in res:
            store.write_failure(name, res["error"], a)
            failed[name] = res["error"]
            what = f"failed: {res['error']}"
        else:
            store.write_case(name, res["frames"], res["time"], res["discharge_time"], res["nrrp"],
                             a | {"particles": res["particles"]})
            failed.pop(name, None)
            what = f"N {jobs[name][0][0]}, {len(res['frames'])} frames, discharge {res['discharge_time']:.3f} s"
        left = (time.perf_counter() - t0) / ended * (len(names) - ended)
        say(f"  {name}: {what}, {res.get('wall') or 0:.0f} s; {ended}/{len(names)} done, "
            f"{sum(k in failed for k in names)} failed, ~{left / 60:.0f} min left")

    if names:
        run_local({i: (name, row_as_json(jobs[name][0]), jobs[name][1], frame_interval) for i, name in enumerate(names)},
                  run_one, max(1, min(workers, len(names))), on_result, say)
