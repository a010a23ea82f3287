"""The signature library: each error source alone, at unit size, through the model.

A cause (causes/, registry `causes.CAUSES`) is a set of model parameters p (zero = the case as
given) and `apply(case, stiffness, p)` returning the perturbed case and stiffness. Its signature on
a record is the model's TE change per unit parameter, (TE(p = u e_j) - TE(0)) / u, u the cause's
`unit_size`, at that record's angles, torque and direction, so the orders, harmonic pattern, load
and direction dependence all come from the model, not a table. Each cause module documents its
parameters, unit size and expected signature. The library is a linearisation (a secant for the
threshold causes, `dc_even`); the extension (diagnose.py) refits on the full model.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from pipeline.diagnosis.orders import spectrum_of


def signature_columns(te_of: Callable, case, stiffness, cause,
                      base_te: list[np.ndarray]) -> list[np.ndarray]:
    """Per record (n_samples, n_params) TE change per unit parameter; te_of(case, stiffness)
    returns the list of simulated TE per record."""
    n, unit = len(cause.params(case)), cause.unit_size
    cols = [np.empty((len(b), n)) for b in base_te]
    for j in range(n):
        p = np.zeros(n)
        p[j] = unit
        c2, s2 = cause.apply(case, stiffness, p)
        for r, te in enumerate(te_of(c2, s2)):
            cols[r][:, j] = (te - base_te[r]) / unit
    return cols


@dataclass(frozen=True)
class SignatureSummary:
    """What a unit parameter does, read from the model (for evidence and the report)."""
    cause: str
    orders: tuple[int, ...]            # dominant orders (>= 10 % of the strongest line)
    line_arcsec: tuple[float, ...]     # their amplitudes per unit (largest over the parameters)
    mean_shift_arcsec: dict            # record name -> mean TE change per unit
    amplitude_by_torque: dict          # |torque| -> strongest line per unit


def summarise(cause_id: str, records, cols: list[np.ndarray], max_order: int,
              rel: float = 0.1) -> SignatureSummary:
    amp = None
    shift, by_t = {}, {}
    ks = np.arange(1, max_order + 1)
    for rec, c in zip(records, cols):
        a = np.zeros(max_order + 1)
        for j in range(c.shape[1]):   # every parameter: a cause's harmonics sit in different columns
            sp = spectrum_of(rec.output_angle_deg, c[:, j])
            idx = np.argmin(np.abs(sp.order[None, :] - ks[:, None]), axis=1)   # the bin nearest each order k
            on = np.abs(sp.order[idx] - ks) < 0.5
            a[ks[on]] = np.maximum(a[ks[on]], sp.amplitude[idx[on]])
        amp = a if amp is None else np.maximum(amp, a)
        shift[rec.name] = float(np.mean(c[:, 0]))
        by_t[round(abs(rec.torque_Nm), 1)] = float(a.max())
    amp = amp if amp is not None else np.zeros(max_order + 1)
    peak = amp.max()
    orders = tuple(int(k) for k in np.flatnonzero(amp >= rel * peak) if k > 0) if peak > 0 else ()
    return SignatureSummary(cause_id, orders, tuple(float(amp[k]) for k in orders), shift, by_t)
