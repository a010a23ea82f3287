"""Carrier: output flange, end plate and pillars as one 3D P2 FE body, seats as rigid rings, flange
face clamped, Richardson over two meshes (fem.carrier); the 4nc x 4nc seat flexibility (racking
couples the cranks). The two meshes are two tasks of the FE stage (`parts`, `compute_part`,
`combine`: fem.reduce runs them in parallel with the other components)."""
from __future__ import annotations

import dataclasses as dc

import numpy as np

from fem.components.base import Result
from fem.components.entries import CarrierSeats

NAME = "carrier"
COUPLING = "support"
COST = 40
LEVEL_COST = (8, 30)    # rough seconds of the coarse and the fine level (2 cores, measured); the pool takes the longest first


def parts(case, ctx) -> list:
    """(cost, part) of the FE stage's tasks: part = the level, 0 coarse, 1 fine."""
    return [(LEVEL_COST[k], k) for k in (1, 0)]


def solve_level(case, ctx, level: int, joints=None):
    """fem.carrier.carrier_compliance of the case's carrier (fem.carrier.case_geometry) on one of the
    default estimate's meshes (ctx['carrier_levels'], default fem.carrier.DEFAULT_LEVELS); `joints`:
    pillar-joint layers (fem.joint_layers.JointLayers, None: bonded)."""
    from fem import carrier
    g = carrier.case_geometry(case)
    h = carrier.level_sizes_m(g, ctx.get("carrier_levels") or carrier.DEFAULT_LEVELS)[level]
    kw = {} if joints is None else {"joints": joints}
    return carrier.carrier_compliance(g, case.material.youngs_modulus_GPa * 1e9, case.material.poisson_ratio,
                                      edge_length_m=h, **kw)


def fe_entry(case, levels: dict) -> dict:
    """The default estimate (fem.carrier.richardson of the levels {0: coarse, 1: fine} CarrierFE),
    its order checked against the lumped model's seats."""
    from fem import carrier
    g = carrier.case_geometry(case)
    fe = carrier.richardson(levels[0], levels[1])
    nc = g.crank_count
    want = [f"crank{j + 1}_{s}_{ax}" for j in range(nc) for s in carrier.SEATS for ax in "xy"]
    if list(fe.labels) != want or not np.allclose(fe.crank_angles_rad, 2 * np.pi * np.arange(nc) / nc):
        raise RuntimeError(f"carrier seat order {fe.labels} / angles {fe.crank_angles_rad}: expected crank j "
                           f"at 2 pi j / nc, seats (flange, end plate), (x, y) (fem.stiffness.CarrierSeats)")
    E, nu = case.material.youngs_modulus_GPa * 1e9, case.material.poisson_ratio
    ARCMIN_PER_RAD = carrier.ARCMIN_PER_RAD
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
            "mesh": {"nodes": fe.nodes, "tets": fe.tets, "dofs": fe.dofs, "edge_length_m": fe.edge_length_m}}


def compute_part(case, ctx, part: int):
    """One level of the bonded carrier (a task: pure, picklable)."""
    return solve_level(case, ctx, part)


def combine(case, ctx, done: list) -> Result:
    """The component's Result from its parts' outputs [(part, CarrierFE)]."""
    levels = dict(done)
    car = fe_entry(case, levels)
    return Result(NAME, {"carrier": CarrierSeats(car["compliance_m_per_N"])},
                  {NAME: "3D FE (P2 tetrahedra, extruded mesh) of flange + end plate + pillars as one bonded "
                         "body, mounting face clamped, each seat a rigid ring over the bearing width, condensed "
                         "to the seat translations; two meshes Richardson-extrapolated (fem.carrier)"},
                  {NAME: car["check"]}, extras={"carrier_mesh": car["mesh"]},
                  artifacts={"carrier_timing_s": {f"level{k}": {"mesh_s": fe.mesh_seconds, "solve_s": fe.solve_seconds}
                                                  for k, fe in levels.items()}},
                  seconds=sum(fe.mesh_seconds + fe.solve_seconds for fe in levels.values()))


def compute(case, ctx) -> Result:
    """Every part in this process (fem.reduce runs the parts as tasks instead)."""
    return combine(case, ctx, [(p, compute_part(case, ctx, p)) for _, p in parts(case, ctx)])


def stiffen(model, f: float):
    return dc.replace(model, carrier=CarrierSeats(model.carrier.compliance_m_per_N / f))


def support_part(model, T: np.ndarray, n_crank: int) -> np.ndarray:
    """T^T C_car T: the seats' flexibility (racking couples the cranks)."""
    return T.T @ model.carrier.compliance_m_per_N @ T
