"""Turning-arm (needle roller) bearing between eccentric and disc crank hole: radial compliance.

2D plane-strain FE (P1, scikit-fem) of one bearing section, times the needle length:
  eccentric (inner race): ring from a clamped core of half its radius out to r_e (the shaft core
      carries the load; its own bending is the crankshaft spring);
  needles: radius r_n on the pitch circle r_e + r_n, one mesh condensed once (centre as datum,
      rigid modes only held), rotated to each needle; the cage holds them tangentially, so each
      has one rigid DOF, its radial shift;
  disc bore ring: from the crank hole a = r_e + 2 r_n (zero clearance: the clearance is the
      dynamics stage's gap) out to the clamp radius b = a + t, t the thinnest ligament from a
      crank hole to a free edge of the disc (tooth root of the modified profile, centre hole,
      pillar holes, the next crank hole: `bore_ligament`): the ring of material the disc has
      on every side of the bore (RV-40E: t = 7 mm to the centre hole, b = 22 mm; RV-160N: 12 mm,
      b = 36 mm). The disc beyond it, with its real holes and edges, is fem.disc_body's, which
      takes out this same ring (a..b, clamped at b, `bore_ring_compliance`) so that the two add
      in series without double counting. (Before the issue-11 audit the clamp sat at 2a, beyond
      the material that exists: 15 mm of ring where the RV-40E has 7.)
The radial load F moves the eccentric core along +x (towards needle 0); contact on every needle
within +-LOAD_ZONE_DEG of the load line is solved exactly by the condensed active-set solver
(fem.contact.solve_rigid: frictionless, g >= 0, lambda >= 0, equilibrium of core and needles).
Needles beyond that zone are unloaded under a zero-clearance translation (their gap opens by
delta |cos psi|); the model reports the load on its outermost needles so this can be checked.
Deflection = the core's shift; it contains both Hertz contacts, the needle, race ovalisation of
the eccentric ring and of the bore ring. Limits: linear elastic, frictionless, no crowning or tilt
(uniform load along the needle), 2D section; the bore ring is plane strain like the contacts
(fem.disc_body's disc is plane stress, its ring's translation 1.22x this one's on the RV-40E,
`clamped_ring_bore_compliance`; the ring translation is ~2.5 % of the bearing's deflection).
References printed beside it (fem.hertz): Palmgren's needle approach at the FE's own most
loaded needle force, Stribeck's Q_max = 4.08 F/Z for the load sharing, and the exact bore-ring
translation (`clamped_ring_bore_compliance`, Michell's n = 1 thick-ring solution).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from fem import contact, elastic, hertz
from fem.mesh import annulus_mesh
from geometry.artifacts import InputError

LOAD_ZONE_DEG = 110.0     # needles modelled: |psi| <= this (loaded zone is +-90 deg at zero clearance)
LOAD_FRACTIONS = (0.05, 0.1, 0.2, 0.4, 0.7, 1.0)


@dataclass(frozen=True)
class NeedleBearingFE:
    load_N: np.ndarray               # (L,) radial loads
    deflection_m: np.ndarray         # (L,) eccentric-core shift along the load
    needle_angle_deg: np.ndarray     # (Z',) modelled needles, 0 = load direction
    needle_load_N: np.ndarray        # (L, Z') radial load of each modelled needle
    law_k_N_per_m_pow: float
    law_n: float
    mesh_size_m: float
    nodes: int
    palmgren_deflection_m: np.ndarray   # (L,) Palmgren at the FE's most loaded needle force
    stribeck_qmax_N: np.ndarray         # (L,) 4.08 F / Z
    meshes: tuple = field(repr=False, default=())


def needle_bearing_fe(radial_loads_N, *, eccentric_radius_m: float, needle_radius_m: float,
                      needle_count: int, needle_length_m: float, bore_clamp_radius_m: float, E_Pa: float,
                      nu: float, mesh_size_m: float | None = None) -> NeedleBearingFE:
    """Load-deflection of a needle bearing section (see module); one factorization per body.
    bore_clamp_radius_m: outer radius of the disc's bore ring (`bore_clamp_radius_m`)."""
    loads = np.asarray(radial_loads_N, float)
    re, rn, Z, L = eccentric_radius_m, needle_radius_m, int(needle_count), needle_length_m
    for name, v in (("eccentric radius", re), ("needle radius", rn), ("needle length", L)):
        if not (v > 0):
            raise InputError(f"needle bearing {name} = {v!r}: must be positive")
    if not (bore_clamp_radius_m > re + 2 * rn):
        raise InputError(f"needle bearing bore clamp radius = {bore_clamp_radius_m * 1e3:g} mm: must "
                         f"exceed the bore radius {(re + 2 * rn) * 1e3:g} mm")
    if Z < 4 or Z * 2 * rn > 2 * math.pi * (re + rn):
        raise InputError(f"needle bearing needle_count = {Z}: allowed 4..{int(math.pi * (re + rn) / rn)}")
    if loads.size == 0 or np.any(loads <= 0):
        raise InputError(f"needle bearing loads = {loads.tolist()}: must be positive")
    from fem.pin_contact import GROWTH, CircleBody
    a, rp = re + 2 * rn, re + rn
    Es = hertz.contact_modulus(E_Pa, nu)
    q_hi = 4.08 * loads.max() / Z * 1.3        # margin over Stribeck for the race compliance
    b_max = float(hertz.hertz_line(q_hi, L, hertz.effective_radius(rn, -a), Es)[1])
    h = mesh_size_m or b_max / 10
    if not (0 < h < b_max):
        raise InputError(f"mesh size = {h * 1e3:g} mm: must be below the largest Hertz half-width "
                         f"{b_max * 1e3:.3g} mm")
    window = 1.5 * b_max
    psi = 2 * np.pi * np.arange(Z) / Z
    psi = (psi + np.pi) % (2 * np.pi) - np.pi
    psi = np.sort(psi[np.abs(psi) <= math.radians(LOAD_ZONE_DEG) + 1e-9])
    h_ring = min(re / 8, 0.5e-3)
    ecc = annulus_mesh(re / 2, re, psi, h, h_ring, GROWTH, graded_side="outer")
    bore = annulus_mesh(a, bore_clamp_radius_m, psi, h, min(h_ring, (bore_clamp_radius_m - a) / 4), GROWTH,
                        graded_side="inner")
    needle = CircleBody.build(rn, h, rn / 4, E_Pa, nu, window, two_sided=True)

    def candidates(mesh, side, radius):
        nodes = mesh.boundary[side]
        th = np.arctan2(mesh.points[nodes, 1], mesh.points[nodes, 0])
        return [nodes[np.abs((th - p + np.pi) % (2 * np.pi) - np.pi) * radius <= window] for p in psi]

    inner, outer = candidates(ecc, "outer", re), candidates(bore, "inner", a)
    rows, blocks = [], []
    g0 = []
    for j, p in enumerate(psi):
        e_j = np.array([math.cos(p), math.sin(p)])
        c_j = rp * e_j
        block = []
        for side, mesh, nodes in (("in", ecc, inner[j]), ("out", bore, outer[j])):
            d = c_j - mesh.points[nodes]
            dist = np.hypot(d[:, 0], d[:, 1])
            n = d / dist[:, None]
            g0.append(dist - rn)
            block.append(n)
            rows.append((side, j, nodes, n))
        blocks.append(np.vstack(block))
    m = sum(len(r[2]) for r in rows)
    # condensed compliance: eccentric (inner rows), bore (outer rows), each needle (its rows)
    C = np.zeros((m, m))
    S = np.zeros((m, 1 + len(psi)))
    offs = np.cumsum([0] + [len(r[2]) for r in rows])
    for body, side in ((ecc, "in"), (bore, "out")):
        fixed_side = "inner" if side == "in" else "outer"
        K = elastic.stiffness(elastic.basis_2d(body), E_Pa, nu)
        fx = body.boundary[fixed_side]
        fac = elastic.Factorized.of(K, np.concatenate([2 * fx, 2 * fx + 1]))
        idx = np.concatenate([np.arange(offs[i], offs[i + 1]) for i, r in enumerate(rows) if r[0] == side])
        sel = [r for r in rows if r[0] == side]
        B = contact.node_operator(np.concatenate([r[2] for r in sel]), -np.vstack([r[3] for r in sel]),
                                  fac.n_dofs)
        C[np.ix_(idx, idx)] += fac.compliance(B)
    for j, p in enumerate(psi):
        idx = np.arange(offs[2 * j], offs[2 * j + 2])
        C[np.ix_(idx, idx)] += needle.compliance(blocks[j], p - math.pi / 2)
        e_j = np.array([math.cos(p), math.sin(p)])
        S[idx, 1 + j] = -blocks[j] @ e_j
        S[offs[2 * j]:offs[2 * j + 1], 0] = blocks[j][:offs[2 * j + 1] - offs[2 * j], 0]
    g0 = np.concatenate(g0)
    j0 = int(np.argmin(np.abs(psi)))
    start = [offs[2 * j0] + int(np.argmin(g0[offs[2 * j0]:offs[2 * j0 + 1]])),
             offs[2 * j0 + 1] + int(np.argmin(g0[offs[2 * j0 + 1]:offs[2 * j0 + 2]]))]
    defl, qn = np.zeros(len(loads)), np.zeros((len(loads), len(psi)))
    for il, F in enumerate(loads):
        f = np.zeros(1 + len(psi))
        f[0] = F / L
        lam, q, _ = contact.solve_rigid(C, g0, S, f, start)
        start = np.flatnonzero(lam > 0)          # warm start of the next (larger) load
        for i, r in enumerate(rows):
            if lam[offs[i]] > 0 or lam[offs[i + 1] - 1] > 0:
                raise InputError(f"needle bearing load {F:g} N: contact reaches the end of the candidate "
                                 f"zone at needle {math.degrees(psi[r[1]]):.0f} deg")
            if r[0] == "in":
                qn[il, r[1]] = -S[offs[i]:offs[i + 1], 1 + r[1]] @ lam[offs[i]:offs[i + 1]] * L
        defl[il] = q[0]
    k, n = hertz.fit_power_law(loads, defl)
    return NeedleBearingFE(loads, defl, np.degrees(psi), qn, k, n, h,
                           len(ecc.points) + len(bore.points) + len(needle.mesh.points),
                           hertz.palmgren_needle_approach(qn.max(axis=1), L), 4.08 * loads / Z,
                           (ecc, bore, needle.mesh))


def bore_ligament(case) -> tuple[float, str]:
    """Thinnest wall from a crank hole to a free edge of the disc [mm] and that edge's name: the
    tooth root of the modified profile (R + dR - E - Rr - dRr) or another hole (centre, pillar,
    crank; geometry.solids.disc_holes, the one home of the hole layout)."""
    from geometry.profile import profile_args
    from geometry.solids import disc_holes
    args = profile_args(case)
    root = args["R"] - case.cycloid.eccentricity_mm - args["Rr"]
    holes = disc_holes(case)
    best = (math.inf, "")
    for h in (h for h in holes if h.name.startswith("crank")):
        best = min(best, (root - math.hypot(h.x_mm, h.y_mm) - h.radius_mm, "tooth root"))
        for o in holes:
            if o is not h:
                best = min(best, (math.hypot(h.x_mm - o.x_mm, h.y_mm - o.y_mm) - h.radius_mm - o.radius_mm,
                                  f"{o.name.rstrip('0123456789')} hole"))
    return best


def bore_clamp_radius_m(case) -> float:
    """Outer radius of the bore ring the needle model carries: crank-hole radius + the thinnest
    ligament (`bore_ligament`); fem.disc_body takes out the same ring."""
    return (case.disc.crank_hole_radius_mm + bore_ligament(case)[0]) * 1e-3


def clamped_ring_bore_compliance(inner_radius_m: float, outer_radius_m: float, E_Pa: float, nu: float,
                                 thickness_m: float, *, plane_strain: bool = True) -> float:
    """Exact mean translation per N of the bore of a ring a..b clamped at b under a radial bore
    load of resultant F (any distribution symmetric about its line, e.g. the half-cosine) [m/N].
    By Betti only the load's first Fourier mode, q cos(theta) with q = F / (pi a w), works on a
    translation. The n = 1 Navier solution (u_r = U cos, u_theta = V sin; k = (lambda + 2 mu) / mu,
    lambda -> 2 lambda mu / (lambda + 2 mu) in plane stress) is
      U = (3 - k) A r^2 / 8 + (1 + k) B ln r / 2 + P / r^2 + T,
      V = (3 k - 1) A r^2 / 8 - (1 + k) B ln r / 2 + (1 - k) B / 2 + P / r^2 - T
    (dilatation (A r + B / r) cos), with U = V = 0 at b, sigma_rr = -q cos, sigma_rtheta = 0 at a;
    the bore's mean translation is (U(a) - V(a)) / 2."""
    a, b = inner_radius_m, outer_radius_m
    lam, mu = elastic.lame(E_Pa, nu)
    if not plane_strain:
        lam = 2 * lam * mu / (lam + 2 * mu)
    k = (lam + 2 * mu) / mu
    al, be, ga, ze = (3 - k) / 8, (3 * k - 1) / 8, (1 + k) / 2, (1 - k) / 2

    def uv(r):   # rows U, V, U', V' over the unknowns (A, B, P, T)
        return np.array([[al * r * r, ga * math.log(r), r ** -2, 1.0],
                         [be * r * r, -ga * math.log(r) + ze, r ** -2, -1.0],
                         [2 * al * r, ga / r, -2 * r ** -3, 0.0],
                         [2 * be * r, -ga / r, -2 * r ** -3, 0.0]])
    Ua, Ub = uv(a), uv(b)
    q = 1.0 / (math.pi * a * thickness_m)
    M = np.vstack([Ub[0], Ub[1],
                   lam * np.array([a, 1 / a, 0, 0]) + 2 * mu * Ua[2],     # sigma_rr(a) = -q
                   -Ua[0] / a + Ua[3] - Ua[1] / a])                      # sigma_rtheta(a) = 0
    c = np.linalg.solve(M, [0.0, 0.0, -q, 0.0])
    return float((Ua[0] - Ua[1]) @ c / 2)


def turning_arm_curve(case, max_load_N: float, *, mesh_size_m: float | None = None) -> dict:
    """The case's turning-arm bearing swept up to max_load_N (LOAD_FRACTIONS of it)."""
    k = case.crankshaft
    E, nu = case.material.youngs_modulus_GPa * 1e9, case.material.poisson_ratio
    loads = max_load_N * np.asarray(LOAD_FRACTIONS)
    b, (t_mm, edge) = bore_clamp_radius_m(case), bore_ligament(case)
    r = needle_bearing_fe(loads, eccentric_radius_m=k.eccentric_radius_mm * 1e-3,
                          needle_radius_m=k.needle_diameter_mm / 2 * 1e-3, needle_count=k.needle_count,
                          needle_length_m=k.needle_length_mm * 1e-3, bore_clamp_radius_m=b, E_Pa=E, nu=nu,
                          mesh_size_m=mesh_size_m)
    ring = max_load_N * clamped_ring_bore_compliance(case.disc.crank_hole_radius_mm * 1e-3, b, E, nu,
                                                     k.needle_length_mm * 1e-3)
    return {"load_N": r.load_N, "deflection_m": r.deflection_m, "law_k_N_per_m_pow": r.law_k_N_per_m_pow,
            "law_n": r.law_n, "lame_ring_deflection_at_max_m": ring, "bore_clamp_radius_m": b,
            "palmgren_deflection_m": r.palmgren_deflection_m, "fe_qmax_N": r.needle_load_N.max(axis=1),
            "stribeck_qmax_N": r.stribeck_qmax_N, "mesh_size_m": r.mesh_size_m, "result": r,
            "source": "2D plane-strain FE (P1, scikit-fem) of eccentric ring (core clamped at r_e/2) + "
                      f"caged needles + disc bore ring (clamped at {b * 1e3:g} mm: the bore plus the "
                      f"thinnest ligament, {t_mm:.3g} mm to the {edge}), zero clearance, condensed "
                      "frictionless contact (fem.contact.solve_rigid), times the needle length; "
                      "lame_ring: the bore ring's exact translation (Michell n = 1) at the largest load"}


def turning_arm_max_load(case, torque_Nm: float) -> float:
    """Radial load on one crank's needle bearing [N]: the disc torque shared by the cranks at the
    crank-circle radius, for one disc (0.55 T for two discs), load-sharing like the pins."""
    share = 0.55 if case.cycloid.disc_count == 2 else 1.0
    return share * torque_Nm / (case.carrier.crank_count * case.carrier.crank_circle_radius_mm * 1e-3)
