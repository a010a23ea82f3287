"""The engineer's pictures: pure functions of arrays -> one PNG each (matplotlib, off screen).

The stages (cmd_dynamics, cmd_fourbar) and the report (pipeline.report) draw through these, and the image tests
(tests/test_report.py) draw them from fixed arrays and compare with tests/reference_images/.
Conventions: catalog axes (torque in % of rated, angle in arcmin), one colour per torque level and
one panel per load form, characteristic orders labelled in staggered rows so labels never overlap.
"""
from __future__ import annotations

import numpy as np

from dynamics.results import ARCSEC_PER_RAD
from pipeline.render import figure, save_figure

TORQUE_COLOURS = ("#1b9e77", "#d95f02", "#7570b3", "#e7298a", "#66a61e", "#e6ab02")
FORM_STYLES = {"constant": "-", "square": "--", "sine": "-."}


def _at(x: np.ndarray, y: np.ndarray, x0: float) -> float:
    """Mean of y at the samples where x == x0 (both branches), else linear interpolation."""
    hit = np.isclose(x, x0, rtol=0, atol=1e-9 * max(1.0, float(np.max(np.abs(x)))))
    if hit.any():
        return float(np.mean(y[hit]))
    order = np.argsort(x)
    return float(np.interp(x0, x[order], y[order]))


def _polyline(x, y, segments):
    """The segments k -> k+1 where `segments` is true, one line broken by NaN between runs."""
    xs, ys, last = [], [], None
    for k in np.flatnonzero(segments):
        if last != k - 1:
            xs += [np.nan, x[k]]
            ys += [np.nan, y[k]]
        xs.append(x[k + 1])
        ys.append(y[k + 1])
        last = k
    return np.array(xs), np.array(ys)


def hysteresis_loop(path, torque_pct: np.ndarray, angle_arcmin: np.ndarray, *, rigidity_Nm_per_arcmin: float,
                    lost_motion_arcmin: float, backlash_arcmin: float, rated_Nm: float, title: str,
                    secant_Nm_per_arcmin: float | None = None, friction: tuple | None = None) -> None:
    """The catalog curve: torsion angle against torque in % of rated, input locked, the sweep
    0 -> +100 -> -100 -> +100 % drawn as rising-torque and falling-torque branches; lost motion
    (angle between +-3 %) and torsional rigidity b/a (50..100 %) dimensioned; a zoom on +-10 %.
    friction = (torque_pct, angle_arcmin, width_at_zero_arcmin): the loop with contact friction
    (dynamics.losses.operating.friction_loop) drawn over it, its width at zero torque marked."""
    x, y = np.asarray(torque_pct, float), np.asarray(angle_arcmin, float)
    y0 = 0.5 * (_at(x, y, 3.0) + _at(x, y, -3.0))         # catalog origin: centre of the lost motion
    y = y - y0
    fig, (ax, zoom) = figure(1, 2, figsize=(12, 5.2), gridspec_kw={"width_ratios": [3, 2]})
    rising = np.diff(x) > 0
    for a in (ax, zoom):
        for branch, style in ((rising, dict(color="#7fb3e6", lw=3.2)), (~rising, dict(color="#c0392b", lw=1.2, ls="--"))):
            a.plot(*_polyline(x, y, branch), **style)
        a.axvspan(-3, 3, color="#f1c40f", alpha=0.25, lw=0)
        a.axhline(0, color="0.6", lw=0.5)
        a.axvline(0, color="0.6", lw=0.5)
        a.grid(True, lw=0.3)
        a.set_xlabel(f"output torque [% of rated {rated_Nm:g} N m]")
    ax.plot([], [], color="#7fb3e6", lw=3.2, label="torque rising")
    ax.plot([], [], color="#c0392b", ls="--", label="torque falling")
    ax.plot([], [], color="#f1c40f", lw=6, alpha=0.4, label="+-3 % rated (lost-motion band)")
    # rigidity b/a: the chord 50 -> 100 % of each direction
    for s in (1, -1):
        xa, xb = 50.0 * s, 100.0 * s
        ya, yb = _at(x, y, xa), _at(x, y, xb)
        ax.plot([xa, xb, xb], [ya, ya, yb], color="k", lw=0.9)
        ax.annotate(f"b/a = {rigidity_Nm_per_arcmin:.0f} N m/arcmin" if s > 0 else "b/a",
                    (xb, 0.5 * (ya + yb)), xytext=(-8 if s > 0 else 8, 0), textcoords="offset points",
                    ha="right" if s > 0 else "left", va="center", fontsize=9)
    if secant_Nm_per_arcmin is not None:
        ax.plot([], [], " ", label=f"secant (midpoint to +-rated): {secant_Nm_per_arcmin:.0f} N m/arcmin")
    if friction is not None:
        fx, fy, fw = np.asarray(friction[0], float), np.asarray(friction[1], float) - y0, friction[2]
        for a in (ax, zoom):
            a.plot(fx, fy, color="k", lw=0.8, marker=".", ms=3)
        ax.plot([], [], color="k", lw=0.8, marker=".", ms=3, label="with contact friction (boundary)")
        hi_f = fy[np.flatnonzero((np.diff(fx, prepend=fx[0]) < 0) & (fx > 0))[-1]]
        lo_f = fy[np.flatnonzero((np.diff(fx, prepend=fx[0]) > 0) & (fx < 0))[-1]]
        zoom.annotate("", xy=(-1.0, hi_f), xytext=(-1.0, lo_f), arrowprops=dict(arrowstyle="<->", lw=1.0, color="k"))
        zoom.text(-1.5, 0.5 * (lo_f + hi_f), f"width at zero\nwith friction\n{fw:.3f} arcmin", ha="right",
                  va="center", fontsize=8)
    ax.set_ylabel("torsion angle of the output, input locked [arcmin]\n(+ torque and + angle: forward)")
    ax.set_title(title, fontsize=10)
    ax.legend(loc="upper left", fontsize=8)
    ax.set_xlim(-110, 110)
    lo, hi = _at(x, y, -3.0), _at(x, y, 3.0)
    zoom.set_xlim(-10, 10)
    inside = np.abs(x) <= 10.0
    pad = 0.25 * max(np.ptp(y[inside]), 1e-6)
    zoom.set_ylim(y[inside].min() - pad, y[inside].max() + pad)
    zoom.annotate("", xy=(4.5, hi), xytext=(4.5, lo), arrowprops=dict(arrowstyle="<->", lw=1.0))
    zoom.hlines([lo, hi], 3, 5, colors="k", lw=0.6)
    zoom.text(5.2, 0.5 * (lo + hi), f"lost motion\n{lost_motion_arcmin:.3f} arcmin\n(catalog: <= 1)",
              va="center", fontsize=9)
    zoom.text(-9.5, zoom.get_ylim()[1], f"loop width at zero torque\n(backlash) {backlash_arcmin:.3f} arcmin",
              va="top", fontsize=8)
    zoom.set_title("zoom: +-10 % rated", fontsize=10)
    save_figure(fig, path)


def _label_orders(ax, orders: dict[str, float], rows: int = 4) -> None:
    """Vertical lines at the named orders, short labels ("39x zc") in staggered rows inside the
    top quarter of a log-y axis, which is first extended to keep that quarter free of data."""
    lo, hi = ax.get_ylim()
    ax.set_ylim(lo, hi * (hi / lo) ** (1 / 3))
    xlo, xhi = ax.get_xlim()
    shown = sorted((o, n) for n, o in orders.items() if xlo <= o <= xhi)
    for k, (o, name) in enumerate(shown):
        tag = name.split()[-1]
        ax.axvline(o, color="0.35", ls=":", lw=0.7)
        ax.text(o, 0.97 - 0.065 * (k % rows), tag if tag.endswith("x") else f"{o:.4g}x {tag}",
                transform=ax.get_xaxis_transform(), ha="center", va="top", fontsize=7.5, color="0.15",
                bbox=dict(boxstyle="round,pad=0.15", fc="white", ec="none", alpha=0.8))


def te_matrix(path, cells: list[dict], orders: dict[str, float], forms: tuple[str, ...], *,
              title: str, steady_from_s: float) -> None:
    """Paper 001's 12 runs: top row TE against output angle (t >= steady_from_s: ramps cut), one
    panel per load form, one colour per torque; bottom row the order spectra of the same window
    with the characteristic orders and the load's own order labelled, the tallest line annotated.
    cells: form, torque_Nm, t_s, output_angle_deg, te_arcsec, optional order/amplitude, load_order."""
    torques = sorted({c["torque_Nm"] for c in cells})
    colour = {T: TORQUE_COLOURS[i % len(TORQUE_COLOURS)] for i, T in enumerate(torques)}
    spectra = any(c.get("order") is not None for c in cells)
    fig, axes = figure(2 if spectra else 1, len(forms), figsize=(5.2 * len(forms), 9.5 if spectra else 4.6),
                       squeeze=False)
    for j, form in enumerate(forms):
        ax = axes[0, j]
        sp = axes[1, j] if spectra else None
        peak = None
        for c in (c for c in cells if c["form"] == form):
            t = np.asarray(c["t_s"])
            keep = t >= steady_from_s
            if not keep.any():       # a run shorter than the ramps (tests): the whole run, said so
                keep = np.ones_like(t, bool)
            out = np.asarray(c["output_angle_deg"])[keep]
            ax.plot(out, np.asarray(c["te_arcsec"])[keep], color=colour[c["torque_Nm"]], lw=0.8,
                    ls=FORM_STYLES.get(form, "-"), label=f"{c['torque_Nm']:g} N m")
            if sp is not None and c.get("order") is not None:
                o, a = np.asarray(c["order"])[1:], np.asarray(c["amplitude"])[1:]
                sp.loglog(o, a + 1e-6, color=colour[c["torque_Nm"]], lw=0.7)
                k = int(np.argmax(a))
                if peak is None or a[k] > peak[1]:
                    peak = (o[k], a[k])
        ax.set_title(f"{form} load", fontsize=10)
        ax.set_xlabel("output angle [deg]")
        ax.set_ylabel(f"TE [arcsec] (t >= {steady_from_s:g} s)")
        ax.grid(True, lw=0.3)
        ax.legend(fontsize=7, title="T", title_fontsize=7, loc="best")
        if sp is not None:
            sp.set_xlim(0.5, max(orders.values()) * 1.5)
            sp.set_ylim(1e-4, None)
            load = {"load": c["load_order"] for c in cells
                    if c["form"] == form and c.get("load_order")}
            _label_orders(sp, {**orders, **dict(list(load.items())[:1])})
            if peak is not None:
                sp.annotate(f"tallest: {peak[0]:.4g}x, {peak[1]:.3g} arcsec", peak, xytext=(-12, -22), ha="right",
                            textcoords="offset points", fontsize=7, arrowprops=dict(arrowstyle="->", lw=0.6))
            sp.set_xlabel("order [cycles per output revolution]")
            sp.set_ylabel("TE amplitude [arcsec]")
            sp.grid(True, which="both", lw=0.2)
    fig.suptitle(title, fontsize=11)
    fig.tight_layout()
    save_figure(fig, path)


def load_deflection(path, stiffness: dict, *, title: str) -> None:
    """FE load-deflection curves of stiffness.json: the cycloid tooth-pin contact at each contact
    position (one curve per pin phase), and the needle and support bearings beside them."""
    pc = stiffness["pin_contact"]
    pos, load = np.asarray(pc["position_deg"], float), np.asarray(pc["load_N"], float)
    appr = np.asarray(pc["approach_m"], float) * 1e6
    panels = [k for k in ("turning_arm", "support_bearings") if isinstance(stiffness.get(k), dict)
              and "deflection_m" in stiffness[k]]
    fig, axes = figure(1, 1 + len(panels), figsize=(6.5 + 4.5 * len(panels), 5), squeeze=False)
    ax = axes[0, 0]
    cmap = __import__("matplotlib").colormaps["viridis"]
    for k, p in enumerate(pos):
        ax.plot(appr[k], load / 1e3, ".-", ms=3, lw=1.0, color=cmap(k / max(len(pos) - 1, 1)),
                label=f"{p:g} deg")
    ax.set_xlabel("normal approach, pin centre to disc [um]")
    ax.set_ylabel("normal contact force [kN]")
    ax.set_title("cycloid tooth - pin (2D FE x disc width)\nby pin phase from the line of centres", fontsize=10)
    ax.grid(True, lw=0.3)
    ax.legend(fontsize=7, ncol=2, title="position", title_fontsize=7)
    names = {"turning_arm": "needle (turning-arm) bearing, radial", "support_bearings": "crank support bearing, radial"}
    for ax, key in zip(axes[0, 1:], panels):
        d = stiffness[key]
        ax.plot(np.asarray(d["deflection_m"], float) * 1e6, np.asarray(d["load_N"], float) / 1e3, ".-",
                color="#1f5fa8")
        if d.get("operating_load_N"):
            ax.axhline(d["operating_load_N"] / 1e3, color="#c0392b", ls="--", lw=0.8, label="at rated torque")
            ax.legend(fontsize=8)
        ax.set_xlabel("radial deflection [um]")
        ax.set_ylabel("radial load [kN]")
        ax.set_title(names[key] + (f"\n{d['designation']}" if d.get("designation") else ""), fontsize=10)
        ax.grid(True, lw=0.3)
    fig.suptitle(title, fontsize=11)
    fig.tight_layout()
    save_figure(fig, path)


def load_sharing(path, pin_angle_deg: np.ndarray, pin_force_N: np.ndarray, cycle: np.ndarray,
                 teeth: np.ndarray, max_share: np.ndarray, *, torque_Nm: float, title: str) -> None:
    """Left: normal force on every pin of each disc at one pose (rated torque). Right: over one
    mesh cycle (a pin pitch of the eccentric), teeth in contact per disc and the largest pin's
    share of its disc's load."""
    fig, (ax, cyc) = figure(1, 2, figsize=(13, 4.8), gridspec_kw={"width_ratios": [3, 2]})
    n_disc = pin_force_N.shape[0]
    width = 360.0 / len(pin_angle_deg) / (n_disc + 1)
    for d in range(n_disc):
        ax.bar(pin_angle_deg + (d - (n_disc - 1) / 2) * width, pin_force_N[d] / 1e3, width=width,
               color=TORQUE_COLOURS[d], label=f"disc {d + 1}: {int((pin_force_N[d] > 0).sum())} pins loaded")
    ax.set_xlim(0, 360)
    ax.set_xticks(np.arange(0, 361, 45))
    ax.set_xlabel("pin position on the pin circle [deg]")
    ax.set_ylabel("pin normal force [kN]")
    ax.set_title(f"load sharing per pin at {torque_Nm:g} N m", fontsize=10)
    ax.legend(fontsize=8)
    ax.grid(True, axis="y", lw=0.3)
    for d in range(n_disc):     # later discs thinner and dashed: equal counts stay visible
        cyc.step(cycle, teeth[:, d], where="mid", color=TORQUE_COLOURS[d], lw=3.0 / (d + 1), ls="-" if d == 0 else "--",
                 label=f"disc {d + 1}: teeth in contact")
    cyc.set_xlabel("mesh cycle [pin pitches of eccentric rotation]")
    cyc.set_ylabel("teeth in contact")
    cyc.yaxis.get_major_locator().set_params(integer=True)
    share = cyc.twinx()
    share.plot(cycle, 100 * max_share, color="0.3", ls="--", lw=1.0, label="largest pin share (both discs)")
    share.set_ylabel("largest pin's share of its disc's load [%]")
    h1, l1 = cyc.get_legend_handles_labels()
    h2, l2 = share.get_legend_handles_labels()
    cyc.legend(h1 + h2, l1 + l2, fontsize=7, loc="lower right")
    cyc.set_title("over one mesh cycle", fontsize=10)
    cyc.grid(True, lw=0.3)
    fig.suptitle(title, fontsize=11)
    fig.tight_layout()
    save_figure(fig, path)


def budget_bars(path, budget: dict, title: str) -> None:
    """Horizontal bars: % of the output compliance per component at the budget's torque, each
    labelled with its equivalent stiffness (tangent rigidity / share: that part alone in series)."""
    rig = budget["tangent_rigidity_Nm_per_arcmin"]
    items = sorted(budget["compliance_budget"].items(), key=lambda kv: kv[1])
    fig, ax = figure(figsize=(8, 0.45 * len(items) + 1.5))
    y = np.arange(len(items))
    ax.barh(y, [100 * v for _, v in items], color="tab:blue")
    ax.set_yticks(y, [f"{k}  ({rig / v:,.0f} N m/arcmin)" if v > 0 else f"{k}  (rigid)" for k, v in items])
    for yi, (_, v) in zip(y, items):
        ax.text(100 * v, yi, f" {100 * v:.1f} %", va="center", fontsize=8)
    ax.set_xlabel("share of the output torsional compliance [%]")
    ax.set_xlim(0, 100 * max(v for _, v in items) * 1.2 + 1e-9)
    ax.set_title(f"{title}: compliance budget at {budget['torque_Nm']:g} N m "
                 f"(tangent rigidity {rig:.0f} N m/arcmin)", fontsize=10)
    ax.grid(True, axis="x", lw=0.3)
    save_figure(fig, path)


def fourbar_sweeps(out, dev, singles, pairs, scan, labels: dict[str, str]) -> None:
    """fourbar/: individual.png (each source swept alone, rigid and elastic), surface_<a>_<b>.png (pairs)
    and crank_angle_scan.png (exact closure beside paper 000's quadratic); deviations in mm, errors in rad."""
    A = ARCSEC_PER_RAD
    fig, ax = figure(1, 2, figsize=(11, 4))
    for s, sw in singles.items():
        ax[0].plot(dev * 1e3, sw.rigid_rad * A, label=labels[s])
        ax[1].plot(dev * 1e3, sw.elastic_rad * A, label=labels[s])
    for a, t in zip(ax, ("rigid", "elastic")):
        a.set_xlabel("deviation [um]"); a.set_ylabel("output-angle error [arcsec]"); a.set_title(t)
        a.axhline(60, ls=":", c="gray"); a.axhline(-60, ls=":", c="gray"); a.grid(alpha=0.3)
    ax[0].legend(fontsize=7)
    save_figure(fig, out / "individual.png")
    for (a, b), sw in pairs.items():
        fig = figure(figsize=(11, 4.5))[0]
        fig.clf()
        X, Y = np.meshgrid(dev * 1e3, dev * 1e3, indexing="ij")
        for k, (z, t) in enumerate(((sw.rigid_rad, "rigid"), (sw.elastic_rad, "elastic"))):
            ax3 = fig.add_subplot(1, 2, k + 1, projection="3d")
            ax3.plot_surface(X, Y, z * A, cmap="viridis")
            ax3.set_xlabel(f"{a} [um]", fontsize=8); ax3.set_ylabel(f"{b} [um]", fontsize=8)
            ax3.set_zlabel("error [arcsec]", fontsize=8); ax3.set_title(t)
        save_figure(fig, out / f"surface_{a}_{b}.png")
    fig, ax = figure(figsize=(7, 4))
    for s, v in scan.items():
        ax.plot(v["beta1_deg"], v["exact_rad"] * A, label=f"{s} exact")
        ax.plot(v["beta1_deg"], v["quadratic_rad"] * A, "--", label=f"{s} quadratic")
    ax.set_yscale("symlog", linthresh=1.0)
    ax.set_xlabel("crank angle beta1 [deg]"); ax.set_ylabel("rigid output-angle error [arcsec]")
    ax.set_title("exact closure vs paper's quadratic (+max deviation, no load)"); ax.legend(fontsize=7)
    ax.grid(alpha=0.3)
    save_figure(fig, out / "crank_angle_scan.png")


def housing_section(path, points_m: np.ndarray, triangles: np.ndarray, displacement_m: np.ndarray,
                    von_mises_Pa: np.ndarray, pin_xy_m: np.ndarray, pin_force_N: np.ndarray, bolt_xy_m: np.ndarray,
                    bolt_radius_m: float, radial_stiffness_N_per_m: np.ndarray, lobes: dict, *, title: str,
                    datum_stiffness_N_per_m: np.ndarray | None = None) -> None:
    """The housing section (fem.housing): von Mises on the deformed mesh under one disc's pin forces
    (displacements magnified), a zoom on the most loaded grooves with the mesh, and the per-pin
    radial stiffness around the ring with its Fourier lobes (and, when given, that of the datum
    one pin pitch behind each groove: the housing beyond the groove law)."""
    import matplotlib.tri as mtri
    from matplotlib.patches import Circle
    p, u = points_m * 1e3, displacement_m * 1e3
    umax = float(np.abs(u).max()) or 1.0
    scale = 0.04 * float(np.ptp(p[:, 0])) / umax
    fig, axes = figure(1, 3, figsize=(18, 6.2), gridspec_kw={"width_ratios": [1.1, 1.0, 1.1]})
    tri = mtri.Triangulation(*(p + scale * u).T, triangles)
    fmax = float(np.hypot(*pin_force_N.T).max()) or 1.0
    k_hot = int(np.argmax(np.hypot(*pin_force_N.T)))
    for ax, zoom in ((axes[0], False), (axes[1], True)):
        pc = ax.tripcolor(tri, facecolors=von_mises_Pa / 1e6, cmap="viridis", edgecolors="0.3" if zoom else "none",
                          linewidth=0.1)
        for b in bolt_xy_m:
            ax.add_patch(Circle(b * 1e3, bolt_radius_m * 1e3, color="#c0392b", alpha=0.6))
        arrow = (0.03 if zoom else 0.08) * float(np.ptp(p[:, 0])) / fmax     # force on the housing, ending at the pin
        for xy, f in zip(pin_xy_m * 1e3, pin_force_N):
            if np.hypot(*f) > 0:
                ax.annotate("", xy=xy, xytext=xy - arrow * f,
                            arrowprops=dict(arrowstyle="-|>", color="#e67e22", lw=1.2, mutation_scale=10))
        ax.set_aspect("equal")
        if zoom:
            c = pin_xy_m[k_hot] * 1e3
            span = 4.0 * np.hypot(*(pin_xy_m[1] - pin_xy_m[0])) * 1e3
            ax.set_xlim(c[0] - span, c[0] + span)
            ax.set_ylim(c[1] - span, c[1] + span)
            ax.set_title("most loaded grooves, mesh (P2 triangles)")
        else:
            ax.set_title(f"von Mises [MPa], displacement x {scale:.3g}")
        ax.set_xlabel("x [mm]")
        ax.set_ylabel("y [mm]")
        fig.colorbar(pc, ax=ax, shrink=0.8, label="von Mises [MPa]")
    ax = axes[2]
    ang = np.degrees(np.arctan2(pin_xy_m[:, 1], pin_xy_m[:, 0])) % 360
    order = np.argsort(ang)
    k = radial_stiffness_N_per_m / 1e6
    ax.plot(ang[order], k[order], "o-", color="#1b9e77", ms=4, label="seat (groove surface)")
    ax.axhline(float(k.mean()), color="0.5", lw=0.8, ls="--", label=f"seat mean {k.mean():.0f} N/um")
    if datum_stiffness_N_per_m is not None:
        kd = datum_stiffness_N_per_m / 1e6
        ax.plot(ang[order], kd[order], "s-", color="#7570b3", ms=3, lw=0.8,
                label=f"datum one pin pitch behind (mean {kd.mean():.0f} N/um)")
    for b in np.degrees(np.arctan2(bolt_xy_m[:, 1], bolt_xy_m[:, 0])) % 360:
        ax.axvline(b, color="#c0392b", lw=0.6, alpha=0.5)
    ax.plot([], [], color="#c0392b", lw=0.6, label="bolt angles")
    big = sorted(((m, v) for m, v in lobes.items() if v > 1e-4), key=lambda kv: -kv[1])[:4]
    text = ", ".join(f"m={m}: {100 * v:.2f} %" for m, v in big) or "none above 0.01 %"
    ax.set_title(f"per-pin radial stiffness; seat lobes (of the mean) {text}", fontsize=9)
    ax.set_xlabel("pin angle [deg]")
    ax.set_ylabel("radial stiffness [N/um]")
    ax.grid(True, lw=0.3)
    ax.set_yscale("log")
    ax.legend(loc="center right", fontsize=8)
    fig.suptitle(title)
    save_figure(fig, path)
