"""Safe edges of the command line, as a user meets them in a real process: every bad option is one
`error:` line and exit code 2 before any work (an earlier artifact stays byte-identical), a
killed run leaves nothing behind and a rerun removes what a SIGKILL left, SIGTERM / Ctrl-C act at
once, and an interrupted load matrix resumes with only its unfinished cells."""
from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import pytest

from fem.stiffness import save
from geometry.params import load_case
from support import case_path, stiffness_for_tests

ROOT = Path(__file__).resolve().parents[1]
CASE = case_path("rv40e-81")
ENV = dict(os.environ, MPLBACKEND="Agg", PYVISTA_OFF_SCREEN="true")
TEMP = re.compile(r"^\..+\.[a-z0-9_]{8}(\.[A-Za-z0-9]+)?$")     # geometry.artifacts.atomic_path's names


def cli(*args, timeout=300):
    return subprocess.run([sys.executable, "-m", "pipeline", *map(str, args)], cwd=ROOT, env=ENV,
                          capture_output=True, text=True, timeout=timeout)


@pytest.fixture
def start():
    """Popen of the CLI; whatever a failing test leaves running is killed at teardown."""
    procs = []

    def run(*args):
        procs.append(subprocess.Popen([sys.executable, "-m", "pipeline", *map(str, args)], cwd=ROOT, env=ENV,
                                      stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True))
        return procs[-1]
    yield run
    for p in procs:
        if p.poll() is None:
            p.kill()
            p.communicate()


def snapshot(folder: Path) -> dict:
    return {p.name: p.read_bytes() for p in folder.iterdir() if p.is_file()}


def temps(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir() if TEMP.match(p.name))


def cpu_seconds(pid: int) -> float:
    """CPU time a process has used (Linux /proc), to signal it once it is really computing."""
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def wait_busy(proc, cpu_s: float, timeout_s: float = 120.0) -> None:
    deadline = time.time() + timeout_s
    while time.time() < deadline and proc.poll() is None:
        try:
            if cpu_seconds(proc.pid) >= cpu_s:
                return
        except (FileNotFoundError, ProcessLookupError):   # no /proc: fall back to wall time
            time.sleep(cpu_s)
            return
        time.sleep(0.05)


@pytest.fixture(scope="module")
def stiffness(tmp_path_factory):
    path = tmp_path_factory.mktemp("stiff") / "stiffness.json"
    save(stiffness_for_tests(load_case(CASE)), path)
    return path


def read_only_folder(tmp_path: Path) -> Path:
    """A folder this process cannot write in: chmod 555, or for root (who writes anyway) sysfs."""
    ro = tmp_path / "read_only"
    ro.mkdir()
    (ro / "earlier.csv").write_text("an earlier artifact\n")
    ro.chmod(0o555)
    try:
        with tempfile.TemporaryFile(dir=ro):
            pass
    except OSError:
        return ro
    if Path("/sys/kernel").is_dir():
        return Path("/sys/kernel")
    pytest.skip("no folder this user cannot write to")


# (id, argv with {S} stiffness / {O} the output folder / {F} a file in it, words of the message)
BAD = [
    ("geometry-out-is-a-file", ["geometry", "--case", CASE, "--out", "{F}"], "is an existing file"),
    ("matrix-out-is-a-file", ["matrix", "--case", CASE, "--stiffness", "{S}", "--duration", "0.1", "--out", "{F}"],
     "is an existing file"),
    ("simulate-out-is-a-folder", ["simulate", "--case", CASE, "--stiffness", "{S}", "--load", "sine:100",
                                  "--duration", "0.1", "--out", "{O}"], "is a folder"),
    ("simulate-out-under-a-file", ["simulate", "--case", CASE, "--stiffness", "{S}", "--load", "sine:100",
                                   "--duration", "0.1", "--out", "{F}/r.csv"], "is a file, not a folder"),
    ("simulate-duration-huge", ["simulate", "--case", CASE, "--stiffness", "{S}", "--load", "sine:100",
                                "--duration", "1e6", "--out", "{F}"], "--duration = 1e+06 s: allowed"),
    ("simulate-duration-zero", ["simulate", "--case", CASE, "--stiffness", "{S}", "--load", "sine:100",
                                "--duration", "0", "--out", "{F}"], "--duration = 0 s: allowed"),
    ("simulate-duration-nan", ["simulate", "--case", CASE, "--stiffness", "{S}", "--load", "sine:100",
                               "--duration", "nan", "--out", "{F}"], "--duration = nan s"),
    ("simulate-dt-coarse", ["simulate", "--case", CASE, "--stiffness", "{S}", "--load", "sine:100",
                            "--dt", "0.01", "--out", "{F}"], "--dt = 0.01 s: allowed"),
    ("simulate-speed-zero", ["simulate", "--case", CASE, "--stiffness", "{S}", "--load", "sine:100",
                             "--speed-rpm", "0", "--out", "{F}"], "--speed-rpm = 0 rpm"),
    ("simulate-speed-negative", ["simulate", "--case", CASE, "--stiffness", "{S}", "--load", "sine:100",
                                 "--speed-rpm", "-300", "--out", "{F}"], "use --backward"),
    ("simulate-load-form", ["simulate", "--case", CASE, "--stiffness", "{S}", "--load", "cubic:100",
                            "--out", "{F}"], "cubic"),
    ("simulate-duration-not-a-number", ["simulate", "--case", CASE, "--load", "sine:100", "--duration", "abc",
                                        "--out", "{F}"], "argument --duration: invalid float value: 'abc'"),
    ("simulate-unknown-option", ["simulate", "--case", CASE, "--load", "sine:100", "--out", "{F}", "--fast"],
     "unrecognized arguments: --fast"),
    ("matrix-duration-negative", ["matrix", "--case", CASE, "--stiffness", "{S}", "--duration", "-1",
                                  "--out", "{O}"], "--duration = -1 s"),
    ("matrix-scheduler-malformed", ["matrix", "--case", CASE, "--stiffness", "{S}", "--scheduler", "my-cluster",
                                    "--out", "{O}"], "--scheduler 'my-cluster'"),
    ("tolerance-limit-negative", ["tolerance", "--case", CASE, "--stiffness", "{S}", "--samples", "100",
                                  "--limit-arcsec", "-1", "--out", "{O}"], "--limit-arcsec = -1 arcsec: allowed > 0"),
    ("tolerance-samples-zero", ["tolerance", "--case", CASE, "--stiffness", "{S}", "--samples", "0",
                                "--out", "{O}"], "--samples = 0"),
    ("tolerance-band-negative", ["tolerance", "--case", CASE, "--stiffness", "{S}", "--samples", "100",
                                 "--eccentricity-um", "-2", "--out", "{O}"], "--eccentricity-um = -2"),
    ("tolerance-workers-zero", ["tolerance", "--case", CASE, "--stiffness", "{S}", "--samples", "100",
                                "--workers", "0", "--out", "{O}"], "--workers = 0"),
    ("tolerance-chunk-zero", ["tolerance", "--case", CASE, "--stiffness", "{S}", "--samples", "100",
                              "--chunk-size", "0", "--out", "{O}"], "--chunk-size = 0"),
    ("fourbar-points", ["fourbar", "--case", CASE, "--stiffness", "{S}", "--points", "2", "--out", "{O}"],
     "--points = 2"),
    ("fourbar-crank-angle", ["fourbar", "--case", CASE, "--stiffness", "{S}", "--crank-angle-deg", "180",
                             "--out", "{O}"], "--crank-angle-deg = 180"),
    ("diagnose-points-per-rev-zero", ["diagnose", "--case", CASE, "--stiffness", "{S}", "--measured", "{F}",
                                      "--points-per-rev", "0", "--out", "{O}"], "--points-per-rev = 0: allowed 82 to"),
    ("diagnose-points-per-rev-negative", ["diagnose", "--case", CASE, "--stiffness", "{S}", "--measured", "{F}",
                                          "--points-per-rev", "-5", "--out", "{O}"], "--points-per-rev = -5"),
]


@pytest.mark.parametrize("argv, words", [b[1:] for b in BAD], ids=[b[0] for b in BAD])
def test_a_bad_option_is_one_error_line_exit_2_and_the_earlier_artifact_stays(tmp_path, stiffness, argv, words):
    out = tmp_path / "out"
    out.mkdir()
    earlier = out / "earlier.csv"      # what an earlier good run left: the failed rerun may not touch it
    earlier.write_text("time_s,input_angle_deg,output_angle_deg,output_torque_Nm\n0,0,0,0\n")
    (out / "summary.json").write_text('{"an": "earlier artifact"}\n')
    before = snapshot(out)
    argv = [a.replace("{S}", str(stiffness)).replace("{O}", str(out)).replace("{F}", str(earlier))
            if isinstance(a, str) else a for a in argv]
    t0 = time.perf_counter()
    res = cli(*argv)
    wall = time.perf_counter() - t0
    errors = [line for line in res.stderr.splitlines() if line.startswith("error:")]
    assert res.returncode == 2, res.stderr[-2000:]
    assert "Traceback" not in res.stderr, res.stderr[-2000:]
    assert len(errors) == 1 and words in errors[0], res.stderr
    assert snapshot(out) == before                 # nothing written, nothing removed, no temporaries
    assert wall < 30, f"refused only after {wall:.0f} s: the check must come before the work"


def test_a_folder_that_cannot_be_written_is_refused_up_front(tmp_path, stiffness):
    ro = read_only_folder(tmp_path)
    before = snapshot(ro) if ro.parent == tmp_path else None
    for argv in (["simulate", "--case", CASE, "--stiffness", stiffness, "--load", "sine:100", "--duration", "0.1",
                  "--out", ro / "r.csv"],
                 ["geometry", "--case", CASE, "--out", ro / "geometry"],
                 ["tolerance", "--case", CASE, "--stiffness", stiffness, "--samples", "100", "--out", ro]):
        res = cli(*argv)
        errors = [line for line in res.stderr.splitlines() if line.startswith("error:")]
        assert res.returncode == 2 and "Traceback" not in res.stderr, res.stderr[-2000:]
        assert len(errors) == 1 and "cannot write in" in errors[0] and str(ro) in errors[0], res.stderr
    if before is not None:
        assert snapshot(ro) == before


def test_a_rerun_removes_the_temporaries_a_killed_run_left_and_nothing_else(tmp_path, stiffness):
    out = tmp_path / "tol"
    out.mkdir()
    stale = [".summary.k1ll3d0x.json", ".histogram.a_b_c_d_.png", ".samples.00000000.csv"]
    keep = [".gitignore", "notes.txt", ".summary.json.bak"]
    for name in stale + keep:
        (out / name).write_text("x")
    res = cli("tolerance", "--case", CASE, "--stiffness", stiffness, "--samples", "300", "--workers", "1",
              "--quiet", "--out", out)
    assert res.returncode == 0, res.stderr[-2000:]
    names = {p.name for p in out.iterdir()}
    assert not names & set(stale) and set(keep) <= names
    # simulate writes one file into a folder others may share: only its own temporaries go
    recs = tmp_path / "records"
    recs.mkdir()
    (recs / ".r.zzzzzzzz.csv").write_text("x")
    (recs / ".other.zzzzzzzz.csv").write_text("x")
    res = cli("simulate", "--case", CASE, "--stiffness", stiffness, "--load", "constant:100", "--duration", "0.1",
              "--quiet", "--out", recs / "r.csv")
    assert res.returncode == 0, res.stderr[-2000:]
    assert sorted(p.name for p in recs.iterdir()) == [".other.zzzzzzzz.csv", "r.csv"]


def test_a_run_shorter_than_the_steady_window_says_so_instead_of_a_sigma(tmp_path, stiffness):
    res = cli("simulate", "--case", CASE, "--stiffness", stiffness, "--load", "sine:200", "--duration", "0.2",
              "--out", tmp_path / "r.csv")
    assert res.returncode == 0, res.stderr[-2000:]
    assert "the window t >= 2 s is empty in a 0.2 s run" in res.stdout
    assert "TE sigma (t >= 2 s) =" not in res.stdout


@pytest.mark.parametrize("signum", [signal.SIGTERM, signal.SIGINT], ids=["SIGTERM", "SIGINT"])
def test_simulate_acts_on_a_signal_at_once_and_leaves_no_temporary(tmp_path, stiffness, start, signum):
    # the time integration returns to Python every ~0.1-0.2 s (dynamics.model: chunked kernel),
    # so the handler runs within a fraction of a second even mid-integration
    out = tmp_path / "r.csv"
    out.write_text("an earlier record\n")
    proc = start("simulate", "--case", CASE, "--stiffness", stiffness, "--load", "sine:200", "--duration", "60",
                 "--out", out)
    wait_busy(proc, cpu_s=2.0)      # imports, model and statics take ~1.2 s of CPU: then it integrates
    assert proc.poll() is None
    t0 = time.perf_counter()
    proc.send_signal(signum)
    _, err = proc.communicate(timeout=60)
    acted_s = time.perf_counter() - t0
    assert proc.returncode == 128 + signum, err[-2000:]
    assert "interrupted" in err and "Traceback" not in err
    assert acted_s < 1.0, f"acted on the signal after {acted_s:.2f} s"
    assert out.read_text() == "an earlier record\n"
    assert temps(tmp_path) == []


def test_an_interrupted_matrix_stops_at_once_and_the_rerun_computes_only_the_unfinished_cells(tmp_path, stiffness,
                                                                                              start):
    out = tmp_path / "matrix"
    argv = ["matrix", "--case", CASE, "--stiffness", stiffness, "--duration", "1.2", "--dt", "2e-4", "--out", out]
    proc = start(*argv)
    deadline = time.time() + 240

    def finished():
        return sorted(p.name for p in out.glob("*.npz") if not p.name.startswith(".")) if out.is_dir() else []

    while time.time() < deadline and len(finished()) < 2 and proc.poll() is None:
        time.sleep(0.05)
    assert proc.poll() is None, "the matrix ended before it could be interrupted"
    t0 = time.perf_counter()
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=60)
    acted_s = time.perf_counter() - t0
    assert proc.returncode == 128 + signal.SIGTERM, err[-2000:]
    assert acted_s < 1.0, f"the sweep stopped {acted_s:.2f} s after SIGTERM"
    assert temps(out) == []
    done = finished()
    assert 2 <= len(done) < 12
    stamps = {n: ((out / n).stat().st_ino, (out / n).stat().st_mtime_ns) for n in done}
    res = cli(*argv, "--quiet")
    assert res.returncode == 0, res.stderr[-2000:]
    assert len(finished()) == 12 and temps(out) == []
    assert {n: ((out / n).stat().st_ino, (out / n).stat().st_mtime_ns) for n in done} == stamps
    # a rerun with the same inputs computes nothing and writes the same bytes
    before = snapshot(out)
    again = cli(*argv)
    assert again.returncode == 0, again.stderr[-2000:]
    assert "0 cells computed, 12 reused" in again.stdout
    assert snapshot(out) == before
