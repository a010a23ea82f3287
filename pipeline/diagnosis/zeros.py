"""Encoder-zero groups: which records share one arbitrary TE offset.

The absolute zero of TE on a bench is arbitrary: one constant offset per zeroing of the encoders is
a free parameter, while differences between records of one zeroing are physical (DESIGN.md). Rule,
in order:
  1. a comment line `# encoder_zero: <id>` puts the record in group <id> (explicit always wins);
  2. otherwise a forward and a backward record of the same |torque| and input speed (within
     `torque_tol_Nm` and `speed_tol_rpm`) share one zero: the bench convention of
     ../shared/measured/README.md (each condition run forward then backward, zeroed alone); pairs
     are formed first come first served in the order given, one forward with one backward;
  3. otherwise the record is alone.
Limits: rule 2 cannot tell a paired run from two independent zeroings; say `encoder_zero` then.
Also here: removing the free offsets (`remove_offsets`, `offset_columns`) and the RMS reported.
"""
from __future__ import annotations

import numpy as np

from dynamics.records import BenchRecord


def group_records(records: list[BenchRecord], torque_tol_Nm: float = 5.0,
                  speed_tol_rpm: float = 5.0) -> list[str]:
    """One zero-group id per record (same id = same encoder zero)."""
    groups: list[str | None] = [None] * len(records)
    for k, r in enumerate(records):
        if r.encoder_zero is not None:
            groups[k] = f"zero:{r.encoder_zero}"
    for k, r in enumerate(records):
        if groups[k] is not None:
            continue
        for j in range(k + 1, len(records)):
            q = records[j]
            if groups[j] is None and q.direction != r.direction \
                    and abs(abs(q.torque_Nm) - abs(r.torque_Nm)) <= torque_tol_Nm \
                    and abs(q.input_speed_rpm - r.input_speed_rpm) <= speed_tol_rpm:
                groups[k] = groups[j] = f"pair:{r.name}+{q.name}"
                break
        if groups[k] is None:
            groups[k] = f"alone:{r.name}"
    return groups  # type: ignore[return-value]


def remove_offsets(residuals, groups) -> list[np.ndarray]:
    """Subtract each zero group's least-squares offset (its mean over all its samples)."""
    out = [np.asarray(r, float).copy() for r in residuals]
    for g in set(groups):
        idx = [k for k, gg in enumerate(groups) if gg == g]
        m = np.concatenate([out[k] for k in idx]).mean()
        for k in idx:
            out[k] -= m
    return out


def rms(arrays) -> float:
    x = np.concatenate([np.asarray(a) for a in arrays]) if len(arrays) else np.zeros(1)
    return float(np.sqrt(np.mean(x * x)))


def offset_columns(fmaps, groups, idx) -> np.ndarray:
    """One column per zero group of records idx: 1 on each record's mean feature (stacked rows
    of features.FeatureMap)."""
    idx = list(idx)
    gids = list(dict.fromkeys(groups[k] for k in idx))
    X = np.zeros((sum(fmaps[k].size for k in idx), len(gids)))
    pos = 0
    for k in idx:
        X[pos, gids.index(groups[k])] = 1.0
        pos += fmaps[k].size
    return X
