"""Turning-arm (needle roller) bearing: the eccentric of crank j under disc d in crank hole j of disc d.

Eccentric centre X_e = R(q_carrier) (s_j + u_jd) + e_dj (cos, sin)(phi_j + phase_dj), s_j the seat at
radius a_j and angle b_j on the carrier, u_jd the crank axis displacement at disc plane d (carrier
frame, layout block crank_axis), R the carrier rotation, e_dj the eccentric radius;
crank-hole centre X_h = c_d + r_j (cos, sin)(alpha_d + b_j) on disc d (centre c_d, rotation alpha_d).
Law (fem.stiffness.turning_arm, FE): F = k x^n along D = X_e - X_h, x = |D| - clearance
(case.errors.turning_arm_clearance_um), V = k x^(n+1) / (n+1). Damping beta K_t D', K_t the 2x2
tangent, ramped in over DAMP_RAMP_M of approach when there is a clearance.
As-built parameters (case.errors, geometry.params.Errors): crank_eccentricity_um (both eccentrics
of crank j), eccentric_error_um (disc 1's eccentric only), eccentric_phase_arcmin (disc 2's
eccentric turned on crank j), crank_timing_arcmin (both eccentrics of crank j turned against its
planet gear, i.e. against the crank rotation DOF the involute mesh drives), crank_hole_position_um /
_tangential_um (hole j on both discs), output_bearing_hole_um / _tangential_um (seat j in the
carrier), main_bearing_runout_um / _phase_deg (every seat moved by one vector of the carrier frame:
the carrier axis off the housing axis, turning with the carrier).
Output: bearing_force_N (nd, nc, 2), the force ON disc d, ground frame.
"""
from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from dynamics.couplings.base import kernel, ramp

NAME = "needle"


class Params(NamedTuple):
    k_N_per_m_pow: float
    n: float
    clearance_m: float
    seat_radius_m: np.ndarray      # (nc,) crank seat in the carrier
    seat_angle_rad: np.ndarray     # (nc,)
    ecc_m: np.ndarray              # (nd, nc) eccentric radius under disc d
    ecc_phase_rad: np.ndarray      # (nd, nc) eccentric angle from the crank rotation DOF
    hole_radius_m: np.ndarray      # (nc,) crank hole in the disc
    hole_angle_rad: np.ndarray     # (nc,) in the disc frame
    dof: np.ndarray                # (nd, nc, 7) carrier, crank rot, axis x, y (plane d), disc x, y, rot
    out0: int                      # offset of bearing_force_N in the work's outputs


def _per_crank(values: tuple, n: int, scale: float = 1e-6) -> np.ndarray:
    """One value per crank (one given: all cranks), times scale (default um -> m)."""
    v = np.asarray(values, dtype=float) * scale
    return np.full(n, v[0]) if len(v) == 1 else v


def _polar(a, b, radial, tangential, shift=(0.0, 0.0)) -> tuple[np.ndarray, np.ndarray]:
    """(radius, angle) of points at radius a + radial, angle b, moved by `tangential` (+ forward)
    and by the vector `shift` (same frame)."""
    x = a + radial + shift[0] * np.cos(b) + shift[1] * np.sin(b)     # along and across the ray b
    y = tangential - shift[0] * np.sin(b) + shift[1] * np.cos(b)
    return np.hypot(x, y), b + np.arctan2(y, x)                        # exactly (a, b) without errors


def params(case, stiffness, layout, slots) -> Params:
    cy, cr, er = case.cycloid, case.carrier, case.errors
    nc, nd = cr.crank_count, cy.disc_count
    a = case.si.crank_circle_radius_m
    b = 2 * np.pi * np.arange(nc) / nc
    ecc = case.si.eccentricity_m + _per_crank(er.crank_eccentricity_um, nc)
    de1 = _per_crank(er.eccentric_error_um, nc)
    arcmin = math.radians(1.0 / 60.0)
    timing = _per_crank(er.crank_timing_arcmin, nc, arcmin)
    phase2 = _per_crank(er.eccentric_phase_arcmin, nc, arcmin)
    run = er.main_bearing_runout_um * 1e-6 * np.array([math.cos(math.radians(er.main_bearing_runout_phase_deg)),
                                                       math.sin(math.radians(er.main_bearing_runout_phase_deg))])
    seat_r, seat_b = _polar(a, b, _per_crank(er.output_bearing_hole_um, nc),
                            _per_crank(er.output_bearing_hole_tangential_um, nc), run)
    hole_r, hole_b = _polar(a, b, _per_crank(er.crank_hole_position_um, nc),
                            _per_crank(er.crank_hole_tangential_um, nc))
    car, rot, axis, disc = (layout[k] for k in ("carrier", "crank_rotation", "crank_axis", "disc"))
    dof = np.array([[[car.index(), rot.index(j), axis.index(j * nd + d, "x"), axis.index(j * nd + d, "y"),
                      disc.index(d, "x"), disc.index(d, "y"), disc.index(d, "rot")]
                     for j in range(nc)] for d in range(nd)], dtype=np.int64)
    ta = stiffness.turning_arm
    return Params(
        k_N_per_m_pow=float(ta.law_k_N_per_m_pow), n=float(ta.law_n),
        clearance_m=er.turning_arm_clearance_um * 1e-6,
        seat_radius_m=seat_r, seat_angle_rad=seat_b,
        ecc_m=np.array([ecc + de1 if d == 0 else ecc for d in range(nd)]),
        # discs 180 deg apart, + timing of crank j, + disc 2's eccentric phase error
        ecc_phase_rad=np.array([math.pi * d + timing + (phase2 if d == 1 else 0.0) for d in range(nd)]),
        hole_radius_m=hole_r, hole_angle_rad=hole_b,
        dof=dof, out0=slots.output("bearing_force_N", (nd, nc, 2)))


@kernel(inline=True)
def add(q, v, th_in, w_in, beta, want_k, p, w, V, tau_in):
    """Coupling interface (see dynamics.couplings)."""
    f, K, C, out, dof = w.f, w.K, w.C, w.out, p.dof
    kta, nta, cta = p.k_N_per_m_pow, p.n, p.clearance_m
    nd, nc = dof.shape[0], dof.shape[1]
    Gm = np.empty((2, 7))              # dD / dq over the seven DOFs of the pair
    gr = np.empty(7)
    idx = np.empty(7, np.int64)
    for d in range(nd):
        for j in range(nc):
            for c in range(7):
                idx[c] = dof[d, j, c]
            a, ecc, hr = p.seat_radius_m[j], p.ecc_m[d, j], p.hole_radius_m[j]
            pe = q[idx[1]] + p.ecc_phase_rad[d, j]
            ca, sa = math.cos(q[idx[0]] + p.seat_angle_rad[j]), math.sin(q[idx[0]] + p.seat_angle_rad[j])
            cc, sc = math.cos(q[idx[0]]), math.sin(q[idx[0]])
            ugx = cc * q[idx[2]] - sc * q[idx[3]]          # crank axis displacement, ground frame
            ugy = sc * q[idx[2]] + cc * q[idx[3]]
            ce, se = math.cos(pe), math.sin(pe)
            ch, sh = math.cos(q[idx[6]] + p.hole_angle_rad[j]), math.sin(q[idx[6]] + p.hole_angle_rad[j])
            Dx = a * ca + ugx + ecc * ce - q[idx[4]] - hr * ch
            Dy = a * sa + ugy + ecc * se - q[idx[5]] - hr * sh
            Gm[0, 0], Gm[1, 0] = -a * sa - ugy, a * ca + ugx
            Gm[0, 1], Gm[1, 1] = -ecc * se, ecc * ce
            Gm[0, 2], Gm[1, 2], Gm[0, 3], Gm[1, 3] = cc, sc, -sc, cc
            Gm[0, 4], Gm[1, 4], Gm[0, 5], Gm[1, 5] = -1.0, 0.0, 0.0, -1.0
            Gm[0, 6], Gm[1, 6] = hr * sh, -hr * ch
            r = math.sqrt(Dx * Dx + Dy * Dy) + 1e-300
            ex, ey = Dx / r, Dy / r
            x = r - cta
            o = p.out0 + 2 * (d * nc + j)
            out[o] = 0.0
            out[o + 1] = 0.0
            if x <= 0.0:
                continue
            F = kta * x ** nta
            kt = nta * kta * x ** (nta - 1.0)
            fr = F / r
            rb = beta * (ramp(x) if cta > 0.0 else 1.0)
            # viscous force beta * K_t * D_dot, K_t the bearing's 2x2 tangent (continuous through D = 0)
            Ddx, Ddy = 0.0, 0.0
            for c in range(7):
                gr[c] = ex * Gm[0, c] + ey * Gm[1, c]
                Ddx += Gm[0, c] * v[idx[c]]
                Ddy += Gm[1, c] * v[idx[c]]
            rd = ex * Ddx + ey * Ddy
            Fx = F * ex + rb * (kt * rd * ex + fr * (Ddx - rd * ex))
            Fy = F * ey + rb * (kt * rd * ey + fr * (Ddy - rd * ey))
            for c in range(7):
                f[idx[c]] -= Fx * Gm[0, c] + Fy * Gm[1, c]
            out[o] = Fx
            out[o + 1] = Fy
            V += kta * x ** (nta + 1.0) / (nta + 1.0)
            if want_k:
                for c1 in range(7):
                    for c2 in range(7):
                        perp = (Gm[0, c1] * Gm[0, c2] + Gm[1, c1] * Gm[1, c2]) - gr[c1] * gr[c2]
                        kk = kt * gr[c1] * gr[c2] + fr * perp
                        K[idx[c1], idx[c2]] += kk
                        C[idx[c1], idx[c2]] += rb * kk
                # force x d^2 D / (d carrier d u): the carrier turns the crank axis displacement
                # (F of the order of the load, no lever to shrink it, unlike the turning arms)
                kx = F * (-ex * sc + ey * cc)
                ky = F * (-ex * cc - ey * sc)
                K[idx[0], idx[2]] += kx
                K[idx[2], idx[0]] += kx
                K[idx[0], idx[3]] += ky
                K[idx[3], idx[0]] += ky
    return V, tau_in, True
