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
re-taken by the model during the extension fit (diagnose.py).
Bounds: the physical range of each parameter (a negative clearance, a negative stiffness are
outside); carried for the fits and checked after them (diagnose.Extension.outside_bounds), not yet
enforced by the solver.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pipeline.diagnosis.orders import spectrum_of


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
    """Magnitude and angle [deg] of (p0, p1) with linearised (delta-method) 95 % intervals."""
    m = float(np.hypot(p[0], p[1]))
    g = np.array([p[0], p[1]]) / max(m, 1e-12)                   # d m / d p
    h = np.array([-p[1], p[0]]) / max(m * m, 1e-12)              # d angle / d p
    ang = float(np.degrees(np.arctan2(p[1], p[0])))
    return (m, ci(m, float(np.sqrt(g @ cp @ g)), tq), ang,
            ci(ang, float(np.degrees(np.sqrt(h @ cp @ h))), tq))


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

    @property
    def prefix(self) -> str:
        s = self.selection
        return f"(p = {s.p_value:.1e}, {s.share:.0%} of the residual power) "

    @property
    def alternatives(self) -> str:
        alts = self.selection.alternatives
        return (f"; {', '.join(a for a, _ in alts)} fits the same lines about as well (the "
                f"records cannot separate them)") if alts else ""

    def line_amplitudes(self, order: float) -> list[tuple[float, float]]:
        """(|torque|, residual line amplitude at `order`) per record, in record order."""
        return [(abs(rec.torque_Nm), spectrum_of(rec.output_angle_deg, r).at(order))
                for rec, r in zip(self.records, self.residuals)]

    def line_by_torque(self, order: float) -> str:
        return ", ".join(f"{a:.2f} at {t:g} N.m" for t, a in sorted(self.line_amplitudes(order)))

    def pair_gaps(self) -> list[tuple[float, float]]:
        """(median |torque|, backward-minus-forward mean residual) per zero group holding both."""
        recs, groups, resid = self.records, self.groups, self.residuals
        out = []
        for g in dict.fromkeys(groups):
            idx = [k for k in range(len(recs)) if groups[k] == g]
            fw = [k for k in idx if recs[k].direction > 0]
            bw = [k for k in idx if recs[k].direction < 0]
            if fw and bw:
                gap = np.mean([resid[k].mean() for k in bw]) - np.mean([resid[k].mean() for k in fw])
                out.append((float(np.median([abs(recs[k].torque_Nm) for k in idx])), float(gap)))
        return sorted(out)

    def pair_gaps_text(self) -> str:
        return ", ".join(f"{g:+.1f} arcsec at {t:g} N.m" for t, g in self.pair_gaps()) \
            or "no forward/backward pair"


class Cause:
    """One physical cause (module docstring). Subclasses set the class attributes and implement
    params, apply, report and evidence; orders, signature and draw document and test it."""
    id: str = ""
    description: str = ""            # one line: the mechanism
    signature: str = ""              # one line: orders, load and direction dependence expected
    unit_size: float = 1.0           # signature step, parameter units (same for every parameter)
    dc_even: bool = False

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
