"""Diagnosis of bench records against the model: residual, causes, extension, gain.

diagnose(case, stiffness, records) runs blind on the records (conditions read from each record):
  1. simulate each record (simulate.py), residual = measured TE - simulated TE;
  2. one free offset per encoder-zero group (zeros.py) is removed in every RMS reported;
  3. signature library (signatures.py) -> features (features.py) -> forward selection (fit.py);
  4. extension: the named causes' parameters are fitted by scipy.optimize.least_squares with the
     model in the loop (Jacobian from the library, a linearisation the solver only uses for its
     steps), the records re-simulated; gain = 1 - rms_after / rms_before on the fitted records,
     holdout_gain the same on the held-out ones; 95 % confidence intervals from the final
     Jacobian and the scaled residual variance (linearised; t quantile on the residual dof).
Hold-out rule: with >= 3 zero groups the group of median |torque| (an interpolation check), with 2
the last group given, with 1 group of several records the last record, with 1 record none.
Limits: quasi-static model (no speed effects); constant torque per record; findings rank the
evidence the records hold (e.g. one torque level cannot tell wind-up from lost motion).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import optimize, stats

from pipeline.diagnosis.features import FeatureMap
from pipeline.diagnosis.fit import CauseColumns, MatchResult, match, reduce_columns
from pipeline.diagnosis.orders import spectrum_of
from pipeline.diagnosis.signatures import (SignatureSummary, cause_specs, crank_pattern_um,
                                           signature_columns,
                                           summarise)
from pipeline.diagnosis.significance import Line, test_lines
from pipeline.diagnosis.simulate import TEModel, quasi_static_te, simulate_record
from pipeline.diagnosis.zeros import group_records
from pipeline.records import BenchRecord


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
    ratio = case.ratio
    groups = group_records(records)
    specs = cause_specs(case)
    notes = []

    def te_of(c, s, idx=None):
        idx = range(len(records)) if idx is None else idx
        return [simulate_record(te_model, c, s, records[k], points_per_rev) for k in idx]

    meas = [r.te_arcsec(ratio) for r in records]
    sim0 = te_of(case, stiffness)
    resid = [m - s for m, s in zip(meas, sim0)]
    before = remove_offsets(resid, groups)
    pp = max(float(np.ptp(r)) for r in before)

    # library and its features
    raw_cols = {sp.cause: signature_columns(te_of, case, stiffness, sp, sim0) for sp in specs}
    max_order = int(min(4 * case.cycloid.zp, points_per_rev // 2 - 1))
    summaries = tuple(summarise(sp, records, raw_cols[sp.cause], max_order) for sp in specs)
    orders = _feature_orders(summaries, max_order)
    fmaps = [FeatureMap(r.output_angle_deg, orders) for r in records]
    y = np.concatenate([fm.apply(res) for fm, res in zip(fmaps, resid)])
    w = 1.0 / np.concatenate([fm.noise_std(res) for fm, res in zip(fmaps, resid)])
    gids = list(dict.fromkeys(groups))
    X_off = np.zeros((len(y), len(gids)))
    pos = 0
    for k, fm in enumerate(fmaps):
        X_off[pos, gids.index(groups[k])] = 1.0
        pos += fm.size
    dc_rows = np.r_[0, np.cumsum([fm.size for fm in fmaps])[:-1]]
    name_cols, fit_cols = [], []
    for sp in specs:
        Xraw = np.vstack([np.column_stack([fm.apply(c[:, j]) for j in range(c.shape[1])])
                          for fm, c in zip(fmaps, raw_cols[sp.cause])])
        naming, fitting = _cause_columns(sp, Xraw, w, dc_rows)
        name_cols.append(naming)
        fit_cols.append(fitting)
    result = match(y, w, X_off, name_cols, p_enter=p_enter)

    lines = []
    for rec, res in zip(records, before):
        spec = spectrum_of(rec.output_angle_deg, res)
        top = min(max_order, int(spec.order[-1]))
        lines.append(tuple(l for l in test_lines(spec, range(1, top + 1), p_line) if l.significant))

    findings = [Finding(s.cause, round(s.share, 4),
                        _evidence(s, case, records, groups, before, lines, summaries, result), s.p_value)
                for s in result.selected]
    for s in result.selected:
        for alt, d_alt in s.alternatives:
            if alt not in {f.cause for f in findings}:
                findings.append(Finding(alt, round(d_alt / result.chi2_offsets, 4) * 0.999,
                                        f"fits the same evidence as {s.cause} (explains "
                                        f"{d_alt / max(s.dchi2, 1e-300):.0%} as much); the records "
                                        f"cannot separate the two, ranked below it.", s.p_value))
    findings.sort(key=lambda f: -f.score)

    extension, after = None, None
    if result.selected:
        extension, after = _extend(case, stiffness, records, groups, meas, te_of, fmaps, w, specs,
                                   fit_cols, result, holdout, max_nfev, te_model)
    return Diagnosis(findings[0].cause if findings else None, tuple(findings), rms(before), pp,
                     extension, tuple(records), tuple(groups), tuple(meas), tuple(sim0),
                     tuple(before), tuple(after) if after is not None else None, tuple(lines),
                     summaries, tuple(notes))


def _cause_columns(spec, Xraw, w, dc_rows) -> tuple[CauseColumns, CauseColumns]:
    """(columns that name the cause, columns the extension fits) from the raw feature columns.

    They differ for a `dc_even` cause (signatures.py): its mean-TE response depends on |p| only,
    which no linear column can carry, so it is named on its order lines alone (mean rows zeroed:
    a mean shift never names it, and cannot steal a lost-motion gap from `backlash`); the fit keeps
    the full secant columns as a first Jacobian (the model in the loop gives the true mean shift).
    Limit: its own mean shift may then also be named as `backlash` (second finding)."""
    Xr, V = reduce_columns(Xraw * w[:, None])
    fitting = CauseColumns(spec.cause, Xr / w[:, None], V)
    if not spec.dc_even:
        return fitting, fitting
    lines = Xraw.copy()
    lines[dc_rows] = 0.0
    Xn, Vn = reduce_columns(lines * w[:, None])
    return CauseColumns(spec.cause, Xn / w[:, None], Vn), fitting


def _apply(case, stiffness, specs, chosen, x, cause_cols):
    V = {c.cause: c.V for c in cause_cols}
    k = 0
    for c in chosen:
        sp = next(s for s in specs if s.cause == c)
        q = V[c].shape[1]
        case, stiffness = sp.apply(case, stiffness, V[c] @ x[k:k + q])
        k += q
    return case, stiffness


def _extend(case, stiffness, records, groups, meas, te_of, fmaps, w, specs, cause_cols,
            result: MatchResult, holdout: bool, max_nfev: int, te_model):
    chosen = [s.cause for s in result.selected]
    fit_idx, hold_idx = holdout_split(records, groups) if holdout else (list(range(len(records))), [])
    cols = {c.cause: c for c in cause_cols}
    sizes = [fm.size for fm in fmaps]
    starts = np.r_[0, np.cumsum(sizes)]
    rows = np.concatenate([np.arange(starts[k], starts[k + 1]) for k in fit_idx])
    fit_groups = [groups[k] for k in fit_idx]
    gids = list(dict.fromkeys(fit_groups))
    X_off = np.zeros((len(rows), len(gids)))
    pos = 0
    for k in fit_idx:
        X_off[pos, gids.index(groups[k])] = 1.0
        pos += fmaps[k].size
    wf = w[rows]
    Xc = np.column_stack([cols[c].X[rows] for c in chosen])
    nz = Xc.shape[1]
    J = -np.column_stack([Xc, X_off]) * wf[:, None]

    def features(c, s):
        sims = te_of(c, s, fit_idx)
        return np.concatenate([fmaps[k].apply(meas[k] - sim) for k, sim in zip(fit_idx, sims)]), sims

    y0, sims0 = features(case, stiffness)
    # linear start: the library solution on the fit records
    x0, *_ = np.linalg.lstsq(-J, y0 * wf, rcond=None)
    cache = {}

    def fun(x):
        c2, s2 = _apply(case, stiffness, specs, chosen, x[:nz], cause_cols)
        yy, sims = features(c2, s2)
        cache[tuple(np.round(x, 12))] = sims
        return (yy - X_off @ x[nz:]) * wf

    # Jacobian: the library's, fixed, for causes near linear at their size; the columns of a
    # `dc_even` cause (a threshold response, signatures.py) are re-taken by the model at every
    # iterate (forward differences of REFRESH_STEP x its unit), so the steps follow the real slope
    spans, k = [], 0
    for c in chosen:
        q = cols[c].X.shape[1]
        sp = next(t for t in specs if t.cause == c)
        if sp.dc_even:
            spans.append((k, q, REFRESH_STEP * sp.unit))
        k += q

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

    if spans:   # a threshold response: start from the best of a coarse scan of its size
        def scaled(f):
            x = x0.copy()
            for k0, q, _ in spans:
                x[k0:k0 + q] *= f
            return x
        x0 = min((scaled(f) for f in START_SCALES), key=lambda x: float(np.sum(fun(x) ** 2)))

    try:
        sol = optimize.least_squares(fun, x0, jac=jac, method="lm" if len(rows) > len(x0) else "trf",
                                     max_nfev=max_nfev, x_scale="jac")
        x = sol.x
    except ValueError:   # a step left the valid geometry (CaseError): keep the linear start
        x = x0
    c_fit, s_fit = _apply(case, stiffness, specs, chosen, x[:nz], cause_cols)
    sims_after = te_of(c_fit, s_fit)
    after = remove_offsets([m - s for m, s in zip(meas, sims_after)], groups)
    before_fit = remove_offsets([meas[k] - s for k, s in zip(fit_idx, sims0)], fit_groups)
    after_fit = remove_offsets([meas[k] - sims_after[k] for k in fit_idx], fit_groups)
    rms_b, rms_a = rms(before_fit), rms(after_fit)
    hold_gain = None
    if hold_idx:
        hg = [groups[k] for k in hold_idx]
        sims_h0 = te_of(case, stiffness, hold_idx)
        rb = rms(remove_offsets([meas[k] - s for k, s in zip(hold_idx, sims_h0)], hg))
        ra = rms(remove_offsets([meas[k] - sims_after[k] for k in hold_idx], hg))
        hold_gain = float(1.0 - ra / rb) if rb > 0 else None

    # confidence intervals (linearised)
    r_final = fun(x)
    dof = max(len(r_final) - len(x), 1)
    s2 = float(r_final @ r_final) / dof
    cov = s2 * np.linalg.pinv(J.T @ J)
    tq = float(stats.t.ppf(0.975, dof))
    params = _parameters(case, stiffness, chosen, cause_cols, x[:nz], cov[:nz, :nz], tq, te_model)
    ext = Extension(tuple(chosen), params, rms_a, rms_b, float(1.0 - rms_a / rms_b) if rms_b > 0 else 0.0,
                    hold_gain, tuple(records[k].name for k in fit_idx),
                    tuple(records[k].name for k in hold_idx))
    return ext, after


def backlash_arcmin_per_um(te_model, case, stiffness, n: int = 24) -> float:
    """Lost motion change per um of extra pin clearance, from the model at +-1 % rated torque."""
    from pipeline.diagnosis.signatures import _backlash
    ang = np.linspace(0.0, 360.0 * case.ratio / case.cycloid.zp, n, endpoint=False)
    c2, _ = _backlash(case, stiffness, np.array([2.0]))
    t = 0.01 * case.rated_torque_Nm
    lm = lambda c: float(np.mean(te_model(c, stiffness, ang, -t, -1)) - np.mean(te_model(c, stiffness, ang, t, 1)))  # noqa: E731
    return (lm(c2) - lm(case)) / 2.0 / 60.0


def _ci(v, sd, tq):
    return [float(v - tq * sd), float(v + tq * sd)]


def _polar(p, cp, tq) -> tuple[float, list, float, list]:
    """Magnitude and angle [deg] of (p0, p1) with linearised (delta-method) 95 % intervals."""
    m = float(np.hypot(p[0], p[1]))
    g = np.array([p[0], p[1]]) / max(m, 1e-12)                   # d m / d p
    h = np.array([-p[1], p[0]]) / max(m * m, 1e-12)              # d angle / d p
    ang = float(np.degrees(np.arctan2(p[1], p[0])))
    return (m, _ci(m, float(np.sqrt(g @ cp @ g)), tq), ang,
            _ci(ang, float(np.degrees(np.sqrt(h @ cp @ h))), tq))


def _parameters(case, stiffness, chosen, cause_cols, z, cov_z, tq, te_model) -> dict:
    V = {c.cause: c.V for c in cause_cols}
    out, k = {}, 0
    for c in chosen:
        q = V[c].shape[1]
        p = V[c] @ z[k:k + q]
        cp = V[c] @ cov_z[k:k + q, k:k + q] @ V[c].T
        sd = np.sqrt(np.maximum(np.diag(cp), 0.0))
        k += q
        if c == "output_coaxiality":
            e, e_ci, ph, ph_ci = _polar(p, cp, tq)
            out.update({"output_coaxiality_um": e, "output_coaxiality_um_ci95": e_ci,
                        "output_coaxiality_phase_deg": ph, "output_coaxiality_phase_deg_ci95": ph_ci})
        elif c == "crank_eccentricity_error":
            # p = per-crank errors of disc 1's eccentric [um]; the zp x line measures the zero-mean
            # pattern A cos(phi - 2 pi j / n) (phi: crank j at 360 j / n deg); a single journal off
            # by e on crank j reads A = 2 |e| / n at phi = 360 j / n (e > 0) or + 180 (e < 0)
            n = len(p)
            out[f"{c}_um"] = [float(v) for v in p]
            out[f"{c}_um_ci95"] = [_ci(float(v), float(s), tq) for v, s in zip(p, sd)]
            Z = 2.0 / n * np.exp(1j * 2 * np.pi * np.arange(n) / n)
            Z = Z - Z.mean()
            M = np.vstack([Z.real, Z.imag])                  # (Re z, Im z) = M p
            a, a_ci, ph, ph_ci = _polar(M @ p, M @ cp @ M.T, tq)
            out[f"{c}_amplitude_um"] = a
            out[f"{c}_amplitude_um_ci95"] = a_ci
            out[f"{c}_phase_deg"] = ph
            out[f"{c}_phase_deg_ci95"] = ph_ci
            # single-journal reading: the crank and sign whose phase is nearest phi
            cand = [(j, sg) for j in range(n) for sg in (1.0, -1.0)]
            dist = [abs(math.remainder(ph - 360.0 * j / n - (0.0 if sg > 0 else 180.0), 360.0)) for j, sg in cand]
            j, sg = cand[int(np.argmin(dist))]
            out[f"{c}_crank"] = j + 1
            out[f"{c}_single_um"] = sg * a * n / 2.0
        elif c == "crank_hole_position_error":
            # p = (A cos 2 phi, A sin 2 phi): A and phi (mod 180 deg: A, -A look alike)
            a, a_ci, two_ph, two_ph_ci = _polar(p, cp, tq)
            out[f"{c}_amplitude_um"] = a
            out[f"{c}_amplitude_um_ci95"] = a_ci
            out[f"{c}_phase_deg"] = two_ph / 2.0
            out[f"{c}_phase_deg_ci95"] = [v / 2.0 for v in two_ph_ci]
            out[f"{c}_um"] = [float(v) for v in crank_pattern_um(case.carrier.crank_count, p)]
        elif c == "torsional_stiffness":
            kappa, skappa = float(p[0]), float(sd[0])
            out["stiffness_factor"] = 1.0 / (1.0 + kappa)
            lo, hi = 1.0 / (1.0 + kappa + tq * skappa), 1.0 / max(1.0 + kappa - tq * skappa, 1e-9)
            out["stiffness_factor_ci95"] = [float(lo), float(hi)]
        elif c == "backlash":
            um = float(p[0])
            per = backlash_arcmin_per_um(te_model, case, stiffness)
            out["pin_clearance_um"] = um
            out["backlash_arcmin"] = um * per
            out["backlash_arcmin_ci95"] = sorted(_ci(um * per, float(sd[0]) * abs(per), tq))
    return out


def _evidence(sel, case, records, groups, resid, lines, summaries, result) -> str:
    summ = {s.cause: s for s in summaries}[sel.cause]
    c = sel.cause
    pfx = f"(p = {sel.p_value:.1e}, {sel.share:.0%} of the residual power) "
    if c == "output_coaxiality":
        amps = []
        for rec, r in zip(records, resid):
            sp = spectrum_of(rec.output_angle_deg, r)
            amps.append((abs(rec.torque_Nm), sp.at(1.0), sp.at(2.0)))
        a1 = ", ".join(f"{a:.1f}" for _, a, _ in amps)
        tq = ", ".join(f"{t:g}" for t, _, _ in amps)
        return (f"{pfx}a once-per-output-revolution residual line of {a1} arcsec at {tq} N.m "
                f"(about the same at every torque) matches the model's coaxiality signature "
                f"(orders {list(summ.orders)[:3]}, load-independent); no other source puts a 1x line there.")
    zp = case.cycloid.zp

    def line_by_torque(order: float) -> str:
        amps = [(abs(rec.torque_Nm), spectrum_of(rec.output_angle_deg, r).at(order))
                for rec, r in zip(records, resid)]
        return ", ".join(f"{a:.2f} at {t:g} N.m" for t, a in sorted(amps))
    alt = (f"; {', '.join(a for a, _ in sel.alternatives)} fits the same lines about as well (the "
           f"records cannot separate them)") if sel.alternatives else ""
    if c == "crank_eccentricity_error":
        atxt = line_by_torque(zp)
        return (f"{pfx}residual line at the crankshaft order zp = {zp}x ({atxt} arcsec, about the same "
                f"at every torque, unlike a stiffness effect): the model's signature of an eccentric of "
                f"one crankshaft off its radius, which turns one disc against the other once per crank "
                f"revolution (orders {list(summ.orders)[:4]}). Caution: zp x is also the order of a "
                f"disc-tooth or crank-hole pattern error of one disc (and of the crank bearings); the "
                f"order alone does not separate them, the crank-to-crank phase and a teardown do{alt}.")
    if c == "crank_hole_position_error":
        atxt = line_by_torque(2 * zp)
        return (f"{pfx}residual line at twice the crankshaft order, 2 zp = {2 * zp}x ({atxt} arcsec, "
                f"falling with torque) with a shift toward less lost motion: the model's signature of "
                f"a crank-hole position pattern on both discs (the two discs, 180 deg apart, cancel the "
                f"zp x line; the rectified part remains; orders {list(summ.orders)[:4]}); an eccentric "
                f"or disc-tooth error of one disc would show at zp x instead{alt}.")
    gaps = _pair_gaps(records, groups, resid)
    gtxt = ", ".join(f"{g:+.1f} arcsec at {t:g} N.m" for t, g in gaps) or "no forward/backward pair"
    if c == "torsional_stiffness":
        return (f"{pfx}the backward-minus-forward mean TE gap left by the model grows with torque "
                f"({gtxt}): the wind-up differs from the FE stiffness, as the model's stiffness "
                f"signature (mean lag proportional to torque, opposite in the two directions).")
    if c == "backlash":
        return (f"{pfx}a backward-minus-forward mean TE gap the model does not have, the same at "
                f"every torque ({gtxt}): lost motion at the reversal of motion, as the model's "
                f"pin-clearance signature.")
    return pfx


def _pair_gaps(records, groups, resid) -> list[tuple[float, float]]:
    out = []
    for g in dict.fromkeys(groups):
        idx = [k for k in range(len(records)) if groups[k] == g]
        fw = [k for k in idx if records[k].direction > 0]
        bw = [k for k in idx if records[k].direction < 0]
        if fw and bw:
            gap = np.mean([resid[k].mean() for k in bw]) - np.mean([resid[k].mean() for k in fw])
            out.append((float(np.median([abs(records[k].torque_Nm) for k in idx])), float(gap)))
    return sorted(out)
