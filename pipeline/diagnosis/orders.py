"""Order-domain view of a record: the characteristic orders of the case and spectra of whole
output revolutions (DESIGN.md "Kinematics and characteristic orders"; pin housing fixed).

Spectra come from dynamics.spectrum.order_spectrum (one FFT-on-angle in the project). A bench that
samples one output revolution ends one sample short of closing it; such a record (travel within
`closing_deg` of a whole number of revolutions) is stretched onto the whole revolution before the
FFT: the order scale changes by < 0.1 %, far below the 1-order bin width of a one-revolution record.
"""
from __future__ import annotations

import numpy as np

from dynamics.spectrum import OrderSpectrum, order_spectrum


def characteristic_orders(case) -> dict[str, float]:
    """Named orders per output revolution, lowest first (harmonics are labelled by `label_order`)."""
    c, s1 = case.cycloid, case.stage1
    named = {"1x (carrier, coaxiality)": 1.0,
             f"{case.carrier.crank_count}x (crank positions)": float(case.carrier.crank_count),
             f"zc={c.zc}x (disc teeth)": float(c.zc),
             f"zp={c.zp}x (pins, crankshaft rotation)": float(c.zp),
             f"i={case.ratio:g}x (input shaft)": float(case.ratio),
             f"zp*zc={c.zp * c.zc}x (cycloid-pin mesh)": float(c.zp * c.zc),
             f"zp*z2={c.zp * s1.z2}x (involute mesh)": float(c.zp * s1.z2)}
    return dict(sorted(named.items(), key=lambda kv: kv[1]))


def label_order(case, order: float, tol: float = 0.25) -> str:
    """Name an order by the characteristic order (or harmonic up to 4) it sits on, else by the
    crank sideband of a pin-ring order it sits on (m zc +- k n_crank, k = 1, 2: a housing pattern
    whose load zone the cranks modulate; through this model no cause makes one: a housing
    stiffness lobe with any crank-side error puts < 0.01 arcsec there), else ''."""
    best = ""
    for name, base in characteristic_orders(case).items():
        for h in (1, 2, 3, 4):
            if abs(order - h * base) <= tol:
                label = name if h == 1 else f"{h} x {name.split(' ')[0]}"
                if not best or h == 1:
                    best = label
    if best:
        return best
    zc, n = case.cycloid.zc, case.carrier.crank_count
    for m in (1, 2, 3, 4):
        for k in (1, 2):
            for sg in (1, -1):
                if abs(order - (m * zc + sg * k * n)) <= tol:
                    return f"{m} zc {'+' if sg > 0 else '-'} {k * n}: crank sideband of {m * zc}x"
    return ""


def spectrum_of(output_angle_deg: np.ndarray, signal: np.ndarray, closing_deg: float | None = None,
                points_per_rev: int = 4096) -> OrderSpectrum:
    """Order spectrum over the whole revolutions of a record (see module docstring)."""
    theta = np.asarray(output_angle_deg, dtype=float)
    travel = abs(theta[-1] - theta[0])
    if closing_deg is None:
        closing_deg = 1.5 * float(np.median(np.abs(np.diff(theta))))
    whole = np.round(travel / 360.0)
    if whole >= 1 and 0 < whole * 360.0 - travel <= closing_deg:
        theta = theta[0] + (theta - theta[0]) * (whole * 360.0 / travel)
    return order_spectrum(theta, signal, points_per_rev)
