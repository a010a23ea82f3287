"""Crank support path: crank bending, support bearings and carrier racking as one stiffness matrix.

DOFs: u = the crank axis displacement of crank j at disc plane d (layout block crank_axis, item
j nd + d, CARRIER frame), 2 nc nd of them. The path from the eccentric forces to the carrier is
linear and statically determinate per crank (a beam pinned at its two bearing centres), so its
compliance is the sum of fem.stiffness.support_compliance_parts: shaft bending between the two
eccentrics (3D FE, the two discs' opposite forces tilt and S-bend the crank instead of cancelling),
the two tapered roller bearings (linearised at the rated-torque load), and the carrier's seat
flexibility (3D FE; racking couples the cranks). K = C^-1, V = u^T K u / 2.
Radial clearance c (case.errors.support_clearance_um, zero for the preloaded pair of the cases):
a dead band on each crank's plane-mean displacement m_j = mean_d u_jd, s(m) = m for |m| <= c,
c m / |m| beyond; the elastic displacement is u - E s(M u) (E repeats per plane), the crank moving
freely as a body within its play (tilt within the play is not modelled). With J = I - E S M,
S = ds/dm: f = -J^T K u_el, tangent J^T K J - M^T G M, G = d(S h)/dm at fixed h = E^T K u_el.
Damping beta K_t u'. Output: support_force_N (nc, nd, 2), the support's force ON each crank plane,
carrier frame.
"""
from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from dynamics.couplings.base import kernel
from fem.stiffness import support_stiffness_matrix

NAME = "support"


class Params(NamedTuple):
    K_N_per_m: np.ndarray      # (2 nc nd, 2 nc nd) support stiffness, carrier frame
    clearance_m: float
    dof: np.ndarray            # (nc, nd, 2) crank_axis indices (x, y)
    out0: int                  # offset of support_force_N in the work's outputs


def params(case, stiffness, layout, slots) -> Params:
    nc, nd = case.carrier.crank_count, case.cycloid.disc_count
    axis = layout["crank_axis"]
    dof = np.array([[[axis.index(j * nd + d, "x"), axis.index(j * nd + d, "y")] for d in range(nd)]
                    for j in range(nc)], dtype=np.int64)
    return Params(K_N_per_m=np.ascontiguousarray(support_stiffness_matrix(stiffness, nc)),
                  clearance_m=case.errors.support_clearance_um * 1e-6, dof=dof,
                  out0=slots.output("support_force_N", (nc, nd, 2)))


@kernel(inline=True)
def add(q, v, th_in, w_in, beta, want_k, p, w, V, tau_in):
    """Coupling interface (see dynamics.couplings)."""
    f, K, C, out, dof, Ks = w.f, w.K, w.C, w.out, p.dof, p.K_N_per_m
    nc, nd = dof.shape[0], dof.shape[1]
    n = 2 * nc * nd
    idx = np.empty(n, np.int64)
    u = np.empty(n)
    ud = np.empty(n)
    for j in range(nc):
        for d in range(nd):
            for c in range(2):
                k = 2 * (j * nd + d) + c
                idx[k] = dof[j, d, c]
                u[k] = q[idx[k]]
                ud[k] = v[idx[k]]
    J = np.eye(n)
    Gs = np.zeros((nc, 2, 2))          # G of each crank (dead band curvature term)
    mean = np.zeros((nc, 3))           # each crank's plane-mean displacement m and |m|
    cl = p.clearance_m
    if cl > 0.0:
        for j in range(nc):
            mx, my = 0.0, 0.0
            for d in range(nd):
                mx += u[2 * (j * nd + d)] / nd
                my += u[2 * (j * nd + d) + 1] / nd
            r = math.sqrt(mx * mx + my * my)
            mean[j, 0], mean[j, 1], mean[j, 2] = mx, my, r
            if r <= cl:
                sx, sy = mx, my
                S00, S01, S11 = 1.0, 0.0, 1.0
            else:
                ex, ey = mx / r, my / r
                sx, sy = cl * ex, cl * ey
                g = cl / r
                S00, S01, S11 = g * (1 - ex * ex), -g * ex * ey, g * (1 - ey * ey)
            for d in range(nd):
                u[2 * (j * nd + d)] -= sx
                u[2 * (j * nd + d) + 1] -= sy
                for d2 in range(nd):        # J = I - E S M on crank j's block
                    a, b = 2 * (j * nd + d), 2 * (j * nd + d2)
                    J[a, b] -= S00 / nd
                    J[a, b + 1] -= S01 / nd
                    J[a + 1, b] -= S01 / nd
                    J[a + 1, b + 1] -= S11 / nd
    g = Ks @ u                          # K u_el: V = u_el^T K u_el / 2
    Jt = np.ascontiguousarray(J.T)
    fs = Jt @ g if cl > 0.0 else g
    if cl > 0.0:                       # G terms: d(S h)/dm outside the play
        for j in range(nc):
            mx, my, r = mean[j, 0], mean[j, 1], mean[j, 2]
            hx, hy = 0.0, 0.0
            for d in range(nd):
                hx += g[2 * (j * nd + d)]
                hy += g[2 * (j * nd + d) + 1]
            if r > cl:
                ex, ey = mx / r, my / r
                eh = ex * hx + ey * hy
                px, py = hx - ex * eh, hy - ey * eh          # (I - e e^T) h
                # d/dm [(c/r)(I - e e^T) h] = -(c/r^2) p e^T - (c/r^2)[(I - e e^T) (e.h) + e p^T]
                a = cl / (r * r)
                Gs[j, 0, 0] = -a * (px * ex + (1 - ex * ex) * eh + ex * px)
                Gs[j, 0, 1] = -a * (px * ey + (-ex * ey) * eh + ex * py)
                Gs[j, 1, 0] = -a * (py * ex + (-ex * ey) * eh + ey * px)
                Gs[j, 1, 1] = -a * (py * ey + (1 - ey * ey) * eh + ey * py)
    if cl > 0.0 and (want_k or beta != 0.0):
        Kt = Jt @ (Ks @ J)
    else:
        Kt = Ks
    if cl > 0.0 and (want_k or beta != 0.0):
        for j in range(nc):
            for d in range(nd):
                for d2 in range(nd):
                    a, b = 2 * (j * nd + d), 2 * (j * nd + d2)
                    for c1 in range(2):
                        for c2 in range(2):
                            Kt[a + c1, b + c2] -= Gs[j, c1, c2] / (nd * nd)
    damp = Kt @ ud if beta != 0.0 else np.zeros(n)
    for k in range(n):
        F = fs[k] + beta * damp[k]
        f[idx[k]] -= F
        out[p.out0 + k] = -fs[k]
        V += 0.5 * u[k] * g[k]
    if want_k:
        for a in range(n):
            for b in range(n):
                K[idx[a], idx[b]] += Kt[a, b]
                C[idx[a], idx[b]] += beta * Kt[a, b]
    return V, tau_in, True
