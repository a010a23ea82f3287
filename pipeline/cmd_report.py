"""`python -m pipeline report --case CASE.toml [--build DIR]`: the static HTML report of a case."""
from __future__ import annotations

from pathlib import Path

from geometry.params import load_case
from pipeline.report import build_report


def run(args) -> int:
    case = load_case(args.case)
    path = build_report(Path(args.build) / case.name, case.name)
    if not args.quiet:
        print(f"report: {path}")
    return 0


def register(sub) -> None:
    p = sub.add_parser("report", help="write build/<case>/report/index.html from the stage artifacts")
    p.add_argument("--case", required=True, help="case file (TOML)")
    p.add_argument("--build", default="build", help="build folder holding <case name>/ (default: build)")
    p.add_argument("--quiet", action="store_true", help="no progress output")
    p.set_defaults(func=run)
