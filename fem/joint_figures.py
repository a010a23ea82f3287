"""The case's joint, ring and main-bearing figures at a torque (rated by default), each with its
band (low / high ends of the contact-layer constants): what fem.joints, fem.bolts, fem.support_rings
and fem.main_bearings give for the sizes the case states. Runnable:
`python -m fem.joint_figures cases/rv40e-81.toml` prints them as JSON.
"""
from __future__ import annotations

import json
import math
import sys

from fem import bolts, joints, main_bearings, support_rings, tapered_roller

ARCMIN = math.pi / 10800


def support_seats(case, torque_Nm: float) -> dict:
    """Tangent radial compliance of one support bearing's cup seat and cone seat at the operating
    load (fem.tapered_roller.operating_radial_load_N), and the cup's ring-on-seat figures (the same
    cup seat as a linear ring on the layer: a cross-check of cup_seat_m_per_N, not an addition)."""
    b = tapered_roller.case_bearing(case)
    jt, E = case.joints, case.material.youngs_modulus_GPa * 1e9
    F = tapered_roller.operating_radial_load_N(case, torque_Nm)
    law = joints.contact_law(jt.seat_roughness_Ra_um)
    D, d = b.D_mm * 1e-3, b.d_mm * 1e-3
    cup_race = (b.pitch_diameter_mm + b.roller_diameter_mm) * 1e-3      # cup raceway (mid), fem.support_rings
    cone_race = (b.pitch_diameter_mm - b.roller_diameter_mm) * 1e-3
    pf_cup = joints.fit_pressure_Pa(jt.support_cup_interference_um * 1e-6, D, cup_race,
                                    D + 2 * jt.support_seat_wall_mm * 1e-3, E, law)
    pf_cone = joints.fit_pressure_Pa(jt.support_cone_interference_um * 1e-6, d, 0.0, cone_race, E, law)
    cup = joints.ring_seat_radial(F, D, b.C_mm * 1e-3, pf_cup, jt.seat_roughness_Ra_um)
    cone = joints.ring_seat_radial(F, d, b.B_mm * 1e-3, pf_cone, jt.seat_roughness_Ra_um)
    R, w, t = support_rings.cup_section_m(b)
    # the seat as the cup's foundation: the layer's tangent at the fit pressure plus the projected
    # bearing pressure F / (D C) (the load zone's mean), so it is linearised where the layer works
    p_seat = pf_cup + F / (D * b.C_mm * 1e-3)
    ring = support_rings.ring_on_seat(R, w, t, E, float(law.normal_stiffness_N_per_m3(p_seat)) * w)
    return {"operating_load_N": F, "cup_fit_pressure_Pa": pf_cup, "cone_fit_pressure_Pa": pf_cone,
            "cup_seat_m_per_N": cup.compliance_m_per_N, "cup_seat_band": cup.band_compliance_m_per_N,
            "cone_seat_m_per_N": cone.compliance_m_per_N, "cone_seat_band": cone.band_compliance_m_per_N,
            "seats_m_per_N": cup.compliance_m_per_N + cone.compliance_m_per_N,
            "seats_band": tuple(a + c for a, c in zip(cup.band_compliance_m_per_N, cone.band_compliance_m_per_N)),
            "seat_pressure_beyond_law": cup.beyond_law or cone.beyond_law,
            "cup_ring_bending_m_per_N": ring.bending_m_per_N, "cup_ring_total_m_per_N": ring.compliance_m_per_N,
            "pressure_centre": support_rings.pressure_centre_moment_Nm(case, torque_Nm), "source": cup.source}


def pillar(case) -> dict:
    """The pillar joint's bolt, preload and FE-layer moduli (per pillar)."""
    jt, cr = case.joints, case.carrier
    E, nu = case.material.youngs_modulus_GPa * 1e9, case.material.poisson_ratio
    th = bolts.thread(jt.pillar_bolt_thread_mm)
    bj = bolts.bolted_joint(jt.pillar_bolt_thread_mm, jt.pillar_bolt_property_class, jt.thread_friction,
                            jt.pillar_clamp_length_mm * 1e-3, 2 * cr.pillar_radius_mm * 1e-3, E)
    dp = jt.taper_pin_diameter_mm * 1e-3
    # face: the pillar's end less the tapped hole and the pin hole
    area = math.pi * ((cr.pillar_radius_mm * 1e-3) ** 2 - (th.d_m / 2) ** 2 * jt.pillar_bolts_per_pillar
                      - (dp / 2) ** 2)
    # ASSUMED pin engagement: two pin diameters in each part (common dowel practice)
    k_pin = bolts.huth_shear_stiffness_N_per_m(dp, 2 * dp, 2 * dp, E)
    pj = joints.pillar_joint_layer(bj.preload_N * jt.pillar_bolts_per_pillar, area, jt.face_roughness_Ra_um,
                                   E_Pa=E, nu=nu, pin_stiffness_N_per_m=k_pin,
                                   bolt_stiffness_N_per_m=bj.bolt_stiffness_N_per_m * jt.pillar_bolts_per_pillar)
    h = 1e-3
    return {"preload_N": bj.preload_N, "bolt_stiffness_N_per_m": bj.bolt_stiffness_N_per_m,
            "member_stiffness_N_per_m": bj.member_stiffness_N_per_m, "load_factor": bj.load_factor,
            "face_area_m2": area, "face_pressure_Pa": pj.mid.pressure_Pa, "pressure_beyond_law": pj.mid.beyond_law,
            "pin_shear_N_per_m": k_pin,
            "normal_N_per_m": {b: getattr(pj, b).normal_stiffness_N_per_m for b in joints.BANDS},
            "tangential_N_per_m": {b: getattr(pj, b).tangential_stiffness_N_per_m for b in joints.BANDS},
            "E_layer_h1mm_Pa": {b: getattr(pj, b).E_layer_Pa(h) for b in joints.BANDS},
            "G_layer_h1mm_Pa": {b: getattr(pj, b).G_layer_Pa(h) for b in joints.BANDS}, "source": pj.source}


def flange(case) -> dict:
    jt, E = case.joints, case.material.youngs_modulus_GPa * 1e9
    F = bolts.assembly_preload_N(jt.output_bolt_thread_mm, jt.output_bolt_property_class, jt.thread_friction)
    g_t = 2 * jt.output_bolt_thread_mm * 1e-3      # ASSUMED plate engagement of a bolt in shear: 2 d
    ff = joints.flange_face_torsional(jt.output_face_inner_radius_mm * 1e-3, jt.output_face_outer_radius_mm * 1e-3,
                                      F * jt.output_bolt_count, jt.output_bolt_count, jt.face_roughness_Ra_um,
                                      friction=jt.face_friction, torque_Nm=case.operation.momentary_torque_Nm,
                                      bolt_circle_r_m=case.carrier.output_flange_radius_mm * 1e-3,
                                      bolt_d_m=jt.output_bolt_thread_mm * 1e-3, plate_t_m=g_t, E_Pa=E,
                                      nu=case.material.poisson_ratio)
    to_arcmin = 1 / ARCMIN
    return {"bolt_preload_N": F, "face_pressure_Pa": ff.pressure_Pa, "pressure_beyond_law": ff.beyond_law,
            "compliance_arcmin_per_Nm": ff.compliance_rad_per_Nm * to_arcmin,
            "band_arcmin_per_Nm": tuple(c * to_arcmin for c in ff.band_compliance_rad_per_Nm),
            "slip_torque_Nm": ff.slip_torque_Nm, "slips_at_momentary": ff.slips,
            "bolt_shear_arcmin_per_Nm": ff.bolt_shear_compliance_rad_per_Nm * to_arcmin, "source": ff.source}


def figures(case, torque_Nm: float | None = None) -> dict:
    T = case.rated_torque_Nm if torque_Nm is None else torque_Nm
    return {"case": case.name, "torque_Nm": T, "support_seats": support_seats(case, T), "pillar": pillar(case),
            "flange": flange(case), "main_bearings": main_bearings.case_main_bearings(case, T)}


if __name__ == "__main__":
    from geometry.params import load_case
    print(json.dumps(figures(load_case(sys.argv[1])), indent=1, default=float))
