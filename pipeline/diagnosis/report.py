"""Off-screen report of a diagnosis: diagnosis.json (DESIGN.md keys, exactly) and index.html with
residual plots in time and in orders, before and after the extension (figures via pipeline.render).

Line attribution (attribute_lines, shared by residual_orders.png and the page's line table): a line
is an order 1 .. 4 zp + 10 that is significant (significance.test_lines, false alarm 1e-3 per record)
AND at least the records' noise floor (an effect, not only a p-value) in a record's residual before
or after the extension. Its label, per record:
  <cause>[+<cause>]            gone after the extension: the reported causes that hold the order;
  partly <cause>[+<cause>]     such causes, the line still there but down by more than half;
  explained (no cause's line)  gone after the extension, but no reported cause holds the order: the
                               joint fit removed it through lines below a signature's 10 % cut
                               (signatures.summarise), so no single cause can be named;
  added by <cause>[+<cause>]   not a line before, a line after (over twice as large): the extension
                               put it there through such causes (it overshoots at that order);
  unexplained                  still there (or grown), or no extension at all.
A reported cause holds an order when its signature (SignatureSummary.orders) has it AND its line
there at the fitted size is at least NAMED_SHARE of the line's change and of the largest such
estimate among the causes holding it; the largest is named first. The fitted size is estimated as
u = effect_arcsec / RMS of the cause's unit signature (its lines, and the spread of its mean shift
within each encoder zero, which the offsets do not remove): mean-shift causes (backlash,
torsional_stiffness) hold every order at ~1e-3 arcsec per unit and are not named for a mesh line
they did not move. Limit: a signature's line is the largest over the cause's parameter columns, not
their fitted combination, so a cause's line is estimated, not computed; hence the lenient share.
"""
from __future__ import annotations

import html
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from geometry.artifacts import write_json_atomic, write_text_atomic
from pipeline import render
from pipeline.diagnosis.causes.base import torque_levels
from pipeline.diagnosis.orders import label_order, spectrum_of
from pipeline.diagnosis.significance import test_lines

UNEXPLAINED = "unexplained"
NO_SINGLE_CAUSE = "explained (no cause's line)"
NAMED_SHARE = 0.1        # a cause is named for a line when its estimated line is >= this share of its change
MAX_LABELS = 10          # labels per panel of residual_orders.png (the page's table has every line)


@dataclass(frozen=True)
class LineRow:
    """One significant residual line of one record, with what explains it."""
    record: str
    order: int
    torque_Nm: float          # |torque| of the record
    direction: int            # +1 forward, -1 backward
    before_arcsec: float      # single-sided amplitude in the residual before the extension
    after_arcsec: float | None   # ... after it (None: no extension)
    label: str                # cause(s), "partly <cause(s)>", "added by <cause(s)>", NO_SINGLE_CAUSE, UNEXPLAINED
    name: str                 # characteristic order it sits on (orders.label_order), or ''


def max_line_order(case) -> int:
    return 4 * case.cycloid.zp + 10


def _lines(rec, residual, top: int) -> dict:
    spec = spectrum_of(rec.output_angle_deg, residual)
    top = int(min(top, spec.order[-1]))
    return {int(round(l.order)): l for l in test_lines(spec, range(1, top + 1))}


def line_sizes(diag) -> dict[str, dict[int, float]]:
    """Per reported cause, its estimated line [arcsec] at each order of its signature, at the fitted
    size (module docstring); a cause without a fitted effect is absent (then never pruned)."""
    ext = diag.extension
    effect = (ext.effect_arcsec or {}) if ext is not None else {}
    groups = list(diag.groups)
    out = {}
    for s in diag.summaries:
        if s.cause not in effect or s.cause not in ext.causes:
            continue
        lines = np.asarray(s.line_arcsec, dtype=float)
        spread = []
        for g in dict.fromkeys(groups):
            m = [s.mean_shift_arcsec[r.name] for r, gr in zip(diag.records, groups)
                 if gr == g and r.name in s.mean_shift_arcsec]
            spread += list(np.asarray(m) - np.mean(m)) if m else []
        unit_rms = float(np.sqrt(np.sum(lines ** 2) / 2.0 + (np.mean(np.square(spread)) if spread else 0.0)))
        u = effect[s.cause] / unit_rms if unit_rms > 0 else 0.0
        out[s.cause] = {int(k): float(u * a) for k, a in zip(s.orders, lines)}
    return out


def _holders(diag, sizes, order: int, change: float) -> str:
    """'+'-joined reported causes holding `order` (module docstring), the largest estimated line first."""
    sig = {s.cause: set(s.orders) for s in diag.summaries}
    held = [c for c in diag.extension.causes if order in sig.get(c, ())]
    est = {c: sizes[c].get(order, 0.0) for c in held if c in sizes}
    cut = NAMED_SHARE * max([abs(change), *est.values()])
    return "+".join(sorted((c for c in held if est.get(c, cut) >= cut), key=lambda c: -est.get(c, np.inf)))


def attribute_lines(diag, case) -> list[LineRow]:
    """Every record's significant residual lines, labelled by cause (module docstring), by record then
    order. `diag` needs records, groups, residual_before/_after, summaries, extension, noise_arcsec."""
    ext, floor = diag.extension, diag.noise_arcsec
    after_all = diag.residual_after if ext is not None else None
    sizes = line_sizes(diag) if ext is not None else {}
    rows = []
    for k, rec in enumerate(diag.records):
        before = _lines(rec, diag.residual_before[k], max_line_order(case))
        after = _lines(rec, after_all[k], max_line_order(case)) if after_all is not None else {}
        real = lambda l: l is not None and l.significant and l.amplitude >= floor   # noqa: E731
        for order in sorted(o for o in before if real(before[o]) or real(after.get(o))):
            b, a = before[order], after.get(order)
            label = UNEXPLAINED
            if a is not None:
                causes = _holders(diag, sizes, order, b.amplitude - a.amplitude)
                if not real(a):
                    label = causes or NO_SINGLE_CAUSE
                elif causes and a.amplitude < 0.5 * b.amplitude:
                    label = f"partly {causes}"
                elif causes and not real(b) and a.amplitude > 2.0 * b.amplitude:
                    label = f"added by {causes}"
            rows.append(LineRow(rec.name, order, abs(float(rec.torque_Nm)), 1 if rec.direction > 0 else -1,
                                b.amplitude, None if a is None else a.amplitude, label,
                                label_order(case, order)))
    return rows


def write_report(diag, case, out_dir) -> Path:
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    write_json_atomic(out / "diagnosis.json", diag.to_json())
    write_json_atomic(out / "diagnosis_lines.json", diag.lines_json())
    rows = attribute_lines(diag, case)
    joined = _beside(_plot_time, diag, out / "residual_time.png")
    plot_orders(diag, case, out / "residual_orders.png", rows)
    write_text_atomic(out / "index.html", _page(diag, case, rows))
    joined()
    return out / "diagnosis.json"


def _beside(fn, *args):
    """Run fn(*args) in a forked process while the caller goes on (the two figures render on two
    cores; the residual-time figure was ~1 of the report's 3-5 s on the 8 real records; the same PNG
    bytes, each written atomically); returns the call that waits for it. Where fork is not
    available, or the child fails, fn runs here (so its error surfaces as it would have). Called
    after the diagnosis' worker pool is shut down: no other thread holds a lock across the fork."""
    import multiprocessing as mp
    if "fork" not in mp.get_all_start_methods():
        fn(*args)
        return lambda: None
    child = mp.get_context("fork").Process(target=fn, args=args, daemon=True)
    child.start()

    def join():
        child.join()
        if child.exitcode != 0:
            fn(*args)
    return join


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


_DIR_COLOUR = {1: "tab:blue", -1: "tab:orange"}
_LABEL_BAND = (0.56, 0.93, 0.025)       # label baselines: lowest, highest, step [axes fraction], above the data
_ROW = 0.075                             # a label this much higher costs one unit
_SLANT_PX = 12.0                         # a leader slanting this far sideways costs as much as a row up
_DATA_TOP = 0.52                         # the strongest line reaches this axes fraction (log scale)


def _level_of(torque, levels) -> float:
    return min(levels, key=lambda lv: abs(abs(torque) - lv))


def panel_labels(rows, level, levels, limit: int = MAX_LABELS) -> tuple[list[LineRow], int]:
    """One row per order at this torque level (forward and backward merged: the larger line wins),
    the `limit` strongest; and how many more lines the level holds."""
    best: dict[int, LineRow] = {}
    for r in rows:
        if _level_of(r.torque_Nm, levels) == level:
            cur = best.get(r.order)
            if cur is None or _strength(r) > _strength(cur):
                best[r.order] = r
    ranked = sorted(best.values(), key=lambda r: -_strength(r))
    return ranked[:limit], max(len(ranked) - limit, 0)


def _strength(r: LineRow) -> float:
    return max(r.before_arcsec, r.after_arcsec or 0.0)


def _label_colour(label: str) -> str:
    return ("tab:red" if label == UNEXPLAINED else "0.45" if label == NO_SINGLE_CAUSE
            else "tab:purple" if label.startswith("added") else "black")


def plot_orders(diag, case, path, rows=None) -> None:
    """residual_orders.png: one panel per |torque| level; forward and backward residual spectra after
    the extension in two colours over the spectra before it (grey), the noise floor dashed, each
    significant line labelled once by its cause or 'unexplained' (attribute_lines)."""
    rows = attribute_lines(diag, case) if rows is None else rows
    levels = torque_levels([abs(r.torque_Nm) for r in diag.records])
    ext, after = diag.extension, diag.residual_after if diag.extension is not None else None
    held = set(ext.held_out) if ext is not None else set()
    top = max_line_order(case)
    fig, axes = render.figure(len(levels), 1, figsize=(12, 2.9 * len(levels) + 1.0), squeeze=False, sharex=True)
    for ax, level in zip(axes[:, 0], levels):
        idx = [k for k, r in enumerate(diag.records) if _level_of(r.torque_Nm, levels) == level]
        amps = []
        for k in idx:
            rec = diag.records[k]
            tag, colour = ("fw" if rec.direction > 0 else "bw"), _DIR_COLOUR[1 if rec.direction > 0 else -1]
            sb = spectrum_of(rec.output_angle_deg, diag.residual_before[k])
            m = (sb.order > 0) & (sb.order <= top)
            amps.append(sb.amplitude[m])
            if after is None:
                ax.semilogy(sb.order[m], sb.amplitude[m], lw=0.8, color=colour, label=f"{tag} (no extension)")
                continue
            ax.semilogy(sb.order[m], sb.amplitude[m], lw=2.4, color="0.78", zorder=1,
                        label="before the extension (fw, bw)")
            sa = spectrum_of(rec.output_angle_deg, after[k])
            ax.semilogy(sa.order[m], sa.amplitude[m], lw=0.8, color=colour, zorder=2, label=f"{tag} after")
            amps.append(sa.amplitude[m])
        ax.axhline(diag.noise_arcsec, ls="--", lw=0.8, color="k", zorder=3,
                   label=f"noise floor {diag.noise_arcsec:.2g} arcsec")
        amp = np.concatenate(amps) if amps else np.array([diag.noise_arcsec])
        lo = max(min(float(np.percentile(amp, 5)), diag.noise_arcsec / 10.0), 1e-4)
        hi = max(float(amp.max()), diag.noise_arcsec)
        ax.set_ylim(lo, lo * (hi / lo) ** (1.0 / _DATA_TOP))
        ax.set_yticks([t for t in 10.0 ** np.arange(np.floor(np.log10(lo)), np.ceil(np.log10(hi)) + 1)
                       if lo <= t <= 3 * hi])    # no scale in the label band above the data
        ax.minorticks_off()
        ax.set_xlim(-1.5, top)      # the 1x line clear of the frame
        roles = " + ".join(sorted({"held out" if diag.records[k].name in held else "fitted" for k in idx}))
        dirs = "+".join(sorted({"fw" if diag.records[k].direction > 0 else "bw" for k in idx}, reverse=True))
        ax.set_title(f"|torque| {level:g} N.m ({dirs}), {roles if ext is not None else 'no extension'}",
                     fontsize=9, loc="left")
        ax.set_ylabel("amplitude [arcsec]")
        ax.grid(True, which="major", lw=0.3, alpha=0.5)
    handles, names = axes[0, 0].get_legend_handles_labels()
    uniq = dict(sorted(dict(zip(names, handles)).items(), key=lambda kv: (kv[0].startswith("noise"),
                                                                          "bw" in kv[0].split()[0])))
    fig.suptitle("Residual order spectra per torque level. Each significant line >= the noise floor is labelled by "
                 + ("the reported cause that removed it (black; 'partly': fell by more than half), 'added by' a cause "
                    "(purple) or 'unexplained' (red)" if ext is not None
                    else "'unexplained' (red): no cause reported, no extension"),
                 x=0.01, ha="left", y=0.995, fontsize=8.5)
    fig.legend(list(uniq.values()), list(uniq.keys()), loc="upper left", ncol=len(uniq), fontsize=7.5,
               bbox_to_anchor=(0.01, 0.995 - 0.25 / fig.get_figheight()), frameon=False)
    axes[-1, 0].set_xlabel("order [per output revolution]")
    fig.tight_layout(rect=(0, 0, 1, 1.0 - 0.5 / fig.get_figheight()))
    for ax, level in zip(axes[:, 0], levels):     # labels last: their layout is in display units
        shown, more = panel_labels(rows, level, levels)
        more += len(shown) - _place_labels(fig, ax, shown, ext is not None)
        if more:
            ax.set_title(f"+{more} weaker line{'s' if more > 1 else ''} in the page's table", fontsize=7,
                         loc="right", color="0.3")
    render.save_figure(fig, path)


def _label_text(r: LineRow, width: int = 32) -> str:
    """'78x cause', wrapped after 'partly' and at '+' to lines of about `width` characters."""
    words = f"{r.order}x {r.label}".replace("+", "+ ").split(" ")
    lines = [""]
    for word in words:
        if lines[-1] and len(lines[-1]) + len(word) + 1 > width:
            lines.append("")
        lines[-1] += (" " if lines[-1] and not lines[-1].endswith("+") else "") + word
    return "\n".join(lines)


def _place_labels(fig, ax, shown: list[LineRow], extended: bool) -> int:
    """Labels above the data, each with a thin leader to its peak. A label takes the free slot (height,
    sideways shift) of least cost: a leader that would run behind another label or cross another
    leader costs most, then a height a row up or a leader slanting _SLANT_PX sideways, then a label
    off centre. Labels never overlap: one that fits nowhere is left to the table. The greedy placement
    is tried strongest first and in both order directions; the layout that drops fewest labels at
    least cost is drawn. Call after the layout is final (display units). Returns the number placed."""
    from matplotlib.transforms import blended_transform_factory
    blend = blended_transform_factory(ax.transData, ax.transAxes)
    renderer = fig.canvas.get_renderer()
    items = []
    for r in shown:
        # the peak the reader looks at: the grey one for a removed line, the coloured one otherwise
        gone = extended and r.label != UNEXPLAINED and not r.label.startswith(("partly", "added"))
        peak = r.before_arcsec if (gone or r.after_arcsec is None) else r.after_arcsec
        colour = _label_colour(r.label)
        txt = ax.text(r.order, _LABEL_BAND[0], _label_text(r), transform=blend, ha="center", va="bottom",
                      fontsize=7, color=colour, zorder=5, linespacing=1.0,
                      fontweight="bold" if r.label == UNEXPLAINED else "normal",
                      bbox=dict(fc="white", ec="none", pad=0.5, alpha=0.9))
        bb = txt.get_window_extent(renderer)
        items.append((r, peak, colour, txt, bb.width + 8.0, bb.height + 4.0))   # air around each label
    orders = (list(range(len(items))), sorted(range(len(items)), key=lambda i: items[i][0].order),
              sorted(range(len(items)), key=lambda i: -items[i][0].order))
    layouts = [_layout(ax, items, seq) for seq in orders]
    slots = min(layouts, key=lambda lay: (sum(s is None for s in lay.values()),
                                          sum(s[0] for s in lay.values() if s is not None)))
    to_data = ax.transData.inverted()
    for i, (r, peak, colour, txt, _, _) in enumerate(items):
        if slots[i] is None:
            txt.remove()
            continue
        _, box, leader, y = slots[i]
        txt.set_x(to_data.transform(((box[0] + box[2]) / 2, 0.0))[0])
        txt.set_y(y)
        ax.annotate("", xy=(r.order, peak), xycoords="data", textcoords=blend, zorder=4,
                    xytext=(to_data.transform((leader[0][0], 0.0))[0], y),
                    arrowprops=dict(arrowstyle="-", lw=0.5, color=colour, shrinkA=0, shrinkB=1.5))
    return sum(s is not None for s in slots.values())


def _layout(ax, items, seq) -> dict:
    """Greedy slots for items in the sequence seq: index -> (cost, box, leader, y) or None."""
    frame = ax.get_window_extent()
    lo, hi, step = _LABEL_BAND
    placed, slots = [], {}   # placed: (label box (x0, y0, x1, y1), leader ((xa, ya), (xp, yp))), display units
    for i in seq:
        r, peak, _, _, w, h = items[i]
        xp, yp = (float(v) for v in ax.transData.transform((r.order, peak)))
        best = None
        for y in np.arange(lo, hi + 1e-9, step):
            y0 = float(ax.transAxes.transform((0.0, y))[1])
            if y0 + h > frame.y1 or (best is not None and (y - lo) / _ROW >= best[0]):
                break            # the cost only grows from here (pruned: the same slot as the full search)
            for s in _SHIFTS:
                xc = min(max(xp + s * w, frame.x0 + w / 2), frame.x1 - w / 2)
                box = (xc - w / 2, y0, xc + w / 2, y0 + h)
                leader = ((min(max(xp, box[0] + 4.0), box[2] - 4.0), y0), (xp, yp))
                cost = (y - lo) / _ROW + abs(leader[0][0] - xp) / _SLANT_PX + 0.3 * abs(xc - xp) / w
                if (best is not None and cost >= best[0]) or any(_overlap(box, b) for b, _ in placed):
                    continue     # no cheaper than the best even with nothing behind, or overlapping
                for b, l in placed:   # 100 per conflict; stop once no cheaper than the best (same slot)
                    cost += 100.0 * (_hits(leader, b) + _hits(l, box) + _crosses(leader, l))
                    if best is not None and cost >= best[0]:
                        break
                if best is None or cost < best[0]:
                    best = (cost, box, leader, y)
        slots[i] = best
        if best is not None:
            placed.append(best[1:3])
    return slots


_SHIFTS = tuple(float(s) for s in sorted(np.arange(-1.5, 1.51, 0.125), key=abs))   # label offsets [widths]


def _overlap(a, b) -> bool:
    return a[0] < b[2] and b[0] < a[2] and a[1] < b[3] and b[1] < a[3]


def _crosses(a, b) -> bool:
    """Do two leaders cross (strictly: a shared peak or end does not count)?"""
    (ax0, ay0), (ax1, ay1) = a
    (bx0, by0), (bx1, by1) = b
    if (max(ax0, ax1) < min(bx0, bx1) or max(bx0, bx1) < min(ax0, ax1) or max(ay0, ay1) < min(by0, by1)
            or max(by0, by1) < min(ay0, ay1)):
        return False         # apart: a crossing point would lie in both bounding boxes

    def side(p, q, r):
        v = float((q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0]))
        return (v > 0) - (v < 0)
    return side(*a, b[0]) * side(*a, b[1]) < 0 and side(*b, a[0]) * side(*b, a[1]) < 0


def _hits(segment, box) -> bool:
    """Does the segment run through the box's inside (Liang-Barsky clipping)?"""
    (x0, y0), (x1, y1) = segment
    if max(x0, x1) <= box[0] or min(x0, x1) >= box[2] or max(y0, y1) <= box[1] or min(y0, y1) >= box[3]:
        return False         # beside the box (what the clipping below finds too, in far fewer steps)
    dx, dy = x1 - x0, y1 - y0
    t0, t1 = 0.0, 1.0
    for p, q in ((-dx, x0 - box[0]), (dx, box[2] - x0), (-dy, y0 - box[1]), (dy, box[3] - y0)):
        if p == 0:
            if q <= 0:
                return False
            continue
        t = q / p
        if p < 0:
            t0 = max(t0, t)
        else:
            t1 = min(t1, t)
    return t1 - t0 > 1e-6


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


def _cell(r: LineRow) -> str:
    return f"{r.before_arcsec:.2f}" + ("" if r.after_arcsec is None else f" &rarr; {r.after_arcsec:.2f}")


def _lines_table(diag, rows: list[LineRow]) -> str:
    """One row per order: amplitude before -> after per torque level and direction, and its label
    (each distinct label with the conditions it holds at, when they differ)."""
    e = html.escape
    if not rows:
        return "<p>none: no line of any record is significant and above the noise floor</p>"
    levels = torque_levels([abs(r.torque_Nm) for r in diag.records])
    cols = sorted({(_level_of(r.torque_Nm, levels), 1 if r.direction > 0 else -1) for r in diag.records},
                  key=lambda c: (c[0], -c[1]))
    tag = lambda c: f"{c[0]:g} {'fw' if c[1] > 0 else 'bw'}"   # noqa: E731
    cells: dict[int, dict] = {}
    for r in rows:
        c = (_level_of(r.torque_Nm, levels), r.direction)
        cur = cells.setdefault(r.order, {}).get(c)
        if cur is None or _strength(r) > _strength(cur):   # two records at one condition: the larger line
            cells[r.order][c] = r
    body = ""
    for order in sorted(cells):
        got = cells[order]
        amp = "".join("<td>&ndash;</td>" if c not in got else f'<td style="white-space:nowrap">{_cell(got[c])}</td>'
                      for c in cols)
        where: dict[str, list] = {}
        for c in cols:
            if c in got:
                where.setdefault(got[c].label, []).append(tag(c))
        label = "; ".join(
            (f'<span style="color:#c00"><b>{e(lb)}</b></span>' if lb == UNEXPLAINED else e(lb))
            + ("" if len(where) == 1 else f" ({', '.join(w)})") for lb, w in where.items())
        name = next(iter(got.values())).name
        body += f"<tr><td>{order}x</td><td>{e(name) or '&ndash;'}</td>{amp}<td>{label}</td></tr>"
    head = "".join(f"<th>{tag(c)}</th>" for c in cols)
    return ("<table border=1><tr><th>order</th><th>characteristic order</th>" + head
            + f"<th>cause</th></tr>{body}</table>")


def _directions_table(diag) -> str:
    """The strongest lines split into their common and reversing parts (directions.py), before ->
    after the extension, per torque level; and the angle frames (frames.py)."""
    e = html.escape
    tab = diag.line_directions
    if not tab:
        return "<p>none: no encoder zero holds both directions at a torque</p>"
    after = {row["order"]: {lv["torque_Nm"]: lv for lv in row["levels"]} for row in (tab.get("after") or [])}

    def cell(lv, new, part):
        a = f"{lv[part]['amplitude_arcsec']:.2f}"
        return a + ("" if new is None else f" &rarr; {new[part]['amplitude_arcsec']:.2f}")
    body = ""
    for row in tab["before"]:
        for lv in row["levels"]:
            new = after.get(row["order"], {}).get(lv["torque_Nm"])
            body += (f"<tr><td>{row['order']}x</td><td>{e(row['label']) or '&ndash;'}</td><td>{lv['torque_Nm']:g}</td>"
                     f"<td>{cell(lv, new, 'common')}</td><td>{cell(lv, new, 'reversing')}</td>"
                     f"<td>{e(lv['reading'])}{'' if new is None else ' &rarr; ' + e(new['reading'])}</td></tr>")
    frames = "".join(f"<li>{e(f.group)}: {f.shift_deg:+.3f} &plusmn; {1.96 * f.sd_deg:.3f} deg from {e(f.reference)}, "
                     f"{f.mismatch_removed:.0%} of the phasor mismatch removed; "
                     f"{'reported' if f.reported else 'not reported'}</li>" for f in diag.angle_frames)
    return ("<table border=1><tr><th>order</th><th>characteristic order</th><th>|torque| N.m</th>"
            "<th>common to both directions</th><th>reversing with the motion</th><th>reading</th></tr>"
            f"{body}</table><p>Angle frames (the mechanism's lines of each encoder zero laid on the first):</p>"
            f"<ul>{frames or '<li>one encoder zero only</li>'}</ul>")


_DIRECTIONS_CAPTION = (
    "Amplitude [arcsec] before -> after the extension. Common: the same in both directions (a position-type "
    "error: a pin or hole off tangentially, a timing, a coaxiality, a reading; or a compliance under a load "
    "that keeps its sign). Reversing: opposite in the two directions (a clearance-type error: a pin off "
    "radially, a pin radius; or a compliance under the signed torque). A geometric error is there at zero "
    "torque, a compliance grows from zero.")


_ORDERS_CAPTION = (
    "One panel per torque level. Grey: the residual spectra before the extension; blue / orange: "
    "forward / backward after it; dashed: the records' noise floor. Each significant line (false alarm "
    "1e-3 per record and at least the noise floor) is labelled once per panel, forward and backward "
    "merged (the larger wins): black, the reported cause whose signature holds the order and that removed "
    "it (the leader points to the grey peak it removed), 'partly' when the line fell by more than half "
    "but stays; red, 'unexplained': no reported cause removes it; purple, 'added by': a line the "
    "extension put there; grey, 'explained (no cause's line)': removed, but by no single cause's line. "
    "At most 10 labels a panel, the strongest; the table below has every line, per record.")


def _page(diag, case, line_rows: list[LineRow]) -> str:
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
    lines = _lines_table(diag, line_rows)
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
<h2>Residual in orders</h2><figure><img src="residual_orders.png"
alt="residual order spectra per torque level, before and after, each significant line labelled by its cause or unexplained">
<figcaption>{e(_ORDERS_CAPTION)}</figcaption></figure>
<h2>Significant residual lines (false alarm 1e-3 per record, amplitude &ge; noise floor
{diag.noise_arcsec:.3g} arcsec)</h2>
<p>amplitude before &rarr; after the extension [arcsec] per |torque| [N.m] and direction; &ndash;: not a line
there</p>{lines}
<h2>Lines by direction of motion</h2><p>{e(_DIRECTIONS_CAPTION)}</p>{_directions_table(diag)}
<h2>Signature library (model, unit size)</h2><table border=1><tr><th>cause</th><th>orders</th><th>arcsec per unit</th></tr>{sig}</table>
</body></html>
"""
