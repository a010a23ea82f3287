"""Crankshaft flexibility matrix with the two eccentrics loaded independently (bending, S-bend, tilt).

The lumped model carries one lateral spring per crank: the two discs' forces on a crank are summed
and their opposite parts (each disc's pin-force resultant, 180 deg apart) cancel. In the shaft they
do not: opposite forces on the two eccentrics bend it in an S and tilt each eccentric. This module
gives the shaft-alone flexibility between the generalized loads of both eccentrics, from the 3D FE
of the project's crankshaft (geometry.solids.crankshaft_solid, P2 tetrahedra, fem.shaft pieces):

    loads (per eccentric i = 1, 2; crank frame, x = eccentric 1 direction):
      F_ix, F_iy   uniform traction over the eccentric's cylindrical surface, unit resultant, plus
                   a torsional traction there that moves the resultant onto the shaft axis (the
                   offset torque E x F turns the crank: the lumped crank-torsion spring's job);
                   conjugate: the shaft axis' lateral displacement at the eccentric (the surface's
                   mean displacement less its twist times the offset);
      S_ix, S_iy   couple: traction t_x = (z - z_i) / I_i with I_i = int (z - z_i)^2 dA (zero
                   resultant, unit moment); conjugate: the least-squares slope du_x/dz of the
                   surface (what edge-loads the needles).
    supports: the journals pinned at the support pair's pressure centres (fem.tapered_roller.
      crank_support_positions_m: a tapered roller bearing's radial reaction acts where its rollers'
      load lines cross the axis, R_m tan(alpha) from its centre, inside the pair for the RV's
      face-to-face X arrangement): the area-mean lateral displacement of a band of the seat
      centred there held, the reaction a uniform traction over it, no moment restraint; so bearing
      and carrier compliances add in series afterwards (`with_elastic_supports`). The carrier takes
      the reaction at its seat centre (its condensed DOFs are seat translations): the moment of the
      few-mm offset is left out.
    C_ij = f_i^T K^-1 f_j (exactly symmetric, work-conjugate); the supports' Lagrange multipliers
      are the journal reactions (statically determinate: checked against statics).

Reference: the stepped Timoshenko beam (`stepped_beam_flexibility`), the same generalized loads
and seat-wide supports by unit-load integration (int M_i M_j / EI + V_i V_j / (kappa G A) dz) on
the layout's sections; pinned and for one load it is fem.shaft.crankshaft_beam_reference.

Output mapping (`output_compliance`): each disc's crank-hole forces per unit output torque (static
equilibrium, fem.disc_body.load_pattern) are applied to both eccentrics of every crank; the
compliance energy sum_j f_j^T C f_j / T^2 is the output torsional compliance of crank bending.
With the forces on crank j's eccentrics written f_t +- f_r, on an isotropic shaft
    c_out = 2 sum_j [(C11 - C12) |f_r|^2 + (C11 + C12) |f_t|^2] / T^2,
f_r = a disc's pin resultant / n (opposite on the two discs: the tilt/S-bend mode; it moves a disc
sideways, which the pins turn into output rotation with the lever E zc, like a crank-angle change)
and f_t = T_d / (n a) along the crank-circle tangent (same on both discs: the bow mode, lever a).
One lateral spring per crank (the lumped model) sees |2 f_t|^2 C11 and nothing of f_r.
Limits: linear elastic, no fillets, uniform load along each eccentric (crowning, needle edge load
ignored), pinned at the pressure centres (the bearings' own tilt is their radial springs there).
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from fem import hertz
from fem.mesh import Mesh3D
from fem.shaft import crankshaft_mesh, default_edge_length_m, p2_stiffness, pinned_solve
from fem.tapered_roller import crank_support_positions_m
from geometry.artifacts import InputError

ARCMIN_PER_RAD = 180.0 * 60.0 / math.pi
LABELS = ("F1x", "F1y", "F2x", "F2y", "S1x", "S1y", "S2x", "S2y")
JOURNAL_LABELS = ("J1x", "J1y", "J2x", "J2y")


@dataclass(frozen=True)
class LoadZone:
    """Cylindrical surface of radius `radius_m` about (cx, cy), z in [z0, z1] (an eccentric)."""
    z0_m: float
    z1_m: float
    cx_m: float
    cy_m: float
    radius_m: float

    @property
    def mid_m(self) -> float:
        return 0.5 * (self.z0_m + self.z1_m)


@dataclass(frozen=True)
class Supports:
    """Support bands centred at z = z_m on the journal surface (radius_m), half-width band_m: the
    band's mean lateral displacement is held (a pin there, the reaction spread over the band)."""
    z_m: tuple[float, float]
    radius_m: float
    band_m: float


@dataclass(frozen=True)
class CrankFlexibility:
    """Generalized flexibility of a two-eccentric shaft (labels `LABELS`): F rows/cols in m/N and
    rad/N, S in m/(N m) and rad/(N m); `journal_force` (4, 8) = force passed to each bearing
    (J1x, J1y, J2x, J2y) per unit generalized load; `method` says FE or beam."""
    matrix: np.ndarray
    journal_force: np.ndarray
    eccentric_z_m: tuple[float, float]
    support_z_m: tuple[float, float]
    method: str
    dofs: int = 0
    edge_length_m: float = 0.0
    asymmetry: float = 0.0          # max |C - C^T| / max |C| before symmetrizing (FE solve check)

    def entry(self, row: str, col: str) -> float:
        return float(self.matrix[LABELS.index(row), LABELS.index(col)])

    def response(self, loads: dict) -> np.ndarray:
        """Generalized displacements (8,) for loads {label: value}."""
        g = np.zeros(len(LABELS))
        for k, v in loads.items():
            g[LABELS.index(k)] = v
        return self.matrix @ g

    def single_compliance_m_per_N(self) -> float:
        """Eccentric-1 deflection per N on eccentric 1 alone: 1 / fem.shaft's bending stiffness."""
        return self.entry("F1x", "F1x")

    def _pair(self, sign: float, axis: str) -> dict:
        r = self.response({f"F1{axis}": 1.0, f"F2{axis}": sign})
        return {"deflection_1_m_per_N": r[LABELS.index(f"F1{axis}")],
                "deflection_2_m_per_N": r[LABELS.index(f"F2{axis}")],
                "slope_1_rad_per_N": r[LABELS.index(f"S1{axis}")],
                "slope_2_rad_per_N": r[LABELS.index(f"S2{axis}")]}

    def opposite(self, axis: str = "x") -> dict:
        """+F on eccentric 1, -F on eccentric 2 (per N): mid-plane deflections [m/N], slopes [rad/N]."""
        return self._pair(-1.0, axis)

    def parallel(self, axis: str = "x") -> dict:
        """+F on both eccentrics (per N)."""
        return self._pair(1.0, axis)


def with_elastic_supports(flex: CrankFlexibility, support_compliance_m_per_N: float) -> CrankFlexibility:
    """The same shaft on radial bearing springs (compliance c each, isotropic) instead of pins:
    C + P^T c P (reciprocity: a bearing shift is seen by each load through its own reaction P)."""
    P = flex.journal_force
    return CrankFlexibility(flex.matrix + support_compliance_m_per_N * P.T @ P, P, flex.eccentric_z_m,
                            flex.support_z_m, flex.method + f" + bearings {support_compliance_m_per_N:.3g} m/N",
                            flex.dofs, flex.edge_length_m)


# ----------------------------------------------------------------------------- 3D FE
class _Strip:
    """The part z0 <= z <= z1 of a cylindrical surface (radius about (cx, cy)) of a tet mesh.
    Facets are taken when their z-extent overlaps the strip and every integrand is multiplied by
    the strip's indicator at high-order quadrature points: the mesh has no edge at a strip end on
    a plain cylinder (a seat, a plain test shaft), and picking facets by their midpoints would move
    each end by up to half an element from mesh to mesh (measured: +-4 % on the opposite-load
    deflection of a plain shaft)."""

    def __init__(self, basis, z0, z1, cx, cy, radius, what: str):
        from skfem import FacetBasis
        mesh = basis.mesh
        on = mesh.facets_satisfying(lambda x: np.abs(np.hypot(x[0] - cx, x[1] - cy) - radius) < 0.03 * radius)
        zf = mesh.p[2][mesh.facets[:, on]]
        facets = on[(zf.max(axis=0) > z0) & (zf.min(axis=0) < z1)]
        if len(facets) < 8:
            raise InputError(f"{what}: z = {z0 * 1e3:g}..{z1 * 1e3:g} mm, radius {radius * 1e3:g} mm: "
                             f"no meshed surface found there")
        self.fb = FacetBasis(mesh, basis.elem, facets=facets, intorder=STRIP_QUADRATURE_ORDER)
        self.z0, self.z1 = z0, z1
        self.area = self.integral(lambda x: 1.0 + 0 * x[0])

    def _ind(self, x):
        return ((x[2] >= self.z0) & (x[2] <= self.z1)).astype(float)

    def integral(self, fn) -> float:
        from skfem import Functional, asm
        return float(asm(Functional(lambda w: self._ind(w.x) * fn(w.x)), self.fb))

    def load(self, traction) -> np.ndarray:
        """Load vector of traction(x) -> (tx, ty, tz) on the strip."""
        from skfem import LinearForm, asm

        @LinearForm
        def form(v, w):
            t = traction(w.x)
            return self._ind(w.x) * (t[0] * v[0] + t[1] * v[1] + t[2] * v[2])
        return asm(form, self.fb)


STRIP_QUADRATURE_ORDER = 8     # the strip's step indicator is integrated inside the facets it cuts


def _support_constraints(basis, supports: Supports) -> sp.csr_matrix:
    """Rows (J1x, J1y, J2x, J2y, axial, torsion): the area-mean lateral displacement of each journal
    band (|z - z_s| <= band, the bearing seat) held, plus the mean axial and mean twist of band 1:
    the six rigid modes, no moment restraint (pins). Each row is the load vector of a uniform
    traction of unit resultant on the band, so the multiplier is the bearing force spread over the
    seat as a bearing spreads it. (A band of about one element, fem.shaft's, concentrates the
    reaction on a ring whose width shrinks with the mesh: measured +1.5 % compliance per 0.7x edge,
    not converging.)"""
    rows = []
    zero = lambda x: 0 * x[0]  # noqa: E731
    for k, z in enumerate(supports.z_m):
        st = _Strip(basis, z - supports.band_m, z + supports.band_m, 0.0, 0.0, supports.radius_m, "support band")
        rows += [st.load(lambda x: (zero(x) + 1 / st.area, zero(x), zero(x))),
                 st.load(lambda x: (zero(x), zero(x) + 1 / st.area, zero(x)))]
        if k == 0:
            J = st.integral(lambda x: x[0] ** 2 + x[1] ** 2)
            rows += [st.load(lambda x: (zero(x), zero(x), zero(x) + 1 / st.area)),
                     st.load(lambda x: (-x[1] / J, x[0] / J, zero(x)))]
    return sp.csr_matrix(np.vstack([rows[0], rows[1], rows[4], rows[5], rows[2], rows[3]]))


def _zone_loads(basis, zone: LoadZone) -> list[np.ndarray]:
    """Load vectors F_x, F_y (unit resultant through the shaft axis) and S_x, S_y (unit couple) on
    one zone. A uniform traction on the eccentric acts through its centre (cx, cy): its torque
    about the shaft axis (cx F_y - cy F_x) is taken out by a torsional traction on the same surface
    (a pure couple about the eccentric's centre), so that the crank twist (the lumped model's crank
    torsion spring) is not counted here too."""
    cx, cy = zone.cx_m, zone.cy_m
    st = _Strip(basis, zone.z0_m, zone.z1_m, cx, cy, zone.radius_m, "load zone")
    zero = lambda x: 0 * x[0]  # noqa: E731
    zbar = st.integral(lambda x: x[2]) / st.area
    Iz = st.integral(lambda x: (x[2] - zbar) ** 2)
    J = st.integral(lambda x: (x[0] - cx) ** 2 + (x[1] - cy) ** 2)
    torque = st.load(lambda x: (-(x[1] - cy) / J, (x[0] - cx) / J, zero(x)))
    fx = st.load(lambda x: (zero(x) + 1 / st.area, zero(x), zero(x)))
    fy = st.load(lambda x: (zero(x), zero(x) + 1 / st.area, zero(x)))
    return [fx + cy * torque, fy - cx * torque,
            st.load(lambda x: ((x[2] - zbar) / Iz, zero(x), zero(x))),
            st.load(lambda x: (zero(x), (x[2] - zbar) / Iz, zero(x)))]


def fe_flexibility(mesh3: Mesh3D, supports: Supports, zones: tuple[LoadZone, LoadZone],
                   E_Pa: float, nu: float, edge_length_m: float = 0.0) -> CrankFlexibility:
    """3D FE (P2) flexibility of a shaft pinned at `supports`, generalized loads on two zones."""
    basis, K = p2_stiffness(mesh3, E_Pa, nu)
    Cm = _support_constraints(basis, supports)
    n = K.shape[0]
    loads = [_zone_loads(basis, z) for z in zones]
    # column order of LABELS: F1x F1y F2x F2y S1x S1y S2x S2y
    F = np.column_stack([loads[0][0], loads[0][1], loads[1][0], loads[1][1],
                         loads[0][2], loads[0][3], loads[1][2], loads[1][3]])
    U, lam = pinned_solve(basis, K, Cm, F)
    C = F.T @ U
    asym = float(np.abs(C - C.T).max() / np.abs(C).max())   # Maxwell-Betti: round-off only
    # K u + Cm^T lam = f: the band carries -lam; the shaft pushes +lam into each bearing
    return CrankFlexibility(0.5 * (C + C.T), lam[:4], (zones[0].mid_m, zones[1].mid_m), tuple(supports.z_m),
                            "3D FE, P2 tetrahedra, journals pinned at the supports",
                            int(n), float(edge_length_m), asym)


# ----------------------------------------------------------------------------- beam reference
def stepped_beam_flexibility(span_m: float, zones: tuple[LoadZone, LoadZone], radius_of_z, E_Pa: float,
                             nu: float, n: int = 40001, support_half_width_m: float = 0.0) -> CrankFlexibility:
    """Stepped Timoshenko beam supported at z = 0 and span (each reaction spread uniformly over
    +-support_half_width, its conjugate the band's mean deflection = 0, as the FE's supports; 0 gives
    pins): the same generalized loads as the FE (uniform line load 1/(z1 - z0) for F, (z - z_i)/I
    for S, I = (z1 - z0)^3 / 12) by unit-load integration
    C_ij = int M_i M_j / (E I) + V_i V_j / (kappa G A) dz; x and y planes uncoupled.
    radius_of_z(z) -> section radius [m] (circle about its own centroid)."""
    G, kappa = E_Pa / (2 * (1 + nu)), hertz.timoshenko_shear_coefficient(nu)
    b = support_half_width_m
    z = np.linspace(-b, span_m + b, n)
    r = radius_of_z(z)
    EI, kGA = E_Pa * np.pi * r ** 4 / 4, kappa * G * np.pi * r ** 2

    def uniform(a, c):
        """Share of a unit load spread uniformly over [a, c] left of z, and its first moment (closed
        form: a trapezoid over the step edges would miss the resultant by O(dz / length))."""
        if c <= a:
            return (z >= a).astype(float), a * (z >= a)
        zc = np.clip(z, a, c)
        return (zc - a) / (c - a), (zc ** 2 - a ** 2) / (2 * (c - a))

    supports = [uniform(zs - b, zs + b) for zs in (0.0, span_m)]
    MV = []
    for kind in ("F", "S"):
        for zone in zones:
            lo, hi, m = zone.z0_m, zone.z1_m, zone.mid_m
            if kind == "F":
                Q, Qz = uniform(lo, hi)
            else:
                zc, I = np.clip(z, lo, hi), (hi - lo) ** 3 / 12
                Q = ((zc - m) ** 2 - (lo - m) ** 2) / (2 * I)
                Qz = ((zc ** 3 - lo ** 3) / 3 - m * (zc ** 2 - lo ** 2) / 2) / I
            R2 = Qz[-1] / span_m                    # moments about z = 0 (reactions centred on 0, span)
            R1 = Q[-1] - R2
            N = Q - R1 * supports[0][0] - R2 * supports[1][0]        # net load left of z
            Nz = Qz - R1 * supports[0][1] - R2 * supports[1][1]
            MV.append((-(z * N - Nz), -N, R1, R2))
    # per plane: order F1 F2 S1 S2
    c = np.array([[np.trapezoid(Mi * Mj / EI + Vi * Vj / kGA, z) for (Mj, Vj, _, _) in MV] for (Mi, Vi, _, _) in MV])
    C = np.zeros((8, 8))
    P = np.zeros((4, 8))
    for p, idx in {0: (0, 2, 4, 6), 1: (1, 3, 5, 7)}.items():   # x: F1x F2x S1x S2x; y: ...
        C[np.ix_(idx, idx)] = c
        for k, (_, _, R1, R2) in zip(idx, MV):
            P[p, k], P[2 + p, k] = R1, R2
    return CrankFlexibility(C, P, (zones[0].mid_m, zones[1].mid_m), (0.0, span_m),
                            "stepped Timoshenko beam, unit-load integration, supports spread over "
                            f"+-{b * 1e3:g} mm")


# ----------------------------------------------------------------------------- the case's crankshaft
def case_zones(case, at: str = "pressure") -> tuple[Supports, tuple[LoadZone, LoadZone], float]:
    """Supports (crank_support_positions_m), eccentric zones and the bearing-centre span of the case's
    crankshaft (crank frame, metres)."""
    from geometry.solids import crankshaft_layout
    lay = crankshaft_layout(case)
    if len(lay.eccentrics_mm) != 2:
        raise InputError(f"[cycloid] disc_count = {case.cycloid.disc_count}: the tilt model needs 2 "
                         f"eccentrics (two discs)")
    zones = tuple(LoadZone(a * 1e-3, b * 1e-3, *(v * 1e-3 for v in lay.eccentric_centre_mm(i)),
                           lay.eccentric_radius_mm * 1e-3) for i, (a, b) in enumerate(lay.eccentrics_mm))
    z, band = crank_support_positions_m(case, at)
    return Supports(z, lay.journal_radius_mm * 1e-3, band), zones, lay.support_span_mm * 1e-3


def beam_flexibility(case, *, pinned: bool = False, at: str = "pressure") -> CrankFlexibility:
    """Stepped-beam reference on the case's layout (journal radius, eccentric radius over the
    eccentrics), supported where the FE is (`at`, crank_support_positions_m), reactions spread over the
    same bands (pinned: at points; at='bearing', pinned: fem.shaft.crankshaft_beam_reference)."""
    sup, zones, _ = case_zones(case, at)
    z1, z2 = sup.z_m
    rj, re = case.crankshaft.journal_radius_mm * 1e-3, case.crankshaft.eccentric_radius_mm * 1e-3
    # the beam is supported at 0 and its span: shift the layout by the first support
    shifted = tuple(dataclasses.replace(zn, z0_m=zn.z0_m - z1, z1_m=zn.z1_m - z1) for zn in zones)

    def radius(z):
        r = np.full(np.shape(z), rj)
        for zn in shifted:
            r[(z >= zn.z0_m) & (z <= zn.z1_m)] = re
        return r
    return stepped_beam_flexibility(z2 - z1, shifted, radius, case.material.youngs_modulus_GPa * 1e9,
                                    case.material.poisson_ratio, support_half_width_m=0.0 if pinned else sup.band_m)


def crank_flexibility(case, edge_length_m: float | None = None, *, mesh3: Mesh3D | None = None) -> CrankFlexibility:
    """FE flexibility of the case's crankshaft. mesh3: a tet mesh of geometry.solids.crankshaft_solid
    (the mesh stage's crankshaft_mesh.npz, fem.mesh.load_mesh3d), else meshed here (fem.shaft)."""
    h = edge_length_m or default_edge_length_m(case)
    m3 = mesh3 if mesh3 is not None else crankshaft_mesh(case, h)
    sup, zones, _ = case_zones(case)
    return fe_flexibility(m3, sup, zones, case.material.youngs_modulus_GPa * 1e9,
                          case.material.poisson_ratio, h)


# ----------------------------------------------------------------------------- output mapping
def crank_forces_per_torque(case, crank_angle_rad: float = 0.0) -> np.ndarray:
    """(n_crank, 4) forces ON the eccentrics (disc 1 on eccentric 1: x, y; disc 2 on eccentric 2),
    crank frame, per N m of output torque; each disc carries half (fem.disc_body.load_pattern)."""
    from fem.disc_body import load_pattern
    c = case.cycloid
    out = np.zeros((case.carrier.crank_count, 4))
    for k in range(2):
        pat = load_pattern(case, 0.5, crank_angle_rad, index=k)
        # body frame of disc k -> ground (turned by -psi/zc) -> crank frame (turned by psi)
        a = -crank_angle_rad / c.zc - crank_angle_rad
        rot = np.array([[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]])
        out[:, 2 * k:2 * k + 2] = -(pat.hole_force_N @ rot.T)
    return out


def output_compliance(case, flex: CrankFlexibility, crank_angle_rad: float = 0.0) -> dict:
    """Output torsional compliance of crank bending [rad/(N m)] and its split, vs one lateral spring."""
    f = crank_forces_per_torque(case, crank_angle_rad)
    Cf = flex.matrix[:4, :4]
    c_true = float(sum(fj @ Cf @ fj for fj in f))
    # the lumped model: one spring 1/C11 per crank carrying the sum of both discs' forces
    c_one = float(sum(flex.entry("F1x", "F1x") * np.sum((fj[:2] + fj[2:]) ** 2) for fj in f))
    anti = 0.5 * (f[:, :2] - f[:, 2:])     # opposite part (pin resultants), per crank
    par = 0.5 * (f[:, :2] + f[:, 2:])      # same-direction part (tangential)
    # 2x2 blocks, not the x entries alone: the shaft is not isotropic (the eccentrics' lens-shaped
    # overlap is narrower along the offset: y bending ~10 % stiffer on the RV-40E); with the two
    # eccentrics' blocks averaged the split is exact to their ~0.1 % difference
    A = 0.5 * (Cf[:2, :2] + Cf[2:, 2:])
    B = 0.5 * (Cf[:2, 2:] + Cf[2:, :2].T)
    B = 0.5 * (B + B.T)
    return {"compliance_rad_per_Nm": c_true,
            "stiffness_Nm_per_arcmin": 1.0 / (c_true * ARCMIN_PER_RAD),
            "opposite_part_rad_per_Nm": float(2 * np.einsum("ji,ik,jk->", anti, A - B, anti)),
            "parallel_part_rad_per_Nm": float(2 * np.einsum("ji,ik,jk->", par, A + B, par)),
            "one_spring_compliance_rad_per_Nm": c_one,
            "one_spring_stiffness_Nm_per_arcmin": 1.0 / (c_one * ARCMIN_PER_RAD),
            "force_opposite_N_per_Nm": float(np.linalg.norm(anti[0])),
            "force_parallel_N_per_Nm": float(np.linalg.norm(par[0]))}


def summary(case, flex: CrankFlexibility, beam: CrankFlexibility | None = None,
            support_compliance_m_per_N: float | None = None) -> dict:
    """Figures for a report: tilt (opposite) and parallel compliances per N, their ratio to the single
    load (what one lateral spring uses), the stepped beam's figures, and the output stiffness of
    crank bending, shaft alone and on the support bearings (default: the case's tapered roller pair,
    fem.tapered_roller, tangent at the rated torque's load)."""
    beam = beam or beam_flexibility(case)
    single = flex.single_compliance_m_per_N()
    if support_compliance_m_per_N is None:
        from fem.tapered_roller import case_support_bearings, crank_support_load_N
        top = crank_support_load_N(case, case.rated_torque_Nm)["radial_N"] * 2
        support_compliance_m_per_N = 1.0 / case_support_bearings(case, top, points=3)["stiffness_N_per_m"]
    sup = with_elastic_supports(flex, support_compliance_m_per_N)
    out = {"single_m_per_N": single, "opposite": flex.opposite("x"), "parallel": flex.parallel("x"),
           "opposite_y": flex.opposite("y"), "parallel_y": flex.parallel("y")}
    out["opposite_over_single"] = out["opposite"]["deflection_1_m_per_N"] / single
    out["parallel_over_single"] = out["parallel"]["deflection_1_m_per_N"] / single
    for mode in ("opposite", "parallel"):
        b = getattr(beam, mode)("x")
        out[f"beam_{mode}"] = b
        out[f"fe_over_beam_{mode}"] = out[mode]["deflection_1_m_per_N"] / b["deflection_1_m_per_N"]
        out[f"fe_over_beam_{mode}_slope"] = out[mode]["slope_1_rad_per_N"] / b["slope_1_rad_per_N"]
        out[f"with_bearings_{mode}"] = getattr(sup, mode)("x")
    out["output_shaft_alone"] = output_compliance(case, flex)
    out["output_with_support_bearings"] = output_compliance(case, sup)
    return out


# ----------------------------------------------------------------------------- stiffness.json entry
def two_eccentric_blocks(flex: CrankFlexibility) -> tuple[np.ndarray, np.ndarray]:
    """The lumped model's view (fem.stiffness.CrankBending): compliance (2, 2) of the eccentrics'
    lateral displacements under their lateral loads, x and y planes averaged (the section is round:
    they differ by the mesh only) and symmetrized; journal_force (2, 2) = force passed to journal s
    (J1 at z = 0, J2 at z = span) per N on eccentric i, the planes averaged."""
    M, P = flex.matrix, flex.journal_force
    C = 0.5 * (M[np.ix_([0, 2], [0, 2])] + M[np.ix_([1, 3], [1, 3])])
    J = 0.5 * (P[np.ix_([0, 2], [0, 2])] + P[np.ix_([1, 3], [1, 3])])
    return 0.5 * (C + C.T), J


def eccentric_slope_per_N(case, flex: CrankFlexibility) -> float:
    """Largest tilt of an eccentric per N of its own load under the real loading (both discs'
    crank-hole forces per unit output torque, crank_forces_per_torque, every crank, crank angle 0):
    |S_i| / |f_i| with S_i = C_SF f, the tilt vector (its full size: the needle edge load takes it in
    the load plane, an upper bound)."""
    f = crank_forces_per_torque(case)
    worst = 0.0
    for fj in f:
        s = flex.matrix[4:8, :4] @ fj
        for i in range(2):
            worst = max(worst, float(np.hypot(*s[2 * i:2 * i + 2]) / np.hypot(*fj[2 * i:2 * i + 2])))
    return worst


def case_crank_bending(case, *, mesh3: Mesh3D | None = None, edge_length_m: float | None = None) -> dict:
    """The FE flexibility of the case's crankshaft reduced to fem.stiffness.CrankBending, with its
    stepped-beam reference (same loads, supports spread over the seats) and the statics of the
    journal reactions (positive shares summing to 1 per eccentric)."""
    fe = crank_flexibility(case, edge_length_m, mesh3=mesh3)
    beam = beam_flexibility(case)
    C, J = two_eccentric_blocks(fe)
    Cb, Jb = two_eccentric_blocks(beam)
    M = fe.matrix
    xy = float(np.abs(M[np.ix_([0, 2], [1, 3])]).max() / np.abs(M[:4, :4]).max())
    check = {"fe_C_m_per_N": C.tolist(), "beam_C_m_per_N": Cb.tolist(),
             "fe_over_beam_C11": float(C[0, 0] / Cb[0, 0]), "fe_over_beam_C12": float(C[0, 1] / Cb[0, 1]),
             "fe_over_beam_opposite": float((C[0, 0] - C[0, 1]) / (Cb[0, 0] - Cb[0, 1])),
             "fe_over_beam_parallel": float((C[0, 0] + C[0, 1]) / (Cb[0, 0] + Cb[0, 1])),
             "x_over_y_C11": float(M[0, 0] / M[1, 1]), "xy_coupling": xy, "asymmetry": fe.asymmetry,
             "journal_force_fe": J.tolist(), "journal_force_statics": Jb.tolist(),
             "journal_force_sum": J.sum(axis=0).tolist(),
             "output_compliance": output_compliance(case, fe), "dofs": fe.dofs,
             "edge_length_m": fe.edge_length_m}
    return {"compliance_m_per_N": C, "journal_force": J, "flex": fe, "check": check,
            "source": ("3D FE (P2 tetrahedra on the mesh stage's crankshaft mesh, scikit-fem), both "
                       "eccentrics loaded independently, journals pinned at the support bearings' pressure "
                       "centres (X pair: R_m tan(alpha) inside the bearing centres) with the reaction spread "
                       "over a band of the seat there (fem.crank_tilt); x and y planes averaged")}
