"""Pictures of the operating map (`conditions`): pure functions of arrays -> one PNG each.

gap_map        predicted beside measured forward-backward gap and TE peak-to-peak against torque, one
               colour per input speed (measured: markers, predicted: lines; frictionless: dotted)
efficiency     the catalog's efficiency chart: efficiency against output speed, one line per torque,
               one line style per oil temperature
"""
from __future__ import annotations

import numpy as np

from pipeline.render import figure, save_figure

SPEED_COLOURS = ("#1b9e77", "#d95f02", "#7570b3", "#e7298a", "#66a61e", "#e6ab02", "#a6761d")
TEMP_STYLES = ("-", "--", ":", "-.")


def gap_map(path, speed_rpm, torque_Nm, gap_pred, gap_frictionless, pp_fw_pred, pp_bw_pred, *,
            gap_meas=None, pp_fw_meas=None, pp_bw_meas=None, title: str = "") -> None:
    speed, T = np.asarray(speed_rpm, float), np.asarray(torque_Nm, float)
    fig, (ax, bx) = figure(1, 2, figsize=(13, 5.2))
    for i, s in enumerate(sorted(set(speed))):
        m = speed == s
        o = np.argsort(T[m])
        c = SPEED_COLOURS[i % len(SPEED_COLOURS)]
        ax.plot(T[m][o], np.asarray(gap_pred)[m][o], "-", marker=".", color=c, lw=1.6, label=f"{s:g} rpm predicted")
        ax.plot(T[m][o], np.asarray(gap_frictionless)[m][o], ":", color=c, lw=1.0)
        bx.plot(T[m][o], np.asarray(pp_fw_pred)[m][o], "-", marker=".", color=c, lw=1.6, label=f"{s:g} rpm predicted fw")
        bx.plot(T[m][o], np.asarray(pp_bw_pred)[m][o], "--", color=c, lw=1.0, label=f"{s:g} rpm predicted bw")
        if gap_meas is not None:
            ax.plot(T[m][o], np.asarray(gap_meas)[m][o], "o", color=c, ms=4, mfc="none", label=f"{s:g} rpm measured")
        if pp_fw_meas is not None:
            bx.plot(T[m][o], np.asarray(pp_fw_meas)[m][o], "o", color=c, ms=4, mfc="none")
            bx.plot(T[m][o], np.asarray(pp_bw_meas)[m][o], "s", color=c, ms=3, mfc="none")
    ax.plot([], [], ":", color="0.3", label="predicted, frictionless")
    ax.set_xlabel("output torque [N m]")
    ax.set_ylabel("mean TE forward - backward [arcsec]")
    ax.set_title("forward-backward gap: lines predicted, circles measured", fontsize=10)
    bx.set_xlabel("output torque [N m]")
    bx.set_ylabel("TE peak-to-peak over one output revolution [arcsec]")
    bx.set_title("TE peak-to-peak: circles forward, squares backward measured", fontsize=10)
    for a in (ax, bx):
        a.grid(True, lw=0.3)
    ax.legend(fontsize=7, ncol=2, loc="lower left")
    bx.legend(fontsize=7, ncol=2, loc="best")
    if title:       # above the panels' own titles, however many lines it wraps to
        fig.suptitle(title, fontsize=10, y=0.93, va="bottom")
    save_figure(fig, path)


def efficiency_chart(path, output_speed_rpm, torque_pct, temperature_C, efficiency, *, published=None,
                     title: str = "") -> None:
    """efficiency[i_temperature, i_torque, i_speed]; published (speed, value, low, high) marked."""
    eff = np.asarray(efficiency, float)
    fig, ax = figure(1, 1, figsize=(8, 5.2))
    for it, temp in enumerate(temperature_C):
        for iq, q in enumerate(torque_pct):
            ax.plot(output_speed_rpm, 100 * eff[it, iq], TEMP_STYLES[it % len(TEMP_STYLES)],
                    color=SPEED_COLOURS[iq % len(SPEED_COLOURS)], lw=1.4,
                    label=f"{q:g} % rated, {temp:g} C oil")
    if published is not None:
        s, v, lo, hi = published
        ax.errorbar([s], [100 * v], yerr=[[100 * (v - lo)], [100 * (hi - v)]], fmt="k*", ms=10, capsize=4,
                    label="published (catalog chart, rated torque)")
    ax.set_xlabel("output speed [rpm]")
    ax.set_ylabel("efficiency, forward [%]")
    ax.grid(True, lw=0.3)
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    ax.set_title(title or "efficiency against output speed", fontsize=10)
    save_figure(fig, path)
