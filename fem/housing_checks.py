"""Closed-form checks of the housing FE (fem.housing): annuli solved with the same P2 plane-stress
machinery. (The mesh convergence and the bolt pattern's symmetry are measured in fem.housing.)

- `lame_fixed_outer`: plain annulus a..b, uniform pressure p on the inner edge, outer edge fixed,
  plane stress: u = A r + B / r with u(b) = 0 and sigma_r(a) = -p gives
      B = p (1 - nu^2) / E / ((1 + nu) / b^2 + (1 - nu) / a^2),   u(a) = B (1 / a - a / b^2);
  the FE (same P2 basis, plane-stress stiffness and thickness as the housing) within 1 %.
- `annulus_torsion`: the same annulus, uniform shear traction on the inner edge (torque T), outer
  edge fixed: sigma_rtheta = T / (2 pi r^2 t), gamma = r d(u_theta / r)/dr = sigma / mu, so
      theta(a) = T / (4 pi mu t) (1 / a^2 - 1 / b^2);
  the FE within 1 %. The housing itself has no closed form (clamped at n_b holes, grooved bore):
  it is set beside this annulus from the pin circle to the bolt circle clamped all round (the
  ratio says how much the holes-only clamp and the grooves soften it).
"""
from __future__ import annotations

import math

import numpy as np

from fem import elastic
from fem.disc_body import _annulus, bore_load, plane_stress_stiffness


def lame_fixed_outer_m(a: float, b: float, p: float, E: float, nu: float) -> float:
    """Inner radial displacement of a plane-stress annulus, outer edge fixed (module doc)."""
    B = p * (1 - nu * nu) / E / ((1 + nu) / b ** 2 + (1 - nu) / a ** 2)
    return B * (1 / a - a / b ** 2)


def annulus_torsion_rad_per_Nm(a: float, b: float, E: float, nu: float, t: float) -> float:
    """Inner-edge rotation per torque of an annulus with its outer edge fixed (module doc)."""
    mu = E / (2 * (1 + nu))
    return (1 / a ** 2 - 1 / b ** 2) / (4 * math.pi * mu * t)


def _clamped_annulus(a, b, h, E, nu, t):
    basis, _, _, f_out, f_in = _annulus(a, b, h)
    K = plane_stress_stiffness(basis, E, nu, t)
    return basis, f_in, elastic.Factorized.of(K, basis.get_dofs(f_out).all())


def lame_fixed_outer(a: float = 64e-3, b: float = 95e-3, h: float = 2e-3, p: float = 100e6, E: float = 206e9,
                     nu: float = 0.3, t: float = 22e-3) -> dict:
    """FE inner radial displacement (mean: the conjugate of a uniform pressure) against the closed form."""
    basis, f_in, fac = _clamped_annulus(a, b, h, E, nu, t)
    u = fac.solve(bore_load(basis, f_in, (0.0, 0.0), a, None, t, pressure_Pa=p))
    g = bore_load(basis, f_in, (0.0, 0.0), a, None, 1.0, pressure_Pa=1.0 / (2 * math.pi * a))
    ref = lame_fixed_outer_m(a, b, p, E, nu)
    return {"fe_m": float(g @ u), "closed_form_m": ref, "error": float(g @ u / ref - 1), "dofs": int(basis.N)}


def annulus_torsion(a: float = 64e-3, b: float = 87.5e-3, h: float = 2e-3, E: float = 206e9, nu: float = 0.3,
                    t: float = 22e-3) -> dict:
    """FE rotation per torque of the clamped annulus against the closed form."""
    from fem.disc_body import _facet_vector
    basis, f_in, fac = _clamped_annulus(a, b, h, E, nu, t)
    # unit torque: shear force per length 1 / (2 pi a^2) along e_theta; its conjugate is the rotation
    g = _facet_vector(basis, f_in, lambda x: (-x[1] / a / (2 * math.pi * a ** 2), x[0] / a / (2 * math.pi * a ** 2)))
    theta = float(g @ fac.solve(g))
    ref = annulus_torsion_rad_per_Nm(a, b, E, nu, t)
    return {"fe_rad_per_Nm": theta, "closed_form_rad_per_Nm": ref, "error": theta / ref - 1}
