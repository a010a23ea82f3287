"""Off-screen report of a diagnosis: diagnosis.json (DESIGN.md keys, exactly) and index.html with
residual plots in time and in orders, before and after the extension (figures via pipeline.render).
"""
from __future__ import annotations

import html
from pathlib import Path

import numpy as np

from geometry.artifacts import write_json_atomic, write_text_atomic
from pipeline import render
from pipeline.diagnosis.orders import label_order, spectrum_of


def write_report(diag, case, out_dir) -> Path:
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    write_json_atomic(out / "diagnosis.json", diag.to_json())
    _plot_time(diag, out / "residual_time.png")
    _plot_orders(diag, out / "residual_orders.png", case)
    write_text_atomic(out / "index.html", _page(diag, case))
    return out / "diagnosis.json"


def _plot_time(diag, path):
    n = len(diag.records)
    fig, axes = render.figure(n, 1, figsize=(9, 1.8 * n + 0.6), squeeze=False, sharex=True)
    for ax, rec, b, k in zip(axes[:, 0], diag.records, diag.residual_before, range(n)):
        ang = np.abs(rec.output_angle_deg - rec.output_angle_deg[0])
        ax.plot(ang, b, lw=0.7, label="before (measured - model)")
        if diag.residual_after is not None:
            ax.plot(ang, diag.residual_after[k], lw=0.7, label="after (extended model)")
        ax.set_ylabel("arcsec")
        ax.set_title(f"{rec.name}  ({rec.torque_Nm:+g} N.m, {'fw' if rec.direction > 0 else 'bw'})", fontsize=8)
    axes[0, 0].legend(fontsize=7, loc="upper right")
    axes[-1, 0].set_xlabel("output travel [deg]")
    render.save_figure(fig, path)


def _plot_orders(diag, path, case):
    n = len(diag.records)
    fig, axes = render.figure(n, 1, figsize=(9, 1.8 * n + 0.6), squeeze=False, sharex=True)
    top = 4 * case.cycloid.zp + 10
    for ax, rec, b, k in zip(axes[:, 0], diag.records, diag.residual_before, range(n)):
        sb = spectrum_of(rec.output_angle_deg, b)
        m = sb.order <= top
        ax.semilogy(sb.order[m], sb.amplitude[m] + 1e-3, lw=0.7, label="before")
        if diag.residual_after is not None:
            sa = spectrum_of(rec.output_angle_deg, diag.residual_after[k])
            ax.semilogy(sa.order[m], sa.amplitude[m] + 1e-3, lw=0.7, label="after")
        for line in diag.lines[k]:
            ax.annotate(f"{line.order:g}", (line.order, line.amplitude), fontsize=6)
        ax.set_ylabel("arcsec")
        ax.set_title(rec.name, fontsize=8)
    axes[0, 0].legend(fontsize=7, loc="upper right")
    axes[-1, 0].set_xlabel("order [per output revolution]")
    render.save_figure(fig, path)


def conditions(diag) -> list[dict]:
    """Per record: its condition (speed, oil temperature from `# oil_temperature_C:`, torque,
    direction, encoder zero), its role and its residual RMS before and after the extension."""
    held = set(diag.extension.held_out) if diag.extension is not None else set()
    out = []
    for k, (r, g) in enumerate(zip(diag.records, diag.groups)):
        after = diag.residual_after[k] if diag.residual_after is not None else None
        out.append({"record": r.name, "input_speed_rpm": r.comment_value("input_speed_rpm") or r.input_speed_rpm,
                    "oil_temperature_C": r.comment_value("oil_temperature_C"), "torque_Nm": r.torque_Nm,
                    "direction": "forward" if r.direction > 0 else "backward", "zero_group": g,
                    "role": "held out" if r.name in held else "fitted",
                    "rms_before_arcsec": float(np.sqrt(np.mean(diag.residual_before[k] ** 2))),
                    "rms_after_arcsec": None if after is None else float(np.sqrt(np.mean(after ** 2)))})
    return out


def _conditions_table(diag) -> str:
    e = html.escape
    num = lambda v, f: "n/a" if v is None else format(v, f)   # noqa: E731
    rows = "".join(f"<tr><td>{e(c['record'])}</td><td>{c['input_speed_rpm']:.0f}</td>"
                   f"<td>{num(c['oil_temperature_C'], 'g')}</td><td>{c['torque_Nm']:+g}</td><td>{c['direction']}</td>"
                   f"<td>{e(c['zero_group'])}</td><td>{c['role']}</td><td>{c['rms_before_arcsec']:.2f}</td>"
                   f"<td>{num(c['rms_after_arcsec'], '.2f')}</td></tr>" for c in conditions(diag))
    return ("<table border=1><tr><th>record</th><th>input rpm</th><th>oil &deg;C</th><th>torque N.m</th>"
            "<th>direction</th><th>encoder zero</th><th>role</th><th>residual RMS before</th>"
            f"<th>after (arcsec; one offset per zero)</th></tr>{rows}</table>")


def _page(diag, case) -> str:
    e = html.escape
    rows = "".join(f"<tr><td>{e(f.cause)}</td><td>{f.score:.3f}</td><td>{e(f.evidence)}</td></tr>"
                   for f in diag.findings) or "<tr><td colspan=3>no cause named: the residual is at the noise floor of the records</td></tr>"
    ext = diag.extension
    ext_html = "<p>no extension (no cause named)</p>"
    if ext is not None:
        params = "".join(f"<tr><td>{e(k)}</td><td>{e(str(v if not isinstance(v, float) else round(v, 4)))}</td></tr>"
                         for k, v in ext.parameters.items())
        ext_html = (f"<p>causes {e(', '.join(ext.causes))}; fitted on {e(', '.join(ext.fitted))}; "
                    f"held out {e(', '.join(ext.held_out)) or 'none'}</p>"
                    f"<p>residual RMS {ext.rms_before_arcsec:.2f} &rarr; {ext.residual_rms_arcsec:.2f} arcsec, "
                    f"gain {ext.gain:.3f}, holdout gain "
                    f"{'n/a' if ext.holdout_gain is None else f'{ext.holdout_gain:.3f}'}</p>"
                    f"<table border=1><tr><th>parameter</th><th>value</th></tr>{params}</table>")
    lines = ""
    for rec, ls in zip(diag.records, diag.lines):
        items = ", ".join(f"{l.order:g}x {l.amplitude:.2f}\" ({e(label_order(case, l.order)) or 'unlabelled'})"
                          for l in sorted(ls, key=lambda l: -l.amplitude)[:8])
        lines += f"<li>{e(rec.name)}: {items or 'none'}</li>"
    sig = "".join(f"<tr><td>{e(s.cause)}</td><td>{e(str(list(s.orders)[:8]))}</td>"
                  f"<td>{e(', '.join(f'{a:.3g}' for a in s.line_arcsec[:8]))}</td></tr>" for s in diag.summaries)
    notes = "".join(f"<li>{e(n)}</li>" for n in diag.notes) or "<li>none</li>"
    if ext is not None and ext.effect_arcsec:
        ext_html += "<p>effect of each cause on the fitted records (RMS, offsets removed; noise floor " \
                    f"{diag.noise_arcsec:.3g} arcsec): " + ", ".join(
                        f"{e(c)} {v:.3g} arcsec" for c, v in ext.effect_arcsec.items()) + "</p>"
    recs = _conditions_table(diag)
    return f"""<!doctype html><html><head><meta charset="utf-8"><title>diagnosis {e(case.name)}</title></head>
<body><h1>Diagnosis: {e(case.name)}</h1>
<p>cause: <b>{e(str(diag.cause))}</b>; baseline residual RMS {diag.residual_rms_arcsec:.2f} arcsec,
peak-to-peak {diag.residual_pp_arcsec:.2f} arcsec (one free offset per encoder zero removed)</p>
<h2>Records and residuals per condition</h2>{recs}
<h2>Findings</h2><table border=1><tr><th>cause</th><th>score</th><th>evidence</th></tr>{rows}</table>
<h2>Extension</h2>{ext_html}
<h2>Notes (input checks, causes not reported, residual left)</h2><ul>{notes}</ul>
<h2>Residual in time</h2><img src="residual_time.png" alt="residual TE over output travel, before and after">
<h2>Residual in orders</h2><img src="residual_orders.png" alt="residual order spectra, before and after">
<h2>Significant residual lines (false-alarm 1e-3 per record)</h2><ul>{lines}</ul>
<h2>Signature library (model, unit size)</h2><table border=1><tr><th>cause</th><th>orders</th><th>arcsec per unit</th></tr>{sig}</table>
</body></html>
"""
