"""Pin in its housing groove: conformal contact (Persson / Ciavarella), ISO 286 H7/h6 mean
clearance (fem.pin_groove); a nonlinear approach in series with each pin."""
from __future__ import annotations

import dataclasses as dc

import numpy as np

from fem.components.base import Result, timed

NAME = "pin_groove"
COUPLING = "pin"
COST = 5


@timed
def compute(case, ctx) -> Result:
    from fem import pin_groove
    g = pin_groove.case_series(case, ctx["loads"]["pin"])
    return Result(NAME, {"pin_series.groove_load_N": g["load_N"], "pin_series.groove_approach_m": g["series_approach_m"]},
                  {NAME: g["source"]}, {NAME: g["check"]})


def stiffen(model, f: float):
    ps = model.pin_series
    return dc.replace(model, pin_series=dc.replace(ps, groove_approach_m=ps.groove_approach_m / f))


def series_approach_m(model, force_N):
    return model.pin_series.groove_m(np.asarray(force_N, float))
