"""The carrier (output flange + end plate + pillars) as a CadQuery solid, sized from the case.

Frame (mm), the ground frame of `geometry.solids.assembly`: axis = z, the disc stack fills
z in [0, g], g = disc_count x disc width. The end plate (input side: the planet gears sit
outboard of crank journal 1, see `geometry.solids.CrankshaftLayout`) spans z in [-t_e, 0]; the
output flange spans [g, g + t_f] and its outer face z = g + t_f is the mounting face (bolted to
the load). Crank seats (bores of the support bearings' cups) at radius a, angles 2 pi j / n_crank;
pillars at the pillar circle, angles 2 pi (j + 1/2) / n_pillar (the disc's pillar holes, see
`geometry.solids.disc_holes`), spanning the gap [0, g].

Each crank's bearings sit inside the plates, centred where the crankshaft layout puts them:
journal 1 (end plate) at z = -(span - g)/2, journal 2 (flange) at z = g + (span - g)/2.

Modelled as ONE body: the pillars are integral with the flange and bolted to the end plate;
the bolted joint is taken as perfectly bonded (preloaded bolts, fitted pillar ends), so its
contact compliance is left out (the model is an upper bound on the carrier's stiffness).
Not modelled: bolt holes, the main-bearing raceways on the plate rims, fillets, chamfers.

Sizes no case key gives (ASSUMED, each with its reason where it is set in `from_case`): seat bore
= tapered-roller cup outer radius (1.85 journal radii); bearing width = journal length; plate
thickness = disc face to bearing centre + half a bearing + a cover of half a bearing; plate rim =
the disc root radius R - E - Rr; centre bore = the discs' centre hole; gap = the disc stack
(running play ignored); seat bores run through both plates (the flange-side cover carries nothing).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from geometry.artifacts import InputError

# Drawing default only: cup outer radius = 1.85 x the journal radius (an extra-light series); the FE
# carrier sizes the seats to the bearing fem.tapered_roller selects (fem.carrier.case_geometry)
SEAT_TO_JOURNAL_RADIUS = 1.85
# ASSUMED: a cup backing ring / cover of half a bearing width lies between each bearing and the
# plate's outer face (cups are held axially), so the plates end beyond the bearings
COVER_PER_BEARING_WIDTH = 0.5


class CarrierGeometryError(InputError):
    """A carrier that cannot be built (walls between bores and pillars missing)."""


@dataclass(frozen=True)
class CarrierGeometry:
    crank_count: int
    crank_circle_radius_mm: float       # a: crank axes
    seat_bore_radius_mm: float          # bore of each bearing cup, through both plates
    bearing_width_mm: float             # axial length of the seat band (the rigid ring)
    seat_z_mm: tuple[float, float]      # bearing centres: (flange, end plate)
    pillar_count: int
    pillar_circle_radius_mm: float
    pillar_radius_mm: float
    outer_radius_mm: float              # both plates
    flange_thickness_mm: float          # t_f, output side
    end_plate_thickness_mm: float       # t_e, input side
    gap_mm: float                       # g: disc stack between the plates = pillar length
    centre_bore_radius_mm: float        # 0: none
    bolt_circle_radius_mm: float        # output mounting bolt circle (information, not cut)

    def __post_init__(self):
        check(self)

    # ------------------------------------------------------------------ derived layout
    @property
    def flange_z_mm(self) -> tuple[float, float]:
        return self.gap_mm, self.gap_mm + self.flange_thickness_mm

    @property
    def end_plate_z_mm(self) -> tuple[float, float]:
        return -self.end_plate_thickness_mm, 0.0

    @property
    def mounting_face_z_mm(self) -> float:
        return self.gap_mm + self.flange_thickness_mm

    def crank_angles_rad(self) -> list[float]:
        return [2 * math.pi * j / self.crank_count for j in range(self.crank_count)]

    def pillar_angles_rad(self) -> list[float]:
        return [2 * math.pi * (j + 0.5) / self.pillar_count for j in range(self.pillar_count)]

    def crank_xy_mm(self, j: int) -> tuple[float, float]:
        t = self.crank_angles_rad()[j]
        return self.crank_circle_radius_mm * math.cos(t), self.crank_circle_radius_mm * math.sin(t)

    def pillar_xy_mm(self, j: int) -> tuple[float, float]:
        t = self.pillar_angles_rad()[j]
        return self.pillar_circle_radius_mm * math.cos(t), self.pillar_circle_radius_mm * math.sin(t)

    def volume_mm3(self) -> float:
        """Exact volume of the solid: two holed discs plus the pillars' free length."""
        t = self.flange_thickness_mm + self.end_plate_thickness_mm
        holes = math.pi * (self.centre_bore_radius_mm ** 2 + self.crank_count * self.seat_bore_radius_mm ** 2)
        return (math.pi * self.outer_radius_mm ** 2 - holes) * t \
            + self.pillar_count * math.pi * self.pillar_radius_mm ** 2 * self.gap_mm

    def with_(self, **changes) -> "CarrierGeometry":
        from dataclasses import replace
        return replace(self, **changes)

    # ------------------------------------------------------------------ from a case
    @classmethod
    def from_case(cls, case) -> "CarrierGeometry":
        """Every size from the case keys; the ones no key gives are ASSUMED (module constants and
        the comments below)."""
        c, cr, ks = case.cycloid, case.carrier, case.crankshaft
        gap = c.disc_count * c.width_mm                       # plates touch the disc stack (running play ignored)
        overhang = (ks.support_span_mm - gap) / 2             # disc face to bearing centre
        if overhang < ks.journal_length_mm / 2:
            raise CarrierGeometryError(
                f"[crankshaft] support_span_mm = {ks.support_span_mm:g}: the bearings must lie outside the "
                f"disc stack ({gap:g} mm); allowed >= {gap + ks.journal_length_mm:g} mm")
        # plate = from the disc face over the bearing to its cover (ASSUMED cover, see constant)
        t = overhang + ks.journal_length_mm * (0.5 + COVER_PER_BEARING_WIDTH)
        # ASSUMED: plate rim at the disc root radius R - E - Rr: the main bearings' inner rings
        # ride on the plate rims inside the pin housing, whose bore is near the pin circle
        outer = c.pin_circle_radius_mm - c.eccentricity_mm - c.pin_radius_mm
        return cls(
            crank_count=cr.crank_count,
            crank_circle_radius_mm=cr.crank_circle_radius_mm,
            seat_bore_radius_mm=SEAT_TO_JOURNAL_RADIUS * ks.journal_radius_mm,
            bearing_width_mm=ks.journal_length_mm,            # ASSUMED: cup width = journal length
            seat_z_mm=(gap + overhang, -overhang),
            pillar_count=cr.pillar_count,
            pillar_circle_radius_mm=cr.pillar_circle_radius_mm,
            pillar_radius_mm=cr.pillar_radius_mm,
            outer_radius_mm=outer,
            flange_thickness_mm=t,
            end_plate_thickness_mm=t,
            gap_mm=gap,
            # ASSUMED: the input shaft passes through both plates in a bore like the discs' centre hole
            centre_bore_radius_mm=case.disc.centre_hole_radius_mm,
            bolt_circle_radius_mm=cr.output_flange_radius_mm)


def check(g: CarrierGeometry) -> None:
    """Raise CarrierGeometryError naming the size that leaves no wall."""
    def need(ok: bool, name: str, value: float, allowed: str) -> None:
        if not ok:
            raise CarrierGeometryError(f"carrier {name} = {value:g} mm: {allowed}")

    if g.crank_count < 1 or g.pillar_count < 1:
        raise CarrierGeometryError(f"carrier crank_count = {g.crank_count}, pillar_count = {g.pillar_count}: "
                                   f"both must be >= 1 (the pillars are the only path to the end plate)")
    for name in ("crank_circle_radius_mm", "seat_bore_radius_mm", "bearing_width_mm", "pillar_circle_radius_mm",
                 "pillar_radius_mm", "outer_radius_mm", "flange_thickness_mm", "end_plate_thickness_mm", "gap_mm"):
        need(getattr(g, name) > 0, name, getattr(g, name), "must be positive")
    need(g.centre_bore_radius_mm >= 0, "centre_bore_radius_mm", g.centre_bore_radius_mm, "must be >= 0")
    a, rs, ro = g.crank_circle_radius_mm, g.seat_bore_radius_mm, g.outer_radius_mm
    need(a + rs < ro, "seat_bore_radius_mm", rs, f"crank seat reaches the plate rim; allowed < {ro - a:g} mm")
    need(a - rs > g.centre_bore_radius_mm, "seat_bore_radius_mm", rs,
         f"crank seat cuts the centre bore; allowed < {a - g.centre_bore_radius_mm:g} mm")
    rp, rpc = g.pillar_radius_mm, g.pillar_circle_radius_mm
    need(rpc + rp < ro, "pillar_radius_mm", rp, f"pillar reaches the plate rim; allowed < {ro - rpc:g} mm")
    need(rpc - rp > g.centre_bore_radius_mm, "pillar_radius_mm", rp,
         f"pillar cuts the centre bore; allowed < {rpc - g.centre_bore_radius_mm:g} mm")
    if g.pillar_count > 1:
        pitch = 2 * rpc * math.sin(math.pi / g.pillar_count)
        need(pitch > 2 * rp, "pillar_radius_mm", rp, f"neighbouring pillars overlap; allowed < {pitch / 2:g} mm")
    for j in range(g.pillar_count):
        px, py = g.pillar_xy_mm(j)
        for k in range(g.crank_count):
            cx, cy = g.crank_xy_mm(k)
            d = math.hypot(px - cx, py - cy)
            need(d > rp + rs, "pillar_radius_mm", rp,
                 f"pillar {j + 1} cuts crank seat {k + 1}; allowed < {d - rs:g} mm")
    need(0 <= g.bolt_circle_radius_mm < ro, "bolt_circle_radius_mm", g.bolt_circle_radius_mm,
         f"the output bolt circle must lie on the flange; allowed [0, {ro:g}) mm")
    half = g.bearing_width_mm / 2
    (f0, f1), (e0, e1) = g.flange_z_mm, g.end_plate_z_mm   # outer faces: f1 (mounting face) and e0
    need(f0 <= g.seat_z_mm[0] - half and g.seat_z_mm[0] + half < f1, "flange seat centre z", g.seat_z_mm[0],
         f"the bearing band must lie in the flange, clear of its mounting face: z in [{f0 + half:g}, {f1 - half:g})")
    need(e0 < g.seat_z_mm[1] - half and g.seat_z_mm[1] + half <= e1, "end plate seat centre z", g.seat_z_mm[1],
         f"the bearing band must lie in the end plate, clear of its outer face: z in ({e0 + half:g}, {e1 - half:g}]")


def carrier_solid(g: CarrierGeometry):
    """One valid solid: end plate and flange (discs with a centre bore and n_crank seat bores)
    joined by the pillars."""
    import cadquery as cq
    ze0, ze1 = g.end_plate_z_mm
    zf0, zf1 = g.flange_z_mm

    def plate(z0: float, z1: float):
        return cq.Solid.makeCylinder(g.outer_radius_mm, z1 - z0, cq.Vector(0, 0, z0))

    body = plate(ze0, ze1).fuse(plate(zf0, zf1))
    for j in range(g.pillar_count):     # pillars reach half-way into both plates: a robust fuse
        x, y = g.pillar_xy_mm(j)
        z0 = ze1 - g.end_plate_thickness_mm / 2
        body = body.fuse(cq.Solid.makeCylinder(g.pillar_radius_mm, zf0 + g.flange_thickness_mm / 2 - z0,
                                               cq.Vector(x, y, z0)))
    length = zf1 - ze0 + 2.0
    cutters = [cq.Solid.makeCylinder(g.seat_bore_radius_mm, length, cq.Vector(*g.crank_xy_mm(j), ze0 - 1.0))
               for j in range(g.crank_count)]
    if g.centre_bore_radius_mm > 0:
        cutters.append(cq.Solid.makeCylinder(g.centre_bore_radius_mm, length, cq.Vector(0, 0, ze0 - 1.0)))
    for c in cutters:
        body = body.cut(c)
    return cq.Workplane("XY").add(body.clean())
