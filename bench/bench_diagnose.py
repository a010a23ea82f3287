"""Wall time of `diagnose` on a 10 s record: RV-40E i=81, input at 486 rpm so that 10 s is one
output revolution (paper 001's 1200 rpm would give 0.82 revolution, too short for orders), a
forward/backward pair with a hidden coaxiality, 4 kHz sampling (40001 samples per record), 1024
simulated points per output revolution."""
from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np


def run() -> dict:
    root = Path(__file__).parents[1]
    sys.path.insert(0, str(root / "tests"))
    from support import stiffness_for_tests
    from geometry.params import load_case
    from pipeline.diagnosis.bench import bench_records, draw_effect
    from pipeline.diagnosis.diagnose import diagnose
    from pipeline.diagnosis.simulate import quasi_static_te
    case = load_case(root / "cases" / "rv40e-81.toml")
    stiff = stiffness_for_tests(case)
    eff = draw_effect(np.random.default_rng(0), case, "output_coaxiality")
    recs = bench_records(quasi_static_te, case, stiff, [eff], seed=0, torque_fractions=(0.3,),
                         samples_per_rev=1024, speed_rpm=6.0 * case.ratio)
    # resample each record to 4 kHz over its 10 s (the loader's view of a real 10 s record)
    from dynamics.records import BenchRecord
    dense = []
    for r in recs:
        t = np.linspace(0.0, r.time_s[-1], 40001)
        dense.append(BenchRecord(r.name, t, np.interp(t, r.time_s, r.input_angle_deg),
                                 np.interp(t, r.time_s, r.output_angle_deg), np.interp(t, r.time_s, r.output_torque_Nm),
                                 r.comments))
    t0 = time.perf_counter()
    d = diagnose(case, stiff, dense, points_per_rev=1024)
    wall = time.perf_counter() - t0
    return {"diagnose_wall_s_10s_record_pair": wall, "record_duration_s": float(dense[0].time_s[-1]),
            "samples_per_record": 40001, "cause": d.cause,
            "gain": d.extension.gain if d.extension else None}


if __name__ == "__main__":
    print(run())
