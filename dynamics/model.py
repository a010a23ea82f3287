"""Lumped planar multibody model of an RV reducer, fed by the FE stiffness (stiffness.json).

Bodies and DOFs (16 for three cranks and two discs; named blocks in `dynamics.layout`):
  input/sun       prescribed exactly (ideal servo): theta_in(t) of paper 001's ramp; the
                  input inertia therefore drops out, and the torque it must supply is an output.
  carrier/output  rotation; inertia = carrier (two steel flanges of the output-flange radius and
                  one disc width each, ASSUMED) + case.dynamics.load_inertia + cranks carried at
                  the crank radius (`dynamics.bodies`).
  crankshafts     rotation (= angle of the disc-1 eccentric) and in-plane axis displacement
                  relative to the carrier seat (rigid shaft; planet gear on it).
  discs           two, 180 deg apart: centre x, y and rotation.
  pin housing     fixed; every pin a separate contact for every disc.
Couplings (`dynamics.couplings`, one module each, physics in its docstring; every stiffness from
`fem.stiffness.StiffnessModel`, none invented here):
  mesh            involute mesh (time-varying, energy form) in series with the crank torsion;
  support         crank support: shaft bending in series with the two support bearings, clearance;
  needle          turning-arm needle bearing, FE law F = k delta^n, clearance;
  pin             F = k(phase) approach^n (FE law by pin phase from the line of centres); the
                  normal gap from the actual (modified, erroneous) profile by the foot point of
                  `geometry.pin_profile` (exact to ~1e-15 m, tests/test_dynamics_geometry.py at
                  K1 = 0.95 and micron clearances), so every error source acts through one mechanism.
Damping: stiffness-proportional on every coupling, c = beta k_t, beta = 2 zeta / omega_1 with
zeta = case.dynamics.damping_ratio (stated source: the case file) and omega_1 the lowest
eigenfrequency of the linearised model at rated torque, so the output torsional mode gets zeta
exactly and stiffer local modes more (contact damping grows with frequency). Contacts cannot
pull: damped contact forces are clipped at zero.
Error sources (case.errors; zero = ideal), each read by the coupling it acts in:
  crank_eccentricity_um    per crank: eccentric radius E + de_j (both eccentrics of the crank);
                           the two discs turn by equal and opposite amounts, the zp x line cancels
  eccentric_error_um       per crank: extra radius of the eccentric under disc 1 only (one journal
                           ground off size): disc 1 alone turns, a zp x line in the TE
  crank_hole_position_um   per crank: radial position of crank hole j on both discs
  output_bearing_hole_um   per crank: radial position of crank j's bearing seat in the carrier
  pin_radius_um, pin_circle_radius_um   all pins
  output_coaxiality_um, _phase_deg       a mounting offset e at the output flange radius r moves
                           the measured output angle by (e / r) sin(theta_out + phase): a
                           once-per-revolution encoder-side error added to the output angle the
                           results report (it carries no load, so it does not enter the dynamics)
  turning_arm_clearance_um, support_clearance_um   radial clearances of those bearings
Limits: planar (no disc tilt, no shaft bending shape beyond one lateral spring per crank,
no axial effects); frictionless contacts (no hysteresis beyond clearance); carrier translation
and pillar contacts not modelled; constant diagonal mass matrix (carrier speed <= 2 rad/s makes
the Coriolis/centripetal terms of the crank translation < 1e-3 of the contact forces).
Integrator: implicit HHT-alpha (alpha = 0.05) with a full Newton per step (numba kernel) at
dt = 1e-4 s by default: the contact modes reach ~10 kHz and an explicit scheme would need
dt < 1e-5 s; the time-step study is in tests/test_dynamics_verification.py. A step whose
contact set is the last step's takes its correction unconfirmed where the Newton contraction last
measured bounds the error left below the tolerance (kernels._hht_step; every sample and candidate
refresh step is confirmed): ~1.5 instead of ~2.1 assemblies a step. Only candidate pins
(gap < kernels.CANDIDATE_MARGIN_M at the last refresh, every CANDIDATE_REFRESH steps) enter the
Newton iterations; a skipped pin found closed raises DynamicsError (never silently wrong). The
kernel runs in chunks of ~CHUNK_WALL_S of wall time, so signal handlers (Ctrl-C, SIGTERM) act
between chunks; chunking does not change a single bit of the result. Runs of any length: the
kernel removes whole mechanism periods from the state as the input turns (`dynamics.kernels`), so
no angle the couplings see grows with the run.
Load range: the FE tables end at the catalog momentary torque (fem.reduce), so `simulate` refuses
a load form whose peak exceeds case.operation.momentary_torque_Nm, and a run whose largest pin
force left the FE pin-contact table (a dynamic overshoot) ends with that reason, not a result
from an extrapolated law.
Statics (`solve_static`, `quasi_static`, linearisation; the robust strategy and the zero-load
convention): `dynamics.statics`, imported from there.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from dynamics import kernels as kn
from dynamics.loads import LoadSpec, input_angle_deg, input_speed_deg_s, load_torque_Nm
from dynamics.reducer import DynamicsError, ReducerModel, build_model, evaluate
from dynamics.results import TEResult
from dynamics.statics import check_direction, damping_beta_s, static_q, te_result, turn_shift

__all__ = ["DynamicsError", "ReducerModel", "build_model", "evaluate", "simulate", "check_load_range"]

DEFAULT_SPEED_RPM = 1200.0   # DESIGN.md: paper 001's 7200 deg/s is the simulate default
DEFAULT_DT_S = 1e-4
DEFAULT_SAMPLE_DT_S = 5e-4
HHT_ALPHA = 0.05             # mild numerical dissipation of the unresolved contact modes
NEWTON_TOL_M = 1e-11         # HHT Newton: largest correction of a step [m] (rotations times ROT_SCALE_M)
NEWTON_MAX_ITER = 40
CHUNK_WALL_S = 0.05          # target wall time of one kernel call: Python regains control well within 0.2 s
CHUNK_FIRST_STEPS = 20       # first chunk (calibrates the steps per CHUNK_WALL_S)


@dataclass(frozen=True)
class Run:
    """Outcome of `run_dynamics`."""
    samples: kn.Samples        # one row per sample
    state: kn.RunState         # last converged state and solver counters
    status: int                # 0 done, 1 Newton failed at the step after last_step
    last_step: int
    chunks: int                # kernel calls (Python regained control after each)
    max_chunk_wall_s: float    # the longest of them

    @property
    def newton_iterations(self) -> int:
        return int(self.state.counts[0])

    @property
    def missed(self) -> int:
        """Contacts found closed at a candidate refresh that had been skipped (expected 0)."""
        return int(self.state.counts[1])

    @property
    def turns(self) -> int:
        """Whole mechanism periods removed from state.q (state.q + turns * shift is the absolute state)."""
        return int(self.state.counts[2])

    @property
    def peak_force_N(self) -> np.ndarray:
        """Largest force of each contact over the run (the Work's contact order)."""
        return self.state.peak


def _next_chunk(steps: int, wall_s: float, target_s: float) -> int:
    """Steps for the next chunk: scaled to the target wall time, at most doubling."""
    if wall_s <= 0.0:
        return 2 * steps
    return max(1, min(2 * steps, int(steps * target_s / wall_s)))


def run_dynamics(model: ReducerModel, q0, v0, th, w, T, dt: float, stride: int, alpha: float, beta: float, *,
                 store_forces: bool = True, max_iter: int = NEWTON_MAX_ITER, tol_m: float = NEWTON_TOL_M,
                 chunk_steps: int | None = None, chunk_wall_s: float = CHUNK_WALL_S,
                 unconfirmed_steps: bool = True) -> Run:
    """HHT-alpha from (q0, v0) along the prescribed input th, w [rad, rad/s] and load T [N m]
    (step n: th[n - 1] -> th[n]), sampled every `stride` steps. The kernel runs in chunks of
    `chunk_steps` steps, or (default) of ~chunk_wall_s of wall time, resuming from its state.
    Whole mechanism periods are removed from the state as the input turns (samples carry the
    absolute output angle; state.q is reduced by Run.turns periods). unconfirmed_steps=False confirms
    every step's correction by an assembly (the integrator before 2026-11-29: the benchmark's and
    the tests' reference)."""
    nsteps = len(th) - 1
    ns = nsteps // stride + 1
    n, m, mass = model.n_dof, model.arrays, model.mass
    nc = len(m.contact_group)
    st = kn.RunState(q=np.array(q0, float), v=np.array(v0, float), acc=np.zeros(n), fn=np.zeros(n),
                     sums=np.zeros(4), counts=np.zeros(3, np.int64), peak=np.zeros(nc),
                     newton=np.array([1.0, -1.0, 1.0 if unconfirmed_steps else 0.0]))
    shift, period = turn_shift(model), 2.0 * math.pi * model.ratio
    out = kn.Samples(q_out=np.zeros(ns), teeth=np.zeros((ns, m.n_groups), np.int64),
                     force=np.zeros((ns if store_forces else 1, nc)), tau_in=np.zeros(ns), energy=np.zeros((ns, 4)))
    wk = model.work()
    th, w, T = (np.ascontiguousarray(x, dtype=float) for x in (th, w, T))
    kn.integrate_start(st, th[0], w[0], T[0], beta, mass, m, wk)
    step, chunk, status, last, chunks, longest = 0, chunk_steps or CHUNK_FIRST_STEPS, 0, nsteps, 0, 0.0
    while step <= nsteps:
        end = min(nsteps + 1, step + chunk)
        t0 = time.perf_counter()
        last, status = kn.integrate(st, step, end, th, w, T, dt, stride, alpha, beta, m, wk, model.scale,
                                    max_iter, tol_m, mass, out, store_forces, shift, period)
        wall = time.perf_counter() - t0
        chunks, longest = chunks + 1, max(longest, wall)
        if status != 0:
            break
        step = end
        if chunk_steps is None:
            chunk = _next_chunk(chunk, wall, chunk_wall_s)
    return Run(out, st, status, last, chunks, longest)


def check_load_range(model: ReducerModel, load: LoadSpec) -> None:
    """Refuse a load form whose peak exceeds the case's momentary maximum torque: the reducer is not
    rated beyond it and the FE stiffness tables end there (fem.reduce). Cheap: no solve."""
    limit = model.case.operation.momentary_torque_Nm
    if load.peak_torque_Nm > limit:
        raise DynamicsError(f"load {load}: peak output torque {load.peak_torque_Nm:.6g} N m exceeds the case's "
                            f"momentary maximum {limit:g} N m ([operation] momentary_torque_Nm, "
                            f"{load.peak_torque_Nm / model.case.rated_torque_Nm:.3g}x rated): the reducer is not "
                            f"rated for it and the FE stiffness tables end there; allowed peak <= {limit:g} N m")


def simulate(model: ReducerModel, load: LoadSpec, *, duration_s: float = 7.0,
             input_speed_rpm: float | None = None, direction: int = +1, dt_s: float | None = None,
             sample_dt_s: float | None = None, ramp: bool = True, store_pin_forces: bool = True,
             hht_alpha: float = HHT_ALPHA, damping_beta_s_: float | None = None,
             return_energy: bool = False, carrier_drag_Nm: float = 0.0) -> TEResult:
    """Time integration of paper 001's run: input speed ramp (STEP over 1 s), load form `load`.
    Starts at rest in static equilibrium under the load's initial torque. input_speed_rpm
    defaults to DESIGN.md's 1200 rpm; direction -1 runs backward (record torque negative).
    carrier_drag_Nm (>= 0, dynamics.losses.contacts.carrier_drag_Nm): the main bearings' and
    output seal's drag, resisting the carrier's motion on top of the load (paper 001's model has
    none: 0); the record's torque column stays the load's, as a torque meter beyond the output reads.
    Energy bookkeeping (kinetic, potential, input work, load work) lands in meta when asked."""
    check_direction(direction)
    if not (math.isfinite(carrier_drag_Nm) and 0.0 <= carrier_drag_Nm <= model.case.rated_torque_Nm):
        raise DynamicsError(f"simulate: carrier_drag_Nm = {carrier_drag_Nm!r}: allowed a finite drag in "
                            f"[0, rated {model.case.rated_torque_Nm:g}] N m")
    check_load_range(model, load)
    speed = DEFAULT_SPEED_RPM if input_speed_rpm is None else float(input_speed_rpm)
    dt = DEFAULT_DT_S if dt_s is None else float(dt_s)
    sdt = DEFAULT_SAMPLE_DT_S if sample_dt_s is None else float(sample_dt_s)
    for name, val, lo in (("duration_s", duration_s, 0.0), ("dt_s", dt, 0.0), ("sample_dt_s", sdt, 0.0),
                          ("input_speed_rpm", speed, -1.0)):
        if not (math.isfinite(val) and val > lo):
            raise DynamicsError(f"simulate: {name} = {val!r} must be finite and > {lo:g}")
    if dt > 1e-3:
        raise DynamicsError(f"simulate: dt_s = {dt:g} s is too coarse for the contact dynamics; allowed <= 1e-3 s")
    stride = max(1, int(round(sdt / dt)))
    nsteps = int(math.ceil(duration_s / (dt * stride))) * stride
    t = np.arange(nsteps + 1) * dt
    th = direction * np.deg2rad(input_angle_deg(t, speed, ramp))
    w = direction * np.deg2rad(input_speed_deg_s(t, speed, ramp))
    T = direction * np.asarray(load_torque_Nm(load, t), dtype=float)
    T_mech = T + direction * carrier_drag_Nm if carrier_drag_Nm else T     # what the mechanism carries
    beta = damping_beta_s(model) if damping_beta_s_ is None else float(damping_beta_s_)
    q, _ = static_q(model, th[0], T_mech[0], None, direction)
    run = run_dynamics(model, q, np.zeros_like(q), th, w, T_mech, dt, stride, hht_alpha, beta,
                       store_forces=store_pin_forces)
    pin_peak = float(model.contacts(run.peak_force_N).max(initial=0.0))
    table = float(np.max(model.stiffness.pin_contact.load_N))
    if run.status != 0:
        raise DynamicsError(f"simulate diverged at t = {run.last_step * dt:.5g} s for load {load}: the step did "
                            f"not converge in {2 ** (kn.SUBSTEP_LEVELS - 1)} sub-steps of dt = {dt:g} s (largest "
                            f"pin force so far {pin_peak:.4g} N, FE table to {table:.4g} N); a smaller --dt helps "
                            f"only where contacts change faster than dt resolves")
    if run.missed:
        raise DynamicsError(f"simulate: {run.missed} pin contacts closed while skipped as open (candidate "
                            f"margin {kn.CANDIDATE_MARGIN_M * 1e6:g} um too small for load {load}); "
                            f"reduce --dt")
    if pin_peak > table:
        raise DynamicsError(f"simulate: load {load} drove a pin force of {pin_peak:.4g} N, beyond the FE "
                            f"pin-contact table (to {table:.4g} N): the result would rest on an extrapolated "
                            f"contact law; lower the torque or widen the FEM stage's load range")
    s = run.samples
    idx = np.arange(len(s.q_out)) * stride
    meta = {"load": str(load), "dt_s": dt, "sample_dt_s": dt * stride,
            "newton_per_step": run.newton_iterations / max(nsteps, 1), "missed_contacts": run.missed,
            "peak_pin_force_N": pin_peak, "pin_table_max_N": table,
            "input_speed_rpm": speed, "direction": direction, "solver": f"HHT-alpha {hht_alpha}",
            "damping_beta_s": beta, "input_torque_Nm": s.tau_in, "carrier_drag_Nm": float(carrier_drag_Nm),
            "kernel_calls": run.chunks, "max_kernel_call_s": run.max_chunk_wall_s}
    if return_energy:
        meta["energy_J"] = s.energy
    return te_result(model, t[idx], th[idx], s.q_out, T[idx], s.teeth,
                     model.contacts(s.force) if store_pin_forces else None, meta)
