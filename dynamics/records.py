"""Bench records: the CSV format shared by the bench and the simulator (DESIGN.md); the one home
of this file contract (dynamics' simulate writes records, pipeline's diagnosis reads them).

Header `time_s,input_angle_deg,output_angle_deg,output_torque_Nm`, unwrapped encoder angles
(positive forward), torque positive when the load resists forward rotation, `#` comment lines
first, more columns allowed after the four.

Loader (`read_record`): checks every row and names the file and the 1-based line of the problem
(missing column, non-numeric or non-finite value, non-increasing time, wrapped angle, a jump across
a time gap larger than the speed explains, a reversal of the motion, shorter than one output
revolution). Samples need not be uniform in time: a gap moves the angles by speed x gap and is no
wrap. `read_records` splits a file whose motion reverses (forward then backward) into one record per
direction. Rows are parsed by numpy's C reader (2 million rows in seconds); a row it cannot read
is then found and named by the row-by-row reader. Other column names or headerless files are read
only through an explicit column map: nothing is guessed. The conditions the diagnosis simulates
(input speed, torque, direction) are read from the record's own samples; comments are kept (they
carry notes such as `# encoder_zero: <id>`, `# input_speed_rpm: 1800`, `comment_value`). A path
that is no readable UTF-8 text file (a folder, no permission, binary or other-encoding content) is
refused in one line naming the file.
"""
from __future__ import annotations

import re
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path

import numpy as np

from dynamics.results import ARCSEC_PER_DEG
from geometry.artifacts import InputError, atomic_path, read_text

COLUMNS = ("time_s", "input_angle_deg", "output_angle_deg", "output_torque_Nm")


def write_record(path: str | Path, time_s, input_angle_deg, output_angle_deg, output_torque_Nm,
                 comments: list[str] = (), extra: dict[str, np.ndarray] | None = None) -> None:
    """Write a record atomically; `extra` adds named columns after the four required ones."""
    cols = [np.asarray(c, dtype=float) for c in (time_s, input_angle_deg, output_angle_deg,
                                                output_torque_Nm)]
    names = list(COLUMNS)
    for name, values in (extra or {}).items():
        names.append(name)
        cols.append(np.asarray(values, dtype=float))
    n = len(cols[0])
    if any(len(c) != n for c in cols):
        raise ValueError("record columns differ in length")
    header = "".join(f"# {line}\n" for line in comments) + ",".join(names)
    with atomic_path(path) as tmp:
        np.savetxt(tmp, np.column_stack(cols), delimiter=",", header=header, comments="",
                   fmt="%.10g")


def write_te_result(path: str | Path, result, comments: list[str] = ()) -> None:
    """A simulated run (dynamics.results.TEResult) as a bench record, plus te_arcsec and
    teeth_in_contact_disc<k> columns."""
    extra = {"te_arcsec": result.te_arcsec}
    for d in range(result.teeth_in_contact.shape[1]):
        extra[f"teeth_in_contact_disc{d + 1}"] = result.teeth_in_contact[:, d]
    write_record(path, result.t_s, result.input_angle_deg, result.output_angle_deg,
                 result.output_torque_Nm, comments=list(comments), extra=extra)


# ---------------------------------------------------------------------------------------------
# Loader
# ---------------------------------------------------------------------------------------------
# A bench sampling one output revolution ends one sample short of closing it (n samples span
# n - 1 steps); a record covers a revolution if its travel plus this many median steps reaches 360.
_CLOSING_STEPS = 1.5
# Largest plausible encoder step between two samples beyond what the speed explains; a step this
# large is a wrap (+-360 deg).
_MAX_STEP_DEG = 180.0
# A time step this many times the median is a gap in the record (data missing), not a wrap.
_GAP_STEPS = 5.0


class RecordError(InputError):
    """A bench record that cannot be read as DESIGN.md's format; the message names file, row
    (1-based line of the file) and problem."""


def comment_number(comments, key: str) -> float | None:
    """The number of a `<key>: <number> [unit]` comment line, if there is one (the record's notes)."""
    for line in comments:
        m = re.match(rf"\s*{re.escape(key)}\s*[:=]\s*([-+0-9.eE]+)\s*(\S*)\s*$", line)
        if m:
            try:
                return float(m.group(1))
            except ValueError:
                return None
    return None


@dataclass(frozen=True)
class BenchRecord:
    """One bench record as read, with the conditions the diagnosis needs read from the record.

    Arrays are in the file's units (s, deg, N.m); `comments` are the `#` lines without the `#`.
    """
    path: str
    time_s: np.ndarray
    input_angle_deg: np.ndarray
    output_angle_deg: np.ndarray
    output_torque_Nm: np.ndarray
    comments: tuple[str, ...] = ()
    extra: dict = field(default_factory=dict)

    @property
    def name(self) -> str:
        return Path(self.path).name

    @property
    def direction(self) -> int:
        """+1 forward, -1 backward: the sign of the output travel (net, over the record)."""
        return 1 if self.output_angle_deg[-1] >= self.output_angle_deg[0] else -1

    @property
    def output_travel_deg(self) -> float:
        return float(abs(self.output_angle_deg[-1] - self.output_angle_deg[0]))

    # cached (the record is frozen): the diagnosis asks at every simulation of every record, and
    # medians and percentiles over all samples were 4 % of a real-records run
    @cached_property
    def input_speed_rpm(self) -> float:
        """Magnitude of the running input speed: the median of the sample-to-sample speed, so a
        start-up ramp (paper 001's 1 s in 7 s) is not averaged in (1200 rpm, not ~1100)."""
        dt = np.diff(self.time_s)
        ok = dt > 0
        return float(np.median(np.abs(np.diff(self.input_angle_deg)[ok] / dt[ok])) / 6.0)

    @cached_property
    def torque_Nm(self) -> float:
        """Median output torque (signed: positive resists forward rotation)."""
        return float(np.median(self.output_torque_Nm))

    @cached_property
    def torque_spread_Nm(self) -> float:
        """The 5-95 % spread of the output torque (a steady record's is small)."""
        return float(np.subtract(*np.percentile(self.output_torque_Nm, [95, 5])))

    @property
    def encoder_zero(self) -> str | None:
        """The id of an explicit `# encoder_zero: <id>` comment, if the record carries one."""
        for line in self.comments:
            m = re.match(r"\s*encoder_zero\s*[:=]\s*(\S+)", line)
            if m:
                return m.group(1)
        return None

    def comment_value(self, key: str) -> float | None:
        """The number of a `# <key>: <number>` comment (e.g. input_speed_rpm), if there is one."""
        return comment_number(self.comments, key)

    def te_arcsec(self, ratio: float) -> np.ndarray:
        """Transmission error theta_out - theta_in / i (arcsec, positive = output ahead)."""
        return (self.output_angle_deg - self.input_angle_deg / ratio) * ARCSEC_PER_DEG


def parse_column_map(text: str) -> dict[str, str | int]:
    """`time_s=t,output_angle_deg=3,...` -> {required column: source name or 0-based index}."""
    out: dict[str, str | int] = {}
    for item in filter(None, (s.strip() for s in text.split(","))):
        key, sep, value = item.partition("=")
        key, value = key.strip(), value.strip()
        if not sep or key not in COLUMNS or not value:
            raise RecordError(f"column map {text!r}: item {item!r} must be NAME=SOURCE with NAME one "
                              f"of {', '.join(COLUMNS)} and SOURCE a column name or 0-based index")
        out[key] = int(value) if value.isdigit() else value
    return out


def read_record(path: str | Path, columns: dict[str, str | int] | None = None,
                header: bool = True) -> BenchRecord:
    """Read and check a bench record; raise RecordError naming file, row and problem.

    `columns` maps a required column to the source's name (or 0-based index); it is the only way
    to read other names (`header=True`) or headerless files (`header=False`, indices required).
    Without it the four DESIGN.md names must be present: nothing is guessed. A record whose
    motion reverses is refused, saying where (`read_records` splits it).
    """
    path, comments, linenos, data, extra = _parse(Path(path), columns, header)
    t, a_in, a_out, torque = data.T
    _check_steps(path, linenos, t, a_in, a_out)
    cuts = reversals(a_in)
    if cuts:
        k = cuts[0]
        raise RecordError(f"{path}: row {linenos[k]}: the motion reverses (output "
                          f"{a_out[k] - a_out[0]:+.2f} deg, then {a_out[-1] - a_out[k]:+.2f} deg); a record "
                          f"runs one direction: split it there (diagnose --split-reversals does)")
    _check_travel(path, linenos, a_out)
    return BenchRecord(str(path), t, a_in, a_out, torque, tuple(comments), extra)


def read_records(path: str | Path, columns: dict[str, str | int] | None = None,
                 header: bool = True) -> list[BenchRecord]:
    """The record(s) of one file: split where the motion reverses (a forward-then-backward run),
    each part checked alone and named `<file>#fw`, `#bw` (numbered if a direction repeats); the
    parts of one file share one encoder zero (`encoder_zero: <file name>` unless the file says)."""
    path, comments, linenos, data, extra = _parse(Path(path), columns, header)
    t, a_in, a_out, _ = data.T
    _check_steps(path, linenos, t, a_in, a_out)
    cuts = reversals(a_in)
    if not cuts:
        _check_travel(path, linenos, a_out)
        return [BenchRecord(str(path), *data.T, tuple(comments), extra)]
    bounds = [0, *cuts, len(t) - 1]
    dirs = ["fw" if a_out[b] >= a_out[a] else "bw" for a, b in zip(bounds[:-1], bounds[1:])]
    zero = () if any(re.match(r"\s*encoder_zero\s*[:=]", c) for c in comments) else (f"encoder_zero: {path.name}",)
    out = []
    for j, (a, b) in enumerate(zip(bounds[:-1], bounds[1:])):
        n = dirs[:j + 1].count(dirs[j])
        tag = dirs[j] + (str(n) if dirs.count(dirs[j]) > 1 else "")
        sl = slice(a, b + 1)
        _check_travel(Path(f"{path} (rows {linenos[a]}-{linenos[b]}, {tag} part)"), linenos[sl], a_out[sl])
        out.append(BenchRecord(f"{path}#{tag}", *(c[sl] for c in data.T), tuple(comments) + zero,
                               {k: v[sl] for k, v in extra.items()}))
    return out


def reversals(angle_deg, hysteresis_deg: float = 360.0) -> list[int]:
    """Indices where the motion reverses: an extreme from which the angle then retreats by more
    than `hysteresis_deg` (one input turn: far above encoder noise, and a glitch that large is
    refused as a jump anyway)."""
    a = np.asarray(angle_deg, float)
    cuts, sign, k, n = [], 0, 0, len(a)
    while k < n - 1:   # zig-zag: the running extreme of the current direction, confirmed by a retreat
        if sign == 0:
            up = np.flatnonzero(np.abs(a[k:] - a[k]) > hysteresis_deg)
            if not up.size:
                break
            sign = 1 if a[k + up[0]] > a[k] else -1
            continue
        seg = sign * a[k:]
        run_ext = np.maximum.accumulate(seg)
        back = np.flatnonzero(run_ext - seg > hysteresis_deg)
        if not back.size:
            break
        j = k + int(np.argmax(seg[:back[0] + 1]))
        cuts.append(j)
        k, sign = j, -sign
    return cuts


def _parse(path: Path, columns, header):
    """(path, comments, file line of each data row, (n, 4) data, extra columns) of a record file."""
    lines = _text_lines(path)
    comments, rows, linenos = [], [], []
    for lineno, line in enumerate(lines, start=1):
        s = line.strip()
        if not s:
            continue
        if s[0] == "#":
            if not rows:    # comments carry the conditions; keep those before the data
                comments.append(s[1:].strip())
            continue
        rows.append(s)
        linenos.append(lineno)
    columns = dict(columns or {})
    names = None
    if header:
        if not rows:
            raise RecordError(f"{path}: no header row (expected {','.join(COLUMNS)})")
        head_line, names = linenos.pop(0), [c.strip() for c in rows.pop(0).split(",")]
        idx = {}
        for col in COLUMNS:
            src = columns.get(col, col)
            if isinstance(src, int):
                if src >= len(names):
                    raise RecordError(f"{path}: row {head_line}: column index {src} for {col} beyond "
                                      f"the {len(names)} columns of the header")
                idx[col] = src
            elif src in names:
                idx[col] = names.index(src)
            else:
                hint = "" if columns else " (use a column map for other names)"
                raise RecordError(f"{path}: row {head_line}: missing column {src!r} for {col}; "
                                  f"header has {', '.join(names)}{hint}")
    else:
        missing = [c for c in COLUMNS if not isinstance(columns.get(c), int)]
        if missing:
            raise RecordError(f"{path}: a headerless record needs a 0-based column index for "
                              f"{', '.join(missing)} (column map NAME=INDEX)")
        idx = {c: columns[c] for c in COLUMNS}
    if not rows:
        raise RecordError(f"{path}: no data rows")
    table = _fast_table(rows)
    if table is None or table.shape[1] <= max(idx.values()):
        return path, comments, linenos, *_slow_table(path, rows, linenos, idx, names)
    data = table[:, [idx[c] for c in COLUMNS]]
    bad = np.flatnonzero(~np.isfinite(data).all(axis=1))
    if bad.size:
        r = int(bad[0])
        j = int(np.flatnonzero(~np.isfinite(data[r]))[0])
        cell = rows[r].split(",")[idx[COLUMNS[j]]].strip()
        raise RecordError(f"{path}: row {linenos[r]}: {COLUMNS[j]} = {cell!r}; values must be finite "
                          f"(no NaN or inf)")
    extra = {nm: table[:, k] for k, nm in enumerate(names or ()) if k not in idx.values() and k < table.shape[1]}
    return path, comments, np.asarray(linenos), data, extra


def _fast_table(rows: list[str]) -> np.ndarray | None:
    """All rows as one float table (numpy's C parser), or None when any cell is not a number or
    the rows differ in width: the row-by-row reader then names the first problem."""
    import io
    try:
        with np.errstate(all="ignore"):
            return np.loadtxt(io.StringIO("\n".join(rows)), delimiter=",", ndmin=2, dtype=float)
    except ValueError:
        return None


def _slow_table(path, rows, linenos, idx, names):
    data = np.empty((len(rows), len(COLUMNS)))
    width = max(idx.values()) + 1
    cells_all = [[c.strip() for c in s.split(",")] for s in rows]
    for r, (lineno, cells) in enumerate(zip(linenos, cells_all)):
        if len(cells) < width:
            raise RecordError(f"{path}: row {lineno}: {len(cells)} values, expected at least {width}")
        for j, col in enumerate(COLUMNS):
            cell = cells[idx[col]]
            try:
                v = float(cell)
            except ValueError:
                raise RecordError(f"{path}: row {lineno}: {col} = {cell!r} is not a number") from None
            if not np.isfinite(v):
                raise RecordError(f"{path}: row {lineno}: {col} = {cell!r}; values must be finite "
                                  f"(no NaN or inf)")
            data[r, j] = v
    extra = {}
    if names is not None:
        for k, nm in enumerate(names):
            if k not in idx.values():
                vals = [float(c[k]) if k < len(c) and _is_number(c[k]) else np.nan for c in cells_all]
                extra[nm] = np.asarray(vals)
    return np.asarray(linenos), data, extra


_ALLOWED = f"a record is a UTF-8 text CSV with the header {','.join(COLUMNS)}"
# the real bench records are < 0.5 MB; 256 MiB is ~5 million samples (over 8 min at 10 kHz): a larger
# file is refused before it is read (parsed, it would take several times its size in memory)
RECORD_MAX_BYTES = 256 * 2**20


def _text_lines(path: Path) -> list[str]:
    """The lines of a record file; anything that is not a readable UTF-8 text file is refused."""
    return read_text(path, what="record", error=RecordError, allowed=_ALLOWED, refuse_nul=True,
                     max_bytes=RECORD_MAX_BYTES, wording={"missing": "record not found"}).splitlines()


def _is_number(s: str) -> bool:
    try:
        float(s)
        return True
    except ValueError:
        return False


def _check_steps(path: Path, linenos, t, a_in, a_out) -> None:
    if len(t) < 3:
        raise RecordError(f"{path}: {len(t)} data rows; a record needs at least one output revolution")
    dt = np.diff(t)
    bad = np.flatnonzero(dt <= 0)
    if bad.size:
        k = bad[0] + 1
        raise RecordError(f"{path}: row {linenos[k]}: time_s = {t[k]:g} does not increase "
                          f"(previous {t[k - 1]:g}); time must be strictly increasing")
    for name, a in (("input_angle_deg", a_in), ("output_angle_deg", a_out)):
        step = np.diff(a)
        # what the speed explains over each step (a time gap moves the angle by speed x gap)
        rate = float(np.median(step / dt))
        jump = np.flatnonzero(np.abs(step - rate * dt) > _MAX_STEP_DEG)
        if jump.size:
            k = jump[0] + 1
            gap = dt[k - 1] > _GAP_STEPS * float(np.median(dt))
            why = (f"in a time gap of {dt[k - 1]:g} s, {step[k - 1] - rate * dt[k - 1]:+.6g} deg more than "
                   f"the speed explains: the run is not continuous across it" if gap else
                   f"the angle is wrapped, not unwrapped (steps must stay below {_MAX_STEP_DEG:g} deg; "
                   f"unwrap it, e.g. numpy.unwrap)")
            raise RecordError(f"{path}: row {linenos[k]}: {name} jumps by {step[k - 1]:+.6g} deg "
                              f"between samples: {why}")


def _check_travel(path: Path, linenos, a_out) -> None:
    travel = abs(a_out[-1] - a_out[0])
    closing = _CLOSING_STEPS * float(np.median(np.abs(np.diff(a_out))))
    if travel + closing < 360.0:
        raise RecordError(f"{path}: row {linenos[-1]}: the output turns {travel:.2f} deg over the "
                          f"record; at least one output revolution (360 deg) is needed to resolve "
                          f"the 1x order")
