"""Elastic bearing rings where the carrier FE holds the seats rigid, and the tapered pair's
pressure-centre offset moment (SI units).

Ring on an elastic seat (ring_on_seat): a bearing ring of mean radius R, section B x t, loaded by
the roller load zone q(psi) = q0 cos^n(psi) on |psi| < 90 deg (per unit circumference; n = 10/9
rollers), resting on a Winkler foundation k_f [N/m^2] (the seat's contact layer, fem.joints,
tangent at the fit pressure: k_f = k_n(p_f) B). Fourier modes of the load, q = sum q_k cos k psi:
  k = 0 (hoop):  w_0 = q_0 / (E A / R^2 + k_f)
  k = 1 (rigid): w_1 = q_1 / k_f                        (the ring shifts on its seat)
  k >= 2:        w_k = q_k / (E I (k^2 - 1)^2 / R^4 + k_f)  (inextensible thin ring, Timoshenko)
and the radial compliance work-conjugate to the load, c = sum pi R q_k w_k (2 pi R q_0 w_0) / F^2.
Check: with no foundation, two opposite forces W change the diameter by (pi/4 - 2/pi) W R^3 / (E I)
= 0.1488 W R^3 / (E I) (Roark's Formulas for Stress and Strain, table 9.2, thin ring under
diametral load; tests/test_fem_main_bearings.py). `bending_m_per_N` is the part beyond the rigid
ring (k != 1): what the ring's own flexibility adds to a rigid-ring bearing model; the k = 1 part
is the seat layer under a rigid ring. fem.joints.ring_seat_radial is the flexible-ring limit (the
layer sees the roller distribution itself, nonlinear, tangent at the load): the two are one physics
seen twice, so a model takes the seat's compliance from ONE of them, never both (on the RV-40E cup
they agree within 2 %: tests/test_fem_main_bearings.py).

Pressure-centre moment (pressure_centre_moment_Nm): a tapered roller bearing's radial reaction
acts at its pressure centre, a = (D_pw / 2) tan(alpha) from the contact mid-plane (inside the pair
for X, fem.tapered_roller); about the bearing centre it is the radial force plus a moment F_r a.
For a crank pinned at its bearing centres, each support adds M_b = F_r,b a_b (the two equal and
of opposite sense for the torque part, X arrangement: a couple that bends the crank).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from fem import tapered_roller
from geometry.artifacts import InputError

MODES = 400                  # Fourier modes of the load zone (the series converges as k^-4 past k ~ R/t)
QUAD = 4096                  # azimuth points for the Fourier coefficients (trapezoid, periodic: spectral)


@dataclass(frozen=True)
class RingOnSeat:
    compliance_m_per_N: float        # all modes: the ring and its seat layer
    bending_m_per_N: float           # k != 1: the ring's own flexibility over a rigid ring
    rigid_ring_m_per_N: float        # k = 1: the seat layer under a rigid ring
    source: str


def load_zone_coefficients(n: float, modes: int = MODES, points: int = QUAD) -> np.ndarray:
    """q_k / q0 of q0 cos^n(psi) on |psi| < pi/2 (0 elsewhere), k = 0..modes."""
    psi = 2 * math.pi * np.arange(points) / points
    q = np.where(np.cos(psi) > 0, np.abs(np.cos(psi)) ** n, 0.0)
    k = np.arange(modes + 1)
    coef = 2.0 / points * (np.cos(np.outer(k, psi)) @ q)
    coef[0] /= 2
    return coef


def ring_modal_compliance(q_k: np.ndarray, R_m: float, EI_Nm2: float, EA_N: float, k_f: float,
                          skip_rigid: bool = False) -> float:
    """Work-conjugate displacement x F for unit-F loads q_k (N/m per N) (module doc)."""
    k = np.arange(len(q_k), dtype=float)
    stiff = EI_Nm2 * (k * k - 1) ** 2 / R_m ** 4 + k_f
    stiff[0] = EA_N / R_m ** 2 + k_f
    weight = np.pi * R_m * np.ones_like(k)
    weight[0] = 2 * np.pi * R_m
    use = np.ones_like(k, dtype=bool)
    use[1] = False
    out = float(np.sum(weight[use] * q_k[use] ** 2 / stiff[use]))
    if not skip_rigid and q_k[1] != 0:
        out += math.pi * R_m * q_k[1] ** 2 / k_f if k_f > 0 else math.inf
    return out


def ring_on_seat(R_m: float, width_m: float, thickness_m: float, E_Pa: float, foundation_N_per_m2: float,
                 *, exponent: float = 10.0 / 9.0) -> RingOnSeat:
    """Radial compliance of a ring under the load zone on a Winkler seat (module doc); linear, so
    independent of the load."""
    if min(R_m, width_m, thickness_m, E_Pa) <= 0 or foundation_N_per_m2 < 0 or thickness_m >= R_m:
        raise InputError(f"ring R {R_m!r} m, width {width_m!r} m, thickness {thickness_m!r} m, foundation "
                         f"{foundation_N_per_m2!r} N/m^2: need positive sizes, thickness < R, foundation >= 0")
    c = load_zone_coefficients(exponent)
    # q0 per unit F: F = int q cos psi R dpsi = pi R q_1 (only the k = 1 mode carries a net force)
    q_k = c / (math.pi * R_m * c[1])
    EI = E_Pa * width_m * thickness_m ** 3 / 12
    EA = E_Pa * width_m * thickness_m
    bend = ring_modal_compliance(q_k, R_m, EI, EA, foundation_N_per_m2, skip_rigid=True)
    rigid = math.pi * R_m * q_k[1] ** 2 / foundation_N_per_m2 if foundation_N_per_m2 > 0 else math.inf
    return RingOnSeat(bend + rigid, bend, rigid,
                      "thin ring on a Winkler seat, Fourier modes of the Stribeck load zone (Timoshenko; check "
                      "Roark table 9.2 diametral load 0.1488 W R^3/EI)")


def cup_section_m(bearing) -> tuple[float, float, float]:
    """(mean radius, width, thickness) of a tapered roller bearing's cup at the raceway middle:
    t = (D - D_pw - D_we) / 2 (the derived geometry of fem.tapered_roller), width C."""
    t = 0.5 * (bearing.D_mm - bearing.pitch_diameter_mm - bearing.roller_diameter_mm)
    return 0.5 * (bearing.D_mm - t) * 1e-3, bearing.C_mm * 1e-3, t * 1e-3


def pressure_centre_moment_Nm(case, torque_Nm: float) -> dict:
    """Moment of each support's radial reaction about its bearing centre (module doc): the torque
    part F_t (fixed in the carrier) and the amplitude of the couple part F_c (turning with the
    crank), each times the pressure-centre offset a; signs for the X pair (toward the pair centre)."""
    b = tapered_roller.case_bearing(case)
    a = b.pressure_centre_offset_mm * 1e-3
    ld = tapered_roller.crank_support_load_N(case, torque_Nm)
    return {"offset_m": a, "torque_part_Nm": ld["radial_N"] * a, "couple_part_Nm": ld["couple_N"] * a,
            "operating_Nm": tapered_roller.operating_radial_load_N(case, torque_Nm) * a,
            "source": f"{b.designation}: pressure centre (D_pw/2) tan(alpha) = {a * 1e3:.2f} mm from the contact "
                      f"mid-plane (fem.tapered_roller); M = F_r a per bearing"}
