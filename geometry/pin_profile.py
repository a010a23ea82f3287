"""The one cycloid-pin geometry kernel: pin-centre curve, foot point, signed gap, normal, curvature.

The disc profile is the inward offset, by the pin radius, of the pin-centre curve
    c(t) = Rot(delta) (R cos t - E cos(zp t), -R sin t + E sin(zp t))       (disc frame, mm)
(DESIGN.md's profile `geometry.profile.cycloid_xy` is exactly c(t) - Rr n(t), R and Rr modified).
Offset curves share their normals, so a pin centre q has its foot point on the profile at the
parameter t* of its foot point on c, the root of g(t) = (c(t) - q) . c'(t) at the nearest point.
With s = (q - c(t*)) . n(t*) the signed distance of q from c along the outward normal n (> 0 outside
the disc), the pin-to-profile gap is s + Rr_profile - Rr_pin (0 tangent, < 0 interference).

Two forms of the same computation, held to the same reference by tests/test_clearance.py:
- `foot_point`: scalar, written in the subset of Python numba compiles, so the dynamics kernels
  compile this very function (`numba.njit(foot_point)`) instead of keeping a copy; damped Newton
  from a seed the caller gives (the previous time step's t, or `seed_parameters`).
- `foot_parameters` / `nearest`: vectorised (geometry, fem): the seed is the nearest of
  `samples_per_tooth` grid points per tooth, then a Newton iteration bracketed by the seed's grid
  neighbours (bisection when Newton leaves the bracket) to machine precision. The grid only picks
  the basin; gaps agree to 1e-12 mm for 4..64 points per tooth at K1 = 0.95 and micron gaps.
  The nearest grid point is searched in a window of polar angle that provably contains it (c(t)
  turns monotonically about the disc centre), in blocks of bounded size: memory and time grow
  with the number of points times the window, not times the grid (a 400-pin disc's CAD check
  asked 30 GiB of a full distance matrix).

Curvature (closed form, from c' and c''): with K1 = E zp / R, phi = (zp - 1) t, x = cos phi,
S = sqrt(1 + K1^2 - 2 K1 x), the signed curvature of c is
    kappa = (1 + zp K1^2 - K1 (1 + zp) x) / (R S^3)       (> 0 convex, where the disc bulges out),
and the profile's curvature radius is 1 / kappa - Rr (same sign convention: the inward offset
shortens a convex radius and lengthens a concave one).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

NEWTON_STEP_MAX_RAD = 0.02   # limits a Newton step to well inside one tooth (2 pi / zc ~ 0.16 rad)
NEWTON_TOL_RAD = 1e-14
NEWTON_ESCAPE_RAD = 1e-6     # first downhill step where the distance is concave (doubles while it stays so)
NEWTON_ITER_MAX = 100
NEWTON_TAYLOR_MAX_RAD = 1e-6   # largest last step finished by Taylor series (see foot_point)


def curve(t, R, E, zp):
    """c(t), c'(t), c''(t) as six floats (x, y, dx, dy, ddx, ddy)."""
    czt, szt = math.cos(zp * t), math.sin(zp * t)
    ct, st = math.cos(t), math.sin(t)
    return (R * ct - E * czt, -R * st + E * szt,
            -R * st + E * zp * szt, -R * ct + E * zp * czt,
            -R * ct + E * zp * zp * czt, R * st - E * zp * zp * szt)


def foot_point(px, py, R, E, zp, t):
    """Foot parameter on c(t) nearest (px, py): safeguarded Newton from the seed t on
    g(t) = (c - q) . c' (self-contained: numba compiles it without the helpers of this module).

    Where g' <= 0 the distance is concave (near a local maximum: a point outside a sharp root of c,
    farther from it than the root's radius of curvature, sees one minimum on each flank), so the
    step goes downhill, doubling while that lasts, instead of crawling; once g has changed sign
    between two iterates, the minimum is bracketed and a Newton step leaving the bracket is
    replaced by bisection. Any length unit (mm or m): only t is in radians.

    Returns (t, s, nx, ny, kappa, ok): s the signed distance of the point from c along the
    outward normal (nx, ny) (> 0 outside the disc), kappa the signed curvature of c at t
    (> 0 where the disc is convex), ok False when Newton did not settle on a minimum.
    """
    ok = False
    lo, hi = -math.inf, math.inf      # g(lo) < 0 < g(hi) once both are known: a minimum between
    escape = 0.0
    cx = cy = dx = dy = ddx = ddy = 0.0   # (typed before the loop: numba inlines this function)
    for _ in range(NEWTON_ITER_MAX):
        czt, szt, ct, st = math.cos(zp * t), math.sin(zp * t), math.cos(t), math.sin(t)
        cx, cy = R * ct - E * czt, -R * st + E * szt
        dx, dy = -R * st + E * zp * szt, -R * ct + E * zp * czt
        ddx, ddy = -R * ct + E * zp * zp * czt, R * st - E * zp * zp * szt
        rx, ry = cx - px, cy - py
        g = rx * dx + ry * dy
        speed2 = dx * dx + dy * dy
        h = speed2 + rx * ddx + ry * ddy
        if g < 0.0 and lo < t < hi:
            lo = t
        elif g > 0.0 and lo < t < hi:
            hi = t
        if h > 0.0:
            step = -g / h
            escape = 0.0
        else:                             # concave here: go downhill (any way when g = 0 exactly)
            escape = max(2.0 * escape, abs(g) / speed2, NEWTON_ESCAPE_RAD)
            step = escape if g <= 0.0 else -escape
        if step > NEWTON_STEP_MAX_RAD:
            step = NEWTON_STEP_MAX_RAD
        elif step < -NEWTON_STEP_MAX_RAD:
            step = -NEWTON_STEP_MAX_RAD
        # converged after this step: Newton's quadratic model puts t + step within
        # |g''| step^2 / (2 h) of the root; below NEWTON_TOL_RAD that is the accuracy the test below
        # gives, and c, c', c'' at t + step follow from their Taylor series at t (c''' costs no
        # trigonometry; truncated at c'''' ~ E zp^4: at |step| <= 1e-6 < 1e-21 m in c, ~zp^3 step^3
        # relative in c' and ~zp^2 step^2 / 2 in c'', which feeds only the curvature): one sin/cos
        # set a pin fewer wherever the seed is already close (the dynamics' Newton iterations)
        if h > 0.0 and abs(step) <= NEWTON_TAYLOR_MAX_RAD and lo < t + step < hi:
            dddx, dddy = R * st - E * zp * zp * zp * szt, R * ct - E * zp * zp * zp * czt
            g2 = 3.0 * (dx * ddx + dy * ddy) + rx * dddx + ry * dddy
            if abs(g2) * step * step < 2.0 * NEWTON_TOL_RAD * h:
                t += step
                s2, s3 = 0.5 * step * step, step * step * step / 6.0
                cx, cy = cx + dx * step + ddx * s2 + dddx * s3, cy + dy * step + ddy * s2 + dddy * s3
                dx, dy = dx + ddx * step + dddx * s2, dy + ddy * step + dddy * s2
                ddx, ddy = ddx + dddx * step, ddy + dddy * step
                ok = True
                break
        tn = t + step
        # <=: a converged step rounds to tn = t, which is lo or hi itself; strict bounds bisected
        # there (8.4 instead of 3.8 iterations per pin in the dynamics, issue 10 task A)
        if lo > -math.inf and hi < math.inf and not lo <= tn <= hi:
            tn = 0.5 * (lo + hi)
        # converged at t: its c, c', c'' just computed are the answer (a step below 1e-14 rad moves
        # the foot < 1e-15 m), which saves one of ~4 sin/cos sets a pin in the dynamics
        if abs(tn - t) < NEWTON_TOL_RAD:
            ok = h > 0.0
            break
        t = tn
    if not ok:                            # out of iterations, or converged where concave: at the last t
        czt, szt, ct, st = math.cos(zp * t), math.sin(zp * t), math.cos(t), math.sin(t)
        cx, cy = R * ct - E * czt, -R * st + E * szt
        dx, dy = -R * st + E * zp * szt, -R * ct + E * zp * czt
        ddx, ddy = -R * ct + E * zp * zp * czt, R * st - E * zp * zp * szt
    speed = math.sqrt(dx * dx + dy * dy)
    nx, ny = -dy / speed, dx / speed      # c(t) runs clockwise: its left side is outward
    s = (px - cx) * nx + (py - cy) * ny
    kappa = -(dx * ddy - dy * ddx) / speed ** 3
    return t, s, nx, ny, kappa, ok


# ----------------------------------------------------------------------------- vectorised forms
SEED_BLOCK_ELEMENTS = 1 << 20   # candidate distances held at once by the seed search (~8 MB each array)


def theoretical_curve(t: np.ndarray, R: float, E: float, zp: int, rotation_rad: float = 0.0,
                      derivative: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """Pin-centre curve c(t) of the profile (or its 1st/2nd derivative in t), disc frame [mm]."""
    t = np.asarray(t, dtype=float)
    ct, st, cz, sz = np.cos(t), np.sin(t), np.cos(zp * t), np.sin(zp * t)
    if derivative == 0:
        x, y = R * ct - E * cz, -R * st + E * sz
    elif derivative == 1:
        x, y = -R * st + E * zp * sz, -R * ct + E * zp * cz
    elif derivative == 2:
        x, y = -R * ct + E * zp**2 * cz, R * st - E * zp**2 * sz
    else:
        raise ValueError(f"derivative = {derivative}: allowed 0, 1, 2")
    if rotation_rad:
        c, s = math.cos(rotation_rad), math.sin(rotation_rad)
        x, y = c * x - s * y, s * x + c * y
    return x, y


def curvature_per_mm(t: np.ndarray, R: float, E: float, zp: int) -> np.ndarray:
    """Signed curvature of c(t), > 0 where the disc is convex (centre of curvature inside)."""
    dx, dy = theoretical_curve(t, R, E, zp, derivative=1)
    ddx, ddy = theoretical_curve(t, R, E, zp, derivative=2)
    # c(t) runs clockwise, so the usual (x'y'' - y'x'') is negative on convex parts
    return -(dx * ddy - dy * ddx) / np.hypot(dx, dy) ** 3


def profile_curvature_radius_mm(kappa_per_mm: np.ndarray, pin_radius_mm: float) -> np.ndarray:
    """Signed curvature radius of the profile (inward offset of c by the pin radius) from the
    curvature of c at the same parameter: 1 / kappa - Rr (> 0 convex, +-inf where kappa = 0)."""
    k = np.asarray(kappa_per_mm, float)
    with np.errstate(divide="ignore"):
        return np.where(k != 0, (1.0 - pin_radius_mm * k) / np.where(k != 0, k, 1.0),
                        np.copysign(np.inf, 1.0 - pin_radius_mm * k))


def min_convex_radius_mm(R: float, E: float, zp: int) -> float:
    """Smallest radius of curvature of c(t) where the disc is convex [mm] (closed form).

    rho(x) = R S^3 / (a - b x), a = 1 + zp K1^2, b = K1 (1 + zp), x = cos phi, convex where
    a > b x (always at the tip, x = -1). d ln rho / dx = 0 has the single root
    x* = 3 a / b - (1 + K1^2) / K1, so the minimum is at x*, if it lies in the convex range, or
    at an end of it (x = -1, and x = 1 when the whole curve is convex)."""
    k1 = E * zp / R
    a, b = 1.0 + zp * k1 * k1, k1 * (1.0 + zp)

    def rho(x: float) -> float:
        return R * (1.0 + k1 * k1 - 2.0 * k1 * x) ** 1.5 / (a - b * x)

    cands = [-1.0] + ([1.0] if a > b else [])
    if k1 > 0:
        xs = 3.0 * a / b - (1.0 + k1 * k1) / k1
        if -1.0 < xs < min(1.0, a / b):
            cands.append(xs)
    return min(rho(x) for x in cands)


@lru_cache(maxsize=32)
def _seed_grid(R: float, E: float, zp: int, rotation_rad: float, n: int):
    """Grid t, points of c and their clockwise polar angle (unwrapped, increasing when c turns
    monotonically about the centre: x y' - y x' <= -(R - E)(R - E zp) < 0 for E zp < R)."""
    t = np.linspace(0.0, 2 * np.pi, n, endpoint=False)
    x, y = theoretical_curve(t, R, E, zp, rotation_rad)
    ang = -np.unwrap(np.arctan2(y, x))
    monotone = bool(np.all(np.diff(ang) > 0) and ang[-1] - ang[0] < 2 * np.pi)
    for a in (t, x, y, ang):
        a.flags.writeable = False
    return t, x, y, ang, monotone


def seed_parameters(qx: np.ndarray, qy: np.ndarray, R: float, E: float, zp: int,
                    rotation_rad: float = 0.0, samples_per_tooth: int = 64) -> np.ndarray:
    """Grid parameter nearest each point q: the nearest of `samples_per_tooth` points per tooth
    of c (the same choice as a full distance matrix, without one).

    Window: the two grid points bracketing q's polar angle are at distance d_q; the nearest grid
    point is no farther, so it is seen from the centre within asin(d_q / |q|) of q."""
    qx, qy = np.atleast_1d(np.asarray(qx, float)), np.atleast_1d(np.asarray(qy, float))
    n = samples_per_tooth * (zp - 1)
    tg, xg, yg, ang, monotone = _seed_grid(float(R), float(E), int(zp), float(rotation_rad), n)
    N = len(qx)
    if monotone:
        phi = ang[0] + np.mod(-np.arctan2(qy, qx) - ang[0], 2 * np.pi)
        j = np.clip(np.searchsorted(ang, phi, side="right") - 1, 0, n - 1)
        d = np.minimum(np.hypot(xg[j] - qx, yg[j] - qy),
                       np.hypot(xg[(j + 1) % n] - qx, yg[(j + 1) % n] - qy))
        r = np.hypot(qx, qy)
        with np.errstate(divide="ignore", invalid="ignore"):
            half = np.where(d < r, np.arcsin(np.minimum(d / r, 1.0)), np.pi)
        half = half * (1 + 1e-9) + 1e-12                   # rounding slack: never cut the nearest
        ext = np.concatenate([ang - 2 * np.pi, ang, ang + 2 * np.pi])
        lo = np.searchsorted(ext, phi - half, side="left")
        count = np.searchsorted(ext, phi + half, side="right") - lo
        full = count >= n
        lo, count = np.where(full, n, lo), np.where(full, n, count)
    else:                                                   # not a star-shaped curve: every grid point
        lo, count = np.full(N, n), np.full(N, n)
    seeds = np.empty(N, dtype=int)
    order = np.argsort(count, kind="stable")
    i = 0
    while i < N:                                            # blocks of bounded size, widest last
        w = count[order[i:]]
        j = i + max(1, int(np.searchsorted(np.arange(1, N - i + 1) * w, SEED_BLOCK_ELEMENTS,
                                           side="right")))
        idx = order[i:j]
        cols = lo[idx, None] + np.arange(count[idx].max())[None, :]
        g = np.mod(cols, n)
        d2 = (xg[g] - qx[idx, None]) ** 2 + (yg[g] - qy[idx, None]) ** 2
        d2[cols >= (lo + count)[idx, None]] = np.inf
        seeds[idx] = g[np.arange(len(idx)), np.argmin(d2, axis=1)]
        i = j
    return tg[seeds]


def foot_parameters(qx: np.ndarray, qy: np.ndarray, R: float, E: float, zp: int,
                    rotation_rad: float = 0.0, samples_per_tooth: int = 64,
                    tol_rad: float = 1e-14) -> np.ndarray:
    """Parameter t* of the nearest point of c(t) to each point q (disc frame) [rad].

    Seeded by `seed_parameters`, refined by Newton on g(t) = (c - q) . c' inside the bracket of
    the seed's grid neighbours (bisection when Newton leaves it)."""
    qx, qy = np.atleast_1d(np.asarray(qx, float)), np.atleast_1d(np.asarray(qy, float))
    t = seed_parameters(qx, qy, R, E, zp, rotation_rad, samples_per_tooth)
    h = 2 * np.pi / (samples_per_tooth * (zp - 1))
    lo, hi = t - h, t + h
    for _ in range(60):
        x, y = theoretical_curve(t, R, E, zp, rotation_rad)
        dx, dy = theoretical_curve(t, R, E, zp, rotation_rad, derivative=1)
        ddx, ddy = theoretical_curve(t, R, E, zp, rotation_rad, derivative=2)
        g = (x - qx) * dx + (y - qy) * dy
        dg = dx * dx + dy * dy + (x - qx) * ddx + (y - qy) * ddy
        lo, hi = np.where(g < 0, t, lo), np.where(g < 0, hi, t)   # g rises through the minimum
        with np.errstate(divide="ignore", invalid="ignore"):
            tn = t - g / dg
        bad = ~np.isfinite(tn) | (dg <= 0) | (tn <= lo) | (tn >= hi)
        tn = np.where(bad, 0.5 * (lo + hi), tn)
        step = np.abs(tn - t)
        t = tn
        if np.all(step < tol_rad):
            break
    return t


@dataclass(frozen=True)
class Foot:
    """Foot points on c of points q (arrays of q's shape (n,)); disc frame, mm."""
    t_rad: np.ndarray            # parameter of the foot point
    distance_mm: np.ndarray      # s = (q - c(t)) . n: signed distance from c, > 0 outside the disc
    normal: np.ndarray           # (n, 2) outward unit normal of c (and of the profile) at t
    curvature_per_mm: np.ndarray # signed curvature of c at t, > 0 convex
    curve_mm: np.ndarray         # (n, 2) c(t)

    def profile_point_mm(self, pin_radius_mm: float) -> np.ndarray:
        """(n, 2) foot point on the profile, the inward offset of c by the profile's pin radius."""
        return self.curve_mm - pin_radius_mm * self.normal


def nearest(qx: np.ndarray, qy: np.ndarray, R: float, E: float, zp: int, rotation_rad: float = 0.0,
            samples_per_tooth: int = 64) -> Foot:
    """Foot point, signed distance, outward normal and curvature of c for each point q."""
    qx, qy = np.atleast_1d(np.asarray(qx, float)), np.atleast_1d(np.asarray(qy, float))
    t = foot_parameters(qx, qy, R, E, zp, rotation_rad, samples_per_tooth)
    cx, cy = theoretical_curve(t, R, E, zp, rotation_rad)
    dx, dy = theoretical_curve(t, R, E, zp, rotation_rad, derivative=1)
    speed = np.hypot(dx, dy)
    nx, ny = -dy / speed, dx / speed            # left of a clockwise curve = outward
    return Foot(t, (qx - cx) * nx + (qy - cy) * ny, np.column_stack([nx, ny]),
                curvature_per_mm(t, R, E, zp), np.column_stack([cx, cy]))
