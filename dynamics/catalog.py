"""Catalog stiffness tests on the lumped model: hysteresis curve, torsional rigidity, lost motion.

Input locked (theta_in = 0), output torque swept quasi-statically 0 -> +rated -> -rated -> +rated
(torque in the record convention: positive resists forward rotation, so it winds the output back).
Definitions (Nabtesco RV catalog):
  torsional rigidity  b / a: torque change over angle change between 50 % and 100 % of rated
                      torque, averaged over the two directions [N m / arcmin]
  lost motion         angle between the curve's points at +3 % and -3 % of rated torque [arcmin]
  backlash            width of the loop at zero torque [arcmin]
The contacts are frictionless, so loading and unloading branches coincide except at zero torque,
where the output is free inside the clearance; "zero" is approached as +-ZERO_FRACTION * rated
from either side (the loop's two branches). Friction hysteresis is not modelled: a bench loop
is wider by the friction torque over the stiffness.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from dynamics.reducer import ReducerModel
from dynamics.statics import quasi_static

ZERO_FRACTION = 1e-4
ARCMIN_PER_RAD = 180 * 60 / np.pi


@dataclass(frozen=True)
class HysteresisResult:
    torque_Nm: np.ndarray            # sweep, record convention
    output_angle_arcmin: np.ndarray  # output (carrier) angle, input locked
    rated_torque_Nm: float
    torsional_rigidity_Nm_per_arcmin: float
    torsional_rigidity_secant_Nm_per_arcmin: float
    lost_motion_arcmin: float
    backlash_arcmin: float

    def summary(self) -> dict:
        return {"rated_torque_Nm": self.rated_torque_Nm,
                "torsional_rigidity_Nm_per_arcmin": self.torsional_rigidity_Nm_per_arcmin,
                "torsional_rigidity_secant_Nm_per_arcmin": self.torsional_rigidity_secant_Nm_per_arcmin,
                "lost_motion_arcmin": self.lost_motion_arcmin, "backlash_arcmin": self.backlash_arcmin,
                "lost_motion_torque_Nm": 0.03 * self.rated_torque_Nm,
                "definitions": "rigidity: slope 50-100 % rated (b/a); rigidity secant: rated torque over "
                               "the angle from the lost-motion midpoint to +-rated; lost motion: angle "
                               "between +-3 % rated; backlash: loop width at zero torque; input locked"}


# below 5 % of rated the Hertzian contacts and the pins closing their modification gaps bend the
# curve most: sampled there too, so the curve is not a chord across its low-torque knee
LOW_TORQUE_FRACTIONS = (ZERO_FRACTION, 0.005, 0.01, 0.02, 0.03)


def _sweep(rated: float, n: int) -> np.ndarray:
    up = np.linspace(0.0, 1.0, n)
    leg = np.unique(np.concatenate([up, LOW_TORQUE_FRACTIONS, [0.5]]))
    legs = [leg, leg[::-1][1:], -leg[1:], -leg[::-1][1:], leg[1:]]
    return rated * np.concatenate(legs)


def sweep_torques(rated: float, points_per_quarter: int = 21) -> np.ndarray:
    """The catalog sweep 0 -> +rated -> -rated -> +rated (record convention), zero torque replaced by
    +-ZERO_FRACTION x rated on the side the sweep comes from (the free play is indeterminate)."""
    T = _sweep(rated, points_per_quarter)
    T[0] = ZERO_FRACTION * rated       # start on the loaded side of the free play
    T[T == 0.0] = np.nan
    for i in np.flatnonzero(np.isnan(T)):
        T[i] = -np.sign(T[i - 1]) * ZERO_FRACTION * rated if i else ZERO_FRACTION * rated
    return T


def rigidity_readings(T: np.ndarray, ang_arcmin: np.ndarray, rated: float) -> tuple[float, float]:
    """(slope, secant) rigidity [N m/arcmin] of a catalog curve (torque T, angle, both branches
    averaged at equal torque), each the mean of the two directions:
      slope   b / a: the torque change over the angle change between 50 % and 100 % of rated;
      secant  rated torque over the angle from the lost-motion midpoint (the mean of the angles at
              +-3 % rated) to +-rated: the whole wind-up, clearance knee included."""
    def at(t):
        return float(np.mean(ang_arcmin[np.isclose(T, t)]))

    slope = [0.5 * rated / abs(at(s * rated) - at(0.5 * s * rated)) for s in (1, -1)]
    mid = 0.5 * (at(0.03 * rated) + at(-0.03 * rated))
    secant = [rated / abs(at(s * rated) - mid) for s in (1, -1)]
    return float(np.mean(slope)), float(np.mean(secant))


def hysteresis(model: ReducerModel, points_per_quarter: int = 21) -> HysteresisResult:
    rated = model.case.rated_torque_Nm
    T = sweep_torques(rated, points_per_quarter)
    res = quasi_static(model, np.zeros(len(T)), T)
    ang = np.deg2rad(res.output_angle_deg) * ARCMIN_PER_RAD

    def at(t):
        i = np.flatnonzero(np.isclose(T, t))
        return float(np.mean(ang[i]))

    slope, secant = rigidity_readings(T, ang, rated)
    lost = abs(at(0.03 * rated) - at(-0.03 * rated))
    back = abs(at(ZERO_FRACTION * rated) - at(-ZERO_FRACTION * rated))
    return HysteresisResult(torque_Nm=T, output_angle_arcmin=ang, rated_torque_Nm=rated,
                            torsional_rigidity_Nm_per_arcmin=slope,
                            torsional_rigidity_secant_Nm_per_arcmin=secant,
                            lost_motion_arcmin=lost, backlash_arcmin=back)
