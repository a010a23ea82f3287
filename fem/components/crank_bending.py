"""Crankshaft bending, tilt and S-bend with the two eccentrics loaded independently: 3D P2 FE of the
crankshaft pinned at its support bearings' pressure centres (fem.crank_tilt); a 2x2 flexibility
per crank between the disc planes."""
from __future__ import annotations

import dataclasses as dc

import numpy as np

from fem.components.base import Result, timed

NAME = "crank_bending"
COUPLING = "support"
COST = 25


@timed
def compute(case, ctx) -> Result:
    from fem import crank_tilt
    from fem.components.entries import CrankBending
    cb = crank_tilt.case_crank_bending(case, mesh3=ctx["crank_mesh"], edge_length_m=ctx["crank_edge_m"])
    return Result(NAME, {"crank_bending": CrankBending(cb["compliance_m_per_N"], cb["journal_force"]),
                         "crankshaft_bending_stiffness_N_per_m": float(1.0 / cb["compliance_m_per_N"][0, 0])},
                  {NAME: cb["source"]}, {NAME: cb["check"]}, artifacts={"flex": cb["flex"]})


def stiffen(model, f: float):
    return dc.replace(model, crankshaft_bending_stiffness_N_per_m=model.crankshaft_bending_stiffness_N_per_m * f,
                      crank_bending=dc.replace(model.crank_bending,
                                               compliance_m_per_N=model.crank_bending.compliance_m_per_N / f))


def support_part(model, T: np.ndarray, n_crank: int) -> np.ndarray:
    """The shaft alone between its eccentrics, isotropic (x and y alike), block-diagonal per crank."""
    Cb = model.crank_bending.compliance_m_per_N
    nd = Cb.shape[0]
    n = 2 * n_crank * nd
    bend = np.zeros((n, n))
    for j in range(n_crank):
        s = slice(2 * nd * j, 2 * nd * (j + 1))
        bend[s, s] = np.kron(0.5 * (Cb + Cb.T), np.eye(2))
    return bend
