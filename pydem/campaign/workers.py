"""Campaign runs in local worker processes (run_local: one fresh process per run, at most
`workers` at a time) or on a Dask cluster (run_dask).

Why not a ProcessPoolExecutor: when one of its workers dies (the out-of-memory killer, a
`kill -9`), the whole pool breaks and the other workers' runs in progress are thrown away. Here
a lost worker costs exactly its own run, which is retried once and then recorded as failed;
the campaign goes on. A worker also exits on its own when the campaign process dies (a
watchdog on its parent's pid, and PR_SET_PDEATHSIG on Linux), so a killed campaign leaves no
idle workers behind.

A run's result reaches the parent through a pipe; the parent saves it before it starts the
next run, so nothing reported finished is ever lost."""
from __future__ import annotations

import multiprocessing as mp
import os
import signal
import sys
import threading
import time
from multiprocessing.connection import wait
from typing import Callable

RETRIES_AFTER_LOSS = 1  # a worker killed from outside: its run is tried once more
MAX_BROKEN = 3          # workers in a row that exit with an error code and no result: stop


class WorkerStartError(RuntimeError):
    """Worker processes cannot run at all (they exit with an error before any result)."""


def _die_with_parent(parent: int):
    """Exit as soon as the campaign process that started us is gone."""
    try:  # Linux: the kernel signals us when the parent dies
        import ctypes
        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(1, signal.SIGKILL)  # PR_SET_PDEATHSIG
    except (OSError, AttributeError):
        pass

    def watch():
        while True:
            if os.getppid() != parent:
                os._exit(3)
            time.sleep(0.5)

    threading.Thread(target=watch, daemon=True).start()
    if os.getppid() != parent:  # died before the watch started
        os._exit(3)


def _worker(conn, parent: int, func, args):
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C goes to the campaign: it lets running runs finish
    _die_with_parent(parent)
    try:
        out = func(*args)
    except BaseException as exc:  # func reports its own errors; this is a last resort
        out = {"error": f"{type(exc).__name__}: {exc}", "wall": 0.0}
    conn.send(out)
    conn.close()


def run_local(jobs: dict, func: Callable, workers: int, on_result: Callable[[int, dict], None],
              say: Callable[[str], None] | None = None):
    """Runs func(*jobs[i]) for every i, `workers` at a time, each in a new process; calls
    on_result(i, result) in the parent as each ends. A worker that dies without a result
    (killed) is retried once, then reported as {"error": "worker process died ..."}.
    Ctrl-C: no new runs start, the running ones finish and are reported, then it re-raises;
    a second Ctrl-C stops them too."""
    ctx = mp.get_context("spawn")  # a fresh interpreter (forking a process that holds OpenMP threads is unsafe)
    queue = list(jobs)
    tries = {i: 0 for i in jobs}
    running: dict = {}  # sentinel -> (index, process, connection, start)
    parent = os.getpid()
    interrupted = None
    broken = 0  # workers in a row that exited with an error and no result: they cannot start

    def start(i):
        recv, send = ctx.Pipe(duplex=False)
        p = ctx.Process(target=_worker, args=(send, parent, func, jobs[i]), daemon=True)
        p.start()
        send.close()
        running[p.sentinel] = [i, p, recv, time.perf_counter(), None]

    try:
        while queue or running:
            while queue and len(running) < workers and interrupted is None:
                start(queue.pop(0))
            if not running:
                break
            # the results are read as they come, not when the worker has exited: a result larger than
            # the pipe's buffer (64 KiB: a hopper's frames) blocks its worker until it is read
            reading = {r[2]: r for r in running.values() if r[4] is None}
            try:
                ready = wait(list(running) + list(reading), timeout=1.0)
            except KeyboardInterrupt as exc:
                if interrupted is not None:
                    raise
                interrupted = exc
                if say:
                    say(f"interrupted: waiting for {len(running)} running run(s) to finish (Ctrl-C again to stop them)")
                continue
            for conn in (r for r in ready if r in reading):
                try:
                    reading[conn][4] = conn.recv()
                except (EOFError, OSError):  # the worker died before it sent: its sentinel follows
                    reading[conn][4] = False
            for sentinel in (r for r in ready if r in running):
                i, p, recv, t0, out = running.pop(sentinel)
                if out is None:
                    try:
                        out = recv.recv() if recv.poll() else None
                    except (EOFError, OSError):
                        out = None
                if out is False:  # the pipe closed with no result
                    out = None
                recv.close()
                p.join()
                if out is None and p.exitcode and p.exitcode > 0:
                    broken += 1
                    if broken >= MAX_BROKEN:  # e.g. the code does not import: stop rather than fail every run
                        queue.insert(0, i)
                        raise WorkerStartError(f"{broken} worker processes in a row exited with code {p.exitcode} "
                                               f"before returning a result (see their error above); the runs stay "
                                               f"pending")
                elif out is not None:
                    broken = 0
                if out is None:  # killed from outside (OOM killer, kill -9): no result
                    tries[i] += 1
                    how = f"signal {-p.exitcode}" if p.exitcode and p.exitcode < 0 else f"exit code {p.exitcode}"
                    if tries[i] <= RETRIES_AFTER_LOSS and interrupted is None:
                        if say:
                            say(f"run {i}: its worker process died ({how}); running it again")
                        queue.insert(0, i)
                        continue
                    out = {"error": f"worker process died ({how}) {tries[i]} time(s)", "wall": time.perf_counter() - t0}
                on_result(i, out)
        if interrupted is not None:
            raise interrupted
    finally:
        for i, p, recv, _, _ in running.values():  # only on an error or a second Ctrl-C
            p.kill()
            p.join()
            recv.close()
    sys.stderr.flush()


def run_dask(address: str, jobs: dict, func: Callable, on_result: Callable[[int, dict], None], key: str,
             timeout: str = "30s"):
    """Each job's func(*args) on the Dask scheduler at `address`, on_result(i, result) as each ends
    (in the calling thread). Task keys are <key>-<i>-<last argument, the seed>: a resubmitted run
    is another task. WorkerStartError names a missing `distributed` or an unreachable scheduler."""
    try:
        from distributed import Client, as_completed
    except ImportError:
        raise WorkerStartError("--dask needs the 'distributed' package (pip install distributed)") from None
    try:
        client = Client(address, timeout=timeout)
    except (OSError, TimeoutError, ValueError) as exc:
        raise WorkerStartError(f"cannot reach the Dask scheduler at {address!r}: {exc}") from None
    with client:
        futures = {client.submit(func, *a, pure=False, key=f"{key}-{i}-{a[-1]}"): i for i, a in jobs.items()}
        index = {f.key: i for f, i in futures.items()}
        for fut in as_completed(list(futures)):
            on_result(index[fut.key], fut.result())
