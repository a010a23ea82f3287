"""torsional_stiffness: the reducer stiffer or softer than the FE model says.

Parameter kappa = 1/c - 1 [1], c the factor on every FE stiffness: deflections at equal load scale
by 1/c, so the TE is near linear in kappa; power-law contacts F = k d^n get k c^n. Signature: a mean
lag proportional to torque, opposite in the two directions (a backward-minus-forward gap growing
with torque). Reported: c with its 95 % interval (mapped through c = 1 / (1 + kappa)).
Unit size kappa = 0.05 (5 %). Bounds c in [0.05, 20] (kappa in [-0.95, 19]): kappa <= -1 is a
negative stiffness; a model off by more than 20 x is a wrong model, not a compliance.
Virtual bench: c in [0.55, 0.8] or [1.3, 1.8].
"""
from __future__ import annotations

import dataclasses

from pipeline.diagnosis.causes.base import Cause, Evidence, Fitted, Param

FACTOR_RANGE = (0.05, 20.0)


def scale_stiffness(stiffness, factor: float):
    """Every FE stiffness times `factor` (deflection at equal load / factor)."""
    if factor <= 0:
        raise ValueError(f"stiffness factor {factor}: must be > 0")
    pc, ta = stiffness.pin_contact, stiffness.turning_arm
    pc2 = dataclasses.replace(pc, approach_m=pc.approach_m / factor,
                              law_k_N_per_m_pow=pc.law_k_N_per_m_pow * factor ** pc.law_n)
    ta2 = dataclasses.replace(ta, deflection_m=ta.deflection_m / factor,
                              law_k_N_per_m_pow=ta.law_k_N_per_m_pow * factor ** ta.law_n)
    return dataclasses.replace(
        stiffness, pin_contact=pc2, turning_arm=ta2,
        crankshaft_bending_stiffness_N_per_m=stiffness.crankshaft_bending_stiffness_N_per_m * factor,
        crankshaft_torsional_stiffness_Nm_per_rad=stiffness.crankshaft_torsional_stiffness_Nm_per_rad * factor,
        support_bearing_radial_stiffness_N_per_m=stiffness.support_bearing_radial_stiffness_N_per_m * factor,
        involute_mesh_mean_stiffness_N_per_m=stiffness.involute_mesh_mean_stiffness_N_per_m * factor)


class TorsionalStiffness(Cause):
    id = "torsional_stiffness"
    description = "the reducer is stiffer or softer than the FE model says"
    signature = "mean lag proportional to torque, opposite in the two directions"
    unit_size = 0.05

    def params(self, case):
        lo, hi = FACTOR_RANGE
        return (Param("compliance_factor_minus_1", "1", (1.0 / hi - 1.0, 1.0 / lo - 1.0)),)

    def apply(self, case, stiffness, p):
        return case, scale_stiffness(stiffness, 1.0 / (1.0 + float(p[0])))

    def orders(self, case):
        return (0,)

    def report(self, fit: Fitted) -> dict:
        kappa, skappa, tq = float(fit.p[0]), float(fit.sd[0]), fit.tq
        lo, hi = 1.0 / (1.0 + kappa + tq * skappa), 1.0 / max(1.0 + kappa - tq * skappa, 1e-9)
        return {"stiffness_factor": 1.0 / (1.0 + kappa), "stiffness_factor_ci95": [float(lo), float(hi)]}

    def evidence(self, ev: Evidence) -> str:
        return (f"{ev.prefix}the backward-minus-forward mean TE gap left by the model grows with torque "
                f"({ev.pair_gaps_text()}): the wind-up differs from the FE stiffness, as the model's "
                f"stiffness signature (mean lag proportional to torque, opposite in the two directions).")

    def draw(self, rng, case):
        c = rng.uniform(0.55, 0.8) if rng.random() < 0.5 else rng.uniform(1.3, 1.8)
        return (1.0 / c - 1.0,), {"stiffness_factor": c}


CAUSE = TorsionalStiffness()
