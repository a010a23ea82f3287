"""The signature library: each error source alone, at unit size, through the model.

A cause is a set of model parameters p (zero = the case as given) and `apply(case, stiffness, p)`
returning the perturbed case and stiffness. Its signature on a record is the model's TE change per
unit parameter, (TE(p = u e_j) - TE(0)) / u, at that record's angles, torque and direction, so the
orders, harmonic pattern, load and direction dependence all come from the model, not a table.

Causes and their parameters (DESIGN.md ids):
  output_coaxiality         (e cos phi, e sin phi) [um]: the mounting offset e at phase phi, read by
                            the output encoder as e/r sin(theta_out + phi) (dynamics.model)
  crank_eccentricity_error  per-crank eccentricity error [um] (Errors.crank_eccentricity_um)
  crank_hole_position_error per-crank crank-hole position error [um] (Errors.crank_hole_position_um):
                            shares the zp x line with the one above; kept so the overlap is shown
  torsional_stiffness       kappa = 1/c - 1, c the factor on every FE stiffness (deflections at equal load
                            scale by 1/c, so TE is near linear in kappa; power-law contacts
                            F = k d^n get k c^n)
  backlash                  extra pin clearance [um] on the equidistant modification dRr (> 0 opens
                            backlash); reported as lost motion in arcmin via the model's own ratio
Unit sizes are small against tolerances (1 um, 5 % stiffness): the library is a linearisation;
extension.py refits on the full model.
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Callable

import numpy as np

from pipeline.diagnosis.orders import spectrum_of


def _per_crank(case, key: str, delta: np.ndarray) -> tuple:
    base = np.asarray(getattr(case.errors, key), float)
    base = np.broadcast_to(base, (case.carrier.crank_count,)) if base.size == 1 else base
    return tuple(float(v) for v in base + delta)


def _coaxiality(case, stiffness, p):
    e0, ph0 = case.errors.output_coaxiality_um, np.radians(case.errors.output_coaxiality_phase_deg)
    v = e0 * np.exp(1j * ph0) + complex(p[0], p[1])
    return case.with_errors(output_coaxiality_um=float(abs(v)),
                            output_coaxiality_phase_deg=float(np.degrees(np.angle(v)))), stiffness


def _crank_ecc(case, stiffness, p):
    return case.with_errors(crank_eccentricity_um=_per_crank(case, "crank_eccentricity_um", p)), stiffness


def _crank_hole(case, stiffness, p):
    return case.with_errors(crank_hole_position_um=_per_crank(case, "crank_hole_position_um", p)), stiffness


def scale_stiffness(stiffness, factor: float):
    """Every FE stiffness times `factor` (deflection at equal load / factor)."""
    if factor <= 0:
        raise ValueError(f"stiffness factor {factor}: must be > 0")
    pc, ta = stiffness.pin_contact, stiffness.turning_arm
    pc2 = dataclasses.replace(pc, approach_m=pc.approach_m / factor,
                              law_k_N_per_m_pow=pc.law_k_N_per_m_pow * factor ** pc.law_n)
    ta2 = dataclasses.replace(ta, deflection_m=ta.deflection_m / factor,
                              law_k_N_per_m_pow=ta.law_k_N_per_m_pow * factor ** ta.law_n)
    return dataclasses.replace(
        stiffness, pin_contact=pc2, turning_arm=ta2,
        crankshaft_bending_stiffness_N_per_m=stiffness.crankshaft_bending_stiffness_N_per_m * factor,
        crankshaft_torsional_stiffness_Nm_per_rad=stiffness.crankshaft_torsional_stiffness_Nm_per_rad * factor,
        support_bearing_radial_stiffness_N_per_m=stiffness.support_bearing_radial_stiffness_N_per_m * factor,
        involute_mesh_mean_stiffness_N_per_m=stiffness.involute_mesh_mean_stiffness_N_per_m * factor)


def _stiffness(case, stiffness, p):
    return case, scale_stiffness(stiffness, 1.0 / (1.0 + float(p[0])))


def _backlash(case, stiffness, p):
    m = case.modification
    return case.replace("modification", equidistant_mm=m.equidistant_mm + float(p[0]) * 1e-3), stiffness


@dataclass(frozen=True)
class CauseSpec:
    cause: str
    params: tuple[str, ...]
    unit: float                                  # finite-difference step, parameter units
    apply: Callable                              # (case, stiffness, p) -> (case, stiffness)
    mechanism: str                               # one line for the report


def cause_specs(case) -> tuple[CauseSpec, ...]:
    n = case.carrier.crank_count
    return (
        CauseSpec("output_coaxiality", ("coaxiality_cos_um", "coaxiality_sin_um"), 1.0, _coaxiality,
                  "output mounted off-axis: the output encoder reads e/r sin(theta + phi)"),
        CauseSpec("crank_eccentricity_error", tuple(f"crank{j + 1}_eccentricity_error_um" for j in range(n)),
                  1.0, _crank_ecc, "crank eccentric radius differs from nominal"),
        CauseSpec("crank_hole_position_error", tuple(f"crank{j + 1}_hole_position_error_um" for j in range(n)),
                  1.0, _crank_hole, "crank hole of the disc off its nominal position"),
        CauseSpec("torsional_stiffness", ("compliance_factor_minus_1",), 0.05, _stiffness,
                  "the reducer is stiffer or softer than the FE model says"),
        CauseSpec("backlash", ("pin_clearance_um",), 2.0, _backlash,
                  "more clearance between disc teeth and pins: lost motion at reversal"),
    )


def signature_columns(te_of: Callable, case, stiffness, spec: CauseSpec,
                      base_te: list[np.ndarray]) -> list[np.ndarray]:
    """Per record (n_samples, n_params) TE change per unit parameter; te_of(case, stiffness)
    returns the list of simulated TE per record."""
    cols = [np.empty((len(b), len(spec.params))) for b in base_te]
    for j in range(len(spec.params)):
        p = np.zeros(len(spec.params))
        p[j] = spec.unit
        c2, s2 = spec.apply(case, stiffness, p)
        for r, te in enumerate(te_of(c2, s2)):
            cols[r][:, j] = (te - base_te[r]) / spec.unit
    return cols


@dataclass(frozen=True)
class SignatureSummary:
    """What a unit parameter does, read from the model (for evidence and the report)."""
    cause: str
    orders: tuple[int, ...]            # dominant orders (>= 10 % of the strongest line)
    line_arcsec: tuple[float, ...]     # their amplitudes per unit (largest parameter column)
    mean_shift_arcsec: dict            # record name -> mean TE change per unit
    amplitude_by_torque: dict          # |torque| -> strongest line per unit


def summarise(spec: CauseSpec, records, cols: list[np.ndarray], max_order: int,
              rel: float = 0.1) -> SignatureSummary:
    amp = None
    shift, by_t = {}, {}
    for rec, c in zip(records, cols):
        j = int(np.argmax(np.std(c, axis=0))) if c.size else 0
        sp = spectrum_of(rec.output_angle_deg, c[:, j])
        a = np.zeros(max_order + 1)
        for k in range(1, max_order + 1):
            idx = int(np.argmin(np.abs(sp.order - k)))
            a[k] = max(sp.amplitude[idx], 0.0) if abs(sp.order[idx] - k) < 0.5 else 0.0
        amp = a if amp is None else np.maximum(amp, a)
        shift[rec.name] = float(np.mean(c[:, 0]))
        by_t[round(abs(rec.torque_Nm), 1)] = float(a.max())
    amp = amp if amp is not None else np.zeros(max_order + 1)
    peak = amp.max()
    orders = tuple(int(k) for k in np.flatnonzero(amp >= rel * peak) if k > 0) if peak > 0 else ()
    return SignatureSummary(spec.cause, orders, tuple(float(amp[k]) for k in orders), shift, by_t)
