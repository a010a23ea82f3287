"""`conditions`: the table contract (dynamics.conditions) as a user meets it, and the operating map of
the real bench table where ../shared/measured is present.

Bad tables give one `error:` line naming the file, the line, the column, the value and what is allowed,
exit code 2, no traceback, before any heavy work. A good table gives the contract's columns, the
input's columns copied through (a measured column named like an output kept as measured_<name>)."""
from __future__ import annotations

import csv
import io
from pathlib import Path

import pytest

from dynamics.conditions import MAX_ROWS, RESULT_COLUMNS, ConditionsError, read_table
from fem.stiffness import save
from geometry.params import load_case
from pipeline.cli import main
from tests.support import stiffness_for_tests

ROOT = Path(__file__).resolve().parents[1]
CASE = ROOT / "cases" / "rv40e-81.toml"
MEASURED = ROOT.parent / "shared" / "measured"
HEAD = "input_speed_rpm,torque_Nm,oil_temperature_C"
RANGE = (-10.0, 120.0)


@pytest.fixture(scope="module")
def stiffness(tmp_path_factory):
    path = tmp_path_factory.mktemp("stiff") / "stiffness.json"
    save(stiffness_for_tests(load_case(CASE)), path)
    return path


def table(tmp_path, text, name="t.csv"):
    p = tmp_path / name
    p.write_text(text)
    return p


CORPUS = [
    ("missing column", "input_speed_rpm,torque_Nm\n100,0\n", "'oil_temperature_C' missing"),
    ("negative speed", f"{HEAD}\n-100,0,25\n", "input_speed_rpm = -100"),
    ("zero speed", f"{HEAD}\n0,10,25\n", "input_speed_rpm = 0"),
    ("NaN torque", f"{HEAD}\n100,nan,25\n", "torque_Nm = 'nan'"),
    ("negative torque", f"{HEAD}\n100,-5,25\n", "torque_Nm = -5"),
    ("text", f"{HEAD}\n100,ten,25\n", "torque_Nm = 'ten': not a number"),
    ("too hot", f"{HEAD}\n100,0,180\n", "oil_temperature_C = 180: outside the lubricant's stated range"),
    ("too cold", f"{HEAD}\n100,0,-40\n", "oil_temperature_C = -40"),
    ("ragged", f"{HEAD}\n100,0\n", "2 fields; the header has 3"),
    ("no rows", f"# only a header\n{HEAD}\n", "no condition rows"),
    ("empty", "# nothing\n", "no header"),
    ("duplicate column", f"{HEAD},torque_Nm\n100,0,25,1\n", "'torque_Nm' appears twice"),
    ("both clash names", f"{HEAD},gap_fw_minus_bw_arcsec,measured_gap_fw_minus_bw_arcsec\n100,0,25,1,1\n",
     "both present"),
]


@pytest.mark.parametrize("label,text,words", CORPUS, ids=[c[0] for c in CORPUS])
def test_a_bad_table_gives_one_clear_line_and_exit_code_2(tmp_path, capsys, stiffness, label, text, words):
    path = table(tmp_path, text)
    rc = main(["conditions", "--case", str(CASE), "--stiffness", str(stiffness), "--table", str(path),
               "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert rc == 2, err
    assert err.startswith("error: ") and err.count("\n") == 1, err
    assert words in err and str(path) in err, err
    assert not (tmp_path / "out" / "conditions.csv").exists()


def test_a_hundred_thousand_rows_are_refused_at_once_with_the_limit(tmp_path):
    path = table(tmp_path, HEAD + "\n" + "100,0,25\n" * 100_000)
    with pytest.raises(ConditionsError, match=f"100000 rows; allowed at most {MAX_ROWS}"):
        read_table(path, RANGE)


def test_a_binary_or_non_utf8_file_or_a_folder_is_refused(tmp_path):
    b = tmp_path / "b.csv"
    b.write_bytes(b"input\0speed")
    with pytest.raises(ConditionsError, match="binary"):
        read_table(b, RANGE)
    b.write_bytes(b"input_speed_rpm\xff\xfe")
    with pytest.raises(ConditionsError, match="not UTF-8"):
        read_table(b, RANGE)
    with pytest.raises(ConditionsError, match="folder"):
        read_table(tmp_path, RANGE)
    with pytest.raises(ConditionsError, match="no such file"):
        read_table(tmp_path / "none.csv", RANGE)


def test_a_torque_beyond_the_momentary_maximum_is_refused(tmp_path, capsys, stiffness):
    path = table(tmp_path, f"{HEAD}\n100,5000,25\n")
    rc = main(["conditions", "--case", str(CASE), "--stiffness", str(stiffness), "--table", str(path),
               "--out", str(tmp_path / "out")])
    assert rc == 2 and "momentary torque" in capsys.readouterr().err


def test_comments_any_column_order_and_extra_columns_are_read_and_copied_through(tmp_path, capsys, stiffness):
    path = table(tmp_path, "# bench map\noil_temperature_C,note,torque_Nm,input_speed_rpm,gap_fw_minus_bw_arcsec\n"
                           "# a comment between rows\n40,slow,0,300,-20\n40,fast,200,1800,-150\n")
    t = read_table(path, RANGE)
    assert [(r.input_speed_rpm, r.torque_Nm, r.oil_temperature_C) for r in t.rows] == [(300, 0, 40), (1800, 200, 40)]
    assert main(["conditions", "--case", str(CASE), "--stiffness", str(stiffness), "--table", str(path),
                 "--out", str(tmp_path / "out"), "--points-per-rev", "4", "--workers", "1", "--quiet"]) == 0
    rows = list(csv.DictReader(io.StringIO((tmp_path / "out" / "conditions.csv").read_text())))
    assert list(rows[0])[:5] == ["oil_temperature_C", "note", "torque_Nm", "input_speed_rpm",
                                 "measured_gap_fw_minus_bw_arcsec"]
    assert list(rows[0])[5:] == list(RESULT_COLUMNS)
    assert rows[0]["note"] == "slow" and rows[0]["efficiency"] == ""         # empty at zero torque
    assert 0.3 < float(rows[1]["efficiency"]) < 1.0
    gap = float(rows[1]["gap_fw_minus_bw_arcsec"])
    assert gap == pytest.approx(float(rows[1]["te_mean_fw_arcsec"]) - float(rows[1]["te_mean_bw_arcsec"]), abs=1e-3)
    assert gap < float(rows[0]["gap_fw_minus_bw_arcsec"]) < 0        # the gap opens with torque


def test_a_table_with_measured_gaps_gets_the_thermal_what_if_and_its_report_row(tmp_path, stiffness):
    import json

    from pipeline.report_summary import operating_rows
    path = table(tmp_path, f"{HEAD},gap_fw_minus_bw_arcsec\n100,0,25,-20\n100,300,25,-100\n"
                           "1800,0,25,-15\n1800,300,25,-90\n")
    out = tmp_path / "case" / "conditions"
    assert main(["conditions", "--case", str(CASE), "--stiffness", str(stiffness), "--table", str(path),
                 "--out", str(out), "--points-per-rev", "4", "--workers", "1", "--quiet"]) == 0
    doc = json.loads((out / "conditions.json").read_text())
    th = doc["against_measured"]["thermal_whatif"]
    assert th["speed_rpm"] == 1800 and th["rows"] == 2 and th["disc_warmer_K"] == [0.0, 2.0, 4.0]
    assert th["zero_load_gap_change_arcsec_per_K"] > 0          # warmer discs: less free play
    assert th["bench_zero_load_gap_change_arcsec"] == pytest.approx(5.0)
    assert th["kelvin_for_bench_zero_load_gap_change"] == pytest.approx(5.0 / th["zero_load_gap_change_arcsec_per_K"])
    row = [r for r in operating_rows(tmp_path / "case") if r.quantity.startswith("what-if, not the prediction: discs")]
    assert len(row) == 1 and "arcsec/K" in row[0].value and "100 -> 1800 rpm" in row[0].reference


def test_a_thermal_what_if_the_case_cannot_take_is_skipped_saying_why_not_the_prediction(tmp_path, stiffness,
                                                                                         monkeypatch):
    import json

    import dynamics.thermal
    def invalid(case, dT):
        raise ValueError("profile cusps")
    monkeypatch.setattr(dynamics.thermal, "warmer_discs", invalid)
    path = table(tmp_path, f"{HEAD},gap_fw_minus_bw_arcsec\n1800,0,25,-15\n1800,300,25,-90\n")
    assert main(["conditions", "--case", str(CASE), "--stiffness", str(stiffness), "--table", str(path),
                 "--out", str(tmp_path / "out"), "--points-per-rev", "4", "--workers", "1", "--quiet"]) == 0
    doc = json.loads((tmp_path / "out" / "conditions.json").read_text())
    assert doc["against_measured"]["thermal_whatif"] == {
        "skipped": "discs 4 K warmer make an invalid case (profile cusps)"}
    assert len(doc["rows"]) == 2


@pytest.mark.skipif(not (MEASURED / "conditions_25C.csv").exists(),
                    reason="../shared/measured/conditions_25C.csv absent (the real bench map is not shipped)")
def test_the_real_bench_table_passes_the_contract():
    t = read_table(MEASURED / "conditions_25C.csv", RANGE)
    assert len(t.rows) == 47
    assert {r.input_speed_rpm for r in t.rows} == {100, 300, 900, 1700, 1800}
    assert all(r.oil_temperature_C == 25 for r in t.rows)


def test_gap_lines_split_the_error_into_the_wind_up_and_the_zero_load_gap():
    from dynamics.conditions import gap_lines
    v = [100.0] * 4 + [1800.0] * 3 + [300.0]
    T = [0.0, 400.0, 800.0, 1200.0, 100.0, 900.0, 1800.0, 500.0]
    bench = [-22.0 - 0.289 * t if s == 100 else -32.0 - 0.242 * t for s, t in zip(v, T)]
    bench[-1] = -180.0
    # a model 2x too stiff, its zero-load gap right: the bench's slopes remove the whole error
    stiff = [(-22.0 if s == 100 else -32.0) - 0.5 * (b + (22.0 if s == 100 else 32.0)) for s, b in zip(v, bench)]
    r = gap_lines(v, T, bench, stiff)
    assert set(r["by_speed_rpm"]) == {"100", "1800"} and r["rows_on_lines"] == 7     # 300 rpm: one torque
    s100 = r["by_speed_rpm"]["100"]
    assert s100["measured_arcsec_per_Nm"] == pytest.approx(-0.289) and s100["measured_zero_load_gap_arcsec"] == pytest.approx(-22.0)
    assert s100["measured_rigidity_Nm_per_arcmin"] == pytest.approx(120 / 0.289)
    assert s100["predicted_rigidity_Nm_per_arcmin"] == pytest.approx(2 * 120 / 0.289)
    assert r["gap_rms_error_with_bench_slopes_arcsec"] == pytest.approx(0.0, abs=1e-9)
    assert r["gap_rms_error_with_bench_zero_load_gaps_arcsec"] == pytest.approx(r["gap_rms_error_on_lines_arcsec"])
    # the stiffness right, 20 arcsec more lost motion: the bench's zero-load gaps remove it all
    loose = [b - 20.0 for b in bench]
    r = gap_lines(v, T, bench, loose)
    assert r["gap_rms_error_on_lines_arcsec"] == pytest.approx(20.0)
    assert r["gap_rms_error_with_bench_zero_load_gaps_arcsec"] == pytest.approx(0.0, abs=1e-9)
    assert r["gap_rms_error_with_bench_slopes_arcsec"] == pytest.approx(20.0)


def test_warmer_discs_grow_about_their_centre_and_close_the_free_play_by_eps_times_r_minus_rr():
    """dynamics.thermal: the disc's profile, crank-hole circle and bores scale by 1 + alpha dT (first
    order); the free play (geometry.clearance.backlash) falls as the flank moves out by eps (R - Rr)
    against the pins, i.e. by the same angle as an offset modification of that size."""
    from dynamics.thermal import STEEL_EXPANSION_PER_K as alpha, warmer_discs
    from geometry.clearance import backlash_arcmin
    case = load_case(CASE)
    hot = warmer_discs(case, 4.0)
    eps = alpha * 4.0
    c, m = case.cycloid, case.modification
    assert hot.modification.offset_mm == pytest.approx(m.offset_mm + eps * c.pin_circle_radius_mm, rel=1e-12)
    assert hot.modification.equidistant_mm == pytest.approx(m.equidistant_mm + eps * c.pin_radius_mm, rel=1e-12)
    assert hot.errors.crank_hole_position_um[0] == pytest.approx(eps * case.carrier.crank_circle_radius_mm * 1e3)
    assert hot.errors.turning_arm_clearance_um == pytest.approx(eps * case.disc.crank_hole_radius_mm * 1e3)
    moved = case.replace("modification", offset_mm=m.offset_mm + eps * (c.pin_circle_radius_mm - c.pin_radius_mm))
    assert backlash_arcmin(hot) < backlash_arcmin(case)
    # first order only: the equidistant part acts on the flank unlike an offset of the same radial size
    # (0.566 against 0.558 arcmin here, 1.4 % apart), hence 2 %; the free play falls by ~27 % at 4 K
    assert backlash_arcmin(hot) == pytest.approx(backlash_arcmin(moved), rel=0.02)
    assert warmer_discs(case, 0.0) == case
    with pytest.raises(ValueError, match="allowed finite and >= 0"):
        warmer_discs(case, -1.0)


def test_the_thermal_what_if_reads_the_change_per_kelvin_and_the_kelvin_the_bench_s_change_asks():
    from dynamics.conditions import thermal_whatif
    T = [100.0, 500.0, 1000.0, 1800.0]
    # the model: zero-load gap -50 + 3 dT arcsec, wind-up -0.145 (1 - 0.001 dT)
    gaps = {dT: [-50.0 + 3.0 * dT - 0.145 * (1 - 0.001 * dT) * t for t in T] for dT in (0.0, 2.0, 4.0)}
    lines = {"100": {"measured_zero_load_gap_arcsec": -43.0, "measured_arcsec_per_Nm": -0.28},
             "1800": {"measured_zero_load_gap_arcsec": -31.0, "measured_arcsec_per_Nm": -0.24}}
    out = thermal_whatif(T, gaps, lines, 1800.0)
    assert out["zero_load_gap_change_arcsec_per_K"] == pytest.approx(3.0)
    assert out["wind_up_change_pct_per_K"] == pytest.approx(-0.1)
    assert out["bench_zero_load_gap_change_arcsec"] == pytest.approx(12.0)
    assert out["kelvin_for_bench_zero_load_gap_change"] == pytest.approx(4.0)
    assert out["bench_wind_up_change_pct"] == pytest.approx(-100 / 7)
    assert out["kelvin_for_bench_wind_up_change"] == pytest.approx(1000 / 7)
    # a change of the other sign cannot be reached by warming: no kelvin
    lines["1800"]["measured_zero_load_gap_arcsec"] = -50.0
    assert thermal_whatif(T, gaps, lines, 1800.0)["kelvin_for_bench_zero_load_gap_change"] is None
    assert thermal_whatif([100.0] * 4, gaps, lines, 1800.0) is None


def test_a_torque_flange_in_the_bench_chain_adds_its_twist_to_every_gap():
    # the what-if of the bench's layout: a series spring k adds -2 T / k to forward minus backward; a model
    # whose gap misses exactly one data-sheet flange's twist is put right by that flange and by no other.
    # TB1A 2 kN m: 2000 N m at 0.034 deg -> 3.37e6 N m/rad, 980 N m/arcmin (data sheet B0161)
    import math

    from dynamics.conditions import TORQUE_FLANGES, chain_whatifs
    from dynamics.results import ARCSEC_PER_RAD
    T = [0.0, 300.0, 900.0, 1800.0]
    name, nominal, angle = TORQUE_FLANGES[0]
    k = nominal / math.radians(angle)
    bench = [-30.0 - 0.24 * t for t in T]
    model = [b + 2.0 * t / k * ARCSEC_PER_RAD for b, t in zip(bench, T)]
    out = chain_whatifs(T, bench, model)
    assert [w["flange"] for w in out] == [f[0] for f in TORQUE_FLANGES]
    assert out[0]["stiffness_Nm_per_rad"] == pytest.approx(3.370e6, rel=1e-3)
    assert out[0]["rigidity_Nm_per_arcmin"] == pytest.approx(980.4, rel=1e-3)
    assert out[0]["gap_rms_error_arcsec"] == pytest.approx(0.0, abs=1e-9)
    assert all(w["gap_rms_error_arcsec"] > 10.0 for w in out[1:])
