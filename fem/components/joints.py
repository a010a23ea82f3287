"""Joints: the contact layers of the interfaces that the part models bond or hold rigid, from a
published contact-layer law for machined steel (fem.joints: delta = c p^0.5, Levina & Reshetov /
Rivin, c by the stated finish, k_t / k_n by Mindlin) and the bolt preloads (VDI 2230, fem.bolts).
In the crank support path, in series:
  carrier   the pillars' bolted, taper-pinned face on the end plate and the output flange's mounting
            face, each a thin layer in the carrier FE (fem.carrier, fem.joint_layers) under its bolts'
            preload pressure: this component carries C_car(with layers) - C_car(bonded), both on the
            same two meshes, Richardson-extrapolated (fem.components.carrier);
  seats     each support bearing's cup in its carrier bore and cone on its journal: the seat layers
            under the fit pressure (Lame, ISO 286 / ISO 492 mean interference) and the roller load
            zone, tangent at the rated-torque load (fem.joints.ring_seat_radial: the layer sees the
            roller distribution, the flexible-ring limit; fem.support_rings.ring_on_seat, the ring's
            bending on that layer, is its cross-check in `checks`, never added): a radial spring per
            bearing, T^T T c_seat.
Band: the law's constant c spans a range for a finish (fem.joints.FINISHES); the mid value is the
prediction, and `band_factors` are the compliance ratios c_end / c_mid of the ends (exact for a
layer at a fixed pressure, first order for the carrier's statically indeterminate frame): the
catalog test reports the rigidity at both ends (stiffened("joints", 1 / factor))."""
from __future__ import annotations

import dataclasses as dc
import math
import time
from dataclasses import dataclass

import numpy as np

from fem.components.base import Result

NAME = "joints"
COUPLING = "support"
COST = 40


@dataclass(frozen=True)
class Entry:
    carrier_delta_m_per_N: np.ndarray   # (4 nc, 4 nc) seat flexibility the carrier's joints add
    seat_compliance_m_per_N: float      # per support bearing, radial (cup + cone layers, ring bending)
    band_factors: tuple                 # (low, high) compliance over mid


def to_json(e: Entry) -> dict:
    return {"carrier_delta_m_per_N": np.asarray(e.carrier_delta_m_per_N).tolist(),
            "seat_compliance_m_per_N": float(e.seat_compliance_m_per_N), "band_factors": list(e.band_factors)}


def from_json(d: dict) -> Entry:
    return Entry(np.asarray(d["carrier_delta_m_per_N"], float), float(d["seat_compliance_m_per_N"]),
                 tuple(float(x) for x in d["band_factors"]))


def carrier_layers(case, band: str = "mid"):
    """fem.joint_layers.JointLayers of the case's carrier, per unit area, and what they came from."""
    from fem import bolts, joints
    from fem.joint_layers import JointLayers
    jt, cr, mat = case.joints, case.carrier, case.material
    E, nu = mat.youngs_modulus_GPa * 1e9, mat.poisson_ratio
    bolt = bolts.bolted_joint(jt.pillar_bolt_thread_mm, jt.pillar_bolt_property_class, jt.thread_friction,
                              jt.pillar_clamp_length_mm * 1e-3, 2 * cr.pillar_radius_mm * 1e-3, E)
    th = bolts.thread(jt.pillar_bolt_thread_mm)
    r = cr.pillar_radius_mm * 1e-3
    area = math.pi * (r * r - (th.hole_diameter_m / 2) ** 2 - (jt.taper_pin_diameter_mm * 1e-3 / 2) ** 2)
    if area <= 0.2 * math.pi * r * r:
        raise ValueError(f"[joints] pillar_bolt_thread_mm = {jt.pillar_bolt_thread_mm:g}, taper_pin_diameter_mm = "
                         f"{jt.taper_pin_diameter_mm:g}: their holes leave {area * 1e6:.1f} mm^2 of the pillar's "
                         f"{math.pi * r * r * 1e6:.1f} mm^2 face; allowed >= 20 %")
    d_pin = jt.taper_pin_diameter_mm * 1e-3
    k_pin = bolts.huth_shear_stiffness_N_per_m(d_pin, 2 * d_pin, jt.pillar_clamp_length_mm * 1e-3, E) if d_pin else 0.0
    preload = bolt.preload_N * jt.pillar_bolts_per_pillar
    pj = getattr(joints.pillar_joint_layer(preload, area, jt.face_roughness_Ra_um, E_Pa=E, nu=nu,
                                           pin_stiffness_N_per_m=k_pin), band)
    ri, ro = jt.output_face_inner_radius_mm * 1e-3, jt.output_face_outer_radius_mm * 1e-3
    out_bolt = bolts.assembly_preload_N(jt.output_bolt_thread_mm, jt.output_bolt_property_class, jt.thread_friction)
    p_face = jt.output_bolt_count * out_bolt / (math.pi * (ro * ro - ri * ri))
    kn_face = float(joints.contact_law(jt.face_roughness_Ra_um, band).normal_stiffness_N_per_m3(p_face))
    layers = JointLayers(pj.normal_stiffness_N_per_m / area, pj.tangential_stiffness_N_per_m / area,
                         kn_face, joints.tangential_ratio(nu) * kn_face)
    info = {"pillar_preload_N": preload, "pillar_face_area_m2": area, "pillar_pressure_Pa": pj.pressure_Pa,
            "taper_pin_shear_N_per_m": k_pin, "pillar_normal_N_per_m3": layers.pillar_normal_Pa_per_m,
            "pillar_tangential_N_per_m3": layers.pillar_tangential_Pa_per_m,
            "output_face_pressure_Pa": p_face, "output_face_normal_N_per_m3": kn_face}
    return layers, info


def seat_compliance_m_per_N(case, band: str = "mid") -> dict:
    """Per support bearing at the rated-torque load: the cup's and the cone's seat layers (module
    doc), and the ring-on-seat cross-check of the cup."""
    from fem import joints, support_rings, tapered_roller
    jt, mat = case.joints, case.material
    E = mat.youngs_modulus_GPa * 1e9
    b = tapered_roller.case_bearing(case)
    F = tapered_roller.operating_radial_load_N(case, case.rated_torque_Nm)
    law = joints.contact_law(jt.seat_roughness_Ra_um, band)
    R_cup, w_cup, t_cup = support_rings.cup_section_m(b)
    D, d = b.D_mm * 1e-3, b.d_mm * 1e-3
    p_cup = joints.fit_pressure_Pa(jt.support_cup_interference_um * 1e-6, D, D - 2 * t_cup,
                                   D + 2 * jt.support_seat_wall_mm * 1e-3, E, law)
    cone_outer = d + 2 * max(0.5 * (b.pitch_diameter_mm - b.roller_diameter_mm) * 1e-3 - d / 2, 0.1 * d)
    p_cone = joints.fit_pressure_Pa(jt.support_cone_interference_um * 1e-6, d, 0.0, cone_outer, E, law)
    cup = joints.ring_seat_radial(F, D, b.C_mm * 1e-3, p_cup, jt.seat_roughness_Ra_um)
    cone = joints.ring_seat_radial(F, d, b.B_mm * 1e-3, p_cone, jt.seat_roughness_Ra_um)
    tan = lambda s: s.compliance_m_per_N if band == "mid" else s.band_compliance_m_per_N[band == "high"]  # noqa: E731
    ring = support_rings.ring_on_seat(R_cup, w_cup, t_cup, E, float(law.normal_stiffness_N_per_m3(p_cup)) * w_cup)
    return {"cup_layer_m_per_N": tan(cup), "cone_layer_m_per_N": tan(cone),
            "cup_ring_on_seat_check_m_per_N": ring.compliance_m_per_N, "total_m_per_N": tan(cup) + tan(cone), "load_N": F,
            "cup_fit_pressure_Pa": p_cup, "cone_fit_pressure_Pa": p_cone, "source": cup.source + "; " + ring.source}


def parts(case, ctx) -> list:
    """(cost, part) of the FE stage's tasks: the jointed carrier's two levels (fem.components.carrier)."""
    from fem.components import carrier
    return carrier.parts(case, ctx)


def compute_part(case, ctx, part: int):
    """One level of the carrier with its joint layers (a task: pure, picklable)."""
    from fem.components import carrier
    return carrier.solve_level(case, ctx, part, joints=carrier_layers(case)[0])


def combine(case, ctx, done: list) -> Result:
    """The component's Result from its parts' outputs [(level, CarrierFE)], the seats' closed forms."""
    from fem import joints
    from fem.components import carrier
    t0 = time.perf_counter()
    _, info = carrier_layers(case)
    car = carrier.fe_entry(case, dict(done))
    seat = seat_compliance_m_per_N(case)
    law = joints.contact_law(case.joints.face_roughness_Ra_um)
    factors = tuple(joints.contact_law(case.joints.face_roughness_Ra_um, b).c_SI / law.c_SI for b in ("low", "high"))
    e = Entry(car["compliance_m_per_N"], seat["total_m_per_N"], factors)   # carrier_delta set in refine
    check = dict(info, carrier_with_joints_Nm_per_arcmin=car["check"]["torsional_stiffness_Nm_per_arcmin"],
                 seat={k: v for k, v in seat.items() if k != "source"}, band_factors=list(factors))
    return Result(NAME, {"parts.joints": e},
                  {NAME: f"{joints.LAW_SOURCE}; carrier: thin layers (fem.joint_layers) at the pillar joint and the "
                         f"mounting face under the VDI 2230 preloads; seats: {seat['source']}"},
                  {NAME: check}, seconds=time.perf_counter() - t0 + sum(fe.mesh_seconds + fe.solve_seconds
                                                                          for _, fe in done))


def compute(case, ctx) -> Result:
    """Every part in this process (fem.reduce runs the parts as tasks instead)."""
    return combine(case, ctx, [(p, compute_part(case, ctx, p)) for _, p in parts(case, ctx)])


def refine(case, results) -> Result:
    """The carrier's joints as the difference of the jointed and the bonded carrier (same meshes)."""
    e = results[NAME].fields["parts.joints"]
    bonded = results["carrier"].fields["carrier"].compliance_m_per_N
    delta = e.carrier_delta_m_per_N - bonded
    delta = 0.5 * (delta + delta.T)
    lo = float(np.linalg.eigvalsh(delta).min())
    e = dc.replace(e, carrier_delta_m_per_N=delta)
    r = results[NAME]
    check = dict(r.checks[NAME], carrier_delta_min_eigenvalue_over_max=lo / float(np.abs(delta).max()),
                 carrier_bonded_Nm_per_arcmin=results["carrier"].checks["carrier"]["torsional_stiffness_Nm_per_arcmin"])
    return dc.replace(r, fields={"parts.joints": e}, checks={NAME: check})


def stiffen(model, f: float):
    e = model.parts.get(NAME)
    if e is None:                       # a stiffness made without this component (in-memory tests)
        return model
    return dc.replace(model, parts=dict(model.parts, **{NAME: dc.replace(
        e, carrier_delta_m_per_N=e.carrier_delta_m_per_N / f, seat_compliance_m_per_N=e.seat_compliance_m_per_N / f)}))


def support_part(model, T: np.ndarray, n_crank: int) -> np.ndarray:
    """T^T (C_car,joints + c_seat I) T: the carrier's joint layers and each seat's radial spring."""
    if NAME not in model.parts:         # a stiffness made without this component: rigid
        return np.zeros((T.shape[1], T.shape[1]))
    e = model.parts[NAME]
    return T.T @ (e.carrier_delta_m_per_N + np.eye(T.shape[0]) * e.seat_compliance_m_per_N) @ T
