"""Where the 8 real records' diagnosis spends its time: a timeline of its phases (not in `make bench`).

Runs `python -m pipeline diagnose` in-process on the records of ../shared/measured as `make all` runs
it (the 800 N.m pair held out, 2 workers) with the diagnosis' phase functions wrapped by a timer, and
prints one line per phase call (start -> end, seconds from the start) and each fit's Jacobian re-takes
(how many columns, how long, how far each re-taken block moved in units of its difference step: the
REUSE_SHARE rule re-takes them all when any block moved more than half a step). Issue 23 asks for the
whole in <= 60 s on 2 cores; bench/README says what the phases cost on the sessions' machines.

  .venv/bin/python bench/diagnose_phases.py [--measured ../shared/measured] [--out /tmp/diagnose_phases]
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import pipeline.diagnosis.diagnose as D  # noqa: E402
import pipeline.diagnosis.extension as X  # noqa: E402
import pipeline.diagnosis.report as R  # noqa: E402

PHASES = ((D, ("_library", "match", "unexplained", "gap_shape_notes", "frame_shifts", "_line_directions")),
          (X, ("_fit", "_verdicts", "_gains", "_parameters")),
          (R, ("write_report",)))


def _timed(mod, name, t0, log):
    f = getattr(mod, name)

    def g(*a, **k):
        t = time.perf_counter()
        r = f(*a, **k)
        log(f"{name}: {t - t0:.1f} -> {time.perf_counter() - t0:.1f} s ({time.perf_counter() - t:.1f} s)")
        return r
    setattr(mod, name, g)


def _timed_jacobian(t0, log):
    inner_make = X._jacobian

    def make(fun, J, spans, model_at=None, tag=(), prefetch=None):
        inner, prev = inner_make(fun, J, spans, model_at, tag, prefetch), {}

        def jac(x):
            t = time.perf_counter()
            out = inner(x)
            moved = ("" if "x" not in prev else " moved/step " + " ".join(
                f"{np.max(np.abs(x[k:k + q] - prev['x'][k:k + q])) / h:.2f}" for k, q, h in spans))
            log(f"  re-take at {t - t0:.1f} s: {sum(q for _, q, _ in spans)} columns, "
                f"{time.perf_counter() - t:.1f} s{moved}")
            prev["x"] = x.copy()
            return out
        return jac
    X._jacobian = make


def _timed_steps(t0, log):
    """Log each accepted step of the fits (the solver's callback): evaluations so far, cost, whether
    the step counts as significant past the budget (extension._Budget)."""
    inner = X._Budget.callback

    def callback(self, intermediate_result):
        prev = self.cost
        try:
            inner(self, intermediate_result)
        finally:
            r = intermediate_result
            drop = "" if prev is None else f", drop {(prev - float(r.cost)) / prev:.2e} of the cost"
            log(f"  step at {time.perf_counter() - t0:.1f} s: {r.nfev} evaluations, cost {float(r.cost):.6g}"
                f"{drop}, significant {self.significant}")
    X._Budget.callback = callback


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--measured", default=str(ROOT.parent / "shared" / "measured"))
    ap.add_argument("--out", default="/tmp/diagnose_phases")
    args = ap.parse_args(argv)
    m = Path(args.measured)
    fit = [m / f"rv160n_1800rpm_{t}Nm_25C_{d}.csv" for t in (0, 1800, 300) for d in ("bw", "fw")]
    held = [m / f"rv160n_1800rpm_800Nm_25C_{d}.csv" for d in ("bw", "fw")]
    missing = [str(p) for p in fit + held if not p.is_file()]
    if missing:
        print(f"diagnose_phases: {missing[0]} not found: the real records live in ../shared/measured",
              file=sys.stderr)
        return 2
    t0 = time.perf_counter()

    def log(text):
        print(text, flush=True)
    for mod, names in PHASES:
        for name in names:
            _timed(mod, name, t0, log)
    _timed_jacobian(t0, log)
    _timed_steps(t0, log)
    from pipeline.cli import main as cli
    rc = cli(["diagnose", "--case", str(ROOT / "cases" / "rv160n-81.toml"),
              "--stiffness", str(ROOT / "build" / "rv160n-81" / "fem" / "stiffness.json"),
              "--measured", *map(str, fit), "--holdout", *map(str, held), "--out", args.out, "--quiet"])
    log(f"total {time.perf_counter() - t0:.1f} s (rc {rc})")
    return rc


if __name__ == "__main__":
    sys.exit(main())
