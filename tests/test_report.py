"""The report page: built from whatever stages exist, opens from disk, every image loads."""
import json
import re
import shutil
import subprocess

import numpy as np
import pytest

from pipeline.report import build_report, markdown_to_html
from pipeline.render import figure, save_figure


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


def test_a_missing_stage_is_listed_as_not_built_and_present_ones_are_shown(case_dir):
    page = build_report(case_dir).read_text()
    assert "not built (no hysteresis/ folder)" in page
    assert "<td>100</td>" in page and "../matrix/te.png" in page


def test_markdown_pipe_tables_become_html_tables():
    out = markdown_to_html("# T\n\n| x | y |\n|---|---|\n| 1 | 2 |\n")
    assert "<th>x</th>" in out and "<td>2</td>" in out and "---" not in out


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


def test_the_case_folder_is_one_plain_level_below_the_build_folder(tmp_path):
    from geometry.artifacts import InputError
    from pipeline.cmd_report import case_folder
    assert case_folder(tmp_path, "rv40e-81") == tmp_path / "rv40e-81"
    for bad in ("..", ".", "", "a/b", "../x", "/abs"):
        with pytest.raises(InputError, match="would leave the build folder"):
            case_folder(tmp_path, bad)
