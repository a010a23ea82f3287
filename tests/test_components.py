"""The stiffness-component registry (fem.components): one module per component of the compliance
path, each with its interface; stiffened, the pin law, the support composition and the budget read
it; the new components' closed forms (joint layers, main bearings in the support path) against
hand-worked references."""
from __future__ import annotations

import numpy as np
import pytest

from fem import components
from fem.components import joints, main_bearings
from fem.joint_layers import layer_material
from fem.stiffness import COMPONENTS, pin_law, seat_transfer, support_compliance_parts
from geometry.params import load_case
from tests.support import case_path, stiffness_for_tests

HOOKS = {"support": "support_part", "pin": "series_approach_m", "mesh": "line_compliance_m_per_N"}


@pytest.fixture(scope="module")
def case():
    return load_case(case_path("rv40e-81"))


@pytest.fixture(scope="module")
def stiffness(case):
    return stiffness_for_tests(case)


def test_every_component_has_the_interface_and_one_name():
    assert len(set(COMPONENTS)) == len(COMPONENTS)
    for c in components.REGISTRY:
        assert callable(c.compute) and callable(c.stiffen) and c.COST >= 0, c.NAME
        for coupling in (c.COUPLING, *getattr(c, "ALSO", ())):
            hook = HOOKS.get(coupling)
            if hook and c.NAME != "pin_contact":
                assert callable(getattr(c, hook)), f"{c.NAME}: a {coupling} component needs {hook}"
        if hasattr(c, "to_json"):        # a parts entry round-trips through JSON
            assert callable(c.from_json)


def test_an_unknown_component_is_refused_with_the_allowed_names(stiffness):
    with pytest.raises(ValueError, match="allowed .*carrier.*joints"):
        stiffness.stiffened("gearbox", 2.0)


@pytest.mark.parametrize("name", [c.NAME for c in components.in_coupling("support")])
def test_stiffening_a_support_component_divides_its_matrix_and_leaves_the_others(stiffness, name):
    nc = 3
    before = support_compliance_parts(stiffness, nc)
    after = support_compliance_parts(stiffness.stiffened(name, 4.0), nc)
    for k in before:
        expect = before[k] / 4.0 if k == name else before[k]
        assert np.allclose(after[k], expect, rtol=1e-12, atol=0), k


def test_the_pin_law_holds_every_pin_component_in_series(stiffness):
    """Stiffening a series part 1e9x removes exactly its approach from the refitted law's table."""
    pos, k, n, err = pin_law(stiffness)
    assert err.max() < 0.05
    rigid = stiffness.stiffened("pin_groove", 1e9)
    _, k2, n2, _ = pin_law(rigid)
    L = stiffness.pin_contact.load_N
    a1, a2 = ((L[None, :] / kk[:, None]) ** (1 / nn[:, None]) for kk, nn in ((k, n), (k2, n2)))
    assert np.all(a2 < a1)


def test_main_bearings_tilt_the_carrier_under_the_discs_opposite_forces(stiffness):
    """Two equal opposite forces F at the disc planes z = -+w/2 (one crank): a moment F w about the
    pair centre, tilt F w / k_tilt, plane displacement -+ (w/2) tilt; the net force is zero, so the
    radial spring carries nothing (B^T C B by hand)."""
    e = stiffness.parts["main_bearings"]
    T = seat_transfer(stiffness, 3)
    C = main_bearings.support_part(stiffness, T, 3)
    z = e.plane_z_m
    F = np.zeros(C.shape[0])
    F[0], F[2] = 1.0, -1.0                     # crank 1, plane 1 +x, plane 2 -x
    u = C @ F
    tilt = (z[0] - z[1]) / e.tilt_stiffness_Nm_per_rad
    assert u[0] == pytest.approx(z[0] * tilt, rel=1e-12) and u[2] == pytest.approx(z[1] * tilt, rel=1e-12)
    G = np.zeros(C.shape[0])
    G[0::2] = 1.0                              # every plane of every crank +x: n F through the radial spring
    assert (C @ G)[0] == pytest.approx(len(G) / 2 / e.radial_stiffness_N_per_m, rel=1e-9)


def test_the_joints_seat_springs_add_in_series_with_the_support_bearings(stiffness):
    """joints.support_part = T^T T c_seat with a rigid carrier delta: the support bearings' own
    matrix T^T T / k_b scaled by c_seat k_b."""
    T = seat_transfer(stiffness, 3)
    e = stiffness.parts["joints"]
    assert e.seat_compliance_m_per_N > 0
    got = joints.support_part(stiffness, T, 3)
    ref = components.by_name("support_bearings").support_part(stiffness, T, 3)
    ratio = e.seat_compliance_m_per_N * stiffness.support_bearings.stiffness_N_per_m
    assert np.allclose(got, ref * ratio, rtol=1e-12, atol=1e-30)


def test_a_joint_layer_adds_exactly_the_joints_compliance_to_its_slab():
    """A slab h carries h / M + 1 / k_n in compression and h / G + 1 / k_t in shear (thin-layer
    element): both branches (k_t / k_n below and above the isotropic limit 1/2)."""
    E, nu, h = 206e9, 0.3, 2e-3
    lam, G = E * nu / ((1 + nu) * (1 - nu * 2)), E / (2 * (1 + nu))
    M = lam + 2 * G
    for kn, kt in ((2e13, 0.82 * 2e13), (2e13, 0.3 * 2e13)):
        El, nul, dG = layer_material(np.array([h]), E, nu, kn, kt)
        lam_l, G_l = El * nul / ((1 + nul) * (1 - 2 * nul)), El / (2 * (1 + nul)) + dG
        assert h / (lam_l + 2 * El / (2 * (1 + nul)))[0] == pytest.approx(h / M + 1 / kn, rel=1e-12)
        assert h / G_l[0] == pytest.approx(h / G + 1 / kt, rel=1e-12)
    with pytest.raises(ValueError, match="must be > 0"):
        layer_material(np.array([h]), E, nu, -1.0, 1.0)


def test_the_seat_compliance_follows_the_finish_band(case):
    """A rougher seat is softer: the band's ends bracket the middle (the law's c range)."""
    mid = joints.seat_compliance_m_per_N(case)["total_m_per_N"]
    lo = joints.seat_compliance_m_per_N(case, "low")["total_m_per_N"]
    hi = joints.seat_compliance_m_per_N(case, "high")["total_m_per_N"]
    assert lo < mid < hi
