"""`python -m pipeline diagnose --case CASE.toml --measured R1.csv [R2.csv ...] --out DIR`

Writes DIR/diagnosis.json (DESIGN.md keys) and DIR/index.html. Stiffness defaults to
build/<case.name>/fem/stiffness.json. `--columns NAME=SOURCE,...` (and `--no-header`) read records
with other column names or none; nothing is guessed. A file whose motion reverses (forward then
backward) is refused, or with `--split-reversals` split into one record per direction
(dynamics.records.read_records). Records are checked against the case before any fitting
(pipeline.diagnosis.inputs, dynamics.record_checks: a refused record is one `error:` line, exit 2;
a repaired one a `warning:` line on stderr, even with --quiet, and a line of diagnosis.json's
`notes`). `--holdout R ...`: records never used to name or fit a cause; holdout_gain is computed on exactly
them. Progress (one tick per record simulated through the model, on stderr, only on a terminal),
the diagnosis notes (input repairs, causes not reported and why, residual left unexplained; one
`note:` line each on stderr, also in index.html) and a one-line summary (stdout) are shown unless
--quiet.
"""
from __future__ import annotations

import sys

from pathlib import Path

from geometry.artifacts import InputError


class DiagnoseError(InputError):
    """A diagnose request that cannot run (missing stiffness, no records)."""


def register(sub) -> None:
    p = sub.add_parser("diagnose", help="diagnose bench records against the model")
    p.add_argument("--case", required=True)
    p.add_argument("--measured", required=True, nargs="+")
    p.add_argument("--holdout", nargs="+", default=None,
                   help="records never used to name or fit a cause; the hold-out gain is computed on exactly them")
    p.add_argument("--out", required=True)
    p.add_argument("--stiffness", default=None, help="stiffness.json (default build/<case>/fem/stiffness.json)")
    p.add_argument("--columns", default=None, help="column map NAME=SOURCE,... (SOURCE a name or 0-based index)")
    p.add_argument("--no-header", action="store_true", help="records have no header row (needs --columns)")
    p.add_argument("--split-reversals", action="store_true",
                   help="split a record whose motion reverses into one record per direction (default: refuse it)")
    p.add_argument("--points-per-rev", type=int, default=None,
                   help="simulated points per output revolution (default: the stroboscopic grid above twice the "
                        "highest order read, 390 for zp = 40)")
    p.add_argument("--workers", type=int, default=None,
                   help="local processes solving the records' conditions (default: the machine's cores)")
    p.add_argument("--quiet", action="store_true", help="no progress bar and no summary line")
    p.set_defaults(func=run)
    w = sub.add_parser("paper001", help="paper 001's no-load bench case as a worked example "
                                        "(simulated peak-to-peak, coaxiality that closes the gap)")
    w.add_argument("--case", required=True)
    w.add_argument("--out", required=True)
    w.add_argument("--stiffness", default=None, help="stiffness.json (default build/<case>/fem/stiffness.json)")
    w.add_argument("--quiet", action="store_true")
    w.set_defaults(func=run_paper001)


def run_paper001(args) -> int:
    from fem.stiffness import for_case
    from geometry.artifacts import write_json_atomic
    from geometry.params import load_case
    from pipeline.diagnosis.paper001 import worked_example
    case = load_case(args.case)
    from geometry.fingerprint import made_from
    stiffness = for_case(case, args.stiffness)
    ex = worked_example(case, stiffness)
    path = Path(args.out) / "paper001.json"
    write_json_atomic(path, {"case": case.name, **ex, "made_from": made_from(
        case, "rv-paper001/1", stiffness=stiffness.made_from).to_json()})
    if not args.quiet:
        print(f"paper001 {case.name}: simulated no-load peak-to-peak {ex['simulated_pp_arcsec']:.3f} arcsec "
              f"vs measured {ex['measured_arcsec']} arcsec: closed by {ex['coaxiality_closing_um']:.2f} um "
              f"coaxiality at r = {ex['output_flange_radius_mm']:g} mm -> {path}")
    return 0


MAX_POINTS_PER_REV = 16384   # 40x the default: the model is solved at every simulated point


def check_points_per_rev(value: int | None, case) -> int | None:
    """Enough points per output revolution to resolve the crank order zp (Nyquist), at most MAX."""
    if value is None:
        return None
    lo = 2 * case.cycloid.zp + 2
    if not lo <= value <= MAX_POINTS_PER_REV:
        raise DiagnoseError(f"--points-per-rev = {value}: allowed {lo} to {MAX_POINTS_PER_REV} (at least "
                            f"2 zp + 2 to resolve the zp = {case.cycloid.zp} crank order; each point is a "
                            "model solve)")
    return value


def run(args) -> int:
    from fem.stiffness import for_case
    from geometry.params import load_case
    case = load_case(args.case)     # options first, before the diagnosis machinery is imported
    check_points_per_rev(args.points_per_rev, case)
    if args.workers is not None and not 1 <= args.workers <= 64:
        raise DiagnoseError(f"--workers = {args.workers}: allowed 1 to 64 local processes")
    from pipeline.diagnosis.diagnose import diagnose
    from pipeline.diagnosis.report import write_report
    from pipeline.diagnosis.simulate import quasi_static_te
    from dynamics.records import parse_column_map, read_record, read_records
    from pipeline.diagnosis.inputs import check_records
    stiffness = for_case(case, args.stiffness)
    cols = parse_column_map(args.columns) if args.columns else None
    _check_holdout(args.measured, args.holdout)

    def read(p):
        return read_records(p, cols, header=not args.no_header) if args.split_reversals else \
            [read_record(p, cols, header=not args.no_header)]
    records = [r for p in args.measured for r in read(p)]
    held = [r for p in (args.holdout or []) for r in read(p)]
    holdout = tuple(range(len(records), len(records) + len(held))) if args.holdout else None
    records, warnings = check_records(case, records + held)   # before the heavy work: said at once
    for w in warnings:
        print(f"warning: {w}", file=sys.stderr)
    te_model, bar = quasi_static_te, None
    if not args.quiet and sys.stderr.isatty():   # a bar in a log file is one line of carriage returns
        from tqdm import tqdm
        bar = tqdm(desc="diagnose", unit=" record sims", file=sys.stderr)
        te_model = _ticking(quasi_static_te, bar)
    try:
        diag = diagnose(case, stiffness, records, te_model, points_per_rev=args.points_per_rev,
                        holdout_records=holdout, workers=args.workers)
    finally:
        if bar is not None:
            bar.close()
    import dataclasses
    diag = dataclasses.replace(diag, notes=tuple(warnings) + tuple(n for n in diag.notes if n not in warnings))
    _add_made_from(Path(args.out) / "diagnosis.json", case, stiffness, args.measured + (args.holdout or []))
    out = write_report(diag, case, args.out)
    if not args.quiet:
        for note in diag.notes[len(warnings):]:
            print(f"note: {note}", file=sys.stderr)
        print(summary_line(diag, out))
    return 0


def _check_holdout(measured: list[str], holdout: list[str] | None) -> None:
    """A held-out record is not also a fitted one (the same file given to both options)."""
    both = {str(Path(p).resolve()) for p in measured} & {str(Path(p).resolve()) for p in holdout or []}
    if both:
        raise DiagnoseError(f"--holdout {', '.join(sorted(both))}: also given to --measured; a held-out "
                            f"record is never fitted, give it to one option only")


def _add_made_from(path: Path, case, stiffness, records: list[str]) -> None:
    """What diagnosis.json was made from (the case, the stiffness, each bench record), in the sidecar
    diagnosis_made_from.json: diagnosis.json itself keeps exactly DESIGN.md's keys."""
    from geometry.artifacts import write_json_atomic
    from geometry.fingerprint import file_fingerprint, made_from
    inputs = {f"record{k + 1}:{Path(r).name}": file_fingerprint(r) for k, r in enumerate(records)}
    write_json_atomic(Path(path).with_name("diagnosis_made_from.json"), {"made_from": made_from(
        case, "rv-diagnosis/1", stiffness=stiffness.made_from, **inputs).to_json()})


def _ticking(te_model, bar):
    """te_model that ticks `bar` once per record simulated."""
    def wrapped(*a, **k):
        out = te_model(*a, **k)
        bar.update(1)
        return out
    wrapped.__wrapped__ = te_model   # still the project's model (simulate.simulate_records)
    return wrapped


def summary_line(diag, out) -> str:
    """cause, baseline RMS, extension causes, gain and holdout gain, where the report went."""
    e = diag.extension
    ext = "no extension" if e is None else (
        f"extension {'+'.join(e.causes)}: gain {e.gain:.3f}, holdout "
        + ("n/a" if e.holdout_gain is None else f"{e.holdout_gain:.3f}"))
    return (f"diagnose: cause {diag.cause}; {len(diag.findings)} finding(s); baseline RMS "
            f"{diag.residual_rms_arcsec:.2f} arcsec; {ext} -> {out}")
