"""Crank support bearings: a standard tapered roller bearing that fits the envelope, roller by
roller with ISO/TS 16281 slices, X-arranged, preloaded (fem.tapered_roller); an isotropic radial
spring per bearing at its seat, tangent at the rated-torque load."""
from __future__ import annotations

import dataclasses as dc
import math

import numpy as np

from fem.components.base import Result, timed

NAME = "support_bearings"
COUPLING = "support"
COST = 5


@timed
def compute(case, ctx) -> Result:
    from fem import tapered_roller
    from fem.components.entries import SupportBearings
    top = ctx["load_margin"] * tapered_roller.operating_radial_load_N(case, case.operation.momentary_torque_Nm)
    sb = tapered_roller.case_support_bearings(case, top)
    bg = sb["bearing"]
    entry = SupportBearings(bg.designation, bg.roller_count, bg.roller_length_mm * 1e-3, bg.roller_diameter_mm * 1e-3,
                            math.degrees(bg.alpha_rad), sb["setup"].preload_N, sb["load_N"], sb["deflection_m"],
                            sb["operating_load_N"], sb["stiffness_N_per_m"])
    return Result(NAME, {"support_bearings": entry}, {NAME: sb["source"]}, {NAME: sb["check"]},
                  extras={"support_bearing_tangent_N_per_m": sb["tangent_N_per_m"].tolist()})


def stiffen(model, f: float):
    sb = model.support_bearings
    return dc.replace(model, support_bearings=dc.replace(sb, deflection_m=sb.deflection_m / f,
                                                         stiffness_N_per_m=sb.stiffness_N_per_m * f))


def support_part(model, T: np.ndarray, n_crank: int) -> np.ndarray:
    """T^T (1/k_b) T: each bearing an isotropic radial spring at its seat."""
    return T.T @ T / model.support_bearings.stiffness_N_per_m
