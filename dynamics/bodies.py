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


def inertias(case, stiffness=None) -> dict:
    """Per DOF block of `dynamics.layout.DofLayout.standard`, the mass [kg] or inertia [kg m^2]
    of each component of one item (the housing: each mode's modal mass, from its FE)."""
    cy, s1, cr, dc, ks = case.cycloid, case.stage1, case.carrier, case.disc, case.crankshaft
    mm = 1e-3
    nc, nd = cr.crank_count, cy.disc_count
    rho = case.material.density_kg_per_m3
    a = cr.crank_circle_radius_mm * mm
    w = cy.width_mm * mm
    r_disc = (cy.pin_circle_radius_mm - cy.pin_radius_mm) * mm      # mean of root and tip radius
    holes = [(dc.centre_hole_radius_mm * mm, 0.0)] + [(dc.crank_hole_radius_mm * mm, a)] * nc \
        + [((cr.pillar_radius_mm + dc.pillar_hole_clearance_mm) * mm, cr.pillar_circle_radius_mm * mm)] \
        * cr.pillar_count
    m_disc = rho * w * math.pi * (r_disc ** 2 - sum(r ** 2 for r, _ in holes))
    j_disc = rho * w * math.pi * (r_disc ** 4 / 2 - sum(r ** 2 * (r ** 2 / 2 + c ** 2) for r, c in holes))
    r_e, r_j, r_pl = ks.eccentric_radius_mm * mm, ks.journal_radius_mm * mm, s1.module_mm * s1.z2 / 2 * mm
    parts = ([(rho * math.pi * r_e ** 2 * w, r_e)] * nd
             + [(rho * math.pi * r_j ** 2 * ks.journal_length_mm * mm, r_j)] * 2
             + [(rho * math.pi * r_pl ** 2 * s1.face_width_mm * mm, r_pl)])
    m_crank = sum(m for m, _ in parts)
    j_crank = sum(m * r ** 2 / 2 for m, r in parts) + nd * parts[0][0] * (cy.eccentricity_mm * mm) ** 2
    r_f = cr.output_flange_radius_mm * mm
    m_carrier = rho * math.pi * r_f ** 2 * 2 * w
    j_out = m_carrier * r_f ** 2 / 2 + case.dynamics.load_inertia_kg_m2 + nc * m_crank * a ** 2
    # the crank's lateral mass lumped equally at its disc planes (crank_axis: one item per plane)
    hm = None if stiffness is None else stiffness.parts.get("housing")
    return {"carrier": [j_out], "crank_rotation": [j_crank], "crank_axis": [m_crank / nd, m_crank / nd],
            "disc": [m_disc, m_disc, j_disc], "housing": [] if hm is None else list(hm.mass_kg)}
