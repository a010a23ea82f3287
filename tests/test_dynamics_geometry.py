"""Pin gaps from the actual profile: the compiled foot point of the dynamics kernels
(`geometry.pin_profile.foot_point` compiled by `dynamics.couplings.base`) against brute force and
against the geometry reference (`geometry.clearance` gaps) at the hard end (K1 = E zp / R = 0.95,
micron clearances), and conjugacy of the unmodified profile."""
import math

import numpy as np
import pytest
from scipy.optimize import minimize_scalar

from dynamics.couplings.base import foot_point
from dynamics.model import build_model, evaluate
from geometry import clearance as cl
from geometry.profile import cycloid_xy
from support import case_path, stiffness_for_tests


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


def _hard_case(dR_mm=-0.001, dRr_mm=0.001):
    """RV-40E with K1 = 0.95 (E = 1.52 mm) and micron modifications; pin radius 2 mm because the
    tips' convex radius is only 2.47 mm at this K1 (no undercut)."""
    from geometry.params import load_case
    return load_case(case_path("rv40e-105")).replace("cycloid", eccentricity_mm=1.52, pin_radius_mm=2.0) \
        .replace("modification", offset_mm=dR_mm, equidistant_mm=dRr_mm)


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
        t, s, nx, ny, _, ok = foot_point(pb[0], pb[1], R + dR, E, float(zp), alpha - 2 * np.pi * k / zp)
        assert ok
        gap = s + (Rr + dRr) - Rr
        brute = _brute_gap(pb[0], pb[1], R + dR, Rr + dRr, E, zp, Rr)
        assert gap == pytest.approx(brute, abs=1e-9), (K1, psi, k)
        assert 0 < gap < 10e-6     # a clearance of microns, no phantom interference


@pytest.mark.parametrize("dR_mm, dRr_mm", [(-0.001, 0.001), (-0.003, 0.0), (0.0, 0.002)])
def test_the_dynamics_pin_gaps_are_the_geometry_reference_gaps_at_k1_095_and_micron_clearances(dR_mm, dRr_mm):
    # the whole dynamics path (pose -> disc frame -> compiled foot point -> gap, in metres) against
    # geometry.clearance (vectorised bracketed Newton, mm) in the conjugate pose: both solve the
    # same equation to machine precision, so 1e-12 m (1e-9 mm) on gaps of 1-4 um
    cs = _hard_case(dR_mm, dRr_mm)
    assert cs.cycloid.eccentricity_mm * cs.cycloid.zp / cs.cycloid.pin_circle_radius_mm == pytest.approx(0.95)
    model = build_model(cs, stiffness_for_tests(cs))
    disc, zc, E = model.layout["disc"], cs.cycloid.zc, cs.cycloid.eccentricity_mm * 1e-3
    for psi in np.linspace(0.0, 2 * np.pi, 7, endpoint=False) + 0.1:
        q = np.zeros(model.n_dof)
        for d in range(model.n_disc):
            q[disc.index(d, "x")], q[disc.index(d, "y")] = E * math.cos(psi + math.pi * d), E * math.sin(psi + math.pi * d)
            q[disc.index(d, "rot")] = -psi / zc
        w, _ = evaluate(model, q, 0.0)
        gaps = model.contacts(w.gap)
        for d in range(model.n_disc):
            ref_mm = cl.pin_contacts(cs, psi + math.pi * d).gap_mm
            assert np.abs(gaps[d] - 1e-3 * ref_mm).max() < 1e-12, (psi, d)
            assert 0.0 < gaps[d].min() < 5e-6          # micron clearance, no phantom interference


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
            _, s, _, _, _, ok = foot_point(pb[0], pb[1], R, E, float(zp), alpha - th)
            assert ok and abs(s) < 1e-12


def test_profile_is_the_inward_offset_of_the_pin_centre_curve_along_the_kernel_normal():
    zp, R, Rr, E = 40, 64e-3, 3e-3, 1.3e-3
    for t in np.linspace(0.1, 6.2, 9):
        cx, cy = R * math.cos(t) - E * math.cos(zp * t), -R * math.sin(t) + E * math.sin(zp * t)
        _, s, nx, ny, _, _ = foot_point(cx, cy, R, E, float(zp), t)
        x, y = cycloid_xy(t, R, Rr, E, zp)
        assert abs(s) < 1e-15 and math.hypot(cx - Rr * nx - x, cy - Rr * ny - y) < 1e-12


@pytest.mark.parametrize("K1", [0.5, 0.81, 0.95])
def test_a_seed_near_the_foot_finishes_by_taylor_series_with_one_trig_set_and_the_converged_foot(K1, monkeypatch):
    """A seed within ~1e-8 rad of the foot: one evaluation of c, c', c'' and the Newton step, then
    c, c', c'' at the stepped parameter by their Taylor series (geometry.pin_profile.foot_point);
    the result equals a Newton converged from far (1e-3 rad off, several evaluations) to
    1e-13 rad in t, 1e-15 m in s and 1e-12 in the normal (its turn over the t difference)."""
    import geometry.pin_profile as pp
    zp, R = 40, 64e-3
    E = K1 * R / zp
    calls = {"cos": 0}

    class _Counting:
        def __getattr__(self, name):
            return getattr(math, name)

        @staticmethod
        def cos(x):
            calls["cos"] += 1
            return math.cos(x)
    rng = np.random.default_rng(11)
    taylor = 0
    for _ in range(40):
        t0 = rng.uniform(-np.pi, np.pi)
        cx, cy, dx, dy, _, _ = pp.curve(t0, R, E, zp)
        sp = math.hypot(dx, dy)
        gap = rng.uniform(-20e-6, 50e-6)
        px, py = cx - dy / sp * gap, cy + dx / sp * gap     # on the outward normal of c at t0
        ref = pp.foot_point(px, py, R, E, zp, t0 + 1e-3)
        assert ref[5]
        monkeypatch.setattr(pp, "math", _Counting())
        calls["cos"] = 0
        near = pp.foot_point(px, py, R, E, zp, ref[0] + rng.uniform(-1e-8, 1e-8))
        monkeypatch.setattr(pp, "math", math)
        assert near[5]
        taylor += calls["cos"] == 2                         # cos(zp t), cos(t): one set
        assert abs(near[0] - ref[0]) < 1e-13
        assert abs(near[1] - ref[1]) < 1e-15
        assert abs(near[2] - ref[2]) < 1e-12 and abs(near[3] - ref[3]) < 1e-12
        assert near[4] == pytest.approx(ref[4], rel=1e-9)
    assert taylor >= 30, f"the Taylor finish took {taylor} of 40 near seeds"
