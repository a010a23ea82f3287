"""Full-model tolerance Monte Carlo (`tolerance --model full`): builds per second on 1 process and on
2 workers (local processes, and a local Dask cluster), parallel efficiency T1 / (2 T2).

Each build is ~390 static solves over one output revolution plus the catalog test (~0.3 s), and a
task carries dynamics.tolerance.FULL_CHUNK builds, so a task is seconds of work and pool or cluster
start-up stays a small share (the four-bar Monte Carlo's microsecond samples gave 0.56 on Dask).
Stiffness: tests/support.py's closed-form stand-in (no earlier stage needed). Local pool start-up
is inside the timing; the Dask workers are warmed first (a cluster outlives one run). Results must
be identical on every runner. The machine's other load skews the figures: read them on an idle one.
"""
from __future__ import annotations

import functools
import os
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests"))


def run(samples: int = 160) -> dict:
    import numpy as np
    from distributed import LocalCluster
    from dynamics import tolerance as tol
    from dynamics.signatures import points_per_rev
    from geometry.params import load_case
    from pipeline.sweep import run_tasks
    from support import stiffness_for_tests

    case = load_case(ROOT / "cases" / "rv40e-81.toml")
    task = tol.FullTask(case, stiffness_for_tests(case), "uniform", 1, case.rated_torque_Nm, points_per_rev(case))
    out = {"case": case.name, "builds": samples, "builds_per_task": tol.FULL_CHUNK, "cpu_count": os.cpu_count()}

    def timed(runner):
        t0 = time.perf_counter()
        res = tol.full_monte_carlo(task, samples, map_chunks=runner)
        return time.perf_counter() - t0, res.samples

    t1, ref = timed(functools.partial(run_tasks, workers=1))
    t2, local = timed(functools.partial(run_tasks, workers=2))
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
        dask_runner = functools.partial(run_tasks, scheduler=cluster.scheduler_address)
        # a cluster is long-lived: its workers' one-time imports and JIT-cache loads (~4 s) are done
        # before timing; local worker processes are forked from this one, start-up inside their time
        tol.full_monte_carlo(task, 2, chunk_size=1, map_chunks=dask_runner)
        td, dask = timed(dask_runner)
    same = lambda a: bool(((a == ref) | (np.isnan(a) & np.isnan(ref))).all())  # noqa: E731
    out.update({"seconds_1_process": t1, "seconds_2_local_processes": t2, "seconds_2_dask_workers": td,
                "builds_per_s_1_process": samples / t1,
                "parallel_efficiency_2_local_processes": t1 / (2 * t2),
                "parallel_efficiency_2_dask_workers": t1 / (2 * td),
                "identical_results": same(local) and same(dask)})
    return out


if __name__ == "__main__":
    import json
    print(json.dumps(run(), indent=1))
