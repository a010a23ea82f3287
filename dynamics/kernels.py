"""Numba solvers of the lumped reducer model: statics (damped Newton) and HHT-alpha time integration.

Pure functions of arrays. The model enters as one `dynamics.couplings.ModelArrays` (m) and one
`Work` (w) of reusable buffers; forces, tangents and damping come from `couplings.assemble`, so the
solvers know nothing of the couplings or of the DOF layout beyond the output DOF m.i_out (where
the load torque acts). SI units throughout (m, rad, N, N m, kg, s).

The time integration runs in chunks of steps (`integrate` from step a to step b) and resumes from
the returned state (`RunState` plus the Work's candidate-contact mask), so Python regains control
between chunks (signals, progress) and a chunked run is bit-identical to an unchunked one.

Bounded angles: the mechanism repeats exactly when the input turns one period 2 pi i (the carrier
one revolution; q changes by `shift`, `dynamics.statics.turn_shift`). The integration keeps the
input within half a period of zero by removing whole periods from the state as it goes (counted in
RunState.counts[2], added back to the recorded output angle), so every angle the couplings see
stays bounded however long the run: an accumulated angle loses the precision of its trigonometry
and of the pin foot-point Newton, whose 1e-14 rad test fails in 2e-4 of the calls at a parameter
of 3-5 pi and in 9 % beyond 20 pi (issue 12 item 5: every run failed after ~3 output revolutions).
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np

from dynamics.couplings import ALL, assemble, start_solve
from dynamics.couplings.base import kernel

# candidate contacts in the time integration: a contact more than CANDIDATE_MARGIN_M open at a
# refresh is skipped for the next CANDIDATE_REFRESH steps. The rigid-body gap rate is ~0.3 um/ms
# (13 um over half an eccentric turn at 7200 deg/s input) and the load-jump vibrations ~2 um: 5 um
# is safe at 1 ms between refreshes (the `missed` counter checks it on every run)
CANDIDATE_MARGIN_M = 5e-6
CANDIDATE_REFRESH = 10
# static Newton's last step taken unconfirmed (static_solve) where the error it leaves, bounded from
# the contraction of the steps before it, is below STATIC_TAIL_M (scaled metres: 2e-11 rad, 4e-6
# arcsec of rotation at ROT_SCALE_M = 0.05 m)
STATIC_TAIL_M = 1e-12
PI_RTOL = 1e-8     # static merit: relative drop of Pi that counts as progress (Pi is consistent to ~1e-9)
SUBSTEP_LEVELS = 6  # a failed step is retried as 2, 4, ... 2^(SUBSTEP_LEVELS - 1) sub-steps
# want_k and only for `assemble`: numpy scalars, typed as plain `bool` and `int64` (a literal
# True/False/-1 would be typed Literal[...] and compile the whole assembly again for each value:
# three copies of it, one per value and one for Python's calls, in the kernel unit's cold compile)
_YES, _NO, _ALL = np.bool_(True), np.bool_(False), np.int64(ALL)


class RunState(NamedTuple):
    """What a time integration carries from one chunk to the next (besides Work.active)."""
    q: np.ndarray              # (n,) last converged state
    v: np.ndarray
    acc: np.ndarray
    fn: np.ndarray             # (n,) total force at the last step (HHT-alpha needs it)
    sums: np.ndarray           # (4,) potential energy, input torque, input work, load work
    counts: np.ndarray         # (3,) int: Newton iterations, contacts missed by the candidate set,
                               #   whole mechanism periods removed from q (see the module doc)
    peak: np.ndarray           # (n_contacts,) largest contact force of the run so far [N]
    newton: np.ndarray         # (3,) the HHT Newton's last measured contraction (_hht_step), the
                               #   closed-contact signature (closed_set_signature) of the last step's
                               #   first iterate, and 1.0 where unconfirmed steps are allowed (0: every
                               #   step confirmed)


class Samples(NamedTuple):
    """Output arrays of a run, one row per sample (every `stride` steps, row 0 = start)."""
    q_out: np.ndarray          # (ns,) output rotation
    teeth: np.ndarray          # (ns, n_groups) int: contacts with force > 0 per group
    force: np.ndarray          # (ns or 1, n_contacts): contact forces when store_force
    tau_in: np.ndarray         # (ns,) input torque
    energy: np.ndarray         # (ns, 4) kinetic, potential, input work, load work (cumulative)


@kernel(inline=True)
def _lu_factor(A, piv):
    """In-place LU with partial pivoting of the square A (L unit lower, U upper), rows swapped as
    recorded in piv; False if a pivot is zero or not finite. The Newton matrices here are 30 x 30:
    LAPACK's gesv through np.linalg.solve spent ~15 us a call on copies, checks and calls, this ~4 us."""
    n = A.shape[0]
    for k in range(n):
        p, big = k, abs(A[k, k])
        for i in range(k + 1, n):
            if abs(A[i, k]) > big:
                p, big = i, abs(A[i, k])
        if not (big > 0.0 and big < np.inf):
            return False
        piv[k] = p
        if p != k:
            for j in range(n):
                A[k, j], A[p, j] = A[p, j], A[k, j]
        inv = 1.0 / A[k, k]
        for i in range(k + 1, n):
            lik = A[i, k] * inv
            A[i, k] = lik
            if lik != 0.0:
                for j in range(k + 1, n):
                    A[i, j] -= lik * A[k, j]
    return True


@kernel(inline=True)
def _lu_solve(A, piv, b):
    """x of A x = b from `_lu_factor`'s A and piv (b is overwritten and returned)."""
    n = A.shape[0]
    for k in range(n):
        p = piv[k]
        if p != k:
            b[k], b[p] = b[p], b[k]
    for i in range(n):
        s = b[i]
        for j in range(i):
            s -= A[i, j] * b[j]
        b[i] = s
    for i in range(n - 1, -1, -1):
        s = b[i]
        for j in range(i + 1, n):
            s -= A[i, j] * b[j]
        b[i] = s / A[i, i]
    return b


@kernel(inline=True)
def _static_residual(w, io, torque, scale):
    """Scaled residual of the static balance (internal force + load torque at io) and its 2-norm."""
    rs = w.f.copy()
    rs[io] -= torque
    rs = rs / scale
    return rs, np.sqrt(np.sum(rs * rs))


@kernel
def static_solve(q, th_in, torque, m, w, scale, max_iter, tol_N):
    """Static equilibrium: minimise the potential Pi = V(q) + torque q_out (frictionless couplings
    are conservative) by a Levenberg-Marquardt-damped Newton in scaled coordinates x = scale q
    (metres), its matrix the exact tangent K + K_rest (couplings.Work; dynamics.couplings.pin).
    Every contact is evaluated. Free play (backlash) is crossed by the damped steps. A step is
    accepted when Pi falls by more than its consistency error (PI_RTOL) or the residual
    norm falls. Returns (q, iterations, status 0 = converged, 1 = iteration limit, 2 = no
    acceptable step)."""
    n = q.shape[0]
    io = m.i_out
    v = np.zeros(n)
    start_solve(w)
    K = w.K
    A = np.empty((n, n))
    piv = np.zeros(n, np.int64)
    Kc = np.empty((n, n))
    # one assembly call site (each caller links the compiled assembly into its own machine code);
    # the first evaluation is the start, each later one a damped step's trial point
    qn, it, tries, mu = q, 0, -1, 0.0
    Pi, rs, norm2, norm = 0.0, np.zeros(n), 0.0, 0.0
    d_trial, d_prev, prev_first = 0.0, 0.0, False   # largest scaled step: of the pending trial, of
                                                    # the step that made q (and was it a first try)
    while True:
        Vn, _, okn = assemble(qn, v, th_in, 0.0, 0.0, _YES, m, w, _ALL)
        Pin = Vn + torque * qn[io]
        rsn, nn2 = _static_residual(w, io, torque, scale)
        fresh = True                     # a new iterate (or the start)
        if tries < 0:                    # the start
            q, rs, Pi, norm2 = qn, rsn, Pin, nn2
            norm = np.max(np.abs(rs))
            dmax = 0.0
            for i in range(n):
                dmax = max(dmax, K[i, i] / scale[i] ** 2)
            mu = 1e-6 * dmax + 1.0
            Kc[:, :] = w.K
            Kc += w.K_rest               # the exact tangent (couplings.Work.K_rest)
        # merit: Pi far from equilibrium (crosses free play, where the residual stays T), the
        # residual near it: the pin law's k(phase) is not differentiated in f, so Pi is only a
        # potential of f to ~1e-9 relative and a Pi-only test stalls (measured: rv40e-105 at 1 deg)
        elif okn and (Pin < Pi - PI_RTOL * (abs(Pi) + 1e-6) or nn2 < norm2):
            q, rs, Pi, norm2 = qn, rsn, Pin, nn2
            d_prev, prev_first = d_trial, tries == 1
            norm = np.max(np.abs(rsn))
            Kc[:, :] = w.K
            Kc += w.K_rest
            mu = max(mu / 10.0, 1e-9)
            it += 1
        else:
            fresh = False
            mu *= 8.0
            if tries == 60:              # no acceptable step at this iterate
                if norm < 1e3 * tol_N:
                    return q, it, 0
                return q, it, 2
        if fresh:                        # converged, or out of iterations?
            if norm < tol_N:
                return q, it, 0
            if it >= max_iter:
                return q, max_iter, 1 if norm > tol_N else 0
            tries = 0
        for i in range(n):
            for j in range(n):
                A[i, j] = Kc[i, j] / (scale[i] * scale[j])
            A[i, i] += mu
        if _lu_factor(A, piv):
            dx = _lu_solve(A, piv, rs.copy())
            d_trial = np.max(np.abs(dx))
            # Newton's tail: steps contracting at rate theta = d / d_prev leave an error of at most
            # d theta / (1 - theta) after this one (error-oriented, not quadratic: the contact laws'
            # tables and kinks make the last steps linear at ~1e-3); where that is below STATIC_TAIL_M
            # the step is taken without the assembly that would confirm its residual (a force
            # residual can then exceed tol_N along the stiff contacts: 1e-4 N at 1e9 N/m x 1e-13 m)
            if tries == 0 and it >= 1 and prev_first and d_trial < 0.5 * d_prev:
                theta = d_trial / d_prev
                if d_trial * theta / (1.0 - theta) < STATIC_TAIL_M:
                    return q + dx / scale, it + 1, 0
            qn = q + dx / scale
        else:                            # not finite: a rejected trial (more damping next)
            qn = np.full(n, np.nan)
        tries += 1


@kernel(inline=True)
def _solve_on_branch(q0, shift, th_in, torque, tol_N, m, w, scale, max_iter, branch_rad, ratio):
    """`static_solve` from the absolute state q0 at the reduced input th_in (q0 - shift, the whole
    periods removed): (solution + shift, converged with the output within branch_rad of
    th_in / ratio: dynamics.statics._on_branch)."""
    q, _, status = static_solve(q0 - shift, th_in, torque, m, w, scale, max_iter, tol_N)
    return q + shift, status == 0 and abs(q[m.i_out] - th_in / ratio) < branch_rad


@kernel
def static_seeded(seeds, shifts, th_in, torque, tol_N, m, w, scale, max_iter, branch_rad, ratio):
    """`_solve_on_branch` from each seed of a path (point i: seeds[i], shifts[i] at input th_in[i]
    under torque[i] to tol_N[i]): (Q, ok), Q[i] the solution where ok[i]. One call for the whole
    path: the per-point Python and dispatch cost of the fit's solves (dynamics.statics.static_path)
    goes; what fails here the caller solves point by point."""
    npt, n = seeds.shape
    Q = np.empty((npt, n))
    ok = np.zeros(npt, np.bool_)
    for i in range(npt):
        q, good = _solve_on_branch(seeds[i], shifts[i], th_in[i], torque[i], tol_N[i], m, w, scale, max_iter,
                                   branch_rad, ratio)
        if good:
            Q[i] = q
            ok[i] = True
    return Q, ok


@kernel
def static_advance(Q, i0, nominal, shifts, th_in, torque, tol_N, m, w, scale, max_iter, branch_rad, ratio):
    """Points i0, i0 + 1, ... of a static path, each from the rigid-body advance of the last
    solution (Q[i - 1] + nominal[i] - nominal[i - 1]; as `static_seeded` otherwise), written into Q;
    stops at the first point that does not converge on its branch and returns its index (len(Q):
    all done). The caller solves that point its robust way and calls again."""
    npt = Q.shape[0]
    for i in range(i0, npt):
        q, good = _solve_on_branch(Q[i - 1] + nominal[i] - nominal[i - 1], shifts[i], th_in[i], torque[i], tol_N[i],
                                   m, w, scale, max_iter, branch_rad, ratio)
        if not good:
            return i
        Q[i] = q
    return npt


_MIX1, _MIX2, _MIX3 = np.uint64(0x9E3779B97F4A7C15), np.uint64(0xBF58476D1CE4E5B9), np.uint64(0x94D049BB133111EB)
_MASK52 = np.uint64((1 << 52) - 1)


@kernel(inline=True)
def closed_set_signature(force):
    """A signature of the set of closed contacts (force > 0): the XOR of each closed index's SplitMix64
    hash, cut to 52 bits so that the float carrying it (RunState.newton[1]) holds it exactly. Any
    change of the set changes it but with probability 2^-52; a sum of indices (the first version)
    was blind to two swaps of equal index sums in one step."""
    h = np.uint64(0)
    for c in range(force.shape[0]):
        if force[c] > 0.0:
            z = np.uint64(c + 1) * _MIX1
            z = (z ^ (z >> np.uint64(30))) * _MIX2
            z = (z ^ (z >> np.uint64(27))) * _MIX3
            h ^= (z ^ (z >> np.uint64(31))) & _MASK52
    return float(h)


@kernel(inline=True)
def _hht_step(q, v, acc, fn, th1, w1, T1, h, alpha, beta, m, w, scale, max_iter, tol_m, Mdiag, J, piv, loose,
              confirm, newton):
    """One HHT-alpha step of size h; returns (q1, v1, a1, fn1, iterations, ok, V, tau).
    Newton on the acceleration; the second iteration reuses the first's factorized Jacobian (a
    modified-Newton iteration: no tangent assembly, no factorization) since the predictor lands
    within ~1e-9 m of the step's state, where the tangent barely changes; from the third on, every
    iteration takes a fresh Jacobian (a contact that opened or closed inside the step).
    Unless `confirm` (or newton[2] == 0), the first correction is taken without the second
    iteration's assembly where the contraction newton[0] last measured bounds what it leaves below
    tol_m and the predictor closes the same contacts as the last step's did (newton[1])."""
    n = q.shape[0]
    bet = 0.25 * (1.0 + alpha) ** 2
    gam = 0.5 + alpha
    qp = q + h * v + h * h * (0.5 - bet) * acc
    vp = v + h * (1.0 - gam) * acc
    a = acc.copy()
    fext = np.zeros(n)
    fext[m.i_out] = -T1
    f, K, C = w.f, w.K, w.C       # locals: no struct access inside the loops
    d0 = 0.0
    for it in range(max_iter):
        qn = qp + bet * h * h * a
        vn = vp + gam * h * a
        fresh = it != 1
        V, tau, ok = assemble(qn, vn, th1, w1, beta, fresh, m, w, _ALL)
        if not ok:
            return q, v, acc, fn, it + 1, False, 0.0, 0.0
        if it == 0:                      # which contacts are closed at the predictor
            sig = closed_set_signature(w.force)
            if sig != newton[1]:
                confirm = True           # a contact closed or opened since the last step
            newton[1] = sig
        res = Mdiag * a - (1.0 - alpha) * (f + fext) - alpha * fn
        if fresh:
            for i in range(n):
                for j in range(n):
                    J[i, j] = (1.0 - alpha) * (gam * h * C[i, j] + bet * h * h * K[i, j])
                J[i, i] += Mdiag[i]
            if not _lu_factor(J, piv):
                return q, v, acc, fn, it + 1, False, 0.0, 0.0
        da = _lu_solve(J, piv, -res)
        if not np.all(np.isfinite(da)):
            return q, v, acc, fn, it + 1, False, 0.0, 0.0
        dq = 0.0
        for i in range(n):
            dq = max(dq, abs(da[i]) * bet * h * h * scale[i])
        # converged: the iterate just evaluated is the step's state (its correction is below tol_m),
        # so force, energy and contact forces come from that evaluation and need no assembly of
        # their own (one of ~3.1 a step). Last resort (finest sub-step): a Newton limit cycle at a
        # contact kink is accepted once its corrections fall below 100 tol (1e-9 m); counted in the
        # iteration statistics
        if it == 1:
            newton[0] = dq / d0 if d0 > 0.0 else 1.0
        if dq < tol_m or (loose and it >= max_iter // 2 and dq < 100.0 * tol_m):
            return qn, vn, a, f + fext, it + 1, True, V, tau
        if it == 0:
            d0 = dq
            theta = newton[0]
            # unconfirmed step: the correction is applied without the assembly that would confirm
            # it where the contraction last measured (theta = dq1 / dq0 of a confirmed step, the
            # same contact set) bounds the error left, dq theta / (1 - theta), below tol_m: the
            # criterion a confirmed step applies, predicted. Force at the new state from the
            # tangent (K, C of this iterate); energy, input torque and contact forces stay this
            # iterate's (O(dq) off; every sample step is confirmed, so the records are exact)
            if not confirm and newton[2] > 0.0 and theta < 0.5 and dq * theta / (1.0 - theta) < tol_m:
                a += da
                dqv = bet * h * h * da
                dvv = gam * h * da
                f1 = f + fext - K @ dqv - C @ dvv
                return qp + bet * h * h * a, vp + gam * h * a, a, f1, 1, True, V, tau
        a += da
    return q, v, acc, fn, max_iter, False, 0.0, 0.0


@kernel
def integrate_start(st, th0, w0, T0, beta, Mdiag, m, w):
    """Initial force and acceleration of a run at rest or in motion from st.q, st.v (every contact
    evaluated); fills st.acc, st.fn, st.sums (potential, input torque) and w."""
    start_solve(w)
    V, tau, ok = assemble(st.q, st.v, th0, w0, beta, _NO, m, w, _ALL)
    st.fn[:] = w.f
    st.fn[m.i_out] -= T0
    st.acc[:] = st.fn / Mdiag
    st.sums[0], st.sums[1] = V, tau
    st.peak[:] = w.force
    return ok


@kernel(inline=True)
def _refresh_candidates(q, v, th, w_in, beta, m, w):
    """Every contact evaluated at the last converged state; those more than CANDIDATE_MARGIN_M
    open are skipped until the next refresh. Returns how many were closed but skipped."""
    active, gap = w.active, w.gap
    prev = active.copy()
    active[:] = True
    assemble(q, v, th, w_in, beta, _NO, m, w, _ALL)
    missed = 0
    for c in range(gap.shape[0]):
        if gap[c] < 0.0 and not prev[c]:
            missed += 1
        active[c] = gap[c] < CANDIDATE_MARGIN_M
    return missed


@kernel(inline=True)
def _record(si, q, v, V, tau, win, wload, Mdiag, m, w, out, store_force, q_out_offset):
    out.q_out[si] = q[m.i_out] + q_out_offset
    out.tau_in[si] = tau
    teeth, force, group = out.teeth, w.force, m.contact_group
    teeth[si, :] = 0
    for c in range(force.shape[0]):
        if force[c] > 0.0 and group[c] >= 0:
            teeth[si, group[c]] += 1
    if store_force:
        out.force[si, :] = force
    ek = 0.0
    for i in range(q.shape[0]):
        ek += 0.5 * Mdiag[i] * v[i] * v[i]
    out.energy[si, 0], out.energy[si, 1] = ek, V
    out.energy[si, 2], out.energy[si, 3] = win, wload


@kernel(inline=True)
def _advance(q, v, acc, fn, step, th_arr, th_off, w_arr, T_arr, dt, alpha, beta, m, w, scale, max_iter,
             tol_m, Mdiag, J, piv, confirm, newton):
    """Step `step` (th_arr[step - 1] -> th_arr[step], less th_off: the periods removed from q); a
    step whose Newton iteration does not converge (contact onset inside the step) is retried as 2,
    4, ... sub-steps (input and load interpolated linearly inside the step). Returns (q, v, acc,
    fn, V, tau, iterations, ok)."""
    V, tau, its_all = 0.0, 0.0, 0
    for level in range(SUBSTEP_LEVELS):
        nsub = 1 << level
        qs, vs, as_, fs = q.copy(), v.copy(), acc.copy(), fn.copy()
        good = True
        for sub in range(nsub):
            s1 = (sub + 1.0) / nsub
            th1 = (th_arr[step - 1] - th_off) + s1 * (th_arr[step] - th_arr[step - 1])
            w1 = w_arr[step - 1] + s1 * (w_arr[step] - w_arr[step - 1])
            T1 = T_arr[step - 1] + s1 * (T_arr[step] - T_arr[step - 1])
            qs, vs, as_, fs, its, okk, V, tau = _hht_step(
                qs, vs, as_, fs, th1, w1, T1, dt / nsub, alpha, beta, m, w, scale, max_iter, tol_m,
                Mdiag, J, piv, level == SUBSTEP_LEVELS - 1, confirm or level > 0, newton)
            its_all += its
            if not okk:
                good = False
                break
        if good:
            return qs, vs, as_, fs, V, tau, its_all, True
    return q, v, acc, fn, V, tau, its_all, False


@kernel
def integrate(st, step_from, step_to, th_arr, w_arr, T_arr, dt, stride, alpha, beta, m, w, scale,
              max_iter, tol_m, Mdiag, out, store_force, shift, period):
    """HHT-alpha (alpha in [0, 1/3]; 0 = trapezoidal rule) with a Newton per step (_hht_step), steps
    step_from .. step_to - 1 of a run whose step n goes from th_arr[n - 1] to th_arr[n] (step 0:
    the start, recorded only; `integrate_start` first). Samples every `stride` steps into `out`.
    Only candidate contacts enter the Newton iterations (see CANDIDATE_MARGIN_M), refreshed every
    CANDIDATE_REFRESH steps; st.counts[1] counts contacts found closed at a refresh that had been
    skipped (a margin too small: expected 0). st is updated to the last converged step.
    Whole mechanism periods (input `period` [rad], state `shift`; period 0: none) are removed from
    q whenever the input leaves (-period / 2, period / 2] (module doc); st.counts[2] counts them,
    st.q is the reduced state. st.peak keeps each contact's largest force.
    Returns (last step done, status 0 = done, 1 = Newton failed at the step after it)."""
    n = st.q.shape[0]
    q, v, acc, fn = st.q.copy(), st.v.copy(), st.acc.copy(), st.fn.copy()
    V, tau, win, wload = st.sums[0], st.sums[1], st.sums[2], st.sums[3]
    turns = st.counts[2]
    peak = st.peak
    J = np.zeros((n, n))
    piv = np.zeros(n, np.int64)
    status, last = 0, step_to - 1
    for step in range(step_from, step_to):
        if period > 0.0:
            rel = th_arr[step] - turns * period
            while rel > 0.5 * period:
                q = q - shift
                turns += 1
                rel -= period
            while rel <= -0.5 * period:
                q = q + shift
                turns -= 1
                rel += period
        th_off = turns * period
        if step > 0 and step % CANDIDATE_REFRESH == 0:
            st.counts[1] += _refresh_candidates(q, v, th_arr[step - 1] - th_off, w_arr[step - 1], beta, m, w)
        if step > 0:
            p_in0 = tau * w_arr[step - 1]
            p_ld0 = -T_arr[step - 1] * v[m.i_out]
            confirm = step % stride == 0 or step % CANDIDATE_REFRESH == 0
            q, v, acc, fn, V, tau, its, done = _advance(q, v, acc, fn, step, th_arr, th_off, w_arr, T_arr, dt,
                                                        alpha, beta, m, w, scale, max_iter, tol_m, Mdiag, J, piv,
                                                        confirm, st.newton)
            st.counts[0] += its
            if not done:
                status, last = 1, step - 1
                break
            win += 0.5 * dt * (p_in0 + tau * w_arr[step])
            wload += 0.5 * dt * (p_ld0 - T_arr[step] * v[m.i_out])
            force = w.force
            for c in range(force.shape[0]):
                if force[c] > peak[c]:
                    peak[c] = force[c]
        if step % stride == 0:
            _record(step // stride, q, v, V, tau, win, wload, Mdiag, m, w, out, store_force,
                    turns * shift[m.i_out])
    st.counts[2] = turns
    st.q[:], st.v[:], st.acc[:], st.fn[:] = q, v, acc, fn
    st.sums[0], st.sums[1], st.sums[2], st.sums[3] = V, tau, win, wload
    return last, status
