"""Involute mesh sun - planet j (first stage), in series with the torsion of crank j.

Line-of-action deflection d = rb1 (th_in - q_carrier) + rb2 (phi_j - q_carrier), phi_j the crank
rotation. Mesh stiffness over one pitch (mesh phase s = z1 (th_in - q_carrier) / 2 pi + offset_j):
k_m(s) = k_mean (1 + var (h(s) - (eps - 1))), h the double-contact indicator (1 over the
double-contact share eps - 1 of a pitch, smoothed over MESH_EDGE of a pitch), eps the contact
ratio; in series with the crank torsion k_t / rb2^2: k_s = 1 / (1 / k_m + rb2^2 / k_t).
Energy form V = k_s(s) d^2 / 2: the parametric force d^2 k_s'(s) / 2 is kept, so an undamped run
conserves energy. Damping beta k_s d'. No first-stage backlash (divided by ~zp at the output).
Stiffness: fem.stiffness (involute_mesh_*, crankshaft_torsional_stiffness_Nm_per_rad).
Output: mesh_force_N (nc,) along the line of action.
"""
from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from dynamics.couplings.base import kernel

NAME = "mesh"
MESH_EDGE = 0.02   # smoothing width of the single/double contact edges [fraction of a pitch]


class Params(NamedTuple):
    k_mean_N_per_m: float
    variation: float           # (k_double - k_single) / k_mean
    contact_ratio: float
    rb_sun_m: float            # base radii
    rb_planet_m: float
    z_sun: float
    k_torsion_Nm_per_rad: float  # crank torsion between planet gear and eccentrics
    phase: np.ndarray          # (nc,) mesh phase offset of planet j [pitches]
    dof: np.ndarray            # (nc, 2) carrier rotation, crank j rotation
    out0: int                  # offset of mesh_force_N in the work's outputs


def params(case, stiffness, layout, slots) -> Params:
    s1 = case.stage1
    nc = case.carrier.crank_count
    alpha = np.deg2rad(s1.pressure_angle_deg)
    beta = 2 * np.pi * np.arange(nc) / nc
    car, rot = layout["carrier"], layout["crank_rotation"]
    return Params(
        k_mean_N_per_m=float(stiffness.involute_mesh_mean_stiffness_N_per_m),
        variation=float(stiffness.involute_mesh_stiffness_variation),
        contact_ratio=float(stiffness.involute_mesh_contact_ratio),
        rb_sun_m=case.si.sun_pitch_radius_m * math.cos(alpha),
        rb_planet_m=case.si.planet_pitch_radius_m * math.cos(alpha),
        z_sun=float(s1.z1),
        k_torsion_Nm_per_rad=float(stiffness.crankshaft_torsional_stiffness_Nm_per_rad),
        phase=np.mod(s1.z1 * beta / (2 * np.pi), 1.0),
        dof=np.column_stack([np.full(nc, car.index()), rot.indices()]).astype(np.int64),
        out0=slots.output("mesh_force_N", (nc,)))


@kernel(inline=True)
def _double_contact(s, eps):
    """Smoothed double-contact indicator over one mesh pitch and its derivative d/ds."""
    f = eps - 1.0
    if f <= 0.0 or f >= 1.0:
        return f, 0.0
    d = s - math.floor(s) - 0.5 * f
    d = d - math.floor(d + 0.5)
    a = abs(d)
    sg = 1.0 if d >= 0.0 else -1.0
    th = math.tanh((a - 0.5 * f) / MESH_EDGE)
    return 0.5 * (1.0 - th), -0.5 * (1.0 - th * th) / MESH_EDGE * sg


@kernel(inline=True)
def add(q, v, th_in, w_in, beta, want_k, p, w, V, tau_in):
    """Coupling interface (see dynamics.couplings): forces into w.f, tangent into w.K, damping
    into w.C; returns (V, tau_in, ok) with this coupling's potential and input torque added."""
    f, K, C, out, dof = w.f, w.K, w.C, w.out, p.dof
    rb1, rb2, z1, eps = p.rb_sun_m, p.rb_planet_m, p.z_sun, p.contact_ratio
    for j in range(dof.shape[0]):
        i0, ij = dof[j, 0], dof[j, 1]
        s = z1 * (th_in - q[i0]) / (2.0 * math.pi) + p.phase[j]
        h, dh = _double_contact(s, eps)
        km = p.k_mean_N_per_m * (1.0 + p.variation * (h - (eps - 1.0)))
        dkm = p.k_mean_N_per_m * p.variation * dh
        ks = 1.0 / (1.0 / km + rb2 * rb2 / p.k_torsion_Nm_per_rad)
        dks = (ks / km) ** 2 * dkm               # d ks / d s
        d = rb1 * (th_in - q[i0]) + rb2 * (q[ij] - q[i0])
        dd = rb1 * (w_in - v[i0]) + rb2 * (v[ij] - v[i0])
        F = ks * d + beta * ks * dd
        ds0 = -z1 / (2.0 * math.pi)
        g0, gj = -(rb1 + rb2), rb2
        f[i0] -= F * g0 + 0.5 * d * d * dks * ds0
        f[ij] -= F * gj
        tau_in += F * rb1 - 0.5 * d * d * dks * ds0
        V += 0.5 * ks * d * d
        out[p.out0 + j] = F
        if want_k:
            K[i0, i0] += ks * g0 * g0
            K[i0, ij] += ks * g0 * gj
            K[ij, i0] += ks * g0 * gj
            K[ij, ij] += ks * gj * gj
            C[i0, i0] += beta * ks * g0 * g0
            C[i0, ij] += beta * ks * g0 * gj
            C[ij, i0] += beta * ks * g0 * gj
            C[ij, ij] += beta * ks * gj * gj
    return V, tau_in, True
