"""3D crankshaft bending and torsion (P2 tetrahedra, scikit-fem), and the
plain-shaft verification against beam theory.

Crankshaft model: the project's solid, geometry.solids.crankshaft_solid(case), with its
zones from crankshaft_layout(case): planet seat | journal 1 centred at z = 0 | core at journal
radius | eccentric 1 (+x) | eccentric 2 (-x) | core | journal 2 centred at z = span.
Supports: the support bearings act as pins: the MEAN lateral displacement of the journal-surface
nodes in a band of about one element at each bearing centre is held (plus mean axial and mean
tangential at bearing 1), so the shaft is simply supported at the bearing centres (the bearings' own compliance is the separate
support_bearing spring). Loads are uniform tractions (resultants F or T) on the eccentric's
cylindrical surface or the planet-seat end face; deflections are averages over the loaded
region (the lumped model's node), rotations least-squares over the section.
Limits: linear elastic, no fillets, no keyways/splines, needle-race hardening ignored.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from fem import hertz
from fem.mesh import (Mesh3D, MeshError, equal_area_polygon, extruded_cylinder, extruded_tets, inside_convex,
                      tet_mesh_from_solid, triangulate, z_levels)


@dataclass(frozen=True)
class ShaftResult:
    bending_stiffness_N_per_m: float
    torsional_stiffness_Nm_per_rad: float
    dofs: int
    edge_length_m: float


def _traction(basis_cls, mesh, facets, elem, vec_fn):
    from skfem import FacetBasis, LinearForm, asm
    fb = FacetBasis(mesh, elem, facets=facets)

    @LinearForm
    def form(v, w):
        t = vec_fn(w.x)
        return sum(t[i] * v[i] for i in range(3))
    return asm(form, fb), fb


def _area(mesh, facets, elem) -> float:
    from skfem import FacetBasis, Functional, asm
    fb = FacetBasis(mesh, elem, facets=facets)
    return float(asm(Functional(lambda w: 1.0 + 0 * w.x[0]), fb))


def _polar_moment(mesh, facets, elem) -> float:
    """Integral of x^2 + y^2 over the facets (the meshed section, not the ideal circle)."""
    from skfem import FacetBasis, Functional, asm
    fb = FacetBasis(mesh, elem, facets=facets)
    return float(asm(Functional(lambda w: w.x[0] ** 2 + w.x[1] ** 2), fb))


def p2_stiffness(mesh3: Mesh3D, E: float, nu: float):
    """(vector P2 basis, K): the stiffness assembled by one einsum per chunk of tets
    (fem.sparse_fe.elasticity_matrix: skfem's generic form, 900 basis pairs one by one, took ~40 % of
    the crankshaft problems), the same matrix to round-off: both quadratures are exact on affine P2."""
    from skfem import Basis, ElementTetP2, ElementVector, MeshTet
    from fem.sparse_fe import elasticity_matrix
    m = MeshTet(np.ascontiguousarray(mesh3.points.T), np.ascontiguousarray(mesh3.tetrahedra.T))
    basis = Basis(m, ElementVector(ElementTetP2()), intorder=2)
    return basis, elasticity_matrix(m, ElementTetP2(), basis, E, nu)


def held_solve(K: sp.spmatrix, fixed: np.ndarray, F: np.ndarray) -> np.ndarray:
    """K u = F with u = 0 on `fixed` (K SPD on the rest), P2 basis: fem.sparse_fe.spd_solve (its
    test: SuperLU of the same system, tests/test_fem_shaft.py)."""
    from fem.sparse_fe import spd_solve
    free = np.setdiff1d(np.arange(K.shape[0]), fixed)
    U = np.zeros((K.shape[0],) + np.shape(F)[1:])
    Ff = np.asarray(F, float)[free]
    U[free] = spd_solve(sp.csr_matrix(K)[free][:, free], Ff.reshape(len(free), -1)).reshape(Ff.shape)
    return U


def _rigid_modes(basis) -> np.ndarray:
    """(N, 6) the rigid motions at the DOFs: translations x, y, z, rotations about x, y, z."""
    x = basis.doflocs
    R = np.zeros((basis.N, 6))
    comp = np.empty(basis.N, np.int64)
    for arr in (basis.nodal_dofs, basis.edge_dofs):
        for i in range(3):
            comp[arr[i]] = i
    for i in range(3):
        m = comp == i
        j, k = (i + 1) % 3, (i + 2) % 3                  # (e_j x x)_i = x_k, (e_k x x)_i = -x_j
        R[m, i] = 1.0
        R[m, 3 + j], R[m, 3 + k] = x[k, m], -x[j, m]
    return R


def _three_two_one(basis, R: np.ndarray) -> np.ndarray:
    """Six vertex DOFs that hold exactly the rigid motions (3-2-1: all of the vertex at the lowest z,
    x and y of the vertex farthest from it, one component of the vertex farthest from that axis):
    statically determinate, so a self-equilibrated load leaves them without reaction."""
    p = basis.mesh.p
    a = int(np.argmin(p[2]))
    b = int(np.argmax(np.linalg.norm(p - p[:, [a]], axis=0)))
    axis = (p[:, b] - p[:, a]) / np.linalg.norm(p[:, b] - p[:, a])
    rel = p - p[:, [a]]
    c = int(np.argmax(np.linalg.norm(rel - np.outer(axis, axis @ rel), axis=0)))
    t = np.cross(axis, rel[:, c])
    nd = basis.nodal_dofs
    ib = np.argsort(-np.abs(axis))[1:]                   # the two components across the axis
    fixed = np.array([nd[0, a], nd[1, a], nd[2, a], nd[ib[0], b], nd[ib[1], b], nd[int(np.argmax(np.abs(t))), c]])
    if np.linalg.cond(R[fixed]) > 1e8:
        raise RuntimeError("3-2-1 support of the shaft mesh is degenerate")
    return fixed


def pinned_solve(basis, K: sp.spmatrix, Cm: sp.spmatrix, F: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """K u + Cm^T lam = F, Cm u = 0 for constraints Cm (6 rows) that hold exactly the rigid motions
    R (K R = 0): the saddle-point system solved through one SPD factorization instead of an
    indefinite one (exact, not a penalty): lam = (Cm R)^-T R^T F makes F - Cm^T lam self-equilibrated,
    w solves it held 3-2-1 (no reaction there), u = w + R a with a = -(Cm R)^-1 Cm w.
    Returns (u (N, m), lam (6, m))."""
    F = np.asarray(F, float)
    R = _rigid_modes(basis)
    CR = np.asarray(Cm @ R)
    lam = np.linalg.solve(CR.T, R.T @ F)
    G = F - Cm.T @ lam
    fixed = _three_two_one(basis, R)
    W = held_solve(K, fixed, G)
    reaction = (K @ W - G)[fixed]
    if np.abs(reaction).max() > 1e-8 * np.abs(G).max():
        raise RuntimeError(f"3-2-1 support carries {np.abs(reaction).max():.3g}: the constraints do not hold "
                           "exactly the rigid motions")
    return W + R @ np.linalg.solve(CR, -(Cm @ W)), lam


def _dof_xyz(basis) -> np.ndarray:
    """Coordinates of every DOF (3 per location), from the basis' global DOF locations."""
    return basis.doflocs.T


def plain_shaft_check(radius_m: float = 5e-3, length_m: float = 100e-3, E: float = 206e9,
                      nu: float = 0.3, edge_length_m: float = 2.5e-3, *, mesher: str = "extruded") -> dict:
    """Cantilever plain shaft: end face z = 0 clamped, tip face z = L loaded by a transverse
    force F and separately by a torque T. FE (tip-face averages) against Timoshenko beam theory
    and Saint-Venant torsion (fem.hertz). Mesher 'extruded' (fem.mesh.extruded_cylinder,
    deterministic) or 'tetwild' (pytetwild on the CadQuery cylinder; varies run to run)."""
    if mesher == "extruded":
        m3 = extruded_cylinder(radius_m, 0.0, length_m, edge_length_m)
    elif mesher == "tetwild":
        import cadquery as cq
        m3 = tet_mesh_from_solid(cq.Workplane("XY").circle(radius_m * 1e3).extrude(length_m * 1e3), edge_length_m)
    else:
        raise MeshError(f"plain shaft mesher = {mesher!r}: allowed 'extruded', 'tetwild'")
    F, T = 100.0, 10.0
    res = _cantilever(m3, radius_m, length_m, E, nu, F, T)
    res["bending_closed_form_m"] = hertz.cantilever_tip_deflection(F, length_m, radius_m, E, nu)
    res["twist_closed_form_rad"] = hertz.shaft_twist(T, length_m, radius_m, E, nu)
    # the tessellated section is a polygon inside the circle: Saint-Venant with its own J
    res["twist_closed_form_meshed_section_rad"] = T * length_m / (E / (2 * (1 + nu)) * res["tip_J_m4"])
    res["bending_error"] = res["tip_deflection_m"] / res["bending_closed_form_m"] - 1
    res["torsion_error"] = res["twist_rad"] / res["twist_closed_form_rad"] - 1
    res["edge_length_m"] = edge_length_m
    return res


def _cantilever(m3: Mesh3D, radius_m, length_m, E, nu, F, T) -> dict:
    basis, K = p2_stiffness(m3, E, nu)
    mesh = basis.mesh
    tol = 1e-3 * length_m
    root = basis.get_dofs(lambda x: x[2] < tol).all()
    tip = mesh.facets_satisfying(lambda x: x[2] > length_m - tol)
    elem = basis.elem
    area = _area(mesh, tip, elem)
    f_b, fb = _traction(None, mesh, tip, elem, lambda x: np.array([0 * x[0] + F / area, 0 * x[0], 0 * x[0]]))
    J = _polar_moment(mesh, tip, elem)
    f_t, _ = _traction(None, mesh, tip, elem, lambda x: np.array([-T * x[1] / J, T * x[0] / J, 0 * x[0]]))
    u = held_solve(K, root, np.column_stack([f_b, f_t]))
    xyz = basis.doflocs
    tipd = basis.get_dofs(tip)
    ix, iy = tipd.nodal["u^1"], tipd.nodal["u^2"]
    ux_mean = float(u[ix, 0].mean())
    x, y = xyz[0, ix], xyz[1, ix]
    rot = float(np.sum(x * u[iy, 1] - y * u[ix, 1]) / np.sum(x * x + y * y))
    return {"tip_deflection_m": ux_mean, "twist_rad": rot, "dofs": int(K.shape[0]), "tip_J_m4": J}


def default_edge_length_m(case) -> float:
    """Tet edge length of the crankshaft mesh: journal radius / 2.5 (P2 elements: within 3 % of beam
    theory on the plain-shaft check at this density)."""
    return case.crankshaft.journal_radius_mm * 1e-3 / 2.5


def crankshaft_fingerprint(case) -> str:
    """What the crankshaft solid depends on ([crankshaft] and [cycloid], see geometry.solids): a mesh
    made for another fingerprint is not this case's shaft."""
    import hashlib
    import json
    from dataclasses import asdict
    blob = json.dumps([asdict(case.crankshaft), asdict(case.cycloid)], sort_keys=True)
    return hashlib.sha256(blob.encode()).hexdigest()[:16]


SURFACE_SIZE = 0.5     # element size on the circles and next to the section steps, units of h


def _section_loops(circles, spacing: float) -> list[np.ndarray]:
    """Polygons of circles (cx, cy, r) that may cross: each an equal-area polygon (fem.mesh) with
    sides at most `spacing` long, and every crossing of two of them one vertex of both, at the same
    coordinates (a crossed circle's vertices lie on its equal-area radius for the uncrossed side
    count: its area within ~0.1 %). Why: a crossing that Triangle has to insert between two
    polygons' own vertices leaves near-coincident vertices (measured: 3 um apart), and their
    triangles extruded over a layer are needles (3D quality 1e-7) that stall the solver."""
    n = [max(16, int(math.ceil(2 * math.pi * r / spacing))) for _, _, r in circles]
    rv = [r * math.sqrt(2 * math.pi / (k * math.sin(2 * math.pi / k))) for (_, _, r), k in zip(circles, n)]
    fixed = [[] for _ in circles]                           # (angle about its centre, point)
    for i in range(len(circles)):
        for j in range(i + 1, len(circles)):
            (xi, yi, _), (xj, yj, _) = circles[i], circles[j]
            d = math.hypot(xj - xi, yj - yi)
            if not abs(rv[i] - rv[j]) < d < rv[i] + rv[j]:
                continue
            a = (rv[i] ** 2 - rv[j] ** 2 + d * d) / (2 * d)
            hh = math.sqrt(max(rv[i] ** 2 - a * a, 0.0))
            ux, uy = (xj - xi) / d, (yj - yi) / d
            for sgn in (1.0, -1.0):
                pt = (xi + a * ux - sgn * hh * uy, yi + a * uy + sgn * hh * ux)
                fixed[i].append((math.atan2(pt[1] - yi, pt[0] - xi) % (2 * math.pi), pt))
                fixed[j].append((math.atan2(pt[1] - yj, pt[0] - xj) % (2 * math.pi), pt))
    loops = []
    for (cx, cy, r0), k, r, fx in zip(circles, n, rv, fixed):
        if not fx:
            loops.append(equal_area_polygon(cx, cy, r0, k))
            continue
        fx.sort()
        pts = []
        for (a0, p0), (a1, _) in zip(fx, fx[1:] + [(fx[0][0] + 2 * math.pi, None)]):
            m = max(1, int(math.ceil((a1 - a0) * r / spacing)))
            pts.append(p0)
            pts.extend((cx + r * math.cos(a0 + (a1 - a0) * q / m), cy + r * math.sin(a0 + (a1 - a0) * q / m))
                       for q in range(1, m))
        loops.append(np.array(pts))
    return loops


def extruded_crankshaft_mesh(case, edge_length_m: float) -> Mesh3D:
    """Tets of crankshaft_solid(case) as prisms of one Triangle mesh (fem.mesh.extruded_tets): the
    journal circle and every eccentric's circle embedded (_section_loops, sides h / 2 long), each
    layer keeping the triangles inside its section (the journal circle, plus the eccentric's over an
    eccentric). Levels through every step (seat, journal ends, bearing centres, eccentric ends),
    h / 2 next to a step growing to h. Minimum angle 10 deg, not Triangle's usual 30: two eccentrics
    cross at 2 asin(e / r_e) (8.8 deg on the RV-160N), an input angle no refinement removes; at 30 deg
    Triangle fans 0.2 mm triangles into each tip, extruded into needles (3D quality 0.007, the
    PCG of that time took 137 iterations); at 10 deg 0.05 and 71. Measured (RV-160N, h = r_j / 2.5):
    bending stiffness / stepped beam 0.846, 0.834, 0.828 at h, h / 1.5, h / 2 (monotone, 2 % from
    the finest); pytetwild at h 0.859 (it varies run to run); torsion 0.930..0.932."""
    from geometry.solids import crankshaft_layout
    lay = crankshaft_layout(case)
    h = edge_length_m * 1e3
    rj, re = lay.journal_radius_mm, lay.eccentric_radius_mm
    if not (0 < h <= rj):
        raise MeshError(f"crankshaft edge length = {edge_length_m:g} m: allowed (0, {rj * 1e-3:g}] m "
                        f"(the journal radius at most)")
    centres = [lay.eccentric_centre_mm(i) for i in range(len(lay.eccentrics_mm))]
    journal, *eccentrics = _section_loops([(0.0, 0.0, rj)] + [(x, y, re) for x, y in centres], SURFACE_SIZE * h)
    reach = max([rj] + [math.hypot(x, y) + re for x, y in centres]) + h
    box = equal_area_polygon(0.0, 0.0, reach, 16)          # around everything; its triangles are never kept
    p2, tri = triangulate(box * 1e-3, edge_length_m, extra_loops=[lp * 1e-3 for lp in [journal, *eccentrics]],
                          min_angle_deg=10)
    p2 = p2 * 1e3
    cen = p2[tri].mean(axis=1)
    in_journal = inside_convex(journal, cen)
    in_section = [in_journal | inside_convex(poly, cen) for poly in eccentrics]
    steps = [*lay.planet_seat_mm, *(z for j in lay.journals_mm for z in j), 0.0, lay.support_span_mm,
             *(z for e in lay.eccentrics_mm for z in e)]
    steps_z = np.array(steps)

    def size_z(z: float) -> float:
        return h * min(SURFACE_SIZE + float(np.min(np.abs(z - steps_z))) / rj, 1.0)
    z = z_levels(steps, size_z)

    def keep(_k: int, zm: float) -> np.ndarray:
        for (a, b), sec in zip(lay.eccentrics_mm, in_section):
            if a < zm < b:
                return sec
        return in_journal
    m, _ = extruded_tets(p2, tri, z, keep)
    return Mesh3D(m.points * 1e-3, m.tetrahedra)


def crankshaft_mesh(case, edge_length_m: float | None = None, *, mesher: str = "extruded") -> Mesh3D:
    """Tetrahedra of geometry.solids.crankshaft_solid(case): mesher 'extruded' (default: deterministic,
    milliseconds) or 'tetwild' (pytetwild on the CadQuery solid: ~12 s and not reproducible run to
    run, the cross-check of tests/test_fem_shaft.py)."""
    h = edge_length_m or default_edge_length_m(case)
    if mesher == "extruded":
        return extruded_crankshaft_mesh(case, h)
    if mesher != "tetwild":
        raise MeshError(f"crankshaft mesher = {mesher!r}: allowed 'extruded', 'tetwild'")
    from geometry.solids import crankshaft_solid
    return tet_mesh_from_solid(crankshaft_solid(case), h)


def crankshaft_stiffness(case, edge_length_m: float | None = None, *,
                         mesh3: Mesh3D | None = None) -> tuple[ShaftResult, dict]:
    """Lateral stiffness at eccentric 1 (force along x, shaft pinned at the bearing centres) and
    torsional stiffness from the planet-seat end face to eccentric 1 (eccentric surface held).
    mesh3: a tet mesh of crankshaft_solid(case) made beforehand (the mesh stage), else meshed here."""
    from geometry.solids import crankshaft_layout
    k = case.crankshaft
    E, nu = case.material.youngs_modulus_GPa * 1e9, case.material.poisson_ratio
    lay = crankshaft_layout(case)
    h = edge_length_m or default_edge_length_m(case)
    m3 = mesh3 if mesh3 is not None else crankshaft_mesh(case, h)
    basis, K = p2_stiffness(m3, E, nu)
    mesh = basis.mesh
    rj, re = k.journal_radius_mm * 1e-3, k.eccentric_radius_mm * 1e-3
    span = k.support_span_mm * 1e-3
    band = 0.6 * h
    on_journal = lambda x: np.abs(np.hypot(x[0], x[1]) - rj) < 0.03 * rj  # noqa: E731
    d1 = basis.get_dofs(lambda x: on_journal(x) & (np.abs(x[2]) < band))
    d2 = basis.get_dofs(lambda x: on_journal(x) & (np.abs(x[2] - span) < band))
    for d in (d1, d2):
        if len(d.nodal["u^1"]) < 3:
            raise RuntimeError("support band caught too few nodes: refine the crankshaft mesh")
    # pins, not clamps: holding every band node would also hold the slope (a clamp, measured 1.7x
    # stiffer). Instead the band's MEAN lateral displacement is zero (Lagrange multipliers), plus
    # mean axial and mean tangential at bearing 1: the six rigid modes, no moment restraint.
    xyz = basis.doflocs
    rows = []
    for d, comps in ((d1, ("u^1", "u^2", "u^3", "rot")), (d2, ("u^1", "u^2"))):
        ix, iy = d.nodal["u^1"], d.nodal["u^2"]
        for comp in comps:
            if comp == "rot":
                r = np.hypot(xyz[0, ix], xyz[1, ix])
                rows.append((np.concatenate([ix, iy]), np.concatenate([-xyz[1, ix] / r, xyz[0, ix] / r]) / len(ix)))
            else:
                rows.append((d.nodal[comp], np.full(len(d.nodal[comp]), 1.0 / len(d.nodal[comp]))))
    n = K.shape[0]
    Cm = sp.csr_matrix((np.concatenate([w for _, w in rows]),
                        (np.repeat(np.arange(len(rows)), [len(c) for c, _ in rows]),
                         np.concatenate([c for c, _ in rows]))), shape=(len(rows), n))
    ez0, ez1 = (z * 1e-3 for z in lay.eccentrics_mm[0])
    ex, ey = (v * 1e-3 for v in lay.eccentric_centre_mm(0))
    ecc_surf = mesh.facets_satisfying(lambda x: (np.abs(np.hypot(x[0] - ex, x[1] - ey) - re) < 0.03 * re)
                                      & (x[2] > ez0 - 1e-9) & (x[2] < ez1 + 1e-9))
    area = _area(mesh, ecc_surf, basis.elem)
    F = 1000.0
    f, _ = _traction(None, mesh, ecc_surf, basis.elem, lambda x: np.array([0 * x[0] + F / area, 0 * x[0], 0 * x[0]]))
    u = pinned_solve(basis, K, Cm, f)[0]
    de = basis.get_dofs(ecc_surf)
    kb = F / float(u[de.nodal["u^1"]].mean())
    # torsion: eccentric 1 surface held, torque on the planet-seat end face
    zs = lay.planet_seat_mm[0] * 1e-3
    face = mesh.facets_satisfying(lambda x: x[2] < zs + 1e-3 * span)
    T = 10.0
    J = _polar_moment(mesh, face, basis.elem)
    ft, _ = _traction(None, mesh, face, basis.elem, lambda x: np.array([-T * x[1] / J, T * x[0] / J, 0 * x[0]]))
    ut = held_solve(K, np.concatenate([de.nodal["u^1"], de.nodal["u^2"], de.nodal["u^3"]]), ft)
    dfc = basis.get_dofs(face)
    ix, iy = dfc.nodal["u^1"], dfc.nodal["u^2"]
    x, y = basis.doflocs[0, ix], basis.doflocs[1, ix]
    rot = float(np.sum(x * ut[iy] - y * ut[ix]) / np.sum(x * x + y * y))
    result = ShaftResult(kb, T / rot, int(K.shape[0]), h)
    nd = basis.nodal_dofs   # vertex displacements (the P2 mid-edge dofs are not needed for a picture)
    uv = np.column_stack([u[nd[0]], u[nd[1]], u[nd[2]]])[: len(m3.points)]
    return result, {"mesh": m3, "displacement_m": uv}


def crankshaft_beam_reference(case, n: int = 20001) -> dict:
    """Stepped-beam closed form of the FE's two load cases, on the layout's actual sections.
    Bending: simply supported at the bearing centres, the FE's uniform load F over eccentric 1;
    by unit-load (virtual work with the same distributed load, i.e. the load-averaged deflection
    the FE reports) delta = int M^2/(E I(z) F) + V^2/(kappa G A(z) F) dz, each section a circle
    about its own centroid (journal radius in the core, eccentric radius over the eccentrics).
    Torsion: T L / (G J) of the journal-radius shaft from the planet-seat face to eccentric 1.
    Limits: plane sections; the steps' local flexibility and 3D load spreading are not included."""
    from geometry.solids import crankshaft_layout
    lay = crankshaft_layout(case)
    E, nu = case.material.youngs_modulus_GPa * 1e9, case.material.poisson_ratio
    G, kappa = E / (2 * (1 + nu)), hertz.timoshenko_shear_coefficient(nu)
    span = lay.support_span_mm * 1e-3
    z = np.linspace(0.0, span, n)
    r = np.full(n, lay.journal_radius_mm * 1e-3)
    for a, b in lay.eccentrics_mm:
        r[(z >= a * 1e-3) & (z <= b * 1e-3)] = lay.eccentric_radius_mm * 1e-3
    I, A = np.pi * r ** 4 / 4, np.pi * r ** 2
    c, d = (v * 1e-3 for v in lay.eccentrics_mm[0])
    F, q = 1.0, 1.0 / (d - c)
    R1 = F * (span - 0.5 * (c + d)) / span
    load_left = q * np.clip(z - c, 0.0, d - c)                        # load to the left of z
    V = R1 - load_left
    M = R1 * z - load_left * (z - 0.5 * (c + np.clip(z, c, d)))
    defl = np.trapezoid(M ** 2 / (E * I) + V ** 2 / (kappa * G * A), z) / F
    _, J = hertz.circle_inertia(lay.journal_radius_mm * 1e-3)
    length_t = (lay.eccentrics_mm[0][0] - lay.planet_seat_mm[0]) * 1e-3
    return {"bending_stiffness_N_per_m": 1 / defl, "torsional_stiffness_Nm_per_rad": G * J / length_t,
            "method": "stepped Timoshenko beam by unit-load integration over the layout's sections"}
