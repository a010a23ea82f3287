"""Rolling bearings and seals: friction moments (Palmgren), ISO 281 ratings and lives.

Friction (Palmgren 1959, Ball and roller bearing engineering; Harris & Kotzalas 2007, ch. 11):
  M0 = 1e-7 f0 (nu n)^(2/3) dm^3  [N mm]  for nu n >= 2000, else 160e-7 f0 dm^3 (nu cSt, n rpm, dm mm):
       the viscous (no-load) moment of an oil-bath bearing
  M1 = f1 P dm                    [N mm]: the load moment (P the bearing load [N])
Radial lip seal: friction power P = 7.69e-6 d^2 n [W] (d mm, n rpm; Freudenberg Simrit catalogue,
mineral oil at 40-80 C), i.e. a speed-independent moment M = P / omega = 7.34e-5 d^2 [N m].
ISO 281:2007 (radial roller bearings, line contact):
  C_r = b_m f_c (i L_we cos a)^(7/9) Z^(3/4) D_we^(29/27)  [N, mm], b_m = 1.1 (machined rings),
  f_c from Lundberg-Palmgren with lambda nu = 0.83 (reproduces ISO 281 table 7 to 0.1),
  C_0r = 44 (1 - D_we cos a / D_pw) i Z L_we D_we cos a (ISO 76), C_u = C_0r / 8.2 (ISO 281 B.3.2),
  L10 = (C_r / P)^(10/3) 1e6 revolutions, P the cubic-mean (exponent 10/3) load over the cycle,
  L_nm = a1 a_ISO L10 with a_ISO(kappa, e_C C_u / P) of ISO 281 eq. 21-23 (roller bearings, capped at
  50), kappa = nu / nu1, nu1 = 45000 n^-0.83 dm^-0.5 (n < 1000 rpm) or 4500 n^-0.5 dm^-0.5.
"""
from __future__ import annotations

import math

import numpy as np

SEAL_MOMENT_NM_PER_MM2 = 7.69e-6 * 60 / (2 * math.pi)   # P / omega of the Simrit seal power law
B_M_ROLLER = 1.1
A_ISO_MAX = 50.0


def palmgren_no_load_Nm(f0: float, nu_cSt: float, n_rpm: float, dm_mm: float) -> float:
    x = nu_cSt * abs(n_rpm)
    m = 1e-7 * f0 * x ** (2 / 3) * dm_mm ** 3 if x >= 2000 else 160e-7 * f0 * dm_mm ** 3
    return m * 1e-3


def palmgren_load_Nm(f1: float, load_N, dm_mm: float):
    return f1 * np.abs(load_N) * dm_mm * 1e-3


def seal_moment_Nm(diameter_mm: float) -> float:
    return SEAL_MOMENT_NM_PER_MM2 * diameter_mm ** 2


def roller_fc(gamma: float) -> float:
    """ISO 281 f_c of radial roller bearings, gamma = D_we cos(a) / D_pw (Lundberg-Palmgren form)."""
    g = gamma
    t = 1.04 * ((1 - g) / (1 + g)) ** (143 / 108)
    return 207.9 * 0.83 * g ** (2 / 9) * (1 - g) ** (29 / 27) / (1 + g) ** 0.25 * (1 + t ** 4.5) ** (-2 / 9)


def dynamic_rating_N(Z: int, D_we_mm: float, L_we_mm: float, D_pw_mm: float, alpha_deg: float = 0.0,
                     rows: int = 1) -> float:
    ca = math.cos(math.radians(alpha_deg))
    fc = roller_fc(D_we_mm * ca / D_pw_mm)
    return B_M_ROLLER * fc * (rows * L_we_mm * ca) ** (7 / 9) * Z ** 0.75 * D_we_mm ** (29 / 27)


def static_rating_N(Z: int, D_we_mm: float, L_we_mm: float, D_pw_mm: float, alpha_deg: float = 0.0,
                    rows: int = 1) -> float:
    ca = math.cos(math.radians(alpha_deg))
    return 44.0 * (1 - D_we_mm * ca / D_pw_mm) * rows * Z * L_we_mm * D_we_mm * ca


def cubic_mean_load_N(loads_N) -> float:
    """Equivalent constant load of a load cycle sampled at equal rotation steps (exponent 10/3)."""
    f = np.abs(np.asarray(loads_N, float))
    return float(np.mean(f ** (10 / 3)) ** 0.3)


def l10_revolutions(C_N: float, P_N: float) -> float:
    return (C_N / P_N) ** (10 / 3) * 1e6


def rated_viscosity_cSt(n_rpm: float, dm_mm: float) -> float:
    """ISO 281 nu1: the viscosity needed for adequate lubrication."""
    n = abs(n_rpm)
    return 45000 * n ** -0.83 * dm_mm ** -0.5 if n < 1000 else 4500 * n ** -0.5 * dm_mm ** -0.5


def a_iso_roller(kappa: float, ec_cu_over_p: float) -> float:
    """ISO 281:2007 life modification factor of roller bearings (kappa clipped to [0.1, 4])."""
    k = min(max(kappa, 0.1), 4.0)
    if k < 0.4:
        inner = 1.5859 - 1.3993 / k ** 0.054381
    elif k < 1.0:
        inner = 1.5859 - 1.2348 / k ** 0.19087
    else:
        inner = 1.5859 - 1.2348 / k ** 0.071739
    base = 1.0 - inner * max(ec_cu_over_p, 0.0) ** 0.4
    if base <= 0.0:
        return A_ISO_MAX
    return min(0.1 * base ** -9.185, A_ISO_MAX)
