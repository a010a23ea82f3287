"""First-stage spur-gear geometry (sun pinion z1, planets z2): profile shift, undercut, tip
thickness and transverse contact ratio, pure math (mm, deg).

Basic rack ISO 53 profile A (tool = the rack's complement): addendum h_aP = 1.0 m, dedendum
h_fP = 1.25 m, root radius rho_fP = 0.38 m; its straight flank ends h_FfP = h_fP - rho_fP (1 -
sin alpha) below the datum line (1.000 m at 20 deg). Formulas (ISO 21771:2007, Niemann &
Winter vol. II sec. 21):
  undercut-free    x >= h_FfP / m - z sin^2(alpha) / 2   (the rack's straight flank stays above
                   the base circle's tangent point; 0.298 for z = 12 at 20 deg)
  tip diameter     d_a = m (z + 2 (1 + x))  (zero-sum shift x2 = -x1: standard centre distance,
                   working pressure angle = alpha, bottom clearance 0.25 m kept, no tip shortening)
  tip thickness    s_a = d_a (s / d + inv alpha - inv alpha_a), s = m (pi / 2 + 2 x tan alpha),
                   cos alpha_a = d_b / d_a; a tooth with s_a < TIP_MIN_OF_MODULE m is taken as
                   pointed (0.2 m is the usual minimum, 0.4 m for case-hardened teeth)
  contact ratio    eps_alpha = (sqrt(r_a1^2 - r_b1^2) + sqrt(r_a2^2 - r_b2^2) - a sin alpha)
                   / (pi m cos alpha)
Limits: external spur gears, zero-sum shift only (the planets ride on the crank circle, which
fixes the centre distance at m (z1 + z2) / 2), no tip shortening or chamfer.
"""
from __future__ import annotations

import math

RACK_DEDENDUM = 1.25        # h_fP / m, ISO 53 profile A
RACK_ROOT_RADIUS = 0.38     # rho_fP / m, ISO 53 profile A
TIP_MIN_OF_MODULE = 0.2     # smallest tip thickness s_a / m accepted (Niemann & Winter: 0.2 m usual)


def _inv(a: float) -> float:
    return math.tan(a) - a


def undercut_limit(z: int, pressure_angle_deg: float) -> float:
    """Smallest profile shift x free of undercut when cut by the ISO 53 rack."""
    a = math.radians(pressure_angle_deg)
    return RACK_DEDENDUM - RACK_ROOT_RADIUS * (1 - math.sin(a)) - z * math.sin(a) ** 2 / 2


def tip_radius_mm(z: int, module_mm: float, x: float) -> float:
    """r_a = m (z / 2 + 1 + x) (no tip shortening)."""
    return module_mm * (z / 2 + 1 + x)


def tip_thickness_of_module(z: int, pressure_angle_deg: float, x: float) -> float:
    """s_a / m, the arc tooth thickness on the tip circle over the module (< 0: pointed, crossed)."""
    a = math.radians(pressure_angle_deg)
    da = z + 2 * (1 + x)
    aa = math.acos(min(1.0, z * math.cos(a) / da))
    return da * ((math.pi / 2 + 2 * x * math.tan(a)) / z + _inv(a) - _inv(aa))


def transverse_contact_ratio(z1: int, z2: int, module_mm: float, pressure_angle_deg: float,
                             x1: float = 0.0, x2: float = 0.0) -> float:
    """eps_alpha of an external spur pair with a zero-sum shift at the standard centre distance."""
    if abs(x1 + x2) > 1e-12:
        raise ValueError(f"profile shifts x1 = {x1}, x2 = {x2}: only a zero-sum shift (x1 + x2 = 0) "
                         f"keeps the standard centre distance")
    a = math.radians(pressure_angle_deg)
    r1, r2 = module_mm * z1 / 2, module_mm * z2 / 2
    ra1, ra2 = tip_radius_mm(z1, module_mm, x1), tip_radius_mm(z2, module_mm, x2)
    rb1, rb2 = r1 * math.cos(a), r2 * math.cos(a)
    path = math.sqrt(ra1 ** 2 - rb1 ** 2) + math.sqrt(ra2 ** 2 - rb2 ** 2) - (r1 + r2) * math.sin(a)
    return path / (math.pi * module_mm * math.cos(a))


def shift_range(z1: int, z2: int, pressure_angle_deg: float) -> tuple[float, float]:
    """Allowed sun shift x1 (planet x2 = -x1): neither gear undercut nor pointed (module doc)."""
    def pointed_from(z):   # smallest x with s_a < TIP_MIN m (s_a falls with x): bisection
        lo, hi = -1.0, 2.0
        for _ in range(60):
            mid = (lo + hi) / 2
            lo, hi = (mid, hi) if tip_thickness_of_module(z, pressure_angle_deg, mid) >= TIP_MIN_OF_MODULE \
                else (lo, mid)
        return lo
    lo = max(undercut_limit(z1, pressure_angle_deg), -pointed_from(z2))
    hi = min(-undercut_limit(z2, pressure_angle_deg), pointed_from(z1))
    return lo, hi
