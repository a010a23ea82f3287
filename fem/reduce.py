"""Reduce every FE/closed-form result of the FEM stage to the stiffness.json schema (rv-stiffness/3).

build_stiffness(case, ...) runs independent tasks (`_component`, so `--workers` runs them in
parallel): the 2D tooth-pin contact map (fem.pin_contact), the 3D crankshaft torsion (fem.shaft),
the crankshaft flexibility with both eccentrics loaded (fem.crank_tilt), the turning-arm bearing
(2D FE, fem.bearing), the crank support bearings (fem.tapered_roller), the carrier (3D FE,
fem.carrier), the disc body (2D FE, fem.disc_body) and the pin in its groove (fem.pin_groove);
then, in this process, the involute mesh (fem.involute) and the needle edge loading
(fem.needle_edge, the crank slope from the crank FE). Every entry carries a source and a check
(the FE beside its closed form); extras keep mesh sizes and timings.

Load ranges (`table_loads_N`): the pin-contact map and the needle curve reach the catalog momentary
torque times LOAD_MARGIN over the classical sharing, because the lumped model's pins and needles
carry more than the classical estimate (measured, see LOAD_MARGIN); tests/test_fem_reduce.py checks
that the model's largest forces at the momentary torque lie inside the tables.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from fem import bearing, involute, pin_contact, shaft
from fem.stiffness import (CarrierSeats, CrankBending, PinContact, PinSeries, StiffnessModel, SupportBearings,
                           TurningArm)

# The lumped model's largest pin and needle forces over the classical estimates (pins:
# pin_contact.contact_force_at_torque; needles: needle_force_classical_N), measured on
# tests/support.model_for_tests with static solves at 12 input angles over one pin pitch: at the
# momentary torque pins 1.46 (rv40e-81) / 1.37 (rv160n-81), needles 1.37 / 1.37 (at the rated
# torque pins 1.86 / 1.82: fewer pins share a light load). 1.8 covers the largest momentary ratio
# with 23 % to spare for the FE's other sharing and as-built errors (tests/test_fem_reduce.py).
LOAD_MARGIN = 1.8
PIN_LOWEST_OF_RATED = 0.125   # lowest pin level / the rated classical force (the former table's low end)
PIN_LEVELS = 8                # geometric spacing: 1.84x per level on the shipped cases
DISC_BODY_ANGLES = 6          # crank angles over one crank spacing (the load pattern's period)
ARCMIN_PER_RAD = 180 * 60 / math.pi


@dataclass(frozen=True)
class FemRun:
    model: StiffnessModel
    tooth_map: pin_contact.ToothPairMap
    crank_fields: dict


def needle_force_classical_N(case, torque_Nm: float) -> float:
    """One needle bearing's load, classical sharing: the more loaded disc's tangential share per
    crank (bearing.turning_arm_max_load) and its pin resultant per crank, R / n_c with
    R = T_d / (z_c e) (fem.tapered_roller.crank_support_load_N), at right angles."""
    from fem.tapered_roller import crank_support_load_N
    R = crank_support_load_N(case, torque_Nm)["disc_resultant_N"] / case.carrier.crank_count
    return math.hypot(bearing.turning_arm_max_load(case, torque_Nm), R)


def table_loads_N(case) -> dict:
    """Load levels of the pin-contact map and the needle curve (module doc), N."""
    mom = case.operation.momentary_torque_Nm
    top = LOAD_MARGIN * pin_contact.contact_force_at_torque(case, mom)
    low = PIN_LOWEST_OF_RATED * pin_contact.contact_force_at_torque(case, case.rated_torque_Nm)
    needle = LOAD_MARGIN * needle_force_classical_N(case, mom) * np.asarray(bearing.LOAD_FRACTIONS)
    return {"pin": np.geomspace(low, top, PIN_LEVELS), "needle": needle}


def _timed(func, *args, **kwargs):
    t0 = time.perf_counter()
    return func(*args, **kwargs), time.perf_counter() - t0


def _component(name: str, case, options: dict):
    """One independent FE sub-problem of the stage (a task: pure, picklable in and out)."""
    from fem import crank_tilt, pin_groove, tapered_roller
    loads = table_loads_N(case)
    if name == "tooth_map":
        return _timed(pin_contact.tooth_pair_map, case, positions_deg=options["positions_deg"],
                      loads_N=loads["pin"], mesh_size_m=options["mesh_size_m"])
    if name == "crankshaft":
        return _timed(shaft.crankshaft_stiffness, case, options["crank_edge_m"], mesh3=options["crank_mesh"])
    if name == "turning_arm":
        return _timed(bearing.turning_arm_curve, case, float(loads["needle"][-1]))
    if name == "support_bearings":
        top = LOAD_MARGIN * tapered_roller.operating_radial_load_N(case, case.operation.momentary_torque_Nm)
        return _timed(tapered_roller.case_support_bearings, case, top)
    if name == "crank_bending":
        return _timed(crank_tilt.case_crank_bending, case, mesh3=options["crank_mesh"],
                      edge_length_m=options["crank_edge_m"])
    if name == "carrier":
        return _timed(_carrier, case, options.get("carrier_levels"))
    if name == "disc_body":
        return _timed(_disc_body, case, options.get("disc_h_profile_m"))
    if name == "pin_groove":
        return _timed(pin_groove.case_series, case, loads["pin"])
    raise ValueError(name)


def _carrier(case, levels=None) -> dict:
    """fem.carrier's default estimate (levels: its two mesh sizes, default carrier.DEFAULT_LEVELS),
    its order checked against the lumped model's seats."""
    from fem import carrier
    g, fe = carrier.carrier_for_case(case, **({} if levels is None else {"levels": levels}))
    nc = g.crank_count
    want = [f"crank{j + 1}_{s}_{ax}" for j in range(nc) for s in carrier.SEATS for ax in "xy"]
    if list(fe.labels) != want or not np.allclose(fe.crank_angles_rad, 2 * np.pi * np.arange(nc) / nc):
        raise RuntimeError(f"carrier seat order {fe.labels} / angles {fe.crank_angles_rad}: expected crank j "
                           f"at 2 pi j / nc, seats (flange, end plate), (x, y) (fem.stiffness.CarrierSeats)")
    E, nu = case.material.youngs_modulus_GPa * 1e9, case.material.poisson_ratio
    portal = carrier.portal_frame_reference(g, E, nu)["end_plate_stiffness_Nm_per_rad"] / ARCMIN_PER_RAD
    ex = fe.extrapolation
    check = {"torsional_stiffness_Nm_per_arcmin": fe.torsional_stiffness_Nm_per_arcmin(0.5),
             "end_plate_load_only_Nm_per_arcmin": fe.torsional_stiffness_Nm_per_arcmin(0.0),
             "portal_frame_rigid_plates_Nm_per_arcmin": portal,
             "end_plate_only_over_portal_frame": fe.torsional_stiffness_Nm_per_arcmin(0.0) / portal,
             "racking_rad_per_Nm": fe.racking_rad_per_Nm(0.5),
             "richardson_levels_edge_length_m": list(ex["edge_length_m"]), "richardson_order": ex["order"],
             "richardson_levels_dofs": list(ex["dofs"]),
             "richardson_levels_Nm_per_arcmin": [1 / (c * ARCMIN_PER_RAD) for c in
                                                 ex["torsional_compliance_rad_per_Nm"]],
             "asymmetry": fe.asymmetry, "rigid_mode_residual": fe.rigid_mode_residual,
             "equilibrium_residual": fe.equilibrium_residual, "condition_number": fe.condition_number}
    return {"compliance_m_per_N": fe.compliance_m_per_N, "check": check,
            "mesh": {"nodes": fe.nodes, "tets": fe.tets, "dofs": fe.dofs, "edge_length_m": fe.edge_length_m,
                     "mesh_s": fe.mesh_seconds, "solve_s": fe.solve_seconds}}


def _disc_body(case, h_profile_m: float | None = None) -> dict:
    """Energy-equivalent per-pin compliance of the disc body, sum F_i delta_i / sum F_i^2 under the
    classical sharing at the rated torque (half per disc), mean over DISC_BODY_ANGLES crank angles
    across one crank spacing (disc 2 at psi + pi sits at another phase of the same period)."""
    from fem import disc_body as db
    m = db.DiscBodyModel.build(case, h_profile_m)
    psi = 2 * np.pi / case.carrier.crank_count * np.arange(DISC_BODY_ANGLES) / DISC_BODY_ANGLES
    c, res = [], []
    for p in psi:
        r = m.solve(float(p), 0.5 * case.rated_torque_Nm)
        F = r.pattern.force_N
        c.append(float(F @ r.approach_m / (F @ F)))
        res.append(r)
    lame = db.lame_ring_check(h_profile_m or db.default_h_profile_m(case))
    check = {"per_angle_m_per_N": c, "crank_angle_rad": psi.tolist(),
             "rotation_per_torque_rad_per_Nm": [r.rotation_per_torque_rad_per_Nm for r in res],
             "tooth_local_taken_out_rad_per_Nm": [r.tooth_local_per_torque_rad_per_Nm for r in res],
             "bore_ring_taken_out_rad_per_Nm": [r.bore_ring_per_torque_rad_per_Nm for r in res],
             "frame_residual_m": max(r.frame_residual_m for r in res),
             "imbalance": max(r.imbalance for r in res), "reaction": max(r.reaction for r in res),
             "lame_ring_inner_error": lame["inner_error"], "lame_ring_outer_error": lame["outer_error"],
             "lame_ring_h_m": lame["h_m"], "dofs": res[0].dofs, "h_profile_m": res[0].h_profile_m}
    return {"compliance_m_per_N": float(np.mean(c)), "check": check}


def build_stiffness(case, *, mesh_size_m: float | None = None, crank_edge_m: float | None = None,
                    positions_deg=None, crank_mesh=None, map_tasks=None, carrier_levels=None,
                    disc_h_profile_m: float | None = None) -> FemRun:
    """crank_mesh: the crankshaft tet mesh of the mesh stage (fem.shaft.crankshaft_mesh), else made here.
    carrier_levels, disc_h_profile_m: coarser meshes than the defaults (tests).
    The FE problems are independent, run through `map_tasks(func, tasks) -> results in order`
    (default: one after the other, in this process; pipeline.sweep.run_tasks puts them on local
    processes or a Dask cluster, same results)."""
    from fem import crank_tilt, needle_edge
    t0 = time.perf_counter()
    map_tasks = map_tasks or (lambda func, tasks: [func(*t) for t in tasks])
    options = {"positions_deg": positions_deg, "mesh_size_m": mesh_size_m, "crank_edge_m": crank_edge_m,
               "crank_mesh": crank_mesh, "carrier_levels": carrier_levels, "disc_h_profile_m": disc_h_profile_m}
    names = ("carrier", "tooth_map", "disc_body", "crank_bending", "crankshaft", "turning_arm",
             "pin_groove", "support_bearings")          # longest first: the pool takes them in order
    out = dict(zip(names, map_tasks(_component, [(n, case, options) for n in names])))
    timing = {f"{n}_s": out[n][1] for n in names}
    (tm, _), ((cs, fields), _), (ta, _) = out["tooth_map"], out["crankshaft"], out["turning_arm"]
    sb, cb, car = out["support_bearings"][0], out["crank_bending"][0], out["carrier"][0]
    disc, groove = out["disc_body"][0], out["pin_groove"][0]
    bg = sb["bearing"]
    inv = involute.mesh_stiffness(case)
    beam_ref = shaft.crankshaft_beam_reference(case)
    rated = pin_contact.contact_force_at_torque(case, case.rated_torque_Nm)
    d_rated = (rated / tm.law_k_N_per_m_pow) ** (1 / tm.law_n)    # secant tooth stiffness at the rated pin force
    # needle edge loading: the eccentric's tilt per N with the shaft on its bearings
    flex_sup = crank_tilt.with_elastic_supports(cb["flex"], 1.0 / sb["stiffness_N_per_m"])
    slope = crank_tilt.eccentric_slope_per_N(case, flex_sup)
    ks = case.crankshaft
    nl = np.array([needle_force_classical_N(case, T) for T in (case.rated_torque_Nm,
                                                                case.operation.momentary_torque_Nm)])
    edge = needle_edge.slope_coupled_curve(nl, slope, needle_count=ks.needle_count,
                                           length_m=ks.needle_length_mm * 1e-3)
    tables = table_loads_N(case)
    model = StiffnessModel(
        case_name=case.name,
        pin_contact=PinContact(tm.position_deg, tm.load_N, tm.approach_m, tm.peak_pressure_Pa,
                               tm.half_width_m, tm.law_k_N_per_m_pow, tm.law_n),
        turning_arm=TurningArm(ta["load_N"], ta["deflection_m"], ta["law_k_N_per_m_pow"], ta["law_n"]),
        crankshaft_bending_stiffness_N_per_m=float(1.0 / cb["compliance_m_per_N"][0, 0]),
        crankshaft_torsional_stiffness_Nm_per_rad=cs.torsional_stiffness_Nm_per_rad,
        involute_mesh_mean_stiffness_N_per_m=inv["mean_stiffness_N_per_m"],
        involute_mesh_stiffness_variation=inv["stiffness_variation"],
        involute_mesh_contact_ratio=inv["contact_ratio"],
        support_bearings=SupportBearings(bg.designation, bg.roller_count, bg.roller_length_mm * 1e-3,
                                         bg.roller_diameter_mm * 1e-3, math.degrees(bg.alpha_rad),
                                         sb["setup"].preload_N, sb["load_N"], sb["deflection_m"],
                                         sb["operating_load_N"], sb["stiffness_N_per_m"]),
        crank_bending=CrankBending(cb["compliance_m_per_N"], cb["journal_force"]),
        carrier=CarrierSeats(car["compliance_m_per_N"]),
        pin_series=PinSeries(disc["compliance_m_per_N"], groove["load_N"], groove["series_approach_m"]),
        sources={
            "pin_contact": "2D plane-strain FE (P1, scikit-fem), condensed frictionless contact, "
                           "modified profile, pin back half on a rigid seat; load levels: load_ranges",
            "turning_arm": ta["source"] + "; loads: load_ranges",
            "crankshaft": "torsion: 3D FE (P2 tetrahedra, pytetwild) of the project's stepped crankshaft, "
                          "planet-seat face to eccentric 1 (fem.shaft); bending = 1 / C11 of crank_bending",
            "support_bearings": sb["source"],
            "crank_bending": cb["source"],
            "carrier": "3D FE (P2 tetrahedra, extruded mesh) of flange + end plate + pillars as one bonded "
                       "body, mounting face clamped, each seat a rigid ring over the bearing width, condensed "
                       "to the seat translations; two meshes Richardson-extrapolated (fem.carrier)",
            "disc_body": "2D plane-stress FE (P2) of the disc with its holes, classical pin sharing at the "
                         "rated torque, crank holes as the datum; tooth-pair region and needle bore ring taken "
                         f"out (fem.disc_body); sum F d / sum F^2, mean of {DISC_BODY_ANGLES} crank angles over "
                         "one crank spacing",
            "pin_groove": groove["source"],
            "pin_series": "disc_body + pin_groove, each in series with every tooth-pin contact (fem.stiffness.pin_law)",
            "needle_edge": "fem.needle_edge slice model with the crank slope per N from crank_bending on the "
                           "support bearings: the slope raises the edge load but does not soften the bearing "
                           "(stiffness_ratio >= 1), so the needle law (turning_arm) is used unchanged",
            "involute_mesh": inv["source"],
            "load_ranges": f"pin and needle tables up to LOAD_MARGIN = {LOAD_MARGIN:g} x the classical "
                           f"force at the catalog momentary torque {case.operation.momentary_torque_Nm:g} N m "
                           f"(fem.reduce: the lumped model's forces over the classical ones, measured 1.46 at most)",
        },
        checks={
            "pin_contact": {"fe_over_hertz_peak_pressure": [float(v) for v in (
                                (tm.peak_pressure_Pa / tm.hertz_peak_pressure_Pa).min(),
                                (tm.peak_pressure_Pa / tm.hertz_peak_pressure_Pa).max())],
                            "fe_over_hertz_half_width": [float(v) for v in (
                                (tm.half_width_m / tm.hertz_half_width_m).min(),
                                (tm.half_width_m / tm.hertz_half_width_m).max())],
                            "power_law_max_error": float(np.max(np.abs(
                                tm.law_k_N_per_m_pow[:, None] * tm.approach_m ** tm.law_n[:, None]
                                / tm.load_N[None, :] - 1)))},
            "turning_arm": {"fe_over_palmgren_deflection": [float(v) for v in (
                                (ta["deflection_m"] / ta["palmgren_deflection_m"]).min(),
                                (ta["deflection_m"] / ta["palmgren_deflection_m"]).max())],
                            "fe_over_stribeck_qmax": [float(v) for v in (
                                (ta["fe_qmax_N"] / ta["stribeck_qmax_N"]).min(),
                                (ta["fe_qmax_N"] / ta["stribeck_qmax_N"]).max())]},
            "crankshaft": {"torsion_fe_over_beam": cs.torsional_stiffness_Nm_per_rad
                           / beam_ref["torsional_stiffness_Nm_per_rad"],
                           "single_load_bending_fe_over_beam": cs.bending_stiffness_N_per_m
                           / beam_ref["bending_stiffness_N_per_m"]},
            "involute_mesh": {"single_pair_N_per_m": inv["single_pair_stiffness_N_per_m"],
                              "note": "ISO 6336-1 closed form itself (no FE)"},
            "support_bearings": sb["check"],
            "crank_bending": cb["check"],
            "carrier": car["check"],
            "disc_body": disc["check"],
            "pin_groove": groove["check"],
            "needle_edge": {"slope_rad_per_N": slope, "load_N": nl.tolist(), "tilt_rad": edge.tilt_rad.tolist(),
                            "stiffness_ratio": edge.stiffness_ratio.tolist(),
                            "edge_load_ratio": edge.edge_load_ratio.tolist(),
                            "torques_Nm": [case.rated_torque_Nm, case.operation.momentary_torque_Nm]},
            "load_ranges": {"pin_top_N": float(tables["pin"][-1]), "needle_top_N": float(tables["needle"][-1]),
                            "pin_classical_at_momentary_N": float(tables["pin"][-1] / LOAD_MARGIN),
                            "needle_classical_at_momentary_N": float(tables["needle"][-1] / LOAD_MARGIN),
                            "margin": LOAD_MARGIN},
        },
        extras={
            "mesh_size_at_contact_m": tm.mesh_size_m,
            "disc_mesh_nodes": int(len(tm.disc_mesh.points)),
            "hertz_peak_pressure_Pa": tm.hertz_peak_pressure_Pa.tolist(),
            "hertz_half_width_m": tm.hertz_half_width_m.tolist(),
            "profile_curvature_radius_m": tm.curvature_radius_m.tolist(),
            "rated_pin_force_N": rated,
            "tooth_secant_stiffness_at_rated_N_per_m": (rated / d_rated).tolist(),
            "crankshaft_single_load_fem_shaft_N_per_m": cs.bending_stiffness_N_per_m,
            "crankshaft_beam_theory": beam_ref,
            "crankshaft_edge_length_m": cs.edge_length_m,
            "support_bearing_tangent_N_per_m": sb["tangent_N_per_m"].tolist(),
            "carrier_mesh": car["mesh"],
            "involute_single_pair_stiffness_N_per_m": inv["single_pair_stiffness_N_per_m"],
            "turning_arm_lame_ring_deflection_at_max_m": ta["lame_ring_deflection_at_max_m"],
            "turning_arm_palmgren_deflection_m": ta["palmgren_deflection_m"].tolist(),
            "turning_arm_fe_qmax_N": ta["fe_qmax_N"].tolist(),
            "turning_arm_stribeck_qmax_N": ta["stribeck_qmax_N"].tolist(),
            "turning_arm_mesh_size_m": ta["mesh_size_m"],
            "timing_s": dict(tm.timing_s, **timing, total_s=time.perf_counter() - t0),
        })
    model.check(case.name)
    return FemRun(model, tm, fields)
