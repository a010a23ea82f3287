"""The validated case's sizes in SI units, made once per case: `ReducerCase.si` (a `CaseSI`).

The case file states lengths in mm as a drawing does (errors in um, the modulus in GPa); the
dynamics and the pipeline compute in m, N, Pa. Each size a stage reads in SI is converted here once,
in exactly the arithmetic the stages used inline (the modified pin circle radius is (R + dR) 1e-3,
not R 1e-3 + dR 1e-3), so the numbers are the same to the last bit. As-built errors stay in um on
the case (each coupling scales its own error fields, `dynamics.couplings`); paper 000's four-bar
model works in mm as its paper does (`dynamics.fourbar`); the FE stage converts its own inputs.
"""
from __future__ import annotations

from dataclasses import dataclass

MM = 1e-3     # m per mm
GPA = 1e9     # Pa per GPa


@dataclass(frozen=True)
class CaseSI:
    # cycloid stage
    pin_circle_radius_m: float            # R
    pin_radius_m: float                   # Rr
    eccentricity_m: float                 # E
    disc_width_m: float                   # one disc's face width
    modified_pin_circle_radius_m: float   # R + dR: the profile's moved-distance modification
    modified_pin_radius_m: float          # Rr + dRr: the profile's equidistant modification
    disc_mean_radius_m: float             # R - Rr, the mean of the disc's root and tip radius
    # carrier and disc
    crank_circle_radius_m: float
    pillar_circle_radius_m: float
    pillar_hole_radius_m: float           # pillar radius + its radial play in the disc hole
    output_flange_radius_m: float
    crank_hole_radius_m: float
    centre_hole_radius_m: float
    # crankshaft
    eccentric_radius_m: float
    journal_radius_m: float
    journal_length_m: float
    # first stage (involute)
    sun_pitch_radius_m: float             # m z1 / 2
    planet_pitch_radius_m: float          # m z2 / 2
    gear_face_width_m: float
    youngs_modulus_Pa: float


def case_si(case) -> CaseSI:
    """The SI view of a validated ReducerCase (read through `ReducerCase.si`, made once per case)."""
    cy, m, s1, cr, dc, ks = case.cycloid, case.modification, case.stage1, case.carrier, case.disc, case.crankshaft
    return CaseSI(
        pin_circle_radius_m=cy.pin_circle_radius_mm * MM, pin_radius_m=cy.pin_radius_mm * MM,
        eccentricity_m=cy.eccentricity_mm * MM, disc_width_m=cy.width_mm * MM,
        modified_pin_circle_radius_m=(cy.pin_circle_radius_mm + m.offset_mm) * MM,
        modified_pin_radius_m=(cy.pin_radius_mm + m.equidistant_mm) * MM,
        disc_mean_radius_m=(cy.pin_circle_radius_mm - cy.pin_radius_mm) * MM,
        crank_circle_radius_m=cr.crank_circle_radius_mm * MM, pillar_circle_radius_m=cr.pillar_circle_radius_mm * MM,
        pillar_hole_radius_m=(cr.pillar_radius_mm + dc.pillar_hole_clearance_mm) * MM,
        output_flange_radius_m=cr.output_flange_radius_mm * MM,
        crank_hole_radius_m=dc.crank_hole_radius_mm * MM, centre_hole_radius_m=dc.centre_hole_radius_mm * MM,
        eccentric_radius_m=ks.eccentric_radius_mm * MM, journal_radius_m=ks.journal_radius_mm * MM,
        journal_length_m=ks.journal_length_mm * MM,
        sun_pitch_radius_m=s1.module_mm * s1.z1 / 2 * MM, planet_pitch_radius_m=s1.module_mm * s1.z2 / 2 * MM,
        gear_face_width_m=s1.face_width_mm * MM,
        youngs_modulus_Pa=case.material.youngs_modulus_GPa * GPA)
