"""Cycloid disc profile with offset, equidistant and rotation modifications (pure numpy).

Verified form (DESIGN.md): with pin circle radius R, pin radius Rr, eccentricity E, zp pins,
    psi = atan2(sin((1 - zp) t), R / (E zp) - cos((1 - zp) t))
    x =  R cos t - Rr cos(t + psi) - E cos(zp t)
    y = -R sin t + Rr sin(t + psi) + E sin(zp t)
The offset (moved-distance) dR and the equidistant dRr replace R and Rr; the rotation delta turns
the profile about the disc centre. Coordinates are in the disc frame, millimetres.
Pose convention that makes the disc conjugate to the pins: disc centre at E (cos psi_c, sin psi_c),
disc rotated by -psi_c / zc, pins at R (cos 2 pi k / zp, sin 2 pi k / zp).
"""
from __future__ import annotations

import numpy as np

from geometry.params import ReducerCase


def cycloid_xy(t: np.ndarray, R: float, Rr: float, E: float, zp: int,
               rotation_rad: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """Profile points at parameter t [rad] (t in [0, 2 pi) traces the closed profile)."""
    t = np.asarray(t, dtype=float)
    a = (1 - zp) * t
    psi = np.arctan2(np.sin(a), R / (E * zp) - np.cos(a))
    x = R * np.cos(t) - Rr * np.cos(t + psi) - E * np.cos(zp * t)
    y = -R * np.sin(t) + Rr * np.sin(t + psi) + E * np.sin(zp * t)
    if rotation_rad:
        c, s = np.cos(rotation_rad), np.sin(rotation_rad)
        x, y = c * x - s * y, s * x + c * y
    return x, y


def profile_args(case: ReducerCase, *, modified: bool = True) -> dict:
    """Keyword arguments of `cycloid_xy` for a case (modified or nominal profile)."""
    c, m = case.cycloid, case.modification
    dR, dRr, rot = (m.offset_mm, m.equidistant_mm, np.deg2rad(m.rotation_deg)) if modified \
        else (0.0, 0.0, 0.0)
    return dict(R=c.pin_circle_radius_mm + dR, Rr=c.pin_radius_mm + dRr,
                E=c.eccentricity_mm, zp=c.zp, rotation_rad=rot)


def disc_profile(case: ReducerCase, n: int = 4000, *, modified: bool = True,
                 closed: bool = True) -> np.ndarray:
    """(n, 2) profile in the disc frame [mm]; closed repeats the first point at the end."""
    t = np.linspace(0.0, 2 * np.pi, n + 1 if closed else n, endpoint=closed)
    x, y = cycloid_xy(t, **profile_args(case, modified=modified))
    return np.column_stack([x, y])
