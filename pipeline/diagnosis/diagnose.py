"""Diagnosis of bench records against the model: residual, causes, extension, gain.

diagnose(case, stiffness, records) runs blind on the records (conditions read from each record):
  1. simulate each record (simulate.py), residual = measured TE - simulated TE;
  2. one free offset per encoder-zero group (zeros.py) is removed in every RMS reported;
  3. signature library (signatures.py) of every registered cause (causes/, `causes.CAUSES`, read
     at each call) -> features (features.py) -> forward selection (fit.py); each finding's text
     is its cause's `evidence`;
  4. extension: the named causes' parameters are fitted by scipy.optimize.least_squares with the
     model in the loop (Jacobian from the library, a linearisation the solver only uses for its
     steps), the records re-simulated; gain = 1 - rms_after / rms_before on the fitted records,
     holdout_gain the same on the held-out ones; 95 % confidence intervals from the final
     Jacobian and the scaled residual variance (linearised; t quantile on the residual dof);
     each cause's `report` turns its fitted model parameters into the reported ones, and fitted
     values outside the cause's physical bounds are listed (Extension.outside_bounds).
Hold-out rule: with >= 3 zero groups the group of median |torque| (an interpolation check), with 2
the last group given, with 1 group of several records the last record, with 1 record none.
Limits: quasi-static model (no speed effects); constant torque per record; findings rank the
evidence the records hold (e.g. one torque level cannot tell wind-up from lost motion).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import optimize, stats

from dynamics.records import BenchRecord
from pipeline.diagnosis import causes as registry
from pipeline.diagnosis.causes.base import Evidence, Fitted
from pipeline.diagnosis.features import FeatureMap
from pipeline.diagnosis.fit import CauseColumns, MatchResult, match, reduce_columns
from pipeline.diagnosis.orders import spectrum_of
from pipeline.diagnosis.signatures import SignatureSummary, signature_columns, summarise
from pipeline.diagnosis.significance import Line, test_lines
from pipeline.diagnosis.simulate import TEModel, quasi_static_te, simulate_record
from pipeline.diagnosis.zeros import group_records


if __doc__:   # the causes that exist, read from the registry (None under python -OO)
    __doc__ += "Registered causes (pipeline.diagnosis.causes):\n" + registry.describe() + "\n"

REFRESH_STEP = 0.3   # forward-difference step of a re-taken Jacobian column, in library units
START_SCALES = (0.5, 0.75, 1.0, 1.5)   # coarse scan of a threshold cause's linear start


@dataclass(frozen=True)
class Finding:
    cause: str
    score: float       # share of the post-offset weighted residual power the cause explains
    evidence: str
    p_value: float = 1.0


@dataclass(frozen=True)
class Extension:
    causes: tuple[str, ...]
    parameters: dict
    residual_rms_arcsec: float       # after, fitted records
    rms_before_arcsec: float         # before, fitted records
    gain: float
    holdout_gain: float | None
    fitted: tuple[str, ...]
    held_out: tuple[str, ...]
    outside_bounds: tuple[str, ...] = ()   # fitted parameters outside their physical range


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
    notes: tuple[str, ...] = ()

    def to_json(self) -> dict:
        ext = None
        if self.extension is not None:
            e = self.extension
            ext = {"causes": list(e.causes), "parameters": e.parameters,
                   "residual_rms_arcsec": e.residual_rms_arcsec, "gain": e.gain,
                   "holdout_gain": e.holdout_gain}
        return {"cause": self.cause,
                "findings": [{"cause": f.cause, "score": f.score, "evidence": f.evidence}
                             for f in self.findings],
                "baseline": {"residual_rms_arcsec": self.residual_rms_arcsec,
                             "residual_pp_arcsec": self.residual_pp_arcsec},
                "extension": ext}


def remove_offsets(residuals, groups) -> list[np.ndarray]:
    """Subtract each zero group's least-squares offset (its mean over all its samples)."""
    out = [np.asarray(r, float).copy() for r in residuals]
    for g in set(groups):
        idx = [k for k, gg in enumerate(groups) if gg == g]
        m = np.concatenate([out[k] for k in idx]).mean()
        for k in idx:
            out[k] -= m
    return out


def rms(arrays) -> float:
    x = np.concatenate([np.asarray(a) for a in arrays]) if arrays else np.zeros(1)
    return float(np.sqrt(np.mean(x * x)))


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
             points_per_rev: int = 1024, p_enter: float = 1e-3, p_line: float = 1e-3,
             max_nfev: int = 8, holdout: bool = True) -> Diagnosis:
    records = list(records)
    groups = group_records(records)
    by_id = {c.id: c for c in registry.CAUSES}   # read now: a cause registered at runtime counts

    def te_of(c, s, idx=None):
        idx = range(len(records)) if idx is None else idx
        return [simulate_record(te_model, c, s, records[k], points_per_rev) for k in idx]

    meas = [r.te_arcsec(case.ratio) for r in records]
    sim0 = te_of(case, stiffness)
    resid = [m - s for m, s in zip(meas, sim0)]
    before = remove_offsets(resid, groups)
    max_order = int(min(4 * case.cycloid.zp, points_per_rev // 2 - 1))
    lib = _library(case, stiffness, records, groups, resid, sim0, te_of, by_id, max_order)
    result = match(lib.y, lib.w, _offset_columns(lib.fmaps, groups, range(len(records))), lib.name_cols,
                   p_enter=p_enter)
    lines = _significant_lines(records, before, max_order, p_line)
    summ = {s.cause: s for s in lib.summaries}
    findings = _findings(result, lambda s: by_id[s.cause].evidence(
        Evidence(s, case, tuple(records), tuple(groups), tuple(before), summ[s.cause])))

    extension, after = None, None
    if result.selected:
        run = _Run(case, stiffness, records, groups, meas, te_of, te_model, lib.fmaps, lib.w)
        extension, after = _extend(run, [by_id[s.cause] for s in result.selected],
                                   {c.cause: c for c in lib.fit_cols}, holdout, max_nfev)
    return Diagnosis(findings[0].cause if findings else None, tuple(findings), rms(before),
                     max(float(np.ptp(r)) for r in before), extension, tuple(records), tuple(groups),
                     tuple(meas), tuple(sim0), tuple(before), tuple(after) if after is not None else None,
                     tuple(lines), lib.summaries, ())


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


def _offset_columns(fmaps, groups, idx) -> np.ndarray:
    """One column per zero group of records idx: 1 on each record's mean feature (stacked rows)."""
    idx = list(idx)
    gids = list(dict.fromkeys(groups[k] for k in idx))
    X = np.zeros((sum(fmaps[k].size for k in idx), len(gids)))
    pos = 0
    for k in idx:
        X[pos, gids.index(groups[k])] = 1.0
        pos += fmaps[k].size
    return X


def _significant_lines(records, before, max_order, p_line) -> list[tuple[Line, ...]]:
    lines = []
    for rec, res in zip(records, before):
        spec = spectrum_of(rec.output_angle_deg, res)
        top = min(max_order, int(spec.order[-1]))
        lines.append(tuple(l for l in test_lines(spec, range(1, top + 1), p_line) if l.significant))
    return lines


def _findings(result: MatchResult, evidence) -> list[Finding]:
    """One finding per selected cause (its evidence), then the alternatives the records cannot
    separate from it, ranked just below; highest score first."""
    findings = [Finding(s.cause, round(s.share, 4), evidence(s), s.p_value) for s in result.selected]
    for s in result.selected:
        for alt, d_alt in s.alternatives:
            if alt not in {f.cause for f in findings}:
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


def _apply(case, stiffness, chosen, x, cols):
    """The chosen causes (objects) applied at reduced coefficients x (cols: id -> CauseColumns)."""
    k = 0
    for cause in chosen:
        V = cols[cause.id].V
        q = V.shape[1]
        case, stiffness = cause.apply(case, stiffness, V @ x[k:k + q])
        k += q
    return case, stiffness


@dataclass(frozen=True)
class _Run:
    """What the extension needs of one diagnosis run."""
    case: object
    stiffness: object
    records: list
    groups: list
    meas: list                       # measured TE per record [arcsec]
    te_of: object                    # (case, stiffness, idx=None) -> simulated TE per record
    te_model: object
    fmaps: list
    w: np.ndarray


def _extend(run: _Run, chosen, cols, holdout: bool, max_nfev: int):
    """Fit the chosen causes with the model in the loop; (Extension, residuals after)."""
    n = len(run.records)
    fit_idx, hold_idx = holdout_split(run.records, run.groups) if holdout else (list(range(n)), [])
    starts = np.r_[0, np.cumsum([fm.size for fm in run.fmaps])]
    rows = np.concatenate([np.arange(starts[k], starts[k + 1]) for k in fit_idx])
    X_off, wf = _offset_columns(run.fmaps, run.groups, fit_idx), run.w[rows]
    nz = sum(cols[c.id].X.shape[1] for c in chosen)
    J = -np.column_stack([cols[c.id].X[rows] for c in chosen] + [X_off]) * wf[:, None]

    def features(c, s):
        sims = run.te_of(c, s, fit_idx)
        return np.concatenate([run.fmaps[k].apply(run.meas[k] - sim) for k, sim in zip(fit_idx, sims)]), sims

    def fun(x):
        yy, _ = features(*_apply(run.case, run.stiffness, chosen, x[:nz], cols))
        return (yy - X_off @ x[nz:]) * wf

    y0, sims0 = features(run.case, run.stiffness)
    x0, *_ = np.linalg.lstsq(-J, y0 * wf, rcond=None)    # linear start: the library's solution
    spans = _refreshed_columns(chosen, cols)
    if spans:   # a threshold response: start from the best of a coarse scan of its size
        x0 = min((_scaled(x0, spans, f) for f in START_SCALES), key=lambda x: float(np.sum(fun(x) ** 2)))
    try:
        x = optimize.least_squares(fun, x0, jac=_jacobian(fun, J, spans), x_scale="jac", max_nfev=max_nfev,
                                   method="lm" if len(rows) > len(x0) else "trf").x
    except ValueError:   # a step left the valid geometry (CaseError): keep the linear start
        x = x0
    sims_after = run.te_of(*_apply(run.case, run.stiffness, chosen, x[:nz], cols))
    after = remove_offsets([m - s for m, s in zip(run.meas, sims_after)], run.groups)
    rms_b, rms_a, hold_gain = _gains(run, fit_idx, hold_idx, sims0, sims_after)
    cov, tq = _covariance(fun(x), J)
    params, outside = _parameters(run.case, run.stiffness, chosen, cols, x[:nz], cov[:nz, :nz], tq,
                                  run.te_model)
    ext = Extension(tuple(c.id for c in chosen), params, rms_a, rms_b,
                    float(1.0 - rms_a / rms_b) if rms_b > 0 else 0.0, hold_gain,
                    tuple(run.records[k].name for k in fit_idx), tuple(run.records[k].name for k in hold_idx),
                    outside)
    return ext, after


def _refreshed_columns(chosen, cols) -> list[tuple[int, int, float]]:
    """(first column, count, step) of each `dc_even` cause's Jacobian columns. The library's
    Jacobian stays fixed for causes near linear at their size; a threshold response's columns are
    re-taken by the model at every iterate (forward differences of REFRESH_STEP x its unit), so
    the steps follow the real slope."""
    spans, k = [], 0
    for c in chosen:
        q = cols[c.id].X.shape[1]
        if c.dc_even:
            spans.append((k, q, REFRESH_STEP * c.unit_size))
        k += q
    return spans


def _scaled(x0, spans, f):
    x = x0.copy()
    for k0, q, _ in spans:
        x[k0:k0 + q] *= f
    return x


def _jacobian(fun, J, spans):
    def jac(x):
        if not spans:
            return J
        Jx, r0 = J.copy(), fun(x)
        for k0, q, h in spans:
            for j in range(k0, k0 + q):
                dx = np.zeros_like(x)
                dx[j] = h
                Jx[:, j] = (fun(x + dx) - r0) / h
        return Jx
    return jac


def _gains(run: _Run, fit_idx, hold_idx, sims0, sims_after) -> tuple[float, float, float | None]:
    """(rms before, rms after) on the fitted records, and the hold-out gain (None without)."""
    meas, groups = run.meas, run.groups
    fit_groups = [groups[k] for k in fit_idx]
    rms_b = rms(remove_offsets([meas[k] - s for k, s in zip(fit_idx, sims0)], fit_groups))
    rms_a = rms(remove_offsets([meas[k] - sims_after[k] for k in fit_idx], fit_groups))
    if not hold_idx:
        return rms_b, rms_a, None
    hg = [groups[k] for k in hold_idx]
    sims_h0 = run.te_of(run.case, run.stiffness, hold_idx)
    rb = rms(remove_offsets([meas[k] - s for k, s in zip(hold_idx, sims_h0)], hg))
    ra = rms(remove_offsets([meas[k] - sims_after[k] for k in hold_idx], hg))
    return rms_b, rms_a, float(1.0 - ra / rb) if rb > 0 else None


def _covariance(r_final, J) -> tuple[np.ndarray, float]:
    """Linearised parameter covariance (scaled residual variance) and the 95 % t quantile."""
    dof = max(len(r_final) - J.shape[1], 1)
    s2 = float(r_final @ r_final) / dof
    return s2 * np.linalg.pinv(J.T @ J), float(stats.t.ppf(0.975, dof))


def _parameters(case, stiffness, chosen, cols, z, cov_z, tq, te_model) -> tuple[dict, tuple[str, ...]]:
    """Reported parameters of each chosen cause (its `report`) from the reduced coefficients z,
    and the fitted model parameters that left their physical bounds (`Cause.out_of_bounds`)."""
    out, outside, k = {}, [], 0
    for cause in chosen:
        V = cols[cause.id].V
        q = V.shape[1]
        p = V @ z[k:k + q]
        cp = V @ cov_z[k:k + q, k:k + q] @ V.T
        k += q
        out.update(cause.report(Fitted(p, cp, tq, case, stiffness, te_model)))
        outside.extend(f"{cause.id}: {t}" for t in cause.out_of_bounds(case, p))
    return out, tuple(outside)
