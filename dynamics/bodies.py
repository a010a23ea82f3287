"""Inertias of the rigid bodies of the lumped model, from the case geometry (steel bodies).

Shapes (ASSUMED where the case gives no drawing):
  disc      annulus of the mean of root and tip radius (R - Rr), one disc width thick, minus the
            centre hole, the crank holes and the pillar holes (parallel-axis terms included);
  crank     eccentrics (one disc width each, at the eccentricity), two journals, the planet gear
            (pitch radius, face width) as solid cylinders;
  carrier   two steel flanges of the output-flange radius and one disc width each, plus
            case.dynamics.load_inertia_kg_m2 and the cranks carried at the crank radius.
"""
from __future__ import annotations

import math

from geometry.case_si import MM


def inertias(case, stiffness=None) -> dict:
    """Per DOF block of `dynamics.layout.DofLayout.standard`, the mass [kg] or inertia [kg m^2]
    of each component of one item (the housing: each mode's modal mass, from its FE)."""
    cy, cr, si = case.cycloid, case.carrier, case.si
    nc, nd = cr.crank_count, cy.disc_count
    rho = case.material.density_kg_per_m3
    a = si.crank_circle_radius_m
    w = si.disc_width_m
    r_disc = si.disc_mean_radius_m      # mean of root and tip radius
    holes = [(si.centre_hole_radius_m, 0.0)] + [(si.crank_hole_radius_m, a)] * nc \
        + [(si.pillar_hole_radius_m, si.pillar_circle_radius_m)] * cr.pillar_count
    m_disc = rho * w * math.pi * (r_disc ** 2 - sum(r ** 2 for r, _ in holes))
    j_disc = rho * w * math.pi * (r_disc ** 4 / 2 - sum(r ** 2 * (r ** 2 / 2 + c ** 2) for r, c in holes))
    r_e, r_j, r_pl = si.eccentric_radius_m, si.journal_radius_m, si.planet_pitch_radius_m
    # the two lengths multiply in mm and then by MM, as before the SI view: the same bits (1 ulp apart
    # on the RV-40E-105 otherwise, and every artifact was to stay byte-identical)
    parts = ([(rho * math.pi * r_e ** 2 * w, r_e)] * nd
             + [(rho * math.pi * r_j ** 2 * case.crankshaft.journal_length_mm * MM, r_j)] * 2
             + [(rho * math.pi * r_pl ** 2 * case.stage1.face_width_mm * MM, r_pl)])
    m_crank = sum(m for m, _ in parts)
    j_crank = sum(m * r ** 2 / 2 for m, r in parts) + nd * parts[0][0] * si.eccentricity_m ** 2
    r_f = si.output_flange_radius_m
    m_carrier = rho * math.pi * r_f ** 2 * 2 * w
    j_out = m_carrier * r_f ** 2 / 2 + case.dynamics.load_inertia_kg_m2 + nc * m_crank * a ** 2
    # the crank's lateral mass lumped equally at its disc planes (crank_axis: one item per plane)
    hm = None if stiffness is None else stiffness.parts.get("housing")
    return {"carrier": [j_out], "crank_rotation": [j_crank], "crank_axis": [m_crank / nd, m_crank / nd],
            "disc": [m_disc, m_disc, j_disc], "housing": [] if hm is None else list(hm.mass_kg)}
