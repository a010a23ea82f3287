"""Test stand-in for the FE stiffness: `stiffness_for_tests(case) -> StiffnessModel` from closed forms.

NOT the production path (that reads build/<case>/fem/stiffness.json from the FEM stage). It exists
so that dynamics tests run fast and before/without the FE stage, with every figure traceable:
  pin contact    Hertz line contact of pin (radius Rr) and profile (curvature radius rho at the
                 contact of the pin at that phase, nominal pose): pin centre approach by Johnson
                 eq. 5.36 plus the disc half-plane approach to 3 mm depth (fem.hertz), fitted to
                 F = k approach^n over 50..3000 N at each phase (0..180 deg).
  turning arm    Palmgren needle approach at Stribeck's Q_max = 4.08 F / Z (fem.hertz), fitted.
  crankshaft     torsion G J / (L / 2) of the journal-radius shaft (planet at one end, eccentrics
                 mid-span); bending: the stepped Timoshenko beam with both eccentrics loaded
                 (fem.crank_tilt.beam_flexibility, supports spread over the seats), 1 / C11 of it.
  support        the case's tapered roller bearing (fem.tapered_roller.case_support_setup) by the
                 Palmgren-Stribeck closed form (rigid rings, zero clearance, no preload):
                 delta(F) = rigid_ring_radial_deflection_m, stiffness its tangent F / (0.9 delta) at
                 the operating load of the rated torque.
  carrier        the portal-frame closed form (rigid plates, flange held, pillars as fixed-guided
                 Timoshenko beams; fem.carrier.portal_frame_reference) as a rigid turn of the end
                 plate's seats about the axis, the flange seats rigid: C = a^2 t t^T / K on the
                 end-plate seats (t the tangents).
  pin series     disc body RIGID (no closed form for the holed disc: the FE is fem.disc_body);
                 groove: the housing's half-plane approach to one pin pitch under Hertz line contact
                 with the clearance radius R' = R (R + dR) / dR, H7/h6 mean clearance (the small-angle
                 limit of fem.pin_groove's conformal contact).
  involute mesh  ISO 6336-1 single-pair stiffness c' = 14 N/(mm um) per face width; mean mesh
                 stiffness c' eps b, peak-to-peak variation 1 / eps (one vs two pairs); eps from
                 the standard-gear contact-ratio formula.
  main bearings  the case's preloaded ball pair by its linearised closed form (fem.main_bearings.
                 preloaded_closed_form, Jones/Harris at no external load).
  joints         the support bearings' seat layers and cup bending at the rated load (fem.components.
                 joints.seat_compliance_m_per_N: closed forms); the carrier's joint layers left out
                 (they need the carrier FE): carrier_delta zero.
  housing        one mode: the pin ring turning as the inner edge of an annulus clamped at the bolt
                 circle, theta / T = (1/a^2 - 1/b^2) / (4 pi G t) (fem.housing_checks.annulus_torsion_rad_per_Nm),
                 modal mass from the ring's polar inertia; no residual.
"""
from __future__ import annotations

import math

import numpy as np

from fem import hertz
from fem.stiffness import (SCHEMA, CarrierSeats, CrankBending, PinContact, PinSeries, StiffnessModel,
                           SupportBearings, TurningArm)
from geometry.fingerprint import made_from
from geometry import pin_profile
from geometry.params import ReducerCase

ISO_C_PRIME_N_PER_MM_UM = 14.0   # ISO 6336-1 single-pair tooth stiffness, solid spur gears
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


def _tables(case: ReducerCase) -> tuple[np.ndarray, np.ndarray]:
    """Pin and needle load levels over the FE stage's ranges (fem.reduce.table_loads_N)."""
    from fem.reduce import table_loads_N
    t = table_loads_N(case)
    return t["pin"], t["needle"]


def _support_bearings(case: ReducerCase) -> SupportBearings:
    from fem import tapered_roller as tr
    su = tr.case_support_setup(case)
    b = su.bearing
    op = tr.operating_radial_load_N(case, case.rated_torque_Nm)
    loads = np.geomspace(0.02, 1.0, 8) * 2 * tr.crank_support_load_N(case, case.operation.momentary_torque_Nm)["radial_N"]
    defl = np.array([tr.rigid_ring_radial_deflection_m(b, F) for F in loads])
    k = op / (0.9 * tr.rigid_ring_radial_deflection_m(b, op))
    return SupportBearings(b.designation, b.roller_count, b.roller_length_mm * 1e-3, b.roller_diameter_mm * 1e-3,
                           float(np.degrees(b.alpha_rad)), su.preload_N, loads, defl, op, k)


def _carrier(case: ReducerCase) -> CarrierSeats:
    from fem.carrier import portal_frame_reference
    from geometry.carrier import CarrierGeometry
    g = CarrierGeometry.from_case(case)
    K = portal_frame_reference(g, case.material.youngs_modulus_GPa * 1e9,
                               case.material.poisson_ratio)["end_plate_stiffness_Nm_per_rad"]
    nc, a = g.crank_count, g.crank_circle_radius_mm * 1e-3
    t = np.zeros(4 * nc)
    for j, b in enumerate(g.crank_angles_rad()):
        t[4 * j + 2:4 * j + 4] = -math.sin(b), math.cos(b)          # seat 1 = end plate
    return CarrierSeats(a * a * np.outer(t, t) / K)


def _pin_series(case: ReducerCase, loads: np.ndarray) -> PinSeries:
    from fem.pin_groove import iso286_h7_h6_radial_clearance_m
    c, E, nu = case.cycloid, case.material.youngs_modulus_GPa * 1e9, case.material.poisson_ratio
    R, w = c.pin_radius_mm * 1e-3, c.width_mm * 1e-3
    dR = iso286_h7_h6_radial_clearance_m(2 * c.pin_radius_mm)[1]
    pitch = 2 * math.pi * c.pin_circle_radius_mm * 1e-3 / c.zp
    _, b = hertz.hertz_line(loads, w, R * (R + dR) / dR, hertz.contact_modulus(E, nu))
    d = np.array([hertz.half_plane_approach(F, w, bb, pitch, E, nu) for F, bb in zip(loads, b)])
    return PinSeries(0.0, loads.copy(), d)


def _parts(case: ReducerCase) -> dict:
    from fem import main_bearings as mb
    from fem.components import joints, main_bearings
    k_rad, k_tilt = mb.preloaded_closed_form(mb.case_pair(case))
    nc = case.carrier.crank_count
    from fem.components import housing
    from fem.housing_checks import annulus_torsion_rad_per_Nm
    h, c, mat = case.housing, case.cycloid, case.material
    a, b, t = c.pin_circle_radius_mm * 1e-3, h.bolt_circle_radius_mm * 1e-3, h.pin_ring_length_mm * 1e-3
    k_theta = 1.0 / annulus_torsion_rad_per_Nm(a, b, mat.youngs_modulus_GPa * 1e9, mat.poisson_ratio, t)
    th = 2 * np.pi * np.arange(c.zp) / c.zp
    phi = np.column_stack([-np.sin(th), np.cos(th)]).reshape(-1, 1) / math.sqrt(c.zp)   # unit-norm turn of every pin
    J = mat.density_kg_per_m3 * t * math.pi * (h.pin_ring_outer_radius_mm ** 4 - a ** 4 * 1e12) * 1e-12 / 2
    ring = housing.Entry(phi, np.array([k_theta / (c.zp * a * a)]), np.array([J / (c.zp * a * a)]), 0.0)
    return {"housing": ring, "main_bearings": main_bearings.Entry(k_rad, k_tilt, main_bearings.plane_z_m(case)),
            "joints": joints.Entry(np.zeros((4 * nc, 4 * nc)), joints.seat_compliance_m_per_N(case)["total_m_per_N"],
                                   (0.75, 1.5))}


def stiffness_for_tests(case: ReducerCase) -> StiffnessModel:
    from fem.crank_tilt import beam_flexibility, two_eccentric_blocks
    E = case.material.youngs_modulus_GPa * 1e9
    nu = case.material.poisson_ratio
    Es = hertz.contact_modulus(E, nu)
    L = case.cycloid.width_mm * 1e-3
    Rr = case.cycloid.pin_radius_mm * 1e-3
    pin_loads, needle_loads = _tables(case)
    pos = np.linspace(0.0, 180.0, 19)
    # the pin at phase phi touches the profile at t = phi / zc (C(t) has zc lobes; DESIGN.md pose)
    rho = _profile_curvature_radius_m(case, np.deg2rad(pos) / case.cycloid.zc)
    P, Lq = len(pos), len(pin_loads)
    app, p0s, bs = np.zeros((P, Lq)), np.zeros((P, Lq)), np.zeros((P, Lq))
    ks, ns = np.zeros(P), np.zeros(P)
    for i, r in enumerate(rho):
        Reff = hertz.effective_radius(Rr, r)
        p0, b = hertz.hertz_line(pin_loads, L, Reff, Es)
        d = np.array([hertz.cylinder_centre_approach(F, L, Rr, bb, E, nu)
                      + hertz.half_plane_approach(F, L, bb, DISC_DATUM_DEPTH_M, E, nu)
                      for F, bb in zip(pin_loads, b)])
        app[i], p0s[i], bs[i] = d, p0, b
        ks[i], ns[i] = _fit(pin_loads, d)
    ck = case.crankshaft
    defl = hertz.needle_bearing_deflection(needle_loads, ck.needle_count, ck.needle_length_mm * 1e-3)
    kta, nta = _fit(needle_loads, defl)
    _, J = hertz.circle_inertia(ck.journal_radius_mm * 1e-3)
    span = ck.support_span_mm * 1e-3
    G = E / (2 * (1 + nu))
    eps = contact_ratio(case)
    k_mesh = ISO_C_PRIME_N_PER_MM_UM * eps * case.stage1.face_width_mm * 1e6
    Cb, Jf = two_eccentric_blocks(beam_flexibility(case))
    return StiffnessModel(
        case_name=case.name,
        pin_contact=PinContact(position_deg=pos, load_N=pin_loads.copy(), approach_m=app,
                               peak_pressure_Pa=p0s, half_width_m=bs, law_k_N_per_m_pow=ks, law_n=ns),
        turning_arm=TurningArm(load_N=needle_loads.copy(), deflection_m=defl,
                               law_k_N_per_m_pow=kta, law_n=nta),
        crankshaft_bending_stiffness_N_per_m=1.0 / Cb[0, 0],
        crankshaft_torsional_stiffness_Nm_per_rad=G * J / (span / 2),
        involute_mesh_mean_stiffness_N_per_m=k_mesh,
        involute_mesh_stiffness_variation=1.0 / eps,
        involute_mesh_contact_ratio=eps,
        support_bearings=_support_bearings(case),
        crank_bending=CrankBending(Cb, Jf),
        carrier=_carrier(case),
        pin_series=_pin_series(case, pin_loads),
        parts=_parts(case),
        sources={"all": "tests/support.py closed-form TEST STAND-IN (Hertz/Johnson, Palmgren, Stribeck, "
                        "stepped beam, portal frame, ISO 6336-1; disc body rigid), not FE"},
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


def computed_once(tmp_path_factory, key: str, make):
    """make() once per test run, shared by every pytest-xdist worker: the first to ask computes it
    under a file lock and pickles it under the run's temporary base; the others (and later modules)
    wait for and load that file (a pickle round trip: the same arrays, bit for bit). For the
    expensive fixtures (FE results) that a worker-split module or several modules would otherwise
    compute again. Serial runs share it between modules the same way."""
    import fcntl
    import os
    import pickle
    base = tmp_path_factory.getbasetemp()
    root = base.parent if os.environ.get("PYTEST_XDIST_WORKER") else base     # the workers' common base
    path = root / f"computed-once-{key}.pkl"
    with open(root / f"computed-once-{key}.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        if path.exists():
            with open(path, "rb") as f:
                return pickle.load(f)
        value = make()
        tmp = path.with_suffix(f".{os.getpid()}.tmp")
        with open(tmp, "wb") as f:
            pickle.dump(value, f, protocol=pickle.HIGHEST_PROTOCOL)
        os.replace(tmp, path)
        return value
