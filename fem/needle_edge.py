"""Turning-arm needle bearing under crank slope: tilted line contacts by slices.

The crankshaft bends under the needle load, so its eccentric tilts by theta = slope_per_N * F
(the slope per newton of bearing load comes from the crankshaft FE, fem.shaft; it is an input
here) relative to the disc bore, which stays parallel to the carrier axis (the disc is held by
its pins and the other cranks). Bending is in the plane of the load, so the needle at azimuth
psi from the load sees the misalignment theta cos psi along its length.

Slice law (ISO/TS 16281, with this project's Palmgren constant, fem.hertz): a needle of length L
is cut into n equal slices; slice k carries q_k = (K_n / n) max(delta_k, 0)^(10/9) with
K_n = palmgren_roller_constant(L) (both contacts: Q = K_n delta^(10/9) for a uniform approach),
  delta_k = delta_c + phi x_k - h(x_k),  x_k the slice centre from the needle middle,
delta_c the approach at the needle middle, phi the local misalignment, h the profile drop.
The needle sits between both races, so only the races' relative tilt phi enters (its own tilt
sets equal loads on both sides, which the total-approach slice law already assumes).
Profile: UNCROWNED by default (h = 0): straight needles with the full length L in contact, the
same needle the 2D FE of fem.bearing models (its zero-tilt reference); NeedleProfile gives a
crowned variant (flat middle, parabolic end drop), common on caged needles.
Closed forms the slices are checked against:
  zero tilt, straight: delta = 7.68e-5 Q^0.9 / L^0.8 mm (Palmgren, both contacts), every n;
  edge contact (contact shorter than L): the continuous slice integral gives the approach at the
    loaded end delta_e = (19 Q L phi / (9 K_n))^(9/19), contact length delta_e / phi.
Bearing: Z needles, zero clearance, rigid rings, the eccentric shifts by delta_r along the load:
needle j approaches delta_r cos psi_j at its middle. Limits: slices are uncoupled (no edge
stress singularity: the slice method's known optimism at a sharp end), no needle skew.

What the tilt does to stiffness (measured, tests/test_fem_rolling.py): the slice law is convex
(q ~ delta^(10/9)), so at a fixed load a tilt LOWERS the middle approach delta_r a little (the
loaded end gains more than the other end loses) until the contact leaves the far end, and the
load's line of action moves towards the loaded end: the bearing transmits a moment M that
opposes the tilt. The disc (held parallel to the carrier) moves by u_d = c F + s M + delta_r,
(c, s the crank's lateral compliance and slope per newton at the eccentric; s is also the
lateral displacement per unit moment, Maxwell), and s M always opposes: a crank slope does not
soften the turning-arm path in this model; it raises the edge load (peak slice load) instead.
`misaligned_stiffness_ratio` = delta_r(F, 0) / delta_r(F, theta) (>= 1: no loss), and
SlopeCoupledCurve carries the moment term as well.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

from fem import hertz
from geometry.artifacts import InputError

EXP = 10.0 / 9.0


@dataclass(frozen=True)
class NeedleProfile:
    """Crown: flat over `flat_fraction` of the length, then a parabolic drop reaching
    `end_drop_m` at each end. Default: uncrowned."""
    end_drop_m: float = 0.0
    flat_fraction: float = 1.0

    def drop_m(self, x_m: np.ndarray, length_m: float) -> np.ndarray:
        half, flat = length_m / 2, self.flat_fraction * length_m / 2
        if self.end_drop_m <= 0 or flat >= half:
            return np.zeros_like(x_m)
        t = np.clip((np.abs(x_m) - flat) / (half - flat), 0.0, None)
        return self.end_drop_m * t ** 2


STRAIGHT = NeedleProfile()


def _check(length_m: float, slices: int) -> None:
    if not (length_m > 0):
        raise InputError(f"needle length = {length_m!r} m: must be positive")
    if int(slices) < 1:
        raise InputError(f"needle slices = {slices!r}: must be >= 1")


def slice_centres_m(length_m: float, slices: int) -> np.ndarray:
    return ((np.arange(slices) + 0.5) / slices - 0.5) * length_m


def slice_loads_N(centre_approach_m, tilt_rad, length_m: float, slices: int,
                  profile: NeedleProfile = STRAIGHT) -> np.ndarray:
    """(..., n) slice loads of needles with middle approach delta_c and misalignment phi."""
    x = slice_centres_m(length_m, slices)
    d = (np.asarray(centre_approach_m, float)[..., None] + np.asarray(tilt_rad, float)[..., None] * x
         - profile.drop_m(x, length_m))
    return hertz.palmgren_roller_constant(length_m) / slices * np.maximum(d, 0.0) ** EXP


def _needle_load(dc, phi, length_m, slices, profile) -> float:
    return float(slice_loads_N(dc, phi, length_m, slices, profile).sum())


@dataclass(frozen=True)
class NeedleContact:
    load_N: float
    tilt_rad: float
    centre_approach_m: float         # approach at the needle middle
    max_approach_m: float            # at the most compressed slice
    slice_load_N: np.ndarray         # (n,)
    contact_length_m: float          # slices in contact x slice length
    moment_Nm: float                 # moment of the slice loads about the needle middle


def needle_contact(load_N: float, tilt_rad: float, length_m: float, *, slices: int = 60,
                   profile: NeedleProfile = STRAIGHT) -> NeedleContact:
    """One needle under load Q and misalignment phi: the middle approach that carries Q."""
    _check(length_m, slices)
    Q, phi = float(load_N), abs(float(tilt_rad))
    x = slice_centres_m(length_m, slices)
    if Q <= 0:
        return NeedleContact(Q, phi, 0.0, 0.0, np.zeros(slices), 0.0, 0.0)
    # bracket: low = the first slice just touching, high = the whole needle loaded beyond Q
    h = profile.drop_m(x, length_m)
    lo = float(np.min(h - phi * x))
    hi = lo + float(hertz.palmgren_needle_approach(Q, length_m)) * slices ** 0.9 + phi * length_m + h.max()
    dc = brentq(lambda d: _needle_load(d, phi, length_m, slices, profile) - Q, lo, hi, xtol=1e-16, rtol=1e-13)
    q = slice_loads_N(dc, phi, length_m, slices, profile)
    dmax = float(np.max(dc + phi * x - h))
    return NeedleContact(Q, phi, dc, dmax, q, float((q > 0).sum()) * length_m / slices, float(q @ x))


def edge_contact_approach_m(load_N: float, tilt_rad: float, length_m: float) -> tuple[float, float]:
    """(approach at the loaded end, contact length) of a straight needle in edge contact, from the
    continuous slice integral (module doc); valid while the contact length is below L."""
    K = hertz.palmgren_roller_constant(length_m)
    de = (19.0 * load_N * length_m * tilt_rad / (9.0 * K)) ** (9.0 / 19.0)
    return de, de / tilt_rad


def edge_contact_onset_tilt_rad(load_N: float, length_m: float) -> float:
    """The misalignment at which a straight needle's far end just unloads (edge contact with a
    contact length of exactly L): delta_e = phi L in the edge law gives phi = (19 Q / (9 K_n))^0.9 / L."""
    K = hertz.palmgren_roller_constant(length_m)
    return (19.0 * load_N / (9.0 * K)) ** 0.9 / length_m


@dataclass(frozen=True)
class MisalignedBearing:
    load_N: float
    tilt_rad: float
    deflection_m: float              # eccentric shift along the load
    needle_load_N: np.ndarray        # (Z,)
    needle_angle_rad: np.ndarray     # (Z,) from the load direction
    moment_Nm: float                 # moment the slices transmit (resists the crank slope)
    max_slice_load_N: float


def misaligned_bearing(radial_load_N: float, tilt_rad: float, *, needle_count: int, length_m: float,
                       slices: int = 60, profile: NeedleProfile = STRAIGHT,
                       phase_rad: float = 0.0) -> MisalignedBearing:
    """Zero-clearance needle bearing under a radial load with the eccentric tilted by theta in the
    plane of the load: the eccentric shift delta_r that carries F (needles at psi_j, needle j with
    middle approach delta_r cos psi_j and misalignment theta cos psi_j)."""
    _check(length_m, slices)
    Z = int(needle_count)
    if Z < 3:
        raise InputError(f"needle_count = {needle_count!r}: must be >= 3")
    F, th = float(radial_load_N), float(tilt_rad)
    psi = phase_rad + 2 * np.pi * np.arange(Z) / Z
    c = np.cos(psi)
    x = slice_centres_m(length_m, slices)

    def loads(dr):
        return slice_loads_N(dr * c, th * c, length_m, slices, profile)   # (Z, n)

    def resid(dr):
        return float(loads(dr).sum(axis=1) @ c) - F

    if F <= 0:
        return MisalignedBearing(F, th, 0.0, np.zeros(Z), psi, 0.0, 0.0)
    hi = 2.0 * float(hertz.palmgren_needle_approach(4.08 * F / Z, length_m)) * slices ** 0.9 \
        + abs(th) * length_m + profile.end_drop_m + 1e-9
    while resid(hi) < 0:
        hi *= 2
    dr = brentq(resid, 0.0, hi, xtol=1e-16, rtol=1e-13)
    q = loads(dr)
    return MisalignedBearing(F, th, dr, q.sum(axis=1), psi, float((q @ x) @ c), float(q.max()))


def misaligned_stiffness_ratio(radial_load_N: float, tilt_rad, *, needle_count: int, length_m: float,
                               slices: int = 60, profile: NeedleProfile = STRAIGHT) -> np.ndarray:
    """Secant radial stiffness of the tilted bearing over the aligned one at the same load,
    delta_r(F, 0) / delta_r(F, theta): 1 = unchanged, < 1 a loss (module doc: it stays >= 1)."""
    kw = dict(needle_count=needle_count, length_m=length_m, slices=slices, profile=profile)
    d0 = misaligned_bearing(radial_load_N, 0.0, **kw).deflection_m
    tilts = np.atleast_1d(np.asarray(tilt_rad, float))
    return np.array([d0 / misaligned_bearing(radial_load_N, t, **kw).deflection_m for t in tilts])


@dataclass(frozen=True)
class SlopeCoupledCurve:
    load_N: np.ndarray
    slope_rad_per_N: float
    tilt_rad: np.ndarray             # slope_per_N * F
    deflection_m: np.ndarray         # middle approach delta_r with the crank slope
    aligned_deflection_m: np.ndarray # same loads, no slope
    moment_Nm: np.ndarray            # |M| the contact transmits against the tilt
    max_slice_load_N: np.ndarray
    aligned_max_slice_load_N: np.ndarray

    @property
    def effective_deflection_m(self) -> np.ndarray:
        """delta_r - |s| |M|: the bearing's share of the disc motion with the crank's response to
        the bearing moment (module doc); add c F (the crank's own lateral compliance) outside."""
        return self.deflection_m - abs(self.slope_rad_per_N) * self.moment_Nm

    @property
    def stiffness_ratio(self) -> np.ndarray:
        """Secant stiffness with slope / without, per load (>= 1: no loss)."""
        return self.aligned_deflection_m / self.effective_deflection_m

    @property
    def edge_load_ratio(self) -> np.ndarray:
        """Peak slice load with slope / without: the edge loading the slope causes."""
        return self.max_slice_load_N / self.aligned_max_slice_load_N


def slope_coupled_curve(loads_N, slope_rad_per_N: float, *, needle_count: int, length_m: float,
                        slices: int = 60, profile: NeedleProfile = STRAIGHT) -> SlopeCoupledCurve:
    """Load-deflection of the turning-arm bearing when the crank slope grows with the load:
    theta = slope_rad_per_N * F (the lead takes slope_rad_per_N from the crankshaft FE)."""
    loads = np.asarray(loads_N, float)
    if loads.size == 0 or np.any(loads <= 0):
        raise InputError(f"needle bearing loads = {loads.tolist()}: must be positive")
    if not (slope_rad_per_N >= 0 and math.isfinite(slope_rad_per_N)):
        raise InputError(f"crank slope per newton = {slope_rad_per_N!r} rad/N: must be finite and >= 0")
    kw = dict(needle_count=needle_count, length_m=length_m, slices=slices, profile=profile)
    tilt = slope_rad_per_N * loads
    tilted = [misaligned_bearing(F, t, **kw) for F, t in zip(loads, tilt)]
    aligned = [misaligned_bearing(F, 0.0, **kw) for F in loads]
    return SlopeCoupledCurve(loads, float(slope_rad_per_N), tilt, np.array([r.deflection_m for r in tilted]),
                             np.array([r.deflection_m for r in aligned]),
                             np.array([abs(r.moment_Nm) for r in tilted]),
                             np.array([r.max_slice_load_N for r in tilted]),
                             np.array([r.max_slice_load_N for r in aligned]))
