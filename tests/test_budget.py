"""The compliance budget: shares of the output torsional compliance that sum to 1 and that agree
with the model's own output rotation (a finite torque step) and with a one-coupling stiffening."""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from dynamics.budget import compliance_budget, coupling_tangents
from dynamics.reducer import build_model
from dynamics.statics import solve_static
from geometry.params import load_case
from tests.support import case_path, stiffness_for_tests


@pytest.fixture(scope="module")
def model():
    case = load_case(case_path("rv40e-81"))
    return build_model(case, stiffness_for_tests(case))


def test_the_shares_sum_to_one_and_are_each_between_zero_and_one(model):
    b = compliance_budget(model)
    shares = np.array(list(b["compliance_budget"].values()))
    assert abs(shares.sum() - 1.0) < 1e-9
    assert np.all(shares > -1e-12) and np.all(shares < 1 + 1e-12)


def test_the_tangent_rigidity_matches_a_small_torque_step_of_the_full_nonlinear_model(model):
    """Tangent from the summed coupling tangents vs (T+dT) - (T-dT) static solves: 1 %."""
    T = model.case.rated_torque_Nm
    b = compliance_budget(model, T)
    dT = 0.01 * T
    lo, hi = (solve_static(model, 0.0, t) for t in (T - dT, T + dT))
    dtheta_arcmin = abs(hi.output_angle_deg - lo.output_angle_deg) * 60
    assert b["tangent_rigidity_Nm_per_arcmin"] == pytest.approx(2 * dT / dtheta_arcmin, rel=0.01)


def test_the_coupling_tangents_add_up_to_the_assembled_tangent(model):
    from dynamics.reducer import evaluate
    st = solve_static(model, 0.0, model.case.rated_torque_Nm)
    Ks = coupling_tangents(model, st.q, 0.0)
    w, _ = evaluate(model, st.q, 0.0, want_k=True)
    assert np.allclose(sum(Ks.values()), w.K, rtol=1e-12, atol=1e-6 * np.abs(w.K).max())
