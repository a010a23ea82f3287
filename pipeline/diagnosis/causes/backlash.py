"""backlash: more clearance between disc teeth and pins, lost motion at reversal.

Parameter: extra pin clearance [um] on the equidistant modification dRr (> 0 opens backlash).
Signature: a backward-minus-forward mean TE gap, the same at every torque. Reported: the clearance
and the lost motion in arcmin through the model's own ratio (`arcmin_per_um`, the lost-motion change
of the model at +-1 % rated torque per um). Unit size 2 um. Bounds: from minus the case's minimum
conjugate-pose gap (geometry.clearance.closed_form_min_clearance_mm: below it the pins interfere,
a negative clearance) to +100 um (~13 arcmin of lost motion on the RV-40E at the model's 0.13
arcmin per um: a worn-out reducer, not a build).
Virtual bench: extra clearance in [4, 12] um.
"""
from __future__ import annotations

import numpy as np

from geometry.clearance import closed_form_min_clearance_mm
from pipeline.diagnosis.causes.base import Cause, Evidence, Fitted, Param, ci

UPPER_UM = 100.0


def arcmin_per_um(te_model, case, stiffness, n: int = 24) -> float:
    """Lost motion change per um of extra pin clearance, from the model at +-1 % rated torque."""
    ang = np.linspace(0.0, 360.0 * case.ratio / case.cycloid.zp, n, endpoint=False)
    c2, _ = CAUSE.apply(case, stiffness, np.array([2.0]))
    t = 0.01 * case.rated_torque_Nm
    lm = lambda c: float(np.mean(te_model(c, stiffness, ang, -t, -1)) - np.mean(te_model(c, stiffness, ang, t, 1)))  # noqa: E731
    return (lm(c2) - lm(case)) / 2.0 / 60.0


class Backlash(Cause):
    id = "backlash"
    description = "more clearance between disc teeth and pins: lost motion at reversal"
    signature = "backward-minus-forward mean gap, the same at every torque"
    unit_size = 2.0

    def params(self, case):
        return (Param("pin_clearance_um", "um", (-1e3 * closed_form_min_clearance_mm(case), UPPER_UM)),)

    def apply(self, case, stiffness, p):
        m = case.modification
        return case.replace("modification", equidistant_mm=m.equidistant_mm + float(p[0]) * 1e-3), stiffness

    def orders(self, case):
        return (0,)

    def report(self, fit: Fitted) -> dict:
        um = float(fit.p[0])
        per = arcmin_per_um(fit.te_model, fit.case, fit.stiffness)
        return {"pin_clearance_um": um, "backlash_arcmin": um * per,
                "backlash_arcmin_ci95": sorted(ci(um * per, float(fit.sd[0]) * abs(per), fit.tq))}

    def evidence(self, ev: Evidence) -> str:
        return (f"{ev.prefix}a backward-minus-forward mean TE gap the model does not have "
                f"({ev.pair_gaps_text()}; the model's is the same at every torque): lost motion at the reversal of motion, as the "
                f"model's pin-clearance signature.")

    def draw(self, rng, case):
        um = rng.uniform(4.0, 12.0)
        return (um,), {"pin_clearance_um": um}


CAUSE = Backlash()
