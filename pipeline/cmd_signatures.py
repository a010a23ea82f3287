"""`signatures`: the as-built error atlas (DESIGN.md CLI contract).

    python -m pipeline signatures --case CASE.toml --out DIR [--stiffness PATH]

Writes DIR/signatures.json (per source at its unit size: order amplitudes per torque and direction,
the main line's torque and direction dependence, the mean shift, the groups of sources that share a
signature; `made_from` the case and the stiffness) and DIR/signatures.png. The computation is
dynamics.signatures (grid, sources and what the model shows are documented there).
"""
from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from geometry.artifacts import write_json_atomic

SCHEMA = "rv-signatures/1"
DIRECTION_NAMES = {1: "forward", -1: "backward"}


def order_name(case, k: int) -> str:
    """The mechanism an order belongs to (DESIGN.md characteristic orders), '' when none."""
    zp, zc, nc = case.cycloid.zp, case.cycloid.zc, case.carrier.crank_count
    if k == 0:
        return "mean"
    names = []
    if k % zc == 0:
        names.append(f"{k // zc} zc" if k > zc else "zc")
    if k % zp == 0:
        names.append(f"{k // zp} zp" if k > zp else "zp")
    if k == nc:
        names.append("n_crank")
    if abs(k - case.ratio) < 1e-9:
        names.append("i")
    if k == 1:
        names.append("1x")
    return ", ".join(names)


def _per_direction(sig, values) -> dict:
    return {DIRECTION_NAMES[d]: [float(v) for v in values[i]] for i, d in enumerate(sig.directions)}


def source_json(case, sig, group: int | None, nearest: tuple[str, float] | None) -> dict:
    s = sig.source
    lines = [{"order": k, "mechanism": order_name(case, k),
              "amplitude_arcsec": _per_direction(sig, sig.amplitude(k)),
              "torque_exponent": sig.torque_exponent(k), "torque_dependence": sig.torque_dependence(k),
              "direction": sig.direction(k)} for k in sig.lines()]
    main = sig.main_order()
    return {"id": s.id, "description": s.description, "kind": s.kind, "unit": s.unit, "unit_size": s.unit_size,
            "errors": s.errors(case, s.unit_size), "negligible": sig.negligible,
            "main_order": main, "main_mechanism": order_name(case, main),
            "main_amplitude_arcsec": float(sig.amplitude(main).max()),
            "torque_dependence": sig.torque_dependence(main), "direction_dependence": sig.direction_dependence(main),
            "lines": lines,
            "mean_shift_arcsec": _per_direction(sig, sig.spectrum[:, :, 0].real),
            "offset_arcsec": sig.offset_arcsec,
            "mean_shift_torque_dependence": sig.torque_dependence(0), "mean_shift_direction": sig.direction(0),
            "group": group, "nearest": None if nearest is None else {"source": nearest[0], "cosine": nearest[1]}}


def atlas_json(case, sigs, grid, made_from) -> dict:
    from dynamics.signatures import groups, similarity
    grp = groups(sigs)
    member = {i: g for g, idx in enumerate(grp) for i in idx}
    out = []
    for i, s in enumerate(sigs):
        others = [(similarity(s, t), t.source.id) for j, t in enumerate(sigs) if j != i and not t.negligible]
        best = max(others) if others and not s.negligible else None
        out.append(source_json(case, s, member.get(i), None if best is None else (best[1], best[0])))
    group_json = []
    for g, idx in enumerate(grp):
        orders = sorted({sigs[i].main_order() for i in idx})
        group_json.append({"group": g, "sources": [sigs[i].source.id for i in idx],
                           "main_orders": orders, "mechanisms": [order_name(case, k) for k in orders],
                           "torque_dependence": sorted({sigs[i].torque_dependence(sigs[i].main_order()) for i in idx}),
                           "shared": len(idx) > 1})
    return {"case": case.name, "schema": SCHEMA,
            "definition": "TE change (arcsec) per unit size of each source alone against the ideal build, "
                          "quasi-static over one output revolution; amplitudes single-sided per order of the "
                          "output revolution (A cos(k theta + phase) -> A), order 0 the mean shift; per torque "
                          "(grid.torques_Nm) and direction (forward: load resists forward motion). offset_arcsec: "
                          "the mean shift averaged over every condition, which no bench sees (its zero is free); "
                          "main order, dependences, nearest and groups use what is left (lines and the "
                          "differences of the mean shift between torques and directions)",
            "grid": grid, "orders": {"zc": case.cycloid.zc, "zp": case.cycloid.zp,
                                     "n_crank": case.carrier.crank_count, "i": case.ratio},
            "sources": out, "groups": group_json, "made_from": made_from}


def plot(path, case, sigs) -> None:
    """Heat map of the line amplitudes at rated torque (forward) per source and order, and the main
    line's torque exponent."""
    from pipeline.render import figure, save_figure
    zp, zc, nc = case.cycloid.zp, case.cycloid.zc, case.carrier.crank_count
    cols = {0, 1, nc, zc, zp, 2 * zc, 2 * zp, 3 * zc, 4 * zc}
    for s in sigs:
        cols.update(s.lines()[:3])
    n_half = sigs[0].spectrum.shape[2] - 1 if sigs else 0
    cols = sorted(k for k in cols if k <= n_half)
    A = np.array([[s.amplitude(k)[0, -1] for k in cols] for s in sigs])
    fig, (ax, ax2) = figure(1, 2, figsize=(15, 0.34 * len(sigs) + 2.5), gridspec_kw={"width_ratios": [3.2, 1]})
    im = ax.imshow(np.log10(np.maximum(A, 1e-4)), aspect="auto", cmap="viridis", vmin=-3, vmax=1)
    for r in range(A.shape[0]):
        for c in range(A.shape[1]):
            if A[r, c] >= 1e-3:
                ax.text(c, r, f"{A[r, c]:.2g}", ha="center", va="center", fontsize=6,
                        color="white" if A[r, c] < 0.3 else "black")
    ax.set_xticks(range(len(cols)), [f"{k}\n{order_name(case, k)}" for k in cols], fontsize=7)
    labels = [f"{s.source.id} ({s.source.unit_size:g} {s.source.unit})" for s in sigs]
    ax.set_yticks(range(len(sigs)), labels, fontsize=7)
    ax.set_xlabel("order (cycles per output revolution); 0 = mean shift less the offset no bench sees")
    ax.set_title(f"{case.name}: TE per unit error at {sigs[0].torques_Nm[-1]:.0f} N m forward [arcsec]",
                 fontsize=9)
    fig.colorbar(im, ax=[ax, ax2], label="log10 amplitude [arcsec]", orientation="horizontal", fraction=0.025,
                 pad=0.09, shrink=0.5)
    ex = [s.torque_exponent(s.main_order()) for s in sigs]
    ax2.barh(range(len(sigs)), ex, color=["#d95f02" if s.negligible else "#1b9e77" for s in sigs])
    ax2.set_ylim(ax.get_ylim())
    ax2.set_yticks([])
    lo, hi = min(min(ex), -0.2), max(max(ex), 0.2)
    ax2.set_xlim(lo - 0.6 * (hi - lo), hi + 0.1 * (hi - lo))
    for r, s in enumerate(sigs):
        ax2.text(lo - 0.55 * (hi - lo), r, f"{s.main_order()}: {s.direction_dependence(s.main_order())}",
                 va="center", fontsize=7)
    ax2.axvline(0, color="k", lw=0.5)
    ax2.set_xlabel("d ln A / d ln T of the main line")
    ax2.set_title("main order: direction; torque exponent", fontsize=9)
    save_figure(fig, path)


def _sources(case, wanted: str | None):
    """The atlas's sources, or the comma-separated ids asked for (checked)."""
    from dynamics.signatures import sources
    from geometry.artifacts import InputError
    allowed = sources(case)
    if wanted is None:
        return allowed
    by_id = {s.id: s for s in allowed}
    ids = [w.strip() for w in wanted.split(",") if w.strip()]
    bad = [w for w in ids if w not in by_id]
    if bad or not ids:
        raise InputError(f"--sources {wanted!r}: unknown source {bad[0] if bad else '(none given)'}; allowed: "
                         f"{', '.join(by_id)}")
    return tuple(by_id[w] for w in ids)


def cmd_signatures(args) -> int:
    from dynamics.signatures import atlas
    from fem.stiffness import load, path_for_case
    from geometry.fingerprint import made_from
    from geometry.params import load_case
    case = load_case(args.case)
    src = _sources(case, args.sources)
    spath = path_for_case(case, args.stiffness)
    stiffness = load(spath)
    from dynamics.reducer import build_model
    build_model(case, stiffness)          # refuses a stiffness of another case before the long part
    out = Path(args.out)
    t0 = time.perf_counter()
    progress = None if args.quiet else (lambda i, n, sid: print(f"signatures: {i}/{n} {sid}", flush=True))
    from dynamics.signatures import housing_structure
    from pipeline.diagnosis.simulate import process_pool
    pool = process_pool(None)             # one process per core; each loads the kernels from their disk cache
    try:
        sigs, grid = atlas(case, stiffness, source_list=src, progress=progress, pool=pool)
        hs = housing_structure(case, stiffness, pool=pool)  # the housing's own lines (its bolt pattern), not an error
    finally:
        if pool is not None:
            pool.shutdown()
    data = atlas_json(case, sigs, grid, made_from(case, SCHEMA, stiffness=stiffness.made_from).to_json())
    data["structure"] = None if hs is None else dict(source_json(case, hs, None, None), grid_points_per_output_rev=int(
        hs.spectrum.shape[-1] * 2 - 2), definition="the ideal build's TE with the elastic housing minus the same "
                                                   "build with the housing held rigid (arcsec, as built)")
    write_json_atomic(out / "signatures.json", data)
    plot(out / "signatures.png", case, sigs)
    if not args.quiet:
        print(f"signatures: {out}/signatures.json: {len(sigs)} sources, {len(data['groups'])} groups, "
              f"{grid['points_per_output_rev']} points per output revolution, "
              f"{time.perf_counter() - t0:.0f} s", flush=True)
    return 0


def register(sub) -> None:
    p = sub.add_parser("signatures", help="as-built error atlas: each source alone through the model")
    p.add_argument("--case", required=True, help="case TOML")
    p.add_argument("--out", required=True, help="output folder")
    p.add_argument("--stiffness", default=None, help="stiffness.json (default build/<case name>/fem/stiffness.json)")
    p.add_argument("--sources", default=None, help="comma-separated source ids (default: every source)")
    p.add_argument("--quiet", action="store_true")
    p.set_defaults(func=cmd_signatures)
