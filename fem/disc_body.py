"""Cycloid disc body between the pin contacts and the crank holes: 2D plane-stress FE compliance.

Model: one disc (real modified profile, geometry.profile; centre, crank and pillar holes,
geometry.solids.disc_holes), P2 triangles (P1 locks in the ligament's bending), plane stress times
the face width (the disc is thin against its diameter). Loads at one crank angle psi_c
(`load_pattern`):
  pins   classical load sharing over the loaded half (moment arm l_i > 0 from
         geometry.clearance.pin_contacts on the modified profile): F_i = T_d l_i / sum l_j^2, so
         sum F_i l_i = T_d; each a point force -F_i n_i at its foot point (n the outward normal);
  crank holes  the reaction, by static equilibrium, shared by the n holes as the least-norm
         solution of the three equilibrium equations: h_j = -R / n + T_d / (n a) t_j (R the pins'
         resultant, a the crank circle, t_j the tangent at hole j: the discs' tangential force
         shared equally), each a half-cosine radial pressure p0 cos(theta - theta_j) over the loaded
         half of the bore (the standard bearing-load model), p0 = 2 |h_j| / (pi r w).
The load set is self-equilibrated up to the bore quadrature (residual reported as `imbalance`,
then projected out), so three DOFs hold the rigid modes and their reactions are checked to be zero.

Output (`DiscBodyModel.solve`): the normal approach delta_i of each loaded pin's contact point
relative to the crank holes, with what the neighbouring models already contain taken out, so that
it adds in series without double counting:
  - crank-hole datum: the rigid motion (least squares) of the holes' translations (mean bore
    displacement) less the bore ring a..b that fem.bearing's needle model carries (the same ring,
    b = fem.bearing.bore_clamp_radius_m the bore plus the thinnest ligament to a free edge, clamped
    at b under the same half-cosine load: `bore_ring_compliance`, within 0.15 % of the exact ring
    solution fem.bearing.clamped_ring_bore_compliance; the ring is counted once, in fem.bearing's
    plane-strain section). With the least-norm sharing the loads lie in the range of the fit, so
    the fit residual (holes moving apart) does no work: the result is also the Castigliano
    compliance of the stated load set;
  - the tooth's own deformation down to the clamp radius of fem.pin_contact's tooth-pair model
    (r_c = root - 2E - pin pitch, an internal line of the mesh) is subtracted: the same mesh,
    pins only, clamped inside r_c and on the bores (a crank hole reaching above r_c would leave a
    free ligament that the tooth-pair model does not have). Being the same mesh, the point-load
    singularity cancels exactly (measured on the RV-40E: the subtracted part grows by ~10 % per mesh
    halving, the log singularity; the difference converges at rate 1.9).
The tooth-ring rotation per unit torque is the work-conjugate average theta / T_d =
sum F_i delta_i / T_d^2 [rad/(N m)]; it maps 1:1 to the output (the carrier holds the crank holes).
Verification: `lame_ring_check` (thick annulus under internal pressure, Lame plane stress) with the
same mesher, loads and solver; `convergence` over three mesh levels.
Limits: linear, plane stress, frictionless point loads, equal crank sharing (no redistribution by
crank or bearing compliance), the classical all-pins-of-the-loaded-half sharing (not the
clearance-dependent contact set of the dynamics stage).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from fem import elastic, hertz
from fem.bearing import bore_clamp_radius_m
from fem.mesh import Mesh2D, graded_parameters, triangulate
from geometry.artifacts import InputError
from geometry.clearance import pin_contacts
from geometry.profile import cycloid_xy, profile_args

ARCMIN_PER_RAD = 180.0 * 60.0 / math.pi
GRADING_PIN_RADII = 1.0   # interior element size doubles one pin radius away from the profile/holes


# ----------------------------------------------------------------------------- loads
@dataclass(frozen=True)
class LoadPattern:
    """Loads on one disc in its body frame (holes at 2 pi j / n), metres and newtons."""
    pin_index: np.ndarray        # (m,) loaded pins (0-based)
    point_m: np.ndarray          # (m, 2) foot points
    normal: np.ndarray           # (m, 2) outward profile normals
    arm_m: np.ndarray            # (m,) moment arms about the disc centre
    force_N: np.ndarray          # (m,) pin force magnitudes (on the disc: -F n)
    hole_centre_m: np.ndarray    # (n, 2) crank-hole centres
    hole_force_N: np.ndarray     # (n, 2) force of each crank (through its needles) on the disc
    torque_Nm: float             # disc torque T_d = sum F_i l_i


def _rot(a: float) -> np.ndarray:
    return np.array([[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]])


def load_pattern(case, torque_disc_Nm: float, crank_angle_rad: float = 0.0, *, index: int = 0) -> LoadPattern:
    """Pin forces (F_i proportional to the arm, loaded half) and crank-hole reactions of disc `index`
    at crank angle psi_c (disc 2 rides at psi_c + pi, its profile clocked by pi / zc)."""
    from geometry.solids import disc_holes
    c, nc = case.cycloid, case.carrier.crank_count
    if nc < 2:
        raise InputError(f"[carrier] crank_count = {nc}: the disc-body model needs >= 2 cranks "
                         f"(one crank cannot balance the pin moment)")
    pc = pin_contacts(case, crank_angle_rad + index * math.pi)
    # pin_contacts' frame has the unclocked profile turned by -(psi + k pi)/zc: body frame = R(-k pi/zc)
    R = _rot(-index * math.pi / c.zc)
    loaded = np.flatnonzero(pc.arm_mm > 1e-3 * pc.arm_mm.max())   # the loaded half (a root pin: arm 0)
    pts, nrm, arm = pc.point_mm[loaded] @ R.T * 1e-3, pc.normal[loaded] @ R.T, pc.arm_mm[loaded] * 1e-3
    F = torque_disc_Nm * arm / np.sum(arm ** 2)
    holes = np.array([[h.x_mm, h.y_mm] for h in disc_holes(case) if h.name.startswith("crank")]) * 1e-3
    resultant = -(F[:, None] * nrm).sum(axis=0)
    moment = -float(np.sum(F * arm))                       # pins on the disc: -T_d
    # equilibrium rows: sum hx, sum hy, sum (x hy - y hx) = (-R, -M); least-norm sharing
    A = np.zeros((3, 2 * nc))
    A[0, 0::2], A[1, 1::2] = 1.0, 1.0
    A[2, 0::2], A[2, 1::2] = -holes[:, 1], holes[:, 0]
    h = A.T @ np.linalg.solve(A @ A.T, np.array([-resultant[0], -resultant[1], -moment]))
    return LoadPattern(loaded, pts, nrm, arm, F, holes, h.reshape(nc, 2),
                       float(np.sum(F * arm)))


# ----------------------------------------------------------------------------- mesh
@dataclass(frozen=True)
class DiscMesh:
    mesh: Mesh2D
    loops: dict                  # name -> ordered node indices of each closed boundary loop
    circles: dict                # hole name -> (centre (2,), radius) [m]
    h_profile_m: float


def _circle_loop(cx, cy, r, h):
    n = max(16, int(math.ceil(2 * math.pi * r / h)))
    a = 2 * math.pi * np.arange(n) / n
    return np.column_stack([cx + r * np.cos(a), cy + r * np.sin(a)])


def _pslg_triangulate(closed: list[np.ndarray], open_runs: list[np.ndarray], hole_marks, h_max: float,
                      size) -> tuple[np.ndarray, np.ndarray]:
    """Triangle quality mesh of closed loops plus open polylines (internal lines kept as edges),
    graded by size(xy) -> h; input vertices come first, in order (fem.mesh.triangulate)."""
    return triangulate(closed[0], h_max, holes=np.asarray(hole_marks, float), extra_loops=closed[1:],
                       size=size, open_runs=open_runs)


def _arc_runs(radius: float, h: float, circles) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """The circle `radius` about the origin where it lies in the material (h/2 clear of every hole):
    ([closed loop], []) when nothing cuts it, else ([], runs of consecutive points)."""
    n = max(24, int(math.ceil(2 * math.pi * radius / h)))
    a = 2 * math.pi * np.arange(n) / n
    xy = radius * np.column_stack([np.cos(a), np.sin(a)])
    keep = np.ones(n, bool)
    for c, r in circles:
        keep &= np.hypot(*(xy - c).T) > r + 0.5 * h
    if keep.all():
        return [xy], []
    order = np.roll(np.arange(n), -int(np.argmin(keep)))    # start the scan at a dropped point
    runs, cur = [], []
    for i in order:
        if keep[i]:
            cur.append(i)
        elif cur:
            runs.append(cur)
            cur = []
    if cur:
        runs.append(cur)
    return [], [xy[r] for r in runs if len(r) >= 2]


def disc_mesh(case, h_profile_m: float, *, h_hole_m: float | None = None, h_max_m: float | None = None,
              index: int = 0, filled: tuple[str, ...] = ()) -> DiscMesh:
    """Triangulation of disc `index` (body frame, metres): the modified profile sampled at uniform
    arc length h_profile, hole circles at h_hole, and the circle r_c of the tooth-pair model's clamp
    as an internal line (so that clamping 'r <= r_c' is exact, not a staircase of nodes: measured,
    a staircase clamp moves the subtracted tooth compliance by +-5 % from mesh to mesh); holes
    whose kind is in `filled` ('centre', 'crank', 'pillar') stay solid (their circle an internal
    line), for the no-hole comparison."""
    from geometry.solids import disc_holes
    if not (h_profile_m > 0):
        raise InputError(f"disc mesh size h_profile_m = {h_profile_m!r}: must be positive")
    h_hole = h_hole_m or h_profile_m
    h_max = h_max_m or 6 * h_profile_m
    args = profile_args(case)
    args["rotation_rad"] += index * math.pi / case.cycloid.zc
    curve = lambda t: np.column_stack(cycloid_xy(t, **args)) * 1e-3  # noqa: E731
    t = graded_parameters(curve, 0.0, 2 * math.pi, [], h_profile_m, h_profile_m, 0.5, n_dense=200001)[:-1]
    prof = curve(t)
    loops, circles, marks = {"profile": prof}, {}, []
    for hole in disc_holes(case):
        cxy = np.array([hole.x_mm, hole.y_mm]) * 1e-3
        circles[hole.name] = (cxy, hole.radius_mm * 1e-3)
        loops[hole.name] = _circle_loop(*cxy, hole.radius_mm * 1e-3, h_hole)
        if not any(hole.name.startswith(k) for k in filled):
            marks.append(cxy)
    r_root = (args["R"] - case.cycloid.eccentricity_mm - args["Rr"]) * 1e-3
    cen = np.array([c for c, _ in circles.values()])
    rad = np.array([r for _, r in circles.values()])
    grade = GRADING_PIN_RADII * case.cycloid.pin_radius_mm * 1e-3

    def size(xy):
        # h grows with the distance d to the nearest boundary as h (1 + d / grade): the whole mesh
        # scales with h_profile, so a halved h_profile is a refinement everywhere
        d_prof = np.maximum(r_root - np.hypot(xy[:, 0], xy[:, 1]), 0.0)
        d_hole = np.min(np.abs(np.hypot(xy[:, None, 0] - cen[None, :, 0], xy[:, None, 1] - cen[None, :, 1])
                               - rad[None, :]), axis=1)
        return np.minimum(np.minimum(h_profile_m * (1 + d_prof / grade), h_hole * (1 + d_hole / grade)), h_max)

    r_c = tooth_model_clamp_radius_m(case)
    arc_loops, arc_runs = _arc_runs(r_c, float(size(np.array([[r_c, 0.0]]))[0]), list(circles.values()))
    p, tri = _pslg_triangulate(list(loops.values()) + arc_loops, arc_runs, marks, h_max, size)
    start, idx = 0, {}
    for name, loop in loops.items():
        idx[name] = np.arange(start, start + len(loop))
        start += len(loop)
    return DiscMesh(Mesh2D(p, tri, dict(idx)), idx, circles, h_profile_m)


# ----------------------------------------------------------------------------- FE pieces
def vector_basis(mesh: Mesh2D, order: int = 2):
    """Vector P2 (default) or P1 triangles on a Mesh2D (the ligaments between holes and teeth bend,
    and P1 triangles are too stiff in bending at a few elements across)."""
    from skfem import Basis, ElementTriP1, ElementTriP2, ElementVector, MeshTri
    m = MeshTri(np.ascontiguousarray(mesh.points.T), np.ascontiguousarray(mesh.triangles.T))
    return Basis(m, ElementVector({1: ElementTriP1, 2: ElementTriP2}[order]()))


def plane_stress_stiffness(basis, E_Pa: float, nu: float, thickness_m: float) -> sp.csr_matrix:
    """Plane-stress stiffness times the thickness: lambda* = 2 lambda mu / (lambda + 2 mu)."""
    from skfem import asm
    from skfem.models.elasticity import linear_elasticity
    lam, mu = elastic.lame(E_Pa, nu)
    return (thickness_m * asm(linear_elasticity(2 * lam * mu / (lam + 2 * mu), mu), basis)).tocsr()


def loop_facets(basis, loop: np.ndarray) -> np.ndarray:
    """Mesh facets joining consecutive nodes of a closed loop (boundary or internal line)."""
    f = basis.mesh.facets
    nv = basis.mesh.p.shape[1]
    key = {int(k): i for i, k in enumerate(np.minimum(f[0], f[1]) * nv + np.maximum(f[0], f[1]))}
    a, b = loop, np.roll(loop, -1)
    want = np.minimum(a, b) * nv + np.maximum(a, b)
    missing = [k for k in want if int(k) not in key]
    if missing:
        raise RuntimeError("a boundary loop is not made of mesh edges (Steiner points on a segment?)")
    return np.array([key[int(k)] for k in want])


def _facet_vector(basis, facets, traction) -> np.ndarray:
    """Load vector of a traction(x) -> (2, ...) [N/m^2 times thickness] on the facets."""
    from skfem import FacetBasis, LinearForm, asm
    fb = FacetBasis(basis.mesh, basis.elem, facets=facets)

    @LinearForm
    def form(v, w):
        t = traction(w.x)
        return t[0] * v[0] + t[1] * v[1]
    return asm(form, fb)


def bore_load(basis, facets, centre, radius: float, force_N, thickness_m: float, *,
              pressure_Pa: float | None = None) -> np.ndarray:
    """Radial pressure on a circular bore pushing the material away from the centre: half-cosine
    p0 cos(theta - theta_F) over the loaded half with resultant force_N (2,), or uniform pressure_Pa."""
    F = np.zeros(2) if force_N is None else np.asarray(force_N, float)
    th_F, p0 = math.atan2(F[1], F[0]), 2 * float(np.hypot(*F)) / (math.pi * radius * thickness_m)
    cx, cy = centre

    def traction(x):
        dx, dy = x[0] - cx, x[1] - cy
        r = np.sqrt(dx * dx + dy * dy)
        p = np.full(dx.shape, pressure_Pa) if pressure_Pa is not None else \
            p0 * np.maximum(np.cos(np.arctan2(dy, dx) - th_F), 0.0)
        return thickness_m * p * dx / r, thickness_m * p * dy / r
    return _facet_vector(basis, facets, traction)


def mean_operator(basis, facets) -> np.ndarray:
    """(2, N) mean displacement (x, y) over facets: a hole's translation."""
    from skfem import FacetBasis, Functional, asm
    fb = FacetBasis(basis.mesh, basis.elem, facets=facets)
    length = float(asm(Functional(lambda w: 1.0 + 0 * w.x[0]), fb))
    return np.vstack([_facet_vector(basis, facets, lambda x, c=c: ((c == 0) + 0 * x[0], (c == 1) + 0 * x[0]))
                      for c in (0, 1)]) / length


def point_operator(basis, points: np.ndarray, loop: np.ndarray, targets: np.ndarray) -> sp.csr_matrix:
    """(2k, N) displacement at k points of a boundary loop, rows x0, y0, x1, ...: each target is
    moved onto the nearest loop segment (the mesh boundary) and a hair inside; its transpose
    spreads point forces."""
    a, b = points[loop], points[np.roll(loop, -1)]
    ab = b - a
    q = []
    for t in np.atleast_2d(targets):
        s = np.clip(np.einsum("ij,ij->i", t - a, ab) / np.einsum("ij,ij->i", ab, ab), 0.0, 1.0)
        k = int(np.argmin(np.hypot(*(a + s[:, None] * ab - t).T)))
        foot = a[k] + s[k] * ab[k]
        inward = np.array([ab[k, 1], -ab[k, 0]])        # the profile runs clockwise: right = inside
        q.append(foot + 1e-9 * inward / np.hypot(*inward) * np.hypot(*ab[k]))
    P = sp.csr_matrix(basis.probes(np.array(q).T))
    k = len(q)
    order = np.column_stack([np.arange(k), np.arange(k, 2 * k)]).ravel()
    return P[order]


def rigid_modes(basis) -> np.ndarray:
    """(N, 3) translations x, y and rotation about the origin at every DOF."""
    x = basis.doflocs
    comp = np.zeros(basis.N, int)
    comp[basis.nodal_dofs[1]] = 1
    if basis.facet_dofs.size:
        comp[basis.facet_dofs[1]] = 1
    R = np.zeros((basis.N, 3))
    R[comp == 0, 0], R[comp == 1, 1] = 1.0, 1.0
    R[comp == 0, 2], R[comp == 1, 2] = -x[1, comp == 0], x[0, comp == 1]
    return R


def equilibrate(f: np.ndarray, basis) -> tuple[np.ndarray, float]:
    """Project the rigid modes out of a load (orthogonal projection); returns it and the removed
    part relative to the largest nodal force (the quadrature imbalance of the load set)."""
    R = rigid_modes(basis)
    fix = R @ np.linalg.solve(R.T @ R, R.T @ f)
    return f - fix, float(np.abs(fix).max() / max(np.abs(f).max(), 1e-300))


def solve_free(K: sp.csr_matrix, f: np.ndarray, basis) -> tuple[np.ndarray, float]:
    """Displacements of a free body under a self-equilibrated load, three DOFs held (both at the
    vertex of least x, y at the vertex of largest x), and the largest reaction there relative to
    the largest load (zero when the load is in equilibrium)."""
    p = basis.mesh.p
    a, b = int(np.argmin(p[0])), int(np.argmax(p[0]))
    nd = basis.nodal_dofs
    fixed = np.array([nd[0, a], nd[1, a], nd[1, b]])
    u = elastic.Factorized.of(K, fixed).solve(f)
    return u, float(np.abs((K @ u - f)[fixed]).max() / np.abs(f).max())


# ----------------------------------------------------------------------------- reference models
def tooth_model_clamp_radius_m(case) -> float:
    """Clamp radius of fem.pin_contact's tooth-pair model: root - 2E - pin pitch (nominal sizes)."""
    c = case.cycloid
    root = c.pin_circle_radius_mm - c.eccentricity_mm - c.pin_radius_mm
    return (root - 2 * c.eccentricity_mm - 2 * math.pi * c.pin_circle_radius_mm / c.zp) * 1e-3


def _annulus(r_in, r_out, h):
    """Ring mesh (P2 basis) and the facets of its outer and inner circles."""
    loops = [_circle_loop(0, 0, r_out, h), _circle_loop(0, 0, r_in, h)]
    p, t = _pslg_triangulate(loops, [], np.zeros((1, 2)), 2 * h, lambda xy: np.full(len(xy), 2 * h))
    n0 = len(loops[0])
    basis = vector_basis(Mesh2D(p, t))
    outer, inner = np.arange(n0), np.arange(n0, n0 + len(loops[1]))
    return basis, outer, inner, loop_facets(basis, outer), loop_facets(basis, inner)


def bore_ring_compliance(radius_m: float, outer_radius_m: float, E_Pa: float, nu: float, thickness_m: float,
                         h_m: float) -> float:
    """Mean bore translation per N of a half-cosine bore load on a ring radius..outer_radius
    clamped outside: the disc part of fem.bearing's needle model (its bore ring, clamped at
    fem.bearing.bore_clamp_radius_m), plane stress [m/N]."""
    basis, _, _, f_out, f_in = _annulus(radius_m, outer_radius_m, h_m)
    K = plane_stress_stiffness(basis, E_Pa, nu, thickness_m)
    f = bore_load(basis, f_in, (0.0, 0.0), radius_m, (1.0, 0.0), thickness_m)
    u = elastic.Factorized.of(K, basis.get_dofs(f_out).all()).solve(f)
    return float((mean_operator(basis, f_in) @ u)[0])


def lame_ring_check(h_m: float, inner_radius_m: float = 15e-3, outer_radius_m: float = 45e-3,
                    pressure_Pa: float = 100e6, E_Pa: float = 206e9, nu: float = 0.3,
                    thickness_m: float = 10e-3) -> dict:
    """Free annulus under internal pressure, solved exactly as the disc (plane stress, bore_load,
    equilibrate, three DOFs held): radial displacement (mean over each circle) against Lame."""
    basis, _, _, f_out, f_in = _annulus(inner_radius_m, outer_radius_m, h_m)
    K = plane_stress_stiffness(basis, E_Pa, nu, thickness_m)
    f, imbalance = equilibrate(bore_load(basis, f_in, (0.0, 0.0), inner_radius_m, None, thickness_m,
                                         pressure_Pa=pressure_Pa), basis)
    u, reaction = solve_free(K, f, basis)
    out = {"h_m": h_m, "imbalance": imbalance, "reaction": reaction, "dofs": int(basis.N)}
    for name, facets, r in (("inner", f_in, inner_radius_m), ("outer", f_out, outer_radius_m)):
        # mean radial displacement: the conjugate of a unit uniform pressure over the circle
        g = bore_load(basis, facets, (0.0, 0.0), r, None, 1.0, pressure_Pa=1.0 / (2 * math.pi * r))
        ref = float(hertz.lame_radial_displacement(r, inner_radius_m, outer_radius_m, pressure_Pa, 0.0,
                                                   E_Pa, nu, plane_strain=False))
        out[f"{name}_m"], out[f"{name}_closed_form_m"] = float(g @ u), ref
        out[f"{name}_error"] = float(g @ u / ref - 1)
    return out


# ----------------------------------------------------------------------------- the disc body
@dataclass(frozen=True)
class DiscBodyResult:
    crank_angle_rad: float
    index: int
    pattern: LoadPattern = field(repr=False)
    approach_m: np.ndarray            # (m,) delta_i: contact-point approach relative to the crank holes
    approach_per_force_m_per_N: np.ndarray   # (m,) delta_i / F_i for this pattern (< 0: the point recedes)
    rotation_per_torque_rad_per_Nm: float    # theta / T_d = sum F_i delta_i / T_d^2 (crank holes as a rigid frame)
    tooth_local_per_torque_rad_per_Nm: float   # taken out: the tooth-pair model's region (fem.pin_contact)
    bore_ring_per_torque_rad_per_Nm: float     # taken out: the needle model's bore ring (fem.bearing)
    frame_residual_m: float           # rms misfit of the rigid crank-hole frame
    imbalance: float                  # quadrature imbalance of the loads (relative)
    reaction: float                   # reaction at the three held DOFs (relative)
    h_profile_m: float
    dofs: int
    mesh: Mesh2D = field(repr=False)
    displacement_m: np.ndarray = field(repr=False)

    @property
    def approach_per_torque_m_per_Nm(self) -> np.ndarray:
        """delta_i per N m of disc torque: the pattern scales linearly with the torque."""
        return self.approach_m / self.pattern.torque_Nm

    @property
    def stiffness_one_disc_Nm_per_arcmin(self) -> float:
        """Output stiffness of this disc body carrying the whole output torque (rigid hole frame)."""
        return 1.0 / (self.rotation_per_torque_rad_per_Nm * ARCMIN_PER_RAD)


@dataclass(frozen=True)
class DiscBodyModel:
    """One disc's mesh and factorizations (free body; tooth-pair region clamped), built once and
    solved for any crank angle (only the loads move with psi_c)."""
    case: object = field(repr=False)
    index: int
    dmesh: DiscMesh = field(repr=False)
    basis: object = field(repr=False)
    K: sp.csr_matrix = field(repr=False)
    free: elastic.Factorized = field(repr=False)
    free_held: np.ndarray = field(repr=False)
    local: elastic.Factorized = field(repr=False)
    facets: dict = field(repr=False)
    bore_ring_m_per_N: float

    @classmethod
    def build(cls, case, h_profile_m: float | None = None, *, index: int = 0,
              filled: tuple[str, ...] = ()) -> "DiscBodyModel":
        c = case.cycloid
        E, nu, w = case.material.youngs_modulus_GPa * 1e9, case.material.poisson_ratio, c.width_mm * 1e-3
        h = h_profile_m or default_h_profile_m(case)
        dm = disc_mesh(case, h, index=index, filled=filled)
        basis = vector_basis(dm.mesh)
        K = plane_stress_stiffness(basis, E, nu, w)
        p, nd = basis.mesh.p, basis.nodal_dofs
        a, b = int(np.argmin(p[0])), int(np.argmax(p[0]))
        held = np.array([nd[0, a], nd[1, a], nd[1, b]])      # the three rigid modes only
        facets = {k: loop_facets(basis, dm.loops[k]) for k in dm.circles}
        # tooth-pair region: clamped at r_c (an internal line of the mesh) and on every bore (a bore
        # reaching above r_c would leave a free ligament that the tooth-pair model does not have)
        clamp = [np.flatnonzero(np.hypot(*basis.doflocs) < tooth_model_clamp_radius_m(case) + 1e-9)]
        clamp += [basis.get_dofs(facets[k]).all() for k in dm.circles if not any(k.startswith(f) for f in filled)]
        r_hole = case.disc.crank_hole_radius_mm * 1e-3
        return cls(case, index, dm, basis, K, elastic.Factorized.of(K, held), held,
                   elastic.Factorized.of(K, np.unique(np.concatenate(clamp))), facets,
                   bore_ring_compliance(r_hole, bore_clamp_radius_m(case), E, nu, w, min(2 * h, r_hole / 8)))

    def solve(self, crank_angle_rad: float = 0.0, torque_disc_Nm: float | None = None) -> DiscBodyResult:
        """torque_disc_Nm: default half the rated torque (linear: it only scales approach_m)."""
        case, basis, dm = self.case, self.basis, self.dmesh
        w = case.cycloid.width_mm * 1e-3
        T = torque_disc_Nm if torque_disc_Nm is not None else 0.5 * case.rated_torque_Nm
        pat = load_pattern(case, T, crank_angle_rad, index=self.index)
        B = point_operator(basis, dm.mesh.points, dm.loops["profile"], pat.point_m)
        f_pin = B.T @ (-(pat.force_N[:, None] * pat.normal)).ravel()
        cranks = sorted(k for k in dm.circles if k.startswith("crank"))
        f = f_pin.copy()
        for j, name in enumerate(cranks):
            f += bore_load(basis, self.facets[name], dm.circles[name][0], dm.circles[name][1],
                           pat.hole_force_N[j], w)
        f, imbalance = equilibrate(f, basis)
        u = self.free.solve(f)
        reaction = float(np.abs((self.K @ u - f)[self.free_held]).max() / np.abs(f).max())
        # crank-hole datum: hole translations less the needle model's bore ring, rigid least squares.
        # With the least-norm crank sharing the loads h lie in the range of A, so the fit residual
        # (the holes moving apart) does no work: theta is also the Castigliano compliance.
        trans = np.array([mean_operator(basis, self.facets[k]) @ u for k in cranks])
        A = np.zeros((2 * len(cranks), 3))
        A[0::2, 0], A[1::2, 1] = 1.0, 1.0
        A[0::2, 2], A[1::2, 2] = -pat.hole_centre_m[:, 1], pat.hole_centre_m[:, 0]
        frames = {}
        for tag, tr in (("full", trans), ("net", trans - self.bore_ring_m_per_N * pat.hole_force_N)):
            sol, *_ = np.linalg.lstsq(A, tr.ravel(), rcond=None)
            frames[tag] = (sol, float(np.sqrt(np.mean((A @ sol - tr.ravel()) ** 2))))
        d_tl = -np.einsum("ij,ij->i", (B @ self.local.solve(f_pin)).reshape(-1, 2), pat.normal)

        def approach(frame):
            t = frame[0]
            rigid = t[:2][None, :] + t[2] * np.column_stack([-pat.point_m[:, 1], pat.point_m[:, 0]])
            return -np.einsum("ij,ij->i", (B @ u).reshape(-1, 2) - rigid, pat.normal) - d_tl

        d_full, d_net = approach(frames["full"]), approach(frames["net"])
        T2 = pat.torque_Nm ** 2
        return DiscBodyResult(
            crank_angle_rad, self.index, pat, d_net, d_net / pat.force_N,
            rotation_per_torque_rad_per_Nm=float(pat.force_N @ d_net) / T2,
            tooth_local_per_torque_rad_per_Nm=float(pat.force_N @ d_tl) / T2,
            bore_ring_per_torque_rad_per_Nm=float(pat.force_N @ (d_full - d_net)) / T2,
            frame_residual_m=frames["net"][1], imbalance=imbalance, reaction=reaction,
            h_profile_m=dm.h_profile_m, dofs=int(basis.N), mesh=dm.mesh, displacement_m=u)


def disc_body(case, *, h_profile_m: float | None = None, crank_angle_rad: float = 0.0, index: int = 0,
              filled: tuple[str, ...] = (), torque_disc_Nm: float | None = None) -> DiscBodyResult:
    """Disc-body compliance of disc `index` at one crank angle (see the module docstring)."""
    return DiscBodyModel.build(case, h_profile_m, index=index, filled=filled).solve(crank_angle_rad, torque_disc_Nm)


def default_h_profile_m(case) -> float:
    """Element size along the profile: pin radius / 4 (P2; measured 0.2 % from the next halving on
    both cases, see `convergence`)."""
    return case.cycloid.pin_radius_mm * 1e-3 / 4


def convergence(case, levels=(1 / 2, 1 / 4, 1 / 8), **kwargs) -> dict:
    """Rotation per torque on three meshes (profile element = level x pin radius) and the observed
    rate p of |theta_k - theta_k+1| ~ h^p (np.polyfit in log-log); Richardson extrapolation."""
    hs = np.array(levels) * case.cycloid.pin_radius_mm * 1e-3
    th = np.array([disc_body(case, h_profile_m=h, **kwargs).rotation_per_torque_rad_per_Nm for h in hs])
    d = np.abs(np.diff(th))
    p = float(np.polyfit(np.log(hs[:-1]), np.log(d), 1)[0]) if np.all(d > 0) else math.inf
    extrap = th[-1] + (th[-1] - th[-2]) / (2 ** p - 1) if math.isfinite(p) and p > 0 else th[-1]
    return {"h_m": hs, "rotation_per_torque_rad_per_Nm": th, "rate": p, "extrapolated": float(extrap),
            "finest_error_estimate": float(abs(extrap - th[-1]) / abs(extrap))}


def crank_angle_sweep(case, n: int = 6, h_profile_m: float | None = None) -> dict:
    """Both discs over one crank spacing of psi_c (the load zone passes one crank hole: the pattern
    repeats every 2 pi / n_crank): each disc's stiffness k_k(psi) [N m/arcmin] for the whole output
    torque, and the pair in parallel (each carrying half): k_pair = k_1 + k_2."""
    psi = 2 * math.pi / case.carrier.crank_count * np.arange(n) / n
    models = [DiscBodyModel.build(case, h_profile_m, index=k) for k in range(case.cycloid.disc_count)]
    res = [[m.solve(p) for p in psi] for m in models]
    k = np.array([[r.stiffness_one_disc_Nm_per_arcmin for r in row] for row in res])
    return {"crank_angle_rad": psi, "disc_Nm_per_arcmin": k, "pair_Nm_per_arcmin": k.sum(axis=0),
            "results": res}
