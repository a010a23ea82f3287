"""Cycloid disc - pin contact: every pin of the housing against every disc, gap from the actual profile.

Disc d (centre c_d, rotation alpha_d + its profile rotation) carries the modified profile: the
inward offset by Rr + dRr of the pin-centre curve c(t) with R + dR (DESIGN.md). Pin k (centre P_k,
radius r_k, both with case.errors applied) is mapped into the disc frame and its foot point on c(t)
found by `geometry.pin_profile.foot_point` (Newton seeded at the conjugate-pose parameter
alpha_d - theta_k, microradians off under load: 2-3 iterations, never the neighbouring lobe).
gap = s + Rr - r_k (s the signed distance from c along the outward normal); approach = -gap.
Law (fem.stiffness.pin_contact, FE, by pin phase from the line of centres, interpolated):
F = k(phase) approach^n, V = k approach^(n+1) / (n+1); the law's phase dependence is not
differentiated (f departs from -grad V by ~2e-4 of the largest force at 300 N m,
tests/test_couplings.py), nor is the profile curvature in the tangent. Damping beta k_t g', ramped in over
DAMP_RAMP_M of approach; a damped contact cannot pull (force clipped at 0).
The contacts are the work's candidate contacts: the time integration skips pins found open by
more than a margin (dynamics.kernels.CANDIDATE_MARGIN_M); w.gap / w.force hold gap and force.
"""
from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from dynamics.couplings.base import foot_point, interp2, kernel, ramp

NAME = "pin"
GAP_LIMIT_M = 1e-3     # a foot point farther than this from the pin-centre curve is lost geometry


class Params(NamedTuple):
    R_m: float                     # pin circle radius of the profile, R + dR
    Rr_m: float                    # pin radius of the profile, Rr + dRr
    E_m: float                     # eccentricity of the profile
    zp: float                      # pins
    pins: np.ndarray               # (zp, 4) actual pins: x [m], y [m], radius [m], angle [rad]
    law: np.ndarray                # (P, 3) pin phase [deg], k [N/m^n], n
    disc_rotation_rad: np.ndarray  # (nd,) profile rotation in each disc's body frame
    dof: np.ndarray                # (nd, 3) disc x, y, rotation
    c0: int                        # offset of the (nd, zp) contacts in the work's contact arrays


def params(case, stiffness, layout, slots) -> Params:
    cy, mod, er = case.cycloid, case.modification, case.errors
    zp, nd = cy.zp, cy.disc_count
    th = 2 * np.pi * np.arange(zp) / zp
    Rp = cy.pin_circle_radius_mm * 1e-3 + er.pin_circle_radius_um * 1e-6
    rp = cy.pin_radius_mm * 1e-3 + er.pin_radius_um * 1e-6
    pc = stiffness.pin_contact
    disc = layout["disc"]
    return Params(
        R_m=(cy.pin_circle_radius_mm + mod.offset_mm) * 1e-3,
        Rr_m=(cy.pin_radius_mm + mod.equidistant_mm) * 1e-3,
        E_m=cy.eccentricity_mm * 1e-3, zp=float(zp),
        pins=np.column_stack([Rp * np.cos(th), Rp * np.sin(th), np.full(zp, rp), th]),
        law=np.column_stack([pc.position_deg, pc.law_k_N_per_m_pow, pc.law_n]).astype(float),
        disc_rotation_rad=np.deg2rad(mod.rotation_deg) + np.pi * np.arange(nd),
        dof=np.column_stack([disc.indices("x"), disc.indices("y"), disc.indices("rot")]).astype(np.int64),
        c0=slots.contacts("pin", (nd, zp), group=np.repeat(np.arange(nd), zp)))


@kernel(inline=True)
def add(q, v, th_in, w_in, beta, want_k, p, w, V, tau_in):
    """Coupling interface (see dynamics.couplings); only the contacts with w.active are
    evaluated (the others are known open: force 0, gap left as it was)."""
    f, K, C, active, gaps, forces = w.f, w.K, w.C, w.active, w.gap, w.force
    R, Rr, E, zp = p.R_m, p.Rr_m, p.E_m, p.zp
    law, pins, dof = p.law, p.pins, p.dof
    npin = pins.shape[0]
    ok = True
    for d in range(dof.shape[0]):
        ix, iy, ia = dof[d, 0], dof[d, 1], dof[d, 2]
        cx, cy, al = q[ix], q[iy], q[ia] + p.disc_rotation_rad[d]
        ca, sa = math.cos(al), math.sin(al)
        psi = math.atan2(cy, cx)
        for k in range(npin):
            c = p.c0 + d * npin + k
            if not active[c]:
                forces[c] = 0.0
                continue
            Px, Py, rp, thk = pins[k, 0], pins[k, 1], pins[k, 2], pins[k, 3]
            wx, wy = Px - cx, Py - cy
            pbx, pby = ca * wx + sa * wy, -sa * wx + ca * wy
            t, s, nx, ny, kappa, okk = foot_point(pbx, pby, R, E, zp, al - thk)
            if not okk or abs(s) > GAP_LIMIT_M:
                ok = False
            gap = s + Rr - rp
            gaps[c] = gap
            forces[c] = 0.0
            if gap >= 0.0:
                continue
            ngx, ngy = ca * nx - sa * ny, sa * nx + ca * ny
            g_x, g_y, g_a = -ngx, -ngy, -(wx * ngy - wy * ngx)
            ph = (thk - psi) * 180.0 / math.pi
            ph = abs(ph - 360.0 * math.floor((ph + 180.0) / 360.0))
            kk, nn = interp2(ph, law)
            app = -gap
            F = kk * app ** nn
            kt = nn * kk * max(app, 1e-10) ** (nn - 1.0)
            gd = g_x * v[ix] + g_y * v[iy] + g_a * v[ia]
            rmp = ramp(app)
            Ft = F - beta * rmp * kt * gd
            if Ft < 0.0:
                Ft = 0.0
            forces[c] = Ft
            f[ix] += Ft * g_x
            f[iy] += Ft * g_y
            f[ia] += Ft * g_a
            V += kk * app ** (nn + 1.0) / (nn + 1.0)
            if want_k:
                gg, ii = (g_x, g_y, g_a), (ix, iy, ia)
                for c1 in range(3):
                    for c2 in range(3):
                        K[ii[c1], ii[c2]] += kt * gg[c1] * gg[c2]
                        if Ft > 0.0:
                            C[ii[c1], ii[c2]] += beta * rmp * kt * gg[c1] * gg[c2]
    return V, tau_in, ok
