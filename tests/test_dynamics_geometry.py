"""Pin gaps from the actual profile: the foot-point Newton against brute force at the hard end
(K1 = E zp / R = 0.95, micron clearances), and conjugacy of the unmodified profile."""
import math

import numpy as np
import pytest
from scipy.optimize import minimize_scalar

from dynamics.kernels import foot_point
from geometry.profile import cycloid_xy


def _brute_gap(px, py, R, Rr, E, zp, rpin):
    """Distance from (px, py) to the actual profile (geometry.profile.cycloid_xy) minus the pin
    radius: dense sampling, then a bounded scalar minimisation around the best sample."""
    t = np.linspace(0, 2 * np.pi, 400_001)
    x, y = cycloid_xy(t, R, Rr, E, zp)
    i = np.argmin((x - px) ** 2 + (y - py) ** 2)
    h = t[1] - t[0]
    fun = lambda s: math.hypot(*(np.array(cycloid_xy(s, R, Rr, E, zp)) - (px, py)))  # noqa: E731
    best = minimize_scalar(fun, bounds=(t[i] - 2 * h, t[i] + 2 * h), method="bounded",
                           options={"xatol": 1e-13})
    return best.fun - rpin


def _min_convex_radius(R, E, zp):
    """Smallest convex curvature radius of the pin-centre curve c(t) (undercut if Rr exceeds it)."""
    t = np.linspace(0, 2 * np.pi / (zp - 1), 20001)
    dx, dy = -R * np.sin(t) + E * zp * np.sin(zp * t), -R * np.cos(t) + E * zp * np.cos(zp * t)
    ddx, ddy = -R * np.cos(t) + E * zp ** 2 * np.cos(zp * t), R * np.sin(t) - E * zp ** 2 * np.sin(zp * t)
    kappa = -(dx * ddy - dy * ddx) / (dx * dx + dy * dy) ** 1.5     # clockwise curve: convex > 0
    return 1.0 / kappa[kappa > 0].max()


@pytest.mark.parametrize("K1", [0.5, 0.81, 0.95])
def test_gap_matches_brute_force_to_a_nanometre_at_micron_clearances(K1):
    zp, R = 40, 64e-3
    E = K1 * R / zp
    Rr = min(3e-3, 0.5 * _min_convex_radius(R, E, zp))   # no undercut: the profile is well defined
    dR, dRr = -2e-6, 1e-6          # modification of a micron: the hard end for any discretisation
    rng = np.random.default_rng(7)
    for _ in range(6):
        psi = rng.uniform(0, 2 * np.pi)
        k = rng.integers(zp)
        alpha = -psi / (zp - 1)
        P = R * np.array([math.cos(2 * np.pi * k / zp), math.sin(2 * np.pi * k / zp)])
        c = E * np.array([math.cos(psi), math.sin(psi)])
        ca, sa = math.cos(alpha), math.sin(alpha)
        w = P - c
        pb = np.array([ca * w[0] + sa * w[1], -sa * w[0] + ca * w[1]])
        t, s, nx, ny, ok = foot_point(pb[0], pb[1], R + dR, E, float(zp), alpha - 2 * np.pi * k / zp)
        assert ok
        gap = s + (Rr + dRr) - Rr
        brute = _brute_gap(pb[0], pb[1], R + dR, Rr + dRr, E, zp, Rr)
        assert gap == pytest.approx(brute, abs=1e-9), (K1, psi, k)
        assert 0 < gap < 10e-6     # a clearance of microns, no phantom interference


def test_unmodified_profile_touches_every_pin_at_every_crank_angle():
    # DESIGN.md check: distance pin centre to profile = Rr to 1e-6 mm (we get ~1e-15 m)
    zp, R, E = 40, 64e-3, 1.3e-3
    for psi in np.linspace(0, 2 * np.pi, 7):
        alpha = -psi / (zp - 1)
        c = E * np.array([math.cos(psi), math.sin(psi)])
        for k in range(zp):
            th = 2 * np.pi * k / zp
            w = R * np.array([math.cos(th), math.sin(th)]) - c
            pb = (math.cos(alpha) * w[0] + math.sin(alpha) * w[1], -math.sin(alpha) * w[0] + math.cos(alpha) * w[1])
            _, s, _, _, ok = foot_point(pb[0], pb[1], R, E, float(zp), alpha - th)
            assert ok and abs(s) < 1e-12


def test_profile_is_the_inward_offset_of_the_pin_centre_curve_along_the_kernel_normal():
    zp, R, Rr, E = 40, 64e-3, 3e-3, 1.3e-3
    for t in np.linspace(0.1, 6.2, 9):
        cx, cy = R * math.cos(t) - E * math.cos(zp * t), -R * math.sin(t) + E * math.sin(zp * t)
        _, s, nx, ny, _ = foot_point(cx, cy, R, E, float(zp), t)
        x, y = cycloid_xy(t, R, Rr, E, zp)
        assert abs(s) < 1e-15 and math.hypot(cx - Rr * nx - x, cy - Rr * ny - y) < 1e-12
