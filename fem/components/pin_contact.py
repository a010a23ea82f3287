"""Cycloid tooth against pin: 2D plane-strain FE of the tooth pair, condensed frictionless contact,
at P pin phases x L loads (fem.pin_contact); the base law of the pin coupling, every other pin
component in series with it."""
from __future__ import annotations

import dataclasses as dc

import numpy as np

from fem import pin_contact
from fem.components.base import Result, timed

NAME = "pin_contact"
COUPLING = "pin"
COST = 30


@timed
def compute(case, ctx) -> Result:
    from fem.components.entries import PinContact
    tm = pin_contact.tooth_pair_map(case, positions_deg=ctx["positions_deg"], loads_N=ctx["loads"]["pin"],
                                    mesh_size_m=ctx["mesh_size_m"])
    rated = pin_contact.contact_force_at_torque(case, case.rated_torque_Nm)
    d_rated = (rated / tm.law_k_N_per_m_pow) ** (1 / tm.law_n)    # secant tooth stiffness at the rated pin force
    p_ratio, b_ratio = tm.peak_pressure_Pa / tm.hertz_peak_pressure_Pa, tm.half_width_m / tm.hertz_half_width_m
    law_err = np.abs(tm.law_k_N_per_m_pow[:, None] * tm.approach_m ** tm.law_n[:, None] / tm.load_N[None, :] - 1)
    return Result(NAME, {"pin_contact": PinContact(tm.position_deg, tm.load_N, tm.approach_m, tm.peak_pressure_Pa,
                                                  tm.half_width_m, tm.law_k_N_per_m_pow, tm.law_n)},
                  {NAME: "2D plane-strain FE (P1, scikit-fem), condensed frictionless contact, modified profile, "
                         "pin back half on a rigid seat; load levels: load_ranges"},
                  {NAME: {"fe_over_hertz_peak_pressure": [float(p_ratio.min()), float(p_ratio.max())],
                          "fe_over_hertz_half_width": [float(b_ratio.min()), float(b_ratio.max())],
                          "power_law_max_error": float(law_err.max())}},
                  extras={"mesh_size_at_contact_m": tm.mesh_size_m,
                          "disc_mesh_nodes": int(len(tm.disc_mesh.points)),
                          "hertz_peak_pressure_Pa": tm.hertz_peak_pressure_Pa.tolist(),
                          "hertz_half_width_m": tm.hertz_half_width_m.tolist(),
                          "profile_curvature_radius_m": tm.curvature_radius_m.tolist(),
                          "rated_pin_force_N": rated,
                          "tooth_secant_stiffness_at_rated_N_per_m": (rated / d_rated).tolist()},
                  artifacts={"tooth_map": tm})


def stiffen(model, f: float):
    pc = model.pin_contact
    return dc.replace(model, pin_contact=dc.replace(pc, approach_m=pc.approach_m / f,
                                                    law_k_N_per_m_pow=pc.law_k_N_per_m_pow * f ** pc.law_n))


def tangent_m_per_N(force_N, law_k, law_n):
    """d(approach)/dF of the tooth-pair law F = k a^n at force F."""
    F = np.maximum(np.asarray(force_N, float), 1e-9)
    return F ** (1.0 / law_n - 1.0) / (law_n * law_k ** (1.0 / law_n))
