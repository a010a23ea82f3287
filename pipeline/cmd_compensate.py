"""`python -m pipeline compensate --case CASE.toml --diagnosis DIR/diagnosis.json --out DIR2 [--check RECORD.csv ...]`

Writes DIR2/compensation.csv (`output_angle_deg,torque_Nm,direction,te_arcsec`: the extended model's
TE per torque level and direction; torque in the record convention, + resists forward rotation)
and DIR2/compensation.json (the levels, made_from and, with --check, `te_rms_before_arcsec`,
`te_rms_after_arcsec`, `rms_reduction` over the checked records and per record, beside the
published 83-94 %). Kernels: pipeline.diagnosis.compensate. Stiffness defaults to
build/<case.name>/fem/stiffness.json. A diagnosis made for another case (its
diagnosis_made_from.json sidecar) or one with no extension is refused in one line.
"""
from __future__ import annotations

import math
import sys
from pathlib import Path

from geometry.artifacts import InputError, read_json

MAX_POINTS = 16384


class CompensateError(InputError):
    """A compensate request that cannot run (diagnosis file, options)."""


def register(sub) -> None:
    p = sub.add_parser("compensate", help="compensation table from a diagnosis' extended model")
    p.add_argument("--case", required=True)
    p.add_argument("--diagnosis", required=True, help="diagnosis.json written by `diagnose`")
    p.add_argument("--out", required=True)
    p.add_argument("--check", nargs="+", default=None, help="bench records to check the table on")
    p.add_argument("--torques-Nm", default=None,
                   help="comma-separated |torque| levels, N m (default 0, 25, 50, 100 %% rated and the --check records' levels)")
    p.add_argument("--points-per-rev", type=int, default=360, help="table points per output revolution")
    p.add_argument("--stiffness", default=None, help="stiffness.json (default build/<case>/fem/stiffness.json)")
    p.add_argument("--quiet", action="store_true")
    p.set_defaults(func=run)


def read_model_parameters(path: str | Path, case) -> dict:
    """{cause: {parameter: value}} of a diagnosis.json, refused when made for another case."""
    from geometry.fingerprint import case_fingerprint
    path = Path(path)
    d = read_json(path, name=f"--diagnosis {path}", missing_hint="run `python -m pipeline diagnose` first",
                  error=CompensateError)
    ext = d.get("extension") if isinstance(d, dict) else None
    params = ext.get("parameters") if isinstance(ext, dict) else None
    mp = params.get("model_parameters") if isinstance(params, dict) else None
    if not isinstance(mp, dict) or not mp:
        raise CompensateError(f"--diagnosis {path}: no extended model (extension null or without "
                              f"model_parameters): nothing to compensate beyond the model as given")
    for cause, given in mp.items():     # the shape diagnose writes: {cause: {parameter: number}}
        if not isinstance(given, dict):
            raise CompensateError(f"--diagnosis {path}: model_parameters.{cause} = {given!r:.60}: allowed an "
                                  f"object {{parameter: number}} (as `diagnose` writes it)")
        for name, v in given.items():
            if isinstance(v, bool) or not isinstance(v, (int, float)):
                raise CompensateError(f"--diagnosis {path}: model_parameters.{cause}.{name} = {v!r:.60}: "
                                      f"allowed a number")
    side = path.with_name("diagnosis_made_from.json")
    if side.exists():
        shown = f"--diagnosis {path}: its sidecar {side}"
        made = read_json(side, name=shown, missing_hint="rerun diagnose", error=CompensateError)
        made = made.get("made_from") if isinstance(made, dict) else None
        if not isinstance(made, dict):
            raise CompensateError(f"{shown}: no made_from object (as `diagnose` writes it): rerun diagnose")
        if made.get("case_fingerprint") not in (None, case_fingerprint(case)):
            raise CompensateError(f"--diagnosis {path}: made for case {made.get('case')!r} "
                                  f"({made.get('case_source')}), not this version of {case.name}: rerun diagnose")
    return mp


def _levels(text: str | None, case, records) -> list[float]:
    if text is None:
        base = [f * case.rated_torque_Nm for f in (0.0, 0.25, 0.5, 1.0)]
        return sorted(set(base) | {round(abs(r.torque_Nm), 6) for r in records})
    try:
        vals = [float(v) for v in text.split(",") if v.strip()]
    except ValueError:
        vals = []
    top = case.operation.momentary_torque_Nm
    if not vals or not all(math.isfinite(v) and 0 <= v <= top for v in vals):
        raise CompensateError(f"--torques-Nm {text!r}: allowed comma-separated numbers 0 to {top:g} "
                              f"(the case's momentary torque)")
    return sorted(set(vals) | {round(abs(r.torque_Nm), 6) for r in records})


def run(args) -> int:
    from fem.stiffness import for_case
    from geometry.params import load_case
    case = load_case(args.case)
    if not 8 <= args.points_per_rev <= MAX_POINTS:
        raise CompensateError(f"--points-per-rev = {args.points_per_rev}: allowed 8 to {MAX_POINTS}")
    mp = read_model_parameters(args.diagnosis, case)
    from dynamics.records import read_records
    from pipeline.diagnosis.inputs import check_records
    records, notes = check_records(case, [r for p in args.check or [] for r in read_records(p)])
    for note in notes:      # repairs of the checked records (dynamics.record_checks): said at once
        print(f"warning: {note}", file=sys.stderr)
    levels = _levels(args.torques_Nm, case, records)
    stiffness = for_case(case, args.stiffness)
    from pipeline.diagnosis import compensate as comp
    try:
        ext_case, ext_stiff = comp.extended_model(case, stiffness, mp)
    except (comp.CompensationError, ValueError) as exc:
        raise CompensateError(f"--diagnosis {args.diagnosis}: {exc}") from None
    tab = comp.table(ext_case, ext_stiff, levels, args.points_per_rev)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    from geometry.artifacts import write_json_atomic, write_text_atomic
    from geometry.fingerprint import file_fingerprint, made_from
    lines = ["output_angle_deg,torque_Nm,direction,te_arcsec"] + [
        f"{a:.6g},{t:.6g},{'forward' if d > 0 else 'backward'},{v:.6f}" for a, t, d, v in tab.rows()]
    write_text_atomic(out / "compensation.csv", "\n".join(lines) + "\n")
    result = {"causes": sorted(mp), "torque_levels_Nm": levels, "points_per_rev": args.points_per_rev,
              "output_angle": "nominal input angle / i, mod 360 deg", "notes": notes}
    if records:
        result.update(comp.check(case, tab, records))
    inputs = {"diagnosis": file_fingerprint(args.diagnosis),
              **{f"check{k + 1}:{Path(p).name}": file_fingerprint(p) for k, p in enumerate(args.check or [])}}
    result["made_from"] = made_from(case, "rv-compensation/1", stiffness=stiffness.made_from, **inputs).to_json()
    write_json_atomic(out / "compensation.json", result)
    if not args.quiet:
        tail = "" if not records else (
            f"; TE RMS {result['te_rms_before_arcsec']:.2f} -> {result['te_rms_after_arcsec']:.2f} arcsec on "
            f"{len(records)} record(s), reduction {result['rms_reduction']:.1%} (published 83-94 %)")
        print(f"compensate {case.name}: {len(tab.levels)} torque/direction levels x {args.points_per_rev} points"
              f"{tail} -> {out / 'compensation.json'}")
    return 0
