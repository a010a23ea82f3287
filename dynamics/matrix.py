"""Paper 001's load-gradient x load-form matrix: 12 runs, sigma table, spectra (pure of plotting).

Each task is a pure function of (case path, stiffness path, form, torque, duration) so it can run
in a local process or on Dask with identical results (pipeline.sweep.run_tasks).
sigma is paper 001's population standard deviation of TE in two windows: (a) the steady part
t >= STEADY_FROM_S (after the 1 s speed ramp and the 1..2 s constant-load ramp; ours, physical,
the te_std.csv contract) and (b) the last full output revolution of the run (2.95..7 s at
88.89 deg/s: paper 001 analyses TE "for one rotation of the output flange", most likely this);
the whole-run sigma is kept too (it includes the ramps).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from dynamics.loads import FORMS, LoadSpec

TORQUES_NM = (100.0, 200.0, 300.0, 400.0)
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


def run_case(case_path: str, stiffness_path: str, form: str, torque_Nm: float, duration_s: float,
             out_dir: str, dt_s: float | None = None) -> dict:
    """Simulate one cell, write DIR/<form>_<T>.npz and return its summary."""
    from dynamics.model import build_model, simulate
    from fem.stiffness import load as load_stiffness
    from geometry.artifacts import atomic_path
    from geometry.params import load_case
    case = load_case(case_path)
    model = build_model(case, load_stiffness(stiffness_path))
    import time
    t0 = time.perf_counter()
    res = simulate(model, LoadSpec(form, torque_Nm), duration_s=duration_s, dt_s=dt_s,
                   store_pin_forces=False)
    wall = time.perf_counter() - t0
    name = f"{form}_{int(round(torque_Nm))}"
    with atomic_path(Path(out_dir) / f"{name}.npz") as tmp:
        with open(tmp, "wb") as fh:
            np.savez_compressed(fh, t_s=res.t_s, input_angle_deg=res.input_angle_deg,
                                output_angle_deg=res.output_angle_deg, output_torque_Nm=res.output_torque_Nm,
                                te_arcsec=res.te_arcsec, teeth_in_contact=res.teeth_in_contact)
    steady = res.t_s >= STEADY_FROM_S
    out = {"form": form, "torque_Nm": torque_Nm, "name": name, "wall_s": wall,
           "sigma_arcsec": res.std_arcsec(STEADY_FROM_S) if steady.any() else float("nan"),
           "sigma_whole_arcsec": res.std_arcsec(),
           "sigma_last_rev_arcsec": _or_nan(res.std_last_revolution_arcsec), "mean_te_arcsec": float(res.te_arcsec[steady].mean())
           if steady.any() else float("nan"),
           "teeth_in_contact_mean": float(res.teeth_in_contact[steady].mean()) if steady.any() else float("nan"),
           "newton_per_step": res.meta["newton_per_step"], "dt_s": res.meta["dt_s"]}
    try:
        sp = res.spectrum(STEADY_FROM_S)
        out["spectrum"] = (sp.order, sp.amplitude)
        out["lines"] = {k: sp.at(o) for k, o in characteristic_orders(case).items()}
    except Exception:   # shorter than one output revolution (short test runs): no spectrum
        out["spectrum"] = None
        out["lines"] = {}
    return out


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
