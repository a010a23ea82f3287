"""Run independent tasks locally (processes) or on a Dask cluster; same results either way.

Tasks are pure functions of their arguments (seeded where random), so where they run cannot
change what they return; results come back in task order. An interrupt (Ctrl-C, SIGTERM turned
into KeyboardInterrupt by the CLI) or a failing task stops the sweep at once: pending tasks are
cancelled and local workers terminated, instead of running every remaining task first. Tasks that
write their own artifacts (the load matrix) keep what finished, so a rerun resumes.

A worker that dies mid-sweep (killed, out of memory) costs nothing but time: its tasks run again,
and being pure they return what they would have (the results equal an undisturbed run's). Locally
the pool is rebuilt and the unfinished tasks resubmitted, at most ALLOWED_FAILURES times; on Dask
the scheduler reschedules them (its `allowed-failures`, 3 by default). A task that keeps killing
its worker, or a cluster left without workers for NO_WORKER_TIMEOUT_S, ends the sweep with one
SweepError line naming the task (its index, function and arguments).
"""
from __future__ import annotations

import os
import re
import signal
import time
from concurrent.futures import ProcessPoolExecutor
from concurrent.futures.process import BrokenProcessPool
from typing import Any, Callable, Iterable, Sequence

from geometry.artifacts import InputError

_ADDRESS = re.compile(r"^((tcp|tls|ucx|ws|wss)://)?(\[[0-9A-Fa-f:.]+\]|[^\s/:\[\]]+):\d{1,5}$")


ALLOWED_FAILURES = 3          # pool breaks (a worker died) tolerated per sweep: Dask's default
EXIT_GRACE_S = 10.0          # a finished pool's workers leave within this on its exit message, else are ended
NO_WORKER_TIMEOUT_S = 120.0   # a Dask cluster without a worker this long ends the sweep
_POLL_S = 1.0


class SchedulerError(InputError):
    """A --scheduler address that is malformed or where no Dask scheduler answers."""


class SweepError(InputError):
    """A sweep that cannot finish: a task kills its worker every time it runs, or the cluster has
    no worker left. The message names the task."""


def describe_task(func, tasks, k: int) -> str:
    """'task 3 of 8 (module.func(args...))', arguments shortened: what a user can rerun alone."""
    args = ", ".join(_short(a) for a in tasks[k])
    return f"task {k + 1} of {len(tasks)} ({getattr(func, '__module__', '?')}.{getattr(func, '__qualname__', func)}({args}))"


def _short(a) -> str:
    text = repr(a)
    return text if len(text) <= 60 else text[:57] + "..."


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


PR_SET_PDEATHSIG = 1           # linux/prctl.h


def die_with_parent(parent: int) -> None:
    """Linux: the kernel kills this worker (SIGKILL) when the run that forked it ends, however it
    ends; a SIGKILLed run would otherwise leave its workers computing for nobody until their task
    ends. Elsewhere (no prctl) a no-op. `parent`: the run's pid, to catch a run that died before
    the request was made."""
    try:
        import ctypes
        ctypes.CDLL(None, use_errno=True).prctl(PR_SET_PDEATHSIG, int(signal.SIGKILL), 0, 0, 0)
    except (OSError, AttributeError):
        return
    if os.getppid() != parent:
        os._exit(1)


def _worker_init(parent: int) -> None:
    # SIGTERM kills a worker at once (the parent terminates the pool and clears its temporaries);
    # Ctrl-C reaches the whole process group, only the parent acts on it.
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    die_with_parent(parent)


def _run_local(func, tasks, workers, progress) -> list:
    out: list = [None] * len(tasks)
    done = [False] * len(tasks)
    breaks, finished = 0, 0
    while True:
        todo = [k for k in range(len(tasks)) if not done[k]]
        pool = ProcessPoolExecutor(max_workers=min(workers, len(todo)), initializer=_worker_init,
                                   initargs=(os.getpid(),))
        try:
            futures = {k: pool.submit(func, *tasks[k]) for k in todo}
            for k in todo:                        # in order: a broken pool fails the first unfinished
                out[k] = futures[k].result()
                done[k] = True
                finished += 1
                if progress:
                    progress(finished, len(tasks))
        except BrokenProcessPool:
            _stop(pool)
            breaks += 1
            first = next(k for k in range(len(tasks)) if not done[k])
            if breaks > ALLOWED_FAILURES:
                raise SweepError(f"{describe_task(func, tasks, first)}: a worker process died "
                                 f"{breaks} times while it was unfinished (killed, out of memory, or a "
                                 f"crash in compiled code); run it alone to see why") from None
            continue                              # pure tasks: rerun the unfinished ones
        except BaseException:
            _stop(pool)
            raise
        _stop(pool, graceful=True)
        return out


def _stop(pool: ProcessPoolExecutor, graceful: bool = False) -> None:
    """Cancel what has not started and terminate the workers (running tasks die mid-way).
    graceful (every result is in): the workers get EXIT_GRACE_S to leave on the pool's exit
    message first. Every worker is gone on return: one that outlives SIGTERM is killed. (A worker
    killed while it waits on the pool's call queue holds that queue's lock for ever, and its
    sibling then never reads the exit message: `shutdown(wait=True)` would hang; seen once in a
    full test run.)"""
    table = getattr(pool, "_processes", None) or {}   # pid -> process; 3.14: pool.terminate_workers()
    procs = list(table.values())
    # the manager thread, read before shutdown: shutdown(wait=False) drops the executor's reference to
    # it (and to pool._processes) while the thread goes on joining the workers; left running, it reaped
    # workers under this thread's joins (a pid reaped by the other thread reads as alive here) and
    # after the return (a worker still listed by multiprocessing.active_children(): tests/test_sweep.py)
    manager = getattr(pool, "_executor_manager_thread", None)
    pool.shutdown(wait=False, cancel_futures=True)    # drops pool._processes, not the manager thread's table
    # the manager thread may still start a worker it had queued (seen under load): read its table again
    procs += [p for p in list(table.values()) if p not in procs]
    if graceful:
        deadline = time.monotonic() + EXIT_GRACE_S
        for p in procs:
            p.join(timeout=max(0.0, deadline - time.monotonic()))
    _end(procs)
    # once the manager thread has exited nothing can start another worker: read its table a last time
    if manager is not None:
        manager.join(timeout=10)
    _end([p for p in list(table.values()) if p not in procs])


def _end(procs) -> None:
    """Terminate the live processes of procs, then kill any that outlive it (a SIGTERM handler a
    just-forked worker inherited before its initializer ran may not exit)."""
    for p in procs:
        if p.is_alive():
            p.terminate()
    for p in procs:
        p.join(timeout=5)
        if p.is_alive():
            p.kill()
            p.join(timeout=5)


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
        index = {f.key: k for k, f in enumerate(futures)}
        try:
            _wait_dask(client, futures, progress)
            try:
                return client.gather(futures)
            except Exception as exc:
                if type(exc).__name__ != "KilledWorker":
                    raise
                k = next((index[f.key] for f in futures if f.status == "error"), 0)
                raise SweepError(f"{describe_task(func, tasks, k)}: its Dask worker died every time it "
                                 f"ran (the scheduler's allowed-failures); run it alone to see why") from None
        except BaseException:
            client.cancel(futures, force=True)   # running tasks finish on their workers, unwaited
            raise


def _wait_dask(client, futures, progress) -> None:
    """Wait for every future, ticking progress; a cluster without workers for NO_WORKER_TIMEOUT_S
    raises SweepError naming the first unfinished task (as_completed alone would wait forever)."""
    from distributed import wait
    pending, finished, idle_since = set(futures), 0, None
    while pending:
        try:
            done, pending = wait(list(pending), timeout=_POLL_S, return_when="FIRST_COMPLETED")
        except TimeoutError:
            done = set()
        finished += len(done)
        if done and progress:
            progress(finished, len(futures))
        if done or client.scheduler_info().get("workers"):
            idle_since = None
            continue
        idle_since = idle_since or time.monotonic()
        if time.monotonic() - idle_since > NO_WORKER_TIMEOUT_S:
            k = next(k for k, f in enumerate(futures) if f in pending)
            raise SweepError(f"task {k + 1} of {len(futures)} unfinished: the Dask cluster at "
                             f"{client.scheduler.address} has had no worker for {NO_WORKER_TIMEOUT_S:g} s")


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
