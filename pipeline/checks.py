"""Up-front checks of command-line options and output paths, and the clean-up of stale temporaries.

Each check runs before any heavy import or computation and raises `InputError` with one line: the
option, the value and what is allowed (the CLI prints `error: ...` and exits 2), so a bad request
costs a second and never touches an earlier artifact.
"""
from __future__ import annotations

import math
import os
import re
import tempfile
from pathlib import Path
from typing import Callable

from geometry.artifacts import InputError

# geometry.artifacts.atomic_path writes `.<stem>.<8 random chars><suffix>` (tempfile.mkstemp's
# name alphabet) beside the target and renames it; a SIGKILL can leave one behind.
_RANDOM = r"[a-z0-9_]{8}"
_STALE_TEMP = re.compile(rf"^\.(?P<stem>.+)\.{_RANDOM}(?P<suffix>\.[A-Za-z0-9]+)?$")

# Time integration (simulate, matrix): dynamics.model.simulate holds its drive, load and sampled
# output arrays for every step: peak 58 B per step (tracemalloc, 1 s and 3 s runs, rv40e-81), and
# it integrates about 1 s of run per wall second at dt 1e-4 s. 1e7 steps: ~0.6 GB and ~15 min.
MAX_TIME_STEPS = 10_000_000
BYTES_PER_STEP = 60
MAX_DT_S = 1e-3                # the model refuses coarser steps (pin contacts unresolved)
MAX_INPUT_SPEED_RPM = 10_000.0  # above any servo motor driving an RV reducer


def number_in(option: str, value: float, lo: float, hi: float, unit: str = "", *,
              lo_open: bool = False, why: str = "") -> float:
    """value if finite and lo <(=) value <= hi, else InputError naming the option and the range."""
    ok = math.isfinite(value) and (value > lo if lo_open else value >= lo) and value <= hi
    if not ok:
        u = f" {unit}" if unit else ""
        rng = f"{'>' if lo_open else '>='} {lo:g}{u} and <= {hi:g}{u}"
        raise InputError(f"{option} = {value:g}{u}: allowed {rng}{f' ({why})' if why else ''}")
    return value


def int_in(option: str, value: int, lo: int, hi: int, why: str = "") -> int:
    if not lo <= value <= hi:
        raise InputError(f"{option} = {value}: allowed {lo} to {hi}{f' ({why})' if why else ''}")
    return value


def run_length(duration_s: float, dt_s: float | None, default_dt_s: Callable[[], float]) -> None:
    """--dt and --duration of a time integration: the run must fit MAX_TIME_STEPS steps.
    default_dt_s() gives the model's step when --dt is not given (called only then: the model's
    module imports numba, and this module stays free of it so every stage's CLI can use it)."""
    if not (math.isfinite(duration_s) and duration_s > 0.0):
        raise InputError(f"--duration = {duration_s:g} s: allowed > 0 s (and at most {MAX_TIME_STEPS:.0e} "
                         "time steps of --dt)")
    dt = default_dt_s() if dt_s is None else dt_s
    number_in("--dt", dt, 0.0, MAX_DT_S, "s", lo_open=True,
              why="coarser steps do not resolve the pin contacts")
    longest = MAX_TIME_STEPS * dt
    if duration_s > longest:
        raise InputError(f"--duration = {duration_s:g} s: allowed > 0 s and <= {longest:g} s at --dt {dt:g} s "
                         f"(at most {MAX_TIME_STEPS:.0e} time steps: the run keeps ~{BYTES_PER_STEP} B of arrays "
                         f"per step in memory; {duration_s:g} s would be {duration_s / dt:.3g} steps, "
                         f"{duration_s / dt * BYTES_PER_STEP / 2**30:.3g} GiB)")


def input_speed(speed_rpm: float | None) -> None:
    if speed_rpm is not None:
        number_in("--speed-rpm", speed_rpm, 0.0, MAX_INPUT_SPEED_RPM, "rpm", lo_open=True,
                  why="the input turns forward; use --backward to reverse it")


def _writable_anchor(option: str, path: Path, shown: Path | None = None) -> Path:
    """The nearest existing folder at or above `path`; it must be a folder we can write in."""
    shown = path if shown is None else shown
    anchor = path
    while not anchor.exists():
        if anchor.parent == anchor:
            break
        anchor = anchor.parent
    if not anchor.is_dir():
        raise InputError(f"{option} {shown}: {anchor} is a file, not a folder; give a path in a folder")
    try:    # a real probe: os.access says yes to root on a folder it still cannot write (sysfs, ro mounts)
        with tempfile.TemporaryFile(dir=anchor):
            pass
    except OSError as exc:
        raise InputError(f"{option} {shown}: cannot write in {anchor} ({exc.strerror or exc}); "
                         "give a folder you can write to") from None
    return anchor


def _not_empty(option: str, path: str | os.PathLike) -> None:
    """An empty path is Path('.'): the artifacts would land in the current folder, the run lock above it."""
    if not os.fspath(path).strip():
        raise InputError(f"{option} {os.fspath(path)!r}: an empty path; give the output's path")


def out_folder(option: str, path: str | os.PathLike) -> Path:
    """An output folder: existing and writable, or creatable (nothing is created here)."""
    _not_empty(option, path)
    path = Path(path)
    if path.exists() and not path.is_dir():
        raise InputError(f"{option} {path}: is an existing file, this stage writes a folder; "
                         "give a folder path")
    _writable_anchor(option, path)
    return path


def out_file(option: str, path: str | os.PathLike) -> Path:
    """An output file: not a folder, in a folder that is (or can be made) writable."""
    _not_empty(option, path)
    text, path = os.fspath(path), Path(path)
    if path.is_dir() or text.endswith(("/", os.sep)):
        raise InputError(f"{option} {text}: is a folder, this stage writes one file; give a file path")
    _writable_anchor(option, path.parent, shown=path)
    return path


def remove_stale_temps(folder: str | os.PathLike, target: str | None = None) -> list[Path]:
    """Remove temporaries of our atomic writes left in `folder` by a killed run (SIGKILL, power
    loss): every `.<stem>.<random><suffix>` there, or only those of the file `target` (a shared
    folder, e.g. simulate's records). Nothing else is touched; run it only where no other run of
    the same stage writes at the same time (Make never does)."""
    folder = Path(folder)
    if not folder.is_dir():
        return []
    if target is not None:
        t = Path(target)
        pattern = re.compile(rf"^\.{re.escape(t.stem)}\.{_RANDOM}{re.escape(t.suffix)}$")
    else:
        pattern = _STALE_TEMP
    removed = []
    for p in folder.iterdir():
        if pattern.match(p.name) and p.is_file() and not p.is_symlink():
            p.unlink(missing_ok=True)
            removed.append(p)
    return removed
