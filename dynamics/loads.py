"""Paper 001's drive and load forms (DESIGN.md "What the dynamics stage must deliver").

STEP is the multibody-code cubic step h0 + (h1 - h0) D^2 (3 - 2 D), D = (x - x0)/(x1 - x0)
clipped to [0, 1]; where x0 == x1 it is a jump (h0 below x0, h1 at and above).
    input speed      speed * STEP(t, 0, 0, 1, 1)               (7200 deg/s = 1200 rpm in paper 001)
    constant         STEP(t, 1, 0, 2, T)
    square           STEP(sin 2 pi t, 0.01, 0.95 T, 0.01, 1.05 T)   (1 Hz between 0.95 T and 1.05 T)
    sine             0.05 T sin(8 t) + T
Torques are output torques in N m, positive when the load resists forward rotation.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from geometry.artifacts import InputError

FORMS = ("constant", "square", "sine")
RAMP_S = 1.0   # paper 001: input speed ramps over 0..1 s


class LoadSpecError(InputError):
    """A load specification that is not FORM:TORQUE_NM."""


def step(x, x0: float, h0: float, x1: float, h1: float):
    """Cubic STEP (MSC Adams); arrays broadcast; a jump at x0 when x0 == x1."""
    x = np.asarray(x, dtype=float)
    if x1 == x0:
        return np.where(x < x0, h0, h1) + 0.0 * x
    d = np.clip((x - x0) / (x1 - x0), 0.0, 1.0)
    return h0 + (h1 - h0) * d * d * (3.0 - 2.0 * d)


def input_speed_deg_s(t, speed_rpm: float, ramp: bool = True):
    """Input speed [deg/s]: speed * STEP(t, 0, 0, 1, 1) (constant speed when ramp is False)."""
    w = 6.0 * speed_rpm
    return w * step(t, 0.0, 0.0, RAMP_S, 1.0) if ramp else w + 0.0 * np.asarray(t, dtype=float)


def input_angle_deg(t, speed_rpm: float, ramp: bool = True):
    """Integral of `input_speed_deg_s` from 0 (closed form of the cubic step: t^3 - t^4 / 2)."""
    t = np.asarray(t, dtype=float)
    w = 6.0 * speed_rpm
    if not ramp:
        return w * t
    tc = np.clip(t / RAMP_S, 0.0, 1.0)
    return w * RAMP_S * (tc ** 3 - 0.5 * tc ** 4) + w * np.maximum(t - RAMP_S, 0.0)


@dataclass(frozen=True)
class LoadSpec:
    form: str         # constant | square | sine
    torque_Nm: float  # T, the load gradient of paper 001

    def __post_init__(self):
        if self.form not in FORMS:
            raise LoadSpecError(f"load form {self.form!r}: allowed forms are {', '.join(FORMS)}")
        if not np.isfinite(self.torque_Nm):
            raise LoadSpecError(f"load torque {self.torque_Nm!r}: must be a finite number in N m")

    @classmethod
    def parse(cls, text: str) -> "LoadSpec":
        """'sine:300' -> LoadSpec('sine', 300.0)."""
        form, sep, torque = str(text).partition(":")
        if not sep:
            raise LoadSpecError(f"--load {text!r}: expected FORM:TORQUE_NM with FORM in "
                                f"{', '.join(FORMS)}, e.g. sine:300")
        try:
            value = float(torque)
        except ValueError:
            raise LoadSpecError(f"--load {text!r}: torque {torque!r} is not a number (N m)") from None
        return cls(form.strip().lower(), value)

    def __str__(self) -> str:
        return f"{self.form}:{self.torque_Nm:g}"

    @property
    def peak_torque_Nm(self) -> float:
        """Largest |torque| of the form: T for constant, 1.05 T for square and sine (+-5 % of T)."""
        return abs(self.torque_Nm) * (1.0 if self.form == "constant" else 1.05)


def load_torque_Nm(spec: LoadSpec, t):
    """Output load torque [N m] of paper 001 at time t [s] (resisting forward rotation)."""
    t = np.asarray(t, dtype=float)
    T = spec.torque_Nm
    if spec.form == "constant":
        return step(t, 1.0, 0.0, 2.0, T)
    if spec.form == "square":
        return step(np.sin(2.0 * np.pi * t), 0.01, 0.95 * T, 0.01, 1.05 * T)
    return 0.05 * T * np.sin(8.0 * t) + T
