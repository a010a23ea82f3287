"""Do the records share one output-angle frame? Read off the mechanism's own lines.

A cause fixed in the reducer (a pin ring pattern, a housing lobe, a tilted ring, a crank's error)
puts its lines at a fixed phase of the output angle, whatever the torque: the diagnosis fits one
set of its parameters across every record, so it assumes every record's angle has one zero. A
bench that zeroes each condition on its own (the real RV-160N dataset says so of its TE) can move
that zero between conditions: a shift d of the recorded angle turns a line of order k by k d, so
the mechanism's high orders (m zc, m zp, the input's i and 2 i) turn far more than the 1x line,
and no fixed-phase cause can then explain them in every record.

For each encoder-zero group beyond the reference (the first: the lowest torque, as diagnose orders
the records), the shift d that best lays the group's phasors onto the reference's,
    M(d) = sum_k sum_parts |z_g,k e^{i k d} - z_ref,k|^2,   parts: common and reversing
(directions.py, each averaged over the group's torque levels), on a 0.005 deg grid over one period
of the zc family (+-180/zc deg), refined by a parabola. Its standard deviation from the
Gauss-Newton normal equation, sd^2 = s^2 / sum k^2 |z_g,k|^2 with s^2 = M(d) / (2 n - 1) (the
mismatch left: lines that change with torque count as noise). Reported when the shift removes at
least MIN_REMOVED of the mismatch, exceeds SIGMAS sd, and is what the other orders say without the
one that weighs most (k^2 |z|^2): their own shift within AGREE of it or SIGMAS of their sd (one
line whose phase moves with torque, a load zone moving, pulls the weighted optimum to itself and
would otherwise pass). A measurement of the records, not applied
to the fit (the fit would then also need to know which lines follow the output encoder's own frame;
README "Lines by direction and the records' angle frames" gives what aligning the real records does).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pipeline.diagnosis.directions import direction_split

MIN_REMOVED = 0.5
SIGMAS = 3.0
GRID_DEG = 0.005
AGREE = 0.25         # the shift without the weightiest order agrees within this share of it (or SIGMAS sd)


def mechanism_orders(case, max_order: int) -> tuple[int, ...]:
    """Orders the mechanism fixes to the output angle: m zc (the pin ring, m = 1..4), m zp (the
    cranks against the carrier, m = 1, 2) and the input shaft's i and 2 i, up to max_order."""
    c = case.cycloid
    ks = {m * c.zc for m in range(1, 5)} | {m * c.zp for m in (1, 2)}
    ratio = float(case.ratio)
    if abs(ratio - round(ratio)) < 1e-9:
        ks |= {int(round(ratio)), int(round(2 * ratio))}
    return tuple(sorted(k for k in ks if k <= max_order))


@dataclass(frozen=True)
class FrameShift:
    group: str
    reference: str
    shift_deg: float           # the group's recorded output angle less the reference's frame (subtract to align)
    sd_deg: float
    mismatch_removed: float    # 1 - M(d) / M(0)
    orders: tuple[int, ...]
    dominant_order: int = 0             # the order that weighs most in the fit
    without_dominant_deg: float = 0.0   # the shift the other orders give alone
    without_dominant_sd_deg: float = float("inf")
    torques_Nm: tuple[float, ...] = ()  # the group's |torque| levels
    reference_torques_Nm: tuple[float, ...] = ()

    @property
    def reported(self) -> bool:
        return (self.mismatch_removed >= MIN_REMOVED and abs(self.shift_deg) >= SIGMAS * self.sd_deg
                and abs(self.without_dominant_deg - self.shift_deg)
                <= max(AGREE * abs(self.shift_deg), SIGMAS * self.without_dominant_sd_deg))

    def to_json(self) -> dict:
        return {"group": self.group, "torques_Nm": list(self.torques_Nm), "reference": self.reference,
                "shift_deg": round(self.shift_deg, 4),
                "sd_deg": round(self.sd_deg, 4), "mismatch_removed": round(self.mismatch_removed, 3),
                "orders": list(self.orders), "dominant_order": self.dominant_order,
                "without_dominant_deg": round(self.without_dominant_deg, 4), "reported": self.reported}


def _phasors(splits, group, orders) -> np.ndarray:
    """(len(orders), 2) mean common and reversing phasors of one group over its torque levels."""
    out = np.zeros((len(orders), 2), complex)
    for i, k in enumerate(orders):
        rows = [s for s in splits if s.group == group and s.order == k]
        if rows:
            out[i] = np.mean([[s.common, s.reversing] for s in rows], axis=0)
    return out


def best_shift(k: np.ndarray, z_ref: np.ndarray, z_g: np.ndarray, half_window_deg: float) -> tuple[float, float, float]:
    """(shift [deg], sd [deg], share of the mismatch removed) of z_g e^{i k d} onto z_ref; k (n,),
    z (n, parts)."""
    kk = np.asarray(k, float)[:, None]
    grid = np.arange(-half_window_deg, half_window_deg + GRID_DEG / 2, GRID_DEG)
    rot = np.exp(1j * kk[None, :, :] * np.radians(grid)[:, None, None])          # (grid, n, 1)
    M = np.sum(np.abs(z_g[None] * rot - z_ref[None]) ** 2, axis=(1, 2))
    j = int(np.argmin(M))
    d = grid[j]
    if 0 < j < len(grid) - 1:                     # parabola through the three grid points
        den = M[j - 1] - 2 * M[j] + M[j + 1]
        if den > 0:
            d += 0.5 * GRID_DEG * (M[j - 1] - M[j + 1]) / den
    Md = float(np.sum(np.abs(z_g * np.exp(1j * kk * np.radians(d)) - z_ref) ** 2))
    M0 = float(np.sum(np.abs(z_g - z_ref) ** 2))
    n = z_ref.size
    s2 = Md / max(2 * n - 1, 1)
    info = float(np.sum(kk ** 2 * np.abs(z_g) ** 2))
    sd = float(np.degrees(np.sqrt(s2 / info))) if info > 0 else float("inf")
    return float(d), sd, (1.0 - Md / M0) if M0 > 0 else 0.0


def frame_shifts(case, records, groups, signals, max_order: int) -> tuple[FrameShift, ...]:
    """One FrameShift per encoder-zero group beyond the reference that holds both directions at a
    torque level (module docstring); () when fewer than two such groups."""
    orders = mechanism_orders(case, max_order)
    splits = direction_split(records, groups, signals, orders)
    have = list(dict.fromkeys(s.group for s in sorted(splits, key=lambda s: (s.torque_Nm, s.group))))
    if len(have) < 2 or not orders:
        return ()
    ref = have[0]
    z_ref = _phasors(splits, ref, orders)

    def levels(g):
        return tuple(sorted({s.torque_Nm for s in splits if s.group == g}))
    k = np.array(orders, float)
    half = 180.0 / case.cycloid.zc
    out = []
    for g in have[1:]:
        z_g = _phasors(splits, g, orders)
        d, sd, removed = best_shift(k, z_ref, z_g, half)
        top = int(np.argmax(k ** 2 * np.sum(np.abs(z_g) ** 2, axis=1)))
        rest = np.arange(len(k)) != top
        d_rest, sd_rest, _ = best_shift(k[rest], z_ref[rest], z_g[rest], half)
        out.append(FrameShift(g, ref, d, sd, removed, orders, int(k[top]), d_rest, sd_rest, levels(g), levels(ref)))
    return tuple(out)


def frame_notes(shifts) -> list[str]:
    """The diagnosis note for the reported shifts (one sentence), or none."""
    shown = [s for s in shifts if s.reported]
    if not shown:
        return []

    def level(torques):
        return "/".join(f"{t:g}" for t in torques)
    parts = ", ".join(f"the {level(s.torques_Nm)} N.m records {s.shift_deg:+.3f} +- {1.96 * s.sd_deg:.3f} deg "
                      f"(removing {s.mismatch_removed:.0%} of their phasor mismatch; the lines but "
                      f"{s.dominant_order}x alone: {s.without_dominant_deg:+.3f} deg)" for s in shown)
    return [f"angle frames: the mechanism's lines (orders {', '.join(f'{k}x' for k in shown[0].orders)}) "
            f"place {parts} from the {level(shown[0].reference_torques_Nm)} N.m records: they do not share one "
            f"output-angle zero (a bench that zeroes each condition on its own can move it); a cause fixed in the "
            f"reducer (pin ring, housing, tilt, cranks) is fitted across them as if they did, so its lines are "
            f"explained only in part; diagnosis_lines.json angle_frames"]
