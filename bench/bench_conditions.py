"""Wall time of `conditions` over 50 rows (issue 21: <= 60 s on 2 cores). RV-160N case on
tests/support.py's closed-form stiffness (the FE stiffness is not needed for timing: the model has
the same DOFs and contacts), a table of 50 conditions spanning 100-1800 rpm, 0-1800 N m, 25-60 C,
run through the command line with --workers 2 (local processes), as `make all` runs it."""
from __future__ import annotations

import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROWS = 50
WORKERS = 2


def run() -> dict:
    root = Path(__file__).parents[1]
    sys.path.insert(0, str(root / "tests"))
    from support import stiffness_for_tests
    from fem.stiffness import save
    from geometry.params import load_case
    case_path = root / "cases" / "rv160n-81.toml"
    case = load_case(case_path)
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        save(stiffness_for_tests(case), tmp / "stiffness.json")
        speeds = (100, 300, 900, 1700, 1800)
        lines = ["input_speed_rpm,torque_Nm,oil_temperature_C"]
        for k in range(ROWS):
            lines.append(f"{speeds[k % 5]},{200 * (k // 5) % 2000},{(25, 40, 60)[k % 3]}")
        (tmp / "t.csv").write_text("\n".join(lines) + "\n")
        cmd = [sys.executable, "-m", "pipeline", "conditions", "--case", str(case_path), "--stiffness",
               str(tmp / "stiffness.json"), "--table", str(tmp / "t.csv"), "--out", str(tmp / "out"),
               "--workers", str(WORKERS), "--quiet"]
        env = dict(os.environ, OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1", MPLBACKEND="Agg")
        t0 = time.perf_counter()
        subprocess.run(cmd, check=True, capture_output=True, cwd=root, env=env)
        wall = time.perf_counter() - t0
    return {"rows": ROWS, "workers": WORKERS, "wall_s": wall, "requirement_s": 60.0, "meets": wall <= 60.0}
