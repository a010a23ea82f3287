"""`python -m pipeline <stage> ...`: one entry point, one module per group of stages.

Each command module exposes `register(subparsers)`, which adds its sub-commands and sets
`func(args) -> int` on them. Errors a user can cause (InputError) print one clear line and exit 2.
"""
from __future__ import annotations

import argparse
import importlib
import sys

from geometry.artifacts import InputError

# Command modules, in pipeline order; each registers one or more sub-commands.
COMMAND_MODULES = (
    "pipeline.cmd_geometry",   # geometry
    "pipeline.cmd_fem",        # fem
    "pipeline.cmd_dynamics",   # simulate, matrix, hysteresis
    "pipeline.cmd_fourbar",    # fourbar, tolerance
    "pipeline.cmd_diagnose",   # diagnose
    "pipeline.cmd_report",     # report
)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="python -m pipeline",
                                     description="FE-informed transmission-error pipeline for RV reducers")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for name in COMMAND_MODULES:
        try:
            module = importlib.import_module(name)
        except ModuleNotFoundError as exc:
            if exc.name != name:   # a real missing dependency, not a stage not yet written
                raise
            continue
        module.register(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args) or 0)
    except InputError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("interrupted: no partial artifact was written", file=sys.stderr)
        return 130
