"""Discs warmer than the parts around them: the geometry a uniform temperature difference gives.

A what-if of the operating map (`conditions`), not the prediction: the discs sit between the two
loaded bearing sets that make most of the heat (needles in their bores, pins on their flanks), so at
speed they may run warmer than the pin ring, the cranks and the carrier, which the oil and the
housing cool. How much warmer depends on the bench's test sequence (an output revolution is 2.7 s at
1800 rpm, thermal time constants are minutes), which no record gives; the what-if asks what a stated
difference dT would do.

A disc dT warmer grows about its own centre by eps = alpha dT (free expansion, no stress), to first
order in eps:
  profile      the pin-centre curve (R + dR, E) and its offset Rr + dRr all scale by 1 + eps:
               dR += eps R, dRr += eps Rr (geometry.params.Modification), i.e. the flank moves out by
               eps (R - Rr) against the pins; E grows by eps E (0.02 um/K at E = 2 mm, neglected: the
               eccentricity is the crank's);
  crank holes  their circle grows: every hole eps a outward (Errors.crank_hole_position_um);
  bores        each hole's radius grows eps r_h against its cold eccentric and needles: the needle
               clearance opens by eps r_h (Errors.turning_arm_clearance_um, a radial clearance).
alpha: bearing steel, 11.5e-6 /K at 20-100 C (100Cr6 to EN ISO 683-17: 11.4e-6, Lucefin technical card
1.3505; AISI 52100: 11.9e-6, Carter Bearings' data; the what-if scales with it). Pins, ring, cranks
and carrier stay at the reference temperature. dT >= 0 (cooler discs would press the needles: no
clearance law for that).
"""
from __future__ import annotations

import numpy as np

STEEL_EXPANSION_PER_K = 11.5e-6


def warmer_discs(case, dT_K: float, alpha_per_K: float = STEEL_EXPANSION_PER_K):
    """The case with both discs dT_K warmer than every other part (module docstring)."""
    if not (np.isfinite(dT_K) and dT_K >= 0):
        raise ValueError(f"disc temperature difference = {dT_K!r} K: allowed finite and >= 0")
    eps = alpha_per_K * float(dT_K)
    c, m, er = case.cycloid, case.modification, case.errors
    case = case.replace("modification", offset_mm=m.offset_mm + eps * c.pin_circle_radius_mm,
                        equidistant_mm=m.equidistant_mm + eps * c.pin_radius_mm)
    holes = np.asarray(er.crank_hole_position_um, float) + eps * case.carrier.crank_circle_radius_mm * 1e3
    return case.with_errors(crank_hole_position_um=tuple(float(v) for v in holes),
                            turning_arm_clearance_um=er.turning_arm_clearance_um
                            + eps * case.disc.crank_hole_radius_mm * 1e3)
