"""The case report: one static HTML page over a case's build folder.

The page links the stage artifacts in place (relative paths), so it opens from disk in any browser
with no server, and it only reads: every figure and table comes from a stage that already wrote it.
A stage whose artifacts are missing is listed as "not built" instead of failing the report; a JSON
artifact whose `made_from` names another case fingerprint than the report's case is flagged as made
from another case (or an older version of it) rather than shown as if it were current.
An inline script marks the body with how many images loaded (data-images-ok="loaded/total"), which
the headless-browser test reads.
"""
from __future__ import annotations

import csv
import html
import json
import os
from dataclasses import dataclass
from pathlib import Path

from geometry.artifacts import InputError, write_text_atomic
from geometry.fingerprint import Provenance, short


@dataclass(frozen=True)
class Section:
    title: str
    folder: str            # stage folder under build/<case>/
    intro: str
    tables: tuple = ()     # file names shown as tables (csv, json, md)


SECTIONS = (
    Section("Geometry", "geometry",
            "Parametric CadQuery solids of the second stage, from the validated case file; "
            "profile with offset/equidistant modification.", ("geometry.json",)),
    Section("Meshes", "mesh",
            "Crankshaft tetrahedra from the CadQuery solid (pytetwild), made once and reused by the FE stage.",
            ()),
    Section("Finite elements", "fem",
            "scikit-fem: 2D cycloid-pin contact (condensed, exact non-penetration), 3D crankshaft on "
            "its bearings, needle (turning-arm) bearing; reduced to stiffness curves.",
            ("fem_summary.json",)),
    Section("Transmission error: load gradient x load form (paper 001)", "matrix",
            "Lumped torsional multibody model fed by the FE stiffness; paper 001's drive and loads.",
            ("te_std.csv", "comparison.md")),
    Section("Catalog tests: hysteresis, torsional rigidity, lost motion", "hysteresis",
            "Input locked, output torque swept to +-rated and back (catalog definitions).",
            ("hysteresis.json",)),
    Section("Original error of the second stage: four-bar model (paper 000)", "fourbar",
            "Four-bar linkage of crank eccentricities, disc crank-hole spacing and output bearing-hole "
            "spacing; rigid and elastic (FE compliance, project load sharing).", ("comparison.md",)),
    Section("Tolerance Monte Carlo", "tolerance",
            "All error sources drawn from their tolerance bands.", ("summary.json",)),
    Section("Diagnosis of measured data", "diagnosis",
            "Residual (measured - simulated) in time and orders, named causes, model extension and "
            "its gain; paper 001's no-load bench case as a worked example.",
            ("diagnosis.json", "paper001.json")),
)

IMAGE_SUFFIXES = (".png", ".svg", ".jpg")


def _table_from_csv(path: Path, max_rows: int = 40) -> str:
    with path.open() as fh:
        rows = [r for r in csv.reader(line for line in fh if not line.startswith("#"))]
    if not rows:
        return ""
    head, body = rows[0], rows[1:max_rows + 1]
    more = f"<p class='note'>{len(rows) - 1 - len(body)} more rows in {path.name}</p>" \
        if len(rows) - 1 > len(body) else ""
    return ("<table><tr>" + "".join(f"<th>{html.escape(h)}</th>" for h in head) + "</tr>"
            + "".join("<tr>" + "".join(f"<td>{html.escape(c)}</td>" for c in r) + "</tr>" for r in body)
            + "</table>" + more)


def _json_block(path: Path) -> str:
    """Scalars as a two-column table (numbers to 4 significant figures); nested values below it."""
    data = json.loads(path.read_text())
    if not isinstance(data, dict):
        return f"<pre>{html.escape(json.dumps(data, indent=1)[:20000])}</pre>"

    def short(v):
        if isinstance(v, list) and len(v) > 12:
            return f"[{len(v)} values]"
        if isinstance(v, dict):
            return {k: short(x) for k, x in v.items()}
        return v

    def fmt(v):
        return f"{v:.4g}" if isinstance(v, float) else str(v)
    scalars = {k: v for k, v in data.items() if not isinstance(v, (dict, list))}
    nested = {k: short(v) for k, v in data.items() if k not in scalars}
    out = ""
    if scalars:
        out += "<table>" + "".join(f"<tr><th>{html.escape(k)}</th><td>{html.escape(fmt(v))}</td></tr>"
                                   for k, v in scalars.items()) + "</table>"
    if nested:
        out += f"<pre>{html.escape(json.dumps(nested, indent=1))}</pre>"
    return out


def markdown_to_html(text: str) -> str:
    """Headings, paragraphs and pipe tables: enough for the comparison pages the stages write."""
    out, table = [], []

    def flush():
        if table:
            rows = [[c.strip() for c in r.strip().strip("|").split("|")] for r in table
                    if not set(r.replace("|", "").strip()) <= set("-: ")]
            out.append("<table><tr>" + "".join(f"<th>{html.escape(c)}</th>" for c in rows[0]) + "</tr>"
                       + "".join("<tr>" + "".join(f"<td>{html.escape(c)}</td>" for c in r) + "</tr>"
                                 for r in rows[1:]) + "</table>")
            table.clear()
    for line in text.splitlines():
        if line.lstrip().startswith("|"):
            table.append(line)
            continue
        flush()
        if line.startswith("#"):
            level = min(len(line) - len(line.lstrip("#")) + 2, 6)
            out.append(f"<h{level}>{html.escape(line.lstrip('#').strip())}</h{level}>")
        elif line.strip():
            out.append(f"<p>{html.escape(line)}</p>")
    flush()
    return "\n".join(out)


def _table(path: Path) -> str:
    if path.suffix == ".csv":
        return _table_from_csv(path)
    if path.suffix == ".json":
        return _json_block(path)
    if path.suffix == ".md":
        return markdown_to_html(path.read_text())
    return f"<pre>{html.escape(path.read_text())}</pre>"


STYLE = """body{font-family:sans-serif;max-width:1200px;margin:auto;padding:1em;color:#222}
img{max-width:100%;border:1px solid #ccc;margin:4px 0}
.figs{display:grid;grid-template-columns:repeat(auto-fill,minmax(520px,1fr));gap:8px}
table{border-collapse:collapse;margin:6px 0}td,th{border:1px solid #bbb;padding:2px 6px;font-size:90%}
th{background:#eee}pre{background:#f6f6f6;padding:6px;overflow:auto;max-height:420px;font-size:85%}
.missing{color:#a00}.note{color:#666;font-size:90%}"""

SCRIPT = """<script>
window.addEventListener('load', function () {
  var imgs = Array.prototype.slice.call(document.images);
  var ok = imgs.filter(function (i) { return i.complete && i.naturalWidth > 0; }).length;
  document.body.setAttribute('data-images-ok', ok + '/' + imgs.length);
});
</script>"""


def _stale_note(path: Path, case_fingerprint: str | None) -> str:
    """A warning when a JSON artifact says (geometry.fingerprint) it was made from another case
    fingerprint, or carries a made_from that does not check out."""
    if case_fingerprint is None:
        return ""
    try:
        made = json.loads(path.read_text()).get("made_from")
    except (ValueError, AttributeError, OSError):
        return ""
    if made is None:
        return ""
    try:
        prov = Provenance.from_json(made, path.name)
    except InputError as exc:
        return f"<p class='missing'>{html.escape(str(exc))}</p>"
    if prov.case_fingerprint == case_fingerprint:
        return ""
    return (f"<p class='missing'>{html.escape(path.name)} was made from case {html.escape(prov.case_name)} "
            f"(fingerprint {short(prov.case_fingerprint)}), not from this case as it is now (fingerprint "
            f"{short(case_fingerprint)}): rebuild it (make)</p>")


def build_report(case_dir: str | Path, case_name: str | None = None,
                 case_fingerprint: str | None = None) -> Path:
    """Write <case_dir>/report/index.html over the artifacts present; return its path. With the
    case's fingerprint, artifacts made from another version of the case are flagged."""
    case_dir = Path(case_dir)
    out_dir = case_dir / "report"
    name = case_name or case_dir.name
    parts = [f"<!doctype html><html><head><meta charset='utf-8'><title>RV transmission error: "
             f"{html.escape(name)}</title><style>{STYLE}</style>{SCRIPT}</head><body>",
             f"<h1>RV reducer transmission error report: {html.escape(name)}</h1>"]
    toc = []
    for sec in SECTIONS:
        folder = case_dir / sec.folder
        anchor = sec.folder
        toc.append(f"<li><a href='#{anchor}'>{html.escape(sec.title)}</a></li>")
        parts.append(f"<h2 id='{anchor}'>{html.escape(sec.title)}</h2><p>{html.escape(sec.intro)}</p>")
        if not folder.is_dir():
            parts.append(f"<p class='missing'>not built (no {sec.folder}/ folder)</p>")
            continue
        parts.extend(_stale_note(p, case_fingerprint) for p in sorted(folder.glob("*.json")))
        for t in sec.tables:
            if (folder / t).exists():
                parts.append(f"<h4>{html.escape(t)}</h4>" + _table(folder / t))
        images = sorted(p for p in folder.rglob("*") if p.suffix in IMAGE_SUFFIXES)
        if images:
            parts.append("<div class='figs'>" + "".join(
                f"<figure><img src='{html.escape(os.path.relpath(p, out_dir))}' alt='{html.escape(p.name)}'>"
                f"<figcaption class='note'>{html.escape(str(p.relative_to(case_dir)))}</figcaption></figure>"
                for p in images) + "</div>")
        sub_reports = sorted(p for p in folder.rglob("index.html"))
        for p in sub_reports:
            parts.append(f"<p><a href='{html.escape(os.path.relpath(p, out_dir))}'>detailed page: "
                         f"{html.escape(str(p.relative_to(case_dir)))}</a></p>")
    parts.insert(2, "<ul>" + "".join(toc) + "</ul>")
    parts.append("</body></html>")
    path = out_dir / "index.html"
    write_text_atomic(path, "\n".join(parts))
    return path
