"""Run every bench/bench_*.py `run()` and the pipeline timings; write one JSON (make bench).

Figures are measured in one run on this machine; ratios (not absolute seconds) are what compare
across machines. `--skip-make` leaves out the full `make all` from clean (it takes minutes).
"""
from __future__ import annotations

import argparse
import importlib.util
import platform
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from geometry.artifacts import write_json_atomic  # noqa: E402


def _bench_modules():
    for path in sorted((ROOT / "bench").glob("bench_*.py")):
        spec = importlib.util.spec_from_file_location(path.stem, path)
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
        yield path.stem, module


def _make_timings(case: str) -> dict:
    """Wall time of `make all` for one case from a clean build folder (each stage timed through
    bench/stage_timer.py as Make's RUN: make's own share is the whole over the sum of the stages),
    then of the no-op rerun. The kernels come from the project's cache (compiled once per machine)."""
    with tempfile.TemporaryDirectory() as build:
        log = Path(build) / "stages.log"
        run = f"{sys.executable} {ROOT / 'bench' / 'stage_timer.py'} {log}"
        cmd = ["make", "-C", str(ROOT), "all", f"CASE=cases/{case}.toml", f"BUILD={build}", "Q=--quiet",
               f"PY={sys.executable}", "-o", ".venv/.installed"]
        t0 = time.perf_counter()
        subprocess.run([*cmd, f"RUN={run}"], check=True, capture_output=True)
        full = time.perf_counter() - t0
        stages: dict[str, float] = {}
        for line in log.read_text().splitlines():
            name, seconds = line.split()
            stages[name] = stages.get(name, 0.0) + float(seconds)
        t0 = time.perf_counter()
        subprocess.run(cmd, check=True, capture_output=True)
        noop = time.perf_counter() - t0
    return {"case": case, "make_all_from_clean_s": full, "make_all_noop_s": noop,
            "noop_over_full_ratio": noop / full, "stages_s": stages, "sum_of_stages_s": sum(stages.values()),
            "make_all_over_sum_of_stages": full / sum(stages.values())}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--out", default=str(ROOT / "build" / "bench.json"))
    ap.add_argument("--skip-make", action="store_true")
    ap.add_argument("--case", default="rv40e-81", help="case timed by the make-all figure")
    args = ap.parse_args()
    result = {"machine": {"cpus": os.cpu_count(), "python": platform.python_version(),
                          "platform": platform.platform()}}
    for name, module in _bench_modules():
        t0 = time.perf_counter()
        print(f"bench: {name} ...", flush=True)
        try:
            result[name] = module.run()
        except Exception as exc:  # a broken benchmark is reported, the others still run
            result[name] = {"error": f"{type(exc).__name__}: {exc}"}
        result[name]["bench_wall_s"] = time.perf_counter() - t0
    if not args.skip_make:
        result["make"] = _make_timings(args.case)
    write_json_atomic(args.out, result)
    print(f"bench: wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
