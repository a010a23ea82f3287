"""The housing (pin ring) FE, fem.housing: closed forms, convergence, reciprocity, the bolt pattern.

Tolerances: the annulus checks 1 % (the brief's, P2 at 2-3 elements across a 2 mm band already gives
< 0.1 %); reciprocity 1e-6 relative (C = G K^-1 G^T from separate solves, not symmetrised);
equilibrium 1e-9 of the load; the bolt pattern's rotation invariance 1e-3 of max |C| (the mesh is
not symmetric: this is its discretisation error, measured 1e-4 at the default mesh, 7e-4 at the
tests' coarse one); lobes off the pattern below 0.5 % of the largest (the same asymmetry).
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from fem import housing, housing_checks
from geometry.params import CaseError, load_case

ROOT = Path(__file__).resolve().parents[1]
COARSE_M = 2e-3          # groove element size of the quick tests (the default is Rr / 3 = 1 mm on the RV-40E)


@pytest.fixture(scope="module")
def case():
    return load_case(ROOT / "cases" / "rv40e-81.toml")


@pytest.fixture(scope="module")
def fe(case):
    return housing.housing_for_case(case, h_m=COARSE_M, checks=False)


def test_a_plain_annulus_fixed_outside_matches_lame_within_1_percent():
    r = housing_checks.lame_fixed_outer(a=64e-3, b=95e-3, h=3e-3)
    assert abs(r["error"]) < 0.01, r
    # and the closed form itself: a thin ring (b -> a) barely moves, a wide one tends to the hole in a plate
    assert housing_checks.lame_fixed_outer_m(0.1, 0.1001, 1e6, 206e9, 0.3) < 1e-3 * 1e6 * 0.1 / 206e9
    assert housing_checks.lame_fixed_outer_m(0.01, 100.0, 1e6, 206e9, 0.3) == pytest.approx(
        1e6 * 0.01 * 1.3 / 206e9, rel=1e-6)


def test_a_clamped_annulus_in_torsion_matches_the_closed_form_within_1_percent():
    r = housing_checks.annulus_torsion(a=64e-3, b=87.5e-3, h=3e-3)
    assert abs(r["error"]) < 0.01, r


def test_the_pin_compliance_is_reciprocal_positive_and_in_equilibrium(fe):
    C = fe.compliance_m_per_N
    assert C.shape == (80, 80)
    assert fe.check["reciprocity"] < 1e-6
    assert fe.check["equilibrium"] < 1e-9
    assert fe.check["load_resultant_error"] < 1e-12
    assert np.linalg.eigvalsh(C).min() > 0
    # a load on one pin moves its neighbours: the matrix is not diagonal
    er, _ = housing.pin_directions(fe.geometry)
    e0, e1 = er[0:2], er[2:4]
    assert 0.01 < (e1 @ C[2:4, 0:2] @ e0) / (e0 @ C[0:2, 0:2] @ e0) < 1.0


def test_the_groove_datum_splits_each_pins_radial_compliance(fe):
    # the datum one pin pitch (10 mm) behind the groove: the seat moves more than the datum, the
    # datum more than nothing, and the bolt pattern modulates the far part more than the whole
    assert fe.check["datum_depth_m"] == pytest.approx(2 * math.pi * 64e-3 / 40)
    assert np.all(fe.local_radial_m_per_N > 0) and np.all(fe.datum_radial_m_per_N > 0)
    assert 0.3 < fe.check["local_groove_share"] < 0.9
    assert fe.radial_stiffness_lobes(1, datum=True)[16] > fe.radial_stiffness_lobes(1)[16]


def test_the_bolt_pattern_sets_the_lobes_of_the_pin_stiffness(case, fe):
    # 16 bolts, 40 pins: the pattern repeats every 40 / gcd(40, 16) = 5 pins; lobes only at m = 8, 16
    s = housing.bolt_symmetry(fe)
    assert s["shift_pins"] == 5 and s["lobe_period"] == 8
    assert s["invariance_error"] < 1e-3
    big = {m for m, v in s["lobes"].items() if v > 5e-3 * max(s["lobes"].values())}
    assert big == {8, 16} and s["lobes"][16] > 0.01
    assert s["largest_lobe_off_pattern"] < 5e-3 * s["lobes"][16]     # the coarse mesh's asymmetry
    # 10 bolts: every 4 pins, lobes at m = 10, 20 only
    ten = housing.housing_for_case(case.replace("housing", bolt_count=10), h_m=COARSE_M, checks=False)
    t = housing.bolt_symmetry(ten)
    assert t["shift_pins"] == 4 and t["invariance_error"] < 1e-3
    big = {m for m, v in t["lobes"].items() if v > 5e-3 * max(t["lobes"].values())}
    assert 10 in big and big <= {10, 20}
    assert t["largest_lobe_off_pattern"] < 5e-3 * max(t["lobes"].values())


def test_the_mesh_convergence_is_measured_with_an_observed_order(case):
    conv = housing.convergence(housing.case_geometry(case), levels=(1.5, 2.0, 3.0))   # h = 2, 1.5, 1 mm
    r = conv["radial_compliance_m_per_N"]
    assert len(r["values"]) == 3
    assert r["rate"] > 1.0                              # P2 with smooth seats: measured ~2.5
    assert r["finest_error_estimate"] < 0.01
    assert conv["torsion_rad_per_Nm"]["finest_error_estimate"] < 0.01


def test_all_modes_rebuild_the_compliance_and_fewer_leave_a_positive_residual(fe):
    zp = fe.geometry.pin_count
    full = fe.modes(2 * zp)
    assert np.allclose(full.kept_fraction, 1.0, atol=1e-9)
    assert np.abs(full.residual_radial_m_per_N).max() < 1e-9 * fe.radial_compliance_m_per_N.max()
    prev = 0.0
    for n in (6, 10, 16):
        m = fe.modes(n)
        assert m.phi.shape == (2 * zp, n) and np.allclose(m.phi.T @ m.phi, np.eye(n), atol=1e-10)
        assert np.all(np.diff(m.stiffness_N_per_m) >= 0)        # most compliant first
        assert np.all(m.residual_radial_m_per_N > 0) and np.all(m.kept_fraction < 1)
        assert m.kept_fraction.mean() > prev
        prev = m.kept_fraction.mean()
        assert np.all(m.mass_kg > 0) and np.allclose(m.mass_matrix_kg, m.mass_matrix_kg.T)
        assert m.stiffness_check < 1e-9                 # Psi^T K Psi = diag(1 / lambda): the Ritz fields
    with pytest.raises(Exception, match="allowed a whole number 1 to 2 zp = 80"):
        fe.modes(0)


def test_the_modal_mass_of_the_ring_is_below_the_ring_mass(fe):
    # a Ritz mode with unit pin displacement (norm 1 over the pins) moves no point of the section
    # more than the groove it pulls, so its modal mass is below the whole section's mass
    g = fe.geometry
    area = math.pi * (g.flange_outer_radius_m ** 2 - g.pin_circle_radius_m ** 2)
    assert np.all(fe.modes(6).mass_kg < g.density_kg_per_m3 * g.thickness_m * area)


def test_one_discs_classical_pin_forces_turn_the_housing_by_zp_over_zc_of_the_disc_torque(case):
    from fem.pin_groove import pin_moment_arms_m
    f = housing.pin_force_pattern(case)
    g = housing.case_geometry(case)
    a = g.pin_angles_rad()
    x, y = g.pin_circle_radius_m * np.cos(a), g.pin_circle_radius_m * np.sin(a)
    moment = float(np.sum(x * f[:, 1] - y * f[:, 0]))
    arms = np.maximum(pin_moment_arms_m(case), 0.0)
    disc_torque = float(np.sum(np.hypot(*f.T) * arms))
    assert moment == pytest.approx(case.cycloid.zp / case.cycloid.zc * disc_torque, rel=1e-9)
    # both discs: the radial resultants cancel, the housing carries (1 - 1/i) of the output torque
    F = housing.output_force_pattern(case, 100.0).reshape(-1, 2)
    assert np.abs(F.sum(axis=0)).max() < 1e-9 * np.abs(F).max()
    assert float(np.sum(x * F[:, 1] - y * F[:, 0])) == pytest.approx(100.0 * (1 - 1 / case.ratio), rel=1e-12)


def test_the_ring_torsion_is_the_clamped_annulus_within_5_percent(case, fe):
    # no closed form for a grooved ring clamped at 16 holes: beside the annulus R..bolt circle
    # clamped all round, the grooves (softer) and the flange beyond the bolts (stiffer) nearly cancel
    out = housing.output_figures(fe, case)
    assert abs(out["housing_torsion_over_clamped_annulus"] - 1) < 0.05
    i = case.ratio
    assert out["torsion_uniform_rad_per_Nm_output"] == pytest.approx(((i - 1) / i) ** 2
                                                                     * fe.torsion_compliance_rad_per_Nm)


@pytest.mark.parametrize("key, change, words", [
    ("pin_ring_outer_radius_mm", {"pin_ring_outer_radius_mm": 66.0}, "outside the groove bottoms"),
    ("pin_ring_length_mm", {"pin_ring_length_mm": 19.0}, "must span the disc stack"),
    ("bolt_circle_radius_mm", {"bolt_circle_radius_mm": 82.0}, "cut the ring wall"),
    ("flange_outer_radius_mm", {"flange_outer_radius_mm": 90.0}, "reach the flange rim"),
    ("bolt_hole_radius_mm", {"bolt_count": 64, "bolt_hole_radius_mm": 4.4}, "overlap"),
    ("bolt_count", {"bolt_count": 2}, "outside the allowed range"),
])
def test_an_impossible_housing_is_one_error_naming_the_key(case, key, change, words):
    with pytest.raises(CaseError) as exc:
        case.replace("housing", **change)
    msg = str(exc.value)
    assert f"[housing] {key}" in msg and words in msg and "\n" not in msg


def test_the_picture_is_drawn(tmp_path, case, fe):
    from pipeline.housing_figure import housing_png
    out = tmp_path / "housing.png"
    housing_png(case, out, fe)
    assert out.stat().st_size > 20_000
