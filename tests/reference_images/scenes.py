"""Fixed scenes of the report's pictures, drawn from closed-form arrays (no model run), and the
comparison with their cached reference PNGs (the way PyVista's image tests work: a tolerance on the
difference, so a picture that breaks fails and a font's sub-pixel change does not).

Regenerate the references after an intended change of a picture, then look at them:
    .venv/bin/python tests/reference_images/scenes.py
"""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent.parent
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from pipeline import figures  # noqa: E402

RMS_TOLERANCE = 6.0     # grey levels (0..255): a moved line or label shows ~10-40, anti-aliasing < 2


def _loop():
    """A catalog-shaped loop: free play +-b/2 closed by a Hertzian (T^(2/3)) start, then linear."""
    rated, k, b = 412.0, 250.0, 0.78                       # N m, N m/arcmin, arcmin
    up = np.linspace(0, 1, 21)
    leg = np.unique(np.concatenate([up, [1e-4, 0.03, 0.5]]))
    pct = 100 * np.concatenate([leg, leg[::-1][1:], -leg[1:], -leg[::-1][1:], leg[1:]])
    T = pct / 100 * rated
    ang = np.sign(T) * (b / 2 + 0.05 * np.abs(T / rated) ** (2 / 3)) + T / k
    return pct, ang, rated, k, b


def hysteresis(path, flip: bool = False):
    pct, ang, rated, k, b = _loop()
    figures.hysteresis_loop(path, pct, -ang if flip else ang, rigidity_Nm_per_arcmin=k, lost_motion_arcmin=0.93,
                            backlash_arcmin=b, rated_Nm=rated, title="scene: catalog hysteresis loop")


def te_matrix(path):
    orders = {"carrier 1x": 1.0, "cranks 3x": 3.0, "disc tooth zc": 39.0, "pin / crank rotation zp": 40.0,
              "input shaft i": 81.0, "cycloid-pin mesh zp*zc": 1560.0}
    cells = []
    t = np.linspace(0, 9.0, 9001)
    out = 88.89 * np.clip(t - 0.5, 0, None)
    for T in (100.0, 200.0, 300.0, 400.0):
        for form, load in (("constant", 0 * t), ("square", np.sign(np.sin(2 * np.pi * t))),
                           ("sine", np.sin(8 * t))):
            te = -T / 250 * 60 * (1 + 0.05 * load) + 0.1 * np.sin(np.deg2rad(out) * 39)
            steady = t >= 2
            rev = int(np.ptp(out[steady]) // 360)
            order = np.arange(0, 4096) / max(rev, 1)
            amp = 1e-3 * np.exp(-order / 300) + np.where(np.isclose(order, 4.0), T / 250 * 3, 0)
            cells.append({"form": form, "torque_Nm": T, "t_s": t, "output_angle_deg": out, "te_arcsec": te,
                          "order": order, "amplitude": amp, "load_order": None if form == "constant" else 4.05})
    figures.te_matrix(path, cells, orders, ("constant", "square", "sine"), title="scene: TE matrix",
                      steady_from_s=2.0)


def load_deflection(path):
    pos = np.array([-60.0, -30.0, 0.0, 30.0, 60.0])
    load = np.linspace(0, 12000, 9)
    appr = (load[None, :] / (2e8 * (1 + np.cos(np.deg2rad(pos)))[:, None])) ** (1 / 1.1)
    defl = (load / 4e8) ** (1 / 1.1)
    stiff = {"pin_contact": {"position_deg": pos.tolist(), "load_N": load.tolist(), "approach_m": appr.tolist()},
             "turning_arm": {"load_N": load.tolist(), "deflection_m": defl.tolist()},
             "support_bearings": {"load_N": load.tolist(), "deflection_m": (0.5 * defl).tolist(),
                                  "operating_load_N": 6000.0, "designation": "30205"}}
    figures.load_deflection(path, stiff, title="scene: FE load-deflection")


def load_sharing(path):
    zp = 40
    pins = 360.0 * np.arange(zp) / zp
    f = np.clip(np.sin(np.deg2rad(pins - 20)), 0, None) ** 2 * 3000
    pf = np.stack([f, np.roll(f, zp // 2)])
    cycle = np.linspace(0, 1, 41)
    teeth = np.stack([np.where(cycle < 0.4, 9, 8), np.where(cycle < 0.6, 8, 9)], axis=1)
    figures.load_sharing(path, pins, pf, cycle, teeth, 0.14 + 0.01 * np.cos(2 * np.pi * cycle), torque_Nm=412,
                         title="scene: load sharing")


def hysteresis_friction(path):
    """The loop with a friction loop over it: branches apart by +-0.02 arcmin, width marked."""
    pct, ang, rated, k, b = _loop()
    rising = np.diff(pct, prepend=pct[0]) >= 0
    figures.hysteresis_loop(path, pct, ang, rigidity_Nm_per_arcmin=k, lost_motion_arcmin=0.93, backlash_arcmin=b,
                            rated_Nm=rated, title="scene: catalog loop with friction", secant_Nm_per_arcmin=0.8 * k,
                            friction=(pct, ang + np.where(rising, -0.02, 0.02), b + 0.04))


def gap_map(path):
    """Gap linear in torque per speed (measured steeper at low speed), p-p flat + growing."""
    from pipeline import figures_conditions
    speed = np.repeat([100.0, 1800.0], 10)
    T = np.tile(np.linspace(0, 1800, 10), 2)
    meas = -(25 + np.where(speed < 500, 0.29, 0.24) * T)
    pred = -(47 + 0.13 * T)
    figures_conditions.gap_map(path, speed, T, pred, pred + 0.01 * T, 0.1 + 0 * T, 0.12 + 0 * T, gap_meas=meas,
                               pp_fw_meas=140 + 0.015 * T, pp_bw_meas=138 + 0.015 * T, title="scene: operating map")


def efficiency(path):
    """Catalog-shaped curves: efficiency falling with speed, rising with torque and temperature."""
    from pipeline import figures_conditions
    n = np.array([2.0, 5, 10, 15, 20, 30, 40])
    eff = np.array([[[0.82 - (0.10 - 0.03 * q) * (n / 40) ** 0.7 / (1 + t / 40) - 0.04 * (1 - q)
                      for q in (0.25, 0.5, 1.0)] for t in (25.0, 40.0, 60.0)]])[0]
    figures_conditions.efficiency_chart(path, n, (25, 50, 100), (25, 40, 60), eff, published=(15.0, 0.82, 0.80, 0.85),
                                        title="scene: efficiency chart")


SCENES = {"hysteresis": hysteresis, "te_matrix": te_matrix, "load_deflection": load_deflection,
          "load_sharing": load_sharing, "hysteresis_friction": hysteresis_friction, "gap_map": gap_map,
          "efficiency": efficiency}


def rms_difference(produced: Path, reference: Path) -> float:
    """RMS grey-level difference (0..255), the produced picture resized to the reference's size."""
    from PIL import Image
    ref = Image.open(reference).convert("L")
    new = Image.open(produced).convert("L")
    if new.size != ref.size:
        new = new.resize(ref.size, Image.BILINEAR)
    d = np.asarray(new, float) - np.asarray(ref, float)
    return float(np.sqrt(np.mean(d ** 2)))


if __name__ == "__main__":
    for name, draw in SCENES.items():
        draw(HERE / f"{name}.png")
        print(f"wrote {HERE / name}.png")
