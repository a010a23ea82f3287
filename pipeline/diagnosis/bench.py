"""Virtual bench: records from the model plus a hidden effect, for blind tests of the diagnosis.

A seeded generator draws the cause, its size and phase (`draw_effect`); `bench_records` runs the
model with the effect (quasi-static, the same path the diagnosis uses) under forward/backward
pairs at a few torques, adds a random encoder zero per pair, Gaussian angle noise and encoder
quantisation (both encoders, `encoder_bits` counts per turn), and returns BenchRecords exactly as
the loader would (write them with `write_records` to test the CLI). Truth is kept beside the
records in `HiddenEffect.truth`, in the units diagnosis.json reports.
Sizes drawn (a tolerance-class error, well above the noise):
  output_coaxiality         e in [5, 25] um, phase in [-180, 180) deg
  crank_eccentricity_error  one eccentric journal off size: disc 1's eccentric on one crank j
                            (uniform over the cranks) by e, |e| in [4, 10] um, either sign
                            (Errors.eccentric_error_um); the model answers a zp x line of ~0.85
                            arcsec per um (RV-40E, signatures.py), 3.4-8.5 arcsec here.
  torsional_stiffness       factor c in [0.55, 0.8] or [1.3, 1.8] on every FE stiffness
  backlash                  extra pin clearance in [4, 12] um (equidistant modification)
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from dynamics.results import ARCSEC_PER_DEG
from pipeline.diagnosis.signatures import _backlash, _coaxiality, _eccentric, _stiffness, eccentric_pattern
from pipeline.records import BenchRecord, write_record

CAUSES = ("output_coaxiality", "crank_eccentricity_error", "torsional_stiffness", "backlash")


@dataclass(frozen=True)
class HiddenEffect:
    cause: str
    p: tuple[float, ...]          # parameters in signatures.py units
    truth: dict = field(default_factory=dict)


def draw_effect(rng: np.random.Generator, case, cause: str) -> HiddenEffect:
    if cause == "output_coaxiality":
        e, ph = rng.uniform(5.0, 25.0), rng.uniform(-180.0, 180.0)
        return HiddenEffect(cause, (e * np.cos(np.radians(ph)), e * np.sin(np.radians(ph))),
                            {"output_coaxiality_um": e, "output_coaxiality_phase_deg": ph})
    if cause == "crank_eccentricity_error":
        n = case.carrier.crank_count
        j, e = int(rng.integers(n)), rng.uniform(4.0, 10.0) * (1.0 if rng.random() < 0.5 else -1.0)
        p = np.zeros(n)
        p[j] = e
        a, ph, _ = eccentric_pattern(p)
        return HiddenEffect(cause, tuple(float(v) for v in p), {
            "crank_eccentricity_error_um": [float(v) for v in p], "crank_eccentricity_error_crank": j + 1,
            "crank_eccentricity_error_single_um": float(e), "crank_eccentricity_error_amplitude_um": a,
            "crank_eccentricity_error_phase_deg": ph})
    if cause == "torsional_stiffness":
        c = rng.uniform(0.55, 0.8) if rng.random() < 0.5 else rng.uniform(1.3, 1.8)
        return HiddenEffect(cause, (1.0 / c - 1.0,), {"stiffness_factor": c})
    if cause == "backlash":
        um = rng.uniform(4.0, 12.0)
        return HiddenEffect(cause, (um,), {"pin_clearance_um": um})
    raise ValueError(f"cause {cause!r}: allowed {', '.join(CAUSES)}")


_APPLY = {"output_coaxiality": _coaxiality, "crank_eccentricity_error": _eccentric,
          "torsional_stiffness": _stiffness, "backlash": _backlash}


def apply_effects(case, stiffness, effects):
    for e in effects:
        case, stiffness = _APPLY[e.cause](case, stiffness, np.asarray(e.p, float))
    return case, stiffness


def bench_records(te_model, case, stiffness, effects, *, seed: int,
                  torque_fractions=(0.03, 0.3, 0.6), samples_per_rev: int = 256,
                  noise_arcsec: float = 0.3, encoder_bits: int = 22, speed_rpm: float | None = None
                  ) -> list[BenchRecord]:
    """Forward/backward pairs (one output revolution each) at torque_fractions x rated."""
    rng = np.random.default_rng(seed)
    hidden_case, hidden_stiff = apply_effects(case, stiffness, effects)
    speed = speed_rpm or case.operation.input_speed_rpm
    q = 360.0 / 2 ** encoder_bits
    out = []
    for frac in torque_fractions:
        T = frac * case.rated_torque_Nm
        zero = rng.uniform(-30.0, 30.0)          # encoder zero of this pair [arcsec]
        for d in (1, -1):
            # each run covers one output revolution from the encoders' common home
            th_in = (0.0 if d > 0 else 360.0 * case.ratio) + d * np.linspace(0.0, 360.0 * case.ratio,
                                                                              samples_per_rev + 1)
            te = te_model(hidden_case, hidden_stiff, th_in, d * T, d)
            te = te + zero + rng.normal(0.0, noise_arcsec, te.shape)
            a_in = np.round(th_in / q) * q
            a_out = np.round((th_in / case.ratio + te / ARCSEC_PER_DEG) / q) * q
            t = np.abs(th_in - th_in[0]) / (6.0 * speed)
            name = f"virtual_{frac:g}rated_{'fw' if d > 0 else 'bw'}.csv"
            out.append(BenchRecord(name, t, a_in, a_out, np.full(t.shape, d * T),
                                   (f"virtual bench seed {seed}", f"encoder_zero: pair{frac:g}")))
    return out


def write_records(records, folder) -> list[Path]:
    paths = []
    for r in records:
        p = Path(folder) / r.name
        write_record(p, r.time_s, r.input_angle_deg, r.output_angle_deg, r.output_torque_Nm,
                     comments=list(r.comments))
        paths.append(p)
    return paths
