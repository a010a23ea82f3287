"""Run independent tasks locally (processes) or on a Dask cluster; same results either way.

Tasks are pure functions of their arguments (seeded where random), so where they run cannot
change what they return; results come back in task order. An interrupt (Ctrl-C, SIGTERM turned
into KeyboardInterrupt by the CLI) or a failing task stops the sweep at once: pending tasks are
cancelled and local workers terminated, instead of running every remaining task first. Tasks that
write their own artifacts (the load matrix) keep what finished, so a rerun resumes.
"""
from __future__ import annotations

import os
import re
import signal
from concurrent.futures import ProcessPoolExecutor
from typing import Any, Callable, Iterable, Sequence

from geometry.artifacts import InputError

_ADDRESS = re.compile(r"^((tcp|tls|ucx|ws|wss)://)?(\[[0-9A-Fa-f:.]+\]|[^\s/:\[\]]+):\d{1,5}$")


class SchedulerError(InputError):
    """A --scheduler address that is malformed or where no Dask scheduler answers."""


def check_scheduler(address: str | None) -> str | None:
    """None, or PROTOCOL://HOST:PORT (or HOST:PORT); checked before any work starts."""
    if address is not None and not _ADDRESS.match(address):
        raise SchedulerError(f"--scheduler {address!r}: allowed a Dask scheduler address "
                             "tcp://HOST:PORT (or tls://, ucx://, ws://, wss://)")
    return address


def run_tasks(func: Callable[..., Any], tasks: Sequence[tuple], *, workers: int | None = None,
              scheduler: str | None = None, progress: Callable[[int, int], None] | None = None) -> list:
    """Call func(*task) for every task; in order. scheduler='tcp://host:port' uses Dask."""
    tasks = list(tasks)
    if scheduler:
        return _run_dask(func, tasks, check_scheduler(scheduler), progress)
    workers = workers or min(len(tasks), os.cpu_count() or 1)
    if workers <= 1 or len(tasks) <= 1:
        out = []
        for i, t in enumerate(tasks, 1):
            out.append(func(*t))
            if progress:
                progress(i, len(tasks))
        return out
    return _run_local(func, tasks, workers, progress)


def _worker_init() -> None:
    # SIGTERM kills a worker at once (the parent terminates the pool and clears its temporaries);
    # Ctrl-C reaches the whole process group, only the parent acts on it.
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    signal.signal(signal.SIGINT, signal.SIG_IGN)


def _run_local(func, tasks, workers, progress) -> list:
    pool = ProcessPoolExecutor(max_workers=workers, initializer=_worker_init)
    try:
        futures = [pool.submit(func, *t) for t in tasks]
        out = []
        for i, f in enumerate(futures, 1):
            out.append(f.result())
            if progress:
                progress(i, len(tasks))
    except BaseException:
        _stop(pool)
        raise
    pool.shutdown()
    return out


def _stop(pool: ProcessPoolExecutor) -> None:
    """Cancel what has not started and terminate the workers (running tasks die mid-way)."""
    table = getattr(pool, "_processes", None) or {}   # pid -> process; 3.14: pool.terminate_workers()
    procs = list(table.values())
    pool.shutdown(wait=False, cancel_futures=True)    # drops pool._processes, not the manager thread's table
    # the manager thread may still start a worker it had queued (seen under load): read its table again
    procs += [p for p in list(table.values()) if p not in procs]
    for p in procs:
        if p.is_alive():
            p.terminate()
    for p in procs:
        p.join(timeout=10)


def _run_dask(func, tasks, scheduler: str, progress) -> list:
    from distributed import Client, as_completed
    try:
        client = Client(scheduler, timeout="30s")
    except (OSError, TimeoutError) as exc:
        raise SchedulerError(f"--scheduler {scheduler}: no Dask scheduler answered within 30 s "
                             f"({type(exc).__name__}); start one (`dask scheduler`) or drop the option "
                             "to run on local processes") from None
    with client:
        futures = [client.submit(func, *t, pure=False) for t in tasks]
        try:
            for done, _ in enumerate(as_completed(futures), 1):
                if progress:
                    progress(done, len(tasks))
            return client.gather(futures)
        except BaseException:
            client.cancel(futures, force=True)   # running tasks finish on their workers, unwaited
            raise


def chunks(items: Iterable, n: int) -> list[list]:
    """Split items into n nearly equal consecutive chunks (for batching many small tasks)."""
    items = list(items)
    n = max(1, min(n, len(items)))
    k, r = divmod(len(items), n)
    out, start = [], 0
    for i in range(n):
        stop = start + k + (i < r)
        out.append(items[start:stop])
        start = stop
    return out
