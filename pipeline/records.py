"""Bench records: the CSV format shared by the bench and the simulator (DESIGN.md).

Header `time_s,input_angle_deg,output_angle_deg,output_torque_Nm`, unwrapped encoder angles
(positive forward), torque positive when the load resists forward rotation, `#` comment lines
first, more columns allowed after the four.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from geometry.artifacts import atomic_path

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
