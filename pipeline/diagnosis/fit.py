"""Naming causes: weighted least squares of the residual's features on the signature library.

Model: y = X_off b_off + sum_c X_c b_c + noise, y the stacked record features of the residual
(features.FeatureMap), X_off one column per encoder-zero group (a constant offset: DC feature 1 on
its records), X_c the model's signature columns of cause c (unit parameter), rows weighted by
1 / noise std of the record's own floor. Causes enter by forward selection: at each step the
candidate with the largest drop in chi^2 is tested with a partial F-test,
F = (dchi2 / q_c) / s^2, s^2 the residual variance per weighted feature of the model with it, taken
robustly: median(r_w^2) / 0.455 (the median of chi^2 with 1 dof), not chi2_full / (n - p). Why: on a
real bench the residual holds lines no registered cause makes (the real records: 156x, 78x, 39x up
to 9 arcsec); the mean of r_w^2 counts them as noise and would hide a well-determined cause of a
few arcsec (a 3x line 46 sigma above its floor failed at p = 0.3), while the median reads the floor
of the many features those lines do not touch. Like the F-test it stays valid when the floor
estimate is off by a common factor. A cause enters when p < p_enter (Bonferroni over the
candidates still out). A cause
must also explain at least `min_share` of the weighted residual power left at its step (the
power the causes already named leave: a 1x line of 60 arcsec must not hide a 5 arcsec cause; its
effect size in arcsec is judged by the extension against the records' noise floor).
Where another candidate explains the same features nearly as well (within `ambiguity` of its
dchi2) both are reported: the evidence cannot separate them (e.g. two zp x sources).
Limits: linear in the parameters (unit-size signatures); diagnose.py refines on the full model.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy import stats


@dataclass(frozen=True)
class CauseColumns:
    cause: str
    X: np.ndarray               # (n_features, q) signature columns, parameter units
    V: np.ndarray               # (n_params, q) maps reduced coefficients to model parameters


@dataclass(frozen=True)
class Selection:
    cause: str
    coef: np.ndarray            # reduced coefficients
    dchi2: float                # chi2 increase when the cause is removed from the final model
    share: float                # share of the post-offset weighted residual power it explains
    p_value: float              # partial F-test in the final model
    alternatives: tuple = ()    # (cause, dchi2 when substituted) that fit nearly as well


@dataclass(frozen=True)
class MatchResult:
    selected: tuple[Selection, ...]
    chi2_offsets: float         # weighted residual power after the zero offsets only
    chi2_final: float
    dof: int
    offsets: np.ndarray
    coef: dict = field(default_factory=dict)        # cause -> reduced coefficients
    cov: dict = field(default_factory=dict)         # cause -> reduced covariance (scaled)


def reduce_columns(X: np.ndarray, rel_tol: float = 1e-3) -> tuple[np.ndarray, np.ndarray]:
    """Keep the identifiable combinations of a cause's raw columns (SVD); returns (X V, V)."""
    if X.shape[1] == 1:
        return X, np.eye(1)
    _, s, vt = np.linalg.svd(X, full_matrices=False)
    keep = s > rel_tol * s[0] if s[0] > 0 else np.zeros_like(s, bool)
    V = vt[keep].T
    return X @ V, V


_CHI2_1_MEDIAN = float(stats.chi2.median(1))


def _wls(y, X):
    """(coefficients, residual) of the least-squares fit of y on X."""
    if X.shape[1] == 0:
        return np.zeros(0), y
    coef, *_ = np.linalg.lstsq(X, y, rcond=None)
    return coef, y - X @ coef


def robust_variance(r: np.ndarray) -> float:
    """Residual variance per feature from the median squared residual (module docstring): lines
    outside the model do not inflate it."""
    return float(np.median(r ** 2)) / _CHI2_1_MEDIAN


def match(y: np.ndarray, w: np.ndarray, X_off: np.ndarray, causes: list[CauseColumns],
          p_enter: float = 1e-3, min_share: float = 0.02, ambiguity: float = 0.9) -> MatchResult:
    """Forward selection of causes (module docstring); y, X rows are weighted here by w."""
    yw, Ow = y * w, X_off * w[:, None]
    cols = {c.cause: c.X * w[:, None] for c in causes if c.X.shape[1] > 0 and np.any(c.X)}
    n = len(y)

    def fit_of(names):
        return _wls(yw, np.column_stack([Ow] + [cols[c] for c in names]) if names else Ow)

    def chi2_of(names):
        coef, r = fit_of(names)
        return coef, float(r @ r)

    _, chi2_off = chi2_of([])
    chosen: list[str] = []
    while True:
        out = [c for c in cols if c not in chosen]
        if not out:
            break
        _, chi2_now = chi2_of(chosen)
        resid = {c: fit_of(chosen + [c])[1] for c in out}
        trials = {c: float(r @ r) for c, r in resid.items()}
        best = min(trials, key=trials.get)
        q = cols[best].shape[1]
        p_full = Ow.shape[1] + sum(cols[c].shape[1] for c in chosen) + q
        dof = max(n - p_full, 1)
        s2 = robust_variance(resid[best])
        F = ((chi2_now - trials[best]) / q) / max(s2, 1e-300)
        p = stats.f.sf(F, q, dof) * len(out)
        if p >= p_enter or (chi2_now - trials[best]) < min_share * chi2_now:
            break
        chosen.append(best)

    coef_all, r_fin = fit_of(chosen)
    chi2_fin = float(r_fin @ r_fin)
    p_tot = Ow.shape[1] + sum(cols[c].shape[1] for c in chosen)
    dof = max(n - p_tot, 1)
    Xfull = np.column_stack([Ow] + [cols[c] for c in chosen]) if chosen else Ow
    s2 = robust_variance(r_fin)    # the entry test's variance: a cause's final p is read alike
    cov_all = s2 * np.linalg.pinv(Xfull.T @ Xfull)
    coef, cov, sel = {}, {}, []
    k = Ow.shape[1]
    for c in chosen:
        q = cols[c].shape[1]
        coef[c], cov[c] = coef_all[k:k + q], cov_all[k:k + q, k:k + q]
        k += q
        others = [o for o in chosen if o != c]
        chi2_without = chi2_of(others)[1]
        dchi2 = chi2_without - chi2_fin
        F = (dchi2 / q) / max(s2, 1e-300)
        alts = []
        for o in cols:
            if o in chosen:
                continue
            d_alt = chi2_without - chi2_of(others + [o])[1]
            if d_alt >= ambiguity * dchi2:
                alts.append((o, float(d_alt)))
        sel.append(Selection(c, coef[c], float(dchi2), float(dchi2 / chi2_off) if chi2_off > 0 else 0.0,
                             float(stats.f.sf(F, q, dof)), tuple(alts)))
    sel.sort(key=lambda s: -s.dchi2)
    return MatchResult(tuple(sel), float(chi2_off), float(chi2_fin), int(dof),
                       coef_all[:Ow.shape[1]], coef, cov)
