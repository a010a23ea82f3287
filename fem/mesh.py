"""Meshes: 2D graded triangulations of contact bodies, 3D tetrahedra from CadQuery solids, VTU export.

2D (Shewchuk's Triangle through the `triangle` package): every boundary is a parametric curve
sampled with a spacing graded toward one or more focus points (the contact points):
    h(s) = clip(growth * d(s), h_min, h_max),  d = arc-length distance to the nearest focus,
and Triangle's quality mesher (minimum angle 30 deg, no Steiner points on the boundary) grades
the interior from that boundary spacing. Boundary nodes therefore lie exactly on the true curve
(the modified cycloid, the pin circle), which matters: a chord of length h on a radius R misses
the curve by h^2 / (8 R), comparable to the Hertz gap b^2 / (2 R') unless h << b.

3D: bodies that are unions of z-extrusions of circles (the crankshaft, the carrier) are prisms of one
2D Triangle mesh (every section's circles embedded, crossings split by Triangle), cut into three tets
each by the vertex-index rule (conforming; Dompierre et al. 1999): deterministic, milliseconds.
pytetwild tetrahedralizes a tessellated CadQuery solid (envelope-bounded surface error) where a body
is not such a union, and cross-checks the extrusions; fTetWild is not reproducible run to run.

Lengths are metres in every mesh; boundary node sets are named and ordered along their curve.
"""
from __future__ import annotations

import contextlib
import json
import math
import os
import tempfile
import threading
import zipfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np

from geometry.artifacts import InputError, atomic_path
from geometry.fingerprint import Provenance


class MeshError(InputError):
    """A mesh request that cannot be met (sizes out of range, a solid that does not mesh)."""


@dataclass(frozen=True)
class Mesh2D:
    points: np.ndarray                 # (n, 2) [m]
    triangles: np.ndarray              # (k, 3) node indices, counter-clockwise
    boundary: dict = field(default_factory=dict)   # name -> ordered node indices

    @property
    def min_edge_m(self) -> float:
        e = self.points[self.triangles[:, [1, 2, 0]]] - self.points[self.triangles]
        return float(np.sqrt((e ** 2).sum(-1)).min())

    def transformed(self, rotation_rad: float = 0.0, shift_m=(0.0, 0.0)) -> "Mesh2D":
        c, s = np.cos(rotation_rad), np.sin(rotation_rad)
        p = self.points @ np.array([[c, s], [-s, c]]) + np.asarray(shift_m)
        return Mesh2D(p, self.triangles, dict(self.boundary))


@dataclass(frozen=True)
class Mesh3D:
    points: np.ndarray                 # (n, 3) [m]
    tetrahedra: np.ndarray             # (k, 4)
    made_from: Provenance | None = field(default=None, compare=False)   # of a mesh read from disk


MESH_SCHEMA = "rv-crankshaft-mesh/3"   # the mesh stage's .npz; 2: carries made_from; 3: extruded (deterministic)


def graded_parameters(curve: Callable[[np.ndarray], np.ndarray], t0: float, t1: float,
                      focus_t, h_min: float, h_max: float, growth: float,
                      n_dense: int = 20001) -> np.ndarray:
    """Curve parameters from t0 to t1 (both included) whose arc-length spacing follows
    h = clip(growth * distance to the nearest focus, h_min, h_max)."""
    if not (0 < h_min <= h_max):
        raise MeshError(f"mesh sizes: need 0 < h_min <= h_max, got h_min = {h_min:g} m, h_max = {h_max:g} m")
    if not (0 < growth < 1):
        raise MeshError(f"mesh growth = {growth!r}: allowed (0, 1)")
    if t1 < t0:   # np.interp needs increasing abscissae: grade the reversed curve
        return graded_parameters(curve, t1, t0, focus_t, h_min, h_max, growth, n_dense)[::-1]
    t = np.linspace(t0, t1, n_dense)
    xy = curve(t)
    s = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(xy, axis=0).T))])
    focus_s = np.interp(np.atleast_1d(focus_t), t, s) if len(np.atleast_1d(focus_t)) else np.array([])
    if s[-1] / h_min > 2e6:
        raise MeshError(f"mesh size at the contact {h_min:g} m is too small for a {s[-1]:g} m boundary")

    def h(si: float) -> float:
        d = np.min(np.abs(focus_s - si)) if focus_s.size else np.inf
        return float(np.clip(growth * d, h_min, h_max))

    out = [0.0]
    while True:
        si = out[-1]
        # step with the smaller of h here and h half a step ahead (keeps the grading smooth)
        step = min(h(si), h(si + 0.5 * h(si)))
        if si + step >= s[-1] - 0.5 * step:
            break
        out.append(si + step)
    out.append(s[-1])
    return np.interp(np.asarray(out), s, t)


def _segments(counts: list[int]) -> np.ndarray:
    """Closed-loop segments through consecutive vertices."""
    n = sum(counts)
    idx = np.arange(n)
    return np.column_stack([idx, np.roll(idx, -1)])


def triangulate(loop: np.ndarray, h_max: float, *, holes: np.ndarray | None = None,
                extra_loops: list[np.ndarray] = (), size: Callable | None = None,
                open_runs: list[np.ndarray] = (), min_angle_deg: float = 30.0) -> tuple[np.ndarray, np.ndarray]:
    """Quality triangulation of a closed polygon (vertices kept, in order, none added on the
    boundary); extra closed loops and open polylines (`open_runs`, kept as internal edges) may be
    added; size(xy) -> element size [m] grades the interior too (refined until every triangle fits)."""
    import triangle
    loops = [np.asarray(loop, float), *[np.asarray(l, float) for l in extra_loops]]
    runs = [np.asarray(r, float) for r in open_runs]
    verts = np.vstack(loops + runs)
    segs, start = [], 0
    for l in loops + runs:
        i = np.arange(start, start + len(l))
        closed = len(segs) < len(loops)
        segs.append(np.column_stack([i, np.roll(i, -1)]) if closed else np.column_stack([i[:-1], i[1:]]))
        start += len(l)
    # a vertex given twice (two loops meeting at a point) is one vertex, at its first place
    _, first, inv = np.unique(verts, axis=0, return_index=True, return_inverse=True)
    order = np.argsort(first)
    rank = np.empty(len(order), np.int64)
    rank[order] = np.arange(len(order))
    verts, segs = verts[np.sort(first)], rank[inv.ravel()][np.vstack(segs)]
    data = {"vertices": verts, "segments": segs}
    if holes is not None and len(holes):
        data["holes"] = np.asarray(holes, float)
    area = np.sqrt(3) / 4 * h_max ** 2
    # Triangle reads the area switch as a plain decimal ("a1.7e-06" is taken as a = 1.7), so write
    # it positional, every digit kept
    out = triangle.triangulate(data, f"pq{min_angle_deg:g}Ya{np.format_float_positional(area, trim='-')}")
    for _ in range(12 if size is not None else 0):
        p, t = out["vertices"], out["triangles"]
        want = np.sqrt(3) / 4 * size(p[t].mean(axis=1)) ** 2
        e1, e2 = p[t[:, 1]] - p[t[:, 0]], p[t[:, 2]] - p[t[:, 0]]
        have = 0.5 * np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])
        if np.all(have <= 1.5 * want):
            break
        out = triangle.triangulate(dict(out, triangle_max_area=np.minimum(want, area)), f"rpq{min_angle_deg:g}Ya")
    p, t = out["vertices"], out["triangles"].astype(np.int64)
    # counter-clockwise orientation for the element maps
    e1, e2 = p[t[:, 1]] - p[t[:, 0]], p[t[:, 2]] - p[t[:, 0]]
    cw = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0] < 0
    t[cw] = t[cw][:, [0, 2, 1]]
    if len(p) < len(verts) or not np.allclose(p[:len(verts)], verts):
        raise MeshError("triangulation moved boundary vertices (self-intersecting boundary?)")
    return p, t


def _focus_size(foci: np.ndarray, h_min: float, h_max: float, growth: float) -> Callable:
    """Interior size field: the boundary grading law with the distance to the nearest focus."""
    foci = np.atleast_2d(foci)

    def size(xy: np.ndarray) -> np.ndarray:
        d = np.min(np.hypot(xy[:, None, 0] - foci[None, :, 0], xy[:, None, 1] - foci[None, :, 1]), axis=1)
        return np.clip(growth * d, h_min, h_max)
    return size


def _circle(radius: float) -> Callable:
    return lambda t: np.column_stack([radius * np.cos(t), radius * np.sin(t)])


def pin_mesh(radius_m: float, h_min: float, h_max: float, growth: float = 0.08,
             contact_angle_rad: float = -np.pi / 2, *, opposite: bool = False) -> Mesh2D:
    """A full circle (pin, roller, needle) graded toward the boundary point at contact_angle
    (and the diametrically opposite point too when `opposite`: a needle between two races).
    Boundary sets: 'surface' (all, counter-clockwise from the contact point), 'back' (the half
    facing away from the contact), 'contact_arc' (the half facing it)."""
    a0 = contact_angle_rad
    foci = [a0, a0 + np.pi, a0 + 2 * np.pi] if opposite else [a0, a0 + 2 * np.pi]
    t = graded_parameters(_circle(radius_m), a0, a0 + 2 * np.pi, foci, h_min, h_max, growth)[:-1]
    loop = _circle(radius_m)(t)
    focus_xy = _circle(radius_m)(np.array(foci[:-1]))
    p, tri = triangulate(loop, h_max, size=_focus_size(focus_xy, h_min, h_max, growth))
    rel = (t - a0 + np.pi) % (2 * np.pi) - np.pi
    idx = np.arange(len(t))
    return Mesh2D(p, tri, {"surface": idx, "back": idx[np.abs(rel) >= np.pi / 2],
                           "contact_arc": idx[np.abs(rel) < np.pi / 2]})


def block_mesh(width_m: float, depth_m: float, h_min: float, h_max: float,
               growth: float = 0.08) -> Mesh2D:
    """Rectangle [-W/2, W/2] x [-D, 0] graded toward the origin on its top edge.
    Boundary sets: 'top' (left to right), 'bottom'."""
    top = graded_parameters(lambda s: np.column_stack([s, 0 * s]), width_m / 2, -width_m / 2,
                            [0.0], h_min, h_max, growth)
    side = lambda x0: graded_parameters(  # noqa: E731
        lambda s: np.column_stack([0 * s + x0, s]), 0.0, -depth_m, [0.0],
        max(h_min, growth * width_m / 2), h_max, growth)
    left = side(-width_m / 2)[1:-1]
    bottom = np.linspace(-width_m / 2, width_m / 2, max(2, int(np.ceil(width_m / h_max)) + 1))
    right = side(width_m / 2)[::-1][1:-1]
    loop = np.vstack([np.column_stack([top, 0 * top]),
                      np.column_stack([0 * left - width_m / 2, left]),
                      np.column_stack([bottom, 0 * bottom - depth_m]),
                      np.column_stack([0 * right + width_m / 2, right])])
    p, tri = triangulate(loop, h_max, size=_focus_size(np.zeros((1, 2)), h_min, h_max, growth))
    n_top = len(top)
    b0 = n_top + len(left)
    return Mesh2D(p, tri, {"top": np.arange(n_top)[::-1],
                           "bottom": np.arange(b0, b0 + len(bottom))})


def profile_sector_mesh(curve_mm: Callable[[np.ndarray], np.ndarray], t0: float, t1: float,
                        focus_t, inner_radius_m: float, h_min: float, h_max: float,
                        growth: float = 0.08) -> Mesh2D:
    """The disc region between a stretch of its profile (curve_mm(t) in mm, t0..t1) and an inner
    arc of radius inner_radius about the disc centre, closed by radial lines.
    Boundary sets: 'profile' (ordered t0 -> t1), 'inner' (the arc), 'sides' (radial lines)."""
    curve = lambda t: curve_mm(t) * 1e-3  # noqa: E731
    tp = graded_parameters(curve, t0, t1, focus_t, h_min, h_max, growth)
    prof = curve(tp)
    ends = [prof[-1], prof[0]]
    angle = [np.arctan2(e[1], e[0]) for e in ends]
    r_out = [np.hypot(*e) for e in ends]
    if inner_radius_m >= min(r_out):
        raise MeshError(f"inner radius {inner_radius_m:g} m must lie below the profile ({min(r_out):g} m)")

    def radial(a, r0, r1):
        n = max(2, int(np.ceil(abs(r1 - r0) / h_max)) + 1)
        r = np.linspace(r0, r1, n)[1:-1]
        return np.column_stack([r * np.cos(a), r * np.sin(a)])

    side1 = radial(angle[0], r_out[0], inner_radius_m)
    a_in0, a_in1 = angle[0], angle[1]
    da = (a_in1 - a_in0 + np.pi) % (2 * np.pi) - np.pi
    n_arc = max(3, int(np.ceil(abs(da) * inner_radius_m / h_max)) + 1)
    arc_a = a_in0 + da * np.linspace(0, 1, n_arc)
    arc = inner_radius_m * np.column_stack([np.cos(arc_a), np.sin(arc_a)])
    side2 = radial(angle[1], inner_radius_m, r_out[1])
    loop = np.vstack([prof, side1, arc, side2])
    p, tri = triangulate(loop, h_max, size=_focus_size(curve(np.atleast_1d(focus_t)), h_min, h_max, growth))
    n0 = len(prof)
    i_side1 = np.arange(n0, n0 + len(side1))
    i_arc = np.arange(n0 + len(side1), n0 + len(side1) + n_arc)
    i_side2 = np.arange(i_arc[-1] + 1, i_arc[-1] + 1 + len(side2))
    return Mesh2D(p, tri, {"profile": np.arange(n0), "inner": i_arc,
                           "sides": np.concatenate([i_side1, i_side2])})


def annulus_mesh(inner_radius_m: float, outer_radius_m: float, focus_angles_rad, h_min: float,
                 h_max: float, growth: float = 0.08, *, graded_side: str = "inner") -> Mesh2D:
    """Ring (or solid disc when inner_radius = 0) graded toward points of one of its circles.
    Boundary sets: 'inner', 'outer' (counter-clockwise)."""
    def ring(radius, graded):
        if graded:
            a0 = float(np.min(focus_angles_rad)) - np.pi / 180
            foci = np.concatenate([np.atleast_1d(focus_angles_rad), np.atleast_1d(focus_angles_rad) + 2 * np.pi])
            t = graded_parameters(_circle(radius), a0, a0 + 2 * np.pi, foci, h_min, h_max, growth)[:-1]
        else:
            t = np.linspace(0, 2 * np.pi, max(12, int(np.ceil(2 * np.pi * radius / h_max))), endpoint=False)
        return _circle(radius)(t)

    outer = ring(outer_radius_m, graded_side == "outer")
    if inner_radius_m <= 0:
        p, tri = triangulate(outer, h_max)
        return Mesh2D(p, tri, {"outer": np.arange(len(outer)), "inner": np.array([], int)})
    inner = ring(inner_radius_m, graded_side == "inner")
    p, tri = triangulate(outer, h_max, extra_loops=[inner], holes=np.zeros((1, 2)))
    return Mesh2D(p, tri, {"outer": np.arange(len(outer)),
                           "inner": np.arange(len(outer), len(outer) + len(inner))})


_CWD_LOCK = threading.Lock()   # the working directory is process-wide: one scratch user at a time


@contextlib.contextmanager
def _scratch_cwd():
    """Run a block inside a fresh temporary directory (fTetWild writes `__tracked_surface.stl`
    into the current directory); the previous cwd is restored and the scratch removed."""
    with _CWD_LOCK, tempfile.TemporaryDirectory(prefix="rvte-tetwild-") as tmp:
        old = os.getcwd()
        os.chdir(tmp)
        try:
            yield
        finally:
            os.chdir(old)


def tet_mesh_from_solid(solid, edge_length_m: float, *, tolerance_m: float | None = None) -> Mesh3D:
    """Tetrahedra (pytetwild) of a CadQuery solid/Workplane given in millimetres; output in metres.
    fTetWild runs in a scratch directory, so nothing is left in the caller's folder.
    fTetWild is not reproducible run to run (measured: the same surface gave 2112..2374 nodes, even
    single-threaded), so the mesh stage writes the mesh once and the fem stage reuses it: everything
    downstream of a mesh file is deterministic."""
    import pytetwild
    shape = solid.val() if hasattr(solid, "val") else solid
    tol = (tolerance_m or edge_length_m / 20) * 1e3
    verts, faces = shape.tessellate(tol, 0.2)
    v = np.array([(p.x, p.y, p.z) for p in verts], dtype=float)
    f = np.array(faces, dtype=np.int32)
    bbox = float(np.linalg.norm(v.max(0) - v.min(0)))
    with _scratch_cwd():
        p, t = pytetwild.tetrahedralize(v, f, edge_length_abs=edge_length_m * 1e3,
                                        epsilon=min(1e-3, tol / bbox), quiet=True)
    if len(t) == 0:
        raise MeshError("pytetwild produced no tetrahedra (open or degenerate solid)")
    p = np.asarray(p, float) * 1e-3
    t = np.asarray(t, np.int64)
    # positive orientation for the element maps
    d = np.einsum("ij,ij->i", np.cross(p[t[:, 1]] - p[t[:, 0]], p[t[:, 2]] - p[t[:, 0]]), p[t[:, 3]] - p[t[:, 0]])
    t[d < 0] = t[d < 0][:, [0, 2, 1, 3]]
    used = np.unique(t)
    remap = -np.ones(len(p), np.int64)
    remap[used] = np.arange(len(used))
    return Mesh3D(p[used], remap[t])


def equal_area_polygon(cx: float, cy: float, r: float, n: int) -> np.ndarray:
    """Regular n-gon with the circle's AREA (vertex radius r sqrt(2 pi / (n sin(2 pi / n)))),
    counter-clockwise from angle 0: an extrusion's volume is the solid's exactly; the second moment
    is within 0.7 % from 6 sides on."""
    rv = r * math.sqrt(2 * math.pi / (n * math.sin(2 * math.pi / n)))
    t = np.linspace(0.0, 2 * math.pi, n, endpoint=False)
    return np.column_stack([cx + rv * np.cos(t), cy + rv * np.sin(t)])


def inside_convex(poly: np.ndarray, xy: np.ndarray) -> np.ndarray:
    """Points strictly inside a convex counter-clockwise polygon (left of every edge)."""
    e = np.roll(poly, -1, axis=0) - poly
    rel = xy[:, None, :] - poly[None, :, :]
    return np.all(e[None, :, 0] * rel[:, :, 1] - e[None, :, 1] * rel[:, :, 0] > 0, axis=1)


def z_levels(breaks, size_z: Callable[[float], float]) -> np.ndarray:
    """z-levels through every break, graded by size_z(z) in between (marched, then scaled to land
    on the next break)."""
    b = np.unique(np.round(breaks, 9))
    out = [b[:1]]
    for z0, z1 in zip(b[:-1], b[1:]):
        s = [z0]
        while s[-1] < z1:
            s.append(s[-1] + min(size_z(s[-1]), size_z(min(s[-1] + 0.5 * size_z(s[-1]), z1))))
        if len(s) > 2 and s[-1] - z1 > 0.5 * (s[-1] - s[-2]):
            s.pop()                              # overshoot by more than half a step: one step fewer
        s = np.asarray(s)
        out.append(z0 + (s[1:] - z0) * (z1 - z0) / (s[-1] - z0))
    return np.concatenate(out)


def extruded_tets(p2: np.ndarray, tri: np.ndarray, z: np.ndarray,
                  keep: Callable[[int, float], np.ndarray | slice]) -> tuple[Mesh3D, np.ndarray]:
    """Tets of the prisms of a 2D mesh (p2, tri) between consecutive levels z; layer k holds the
    triangles keep(k, z_mid) (a mask or slice). Each prism is cut into three tets by the vertex-index
    rule (each quad's diagonal leaves its lowest index), so neighbouring prisms conform whichever
    layer they are in. Units are the caller's; returns (mesh, layer of each tet), positively
    oriented, unused vertices dropped."""
    n2 = len(p2)
    a, b, c = np.sort(tri, axis=1).T
    tets, layer = [], []
    for k in range(len(z) - 1):
        sel = keep(k, 0.5 * (z[k] + z[k + 1]))
        A, B, C = a[sel] + k * n2, b[sel] + k * n2, c[sel] + k * n2
        t = np.concatenate([np.column_stack([A, B, C, C + n2]), np.column_stack([A, B, B + n2, C + n2]),
                            np.column_stack([A, A + n2, B + n2, C + n2])])
        tets.append(t)
        layer.append(np.full(len(t), k))
    p = np.column_stack([np.tile(p2, (len(z), 1)), np.repeat(z, n2)])
    t = np.concatenate(tets)
    d = np.einsum("ij,ij->i", np.cross(p[t[:, 1]] - p[t[:, 0]], p[t[:, 2]] - p[t[:, 0]]), p[t[:, 3]] - p[t[:, 0]])
    t[d < 0] = t[d < 0][:, [0, 2, 1, 3]]                 # positive orientation
    used = np.unique(t)
    remap = -np.ones(len(p), np.int64)
    remap[used] = np.arange(len(used))
    return Mesh3D(p[used], remap[t]), np.concatenate(layer)


def extruded_cylinder(radius_m: float, z0_m: float, z1_m: float, edge_length_m: float,
                      surface_size: float = 0.5) -> Mesh3D:
    """A plain round shaft as prisms (extruded_tets): the circle's equal-area polygon with sides
    surface_size * h, Triangle inside it, uniform levels about h apart. Deterministic, for the
    beam-theory checks (pytetwild's draws vary: its 4 mm plain shaft bent 1.2 % to 12.6 % off)."""
    n = max(6, math.ceil(2 * math.pi * radius_m / (surface_size * edge_length_m)))
    p2, tri = triangulate(equal_area_polygon(0.0, 0.0, radius_m, n), edge_length_m)
    z = np.linspace(z0_m, z1_m, max(2, math.ceil((z1_m - z0_m) / edge_length_m)) + 1)
    return extruded_tets(p2, tri, z, lambda _k, _z: slice(None))[0]


def cylinder_band_facets(msk, cx: float, cy: float, radius: float, z0: float, z1: float,
                         radial_tol: float, z_tol: float) -> np.ndarray:
    """Boundary facets of a skfem tet mesh whose vertices all lie on the cylinder of `radius` about
    (cx, cy) (within radial_tol) and inside z0 - z_tol <= z <= z1 + z_tol: a bore or journal band
    (a rigid ring's surface). Metres."""
    bf = msk.boundary_facets()
    x = msk.p[:, msk.facets[:, bf]]                     # (3, 3 vertices, n facets)
    ok = (np.abs(np.hypot(x[0] - cx, x[1] - cy) - radius) < radial_tol) & (x[2] > z0 - z_tol) & (x[2] < z1 + z_tol)
    return bf[ok.all(axis=0)]


def write_vtu(path: str | Path, points: np.ndarray, cells: np.ndarray,
              point_data: dict | None = None, cell_data: dict | None = None) -> None:
    """Write triangles/tetrahedra (meshio) atomically; 2D points get z = 0 (ParaView-ready)."""
    import meshio
    pts = np.asarray(points, float)
    if pts.shape[1] == 2:
        pts = np.column_stack([pts, np.zeros(len(pts))])
    kind = {3: "triangle", 4: "tetra", 6: "triangle6", 10: "tetra10"}[cells.shape[1]]
    m = meshio.Mesh(pts, [(kind, np.asarray(cells))], point_data=point_data or {},
                    cell_data={k: [np.asarray(v)] for k, v in (cell_data or {}).items()})
    with atomic_path(path) as tmp:
        meshio.write(tmp, m, file_format="vtu")


def save_mesh3d(path: str | Path, mesh: Mesh3D, made_from=None, **meta: str | float) -> None:
    """A tet mesh and what it was made from (a geometry.fingerprint.Provenance, stored as JSON, and
    e.g. the solid's fingerprint), atomically (.npz)."""
    if made_from is not None:
        meta["made_from"] = json.dumps(made_from.to_json(), sort_keys=True)
    with atomic_path(path) as tmp:
        with open(tmp, "wb") as fh:
            np.savez(fh, points=mesh.points, tetrahedra=mesh.tetrahedra,
                     **{f"meta_{k}": np.asarray(v) for k, v in meta.items()})


def load_mesh3d(path: str | Path, case=None, **expect: str | float) -> Mesh3D:
    """Read a mesh of `save_mesh3d`; every `expect` entry must match the stored one, and with `case`
    the mesh must have been made from that case as it is now (its fingerprint)."""
    path = Path(path)
    if not path.exists():
        raise MeshError(f"{path}: mesh not found (run `python -m pipeline mesh` first)")
    try:
        z = np.load(path)
    except (OSError, ValueError, EOFError, zipfile.BadZipFile) as exc:   # EOFError: an empty file
        raise MeshError(f"{path}: not a mesh of the mesh stage ({exc}); rerun `python -m pipeline mesh`") from None
    with z:
        made = None
        if case is not None:
            stored = z["meta_made_from"].item() if "meta_made_from" in z.files else None
            made = Provenance.from_json(None if stored is None else json.loads(stored), str(path))
            made.check(case, str(path), f"python -m pipeline mesh --case {case.source or case.name} "
                                        f"--out {path.parent}", artifact=MESH_SCHEMA)
        for key, want in expect.items():
            got = z[f"meta_{key}"].item() if f"meta_{key}" in z.files else None
            if got != want:
                raise MeshError(f"{path}: made for {key} = {got!r}, this case needs {want!r}; "
                                f"rerun `python -m pipeline mesh` for this case")
        return Mesh3D(z["points"].copy(), z["tetrahedra"].copy(), made)
