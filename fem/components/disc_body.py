"""Disc body with its holes: 2D plane-stress P2 FE of the disc, pins to crank holes, less the parts
the tooth and needle models carry (fem.disc_body); a linear compliance in series with each pin."""
from __future__ import annotations

import dataclasses as dc

import numpy as np

from fem.components.base import Result, timed

NAME = "disc_body"
COUPLING = "pin"
COST = 20
ANGLES = 6          # crank angles over one crank spacing (the load pattern's period)


@timed
def compute(case, ctx) -> Result:
    """Energy-equivalent per-pin compliance of the disc body, sum F_i delta_i / sum F_i^2 under the
    classical sharing at the rated torque (half per disc), mean over ANGLES crank angles across one
    crank spacing (disc 2 at psi + pi sits at another phase of the same period)."""
    from fem import disc_body as db
    h = ctx.get("disc_h_profile_m")
    m = db.DiscBodyModel.build(case, h)
    psi = 2 * np.pi / case.carrier.crank_count * np.arange(ANGLES) / ANGLES
    c, res = [], []
    for p in psi:
        r = m.solve(float(p), 0.5 * case.rated_torque_Nm)
        F = r.pattern.force_N
        c.append(float(F @ r.approach_m / (F @ F)))
        res.append(r)
    lame = db.lame_ring_check(h or db.default_h_profile_m(case))
    check = {"per_angle_m_per_N": c, "crank_angle_rad": psi.tolist(),
             "rotation_per_torque_rad_per_Nm": [r.rotation_per_torque_rad_per_Nm for r in res],
             "tooth_local_taken_out_rad_per_Nm": [r.tooth_local_per_torque_rad_per_Nm for r in res],
             "bore_ring_taken_out_rad_per_Nm": [r.bore_ring_per_torque_rad_per_Nm for r in res],
             "frame_residual_m": max(r.frame_residual_m for r in res),
             "imbalance": max(r.imbalance for r in res), "reaction": max(r.reaction for r in res),
             "lame_ring_inner_error": lame["inner_error"], "lame_ring_outer_error": lame["outer_error"],
             "lame_ring_h_m": lame["h_m"], "dofs": res[0].dofs, "h_profile_m": res[0].h_profile_m}
    return Result(NAME, {"pin_series.disc_body_compliance_m_per_N": float(np.mean(c))},
                  {NAME: "2D plane-stress FE (P2) of the disc with its holes, classical pin sharing at the rated "
                         "torque, crank holes as the datum; tooth-pair region and needle bore ring taken out "
                         f"(fem.disc_body); sum F d / sum F^2, mean of {ANGLES} crank angles over one crank spacing"},
                  {NAME: check})


def stiffen(model, f: float):
    ps = model.pin_series
    return dc.replace(model, pin_series=dc.replace(ps, disc_body_compliance_m_per_N=ps.disc_body_compliance_m_per_N / f))


def series_approach_m(model, force_N):
    return model.pin_series.disc_body_compliance_m_per_N * np.asarray(force_N, float)
