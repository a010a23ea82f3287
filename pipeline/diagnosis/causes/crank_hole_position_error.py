"""crank_hole_position_error: crank holes of both discs off their nominal radial position.

Parameters (A cos 2 phi, A sin 2 phi) [um]: the zero-mean pattern de_j = A cos(phi - 2 pi j / n)
of radial crank-hole position errors on both discs (added to Errors.crank_hole_position_um). Both
discs, so the zp x line cancels and the rectified 2 zp x part remains (even in A, hence 2 phi):
a 2 zp x line falling with torque and a shift toward less lost motion (`dc_even`).
Unit size 10 um, a tolerance-class size: at 1 um that misfit stays inside the elastic approach of
the loaded pins and the model answers ~0.01 arcsec (second order), so a 1 um secant would not
represent the 5-20 um errors that matter. Reported: A, phi (mod 180 deg: A and -A look alike) and
the per-crank pattern. Bounds +-50 um per component. No virtual-bench draw.
"""
from __future__ import annotations

import numpy as np

from pipeline.diagnosis.causes.base import Cause, Evidence, Fitted, Param, per_crank, polar

UNIT_UM = 10.0
BOUND_UM = 50.0


def crank_pattern_um(n_crank: int, p) -> np.ndarray:
    """Per-crank values A cos(phi - 2 pi j / n) from p = (A cos 2 phi, A sin 2 phi) [um]."""
    a, two_phi = float(np.hypot(p[0], p[1])), float(np.arctan2(p[1], p[0]))
    return a * np.cos(0.5 * two_phi - 2 * np.pi * np.arange(n_crank) / n_crank)


class CrankHolePositionError(Cause):
    id = "crank_hole_position_error"
    description = "crank holes of the discs off their nominal radial position"
    signature = "2 zp x falling with torque, a mean shift toward less lost motion (even in the error)"
    unit_size = UNIT_UM
    dc_even = True

    def params(self, case):
        return (Param("hole_A_cos2phi_um", "um", (-BOUND_UM, BOUND_UM)),
                Param("hole_A_sin2phi_um", "um", (-BOUND_UM, BOUND_UM)))

    def apply(self, case, stiffness, p):
        d = crank_pattern_um(case.carrier.crank_count, p)
        return case.with_errors(crank_hole_position_um=per_crank(case, "crank_hole_position_um", d)), stiffness

    def orders(self, case):
        return (2 * case.cycloid.zp, 0)

    def report(self, fit: Fitted) -> dict:
        c = self.id
        a, a_ci, two_ph, two_ph_ci = polar(fit.p, fit.cov, fit.tq)
        return {f"{c}_amplitude_um": a, f"{c}_amplitude_um_ci95": a_ci,
                f"{c}_phase_deg": two_ph / 2.0, f"{c}_phase_deg_ci95": [v / 2.0 for v in two_ph_ci],
                f"{c}_um": [float(v) for v in crank_pattern_um(fit.case.carrier.crank_count, fit.p)]}

    def evidence(self, ev: Evidence) -> str:
        k = self.orders(ev.case)[0]
        return (f"{ev.prefix}residual line at twice the crankshaft order, 2 zp = {k}x "
                f"({ev.line_by_torque(k)}; the model's line falls with torque) with a shift toward less "
                f"lost motion: the model's signature of a crank-hole position pattern on both discs (the "
                f"two discs, 180 deg apart, cancel the zp x line; the rectified part remains; orders "
                f"{list(ev.summary.orders)[:4]}); an eccentric or disc-tooth error of one disc would "
                f"show at zp x instead{ev.alternatives}.")


CAUSE = CrankHolePositionError()
