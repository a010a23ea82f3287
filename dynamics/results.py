"""Result objects of the dynamics stage (frozen; python-control style: data plus small methods).

TE = theta_out - theta_in / i in arcsec, positive = output ahead (DESIGN.md). The output angle is
the one an output encoder reads: the carrier angle plus the once-per-revolution apparent error of
an output coaxiality (mounting) offset (see dynamics.model). A TEResult is written as a bench record
by dynamics.records.write_te_result (the record format's home; this module does not import it).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from dynamics.spectrum import OrderSpectrum, order_spectrum
from geometry.artifacts import InputError

ARCSEC_PER_DEG = 3600.0                        # TE is reported in arcsec (DESIGN.md)
ARCSEC_PER_RAD = 180.0 / np.pi * ARCSEC_PER_DEG  # 206264.806...
ARCSEC_PER_ARCMIN = 60.0


class ResultError(InputError):
    """A request a result cannot serve (e.g. a window with no samples)."""


@dataclass(frozen=True)
class TEResult:
    t_s: np.ndarray                 # (n,) time (quasi-static: sample index * 0, see `quasi_static`)
    input_angle_deg: np.ndarray     # (n,) unwrapped, positive forward
    output_angle_deg: np.ndarray    # (n,) as an output encoder reads it
    output_torque_Nm: np.ndarray    # (n,) load torque, positive when it resists forward rotation
    te_arcsec: np.ndarray           # (n,) theta_out - theta_in / i
    teeth_in_contact: np.ndarray    # (n, discs) pins touching each disc
    pin_force_N: np.ndarray | None = None    # (n, discs, zp) normal pin forces
    ratio: float = 1.0
    meta: dict = field(default_factory=dict)  # case, load, dt, solver statistics

    def window(self, t_from_s: float | None = None) -> np.ndarray:
        """Boolean mask of the samples at or after t_from_s (all when None)."""
        if t_from_s is None:
            return np.ones(len(self.t_s), bool)
        mask = self.t_s >= t_from_s - 1e-12
        if not mask.any():
            raise ResultError(f"t_from_s = {t_from_s}: no samples at or after it "
                              f"(result ends at {self.t_s[-1]:g} s)")
        return mask

    def std_arcsec(self, t_from_s: float | None = None) -> float:
        """Population standard deviation sqrt(sum (x - mean)^2 / n) of TE (paper 001's sigma)."""
        return float(np.std(self.te_arcsec[self.window(t_from_s)]))

    def last_revolution(self) -> np.ndarray:
        """Mask of the last full output revolution of the run (output travel 360 deg back from
        the end, either direction): the window paper 001 most likely analysed."""
        out = self.output_angle_deg
        travel = np.abs(out - out[-1])
        if travel.max() < 360.0:
            raise ResultError(f"last output revolution: the output turned only {travel.max():.4g} deg "
                              f"(allowed: runs with >= 360 deg of output travel)")
        first = np.flatnonzero(travel >= 360.0)[-1]
        mask = np.zeros(len(out), bool)
        mask[first:] = True
        return mask

    def std_last_revolution_arcsec(self) -> float:
        """Population sigma of TE over `last_revolution`."""
        return float(np.std(self.te_arcsec[self.last_revolution()]))

    def spectrum(self, t_from_s: float | None = None, points_per_rev: int = 4096) -> OrderSpectrum:
        """Order spectrum of TE per output revolution (needs one whole output revolution)."""
        m = self.window(t_from_s)
        try:
            return order_spectrum(self.output_angle_deg[m], self.te_arcsec[m], points_per_rev)
        except ValueError as exc:
            raise ResultError(f"TE spectrum: {exc}; simulate longer or start the window earlier") from None


@dataclass(frozen=True)
class StaticState:
    """One static equilibrium (SI except where a name says otherwise)."""
    input_angle_deg: float
    torque_Nm: float                  # output load torque, positive resisting forward rotation
    output_angle_deg: float           # carrier angle (no encoder coaxiality term)
    te_arcsec: float                  # carrier angle - input / i (elastic windup + geometry)
    pin_force_N: np.ndarray           # (discs, zp) normal force of each pin
    pin_gap_m: np.ndarray             # (discs, zp) signed normal gap (< 0: approach)
    bearing_force_N: np.ndarray       # (discs, cranks, 2) turning-arm force ON the disc, ground frame
    mesh_force_N: np.ndarray          # (cranks,) involute mesh force along the line of action
    disc_pose: np.ndarray             # (discs, 3) centre x [m], y [m], rotation [rad]
    crank_angle_rad: np.ndarray       # (cranks,) eccentric (disc 1) angle in the ground frame
    input_torque_Nm: float            # torque the input must supply
    q: np.ndarray                     # generalized coordinates (see dynamics.model DOF layout)
    iterations: int = 0

    @property
    def teeth_in_contact(self) -> np.ndarray:
        return (self.pin_force_N > 0).sum(axis=1)

    @property
    def load_share(self) -> np.ndarray:
        """(discs, zp) share of each pin in its disc's total normal force."""
        tot = self.pin_force_N.sum(axis=1, keepdims=True)
        return np.divide(self.pin_force_N, tot, out=np.zeros_like(self.pin_force_N), where=tot > 0)
