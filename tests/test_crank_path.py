"""The assembled crank path (fem.crank_path): its roller-by-roller bearings against fem.tapered_roller's
own pair model in the rigid limit, the stated preload, and the check's figure on a coarse FE run."""
from pathlib import Path

import numpy as np
import pytest

from fem import carrier as fe_carrier
from fem import crank_path, tapered_roller
from geometry.params import load_case

CASES = Path(__file__).resolve().parents[1] / "cases"


def _rigid_crank(span_m: float, eccentric_z_m, stiffness: float = 1e16) -> dict:
    """A rigid crankshaft as a superelement: a penalty K = k A^T A on ring 2 following ring 1 rigidly
    (null space: exactly the six rigid motions), the eccentric loads put on the rings by the lever
    rule (statically equivalent), no own deflection (H = 0)."""
    A = np.zeros((6, 12))
    lever = np.array([0.0, 0.0, span_m])
    A[:3, 6:9], A[:3, :3] = np.eye(3), -np.eye(3)
    for k in range(3):                       # - theta_1 x lever
        A[:3, 3 + k] = -np.cross(np.eye(3)[k], lever)
    A[3:, 9:], A[3:, 3:6] = np.eye(3), -np.eye(3)
    G = np.zeros((4, 12))
    for i, z in enumerate(eccentric_z_m):
        share2 = z / span_m
        for ax in range(2):
            G[2 * i + ax, ax], G[2 * i + ax, 6 + ax] = -(1 - share2), -share2
    return {"K": stiffness * A.T @ A, "G": G, "H": np.zeros((4, 4)),
            "ring_centres_m": [np.zeros(3), lever], "dofs": 0}


@pytest.fixture(scope="module")
def rigid_assembly():
    case = load_case(CASES / "rv40e-81.toml")
    g = fe_carrier.case_geometry(case)
    setup = tapered_roller.case_support_setup(case)
    span = setup.spacing_m
    crank = _rigid_crank(span, (0.5 * span - 0.01, 0.5 * span + 0.01))
    C6 = 1e-16 * np.eye(12 * g.crank_count)          # a rigid carrier
    return case, setup, crank_path.AssembledCrankPath(crank, C6, g, setup)


def test_rigid_limit_reproduces_the_preloaded_pair_of_fem_tapered_roller(rigid_assembly):
    # rigid crank and carrier: every roller slice of both bearings between rigid rings, which is
    # fem.tapered_roller.solve_pair's model (Jones / Harris, ISO/TS 16281 slices) written in its own
    # pair coordinates; the assembly places the same rollers in 3D on rings. Same load, same answer.
    case, setup, asm = rigid_assembly
    d0, pre = asm.preloaded_d0()
    # a rigid setting needs no more interference than the pair's own, and leaves the stated preload
    assert d0 == pytest.approx(asm.d0_base, rel=1e-6)
    assert np.allclose(pre, setup.preload_N, rtol=1e-6)
    for Fx in (500.0, 3000.0):
        f = np.zeros((asm.nc, 4))
        f[:, 0] = f[:, 2] = 0.5 * Fx          # both eccentrics, the resultant at the pair centre along +x (roller 0)
        q, Q = asm.solve(f, d0)
        ref = tapered_roller.solve_pair(setup, Fx)
        for cd in asm.crank_dofs:
            u_mid = 0.5 * (q[cd[0]] + q[cd[6]])
            assert u_mid == pytest.approx(ref.q[0], rel=1e-6)
            assert abs(q[cd[4]] - ref.q[2]) < 1e-6 * abs(ref.q[0]) / setup.spacing_m   # tilt: none by symmetry
        # every crank carries the same load: the rollers' loads repeat per crank (roller 0 along psi = 0),
        # to the rounding the rigid crank's penalty allows: its 1e16 N/m over the rollers' ~1e9 N/m times
        # the double's 2.2e-16 is ~2e-9 of the largest load (measured 0.6-1.7e-9 on an AMD EPYC, whose
        # OpenBLAS kernels round otherwise than the machine that set 1e-9 here); a real asymmetry (a
        # crank's rollers phased or placed otherwise) is >= 1e-3
        per = Q.reshape(asm.nc, -1)
        assert np.allclose(per, per[0], rtol=1e-8, atol=1e-8 * Q.max())


def test_seats_that_do_not_face_the_journals_are_an_input_error(rigid_assembly):
    import dataclasses as dc
    from geometry.artifacts import InputError
    case, setup, asm = rigid_assembly
    g = fe_carrier.case_geometry(case)
    with pytest.raises(InputError, match="seats"):
        crank_path.AssembledCrankPath(asm.crank, 1e-16 * np.eye(12 * g.crank_count),
                                      g, dc.replace(setup, spacing_m=setup.spacing_m * 1.5))
