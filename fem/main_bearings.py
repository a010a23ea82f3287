"""The RV's built-in main bearings: a preloaded pair of angular contact ball bearings between the
carrier (inner rings on the plate rims) and the housing, ball by ball (SI units).

Ball-raceway contact: Hertz point contact with the Brewe-Hamrock approximations (Hamrock & Brewe,
J. Lubr. Technol. 105 (1983) 171; Hamrock & Dowson, Ball Bearing Lubrication, 1981): for
curvature radii R_x < R_y, alpha_r = R_y / R_x, 1/R = 1/R_x + 1/R_y, E' = E / (1 - nu^2),
  k = 1.0339 alpha_r^0.636, Ecal = 1.0003 + 0.5968 / alpha_r, Fcal = 1.5277 + 0.6023 ln(alpha_r),
  delta = Fcal [9 / (2 Ecal R) (Q / (pi k E'))^2]^(1/3), i.e. Q = K delta^1.5,
  K = pi k E' sqrt(2 Ecal R / (9 Fcal^3));
inner contact R_x = D_w (1 - gamma) / 2, outer R_x = D_w (1 + gamma) / 2, gamma = D_w cos a0 / d_m,
R_y = f D_w / (2 f - 1); the ball's two contacts in series (K = (K_i^-2/3 + K_o^-2/3)^-3/2, Harris).
Checked against the exact Hertz ellipse (complete elliptic integrals) in the tests.

Pair (Jones / Harris, rigid rings, no centrifugal load: an RV turns at ~15 rpm): inner rings
(carrier) displaced by u (radial, along psi = 0), w (axial) and tilt theta about the normal at the
pair centre; the groove curvature centres of a ball at azimuth psi in row b (axial position z_b,
sense s_b) are apart by
  A1 = A sin a0 + s_b (w - theta R_i cos psi) + a_pre,  A2 = A cos a0 + (u + theta z_b) cos psi,
  delta = sqrt(A1^2 + A2^2) - A,  A = (f_i + f_o - 1) D_w,  R_i = d_m/2 - (f_i - 1/2) D_w cos a0,
so the contact angle follows the load. Back-to-back (O: pressure centres outside the pair, s_b =
-sign z_b), the RV's arrangement for tilt rigidity. Fixed-position preload: a_pre from the preload
F_pre each row carries at no external load. Forces and the tangent stiffness from the potential
sum (2/5) K delta^2.5 (analytic gradient and Hessian, so the contact-angle change is in it).
Closed-form check: at no external load every ball carries Q0, k_b = 1.5 Q0 / delta0, and
  K_radial = Z [k_b cos^2 a + Q0 sin^2 a / S0],
  K_tilt = sum_b Z/2 [k_b lambda_b^2 + Q0 (R_i^2 + z_b^2 - lambda_b^2) / S0],
  lambda_b = z_b cos a - s_b R_i sin a,  S0 = A + delta0.

Operating load (operating_load): the two discs push the pins (housing) and the cranks (carrier)
with opposite resultants R_d = T_d / (z_c e), T_d = 0.55 T and 0.45 T (fem.tapered_roller's split)
at their mid-planes one disc width apart: a moment (R_1 + R_2) w / 2 = T w / (2 z_c e) about the
pair centre (the disc stack centred between the rows, ASSUMED) and a net radial force
(R_1 - R_2) = 0.1 T / (z_c e).

Limits: rigid rings and seats (the plate rims and housing are the FE's), no ball spin or
gyroscopic moments, one contact-angle free geometry for every ball.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

from fem import tapered_roller
from geometry.artifacts import InputError

HERTZ_SOURCE = "Hertz point contact, Brewe-Hamrock approximation (Hamrock & Brewe 1983)"


def hertz_point_constant(Rx_m: float, Ry_m: float, E_Pa: float, nu: float) -> float:
    """K [N/m^1.5] of Q = K delta^1.5 (module doc); Rx, Ry may come in either order."""
    Rx, Ry = min(Rx_m, Ry_m), max(Rx_m, Ry_m)
    ar = Ry / Rx
    k = 1.0339 * ar ** 0.636
    Ec = 1.0003 + 0.5968 / ar
    Fc = 1.5277 + 0.6023 * math.log(ar)
    R = 1.0 / (1.0 / Rx + 1.0 / Ry)
    Ep = E_Pa / (1 - nu * nu)
    return math.pi * k * Ep * math.sqrt(2 * Ec * R / (9 * Fc ** 3))


@dataclass(frozen=True)
class BallPair:
    pitch_diameter_m: float
    ball_diameter_m: float
    ball_count: int
    contact_angle_rad: float
    inner_conformity: float
    outer_conformity: float
    spacing_m: float
    preload_N: float
    E_Pa: float = 206e9
    nu: float = 0.3

    @property
    def groove_distance_m(self) -> float:
        return (self.inner_conformity + self.outer_conformity - 1) * self.ball_diameter_m

    @property
    def inner_groove_radius_m(self) -> float:
        """R_i: radius of the inner groove curvature centres (the tilt lever of the axial shift)."""
        return self.pitch_diameter_m / 2 - (self.inner_conformity - 0.5) * self.ball_diameter_m * math.cos(
            self.contact_angle_rad)

    @property
    def ball_constant(self) -> float:
        """K [N/m^1.5] of one ball, both contacts in series."""
        Dw, g = self.ball_diameter_m, self.ball_diameter_m * math.cos(self.contact_angle_rad) / self.pitch_diameter_m
        Ki = hertz_point_constant(Dw * (1 - g) / 2, self.inner_conformity * Dw / (2 * self.inner_conformity - 1),
                                  self.E_Pa, self.nu)
        Ko = hertz_point_constant(Dw * (1 + g) / 2, self.outer_conformity * Dw / (2 * self.outer_conformity - 1),
                                  self.E_Pa, self.nu)
        return (Ki ** (-2 / 3) + Ko ** (-2 / 3)) ** (-1.5)


def _rows(p: BallPair):
    z = np.array([-p.spacing_m / 2, p.spacing_m / 2])
    return z, -np.sign(z)                          # O arrangement: s_b = -sign z_b


def _preload_shift_m(p: BallPair) -> float:
    """a_pre: axial pre-approach of each row giving F_pre = Z Q sin(a) at no external load."""
    A, a0, K, Z = p.groove_distance_m, p.contact_angle_rad, p.ball_constant, p.ball_count
    if p.preload_N <= 0:
        return 0.0

    def axial(a):
        A1, A2 = A * math.sin(a0) + a, A * math.cos(a0)
        S = math.hypot(A1, A2)
        return Z * K * max(S - A, 0.0) ** 1.5 * A1 / S - p.preload_N
    return brentq(axial, 0.0, A, xtol=1e-15)


def _state(p: BallPair, q: np.ndarray, a_pre: float):
    """Force on the inner rings [N, N, N m], its Jacobian d F / d q, ball loads (2, Z), angles."""
    u, w, th = q
    A, a0, K, Z = p.groove_distance_m, p.contact_angle_rad, p.ball_constant, p.ball_count
    psi = 2 * math.pi * np.arange(Z) / Z
    c = np.cos(psi)
    Ri = p.inner_groove_radius_m
    zs, sense = _rows(p)
    F, J = np.zeros(3), np.zeros((3, 3))
    Q, ang = np.zeros((2, Z)), np.zeros((2, Z))
    for b in range(2):
        A1 = A * math.sin(a0) + sense[b] * (w - th * Ri * c) + a_pre
        A2 = A * math.cos(a0) + (u + th * zs[b]) * c
        S = np.hypot(A1, A2)
        d = np.maximum(S - A, 0.0)
        Qb = K * d ** 1.5
        kb = 1.5 * K * np.sqrt(d)
        d1 = [np.zeros(Z), np.full(Z, sense[b]), -sense[b] * Ri * c]     # dA1 / d(u, w, th)
        d2 = [c, np.zeros(Z), zs[b] * c]                                  # dA2 / d(u, w, th)
        g = [(A1 * d1[i] + A2 * d2[i]) / S for i in range(3)]
        for i in range(3):
            F[i] -= np.sum(Qb * g[i])
            for j in range(3):
                hess = (d1[i] * d1[j] + d2[i] * d2[j] - g[i] * g[j]) / S
                J[i, j] -= np.sum(kb * g[i] * g[j] + Qb * hess)
        Q[b], ang[b] = Qb, np.arctan2(A1, A2)
    return F, J, Q, ang


@dataclass(frozen=True)
class PairSolution:
    q: np.ndarray                   # u [m], w [m], theta [rad]
    stiffness: np.ndarray           # (3, 3) tangent [N/m, N/rad, N m/rad ...]
    ball_load_N: np.ndarray         # (2, Z)
    contact_angle_rad: np.ndarray   # (2, Z)

    @property
    def condensed(self) -> np.ndarray:
        """(u, theta) tangent with the axial DOF free (no external axial load)."""
        K, i = self.stiffness, [0, 2]
        return K[np.ix_(i, i)] - np.outer(K[i, 1], K[1, i]) / K[1, 1]

    @property
    def radial_stiffness_N_per_m(self) -> float:
        return float(self.condensed[0, 0])

    @property
    def tilt_stiffness_Nm_per_rad(self) -> float:
        return float(self.condensed[1, 1])

    @property
    def unloaded_balls(self) -> int:
        return int(np.sum(self.ball_load_N <= 0))


def solve(p: BallPair, Fr_N: float = 0.0, M_Nm: float = 0.0, Fa_N: float = 0.0) -> PairSolution:
    """Equilibrium of the inner rings under F_r (along psi = 0), M (tilt) and F_a; Newton with step
    halving on the scaled residual."""
    a_pre = _preload_shift_m(p)
    ext = np.array([Fr_N, Fa_N, M_Nm])
    scale = np.array([1.0, 1.0, 1.0 / max(p.pitch_diameter_m, p.spacing_m)])
    # no preload: every ball is at zero approach and the Jacobian singular; start a step into the load
    q = np.zeros(3) if p.preload_N > 0 else 1e-7 * np.sign(ext) * np.array([1.0, 1.0, 1.0 / p.spacing_m])
    tol = 1e-10 * max(abs(Fr_N) + abs(Fa_N) + abs(M_Nm) * scale[2] + p.preload_N, 1.0)
    for _ in range(200):
        F, J, _, _ = _state(p, q, a_pre)
        r = F + ext
        base = np.linalg.norm(r * scale)
        if base < tol:
            break
        dq = -np.linalg.lstsq(J, r, rcond=None)[0]
        t = 1.0
        while t > 1e-8:
            trial = q + t * dq
            if np.linalg.norm((_state(p, trial, a_pre)[0] + ext) * scale) < base:
                break
            t *= 0.5
        q = trial
    else:
        raise InputError(f"main bearing pair: no equilibrium for F_r = {Fr_N:g} N, M = {M_Nm:g} N m, "
                         f"F_a = {Fa_N:g} N (beyond the pair's reach?)")
    F, J, Q, ang = _state(p, q, a_pre)
    return PairSolution(q, -J, Q, ang)


def preloaded_closed_form(p: BallPair) -> tuple[float, float]:
    """(radial [N/m], tilt [N m/rad]) at no external load (module doc)."""
    a_pre = _preload_shift_m(p)
    A, a0, K, Z = p.groove_distance_m, p.contact_angle_rad, p.ball_constant, p.ball_count
    A1, A2 = A * math.sin(a0) + a_pre, A * math.cos(a0)
    S0 = math.hypot(A1, A2)
    d0 = S0 - A
    a = math.atan2(A1, A2)
    Q0, kb = K * d0 ** 1.5, 1.5 * K * math.sqrt(d0)
    Ri = p.inner_groove_radius_m
    zs, sense = _rows(p)
    k_rad = Z * (kb * math.cos(a) ** 2 + Q0 * math.sin(a) ** 2 / S0)
    lam = zs * math.cos(a) - sense * Ri * math.sin(a)
    k_tilt = sum(Z / 2 * (kb * lb ** 2 + Q0 * (Ri ** 2 + z ** 2 - lb ** 2) / S0) for lb, z in zip(lam, zs))
    return k_rad, k_tilt


# ---------------------------------------------------------------- the case's pair
def case_pair(case) -> BallPair:
    mb, mat = case.main_bearings, case.material
    return BallPair(mb.pitch_diameter_mm * 1e-3, mb.ball_diameter_mm * 1e-3, mb.ball_count,
                    math.radians(mb.contact_angle_deg), mb.inner_conformity, mb.outer_conformity,
                    mb.spacing_mm * 1e-3, mb.preload_N, mat.youngs_modulus_GPa * 1e9, mat.poisson_ratio)


def operating_load(case, torque_Nm: float) -> dict:
    """The discs' load on the main bearings at output torque T (module doc)."""
    cy = case.cycloid
    base = torque_Nm / (cy.zc * cy.eccentricity_mm * 1e-3)
    share = tapered_roller.crank_support_load_N(case, torque_Nm)["disc_resultant_N"] / base if base else 0.55
    if cy.disc_count == 1:
        return {"moment_Nm": 0.0, "radial_N": base, "source": "one disc: its resultant T / (z_c e)"}
    return {"moment_Nm": base * cy.width_mm * 1e-3 / 2, "radial_N": (2 * share - 1) * base,
            "source": "two discs' opposite resultants T_d / (z_c e), T_d = 0.55 T and 0.45 T, one disc width "
                      "apart: M = T w / (2 z_c e), F_r = 0.1 T / (z_c e)"}


def case_main_bearings(case, torque_Nm: float | None = None) -> dict:
    """Radial and tilt tangent stiffness of the case's pair at the operating load of `torque_Nm`
    (rated by default), with the preloaded closed form as the check (at no external load)."""
    p = case_pair(case)
    T = case.rated_torque_Nm if torque_Nm is None else torque_Nm
    ld = operating_load(case, T)
    op = solve(p, ld["radial_N"], ld["moment_Nm"])
    zero = solve(p)
    k_rad, k_tilt = preloaded_closed_form(p)
    return {"radial_stiffness_N_per_m": op.radial_stiffness_N_per_m,
            "tilt_stiffness_Nm_per_rad": op.tilt_stiffness_Nm_per_rad,
            "operating_moment_Nm": ld["moment_Nm"], "operating_radial_N": ld["radial_N"],
            "tilt_rad": float(op.q[2]), "radial_m": float(op.q[0]), "unloaded_balls": op.unloaded_balls,
            "max_ball_load_N": float(op.ball_load_N.max()),
            "check": {"zero_load_radial_N_per_m": zero.radial_stiffness_N_per_m,
                      "closed_form_radial_N_per_m": k_rad,
                      "zero_load_tilt_Nm_per_rad": zero.tilt_stiffness_Nm_per_rad,
                      "closed_form_tilt_Nm_per_rad": k_tilt,
                      "radial_error": zero.radial_stiffness_N_per_m / k_rad - 1,
                      "tilt_error": zero.tilt_stiffness_Nm_per_rad / k_tilt - 1},
            "source": (f"{HERTZ_SOURCE}; back-to-back pair ball by ball (Jones / Harris), rigid rings, "
                       f"fixed-position preload {p.preload_N:g} N per row; {ld['source']}")}
