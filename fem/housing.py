"""The housing (pin ring) as an elastic body: 2D plane-stress FE of its section, condensed to the pins.

Model: the section of the housing in the discs' plane, from the pin grooves out to the flange rim
(geometry from the case's [housing] keys, `case_geometry`): a bore of the pin-circle radius R with
zp grooves of the pin radius Rr centred on the pin circle (each groove is the part of the pin's
circle outside the bore, a hair more than a half circle), the flange's bolt holes on their circle
(bolt 1 at the angle of pin 1, ASSUMED: the phase only turns the lobes' phases). P2 triangles
(fem.disc_body.vector_basis), plane stress times ONE thickness, the pin ring's axial length:
IDEALISATION, the flange and the ring in one plane and equally thick. Clamped at the bolt holes
(every DOF on the hole edges fixed: bolts and the mounting face held rigid, no joint slip; the
joints are issue 20's own component).
Loads: each pin's force F reaches its groove as the seat pressure p(theta) = p0 cos(theta - theta_F)
over the seat, the groove's half circle facing outwards (theta the polar angle about the pin centre),
p0 = 2 |F| / (pi Rr L): its resultant is exactly F and it is linear in F (so the pins have a
compliance MATRIX); for a radial force it is the classical loaded-half bearing pressure, for an
inclined one the seat's trailing edge carries a small negative part (the linearisation). The
quadrature resultant is corrected to exactly F per pin.
Seat displacement: the displacement work-conjugate to that pressure (a pressure-weighted mean over
the seat), so C = G K^-1 G^T [m/N], (2 zp, 2 zp), rows/columns 2k (x) and 2k+1 (y) of pin k at
2 pi k / zp, ground frame. It includes the groove's local deformation under the seat pressure
(fem.pin_groove's series term holds the groove behind the conformal contact down to a datum one pin
pitch deep: that part is counted twice if both go in series). `local_radial_m_per_N` is each pin's
radial compliance between its seat and that datum (the seat's radial displacement less the datum
point's, under its own radial load; `check['local_groove_share']` its mean share of the radial
diagonal), `datum_radial_m_per_N` the rest: the housing beyond the groove law under a pin's own load.
The overlap cannot be taken out of C pin by pin (C less the local parts is indefinite, measured).
Reduction (`HousingFE.modes`): the n most compliant eigenvectors of C, modal stiffness 1/lambda,
modal masses of their displacement fields (Ritz, consistent mass of the section, density from the
case), and the residual (C - Phi Lambda Phi^T) projected on each pin's radial direction (diagonal),
for a spring in series in the pin law.
Torsion: tangential pin forces T / (zp R) on every pin -> ring rotation theta = t.C.t / (zp R)^2 per
N m on the housing; at the output (input locked, w_in = i w_out - (i - 1) w_housing) the housing
turns the output by (i - 1) / i of its own rotation and carries (i - 1) / i of the output torque,
so theta_out / T_out = ((i - 1) / i)^2 theta / T. With the classical pin loads of both discs
(`pin_force_pattern`; one disc's pin forces turn the housing by zp / zc of the disc torque) the
work-conjugate output compliance is F.C.F / T_out^2.
Verification (`check`): Lame annulus with its outer edge fixed and the clamped annulus in torsion
(fem.housing_checks, closed forms), mesh convergence, reciprocity, equilibrium, the bolt pattern's
symmetry (`bolt_symmetry`).
Limits: 2D (no axial bending of the flange, no tilt from the two discs' axial offset), linear,
frictionless, uniform thickness, rigid bolts; main-bearing seats not modelled; a pin's load spreads
over the whole ring length L in the section, while one disc loads its pin over its face width w:
the local groove part is therefore about L / w too stiff here (fem.pin_groove carries it per disc).
"""
from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from fem import elastic
from fem.disc_body import plane_stress_stiffness, rigid_modes, vector_basis
from fem.mesh import Mesh2D, triangulate
from geometry.artifacts import InputError

GROOVE_ELEMENTS_PER_RADIUS = 3      # default element size on the grooves: Rr / 3 (check["convergence"])
ARCMIN_PER_RAD = 180.0 * 60.0 / math.pi
GRADING_PIN_RADII = 1.5             # interior element size doubles this many pin radii from a boundary


@dataclass(frozen=True)
class HousingGeometry:
    """The housing section in metres (ground frame, pin k at 2 pi k / zp)."""
    pin_count: int
    pin_circle_radius_m: float
    pin_radius_m: float
    ring_outer_radius_m: float       # informative in 2D (uniform thickness); bounds the bolt circle
    flange_outer_radius_m: float
    bolt_count: int
    bolt_circle_radius_m: float
    bolt_hole_radius_m: float
    thickness_m: float               # the pin ring's axial length
    E_Pa: float
    nu: float
    density_kg_per_m3: float

    def pin_angles_rad(self) -> np.ndarray:
        return 2 * math.pi * np.arange(self.pin_count) / self.pin_count

    def bolt_centres_m(self) -> np.ndarray:
        a = 2 * math.pi * np.arange(self.bolt_count) / self.bolt_count
        return self.bolt_circle_radius_m * np.column_stack([np.cos(a), np.sin(a)])

    @property
    def groove_end_rad(self) -> float:
        """Half-angle (about the pin centre, from the outward radial) where the groove meets the
        bore: |c + Rr n|^2 = R^2 <=> cos(alpha) = -Rr / (2 R)."""
        return math.acos(-self.pin_radius_m / (2 * self.pin_circle_radius_m))


def case_geometry(case) -> HousingGeometry:
    c, h, m = case.cycloid, case.housing, case.material
    return HousingGeometry(c.zp, c.pin_circle_radius_mm * 1e-3, c.pin_radius_mm * 1e-3,
                           h.pin_ring_outer_radius_mm * 1e-3, h.flange_outer_radius_mm * 1e-3, h.bolt_count,
                           h.bolt_circle_radius_mm * 1e-3, h.bolt_hole_radius_mm * 1e-3,
                           h.pin_ring_length_mm * 1e-3, m.youngs_modulus_GPa * 1e9, m.poisson_ratio,
                           m.density_kg_per_m3)


# ----------------------------------------------------------------------------- mesh
def _arc(centre, radius, a0, a1, h):
    """Points on an arc a0 -> a1 (a0 included, a1 not), spacing <= h."""
    n = max(1, int(math.ceil(abs(a1 - a0) * radius / h)))
    a = a0 + (a1 - a0) * np.arange(n) / n
    return np.column_stack([centre[0] + radius * np.cos(a), centre[1] + radius * np.sin(a)])


@dataclass(frozen=True)
class HousingMesh:
    mesh: Mesh2D
    seats: tuple                     # per pin: ordered node indices of the seat (alpha in [-pi/2, pi/2])
    bolts: tuple                     # per bolt: closed loop of node indices
    h_m: float


def housing_mesh(g: HousingGeometry, h_m: float) -> HousingMesh:
    """Triangle mesh of the section: the grooved bore (seat ends at alpha = +-pi/2 are nodes, so the
    seat load is integrated over exactly the seat), the flange rim and the bolt holes; element size
    h on the grooves growing with the distance from the grooves and the bolt holes."""
    if not (0 < h_m <= g.pin_radius_m):
        raise InputError(f"housing mesh size h_m = {h_m!r}: allowed 0 < h <= the pin radius {g.pin_radius_m:g} m")
    R, r, ae = g.pin_circle_radius_m, g.pin_radius_m, g.groove_end_rad
    h_bolt = h_m * max(1.0, g.bolt_hole_radius_m / r)
    h_max = 8 * h_m * max(1.0, g.bolt_hole_radius_m / r)
    pts, seats, start = [], [], 0
    phis = g.pin_angles_rad()
    for k, phi in enumerate(phis):
        c = R * np.array([math.cos(phi), math.sin(phi)])
        # alpha about the pin centre from its outward radial: polar angle phi + alpha
        groove = np.vstack([_arc(c, r, phi - ae, phi - math.pi / 2, h_m),
                            _arc(c, r, phi - math.pi / 2, phi + math.pi / 2, h_m),
                            _arc(c, r, phi + math.pi / 2, phi + ae, h_m)])
        i0 = len(_arc(c, r, phi - ae, phi - math.pi / 2, h_m))
        n_seat = len(_arc(c, r, phi - math.pi / 2, phi + math.pi / 2, h_m))
        seats.append(np.arange(start + i0, start + i0 + n_seat + 1))      # + the node at +pi/2
        end = c + r * np.array([math.cos(phi + ae), math.sin(phi + ae)])
        nxt = phis[(k + 1) % g.pin_count] + (2 * math.pi if k + 1 == g.pin_count else 0.0)
        delta = math.atan2(end[1], end[0]) - phi
        delta = (delta + math.pi) % (2 * math.pi) - math.pi
        land = _arc((0.0, 0.0), R, phi + delta, nxt - delta, h_m)
        pts += [groove, land]
        start += len(groove) + len(land)
    bore = np.vstack(pts)
    outer = _arc((0.0, 0.0), g.flange_outer_radius_m, 0.0, 2 * math.pi, min(h_max, 2 * math.pi * g.flange_outer_radius_m / 48))
    bolts_xy = g.bolt_centres_m()
    bolt_loops = [_arc(b, g.bolt_hole_radius_m, 0.0, 2 * math.pi, min(h_bolt, 2 * math.pi * g.bolt_hole_radius_m / 16))
                  for b in bolts_xy]
    grade = GRADING_PIN_RADII * r

    def size(xy):
        rr = np.hypot(xy[:, 0], xy[:, 1])
        d_groove = np.maximum(rr - R - r, 0.0)
        d_bolt = np.min(np.abs(np.hypot(xy[:, None, 0] - bolts_xy[None, :, 0], xy[:, None, 1] - bolts_xy[None, :, 1])
                               - g.bolt_hole_radius_m), axis=1)
        return np.minimum(np.minimum(h_m * (1 + d_groove / grade), h_bolt * (1 + d_bolt / grade)), h_max)

    holes = np.vstack([np.zeros((1, 2)), bolts_xy])
    p, t = triangulate(outer, h_max, holes=holes, extra_loops=[bore, *bolt_loops], size=size)
    n_out = len(outer)
    seats = tuple(s + n_out for s in seats)
    seats = tuple(np.where(s >= n_out + len(bore), s - len(bore), s) for s in seats)   # the last seat's end wraps
    b0 = n_out + len(bore)
    bolts, o = [], b0
    for loop in bolt_loops:
        bolts.append(np.arange(o, o + len(loop)))
        o += len(loop)
    return HousingMesh(Mesh2D(p, t, {"outer": np.arange(n_out), "bore": np.arange(n_out, b0)}),
                       seats, tuple(bolts), h_m)


def facet_lookup(basis) -> dict:
    """Edge key (lower node * n + higher node) -> facet index of the mesh."""
    f = basis.mesh.facets
    nv = basis.mesh.p.shape[1]
    return {int(k): i for i, k in enumerate(np.minimum(f[0], f[1]) * nv + np.maximum(f[0], f[1]))}


def run_facets(basis, run: np.ndarray, closed: bool = False, lookup: dict | None = None) -> np.ndarray:
    """Mesh facets joining consecutive nodes of a run (a closed loop when `closed`)."""
    key = lookup if lookup is not None else facet_lookup(basis)
    nv = basis.mesh.p.shape[1]
    a = run if closed else run[:-1]
    b = np.roll(run, -1) if closed else run[1:]
    want = np.minimum(a, b) * nv + np.maximum(a, b)
    if any(int(k) not in key for k in want):
        raise RuntimeError("a boundary run is not made of mesh edges (Steiner points on a segment?)")
    return np.array([key[int(k)] for k in want])


# ----------------------------------------------------------------------------- loads and operators
def seat_loads(basis, facets, centre, radius: float) -> np.ndarray:
    """(2, N): the seat pressure of a unit force in x and in y (module doc), force per length on the
    section (the thickness is in K), resultants corrected to exactly (1, 0) and (0, 1)."""
    from skfem import FacetBasis, LinearForm, asm
    fb = FacetBasis(basis.mesh, basis.elem, facets=facets)
    cx, cy = centre
    p0 = 2.0 / (math.pi * radius)

    def form(comp):
        @LinearForm
        def f(v, w):
            dx, dy = w.x[0] - cx, w.x[1] - cy
            rr = np.sqrt(dx * dx + dy * dy)
            nx, ny = dx / rr, dy / rr
            p = p0 * (nx if comp == 0 else ny)          # cos(theta - theta_F) for F along x or y
            return p * (nx * v[0] + ny * v[1])
        return asm(f, fb)
    G = np.vstack([form(0), form(1)])
    Rm = rigid_modes(basis)[:, :2].T @ G.T              # (2, 2): resultant of each load
    return np.linalg.solve(Rm.T, G)


def datum_depth_m(g: HousingGeometry) -> float:
    """fem.pin_groove's datum: one pin pitch behind the groove bottom."""
    return 2 * math.pi * g.pin_circle_radius_m / g.pin_count


def datum_radius_m(g: HousingGeometry) -> float:
    """Radius of the datum points: one pin pitch behind the groove bottoms, at most 3/4 of the way
    to the bolt holes' inner edge (a thinner wall: the datum stays clear of the clamp)."""
    bottom = g.pin_circle_radius_m + g.pin_radius_m
    return bottom + min(datum_depth_m(g), 0.75 * (g.bolt_circle_radius_m - g.bolt_hole_radius_m - bottom))


def datum_probes(basis, g: HousingGeometry) -> sp.csr_matrix:
    """(2 zp, N): displacement (x, y) of the datum point behind each groove."""
    r, a = datum_radius_m(g), g.pin_angles_rad()
    P = sp.csr_matrix(basis.probes(r * np.vstack([np.cos(a), np.sin(a)])))     # rows: all x, then all y
    k = len(a)
    return P[np.column_stack([np.arange(k), np.arange(k, 2 * k)]).ravel()]


def mass_matrix(basis, density: float, thickness_m: float) -> sp.csr_matrix:
    from skfem import BilinearForm, asm
    from skfem.helpers import dot

    @BilinearForm
    def m(u, v, w):
        return dot(u, v)
    return (density * thickness_m * asm(m, basis)).tocsr()


def pin_directions(g: HousingGeometry) -> tuple[np.ndarray, np.ndarray]:
    """(2 zp,) radial and tangential unit vectors stacked pin by pin (x, y)."""
    a = g.pin_angles_rad()
    return np.column_stack([np.cos(a), np.sin(a)]).ravel(), np.column_stack([-np.sin(a), np.cos(a)]).ravel()


def radial_diagonal(C: np.ndarray, er: np.ndarray) -> np.ndarray:
    """(zp,) e_k.C_kk.e_k of a (2 zp, 2 zp) matrix with the stacked directions er."""
    zp = len(er) // 2
    blocks = C.reshape(zp, 2, zp, 2)[np.arange(zp), :, np.arange(zp), :]     # (zp, 2, 2)
    e = er.reshape(zp, 2)
    return np.einsum("ka,kab,kb->k", e, blocks, e)


def pin_force_pattern(case, crank_angle_rad: float = 0.0) -> np.ndarray:
    """(zp, 2) forces of one disc on the pins (= on the housing) in classical load sharing, scaled
    to the largest = 1: pins with a positive arm l_k (fem.pin_groove.pin_moment_arms_m) carry
    F_k ~ l_k along the common normal, from the pitch point P = zp e (cos psi, sin psi) through the
    pin centre."""
    from fem.pin_groove import pin_moment_arms_m
    cy = case.cycloid
    g = case_geometry(case)
    arm = pin_moment_arms_m(case, crank_angle_rad)
    a = g.pin_angles_rad()
    pins = g.pin_circle_radius_m * np.column_stack([np.cos(a), np.sin(a)])
    P = cy.zp * cy.eccentricity_mm * 1e-3 * np.array([math.cos(crank_angle_rad), math.sin(crank_angle_rad)])
    d = pins - P
    d /= np.hypot(d[:, 0], d[:, 1])[:, None]
    mag = np.where(arm > 1e-9 * arm.max(), arm / arm.max(), 0.0)
    return mag[:, None] * d


def output_force_pattern(case, output_torque_Nm: float = 1.0) -> np.ndarray:
    """(2 zp,) pin forces on the housing of all discs (disc d at crank angle d pi) in classical
    sharing, scaled so that they turn the housing by (1 - 1/i) T_out, shared equally by the discs."""
    nd, i = case.cycloid.disc_count, case.ratio
    g = case_geometry(case)
    a = g.pin_angles_rad()
    pins = g.pin_circle_radius_m * np.column_stack([np.cos(a), np.sin(a)])
    F = np.zeros((g.pin_count, 2))
    for d in range(nd):
        f = pin_force_pattern(case, d * math.pi)
        moment = float(np.sum(pins[:, 0] * f[:, 1] - pins[:, 1] * f[:, 0]))
        F += f * (1 - 1 / i) * output_torque_Nm / nd / moment
    return F.ravel()


# ----------------------------------------------------------------------------- the result
@dataclass(frozen=True)
class HousingModes:
    """Modal reduction of the pins' compliance (module doc); phi columns are unit vectors of C."""
    phi: np.ndarray                        # (2 zp, n) pin displacements of each mode
    stiffness_N_per_m: np.ndarray          # (n,) 1 / lambda
    mass_kg: np.ndarray                    # (n,) Ritz modal masses (diagonal of mass_matrix_kg)
    residual_radial_m_per_N: np.ndarray    # (zp,) e_r.(C - Phi Lambda Phi^T)_kk.e_r, in series per pin
    kept_fraction: np.ndarray              # (zp,) share of each pin's radial compliance the modes carry
    mass_matrix_kg: np.ndarray             # (n, n) Ritz mass matrix (off-diagonals: the modes' coupling)
    stiffness_check: float                 # max |Psi^T K Psi - diag(1/lambda)| * lambda_1 (Ritz fields exact: ~0)


@dataclass(frozen=True)
class HousingFE:
    geometry: HousingGeometry
    compliance_m_per_N: np.ndarray         # (2 zp, 2 zp), symmetric: the seats
    local_radial_m_per_N: np.ndarray       # (zp,) radial compliance between each seat and its datum
    h_m: float
    dofs: int
    elements: int
    timings_s: dict
    check: dict
    source: str
    mesh: HousingMesh = field(repr=False, compare=False)
    basis: object = field(repr=False, compare=False)
    unit_displacements: np.ndarray = field(repr=False, compare=False)    # (N, 2 zp): K^-1 G^T
    mass_flexibility: np.ndarray = field(repr=False, compare=False)      # (2 zp, 2 zp): U^T M U
    stiffness_matrix: object = field(repr=False, compare=False)

    @property
    def radial_compliance_m_per_N(self) -> np.ndarray:
        """(zp,) e_r.C_kk.e_r: each pin's radial compliance under its own radial force."""
        er, _ = pin_directions(self.geometry)
        return radial_diagonal(self.compliance_m_per_N, er)

    @property
    def datum_radial_m_per_N(self) -> np.ndarray:
        """(zp,) radial compliance of each pin's datum (one pin pitch behind the groove) under its own load."""
        return self.radial_compliance_m_per_N - self.local_radial_m_per_N

    @property
    def torsion_compliance_rad_per_Nm(self) -> float:
        """Ring rotation per N m on the housing, all pins loaded equally and tangentially."""
        _, et = pin_directions(self.geometry)
        g = self.geometry
        return float(et @ self.compliance_m_per_N @ et) / (g.pin_count * g.pin_circle_radius_m) ** 2

    def modes(self, n: int) -> HousingModes:
        """The n most compliant eigenvectors of C, their Ritz masses and the radial residual."""
        zp = self.geometry.pin_count
        if not (isinstance(n, (int, np.integer)) and 1 <= n <= 2 * zp):
            raise InputError(f"housing modes n = {n!r}: allowed a whole number 1 to 2 zp = {2 * zp}")
        C = self.compliance_m_per_N
        lam, V = np.linalg.eigh(C)
        lam, V = lam[::-1][:n], V[:, ::-1][:, :n]
        V = V * np.sign(V[np.argmax(np.abs(V), axis=0), np.arange(n)])      # deterministic sign
        # Ritz fields psi_j = U v_j / lambda_j: unit modal coordinate = pins displaced by v_j
        Mq = V.T @ self.mass_flexibility @ V / np.outer(lam, lam)
        Kq = V.T @ self.compliance_m_per_N @ V / np.outer(lam, lam)         # = Psi^T K Psi (seat modes)
        er, _ = pin_directions(self.geometry)
        full, part = radial_diagonal(C, er), radial_diagonal((V * lam) @ V.T, er)
        return HousingModes(V, 1 / lam, np.diag(Mq).copy(), full - part, part / full, Mq,
                            float(np.abs(Kq - np.diag(1 / lam)).max() * lam[0]))

    def radial_stiffness_lobes(self, top: int = 8, *, datum: bool = False) -> dict:
        """Fourier lobes of the per-pin radial stiffness k_k = 1 / c_k (of the datum's with `datum`):
        {m: amplitude / mean} of the `top` largest m = 1..zp/2 (a pattern with n_b-fold symmetry has
        only multiples of gcd(zp, n_b))."""
        k = 1 / (self.datum_radial_m_per_N if datum else self.radial_compliance_m_per_N)
        X = np.fft.rfft(k) / len(k)
        amp = 2 * np.abs(X[1:]) / X[0].real
        if len(k) % 2 == 0:
            amp[-1] /= 2
        order = np.argsort(amp)[::-1][:top]
        return {int(m + 1): float(amp[m]) for m in sorted(order)}


def rated_disc_loads_N(case) -> np.ndarray:
    """(zp, 2) pin forces on the housing of disc 1 at crank angle 0 and rated torque, classical
    sharing with the project's most-loaded-pin force (fem.pin_contact.contact_force_at_torque)."""
    from fem.pin_contact import contact_force_at_torque
    return pin_force_pattern(case, 0.0) * contact_force_at_torque(case, case.rated_torque_Nm)


def field_under(fe: HousingFE, forces_N: np.ndarray) -> dict:
    """Vertex displacements (n, 2) [m] and element-mean plane-stress von Mises [Pa] under pin forces
    (zp, 2) on the housing."""
    u = fe.unit_displacements @ np.asarray(forces_N, float).ravel()
    b, g = fe.basis, fe.geometry
    grad = b.interpolate(u).grad                        # (2, 2, elements, points)
    lam, mu = elastic.lame(g.E_Pa, g.nu)
    lam = 2 * lam * mu / (lam + 2 * mu)                 # plane stress
    exx, eyy, exy = grad[0, 0], grad[1, 1], 0.5 * (grad[0, 1] + grad[1, 0])
    sxx, syy, sxy = lam * (exx + eyy) + 2 * mu * exx, lam * (exx + eyy) + 2 * mu * eyy, 2 * mu * exy
    vm = np.sqrt(sxx ** 2 - sxx * syy + syy ** 2 + 3 * sxy ** 2).mean(axis=1)
    return {"displacement_m": u[b.nodal_dofs].T, "von_mises_Pa": vm}


def default_h_m(case) -> float:
    return case.cycloid.pin_radius_mm * 1e-3 / GROOVE_ELEMENTS_PER_RADIUS


def solve_housing(g: HousingGeometry, h_m: float) -> HousingFE:
    """Mesh, assemble, factorize and condense (module doc)."""
    t0 = time.perf_counter()
    hm = housing_mesh(g, h_m)
    t1 = time.perf_counter()
    basis = vector_basis(hm.mesh)
    K = plane_stress_stiffness(basis, g.E_Pa, g.nu, g.thickness_m)
    M = mass_matrix(basis, g.density_kg_per_m3, g.thickness_m)
    a, lookup = g.pin_angles_rad(), facet_lookup(basis)
    G = np.vstack([seat_loads(basis, run_facets(basis, s, lookup=lookup),
                              g.pin_circle_radius_m * np.array([math.cos(p), math.sin(p)]), g.pin_radius_m)
                   for s, p in zip(hm.seats, a)])
    fixed = np.unique(np.concatenate([basis.get_dofs(run_facets(basis, b, closed=True, lookup=lookup)).all()
                                      for b in hm.bolts]))
    t2 = time.perf_counter()
    fac = elastic.Factorized.of(K, fixed)
    U = fac.solve(G.T)
    t3 = time.perf_counter()
    C_raw = G @ U
    C = 0.5 * (C_raw + C_raw.T)
    R = rigid_modes(basis)
    react = R.T @ (K @ U - G.T)                          # (3, 2 zp): bolt reactions' resultant and moment
    applied = R.T @ G.T
    check = {"reciprocity": float(np.abs(C_raw - C_raw.T).max() / np.abs(C_raw).max()),
             "equilibrium": float(np.abs(react + applied).max() / np.abs(applied).max()),
             "load_resultant_error": float(np.abs(applied[:2] - np.tile(np.eye(2), g.pin_count)).max()),
             "positive_definite": bool(np.linalg.eigvalsh(C).min() > 0)}
    # each pin's radial compliance between its seat and fem.pin_groove's datum (one pin pitch behind
    # the groove bottom, on the pin's radial; the datum's displacement under its own pin's load is a
    # diagonal entry of D K^-1 G^T: as a matrix D K^-1 G^T is not reciprocal, measured 60 % asymmetric,
    # and C less these diagonal parts is indefinite, measured: the overlap cannot be taken out pin by pin)
    er, _ = pin_directions(g)
    local = radial_diagonal(C, er) - radial_diagonal(datum_probes(basis, g) @ U, er)
    check["local_groove_share"] = float(np.mean(local / radial_diagonal(C, er)))
    check["datum_depth_m"] = datum_radius_m(g) - g.pin_circle_radius_m - g.pin_radius_m
    mf = U.T @ (M @ U)
    t4 = time.perf_counter()
    return HousingFE(g, C, local, h_m, int(basis.N), int(hm.mesh.triangles.shape[0]),
                     {"mesh": t1 - t0, "assemble": t2 - t1, "factor_solve": t3 - t2, "condense": t4 - t3,
                      "total": t4 - t0},
                     check, _source(g), hm, basis, U, mf, K)


def _source(g: HousingGeometry) -> str:
    return (f"housing section FE (fem.housing): 2D plane stress, P2 triangles, thickness = pin ring length "
            f"{g.thickness_m * 1e3:g} mm, bore R = {g.pin_circle_radius_m * 1e3:g} mm with {g.pin_count} grooves of "
            f"{g.pin_radius_m * 1e3:g} mm, flange to {g.flange_outer_radius_m * 1e3:g} mm clamped at "
            f"{g.bolt_count} bolt holes (r {g.bolt_hole_radius_m * 1e3:g} mm on {g.bolt_circle_radius_m * 1e3:g} mm); "
            f"seat load = cosine pressure over each groove's half circle; seat displacement work-conjugate")


def convergence(g: HousingGeometry, finest: HousingFE | None = None, levels=(1.5, 2.0, 3.0)) -> dict:
    """Mean radial compliance and torsion on meshes h = Rr / level (the finest may be given: the
    result's own mesh); observed order of |q_k - q_k+1| ~ h^p (np.polyfit in log-log), Richardson
    extrapolation and the finest mesh's estimated error."""
    hs = g.pin_radius_m / np.asarray(levels, float)
    fes = [solve_housing(g, h) for h in hs[:-1]] + [finest if finest is not None else solve_housing(g, hs[-1])]
    out = {"h_m": hs.tolist(), "dofs": [fe.dofs for fe in fes]}
    for key, q in (("radial_compliance_m_per_N", [float(fe.radial_compliance_m_per_N.mean()) for fe in fes]),
                   ("torsion_rad_per_Nm", [fe.torsion_compliance_rad_per_Nm for fe in fes])):
        q = np.array(q)
        d = np.abs(np.diff(q))
        p = float(np.polyfit(np.log(hs[:-1]), np.log(d), 1)[0]) if np.all(d > 0) and len(d) > 1 else math.nan
        r = hs[-2] / hs[-1]
        if math.isfinite(p) and p > 0.5:
            extrap = float(q[-1] + (q[-1] - q[-2]) / (r ** p - 1))
            err = abs(extrap - q[-1]) / abs(extrap)
        else:       # no observed order (changes at round-off level): the last change bounds the error
            extrap, err = float(q[-1]), float(d[-1] / abs(q[-1]))
        out[key] = {"values": q.tolist(), "rate": p, "extrapolated": extrap, "finest_error_estimate": err}
    return out


def bolt_symmetry(fe: HousingFE) -> dict:
    """C invariant under a turn by s = zp / gcd(zp, n_b) pins (the bolt pattern repeats there):
    max |C(k+s, l+s) - Q C(k, l) Q^T| / max |C| (the mesh is not symmetric: this measures its
    error), and the radial stiffness lobes, which can only sit at multiples of gcd(zp, n_b)."""
    g = fe.geometry
    zp, nb = g.pin_count, g.bolt_count
    period = math.gcd(zp, nb)
    s = zp // period
    a = 2 * math.pi * s / zp
    Q = np.array([[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]])
    C4 = fe.compliance_m_per_N.reshape(zp, 2, zp, 2)
    # turned[k + s, l + s] = Q C(k, l) Q^T: what C(k + s, l + s) must be
    turned = np.roll(np.roll(np.einsum("ab,kbld,cd->kalc", Q, C4, Q), s, axis=0), s, axis=2)
    lobes = fe.radial_stiffness_lobes(top=zp // 2)
    return {"shift_pins": s, "invariance_error": float(np.abs(C4 - turned).max() / np.abs(C4).max()),
            "lobes": {m: v for m, v in lobes.items() if v > 1e-4},
            "largest_lobe_off_pattern": max((v for m, v in lobes.items() if m % period), default=0.0),
            "lobe_period": period}


def output_figures(fe: HousingFE, case) -> dict:
    """Torsion of the ring at the output (module doc): uniform tangential pin loads, and the
    classical pin loads of both discs (work-conjugate), in rad per N m of output torque and as an
    output stiffness [N m/arcmin]; the housing's torsion over the clamped annulus R..bolt circle."""
    from fem.housing_checks import annulus_torsion_rad_per_Nm
    i, g = case.ratio, fe.geometry
    uniform = ((i - 1) / i) ** 2 * fe.torsion_compliance_rad_per_Nm
    F = output_force_pattern(case, 1.0)
    classical = float(F @ fe.compliance_m_per_N @ F)
    ring = annulus_torsion_rad_per_Nm(g.pin_circle_radius_m, g.bolt_circle_radius_m, g.E_Pa, g.nu, g.thickness_m)
    return {"torsion_uniform_rad_per_Nm_output": uniform,
            "torsion_uniform_Nm_per_arcmin": 1 / (uniform * ARCMIN_PER_RAD),
            "classical_rad_per_Nm_output": classical,
            "classical_Nm_per_arcmin": 1 / (classical * ARCMIN_PER_RAD),
            "housing_torsion_over_clamped_annulus": fe.torsion_compliance_rad_per_Nm / ring,
            "conversion": f"output = ((i-1)/i)^2 x housing, i = {i:g}; classical: F.C.F / T_out^2 with the "
                          f"pin forces of {case.cycloid.disc_count} disc(s) turning the housing by (1 - 1/i) T_out"}


def housing_for_case(case, *, h_m: float | None = None, checks: bool = True) -> HousingFE:
    """The case's housing condensed to its pins (module doc), at element size h_m on the grooves
    (default pin radius / 3), with its checks (closed forms, convergence on two coarser meshes,
    the bolt pattern, the torsion at the output) in `check` unless checks=False."""
    from fem import housing_checks as hc
    g = case_geometry(case)
    fe = solve_housing(g, h_m or default_h_m(case))
    if not checks:
        return fe
    out = dict(fe.check)
    out["lame_fixed_outer"] = hc.lame_fixed_outer(g.pin_circle_radius_m, g.flange_outer_radius_m, h=g.pin_radius_m,
                                                  E=g.E_Pa, nu=g.nu, t=g.thickness_m)
    out["annulus_torsion"] = hc.annulus_torsion(g.pin_circle_radius_m, g.bolt_circle_radius_m, h=g.pin_radius_m,
                                                E=g.E_Pa, nu=g.nu, t=g.thickness_m)
    out["bolt_symmetry"] = bolt_symmetry(fe)
    levels = (GROOVE_ELEMENTS_PER_RADIUS / 2, GROOVE_ELEMENTS_PER_RADIUS / 1.5, GROOVE_ELEMENTS_PER_RADIUS)
    out["convergence"] = convergence(g, fe if h_m is None else None,
                                     levels if h_m is None else tuple(g.pin_radius_m / h_m / np.array([2, 1.5, 1])))
    out.update(output_figures(fe, case))
    return dataclasses.replace(fe, check=out)


def summary(fe: HousingFE, case, modes=(6, 10, 16)) -> dict:
    """The budget's figures of a housing (what `python -m fem.housing` prints)."""
    c, cd = fe.radial_compliance_m_per_N, fe.datum_radial_m_per_N
    ck = fe.check
    out = {"case": case.name, "dofs": fe.dofs, "elements": fe.elements, "seconds": fe.timings_s,
           "radial_compliance_m_per_N": {"mean": float(c.mean()), "min": float(c.min()), "max": float(c.max())},
           "radial_lobes": fe.radial_stiffness_lobes(4),
           "datum_radial_compliance_m_per_N": {"mean": float(cd.mean()), "min": float(cd.min()), "max": float(cd.max())},
           "datum_radial_lobes": fe.radial_stiffness_lobes(4, datum=True),
           "kept_fraction": {n: {"mean": float(fe.modes(n).kept_fraction.mean()),
                                 "min": float(fe.modes(n).kept_fraction.min())} for n in modes},
           "housing_torsion_rad_per_Nm": fe.torsion_compliance_rad_per_Nm}
    out["check"] = {k: v for k, v in ck.items()}
    return out


if __name__ == "__main__":
    import argparse
    import json
    import sys
    from geometry.params import load_case
    ap = argparse.ArgumentParser(prog="python -m fem.housing", description="the housing FE's figures (JSON)")
    ap.add_argument("--case", required=True)
    args = ap.parse_args()
    try:
        cs = load_case(args.case)
        print(json.dumps(summary(housing_for_case(cs), cs), indent=1, default=float))
    except InputError as exc:
        print(f"error: {exc}", file=sys.stderr)
        sys.exit(2)
