"""`simulate`, `matrix`, `hysteresis`: the dynamics stage's commands (DESIGN.md CLI contracts).

  python -m pipeline simulate --case CASE.toml --load FORM:TORQUE_NM [--duration S] [--speed-rpm N] --out RECORD.csv
  python -m pipeline matrix --case CASE.toml --out DIR [--forms F1,F2,...] [--scheduler ADDRESS]
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

from geometry.artifacts import InputError, write_json_atomic, write_text_atomic


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
    # a bench run: the carrier's own drag (main bearings, output seal) at the run's speed and the
    # lubricant's stated oil temperature rides on the load (what keeps an unloaded reducer on a flank)
    from dynamics.losses.contacts import carrier_drag_Nm
    from dynamics.losses.lubricant import Lubricant
    oil_C = model.case.lubrication.run_oil_temperature_C
    drag = carrier_drag_Nm(model.case, Lubricant.from_section(model.case.lubrication), speed, oil_C,
                           f"{model.case.source or 'case'}: [lubrication] run_oil_temperature_C")
    t0 = time.perf_counter()
    res = simulate(model, load, duration_s=args.duration, input_speed_rpm=speed,
                   direction=-1 if args.backward else 1, dt_s=args.dt, store_pin_forces=False,
                   carrier_drag_Nm=drag)
    wall = time.perf_counter() - t0
    made = _made_from(model, "rv-record/1")
    write_te_result(args.out, res, comments=[
        f"simulated by rvte dynamics: case {model.case.name}, load {load}, "
        f"speed {res.meta['input_speed_rpm']:g} rpm, {'backward' if args.backward else 'forward'}",
        f"stiffness {spath}; dt {res.meta['dt_s']:g} s; {res.meta['solver']}",
        f"carrier drag {drag:.4g} N m on the load (main bearings and output seal, [lubrication], oil {oil_C:g} C); "
        "the torque column is the load",
        f"made_from: case {made.case_fingerprint}, stiffness {dict(made.inputs)['stiffness']}",
        "encoder_zero: simulation (TE = 0 at the unloaded kinematic zero)",
        f"input_speed_rpm: {res.meta['input_speed_rpm']:g}",    # the condition, read by diagnose
        f"oil_temperature_C: {oil_C:g}"])
    _say(args, f"simulate: {args.out}: {res.t_s[-1]:.3g} s simulated in {wall:.1f} s, " + _sigma_text(res))
    return 0


def _sigma_text(res) -> str:
    """TE sigma over the steady window, or why there is none (a run that ends before it starts)."""
    from dynamics.matrix import STEADY_FROM_S as steady_from_s
    from dynamics.loads import LOAD_FORMS
    # at least one period of the slowest load form (1 s: the square wave): a shorter window's
    # sigma (a 2 s run leaves one sample: "0 arcsec") says nothing
    need = max(1.0 / f.frequency_Hz for f in LOAD_FORMS.values() if f.frequency_Hz)
    span = res.t_s[-1] - steady_from_s
    if span >= need:
        return f"TE sigma (t >= {steady_from_s:g} s) = {res.std_arcsec(steady_from_s):.4g} arcsec"
    what = (f"is empty in a {res.t_s[-1]:.3g} s run" if span <= 0 else
            f"spans only {span:.3g} s of a {res.t_s[-1]:.3g} s run (needs >= {need:g} s, one period of the "
            "slowest load form)")
    return (f"no steady TE sigma: the window t >= {steady_from_s:g} s {what} "
            f"(whole run incl. the ramps: sigma {res.std_arcsec():.4g} arcsec)")


def _plot_te(results, case, out: Path, forms: tuple[str, ...]) -> None:
    """te_matrix.png: TE against output angle per load form (ramps cut) and its order spectra."""
    from dynamics.loads import PAPER_001_FORMS, load_form
    from dynamics.matrix import STEADY_FROM_S, characteristic_orders
    from pipeline.figures import te_matrix
    from pipeline.matrix_cache import read_cell
    cells = []
    for r in results:
        d = read_cell(out, r["name"])
        cell = {"form": r["form"], "torque_Nm": r["torque_Nm"], "t_s": d["t_s"],
                "output_angle_deg": d["output_angle_deg"], "te_arcsec": d["te_arcsec"]}
        if r["spectrum"] is not None:
            cell["order"], cell["amplitude"] = r["spectrum"]
            steady = d["t_s"] >= STEADY_FROM_S      # the load's own order: its frequency over the output's
            rev_per_s = abs(np.ptp(d["output_angle_deg"][steady])) / 360.0 / np.ptp(d["t_s"][steady])
            hz = load_form(r["form"]).frequency_Hz
            cell["load_order"] = hz / rev_per_s if hz else None
        cells.append(cell)
    what = "paper 001's load forms" if forms == PAPER_001_FORMS else "load forms " + ", ".join(forms)
    te_matrix(out / "te_matrix.png", cells, characteristic_orders(case), forms, steady_from_s=STEADY_FROM_S,
              title=f"{case.name}: transmission error, {what} (one colour per torque)")


def _forms(text: str) -> tuple[str, ...]:
    """--forms F1,F2,...: names of dynamics.loads' table, each once."""
    from dynamics.loads import FORMS, load_form
    forms = tuple(f.strip().lower() for f in str(text).split(","))
    for f in forms:
        if not f:
            raise InputError(f"--forms {text!r}: an empty name; expected a comma-separated list of {', '.join(FORMS)}")
        load_form(f)
    if len(set(forms)) < len(forms):
        raise InputError(f"--forms {text!r}: a form named twice; each of {', '.join(FORMS)} at most once")
    return forms


def _paper(form: str, torque_Nm: float) -> str:
    """Paper 001's sigma of a cell, or that it has none."""
    from dynamics.matrix import paper001_sigma_arcsec
    v = paper001_sigma_arcsec(form, torque_Nm)
    return "no paper figure" if v is None else f"{v:.3f}"


def cmd_matrix(args) -> int:
    from dynamics.matrix import STEADY_FROM_S, TORQUES_NM, characteristic_orders, sigma_table
    from pipeline import checks
    from pipeline.matrix_cache import run_matrix
    from pipeline.sweep import check_scheduler, run_tasks
    forms = _forms(args.forms)
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
                                 str(out.resolve()), args.dt, runner, forms)
    wall = time.perf_counter() - t0
    tab, whole = sigma_table(results, forms=forms), sigma_table(results, "sigma_whole_arcsec", forms)
    last = sigma_table(results, "sigma_last_rev_arcsec", forms)
    for name, t in (("te_std.csv", tab), ("te_std_last_rev.csv", last), ("te_std_whole.csv", whole)):
        write_text_atomic(out / name, _sigma_csv(t, forms, TORQUES_NM))
    orders = characteristic_orders(case)
    kind = "TEST STAND-IN" if "STAND-IN" in str(model.stiffness.sources) else "FE"
    lines = ["# TE standard deviation: this model beside paper 001", "",
             f"Case `{case.name}`, stiffness `{spath}` ({kind}), {args.duration:g} s per run, population "
             "sigma (paper 001's formula) [arcsec].", "",
             f"Windows: **steady** t >= {STEADY_FROM_S:g} s (after the speed and load ramps; `te_std.csv`), "
             "**last rev** the last full output revolution of the run (`te_std_last_rev.csv`; 2.95..7 s at "
             "88.89 deg/s), **whole** the whole run including the ramps (`te_std_whole.csv`).", "",
             "| torque N m | " + " | ".join(f"{f} steady | {f} last rev | {f} whole | {f} paper 001" for f in forms)
             + " |", "|---" * (1 + 4 * len(forms)) + "|"]
    for i, T in enumerate(TORQUES_NM):
        cells = [f"{tab[i, j]:.3f} | {last[i, j]:.3f} | {whole[i, j]:.3f} | {_paper(f, T)}"
                 for j, f in enumerate(forms)]
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
              f"{_ratio(tab, forms, 'square', 'sine')}); paper 001 has sine > square, so its sigma is not "
              "dominated by the load swing.",
              f"- Steady and last-revolution windows differ here by at most {_max_rel_pct(last, tab)} "
              "(both start after the ramps; n/a: runs shorter than one output revolution).",
              "- Paper 001's sigma of ~14 arcsec at 100 N m is far above a windup ripple: it likely contains "
              "the kinematic error of its profile/modification (TE at no load), which depends on a geometry "
              "the paper does not give. Our values cannot confirm or refute its absolute level."]
    lines += _paper001_like(results, case, out, forms)
    lines += ["", "Characteristic-order amplitudes of TE [arcsec] (steady part):", "",
              "| run | " + " | ".join(orders) + " |", "|---" * (1 + len(orders)) + "|"]
    for r in results:
        lines.append(f"| {r['name']} | " + " | ".join(f"{r['lines'].get(k, float('nan')):.3g}" for k in orders) + " |")
    write_text_atomic(out / "comparison.md", "\n".join(lines) + "\n")
    # matrix.json is te_std.csv's sidecar: what the table was made from
    write_json_atomic(out / "matrix.json", {"made_from": _made_from(model, "rv-matrix/1").to_json(),
                                            "runs": [
        {k: v for k, v in r.items() if k != "spectrum"} for r in results]})
    _plot_te(results, case, out, forms)
    short = "" if args.duration >= STEADY_FROM_S else f"; runs end before t = {STEADY_FROM_S:g} s: no steady sigma (nan)"
    _say(args, f"matrix: {out}/te_std.csv, comparison.md ({len(results) - reused} cells computed, {reused} reused "
               f"from an earlier run; {wall:.1f} s wall{short})")
    return 0


def _ratio(tab, forms: tuple[str, ...], a: str, b: str) -> str:
    """Mean ratio of two forms' sigma columns (by name), n/a where the matrix lacks one."""
    if a not in forms or b not in forms:
        return "n/a"
    return f"{np.mean(tab[:, forms.index(a)] / tab[:, forms.index(b)]):.2f}"


def _paper001_like(results, case, out: Path, forms: tuple[str, ...]) -> list[str]:
    """comparison.md: paper 001's TE definition and 100 Hz sampling applied to our runs, and where
    each characteristic order lands at 100 Hz."""
    from dynamics.matrix import PAPER_001_STEP_S, TORQUES_NM, aliasing, paper001_sigmas
    from pipeline.matrix_cache import read_cell

    def sigmas(name):
        d = read_cell(out, name)
        return paper001_sigmas(d["t_s"], d["input_angle_deg"], d["output_angle_deg"], d["te_arcsec"], case.ratio)
    sig = {(r["torque_Nm"], r["form"]): sigmas(r["name"]) for r in results}
    L = ["", "## Paper 001 like for like", "",
         "Paper 001 defines TE per output step as dphi(t) = (omega_out - omega_in / i) * dt with 700 steps over "
         f"7 s (dt = {PAPER_001_STEP_S:g} s, 100 Hz) and takes its population sigma over one output revolution. "
         "Applied to our runs (speeds at the 100 Hz instants from our 2 kHz record; last output revolution): "
         "**ours** = sigma of theta_out - theta_in / i (our definition), **paper dphi** = sigma of the per-step "
         "figure as printed, **summed** = sigma of its running sum (what 'integrating' would give), beside paper "
         "001's table [arcsec].", "",
         "| torque N m | " + " | ".join(f"{f} ours | {f} paper dphi | {f} summed | {f} paper 001" for f in forms)
         + " |", "|---" * (1 + 4 * len(forms)) + "|"]
    for T in TORQUES_NM:
        L.append(f"| {T:g} | " + " | ".join(
            f"{sig[(T, f)]['ours_theta_last_rev']:.3f} | {sig[(T, f)]['paper_step_last_rev']:.3f} | "
            f"{sig[(T, f)]['paper_summed_last_rev']:.3f} | {_paper(f, T)}"
            for f in forms) + " |")
    revs = [v["output_rev_per_s"] for v in sig.values() if np.isfinite(v["output_rev_per_s"])]
    # runs shorter than the steady window: the nominal output speed of the case
    rev = float(np.median(revs)) if revs else case.operation.input_speed_rpm / 60.0 / case.ratio
    L += ["", f"Aliasing at 100 Hz (output {rev:.4g} rev/s): a line of order k is at k x {rev:.4g} Hz; sampled at "
          "100 Hz it shows at the apparent frequency below. The per-step dphi is a speed: it weighs a TE line "
          "by 2 pi f dt (x step gain), so slow lines (1x, 3x) all but vanish and the meshes dominate; summed, an "
          "aliased line is integrated at its apparent frequency (x summed gain ~ f / f_apparent).", "",
          "| mechanism | order | frequency Hz | apparent Hz at 100 Hz | apparent order | step gain | summed gain |",
          "|---|---|---|---|---|---|---|"]
    for a in aliasing(case, rev):
        L.append(f"| {a['mechanism']} | {a['order']:g} | {a['frequency_Hz']:.4g} | {a['apparent_Hz']:.4g} | "
                 f"{a['apparent_order']:.4g} | {a['step_gain']:.3g} | {a['summed_gain']:.3g} |")
    L += ["", "Read as printed, paper 001's sigma is not a sigma of the angle: it is dominated by the mesh ripple's speed "
          "(zp zc and zp z2 folded to the apparent frequencies above), and the 1x and crank lines a bench reads in "
          "angle hardly enter it; square-wave runs add the speed spikes of each load step (a sum of them drifts)."]
    return L


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


def _load_sharing(model, out: Path, points: int = 41) -> None:
    """load_sharing.json/.png: static pin forces at rated torque over one mesh cycle (the eccentric
    turning one pin pitch: input period 360 i / (zp zc) deg), input held at each angle."""
    from dynamics.statics import quasi_static
    from pipeline.figures import load_sharing
    c = model.case.cycloid
    rated = model.case.rated_torque_Nm
    cycle = np.linspace(0.0, 1.0, points)
    res = quasi_static(model, cycle * 360.0 * model.ratio / (c.zp * c.zc), rated)
    pf = res.pin_force_N                                        # (n, discs, zp)
    total = pf.sum(axis=2, keepdims=True)
    share = np.divide(pf, total, out=np.zeros_like(pf), where=total > 0).max(axis=(1, 2))
    pins = 360.0 * np.arange(c.zp) / c.zp                       # pin k at 2 pi k / zp (DESIGN.md)
    write_json_atomic(out / "load_sharing.json", {
        "torque_Nm": rated, "pin_angle_deg": pins.tolist(), "pin_force_N": pf[0].tolist(),
        "mesh_cycle": cycle.tolist(), "teeth_in_contact": res.teeth_in_contact.tolist(),
        "max_pin_share": share.tolist(),
        "teeth_in_contact_range": [int(res.teeth_in_contact.min()), int(res.teeth_in_contact.max())],
        "max_pin_force_N": float(pf.max()), "max_pin_share_of_disc_load": float(share.max()),
        "made_from": _made_from(model, "rv-load-sharing/1").to_json()})
    load_sharing(out / "load_sharing.png", pins, pf[0], cycle, res.teeth_in_contact, share, torque_Nm=rated,
                 title=f"{model.case.name}: pin load sharing (static, input held, rated torque)")


LOOP_OIL_C = 25.0      # the catalog test's oil (room temperature; at rest the film is gone anyway)


def _loop_summary(loop) -> dict:
    return {"oil_temperature_C": LOOP_OIL_C, "width_at_zero_arcmin": loop.width_at_zero_arcmin,
            "width_frictionless_at_zero_arcmin": loop.width_frictionless_at_zero_arcmin,
            "max_width_beyond_5pct_rated_arcmin": loop.max_width_arcmin,
            "torsional_rigidity_Nm_per_arcmin": loop.torsional_rigidity_Nm_per_arcmin,
            "torsional_rigidity_secant_Nm_per_arcmin": loop.torsional_rigidity_secant_Nm_per_arcmin,
            "what": "the catalog loop with contact friction at boundary friction (no film at rest) opposing "
                    "each contact's creep (dynamics.losses.operating.friction_loop); width = falling minus "
                    "rising branch at zero torque (free play plus friction)"}


def cmd_hysteresis(args) -> int:
    from dynamics.budget import against_reference, compliance_budget, rigidity_band
    from dynamics.catalog import hysteresis
    from pipeline.figures import budget_bars, hysteresis_loop
    model, spath = _model(args)
    from dynamics.losses import Lubricant
    from dynamics.losses.operating import friction_loop
    res = hysteresis(model)
    loop = friction_loop(model, Lubricant.from_section(model.case.lubrication), LOOP_OIL_C)
    budget = compliance_budget(model)
    band = rigidity_band(model, lambda m: hysteresis(m).torsional_rigidity_Nm_per_arcmin)
    ref = against_reference(res.torsional_rigidity_Nm_per_arcmin,
                            model.case.operation.reference_rigidity_Nm_per_arcmin, budget["compliance_budget"])
    out = Path(args.out)
    write_json_atomic(out / "hysteresis.json", {"case": model.case.name, "stiffness": str(spath),
                                                **res.summary(),
                                                "loop_width_at_zero_arcmin": loop.width_at_zero_arcmin,
                                                "friction_loop": _loop_summary(loop),
                                                "compliance_budget": budget["compliance_budget"],
                                                "compliance_budget_by_coupling": budget["by_coupling"],
                                                "compliance_budget_torque_Nm": budget["torque_Nm"],
                                                "tangent_rigidity_at_rated_Nm_per_arcmin":
                                                    budget["tangent_rigidity_Nm_per_arcmin"],
                                                "reference": ref,
                                                "rigidity_band": band,
                                                "made_from": _made_from(model, "rv-hysteresis/1").to_json()})
    buf = io.StringIO()
    np.savetxt(buf, np.column_stack([res.torque_Nm, res.output_angle_arcmin]), delimiter=",",
               header="output_torque_Nm,output_angle_arcmin", comments="", fmt="%.8g")
    write_text_atomic(out / "hysteresis.csv", buf.getvalue())
    # catalog axes: torque driving the output forward (= -record torque) against the output angle
    hysteresis_loop(out / "hysteresis.png", -100 * res.torque_Nm / res.rated_torque_Nm, res.output_angle_arcmin,
                    rigidity_Nm_per_arcmin=res.torsional_rigidity_Nm_per_arcmin,
                    lost_motion_arcmin=res.lost_motion_arcmin, backlash_arcmin=res.backlash_arcmin,
                    rated_Nm=res.rated_torque_Nm, title=f"{model.case.name}: catalog hysteresis test, input locked",
                    secant_Nm_per_arcmin=res.torsional_rigidity_secant_Nm_per_arcmin,
                    friction=(-100 * loop.torque_Nm / loop.rated_torque_Nm, loop.output_angle_arcmin,
                              loop.width_at_zero_arcmin))
    _load_sharing(model, out)
    budget_bars(out / "compliance_budget.png", budget, model.case.name)
    _say(args, f"hysteresis: {out}/hysteresis.json: rigidity {res.torsional_rigidity_Nm_per_arcmin:.1f} "
               f"N m/arcmin (secant {res.torsional_rigidity_secant_Nm_per_arcmin:.1f}), loop width at zero "
               f"{loop.width_at_zero_arcmin:.3f} arcmin with friction, lost motion {res.lost_motion_arcmin:.3f} arcmin, backlash {res.backlash_arcmin:.3f} arcmin")
    for name, b in band.items():
        _say(args, f"rigidity band ({name}: compliance x {b['factors'][0]:.2f} .. x {b['factors'][1]:.2f}): "
                   f"{b['rigidity_Nm_per_arcmin'][0]:.1f} .. {b['rigidity_Nm_per_arcmin'][1]:.1f} N m/arcmin")
    top = sorted(budget["compliance_budget"].items(), key=lambda kv: -kv[1])
    _say(args, "compliance budget at rated torque: " + ", ".join(
        f"{k} {100 * v:.1f} %" for k, v in top if v >= 0.005) + " (components under 0.5 % omitted)")
    if ref:
        need = ref["compliance_factor_to_meet_reference"]
        _say(args, f"reference {ref['reference_Nm_per_arcmin']:g} N m/arcmin: predicted x "
                   f"{ref['predicted_over_reference']:.2f}; to meet it alone, "
                   + ", ".join(f"{k} compliance x {v:.2f}" for k, v in list(need.items())[:3] if v))
    return 0


def _common(p) -> None:
    p.add_argument("--case", required=True, help="case TOML")
    p.add_argument("--stiffness", default=None,
                   help="stiffness.json (default build/<case name>/fem/stiffness.json)")
    p.add_argument("--quiet", action="store_true")


def register(sub) -> None:
    from dynamics.loads import FORMS, PAPER_001_FORMS
    p = sub.add_parser("simulate", help="simulate one bench run -> record CSV")
    _common(p)
    p.add_argument("--load", required=True, help=f"FORM:TORQUE_NM, FORM in {', '.join(FORMS)} (dynamics.loads)")
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
    p.add_argument("--forms", default=",".join(PAPER_001_FORMS),
                   help=f"comma-separated load forms of {', '.join(FORMS)} (default paper 001's: "
                        f"{','.join(PAPER_001_FORMS)})")
    p.add_argument("--duration", type=float, default=7.0)
    p.add_argument("--dt", type=float, default=None)
    p.add_argument("--scheduler", default=None, help="Dask scheduler address (default: local processes)")
    p.set_defaults(func=cmd_matrix)
    p = sub.add_parser("hysteresis", help="catalog hysteresis test (input locked)")
    _common(p)
    p.add_argument("--out", required=True)
    p.set_defaults(func=cmd_hysteresis)
