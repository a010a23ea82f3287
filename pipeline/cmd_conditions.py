"""`python -m pipeline conditions --case CASE.toml --table CONDITIONS.csv [--diagnosis DIR/diagnosis.json] --out DIR`

The operating map (DESIGN.md): each row of the conditions table (dynamics.conditions, the contract)
through dynamics.losses.operating_point in both directions; rows run on local processes or a Dask
cluster (pipeline.sweep.run_tasks), results identical either way. With --diagnosis the diagnosis'
fitted extension is applied to the case and stiffness first (pipeline.diagnosis.compensate, as
`compensate` does). Writes DIR/conditions.csv (the contract's columns) and DIR/conditions.json:
per row the frictionless gap, pin friction and film parameter, loss shares and the no-load input
torque at the row's speed and temperature; the starting torque; the efficiency at rated torque and
rated output speed beside the published figure; the ISO 281 bearing lives beside the catalog's
K = 6000 h; and, where the table carries measured gaps (an input column named like an output
column is kept as measured_<name>), the gap error RMS with and without friction and the gap per
N m per speed.
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from geometry.artifacts import InputError

ROWS_PER_TASK = 4
# the efficiency chart's grid (the catalog's: efficiency against output speed per torque and temperature)
CHART_OUTPUT_RPM = (2.0, 5.0, 10.0, 15.0, 20.0, 30.0, 40.0)
CHART_TORQUE_PCT = (25.0, 50.0, 100.0)
CHART_TEMPERATURE_C = (25.0, 40.0, 60.0)
CHART_POINTS_PER_REV = 4     # efficiency alone: a revolution mean of the power, not a TE curve
# Nabtesco RV-N catalogue, efficiency chart: ~80-85 % at rated torque, 15 rpm output, case 30 C
# (grease); read as a band, the catalogue prints a curve, not a number
PUBLISHED_EFFICIENCY = {"value": 0.82, "band": [0.80, 0.85],
                        "source": "Nabtesco RV-N series catalogue, efficiency curve at rated torque and 15 rpm "
                                  "output (read from the chart; case temperature 30 C, grease)"}


class ConditionsCommandError(InputError):
    """A conditions request that cannot run (options)."""


def register(sub) -> None:
    p = sub.add_parser("conditions", help="operating map: TE gap, efficiency, input torque per condition")
    p.add_argument("--case", required=True)
    p.add_argument("--table", required=True, help="CONDITIONS.csv: input_speed_rpm,torque_Nm,oil_temperature_C,...")
    p.add_argument("--diagnosis", default=None, help="diagnosis.json: apply its fitted extension first")
    p.add_argument("--out", required=True)
    p.add_argument("--points-per-rev", type=int, default=None, help="input angles per output revolution "
                   "(default dynamics.losses.operating.POINTS_PER_REV)")
    p.add_argument("--workers", type=int, default=None, help="local processes (default: the cores)")
    p.add_argument("--scheduler", default=None, help="Dask scheduler tcp://HOST:PORT")
    p.add_argument("--stiffness", default=None, help="stiffness.json (default build/<case>/fem/stiffness.json)")
    p.add_argument("--quiet", action="store_true")
    p.set_defaults(func=run)


def _task(kind, *args):
    """Pure task of the pool: one of the row chunks, no-load points, chart temperatures, case figures."""
    return {"rows": _rows_task, "noload": _no_load_task, "chart": _efficiency_task, "case": _case_task,
            "thermal": _thermal_task}[kind](*args)


def _case_task(case, stiffness):
    from dynamics.losses import Lubricant
    return _case_figures(case, stiffness, Lubricant.from_section(case.lubrication))


def _rows_task(case, stiffness, rows, points_per_rev):
    """Pure task: operating points of a few (speed, torque, temperature) rows."""
    from dynamics.losses import Lubricant, operating_point
    from dynamics.reducer import build_model
    model = build_model(case, stiffness)
    lub = Lubricant.from_section(case.lubrication)
    out = []
    for speed, torque, temp in rows:
        op = operating_point(model, lub, speed, torque, temp, points_per_rev=points_per_rev)
        out.append(op.summary())
    return out


def _thermal_task(case, stiffness, rows, points_per_rev, dT):
    """Pure task: the rows' operating points on a case whose discs are dT warmer (dT: the result's key)."""
    return _rows_task(case, stiffness, rows, points_per_rev)


def _no_load_task(case, stiffness, speed, temp, points_per_rev):
    """No-load running torque at the input: the loss power over the input speed, forward."""
    from dynamics.losses import Lubricant
    from dynamics.losses.contacts import RPM_PER_RAD_S
    from dynamics.losses.operating import revolution_angles_deg, run_direction
    from dynamics.reducer import build_model
    model = build_model(case, stiffness)
    run = run_direction(model, Lubricant.from_section(case.lubrication), speed, 0.0, temp, +1,
                        revolution_angles_deg(model, min(points_per_rev, CHART_POINTS_PER_REV)))
    return float(np.mean(run.total_loss_W)) / (speed / RPM_PER_RAD_S)


def _efficiency_task(case, stiffness, temp):
    from dynamics.losses import Lubricant
    from dynamics.losses.operating import forward_efficiency
    from dynamics.reducer import build_model
    model, lub = build_model(case, stiffness), Lubricant.from_section(case.lubrication)
    return [[forward_efficiency(model, lub, n * case.ratio, q / 100 * case.rated_torque_Nm, temp, CHART_POINTS_PER_REV)
             for n in CHART_OUTPUT_RPM] for q in CHART_TORQUE_PCT]


def _measured(table, col: str = "gap_fw_minus_bw_arcsec") -> np.ndarray | None:
    """A measured column of the table (default the gaps), where it has it and it is numeric."""
    if col not in table.header:
        return None
    i = table.header.index(col)
    try:
        return np.array([float(r.fields[i]) for r in table.rows])
    except ValueError:
        return None


def _thermal_rows(table) -> tuple[float, list[int]] | None:
    """(speed, row indices) of the thermal what-if: the fastest speed with two torques or more, where
    the table has measured gaps (the what-if sets the model's change beside the bench's)."""
    if _measured(table) is None:
        return None
    for s in sorted({r.input_speed_rpm for r in table.rows}, reverse=True):
        idx = [i for i, r in enumerate(table.rows) if r.input_speed_rpm == s]
        if len({table.rows[i].torque_Nm for i in idx}) >= 2:
            return s, idx
    return None


def _measured_comparison(table, results, thermal_gaps: dict | str | None = None) -> dict | None:
    """Gap error RMS (with and without friction) and gap per N m per speed, where the table has gaps;
    thermal_gaps {dT: gaps at the _thermal_rows} adds the thermal what-if (a string: why it was skipped)."""
    from dynamics.conditions import chain_whatifs, gap_lines, thermal_whatif
    meas = _measured(table)
    if meas is None:
        return None
    pred = np.array([r["gap_fw_minus_bw_arcsec"] for r in results])
    pred0 = np.array([r["gap_frictionless_arcsec"] for r in results])
    speed = np.array([r.input_speed_rpm for r in table.rows])
    torque = np.array([r.torque_Nm for r in table.rows])
    lines = gap_lines(speed, torque, meas, pred)
    friction_free = gap_lines(speed, torque, meas, pred0)["by_speed_rpm"]
    slopes = {k: {"measured_arcsec_per_Nm": v["measured_arcsec_per_Nm"], "predicted_arcsec_per_Nm": v["predicted_arcsec_per_Nm"],
                  "frictionless_arcsec_per_Nm": friction_free[k]["predicted_arcsec_per_Nm"], "rows": v["rows"]}
              for k, v in lines["by_speed_rpm"].items()}
    thermal = {"skipped": thermal_gaps} if isinstance(thermal_gaps, str) else None
    if isinstance(thermal_gaps, dict) and thermal_gaps:
        s, idx = _thermal_rows(table)
        thermal = thermal_whatif(torque[idx], {0.0: pred[idx], **thermal_gaps}, lines["by_speed_rpm"], s)
    return {"rows": len(meas), "gap_rms_error_arcsec": float(np.sqrt(np.mean((pred - meas) ** 2))),
            "gap_rms_error_frictionless_arcsec": float(np.sqrt(np.mean((pred0 - meas) ** 2))),
            "gap_mean_error_arcsec": float(np.mean(pred - meas)), "gap_slope_by_speed_rpm": slopes,
            "gap_lines": lines, "bench_chain_whatifs": chain_whatifs(torque, meas, pred),
            "thermal_whatif": thermal,
            "note": "gap = mean TE forward - backward (bench convention, negative under load); gap_lines: "
                    "per speed gap = a + b T (a zero-load gap, b wind-up, rigidity 120 / |b| N m/arcmin) and the "
                    "RMS error with the bench's slopes or zero-load gaps put in (what-ifs, the model unchanged); "
                    "bench_chain_whatifs: the gap RMS error were the output encoder to read beyond a torque flange "
                    "(a what-if of the bench's layout, which the dataset does not state; not the prediction); "
                    "thermal_whatif: the gap line at the fastest speed were both discs dT warmer than every other "
                    "part (dynamics.thermal; a what-if of the parts' temperatures, which the bench does not give; "
                    "not the prediction), its change per K beside the bench's from its slowest to its fastest speed"}


def run(args) -> int:
    from dynamics.conditions import check_torques, read_table
    from dynamics.losses.lubricant import Lubricant
    from fem.stiffness import for_case
    from geometry.params import load_case
    from pipeline.sweep import check_scheduler, run_tasks
    case = load_case(args.case)
    lub = Lubricant.from_section(case.lubrication)
    check_scheduler(args.scheduler)
    if args.workers is not None and not 1 <= args.workers <= 64:
        raise ConditionsCommandError(f"--workers = {args.workers}: allowed 1 to 64")
    from dynamics.losses.operating import POINTS_PER_REV
    ppr = POINTS_PER_REV if args.points_per_rev is None else args.points_per_rev
    if not 4 <= ppr <= 720:
        raise ConditionsCommandError(f"--points-per-rev = {ppr}: allowed 4 to 720")
    table = read_table(args.table, (case.lubrication.min_temperature_C, case.lubrication.max_temperature_C))
    check_torques(table, case.operation.momentary_torque_Nm)
    stiffness = for_case(case, args.stiffness)
    base_case, base_stiffness = case, stiffness
    causes = None
    if args.diagnosis:
        from pipeline.cmd_compensate import read_model_parameters
        from pipeline.diagnosis import compensate as comp
        mp = read_model_parameters(args.diagnosis, case)
        try:
            case, stiffness = comp.extended_model(case, stiffness, mp)
        except (comp.CompensationError, ValueError) as exc:
            raise ConditionsCommandError(f"--diagnosis {args.diagnosis}: {exc}") from None
        causes = sorted(mp)
    rows = [(r.input_speed_rpm, r.torque_Nm, r.oil_temperature_C) for r in table.rows]
    pairs = sorted({(r[0], r[2]) for r in rows})
    temps = [t for t in CHART_TEMPERATURE_C if lub.section.min_temperature_C <= t <= lub.section.max_temperature_C]
    # one pool for everything (each worker loads the compiled kernels once); the case figures first,
    # they are the longest single tasks
    tasks = [("case", case, stiffness)] + [("chart", case, stiffness, t) for t in temps] \
        + [("rows", case, stiffness, rows[i:i + ROWS_PER_TASK], ppr) for i in range(0, len(rows), ROWS_PER_TASK)] \
        + [("noload", case, stiffness, s, t, ppr) for s, t in pairs]
    hot, thermal_skipped = _thermal_rows(table), None
    if hot is not None:
        from dynamics.conditions import DISC_WARMER_K
        from dynamics.thermal import warmer_discs
        hot_rows = [rows[i] for i in hot[1]]
        try:       # a what-if never stops the prediction: a case the warm discs make invalid skips it
            warm = {dT: warmer_discs(case, dT) for dT in DISC_WARMER_K}
        except (InputError, ValueError) as exc:
            thermal_skipped = f"discs {max(DISC_WARMER_K):g} K warmer make an invalid case ({exc})"
        else:
            tasks += [("thermal", warm[dT], stiffness, hot_rows[i:i + ROWS_PER_TASK], ppr, dT)
                      for dT in DISC_WARMER_K for i in range(0, len(hot_rows), ROWS_PER_TASK)]
    done = run_tasks(_task, tasks, workers=args.workers, scheduler=args.scheduler)
    kinds = [t[0] for t in tasks]
    thermal_gaps: dict = {}
    for t, d in zip(tasks, done):
        if t[0] == "thermal":
            thermal_gaps.setdefault(t[-1], []).extend(r["gap_fw_minus_bw_arcsec"] for r in d)
    summary = done[0]
    chart = [d for k, d in zip(kinds, done) if k == "chart"]
    results = [r for k, d in zip(kinds, done) if k == "rows" for r in d]
    no_load = dict(zip(pairs, [d for k, d in zip(kinds, done) if k == "noload"]))
    summary["efficiency_chart"] = {"output_speed_rpm": list(CHART_OUTPUT_RPM), "torque_pct": list(CHART_TORQUE_PCT),
                                   "temperature_C": temps, "efficiency": chart}
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    _write(out, args, base_case, base_stiffness, lub, table, results, no_load, summary, causes, ppr,
           thermal_skipped or thermal_gaps)
    if not args.quiet:
        cmp = _measured_comparison(table, results)
        tail = "" if cmp is None else (f"; gap RMS error {cmp['gap_rms_error_arcsec']:.1f} arcsec "
                                       f"(frictionless {cmp['gap_rms_error_frictionless_arcsec']:.1f})")
        print(f"conditions {case.name}: {len(rows)} rows{tail}; efficiency at rated "
              f"{summary['rated_point']['efficiency']:.3f} (published ~{PUBLISHED_EFFICIENCY['value']}) -> "
              f"{out / 'conditions.csv'}")
    return 0


def _case_figures(case, stiffness, lub) -> dict:
    """Rated point (rated torque, rated output speed, 40 C), starting torque, bearing lives."""
    from dynamics.losses import operating_point
    from dynamics.losses.life import bearing_lives
    from dynamics.losses.operating import friction_lever, starting_torque_Nm
    from dynamics.reducer import build_model
    model = build_model(case, stiffness)
    n_in = case.operation.rated_output_speed_rpm * case.ratio
    rated = {}
    for temp in (25.0, 40.0):
        op = operating_point(model, lub, n_in, case.rated_torque_Nm, temp)
        rated[f"{temp:g}"] = {"efficiency": op.forward.efficiency, "input_torque_Nm": op.input_torque_Nm,
                              "pin_friction_mean": float(np.nanmean(op.forward.pin_mu)),
                              "pin_film_parameter_mean": float(np.nanmean(op.forward.pin_film_parameter))}
    life = bearing_lives(model, lub, 40.0)
    # how much of the running friction loads the compliance (dynamics.losses.operating.FrictionLever)
    lever = [friction_lever(model, lub, case.rated_torque_Nm, n, 25.0).summary()
             for n in sorted({n_in, case.operation.input_speed_rpm})]
    return {"rated_point": {"input_speed_rpm": n_in, "torque_Nm": case.rated_torque_Nm, "oil_temperature_C": 40.0,
                            **rated["40"], "at_25C": rated["25"], "published": PUBLISHED_EFFICIENCY},
            "starting_torque_input_Nm": {"25": starting_torque_Nm(model, lub, 25.0),
                                         "40": starting_torque_Nm(model, lub, 40.0)},
            "bearing_life": life, "friction_lever": lever}


def _jsonable(x):
    if isinstance(x, dict):
        return {str(k): _jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_jsonable(v) for v in x]
    if isinstance(x, (np.floating, float)):
        return float(x) if math.isfinite(float(x)) else None
    if isinstance(x, np.integer):
        return int(x)
    return x


def _write(out, args, case, stiffness, lub, table, results, no_load, summary, causes, ppr, thermal_gaps) -> None:
    import dataclasses

    from dynamics.conditions import measured_name, table_text
    from geometry.artifacts import write_json_atomic, write_text_atomic
    from geometry.fingerprint import file_fingerprint, made_from
    header = tuple(measured_name(h) for h in table.header)
    write_text_atomic(out / "conditions.csv", table_text(table, results))
    rows = []
    for r, res in zip(table.rows, results):
        rows.append({**dict(zip(header, r.fields)), **res,
                     "no_load_input_torque_Nm": no_load[(r.input_speed_rpm, r.oil_temperature_C)]})
    inputs = {"table": file_fingerprint(args.table)}
    if args.diagnosis:
        inputs["diagnosis"] = file_fingerprint(args.diagnosis)
    doc = {"case": case.name, "rows": rows, "points_per_rev": ppr, "diagnosis_causes": causes,
           "against_measured": _measured_comparison(table, results, thermal_gaps),
           "lubrication": dataclasses.asdict(case.lubrication),
           "viscosity_cSt_at": {f"{t:g}": float(lub.kinematic_cSt(t)) for t in (25.0, 40.0, 100.0)},
           **summary,
           "made_from": made_from(case, "rv-conditions/1", stiffness=stiffness.made_from, **inputs).to_json()}
    write_json_atomic(out / "conditions.json", _jsonable(doc))
    _pictures(out, case, table, results, doc)


def _pictures(out: Path, case, table, results, doc) -> None:
    import textwrap

    from pipeline.figures_conditions import efficiency_chart, gap_map

    speed = [r.input_speed_rpm for r in table.rows]
    torque = [r.torque_Nm for r in table.rows]
    cmp = doc["against_measured"]
    tail = "" if cmp is None else (f": gap RMS error {cmp['gap_rms_error_arcsec']:.1f} arcsec "
                                   f"(frictionless {cmp['gap_rms_error_frictionless_arcsec']:.1f})")
    gap_map(out / "gap_map.png", speed, torque, [r["gap_fw_minus_bw_arcsec"] for r in results],
            [r["gap_frictionless_arcsec"] for r in results], [r["te_pp_fw_arcsec"] for r in results],
            [r["te_pp_bw_arcsec"] for r in results], gap_meas=_measured(table),
            pp_fw_meas=_measured(table, "te_pp_fw_arcsec"), pp_bw_meas=_measured(table, "te_pp_bw_arcsec"),
            title=textwrap.fill(f"{case.name}: operating map{tail}" + (
                f" (extension: {', '.join(doc['diagnosis_causes'])})" if doc["diagnosis_causes"] else ""), 110))
    ch, pub = doc["efficiency_chart"], PUBLISHED_EFFICIENCY
    eff = np.array([[[np.nan if v is None else v for v in row] for row in t] for t in ch["efficiency"]])
    efficiency_chart(out / "efficiency.png", ch["output_speed_rpm"], ch["torque_pct"], ch["temperature_C"], eff,
                     published=(case.operation.rated_output_speed_rpm, pub["value"], *pub["band"]),
                     title=f"{case.name}: efficiency against output speed (model; the catalog's chart)")
