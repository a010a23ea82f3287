"""Reduce every FE/closed-form result of the FEM stage to the stiffness.json schema.

build_stiffness(case, mesh_size_m=...) runs: the 2D tooth-pin contact map (fem.pin_contact),
the 3D crankshaft (fem.shaft), the turning-arm bearing (2D FE, fem.bearing), the involute mesh
(fem.involute), and returns a StiffnessModel plus the fields the pictures need.
Crankshaft bending is the shaft alone, simply supported at the bearing centres; the support
bearings are the separate `support_bearing` spring (in series; extras give the combined figure).
"""
from __future__ import annotations

import time
from dataclasses import dataclass


from fem import bearing, involute, pin_contact, shaft
from fem.stiffness import PinContact, StiffnessModel, TurningArm


@dataclass(frozen=True)
class FemRun:
    model: StiffnessModel
    tooth_map: pin_contact.ToothPairMap
    crank_fields: dict


def _timed(func, *args, **kwargs):
    t0 = time.perf_counter()
    return func(*args, **kwargs), time.perf_counter() - t0


def _component(name: str, case, options: dict):
    """One independent FE sub-problem of the stage (a task: pure, picklable in and out)."""
    if name == "tooth_map":
        return _timed(pin_contact.tooth_pair_map, case, positions_deg=options["positions_deg"],
                      mesh_size_m=options["mesh_size_m"])
    if name == "crankshaft":
        return _timed(shaft.crankshaft_stiffness, case, options["crank_edge_m"], mesh3=options["crank_mesh"])
    if name == "turning_arm":
        return _timed(bearing.turning_arm_curve, case,
                      bearing.turning_arm_max_load(case, 2.5 * case.rated_torque_Nm))
    raise ValueError(name)


def build_stiffness(case, *, mesh_size_m: float | None = None, crank_edge_m: float | None = None,
                    positions_deg=None, crank_mesh=None, map_tasks=None) -> FemRun:
    """crank_mesh: the crankshaft tet mesh of the mesh stage (fem.shaft.crankshaft_mesh), else made here.
    The tooth map, the crankshaft and the needle bearing are independent FE problems, run through
    `map_tasks(func, tasks) -> results in order` (default: one after the other, in this process;
    pipeline.sweep.run_tasks puts them on local processes or a Dask cluster, same results)."""
    t0 = time.perf_counter()
    map_tasks = map_tasks or (lambda func, tasks: [func(*t) for t in tasks])
    options = {"positions_deg": positions_deg, "mesh_size_m": mesh_size_m, "crank_edge_m": crank_edge_m,
               "crank_mesh": crank_mesh}
    ((tm, t_map), ((cs, fields), t_crank), (ta, t_bearing)) = map_tasks(
        _component, [(n, case, options) for n in ("tooth_map", "crankshaft", "turning_arm")],
    )
    beam = shaft.crankshaft_beam_reference(case)
    inv = involute.mesh_stiffness(case)
    ksb = case.crankshaft.support_bearing_stiffness_N_per_um * 1e6
    series = 1.0 / (1.0 / cs.bending_stiffness_N_per_m + 1.0 / (2 * ksb))
    rated = pin_contact.contact_force_at_torque(case, case.rated_torque_Nm)
    # per-tooth secant stiffness at the rated-torque pin force, from each position's law
    d_rated = (rated / tm.law_k_N_per_m_pow) ** (1 / tm.law_n)
    model = StiffnessModel(
        case_name=case.name,
        pin_contact=PinContact(tm.position_deg, tm.load_N, tm.approach_m, tm.peak_pressure_Pa,
                               tm.half_width_m, tm.law_k_N_per_m_pow, tm.law_n),
        turning_arm=TurningArm(ta["load_N"], ta["deflection_m"], ta["law_k_N_per_m_pow"], ta["law_n"]),
        crankshaft_bending_stiffness_N_per_m=cs.bending_stiffness_N_per_m,
        crankshaft_torsional_stiffness_Nm_per_rad=cs.torsional_stiffness_Nm_per_rad,
        support_bearing_radial_stiffness_N_per_m=ksb,
        involute_mesh_mean_stiffness_N_per_m=inv["mean_stiffness_N_per_m"],
        involute_mesh_stiffness_variation=inv["stiffness_variation"],
        involute_mesh_contact_ratio=inv["contact_ratio"],
        sources={
            "pin_contact": "2D plane-strain FE (P1, scikit-fem), condensed frictionless contact, "
                           "modified profile, pin back half on a rigid seat; load levels up to the "
                           "most-loaded pin force at 2.5x rated torque (F_max = 4*0.55*T/(K1 zc rp))",
            "turning_arm": ta["source"],
            "crankshaft": "3D FE (P2 tetrahedra, pytetwild) of the project's stepped crankshaft, "
                          "pinned at the support-bearing centres; bending = shaft alone",
            "support_bearing": "case file (assumed catalog figure)",
            "involute_mesh": inv["source"],
        },
        extras={
            "mesh_size_at_contact_m": tm.mesh_size_m,
            "disc_mesh_nodes": int(len(tm.disc_mesh.points)),
            "hertz_peak_pressure_Pa": tm.hertz_peak_pressure_Pa.tolist(),
            "hertz_half_width_m": tm.hertz_half_width_m.tolist(),
            "profile_curvature_radius_m": tm.curvature_radius_m.tolist(),
            "rated_pin_force_N": rated,
            "tooth_secant_stiffness_at_rated_N_per_m": (rated / d_rated).tolist(),
            "crankshaft_with_support_bearings_N_per_m": series,
            "crankshaft_beam_theory": beam,
            "crankshaft_edge_length_m": cs.edge_length_m,
            "involute_single_pair_stiffness_N_per_m": inv["single_pair_stiffness_N_per_m"],
            "turning_arm_lame_ring_deflection_at_max_m": ta["lame_ring_deflection_at_max_m"],
            "turning_arm_palmgren_deflection_m": ta["palmgren_deflection_m"].tolist(),
            "turning_arm_fe_qmax_N": ta["fe_qmax_N"].tolist(),
            "turning_arm_stribeck_qmax_N": ta["stribeck_qmax_N"].tolist(),
            "turning_arm_mesh_size_m": ta["mesh_size_m"],
            "timing_s": dict(tm.timing_s, crankshaft_s=t_crank, turning_arm_s=t_bearing,
                             tooth_map_s=t_map, total_s=time.perf_counter() - t0),
        })
    model.check(case.name)
    return FemRun(model, tm, fields)
