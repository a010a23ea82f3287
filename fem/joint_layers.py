"""Joints that a one-body FE bonds, as thin layers: the layer material that carries a contact
layer's normal and tangential compliance (per unit area, from a contact-layer law: fem.joints) in
series with the slab's own steel. Used by the carrier FE (fem.carrier) for the bolted pillar joint
and the output flange's mounting face."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fem import elastic


@dataclass(frozen=True)
class JointLayers:
    """Contact-layer stiffness per unit area [Pa/m] (normal, tangential; fem.joints) of the carrier's
    two joints that the one-body FE bonds: the pillars' bolted, taper-pinned face on the end plate
    (the pillars are one piece with the output flange, the end plate is bolted on: the RV's two-part
    carrier) and the output flange's mounting face on the load (the clamp). None: bonded."""
    pillar_normal_Pa_per_m: float | None = None
    pillar_tangential_Pa_per_m: float | None = None
    face_normal_Pa_per_m: float | None = None
    face_tangential_Pa_per_m: float | None = None


def layer_material(h_m, E_Pa: float, nu: float, k_n: float, k_t: float):
    """(E, nu, dG) of a slab of thickness h that carries its own steel AND a joint's compliance in
    series (a thin-layer element, Desai et al. 1984): its constrained modulus M_l = h / (h / M + 1 / k_n)
    and shear modulus G_l = h / (h / G + 1 / k_t). An isotropic slab has G / M = (1 - 2 nu) / (2 (1 - nu))
    <= 1/2: below that, nu from the ratio and dG = 0; above (Mindlin's k_t / k_n = 0.82 for steel),
    nu = 0, E = M_l and the extra transverse shear dG = G_l - M_l / 2 on the layer's xz, yz strains
    (fem.carrier.elasticity_matrix: a transversely isotropic layer). A joint has no in-plane
    stiffness: the slab's (~ M_l) is small beside the steel around it."""
    h = np.asarray(h_m, float)
    lam, G = elastic.lame(E_Pa, nu)
    M = lam + 2 * G
    Ml, Gl = h / (h / M + 1.0 / k_n), h / (h / G + 1.0 / k_t)
    r = Gl / Ml
    if np.any(r <= 0):
        raise ValueError(f"joint layer k_n = {k_n!r}, k_t = {k_t!r} Pa/m: both must be > 0")
    iso = r < 0.5
    nu_l = np.where(iso, (1 - 2 * r) / (2 * (1 - np.minimum(r, 0.4999))), 0.0)
    E_l = np.where(iso, Ml * (1 + nu_l) * (1 - 2 * nu_l) / (1 - nu_l), Ml)
    return E_l, nu_l, np.where(iso, 0.0, Gl - Ml / 2)


def joint_layer_tets(m3, in_pillar: np.ndarray, in_flange: np.ndarray, face_z_m: float) -> dict:
    """Tets of the first element layer on each joint of the carrier's extruded mesh (pillar tets on
    the end plate, z_min = 0; flange tets under the mounting face, z_max = face_z_m) and each one's
    layer thickness [m] (its z-extent: the mesh's z-levels)."""
    z = m3.points[m3.tetrahedra, 2]
    zlo, zhi = z.min(axis=1), z.max(axis=1)
    out = {}
    for name, sel in (("pillar", in_pillar & np.isclose(zlo, 0.0, atol=1e-9)),
                      ("face", in_flange & np.isclose(zhi, face_z_m, atol=1e-9))):
        idx = np.flatnonzero(sel)
        out[name] = (idx, zhi[idx] - zlo[idx])
    return out
