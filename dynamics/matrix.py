"""Paper 001's load-gradient x load-form matrix: one cell's run and summary, sigma tables, paper 001's
TE definition (pure of files and plotting; the cell cache and its npz artifacts: pipeline.matrix_cache).

sigma is paper 001's population standard deviation of TE in two windows: (a) the steady part
t >= STEADY_FROM_S (after the 1 s speed ramp and the 1..2 s constant-load ramp; ours, physical,
the te_std.csv contract) and (b) the last full output revolution of the run (2.95..7 s at
88.89 deg/s: paper 001 analyses TE "for one rotation of the output flange", most likely this);
the whole-run sigma is kept too (it includes the ramps). The forms are dynamics.loads' table:
paper 001's three by default, any other by name, its paper figure read from its own entry.
"""
from __future__ import annotations

import numpy as np

from dynamics.loads import PAPER_001_FORMS, LoadSpec, load_form

TORQUES_NM = (100.0, 200.0, 300.0, 400.0)
STEADY_FROM_S = 2.0


def paper001_sigma_arcsec(form: str, torque_Nm: float) -> float | None:
    """Paper 001's sigma [arcsec] of this form at this load gradient, None where it has no figure."""
    column = load_form(form).paper001_sigma_arcsec
    return None if column is None else column.get(float(torque_Nm))


def characteristic_orders(case) -> dict[str, float]:
    """Orders per output revolution named by mechanism (DESIGN.md)."""
    c, s = case.cycloid, case.stage1
    return {"carrier 1x": 1.0, f"cranks {case.carrier.crank_count}x": float(case.carrier.crank_count),
            "disc tooth zc": float(c.zc), "pin / crank rotation zp": float(c.zp),
            "input shaft i": float(case.ratio), "involute mesh zp*z2": float(c.zp * s.z2),
            "cycloid-pin mesh zp*zc": float(c.zp * c.zc)}


def run_cell(model, form: str, torque_Nm: float, duration_s: float, dt_s: float | None = None,
             name: str = "") -> tuple[dict, dict, tuple | None]:
    """Simulate one cell: (summary, arrays of the run, spectrum (order, amplitude) or None)."""
    from dynamics.model import simulate
    from dynamics.results import ResultError
    res = simulate(model, LoadSpec(form, torque_Nm), duration_s=duration_s, dt_s=dt_s,
                   store_pin_forces=False)
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
        out["lines"] = {k: sp.at(o) for k, o in characteristic_orders(model.case).items()}
    except ResultError:   # shorter than one output revolution (short test runs): no spectrum
        spectrum = None
        out["lines"] = {}
    arrays = dict(t_s=res.t_s, input_angle_deg=res.input_angle_deg, output_angle_deg=res.output_angle_deg,
                  output_torque_Nm=res.output_torque_Nm, te_arcsec=res.te_arcsec,
                  teeth_in_contact=res.teeth_in_contact)
    return out, arrays, spectrum


def _or_nan(fn) -> float:
    from dynamics.results import ResultError
    try:
        return fn()
    except ResultError:     # a short run (tests) has no full output revolution
        return float("nan")


def sigma_table(results: list[dict], key: str = "sigma_arcsec", forms: tuple[str, ...] = PAPER_001_FORMS) -> np.ndarray:
    """(torques, forms) table, rows TORQUES_NM, columns `forms` (by name)."""
    tab = np.full((len(TORQUES_NM), len(forms)), np.nan)
    for r in results:
        tab[TORQUES_NM.index(r["torque_Nm"]), forms.index(r["form"])] = r[key]
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


def paper001_sigmas(t, th_in, th_out, te, ratio: float) -> dict:
    """sigma [arcsec] of one matrix cell's run (time, input and output angle, TE), last output revolution:
    ours (theta_out - theta_in / i on the record), paper 001's per-step dphi at 100 Hz, and its
    running sum at 100 Hz."""
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
