"""The diagnosis' simulation path (pipeline.diagnosis.simulate) and its verdicts (extension.py):
trigonometric interpolation against closed forms, content-keyed caches (never an object id), the
reading errors reusing the solved carrier, the record's condition passed to the TE model, a cause
held at its bound reported "beyond the stated range", a cause that does not explain its lines
not named.
"""
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

import pipeline.diagnosis.simulate as sim
from dynamics.records import BenchRecord
from geometry.params import load_case
from pipeline.diagnosis.bench import bench_records
from pipeline.diagnosis.diagnose import diagnose
from pipeline.diagnosis.extension import EXPLAINS_SHARE, Run, claimed_share
from pipeline.diagnosis.features import FeatureMap
from test_diagnose_machinery import STIFF as TOY_STIFF, toy_te

ROOT = Path(__file__).parents[1]
CASE = load_case(ROOT / "cases" / "rv40e-81.toml")


@pytest.fixture(autouse=True)
def _toy_compliance_is_crank_torsion(monkeypatch):
    from pipeline.diagnosis.causes import torsional_stiffness
    monkeypatch.setattr(torsional_stiffness, "located_component", lambda case, stiffness: ("crank_torsion", 1.0))


@pytest.mark.parametrize("n", [390, 256])
def test_trigonometric_interpolation_is_exact_below_nyquist(n):
    # x(phi) = sum a_k cos(2 pi k phi + b_k), k < n / 2: the interpolant at any phase equals it
    # to the upsampled linear step's error, (2 pi k / (64 n))^2 / 8 of each amplitude (< 3.1e-4)
    rng = np.random.default_rng(0)
    ks = np.array([k for k in (1, 3, 40, 78, 156) if k < n // 2 - 2] + [n // 2 - 2])
    a, b = rng.uniform(1, 5, ks.size), rng.uniform(-np.pi, np.pi, ks.size)
    f = lambda ph: np.sum(a[:, None] * np.cos(2 * np.pi * ks[:, None] * ph[None, :] + b[:, None]), axis=0)  # noqa: E731
    at = rng.uniform(-3.0, 3.0, 2000)
    err = np.abs(sim.trig_interp(f(np.arange(n) / n), at) - f(at)).max()
    assert err <= 3.1e-4 * a.sum()


def test_the_default_grid_is_stroboscopic_and_resolves_every_order_read():
    n = sim.default_points_per_rev(CASE)
    zp, zc = CASE.cycloid.zp, CASE.cycloid.zc
    assert (zp * zc) % n == 0 and n > 2 * sim.max_order(CASE)
    assert sim.max_order(CASE) >= 4 * zc + 2 * CASE.carrier.crank_count   # 156x and its crank sidebands


def test_the_stiffness_digest_follows_the_content_not_the_object():
    import dataclasses
    same = dataclasses.replace(TOY_STIFF, sources={"x": "another note"})
    assert sim.stiffness_digest(same) == sim.stiffness_digest(TOY_STIFF)
    other = dataclasses.replace(TOY_STIFF, crankshaft_torsional_stiffness_Nm_per_rad=2.0001e4)
    assert sim.stiffness_digest(other) != sim.stiffness_digest(TOY_STIFF)
    arr = dataclasses.replace(TOY_STIFF, pin_series=dataclasses.replace(
        TOY_STIFF.pin_series, groove_approach_m=TOY_STIFF.pin_series.groove_approach_m * 1.001))
    assert sim.stiffness_digest(arr) != sim.stiffness_digest(TOY_STIFF)


def test_reading_errors_load_no_part():
    # the carrier cache reuses a solve across cases that differ in READING_FIELDS only: valid
    # because no coupling reads them (the packed arrays are equal)
    from dynamics.couplings import build
    from dynamics.layout import DofLayout
    from support import stiffness_for_tests
    stiff = stiffness_for_tests(CASE)
    lay = DofLayout.standard(CASE.carrier.crank_count, CASE.cycloid.disc_count)
    read = CASE.with_errors(output_coaxiality_um=30.0, output_coaxiality_phase_deg=40.0,
                            output_reading_lobes=[[3, 2.0, 10.0]])
    a, _ = build(CASE, stiff, lay)
    b, _ = build(read, stiff, lay)
    for pa, pb in zip(a.couplings, b.couplings):
        for x, y in zip(pa, pb):
            assert np.array_equal(np.asarray(x), np.asarray(y))
    assert sim._mechanics(read) == sim._mechanics(CASE)


def test_a_reading_error_reuses_the_solved_carrier(monkeypatch):
    from support import stiffness_for_tests
    import dynamics.statics as dm
    stiff = stiffness_for_tests(CASE)
    calls = []
    real = dm.static_path
    monkeypatch.setattr(dm, "static_path", lambda *a, **k: calls.append(1) or real(*a, **k))
    sim._CARRIERS.clear()
    grid = sim.periodic_grid_deg(CASE, 64, 1)
    base = sim.quasi_static_te(CASE, stiff, grid, 200.0, 1)
    e, ph, r = 20.0, 30.0, CASE.carrier.output_flange_radius_mm
    te = sim.quasi_static_te(CASE.with_errors(output_coaxiality_um=e, output_coaxiality_phase_deg=ph), stiff, grid, 200.0, 1)
    assert len(calls) == 1
    # closed form: the reading adds (e / r) sin(theta_out + phi), theta_out the carrier angle
    th = np.radians(grid / CASE.ratio + base / 3600.0)
    assert te - base == pytest.approx(e * 1e-3 / r * np.sin(th + np.radians(ph)) * 206264.806, abs=1e-6)


def test_the_record_condition_reaches_the_te_model():
    rec = bench_records(toy_te, CASE, TOY_STIFF, [], seed=0, torque_fractions=(0.3,))[0]
    rec = BenchRecord(rec.path, rec.time_s, rec.input_angle_deg, rec.output_angle_deg, rec.output_torque_Nm,
                      rec.comments + ("oil_temperature_C: 40",))
    seen = []

    def te_model(case, stiffness, ang, torque, direction, condition=None):
        seen.append(condition)
        return toy_te(case, stiffness, ang, torque, direction)

    sim.simulate_record(te_model, CASE, TOY_STIFF, rec, 128)
    assert seen[0].oil_temperature_C == 40.0
    assert seen[0].input_speed_rpm == pytest.approx(CASE.operation.input_speed_rpm, rel=1e-3)
    # a five-argument model (condition-blind) still works
    sim.simulate_record(toy_te, CASE, TOY_STIFF, rec, 128)


def test_claimed_share_is_the_fall_of_the_claimed_lines():
    th = np.linspace(0.0, 360.0, 2048, endpoint=False)
    fm = FeatureMap(th, (1, 2))
    line = np.sin(np.radians(th))
    run = Run(CASE, None, [None], ["g"], [np.zeros_like(th)], None, None, [fm], np.ones(fm.size), 0.1)
    before, after = 2.0 * line + 0.5 * np.sin(np.radians(2 * th)), 0.5 * line + 0.5 * np.sin(np.radians(2 * th))
    # the cause claims 1x only (its effect there): its line falls from 2 to 0.5, 75 %; 2x is not its
    assert claimed_share(run, [0], [1.5 * line], [before], [after]) == pytest.approx(0.75, abs=1e-3)


def test_a_coaxiality_beyond_its_range_is_reported_at_its_bound():
    # 160 um at the flange (bound 100 um): named at the bound, beyond the stated range, never silent
    from pipeline.diagnosis.bench import HiddenEffect
    e, ph = 160.0, 25.0
    eff = HiddenEffect("output_coaxiality", (e * np.cos(np.radians(ph)), e * np.sin(np.radians(ph))))
    recs = bench_records(toy_te, CASE, TOY_STIFF, [eff], seed=3, samples_per_rev=2048)
    d = diagnose(CASE, TOY_STIFF, recs, toy_te, points_per_rev=256)
    assert d.cause == "output_coaxiality"
    assert d.extension is not None and "output_coaxiality" in d.extension.beyond_range
    mp = d.extension.model_parameters["output_coaxiality"]
    assert mp["coaxiality_cos_um"] == pytest.approx(100.0)                  # held at its bound
    assert mp["coaxiality_sin_um"] == pytest.approx(e * np.sin(np.radians(ph)), rel=0.05)
    assert any("beyond the stated range" in n for n in d.notes)
    assert "beyond the stated range" in d.findings[0].evidence
    assert d.extension.explained_share["output_coaxiality"] >= 0.2


def test_explains_share_threshold_is_stated():
    assert 0.0 < EXPLAINS_SHARE < 1.0


def test_a_seeded_path_is_the_same_equilibrium_and_foreign_seeds_are_ignored():
    """statics.static_path with seeds (a nearby model's states at the same angles, the fit's warm
    start) lands on the unseeded equilibria to the Newton tolerance (1e-6 arcsec here); seeds of
    another shape are not used."""
    from support import stiffness_for_tests
    import dynamics.statics as dm
    model = sim.model_for(CASE, stiffness_for_tests(CASE))
    th = np.radians(sim.periodic_grid_deg(CASE, 64, 1))
    T = np.full(th.shape, 0.3 * CASE.rated_torque_Nm)
    _, Q = dm.static_path(model, th, T, 1)
    cold, _ = dm.static_path(model, th, 1.05 * T, 1)
    seeded, _ = dm.static_path(model, th, 1.05 * T, 1, seeds=Q)
    foreign, Qf = dm.static_path(model, th, 1.05 * T, 1, seeds=Q[:, :-1])
    arcsec = 206264.806
    assert np.max(np.abs(seeded - cold)) * arcsec < 1e-6
    assert np.array_equal(foreign, cold)
    assert np.array_equal(Qf[:, model.i_out], foreign)


def test_the_stiffness_digest_is_by_content_and_remembered_per_object():
    from support import stiffness_for_tests
    a, b = stiffness_for_tests(CASE), stiffness_for_tests(CASE)
    assert a is not b and sim.stiffness_digest(a) == sim.stiffness_digest(b) == sim.stiffness_digest(a)
    assert sim._DIGESTS[id(a)][0] is a


def test_seeds_follow_the_last_model_solved_on_a_grid_and_only_inside_a_run():
    """Inside `seeding()` each grid's seeds are the states of the last model solved there (the fit's
    next column or step starts from its neighbour); outside it nothing is kept."""
    key_a, key_b = ("case", "digest A", "grid", 1, None), ("case", "digest B", "grid", 1, None)
    qa, qb = np.zeros((3, 2)), np.ones((3, 2))
    sim._seeded(key_a, (np.zeros(3), qa))
    assert sim._seeds_for(key_a) is None
    with sim.seeding():
        sim._seeded(key_a, (np.zeros(3), qa))
        assert sim._seeds_for(key_b) is qa           # the same grid: another model's states
        sim._seeded(key_b, (np.zeros(3), qb))
        assert sim._seeds_for(key_a) is qb
    assert sim._seeds_for(key_a) is None


def test_a_record_s_condition_puts_the_carrier_drag_on_the_mechanism_not_on_the_reading():
    """quasi_static_te at a record's condition solves the statics under load + the carrier's drag at
    that speed and oil temperature (resisting the motion: + forward, - backward, in the record's
    sign convention of solve_static); without a
    condition it is the frictionless model at the load alone. A temperature outside the
    lubricant's range is the one-line error."""
    from dynamics.losses import Lubricant
    from dynamics.losses.contacts import carrier_drag_Nm
    from dynamics.statics import solve_static
    from tests.support import stiffness_for_tests
    stiff = stiffness_for_tests(CASE)
    model = sim.model_for(CASE, stiff)
    ang = np.array([10.0, 200.0])
    cond = sim.Condition(1500.0, 40.0)
    drag = carrier_drag_Nm(CASE, Lubricant.from_section(CASE.lubrication), 1500.0, 40.0)
    assert sim.carrier_drag(CASE, cond) == pytest.approx(drag) and drag > 0.5
    assert sim.carrier_drag(CASE, None) == 0.0
    for d, T in ((1, 100.0), (-1, -100.0), (1, 0.0)):
        te = sim.quasi_static_te(CASE, stiff, d * ang, T, d, cond)
        want = [solve_static(model, a, T + d * drag, None, d).te_arcsec for a in d * ang]
        assert np.allclose(te, want, atol=1e-6)
        bare = sim.quasi_static_te(CASE, stiff, d * ang, T, d)
        assert np.allclose(bare, [solve_static(model, a, T, None, d).te_arcsec for a in d * ang], atol=1e-6)
    with pytest.raises(Exception, match="oil temperature"):
        sim.quasi_static_te(CASE, stiff, ang, 100.0, 1, sim.Condition(1500.0, 500.0))


def test_library_tangents_predict_a_column_s_first_solves_and_change_no_equilibrium():
    """simulate.seed_tangents: before a fit has taken a Jacobian column, its predictor on each grid is
    coef x (the library's unit model's states - the base's), both as solved in the run; a column
    solved from it (tangent_seeds) lands on the cold solve's equilibria to the Newton tolerance
    (1e-6 arcsec). A predictor the fit already has is kept; outside a run nothing is set."""
    from support import stiffness_for_tests
    from pipeline.diagnosis.causes.backlash import CAUSE as backlash
    stiff = stiffness_for_tests(CASE)
    rec = bench_records(toy_te, CASE, TOY_STIFF, [], seed=0, torque_fractions=(0.3,))[0]
    n = 64
    unit = backlash.apply(CASE, stiff, np.array([backlash.unit_size]))
    column = backlash.apply(CASE, stiff, np.array([0.3 * backlash.unit_size]))
    tag = ("backlash", 0)
    assert sim.seed_tangents(CASE, stiff, [rec], n, {tag: [(0.3, unit)]}) == 0     # no run: nothing kept
    cold = sim.simulate_record(sim.quasi_static_te, *column, rec, n)
    sim._CARRIERS.clear()
    with sim.seeding():
        sim.simulate_record(sim.quasi_static_te, CASE, stiff, rec, n)
        sim.simulate_record(sim.quasi_static_te, *unit, rec, n)
        assert sim.seed_tangents(CASE, stiff, [rec], n, {tag: [(0.3, unit)]}) == 1
        d, cond = rec.direction, sim.record_condition(rec)
        ang = sim.periodic_grid_deg(CASE, n, d)
        T = np.full(ang.shape, sim.mechanism_torque(CASE, np.float64(rec.torque_Nm), d, cond))
        kb = sim._carrier_key(CASE, stiff, ang, T, d, cond)[0]
        ku = sim._carrier_key(*unit, ang, T, d, cond)[0]
        step = sim._STEPS[(tag, kb[2:])]
        np.testing.assert_allclose(step, 0.3 * (sim._STATES[ku] - sim._STATES[kb]))
        assert np.any(step != 0.0)
        assert sim.seed_tangents(CASE, stiff, [rec], n, {tag: [(0.7, unit)]}) == 0   # kept, not replaced
        with sim.tangent_seeds(CASE, stiff, tag):
            kc = sim._carrier_key(*column, ang, T, d, cond)[0]
            start, _ = sim._seeds_for(kc)
            np.testing.assert_allclose(start, sim._STATES[kb] + step)
            warm = sim.simulate_record(sim.quasi_static_te, *column, rec, n)
    sim._CARRIERS.clear()
    assert np.max(np.abs(warm - cold)) < 1e-6


def test_a_refit_after_a_drop_gets_what_the_first_fit_left_of_the_budget(monkeypatch):
    """extension.extend: the evaluation budget is the extension's; a refit after a drop gets the rest,
    at least REFIT_MIN_NFEV, and the first fit the whole of it."""
    import pipeline.diagnosis.extension as X

    class C:
        def __init__(self, cid):
            self.id = cid
    a, b = C("a"), C("b")
    budgets = []

    def fake_fit(run, chosen, cols, fit_idx, hold_idx, max_nfev, warm=None):
        budgets.append(max_nfev)
        reasons = {c.id: ("below the noise floor" if c is b and len(budgets) == 1 else None) for c in chosen}
        return SimpleNamespace(beyond_range=None), None, reasons, "", ({}, np.zeros(0)), spent[len(budgets) - 1]
    monkeypatch.setattr(X, "_fit", fake_fit)
    monkeypatch.setattr(X, "_unidentifiable", lambda *a, **k: [])
    for spent, want in (([8, 3], [8, 2]), ([5, 3], [8, 3]), ([12, 3], [8, 2])):
        budgets.clear()
        ext, _, notes, dropped = X.extend(None, [a, b], {}, [0], [], 8)
        assert budgets == want and dropped == ["b"] and any("b: below the noise floor" in n for n in notes)
    assert X.REFIT_MIN_NFEV >= 1


def test_a_batch_of_models_skips_the_ones_the_geometry_refuses():
    """extension._prefetch_valid: a maker raising ValueError (a CaseError) is left to its caller; the
    rest go to the workers as one batch, each with no tangent."""
    from pipeline.diagnosis.extension import _prefetch_valid
    seen = []

    def bad():
        raise ValueError("E zp >= R")
    _prefetch_valid(seen.extend, [lambda: ("c1", "s1"), bad, lambda: ("c2", "s2")])
    assert seen == [("c1", "s1", None), ("c2", "s2", None)]
    _prefetch_valid(None, [bad])        # no workers: nothing made, nothing raised


def test_a_lazy_batch_caches_each_model_when_asked_and_in_order(monkeypatch):
    """simulate.prefetch_models(lazy=True): every grid is submitted at once, model by model as the
    generator builds them; ready(i) caches models 0..i in the order given, as the eager call does."""
    from concurrent.futures import Future
    monkeypatch.setattr(sim, "_steady_grids", lambda case, stiffness, records, n: (
        (("k", case, r), case, np.zeros(2), np.zeros(2), 1, None) for r in records))
    monkeypatch.setattr(sim, "_CARRIERS", {})

    class Pool:                          # resolves at submit; records what went and when
        def __init__(self):
            self.sent = []

        def submit(self, fn, mech, *rest):
            self.sent.append((mech, len(built)))
            f = Future()
            f.set_result((np.full(2, float(len(self.sent))), None))
            return f
    built = []

    def models():
        for i in range(3):
            built.append(i)
            yield f"m{i}", None, None
    pool = Pool()
    ready = sim.prefetch_models(models(), ["r1", "r2"], 4, pool, lazy=True)
    # each model's two grids left as soon as it was built, before the next one was
    assert pool.sent == [("m0", 1), ("m0", 1), ("m1", 2), ("m1", 2), ("m2", 3), ("m2", 3)]
    assert not sim._CARRIERS
    ready(0)
    assert list(sim._CARRIERS) == [("k", "m0", "r1"), ("k", "m0", "r2")]
    ready(2)
    assert [k[1] for k in sim._CARRIERS] == ["m0", "m0", "m1", "m1", "m2", "m2"]
    assert np.array_equal(sim._CARRIERS[("k", "m1", "r2")], np.full(2, 4.0))
    ready()
    assert len(sim._CARRIERS) == 6
    sim._CARRIERS.clear()                # eager: all cached on return, the same entries
    assert sim.prefetch_models(models(), ["r1", "r2"], 4, Pool()) is None and len(sim._CARRIERS) == 6


def test_the_jacobian_waits_for_each_column_just_before_its_difference():
    """extension._jacobian: the columns' models go out as one lazy batch; column i's difference
    waits only for column i (the workers solve the later ones meanwhile); J is the forward secant."""
    from pipeline.diagnosis.extension import _jacobian
    log = []

    def prefetch(models, lazy=False):
        log.append(("submit", len(list(models)), lazy))
        return lambda i=None: log.append(("ready", i))

    def fun(x):
        log.append(("fun", tuple(np.round(x, 6))))
        return np.array([x[0] ** 2, 3.0 * x[1]])
    jac = _jacobian(fun, np.zeros((2, 2)), [(0, 2, 0.5)], lambda x: ("case", "stiff"), tag=("a", "b"),
                    prefetch=prefetch)
    J = jac(np.array([1.0, 2.0]))
    assert log == [("fun", (1.0, 2.0)), ("submit", 2, True), ("ready", 0), ("fun", (1.5, 2.0)),
                   ("ready", 1), ("fun", (1.0, 2.5))]
    assert np.allclose(J, [[2.5, 0.0], [0.0, 3.0]])
