"""The operating-conditions table (DESIGN.md, `conditions`): its one home, read, validated, written.

Input CONDITIONS.csv: `#` comment lines anywhere, then a header with at least input_speed_rpm,
torque_Nm, oil_temperature_C (any order; other columns are copied through); one row per condition.
Refused in one line naming the file, the line, the column, the value and what is allowed: a file
that is missing, a folder, binary or not UTF-8, over MAX_BYTES; no header or a required column
missing; a duplicate column; a row with another number of fields; a speed that is not a finite
number > 0 (the map is of a running reducer); a torque that is not finite and >= 0 (the load's
magnitude, resisting the motion in both directions); an oil temperature outside the lubricant's
stated range; no rows; more than MAX_ROWS rows (each row is two static sweeps of one output
revolution, ~1-2 s of one core: 10^4 rows is ~3 h on 2 cores; split a larger map).
Output DIR/conditions.csv: each input row with RESULT_COLUMNS appended (TE in the bench convention,
efficiency forward, empty at zero torque); an input column named like an output column (a measured
map) is kept beside the prediction as measured_<name>.
"""
from __future__ import annotations

import csv
import io
import math
from dataclasses import dataclass
from pathlib import Path

from geometry.artifacts import InputError

REQUIRED = ("input_speed_rpm", "torque_Nm", "oil_temperature_C")
RESULT_COLUMNS = ("te_mean_fw_arcsec", "te_mean_bw_arcsec", "gap_fw_minus_bw_arcsec", "te_pp_fw_arcsec",
                  "te_pp_bw_arcsec", "efficiency", "input_torque_Nm")
MAX_ROWS = 10000
MAX_BYTES = 8 << 20
MAX_SPEED_RPM = 20000.0      # beyond any servo motor driving an RV reducer


class ConditionsError(InputError):
    """A conditions table that breaks the contract (one line: file, line, column, value, allowed)."""


@dataclass(frozen=True)
class Condition:
    input_speed_rpm: float
    torque_Nm: float
    oil_temperature_C: float
    line: int                 # line in the file (1-based), for messages
    fields: tuple             # the row as read, every column, copied through


@dataclass(frozen=True)
class ConditionsTable:
    source: str
    header: tuple
    rows: tuple               # of Condition


def _text(path: Path) -> str:
    name = f"--table {path}"
    if not path.exists():
        raise ConditionsError(f"{name}: no such file")
    if path.is_dir():
        raise ConditionsError(f"{name}: is a folder; allowed a CSV file")
    if path.stat().st_size > MAX_BYTES:
        raise ConditionsError(f"{name}: {path.stat().st_size} bytes; allowed at most {MAX_BYTES} "
                              f"(a table of at most {MAX_ROWS} conditions)")
    raw = path.read_bytes()
    if b"\0" in raw:
        raise ConditionsError(f"{name}: binary content; allowed a UTF-8 CSV text")
    try:
        return raw.decode("utf-8-sig")
    except UnicodeDecodeError:
        raise ConditionsError(f"{name}: not UTF-8 text") from None


def _number(text: str, where: str, column: str) -> float:
    try:
        v = float(text)
    except ValueError:
        raise ConditionsError(f"{where}: {column} = {text!r}: not a number") from None
    if not math.isfinite(v):
        raise ConditionsError(f"{where}: {column} = {text!r}: must be a finite number")
    return v


def read_table(path: str | Path, temperature_range_C: tuple[float, float]) -> ConditionsTable:
    """Read and validate CONDITIONS.csv (module doc); temperature_range_C: the lubricant's stated range."""
    path = Path(path)
    lines = [(i, s) for i, s in enumerate(_text(path).splitlines(), 1) if s.strip() and not s.lstrip().startswith("#")]
    name = f"--table {path}"
    if not lines:
        raise ConditionsError(f"{name}: no header; needs a header with {', '.join(REQUIRED)}")
    parsed = list(csv.reader(io.StringIO("\n".join(s for _, s in lines))))
    header = tuple(h.strip() for h in parsed[0])
    dup = sorted({h for h in header if header.count(h) > 1})
    if dup:
        raise ConditionsError(f"{name}: column {dup[0]!r} appears twice in the header")
    missing = [c for c in REQUIRED if c not in header]
    if missing:
        raise ConditionsError(f"{name}: column {missing[0]!r} missing from the header {','.join(header)!r}; "
                              f"required: {', '.join(REQUIRED)}")
    clash = [c for c in RESULT_COLUMNS if f"measured_{c}" in header and c in header]
    if clash:
        raise ConditionsError(f"{name}: columns {clash[0]!r} and 'measured_{clash[0]}' both present: the "
                              f"first would be kept as the second beside the prediction; drop one")
    n = len(parsed) - 1
    if n == 0:
        raise ConditionsError(f"{name}: no condition rows after the header")
    if n > MAX_ROWS:
        raise ConditionsError(f"{name}: {n} rows; allowed at most {MAX_ROWS} (each row is two sweeps of one "
                              f"output revolution, ~1-2 s of a core: split the table)")
    idx = {c: header.index(c) for c in REQUIRED}
    lo, hi = temperature_range_C
    rows = []
    for (line, _), fields in zip(lines[1:], parsed[1:]):
        where = f"{name} line {line}"
        if len(fields) != len(header):
            raise ConditionsError(f"{where}: {len(fields)} fields; the header has {len(header)}")
        speed = _number(fields[idx["input_speed_rpm"]].strip(), where, "input_speed_rpm")
        torque = _number(fields[idx["torque_Nm"]].strip(), where, "torque_Nm")
        temp = _number(fields[idx["oil_temperature_C"]].strip(), where, "oil_temperature_C")
        if not 0 < speed <= MAX_SPEED_RPM:
            raise ConditionsError(f"{where}: input_speed_rpm = {speed:g}: allowed (0, {MAX_SPEED_RPM:g}] rpm "
                                  f"(a running reducer; the direction is not a sign: both are predicted)")
        if torque < 0:
            raise ConditionsError(f"{where}: torque_Nm = {torque:g}: allowed >= 0 (the load's magnitude, "
                                  f"resisting the motion in both directions)")
        if not lo <= temp <= hi:
            raise ConditionsError(f"{where}: oil_temperature_C = {temp:g}: outside the lubricant's stated "
                                  f"range [{lo:g}, {hi:g}] C ([lubrication] min/max_temperature_C)")
        rows.append(Condition(speed, torque, temp, line, tuple(fields)))
    return ConditionsTable(source=str(path), header=header, rows=tuple(rows))


def check_torques(table: ConditionsTable, momentary_torque_Nm: float) -> None:
    """Torques beyond the case's momentary maximum are outside the FE stiffness tables."""
    for r in table.rows:
        if r.torque_Nm > momentary_torque_Nm:
            raise ConditionsError(f"--table {table.source} line {r.line}: torque_Nm = {r.torque_Nm:g}: allowed "
                                  f"0 to {momentary_torque_Nm:g} (the case's momentary torque)")


def measured_name(column: str) -> str:
    """An input column's name in the output: measured_<name> where it would clash with a result."""
    return f"measured_{column}" if column in RESULT_COLUMNS else column


def _cell(v) -> str:
    return "" if v is None or (isinstance(v, float) and not math.isfinite(v)) else f"{v:.6g}"


def table_text(table: ConditionsTable, results: list[dict]) -> str:
    """conditions.csv: every input column, then RESULT_COLUMNS (efficiency empty at zero torque)."""
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow([measured_name(h) for h in table.header] + list(RESULT_COLUMNS))
    for row, res in zip(table.rows, results):
        eff = res["efficiency"] if row.torque_Nm > 0 else None
        w.writerow(list(row.fields) + [_cell(eff if c == "efficiency" else res[c]) for c in RESULT_COLUMNS])
    return buf.getvalue()


def gap_lines(speed_rpm, torque_Nm, measured_arcsec, predicted_arcsec) -> dict:
    """The forward-backward gap against torque, measured beside predicted, split into its two
    physical parts. Per input speed with two torques or more, the least-squares line
    gap = a + b T: a the zero-load gap (lost motion, no-load drag), b the wind-up, both directions'
    (gap = -2 T / k, so k = 2 / |b| N m/arcsec = 120 / |b| N m/arcmin: the rigidity the line implies).
    Then two what-ifs over the rows on those lines (diagnostic, nothing is changed in the model): the
    gap RMS error with each speed's predicted slope replaced by the bench's (the stiffness right,
    the zero-load gap as predicted) and with the predicted intercept replaced by the bench's (the
    zero-load gap right, the stiffness as predicted): which part of the error each explains."""
    import numpy as np

    from dynamics.results import ARCSEC_PER_ARCMIN
    v, T = np.asarray(speed_rpm, float), np.asarray(torque_Nm, float)
    m, p = np.asarray(measured_arcsec, float), np.asarray(predicted_arcsec, float)
    by, on = {}, np.zeros(len(v), bool)
    p_slope, p_icpt = p.copy(), p.copy()
    for s in sorted(set(v.tolist())):
        k = v == s
        if len(set(T[k].tolist())) < 2:
            continue
        (bm, am), (bp, ap) = np.polyfit(T[k], m[k], 1), np.polyfit(T[k], p[k], 1)
        on |= k
        p_slope[k] -= (bp - bm) * T[k]
        p_icpt[k] -= ap - am
        by[f"{s:g}"] = {"rows": int(k.sum()), "measured_arcsec_per_Nm": float(bm), "predicted_arcsec_per_Nm": float(bp),
                        "measured_zero_load_gap_arcsec": float(am), "predicted_zero_load_gap_arcsec": float(ap),
                        "measured_rigidity_Nm_per_arcmin": 2 * ARCSEC_PER_ARCMIN / abs(bm) if bm else None,
                        "predicted_rigidity_Nm_per_arcmin": 2 * ARCSEC_PER_ARCMIN / abs(bp) if bp else None}
    rms = lambda e: float(np.sqrt(np.mean(e ** 2))) if len(e) else None  # noqa: E731
    return {"by_speed_rpm": by, "rows_on_lines": int(on.sum()),
            "gap_rms_error_on_lines_arcsec": rms(p[on] - m[on]),
            "gap_rms_error_with_bench_slopes_arcsec": rms(p_slope[on] - m[on]),
            "gap_rms_error_with_bench_zero_load_gaps_arcsec": rms(p_icpt[on] - m[on])}


# What-ifs of the bench's own chain (not the prediction: the dataset does not say where its output encoder
# sits): where the output encoder reads beyond the torque meter, the meter's twist adds to every gap. Torque
# flanges of the bench's class, HBM TB1A data sheet (B0161), torsion angle at the nominal torque:
TORQUE_FLANGES = (("HBM TB1A 2 kN m", 2000.0, 0.034), ("HBM TB1A 5 kN m", 5000.0, 0.029))


def torque_flange_rigidities() -> list[tuple[str, float, float]]:
    """(name, nominal torque [N m], torsional stiffness [N m/rad]) of each of TORQUE_FLANGES."""
    return [(name, nominal, nominal / math.radians(angle)) for name, nominal, angle in TORQUE_FLANGES]


def torque_flange_range_text() -> str:
    """The TORQUE_FLANGES' span in words, for the evidence and report lines that set a fitted compliance
    beside a bench's torque meter: 'a 2-5 kN m torque flange is 980-2874 N m/arcmin, HBM TB1A data sheet'."""
    from dynamics.results import ARCSEC_PER_ARCMIN, ARCSEC_PER_RAD
    f = torque_flange_rigidities()
    kn = [n / 1e3 for _, n, _ in f]
    r = [k * ARCSEC_PER_ARCMIN / ARCSEC_PER_RAD for _, _, k in f]
    return (f"a {min(kn):g}-{max(kn):g} kN m torque flange is {min(r):.0f}-{max(r):.0f} N m/arcmin, "
            f"HBM TB1A data sheet")


def chain_whatifs(torque_Nm, measured_arcsec, predicted_arcsec) -> list[dict]:
    """Per flange of TORQUE_FLANGES: its torsional stiffness k and the gap RMS error with its twist added to
    the predicted gap (a series spring adds exactly -2 T / k to forward minus backward, the bench's
    convention; couplings not counted)."""
    import numpy as np

    from dynamics.results import ARCSEC_PER_ARCMIN, ARCSEC_PER_RAD
    T, m, p = (np.asarray(x, float) for x in (torque_Nm, measured_arcsec, predicted_arcsec))
    out = []
    for name, _, k in torque_flange_rigidities():
        with_chain = p - 2.0 * T / k * ARCSEC_PER_RAD
        out.append({"flange": name, "source": "HBM TB1A data sheet B0161: torsion angle at nominal torque",
                    "stiffness_Nm_per_rad": k, "rigidity_Nm_per_arcmin": k * ARCSEC_PER_ARCMIN / ARCSEC_PER_RAD,
                    "gap_rms_error_arcsec": float(np.sqrt(np.mean((with_chain - m) ** 2)))})
    return out


# What-if of the parts' temperatures (not the prediction: dynamics.thermal): both discs this much warmer
# than every other part, at the table's fastest speed
DISC_WARMER_K = (2.0, 4.0)


def thermal_whatif(torque_Nm, gap_by_dT: dict, lines: dict, speed_rpm: float) -> dict | None:
    """What discs dT warmer than the ring do to the gap line at one speed, beside the bench's change of
    its line from its slowest to its fastest speed. gap_by_dT: {dT [K]: predicted gaps at torque_Nm}
    (0 K the prediction); lines: gap_lines(...)["by_speed_rpm"] of the measured table. Per dT the line
    gap = a + b T; the change per K of a [arcsec] and of b [% of b at 0 K] (least squares through the
    dTs); the bench's change a_fast - a_slow and (b_fast - b_slow) / b_slow; and the kelvin that
    would give each (None where the model's change per K has the other sign or is nil)."""
    import numpy as np
    T = np.asarray(torque_Nm, float)
    if len(set(T.tolist())) < 2 or 0.0 not in gap_by_dT:
        return None
    dTs = sorted(gap_by_dT)
    fits = {dT: np.polyfit(T, np.asarray(gap_by_dT[dT], float), 1) for dT in dTs}
    a = np.array([fits[dT][1] for dT in dTs])
    b = np.array([fits[dT][0] for dT in dTs])
    da = float(np.polyfit(dTs, a, 1)[0])
    db_pct = float(np.polyfit(dTs, b, 1)[0] / b[0] * 100.0)
    out = {"speed_rpm": float(speed_rpm), "rows": int(len(T)), "disc_warmer_K": [float(d) for d in dTs],
           "zero_load_gap_arcsec": a.tolist(), "arcsec_per_Nm": b.tolist(),
           "zero_load_gap_change_arcsec_per_K": da, "wind_up_change_pct_per_K": db_pct}
    speeds = sorted(lines, key=float)
    if len(speeds) >= 2:
        slow, fast = lines[speeds[0]], lines[speeds[-1]]
        d_a = fast["measured_zero_load_gap_arcsec"] - slow["measured_zero_load_gap_arcsec"]
        d_b = (fast["measured_arcsec_per_Nm"] - slow["measured_arcsec_per_Nm"]) / slow["measured_arcsec_per_Nm"] * 100.0
        kelvin = lambda need, per_K: need / per_K if per_K and need / per_K > 0 else None  # noqa: E731
        out.update({"bench_speeds_rpm": [float(speeds[0]), float(speeds[-1])],
                    "bench_zero_load_gap_change_arcsec": float(d_a), "bench_wind_up_change_pct": float(d_b),
                    "kelvin_for_bench_zero_load_gap_change": kelvin(d_a, da),
                    "kelvin_for_bench_wind_up_change": kelvin(d_b, db_pct)})
    return out
