"""Carrier: output flange, end plate and pillars as one 3D P2 FE body, seats as rigid rings, flange
face clamped, Richardson over two meshes (fem.carrier); the 4nc x 4nc seat flexibility (racking
couples the cranks)."""
from __future__ import annotations

import dataclasses as dc

import numpy as np

from fem.components.base import Result, timed
from fem.components.entries import CarrierSeats

NAME = "carrier"
COUPLING = "support"
COST = 40


def fe_entry(case, levels=None, joints=None) -> dict:
    """fem.carrier's default estimate (levels: its two mesh sizes, default carrier.DEFAULT_LEVELS),
    its order checked against the lumped model's seats; `joints`: pillar-joint layers (fem.carrier)."""
    from fem import carrier
    kw = {} if levels is None else {"levels": levels}
    if joints is not None:
        kw["joints"] = joints
    g, fe = carrier.carrier_for_case(case, **kw)
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
            "mesh": {"nodes": fe.nodes, "tets": fe.tets, "dofs": fe.dofs, "edge_length_m": fe.edge_length_m,
                     "mesh_s": fe.mesh_seconds, "solve_s": fe.solve_seconds}}


@timed
def compute(case, ctx) -> Result:
    car = fe_entry(case, ctx.get("carrier_levels"))
    return Result(NAME, {"carrier": CarrierSeats(car["compliance_m_per_N"])},
                  {NAME: "3D FE (P2 tetrahedra, extruded mesh) of flange + end plate + pillars as one bonded "
                         "body, mounting face clamped, each seat a rigid ring over the bearing width, condensed "
                         "to the seat translations; two meshes Richardson-extrapolated (fem.carrier)"},
                  {NAME: car["check"]}, extras={"carrier_mesh": car["mesh"]})


def stiffen(model, f: float):
    return dc.replace(model, carrier=CarrierSeats(model.carrier.compliance_m_per_N / f))


def support_part(model, T: np.ndarray, n_crank: int) -> np.ndarray:
    """T^T C_car T: the seats' flexibility (racking couples the cranks)."""
    return T.T @ model.carrier.compliance_m_per_N @ T
