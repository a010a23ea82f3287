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


# ---------------------------------------------------------------- full model (tolerance --model full)
# n = 78 points per output revolution (a divisor of zp zc = 1560 above 2 zc): orders up to 39 resolved,
# enough for what these tests read (1x, zp folds to 78 - 40 = 38), and 5x faster than the default grid

N_FAST = 78


@pytest.fixture(scope="module")
def full():
    case = load_case(CASE)
    return tol.FullTask(case, stiffness_for_tests(case), "uniform", 11, case.rated_torque_Nm, N_FAST)


def _bands(case, **bands):
    import dataclasses
    zero = {f.name: 0.0 for f in dataclasses.fields(case.tolerances)}
    return case.replace("tolerances", **(zero | bands))


def test_full_model_draws_stay_inside_the_case_bands():
    case = load_case(CASE)
    tl = case.tolerances
    for i in range(30):
        b = tol.draw_build(case, "uniform", 3, i)
        assert max(map(abs, b["pin_position_um"]["per_pin_radial_um"])) <= tl.pin_position_um
        assert len(b["pin_position_um"]["per_pin_tangential_um"]) == case.cycloid.zp
        assert max(map(abs, b["crank_hole_um"]["crank_hole_position_um"])) <= tl.crank_hole_um
        assert max(map(abs, b["eccentricity_um"]["crank_eccentricity_um"])) <= tl.eccentricity_um
        assert max(abs(r[2]) for r in b["disc_pitch_um"]["disc_pitch_lobes"]) <= tl.disc_pitch_um
        assert 0 <= b["turning_arm_clearance_um"]["turning_arm_clearance_um"] <= tl.turning_arm_clearance_um
        case.with_errors(**tol.merge_errors(b.values()))       # every draw is a valid [errors] set


def test_a_build_is_seeded_by_its_index_not_by_its_chunk(full):
    a = tol.evaluate_full_chunk(full, 0, 3)
    b = tol.evaluate_full_chunk(full, 2, 3)
    assert np.array_equal(a[2:], b, equal_nan=True)
    assert np.isfinite(a[:, :4]).all() and not np.array_equal(a[0], a[1])


def test_zero_bands_give_the_ideal_build(full):
    import dataclasses
    zero = dataclasses.replace(full, case=_bands(full.case))
    ideal = tol.evaluate_full_chunk(full, 0, 1, "")[0]
    assert np.allclose(tol.evaluate_full_chunk(zero, 0, 2), ideal, rtol=1e-9, atol=1e-9, equal_nan=True)


def test_the_coaxiality_band_is_a_reading_of_e_over_r_at_1x(full):
    # encoder/mounting eccentricity e at flange radius r reads e / r sin(theta + phase): a 1x line of
    # e / r rad (dynamics.reducer.measured_output_rad), and leaves the reducer's own TE untouched
    import dataclasses
    task = dataclasses.replace(full, case=_bands(full.case, output_coaxiality_um=8.0))
    row = tol.evaluate_full_chunk(task, 0, 1)[0]
    e_um = tol.draw_build(task.case, "uniform", task.seed, 0)["output_coaxiality_um"]["output_coaxiality_um"]
    expect = e_um * 1e-6 / (task.case.carrier.output_flange_radius_mm * 1e-3) * fb.ARCSEC_PER_RAD
    c = tol.FULL_METRICS.index
    assert row[c("bench_line_1x_arcsec")] == pytest.approx(expect, rel=1e-3)
    assert row[c("te_pp_arcsec")] < 0.2 * row[c("bench_te_pp_arcsec")]


def test_full_runs_give_the_same_numbers_in_process_on_local_processes_and_on_dask(full):
    distributed = pytest.importorskip("distributed")
    ref = tol.full_monte_carlo(full, 4, chunk_size=4, sensitivity_builds=1)
    loc = tol.full_monte_carlo(full, 4, chunk_size=1, sensitivity_builds=1,
                               map_chunks=functools.partial(run_tasks, workers=2))
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                                  dashboard_address=None) as cluster:
        dask = tol.full_monte_carlo(full, 4, chunk_size=2, sensitivity_builds=1,
                                    map_chunks=functools.partial(run_tasks, scheduler=cluster.scheduler_address))
    for got in (loc, dask):
        assert np.array_equal(ref.samples, got.samples, equal_nan=True)
        assert json.dumps(ref.summary()) == json.dumps(got.summary())      # NaN-safe, chunking-free
    rank = ref.summary()["sensitivity"]
    assert {d["band"] for d in rank} == set(tol.band_names(full.case))
    assert sum(d["te_variance_share"] for d in rank) == pytest.approx(1.0)


def test_tolerances_are_not_in_the_case_fingerprint_but_in_the_artifact(tmp_path):
    from fem.stiffness import save
    from geometry.fingerprint import case_fingerprint
    from pipeline.cli import main
    case = load_case(CASE)
    assert case_fingerprint(_bands(case, disc_pitch_um=1.0)) == case_fingerprint(case)
    stiff = tmp_path / "s.json"
    save(stiffness_for_tests(case), stiff)
    out = tmp_path / "full"
    assert main(["tolerance", "--model", "full", "--case", str(CASE), "--samples", "2", "--sensitivity-builds", "1",
                 "--stiffness", str(stiff), "--workers", "1", "--out", str(out), "--quiet"]) == 0
    s = json.loads((out / "summary.json").read_text())
    assert s["model"] == "full" and s["samples"] == 2 and "tolerances" in s["made_from"]["inputs"]
    assert s["bands_um"]["disc_pitch_um"] == case.tolerances.disc_pitch_um
    assert len((out / "samples.csv").read_text().splitlines()) == 3
    for name in ("histogram.png", "sensitivity.png", "sensitivity.csv"):
        assert (out / name).stat().st_size > 0, name
    # a four-bar band option is refused with --model full (the bands are the case's [tolerances])
    assert main(["tolerance", "--model", "full", "--case", str(CASE), "--samples", "2", "--eccentricity-um", "3",
                 "--stiffness", str(stiff), "--out", str(out), "--quiet"]) == 2


def test_a_bad_tolerance_band_names_the_key_and_the_range(tmp_path):
    from geometry.params import CaseError
    text = CASE.read_text().replace("disc_pitch_um = 11.0", "disc_pitch_um = -1.0")
    bad = tmp_path / "bad.toml"
    bad.write_text(text)
    with pytest.raises(CaseError, match=r"\[tolerances\] disc_pitch_um = -1.0: outside the allowed range"):
        load_case(bad)
    case = _bands(load_case(CASE), eccentricity_um=40.0)   # eccentric phase 2 x 40 um / 1.3 mm = 212 arcmin
    with pytest.raises(CaseError, match=r"\[tolerances\] eccentricity_um = 40"):
        tol.check_tolerances(case)


def test_the_pin_ring_tilt_band_is_drawn_last_so_the_other_bands_keep_their_numbers():
    import dataclasses
    from support import case_path
    case = load_case(case_path("rv160n-81"))
    build = tol.draw_build(case, "uniform", 7, 3)
    assert list(build)[-1] == "pin_ring_tilt_um"
    assert 0.0 <= build["pin_ring_tilt_um"]["pin_ring_tilt_um"] <= case.tolerances.pin_ring_tilt_um
    narrow = dataclasses.replace(case, tolerances=dataclasses.replace(case.tolerances, pin_ring_tilt_um=0.0))
    other = tol.draw_build(narrow, "uniform", 7, 3)
    assert other["pin_ring_tilt_um"]["pin_ring_tilt_um"] == 0.0
    assert {k: v for k, v in other.items() if k != "pin_ring_tilt_um"} == \
        {k: v for k, v in build.items() if k != "pin_ring_tilt_um"}
