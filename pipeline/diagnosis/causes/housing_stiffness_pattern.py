"""housing_stiffness_pattern: the housing's pin seats softer in m lobes around the ring.

Mechanism: the elastic housing (fem.components.housing: the pins' seat compliance condensed from
the housing FE; its kept modes are DOFs of the lumped model, dynamics.couplings.housing) is softer
at pin k (angle theta_k) by an added seat compliance
    c_k = sum_m A_m (1 + cos(m theta_k - phi_m)),   (c_m, s_m) = A_m (cos phi_m, sin phi_m):
the ring thinner or less supported in m places (between ribs, bolt bosses or mounting pads) and
as the FE has it in between; one-sided, never stiffer than the housing FE. Each softened seat is a
local housing mode (a load on pin k moves its own seat, in any direction of the ring's plane),
condensed exactly into that pin's contact (dynamics.couplings.housing.SeatCompliance: in series
with the pin law, no DOF added). A linear spring: the lines it makes grow with torque as the
housing's own compliance does, none at zero torque.
Parameters (c_m, s_m) [um/kN] per harmonic m in `harmonics`.
Signature (the model, tests/support.py RV-40E stand-in, per 1 um/kN; isotropic seat modes as
DOFs gave the same): m = 4: 156x 0.016, 0.061, 0.083 arcsec at 3, 30, 60 % rated; m = 2: 78x
0.37 arcsec at 60 %; the mean (the pattern's average softening A_m: 1.2 arcsec at 60 %) is even in
the pattern's phase and size (`dc_even`, as LobeCause). By direction (RV-160N FE, 5 um/kN, 300 /
800 / 1800 N m, signed torque): m = 4's 156x reverses with the motion (1.4 / 1.8 / 2.3 arcsec), m = 2's
78x is common to both (2.6 / 5.2 / 9.0). Odd m: m = 3 nearly cancels between the discs 180 deg apart
(0.2 arcsec), m = 1 does not (39x, 0.56 / 1.36 / 2.79 arcsec, both common and reversing); not in
`harmonics` (README: its share of the real records' residual). The atlas (dynamics.signatures.groups)
puts each lobe in a group of its own: the same orders as pin_ring_pattern (flat or falling with
torque), told apart by the growth with torque.
Bounds: +-10 um/kN per component (a seat up to 2 x 14 um/kN softer at the crest of one lobe).
ASSUMED: a housing wall down to ~6 mm between supports ~40 mm apart, read as a beam in bending
under one seat's load (F L^3 / 48 E I with b = 40 mm: ~9 um/kN), bounds what a built housing's
thin spots add; the housing FE's own seats are stiffer by one to two orders. A line larger than
the bound can make is reported at the bound, "beyond the stated range", the rest unexplained
(extension.py): on the real RV-160N records (FE stiffness, 2026-11-27) the 156x line asks for
m = 4 at ~890 um/kN, held at 10. Limit: the pattern is one-sided, so its mean softening (A_m)
trades with torsional_stiffness's factor (there 3.11 -> 2.44); a pattern around the FE seat
(stiffer and softer) needs the FE seat's own compliance as its floor. Unit size 1 um/kN.
Virtual bench: one lobe, 4-8 um/kN, any phase.
History: until issue 23b this cause scaled each pin's whole series law (tooth FE, disc body and
groove: a Hertzian law), which saturates with torque and could not make a line growing with it.
"""
from __future__ import annotations

import dataclasses as dc

import numpy as np

from dynamics.couplings.housing import SEATS, SeatCompliance, seat_compliance
from pipeline.diagnosis.causes.base import Evidence, LobeCause

UM_PER_KN = 1e-9          # [m/N] per um/kN


def added_seat_compliance_m_per_N(harmonics, p, zp: int) -> np.ndarray:
    """(zp,) the added compliance of each pin seat [m/N] (module docstring), >= 0."""
    th = 2 * np.pi * np.arange(zp) / zp
    p = np.asarray(p, float).reshape(len(harmonics), 2)
    c = np.zeros(zp)
    for m, (cm, sm) in zip(harmonics, p):
        c += np.hypot(cm, sm) + cm * np.cos(m * th) + sm * np.sin(m * th)
    return np.maximum(c, 0.0) * UM_PER_KN


class HousingStiffnessPattern(LobeCause):
    id = "housing_stiffness_pattern"
    description = "housing pin seats softer in m lobes around the ring (a seat compliance of the housing)"
    signature = "m zc x lines (even m) absent at zero torque, growing with torque"
    unit_size = 1.0
    harmonics = (2, 4)
    bound = 10.0
    param_prefix, param_unit, report_unit = "housing_seat", "um_per_kN", "um_per_kN"
    errors_field = ""
    draw_range = (4.0, 8.0)

    def apply(self, case, stiffness, p):
        if not np.any(np.asarray(p, float)):
            return case, stiffness
        zp = case.cycloid.zp
        c = seat_compliance(stiffness, zp) + added_seat_compliance_m_per_N(self.harmonics, p, zp)
        return case, dc.replace(stiffness, parts=dict(stiffness.parts, **{SEATS: SeatCompliance(c)}))

    def evidence(self, ev: Evidence) -> str:
        return (f"{ev.prefix}residual lines at m zc x ({self.lines_text(ev)}) as the model's signature of housing "
                f"pin seats softer in m lobes (orders {list(ev.summary.orders)[:4]}; none at zero torque, growing "
                f"with it): each disc's load zone sweeps the soft and the stiff seats zc times per output "
                f"revolution. Same orders as pin_ring_pattern (pin positions: flat or falling with torque); "
                f"only the torque trend separates them, a ring measured under load would{ev.alternatives}.")


CAUSE = HousingStiffnessPattern()
