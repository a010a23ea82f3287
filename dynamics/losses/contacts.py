"""Friction at every contact of a static state, with the velocities of the running mechanism.

For a static state q of the lumped model (dynamics.statics) at input angle th, running at input
speed omega_in in `direction` (+1 forward, -1 backward), each contact gets its normal load from the
state, its sliding and rolling velocities from the rigid kinematics (dq/dth of
dynamics.statics.nominal_q, times omega_in), its regime from dynamics.losses.lubricant, and so a
friction force or moment, a generalized force on the model's DOFs and a power loss:
  cycloid - pin   line contact of the pin (radius r_p, its seat moved by the housing's modes, the
                  friction's reaction on them) on the disc profile (signed radius from the
                  pin-centre curve's curvature): sliding v_s = disc velocity at the contact along
                  the tangent, entrainment u_e = |2 u_c - v_s| / 2 with u_c = -r_p dpsi/dt the
                  contact's speed over the fixed pin (psi the normal's angle); friction mu N opposes
                  v_s. The pin is taken as sliding on the disc, not turning in its groove: an upper
                  bound (a turning pin moves the sliding into the conformal groove, whose thicker
                  film can only lower mu)
  needle bearing  between eccentric (crank rotation) and disc: Palmgren M0 + f1 F dm, dm = eccentric
                  diameter + needle diameter
  crank supports  two tapered roller bearings per crank between crank and carrier: Palmgren M0 +
                  f1 P1 dm, P1 = max(F_r, 2 Y F_a) (Harris & Kotzalas), F_a the preload of the
                  stiffness model, dm = d + 2 D_we (the roller rule of fem.tapered_roller)
  involute mesh   Ohlendorf's tooth loss factor H_V = pi (u + 1) / (z1 u) (1 - eps + eps1^2 + eps2^2)
                  (ISO/TR 14179-2), P = mu H_V F_bn v_b, mu from the film at the pitch point; its
                  moment on the crank is not applied (the mesh is 1-2 % of the compliance)
  main bearings   (carrier in housing, the case's [main_bearings] pair) Palmgren M0 at output speed; lip
                  seals (output, input)
Friction forces and moments enter as generalized forces; dynamics.losses.operating solves the
statics with them. Rolling-bearing moments carry no film dependence (Palmgren's f1 is a constant).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from dynamics.couplings.base import foot_point, kernel
from dynamics.losses import bearings as brg
from dynamics.losses.lubricant import Lubricant, composite_roughness_m, line_contact_regime, reduced_modulus_Pa
from dynamics.reducer import ReducerModel, evaluate
from dynamics.statics import nominal_q

RPM_PER_RAD_S = 30.0 / math.pi
D_THETA_RAD = 1e-4          # finite-difference step of the kinematics in input angle


@dataclass(frozen=True)
class ContactFriction:
    """Friction of one static state at one running condition (arrays per contact set)."""
    force: np.ndarray               # (n_dof,) generalized friction force on the model [N | N m]
    carrier_drag_Nm: float          # main bearings + output seal, resisting the carrier's motion
    pin_mu: np.ndarray              # (k,) friction coefficient at each loaded pin
    pin_film_parameter: np.ndarray  # (k,)
    pin_film_m: np.ndarray          # (k,)
    power_W: dict                   # loss by contact set: pins, needles, supports, mesh, main, seals
    mesh_mu: float
    mesh_film_parameter: float

    @property
    def total_power_W(self) -> float:
        return float(sum(self.power_W.values()))


def rates(model: ReducerModel, input_rad: float) -> np.ndarray:
    """dq/dth_in of the rigid mechanism (per rad of input)."""
    h = D_THETA_RAD
    return (nominal_q(model, input_rad + h) - nominal_q(model, input_rad - h)) / (2 * h)


@kernel
def _pin_frames(qs, sel, pins, shift, dof, disc_rotation, R, E, zp):
    """For the selected (disc, pin) pairs at each state of qs (rows): the disc profile's outward normal
    angle at the pin (global) and the curvature of the pin-centre curve there (disc frame)."""
    out = np.empty((qs.shape[0], sel.shape[0], 2))
    for s in range(qs.shape[0]):
        q = qs[s]
        for i in range(sel.shape[0]):
            d, k = sel[i, 0], sel[i, 1]
            cx, cy, al = q[dof[d, 0]], q[dof[d, 1]], q[dof[d, 2]] + disc_rotation[d]
            wx, wy = pins[k, 0] + shift[d, 0] - cx, pins[k, 1] + shift[d, 1] - cy
            ca, sa = math.cos(al), math.sin(al)
            seed = al - pins[k, 3]
            seed -= 2.0 * math.pi * math.floor(seed / (2.0 * math.pi) + 0.5)
            _, _, nx, ny, kappa, _ = foot_point(ca * wx + sa * wy, -sa * wx + ca * wy, R, E, zp, seed)
            out[s, i, 0] = math.atan2(sa * nx + ca * ny, ca * nx - sa * ny)
            out[s, i, 1] = kappa
    return out


def mesh_loss_factor(case) -> float:
    """Ohlendorf H_V of the sun-planet pair (zero-sum shift: working angle = pressure angle)."""
    s1 = case.stage1
    a = math.radians(s1.pressure_angle_deg)
    m, z1, z2, x1 = s1.module_mm, s1.z1, s1.z2, s1.profile_shift
    u = z2 / z1
    eps = []
    for z, x in ((z1, x1), (z2, -x1)):
        r, rb = m * z / 2, m * z / 2 * math.cos(a)
        ra = r + m * (1 + x)
        eps.append(z / (2 * math.pi) * (math.tan(math.acos(rb / ra)) - math.tan(a)))
    e = eps[0] + eps[1]
    return math.pi * (u + 1) / (z1 * u) * (1 - e + eps[0] ** 2 + eps[1] ** 2)


def contact_friction(model: ReducerModel, lub: Lubricant, q: np.ndarray, input_rad: float,
                     qdot: np.ndarray, oil_temperature_C: float, input_speed_rad_s: float | None = None,
                     shape: np.ndarray | None = None, viscous: bool = True) -> ContactFriction:
    """Friction of state q moving at qdot [rad/s, m/s] (running: `rates` x omega_in). shape: the
    motion's direction in q along which the contact normals turn (default qdot); the input turns at
    input_speed_rad_s (default qdot's kinematic input speed: carrier rate x i). viscous False drops
    the bearings' no-load (viscous) moments M0: a reducer at rest or creeping (catalog test)."""
    case, lay, sec = model.case, model.layout, lub.section
    w, _ = evaluate(model, q, input_rad)
    dq = np.asarray(qdot, float)
    om_in = dq[model.i_out] * model.ratio if input_speed_rad_s is None else input_speed_rad_s
    shape = dq if shape is None else shape
    scale = float(np.max(np.abs(shape))) or 1.0
    qa, qb = q - D_THETA_RAD * shape / scale, q + D_THETA_RAD * shape / scale
    f = np.zeros(model.n_dof)
    E_red = reduced_modulus_Pa(case.material.youngs_modulus_GPa * 1e9, case.material.poisson_ratio)
    nu_cSt = float(lub.kinematic_cSt(oil_temperature_C))
    power = {}

    # --- cycloid - pin
    p = model.params("pin")
    forces = model.contacts(w.force)                 # (nd, zp)
    width = case.cycloid.width_mm * 1e-3
    sigma = composite_roughness_m(sec.disc_Ra_um, sec.pin_Ra_um)
    sel = np.argwhere(forces > 0.0)
    hphi, hdof = p.housing_phi, p.housing_dof            # the elastic housing's modes move the pin seats
    pins = p.pins.copy()
    if len(hdof):
        pins[:, :2] += np.einsum("kci,i->kc", hphi, q[hdof])
    if len(sel):
        fr = _pin_frames(np.stack([q, qa, qb]), sel.astype(np.int64), pins, p.plane_shift, p.dof,
                         p.disc_rotation_rad, p.R_m, p.E_m, p.zp)
        psi, kappa = fr[0, :, 0], fr[0, :, 1]
        # the normal's turning rate: its angle change along `shape`, times the motion's rate along it
        along = float(dq @ shape) / float(shape @ shape) if shape.any() else 0.0
        dpsi = np.remainder(fr[2, :, 0] - fr[1, :, 0] + np.pi, 2 * np.pi) - np.pi
        dpsi = dpsi / (2 * D_THETA_RAD) * scale * along
        n = np.column_stack([np.cos(psi), np.sin(psi)])
        t = np.column_stack([-n[:, 1], n[:, 0]])
        dd, kk = sel[:, 0], sel[:, 1]
        rp = p.pins[kk, 2]
        ixyz = p.dof[dd]                                      # (m, 3) disc x, y, rotation
        r = pins[kk, :2] + p.plane_shift[dd] - rp[:, None] * n - q[ixyz[:, :2]]   # contact point from the disc centre
        v = dq[ixyz[:, :2]] + dq[ixyz[:, 2]][:, None] * np.column_stack([-r[:, 1], r[:, 0]])
        vs = np.sum(v * t, axis=1)                            # disc sliding over the pin
        uc = -rp * dpsi                                       # contact point's speed over the pin
        with np.errstate(divide="ignore"):
            inv_rho = np.where(kappa != 0, kappa / (1.0 - p.Rr_m * kappa), 0.0)   # signed profile curvature
        R_red = 1.0 / np.maximum(1.0 / rp + inv_rho, 1e-6)
        N = forces[dd, kk]
        reg = line_contact_regime(lub, oil_temperature_C, np.abs(2 * uc - vs) / 2, R_red, N / width, E_red, sigma)
        Ft = -(reg.friction * N * np.sign(vs))[:, None] * t    # on the disc, against its sliding
        np.add.at(f, ixyz[:, 0], Ft[:, 0])
        np.add.at(f, ixyz[:, 1], Ft[:, 1])
        np.add.at(f, ixyz[:, 2], r[:, 0] * Ft[:, 1] - r[:, 1] * Ft[:, 0])
        if len(hdof):                                         # the reaction on the pin seats
            f[hdof] -= np.einsum("mci,mc->i", hphi[kk], Ft)
        power["pins"] = float(np.sum(reg.friction * N * np.abs(vs)))
        pin_mu, pin_lam, pin_h = reg.friction, reg.film_parameter, reg.film_m
    else:
        power["pins"] = 0.0
        pin_mu = pin_lam = pin_h = np.zeros(0)

    # --- needle bearings: crank j's eccentric in disc d
    cr = case.crankshaft
    rot, disc = lay["crank_rotation"], lay["disc"]
    io = model.i_out
    Fn = model.output(w, "bearing_force_N")           # (nd, nc, 2)
    dm_needle = 2 * cr.eccentric_radius_mm + cr.needle_diameter_mm
    pw = 0.0
    for d in range(Fn.shape[0]):
        for j in range(Fn.shape[1]):
            ic, idd = rot.index(j), disc.index(d, "rot")
            om = dq[ic] - dq[idd]
            n_rpm = abs(om) * RPM_PER_RAD_S
            M = viscous * brg.palmgren_no_load_Nm(sec.f0_needle, nu_cSt, n_rpm, dm_needle) \
                + float(brg.palmgren_load_Nm(sec.f1_needle, np.hypot(*Fn[d, j]), dm_needle))
            s = math.copysign(1.0, om) if om else 0.0
            f[ic] -= s * M
            f[idd] += s * M
            pw += M * abs(om)
    power["needles"] = pw

    # --- crank supports: two tapered roller bearings per crank, crank against carrier
    sb = model.stiffness.support_bearings
    Fs = model.output(w, "support_force_N")           # (nc, nd, 2)
    dm_sup = 2 * cr.journal_radius_mm + 2 * sb.roller_diameter_m * 1e3
    Y = 0.4 / math.tan(math.radians(sb.contact_angle_deg))
    pw = 0.0
    for j in range(Fs.shape[0]):
        ic = rot.index(j)
        om = dq[ic] - dq[io]
        n_rpm = abs(om) * RPM_PER_RAD_S
        Fr = 0.5 * float(np.sum(np.hypot(Fs[j, :, 0], Fs[j, :, 1])))   # per bearing, mean of the planes
        P1 = max(Fr, 2 * Y * sb.preload_N)
        M = 2 * (viscous * brg.palmgren_no_load_Nm(sec.f0_tapered, nu_cSt, n_rpm, dm_sup)
                 + float(brg.palmgren_load_Nm(sec.f1_tapered, P1, dm_sup)))
        s = math.copysign(1.0, om) if om else 0.0
        f[ic] -= s * M
        f[io] += s * M
        pw += M * abs(om)
    power["supports"] = pw

    # --- involute mesh (power only)
    mp = model.params("mesh")
    s1 = case.stage1
    Fm = np.abs(model.output(w, "mesh_force_N"))
    v_b = abs(om_in - dq[io]) * mp.rb_sun_m
    a = math.radians(s1.pressure_angle_deg)
    r1, r2 = s1.module_mm * s1.z1 / 2e3, s1.module_mm * s1.z2 / 2e3
    Rm = r1 * r2 * math.sin(a) / (r1 + r2)
    u_e = v_b / math.cos(a) * math.sin(a)
    reg = line_contact_regime(lub, oil_temperature_C, np.full(len(Fm), u_e), np.full(len(Fm), Rm),
                              Fm / (s1.face_width_mm * 1e-3), E_red,
                              composite_roughness_m(sec.gear_Ra_um, sec.gear_Ra_um))
    power["mesh"] = float(np.sum(reg.friction * mesh_loss_factor(case) * Fm * v_b))

    # --- main bearings and seals (no-load): the carrier's drag, kept apart (the caller adds it to
    # the load torque, so the robust static solver closes the free play with it)
    om_out = dq[io]
    M_main, M_seal_out = _carrier_drag_parts(case, lub, abs(om_out) * RPM_PER_RAD_S, nu_cSt, viscous)
    power["main_bearings"] = M_main * abs(om_out)
    power["seals"] = M_seal_out * abs(om_out) + brg.seal_moment_Nm(sec.input_seal_diameter_mm) * abs(om_in)
    return ContactFriction(force=f, carrier_drag_Nm=M_main + M_seal_out, pin_mu=np.asarray(pin_mu), pin_film_parameter=np.asarray(pin_lam),
                           pin_film_m=np.asarray(pin_h), power_W=power,
                           mesh_mu=float(np.mean(reg.friction)) if len(Fm) else 0.0,
                           mesh_film_parameter=float(np.mean(reg.film_parameter)) if len(Fm) else 0.0)


def _carrier_drag_parts(case, lub: Lubricant, output_speed_rpm: float, nu_cSt: float,
                        viscous: bool = True) -> tuple[float, float]:
    """(main-bearing pair's Palmgren M0, output seal's moment) [N m] at the carrier's speed."""
    sec = lub.section
    M_main = 2 * viscous * brg.palmgren_no_load_Nm(sec.f0_main, nu_cSt, output_speed_rpm,
                                                   case.main_bearings.pitch_diameter_mm)
    return M_main, brg.seal_moment_Nm(sec.output_seal_diameter_mm)


def carrier_drag_Nm(case, lub: Lubricant, input_speed_rpm: float, oil_temperature_C: float,
                    where: str = "oil temperature") -> float:
    """The torque [N m, >= 0] that resists the carrier's motion whatever the load: the main bearings'
    no-load moment and the output seal, at the input speed's output speed and the oil temperature
    (the carrier_drag_Nm of contact_friction, without a state: it depends on neither). A running
    reducer's mechanism carries load + drag; a bench's torque meter beyond the output reads the load.
    At rest (speed 0) the bearings' viscous part vanishes and the seal's remains. `where` names the
    temperature in the error when it lies outside the lubricant's range."""
    lub.check_temperature(oil_temperature_C, where)
    n_out = abs(float(input_speed_rpm)) / case.ratio
    return float(sum(_carrier_drag_parts(case, lub, n_out, float(lub.kinematic_cSt(oil_temperature_C)),
                                         input_speed_rpm != 0)))
