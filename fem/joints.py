"""Joint (contact-layer) compliance of the interfaces a part FE treats as bonded or rigid (SI units):
bearing rings in their seats, the bolted and pinned pillar joint, the output flange face.

Contact-layer law (Levina & Reshetov, "Contact stiffness of machine joints" 1971; Rivin, Stiffness
and Damping in Mechanical Design, 1999, ch. 4): the normal approach of two machined, nominally flat
steel surfaces under the nominal pressure p is delta = c p^m, m = 0.5, with c set by the finish
(FINISHES: c in um / MPa^0.5, a range per finish class of the rougher surface's Ra). The middle of
the range is the default ('mid'); 'low' (stiffer) and 'high' (softer) are its ends, so every figure
below is a band. The data behind the law are machine-tool joints at nominal pressures of the order of
tens of MPa; every result flags a pressure beyond P_LAW_MAX_PA (`beyond_law`). NOTE: the project's
stored references do not hold the book's table; the class ranges are recalled from Rivin ch. 4, not
verified here, and must be checked against the book before they are quoted.
Tangent normal stiffness per area k_n = dp/d delta = p^(1 - m) / (m c) [N/m^3].
Tangential stiffness per area k_t = k_n 2(1 - nu)/(2 - nu) (Mindlin's ratio for one circular
contact, which holds for randomly rough interfaces too: Campana, Persson & Mueser, J. Phys.:
Condens. Matter 23 (2011) 085001), no slip.

Bearing ring in its seat (ring_seat_radial): the seat layer carries the fit pressure p_f all round
plus the load zone of a zero-clearance Stribeck distribution, p(psi) = p_f + p0 cos^n(psi) on
|psi| < 90 deg (n = 10/9 rollers, 3/2 balls: the roller loads of Harris' load-zone integral with
epsilon = 0.5, spread by the ring), p0 from equilibrium F = p0 R B I1, I1 = int cos^(n+1). The
ring's radial displacement is the one work-conjugate to F for that traction shape (Castigliano):
  du/dF = int s(psi)^2 / k_n(p(psi)) dpsi / (R B I1^2),  u(F) = int s [delta(p) - delta(p_f)] dpsi / I1,
s = cos^n. Tangent at the operating load, secant u/F. The fit pressure from the interference
(ISO 286 with ISO 492 ring tolerances: the case's mean interference) by Lame (Timoshenko & Goodier
sec. 28), the interference shared by the rings' elastic strain and the layer's own approach:
I/2 = p_f (R/E)[(c_o^2 + b^2)/(c_o^2 - b^2) + (b^2 + a^2)/(b^2 - a^2)] + delta(p_f) (one E, nu).
Plastic smoothing of the peaks on pressing in (DIN 7190's 0.8 (Rz_i + Rz_a)) is left out: the
layer law already carries the roughness.

Pillar joint (pillar_joint_layer): the bolt preload over the face, p = F_V / A (uniform: the
VDI pressure cone concentrates it near the bolt, the mean is used), gives K_n = k_n A and
K_t = k_t A + the taper pin in shear (fem.bolts, Huth). As a layer of thickness h in an FE that
already holds steel there: h / E_layer = A / K_n + h / E_steel (the layer carries the joint's
compliance and not the steel it replaces), the same with G; the layer's own Poisson ratio 0, so
its normal stiffness is E_layer A / h.

Flange face (flange_face_torsional): the face's tangential layer over its polar moment,
K_theta = k_t J_p, J_p = pi (r_o^4 - r_i^4) / 2, p = total preload / annulus area; no slip
assumed and checked: the friction torque mu F_total r_f (r_f = 2/3 (r_o^3 - r_i^3)/(r_o^2 - r_i^2))
against the momentary torque; when it slips the bolts carry the torque in shear (Huth, n r_b^2 k).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.integrate import quad
from scipy.optimize import brentq
from scipy.special import gamma

from fem import bolts
from geometry.artifacts import InputError

M_EXP = 0.5                    # Levina's exponent for machined steel joints
# ASSUMED: the order of the nominal pressures machine-joint data were taken at (tens of MPa); the
# results flag a pressure beyond it as an extrapolation of the law
P_LAW_MAX_PA = 50e6
# Ra upper bound of the rougher face [um], finish, c low / high [um / MPa^0.5] (Rivin ch. 4, see doc)
FINISHES = ((0.4, "fine ground / lapped", 0.3, 0.6), (1.6, "ground", 0.5, 1.0),
            (3.2, "fine turned / milled", 1.0, 2.0), (6.3, "turned / milled", 2.0, 3.0))
BANDS = ("low", "mid", "high")
LAW_SOURCE = ("contact layer delta = c p^0.5, Levina & Reshetov (1971) / Rivin, Stiffness and Damping "
              "in Mechanical Design (1999) ch. 4; tangential k_t = k_n 2(1-nu)/(2-nu) (Mindlin; Campana, "
              "Persson & Mueser 2011)")
LINE_CONTACT_N, POINT_CONTACT_N = 10.0 / 9.0, 1.5


@dataclass(frozen=True)
class LayerLaw:
    c_SI: float                  # m / Pa^m
    m: float
    finish: str
    band: str
    Ra_um: float

    def approach_m(self, p_Pa):
        return self.c_SI * np.maximum(np.asarray(p_Pa, float), 0.0) ** self.m

    def pressure_Pa(self, delta_m):
        return (np.maximum(np.asarray(delta_m, float), 0.0) / self.c_SI) ** (1.0 / self.m)

    def compliance_m3_per_N(self, p_Pa):
        """d delta / dp = m c p^(m-1) (infinite at p = 0 for m < 1)."""
        p = np.asarray(p_Pa, float)
        with np.errstate(divide="ignore"):
            return self.m * self.c_SI * p ** (self.m - 1.0)

    def normal_stiffness_N_per_m3(self, p_Pa):
        return 1.0 / self.compliance_m3_per_N(p_Pa)


def contact_law(Ra_um: float, band: str = "mid") -> LayerLaw:
    """The layer law of the finish class holding Ra (the rougher face); band low / mid / high."""
    if band not in BANDS:
        raise InputError(f"band = {band!r}: allowed {', '.join(BANDS)}")
    if not 0 < Ra_um <= FINISHES[-1][0]:
        raise InputError(f"surface finish Ra = {Ra_um!r} um: allowed 0 < Ra <= {FINISHES[-1][0]} um "
                         f"(classes {', '.join(f[1] for f in FINISHES)})")
    _, name, lo, hi = next(f for f in FINISHES if Ra_um <= f[0] + 1e-12)
    c_um = {"low": lo, "mid": 0.5 * (lo + hi), "high": hi}[band]
    return LayerLaw(c_um * 1e-6 / 1e6 ** M_EXP, M_EXP, name, band, Ra_um)


def tangential_ratio(nu: float) -> float:
    """k_t / k_n = 2(1 - nu)/(2 - nu) (Mindlin)."""
    return 2 * (1 - nu) / (2 - nu)


# ---------------------------------------------------------------- fits
def lame_fit_compliance_m_per_Pa(d_m: float, inner_d_m: float, outer_d_m: float, E_Pa: float) -> float:
    """Radial interference per fit pressure of a shaft (bore inner_d) in a hub (outer_d), one E."""
    b, a, c = d_m / 2, inner_d_m / 2, outer_d_m / 2
    if not 0 <= a < b < c:
        raise InputError(f"fit diameters inner {inner_d_m!r}, seat {d_m!r}, outer {outer_d_m!r} m: "
                         f"need inner < seat < outer")
    return b / E_Pa * ((c * c + b * b) / (c * c - b * b) + (b * b + a * a) / (b * b - a * a))


def fit_pressure_Pa(interference_m: float, d_m: float, inner_d_m: float, outer_d_m: float, E_Pa: float,
                    law: LayerLaw | None = None) -> float:
    """Fit pressure of a diametral interference: Lame alone (law None) or shared with the layer."""
    if interference_m < 0:
        raise InputError(f"interference = {interference_m!r} m: allowed >= 0 (a clearance fit has no pressure)")
    lam = lame_fit_compliance_m_per_Pa(d_m, inner_d_m, outer_d_m, E_Pa)
    target = interference_m / 2
    if law is None or target == 0:
        return target / lam
    return brentq(lambda p: lam * p + float(law.approach_m(p)) - target, 0.0, target / lam, xtol=1e-6)


# ---------------------------------------------------------------- ring in its seat
@dataclass(frozen=True)
class RingSeat:
    compliance_m_per_N: float            # tangent at the load, 'mid'
    secant_m_per_N: float                # u(F) / F, 'mid'
    band_compliance_m_per_N: tuple       # (low, high) tangent
    band_secant_m_per_N: tuple
    load_zone_peak_Pa: float             # p0
    fit_pressure_Pa: float
    source: str

    @property
    def beyond_law(self) -> bool:
        """The layer's largest pressure is past the law's data (P_LAW_MAX_PA): an extrapolation."""
        return self.fit_pressure_Pa + self.load_zone_peak_Pa > P_LAW_MAX_PA


def _load_zone(n: float):
    s = lambda psi: np.cos(psi) ** n  # noqa: E731
    I1 = math.sqrt(math.pi) * gamma((n + 2) / 2) / gamma((n + 3) / 2)      # int cos^(n+1), |psi| < pi/2
    return s, I1


def _ring_seat(law: LayerLaw, F: float, R: float, B: float, pf: float, n: float) -> tuple[float, float, float]:
    s, I1 = _load_zone(n)
    p0 = F / (R * B * I1)
    tan = quad(lambda x: s(x) ** 2 * float(law.compliance_m3_per_N(pf + p0 * s(x))), -math.pi / 2, math.pi / 2,
               limit=200)[0] / (R * B * I1 ** 2)
    u = quad(lambda x: s(x) * float(law.approach_m(pf + p0 * s(x)) - law.approach_m(pf)),
             -math.pi / 2, math.pi / 2, limit=200)[0] / I1
    return tan, u / F, p0


def ring_seat_radial(load_N: float, diameter_m: float, width_m: float, fit_pressure_Pa: float,
                     finish_Ra_um: float, *, exponent: float = LINE_CONTACT_N) -> RingSeat:
    """Tangent and secant radial compliance of a ring's seat layer under a radial load (module doc)."""
    for name, v in (("load_N", load_N), ("diameter_m", diameter_m), ("width_m", width_m)):
        if not v > 0:
            raise InputError(f"ring seat {name} = {v!r}: must be > 0")
    if fit_pressure_Pa < 0:
        raise InputError(f"ring seat fit_pressure_Pa = {fit_pressure_Pa!r}: must be >= 0")
    out = {b: _ring_seat(contact_law(finish_Ra_um, b), load_N, diameter_m / 2, width_m, fit_pressure_Pa,
                         exponent) for b in BANDS}
    law = contact_law(finish_Ra_um)
    return RingSeat(out["mid"][0], out["mid"][1], (out["low"][0], out["high"][0]),
                    (out["low"][1], out["high"][1]), out["mid"][2], fit_pressure_Pa,
                    f"{LAW_SOURCE}; {law.finish} (Ra {finish_Ra_um:g} um); load zone p_f + p0 cos^{exponent:.3g} "
                    f"over +-90 deg (Stribeck, zero clearance), displacement work-conjugate to the load")


# ---------------------------------------------------------------- pillar joint as an FE layer
@dataclass(frozen=True)
class LayerJoint:
    normal_stiffness_N_per_m: float      # contact layer k_n A (+ bolt, see pillar_joint_layer)
    tangential_stiffness_N_per_m: float  # k_t A + pin
    face_area_m2: float
    pressure_Pa: float
    pin_stiffness_N_per_m: float
    E_steel_Pa: float
    G_steel_Pa: float
    band: str

    @property
    def beyond_law(self) -> bool:
        return self.pressure_Pa > P_LAW_MAX_PA

    def E_layer_Pa(self, h_m: float) -> float:
        """Modulus of an FE layer of thickness h that adds the joint's normal compliance to the steel's."""
        return h_m / (self.face_area_m2 / self.normal_stiffness_N_per_m + h_m / self.E_steel_Pa)

    def G_layer_Pa(self, h_m: float) -> float:
        return h_m / (self.face_area_m2 / self.tangential_stiffness_N_per_m + h_m / self.G_steel_Pa)


@dataclass(frozen=True)
class PillarJoint:
    mid: LayerJoint
    low: LayerJoint
    high: LayerJoint
    source: str


def _layer(law, preload_N, area, nu, E, k_pin, k_bolt):
    p = preload_N / area
    kn = float(law.normal_stiffness_N_per_m3(p))
    return LayerJoint(kn * area + k_bolt, tangential_ratio(nu) * kn * area + k_pin, area, p, k_pin, E,
                      E / (2 * (1 + nu)), law.band)


def pillar_joint_layer(preload_N: float, face_area_m2: float, finish_Ra_um: float, *, E_Pa: float = 206e9,
                       nu: float = 0.3, pin_stiffness_N_per_m: float = 0.0,
                       bolt_stiffness_N_per_m: float = 0.0) -> PillarJoint:
    """The bolted, pinned pillar-to-plate joint as an FE layer (module doc). The bolt's axial
    stiffness (fem.bolts) acts in parallel with the layer when the joint is pulled apart."""
    if not preload_N > 0 or not face_area_m2 > 0:
        raise InputError(f"pillar joint preload {preload_N!r} N, face area {face_area_m2!r} m^2: both must be > 0")
    b = {band: _layer(contact_law(finish_Ra_um, band), preload_N, face_area_m2, nu, E_Pa,
                      pin_stiffness_N_per_m, bolt_stiffness_N_per_m) for band in BANDS}
    return PillarJoint(b["mid"], b["low"], b["high"],
                       f"{LAW_SOURCE}; uniform face pressure F_V / A; taper pin in shear ({bolts.HUTH_SOURCE}) "
                       f"and bolt (VDI 2230) in parallel; layer: h/E_layer = A/K + h/E_steel")


# ---------------------------------------------------------------- flange face in torsion
@dataclass(frozen=True)
class FlangeFace:
    compliance_rad_per_Nm: float          # no slip, 'mid'
    band_compliance_rad_per_Nm: tuple     # (low, high)
    pressure_Pa: float
    slip_torque_Nm: float
    slips: bool                           # at the checked torque
    bolt_shear_compliance_rad_per_Nm: float   # what carries the torque once it slips
    source: str

    @property
    def beyond_law(self) -> bool:
        return self.pressure_Pa > P_LAW_MAX_PA


def flange_face_torsional(inner_r_m: float, outer_r_m: float, preload_total_N: float, bolt_count: int,
                          finish_Ra_um: float, *, friction: float, torque_Nm: float, bolt_circle_r_m: float,
                          bolt_d_m: float, plate_t_m: float, E_Pa: float = 206e9, nu: float = 0.3) -> FlangeFace:
    """Torsional compliance of a bolted flange face joint (module doc)."""
    if not 0 < inner_r_m < outer_r_m:
        raise InputError(f"flange face radii {inner_r_m!r}, {outer_r_m!r} m: need 0 < inner < outer")
    if not preload_total_N > 0 or bolt_count < 1:
        raise InputError(f"flange preload {preload_total_N!r} N, bolt count {bolt_count!r}: need > 0")
    area = math.pi * (outer_r_m ** 2 - inner_r_m ** 2)
    Jp = math.pi * (outer_r_m ** 4 - inner_r_m ** 4) / 2
    p = preload_total_N / area
    comp = {b: 1.0 / (tangential_ratio(nu) * float(contact_law(finish_Ra_um, b).normal_stiffness_N_per_m3(p)) * Jp)
            for b in BANDS}
    r_f = 2 / 3 * (outer_r_m ** 3 - inner_r_m ** 3) / (outer_r_m ** 2 - inner_r_m ** 2)
    t_slip = friction * preload_total_N * r_f
    k_b = bolts.huth_shear_stiffness_N_per_m(bolt_d_m, plate_t_m, plate_t_m, E_Pa)
    return FlangeFace(comp["mid"], (comp["low"], comp["high"]), p, t_slip, abs(torque_Nm) > t_slip,
                      1.0 / (bolt_count * bolt_circle_r_m ** 2 * k_b),
                      f"{LAW_SOURCE}; K = k_t J_p over the annulus, no slip below mu F r_f; bolts in shear "
                      f"({bolts.HUTH_SOURCE})")
