"""Test stand-in for the FE stiffness: `stiffness_for_tests(case) -> StiffnessModel` from closed forms.

NOT the production path (that reads build/<case>/fem/stiffness.json from the FEM stage). It exists
so that dynamics tests run fast and before/without the FE stage, with every figure traceable:
  pin contact    Hertz line contact of pin (radius Rr) and profile (curvature radius rho at the
                 contact of the pin at that phase, nominal pose): pin centre approach by Johnson
                 eq. 5.36 plus the disc half-plane approach to 3 mm depth (fem.hertz), fitted to
                 F = k approach^n over 50..3000 N at each phase (0..180 deg).
  turning arm    Palmgren needle approach at Stribeck's Q_max = 4.08 F / Z (fem.hertz), fitted.
  crankshaft     simply supported journal-radius shaft, load at mid-span: 48 E I / L^3; torsion
                 G J / (L / 2) (planet at one end, eccentrics mid-span).
  support        the case file's support_bearing_stiffness_N_per_um.
  involute mesh  ISO 6336-1 single-pair stiffness c' = 14 N/(mm um) per face width; mean mesh
                 stiffness c' eps b, peak-to-peak variation 1 / eps (one vs two pairs); eps from
                 the standard-gear contact-ratio formula.
"""
from __future__ import annotations

import math

import numpy as np

from fem import hertz
from fem.stiffness import SCHEMA, PinContact, StiffnessModel, TurningArm
from geometry.fingerprint import made_from
from geometry import pin_profile
from geometry.params import ReducerCase

ISO_C_PRIME_N_PER_MM_UM = 14.0   # ISO 6336-1 single-pair tooth stiffness, solid spur gears
PIN_LOADS_N = np.geomspace(50.0, 3000.0, 8)
NEEDLE_LOADS_N = np.geomspace(200.0, 20000.0, 8)
DISC_DATUM_DEPTH_M = 3e-3


def _profile_curvature_radius_m(case: ReducerCase, t: np.ndarray) -> np.ndarray:
    """Signed curvature radius of the nominal profile (convex > 0) at parameter t [m]: the
    analytic curvature of the pin-centre curve, offset by the pin radius (geometry.pin_profile)."""
    c = case.cycloid
    kappa = pin_profile.curvature_per_mm(t, c.pin_circle_radius_mm, c.eccentricity_mm, c.zp)
    return pin_profile.profile_curvature_radius_mm(kappa, c.pin_radius_mm) * 1e-3


def contact_ratio(case: ReducerCase) -> float:
    s = case.stage1
    m, al = s.module_mm, math.radians(s.pressure_angle_deg)
    r1, r2 = m * s.z1 / 2, m * s.z2 / 2
    rb1, rb2 = r1 * math.cos(al), r2 * math.cos(al)
    num = math.sqrt((r1 + m) ** 2 - rb1 ** 2) + math.sqrt((r2 + m) ** 2 - rb2 ** 2) - (r1 + r2) * math.sin(al)
    return num / (math.pi * m * math.cos(al))


def _fit(F, d):
    n, lnk = np.polyfit(np.log(d), np.log(F), 1)
    return math.exp(lnk), n


def stiffness_for_tests(case: ReducerCase) -> StiffnessModel:
    E = case.material.youngs_modulus_GPa * 1e9
    nu = case.material.poisson_ratio
    Es = hertz.contact_modulus(E, nu)
    L = case.cycloid.width_mm * 1e-3
    Rr = case.cycloid.pin_radius_mm * 1e-3
    pos = np.linspace(0.0, 180.0, 19)
    # the pin at phase phi touches the profile at t = phi / zc (C(t) has zc lobes; DESIGN.md pose)
    rho = _profile_curvature_radius_m(case, np.deg2rad(pos) / case.cycloid.zc)
    P, Lq = len(pos), len(PIN_LOADS_N)
    app, p0s, bs = np.zeros((P, Lq)), np.zeros((P, Lq)), np.zeros((P, Lq))
    ks, ns = np.zeros(P), np.zeros(P)
    for i, r in enumerate(rho):
        Reff = hertz.effective_radius(Rr, r)
        p0, b = hertz.hertz_line(PIN_LOADS_N, L, Reff, Es)
        d = np.array([hertz.cylinder_centre_approach(F, L, Rr, bb, E, nu)
                      + hertz.half_plane_approach(F, L, bb, DISC_DATUM_DEPTH_M, E, nu)
                      for F, bb in zip(PIN_LOADS_N, b)])
        app[i], p0s[i], bs[i] = d, p0, b
        ks[i], ns[i] = _fit(PIN_LOADS_N, d)
    ck = case.crankshaft
    defl = hertz.needle_bearing_deflection(NEEDLE_LOADS_N, ck.needle_count, ck.needle_length_mm * 1e-3)
    kta, nta = _fit(NEEDLE_LOADS_N, defl)
    I, J = hertz.circle_inertia(ck.journal_radius_mm * 1e-3)
    span = ck.support_span_mm * 1e-3
    G = E / (2 * (1 + nu))
    eps = contact_ratio(case)
    k_mesh = ISO_C_PRIME_N_PER_MM_UM * eps * case.stage1.face_width_mm * 1e6
    return StiffnessModel(
        case_name=case.name,
        pin_contact=PinContact(position_deg=pos, load_N=PIN_LOADS_N.copy(), approach_m=app,
                               peak_pressure_Pa=p0s, half_width_m=bs, law_k_N_per_m_pow=ks, law_n=ns),
        turning_arm=TurningArm(load_N=NEEDLE_LOADS_N.copy(), deflection_m=defl,
                               law_k_N_per_m_pow=kta, law_n=nta),
        crankshaft_bending_stiffness_N_per_m=48 * E * I / span ** 3,
        crankshaft_torsional_stiffness_Nm_per_rad=G * J / (span / 2),
        support_bearing_radial_stiffness_N_per_m=ck.support_bearing_stiffness_N_per_um * 1e6,
        involute_mesh_mean_stiffness_N_per_m=k_mesh,
        involute_mesh_stiffness_variation=1.0 / eps,
        involute_mesh_contact_ratio=eps,
        sources={"all": "tests/support.py closed-form TEST STAND-IN (Hertz/Johnson, Palmgren, beam "
                        "theory, ISO 6336-1), not FE"},
        made_from=made_from(case, SCHEMA))   # fingerprinted like the fem stage's file


def case_path(name: str = "rv40e-81"):
    """Path of a shipped case file (tests do not depend on the working directory)."""
    from pathlib import Path
    return Path(__file__).resolve().parent.parent / "cases" / f"{name}.toml"


def model_for_tests(name: str = "rv40e-81", **errors):
    """Lumped model of a shipped case on the test stand-in stiffness (errors via case.with_errors)."""
    from dynamics.model import build_model
    from geometry.params import load_case
    case = load_case(case_path(name))
    if errors:
        case = case.with_errors(**errors)
    return build_model(case, stiffness_for_tests(case))
