"""Paper 001's drive and loads (DESIGN.md formulas, exact to round-off)."""
import numpy as np
import pytest
from scipy.integrate import quad

from dynamics.loads import LoadSpec, LoadSpecError, input_angle_deg, input_speed_deg_s, load_torque_Nm, step
from geometry.artifacts import InputError


def test_step_is_the_cubic_multibody_step_and_a_jump_when_x0_equals_x1():
    # h0 + (h1 - h0) D^2 (3 - 2 D): D = 0.5 gives the midpoint exactly
    assert step(1.5, 1, 0, 2, 100) == pytest.approx(50.0, abs=1e-12)
    assert step([0.0, 3.0], 1, 0, 2, 100).tolist() == [0.0, 100.0]
    assert step(0.25, 0, 0, 1, 1) == pytest.approx(0.25 ** 2 * 2.5, abs=1e-15)
    assert step([0.0099, 0.01, 0.5], 0.01, -1.0, 0.01, 1.0).tolist() == [-1.0, 1.0, 1.0]


def test_input_speed_ramps_to_7200_deg_s_in_one_second_and_the_angle_is_its_integral():
    assert input_speed_deg_s(1.0, 1200) == pytest.approx(7200.0, rel=1e-15)
    assert input_speed_deg_s(0.0, 1200) == 0.0
    for t in (0.3, 1.0, 2.7):
        exact, _ = quad(lambda s: float(input_speed_deg_s(s, 1200)), 0, t, epsabs=1e-10)
        assert input_angle_deg(t, 1200) == pytest.approx(exact, rel=1e-10)


def test_load_forms_follow_paper_001():
    T = 300.0
    assert load_torque_Nm(LoadSpec("constant", T), 0.5) == 0.0
    assert load_torque_Nm(LoadSpec("constant", T), 2.5) == T
    sq = load_torque_Nm(LoadSpec("square", T), np.linspace(2, 3, 1001))
    assert set(np.round(sq, 9)) == {0.95 * T, 1.05 * T}            # 1 Hz square between 0.95T and 1.05T
    assert abs((sq > T).mean() - 0.5) < 0.01
    t = np.linspace(0, 7, 50)
    assert np.allclose(load_torque_Nm(LoadSpec("sine", T), t), 0.05 * T * np.sin(8 * t) + T, rtol=0, atol=1e-12)


@pytest.mark.parametrize("text", ["sine", "wave:300", "sine:abc", "sine:nan"])
def test_bad_load_specs_are_input_errors_naming_the_allowed_forms(text):
    with pytest.raises(InputError) as exc:
        LoadSpec.parse(text)
    assert isinstance(exc.value, LoadSpecError)
    assert text.split(":")[0] in str(exc.value) or "torque" in str(exc.value)


def test_parse_round_trip():
    assert LoadSpec.parse("Sine:300") == LoadSpec("sine", 300.0)
    assert str(LoadSpec("square", 100)) == "square:100"


@pytest.mark.parametrize("form", ["constant", "square", "sine"])
def test_peak_torque_is_the_largest_torque_the_form_reaches(form):
    # what simulate checks against the momentary rating: max |T(t)| over a whole sine period (8 rad/s)
    spec = LoadSpec(form, -300.0)
    t = np.linspace(0.0, 12.0, 600_001)
    assert spec.peak_torque_Nm == pytest.approx(np.abs(load_torque_Nm(spec, t)).max(), rel=1e-8)
