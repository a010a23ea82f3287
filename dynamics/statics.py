"""Kinematics and statics of the lumped model: rigid poses, static equilibria, linearisation.

The static strategy (robust at any input angle, either torque sign, zero load) is documented in
`solve_static`; the numba Newton is `dynamics.kernels.static_solve`.
"""
from __future__ import annotations

import math

import numpy as np

from dynamics import kernels as kn
from dynamics.reducer import DynamicsError, ReducerModel, evaluate
from dynamics.results import ARCSEC_PER_DEG, StaticState, TEResult

STATIC_TOL_N = 1e-6          # static residual tolerance [N] (rotations: N m / ROT_SCALE_M)
ZERO_LOAD_FRACTION = 1e-5    # |T| below this share of rated torque is solved as this preload
FLANK_SEARCH_RAD = 2e-3      # output rotation searched for the loaded flank (7 arcmin >> any backlash)
CONTINUATION_MAX_SOLVES = 40


def check_direction(direction):
    if direction not in (1, -1):
        raise DynamicsError(f"direction = {direction!r}: allowed +1 (forward) or -1 (backward)")


def _crank_phase(model: ReducerModel, input_rad: float, carrier_rad: float) -> float:
    """Crank rotation with the input held and the mesh rigid: the planet rolls on the sun."""
    s1 = model.case.stage1
    return carrier_rad - s1.z1 / s1.z2 * (input_rad - carrier_rad)


def nominal_q(model: ReducerModel, input_rad: float, lag_rad: float = 0.0) -> np.ndarray:
    """Rigid-body kinematics (ideal geometry): carrier = input / i - lag, eccentric = -zc carrier."""
    lay = model.layout
    q = np.zeros(model.n_dof)
    io = model.i_out
    q[io] = input_rad / model.ratio - lag_rad
    phi = _crank_phase(model, input_rad, q[io])
    q[lay["crank_rotation"].slice] = phi
    E = model.case.si.eccentricity_m
    disc = lay["disc"]
    for d in range(model.n_disc):
        i = disc.index(d)
        q[i:i + 3] = E * math.cos(phi + math.pi * d), E * math.sin(phi + math.pi * d), q[io]
    return q


def nominal_qdd(model: ReducerModel, input_rad: float) -> np.ndarray:
    """d2 nominal_q / d input^2: the discs' orbit, -(d phi / d th)^2 E (cos, sin)(phi + pi d); every
    other coordinate of the rigid kinematics is linear in the input (zero)."""
    s1, lay = model.case.stage1, model.layout
    dphi = 1.0 / model.ratio - s1.z1 / s1.z2 * (1.0 - 1.0 / model.ratio)
    qdd = np.zeros(model.n_dof)
    q = nominal_q(model, input_rad)
    disc = lay["disc"]
    for d in range(model.n_disc):
        i = disc.index(d)
        qdd[i:i + 2] = -dphi ** 2 * q[i:i + 2]
    return qdd


def turn_shift(model: ReducerModel) -> np.ndarray:
    """Exact change of q when the input turns one period 2 pi i (the carrier one revolution):
    carrier and discs +2 pi, eccentrics 2 pi (1 - zp), mesh deflection and translations unchanged.
    The whole mechanism (pins, mesh phase z1 (th - q0) / 2 pi, cranks) repeats after it."""
    lay = model.layout
    shift = np.zeros(model.n_dof)
    shift[model.i_out] = 2 * np.pi
    shift[lay["crank_rotation"].slice] = 2 * np.pi * (1 - model.case.cycloid.zp)
    shift[lay["disc"].indices("rot")] = 2 * np.pi
    return shift


def _reduce(model: ReducerModel, input_rad: float) -> tuple[float, int]:
    """(input angle within one period 2 pi i of 0, whole periods removed): keeps the kernels'
    trigonometry and the mesh deflection rb1 (th - q0) + rb2 (phi - q0) free of cancellation."""
    turns = int(np.round(input_rad / (2 * np.pi * model.ratio)))
    return input_rad - turns * 2 * np.pi * model.ratio, turns


def _min_gap_m(model: ReducerModel, q: np.ndarray, input_rad: float, w) -> float:
    evaluate(model, q, input_rad, w=w)
    return float(w.gap.min())


def _rigid_pose(model: ReducerModel, input_rad: float, carrier_rad: float) -> np.ndarray:
    """Rigid-body pose (input held, mesh rigid, crank axes on their seats) at a given carrier
    angle, with each disc placed by the least-squares (2D Kabsch) fit of its crank holes onto the
    actual eccentric centres: exact for ideal geometry, first order with crank errors."""
    lay, nc = model.layout, model.n_crank
    q = np.zeros(model.n_dof)
    q[model.i_out] = carrier_rad
    phi = _crank_phase(model, input_rad, carrier_rad)
    q[lay["crank_rotation"].slice] = phi
    p = model.params("needle")
    seat = p.seat_radius_m[:, None] * np.column_stack([np.cos(carrier_rad + p.seat_angle_rad),
                                                       np.sin(carrier_rad + p.seat_angle_rad)])
    hole = p.hole_radius_m[:, None] * np.column_stack([np.cos(p.hole_angle_rad), np.sin(p.hole_angle_rad)])
    hc = hole.mean(axis=0)                                             # disc frame, at rotation 0
    disc = lay["disc"]
    for d in range(model.n_disc):
        X = seat + p.ecc_m[d][:, None] * np.array([[math.cos(phi + ph), math.sin(phi + ph)]
                                                   for ph in p.ecc_phase_rad[d]])
        Xc = X.mean(axis=0)
        u, x = hole - hc, X - Xc
        # rotation minimising sum |x - Rot(g) u|^2, near the carrier angle (holes may be symmetric)
        g = math.atan2(np.sum(u[:, 0] * x[:, 1] - u[:, 1] * x[:, 0]), np.sum(u[:, 0] * x[:, 0] + u[:, 1] * x[:, 1]))
        g = carrier_rad + math.remainder(g - carrier_rad, 2 * np.pi) if nc > 1 else carrier_rad
        cg, sg = math.cos(g), math.sin(g)
        i = disc.index(d)
        q[i:i + 2] = Xc - np.array([cg * hc[0] - sg * hc[1], sg * hc[0] + cg * hc[1]])
        q[i + 2] = g
    return q


def kinematic_q(model: ReducerModel, input_rad: float, flank: int = +1) -> np.ndarray:
    """Zero-load pose: the rigid-body pose of `_rigid_pose` with the output turned (input held)
    until the first pin of the loaded flank just touches (smallest gap = 0 to 1e-12 m).
    flank +1 is the flank a positive record torque loads (output lagging forward motion), -1
    the other. With an interference (negative gap) in the centred pose the output is turned the
    other way until it opens; with interference on both flanks (no backlash) the centred pose is kept."""
    check_direction(flank)
    centre = input_rad / model.ratio
    w = model.work()

    def gap(lag):
        return _min_gap_m(model, _rigid_pose(model, input_rad, centre - flank * lag), input_rad, w)

    g0 = gap(0.0)
    sign = 1.0 if g0 > 0 else -1.0       # turn toward the flank to close, away to open
    lo, hi, step = 0.0, None, 1e-6
    while step <= FLANK_SEARCH_RAD:
        if (gap(sign * step) > 0) != (g0 > 0):
            hi = step
            break
        lo, step = step, 2 * step
    if hi is None:
        return _rigid_pose(model, input_rad, centre)
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        if (gap(sign * mid) > 0) == (g0 > 0):
            lo = mid
        else:
            hi = mid
        if hi - lo < 1e-13:
            break
    # the side with gap >= 0: touching, not yet loaded
    return _rigid_pose(model, input_rad, centre - flank * sign * (lo if g0 > 0 else hi))


NEWTON_MAX_ITER = 100


def _tol(T: float) -> float:
    return STATIC_TOL_N * max(1.0, abs(T) / 100)


def _newton(model, input_rad, T, q0, w, max_iter=NEWTON_MAX_ITER):
    return kn.static_solve(q0.copy(), float(input_rad), float(T), model.arrays, w, model.scale, max_iter, _tol(T))


def _branch_rad(model: ReducerModel) -> float:
    """Newton can land on the next tooth (the profile is periodic: the disc one pin pitch on is also
    an equilibrium). Windup plus backlash stay far below a quarter pin pitch of output rotation."""
    return 0.25 * 2 * np.pi / model.case.cycloid.zp


def _on_branch(model: ReducerModel, th: float, q: np.ndarray) -> bool:
    return abs(q[model.i_out] - th / model.ratio) < _branch_rad(model)


def _applied(model: ReducerModel, record_torque_Nm: float, flank: int) -> float:
    """The torque solved for: a record torque below ZERO_LOAD_FRACTION x rated is that vanishing
    preload on `flank` (see `solve_static`)."""
    T = float(record_torque_Nm)
    floor = ZERO_LOAD_FRACTION * model.case.rated_torque_Nm
    return flank * floor if abs(T) < floor else T


def _continuation(model, th, T, qk, w):
    """Torque continuation 0 -> T from the touching pose qk, adaptive steps: (q, iterations, status)."""
    q, frac, dfrac, total, status = qk, 0.0, 1.0 / 16, 0, 1
    for _ in range(CONTINUATION_MAX_SOLVES):
        nxt = min(1.0, frac + dfrac)
        qn, it, status = _newton(model, th, nxt * T if nxt < 1 else T, q, w)
        total += it
        if status == 0 and _on_branch(model, th, qn):
            q, frac, dfrac = qn, nxt, 2 * dfrac
            if frac >= 1.0:
                break
        else:
            dfrac /= 4
            if dfrac < 1e-6:
                break
    return q, total, 0 if frac >= 1.0 else max(status, 1)


def _from_above(model, th, T, qk, w):
    """The zero-load state as the limit of the loaded flank: torque 1000 T, 100 T, 10 T, T, each
    warm-started from the last (q, iterations, status). Needed where the rigid touching pose is not
    touching in the elastic one: a build whose cranks fight (per-crank eccentricity or timing errors)
    deforms under its own internal preload and opens the flank by a fraction of a micrometre; the
    vanishing preload T cannot cross that free play, since the work it does there is below the
    potential's consistency error (PI_RTOL of the stored internal energy), so Newton finds no
    acceptable step (rv160n stand-in with a fitted crank pattern, 0 N m: status 2)."""
    q, total, status = qk, 0, 1
    for k in (3, 2, 1, 0):
        q, it, status = _newton(model, th, T * 10.0 ** k, q, w)
        total += it
        if status != 0 or not _on_branch(model, th, q):
            return q, total, max(status, 3)
    return q, total, status


def static_q(model: ReducerModel, input_rad: float, record_torque_Nm: float, q0,
            flank: int = +1, w=None, period_shift: np.ndarray | None = None,
            seed: np.ndarray | None = None) -> tuple[np.ndarray, int]:
    """State vector q of the static equilibrium at input_rad [rad] under the record torque, robust by
    construction (see `solve_static`; flank the zero-load flank): returns (q, iterations).
    q0: a warm start (the caller's guess, e.g. the last solution; a callable is called only when
    reached), or None. seed: a nearby model's equilibrium at this angle, tried first
    (`static_path`). period_shift: `turn_shift(model)` when the caller has it."""
    w = model.work() if w is None else w
    th, turns = _reduce(model, input_rad)
    shift = turns * (turn_shift(model) if period_shift is None else period_shift)
    floor = ZERO_LOAD_FRACTION * model.case.rated_torque_Nm
    T = _applied(model, record_torque_Nm, flank)     # zero load: vanishing preload on the given flank
    flank = 1 if T > 0 else -1
    total = 0
    for g in (seed, q0):                 # warm starts
        g = g() if callable(g) else g
        if g is None:
            continue
        q, it, status = _newton(model, th, T, np.asarray(g, float) - shift, w)
        total += it
        if status == 0 and _on_branch(model, th, q):
            return q + shift, total
    qk = kinematic_q(model, th, flank)
    q, it, status = _newton(model, th, T, qk, w)
    total += it
    if status == 0 and not _on_branch(model, th, q):
        status = 3                       # a neighbouring tooth's equilibrium: approach it gradually
    if status != 0:
        q, it, status = _continuation(model, th, T, qk, w)
        total += it
    if status != 0 and abs(T) <= floor:
        q, it, status = _from_above(model, th, T, qk, w)
        total += it
    if status != 0:
        raise DynamicsError(f"static equilibrium not found at input {np.rad2deg(input_rad):.6g} deg, "
                            f"torque {record_torque_Nm:.4g} N m (status {status} after {total} iterations, "
                            f"torque continuation included); check the case's clearances and errors "
                            f"(an interference larger than the stiffness laws' range?)")
    return q + shift, total


def _state(model: ReducerModel, q: np.ndarray, input_rad: float, torque: float, it: int) -> StaticState:
    w, tau = evaluate(model, q, input_rad)
    disc, rot = model.layout["disc"], model.layout["crank_rotation"]
    io = model.i_out
    return StaticState(input_angle_deg=float(np.rad2deg(input_rad)), torque_Nm=float(torque),
                       output_angle_deg=float(np.rad2deg(q[io])),
                       te_arcsec=float(np.rad2deg(q[io] - input_rad / model.ratio) * ARCSEC_PER_DEG),
                       pin_force_N=model.contacts(w.force), pin_gap_m=model.contacts(w.gap),
                       bearing_force_N=model.output(w, "bearing_force_N"),
                       mesh_force_N=model.output(w, "mesh_force_N"),
                       disc_pose=q[disc.slice].reshape(disc.count, disc.width).copy(),
                       crank_angle_rad=q[rot.slice].copy(), input_torque_Nm=tau, q=q.copy(), iterations=it)


def solve_static(model: ReducerModel, input_angle_deg: float, torque_Nm: float,
                 q_guess: np.ndarray | None = None, direction: int = +1) -> StaticState:
    """Static equilibrium at one input angle under an output torque (record convention:
    positive resists forward rotation). Carrier angle, pin forces, bearing forces, poses.

    Robust by construction, at any input angle and either sign of torque:
      1. the input angle is reduced by whole periods 2 pi i (the mechanism repeats exactly);
      2. q_guess (if given) is tried first by the damped Newton of `kernels.static_solve`;
      3. else (or if that fails) from `kinematic_q`: the rigid pose with the loaded flank
         (the flank the torque's sign loads) just touching, so no free play is left to cross;
      4. if that fails, torque continuation 0 -> T from the touching pose with adaptive steps.
      5. at zero load, if that fails too, the loaded flank's limit: 1000 T down to T (`_from_above`).
    Zero load: the output floats in the backlash, so |T| < ZERO_LOAD_FRACTION x rated is solved
    at that vanishing preload (4 mN m on the RV-40E: TE change < 0.01 arcsec) on the flank of
    `direction` (the flank of the direction of motion that a running reducer's drag closes);
    the state reports the torque asked for. Raises DynamicsError when no equilibrium is found."""
    check_direction(direction)
    th = math.radians(float(input_angle_deg))
    if not math.isfinite(th) or not math.isfinite(torque_Nm):
        raise DynamicsError(f"solve_static: input angle {input_angle_deg!r} deg and torque "
                            f"{torque_Nm!r} N m must be finite")
    q, it = static_q(model, th, torque_Nm, q_guess, direction)
    return _state(model, q, th, torque_Nm, it)


def quasi_static(model: ReducerModel, input_angle_deg, torque_Nm, direction: int = +1,
                 t_s=None, pin_forces: bool = True) -> TEResult:
    """A sequence of static equilibria (no inertia) along the input angles, warm-started.
    The applied output torque is direction * torque_Nm (record convention), as in `simulate`.
    t_s defaults to the time at the case's input speed (for records and spectra).
    pin_forces=False skips the per-point force evaluation (a third of the cost) when only the TE
    is wanted (the diagnosis): pin_force_N is then None and teeth_in_contact zeros."""
    check_direction(direction)
    th = np.deg2rad(np.atleast_1d(np.asarray(input_angle_deg, dtype=float)))
    T = direction * np.broadcast_to(np.asarray(torque_Nm, dtype=float), th.shape).astype(float)
    if not (np.all(np.isfinite(th)) and np.all(np.isfinite(T))):
        raise DynamicsError("quasi_static: input angles and torques must be finite")
    n = len(th)
    pf = np.zeros((n, model.n_disc, model.case.cycloid.zp))
    w = model.work()
    on_each = None
    if pin_forces:
        def on_each(i, q):
            evaluate(model, q, th[i], w=w)
            pf[i] = model.contacts(w.force)
    carrier, _ = static_path(model, th, T, direction, w=w, on_each=on_each)
    if t_s is None:
        speed = 6.0 * model.case.operation.input_speed_rpm
        t_s = np.concatenate([[0.0], np.cumsum(np.abs(np.diff(np.rad2deg(th)))) / speed])
    return te_result(model, np.asarray(t_s, float), th, carrier, T, (pf > 0).sum(axis=2),
                     pf if pin_forces else None, {"solver": "quasi_static", "direction": direction})


def static_path(model: ReducerModel, th_rad: np.ndarray, T: np.ndarray, direction: int = +1,
                seeds: np.ndarray | None = None, w=None, on_each=None,
                fallback_seeds: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The static equilibria along input angles th_rad [rad] under applied torques T (as solved by
    `static_q`, each warm-started): (carrier angles [rad], states Q (n, n_dof)). on_each(i, q) is
    called for each point in order once the path is solved.
    Warm starts: seeds[i] first when given (the equilibria of a nearby model at the same angles,
    e.g. the unperturbed model of a fit: 2.2 instead of 4 Newton iterations a point, measured on the
    RV-40E stand-in), then the rigid-body advance of the last solution (the solver falls back to the
    touching kinematic pose and torque continuation when neither converges on the branch). The
    result is the same equilibrium to the Newton tolerance STATIC_TOL_N whichever start succeeds.
    The seeds are tried in one kernel call (`kernels.static_seeded`), the points where they fail
    then solved in order as `static_q` would have after its seed; without seeds the advances run in
    the kernel (`kernels.static_advance`) and Python takes only the points where one fails.
    fallback_seeds: a second set of seeds (same shape), tried in one more kernel call at the points
    where `seeds` failed before the in-order solves (the fit's column predictor, then the last
    model's states: pipeline.diagnosis.simulate)."""
    n = len(th_rad)
    if seeds is not None and np.shape(seeds) != (n, model.n_dof):
        seeds = None                     # another layout's states: no use as a start
    if fallback_seeds is not None and np.shape(fallback_seeds) != (n, model.n_dof):
        fallback_seeds = None
    if seeds is None:
        seeds, fallback_seeds = fallback_seeds, None
    w = model.work() if w is None else w
    shift = turn_shift(model)
    Q = np.empty((n, model.n_dof))
    # _reduce, _applied and _tol of every point at once (the same operations in the same order: the
    # same bits; one by one they were ~10 % of a seeded path's time, the kernel the rest)
    th_rad = np.asarray(th_rad, float)
    turns = np.round(th_rad / (2 * np.pi * model.ratio)).astype(np.int64)
    th_red = th_rad - turns * 2 * np.pi * model.ratio
    shifts = (turns[:, None] * shift).reshape(n, model.n_dof)
    T_rec = np.asarray(T, float).reshape(n)
    floor = ZERO_LOAD_FRACTION * model.case.rated_torque_Nm
    Ts = np.where(np.abs(T_rec) < floor, direction * floor, T_rec)
    tols = STATIC_TOL_N * np.maximum(1.0, np.abs(Ts) / 100)
    args = (model.arrays, w, model.scale, NEWTON_MAX_ITER, _branch_rad(model), model.ratio)
    if seeds is not None:                # every seed tried in one kernel call (static_q's first try)
        Qs, done = kn.static_seeded(np.ascontiguousarray(seeds, float), shifts, th_red, Ts, tols, *args)
        if fallback_seeds is not None and not done.all():
            idx = np.flatnonzero(~done)
            Qf, ok = kn.static_seeded(np.ascontiguousarray(np.asarray(fallback_seeds, float)[idx]),
                                      np.ascontiguousarray(shifts[idx]), np.ascontiguousarray(th_red[idx]),
                                      np.ascontiguousarray(Ts[idx]), np.ascontiguousarray(tols[idx]), *args)
            Qs[idx[ok]] = Qf[ok]
            done[idx[ok]] = True
        Q[done] = Qs[done]
        q = None
        for i in range(n):
            if not done[i]:              # the seed failed: the rigid-body advance of the last solution
                guess = None if q is None else q + nominal_q(model, th_rad[i]) - nominal_q(model, th_rad[i - 1])
                Q[i], _ = static_q(model, th_rad[i], T[i], guess, direction, w, shift)
            q = Q[i]
    else:                                # the rigid-body advance of the last solution, in the kernel
        nominal = np.array([nominal_q(model, t) for t in th_rad]).reshape(n, model.n_dof)
        i = 0
        while i < n:                     # point i: no start (the first) or its advance failed
            Q[i], _ = static_q(model, th_rad[i], T[i], None, direction, w, shift)
            i = kn.static_advance(Q, i + 1, nominal, shifts, th_red, Ts, tols, *args)
    if on_each is not None:
        for i in range(n):
            on_each(i, Q[i])
    return Q[:, model.i_out].copy(), Q


def te_result(model, t, th_in, carrier, T, teeth, pf, meta) -> TEResult:
    out = model.measured_output_rad(carrier)
    te = np.rad2deg(out - th_in / model.ratio) * ARCSEC_PER_DEG
    return TEResult(t_s=t, input_angle_deg=np.rad2deg(th_in), output_angle_deg=np.rad2deg(out),
                    output_torque_Nm=T, te_arcsec=te, teeth_in_contact=teeth, pin_force_N=pf,
                    ratio=model.ratio, meta={"case": model.case.name, **meta})


def linearise(model: ReducerModel, state: StaticState) -> tuple[np.ndarray, np.ndarray]:
    """(K, M) of the model linearised about a static state (input held)."""
    w, _ = evaluate(model, state.q, math.radians(state.input_angle_deg), want_k=True)
    K = 0.5 * (w.K + w.K.T)
    return K, np.diag(model.mass)


def eigenfrequencies_Hz(model: ReducerModel, input_angle_deg: float = 0.0,
                        torque_Nm: float | None = None) -> np.ndarray:
    """Natural frequencies of the linearised model (default at rated torque), ascending."""
    from scipy.linalg import eigh
    T = model.case.rated_torque_Nm if torque_Nm is None else torque_Nm
    K, M = linearise(model, solve_static(model, input_angle_deg, T))
    lam = eigh(K, M, eigvals_only=True)
    return np.sqrt(np.maximum(lam, 0.0)) / (2 * np.pi)


def damping_beta_s(model: ReducerModel) -> float:
    """Stiffness-proportional damping coefficient beta = 2 zeta / omega_1 (see dynamics.model)."""
    zeta = model.case.dynamics.damping_ratio
    if zeta == 0:
        return 0.0
    f = eigenfrequencies_Hz(model)
    f1 = f[f > 1e-3][0]
    return 2.0 * zeta / (2 * np.pi * f1)
