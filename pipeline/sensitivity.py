"""Sensitivity of the catalog test to the case's sizes: which figure would have to be what.

The stiffness is predicted from stated geometry (DESIGN.md), and where no source gives a size the
case file says ASSUMED. When the predicted rigidity misses its reference, the budget names the
component; this names the SIZE: each variant is a copy of the case with one size changed (and the
sizes tied to it, e.g. the needle length with the disc width), run through the same stages as
`make` (geometry -> mesh -> fem -> hysteresis, nothing reused from the base build), and compared
with the unchanged case run the same way. Per variant:

    elasticity  e = ln(K1 / K0) / ln(x1 / x0)        (K the rigidity, x the size)
    needed size x_t = x0 (K_t / K0)^(1 / e)          for a target rigidity K_t (power law in x)

a local, first-order reading: x_t far from x0 is outside the range where one power law holds and
is reported as such. Nothing here feeds the model; it says what a teardown would have to find.
The crankshaft tet mesh is remade per variant (fTetWild is not run-to-run reproducible: up to
~0.5 % on the rigidity between remeshes, stated as the noise floor of a variant's change).
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass

from geometry.artifacts import InputError


class SensitivityError(InputError):
    """A variant that names no size of the case, an edit the case file cannot take, a bad --only
    or --band, or an unchanged case that fails to run."""


@dataclass(frozen=True)
class Edit:
    """One case-file value changed: `scale` multiplies it, `add` adds to it, `set` replaces it,
    `follow` adds the same change as the variant's first edit (a size tied to it)."""
    section: str
    key: str
    kind: str          # "scale" | "add" | "set" | "follow"
    amount: float = 0.0

    def apply(self, value: float) -> float:
        if self.kind == "scale":
            return value * self.amount
        if self.kind == "add":
            return value + self.amount
        return self.amount


@dataclass(frozen=True)
class Variant:
    """A named change of one size (`edits[0]`, the size the elasticity is taken against) and the
    sizes tied to it; `why` says what it probes."""
    name: str
    edits: tuple[Edit, ...]
    why: str
    continuous: bool = True    # False: a count changed by a step (a what-if, no elasticity)

    @property
    def size(self) -> Edit:
        return self.edits[0]


# The sizes that carry the budget (RV cases: carrier racking and crank bending ~ 60 %, bearings
# ~ 25 %, contacts ~ 10 %), each by a step small enough for one power law and large enough to stand
# above the remeshing noise (up to ~0.5 %: 957.9 vs 961.8 N m/arcmin for the RV-160N).
VARIANTS: tuple[Variant, ...] = (
    Variant("pillar_radius", (Edit("carrier", "pillar_radius_mm", "scale", 1.10),),
            "carrier racking: the pillars' bending between flange and end plate"),
    Variant("support_span", (Edit("crankshaft", "support_span_mm", "scale", 1.10),),
            "crank bending between its support bearings (and the carrier's plate spacing)"),
    Variant("eccentric_radius", (Edit("crankshaft", "eccentric_radius_mm", "scale", 0.90),
                                 Edit("disc", "crank_hole_radius_mm", "follow")),
            "crank section at the eccentrics; the disc's crank hole follows (same needles)"),
    Variant("disc_width", (Edit("cycloid", "width_mm", "scale", 1.10),
                           Edit("crankshaft", "needle_length_mm", "scale", 1.10),
                           Edit("housing", "pin_ring_length_mm", "scale", 1.10)),
            "tooth contact, needle and disc-body length (needles as long as the disc; the pin ring "
            "still spans the disc stack)"),
    Variant("needle_count", (Edit("crankshaft", "needle_count", "add", -4),),
            "turning-arm needle bearing: fewer needles share the load"),
    Variant("modification", (Edit("modification", "offset_mm", "scale", 1.5),
                             Edit("modification", "equidistant_mm", "scale", 1.5)),
            "profile modification 1.5 x: fewer teeth in contact at a load, more lost motion"),
    Variant("crank_count", (Edit("carrier", "crank_count", "set", 2),
                            Edit("carrier", "pillar_count", "set", 2)),
            "two cranks and two pillars instead of three (a what-if of the count)", continuous=False),
)
BY_NAME = {v.name: v for v in VARIANTS}
# Beyond a factor 2 on a size the one power law is an extrapolation, and a size that far off would
# be another reducer: the table says "not this size alone" instead of a number.
LOCAL_RANGE = 2.0

_SECTION = re.compile(r"^\s*\[([A-Za-z0-9_]+)\]")
_VALUE = r"^(\s*{key}\s*=\s*)([-+0-9.eE]+)(.*)$"


def _format(value: float, integer: bool) -> str:
    return str(int(round(value))) if integer else repr(round(float(value), 9))


def _locate(lines: list[str], section: str, key: str) -> tuple[int, re.Match]:
    """Index and value match of the numeric `key` line in `[section]` (one scan of the text)."""
    here, pattern = None, re.compile(_VALUE.format(key=re.escape(key)))
    for i, line in enumerate(lines):
        m = _SECTION.match(line)
        if m:
            here = m.group(1)
            continue
        m = pattern.match(line) if here == section else None
        if m:
            return i, m
    raise SensitivityError(f"case file: no numeric `{key}` in [{section}]; a sensitivity variant "
                           f"changes a size the case file states")


def _parsed(m: re.Match) -> tuple[float, str, bool]:
    raw = m.group(2)
    return float(raw), m.group(3), not any(c in raw for c in ".eE")


def case_value(text: str, section: str, key: str) -> tuple[float, str, bool]:
    """(value, its line's comment, integer?) of `key` in `[section]` of a case file's text."""
    return _parsed(_locate(text.splitlines(), section, key)[1])


def edited(text: str, variant: Variant, name: str) -> tuple[str, list[dict]]:
    """The case text with the variant's edits (and `name`); the list of {section, key, from, to}."""
    lines = text.splitlines()
    done, first_delta = [], None
    for e in variant.edits:
        i, m = _locate(lines, e.section, e.key)
        x0, _, integer = _parsed(m)
        if e.kind == "follow":
            if first_delta is None:
                raise SensitivityError(f"variant {variant.name}: a tied edit needs a first edit")
            x1 = x0 + first_delta
        else:
            x1 = e.apply(x0)
        if first_delta is None:
            first_delta = x1 - x0
        lines[i] = f"{m.group(1)}{_format(x1, integer)}{m.group(3)}  # sensitivity {variant.name}: was {m.group(2)}"
        done.append({"section": e.section, "key": e.key, "from": x0, "to": float(_format(x1, integer))})
    return renamed("\n".join(lines) + "\n", name), done


def renamed(text: str, name: str) -> str:
    """The case text under another `name` (each run builds into its own folder)."""
    out, n = re.subn(r'^name\s*=\s*"[^"]*"', f'name = "{name}"', text, count=1, flags=re.M)
    if n != 1:
        raise SensitivityError("case file: no `name = \"...\"` line to rename the variant")
    return out


def is_assumed(comment: str) -> bool:
    """The case file's own word on a size: its comment says ASSUMED (or nothing at all)."""
    return "ASSUMED" in comment or not comment.strip()


def elasticity(x0: float, x1: float, k0: float, k1: float) -> float | None:
    """d ln K / d ln |x| from two points (None when the size did not change or changed sign; a
    negative size, such as the profile modification's moved distance, scales by x1 / x0 > 0)."""
    if x0 == 0 or x1 / x0 <= 0 or x0 == x1 or k0 <= 0 or k1 <= 0:
        return None
    return math.log(k1 / k0) / math.log(x1 / x0)


def needed_size(x0: float, k0: float, e: float | None, target: float) -> float | None:
    """The size at which the power law K0 (x / x0)^e reaches `target` (None when e ~ 0)."""
    if e is None or abs(e) < 1e-3 or target <= 0 or k0 <= 0:
        return None
    return x0 * (target / k0) ** (1.0 / e)


def summarise(base: dict, runs: dict[str, dict], reference: float | None, band: float) -> dict:
    """Table rows from the base run and each variant's run ({'rigidity', 'lost_motion', 'budget',
    'edits', 'assumed'} or {'error'})."""
    k0 = base["rigidity"]
    targets = {}
    if reference and reference > 0:
        targets = {"band_edge": reference * (1 + band) if k0 > reference else reference * (1 - band),
                   "reference": reference}
    rows = {}
    for name, r in runs.items():
        v = BY_NAME[name]
        if "error" in r:
            rows[name] = {"why": v.why, "error": r["error"]}
            continue
        size = r["edits"][0]
        x0, x1, k1 = size["from"], size["to"], r["rigidity"]
        e = elasticity(x0, x1, k0, k1) if v.continuous else None
        row = {"why": v.why, "size": f"{size['section']}.{size['key']}", "assumed": r["assumed"],
               "edits": r["edits"], "rigidity_Nm_per_arcmin": k1, "rigidity_change": k1 / k0 - 1.0,
               "lost_motion_arcmin": r["lost_motion"], "elasticity": e,
               "budget": r.get("budget", {})}
        for label, kt in targets.items():
            xt = needed_size(x0, k0, e, kt)
            row[f"size_for_{label}"] = xt
            row[f"size_for_{label}_over_case"] = None if xt is None else xt / x0
        rows[name] = row
    return {"base": {"rigidity_Nm_per_arcmin": k0, "lost_motion_arcmin": base["lost_motion"],
                     "budget": base.get("budget", {})},
            "reference_Nm_per_arcmin": reference, "band": band, "targets_Nm_per_arcmin": targets,
            "variants": rows,
            "definitions": "elasticity d ln K / d ln x from the case and one variant; size_for_* the "
                           "power-law size that gives the target rigidity (a local reading: far "
                           "from the case's size it only says 'not this size alone'); band_edge is "
                           "the reference's band edge on the prediction's side; in the Markdown table a size beyond "
                           f"{LOCAL_RANGE:g} x or 1/{LOCAL_RANGE:g} of the case's reads 'not alone'"}


def markdown(table: dict, case_name: str) -> str:
    """The table as Markdown, one row per variant."""
    b = table["base"]
    ref = table["reference_Nm_per_arcmin"]
    t = table["targets_Nm_per_arcmin"]
    out = [f"# {case_name}: sensitivity of the catalog rigidity to the case's sizes", "",
           f"Case as stated: rigidity {b['rigidity_Nm_per_arcmin']:.1f} N m/arcmin, lost motion "
           f"{b['lost_motion_arcmin']:.3f} arcmin" + (f"; reference {ref:g} N m/arcmin, band edge "
                                                       f"{t['band_edge']:.0f}" if t else "") + ".", "",
           "| variant | size (case file says) | from -> to | rigidity | change | lost motion | "
           "elasticity | size for band edge | size for reference |",
           "|---|---|---|---|---|---|---|---|---|"]
    for name, r in table["variants"].items():
        if "error" in r:
            out.append(f"| {name} | | | failed: {r['error']} | | | | | |")
            continue
        s = r["edits"][0]

        def need(label, r=r):
            v, f = r.get(f"size_for_{label}"), r.get(f"size_for_{label}_over_case")
            if v is None:
                return "-"
            if not 1 / LOCAL_RANGE <= f <= LOCAL_RANGE:
                return f"not alone (beyond {LOCAL_RANGE:g} x)"
            return f"{v:.3g} ({f:.2f} x)"
        e = "-" if r["elasticity"] is None else f"{r['elasticity']:+.2f}"
        tied = "".join(f" with {ed['key']}" for ed in r["edits"][1:])
        out.append(f"| {name} | {r['size']}{tied} ({'ASSUMED' if r['assumed'] else 'sourced'}) | "
                   f"{s['from']:g} -> {s['to']:g} | {r['rigidity_Nm_per_arcmin']:.1f} | "
                   f"{100 * r['rigidity_change']:+.1f} % | {r['lost_motion_arcmin']:.3f} | {e} | "
                   f"{need('band_edge')} | {need('reference')} |")
    out += ["", table["definitions"] + ".", ""]
    return "\n".join(out)
