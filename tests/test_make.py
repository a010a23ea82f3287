"""Make rebuilds exactly what changed: each stage's rule lists the code its command can import
(pipeline/deps.py), cases are found by their `name` wherever the file lies, and a rebuild follows
the case's content fingerprint, not its file. Make runs with BUILD in a temporary folder and `-o`
on the venv stamp, so nothing here touches build/ or reinstalls anything."""
import json
import os
import re
import shutil
import subprocess
import sys
import time
from modulefinder import ModuleFinder
from pathlib import Path

import pytest

from pipeline import deps
from support import case_path, stiffness_for_tests

ROOT = Path(__file__).resolve().parents[1]
MAKE = shutil.which("make")
pytestmark = pytest.mark.skipif(MAKE is None, reason="GNU make not installed")

TARGETS = {"geometry": "geometry/profile.csv", "mesh": "mesh/crankshaft_mesh.npz", "fem": "fem/stiffness.json",
           "matrix": "matrix/te_std.csv", "hysteresis": "hysteresis/hysteresis.json",
           "fourbar": "fourbar/comparison.md", "tolerance": "tolerance/summary.json",
           "signatures": "signatures/signatures.json",
           "diagnosis": "diagnosis/diagnosis.json", "paper001": "diagnosis/paper001.json",
           "report": "report/index.html", "sensitivity": "sensitivity/sensitivity.json"}


def make(build: Path, *args: str, check: bool = True) -> subprocess.CompletedProcess:
    r = subprocess.run([MAKE, "-C", str(ROOT), f"BUILD={build}", f"PY={sys.executable}", "-o", ".venv/.installed",
                        "--no-print-directory", *args], capture_output=True, text=True, timeout=600)
    if check and r.returncode:
        raise AssertionError(f"make {' '.join(args)} -> {r.returncode}\n{r.stdout}\n{r.stderr}")
    return r


def copy_case(folder: Path, name: str = "my-rv", *edits, file: str = "my.toml") -> Path:
    """rv40e-81 as another file somewhere else, named `name`, with text edits (old, new)."""
    text = case_path("rv40e-81").read_text().replace('name = "rv40e-81"', f'name = "{name}"')
    for old, new in edits:
        assert old in text, old
        text = text.replace(old, new)
    folder.mkdir(parents=True, exist_ok=True)
    (folder / file).write_text(text)
    return folder / file


# ----------------------------------------------------------------------- stage sources from imports
def _rule_prerequisites(database: str, build: Path, target: str) -> set[str]:
    # make prints its database once per reading; the last one is after the generated makefiles
    found = re.findall(rf"^{re.escape(str(build))}/%/{re.escape(target)}:(.*)$", database, re.M)
    assert found, f"no pattern rule for {target} in make's database"
    return set(found[-1].split("|")[0].split())


@pytest.fixture(scope="module")
def database(tmp_path_factory):
    build = tmp_path_factory.mktemp("build")
    return build, make(build, "-p", "-n", "all").stdout


@pytest.mark.parametrize("stage", sorted(set(TARGETS) & set(deps.STAGES)))
def test_each_stage_rule_depends_on_every_file_its_command_can_import(database, stage):
    build, db = database
    need = set(deps.stage_files(stage))
    assert {"pipeline/__main__.py", "pipeline/cli.py", "geometry/params.py"} <= need
    missing = need - _rule_prerequisites(db, build, TARGETS[stage])
    assert not missing, f"make's {stage} rule misses {sorted(missing)}"


def test_the_drift_of_issue_10_is_gone_and_the_mesh_ignores_the_solvers(database):
    build, db = database
    # the tolerance Monte Carlo runs the dynamics model (lazy imports): its rule lists that code
    assert {"dynamics/model.py", "dynamics/kernels.py", "dynamics/fourbar.py"} <= _rule_prerequisites(
        db, build, TARGETS["tolerance"])
    # the mesh command reaches the crankshaft solid and the mesher, not the FE contact solvers of
    # the same module: a solver change must not remake the (non-reproducible) tet mesh
    mesh = _rule_prerequisites(db, build, TARGETS["mesh"])
    assert {"fem/shaft.py", "fem/mesh.py", "geometry/solids.py"} <= mesh
    assert "fem/pin_contact.py" not in mesh and "fem/pin_contact.py" in _rule_prerequisites(db, build, TARGETS["fem"])
    # the sensitivity study runs the stages as subprocesses (no import reaches them): their code too
    assert {"geometry/solids.py", "fem/carrier.py", "fem/tapered_roller.py", "dynamics/budget.py"} <= \
        _rule_prerequisites(db, build, TARGETS["sensitivity"])
    # the records a diagnosis reads are prerequisites too (secondary expansion)
    assert "$(RECORDS_$*)" in _rule_prerequisites(db, build, TARGETS["diagnosis"])


@pytest.mark.parametrize("module", ["pipeline.cmd_fourbar", "pipeline.cmd_dynamics", "pipeline.cmd_fem",
                                    "pipeline.cmd_diagnose", "pipeline.cmd_report"])
def test_the_import_walk_finds_what_pythons_module_finder_finds(module):
    # an independent reader (bytecode of every code object, lazy imports included) over the project
    finder = ModuleFinder(path=[str(ROOT)])
    finder.import_hook(module)
    found = {n for n, m in finder.modules.items() if m.__file__ and Path(m.__file__).is_relative_to(ROOT)}
    walk = deps.closure({module})
    # beyond import statements, the walk follows registries' import_module(f"{__name__}.x") calls
    registries = set().union(*(deps.dynamic_imports(m) for m in walk))
    assert walk == found | deps.closure(registries)


def test_a_registry_loads_at_run_time_no_module_the_walk_missed():
    registries = [m for m in deps.closure(set(deps.ENTRY) | {s.split(":")[0] for s in deps.STAGES.values()})
                  if deps.dynamic_imports(m) and m not in deps.DYNAMIC_OK]
    for module in registries:
        code = (f"import json, sys, {module}\n"
                f"pkgs = {tuple(f'{ROOT}/{p}/' for p in deps.PACKAGES)!r}\n"
                "print(json.dumps(sorted(m.__file__ for m in list(sys.modules.values())"
                " if (getattr(m, '__file__', None) or '').startswith(pkgs))))\n")
        r = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=300)
        assert r.returncode == 0, r.stderr
        loaded = {str(Path(f).relative_to(ROOT)) for f in json.loads(r.stdout.splitlines()[-1])}
        walked = {str(deps.module_file(m).relative_to(ROOT)) for m in deps.closure({module})}
        assert loaded <= walked, f"{module} loads {sorted(loaded - walked)} that the walk missed"


def test_the_import_walk_follows_lazy_imports_and_skips_registered_stages(tmp_path):
    pkg = tmp_path / "pipeline"
    pkg.mkdir()
    (pkg / "__init__.py").write_text("")
    (pkg / "a.py").write_text("def run(args):\n    from pipeline import b\n    return helper()\n"
                              "def helper():\n    import pipeline.c\n"
                              "def other(args):\n    import pipeline.d\n"
                              "def register(sub):\n    sub.set_defaults(func=run)\n    sub.set_defaults(func=other)\n")
    for name in "bcd":
        (pkg / f"{name}.py").write_text("")
    assert deps.entry_imports("pipeline.a", ("run", "register"), tmp_path) == {"pipeline", "pipeline.b",
                                                                              "pipeline.c"}
    assert deps.entry_imports("pipeline.a", ("other", "register"), tmp_path) == {"pipeline.d"}
    with pytest.raises(deps.DepsError, match="no function gone"):
        deps.entry_imports("pipeline.a", ("gone",), tmp_path)
    reg = pkg / "reg"
    reg.mkdir()
    (reg / "__init__.py").write_text("from importlib import import_module\n"
                                     "ALL = [import_module(f'{__name__}.{m}') for m in ('x',)]\n")
    (reg / "x.py").write_text("")
    (reg / "y.py").write_text("")
    assert deps.closure({"pipeline.reg"}, tmp_path) == {"pipeline", "pipeline.reg", "pipeline.reg.x", "pipeline.reg.y"}
    (pkg / "e.py").write_text("import importlib\ndef f(n):\n    return importlib.import_module(n)\n")
    with pytest.raises(deps.DepsError, match=r"pipeline.e \(line 3\): import_module\(\) with a computed name"):
        deps.closure({"pipeline.e"}, tmp_path)


def _modules_loaded_by(args: list[str]) -> set[str]:
    """Project files a real `python -m pipeline ARGS` run has imported by its exit."""
    code = ("import atexit, json, runpy, sys\n"
            f"root = {str(ROOT)!r}\n"
            f"pkgs = {tuple(f'{ROOT}/{p}/' for p in deps.PACKAGES)!r}\n"
            "atexit.register(lambda: print('LOADED=' + json.dumps(sorted(m.__file__ for m in list(sys.modules.values())"
            " if (getattr(m, '__file__', None) or '').startswith(pkgs)))))\n"
            f"sys.argv = ['pipeline', *{args!r}]\n"
            "runpy.run_module('pipeline', run_name='__main__', alter_sys=True)\n")
    r = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=600,
                       env={**os.environ, "MPLBACKEND": "Agg", "PYVISTA_OFF_SCREEN": "true"})
    assert r.returncode == 0, r.stderr
    line = next(ln for ln in r.stdout.splitlines() if ln.startswith("LOADED="))
    return {str(Path(p).relative_to(ROOT)) for p in json.loads(line[len("LOADED="):])}


def test_a_real_run_imports_nothing_outside_its_stage_sources(tmp_path):
    loaded = _modules_loaded_by(["report", "--case", str(case_path("rv40e-81")), "--build", str(tmp_path), "--quiet"])
    assert "pipeline/report.py" in loaded and not loaded - set(deps.stage_files("report"))
    from fem.stiffness import save
    from geometry.params import load_case
    save(stiffness_for_tests(load_case(case_path("rv40e-81"))), tmp_path / "stiffness.json")
    loaded = _modules_loaded_by(["simulate", "--case", str(case_path("rv40e-81")), "--stiffness",
                                 str(tmp_path / "stiffness.json"), "--load", "constant:100", "--duration", "0.002",
                                 "--out", str(tmp_path / "r.csv"), "--quiet"])
    assert "dynamics/model.py" in loaded and not loaded - set(deps.stage_files("simulate"))


# ------------------------------------------------------------------------ cases anywhere, by name
def test_a_case_file_anywhere_builds_under_its_name(tmp_path):
    case = copy_case(tmp_path / "elsewhere", "my-rv")
    out = make(tmp_path / "build", "-n", "all", f"CASE={case}").stdout
    b = tmp_path / "build" / "my-rv"
    for cmd in (f"pipeline geometry --case {case} --out {b}/geometry",
                f"pipeline fem --case {case} --mesh {b}/mesh --out {b}/fem",
                f"pipeline tolerance --case {case} --stiffness {b}/fem/stiffness.json",
                f"pipeline report --case {case} --build {tmp_path / 'build'}"):
        assert cmd in out, cmd
    assert "No rule to make target" not in out and "/my/" not in out
    assert (b / ".case-fingerprint").read_text().strip() == _fingerprint(case)


def test_two_case_files_with_one_name_are_refused_and_a_missing_file_is_named(tmp_path):
    a = copy_case(tmp_path / "a", "twin")
    b = copy_case(tmp_path / "b", "twin", ("rated_torque_Nm = 412.0", "rated_torque_Nm = 400.0"))
    r = make(tmp_path / "build", "-n", "all", f"CASE={a} {b}", check=False)
    assert r.returncode and "two case files are named 'twin'" in r.stderr
    r = make(tmp_path / "build", "-n", "all", f"CASE={tmp_path / 'none.toml'}", check=False)
    assert r.returncode and f"case file {tmp_path / 'none.toml'} not found" in r.stderr


def _fingerprint(path: Path) -> str:
    from geometry.fingerprint import case_fingerprint
    from geometry.params import load_case
    return case_fingerprint(load_case(path))


def test_a_rebuild_follows_the_case_content_not_its_file(tmp_path):
    build = tmp_path / "build"
    case = copy_case(tmp_path / "c", "my-rv")
    target = build / "my-rv" / TARGETS["geometry"]
    make(build, "-n", str(target), f"CASE={case}")          # writes the fingerprint (a `+` line)
    stamp = build / "my-rv" / ".case-fingerprint"
    old = time.time() - 60
    os.utime(stamp, (old, old))
    target.parent.mkdir(parents=True)
    target.write_text("stand-in for the geometry stage's output\n")   # newer than stamp and sources

    def reruns(case_file: Path) -> bool:
        return f"pipeline geometry --case {case_file}" in make(build, "-n", str(target), f"CASE={case_file}").stdout

    assert not reruns(case)
    case.write_text(case.read_text().replace("# paper 000: crank eccentricity e", "# e, reworded"))
    assert not reruns(case) and stamp.stat().st_mtime == pytest.approx(old)   # a comment: nothing
    twin = copy_case(tmp_path / "twin", "my-rv", ("eccentricity_mm = 1.3 ", "eccentricity_mm = 1.0 "))
    assert reruns(twin)                       # same name, other content: the stamp changed
    assert stamp.read_text().strip() == _fingerprint(twin)


@pytest.mark.slow
def test_one_real_stage_runs_for_a_case_outside_cases_and_is_then_up_to_date(tmp_path):
    build = tmp_path / "build"
    case = copy_case(tmp_path / "elsewhere", "my-rv")
    make(build, "stage-geometry", f"CASE={case}", "Q=--quiet")
    assert (build / "my-rv" / "geometry" / "profile.csv").stat().st_size > 0
    assert not (build / "my").exists()
    again = make(build, "-n", "stage-geometry", f"CASE={case}").stdout
    assert "pipeline geometry" not in again and "pipeline.deps fingerprint" in again
