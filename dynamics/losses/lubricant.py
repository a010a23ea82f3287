"""Lubricant and lubrication regime of a line contact: viscosity, EHL film, film parameter, friction.

Laws (each with its source; SI inside):
  viscosity-temperature  Walther (ASTM D341): log10 log10(nu + 0.7) = A - B log10(T / K), nu in cSt,
                         A and B from the grade's 40 and 100 C viscosities; valid between the
                         section's min and max temperature (refused outside)
  density                rho(T) = rho_15 (1 - 6.5e-4 (T - 15 C)) (mineral oil, ASTM D1250 order)
  pressure-viscosity     Barus, alpha from the case (mineral oils 15-25 /GPa)
  EHL film               central film of the isothermal line contact, Pan & Hamrock (1989, J. Tribol.
                         111: 246): h_c / R' = 2.922 U^0.692 G^0.470 W'^-0.166, U = eta0 u_e / (E' R'),
                         G = alpha E', W' = w' / (E' R'); the Dowson-Higginson minimum film
                         h_min / R' = 2.65 U^0.70 G^0.54 W'^-0.13 is kept as its cross-check
  roughness              sigma = sqrt(Rq1^2 + Rq2^2), Rq = sqrt(pi / 2) Ra (Gaussian heights)
  film parameter         Lambda = h_c / sigma
  mixed friction         mu = phi mu_boundary + (1 - phi) mu_full_film, phi(Lambda) = erfc(Lambda / sqrt 2):
                         the share of the composite Gaussian roughness heights that reach through the
                         film (|z| > h; after Tallian 1967, ASLE Trans. 10: 418): 1 at Lambda = 0,
                         0.32 at 1, 0.046 at 2, 0.003 at 3, the usual bounds of the boundary, mixed
                         and full-film regimes
Thermal and starvation corrections to the film are left out (a slow RV contact runs cool; an
oil-bath reducer is flooded): the film is an upper bound at speed, which errs toward low friction.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.special import erfc

from geometry.artifacts import InputError
from geometry.lubrication import Lubrication

KELVIN = 273.15
RQ_PER_RA = math.sqrt(math.pi / 2)       # Gaussian profile: Rq / Ra = 1.2533
DENSITY_PER_K = 6.5e-4                   # mineral oil thermal expansion, 1/K


class LubricationError(InputError):
    """A lubricant section or an oil temperature the laws cannot serve."""


@dataclass(frozen=True)
class Lubricant:
    """A lubricant grade with its Walther constants (build with `from_section`)."""
    section: Lubrication
    walther_A: float
    walther_B: float

    @classmethod
    def from_section(cls, lub: Lubrication) -> "Lubricant":
        if lub.viscosity_100C_cSt >= lub.viscosity_40C_cSt:
            raise LubricationError(f"[lubrication] viscosity_100C_cSt = {lub.viscosity_100C_cSt:g}: must be "
                                   f"below viscosity_40C_cSt = {lub.viscosity_40C_cSt:g} (oils thin when hot)")
        if lub.min_temperature_C >= lub.max_temperature_C:
            raise LubricationError(f"[lubrication] min_temperature_C = {lub.min_temperature_C:g}: must be "
                                   f"below max_temperature_C = {lub.max_temperature_C:g}")
        y1 = math.log10(math.log10(lub.viscosity_40C_cSt + 0.7))
        y2 = math.log10(math.log10(lub.viscosity_100C_cSt + 0.7))
        x1, x2 = math.log10(40 + KELVIN), math.log10(100 + KELVIN)
        B = (y1 - y2) / (x2 - x1)
        return cls(section=lub, walther_A=y1 + B * x1, walther_B=B)

    def check_temperature(self, T_C: float, where: str = "oil temperature") -> None:
        lo, hi = self.section.min_temperature_C, self.section.max_temperature_C
        if not (math.isfinite(T_C) and lo <= T_C <= hi):
            raise LubricationError(f"{where} = {T_C!r} C: outside the lubricant's stated range [{lo:g}, {hi:g}] C "
                                   f"([lubrication] min/max_temperature_C)")

    def kinematic_cSt(self, T_C):
        """Walther / ASTM D341 kinematic viscosity [cSt = mm^2/s]."""
        T = np.asarray(T_C, float) + KELVIN
        return 10.0 ** (10.0 ** (self.walther_A - self.walther_B * np.log10(T))) - 0.7

    def density_kg_per_m3(self, T_C):
        return self.section.density_15C_kg_per_m3 * (1.0 - DENSITY_PER_K * (np.asarray(T_C, float) - 15.0))

    def dynamic_Pa_s(self, T_C):
        return self.kinematic_cSt(T_C) * 1e-6 * self.density_kg_per_m3(T_C)

    @property
    def alpha_per_Pa(self) -> float:
        return self.section.pressure_viscosity_per_GPa * 1e-9


def reduced_modulus_Pa(E_Pa: float, nu: float) -> float:
    """E' of two bodies of one material: 2 / E' = 2 (1 - nu^2) / E."""
    return E_Pa / (1.0 - nu * nu)


def _groups(eta0, u_e, R, w_line, E_red, alpha):
    R = np.asarray(R, float)
    U = np.asarray(eta0, float) * np.abs(u_e) / (E_red * R)
    W = np.maximum(np.asarray(w_line, float), 1e-9) / (E_red * R)
    return U, alpha * E_red, W, R


def central_film_m(eta0, u_e, R, w_line, E_red, alpha):
    """Pan & Hamrock (1989) central film thickness of the line contact [m]; u_e the entrainment
    (mean surface) speed [m/s], R the reduced radius [m], w_line the load per unit length [N/m]."""
    U, G, W, R = _groups(eta0, u_e, R, w_line, E_red, alpha)
    return 2.922 * U ** 0.692 * G ** 0.470 * W ** -0.166 * R


def dowson_higginson_min_film_m(eta0, u_e, R, w_line, E_red, alpha):
    """Dowson & Higginson (1977) minimum film of the line contact [m] (cross-check of the central)."""
    U, G, W, R = _groups(eta0, u_e, R, w_line, E_red, alpha)
    return 2.65 * U ** 0.70 * G ** 0.54 * W ** -0.13 * R


def composite_roughness_m(Ra1_um: float, Ra2_um: float) -> float:
    return RQ_PER_RA * math.hypot(Ra1_um, Ra2_um) * 1e-6


def asperity_share(film_parameter):
    """phi(Lambda) = erfc(Lambda / sqrt 2): the boundary share of the mixed-friction law."""
    return erfc(np.maximum(np.asarray(film_parameter, float), 0.0) / math.sqrt(2.0))


def mixed_friction(film_parameter, mu_boundary: float, mu_full_film: float):
    phi = asperity_share(film_parameter)
    return phi * mu_boundary + (1.0 - phi) * mu_full_film


@dataclass(frozen=True)
class Regime:
    """The lubrication state of a set of line contacts (arrays of one shape)."""
    film_m: np.ndarray
    film_parameter: np.ndarray
    friction: np.ndarray


def line_contact_regime(lub: Lubricant, T_C: float, u_e, R, w_line, E_red: float, sigma_m: float) -> Regime:
    """Film, Lambda and friction coefficient of line contacts at oil temperature T_C."""
    eta0 = lub.dynamic_Pa_s(T_C)
    h = central_film_m(eta0, u_e, R, w_line, E_red, lub.alpha_per_Pa)
    lam = h / sigma_m
    s = lub.section
    return Regime(film_m=h, film_parameter=lam, friction=mixed_friction(lam, s.boundary_friction, s.full_film_friction))
