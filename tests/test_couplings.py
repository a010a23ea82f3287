"""The lumped model as couplings (dynamics.couplings): each coupling alone against finite
differences and its own potential, the registry sum, the DOF layout, the kernel cache stamp, and
the chunked time integration (bit-identical to one chunk; signals act between chunks)."""
import math
import shutil
import signal
import time
from pathlib import Path

import numpy as np
import pytest

from dynamics import couplings
from dynamics.couplings import REGISTRY, base
from dynamics.kernel_cache import KernelUnit
from dynamics.layout import DofLayout
from dynamics.loads import LoadSpec, input_angle_deg, input_speed_deg_s, load_torque_Nm
from dynamics.model import evaluate, run_dynamics, simulate
from dynamics.statics import solve_static
from support import model_for_tests

NAMES = [m.NAME for m in REGISTRY]


@pytest.fixture(scope="module")
def loaded():
    """rv40e-81 with both bearing clearances open (every branch of every coupling is live) at
    300 N m, and a random velocity for the damping terms."""
    model = model_for_tests("rv40e-81", turning_arm_clearance_um=2.0, support_clearance_um=1.0)
    s = solve_static(model, 10.0, 300.0)
    v = np.random.default_rng(3).normal(size=model.n_dof) * 1e-3 / model.scale
    return model, s, v


def _alone(model, name):
    """assemble's `only` for the coupling `name` alone (its registry index)."""
    return couplings.index_of(name)


def _eval(model, only, q, v, th, beta=0.0, want_k=True):
    w = model.work()
    V, tau, ok = couplings.assemble(q, v, th, 0.0, beta, want_k, model.arrays, w, only)
    return w, V, tau, ok


def test_the_assembler_is_the_sum_of_the_registered_couplings(loaded):
    model, s, v = loaded
    th = math.radians(s.input_angle_deg)
    w, V, tau, ok = _eval(model, couplings.ALL, s.q, v, th, beta=1e-5)
    parts = [_eval(model, _alone(model, n), s.q, v, th, beta=1e-5) for n in NAMES]
    assert ok and all(p[3] for p in parts)
    for attr in ("f", "K", "C"):
        total = sum(getattr(p[0], attr) for p in parts)
        assert np.allclose(getattr(w, attr), total, rtol=1e-13, atol=1e-13 * np.abs(total).max())
    assert V == pytest.approx(sum(p[1] for p in parts), rel=1e-13)
    assert tau == pytest.approx(sum(p[2] for p in parts), rel=1e-13)
    # every coupling carries load at this state (a registry entry that adds nothing would pass above)
    assert all(np.abs(p[0].f).max() > 1.0 for p in parts)


# Tangent -df/dq against central differences (scaled: rotations as N m / ROT_SCALE_M), per coupling.
# Left out of K on purpose (the symmetric tangent of the budget, the eigenfrequencies and the time
# integration, whose Newton converges without them): force x curvature terms (pin: profile
# curvature; needle: the turning arms of seat, eccentric and hole) and the mesh's d k_s/ds terms
# (zero away from the single/double contact edges, as here). Measured on this state (largest error /
# largest entry): mesh 1e-10, support 3e-10, needle 1.2e-6, pin 3.4e-4. The pin's two (its
# curvature and its law's phase) are in Work.K_rest for the statics: test below.
TANGENT_RTOL = {"mesh": 1e-6, "support": 1e-6, "needle": 1e-5, "pin": 1e-3, "housing": 1e-6}
# f = -dV/dq: exact but for the pin law's k(phase), which is not differentiated. Measured: mesh,
# support 1e-10, needle 4e-8 (round-off of V), pin 1.7e-4 of the largest force; housing: linear springs.
POTENTIAL_RTOL = {"mesh": 1e-6, "support": 1e-6, "needle": 1e-6, "pin": 1e-3, "housing": 1e-6}


@pytest.mark.parametrize("name", NAMES)
def test_each_coupling_tangent_matches_finite_differences_of_its_force(loaded, name):
    model, s, _ = loaded
    only, th = _alone(model, name), math.radians(s.input_angle_deg)
    K = _eval(model, only, s.q, np.zeros(model.n_dof), th)[0].K.copy()
    h0 = min(1e-9, 0.2 * np.abs(s.pin_gap_m).min())     # never straddle a pin's contact onset
    Kfd = np.zeros_like(K)
    for j in range(model.n_dof):
        e = np.zeros(model.n_dof)
        e[j] = h0 / model.scale[j]
        fp = _eval(model, only, s.q + e, np.zeros(model.n_dof), th, want_k=False)[0].f
        fm = _eval(model, only, s.q - e, np.zeros(model.n_dof), th, want_k=False)[0].f
        Kfd[:, j] = -(fp - fm) / (2 * e[j])
    S = np.diag(1 / model.scale)
    scale = np.abs(S @ K @ S).max()
    assert scale > 0
    assert np.abs(S @ (K - Kfd) @ S).max() < TANGENT_RTOL[name] * scale


def _fd_tangent(model, only, q, th, h=1e-10):
    """-df/dq by central differences (steps of h metres, scaled) of the coupling `only` at rest at q.
    Their own error is ~h^2 (pins of the stand-in at 300 N m: 7e-6, 6e-7, 1.2e-7 of the largest
    entry at h = 1e-9, 3e-10, 1e-10 m)."""
    z = np.zeros(model.n_dof)
    Kfd = np.zeros((model.n_dof, model.n_dof))
    for j in range(model.n_dof):
        e = np.zeros(model.n_dof)
        e[j] = h / model.scale[j]
        Kfd[:, j] = -(_eval(model, only, q + e, z, th, want_k=False)[0].f
                      - _eval(model, only, q - e, z, th, want_k=False)[0].f) / (2 * e[j])
    return Kfd


@pytest.mark.parametrize("torque", [30.0, 300.0])
def test_the_statics_tangent_of_the_pins_is_exact(torque):
    """K + K_rest (the statics' Newton matrix: the pin law's phase part and the force x gap-Hessian
    part added, kernels.static_solve) is -df/dq to the differences' own error, where K alone misses
    by ~3e-4 of its largest entry; the time integration (beta > 0) leaves K_rest empty."""
    model = model_for_tests("rv40e-81")
    s = solve_static(model, 10.0, torque)
    only, th = _alone(model, "pin"), math.radians(s.input_angle_deg)
    assert np.abs(s.pin_gap_m).min() > 1e-9          # no contact within the steps' reach of its onset
    w = _eval(model, only, s.q, np.zeros(model.n_dof), th)[0]
    Kfd = _fd_tangent(model, only, s.q, th)
    S = np.diag(1 / model.scale)
    scale = np.abs(S @ Kfd @ S).max()
    assert np.abs(S @ (w.K + w.K_rest - Kfd) @ S).max() < 1e-6 * scale
    assert np.abs(S @ (w.K - Kfd) @ S).max() > 5e-5 * scale           # what K_rest adds is not noise
    assert not np.allclose(w.K_rest, w.K_rest.T)                        # the law's phase part: not symmetric
    wd = _eval(model, only, s.q, np.zeros(model.n_dof), th, beta=1e-5)[0]
    assert not wd.K_rest.any()


@pytest.mark.parametrize("name", NAMES)
def test_each_coupling_force_is_minus_the_gradient_of_its_potential(loaded, name):
    model, s, _ = loaded
    only, th = _alone(model, name), math.radians(s.input_angle_deg)
    z = np.zeros(model.n_dof)
    f = _eval(model, only, s.q, z, th, want_k=False)[0].f.copy()
    h0 = min(1e-9, 0.2 * np.abs(s.pin_gap_m).min())
    g = np.zeros(model.n_dof)
    for j in range(model.n_dof):
        e = np.zeros(model.n_dof)
        e[j] = h0 / model.scale[j]
        g[j] = (_eval(model, only, s.q + e, z, th, want_k=False)[1]
                - _eval(model, only, s.q - e, z, th, want_k=False)[1]) / (2 * e[j])
    assert np.abs((f + g) / model.scale).max() < POTENTIAL_RTOL[name] * np.abs(f / model.scale).max()


@pytest.mark.parametrize("name", NAMES)
def test_each_coupling_damping_is_minus_the_velocity_derivative_of_its_force(loaded, name):
    model, s, v = loaded
    only, th, beta = _alone(model, name), math.radians(s.input_angle_deg), 2e-5
    C = _eval(model, only, s.q, v, th, beta=beta)[0].C.copy()
    Cfd = np.zeros_like(C)
    for j in range(model.n_dof):
        e = np.zeros(model.n_dof)
        e[j] = 1e-6 / model.scale[j]
        fp = _eval(model, only, s.q, v + e, th, beta=beta, want_k=False)[0].f
        fm = _eval(model, only, s.q, v - e, th, beta=beta, want_k=False)[0].f
        Cfd[:, j] = -(fp - fm) / (2 * e[j])
    S = np.diag(1 / model.scale)
    assert np.abs(S @ C @ S).max() > 0
    assert np.abs(S @ (C - Cfd) @ S).max() < 1e-6 * np.abs(S @ C @ S).max()


def test_the_standard_layout_names_the_blocks():
    nc, nd = 3, 2
    lay = DofLayout.standard(nc, nd)
    assert lay.n == 1 + nc + 2 * nc * nd + 3 * nd
    assert lay["carrier"].index() == 0
    assert [lay["crank_rotation"].index(j) for j in range(nc)] == [1 + j for j in range(nc)]
    # crank axis per disc plane: item j nd + d
    assert [lay["crank_axis"].index(j * nd + 1, "y") for j in range(nc)] == \
        [1 + nc + 2 * (j * nd + 1) + 1 for j in range(nc)]
    first_disc = 1 + nc + 2 * nc * nd
    assert [lay["disc"].index(d, "rot") for d in range(nd)] == [first_disc + 2 + 3 * d for d in range(nd)]
    assert lay.labels[:2] == ("carrier", "crank1_rot") and lay.labels[-1] == "disc2_rot"
    assert lay.labels[1 + nc:1 + nc + 4] == ("crank1_plane1_x", "crank1_plane1_y",
                                             "crank1_plane2_x", "crank1_plane2_y")
    assert list(lay.scale(0.05)) == [0.05] * 4 + [1.0] * 12 + [1.0, 1.0, 0.05] * 2
    with pytest.raises(IndexError, match="disc"):
        lay["disc"].index(2)
    with pytest.raises(KeyError, match="crank_axis"):
        lay["pillar"]


def test_a_layout_with_an_extra_block_moves_the_coupling_index_tables_with_it():
    # a later block (here: a crank axis tilt per crank) shifts the discs; couplings built on the
    # new layout address the discs through their tables, the solvers see only n
    lay = DofLayout.build([("carrier", 1, ("rot",), (True,), ""),
                           ("crank_rotation", 3, ("rot",), (True,), "crank"),
                           ("crank_axis", 6, ("x", "y"), (False, False), "crank"),
                           ("crank_tilt", 3, ("a", "b"), (True, True), "crank"),
                           ("disc", 2, ("x", "y", "rot"), (False, False, True), "disc")])
    model = model_for_tests()
    p = couplings.pin.params(model.case, model.stiffness, lay, couplings.Slots())
    assert p.dof.tolist() == [[22, 23, 24], [25, 26, 27]]
    n = couplings.needle.params(model.case, model.stiffness, lay, couplings.Slots())
    # disc 2 (d = 1), crank 3 (j = 2): crank axis item j nd + d = 5 -> indices 4 + 10, 4 + 11
    assert n.dof[1, 2].tolist() == [0, 3, 14, 15, 25, 26, 27]
    s = couplings.support.params(model.case, model.stiffness, lay, couplings.Slots())
    assert s.dof[2, 1].tolist() == [14, 15] and s.K_N_per_m.shape == (12, 12)


def test_every_kernel_cache_is_stamped_with_the_sources_of_the_whole_compiled_unit(tmp_path):
    from dynamics import kernels
    disps = [couplings.assemble, kernels.integrate, kernels.static_solve, base.foot_point] \
        + [m.add for m in REGISTRY]
    for d in disps:
        assert base.cache_stamp(d) == base.UNIT.digest
        assert base.UNIT.cache_dir in Path(d._cache.cache_path).parents
    names = {p.name for p in base.KERNEL_SOURCES}
    assert {"pin.py", "mesh.py", "kernels.py", "pin_profile.py", "__init__.py"} <= names
    # a one-byte change in any coupling (inlined into the solvers) gives another cache folder
    assert len({p.name for p in base.KERNEL_SOURCES}) == len(base.KERNEL_SOURCES)   # one folder holds copies
    (tmp_path / "copy").mkdir()
    (tmp_path / "edit").mkdir()
    copies = [Path(shutil.copy(p, tmp_path / "copy" / p.name)) for p in base.KERNEL_SOURCES]
    assert KernelUnit(copies, tmp_path).cache_dir == KernelUnit(base.KERNEL_SOURCES, tmp_path).cache_dir
    for i, p in enumerate(base.KERNEL_SOURCES):
        if p.parent.name == "couplings" and p.name != "__init__.py":
            edited = list(copies)
            edited[i] = tmp_path / "edit" / p.name
            edited[i].write_bytes(p.read_bytes() + b" ")
            assert KernelUnit(edited, tmp_path).cache_dir != KernelUnit(copies, tmp_path).cache_dir, p.name


def _drive(duration_s, load):
    dt, n = 1e-4, int(round(duration_s / 1e-4))
    t = np.arange(n + 1) * dt
    return (np.deg2rad(input_angle_deg(t, 1200.0, True)), np.deg2rad(input_speed_deg_s(t, 1200.0, True)),
            np.asarray(load_torque_Nm(load, t), float), dt)


def test_a_chunked_time_integration_is_bit_identical_to_one_chunk():
    model = model_for_tests("rv40e-81", turning_arm_clearance_um=2.0)
    th, w, T, dt = _drive(0.3, LoadSpec("square", 300.0))
    q0 = solve_static(model, math.degrees(th[0]), T[0]).q
    runs = [run_dynamics(model, q0, np.zeros_like(q0), th, w, T, dt, 5, 0.05, 1e-5, chunk_steps=c)
            for c in (len(th), 7, 1)]
    assert [r.chunks for r in runs] == [1, math.ceil(len(th) / 7), len(th)]
    ref = runs[0]
    assert ref.status == 0 and ref.newton_iterations > len(th)
    for r in runs[1:]:
        for a, b in zip(ref.samples, r.samples):
            assert np.array_equal(a, b)
        for a, b in zip(ref.state, r.state):
            assert np.array_equal(a, b)


class _Alarm(Exception):
    pass


def test_a_signal_handler_acts_within_a_second_during_a_long_simulation():
    model = model_for_tests()
    simulate(model, LoadSpec("sine", 300.0), duration_s=0.01)          # compiled and cached
    fired = []

    def handler(signum, frame):
        fired.append(time.perf_counter())
        raise _Alarm

    old = signal.signal(signal.SIGALRM, handler)
    try:
        t_due = time.perf_counter() + 1.0
        signal.setitimer(signal.ITIMER_REAL, 1.0)
        with pytest.raises(_Alarm):       # 30 s simulated take ~15 s of wall time: interrupted
            simulate(model, LoadSpec("sine", 300.0), duration_s=30.0, store_pin_forces=False)
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0.0)
        signal.signal(signal.SIGALRM, old)
    # Python runs the handler when the kernel returns (chunks of ~dynamics.model.CHUNK_WALL_S)
    assert 0.0 <= fired[0] - t_due < 1.0


def test_the_one_search_interpolation_of_a_law_table_is_np_interp_of_both_columns():
    law = np.column_stack([np.linspace(0.0, 180.0, 19), np.linspace(1e9, 3e9, 19) ** 1.1, np.linspace(1.1, 1.4, 19)])
    for x in np.concatenate([[-5.0, 0.0, 180.0, 200.0], np.random.default_rng(0).uniform(0.0, 180.0, 50)]):
        k, n, dk, dn = base.interp2(x, law)
        assert k == pytest.approx(np.interp(x, law[:, 0], law[:, 1]), rel=1e-14)
        assert n == pytest.approx(np.interp(x, law[:, 0], law[:, 2]), rel=1e-14)
        # the slopes: the segment's (0 where clamped), as a difference within the segment gives them
        h = 1e-3
        for col, d in ((1, dk), (2, dn)):
            fd = (np.interp(x + h, law[:, 0], law[:, col]) - np.interp(x - h, law[:, 0], law[:, col])) / (2 * h)
            if x < 0.0 or x > 180.0:
                assert d == 0.0
            elif min(abs(x - law[:, 0])) > h:
                assert d == pytest.approx(fd, rel=1e-6)


def test_the_assembly_of_a_model_compiles_once_for_every_solver():
    """Statics, a static path, the time integration, Python's own calls and the compliance budget's
    per-coupling tangents share one compiled `assemble` for a model: a literal want_k or only at a
    call site (typed Literal[...]) would compile the whole assembly again for each value (it tripled
    the kernel unit's cold compile), and so would a model of one coupling (5 more compiles)."""
    import numba
    from dynamics.budget import coupling_tangents
    from dynamics.statics import nominal_q, quasi_static
    model = model_for_tests()
    simulate(model, LoadSpec("sine", 300.0), duration_s=0.002, store_pin_forces=False)
    quasi_static(model, [0.0, 1.0, 2.0], 300.0)
    q = nominal_q(model, 0.0)
    evaluate(model, q, 0.0, want_k=True)
    coupling_tangents(model, q, 0.0)
    mine = [s for s in couplings.assemble.signatures if s[6] == numba.typeof(model.arrays)]
    assert len(mine) == 1, mine
    assert mine[0][5] == numba.types.boolean and mine[0][8] == numba.types.int64
