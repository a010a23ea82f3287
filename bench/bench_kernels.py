"""Numba kernel cache (issue 24 item 1): the first dynamics call of a process on a cold cache (compile)
and on a warm one (load), and the 12-case matrix of one case cold and warm; each in fresh processes
on its own empty cache folder ($RVTE_KERNEL_CACHE), so the project's cache is neither used nor
touched. Ratios cold / warm. Uses build/<case>/fem/stiffness.json when it exists, else the test
stand-in. Run: .venv/bin/python bench/bench_kernels.py [--no-matrix]"""
from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

FIRST_CALL = """
import sys, time
sys.path[:0] = [{root!r}, {tests!r}]
from dynamics.loads import LoadSpec
from dynamics.model import build_model, simulate
from fem.stiffness import load
from geometry.params import load_case
case = load_case({case!r})
model = build_model(case, load({stiffness!r}))
t0 = time.perf_counter()
simulate(model, LoadSpec("sine", 300.0), duration_s=0.01, store_pin_forces=False)
print(time.perf_counter() - t0)
"""


def _stiffness(case_name: str, tmp: Path) -> tuple[Path, str]:
    fe = ROOT / "build" / case_name / "fem" / "stiffness.json"
    if fe.exists():
        return fe, "FE"
    sys.path[:0] = [str(ROOT), str(ROOT / "tests")]
    from fem.stiffness import save
    from geometry.params import load_case
    from support import stiffness_for_tests
    path = tmp / "stiffness.json"
    save(stiffness_for_tests(load_case(ROOT / "cases" / f"{case_name}.toml")), path)
    return path, "test stand-in"


def _run(argv, cache: Path) -> tuple[float, str]:
    env = dict(os.environ, RVTE_KERNEL_CACHE=str(cache), MPLBACKEND="Agg")
    t0 = time.perf_counter()
    r = subprocess.run(argv, cwd=ROOT, env=env, capture_output=True, text=True, check=True)
    return time.perf_counter() - t0, r.stdout


def run(case_name: str = "rv40e-81", matrix: bool = True) -> dict:
    case = ROOT / "cases" / f"{case_name}.toml"
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        stiffness, kind = _stiffness(case_name, tmp)
        code = FIRST_CALL.format(root=str(ROOT), tests=str(ROOT / "tests"), case=str(case), stiffness=str(stiffness))
        first = [float(_run([sys.executable, "-c", code], tmp / "calls")[1]) for _ in range(2)]
        out = {"case": case_name, "stiffness": kind, "first_call_cold_s": first[0], "first_call_warm_s": first[1],
               "first_call_cold_over_warm": first[0] / first[1]}
        if matrix:
            walls = []
            for name in ("cold", "warm"):
                argv = [sys.executable, "-m", "pipeline", "matrix", "--case", str(case), "--stiffness", str(stiffness),
                        "--out", str(tmp / f"matrix_{name}"), "--quiet"]
                walls.append(_run(argv, tmp / "matrix")[0])
            out.update(matrix_cold_s=walls[0], matrix_warm_s=walls[1], matrix_cold_over_warm=walls[0] / walls[1])
    return out


if __name__ == "__main__":
    print(json.dumps(run(matrix="--no-matrix" not in sys.argv), indent=1))
