"""First-stage (sun-planet) involute mesh stiffness after ISO 6336-1:2019, method B (sec. 9).

Single-pair stiffness c' = c'_th C_M C_R C_B cos(beta), with 1/c'_th = q' from the standard's
polynomial in the virtual tooth numbers and profile shifts (eq. 74, table 9); C_M = 0.8 (solid
gear blanks measured), C_R = 1 (solid blanks), C_B = 1 (standard basic rack ISO 53).
Mesh stiffness c_gamma_alpha = c' (0.75 eps_alpha + 0.25) (eq. 77), times the face width.
Time variation: a rectangular wave between one pair (c' b) and two pairs (about 2 c' b), so the
peak-to-peak over the mean is c' / c_gamma_alpha. Spur gears, no profile shift (x = 0), standard
addendum m and the case's pressure angle. Limits: ISO's own (steel, b / m > 5 recommended).
"""
from __future__ import annotations

import math


def transverse_contact_ratio(z1: int, z2: int, module_mm: float, pressure_angle_deg: float,
                             addendum_coeff: float = 1.0) -> float:
    """eps_alpha of an external spur pair at the standard centre distance."""
    a = math.radians(pressure_angle_deg)
    r1, r2 = module_mm * z1 / 2, module_mm * z2 / 2
    ra1, ra2 = r1 + addendum_coeff * module_mm, r2 + addendum_coeff * module_mm
    rb1, rb2 = r1 * math.cos(a), r2 * math.cos(a)
    path = math.sqrt(ra1 ** 2 - rb1 ** 2) + math.sqrt(ra2 ** 2 - rb2 ** 2) - (r1 + r2) * math.sin(a)
    return path / (math.pi * module_mm * math.cos(a))


def single_pair_stiffness_N_per_mm_um(z1: int, z2: int, x1: float = 0.0, x2: float = 0.0) -> float:
    """c' [N/(mm um)] of ISO 6336-1 method B for spur gears with C_M = 0.8, C_R = C_B = 1."""
    q = (0.04723 + 0.15551 / z1 + 0.25791 / z2 - 0.00635 * x1 - 0.11654 * x1 / z1
         - 0.00193 * x2 - 0.24188 * x2 / z2 + 0.00529 * x1 ** 2 + 0.00182 * x2 ** 2)
    return 0.8 / q


def mesh_stiffness(case) -> dict:
    """Mean mesh stiffness [N/m], its peak-to-peak variation over the mean, the contact ratio."""
    s = case.stage1
    eps = transverse_contact_ratio(s.z1, s.z2, s.module_mm, s.pressure_angle_deg)
    c1 = single_pair_stiffness_N_per_mm_um(s.z1, s.z2)
    c_gamma = c1 * (0.75 * eps + 0.25)
    return {"mean_stiffness_N_per_m": c_gamma * s.face_width_mm * 1e6,
            "single_pair_stiffness_N_per_m": c1 * s.face_width_mm * 1e6,
            "stiffness_variation": c1 / c_gamma, "contact_ratio": eps,
            "source": "ISO 6336-1:2019 method B (q' polynomial, C_M = 0.8, C_R = C_B = 1), "
                      "c_gamma_alpha = c' (0.75 eps_alpha + 0.25); eps_alpha from the standard-addendum geometry"}
