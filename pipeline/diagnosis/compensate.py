"""Compensation: the extended model (the diagnosis' causes at their fitted parameters) turned into
what a controller uses, a table of predicted TE against output angle per torque and direction,
and its check on bench records (DESIGN.md `compensate`).

The extended model: each cause of diagnosis.json's `extension.parameters.model_parameters`
applied to the case and the FE stiffness (causes/, the registry's `apply`, in registry order: the
causes act on different parts, their order does not matter) - the same contact mechanics the
diagnosis fitted, no TE curve added.
Table: n points per output revolution, output angle = nominal input angle / i (what the
controller commands), mod 360; TE by the quasi-static model (simulate.quasi_static_te) at each
torque level (record convention: + resists forward rotation, so a backward run's load is < 0)
and direction. Applying it: at a sample, the table's TE at (output angle, torque), periodic
linear interpolation in angle, linear in torque between the two nearest levels of that direction
(clamped at the ends). The check records' own torque levels are in the table, so no torque
interpolation happens on them.
Check: TE RMS before and after subtracting the table, one constant per encoder zero free
(zeros.py, as the diagnosis: a forward/backward pair sharing a zero keeps its physical gap in
both figures); rms_reduction = 1 - after / before. Published beside it: Bilancia et al. (RCIM
2025, the same bench) remove 83-94 % of the TE RMS online with black-box per-order regressors
(orders 0, 1, 39, 40, 78).
Limit: the output encoder's reading error (output_coaxiality) is in the table like the rest: a
controller that closes its loop on the input encoder must take it out if the bench's mounting
is not the machine's.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pipeline.diagnosis import causes as registry
from pipeline.diagnosis.simulate import quasi_static_te
from pipeline.diagnosis.zeros import group_records, remove_offsets, rms

PUBLISHED_RMS_REDUCTION = (0.83, 0.94)
PUBLISHED_SOURCE = ("Bilancia et al., Robotics and Computer-Integrated Manufacturing (2025) 102838: "
                    "per-order regressors of orders 0, 1, 39, 40, 78, online, the same bench")


class CompensationError(ValueError):
    """A diagnosis that carries no extended model, or one this case cannot rebuild."""


def extended_model(case, stiffness, model_parameters: dict):
    """(case, stiffness) with each cause of `model_parameters` ({cause: {parameter: value}}) applied."""
    unknown = set(model_parameters) - {c.id for c in registry.CAUSES}
    if unknown:
        raise CompensationError(f"causes {sorted(unknown)}: not registered (allowed "
                                f"{', '.join(c.id for c in registry.CAUSES)})")
    for cause in registry.CAUSES:
        if cause.id not in model_parameters:
            continue
        given, names = model_parameters[cause.id], [q.name for q in cause.params(case)]
        if set(given) != set(names):
            raise CompensationError(f"{cause.id}: parameters {sorted(given)}, the case {case.name} needs {names}")
        p = np.array([float(given[n]) for n in names])
        bad = cause.out_of_bounds(case, p)
        if bad:
            raise CompensationError(f"{cause.id}: {'; '.join(bad)}")
        case, stiffness = cause.apply(case, stiffness, p)
    return case, stiffness


@dataclass(frozen=True)
class Table:
    output_angle_deg: np.ndarray            # (n,)
    levels: tuple[tuple[float, int], ...]   # (torque_Nm record convention, direction) per row
    te_arcsec: np.ndarray                   # (len(levels), n)

    def rows(self):
        for (t, d), te in zip(self.levels, self.te_arcsec):
            for a, v in zip(self.output_angle_deg, te):
                yield float(a), t, d, float(v)

    def predict(self, output_angle_deg: np.ndarray, torque_Nm: np.ndarray, direction: int) -> np.ndarray:
        """Table TE at samples (angle periodic, torque linear between this direction's levels)."""
        ang = np.mod(np.asarray(output_angle_deg, float), 360.0)
        rows = sorted((t, k) for k, (t, d) in enumerate(self.levels) if d == direction)
        if not rows:
            raise CompensationError(f"the table has no {'forward' if direction > 0 else 'backward'} level")
        ts = np.array([t for t, _ in rows])
        at = np.array([np.interp(ang, self.output_angle_deg, self.te_arcsec[k], period=360.0) for _, k in rows])
        tq = np.clip(np.broadcast_to(np.asarray(torque_Nm, float), ang.shape), ts[0], ts[-1])
        if len(ts) == 1:
            return at[0]
        j = np.clip(np.searchsorted(ts, tq) - 1, 0, len(ts) - 2)
        w = (tq - ts[j]) / np.maximum(ts[j + 1] - ts[j], 1e-300)
        cols = np.arange(ang.size)
        return (1.0 - w) * at[j, cols] + w * at[j + 1, cols]


def table(case, stiffness, torques_Nm, points_per_rev: int = 360, te_model=quasi_static_te) -> Table:
    """TE of the (extended) model over one output revolution per |torque| level and direction."""
    out = np.arange(points_per_rev) * 360.0 / points_per_rev
    levels, te = [], []
    for T in sorted({round(abs(float(t)), 6) for t in torques_Nm}):
        for d in (1, -1):
            order = slice(None) if d > 0 else slice(None, None, -1)   # solved in the direction of motion
            ang = out[order] * case.ratio
            v = np.asarray(te_model(case, stiffness, ang, d * T, d), float)
            levels.append((d * T, d))
            te.append(v[order])
    return Table(out, tuple(levels), np.array(te))


def check(case, tab: Table, records) -> dict:
    """TE RMS of the records before and after subtracting the table (one offset per encoder zero)."""
    groups = group_records(records)
    meas = [r.te_arcsec(case.ratio) for r in records]
    pred = [tab.predict(r.input_angle_deg / case.ratio, r.output_torque_Nm, r.direction) for r in records]
    before = remove_offsets(meas, groups)
    after = remove_offsets([m - p for m, p in zip(meas, pred)], groups)
    b, a = rms(before), rms(after)
    per = {r.name: {"te_rms_before_arcsec": rms([x]), "te_rms_after_arcsec": rms([y]),
                    "rms_reduction": 1.0 - rms([y]) / rms([x]) if rms([x]) > 0 else 0.0,
                    "torque_Nm": r.torque_Nm, "direction": "forward" if r.direction > 0 else "backward"}
           for r, x, y in zip(records, before, after)}
    return {"te_rms_before_arcsec": b, "te_rms_after_arcsec": a,
            "rms_reduction": 1.0 - a / b if b > 0 else 0.0, "records": per,
            "published_rms_reduction": list(PUBLISHED_RMS_REDUCTION), "published_source": PUBLISHED_SOURCE}
