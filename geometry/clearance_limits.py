"""How much backlash, or interference, a case's profile modification may give (checked when a case
is read, geometry.params.validate), from the closed form of geometry.clearance:
b0 = (dRr - dR sqrt(1 - K1^2)) / (E zc), K1 = E zp / R, pin errors folded into dR and dRr.

  MAX_BACKLASH_ARCMIN  60 x the catalog's 1 arcmin lost motion. Beyond it the modification is no
                       longer small beside the eccentricity (the clearance model is first order in
                       dR, dRr against E) and the teeth barely engage; a 1e-9 mm eccentricity gave
                       "backlash root not bracketed near 179487 rad".
  MAX_INTERFERENCE_UM  ASSUMED 3 um of negative clearance: about a pin's contact approach at its
                       rated-torque force (~600 N on the RV-40E at 127-228 N/um tooth stiffness), a
                       preload up to the rated load; beyond it the pins are press-fitted and no pin
                       pose is free (the backlash search found no root at -39 um).
No import of geometry.params, so that params can call it (`check(case)` from validate).
"""
from __future__ import annotations

import math

from geometry.case_fields import CaseError, where

MAX_BACKLASH_ARCMIN = 60.0
MAX_INTERFERENCE_UM = 3.0


def problem(E_mm: float, zc: int, zp: int, R_mm: float, offset_mm: float, equidistant_mm: float,
            pin_circle_radius_um: float = 0.0, pin_radius_um: float = 0.0) -> tuple[tuple[str, str], str]:
    """((section, key) to blame, the rest of the message after `key = value`) or (key, '') when
    the modification is within the limits."""
    dR, dRr = offset_mm - pin_circle_radius_um * 1e-3, equidistant_mm - pin_radius_um * 1e-3
    root = math.sqrt(max(1.0 - (E_mm * zp / R_mm) ** 2, 0.0))
    clearance_mm = dRr - dR * root
    if clearance_mm * 1e3 < -MAX_INTERFERENCE_UM:
        top_offset = (dRr + MAX_INTERFERENCE_UM * 1e-3) / max(root, 1e-12) + pin_circle_radius_um * 1e-3
        low_equidistant = dR * root - MAX_INTERFERENCE_UM * 1e-3 + pin_radius_um * 1e-3
        return ("modification", "offset_mm"), (
            f" with equidistant_mm = {equidistant_mm:g}: the profile's clearance dRr - dR sqrt(1 - K1^2) is "
            f"{clearance_mm * 1e3:.4g} um (pin errors included), an interference; allowed down to "
            f"-{MAX_INTERFERENCE_UM:g} um (a preload of about the rated pin force): offset_mm <= {top_offset:.4g} mm "
            f"for this equidistant, or equidistant_mm >= {low_equidistant:.4g} mm for this offset")
    b0_arcmin = math.degrees(clearance_mm / (E_mm * zc)) * 60.0
    if b0_arcmin > MAX_BACKLASH_ARCMIN:
        b_max = math.radians(MAX_BACKLASH_ARCMIN / 60.0)
        return ("cycloid", "eccentricity_mm"), (
            f" with [modification] offset_mm = {offset_mm:g}, equidistant_mm = {equidistant_mm:g}: the profile's "
            f"clearance {clearance_mm * 1e3:.4g} um over E zc gives {b0_arcmin:.4g} arcmin of backlash (b0 = (dRr - "
            f"dR sqrt(1 - K1^2)) / (E zc)); allowed at most {MAX_BACKLASH_ARCMIN:g} arcmin: eccentricity_mm >= "
            f"{clearance_mm / (zc * b_max):.3g} for this modification, or a clearance <= "
            f"{b_max * E_mm * zc * 1e3:.4g} um for this eccentricity")
    return ("", ""), ""


def check(case) -> None:
    """CaseError naming the key when the case's modification is beyond a limit (validate)."""
    c, m, e = case.cycloid, case.modification, case.errors
    key, why = problem(c.eccentricity_mm, c.zc, c.zp, c.pin_circle_radius_mm, m.offset_mm,
                       m.equidistant_mm, e.pin_circle_radius_um, e.pin_radius_um)
    if why:
        raise CaseError(f"{where(*key, case.source)} = {getattr(getattr(case, key[0]), key[1]):g}{why}")
