"""`python -m pipeline <stage> ...`: one entry point, one module per group of stages.

Each command module exposes `register(subparsers)`, which adds its sub-commands and sets
`func(args) -> int` on them. Errors a user can cause (InputError) print one clear line and exit 2.
"""
from __future__ import annotations

import argparse
import importlib
import multiprocessing
import os
import signal
import sys

from geometry.artifacts import InputError
from pipeline import checks, runlock

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
    "signatures": ("pipeline.cmd_signatures", "as-built error atlas: each error source alone through the model"),
    "diagnose": ("pipeline.cmd_diagnose", "measured records -> causes, extension, gain"),
    "compensate": ("pipeline.cmd_compensate", "diagnosis' extended model -> TE compensation table, checked on records"),
    "paper001": ("pipeline.cmd_diagnose", "paper 001's no-load bench case: coaxiality that closes the gap"),
    "conditions": ("pipeline.cmd_conditions", "operating map: TE gap, efficiency, input torque per condition (friction, lubrication)"),
    "sensitivity": ("pipeline.cmd_sensitivity", "catalog rigidity against each size of the case (what a teardown would have to find)"),
    "report": ("pipeline.cmd_report", "static HTML report of a case"),
}
FILE_OUTPUT = {"simulate"}     # `--out` is one file; every other stage's `--out` is a folder


class UsageError(InputError):
    """A command line argparse cannot read (unknown option, missing or malformed value)."""


class _Parser(argparse.ArgumentParser):
    def error(self, message):    # one `error:` line and exit 2 like every other user error
        # the top-level parser reports a command's unknown options: point at that command's help
        raise UsageError(f"{message} (`{getattr(self, 'help_prog', self.prog)} --help` lists the options)")


def build_parser(command: str | None = None) -> argparse.ArgumentParser:
    """The parser; with `command`, only that command's module is imported and registered."""
    parser = _Parser(
        prog="python -m pipeline",
        description="FE-informed transmission-error pipeline for RV reducers",
        epilog="commands: " + "; ".join(f"{k}: {h}" for k, (_, h) in COMMANDS.items()))
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    if command in COMMANDS:
        parser.help_prog = f"{parser.prog} {command}"
        importlib.import_module(COMMANDS[command][0]).register(sub)
    else:
        for name, (_, help_text) in COMMANDS.items():   # listed for --help and error messages
            sub.add_parser(name, help=help_text)
    return parser


INTERRUPTED = "interrupted: no partial artifact was written (finished parts are kept; rerun to complete)"
_RUN: dict = {}     # the parsed arguments of this process's run, for the signal handler


def _on_signal(signum, frame):
    """SIGTERM (a killed batch job, `make` interrupted) or Ctrl-C: stop now, leave nothing behind.

    Raising KeyboardInterrupt wherever the main thread happens to be is not safe: inside a C
    callback it can crash the process, a library's broad `except` can swallow it (the run then
    goes on for minutes), and it can leave the interpreter exiting by SIGINT after it was handled.
    So the handler ends the run itself: it terminates the pool workers, removes the temporaries
    of this run's --out (finished artifacts were renamed into place and stay) and exits with
    128 + signum. Commands without --out unwind by KeyboardInterrupt as before."""
    if _RUN.get("pid", os.getpid()) != os.getpid():   # a forked worker before its own handlers are set
        os._exit(128 + signum)
    args = _RUN.get("args")
    if args is not None and getattr(args, "out", None) is None:
        raise KeyboardInterrupt(signum)
    children = multiprocessing.active_children()
    for child in children:
        child.terminate()
    for child in children:
        child.join(timeout=5)
    if args is not None:
        _clear_temps(args)
    runlock.release(_RUN.get("lock"))
    try:    # the main thread may have been stopped inside a write to these very streams
        sys.stdout.flush()
        print(INTERRUPTED, file=sys.stderr, flush=True)
    except (RuntimeError, OSError, ValueError):
        pass
    os._exit(128 + signum)


def _check_output(args) -> tuple | None:
    """Refuse an unusable --out before anything runs, take the output's run lock (pipeline.runlock:
    a second run on the same output waits for it), then clear what a killed run left there. Returns
    the lock (None without --out)."""
    out = getattr(args, "out", None)
    if out is None:
        return None
    if args.command in FILE_OUTPUT:
        path = checks.out_file("--out", out)
        folder, target = path.parent, path.name
    else:
        folder, target = checks.out_folder("--out", out), None
    lock = runlock.acquire(out, f"python -m pipeline {args.command}", os.fspath(out))
    checks.remove_stale_temps(folder, target=target)
    return lock


def _clear_temps(args) -> None:
    """After an interrupt: the temporaries of this run's --out (killed workers, unfinished writes)."""
    out = getattr(args, "out", None)
    try:
        if out is not None and args.command in FILE_OUTPUT:
            checks.remove_stale_temps(os.path.dirname(os.fspath(out)) or ".", target=os.path.basename(out))
        elif out is not None:
            checks.remove_stale_temps(out)
    except OSError:
        pass


def main(argv: list[str] | None = None) -> int:
    if argv is None:   # a real process, not a call from Python code: act on signals from the start
        signal.signal(signal.SIGTERM, _on_signal)
        signal.signal(signal.SIGINT, _on_signal)
    words = sys.argv[1:] if argv is None else argv
    args, lock = None, None
    try:
        parser = build_parser(next((w for w in words if not w.startswith("-")), None))
        args = parser.parse_args(argv)
        lock = _check_output(args)
        if argv is None:
            _RUN.update(args=args, pid=os.getpid(), lock=lock)
        return int(args.func(args) or 0)
    except InputError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    except OSError as exc:
        if exc.filename is None:    # not about a path the user gave or made: a bug, keep the traceback
            raise
        print(f"error: {exc.filename}: {exc.strerror or exc}", file=sys.stderr)
        return 2
    except MemoryError:
        # inputs are bounded before heavy work; what still exhausts the memory (a large case on a small
        # machine, many workers) ends like an interrupt: one line, no partial artifact
        if args is not None:
            _clear_temps(args)
        what = f"`{args.command}`" if args is not None else "the command line"
        print(f"error: {what} ran out of memory; no partial artifact was written (fewer --workers or a "
              f"coarser mesh or grid need less)", file=sys.stderr)
        return 2
    except KeyboardInterrupt as exc:
        if args is not None:
            _clear_temps(args)
        print(INTERRUPTED, file=sys.stderr)
        signum = exc.args[0] if exc.args and isinstance(exc.args[0], int) else signal.SIGINT
        return 128 + int(signum)
    finally:
        runlock.release(lock)
