"""Housing: the pin ring as an elastic body, 2D plane-stress FE of the ring with its pin grooves and
mounting flange, clamped at its bolt holes (fem.housing), condensed to the pins' seat compliance
(2 zp x 2 zp: a load on one pin moves its neighbours). In the lumped model as the housing's MODES
most compliant eigenvectors of that matrix, each a DOF on its own spring with its Ritz modal mass
(dynamics.couplings.housing; the pin coupling moves each pin seat with them), and the rest of each
pin's radial compliance beyond the groove law's datum (fem.pin_groove already holds the first pin
pitch of depth), mean over the pins, in series in the pin law. The bolt pattern makes the
pin support stiffness vary around the ring (lobes at multiples of gcd(zp, n_bolts)): lines at
m zc that grow with torque."""
from __future__ import annotations

import dataclasses as dc
from dataclasses import dataclass

import numpy as np

from fem.components.base import Result, timed

NAME = "housing"
COUPLING = "housing"
ALSO = ("pin",)        # its residual (the modes left out) sits in series in the pin law
COST = 15
MODES = 8              # kept modes: see fem.housing's kept_fraction in stiffness.json checks


@dataclass(frozen=True)
class Entry:
    phi: np.ndarray                    # (2 zp, n) pin seat displacements (x, y per pin) per modal coordinate
    stiffness_N_per_m: np.ndarray      # (n,)
    mass_kg: np.ndarray                # (n,) Ritz modal masses (diagonal)
    residual_m_per_N: float            # mean radial compliance the kept modes leave out, per pin


def to_json(e: Entry) -> dict:
    return {"phi": np.asarray(e.phi).tolist(), "stiffness_N_per_m": np.asarray(e.stiffness_N_per_m).tolist(),
            "mass_kg": np.asarray(e.mass_kg).tolist(), "residual_m_per_N": float(e.residual_m_per_N)}


def from_json(d: dict) -> Entry:
    return Entry(np.asarray(d["phi"], float), np.asarray(d["stiffness_N_per_m"], float),
                 np.asarray(d["mass_kg"], float), float(d["residual_m_per_N"]))


@timed
def compute(case, ctx) -> Result:
    from fem import housing
    fe = housing.housing_for_case(case)
    hm = fe.modes(MODES)
    # in series in the pin law: the housing beyond fem.pin_groove's datum (one pin pitch deep, already
    # in the groove law: fem.housing) less what the kept modes carry; the overlap cannot be taken out of
    # the matrix pin by pin (indefinite), so the modes keep it (~10 % of a pin's radial compliance)
    modal = fe.radial_compliance_m_per_N - hm.residual_radial_m_per_N
    series = float(np.mean(np.maximum(fe.datum_radial_m_per_N - modal, 0.0)))
    e = Entry(hm.phi, hm.stiffness_N_per_m, hm.mass_kg, series)
    check = dict(fe.check, kept_modes=MODES, kept_fraction_mean=float(np.mean(hm.kept_fraction)),
                 kept_fraction_min=float(np.min(hm.kept_fraction)),
                 radial_compliance_mean_m_per_N=float(np.mean(fe.radial_compliance_m_per_N)),
                 datum_radial_mean_m_per_N=float(np.mean(fe.datum_radial_m_per_N)),
                 series_in_pin_law_m_per_N=series,
                 radial_stiffness_lobes={str(m): a for m, a in fe.radial_stiffness_lobes().items()},
                 torsion_compliance_rad_per_Nm=fe.torsion_compliance_rad_per_Nm,
                 modal_stiffness_check=hm.stiffness_check)
    return Result(NAME, {"parts.housing": e}, {NAME: fe.source + f"; {MODES} most compliant modes as DOFs, the rest "
                                                         "(mean radial) in series in the pin law"},
                  {NAME: check}, artifacts={"housing_fe": fe})


def stiffen(model, f: float):
    e = model.parts.get(NAME)
    if e is None:
        return model
    return dc.replace(model, parts=dict(model.parts, **{NAME: dc.replace(
        e, stiffness_N_per_m=e.stiffness_N_per_m * f, residual_m_per_N=e.residual_m_per_N / f)}))


def series_approach_m(model, force_N):
    e = model.parts.get(NAME)
    return np.zeros_like(np.asarray(force_N, float)) if e is None else e.residual_m_per_N * np.asarray(force_N, float)
