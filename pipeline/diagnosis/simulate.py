"""Simulating a record's conditions through the model (the fast quasi-static path).

A record is simulated at its own input angles (decimated to at most `points_per_rev` per output
revolution, then interpolated back in input angle), at its own torque samples (signed: + resists
forward rotation) and its direction, all read from the record itself. Quasi-static means no
inertia or damping: valid for the slow, steady runs of a TE bench (speed does not enter), not for
load transients (a torque that varies within a record is followed statically).
`TEModel` is the seam to the dynamics stage: any callable with its signature can stand in.
"""
from __future__ import annotations

from typing import Callable

import numpy as np

from pipeline.records import BenchRecord

# te_model(case, stiffness, input_angle_deg, torque_Nm, direction) -> te_arcsec at those angles;
# torque_Nm in the record convention (+ resists forward rotation), scalar or one per angle
TEModel = Callable[..., np.ndarray]

# A bench's "0 N.m" run still drags: the reducer's own no-load running torque keeps the flanks in
# contact in the direction of motion (and a static solve with clearance and no load is singular).
# Loads below this share of rated torque are simulated at it, resisting the motion. ASSUMED figure.
NO_LOAD_DRAG_FRACTION = 0.005

_MODELS: dict = {}
RAMP_STEPS = 8


def quasi_static_te(case, stiffness, input_angle_deg: np.ndarray, torque_Nm: float,
                    direction: int) -> np.ndarray:
    """TE [arcsec] of the dynamics model's static equilibria (dynamics.model.quasi_static)."""
    from dynamics.model import build_model, quasi_static
    key = (case, id(stiffness))
    model = _MODELS.get(key)
    if model is None:
        if len(_MODELS) > 64:
            _MODELS.clear()
        model = _MODELS[key] = (build_model(case, stiffness), stiffness)
    ang = np.asarray(input_angle_deg, float)
    period = 360.0 * case.ratio
    if abs(case.ratio - round(case.ratio)) < 1e-9:
        # integer ratio: the mechanism repeats every output revolution (crank turns zp times), so
        # start near input 0 where the solver's rigid-body guess is built; TE is unchanged
        ang = ang - period * np.round(ang[0] / period)
    # load continuation: the solver's first guess is unloaded, so ramp the torque up at the
    # first angle (RAMP_STEPS extra equilibria, dropped) before following the record
    T = np.broadcast_to(np.asarray(torque_Nm, float), ang.shape) * int(direction)
    ramp = T[0] * np.linspace(0.0, 1.0, RAMP_STEPS + 1)[1:-1]
    # quasi_static applies direction * torque_Nm: convert from the record convention
    res = quasi_static(model[0], np.r_[np.full(ramp.size, ang[0]), ang], np.r_[ramp, T], int(direction))
    return np.asarray(res.te_arcsec, float)[ramp.size:]


def simulation_indices(record: BenchRecord, points_per_rev: int) -> np.ndarray:
    """Samples to simulate: the record's own, thinned to <= points_per_rev per output rev."""
    revs = max(record.output_travel_deg / 360.0, 1e-9)
    step = max(1, int(np.floor(len(record.time_s) / (revs * points_per_rev))))
    idx = np.r_[np.arange(0, len(record.time_s), step), len(record.time_s) - 1]
    return np.unique(idx)


def simulate_record(te_model: TEModel, case, stiffness, record: BenchRecord,
                    points_per_rev: int = 1024) -> np.ndarray:
    """Simulated TE [arcsec] at every sample of `record` (same input angle, torque, direction)."""
    idx = simulation_indices(record, points_per_rev)
    ang = record.input_angle_deg[idx]
    torque = record.output_torque_Nm[idx]
    drag = NO_LOAD_DRAG_FRACTION * case.rated_torque_Nm
    torque = np.where(np.abs(torque) < drag, record.direction * drag, torque)
    te = te_model(case, stiffness, ang, torque, record.direction)
    order = np.argsort(ang)
    return np.interp(record.input_angle_deg, ang[order], np.asarray(te)[order])
