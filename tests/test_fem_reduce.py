"""The FEM stage's reduction to rv-stiffness/4: load ranges that hold the lumped model's forces up
to the catalog momentary torque, the support bearing entry, the crank bending blocks, and the
closed-form test stand-in (tests/support.py) that the dynamics tests run on."""
import math
import time

import numpy as np
import pytest

from fem import crank_tilt as ct
from fem.tapered_roller import crank_support_positions_m
from fem import stiffness
from fem import tapered_roller as tr
from fem.reduce import LOAD_MARGIN, needle_force_classical_N, table_loads_N
from geometry.params import CaseError, load_case
from tests.support import case_path, model_for_tests, stiffness_for_tests


@pytest.mark.parametrize("name", ["rv40e-81", "rv160n-81"])
def test_the_tables_hold_the_models_largest_pin_and_needle_forces_at_the_momentary_torque(name):
    # static solves at 12 input angles over one pin pitch of the output (the pattern's period);
    # measured largest force / classical estimate: pins 1.46, 1.37, needles 1.37, 1.37 (LOAD_MARGIN 1.8)
    from dynamics.statics import solve_static
    model = model_for_tests(name)
    case = model.case
    T = case.operation.momentary_torque_Nm
    tables = table_loads_N(case)
    pin, needle = 0.0, 0.0
    for a in np.linspace(0.0, 360.0 * case.ratio / case.cycloid.zp, 12, endpoint=False):
        s = solve_static(model, a, T)
        pin = max(pin, float(s.pin_force_N.max()))
        needle = max(needle, float(np.linalg.norm(s.bearing_force_N, axis=-1).max()))
    assert pin < tables["pin"][-1] and needle < tables["needle"][-1]
    # and the tables are not vastly oversized: the model uses more than half of each
    assert pin > 0.5 * tables["pin"][-1] and needle > 0.5 * tables["needle"][-1]


def test_the_needle_estimate_adds_the_pin_resultant_to_the_tangential_share():
    case = load_case(case_path("rv40e-81"))
    # tangential 0.55 T / (3 a) = 2098 N at 412 N m; resultant 0.55 T / (zc e) / 3 = 1490 N
    t, r = 0.55 * 412.0 / (3 * 0.036), 0.55 * 412.0 / (39 * 1.3e-3) / 3
    assert needle_force_classical_N(case, 412.0) == pytest.approx(math.hypot(t, r), rel=1e-12)
    assert table_loads_N(case)["needle"][-1] == pytest.approx(LOAD_MARGIN * needle_force_classical_N(case, 2058.0))


def test_a_momentary_torque_not_above_the_rated_one_is_refused_naming_the_key():
    case = load_case(case_path("rv40e-81"))
    with pytest.raises(CaseError, match=r"\[operation\] momentary_torque_Nm = 412: .*allowed > 412"):
        case.replace("operation", momentary_torque_Nm=412.0)


@pytest.mark.parametrize("name, designation", [("rv40e-81", "30203"), ("rv160n-81", "32006X")])
def test_each_case_holds_a_standard_bearing_on_journals_sized_to_it(name, designation):
    case = load_case(case_path(name))
    b = tr.select_bearing(case.crankshaft.journal_radius_mm, tr.case_envelope(case))
    assert b.designation == designation
    assert case.crankshaft.journal_radius_mm == b.d_mm / 2 and case.crankshaft.journal_length_mm == b.T_mm


def test_the_support_entry_is_the_tangent_of_its_curve_at_the_operating_load():
    case = load_case(case_path("rv40e-81"))
    r = tr.case_support_bearings(case, 20000.0)
    op = r["operating_load_N"]
    ld = tr.crank_support_load_N(case, 412.0)
    assert op == pytest.approx(math.hypot(ld["radial_N"], ld["couple_N"]))
    assert r["setup"].preload_N == pytest.approx(0.5 * op / r["bearing"].Y)
    # the tangent is the curve's own slope: a central difference of two nearby solves
    su = r["setup"]
    u = [tr.solve_pair(su, 2 * F).q[0] for F in (0.999 * op, 1.001 * op)]
    assert r["stiffness_N_per_m"] == pytest.approx(0.002 * op / (u[1] - u[0]), rel=0.01)
    assert np.all(np.diff(r["deflection_m"]) > 0) and r["load_N"][-1] == pytest.approx(20000.0)
    # checks: the preloaded pair at zero load is its linearised closed form; without preload the
    # pair is Palmgren-Stribeck (measured 0.3 %)
    assert abs(r["check"]["preloaded_error"]) < 1e-3 and abs(r["check"]["unpreloaded_error"]) < 0.02


def test_the_crank_blocks_carry_statics_and_the_two_planes_averaged():
    case = load_case(case_path("rv40e-81"))
    beam = ct.beam_flexibility(case)
    C, J = ct.two_eccentric_blocks(beam)
    assert C == pytest.approx(C.T) and C[0, 0] > C[0, 1] > 0
    # the eccentrics sit symmetrically about mid-span: C11 = C22, J1 takes eccentric 1's larger share
    assert C[0, 0] == pytest.approx(C[1, 1], rel=1e-9)
    assert np.all(J > 0) and J.sum(axis=0) == pytest.approx([1.0, 1.0])
    zm = (case.crankshaft.support_span_mm / 2 - case.cycloid.width_mm / 2) * 1e-3   # eccentric 1's mid-plane
    (s1, s2), _ = crank_support_positions_m(case)          # pinned at the pressure centres (statics)
    assert J[:, 0] == pytest.approx([(s2 - zm) / (s2 - s1), (zm - s1) / (s2 - s1)], rel=1e-6)
    # the journal order is the carrier's seat order read through SEAT_OF_JOURNAL: J1 (z = 0, planet
    # side) sits in the end plate (seat 1), J2 in the flange (seat 0)
    assert stiffness.SEAT_OF_JOURNAL == (1, 0)
    # elastic supports add tilt: a bearing compliance raises the slope per newton
    s0 = ct.eccentric_slope_per_N(case, beam)
    s1 = ct.eccentric_slope_per_N(case, ct.with_elastic_supports(beam, 2e-9))
    assert 0 < s0 < s1


@pytest.mark.parametrize("name", ["rv40e-81", "rv160n-81"])
def test_the_test_stand_in_is_fast_complete_and_survives_the_schema(tmp_path, name):
    case = load_case(case_path(name))
    t0 = time.perf_counter()
    m = stiffness_for_tests(case)
    assert time.perf_counter() - t0 < 1.0
    assert "TEST STAND-IN" in m.sources["all"]
    m.check(name)
    stiffness.save(m, tmp_path / "s.json")
    back = stiffness.load(tmp_path / "s.json", case)
    assert np.array_equal(back.carrier.compliance_m_per_N, m.carrier.compliance_m_per_N)
    assert back.support_bearings.designation == m.support_bearings.designation
    # the stand-in carrier turns the end plate's seats rigidly: rank one, flange seats rigid
    Cc = m.carrier.compliance_m_per_N
    assert np.linalg.matrix_rank(Cc, tol=1e-9 * np.abs(Cc).max()) == 1 and np.all(Cc[0:2] == 0)
