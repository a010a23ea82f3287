"""Linear elasticity with scikit-fem, shared by every FE model of the project.

2D is plane strain (the 3D Lame constants in the 2D form), per metre of thickness unless a
thickness is given: the cycloid disc, pin and needle contacts are long in the axial direction
compared with their contact half-widths. 3D uses P1 or P2 tetrahedra (P2 for bending: linear
tetrahedra lock in bending). Isotropic, small strain, SI units (m, Pa, N).

A `Factorized` body holds ONE sparse LU factorization of its constrained stiffness; every load
case, unit load and condensed compliance afterwards costs triangular solves only.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from scipy.linalg.lapack import dtrtri
from scipy.sparse.linalg import splu

from fem.mesh import Mesh2D, Mesh3D


def lame(E_Pa: float, nu: float) -> tuple[float, float]:
    """(lambda, mu) of an isotropic solid."""
    return E_Pa * nu / ((1 + nu) * (1 - 2 * nu)), E_Pa / (2 * (1 + nu))


def basis_2d(mesh: Mesh2D):
    """P1 vector basis with the centroid rule: P1 strains are constant per triangle, so one point
    integrates the stiffness exactly (skfem's default 3 points cost 3x the assembly for the same K).
    Not for integrands that vary over a triangle (loads from a varying field)."""
    from skfem import Basis, ElementTriP1, ElementVector, MeshTri
    m = MeshTri(np.ascontiguousarray(mesh.points.T), np.ascontiguousarray(mesh.triangles.T))
    return Basis(m, ElementVector(ElementTriP1()), quadrature=(np.full((2, 1), 1 / 3), np.array([0.5])))


def basis_3d(mesh: Mesh3D, order: int = 2):
    from skfem import Basis, ElementTetP1, ElementTetP2, ElementVector, MeshTet
    m = MeshTet(np.ascontiguousarray(mesh.points.T), np.ascontiguousarray(mesh.tetrahedra.T))
    elem = {1: ElementTetP1, 2: ElementTetP2}[order]()
    return Basis(m, ElementVector(elem))


def stiffness(basis, E_Pa: float, nu: float, thickness_m: float = 1.0) -> sp.csr_matrix:
    """Stiffness matrix of linear elasticity (plane strain in 2D) on a vector basis."""
    from skfem import asm
    from skfem.models.elasticity import linear_elasticity
    lam, mu = lame(E_Pa, nu)
    return (thickness_m * asm(linear_elasticity(lam, mu), basis)).tocsr()


def stress_2d(basis, u: np.ndarray, E_Pa: float, nu: float) -> dict:
    """Element-mean plane-strain stresses [Pa]: sxx, syy, sxy, szz and von Mises."""
    lam, mu = lame(E_Pa, nu)
    m = basis.mesh
    p, t = m.p, m.t
    # P1: constant strain per triangle from the nodal displacements
    ux, uy = u[0::2], u[1::2]
    x, y = p[0, t], p[1, t]
    det = (x[1] - x[0]) * (y[2] - y[0]) - (x[2] - x[0]) * (y[1] - y[0])
    bx = np.array([y[1] - y[2], y[2] - y[0], y[0] - y[1]]) / det
    by = np.array([x[2] - x[1], x[0] - x[2], x[1] - x[0]]) / det
    exx = (bx * ux[t]).sum(0)
    eyy = (by * uy[t]).sum(0)
    exy = 0.5 * ((by * ux[t]).sum(0) + (bx * uy[t]).sum(0))
    tr = exx + eyy
    sxx, syy, sxy = lam * tr + 2 * mu * exx, lam * tr + 2 * mu * eyy, 2 * mu * exy
    szz = lam * tr
    vm = np.sqrt(0.5 * ((sxx - syy) ** 2 + (syy - szz) ** 2 + (szz - sxx) ** 2) + 3 * sxy ** 2)
    return {"sxx": sxx, "syy": syy, "sxy": sxy, "szz": szz, "von_mises": vm}


@dataclass(frozen=True)
class Factorized:
    """K restricted to its free DOFs, factorized once (fixed DOFs carry zero displacement).

    With `last` (the DOFs where contact loads act) those DOFs are ordered last, so the trailing
    block of the LU factors IS the Schur complement S = K_cc - K_ci K_ii^-1 K_ic, and the
    condensed compliance of the contact DOFs is S^-1: no solve with the big factors at all.
    """
    n_dofs: int
    free: np.ndarray
    lu: object
    factor_seconds: float
    perm: np.ndarray | None = None        # factor order -> index into free (None: SuperLU's own)
    last: np.ndarray | None = None        # global DOFs condensed exactly (ordered last)
    last_inverse_factor: np.ndarray | None = None   # W, S^-1 = W^T W, S the Schur complement on `last`

    @classmethod
    def of(cls, K: sp.spmatrix, fixed_dofs, last=None) -> "Factorized":
        import time
        n = K.shape[0]
        mask = np.ones(n, bool)
        mask[np.asarray(fixed_dofs, int)] = False
        free = np.flatnonzero(mask)
        Kff = sp.csc_matrix(K[free][:, free])
        t0 = time.perf_counter()
        if last is None:
            lu = splu(Kff, permc_spec="MMD_AT_PLUS_A", options={"SymmetricMode": True})
            return cls(n, free, lu, time.perf_counter() - t0)
        last = np.asarray(last, int)
        pos_in_free = np.searchsorted(free, last)
        if np.any(free[np.minimum(pos_in_free, len(free) - 1)] != last):
            raise ValueError("a condensed DOF is also a fixed DOF")
        is_last = np.zeros(len(free), bool)
        is_last[pos_in_free] = True
        npn = 2 if n % 2 == 0 else 3                     # DOFs per node (ordering only: a wrong guess costs fill)
        perm = np.concatenate([_interior_order(Kff, free, is_last, npn), pos_in_free])
        lu = splu(sp.csc_matrix(Kff[perm][:, perm]), permc_spec="NATURAL",
                  options={"SymmetricMode": True}, diag_pivot_thresh=0.0)
        k, m = len(last), len(free)
        pc = lu.perm_c
        if not (np.array_equal(lu.perm_r, pc) and np.array_equal(pc[m - k:], np.arange(m - k, m))):
            raise RuntimeError("SuperLU reordered the condensed DOFs; cannot read the Schur complement")
        # no pivoting on an SPD matrix: S = L_t D L_t^T (U = D L^T), so S^-1 = W^T W with
        # W = D^-1/2 L_t^-1: one dense triangular inverse (LAPACK); compliance blocks are read from W
        Lt = _trailing_dense(lu.L, m - k)
        d = lu.U.diagonal()[m - k:]
        if not np.all(d > 0):
            raise RuntimeError("stiffness not positive definite on the free DOFs (a rigid mode left unconstrained?)")
        Li, info = dtrtri(Lt, lower=1, unitdiag=1, overwrite_c=1)
        if info != 0:
            raise RuntimeError(f"LAPACK dtrtri failed (info {info}) on the Schur block")
        Li /= np.sqrt(d)[:, None]
        return cls(n, free, lu, time.perf_counter() - t0, perm, last, Li)

    @property
    def last_compliance(self) -> np.ndarray | None:
        """S^-1 = (K^-1 restricted to `last`), in the order of `last`."""
        return None if self.last_inverse_factor is None else self.last_block(np.arange(len(self.last)))

    def last_block(self, idx: np.ndarray) -> np.ndarray:
        """Block S^-1[idx, idx] (positions in `last`): W is lower triangular, so only its rows from
        min(idx) on enter; a window of the contact path costs k w^2, not the k^3 of all of S^-1."""
        W = self.last_inverse_factor[int(np.min(idx)):, idx]
        out = W.T @ W
        return 0.5 * (out + out.T)

    def solve(self, f: np.ndarray) -> np.ndarray:
        """Displacements for nodal loads f (n_dofs,) or (n_dofs, k)."""
        f = np.asarray(f, float)
        u = np.zeros(f.shape)
        if self.perm is None:
            u[self.free] = self.lu.solve(np.asfortranarray(f[self.free]))
        else:
            u[self.free[self.perm]] = self.lu.solve(np.asfortranarray(f[self.free[self.perm]]))
        return u

    def compliance(self, B: sp.spmatrix, chunk: int = 256) -> np.ndarray:
        """Condensed compliance B K^-1 B^T (dense, m x m) for m unit-load vectors (rows of B)."""
        B = sp.csr_matrix(B, copy=True)
        B.eliminate_zeros()           # exact zeros (a load normal to a framed DOF) are no load
        if self.last is not None:
            cols = np.unique(B.indices)
            where = {d: i for i, d in enumerate(self.last)}
            if all(c in where for c in cols):
                idx = np.array([where[c] for c in cols])
                Bl = B[:, cols].toarray()
                return Bl @ self.last_block(idx) @ Bl.T
            if self.perm is not None:
                raise ValueError("unit loads outside the condensed DOFs of a Schur-ordered factorization")
        Bf = B[:, self.free]
        out = np.empty((B.shape[0], B.shape[0]))
        BfT = Bf.T.tocsc()
        for i in range(0, B.shape[0], chunk):
            rhs = BfT[:, i:i + chunk].toarray(order="F")   # SuperLU copies C-order blocks column by column: 7x slower
            x = self.lu.solve(rhs)
            out[:, i:i + chunk] = Bf @ x
        return 0.5 * (out + out.T)   # symmetric up to round-off


def _interior_order(Kff: sp.csc_matrix, free: np.ndarray, is_last: np.ndarray, npn: int) -> np.ndarray:
    """Fill-reducing order of the free DOFs not in `is_last` (indices into free): SuperLU's minimum
    degree on the node graph (npn x npn blocks summed: 4-9x smaller than the DOF graph), DOFs kept
    node by node. Condensed nodes stay in the graph: a node framed along its load direction keeps
    its other DOF in the interior, and ordering that DOF with its neighbours measured 25 % less fill."""
    nodes, inv = np.unique(free // npn, return_inverse=True)
    if len(free) == npn * len(nodes):                  # every node whole: its first DOF's pattern is the graph
        A = abs(sp.csc_matrix(Kff[::npn, ::npn]))
    else:
        G = Kff.tocoo()
        A = sp.csc_matrix((np.ones(G.nnz), (inv[G.row], inv[G.col])), shape=(len(nodes), len(nodes)))
    A.data[:] = 1.0
    A = sp.csc_matrix(sp.diags(np.asarray(A.sum(1)).ravel() + 1.0) - 0.5 * (A + A.T))   # SPD, same pattern
    node_pos = splu(A, permc_spec="MMD_AT_PLUS_A", options={"SymmetricMode": True}, diag_pivot_thresh=0.0).perm_c
    order = np.lexsort((free, node_pos[inv]))           # free indices, node by node
    return order[~is_last[order]]


def _trailing_dense(M: sp.spmatrix, start: int) -> np.ndarray:
    """Dense block M[start:, start:] of a sparse factor, read from its CSC arrays (no slicing copy)."""
    M = M if sp.isspmatrix_csc(M) else sp.csc_matrix(M)
    k = M.shape[0] - start
    s = M.indptr[start]
    cols = np.repeat(np.arange(k), np.diff(M.indptr[start:]))
    rows = M.indices[s:]
    sel = rows >= start
    out = np.zeros((k, k))
    out[rows[sel] - start, cols[sel]] = M.data[s:][sel]
    return out
