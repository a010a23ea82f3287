"""Crank support: shaft bending in series with the two support bearings in parallel, radial clearance.

The crank axis displacement u_j (from its carrier seat, ground frame) meets the isotropic spring
1/k = 1/k_bend + 1/(2 k_bearing) (fem.stiffness: crankshaft_bending_stiffness_N_per_m,
support_bearing_radial_stiffness_N_per_m) through a radial clearance c (case.errors.support_clearance_um):
V = k max(|u_j| - c, 0)^2 / 2. Damping beta K_t u_j', K_t the 2x2 tangent (continuous at |u| = c).
"""
from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from dynamics.couplings.base import kernel

NAME = "support"


class Params(NamedTuple):
    k_N_per_m: float
    clearance_m: float
    dof: np.ndarray            # (nc, 2) crank j axis x, y


def params(case, stiffness, layout, slots) -> Params:
    axis = layout["crank_axis"]
    return Params(
        k_N_per_m=1.0 / (1.0 / stiffness.crankshaft_bending_stiffness_N_per_m
                         + 1.0 / (2.0 * stiffness.support_bearing_radial_stiffness_N_per_m)),
        clearance_m=case.errors.support_clearance_um * 1e-6,
        dof=np.column_stack([axis.indices("x"), axis.indices("y")]).astype(np.int64))


@kernel(inline=True)
def add(q, v, th_in, w_in, beta, want_k, p, w, V, tau_in):
    """Coupling interface (see dynamics.couplings)."""
    f, K, C, dof = w.f, w.K, w.C, p.dof
    ksup, csup = p.k_N_per_m, p.clearance_m
    for j in range(dof.shape[0]):
        ix, iy = dof[j, 0], dof[j, 1]
        ux, uy = q[ix], q[iy]
        r = math.sqrt(ux * ux + uy * uy)
        if csup <= 0.0:
            f[ix] -= ksup * ux + beta * ksup * v[ix]
            f[iy] -= ksup * uy + beta * ksup * v[iy]
            V += 0.5 * ksup * r * r
            if want_k:
                K[ix, ix] += ksup
                K[iy, iy] += ksup
                C[ix, ix] += beta * ksup
                C[iy, iy] += beta * ksup
        elif r > csup:
            ex, ey = ux / r, uy / r
            x = r - csup
            fr = ksup * x / r
            rd = ex * v[ix] + ey * v[iy]
            Fx = ksup * x * ex + beta * (ksup * rd * ex + fr * (v[ix] - rd * ex))
            Fy = ksup * x * ey + beta * (ksup * rd * ey + fr * (v[iy] - rd * ey))
            f[ix] -= Fx
            f[iy] -= Fy
            V += 0.5 * ksup * x * x
            if want_k:
                kxx = ksup * ex * ex + fr * (1.0 - ex * ex)
                kxy = ksup * ex * ey - fr * ex * ey
                kyy = ksup * ey * ey + fr * (1.0 - ey * ey)
                K[ix, ix] += kxx
                K[ix, iy] += kxy
                K[iy, ix] += kxy
                K[iy, iy] += kyy
                C[ix, ix] += beta * kxx
                C[ix, iy] += beta * kxy
                C[iy, ix] += beta * kxy
                C[iy, iy] += beta * kyy
    return V, tau_in, True
