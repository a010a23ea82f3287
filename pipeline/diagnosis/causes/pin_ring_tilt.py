"""pin_ring_tilt: the pin ring's axis tilted against the carrier's (housing bore and main-bearing seats
not coaxial, a housing clamped askew on its flange).

Parameters (t cos phi, t sin phi) [um]: the pin circle's centre moved by t toward the ground-frame
angle phi (from pin 1) at disc 1's plane and by -t at disc 2's (Errors.pin_ring_tilt_um and
_phase_deg; dynamics.couplings.pin moves the pin centres of each disc's plane, the real gaps follow):
a tilt of 2 t / disc width about the axis at phi + 90 deg.
Signature (rigid kinematics, checked against the model in tests/test_signatures.py): a disc whose
ring is shifted by t sits as if its eccentric were turned by t_perp / E, so it turns by
t_perp / (E zc), t_perp = t sin(psi - phi) the shift across its eccentric psi; psi sweeps the ground
frame zc times per output revolution, so the line is at zc x with amplitude t / (E zc) per disc.
Disc 2's eccentric is turned 180 deg and its shift is -t: its t_perp is disc 1's, the two lines ADD.
A ring shifted alike at both planes (pin_ring_pattern's m = 1, 0.2-0.3 arcsec/um) makes the discs
pull opposite ways and cancels. Model, RV-160N FE stiffness: 2.55-2.57 arcsec/um at 39x from 0 to
1800 N.m, the same size in both directions, its phase 17 deg apart between them (the radial part of the
shift acts on the loaded flank; on the RV-40E stand-in 'same'); closed form 2.64, the rest is that
radial part and the crank supports' compliance; mean shift < 0.04 arcsec: a 39x line independent of
torque. The atlas groups it with pin_radial_lobes_m1 (the same shape, a tenth of the size).
Bounds: +-10 um per component, ASSUMED: the pin ring and the main-bearing seats bored in one
setting hold their coaxiality within IT5 (20 um at 180-250 mm) over the housing, half of it at each
disc plane; more is a housing clamped askew or a damaged seat. Unit size 1 um.
Virtual bench: t in [0.8, 3] um (2-8 arcsec on the RV-40E stand-in), any phase.
"""
from __future__ import annotations

from dynamics.results import ARCSEC_PER_RAD
from pipeline.diagnosis.causes.base import (Cause, Evidence, Fitted, polar_draw, polar_params, polar_report,
                                             with_phasor_added)

BOUND_UM = 10.0


class PinRingTilt(Cause):
    id = "pin_ring_tilt"
    description = "pin ring axis tilted against the carrier's: its centre off oppositely at the two disc planes"
    signature = "zc x line (the discs' lines add), independent of torque, one size in both directions"
    unit_size = 1.0

    def params(self, case):
        return polar_params("pin_ring_tilt", BOUND_UM)

    def apply(self, case, stiffness, p):
        return with_phasor_added(case, "pin_ring_tilt", p), stiffness

    def orders(self, case):
        return (case.cycloid.zc,)

    def report(self, fit: Fitted) -> dict:
        out = polar_report(fit, "pin_ring_tilt")
        # the planes' mid-planes lie one disc width apart: tilt = 2 t / width [rad]
        per_um = 2e-3 / fit.case.cycloid.width_mm * ARCSEC_PER_RAD
        return {**out, "pin_ring_tilt_arcsec": out["pin_ring_tilt_um"] * per_um,
                "pin_ring_tilt_arcsec_ci95": [v * per_um for v in out["pin_ring_tilt_um_ci95"]]}

    def evidence(self, ev: Evidence) -> str:
        zc = ev.case.cycloid.zc
        return (f"{ev.prefix}a residual line at {zc}x ({ev.line_by_torque(float(zc))}) as the model's signature of "
                f"a pin ring tilted against the carrier's axis (orders {list(ev.summary.orders)[:3]}): its centre "
                f"off oppositely at the two disc planes, each disc turns by the shift across its eccentric over "
                f"E zc, and the two discs' {zc}x lines add; a ring off-centre alike at both planes "
                f"(pin_ring_pattern m = 1) nearly cancels between them (a tenth of the size). A {zc}x line "
                f"that grows with torque is not this cause's (its line is independent of torque){ev.alternatives}.")

    def draw(self, rng, case):
        return polar_draw(rng, (0.8, 3.0), "pin_ring_tilt")


CAUSE = PinRingTilt()
