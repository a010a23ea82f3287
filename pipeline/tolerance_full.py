"""Artifacts of `tolerance --model full` (the computation is dynamics.tolerance.full_monte_carlo).

    DIR/summary.json     distributions, yields, sensitivity ranking, bands, grid, made_from
    DIR/samples.csv      one row per build: TE p-p and sigma (reducer, bench-read), lost motion,
                         rigidity, line amplitudes; build i's errors are
                         dynamics.tolerance.draw_build(case, distribution, seed, i)
    DIR/sensitivity.csv  each band alone: its share of the summed TE variance, TE, lost-motion change
    DIR/histogram.png, DIR/sensitivity.png
"""
from __future__ import annotations

import csv
import io
from pathlib import Path

import numpy as np

from geometry.artifacts import write_json_atomic, write_text_atomic

SENSITIVITY_COLUMNS = ("band", "te_variance_share", "te_sigma_mean_arcsec", "te_pp_mean_arcsec",
                       "lost_motion_change_mean_arcmin", "builds", "not_solved")


def _csv(rows, header) -> str:
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(header)
    w.writerows(rows)
    return buf.getvalue()


def write_full(out: Path, res, summary: dict) -> None:
    write_json_atomic(out / "summary.json", summary)
    rows = [[i, *(f"{v:.6g}" for v in r)] for i, r in enumerate(res.samples)]
    write_text_atomic(out / "samples.csv", _csv(rows, ["build", *res.columns]))
    rank = summary["sensitivity"]
    write_text_atomic(out / "sensitivity.csv", _csv(
        [[d[c] if isinstance(d[c], (str, int)) else f"{d[c]:.6g}" for c in SENSITIVITY_COLUMNS] for d in rank],
        SENSITIVITY_COLUMNS))
    _figures(out, res, summary)


def _figures(out: Path, res, summary: dict) -> None:
    from pipeline.render import figure, save_figure
    lim, lm_lim, y = summary["limit_te_pp_arcsec"], summary["limit_lost_motion_arcmin"], summary["yield"]
    fig, ax = figure(2, 2, figsize=(12, 8))
    panels = [([("te_pp_arcsec", "reducer"), ("bench_te_pp_arcsec", "bench-read (+ coaxiality)")], lim,
               f"TE peak-to-peak over one output revolution [arcsec]; within {lim:g}: reducer "
               f"{100 * y['te_pp']:.0f} %, bench-read {100 * y['bench_te_pp']:.0f} %"),
              ([("te_sigma_arcsec", "reducer"), ("bench_te_sigma_arcsec", "bench-read")], None, "TE sigma [arcsec]"),
              ([("lost_motion_arcmin", "lost motion")], lm_lim,
               f"lost motion at +-3 % rated [arcmin]; within {lm_lim:g}: {100 * y['lost_motion']:.0f} %"),
              ([("rigidity_Nm_per_arcmin", "rigidity")], None, "torsional rigidity 50-100 % rated [N m/arcmin]")]
    for a, (series, limit, title) in zip(ax.ravel(), panels):
        for name, label in series:
            x = res.column(name)
            a.hist(x[np.isfinite(x)], bins=40, alpha=0.6, label=label)
            a.axvline(summary["nominal"][name], c="k", ls=":", lw=1)
        if limit is not None:
            a.axvline(limit, c="r", ls="--")
        a.set_title(title, fontsize=9)
        a.set_ylabel("builds")
        a.legend(fontsize=8)
    fig.suptitle(f"{summary['case']}: {summary['samples']} builds from the case's [tolerances], full model "
                 f"at {summary['torque_Nm']:g} N m (dotted: ideal build)", fontsize=10)
    save_figure(fig, out / "histogram.png")
    rank = [d for d in summary["sensitivity"] if np.isfinite(d["te_variance_share"])][::-1]
    fig, a = figure(figsize=(8, 0.35 * len(rank) + 1.5))
    a.barh([d["band"] for d in rank], [100 * d["te_variance_share"] for d in rank], color="tab:blue")
    a.set_xlabel("share of the summed TE variance, each band alone [%] (bench-read TE)")
    a.set_title("which tolerance to tighten first (top)", fontsize=10)
    save_figure(fig, out / "sensitivity.png")
