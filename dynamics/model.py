"""Lumped planar multibody model of an RV reducer, fed by the FE stiffness (stiffness.json).

Bodies and DOFs (16 for three cranks and two discs; layout in `dynamics.kernels`):
  input/sun       prescribed exactly (ideal servo): theta_in(t) of paper 001's ramp; the
                  input inertia therefore drops out, and the torque it must supply is an output.
  carrier/output  rotation; inertia = carrier (two steel flanges of the output-flange radius and
                  one disc width each, ASSUMED) + case.dynamics.load_inertia + cranks carried at
                  the crank radius.
  crankshafts     rotation (= angle of the disc-1 eccentric) and in-plane axis displacement
                  relative to the carrier seat (rigid shaft; planet gear on it).
  discs           two, 180 deg apart: centre x, y and rotation.
  pin housing     fixed; every pin a separate contact for every disc.
Couplings (every stiffness from `fem.stiffness.StiffnessModel`, none invented here):
  involute mesh   k_m(s) = k_mean (1 + var (h(s) - (eps - 1))), h the double-contact indicator
                  over one pitch (smoothed edges), contact ratio eps; in series with the crank
                  torsion k_t / rb2^2 along the line of action; no first-stage backlash (it is
                  divided by ~zp at the output). Energy form V = k(s) d^2 / 2, so the parametric
                  force d^2 k'(s) / 2 is kept and an undamped run conserves energy.
  crank support   shaft bending in series with the two support bearings in parallel:
                  1/k = 1/k_bend + 1/(2 k_bearing); radial clearance errors.support_clearance.
  turning arm     needle bearing law F = k delta^n (FE), radial clearance errors.turning_arm_clearance.
  pins            F = k(phase) approach^n (FE law by pin phase from the line of centres); the
                  normal gap is computed from the actual (modified, erroneous) profile: foot point
                  on the theoretical pin-centre curve by Newton (exact to ~1e-15 m, see
                  tests/test_dynamics_geometry.py at K1 = 0.95 and micron clearances), so
                  every error source acts through one contact mechanism.
Damping: stiffness-proportional on every coupling, c = beta k_t, beta = 2 zeta / omega_1 with
zeta = case.dynamics.damping_ratio (stated source: the case file) and omega_1 the lowest
eigenfrequency of the linearised model at rated torque, so the output torsional mode gets zeta
exactly and stiffer local modes more (contact damping grows with frequency). Contacts cannot
pull: damped contact forces are clipped at zero.
Error sources (case.errors; zero = ideal):
  crank_eccentricity_um    per crank: eccentric radius E + de_j (both eccentrics of the crank);
                           the two discs turn by equal and opposite amounts, the zp x line cancels
  eccentric_error_um       per crank: extra radius of the eccentric under disc 1 only (one journal
                           ground off size): disc 1 alone turns, a zp x line in the TE
  crank_hole_position_um   per crank: radial position of crank hole j on both discs
  output_bearing_hole_um   per crank: radial position of crank j's bearing seat in the carrier
  pin_radius_um, pin_circle_radius_um   all pins
  output_coaxiality_um, _phase_deg       a mounting offset e at the output flange radius r moves
                           the measured output angle by (e / r) sin(theta_out + phase): a
                           once-per-revolution encoder-side error added to the output angle the
                           results report (it carries no load, so it does not enter the dynamics)
  turning_arm_clearance_um, support_clearance_um   radial clearances of those bearings
Limits: planar (no disc tilt, no shaft bending shape beyond one lateral spring per crank,
no axial effects); frictionless contacts (no hysteresis beyond clearance); carrier translation
and pillar contacts not modelled; constant diagonal mass matrix (carrier speed <= 2 rad/s makes
the Coriolis/centripetal terms of the crank translation < 1e-3 of the contact forces).
Integrator: implicit HHT-alpha (alpha = 0.05) with a full Newton per step (numba kernel) at
dt = 1e-4 s by default: the contact modes reach ~10 kHz and an explicit scheme would need
dt < 1e-5 s; the time-step study is in tests/test_dynamics_verification.py. Only candidate pins
(gap < kernels.CANDIDATE_MARGIN_M at the last refresh, every CANDIDATE_REFRESH steps) enter the
Newton iterations; a skipped pin found closed raises DynamicsError (never silently wrong).
Statics: `solve_static` (robust strategy and the zero-load convention in its docstring).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from dynamics import kernels as kn
from dynamics.loads import LoadSpec, input_angle_deg, input_speed_deg_s, load_torque_Nm
from dynamics.results import ARCSEC_PER_DEG, StaticState, TEResult
from fem.stiffness import StiffnessModel
from geometry.artifacts import InputError
from geometry.params import ReducerCase

DEFAULT_SPEED_RPM = 1200.0   # DESIGN.md: paper 001's 7200 deg/s is the simulate default
DEFAULT_DT_S = 1e-4
DEFAULT_SAMPLE_DT_S = 5e-4
HHT_ALPHA = 0.05             # mild numerical dissipation of the unresolved contact modes
ROT_SCALE_M = 0.05           # lever arm that makes rotations comparable with translations [m]
STATIC_TOL_N = 1e-6          # static residual tolerance [N] (rotations: N m / ROT_SCALE_M)
NEWTON_TOL_M = 1e-11         # HHT Newton: largest correction of a step [m] (rotations times ROT_SCALE_M)


class DynamicsError(InputError):
    """A model that cannot be built or a solver that did not converge on the user's input."""


@dataclass(frozen=True)
class ReducerModel:
    case: ReducerCase
    stiffness: StiffnessModel
    geo: np.ndarray          # scalars, indices in dynamics.kernels (G_*)
    pins: np.ndarray         # (zp, 4) x [m], y [m], radius [m], angle [rad]
    cranks: np.ndarray       # (nc, 6) axis radius, axis angle, eccentricity, hole radius, mesh phase,
                             # extra eccentricity of disc 1 (columns kernels.C_*)
    law: np.ndarray          # (P, 3) pin phase [deg], k [N/m^n], n
    disc_rotation: np.ndarray  # (nd,) profile rotation in each disc's body frame [rad]
    mass: np.ndarray         # (n,) diagonal mass matrix [kg | kg m^2]
    scale: np.ndarray        # (n,) ROT_SCALE_M for rotations, 1 for translations
    ratio: float
    coaxiality_rad: float    # e / r of the output mounting offset
    coaxiality_phase_rad: float
    labels: tuple = field(default=())

    @property
    def n_dof(self) -> int:
        return len(self.mass)

    @property
    def n_disc(self) -> int:
        return int(self.geo[kn.G_ND])

    @property
    def n_crank(self) -> int:
        return int(self.geo[kn.G_NC])

    def disc_index(self, d: int) -> int:
        return 1 + 3 * self.n_crank + 3 * d

    def measured_output_rad(self, carrier_rad):
        """What an output encoder reads: carrier angle + coaxiality (e/r) sin(theta + phase)."""
        return carrier_rad + self.coaxiality_rad * np.sin(carrier_rad + self.coaxiality_phase_rad)


def _per_crank(values: tuple, n: int) -> np.ndarray:
    v = np.asarray(values, dtype=float) * 1e-6
    return np.full(n, v[0]) if len(v) == 1 else v


def build_model(case: ReducerCase, stiffness: StiffnessModel) -> ReducerModel:
    """Precompute the arrays of the lumped model (cheap: no solve)."""
    if stiffness.case_name != case.name:
        raise DynamicsError(f"stiffness for case {stiffness.case_name!r} given to case {case.name!r}: "
                            f"run `python -m pipeline fem --case` on this case")
    stiffness.check()
    cy, mod, s1, cr, dc, ks, mat, er = (case.cycloid, case.modification, case.stage1, case.carrier,
                                        case.disc, case.crankshaft, case.material, case.errors)
    mm = 1e-3
    nc, nd, zp = cr.crank_count, cy.disc_count, cy.zp
    rho = mat.density_kg_per_m3
    # pins, with pin errors applied to the actual pins
    th = 2 * np.pi * np.arange(zp) / zp
    Rp = cy.pin_circle_radius_mm * mm + er.pin_circle_radius_um * 1e-6
    rp = cy.pin_radius_mm * mm + er.pin_radius_um * 1e-6
    pins = np.column_stack([Rp * np.cos(th), Rp * np.sin(th), np.full(zp, rp), th])
    # cranks
    a = cr.crank_circle_radius_mm * mm
    beta = 2 * np.pi * np.arange(nc) / nc
    cranks = np.column_stack([
        a + _per_crank(er.output_bearing_hole_um, nc), beta,
        cy.eccentricity_mm * mm + _per_crank(er.crank_eccentricity_um, nc),
        a + _per_crank(er.crank_hole_position_um, nc),
        np.mod(s1.z1 * beta / (2 * np.pi), 1.0),
        _per_crank(er.eccentric_error_um, nc)])
    pc = stiffness.pin_contact
    law = np.column_stack([pc.position_deg, pc.law_k_N_per_m_pow, pc.law_n]).astype(float)
    drot = np.deg2rad(mod.rotation_deg) + np.pi * np.arange(nd)
    alpha = np.deg2rad(s1.pressure_angle_deg)
    geo = np.zeros(kn.N_GEO)
    geo[kn.G_R] = (cy.pin_circle_radius_mm + mod.offset_mm) * mm
    geo[kn.G_RR] = (cy.pin_radius_mm + mod.equidistant_mm) * mm
    geo[kn.G_E] = cy.eccentricity_mm * mm
    geo[kn.G_ZP], geo[kn.G_ND], geo[kn.G_NC] = zp, nd, nc
    ta = stiffness.turning_arm
    geo[kn.G_KTA], geo[kn.G_NTA] = ta.law_k_N_per_m_pow, ta.law_n
    geo[kn.G_CTA] = er.turning_arm_clearance_um * 1e-6
    geo[kn.G_KSUP] = 1.0 / (1.0 / stiffness.crankshaft_bending_stiffness_N_per_m
                            + 1.0 / (2.0 * stiffness.support_bearing_radial_stiffness_N_per_m))
    geo[kn.G_CSUP] = er.support_clearance_um * 1e-6
    geo[kn.G_KM] = stiffness.involute_mesh_mean_stiffness_N_per_m
    geo[kn.G_MVAR] = stiffness.involute_mesh_stiffness_variation
    geo[kn.G_MEPS] = stiffness.involute_mesh_contact_ratio
    geo[kn.G_RB1] = s1.module_mm * s1.z1 / 2 * mm * math.cos(alpha)
    geo[kn.G_RB2] = s1.module_mm * s1.z2 / 2 * mm * math.cos(alpha)
    geo[kn.G_Z1] = s1.z1
    geo[kn.G_KTOR] = stiffness.crankshaft_torsional_stiffness_Nm_per_rad
    # inertias from the case geometry (steel bodies; shapes stated in the module docstring)
    w = cy.width_mm * mm
    r_disc = (cy.pin_circle_radius_mm - cy.pin_radius_mm) * mm      # mean of root and tip radius
    holes = [(dc.centre_hole_radius_mm * mm, 0.0)] + [(dc.crank_hole_radius_mm * mm, a)] * nc \
        + [((cr.pillar_radius_mm + dc.pillar_hole_clearance_mm) * mm, cr.pillar_circle_radius_mm * mm)] \
        * cr.pillar_count
    m_disc = rho * w * math.pi * (r_disc ** 2 - sum(r ** 2 for r, _ in holes))
    j_disc = rho * w * math.pi * (r_disc ** 4 / 2 - sum(r ** 2 * (r ** 2 / 2 + c ** 2) for r, c in holes))
    r_e, r_j, r_pl = ks.eccentric_radius_mm * mm, ks.journal_radius_mm * mm, s1.module_mm * s1.z2 / 2 * mm
    parts = [(rho * math.pi * r_e ** 2 * w, r_e)] * nd + [(rho * math.pi * r_j ** 2 * ks.journal_length_mm * mm,
                                                          r_j)] * 2 \
        + [(rho * math.pi * r_pl ** 2 * s1.face_width_mm * mm, r_pl)]
    m_crank = sum(m for m, _ in parts)
    j_crank = sum(m * r ** 2 / 2 for m, r in parts) + nd * parts[0][0] * (cy.eccentricity_mm * mm) ** 2
    r_f = cr.output_flange_radius_mm * mm
    m_carrier = rho * math.pi * r_f ** 2 * 2 * w
    j_out = m_carrier * r_f ** 2 / 2 + case.dynamics.load_inertia_kg_m2 + nc * m_crank * a ** 2
    mass = np.concatenate([[j_out], np.full(nc, j_crank), np.full(2 * nc, m_crank),
                           np.tile([m_disc, m_disc, j_disc], nd)])
    scale = np.concatenate([[ROT_SCALE_M], np.full(nc, ROT_SCALE_M), np.ones(2 * nc),
                            np.tile([1.0, 1.0, ROT_SCALE_M], nd)])
    labels = (("carrier",) + tuple(f"crank{j + 1}_rot" for j in range(nc))
              + tuple(f"crank{j + 1}_{x}" for j in range(nc) for x in "xy")
              + tuple(f"disc{d + 1}_{x}" for d in range(nd) for x in ("x", "y", "rot")))
    return ReducerModel(case=case, stiffness=stiffness, geo=geo, pins=pins, cranks=cranks, law=law,
                        disc_rotation=drot, mass=mass, scale=scale, ratio=case.ratio,
                        coaxiality_rad=er.output_coaxiality_um * 1e-6 / r_f,
                        coaxiality_phase_rad=np.deg2rad(er.output_coaxiality_phase_deg), labels=labels)


def nominal_q(model: ReducerModel, input_rad: float, lag_rad: float = 0.0) -> np.ndarray:
    """Rigid-body kinematics (ideal geometry): carrier = input / i - lag, eccentric = -zc carrier."""
    s1 = model.case.stage1
    nc, nd = model.n_crank, model.n_disc
    q = np.zeros(model.n_dof)
    q[0] = input_rad / model.ratio - lag_rad
    phi = q[0] - s1.z1 / s1.z2 * (input_rad - q[0])
    q[1:1 + nc] = phi
    E = model.geo[kn.G_E]
    for d in range(nd):
        i = model.disc_index(d)
        q[i:i + 3] = E * math.cos(phi + math.pi * d), E * math.sin(phi + math.pi * d), q[0]
    return q


def _workspace(model: ReducerModel):
    nd, nc, zp, n = model.n_disc, model.n_crank, len(model.pins), model.n_dof
    return dict(f=np.zeros(n), K=np.zeros((n, n)), C=np.zeros((n, n)), pf=np.zeros((nd, zp)),
                pg=np.zeros((nd, zp)), br=np.zeros((nd, nc, 2)), mf=np.zeros(nc))


def _fresh_tws(model: ReducerModel) -> np.ndarray:
    return np.full((model.n_disc, len(model.pins)), np.nan)


ZERO_LOAD_FRACTION = 1e-5   # |T| below this share of rated torque is solved as this preload
FLANK_SEARCH_RAD = 2e-3     # output rotation searched for the loaded flank (7 arcmin >> any backlash)
CONTINUATION_MAX_SOLVES = 40


def _turn_shift(model: ReducerModel) -> np.ndarray:
    """Exact change of q when the input turns one period 2 pi i (the carrier one revolution):
    carrier and discs +2 pi, eccentrics 2 pi (1 - zp), mesh deflection and translations unchanged.
    The whole mechanism (pins, mesh phase z1 (th - q0) / 2 pi, cranks) repeats after it."""
    zp, nc = len(model.pins), model.n_crank
    shift = np.zeros(model.n_dof)
    shift[0] = 2 * np.pi
    shift[1:1 + nc] = 2 * np.pi * (1 - zp)
    for d in range(model.n_disc):
        shift[model.disc_index(d) + 2] = 2 * np.pi
    return shift


def _reduce(model: ReducerModel, input_rad: float) -> tuple[float, int]:
    """(input angle within one period 2 pi i of 0, whole periods removed): keeps the kernels'
    trigonometry and the mesh deflection rb1 (th - q0) + rb2 (phi - q0) free of cancellation."""
    turns = int(np.round(input_rad / (2 * np.pi * model.ratio)))
    return input_rad - turns * 2 * np.pi * model.ratio, turns


def _min_gap_m(model: ReducerModel, q: np.ndarray, input_rad: float) -> float:
    w = _workspace(model)
    geo = model.geo.copy()
    geo[kn.G_BETA] = 0.0
    kn.assemble(q, np.zeros_like(q), input_rad, 0.0, geo, model.pins, model.cranks, model.law,
                model.disc_rotation, _fresh_tws(model), False, w["f"], w["K"], w["C"], w["pf"], w["pg"],
                w["br"], w["mf"])
    return float(w["pg"].min())


def _rigid_pose(model: ReducerModel, input_rad: float, carrier_rad: float) -> np.ndarray:
    """Rigid-body pose (input held, mesh rigid, crank axes on their seats) at a given carrier
    angle, with each disc placed by the least-squares (2D Kabsch) fit of its crank holes onto the
    actual eccentric centres: exact for ideal geometry, first order with crank errors."""
    s1 = model.case.stage1
    nc = model.n_crank
    q = np.zeros(model.n_dof)
    q[0] = carrier_rad
    phi = carrier_rad - s1.z1 / s1.z2 * (input_rad - carrier_rad)
    q[1:1 + nc] = phi
    a, b, ecc0, hr = (model.cranks[:, c] for c in (kn.C_A, kn.C_B, kn.C_ECC, kn.C_H))
    seat = a[:, None] * np.column_stack([np.cos(carrier_rad + b), np.sin(carrier_rad + b)])
    hole = hr[:, None] * np.column_stack([np.cos(b), np.sin(b)])       # disc frame, at rotation 0
    hc = hole.mean(axis=0)
    for d in range(model.n_disc):
        ecc = ecc0 + (model.cranks[:, kn.C_DE1] if d == 0 else 0.0)
        X = seat + ecc[:, None] * np.array([math.cos(phi + math.pi * d), math.sin(phi + math.pi * d)])
        Xc = X.mean(axis=0)
        u, x = hole - hc, X - Xc
        # rotation minimising sum |x - Rot(g) u|^2, near the carrier angle (holes may be symmetric)
        g = math.atan2(np.sum(u[:, 0] * x[:, 1] - u[:, 1] * x[:, 0]), np.sum(u[:, 0] * x[:, 0] + u[:, 1] * x[:, 1]))
        g = carrier_rad + math.remainder(g - carrier_rad, 2 * np.pi) if nc > 1 else carrier_rad
        cg, sg = math.cos(g), math.sin(g)
        i = model.disc_index(d)
        q[i:i + 2] = Xc - np.array([cg * hc[0] - sg * hc[1], sg * hc[0] + cg * hc[1]])
        q[i + 2] = g
    return q


def kinematic_q(model: ReducerModel, input_rad: float, flank: int = +1) -> np.ndarray:
    """Zero-load pose: the rigid-body pose of `_rigid_pose` with the output turned (input held)
    until the first pin of the loaded flank just touches (smallest gap = 0 to 1e-12 m).
    flank +1 is the flank a positive record torque loads (output lagging forward motion), -1
    the other. With an interference (negative gap) in the centred pose the output is turned the
    other way until it opens; with interference on both flanks (no backlash) the centred pose is kept."""
    _check_direction(flank)
    centre = input_rad / model.ratio

    def gap(lag):
        return _min_gap_m(model, _rigid_pose(model, input_rad, centre - flank * lag), input_rad)

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


def _newton(model, input_rad, T, q0, tws, max_iter=100):
    tol = STATIC_TOL_N * max(1.0, abs(T) / 100)
    tw = tws.copy()
    q, it, status = kn.static_solve(q0.copy(), float(input_rad), float(T), model.geo, model.pins, model.cranks,
                                    model.law, model.disc_rotation, tw, model.scale, max_iter, tol)
    if status == 0:
        tws[:, :] = tw
    return q, it, status


def _on_branch(model: ReducerModel, th: float, q: np.ndarray) -> bool:
    """Newton can land on the next tooth (the profile is periodic: the disc one pin pitch on is also
    an equilibrium). Windup plus backlash stay far below a quarter pin pitch of output rotation."""
    return abs(q[0] - th / model.ratio) < 0.25 * 2 * np.pi / model.case.cycloid.zp


def _static(model: ReducerModel, input_rad: float, record_torque_Nm: float, q0: np.ndarray | None,
            tws: np.ndarray, flank: int = +1) -> tuple[np.ndarray, int]:
    """Static equilibrium, robust by construction (see `solve_static`): returns (q, iterations)."""
    th, turns = _reduce(model, input_rad)
    shift = turns * _turn_shift(model)
    T = float(record_torque_Nm)
    floor = ZERO_LOAD_FRACTION * model.case.rated_torque_Nm
    if abs(T) < floor:                   # zero load: vanishing preload on the given flank
        T = flank * floor
    flank = 1 if T > 0 else -1
    total = 0
    if q0 is not None:                   # warm start (the caller's guess, e.g. the last solution)
        q, it, status = _newton(model, th, T, np.asarray(q0, float) - shift, tws)
        total += it
        if status == 0 and _on_branch(model, th, q):
            return q + shift, total
    qk = kinematic_q(model, th, flank)
    q, it, status = _newton(model, th, T, qk, tws)
    total += it
    if status == 0 and not _on_branch(model, th, q):
        status = 3                       # a neighbouring tooth's equilibrium: approach it gradually
    if status != 0:                      # torque continuation from the touching pose, adaptive
        q, frac, dfrac = qk, 0.0, 1.0 / 16
        for _ in range(CONTINUATION_MAX_SOLVES):
            nxt = min(1.0, frac + dfrac)
            qn, it, status = _newton(model, th, nxt * T if nxt < 1 else T, q, tws)
            total += it
            if status == 0 and _on_branch(model, th, qn):
                q, frac, dfrac = qn, nxt, 2 * dfrac
                if frac >= 1.0:
                    break
            else:
                dfrac /= 4
                if dfrac < 1e-6:
                    break
        status = 0 if frac >= 1.0 else max(status, 1)
    if status != 0:
        raise DynamicsError(f"static equilibrium not found at input {np.rad2deg(input_rad):.6g} deg, "
                            f"torque {record_torque_Nm:.4g} N m (status {status} after {total} iterations, "
                            f"torque continuation included); check the case's clearances and errors "
                            f"(an interference larger than the stiffness laws' range?)")
    return q + shift, total


def _state(model: ReducerModel, q: np.ndarray, input_rad: float, torque: float, it: int) -> StaticState:
    w = _workspace(model)
    geo = model.geo.copy()
    geo[kn.G_BETA] = 0.0
    _, tau, _ = kn.assemble(q, np.zeros_like(q), input_rad, 0.0, geo, model.pins, model.cranks,
                            model.law, model.disc_rotation, _fresh_tws(model), False, w["f"], w["K"],
                            w["C"], w["pf"], w["pg"], w["br"], w["mf"])
    poses = np.array([q[model.disc_index(d):model.disc_index(d) + 3] for d in range(model.n_disc)])
    return StaticState(input_angle_deg=float(np.rad2deg(input_rad)), torque_Nm=float(torque),
                       output_angle_deg=float(np.rad2deg(q[0])),
                       te_arcsec=float(np.rad2deg(q[0] - input_rad / model.ratio) * ARCSEC_PER_DEG),
                       pin_force_N=w["pf"].copy(), pin_gap_m=w["pg"].copy(), bearing_force_N=w["br"].copy(),
                       mesh_force_N=w["mf"].copy(), disc_pose=poses,
                       crank_angle_rad=q[1:1 + model.n_crank].copy(), input_torque_Nm=float(tau),
                       q=q.copy(), iterations=it)


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
    Zero load: the output floats in the backlash, so |T| < ZERO_LOAD_FRACTION x rated is solved
    at that vanishing preload (4 mN m on the RV-40E: TE change < 0.01 arcsec) on the flank of
    `direction` (the flank of the direction of motion that a running reducer's drag closes);
    the state reports the torque asked for. Raises DynamicsError when no equilibrium is found."""
    _check_direction(direction)
    th = math.radians(float(input_angle_deg))
    if not math.isfinite(th) or not math.isfinite(torque_Nm):
        raise DynamicsError(f"solve_static: input angle {input_angle_deg!r} deg and torque "
                            f"{torque_Nm!r} N m must be finite")
    q, it = _static(model, th, torque_Nm, q_guess, _fresh_tws(model), direction)
    return _state(model, q, th, torque_Nm, it)


def quasi_static(model: ReducerModel, input_angle_deg, torque_Nm, direction: int = +1,
                 t_s=None) -> TEResult:
    """A sequence of static equilibria (no inertia) along the input angles, warm-started.
    The applied output torque is direction * torque_Nm (record convention), as in `simulate`.
    t_s defaults to the time at the case's input speed (for records and spectra)."""
    _check_direction(direction)
    th = np.deg2rad(np.atleast_1d(np.asarray(input_angle_deg, dtype=float)))
    T = direction * np.broadcast_to(np.asarray(torque_Nm, dtype=float), th.shape).astype(float)
    if not (np.all(np.isfinite(th)) and np.all(np.isfinite(T))):
        raise DynamicsError("quasi_static: input angles and torques must be finite")
    n = len(th)
    carrier = np.empty(n)
    teeth = np.empty((n, model.n_disc), int)
    pf = np.empty((n, model.n_disc, len(model.pins)))
    tws = _fresh_tws(model)
    w = _workspace(model)
    geo = model.geo.copy()
    geo[kn.G_BETA] = 0.0
    q = None
    for i in range(n):
        # warm start: rigid-body advance of the last solution (the solver falls back to the
        # touching kinematic pose and torque continuation when the step is too large for it)
        guess = None if q is None else q + nominal_q(model, th[i]) - nominal_q(model, th[i - 1])
        q, _ = _static(model, th[i], T[i], guess, tws, direction)
        kn.assemble(q, np.zeros_like(q), th[i], 0.0, geo, model.pins, model.cranks, model.law,
                    model.disc_rotation, tws, False, w["f"], w["K"], w["C"], w["pf"], w["pg"], w["br"], w["mf"])
        carrier[i] = q[0]
        pf[i] = w["pf"]
        teeth[i] = (w["pf"] > 0).sum(axis=1)
    if t_s is None:
        speed = 6.0 * model.case.operation.input_speed_rpm
        t_s = np.concatenate([[0.0], np.cumsum(np.abs(np.diff(np.rad2deg(th)))) / speed])
    return _result(model, np.asarray(t_s, float), th, carrier, T, teeth, pf,
                   {"solver": "quasi_static", "direction": direction})


def _result(model, t, th_in, carrier, T, teeth, pf, meta) -> TEResult:
    out = model.measured_output_rad(carrier)
    te = np.rad2deg(out - th_in / model.ratio) * ARCSEC_PER_DEG
    return TEResult(t_s=t, input_angle_deg=np.rad2deg(th_in), output_angle_deg=np.rad2deg(out),
                    output_torque_Nm=T, te_arcsec=te, teeth_in_contact=teeth, pin_force_N=pf,
                    ratio=model.ratio, meta={"case": model.case.name, **meta})


def _check_direction(direction):
    if direction not in (1, -1):
        raise DynamicsError(f"direction = {direction!r}: allowed +1 (forward) or -1 (backward)")


def linearise(model: ReducerModel, state: StaticState) -> tuple[np.ndarray, np.ndarray]:
    """(K, M) of the model linearised about a static state (input held)."""
    w = _workspace(model)
    geo = model.geo.copy()
    geo[kn.G_BETA] = 0.0
    th = math.radians(state.input_angle_deg)
    kn.assemble(state.q, np.zeros_like(state.q), th, 0.0, geo, model.pins, model.cranks, model.law,
                model.disc_rotation, _fresh_tws(model), True, w["f"], w["K"], w["C"], w["pf"], w["pg"],
                w["br"], w["mf"])
    K = 0.5 * (w["K"] + w["K"].T)
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
    """Stiffness-proportional damping coefficient beta = 2 zeta / omega_1 (see module docstring)."""
    zeta = model.case.dynamics.damping_ratio
    if zeta == 0:
        return 0.0
    f = eigenfrequencies_Hz(model)
    f1 = f[f > 1e-3][0]
    return 2.0 * zeta / (2 * np.pi * f1)


def simulate(model: ReducerModel, load: LoadSpec, *, duration_s: float = 7.0,
             input_speed_rpm: float | None = None, direction: int = +1, dt_s: float | None = None,
             sample_dt_s: float | None = None, ramp: bool = True, store_pin_forces: bool = True,
             hht_alpha: float = HHT_ALPHA, damping_beta_s_: float | None = None,
             return_energy: bool = False) -> TEResult:
    """Time integration of paper 001's run: input speed ramp (STEP over 1 s), load form `load`.
    Starts at rest in static equilibrium under the load's initial torque. input_speed_rpm
    defaults to DESIGN.md's 1200 rpm; direction -1 runs backward (record torque negative).
    Energy bookkeeping (kinetic, potential, input work, load work) lands in meta when asked."""
    _check_direction(direction)
    speed = DEFAULT_SPEED_RPM if input_speed_rpm is None else float(input_speed_rpm)
    dt = DEFAULT_DT_S if dt_s is None else float(dt_s)
    sdt = DEFAULT_SAMPLE_DT_S if sample_dt_s is None else float(sample_dt_s)
    for name, val, lo in (("duration_s", duration_s, 0.0), ("dt_s", dt, 0.0), ("sample_dt_s", sdt, 0.0),
                          ("input_speed_rpm", speed, -1.0)):
        if not (math.isfinite(val) and val > lo):
            raise DynamicsError(f"simulate: {name} = {val!r} must be finite and > {lo:g}")
    if dt > 1e-3:
        raise DynamicsError(f"simulate: dt_s = {dt:g} s is too coarse for the contact dynamics; allowed <= 1e-3 s")
    stride = max(1, int(round(sdt / dt)))
    nsteps = int(math.ceil(duration_s / (dt * stride))) * stride
    t = np.arange(nsteps + 1) * dt
    th = direction * np.deg2rad(input_angle_deg(t, speed, ramp))
    w = direction * np.deg2rad(input_speed_deg_s(t, speed, ramp))
    T = direction * np.asarray(load_torque_Nm(load, t), dtype=float)
    geo = model.geo.copy()
    geo[kn.G_BETA] = damping_beta_s(model) if damping_beta_s_ is None else damping_beta_s_
    tws = _fresh_tws(model)
    q, _ = _static(model, th[0], T[0], None, tws, direction)
    ns = nsteps // stride + 1
    zp = len(model.pins)
    out_q0, out_tau = np.zeros(ns), np.zeros(ns)
    out_teeth = np.zeros((ns, model.n_disc), np.int64)
    out_pf = np.zeros((ns if store_pin_forces else 1, model.n_disc, zp))
    out_e = np.zeros((ns, 4))
    done, iters, status, missed = kn.integrate(q, np.zeros_like(q), model.mass, th, w, T, dt, stride, hht_alpha,
                                       geo, model.pins, model.cranks, model.law, model.disc_rotation, tws,
                                       model.scale, 40, NEWTON_TOL_M, out_q0, out_teeth, out_pf, out_tau, out_e,
                                       store_pin_forces, np.zeros((3, model.n_dof)))
    if status != 0:
        why = {1: "Newton did not converge", 3: "contact geometry lost (foot point)"}.get(status, "failed")
        raise DynamicsError(f"simulate diverged at t = {done * dt:.5g} s ({why}) for load {load}, "
                            f"dt = {dt:g} s: reduce --dt or check the stiffness laws")
    if missed:
        raise DynamicsError(f"simulate: {missed} pin contacts closed while skipped as open (candidate "
                            f"margin {kn.CANDIDATE_MARGIN_M * 1e6:g} um too small for load {load}); "
                            f"reduce --dt")
    idx = np.arange(ns) * stride
    meta = {"load": str(load), "dt_s": dt, "sample_dt_s": dt * stride, "newton_per_step": iters / max(nsteps, 1),
            "missed_contacts": int(missed),
            "input_speed_rpm": speed, "direction": direction, "solver": f"HHT-alpha {hht_alpha}",
            "damping_beta_s": float(geo[kn.G_BETA]), "input_torque_Nm": out_tau}
    if return_energy:
        meta["energy_J"] = out_e
    return _result(model, t[idx], th[idx], out_q0, T[idx], out_teeth,
                   out_pf if store_pin_forces else None, meta)
