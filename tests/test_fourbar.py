"""Four-bar original-error model (paper 000): closure, sensitivities, rigid vs elastic, CLI."""
from __future__ import annotations

import csv
import math
from pathlib import Path

import numpy as np
import pytest

from dynamics import fourbar as fb
from fem.stiffness import save
from geometry.params import load_case
from support import stiffness_for_tests   # closed-form stand-in for stiffness.json (tests/support.py)

ROOT = Path(__file__).resolve().parents[1]
CASE = ROOT / "cases" / "rv40e-105.toml"
A = fb.ARCSEC_PER_RAD
RAD90 = math.pi / 2


@pytest.fixture(scope="module")
def case():
    return load_case(CASE)


@pytest.fixture(scope="module")
def geom(case):
    return fb.PairGeometry.from_case(case)


@pytest.fixture(scope="module")
def compliance(case):
    return fb.JointCompliance.from_stiffness(stiffness_for_tests(case))


@pytest.fixture(scope="module")
def loads(case, geom):
    return fb.statics_pair_loads(case, geom, RAD90, case.rated_torque_Nm)


def test_the_ground_link_is_the_chord_between_two_of_three_cranks(geom):
    # 3 cranks on r = 36 mm (case file): l4 = 2 r sin(60 deg) = 36 sqrt(3)
    assert geom.spacing_mm == pytest.approx(36 * math.sqrt(3), rel=1e-12)


@pytest.mark.parametrize("beta1_deg", [10.0, 45.0, 90.0, 150.0, 200.0, 300.0])
def test_zero_error_sources_give_zero_rigid_error(geom, beta1_deg):
    r = fb.output_error(geom, fb.Build(), math.radians(beta1_deg))
    # factored parallelogram residual: exactly zero, not merely small
    assert r.output_error_rad == 0.0 and r.quadratic_error_rad == 0.0


@pytest.mark.parametrize("e, L", [(1.3, 62.35), (3.0, 40.0), (0.5, 120.0)])
def test_a_pure_parallelogram_keeps_the_coupler_parallel_on_the_exact_closure(e, L):
    beta1 = np.radians(np.linspace(1, 359, 181))
    ex = fb.closure_exact(e, L, e, L, beta1)
    assert np.max(np.abs(ex.open_rad)) < 1e-15
    # crossed branch of an anti-parallelogram: tan(beta2/2) = -e sin b1 / (L - e cos b1)
    # (from (C - A) t + 2B = 0 with A + C = 0)
    want = 2 * np.arctan(-e * np.sin(beta1) / (L - e * np.cos(beta1)))
    assert np.allclose(ex.crossed_rad, want, rtol=0, atol=1e-14)


def test_exact_closure_satisfies_the_loop_equation(geom):
    rng = np.random.default_rng(3)
    l1, l3 = 1.3 + rng.uniform(-0.1, 0.1, (2, 50))
    l2, l4 = geom.spacing_mm + rng.uniform(-0.1, 0.1, (2, 50))
    b1 = rng.uniform(0.3, 2.8, 50)
    b2 = fb.closure_exact(l1, l2, l3, l4, b1).open_rad
    loop = lambda b: np.hypot(l1 * np.cos(b1) + l2 * np.cos(b) - l4, l1 * np.sin(b1) + l2 * np.sin(b)) - l3
    ok = np.isfinite(b2)
    assert np.max(np.abs(loop(b2)[ok])) < 1e-12   # mm: round-off of ~60 mm lengths
    # nan = the free rocker cannot reach this crank angle: no root anywhere near the parallelogram
    grid = np.linspace(-0.3, 0.3, 60001)[:, None]
    assert np.all(loop(grid)[:, ~ok] > 0) and ok.sum() >= 40


def test_a_small_perturbation_matches_the_linearised_sensitivity(geom):
    L, e = geom.spacing_mm, geom.eccentricity_mm
    # closed form at the parallelogram, beta1 = 90 deg: d beta2/d(l1..l4) = (-1/L, 0, 1/L, 0)
    s = fb.closure_sensitivity(e, L, e, L, RAD90)
    assert np.allclose(s, [-1 / L, 0, 1 / L, 0], rtol=0, atol=1e-15)
    # and at a generic point, central differences agree to O(h^2) (h = 1e-6 mm: ~1e-9 relative)
    x0 = np.array([1.35, L - 0.03, 1.28, L + 0.05])
    b1 = math.radians(70.0)
    s = fb.closure_sensitivity(*x0, b1)
    h = 1e-6
    for k in range(4):
        dx = np.zeros(4)
        dx[k] = h
        fd = (fb.closure_exact(*(x0 + dx), b1).open_rad - fb.closure_exact(*(x0 - dx), b1).open_rad) / (2 * h)
        assert fd == pytest.approx(s[k], rel=1e-6, abs=1e-9)


def test_one_crank_eccentric_error_turns_the_disc_by_dl_over_l_at_90_deg(geom):
    d = 0.01
    r = fb.output_error(geom, fb.Build(d_l1_mm=d), RAD90)
    # first order: output error = -beta2 = +d/L; second order relative O(d/e) ~ 1e-2
    assert float(r.output_error_rad) == pytest.approx(d / geom.spacing_mm, rel=2e-2)


def test_quadratic_small_root_departs_from_the_exact_closure_at_third_order_in_beta2(geom):
    # the quadratic is the closure expanded to second order in beta2: gap = O(beta2^3)
    d = np.array([0.0025, 0.005, 0.01, 0.02])
    r = fb.output_error(geom, fb.Build(d_l4_mm=d), math.radians(10.0))   # first order in d off 90 deg
    gap = np.abs(r.output_error_rad - r.quadratic_error_rad)
    slope = np.polyfit(np.log(np.abs(r.output_error_rad)), np.log(gap), 1)[0]
    assert slope == pytest.approx(3.0, abs=0.15)
    at90 = fb.output_error(geom, fb.Build(d_l4_mm=0.1), RAD90)
    assert abs(float(at90.output_error_rad - at90.quadratic_error_rad)) * A < 1e-6


@pytest.mark.parametrize("source, paper", [
    ("eccentricity_common", (0.0333, 0.0389)), ("crank_hole", (0.036058, 0.036111)),
    ("output_hole", (0.036008, 0.036123))])
def test_paper_000_prints_the_crossed_root_in_radians_with_l4_72mm(source, paper):
    # paper 000's rigid ranges, reproduced to their printed digits by |crossed quadratic root| [rad]
    g72 = fb.PairGeometry(1.3, 72.0, 36.0, 2, 0.0)
    dev = np.linspace(-0.1, 0.1, 201)
    q = fb.output_error(g72, fb.with_source(fb.Build(), source, dev), RAD90).paper_quantity_rad
    digits = len(str(paper[0]).split(".")[1])
    assert (round(float(q.min()), digits), round(float(q.max()), digits)) == paper


def test_statics_loads_carry_the_output_torque(case, geom, loads):
    # tangential forces on the crank circle give back the disc's torque share; disc 1 + 2
    cr = fb.crank_positions_mm(geom.crank_circle_radius_mm, 3)[:2]
    f_carrier = loads.support_N @ np.array([[math.cos(geom.ground_angle_rad), -math.sin(geom.ground_angle_rad)],
                                            [math.sin(geom.ground_angle_rad), math.cos(geom.ground_angle_rad)]]).T
    torque = -np.sum(cr[:, 0] * f_carrier[:, 1] - cr[:, 1] * f_carrier[:, 0]) * 1e-3
    assert torque == pytest.approx(2 / 3 * case.rated_torque_Nm, rel=1e-9)   # 2 of 3 cranks


def test_elastic_error_lags_the_rigid_error_under_positive_load(geom, loads, compliance):
    dev = np.linspace(-0.1, 0.1, 21)
    base = fb.Build(turning_arm_clearance_mm=(0.005, 0.005), support_clearance_mm=(0.002, 0.002))
    for s in fb.MAIN_SOURCES:
        re = fb.rigid_and_elastic(geom, fb.with_source(base, s, dev), loads, compliance)
        lag_rigid, lag_elastic = -re.rigid.output_error_rad, -re.elastic.output_error_rad
        assert np.all(lag_elastic >= lag_rigid), s
    nominal = fb.rigid_and_elastic(geom, fb.Build(), loads, compliance)
    assert float(nominal.rigid.output_error_rad) == 0.0
    assert abs(float(nominal.elastic.output_error_rad)) > 0.0


def test_elastic_windup_grows_with_torque(case, geom, compliance):
    lags = [-float(fb.rigid_and_elastic(geom, fb.Build(), fb.statics_pair_loads(case, geom, RAD90, t),
                                        compliance).elastic.output_error_rad) for t in (100, 200, 400)]
    assert 0 < lags[0] < lags[1] < lags[2]


def test_windup_equals_the_tangential_shift_over_the_crank_radius(case, geom, compliance):
    # equal clearance c at both cranks, no load-dependent part: at 90 deg the free-rocker four-bar
    # turns the disc by the difference of the crank-direction components, which for the tangential
    # shift of the torque path is (c_t / r_c) to first order (rigid rotation about the centre)
    c = 0.005
    loads = fb.PairLoads(np.zeros((2, 2)), np.zeros((2, 2)), 0.0, RAD90, "test")
    cr = fb.crank_positions_mm(geom.crank_circle_radius_mm, 3)[:2]
    tang = geom.to_pair_frame(np.stack([-cr[:, 1], cr[:, 0]], -1) / geom.crank_circle_radius_mm)
    loads = fb.PairLoads(-tang * 1000.0, np.zeros((2, 2)), 1.0, RAD90, "pure torque")
    r = fb.output_error(geom, fb.Build(), RAD90,
                        fb.joint_displacements_mm(fb.Build(turning_arm_clearance_mm=(c, c)), loads, None))
    assert -float(r.output_error_rad) == pytest.approx(c / geom.crank_circle_radius_mm, rel=1e-3)


def test_unknown_source_names_the_allowed_ones():
    with pytest.raises(fb.FourBarError, match="allowed: eccentricity"):
        fb.with_source(fb.Build(), "pin_radius", 0.1)


def test_fourbar_command_writes_the_contract_files(tmp_path, case):
    from pipeline.cli import main
    stiff = tmp_path / "stiffness.json"
    save(stiffness_for_tests(case), stiff)
    out = tmp_path / "fb"
    assert main(["fourbar", "--case", str(CASE), "--out", str(out), "--stiffness", str(stiff),
                 "--points", "11", "--quiet"]) == 0
    with (out / "individual.csv").open() as fh:
        rows = list(csv.reader(fh))
    assert rows[0] == ["source", "deviation_mm", "rigid_error_deg", "elastic_error_deg"]
    assert {r[0] for r in rows[1:]} >= set(fb.MAIN_SOURCES)
    for a, b in fb.PAIRS:
        assert (out / f"combined_{a}_{b}.csv").stat().st_size > 0
        assert (out / f"surface_{a}_{b}.png").stat().st_size > 10_000
    assert "paper 000" in (out / "comparison.md").read_text()


def test_missing_stiffness_is_one_clear_line(tmp_path, capsys):
    from pipeline.cli import main
    assert main(["fourbar", "--case", str(CASE), "--out", str(tmp_path), "--stiffness",
                 str(tmp_path / "nope.json"), "--quiet"]) == 2
    assert "nope.json: not found" in capsys.readouterr().err
