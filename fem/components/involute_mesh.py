"""First-stage involute mesh: ISO 6336-1 single-pair and mesh stiffness with profile shift
(fem.involute), time-varying with the contact ratio."""
from __future__ import annotations

import dataclasses as dc

from fem.components.base import Result, timed

NAME = "involute_mesh"
COUPLING = "mesh"
COST = 0


@timed
def compute(case, ctx) -> Result:
    from fem import involute
    inv = involute.mesh_stiffness(case)
    return Result(NAME, {"involute_mesh_mean_stiffness_N_per_m": inv["mean_stiffness_N_per_m"],
                         "involute_mesh_stiffness_variation": inv["stiffness_variation"],
                         "involute_mesh_contact_ratio": inv["contact_ratio"]},
                  {NAME: inv["source"]},
                  {NAME: {"single_pair_N_per_m": inv["single_pair_stiffness_N_per_m"],
                          "note": "ISO 6336-1 closed form itself (no FE)"}},
                  extras={"involute_single_pair_stiffness_N_per_m": inv["single_pair_stiffness_N_per_m"]})


def stiffen(model, f: float):
    return dc.replace(model, involute_mesh_mean_stiffness_N_per_m=model.involute_mesh_mean_stiffness_N_per_m * f)


def line_compliance_m_per_N(p, h) -> float:
    """1 / k_m(s): the mesh stiffness at the crank's mesh phase (h pairs beyond one)."""
    return 1.0 / (p.k_mean_N_per_m * (1.0 + p.variation * (h - (p.contact_ratio - 1.0))))
