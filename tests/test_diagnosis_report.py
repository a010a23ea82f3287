"""The diagnosis report's line attribution (report.attribute_lines) and its pictures, on synthetic
residuals with chosen lines: what the extension removed is labelled by its cause, what it left is
'unexplained', what it removed though no reported cause's signature holds the order is
'explained (no cause's line)' (report.NO_SINGLE_CAUSE), a line the extension put there is 'added by'
its cause, a reported cause that did not move a line is not named for it; residual_orders.png has a
panel per torque level and its labels never overlap."""
import os
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
import pytest

from dynamics.records import BenchRecord
from geometry.params import load_case
from pipeline import render
from pipeline.diagnosis import report
from pipeline.diagnosis.diagnose import Diagnosis
from pipeline.diagnosis.extension import Extension
from pipeline.diagnosis.signatures import SignatureSummary

CASE = load_case(Path(__file__).parents[1] / "cases" / "rv40e-81.toml")
N = 2048                   # samples over one output revolution
NOISE = 0.3                # the records' noise floor given to the diagnosis [arcsec]
# order -> (amplitude before, amplitude after) [arcsec], the same in every record
LINES = {1: (6.0, 0.0),     # removed; output_coaxiality's signature holds 1x
         7: (1.5, 0.0),     # removed; only pin_ring_pattern's signature holds 7x, and it is not reported
         39: (2.0, 2.0),    # left as it was
         80: (3.0, 1.0),    # down by two thirds but still there; housing_stiffness_pattern's 80x
         120: (0.0, 1.0),   # no line before, one after: housing_stiffness_pattern's 120x overshoots
         20: (0.2, 0.2)}    # significant over the seeded noise (0.01) but below the noise floor: no row


def _record(torque, direction, k):
    theta = np.linspace(0.0, 360.0, N, endpoint=False) * direction
    t = np.arange(N) * 1e-3
    return BenchRecord(f"rec{k}_{torque:g}Nm_{'fw' if direction > 0 else 'bw'}.csv", t, theta * 81.0, theta,
                       np.full(N, float(torque) * direction))


def _residual(rec, which, rng):
    th = np.deg2rad(rec.output_angle_deg)
    x = sum(amp[which] * np.cos(k * th + 0.3 * k) for k, amp in LINES.items())
    return x + rng.normal(0.0, 0.01, th.size)


def _diag(extended=True):
    rng = np.random.default_rng(7)
    recs = tuple(_record(t, d, k) for k, (t, d) in enumerate([(0, 1), (0, -1), (300, 1), (300, -1)]))
    before = tuple(_residual(r, 0, rng) for r in recs)
    after = tuple(_residual(r, 1, rng) for r in recs) if extended else None
    # backlash: reported, its signature holds 1x and 80x, but at ~1e-3 arcsec per unit beside a mean shift
    # of 10 arcsec per unit between the directions: it moved neither line and must not be named
    shift = {r.name: 5.0 * r.direction for r in recs}
    summaries = (SignatureSummary("output_coaxiality", (1, 2), (1.0, 0.1), {}, {}),
                 SignatureSummary("pin_ring_pattern", (7, 39), (1.0, 0.5), {}, {}),
                 SignatureSummary("housing_stiffness_pattern", (78, 80, 120), (1.0, 0.4, 0.5), {}, {}),
                 SignatureSummary("backlash", (1, 80), (1e-3, 1e-3), shift, {}))
    ext = None
    if extended:
        ext = Extension(("output_coaxiality", "backlash", "housing_stiffness_pattern"), {"coaxiality_um": 3.0},
                        1.0, 4.0, 0.75, 0.7, tuple(r.name for r in recs[:2]), tuple(r.name for r in recs[2:]),
                        effect_arcsec={"output_coaxiality": 4.2, "backlash": 2.0, "housing_stiffness_pattern": 0.7})
    return Diagnosis("output_coaxiality" if extended else None, (), 4.0, 12.0, ext, recs, ("z1", "z1", "z2", "z2"),
                     before, before, before, after, tuple(() for _ in recs), summaries, ("a note",), NOISE)


def _by_order(rows):
    out = {}
    for r in rows:
        out.setdefault(r.order, set()).add(r.label)
    return out


def test_each_line_is_labelled_by_the_cause_that_removed_it_or_unexplained():
    rows = report.attribute_lines(_diag(), CASE)
    assert len(rows) == 5 * 4            # five real lines in each of the four records
    got = _by_order(rows)
    assert got == {1: {"output_coaxiality"}, 7: {report.NO_SINGLE_CAUSE}, 39: {report.UNEXPLAINED},
                   80: {"partly housing_stiffness_pattern"}, 120: {"added by housing_stiffness_pattern"}}
    one = next(r for r in rows if r.order == 1 and r.torque_Nm == 300 and r.direction == -1)
    assert one.before_arcsec == pytest.approx(6.0, rel=0.02) and one.after_arcsec < NOISE
    assert "carrier" in one.name and next(r for r in rows if r.order == 39).name.startswith("zc=39")


def test_without_an_extension_every_line_is_unexplained():
    rows = report.attribute_lines(_diag(extended=False), CASE)
    assert {r.order for r in rows} == {1, 7, 39, 80}     # 120x is a line only after an extension
    assert {r.label for r in rows} == {report.UNEXPLAINED} and all(r.after_arcsec is None for r in rows)


def test_write_report_draws_both_pictures_and_the_line_table(tmp_path):
    report.write_report(_diag(), CASE, tmp_path)
    for png in ("residual_time.png", "residual_orders.png"):
        assert (tmp_path / png).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and (tmp_path / png).stat().st_size > 10000
    page = (tmp_path / "index.html").read_text()
    table = page[page.index("Significant residual lines"):page.index("Signature library")]
    assert "<th>300 bw</th>" in table and "partly housing_stiffness_pattern" in table
    assert "<td>80x</td>" in table and "6.00 &rarr; 0.00" in table and table.count("<tr>") == 1 + 5
    assert "held out" in page and "<figcaption>" in page


def test_the_orders_picture_has_a_panel_per_torque_and_one_label_per_line(monkeypatch):
    figs = []
    monkeypatch.setattr(render, "save_figure", lambda fig, path: figs.append(fig))
    report.plot_orders(_diag(), CASE, "unused.png")
    axes = [ax for ax in figs[0].axes if ax.get_title(loc="left")]
    assert [ax.get_title(loc="left") for ax in axes] == ["|torque| 0 N.m (fw+bw), fitted",
                                                          "|torque| 300 N.m (fw+bw), held out"]
    for ax in axes:
        labels = {t.get_text().replace("\n", " "): t.get_color() for t in ax.texts if "x " in t.get_text()}
        assert labels == {"1x output_coaxiality": "black", f"7x {report.NO_SINGLE_CAUSE}": "0.45",
                          "39x unexplained": "tab:red", "80x partly housing_stiffness_pattern": "black",
                          "120x added by housing_stiffness_pattern": "tab:purple"}
        assert ax.get_yscale() == "log" and ax.get_xlim()[1] == 4 * CASE.cycloid.zp + 10
    plt.close(figs[0])


def test_crowded_labels_do_not_overlap_and_the_rest_is_left_to_the_table():
    fig, ax = render.figure(1, 1, figsize=(12, 3))
    ax.set_xlim(0, 170)
    ax.set_yscale("log")
    ax.set_ylim(0.01, 100)
    rows = [report.LineRow("r", k, 0.0, 1, 1.0 + k / 10, 0.0, "housing_stiffness_pattern", "")
            for k in range(40, 70)]
    n = report._place_labels(fig, ax, rows, extended=True)
    r = fig.canvas.get_renderer()
    boxes = [t.get_window_extent(r) for t in ax.texts if t.get_text()]   # not the leaders
    assert n == len(boxes) and 8 <= n < len(rows)   # what fits nowhere is dropped, never overlapped
    assert not any(a.overlaps(b) for i, a in enumerate(boxes) for b in boxes[i + 1:])
    plt.close(fig)


def test_a_figure_drawn_beside_lands_and_a_failing_child_is_redone_here(tmp_path):
    """report._beside: the forked figure's file exists once joined; where the child fails the call is
    repeated in-process (its error would surface here)."""
    from pipeline.diagnosis import report
    calls = []

    def write(path):
        calls.append(path)
        Path(path).write_text("drawn")
    report._beside(write, tmp_path / "a.txt")()
    assert (tmp_path / "a.txt").read_text() == "drawn"

    def fails_in_child(path, parent=os.getpid()):
        if os.getpid() != parent:
            raise RuntimeError("child")
        Path(path).write_text("here")
    report._beside(fails_in_child, tmp_path / "b.txt")()
    assert (tmp_path / "b.txt").read_text() == "here"


def test_the_label_layouts_quick_rejects_agree_with_the_full_tests():
    """report._hits / _crosses skip the clipping / orientation tests where the bounding boxes are apart:
    the same answers as the full tests on random segments, boxes and leaders, edges touching included
    (coordinates on a coarse grid so that touching and shared ends occur)."""
    def clip(segment, box):                # the t-interval inside the open box, axis by axis
        (x0, y0), (x1, y1) = segment
        lo, hi = 0.0, 1.0
        for a, b, low, high in ((x0, x1, box[0], box[2]), (y0, y1, box[1], box[3])):
            if a == b:
                lo, hi = (lo, hi) if low < a < high else (1.0, 0.0)
            else:
                ta, tb = sorted(((low - a) / (b - a), (high - a) / (b - a)))
                lo, hi = max(lo, ta), min(hi, tb)
        return hi - lo > 1e-6

    def side(p, q, r):
        v = (q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0])
        return (v > 0) - (v < 0)
    rng = np.random.default_rng(3)
    pt = lambda: tuple(float(v) for v in rng.integers(0, 9, 2))   # noqa: E731
    hits = crosses = 0
    for _ in range(4000):
        a, b = (pt(), pt()), (pt(), pt())
        x, y = sorted(rng.integers(0, 9, 2)), sorted(rng.integers(0, 9, 2))
        box = (float(x[0]), float(y[0]), float(x[1]) + 1.0, float(y[1]) + 1.0)
        want = clip(a, box)
        assert report._hits(a, box) == want
        full = side(*a, b[0]) * side(*a, b[1]) < 0 and side(*b, a[0]) * side(*b, a[1]) < 0
        assert report._crosses(a, b) == full
        hits, crosses = hits + want, crosses + full
    assert 400 < hits < 3600 and 100 < crosses < 3900      # both answers well represented
