"""Checks of the records against the case, before any fitting: refuse what cannot be diagnosed,
repair what can be repaired, and say so (DESIGN.md: records of another ratio are refused).

  ratio     the record's input/output angle ratio (median over quarter-record spans: robust to a
            glitch) must be the case's within RATIO_TOL; a record of another reducer is refused;
  then the metrologist's checks of dynamics.record_checks, in this order: time unit (against the
  record's `# input_speed_rpm:` or the case's speed), stated torque and other stated columns
  against the columns, encoder glitches (bound from the case's lost motion, reference rigidity,
  momentary torque and load inertia), samples missing from the record's clock (resampled within
  the limits), and, over the zero groups (zeros.py), a forward/backward pair winding up against
  its torque column. An error is one RecordError line; a repair is a note (`check_records`
  returns them; `diagnose` prints them as `warning:` lines and keeps them in diagnosis.json).
The quasi-static model does not use the speed: it matters for pairing (zeros.py) and the report.
"""
from __future__ import annotations

import dataclasses

import numpy as np

from dynamics import record_checks as rc
from dynamics.records import BenchRecord, RecordError

RATIO_TOL = 0.01          # TE is < 0.1 % of the travel on any working gear: 1 % is another ratio


def check_records(case, records) -> tuple[list[BenchRecord], list[str]]:
    """(records as the diagnosis uses them, notes: one warning line per repair); RecordError (one
    line) for a refused record."""
    out, notes = [], []
    lm = lost_motion_arcsec(case)
    for r in records:
        _check_ratio(case, r)
        r, found = check_record(case, r, lm)
        out.append(r)
        notes += [f.message for f in found]
    _check_wind_up(case, out, lm)
    return out, notes


def lost_motion_arcsec(case) -> float:
    """The case's geometric backlash, both ways (closed form of the modified profile)."""
    from geometry.clearance import closed_form_backlash
    return max(float(closed_form_backlash(case).total_arcmin) * rc.ARCSEC_PER_ARCMIN, 0.0)


def _raise_if(f: rc.Finding | None, r: BenchRecord) -> rc.Finding | None:
    if f is not None and f.is_error:
        raise RecordError(f.message.replace(r.name, r.path, 1))
    return f


def check_record(case, r: BenchRecord, lost_motion: float) -> tuple[BenchRecord, list[rc.Finding]]:
    """One record through the checks of dynamics.record_checks: (repaired record, warnings)."""
    op, found = case.operation, []
    factor, f = rc.time_unit(r.name, r.time_s, r.input_angle_deg, r.comment_value("input_speed_rpm"),
                             op.input_speed_rpm, op.rated_output_speed_rpm * case.ratio)
    if _raise_if(f, r):
        found.append(f)
        r = dataclasses.replace(r, time_s=r.time_s * factor)
    _raise_if(rc.torque_against_comment(r.name, r.comments, r.output_torque_Nm, op.rated_torque_Nm), r)
    _raise_if(rc.columns_against_comments(r.name, r.comments, r.extra), r)
    dt = np.diff(r.time_s)
    per_sample = np.r_[dt[0], np.maximum(dt[:-1], dt[1:]), dt[-1]]
    bound = rc.glitch_bound_arcsec(per_sample, lost_motion, op.reference_rigidity_Nm_per_arcmin,
                                   op.momentary_torque_Nm, case.dynamics.load_inertia_kg_m2)
    fixed, f = rc.repair_glitches(r.name, r.time_s, r.input_angle_deg, r.output_angle_deg, case.ratio, bound)
    if _raise_if(f, r):
        found.append(f)
        r = dataclasses.replace(r, input_angle_deg=fixed[0], output_angle_deg=fixed[1])
    cols = {"input_angle_deg": r.input_angle_deg, "output_angle_deg": r.output_angle_deg,
            "output_torque_Nm": r.output_torque_Nm, **{f"extra:{k}": v for k, v in r.extra.items()}}
    res, f = rc.resample_gaps(r.name, r.time_s, cols, r.output_angle_deg, case.cycloid.zp)
    if _raise_if(f, r):
        found.append(f)
        t, c = res
        r = dataclasses.replace(r, time_s=t, input_angle_deg=c["input_angle_deg"],
                                output_angle_deg=c["output_angle_deg"], output_torque_Nm=c["output_torque_Nm"],
                                extra={k[6:]: v for k, v in c.items() if k.startswith("extra:")})
    return r, found


def _check_wind_up(case, records, lost_motion: float) -> None:
    from pipeline.diagnosis.zeros import group_records
    groups = group_records(records)
    op = case.operation
    for g in dict.fromkeys(groups):
        idx = [k for k in range(len(records)) if groups[k] == g]
        fws = [k for k in idx if records[k].direction > 0]
        bws = [k for k in idx if records[k].direction < 0]
        for i in fws:
            for j in bws:
                a, b = records[i], records[j]
                if abs(abs(a.torque_Nm) - abs(b.torque_Nm)) > rc.TORQUE_TOL_RATED * op.rated_torque_Nm:
                    continue
                f = rc.wind_up_against_torque(a.path, b.path, a.te_arcsec(case.ratio), b.te_arcsec(case.ratio),
                                              a.torque_Nm, b.torque_Nm, lost_motion,
                                              op.reference_rigidity_Nm_per_arcmin, op.rated_torque_Nm)
                if f is not None:
                    raise RecordError(f.message)


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
