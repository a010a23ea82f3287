"""`python -m pipeline fem`: the FEM stage (stiffness.json, meshes, pictures) or the Hertz benchmark.

    python -m pipeline mesh --case CASE.toml --out DIR [--crank-edge-mm H] [--quiet]
    python -m pipeline fem --case CASE.toml --out DIR [--mesh MESHDIR] [--mesh-size-mm H] [--quiet]
    python -m pipeline fem --benchmark hertz --radius-mm R --width-mm L --load-N F --out DIR
                           [--counter-radius-mm Rc] [--mesh-size-mm H]
"""
from __future__ import annotations

import math
import time
from pathlib import Path

import numpy as np

from geometry.artifacts import InputError, write_json_atomic


def register(sub) -> None:
    m = sub.add_parser("mesh", help="the crankshaft tet mesh (extruded sections) that the fem stage reuses")
    m.add_argument("--case", required=True, help="case TOML")
    m.add_argument("--out", required=True, help="output folder")
    m.add_argument("--crank-edge-mm", type=float, default=None,
                   help="tet edge length [mm], journal radius / 10 to the journal radius "
                        "(default: journal radius / 2.5)")
    m.add_argument("--quiet", action="store_true")
    m.set_defaults(func=run_mesh)
    p = sub.add_parser("fem", help="FE stiffness of a case, or the Hertz contact benchmark")
    src = p.add_mutually_exclusive_group(required=True)
    src.add_argument("--case", help="case TOML")
    src.add_argument("--benchmark", choices=["hertz"], help="verification benchmark")
    p.add_argument("--out", required=True, help="output folder")
    p.add_argument("--mesh-size-mm", type=float, default=None,
                   help="element size at the contact [mm] (default: 1/12 of the smallest Hertz half-width)")
    p.add_argument("--mesh", default=None, help="folder of the mesh stage (crankshaft_mesh.npz) to reuse")
    p.add_argument("--workers", type=int, default=None,
                   help="local processes for the independent FE problems (tooth map, crankshaft, carrier, ...), "
                        "1-64; default: the cores")
    p.add_argument("--scheduler", default=None, help="Dask scheduler address (runs the FE problems there)")
    p.add_argument("--radius-mm", type=float)
    p.add_argument("--width-mm", type=float)
    p.add_argument("--load-N", type=float)
    p.add_argument("--counter-radius-mm", type=float, default=None)
    p.add_argument("--quiet", action="store_true")
    p.set_defaults(func=run)


MESH_FILE = "crankshaft_mesh.npz"
# --crank-edge-mm at least journal radius / 10 (4x finer than the default r_j / 2.5: 558k tets, 0.6 GB
# for the mesh stage on the RV-40E; r_j / 20: 5.3M tets, 1.6 GB; r_j / 40: 41M tets, 9 GB, 100 s)
MIN_EDGE_FRACTION = 10


def run_mesh(args) -> int:
    """The mesh stage: the 3D crankshaft tets (the slow, load-independent part of the FE stage),
    as .npz for `fem --mesh` and .vtu for ParaView. The 2D tooth mesh depends on the contact
    positions and Hertz widths, so the fem stage makes it itself (seconds)."""
    from fem.mesh import MESH_SCHEMA, save_mesh3d, write_vtu
    from fem.shaft import crankshaft_fingerprint, crankshaft_mesh, default_edge_length_m
    from geometry.fingerprint import made_from
    from geometry.params import load_case
    if args.crank_edge_mm is not None and not (args.crank_edge_mm > 0):
        raise InputError(f"--crank-edge-mm = {args.crank_edge_mm}: must be positive")
    t0 = time.perf_counter()
    case = load_case(args.case)
    if args.crank_edge_mm is not None:
        from pipeline.checks import number_in
        rj = case.crankshaft.journal_radius_mm
        number_in("--crank-edge-mm", args.crank_edge_mm, rj / MIN_EDGE_FRACTION, rj, "mm",
                  why=f"journal radius / {MIN_EDGE_FRACTION} to the journal radius: each halving of the edge "
                      "makes 8x the tets; at journal radius / 40 the mesh alone takes ~9 GB")
    h = args.crank_edge_mm * 1e-3 if args.crank_edge_mm else default_edge_length_m(case)
    m3 = crankshaft_mesh(case, h)
    out = Path(args.out)
    write_vtu(out / "crankshaft_mesh.vtu", m3.points, m3.tetrahedra)
    save_mesh3d(out / MESH_FILE, m3, made_from=made_from(case, MESH_SCHEMA), case=case.name,
                fingerprint=crankshaft_fingerprint(case), edge_length_m=h)
    if not args.quiet:
        print(f"mesh {case.name}: crankshaft {len(m3.points)} nodes, {len(m3.tetrahedra)} tets, edge "
              f"{h * 1e3:.2f} mm; {time.perf_counter() - t0:.0f} s -> {out / MESH_FILE}")
    return 0


def run(args) -> int:
    if args.mesh_size_mm is not None and not (args.mesh_size_mm > 0):
        raise InputError(f"--mesh-size-mm = {args.mesh_size_mm}: must be positive")
    out = Path(args.out)
    if args.benchmark:
        return _benchmark(args, out)
    return _case(args, out)


def _benchmark(args, out: Path) -> int:
    from fem.pin_contact import hertz_benchmark
    for name in ("radius_mm", "width_mm", "load_N"):
        if getattr(args, name) is None:
            raise InputError(f"--benchmark hertz needs --{name.replace('_', '-')}")
    rc = math.inf if args.counter_radius_mm is None else args.counter_radius_mm * 1e-3
    r = hertz_benchmark(args.radius_mm * 1e-3, args.width_mm * 1e-3, args.load_N, counter_radius_m=rc,
                        mesh_size_m=None if args.mesh_size_mm is None else args.mesh_size_mm * 1e-3)
    write_json_atomic(out / "hertz.json", r.to_json())
    if not args.quiet:
        j = r.to_json()
        print(f"hertz: p0 {j['peak_pressure_MPa']:.1f} MPa (closed form {j['peak_pressure_closed_form_MPa']:.1f}), "
              f"b {j['half_width_mm'] * 1e3:.2f} um ({j['half_width_closed_form_mm'] * 1e3:.2f}), "
              f"approach {j['approach_um']:.3f} um ({j['approach_closed_form_um']:.3f}) -> {out / 'hertz.json'}")
    return 0


def _case(args, out: Path) -> int:
    import dataclasses

    from fem import stiffness
    from fem.reduce import build_stiffness
    from geometry.fingerprint import made_from
    from geometry.params import load_case
    t0 = time.perf_counter()
    case = load_case(args.case)
    from pipeline.checks import int_in
    if args.workers is not None:
        int_in("--workers", args.workers, 1, 64, "local processes")
    crank_mesh = None
    if args.mesh and Path(args.mesh).is_file():
        raise InputError(f"--mesh {args.mesh}: is a file; give the mesh stage's folder (its --out), "
                         f"which holds {MESH_FILE}")
    if args.mesh:
        from fem.mesh import load_mesh3d
        from fem.shaft import crankshaft_fingerprint
        crank_mesh = load_mesh3d(Path(args.mesh) / MESH_FILE, case=case,
                                 fingerprint=crankshaft_fingerprint(case))
    import os
    from functools import partial
    from pipeline.sweep import run_tasks
    workers = args.workers or os.cpu_count() or 1
    if workers > 1 and not args.scheduler:
        import geometry.solids  # noqa: F401  imported once here, the forked workers inherit it (cadquery: 5-8 s a process)
    runres = build_stiffness(case, mesh_size_m=None if args.mesh_size_mm is None else args.mesh_size_mm * 1e-3,
                             crank_mesh=crank_mesh,
                             map_tasks=partial(run_tasks, workers=workers, scheduler=args.scheduler))
    # what it was made from: the case and, when reused, the mesh stage's mesh
    prov = made_from(case, stiffness.SCHEMA, mesh=crank_mesh.made_from if crank_mesh is not None else None)
    stiffness.save(dataclasses.replace(runres.model, made_from=prov), out / "stiffness.json")
    write_json_atomic(out / "timings.json", {"case": case.name, "wall_s": runres.timings_s,
                                             "note": "wall seconds of this run (not in stiffness.json, which "
                                                     "is the same bytes for the same inputs on one BLAS thread)"})
    _write_meshes(runres, out)
    _pictures(runres, out)
    if "housing_fe" in runres.artifacts:
        from pipeline.housing_figure import housing_png
        housing_png(case, out / "housing.png", runres.artifacts["housing_fe"])
    if not args.quiet:
        print(summary_line(runres.model, time.perf_counter() - t0, out / "stiffness.json"))
    return 0


def summary_line(m, seconds: float, path) -> str:
    """The stage's console line: the new figures of each part of the compliance path, briefly."""
    k = m.extras["tooth_secant_stiffness_at_rated_N_per_m"]
    sb, C = m.support_bearings, m.crank_bending.compliance_m_per_N
    ch = m.checks
    return (f"fem {m.case_name}: {len(m.pin_contact.position_deg)} positions x {len(m.pin_contact.load_N)} loads "
            f"(to {m.pin_contact.load_N[-1]:.0f} N); tooth {min(k) / 1e6:.0f}..{max(k) / 1e6:.0f} N/um at rated; "
            f"support {sb.designation} Z {sb.roller_count}, {sb.stiffness_N_per_m / 1e6:.0f} N/um at "
            f"{sb.operating_load_N:.0f} N (preload {sb.preload_N:.0f} N); crank C11 {C[0, 0] * 1e9:.2f}, "
            f"C12 {C[0, 1] * 1e9:.2f} nm/N (FE/beam {ch['crank_bending']['fe_over_beam_C11']:.2f}); carrier "
            f"{ch['carrier']['torsional_stiffness_Nm_per_arcmin']:.0f} N m/arcmin; disc body "
            f"{1e-6 / m.pin_series.disc_body_compliance_m_per_N:.0f} N/um per pin; groove "
            f"{ch['pin_groove']['tangent_at_rated_N_per_m'] / 1e6:.0f} N/um at rated; crank torsion "
            f"{m.crankshaft_torsional_stiffness_Nm_per_rad:.0f} N m/rad;"
            + (f" crank path assembled/lumped {ch['crank_path']['crank_path_assembled_over_lumped']:.3f};"
               if "crank_path" in ch else "") + f" {seconds:.0f} s -> {path}")


def _write_meshes(runres, out: Path) -> None:
    from fem.mesh import write_vtu
    tm = runres.tooth_map
    write_vtu(out / "disc_mesh.vtu", tm.disc_mesh.points, tm.disc_mesh.triangles)
    write_vtu(out / "pin_mesh.vtu", tm.pin_mesh_local.points, tm.pin_mesh_local.triangles)
    m3 = runres.crank_fields["mesh"]
    write_vtu(out / "crankshaft_mesh.vtu", m3.points, m3.tetrahedra)


def _pictures(runres, out: Path) -> None:
    import pyvista as pv
    from pipeline import render
    tm = runres.tooth_map
    tri = tm.disc_mesh.triangles
    pts3 = np.column_stack([tm.disc_mesh.points * 1e3, np.zeros(len(tm.disc_mesh.points))])
    faces = np.column_stack([np.full(len(tri), 3), tri]).ravel()
    disc = pv.PolyData(pts3, faces)
    snap = tm.snapshot
    pin_pts = tm.pin_mesh_local.points
    rot = math.atan2(snap["normal"][1], snap["normal"][0]) - math.pi / 2
    c, s = math.cos(rot), math.sin(rot)
    pg = pin_pts @ np.array([[c, s], [-s, c]]) + snap["centre_m"]
    pin = pv.PolyData(np.column_stack([pg * 1e3, np.zeros(len(pg))]),
                      np.column_stack([np.full(len(tm.pin_mesh_local.triangles), 3), tm.pin_mesh_local.triangles]).ravel())
    p = render.plotter()
    p.add_mesh(disc, show_edges=True, color="lightsteelblue", edge_color="black", line_width=0.3)
    p.add_mesh(pin, show_edges=True, color="wheat", edge_color="black", line_width=0.3)
    p.add_text(f"disc tooth + pin mesh ({len(tm.disc_mesh.points)} + {len(pin_pts)} nodes), "
               f"contact element {tm.mesh_size_m * 1e6:.2f} um", font_size=10, color="black")
    p.view_xy()
    render.screenshot(p, out / "mesh.png")
    vm = snap["von_mises_Pa"]
    disc.cell_data["von Mises [MPa]"] = vm / 1e6
    p = render.plotter()
    p.add_mesh(disc, scalars="von Mises [MPa]", cmap="turbo", clim=[0, float(np.percentile(vm, 99.9)) / 1e6])
    p.add_mesh(pin, style="wireframe", color="gray", line_width=0.3)
    r_pin_mm = float(np.max(np.linalg.norm(pin_pts, axis=1))) * 1e3    # this case's pin, not the RV-40E's 3 mm
    centre = snap["centre_m"] * 1e3 - snap["normal"] * r_pin_mm
    p.add_text(f"contact stress at {snap['position_deg']:.0f} deg, {snap['load_N']:.0f} N", font_size=10, color="black")
    p.view_xy()
    p.camera.focal_point = (*centre[:2], 0.0)
    p.camera.position = (*centre[:2], 20.0)
    p.camera.parallel_projection = True
    p.camera.parallel_scale = 0.4
    render.screenshot(p, out / "contact_stress.png")
    f = runres.crank_fields
    m3, uv = f["mesh"], f["displacement_m"]
    grid = pv.UnstructuredGrid({pv.CellType.TETRA: m3.tetrahedra}, m3.points * 1e3)
    grid.point_data["|u| [um]"] = np.linalg.norm(uv, axis=1) * 1e6
    warped = grid.copy()
    warped.points = grid.points + uv * 1e3 * (2.0 / max(np.abs(uv).max() * 1e3, 1e-12))
    p = render.plotter()
    p.add_mesh(warped, scalars="|u| [um]", cmap="viridis", show_edges=True, edge_color="gray", line_width=0.2)
    p.add_text("crankshaft under 1 kN at eccentric 1 (deflection magnified)", font_size=10, color="black")
    p.view_xz()
    render.screenshot(p, out / "crankshaft.png")
