"""Simulating a record's conditions through the model (the fast quasi-static path).

A record is simulated at its own input angles (decimated to at most `points_per_rev` per output
revolution, then interpolated back in input angle), at its own torque samples (signed: + resists
forward rotation) and its direction, all read from the record itself. The mechanism repeats after
one output revolution (dynamics.statics: every body's phase returns), so a record of several
revolutions at a steady torque (spread within STEADY_TORQUE of rated) is simulated over one
revolution at its median torque and read periodically: the cost no longer grows with its length.
A torque that varies more is followed sample by sample (cost grows with the revolutions). Quasi-static means no
inertia or damping: valid for the slow, steady runs of a TE bench (speed does not enter), not for
load transients (a torque that varies within a record is followed statically).
Zero torque (the bench's "0 N.m" runs) is passed as 0: the model rests on the flank of the
direction of motion under a vanishing preload (dynamics.model.solve_static), so the no-load TE
carries half the backlash with the sign of the motion. Angles far from 0 and large torques are the
static solver's business (period reduction, torque continuation): nothing is shifted or ramped here.
`TEModel` is the seam to the dynamics stage: any callable with its signature can stand in.
"""
from __future__ import annotations

from typing import Callable

import numpy as np

from dynamics.records import BenchRecord

# te_model(case, stiffness, input_angle_deg, torque_Nm, direction) -> te_arcsec at those angles;
# torque_Nm in the record convention (+ resists forward rotation), scalar or one per angle
TEModel = Callable[..., np.ndarray]

_MODELS: dict = {}
_MODEL_CACHE_SIZE = 64
STEADY_TORQUE = 0.01   # 5-95 % torque spread / rated torque under which a record is steady


def quasi_static_te(case, stiffness, input_angle_deg: np.ndarray, torque_Nm,
                    direction: int) -> np.ndarray:
    """TE [arcsec] of the dynamics model's static equilibria (dynamics.model.quasi_static).

    torque_Nm is the record's (signed, + resists forward rotation); quasi_static applies
    direction * its argument, so it gets direction * torque_Nm (= |T| for a steady record).
    Models are cached per (case, stiffness object): a diagnosis re-simulates the same few."""
    from dynamics.model import build_model
    from dynamics.statics import quasi_static
    key = (case, id(stiffness))
    entry = _MODELS.get(key)
    if entry is None:
        if len(_MODELS) >= _MODEL_CACHE_SIZE:
            _MODELS.clear()
        entry = _MODELS[key] = (build_model(case, stiffness), stiffness)  # keeps id(stiffness) alive
    ang = np.asarray(input_angle_deg, float)
    T = int(direction) * np.broadcast_to(np.asarray(torque_Nm, float), ang.shape)
    return np.asarray(quasi_static(entry[0], ang, T, int(direction)).te_arcsec, float)


def simulation_indices(record: BenchRecord, points_per_rev: int) -> np.ndarray:
    """Samples to simulate: those nearest a uniform grid of <= points_per_rev per output rev in
    output travel (not in sample index: sampling need not be uniform), first and last included."""
    travel = np.maximum.accumulate(np.abs(record.output_angle_deg - record.output_angle_deg[0]))
    n_pts = max(int(np.ceil(travel[-1] / 360.0 * points_per_rev)), 2)
    if len(travel) <= 1.5 * n_pts:   # no thinning worth its interpolation error
        return np.arange(len(travel))
    grid = np.linspace(0.0, travel[-1], n_pts + 1)
    idx = np.clip(np.searchsorted(travel, grid), 0, len(travel) - 1)
    return np.unique(np.r_[0, idx, len(travel) - 1])


def simulate_record(te_model: TEModel, case, stiffness, record: BenchRecord,
                    points_per_rev: int = 1024) -> np.ndarray:
    """Simulated TE [arcsec] at every sample of `record` (same input angle, torque, direction)."""
    T = record.output_torque_Nm
    spread = float(np.subtract(*np.percentile(T, [95, 5])))
    if record.output_travel_deg > 1.5 * 360.0 and spread <= STEADY_TORQUE * case.rated_torque_Nm:
        period = 360.0 * case.ratio                      # input degrees per output revolution
        a0, d = record.input_angle_deg[0], record.direction
        grid = a0 + d * np.arange(points_per_rev) * (period / points_per_rev)
        te = np.asarray(te_model(case, stiffness, grid, float(np.median(T)), d))
        return np.interp(record.input_angle_deg - a0, grid - a0, te, period=period)
    idx = simulation_indices(record, points_per_rev)
    ang = record.input_angle_deg[idx]
    te = te_model(case, stiffness, ang, record.output_torque_Nm[idx], record.direction)
    order = np.argsort(ang)
    return np.interp(record.input_angle_deg, ang[order], np.asarray(te)[order])
