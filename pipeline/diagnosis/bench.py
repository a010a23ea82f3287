"""Virtual bench: records from the model plus a hidden effect, for blind tests of the diagnosis.

A seeded generator draws the cause, its size and phase (`draw_effect`); `bench_records` runs the
model with the effect (quasi-static, the same path the diagnosis uses) under forward/backward
pairs at a few torques (at the records' condition: the carrier's drag rides on the load as in the
diagnosis), adds a random encoder zero per pair, Gaussian angle noise and encoder
quantisation (both encoders, `encoder_bits` counts per turn), and returns BenchRecords exactly as
the loader would (write them with `write_records` to test the CLI). Truth is kept beside the
records in `HiddenEffect.truth`, in the units diagnosis.json reports.
Causes and sizes drawn: every registered cause with a `draw` (causes/, `drawable_causes()`); each
cause module states its tolerance-class range, well above the noise.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from dynamics.records import BenchRecord, write_record
from dynamics.results import ARCSEC_PER_DEG
from pipeline.diagnosis import causes
from pipeline.diagnosis.simulate import Condition, call_te_model


def drawable_causes() -> tuple[str, ...]:
    """Ids of the registered causes the virtual bench can hide, in registry order."""
    return tuple(c.id for c in causes.CAUSES if c.drawable)


@dataclass(frozen=True)
class HiddenEffect:
    cause: str
    p: tuple[float, ...]          # model parameters of the cause (its params(case))
    truth: dict = field(default_factory=dict)


def draw_effect(rng: np.random.Generator, case, cause: str) -> HiddenEffect:
    """A seeded tolerance-class instance of `cause` (its module's `draw`)."""
    found = [c for c in causes.CAUSES if c.id == cause and c.drawable]
    if not found:
        raise ValueError(f"cause {cause!r}: allowed {', '.join(drawable_causes())}")
    p, truth = found[0].draw(rng, case)
    return HiddenEffect(cause, tuple(p), truth)


def apply_effects(case, stiffness, effects):
    for e in effects:
        case, stiffness = causes.get(e.cause).apply(case, stiffness, np.asarray(e.p, float))
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
            # at the condition the diagnosis will read off the record (its speed; no oil temperature
            # comment: the lubricant's stated run temperature), so the carrier's drag is the same
            te = call_te_model(te_model, hidden_case, hidden_stiff, th_in, d * T, d, Condition(round(float(speed), 1)))
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
