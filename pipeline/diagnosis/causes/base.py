"""What a diagnosis cause is: one object that carries everything the machinery asks of it.

A cause has model parameters p (zero = the case as given, `params(case)`: names, units, physical
bounds) and `apply(case, stiffness, p) -> (case, stiffness)`, the perturbed model. The library
(signatures.py) differences the model at p = unit_size e_j, so orders, load and direction
dependence come from the model; `orders` and `signature` only document what it is expected to find
(and which lines the evidence quotes). After the fit, `report` turns p and its covariance into the
reported parameters (diagnosis.json units), `evidence` writes the finding's sentence, and `draw`
(optional) hides a tolerance-class instance in the virtual bench (bench.py).

`dc_even`: the mean-TE response depends on |p| only (a rectified threshold response): no linear
column carries it, so the cause is named on its order lines alone and its Jacobian columns are
re-taken by the model during the extension fit (extension.py); `nonlinear` asks for the latter
alone (a response far from linear over the parameter's range, e.g. exp(u)).
`additive`: the cause's TE change is the same whatever the other causes' sizes (a reading error of
the output encoder, added after the mechanism solves): its library columns are exact Jacobian
columns at every iterate. Any other cause acts on the mechanism and its slope moves with the
threshold causes sharing its contacts: the extension re-takes its columns when the fit holds one.
Bounds: the physical range of each parameter (a negative clearance, a negative stiffness are
outside), enforced by the extension fit (extension.py: the model never sees a value outside; a
cause whose fit sits on a bound or is pulled past it is not reported). Parameterise so that every
value inside the bounds is a valid model (e.g. the log of a stiffness factor).
Evidence sentences quote only what the records hold: the torques of the records compared, and
trends computed from the numbers (`trend`), never asserted.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pipeline.diagnosis.orders import spectrum_of
from pipeline.diagnosis.significance import noise_sigma


@dataclass(frozen=True)
class Param:
    name: str                        # model parameter, with its unit suffix
    unit: str                        # "um", "1", ...
    bounds: tuple[float, float]      # physical range of p (the case as given is p = 0)


@dataclass(frozen=True)
class Fitted:
    """One cause's fitted model parameters, for `Cause.report`."""
    p: np.ndarray                    # model parameters (params(case) order)
    cov: np.ndarray                  # their covariance (linearised)
    tq: float                        # t quantile of the 95 % interval
    case: object
    stiffness: object
    te_model: object                 # simulate.TEModel, for model-derived conversions

    @property
    def sd(self) -> np.ndarray:
        return np.sqrt(np.maximum(np.diag(self.cov), 0.0))


def ci(v: float, sd: float, tq: float) -> list[float]:
    return [float(v - tq * sd), float(v + tq * sd)]


def polar(p, cp, tq) -> tuple[float, list, float, list]:
    """Magnitude and angle [deg] of (p0, p1) with linearised (delta-method) 95 % intervals; the
    magnitude's interval stops at 0 (an interval reaching 0 says that harmonic is not determined)."""
    m = float(np.hypot(p[0], p[1]))
    g = np.array([p[0], p[1]]) / max(m, 1e-12)                   # d m / d p
    h = np.array([-p[1], p[0]]) / max(m * m, 1e-12)              # d angle / d p
    ang = float(np.degrees(np.arctan2(p[1], p[0])))
    lo, hi = ci(m, float(np.sqrt(g @ cp @ g)), tq)
    return (m, [max(lo, 0.0), hi], ang, ci(ang, float(np.degrees(np.sqrt(h @ cp @ h))), tq))


def polar_params(prefix: str, bound: float) -> tuple[Param, Param]:
    """A phasor's two components (<prefix>_cos_um, <prefix>_sin_um), each within +-bound [um]."""
    return tuple(Param(f"{prefix}_{part}_um", "um", (-bound, bound)) for part in ("cos", "sin"))


def polar_report(fit: "Fitted", key: str) -> dict:
    """<key>_um and <key>_phase_deg of a phasor fit, with their 95 % intervals (polar)."""
    a, a_ci, ph, ph_ci = polar(fit.p, fit.cov, fit.tq)
    return {f"{key}_um": a, f"{key}_um_ci95": a_ci, f"{key}_phase_deg": ph, f"{key}_phase_deg_ci95": ph_ci}


def with_phasor_added(case, key: str, p):
    """The case with (p0, p1) added as a phasor to the error pair <key>_um at <key>_phase_deg."""
    er = case.errors
    v = getattr(er, f"{key}_um") * np.exp(1j * np.radians(getattr(er, f"{key}_phase_deg"))) + complex(p[0], p[1])
    return case.with_errors(**{f"{key}_um": float(abs(v)), f"{key}_phase_deg": float(np.degrees(np.angle(v)))})


def polar_draw(rng, amplitude_range: tuple[float, float], key: str) -> tuple[tuple[float, float], dict]:
    """A virtual-bench phasor: amplitude uniform in the range, any phase; (p, truth in report units)."""
    a, ph = rng.uniform(*amplitude_range), rng.uniform(-180.0, 180.0)
    return ((a * np.cos(np.radians(ph)), a * np.sin(np.radians(ph))), {f"{key}_um": a, f"{key}_phase_deg": ph})


@dataclass(frozen=True)
class Evidence:
    """What a finding's sentence may quote: the selection (fit.Selection), the records, their
    residuals (zero offsets removed) and the cause's signature summary."""
    selection: object
    case: object
    records: tuple
    groups: tuple
    residuals: tuple
    summary: object                  # signatures.SignatureSummary
    stiffness: object = None         # the model's stiffness (fem.stiffness.StiffnessModel)

    @property
    def prefix(self) -> str:
        s = self.selection
        return f"(p = {s.p_value:.1e}, {s.share:.0%} of the residual power) "

    @property
    def alternatives(self) -> str:
        alts = self.selection.alternatives
        return (f"; {', '.join(a for a, _ in alts)} fits the same lines about as well (the "
                f"records cannot separate them)") if alts else ""

    def line_amplitudes(self, order: float) -> list[tuple[float, float, float]]:
        """(|torque|, residual line amplitude at `order`, its noise sigma) per record, in record order."""
        out = []
        for rec, r in zip(self.records, self.residuals):
            sp = spectrum_of(rec.output_angle_deg, r)
            k = int(np.argmin(np.abs(sp.order - order)))
            out.append((abs(rec.torque_Nm), float(sp.amplitude[k]), noise_sigma(sp.amplitude, k)))
        return out

    def line_by_torque(self, order: float) -> str:
        """'a at T N.m, ...' then the trend the numbers show (never a trend they do not)."""
        amps = sorted(self.line_amplitudes(order))
        text = ", ".join(f"{a:.2f} arcsec at {t:g} N.m" for t, a, _ in amps)
        return f"{text}; {trend([(t, a) for t, a, _ in amps], max(s for *_, s in amps))}"

    def pair_gaps(self) -> list[tuple[float, float]]:
        """(|torque|, backward-minus-forward mean residual) per zero group and torque level holding
        both directions: the torques quoted are those of the records compared, nothing in between."""
        recs, groups, resid = self.records, self.groups, self.residuals
        out = []
        for g in dict.fromkeys(groups):
            idx = [k for k in range(len(recs)) if groups[k] == g]
            for level in torque_levels([abs(recs[k].torque_Nm) for k in idx]):
                at = [k for k in idx if abs(abs(recs[k].torque_Nm) - level) <= TORQUE_TOL_NM]
                fw = [k for k in at if recs[k].direction > 0]
                bw = [k for k in at if recs[k].direction < 0]
                if fw and bw:
                    gap = np.mean([resid[k].mean() for k in bw]) - np.mean([resid[k].mean() for k in fw])
                    t = float(np.mean([abs(recs[k].torque_Nm) for k in at]))
                    out.append((t, float(gap)))
        return sorted(out)

    def pair_gaps_text(self) -> str:
        """The gaps, then their trend with torque (computed, as line_by_torque)."""
        gaps = self.pair_gaps()
        if not gaps:
            return "no forward/backward pair"
        return ", ".join(f"{g:+.1f} arcsec at {t:g} N.m" for t, g in gaps) + f"; {trend(gaps)}"


TORQUE_TOL_NM = 5.0   # two records within this |torque| are at one torque level (zeros.py's pairing)


def torque_levels(torques) -> list[float]:
    """Distinct |torque| levels (within TORQUE_TOL_NM), lowest first."""
    levels: list[float] = []
    for t in sorted(torques):
        if not levels or t - levels[-1] > TORQUE_TOL_NM:
            levels.append(float(t))
    return levels


def trend(points, sigma: float = 0.0) -> str:
    """What values (|torque|, a) do with torque, from the numbers: 'about the same at every torque'
    when they agree within 25 % of the largest magnitude or 3 noise sigma, 'growing' or 'falling'
    when they move monotonically with torque (magnitudes when all share a sign; a step back within
    that tolerance still counts), 'varying' otherwise; a single torque level says so."""
    levels = torque_levels([t for t, _ in points])
    if len(levels) < 2:
        return f"one torque level only ({levels[0]:g} N.m), no trend" if levels else "no record"
    a = np.array([np.mean([v for t, v in points if abs(t - lv) <= TORQUE_TOL_NM]) for lv in levels])
    if np.all(a <= 0):
        a = -a
    tol = max(3.0 * sigma, 0.25 * float(np.max(np.abs(a))))
    if a.max() - a.min() <= tol:
        return "about the same at every torque"
    d = np.diff(a)
    step = max(3.0 * sigma, 0.1 * float(np.max(np.abs(a))))
    if np.all(d >= -step):
        return "growing with torque"
    if np.all(d <= step):
        return "falling with torque"
    return "varying with torque"


class Cause:
    """One physical cause (module docstring). Subclasses set the class attributes and implement
    params, apply, report and evidence; orders, signature and draw document and test it."""
    id: str = ""
    description: str = ""            # one line: the mechanism
    signature: str = ""              # one line: orders, load and direction dependence expected
    unit_size: float = 1.0           # signature step, parameter units (same for every parameter)
    dc_even: bool = False
    nonlinear: bool = False          # far from linear over its range: Jacobian re-taken in the fit
    additive: bool = False           # a reading error: its TE adds to any model's (exact library columns)

    def params(self, case) -> tuple[Param, ...]:
        raise NotImplementedError

    def apply(self, case, stiffness, p) -> tuple:
        raise NotImplementedError

    def orders(self, case) -> tuple[int, ...]:
        """Orders per output revolution the signature is expected at (0 = the mean TE)."""
        return ()

    def report(self, fit: Fitted) -> dict:
        raise NotImplementedError

    def evidence(self, ev: Evidence) -> str:
        return ev.prefix + self.description

    def draw(self, rng: np.random.Generator, case) -> tuple[tuple[float, ...], dict] | None:
        """(hidden p, truth in report units) of a tolerance-class instance, or None (no draw)."""
        return None

    @property
    def drawable(self) -> bool:
        """Does the virtual bench know how to hide this cause (draw overridden)?"""
        return type(self).draw is not Cause.draw

    def out_of_bounds(self, case, p) -> tuple[str, ...]:
        """Names (= value, range) of the parameters of p outside their physical bounds."""
        return tuple(f"{q.name} = {v:.4g} outside [{q.bounds[0]:g}, {q.bounds[1]:g}]"
                     for q, v in zip(self.params(case), np.asarray(p, float))
                     if not q.bounds[0] <= v <= q.bounds[1])

    def __repr__(self) -> str:
        return f"<cause {self.id}>"


def per_crank(case, key: str, delta: np.ndarray) -> tuple:
    """case.errors.<key> (one value or one per crank) plus a per-crank delta."""
    base = np.asarray(getattr(case.errors, key), float)
    base = np.broadcast_to(base, (case.carrier.crank_count,)) if base.size == 1 else base
    return tuple(float(v) for v in base + delta)


class LobeCause(Cause):
    """A ring pattern of m lobes (c_m, s_m per harmonic m in `harmonics`, each within +-`bound`),
    added as lobe rows [m, amplitude, phase_deg] to the case's `errors_field` (geometry.params
    Errors). Each disc's load zone sweeps the ring zc times per output revolution, so m lobes show
    at m zc x. Subclasses set the attributes and write the evidence."""
    harmonics: tuple[int, ...] = ()
    bound: float = 0.0
    param_prefix: str = ""           # parameter names <prefix>_m<m>_{cos,sin}_<param_unit>
    param_unit: str = ""
    report_unit: str = ""            # report keys <id>_m<m>_<report_unit>
    errors_field: str = ""
    draw_range: tuple[float, float] = (0.0, 0.0)   # virtual bench: one lobe, |a| in this range
    dc_even = True   # the mean shift (lost motion) is the same for the pattern turned: even in its size

    def params(self, case):
        return tuple(Param(f"{self.param_prefix}_m{m}_{part}_{self.param_unit}", self.param_unit,
                           (-self.bound, self.bound)) for m in self.harmonics for part in ("cos", "sin"))

    def apply(self, case, stiffness, p):
        rows = [list(r) for r in getattr(case.errors, self.errors_field)] + lobe_rows(self.harmonics, p)
        return case.with_errors(**{self.errors_field: rows}), stiffness

    def orders(self, case):
        return tuple(m * case.cycloid.zc for m in self.harmonics)

    def report(self, fit: Fitted) -> dict:
        """Amplitude and phase per harmonic with delta-method 95 % intervals (polar)."""
        out: dict = {f"{self.id}_harmonics": [int(m) for m in self.harmonics]}
        for j, m in enumerate(self.harmonics):
            sl = slice(2 * j, 2 * j + 2)
            a, a_ci, ph, ph_ci = polar(fit.p[sl], fit.cov[sl, sl], fit.tq)
            key = f"{self.id}_m{m}"
            out.update({f"{key}_{self.report_unit}": a, f"{key}_{self.report_unit}_ci95": a_ci,
                        f"{key}_phase_deg": ph, f"{key}_phase_deg_ci95": ph_ci})
        return out

    def lines_text(self, ev: Evidence) -> str:
        """'78x: <amplitude per torque>; 156x: ...' of the records at the cause's orders."""
        return "; ".join(f"{k}x: {ev.line_by_torque(k)}" for k in self.orders(ev.case))

    def draw(self, rng, case):
        """One lobe harmonics[j] alone, |a| uniform in draw_range, any phase."""
        j = int(rng.integers(len(self.harmonics)))
        m = self.harmonics[j]
        p = np.zeros(2 * len(self.harmonics))
        a, ph = rng.uniform(*self.draw_range), rng.uniform(-180.0, 180.0)
        p[2 * j:2 * j + 2] = a * np.cos(np.radians(ph)), a * np.sin(np.radians(ph))
        return tuple(float(v) for v in p), {f"{self.id}_harmonic": m, f"{self.id}_m{m}_{self.report_unit}": float(a),
                                            f"{self.id}_m{m}_phase_deg": float(ph)}


def lobe_rows(harmonics, p) -> list[list[float]]:
    """Lobe rows [m, amplitude, phase_deg] (geometry.params.Errors) from p = (c_m, s_m) per
    harmonic m: c cos(m theta) + s sin(m theta) = a cos(m theta - phase)."""
    p = np.asarray(p, float).reshape(len(harmonics), 2)
    return [[int(m), float(np.hypot(c, s)), float(np.degrees(np.arctan2(s, c)))]
            for m, (c, s) in zip(harmonics, p)]
