"""Pin-to-profile gaps, moment arms, minimum clearance and backlash of a case.

Method (numerical, on the parametric curve, no polyline): the foot point of each pin centre q on
the pin-centre curve c(t) (R, delta modified) comes from the one geometry kernel,
`geometry.pin_profile` (seeded bracketed Newton to machine precision); the profile point is
p = c(t*) - Rr n(t*) (Rr modified, n the outward normal) and
    gap = (q - c(t*)) . n(t*) + Rr_profile - Rr_pin       (0 = tangent, < 0 = interference).
A 2000-point polyline would instead carry a chordal error h^2 / (8 rho), up to 4 um on the RV-40E
(h = 0.23 mm, rho = 1.6 mm at the tips), the size of a micron clearance; here the discretisation
only picks the basin (tests: gaps independent of the seed grid at K1 = 0.95, micron gaps).

Pose convention (DESIGN.md): disc centre at E (cos psi_c, sin psi_c), disc turned by -psi_c / zc
(+ an extra rotation `disc_rotation_rad`, the output side of backlash), pins at
R_pin (cos 2 pi k/zp, sin 2 pi k/zp). Pin errors of the case (`errors.pin_radius_um`,
`errors.pin_circle_radius_um`) are applied to the pins, so gaps come from the actual geometry.
The second disc of a two-disc reducer sits at psi_c + pi: its gaps are those of disc 1 there.

Backlash: the eccentric held fixed in the ground frame (the cycloid stage's input locked), the disc
turned about its own centre until the first pin touches, in both directions; the output (carrier)
follows the disc rotation one to one. Moment arm of pin k: l_k = (p - O_disc) x n, so that
d gap_k / d beta = -l_k. Only the drive zone counts (pins with at least half the largest arm on
that side): it holds the first contact of any positive clearance, and with an interference
(negative gaps) it gives the signed angle the loaded pins are pressed in, instead of the
meaningless angle of a root pin whose arm vanishes. Negative backlash = interference (preload).

Closed forms (first order in the modifications, derived from c(t) above and checked against the
numerical gaps in tests/test_clearance.py). With pin phase phi = 2 pi k / zp - psi_c,
K1 = E zp / R, S = sqrt(1 + K1^2 - 2 K1 cos phi), modifications dR (offset), dRr (equidistant):
    normal gap in the conjugate pose   D0(phi) = dRr - dR (1 - K1 cos phi) / S
    moment arm about the disc centre   l(phi)  = E zc sin phi / S   (normal through the pitch point)
    one-side backlash (continuous phi) b0 = (dRr - dR sqrt(1 - K1^2)) / (E zc)   at cos phi = K1
    clearance after taking up b0       D(phi) = D0 - b0 l
                                       = dRr (1 - sin phi / S) - dR (1 - K1 cos phi - sqrt(1-K1^2) sin phi) / S
(the last is the textbook "initial clearance" form). Minimum conjugate-pose gap:
dRr - dR sqrt(1 - K1^2) for dR <= 0 (at cos phi = K1), dRr - dR otherwise (at phi = 0).
A profile rotation delta shifts the two sides: b+ = b0 - delta, b- = b0 + delta.

Limits: rigid bodies, no load; gaps are 2D (the disc section); the closed forms are first order in
dR, dRr: the foot point moves with the modification, a second-order error that is largest at the
tooth roots, where the pin-centre curve is sharpest (measured on the RV-40E: 0.025 um of a 12 um
conjugate-pose gap; 0.02 % on the backlash; the textbook D(phi) after turning by b0 is off by up
to 1.3 um within 0.4 rad of phi = 0 and by 0.02 um elsewhere). Use the numerical gaps.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

from geometry import pin_profile
from geometry.params import CaseError, ReducerCase
# re-exported for their callers (geometry.solids, pipeline.cmd_geometry); their home is pin_profile
from geometry.pin_profile import min_convex_radius_mm, theoretical_curve  # noqa: F401
from geometry.profile import profile_args

ARCMIN_PER_RAD = 180.0 * 60.0 / math.pi


# ----------------------------------------------------------------------------- foot points
def _nearest(args: dict, qx: np.ndarray, qy: np.ndarray, samples_per_tooth: int = 64):
    """Signed distance to the profile (> 0 outside the disc), foot point and outward normal."""
    foot = pin_profile.nearest(qx, qy, args["R"], args["E"], args["zp"], args["rotation_rad"],
                               samples_per_tooth)
    p = foot.profile_point_mm(args["Rr"])
    return foot.distance_mm + args["Rr"], (p[:, 0], p[:, 1]), (foot.normal[:, 0], foot.normal[:, 1])


def distance_to_profile_mm(case: ReducerCase, points_mm: np.ndarray, *, modified: bool = True,
                           clocking_rad: float = 0.0) -> np.ndarray:
    """Signed distance of points (n, 2) in the disc frame to the profile (> 0 outside the disc);
    `clocking_rad` turns the profile (the second disc is clocked by half a tooth)."""
    args = profile_args(case, modified=modified)
    args["rotation_rad"] += clocking_rad
    pts = np.asarray(points_mm, float).reshape(-1, 2)
    return _nearest(args, pts[:, 0], pts[:, 1])[0]


# ----------------------------------------------------------------------------- pin contacts
@dataclass(frozen=True)
class PinContacts:
    """Per-pin geometry of one disc in one pose (arrays of shape (zp,)); disc frame, mm."""
    gap_mm: np.ndarray         # normal gap, pin surface to profile (0 tangent, < 0 interference)
    point_mm: np.ndarray       # (zp, 2) foot point on the profile
    normal: np.ndarray         # (zp, 2) outward unit normal of the profile at the foot point
    arm_mm: np.ndarray         # moment arm about the disc centre, d gap / d beta = -arm
    phase_rad: np.ndarray      # pin phase phi = 2 pi k / zp - psi_c, wrapped to (-pi, pi]


def pin_radius_mm(case: ReducerCase) -> float:
    """Actual pin radius (nominal + error)."""
    return case.cycloid.pin_radius_mm + case.errors.pin_radius_um * 1e-3


def pin_centres_mm(case: ReducerCase) -> np.ndarray:
    """(zp, 2) actual pin centres in the ground frame."""
    c = case.cycloid
    r = c.pin_circle_radius_mm + case.errors.pin_circle_radius_um * 1e-3
    a = 2 * np.pi * np.arange(c.zp) / c.zp
    return r * np.column_stack([np.cos(a), np.sin(a)])


def pin_contacts(case: ReducerCase, crank_angle_rad: float, *, modified: bool = True,
                 disc_rotation_rad: float = 0.0, samples_per_tooth: int = 64) -> PinContacts:
    """Gaps, foot points, normals and moment arms of all pins for a disc at crank angle psi_c."""
    c = case.cycloid
    args = profile_args(case, modified=modified)
    E = c.eccentricity_mm
    theta = -crank_angle_rad / c.zc + disc_rotation_rad
    centre = E * np.array([math.cos(crank_angle_rad), math.sin(crank_angle_rad)])
    rel = pin_centres_mm(case) - centre
    ct, st = math.cos(-theta), math.sin(-theta)
    qx, qy = ct * rel[:, 0] - st * rel[:, 1], st * rel[:, 0] + ct * rel[:, 1]
    dist, (px, py), (nx, ny) = _nearest(args, qx, qy, samples_per_tooth)
    gap = dist - pin_radius_mm(case)
    arm = px * ny - py * nx
    phase = np.angle(np.exp(1j * (2 * np.pi * np.arange(c.zp) / c.zp - crank_angle_rad)))
    return PinContacts(gap, np.column_stack([px, py]), np.column_stack([nx, ny]), arm, phase)


def pin_distances_mm(case: ReducerCase, crank_angle_rad: float, *, modified: bool = True,
                     disc_rotation_rad: float = 0.0) -> np.ndarray:
    """(zp,) normal gap from each pin to the profile (pin-centre distance minus pin radius)."""
    return pin_contacts(case, crank_angle_rad, modified=modified,
                        disc_rotation_rad=disc_rotation_rad).gap_mm


# ----------------------------------------------------------------------------- clearance, backlash
def min_clearance_mm(case: ReducerCase, *, modified: bool = True, samples: int = 48) -> float:
    """Smallest conjugate-pose gap over all pins and crank angles (one pin pitch of psi_c
    sampled, the pattern repeats every 2 pi / zp; the smallest sample is refined)."""
    zp = case.cycloid.zp
    pitch = 2 * np.pi / zp
    psis = np.linspace(0.0, pitch, samples, endpoint=False)
    gaps = np.array([pin_distances_mm(case, p, modified=modified) for p in psis])
    i, k = np.unravel_index(np.argmin(gaps), gaps.shape)
    from scipy.optimize import minimize_scalar
    h = pitch / samples
    res = minimize_scalar(lambda p: pin_distances_mm(case, p, modified=modified)[k],
                          bounds=(psis[i] - h, psis[i] + h), method="bounded",
                          options={"xatol": 1e-10})
    return float(min(res.fun, gaps[i, k]))


@dataclass(frozen=True)
class Backlash:
    """Free output rotation from the conjugate pose to first pin contact, each way [arcmin]."""
    plus_arcmin: float         # disc/output turning in +z (counter-clockwise)
    minus_arcmin: float        # turning in -z
    crank_angle_rad: float

    @property
    def total_arcmin(self) -> float:
        return self.plus_arcmin + self.minus_arcmin


DRIVE_ZONE_ARM_FRACTION = 0.5


def _drive_zone(arm: np.ndarray) -> np.ndarray:
    """Pins that can take up the backlash on one side: arm >= half the largest. The first contact
    of a positive clearance lies there (at cos phi = K1, where l = E zc); pins near the roots,
    with vanishing arms, would otherwise turn an interference into a meaningless huge angle."""
    return arm >= DRIVE_ZONE_ARM_FRACTION * np.max(arm)


def _side_root(case: ReducerCase, crank_angle_rad: float, sign: int, modified: bool) -> float:
    """Rotation (rad, along `sign`) at which the first pin that closes this way touches."""
    c0 = pin_contacts(case, crank_angle_rad, modified=modified)
    closing = _drive_zone(sign * c0.arm_mm)

    def f(beta: float) -> float:
        return float(np.min(pin_distances_mm(case, crank_angle_rad, modified=modified,
                                             disc_rotation_rad=sign * beta)[closing]))

    est = float(np.min(c0.gap_mm[closing] / np.abs(c0.arm_mm[closing])))
    span = max(abs(est), 1e-7)
    lo, hi = est - span, est + span
    for _ in range(60):                       # f falls with beta: widen until it brackets
        if f(lo) > 0 and f(hi) < 0:
            break
        lo, hi = lo - span, hi + span
        span *= 2
    else:
        raise CaseError(f"{case.source or case.name}: backlash root not bracketed near {est:g} rad")
    return brentq(f, lo, hi, xtol=1e-15, rtol=4 * np.finfo(float).eps)


def backlash(case: ReducerCase, crank_angle_rad: float = 0.0, *, modified: bool = True) -> Backlash:
    """Numerical backlash at one crank angle (eccentric fixed, disc turned both ways)."""
    plus = _side_root(case, crank_angle_rad, +1, modified)
    minus = _side_root(case, crank_angle_rad, -1, modified)
    return Backlash(plus * ARCMIN_PER_RAD, minus * ARCMIN_PER_RAD, crank_angle_rad)


def backlash_arcmin(case: ReducerCase, crank_angle_rad: float = 0.0) -> float:
    """Total (both directions) output backlash of the modified disc [arcmin]."""
    return backlash(case, crank_angle_rad).total_arcmin


# ----------------------------------------------------------------------------- closed forms
def _k1(case: ReducerCase) -> float:
    c = case.cycloid
    return c.eccentricity_mm * c.zp / c.pin_circle_radius_mm


def _effective_mods_mm(case: ReducerCase) -> tuple[float, float]:
    """(dR, dRr) with the pin errors folded in: a bigger pin acts as a smaller equidistant, a
    bigger pin circle as a smaller offset."""
    m, e = case.modification, case.errors
    return m.offset_mm - e.pin_circle_radius_um * 1e-3, m.equidistant_mm - e.pin_radius_um * 1e-3


def closed_form_gap_mm(case: ReducerCase, phase_rad: np.ndarray) -> np.ndarray:
    """D0(phi) = dRr - dR (1 - K1 cos phi) / S: conjugate-pose normal gap (first order)."""
    k1, phi = _k1(case), np.asarray(phase_rad, float)
    dR, dRr = _effective_mods_mm(case)
    S = np.sqrt(1 + k1**2 - 2 * k1 * np.cos(phi))
    return dRr - dR * (1 - k1 * np.cos(phi)) / S


def closed_form_arm_mm(case: ReducerCase, phase_rad: np.ndarray) -> np.ndarray:
    """l(phi) = E zc sin phi / S: moment arm of the normal through the pitch point."""
    k1, phi = _k1(case), np.asarray(phase_rad, float)
    S = np.sqrt(1 + k1**2 - 2 * k1 * np.cos(phi))
    return case.cycloid.eccentricity_mm * case.cycloid.zc * np.sin(phi) / S


def closed_form_min_clearance_mm(case: ReducerCase) -> float:
    """min over phi of D0: dRr - dR sqrt(1 - K1^2) (dR <= 0, at cos phi = K1) or dRr - dR."""
    dR, dRr = _effective_mods_mm(case)
    return dRr - dR * (math.sqrt(1 - _k1(case) ** 2) if dR <= 0 else 1.0)


def closed_form_backlash(case: ReducerCase, crank_angle_rad: float | None = None) -> Backlash:
    """b+- = b0 -+ delta with b0 = (dRr - dR sqrt(1-K1^2)) / (E zc) over continuous phi
    (crank_angle_rad None: the bound every crank angle approaches), or min over the actual pins
    of D0 / |l| at a crank angle."""
    delta = math.radians(case.modification.rotation_deg)
    c = case.cycloid
    if crank_angle_rad is None:
        dR, dRr = _effective_mods_mm(case)
        b0 = (dRr - dR * math.sqrt(1 - _k1(case) ** 2)) / (c.eccentricity_mm * c.zc)
        plus, minus = b0, b0
        crank = float("nan")
    else:
        phi = 2 * np.pi * np.arange(c.zp) / c.zp - crank_angle_rad
        gap, arm = closed_form_gap_mm(case, phi), closed_form_arm_mm(case, phi)
        with np.errstate(divide="ignore"):
            ratio = gap / np.abs(arm)
        plus = float(np.min(ratio[_drive_zone(arm)]))
        minus = float(np.min(ratio[_drive_zone(-arm)]))
        crank = crank_angle_rad
    return Backlash((plus - delta) * ARCMIN_PER_RAD, (minus + delta) * ARCMIN_PER_RAD, crank)


def initial_clearance_mm(case: ReducerCase, phase_rad: np.ndarray) -> np.ndarray:
    """Textbook initial clearance D(phi) = D0 - b0 l: gap left at each pin once the disc has
    turned through the one-side backlash b0 (zero at cos phi = K1)."""
    c = case.cycloid
    dR, dRr = _effective_mods_mm(case)
    b0 = (dRr - dR * math.sqrt(1 - _k1(case) ** 2)) / (c.eccentricity_mm * c.zc)
    return closed_form_gap_mm(case, phase_rad) - b0 * closed_form_arm_mm(case, phase_rad)
