"""What-if (not in `make bench`): does the model make the crank sidebands of the housing's 156x line?

The real records' residual holds 159x and 162x lines (4 zc + 3, + 6: `orders.label_order` calls them
crank sidebands of 156x) growing with torque. Issue 23 asks whether the model makes such products of
two causes. This script puts the housing seat pattern (m = 4 at its 10 um/kN bound) and a crank
eccentric error (disc 1's eccentric on crank 1, 5 um) in the RV-160N case, alone and together, solves
the quasi-static TE over one output revolution at 300 and 1800 N m in both directions (1800 rpm, 25 C,
a grid of zp zc points) and prints the lines at 155, 156, 157, 159, 162, 40 and 80x.

  .venv/bin/python bench/sideband_whatif.py [--stiffness build/rv160n-81/fem/stiffness.json]
"""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from fem.stiffness import StiffnessModel  # noqa: E402
from geometry.params import load_case  # noqa: E402
import pipeline.diagnosis.simulate as S  # noqa: E402
from pipeline.diagnosis.causes.crank_eccentricity_error import CAUSE as CRANK  # noqa: E402
from pipeline.diagnosis.causes.housing_stiffness_pattern import CAUSE as HOUSING  # noqa: E402

ORDERS = (155, 156, 157, 159, 162, 40, 80)


def lines(case, stiffness, torque, direction, n) -> np.ndarray:
    ang = S.periodic_grid_deg(case, n, direction)
    te = S.quasi_static_te(case, stiffness, ang, torque, direction, S.Condition(1800.0, 25.0))
    return np.abs(np.fft.rfft(te - te.mean())) / n * 2.0


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--case", default=str(ROOT / "cases" / "rv160n-81.toml"))
    ap.add_argument("--stiffness", default=str(ROOT / "build" / "rv160n-81" / "fem" / "stiffness.json"))
    args = ap.parse_args(argv)
    if not Path(args.stiffness).is_file():
        print(f"sideband_whatif: {args.stiffness} not found: run `make all` first", file=sys.stderr)
        return 2
    case = load_case(args.case)
    stiffness = StiffnessModel.from_json(json.loads(Path(args.stiffness).read_text()))
    n = case.cycloid.zp * (case.cycloid.zp - 1)          # stroboscopic: the mesh ripple folds onto the mean
    ph = np.zeros(len(HOUSING.params(case)))
    ph[2] = HOUSING.bound                                 # m = 4 cos at its bound
    pc = np.zeros(len(CRANK.params(case)))
    pc[0] = 5.0                                           # crank 1, 5 um
    models = {"as given": (case, stiffness), "housing": HOUSING.apply(case, stiffness, ph),
              "crank": CRANK.apply(case, stiffness, pc)}
    models["both"] = CRANK.apply(*models["housing"], pc)
    print("arcsec at orders " + " ".join(f"{k}x" for k in ORDERS))
    for torque in (300.0, 1800.0):
        for d in (1, -1):
            for name, (c, s) in models.items():
                a = lines(c, s, torque, d, n)
                print(f"{torque:6.0f} N m {'fw' if d > 0 else 'bw'} {name:9s} " + " ".join(f"{a[k]:6.3f}" for k in ORDERS))
    return 0


if __name__ == "__main__":
    sys.exit(main())
