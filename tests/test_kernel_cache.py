"""The kernel cache (dynamics.kernel_cache) on a toy unit of two files, in fresh processes: a caller
in one file inlines a callee from another (as the solvers inline the couplings). Editing the callee
must recompile the caller (numba's own cache=True serves the stale caller: shown beside it), a
rerun must load instead of compiling (even while another process holds the compile lock), and
processes starting together on a cold cache compile once."""
import fcntl
import json
import os
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

CALLEE = "VALUE = {value}\n\n\ndef callee(x):\n    return x + VALUE\n"
UNIT = """
from pathlib import Path
from dynamics.kernel_cache import KernelUnit
HERE = Path(__file__).resolve().parent
UNIT = KernelUnit([HERE / "toy_callee.py", HERE / "toy_caller.py"], root=HERE / "cache")
"""
CALLER = """
import numba
from toy_unit import UNIT
import toy_callee

callee = UNIT.kernel(toy_callee.callee, inline=True)
plain_callee = numba.njit(inline="always")(toy_callee.callee)


@UNIT.kernel
def caller(x):
    return callee(x) * 2.0


@numba.njit(cache=True)
def plain_caller(x):        # numba's own cache, in NUMBA_CACHE_DIR
    return plain_callee(x) * 2.0
"""
RUN = """
import json, sys, time
start = float(sys.argv[1])
import toy_caller as m
while time.time() < start:
    time.sleep(0.005)
out = {"unit": m.caller(1.0), "plain": m.plain_caller(1.0)}
out["compiled"] = sum(m.caller.stats.cache_misses.values())
out["loaded"] = sum(m.caller.stats.cache_hits.values())
print(json.dumps(out))
"""


def _write(folder: Path, value: float) -> None:
    (folder / "toy_callee.py").write_text(CALLEE.format(value=value))
    (folder / "toy_unit.py").write_text(UNIT)
    (folder / "toy_caller.py").write_text(CALLER)
    (folder / "run.py").write_text(RUN)


def _start(folder: Path, start: float) -> subprocess.Popen:
    env = {**os.environ, "PYTHONPATH": f"{folder}{os.pathsep}{ROOT}", "NUMBA_CACHE_DIR": str(folder / "plain")}
    env.pop("NUMBA_CACHE_LOCATOR_CLASSES", None)
    return subprocess.Popen([sys.executable, str(folder / "run.py"), repr(start)], cwd=folder, env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def _results(procs) -> list[dict]:
    out = []
    for p in procs:
        stdout, stderr = p.communicate(timeout=300)
        assert p.returncode == 0, stderr
        out.append(json.loads(stdout.strip().splitlines()[-1]))
    return out


def test_an_edited_inlined_callee_recompiles_its_caller_and_a_rerun_loads(tmp_path):
    _write(tmp_path, 1.0)
    first, = _results([_start(tmp_path, 0.0)])
    assert first == {"unit": 4.0, "plain": 4.0, "compiled": 1, "loaded": 0}
    again, = _results([_start(tmp_path, 0.0)])
    assert again == {"unit": 4.0, "plain": 4.0, "compiled": 0, "loaded": 1}
    # a kernel on disk loads while another process holds the compile lock (compiling something else)
    folder, = [d for d in (tmp_path / "cache").iterdir() if d.is_dir()]
    with open(folder / "compile.lock", "a+b") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        held, = _results([_start(tmp_path, 0.0)])
    assert held == again
    (tmp_path / "toy_callee.py").write_text(CALLEE.format(value=5.0))
    edited, = _results([_start(tmp_path, 0.0)])
    # the unit recompiles; numba's own cache keeps the caller compiled with the old callee
    assert edited == {"unit": 12.0, "plain": 4.0, "compiled": 1, "loaded": 0}
    assert len([d for d in (tmp_path / "cache").iterdir() if d.is_dir()]) == 2


def test_processes_starting_together_on_a_cold_cache_compile_once(tmp_path):
    _write(tmp_path, 1.0)
    start = time.time() + 8.0          # after every process has imported numba: they call together
    runs = _results([_start(tmp_path, start) for _ in range(3)])
    assert [r["unit"] for r in runs] == [4.0] * 3
    assert sorted(r["compiled"] for r in runs) == [0, 0, 1]
    assert sorted(r["loaded"] for r in runs) == [0, 1, 1]


@pytest.mark.parametrize("value", ["", "relative/path"])
def test_the_cache_folder_follows_the_environment(monkeypatch, tmp_path, value):
    from dynamics import kernel_cache
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv(kernel_cache.ENV, value)
    root = kernel_cache.cache_root()
    if value:
        assert root == (tmp_path / value).resolve()
    else:
        assert root == ROOT / "build" / ".kernel-cache"
    assert textwrap.dedent(kernel_cache.__doc__).count(kernel_cache.ENV) == 1


def test_a_kernel_outside_its_units_sources_is_refused(tmp_path):
    """Its cache would carry the unit's digest, which does not cover its code: an edit would keep
    serving the old machine code (dynamics/losses/contacts.py's kernel was such a case)."""
    from dynamics.couplings import base
    from dynamics.kernel_cache import KernelUnit
    (tmp_path / "inside.py").write_text("def f(x):\n    return x\n")

    def g(x):
        return x
    unit = KernelUnit([tmp_path / "inside.py"], root=tmp_path / "cache")
    with pytest.raises(ValueError, match="not one of its unit's sources"):
        unit.kernel(g)
    # every file of the project that defines a unit kernel is in the unit (they imported above)
    import dynamics.kernels  # noqa: F401
    import dynamics.losses.contacts  # noqa: F401
    assert {"contacts.py", "kernels.py", "pin_profile.py"} <= {p.name for p in base.KERNEL_SOURCES}
