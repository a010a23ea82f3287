"""Reduce every FE/closed-form result of the FEM stage to the stiffness.json schema (fem.stiffness).

build_stiffness(case, ...) runs every registered stiffness-path component's `compute` as an
independent task (fem.components.REGISTRY: the 2D tooth-pin contact map, the 3D crankshaft torsion
and bending, the needle bearing, the crank support bearings, the carrier, the disc body, the pin in
its groove, the involute mesh, ...; `--workers` runs them in parallel), then each one's `refine`
(steps that need another component's result, e.g. the needle edge loading from the crank slope),
and assembles the StiffnessModel from their fields. Every entry carries a source and a check (the
FE beside its closed form); extras keep mesh sizes and timings.

Load ranges (`table_loads_N`): the pin-contact map and the needle curve reach the catalog momentary
torque times LOAD_MARGIN over the classical sharing, because the lumped model's pins and needles
carry more than the classical estimate (measured, see LOAD_MARGIN); tests/test_fem_reduce.py checks
that the model's largest forces at the momentary torque lie inside the tables.
"""
from __future__ import annotations

import json
import time
from dataclasses import dataclass, field

import numpy as np

from fem import bearing, crank_path, pin_contact
from fem.components import REGISTRY, by_name
from fem.components.needle_bearings import force_classical_N as needle_force_classical_N
from fem.stiffness import PinSeries, StiffnessModel

# The lumped model's largest pin and needle forces over the classical estimates (pins:
# pin_contact.contact_force_at_torque; needles: needle_force_classical_N), measured on
# tests/support.model_for_tests with static solves at 12 input angles over one pin pitch: at the
# momentary torque pins 1.46 (rv40e-81) / 1.37 (rv160n-81), needles 1.37 / 1.37 (at the rated
# torque pins 1.86 / 1.82: fewer pins share a light load). 1.8 covers the largest momentary ratio
# with 23 % to spare for the FE's other sharing and as-built errors (tests/test_fem_reduce.py).
LOAD_MARGIN = 1.8
PIN_LOWEST_OF_RATED = 0.125   # lowest pin level / the rated classical force (the former table's low end)
PIN_LEVELS = 8                # geometric spacing: 1.84x per level on the shipped cases


@dataclass(frozen=True)
class FemRun:
    model: StiffnessModel
    tooth_map: pin_contact.ToothPairMap
    crank_fields: dict
    artifacts: dict = field(default_factory=dict)   # every component's in-memory artifacts (pictures)
    timings_s: dict = field(default_factory=dict)   # wall seconds per component and of the tooth map (the
    # fem command writes them to timings.json: kept out of stiffness.json, which is then the same bytes
    # for the same inputs)


def table_loads_N(case) -> dict:
    """Load levels of the pin-contact map and the needle curve (module doc), N."""
    mom = case.operation.momentary_torque_Nm
    top = LOAD_MARGIN * pin_contact.contact_force_at_torque(case, mom)
    low = PIN_LOWEST_OF_RATED * pin_contact.contact_force_at_torque(case, case.rated_torque_Nm)
    needle = LOAD_MARGIN * needle_force_classical_N(case, mom) * np.asarray(bearing.LOAD_FRACTIONS)
    return {"pin": np.geomspace(low, top, PIN_LEVELS), "needle": needle}


def task_context(case, **options) -> dict:
    """What every component's compute reads besides the case: the options of build_stiffness, the
    load tables and the load margin (a plain dict: picklable to workers)."""
    return dict(options, loads=table_loads_N(case), load_margin=LOAD_MARGIN)


ASSEMBLY_CHECKS = {crank_path.NAME: crank_path}   # checks of the reduction: prepare (a pool task), check(model)


def _compute(name: str, case, ctx: dict, part=None):
    """One component's FE or closed form, one part of it, or an assembly check's FE part (a task:
    pure, picklable in and out)."""
    if name in ASSEMBLY_CHECKS:
        return ASSEMBLY_CHECKS[name].prepare(case, ctx)
    c = by_name(name)
    return c.compute(case, ctx) if part is None else c.compute_part(case, ctx, part)


def _tasks(case, ctx, checks=()) -> list:
    """(cost, name, part) of every task, longest first (the pool takes them in order): a component
    with `parts` (independent meshes, e.g. the carrier's levels) is one task per part, put together
    by its `combine`; any other is one task (part None); each assembly check's `prepare` one task."""
    jobs = [(cost, c.NAME, p) for c in REGISTRY
            for cost, p in (c.parts(case, ctx) if hasattr(c, "parts") else [(c.COST, None)])]
    jobs += [(ASSEMBLY_CHECKS[n].COST, n, None) for n in checks]
    return sorted(jobs, key=lambda j: -j[0])


NESTED = {"pin_series": PinSeries}   # StiffnessModel fields assembled from several components' "<field>.<key>";
                                     # "parts.<component>": the entries of components without a field


def assemble(case, results: dict, extras: dict) -> StiffnessModel:
    """The StiffnessModel from the components' results (fields, sources, checks, extras)."""
    fields, nested, sources, checks = {}, {k: {} for k in (*NESTED, "parts")}, {}, {}
    for r in results.values():
        for k, v in r.fields.items():
            head, _, tail = k.partition(".")
            (nested[head].__setitem__(tail, v) if tail else fields.__setitem__(k, v))
        sources.update(r.sources)
        checks.update(r.checks)
        extras.update(r.extras)
    fields.update({k: NESTED[k](**v) for k, v in nested.items() if k in NESTED}, parts=nested["parts"])
    checks = json.loads(json.dumps(checks))     # as stiffness.json holds them (tuples as lists, keys as str)
    return StiffnessModel(case_name=case.name, sources=sources, checks=checks, extras=extras, **fields)


def build_stiffness(case, *, mesh_size_m: float | None = None, crank_edge_m: float | None = None,
                    positions_deg=None, crank_mesh=None, map_tasks=None, carrier_levels=None,
                    disc_h_profile_m: float | None = None, assembly_checks: bool = True) -> FemRun:
    """crank_mesh: the crankshaft tet mesh of the mesh stage (fem.shaft.crankshaft_mesh), else made here.
    carrier_levels, disc_h_profile_m: coarser meshes than the defaults (tests). assembly_checks: run
    ASSEMBLY_CHECKS (fem.crank_path: the crank path assembled as one FE model) into `checks`.
    The components are independent, run through `map_tasks(func, tasks) -> results in order`
    (default: one after the other, in this process; pipeline.sweep.run_tasks puts them on local
    processes or a Dask cluster, same results)."""
    t0 = time.perf_counter()
    map_tasks = map_tasks or (lambda func, tasks: [func(*t) for t in tasks])
    ctx = task_context(case, positions_deg=positions_deg, mesh_size_m=mesh_size_m, crank_edge_m=crank_edge_m,
                       crank_mesh=crank_mesh, carrier_levels=carrier_levels, disc_h_profile_m=disc_h_profile_m)
    checks = ASSEMBLY_CHECKS if assembly_checks else {}
    jobs = _tasks(case, ctx, checks)
    done: dict = {}
    for (_, n, p), r in zip(jobs, map_tasks(_compute, [(n, case, ctx, p) for _, n, p in jobs])):
        done.setdefault(n, []).append((p, r))
    prepared = {n: done.pop(n)[0][1] for n in checks}
    names = [c.NAME for c in sorted(REGISTRY, key=lambda c: -c.COST)]   # the former task order (stiffness.json's)
    results = {n: by_name(n).combine(case, ctx, done[n]) if hasattr(by_name(n), "parts") else done[n][0][1]
               for n in names}
    for c in REGISTRY:
        if hasattr(c, "refine"):
            r = c.refine(case, results)
            results[r.name] = r
    tables = ctx["loads"]
    timing = {f"{n}_s": r.seconds for n, r in results.items()}
    tm = results["pin_contact"].artifacts["tooth_map"]
    model = assemble(case, results, {})
    mom = case.operation.momentary_torque_Nm
    model.sources["load_ranges"] = (f"pin and needle tables up to LOAD_MARGIN = {LOAD_MARGIN:g} x the classical force "
                                    f"at the catalog momentary torque {mom:g} N m (fem.reduce: the lumped model's "
                                    f"forces over the classical ones, measured 1.46 at most)")
    model.sources["pin_series"] = ("every pin component in series with each tooth-pin contact "
                                   "(fem.components, fem.stiffness.pin_law)")
    model.checks["load_ranges"] = {"pin_top_N": float(tables["pin"][-1]), "needle_top_N": float(tables["needle"][-1]),
                                   "pin_classical_at_momentary_N": float(tables["pin"][-1] / LOAD_MARGIN),
                                   "needle_classical_at_momentary_N": float(tables["needle"][-1] / LOAD_MARGIN),
                                   "margin": LOAD_MARGIN}
    for n, mod in checks.items():
        t1 = time.perf_counter()
        model.checks[n] = json.loads(json.dumps(mod.check(case, model, prepared[n])))
        timing[f"{n}_s"] = prepared[n]["seconds"] + time.perf_counter() - t1
        model.sources[n] = mod.__doc__.split("\n\n")[0].replace("\n", " ")
    model.check(case.name)
    artifacts = {k: v for r in results.values() for k, v in r.artifacts.items()}
    timings = dict(timing, tooth_map=dict(tm.timing_s), carrier_levels=results["carrier"].artifacts["carrier_timing_s"],
                   total_s=time.perf_counter() - t0)
    return FemRun(model, tm, artifacts["crank_fields"], artifacts, timings)
