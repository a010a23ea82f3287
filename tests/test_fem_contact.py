"""FEM stage: Hertz benchmark, convergence, patch test, contact solver (coarse, fast meshes), and the
first contact of a pin on the modified profile (exact, from the one geometry kernel)."""
import math
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import minimize_scalar

from fem import contact, elastic, hertz
from fem.mesh import block_mesh
from fem.pin_contact import first_contact, hertz_benchmark, pin_pose, tooth_pair_map
from geometry.artifacts import InputError
from geometry.params import load_case
from geometry.profile import cycloid_xy, profile_args


def test_cylinder_on_flat_matches_hertz_peak_pressure_and_half_width_within_3_percent():
    # closed form: Johnson 1985 eqs. 4.43-4.45 (p0 = 1095.9 MPa, b = 58.09 um at 1 kN, R 3 mm, L 10 mm)
    r = hertz_benchmark(3e-3, 10e-3, 1000.0)
    assert abs(r.peak_pressure_Pa / r.peak_pressure_closed_form_Pa - 1) < 0.03
    assert abs(r.half_width_m / r.half_width_closed_form_m - 1) < 0.03


def test_cylinder_on_cylinder_matches_hertz_within_3_percent():
    r = hertz_benchmark(3e-3, 10e-3, 800.0, counter_radius_m=8e-3)
    assert abs(r.peak_pressure_Pa / r.peak_pressure_closed_form_Pa - 1) < 0.03
    assert abs(r.half_width_m / r.half_width_closed_form_m - 1) < 0.03
    # approach against Johnson eq. 5.36 for both cylinders: the clamped back halves differ from
    # Johnson's loading, measured 1-5 %; band 8 %
    assert abs(r.approach_m / r.approach_closed_form_m - 1) < 0.08


def test_half_width_error_falls_with_the_contact_element_size():
    b = float(hertz.hertz_line(1000.0, 10e-3, 3e-3, hertz.contact_modulus(206e9, 0.3))[1])
    h = b / np.array([4.0, 8.0, 16.0])
    err = [abs(hertz_benchmark(3e-3, 10e-3, 1000.0, mesh_size_m=hi).half_width_m / b - 1) for hi in h]
    rate = np.polyfit(np.log(h), np.log(err), 1)[0]
    print(f"half-width errors {err}, observed rate {rate:.2f}")
    assert err[-1] < err[0] and rate > 0.5   # measured ~1 (edge located to O(h)); bound 0.5


def test_linear_displacement_field_is_reproduced_exactly_patch_test():
    m = block_mesh(4e-3, 2e-3, 1e-4, 5e-4)
    K = elastic.stiffness(elastic.basis_2d(m), 206e9, 0.3)
    A = np.array([[1e-3, 2e-4], [-3e-4, 5e-4]])
    exact = m.points @ A.T + np.array([1e-6, -2e-6])
    bnd = np.unique(np.concatenate(list(m.boundary.values()) + [np.flatnonzero(
        (np.abs(np.abs(m.points[:, 0]) - 2e-3) < 1e-12))]))
    fixed = np.concatenate([2 * bnd, 2 * bnd + 1])
    u_b = np.zeros(K.shape[0])
    u_b[2 * bnd], u_b[2 * bnd + 1] = exact[bnd, 0], exact[bnd, 1]
    fac = elastic.Factorized.of(K, fixed)
    u = fac.solve(-(K @ u_b)) + u_b
    # round-off only: 1e-10 relative
    assert np.abs(u.reshape(-1, 2) - exact).max() < 1e-10 * np.abs(exact).max()


def test_schur_ordered_factorization_gives_the_same_compliance_as_solves():
    m = block_mesh(6e-3, 3e-3, 2e-5, 5e-4)
    K = elastic.stiffness(elastic.basis_2d(m), 206e9, 0.3)
    fixed = np.concatenate([2 * m.boundary["bottom"], 2 * m.boundary["bottom"] + 1])
    top = m.boundary["top"][:20]
    B = contact.node_operator(top, np.tile([0.0, 1.0], (len(top), 1)), K.shape[0])
    plain = elastic.Factorized.of(K, fixed).compliance(B)
    schur = elastic.Factorized.of(K, fixed, last=np.column_stack([2 * top, 2 * top + 1]).ravel()).compliance(B)
    assert np.allclose(plain, schur, rtol=1e-9, atol=0)


def test_the_condensed_tooth_map_gives_the_approach_of_a_direct_solve(monkeypatch):
    # fast path: disc factorized with its candidates last, single-window candidates framed along
    # their load direction (one DOF each), compliance read off the Schur block; direct path: plain
    # factorization, unit-load solves. Same mesh and contact solver, so only round-off may differ:
    # measured 1.0e-13 (approach), 4e-14 (peak pressure), 8e-14 (half-width); bound 1e-9. 30 and 33 deg
    # share candidates (nodes kept with both DOFs), 100 and 160 deg do not (framed nodes).
    seen = []                                                # (DOFs, condensed DOFs) of each factorization
    of = elastic.Factorized.of.__func__
    monkeypatch.setattr(elastic.Factorized, "of", classmethod(
        lambda cls, K, fixed, last=None: (seen.append((K.shape[0], last)), of(cls, K, fixed, last))[1]))
    kw = dict(positions_deg=[30.0, 33.0, 100.0, 160.0], loads_N=[300.0, 1500.0], mesh_size_m=8e-6, h_max_m=1e-3)
    fast = tooth_pair_map(_case(), **kw)
    direct = tooth_pair_map(_case(), **kw, direct=True)
    disc_last = max((s for s in seen if s[1] is not None), key=lambda s: s[0])[1]
    per_node = np.unique(disc_last // 2, return_counts=True)[1]
    assert np.any(per_node == 1) and np.any(per_node == 2)  # framed (1 DOF) and shared (2 DOFs) candidates
    assert np.allclose(fast.approach_m, direct.approach_m, rtol=1e-9, atol=0)
    assert np.allclose(fast.peak_pressure_Pa, direct.peak_pressure_Pa, rtol=1e-9, atol=0)
    assert np.allclose(fast.half_width_m, direct.half_width_m, rtol=1e-9, atol=0)


def test_active_set_solves_a_two_spring_contact_exactly():
    # two independent springs k = 1, 2 N/m with gaps 0 and 1 m, total force 5 N:
    # both touch: delta - 0 = l1, delta - 1 = l2 / 2, l1 + l2 = 5 -> delta = 7/3
    setup = contact.ContactSetup(np.diag([1.0, 0.5]), np.array([0.0, 1.0]), np.ones(2),
                                 np.array([0.0, 1.0]), np.ones(2), np.arange(2))
    lam, delta, _ = contact.solve_force(setup, 5.0)
    assert delta == pytest.approx(7 / 3, rel=1e-12)
    assert lam == pytest.approx([7 / 3, 8 / 3], rel=1e-12)


def test_power_law_fit_recovers_an_exact_law():
    d = np.geomspace(1e-7, 1e-5, 6)
    k, n = hertz.fit_power_law(3e9 * d ** 1.1, d)
    assert n == pytest.approx(1.1, rel=1e-10) and k == pytest.approx(3e9, rel=1e-8)


def test_a_benchmark_load_too_large_for_hertz_is_refused_with_the_value():
    with pytest.raises(ValueError, match="half-width"):
        hertz_benchmark(1e-3, 1e-3, 1e6)


# ----------------------------------------------------------------------------- first contact
CASES = Path(__file__).resolve().parents[1] / "cases"


def grid_first_contact(case, centres_mm, t_range, n=40001):
    """The former fem first contact, kept as a reference: nearest of 40001 profile points, a
    2001-point local refinement, curvature by central differences (dt = 1e-5 rad). Accurate
    where the profile is neither flat nor sharp: t ~1e-8 rad, curvature ~1e-5 relative."""
    args = profile_args(case, modified=True)
    t = np.linspace(*t_range, n)
    xy = np.column_stack(cycloid_xy(t, **args))
    out = []
    for c in centres_mm:
        i = int(np.argmin(np.hypot(*(xy - c).T)))
        tt = np.linspace(t[max(i - 2, 0)], t[min(i + 2, n - 1)], 2001)
        pts = np.column_stack(cycloid_xy(tt, **args))
        j = int(np.argmin(np.hypot(*(pts - c).T)))
        tc, p = tt[j], pts[j]
        nrm = (c - p) / np.hypot(*(c - p))
        dt = 1e-5
        p_m, p_p = (np.array(cycloid_xy(np.array([tc + s]), **args)).ravel() for s in (-dt, dt))
        d1, d2 = (p_p - p_m) / (2 * dt), (p_p - 2 * p + p_m) / dt ** 2
        rho = np.hypot(*d1) ** 3 / (d1[0] * d2[1] - d1[1] * d2[0])
        convex = np.dot(np.array([-d1[1], d1[0]]) / np.hypot(*d1) * rho, nrm) < 0
        out.append((tc, p, nrm, p + nrm * case.cycloid.pin_radius_mm, abs(rho) if convex else -abs(rho)))
    return out


def _case(name="rv40e-105"):
    return load_case(CASES / f"{name}.toml")


def _t_range(case):
    pitch = 2 * np.pi / case.cycloid.zp
    return (-1.5 * pitch, 1.5 * pitch)


@pytest.mark.parametrize("name", ["rv40e-105", "rv160n-81"])
def test_first_contact_agrees_with_the_former_grid_search_where_that_was_accurate(name):
    # 40 pin phases along the path of contact: measured differences t 1.2e-8 rad, point 3.6e-6 mm,
    # normal 1.2e-6, touching centre 8e-9 mm, curvature radius 2.6e-5 relative (the grid's own
    # resolution and finite-difference error); bounds 1e-7 rad, 1e-5 mm, 1e-5, 1e-7 mm, 1e-4
    case = _case(name)
    pos = np.linspace(5, 175, 40)
    centres = pin_pose(case, pos)
    new = first_contact(case, centres, _t_range(case))
    old = grid_first_contact(case, centres, _t_range(case))
    assert np.max(np.abs(new.t_rad - [o[0] for o in old])) < 1e-7
    assert np.max(np.abs(new.point_mm - [o[1] for o in old])) < 1e-5
    assert np.max(np.abs(new.normal - [o[2] for o in old])) < 1e-5
    assert np.max(np.abs(new.centre_mm - [o[3] for o in old])) < 1e-7
    assert np.allclose(new.curvature_radius_mm, [o[4] for o in old], rtol=1e-4, atol=0)


def _hard_case():
    # K1 = 0.95, micron modifications, pin radius 2 mm (tests/test_clearance.py's hard end)
    return _case().replace("cycloid", eccentricity_mm=1.52, pin_radius_mm=2.0) \
        .replace("modification", offset_mm=-0.001, equidistant_mm=0.001)


@pytest.mark.parametrize("make", [_case, _hard_case])
def test_the_moved_pin_touches_the_modified_profile_exactly(make):
    # the pin centre moved along the normal lies one pin radius from the profile: direct bounded
    # minimisation of |cycloid_xy(t) - centre| around 200000 samples, to 1e-9 mm
    case = make()
    args = profile_args(case, modified=True)
    fc = first_contact(case, pin_pose(case, np.linspace(2, 178, 12)), _t_range(case))
    tg = np.linspace(*_t_range(case), 200000)
    xg, yg = cycloid_xy(tg, **args)
    for c, n, p in zip(fc.centre_mm, fc.normal, fc.point_mm):
        i = np.argmin((xg - c[0]) ** 2 + (yg - c[1]) ** 2)
        f = lambda u: math.hypot(*(np.array(cycloid_xy(tg[i] + u, **args)).ravel() - c))  # noqa: E731
        d = minimize_scalar(f, bounds=(-2e-5, 2e-5), method="bounded", options={"xatol": 1e-15}).fun
        assert d == pytest.approx(case.cycloid.pin_radius_mm, abs=1e-9)
        assert np.allclose((c - p) / np.hypot(*(c - p)), n, atol=1e-12)


@pytest.mark.parametrize("make", [_case, _hard_case])
def test_the_curvature_radius_at_root_and_tip_is_the_closed_form_minus_the_pin_radius(make):
    # pin phase 0 touches the root, 180 deg the tip. Pin-centre curve (R, Rr modified, K1 = E zp / R):
    # root -(R - E zp)^2 / (E zp^2 - R) (concave), tip R (1 + K1)^2 / (1 + zp K1) (convex); the
    # profile is offset inward by Rr: rho - Rr, to 1e-9 relative
    case = make()
    a = profile_args(case, modified=True)
    R, E, zp, Rr = a["R"], a["E"], a["zp"], a["Rr"]
    k1 = E * zp / R
    fc = first_contact(case, pin_pose(case, [0.0, 180.0]), _t_range(case))
    root = -(R - E * zp) ** 2 / (E * zp ** 2 - R) - Rr
    tip = R * (1 + k1) ** 2 / (1 + zp * k1) - Rr
    assert fc.curvature_radius_mm == pytest.approx([root, tip], rel=1e-9)
    assert abs(fc.t_rad[0]) < 1e-9 and abs(abs(fc.t_rad[1]) - np.pi / case.cycloid.zc) < 1e-9


def test_a_foot_point_outside_the_meshed_stretch_is_refused():
    case = _case()
    with pytest.raises(InputError, match="outside the profile stretch"):
        first_contact(case, pin_pose(case, [90.0]), (0.05, 0.1))
