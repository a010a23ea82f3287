"""Bearing life at rated torque and rated output speed: ISO 281 basic and modified rating life of the
needle (turning-arm) bearings and the crank support bearings, from the model's load distribution.

Loads: static states (dynamics.statics) at rated torque, forward, over one output revolution; each
bearing's equivalent load is the cubic mean (exponent 10/3) of its load over the revolution (ISO 281
variable load). Needle bearing of crank j in disc d: the model's needle force; raceways = eccentric
and disc bore (hardened, b_m 1.1), Z, D_we, L_we from the case, D_pw = eccentric diameter + D_we.
Support pair of crank j: the support forces at the two disc planes F1, F2 split onto the two bearings
by beam statics with the planes ASSUMED one disc width apart, centred in the span L (support_span_mm):
R = |(F1 + F2) / 2 +- (F1 - F2) w / (2 L)|; equivalent P = F_r if F_a / F_r <= e, else 0.4 F_r + Y F_a
(ISO 281, single-row tapered), F_a the stiffness model's preload; geometry from the stiffness model
(roller count, D_we, L_we, contact angle; D_pw = bore + 2 D_we, the roller rule of fem.tapered_roller).
Speeds: crank relative to disc and to carrier at the rated output speed. kappa at the given oil
temperature. The catalog's rated life K (RV-E series: 6000 h at rated torque and 15 rpm) is the
reducer's; the system life of n bearings is (sum L_i^-9/8)^-8/9 (Weibull slope 9/8 of roller
bearings, ISO 281 background), reported beside the weakest bearing.
"""
from __future__ import annotations

import math

import numpy as np

from dynamics.losses import bearings as brg
from dynamics.losses.contacts import RPM_PER_RAD_S, rates
from dynamics.losses.lubricant import Lubricant
from dynamics.losses.operating import revolution_angles_deg
from dynamics.reducer import ReducerModel, evaluate
from dynamics.statics import solve_static

CATALOG_RATED_LIFE_H = 6000.0     # Nabtesco RV-E catalogue: K at rated torque and rated output speed
WEIBULL_SLOPE = 9 / 8


def _system_life(lives) -> float:
    lives = np.asarray(lives, float)
    return float(np.sum(lives ** -WEIBULL_SLOPE) ** (-1 / WEIBULL_SLOPE))


def _entry(name, C, C0, P, n_rpm, dm, nu, ec) -> dict:
    L10h = brg.l10_revolutions(C, P) / (60.0 * n_rpm)
    kappa = nu / brg.rated_viscosity_cSt(n_rpm, dm)
    a = brg.a_iso_roller(kappa, ec * (C0 / 8.2) / P)
    return {"bearing": name, "C_N": C, "C0_N": C0, "P_N": P, "speed_rpm": n_rpm, "dm_mm": dm,
            "L10_h": L10h, "kappa": kappa, "a_iso": a, "Lnm_h": a * L10h}


def bearing_lives(model: ReducerModel, lub: Lubricant, oil_temperature_C: float = 40.0,
                  points_per_rev: int = 24) -> dict:
    case, cr = model.case, model.case.crankshaft
    T = case.rated_torque_Nm
    n_in = case.operation.rated_output_speed_rpm * model.ratio
    ang = revolution_angles_deg(model, points_per_rev)
    lay = model.layout
    needle, support, q = [], [], None
    for th in ang:
        st = solve_static(model, th, T, q, +1)
        q = st.q
        w, _ = evaluate(model, q, math.radians(th))
        needle.append(np.hypot(*np.moveaxis(model.output(w, "bearing_force_N"), -1, 0)))   # (nd, nc)
        support.append(model.output(w, "support_force_N"))                                   # (nc, nd, 2)
    needle, support = np.array(needle), np.array(support)
    dq = rates(model, math.radians(ang[0])) * n_in / RPM_PER_RAD_S
    rot, disc, io = lay["crank_rotation"], lay["disc"], model.i_out
    n_needle = abs(dq[rot.index(0)] - dq[disc.index(0, "rot")]) * RPM_PER_RAD_S
    n_support = abs(dq[rot.index(0)] - dq[io]) * RPM_PER_RAD_S
    nu = float(lub.kinematic_cSt(oil_temperature_C))
    ec = lub.section.contamination_factor
    out = []
    Dw, Lw, Z = cr.needle_diameter_mm, cr.needle_length_mm, cr.needle_count
    dpw = 2 * cr.eccentric_radius_mm + Dw
    C, C0 = brg.dynamic_rating_N(Z, Dw, Lw, dpw), brg.static_rating_N(Z, Dw, Lw, dpw)
    for d in range(needle.shape[1]):
        for j in range(needle.shape[2]):
            out.append(_entry(f"needle crank {j + 1} disc {d + 1}", C, C0, brg.cubic_mean_load_N(needle[:, d, j]),
                              n_needle, dpw, nu, ec))
    sb = model.stiffness.support_bearings
    Dw, Lw, a = sb.roller_diameter_m * 1e3, sb.roller_length_m * 1e3, sb.contact_angle_deg
    dpw = 2 * cr.journal_radius_mm + 2 * Dw
    C = brg.dynamic_rating_N(sb.roller_count, Dw, Lw, dpw, a)
    C0 = brg.static_rating_N(sb.roller_count, Dw, Lw, dpw, a)
    e = 1.5 * math.tan(math.radians(a))
    Y = 0.4 / math.tan(math.radians(a))
    share = case.cycloid.width_mm / (2 * cr.support_span_mm)
    F1, F2 = support[:, :, 0, :], support[:, :, -1, :]                  # (n, nc, 2) the two planes
    for j in range(support.shape[1]):
        for side, sgn in (("flange", 1.0), ("end plate", -1.0)):
            R = np.hypot(*np.moveaxis(0.5 * (F1[:, j] + F2[:, j]) + sgn * share * (F1[:, j] - F2[:, j]), -1, 0))
            P = np.where(sb.preload_N / np.maximum(R, 1e-9) <= e, R, 0.4 * R + Y * sb.preload_N)
            out.append(_entry(f"support crank {j + 1} {side}", C, C0, brg.cubic_mean_load_N(P), n_support, dpw, nu, ec))
    weakest = min(out, key=lambda x: x["L10_h"])
    sys_l10, sys_lnm = _system_life([x["L10_h"] for x in out]), _system_life([x["Lnm_h"] for x in out])
    return {"torque_Nm": T, "output_speed_rpm": case.operation.rated_output_speed_rpm,
            "oil_temperature_C": oil_temperature_C, "viscosity_cSt": nu, "bearings": out,
            "weakest": weakest["bearing"], "weakest_L10_h": weakest["L10_h"], "weakest_Lnm_h": weakest["Lnm_h"],
            "system_L10_h": sys_l10, "system_Lnm_h": sys_lnm, "catalog_rated_life_h": CATALOG_RATED_LIFE_H,
            "weakest_L10_over_catalog": weakest["L10_h"] / CATALOG_RATED_LIFE_H,
            "system_L10_over_catalog": sys_l10 / CATALOG_RATED_LIFE_H}
