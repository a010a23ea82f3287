"""Compliance budget: each coupling's and each physical component's share of the output torsional
compliance at a load.

At a static equilibrium q* (input locked, output torque T) the tangent stiffness is the sum of the
couplings' tangents, K = sum_i K_i (`dynamics.couplings`: every force comes from one coupling).
A torque increment dT at the output gives dq = K^-1 e_out dT and the output rotation
dtheta = e_out . dq, so the complementary work splits exactly over the couplings:
    dT dtheta = dq^T K dq = sum_i dq^T K_i dq,     share_i = dq^T K_i dq / dq^T K dq,
the shares sum to 1 by construction (no "stiffen one part 1000x" differences, which do not add
up for a nonlinear, statically indeterminate path).

By component (fem.stiffness.COMPONENTS): a coupling lumps physical parts in series, which carry
the same force increment dF, so its energy splits over them as dF^T C_part dF, i.e. in proportion
of their tangent compliances at the operating state:
the components of each coupling are fem.components.in_coupling(name):
  mesh     per crank, the mesh components' line compliances (involute_mesh 1/k_m(s), crank_torsion
           rb2^2/k_t) at the crank's mesh phase;
  support  dF = K_t du on the crank-axis DOFs (K_t the coupling's tangent there), part energies
           dF^T C_part dF with C_part = fem.stiffness.support_compliance_parts (one matrix per
           support component); a clearance's dead band only changes K_t;
  pin      per contact, its energy dq^T K_c dq split over the pin components by
           fem.stiffness.pin_series_tangents at that contact's force (tooth-pair law at its phase);
  others   a coupling that is one component (needle: needle_bearings) takes all its energy.
Each coupling's split is normalised, so the component shares also sum to 1 exactly.
"""
from __future__ import annotations

import math

import numpy as np

from dynamics import couplings
from dynamics.couplings import mesh as mesh_coupling
from dynamics.reducer import ReducerModel, build_model
from dynamics.statics import solve_static
from fem.stiffness import COMPONENTS, in_coupling, pin_series_tangents, support_compliance_parts


def coupling_tangents(model: ReducerModel, q: np.ndarray, input_rad: float) -> dict[str, np.ndarray]:
    """Tangent stiffness -df/dq of each registered coupling alone at state q."""
    return {mod.NAME: _assemble_alone(model, mod.NAME, q, input_rad).K.copy() for mod in couplings.REGISTRY}


def _assemble_alone(model: ReducerModel, name: str, q, input_rad: float, active=None):
    """Work of the coupling `name` alone at rest at q; `active` masks the candidate contacts."""
    w = model.work()
    if active is not None:
        w.active[:] = active
    couplings.assemble(np.asarray(q, float), np.zeros(model.n_dof), float(input_rad), 0.0, 0.0, True,
                       model.arrays, w, couplings.index_of(name))
    return w


def energy_shares(Ks: dict[str, np.ndarray], dq: np.ndarray) -> dict[str, float]:
    """share_i = dq^T K_i dq / dq^T (sum K) dq (the tangent complementary energy of each part)."""
    e = {k: float(dq @ Ki @ dq) for k, Ki in Ks.items()}
    total = sum(e.values())
    return {k: v / total for k, v in e.items()}


def normalised(weights: dict[str, float]) -> dict[str, float]:
    """Fractions summing to 1 (all zero when nothing carries energy)."""
    s = float(sum(weights.values()))
    return {k: (float(v) / s if s > 0 else 0.0) for k, v in weights.items()}


# ----------------------------------------------------------------------------- series splits
# Each split returns the coupling's tangent energy dq^T K_i dq spread over its series parts
# (component -> energy); compliance_budget normalises it to the coupling's share.

def mesh_split(model: ReducerModel, q: np.ndarray, input_rad: float, dq: np.ndarray) -> dict[str, float]:
    """Per crank j: energy (g_j . dq)^2 / sum_c c_c (g the line-of-action gradient, input locked),
    split in the series ratio of the mesh components' line compliances at the crank's mesh phase
    (fem.components, COUPLING "mesh": involute_mesh 1/k_m(s), crank_torsion rb2^2/k_t)."""
    p = couplings.params_of(model.arrays, "mesh")
    rb1, rb2, eps = p.rb_sun_m, p.rb_planet_m, p.contact_ratio
    comps = in_coupling("mesh")
    w = dict.fromkeys((c.NAME for c in comps), 0.0)
    for j in range(p.dof.shape[0]):
        i0, ij = p.dof[j]
        s = p.z_sun * (input_rad - q[i0]) / (2 * math.pi) + p.phase[j]
        h, _ = mesh_coupling._double_contact(s, eps)
        c = {comp.NAME: comp.line_compliance_m_per_N(p, h) for comp in comps}
        total = sum(c.values())
        energy = (rb2 * dq[ij] - (rb1 + rb2) * dq[i0]) ** 2 / total
        for k, v in c.items():
            w[k] += energy * v / total
    return w


def support_split(K_t: np.ndarray, du: np.ndarray, parts: dict[str, np.ndarray]) -> dict[str, float]:
    """dF = K_t du through the parts in series (one force, added compliances): part energies
    dF^T C_part dF (their sum is du^T K_t du when K_t = (sum C_part)^-1)."""
    dF = K_t @ du
    return {k: max(float(dF @ C @ dF), 0.0) for k, C in parts.items()}


def _support_split(model: ReducerModel, q, input_rad, dq, K_support) -> dict[str, float]:
    idx = np.asarray(couplings.params_of(model.arrays, "support").dof).reshape(-1)  # crank, plane, x/y
    parts = support_compliance_parts(model.stiffness, model.n_crank)
    return support_split(K_support[np.ix_(idx, idx)], dq[idx], parts)


def pin_phase_deg(model: ReducerModel, q: np.ndarray) -> np.ndarray:
    """(nd, zp) phase of each pin from its disc's line of centres, folded into [0, 180] deg
    (as dynamics.couplings.pin does)."""
    disc, zp = model.layout["disc"], model.case.cycloid.zp
    psi = np.arctan2(q[disc.indices("y")], q[disc.indices("x")])
    ph = np.rad2deg(2 * np.pi * np.arange(zp)[None, :] / zp - psi[:, None])
    return np.abs(ph - 360.0 * np.floor((ph + 180.0) / 360.0))


def pin_split(model: ReducerModel, q, input_rad, dq, K_pin=None) -> dict[str, float]:
    """Per loaded contact c: its energy dq^T K_c dq (the pin kernel with only c active), split by
    the series tangent compliances at its force, the tooth pair on the FE law at its phase."""
    off, _ = model.slots.contact_sets["pin"]
    force = model.contacts(_assemble_alone(model, "pin", q, input_rad).force).reshape(-1)
    pc = model.stiffness.pin_contact
    pos = np.clip(pin_phase_deg(model, q).reshape(-1), pc.position_deg[0], pc.position_deg[-1])
    k, n = np.interp(pos, pc.position_deg, pc.law_k_N_per_m_pow), np.interp(pos, pc.position_deg, pc.law_n)
    w = dict.fromkeys((c.NAME for c in in_coupling("pin")), 0.0)
    for c in np.flatnonzero(force > 0):
        active = np.zeros(model.slots.n_contacts, np.bool_)
        active[off + c] = True
        energy = float(dq @ _assemble_alone(model, "pin", q, input_rad, active).K @ dq)
        frac = normalised({kk: float(v[0]) for kk, v in
                           pin_series_tangents(model.stiffness, force[c:c + 1], k[c], n[c]).items()})
        for kk in w:
            w[kk] += energy * frac[kk]
    return w


def whole(name: str):
    """A coupling that is one component (needle, housing): all its energy is that component's."""
    comps = in_coupling(name)
    if len(comps) != 1:
        raise KeyError(f"coupling {name!r} carries components {[c.NAME for c in comps]}: it needs a split in SPLITS")
    return lambda m, q, th, dq, K: {comps[0].NAME: float(dq @ K @ dq)}


SPLITS = {  # coupling -> f(model, q, input_rad, dq, K_coupling) -> {component: energy}; others: whole()
    "mesh": lambda m, q, th, dq, K: mesh_split(m, q, th, dq),
    "support": _support_split,
    "pin": pin_split,
}


def split_for(name: str):
    """The split of coupling `name` (SPLITS, or the whole coupling for a one-component coupling)."""
    return SPLITS.get(name) or whole(name)


def tangent_state(model: ReducerModel, torque_Nm: float, input_angle_deg: float = 0.0):
    """(q*, input angle [rad], coupling tangents, dq per unit output torque) at a static equilibrium."""
    th = float(np.deg2rad(input_angle_deg))
    q = solve_static(model, input_angle_deg, torque_Nm).q
    Ks = coupling_tangents(model, q, th)
    e = np.zeros(model.n_dof)
    e[model.i_out] = 1.0
    return q, th, Ks, np.linalg.solve(sum(Ks.values()), e)


def compliance_budget(model: ReducerModel, torque_Nm: float | None = None,
                      input_angle_deg: float = 0.0) -> dict:
    """Shares of the output torsional compliance at `torque_Nm` (default rated): by component
    (`compliance_budget`, fem.stiffness.COMPONENTS order) and by coupling (`by_coupling`)."""
    T = model.case.rated_torque_Nm if torque_Nm is None else float(torque_Nm)
    q, th, Ks, dq = tangent_state(model, T, input_angle_deg)
    by_coupling = energy_shares(Ks, dq)
    parts = dict.fromkeys(COMPONENTS, 0.0)
    for name, share in by_coupling.items():
        split = split_for(name)
        for comp, frac in normalised(split(model, q, th, dq, Ks[name])).items():
            parts[comp] += share * frac
    return {"torque_Nm": T, "input_angle_deg": float(input_angle_deg),
            "tangent_rigidity_Nm_per_arcmin": float(np.deg2rad(1 / 60) / dq[model.i_out]),
            "compliance_budget": parts, "by_coupling": by_coupling}


def against_reference(rigidity_Nm_per_arcmin: float, reference_Nm_per_arcmin: float, shares: dict) -> dict:
    """The prediction beside a reference rigidity (catalog or bench), and what it would take to meet
    it: the factor on ONE component's compliance that alone closes the gap, to first order
    (its compliance c_i = s_i C grows by C (K / K_ref - 1), so f_i = 1 + (K / K_ref - 1) / s_i). A
    report of where the model could be wrong, not a correction: nothing here feeds the model."""
    K, Kr = float(rigidity_Nm_per_arcmin), float(reference_Nm_per_arcmin)
    if not Kr > 0:
        return {}
    gap = K / Kr - 1.0
    need = {name: (1.0 + gap / s if s > 1e-9 else None) for name, s in
            sorted(shares.items(), key=lambda kv: -kv[1])}
    return {"reference_Nm_per_arcmin": Kr, "predicted_over_reference": K / Kr,
            "compliance_factor_to_meet_reference": {k: v for k, v in need.items()
                                                    if v is None or v > 0},
            "note": "factor on one component's compliance that alone brings the rigidity to the "
                    "reference (first order in the shares at rated torque); components that cannot "
                    "do it alone (factor <= 0 or share ~ 0) are omitted or null"}


def rigidity_band(model: ReducerModel, rigidity) -> dict:
    """The catalog rigidity at the ends of each banded component's published constants (a component
    whose entry carries `band_factors`: its compliance x factor at the low and high end, e.g. the
    contact-layer law's c range of fem.components.joints). rigidity: ReducerModel -> N m/arcmin (the
    catalog test). Returns {component: {"factors": [lo, hi], "rigidity_Nm_per_arcmin": [at lo, at hi]}}."""
    out = {}
    for name, entry in model.stiffness.parts.items():
        factors = getattr(entry, "band_factors", None)
        if not factors:
            continue
        rig = [float(rigidity(build_model(model.case, model.stiffness.stiffened(name, 1.0 / f)))) for f in factors]
        out[name] = {"factors": [float(f) for f in factors], "rigidity_Nm_per_arcmin": rig}
    return out
