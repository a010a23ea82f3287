"""Artifact fingerprints: every artifact says what it was made from, and a stage refuses an
artifact made from another case or another version of the same case (geometry/fingerprint.py)."""
import dataclasses
import json

import numpy as np
import pytest

from fem import stiffness
from fem.mesh import MESH_SCHEMA, Mesh3D, load_mesh3d, save_mesh3d
from geometry.artifacts import InputError
from geometry.fingerprint import FingerprintError, case_fingerprint, made_from
from geometry.params import load_case
from pipeline.cli import main
from support import case_path, stiffness_for_tests


def _copy(tmp_path, name="copy.toml", *edits):
    """A copy of the rv40e-81 case file elsewhere, with text edits (old, new)."""
    text = case_path("rv40e-81").read_text()
    for old, new in edits:
        assert old in text, old
        text = text.replace(old, new)
    p = tmp_path / name
    p.write_text(text)
    return p


ECC_1_0 = ("eccentricity_mm = 1.3 ", "eccentricity_mm = 1.0 ")   # the case tried in issue 10


@pytest.fixture(scope="module")
def original():
    return load_case(case_path("rv40e-81"))


def test_the_fingerprint_follows_the_content_not_the_file(tmp_path, original):
    fp = case_fingerprint(original)
    assert len(fp) == 64 and int(fp, 16) >= 0
    # another path, comments and number spelling changed: the same case
    same = _copy(tmp_path, "same.toml", ("eccentricity_mm = 1.3 ", "eccentricity_mm = 1.30 "),
                 ("# RV-40E, ratio 81", "# a copy of RV-40E, ratio 81"))
    assert case_fingerprint(load_case(same)) == fp
    # one value or the name changed: another case
    assert case_fingerprint(load_case(_copy(tmp_path, "ecc.toml", ECC_1_0))) != fp
    assert case_fingerprint(load_case(_copy(tmp_path, "named.toml", ('name = "rv40e-81"', 'name = "other"')))) != fp
    assert case_fingerprint(original.with_errors(output_coaxiality_um=5.0)) != fp


def test_an_artifact_fingerprint_covers_its_inputs_and_schema(original):
    a = made_from(original, "rv-stiffness/2", mesh="f" * 64)
    assert a.fingerprint != made_from(original, "rv-stiffness/2", mesh="e" * 64).fingerprint
    assert a.fingerprint != made_from(original, "rv-stiffness/3", mesh="f" * 64).fingerprint
    assert made_from(original, "x", mesh=None).inputs == ()      # an optional input not given
    back = type(a).from_json(json.loads(json.dumps(a.to_json())), "here")
    assert back == a and back.fingerprint == a.fingerprint


@pytest.fixture(scope="module")
def stiffness_file(tmp_path_factory, original):
    path = tmp_path_factory.mktemp("fem") / "stiffness.json"
    stiffness.save(stiffness_for_tests(original), path)
    return path


def test_a_stiffness_of_another_version_of_the_case_is_refused_naming_both(tmp_path, stiffness_file, original):
    assert stiffness.load(stiffness_file, original).made_from.case_fingerprint == case_fingerprint(original)
    other_path = _copy(tmp_path, "my.toml", ECC_1_0)
    other = load_case(other_path)
    for read in (lambda: stiffness.load(stiffness_file, other), lambda: stiffness.for_case(other, stiffness_file),
                 lambda: stiffness.path_for_case(other, stiffness_file)):
        with pytest.raises(FingerprintError) as e:
            read()
        msg = str(e.value)
        assert "\n" not in msg
        assert f"{stiffness_file} was made from case 'rv40e-81'" in msg
        assert case_fingerprint(original)[:12] in msg and case_fingerprint(other)[:12] in msg
        assert f"not from {other_path} (case 'rv40e-81' with other content, fingerprint" in msg
        assert f"rerun `python -m pipeline fem --case {other_path} --out {stiffness_file.parent}`" in msg


def test_simulate_refuses_the_stiffness_of_the_13_mm_case_for_a_10_mm_copy(tmp_path, stiffness_file, capsys):
    # issue 10: a copy with 1.0 mm eccentricity and the same name ran silently on the 1.3 mm stiffness
    copy = _copy(tmp_path, "my.toml", ECC_1_0)
    rc = main(["simulate", "--case", str(copy), "--stiffness", str(stiffness_file), "--load", "constant:100",
               "--duration", "0.01", "--out", str(tmp_path / "r.csv")])
    err = capsys.readouterr().err
    assert rc == 2 and err.count("\n") == 1 and "was made from case 'rv40e-81'" in err
    assert not (tmp_path / "r.csv").exists()


def test_a_stiffness_without_fingerprint_or_edited_by_hand_is_refused(tmp_path, stiffness_file, original):
    data = json.loads(stiffness_file.read_text())
    bare = tmp_path / "bare.json"
    bare.write_text(json.dumps({**data, "made_from": None}))
    assert stiffness.load(bare).made_from is None                   # readable as data ...
    with pytest.raises(FingerprintError, match="no fingerprint"):   # ... but not for a case
        stiffness.load(bare, original)
    edited = tmp_path / "edited.json"
    edited.write_text(json.dumps({**data, "made_from": {**data["made_from"],
                                                        "case_fingerprint": case_fingerprint(original)[::-1]}}))
    with pytest.raises(FingerprintError, match="does not match its own content"):
        stiffness.load(edited, original)
    old = tmp_path / "old.json"
    old.write_text(json.dumps({**data, "schema": "rv-stiffness/1"}))
    with pytest.raises(InputError, match=r"schema 'rv-stiffness/1', expected 'rv-stiffness/4': rebuild"):
        stiffness.path_for_case(original, old)


def test_a_mesh_of_another_version_of_the_case_is_refused(tmp_path, original):
    m = Mesh3D(np.zeros((4, 3)), np.array([[0, 1, 2, 3]]))
    save_mesh3d(tmp_path / "m.npz", m, made_from=made_from(original, MESH_SCHEMA))
    got = load_mesh3d(tmp_path / "m.npz", case=original)
    assert got.made_from.case_fingerprint == case_fingerprint(original)
    other = load_case(_copy(tmp_path, "my.toml", ECC_1_0))
    with pytest.raises(FingerprintError, match=r"m.npz was made from case 'rv40e-81'.*rerun `python -m pipeline mesh"):
        load_mesh3d(tmp_path / "m.npz", case=other)
    save_mesh3d(tmp_path / "old.npz", m)                          # a mesh from before fingerprints
    with pytest.raises(FingerprintError, match="no fingerprint"):
        load_mesh3d(tmp_path / "old.npz", case=original)


def test_the_fem_stage_refuses_a_mesh_made_from_another_case_before_computing(tmp_path, original, capsys):
    from fem.shaft import crankshaft_fingerprint
    save_mesh3d(tmp_path / "mesh" / "crankshaft_mesh.npz", Mesh3D(np.zeros((4, 3)), np.array([[0, 1, 2, 3]])),
                made_from=made_from(original, MESH_SCHEMA), fingerprint=crankshaft_fingerprint(original))
    copy = _copy(tmp_path, "my.toml", ("rated_torque_Nm = 412.0", "rated_torque_Nm = 400.0"))
    rc = main(["fem", "--case", str(copy), "--mesh", str(tmp_path / "mesh"), "--out", str(tmp_path / "fem"),
               "--quiet"])
    assert rc == 2 and "crankshaft_mesh.npz was made from case 'rv40e-81'" in capsys.readouterr().err
    assert not (tmp_path / "fem").exists()


def test_the_stand_in_and_a_replaced_model_keep_or_drop_the_fingerprint(original):
    s = stiffness_for_tests(original)
    assert s.made_from is not None and s.to_json()["made_from"]["case"] == "rv40e-81"
    assert dataclasses.replace(s, made_from=None).to_json()["made_from"] is None


def test_the_tolerance_summary_records_the_stiffness_it_was_made_from(tmp_path, stiffness_file, original):
    out = tmp_path / "tol"
    assert main(["tolerance", "--case", str(case_path("rv40e-81")), "--samples", "20", "--out", str(out),
                 "--stiffness", str(stiffness_file), "--workers", "1", "--quiet"]) == 0
    made = json.loads((out / "summary.json").read_text())["made_from"]
    stiff = json.loads(stiffness_file.read_text())["made_from"]
    assert made["artifact"] == "rv-tolerance/1" and made["inputs"] == {"stiffness": stiff["fingerprint"]}
    assert made["case_fingerprint"] == case_fingerprint(original)
