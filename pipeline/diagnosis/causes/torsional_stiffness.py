"""torsional_stiffness: a located series compliance, the FE model's largest one off by a factor.

Not a scale of every stiffness (issue 13): the compliance budget of the model
(dynamics.budget.compliance_budget, each component's share of the output torsional compliance at
rated torque) names the component that carries most of the wind-up; that component, and it alone,
gets its compliance multiplied by f = exp(u) (StiffnessModel.stiffened(component, 1 / f)). Why
that one: a TE bench sees only the sum of the series compliances, so the records cannot locate a
missing compliance among the components (nor from the bench's own chain between the reducer and its
output encoder: a torque meter or coupling there adds its twist, which the evidence says); the
largest share is the one whose model is most likely to be off (for the RV-160N FE: the carrier,
35 %, a 3D FE body whose bolted and pinned pillar joints the FE models as bonded), and one factor
on it is one bounded, physical parameter. A linear
FE component (carrier, crank bending) adds wind-up proportional to torque; a Hertzian one would
stiffen with load: the evidence quotes the records' gap increments so the reader can check which.
Parameter u = ln f [1]: any u is a positive compliance (a linearisation step in u cannot cross
zero). Bounds f in [0.1, 10] (ASSUMED: an FE component off by more than 10 x is a wrong model,
not a tolerance). Signature: a mean lag growing with torque, opposite in the two directions (a
backward-minus-forward gap growing with torque). Reported: the component, its share, f with its
95 % interval, the model's tangent rigidity at rated torque before and after, and the difference of
their compliances (the same wind-up as one series spring, arcmin per kN m; negative: stiffer).
Unit size u = 0.1. Virtual bench: f in [0.4, 0.7] or [1.5, 3.0].
"""
from __future__ import annotations

import dataclasses
import math

from dynamics.conditions import torque_flange_range_text
from pipeline.diagnosis.causes.base import Cause, Evidence, Fitted, Param

FACTOR_RANGE = (0.1, 10.0)
_BUDGETS: dict = {}


def budget(case, stiffness) -> dict:
    """compliance_budget of the model at rated torque (cached per case and stiffness content)."""
    from pipeline.diagnosis.simulate import model_for, stiffness_digest
    key = (case, stiffness_digest(stiffness))
    if key not in _BUDGETS:
        from dynamics.budget import compliance_budget
        if len(_BUDGETS) > 32:
            _BUDGETS.clear()
        _BUDGETS[key] = compliance_budget(model_for(case, stiffness, key[1]))
    return _BUDGETS[key]


def located_component(case, stiffness) -> tuple[str, float]:
    """(component, share) of the largest share of the output compliance at rated torque, read on
    the ideal build (the case without its errors): the location is a property of the FE model, so
    every model the extension fit evaluates scales the same component, and the budget is solved
    once per stiffness instead of once per iterate's errors (0.6 s each: 8 % of the real records'
    diagnosis). For a case file without errors (every shipped case) the same as before."""
    ideal = dataclasses.replace(case, errors=type(case.errors)())
    shares = budget(ideal, stiffness)["compliance_budget"]
    comp = max(shares, key=shares.get)
    return comp, float(shares[comp])


def compliance_scaled(case, stiffness, factor: float):
    """The located component's compliance times `factor` (> 0, finite)."""
    if not (math.isfinite(factor) and factor > 0):
        raise ValueError(f"compliance factor {factor}: must be finite and > 0")
    comp, _ = located_component(case, stiffness)
    return stiffness.stiffened(comp, 1.0 / factor)


class TorsionalStiffness(Cause):
    id = "torsional_stiffness"
    description = "a series compliance the FE model misses, located in its largest-share component"
    signature = "mean lag growing with torque, opposite in the two directions"
    unit_size = 0.1
    nonlinear = True   # the wind-up grows as exp(u): a 10 % secant is 2x off at f = 3

    def params(self, case):
        lo, hi = FACTOR_RANGE
        return (Param("log_compliance_factor", "1", (math.log(lo), math.log(hi))),)

    def apply(self, case, stiffness, p):
        return case, compliance_scaled(case, stiffness, math.exp(float(p[0])))

    def orders(self, case):
        return (0,)

    def report(self, fit: Fitted) -> dict:
        u, su, tq = float(fit.p[0]), float(fit.sd[0]), fit.tq
        lo, hi = self.params(fit.case)[0].bounds    # the interval within the physical range
        comp, share = located_component(fit.case, fit.stiffness)
        before = budget(fit.case, fit.stiffness)["tangent_rigidity_Nm_per_arcmin"]
        after = budget(fit.case, compliance_scaled(fit.case, fit.stiffness, math.exp(u)))["tangent_rigidity_Nm_per_arcmin"]
        return {"located_component": comp, "located_component_share": share,
                "compliance_factor": math.exp(u),
                "compliance_factor_ci95": [math.exp(max(u - tq * su, lo)), math.exp(min(u + tq * su, hi))],
                "rigidity_at_rated_Nm_per_arcmin": {"model": before, "extended": after},
                # the same wind-up as one series spring, wherever it sits (the located component or the
                # bench's chain): what to set beside a torque flange's or coupling's data sheet
                "added_series_compliance_arcmin_per_kNm": 1e3 * (1.0 / after - 1.0 / before)}

    def evidence(self, ev: Evidence) -> str:
        comp, share = located_component(ev.case, ev.stiffness)
        gaps = ev.pair_gaps()
        slope = ""
        if len(gaps) >= 2:
            steps = [f"{(g1 - g0) / (t1 - t0) * 100:+.1f}" for (t0, g0), (t1, g1) in zip(gaps, gaps[1:])]
            slope = f"; the gap moves {', '.join(steps)} arcsec per 100 N.m between the torques compared"
        where = f"{comp} ({share:.0%} of the model's compliance at rated torque)"
        return (f"{ev.prefix}a backward-minus-forward mean TE gap left by the model ({ev.pair_gaps_text()}"
                f"{slope}): the reducer winds up more (or less) than the FE says. Located in {where}, the "
                f"largest share of the compliance budget: a TE bench sees only the sum of the series "
                f"compliances, so which component is off is the budget's reading, not the records'; the sum "
                f"includes the bench's own chain where the output encoder reads beyond a torque meter or "
                f"coupling ({torque_flange_range_text()}).")

    def draw(self, rng, case):
        f = rng.uniform(0.4, 0.7) if rng.random() < 0.5 else rng.uniform(1.5, 3.0)
        return (math.log(f),), {"compliance_factor": f}


CAUSE = TorsionalStiffness()
