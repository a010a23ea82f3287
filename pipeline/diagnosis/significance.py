"""Is a spectral line above the record's own noise floor?

Model: away from real lines, the complex order coefficient of a stationary noise is circular
Gaussian, so the single-sided amplitude A of a bin is Rayleigh distributed with scale sigma:
P(A > a) = exp(-a^2 / (2 sigma^2)), median(A) = sigma sqrt(2 ln 2). sigma is estimated per line from
the median amplitude of its neighbouring bins (a median ignores the few real lines among them).
A line is significant when its false-alarm probability, Bonferroni-corrected over the lines tested,
is below `p_fa`: noise alone then names a line with probability < p_fa per record.
Limits: coloured noise is handled only as far as it is flat over the neighbourhood (+-`half_window`
bins); a line closer than `guard` bins to a stronger one shares its leakage.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from dynamics.spectrum import OrderSpectrum
from pipeline.diagnosis.orders import spectrum_of

_RAYLEIGH_MEDIAN = np.sqrt(2.0 * np.log(2.0))


@dataclass(frozen=True)
class Line:
    order: float
    amplitude: float          # single-sided, units of the signal
    noise_sigma: float        # Rayleigh scale of the local floor (= std of Re or Im of 2c_k)
    p_value: float            # probability that noise alone reaches this amplitude
    significant: bool


def noise_sigma(amplitude: np.ndarray, index: int, half_window: int = 12, guard: int = 1) -> float:
    """Rayleigh scale of the noise around bin `index` from the median of its neighbours."""
    n = len(amplitude)
    lo, hi = max(1, index - half_window - guard), min(n, index + half_window + guard + 1)
    nb = np.r_[amplitude[lo:max(lo, index - guard)], amplitude[min(hi, index + guard + 1):hi]]
    if nb.size < 4:   # at the spectrum's edge: widen one-sided
        nb = amplitude[max(1, n - 2 * half_window):n]
    return float(np.median(nb) / _RAYLEIGH_MEDIAN) + 1e-300


def test_lines(spec: OrderSpectrum, orders, p_fa: float = 1e-3, half_window: int = 12) -> list[Line]:
    """Lines at the given orders (nearest bins) with their significance (see module docstring)."""
    orders = [float(k) for k in orders]
    out = []
    for k in orders:
        idx = int(np.argmin(np.abs(spec.order - k)))
        sigma = noise_sigma(spec.amplitude, idx, half_window)
        a = float(spec.amplitude[idx])
        p = float(np.exp(-a * a / (2.0 * sigma * sigma)))
        out.append(Line(float(spec.order[idx]), a, sigma, p, p * max(len(orders), 1) < p_fa))
    return out


# ASSUMED: no bench resolves TE below a tenth of the +-1 arcsec accuracy grade of the best absolute
# angle encoders (Heidenhain RCN 8000 class); an effect smaller than this is not measurable.
MIN_NOISE_ARCSEC = 0.1


def sample_noise(output_angle_deg, signal) -> float:
    """Std of the broadband noise of one record [signal units], from its order spectrum's floor:
    the median Rayleigh scale over the bins (lines are few among them) gives, for white noise on
    N samples, sigma_n = sigma_R sqrt(N / 2) (Parseval), N the samples the spectrum rests on (the
    record's own over its whole revolutions, at most the resampled grid's)."""
    spec = spectrum_of(output_angle_deg, signal)
    travel = abs(float(output_angle_deg[-1] - output_angle_deg[0]))
    n = min(len(signal) * min(spec.revolutions * 360.0 / max(travel, 1e-12), 1.0), 2 * (len(spec.amplitude) - 1))
    amp = spec.amplitude[1:int(n // 4) + 1]      # bins to half the record's own Nyquist order:
    # the angle resampling's linear interpolation attenuates the upper half
    if amp.size < 4:
        return 0.0
    return float(np.median(amp) / _RAYLEIGH_MEDIAN) * float(np.sqrt(n / 2.0))


def noise_floor_arcsec(records, residuals) -> float:
    """The records' noise floor: RMS over the records of their broadband noise (sample_noise), at
    least MIN_NOISE_ARCSEC."""
    s = [sample_noise(r.output_angle_deg, x) for r, x in zip(records, residuals)]
    return max(float(np.sqrt(np.mean(np.square(s)))) if s else 0.0, MIN_NOISE_ARCSEC)
