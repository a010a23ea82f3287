"""Compliance budget: each coupling's share of the output torsional compliance at a load.

At a static equilibrium q* (input locked, output torque T) the tangent stiffness is the sum of the
couplings' tangents, K = sum_i K_i (`dynamics.couplings`: every force comes from one coupling).
A torque increment dT at the output gives dq = K^-1 e_out dT and the output rotation
dtheta = e_out . dq, so the complementary work splits exactly over the couplings:
    dT dtheta = dq^T K dq = sum_i dq^T K_i dq,     share_i = dq^T K_i dq / dq^T K dq,
the shares sum to 1 by construction (no "stiffen one part 1000x" differences, which do not add
up for a nonlinear, statically indeterminate path). The shares are per coupling; a coupling that
will lump several physical parts in series (issue 11) has to split its share by the parts'
compliances at the operating force, which stiffness.json does not carry yet.
"""
from __future__ import annotations

import numpy as np

from dynamics import couplings
from dynamics.reducer import ReducerModel
from dynamics.statics import solve_static


def coupling_tangents(model: ReducerModel, q: np.ndarray, input_rad: float) -> dict[str, np.ndarray]:
    """Tangent stiffness -df/dq of each registered coupling alone at state q."""
    out = {}
    for mod, p in zip(couplings.REGISTRY, model.arrays.couplings):
        arrays = model.arrays._replace(couplings=(p,))
        w = couplings.make_work(arrays, model.slots)
        couplings.assemble(np.asarray(q, float), np.zeros(model.n_dof), float(input_rad), 0.0, 0.0, True,
                           arrays, w)
        out[mod.NAME] = w.K.copy()
    return out


def compliance_budget(model: ReducerModel, torque_Nm: float | None = None,
                      input_angle_deg: float = 0.0) -> dict:
    """Shares of the output torsional compliance at `torque_Nm` (default rated), by coupling."""
    T = model.case.rated_torque_Nm if torque_Nm is None else float(torque_Nm)
    st = solve_static(model, input_angle_deg, T)
    Ks = coupling_tangents(model, st.q, np.deg2rad(input_angle_deg))
    K = sum(Ks.values())
    e = np.zeros(model.n_dof)
    e[model.i_out] = 1.0
    dq = np.linalg.solve(K, e)
    total = float(dq @ K @ dq)
    shares = {name: float(dq @ Ki @ dq) / total for name, Ki in Ks.items()}
    return {"torque_Nm": T, "input_angle_deg": float(input_angle_deg),
            "tangent_rigidity_Nm_per_arcmin": float(np.deg2rad(1 / 60) / dq[model.i_out]),
            "compliance_budget": shares}
