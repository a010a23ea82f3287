"""Diagnosis of bench records against the model: residual, causes, extension, gain.

diagnose(case, stiffness, records) runs blind on the records (conditions read from each record):
  0. input checks (inputs.py, dynamics.record_checks): ratio, time unit, stated torque, encoder
     glitches and missing samples (repaired), wind-up against the torque column; refused
     records raise RecordError (one line), repairs and doubts become notes;
  1. simulate each record (simulate.py), residual = measured TE - simulated TE;
  2. one free offset per encoder-zero group (zeros.py) is removed in every RMS reported;
  3. signature library (signatures.py) of every registered cause (causes/, `causes.CAUSES`, read
     at each call) -> features (features.py) -> forward selection (fit.py); each finding's text
     is its cause's `evidence`;
  4. extension (extension.py): the named causes' parameters fitted with the model in the loop,
     bounded to each cause's physical range; a cause on its bound or whose effect is below the
     records' noise floor is dropped (a note says why) and never reported;
  5. what the residual left holds that no reported cause explains (unexplained.py): one line each;
     the strongest lines before and after, split into the part common to both directions of motion
     and the part that reverses with it (directions.py: which kind of error made each); whether
     the records share one output-angle zero, read off the mechanism's lines (frames.py: reported,
     not applied).
Hold-out rule: with >= 3 zero groups the group of median |torque| (an interpolation check), with 2
the last group given, with 1 group of several records the last record, with 1 record none.
Limits: quasi-static model (no speed effects); constant torque per record; findings rank the
evidence the records hold (e.g. one torque level cannot tell wind-up from lost motion).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from dynamics.records import BenchRecord
from pipeline.diagnosis import causes as registry, directions
from pipeline.diagnosis.directions import direction_split
from pipeline.diagnosis.frames import frame_notes, frame_shifts
from pipeline.diagnosis.causes.base import Evidence
from pipeline.diagnosis.extension import Extension, Run, extend
from pipeline.diagnosis.features import FeatureMap
from pipeline.diagnosis.fit import CauseColumns, MatchResult, match, reduce_columns
from pipeline.diagnosis.inputs import check_records
from pipeline.diagnosis.orders import spectrum_of
from pipeline.diagnosis.signatures import SignatureSummary, signature_columns, summarise
from pipeline.diagnosis.significance import Line, noise_floor_arcsec, test_lines
from pipeline.diagnosis.simulate import (TEModel, default_points_per_rev, max_order as order_limit, process_pool,
                                         prefetch_models, quasi_static_te, seed_tangents, seeding,
                                         simulate_records)
from pipeline.diagnosis.unexplained import gap_shape_notes, strongest_lines, torque_sign_notes, unexplained
from pipeline.diagnosis.zeros import group_records, offset_columns, remove_offsets, rms

__all__ = ["Diagnosis", "Extension", "Finding", "diagnose", "holdout_split", "remove_offsets", "rms"]


if __doc__:   # the causes that exist, read from the registry (None under python -OO)
    __doc__ += "Registered causes (pipeline.diagnosis.causes):\n" + registry.describe() + "\n"

@dataclass(frozen=True)
class Finding:
    cause: str
    score: float       # share of the post-offset weighted residual power the cause explains
    evidence: str
    p_value: float = 1.0


@dataclass(frozen=True)
class Diagnosis:
    cause: str | None
    findings: tuple[Finding, ...]
    residual_rms_arcsec: float
    residual_pp_arcsec: float
    extension: Extension | None
    records: tuple[BenchRecord, ...]
    groups: tuple[str, ...]
    measured_te: tuple[np.ndarray, ...]
    simulated_te: tuple[np.ndarray, ...]
    residual_before: tuple[np.ndarray, ...]      # offsets removed
    residual_after: tuple[np.ndarray, ...] | None
    lines: tuple[tuple[Line, ...], ...]           # significant residual lines per record
    summaries: tuple[SignatureSummary, ...] = ()
    notes: tuple[str, ...] = ()                   # input repairs, dropped causes, unexplained residual
    noise_arcsec: float = 0.0                     # the records' noise floor (significance.py)
    line_directions: dict | None = None           # {"before", "after"}: directions.table of the strongest lines
    angle_frames: tuple = ()                      # frames.FrameShift per encoder-zero group beyond the first

    def lines_json(self) -> dict:
        """diagnosis_lines.json (beside diagnosis.json, which keeps DESIGN.md's keys): the strongest
        lines split by direction of motion, before and after, and the records' angle frames."""
        return {"lines_by_direction": self.line_directions,
                "angle_frames": [f.to_json() for f in self.angle_frames]}

    def to_json(self) -> dict:
        ext = None
        if self.extension is not None:
            e = self.extension
            params = {**e.parameters, "model_parameters": e.model_parameters} if e.model_parameters else dict(e.parameters)
            if e.beyond_range:
                params["beyond_stated_range"] = dict(e.beyond_range)
            ext = {"causes": list(e.causes), "parameters": params,
                   "residual_rms_arcsec": e.residual_rms_arcsec, "gain": e.gain,
                   "holdout_gain": e.holdout_gain}
        return {"cause": self.cause,
                "findings": [{"cause": f.cause, "score": f.score, "evidence": f.evidence}
                             for f in self.findings],
                "baseline": {"residual_rms_arcsec": self.residual_rms_arcsec,
                             "residual_pp_arcsec": self.residual_pp_arcsec},
                "extension": ext,
                "notes": list(self.notes)}   # input repairs (warnings), causes not reported, residual left


LINE_TABLE = 6    # strongest residual lines per table (before, after) split by direction


def holdout_split(records, groups) -> tuple[list[int], list[int]]:
    """(fit indices, held-out indices) by the module's hold-out rule."""
    n = len(records)
    order = list(dict.fromkeys(groups))
    if n == 1:
        return [0], []
    if len(order) == 1:
        return list(range(n - 1)), [n - 1]
    if len(order) >= 3:
        tq = {g: np.median([abs(records[k].torque_Nm) for k in range(n) if groups[k] == g]) for g in order}
        ranked = sorted(order, key=lambda g: (tq[g], order.index(g)))
        hold = ranked[len(ranked) // 2]
    else:
        hold = order[-1]
    return [k for k in range(n) if groups[k] != hold], [k for k in range(n) if groups[k] == hold]


def _feature_orders(summaries, max_order: int, max_count: int = 24) -> tuple[int, ...]:
    ks = {1, 2}
    for s in summaries:
        for k, a in sorted(zip(s.orders, s.line_arcsec), key=lambda t: -t[1])[:8]:
            if k <= max_order:
                ks.add(int(k))
    return tuple(sorted(ks))[:max_count]


def diagnose(case, stiffness, records: list[BenchRecord], te_model: TEModel = quasi_static_te, *,
             points_per_rev: int | None = None, p_enter: float = 1e-3, p_line: float = 1e-3,
             max_nfev: int = 8, holdout: bool = True, holdout_records: tuple[int, ...] | None = None,
             workers: int | None = None) -> Diagnosis:
    """`holdout_records`: indices of records given to hold out (`diagnose --holdout`): never used to
    name or fit a cause, the hold-out gain is computed on exactly them; otherwise `holdout` applies
    the module's hold-out rule (those records help name the causes, never fit their parameters).
    `workers`: local processes solving the records' grids (default: the machine's cores; 1 = none).
    The records are diagnosed by torque, forward before backward, then by name and path: the result
    does not depend on the order they are given in (the fit's warm starts follow the solve order,
    and a claim that sits on the 50 % rule was seen to flip with it); the Diagnosis lists them so."""
    records = list(records)
    order = sorted(range(len(records)), key=lambda k: (round(abs(records[k].torque_Nm), 1), -records[k].direction,
                                                        records[k].name, str(records[k].path), k))
    if holdout_records is not None:
        holdout_records = tuple(order.index(int(k)) if 0 <= int(k) < len(order) else int(k)
                                for k in holdout_records)
    records = [records[k] for k in order]
    pool = process_pool(workers) if getattr(te_model, "__wrapped__", te_model) is quasi_static_te else None
    try:
        with seeding():
            return _diagnose(case, stiffness, records, te_model, pool, points_per_rev=points_per_rev,
                             p_enter=p_enter, p_line=p_line, max_nfev=max_nfev, holdout=holdout,
                             holdout_records=holdout_records)
    finally:
        if pool is not None:     # after an error, the batch's queued solves are not waited for
            pool.shutdown(cancel_futures=True)


def _diagnose(case, stiffness, records, te_model, pool, *, points_per_rev, p_enter, p_line, max_nfev, holdout,
              holdout_records) -> Diagnosis:
    records, notes = check_records(case, list(records))
    points_per_rev = default_points_per_rev(case) if points_per_rev is None else int(points_per_rev)
    notes += torque_sign_notes(records)
    groups = group_records(records)
    by_id = {c.id: c for c in registry.CAUSES}   # read now: a cause registered at runtime counts

    def te_of(c, s, idx=None):
        idx = range(len(records)) if idx is None else idx
        return simulate_records(te_model, c, s, [records[k] for k in idx], points_per_rev, pool)

    meas = [r.te_arcsec(case.ratio) for r in records]
    sim0 = te_of(case, stiffness)
    resid = [m - s for m, s in zip(meas, sim0)]
    before = remove_offsets(resid, groups)
    noise = noise_floor_arcsec(records, before)
    max_order = int(min(order_limit(case), points_per_rev // 2 - 1))
    n = len(records)
    if holdout_records is not None:
        hold_idx = sorted(set(int(k) for k in holdout_records))
        fit_idx = [k for k in range(n) if k not in hold_idx]
        if not fit_idx:
            raise ValueError("every record is held out: at least one record must be fitted")
    else:
        fit_idx, hold_idx = holdout_split(records, groups) if holdout else (list(range(n)), [])
    named = fit_idx if holdout_records is not None else list(range(n))
    lib = _library(case, stiffness, records, groups, resid, sim0, te_of, by_id, max_order)
    rows = _rows_of(lib.fmaps, named)
    result = match(lib.y[rows], lib.w[rows], offset_columns(lib.fmaps, groups, named),
                   [CauseColumns(c.cause, c.X[rows], c.V) for c in lib.name_cols], p_enter=p_enter)
    lines = _significant_lines(records, before, max_order, p_line)
    summ = {s.cause: s for s in lib.summaries}

    extension, after, dropped = None, None, []
    if result.selected:
        # the fit's re-taken Jacobian columns, one batch on the workers (no pool: nothing to do)
        def prefetch(models, idx, lazy=False):
            return prefetch_models(models, [records[k] for k in idx], points_per_rev, pool, lazy)
        def seed(columns, idx):
            seed_tangents(case, stiffness, [records[k] for k in idx], points_per_rev, columns)
        run = Run(case, stiffness, records, groups, meas, te_of, te_model, lib.fmaps, lib.w, noise, prefetch, seed)
        extension, after, ext_notes, dropped = extend(run, [by_id[s.cause] for s in result.selected],
                                                      {c.cause: c for c in lib.fit_cols}, fit_idx, hold_idx,
                                                      max_nfev)
        notes += ext_notes
    beyond = (extension.beyond_range or {}) if extension is not None else {}
    findings = _findings(result, lambda s: by_id[s.cause].evidence(
        Evidence(s, case, tuple(records[k] for k in named), tuple(groups[k] for k in named),
                 tuple(before[k] for k in named), summ[s.cause], stiffness))
        + (f" Held at its bound: {beyond[s.cause]}; the rest is unexplained." if s.cause in beyond else ""),
        set(dropped))
    notes += unexplained(case, records, groups, after if after is not None else before, noise,
                         explained=extension is not None)
    notes += gap_shape_notes(records, groups, meas, sim0, after if after is not None else before, noise)
    shifts = frame_shifts(case, records, groups, before, max_order)
    notes += frame_notes(shifts)
    line_dirs = _line_directions(case, records, groups, before, after, noise)
    return Diagnosis(findings[0].cause if findings else None, tuple(findings), rms(before),
                     max(float(np.ptp(r)) for r in before), extension, tuple(records), tuple(groups),
                     tuple(meas), tuple(sim0), tuple(before), tuple(after) if after is not None else None,
                     tuple(lines), lib.summaries, tuple(notes), noise, line_dirs, shifts)


def _line_directions(case, records, groups, before, after, noise) -> dict | None:
    """The strongest residual lines before and after the extension (both sets of orders in both
    tables), each split into its common and reversing parts (directions.py); None when no group
    holds both directions at a torque."""
    orders = set(strongest_lines(case, records, before, noise, LINE_TABLE))
    if after is not None:
        orders |= set(strongest_lines(case, records, after, noise, LINE_TABLE))
    orders = tuple(sorted(orders))
    split_before = direction_split(records, groups, before, orders)
    if not split_before:
        return None
    return {"before": directions.table(case, split_before),
            "after": directions.table(case, direction_split(records, groups, after, orders)) if after is not None else None}


def _rows_of(fmaps, idx) -> np.ndarray:
    """Rows of the stacked features (features.FeatureMap) that belong to records idx."""
    starts = np.r_[0, np.cumsum([fm.size for fm in fmaps])]
    return np.concatenate([np.arange(starts[k], starts[k + 1]) for k in idx])


@dataclass(frozen=True)
class _Library:
    """The signature library on these records, in feature space (features.py)."""
    summaries: tuple[SignatureSummary, ...]
    fmaps: list[FeatureMap]
    y: np.ndarray                    # residual features, stacked over the records
    w: np.ndarray                    # their weights, 1 / noise std
    name_cols: list[CauseColumns]    # columns that name each cause (fit.match)
    fit_cols: list[CauseColumns]     # columns the extension fits


def _library(case, stiffness, records, groups, resid, sim0, te_of, by_id, max_order) -> _Library:
    # one model at a time: the unit models batched on the workers (simulate.prefetch_models, as the
    # fit's Jacobian columns are) took the real records 56 s instead of 50 (CPU 96 s against 86): their
    # solves start from the base model's states instead of the previous column's; not adopted
    raw_cols = {c: signature_columns(te_of, case, stiffness, cause, sim0) for c, cause in by_id.items()}
    summaries = tuple(summarise(c, records, raw_cols[c], max_order) for c in by_id)
    orders = _feature_orders(summaries, max_order)
    fmaps = [FeatureMap(r.output_angle_deg, orders) for r in records]
    y = np.concatenate([fm.apply(res) for fm, res in zip(fmaps, resid)])
    w = 1.0 / np.concatenate([fm.noise_std(res) for fm, res in zip(fmaps, resid)])
    dc_rows = np.r_[0, np.cumsum([fm.size for fm in fmaps])[:-1]]
    name_cols, fit_cols = [], []
    for cause in by_id.values():
        Xraw = np.vstack([np.column_stack([fm.apply(c[:, j]) for j in range(c.shape[1])])
                          for fm, c in zip(fmaps, raw_cols[cause.id])])
        naming, fitting = _cause_columns(cause, Xraw, w, dc_rows)
        name_cols.append(naming)
        fit_cols.append(fitting)
    return _Library(summaries, fmaps, y, w, name_cols, fit_cols)


def _significant_lines(records, before, max_order, p_line) -> list[tuple[Line, ...]]:
    lines = []
    for rec, res in zip(records, before):
        spec = spectrum_of(rec.output_angle_deg, res)
        top = min(max_order, int(spec.order[-1]))
        lines.append(tuple(l for l in test_lines(spec, range(1, top + 1), p_line) if l.significant))
    return lines


def _findings(result: MatchResult, evidence, dropped=frozenset()) -> list[Finding]:
    """One finding per selected cause the extension kept (its evidence), then the alternatives the
    records cannot separate from it, ranked just below; highest score first. A dropped cause
    (extension.py: on its bound, or below the noise floor) is no finding, nor are its alternatives."""
    kept = [s for s in result.selected if s.cause not in dropped]
    findings = [Finding(s.cause, round(s.share, 4), evidence(s), s.p_value) for s in kept]
    for s in kept:
        for alt, d_alt in s.alternatives:
            if alt not in {f.cause for f in findings} and alt not in dropped:
                findings.append(Finding(alt, round(d_alt / result.chi2_offsets, 4) * 0.999,
                                        f"fits the same evidence as {s.cause} (explains "
                                        f"{d_alt / max(s.dchi2, 1e-300):.0%} as much); the records "
                                        f"cannot separate the two, ranked below it.", s.p_value))
    findings.sort(key=lambda f: -f.score)
    return findings


def _cause_columns(cause, Xraw, w, dc_rows) -> tuple[CauseColumns, CauseColumns]:
    """(columns that name the cause, columns the extension fits) from the raw feature columns.

    They differ for a `dc_even` cause (causes/base.py): its mean-TE response depends on |p| only,
    which no linear column can carry, so it is named on its order lines alone (mean rows zeroed:
    a mean shift never names it, and cannot steal a lost-motion gap from `backlash`); the fit keeps
    the full secant columns as a first Jacobian (the model in the loop gives the true mean shift).
    Limit: its own mean shift may then also be named as `backlash` (second finding)."""
    Xr, V = reduce_columns(Xraw * w[:, None])
    fitting = CauseColumns(cause.id, Xr / w[:, None], V)
    if not cause.dc_even:
        return fitting, fitting
    lines = Xraw.copy()
    lines[dc_rows] = 0.0
    Xn, Vn = reduce_columns(lines * w[:, None])
    return CauseColumns(cause.id, Xn / w[:, None], Vn), fitting
