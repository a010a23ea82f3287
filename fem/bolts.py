"""Bolts and pins of the assembled reducer (SI units): VDI 2230 Part 1 (2015) bolt and clamped-part
resilience and the assembly preload, and the shear flexibility of a pin or fitted bolt (Huth).

- Thread: ISO 261 coarse pitch, ISO 724 basic sizes d2 = d - 0.649519 P, d3 = d - 1.226869 P,
  stress area A_S = pi/4 ((d2 + d3)/2)^2 (ISO 898-1). Property class yield R_p0.2,min (ISO 898-1:
  8.8 640 MPa up to M16 and 660 above, 10.9 940, 12.9 1100).
- Assembly preload (VDI 2230-1 eq. R7/1, the permissible assembly preload at utilisation nu = 0.9
  of the yield under the combined tension and thread torsion, the torsion with the plastic-section
  factor 3/2): F_M,zul = A_S nu R_p0.2 / sqrt(1 + 3 [1.5 (d2/d_S)(P/(pi d2) + 1.155 mu_G)]^2),
  d_S = (d2 + d3)/2. This is the nominal preload of a torque-controlled joint; the tightening
  scatter (alpha_A = 1.4..1.6 for a torque wrench, VDI table A8) lowers the minimum, not the nominal.
- Bolt resilience (VDI 2230-1 sec. 5.1.1): head 0.4 d / (E A_N) (socket head cap screw), the
  clamped part as shank l_K - d (A_N) and one d of free thread (A_d3), engaged thread 0.5 d / (E A_d3)
  and the tapped-thread region 0.33 d / (E A_N) (ESV, bolt in a tapped hole).
- Clamped-part resilience (VDI 2230-1 sec. 5.1.2, cone and sleeve): tapped-thread joint (ESV, w = 2)
  tan phi = 0.348 + 0.013 ln(beta_L) + 0.193 ln(y), beta_L = l_K / d_W, y = D_A / d_W; limiting
  diameter D_A,Gr = d_W + w l_K tan phi; for D_A >= D_A,Gr the cone alone,
  delta_P = 2 ln[(d_W + d_h)(d_W + w l_K tan phi - d_h) / ((d_W - d_h)(d_W + w l_K tan phi + d_h))]
           / (w E pi d_h tan phi),
  else cone plus sleeve (eq. 5.1/24): delta_P = [2/(w d_h tan phi) ln((d_W + d_h)(D_A - d_h) /
  ((d_W - d_h)(D_A + d_h))) + 4/(D_A^2 - d_h^2) (l_K - (D_A - d_W)/(w tan phi))] / (E pi).
  d_W: head bearing diameter (ISO 4762 head diameter d_k), d_h: ISO 273 medium clearance hole.
- Pin / fitted fastener in single shear (Huth 1986, ASTM STP 927, pp. 221-250, bolted metallic
  joints a = 2/3, b = 3.0): C = ((t1 + t2)/(2 d))^a (b/n) [1/(t1 E1) + 1/(n t2 E2) + 1/(2 t1 E3)
  + 1/(2 n t2 E3)], n = 1 single shear; k = 1/C. A taper pin is reamed in both parts (no
  clearance), the condition Huth's bolted constants were fitted to.

Limits: steel bolts and parts of one modulus; no thread stripping or embedding loss (VDI f_Z,
a few um, lowers the preload by a few per cent); the clamped part treated as a solid cylinder of
diameter D_A around one bolt.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from geometry.artifacts import InputError

# d: (P, d_k ISO 4762 head diameter, d_h ISO 273 medium hole) [mm]
THREADS = {3.0: (0.5, 5.5, 3.4), 4.0: (0.7, 7.0, 4.5), 5.0: (0.8, 8.5, 5.5), 6.0: (1.0, 10.0, 6.6),
           8.0: (1.25, 13.0, 9.0), 10.0: (1.5, 16.0, 11.0), 12.0: (1.75, 18.0, 13.5),
           14.0: (2.0, 21.0, 15.5), 16.0: (2.0, 24.0, 17.5), 20.0: (2.5, 30.0, 22.0), 24.0: (3.0, 36.0, 26.0)}
YIELD_MPA = {8.8: (640.0, 660.0), 10.9: (940.0, 940.0), 12.9: (1100.0, 1100.0)}   # (<= M16, > M16)
UTILISATION = 0.9            # VDI 2230 nu: the tabulated assembly preloads F_M,Tab
HUTH_A, HUTH_B = 2.0 / 3.0, 3.0   # bolted metallic joints
VDI_SOURCE = "VDI 2230 Part 1 (2015): assembly preload eq. R7/1 (nu = 0.9), bolt and cone/sleeve member resilience"
HUTH_SOURCE = "Huth 1986 (ASTM STP 927): fastener flexibility, bolted metallic a = 2/3, b = 3.0, single shear"


@dataclass(frozen=True)
class Thread:
    d_m: float
    pitch_m: float
    head_diameter_m: float       # d_W = d_k (ISO 4762)
    hole_diameter_m: float       # d_h (ISO 273 medium)

    @property
    def d2_m(self) -> float:
        return self.d_m - 0.649519 * self.pitch_m

    @property
    def d3_m(self) -> float:
        return self.d_m - 1.226869 * self.pitch_m

    @property
    def stress_diameter_m(self) -> float:
        return 0.5 * (self.d2_m + self.d3_m)

    @property
    def stress_area_m2(self) -> float:
        return math.pi / 4 * self.stress_diameter_m ** 2


def thread(d_mm: float) -> Thread:
    if d_mm not in THREADS:
        raise InputError(f"bolt thread M{d_mm:g}: allowed ISO 261 coarse sizes "
                         f"{', '.join('M%g' % t for t in THREADS)}")
    P, dk, dh = THREADS[d_mm]
    return Thread(d_mm * 1e-3, P * 1e-3, dk * 1e-3, dh * 1e-3)


def yield_Pa(property_class: float, d_mm: float) -> float:
    key = min(YIELD_MPA, key=lambda c: abs(c - property_class))
    if abs(key - property_class) > 1e-6:
        raise InputError(f"property class {property_class!r}: allowed {', '.join('%g' % c for c in YIELD_MPA)}")
    return YIELD_MPA[key][0 if d_mm <= 16 else 1] * 1e6


def assembly_preload_N(d_mm: float, property_class: float, thread_friction: float,
                       utilisation: float = UTILISATION) -> float:
    """VDI 2230 F_M,zul (module doc)."""
    t = thread(d_mm)
    if not 0 < thread_friction < 1:
        raise InputError(f"thread friction = {thread_friction!r}: allowed 0 < mu_G < 1")
    torsion = 1.5 * t.d2_m / t.stress_diameter_m * (t.pitch_m / (math.pi * t.d2_m) + 1.155 * thread_friction)
    return t.stress_area_m2 * utilisation * yield_Pa(property_class, d_mm) / math.sqrt(1 + 3 * torsion ** 2)


@dataclass(frozen=True)
class BoltedJoint:
    preload_N: float
    bolt_stiffness_N_per_m: float
    member_stiffness_N_per_m: float
    cone_tan_phi: float
    source: str = VDI_SOURCE

    @property
    def load_factor(self) -> float:
        """Phi_K = delta_P / (delta_S + delta_P): share of an axial service load the bolt takes."""
        return self.bolt_stiffness_N_per_m / (self.bolt_stiffness_N_per_m + self.member_stiffness_N_per_m)


def bolt_resilience_m_per_N(t: Thread, clamp_length_m: float, E_Pa: float) -> float:
    """delta_S of a socket head cap screw in a tapped hole (module doc)."""
    AN, Ad3 = math.pi / 4 * t.d_m ** 2, math.pi / 4 * t.d3_m ** 2
    d = t.d_m
    shank = max(clamp_length_m - d, 0.0)
    free_thread = min(d, clamp_length_m)
    return (0.4 * d / AN + shank / AN + free_thread / Ad3 + 0.5 * d / Ad3 + 0.33 * d / AN) / E_Pa


def member_resilience_m_per_N(t: Thread, clamp_length_m: float, outer_diameter_m: float, E_Pa: float,
                              w: float = 2.0) -> tuple[float, float]:
    """(delta_P, tan phi) of the clamped parts, VDI cone (and sleeve), tapped-thread joint w = 2."""
    dW, dh, lK = t.head_diameter_m, t.hole_diameter_m, clamp_length_m
    DA = max(outer_diameter_m, dW)
    tan_phi = 0.348 + 0.013 * math.log(lK / dW) + 0.193 * math.log(DA / dW)
    D_gr = dW + w * lK * tan_phi
    if DA >= D_gr:
        num = (dW + dh) * (dW + w * lK * tan_phi - dh)
        den = (dW - dh) * (dW + w * lK * tan_phi + dh)
        return 2 * math.log(num / den) / (w * E_Pa * math.pi * dh * tan_phi), tan_phi
    cone = 2 / (w * dh * tan_phi) * math.log((dW + dh) * (DA - dh) / ((dW - dh) * (DA + dh)))
    sleeve = 4 / (DA ** 2 - dh ** 2) * (lK - (DA - dW) / (w * tan_phi))
    return (cone + sleeve) / (E_Pa * math.pi), tan_phi


def bolted_joint(d_mm: float, property_class: float, thread_friction: float, clamp_length_m: float,
                 member_diameter_m: float, E_Pa: float) -> BoltedJoint:
    if not clamp_length_m > 0:
        raise InputError(f"clamp length = {clamp_length_m!r} m: must be > 0")
    t = thread(d_mm)
    dP, tan_phi = member_resilience_m_per_N(t, clamp_length_m, member_diameter_m, E_Pa)
    return BoltedJoint(assembly_preload_N(d_mm, property_class, thread_friction),
                       1.0 / bolt_resilience_m_per_N(t, clamp_length_m, E_Pa), 1.0 / dP, tan_phi)


def huth_shear_stiffness_N_per_m(d_m: float, t1_m: float, t2_m: float, E_Pa: float,
                                 E_fastener_Pa: float | None = None) -> float:
    """1 / C of a pin or fitted bolt in single shear between plates t1 and t2 (Huth, module doc)."""
    if min(d_m, t1_m, t2_m) <= 0:
        raise InputError(f"pin diameter {d_m!r} m, lengths {t1_m!r}, {t2_m!r} m: all must be > 0")
    E3 = E_Pa if E_fastener_Pa is None else E_fastener_Pa
    n = 1.0
    C = ((t1_m + t2_m) / (2 * d_m)) ** HUTH_A * HUTH_B / n * (
        1 / (t1_m * E_Pa) + 1 / (n * t2_m * E_Pa) + 1 / (2 * t1_m * E3) + 1 / (2 * n * t2_m * E3))
    return 1.0 / C
