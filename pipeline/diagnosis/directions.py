"""A line's forward and backward phasors split into the part common to both directions of motion
and the part that reverses with the motion: what kind of error made it.

Within one encoder zero (zeros.py), a forward and a backward record at one torque level share the
output angle theta, so each order k has a phasor per direction, F and B (least squares of the signal
on cos k theta, sin k theta and a constant over the whole record, theta absolute: a backward run's
angle runs down and its phasor is in the same frame as the forward one's). Then

  common    C = (F + B) / 2   the same in both directions: a position-type error (a pin or crank
                              hole off tangentially, a crank timing, a coaxiality, an encoder's
                              reading), or a compliance under a load that keeps its sign when the
                              motion reverses (the radial part of the discs' pin resultant);
  reversing R = (F - B) / 2   opposite in the two directions: a clearance-type error (a pin off
                              radially, a pin radius: the contacts change flank with the motion and
                              the gap change acts with the opposite sign), or a compliance under the
                              torque itself (a stiffness lobe times the signed load).

The torque trend separates the two kinds within each part: a geometric error is there at zero torque,
a compliance grows from zero. A line of one part only names the kind of cause before any model is
fitted; the residual's lines after the extension say what kind of cause is still missing.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pipeline.diagnosis.causes.base import TORQUE_TOL_NM
from pipeline.diagnosis.orders import label_order

DOMINANT = 2.0   # one part is "the" reading when its amplitude is at least this times the other's


@dataclass(frozen=True)
class DirectionSplit:
    """One order at one torque level of one encoder-zero group [arcsec; phases of cos(k theta + phi)]."""
    order: int
    torque_Nm: float
    group: str
    forward: complex
    backward: complex

    @property
    def common(self) -> complex:
        return 0.5 * (self.forward + self.backward)

    @property
    def reversing(self) -> complex:
        return 0.5 * (self.forward - self.backward)

    @property
    def reading(self) -> str:
        c, r = abs(self.common), abs(self.reversing)
        if r >= DOMINANT * c:
            return "reverses with the motion"
        if c >= DOMINANT * r:
            return "common to both directions"
        return "both parts"

    def to_json(self) -> dict:
        def ph(z):
            return {"amplitude_arcsec": round(float(abs(z)), 4), "phase_deg": round(float(np.degrees(np.angle(z))), 1)}
        return {"order": self.order, "torque_Nm": self.torque_Nm, "group": self.group,
                "forward": ph(self.forward), "backward": ph(self.backward),
                "common": ph(self.common), "reversing": ph(self.reversing), "reading": self.reading}


def line_phasor(output_angle_deg, signal, order: int) -> complex:
    """a + i b of the least-squares a cos(k theta) - b sin(k theta) + const, i.e. |z| cos(k theta + arg z),
    theta the absolute output angle [deg] (not the record's travel): both directions in one frame."""
    th = np.radians(np.asarray(output_angle_deg, float)) * order
    A = np.column_stack([np.cos(th), -np.sin(th), np.ones_like(th)])
    coef = np.linalg.lstsq(A, np.asarray(signal, float), rcond=None)[0]
    return complex(coef[0], coef[1])


def direction_pairs(records, groups) -> list[tuple[int, int, float, str]]:
    """(forward index, backward index, |torque|, group) for each forward record of an encoder-zero
    group with a backward partner at its torque level (each record used once, in the given order)."""
    pairs = []
    for g in dict.fromkeys(groups):
        idx = [k for k in range(len(records)) if groups[k] == g]
        used = set()
        for k in idx:
            if k in used or records[k].direction < 0:
                continue
            tq = abs(records[k].torque_Nm)
            partner = next((j for j in idx if j not in used and records[j].direction < 0
                            and abs(abs(records[j].torque_Nm) - tq) <= TORQUE_TOL_NM), None)
            if partner is not None:
                used.update((k, partner))
                pairs.append((k, partner, float(tq), str(g)))
    return pairs


def direction_split(records, groups, signals, orders) -> tuple[DirectionSplit, ...]:
    """Every order of `orders` at every torque level where one encoder-zero group holds a forward and
    a backward record (direction_pairs); records lacking a partner are skipped."""
    out = [DirectionSplit(int(order), tq, g, line_phasor(records[f].output_angle_deg, signals[f], order),
                          line_phasor(records[b].output_angle_deg, signals[b], order))
           for f, b, tq, g in direction_pairs(records, groups) for order in orders]
    return tuple(sorted(out, key=lambda s: (s.order, s.torque_Nm, s.group)))


def split_text(case, splits, order: int) -> str:
    """'reverses with the motion at 0/300 N.m, both parts at 1800 N.m (reversing / common 3.1/1.3,
    3.5/0.96, 4.8/4 arcsec)', or '' when no level holds both directions."""
    rows = [s for s in splits if s.order == order]
    if not rows:
        return ""
    by_reading: dict[str, list] = {}
    for s in rows:
        by_reading.setdefault(s.reading, []).append(f"{s.torque_Nm:g}")
    what = ", ".join(f"{r} at {'/'.join(t)} N.m" for r, t in by_reading.items())
    return f"{what} (reversing / common {', '.join(f'{abs(s.reversing):.2g}/{abs(s.common):.2g}' for s in rows)} arcsec)"


def table(case, splits) -> list[dict]:
    """diagnosis_lines.json rows: one per order, its label and the split at each torque level."""
    rows = []
    for order in sorted({s.order for s in splits}):
        mine = [s for s in splits if s.order == order]
        rows.append({"order": order, "label": label_order(case, order),
                     "levels": [s.to_json() for s in mine]})
    return rows
