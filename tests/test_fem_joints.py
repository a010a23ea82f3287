"""fem.joints and fem.bolts against closed forms (tolerances stated per test)."""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from scipy.special import gamma

from fem import bolts, joints
from geometry.artifacts import InputError
from geometry.params import CaseError, case_from_dict, load_case

CASES = Path(__file__).resolve().parents[1] / "cases"
E = 206e9


def test_layer_law_is_c_p_to_the_half_and_its_tangent_is_the_derivative():
    law = joints.contact_law(0.8)
    p = np.array([1e6, 1e7, 1e8])
    c_um = 0.75                                   # ground class middle, um / MPa^0.5
    assert np.allclose(law.approach_m(p), c_um * 1e-6 * np.sqrt(p / 1e6), rtol=1e-12)
    h = 1e-3 * p                                  # central difference, O(h^2): 1e-6 relative
    fd = (law.approach_m(p + h) - law.approach_m(p - h)) / (2 * h)
    assert np.allclose(law.compliance_m3_per_N(p), fd, rtol=1e-6)


def test_bands_order_low_stiffer_than_high_and_mid_between():
    k = {b: float(joints.contact_law(1.6, b).normal_stiffness_N_per_m3(1e7)) for b in joints.BANDS}
    assert k["low"] > k["mid"] > k["high"]


@pytest.mark.parametrize("Ra", [0.0, -1.0, 6.31, 100.0])
def test_a_finish_outside_the_classes_is_refused(Ra):
    with pytest.raises(InputError, match="Ra"):
        joints.contact_law(Ra)


def test_hard_end_of_the_finish_range_is_the_roughest_class():
    assert joints.contact_law(6.3).finish == "turned / milled"


def test_mindlin_ratio():
    assert joints.tangential_ratio(0.3) == pytest.approx(1.4 / 1.7, rel=1e-12)
    assert joints.tangential_ratio(0.0) == pytest.approx(1.0)


def test_lame_fit_pressure_of_a_solid_shaft_in_a_thick_hub():
    # Timoshenko & Goodier: solid shaft (a = 0) in a hub c = 2 b, one E:
    # I/2 = p b/E [(c^2+b^2)/(c^2-b^2) + 1] = p b/E (5/3 + 1) = 8/3 p b / E
    b, I = 0.02, 20e-6
    p = joints.fit_pressure_Pa(I, 2 * b, 0.0, 4 * b, E)
    assert p == pytest.approx(I / 2 * 3 * E / (8 * b), rel=1e-12)


def test_the_layer_takes_its_share_of_the_interference():
    law = joints.contact_law(0.8)
    I, d = 10e-6, 0.04
    p = joints.fit_pressure_Pa(I, d, 0.03, 0.05, E, law)
    lam = joints.lame_fit_compliance_m_per_Pa(d, 0.03, 0.05, E)
    assert lam * p + float(law.approach_m(p)) == pytest.approx(I / 2, rel=1e-6)
    assert p < joints.fit_pressure_Pa(I, d, 0.03, 0.05, E)


def _gamma_int(k):
    """int cos^k over |psi| < pi/2."""
    return math.sqrt(math.pi) * gamma((k + 1) / 2) / gamma(k / 2 + 1)


def test_ring_seat_without_fit_is_the_power_law_closed_form():
    # p_f = 0: du/dF = c m p0^(m-1) int cos^(n(m+1)) / (R B I1^2), p0 = F / (R B I1)
    F, D, B, n = 2000.0, 0.04, 0.011, 10 / 9
    r = joints.ring_seat_radial(F, D, B, 0.0, 0.8)
    law = joints.contact_law(0.8)
    I1 = _gamma_int(n + 1)
    p0 = F / (D / 2 * B * I1)
    closed = law.c_SI * 0.5 * p0 ** -0.5 * _gamma_int(n * 1.5) / (D / 2 * B * I1 ** 2)
    assert r.compliance_m_per_N == pytest.approx(closed, rel=1e-6)
    # secant of a power law u ~ F^m is tangent / m
    assert r.secant_m_per_N == pytest.approx(closed / 0.5, rel=1e-6)


def test_ring_seat_under_a_large_fit_is_linear_at_the_fit_pressure():
    # p_f >> p0: du/dF -> c m p_f^(m-1) int cos^(2n) / (R B I1^2); error O(p0/p_f) ~ 1e-4
    F, D, B, n, pf = 10.0, 0.04, 0.011, 10 / 9, 1e8
    r = joints.ring_seat_radial(F, D, B, pf, 0.8)
    law = joints.contact_law(0.8)
    closed = law.c_SI * 0.5 * pf ** -0.5 * _gamma_int(2 * n) / (D / 2 * B * _gamma_int(n + 1) ** 2)
    assert r.compliance_m_per_N == pytest.approx(closed, rel=1e-3)
    assert r.secant_m_per_N == pytest.approx(closed, rel=1e-3)


def test_ring_seat_band_brackets_the_middle():
    r = joints.ring_seat_radial(2000.0, 0.04, 0.011, 5e6, 1.6)
    lo, hi = r.band_compliance_m_per_N
    assert lo < r.compliance_m_per_N < hi


def test_pillar_layer_carries_the_joint_compliance_not_the_steel():
    pj = joints.pillar_joint_layer(17e3, 1e-4, 1.6, pin_stiffness_N_per_m=1e8).mid
    for h in (1e-4, 1e-3, 5e-3):
        A = pj.face_area_m2
        # a layer h with E_layer in place of steel h: added compliance h/(E_l A) - h/(E A) = 1/K_n
        added = h / (pj.E_layer_Pa(h) * A) - h / (pj.E_steel_Pa * A)
        assert added == pytest.approx(1 / pj.normal_stiffness_N_per_m, rel=1e-9)
        added_t = h / (pj.G_layer_Pa(h) * A) - h / (pj.G_steel_Pa * A)
        assert added_t == pytest.approx(1 / pj.tangential_stiffness_N_per_m, rel=1e-9)
    kn = float(joints.contact_law(1.6).normal_stiffness_N_per_m3(17e3 / 1e-4))
    assert pj.tangential_stiffness_N_per_m == pytest.approx(joints.tangential_ratio(0.3) * kn * 1e-4 + 1e8, rel=1e-12)


def test_flange_face_is_k_t_times_the_polar_moment_and_slip_is_checked():
    ri, ro, F = 0.04, 0.06, 3e5
    ff = joints.flange_face_torsional(ri, ro, F, 12, 1.6, friction=0.12, torque_Nm=1500.0, bolt_circle_r_m=0.05,
                                      bolt_d_m=0.008, plate_t_m=0.016)
    p = F / (math.pi * (ro ** 2 - ri ** 2))
    kt = joints.tangential_ratio(0.3) * float(joints.contact_law(1.6).normal_stiffness_N_per_m3(p))
    assert 1 / ff.compliance_rad_per_Nm == pytest.approx(kt * math.pi * (ro ** 4 - ri ** 4) / 2, rel=1e-12)
    r_f = 2 / 3 * (ro ** 3 - ri ** 3) / (ro ** 2 - ri ** 2)
    assert ff.slip_torque_Nm == pytest.approx(0.12 * F * r_f, rel=1e-12)
    assert not ff.slips
    weak = joints.flange_face_torsional(ri, ro, 1e4, 12, 1.6, friction=0.12, torque_Nm=2000.0,
                                        bolt_circle_r_m=0.05, bolt_d_m=0.008, plate_t_m=0.016)
    assert weak.slips


def test_vdi_preload_puts_the_reduced_stress_at_90_percent_of_yield():
    # sigma = F/A_S, tau = 16 M_G / (pi d_S^3) with M_G = F d2/2 (P/(pi d2) + 1.155 mu), VDI's plastic
    # torsion factor 3/4 on tau (the 3/2 of R7/1): sqrt(sigma^2 + 3 (3/4 tau)^2) = 0.9 R_p0.2
    for d, cls, mu in ((12.0, 10.9, 0.12), (3.0, 8.8, 0.5), (24.0, 12.9, 0.04)):
        t = bolts.thread(d)
        F = bolts.assembly_preload_N(d, cls, mu)
        sigma = F / t.stress_area_m2
        MG = F * t.d2_m / 2 * (t.pitch_m / (math.pi * t.d2_m) + 1.155 * mu)
        tau = 16 * MG / (math.pi * t.stress_diameter_m ** 3)
        assert math.hypot(sigma, math.sqrt(3) * 0.75 * tau) == pytest.approx(0.9 * bolts.yield_Pa(cls, d), rel=1e-12)


def test_stress_area_of_m12_is_the_iso_898_figure():
    assert bolts.thread(12.0).stress_area_m2 == pytest.approx(84.3e-6, rel=2e-3)   # ISO 898-1 table: 84.3 mm^2


def test_member_cone_alone_for_a_wide_part_and_sleeve_when_narrow():
    t = bolts.thread(8.0)
    wide, tan_phi = bolts.member_resilience_m_per_N(t, 0.02, 0.2, E)
    # a very wide part is the cone limit; a part no wider than the head is a sleeve of d_W
    narrow, _ = bolts.member_resilience_m_per_N(t, 0.02, t.head_diameter_m, E)
    sleeve = 0.02 / (E * math.pi / 4 * (t.head_diameter_m ** 2 - t.hole_diameter_m ** 2))
    assert narrow == pytest.approx(sleeve, rel=1e-9)
    assert wide < narrow


def test_huth_single_shear_closed_form():
    d, t1, t2 = 0.01, 0.01, 0.01            # (t1 + t2) / (2 d) = 1
    C = (1.0) ** (2 / 3) * 3.0 * (1 / (t1 * E) + 1 / (t2 * E) + 1 / (2 * t1 * E) + 1 / (2 * t2 * E))
    assert bolts.huth_shear_stiffness_N_per_m(d, t1, t2, E) == pytest.approx(1 / C, rel=1e-12)


def _raw(name="rv40e-81"):
    import tomllib
    return tomllib.loads((CASES / f"{name}.toml").read_text())


@pytest.mark.parametrize("key,value", [("seat_roughness_Ra_um", 0.0), ("seat_roughness_Ra_um", -0.8),
                                       ("face_roughness_Ra_um", 25.0), ("pillar_bolt_thread_mm", 7.0),
                                       ("pillar_bolt_property_class", 9.8), ("output_bolt_count", 1000),
                                       ("support_cup_interference_um", -3.0),
                                       ("support_cone_interference_um", 500.0)])
def test_bad_joint_keys_are_refused_with_key_and_range(key, value):
    raw = _raw()
    raw["joints"][key] = value
    with pytest.raises(CaseError) as exc:
        case_from_dict(raw, source="x.toml")
    assert f"[joints] {key}" in str(exc.value) and repr(value) in str(exc.value) and "allowed" in str(exc.value)


def test_a_case_without_the_joints_section_is_refused():
    raw = _raw()
    del raw["joints"]
    with pytest.raises(CaseError, match=r"\[joints\].*missing"):
        case_from_dict(raw)


@pytest.mark.parametrize("name", ["rv40e-81", "rv40e-105", "rv160n-81"])
def test_shipped_cases_give_finite_joint_figures(name):
    from fem import joint_figures
    case = load_case(CASES / f"{name}.toml")
    s = joint_figures.support_seats(case, case.rated_torque_Nm)
    lo, hi = s["seats_band"]
    assert 0 < lo < s["seats_m_per_N"] < hi
    p = joint_figures.pillar(case)
    assert p["E_layer_h1mm_Pa"]["high"] < p["E_layer_h1mm_Pa"]["mid"] < p["E_layer_h1mm_Pa"]["low"] < E
    f = joint_figures.flange(case)
    assert not f["slips_at_momentary"]


def test_hard_end_largest_interference_and_roughest_seat_still_solve():
    law = joints.contact_law(6.3, "high")
    p = joints.fit_pressure_Pa(50e-6, 0.017, 0.0, 0.0227, E, law)     # the case's largest interference
    lam = joints.lame_fit_compliance_m_per_Pa(0.017, 0.0, 0.0227, E)
    assert lam * p + float(law.approach_m(p)) == pytest.approx(25e-6, rel=1e-6)
    r = joints.ring_seat_radial(1e5, 0.017, 0.012, p, 6.3)
    assert 0 < r.band_compliance_m_per_N[0] < r.compliance_m_per_N < r.band_compliance_m_per_N[1]


def test_a_pressure_past_the_laws_data_is_flagged():
    assert joints.pillar_joint_layer(17e3, 6.5e-5, 1.6).mid.beyond_law          # 260 MPa
    assert not joints.pillar_joint_layer(17e3, 1e-3, 1.6).mid.beyond_law        # 17 MPa
