"""The registry of diagnosis causes: one module per cause, one line per cause in `_MODULES`.

Each module defines `CAUSE`, an instance of base.Cause (parameters, units and physical bounds,
model application, signature metadata, evidence sentence, reported parameters, virtual-bench
draw). The machinery (signatures.py, diagnose.py, bench.py) reads `CAUSES` when it runs and never
branches on a cause id, so adding a cause is one new module here and one line in `_MODULES`
(the order is the library's order: it breaks ties in the selection). The list below is built from
the registry itself.
"""
from __future__ import annotations

from importlib import import_module

from pipeline.diagnosis.causes.base import Cause

_MODULES = (
    "output_coaxiality",
    "crank_eccentricity_error",
    "crank_hole_position_error",
    "torsional_stiffness",
    "backlash",
    "pin_ring_pattern",
    "pin_ring_tilt",
    "housing_stiffness_pattern",
    "disc_cumulative_pitch",
    "output_reading_lobes",
)

CAUSES: tuple[Cause, ...] = tuple(import_module(f"{__name__}.{m}").CAUSE for m in _MODULES)


def get(cause_id: str) -> Cause:
    """The registered cause with this id (ValueError naming the allowed ids otherwise)."""
    for c in CAUSES:
        if c.id == cause_id:
            return c
    raise ValueError(f"cause {cause_id!r}: allowed {', '.join(c.id for c in CAUSES)}")


def describe(causes=None) -> str:
    """One line per registered cause: id, signature, mechanism."""
    return "\n".join(f"  {c.id}: {c.signature}; {c.description}" for c in (causes or CAUSES))


def _check(causes) -> None:
    ids = [c.id for c in causes]
    if len(set(ids)) != len(ids) or not all(ids):
        raise ValueError(f"cause ids must be unique and non-empty: {ids}")


_check(CAUSES)
if __doc__:   # None under python -OO
    __doc__ += "\nRegistered causes:\n" + describe() + "\n"
