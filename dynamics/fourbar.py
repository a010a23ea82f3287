"""Four-bar original-error model of the RV second stage (paper 000), rigid and elastic.

Two crankshafts A and B of one disc form a four-bar in the carrier frame: crank eccentricities
l1 (A) and l3 (B), disc crank-hole spacing l2 (coupler), output-mechanism (carrier) bearing-hole
spacing l4 (ground link, along +x, origin at crank A's axis). l1 is the input crank at beta1
(angle from the ground link); l3 is the free rocker, as in the paper. Ideal: l1 = l3 = e,
l2 = l4 = 2 r_c sin(pi / n_cranks), a parallelogram with the coupler at beta2 = 0 for every beta1.

Output-angle error: the disc's orientation in the ground frame is set by the pins, so a coupler
(disc) rotation beta2 relative to the carrier is a carrier rotation of -beta2 against the disc:
output_error = -beta2 (positive = output ahead, DESIGN.md's TE sign).

Closure |l1 u(b1) + l2 u(b2) - l4|^2 = l3^2, i.e. A cos b2 + B sin b2 + C = 0, is solved in closed
form (half-angle tangent, cancellation-free residual) on the open branch (continuous with the
parallelogram, beta2 -> 0) and on the crossed branch. The paper's small-angle quadratic
a b2^2 + b b2 + c = 0 (coefficients as printed; c equals A + C) is solved too: its small root is
the open branch, its other root approximates the crossed branch.

Joint displacements (the paper's clearance vectors and elastic l11, l33) are vectors added to the
crank vectors: all joint compliances of a crank are in series along its load path, and the disc
shifts against the carrier along the load it receives from the pins, i.e. along -F (F: force ON
the disc from the eccentric). Clearances are taken up in the same direction (rigid error);
elastic adds needle-bearing (turning-arm) law, crankshaft bending and support-bearing compliance
from stiffness.json. The rocker's effective length uses its nominal angle (the paper's cos-law).

Limits: one disc's crank pair, quasi-static, planar. The real reducer drives every crank through
the sun gear (beta3 = beta1 imposed), so it is over-constrained; the free-rocker four-bar puts
every length mismatch into a coupler rotation and is singular at the dead centres (beta1 -> 0,
180 deg), where the paper's quadratic also breaks down (b -> 0). At beta1 = 90 deg (the paper's
evaluation point) both pictures agree to first order.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from geometry.artifacts import InputError
from dynamics.results import ARCSEC_PER_RAD
from geometry.params import ReducerCase

# Paper 000's tables (seeds/000_eca208c918471efb.txt): ranges as printed, "deg".
PAPER_000 = {
    "eccentricity": {"rigid": (0.0333, 0.0389), "elastic": (0.0335, 0.0390),
                     "trend": "accuracy improves with negative bias", "bias": "negative"},
    "crank_hole": {"rigid": (0.036058, 0.036111), "elastic": (0.03618, 0.03624),
                   "trend": "accuracy improves within tolerance band", "bias": "within band"},
    "output_hole": {"rigid": (0.036008, 0.036123), "elastic": (0.038588, 0.038706),
                    "trend": "accuracy improves with positive bias", "bias": "positive"},
    ("eccentricity", "crank_hole"): {"rigid": (0.0347, 0.0375), "elastic": (0.0355, 0.0383),
                                     "bias": "crankshaft: negative; cycloid: within band"},
    ("eccentricity", "output_hole"): {"rigid": (0.0346, 0.0375), "elastic": (0.0354, 0.0383),
                                      "bias": "crankshaft: negative; output: positive"},
    ("crank_hole", "output_hole"): {"rigid": (0.0358, 0.0362), "elastic": (0.0384, 0.0387),
                                    "bias": "cycloid: negative; output: positive"},
}

# Error source -> the link-length deviations (Build fields) it moves.
SOURCES = {
    "eccentricity": ("d_l1_mm",),                 # crank A's eccentricity; crank B nominal
    "crank_hole": ("d_l2_mm",),                   # disc crank-hole spacing
    "output_hole": ("d_l4_mm",),                  # carrier bearing-hole spacing
    "eccentricity_common": ("d_l1_mm", "d_l3_mm"),  # paper's reading: e of both cranks
}
MAIN_SOURCES = ("eccentricity", "crank_hole", "output_hole")
PAIRS = (("eccentricity", "crank_hole"), ("eccentricity", "output_hole"),
         ("crank_hole", "output_hole"))


class FourBarError(InputError):
    """A request the four-bar model cannot serve (names input, value, allowed range)."""


# ---------------------------------------------------------------- closure kernels (pure numpy)

@dataclass(frozen=True)
class Closure:
    open_rad: np.ndarray      # coupler angle beta2 on the branch continuous with the parallelogram
    crossed_rad: np.ndarray   # the other branch (anti-parallelogram), nan where none


def _terms(l1, l2, l3, l4, beta1):
    l1, l2, l3, l4, beta1 = np.broadcast_arrays(*(np.asarray(v, float) for v in (l1, l2, l3, l4, beta1)))
    c1 = np.cos(beta1)
    # A + C and C - A in factored form: the parallelogram residual without cancellation
    apc = (l1 - l3) * (l1 + l3) + (l2 - l4) ** 2 + 2.0 * l1 * (l2 - l4) * c1
    cma = (l1 - l3) * (l1 + l3) + (l2 + l4) ** 2 - 2.0 * l1 * (l2 + l4) * c1
    b = 2.0 * l1 * l2 * np.sin(beta1)
    return l1, l2, l3, l4, beta1, apc, cma, b


def closure_exact(l1, l2, l3, l4, beta1_rad) -> Closure:
    """Exact coupler angle: (C-A) t^2 + 2B t + (A+C) = 0 with t = tan(beta2/2); nan: no assembly."""
    *_, apc, cma, b = _terms(l1, l2, l3, l4, beta1_rad)
    disc = b * b - cma * apc
    with np.errstate(invalid="ignore", divide="ignore"):
        root = np.sqrt(disc)
        q = b + np.where(b >= 0, 1.0, -1.0) * root        # no cancellation in q
        t_open = -apc / q
        t_cross = -q / cma
        ok = disc >= 0
        return Closure(np.where(ok, 2.0 * np.arctan(t_open), np.nan),
                       np.where(ok, 2.0 * np.arctan(t_cross), np.nan))


def quadratic_coefficients(l1, l2, l3, l4, beta1_rad):
    """Paper 000's a, b, c exactly as printed."""
    l1, l2, l3, l4, beta1 = np.broadcast_arrays(*(np.asarray(v, float) for v in (l1, l2, l3, l4, beta1_rad)))
    a = l2 * l4 - l1 * l2 * np.cos(beta1)
    b = 2.0 * l1 * l2 * np.sin(beta1)
    c = (l1 ** 2 + l2 ** 2 + l4 ** 2 - l3 ** 2 - 2 * l1 * l4 * np.cos(beta1)
         + 2 * l1 * l2 * np.cos(beta1) - 2 * l2 * l4)
    return a, b, c


def closure_quadratic(l1, l2, l3, l4, beta1_rad) -> Closure:
    """Roots of the paper's small-angle quadratic (c taken in the factored, cancellation-free form)."""
    a, b, _ = quadratic_coefficients(l1, l2, l3, l4, beta1_rad)
    c = _terms(l1, l2, l3, l4, beta1_rad)[5]             # algebraically equal to the printed c
    disc = b * b - 4.0 * a * c
    with np.errstate(invalid="ignore", divide="ignore"):
        q = -0.5 * (b + np.where(b >= 0, 1.0, -1.0) * np.sqrt(disc))
        ok = disc >= 0
        return Closure(np.where(ok, c / q, np.nan), np.where(ok, q / a, np.nan))


def closure_sensitivity(l1, l2, l3, l4, beta1_rad) -> np.ndarray:
    """d beta2 / d(l1, l2, l3, l4) [rad/mm] on the open branch, implicit-function theorem.

    At the parallelogram and beta1 = 90 deg: (-1/L, 0, +1/L, 0), L = l2 = l4.
    """
    l1, l2, l3, l4, b1, *_ = _terms(l1, l2, l3, l4, beta1_rad)
    b2 = closure_exact(l1, l2, l3, l4, b1).open_rad
    A = 2 * l2 * (l1 * np.cos(b1) - l4)
    B = 2 * l1 * l2 * np.sin(b1)
    f_b2 = -A * np.sin(b2) + B * np.cos(b2)
    f_l = np.stack([2 * l2 * np.cos(b1 - b2) + 2 * l1 - 2 * l4 * np.cos(b1),
                    2 * (l1 * np.cos(b1) - l4) * np.cos(b2) + 2 * l1 * np.sin(b1) * np.sin(b2) + 2 * l2,
                    -2 * l3,
                    -2 * l2 * np.cos(b2) + 2 * l4 - 2 * l1 * np.cos(b1)], axis=-1)
    return -f_l / f_b2[..., None]


# ---------------------------------------------------------------- geometry, build, loads

@dataclass(frozen=True)
class PairGeometry:
    """Nominal four-bar of crank pair (A, B) = (crank 0, crank 1) and its place on the carrier."""
    eccentricity_mm: float
    spacing_mm: float               # l2 = l4 nominal
    crank_circle_radius_mm: float
    crank_count: int
    ground_angle_rad: float         # direction of O_A -> O_B in the carrier frame

    @classmethod
    def from_case(cls, case: ReducerCase) -> "PairGeometry":
        n = case.carrier.crank_count
        if n < 2:
            raise FourBarError(f"{case.source or case.name}: [carrier] crank_count = {n}: the four-bar "
                               f"model needs at least 2 crankshafts")
        r = case.carrier.crank_circle_radius_mm
        a, b = crank_positions_mm(r, n)[:2]
        d = b - a
        return cls(case.cycloid.eccentricity_mm, float(np.hypot(*d)), r, n, float(math.atan2(d[1], d[0])))

    def to_pair_frame(self, v: np.ndarray) -> np.ndarray:
        """Rotate carrier-frame vectors (..., 2) into the four-bar frame (ground link on +x)."""
        c, s = math.cos(-self.ground_angle_rad), math.sin(-self.ground_angle_rad)
        v = np.asarray(v, float)
        return np.stack([c * v[..., 0] - s * v[..., 1], s * v[..., 0] + c * v[..., 1]], axis=-1)


def crank_positions_mm(radius_mm: float, count: int) -> np.ndarray:
    """Crank axes on the carrier: crank k at angle 2 pi k / n (carrier frame)."""
    ang = 2 * np.pi * np.arange(count) / count
    return radius_mm * np.stack([np.cos(ang), np.sin(ang)], axis=-1)


@dataclass(frozen=True)
class Build:
    """Deviations of one build from the ideal [mm]; floats or broadcastable arrays."""
    d_l1_mm: float | np.ndarray = 0.0
    d_l2_mm: float | np.ndarray = 0.0
    d_l3_mm: float | np.ndarray = 0.0
    d_l4_mm: float | np.ndarray = 0.0
    turning_arm_clearance_mm: tuple = (0.0, 0.0)   # radial clearance at crank A, B
    support_clearance_mm: tuple = (0.0, 0.0)


@dataclass(frozen=True)
class PairLoads:
    """Forces on crank pair (A, B) at one crank angle, four-bar frame.

    turning_arm_N: force ON disc 1 from the eccentrics of crank A and B, (2, 2).
    support_N: the same summed over all discs: what each crank passes to its support bearings
    (with the opposite sign).
    """
    turning_arm_N: np.ndarray
    support_N: np.ndarray
    torque_Nm: float
    beta1_rad: float
    source: str                      # where the forces come from


@dataclass(frozen=True)
class JointCompliance:
    """Joint laws from stiffness.json (SI)."""
    turning_arm_k_N_per_m_pow: float     # needle bearing F = k d^n
    turning_arm_n: float
    crankshaft_bending_N_per_m: float
    support_bearing_N_per_m: float       # per bearing; two per crank share the load

    @classmethod
    def from_stiffness(cls, model) -> "JointCompliance":
        return cls(float(model.turning_arm.law_k_N_per_m_pow), float(model.turning_arm.law_n),
                   float(model.crankshaft_bending_stiffness_N_per_m),
                   float(model.support_bearing_radial_stiffness_N_per_m))

    def turning_arm_mm(self, force_N):
        return 1e3 * (np.asarray(force_N, float) / self.turning_arm_k_N_per_m_pow) ** (1.0 / self.turning_arm_n)


def _unit(v: np.ndarray) -> np.ndarray:
    n = np.linalg.norm(v, axis=-1, keepdims=True)
    return np.divide(v, n, out=np.zeros_like(v), where=n > 0)


def joint_displacements_mm(build: Build, loads: PairLoads, compliance: JointCompliance | None,
                           ) -> tuple[np.ndarray, np.ndarray]:
    """Disc-hole shift against the carrier axis at crank A and B, (..., 2) each, four-bar frame.

    compliance None: clearances only (rigid). Every term points along the load the disc gets
    from the pins (-F), so the clearance and the elastic part add.
    """
    out = []
    for k in range(2):
        f, s = loads.turning_arm_N[k], loads.support_N[k]
        fn, sn = float(np.linalg.norm(f)), float(np.linalg.norm(s))
        ta = np.asarray(build.turning_arm_clearance_mm[k], float)
        sp = np.asarray(build.support_clearance_mm[k], float)
        if compliance is not None:
            ta = ta + compliance.turning_arm_mm(fn) + 1e3 * fn / compliance.crankshaft_bending_N_per_m
            sp = sp + 1e3 * sn / (2.0 * compliance.support_bearing_N_per_m)
        out.append(-ta[..., None] * _unit(f) - sp[..., None] * _unit(s))
    return out[0], out[1]


@dataclass(frozen=True)
class ErrorResult:
    """Output-angle error of a build (rad, positive = output ahead) and the paper's quantity."""
    output_error_rad: np.ndarray            # exact closure, open branch
    quadratic_error_rad: np.ndarray         # the paper's quadratic, small root
    paper_quantity_rad: np.ndarray          # |crossed root of the quadratic|: what paper 000 prints
    rocker_phase_rad: np.ndarray            # beta3 - beta1: what the gear train would have to absorb

    @property
    def output_error_arcsec(self) -> np.ndarray:
        return self.output_error_rad * ARCSEC_PER_RAD


def output_error(geom: PairGeometry, build: Build, beta1_rad: float,
                 displacements: tuple[np.ndarray, np.ndarray] | None = None) -> ErrorResult:
    """Output-angle error of a build at crank angle beta1, with optional joint displacements."""
    e, L = geom.eccentricity_mm, geom.spacing_mm
    l1 = e + np.asarray(build.d_l1_mm, float)
    l3 = e + np.asarray(build.d_l3_mm, float)
    l2 = L + np.asarray(build.d_l2_mm, float)
    l4 = L + np.asarray(build.d_l4_mm, float)
    u = np.array([math.cos(beta1_rad), math.sin(beta1_rad)])
    if displacements is None:
        b1 = np.full(np.broadcast(l1, l3).shape, beta1_rad)
    else:
        da, db = displacements
        v1 = l1[..., None] * u + da
        v3 = l3[..., None] * u + db
        l1, b1 = np.hypot(v1[..., 0], v1[..., 1]), np.arctan2(v1[..., 1], v1[..., 0])
        l3 = np.hypot(v3[..., 0], v3[..., 1])
    ex = closure_exact(l1, l2, l3, l4, b1)
    qd = closure_quadratic(l1, l2, l3, l4, b1)
    # rocker angle from the closed loop: l3 u(b3) = l1 u(b1) + l2 u(b2) - l4
    x = l1 * np.cos(b1) + l2 * np.cos(ex.open_rad) - l4
    y = l1 * np.sin(b1) + l2 * np.sin(ex.open_rad)
    return ErrorResult(-ex.open_rad, -qd.open_rad, np.abs(qd.crossed_rad),
                       np.angle(np.exp(1j * (np.arctan2(y, x) - beta1_rad))))


@dataclass(frozen=True)
class RigidElastic:
    rigid: ErrorResult
    elastic: ErrorResult


def rigid_and_elastic(geom: PairGeometry, build: Build, loads: PairLoads,
                      compliance: JointCompliance) -> RigidElastic:
    """Rigid (geometry + clearances taken up along the load) and elastic (plus compliance) error."""
    rigid = output_error(geom, build, loads.beta1_rad, joint_displacements_mm(build, loads, None))
    elastic = output_error(geom, build, loads.beta1_rad, joint_displacements_mm(build, loads, compliance))
    return RigidElastic(rigid, elastic)


def with_source(build: Build, source: str, deviation_mm) -> Build:
    """A build with one error source set to a deviation (array allowed)."""
    if source not in SOURCES:
        raise FourBarError(f"error source {source!r}: unknown; allowed: {', '.join(SOURCES)}")
    return replace(build, **{f: deviation_mm for f in SOURCES[source]})


# ---------------------------------------------------------------- forces: statics estimate

def statics_pair_loads(case: ReducerCase, geom: PairGeometry, beta1_rad: float,
                       torque_Nm: float) -> PairLoads:
    """Turning-arm forces from a rigid-disc statics estimate (closed form, no lumped model: tests, benches).

    Pins: every pin normal passes through the pitch point (zp E from the housing centre on the line
    of centres); pins whose force turns the disc the loaded way carry load in proportion to their
    lever arm about the disc centre (rigid disc, equal pin stiffness). The pins' moment about the
    disc centre equals the disc's share of the output torque; cranks share the pin resultant
    equally and the moment as equal tangential forces on the crank circle.
    """
    c, n = case.cycloid, geom.crank_count
    E, R, zp = c.eccentricity_mm, c.pin_circle_radius_mm, c.zp
    moment_Nmm = torque_Nm * 1e3 / c.disc_count
    psi = beta1_rad + geom.ground_angle_rad           # eccentric direction in the carrier frame
    pins_deg = np.arange(zp) * 360.0 / zp + 180.0 / zp   # symmetric pin phase about the line of centres
    pins = R * np.stack([np.cos(np.radians(pins_deg)), np.sin(np.radians(pins_deg))], -1)
    pitch = np.array([zp * E, 0.0])
    nrm = _unit(pitch - pins)                          # pin pushes the disc towards the pitch point
    arm = c.zc * E * nrm[:, 1]                         # moment arm about the disc centre (x-frame)
    arm = np.where(arm > 0, arm, 0.0)
    f_pin = moment_Nmm * arm / np.sum(arm ** 2)
    res = (f_pin[:, None] * nrm).sum(0)
    rot = np.array([[math.cos(psi), -math.sin(psi)], [math.sin(psi), math.cos(psi)]])
    res = rot @ res                                    # carrier frame
    cranks = crank_positions_mm(geom.crank_circle_radius_mm, n)[:2]
    tang = np.stack([-cranks[:, 1], cranks[:, 0]], -1) / geom.crank_circle_radius_mm
    # disc 1: F_k = -res/n - M/(n r_c) t_k ; disc 2 (180 deg out of phase): resultant reversed
    f1 = -res / n - moment_Nmm / (n * geom.crank_circle_radius_mm) * tang
    f2 = +res / n - moment_Nmm / (n * geom.crank_circle_radius_mm) * tang
    total = f1 + (f2 if c.disc_count == 2 else 0.0)
    return PairLoads(geom.to_pair_frame(f1), geom.to_pair_frame(total), float(torque_Nm),
                     float(beta1_rad), "statics estimate (rigid disc, equal pin stiffness)")


# ---------------------------------------------------------------- forces: the lumped model

def model_pair_loads(case: ReducerCase, geom: PairGeometry, stiffness, beta1_rad: float,
                     torque_Nm: float) -> PairLoads:
    """Turning-arm forces from the lumped model's static load sharing (dynamics.statics.solve_static)
    at the input angle that puts crank pair (0, 1) at beta1."""
    from dynamics.model import build_model
    from dynamics.statics import solve_static
    model = build_model(case, stiffness)
    s0 = solve_static(model, 0.0, torque_Nm)
    carrier0 = math.radians(s0.output_angle_deg)
    psi0 = float(s0.crank_angle_rad[0]) - carrier0            # eccentric angle on the carrier
    # the eccentric turns against the carrier (zc/zp - ...): measure its rate numerically
    s1 = solve_static(model, 1.0, torque_Nm)
    rate = (float(s1.crank_angle_rad[0]) - math.radians(s1.output_angle_deg) - psi0)  # rad per input deg
    rate = math.atan2(math.sin(rate), math.cos(rate))
    target = beta1_rad + geom.ground_angle_rad
    dpsi = math.atan2(math.sin(target - psi0), math.cos(target - psi0))
    st = solve_static(model, dpsi / rate, torque_Nm)
    carrier = math.radians(st.output_angle_deg)
    c, s = math.cos(-carrier), math.sin(-carrier)
    rot = np.array([[c, -s], [s, c]])
    f = np.asarray(st.bearing_force_N, float) @ rot.T            # (discs, cranks, 2), carrier frame
    psi = float(st.crank_angle_rad[0]) - carrier
    beta1 = math.atan2(math.sin(psi - geom.ground_angle_rad), math.cos(psi - geom.ground_angle_rad))
    return PairLoads(geom.to_pair_frame(f[0, :2]), geom.to_pair_frame(f[:, :2].sum(0)),
                     float(torque_Nm), beta1,
                     f"dynamics.model.solve_static (input {dpsi / rate:.3f} deg)")


# ---------------------------------------------------------------- sweeps

@dataclass(frozen=True)
class Sweep:
    """Errors over deviations of one source (1-D) or a pair (2-D, [i, j] = (dev_a[i], dev_b[j]))."""
    sources: tuple
    deviation_mm: np.ndarray
    rigid_rad: np.ndarray
    elastic_rad: np.ndarray
    paper_rigid_rad: np.ndarray
    paper_elastic_rad: np.ndarray
    quadratic_gap_rad: np.ndarray       # max |exact - quadratic| of the open branch over the sweep
    meta: dict = field(default_factory=dict)


def sweep(geom: PairGeometry, loads: PairLoads, compliance: JointCompliance,
          sources: tuple[str, ...], deviation_mm: np.ndarray, base: Build = Build()) -> Sweep:
    """One source (len 1) over the deviations, or two sources over the grid of deviations."""
    dev = np.asarray(deviation_mm, float)
    if len(sources) == 1:
        build = with_source(base, sources[0], dev)
    elif len(sources) == 2:
        build = with_source(with_source(base, sources[0], dev[:, None]), sources[1], dev[None, :])
    else:
        raise FourBarError(f"sources {sources}: give one or two")
    re = rigid_and_elastic(geom, build, loads, compliance)
    gap = np.nanmax(np.abs(np.concatenate([
        (re.rigid.output_error_rad - re.rigid.quadratic_error_rad).ravel(),
        (re.elastic.output_error_rad - re.elastic.quadratic_error_rad).ravel()])))
    return Sweep(tuple(sources), dev, re.rigid.output_error_rad, re.elastic.output_error_rad,
                 re.rigid.paper_quantity_rad, re.elastic.paper_quantity_rad, np.float64(gap))


def best_bias(dev: np.ndarray, err: np.ndarray, band_frac: float = 0.25, sym_tol: float = 0.05) -> str:
    """Where |error| is smallest: 'negative', 'positive', 'within band' (|dev| < band_frac*max) or
    'either sign' (the mirrored deviation is within sym_tol of the best: an even function)."""
    a = np.abs(err)
    i = int(np.nanargmin(a))
    if abs(dev[i]) <= band_frac * np.max(np.abs(dev)):
        return "within band"
    j = int(np.argmin(np.abs(dev + dev[i])))
    if a[j] - a[i] <= sym_tol * (np.nanmax(a) - a[i]):
        return "either sign"
    return "negative" if dev[i] < 0 else "positive"


def trend(dev: np.ndarray, err: np.ndarray) -> str:
    """A phrase on how |error| changes across the sweep."""
    a = np.abs(err)
    if float(np.nanmax(a) - np.nanmin(a)) < 1e-3 / ARCSEC_PER_RAD:
        return "insensitive (< 0.001 arcsec)"
    lo, mid, hi = a[0], a[len(a) // 2], a[-1]
    if mid <= min(lo, hi):
        return "smallest at nominal, grows both ways"
    if mid >= max(lo, hi):
        return "largest at nominal, falls both ways"
    return "falls toward negative deviation" if lo < hi else "falls toward positive deviation"


def crank_angle_scan(geom: PairGeometry, build: Build, beta1_deg: np.ndarray) -> dict:
    """Output error (-beta2) exact vs quadratic over crank angles, no load [rad]."""
    out = [output_error(geom, build, math.radians(b)) for b in beta1_deg]
    ex = np.array([float(np.squeeze(o.output_error_rad)) for o in out])
    qd = np.array([float(np.squeeze(o.quadratic_error_rad)) for o in out])
    return {"beta1_deg": np.asarray(beta1_deg, float), "exact_rad": ex, "quadratic_rad": qd}
