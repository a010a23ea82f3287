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


def layer_material(h_m, E_Pa: float, nu: float, k_n: float, k_t: float) -> tuple[np.ndarray, np.ndarray]:
    """(E, nu) of a slab of thickness h that carries its own steel AND a joint's compliance in series
    (a thin-layer element, Desai et al. 1984): its constrained modulus M_l = h / (h / M + 1 / k_n) and
    shear modulus G_l = h / (h / G + 1 / k_t), back to isotropic E, nu. A joint has no in-plane
    stiffness: the slab's in-plane stiffness (E_l ~ k h) is small beside the steel around it.
    G_l / M_l = (1 - 2 nu) / (2 (1 - nu)) needs nu in (-1, 0.5): a ratio G_l / M_l outside
    (0, 0.75) is refused (the joint law's k_t / k_n, fem.joints, lies within)."""
    h = np.asarray(h_m, float)
    lam, G = elastic.lame(E_Pa, nu)
    M = lam + 2 * G
    Ml, Gl = h / (h / M + 1.0 / k_n), h / (h / G + 1.0 / k_t)
    r = Gl / Ml
    if np.any(r <= 0) or np.any(r >= 0.75):
        raise ValueError(f"joint layer G/M = {r.min():.3g}..{r.max():.3g}: allowed (0, 0.75) (k_t / k_n of the law)")
    nu_l = (1 - 2 * r) / (2 * (1 - r))
    return 2 * Gl * (1 + nu_l), nu_l
