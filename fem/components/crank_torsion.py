"""Crankshaft torsion between the planet seat and eccentric 1: 3D P2 FE of the stepped crankshaft
(fem.shaft), checked against GJ beam theory; in series with the involute mesh per crank."""
from __future__ import annotations

import dataclasses as dc

from fem.components.base import Result, timed

NAME = "crank_torsion"
COUPLING = "mesh"
COST = 15


@timed
def compute(case, ctx) -> Result:
    from fem import shaft
    cs, fields = shaft.crankshaft_stiffness(case, ctx["crank_edge_m"], mesh3=ctx["crank_mesh"])
    beam = shaft.crankshaft_beam_reference(case)
    return Result(NAME, {"crankshaft_torsional_stiffness_Nm_per_rad": cs.torsional_stiffness_Nm_per_rad},
                  {"crankshaft": "torsion: 3D FE (P2 tetrahedra, prisms of one section mesh: fem.shaft.extruded_crankshaft_mesh) of the project's stepped crankshaft, "
                                 "planet-seat face to eccentric 1 (fem.shaft); bending = 1 / C11 of crank_bending"},
                  {"crankshaft": {"torsion_fe_over_beam": cs.torsional_stiffness_Nm_per_rad
                                  / beam["torsional_stiffness_Nm_per_rad"],
                                  "single_load_bending_fe_over_beam": cs.bending_stiffness_N_per_m
                                  / beam["bending_stiffness_N_per_m"]}},
                  extras={"crankshaft_single_load_fem_shaft_N_per_m": cs.bending_stiffness_N_per_m,
                          "crankshaft_beam_theory": beam, "crankshaft_edge_length_m": cs.edge_length_m},
                  artifacts={"crank_fields": fields})


def stiffen(model, f: float):
    return dc.replace(model, crankshaft_torsional_stiffness_Nm_per_rad=model.crankshaft_torsional_stiffness_Nm_per_rad * f)


def line_compliance_m_per_N(p, h) -> float:
    """The crank's torsion seen along the mesh line of action: rb2^2 / k_t."""
    return p.rb_planet_m * p.rb_planet_m / p.k_torsion_Nm_per_rad
