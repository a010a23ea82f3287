"""Compile the dynamics kernel unit into its on-disk cache (dynamics.kernel_cache), once per machine:
`make install` runs it, so neither the first stage of `make all` nor the test workers pay the
compile (60-90 s a process on the 2-core machine).

numba caches a kernel per argument types, not values: the closed-form test stand-in's model
(tests/support.py, no FE needed at install time) has the same numba types as a model of any case's
FE stiffness (checked in tests/test_fem_shaft.py on an FE run), so the machine code it compiles is what the
pipeline loads. Every solver path is called once (time integration, statics, a static path, the
budget's per-coupling tangents, the contact friction); a kernel of the unit left uncompiled is
reported (exit 1), so a new solver entry that this script misses cannot go unnoticed.

Run: .venv/bin/python tests/warm_kernels.py
"""
from __future__ import annotations

import sys
import time
from pathlib import Path

sys.path[:0] = [str(Path(__file__).resolve().parent.parent), str(Path(__file__).resolve().parent)]


def warm() -> list[str]:
    """Call every solver path once on the stand-in model; returns the unit's kernels still uncompiled."""
    import numba
    from dynamics import kernels
    from dynamics.budget import coupling_tangents
    from dynamics.couplings import assemble, base, start_solve
    from dynamics.loads import LoadSpec
    from dynamics.losses import contacts
    from dynamics.losses.lubricant import Lubricant
    from dynamics.losses.operating import starting_torque_Nm
    from dynamics.model import simulate
    from dynamics.reducer import evaluate
    import numpy as np
    from dynamics.statics import nominal_q, quasi_static, solve_static, static_path
    from support import model_for_tests
    model = model_for_tests()
    simulate(model, LoadSpec("sine", 300.0), duration_s=0.002, store_pin_forces=False)
    quasi_static(model, [0.0, 1.0, 2.0], 300.0)
    th, T = np.deg2rad([0.0, 1.0]), np.array([300.0, 300.0])
    static_path(model, th, T, seeds=static_path(model, th, T)[1])   # the diagnosis' seeded path
    solve_static(model, 0.5, 100.0)
    q = nominal_q(model, 0.0)
    evaluate(model, q, 0.0, want_k=True)
    coupling_tangents(model, q, 0.0)
    starting_torque_Nm(model, Lubricant.from_section(model.case.lubrication), 40.0)
    disps = [assemble, start_solve, contacts._pin_frames] + [getattr(kernels, n) for n in
                                                ("static_solve", "static_seeded", "static_advance",
                                                 "integrate_start", "integrate")]
    assert all(isinstance(d, numba.core.registry.CPUDispatcher) for d in disps)
    return [d.py_func.__qualname__ for d in disps if not d.signatures] \
        + ([] if base.UNIT.cache_dir.is_dir() else [f"(no cache folder {base.UNIT.cache_dir})"])


if __name__ == "__main__":
    t0 = time.perf_counter()
    missing = warm()
    from dynamics.couplings.base import UNIT
    if missing:
        print(f"warm_kernels: not compiled: {', '.join(missing)}", file=sys.stderr)
        sys.exit(1)
    print(f"warm_kernels: the dynamics kernels are compiled in {UNIT.cache_dir} ({time.perf_counter() - t0:.0f} s)")
