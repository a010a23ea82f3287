"""Paper 001's TE definition on our runs (dynamics.matrix.paper001_te, aliasing): a closed-form record.

Paper 001: dphi(t_k) = (omega_out - omega_in / i) dt at 700 steps over 7 s (dt = 0.01 s). A TE line
A sin(2 pi f t) has speed error 2 pi f A cos(2 pi f t), so its per-step figure has amplitude
2 pi f dt A and population sigma 2 pi f dt A / sqrt 2 whatever the sampling phase, as long as the
100 Hz samples do not lock onto the line (f_apparent not 0 or 50 Hz)."""
import math

import numpy as np
import pytest

from dynamics import matrix as mx
from geometry.params import load_case
from support import case_path


def _record(f_Hz, A_arcsec, ratio=81.0, h=1e-5, T=7.0):
    t = np.arange(0.0, T + h / 2, h)
    th_in = 7200.0 * t
    th_out = th_in / ratio + A_arcsec / 3600.0 * np.sin(2 * np.pi * f_Hz * t)
    return t, th_in, th_out


@pytest.mark.parametrize("f_Hz", [0.2469, 9.877, 385.2])     # 1x, zp x and zp zc x of paper 001's run
def test_the_per_step_te_of_a_line_is_its_speed_times_dt(f_Hz):
    t, th_in, th_out = _record(f_Hz, 2.0)
    tk, step, summed = mx.paper001_te(t, th_in, th_out, 81.0)
    assert len(tk) == 700 and tk[0] == pytest.approx(0.01) and tk[-1] == pytest.approx(7.0)
    expect = 2 * np.pi * f_Hz * 0.01 * 2.0 / math.sqrt(2)
    assert np.std(step) == pytest.approx(expect, rel=0.03)
    # below 50 Hz the running sum is the angle TE sampled at 100 Hz (sigma A / sqrt 2) to O((pi f dt)^2)
    if f_Hz < 1:
        assert np.std(summed) == pytest.approx(2.0 / math.sqrt(2), rel=0.05)


def test_the_mesh_orders_fold_where_the_sampling_theorem_puts_them():
    case = load_case(case_path("rv40e-81"))
    rev = 7200.0 / 360.0 / case.ratio                   # output rev/s at paper 001's drive
    rows = {r["mechanism"]: r for r in mx.aliasing(case, rev)}
    mesh = rows["cycloid-pin mesh zp*zc"]
    assert mesh["frequency_Hz"] == pytest.approx(1560 * rev)
    assert mesh["apparent_Hz"] == pytest.approx(abs(1560 * rev - 400.0))    # 385.2 Hz -> 14.8 Hz
    assert rows["carrier 1x"]["apparent_Hz"] == pytest.approx(rev)          # below Nyquist: unchanged
    assert mesh["step_gain"] > 20 > 1 > 50 * rows["carrier 1x"]["step_gain"]
