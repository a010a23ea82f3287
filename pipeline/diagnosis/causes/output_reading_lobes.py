"""output_reading_lobes: the output encoder's reading error in m lobes (its mounting, not the reducer).

Parameters (c_m, s_m) [um] per harmonic m in `harmonics`: a tangential reading error
c_m cos(m theta) + s_m sin(m theta) at the output flange radius r, added as rows of
Errors.output_reading_lobes (dynamics.reducer.measured_output_rad reads it as amplitude / r). The
mechanism: a ring encoder (or the hub it is clamped to) deformed by its mounting screws, and the
graduation's own low-order error, read once per output revolution m times. Signature (the
model): a line at m x, the same at every torque and in both directions (a reading error, like
output_coaxiality at 1x), 1 / r = 2.29 arcsec per um at r = 90 mm. No part of the reducer puts a
line at 2x or 3x in this model (the atlas: carrier-side errors show at multiples of zp, ring
patterns at m zc), so a 2x or 3x line fixed in output angle is the bench's, or a mechanism the
model lacks: a line that grows with torque or turns with the direction is not this cause
(its load-dependent part stays in the residual, said unexplained).
Bounds: +-20 um per component (ASSUMED: a clamped encoder ring or hub deforms by a few um; 20 um
is a damaged or badly mounted encoder). Harmonics (2, 3): the low orders above coaxiality that an
RV bench shows (the real records: 2x at 1.1-1.4 arcsec and 3x at 2.7-5.0 arcsec, phase fixed in
output angle within +-35 deg over every record). Unit size 1 um.
Virtual bench: one lobe m in `harmonics`, amplitude 1-3 um, any phase.
"""
from __future__ import annotations

from pipeline.diagnosis.causes.base import Evidence, LobeCause


class OutputReadingLobes(LobeCause):
    id = "output_reading_lobes"
    description = "output encoder reading error in m lobes (mounting deformation, graduation)"
    signature = "m x lines (m = 2, 3), the same at every torque and in both directions"
    unit_size = 1.0
    additive = True   # a reading of the output encoder: adds to the mechanism's TE whatever it is
    harmonics = (2, 3)
    bound = 20.0
    param_prefix, param_unit, report_unit = "reading", "um", "um"
    errors_field = "output_reading_lobes"
    draw_range = (1.0, 3.0)
    dc_even = False   # a reading lobe averages out over each revolution: no mean shift

    def orders(self, case):
        return self.harmonics

    def evidence(self, ev: Evidence) -> str:
        return (f"{ev.prefix}low-order residual lines fixed in output angle ({self.lines_text(ev)}) as the model's signature "
                f"of the output encoder's reading in m lobes (the same at every torque and in both directions, "
                f"like the 1x of coaxiality): the encoder ring or hub deformed by its mounting. No part error "
                f"of the reducer puts a line at these orders in this model; a part of the line that grows "
                f"with torque is not explained by it{ev.alternatives}.")


CAUSE = OutputReadingLobes()
