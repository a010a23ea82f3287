"""The diagnosis never breaks on user input (issue 13, "tried as a user would"): each failure found
there is a seeded case here, ending in a one-line reason or a correct result, never a traceback.

Fast cases run on test_diagnose_machinery's closed-form stand-in model (toy_te); the cases whose
failure lived in the real model's response (zero torque, a perfect record, wind-up 3x the model's)
run through dynamics.model on tests/support.py's stiffness at 128 points per revolution.
"""
import dataclasses
import re
from pathlib import Path

import numpy as np
import pytest

from dynamics.records import BenchRecord, RecordError, read_record, read_records, write_record
from fem.stiffness import save
from geometry.params import load_case
from pipeline.cli import main
from pipeline.diagnosis import causes
from pipeline.diagnosis.bench import bench_records, draw_effect, write_records
from pipeline.diagnosis.causes.base import trend
from pipeline.diagnosis.diagnose import diagnose
from pipeline.diagnosis.inputs import check_records
from pipeline.diagnosis.simulate import quasi_static_te

import test_diagnose_machinery as machinery

support = pytest.importorskip("support", reason="tests/support.py (stiffness stand-in) not present")
ROOT = Path(__file__).parents[1]
CASE, STIFF = machinery.CASE, machinery.STIFF
toy_te = machinery.toy_te
REAL = support.stiffness_for_tests(CASE)
PPR = 128


def _toy(effects, seed, **kw):
    return bench_records(toy_te, CASE, STIFF, effects, seed=seed, **kw)


def _replace(r, **kw):
    return dataclasses.replace(r, **kw)


def _reported_within_bounds(d, case):
    """No finding or extension parameter outside (or on) its cause's physical range."""
    if d.extension is None:
        return
    # the extension's model parameters are not exposed; the reported ones that carry the bounds:
    p = d.extension.parameters
    if "pin_clearance_um" in p:
        lo, hi = causes.get("backlash").params(case)[0].bounds
        assert lo < p["pin_clearance_um"] < hi
    if "compliance_factor" in p:
        assert 0.1 <= p["compliance_factor"] <= 10.0 and p["compliance_factor_ci95"][0] > 0
        # the same wind-up as one series spring: the difference of the rated tangent compliances, its
        # sign that of the factor's log (more compliance where f > 1)
        rig = p["rigidity_at_rated_Nm_per_arcmin"]
        added = p["added_series_compliance_arcmin_per_kNm"]
        assert added == pytest.approx(1e3 * (1 / rig["extended"] - 1 / rig["model"]), rel=1e-12)
        assert (added > 0) == (p["compliance_factor"] > 1)


# ------------------------------------------------------------------ bounded fits (real model)
def test_a_zero_torque_pair_alone_gives_no_stiffness_and_no_traceback():
    # at 0 N.m the wind-up column is ~0: its linear coefficient crossed c = 0 (ValueError) before
    eff = draw_effect(np.random.default_rng(21), CASE, "output_coaxiality")
    recs = bench_records(quasi_static_te, CASE, REAL, [eff], seed=21, torque_fractions=(0.0,), samples_per_rev=PPR)
    d = diagnose(CASE, REAL, recs, points_per_rev=PPR)
    assert d.cause == "output_coaxiality"
    assert "torsional_stiffness" not in {f.cause for f in d.findings}
    assert d.extension.parameters["output_coaxiality_um"] == pytest.approx(eff.truth["output_coaxiality_um"], rel=0.05)
    _reported_within_bounds(d, CASE)


@pytest.mark.parametrize("softer", [3.0, 4.0])
def test_a_reducer_several_times_softer_than_the_model_is_fitted_positive(softer):
    # the located component 3x / 4x as compliant as the model's: a global factor's linear start once
    # crossed c = 0; 4x: a negative backlash with an all-negative interval came along
    rng = np.random.default_rng(22)
    effs = [draw_effect(rng, CASE, "output_coaxiality"),
            dataclasses.replace(draw_effect(rng, CASE, "torsional_stiffness"), p=(np.log(softer),))]
    recs = bench_records(quasi_static_te, CASE, REAL, effs, seed=22, samples_per_rev=PPR)
    d = diagnose(CASE, REAL, recs, points_per_rev=PPR)
    assert {"output_coaxiality", "torsional_stiffness"} <= set(d.extension.causes)
    # 5 %: the noise (0.3 arcsec) against a wind-up of tens of arcsec moves it < 1 %
    assert d.extension.parameters["compliance_factor"] == pytest.approx(softer, rel=0.05)
    _reported_within_bounds(d, CASE)


def test_a_kinematically_perfect_record_names_no_unphysical_cause():
    # TE = 0 exactly: less lost motion and wind-up than any physical reducer of this case; the
    # fit once answered a pin clearance below the closing one (a negative backlash)
    n = 4 * PPR + 1
    recs = []
    for d_, T in ((1, 120.0), (-1, -120.0)):
        th_in = (0.0 if d_ > 0 else 360.0 * CASE.ratio) + d_ * np.linspace(0.0, 360.0 * CASE.ratio, n)
        recs.append(BenchRecord(f"perfect_{d_}.csv", np.linspace(0, 10, n), th_in, th_in / CASE.ratio,
                                np.full(n, T), ("encoder_zero: p",)))
    d = diagnose(CASE, REAL, recs, points_per_rev=PPR)
    _reported_within_bounds(d, CASE)
    assert "backlash" not in {f.cause for f in d.findings}
    assert any("not reported" in n for n in d.notes) or d.cause is None


# ------------------------------------------------------------------ bounded fits (stand-in model)
def test_a_sign_flipped_torque_column_is_said_and_fits_stay_physical():
    eff = draw_effect(np.random.default_rng(23), CASE, "output_coaxiality")
    recs = [_replace(r, output_torque_Nm=-r.output_torque_Nm) for r in _toy([eff], 23)]
    d = diagnose(CASE, STIFF, recs, toy_te, points_per_rev=256)
    assert any("torque assists its motion" in n for n in d.notes)
    assert d.cause == "output_coaxiality"
    _reported_within_bounds(d, CASE)


def test_a_cause_below_the_noise_floor_is_not_reported():
    # a 0.2 um coaxiality: a 0.6 arcsec 1x line, highly significant on 3 x 2 x 257 samples, yet an
    # effect of 0.4 arcsec RMS under 1 arcsec of noise: an engineer cannot act on it
    eff = dataclasses.replace(draw_effect(np.random.default_rng(24), CASE, "output_coaxiality"), p=(0.2, 0.0))
    recs = _toy([eff], 24, noise_arcsec=1.0)
    d = diagnose(CASE, STIFF, recs, toy_te, points_per_rev=256)
    assert d.cause is None and d.extension is None
    assert any(re.search(r"output_coaxiality: its effect .* below their noise floor", n) for n in d.notes)


def test_direction_asymmetry_is_said_in_one_line():
    # backward runs 3x stiffer than forward, one encoder zero for the session: no cause models it
    stiff_bw = STIFF.stiffened("all", 3.0)
    fw = [r for r in _toy([], 25, torque_fractions=(0.1, 0.4, 0.7)) if r.direction > 0]
    bw = [r for r in bench_records(toy_te, CASE, stiff_bw, [], seed=26, torque_fractions=(0.1, 0.4, 0.7))
          if r.direction < 0]
    recs = [_replace(r, comments=("encoder_zero: session",)) for r in fw + bw]
    d = diagnose(CASE, STIFF, recs, toy_te, points_per_rev=256)
    asym = [n for n in d.notes if n.startswith("direction asymmetry")]
    assert len(asym) == 1 and "\n" not in asym[0]


# ------------------------------------------------------------------ evidence quotes the records
def test_evidence_quotes_only_the_torques_of_the_records(monkeypatch):
    # one encoder zero for all: the median torque of the group (a torque no record ran at) was quoted
    # (the stand-in's one compliance is crank torsion: torsional_stiffness must locate it there,
    # else no cause explains the gap and none is named)
    from pipeline.diagnosis.causes import torsional_stiffness
    monkeypatch.setattr(torsional_stiffness, "located_component", lambda case, stiffness: ("crank_torsion", 1.0))
    eff = dataclasses.replace(draw_effect(np.random.default_rng(27), CASE, "torsional_stiffness"), p=(np.log(2.0),))
    recs = [_replace(r, comments=("encoder_zero: session",)) for r in _toy([eff], 27, torque_fractions=(0.0, 0.5))]
    d = diagnose(CASE, STIFF, recs, toy_te, points_per_rev=256)
    quoted = {float(t) for f in d.findings for t in re.findall(r"at ([0-9.]+) N\.m", f.evidence)}
    assert quoted and quoted <= {abs(r.torque_Nm) for r in recs}


def test_a_trend_is_read_from_the_numbers():
    assert trend([(0.0, 1.1), (400.0, 128.8)]) == "growing with torque"
    assert trend([(0.0, 60.0), (300.0, 62.0), (800.0, 61.0)]) == "about the same at every torque"
    assert trend([(0.0, 9.0), (300.0, 4.0), (800.0, 1.0)]) == "falling with torque"
    assert trend([(300.0, 5.0)]).startswith("one torque level only")
    assert trend([(0.0, -14.1), (300.0, 22.3), (800.0, 89.6), (1800.0, 229.1)]) == "growing with torque"
    assert trend([(0.0, 2.8), (300.0, 2.9), (800.0, 4.6), (1800.0, 9.7)]) == "growing with torque"
    assert trend([(0.0, 5.0), (300.0, 1.0), (800.0, 6.0)]) == "varying with torque"


# ------------------------------------------------------------------ input checks
def test_a_record_of_another_ratio_is_refused_in_one_line():
    r = _toy([], 28, torque_fractions=(0.1,))[0]
    other = _replace(r, input_angle_deg=r.input_angle_deg * 105.0 / CASE.ratio)
    with pytest.raises(RecordError, match=r"input/output angle ratio 105, the case rv40e-81 has i = 81"):
        check_records(CASE, [other])


def test_time_in_milliseconds_is_converted_when_the_record_states_its_speed():
    r = _toy([], 29, torque_fractions=(0.1,), speed_rpm=CASE.operation.input_speed_rpm)[0]
    ms = _replace(r, time_s=r.time_s * 1000.0)
    # without a stated speed, 1/1000 of the case's speed is ambiguous (ms, or a slow run): refused
    with pytest.raises(RecordError, match=r"1/1000 of the case's 1200 rpm: time_s looks like milliseconds"):
        check_records(CASE, [ms])
    said_ms = _replace(ms, comments=("input_speed_rpm: 1200",))
    (back,), notes = check_records(CASE, [said_ms])
    assert back.input_speed_rpm == pytest.approx(CASE.operation.input_speed_rpm, rel=1e-6)
    assert len(notes) == 1 and "time_s read as milliseconds" in notes[0] and "converted to seconds" in notes[0]
    # a stated speed that disagrees otherwise is refused; one that says seconds keeps them
    said = _replace(ms, comments=("input_speed_rpm: 700",))
    with pytest.raises(RecordError, match="input_speed_rpm 700; they must agree"):
        check_records(CASE, [said])
    slow = _replace(ms, comments=(f"input_speed_rpm: {ms.input_speed_rpm:.6g}",))
    (kept,), notes = check_records(CASE, [slow])
    assert notes == [] and kept.time_s[-1] == ms.time_s[-1]


def test_an_encoder_glitch_is_found_reported_and_repaired():
    eff = draw_effect(np.random.default_rng(30), CASE, "output_coaxiality")
    clean = _toy([eff], 30)
    out = clean[2].output_angle_deg.copy()
    out[100] += 10.0                                       # one sample 10 deg off
    recs = clean[:2] + [_replace(clean[2], output_angle_deg=out)] + clean[3:]
    d = diagnose(CASE, STIFF, recs, toy_te, points_per_rev=256)
    glitch = [n for n in d.notes if "glitch" in n]
    assert len(glitch) == 1 and "sample 100" in glitch[0]
    assert d.cause == "output_coaxiality" and d.extension.gain >= 0.6
    assert d.extension.parameters["output_coaxiality_um"] == pytest.approx(eff.truth["output_coaxiality_um"], rel=0.05)


def test_non_uniform_sampling_gives_the_same_diagnosis():
    eff = draw_effect(np.random.default_rng(31), CASE, "output_coaxiality")
    rng = np.random.default_rng(31)
    recs = []
    for r in _toy([eff], 31, samples_per_rev=512):
        keep = np.sort(np.r_[0, rng.choice(np.arange(1, len(r.time_s) - 1), 300, replace=False), len(r.time_s) - 1])
        recs.append(_replace(r, time_s=r.time_s[keep], input_angle_deg=r.input_angle_deg[keep],
                             output_angle_deg=r.output_angle_deg[keep], output_torque_Nm=r.output_torque_Nm[keep]))
    d = diagnose(CASE, STIFF, recs, toy_te, points_per_rev=256)
    assert d.cause == "output_coaxiality"
    assert d.extension.parameters["output_coaxiality_um"] == pytest.approx(eff.truth["output_coaxiality_um"], rel=0.05)


def _write(tmp_path, name, t, a_in, a_out, T, comments=()):
    p = tmp_path / name
    write_record(p, t, a_in, a_out, T, comments=list(comments))
    return p


def test_a_time_gap_is_no_wrapped_angle_and_is_resampled_within_its_limit(tmp_path):
    r = _toy([], 32, torque_fractions=(0.1,), samples_per_rev=512)[0]
    keep = np.r_[0:200, 208:len(r.time_s)]               # 8 samples missing: 5.6 deg of output < 360/zp
    p = _write(tmp_path, "gap.csv", r.time_s[keep], r.input_angle_deg[keep], r.output_angle_deg[keep],
               r.output_torque_Nm[keep])
    rec = read_record(p)                                   # was: "the angle is wrapped"
    (fixed,), notes = check_records(CASE, [rec])
    assert len(notes) == 1 and "8 samples missing" in notes[0] and "between samples 199 and 200" in notes[0]
    assert len(fixed.time_s) == len(r.time_s)              # back on the record's clock
    assert fixed.output_angle_deg == pytest.approx(r.output_angle_deg, abs=1e-3)   # linear over 5.6 deg
    far = np.r_[0:200, 260:len(r.time_s)]                  # 60 missing: 42 deg, more than one crank period
    rec = read_record(_write(tmp_path, "gap2.csv", r.time_s[far], r.input_angle_deg[far],
                             r.output_angle_deg[far], r.output_torque_Nm[far]))
    with pytest.raises(RecordError, match=r"gap2.csv: a time gap spans 42.\d deg of output .* up to 9 deg"):
        check_records(CASE, [rec])


def test_a_forward_then_backward_file_is_split_or_refused_with_its_reason(tmp_path):
    fw, bw = _toy([], 33, torque_fractions=(0.1,))
    t = np.r_[fw.time_s, fw.time_s[-1] + bw.time_s[1:]]
    cols = [np.r_[getattr(fw, c), getattr(bw, c)[1:]] for c in ("input_angle_deg", "output_angle_deg", "output_torque_Nm")]
    p = _write(tmp_path, "both.csv", t, *cols)
    with pytest.raises(RecordError, match=r"row \d+: the motion reverses .* split it there"):
        read_record(p)                                     # was: "output turns 0.00 deg"
    parts = read_records(p)
    assert [q.name for q in parts] == ["both.csv#fw", "both.csv#bw"]
    assert [q.direction for q in parts] == [1, -1] and parts[0].encoder_zero == parts[1].encoder_zero == "both.csv"


def test_cli_refuses_a_ratio_mismatch_in_one_line_and_prints_notes(tmp_path, capsys):
    case_path = ROOT / "cases" / "rv40e-81.toml"
    save(REAL, tmp_path / "stiffness.json")
    recs = bench_records(quasi_static_te, CASE, REAL, [], seed=34, torque_fractions=(0.1,), samples_per_rev=PPR)
    wrong = [_replace(r, input_angle_deg=r.input_angle_deg * 105.0 / 81.0) for r in recs]
    paths = write_records(wrong, tmp_path)
    rc = main(["diagnose", "--case", str(case_path), "--measured", *map(str, paths), "--out", str(tmp_path / "d"),
               "--stiffness", str(tmp_path / "stiffness.json"), "--points-per-rev", str(PPR), "--quiet"])
    err = capsys.readouterr().err
    assert rc == 2 and err.startswith("error: ") and err.count("\n") == 1 and "i = 81" in err
