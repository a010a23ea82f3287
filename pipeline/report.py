"""The case report: one static HTML page over a case's build folder.

The page opens on the case's key figures beside their references (pipeline.report_summary), then one
section per stage: a sentence on what was computed, its tables rendered as tables (CSV, JSON and
markdown alike), and its pictures full width, each a link to the full-size PNG with a caption that
says what to look at. It links the stage artifacts in place (relative paths), so it opens from disk
in any browser with no server, and it only reads, except the pictures drawn from artifacts no stage
draws (the FE load-deflection curves of stiffness.json), which go to report/figures/.
A stage whose artifacts are missing is said so in neutral text instead of failing the report; a JSON
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
import re
from dataclasses import dataclass
from pathlib import Path

from geometry.artifacts import InputError, write_text_atomic
from geometry.fingerprint import Provenance, short
from pipeline.report_summary import key_figures, read_json, windup_at_rated_arcsec

E = html.escape


@dataclass(frozen=True)
class Section:
    title: str
    folder: str            # stage folder under build/<case>/
    intro: str
    tables: tuple = ()     # file names shown as tables (csv, json, md)
    missing: str = "not built yet: `make all CASE=<this case>` builds it"
    deep: bool = True      # pictures and pages from sub-folders too (False: the folder's own only)


SECTIONS = (
    Section("Geometry", "geometry",
            "Parametric CadQuery solids of the second stage, from the validated case file; profile with "
            "offset/equidistant modification. The backlash here is the rigid free play of the unloaded profile.",
            ("geometry.json",)),
    Section("Meshes", "mesh",
            "Crankshaft tetrahedra: prisms of one section triangulation (every circle of the CadQuery solid embedded), deterministic, made once and reused by the FE stage."),
    Section("Finite elements", "fem",
            "scikit-fem: 2D cycloid-pin contact (condensed, exact non-penetration), 3D crankshaft on its "
            "bearings, needle (turning-arm) bearing; reduced to the load-deflection curves of stiffness.json "
            "(drawn below) that the lumped model reads.", ("fem_summary.json",)),
    Section("Catalog tests: hysteresis loop, torsional rigidity, lost motion, compliance budget, load sharing",
            "hysteresis",
            "Input locked, output torque swept 0 -> +rated -> -rated -> +rated quasi-statically (catalog "
            "definitions). Backlash (loop width at zero torque) is free play only; lost motion (angle between "
            "+-3 % rated) adds the elastic wind-up over that band, so it is the larger of the two.",
            ("hysteresis.json",)),
    Section("Transmission error: load gradient x load form (paper 001)", "matrix",
            "Lumped torsional multibody model fed by the FE stiffness; paper 001's drive (1 s speed ramp "
            "to 7200 deg/s input) and loads (constant, 1 Hz square, 8 rad/s sine; 100..400 N m).",
            ("te_std.csv", "comparison.md")),
    Section("Original error of the second stage: four-bar model (paper 000)", "fourbar",
            "Four-bar linkage of crank eccentricities, disc crank-hole spacing and output bearing-hole "
            "spacing; rigid and elastic (FE compliance, project load sharing). Its elastic figure is the "
            "displacement of one crank pair's four-bar under its bearing loads, not the reducer's wind-up: "
            "the lumped model's wind-up (hysteresis section) carries every compliance in the path, so the two "
            "differ.", ("comparison.md",)),
    Section("As-built error signatures", "signatures",
            "Every as-built error source (geometry.params Errors) alone at unit size through the quasi-static "
            "model over one output revolution: its order lines, torque and direction dependence, and the "
            "sources a record cannot tell apart (signatures.json)."),
    Section("Tolerance Monte Carlo", "tolerance",
            "All error sources drawn from their tolerance bands.", ("summary.json",)),
    Section("Diagnosis of measured data", "diagnosis",
            "Residual (measured - simulated) in time and orders, named causes, model extension and its gain; "
            "paper 001's no-load bench case as a worked example.", ("diagnosis.json", "paper001.json"),
            missing="no bench records for this case (put records beside the case and run `diagnose`; "
                    "see README, Bringing your own bench data)"),
    Section("Compensation from the extended model", "compensate",
            "The diagnosis' extended model (every fitted cause) predicts the TE against output angle per torque "
            "and direction (compensation.csv, what a controller would subtract); checked on the bench records, "
            "fitted and held out alike, beside the black-box per-order compensation of Bilancia et al. 2025 "
            "(83-94 % TE RMS removed online on this bench).", ("compensation.json",),
            missing="not built: `compensate` runs on a diagnosis (`make all` runs both where the case has "
                    "bench records)"),
    Section("Operating map: friction, lubrication, efficiency, bearing life", "conditions",
            "Each condition of the bench's table (input speed, torque, oil temperature) through the model with "
            "friction at every contact (dynamics.losses: mixed-lubrication coefficient from the EHL film and the "
            "roughness, Palmgren bearing moments, seals): mean TE forward and backward and their gap, efficiency, "
            "input torque; the efficiency chart; ISO 281 bearing lives at rated torque and speed.",
            ("conditions.csv",),
            missing="not built: `conditions` runs where the case has a conditions table (`make all` runs it for "
                    "the RV-160N on ../shared/measured/conditions_25C.csv)"),
    Section("Operating map with the diagnosis' extension", "conditions_diagnosed",
            "The same table through the model extended by the diagnosis' fitted causes (`conditions --diagnosis`).",
            ("conditions.csv",),
            missing="not built: needs the diagnosis of bench records and a conditions table"),
    Section("Sensitivity of the rigidity to the case's sizes", "sensitivity",
            "Where the predicted rigidity misses its reference, which size would have to be what: each variant is "
            "the case with one size changed (and the sizes tied to it), run through geometry, mesh, FE and the "
            "catalog test like the case itself; elasticity d ln K / d ln x and the size that alone would reach "
            "the reference's band edge. A guide for a teardown, never a correction: nothing here feeds the model.",
            ("sensitivity.md",),
            missing="not built: `make sensitivity CASE=<this case>` (about 8 runs of geometry to hysteresis, "
                    "so not part of `make all`)", deep=False),
)

IMAGE_SUFFIXES = (".png", ".svg", ".jpg")

# picture -> (title, what to see); matched on the path below build/<case>/, then on the file name
CAPTIONS = {
    "assembly.png": ("Second stage assembly (CadQuery)", "disc, pins and crankshaft as built from the case file: "
                     "check that the parts fit and the crank count."),
    "mesh.png": ("FE meshes", "the graded 2D contact mesh and the crankshaft tetrahedra: elements shrink towards "
                 "the contact."),
    "contact_stress.png": ("Contact stress (2D FE)", "von Mises stress at the loaded tooth-pin contact: the peak "
                           "sits just below the surface, as Hertz predicts."),
    "crankshaft.png": ("Crankshaft on its bearings (3D FE)", "displacement under a unit load on one eccentric "
                       "(magnified): the shaft bends between its support bearings; the colour bar gives um per kN."),
    "load_deflection.png": ("FE load-deflection curves", "force against approach at each contact position along "
                            "the path of contact: the slope (tooth stiffness) changes with the pin phase and "
                            "grows slightly with load (Hertzian line contact); the bearings beside them."),
    "hysteresis.png": ("Catalog hysteresis loop", "torsion angle against torque in % of rated: the b/a chord gives "
                       "the torsional rigidity, the +-3 % band the lost motion (zoom on the right); the rising and "
                       "falling branches part only inside the clearance (frictionless contacts); black: the loop "
                       "with contact friction at rest (boundary), its width at zero torque marked in the zoom."),
    "gap_map.png": ("Operating map: gap and peak-to-peak against torque", "left: mean TE forward minus backward, "
                    "one colour per input speed, lines predicted (dotted frictionless), circles measured: the slope "
                    "is the wind-up, its offset at zero torque the free play; right: TE peak-to-peak per direction "
                    "(the bench's is dominated by the once-per-revolution reading error, absent from an ideal model)."),
    "efficiency.png": ("Efficiency against output speed (the catalog's chart)", "one colour per torque, one line "
                       "style per oil temperature: efficiency falls with speed (viscous losses grow) and rises with "
                       "torque and temperature; the star is the published figure at rated torque."),
    "compliance_budget.png": ("Compliance budget at rated torque", "each component's share of the output "
                              "torsional compliance: the longest bar is where stiffness is lost."),
    "load_sharing.png": ("Load sharing per pin and teeth in contact", "left: how many pins of each disc carry "
                         "load at rated torque and how unevenly; right: the teeth-in-contact count stepping over "
                         "one mesh cycle (the source of the zp x zc mesh ripple)."),
    "te_matrix.png": ("Transmission error of paper 001's 12 load cases", "top: TE against output angle after "
                      "the ramps (t >= 2 s), one panel per load form, one colour per torque: wind-up grows with "
                      "torque, the load swing rides on it; bottom: order spectra with the characteristic orders "
                      "and the load's own order marked (resolution 1 / revolutions analysed)."),
    "individual.png": ("Four-bar output error of each source alone", "output-angle error against the deviation "
                       "of one dimension, rigid and elastic: only the crank-to-crank eccentricity difference acts in "
                       "first order; the elastic panel is shifted by the wind-up every build shares; dotted: +-1 arcmin."),
    "crank_angle_scan.png": ("Exact closure against paper 000's quadratic", "rigid output error at +range deviation "
                             "over the crank angle (symmetric log scale): the two agree except near the dead centres, "
                             "where the free-rocker four-bar cannot close (gaps)."),
    "surface_eccentricity_crank_hole.png": ("Pair sweep: eccentricity x crank-hole spacing",
                                            "output error over both deviations: read the slope along each axis."),
    "surface_eccentricity_output_hole.png": ("Pair sweep: eccentricity x output bearing-hole spacing",
                                             "output error over both deviations: read the slope along each axis."),
    "surface_crank_hole_output_hole.png": ("Pair sweep: crank-hole x output bearing-hole spacing",
                                           "output error over both deviations: their mismatch, not their sign, counts."),
    "signatures.png": ("Signature atlas", "left: TE change per unit error at rated torque, forward, per source "
                       "(rows) and order per output revolution (columns): pin-ring lobes at m zc, carrier-side errors "
                       "at multiples of zp, the encoder reading at 1x; right: the main line's torque exponent and "
                       "how it changes backward."),
    "histogram.png": ("Tolerance Monte Carlo", "output error of the drawn builds, rigid, elastic and elastic less the "
                      "wind-up of the ideal build (shared by every build: stiffness, not accuracy); dashed: the limit."),
    "residual_time.png": ("Diagnosis residual per record", "measured - simulated against output travel, before "
                          "and after the extension: what the named causes remove (the once-per-revolution swing, the "
                          "torque-dependent offset) and what stays unexplained (the mesh-order ripple)."),
    "residual_orders.png": ("Diagnosis residual in orders", "one panel per torque level: the residual's order "
                            "spectrum after the extension, forward (blue) and backward (orange), over the spectrum "
                            "before it (grey); dashed: the records' noise floor. Each significant line is labelled by "
                            "the reported cause that removed it (black; 'partly' when it fell by more than half), "
                            "'added by' a cause (purple) when the extension put it there, or 'unexplained' (red)."),
}


def _picture_order(path: Path) -> tuple:
    """Captioned pictures in CAPTIONS order (the headline one first), then the rest by name."""
    names = list(CAPTIONS)
    return (names.index(path.name) if path.name in names else len(names), path.as_posix())


def _caption(rel: str) -> tuple[str, str]:
    name = rel.rsplit("/", 1)[-1]
    return CAPTIONS.get(rel, CAPTIONS.get(name, (name.rsplit(".", 1)[0].replace("_", " "), "")))


def _inline(text: str) -> str:
    """Escaped text with markdown's **bold**, *italic* and `code`."""
    t = E(text)
    t = re.sub(r"`([^`]+)`", r"<code>\1</code>", t)
    t = re.sub(r"\*\*([^*]+)\*\*", r"<b>\1</b>", t)
    return re.sub(r"(?<![\w*])\*([^*\s][^*]*)\*(?![\w*])", r"<i>\1</i>", t)


def _split_row(line: str) -> list[str]:
    """Cells of a pipe-table row; `\\|` and |x| inside a cell (absolute value bars) are kept."""
    body = line.strip()
    body = body[1:] if body.startswith("|") else body
    body = body[:-1] if body.endswith("|") and not body.endswith("\\|") else body
    return [c.strip().replace("\\|", "|") for c in re.split(r"(?<!\\)\|", body)]


def markdown_to_html(text: str) -> str:
    """Headings, paragraphs (wrapped lines joined), bullet lists, inline emphasis and pipe tables."""
    out: list[str] = []
    para: list[str] = []
    items: list[str] = []
    table: list[str] = []

    def flush():
        if para:
            out.append(f"<p>{_inline(' '.join(para))}</p>")
            para.clear()
        if items:
            out.append("<ul>" + "".join(f"<li>{_inline(i)}</li>" for i in items) + "</ul>")
            items.clear()
        if table:
            rows = [_split_row(r) for r in table if not set(r.replace("|", "").strip()) <= set("-: ")]
            width = max(len(r) for r in rows)
            rows = [r + [""] * (width - len(r)) for r in rows]
            out.append(_html_table(rows[0], rows[1:], raw=True))
            table.clear()
    for line in text.splitlines():
        s = line.strip()
        if s.startswith("|"):
            if para or items:
                flush()
            table.append(s)
            continue
        if table:
            flush()
        if not s:
            flush()
        elif s.startswith("#"):
            flush()
            level = min(len(s) - len(s.lstrip("#")) + 2, 6)
            out.append(f"<h{level}>{_inline(s.lstrip('#').strip())}</h{level}>")
        elif s.startswith(("- ", "* ")):
            if para:
                flush()
            items.append(s[2:])
        elif items and line.startswith("  "):      # continuation of a bullet
            items[-1] += " " + s
        else:
            if items:
                flush()
            para.append(s)
    flush()
    return "\n".join(out)


def _html_table(head: list[str], rows: list[list[str]], raw: bool = False) -> str:
    cell = _inline if raw else E
    return ("<div class='tw'><table><tr>" + "".join(f"<th>{cell(str(h))}</th>" for h in head) + "</tr>"
            + "".join("<tr>" + "".join(f"<td>{cell(str(c))}</td>" for c in r) + "</tr>" for r in rows)
            + "</table></div>")


def _table_from_csv(path: Path, max_rows: int = 40) -> str:
    with path.open() as fh:
        rows = [r for r in csv.reader(line for line in fh if not line.startswith("#"))]
    if not rows:
        return ""
    head, body = rows[0], rows[1:max_rows + 1]
    more = f"<p class='note'>{len(rows) - 1 - len(body)} more rows in {E(path.name)}</p>" \
        if len(rows) - 1 > len(body) else ""
    return _html_table(head, body) + more


def _fmt(v) -> str:
    if isinstance(v, float):
        return f"{v:.0f}" if 1e3 <= abs(v) < 1e7 else f"{v:.4g}"   # 83803, not 8.38e+04
    if isinstance(v, list):
        if all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in v):
            if len(v) <= 8:
                return ", ".join(_fmt(x) for x in v)
            return f"{len(v)} values, {_fmt(float(min(v)))} .. {_fmt(float(max(v)))}"
        if all(isinstance(x, list) for x in v):
            return f"{len(v)} x {len(v[0]) if v else 0} table"
        return ", ".join(_fmt(x) for x in v[:8]) + (" ..." if len(v) > 8 else "")
    return str(v)


def json_to_html(data) -> str:
    """A JSON artifact as tables: one row per (nested) key with its value; a list of records, or a
    mapping of names to flat records, as a table of its own with one column per field; made_from
    left out (shown as provenance)."""
    if not isinstance(data, dict):
        return f"<p>{E(_fmt(data))}</p>"
    rows, records = [], []

    def walk(d, prefix):
        for k, v in d.items():
            if k == "made_from":
                continue
            key = f"{prefix}{k}"
            if isinstance(v, dict) and len(v) > 1 and all(
                    isinstance(x, dict) and x and not any(isinstance(y, (dict, list)) for y in x.values())
                    for x in v.values()):
                records.append((key, [{"": name, **x} for name, x in v.items()]))   # name -> flat record
            elif isinstance(v, dict):
                walk(v, key + " / ")
            elif isinstance(v, list) and v and all(isinstance(x, dict) for x in v):
                records.append((key, v))
            else:
                rows.append([key, _fmt(v)])
    walk(data, "")
    out = _html_table(["key", "value"], rows) if rows else ""
    for key, recs in records:
        cols = list(dict.fromkeys(k for r in recs for k in r if k != "made_from"))
        out += f"<h5>{E(key)}</h5>" + _html_table(cols, [[_fmt(r.get(c, "")) for c in cols] for r in recs])
    return out


def _table(path: Path) -> str:
    if path.suffix == ".csv":
        return _table_from_csv(path)
    if path.suffix == ".json":
        return json_to_html(read_json(path))
    if path.suffix == ".md":
        return markdown_to_html(path.read_text())
    return f"<pre>{E(path.read_text())}</pre>"


STYLE = """body{font-family:sans-serif;max-width:1280px;margin:auto;padding:1em;color:#222;line-height:1.35}
figure{margin:14px 0}img{max-width:100%;height:auto;border:1px solid #ccc}
figcaption{font-size:92%;color:#333;margin-top:3px}.path{color:#888;font-size:85%}
.tw{overflow-x:auto;max-width:100%}table{border-collapse:collapse;margin:6px 0}
td,th{border:1px solid #bbb;padding:2px 6px;font-size:90%;vertical-align:top;overflow-wrap:break-word}
th{background:#eee;text-align:left}table.key{table-layout:fixed;width:100%}
table.key td,table.key th{font-size:95%;padding:3px 8px}table.key td.v{font-weight:bold}.why{color:#555;font-size:88%}
pre{background:#f6f6f6;padding:6px;overflow:auto;max-height:420px;font-size:85%;white-space:pre-wrap}
code{background:#f3f3f3;padding:0 2px}.missing{color:#a00}.absent{color:#666;font-style:italic}
.note{color:#666;font-size:90%}nav ul{columns:2;font-size:92%}"""

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
        return f"<p class='missing'>{E(str(exc))}</p>"
    if prov.case_fingerprint == case_fingerprint:
        return ""
    return (f"<p class='missing'>{E(path.name)} was made from case {E(prov.case_name)} "
            f"(fingerprint {short(prov.case_fingerprint)}), not from this case as it is now (fingerprint "
            f"{short(case_fingerprint)}): rebuild it (make)</p>")


def _sensitivity_code_note(path: Path) -> str:
    """The sensitivity table is not a `make all` prerequisite (about 8 pipeline runs): say so when
    the stages' code has changed since it was made."""
    from pipeline.cmd_sensitivity import code_fingerprint
    try:
        made = json.loads(path.read_text()).get("code_fingerprint")
    except (ValueError, AttributeError, OSError):
        return ""
    if made == code_fingerprint():
        return ""
    return ("<p class='missing'>this table was made by other code than the stages have now: rerun "
            "<code>make sensitivity CASE=&lt;this case&gt;</code></p>")


def _figure(path: Path, case_dir: Path, out_dir: Path) -> str:
    rel = os.path.relpath(path, out_dir)
    where = path.relative_to(case_dir).as_posix()
    title, what = _caption(where)
    return (f"<figure><a href='{E(rel)}'><img src='{E(rel)}' alt='{E(title)}'></a>"
            f"<figcaption><b>{E(title)}.</b> {E(what)} <span class='path'>({E(where)}; click for full size)"
            f"</span></figcaption></figure>")


def _derived_figures(case_dir: Path, out_dir: Path, name: str) -> dict[str, list[Path]]:
    """Pictures of artifacts no stage draws, by section folder: stiffness.json's load-deflection."""
    made: dict[str, list[Path]] = {}
    stiff = read_json(case_dir / "fem" / "stiffness.json")
    if isinstance(stiff, dict) and isinstance(stiff.get("pin_contact"), dict):
        from pipeline.figures import load_deflection
        path = out_dir / "figures" / "load_deflection.png"
        path.parent.mkdir(parents=True, exist_ok=True)
        load_deflection(path, stiff, title=f"{name}: FE load-deflection curves (stiffness.json)")
        made["fem"] = [path]
    return made


def _summary(case_dir: Path, rated_Nm, ratio) -> str:
    rows = key_figures(case_dir, rated_Nm, ratio)
    body = "".join(
        f"<tr><th>{E(r.quantity)}</th><td class='v'>{E(r.value)}</td><td>{E(r.reference)}</td>"
        f"<td class='why'>{E(r.note)} <span class='path'>{E(r.where)}</span></td></tr>" for r in rows)
    return ("<h2 id='summary'>Key figures beside their references</h2><div class='tw'><table class='key'>"
            "<colgroup><col style='width:24%'><col style='width:24%'><col style='width:22%'><col style='width:30%'>"
            "</colgroup><tr><th>quantity</th><th>this case</th><th>reference</th><th>why it differs / source</th></tr>"
            f"{body}</table></div>")


def _budget_table(h: dict | None) -> str:
    """hysteresis.json's compliance budget, largest share first, with each part's equivalent
    stiffness (tangent rigidity / share: that part alone would give this rigidity)."""
    budget, rig = (h or {}).get("compliance_budget"), (h or {}).get("tangent_rigidity_at_rated_Nm_per_arcmin")
    if not isinstance(budget, dict) or not budget:
        return ""
    rows = [[k, f"{100 * v:.1f}", f"{rig / v:.0f}" if rig and v > 0 else "-"]
            for k, v in sorted(budget.items(), key=lambda kv: -kv[1])]
    return ("<h4>Compliance budget at rated torque</h4>"
            + _html_table(["component", "share of output compliance [%]", "equivalent rigidity [N m/arcmin]"], rows))


def _windup_note(case_dir: Path) -> str:
    """The lumped model's wind-up at rated torque, beside the four-bar's figures."""
    w = windup_at_rated_arcsec(case_dir)
    if w is None:
        return ""
    return (f"<p class='note'>Lumped model (hysteresis.csv): output wind-up at rated torque, input locked = "
            f"{w:.1f} arcsec (half the free play included). The four-bar elastic error above is another quantity: "
            "one crank pair's linkage under its bearing loads, not the whole compliance path.</p>")


def build_report(case_dir: str | Path, case_name: str | None = None, case_fingerprint: str | None = None,
                 rated_torque_Nm: float | None = None, ratio: float | None = None) -> Path:
    """Write <case_dir>/report/index.html over the artifacts present; return its path. With the
    case's fingerprint, artifacts made from another version of the case are flagged; rated torque
    and ratio pick the catalog and paper references of the summary."""
    case_dir = Path(case_dir)
    out_dir = case_dir / "report"
    name = case_name or case_dir.name
    derived = _derived_figures(case_dir, out_dir, name)
    parts = [f"<!doctype html><html><head><meta charset='utf-8'><title>RV transmission error: "
             f"{E(name)}</title><style>{STYLE}</style>{SCRIPT}</head><body>",
             f"<h1>RV reducer transmission error report: {E(name)}</h1>",
             _summary(case_dir, rated_torque_Nm, ratio)]
    toc = []
    for sec in SECTIONS:
        folder = case_dir / sec.folder
        toc.append(f"<li><a href='#{sec.folder}'>{E(sec.title)}</a></li>")
        parts.append(f"<h2 id='{sec.folder}'>{E(sec.title)}</h2><p>{_inline(sec.intro)}</p>")
        if not folder.is_dir():
            parts.append(f"<p class='absent'>{_inline(sec.missing)}</p>")
            continue
        parts.extend(_stale_note(p, case_fingerprint) for p in sorted(folder.glob("*.json")))
        for t in sec.tables:
            if (folder / t).exists():
                parts.append(f"<h4>{E(t)}</h4>" + _table(folder / t))
        if sec.folder == "hysteresis":
            parts.append(_budget_table(read_json(folder / "hysteresis.json")))
        if sec.folder == "fourbar":
            parts.append(_windup_note(case_dir))
        if sec.folder == "sensitivity":
            parts.append(_sensitivity_code_note(folder / "sensitivity.json"))
        walk = folder.rglob if sec.deep else folder.glob
        images = derived.get(sec.folder, []) + sorted((p for p in walk("*") if p.suffix in IMAGE_SUFFIXES),
                                                      key=_picture_order)
        parts.extend(_figure(p, case_dir, out_dir) for p in images)
        for p in sorted(walk("index.html")):
            parts.append(f"<p><a href='{E(os.path.relpath(p, out_dir))}'>detailed page: "
                         f"{E(p.relative_to(case_dir).as_posix())}</a></p>")
    parts.insert(3, "<nav><ul><li><a href='#summary'>Key figures</a></li>" + "".join(toc) + "</ul></nav>")
    parts.append("</body></html>")
    path = out_dir / "index.html"
    write_text_atomic(path, "\n".join(parts))
    return path
