"""Sensitivity of the catalog rigidity to the case's sizes (pipeline.sensitivity, `sensitivity`)."""
from __future__ import annotations

import json
import math
import sys
import tomllib

import pytest

from geometry.params import case_from_dict
from pipeline import cmd_sensitivity
from pipeline.cli import main
from pipeline.sensitivity import (BY_NAME, SensitivityError, Variant, Edit, case_value, edited,
                                  elasticity, is_assumed, needed_size, summarise)
from tests.support import case_path

TEXT = case_path("rv40e-81").read_text()


def test_a_variant_edits_its_size_and_the_sizes_tied_to_it_and_the_case_still_validates():
    text, edits = edited(TEXT, BY_NAME["eccentric_radius"], "rv40e-81-eccentric_radius")
    case = case_from_dict(tomllib.loads(text))
    assert case.name == "rv40e-81-eccentric_radius"
    assert case.crankshaft.eccentric_radius_mm == pytest.approx(10.8)
    assert case.disc.crank_hole_radius_mm == pytest.approx(13.8)     # follows: the same needles
    assert [(e["key"], e["from"]) for e in edits] == [("eccentric_radius_mm", 12.0), ("crank_hole_radius_mm", 15.0)]
    # nothing else moved: every other value of every section as in the case
    base, var = tomllib.loads(TEXT), tomllib.loads(text)
    for sec in base:
        if isinstance(base[sec], dict):
            changed = {k for k in base[sec] if base[sec][k] != var[sec][k]}
            assert changed <= {"eccentric_radius_mm", "crank_hole_radius_mm"}, (sec, changed)
    assert "# ASSUMED: needle inner race  # sensitivity eccentric_radius: was 12.0" in text


@pytest.mark.parametrize("name", ["rv40e-81", "rv40e-105", "rv160n-81"])
def test_every_variant_of_every_shipped_case_is_a_valid_case(name):
    # a wider disc needs a longer pin ring (the housing spans the disc stack): the RV-160N's variant
    # failed validation before the ring followed
    text = case_path(name).read_text()
    for v in BY_NAME.values():
        case = case_from_dict(tomllib.loads(edited(text, v, f"{name}-{v.name}")[0]))
        assert case.name == f"{name}-{v.name}"


def test_width_is_not_face_width_and_integers_stay_integers():
    text, _ = edited(TEXT, BY_NAME["disc_width"], "x")
    var = tomllib.loads(text)
    assert var["cycloid"]["width_mm"] == pytest.approx(11.0)
    assert var["stage1"]["face_width_mm"] == 10.0                     # another key ending in width_mm
    assert var["crankshaft"]["needle_length_mm"] == pytest.approx(11.0)
    text, _ = edited(TEXT, BY_NAME["needle_count"], "x")
    assert tomllib.loads(text)["crankshaft"]["needle_count"] == 20


def test_a_size_the_case_does_not_state_is_refused():
    with pytest.raises(SensitivityError, match=r"no numeric `bogus_mm` in \[carrier\]"):
        edited(TEXT, Variant("b", (Edit("carrier", "bogus_mm", "scale", 1.1),), ""), "x")


def test_the_case_files_own_word_says_which_sizes_are_assumed():
    assert is_assumed(case_value(TEXT, "carrier", "pillar_radius_mm")[1])
    assert not is_assumed(case_value(TEXT, "cycloid", "eccentricity_mm")[1])   # paper 000


def test_elasticity_and_needed_size_are_exact_on_a_power_law():
    k = lambda x: 170.0 * (x / 6.0) ** 0.65          # noqa: E731
    e = elasticity(6.0, 6.6, k(6.0), k(6.6))
    assert e == pytest.approx(0.65, rel=1e-12)
    assert k(needed_size(6.0, k(6.0), e, 108.0)) == pytest.approx(108.0, rel=1e-12)
    assert needed_size(6.0, 170.0, 0.0, 108.0) is None and elasticity(6.0, 6.0, 1, 1) is None
    # a negative size (the modification's moved distance) scales as well: 1.5 x the magnitude
    assert elasticity(-0.003, -0.0045, 100.0, 100.0 * 1.5 ** -0.2) == pytest.approx(-0.2)
    assert needed_size(-0.003, 100.0, -0.2, 100.0 * 1.5 ** -0.2) == pytest.approx(-0.0045)
    assert elasticity(-0.003, 0.003, 100.0, 90.0) is None


def test_the_table_aims_at_the_band_edge_on_the_predictions_side():
    runs = {"pillar_radius": {"edits": [{"section": "carrier", "key": "pillar_radius_mm", "from": 6.0, "to": 6.6}],
                              "assumed": True, "rigidity": 170.0 * 1.1 ** 0.65, "lost_motion": 0.9},
            "crank_count": {"error": "fem: error: boom"}}
    t = summarise({"rigidity": 170.0, "lost_motion": 0.95}, runs, 108.0, 0.25)
    assert t["targets_Nm_per_arcmin"]["band_edge"] == pytest.approx(135.0)
    row = t["variants"]["pillar_radius"]
    assert 170.0 * (row["size_for_band_edge"] / 6.0) ** 0.65 == pytest.approx(135.0)
    assert t["variants"]["crank_count"] == {"why": BY_NAME["crank_count"].why, "error": "fem: error: boom"}
    low = summarise({"rigidity": 60.0, "lost_motion": 0.95}, {}, 108.0, 0.25)
    assert low["targets_Nm_per_arcmin"]["band_edge"] == pytest.approx(81.0)


FAKE_STAGE = r"""
import json, pathlib, sys, tomllib
case, folder = pathlib.Path(sys.argv[1]), pathlib.Path(sys.argv[2])
c = tomllib.loads(case.read_text())
if c["carrier"]["crank_count"] == 2:
    print("error: two cranks refused here", file=sys.stderr); sys.exit(2)
runs = folder / "runs.txt"
runs.write_text(runs.read_text() + "x" if runs.exists() else "x")
for sub in ("fem", "hysteresis"):
    (folder / sub).mkdir(parents=True, exist_ok=True)
(folder / "fem" / "stiffness.json").write_text(json.dumps({"support_bearings": {"designation": "30203"}}))
k = 170.0 * (c["carrier"]["pillar_radius_mm"] / 6.0) ** 0.65
(folder / "hysteresis" / "hysteresis.json").write_text(json.dumps(
    {"torsional_rigidity_Nm_per_arcmin": k, "lost_motion_arcmin": 0.95, "compliance_budget": {"carrier": 0.3}}))
"""


@pytest.fixture
def fake_stages(monkeypatch):
    """The stage chain replaced by one script with a known power law (K ~ pillar_radius^0.65)."""
    monkeypatch.setattr(cmd_sensitivity, "_stage_commands",
                        lambda case, folder: [[sys.executable, "-c", FAKE_STAGE, str(case), str(folder)]])


def test_the_command_runs_each_variant_resumes_and_reports_a_failed_one(tmp_path, fake_stages, capsys):
    out = tmp_path / "s"
    argv = ["sensitivity", "--case", str(case_path("rv40e-81")), "--out", str(out), "--workers", "1",
            "--only", "pillar_radius,crank_count", "--quiet"]
    assert main(argv) == 0
    t = json.loads((out / "sensitivity.json").read_text())
    row = t["variants"]["pillar_radius"]
    assert row["elasticity"] == pytest.approx(0.65, rel=1e-9) and row["assumed"] is True
    assert math.isclose(t["base"]["rigidity_Nm_per_arcmin"], 170.0)
    assert "two cranks refused here" in t["variants"]["crank_count"]["error"]
    assert "| pillar_radius | carrier.pillar_radius_mm (ASSUMED) | 6 -> 6.6 |" in (out / "sensitivity.md").read_text()
    runs = out / "variants" / "pillar_radius" / "runs.txt"
    assert runs.read_text() == "x"
    assert main(argv) == 0                             # resumed: the unchanged variant is read
    assert runs.read_text() == "x"
    assert t["code_fingerprint"] == cmd_sensitivity.code_fingerprint()
    # other stage code (a stiffness model changed since): recomputed, not read from the old run
    real = cmd_sensitivity.code_fingerprint
    cmd_sensitivity.code_fingerprint = lambda: "other code"
    try:
        assert main(argv) == 0
    finally:
        cmd_sensitivity.code_fingerprint = real
    assert runs.read_text() == "x"                     # a fresh folder (the old count is gone), run once
    assert (out / "variants" / "pillar_radius" / "code.txt").read_text() == "other code"
    assert main(argv) == 0                             # and back: recomputed again
    assert (out / "variants" / "pillar_radius" / "code.txt").read_text() == real()
    # another case text in the same folder is recomputed from scratch, not mixed with the old
    other = tmp_path / "other.toml"
    other.write_text(TEXT.replace("pillar_radius_mm = 6.0 ", "pillar_radius_mm = 7.0 "))
    assert main(["sensitivity", "--case", str(other), "--out", str(out), "--workers", "1",
                 "--only", "pillar_radius", "--quiet"]) == 0
    assert runs.read_text() == "x"                     # a fresh folder: the old count is gone
    assert json.loads((out / "sensitivity.json").read_text())["base"]["rigidity_Nm_per_arcmin"] == \
        pytest.approx(170.0 * (7.0 / 6.0) ** 0.65)


@pytest.mark.parametrize("extra, words", [(["--only", "bogus"], "allowed comma-separated variants"),
                                           (["--band", "2"], "--band = 2: allowed"),
                                           (["--workers", "0"], "--workers = 0: allowed")])
def test_bad_options_get_one_line_and_exit_2(tmp_path, capsys, extra, words):
    assert main(["sensitivity", "--case", str(case_path("rv40e-81")), "--out", str(tmp_path / "s"),
                 *extra]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and words in err[0]
    assert not (tmp_path / "s" / "variants").exists()


def test_the_code_fingerprint_covers_exactly_the_stages_the_variants_run(tmp_path):
    cmds = cmd_sensitivity._stage_commands(tmp_path / "case.toml", tmp_path)
    assert [c[3] for c in cmds] == list(cmd_sensitivity.RUN_STAGES)

