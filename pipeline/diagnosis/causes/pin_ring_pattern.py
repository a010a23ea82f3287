"""pin_ring_pattern: the pin grooves of the housing off their circle in a pattern of m lobes.

Parameters (c_m, s_m) [um] per harmonic m in `harmonics`: the radial pin-position error
c_m cos(m theta) + s_m sin(m theta) at pin angle theta, added as rows of
Errors.pin_radial_lobes (dynamics.couplings.pin: each pin's centre moved, the real gap follows).
Signature (the model, RV-160N FE stiffness, per um): each disc's load zone sweeps the ring at
zc x the output speed, so m lobes give m zc x; the two discs sit 180 deg apart, so odd m largely
cancel (m = 1: 0.3 arcsec/um at 39x) and even m add (m = 2: 1.8 -> 1.2 arcsec/um at 78x from 0
to 1800 N.m; m = 4: 1.6 -> 0.35 at 156x): lines independent of torque or falling with it. At no
load m = 1 also shows at 78x and shifts the mean. Shares its orders with housing_stiffness_pattern
(the same lobes of the pin support stiffness), told apart by the torque trend: a stiffness lobe
has no line at zero torque and grows with it; a single pin off (Errors.per_pin_radial_um) puts a
comb at every m zc x.
Bounds: +-20 um per component. ASSUMED: a housing ring ground to IT5 at 180-250 mm (20 um) holds
every lobe below it; more is a damaged or wrong housing. Unit size 2 um. Harmonics (2, 4): the
78x and 156x lines of a real RV bench (DESIGN.md); m = 1 is left out: its 39x line is cancelled to
0.3 arcsec/um, so a few arcsec at 39x would need a lobe near the bound that the records cannot
determine (on the real records its 95 % interval spanned the whole range), and one undetermined
harmonic would drop the whole cause; a 39x line is reported as unexplained instead.
Virtual bench: one lobe m in `harmonics`, amplitude 3-8 um, any phase.
"""
from __future__ import annotations

from pipeline.diagnosis.causes.base import Evidence, LobeCause


class PinRingPattern(LobeCause):
    id = "pin_ring_pattern"
    description = "pin grooves off their circle in m lobes (housing roundness)"
    signature = "m zc x lines (odd m cancelled between the discs, even m added), flat or falling with torque"
    unit_size = 2.0
    harmonics = (2, 4)
    bound = 20.0
    param_prefix, param_unit, report_unit = "pin_ring", "um", "um"
    errors_field = "pin_radial_lobes"
    draw_range = (3.0, 8.0)

    def evidence(self, ev: Evidence) -> str:
        return (f"{ev.prefix}residual lines at m zc x ({self.lines_text(ev)}) as the model's signature of a pin ring "
                f"with m lobes of radial position (orders {list(ev.summary.orders)[:4]}): each disc's load "
                f"zone sweeps the ring zc times per output revolution; the discs 180 deg apart cancel odd m "
                f"and add even m. Shares these orders with housing_stiffness_pattern (support-stiffness "
                f"lobes, no line at zero torque, growing with it) and with single pins off their circle "
                f"(a comb at every m zc x); the torque trend separates the first, a pin-by-pin "
                f"measurement of the ring the second{ev.alternatives}.")


CAUSE = PinRingPattern()
