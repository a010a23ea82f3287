"""Paper 001's load-gradient x load-form matrix: 12 runs, sigma table, spectra (pure of plotting).

Each task is a pure function of (case path, stiffness path, form, torque, duration) so it can run
in a local process or on Dask with identical results (pipeline.sweep.run_tasks).
sigma is paper 001's population standard deviation of TE in two windows: (a) the steady part
t >= STEADY_FROM_S (after the 1 s speed ramp and the 1..2 s constant-load ramp; ours, physical,
the te_std.csv contract) and (b) the last full output revolution of the run (2.95..7 s at
88.89 deg/s: paper 001 analyses TE "for one rotation of the output flange", most likely this);
the whole-run sigma is kept too (it includes the ramps).

Resumable: each cell is its own artifact, DIR/<form>_<T>.npz, holding its arrays, its summary and
the fingerprint of everything it was computed from (case and stiffness file content, form, torque,
duration, time step, and the source of the code that computes it). `run_matrix` reuses a cell whose
fingerprint matches and computes only the others, so an interrupted matrix resumes where it stopped
and a rerun with unchanged inputs computes nothing. Cells are written with fixed zip timestamps:
same inputs, same bytes. Wall times go to the log, never into an artifact.
"""
from __future__ import annotations

import functools
import hashlib
import json
import zipfile
from pathlib import Path
from typing import Callable, Sequence

import numpy as np

from dynamics.loads import FORMS, LoadSpec

TORQUES_NM = (100.0, 200.0, 300.0, 400.0)
CELL_SCHEMA = "rv-matrix-cell/1"
_ROOT = Path(__file__).resolve().parent.parent
# the sources a cell's numbers come from (a change to any of them recomputes every cell)
CODE_SOURCES = ("dynamics/**/*.py", "geometry/**/*.py", "fem/stiffness.py")
STEADY_FROM_S = 2.0
# paper 001, standard-deviation table [arcsec]: rows 100..400 N m, columns constant, square, sine
PAPER_001_SIGMA_ARCSEC = np.array([[14.154, 14.056, 14.172],
                                   [14.695, 14.898, 15.416],
                                   [16.817, 17.312, 17.930],
                                   [19.196, 19.032, 19.485]])


def characteristic_orders(case) -> dict[str, float]:
    """Orders per output revolution named by mechanism (DESIGN.md)."""
    c, s = case.cycloid, case.stage1
    return {"carrier 1x": 1.0, f"cranks {case.carrier.crank_count}x": float(case.carrier.crank_count),
            "disc tooth zc": float(c.zc), "pin / crank rotation zp": float(c.zp),
            "input shaft i": float(case.ratio), "involute mesh zp*z2": float(c.zp * s.z2),
            "cycloid-pin mesh zp*zc": float(c.zp * c.zc)}


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
    from dynamics.model import build_model, simulate
    from dynamics.results import ResultError
    from fem.stiffness import load as load_stiffness
    from geometry.params import load_case
    fingerprint = cell_fingerprint(case_path, stiffness_path, form, torque_Nm, duration_s, dt_s)
    case = load_case(case_path)
    model = build_model(case, load_stiffness(stiffness_path))
    res = simulate(model, LoadSpec(form, torque_Nm), duration_s=duration_s, dt_s=dt_s,
                   store_pin_forces=False)
    name = cell_name(form, torque_Nm)
    steady = res.t_s >= STEADY_FROM_S
    out = {"form": form, "torque_Nm": torque_Nm, "name": name,
           "sigma_arcsec": res.std_arcsec(STEADY_FROM_S) if steady.any() else float("nan"),
           "sigma_whole_arcsec": res.std_arcsec(),
           "sigma_last_rev_arcsec": _or_nan(res.std_last_revolution_arcsec), "mean_te_arcsec": float(res.te_arcsec[steady].mean())
           if steady.any() else float("nan"),
           "teeth_in_contact_mean": float(res.teeth_in_contact[steady].mean()) if steady.any() else float("nan"),
           "newton_per_step": res.meta["newton_per_step"], "dt_s": res.meta["dt_s"]}
    try:
        sp = res.spectrum(STEADY_FROM_S)
        spectrum = (sp.order, sp.amplitude)
        out["lines"] = {k: sp.at(o) for k, o in characteristic_orders(case).items()}
    except ResultError:   # shorter than one output revolution (short test runs): no spectrum
        spectrum = None
        out["lines"] = {}
    arrays = dict(t_s=res.t_s, input_angle_deg=res.input_angle_deg, output_angle_deg=res.output_angle_deg,
                  output_torque_Nm=res.output_torque_Nm, te_arcsec=res.te_arcsec,
                  teeth_in_contact=res.teeth_in_contact, cell_fingerprint=np.array(fingerprint),
                  cell_summary=np.array(json.dumps(out)))
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
               runner: Callable[[Callable, Sequence[tuple]], list]) -> tuple[list[dict], int]:
    """Every cell (TORQUES_NM x FORMS, in that order): reused where finished, else computed through
    runner(run_case, tasks). Returns (summaries, number reused)."""
    cells = [(case_path, stiffness_path, form, T, duration_s, out_dir, dt_s) for T in TORQUES_NM for form in FORMS]
    results = [finished_cell(out_dir, c[2], c[3], cell_fingerprint(*c[:5], dt_s)) for c in cells]
    # highest torque first (more contacts, more Newton iterations): the pool ends on the short cells
    todo = sorted((i for i, r in enumerate(results) if r is None), key=lambda i: (-cells[i][3], i))
    for i, r in zip(todo, runner(run_case, [cells[i] for i in todo]) if todo else []):
        results[i] = r
    return results, len(cells) - len(todo)


def _or_nan(fn) -> float:
    from dynamics.results import ResultError
    try:
        return fn()
    except ResultError:     # a short run (tests) has no full output revolution
        return float("nan")


def sigma_table(results: list[dict], key: str = "sigma_arcsec") -> np.ndarray:
    """(4, 3) table, rows TORQUES_NM, columns FORMS."""
    tab = np.full((len(TORQUES_NM), len(FORMS)), np.nan)
    for r in results:
        tab[TORQUES_NM.index(r["torque_Nm"]), FORMS.index(r["form"])] = r[key]
    return tab


# ---------------------------------------------------------------- paper 001's TE definition

PAPER_001_STEP_S = 0.01    # 700 output steps over 7 s (100 Hz)


def paper001_te(t_s, input_angle_deg, output_angle_deg, ratio: float, step_s: float = PAPER_001_STEP_S):
    """Paper 001's TE on our run: dphi(t_k) = (omega_out - omega_in / i)(t_k) * dt at its output steps
    t_k = k dt (k = 1, 2, ...), speeds at those instants (central differences of our record, which
    scale a line at f by sin(2 pi f h) / (2 pi f h), h its spacing: 0.77 at 385 Hz, h = 0.5 ms).
    Returns (t_k, per-step dphi [arcsec], its running sum [arcsec]): the formula as printed is the
    per-step figure; summed it would be theta_out - theta_in / i sampled at 100 Hz."""
    t = np.asarray(t_s, float)
    w_out, w_in = np.gradient(np.asarray(output_angle_deg, float), t), np.gradient(np.asarray(input_angle_deg, float), t)
    tk = np.arange(1, int(np.floor(t[-1] / step_s + 1e-9)) + 1) * step_s
    step = (np.interp(tk, t, w_out) - np.interp(tk, t, w_in) / ratio) * step_s * 3600.0
    return tk, step, np.cumsum(step)


def last_rev_window(t_k, t_s, output_angle_deg) -> np.ndarray:
    """Mask of the samples t_k inside the last full output revolution of the record."""
    out = np.asarray(output_angle_deg, float)
    travel = np.abs(out - out[-1])
    if travel.max() < 360.0:
        return np.zeros(len(t_k), bool)
    return np.asarray(t_k) >= t_s[np.flatnonzero(travel >= 360.0)[-1]]


def paper001_sigmas(npz_path, ratio: float) -> dict:
    """sigma [arcsec] of one matrix cell, last output revolution: ours (theta_out - theta_in / i on the
    record), paper 001's per-step dphi at 100 Hz, and its running sum at 100 Hz."""
    with np.load(npz_path, allow_pickle=False) as d:
        t, th_in, th_out, te = d["t_s"], d["input_angle_deg"], d["output_angle_deg"], d["te_arcsec"]
    tk, step, summed = paper001_te(t, th_in, th_out, ratio)
    last = last_rev_window(tk, t, th_out)
    ours = last_rev_window(t, t, th_out)
    nan = float("nan")
    return {"ours_theta_last_rev": float(np.std(te[ours])) if ours.any() else nan,
            "paper_step_last_rev": float(np.std(step[last])) if last.any() else nan,
            "paper_summed_last_rev": float(np.std(summed[last])) if last.any() else nan,
            "output_rev_per_s": float(np.median(np.gradient(th_out, t)[t >= STEADY_FROM_S]) / 360.0)
            if (t >= STEADY_FROM_S).any() else nan}


def aliasing(case, output_rev_per_s: float, step_s: float = PAPER_001_STEP_S) -> list[dict]:
    """Where each characteristic order shows up when sampled at 1 / step_s, and how paper 001's
    speed-based dphi weighs a TE line of that order: amplitude x 2 pi f dt per step (a derivative),
    and x ~ f / f_apparent once summed (the sum integrates the aliased line)."""
    fs = 1.0 / step_s
    rows = []
    for name, k in characteristic_orders(case).items():
        f = k * output_rev_per_s
        fa = abs(f - fs * round(f / fs))
        rows.append({"mechanism": name, "order": k, "frequency_Hz": f, "apparent_Hz": fa,
                     "apparent_order": fa / output_rev_per_s if output_rev_per_s > 0 else float("nan"),
                     "step_gain": 2 * np.pi * f * step_s,
                     "summed_gain": (2 * np.pi * f * step_s) / (2 * np.sin(np.pi * fa * step_s)) if fa > 0 else float("inf")})
    return rows
