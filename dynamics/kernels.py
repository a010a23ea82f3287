"""Numba kernels of the lumped reducer model: coupling forces, tangents, HHT-alpha and statics.

Pure functions of arrays (no case objects); `dynamics.model` packs the arrays and documents the
physics. SI units throughout (m, rad, N, N m, kg, s).

DOF layout (n = 1 + 3 nc + 3 nd):
  0                      carrier (output) rotation
  1 .. nc                crank rotation = eccentric angle of disc 1 in the ground frame
  1+nc+2j, 2+nc+2j       crank j axis displacement from its carrier seat (ground frame)
  1+3nc+3d + (0, 1, 2)   disc d centre x, y and rotation
Couplings (potential V, force = -grad V, stiffness-proportional damping beta * k_t * rate):
  mesh j     V = k_s(s) d^2 / 2, d = rb1 (th_in - q0) + rb2 (phi_j - q0), s the mesh phase
  support j  V = k_sup max(|u_j| - c_sup, 0)^2 / 2
  needle jd  V = k_ta max(|X_ecc - X_hole| - c_ta, 0)^(n+1) / (n+1)
  pin kd     V = k(phase) max(-gap, 0)^(n+1) / (n+1), gap from the foot point on the profile
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

# geo vector indices
G_R, G_RR, G_E, G_ZP, G_ND, G_NC = 0, 1, 2, 3, 4, 5
G_KTA, G_NTA, G_CTA, G_KSUP, G_CSUP = 6, 7, 8, 9, 10
G_KM, G_MVAR, G_MEPS, G_RB1, G_RB2, G_Z1, G_KTOR, G_BETA = 11, 12, 13, 14, 15, 16, 17, 18
N_GEO = 19
# crank table columns: axis radius, axis angle, eccentricity (both discs), hole radius, mesh phase
# offset, extra eccentricity of disc 1's eccentric only (disc d's radius: C_ECC + (d == 0) C_DE1)
C_A, C_B, C_ECC, C_H, C_PH, C_DE1 = 0, 1, 2, 3, 4, 5
MESH_EDGE = 0.02   # smoothing width of the single/double contact edges [fraction of a pitch]
# candidate pins in the time integration: a pin more than CANDIDATE_MARGIN_M open at a refresh is
# skipped for the next CANDIDATE_REFRESH steps. The rigid-body gap rate is ~0.3 um/ms (13 um over
# half an eccentric turn at 7200 deg/s input) and the load-jump vibrations ~2 um: 5 um is safe
# at 1 ms between refreshes (the `missed` counter checks it on every run)
CANDIDATE_MARGIN_M = 5e-6
CANDIDATE_REFRESH = 10
PI_RTOL = 1e-8     # static merit: relative drop of Pi that counts as progress (Pi is consistent to ~1e-9)


@njit(cache=True)
def _interp(x, xs, ys):
    if x <= xs[0]:
        return ys[0]
    n = xs.shape[0]
    if x >= xs[n - 1]:
        return ys[n - 1]
    lo, hi = 0, n - 1
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if xs[mid] <= x:
            lo = mid
        else:
            hi = mid
    w = (x - xs[lo]) / (xs[hi] - xs[lo])
    return ys[lo] * (1.0 - w) + ys[hi] * w


@njit(cache=True)
def foot_point(px, py, R, E, zp, t):
    """Foot parameter on c(t) = (R cos t - E cos zp t, -R sin t + E sin zp t) nearest (px, py),
    Newton from t; returns (t, signed distance along the outward normal, nx, ny, ok)."""
    ok = False
    for _ in range(30):
        czt, szt = math.cos(zp * t), math.sin(zp * t)
        ct, st = math.cos(t), math.sin(t)
        cx, cy = R * ct - E * czt, -R * st + E * szt
        dx, dy = -R * st + E * zp * szt, -R * ct + E * zp * czt
        ddx, ddy = -R * ct + E * zp * zp * czt, R * st - E * zp * zp * szt
        rx, ry = cx - px, cy - py
        g = rx * dx + ry * dy
        h = dx * dx + dy * dy + rx * ddx + ry * ddy
        if h <= 0.0:
            h = dx * dx + dy * dy
        step = -g / h
        if step > 0.02:
            step = 0.02
        elif step < -0.02:
            step = -0.02
        t += step
        if abs(step) < 1e-14:
            ok = True
            break
    czt, szt = math.cos(zp * t), math.sin(zp * t)
    ct, st = math.cos(t), math.sin(t)
    cx, cy = R * ct - E * czt, -R * st + E * szt
    dx, dy = -R * st + E * zp * szt, -R * ct + E * zp * czt
    nd = math.sqrt(dx * dx + dy * dy)
    nx, ny = dy / nd, -dx / nd      # outward normal: tangent turned -90 deg... for a clockwise curve
    nx, ny = -nx, -ny
    s = (px - cx) * nx + (py - cy) * ny
    return t, s, nx, ny, ok


DAMP_RAMP_M = 1e-7   # contact damping ramps in over 0.1 um of approach (ADAMS IMPACT convention)


@njit(cache=True)
def _ramp(x):
    """Cubic STEP(x, 0, 0, DAMP_RAMP_M, 1): damping that vanishes at first touch (no force jump)."""
    if x >= DAMP_RAMP_M:
        return 1.0
    if x <= 0.0:
        return 0.0
    d = x / DAMP_RAMP_M
    return d * d * (3.0 - 2.0 * d)


@njit(cache=True)
def _mesh_h(s, eps):
    """Smoothed double-contact indicator over one mesh pitch and its derivative d/ds."""
    f = eps - 1.0
    if f <= 0.0 or f >= 1.0:
        return f, 0.0
    d = s - math.floor(s) - 0.5 * f
    d = d - math.floor(d + 0.5)
    a = abs(d)
    sg = 1.0 if d >= 0.0 else -1.0
    th = math.tanh((a - 0.5 * f) / MESH_EDGE)
    return 0.5 * (1.0 - th), -0.5 * (1.0 - th * th) / MESH_EDGE * sg


@njit(cache=True)
def assemble(q, v, th_in, w_in, geo, pins, cranks, law, drot, tws, want_k,
             f, K, C, pin_f, pin_g, bear, mesh_f):
    """Internal generalized force f (on the system), tangent K = -df/dq, damping C = -df/dv.
    Fills pin_f/pin_g (nd, zp), bear (nd, nc, 2) force on disc, mesh_f (nc). Returns
    (potential energy, input torque, ok). Every pin of every disc is evaluated."""
    return _assemble(q, v, th_in, w_in, geo, pins, cranks, law, drot, tws, want_k,
                     f, K, C, pin_f, pin_g, bear, mesh_f, np.ones(pin_f.shape, np.bool_))


@njit(cache=True)
def _assemble(q, v, th_in, w_in, geo, pins, cranks, law, drot, tws, want_k,
              f, K, C, pin_f, pin_g, bear, mesh_f, active):
    """`assemble` restricted to the pins where active[d, k] (the others are known to be open:
    pin_f = 0, pin_g left as it was)."""
    nd, nc = int(geo[G_ND]), int(geo[G_NC])
    zp = geo[G_ZP]
    beta = geo[G_BETA]
    f[:] = 0.0
    if want_k:
        K[:, :] = 0.0
        C[:, :] = 0.0
    V = 0.0
    tau_in = 0.0
    ok = True
    # --- involute mesh, in series with the crank torsion ---
    rb1, rb2, z1 = geo[G_RB1], geo[G_RB2], geo[G_Z1]
    for j in range(nc):
        s = z1 * (th_in - q[0]) / (2.0 * math.pi) + cranks[j, C_PH]
        h, dh = _mesh_h(s, geo[G_MEPS])
        km = geo[G_KM] * (1.0 + geo[G_MVAR] * (h - (geo[G_MEPS] - 1.0)))
        dkm = geo[G_KM] * geo[G_MVAR] * dh
        ks = 1.0 / (1.0 / km + rb2 * rb2 / geo[G_KTOR])
        dks = (ks / km) ** 2 * dkm               # d ks / d s
        d = rb1 * (th_in - q[0]) + rb2 * (q[1 + j] - q[0])
        dd = rb1 * (w_in - v[0]) + rb2 * (v[1 + j] - v[0])
        F = ks * d + beta * ks * dd
        ds0 = -z1 / (2.0 * math.pi)
        g0, gj = -(rb1 + rb2), rb2
        f[0] -= F * g0 + 0.5 * d * d * dks * ds0
        f[1 + j] -= F * gj
        tau_in += F * rb1 - 0.5 * d * d * dks * ds0
        V += 0.5 * ks * d * d
        mesh_f[j] = F
        if want_k:
            K[0, 0] += ks * g0 * g0
            K[0, 1 + j] += ks * g0 * gj
            K[1 + j, 0] += ks * g0 * gj
            K[1 + j, 1 + j] += ks * gj * gj
            C[0, 0] += beta * ks * g0 * g0
            C[0, 1 + j] += beta * ks * g0 * gj
            C[1 + j, 0] += beta * ks * g0 * gj
            C[1 + j, 1 + j] += beta * ks * gj * gj
    # --- crank supports (shaft bending in series with the support bearings), radial clearance ---
    ksup, csup = geo[G_KSUP], geo[G_CSUP]
    for j in range(nc):
        iu = 1 + nc + 2 * j
        ux, uy = q[iu], q[iu + 1]
        r = math.sqrt(ux * ux + uy * uy)
        if csup <= 0.0:
            f[iu] -= ksup * ux + beta * ksup * v[iu]
            f[iu + 1] -= ksup * uy + beta * ksup * v[iu + 1]
            V += 0.5 * ksup * r * r
            if want_k:
                K[iu, iu] += ksup
                K[iu + 1, iu + 1] += ksup
                C[iu, iu] += beta * ksup
                C[iu + 1, iu + 1] += beta * ksup
        elif r > csup:
            ex, ey = ux / r, uy / r
            x = r - csup
            fr = ksup * x / r
            rd = ex * v[iu] + ey * v[iu + 1]
            Fx = ksup * x * ex + beta * (ksup * rd * ex + fr * (v[iu] - rd * ex))
            Fy = ksup * x * ey + beta * (ksup * rd * ey + fr * (v[iu + 1] - rd * ey))
            f[iu] -= Fx
            f[iu + 1] -= Fy
            V += 0.5 * ksup * x * x
            if want_k:
                kxx = ksup * ex * ex + fr * (1.0 - ex * ex)
                kxy = ksup * ex * ey - fr * ex * ey
                kyy = ksup * ey * ey + fr * (1.0 - ey * ey)
                K[iu, iu] += kxx
                K[iu, iu + 1] += kxy
                K[iu + 1, iu] += kxy
                K[iu + 1, iu + 1] += kyy
                C[iu, iu] += beta * kxx
                C[iu, iu + 1] += beta * kxy
                C[iu + 1, iu] += beta * kxy
                C[iu + 1, iu + 1] += beta * kyy
    # --- turning-arm (needle) bearings: eccentric j of disc d in crank hole j ---
    kta, nta, cta = geo[G_KTA], geo[G_NTA], geo[G_CTA]
    idx = np.empty(7, np.int64)
    Gm = np.empty((2, 7))
    gr = np.empty(7)
    for d in range(nd):
        ib = 1 + 3 * nc + 3 * d
        for j in range(nc):
            iu = 1 + nc + 2 * j
            a, b, ecc, hr = cranks[j, C_A], cranks[j, C_B], cranks[j, C_ECC], cranks[j, C_H]
            if d == 0:
                ecc += cranks[j, C_DE1]
            pe = q[1 + j] + math.pi * d
            ca, sa = math.cos(q[0] + b), math.sin(q[0] + b)
            ce, se = math.cos(pe), math.sin(pe)
            ch, sh = math.cos(q[ib + 2] + b), math.sin(q[ib + 2] + b)
            Dx = a * ca + q[iu] + ecc * ce - q[ib] - hr * ch
            Dy = a * sa + q[iu + 1] + ecc * se - q[ib + 1] - hr * sh
            idx[0], idx[1], idx[2], idx[3] = 0, 1 + j, iu, iu + 1
            idx[4], idx[5], idx[6] = ib, ib + 1, ib + 2
            Gm[0, 0], Gm[1, 0] = -a * sa, a * ca
            Gm[0, 1], Gm[1, 1] = -ecc * se, ecc * ce
            Gm[0, 2], Gm[1, 2], Gm[0, 3], Gm[1, 3] = 1.0, 0.0, 0.0, 1.0
            Gm[0, 4], Gm[1, 4], Gm[0, 5], Gm[1, 5] = -1.0, 0.0, 0.0, -1.0
            Gm[0, 6], Gm[1, 6] = hr * sh, -hr * ch
            r = math.sqrt(Dx * Dx + Dy * Dy) + 1e-300
            ex, ey = Dx / r, Dy / r
            x = r - cta
            bear[d, j, 0] = 0.0
            bear[d, j, 1] = 0.0
            if x <= 0.0:
                continue
            F = kta * x ** nta
            kt = nta * kta * x ** (nta - 1.0)
            fr = F / r
            rb = beta * (_ramp(x) if cta > 0.0 else 1.0)
            # viscous force beta * K_t * D_dot, K_t the bearing's 2x2 tangent (continuous through D = 0)
            Ddx, Ddy = 0.0, 0.0
            for c in range(7):
                gr[c] = ex * Gm[0, c] + ey * Gm[1, c]
                Ddx += Gm[0, c] * v[idx[c]]
                Ddy += Gm[1, c] * v[idx[c]]
            rd = ex * Ddx + ey * Ddy
            Fx = F * ex + rb * (kt * rd * ex + fr * (Ddx - rd * ex))
            Fy = F * ey + rb * (kt * rd * ey + fr * (Ddy - rd * ey))
            for c in range(7):
                f[idx[c]] -= Fx * Gm[0, c] + Fy * Gm[1, c]
            bear[d, j, 0] = Fx
            bear[d, j, 1] = Fy
            V += kta * x ** (nta + 1.0) / (nta + 1.0)
            if want_k:
                for c1 in range(7):
                    for c2 in range(7):
                        perp = (Gm[0, c1] * Gm[0, c2] + Gm[1, c1] * Gm[1, c2]) - gr[c1] * gr[c2]
                        kk = kt * gr[c1] * gr[c2] + fr * perp
                        K[idx[c1], idx[c2]] += kk
                        C[idx[c1], idx[c2]] += rb * kk
    # --- pins: every pin of every disc, gap from the foot point on the actual profile ---
    R, Rr, E = geo[G_R], geo[G_RR], geo[G_E]
    for d in range(nd):
        ib = 1 + 3 * nc + 3 * d
        cx, cy, al = q[ib], q[ib + 1], q[ib + 2] + drot[d]
        ca, sa = math.cos(al), math.sin(al)
        psi = math.atan2(cy, cx)
        for k in range(pins.shape[0]):
            if not active[d, k]:
                pin_f[d, k] = 0.0
                continue
            Px, Py, rp, thk = pins[k, 0], pins[k, 1], pins[k, 2], pins[k, 3]
            wx, wy = Px - cx, Py - cy
            pbx, pby = ca * wx + sa * wy, -sa * wx + ca * wy
            # R e(-t0) = Rot(-al) P_k: exact foot parameter in the conjugate pose, microradians off
            # under load, so Newton needs 2-3 iterations and can never jump to a neighbouring lobe
            t, s, nx, ny, okk = foot_point(pbx, pby, R, E, zp, al - thk)
            if not okk or abs(s) > 1e-3:
                ok = False
            tws[d, k] = t
            gap = s + Rr - rp
            pin_g[d, k] = gap
            pin_f[d, k] = 0.0
            if gap >= 0.0:
                continue
            ngx, ngy = ca * nx - sa * ny, sa * nx + ca * ny
            g_x, g_y, g_a = -ngx, -ngy, -(wx * ngy - wy * ngx)
            ph = (thk - psi) * 180.0 / math.pi
            ph = abs(ph - 360.0 * math.floor((ph + 180.0) / 360.0))
            kk = _interp(ph, law[:, 0], law[:, 1])
            nn = _interp(ph, law[:, 0], law[:, 2])
            app = -gap
            F = kk * app ** nn
            kt = nn * kk * max(app, 1e-10) ** (nn - 1.0)
            gd = g_x * v[ib] + g_y * v[ib + 1] + g_a * v[ib + 2]
            ramp = _ramp(app)
            Ft = F - beta * ramp * kt * gd
            if Ft < 0.0:
                Ft = 0.0
            pin_f[d, k] = Ft
            f[ib] += Ft * g_x
            f[ib + 1] += Ft * g_y
            f[ib + 2] += Ft * g_a
            V += kk * app ** (nn + 1.0) / (nn + 1.0)
            if want_k:
                gg = (g_x, g_y, g_a)
                for c1 in range(3):
                    for c2 in range(3):
                        K[ib + c1, ib + c2] += kt * gg[c1] * gg[c2]
                        if Ft > 0.0:
                            C[ib + c1, ib + c2] += beta * ramp * kt * gg[c1] * gg[c2]
    return V, tau_in, ok


@njit(cache=True)
def _buffers(n, nd, nc, zp):
    """Output buffers of `assemble`: force, stiffness, damping, pin forces and gaps, bearing and
    mesh forces (one allocation per solve, reused by every iteration)."""
    return (np.zeros(n), np.zeros((n, n)), np.zeros((n, n)), np.zeros((nd, zp)), np.zeros((nd, zp)),
            np.zeros((nd, nc, 2)), np.zeros(nc))


@njit(cache=True)
def static_solve(q, th_in, torque, geo, pins, cranks, law, drot, tws, scale, max_iter, tol_N):
    """Static equilibrium: minimise the potential Pi = V(q) + torque q0 (frictionless couplings
    are conservative) by a Levenberg-Marquardt-damped Newton in scaled coordinates x = scale q
    (metres); a step is taken when Pi or the residual norm falls. Free play (backlash) is crossed
    by the damped steps. A step is accepted when Pi falls by more than its consistency error
    (PI_RTOL) or the residual norm falls. Returns (q, iterations, status 0 = converged,
    1 = iteration limit, 2 = no acceptable step)."""
    n = q.shape[0]
    nd, nc, zp = int(geo[G_ND]), int(geo[G_NC]), pins.shape[0]
    v = np.zeros(n)
    f, K, C, pf, pg, br, mf = _buffers(n, nd, nc, zp)
    geo0 = geo.copy()
    geo0[G_BETA] = 0.0
    V, _, ok = assemble(q, v, th_in, 0.0, geo0, pins, cranks, law, drot, tws, True, f, K, C, pf, pg, br, mf)
    Pi = V + torque * q[0]
    rs = f.copy()
    rs[0] -= torque
    rs = rs / scale
    norm = np.max(np.abs(rs))
    norm2 = np.sqrt(np.sum(rs * rs))
    dmax = 0.0
    for i in range(n):
        dmax = max(dmax, K[i, i] / scale[i] ** 2)
    mu = 1e-6 * dmax + 1.0
    A = np.empty((n, n))
    Kc = K.copy()
    for it in range(max_iter):
        if norm < tol_N:
            return q, it, 0
        accepted = False
        for _ in range(60):
            for i in range(n):
                for j in range(n):
                    A[i, j] = Kc[i, j] / (scale[i] * scale[j])
                A[i, i] += mu
            dx = np.linalg.solve(A, rs)
            qn = q + dx / scale
            tw = tws.copy()
            Vn, _, okn = assemble(qn, v, th_in, 0.0, geo0, pins, cranks, law, drot, tw, True,
                                  f, K, C, pf, pg, br, mf)
            Pin = Vn + torque * qn[0]
            rsn = f.copy()
            rsn[0] -= torque
            rsn = rsn / scale
            nn2 = np.sqrt(np.sum(rsn * rsn))
            # merit: Pi far from equilibrium (crosses free play, where the residual stays T), the
            # residual near it: the pin law's k(phase) is not differentiated in f, so Pi is only a
            # potential of f to ~1e-9 relative and a Pi-only test stalls (measured: rv40e-105 at 1 deg)
            if okn and (Pin < Pi - PI_RTOL * (abs(Pi) + 1e-6) or nn2 < norm2):
                q, rs, Pi, norm2 = qn, rsn, Pin, nn2
                norm = np.max(np.abs(rsn))
                tws[:, :] = tw
                Kc[:, :] = K
                mu = max(mu / 10.0, 1e-9)
                accepted = True
                break
            mu *= 8.0
        if not accepted:
            if norm < 1e3 * tol_N:
                return q, it, 0
            return q, it, 2
    return q, max_iter, 1 if norm > tol_N else 0


@njit(cache=True)
def _hht_step(q, v, acc, fn, th1, w1, T1, h, alpha, geo, pins, cranks, law, drot, tws, scale,
              max_iter, tol_m, Mdiag, f, K, C, pf, pg, br, mf, J, loose, active):
    """One HHT-alpha step of size h; returns (q1, v1, a1, fn1, iterations, ok, V, tau)."""
    n = q.shape[0]
    bet = 0.25 * (1.0 + alpha) ** 2
    gam = 0.5 + alpha
    qp = q + h * v + h * h * (0.5 - bet) * acc
    vp = v + h * (1.0 - gam) * acc
    a = acc.copy()
    fext = np.zeros(n)
    fext[0] = -T1
    tw = tws.copy()
    for it in range(max_iter):
        qn = qp + bet * h * h * a
        vn = vp + gam * h * a
        V, tau, ok = _assemble(qn, vn, th1, w1, geo, pins, cranks, law, drot, tw, True,
                               f, K, C, pf, pg, br, mf, active)
        if not ok:
            return q, v, acc, fn, it + 1, False, 0.0, 0.0
        res = Mdiag * a - (1.0 - alpha) * (f + fext) - alpha * fn
        for i in range(n):
            for j in range(n):
                J[i, j] = (1.0 - alpha) * (gam * h * C[i, j] + bet * h * h * K[i, j])
            J[i, i] += Mdiag[i]
        da = np.linalg.solve(J, -res)
        if not np.all(np.isfinite(da)):
            return q, v, acc, fn, it + 1, False, 0.0, 0.0
        a += da
        dq = 0.0
        for i in range(n):
            dq = max(dq, abs(da[i]) * bet * h * h * scale[i])
        # last resort (finest sub-step): a Newton limit cycle at a contact kink is accepted once
        # its corrections fall below 100 tol (1e-9 m); counted in the iteration statistics
        if dq < tol_m or (loose and it >= max_iter // 2 and dq < 100.0 * tol_m):
            q1 = qp + bet * h * h * a
            v1 = vp + gam * h * a
            V, tau, ok = _assemble(q1, v1, th1, w1, geo, pins, cranks, law, drot, tw, False,
                                   f, K, C, pf, pg, br, mf, active)
            tws[:, :] = tw
            return q1, v1, a, f + fext, it + 1, True, V, tau
    return q, v, acc, fn, max_iter, False, 0.0, 0.0


@njit(cache=True)
def integrate(q, v, Mdiag, th_arr, w_arr, T_arr, dt, stride, alpha, geo, pins, cranks, law, drot,
              tws, scale, max_iter, tol_m, out_q0, out_teeth, out_pf, out_tau, out_energy, store_pf,
              out_state):
    """HHT-alpha (alpha in [0, 1/3]; 0 = trapezoidal rule) with a full Newton per step; a step
    whose Newton iteration does not converge (contact onset inside the step) is retried as
    2, 4, ... 32 sub-steps (input and load interpolated linearly inside the step).
    Step n goes from th_arr[n] to th_arr[n+1]; samples every `stride` steps (sample 0 = start).
    out_energy[:, :] = kinetic, potential, input work, load work (cumulative); out_state (3, n)
    receives the last converged q, v, a. Only candidate pins enter the Newton iterations (see
    CANDIDATE_MARGIN_M); `missed` counts pins found closed at a refresh that were skipped (a
    margin too small: expected 0). Returns (steps done, total Newton iterations, status, missed)."""
    n = q.shape[0]
    nd, nc, zp = int(geo[G_ND]), int(geo[G_NC]), pins.shape[0]
    nsteps = th_arr.shape[0] - 1
    f, K, C, pf, pg, br, mf = _buffers(n, nd, nc, zp)
    J = np.zeros((n, n))
    active = np.ones((nd, zp), np.bool_)
    V, tau, ok = assemble(q, v, th_arr[0], w_arr[0], geo, pins, cranks, law, drot, tws, False,
                          f, K, C, pf, pg, br, mf)
    fn = f.copy()
    fn[0] -= T_arr[0]
    acc = fn / Mdiag
    Win, Wload = 0.0, 0.0
    total_it = 0
    missed = 0
    for step in range(nsteps + 1):
        if step > 0 and step % CANDIDATE_REFRESH == 0:
            # candidate pins: every pin evaluated at the last converged state; those more than
            # CANDIDATE_MARGIN_M open are skipped until the next refresh
            assemble(q, v, th_arr[step - 1], w_arr[step - 1], geo, pins, cranks, law, drot, tws, False,
                     f, K, C, pf, pg, br, mf)
            for d in range(nd):
                for k in range(zp):
                    if pg[d, k] < 0.0 and not active[d, k]:
                        missed += 1
                    active[d, k] = pg[d, k] < CANDIDATE_MARGIN_M
        if step > 0:
            p_in0 = tau * w_arr[step - 1]
            p_ld0 = -T_arr[step - 1] * v[0]
            done = False
            for level in range(6):
                m = 1 << level
                qs, vs, as_, fs = q.copy(), v.copy(), acc.copy(), fn.copy()
                tw0 = tws.copy()
                good = True
                for sub in range(m):
                    s1 = (sub + 1.0) / m
                    th1 = th_arr[step - 1] + s1 * (th_arr[step] - th_arr[step - 1])
                    w1 = w_arr[step - 1] + s1 * (w_arr[step] - w_arr[step - 1])
                    T1 = T_arr[step - 1] + s1 * (T_arr[step] - T_arr[step - 1])
                    qs, vs, as_, fs, its, okk, V, tau = _hht_step(
                        qs, vs, as_, fs, th1, w1, T1, dt / m, alpha, geo, pins, cranks, law, drot,
                        tws, scale, max_iter, tol_m, Mdiag, f, K, C, pf, pg, br, mf, J, level == 5, active)
                    total_it += its
                    if not okk:
                        good = False
                        break
                if good:
                    done = True
                    break
                tws[:, :] = tw0
            if not done:
                out_state[0], out_state[1], out_state[2] = q, v, acc
                return step - 1, total_it, 1, missed
            q, v, acc, fn = qs, vs, as_, fs
            Win += 0.5 * dt * (p_in0 + tau * w_arr[step])
            Wload += 0.5 * dt * (p_ld0 - T_arr[step] * v[0])
        if step % stride == 0:
            si = step // stride
            out_q0[si] = q[0]
            out_tau[si] = tau
            for d in range(nd):
                cnt = 0
                for k in range(zp):
                    if pf[d, k] > 0.0:
                        cnt += 1
                    if store_pf:
                        out_pf[si, d, k] = pf[d, k]
                out_teeth[si, d] = cnt
            ek = 0.0
            for i in range(n):
                ek += 0.5 * Mdiag[i] * v[i] * v[i]
            out_energy[si, 0], out_energy[si, 1] = ek, V
            out_energy[si, 2], out_energy[si, 3] = Win, Wload
    out_state[0], out_state[1], out_state[2] = q, v, acc
    return nsteps, total_it, 0, missed
