"""The report page: built from whatever stages exist, opens from disk, every image loads."""
import json
import re
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from pipeline.report import build_report, json_to_html, markdown_to_html
from pipeline.render import figure, save_figure

REFS = Path(__file__).resolve().parent / "reference_images"
sys.path.insert(0, str(REFS))
import scenes  # noqa: E402  (tests/reference_images/scenes.py: the pictures' fixed scenes)


@pytest.fixture()
def case_dir(tmp_path):
    d = tmp_path / "rv-test"
    (d / "matrix").mkdir(parents=True)
    fig, ax = figure()
    ax.plot(np.arange(5), np.arange(5) ** 2)
    save_figure(fig, d / "matrix" / "te.png")
    (d / "matrix" / "te_std.csv").write_text("torque_Nm,constant,square,sine\n100,1.0,2.0,3.0\n")
    (d / "matrix" / "comparison.md").write_text("# sigma\n\n| a | b |\n|---|---|\n| 1 | 2 |\n")
    return d


def test_a_missing_stage_is_said_in_neutral_text_and_present_ones_are_shown(case_dir):
    page = build_report(case_dir).read_text()
    assert "not built yet" in page and "class='missing'" not in page
    assert "no bench records for this case" in page          # no diagnosis/ folder: not an error
    assert "<td>100</td>" in page and "../matrix/te.png" in page


def test_the_page_opens_on_the_key_figures_beside_their_references(case_dir):
    (case_dir / "hysteresis").mkdir()
    (case_dir / "hysteresis" / "hysteresis.json").write_text(json.dumps(
        {"torsional_rigidity_Nm_per_arcmin": 243.4, "lost_motion_arcmin": 0.904, "backlash_arcmin": 0.752}))
    page = build_report(case_dir, rated_torque_Nm=412.0, ratio=81.0).read_text()
    summary = page.index("Key figures beside their references")
    assert summary < page.index("<h2 id='geometry'>")        # first, before every section
    head = page[summary:page.index("<h2 id='geometry'>")]
    assert "243 N m/arcmin" in head and "catalog RV-40E: 108 N m/arcmin" in head
    assert "0.904 arcmin" in head and "catalog &lt;= 1 arcmin" in head
    assert "paper 001: 19.20 / 19.03 / 19.49" not in head     # te_std.csv has no 400 N m row here
    assert "no bench records for this case" in head
    page = build_report(case_dir, rated_torque_Nm=1568.0, ratio=81.0).read_text()
    assert "catalog RV-40E" not in page                      # another size: no borrowed reference


def test_the_bench_rigidity_reference_comes_from_the_case_s_own_diagnosis(case_dir):
    (case_dir / "hysteresis").mkdir()
    (case_dir / "hysteresis" / "hysteresis.json").write_text(json.dumps({"torsional_rigidity_Nm_per_arcmin": 1305.0}))
    (case_dir / "diagnosis").mkdir()
    (case_dir / "diagnosis" / "diagnosis.json").write_text(json.dumps(
        {"cause": "output_coaxiality", "findings": [], "baseline": {"residual_rms_arcsec": 80.7},
         "extension": {"causes": ["output_coaxiality", "torsional_stiffness"], "residual_rms_arcsec": 10.3,
                       "gain": 0.87, "holdout_gain": 0.86,
                       "parameters": {"located_component": "carrier", "compliance_factor": 3.05,
                                      "compliance_factor_ci95": [2.70, 3.46],
                                      "rigidity_at_rated_Nm_per_arcmin": {"model": 871.4, "extended": 514.1},
                                      # 1e3 (1 / 514.1 - 1 / 871.4): the same wind-up as one series spring
                                      "added_series_compliance_arcmin_per_kNm": 0.79757}}}))
    page = build_report(case_dir, rated_torque_Nm=1568.0, ratio=81.0).read_text()
    assert ("real bench (this case&#x27;s records, diagnosis) ~514 N m/arcmin tangent at rated (model 871): "
            "carrier compliance x 3.05 [2.70, 3.46], i.e. a series spring of 1254 N m/arcmin wherever it sits") in page
    # the fitted records' RMS before (10.3 / (1 - 0.87) = 79.2), not the baseline over every record
    assert "residual RMS on the fitted records 79.2 -&gt; 10.3 arcsec, gain 0.870, held-out gain 0.860" in page
    assert "baseline RMS over every record 80.7 arcsec" in page
    assert "no bench records" not in page
    assert "compensation from the extended model" not in page      # no compensate/ folder: no row


def test_the_compensation_row_sits_beside_the_published_black_box(case_dir):
    (case_dir / "compensate").mkdir()
    (case_dir / "compensate" / "compensation.json").write_text(json.dumps(
        {"te_rms_before_arcsec": 139.89, "te_rms_after_arcsec": 6.46, "rms_reduction": 0.9538,
         "records": {"a.csv": {}, "b.csv": {}}, "published_rms_reduction": [0.83, 0.94]}))
    page = build_report(case_dir, rated_torque_Nm=1568.0, ratio=81.0).read_text()
    assert "TE RMS 139.9 -&gt; 6.5 arcsec on 2 records (95.4% removed)" in page
    assert "Bilancia et al. 2025: 83%-94% online (per-order black box)" in page


def test_figures_are_full_width_links_to_the_picture_with_a_caption(case_dir):
    page = build_report(case_dir).read_text()
    assert "<a href='../matrix/te.png'><img src='../matrix/te.png'" in page
    assert "<figcaption>" in page and "click for full size" in page
    assert "img{max-width:100%" in page and "figure{" in page      # one picture a row, up to the page width


def test_markdown_pipe_tables_become_html_tables():
    out = markdown_to_html("# T\n\n| x | y |\n|---|---|\n| 1 | 2 |\n")
    assert "<th>x</th>" in out and "<td>2</td>" in out and "---" not in out


def test_markdown_is_rendered_not_shown_raw():
    out = markdown_to_html("**Forces:** from the\nlumped model, `te_std.csv`.\n\n- one\n- two\n")
    assert "<b>Forces:</b> from the lumped model, <code>te_std.csv</code>." in out
    assert out.count("<p>") == 1 and "<li>one</li><li>two</li>" in out and "**" not in out


def test_a_table_row_keeps_its_cells_when_a_cell_holds_absolute_value_bars():
    out = markdown_to_html("| a | b | c |\n|---|---|---|\n| 1 | 2 | 3 |\n| x | y |\n")
    rows = re.findall(r"<tr>(.*?)</tr>", out)
    assert [r.count("<th>") + r.count("<td>") for r in rows] == [3, 3, 3]   # short rows padded


def test_json_artifacts_become_tables_not_dumps():
    out = json_to_html({"made_from": {"x": 1}, "lost_motion_arcmin": 0.90412, "budget": {"pin_contact": 0.61},
                        "curve": list(range(30)), "findings": [{"cause": "backlash", "score": 3.5}]})
    assert "<pre>" not in out and "made_from" not in out
    assert "<td>budget / pin_contact</td><td>0.61</td>" in out and "<td>0.9041</td>" in out
    assert "30 values, 0 .. 29" in out and "<th>cause</th><th>score</th>" in out


@pytest.mark.parametrize("name", sorted(scenes.SCENES))
def test_each_picture_matches_its_reference_image(name, tmp_path):
    """Drawn from fixed arrays and compared with tests/reference_images/<name>.png (regenerate with
    `.venv/bin/python tests/reference_images/scenes.py` after an intended change, and look at it)."""
    path = tmp_path / f"{name}.png"
    scenes.SCENES[name](path)
    err = scenes.rms_difference(path, REFS / f"{name}.png")
    assert err < scenes.RMS_TOLERANCE, f"{name}.png differs from its reference: RMS {err:.2f} grey levels"


def test_the_image_comparison_fails_on_a_broken_picture(tmp_path):
    """The check can fail: the loop drawn mirrored (a sign error) is far outside the tolerance."""
    scenes.hysteresis(tmp_path / "flipped.png", flip=True)
    assert scenes.rms_difference(tmp_path / "flipped.png", REFS / "hysteresis.png") > 2 * scenes.RMS_TOLERANCE


def _chromium():
    return shutil.which("chromium") or shutil.which("chromium-browser") or shutil.which("google-chrome")


@pytest.mark.skipif(_chromium() is None, reason="no headless Chromium on this machine "
                    "(CI installs Debian's chromium; `apt-get install chromium` to run this check)")
def test_every_image_loads_in_headless_chromium(case_dir, tmp_path):
    page = build_report(case_dir)
    (case_dir / "matrix" / "broken.png").write_bytes(b"not a png")   # one image that cannot load
    page = build_report(case_dir)
    dom = subprocess.run(
        [_chromium(), "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
         "--disable-background-networking", "--disable-component-update", "--disable-sync",
         f"--user-data-dir={tmp_path / 'chrome'}", "--allow-file-access-from-files",
         "--virtual-time-budget=5000", "--dump-dom", page.resolve().as_uri()],
        capture_output=True, text=True, timeout=120).stdout
    found = re.search(r'data-images-ok="(\d+)/(\d+)"', dom)
    assert found, "the page's load script did not run"
    # two images on the page; the deliberately broken one must be the only one that fails
    assert (int(found.group(1)), int(found.group(2))) == (1, 2)


def test_an_artifact_made_from_another_case_version_is_flagged(case_dir):
    from geometry.fingerprint import Provenance
    (case_dir / "hysteresis").mkdir()
    made = Provenance("rv-hysteresis/1", "rv-test", "a" * 64, (("stiffness", "c" * 64),)).to_json()
    path = case_dir / "hysteresis" / "hysteresis.json"
    path.write_text(json.dumps({"made_from": made, "lost_motion_arcmin": 0.9}))
    page = build_report(case_dir, "rv-test", "a" * 64).read_text()
    assert "was made from case" not in page
    page = build_report(case_dir, "rv-test", "b" * 64).read_text()
    assert ("hysteresis.json was made from case rv-test (fingerprint aaaaaaaaaaaa...), not from this case "
            "as it is now (fingerprint bbbbbbbbbbbb...)") in page
    path.write_text(json.dumps({"made_from": {**made, "case_fingerprint": "b" * 64}}))   # edited by hand
    assert "does not match its own content" in build_report(case_dir, "rv-test", "b" * 64).read_text()


@pytest.mark.parametrize("name", ["../escaped", "../../x", "a/b", ".."])
def test_the_report_never_writes_outside_the_build_folder(tmp_path, name, capsys):
    from pipeline.cli import main
    from support import case_path
    text = case_path("rv40e-81").read_text().replace('name = "rv40e-81"', f'name = "{name}"')
    case = tmp_path / "bad.toml"
    case.write_text(text)
    build = tmp_path / "deep" / "build"
    build.mkdir(parents=True)
    before = sorted(p for p in tmp_path.rglob("*"))
    assert main(["report", "--case", str(case), "--build", str(build), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: ") and err.count("\n") == 1 and name in err
    assert sorted(p for p in tmp_path.rglob("*")) == before      # nothing written anywhere


@pytest.mark.parametrize("build, needle", [("missing", "no such folder"), ("afile", "is a file"), ("", "an empty path")])
def test_a_build_folder_that_is_not_one_is_refused_instead_of_an_empty_report(tmp_path, build, needle, capsys,
                                                                               monkeypatch):
    from pipeline.cli import main
    from support import case_path
    monkeypatch.chdir(tmp_path)      # an empty --build is the current folder: nothing may land there
    (tmp_path / "afile").write_text("x")
    before = sorted(p for p in tmp_path.rglob("*"))
    assert main(["report", "--case", str(case_path("rv40e-81")), "--build", build, "--quiet"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: --build ") and err.count("\n") == 1 and needle in err, err
    assert sorted(p for p in tmp_path.rglob("*")) == before


def test_a_report_folder_that_cannot_be_written_is_one_line_naming_it(tmp_path, capsys, monkeypatch):
    import tempfile
    from pipeline.cli import main
    from support import case_path
    real = tempfile.TemporaryFile
    # chmod 555 does not stop root (the CI container): make the write probe fail as it would
    monkeypatch.setattr(tempfile, "TemporaryFile", lambda *a, dir=None, **k: (_ for _ in ()).throw(
        PermissionError(13, "Permission denied")) if str(dir).startswith(str(tmp_path)) else real(*a, dir=dir, **k))
    assert main(["report", "--case", str(case_path("rv40e-81")), "--build", str(tmp_path), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: report folder ") and err.count("\n") == 1 and "Permission denied" in err, err
    assert list(tmp_path.iterdir()) == []


def test_the_case_folder_is_one_plain_level_below_the_build_folder(tmp_path):
    from geometry.artifacts import InputError
    from pipeline.cmd_report import case_folder
    assert case_folder(tmp_path, "rv40e-81") == tmp_path / "rv40e-81"
    for bad in ("..", ".", "", "a/b", "../x", "/abs"):
        with pytest.raises(InputError, match="would leave the build folder"):
            case_folder(tmp_path, bad)


def test_the_sensitivity_section_shows_its_table_and_not_the_variants_own_pictures(case_dir):
    page = build_report(case_dir).read_text()
    assert "make sensitivity CASE=" in page                  # not built: said how to build it
    sens = case_dir / "sensitivity"
    (sens / "variants" / "base" / "hysteresis").mkdir(parents=True)
    fig, ax = figure()
    ax.plot([0, 1], [0, 1])
    save_figure(fig, sens / "variants" / "base" / "hysteresis" / "hysteresis.png")
    (sens / "sensitivity.md").write_text("# s\n\n| variant | rigidity |\n|---|---|\n| support_span | 154.1 |\n")
    page = build_report(case_dir).read_text()
    assert "<td>support_span</td>" in page
    assert "variants/base" not in page                        # eight runs' pictures stay out of the page
    # not a make-all prerequisite: a table made by other stage code is flagged, the current one not
    from pipeline.cmd_sensitivity import code_fingerprint
    (sens / "sensitivity.json").write_text(json.dumps({"code_fingerprint": "old"}))
    assert "made by other code" in build_report(case_dir).read_text()
    (sens / "sensitivity.json").write_text(json.dumps({"code_fingerprint": code_fingerprint()}))
    assert "made by other code" not in build_report(case_dir).read_text()


def test_the_key_figures_say_which_records_sit_in_another_angle_frame_and_the_gap_shape():
    from pipeline.report_summary import _record_reading_rows
    lines = {"lines_by_direction": None, "angle_frames": [
        {"group": "pair:a+b", "torques_Nm": [300.0], "shift_deg": 0.5133, "reported": True},
        {"group": "pair:c+d", "torques_Nm": [1800.0], "shift_deg": -0.1, "reported": False}]}
    diag = {"notes": ["gap shape: the residual half-gap departs by -2.6/+1.8 arcsec at 0/300 N.m; the records' own "
                      "half-gap departs by up to 0.21 arcsec"]}
    rows = _record_reading_rows(lines, diag)
    assert [r.value for r in rows] == ["300 N m records +0.513 deg",
                                       "the residual half-gap departs by -2.6/+1.8 arcsec at 0/300 N.m"]
    assert "reported, not applied" in rows[0].note and rows[1].note.startswith("the records' own")
    one = _record_reading_rows({"lines_by_direction": None, "angle_frames": []}, {"notes": []})
    assert [r.value for r in one] == ["one frame"]
    assert _record_reading_rows(None, {"notes": []}) == []
