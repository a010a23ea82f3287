"""housing_stiffness_pattern: the pins' support stiffness varying around the housing in m lobes.

Parameters (c_m, s_m) [1] per harmonic m in HARMONICS: each pin's support law (groove and
housing behind it) multiplied by 1 + c_m cos(m theta) + s_m sin(m theta) at pin angle theta, added
as rows of Errors.pin_stiffness_lobes (dynamics.couplings.pin: the load sharing among the pins
follows). Signature (the model, RV-160N FE stiffness, per 0.1): no line at zero torque, m zc x
lines growing with it (m = 2: 0.34 arcsec at 300 N.m, 1.09 at 1800 N.m at 78x; m = 4: 0.23 ->
0.35 at 156x); odd m largely cancel between the two discs (180 deg apart) as for the pin
positions. The atlas (dynamics.signatures.groups) puts each lobe in a group of its own: the same
orders as pin_ring_pattern, told apart by the growth with torque.
Bounds: +-0.6 per component (the lobe <= 0.85 leaves every pin >= 0.15 of its law: the geometry's
floor is 0.1, a broken groove). ASSUMED: a housing's wall thickness, ribs and bolt holes vary the
pins' radial support by less than this. HARMONICS (2,): the even lobe whose line is strongest;
odd lobes cancel between the discs, and m = 4 (0.23-0.35 arcsec per 0.1 at 156x) was undetermined
on the real records (95 % interval wider than its range), which would drop the whole cause: a 156x
line growing with torque is reported as unexplained instead. Unit size 0.1.
Virtual bench: amplitude 0.2-0.5, any phase.
"""
from __future__ import annotations

from pipeline.diagnosis.causes.base import (Cause, Evidence, Fitted, lobe_draw, lobe_params, lobe_report,
                                            lobe_rows)

HARMONICS = (2,)
BOUND = 0.6


class HousingStiffnessPattern(Cause):
    id = "housing_stiffness_pattern"
    description = "pin support (groove, housing) stiffness varying around the ring in m lobes"
    signature = "m zc x lines (even m) absent at zero torque, growing with it"
    unit_size = 0.1
    dc_even = True   # the mean shift (lost motion) is the same for the pattern turned: even in its size

    def params(self, case):
        return lobe_params("housing_stiffness", "1", HARMONICS, BOUND)

    def apply(self, case, stiffness, p):
        rows = [list(r) for r in case.errors.pin_stiffness_lobes] + lobe_rows(HARMONICS, p)
        return case.with_errors(pin_stiffness_lobes=rows), stiffness

    def orders(self, case):
        return tuple(m * case.cycloid.zc for m in HARMONICS)

    def report(self, fit: Fitted) -> dict:
        return lobe_report(self.id, "fraction", HARMONICS, fit)

    def evidence(self, ev: Evidence) -> str:
        zc = ev.case.cycloid.zc
        lines = "; ".join(f"{m * zc}x: {ev.line_by_torque(m * zc)}" for m in HARMONICS)
        return (f"{ev.prefix}residual lines at m zc x ({lines}) as the model's signature of a pin support "
                f"stiffness with m lobes (orders {list(ev.summary.orders)[:4]}; none at zero torque, growing "
                f"with it): the stiffer pins take more of the load as each disc's load zone sweeps the "
                f"ring. Same orders as pin_ring_pattern (pin positions: flat or falling with torque); "
                f"only the torque trend separates them, a ring measured under load would{ev.alternatives}.")

    def draw(self, rng, case):
        j = int(rng.integers(len(HARMONICS)))
        m = HARMONICS[j]
        p, a, ph = lobe_draw(rng, HARMONICS, j, 0.2, 0.5)
        return tuple(float(v) for v in p), {"housing_stiffness_pattern_harmonic": m,
                                            f"housing_stiffness_pattern_m{m}_fraction": a,
                                            f"housing_stiffness_pattern_m{m}_phase_deg": ph}


CAUSE = HousingStiffnessPattern()
