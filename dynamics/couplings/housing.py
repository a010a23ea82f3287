"""The housing (pin ring) as an elastic body: its modal coordinates on their own stiffness.

DOFs: a_i, the housing block of the layout (one per kept mode of the housing FE, fem.components.
housing: the most compliant eigenvectors of the condensed pin-seat compliance, a load on one pin
moves its neighbours); pin k's seat moves by phi[k] a (ground frame, m), which the pin coupling
reads (dynamics.couplings.pin). Each mode is a spring of stiffness k_i = 1 / lambda_i on its
coordinate: V = sum k_i a_i^2 / 2, damping beta k_i a_i'. No modes (a stiffness without a housing
entry): nothing to add.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from dynamics.couplings.base import kernel

NAME = "housing"


class Params(NamedTuple):
    k_N_per_m: np.ndarray      # (n,) modal stiffness
    dof: np.ndarray            # (n,) housing block indices


def modes(stiffness, layout):
    """The housing's kept modes and their DOF indices, or None: a stiffness without a housing entry,
    or a layout without the housing block (the housing then held rigid)."""
    hm = stiffness.parts.get("housing")
    names = [b.name for b in layout.blocks]
    if hm is None or "housing" not in names or layout["housing"].count != len(hm.stiffness_N_per_m):
        return None
    return hm, layout["housing"].indices(0)


SEATS = "housing_seats"   # stiffness.parts key of a SeatCompliance (in memory only: the diagnosis' causes)


@dataclass(frozen=True)
class SeatCompliance:
    """Pin seats softer than the housing FE: an added compliance c_k [m/N] at pin k's seat, local
    (a load on pin k moves only its own seat) and isotropic in the ring's plane. Each such seat is
    a housing mode of its own (phi = the unit vector at pin k, stiffness 1 / c_k) whose massless
    coordinate the pin coupling condenses exactly into the contact: the seat in series with the
    pin law along the contact normal (dynamics.couplings.pin), no DOF added. Limit: the two discs'
    contacts on one pin each see the whole seat (their load zones lie 180 deg apart, so a pin
    carries one disc's load at a time but for the lightly loaded pins at the zones' ends)."""
    compliance_m_per_N: np.ndarray     # (zp,) >= 0


def seat_compliance(stiffness, zp: int) -> np.ndarray:
    """(zp,) the added seat compliances [m/N] of the stiffness (zeros without a SeatCompliance)."""
    sc = stiffness.parts.get(SEATS)
    return np.zeros(zp) if sc is None else np.asarray(sc.compliance_m_per_N, float).reshape(zp)


def params(case, stiffness, layout, slots) -> Params:
    m = modes(stiffness, layout)
    if m is None:
        return Params(k_N_per_m=np.zeros(0), dof=np.zeros(0, np.int64))
    return Params(k_N_per_m=np.ascontiguousarray(np.asarray(m[0].stiffness_N_per_m, float)), dof=m[1])


@kernel(inline=True)
def add(q, v, th_in, w_in, beta, want_k, p, w, V, tau_in):
    """Coupling interface (see dynamics.couplings)."""
    f, K, C = w.f, w.K, w.C
    for i in range(p.dof.shape[0]):
        j, k = p.dof[i], p.k_N_per_m[i]
        f[j] -= k * q[j] + beta * k * v[j]
        V += 0.5 * k * q[j] * q[j]
        if want_k:
            K[j, j] += k
            C[j, j] += beta * k
    return V, tau_in, True
