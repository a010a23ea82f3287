"""Pin gaps, clearance and backlash: numerical (Newton on the parametric curve) against closed forms."""
import math
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import minimize_scalar

from geometry import clearance as cl
from geometry import pin_profile as pp
from geometry.params import CaseError, load_case
from geometry.profile import cycloid_xy, profile_args

CASES = Path(__file__).resolve().parents[1] / "cases"
NAMES = ("rv40e-105", "rv40e-81", "rv160n-81")


def case(name="rv40e-105"):
    return load_case(CASES / f"{name}.toml")


def hard_case(dR=-0.001, dRr=0.001):
    """K1 = E zp / R = 0.95 (E = 1.52 mm on the RV-40E pin circle), micron modifications; the pin
    radius drops to 2 mm because the tips' convex radius is only 2.47 mm at this K1."""
    return case().replace("cycloid", eccentricity_mm=1.52, pin_radius_mm=2.0) \
        .replace("modification", offset_mm=dR, equidistant_mm=dRr)


@pytest.mark.parametrize("name", NAMES)
def test_every_pin_touches_the_unmodified_profile_at_every_crank_angle(name):
    # DESIGN.md conjugacy check: distance pin centre - profile = Rr to 1e-6 mm (measured 7e-14)
    for psi in np.linspace(0, 2 * np.pi, 37):
        assert np.max(np.abs(cl.pin_distances_mm(case(name), psi, modified=False))) < 1e-6


def test_tangency_holds_at_the_hard_end_too():
    # K1 = 0.95: the sharpest profile the kernel accepts for these pins; same 1e-6 mm bound
    for psi in np.linspace(0, 2 * np.pi, 13):
        assert np.max(np.abs(cl.pin_distances_mm(hard_case(), psi, modified=False))) < 1e-6


@pytest.mark.parametrize("name", NAMES)
def test_modified_gaps_follow_the_first_order_closed_form(name):
    # D0(phi) = dRr - dR (1 - K1 cos phi) / S (module docstring); the closed form ignores the
    # foot point's shift, a second-order error largest at the roots: measured 0.025 um on a
    # 11-13 um gap (RV-40E), bound here 0.1 um
    cs = case(name)
    for psi in (0.0, 0.3, 1.7):
        pc = cl.pin_contacts(cs, psi)
        assert np.max(np.abs(pc.gap_mm - cl.closed_form_gap_mm(cs, pc.phase_rad))) < 1e-4


@pytest.mark.parametrize("name", NAMES)
def test_moment_arms_are_those_of_normals_through_the_pitch_point(name):
    # l(phi) = E zc sin phi / S for the conjugate (unmodified) profile, to 1e-9 mm
    pc = cl.pin_contacts(case(name), 0.4, modified=False)
    assert np.max(np.abs(pc.arm_mm - cl.closed_form_arm_mm(case(name), pc.phase_rad))) < 1e-9


@pytest.mark.parametrize("name", NAMES)
def test_minimum_clearance_matches_its_closed_form(name):
    # dRr - dR sqrt(1 - K1^2) at cos phi = K1; measured within 0.3 nm, bound 5 nm
    cs = case(name)
    assert cl.min_clearance_mm(cs, samples=16) == pytest.approx(cl.closed_form_min_clearance_mm(cs), abs=5e-6)


@pytest.mark.parametrize("name", NAMES)
def test_backlash_matches_the_closed_form_at_the_same_crank_angle(name):
    # min over pins of D0 / |l|, each side; measured within 0.02 %, bound 0.1 %; and never below
    # the continuous-phase bound b0 = (dRr - dR sqrt(1 - K1^2)) / (E zc) by more than that
    cs = case(name)
    for psi in (0.0, 0.05):
        num, cf = cl.backlash(cs, psi), cl.closed_form_backlash(cs, psi)
        assert num.plus_arcmin == pytest.approx(cf.plus_arcmin, rel=1e-3)
        assert num.minus_arcmin == pytest.approx(cf.minus_arcmin, rel=1e-3)
        assert num.total_arcmin >= cl.closed_form_backlash(cs).total_arcmin * (1 - 1e-3)


def test_the_reference_reducer_backlash_stays_below_the_catalog_arcmin():
    # closed form b0 = (0.004 + 0.003 sqrt(1 - 0.8125^2)) / (1.3 * 39) rad = 0.38983 arcmin per side;
    # the total is below the catalog's 1 arcmin lost motion (Nabtesco RV-E)
    b0 = (0.004 + 0.003 * np.sqrt(1 - 0.8125 ** 2)) / (1.3 * 39) * 180 / np.pi * 60
    assert cl.backlash_arcmin(case()) == pytest.approx(2 * b0, rel=1e-3)
    assert cl.backlash_arcmin(case()) < 1.0


def test_a_rotation_modification_shifts_backlash_from_one_side_to_the_other():
    # rotating the profile by delta is turning the disc by delta: b+ = b0 - delta, b- = b0 + delta
    delta_deg = 0.004
    base, turned = cl.backlash(case(), 0.0), cl.backlash(case().replace("modification", rotation_deg=delta_deg), 0.0)
    shift = delta_deg * 60
    assert turned.plus_arcmin == pytest.approx(base.plus_arcmin - shift, abs=1e-3 * base.plus_arcmin)
    assert turned.minus_arcmin == pytest.approx(base.minus_arcmin + shift, abs=1e-3 * base.plus_arcmin)


def test_a_pin_oversize_closes_every_gap_by_its_size():
    # the gap is measured to the actual pin: +2 um pin radius error = -2 um on every pin (to 1e-9 mm)
    cs = case()
    delta = cl.pin_distances_mm(cs.with_errors(pin_radius_um=2.0), 0.2) - cl.pin_distances_mm(cs, 0.2)
    assert np.allclose(delta, -0.002, atol=1e-9)


def test_a_tolerance_that_eats_the_clearance_is_reported_as_interference_not_absorbed():
    # dRr = -2 um, dR = 0: every pin overlaps the disc by 2 um (D0 = dRr, to 1e-9 mm); the
    # backlash is negative: the drive zone (arm >= E zc / 2) is freed only after turning back by
    # about 0.002 / (E zc / 2) rad per side; the closed form at the same crank angle agrees to 0.1 %
    cs = case().replace("modification", offset_mm=0.0, equidistant_mm=-0.002)
    assert np.allclose(cl.pin_distances_mm(cs, 0.1), -0.002, atol=1e-9)
    total = cl.backlash_arcmin(cs)
    assert total == pytest.approx(cl.closed_form_backlash(cs, 0.0).total_arcmin, rel=1e-3)
    assert total == pytest.approx(-2 * 0.002 / (1.3 * 39 / 2) * 60 * 180 / math.pi, rel=2e-2)


def test_the_textbook_initial_clearance_is_the_gap_left_after_taking_up_the_backlash():
    # D(phi) = dRr (1 - sin phi / S) - dR (1 - K1 cos phi - sqrt(1 - K1^2) sin phi) / S: the
    # textbook form, zero at cos phi = K1; numerically: the gaps after turning the disc by b0
    # (bound 0.05 um)
    cs = case()
    k1 = 1.3 * 40 / 64
    dR, dRr = cs.modification.offset_mm, cs.modification.equidistant_mm
    phi = np.linspace(0.01, np.pi - 0.01, 50)
    S = np.sqrt(1 + k1**2 - 2 * k1 * np.cos(phi))
    textbook = dRr * (1 - np.sin(phi) / S) - dR * (1 - k1 * np.cos(phi) - np.sqrt(1 - k1**2) * np.sin(phi)) / S
    assert np.allclose(cl.initial_clearance_mm(cs, phi), textbook, atol=1e-12)
    assert cl.initial_clearance_mm(cs, np.arccos(k1)) == pytest.approx(0.0, abs=1e-12)
    b0 = math.radians(cl.closed_form_backlash(cs).plus_arcmin / 60)
    pc = cl.pin_contacts(cs, 0.0, disc_rotation_rad=b0)
    # first order: 0.02 um away from the roots; within 0.4 rad of phi = 0 the foot point slides
    # fast and the form is off by up to 1.3 um (measured), so those pins are left out
    away = np.abs(pc.phase_rad) > 0.4
    assert np.max(np.abs(pc.gap_mm - cl.initial_clearance_mm(cs, pc.phase_rad))[away]) < 5e-5


def independent_gap(cs, psi):
    """Reference: minimise |cycloid_xy(t) - q| directly (no offset-curve argument), bounded
    around a dense seed, xatol 1e-14 rad."""
    c, a = cs.cycloid, profile_args(cs)
    theta = -psi / c.zc
    centre = c.eccentricity_mm * np.array([np.cos(psi), np.sin(psi)])
    out = []
    tg = np.linspace(0, 2 * np.pi, 200000, endpoint=False)
    xg, yg = cycloid_xy(tg, **a)
    for k in range(c.zp):
        p = c.pin_circle_radius_mm * np.array([np.cos(2 * np.pi * k / c.zp), np.sin(2 * np.pi * k / c.zp)]) - centre
        q = np.array([[np.cos(-theta), -np.sin(-theta)], [np.sin(-theta), np.cos(-theta)]]) @ p
        i = np.argmin((xg - q[0]) ** 2 + (yg - q[1]) ** 2)
        f = lambda t: np.hypot(*(np.array(cycloid_xy(np.array([t]), **a)).ravel() - q))  # noqa: E731
        r = minimize_scalar(f, bounds=(tg[i] - 4e-5, tg[i] + 4e-5), method="bounded", options={"xatol": 1e-14})
        out.append(r.fun - c.pin_radius_mm)
    return np.array(out)


def test_micron_gaps_at_high_K1_agree_with_a_direct_minimisation():
    # K1 = 0.95, dR = -1 um, dRr = +1 um: Newton on the curve vs bounded minimisation of the
    # distance itself agree to 1e-9 mm (measured ~1e-12)
    cs = hard_case()
    for psi in (0.0, 0.37):
        assert np.max(np.abs(cl.pin_distances_mm(cs, psi) - independent_gap(cs, psi))) < 1e-9


def test_the_gap_does_not_depend_on_the_seed_grid_at_high_K1():
    # the only discretisation is the seed grid that picks the basin: 4, 16 or 64 points per tooth
    # give the same gaps to 1e-12 mm at K1 = 0.95 with micron modifications
    cs = hard_case()
    c = cs.cycloid
    gaps = [cl.pin_contacts(cs, 0.37, samples_per_tooth=n).gap_mm for n in (4, 16, 64)]
    assert np.max(np.abs(gaps[0] - gaps[2])) < 1e-12 and np.max(np.abs(gaps[1] - gaps[2])) < 1e-12
    assert c.eccentricity_mm * c.zp / c.pin_circle_radius_mm == pytest.approx(0.95)


def test_micron_clearance_and_backlash_at_high_K1_match_their_closed_forms():
    # the closed forms still hold at K1 = 0.95 with micron modifications (bounds as above: 5 nm, 0.1 %)
    cs = hard_case()
    assert cl.min_clearance_mm(cs, samples=16) == pytest.approx(cl.closed_form_min_clearance_mm(cs), abs=5e-6)
    assert cl.backlash(cs, 0.2).total_arcmin == pytest.approx(cl.closed_form_backlash(cs, 0.2).total_arcmin, rel=1e-3)


def test_a_pin_too_big_for_the_tooth_tips_is_refused_as_undercut():
    # K1 = 0.98 (E = 1.568): the tips' convex radius is 1.57 mm < Rr = 3 mm: the profile loops
    with pytest.raises(CaseError, match=r"pin_radius_mm = 3.0.*undercuts.*allowed modified pin radius < 1.57"):
        case().replace("cycloid", eccentricity_mm=1.568)


@pytest.mark.parametrize("name", NAMES)
def test_shipped_cases_keep_their_pins_inside_the_undercut_limit(name):
    cs = case(name)
    a = profile_args(cs)
    assert a["Rr"] < cl.min_convex_radius_mm(a["R"], a["E"], a["zp"])


# ----------------------------------------------------------------------------- the kernel's two forms
def pin_points(cs, psi, disc_rotation_rad=0.0):
    """Actual pin centres in the disc frame (DESIGN.md pose), as clearance.pin_contacts places them."""
    c = cs.cycloid
    theta = -psi / c.zc + disc_rotation_rad
    rel = cl.pin_centres_mm(cs) - c.eccentricity_mm * np.array([np.cos(psi), np.sin(psi)])
    ct, st = np.cos(-theta), np.sin(-theta)
    return ct * rel[:, 0] - st * rel[:, 1], st * rel[:, 0] + ct * rel[:, 1]


def dense_distance(qx, qy, R, E, zp):
    """Reference: |c(t) - q| minimised directly over u = t - t_i, bounded around the best t_i of
    400000 samples (xatol 1e-15 rad; u near 0 keeps Brent's relative tolerance from limiting
    it); independent of the Newton kernels."""
    tg = np.linspace(0, 2 * np.pi, 400000, endpoint=False)
    xg, yg = pp.theoretical_curve(tg, R, E, zp)
    out = []
    for x, y in zip(qx, qy):
        i = np.argmin((xg - x) ** 2 + (yg - y) ** 2)
        f = lambda u: math.hypot(*(np.array(pp.theoretical_curve(tg[i] + u, R, E, zp)) - (x, y)))  # noqa: E731
        out.append(minimize_scalar(f, bounds=(-2e-5, 2e-5), method="bounded",
                                   options={"xatol": 1e-15}).fun)
    return np.array(out)


@pytest.mark.parametrize("psi, turn", [(0.0, 0.0), (0.37, 0.0), (0.1, 3e-4), (0.1, -3e-4)])
def test_scalar_and_vectorised_foot_points_agree_with_a_dense_minimisation_at_high_K1(psi, turn):
    # K1 = 0.95, dR = -1 um, dRr = +1 um, disc turned by +-1 arcmin (a loaded pin): both forms,
    # seeded from 2..64 grid points per tooth, give the same foot point, and |s| is the distance a
    # direct minimisation finds, to 1e-9 mm (measured ~4e-14 mm)
    cs = hard_case()
    a = profile_args(cs)
    R, E, zp = a["R"], a["E"], a["zp"]
    qx, qy = pin_points(cs, psi, turn)
    vec = pp.nearest(qx, qy, R, E, zp)
    assert np.max(np.abs(np.abs(vec.distance_mm) - dense_distance(qx, qy, R, E, zp))) < 1e-9
    for n in (2, 4, 16, 64):
        seeds = pp.seed_parameters(qx, qy, R, E, zp, 0.0, n)
        sc = np.array([pp.foot_point(x, y, R, E, zp, t) for x, y, t in zip(qx, qy, seeds)])
        assert np.all(sc[:, 5] == 1.0), f"{n} per tooth: Newton did not settle"
        assert np.max(np.abs(sc[:, 1] - vec.distance_mm)) < 1e-9
        assert np.max(np.abs(sc[:, 2:4] - vec.normal)) < 1e-9
        assert np.allclose(sc[:, 4], vec.curvature_per_mm, rtol=1e-9, atol=0)
        assert np.allclose(sc[:, 4], pp.curvature_per_mm(sc[:, 0], R, E, zp), rtol=1e-9, atol=0)
        other = pp.nearest(qx, qy, R, E, zp, samples_per_tooth=n)
        assert np.max(np.abs(other.distance_mm - vec.distance_mm)) < 1e-12


@pytest.mark.parametrize("outside_um", [7.0, 20.0])
def test_a_pin_outside_a_sharp_root_finds_its_flank_not_the_root_point(outside_um):
    # K1 = 0.95: c's root radius is (R - E zp)^2 / (E zp^2 - R) = 4.3 um; a pin on the root axis
    # farther out than that sees two flank minima and a maximum at the root itself. Seeded at the
    # root (t = 0: g = 0 exactly), a plain Newton stays there and reports the root distance
    # (7 um instead of 6.504 um, 20 um instead of 13.10 um); both forms must find a flank (dense
    # minimisation, 1e-9 mm)
    R, E, zp = 64.0, 1.52, 40
    q = (R - E + outside_um * 1e-3, 0.0)
    ref = dense_distance([q[0]], [q[1]], R, E, zp)[0]
    assert ref < outside_um * 1e-3 - 1e-4
    sc = pp.foot_point(q[0], q[1], R, E, zp, 0.0)
    assert sc[5] and sc[1] == pytest.approx(ref, abs=1e-9)
    assert pp.nearest([q[0]], [q[1]], R, E, zp).distance_mm[0] == pytest.approx(ref, abs=1e-9)


def test_points_near_c_get_the_same_foot_from_every_seed_grid():
    # 4000 points within +-2 mm of c at K1 = 0.95: inside the disc (below c's smallest convex
    # radius, 2.47 mm) each has one nearest point, c(t0) itself, so s is known exactly; outside,
    # near the sharp roots, two flanks compete. Scalar and vectorised forms, 4 or 64 seeds per
    # tooth, agree with each other to 1e-9 mm (measured 5e-14) and inside with s
    R, E, zp = 63.999, 1.52, 40
    rng = np.random.default_rng(3)
    t0, s = rng.uniform(0, 2 * np.pi, 4000), rng.uniform(-2.0, 2.0, 4000)
    cx, cy = pp.theoretical_curve(t0, R, E, zp)
    dx, dy = pp.theoretical_curve(t0, R, E, zp, derivative=1)
    sp = np.hypot(dx, dy)
    qx, qy = cx - dy / sp * s, cy + dx / sp * s
    ref = pp.nearest(qx, qy, R, E, zp).distance_mm
    inside = s < 0
    assert np.allclose(ref[inside], s[inside], atol=1e-9, rtol=0)
    for n in (4, 64):
        seeds = pp.seed_parameters(qx, qy, R, E, zp, 0.0, n)
        sc = np.array([pp.foot_point(x, y, R, E, zp, t) for x, y, t in zip(qx, qy, seeds)])
        assert np.all(sc[:, 5] == 1.0)
        assert np.allclose(sc[:, 1], ref, atol=1e-9, rtol=0)
        assert np.allclose(pp.nearest(qx, qy, R, E, zp, samples_per_tooth=n).distance_mm, ref,
                           atol=1e-9, rtol=0)


def test_the_windowed_seed_search_picks_what_a_full_distance_matrix_picks():
    # random points anywhere (the disc centre included), a rotated profile, three pin counts
    rng = np.random.default_rng(7)
    for zp, E in ((40, 1.3), (40, 1.52), (100, 0.5)):
        R, rot = 64.0, 0.3
        q = np.vstack([rng.uniform(-70, 70, (1500, 2)), rng.normal(0, 2, (100, 2)), [[0.0, 0.0]]])
        n = 16 * (zp - 1)
        tg = np.linspace(0, 2 * np.pi, n, endpoint=False)
        xg, yg = pp.theoretical_curve(tg, R, E, zp, rot)
        full = tg[np.argmin((xg[None] - q[:, :1]) ** 2 + (yg[None] - q[:, 1:]) ** 2, axis=1)]
        assert np.array_equal(pp.seed_parameters(q[:, 0], q[:, 1], R, E, zp, rot, 16), full)


def test_the_seed_search_memory_does_not_grow_with_the_grid():
    # the CAD deviation check of a 120-pin disc: 47600 points against 7616 seeds is a 2.9 GB
    # distance matrix; in blocks the search peaks at a few tens of MB (bound 150 MB)
    import tracemalloc
    zp = 120
    R, E = 64.0, 0.8125 * 64.0 / zp
    t = np.linspace(0, 2 * np.pi, (zp - 1) * 400, endpoint=False)
    x, y = cycloid_xy(t, R, 0.4, E, zp)
    tracemalloc.start()
    try:
        d = pp.nearest(x, y, R, E, zp).distance_mm + 0.4
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert np.max(np.abs(d)) < 1e-9
    assert peak < 150e6, f"peak {peak / 1e6:.0f} MB"
