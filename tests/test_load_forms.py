"""Load forms are one table (dynamics.loads.LOAD_FORMS): each entry's peak factor and load frequency
hold for its own torque, an unknown form is an error, and the fourth form (a trapezoidal pick-and-place
torque) runs through simulate, the matrix and the report by its table entry alone
(tests/test_dynamics_cli.py)."""
import numpy as np
import pytest

from dynamics.loads import (FORMS, LOAD_FORMS, PAPER_001_FORMS, TRAPEZOID_DWELL_S, TRAPEZOID_HOLD, TRAPEZOID_PERIOD_S,
                            TRAPEZOID_RAMP_S, TRAPEZOID_START_S, LoadSpec, LoadSpecError, load_form, load_torque_Nm)

T = 300.0


@pytest.mark.parametrize("form", FORMS)
def test_each_entry_s_peak_factor_is_the_largest_torque_its_form_reaches(form):
    t = np.linspace(0.0, 12.0, 600_001)          # a whole sine period (8 rad/s) and many square/trapezoid cycles
    peak = np.abs(load_torque_Nm(LoadSpec(form, -T), t)).max()
    assert LoadSpec(form, -T).peak_torque_Nm == pytest.approx(peak, rel=1e-8)


@pytest.mark.parametrize("form", [f for f in FORMS if LOAD_FORMS[f].frequency_Hz])
def test_each_entry_s_load_frequency_is_the_period_its_torque_repeats_with(form):
    # after the ramps (t >= 2 s) the torque at t and at t + 1/f agree to round-off
    t = np.linspace(2.0, 5.0, 3001)
    period = 1.0 / LOAD_FORMS[form].frequency_Hz
    a, b = load_torque_Nm(LoadSpec(form, T), t), load_torque_Nm(LoadSpec(form, T), t + period)
    jumps = np.abs(np.sin(2 * np.pi * t)) < 0.02 if form == "square" else np.zeros_like(t, bool)   # its edges
    assert np.allclose(a[~jumps], b[~jumps], rtol=0, atol=1e-9 * T)


def test_an_unknown_form_is_an_error_never_a_silent_sine():
    with pytest.raises(LoadSpecError, match="'ramp'"):
        load_form("ramp")
    with pytest.raises(LoadSpecError, match="allowed forms are constant, square, sine, trapezoid"):
        LoadSpec("ramp", 100.0)


def test_paper_001_s_three_forms_are_the_default_and_the_trapezoid_has_no_paper_figure():
    assert PAPER_001_FORMS == ("constant", "square", "sine")
    assert LOAD_FORMS["trapezoid"].paper001_sigma_arcsec is None
    assert LOAD_FORMS["sine"].paper001_sigma_arcsec[400.0] == 19.485     # paper 001's table, by name


def test_the_trapezoid_ramps_dwells_and_repeats_as_stated():
    r, d, t0 = TRAPEZOID_RAMP_S, TRAPEZOID_DWELL_S, TRAPEZOID_START_S
    assert 2 * r + 2 * d == pytest.approx(TRAPEZOID_PERIOD_S)
    for k in (0, 3):                             # first and fourth cycle
        s = t0 + k * TRAPEZOID_PERIOD_S
        at = [s - 0.5 * d, s, s + r / 2, s + r, s + r + d / 2, s + r + d + r / 2, s + 2 * r + d, s + 2 * r + 1.5 * d]
        h, mid = TRAPEZOID_HOLD * T, (1 + TRAPEZOID_HOLD) * T / 2     # holding level, half-way up a ramp
        expect = [h, h, mid, T, T, mid, h, h]
        assert load_torque_Nm(LoadSpec("trapezoid", T), np.array(at)) == pytest.approx(expect, abs=1e-9 * T)
    assert np.all(load_torque_Nm(LoadSpec("trapezoid", T), np.linspace(0, t0 - 1e-9, 50)) == TRAPEZOID_HOLD * T)
    assert 0.0 < TRAPEZOID_HOLD < 1.0                 # loaded throughout, never beyond T
