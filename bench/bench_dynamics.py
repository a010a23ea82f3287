"""Dynamics speed figures (issue 4 item 7): simulated seconds per wall second for one 7 s case,
the longest stretch the numba kernel keeps Python waiting (issue 10: signals act between kernel
calls), and the wall time of the 12-case matrix on local processes. Uses the test stand-in stiffness
unless build/<case>/fem/stiffness.json exists. Run: .venv/bin/python bench/bench_dynamics.py"""
from __future__ import annotations

import json
import resource
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path[:0] = [str(ROOT), str(ROOT / "tests")]


def _children_cpu_s() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def run(case_name: str = "rv40e-81", matrix: bool = True) -> dict:
    from dynamics.loads import LoadSpec
    from dynamics.model import build_model, simulate
    from fem.stiffness import load, save
    from geometry.params import load_case
    from support import stiffness_for_tests
    case = load_case(ROOT / "cases" / f"{case_name}.toml")
    fe = ROOT / "build" / case_name / "fem" / "stiffness.json"
    stiff = load(fe) if fe.exists() else stiffness_for_tests(case)
    model = build_model(case, stiff)
    simulate(model, LoadSpec("sine", 300.0), duration_s=0.05)          # compile / load the numba cache
    t0, c0 = time.perf_counter(), time.process_time()
    res = simulate(model, LoadSpec("sine", 300.0), duration_s=7.0, store_pin_forces=False)
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    out = {"case": case_name, "stiffness": "FE" if fe.exists() else "test stand-in",
           "dt_s": res.meta["dt_s"], "one_case_wall_s": wall, "sim_s_per_wall_s": 7.0 / wall,
           "one_case_cpu_s": cpu,   # CPU time: the figure to compare on a shared machine
           "newton_per_step": res.meta["newton_per_step"],
           # Python regains control between kernel calls (signals act there): their count, longest
           "kernel_calls": res.meta.get("kernel_calls"), "max_kernel_call_s": res.meta.get("max_kernel_call_s")}
    if matrix:
        from pipeline.cli import main
        with tempfile.TemporaryDirectory() as tmp:
            path = Path(tmp) / "stiffness.json"
            save(stiff, path)
            t0, c0 = time.perf_counter(), _children_cpu_s()
            out["matrix_exit_code"] = main(["matrix", "--case", str(case.source), "--stiffness", str(path), "--out", tmp, "--quiet"])
            out["matrix_wall_s"] = time.perf_counter() - t0
            out["matrix_worker_cpu_s"] = _children_cpu_s() - c0   # the local worker processes
            if out["matrix_exit_code"] == 0:
                out["te_std_csv"] = (Path(tmp) / "te_std.csv").read_text()
                out["comparison_md"] = (Path(tmp) / "comparison.md").read_text()
    return out


if __name__ == "__main__":
    print(json.dumps(run(), indent=1))
