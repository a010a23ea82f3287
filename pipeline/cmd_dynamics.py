"""`simulate`, `matrix`, `hysteresis`: the dynamics stage's commands (DESIGN.md CLI contracts).

  python -m pipeline simulate --case CASE.toml --load FORM:TORQUE_NM [--duration S] [--speed-rpm N] --out RECORD.csv
  python -m pipeline matrix --case CASE.toml --out DIR [--scheduler ADDRESS]
  python -m pipeline hysteresis --case CASE.toml --out DIR
The stiffness comes from the FEM stage (default build/<case name>/fem/stiffness.json).
"""
from __future__ import annotations

import csv
import functools
import io
import time
from pathlib import Path

import numpy as np

from geometry.artifacts import write_json_atomic, write_text_atomic


def _model(args):
    from dynamics.model import build_model
    from fem.stiffness import load, path_for_case
    from geometry.params import load_case
    case = load_case(args.case)
    path = path_for_case(case, args.stiffness)
    return build_model(case, load(path)), path


def _made_from(model, artifact: str):
    """Provenance of an output of this stage: the case and the stiffness it was computed from."""
    from geometry.fingerprint import made_from
    return made_from(model.case, artifact, stiffness=model.stiffness.made_from)


def _default_dt_s() -> float:
    from dynamics.model import DEFAULT_DT_S    # numba: imported once the cheap checks have passed
    return DEFAULT_DT_S


def _say(args, msg: str) -> None:
    if not args.quiet:
        print(msg, flush=True)


def cmd_simulate(args) -> int:
    from dynamics.loads import LoadSpec
    from pipeline import checks
    load = LoadSpec.parse(args.load)     # every option checked before the model is imported
    checks.input_speed(args.speed_rpm)
    checks.run_length(args.duration, args.dt, _default_dt_s)
    from dynamics.model import simulate
    from dynamics.records import write_te_result
    model, spath = _model(args)
    # DESIGN.md: the input speed defaults to the case's [operation] input_speed_rpm
    speed = model.case.operation.input_speed_rpm if args.speed_rpm is None else args.speed_rpm
    t0 = time.perf_counter()
    res = simulate(model, load, duration_s=args.duration, input_speed_rpm=speed,
                   direction=-1 if args.backward else 1, dt_s=args.dt, store_pin_forces=False)
    wall = time.perf_counter() - t0
    made = _made_from(model, "rv-record/1")
    write_te_result(args.out, res, comments=[
        f"simulated by rvte dynamics: case {model.case.name}, load {load}, "
        f"speed {res.meta['input_speed_rpm']:g} rpm, {'backward' if args.backward else 'forward'}",
        f"stiffness {spath}; dt {res.meta['dt_s']:g} s; {res.meta['solver']}",
        f"made_from: case {made.case_fingerprint}, stiffness {dict(made.inputs)['stiffness']}",
        "encoder_zero: simulation (TE = 0 at the unloaded kinematic zero)"])
    _say(args, f"simulate: {args.out}: {res.t_s[-1]:.3g} s simulated in {wall:.1f} s, " + _sigma_text(res))
    return 0


def _sigma_text(res) -> str:
    """TE sigma over the steady window, or why there is none (a run that ends before it starts)."""
    from dynamics.matrix import STEADY_FROM_S as steady_from_s
    steady = res.t_s >= steady_from_s
    if steady.any():
        return f"TE sigma (t >= {steady_from_s:g} s) = {res.std_arcsec(steady_from_s):.4g} arcsec"
    return (f"no steady TE sigma: the window t >= {steady_from_s:g} s is empty in a {res.t_s[-1]:.3g} s run "
            f"(whole run incl. the ramps: sigma {res.std_arcsec():.4g} arcsec)")


def _plot_te(results, case, out: Path) -> None:
    from dynamics.matrix import characteristic_orders
    from pipeline.render import figure, save_figure
    fig, axes = figure(2, 1, figsize=(10, 8))
    for r in results:
        d = np.load(out / f"{r['name']}.npz")
        axes[0].plot(d["t_s"], d["te_arcsec"], lw=0.6, label=r["name"])
        if r["spectrum"] is not None:
            o, a = r["spectrum"]
            axes[1].semilogy(o[1:], a[1:] + 1e-6, lw=0.6)
    axes[0].set_xlabel("time [s]")
    axes[0].set_ylabel("TE [arcsec]")
    axes[0].legend(fontsize=6, ncol=4)
    for name, o in characteristic_orders(case).items():
        axes[1].axvline(o, color="k", ls=":", lw=0.6)
        axes[1].text(o, axes[1].get_ylim()[1], name, rotation=90, va="top", fontsize=6)
    axes[1].set_xscale("log")
    axes[1].set_xlabel("order [cycles per output revolution]")
    axes[1].set_ylabel("TE amplitude [arcsec]")
    save_figure(fig, out / "te_matrix.png")


def cmd_matrix(args) -> int:
    from dynamics.loads import FORMS
    from dynamics.matrix import (PAPER_001_SIGMA_ARCSEC, STEADY_FROM_S, TORQUES_NM, characteristic_orders,
                                 run_matrix, sigma_table)
    from pipeline import checks
    from pipeline.sweep import check_scheduler, run_tasks
    check_scheduler(args.scheduler)
    checks.run_length(args.duration, args.dt, _default_dt_s)
    model, spath = _model(args)
    case = model.case
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    runner = functools.partial(run_tasks, scheduler=args.scheduler,
                               progress=None if args.quiet else lambda i, n: print(f"matrix: {i}/{n}", flush=True))
    # each cell is its own artifact: finished cells with the same inputs are reused (resume)
    results, reused = run_matrix(str(Path(args.case).resolve()), str(spath.resolve()), args.duration,
                                 str(out.resolve()), args.dt, runner)
    wall = time.perf_counter() - t0
    tab, whole = sigma_table(results), sigma_table(results, "sigma_whole_arcsec")
    last = sigma_table(results, "sigma_last_rev_arcsec")
    for name, t in (("te_std.csv", tab), ("te_std_last_rev.csv", last), ("te_std_whole.csv", whole)):
        write_text_atomic(out / name, _sigma_csv(t, FORMS, TORQUES_NM))
    orders = characteristic_orders(case)
    kind = "TEST STAND-IN" if "STAND-IN" in str(model.stiffness.sources) else "FE"
    lines = ["# TE standard deviation: this model beside paper 001", "",
             f"Case `{case.name}`, stiffness `{spath}` ({kind}), {args.duration:g} s per run, population "
             "sigma (paper 001's formula) [arcsec].", "",
             f"Windows: **steady** t >= {STEADY_FROM_S:g} s (after the speed and load ramps; `te_std.csv`), "
             "**last rev** the last full output revolution of the run (`te_std_last_rev.csv`; 2.95..7 s at "
             "88.89 deg/s), **whole** the whole run including the ramps (`te_std_whole.csv`).", "",
             "| torque N m | " + " | ".join(f"{f} steady | {f} last rev | {f} whole | {f} paper 001" for f in FORMS)
             + " |", "|---" * (1 + 4 * len(FORMS)) + "|"]
    for i, T in enumerate(TORQUES_NM):
        cells = [f"{tab[i, j]:.3f} | {last[i, j]:.3f} | {whole[i, j]:.3f} | {PAPER_001_SIGMA_ARCSEC[i, j]:.3f}"
                 for j in range(len(FORMS))]
        lines.append(f"| {T:g} | " + " | ".join(cells) + " |")
    lines += ["", "What paper 001's numbers can and cannot be compared with:", "",
              "- Paper 001 analyses TE \"for one rotation of the output flange\" of a 7 s run at 88.89 deg/s "
              "(4.05 s per revolution): its window is one revolution, most likely the last one (2.95..7 s), "
              "which begins after both ramps: `last rev` is the like-for-like window, `steady` is ours.",
              "- Trends (sigma grows with load; sine >= square >= constant) can be compared; absolute values "
              "only as an order of magnitude: paper 001's model (geometry, modification, stiffness, "
              "damping, and whether its sigma includes the mean windup drift over the revolution) is not "
              "published in enough detail to rebuild, and our stiffness is "
              f"{'the closed-form test stand-in, not FE' if kind != 'FE' else 'the FE stage'}.",
              "- Sigma of the constant-load run is the mesh ripple only (the windup is a constant offset); "
              "square and sine add the windup swing of +-5 % T. A square wave's RMS is its amplitude, a "
              "sine's amplitude / sqrt 2: where the swing dominates, square / sine -> 1.41 (ours: "
              f"{np.mean(tab[:, 1] / tab[:, 2]):.2f}); paper 001 has sine > square, so its sigma is not "
              "dominated by the load swing.",
              f"- Steady and last-revolution windows differ here by at most {_max_rel_pct(last, tab)} "
              "(both start after the ramps; n/a: runs shorter than one output revolution).",
              "- Paper 001's sigma of ~14 arcsec at 100 N m is far above a windup ripple: it likely contains "
              "the kinematic error of its profile/modification (TE at no load), which depends on a geometry "
              "the paper does not give. Our values cannot confirm or refute its absolute level."]
    lines += ["", "Characteristic-order amplitudes of TE [arcsec] (steady part):", "",
              "| run | " + " | ".join(orders) + " |", "|---" * (1 + len(orders)) + "|"]
    for r in results:
        lines.append(f"| {r['name']} | " + " | ".join(f"{r['lines'].get(k, float('nan')):.3g}" for k in orders) + " |")
    write_text_atomic(out / "comparison.md", "\n".join(lines) + "\n")
    # matrix.json is te_std.csv's sidecar: what the table was made from
    write_json_atomic(out / "matrix.json", {"made_from": _made_from(model, "rv-matrix/1").to_json(),
                                            "runs": [
        {k: v for k, v in r.items() if k != "spectrum"} for r in results]})
    _plot_te(results, case, out)
    short = "" if args.duration >= STEADY_FROM_S else f"; runs end before t = {STEADY_FROM_S:g} s: no steady sigma (nan)"
    _say(args, f"matrix: {out}/te_std.csv, comparison.md ({len(results) - reused} cells computed, {reused} reused "
               f"from an earlier run; {wall:.1f} s wall{short})")
    return 0


def _max_rel_pct(a, b) -> str:
    d = np.abs(a / b - 1)
    return f"{100 * np.max(d[np.isfinite(d)]):.2g} %" if np.isfinite(d).any() else "n/a"


def _sigma_csv(tab, forms, torques) -> str:
    """rows torque_Nm, columns the load forms, values arcsec (the te_std.csv contract)."""
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(["torque_Nm", *forms])
    for T, row in zip(torques, tab):
        w.writerow([f"{T:g}", *(f"{v:.6g}" for v in row)])
    return buf.getvalue()


def cmd_hysteresis(args) -> int:
    from dynamics.budget import compliance_budget
    from dynamics.catalog import hysteresis
    from pipeline.render import figure, save_figure
    model, spath = _model(args)
    res = hysteresis(model)
    budget = compliance_budget(model)
    out = Path(args.out)
    write_json_atomic(out / "hysteresis.json", {"case": model.case.name, "stiffness": str(spath),
                                                **res.summary(),
                                                "compliance_budget": budget["compliance_budget"],
                                                "tangent_rigidity_at_rated_Nm_per_arcmin":
                                                    budget["tangent_rigidity_Nm_per_arcmin"],
                                                "made_from": _made_from(model, "rv-hysteresis/1").to_json()})
    buf = io.StringIO()
    np.savetxt(buf, np.column_stack([res.torque_Nm, res.output_angle_arcmin]), delimiter=",",
               header="output_torque_Nm,output_angle_arcmin", comments="", fmt="%.8g")
    write_text_atomic(out / "hysteresis.csv", buf.getvalue())
    fig, ax = figure(figsize=(7, 5))
    ax.plot(res.output_angle_arcmin, res.torque_Nm, ".-", lw=0.8)
    ax.set_xlabel("output angle, input locked [arcmin]")
    ax.set_ylabel("output torque [N m] (positive resists forward rotation)")
    ax.set_title(f"{model.case.name}: rigidity {res.torsional_rigidity_Nm_per_arcmin:.0f} N m/arcmin, "
                 f"lost motion {res.lost_motion_arcmin:.2f} arcmin")
    ax.grid(True, lw=0.3)
    save_figure(fig, out / "hysteresis.png")
    _say(args, f"hysteresis: {out}/hysteresis.json: rigidity {res.torsional_rigidity_Nm_per_arcmin:.1f} "
               f"N m/arcmin, lost motion {res.lost_motion_arcmin:.3f} arcmin, backlash {res.backlash_arcmin:.3f} arcmin")
    _say(args, "compliance budget at rated torque: " + ", ".join(
        f"{k} {100 * v:.1f} %" for k, v in sorted(budget["compliance_budget"].items(), key=lambda kv: -kv[1])))
    return 0


def _common(p) -> None:
    p.add_argument("--case", required=True, help="case TOML")
    p.add_argument("--stiffness", default=None,
                   help="stiffness.json (default build/<case name>/fem/stiffness.json)")
    p.add_argument("--quiet", action="store_true")


def register(sub) -> None:
    p = sub.add_parser("simulate", help="simulate one bench run -> record CSV")
    _common(p)
    p.add_argument("--load", required=True, help="FORM:TORQUE_NM, FORM in constant, square, sine")
    p.add_argument("--duration", type=float, default=7.0, help="seconds (default 7, paper 001)")
    p.add_argument("--speed-rpm", type=float, default=None,
                   help="input speed [rpm] (default: the case's [operation] input_speed_rpm)")
    p.add_argument("--backward", action="store_true", help="run backward (record torque negative)")
    p.add_argument("--dt", type=float, default=None, help="time step [s] (default 1e-4)")
    p.add_argument("--out", required=True, help="record CSV")
    p.set_defaults(func=cmd_simulate)
    p = sub.add_parser("matrix", help="paper 001's 12 load cases -> te_std.csv, comparison.md, plots")
    _common(p)
    p.add_argument("--out", required=True)
    p.add_argument("--duration", type=float, default=7.0)
    p.add_argument("--dt", type=float, default=None)
    p.add_argument("--scheduler", default=None, help="Dask scheduler address (default: local processes)")
    p.set_defaults(func=cmd_matrix)
    p = sub.add_parser("hysteresis", help="catalog hysteresis test (input locked)")
    _common(p)
    p.add_argument("--out", required=True)
    p.set_defaults(func=cmd_hysteresis)
