"""Wall time of the diagnosis on long records (issue 13: cost grew 0.5 ms a row, > 5 min for 2
million rows). RV-40E i = 81 on tests/support.py's stiffness, a hidden coaxiality, 0.3 x rated
torque, 0.3 arcsec noise and 2^22-count encoders (as the virtual bench):
  pair_10s     a forward/backward pair of 10 s records at 4 kHz (40001 samples each), input at
               486 rpm so that 10 s is one output revolution;
  rows_2M      one forward record of 2 million rows at 4 kHz (500 s at the case's 1200 rpm input:
               123 output revolutions), written as CSV, then read (dynamics.records.read_records)
               and diagnosed; the requirement is <= 60 s for read + diagnose on this machine.
The diagnosis' default grid (simulate.default_points_per_rev). Records are built from one simulated revolution
read periodically (the mechanism repeats each output revolution), so building them is cheap."""
from __future__ import annotations

import sys
import tempfile
import time
from pathlib import Path

import numpy as np


def _setup():
    root = Path(__file__).parents[1]
    sys.path.insert(0, str(root / "tests"))
    from support import stiffness_for_tests
    from geometry.params import load_case
    case = load_case(root / "cases" / "rv40e-81.toml")
    return case, stiffness_for_tests(case)


def _long_record(case, stiff, eff, n_rows: int, fs_hz: float, seed: int = 0):
    """(t, input, output, torque) of a forward run sampled at fs_hz, the TE of the hidden model."""
    from dynamics.results import ARCSEC_PER_DEG
    from pipeline.diagnosis.bench import apply_effects
    from pipeline.diagnosis.simulate import quasi_static_te
    rng = np.random.default_rng(seed)
    hc, hs = apply_effects(case, stiff, [eff])
    T = 0.3 * case.rated_torque_Nm
    period = 360.0 * case.ratio
    grid = np.arange(4096) * (period / 4096)
    te1 = quasi_static_te(hc, hs, grid, T, 1)
    t = np.arange(n_rows) / fs_hz
    th_in = 6.0 * case.operation.input_speed_rpm * t
    te = np.interp(th_in, grid, te1, period=period) + rng.normal(0.0, 0.3, n_rows)
    q = 360.0 / 2 ** 22
    return t, np.round(th_in / q) * q, np.round((th_in / case.ratio + te / ARCSEC_PER_DEG) / q) * q, np.full(n_rows, T)


def rows_2m(case, stiff, eff) -> dict:
    from dynamics.records import read_records, write_record
    from pipeline.diagnosis.diagnose import diagnose
    cols = _long_record(case, stiff, eff, 2_000_000, 4000.0)
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "rows_2M_fw.csv"
        write_record(path, *cols, comments=[f"input_speed_rpm: {case.operation.input_speed_rpm:g}"])
        t0 = time.perf_counter()
        recs = read_records(path)
        t1 = time.perf_counter()
        d = diagnose(case, stiff, recs)
        t2 = time.perf_counter()
    return {"rows_2M_read_s": t1 - t0, "rows_2M_diagnose_s": t2 - t1, "rows_2M_total_s": t2 - t0,
            "rows_2M_revolutions": float(recs[0].output_travel_deg / 360.0), "rows_2M_cause": d.cause,
            "rows_2M_coaxiality_um": d.extension.parameters.get("output_coaxiality_um") if d.extension else None,
            "rows_2M_true_coaxiality_um": eff.truth["output_coaxiality_um"]}


def pair_10s(case, stiff, eff) -> dict:
    from dynamics.records import BenchRecord
    from pipeline.diagnosis.bench import bench_records
    from pipeline.diagnosis.diagnose import diagnose
    from pipeline.diagnosis.simulate import quasi_static_te
    recs = bench_records(quasi_static_te, case, stiff, [eff], seed=0, torque_fractions=(0.3,),
                         samples_per_rev=1024, speed_rpm=6.0 * case.ratio)
    dense = []   # each record resampled to 4 kHz over its 10 s (the loader's view of a real record)
    for r in recs:
        t = np.linspace(0.0, r.time_s[-1], 40001)
        dense.append(BenchRecord(r.name, t, np.interp(t, r.time_s, r.input_angle_deg),
                                 np.interp(t, r.time_s, r.output_angle_deg),
                                 np.interp(t, r.time_s, r.output_torque_Nm), r.comments))
    t0 = time.perf_counter()
    d = diagnose(case, stiff, dense)
    return {"diagnose_wall_s_10s_record_pair": time.perf_counter() - t0,
            "record_duration_s": float(dense[0].time_s[-1]), "samples_per_record": 40001, "cause": d.cause,
            "gain": d.extension.gain if d.extension else None}


def run() -> dict:
    from pipeline.diagnosis.bench import draw_effect
    case, stiff = _setup()
    eff = draw_effect(np.random.default_rng(0), case, "output_coaxiality")
    return {**pair_10s(case, stiff, eff), **rows_2m(case, stiff, eff)}


if __name__ == "__main__":
    print(run())
