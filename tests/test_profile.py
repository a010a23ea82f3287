"""The profile kernel: the verified cycloid form of DESIGN.md, its modifications and curvature."""
from pathlib import Path

import numpy as np
import pytest

from geometry.params import load_case
from geometry.pin_profile import (curvature_per_mm, min_convex_radius_mm,
                                  profile_curvature_radius_mm, theoretical_curve)
from geometry.profile import cycloid_xy, disc_profile, profile_args

CASES = Path(__file__).resolve().parents[1] / "cases"
NAMES = ("rv40e-105", "rv40e-81", "rv160n-81")


def case(name="rv40e-105"):
    return load_case(CASES / f"{name}.toml")


@pytest.mark.parametrize("name", NAMES)
def test_the_profile_runs_from_root_radius_to_tip_radius(name):
    # DESIGN.md: radius R - E - Rr at the root (t = 0) to R + E - Rr at the tip (t = pi / zc);
    # closed form, to rounding (1e-9 mm)
    c = case(name).cycloid
    x, y = cycloid_xy(np.array([0.0, np.pi / c.zc]), **profile_args(case(name), modified=False))
    R, E, Rr = c.pin_circle_radius_mm, c.eccentricity_mm, c.pin_radius_mm
    assert np.hypot(x, y) == pytest.approx([R - E - Rr, R + E - Rr], abs=1e-9)
    r = np.hypot(*disc_profile(case(name), n=20000, modified=False).T)
    assert r.min() >= R - E - Rr - 1e-9 and r.max() <= R + E - Rr + 1e-9


def test_offset_and_equidistant_replace_R_and_Rr():
    # DESIGN.md: dR and dRr replace R and Rr, so root = R + dR - E - (Rr + dRr), exactly
    cs = case()
    m, c = cs.modification, cs.cycloid
    x, y = cycloid_xy(np.array([0.0]), **profile_args(cs))
    assert np.hypot(x, y)[0] == pytest.approx(c.pin_circle_radius_mm + m.offset_mm - c.eccentricity_mm
                                              - c.pin_radius_mm - m.equidistant_mm, abs=1e-12)


@pytest.mark.parametrize("name", NAMES)
def test_the_profile_is_the_pin_centre_curve_offset_inward_by_the_pin_radius(name):
    # the envelope of the pins: every profile point lies Rr from the pin-centre curve, along its
    # normal, on the disc side (the curve runs clockwise, outward = left); to rounding (1e-9 mm)
    a = profile_args(case(name))
    t = np.linspace(0, 2 * np.pi, 50001)
    px, py = cycloid_xy(t, **a)
    cx, cy = theoretical_curve(t, a["R"], a["E"], a["zp"], a["rotation_rad"])
    dx, dy = theoretical_curve(t, a["R"], a["E"], a["zp"], a["rotation_rad"], derivative=1)
    ox, oy = cx - px, cy - py
    assert np.hypot(ox, oy) == pytest.approx(a["Rr"], abs=1e-9)
    assert np.max(np.abs(ox * dx + oy * dy) / np.hypot(dx, dy)) < 1e-9
    assert np.all(dx * oy - dy * ox > 0)


def test_the_profile_repeats_every_tooth():
    # zc-fold symmetry: p(t + 2 pi / zc) is p(t) turned clockwise by one tooth pitch (to 1e-9 mm)
    cs = case()
    zc = cs.cycloid.zc
    t = np.linspace(0, 2 * np.pi, 997)
    x0, y0 = cycloid_xy(t, **profile_args(cs))
    x1, y1 = cycloid_xy(t + 2 * np.pi / zc, **profile_args(cs))
    a = -2 * np.pi / zc
    assert np.allclose(np.cos(a) * x0 - np.sin(a) * y0, x1, atol=1e-9)
    assert np.allclose(np.sin(a) * x0 + np.cos(a) * y0, y1, atol=1e-9)


def test_the_rotation_modification_turns_the_profile_about_the_disc_centre():
    cs = case().replace("modification", rotation_deg=0.5)
    t = np.linspace(0, 2 * np.pi, 101)
    a = profile_args(cs)
    x, y = cycloid_xy(t, **(a | {"rotation_rad": 0.0}))
    xr, yr = cycloid_xy(t, **a)
    d = np.deg2rad(0.5)
    assert np.allclose(xr, np.cos(d) * x - np.sin(d) * y, atol=1e-12)
    assert np.allclose(yr, np.sin(d) * x + np.cos(d) * y, atol=1e-12)


def test_disc_profile_is_closed_and_clockwise():
    p = disc_profile(case(), n=2000)
    assert p.shape == (2001, 2) and np.allclose(p[0], p[-1], atol=1e-12)
    assert np.sum(p[:-1, 0] * p[1:, 1] - p[1:, 0] * p[:-1, 1]) < 0     # negative shoelace


def test_the_shoelace_area_converges_at_second_order():
    # a polygon through the curve misses area ~ h^2 (the basis of the Richardson step used for
    # the disc-volume reference): measured rate -2 +- 0.1 over n = 2^10..2^14
    ns = 2 ** np.arange(10, 15)

    def area(n):
        p = disc_profile(case(), n=int(n))
        return -0.5 * np.sum(p[:-1, 0] * p[1:, 1] - p[1:, 0] * p[:-1, 1])
    exact = area(2**18)
    rate = np.polyfit(np.log(ns), np.log([abs(exact - area(n)) for n in ns]), 1)[0]
    assert rate == pytest.approx(-2.0, abs=0.1)


@pytest.mark.parametrize("name", NAMES)
def test_pin_centre_curve_curvature_matches_its_closed_forms_at_root_and_tip(name):
    # root (t = 0): c' = (0, -(R - E zp)), c'' = (E zp^2 - R, 0): concave, rho = (R - E zp)^2 / (E zp^2 - R);
    # tip (t = pi / zc, phi = pi): convex, rho = R (1 + K1)^2 / (1 + zp K1), K1 = E zp / R
    # (from rho0 = R S^3 / (K1 (1 + zp) cos phi - (1 + zp K1^2)), S = 1 + K1); to 1e-9 relative
    c = case(name).cycloid
    R, E, zp = c.pin_circle_radius_mm, c.eccentricity_mm, c.zp
    k1 = E * zp / R
    k = curvature_per_mm(np.array([0.0, np.pi / c.zc]), R, E, zp)
    assert k[0] == pytest.approx(-(E * zp**2 - R) / (R - E * zp) ** 2, rel=1e-9)
    assert k[1] == pytest.approx((1 + zp * k1) / (R * (1 + k1) ** 2), rel=1e-9)


@pytest.mark.parametrize("zp", [10, 40, 120])
@pytest.mark.parametrize("k1", [0.3, 0.5, 0.8125, 0.95, 0.99])
def test_the_smallest_convex_radius_closed_form_matches_brute_force(k1, zp):
    # closed form (geometry.pin_profile: stationary point of R S^3 / (a - b cos phi), or the tip)
    # against 200001 samples of one tooth: never above it, and equal to 1e-8 relative (measured
    # 2e-10; the samples miss the minimum by ~h^2)
    R = 64.0
    E = k1 * R / zp
    t = np.linspace(0, 2 * np.pi / (zp - 1), 200001)
    brute = 1 / curvature_per_mm(t, R, E, zp).max()
    rho = min_convex_radius_mm(R, E, zp)
    assert rho <= brute * (1 + 1e-12)
    assert rho == pytest.approx(brute, rel=1e-8)


def test_the_profile_curvature_radius_is_the_centre_curve_radius_minus_the_pin_radius():
    # the inward offset by Rr shortens a convex radius and lengthens a concave one: rho_p = 1/kappa - Rr
    # (signed, > 0 convex); checked against the curvature of cycloid_xy itself by central
    # differences (h = 1e-5 rad: measured 1.7e-6 relative, truncation and rounding), bound 1e-5
    a = profile_args(case())
    t = np.linspace(0.01, 2 * np.pi / 39 - 0.01, 37)
    h = 1e-5
    (x0, y0), (xp, yp), (xm, ym) = (cycloid_xy(t + d, **a) for d in (0.0, h, -h))
    dx, dy = (xp - xm) / (2 * h), (yp - ym) / (2 * h)
    ddx, ddy = (xp - 2 * x0 + xm) / h ** 2, (yp - 2 * y0 + ym) / h ** 2
    fd = -(dx * ddy - dy * ddx) / np.hypot(dx, dy) ** 3           # clockwise: convex > 0
    rho = profile_curvature_radius_mm(curvature_per_mm(t, a["R"], a["E"], a["zp"]), a["Rr"])
    assert np.allclose(1 / rho, fd, rtol=1e-5, atol=0)
    assert np.any(rho > 0) and np.any(rho < 0)
    assert profile_curvature_radius_mm(np.array([0.0]), 3.0)[0] == np.inf
