"""FEM benchmark: full tooth-pin stiffness map wall time over one sparse factorization of the
same 2D disc mesh (target <= 3), plus the Hertz benchmark time. `python bench/bench_fem.py`."""
from __future__ import annotations

import json
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))


def run(case_path: str | Path = ROOT / "cases" / "rv40e-105.toml") -> dict:
    import numpy as np
    from fem import elastic
    from fem.pin_contact import hertz_benchmark, tooth_pair_map
    from geometry.params import load_case
    case = load_case(case_path)
    t0 = time.perf_counter()
    tm = tooth_pair_map(case)
    total = time.perf_counter() - t0
    K = elastic.stiffness(elastic.basis_2d(tm.disc_mesh), case.material.youngs_modulus_GPa * 1e9,
                          case.material.poisson_ratio)
    fixed = tm.disc_mesh.boundary["inner"]
    one = elastic.Factorized.of(K, np.concatenate([2 * fixed, 2 * fixed + 1])).factor_seconds
    t1 = time.perf_counter()
    hertz_benchmark(3e-3, 10e-3, 1000.0)
    return {"case": case.name, "map_points": int(tm.approach_m.size), "disc_dofs": int(K.shape[0]),
            "map_wall_s": total, "map_wall_without_meshing_s": total - tm.timing_s["mesh_s"],
            "one_factorization_s": one, "ratio": total / one,
            "ratio_without_meshing": (total - tm.timing_s["mesh_s"]) / one,
            "timing_s": tm.timing_s, "hertz_benchmark_s": time.perf_counter() - t1}


if __name__ == "__main__":
    print(json.dumps(run(*sys.argv[1:]), indent=1))
