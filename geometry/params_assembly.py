"""Case sections of the assembled reducer (DESIGN.md "The assembled reducer"): the joints between
the parts (`[joints]`: surface finish, bolts, pins, fits) and the built-in main bearing pair
(`[main_bearings]`). Read by fem.joints, fem.bolts, fem.support_rings and fem.main_bearings.


Ranges: a value outside is refused with key, value and the allowed range (geometry.params). The
bounds are those of the laws used: the contact-layer law's finish classes end at Ra 6.3 um (turned
or milled faces; a rougher face is no bearing seat or flange face), the ISO 261 coarse threads and
ISO 898-1 property classes of fem.bolts, the ball-bearing geometry of real angular contact bearings
(conformity 0.5 < f <= 0.6, contact angle up to 60 deg).
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

from geometry.case_fields import ranged as _f

RA_MAX_UM = 6.3                          # roughest finish class of fem.joints (turned / milled)
THREADS_MM = (3.0, 4.0, 5.0, 6.0, 8.0, 10.0, 12.0, 14.0, 16.0, 20.0, 24.0)   # ISO 261 coarse, fem.bolts
PROPERTY_CLASSES = (8.8, 10.9, 12.9)     # ISO 898-1, fem.bolts


_RA = dict(why=f"the contact-layer law's finish classes end at Ra {RA_MAX_UM} um (turned/milled); "
               f"a rougher face is no bearing seat or flange face")
_THREAD = dict(why="ISO 261 coarse threads M3..M24 (fem.bolts)")
_CLASS = dict(why="ISO 898-1 property classes 8.8, 10.9, 12.9 (fem.bolts)")
_CONF = dict(why="groove radius / ball diameter of real bearings, 0.505..0.56; closer to 0.5 the contact "
                 "ellipse leaves the range of fem.main_bearings' Hertz approximation (R_y / R_x > 100)")
_FIT = dict(why="mean diametral interference of a bearing fit (ISO 286 with ISO 492 ring tolerances); "
                "a clearance fit is not a seat the load-zone layer model holds, > 50 um is no bearing fit")


@dataclass(frozen=True)
class Joints:
    seat_roughness_Ra_um: float = _f(0.0, RA_MAX_UM, **_RA)      # bearing seats: carrier bores, journals
    face_roughness_Ra_um: float = _f(0.0, RA_MAX_UM, **_RA)      # pillar and flange faces
    face_friction: float = _f(0.05, 0.8, open_lo=False,
                              why="dry or oiled steel on steel (VDI 2230 table A6: 0.1..0.23 dry)")
    thread_friction: float = _f(0.04, 0.5, open_lo=False, why="VDI 2230 table A5 range of mu_G")
    pillar_bolt_thread_mm: float = _f(3.0, 24.0, open_lo=False, **_THREAD)
    pillar_bolt_property_class: float = _f(8.8, 12.9, open_lo=False, **_CLASS)
    pillar_bolts_per_pillar: int = _f(1, 4, open_lo=False)
    pillar_clamp_length_mm: float = _f(0.0, 200.0)              # end plate thickness under the head
    taper_pin_diameter_mm: float = _f(0.0, 30.0)                 # mean diameter, one pin per pillar
    output_bolt_thread_mm: float = _f(3.0, 24.0, open_lo=False, **_THREAD)
    output_bolt_property_class: float = _f(8.8, 12.9, open_lo=False, **_CLASS)
    output_bolt_count: int = _f(3, 64, open_lo=False)
    output_face_inner_radius_mm: float = _f(0.0)
    output_face_outer_radius_mm: float = _f(0.0)
    support_cup_interference_um: float = _f(0.0, 50.0, open_lo=False, **_FIT)   # cup in carrier bore
    support_cone_interference_um: float = _f(0.0, 50.0, open_lo=False, **_FIT)  # cone on journal
    support_seat_wall_mm: float = _f(0.0, 100.0)                 # carrier wall around a cup (Lame hub)


@dataclass(frozen=True)
class MainBearings:
    pitch_diameter_mm: float = _f(0.0)
    ball_diameter_mm: float = _f(0.0)
    ball_count: int = _f(3, 400, open_lo=False)
    contact_angle_deg: float = _f(0.0, 60.0, why="angular contact ball bearings: 15..45 deg, 60 deg the steepest")
    inner_conformity: float = _f(0.505, 0.6, open_lo=False, **_CONF)
    outer_conformity: float = _f(0.505, 0.6, open_lo=False, **_CONF)
    spacing_mm: float = _f(0.0)                                  # between the two rows' centres
    preload_N: float = _f(0.0)                                   # axial, each row, no external load


def check(joints: Joints, mb: MainBearings, where) -> list[str]:
    """Cross-field checks of the two sections: the messages of the violated ones (empty: none);
    `where(section, key)` names a key. geometry.params.validate raises the first."""
    out = []
    for key in ("pillar_bolt_thread_mm", "output_bolt_thread_mm"):
        v = getattr(joints, key)
        if v not in THREADS_MM:
            out.append(f"{where('joints', key)} = {v!r}: allowed ISO 261 coarse sizes "
                       f"{', '.join(f'{t:g}' for t in THREADS_MM)} mm")
    for key in ("pillar_bolt_property_class", "output_bolt_property_class"):
        v = getattr(joints, key)
        if not any(math.isclose(v, c) for c in PROPERTY_CLASSES):
            out.append(f"{where('joints', key)} = {v!r}: allowed ISO 898-1 classes "
                       f"{', '.join(f'{c:g}' for c in PROPERTY_CLASSES)}")
    if joints.output_face_inner_radius_mm >= joints.output_face_outer_radius_mm:
        out.append(f"{where('joints', 'output_face_inner_radius_mm')} = {joints.output_face_inner_radius_mm:g}: "
                   f"must be below output_face_outer_radius_mm = {joints.output_face_outer_radius_mm:g}")
    if mb.ball_diameter_mm >= 0.25 * mb.pitch_diameter_mm:
        out.append(f"{where('main_bearings', 'ball_diameter_mm')} = {mb.ball_diameter_mm:g}: allowed < "
                   f"{0.25 * mb.pitch_diameter_mm:g} mm (a quarter of the pitch diameter: rings need a section)")
    if mb.ball_count * mb.ball_diameter_mm >= math.pi * mb.pitch_diameter_mm:
        out.append(f"{where('main_bearings', 'ball_count')} = {mb.ball_count}: {mb.ball_count} balls of "
                   f"{mb.ball_diameter_mm:g} mm do not fit on the {mb.pitch_diameter_mm:g} mm pitch circle "
                   f"(allowed < {math.pi * mb.pitch_diameter_mm / mb.ball_diameter_mm:.1f})")
    return out
