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
from scipy.sparse.linalg import splu

from fem.mesh import Mesh2D, Mesh3D


def lame(E_Pa: float, nu: float) -> tuple[float, float]:
    """(lambda, mu) of an isotropic solid."""
    return E_Pa * nu / ((1 + nu) * (1 - 2 * nu)), E_Pa / (2 * (1 + nu))


def basis_2d(mesh: Mesh2D):
    from skfem import Basis, ElementTriP1, ElementVector, MeshTri
    m = MeshTri(np.ascontiguousarray(mesh.points.T), np.ascontiguousarray(mesh.triangles.T))
    return Basis(m, ElementVector(ElementTriP1()))


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
    last_compliance: np.ndarray | None = None   # S^-1 in the order of `last`

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
        # minimum-degree order of the node graph (2x2 or 3x3 blocks summed), then contact DOFs last
        npn = 2 if K.shape[0] == 2 * (K.shape[0] // 2) else 3
        G = abs(Kff).tocoo()
        fn = free // npn
        nodes, inv = np.unique(fn, return_inverse=True)
        A = sp.csc_matrix((np.ones(G.nnz), (inv[G.row], inv[G.col])), shape=(len(nodes), len(nodes)))
        A = sp.csc_matrix(sp.diags(np.asarray(A.sum(1)).ravel() + 1.0) - 0.5 * (A + A.T) + 1e-3 * sp.eye(len(nodes)))
        node_pos = splu(A, permc_spec="MMD_AT_PLUS_A", options={"SymmetricMode": True},
                        diag_pivot_thresh=0.0).perm_c
        order = np.lexsort((free, node_pos[inv]))        # free indices, node by node
        is_last = np.zeros(len(free), bool)
        is_last[pos_in_free] = True
        perm = np.concatenate([order[~is_last[order]], pos_in_free])
        lu = splu(sp.csc_matrix(Kff[perm][:, perm]), permc_spec="NATURAL",
                  options={"SymmetricMode": True}, diag_pivot_thresh=0.0)
        k, m = len(last), len(free)
        pc = lu.perm_c
        if not (np.array_equal(lu.perm_r, pc) and np.array_equal(np.sort(pc[m - k:]), np.arange(m - k, m))):
            raise RuntimeError("SuperLU reordered the condensed DOFs; cannot read the Schur complement")
        t = pc[m - k:]                                    # factor positions of `last`, in order
        L = lu.L.tocsc()[:, m - k:][m - k:, :]
        U = lu.U.tocsc()[:, m - k:][m - k:, :]
        S = (L @ U).toarray()[np.ix_(t - (m - k), t - (m - k))]
        Sinv = np.linalg.inv(0.5 * (S + S.T))
        return cls(n, free, lu, time.perf_counter() - t0, perm, last, 0.5 * (Sinv + Sinv.T))

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
        B = sp.csr_matrix(B)
        if self.last is not None:
            cols = np.unique(B.indices)
            where = {d: i for i, d in enumerate(self.last)}
            if all(c in where for c in cols):
                idx = np.array([where[c] for c in cols])
                Bl = B[:, cols].toarray()
                return Bl @ self.last_compliance[np.ix_(idx, idx)] @ Bl.T
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
