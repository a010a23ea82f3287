"""housing_stiffness_pattern: the pins' support stiffness varying around the housing in m lobes.

Parameters (c_m, s_m) [1] per harmonic m in `harmonics`: each pin's support law (groove and
housing behind it) multiplied by 1 + c_m cos(m theta) + s_m sin(m theta) at pin angle theta, added
as rows of Errors.pin_stiffness_lobes (dynamics.couplings.pin: the load sharing among the pins
follows). Signature (the model, RV-160N FE stiffness, per 0.1): no line at zero torque, m zc x
lines growing with it (m = 2: 0.34 arcsec at 300 N.m, 1.09 at 1800 N.m at 78x; m = 4: 0.23 ->
0.35 at 156x); odd m largely cancel between the two discs (180 deg apart) as for the pin
positions. The atlas (dynamics.signatures.groups) puts each lobe in a group of its own: the same
orders as pin_ring_pattern, told apart by the growth with torque.
Bounds: +-0.3 per component: two harmonics of magnitude <= 0.42 each leave every pin >= 0.15 of
its law (the geometry's floor is 0.1, a broken groove; +-0.6 with two harmonics let the real
records' fit step to -0.23 and abort). ASSUMED: a housing's wall thickness, ribs and bolt holes vary the
pins' radial support by less than this. Harmonics (2, 4): the 78x and 156x lines that grow with
torque on a real RV bench (156x from 2.7 to 7.1 arcsec, DESIGN.md); odd lobes cancel between the
discs. The cause acts only through the model's pin support stiffness parameter
(Errors.pin_stiffness_lobes), never through a hand-made line: today dynamics.couplings.pin scales
each pin's whole series law with it (tooth FE + disc body + groove), a Hertzian path that carries
~14 % of the output compliance, so a lobe of 0.3 gives ~1.1 arcsec at 156x at rated torque on the
RV-40E, saturating with torque; ASSUMED for the assembled-reducer work (issue 20, an elastic
housing condensed to the pins' support compliance): the same parameter will modulate that
housing compliance, and this cause follows without change. A 156x line larger than the model can
make within the bound is reported at the bound, "beyond the stated range", the rest unexplained
(extension.py). Unit size 0.1.
Virtual bench: amplitude 0.2-0.5, any phase.
"""
from __future__ import annotations

from pipeline.diagnosis.causes.base import Evidence, LobeCause


class HousingStiffnessPattern(LobeCause):
    id = "housing_stiffness_pattern"
    description = "pin support (groove, housing) stiffness varying around the ring in m lobes"
    signature = "m zc x lines (even m) absent at zero torque, growing with it"
    unit_size = 0.1
    harmonics = (2, 4)
    bound = 0.3
    param_prefix, param_unit, report_unit = "housing_stiffness", "1", "fraction"
    errors_field = "pin_stiffness_lobes"
    draw_range = (0.2, 0.5)

    def evidence(self, ev: Evidence) -> str:
        return (f"{ev.prefix}residual lines at m zc x ({self.lines_text(ev)}) as the model's signature of a pin support "
                f"stiffness with m lobes (orders {list(ev.summary.orders)[:4]}; none at zero torque, growing "
                f"with it): the stiffer pins take more of the load as each disc's load zone sweeps the "
                f"ring. Same orders as pin_ring_pattern (pin positions: flat or falling with torque); "
                f"only the torque trend separates them, a ring measured under load would{ev.alternatives}.")


CAUSE = HousingStiffnessPattern()
