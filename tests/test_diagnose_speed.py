"""The diagnosis' cost cuts give the same results: a Jacobian column's predicted warm start
(simulate.tangent_seeds), the fallback seeds of statics.static_path and the per-record facts."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import dynamics.statics as dm
import pipeline.diagnosis.simulate as sim
from geometry.params import load_case
from pipeline.diagnosis import causes as registry

ROOT = Path(__file__).resolve().parents[1]
CASE = load_case(ROOT / "cases" / "rv40e-81.toml")
ARCSEC = 206264.806


def _stiffness():
    from support import stiffness_for_tests
    return stiffness_for_tests(CASE)


def test_fallback_seeds_are_tried_where_the_seeds_fail_and_give_the_same_equilibria(monkeypatch):
    model = sim.model_for(CASE, _stiffness())
    th = np.radians(sim.periodic_grid_deg(CASE, 64, 1))
    T = np.full(th.shape, 0.3 * CASE.rated_torque_Nm)
    _, Q = dm.static_path(model, th, T, 1)
    cold, _ = dm.static_path(model, th, 1.05 * T, 1)
    seeded, _ = dm.static_path(model, th, 1.05 * T, 1, seeds=Q)
    bad = Q.copy()
    bad[:, model.i_out] += 3 * 2 * np.pi / CASE.cycloid.zp    # three teeth on: off the branch everywhere
    import dynamics.kernels as kn
    real, calls = kn.static_seeded, []

    def counted(*a):
        out = real(*a)
        calls.append(int(out[1].sum()))
        return out
    monkeypatch.setattr(kn, "static_seeded", counted)
    rescued, _ = dm.static_path(model, th, 1.05 * T, 1, seeds=bad, fallback_seeds=Q)
    assert calls == [0, len(th)]                              # every point taken from the fallback
    monkeypatch.undo()
    only, _ = dm.static_path(model, th, 1.05 * T, 1, fallback_seeds=Q)
    assert np.max(np.abs(rescued - cold)) * ARCSEC < 1e-6
    assert np.array_equal(rescued, seeded)
    assert np.array_equal(only, seeded)                       # fallback alone: used as the seeds
    foreign, _ = dm.static_path(model, th, 1.05 * T, 1, fallback_seeds=Q[:, :-1])
    assert np.array_equal(foreign, cold)


def test_a_jacobian_column_starts_from_its_predictor_and_lands_on_the_same_equilibria():
    """Inside seeding(), a column solved under tangent_seeds(base, tag) records its state change;
    at the next iterate the same column starts from base states + that change (last model's states
    as the fallback), and its TE equals a cold solve's to the Newton tolerance."""
    stiff = _stiffness()
    cause = registry.get("backlash")
    grid = sim.periodic_grid_deg(CASE, 64, 1)
    T = 0.3 * CASE.rated_torque_Nm
    h = 0.3 * cause.unit_size

    def case_at(p):
        return cause.apply(CASE, stiff, np.array([p]))[0]

    sim._CARRIERS.clear()
    with sim.seeding():
        for p in (1.0, 1.2):
            base = case_at(p)
            sim.quasi_static_te(base, stiff, grid, T, 1)
            key = sim._carrier_key(case_at(p + h), stiff, grid, np.full(grid.shape, T), 1, None)[0]
            with sim.tangent_seeds(base, stiff, ("backlash", 0)):
                seeds = sim._seeds_for(key)
                te = sim.quasi_static_te(case_at(p + h), stiff, grid, T, 1)
            assert isinstance(seeds, tuple) == (p == 1.2)     # a predictor once the step is known
        assert ("backlash", 0) in {k[0] for k in sim._STEPS}
    assert not sim._STATES and not sim._STEPS                 # nothing kept after the run
    model = sim.model_for(case_at(1.2 + h), stiff)
    carrier, _ = sim._carrier_deg(model, grid, np.full(grid.shape, T), 1)
    cold = (np.rad2deg(model.measured_output_rad(np.deg2rad(carrier))) - grid / model.ratio) * 3600.0
    assert np.max(np.abs(te - cold)) < 1e-6
    with sim.tangent_seeds(CASE, stiff, ("backlash", 0)):     # outside a run: no effect
        assert sim._seeds_for(key) is None


def test_a_records_median_torque_spread_and_speed_are_its_own_and_computed_once():
    from dynamics.records import BenchRecord
    n = 2001
    t = np.linspace(0.0, 10.0, n)
    th_in = 6.0 * 486.0 * t
    r = BenchRecord("r", t, th_in, th_in / CASE.ratio, np.full(n, 300.0) + np.linspace(0, 1, n), ())
    assert r.torque_spread_Nm == float(np.subtract(*np.percentile(r.output_torque_Nm, [95, 5])))
    assert r.torque_Nm == float(np.median(r.output_torque_Nm))
    assert r.input_speed_rpm == pytest.approx(486.0, rel=1e-9)
    assert {"torque_Nm", "torque_spread_Nm", "input_speed_rpm"} <= set(vars(r))    # cached on the record
    assert sim.record_condition(r) == sim.Condition(486.0, None)


def test_re_taken_columns_are_kept_while_no_coordinate_moved_half_a_step_and_re_taken_beyond():
    from pipeline.diagnosis.extension import REUSE_SHARE, _jacobian
    calls = []

    def fun(x):                          # a nonlinear residual whose Jacobian changes with x
        calls.append(x.copy())
        return np.array([x[0] ** 2 + x[1], np.sin(x[1]) + 3.0 * x[2], x[2] ** 3])

    h = 0.3
    J0 = np.eye(3)                       # library columns: column 2 is never re-taken
    jac = _jacobian(fun, J0, [(0, 2, h)])
    x = np.array([1.0, 0.5, 2.0])
    J1 = jac(x)
    assert len(calls) == 3               # f(x) and one forward difference per re-taken column
    assert J1[0, 0] == pytest.approx((1.3 ** 2 - 1.0) / h) and np.array_equal(J1[:, 2], J0[:, 2])
    # every re-taken coordinate within REUSE_SHARE h (the free column 2 may move at will): kept
    near = x + np.array([0.99 * REUSE_SHARE * h, -0.99 * REUSE_SHARE * h, 5.0])
    assert jac(near) is J1 and len(calls) == 3
    # one re-taken coordinate beyond it: re-taken at the new point
    far = x + np.array([0.0, 1.01 * REUSE_SHARE * h, 0.0])
    J2 = jac(far)
    assert len(calls) == 6 and J2[1, 1] == pytest.approx((np.sin(far[1] + h) - np.sin(far[1])) / h)
