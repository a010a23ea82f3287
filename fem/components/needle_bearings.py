"""Turning-arm (needle) bearings between eccentric and disc crank hole: 2D FE of the needles
between the eccentric and the crank-hole ring, clamped at the thinnest ligament (fem.bearing);
edge loading from the crank slope by slices (fem.needle_edge, a refinement: it raises the edge
load and does not soften the bearing, so the law is used unchanged). The whole needle coupling."""
from __future__ import annotations

import dataclasses as dc
import math

import numpy as np

from fem.components.base import Result, timed

NAME = "needle_bearings"
COUPLING = "needle"
COST = 10


def force_classical_N(case, torque_Nm: float) -> float:
    """One needle bearing's load, classical sharing: the more loaded disc's tangential share per
    crank (bearing.turning_arm_max_load) and its pin resultant per crank, R / n_c with
    R = T_d / (z_c e) (fem.tapered_roller.crank_support_load_N), at right angles."""
    from fem import bearing
    from fem.tapered_roller import crank_support_load_N
    R = crank_support_load_N(case, torque_Nm)["disc_resultant_N"] / case.carrier.crank_count
    return math.hypot(bearing.turning_arm_max_load(case, torque_Nm), R)


@timed
def compute(case, ctx) -> Result:
    from fem import bearing
    from fem.components.entries import TurningArm
    ta = bearing.turning_arm_curve(case, float(ctx["loads"]["needle"][-1]))
    dp, sq = ta["deflection_m"] / ta["palmgren_deflection_m"], ta["fe_qmax_N"] / ta["stribeck_qmax_N"]
    return Result(NAME, {"turning_arm": TurningArm(ta["load_N"], ta["deflection_m"], ta["law_k_N_per_m_pow"],
                                                   ta["law_n"])},
                  {"turning_arm": ta["source"] + "; loads: load_ranges"},
                  {"turning_arm": {"fe_over_palmgren_deflection": [float(dp.min()), float(dp.max())],
                                   "fe_over_stribeck_qmax": [float(sq.min()), float(sq.max())]}},
                  extras={"turning_arm_lame_ring_deflection_at_max_m": ta["lame_ring_deflection_at_max_m"],
                          "turning_arm_palmgren_deflection_m": ta["palmgren_deflection_m"].tolist(),
                          "turning_arm_fe_qmax_N": ta["fe_qmax_N"].tolist(),
                          "turning_arm_stribeck_qmax_N": ta["stribeck_qmax_N"].tolist(),
                          "turning_arm_mesh_size_m": ta["mesh_size_m"]})


def refine(case, results) -> Result:
    """Needle edge loading with the eccentric's slope per N from the crank FE on its support bearings."""
    from fem import crank_tilt, needle_edge
    cb = results["crank_bending"]
    sb = results["support_bearings"].fields["support_bearings"]
    flex_sup = crank_tilt.with_elastic_supports(cb.artifacts["flex"], 1.0 / sb.stiffness_N_per_m)
    slope = crank_tilt.eccentric_slope_per_N(case, flex_sup)
    ks = case.crankshaft
    torques = [case.rated_torque_Nm, case.operation.momentary_torque_Nm]
    nl = np.array([force_classical_N(case, T) for T in torques])
    edge = needle_edge.slope_coupled_curve(nl, slope, needle_count=ks.needle_count, length_m=ks.needle_length_mm * 1e-3)
    return Result("needle_edge", {},
                  {"needle_edge": "fem.needle_edge slice model with the crank slope per N from crank_bending on the "
                                  "support bearings: the slope raises the edge load but does not soften the bearing "
                                  "(stiffness_ratio >= 1), so the needle law (turning_arm) is used unchanged"},
                  {"needle_edge": {"slope_rad_per_N": slope, "load_N": nl.tolist(), "tilt_rad": edge.tilt_rad.tolist(),
                                   "stiffness_ratio": edge.stiffness_ratio.tolist(),
                                   "edge_load_ratio": edge.edge_load_ratio.tolist(), "torques_Nm": torques}})


def stiffen(model, f: float):
    ta = model.turning_arm
    return dc.replace(model, turning_arm=dc.replace(ta, deflection_m=ta.deflection_m / f,
                                                    law_k_N_per_m_pow=ta.law_k_N_per_m_pow * f ** ta.law_n))
