"""`python -m pipeline report --case CASE.toml [--build DIR]`: the static HTML report of a case.

The page goes to <build>/<case name>/report/index.html and nowhere else: the case name (validated
by geometry.params) must be one plain folder right under the build folder.
"""
from __future__ import annotations

from pathlib import Path

from geometry.artifacts import InputError
from geometry.fingerprint import case_fingerprint
from geometry.params import load_case
from pipeline import checks
from pipeline.report import build_report


def case_folder(build: str | Path, name: str) -> Path:
    """<build>/<name>, refused unless it is exactly one folder level below the build folder."""
    build = Path(build)
    folder = build / name
    if Path(name).name != name or name in ("", ".", "..") or folder.resolve().parent != build.resolve():
        raise InputError(f"case name {name!r}: the report would leave the build folder {build}; "
                         f"allowed: a plain folder name (letters, digits, . _ -)")
    return folder


def run(args) -> int:
    case = load_case(args.case)
    build = Path(args.build)
    if not args.build.strip() or not build.is_dir():   # a mistyped --build would get a report of nothing
        what = "an empty path" if not args.build.strip() else "is a file" if build.exists() else "no such folder"
        raise InputError(f"--build {args.build!r}: {what}; allowed "
                         f"the build folder that holds {case.name}/ (`make all` writes build/)")
    folder = case_folder(build, case.name)
    checks.out_folder("report folder", folder / "report")
    path = build_report(folder, case.name, case_fingerprint(case),
                        rated_torque_Nm=case.rated_torque_Nm, ratio=case.ratio)
    if not args.quiet:
        print(f"report: {path}")
    return 0


def register(sub) -> None:
    p = sub.add_parser("report", help="write build/<case>/report/index.html from the stage artifacts")
    p.add_argument("--case", required=True, help="case file (TOML)")
    p.add_argument("--build", default="build", help="build folder holding <case name>/ (default: build)")
    p.add_argument("--quiet", action="store_true", help="no progress output")
    p.set_defaults(func=run)
