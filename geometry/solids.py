"""CadQuery solids of the second stage: cycloid disc, pin, pin housing, crankshaft, assembly.

The profile comes from the numpy kernel (`geometry.profile`); each solid is then built by a chain
of `body -> body` steps (cq_gears style), each a no-op when its feature is absent.

Disc outline: one cubic B-spline per tooth (root to root) through `points_per_tooth` profile
points equally spaced in arc length, with the analytic unit tangents imposed at both ends (G1
joins). Measured deviation of the CAD edge from the analytic profile (`profile_deviation_mm`):
0.02 um at 96 points per tooth on the RV-40E (tests/test_solids.py pins < 0.5 um). A single
periodic spline through the whole profile deviates less well and, worse, OpenCascade's default
mass properties of such a solid are off by up to 30 %; volumes here use the Gauss-Kronrod
integration over B-spline spans (`volume_mm3`), 2e-8 relative to the shoelace area x width.

Frames (mm):
- disc frame: disc centre at the origin, z from 0 to the face width; a tooth root on +x (for
  rotation modification 0); crank holes at crank_circle_radius, angles 2 pi j / n_crank; pillar
  holes half-way between them (ASSUMED layout, matches the case files' comments). The second disc
  (index 1) is the same part with its teeth clocked by half a tooth (pi / zc) against the holes, so
  that both discs ride on the same cranks 180 deg apart (zc odd cannot mesh otherwise).
- crankshaft frame: axis = z, z = 0 at the first support-bearing centre, the second at
  z = support_span; eccentric 1 offset along +x, eccentric 2 along -x; see `CrankshaftLayout`.
- ground frame (assembly): pin housing centre at the origin, disc k occupies z in
  [k w, (k + 1) w]; pose convention of DESIGN.md.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import cadquery as cq
import numpy as np

from geometry.clearance import distance_to_profile_mm, theoretical_curve
from geometry.params import CaseError, ReducerCase
from geometry.profile import cycloid_xy, disc_profile, profile_args

POINTS_PER_TOOTH = 96      # B-spline points per tooth: 0.02 um edge deviation (RV-40E)
HOUSING_WALL_PIN_RADII = 3.0   # ASSUMED: ring wall beyond the pin circle, in pin radii (picture only)


# ----------------------------------------------------------------------------- disc outline
def _clocking_rad(case: ReducerCase, index: int) -> float:
    return index * math.pi / case.cycloid.zc


def tooth_edges(case: ReducerCase, *, index: int = 0, points_per_tooth: int = POINTS_PER_TOOTH,
                modified: bool = True) -> list[cq.Edge]:
    """One B-spline edge per tooth (root to root), G1 at the joins, disc frame, z = 0."""
    args = profile_args(case, modified=modified)
    args["rotation_rad"] += _clocking_rad(case, index)
    zc = case.cycloid.zc
    edges = []
    for k in range(zc):
        dense = np.linspace(2 * np.pi * k / zc, 2 * np.pi * (k + 1) / zc, 20 * points_per_tooth + 1)
        x, y = cycloid_xy(dense, **args)
        s = np.concatenate([[0.0], np.cumsum(np.hypot(np.diff(x), np.diff(y)))])
        t = np.interp(np.linspace(0.0, s[-1], points_per_tooth + 1), s, dense)
        t[0], t[-1] = dense[0], dense[-1]       # neighbours share their end points exactly
        x, y = cycloid_xy(t, **args)
        dx, dy = theoretical_curve(t[[0, -1]], args["R"], args["E"], args["zp"],
                                   args["rotation_rad"], derivative=1)
        # unit tangents with scale=False: cq's tangent scaling spoils the end spans (1.7 um)
        tangents = [cq.Vector(dx[i], dy[i], 0).normalized() for i in (0, 1)]
        edges.append(cq.Edge.makeSpline([cq.Vector(a, b, 0) for a, b in zip(x, y)],
                                        tangents=tangents, scale=False))
    return edges


def profile_deviation_mm(case: ReducerCase, edges: list[cq.Edge], *, index: int = 0,
                         samples_per_edge: int = 400, modified: bool = True) -> float:
    """Largest distance of the CAD edges (sampled in their parameter) from the analytic profile."""
    pts = []
    for e in edges:
        a, b = e._bounds()
        pts += [e.positionAt(u, mode="parameter").toTuple()[:2]
                for u in np.linspace(a, b, samples_per_edge)]
    d = distance_to_profile_mm(case, np.array(pts), modified=modified,
                               clocking_rad=_clocking_rad(case, index))
    return float(np.max(np.abs(d)))


# ----------------------------------------------------------------------------- hole layout
@dataclass(frozen=True)
class Hole:
    name: str
    x_mm: float
    y_mm: float
    radius_mm: float


def disc_holes(case: ReducerCase) -> list[Hole]:
    """Through holes of the disc in the disc frame: centre, crank and pillar holes."""
    cr, d = case.carrier, case.disc
    holes = []
    if d.centre_hole_radius_mm > 0:
        holes.append(Hole("centre", 0.0, 0.0, d.centre_hole_radius_mm))
    for j in range(cr.crank_count):
        a = 2 * math.pi * j / cr.crank_count
        holes.append(Hole(f"crank{j + 1}", cr.crank_circle_radius_mm * math.cos(a),
                          cr.crank_circle_radius_mm * math.sin(a), d.crank_hole_radius_mm))
    # the disc orbits with radius E around each pillar: hole = pillar + E + play
    r_pillar = cr.pillar_radius_mm + case.cycloid.eccentricity_mm + d.pillar_hole_clearance_mm
    for j in range(cr.pillar_count):
        a = 2 * math.pi * (j + 0.5) / cr.pillar_count
        holes.append(Hole(f"pillar{j + 1}", cr.pillar_circle_radius_mm * math.cos(a),
                          cr.pillar_circle_radius_mm * math.sin(a), r_pillar))
    return holes


def check_hole_layout(case: ReducerCase) -> None:
    """Raise CaseError when two disc holes overlap or a hole reaches the tooth root."""
    holes = disc_holes(case)
    args = profile_args(case)
    root = args["R"] - case.cycloid.eccentricity_mm - args["Rr"]
    where = f"{case.source + ': ' if case.source else ''}"
    for i, a in enumerate(holes):
        if math.hypot(a.x_mm, a.y_mm) + a.radius_mm >= root:
            raise CaseError(f"{where}{a.name} hole (radius {a.radius_mm:g} mm at "
                            f"{math.hypot(a.x_mm, a.y_mm):g} mm) reaches the tooth root "
                            f"(radius {root:.4g} mm)")
        for b in holes[i + 1:]:
            gap = math.hypot(a.x_mm - b.x_mm, a.y_mm - b.y_mm) - a.radius_mm - b.radius_mm
            if gap <= 0:
                raise CaseError(f"{where}disc holes {a.name} and {b.name} overlap by {-gap:.3g} mm; "
                                f"allowed: a wall between them (check [carrier] circles and radii, "
                                f"[disc] hole radii)")


# ----------------------------------------------------------------------------- disc
def _toothed_blank(case: ReducerCase, index: int, points_per_tooth: int) -> cq.Workplane:
    face = cq.Face.makeFromWires(cq.Wire.assembleEdges(
        tooth_edges(case, index=index, points_per_tooth=points_per_tooth)))
    solid = cq.Solid.extrudeLinear(face, cq.Vector(0, 0, case.cycloid.width_mm))
    return cq.Workplane("XY").add(solid)


def _cut_holes(body: cq.Workplane, case: ReducerCase, kind: str) -> cq.Workplane:
    holes = [h for h in disc_holes(case) if h.name.startswith(kind)]
    if not holes:
        return body
    w = case.cycloid.width_mm
    cutter = None
    for h in holes:
        cyl = cq.Solid.makeCylinder(h.radius_mm, w + 2.0, cq.Vector(h.x_mm, h.y_mm, -1.0))
        cutter = cyl if cutter is None else cutter.fuse(cyl)
    return body.cut(cutter)


def disc_solid(case: ReducerCase, *, index: int = 0,
               points_per_tooth: int = POINTS_PER_TOOTH) -> cq.Workplane:
    """Cycloid disc (modified profile) in the disc frame, z from 0 to the face width.

    index 1 gives the second disc (teeth clocked by half a tooth, see the module docstring)."""
    check_hole_layout(case)
    body = _toothed_blank(case, index, points_per_tooth)
    for kind in ("centre", "crank", "pillar"):
        body = _cut_holes(body, case, kind)
    return body


# ----------------------------------------------------------------------------- pin, housing
def pin_length_mm(case: ReducerCase) -> float:
    """Pins span all discs."""
    return case.cycloid.disc_count * case.cycloid.width_mm


def pin_solid(case: ReducerCase) -> cq.Workplane:
    """One pin (nominal radius) on the z axis, z from 0 to the stack of discs."""
    return cq.Workplane("XY").circle(case.cycloid.pin_radius_mm).extrude(pin_length_mm(case))


def housing_solid(case: ReducerCase) -> cq.Workplane:
    """Pin-housing ring with a half-round groove per pin (for the picture; wall ASSUMED)."""
    c = case.cycloid
    R, Rr, L = c.pin_circle_radius_mm, c.pin_radius_mm, pin_length_mm(case)
    body = cq.Workplane("XY").circle(R + HOUSING_WALL_PIN_RADII * Rr).circle(R).extrude(L)
    grooves = cq.Workplane("XY").polarArray(R, 0, 360, c.zp).circle(Rr).extrude(L)
    return body.cut(grooves)


# ----------------------------------------------------------------------------- crankshaft
@dataclass(frozen=True)
class CrankshaftLayout:
    """Where the crankshaft's parts are along its axis (crankshaft frame, mm).

    z = 0 at the first support-bearing centre, z = span at the second. Journals (radius
    journal_radius) are centred on the bearings; the eccentrics (radius eccentric_radius, one per
    disc, each one disc width long, offset by E along +x, then -x) are centred between the
    bearings and touch each other; the planet seat (journal radius, one journal length, ASSUMED:
    the planet gear rides on the input end, as in fem/shaft.py) lies outboard of journal 1;
    a core of journal radius joins everything:
        | seat | journal 1 | core | eccentric 1 | eccentric 2 | core | journal 2 |
    """
    planet_seat_mm: tuple[float, float]              # (z_start, z_end), outboard of journal 1
    journals_mm: tuple[tuple[float, float], ...]     # (z_start, z_end) per support journal
    eccentrics_mm: tuple[tuple[float, float], ...]   # (z_start, z_end) per eccentric, disc 1 first
    eccentric_phase_deg: tuple[float, ...]           # direction of each eccentric's offset
    eccentricity_mm: float
    journal_radius_mm: float
    eccentric_radius_mm: float
    support_span_mm: float

    @property
    def z_range_mm(self) -> tuple[float, float]:
        return self.planet_seat_mm[0], self.journals_mm[-1][1]

    def eccentric_centre_mm(self, i: int) -> tuple[float, float]:
        a = math.radians(self.eccentric_phase_deg[i])
        return self.eccentricity_mm * math.cos(a), self.eccentricity_mm * math.sin(a)


def crankshaft_layout(case: ReducerCase) -> CrankshaftLayout:
    ks, c = case.crankshaft, case.cycloid
    span, lj, w, n = ks.support_span_mm, ks.journal_length_mm, c.width_mm, c.disc_count
    start = span / 2 - n * w / 2
    if start < lj / 2:
        raise CaseError(f"{case.source + ': ' if case.source else ''}[crankshaft] support_span_mm = "
                        f"{span:g}: the {n} eccentric(s) of {w:g} mm and the journals of {lj:g} mm "
                        f"do not fit; allowed span >= {n * w + lj:g} mm")
    return CrankshaftLayout(
        planet_seat_mm=(-3 * lj / 2, -lj / 2),
        journals_mm=((-lj / 2, lj / 2), (span - lj / 2, span + lj / 2)),
        eccentrics_mm=tuple((start + i * w, start + (i + 1) * w) for i in range(n)),
        eccentric_phase_deg=tuple(180.0 * i for i in range(n)),
        eccentricity_mm=c.eccentricity_mm, journal_radius_mm=ks.journal_radius_mm,
        eccentric_radius_mm=ks.eccentric_radius_mm, support_span_mm=span)


def crankshaft_solid(case: ReducerCase) -> cq.Workplane:
    """Crankshaft in its own frame (see `CrankshaftLayout`)."""
    lay = crankshaft_layout(case)
    z0, z1 = lay.z_range_mm
    body = cq.Workplane("XY").add(
        cq.Solid.makeCylinder(lay.journal_radius_mm, z1 - z0, cq.Vector(0, 0, z0)))
    for i, (a, b) in enumerate(lay.eccentrics_mm):
        x, y = lay.eccentric_centre_mm(i)
        body = body.union(cq.Solid.makeCylinder(lay.eccentric_radius_mm, b - a, cq.Vector(x, y, a)))
    return body


# ----------------------------------------------------------------------------- assembly
def _shape(wp: cq.Workplane) -> cq.Shape:
    return wp.val() if len(wp.vals()) == 1 else cq.Compound.makeCompound(wp.vals())


def _placed(shape: cq.Shape, angle_deg: float, x: float, y: float, z: float) -> cq.Shape:
    """Turn about the local z axis, then move: the located copy."""
    return shape.rotate(cq.Vector(0, 0, 0), cq.Vector(0, 0, 1), angle_deg).translate(
        cq.Vector(x, y, z))


def assembly(case: ReducerCase, crank_angle_deg: float, *,
             include_housing: bool = True) -> list[tuple[str, cq.Shape]]:
    """The second stage at crank angle psi_c, every part located in the ground frame.

    Disc k (k = 0, 1): centre E (cos(psi_c + k pi), sin(...)), turned by the carrier angle
    -psi_c / zc; pins at R (cos 2 pi k / zp, sin ...); crankshafts on the crank circle turned with
    the carrier, their eccentric 1 pointing along psi_c.
    """
    c, cr = case.cycloid, case.carrier
    psi = math.radians(crank_angle_deg)
    carrier_deg = -crank_angle_deg / c.zc
    parts: list[tuple[str, cq.Shape]] = []
    for k in range(c.disc_count):
        a = psi + k * math.pi
        disc = _shape(disc_solid(case, index=k))
        parts.append((f"disc{k + 1}", _placed(disc, carrier_deg, c.eccentricity_mm * math.cos(a),
                                              c.eccentricity_mm * math.sin(a), k * c.width_mm)))
    pin = _shape(pin_solid(case))
    for k in range(c.zp):
        a = 2 * math.pi * k / c.zp
        parts.append((f"pin{k + 1:02d}", _placed(pin, 0.0, c.pin_circle_radius_mm * math.cos(a),
                                                 c.pin_circle_radius_mm * math.sin(a), 0.0)))
    if include_housing:
        parts.append(("housing", _shape(housing_solid(case))))
    lay = crankshaft_layout(case)
    shaft = _shape(crankshaft_solid(case))
    for j in range(cr.crank_count):
        a = 2 * math.pi * j / cr.crank_count + math.radians(carrier_deg)
        parts.append((f"crankshaft{j + 1}", _placed(
            shaft, crank_angle_deg, cr.crank_circle_radius_mm * math.cos(a),
            cr.crank_circle_radius_mm * math.sin(a), -lay.eccentrics_mm[0][0])))
    return parts


# ----------------------------------------------------------------------------- volumes
def volume_mm3(shape: cq.Shape | cq.Workplane) -> float:
    """Volume by adaptive Gauss-Kronrod integration over B-spline spans (OpenCascade's default
    integration is off by up to 30 % on many-knot spline faces)."""
    from OCP.BRepGProp import BRepGProp
    from OCP.GProp import GProp_GProps
    if isinstance(shape, cq.Workplane):
        shape = _shape(shape)
    props = GProp_GProps()
    BRepGProp.VolumePropertiesGK_s(shape.wrapped, props, 1e-7, True, True)
    return props.Mass()


@dataclass(frozen=True)
class DiscVolume:
    """Analytic references for the disc volume [mm^3]."""
    reference_mm3: float     # shoelace area of a dense profile (Richardson) minus holes, x width
    lower_mm3: float         # (pi r_root^2 - holes) x width
    upper_mm3: float         # (pi r_tip^2 - holes) x width
    reference_error_mm3: float   # Richardson estimate of the reference's discretisation error


def disc_volume_bounds(case: ReducerCase, n: int = 1 << 17) -> DiscVolume:
    def area(m: int) -> float:
        p = disc_profile(case, n=m, closed=True)
        return -0.5 * float(np.sum(p[:-1, 0] * p[1:, 1] - p[1:, 0] * p[:-1, 1]))  # clockwise
    holes = sum(math.pi * h.radius_mm**2 for h in disc_holes(case))
    args = profile_args(case)
    E, w = case.cycloid.eccentricity_mm, case.cycloid.width_mm
    r_root, r_tip = args["R"] - E - args["Rr"], args["R"] + E - args["Rr"]
    a_fine, a_coarse = area(n), area(n // 2)
    a = a_fine + (a_fine - a_coarse) / 3        # polygon area error ~ n^-2: Richardson step
    return DiscVolume((a - holes) * w, (math.pi * r_root**2 - holes) * w,
                      (math.pi * r_tip**2 - holes) * w, abs(a - a_fine) * w)
