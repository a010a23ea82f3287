"""Order spectra: a signal over output rotation, resampled uniformly in output angle.

Orders are cycles per output revolution (DESIGN.md "characteristic orders"). Resampling on the
output angle (not time) keeps the lines sharp when the speed varies. Amplitudes are single-sided
(a pure A sin(k theta) gives amplitude A at order k) and need an integer number of revolutions
for leakage-free lines; a partial final revolution is dropped.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class OrderSpectrum:
    order: np.ndarray        # cycles per output revolution
    amplitude: np.ndarray    # single-sided amplitude, units of the signal
    phase_rad: np.ndarray    # phase of cos(order * theta + phase)
    revolutions: int         # whole output revolutions analysed

    def at(self, order: float) -> float:
        """Amplitude of the line nearest to `order`."""
        return float(self.amplitude[np.argmin(np.abs(self.order - order))])


def resample_on_angle(output_angle_deg: np.ndarray, signal: np.ndarray,
                      points_per_rev: int = 4096) -> tuple[np.ndarray, np.ndarray]:
    """Signal on a uniform output-angle grid from the first sample over whole revolutions.

    Works for either direction of rotation (the angle is taken relative to its start, by magnitude).
    """
    theta = np.asarray(output_angle_deg, dtype=float)
    s = np.asarray(signal, dtype=float)
    travel = np.abs(theta - theta[0])
    if np.any(np.diff(travel) < 0):
        order = np.argsort(travel, kind="stable")
        travel, s = travel[order], s[order]
    revs = int(np.floor(travel[-1] / 360.0 + 1e-9))
    if revs < 1:
        raise ValueError(f"order spectrum needs at least one output revolution; got {travel[-1]:.1f} deg")
    grid = np.arange(revs * points_per_rev) * (360.0 / points_per_rev)
    return grid, np.interp(grid, travel, s)


def order_spectrum(output_angle_deg: np.ndarray, signal: np.ndarray,
                   points_per_rev: int = 4096) -> OrderSpectrum:
    grid, s = resample_on_angle(output_angle_deg, signal, points_per_rev)
    revs = len(grid) // points_per_rev
    c = np.fft.rfft(s - s.mean()) / len(s)
    amp = 2.0 * np.abs(c)
    amp[0] = 0.0
    order = np.arange(len(c)) / revs
    return OrderSpectrum(order=order, amplitude=amp, phase_rad=np.angle(c), revolutions=revs)
