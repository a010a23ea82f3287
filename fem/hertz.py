"""Closed forms the FE results are checked against (SI units throughout).

- Hertz line contact (Johnson, Contact Mechanics, 1985, sec. 4.2, eqs. 4.43-4.45):
  p0 = sqrt(P' E* / (pi R')),  b = sqrt(4 P' R' / (pi E*)),  P' = F / L the load per length,
  1/R' = 1/R1 + 1/R2 (a concave surface has a negative radius), 1/E* = sum (1 - nu^2)/E.
- Approach of line contacts. 2D displacements are logarithmic, so an approach needs a datum:
  cylinder centre to contact (Johnson eq. 5.36): delta = P'(1 - nu^2)/(pi E) (2 ln(4R/b) - 1);
  half-plane surface to a point at depth d on the load axis: integral of the plane-strain strain
  under McEwen's subsurface stresses of the Hertz pressure (Johnson eq. 4.75), done numerically.
- Palmgren's empirical line-contact approach (Palmgren, Ball and Roller Bearing Engineering,
  1959; Harris & Kotzalas, Rolling Bearing Analysis / Essential Concepts, line-contact deformation):
  delta_mm = 3.84e-5 Q_N^0.9 / l_mm^0.8 for ONE roller-raceway contact (steel on steel; load-
  deflection constant K = 8.06e4 l^(8/9) N/mm^(10/9) per contact). A roller between two races
  has two such contacts in series: delta = 7.68e-5 Q^0.9 / l^0.8 (K_n = K / 2^(10/9) = 3.73e4
  l^(8/9)). ISO/TS 16281 (and DIN 26281) give the roller's two contacts as c_L = 35948 L_we^(8/9),
  i.e. 7.93e-5 Q^0.9 / L^0.8: 3 % softer, the same physics. The 2D FE of fem.bearing lands on the
  two-contact figure (FE / Palmgren 0.96..1.03, tests/test_fem_bearing.py). Also the Stribeck
  load of the most loaded roller of a line-contact bearing with zero clearance,
  Q_max = 4.08 F_r / Z (Harris & Kotzalas; Stribeck 1901 with the line-contact exponent).
- Lame thick cylinder under internal/external pressure (Timoshenko & Goodier sec. 28).
- Euler-Bernoulli/Timoshenko beams and Saint-Venant torsion of circular shafts.

Limits: frictionless, linear elastic, small strain, semi-infinite bodies for Hertz (b << radii).
"""
from __future__ import annotations

import math

import numpy as np
from scipy.integrate import quad


def plane_strain_modulus(E_Pa: float, nu: float) -> float:
    """E / (1 - nu^2)."""
    return E_Pa / (1.0 - nu * nu)


def contact_modulus(E1_Pa: float, nu1: float, E2_Pa: float | None = None, nu2: float | None = None) -> float:
    """E* with 1/E* = (1 - nu1^2)/E1 + (1 - nu2^2)/E2 (second body defaults to the first)."""
    E2_Pa = E1_Pa if E2_Pa is None else E2_Pa
    nu2 = nu1 if nu2 is None else nu2
    return 1.0 / (1.0 / plane_strain_modulus(E1_Pa, nu1) + 1.0 / plane_strain_modulus(E2_Pa, nu2))


def effective_radius(R1_m: float, R2_m: float = math.inf) -> float:
    """R' with 1/R' = 1/R1 + 1/R2; R2 = inf is a flat, R2 < 0 a concave counter-surface."""
    inv = 1.0 / R1_m + (0.0 if math.isinf(R2_m) else 1.0 / R2_m)
    if inv <= 0:
        raise ValueError(f"conformal or concave-dominated contact: 1/R1 + 1/R2 = {inv:g} 1/m must be > 0")
    return 1.0 / inv


def hertz_line(force_N, length_m: float, radius_eff_m: float, modulus_eff_Pa: float):
    """(peak pressure p0 [Pa], half-width b [m]) of a Hertz line contact; arrays broadcast."""
    P = np.asarray(force_N, dtype=float) / length_m
    p0 = np.sqrt(P * modulus_eff_Pa / (math.pi * radius_eff_m))
    b = np.sqrt(4.0 * P * radius_eff_m / (math.pi * modulus_eff_Pa))
    return p0, b


def cylinder_centre_approach(force_N, length_m: float, radius_m: float, half_width_m,
                             E_Pa: float, nu: float):
    """Johnson eq. 5.36: compression of a cylinder between its centre and one line contact."""
    P = np.asarray(force_N, dtype=float) / length_m
    return P / (math.pi * plane_strain_modulus(E_Pa, nu)) * (2.0 * np.log(4.0 * radius_m / half_width_m) - 1.0)


def half_plane_approach(force_N: float, length_m: float, half_width_m: float, depth_m: float,
                        E_Pa: float, nu: float) -> float:
    """Shortening of a half-plane between the contact centre and depth d on the load axis,
    plane strain, under a Hertz (elliptic) pressure: integral of eps_z with McEwen's stresses
    sigma_z = -p0 b / sqrt(b^2+z^2), sigma_x = -(p0/b) ((b^2 + 2 z^2)/sqrt(b^2+z^2) - 2 z)."""
    b = half_width_m
    p0 = 2.0 * force_N / length_m / (math.pi * b)

    def eps_z(z: float) -> float:
        s = math.sqrt(b * b + z * z)
        sz = -p0 * b / s
        sx = -(p0 / b) * ((b * b + 2 * z * z) / s - 2 * z)
        return ((1 - nu * nu) * sz - nu * (1 + nu) * sx) / E_Pa

    val, _ = quad(eps_z, 0.0, depth_m, limit=200, points=[b, 10 * b])
    return -val


PALMGREN_CONTACT_MM = 3.84e-5   # delta_mm per Q_N^0.9 / l_mm^0.8, ONE roller-raceway contact (module doc)
ISO16281_ROLLER_C_L = 35948.0   # ISO/TS 16281 roller (both contacts): Q_N = c_L L_mm^(8/9) delta_mm^(10/9)


def palmgren_contact_approach(load_N, length_m: float):
    """Palmgren: approach of ONE steel roller-raceway line contact [m] for a roller load [N]."""
    q = np.maximum(np.asarray(load_N, dtype=float), 0.0)
    return PALMGREN_CONTACT_MM * q ** 0.9 / (length_m * 1e3) ** 0.8 * 1e-3


def palmgren_needle_approach(load_N, length_m: float):
    """Palmgren: approach of one steel needle between two steel races [m] for a roller load [N]:
    its two roller-raceway contacts in series, 2 x 3.84e-5 Q^0.9 / l^0.8 mm (module doc; this
    function used the one-contact figure for the whole roller until the issue-11 audit)."""
    return 2.0 * palmgren_contact_approach(load_N, length_m)


def palmgren_roller_constant(length_m: float) -> float:
    """K_n [N/m^(10/9)] of one roller between two races, Q = K_n delta^(10/9): the inverse of
    palmgren_needle_approach (both contacts)."""
    k_mm = (1.0 / (2.0 * PALMGREN_CONTACT_MM)) ** (10.0 / 9.0) * (length_m * 1e3) ** (8.0 / 9.0)
    return k_mm * 1e3 ** (10.0 / 9.0)        # N/mm^(10/9) -> N/m^(10/9)


def needle_bearing_deflection(radial_load_N, needle_count: int, length_m: float):
    """Radial deflection of a zero-clearance needle bearing: Palmgren approach at Stribeck's
    Q_max = 4.08 F_r / Z (race bending not included)."""
    return palmgren_needle_approach(4.08 * np.asarray(radial_load_N, dtype=float) / needle_count, length_m)


def lame_radial_displacement(r_m, inner_radius_m: float, outer_radius_m: float, p_inner_Pa: float,
                             p_outer_Pa: float, E_Pa: float, nu: float, *, plane_strain: bool = True):
    """Radial displacement u(r) of a thick cylinder under inner/outer pressure (Lame)."""
    a, b = inner_radius_m, outer_radius_m
    r = np.asarray(r_m, dtype=float)
    A = (p_inner_Pa * a * a - p_outer_Pa * b * b) / (b * b - a * a)      # sigma_r = A - B / r^2
    B = (p_inner_Pa - p_outer_Pa) * a * a * b * b / (b * b - a * a)
    if plane_strain:
        return (1 + nu) / E_Pa * ((1 - 2 * nu) * A * r + B / r)
    return ((1 - nu) * A * r + (1 + nu) * B / r) / E_Pa


def circle_inertia(radius_m: float) -> tuple[float, float]:
    """(I, J) of a solid circular section: pi r^4 / 4 and pi r^4 / 2."""
    i = math.pi * radius_m ** 4 / 4.0
    return i, 2.0 * i


def timoshenko_shear_coefficient(nu: float) -> float:
    """Cowper's kappa for a solid circular section: 6 (1 + nu) / (7 + 6 nu)."""
    return 6.0 * (1 + nu) / (7 + 6 * nu)


def cantilever_tip_deflection(force_N: float, length_m: float, radius_m: float, E_Pa: float,
                              nu: float) -> float:
    """Timoshenko cantilever, tip load: F L^3 / (3 E I) + F L / (kappa G A)."""
    I, _ = circle_inertia(radius_m)
    G = E_Pa / (2 * (1 + nu))
    A = math.pi * radius_m ** 2
    return force_N * length_m ** 3 / (3 * E_Pa * I) + force_N * length_m / (timoshenko_shear_coefficient(nu) * G * A)


def shaft_twist(torque_Nm: float, length_m: float, radius_m: float, E_Pa: float, nu: float) -> float:
    """Saint-Venant twist of a solid circular shaft: T L / (G J)."""
    _, J = circle_inertia(radius_m)
    return torque_Nm * length_m / (E_Pa / (2 * (1 + nu)) * J)


def fit_power_law(force_N, deflection_m) -> tuple[float, float]:
    """Least-squares fit of F = k d^n in log-log; returns (k [N/m^n], n)."""
    F = np.asarray(force_N, dtype=float)
    d = np.asarray(deflection_m, dtype=float)
    ok = (F > 0) & (d > 0)
    if ok.sum() < 2:
        raise ValueError("a power-law fit needs at least two positive (force, deflection) pairs")
    n, logk = np.polyfit(np.log(d[ok]), np.log(F[ok]), 1)
    return float(np.exp(logk)), float(n)
