"""Cycloid disc - pin contact: every pin of the housing against every disc, gap from the actual profile.

Disc d (centre c_d, rotation alpha_d + its profile rotation) carries the modified profile: the
inward offset by Rr + dRr of the pin-centre curve c(t) with R + dR (DESIGN.md). Pin k (centre P_k,
radius r_k, both with case.errors applied) is mapped into the disc frame and its foot point on c(t)
found by `geometry.pin_profile.foot_point` (Newton seeded at the conjugate-pose parameter
alpha_d - theta_k, microradians off under load: 2-3 iterations, never the neighbouring lobe).
gap = s + Rr - r_k (s the signed distance from c along the outward normal); approach = -gap.
Law (fem.stiffness.pin_law: the tooth-pair FE with the disc body and the pin's housing groove in
series, refitted; by pin phase from the line of centres, interpolated): F = k(phase) approach^n, V = k approach^(n+1) / (n+1); the law's phase dependence is not
differentiated in f (f departs from -grad V by ~2e-4 of the largest force at 300 N m,
tests/test_couplings.py). Tangent: K = k_t g g^T (symmetric: the budget, the eigenfrequencies and
the time integration use it); the rest of -df/dq, the law's phase part g dF/dphase dphase/dq
(the disc centre turns the line of centres) and the geometric part -F d2gap/dq2 (the profile's
curvature kappa / (1 + kappa s) along the tangent and the frame's rotation), goes to Work.K_rest
at beta = 0, where the statics' Newton adds it: K + K_rest is -df/dq to the differences' own
error (tests/test_couplings.py), K alone to ~3e-4 of its largest entry. What it buys is small:
the fit's static points took 3.0 accepted Newton steps instead of 3.17 (48 sampled points of
the real records' diagnosis), whose run went 112.8 -> 105.7 s on one worker (two paired runs
each, this machine's noise ~6 %); the steps end at the residual floor the foot point's 1e-14 rad
sets (~1e-7 N, just under the statics' tolerance), not at the tangent.
Damping beta k_t g', ramped in over DAMP_RAMP_M of approach; a damped contact cannot pull (force
clipped at 0).
The contacts are the work's candidate contacts: the time integration skips pins found open by
more than a margin (dynamics.kernels.CANDIDATE_MARGIN_M); w.gap / w.force hold gap and force.
As-built errors (case.errors, geometry.params.Errors), all through this same gap and law:
  pins   uniform radius / circle radius, per-pin radial, tangential and radius, pin-ring radial
         lobes: the pin centres and radii of `pins`; a tilted pin ring: the centres shifted per
         disc plane (`plane_shift`, constant: no change of the gradients); pin support (groove)
         stiffness lobes: a multiplier on each pin's law (column 4 of `pins`; the whole series law
         is scaled, ASSUMED: the refitted law does not separate the groove's share);
  seats  pin seats softer than the housing FE (dynamics.couplings.housing.SeatCompliance, a
         stiffness part the diagnosis sets): compliance sk in series with the law along the normal,
         approach = dc + sk F(dc), solved per contact (`_series_approach`), V = law energy + sk F^2 / 2;
  discs  disc-to-disc phase (disc 2's profile turned), uniform profile error per disc (material
         added closes the gap), cumulative pitch lobes (the profile turned locally by
         amplitude / R) and profile lobes (normal), both read at the polar angle of the pin centre
         in the disc's profile frame (the tooth space it sits in; a pattern of m <= zc / 2 lobes
         varies slowly over a tooth). The lobes' own dependence on that angle is left out of the
         gradient (relative size m amplitude / R, < 1e-3 for 10 um).
"""
from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from dynamics.couplings.housing import modes as housing_modes, seat_compliance
from dynamics.couplings.base import foot_point, interp2, kernel, ramp
from fem.stiffness import pin_law
from geometry.params import lobe_sum

NAME = "pin"
GAP_LIMIT_M = 1e-3     # a foot point farther than this from the pin-centre curve is lost geometry


class Params(NamedTuple):
    R_m: float                     # pin circle radius of the profile, R + dR
    Rr_m: float                    # pin radius of the profile, Rr + dRr
    E_m: float                     # eccentricity of the profile
    zp: float                      # pins
    pins: np.ndarray               # (zp, 6) actual pins: x [m], y [m], radius [m], angle [rad], law factor,
    #                                added seat compliance [m/N] (dynamics.couplings.housing.SeatCompliance)
    law: np.ndarray                # (P, 3) pin phase [deg], k [N/m^n], n
    disc_rotation_rad: np.ndarray  # (nd,) profile rotation in each disc's body frame
    disc_profile_m: np.ndarray     # (nd,) uniform profile error, + material added
    disc_pitch: np.ndarray         # (nd, L, 3) cumulative pitch lobes: m, amplitude [rad], phase [rad]
    disc_profile_lobes: np.ndarray  # (nd, L2, 3) profile lobes: m, amplitude [m], phase [rad]
    dof: np.ndarray                # (nd, 3) disc x, y, rotation
    plane_shift: np.ndarray        # (nd, 2) pin centres' shift [m] at each disc's plane (Errors.pin_ring_tilt_um)
    housing_phi: np.ndarray        # (zp, 2, nh) pin k's seat displacement (x, y) per housing modal coordinate
    housing_dof: np.ndarray        # (nh,) the housing block's indices (dynamics.couplings.housing)
    c0: int                        # offset of the (nd, zp) contacts in the work's contact arrays


def params(case, stiffness, layout, slots) -> Params:
    cy, mod, er, si = case.cycloid, case.modification, case.errors, case.si
    zp, nd = cy.zp, cy.disc_count
    th = 2 * np.pi * np.arange(zp) / zp
    each = lambda v: np.asarray(v, float) * 1e-6 if len(v) else np.zeros(zp)  # noqa: E731
    Rp = si.pin_circle_radius_m + er.pin_circle_radius_um * 1e-6 + each(er.per_pin_radial_um) \
        + 1e-6 * lobe_sum(er.pin_radial_lobes, 0, th)
    tp = each(er.per_pin_tangential_um)
    rp = si.pin_radius_m + er.pin_radius_um * 1e-6 + each(er.per_pin_radius_um)
    factor = 1.0 + np.zeros(zp) + lobe_sum(er.pin_stiffness_lobes, 0, th)
    R_disc = si.pin_circle_radius_m      # pitch errors are tangential at the pin circle
    pos, k_law, n_law, _ = pin_law(stiffness)
    disc = layout["disc"]
    hm = housing_modes(stiffness, layout)
    phi = np.zeros((zp, 2, 0)) if hm is None else np.asarray(hm[0].phi, float).reshape(zp, 2, -1)
    return Params(
        R_m=si.modified_pin_circle_radius_m, Rr_m=si.modified_pin_radius_m, E_m=si.eccentricity_m, zp=float(zp),
        pins=np.column_stack([Rp * np.cos(th) - tp * np.sin(th), Rp * np.sin(th) + tp * np.cos(th), rp, th,
                              factor, seat_compliance(stiffness, zp)]),
        law=np.column_stack([pos, k_law, n_law]).astype(float),
        disc_rotation_rad=np.deg2rad(mod.rotation_deg) + np.pi * np.arange(nd)
        + np.array([0.0, er.disc_phase_um * 1e-6 / R_disc])[:nd],
        disc_profile_m=np.broadcast_to(np.asarray(er.disc_profile_um, float) * 1e-6, (nd,)).copy(),
        disc_pitch=_disc_lobes(er.disc_pitch_lobes, nd, 1e-6 / R_disc),
        disc_profile_lobes=_disc_lobes(er.disc_profile_lobes, nd, 1e-6),
        dof=np.column_stack([disc.indices("x"), disc.indices("y"), disc.indices("rot")]).astype(np.int64),
        plane_shift=plane_shift_m(er, nd),
        housing_phi=np.ascontiguousarray(phi),
        housing_dof=np.zeros(0, np.int64) if hm is None else hm[1],
        c0=slots.contacts("pin", (nd, zp), group=np.repeat(np.arange(nd), zp)))


def plane_shift_m(er, nd: int) -> np.ndarray:
    """(nd, 2) the pin centres' shift at each disc's plane from a tilted pin ring: +t at disc 1, -t at
    disc 2 toward the tilt phase (a single disc: +t, a shift of the ring; more discs: spread linearly
    between +t and -t, as the planes lie along a tilted axis)."""
    t = er.pin_ring_tilt_um * 1e-6
    lever = np.ones(1) if nd == 1 else np.linspace(1.0, -1.0, nd)
    ph = math.radians(er.pin_ring_tilt_phase_deg)
    return np.ascontiguousarray(np.outer(t * lever, [math.cos(ph), math.sin(ph)]))


def _disc_lobes(rows, nd: int, scale: float) -> np.ndarray:
    """(nd, L, 3): m, amplitude * scale, phase [rad] from rows [disc, m, amplitude, phase_deg]
    (a disc with fewer rows padded with zero amplitude)."""
    per = [[r for r in rows if r[0] == d + 1] for d in range(nd)]
    out = np.zeros((nd, max(len(x) for x in per), 3))
    for d, rs in enumerate(per):
        for i, (_, m, a, ph) in enumerate(rs):
            out[d, i] = m, a * scale, np.radians(ph)
    return out


@kernel(inline=True)
def _series_approach(app, kk, nn, sk):
    """The contact's own approach dc of app = dc + sk kk dc^nn (a seat of compliance sk in series):
    Newton from dc = app, monotone from above (the left side is increasing and convex for nn >= 1)."""
    dc = app
    for _ in range(50):
        g = dc + sk * kk * dc ** nn - app
        dg = 1.0 + sk * nn * kk * max(dc, 1e-300) ** (nn - 1.0)
        step = g / dg
        dc = max(dc - step, 0.5 * dc)
        if abs(step) <= 1e-14 * app:
            break
    return dc


@kernel(inline=True)
def add(q, v, th_in, w_in, beta, want_k, p, w, V, tau_in):
    """Coupling interface (see dynamics.couplings); only the contacts with w.active are
    evaluated (the others are known open: force 0, gap left as it was)."""
    f, K, C, active, gaps, forces, Kr = w.f, w.K, w.C, w.active, w.gap, w.force, w.K_rest
    rest = want_k and beta == 0.0       # the statics' exact tangent (Work.K_rest)
    R, Rr, E, zp = p.R_m, p.Rr_m, p.E_m, p.zp
    law, pins, dof = p.law, p.pins, p.dof
    npin = pins.shape[0]
    hphi, hdof = p.housing_phi, p.housing_dof
    nh = hdof.shape[0]
    hu = np.zeros((npin, 2))            # each pin seat's displacement with the housing's modes
    # the pin coupling is the only one that touches the housing rows and columns of K and C: their
    # blocks are summed here (same contacts, same order: the same bits as summing into K directly)
    # and added once at the end, no allocation per contact (no measurable change of `make bench`)
    gh = np.empty(nh)                   # the gap's gradient on the housing modes
    tjh = np.empty(nh)                  # the tangent's component of the pin's motion per housing mode
    Khh, Chh = np.zeros((nh, nh)), np.zeros((nh, nh))
    ndisc = dof.shape[0]
    Kdh, Cdh = np.zeros((ndisc, 3, nh)), np.zeros((ndisc, 3, nh))
    Khd, Chd = np.zeros((ndisc, nh, 3)), np.zeros((ndisc, nh, 3))
    for k in range(npin):
        for i in range(nh):
            hu[k, 0] += hphi[k, 0, i] * q[hdof[i]]
            hu[k, 1] += hphi[k, 1, i] * q[hdof[i]]
    ok = True
    for d in range(dof.shape[0]):
        ix, iy, ia = dof[d, 0], dof[d, 1], dof[d, 2]
        cx, cy, al = q[ix], q[iy], q[ia] + p.disc_rotation_rad[d]
        ca0, sa0 = math.cos(al), math.sin(al)
        psi = math.atan2(cy, cx)
        # d(phase)/d(centre) [deg/m] without its sign (the fold below): psi turns as the centre moves
        r2 = max(cx * cx + cy * cy, 1e-30)
        dph_x, dph_y = (180.0 / math.pi) * cy / r2, -(180.0 / math.pi) * cx / r2
        npitch, nprof = p.disc_pitch.shape[1], p.disc_profile_lobes.shape[1]
        for k in range(npin):
            c = p.c0 + d * npin + k
            if not active[c]:
                forces[c] = 0.0
                continue
            Px, Py = pins[k, 0] + hu[k, 0] + p.plane_shift[d, 0], pins[k, 1] + hu[k, 1] + p.plane_shift[d, 1]
            rp, thk = pins[k, 2], pins[k, 3]
            wx, wy = Px - cx, Py - cy
            ca, sa, alk = ca0, sa0, al
            pbx, pby = ca * wx + sa * wy, -sa * wx + ca * wy
            dprof = p.disc_profile_m[d]
            if npitch + nprof > 0:           # the disc's patterns at the tooth space of this pin
                phi = math.atan2(pby, pbx)
                dal = 0.0
                for i in range(npitch):
                    dal += p.disc_pitch[d, i, 1] * math.cos(p.disc_pitch[d, i, 0] * phi - p.disc_pitch[d, i, 2])
                for i in range(nprof):
                    dprof += p.disc_profile_lobes[d, i, 1] * math.cos(p.disc_profile_lobes[d, i, 0] * phi
                                                                      - p.disc_profile_lobes[d, i, 2])
                if dal != 0.0:               # the profile turned locally by the cumulative pitch
                    alk = al + dal
                    ca, sa = math.cos(alk), math.sin(alk)
                    pbx, pby = ca * wx + sa * wy, -sa * wx + ca * wy
            # seed wrapped into [-pi, pi): at |t| > 3 pi the foot point's 1e-14 rad test nears the
            # float spacing of t and fails (2e-4 of the calls at 3-5 pi, 9 % beyond 20 pi; issue 12)
            seed = alk - thk
            seed -= 2.0 * math.pi * math.floor(seed / (2.0 * math.pi) + 0.5)
            # started at the last solve's offset from the conjugate seed (w.foot: microradians of
            # load, changing by ~1e-12 rad between Newton iterations): the same foot to 1e-14 rad,
            # one iteration fewer; a stale or bad offset only costs iterations (the Newton is
            # safeguarded and the offset is dropped where it failed)
            t, s, nx, ny, kappa, okk = foot_point(pbx, pby, R, E, zp, seed + w.foot[c])
            w.foot[c] = t - seed if okk and abs(t - seed) < 0.02 else 0.0
            if not okk or abs(s) > GAP_LIMIT_M:
                ok = False
            gap = s + Rr - rp - dprof
            gaps[c] = gap
            forces[c] = 0.0
            if gap >= 0.0:
                continue
            ngx, ngy = ca * nx - sa * ny, sa * nx + ca * ny
            g_x, g_y, g_a = -ngx, -ngy, -(wx * ngy - wy * ngx)
            ph = (thk - psi) * 180.0 / math.pi
            ph -= 360.0 * math.floor((ph + 180.0) / 360.0)
            sgn = 1.0 if ph >= 0.0 else -1.0
            ph = abs(ph)
            kk, nn, dk, dn = interp2(ph, law)
            kk *= pins[k, 4]
            dk *= pins[k, 4]
            app = -gap
            sk = pins[k, 5]
            if sk > 0.0:                     # a softer seat in series: app = dc + sk F(dc)
                dc = _series_approach(app, kk, nn, sk)
                F = kk * dc ** nn
                ktc = nn * kk * max(dc, 1e-10) ** (nn - 1.0)
                kt = ktc / (1.0 + sk * ktc)
                Vc = kk * dc ** (nn + 1.0) / (nn + 1.0) + 0.5 * sk * F * F
                # dF/d(phase) at fixed approach: dF = (dc^n dk + F ln(dc) dn) / (1 + sk ktc)
                dFph = F * (dk / kk + math.log(max(dc, 1e-300)) * dn) / (1.0 + sk * ktc) if rest else 0.0
            else:
                F = kk * app ** nn
                kt = nn * kk * max(app, 1e-10) ** (nn - 1.0)
                Vc = kk * app ** (nn + 1.0) / (nn + 1.0)
                dFph = F * (dk / kk + math.log(app) * dn) if rest else 0.0
            for i in range(nh):              # the gap's gradient on the housing modes: d gap = n . d(seat)
                gh[i] = ngx * hphi[k, 0, i] + ngy * hphi[k, 1, i]
            gd = g_x * v[ix] + g_y * v[iy] + g_a * v[ia]
            for i in range(nh):
                gd += gh[i] * v[hdof[i]]
            rmp = ramp(app)
            Ft = F - beta * rmp * kt * gd
            if Ft < 0.0:
                Ft = 0.0
            forces[c] = Ft
            f[ix] += Ft * g_x
            f[iy] += Ft * g_y
            f[ia] += Ft * g_a
            V += Vc
            damp = Ft > 0.0
            gg, ii = (g_x, g_y, g_a), (ix, iy, ia)
            if want_k:                       # K += kt g g^T over the disc's (x, y, rot)
                for c1 in range(3):
                    for c2 in range(3):
                        K[ii[c1], ii[c2]] += kt * gg[c1] * gg[c2]
                        if damp:
                            C[ii[c1], ii[c2]] += beta * rmp * kt * gg[c1] * gg[c2]
            if rest and damp:
                # K_rest = -g dF/dph dph/dq (phase) - F d2gap/dq2 (geometric) over (cx, cy, rot, housing
                # modes): gap = s(pb), pb = R(al)^T (P - c) the pin centre in the disc frame; d2s/dpb2 =
                # kappa / (1 + kappa s) t t^T (t the unit tangent); d2pb/dal2 = -pb, d2pb/dc dal from dR^T/dal
                ex, ey = sgn * dFph * dph_x, sgn * dFph * dph_y
                for c1 in range(3):
                    Kr[ii[c1], ix] -= gg[c1] * ex
                    Kr[ii[c1], iy] -= gg[c1] * ey
                tx, ty = -ny, nx
                hts = Ft * kappa / (1.0 + kappa * s)
                tj = (-tx * ca + ty * sa, -tx * sa - ty * ca, tx * pby - ty * pbx)
                na = (nx * sa + ny * ca, -nx * ca + ny * sa, -(nx * pbx + ny * pby))
                for c1 in range(3):
                    for c2 in range(3):
                        Kr[ii[c1], ii[c2]] -= hts * tj[c1] * tj[c2]
                    Kr[ii[c1], ia] -= Ft * na[c1]
                    if c1 < 2:
                        Kr[ia, ii[c1]] -= Ft * na[c1]
                for i in range(nh):          # the seat moves with the housing: P = pin + phi q_h
                    fx, fy = hphi[k, 0, i], hphi[k, 1, i]
                    tjh[i] = tx * (ca * fx + sa * fy) + ty * (-sa * fx + ca * fy)
                for i in range(nh):
                    fx, fy = hphi[k, 0, i], hphi[k, 1, i]
                    nah = nx * (-sa * fx + ca * fy) + ny * (-ca * fx - sa * fy)
                    Kr[hdof[i], ix] -= gh[i] * ex
                    Kr[hdof[i], iy] -= gh[i] * ey
                    for c2 in range(3):
                        Kr[hdof[i], ii[c2]] -= hts * tjh[i] * tj[c2]
                        Kr[ii[c2], hdof[i]] -= hts * tj[c2] * tjh[i]
                    Kr[hdof[i], ia] -= Ft * nah
                    Kr[ia, hdof[i]] -= Ft * nah
                    for i2 in range(nh):
                        Kr[hdof[i], hdof[i2]] -= hts * tjh[i] * tjh[i2]
            if nh == 0:
                continue
            for i in range(nh):
                f[hdof[i]] += Ft * gh[i]
            if want_k:                       # ... and over (disc, housing modes)
                for c1 in range(3):
                    for c2 in range(nh):
                        Kdh[d, c1, c2] += kt * gg[c1] * gh[c2]
                        Khd[d, c2, c1] += kt * gh[c2] * gg[c1]
                        if damp:
                            Cdh[d, c1, c2] += beta * rmp * kt * gg[c1] * gh[c2]
                            Chd[d, c2, c1] += beta * rmp * kt * gh[c2] * gg[c1]
                for c1 in range(nh):
                    for c2 in range(nh):
                        Khh[c1, c2] += kt * gh[c1] * gh[c2]
                        if damp:
                            Chh[c1, c2] += beta * rmp * kt * gh[c1] * gh[c2]
    if want_k and nh > 0:
        for d in range(ndisc):
            for c1 in range(3):
                for c2 in range(nh):
                    K[dof[d, c1], hdof[c2]] += Kdh[d, c1, c2]
                    K[hdof[c2], dof[d, c1]] += Khd[d, c2, c1]
                    C[dof[d, c1], hdof[c2]] += Cdh[d, c1, c2]
                    C[hdof[c2], dof[d, c1]] += Chd[d, c2, c1]
        for c1 in range(nh):
            for c2 in range(nh):
                K[hdof[c1], hdof[c2]] += Khh[c1, c2]
                C[hdof[c1], hdof[c2]] += Chh[c1, c2]
    return V, tau_in, ok
