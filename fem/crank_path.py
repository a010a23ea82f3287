"""The crank path assembled as one FE model, beside the lumped model's composition of the same parts:
the check `crank_path_assembled_over_lumped` of stiffness.json (DESIGN.md, "The assembled reducer").

What the lumped model does (fem.stiffness.support_compliance_parts): each part condensed on its own
and added in series, u = [T^T C_car T + T^T T / k_b + C_bend] f, with
  C_bend  the crankshaft pinned at its support pair's pressure centres (fem.crank_tilt),
  T       the crank's statics (journal reactions, fem.stiffness.seat_transfer),
  k_b     one isotropic linear spring per bearing, the tangent of the preloaded pair at the rms
          operating load (fem.tapered_roller.case_support_bearings),
  C_car   the seats' translations only, each reaction at the seat centre (fem.carrier).
What this module does instead: one elastic system of the carrier and the nc crankshafts joined by
every roller of every support bearing, under the discs' forces at rated torque:
  carrier   the 3D P2 FE of fem.carrier (same mesh family, its coarse level), every seat a rigid ring
            (the press-fitted cup), condensed to all 6 DOFs of each ring (tilts and axial included);
  crank     the 3D P2 FE of the mesh stage's crankshaft (fem.shaft), each journal's surface a rigid
            ring (the press-fitted cone), condensed exactly to those 12 ring DOFs plus the two
            eccentric loads of fem.crank_tilt (uniform traction, torque taken out); one crank is
            three copies of this superelement on the crank circle (static condensation of a linear
            body is exact: the assembly equals the unreduced FE model);
  bearings  every roller, ISO/TS 16281 slice by slice (fem.tapered_roller's geometry and Palmgren
            law, nonlinear, unilateral), between the cone ring and the cup ring at the roller's
            real position: the pressure centre, the tilt stiffness and the cup's offset moment come
            out of the geometry; the fixed-position preload set so that each bearing carries the
            stated axial force at zero load in the assembled, elastic state;
  needles   the turning-arm law of stiffness.json in series (same forces in both models: it adds
            the same approach to both).
Loads: each disc's crank-hole forces per unit output torque (fem.crank_tilt.crank_forces_per_torque,
crank angle 0) times the rated torque; the carrier's mounting face clamped (as fem.carrier).
Output rotation: the work-conjugate phi = sum_j f_j . u_j / T (f_j the forces per N m, u_j the
disc-hole centre displacements), the same reading for both models.
Limits: the crank's spin about its own axis carries no load here (the zone loads are torque-free,
the crank torsion spring is the lumped model's crank_torsion) and is held at one journal; the
crank's rotation with the carrier about the output axis is the carrier's, not in this path; joints,
main bearings and the jointed carrier are not in either side (they enter both in the same way, as
matrices added to the carrier's).
"""
from __future__ import annotations

import math
import time

import numpy as np
import scipy.sparse as sp

from fem import carrier as fe_carrier
from fem import crank_tilt, shaft, tapered_roller
from fem.mesh import cylinder_band_facets
from fem.sparse_fe import spd_solve
from fem.stiffness import seat_transfer
from geometry.artifacts import InputError

ARCMIN_PER_RAD = fe_carrier.ARCMIN_PER_RAD
TOLERANCE = 0.10                               # the issue's: output rotation within 10 %


def _journal_ring_dofs(basis, mesh_sk, radius_m: float, z0_m: float, z1_m: float, h: float) -> np.ndarray:
    """DOFs of the boundary facets whose vertices all lie on the journal cylinder within [z0, z1]."""
    facets = cylinder_band_facets(mesh_sk, 0.0, 0.0, radius_m, z0_m, z1_m, max(0.03 * radius_m, 0.05 * h), 0.02 * h)
    d = basis.get_dofs(facets).all()
    if len(d) < 9:
        raise InputError(f"crankshaft journal z = {z0_m * 1e3:g}..{z1_m * 1e3:g} mm: no meshed surface on "
                         f"radius {radius_m * 1e3:g} mm (mesh stage's crankshaft mesh)")
    return d


def crank_superelement(case, mesh3, E_Pa: float, nu: float) -> dict:
    """The crankshaft condensed to its two journal rings (6 DOFs each about the journal centre,
    crank frame) and the two eccentrics' lateral loads (fem.crank_tilt labels F1x F1y F2x F2y):
    K_ring (12, 12) with the crank's six rigid modes in its null space, G (4, 12) and H (4, 4) with
    ring loads K_ring q + G^T f = bearing forces and eccentric displacements g = H f - G q."""
    from geometry.solids import crankshaft_layout
    lay = crankshaft_layout(case)
    basis, K = shaft.p2_stiffness(mesh3, E_Pa, nu)
    msk = basis.mesh
    h = float(np.median(np.linalg.norm(mesh3.points[mesh3.tetrahedra[:, 0]] - mesh3.points[mesh3.tetrahedra[:, 1]], axis=1)))
    comp = fe_carrier._dof_components(basis)
    rj = lay.journal_radius_mm * 1e-3
    rings = [(_journal_ring_dofs(basis, msk, rj, a * 1e-3, b * 1e-3, h), np.array([0.0, 0.0, 0.5e-3 * (a + b)]))
             for a, b in lay.journals_mm]
    T, keep = fe_carrier._ring_transform(basis, comp, rings, np.array([], int))
    Kq = (T.T @ K @ T).tocsr()
    _, zones, _ = crank_tilt.case_zones(case)
    loads = [crank_tilt._zone_loads(basis, z) for z in zones]
    Fq = T.T @ np.column_stack([loads[0][0], loads[0][1], loads[1][0], loads[1][1]])
    ni = len(keep)
    if np.abs(Fq[ni:]).max() > 1e-12 * np.abs(Fq).max():
        raise RuntimeError("an eccentric's load zone reaches a journal ring: check the crankshaft layout")
    Kir = Kq[:ni, ni:].toarray()
    X = spd_solve(Kq[:ni, :ni], np.hstack([Kir, Fq[:ni]]))
    K_ring = Kq[ni:, ni:].toarray() - Kir.T @ X[:, :12]
    G = (Kir.T @ X[:, 12:]).T
    H = Fq[:ni].T @ X[:, 12:]
    return {"K": 0.5 * (K_ring + K_ring.T), "G": G, "H": 0.5 * (H + H.T), "dofs": int(K.shape[0]),
            "ring_centres_m": [c for _, c in rings]}


def carrier_rings(case, level: float) -> tuple[object, np.ndarray, float]:
    """The carrier's (6 nr, 6 nr) seat-ring flexibility on the mesh of size `level` pillar radii
    (rings: crank j, seat (flange, end plate); per ring tx ty tz rx ry rz about the seat centre),
    its geometry and h."""
    g = fe_carrier.case_geometry(case)
    h = level * g.pillar_radius_mm * 1e-3
    C6 = fe_carrier.carrier_compliance(g, case.material.youngs_modulus_GPa * 1e9, case.material.poisson_ratio,
                                       edge_length_m=h, every_ring_dof=True)
    return g, C6, h


def _rollers(setup: tapered_roller.PairSetup):
    """Per bearing b (0: J1 at z = 0, 1: J2 at z = span, crank frame): contact points p (n, 3) of
    every roller slice and their normals (unit, pointing from the cup towards the cone: the
    approach is n . (u_cone - u_cup) + d0), from fem.tapered_roller's geometry."""
    a, psi, s, sense, lam, d0, cs = tapered_roller._geometry(setup)
    ca, sa = math.cos(a), math.sin(a)
    R = setup.bearing.pitch_diameter_mm * 0.5e-3
    out = []
    for b, zb in enumerate((0.0, setup.spacing_m)):
        P, N = [], []
        for p_ in psi:
            c, si = math.cos(p_), math.sin(p_)
            t = np.array([-sense[b] * sa * c, -sense[b] * sa * si, ca])
            n = np.array([ca * c, ca * si, sense[b] * sa])
            for sm in s * 1e-3:
                P.append(np.array([R * c, R * si, zb]) + sm * t)
                N.append(n)
        out.append((np.array(P), np.array(N)))
    return out, d0 * 1e-3, cs * 1e3 ** tapered_roller.EXP     # d0 [m], slice constant [N/m^(10/9)]


def _ring_rows(P: np.ndarray, N: np.ndarray, centre: np.ndarray) -> np.ndarray:
    """(n, 6) rows mapping a ring's (t, theta) to n . u at P: [n, (P - c) x n]."""
    return np.hstack([N, np.cross(P - centre, N)])


class AssembledCrankPath:
    """The nonlinear system q -> R(q) = K q + g_ext + sum_k Q_k(B_k q + d0) B_k^T (module doc)."""

    def __init__(self, crank: dict, C6: np.ndarray, g, setup: tapered_roller.PairSetup):
        nc = g.crank_count
        self.nc, self.setup = nc, setup
        span = setup.spacing_m
        zs = np.array(g.seat_z_mm) * 1e-3                        # (flange, end plate)
        dz = zs[1]                                              # crank frame z = 0 (J1) at the end plate's seat
        if abs((zs[0] - zs[1]) - span) > 1e-6:
            raise InputError(f"carrier seats {zs * 1e3} mm apart {abs(zs[0] - zs[1]) * 1e3:g} mm, the crank's "
                             f"support span {span * 1e3:g} mm: the seats must face the journals")
        n_car = 12 * nc
        self.n = n_car + 12 * nc
        K = np.zeros((self.n, self.n))
        K[:n_car, :n_car] = np.linalg.inv(C6)
        rollers, self.d0_base, self.cs = _rollers(setup)
        rows, self.crank_dofs = [], []
        for j in range(nc):
            off = np.array([*g.crank_xy_mm(j), 0.0]) * 1e-3 + np.array([0, 0, dz])
            cd = n_car + 12 * j + np.arange(12)
            self.crank_dofs.append(cd)
            K[np.ix_(cd, cd)] = crank["K"]
            for b, (P, N) in enumerate(rollers):
                ring_car = 2 * j + (1 if b == 0 else 0)          # J1 -> end-plate seat, J2 -> flange seat
                Pc = P + off
                B = np.zeros((len(P), self.n))
                B[:, cd[6 * b:6 * b + 6]] = _ring_rows(Pc, N, crank["ring_centres_m"][b] + off)
                B[:, 6 * ring_car:6 * ring_car + 6] = -_ring_rows(Pc, N, np.array([*g.crank_xy_mm(j), g.seat_z_mm[ring_car % 2]]) * 1e-3)
                rows.append(B)
        self.B = sp.csr_matrix(np.vstack(rows))
        self.bearing_of_row = np.repeat(np.arange(2 * nc), [len(r[0]) for r in rollers] * nc)
        # the cranks' spin about their own axes carries no load: held at journal J1 (DOF rz of ring 0)
        self.free = np.setdiff1d(np.arange(self.n), [cd[5] for cd in self.crank_dofs])
        self.K, self.crank = 0.5 * (K + K.T), crank
        self.k_max = float(np.abs(self.K).max())
        self.sin_a = math.sin(setup.bearing.alpha_rad)

    def _external(self, f: np.ndarray) -> np.ndarray:
        """g_ext from the eccentric forces f (nc, 4)."""
        out = np.zeros(self.n)
        for j, cd in enumerate(self.crank_dofs):
            out[cd] = self.crank["G"].T @ f[j]
        return out

    def solve(self, f: np.ndarray, d0: float, q0=None) -> tuple[np.ndarray, np.ndarray]:
        """Equilibrium (Newton, step halving on the residual) -> (q, roller slice loads)."""
        fr, q = self.free, np.zeros(self.n) if q0 is None else q0.copy()
        ext = self._external(f)
        scale = max(np.abs(ext).max(), self.setup.preload_N, 1.0)

        def residual(q):
            d = self.B @ q + d0
            dp = np.maximum(d, 0.0)
            Q = self.cs * dp ** tapered_roller.EXP
            return self.K @ q + ext + self.B.T @ Q, Q, self.cs * tapered_roller.EXP * dp ** (tapered_roller.EXP - 1)

        for _ in range(100):
            R, Q, kq = residual(q)
            r0 = np.linalg.norm(R[fr])
            floor = 1e3 * np.finfo(float).eps * self.k_max * np.abs(q).max()   # round-off of K q (rigid limits)
            if r0 < 1e-10 * scale + floor:
                return q, Q
            J = self.K + (self.B.T @ sp.diags(kq) @ self.B).toarray()
            dq = np.zeros(self.n)
            dq[fr] = -np.linalg.solve(J[np.ix_(fr, fr)], R[fr])
            t = 1.0
            while t > 1e-8 and np.linalg.norm(residual(q + t * dq)[0][fr]) >= r0:
                t *= 0.5
            q = q + t * dq
        raise InputError(f"assembled crank path: no equilibrium (residual {r0:.3g} N): loads beyond the "
                         f"support bearings' reach?")

    def axial_forces_N(self, Q: np.ndarray) -> np.ndarray:
        """Axial force carried by each bearing (2 nc)."""
        return np.bincount(self.bearing_of_row, Q * self.sin_a, minlength=2 * self.nc)

    def preloaded_d0(self) -> tuple[float, np.ndarray]:
        """The rollers' interference that leaves each bearing the stated preload at zero load in the
        elastic assembly (secant on d0; the crank and carrier relieve part of a rigid setting's)."""
        zero = np.zeros((self.nc, 4))
        target = self.setup.preload_N
        d_a = self.d0_base
        f_a = self.axial_forces_N(self.solve(zero, d_a)[1]).mean() - target
        d_b = 1.2 * d_a
        f_b = self.axial_forces_N(self.solve(zero, d_b)[1]).mean() - target
        for _ in range(30):
            if abs(f_b) < 1e-7 * target:
                break
            d_a, d_b, f_a = d_b, d_b - f_b * (d_b - d_a) / (f_b - f_a), f_b
            f_b = self.axial_forces_N(self.solve(zero, d_b)[1]).mean() - target
        return d_b, self.axial_forces_N(self.solve(zero, d_b)[1])

    def eccentric_displacements(self, q: np.ndarray, f: np.ndarray) -> np.ndarray:
        """(nc, 4) lateral displacements of the eccentric axes (conjugate to f)."""
        return np.array([self.crank["H"] @ f[j] - self.crank["G"] @ q[cd] for j, cd in enumerate(self.crank_dofs)])


def needle_approach_m(model, f: np.ndarray) -> np.ndarray:
    """(nc, 4) the needle bearings' approach along each eccentric's force (turning-arm law)."""
    out = np.zeros_like(f)
    k, n = model.turning_arm.law_k_N_per_m_pow, model.turning_arm.law_n
    for i in range(2):
        F = f[:, 2 * i:2 * i + 2]
        mag = np.linalg.norm(F, axis=1)
        out[:, 2 * i:2 * i + 2] = np.where(mag[:, None] > 0, (mag[:, None] / k) ** (1 / n) * F / np.maximum(mag, 1e-30)[:, None], 0.0)
    return out


def lumped_compliance(model, C_xy: np.ndarray, n_crank: int) -> dict:
    """The lumped composition of the same parts (fem.components' support_part), the carrier's seat
    translations taken from the same FE matrix as the assembly."""
    import dataclasses as dc

    from fem.components import by_name
    from fem.components.entries import CarrierSeats
    m = dc.replace(model, carrier=CarrierSeats(C_xy))
    T = seat_transfer(m, n_crank)
    return {name: by_name(name).support_part(m, T, n_crank) for name in ("carrier", "support_bearings", "crank_bending")}


NAME = "crank_path"
COST = 45     # rough seconds of `prepare` (the FE stage's pool takes the longest first)


def prepare(case, ctx: dict) -> dict:
    """The FE part (a pure task: picklable in and out, run in the FE stage's pool beside the
    components): the crank superelement on the mesh stage's mesh and the carrier's seat rings on the
    coarse level of the carrier's levels (ctx: fem.reduce.task_context)."""
    t0 = time.perf_counter()
    E, nu = case.material.youngs_modulus_GPa * 1e9, case.material.poisson_ratio
    h_crank = ctx.get("crank_edge_m") or shaft.default_edge_length_m(case)
    m3 = ctx["crank_mesh"] if ctx.get("crank_mesh") is not None else shaft.crankshaft_mesh(case, h_crank)
    crank = crank_superelement(case, m3, E, nu)
    g, C6, h = carrier_rings(case, (ctx.get("carrier_levels") or fe_carrier.DEFAULT_LEVELS)[0])
    return {"crank": crank, "geometry": g, "carrier_rings": C6, "carrier_edge_length_m": h,
            "seconds": time.perf_counter() - t0}


def check(case, model, prepared: dict) -> dict:
    """`crank_path_assembled_over_lumped` and what lies behind it (module doc), at rated torque."""
    crank, g, C6, h = (prepared[k] for k in ("crank", "geometry", "carrier_rings", "carrier_edge_length_m"))
    nc = g.crank_count
    setup = tapered_roller.case_support_setup(case)
    asm = AssembledCrankPath(crank, C6, g, setup)
    d0, pre = asm.preloaded_d0()
    torque = case.rated_torque_Nm
    f_unit = crank_tilt.crank_forces_per_torque(case)
    f = torque * f_unit
    q, Q = asm.solve(f, d0)
    u_fe = asm.eccentric_displacements(q, f)
    needle = needle_approach_m(model, f)
    ring = np.concatenate([[6 * r, 6 * r + 1] for r in range(2 * nc)])
    parts = lumped_compliance(model, C6[np.ix_(ring, ring)], nc)
    u_l = sum(parts.values()) @ f.ravel()
    phi_fe = float(f_unit.ravel() @ (u_fe + needle).ravel())
    phi_l = float(f_unit.ravel() @ (u_l + needle.ravel()))
    phi_fe_path, phi_l_path = float(f_unit.ravel() @ u_fe.ravel()), float(f_unit.ravel() @ u_l)
    # equilibrium: the bearings pass the eccentric forces to the carrier (force sum, carrier frame)
    on_cone = -(asm.B.T @ Q)
    force_sum = sum(on_cone[cd[[0, 1, 6, 7]]].reshape(2, 2).sum(0) for cd in asm.crank_dofs)
    applied = np.array([f[:, 0].sum() + f[:, 2].sum(), f[:, 1].sum() + f[:, 3].sum()])
    eq = float(np.linalg.norm(force_sum + applied) / max(np.linalg.norm(f), 1.0))
    return {
        "crank_path_assembled_over_lumped": phi_fe / phi_l,
        "without_needles": phi_fe_path / phi_l_path,
        "tolerance": TOLERANCE, "within_tolerance": bool(abs(phi_fe / phi_l - 1) <= TOLERANCE),
        "torque_Nm": float(torque),
        "assembled_rad": phi_fe, "lumped_rad": phi_l,
        "assembled_Nm_per_arcmin": torque / (phi_fe * ARCMIN_PER_RAD),
        "lumped_Nm_per_arcmin": torque / (phi_l * ARCMIN_PER_RAD),
        "lumped_parts_rad": {k: float(f_unit.ravel() @ (v @ f.ravel())) for k, v in parts.items()},
        "needles_rad": float(f_unit.ravel() @ needle.ravel()),
        "preload_N": float(setup.preload_N), "preload_reached_N": pre.tolist(),
        "roller_interference_rigid_setting_m": float(asm.d0_base), "roller_interference_m": float(d0),
        "max_slice_load_N": float(Q.max()), "unloaded_slices_share": float(np.mean(Q <= 0)),
        "force_balance_residual": eq,   # ~1e-3: fem.crank_tilt's torque-free traction on the faceted eccentric
        "carrier_edge_length_m": h, "crank_dofs": crank["dofs"],
    }
