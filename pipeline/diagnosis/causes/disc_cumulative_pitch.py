"""disc_cumulative_pitch: a cycloid disc's teeth turned by a once-around (1-lobe) pitch error.

Parameters (c, s) [um]: disc 1's cumulative pitch, c cos(theta) + s sin(theta) at the pin circle
radius (tangential, + forward) at polar angle theta of the disc's own frame, added as a row
[1, 1, a, phase] of Errors.disc_pitch_lobes (dynamics.couplings.pin: the teeth move, the contact
follows); the ISO 1328 cumulative pitch deviation is F_p = 2 a. Signature: through this model a
1-lobe pitch error of one disc does NOT show at 1x but at the crankshaft order zp x (0.90 ->
0.67 arcsec/um from 0 to 1800 N.m at 40x on the RV-160N FE stiffness; 80x at no load): the disc
turns with the carrier and its state repeats every pin pitch (dynamics.signatures), and it turns
against the other disc. Helper H8 measured it and this cause takes the model's signature as the
truth, though DESIGN.md expects 1x: a real bench's 1x line is left to output_coaxiality.
The atlas (dynamics.signatures.groups) puts it in one group with eccentric_error (one eccentric
journal off its radius), crank_hole_radial and main_bearing_runout: a zp x line alone cannot
separate them (crank_eccentricity_error is the registered cause of that group). Disc 2's error
gives the same line turned: the records cannot say which disc, reported as disc 1's.
Bounds: +-20 um per component (grade 5 F_p / 2 for the RV-160N is 13.7 um; a disc worse than
grade 6 is rejected at inspection). Unit size 2 um. Virtual bench: a in [5, 12] um, any phase.
"""
from __future__ import annotations

import numpy as np

from pipeline.diagnosis.causes.base import Cause, Evidence, Fitted, polar_draw, polar_params, polar_report

BOUND_UM = 20.0


class DiscCumulativePitch(Cause):
    id = "disc_cumulative_pitch"
    description = "a cycloid disc's cumulative pitch error (teeth turned once around the disc)"
    signature = "zp x (the model's: not 1x), nearly independent of torque; 2 zp x at no load"
    unit_size = 2.0
    dc_even = True   # the mean shift (lost motion) is the same for the pattern turned: even in its size

    def params(self, case):
        return polar_params("disc_pitch", BOUND_UM)

    def apply(self, case, stiffness, p):
        a, ph = float(np.hypot(p[0], p[1])), float(np.degrees(np.arctan2(p[1], p[0])))
        rows = [list(r) for r in case.errors.disc_pitch_lobes] + [[1, 1, a, ph]]
        return case.with_errors(disc_pitch_lobes=rows), stiffness

    def orders(self, case):
        return (case.cycloid.zp,)

    def report(self, fit: Fitted) -> dict:
        out = polar_report(fit, "disc_cumulative_pitch")
        return {**out, "disc_cumulative_pitch_Fp_um": 2.0 * out["disc_cumulative_pitch_um"]}

    def evidence(self, ev: Evidence) -> str:
        zp = ev.case.cycloid.zp
        return (f"{ev.prefix}residual line at zp = {zp}x ({ev.line_by_torque(zp)}) as the model's signature "
                f"of a disc's cumulative pitch error (orders {list(ev.summary.orders)[:4]}: through this model "
                f"a once-around pitch error shows at zp x, not 1x). The signature atlas groups it with an "
                f"eccentric journal off its radius (crank_eccentricity_error), a crank-hole and a "
                f"main-bearing error: the zp x line alone cannot separate them, nor say which disc; a "
                f"pitch measurement of the discs can{ev.alternatives}.")

    def draw(self, rng, case):
        return polar_draw(rng, (5.0, 12.0), "disc_cumulative_pitch")


CAUSE = DiscCumulativePitch()
