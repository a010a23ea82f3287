"""The FE stage of one case (issue 24 item 2: <= 45 s on 2 cores) over ONE sparse factorization of its
largest mesh (the carrier's fine level: P2 elasticity, mounting face clamped, the Cholesky of fem.sparse_fe.spd_solve),
measured in one run; the stage's own per-problem timings (stiffness.json extras) beside it.
Reuses build/<case>/mesh/ when it exists, else makes the mesh first (not timed).
Run: .venv/bin/python bench/bench_fem_stage.py [CASE_NAME]"""
from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))


def _stage(args, env) -> float:
    t0 = time.perf_counter()
    subprocess.run([sys.executable, "-m", "pipeline", *args, "--quiet"], cwd=ROOT, env=env, check=True,
                   capture_output=True, text=True)
    return time.perf_counter() - t0


def largest_mesh_factorization(case) -> dict:
    """One factorization (and one solve) of the carrier's fine-level stiffness, the face clamped."""
    import numpy as np
    from skfem import Basis, ElementTetP2, ElementVector, MeshTet
    from fem import carrier as fc
    g = fc.case_geometry(case)
    h = fc.DEFAULT_LEVELS[-1] * g.pillar_radius_mm * 1e-3
    m3, _ = fc.carrier_mesh(g, h)
    msk = MeshTet(np.ascontiguousarray(m3.points.T), np.ascontiguousarray(m3.tetrahedra.T))
    basis = Basis(msk, ElementVector(ElementTetP2()), intorder=2)
    K = fc.elasticity_matrix(msk, ElementTetP2(), basis, case.material.youngs_modulus_GPa * 1e9,
                             case.material.poisson_ratio)
    zf = g.mounting_face_z_mm * 1e-3
    fixed = basis.get_dofs(msk.facets_satisfying(lambda x: x[2] > zf - 0.02 * h, boundaries_only=True)).all()
    free = np.setdiff1d(np.arange(basis.N), fixed)
    Kf = K[free][:, free]
    t0 = time.perf_counter()
    fc.spd_solve(Kf, np.ones((len(free), 1)))
    return {"largest_mesh": "carrier, fine level", "largest_mesh_dofs": int(len(free)),
            "one_factorization_s": time.perf_counter() - t0}


def run(case_name: str = "rv40e-81") -> dict:
    from geometry.params import load_case
    case_file = ROOT / "cases" / f"{case_name}.toml"
    env = dict(os.environ, MPLBACKEND="Agg", PYVISTA_OFF_SCREEN="true", OPENBLAS_NUM_THREADS="1",
               OMP_NUM_THREADS="1")
    with tempfile.TemporaryDirectory() as tmp:
        mesh = ROOT / "build" / case_name / "mesh"
        if not (mesh / "crankshaft_mesh.npz").exists():
            mesh = Path(tmp) / "mesh"
            _stage(["mesh", "--case", str(case_file), "--out", str(mesh)], env)
        stage_s = _stage(["fem", "--case", str(case_file), "--mesh", str(mesh), "--out", str(Path(tmp) / "fem")], env)
        timing = json.loads((Path(tmp) / "fem" / "timings.json").read_text())["wall_s"]
    out = {"case": case_name, "workers": os.cpu_count(), "fem_stage_s": stage_s, "problems_s": timing}
    try:
        out.update(largest_mesh_factorization(load_case(case_file)))
        out["fem_stage_over_one_factorization"] = stage_s / out["one_factorization_s"]
    except Exception as exc:   # noqa: BLE001 - the carrier's internals may move; the stage figure stands
        out["one_factorization_error"] = f"{type(exc).__name__}: {exc}"
    return out


if __name__ == "__main__":
    print(json.dumps(run(*sys.argv[1:]), indent=1))
