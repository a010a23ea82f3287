"""The housing picture (fem.housing): `housing_png(case, path)` and `python -m pipeline.housing_figure`.

Von Mises and the deformed section under the rated-torque pin forces of one disc (classical sharing),
a zoom on the most loaded grooves with the mesh, and the per-pin radial stiffness around the ring.
"""
from __future__ import annotations

import argparse
import sys

import numpy as np

from fem import housing
from pipeline import figures


def housing_png(case, path, fe=None) -> None:
    fe = fe or housing.housing_for_case(case, checks=False)
    g = fe.geometry
    F = housing.rated_disc_loads_N(case)
    fld = housing.field_under(fe, F)
    a = g.pin_angles_rad()
    pins = g.pin_circle_radius_m * np.column_stack([np.cos(a), np.sin(a)])
    figures.housing_section(path, fe.mesh.mesh.points, fe.mesh.mesh.triangles, fld["displacement_m"],
                            fld["von_mises_Pa"], pins, F, g.bolt_centres_m(), g.bolt_hole_radius_m,
                            1 / fe.radial_compliance_m_per_N, fe.radial_stiffness_lobes(4),
                            title=f"{case.name}: housing section at rated torque {case.rated_torque_Nm:g} N m "
                                  f"(disc 1, crank angle 0), {g.bolt_count} bolts, {fe.dofs} DOFs",
                            datum_stiffness_N_per_m=1 / fe.datum_radial_m_per_N)


def main(argv=None) -> int:
    from geometry.params import load_case
    from geometry.artifacts import InputError
    ap = argparse.ArgumentParser(prog="python -m pipeline.housing_figure", description=__doc__.splitlines()[0])
    ap.add_argument("--case", required=True)
    ap.add_argument("--out", required=True, help="PNG path")
    args = ap.parse_args(argv)
    try:
        housing_png(load_case(args.case), args.out)
    except InputError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
