"""What the residual holds that no reported cause explains, said in one line each.

  left over        when the residual (after the extension, or before when no cause was reported)
                   is above LEFT_FACTOR x the records' noise floor: its RMS, the share in the record
                   means, and the strongest significant lines with order, amplitude per torque and
                   trend (causes/base.trend);
  direction        within one encoder zero holding both directions at >= 2 torque levels, a model
                   with one stiffness winds up symmetrically: the forward and backward mean
                   residuals then move with torque by opposite amounts. Their common part (the
                   mean over both directions changing with torque) is a direction asymmetry (e.g.
                   one direction stiffer) no registered cause models; said when it moves by more
                   than LEFT_FACTOR x the noise floor over the torques;
  torque sign      every loaded record's torque assisting its motion is DESIGN.md's convention
                   reversed (+ resists forward rotation): most likely a sign-flipped column;
  gap shape        the half-gap (forward minus backward mean of one encoder zero, halved) at >= 3
                   torque levels, for the records and for the model: each one's largest departure from
                   its own straight line in torque. When the residual's departs by more than
                   LEFT_FACTOR x the noise floor, the note gives both: a model whose contacts engage and
                   stiffen with load bends where a bench may be straight (or the reverse), and a
                   compliance factor scales a curve, it cannot straighten it.
"""
from __future__ import annotations

import numpy as np

from pipeline.diagnosis.causes.base import TORQUE_TOL_NM, torque_levels, trend
from pipeline.diagnosis.directions import direction_pairs, direction_split, split_text
from pipeline.diagnosis.orders import label_order, spectrum_of
from pipeline.diagnosis.significance import test_lines
from pipeline.diagnosis.zeros import rms

LEFT_FACTOR = 3.0
MAX_LINES = 4


def torque_sign_notes(records) -> list[str]:
    loaded = [r for r in records if abs(r.torque_Nm) > 0]
    if loaded and all(r.torque_Nm * r.direction < 0 for r in loaded):
        return ["every loaded record's torque assists its motion (negative on forward runs, positive "
                "on backward ones), the reverse of DESIGN.md's convention (+ resists forward rotation): "
                "if the torque column's sign is flipped, negate it; the diagnosis simulates the column as given"]
    return []


def unexplained(case, records, groups, residuals, noise: float, explained: bool) -> list[str]:
    out = _direction_asymmetry(records, groups, residuals, noise)
    total = rms(residuals)
    if total <= LEFT_FACTOR * noise:
        return out
    means = rms([np.full(1, float(np.mean(r))) for r in residuals])
    what = "after the extension" if explained else "with no cause reported"
    out.append(f"{total:.3g} arcsec RMS left {what} (noise floor {noise:.3g} arcsec; record means "
               f"{means:.3g} arcsec RMS){_lines_text(case, records, groups, residuals, noise)}: no registered cause "
               f"explains it")
    return out


def strongest_lines(case, records, residuals, noise: float, count: int = MAX_LINES) -> dict[int, list]:
    """{order: [(|torque|, amplitude), ...]} of the `count` strongest lines that are significant and
    above the noise floor in some record, strongest first."""
    found: dict[int, list] = {}
    for rec, r in zip(records, residuals):
        spec = spectrum_of(rec.output_angle_deg, r)
        top = int(min(4 * case.cycloid.zp + 10, spec.order[-1]))
        for line in test_lines(spec, range(1, top + 1)):
            if line.significant and line.amplitude >= noise:   # significant and an effect
                found.setdefault(int(round(line.order)), []).append((abs(rec.torque_Nm), line.amplitude))
    best = sorted(found, key=lambda k: -max(a for _, a in found[k]))[:count]
    return {k: found[k] for k in best}


def _lines_text(case, records, groups, residuals, noise: float) -> str:
    """'; strongest lines: 39x (zc=39x ...) 9.7 arcsec at 300 N.m, ...; growing with torque, reverses
    with the motion (...)' (directions.py: where a group holds both directions at a torque)."""
    found = strongest_lines(case, records, residuals, noise)
    if not found:
        return ""
    splits = direction_split(records, groups, residuals, tuple(found))
    items = []
    for k, pts in found.items():
        pts = sorted(pts)
        levels = torque_levels([t for t, _ in pts])
        amps = [max(a for t, a in pts if abs(t - lv) <= TORQUE_TOL_NM) for lv in levels]   # largest per torque level
        label = label_order(case, k)
        how = split_text(case, splits, k)
        items.append(f"{k}x{f' ({label})' if label else ''} {'/'.join(f'{a:.2g}' for a in amps)} arcsec "
                     f"at {'/'.join(f'{t:g}' for t in levels)} N.m, {trend(pts)}{f', {how}' if how else ''}")
    return "; strongest lines " + "; ".join(items)


def half_gaps(records, groups, signals) -> dict[float, float]:
    """|torque| -> (forward mean - backward mean) / 2 of the first pair (direction_pairs) at that level."""
    out: dict[float, float] = {}
    for f, b, t, _ in direction_pairs(records, groups):
        if not any(abs(t - lv) <= TORQUE_TOL_NM for lv in out):
            out[t] = 0.5 * (float(np.mean(signals[f])) - float(np.mean(signals[b])))
    return dict(sorted(out.items()))


def departure_from_line(points: dict[float, float]) -> np.ndarray:
    """Values less their least-squares straight line in torque."""
    t, v = np.array(list(points)), np.array(list(points.values()))
    return v - np.polyval(np.polyfit(t, v, 1), t)


def gap_shape_notes(records, groups, measured, simulated, residuals, noise: float) -> list[str]:
    res = half_gaps(records, groups, residuals)
    if len(res) < 3:
        return []
    dev = departure_from_line(res)
    if np.max(np.abs(dev)) <= LEFT_FACTOR * noise:
        return []
    rec = np.max(np.abs(departure_from_line(half_gaps(records, groups, measured))))
    mod = np.max(np.abs(departure_from_line(half_gaps(records, groups, simulated))))
    levels = "/".join(f"{t:g}" for t in res)
    return [f"gap shape: the residual half-gap (forward minus backward mean, halved) departs from a straight "
            f"line in torque by {'/'.join(f'{d:+.2g}' for d in dev)} arcsec at {levels} N.m; the records' own "
            f"half-gap departs from its straight line by up to {rec:.2g} arcsec, the model's (as given, before "
            f"any cause) by {mod:.2g}: the {'model bends where the records are straight' if mod > rec else 'records bend where the model is straight'}, "
            f"which a compliance factor scales but cannot straighten"]


def _direction_asymmetry(records, groups, residuals, noise: float) -> list[str]:
    out = []
    for g in dict.fromkeys(groups):
        idx = [k for k in range(len(records)) if groups[k] == g]
        levels = torque_levels([abs(records[k].torque_Nm) for k in idx])
        per_dir = {}
        for d in (1, -1):
            pts = [(abs(records[k].torque_Nm), float(np.mean(residuals[k]))) for k in idx
                   if records[k].direction == d]
            if len(torque_levels([t for t, _ in pts])) >= 2:
                per_dir[d] = np.polyfit(*np.array(pts).T, 1)[0]
        if len(per_dir) < 2 or len(levels) < 2:
            continue
        span = levels[-1] - levels[0]
        common = 0.5 * (per_dir[1] + per_dir[-1]) * span
        if abs(common) > LEFT_FACTOR * noise:
            out.append(f"direction asymmetry: with one encoder zero, the forward mean residual moves "
                       f"{per_dir[1] * 100:+.3g} and the backward {per_dir[-1] * 100:+.3g} arcsec per 100 N.m "
                       f"({levels[0]:g} to {levels[-1]:g} N.m): one stiffness would move them oppositely; the "
                       f"reducer winds up differently in the two directions ({common:+.3g} arcsec over the "
                       f"torques), which no registered cause models")
    return out
