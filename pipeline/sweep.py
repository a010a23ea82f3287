"""Run independent tasks locally (processes) or on a Dask cluster; same results either way.

Tasks are pure functions of their arguments (seeded where random), so where they run cannot
change what they return; results come back in task order.
"""
from __future__ import annotations

import os
from concurrent.futures import ProcessPoolExecutor
from typing import Any, Callable, Iterable, Sequence


def run_tasks(func: Callable[..., Any], tasks: Sequence[tuple], *, workers: int | None = None,
              scheduler: str | None = None, progress: Callable[[int, int], None] | None = None) -> list:
    """Call func(*task) for every task; in order. scheduler='tcp://host:port' uses Dask."""
    tasks = list(tasks)
    if scheduler:
        from distributed import Client, as_completed
        with Client(scheduler, timeout="30s") as client:
            futures = [client.submit(func, *t, pure=False) for t in tasks]
            for done, _ in enumerate(as_completed(futures), 1):
                if progress:
                    progress(done, len(tasks))
            return client.gather(futures)
    workers = workers or min(len(tasks), os.cpu_count() or 1)
    if workers <= 1 or len(tasks) <= 1:
        out = []
        for i, t in enumerate(tasks, 1):
            out.append(func(*t))
            if progress:
                progress(i, len(tasks))
        return out
    with ProcessPoolExecutor(max_workers=workers) as pool:
        futures = [pool.submit(func, *t) for t in tasks]
        out = []
        for i, f in enumerate(futures, 1):
            out.append(f.result())
            if progress:
                progress(i, len(tasks))
        return out


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
