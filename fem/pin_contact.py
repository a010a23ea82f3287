"""2D contact models built on `fem.contact`: the Hertz benchmark and the cycloid tooth-pin pair.

Circle body (pin, roller, benchmark cylinder): a full disc meshed once in its own frame, graded
toward its contact point, its back half clamped to a rigid seat (the pin housing groove, a
conformal support much stiffer than the concentrated contact). Its compliance on the surface
nodes of the contact window is condensed once and reused for every position: the pin is round,
so only the direction of the contact changes along the path.

Tooth pair: one disc mesh (profile stretch of the loaded tooth flank and its neighbour, down to
an inner arc one tooth height plus one pin pitch below the root, inner arc clamped: the rest of
the disc is far stiffer than a tooth) graded toward the contact point of every position. Pin
phase `position_deg` is the angle at the disc centre between the eccentric direction and the
pin, 0 = pin in the direction of the eccentricity, in the pose convention of geometry.profile.
At each position the pin is placed on its nominal centre, then moved along the contact normal
until it touches the MODIFIED profile (first contact), so the approach counts from first touch:
profile modifications shift where contact starts (the dynamics stage's gap), not the law.
The disc is factorized once with every position's candidates ordered last: their compliance is
the inverse of the trailing Schur block (`_condensed_disc`; issue 11: the map <= 3 factorizations).
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from fem import contact, elastic, hertz
from fem.mesh import Mesh2D, block_mesh, pin_mesh, profile_sector_mesh
from geometry import pin_profile
from geometry.artifacts import InputError
from geometry.profile import cycloid_xy, profile_args

GROWTH = 0.08   # element growth per unit distance from the contact (8 %: smooth grading)


@dataclass(frozen=True)
class CircleBody:
    radius_m: float
    mesh: Mesh2D                  # own frame: centre at origin, contact point at (0, -R)
    factor: elastic.Factorized
    window_nodes: np.ndarray      # surface nodes of the contact window
    window_compliance: np.ndarray # (2w, 2w) condensed compliance of those nodes' DOFs

    @classmethod
    def build(cls, radius_m: float, h_min: float, h_max: float, E_Pa: float, nu: float,
              window_m: float, *, two_sided: bool = False) -> "CircleBody":
        """one-sided (pin): back half clamped to its seat, window about (0, -R).
        two_sided (needle between two races, self-equilibrated loads): windows about (0, -R) and
        (0, R); the node nearest the centre is pinned and one node on the x axis held in y, which
        removes the rigid modes only (zero reactions), so the centre is the needle's datum."""
        mesh = pin_mesh(radius_m, h_min, h_max, GROWTH, opposite=two_sided)
        basis = elastic.basis_2d(mesh)
        K = elastic.stiffness(basis, E_Pa, nu)
        surf = mesh.boundary["surface"]
        ang = np.arctan2(mesh.points[surf, 1], mesh.points[surf, 0]) + np.pi / 2
        arc = np.abs((ang + np.pi) % (2 * np.pi) - np.pi) * radius_m
        if two_sided:
            arc = np.minimum(arc, np.pi * radius_m - arc)
            c0 = int(np.argmin(np.hypot(*mesh.points.T)))
            c1 = int(np.argmin(np.hypot(mesh.points[:, 0] - radius_m / 2, mesh.points[:, 1])))
            fixed = np.array([2 * c0, 2 * c0 + 1, 2 * c1 + 1])
        else:
            back = mesh.boundary["back"]
            fixed = np.concatenate([2 * back, 2 * back + 1])
        win = surf[arc <= min(window_m, 0.45 * np.pi * radius_m)]
        dofs = np.column_stack([2 * win, 2 * win + 1]).ravel()
        factor = elastic.Factorized.of(K, fixed, last=dofs)
        return cls(radius_m, mesh, factor, win, factor.last_compliance)

    def compliance(self, n_global: np.ndarray, rotation_rad: float) -> np.ndarray:
        """Condensed compliance for contact forces +n_i acting at the surface points -R n_i."""
        B = contact.circle_projection_operator(n_global, self.window_nodes,
                                               self.mesh.points[self.window_nodes], np.zeros(2),
                                               2 * len(self.mesh.points), rotation_rad)
        dofs = np.column_stack([2 * self.window_nodes, 2 * self.window_nodes + 1]).ravel()
        Bw = B[:, dofs].toarray()
        return Bw @ self.window_compliance @ Bw.T


def contact_directions(centre_m: np.ndarray, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Unit vectors from counter-body points to the circle's centre, and the distances."""
    d = centre_m - points
    dist = np.hypot(d[..., 0], d[..., 1])
    return d / dist[..., None], dist


def node_frames(n_dofs: int, nodes: np.ndarray, directions: np.ndarray) -> sp.csr_matrix:
    """R with u_global = R u_local: at `nodes` the local DOFs are (along directions[i], normal to it),
    identity elsewhere. With K' = R^T K R a unit load along directions[i] is ONE local DOF, so a
    node whose contact direction is known needs one condensed DOF instead of two (exact)."""
    n = np.asarray(directions, float)
    keep = np.ones(n_dofs, bool)
    keep[2 * nodes] = keep[2 * nodes + 1] = False
    eye = np.flatnonzero(keep)
    x, y = 2 * nodes, 2 * nodes + 1                 # local columns: x <- n, y <- t = (-n_y, n_x)
    rows = np.concatenate([eye, x, x, y, y])
    cols = np.concatenate([eye, x, y, x, y])
    vals = np.concatenate([np.ones(len(eye)), n[:, 0], -n[:, 1], n[:, 1], n[:, 0]])
    return sp.csr_matrix((vals, (rows, cols)), shape=(n_dofs, n_dofs))


def make_setup(body: CircleBody, centre_m: np.ndarray, normal_m: np.ndarray,
               counter_points: np.ndarray, counter_factor: elastic.Factorized,
               candidates: np.ndarray, coord_m: np.ndarray,
               counter_frames: sp.spmatrix | None = None) -> contact.ContactSetup:
    """Condensed contact setup of a circle centred at centre_m pressed along -normal_m (unit,
    from the counter-body towards the circle) onto candidate nodes of a meshed counter-body.
    counter_frames: R of `node_frames` when the counter factor is of R^T K R."""
    x = counter_points[candidates]
    n, dist = contact_directions(centre_m, x)
    rot = math.atan2(normal_m[1], normal_m[0]) - math.pi / 2
    Bc = contact.node_operator(candidates, -n, counter_factor.n_dofs)
    if counter_frames is not None:
        Bc = Bc @ counter_frames      # the t part of a node framed along this n is exactly 0
    C = counter_factor.compliance(Bc) + body.compliance(n, rot)
    return contact.ContactSetup(C, dist - body.radius_m, n @ normal_m, coord_m,
                                contact.tributary_lengths(x), candidates)


# ---------------------------------------------------------------------------- Hertz benchmark

@dataclass(frozen=True)
class HertzBenchmark:
    radius_m: float
    counter_radius_m: float
    width_m: float
    force_N: float
    mesh_size_m: float                 # element size at the contact
    peak_pressure_Pa: float
    half_width_m: float
    approach_m: float
    peak_pressure_closed_form_Pa: float
    half_width_closed_form_m: float
    approach_closed_form_m: float
    nodes: int
    result: contact.ContactResult = field(repr=False)
    meshes: tuple = field(repr=False, default=())

    def to_json(self) -> dict:
        return {
            "radius_mm": self.radius_m * 1e3,
            "counter_radius_mm": None if math.isinf(self.counter_radius_m) else self.counter_radius_m * 1e3,
            "width_mm": self.width_m * 1e3, "load_N": self.force_N,
            "peak_pressure_MPa": self.peak_pressure_Pa / 1e6,
            "peak_pressure_closed_form_MPa": self.peak_pressure_closed_form_Pa / 1e6,
            "peak_pressure_error": self.peak_pressure_Pa / self.peak_pressure_closed_form_Pa - 1,
            "half_width_mm": self.half_width_m * 1e3,
            "half_width_closed_form_mm": self.half_width_closed_form_m * 1e3,
            "half_width_error": self.half_width_m / self.half_width_closed_form_m - 1,
            "approach_um": self.approach_m * 1e6,
            "approach_closed_form_um": self.approach_closed_form_m * 1e6,
            "approach_error": self.approach_m / self.approach_closed_form_m - 1,
            "mesh_size_mm": self.mesh_size_m * 1e3, "nodes": self.nodes,
            "closed_form": "Hertz line contact (Johnson 1985 eqs. 4.43-4.45); approach: Johnson eq. 5.36 "
                           "for each cylinder centre, plane-strain McEwen-stress integral for the flat "
                           "block to its clamped base",
        }


def hertz_benchmark(radius_m: float, width_m: float, force_N: float, E_Pa: float = 206e9,
                    nu: float = 0.3, counter_radius_m: float = math.inf,
                    mesh_size_m: float | None = None) -> HertzBenchmark:
    """A cylinder (back half clamped) pressed on a flat block (10 R deep, 20 R wide, base
    clamped) or on a counter-cylinder (back half clamped): FE against Hertz."""
    for name, v in (("radius", radius_m), ("width", width_m), ("load", force_N),
                    ("counter radius", counter_radius_m)):
        if not (v > 0):
            raise InputError(f"hertz benchmark {name} = {v!r}: must be positive")
    Es = hertz.contact_modulus(E_Pa, nu)
    Rp = hertz.effective_radius(radius_m, counter_radius_m)
    p0, b = (float(v) for v in hertz.hertz_line(force_N, width_m, Rp, Es))
    if b > 0.2 * min(radius_m, counter_radius_m):
        raise InputError(f"hertz benchmark load = {force_N:g} N: Hertz half-width {b * 1e3:.3g} mm is not "
                         f"small against the radius; lower the load (Hertz needs b << R)")
    h = mesh_size_m or b / 25
    if not (0 < h < b):
        raise InputError(f"mesh size = {h * 1e3:g} mm: must be below the Hertz half-width {b * 1e3:.3g} mm")
    window = 2.0 * b
    body = CircleBody.build(radius_m, h, radius_m / 8, E_Pa, nu, window * 1.5)
    if math.isinf(counter_radius_m):
        D = 10 * radius_m
        cm = block_mesh(20 * radius_m, D, h, radius_m, GROWTH)
        fixed = cm.boundary["bottom"]
        top = cm.boundary["top"]
        cand = top[np.abs(cm.points[top, 0]) <= window]
        coord = cm.points[cand, 0]
        approach_cf = (hertz.cylinder_centre_approach(force_N, width_m, radius_m, b, E_Pa, nu)
                       + hertz.half_plane_approach(force_N, width_m, b, D, E_Pa, nu))
        cpoints = cm.points
    else:
        cm = pin_mesh(counter_radius_m, h, counter_radius_m / 8, GROWTH, contact_angle_rad=np.pi / 2)
        fixed = cm.boundary["back"]
        surf = cm.boundary["surface"]
        ang = np.arctan2(cm.points[surf, 1], cm.points[surf, 0]) - np.pi / 2
        ang = (ang + np.pi) % (2 * np.pi) - np.pi
        keep = np.abs(ang) * counter_radius_m <= window
        order = np.argsort(ang[keep])
        cand = surf[keep][order]
        coord = ang[keep][order] * counter_radius_m
        cpoints = cm.points - np.array([0.0, counter_radius_m])    # top of the counter-cylinder at 0
        approach_cf = float(hertz.cylinder_centre_approach(force_N, width_m, radius_m, b, E_Pa, nu)
                            + hertz.cylinder_centre_approach(force_N, width_m, counter_radius_m, b, E_Pa, nu))
        cm = Mesh2D(cpoints, cm.triangles, cm.boundary)
    K = elastic.stiffness(elastic.basis_2d(cm), E_Pa, nu)
    cf = elastic.Factorized.of(K, np.concatenate([2 * fixed, 2 * fixed + 1]),
                               last=np.column_stack([2 * cand, 2 * cand + 1]).ravel())
    setup = make_setup(body, np.array([0.0, radius_m]), np.array([0.0, 1.0]), cpoints, cf, cand, coord)
    res = contact.solve_load(setup, force_N, width_m)
    return HertzBenchmark(radius_m, counter_radius_m, width_m, force_N, h, res.peak_pressure_Pa,
                          res.half_width_m, res.approach_m, p0, b, float(approach_cf),
                          len(body.mesh.points) + len(cm.points), res,
                          (body.mesh.transformed(0.0, (0.0, radius_m)), cm))


# ---------------------------------------------------------------------------- cycloid tooth pair

def pin_pose(case, position_deg: np.ndarray) -> np.ndarray:
    """Nominal pin centres in the disc frame [mm] for pin phases (deg): pin at angle phi_k,
    crank at psi_c = phi_k - position; disc centre E (cos psi_c, sin psi_c), rotated -psi_c/zc.
    The pin is chosen as the one on the +x axis (phi_k = 0), so psi_c = -position."""
    c = case.cycloid
    psi = -np.deg2rad(np.asarray(position_deg, float))
    rel = np.column_stack([c.pin_circle_radius_mm - c.eccentricity_mm * np.cos(psi),
                           -c.eccentricity_mm * np.sin(psi)])
    rot = psi / c.zc                      # undo the disc rotation -psi_c / zc
    cr, sr = np.cos(rot), np.sin(rot)
    return np.column_stack([cr * rel[:, 0] - sr * rel[:, 1], sr * rel[:, 0] + cr * rel[:, 1]])


@dataclass(frozen=True)
class FirstContact:
    """Where each pin first touches the modified profile (arrays over pin positions; disc frame, mm)."""
    t_rad: np.ndarray                 # profile parameter of the contact point
    point_mm: np.ndarray              # (P, 2) contact point on the profile
    normal: np.ndarray                # (P, 2) unit normal of the profile there, towards the pin (outward)
    centre_mm: np.ndarray             # (P, 2) pin centre moved along the normal until it touches
    curvature_radius_mm: np.ndarray   # profile curvature radius at the contact (> 0 convex)


def first_contact(case, centres_mm: np.ndarray, t_range: tuple[float, float]) -> FirstContact:
    """For each pin centre: the foot point on the modified profile (exact, from the one geometry
    kernel `geometry.pin_profile`), its outward normal, the pin centre moved along it to touch
    (distance = the pin radius the FE pin mesh has) and the profile's curvature radius there, from
    the analytic curvature of the pin-centre curve (1 / kappa - Rr). t is reported in the branch
    t_range, which must hold the foot point."""
    args = profile_args(case, modified=True)
    q = np.asarray(centres_mm, float).reshape(-1, 2)
    foot = pin_profile.nearest(q[:, 0], q[:, 1], args["R"], args["E"], args["zp"], args["rotation_rad"])
    t = t_range[0] + np.mod(foot.t_rad - t_range[0], 2 * np.pi)
    if np.any(t > t_range[1]):
        k = int(np.argmax(t > t_range[1]))
        raise InputError(f"pin centre {q[k].tolist()} mm: its foot point t = {t[k]:.6g} rad lies outside "
                         f"the profile stretch t in [{t_range[0]:.6g}, {t_range[1]:.6g}] rad")
    point = foot.profile_point_mm(args["Rr"])
    return FirstContact(t, point, foot.normal, point + case.cycloid.pin_radius_mm * foot.normal,
                        pin_profile.profile_curvature_radius_mm(foot.curvature_per_mm, args["Rr"]))


def path_of_contact(case, *, n: int = 9, lo_deg: float = 10.0, hi_deg: float = 170.0) -> np.ndarray:
    """Pin phases along the path of contact of one flank (the loaded half, 0..180 deg)."""
    return np.linspace(lo_deg, hi_deg, n)


def contact_force_at_torque(case, torque_Nm: float) -> float:
    """Most loaded pin's normal force [N] from the classical load-sharing estimate (all pins of
    the loaded half in contact, force proportional to the lever arm; e.g. Blanche & Yang 1989,
    Li Lixing, Design of cycloid drives): F_max = 4 T_disc / (K1 zc rp), K1 = E zp / rp, with one
    disc carrying T_disc = 0.55 T (two discs, 10 % uneven sharing) or the whole T for one disc."""
    c = case.cycloid
    K1 = c.eccentricity_mm * c.zp / c.pin_circle_radius_mm
    share = 0.55 if c.disc_count == 2 else 1.0
    return 4.0 * share * torque_Nm / (K1 * c.zc * c.pin_circle_radius_mm * 1e-3)


@dataclass(frozen=True)
class ToothPairMap:
    position_deg: np.ndarray
    load_N: np.ndarray
    approach_m: np.ndarray           # (P, L)
    peak_pressure_Pa: np.ndarray
    half_width_m: np.ndarray
    hertz_peak_pressure_Pa: np.ndarray
    hertz_half_width_m: np.ndarray
    curvature_radius_m: np.ndarray   # (P,) profile curvature radius at first contact (<0 concave)
    law_k_N_per_m_pow: np.ndarray
    law_n: np.ndarray
    mesh_size_m: float
    disc_mesh: Mesh2D = field(repr=False)
    pin_mesh_local: Mesh2D = field(repr=False)
    timing_s: dict = field(default_factory=dict)
    snapshot: dict = field(default_factory=dict, repr=False)   # one solution's fields (arrays), for pictures


def _disc_von_mises(basis, setup, res, centre_m, fac, E: float, nu: float, frames=None) -> np.ndarray:
    """Von Mises stress [Pa] per element of the disc under one contact solution (one more solve with
    the same factors; the contact pressure acts along the pin-centre direction). frames: R of
    `node_frames` when fac is of R^T K R (u = R u_local)."""
    from fem.contact import node_operator
    n, _ = contact_directions(centre_m, basis.mesh.p.T[setup.nodes])
    B = node_operator(setup.nodes, -n, fac.n_dofs)
    f = B.T @ (res.pressure_Pa * setup.tributary_m)    # per metre of width
    u = fac.solve(f) if frames is None else frames @ fac.solve(frames.T @ f)
    return elastic.stress_2d(basis, u, E, nu)["von_mises"]


def _condensed_disc(K, fixed, prof_nodes, member, directions):
    """Disc factorized with its candidates' DOFs last (their compliance read off the factors: a
    plain factorization + unit-load solves measured ~10x slower, SuperLU's dense-RHS solve).
    member (P, n_profile): candidate windows; directions (P, n_profile, 2): profile node -> pin
    centre. A candidate of ONE position is loaded along one known direction: framed along it,
    that DOF alone is condensed; candidates shared by positions keep both (the block costs ~k^3)."""
    single = np.flatnonzero(member.sum(0) == 1)
    owner = np.argmax(member[:, single], axis=0)
    frames = node_frames(K.shape[0], prof_nodes[single], directions[owner, single])
    cand = np.flatnonzero(member.any(axis=0))          # along the profile: windows stay contiguous
    both = np.column_stack([np.ones(len(cand), bool), member[:, cand].sum(0) > 1]).ravel()
    last = np.column_stack([2 * prof_nodes[cand], 2 * prof_nodes[cand] + 1]).ravel()[both]
    D = (frames - sp.identity(K.shape[0], format="csr")).tocsr()
    D.eliminate_zeros()                               # framed nodes only: R^T K R without two full products
    KD = K @ D
    Kr = (K + KD + D.T @ (K + KD)).tocsr()
    return elastic.Factorized.of(Kr, np.concatenate([2 * fixed, 2 * fixed + 1]), last=last), frames


def tooth_pair_map(case, *, positions_deg=None, loads_N=None, mesh_size_m: float | None = None,
                   h_max_m: float | None = None, direct: bool = False) -> ToothPairMap:
    """Load-deflection map of one tooth-pin pair, ONE factorization for the disc and one for the pin.
    direct: the reference path for tests, the disc's compliance by unit-load solves on a plain
    factorization (same results, ~10x slower)."""
    t_start = time.perf_counter()
    c = case.cycloid
    E, nu = case.material.youngs_modulus_GPa * 1e9, case.material.poisson_ratio
    width = c.width_mm * 1e-3
    pos = np.asarray(path_of_contact(case) if positions_deg is None else positions_deg, float)
    if np.any(pos <= 0) or np.any(pos >= 180) or np.any(np.diff(pos) <= 0):
        raise InputError(f"positions_deg = {pos.tolist()}: need increasing pin phases inside (0, 180) deg")
    fmax = contact_force_at_torque(case, 2.5 * case.rated_torque_Nm)
    loads = np.asarray(fmax * np.array([0.05, 0.1, 0.2, 0.4, 0.7, 1.0]) if loads_N is None else loads_N, float)
    centres = pin_pose(case, pos)
    # the flank near the +x pin: profile parameter about t = 0 (x = R cos t, y = -R sin t)
    pitch = 2 * np.pi / c.zp
    t_range = (-1.5 * pitch, 1.5 * pitch)
    fc = first_contact(case, centres, t_range)
    Es = hertz.contact_modulus(E, nu)
    Rr = c.pin_radius_mm * 1e-3
    rho = fc.curvature_radius_mm * 1e-3
    Rp = np.array([hertz.effective_radius(Rr, r) for r in rho])
    p0_h, b_h = hertz.hertz_line(loads[None, :], width, Rp[:, None], Es)
    b_min = float(b_h.min())
    h = mesh_size_m or b_min / 12
    if not (0 < h < b_min):
        raise InputError(f"mesh size = {h * 1e3:g} mm: must be below the smallest Hertz half-width "
                         f"{b_min * 1e3:.3g} mm (else the contact is not resolved)")
    h_max = h_max_m or min(0.5e-3, c.pin_radius_mm * 1e-3 / 6)
    # contact stays within the window (checked per load below); 2 b_max, not 1.4: on a near-conformal
    # flank the contact drifts along the profile (RV-40E, 10 deg, 4019 N: 1.4 b_max is reached)
    window = 2.0 * float(b_h.max())
    # disc: one mesh graded toward every first-contact point
    args = profile_args(case, modified=True)
    curve = lambda t: np.column_stack(cycloid_xy(t, **args))  # noqa: E731
    root = c.pin_circle_radius_mm - c.eccentricity_mm - c.pin_radius_mm
    inner = (root - 2 * c.eccentricity_mm - 2 * np.pi * c.pin_circle_radius_mm / c.zp) * 1e-3
    t0, t1 = -0.9 * pitch, 0.9 * pitch
    dmesh = profile_sector_mesh(curve, t1, t0, list(fc.t_rad), inner, h, h_max, GROWTH)
    t_mesh = time.perf_counter()
    prof_nodes = dmesh.boundary["profile"]
    prof_pts = dmesh.points[prof_nodes]
    s_arc = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(prof_pts, axis=0).T))])
    # candidate zone of each position: the same 2 b_max, with the b_max of THAT position (the
    # near-conformal root sets the path's largest; sized by it, RV-40E-81's nine zones held 2503
    # candidates, 809 so): fewer condensed DOFs, same solution while no contact reaches a zone end
    windows = []
    for p_mm, w in zip(fc.point_mm, 2.0 * b_h.max(axis=1)):
        i0 = int(np.argmin(np.hypot(*(prof_pts - p_mm * 1e-3).T)))
        windows.append((i0, np.abs(s_arc - s_arc[i0]) <= w))
    dbasis = elastic.basis_2d(dmesh)
    K = elastic.stiffness(dbasis, E, nu)
    fixed = dmesh.boundary["inner"]
    t_a = time.perf_counter()
    member = np.array([w for _, w in windows])
    if direct:
        dfac, frames = elastic.Factorized.of(K, np.concatenate([2 * fixed, 2 * fixed + 1])), None
    else:
        dfac, frames = _condensed_disc(K, fixed, prof_nodes, member,
                                       contact_directions(fc.centre_mm[:, None] * 1e-3, prof_pts[None])[0])
    pin = CircleBody.build(Rr, h, h_max, E, nu, 1.5 * window)
    t_fact = time.perf_counter()
    P, L = len(pos), len(loads)
    app, pk, hw = (np.zeros((P, L)) for _ in range(3))
    snapshot = {}
    for ip, (nrm, centre_mm) in enumerate(zip(fc.normal, fc.centre_mm)):
        i0, sel = windows[ip]
        setup = make_setup(pin, centre_mm * 1e-3, nrm, dmesh.points, dfac, prof_nodes[sel],
                           s_arc[sel] - s_arc[i0], frames)
        r = None
        for il, F in enumerate(loads):
            r = contact.solve_load(setup, F, width, None if r is None else np.flatnonzero(r.active))
            if r.active[0] or r.active[-1]:
                raise InputError(f"contact at position {pos[ip]:g} deg, load {F:g} N reaches the end of the "
                                 f"candidate zone: the profile is too flat there for a line contact")
            app[ip, il], pk[ip, il], hw[ip, il] = r.approach_m, r.peak_pressure_Pa, r.half_width_m
            if il == L - 1 and ip == int(np.argmin(np.abs(pos - 90))):
                snapshot = {"position_deg": float(pos[ip]), "load_N": float(F), "centre_m": centre_mm * 1e-3,
                            "normal": nrm,
                            "von_mises_Pa": _disc_von_mises(dbasis, setup, r, centre_mm * 1e-3, dfac, E, nu,
                                                              frames)}
    t_solve = time.perf_counter()
    fits = [hertz.fit_power_law(loads, app[i]) for i in range(P)]
    return ToothPairMap(pos, loads, app, pk, hw, p0_h, b_h, rho, np.array([f[0] for f in fits]),
                        np.array([f[1] for f in fits]), h, dmesh, pin.mesh,
                        {"mesh_s": t_mesh - t_start, "assemble_s": t_a - t_mesh,
                         "factorize_s": t_fact - t_a, "disc_factor_s": dfac.factor_seconds,
                         "pin_factor_s": pin.factor.factor_seconds, "solve_s": t_solve - t_fact,
                         "total_s": t_solve - t_start, "disc_dofs": int(K.shape[0])},
                        snapshot)
