"""output_coaxiality: the output mounted off-axis, read by the output encoder.

Parameters (e cos phi, e sin phi) [um], added to the case's Errors.output_coaxiality_um at
output_coaxiality_phase_deg: the offset e at phase phi reads e/r sin(theta_out + phi) at the output
flange radius r (dynamics.model). Signature: a 1x line, independent of load and direction; no other
cause puts a 1x line there. Reported: e [um] and phi [deg] with delta-method 95 % intervals.
Bounds: +-100 um per component (an output 0.1 mm off axis is an assembly fault, not a tolerance).
Virtual bench: e in [5, 25] um, phi in [-180, 180) deg.
"""
from __future__ import annotations

from pipeline.diagnosis.causes.base import (Cause, Evidence, Fitted, polar_draw, polar_params, polar_report,
                                             with_phasor_added)

BOUND_UM = 100.0


class OutputCoaxiality(Cause):
    id = "output_coaxiality"
    description = "output mounted off-axis: the output encoder reads e/r sin(theta + phi)"
    signature = "1x, independent of load and direction"
    unit_size = 1.0
    additive = True   # a reading of the output encoder: adds to the mechanism's TE whatever it is

    def params(self, case):
        return polar_params("coaxiality", BOUND_UM)

    def apply(self, case, stiffness, p):
        return with_phasor_added(case, "output_coaxiality", p), stiffness

    def orders(self, case):
        return (1,)

    def report(self, fit: Fitted) -> dict:
        return polar_report(fit, "output_coaxiality")

    def evidence(self, ev: Evidence) -> str:
        return (f"{ev.prefix}a once-per-output-revolution residual line ({ev.line_by_torque(1.0)}) "
                f"as the model's coaxiality signature (orders {list(ev.summary.orders)[:3]}, "
                f"load-independent); among the registered causes no other puts a 1x line there"
                f"{ev.alternatives}.")

    def draw(self, rng, case):
        return polar_draw(rng, (5.0, 25.0), "output_coaxiality")


CAUSE = OutputCoaxiality()
