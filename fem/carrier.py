"""The carrier (output flange + end plate + pillars) as a 3D FE body, condensed to the crank seats.

Body: geometry.carrier.CarrierGeometry (frame, ASSUMED sizes and the one-body assumption are stated
there); linear elastic, isotropic, small strain, SI units inside.
Elements: P2 tetrahedra. P1 locks in the pillars' bending: on the RV-40E carrier P1 gives 756, 651,
580, 527 N m/arcmin at h = 1, 2/3, 1/2, 1/3 pillar radii (12k..276k DOFs), still 15 % above the
P2 limit (459) at 276k DOFs, where P2 is 11 % above it at 88k DOFs on one mesh.
Boundary: the output flange's mounting face (z = g + t_f) clamped: it is bolted to the load.
Seats: each crank's two support-bearing cups (flange side, end-plate side) sit in bores; each
bore's surface over the bearing width is a RIGID RING: every displacement DOF on it follows
u = t + theta x (x - c) of 6 ring DOFs (c = the bearing centre on the crank axis), imposed by
master-slave elimination u = T q, K_q = T^T K T. Why: an exact multipoint constraint, no penalty
to tune and no Lagrange multipliers, so K_q stays symmetric positive definite and one sparse Cholesky
serves every load. Rigid because the hardened cup is press-fitted in the bore (its ovalisation and
the rollers are the bearing's own compliance). The ring's axial shift and three rotations carry no
load (a tapered pair carries the crank's tilt as radial forces at its two seats, nothing about the
crank axis): they are condensed out with the body.
Output: the flexibility C of the 2 nc ring translations (x, y), order crank j, seat (flange, end
plate), direction (x, y): 4 nc x 4 nc, symmetric positive definite. The output torque T reaches
the carrier as a tangential force T / (nc a) per crank (a = crank circle radius), a share s at the
flange seat and 1 - s at the end-plate seat; by reciprocity the output turns by phi = f^T C f T
(f: the seat forces of a unit torque), the load-weighted mean tangential seat translation over a.
Racking: the end plate's inner face turning relative to the flange's (least-squares rotation of
each face's nodes about the axis).
Mesh: the carrier is a union of z-extrusions (holed discs, circles), so it is meshed as prisms of
a 2D Triangle mesh (pillar circles embedded) cut into three tets each by the vertex-index rule
(conforming; Dompierre et al. 1999). Circles are equal-area polygons: the mesh volume is the CAD
volume exactly. Not pytetwild (fem.mesh.tet_mesh_from_solid, kept as mesher="tetwild"): on this
carrier it took 41 s at 8 mm edges and 110..400 s at 5..6 mm (2 shared cores) and is not
reproducible; the extrusion takes milliseconds, is deterministic, and grades toward the edges.
Convergence: the rigid-ring ends (bonded edge, stress ~ r^-1/2) and the re-entrant pillar roots
(~ r^-0.455) are singular, so the compliance error decays ~ h; `carrier_fe` extrapolates two
meshes with p = 1 (see there for the measured error).
Limits: bolted pillar joint bonded (an upper bound on stiffness), no fillets, bolt holes or main-bearing
raceways; the main bearings are no support (under a torque the end plate carries no net force).
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field, replace

import numpy as np
import scipy.sparse as sp

from fem import hertz
from fem.joint_layers import JointLayers, joint_layer_tets, layer_material
from fem.mesh import (Mesh3D, MeshError, cylinder_band_facets, equal_area_polygon, extruded_tets, inside_convex,
                      tet_mesh_from_solid, triangulate, z_levels)
from fem.sparse_fe import elasticity_matrix, node_ordered_lu_solve, spd_solve
from geometry.carrier import CarrierGeometry

ARCMIN_PER_RAD = 180 * 60 / math.pi
SEATS = ("flange", "end_plate")
END_PLATE, PILLAR, FLANGE = 0, 1, 2        # tet region labels
ROOT_SIZE = 0.5             # element size at the singular edges (pillar surfaces, seat bands), units of h
COARSEST = 2.5              # largest element, units of h
BORE_SIDES = 16             # fewest polygon sides of a bore or the rim (vertices within 1.3 % of r)
PILLAR_SIDES = 6            # fewest of a pillar (equal-area hexagon: bending inertia +0.7 %)
DEFAULT_LEVELS = (1.6, 1.0)  # the default estimate's two sizes h, in pillar radii (carrier_fe)
RICHARDSON_ORDER = 1.0       # the compliance error's order in h (singular edges, carrier_fe)
# ASSUMED (clamp='bolt_annulus'): an annulus 0.3 x the bolt-circle radius wide (15 / 27 mm): the VDI 2230
# cone of M8..M12 output bolts at the interface. Measured: 463 / 2198 N m/arcmin (RV-40E / RV-160N)
# against 465 / 2211 with the whole face held (-0.5 %): the clamp is not where compliance hides.
BOLT_ANNULUS_WIDTH = 0.3


def default_edge_length_m(g: CarrierGeometry) -> float:
    """h of one default mesh: the finer of DEFAULT_LEVELS."""
    return DEFAULT_LEVELS[1] * g.pillar_radius_mm * 1e-3


# ----------------------------------------------------------------------------- mesh
def _size_mm(g: CarrierGeometry, h: float):
    """Section size field [mm]: ROOT_SIZE h on the pillar and seat-bore circles (the singular
    edges lie on them), growing by h per pillar radius of distance up to COARSEST h. Every size
    scales with h: a mesh family."""
    c = np.array([(*g.pillar_xy_mm(j), g.pillar_radius_mm) for j in range(g.pillar_count)]
                 + [(*g.crank_xy_mm(j), g.seat_bore_radius_mm) for j in range(g.crank_count)])

    def size(xy: np.ndarray) -> np.ndarray:
        d = np.min(np.abs(np.hypot(xy[:, None, 0] - c[None, :, 0], xy[:, None, 1] - c[None, :, 1]) - c[None, :, 2]),
                   axis=1)
        return h * np.clip(ROOT_SIZE + d / g.pillar_radius_mm, ROOT_SIZE, COARSEST)
    return size


def _circle_mm(cx: float, cy: float, r: float, size, min_sides: int) -> np.ndarray:
    """Equal-area polygon (fem.mesh.equal_area_polygon) at the size field's spacing."""
    a = np.linspace(0, 2 * np.pi, 64)
    spacing = float(np.mean(size(np.column_stack([cx + r * np.cos(a), cy + r * np.sin(a)]))))
    return equal_area_polygon(cx, cy, r, max(min_sides, int(math.ceil(2 * math.pi * r / spacing))))


def extruded_mesh(g: CarrierGeometry, edge_length_m: float) -> tuple[Mesh3D, np.ndarray]:
    """Conforming tets of the carrier (see module) and each tet's region label; edge_length_m is
    h of the size field (h / 2 at the singular edges, up to 2.5 h away from them)."""
    h = edge_length_m * 1e3
    if not (0 < h <= g.pillar_radius_mm * 2):
        raise MeshError(f"carrier edge length = {edge_length_m:g} m: allowed (0, {g.pillar_radius_mm * 2e-3:g}] m "
                        f"(a pillar diameter at most)")
    size = _size_mm(g, h)
    holes = [g.crank_xy_mm(j) for j in range(g.crank_count)]
    loops = [_circle_mm(x, y, g.seat_bore_radius_mm, size, BORE_SIDES) for x, y in holes]
    if g.centre_bore_radius_mm > 0:
        loops.append(_circle_mm(0.0, 0.0, g.centre_bore_radius_mm, size, BORE_SIDES))
        holes.append((0.0, 0.0))
    pillars = [_circle_mm(*g.pillar_xy_mm(j), g.pillar_radius_mm, size, PILLAR_SIDES) for j in range(g.pillar_count)]
    # in metres with a size field: triangulate's refinement pass enforces it triangle by triangle
    p2, tri = triangulate(_circle_mm(0.0, 0.0, g.outer_radius_mm, size, BORE_SIDES) * 1e-3, COARSEST * edge_length_m,
                          holes=np.array(holes) * 1e-3, extra_loops=[lp * 1e-3 for lp in loops + pillars],
                          size=lambda xy: size(xy * 1e3) * 1e-3)
    p2 = p2 * 1e3
    in_pillar = np.zeros(len(tri), bool)
    for poly in pillars:
        in_pillar |= inside_convex(poly, p2[tri].mean(axis=1))
    bands = [zs + d for zs in g.seat_z_mm for d in (-g.bearing_width_mm / 2, g.bearing_width_mm / 2)]
    edges_z = np.array([0.0, g.gap_mm, *bands])          # pillar roots and ring ends

    def size_z(z: float) -> float:
        return h * min(ROOT_SIZE + float(np.min(np.abs(z - edges_z))) / g.pillar_radius_mm, COARSEST)
    z = z_levels([*g.end_plate_z_mm, *g.flange_z_mm, *bands], size_z)
    zm = 0.5 * (z[:-1] + z[1:])
    lab = np.where(zm < 0, END_PLATE, np.where(zm > g.gap_mm, FLANGE, PILLAR))
    m, layer = extruded_tets(p2, tri, z, lambda k, _: in_pillar if lab[k] == PILLAR else slice(None))
    return Mesh3D(m.points * 1e-3, m.tetrahedra), lab[layer]


def carrier_mesh(g: CarrierGeometry, edge_length_m: float | None = None, *,
                 mesher: str = "extruded") -> tuple[Mesh3D, np.ndarray]:
    """(tets, region per tet); mesher 'extruded' (default) or 'tetwild' (pytetwild on
    geometry.carrier.carrier_solid, uniform edges: slow and not reproducible, a cross-check)."""
    h = edge_length_m or default_edge_length_m(g)
    if mesher == "extruded":
        return extruded_mesh(g, h)
    if mesher != "tetwild":
        raise MeshError(f"carrier mesher = {mesher!r}: allowed 'extruded', 'tetwild'")
    from geometry.carrier import carrier_solid
    m = tet_mesh_from_solid(carrier_solid(g), h)
    zc = m.points[m.tetrahedra, 2].mean(axis=1) * 1e3
    return m, np.where(zc < 0, END_PLATE, np.where(zc > g.gap_mm, FLANGE, PILLAR))


# ----------------------------------------------------------------------------- rigid rings
def seat_facets(msk, g: CarrierGeometry, h: float, crank: int, seat_z_mm: float) -> np.ndarray:
    """Boundary facets of one rigid ring: every vertex on crank's seat bore (equal-area polygons put
    vertices up to 1.3 % outside r; tetwild's envelope is h / 20) and inside the bearing band."""
    cx, cy = (v * 1e-3 for v in g.crank_xy_mm(crank))
    rs, half, zc = g.seat_bore_radius_mm * 1e-3, g.bearing_width_mm * 0.5e-3, seat_z_mm * 1e-3
    return cylinder_band_facets(msk, cx, cy, rs, zc - half, zc + half, max(0.03 * rs, 0.06 * h), 1e-3 * h)


def _dof_components(basis) -> np.ndarray:
    comp = np.empty(basis.N, int)
    for arr in (basis.nodal_dofs, basis.edge_dofs, basis.facet_dofs, basis.interior_dofs):
        for i in range(arr.shape[0]):
            comp[arr[i]] = i
    return comp


def _ring_transform(basis, comp, rings, fixed) -> tuple[sp.csr_matrix, np.ndarray]:
    """T (N x (n_keep + 6 n_ring)), u = T q: kept DOFs one to one, each ring's DOFs the rigid motion
    t + theta x (x - c) of its 6 DOFs (tx, ty, tz, rx, ry, rz), appended last. rings: (DOFs on the
    ring surface, centre [m]). Returns T and the kept global DOFs."""
    slave = np.concatenate([d for d, _ in rings])
    if len(np.unique(slave)) != len(slave) or np.intersect1d(slave, fixed).size:
        raise MeshError("carrier seat rings overlap each other or the clamped face: refine the mesh")
    keep = np.setdiff1d(np.arange(basis.N), np.concatenate([slave, fixed]))
    rows, cols, vals = [keep], [np.arange(len(keep))], [np.ones(len(keep))]
    for k, (d, c) in enumerate(rings):
        r = basis.doflocs[:, d] - np.asarray(c)[:, None]
        one = np.ones(len(d))
        # component -> (ring column, coefficient): u = t + theta x r
        terms = {0: ((0, one), (4, r[2]), (5, -r[1])), 1: ((1, one), (5, r[0]), (3, -r[2])),
                 2: ((2, one), (3, r[1]), (4, -r[0]))}
        for i, pairs in terms.items():
            m = comp[d] == i
            for col, v in pairs:
                rows.append(d[m])
                cols.append(np.full(m.sum(), len(keep) + 6 * k + col))
                vals.append(v[m])
    T = sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                      shape=(basis.N, len(keep) + 6 * len(rings)))
    return T, keep


def _rigid_modes(x: np.ndarray, comp: np.ndarray) -> np.ndarray:
    """(len(comp), 6) rigid motions (3 translations, 3 rotations about the origin) at DOFs x (3, n)."""
    out = np.zeros((len(comp), 6))
    for i in range(3):
        m = comp == i
        out[m, i] = 1.0
        j, k = (i + 1) % 3, (i + 2) % 3                   # (e_j x x)_i = x_k, (e_k x x)_i = -x_j
        out[m, 3 + j], out[m, 3 + k] = x[k, m], -x[j, m]
    return out


def _ring_rigid(c: np.ndarray) -> np.ndarray:
    """(6, 6) ring coordinates (t at c, theta) of the six rigid motions about the origin."""
    out = np.zeros((6, 6))
    out[:3, :3] = np.eye(3)
    for k in range(3):
        out[:3, 3 + k] = np.cross(np.eye(3)[k], c)
        out[3 + k, 3 + k] = 1.0
    return out


# ----------------------------------------------------------------------------- result
@dataclass(frozen=True)
class CarrierFE:
    """The carrier condensed to its 2 nc seats (orders and conventions: module docstring)."""
    compliance_m_per_N: np.ndarray         # (4nc, 4nc) C, symmetrized
    plate_rotation_rad_per_N: np.ndarray   # (2, 4nc) inner-face rotation [flange, end plate] per unit seat force
    crank_angles_rad: np.ndarray           # (nc,)
    crank_circle_radius_m: float
    asymmetry: float                       # |C_raw - C_raw^T| / |C_raw| before symmetrizing (reciprocity)
    rigid_mode_residual: float             # max |T^T K u_rb| / (max|K| max|u_rb|), unclamped, 6 rigid motions
    equilibrium_residual: float            # clamp reactions + unit seat force (force, moment / rim radius)
    order: int
    edge_length_m: float
    nodes: int
    tets: int
    dofs: int                              # after the rings replace the bore DOFs and the clamp
    mesh_seconds: float
    solve_seconds: float                   # assembly, factorization, the 4 nc unit loads
    plate_modulus_factor: float = 1.0
    labels: tuple = ()
    extrapolation: dict = field(default_factory=dict)   # levels and order when Richardson-extrapolated

    @property
    def condition_number(self) -> float:
        return float(np.linalg.cond(self.compliance_m_per_N))

    def seat_forces_per_Nm(self, flange_share: float = 0.5) -> np.ndarray:
        return seat_forces_per_Nm(self.crank_angles_rad, self.crank_circle_radius_m, flange_share)

    def torsional_compliance_rad_per_Nm(self, flange_share: float = 0.5) -> float:
        f = self.seat_forces_per_Nm(flange_share)
        return float(f @ self.compliance_m_per_N @ f)

    def torsional_stiffness_Nm_per_arcmin(self, flange_share: float = 0.5) -> float:
        return 1.0 / (self.torsional_compliance_rad_per_Nm(flange_share) * ARCMIN_PER_RAD)

    def racking_rad_per_Nm(self, flange_share: float = 0.5) -> float:
        """End plate's rotation relative to the flange per N m of output torque."""
        r = self.plate_rotation_rad_per_N @ self.seat_forces_per_Nm(flange_share)
        return float(r[1] - r[0])


def seat_forces_per_Nm(crank_angles_rad, crank_circle_radius_m: float, flange_share: float = 0.5) -> np.ndarray:
    """Seat forces (4 nc, CarrierFE order) of a unit output torque: 1 / (nc a) tangential per crank, a
    flange_share at the flange seat, the rest at the end plate's."""
    if not (0.0 <= flange_share <= 1.0):
        raise ValueError(f"flange_share = {flange_share!r}: allowed [0, 1]")
    ang = np.asarray(crank_angles_rad, float)
    ft = 1.0 / (len(ang) * crank_circle_radius_m)
    f = np.zeros((len(ang), 2, 2))
    for s, share in enumerate((flange_share, 1.0 - flange_share)):
        f[:, s, 0], f[:, s, 1] = -share * ft * np.sin(ang), share * ft * np.cos(ang)
    return f.ravel()


# ----------------------------------------------------------------------------- joint layers
# ----------------------------------------------------------------------------- the FE model
def carrier_compliance(g: CarrierGeometry, E_Pa: float, nu: float, *, edge_length_m: float | None = None,
                       order: int = 2, plate_modulus_factor: float = 1.0, mesher: str = "extruded",
                       mesh: tuple[Mesh3D, np.ndarray] | None = None, solver: str = "pardiso",
                       clamp: str = "face", joints: JointLayers | None = None,
                       every_ring_dof: bool = False) -> CarrierFE | np.ndarray:
    """The carrier's seat flexibility on one mesh (see module). plate_modulus_factor multiplies E
    in both plates (the rigid-plate check); mesh: (tets, regions) made beforehand; solver 'pardiso'
    (fem.sparse_fe.spd_solve) or 'superlu' (node_ordered_lu_solve: its independent check). clamp: 'face' (the whole
    mounting face) or 'bolt_annulus' (the what-if of a flange held by its bolts alone). joints:
    contact layers of the pillar joint and the mounting face (JointLayers; None: bonded).
    every_ring_dof: return only the (6 nr, 6 nr) flexibility of every ring DOF (ring order of the
    seats; per ring tx, ty, tz, rx, ry, rz about its centre; fem.crank_path's assembled check)."""
    from skfem import Basis, ElementTetP1, ElementTetP2, ElementVector, MeshTet
    if order not in (1, 2):
        raise ValueError(f"carrier element order = {order!r}: allowed 1, 2")
    if solver not in ("pardiso", "superlu") or clamp not in ("face", "bolt_annulus"):
        raise ValueError(f"carrier solver = {solver!r}, clamp = {clamp!r}: allowed solver 'pardiso', 'superlu'; "
                         f"clamp 'face', 'bolt_annulus'")
    h = edge_length_m or default_edge_length_m(g)
    t0 = time.perf_counter()
    m3, region = mesh if mesh is not None else carrier_mesh(g, h, mesher=mesher)
    t_mesh, t0 = time.perf_counter() - t0, time.perf_counter()
    msk = MeshTet(np.ascontiguousarray(m3.points.T), np.ascontiguousarray(m3.tetrahedra.T))
    scalar = {1: ElementTetP1, 2: ElementTetP2}[order]()
    basis = Basis(msk, ElementVector(scalar))
    comp = _dof_components(basis)
    E_t = np.where(region == PILLAR, 1.0, plate_modulus_factor) * E_Pa
    nu_t, dG = np.full(len(region), float(nu)), np.zeros(len(region))
    if joints is not None and mesher == "extruded":
        for name, (idx, hl) in joint_layer_tets(m3, region == PILLAR, region == FLANGE,
                                                   g.mounting_face_z_mm * 1e-3).items():
            kn, kt = getattr(joints, f"{name}_normal_Pa_per_m"), getattr(joints, f"{name}_tangential_Pa_per_m")
            if kn is not None:
                E_t[idx], nu_t[idx], dG[idx] = layer_material(hl, E_t[idx], nu, kn, kt)
    elif joints is not None:
        raise ValueError("carrier joints need the extruded mesh (its z-levels give the layers)")
    K = elasticity_matrix(msk, scalar, basis, E_t, nu_t, shear_xz_Pa=dG if dG.any() else None)
    zf, rb, half = g.mounting_face_z_mm * 1e-3, g.bolt_circle_radius_mm * 1e-3, 0.5e-3 * BOLT_ANNULUS_WIDTH * g.bolt_circle_radius_mm
    held = lambda x: (x[2] > zf - 0.02 * h) & ((clamp == "face") | (abs(np.hypot(x[0], x[1]) - rb) <= half))  # noqa: E731
    fixed = basis.get_dofs(msk.facets_satisfying(held, boundaries_only=True)).all()
    rings, labels = [], []
    for j in range(g.crank_count):
        for s, zs in zip(SEATS, g.seat_z_mm):
            d = basis.get_dofs(seat_facets(msk, g, h, j, zs)).all()
            if len(d) < 9:
                raise MeshError(f"crank {j + 1} {s} seat caught {len(d)} DOFs: refine the carrier mesh")
            rings.append((d, np.array([*g.crank_xy_mm(j), zs]) * 1e-3))
            labels += [f"crank{j + 1}_{s}_{ax}" for ax in "xy"]
    # rigid-body check, unclamped: T reproduces the six rigid motions exactly and K annihilates them
    rb = _rigid_modes(basis.doflocs, comp)
    T_free, keep_free = _ring_transform(basis, comp, rings, np.array([], int))
    q_rb = np.vstack([rb[keep_free]] + [_ring_rigid(c) for _, c in rings])
    if np.max(np.abs(T_free @ q_rb - rb)) > 1e-9 * np.max(np.abs(rb)):
        raise RuntimeError("the rigid-ring map does not reproduce rigid motions")
    rb_res = float(np.max(np.abs(T_free.T @ (K @ rb))) / (abs(K).max() * np.max(np.abs(rb))))
    T, keep = _ring_transform(basis, comp, rings, fixed)
    Kq = (T.T @ K @ T).tocsr()
    nr = len(rings)
    load = len(keep) + (np.arange(6 * nr) if every_ring_dof else 6 * np.repeat(np.arange(nr), 2) + np.tile([0, 1], nr))
    F = np.zeros((Kq.shape[0], len(load)))
    F[load, np.arange(len(load))] = 1.0
    if solver == "superlu":
        node = np.concatenate([keep // 3, basis.N // 3 + np.repeat(np.arange(nr), 6)])   # skfem interleaves xyz
        U = node_ordered_lu_solve(Kq, node, F)
    else:
        U = spd_solve(Kq, F)
    if every_ring_dof:
        return 0.5 * (U[load] + U[load].T)
    C_raw = U[load]
    u = T @ U                                           # (N, 4nc) displacement fields
    # equilibrium: the clamp reactions balance each unit seat force and its moment about the axis
    R, x, cf = (K @ u)[fixed], basis.doflocs[:, fixed], comp[fixed]
    eq = 0.0
    for i in range(2 * nr):
        c, ax = rings[i // 2][1], i % 2
        fx, fy = R[cf == 0, i].sum() + (ax == 0), R[cf == 1, i].sum() + (ax == 1)
        mz = (x[0, cf == 1] * R[cf == 1, i]).sum() - (x[1, cf == 0] * R[cf == 0, i]).sum() + (c[0] if ax else -c[1])
        eq = max(eq, abs(fx), abs(fy), abs(mz) / (g.outer_radius_mm * 1e-3))
    nd, z = basis.nodal_dofs, m3.points[:, 2]
    rot = []
    for z0 in (g.gap_mm * 1e-3, 0.0):                   # flange inner face, end-plate inner face
        v = np.flatnonzero(np.abs(z - z0) < 0.25 * h)
        xy, uxy = m3.points[v, :2].T, (u[nd[0, v]], u[nd[1, v]])
        rot.append((xy[0][:, None] * uxy[1] - xy[1][:, None] * uxy[0]).sum(0) / (xy ** 2).sum())
    return CarrierFE(0.5 * (C_raw + C_raw.T), np.array(rot), np.array(g.crank_angles_rad()),
                     g.crank_circle_radius_mm * 1e-3, float(np.linalg.norm(C_raw - C_raw.T) / np.linalg.norm(C_raw)),
                     rb_res, float(eq), order, h, len(m3.points), len(m3.tetrahedra), int(Kq.shape[0]), t_mesh,
                     time.perf_counter() - t0, plate_modulus_factor, tuple(labels))


def carrier_fe(g: CarrierGeometry, E_Pa: float, nu: float, *, levels=DEFAULT_LEVELS, p: float = RICHARDSON_ORDER,
               **kw) -> CarrierFE:
    """The default estimate: the carrier on two meshes (h = levels x pillar radius), C and the
    plate rotations Richardson-extrapolated, X = X_f + (X_f - X_c) h_f^p / (h_c^p - h_f^p), p = 1
    (the singular edges' rate, module docstring). Measured, output stiffness at equal split:
    RV-40E, h = 1.6, 1.33, 1.2, 1.0, 0.8, 0.67, 0.5 pillar radii (39k..600k DOFs): 542, 526, 522,
    510, 497, 491, 481 N m/arcmin; the compliance is a straight line in h (residuals < 0.5 %) to
    459; this pair gives 465 (+1.3 %), other pairs 450..486. RV-160N, h = 1.6, 1.33, 1.0, 0.8:
    2620, 2546, 2444, 2402, line to 2210; this pair gives 2197 (-0.6 %)."""
    hc, hf = level_sizes_m(g, levels)
    coarse, fine = (carrier_compliance(g, E_Pa, nu, edge_length_m=h, **kw) for h in (hc, hf))
    return richardson(coarse, fine, p)


def level_sizes_m(g: CarrierGeometry, levels=DEFAULT_LEVELS) -> tuple[float, float]:
    """(h_coarse, h_fine) [m] of the default estimate's two meshes (levels in pillar radii)."""
    hc, hf = (q * g.pillar_radius_mm * 1e-3 for q in levels)
    if not hc > hf:
        raise ValueError(f"carrier levels = {levels!r}: give a coarse then a finer size")
    return hc, hf


def richardson(coarse: CarrierFE, fine: CarrierFE, p: float = RICHARDSON_ORDER) -> CarrierFE:
    """carrier_fe's extrapolation of two levels solved apart (the FE stage runs each level as its
    own task, fem.components.carrier)."""
    hc, hf = coarse.edge_length_m, fine.edge_length_m
    a = hf ** p / (hc ** p - hf ** p)
    C = fine.compliance_m_per_N + a * (fine.compliance_m_per_N - coarse.compliance_m_per_N)
    rot = fine.plate_rotation_rad_per_N + a * (fine.plate_rotation_rad_per_N - coarse.plate_rotation_rad_per_N)
    info = {"edge_length_m": (hc, hf), "order": p, "dofs": (coarse.dofs, fine.dofs),
            "torsional_compliance_rad_per_Nm": (coarse.torsional_compliance_rad_per_Nm(),
                                                fine.torsional_compliance_rad_per_Nm())}
    return replace(fine, compliance_m_per_N=0.5 * (C + C.T), plate_rotation_rad_per_N=rot, extrapolation=info,
                   mesh_seconds=coarse.mesh_seconds + fine.mesh_seconds,
                   solve_seconds=coarse.solve_seconds + fine.solve_seconds)


def case_geometry(case) -> CarrierGeometry:
    """CarrierGeometry.from_case with the seats sized to the support bearing the FE stage selects
    (fem.tapered_roller.case_support_setup): bore = cup outer radius D / 2, seat band = width T."""
    from fem.tapered_roller import case_support_setup
    b = case_support_setup(case).bearing
    return CarrierGeometry.from_case(case).with_(seat_bore_radius_mm=b.D_mm / 2, bearing_width_mm=b.T_mm)


def carrier_for_case(case, **kw) -> tuple[CarrierGeometry, CarrierFE]:
    """The case's carrier (case_geometry) and its default estimate (carrier_fe)."""
    g = case_geometry(case)
    return g, carrier_fe(g, case.material.youngs_modulus_GPa * 1e9, case.material.poisson_ratio, **kw)


# ----------------------------------------------------------------------------- verification
def portal_frame_reference(g: CarrierGeometry, E_Pa: float, nu: float) -> dict:
    """Closed form with RIGID plates, flange held: the end plate turns by theta under a torque on
    it; each pillar (length L = g, radius r, at radius r_p) is a fixed-guided Timoshenko beam
    sheared sideways by r_p theta and twisted by theta (Saint-Venant):
        K = n_p (k_lat r_p^2 + G J / L),  k_lat = 12 E I / L^3 / (1 + Phi),
        Phi = 12 E I / (kappa G A L^2),   kappa = 6 (1 + nu) / (7 + 6 nu) (Cowper).
    With a share s of the crank load at the (held) flange seats: output compliance (1 - s)^2 / K,
    racking (1 - s) / K per N m. Limits: plane sections (a stubby pillar, L / r ~ 3, is stiffer)."""
    r, L, rp = g.pillar_radius_mm * 1e-3, g.gap_mm * 1e-3, g.pillar_circle_radius_mm * 1e-3
    G = E_Pa / (2 * (1 + nu))
    I, J = hertz.circle_inertia(r)
    phi = 12 * E_Pa * I / (hertz.timoshenko_shear_coefficient(nu) * G * math.pi * r * r * L * L)
    k_lat = 12 * E_Pa * I / L ** 3 / (1 + phi)
    bend, twist = g.pillar_count * k_lat * rp * rp, g.pillar_count * G * J / L
    return {"end_plate_stiffness_Nm_per_rad": bend + twist, "bending_shear_Nm_per_rad": bend,
            "pillar_torsion_Nm_per_rad": twist, "shear_parameter_phi": phi, "pillar_lateral_stiffness_N_per_m": k_lat}


def convergence_study(g: CarrierGeometry, E_Pa: float, nu: float, *, sizes_per_pillar_radius=(1.6, 1.33, 1.0),
                      flange_share: float = 0.5, p_assumed: float | None = RICHARDSON_ORDER, known=(), **kw) -> dict:
    """The output torsional compliance c on three meshes (h = size x pillar radius), the observed
    order (from the three levels; nan outside (0.2, 6) or if not monotone), the Richardson limit
    c_inf = c_3 + (c_3 - c_2) h_3^p / (h_2^p - h_3^p) with p = p_assumed (None: the observed order),
    each level's relative error and np.polyfit's slope of log error against log h. known: CarrierFE
    solved beforehand with the same g, E, nu and options (one taken for each level whose h it has)."""
    from scipy.optimize import brentq
    h = np.asarray(sizes_per_pillar_radius, float) * g.pillar_radius_mm * 1e-3
    runs = [next((r for r in known if math.isclose(r.edge_length_m, x, rel_tol=1e-12)), None)
            or carrier_compliance(g, E_Pa, nu, edge_length_m=float(x), **kw) for x in h]
    c = np.array([r.torsional_compliance_rad_per_Nm(flange_share) for r in runs])
    d1, d2 = c[0] - c[1], c[1] - c[2]
    f = lambda q: (h[0] ** q - h[1] ** q) / (h[1] ** q - h[2] ** q) - d1 / d2  # noqa: E731
    p_obs = float(brentq(f, 0.2, 6.0)) if d1 * d2 > 0 and f(0.2) * f(6.0) < 0 else float("nan")
    p = p_obs if p_assumed is None else p_assumed
    c_inf = c[2] - d2 * h[2] ** p / (h[1] ** p - h[2] ** p)
    err = np.abs(c - c_inf) / c_inf
    return {"edge_length_m": h, "dofs": np.array([r.dofs for r in runs]), "compliance_rad_per_Nm": c,
            "stiffness_Nm_per_arcmin": 1 / (c * ARCMIN_PER_RAD), "observed_order": p_obs, "order_used": p,
            "extrapolated_compliance_rad_per_Nm": c_inf, "relative_error": err,
            "polyfit_slope": float(np.polyfit(np.log(h), np.log(err), 1)[0]),
            "seconds": np.array([r.mesh_seconds + r.solve_seconds for r in runs])}
