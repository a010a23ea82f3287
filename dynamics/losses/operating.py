"""The operating point: TE, efficiency and torques of the running reducer with friction.

Per condition (input speed, output torque, oil temperature) and direction (the load resists the
motion in both: power flows from input to output either way), at input angles over one output
revolution:
  1. the frictionless static state (dynamics.statics.solve_static) under the load plus the carrier's
     drag (main bearings + output seal, dynamics.losses.contacts): the drag closes the free play on
     the loaded flank at zero load, so the no-load loss acts through the low-torque (clearance,
     Hertzian) part of the wind-up;
  2. the friction forces and moments of every contact (dynamics.losses.contacts: directions from the
     running kinematics, magnitudes from the contact loads and the mixed-friction coefficient) added
     as loads, and the statics re-solved by Newton on the model's tangent with the contact normal
     forces (hence the friction) recomputed at each iterate, to FRICTION_TOL. With the friction, the
     steady inertia of the running mechanism (d'Alembert): -M d2q/dt2 of the rigid
     kinematics at constant input speed, i.e. each disc's orbit, m E omega_e^2 outward along its
     eccentric (omega_e = the eccentrics' absolute speed, 39/81 of the input on the RV-160N: 61 N per
     disc at 1800 rpm); every other body turns at constant speed. Even in the sense of motion, it
     moves the gap by <= 0.012 arcsec at 1800 rpm (RV-160N, 0 to 1000 N m): not the bench's speed trend;
  3. TE = the output encoder's reading - input / i (bench convention), its mean and peak-to-peak per
     direction; efficiency = P_out / (P_out + P_loss) and input torque = (P_out + P_loss) / omega_in,
     forward, averaged over the revolution (power-weighted).
The stiffness is the model's (dynamics.reducer.build_model from fem.stiffness): a softer or stiffer
stiffness model changes every figure here with no edit. Starting torque: zero speed, no load, every
sliding contact at boundary friction (Lambda = 0) and the bearings at Palmgren's slow-running moment.
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

import numpy as np

from dynamics.losses.contacts import RPM_PER_RAD_S, contact_friction, rates
from dynamics.losses.lubricant import Lubricant
from dynamics.reducer import DynamicsError, ReducerModel, evaluate
from dynamics.results import ARCSEC_PER_RAD
from dynamics.statics import nominal_q, nominal_qdd, solve_static

FRICTION_TOL_RAD = 2.5e-8      # Newton on the friction loads: output-angle step below 0.005 arcsec
FRICTION_MAX_ITER = 8
POINTS_PER_REV = 16            # input angles per output revolution (mean and p-p of TE: a 1x line's p-p to 2 %)


@dataclass(frozen=True)
class DirectionRun:
    """One direction of one condition, per sampled input angle."""
    direction: int
    input_angle_deg: np.ndarray
    te_arcsec: np.ndarray
    te_frictionless_arcsec: np.ndarray
    output_power_W: np.ndarray
    loss_W: dict                   # contact set -> (n,) power loss
    pin_mu: np.ndarray             # (n,) mean friction coefficient of the loaded pins
    pin_film_parameter: np.ndarray  # (n,) mean Lambda of the loaded pins
    carrier_drag_Nm: float
    newton_iterations: int

    @property
    def total_loss_W(self) -> np.ndarray:
        return np.sum(list(self.loss_W.values()), axis=0)

    @property
    def efficiency(self) -> float | None:
        out = float(np.sum(self.output_power_W))
        return out / (out + float(np.sum(self.total_loss_W))) if out > 0 else None


@dataclass(frozen=True)
class OperatingPoint:
    input_speed_rpm: float
    torque_Nm: float
    oil_temperature_C: float
    forward: DirectionRun
    backward: DirectionRun
    meta: dict = field(default_factory=dict)

    @property
    def gap_arcsec(self) -> float:
        return float(np.mean(self.forward.te_arcsec) - np.mean(self.backward.te_arcsec))

    @property
    def gap_frictionless_arcsec(self) -> float:
        return float(np.mean(self.forward.te_frictionless_arcsec) - np.mean(self.backward.te_frictionless_arcsec))

    @property
    def input_torque_Nm(self) -> float:
        """Forward input torque: (P_out + P_loss) / omega_in, revolution mean."""
        om = self.input_speed_rpm / RPM_PER_RAD_S
        return float(np.mean(self.forward.output_power_W + self.forward.total_loss_W)) / om if om else math.nan

    def row(self) -> dict:
        """The `conditions.csv` columns (DESIGN.md), efficiency empty (None) at zero torque."""
        fw, bw = self.forward.te_arcsec, self.backward.te_arcsec
        return {"te_mean_fw_arcsec": float(np.mean(fw)), "te_mean_bw_arcsec": float(np.mean(bw)),
                "gap_fw_minus_bw_arcsec": self.gap_arcsec, "te_pp_fw_arcsec": float(np.ptp(fw)),
                "te_pp_bw_arcsec": float(np.ptp(bw)), "efficiency": self.forward.efficiency,
                "input_torque_Nm": self.input_torque_Nm}

    def summary(self) -> dict:
        f = self.forward
        return {**self.row(), "gap_frictionless_arcsec": self.gap_frictionless_arcsec,
                "pin_friction_mean": float(np.mean(f.pin_mu)) if len(f.pin_mu) else None,
                "pin_film_parameter_mean": float(np.mean(f.pin_film_parameter)) if len(f.pin_mu) else None,
                "carrier_drag_Nm": f.carrier_drag_Nm,
                "loss_share": {k: float(np.sum(v)) / max(float(np.sum(f.total_loss_W)), 1e-300)
                               for k, v in f.loss_W.items()}}


def _output_angle_rad(model: ReducerModel, q: np.ndarray) -> float:
    return float(model.measured_output_rad(q[model.i_out]))


def inertia_load(model: ReducerModel, input_rad: float, input_speed_rad_s: float) -> np.ndarray:
    """(n,) d'Alembert load of the rigid mechanism running at a constant input speed: -M qdd."""
    return -model.mass * nominal_qdd(model, input_rad) * input_speed_rad_s ** 2


def friction_equilibrium(model: ReducerModel, lub: Lubricant, q: np.ndarray, input_rad: float, torque: float,
                         qdot: np.ndarray, oil_temperature_C: float, input_speed_rad_s: float,
                         shape: np.ndarray | None = None, viscous: bool = True, load: np.ndarray | None = None):
    """Static equilibrium under `torque` at the output (record convention, applied), the optional
    `load` (n,) and the contact friction of a motion qdot: Newton on the tangent from the frictionless
    state q, the friction recomputed from the normal forces at every iterate. Returns (q, friction of
    the last iterate, its)."""
    io = model.i_out
    fr = None
    for it in range(1, FRICTION_MAX_ITER + 1):
        fr = contact_friction(model, lub, q, input_rad, qdot, oil_temperature_C, input_speed_rad_s, shape, viscous)
        w, _ = evaluate(model, q, input_rad, want_k=True)
        res = w.f + fr.force
        if load is not None:
            res += load
        res[io] -= torque
        try:
            dq = np.linalg.solve(0.5 * (w.K + w.K.T), res)
        except np.linalg.LinAlgError:
            raise DynamicsError(f"friction statics: singular tangent at input {math.degrees(input_rad):.6g} deg, "
                                f"torque {torque:.4g} N m") from None
        q = q + dq
        if abs(dq[io]) < FRICTION_TOL_RAD:
            return q, fr, it
    raise DynamicsError(f"friction statics did not converge at input {math.degrees(input_rad):.6g} deg, "
                        f"torque {torque:.4g} N m (output step {abs(dq[io]) * ARCSEC_PER_RAD:.3g} arcsec "
                        f"after {FRICTION_MAX_ITER} iterations)")


def run_direction(model: ReducerModel, lub: Lubricant, input_speed_rpm: float, torque_Nm: float,
                  oil_temperature_C: float, direction: int, input_angle_deg: np.ndarray,
                  friction: bool = True) -> DirectionRun:
    om_in = direction * input_speed_rpm / RPM_PER_RAD_S
    io = model.i_out
    te, te0, pout, mu, lam = [], [], [], [], []
    losses: dict[str, list] = {}
    q, drag, iters = None, None, 0
    for th_deg in input_angle_deg:
        th = math.radians(th_deg)
        qdot = rates(model, th) * om_in
        if drag is None:       # the carrier's drag depends on speed and temperature only
            st = solve_static(model, th_deg, direction * torque_Nm, None, direction)
            drag = contact_friction(model, lub, st.q, th, qdot, oil_temperature_C, om_in).carrier_drag_Nm \
                if friction else 0.0
        T = direction * (torque_Nm + drag)
        guess = None if q is None else q + nominal_q(model, th) - nominal_q(model, th_prev)
        st = solve_static(model, th_deg, T, guess, direction)
        th_prev = th
        q = st.q
        te0.append(st.te_arcsec)
        if friction:
            qf, fr, it = friction_equilibrium(model, lub, q, th, T, qdot, oil_temperature_C, om_in,
                                              load=inertia_load(model, th, om_in))
            iters += it
            for k, v in fr.power_W.items():
                losses.setdefault(k, []).append(v)
            mu.append(float(np.mean(fr.pin_mu)) if len(fr.pin_mu) else math.nan)
            lam.append(float(np.mean(fr.pin_film_parameter)) if len(fr.pin_mu) else math.nan)
        else:
            qf = q
        te.append((_output_angle_rad(model, qf) - th / model.ratio) * ARCSEC_PER_RAD)
        pout.append(torque_Nm * abs(qdot[io]))
    return DirectionRun(direction=direction, input_angle_deg=np.asarray(input_angle_deg, float),
                        te_arcsec=np.array(te), te_frictionless_arcsec=np.array(te0),
                        output_power_W=np.array(pout), loss_W={k: np.array(v) for k, v in losses.items()},
                        pin_mu=np.array(mu), pin_film_parameter=np.array(lam), carrier_drag_Nm=float(drag),
                        newton_iterations=iters)


def check_condition(lub: Lubricant, input_speed_rpm: float, torque_Nm: float, oil_temperature_C: float,
                    loaded: bool = False) -> None:
    """One error line for a condition the operating model cannot run: speed finite and > 0, torque
    finite and >= 0 (the load's magnitude; > 0 where a loaded state is asked for), the oil temperature
    inside the lubricant's range."""
    if not (math.isfinite(input_speed_rpm) and input_speed_rpm > 0):
        raise DynamicsError(f"input speed = {input_speed_rpm!r} rpm: must be finite and > 0")
    if loaded and not (math.isfinite(torque_Nm) and torque_Nm > 0):
        raise DynamicsError(f"torque = {torque_Nm!r} N m: must be finite and > 0 (a loaded state)")
    if not (math.isfinite(torque_Nm) and torque_Nm >= 0):
        raise DynamicsError(f"torque = {torque_Nm!r} N m: must be finite and >= 0 (the load's magnitude)")
    lub.check_temperature(oil_temperature_C)


def revolution_angles_deg(model: ReducerModel, points_per_rev: int = POINTS_PER_REV) -> np.ndarray:
    """Input angles over one output revolution, offset half a step from zero."""
    n = int(points_per_rev)
    return 360.0 * model.ratio * (np.arange(n) + 0.5) / n


def operating_point(model: ReducerModel, lub: Lubricant, input_speed_rpm: float, torque_Nm: float,
                    oil_temperature_C: float, *, points_per_rev: int = POINTS_PER_REV,
                    friction: bool = True) -> OperatingPoint:
    """TE in each direction, gap, efficiency and input torque at one condition (see module doc).
    torque_Nm >= 0 is the load's magnitude (resisting the motion in both directions)."""
    check_condition(lub, input_speed_rpm, torque_Nm, oil_temperature_C)
    ang = revolution_angles_deg(model, points_per_rev)
    runs = [run_direction(model, lub, input_speed_rpm, torque_Nm, oil_temperature_C, s, ang, friction)
            for s in (1, -1)]
    return OperatingPoint(input_speed_rpm=float(input_speed_rpm), torque_Nm=float(torque_Nm),
                          oil_temperature_C=float(oil_temperature_C), forward=runs[0], backward=runs[1],
                          meta={"points_per_rev": int(points_per_rev), "friction": bool(friction)})


CREEP_RAD_S = 1e-9      # input speed of a start or a catalog sweep: no film (Lambda -> 0), no viscous drag


def starting_torque_Nm(model: ReducerModel, lub: Lubricant, oil_temperature_C: float,
                       input_angle_deg: float = 0.0) -> float:
    """Input torque that starts the unloaded reducer: every sliding contact at boundary friction
    (no film at zero speed), the bearings' load moments (preload) and the seals, no viscous drag:
    sum of the loss moments times their speed ratio to the input."""
    th = math.radians(input_angle_deg)
    st = solve_static(model, input_angle_deg, 0.0, None, +1)
    fr = contact_friction(model, lub, st.q, th, rates(model, th) * CREEP_RAD_S, oil_temperature_C,
                          CREEP_RAD_S, viscous=False)
    return (fr.total_power_W + fr.carrier_drag_Nm * CREEP_RAD_S / model.ratio) / CREEP_RAD_S


@dataclass(frozen=True)
class FrictionLoop:
    """The catalog loop (input locked, output torque swept 0 -> +rated -> -rated -> +rated) with the
    contact friction opposing the creep of every contact (boundary friction: no film at rest)."""
    torque_Nm: np.ndarray
    output_angle_arcmin: np.ndarray              # with friction
    output_angle_frictionless_arcmin: np.ndarray
    rated_torque_Nm: float
    width_at_zero_arcmin: float                  # falling minus rising branch at zero torque
    width_frictionless_at_zero_arcmin: float
    max_width_arcmin: float                      # widest gap between the branches over the sweep
    torsional_rigidity_Nm_per_arcmin: float      # slope 50-100 % rated (catalog b / a), with friction
    torsional_rigidity_secant_Nm_per_arcmin: float


def _branch_width(T, ang, rated):
    """(width at zero, widest) of the loop: the falling branch (from +rated) at its last point on the
    positive side of zero minus the rising branch (from -rated) at its last negative point, and the
    largest difference of the two branches at matched torques beyond +-5 % rated (friction alone)."""
    dT = np.diff(T, prepend=T[0])
    half = np.arange(len(T)) >= len(T) // 5           # past the first loading leg
    dn, up = half & (dT < 0), half & (dT > 0)
    i_dn = np.flatnonzero(dn & (T > 0))[-1]
    i_up = np.flatnonzero(up & (T < 0))[-1]
    grid = np.concatenate([np.linspace(-0.9, -0.05, 18), np.linspace(0.05, 0.9, 18)]) * rated   # off the free play
    iu, idn = np.argsort(T[up]), np.argsort(T[dn])
    w = np.interp(grid, T[dn][idn], ang[dn][idn]) - np.interp(grid, T[up][iu], ang[up][iu])
    return float(abs(ang[i_dn] - ang[i_up])), float(np.max(np.abs(w)))


def friction_loop(model: ReducerModel, lub: Lubricant, oil_temperature_C: float, points_per_quarter: int = 11,
                  input_angle_deg: float = 0.0) -> FrictionLoop:
    from dynamics.catalog import rigidity_readings, sweep_torques
    rated = model.case.rated_torque_Nm
    T = sweep_torques(rated, points_per_quarter)
    th = math.radians(input_angle_deg)
    qs, q = [], None
    for t in T:
        q = solve_static(model, input_angle_deg, t, q, +1 if t >= 0 else -1).q
        qs.append(q)
    qs = np.array(qs)
    io = model.i_out
    a0 = np.array([_output_angle_rad(model, q) for q in qs]) * ARCSEC_PER_RAD / 60
    a1 = [a0[0]]
    for k in range(1, len(T)):
        # Coulomb: the output moves only where the load overcomes the friction, and then only in the
        # sweep's sense; where the friction statics has no solution on the loaded flank, or one
        # behind the last point, the output sticks there (the loop's flat, friction-held parts)
        sense = np.sign(a0[k] - a0[k - 1])
        shape = (qs[k] - qs[k - 1]) * np.sign(T[k] - T[k - 1])
        qdot = shape / max(abs(shape[io]), 1e-30) * CREEP_RAD_S / model.ratio
        try:
            qf, _, _ = friction_equilibrium(model, lub, qs[k], th, T[k], qdot, oil_temperature_C, 0.0, shape,
                                            viscous=False)
            a = _output_angle_rad(model, qf) * ARCSEC_PER_RAD / 60
        except DynamicsError:
            a = a1[-1]
        a1.append(a if (a - a1[-1]) * sense >= 0 else a1[-1])
    a1 = np.array(a1)
    w1, m1 = _branch_width(T, a1, rated)
    w0, _ = _branch_width(T, a0, rated)
    slope, secant = rigidity_readings(-T, a1, rated)
    return FrictionLoop(torque_Nm=T, output_angle_arcmin=a1, output_angle_frictionless_arcmin=a0,
                        rated_torque_Nm=rated, width_at_zero_arcmin=w1, width_frictionless_at_zero_arcmin=w0,
                        max_width_arcmin=m1, torsional_rigidity_Nm_per_arcmin=slope,
                        torsional_rigidity_secant_Nm_per_arcmin=secant)


def forward_efficiency(model: ReducerModel, lub: Lubricant, input_speed_rpm: float, torque_Nm: float,
                       oil_temperature_C: float, points_per_rev: int = 6) -> float | None:
    """Forward efficiency alone (the catalog's efficiency chart): fewer angles, no backward run."""
    lub.check_temperature(oil_temperature_C)
    run = run_direction(model, lub, input_speed_rpm, torque_Nm, oil_temperature_C, +1,
                        revolution_angles_deg(model, points_per_rev))
    return run.efficiency


def simulate_condition(model: ReducerModel, lub: Lubricant, input_angle_deg, torque_Nm: float, direction: int,
                       input_speed_rpm: float, oil_temperature_C: float, friction: bool = True) -> DirectionRun:
    """The TE of a record's condition (the diagnosis' entry): input angles [deg, any, unwrapped],
    torque_Nm >= 0 the load's magnitude resisting the motion, direction +1 forward / -1 backward, the
    input speed [rpm] and oil temperature [C]; returns the DirectionRun (te_arcsec at each angle,
    te_frictionless_arcsec, losses). The angles are solved in order, warm-started."""
    if direction not in (1, -1):
        raise DynamicsError(f"direction = {direction!r}: allowed +1 (forward) or -1 (backward)")
    check_condition(lub, input_speed_rpm, torque_Nm, oil_temperature_C)
    return run_direction(model, lub, input_speed_rpm, torque_Nm, oil_temperature_C, direction,
                         np.atleast_1d(np.asarray(input_angle_deg, float)), friction)


@dataclass(frozen=True)
class FrictionLever:
    """How much of the running friction loads the reducer's compliance, at one static state.

    By Maxwell-Betti, the output shift the friction loads f cause (the statics re-solved with them,
    input held) is f . u, u = K^-1 e_out the deflection per unit output torque (K the tangent, its
    mean over the frictionless and the friction state: the Hertzian contacts stiffen a little in
    between). Friction that loaded the compliance as the torque does (every internal force x 1/eta)
    would shift the output by windup x loss_share; `lever` = (shift / windup) / loss_share says which
    share of that it does. The friction of the cycloid-pin contacts (most of the loss) acts along
    the contact tangents, nearly at right angles to the motion the wind-up gives the disc there."""
    torque_Nm: float
    input_speed_rpm: float
    oil_temperature_C: float
    windup_arcsec: float          # the output's lag under T on the tangent at the frictionless state (TE sign)
    shift_arcsec: float           # friction statics minus frictionless, output angle
    reciprocity_arcsec: float     # f_friction . u (mean tangent): the check of shift_arcsec
    loss_share: float             # friction power of the applied contacts / output power

    @property
    def lever(self) -> float:
        return (self.shift_arcsec / self.windup_arcsec) / self.loss_share if self.loss_share > 0 else math.nan

    def summary(self) -> dict:
        return {**dataclasses.asdict(self), "lever": self.lever}


def friction_lever(model: ReducerModel, lub: Lubricant, torque_Nm: float, input_speed_rpm: float,
                   oil_temperature_C: float, input_angle_deg: float = 7.0) -> FrictionLever:
    """FrictionLever of the forward run at one input angle (the shift is flat in angle: below)."""
    check_condition(lub, input_speed_rpm, torque_Nm, oil_temperature_C, loaded=True)
    io, th = model.i_out, math.radians(input_angle_deg)
    om = input_speed_rpm / RPM_PER_RAD_S
    qdot = rates(model, th) * om
    st = solve_static(model, input_angle_deg, torque_Nm, None, +1)
    qf, fr, _ = friction_equilibrium(model, lub, st.q, th, torque_Nm, qdot, oil_temperature_C, om)
    e = np.zeros(model.n_dof)
    e[io] = 1.0
    tangents = [evaluate(model, q, th, want_k=True)[0].K for q in (st.q, qf)]
    u0 = np.linalg.solve(0.5 * (tangents[0] + tangents[0].T), e)
    um = np.linalg.solve(0.25 * sum(k + k.T for k in tangents), e)
    applied = fr.power_W["pins"] + fr.power_W["needles"] + fr.power_W["supports"]
    return FrictionLever(torque_Nm=float(torque_Nm), input_speed_rpm=float(input_speed_rpm),
                         oil_temperature_C=float(oil_temperature_C),
                         windup_arcsec=float(-torque_Nm * u0[io] * ARCSEC_PER_RAD),
                         shift_arcsec=float((qf[io] - st.q[io]) * ARCSEC_PER_RAD),
                         reciprocity_arcsec=float(fr.force @ um * ARCSEC_PER_RAD),
                         loss_share=float(applied / (torque_Nm * abs(qdot[io]))))


SHIFT_POINTS = 3   # input angles the friction shift is averaged over (it is flat in angle: below)


def friction_shift_arcsec(model: ReducerModel, lub: Lubricant, torque_Nm: float, direction: int,
                          input_speed_rpm: float, oil_temperature_C: float, points: int = SHIFT_POINTS) -> float:
    """The mean TE [arcsec] the running losses add to the frictionless statics at one condition and
    direction: the carrier's drag on the load, every contact's friction and the running inertia
    (simulate_condition with them minus without), averaged over `points` input angles spread over one
    output revolution. It is flat in angle (RV-160N FE stiffness, 1800 rpm, 25 C, 26 angles: std
    <= 0.007 arcsec from 0 to 1800 N m, where it is -0.86, -0.98, -2.94 arcsec forward at 0, 300,
    1800 N m and the opposite backward), so a bench record's model adds it as one constant."""
    ang = direction * revolution_angles_deg(model, points)
    run = [simulate_condition(model, lub, ang, torque_Nm, direction, input_speed_rpm, oil_temperature_C, f)
           for f in (True, False)]
    return float(np.mean(run[0].te_arcsec - run[1].te_arcsec))


def shift_by_torque(torque_Nm, shift_at):
    """shift_at(|T|) of a run's torque: one value (a scalar) where |T| varies by < 1 N m, else each
    sample's by linear interpolation between three levels over its range (the shift is smooth in
    torque); the levels are rounded to 1e-3 N m (a cache key)."""
    T = np.abs(np.asarray(torque_Nm, float))
    lo, hi = round(float(T.min()), 3), round(float(T.max()), 3)
    if hi - lo < 1.0:
        return shift_at(round(0.5 * (lo + hi), 3))
    levels = np.round(np.linspace(lo, hi, 3), 3)
    return np.interp(T, levels, [shift_at(float(t)) for t in levels])
