"""FEM stage: Hertz benchmark, convergence, patch test, contact solver (coarse, fast meshes)."""
import math

import numpy as np
import pytest

from fem import contact, elastic, hertz
from fem.mesh import block_mesh
from fem.pin_contact import hertz_benchmark


def test_cylinder_on_flat_matches_hertz_peak_pressure_and_half_width_within_3_percent():
    # closed form: Johnson 1985 eqs. 4.43-4.45 (p0 = 1095.9 MPa, b = 58.09 um at 1 kN, R 3 mm, L 10 mm)
    r = hertz_benchmark(3e-3, 10e-3, 1000.0)
    assert abs(r.peak_pressure_Pa / r.peak_pressure_closed_form_Pa - 1) < 0.03
    assert abs(r.half_width_m / r.half_width_closed_form_m - 1) < 0.03


def test_cylinder_on_cylinder_matches_hertz_within_3_percent():
    r = hertz_benchmark(3e-3, 10e-3, 800.0, counter_radius_m=8e-3)
    assert abs(r.peak_pressure_Pa / r.peak_pressure_closed_form_Pa - 1) < 0.03
    assert abs(r.half_width_m / r.half_width_closed_form_m - 1) < 0.03
    # approach against Johnson eq. 5.36 for both cylinders: the clamped back halves differ from
    # Johnson's loading, measured 1-5 %; band 8 %
    assert abs(r.approach_m / r.approach_closed_form_m - 1) < 0.08


def test_half_width_error_falls_with_the_contact_element_size():
    b = float(hertz.hertz_line(1000.0, 10e-3, 3e-3, hertz.contact_modulus(206e9, 0.3))[1])
    h = b / np.array([4.0, 8.0, 16.0])
    err = [abs(hertz_benchmark(3e-3, 10e-3, 1000.0, mesh_size_m=hi).half_width_m / b - 1) for hi in h]
    rate = np.polyfit(np.log(h), np.log(err), 1)[0]
    print(f"half-width errors {err}, observed rate {rate:.2f}")
    assert err[-1] < err[0] and rate > 0.5   # measured ~1 (edge located to O(h)); bound 0.5


def test_linear_displacement_field_is_reproduced_exactly_patch_test():
    m = block_mesh(4e-3, 2e-3, 1e-4, 5e-4)
    K = elastic.stiffness(elastic.basis_2d(m), 206e9, 0.3)
    A = np.array([[1e-3, 2e-4], [-3e-4, 5e-4]])
    exact = m.points @ A.T + np.array([1e-6, -2e-6])
    bnd = np.unique(np.concatenate(list(m.boundary.values()) + [np.flatnonzero(
        (np.abs(np.abs(m.points[:, 0]) - 2e-3) < 1e-12))]))
    fixed = np.concatenate([2 * bnd, 2 * bnd + 1])
    u_b = np.zeros(K.shape[0])
    u_b[2 * bnd], u_b[2 * bnd + 1] = exact[bnd, 0], exact[bnd, 1]
    fac = elastic.Factorized.of(K, fixed)
    u = fac.solve(-(K @ u_b)) + u_b
    # round-off only: 1e-10 relative
    assert np.abs(u.reshape(-1, 2) - exact).max() < 1e-10 * np.abs(exact).max()


def test_schur_ordered_factorization_gives_the_same_compliance_as_solves():
    m = block_mesh(6e-3, 3e-3, 2e-5, 5e-4)
    K = elastic.stiffness(elastic.basis_2d(m), 206e9, 0.3)
    fixed = np.concatenate([2 * m.boundary["bottom"], 2 * m.boundary["bottom"] + 1])
    top = m.boundary["top"][:20]
    B = contact.node_operator(top, np.tile([0.0, 1.0], (len(top), 1)), K.shape[0])
    plain = elastic.Factorized.of(K, fixed).compliance(B)
    schur = elastic.Factorized.of(K, fixed, last=np.column_stack([2 * top, 2 * top + 1]).ravel()).compliance(B)
    assert np.allclose(plain, schur, rtol=1e-9, atol=0)


def test_active_set_solves_a_two_spring_contact_exactly():
    # two independent springs k = 1, 2 N/m with gaps 0 and 1 m, total force 5 N:
    # both touch: delta - 0 = l1, delta - 1 = l2 / 2, l1 + l2 = 5 -> delta = 7/3
    setup = contact.ContactSetup(np.diag([1.0, 0.5]), np.array([0.0, 1.0]), np.ones(2),
                                 np.array([0.0, 1.0]), np.ones(2), np.arange(2))
    lam, delta, _ = contact.solve_force(setup, 5.0)
    assert delta == pytest.approx(7 / 3, rel=1e-12)
    assert lam == pytest.approx([7 / 3, 8 / 3], rel=1e-12)


def test_power_law_fit_recovers_an_exact_law():
    d = np.geomspace(1e-7, 1e-5, 6)
    k, n = hertz.fit_power_law(3e9 * d ** 1.1, d)
    assert n == pytest.approx(1.1, rel=1e-10) and k == pytest.approx(3e9, rel=1e-8)


def test_a_benchmark_load_too_large_for_hertz_is_refused_with_the_value():
    with pytest.raises(ValueError, match="half-width"):
        hertz_benchmark(1e-3, 1e-3, 1e6)
