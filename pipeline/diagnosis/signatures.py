"""The signature library: each error source alone, at unit size, through the model.

A cause is a set of model parameters p (zero = the case as given) and `apply(case, stiffness, p)`
returning the perturbed case and stiffness. Its signature on a record is the model's TE change per
unit parameter, (TE(p = u e_j) - TE(0)) / u, at that record's angles, torque and direction, so the
orders, harmonic pattern, load and direction dependence all come from the model, not a table.

Causes and their parameters (DESIGN.md ids):
  output_coaxiality         (e cos phi, e sin phi) [um]: the mounting offset e at phase phi, read by
                            the output encoder as e/r sin(theta_out + phi) (dynamics.model)
  crank_eccentricity_error  (e_1 .. e_n) [um]: per crank, the radius error of the eccentric under
                            disc 1 only (Errors.eccentric_error_um; e.g. one journal ground off
                            size). Disc 1 alone is displaced, so it turns against disc 2 by a
                            misfit at the crankshaft order: a zp x line (the model, RV-40E on the
                            tests' stand-in stiffness: 0.85 arcsec per um, linear, nearly
                            torque-independent; 2 zp x and a mean shift, even in e, only at light
                            load, so it stays `dc_even`: named on its lines, refitted in the loop).
                            The line's complex amplitude is linear in the e_j with a crank-dependent phase (crank j at
                            360 j / n deg), so the zero-mean pattern e_j - mean(e) = A cos(phi -
                            2 pi j / n) is what the line measures (amplitude A, phase phi: which
                            crank); the common part (disc 1's whole eccentricity) has no line and
                            is read from the mean shifts alone. Why not Errors.crank_eccentricity_um:
                            it changes BOTH eccentrics of a crank (180 deg apart), the two discs
                            turn by +d and -d, the zp x line cancels in the carrier and only a
                            rectified 2 zp x threshold response remains, unlike real benches.
  crank_hole_position_error (A cos 2 phi, A sin 2 phi) [um]: the zero-mean pattern de_j = A cos(phi
                            - 2 pi j / n_crank) of radial crank-hole position errors on both discs
                            (Errors.crank_hole_position_um): both discs, so the zp x line cancels
                            and the rectified 2 zp x part remains (even in A, hence 2 phi).
  torsional_stiffness       kappa = 1/c - 1, c the factor on every FE stiffness (deflections at equal load
                            scale by 1/c, so TE is near linear in kappa; power-law contacts
                            F = k d^n get k c^n)
  backlash                  extra pin clearance [um] on the equidistant modification dRr (> 0 opens
                            backlash); reported as lost motion in arcmin via the model's own ratio
Unit sizes: 1 um coaxiality, 5 % stiffness, 2 um clearance, 2 um eccentric error (linear causes);
10 um for the crank-hole pattern, a tolerance-class size: at 1 um that misfit stays inside the
elastic approach of the loaded pins and the model answers ~0.01 arcsec (second order), so a 1 um
secant would not represent the 5-20 um errors that matter. The library is a linearisation (a
secant for the crank patterns); the extension (diagnose.py) refits on the full model.
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


def crank_pattern_um(n_crank: int, p) -> np.ndarray:
    """Per-crank values A cos(phi - 2 pi j / n) from p = (A cos 2 phi, A sin 2 phi) [um]."""
    a, two_phi = float(np.hypot(p[0], p[1])), float(np.arctan2(p[1], p[0]))
    return a * np.cos(0.5 * two_phi - 2 * np.pi * np.arange(n_crank) / n_crank)


def eccentric_pattern(values_um) -> tuple[float, float, float]:
    """(A, phi [deg], mean) of per-crank values v_j = mean + A cos(phi - 2 pi j / n): the part the
    zp x line of a disc-1 eccentric error measures (A, phi) and the common part (mean)."""
    v = np.asarray(values_um, float)
    n = len(v)
    z = 2.0 / n * np.sum((v - v.mean()) * np.exp(1j * 2 * np.pi * np.arange(n) / n))
    return float(abs(z)), float(np.degrees(np.angle(z))), float(v.mean())


def _eccentric(case, stiffness, p):
    """p: per-crank errors [um] of disc 1's eccentric (added to Errors.eccentric_error_um)."""
    d = np.asarray(p, float)
    return case.with_errors(eccentric_error_um=_per_crank(case, "eccentric_error_um", d)), stiffness


def _crank_hole(case, stiffness, p):
    d = crank_pattern_um(case.carrier.crank_count, p)
    return case.with_errors(crank_hole_position_um=_per_crank(case, "crank_hole_position_um", d)), stiffness


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
    dc_even: bool = False                        # mean-TE response depends on |p| only (see above)


CRANK_UNIT_UM = 10.0
ECCENTRIC_UNIT_UM = 2.0


def cause_specs(case) -> tuple[CauseSpec, ...]:
    return (
        CauseSpec("output_coaxiality", ("coaxiality_cos_um", "coaxiality_sin_um"), 1.0, _coaxiality,
                  "output mounted off-axis: the output encoder reads e/r sin(theta + phi)"),
        CauseSpec("crank_eccentricity_error",
                  tuple(f"eccentric_error_crank{j + 1}_um" for j in range(case.carrier.crank_count)),
                  ECCENTRIC_UNIT_UM, _eccentric,
                  "an eccentric of a crankshaft off its radius (disc 1's journal): the disc turns "
                  "at the crankshaft order", dc_even=True),
        CauseSpec("crank_hole_position_error", ("hole_A_cos2phi_um", "hole_A_sin2phi_um"), CRANK_UNIT_UM,
                  _crank_hole, "crank holes of the discs off their nominal radial position", dc_even=True),
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
