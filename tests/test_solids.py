"""CadQuery solids: valid, the right size (analytic volumes), the right place (pose convention)."""
import math
from pathlib import Path

import cadquery as cq
import numpy as np
import pytest

from geometry import solids
from geometry.clearance import pin_distances_mm
from geometry.export import InvalidSolidError, export_solid
from geometry.params import CaseError, case_from_dict, load_case

CASES = Path(__file__).resolve().parents[1] / "cases"


@pytest.fixture(scope="module")
def case():
    return load_case(CASES / "rv40e-105.toml")


@pytest.fixture(scope="module")
def disc(case):
    return solids.disc_solid(case)


def test_the_disc_is_a_valid_solid_with_the_volume_of_its_profile_minus_its_holes(case, disc):
    # reference: shoelace area of 2^17 profile points (Richardson), minus 1 centre, 3 crank and
    # 3 pillar holes, times the width; measured agreement 1e-10 relative, bound 1e-6; loose
    # bounds: pi r_root^2 .. pi r_tip^2 minus the same holes
    v = solids.disc_volume_bounds(case)
    measured = solids.volume_mm3(disc)
    assert disc.val().isValid()
    assert v.lower_mm3 < measured < v.upper_mm3
    assert measured == pytest.approx(v.reference_mm3, rel=1e-6)


def test_the_cad_outline_follows_the_analytic_profile_below_half_a_micron(case):
    # 96 spline points per tooth: measured 0.019 um (RV-40E); the FE meshes need sub-micron
    assert solids.profile_deviation_mm(case, solids.tooth_edges(case), samples_per_edge=150) < 5e-4


def test_the_second_disc_is_clocked_by_half_a_tooth(case):
    # its outline lies on the profile turned by pi / zc (same 0.5 um bound), not on the first's
    edges = solids.tooth_edges(case, index=1)
    assert solids.profile_deviation_mm(case, edges, index=1, samples_per_edge=40) < 5e-4
    assert solids.profile_deviation_mm(case, edges, index=0, samples_per_edge=40) > 0.1


def test_the_crankshaft_has_the_volume_of_its_cylinders(case):
    # core of journal radius over the whole length (seat, journals, shaft) + the eccentrics'
    # excess over the core
    # (the core lies inside each eccentric: 9 + 1.3 < 12), to 1e-7 relative
    lay = solids.crankshaft_layout(case)
    z0, z1 = lay.z_range_mm
    ecc_len = sum(b - a for a, b in lay.eccentrics_mm)
    expected = math.pi * (lay.journal_radius_mm**2 * (z1 - z0)
                          + (lay.eccentric_radius_mm**2 - lay.journal_radius_mm**2) * ecc_len)
    shaft = solids.crankshaft_solid(case)
    assert shaft.val().isValid()
    assert solids.volume_mm3(shaft) == pytest.approx(expected, rel=1e-7)


def test_the_crankshaft_layout_puts_journals_on_the_bearings_and_eccentrics_between(case):
    lay = solids.crankshaft_layout(case)
    span, lj, w = 50.0, 13.25, 10.0             # rv40e-105 case file (30203: T = 13.25)
    assert lay.journals_mm == ((-lj / 2, lj / 2), (span - lj / 2, span + lj / 2))
    assert lay.planet_seat_mm == (-3 * lj / 2, -lj / 2)
    assert lay.eccentrics_mm == ((span / 2 - w, span / 2), (span / 2, span / 2 + w))
    assert lay.eccentric_phase_deg == (0.0, 180.0)
    assert lay.eccentric_centre_mm(1) == pytest.approx((-1.3, 0.0))


def test_a_span_too_short_for_the_discs_is_refused(case):
    with pytest.raises(CaseError, match=r"support_span_mm = 25.*allowed span >= 33.25"):
        solids.crankshaft_layout(case.replace("crankshaft", support_span_mm=25.0))


def test_the_pin_is_a_cylinder_spanning_both_discs(case):
    pin = solids.pin_solid(case)
    assert solids.volume_mm3(pin) == pytest.approx(math.pi * 3.0**2 * 20.0, rel=1e-9)


def test_overlapping_disc_holes_are_refused_before_any_cad(case):
    # pillar hole 20 + 1.3 + 0.5 mm at 36 mm, 60 deg from a 15 mm crank hole at 36 mm: overlap 0.8 mm
    with pytest.raises(CaseError, match="pillar1 overlap by 0.8"):
        solids.disc_solid(case.replace("carrier", pillar_radius_mm=20.0))


def outline_points(shape, z):
    """Points on the spline edges of a located disc at height z (the CAD outline, ground frame)."""
    pts = []
    for e in shape.Edges():
        if e.geomType() == "BSPLINE" and abs(e.startPoint().z - z) < 1e-9:
            a, b = e._bounds()
            pts += [e.positionAt(u, mode="parameter").toTuple()[:2] for u in np.linspace(a, b, 250)]
    return np.array(pts)


def test_the_assembly_places_every_part_by_the_pose_convention(case):
    # DESIGN.md pose: the assembled CAD outline must show the gaps the clearance kernel computes
    # for that crank angle: per pin min |outline - pin centre| - Rr against pin_distances_mm,
    # within 0.5 um (sampling 0.05 mm apart costs < 0.2 um); disc 2 is disc 1 at psi + pi
    psi_deg = 30.0
    parts = dict(solids.assembly(case, psi_deg, include_housing=False))
    assert len(parts) == 2 + 40 + 3
    pins = np.array([[64 * math.cos(2 * math.pi * k / 40), 64 * math.sin(2 * math.pi * k / 40)] for k in range(40)])
    for k, (name, z) in enumerate((("disc1", 0.0), ("disc2", 10.0))):
        pts = outline_points(parts[name], z)
        cad_gap = np.sqrt(((pts[None] - pins[:, None]) ** 2).sum(-1)).min(axis=1) - 3.0
        kernel = pin_distances_mm(case, math.radians(psi_deg) + k * math.pi)
        assert np.max(np.abs(cad_gap - kernel)) < 5e-4
    # each eccentric sits in its disc's crank hole: circle centres on the outer faces (z = 0 for
    # disc 1, z = 20 for disc 2) coincide to 1e-6 mm
    def centres(shape, radius, z):
        return [e.arcCenter() for e in shape.Edges() if e.geomType() == "CIRCLE"
                and abs(e.radius() - radius) < 1e-9 and abs(e.startPoint().z - z) < 1e-9]
    for j in (1, 2, 3):
        for name, z in (("disc1", 0.0), ("disc2", 20.0)):
            ecc = centres(parts[f"crankshaft{j}"], 12.0, z)
            assert len(ecc) == 1
            assert min(math.hypot(h.x - ecc[0].x, h.y - ecc[0].y) for h in centres(parts[name], 15.0, z)) < 1e-6


def random_case(rng):
    """A valid reducer drawn over declared ranges; every other size scales with R."""
    import tomllib
    raw = tomllib.loads((CASES / "rv40e-105.toml").read_text())
    R = rng.uniform(40.0, 120.0)                 # pin circle radius [mm]
    zp = int(rng.integers(16, 51))               # pins
    k1 = rng.uniform(0.5, 0.9)                   # E zp / R
    E = k1 * R / zp
    from geometry.clearance import min_convex_radius_mm
    rr_max = min(0.6 * R * math.sin(math.pi / zp), 0.8 * min_convex_radius_mm(R, E, zp))
    Rr = rng.uniform(0.5, 1.0) * rr_max          # pin radius, below overlap and undercut limits
    w = rng.uniform(5.0, 20.0)                   # disc width
    rc, hole, nd = 0.55 * R, 0.22 * R, 0.05 * R  # crank circle, crank hole, needle diameter
    raw["cycloid"] |= dict(pin_circle_radius_mm=R, pin_radius_mm=Rr, zp=zp, zc=zp - 1,
                           eccentricity_mm=E, width_mm=w)
    raw["modification"] |= dict(offset_mm=rng.uniform(-0.02, 0.0), equidistant_mm=rng.uniform(0.0, 0.02),
                                rotation_deg=rng.uniform(-0.01, 0.01))
    raw["stage1"] |= dict(z1=10, z2=26, module_mm=2 * rc / 36)
    raw["carrier"] |= dict(crank_circle_radius_mm=rc, pillar_circle_radius_mm=rc, pillar_radius_mm=0.08 * R)
    raw["disc"] |= dict(crank_hole_radius_mm=hole, centre_hole_radius_mm=0.2 * R, pillar_hole_clearance_mm=0.3)
    ecc = hole - nd
    raw["crankshaft"] |= dict(eccentric_radius_mm=ecc, needle_diameter_mm=nd, journal_radius_mm=0.7 * ecc,
                              needle_count=int(0.85 * 2 * math.pi * (ecc + nd / 2) / nd),
                              journal_length_mm=0.8 * w, support_span_mm=2.8 * w + 10.0, needle_length_mm=w)
    # the housing by the case files' rules: a 0.2 R wall outside the grooves, bolts outside it
    ring = R + Rr + 0.2 * R
    raw["housing"] |= dict(pin_ring_outer_radius_mm=ring, pin_ring_length_mm=2 * w + 2.0,
                           bolt_circle_radius_mm=ring + 7.5, bolt_hole_radius_mm=3.3,
                           flange_outer_radius_mm=ring + 15.0)
    return case_from_dict(raw, source="random draw")


def test_a_seeded_sweep_of_valid_reducers_gives_valid_solids_within_their_bounds():
    # cq_gears-style stability sweep: 4 seeded draws; each disc valid, between the loose bounds
    # and within 1e-6 of the reference; crankshaft valid; CAD outline within 1 um of the profile
    rng = np.random.default_rng(20261121)
    for _ in range(4):
        cs = random_case(rng)
        disc = solids.disc_solid(cs)
        v = solids.disc_volume_bounds(cs, n=1 << 15)
        measured = solids.volume_mm3(disc)
        assert disc.val().isValid(), cs.cycloid
        assert v.lower_mm3 < measured < v.upper_mm3
        assert measured == pytest.approx(v.reference_mm3, rel=1e-6), cs.cycloid
        assert solids.crankshaft_solid(cs).val().isValid()
        assert solids.profile_deviation_mm(cs, solids.tooth_edges(cs), samples_per_edge=20) < 1e-3


def test_an_invalid_solid_is_never_exported(tmp_path):
    # a bow-tie outline: OpenCascade calls it invalid; nothing may be written
    w = cq.Wire.makePolygon([cq.Vector(0, 0, 0), cq.Vector(10, 10, 0), cq.Vector(10, 0, 0),
                             cq.Vector(0, 10, 0)], close=True)
    bad = cq.Solid.extrudeLinear(cq.Face.makeFromWires(w), cq.Vector(0, 0, 1))
    with pytest.raises(InvalidSolidError, match="bowtie: the CAD solid is not valid"):
        export_solid(bad, tmp_path, "bowtie")
    assert list(tmp_path.iterdir()) == []


def test_export_writes_step_and_stl_and_nothing_else(case, tmp_path):
    export_solid(solids.pin_solid(case), tmp_path, "pin")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["pin.step", "pin.stl"]
    assert cq.importers.importStep(str(tmp_path / "pin.step")).val().isValid()
