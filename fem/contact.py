"""Condensed frictionless contact between a circular body (pin, roller) and a meshed counter-body.

Formulation (no penalty): candidate contact nodes x_i on the counter-body (disc profile, flat,
counter-cylinder), the normal n_i pointing from x_i to the circle's centre c, the initial gap
g0_i = |x_i - c| - R. A contact force lambda_i >= 0 pushes the circle along +n_i (at the
projection of x_i on its surface, shared linearly by the two nearest surface nodes) and the
counter-body along -n_i. With unit loads on every candidate, one factorization per body gives
the condensed compliance C = sum over bodies of B K^-1 B^T (m x m), and the gap after loading is
    g = g0 - delta s + C lambda,     s_i = n_i . m,
where delta is the rigid approach of the circle's support (its back half, clamped to a rigid
seat) along -m, m the nominal contact normal. Force control adds sum_i s_i lambda_i = F.
The exact complementarity g >= 0, lambda >= 0, g . lambda = 0 is solved by a primal-dual active
set on the small dense system (m ~ 100): each load level costs a few m x m solves.

Results are per metre of thickness (plane strain); `ContactResult` scales them to the face width.
Pressure at node i is lambda_i over its tributary boundary length (exact for a linear pressure
between nodes); the peak is recovered from a quadratic fit of p^2 (see `recovered_peak`); the half-width comes from the contact edges, each placed where p^2 (linear in the
distance near a smooth contact edge, p ~ sqrt(b - x)) extrapolates to zero from the two outermost
loaded nodes, bounded by the first node out of contact.
Limits: small displacements and rotations, linear elastic bodies, frictionless.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from geometry.artifacts import InputError


class ContactError(InputError):
    """A contact problem without a solution on the given input (no candidate can touch...)."""


@dataclass(frozen=True)
class ContactSetup:
    """Everything a load level needs: the condensed compliance and the geometry of the gap."""
    compliance_m_per_N: np.ndarray   # (m, m), per metre of thickness: [m / (N/m)]
    gap0_m: np.ndarray               # (m,)
    direction: np.ndarray            # s_i = n_i . m
    coord_m: np.ndarray              # (m,) arc coordinate of each candidate along the surface
    tributary_m: np.ndarray          # (m,) boundary length each candidate node carries
    nodes: np.ndarray                # counter-body node indices of the candidates


@dataclass(frozen=True)
class ContactResult:
    force_N: float
    approach_m: float
    peak_pressure_Pa: float
    half_width_m: float
    nodal_force_N: np.ndarray        # (m,) contact forces on the candidates
    pressure_Pa: np.ndarray          # (m,)
    active: np.ndarray               # (m,) bool
    iterations: int
    raw_peak_pressure_Pa: float      # largest nodal pressure (noisier than the recovered peak)


def circle_projection_operator(n_global: np.ndarray, surface_nodes: np.ndarray,
                               surface_points: np.ndarray, centre: np.ndarray, n_dofs: int,
                               rotation_rad: float = 0.0) -> sp.csr_matrix:
    """Rows i: unit load along n_i at the circle's surface point c - R n_i, shared linearly
    between the two surface nodes bracketing its angle. surface_points are the circle body's
    mesh points of surface_nodes in its own frame (centred at the origin), and rotation_rad
    turns that frame into the global one."""
    c, s = np.cos(rotation_rad), np.sin(rotation_rad)
    to_local = np.array([[c, s], [-s, c]])           # global -> local
    n_loc = n_global @ to_local.T
    ang_nodes = np.arctan2(surface_points[:, 1], surface_points[:, 0])
    order = np.argsort(ang_nodes)
    a_sorted = ang_nodes[order]
    a_q = np.arctan2(-n_loc[:, 1], -n_loc[:, 0])    # surface point is at -n from the centre
    k = np.searchsorted(a_sorted, a_q) % len(a_sorted)
    k0 = (k - 1) % len(a_sorted)
    span = (a_sorted[k] - a_sorted[k0]) % (2 * np.pi)
    w1 = np.where(span > 0, ((a_q - a_sorted[k0]) % (2 * np.pi)) / np.where(span > 0, span, 1), 0.0)
    rows, cols, vals = [], [], []
    for node_pos, w in ((k0, 1 - w1), (k, w1)):
        node = surface_nodes[order[node_pos]]
        for comp in (0, 1):
            rows.append(np.arange(len(n_loc)))
            cols.append(2 * node + comp)
            vals.append(w * n_loc[:, comp])
    return sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                         shape=(len(n_loc), n_dofs))


def node_operator(nodes: np.ndarray, directions: np.ndarray, n_dofs: int) -> sp.csr_matrix:
    """Rows i: unit load along directions[i] at node nodes[i] (2D interleaved DOFs)."""
    m = len(nodes)
    rows = np.repeat(np.arange(m), 2)
    cols = np.column_stack([2 * nodes, 2 * nodes + 1]).ravel()
    return sp.csr_matrix((np.asarray(directions, float).ravel(), (rows, cols)), shape=(m, n_dofs))


def tributary_lengths(points: np.ndarray) -> np.ndarray:
    """Half the lengths of the two boundary segments at each point of an ordered polyline."""
    seg = np.hypot(*np.diff(points, axis=0).T)
    return 0.5 * (np.concatenate([[seg[0]], seg]) + np.concatenate([seg, [seg[-1]]]))


def solve_force(setup: ContactSetup, force_per_m: float, *, max_iter: int = 500, active0=None) -> tuple:
    """Active-set solution of the force-controlled LCP; returns (lambda [N/m], delta [m], its).
    active0: rows to start from (the previous load level's contact: the solution is unique, a
    good start only saves iterations); default the first candidate to touch."""
    if force_per_m <= 0:
        raise ContactError(f"contact load = {force_per_m:g} N/m: must be positive")
    s = setup.direction
    if np.all(s <= 0):
        raise ContactError("no candidate node faces the load direction")
    if active0 is None or not len(active0):
        active0 = [int(np.argmin(np.where(s > 0, setup.gap0_m, np.inf)))]
    lam, q, its = solve_rigid(setup.compliance_m_per_N, setup.gap0_m, s[:, None],
                              np.array([force_per_m]), active0, max_iter=max_iter)
    return lam, float(q[0]), its


def solve_rigid(C: np.ndarray, g0: np.ndarray, S: np.ndarray, f: np.ndarray, active0,
                *, max_iter: int = 500) -> tuple:
    """Frictionless contact with r rigid-body DOFs q (a pin's approach, an eccentric's shift,
    caged needles' radial shifts): find lambda >= 0 (m,) and q (r,) with
        g = g0 - S q + C lambda >= 0,   g . lambda = 0,   S^T lambda = f (equilibrium of each DOF).
    Primal-dual active set from the rows active0. A DOF with no load and no active row (a needle
    out of the load zone) is free: it is centred between its nearest constraints, zero force.
    Returns (lambda, q, iterations)."""
    m, r = S.shape
    f = np.asarray(f, float)
    active = np.zeros(m, bool)
    active[np.asarray(active0, int)] = True
    touches = S != 0
    tol = 1e-14 + 1e-9 * float(np.max(np.abs(g0)))
    lam, q = np.zeros(m), np.zeros(r)
    seen = set()
    for it in range(1, max_iter + 1):
        A = np.flatnonzero(active)
        used = touches[A].any(axis=0)
        if np.any(~used & (f != 0)):   # a loaded DOF needs a contact: take its closest row
            j = int(np.flatnonzero(~used & (f != 0))[0])
            rows = np.flatnonzero(touches[:, j] & ~active)
            active[rows[np.argmin((g0 - S @ q + C @ lam)[rows])]] = True
            continue
        k = np.flatnonzero(used)
        nA = len(A)
        M = np.zeros((nA + len(k), nA + len(k)))
        M[:nA, :nA] = C[np.ix_(A, A)]
        M[:nA, nA:] = -S[np.ix_(A, k)]
        M[nA:, :nA] = S[np.ix_(A, k)].T
        sol = np.linalg.solve(M, np.concatenate([-g0[A], f[k]]))
        lam = np.zeros(m)
        lam[A] = sol[:nA]
        q = np.zeros(r)
        q[k] = sol[nA:]
        base = g0 + C @ lam
        for j in np.flatnonzero(~used):       # free DOFs: midway between their two sides
            rows = np.flatnonzero(touches[:, j])
            part = base[rows] - S[rows] @ q
            sj = S[rows, j]
            hi = (part[sj > 0] / sj[sj > 0]).min() if np.any(sj > 0) else None
            lo = (part[sj < 0] / sj[sj < 0]).max() if np.any(sj < 0) else None
            q[j] = 0.5 * (hi + lo) if hi is not None and lo is not None else (hi if lo is None else lo)
        gap = base - S @ q
        neg = A[lam[A] < 0]
        pen = np.flatnonzero(~active & (gap < -tol))
        if not len(neg) and not len(pen):
            return lam, q, it
        key = active.tobytes()
        if key in seen:            # a cycle of the block update: fall back to one change per step
            if len(neg):
                active[A[np.argmin(lam[A])]] = False
            else:
                active[pen[np.argmin(gap[pen])]] = True
            continue
        seen.add(key)
        active[neg] = False
        active[pen] = True
        if not active.any():
            active[np.argmin(gap)] = True
    raise ContactError(f"contact active set did not converge in {max_iter} iterations "
                       f"(loads {f.tolist()}): enlarge the candidate zone or refine the mesh")


def half_width(coord: np.ndarray, pressure: np.ndarray, active: np.ndarray) -> float:
    """Half the distance between the two contact edges (p^2 extrapolated to zero, see module)."""
    idx = np.flatnonzero(active & (pressure > 0))
    if len(idx) == 0:
        return 0.0
    edges = []
    for side in (-1, 1):
        i_last = idx[0] if side < 0 else idx[-1]
        i_prev = i_last - side
        i_out = i_last + side
        x_out = coord[i_out] if 0 <= i_out < len(coord) else coord[i_last]
        if len(idx) >= 2 and 0 <= i_prev < len(coord) and pressure[i_prev] > pressure[i_last]:
            q1, q0 = pressure[i_last] ** 2, pressure[i_prev] ** 2
            x = coord[i_last] + (coord[i_last] - coord[i_prev]) * q1 / (q0 - q1)
        else:
            x = 0.5 * (coord[i_last] + x_out)
        lo, hi = sorted((coord[i_last], x_out))
        edges.append(float(np.clip(x, lo, hi)))
    return 0.5 * abs(edges[1] - edges[0])


def recovered_peak(coord: np.ndarray, pressure: np.ndarray) -> float:
    """Peak of a least-squares quadratic in p^2 over the nodes above half the nodal maximum
    (p^2 is quadratic in x for a Hertz contact and smooth near any peak): a patch recovery that
    removes the node-to-node scatter of non-matching contact meshes."""
    sel = pressure >= 0.5 * pressure.max()
    if sel.sum() < 4:
        return float(pressure.max())
    a, b, c = np.polyfit(coord[sel], pressure[sel] ** 2, 2)
    if a >= 0:
        return float(pressure.max())
    x_peak = np.clip(-b / (2 * a), coord[sel].min(), coord[sel].max())
    return float(np.sqrt(max(np.polyval([a, b, c], x_peak), 0.0)))


def solve_load(setup: ContactSetup, force_N: float, width_m: float, active0=None) -> ContactResult:
    """Contact at a total normal force force_N over a face width (plane strain)."""
    lam, delta, its = solve_force(setup, force_N / width_m, active0=active0)
    pressure = lam / setup.tributary_m
    active = lam > 0
    return ContactResult(force_N=float(force_N), approach_m=delta,
                         peak_pressure_Pa=recovered_peak(setup.coord_m, pressure),
                         half_width_m=half_width(setup.coord_m, pressure, active),
                         nodal_force_N=lam * width_m, pressure_Pa=pressure, active=active,
                         iterations=its, raw_peak_pressure_Pa=float(pressure.max()))
