"""`sensitivity`: the catalog test's rigidity against each size of the case (pipeline.sensitivity).

  python -m pipeline sensitivity --case CASE.toml --out DIR [--only NAME,...] [--band 0.25]
                                 [--workers N | --scheduler ADDRESS]

Every variant (and the unchanged case, `base`) is a folder DIR/variants/<name>/, owned by this
command, holding its case file and the stages' outputs (geometry, mesh, fem, hysteresis), made by
the same commands `make` runs. A rerun resumes: a variant whose case text and stage code (code_fingerprint) are unchanged and
whose hysteresis.json exists is read, not recomputed; one whose text or code changed is recomputed
from scratch. Variants run side by side on local processes or a Dask cluster (pipeline.sweep), each
one process chain; DIR must be on a file system the Dask workers share.
"""
from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

from geometry.artifacts import write_json_atomic, write_text_atomic
from pipeline.sensitivity import SensitivityError

RUN_STAGES = ("geometry", "mesh", "fem", "hysteresis")   # _stage_commands' order (a test holds it)


def register(sub) -> None:
    from pipeline.sensitivity import VARIANTS
    p = sub.add_parser("sensitivity", help="rigidity against each size of the case")
    p.add_argument("--case", required=True)
    p.add_argument("--out", required=True)
    p.add_argument("--only", default=None,
                   help="comma-separated variants (default all: " + ", ".join(v.name for v in VARIANTS) + ")")
    p.add_argument("--band", type=float, default=0.25,
                   help="relative band around the case's reference rigidity (default 0.25)")
    p.add_argument("--workers", type=int, default=None, help="local processes (default: the cores)")
    p.add_argument("--scheduler", default=None, help="Dask scheduler address tcp://HOST:PORT")
    p.add_argument("--quiet", action="store_true")
    p.set_defaults(func=run)


def _stage_commands(case: Path, folder: Path) -> list[list[str]]:
    py = [sys.executable, "-m", "pipeline"]
    return [py + ["geometry", "--case", str(case), "--out", str(folder / "geometry"), "--quiet"],
            py + ["mesh", "--case", str(case), "--out", str(folder / "mesh"), "--quiet"],
            py + ["fem", "--case", str(case), "--mesh", str(folder / "mesh"), "--out", str(folder / "fem"),
                  "--quiet"],
            py + ["hysteresis", "--case", str(case), "--stiffness", str(folder / "fem" / "stiffness.json"),
                  "--out", str(folder / "hysteresis"), "--quiet"]]


def code_fingerprint() -> str:
    """sha256 over the source files the stage commands run (pipeline.deps import walk; not this
    command's own, whose table is re-derived on every run): a variant made by other stage code is
    recomputed, and the report flags a table made by other stage code."""
    import hashlib
    from pipeline import deps
    from geometry.fingerprint import file_fingerprint
    files = sorted(set().union(*(deps.stage_files(s) for s in RUN_STAGES)))
    h = hashlib.sha256()
    for f in files:
        h.update(f"{f}:{file_fingerprint(deps.ROOT / f)}\n".encode())
    return h.hexdigest()


def run_variant(text: str, folder: str, code: str = "") -> dict:
    """One variant through geometry -> mesh -> fem -> hysteresis in `folder` (resumed when its case
    text and the stages' code are unchanged); its figures, or {'error': the failing stage's last line}."""
    folder = Path(folder)
    case, stamp = folder / "case.toml", folder / "code.txt"
    result = folder / "hysteresis" / "hysteresis.json"
    if not (case.exists() and case.read_text() == text and stamp.exists() and stamp.read_text() == code
            and result.exists()):
        shutil.rmtree(folder, ignore_errors=True)   # another case text or code: nothing old is kept
        folder.mkdir(parents=True, exist_ok=True)
        write_text_atomic(case, text)
        # one BLAS thread per stage process, as `make` exports: runs go side by side on the cores
        env = {"OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", **os.environ}
        for cmd in _stage_commands(case, folder):
            r = subprocess.run(cmd, capture_output=True, text=True, env=env)
            if r.returncode:
                last = (r.stderr.strip().splitlines() or [f"exit {r.returncode}"])[-1]
                return {"error": f"{cmd[3]}: {last}"}
        write_text_atomic(stamp, code)               # last: an interrupted variant is redone
    h = json.loads(result.read_text())
    stiff = json.loads((folder / "fem" / "stiffness.json").read_text())
    return {"rigidity": h["torsional_rigidity_Nm_per_arcmin"], "lost_motion": h["lost_motion_arcmin"],
            "budget": h.get("compliance_budget", {}),
            "bearing": stiff.get("support_bearings", {}).get("designation")}


def _selected(only: str | None):
    from pipeline.sensitivity import BY_NAME, VARIANTS
    if only is None:
        return list(VARIANTS)
    names = [n.strip() for n in only.split(",") if n.strip()]
    bad = [n for n in names if n not in BY_NAME]
    if bad or not names:
        raise SensitivityError(f"--only {only!r}: allowed comma-separated variants among "
                                  f"{', '.join(BY_NAME)}")
    return [BY_NAME[n] for n in names]


def run(args) -> int:
    from geometry.fingerprint import made_from
    from geometry.params import load_case
    from pipeline import checks
    from pipeline.sensitivity import case_value, edited, is_assumed, markdown, renamed, summarise
    from pipeline.sweep import check_scheduler, run_tasks
    variants = _selected(args.only)
    checks.number_in("--band", args.band, 0.0, 0.9, lo_open=True)
    if args.workers is not None:
        checks.int_in("--workers", args.workers, 1, 64)
    check_scheduler(args.scheduler)
    case = load_case(args.case)
    text = Path(args.case).read_text(encoding="utf-8-sig")
    out = Path(args.out)
    code = code_fingerprint()
    tasks, meta = [(renamed(text, f"{case.name}-base"), str(out / "variants" / "base"), code)], {}
    for v in variants:
        vtext, edits = edited(text, v, f"{case.name}-{v.name}")
        s = v.size
        meta[v.name] = {"edits": edits, "assumed": is_assumed(case_value(text, s.section, s.key)[1])}
        tasks.append((vtext, str(out / "variants" / v.name), code))

    def progress(done, total):
        if not args.quiet:
            print(f"  {done}/{total} runs", flush=True)
    results = run_tasks(run_variant, tasks, workers=args.workers, scheduler=args.scheduler,
                        progress=progress)
    base = results[0]
    if "error" in base:
        raise SensitivityError(f"--case {args.case}: the unchanged case failed ({base['error']})")
    runs = {v.name: {**meta[v.name], **r} for v, r in zip(variants, results[1:])}
    table = summarise(base, runs, case.operation.reference_rigidity_Nm_per_arcmin, args.band)
    table.update(case=case.name, case_source=str(args.case),
                 base_bearing=base.get("bearing"),
                 noise="the crankshaft tet mesh is remade per run (fTetWild): up to ~0.5 % on the rigidity",
                 code_fingerprint=code,
                 made_from=made_from(case, "rv-sensitivity/1").to_json())
    write_json_atomic(out / "sensitivity.json", table)
    md = markdown(table, case.name)
    write_text_atomic(out / "sensitivity.md", md)
    if not args.quiet:
        print(md)
    return 0
