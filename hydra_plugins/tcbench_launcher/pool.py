"""Worker processes for a sweep's jobs that survive a worker's death and die with their parent.

``concurrent.futures.ProcessPoolExecutor`` breaks as a whole when one worker dies (a job that
calls ``os._exit``, the kernel's OOM killer, ``kill -9``): every pending job fails with
``BrokenProcessPool`` and nobody knows which job was running. Here each worker takes one job at a
time over its own pipe, so the parent knows which job a dead worker held: that job is reported
failed (its MLflow run marked FAILED, when it had one), a new worker takes the next job, and the
sweep goes on. Each worker watches its parent and exits when the parent is gone, so killing the
sweep's main process leaves no orphan workers behind.
"""

from __future__ import annotations

import logging
import multiprocessing
import os
import signal
import threading
import time
from collections import deque
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from multiprocessing.connection import Connection, wait
from typing import Any

log = logging.getLogger(__name__)

Job = Callable[[dict[str, Any]], tuple[bool, Any]]


# How often the sweep's main loop wakes with nothing to read. The kernel may hand a Ctrl-C (a
# process-directed SIGINT) to any thread that does not block it; Python then runs its handler in
# the main thread only when that thread next runs, which a wait with no timeout would put off until
# a worker next reports (the end of a job, for a sweep of long jobs).
SIGNAL_CHECK_S = 0.5


class WorkerDied(RuntimeError):
    """The worker process running a job ended before the job did."""


def _exit_with_parent() -> None:
    """End this worker as soon as its parent process ends (``kill -9`` of the sweep included)."""
    parent = multiprocessing.parent_process()
    if parent is None:
        return

    def watch() -> None:
        parent.join()
        os._exit(1)

    threading.Thread(target=watch, daemon=True, name="tcbench-parent-watch").start()


@contextmanager
def _sigint_ignored_by_children() -> Iterator[None]:
    """Around starting a worker: SIGINT ignored (a disposition a spawned process keeps through
    ``exec``, so a Ctrl-C at the terminal cannot interrupt a worker still starting, before its
    own code runs) and blocked meanwhile in this process, so a Ctrl-C then is delivered, not lost,
    once the handler is back."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    mask = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    handler = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, handler)
        signal.pthread_sigmask(signal.SIG_SETMASK, mask)


BLAS_THREAD_VARS = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")


def blas_threads_per_worker(n_workers: int) -> int:
    """The BLAS threads each of ``n_workers`` gets: the cores this process may run on, shared.
    OpenBLAS's threads spin while they wait: with more of them than cores (two workers of two
    threads each on two cores) a 21 579 x 25 Gram took 474 ms where one thread takes 1.4 ms,
    and a diagnosis 38 s where it takes 7 s."""
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)
    return max(1, cores // max(1, n_workers))


@contextmanager
def _blas_threads(n: int) -> Iterator[None]:
    """Around starting a worker: the BLAS thread count its libraries read at load time (a spawned
    process inherits this environment), unless the user set it; this process's own is restored."""
    saved = {var: os.environ.get(var) for var in BLAS_THREAD_VARS}
    if all(value is None for value in saved.values()):
        os.environ.update({var: str(n) for var in BLAS_THREAD_VARS})
    try:
        yield
    finally:
        for var, value in saved.items():
            if value is None:
                os.environ.pop(var, None)
            else:
                os.environ[var] = value


def _worker(conn: Connection, job: Job, init: Callable[[], None] | None) -> None:
    """Worker loop: ``(index, cfg)`` in; ``("run", index, run_id)`` when the job opens its
    MLflow run and ``("done", index, ok, value)`` out; ``None`` in ends it."""
    _exit_with_parent()
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C is the parent's to handle
    signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})  # blocked while the parent started it
    if init is not None:
        init()
    from tcbench.tracking import announce  # not the store: a job that tracks imports MLflow itself

    current = [-1]
    announce.on_run_created = lambda run_id: conn.send(("run", current[0], run_id))
    while True:
        try:
            task = conn.recv()
        except EOFError:
            return
        if task is None:
            return
        current[0], cfg = task
        ok, value = job(cfg)
        conn.send(("done", current[0], ok, value))


def _died(proc: multiprocessing.process.BaseProcess) -> str:
    proc.join(1)
    code = proc.exitcode
    if code is not None and code < 0:
        try:
            return f"killed by signal {signal.Signals(-code).name}"
        except ValueError:
            return f"killed by signal {-code}"
    return f"exited with code {code}"


def _end(procs: list[multiprocessing.process.BaseProcess], at_once: bool, grace_s: float = 5.0) -> None:
    """End every worker: ``at_once`` (a Ctrl-C, an error) by SIGTERM, else (every job done) each
    given ``grace_s`` to exit by itself; any left then is killed (SIGKILL). Each is reaped, so
    none outlives the sweep and none holds its runs when they are marked, and no wait is
    unbounded: a worker still starting, or slow to exit, cannot hold the sweep's end."""
    for proc in procs:
        if at_once and proc.pid is not None and proc.is_alive():
            proc.terminate()
    deadline = time.monotonic() + grace_s
    for proc in procs:
        if proc.pid is not None:
            proc.join(max(0.0, deadline - time.monotonic()))
    for proc in procs:
        if proc.pid is not None and proc.is_alive():
            proc.kill()
            proc.join(1.0)


def run_jobs(configs: Sequence[dict[str, Any]], n_workers: int, job: Job,
             init: Callable[[], None] | None = None,
             on_lost_run: Callable[[int, str, str], None] | None = None,
             on_done: Callable[[int, bool], None] | None = None) -> list[tuple[bool, Any]]:
    """Run ``job(cfg)`` for every config on ``n_workers`` spawned processes; the ``(ok, value)``
    of each, in order. A job whose worker died gets ``(False, WorkerDied(...))`` and, if it had
    opened an MLflow run, ``on_lost_run(index, run_id, why)`` is called for it. ``on_done(index,
    ok)`` is called as each job ends (the sweep's progress)."""
    context = multiprocessing.get_context("spawn")
    pending = deque(enumerate(configs))
    results: list[tuple[bool, Any] | None] = [None] * len(configs)
    busy: dict[Connection, tuple[multiprocessing.process.BaseProcess, int | None, str | None]] = {}

    started: list[multiprocessing.process.BaseProcess] = []  # every worker, ended by the finally below
    blas_threads = blas_threads_per_worker(min(n_workers, len(configs)))

    def start() -> None:
        parent_end, child_end = context.Pipe()
        proc = context.Process(target=_worker, args=(child_end, job, init), daemon=True)
        started.append(proc)  # before it runs: a Ctrl-C while it starts still ends it
        with _sigint_ignored_by_children(), _blas_threads(blas_threads):
            proc.start()
        child_end.close()
        busy[parent_end] = (proc, None, None)
        give(parent_end)

    def give(conn: Connection) -> None:
        proc, _, _ = busy[conn]
        if pending:
            index, cfg = pending.popleft()
            conn.send((index, cfg))
            busy[conn] = (proc, index, None)
        else:  # no job left: the worker ends by itself, and is reaped when it has (or ended below)
            try:
                conn.send(None)
            except OSError:
                pass
            conn.close()
            del busy[conn]

    done = False
    try:
        for _ in range(min(n_workers, len(configs))):
            start()
        while busy:
            sentinels = {proc.sentinel: conn for conn, (proc, _, _) in busy.items()}
            for ready in wait([*busy, *sentinels], timeout=SIGNAL_CHECK_S):
                conn = ready if isinstance(ready, Connection) else sentinels[ready]
                if conn not in busy:
                    continue
                proc, index, run_id = busy[conn]
                try:
                    message = conn.recv()
                except (EOFError, OSError):
                    message = None
                if message is not None and message[0] == "run":
                    busy[conn] = (proc, index, message[2])
                elif message is not None:
                    results[message[1]] = (message[2], message[3])
                    if on_done is not None:
                        on_done(message[1], bool(message[2]))
                    give(conn)
                else:  # the worker is gone
                    why = _died(proc)
                    conn.close()
                    del busy[conn]
                    if index is not None:
                        log.error("the worker running job %d %s; the sweep goes on", index, why)
                        results[index] = (False, WorkerDied(f"the worker process running the job {why}"))
                        if on_done is not None:
                            on_done(index, False)
                        if run_id is not None and on_lost_run is not None:
                            on_lost_run(index, run_id, f"WorkerDied: the worker process running the job {why}")
                    if pending:
                        start()
        done = True
    finally:  # on Ctrl-C too: the workers end, and are reaped, before the sweep marks their runs KILLED
        _end(started, at_once=not done)
    return [r if r is not None else (False, WorkerDied("the job never ran")) for r in results]
