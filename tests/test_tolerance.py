"""Monte Carlo tolerance analysis: bands, seed determinism, chunking, local processes vs Dask."""
from __future__ import annotations

import functools
import json
import math
import sys
from pathlib import Path

import numpy as np
import pytest

from dynamics import fourbar as fb
from dynamics import tolerance as tol
from geometry.params import load_case
from pipeline.sweep import run_tasks

sys.path.insert(0, str(Path(__file__).resolve().parent))
from support import stiffness_for_tests  # noqa: E402
from test_fourbar import CASE  # noqa: E402


@pytest.fixture(scope="module")
def task():
    case = load_case(CASE)
    geom = fb.PairGeometry.from_case(case)
    loads = fb.statics_pair_loads(case, geom, math.pi / 2, case.rated_torque_Nm)
    comp = fb.JointCompliance.from_stiffness(stiffness_for_tests(case))
    return tol.ChunkTask(geom, loads, comp, tol.ToleranceBands(), seed=7)


def test_draws_stay_inside_their_bands():
    b = tol.ToleranceBands(eccentricity_um=3, crank_hole_um=4, output_hole_um=6,
                           turning_arm_clearance_um=5, support_clearance_um=2)
    d = tol.draw(b, 1, 0, 4000)
    lim = np.array([3, 3, 4, 6, 5, 5, 2, 2])
    assert np.all(np.abs(d) <= lim) and np.all(d[:, 4:] >= 0)
    # uniform +-band: the sample spread reaches the band edges (4000 draws: within 1 %)
    assert np.all(np.max(np.abs(d[:, :4]), axis=0) > 0.99 * lim[:4])


def test_the_same_seed_gives_the_same_builds_whatever_the_chunking(task):
    a = tol.monte_carlo(task, 1000, chunk_size=1000).samples
    b = tol.monte_carlo(task, 1000, chunk_size=137).samples
    c = tol.monte_carlo(tol.ChunkTask(task.geom, task.loads, task.compliance, task.bands, 8), 1000).samples
    assert np.array_equal(a, b)
    assert not np.array_equal(a, c)


def test_local_processes_give_the_in_process_result(task):
    ref = tol.monte_carlo(task, 600, chunk_size=100).samples
    par = tol.monte_carlo(task, 600, chunk_size=150,
                          map_chunks=functools.partial(run_tasks, workers=2)).samples
    assert np.array_equal(ref, par)


def test_dask_on_loopback_gives_the_local_result(task):
    distributed = pytest.importorskip("distributed")
    ref = tol.monte_carlo(task, 600, chunk_size=200, map_chunks=functools.partial(run_tasks, workers=2))
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                                  dashboard_address=None) as cluster:
        got = tol.monte_carlo(task, 600, chunk_size=150,
                              map_chunks=functools.partial(run_tasks, scheduler=cluster.scheduler_address))
    assert np.array_equal(ref.samples, got.samples)


def test_zero_bands_reproduce_the_nominal_build(task):
    zero = tol.ToleranceBands(0, 0, 0, 0, 0)
    res = tol.monte_carlo(tol.ChunkTask(task.geom, task.loads, task.compliance, zero, 1), 50)
    assert np.all(res.rigid_arcsec == 0.0)
    assert np.allclose(res.elastic_arcsec, res.nominal_elastic_arcsec, rtol=0, atol=1e-12)
    assert res.summary()["rigid"]["share_within_limit"] == 1.0


def test_rigid_spread_follows_the_eccentricity_difference(task):
    # at 90 deg the rigid error is (l1 - l3) / l4 to first order (clearances: along the load)
    res = tol.monte_carlo(tol.ChunkTask(task.geom, task.loads, task.compliance,
                                        tol.ToleranceBands(5, 0, 0, 0, 0), 3), 400)
    d = res.samples
    want = (d[:, 0] - d[:, 1]) * 1e-3 / task.geom.spacing_mm * fb.ARCSEC_PER_RAD
    assert np.allclose(res.rigid_arcsec, want, rtol=5e-3, atol=1e-3)


@pytest.mark.parametrize("field, value", [("eccentricity_um", -1.0), ("support_clearance_um", 500.0),
                                          ("distribution", "triangular")])
def test_bad_bands_name_the_band_and_the_allowed_range(field, value):
    with pytest.raises(fb.FourBarError, match=field.replace("_um", "") if field != "distribution" else "allowed"):
        tol.ToleranceBands(**{field: value})


def test_tolerance_command_writes_summary_samples_and_histogram(tmp_path):
    from fem.stiffness import save
    from pipeline.cli import main
    stiff = tmp_path / "s.json"
    save(stiffness_for_tests(load_case(CASE)), stiff)
    out = tmp_path / "tol"
    assert main(["tolerance", "--case", str(CASE), "--samples", "500", "--seed", "3", "--out", str(out),
                 "--stiffness", str(stiff), "--workers", "1", "--quiet"]) == 0
    s = json.loads((out / "summary.json").read_text())
    assert s["samples"] == 500 and 0.0 <= s["rigid"]["share_within_limit"] <= 1.0
    assert len((out / "samples.csv").read_text().splitlines()) == 501
    assert (out / "histogram.png").stat().st_size > 10_000
    assert main(["tolerance", "--case", str(CASE), "--samples", "0", "--out", str(out),
                 "--stiffness", str(stiff), "--quiet"]) == 2


def test_a_rerun_of_the_tolerance_command_gives_the_same_bytes(tmp_path):
    # timings belong in logs and benchmarks, not in artifacts: summary.json holds no wall time
    from fem.stiffness import save
    from pipeline.cli import main
    stiff = tmp_path / "s.json"
    save(stiffness_for_tests(load_case(CASE)), stiff)
    outs = [tmp_path / "a", tmp_path / "b"]
    for out in outs:
        assert main(["tolerance", "--case", str(CASE), "--samples", "400", "--seed", "5", "--out", str(out),
                     "--stiffness", str(stiff), "--workers", "1", "--quiet"]) == 0
    summary = json.loads((outs[0] / "summary.json").read_text())
    assert not [k for k in summary if "wall" in k]
    for name in ("summary.json", "samples.csv"):
        assert (outs[0] / name).read_bytes() == (outs[1] / name).read_bytes(), name


def test_a_limit_that_is_not_positive_is_refused():
    task = tol.ChunkTask(None, None, None, tol.ToleranceBands(), 0)
    for limit in (0.0, -1.0, float("nan")):
        with pytest.raises(fb.FourBarError, match="accuracy limit"):
            tol.monte_carlo(task, 10, limit_arcsec=limit)
