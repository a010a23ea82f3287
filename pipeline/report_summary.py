"""The report's first screen: key figures of a case beside their references, read from its artifacts.

Nothing here is a result: every "this case" figure is read from a stage artifact under
build/<case>/ (a missing artifact shows "not built"), and every reference is a published figure
with its source, or a figure computed from this case's own bench records (the diagnosis fit).
References are matched by what identifies the catalog size in the case file (rated torque, ratio):
a case of another size simply shows no catalog reference.
"""
from __future__ import annotations

import csv
import json
from dataclasses import dataclass
from pathlib import Path

from dynamics.conditions import torque_flange_range_text
from dynamics.loads import FORMS
from dynamics.matrix import paper001_sigma_arcsec

LOST_MOTION_CATALOG_ARCMIN = 1.0     # Nabtesco RV-E / RV-N catalogs: backlash and lost motion <= 1 arcmin
# Nabtesco RV-E catalog, RV-40E: rated torque 412 N m, torsional rigidity 108 N m/arcmin
CATALOG_RIGIDITY = {412.0: ("RV-40E", 108.0)}
PAPER_001_RATIO = 81                 # paper 001's RV-40E (i = 81), rated torque 412 N m


@dataclass(frozen=True)
class Row:
    quantity: str
    value: str            # this case, read from an artifact ("not built" when missing)
    reference: str        # published figure with its source, or "-"
    where: str            # the artifact the value comes from
    note: str = ""        # why two figures that look alike differ


def read_json(path: Path) -> dict | None:
    try:
        return json.loads(path.read_text())
    except (OSError, ValueError):
        return None


def read_sigma(path: Path) -> dict | None:
    """te_std.csv -> {(torque, form): sigma}, the load forms (by name) in the file's column order."""
    try:
        with path.open() as fh:
            rows = list(csv.DictReader(line for line in fh if not line.startswith("#")))
    except OSError:
        return None
    return {(float(r["torque_Nm"]), f): float(r[f]) for r in rows for f in r if f in FORMS}


def _f(v, fmt=".3g", unit="", missing="not built") -> str:
    return missing if v is None else (f"{v:{fmt}}" + (f" {unit}" if unit else ""))


def _get(d: dict | None, *keys):
    for k in keys:
        if not isinstance(d, dict) or k not in d:
            return None
        d = d[k]
    return d


def _bench_rigidity(diag: dict | None, rigidity: float | None) -> str | None:
    """The rigidity the case's own bench records imply: the diagnosis' torsional_stiffness cause
    fits a factor on the compliance of one located component (the largest share of the budget) and
    reports the model's tangent rigidity at rated torque before and after."""
    ext = _get(diag, "extension") or {}
    rig = _get(ext, "parameters", "rigidity_at_rated_Nm_per_arcmin")
    if "torsional_stiffness" not in ext.get("causes", []) or not isinstance(rig, dict) or not rig.get("extended"):
        return None
    where = _get(ext, "parameters", "located_component") or "?"
    f = _get(ext, "parameters", "compliance_factor")
    ci = _get(ext, "parameters", "compliance_factor_ci95")
    band = f" [{ci[0]:.2f}, {ci[1]:.2f}]" if isinstance(ci, list) and len(ci) == 2 else ""
    fx = f"{f:.2f}{band}" if isinstance(f, (int, float)) else "?"
    added = _get(ext, "parameters", "added_series_compliance_arcmin_per_kNm")
    spring = (f", i.e. a series spring of {1e3 / added:.0f} N m/arcmin wherever it sits (in the bench's chain too: "
              f"{torque_flange_range_text()})") if isinstance(added, (int, float)) and added > 0 else ""
    return (f"real bench (this case's records, diagnosis) ~{rig['extended']:.0f} N m/arcmin tangent at "
            f"rated (model {rig.get('model', float('nan')):.0f}): {where} compliance x {fx}{spring}")


def key_figures(case_dir: Path, rated_Nm: float | None, ratio: float | None) -> list[Row]:
    g = read_json(case_dir / "geometry" / "geometry.json")
    h = read_json(case_dir / "hysteresis" / "hysteresis.json")
    ls = read_json(case_dir / "hysteresis" / "load_sharing.json")
    sig = read_sigma(case_dir / "matrix" / "te_std.csv")
    tol = read_json(case_dir / "tolerance" / "summary.json")
    diag = read_json(case_dir / "diagnosis" / "diagnosis.json")
    p001 = read_json(case_dir / "diagnosis" / "paper001.json")
    rig = _get(h, "torsional_rigidity_Nm_per_arcmin")
    cat = CATALOG_RIGIDITY.get(float(rated_Nm)) if rated_Nm else None
    refs = [f"catalog {cat[0]}: {cat[1]:g} N m/arcmin"] if cat else []
    bench = _bench_rigidity(diag, rig)
    refs += [bench] if bench else []
    rows = [
        Row("torsional rigidity b/a (50-100 % rated)", _f(rig, ".0f", "N m/arcmin"), "; ".join(refs) or "-",
            "hysteresis/hysteresis.json",
            "stiffer than the reference: a compliance of the real path that the model lacks or underrates reads "
            "as excess stiffness (the compliance budget shows what the model's path holds)"
            if rig and ((cat and rig > 1.2 * cat[1]) or bench) else ""),
        Row("torsional rigidity, secant (lost-motion midpoint to +-rated)",
            _f(_get(h, "torsional_rigidity_secant_Nm_per_arcmin"), ".0f", "N m/arcmin"), "-",
            "hysteresis/hysteresis.json", "the whole wind-up, clearance knee included: below b/a, which is "
            "the slope of the stiff upper part"),
        Row("loop width at zero torque with contact friction", _f(_get(h, "loop_width_at_zero_arcmin"), ".3f", "arcmin"),
            "-", "hysteresis/hysteresis.json", "free play plus what boundary friction holds at rest "
            "(dynamics.losses: the friction adds "
            + _f(None if _get(h, "friction_loop") is None else 60 * (h["friction_loop"]["width_at_zero_arcmin"]
                                                                     - h["friction_loop"]["width_frictionless_at_zero_arcmin"]),
                 ".2f", "arcsec", "?") + ")"),
        Row("lost motion (angle between +-3 % rated)", _f(_get(h, "lost_motion_arcmin"), ".3f", "arcmin"),
            f"catalog <= {LOST_MOTION_CATALOG_ARCMIN:g} arcmin", "hysteresis/hysteresis.json",
            "lost motion = free play + elastic wind-up between -3 % and +3 % rated, so it exceeds the backlash"),
        Row("backlash, rigid geometry (unloaded profile, disc on its eccentric)",
            _f(_get(g, "backlash_total_arcmin"), ".3f", "arcmin"), f"catalog <= {LOST_MOTION_CATALOG_ARCMIN:g} arcmin",
            "geometry/geometry.json",
            "rigid parts, one crank angle, closed form beside the CAD profile"),
        Row("backlash, loop width at zero torque (lumped model)", _f(_get(h, "backlash_arcmin"), ".3f", "arcmin"), "-",
            "hysteresis/hysteresis.json",
            "the same free play taken up by the lumped model (every body free to settle, +-0.01 % rated) "
            "instead of the rigid disc on its eccentric, so it differs slightly from the rigid figure"),
    ]
    rows += operating_rows(case_dir)
    if ls:
        lo, hi = ls.get("teeth_in_contact_range", [None, None])
        rows.append(Row("teeth in contact per disc at rated torque (over a mesh cycle)", f"{lo}-{hi}",
                        "-", "hysteresis/load_sharing.json",
                        f"largest pin carries {100 * ls.get('max_pin_share_of_disc_load', 0):.1f} % of its disc's load"))
    if sig:
        top = max(T for T, _ in sig)
        forms = list(dict.fromkeys(f for _, f in sig))
        vals = " / ".join(f"{sig.get((top, f), float('nan')):.3g}" for f in forms)
        ref = "-"
        paper = [paper001_sigma_arcsec(f, top) for f in forms]
        if ratio == PAPER_001_RATIO and cat and any(v is not None for v in paper):
            ref = "paper 001: " + " / ".join("no paper figure" if v is None else f"{v:.2f}" for v in paper)
        rows.append(Row(f"sigma of TE at {top:g} N m, {' / '.join(forms)} (t >= 2 s)", vals + " arcsec", ref,
                        "matrix/te_std.csv",
                        "ours is the elastic TE alone; paper 001's level must hold a no-load kinematic error of "
                        "a geometry it does not publish: compare trends" if ref != "-" else ""))
    else:
        rows.append(Row("sigma of TE (paper 001's load matrix)", "not built", "-", "matrix/te_std.csv"))
    if tol is not None:
        rows.append(Row("tolerance Monte Carlo (four-bar, paper 000 bands)", _tolerance_text(tol), "-",
                        "tolerance/summary.json", _windup_note(tol, case_dir)))
    if diag is not None:
        ext = diag.get("extension") or {}
        base = _get(diag, "baseline", "residual_rms_arcsec")
        causes = ", ".join(ext.get("causes", [])) or "none named"
        after = ext.get("residual_rms_arcsec")
        hold = ext.get("holdout_gain")
        gain = ext.get("gain")
        fitted_before = after / (1.0 - gain) if after is not None and gain is not None and gain < 1 else None
        rows.append(Row("diagnosis of the bench records", f"causes: {causes}; residual RMS on the fitted records "
                        f"{_f(fitted_before, '.3g', missing='n/a')} -> {_f(after, '.3g', missing='n/a')} arcsec, "
                        f"gain {_f(gain, '.3f', missing='n/a')}, held-out gain {_f(hold, '.3f', missing='n/a')}",
                        "-", "diagnosis/diagnosis.json",
                        f"baseline RMS over every record {_f(base, '.3g')} arcsec (one free offset per encoder zero); "
                        "the lines no cause explains are listed in the diagnosis section"))
        rows += _record_reading_rows(read_json(case_dir / "diagnosis" / "diagnosis_lines.json"), diag)
    else:
        rows.append(Row("diagnosis of bench records", "no bench records for this case", "-", "diagnosis/"))
    comp = read_json(case_dir / "compensate" / "compensation.json")
    if comp is not None:
        lo, hi = (comp.get("published_rms_reduction") or [None, None])[:2]
        ref = f"Bilancia et al. 2025: {_f(lo, '.0%')}-{_f(hi, '.0%')} online (per-order black box)" \
            if lo is not None and hi is not None else "-"
        rows.append(Row("compensation from the extended model", f"TE RMS {_f(comp.get('te_rms_before_arcsec'), '.1f')} -> "
                        f"{_f(comp.get('te_rms_after_arcsec'), '.1f')} arcsec on {len(comp.get('records', {}))} "
                        f"records ({_f(comp.get('rms_reduction'), '.1%')} removed)", ref, "compensate/compensation.json",
                        "fitted and held-out records alike; the table is the model's, no record's TE is stored in it"))
    if p001 is not None:
        rows.append(Row("paper 001 no-load bench case", _paper001_text(p001),
                        f"paper 001: measured {p001.get('measured_arcsec', float('nan')):g} arcsec p-p",
                        "diagnosis/paper001.json"))
    return rows


def _record_reading_rows(lines: dict | None, diag: dict) -> list[Row]:
    """What the bench records say of themselves (diagnosis_lines.json, the diagnosis' notes): the
    encoder-zero groups whose mechanism lines sit in another angle frame, and the gap's shape."""
    rows = []
    shifted = [f for f in (lines or {}).get("angle_frames", []) if f.get("reported")]
    if lines is not None:
        rows.append(Row("records' output-angle frames (mechanism lines laid on the first encoder zero)",
                        "; ".join(f"{'/'.join(f'{t:g}' for t in f.get('torques_Nm', [])) or f['group']} N m records "
                                  f"{f['shift_deg']:+.3f} deg" for f in shifted)
                        or "one frame", "-", "diagnosis/diagnosis_lines.json",
                        "records whose angle zero moved: a cause fixed in the reducer is fitted across them as if "
                        "it had not (reported, not applied)" if shifted else ""))
    shape = next((n for n in diag.get("notes", []) if n.startswith("gap shape:")), None)
    if shape is not None:
        rows.append(Row("gap shape (forward minus backward, against torque)", shape.split(": ", 1)[1].split(";")[0],
                        "-", "diagnosis/diagnosis.json", shape.split("; ", 1)[1] if "; " in shape else ""))
    return rows


def _tolerance_text(tol: dict) -> str:
    """Share of builds within the limit: rigid, and elastic less the wind-up every build shares
    (an error of stiffness, not of accuracy); the raw elastic share counts that wind-up as error."""
    lim = tol.get("limit_arcsec", float("nan"))
    pct = {k: _get(tol, k, "share_within_limit") for k in ("rigid", "elastic_minus_nominal_windup", "elastic")}
    if pct["rigid"] is None:
        return "built (see the tolerance section)"
    out = f"{tol.get('samples', '?')} builds within +-{lim:g} arcsec: rigid {100 * pct['rigid']:.1f} %"
    if pct["elastic_minus_nominal_windup"] is not None:
        out += f", elastic less the shared wind-up {100 * pct['elastic_minus_nominal_windup']:.1f} %"
    if pct["elastic"] is not None:
        out += f" (raw elastic {100 * pct['elastic']:.1f} %)"
    return out


def _windup_note(tol: dict, case_dir: Path) -> str:
    w4 = tol.get("nominal_elastic_windup_arcsec")
    if w4 is None:
        return ""
    note = (f"the four-bar's wind-up at {tol.get('torque_Nm', 0):g} N m ({w4:.1f} arcsec) is shared by every build, "
            "so it is taken out; it is one crank pair's bearing deflection")
    lumped = windup_at_rated_arcsec(case_dir)
    return note + (f", the lumped model's ({lumped:.1f} arcsec, hysteresis) has every compliance in the path"
                   if lumped is not None else "")


def windup_at_rated_arcsec(case_dir: Path) -> float | None:
    """Output angle at +rated torque, input locked (hysteresis.csv; half the free play included)."""
    h = read_json(case_dir / "hysteresis" / "hysteresis.json")
    try:
        with (case_dir / "hysteresis" / "hysteresis.csv").open() as fh:
            rows = [(float(a), float(b)) for a, b in list(csv.reader(fh))[1:]]
        rated = float(h["rated_torque_Nm"])
    except (OSError, ValueError, TypeError, KeyError):
        return None
    at = [b for a, b in rows if abs(a - rated) <= 1e-9 * rated]
    return 60.0 * sum(at) / len(at) if at else None


def _paper001_text(p: dict) -> str:
    sim, um = p.get("simulated_pp_arcsec"), p.get("coaxiality_closing_um")
    if sim is None or um is None:
        return "built (see the diagnosis section)"
    return (f"simulated no-load peak-to-peak {sim:.3g} arcsec; an output coaxiality of {um:.3g} um at "
            f"r = {p.get('output_flange_radius_mm', float('nan')):g} mm closes the gap")


def operating_rows(case_dir: Path) -> list[Row]:
    """Efficiency, bearing life and the operating map's gap error (the `conditions` stage)."""
    c = read_json(case_dir / "conditions" / "conditions.json")
    if not c:
        return [Row("operating map (efficiency, bearing life, gap over speed and torque)", "not built", "-",
                    "conditions/conditions.json", "built where the case has a conditions table (RV-160N bench)")]
    rp, life, pub = c["rated_point"], c["bearing_life"], c["rated_point"]["published"]
    rows = [Row(f"efficiency at rated torque, {c['bearing_life']['output_speed_rpm']:g} rpm output, 40 C oil",
                _f(rp["efficiency"], ".1%"), f"{pub['value']:.0%} ({pub['band'][0]:.0%}-{pub['band'][1]:.0%}): "
                f"{pub['source']}", "conditions/conditions.json",
                f"pin friction {rp['pin_friction_mean']:.3f} at film parameter {rp['pin_film_parameter_mean']:.2f}"),
            Row("bearing life L10 at rated torque and speed (weakest; system)",
                f"{life['weakest_L10_h']:.0f} h ({life['weakest']}); system {life['system_L10_h']:.0f} h "
                f"(x {life['system_L10_over_catalog']:.2f}); modified Lnm {life['system_Lnm_h']:.0f} h",
                f"catalog rated life K = {life['catalog_rated_life_h']:g} h", "conditions/conditions.json",
                "ISO 281 from the model's load distribution; the system life of all crank bearings"),
            Row("starting torque at the input (no load, 25 C)", _f(c["starting_torque_input_Nm"]["25"], ".2f", "N m"),
                "-", "conditions/conditions.json", "boundary friction, bearing preload moments, seals")]
    m = c.get("against_measured")
    if m:
        sl = m["gap_slope_by_speed_rpm"]
        txt = "; ".join(f"{k} rpm {v['predicted_arcsec_per_Nm']:.3f} (bench {v['measured_arcsec_per_Nm']:.3f})"
                        for k, v in sl.items() if v["rows"] >= 5)
        rows.append(Row("forward-backward gap over the bench's conditions: RMS error",
                        f"{m['gap_rms_error_arcsec']:.1f} arcsec (frictionless {m['gap_rms_error_frictionless_arcsec']:.1f})",
                        f"{m['rows']} bench conditions (conditions_25C.csv)", "conditions/conditions.json",
                        f"gap per N m by input speed: {txt} arcsec/(N m)"))
        gl = m.get("gap_lines")
        if gl and gl["by_speed_rpm"]:
            k = "".join(f"; {s} rpm {v['predicted_rigidity_Nm_per_arcmin']:.0f} (bench {v['measured_rigidity_Nm_per_arcmin']:.0f})"
                        for s, v in gl["by_speed_rpm"].items() if v["rows"] >= 5 and v["measured_rigidity_Nm_per_arcmin"])
            rows.append(Row("the gap's error split: with the bench's wind-up slopes / zero-load gaps put in",
                            f"{gl['gap_rms_error_with_bench_slopes_arcsec']:.1f} / "
                            f"{gl['gap_rms_error_with_bench_zero_load_gaps_arcsec']:.1f} arcsec RMS "
                            f"(as predicted {gl['gap_rms_error_on_lines_arcsec']:.1f})",
                            "what-ifs on the bench's own lines, the model unchanged", "conditions/conditions.json",
                            f"rigidity the gap lines imply, N m/arcmin{k}"))
        ch = m.get("bench_chain_whatifs")
        if ch:
            rows.append(Row("what-if, not the prediction: a torque flange between the reducer and the output encoder",
                            " / ".join(f"{w['gap_rms_error_arcsec']:.1f}" for w in ch) + " arcsec gap RMS",
                            "; ".join(f"{w['flange']}: {w['rigidity_Nm_per_arcmin']:.0f} N m/arcmin" for w in ch),
                            "conditions/conditions.json",
                            "the bench's layout, which its dataset does not state: the unknown that moves this "
                            "figure most (its twist adds -2 T / k to every gap)"))
        th = m.get("thermal_whatif")
        if th and th.get("bench_speeds_rpm"):
            need = lambda k: "no warming gives it" if k is None else f"{k:.3g} K"  # noqa: E731
            rows.append(Row(f"what-if, not the prediction: discs warmer than the ring, {th['speed_rpm']:g} rpm",
                            f"zero-load gap {th['zero_load_gap_change_arcsec_per_K']:+.2f} arcsec/K, "
                            f"wind-up {th['wind_up_change_pct_per_K']:+.2f} %/K",
                            f"bench {th['bench_speeds_rpm'][0]:g} -> {th['bench_speeds_rpm'][1]:g} rpm: "
                            f"{th['bench_zero_load_gap_change_arcsec']:+.1f} arcsec "
                            f"({need(th['kelvin_for_bench_zero_load_gap_change'])}), "
                            f"wind-up {th['bench_wind_up_change_pct']:+.1f} % "
                            f"({need(th['kelvin_for_bench_wind_up_change'])})",
                            "conditions/conditions.json",
                            "the parts' temperatures, which the bench does not give (dynamics.thermal); in brackets "
                            "the warming that would make the bench's change between its slowest and fastest speed"))
    return rows
