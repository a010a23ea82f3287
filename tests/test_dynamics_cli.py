"""CLI contracts of the dynamics stage (DESIGN.md): simulate, hysteresis, matrix (short runs)."""
import csv
import json

import numpy as np
import pytest

from dynamics.loads import LoadSpec, load_torque_Nm
from fem.stiffness import COMPONENTS, save
from geometry.params import load_case
from pipeline.cli import main
from pipeline.report_summary import key_figures
from support import case_path, stiffness_for_tests


@pytest.fixture(scope="module")
def stiffness_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("fem") / "stiffness.json"
    save(stiffness_for_tests(load_case(case_path())), path)
    return path


def test_simulate_writes_a_bench_record(tmp_path, stiffness_file):
    out = tmp_path / "rec.csv"
    rc = main(["simulate", "--case", str(case_path()), "--stiffness", str(stiffness_file), "--load", "sine:200",
               "--duration", "0.3", "--out", str(out), "--quiet"])
    assert rc == 0
    rows = [r for r in out.read_text().splitlines() if not r.startswith("#")]
    assert rows[0].split(",")[:4] == ["time_s", "input_angle_deg", "output_angle_deg", "output_torque_Nm"]
    data = np.loadtxt(rows[1:], delimiter=",")
    assert data[-1, 0] == pytest.approx(0.3)
    assert np.allclose(data[:, 3], 0.05 * 200 * np.sin(8 * data[:, 0]) + 200, atol=1e-6)
    # the run's condition for diagnose, and the carrier's drag it carried beside the load (not in the column)
    notes = [r for r in out.read_text().splitlines() if r.startswith("#")]
    assert "# oil_temperature_C: 25" in notes and any(n.startswith("# carrier drag ") for n in notes)


def test_missing_stiffness_is_a_one_line_error_naming_the_fem_stage(tmp_path, capsys):
    rc = main(["simulate", "--case", str(case_path()), "--stiffness", str(tmp_path / "none.json"),
               "--load", "sine:200", "--out", str(tmp_path / "r.csv")])
    assert rc == 2
    assert "pipeline fem" in capsys.readouterr().err


def test_hysteresis_writes_the_catalog_figures(tmp_path, stiffness_file):
    rc = main(["hysteresis", "--case", str(case_path()), "--stiffness", str(stiffness_file), "--out",
               str(tmp_path), "--quiet"])
    assert rc == 0
    h = json.loads((tmp_path / "hysteresis.json").read_text())
    for key in ("torsional_rigidity_Nm_per_arcmin", "lost_motion_arcmin", "backlash_arcmin"):
        assert h[key] > 0
    # backlash of the case's modification (dR < 0, dRr > 0). Closed form with the eccentric
    # fixed: b0 = (dRr - dR sqrt(1 - K1^2)) / (E zc) per side (geometry/clearance.py, first order).
    # With the INPUT locked the eccentric turns (1 + z1/z2) x the output, so the mismatch to the
    # conjugate motion grows (zc + 1 + z1/z2) / zc times faster: backlash = 2 b0 zc / (zc + 1 + z1/z2)
    case = load_case(case_path())
    c, m, s1 = case.cycloid, case.modification, case.stage1
    K1 = c.eccentricity_mm * c.zp / c.pin_circle_radius_mm
    b0 = (m.equidistant_mm - m.offset_mm * np.sqrt(1 - K1 ** 2)) / (c.eccentricity_mm * c.zc)
    expected = 2 * np.rad2deg(b0) * 60 * c.zc / (c.zc + 1 + s1.z1 / s1.z2)
    assert h["backlash_arcmin"] == pytest.approx(expected, rel=5e-3)
    assert h["lost_motion_arcmin"] > h["backlash_arcmin"]
    assert (tmp_path / "hysteresis.csv").exists() and (tmp_path / "hysteresis.png").exists()
    assert sum(h["compliance_budget"].values()) == pytest.approx(1.0, abs=1e-9)
    assert tuple(h["compliance_budget"]) == COMPONENTS       # by physical component (dynamics.budget)
    assert set(h["compliance_budget_by_coupling"]) >= {"pin", "needle", "support", "mesh"}
    assert (tmp_path / "compliance_budget.png").exists()


def test_matrix_writes_the_sigma_table_with_twelve_cells(tmp_path, stiffness_file):
    rc = main(["matrix", "--case", str(case_path()), "--stiffness", str(stiffness_file), "--out", str(tmp_path),
               "--duration", "0.1", "--dt", "2e-4", "--quiet"])
    assert rc == 0
    rows = list(csv.reader((tmp_path / "te_std.csv").open()))
    assert rows[0] == ["torque_Nm", "constant", "square", "sine"]
    assert [r[0] for r in rows[1:]] == ["100", "200", "300", "400"]
    assert "14.154" in (tmp_path / "comparison.md").read_text()
    for name in ("te_std_last_rev.csv", "te_std_whole.csv"):      # the other two sigma windows
        assert list(csv.reader((tmp_path / name).open()))[0] == rows[0]
    assert len(list(tmp_path.glob("*.npz"))) == 12
    # matrix.json is te_std.csv's sidecar: what the table was made from
    made = json.loads((tmp_path / "matrix.json").read_text())["made_from"]
    assert made["artifact"] == "rv-matrix/1" and set(made["inputs"]) == {"stiffness"}


def test_simulate_defaults_to_the_case_input_speed(tmp_path):
    # DESIGN.md: speed defaults to the case's [operation] input_speed_rpm (rv40e-105: 525 rpm, paper
    # 000), not paper 001's 1200. The drive is speed * STEP(t, 0, 0, 1, 1) (paper 001), so the input
    # angle at t is speed * (t^3 - t^4 / 2) for t <= 1 s: 0.02295 speed at 0.3 s.
    case = load_case(case_path("rv40e-105"))
    assert case.operation.input_speed_rpm == 525.0
    stiff = tmp_path / "stiffness.json"
    save(stiffness_for_tests(case), stiff)
    for speed_args, rpm in (([], 525.0), (["--speed-rpm", "1800"], 1800.0)):
        out = tmp_path / f"rec{rpm:g}.csv"
        assert main(["simulate", "--case", str(case_path("rv40e-105")), "--stiffness", str(stiff), "--load",
                     "constant:100", "--duration", "0.3", *speed_args, "--out", str(out), "--quiet"]) == 0
        text = out.read_text()
        assert f"speed {rpm:g} rpm" in text
        data = np.loadtxt([r for r in text.splitlines() if not r.startswith("#")][1:], delimiter=",")
        t = data[-1, 0]
        assert data[-1, 1] == pytest.approx(rpm * 6.0 * (t ** 3 - t ** 4 / 2), rel=1e-3)


def test_outputs_record_the_case_and_stiffness_they_were_made_from(tmp_path, stiffness_file):
    from geometry.fingerprint import case_fingerprint
    rc = main(["hysteresis", "--case", str(case_path()), "--stiffness", str(stiffness_file), "--out",
               str(tmp_path), "--quiet"])
    assert rc == 0
    made = json.loads((tmp_path / "hysteresis.json").read_text())["made_from"]
    stiff = json.loads(stiffness_file.read_text())["made_from"]
    assert made["case_fingerprint"] == case_fingerprint(load_case(case_path())) == stiff["case_fingerprint"]
    assert made["inputs"] == {"stiffness": stiff["fingerprint"]} and made["artifact"] == "rv-hysteresis/1"
    rc = main(["simulate", "--case", str(case_path()), "--stiffness", str(stiffness_file), "--load", "constant:100",
               "--duration", "0.01", "--out", str(tmp_path / "r.csv"), "--quiet"])
    assert rc == 0 and f"# made_from: case {made['case_fingerprint']}, stiffness {stiff['fingerprint']}" \
        in (tmp_path / "r.csv").read_text()


def test_the_matrix_reuses_finished_cells_with_the_same_inputs_and_recomputes_the_rest(tmp_path, stiffness_file,
                                                                                     capsys):
    # each cell is its own artifact carrying the fingerprint of its inputs (dynamics/matrix.py):
    # a rerun recomputes only the cells that are missing or were made from other inputs
    argv = ["matrix", "--case", str(case_path()), "--stiffness", str(stiffness_file), "--out", str(tmp_path),
            "--duration", "0.1", "--dt", "2e-4"]
    assert main(argv + ["--quiet"]) == 0
    table = (tmp_path / "te_std_whole.csv").read_bytes()

    def stamps():
        return {p.name: (p.stat().st_ino, p.stat().st_mtime_ns) for p in tmp_path.glob("*.npz")}
    first = stamps()
    (tmp_path / "sine_300.npz").unlink()
    (tmp_path / "constant_100.npz").write_bytes(b"a damaged file")
    capsys.readouterr()
    assert main(argv) == 0
    assert "2 cells computed, 10 reused" in capsys.readouterr().out
    second = stamps()
    assert {k for k in first if first[k] != second[k]} == {"sine_300.npz", "constant_100.npz"}
    assert (tmp_path / "te_std_whole.csv").read_bytes() == table      # reused or computed: same numbers
    assert main(argv[:-1] + ["1e-4"]) == 0                              # another time step: all new
    assert "12 cells computed, 0 reused" in capsys.readouterr().out


def test_a_torque_beyond_the_momentary_rating_is_a_one_line_error(tmp_path, stiffness_file, capsys):
    # issue 12: constant:50000 (121x rated) "completed" with --dt 1e-5
    out = tmp_path / "r.csv"
    rc = main(["simulate", "--case", str(case_path()), "--stiffness", str(stiffness_file), "--load",
               "constant:50000", "--dt", "1e-5", "--out", str(out)])
    assert rc == 2 and not out.exists()
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "momentary" in err and "2058" in err


# ------------------------------------------------------------------ a load form beyond paper 001

def test_simulate_runs_the_trapezoid(tmp_path, stiffness_file):
    out = tmp_path / "rec.csv"
    assert main(["simulate", "--case", str(case_path()), "--stiffness", str(stiffness_file), "--load", "trapezoid:300",
                 "--duration", "1.3", "--dt", "2e-4", "--out", str(out), "--quiet"]) == 0
    text = out.read_text()
    assert "load trapezoid:300" in text
    data = np.loadtxt([r for r in text.splitlines() if not r.startswith("#")][1:], delimiter=",")
    assert np.allclose(data[:, 3], load_torque_Nm(LoadSpec("trapezoid", 300.0), data[:, 0]), atol=1e-6)
    assert data[-1, 3] == pytest.approx(300.0)          # t = 1.3 s: on the dwell at T


def test_the_matrix_runs_a_form_when_asked_and_says_it_has_no_paper_figure(tmp_path, stiffness_file):
    assert main(["matrix", "--case", str(case_path()), "--stiffness", str(stiffness_file), "--out", str(tmp_path),
                 "--duration", "0.1", "--dt", "2e-4", "--forms", "sine,trapezoid", "--quiet"]) == 0
    rows = list(csv.reader((tmp_path / "te_std.csv").open()))
    assert rows[0] == ["torque_Nm", "sine", "trapezoid"]
    assert sorted(p.name for p in tmp_path.glob("*.npz")) == sorted(
        f"{f}_{T}.npz" for f in ("sine", "trapezoid") for T in (100, 200, 300, 400))
    text = (tmp_path / "comparison.md").read_text()
    assert "| 400 | " in text and "19.485" in text and "no paper figure" in text
    # the report's key figures read the forms by name from the table's header
    (tmp_path / "case" / "matrix").mkdir(parents=True)
    (tmp_path / "case" / "matrix" / "te_std.csv").write_text(
        "torque_Nm,constant,square,sine,trapezoid\n400,1.0,2.0,3.0,4.0\n")
    row = next(r for r in key_figures(tmp_path / "case", 412.0, 81) if r.quantity.startswith("sigma of TE"))
    assert "constant / square / sine / trapezoid" in row.quantity and row.value == "1 / 2 / 3 / 4 arcsec"
    assert row.reference == "paper 001: 19.20 / 19.03 / 19.48 / no paper figure"   # 19.485 to 2 places


@pytest.mark.parametrize("forms", ["ramp", "sine,,square", "sine,sine"])
def test_a_bad_forms_option_is_one_error_line(tmp_path, stiffness_file, forms, capsys):
    assert main(["matrix", "--case", str(case_path()), "--stiffness", str(stiffness_file), "--out", str(tmp_path),
                 "--forms", forms]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("error:") and "constant, square, sine, trapezoid" in err


def test_a_run_oil_temperature_outside_the_lubricant_s_range_is_a_one_line_error(tmp_path, stiffness_file, capsys):
    # the record's drag is read at [lubrication] run_oil_temperature_C: outside [min, max] it names the key
    text = case_path().read_text().replace("[lubrication]", "[lubrication]\nrun_oil_temperature_C = 200.0", 1)
    case, out = tmp_path / "hot.toml", tmp_path / "r.csv"
    case.write_text(text)
    rc = main(["simulate", "--case", str(case), "--stiffness", str(stiffness_file), "--load", "constant:100",
               "--duration", "0.2", "--out", str(out)])
    assert rc == 2 and not out.exists()
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "run_oil_temperature_C = 200.0" in err and "[-10, 120]" in err
