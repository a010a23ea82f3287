"""`python -m pipeline geometry`: every artifact of the contract, written in-process on tmp_path."""
import json
from pathlib import Path

import numpy as np
import pytest

from pipeline.cli import main

CASES = Path(__file__).resolve().parents[1] / "cases"
ARTIFACTS = ["assembly.png", "crankshaft.step", "crankshaft.stl", "disc.step", "disc.stl",
             "geometry.json", "pin.step", "pin.stl", "profile.csv"]


@pytest.fixture(scope="module")
def out(tmp_path_factory):
    d = tmp_path_factory.mktemp("geometry")
    rc = main(["geometry", "--case", str(CASES / "rv40e-81.toml"), "--out", str(d), "--quiet"])
    assert rc == 0
    return d


def test_the_command_writes_every_artifact_and_nothing_else(out):
    # no temporary file may be left behind by the atomic writes
    assert sorted(p.name for p in out.iterdir()) == ARTIFACTS
    assert all((out / a).stat().st_size > 0 for a in ARTIFACTS)


def test_profile_csv_is_the_closed_modified_profile_in_the_disc_frame(out):
    # contract: columns x_mm,y_mm, closed, >= 2000 points; radius from the modified root
    # R + dR - E - Rr - dRr = 59.687 mm to the tip 62.287 mm (rv40e-81 case file), to 1e-6 mm
    assert (out / "profile.csv").read_text().splitlines()[0] == "x_mm,y_mm"
    p = np.loadtxt(out / "profile.csv", delimiter=",", skiprows=1)
    assert p.shape[0] >= 2000 and p.shape[1] == 2
    assert np.allclose(p[0], p[-1], atol=1e-9)
    r = np.hypot(p[:, 0], p[:, 1])
    assert r.min() == pytest.approx(64 - 0.003 - 1.3 - 3.004, abs=1e-6)  # root R+dR-E-(Rr+dRr)
    assert r.max() == pytest.approx(64 - 0.003 + 1.3 - 3.004, abs=1e-4)   # tip R+dR+E-(Rr+dRr), sampled


def test_geometry_json_reports_consistent_figures(out):
    g = json.loads((out / "geometry.json").read_text())
    assert g["case"] == "rv40e-81"
    assert g["disc_volume_lower_bound_mm3"] < g["disc_volume_mm3"] < g["disc_volume_upper_bound_mm3"]
    assert g["disc_volume_mm3"] == pytest.approx(g["disc_volume_reference_mm3"], rel=1e-6)
    assert g["cad_profile_deviation_um"] < 0.5
    # numerical vs closed form: 5 nm on the clearance, 0.1 % on the backlash (test_clearance.py)
    assert g["min_clearance_um"] == pytest.approx(g["min_clearance_closed_form_um"], abs=5e-3)
    assert g["backlash_total_arcmin"] == pytest.approx(g["backlash_closed_form_total_arcmin"], rel=1e-3)
    assert g["crankshaft_layout"]["journals_mm"] == [[-6.625, 6.625], [43.375, 56.625]]   # 30203: T = 13.25


def test_the_picture_shows_something(out):
    # a blank or single-colour render would mean the off-screen plotter drew nothing
    import matplotlib.image
    img = matplotlib.image.imread(out / "assembly.png")
    assert img.shape[0] >= 600 and img.shape[1] >= 800
    colours = np.unique((img[..., :3] * 255).astype(np.uint8).reshape(-1, 3), axis=0)
    assert len(colours) > 100
    assert np.mean(img[..., :3]) < 0.95      # not a white page


def test_the_step_files_read_back_as_valid_solids(out):
    import cadquery as cq
    for name in ("disc", "pin", "crankshaft"):
        assert cq.importers.importStep(str(out / f"{name}.step")).val().isValid()


def test_an_impossible_case_fails_with_one_clear_line_and_no_artifacts(tmp_path, capsys):
    # E = 1.568 mm: K1 = 0.98, the 3 mm pins undercut the tooth tips -> exit 2, one error line
    text = (CASES / "rv40e-105.toml").read_text().replace("eccentricity_mm = 1.3 ", "eccentricity_mm = 1.568 ")
    bad = tmp_path / "bad.toml"
    bad.write_text(text)
    rc = main(["geometry", "--case", str(bad), "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2
    assert len(err) == 1 and err[0].startswith("error: ") and "undercuts" in err[0]
    assert not (tmp_path / "out").exists()


def test_a_rerun_after_a_sigkill_removes_its_temporaries_and_gives_the_same_bytes(out, tmp_path):
    # SIGKILL cannot be handled: the atomic writes' temporaries (.disc.<random>.step ...) stay, and
    # the next run of the stage removes them before it writes. Same case, same bytes: the STEP
    # header carries no clock time (geometry/export.py), the STL, csv and json no run-dependent value.
    import os
    import signal
    import subprocess
    import sys
    import time
    again = tmp_path / "again"
    env = dict(os.environ, MPLBACKEND="Agg", PYVISTA_OFF_SCREEN="true")
    argv = [sys.executable, "-m", "pipeline", "geometry", "--case", str(CASES / "rv40e-81.toml"), "--out",
            str(again), "--quiet"]
    proc = subprocess.Popen(argv, cwd=CASES.parent, env=env, stderr=subprocess.PIPE)
    deadline = time.time() + 120
    while time.time() < deadline and not (again / "profile.csv").exists() and proc.poll() is None:
        time.sleep(0.05)
    proc.send_signal(signal.SIGKILL)
    proc.communicate(timeout=60)
    planted = again / ".disc.k1ll3d00.step"     # what a kill inside the STEP export leaves
    planted.write_text("partial")
    rerun = subprocess.run(argv, cwd=CASES.parent, env=env, capture_output=True, text=True, timeout=600)
    assert rerun.returncode == 0, rerun.stderr[-2000:]
    assert sorted(p.name for p in again.iterdir()) == ARTIFACTS
    for name in ARTIFACTS:
        if name != "assembly.png":     # a rendering: pixels may depend on the GL driver's threads
            assert (again / name).read_bytes() == (out / name).read_bytes(), name
    assert "FILE_NAME('disc','1970-01-01T00:00:00',('rvte')" in (again / "disc.step").read_text()
