"""`python -m pipeline <stage> ...`: one entry point, one module per group of stages.

Each command module exposes `register(subparsers)`, which adds its sub-commands and sets
`func(args) -> int` on them. Errors a user can cause (InputError) print one clear line and exit 2.
"""
from __future__ import annotations

import argparse
import importlib
import signal
import sys

from geometry.artifacts import InputError

# Sub-command -> the module that registers it. Only the module of the command asked for is
# imported (CadQuery, numba, scikit-fem take seconds to import), so `--help` and errors stay quick.
COMMANDS = {
    "geometry": ("pipeline.cmd_geometry", "CadQuery solids, profile, clearance and backlash"),
    "mesh": ("pipeline.cmd_fem", "2D contact and 3D crankshaft meshes"),
    "fem": ("pipeline.cmd_fem", "FE stiffness map -> stiffness.json (or --benchmark hertz)"),
    "simulate": ("pipeline.cmd_dynamics", "one load case -> a bench-format record"),
    "matrix": ("pipeline.cmd_dynamics", "paper 001's 12 load cases, sigma table, spectra"),
    "hysteresis": ("pipeline.cmd_dynamics", "catalog test: rigidity, lost motion, backlash"),
    "fourbar": ("pipeline.cmd_fourbar", "paper 000's four-bar original-error analysis"),
    "tolerance": ("pipeline.cmd_fourbar", "Monte Carlo tolerance analysis (local or Dask)"),
    "diagnose": ("pipeline.cmd_diagnose", "measured records -> causes, extension, gain"),
    "paper001": ("pipeline.cmd_diagnose", "paper 001's no-load bench case: coaxiality that closes the gap"),
    "report": ("pipeline.cmd_report", "static HTML report of a case"),
}


def build_parser(command: str | None = None) -> argparse.ArgumentParser:
    """The parser; with `command`, only that command's module is imported and registered."""
    parser = argparse.ArgumentParser(
        prog="python -m pipeline",
        description="FE-informed transmission-error pipeline for RV reducers",
        epilog="commands: " + "; ".join(f"{k}: {h}" for k, (_, h) in COMMANDS.items()))
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    if command in COMMANDS:
        importlib.import_module(COMMANDS[command][0]).register(sub)
    else:
        for name, (_, help_text) in COMMANDS.items():   # listed for --help and error messages
            sub.add_parser(name, help=help_text)
    return parser


def _terminate(signum, frame):
    # SIGTERM (a killed batch job, `make` interrupted) unwinds like Ctrl-C, so every atomic write
    # in progress removes its temporary file and no partial artifact is left behind.
    raise KeyboardInterrupt


def main(argv: list[str] | None = None) -> int:
    words = sys.argv[1:] if argv is None else argv
    parser = build_parser(next((w for w in words if not w.startswith("-")), None))
    args = parser.parse_args(argv)
    if argv is None:   # a real process, not a call from Python code
        signal.signal(signal.SIGTERM, _terminate)
    try:
        return int(args.func(args) or 0)
    except InputError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("interrupted: no partial artifact was written", file=sys.stderr)
        return 130
