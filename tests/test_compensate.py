"""`python -m pipeline compensate`: the extended model as a TE table, checked on records.

Model: the quasi-static path with tests/support.py's closed-form stiffness (RV-40E i = 81). The
virtual bench (pipeline.diagnosis.bench) hides a drawn cause; a diagnosis.json that carries exactly
that cause's model parameters must then compensate those records down to their noise (0.3 arcsec
Gaussian + 2^22-count quantisation, against a TE of tens of arcsec): reduction >= 0.95.
"""
import json
from pathlib import Path

import numpy as np
import pytest

from fem.stiffness import save
from geometry.params import load_case
from pipeline.cli import main
from pipeline.diagnosis import causes
from pipeline.diagnosis.bench import bench_records, draw_effect, write_records
from pipeline.diagnosis.compensate import Table, extended_model
from pipeline.diagnosis.simulate import quasi_static_te

support = pytest.importorskip("support", reason="tests/support.py (stiffness stand-in) not present")
ROOT = Path(__file__).parents[1]
CASE_PATH = ROOT / "cases" / "rv40e-81.toml"
CASE = load_case(CASE_PATH)
STIFF = support.stiffness_for_tests(CASE)


def _diagnosis(tmp_path, effects) -> Path:
    mp = {e.cause: {q.name: float(v) for q, v in zip(causes.get(e.cause).params(CASE), e.p)} for e in effects}
    path = tmp_path / "diag" / "diagnosis.json"
    path.parent.mkdir()
    path.write_text(json.dumps({"cause": effects[0].cause if effects else None, "findings": [], "baseline": {},
                                "extension": {"causes": sorted(mp), "parameters": {"model_parameters": mp},
                                              "residual_rms_arcsec": 0.0, "gain": 0.0, "holdout_gain": None}
                                if mp else None}))
    return path


def test_a_table_of_the_hidden_causes_compensates_their_records_down_to_the_noise(tmp_path, capsys):
    rng = np.random.default_rng(7)
    effs = [draw_effect(rng, CASE, "output_coaxiality"), draw_effect(rng, CASE, "pin_ring_pattern")]
    recs = bench_records(quasi_static_te, CASE, STIFF, effs, seed=7, torque_fractions=(0.1, 0.4),
                         samples_per_rev=256)
    paths = write_records(recs, tmp_path)
    save(STIFF, tmp_path / "stiffness.json")
    rc = main(["compensate", "--case", str(CASE_PATH), "--diagnosis", str(_diagnosis(tmp_path, effs)),
               "--out", str(tmp_path / "comp"), "--check", *map(str, paths), "--stiffness",
               str(tmp_path / "stiffness.json"), "--points-per-rev", "256"])
    assert rc == 0 and "reduction" in capsys.readouterr().out
    res = json.loads((tmp_path / "comp" / "compensation.json").read_text())
    assert res["rms_reduction"] >= 0.95 and res["te_rms_after_arcsec"] < 1.0
    assert res["published_rms_reduction"] == [0.83, 0.94] and len(res["records"]) == 4
    assert all(r["rms_reduction"] >= 0.9 for r in res["records"].values())
    rows = (tmp_path / "comp" / "compensation.csv").read_text().splitlines()
    assert rows[0] == "output_angle_deg,torque_Nm,direction,te_arcsec"
    # levels: 0, 25, 50, 100 % rated and the two check torques, both directions, 256 points each
    assert len(rows) - 1 == 6 * 2 * 256
    assert {r.split(",")[2] for r in rows[1:]} == {"forward", "backward"}


def test_the_table_interpolates_in_torque_between_levels_and_in_angle_periodically():
    ang = np.array([0.0, 90.0, 180.0, 270.0])
    tab = Table(ang, ((0.0, 1), (100.0, 1), (-100.0, -1)), np.array([[0, 1, 2, 3], [10, 11, 12, 13], [5, 5, 5, 5.0]]))
    assert tab.predict(np.array([45.0, 315.0, 405.0]), 50.0, 1) == pytest.approx([5.5, 6.5, 5.5])
    assert tab.predict(np.array([90.0]), 500.0, 1) == pytest.approx([11.0])     # clamped at the top level
    assert tab.predict(np.array([10.0]), -100.0, -1) == pytest.approx([5.0])


def test_a_diagnosis_without_an_extension_or_of_another_case_is_one_clear_line(tmp_path, capsys):
    save(STIFF, tmp_path / "stiffness.json")
    args = ["compensate", "--case", str(CASE_PATH), "--out", str(tmp_path / "comp"), "--stiffness",
            str(tmp_path / "stiffness.json")]
    rc = main(args + ["--diagnosis", str(_diagnosis(tmp_path, []))])
    err = capsys.readouterr().err
    assert rc == 2 and "no extended model" in err and err.count("\n") == 1
    d = tmp_path / "other"
    d.mkdir()
    (d / "diagnosis.json").write_text(json.dumps({"extension": {"parameters": {"model_parameters": {
        "output_coaxiality": {"coaxiality_cos_um": 1.0, "coaxiality_sin_um": 0.0}}}}}))
    (d / "diagnosis_made_from.json").write_text(json.dumps({"made_from": {"case": "rv160n-81",
                                                                          "case_fingerprint": "0" * 64}}))
    rc = main(args + ["--diagnosis", str(d / "diagnosis.json")])
    err = capsys.readouterr().err
    assert rc == 2 and "made for case 'rv160n-81'" in err and err.count("\n") == 1
    rc = main(args + ["--diagnosis", str(tmp_path / "missing.json")])
    assert rc == 2 and "not found" in capsys.readouterr().err


def test_a_model_parameter_outside_its_physical_range_is_refused():
    with pytest.raises(ValueError, match="outside"):
        extended_model(CASE, STIFF, {"output_coaxiality": {"coaxiality_cos_um": 1e4, "coaxiality_sin_um": 0.0}})
    with pytest.raises(ValueError, match="not registered"):
        extended_model(CASE, STIFF, {"gear_rattle": {}})


@pytest.mark.parametrize("edit, needle", [
    (lambda d: d["extension"].update(parameters=[1]), "no extended model"),
    (lambda d: d["extension"]["parameters"]["model_parameters"].update(output_coaxiality=5),
     "model_parameters.output_coaxiality = 5: allowed an object"),
    (lambda d: d["extension"]["parameters"]["model_parameters"]["output_coaxiality"].update(coaxiality_cos_um=[1, 2]),
     "model_parameters.output_coaxiality.coaxiality_cos_um = [1, 2]: allowed a number"),
    (lambda d: d["extension"]["parameters"]["model_parameters"]["output_coaxiality"].update(coaxiality_cos_um=None),
     "coaxiality_cos_um = None: allowed a number"),
    (lambda d: d["extension"]["parameters"]["model_parameters"]["output_coaxiality"].update(
        coaxiality_cos_um=float("nan")), "coaxiality_cos_um = nan outside"),
])
def test_a_malformed_extension_is_one_clear_line_not_a_traceback(tmp_path, capsys, edit, needle):
    save(STIFF, tmp_path / "stiffness.json")
    path = _diagnosis(tmp_path, [draw_effect(np.random.default_rng(0), CASE, "output_coaxiality")])
    d = json.loads(path.read_text())
    edit(d)
    path.write_text(json.dumps(d))
    (tmp_path / "comp").mkdir()
    (tmp_path / "comp" / "compensation.csv").write_text("earlier\n")
    rc = main(["compensate", "--case", str(CASE_PATH), "--out", str(tmp_path / "comp"), "--stiffness",
               str(tmp_path / "stiffness.json"), "--diagnosis", str(path)])
    err = capsys.readouterr().err
    assert rc == 2 and err.startswith("error: ") and err.count("\n") == 1 and needle in err, err
    assert (tmp_path / "comp" / "compensation.csv").read_text() == "earlier\n"


@pytest.mark.parametrize("side, needle", [(b"\xa3\x01 binary", "not UTF-8 text"), (b"{nope", "not valid JSON"),
                                          (b"[1]", "no made_from object"), (b'{"made_from": [1]}', "no made_from")])
def test_a_broken_made_from_sidecar_is_one_clear_line_naming_it(tmp_path, capsys, side, needle):
    save(STIFF, tmp_path / "stiffness.json")
    path = _diagnosis(tmp_path, [draw_effect(np.random.default_rng(0), CASE, "output_coaxiality")])
    (path.parent / "diagnosis_made_from.json").write_bytes(side)
    rc = main(["compensate", "--case", str(CASE_PATH), "--out", str(tmp_path / "comp"), "--stiffness",
               str(tmp_path / "stiffness.json"), "--diagnosis", str(path)])
    err = capsys.readouterr().err
    assert rc == 2 and err.count("\n") == 1 and "diagnosis_made_from.json" in err and needle in err, err


def test_a_diagnosis_file_larger_than_any_artifact_is_refused_before_it_is_read(tmp_path, capsys, monkeypatch):
    import geometry.artifacts as artifacts
    path = _diagnosis(tmp_path, [])
    monkeypatch.setattr(artifacts, "JSON_MAX_BYTES", 10)    # a 30 GB file read whole ran out of memory
    rc = main(["compensate", "--case", str(CASE_PATH), "--out", str(tmp_path / "comp"), "--diagnosis", str(path)])
    err = capsys.readouterr().err
    assert rc == 2 and err.count("\n") == 1 and "a JSON file has at most 10 bytes" in err, err
