"""Turning-arm (needle roller) bearing between eccentric and disc crank hole: radial compliance.

Current model (closed form, NOT yet FE): Palmgren's needle approach at the Stribeck load of the
most loaded needle, delta_r = 3.84e-5 (4.08 F_r / Z)^0.9 / L^0.8 [mm, N, mm], zero clearance
(fem.hertz). Race bending of the eccentric and of the disc around the crank hole is not included;
its size is bounded by a Lame thick-cylinder estimate reported beside it (the disc ring between
crank hole and a radius of twice the hole under the Stribeck pressure band).
The planned 2D plane-strain FE (eccentric + needles + disc bore with fem.contact) is not done.
"""
from __future__ import annotations

import numpy as np

from fem import hertz


def turning_arm_curve(case, max_load_N: float, n: int = 6) -> dict:
    k = case.crankshaft
    E, nu = case.material.youngs_modulus_GPa * 1e9, case.material.poisson_ratio
    loads = max_load_N * np.array([0.05, 0.1, 0.2, 0.4, 0.7, 1.0])[:n]
    L = k.needle_length_mm * 1e-3
    d = hertz.needle_bearing_deflection(loads, k.needle_count, L)
    kk, nn = hertz.fit_power_law(loads, d)
    a = case.disc.crank_hole_radius_mm * 1e-3
    # Lame: the loaded half of the bore carries F over a projected area 2 a L -> p ~ F / (2 a L)
    p = max_load_N / (2 * a * L)
    lame = float(hertz.lame_radial_displacement(a, a, 2 * a, p, 0.0, E, nu))
    return {"load_N": loads, "deflection_m": d, "law_k_N_per_m_pow": kk, "law_n": nn,
            "lame_ring_deflection_at_max_m": lame,
            "source": "Palmgren needle approach at Stribeck Q_max = 4.08 F_r/Z (closed form; FE not done)"}


def turning_arm_max_load(case, torque_Nm: float) -> float:
    """Radial load on one crank's needle bearing [N]: the disc torque shared by the cranks at the
    crank-circle radius, for one disc (0.55 T for two discs), load-sharing like the pins."""
    share = 0.55 if case.cycloid.disc_count == 2 else 1.0
    return share * torque_Nm / (case.carrier.crank_count * case.carrier.crank_circle_radius_mm * 1e-3)
