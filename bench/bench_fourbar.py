"""Monte Carlo tolerance samples per second on 1 and 2 local worker processes (parallel efficiency).

The physics is the four-bar kernel of dynamics.fourbar at paper 000's crank angle; forces from the
statics estimate and compliance from tests/support.py's closed-form stand-in so the bench needs no earlier
stage. Efficiency = rate(2) / (2 rate(1)); pool start-up is inside the timing, as a user sees it.
"""
from __future__ import annotations

import functools
import math
import os
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests"))


def run(samples: int = 1_000_000, chunk_size: int = 50_000) -> dict:
    from dynamics import fourbar as fb
    from dynamics import tolerance as tol
    from geometry.params import load_case
    from pipeline.sweep import run_tasks
    from support import stiffness_for_tests

    case = load_case(ROOT / "cases" / "rv40e-105.toml")
    geom = fb.PairGeometry.from_case(case)
    loads = fb.statics_pair_loads(case, geom, math.pi / 2, case.rated_torque_Nm)
    task = tol.ChunkTask(geom, loads, fb.JointCompliance.from_stiffness(stiffness_for_tests(case)),
                         tol.ToleranceBands(), seed=1)
    out = {"samples": samples, "chunk_size": chunk_size, "cpu_count": os.cpu_count()}
    ref = None
    for workers in (1, 2):
        runner = functools.partial(run_tasks, workers=workers)
        t0 = time.perf_counter()
        res = tol.monte_carlo(task, samples, chunk_size=chunk_size, map_chunks=runner)
        dt = time.perf_counter() - t0
        out[f"samples_per_s_{workers}_workers"] = samples / dt
        ref = res.samples if ref is None else ref
        out["identical_results"] = bool((ref == res.samples).all())
    out["parallel_efficiency_2_workers"] = out["samples_per_s_2_workers"] / (2 * out["samples_per_s_1_workers"])
    return out


if __name__ == "__main__":
    import json
    print(json.dumps(run(), indent=1))
