"""The as-built error set ([errors], geometry.params.Errors): validation with one-line errors, and
each error acting where DESIGN.md puts it, through the contact geometry of the pin and needle
couplings (checked at fixed poses against the ideal model moved by hand: no solve, exact)."""
import math
import tomllib

import numpy as np
import pytest

from dynamics.model import evaluate
from dynamics.statics import nominal_q, solve_static
from geometry.params import CaseError, Errors, case_from_dict, load_case
from support import case_path, model_for_tests

ZP = 40


@pytest.fixture(scope="module")
def case():
    return load_case(case_path("rv40e-81"))


@pytest.fixture(scope="module")
def ideal():
    return model_for_tests("rv40e-81")


def test_every_error_defaults_to_the_ideal_build(case):
    er = Errors()
    for name in er.__dataclass_fields__:
        v = getattr(er, name)
        flat = [x for row in v for x in (row if isinstance(row, tuple) else (row,))] if isinstance(v, tuple) else [v]
        assert all(x == 0 for x in flat) or name.endswith("_lobes") and v == (), name
    assert case.errors == er


@pytest.mark.parametrize("changes, key, allowed", [
    ({"per_pin_radial_um": [1.0, 2.0]}, "per_pin_radial_um", "zp = 40"),
    ({"per_pin_tangential_um": [200.0] * ZP}, "per_pin_tangential_um", "allowed range"),
    ({"pin_radial_lobes": [[0, 1.0, 0.0]]}, "pin_radial_lobes row 1 m", "allowed range"),
    ({"pin_radial_lobes": [[21, 1.0, 0.0]]}, "pin_radial_lobes row 1 m", "zp / 2 = 20"),
    ({"pin_radial_lobes": [[2.5, 1.0, 0.0]]}, "pin_radial_lobes row 1 m", "whole number"),
    ({"pin_radial_lobes": [2, 1.0, 0.0]}, "pin_radial_lobes", "list of rows [m, amplitude_um, phase_deg]"),
    ({"pin_radial_lobes": [[2, 1.0]]}, "pin_radial_lobes row 1", "needs 3 numbers"),
    ({"pin_radial_lobes": [[2, -1.0, 0.0]]}, "pin_radial_lobes row 1 amplitude_um", "allowed range"),
    ({"pin_radial_lobes": [[1, 1.0, 0.0]] * 17}, "pin_radial_lobes", "at most 16"),
    ({"pin_stiffness_lobes": [[1, 0.5, 0.0], [2, 0.5, 180.0]]}, "pin_stiffness_lobes", ">= 0.1 at every pin"),
    ({"pin_stiffness_lobes": [[1, 0.95, 0.0]]}, "pin_stiffness_lobes row 1 amplitude", "allowed range"),
    ({"disc_pitch_lobes": [[3, 1, 1.0, 0.0]]}, "disc_pitch_lobes row 1 disc", "allowed 1 to 2"),
    ({"disc_profile_lobes": [[1, 20, 1.0, 0.0]]}, "disc_profile_lobes row 1 m", "zc / 2 = 19"),
    ({"disc_profile_um": [1.0, 2.0, 3.0]}, "disc_profile_um", "one per disc"),
    ({"crank_timing_arcmin": [1.0, 2.0]}, "crank_timing_arcmin", "one per crank"),
    ({"eccentric_phase_arcmin": [90.0]}, "eccentric_phase_arcmin", "allowed range"),
    ({"crank_hole_tangential_um": [float("nan")]}, "crank_hole_tangential_um", "finite"),
    ({"main_bearing_runout_um": -1.0}, "main_bearing_runout_um", "allowed range"),
    ({"disc_phase_um": "1"}, "disc_phase_um", "number"),
])
def test_a_bad_error_value_is_one_line_naming_the_key_and_what_is_allowed(case, changes, key, allowed):
    with pytest.raises(CaseError) as exc:
        case.with_errors(**changes)
    msg = str(exc.value)
    assert "\n" not in msg and f"[errors] {key}" in msg and allowed in msg, msg


def test_errors_between_two_discs_are_refused_on_a_one_disc_reducer(case):
    one = case.replace("cycloid", disc_count=1)
    for key, v in (("disc_phase_um", 2.0), ("eccentric_phase_arcmin", [3.0])):
        with pytest.raises(CaseError, match=f"{key}.*disc_count = 1"):
            one.with_errors(**{key: v})


def test_lobes_and_per_pin_arrays_read_from_toml(case):
    text = case_path("rv40e-81").read_text().split("[errors]")[0] + (
        "[errors]\npin_radial_lobes = [[2, 3.0, 45.0], [4, 1, 0]]\n"
        "disc_pitch_lobes = [[1, 1, 5.0, 0.0]]\n"
        f"per_pin_radius_um = [{', '.join(['0.5'] * ZP)}]\n")
    c = case_from_dict(tomllib.loads(text))
    assert c.errors.pin_radial_lobes == ((2, 3.0, 45.0), (4, 1.0, 0.0))
    assert c.errors.disc_pitch_lobes == ((1, 1, 5.0, 0.0),)
    assert c.errors.per_pin_radius_um == (0.5,) * ZP
    assert hash(c)          # cases key the model caches (tuples of tuples stay hashable)


# ------------------------------------------------------------------ pins: where each error acts

def _pose(model, input_deg=7.0):
    return nominal_q(model, math.radians(input_deg))


def _gaps(model, q, input_deg=7.0):
    w, _ = evaluate(model, q, math.radians(input_deg))
    return model.contacts(w.gap).copy()


def test_pin_errors_move_the_pin_centres_and_radii_they_name():
    th = 2 * np.pi * np.arange(ZP) / ZP
    radial, tang, radius = np.linspace(-3, 3, ZP), np.cos(3 * th), np.sin(th)
    m = model_for_tests("rv40e-81", per_pin_radial_um=list(radial), per_pin_tangential_um=list(tang),
                        per_pin_radius_um=list(radius), pin_radial_lobes=[[2, 4.0, 30.0]],
                        pin_circle_radius_um=1.5)
    p = m.params("pin")
    R = 64e-3 + 1.5e-6 + radial * 1e-6 + 4e-6 * np.cos(2 * th - math.radians(30.0))
    P = p.pins[:, :2]
    er, et = np.column_stack([np.cos(th), np.sin(th)]), np.column_stack([-np.sin(th), np.cos(th)])
    assert np.allclose((P * er).sum(1), R, rtol=0, atol=1e-15)
    assert np.allclose((P * et).sum(1), tang * 1e-6, rtol=0, atol=1e-15)
    assert np.allclose(p.pins[:, 2], 3e-3 + radius * 1e-6, rtol=0, atol=1e-15)


def test_a_pin_radius_error_changes_that_pins_gap_by_exactly_its_size(ideal):
    m = model_for_tests("rv40e-81", per_pin_radius_um=[0.0] * 5 + [2.0] + [0.0] * (ZP - 6))
    q = _pose(ideal)
    d = _gaps(m, q) - _gaps(ideal, q)
    assert d[:, 5] == pytest.approx([-2e-6, -2e-6], abs=1e-15)
    assert np.abs(np.delete(d, 5, axis=1)).max() < 1e-15


def test_a_disc_profile_error_closes_every_gap_of_that_disc_only(ideal):
    m = model_for_tests("rv40e-81", disc_profile_um=[0.0, 1.5])
    q = _pose(ideal)
    d = _gaps(m, q) - _gaps(ideal, q)
    assert np.abs(d[0]).max() < 1e-15 and np.allclose(d[1], -1.5e-6, rtol=0, atol=1e-15)


def test_disc_phase_is_disc_2_turned_by_its_size_over_the_pin_circle_radius(ideal):
    m = model_for_tests("rv40e-81", disc_phase_um=3.0)
    q = _pose(ideal)
    q2 = q.copy()
    q2[ideal.disc_index(1) + 2] += 3e-6 / 64e-3
    assert np.allclose(_gaps(m, q), _gaps(ideal, q2), rtol=0, atol=1e-15)


def test_a_cumulative_pitch_lobe_turns_the_profile_under_each_pin_by_its_local_value(ideal):
    A, ph = 5.0, math.radians(20.0)
    m = model_for_tests("rv40e-81", disc_pitch_lobes=[[1, 1, A, 20.0]])
    q = _pose(ideal)
    g = _gaps(m, q)
    i = ideal.disc_index(0)
    c, al = q[i:i + 2], q[i + 2] + ideal.params("pin").disc_rotation_rad[0]
    for k in (0, 9, 23, 31):
        P = ideal.params("pin").pins[k, :2] - c
        phi = math.atan2(-math.sin(al) * P[0] + math.cos(al) * P[1], math.cos(al) * P[0] + math.sin(al) * P[1])
        q2 = q.copy()
        q2[i + 2] += A * 1e-6 / 64e-3 * math.cos(phi - ph)
        assert g[0, k] == pytest.approx(_gaps(ideal, q2)[0, k], abs=1e-15)
    assert np.allclose(g[1], _gaps(ideal, q)[1], rtol=0, atol=1e-15)     # disc 2 untouched


def test_stiffness_lobes_multiply_each_pins_law(ideal):
    s = solve_static(ideal, 7.0, 412.0)
    m = model_for_tests("rv40e-81", pin_stiffness_lobes=[[2, 0.3, 10.0]])
    w0, _ = evaluate(ideal, s.q, math.radians(7.0))
    w1, _ = evaluate(m, s.q, math.radians(7.0))
    f0, f1 = ideal.contacts(w0.force), m.contacts(w1.force)
    th = 2 * np.pi * np.arange(ZP) / ZP
    factor = 1 + 0.3 * np.cos(2 * th - math.radians(10.0))
    loaded = f0 > 1.0
    assert loaded.sum() >= 10
    assert np.allclose((f1 / np.where(loaded, f0, 1))[loaded], np.broadcast_to(factor, f0.shape)[loaded], rtol=1e-12)


# ------------------------------------------------------------------ cranks, holes, main bearing

def test_crank_errors_set_the_needle_geometry_they_name():
    m = model_for_tests("rv40e-81", crank_timing_arcmin=[2.0, 0.0, 0.0], eccentric_phase_arcmin=[0.0, 3.0, 0.0],
                        crank_hole_tangential_um=[0.0, 0.0, 4.0], output_bearing_hole_tangential_um=[5.0, 0, 0],
                        output_bearing_hole_um=[0.0, 1.0, 0.0], main_bearing_runout_um=2.0,
                        main_bearing_runout_phase_deg=90.0)
    p = m.params("needle")
    am = math.radians(1 / 60)
    assert np.allclose(p.ecc_phase_rad[0], [2 * am, 0, 0], rtol=0, atol=1e-15)
    assert np.allclose(p.ecc_phase_rad[1], [math.pi + 2 * am, math.pi + 3 * am, math.pi], rtol=0, atol=1e-15)
    b = 2 * np.pi * np.arange(3) / 3
    hole = p.hole_radius_m[:, None] * np.column_stack([np.cos(p.hole_angle_rad), np.sin(p.hole_angle_rad)])
    want = 36e-3 * np.column_stack([np.cos(b), np.sin(b)]) + np.array([0, 0, 4e-6])[:, None] * np.column_stack(
        [-np.sin(b), np.cos(b)])
    assert np.allclose(hole, want, rtol=0, atol=1e-15)
    seat = p.seat_radius_m[:, None] * np.column_stack([np.cos(p.seat_angle_rad), np.sin(p.seat_angle_rad)])
    want = (36e-3 + np.array([0, 1e-6, 0]))[:, None] * np.column_stack([np.cos(b), np.sin(b)]) \
        + np.array([5e-6, 0, 0])[:, None] * np.column_stack([-np.sin(b), np.cos(b)]) + np.array([0.0, 2e-6])
    assert np.allclose(seat, want, rtol=0, atol=1e-15)


def test_without_errors_the_needle_geometry_is_exactly_the_nominal_one(ideal):
    p = ideal.params("needle")
    a, b = np.full(3, 36.0 * 1e-3), 2 * np.pi * np.arange(3) / 3     # as the crank circle is read: mm * 1e-3
    assert np.array_equal(p.seat_radius_m, a) and np.array_equal(p.seat_angle_rad, b)
    assert np.array_equal(p.hole_radius_m, a) and np.array_equal(p.hole_angle_rad, b)
    pin = ideal.params("pin")
    assert np.array_equal(pin.pins[:, 4], np.ones(ZP)) and pin.disc_pitch.shape == (2, 0, 3)
