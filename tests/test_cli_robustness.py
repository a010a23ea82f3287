"""The command line as a user meets it: bad input gives one clear line and exit code 2 (never a
traceback) and loses no earlier artifact; a killed stage leaves no partial file; same inputs give
the same bytes."""
import hashlib
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from fem.stiffness import save
from tests.support import stiffness_for_tests
from geometry.params import load_case

ROOT = Path(__file__).resolve().parents[1]
CASE = ROOT / "cases" / "rv40e-81.toml"


def cli(*args, cwd=None, timeout=600):
    env = dict(os.environ, MPLBACKEND="Agg", PYVISTA_OFF_SCREEN="true")
    return subprocess.run([sys.executable, "-m", "pipeline", *map(str, args)], cwd=cwd or ROOT,
                          capture_output=True, text=True, timeout=timeout, env=env)


@pytest.fixture(scope="module")
def stiffness(tmp_path_factory):
    path = tmp_path_factory.mktemp("stiff") / "stiffness.json"
    save(stiffness_for_tests(load_case(CASE)), path)
    return path


def bad_case(tmp_path, old, new, name):
    text = CASE.read_text()
    assert old in text
    path = tmp_path / name
    path.write_text(text.replace(old, new))
    return path


def record(tmp_path, body, name="rec.csv"):
    path = tmp_path / name
    path.write_text("time_s,input_angle_deg,output_angle_deg,output_torque_Nm\n" + body)
    return path


def _corpus(tmp_path, stiffness):
    """(argv, words the message must contain) for each bad input a user can give."""
    cusp = bad_case(tmp_path, "eccentricity_mm = 1.3", "eccentricity_mm = 1.7", "cusp.toml")
    unknown = bad_case(tmp_path, "[disc]", "[disc]\nbore_mm = 3", "unknown.toml")
    nan_rec = record(tmp_path, "0,0,0,0\n0.001,nan,0,0\n", "nan.csv")
    back_rec = record(tmp_path, "0,0,0,0\n0.001,1,0.01,0\n0.0005,2,0.02,0\n", "back.csv")
    cols = tmp_path / "cols.csv"
    cols.write_text("t,a,b\n0,0,0\n")
    return [
        (["geometry", "--case", cusp, "--out", tmp_path / "g"], "cusps"),
        (["geometry", "--case", unknown, "--out", tmp_path / "g"], "unknown key"),
        (["geometry", "--case", tmp_path / "missing.toml", "--out", tmp_path / "g"], "not found"),
        (["simulate", "--case", CASE, "--stiffness", stiffness, "--load", "cubic:100", "--out",
          tmp_path / "r.csv"], "cubic"),
        (["simulate", "--case", CASE, "--stiffness", tmp_path / "none.json", "--load", "constant:100",
          "--out", tmp_path / "r.csv"], "none.json"),
        (["diagnose", "--case", CASE, "--stiffness", stiffness, "--measured", nan_rec, "--out",
          tmp_path / "d"], "nan.csv"),
        (["diagnose", "--case", CASE, "--stiffness", stiffness, "--measured", back_rec, "--out",
          tmp_path / "d"], "back.csv"),
        (["diagnose", "--case", CASE, "--stiffness", stiffness, "--measured", cols, "--out",
          tmp_path / "d"], "cols.csv"),
        # an unknown option points at the command's own help, where the options are
        (["fourbar", "--case", CASE, "--out", tmp_path / "f", "--frob", "3"],
         "unrecognized arguments: --frob 3 (`python -m pipeline fourbar --help` lists the options)"),
    ]


def test_every_bad_input_in_the_corpus_gives_one_clear_line_and_exit_code_2(tmp_path, stiffness):
    for argv, words in _corpus(tmp_path, stiffness):
        out = cli(*argv)
        assert out.returncode == 2, (argv, out.stderr[-2000:])
        assert "Traceback" not in out.stderr, (argv, out.stderr[-2000:])
        assert words in out.stderr, (argv, out.stderr)
        assert out.stderr.startswith("error: "), out.stderr


def test_a_failing_rerun_keeps_the_earlier_artifact(tmp_path, stiffness):
    out = tmp_path / "run.csv"
    ok = cli("simulate", "--case", CASE, "--stiffness", stiffness, "--load", "constant:100",
             "--duration", "0.3", "--out", out)
    assert ok.returncode == 0, ok.stderr
    before = out.read_bytes()
    bad = cli("simulate", "--case", CASE, "--stiffness", stiffness, "--load", "constant:-5x",
              "--duration", "0.3", "--out", out)
    assert bad.returncode == 2 and out.read_bytes() == before


def test_same_inputs_give_byte_identical_records(tmp_path, stiffness):
    digests = []
    for name in ("a.csv", "b.csv"):
        res = cli("simulate", "--case", CASE, "--stiffness", stiffness, "--load", "sine:200",
                  "--duration", "0.3", "--out", tmp_path / name)
        assert res.returncode == 0, res.stderr
        digests.append(hashlib.sha256((tmp_path / name).read_bytes()).hexdigest())
    assert digests[0] == digests[1]


def test_a_stage_killed_midway_leaves_no_partial_artifact_and_the_rerun_completes(tmp_path):
    out = tmp_path / "geom"
    env = dict(os.environ, MPLBACKEND="Agg", PYVISTA_OFF_SCREEN="true")
    proc = subprocess.Popen([sys.executable, "-m", "pipeline", "geometry", "--case", CASE, "--out",
                             out, "--quiet"], cwd=ROOT, env=env, stderr=subprocess.PIPE)
    deadline = time.time() + 120
    while time.time() < deadline and not (out / "profile.csv").exists():
        time.sleep(0.05)
    proc.send_signal(signal.SIGTERM)   # killed while the solids are being built and exported
    proc.wait(timeout=60)
    assert proc.returncode != 0
    leftovers = [p.name for p in out.iterdir() if p.name.startswith(".")]
    assert leftovers == [], f"temporary files left behind: {leftovers}"
    rerun = cli("geometry", "--case", CASE, "--out", out, "--quiet")
    assert rerun.returncode == 0, rerun.stderr
    assert {"profile.csv", "disc.step", "pin.step", "crankshaft.step", "assembly.png"} <= \
        {p.name for p in out.iterdir()}


@pytest.mark.parametrize("argv", [["fourbar", "--points", "3"], ["simulate", "--load", "constant:100"]])
@pytest.mark.parametrize("out", ["", " "])
def test_an_empty_out_path_is_refused_instead_of_writing_into_the_current_folder(tmp_path, monkeypatch, capsys,
                                                                                 argv, out):
    from pipeline.cli import main
    work = tmp_path / "work"
    work.mkdir()
    monkeypatch.chdir(work)          # Path("") is ".": the artifacts would land here, the run lock in tmp_path
    rc = main([argv[0], "--case", str(CASE), "--stiffness", str(tmp_path / "none.json"), *argv[1:], "--out", out])
    err = capsys.readouterr().err
    assert rc == 2 and err == f"error: --out {out!r}: an empty path; give the output's path\n", err
    assert list(tmp_path.rglob("*")) == [work] and list(work.iterdir()) == []


def test_running_out_of_memory_is_one_line_and_leaves_no_temporary(tmp_path, monkeypatch, capsys):
    from pipeline import cmd_fourbar
    from pipeline.cli import main
    out = tmp_path / "fb"
    out.mkdir()
    (out / "earlier.json").write_text("{}")

    def exhausted(args):
        (out / ".fourbar.abcdefgh.json").write_text("{")       # a write in progress
        raise MemoryError
    monkeypatch.setattr(cmd_fourbar, "run_fourbar", exhausted)
    assert main(["fourbar", "--case", str(CASE), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: `fourbar` ran out of memory;") and err.count("\n") == 1, err
    assert sorted(p.name for p in out.iterdir()) == ["earlier.json"]
