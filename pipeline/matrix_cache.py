"""The load matrix's cell cache: one npz artifact per cell, reused when made from the same inputs.

Each task is a pure function of (case path, stiffness path, form, torque, duration) so it can run
in a local process or on Dask with identical results (pipeline.sweep.run_tasks).
Resumable: each cell is its own artifact, DIR/<form>_<T>.npz, holding its arrays, its summary and
the fingerprint of everything it was computed from (case and stiffness file content, form, torque,
duration, time step, and the source of the code that computes it). `run_matrix` reuses a cell whose
fingerprint matches and computes only the others, so an interrupted matrix resumes where it stopped
and a rerun with unchanged inputs computes nothing. Cells are written with fixed zip timestamps:
same inputs, same bytes. Wall times go to the log, never into an artifact.
The physics of a cell (its run and summary) is dynamics.matrix.run_cell.
"""
from __future__ import annotations

import functools
import hashlib
import json
import zipfile
from pathlib import Path
from typing import Callable, Sequence

import numpy as np

from dynamics.loads import PAPER_001_FORMS
from dynamics.matrix import TORQUES_NM

CELL_SCHEMA = "rv-matrix-cell/1"
_ROOT = Path(__file__).resolve().parent.parent
# the sources a cell's numbers come from (a change to any of them recomputes every cell)
CODE_SOURCES = ("dynamics/**/*.py", "geometry/**/*.py", "fem/stiffness.py", "pipeline/matrix_cache.py")


def cell_name(form: str, torque_Nm: float) -> str:
    return f"{form}_{int(round(torque_Nm))}"


@functools.lru_cache(maxsize=1)
def code_fingerprint() -> str:
    """sha256 of CODE_SOURCES and the numpy / numba versions."""
    import numba
    h = hashlib.sha256(f"numpy {np.__version__} numba {numba.__version__}".encode())
    for pattern in CODE_SOURCES:
        for path in sorted(_ROOT.glob(pattern)):
            h.update(str(path.relative_to(_ROOT)).encode() + b"\0" + path.read_bytes())
    return h.hexdigest()


def cell_fingerprint(case_path: str, stiffness_path: str, form: str, torque_Nm: float, duration_s: float,
                     dt_s: float | None) -> str:
    """sha256 of one cell's inputs: file contents (not paths), load, duration, step and the code."""
    def sha(path):
        return hashlib.sha256(Path(path).read_bytes()).hexdigest()
    blob = json.dumps({"schema": CELL_SCHEMA, "case_sha256": sha(case_path), "stiffness_sha256": sha(stiffness_path),
                       "form": form, "torque_Nm": float(torque_Nm), "duration_s": float(duration_s),
                       "dt_s": None if dt_s is None else float(dt_s), "code": code_fingerprint()}, sort_keys=True)
    return hashlib.sha256(blob.encode()).hexdigest()


def run_case(case_path: str, stiffness_path: str, form: str, torque_Nm: float, duration_s: float,
             out_dir: str, dt_s: float | None = None) -> dict:
    """Simulate one cell, write DIR/<form>_<T>.npz (arrays, summary, fingerprint); return the summary."""
    from dynamics.matrix import run_cell
    from dynamics.model import build_model
    from fem.stiffness import load as load_stiffness
    from geometry.params import load_case
    fingerprint = cell_fingerprint(case_path, stiffness_path, form, torque_Nm, duration_s, dt_s)
    model = build_model(load_case(case_path), load_stiffness(stiffness_path))
    name = cell_name(form, torque_Nm)
    out, arrays, spectrum = run_cell(model, form, torque_Nm, duration_s, dt_s, name)
    arrays.update(cell_fingerprint=np.array(fingerprint), cell_summary=np.array(json.dumps(out)))
    if spectrum is not None:
        arrays.update(spectrum_order=spectrum[0], spectrum_amplitude=spectrum[1])
    _save_npz(Path(out_dir) / f"{name}.npz", arrays)
    return {**out, "spectrum": spectrum}


def _save_npz(path: Path, arrays: dict) -> None:
    """np.savez_compressed with fixed zip timestamps (same arrays, same bytes), written atomically."""
    from geometry.artifacts import atomic_path
    with atomic_path(path) as tmp, zipfile.ZipFile(tmp, "w", zipfile.ZIP_DEFLATED) as zf:
        for key, value in arrays.items():
            info = zipfile.ZipInfo(f"{key}.npy", date_time=(1980, 1, 1, 0, 0, 0))
            info.compress_type = zipfile.ZIP_DEFLATED
            with zf.open(info, "w", force_zip64=True) as fh:
                np.lib.format.write_array(fh, np.asanyarray(value), allow_pickle=False)


def read_cell(out_dir: str | Path, name: str) -> dict:
    """The arrays of a finished cell DIR/<name>.npz."""
    with np.load(Path(out_dir) / f"{name}.npz", allow_pickle=False) as d:
        return {k: d[k] for k in d.files}


def finished_cell(out_dir: str | Path, form: str, torque_Nm: float, fingerprint: str) -> dict | None:
    """The summary of a cell already computed from exactly these inputs, else None."""
    path = Path(out_dir) / f"{cell_name(form, torque_Nm)}.npz"
    if not path.is_file():
        return None
    try:
        with np.load(path, allow_pickle=False) as d:
            if str(d["cell_fingerprint"]) != fingerprint:
                return None
            out = json.loads(str(d["cell_summary"]))
            out["spectrum"] = ((d["spectrum_order"], d["spectrum_amplitude"])
                               if "spectrum_order" in d.files else None)
    except (OSError, ValueError, KeyError, zipfile.BadZipFile):   # foreign, old or damaged: recompute
        return None
    return out


def run_matrix(case_path: str, stiffness_path: str, duration_s: float, out_dir: str, dt_s: float | None,
               runner: Callable[[Callable, Sequence[tuple]], list],
               forms: tuple[str, ...] = PAPER_001_FORMS) -> tuple[list[dict], int]:
    """Every cell (TORQUES_NM x forms, in that order): reused where finished, else computed through
    runner(run_case, tasks). Returns (summaries, number reused)."""
    cells = [(case_path, stiffness_path, form, T, duration_s, out_dir, dt_s) for T in TORQUES_NM for form in forms]
    results = [finished_cell(out_dir, c[2], c[3], cell_fingerprint(*c[:5], dt_s)) for c in cells]
    # highest torque first (more contacts, more Newton iterations): the pool ends on the short cells
    todo = sorted((i for i, r in enumerate(results) if r is None), key=lambda i: (-cells[i][3], i))
    for i, r in zip(todo, runner(run_case, [cells[i] for i in todo]) if todo else []):
        results[i] = r
    return results, len(cells) - len(todo)
