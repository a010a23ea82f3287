"""First-stage (sun-planet) involute mesh stiffness after ISO 6336-1:2019, method B (sec. 9).

Single-pair stiffness c' = c'_th C_M C_R C_B cos(beta), with 1/c'_th = q' from the standard's
polynomial in the virtual tooth numbers and profile shifts x1, x2 (eq. 74, table 9: valid for
x1 >= x2 and -0.5 <= x1 + x2 <= 2); C_M = 0.8 (solid gear blanks measured), C_R = 1 (solid
blanks), C_B = 1 (basic rack ISO 53). Mesh stiffness c_gamma_alpha = c' (0.75 eps_alpha + 0.25)
(eq. 77), times the face width. Time variation: a rectangular wave between one pair (c' b) and
two pairs (about 2 c' b), so the peak-to-peak over the mean is c' / c_gamma_alpha.
Spur gears with the case's zero-sum profile shift ([stage1] profile_shift: sun x1, planets
x2 = -x1, standard centre distance); eps_alpha from the shifted tip diameters (geometry.spur).
Limits: ISO's own (steel, b / m > 5 recommended).
"""
from __future__ import annotations

from geometry.spur import transverse_contact_ratio


def single_pair_stiffness_N_per_mm_um(z1: int, z2: int, x1: float = 0.0, x2: float = 0.0) -> float:
    """c' [N/(mm um)] of ISO 6336-1 method B for spur gears with C_M = 0.8, C_R = C_B = 1."""
    q = (0.04723 + 0.15551 / z1 + 0.25791 / z2 - 0.00635 * x1 - 0.11654 * x1 / z1
         - 0.00193 * x2 - 0.24188 * x2 / z2 + 0.00529 * x1 ** 2 + 0.00182 * x2 ** 2)
    return 0.8 / q


def mesh_stiffness(case) -> dict:
    """Mean mesh stiffness [N/m], its peak-to-peak variation over the mean, the contact ratio."""
    s = case.stage1
    x1, x2 = s.profile_shift, s.planet_profile_shift
    eps = transverse_contact_ratio(s.z1, s.z2, s.module_mm, s.pressure_angle_deg, x1, x2)
    c1 = single_pair_stiffness_N_per_mm_um(s.z1, s.z2, x1, x2)
    c_gamma = c1 * (0.75 * eps + 0.25)
    return {"mean_stiffness_N_per_m": c_gamma * s.face_width_mm * 1e6,
            "single_pair_stiffness_N_per_m": c1 * s.face_width_mm * 1e6,
            "stiffness_variation": c1 / c_gamma, "contact_ratio": eps,
            "profile_shift": (x1, x2),
            "source": "ISO 6336-1:2019 method B (q' polynomial with the profile shifts x1, x2, C_M = 0.8, "
                      "C_R = C_B = 1), c_gamma_alpha = c' (0.75 eps_alpha + 0.25); eps_alpha from the "
                      f"shifted tip diameters (x1 = {x1:g}, x2 = {x2:g}, standard centre distance)"}
