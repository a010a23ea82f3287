"""Checks of the records against the case, before any fitting: refuse what cannot be diagnosed,
repair what can be repaired, and say so (DESIGN.md: records of another ratio are refused).

  ratio     the record's input/output angle ratio (median over quarter-record spans: robust to a
            glitch) must be the case's within RATIO_TOL; a record of another reducer is refused;
  time unit `time_s` is seconds. A `# input_speed_rpm:` comment that disagrees with the samples by
            a factor 1000 or 10^6 (time in ms or us) or 1/60 (minutes) converts the time, with a
            note; any other disagreement is refused. Without the comment, a speed above
            MAX_SPEED_FACTOR x the case's rated input speed is refused (no time unit in seconds
            gives it), and one whose x 1000 lies within a factor 2 of the case's input speed while
            it is below 1/100 of it is read as milliseconds, converted with a note naming the
            comment that keeps seconds;
  glitches  a sample whose TE leaves the running median of its GLITCH_WINDOW neighbours by more
            than GLITCH_SIGMAS robust sigmas (floored at significance.MIN_NOISE_ARCSEC) is an encoder
            glitch: found, reported (sample, time, size) and masked (the row dropped); more than
            MAX_GLITCH_SHARE of a record is refused as an unusable encoder signal;
  gaps      time steps over GAP_STEPS x the median are reported with the output angle they span
            (the diagnosis works on output angle and interpolates across them).
The quasi-static model does not use the speed: it matters for pairing (zeros.py) and the report.
"""
from __future__ import annotations

import dataclasses

import numpy as np
from scipy.ndimage import median_filter

from dynamics.records import BenchRecord, RecordError
from pipeline.diagnosis.significance import MIN_NOISE_ARCSEC

RATIO_TOL = 0.01          # TE is < 0.1 % of the travel on any working gear: 1 % is another ratio
MAX_SPEED_FACTOR = 10.0   # ASSUMED: catalog maximum input speeds are 2-5 x rated; 10 x is no bench
UNIT_TOL = 0.05           # a stated speed agrees with the samples within 5 %
TIME_UNITS = {1e-3: "milliseconds", 1e-6: "microseconds", 60.0: "minutes"}   # factor to seconds
GLITCH_SIGMAS = 10.0
GLITCH_WINDOW = 11        # running-median window (samples): bridges up to 5 consecutive glitches
MAX_GLITCH_SHARE = 0.01
GAP_STEPS = 5.0


def check_records(case, records) -> tuple[list[BenchRecord], list[str]]:
    """(records as the diagnosis uses them, notes); RecordError (one line) for a refused record."""
    out, notes = [], []
    for r in records:
        _check_ratio(case, r)
        r, n1 = _time_unit(case, r)
        r, n2 = _mask_glitches(case, r)
        out.append(r)
        notes += n1 + n2 + _gaps(r)
    return out, notes


def record_ratio(r: BenchRecord) -> float:
    """Input/output angle ratio: the median over spans of a quarter of the record."""
    n = len(r.time_s)
    lag = max(n // 4, 1)
    d_in = r.input_angle_deg[lag:] - r.input_angle_deg[:-lag]
    d_out = r.output_angle_deg[lag:] - r.output_angle_deg[:-lag]
    ok = np.abs(d_out) > 0
    return float(np.median(d_in[ok] / d_out[ok])) if ok.any() else float("nan")


def _check_ratio(case, r: BenchRecord) -> None:
    ratio = record_ratio(r)
    if not (np.isfinite(ratio) and abs(ratio / case.ratio - 1.0) <= RATIO_TOL):
        raise RecordError(f"{r.path}: input/output angle ratio {ratio:.4g}, the case {case.name} has "
                          f"i = {case.ratio:g}: allowed within {RATIO_TOL:.0%} (a record of another "
                          f"reducer, or angles of another unit or sign, cannot be diagnosed on this case)")


def _scaled_time(r: BenchRecord, factor: float) -> BenchRecord:
    return dataclasses.replace(r, time_s=r.time_s * factor)


def _time_unit(case, r: BenchRecord) -> tuple[BenchRecord, list[str]]:
    speed, stated = r.input_speed_rpm, r.comment_value("input_speed_rpm")
    if stated is not None and stated > 0:
        ratio = speed / stated
        if abs(ratio - 1.0) <= UNIT_TOL:
            return r, []
        for f, unit in TIME_UNITS.items():
            if abs(ratio / f - 1.0) <= UNIT_TOL:
                return _scaled_time(r, f), [
                    f"{r.name}: time_s read as {unit} (the samples give {speed:.4g} rpm, the record "
                    f"states input_speed_rpm {stated:g}): converted to seconds"]
        raise RecordError(f"{r.path}: the samples give an input speed of {speed:.4g} rpm, the record "
                          f"states input_speed_rpm {stated:g}; they must agree within {UNIT_TOL:.0%} "
                          f"(time_s in seconds; milliseconds, microseconds and minutes are recognised)")
    nominal = case.operation.input_speed_rpm
    top = MAX_SPEED_FACTOR * case.operation.rated_output_speed_rpm * case.ratio
    if speed > top:
        raise RecordError(f"{r.path}: the samples give an input speed of {speed:.4g} rpm, above "
                          f"{top:.4g} rpm ({MAX_SPEED_FACTOR:g} x the case's rated input speed): time_s "
                          f"must be in seconds (or state the speed: `# input_speed_rpm: N`)")
    if speed < nominal / 100.0 and 0.5 <= speed * 1000.0 / nominal <= 2.0:
        return _scaled_time(r, 1e-3), [
            f"{r.name}: time_s read as milliseconds (the samples give {speed:.4g} rpm, x 1000 = "
            f"{speed * 1000:.4g} rpm near the case's {nominal:g} rpm): converted; add "
            f"`# input_speed_rpm: {speed:.4g}` to the record if the time really is in seconds"]
    return r, []


def glitches(case, r: BenchRecord) -> tuple[np.ndarray, np.ndarray, float]:
    """(indices of glitch samples, their TE deviation [arcsec], threshold [arcsec])."""
    te = r.te_arcsec(case.ratio)
    if len(te) < GLITCH_WINDOW:
        return np.zeros(0, int), np.zeros(0), np.inf
    dev = np.abs(te - median_filter(te, size=GLITCH_WINDOW, mode="nearest"))
    # robust scale: the 95th percentile / 1.96 (Gaussian); the MAD collapses to 0 on quantised
    # encoders (most samples equal their median); <= 1 % glitches cannot move either
    sigma = max(float(np.percentile(dev, 95)) / 1.96, 1.4826 * float(np.median(dev)))
    thr = GLITCH_SIGMAS * max(sigma, MIN_NOISE_ARCSEC)
    idx = np.flatnonzero(dev > thr)
    return idx, dev[idx], thr


def _mask_glitches(case, r: BenchRecord) -> tuple[BenchRecord, list[str]]:
    idx, dev, thr = glitches(case, r)
    if not idx.size:
        return r, []
    share = idx.size / len(r.time_s)
    if share > MAX_GLITCH_SHARE:
        raise RecordError(f"{r.path}: {idx.size} samples ({share:.1%}) leave their neighbours' TE by more "
                          f"than {thr:.3g} arcsec: at most {MAX_GLITCH_SHARE:.0%} glitches can be masked; "
                          f"the encoder signal is unusable")
    k = int(idx[np.argmax(np.abs(dev))])
    keep = np.ones(len(r.time_s), bool)
    keep[idx] = False
    masked = dataclasses.replace(r, time_s=r.time_s[keep], input_angle_deg=r.input_angle_deg[keep],
                                 output_angle_deg=r.output_angle_deg[keep],
                                 output_torque_Nm=r.output_torque_Nm[keep],
                                 extra={n: v[keep] for n, v in r.extra.items()})
    return masked, [f"{r.name}: {idx.size} encoder glitch(es) masked (largest at sample {k}, t = "
                    f"{r.time_s[k]:g} s: TE {np.max(np.abs(dev)):.4g} arcsec off its neighbours; "
                    f"threshold {thr:.3g} arcsec)"]


def _gaps(r: BenchRecord) -> list[str]:
    dt = np.diff(r.time_s)
    big = np.flatnonzero(dt > GAP_STEPS * float(np.median(dt)))
    if not big.size:
        return []
    k = int(big[np.argmax(dt[big])])
    span = abs(r.output_angle_deg[k + 1] - r.output_angle_deg[k])
    return [f"{r.name}: {big.size} time gap(s) in the samples (largest {dt[k]:.4g} s at t = "
            f"{r.time_s[k]:g} s, {span:.3g} deg of output): the TE is interpolated across them"]
