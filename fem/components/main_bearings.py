"""Main bearings: the RV's built-in preloaded angular contact ball pair between carrier and housing,
ball by ball (fem.main_bearings: Hertz point contact, Jones/Harris), tangent at the rated-torque
load. Under the two discs' opposite forces the carrier tilts (and shifts) on the pair; the crank
axes, which the carrier holds, move with it relative to the housing's pins: in series in the
crank support path, B^T C_mb B, B the crank-plane forces' resultant (F_x, F_y, M_x, M_y) at the
pair centre (disc stack centred between the rows, ASSUMED as in fem.main_bearings). The output
takes torque only (the load's torque arm; a robot arm's radial loads also go through this pair)."""
from __future__ import annotations

import dataclasses as dc
from dataclasses import dataclass

import numpy as np

from fem.components.base import Result, timed

NAME = "main_bearings"
COUPLING = "support"
COST = 2


@dataclass(frozen=True)
class Entry:
    radial_stiffness_N_per_m: float
    tilt_stiffness_Nm_per_rad: float
    plane_z_m: np.ndarray          # (nd,) disc planes from the pair centre, crank axis direction


def to_json(e: Entry) -> dict:
    return {"radial_stiffness_N_per_m": float(e.radial_stiffness_N_per_m),
            "tilt_stiffness_Nm_per_rad": float(e.tilt_stiffness_Nm_per_rad), "plane_z_m": np.asarray(e.plane_z_m).tolist()}


def from_json(d: dict) -> Entry:
    return Entry(float(d["radial_stiffness_N_per_m"]), float(d["tilt_stiffness_Nm_per_rad"]),
                 np.asarray(d["plane_z_m"], float))


def plane_z_m(case) -> np.ndarray:
    """Disc planes (the eccentrics' mid-planes, geometry.solids.crankshaft_layout) from the disc
    stack's centre, m."""
    nd, w = case.cycloid.disc_count, case.cycloid.width_mm * 1e-3
    return (np.arange(nd) - (nd - 1) / 2) * w


@timed
def compute(case, ctx) -> Result:
    from fem import main_bearings as mb
    r = mb.case_main_bearings(case)
    e = Entry(r["radial_stiffness_N_per_m"], r["tilt_stiffness_Nm_per_rad"], plane_z_m(case))
    check = dict(r["check"], operating_moment_Nm=r["operating_moment_Nm"], operating_radial_N=r["operating_radial_N"],
                 tilt_rad=r["tilt_rad"], max_ball_load_N=r["max_ball_load_N"], unloaded_balls=r["unloaded_balls"])
    return Result(NAME, {"parts.main_bearings": e}, {NAME: r["source"]}, {NAME: check})


def stiffen(model, f: float):
    e = model.parts.get(NAME)
    if e is None:                       # a stiffness made without this component (in-memory tests)
        return model
    return dc.replace(model, parts=dict(model.parts, **{NAME: dc.replace(
        e, radial_stiffness_N_per_m=e.radial_stiffness_N_per_m * f, tilt_stiffness_Nm_per_rad=e.tilt_stiffness_Nm_per_rad * f)}))


def support_part(model, T: np.ndarray, n_crank: int) -> np.ndarray:
    """B^T diag(1/k_r, 1/k_r, 1/k_tilt, 1/k_tilt) B on the crank-axis displacements (crank j, plane d,
    x, y): a force F at plane z moves the carrier by F / k_r and tilts it by z F / k_tilt, which
    moves plane z' by z' z F / k_tilt (isotropic pair: the same in the carrier frame)."""
    if NAME not in model.parts:         # a stiffness made without this component: rigid
        return np.zeros((T.shape[1], T.shape[1]))
    e = model.parts[NAME]
    z = np.asarray(e.plane_z_m, float)
    nd = len(z)
    B = np.zeros((4, 2 * n_crank * nd))
    for j in range(n_crank):
        for d in range(nd):
            i = 2 * (j * nd + d)
            B[0, i], B[1, i + 1] = 1.0, 1.0             # F_x, F_y
            B[2, i + 1], B[3, i] = -z[d], z[d]           # M_x = -z F_y, M_y = z F_x
    C = np.diag([1 / e.radial_stiffness_N_per_m] * 2 + [1 / e.tilt_stiffness_Nm_per_rad] * 2)
    return B.T @ C @ B
