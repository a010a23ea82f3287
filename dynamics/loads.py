"""Load forms and paper 001's drive (DESIGN.md "What the dynamics stage must deliver").

STEP is the multibody-code cubic step h0 + (h1 - h0) D^2 (3 - 2 D), D = (x - x0)/(x1 - x0)
clipped to [0, 1]; where x0 == x1 it is a jump (h0 below x0, h1 at and above).
    input speed      speed * STEP(t, 0, 0, 1, 1)               (7200 deg/s = 1200 rpm in paper 001)
Every load form is one entry of `LOAD_FORMS` (its torque, peak factor, load frequency and its
column of paper 001's sigma table by torque, or none); nothing elsewhere branches on a form's name.
Torques are output torques in N m, positive when the load resists forward rotation.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from geometry.artifacts import InputError

RAMP_S = 1.0   # paper 001: input speed ramps over 0..1 s

# A robot joint's pick-and-place cycle as a trapezoidal torque profile (ASSUMED; no bench or paper
# here gives one): one 1 s cycle (a 6-axis robot of the RV-40E's payload class moves a part in
# ~0.5-1 s) after the 1 s speed ramp: the torque rises linearly from the holding level to T in
# TRAPEZOID_RAMP_S (the jerk-limited acceleration ramp of the motion planner), dwells at T while the
# joint carries and accelerates the payload, falls back in TRAPEZOID_RAMP_S and dwells at the
# holding level while the gripper picks or places. The holding level is the arm's own gravity
# moment, which a vertical joint always carries: ASSUMED half of T. (A cycle down to zero torque
# crosses the backlash at every cycle; at the default step the model then reports contacts that
# closed between candidate refreshes: rv40e-81, 300 N m, dt 1e-4 s.) The load gradient T is the user's.
TRAPEZOID_START_S = 1.0      # first rise when the input has reached its speed (like paper 001's loads)
TRAPEZOID_PERIOD_S = 1.0     # one pick-and-place cycle
TRAPEZOID_RAMP_S = 0.1       # rise and fall, each
TRAPEZOID_DWELL_S = 0.4      # at T, and again at the holding level (2 ramps + 2 dwells = the period)
TRAPEZOID_HOLD = 0.5         # holding level / T


class LoadSpecError(InputError):
    """A load specification that is not FORM:TORQUE_NM."""


def step(x, x0: float, h0: float, x1: float, h1: float):
    """Cubic STEP (MSC Adams); arrays broadcast; a jump at x0 when x0 == x1."""
    x = np.asarray(x, dtype=float)
    if x1 == x0:
        return np.where(x < x0, h0, h1) + 0.0 * x
    d = np.clip((x - x0) / (x1 - x0), 0.0, 1.0)
    return h0 + (h1 - h0) * d * d * (3.0 - 2.0 * d)


def _constant(t, T):
    return step(t, 1.0, 0.0, 2.0, T)                                 # paper 001: STEP(t, 1, 0, 2, T)


def _square(t, T):
    return step(np.sin(2.0 * np.pi * t), 0.01, 0.95 * T, 0.01, 1.05 * T)   # 1 Hz between 0.95 T and 1.05 T


def _sine(t, T):
    return 0.05 * T * np.sin(8.0 * t) + T                            # paper 001: 0.05 T sin(8 t) + T


def _trapezoid(t, T):
    """Holding level TRAPEZOID_HOLD T until TRAPEZOID_START_S, then per cycle: ramp to T, dwell at T,
    ramp back, dwell at the holding level."""
    tau = np.mod(t - TRAPEZOID_START_S, TRAPEZOID_PERIOD_S)
    r, d = TRAPEZOID_RAMP_S, TRAPEZOID_DWELL_S
    level = np.clip(np.minimum(tau / r, (2 * r + d - tau) / r), 0.0, 1.0)
    level = np.where(t < TRAPEZOID_START_S, 0.0, level)
    return T * (TRAPEZOID_HOLD + (1.0 - TRAPEZOID_HOLD) * level)


@dataclass(frozen=True)
class LoadForm:
    """One load form: what it is, where it comes from, and what the matrix and reports read of it."""
    torque: Callable                  # (t [s] array, T [N m]) -> output load torque [N m]
    peak_factor: float                # max |torque(t, T)| / |T| over the run
    frequency_Hz: float | None        # the load's own repetition rate (its line in the spectra); None: none
    source: str
    # paper 001's sigma table [arcsec] for this form by load gradient T [N m]; None: no paper figure
    paper001_sigma_arcsec: dict[float, float] | None = None


LOAD_FORMS: dict[str, LoadForm] = {
    "constant": LoadForm(_constant, 1.0, None, "paper 001",
                         {100.0: 14.154, 200.0: 14.695, 300.0: 16.817, 400.0: 19.196}),
    "square": LoadForm(_square, 1.05, 1.0, "paper 001",
                       {100.0: 14.056, 200.0: 14.898, 300.0: 17.312, 400.0: 19.032}),
    "sine": LoadForm(_sine, 1.05, 8.0 / (2 * np.pi), "paper 001",
                     {100.0: 14.172, 200.0: 15.416, 300.0: 17.930, 400.0: 19.485}),
    "trapezoid": LoadForm(_trapezoid, 1.0, 1.0 / TRAPEZOID_PERIOD_S,
                          "ASSUMED robot pick-and-place cycle (dynamics.loads, TRAPEZOID_*)"),
}
FORMS = tuple(LOAD_FORMS)
PAPER_001_FORMS = tuple(k for k, f in LOAD_FORMS.items() if f.paper001_sigma_arcsec)   # the default matrix


def load_form(name: str) -> LoadForm:
    """The table entry of a form; an unknown name is an error, never a silent default."""
    try:
        return LOAD_FORMS[name]
    except KeyError:
        raise LoadSpecError(f"load form {name!r}: allowed forms are {', '.join(FORMS)}") from None


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
    form: str         # a key of LOAD_FORMS
    torque_Nm: float  # T, the load gradient of paper 001

    def __post_init__(self):
        load_form(self.form)
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
        """Largest |torque| of the form: |T| times the form's peak factor."""
        return abs(self.torque_Nm) * load_form(self.form).peak_factor


def load_torque_Nm(spec: LoadSpec, t):
    """Output load torque [N m] of the spec's form at time t [s] (resisting forward rotation)."""
    return load_form(spec.form).torque(np.asarray(t, dtype=float), spec.torque_Nm)
