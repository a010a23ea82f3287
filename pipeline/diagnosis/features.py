"""The linear map from a TE signal over one record to the features the diagnosis fits.

Per record: the mean over its whole output revolutions (the order-0 term, where encoder zeros,
wind-up and lost motion live) and the complex amplitude a_k = A_k exp(i phi_k) of each order k of
interest (Re and Im as two features). The map is linear, so a residual and the model's signatures
go through the same map and stay comparable; each feature carries the noise standard deviation of
the record's own floor (significance.noise_sigma): Re and Im of a_k have std sigma_k (the Rayleigh
scale), the mean has std sigma_0 / sqrt(2) (white-noise relation between |c_0| and |c_k|).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from dynamics.spectrum import resample_on_angle
from pipeline.diagnosis.orders import spectrum_of
from pipeline.diagnosis.significance import noise_sigma


@dataclass(frozen=True)
class FeatureMap:
    """Features of one record: mean, then (Re, Im) per order in `orders`."""
    output_angle_deg: np.ndarray
    orders: tuple[int, ...]

    @property
    def size(self) -> int:
        return 1 + 2 * len(self.orders)

    def _theta(self) -> np.ndarray:
        th = self.output_angle_deg
        travel = abs(th[-1] - th[0])
        whole = max(np.round(travel / 360.0), 1.0)
        return th[0] + (th - th[0]) * (whole * 360.0 / travel) if travel < whole * 360.0 else th

    def apply(self, signal: np.ndarray) -> np.ndarray:
        spec = spectrum_of(self.output_angle_deg, signal)
        _, s = resample_on_angle(self._theta(), signal)
        out = np.empty(self.size)
        out[0] = s.mean()
        for j, k in enumerate(self.orders):
            idx = int(np.argmin(np.abs(spec.order - k)))
            a = spec.amplitude[idx] * np.exp(1j * spec.phase_rad[idx])
            out[1 + 2 * j], out[2 + 2 * j] = a.real, a.imag
        return out

    def noise_std(self, residual: np.ndarray, half_window: int = 12) -> np.ndarray:
        """Per-feature noise std from the residual's own spectrum (see module docstring)."""
        spec = spectrum_of(self.output_angle_deg, residual)
        out = np.empty(self.size)
        out[0] = noise_sigma(spec.amplitude, 0, half_window) / np.sqrt(2.0)
        for j, k in enumerate(self.orders):
            idx = int(np.argmin(np.abs(spec.order - k)))
            out[1 + 2 * j] = out[2 + 2 * j] = noise_sigma(spec.amplitude, idx, half_window)
        return out
