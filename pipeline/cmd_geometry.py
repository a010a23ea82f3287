"""`python -m pipeline geometry --case CASE.toml --out DIR [--quiet]`: the geometry stage.

Writes (each atomically): DIR/profile.csv (x_mm,y_mm: modified disc profile, disc frame, closed,
4001 rows), DIR/disc.step|stl, DIR/pin.step|stl, DIR/crankshaft.step|stl (each checked valid
first), DIR/assembly.png (off-screen picture of the assembled second stage) and DIR/geometry.json
(measured figures: disc volume and its analytic bounds, CAD deviation from the analytic profile,
minimum clearance and backlash, numerical and closed form).
"""
from __future__ import annotations

import argparse
import dataclasses
import io
import math
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from geometry.artifacts import write_json_atomic, write_text_atomic
from geometry.fingerprint import made_from
from geometry.params import ReducerCase, load_case
from geometry.profile import disc_profile, profile_args
# geometry.solids / export (CadQuery) and clearance (scipy) are imported where used: the CLI
# imports this module before it checks the options, and a bad option must fail in a second.

PROFILE_POINTS = 4000          # profile.csv rows (+1 closing row); the contract asks >= 2000
PICTURE_CRANK_ANGLE_DEG = 0.0
PART_COLOURS = {"disc1": "steelblue", "disc2": "darkorange", "pin": "lightgrey",
                "housing": "dimgrey", "crankshaft": "goldenrod"}


@dataclass(frozen=True)
class GeometryFigures:
    """What the geometry stage measured (the content of geometry.json)."""
    case: str
    disc_volume_mm3: float
    disc_volume_reference_mm3: float
    disc_volume_reference_error_mm3: float
    disc_volume_lower_bound_mm3: float
    disc_volume_upper_bound_mm3: float
    cad_profile_deviation_um: float
    cad_points_per_tooth: int
    min_clearance_um: float
    min_clearance_closed_form_um: float
    backlash_crank_angle_deg: float
    backlash_plus_arcmin: float
    backlash_minus_arcmin: float
    backlash_total_arcmin: float
    backlash_closed_form_total_arcmin: float          # same crank angle, the actual pins
    backlash_closed_form_bound_total_arcmin: float    # continuous pin phase (crank-angle minimum)
    min_convex_radius_mm: float                       # undercut limit of the modified pin radius
    modified_pin_radius_mm: float
    crankshaft_layout: dict


def profile_csv(case: ReducerCase, n: int = PROFILE_POINTS) -> str:
    """The modified profile, disc frame, closed (last row = first row)."""
    buf = io.StringIO()
    np.savetxt(buf, disc_profile(case, n=n, closed=True), delimiter=",", fmt="%.9f",
               header="x_mm,y_mm", comments="")
    return buf.getvalue()


def measure(case: ReducerCase, disc) -> GeometryFigures:
    """Figures of one case; `disc` is the solid of `solids.disc_solid(case)`."""
    from geometry import clearance, solids
    vol = solids.disc_volume_bounds(case)
    bl = clearance.backlash(case, math.radians(0.0))
    cf = clearance.closed_form_backlash(case, 0.0)
    bound = clearance.closed_form_backlash(case)
    args = profile_args(case)
    edges = solids.tooth_edges(case)
    return GeometryFigures(
        case=case.name,
        disc_volume_mm3=solids.volume_mm3(disc),
        disc_volume_reference_mm3=vol.reference_mm3,
        disc_volume_reference_error_mm3=vol.reference_error_mm3,
        disc_volume_lower_bound_mm3=vol.lower_mm3,
        disc_volume_upper_bound_mm3=vol.upper_mm3,
        cad_profile_deviation_um=solids.profile_deviation_mm(case, edges) * 1e3,
        cad_points_per_tooth=solids.POINTS_PER_TOOTH,
        min_clearance_um=clearance.min_clearance_mm(case) * 1e3,
        min_clearance_closed_form_um=clearance.closed_form_min_clearance_mm(case) * 1e3,
        backlash_crank_angle_deg=0.0,
        backlash_plus_arcmin=bl.plus_arcmin,
        backlash_minus_arcmin=bl.minus_arcmin,
        backlash_total_arcmin=bl.total_arcmin,
        backlash_closed_form_total_arcmin=cf.total_arcmin,
        backlash_closed_form_bound_total_arcmin=bound.total_arcmin,
        min_convex_radius_mm=clearance.min_convex_radius_mm(args["R"], args["E"], args["zp"]),
        modified_pin_radius_mm=args["Rr"],
        crankshaft_layout=dataclasses.asdict(solids.crankshaft_layout(case)),
    )


def render_assembly(case: ReducerCase, path: Path, crank_angle_deg: float = PICTURE_CRANK_ANGLE_DEG):
    """Off-screen picture of the assembled stage (half the housing cut away to show the mesh)."""
    import pyvista as pv

    from geometry import solids
    from pipeline.render import plotter, screenshot
    p = plotter()
    for name, shape in solids.assembly(case, crank_angle_deg):
        verts, tris = shape.tessellate(0.05, 0.3)
        faces = np.hstack([np.full((len(tris), 1), 3), np.asarray(tris)]).ravel()
        mesh = pv.PolyData(np.array([v.toTuple() for v in verts]), faces)
        key = name.rstrip("0123456789") if not name.startswith("disc") else name
        opacity = 0.25 if key == "housing" else 1.0
        p.add_mesh(mesh, color=PART_COLOURS.get(key, "grey"), opacity=opacity, smooth_shading=True)
    p.add_text(f"{case.name}: second stage at crank angle {crank_angle_deg:g} deg "
               f"(zc {case.cycloid.zc}, zp {case.cycloid.zp}, E {case.cycloid.eccentricity_mm} mm)",
               font_size=10, color="black")
    p.view_vector((0.35, -0.55, 1.0), viewup=(0, 1, 0))
    p.reset_camera()
    p.camera.zoom(1.25)
    screenshot(p, path)


def run_geometry(case: ReducerCase, out: Path, *, quiet: bool = False) -> GeometryFigures:
    """Build, check and write every artifact of the geometry stage for one case."""
    from geometry import solids
    from geometry.export import check_valid, export_solid
    t0 = time.perf_counter()
    say = (lambda *a: None) if quiet else (lambda *a: print(*a, flush=True))
    out = Path(out)
    write_text_atomic(out / "profile.csv", profile_csv(case))
    disc = solids.disc_solid(case)
    parts = {"disc": disc, "pin": solids.pin_solid(case), "crankshaft": solids.crankshaft_solid(case)}
    for name, body in parts.items():
        check_valid(body, f"{case.name} {name}")        # all valid before any file is written
    for name, body in parts.items():
        export_solid(body, out, name)
    say(f"geometry {case.name}: solids exported ({time.perf_counter() - t0:.1f} s)")
    figures = measure(case, disc)
    render_assembly(case, out / "assembly.png")
    write_json_atomic(out / "geometry.json", {**dataclasses.asdict(figures),
                                              "made_from": made_from(case, "rv-geometry/1").to_json()})
    say(f"geometry {case.name}: disc volume {figures.disc_volume_mm3:.1f} mm^3 (reference "
        f"{figures.disc_volume_reference_mm3:.1f}), CAD deviation {figures.cad_profile_deviation_um:.3f} um, "
        f"min clearance {figures.min_clearance_um:.2f} um, backlash {figures.backlash_total_arcmin:.3f} "
        f"arcmin (closed form {figures.backlash_closed_form_total_arcmin:.3f}) "
        f"[{time.perf_counter() - t0:.1f} s] -> {out}")
    return figures


def _run(args: argparse.Namespace) -> int:
    run_geometry(load_case(args.case), Path(args.out), quiet=args.quiet)
    return 0


def register(subparsers) -> None:
    p = subparsers.add_parser("geometry", help="profile, CAD solids (STEP/STL), picture, figures",
                              description=__doc__.split("\n\n")[0])
    p.add_argument("--case", required=True, help="case file (TOML)")
    p.add_argument("--out", required=True, help="output folder")
    p.add_argument("--quiet", action="store_true", help="print nothing on success")
    p.set_defaults(func=_run)
