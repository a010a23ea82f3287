"""Simulating a record's conditions through the model (the fast quasi-static path).

Each record is simulated at its own torque (signed: + resists forward rotation), direction and
operating condition (input speed from the samples, oil temperature from `# oil_temperature_C`:
`record_condition`), all read from the record itself.
Steady records (torque spread within STEADY_TORQUE of rated, every real bench run): the mechanism
repeats after one output revolution (dynamics.statics: every body's phase returns), so the model is
solved once per revolution on a uniform grid of input angles anchored at 0 (`points_per_rev`
points, default `default_points_per_rev`) and read at the record's angles by trigonometric
interpolation (exact for every order below the grid's Nyquist order, so the 156x line is not
attenuated as a linear interpolation between 1024 points would: -7 %); the cost does not grow
with the record's length. The default grid is the signature atlas's stroboscopic one
(dynamics.signatures.points_per_rev: a divisor of zp zc above 2 MAX_ORDER, 390 for zp = 40): the
cycloid-pin mesh ripple (zp zc x, the model's strongest line above MAX_ORDER: 0.04 arcsec on the
RV-160N) folds onto the mean instead of onto a line. A torque that varies more is followed sample
by sample on a thinned set of samples (cost grows with the revolutions, linear interpolation).
Quasi-static means no inertia or damping: valid for the slow, steady runs of a TE bench, not for
load transients. Zero torque (the bench's "0 N.m" runs) is passed as 0: at the record's condition
the carrier's drag holds the model on the flank of the direction of motion (below); without a
condition it rests there under a vanishing preload (dynamics.model.solve_static).

Caches (content-keyed, never by object id: an id is reused after garbage collection):
  models    per (case, stiffness content digest `stiffness_digest`);
  carrier   the carrier angles of a solved grid per (the case's mechanics, stiffness digest, grid,
            torque, direction, condition): the output encoder's reading errors
            (READING_FIELDS: coaxiality, reading lobes) do not load any part (dynamics.reducer:
            they enter only `measured_output_rad`), so a case that differs only in them reuses the
            solved carrier angles and re-reads them: the signature columns of the reading causes
            and the fit's repeats of an already solved model cost no solve;
  seeds     inside `seeding()` (a diagnosis run), the states of the last model solved on each grid
            start the next model's solve there (statics.static_path): the same equilibria to
            the Newton tolerance, 2.2 instead of 4 Newton iterations a point from the unperturbed
            model's states; from the last model's (a fit's Jacobian columns and steps are near
            each other, the unperturbed model falls behind as the fit moves) the 8 real records'
            diagnosis takes 145 s instead of 179 s.
`TEModel` is the seam to the dynamics stage: any callable with its signature can stand in. It
receives the record's `Condition` (speed, oil temperature): given one, the mechanism carries the
record's load plus the carrier's drag at that condition (main bearings and output seal,
dynamics.losses.contacts.carrier_drag_Nm; a bench's torque meter reads the load alone), which also
holds an unloaded record's discs on the flank of the motion as on a running reducer. The contacts'
friction is not in this path (dynamics.losses.operating.friction_shift_arcsec: a constant per record).
"""
from __future__ import annotations

import contextlib
import dataclasses
import hashlib
import inspect
from dataclasses import dataclass
from typing import Callable

import numpy as np

from dynamics.records import BenchRecord
from dynamics.results import ARCSEC_PER_DEG

# te_model(case, stiffness, input_angle_deg, torque_Nm, direction, condition=None) -> te_arcsec at
# those angles; torque_Nm in the record convention (+ resists forward rotation), scalar or one per angle
TEModel = Callable[..., np.ndarray]

STEADY_TORQUE = 0.01   # 5-95 % torque spread / rated torque under which a record is steady
_CACHE_SIZE = 256
# Errors fields read only by the output encoder (dynamics.reducer.build_model: coaxiality_rad and
# reading_lobes enter measured_output_rad alone; tests/test_diagnose_machinery checks the arrays)
READING_FIELDS = dict(output_coaxiality_um=0.0, output_coaxiality_phase_deg=0.0, output_reading_lobes=())
_MODELS: dict = {}
_CARRIERS: dict = {}
_DIGESTS: dict = {}


@dataclass(frozen=True)
class Condition:
    """A record's operating condition: input speed [rpm] (from the samples) and oil temperature
    [degC] (`# oil_temperature_C`, None when the record does not say)."""
    input_speed_rpm: float
    oil_temperature_C: float | None = None


def record_condition(record: BenchRecord) -> Condition:
    """The condition a record was run at, read from the record (speed to 0.1 rpm: a cache key)."""
    return Condition(round(float(record.input_speed_rpm), 1), record.comment_value("oil_temperature_C"))


_DRAGS: dict = {}


def carrier_drag(case, condition: Condition | None) -> float:
    """The carrier's drag [N m] at a record's condition (0 without one); oil temperature from the
    condition or the lubricant's stated run temperature; outside its range: the one-line error."""
    if condition is None:
        return 0.0

    def make():
        from dynamics.losses.contacts import carrier_drag_Nm
        from dynamics.losses.lubricant import Lubricant
        temp = condition.oil_temperature_C
        temp = case.lubrication.run_oil_temperature_C if temp is None else float(temp)
        return carrier_drag_Nm(case, Lubricant.from_section(case.lubrication), condition.input_speed_rpm, temp)
    return _cached(_DRAGS, (case.lubrication, case.ratio, case.main_bearings, condition), make)


def mechanism_torque(case, torque_Nm: np.ndarray, direction: int, condition: Condition | None) -> np.ndarray:
    """What the mechanism carries in the record convention (+ resists forward): the record's torque
    plus the carrier's drag, which resists the motion in either direction."""
    drag = carrier_drag(case, condition)
    return torque_Nm + direction * drag if drag else torque_Nm


def max_order(case) -> int:
    """Highest order the diagnosis reads: the pin ring's m <= 4 lobes at m zc (<= 4 zp) and their
    sidebands at +- n_crank and +- 2 n_crank (a housing pattern modulated by the cranks)."""
    return 4 * case.cycloid.zp + 2 * case.carrier.crank_count


def default_points_per_rev(case) -> int:
    """The stroboscopic grid above 2 max_order (module docstring): 390 points for zp = 40."""
    from dynamics.signatures import points_per_rev
    return points_per_rev(case, max_order(case))


def _digest(obj, h) -> None:
    """Feed a value's content into hash h: dataclasses field by field, arrays by their bytes."""
    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        h.update(type(obj).__name__.encode())
        for f in dataclasses.fields(obj):
            if f.name not in ("sources", "checks", "made_from"):   # provenance, no physics
                h.update(f.name.encode())
                _digest(getattr(obj, f.name), h)
    elif isinstance(obj, np.ndarray):
        h.update(str(obj.dtype).encode() + str(obj.shape).encode())
        h.update(np.ascontiguousarray(obj).tobytes())
    elif isinstance(obj, dict):
        for k in sorted(obj, key=str):
            h.update(str(k).encode())
            _digest(obj[k], h)
    elif isinstance(obj, (list, tuple)):
        h.update(f"{type(obj).__name__}{len(obj)}".encode())
        for v in obj:
            _digest(v, h)
    elif hasattr(obj, "__dict__") and not callable(obj):   # a plain object: its attributes
        h.update(type(obj).__name__.encode())
        _digest(vars(obj), h)
    else:
        h.update(repr(obj).encode())


def stiffness_digest(stiffness) -> str:
    """Content digest of a stiffness model (its physics; provenance left out). Remembered per object
    (the entry holds the object, so its id cannot be reused while remembered; stiffness models are
    frozen): the fit asks for it at every solve (3 ms each, 5 % of a real-records diagnosis)."""
    hit = _DIGESTS.get(id(stiffness))
    if hit is not None and hit[0] is stiffness:
        return hit[1]
    h = hashlib.sha256()
    _digest(stiffness, h)
    digest = h.hexdigest()
    _DIGESTS.pop(id(stiffness), None)    # a dead object's id reused: replace its entry
    _cached(_DIGESTS, id(stiffness), lambda: (stiffness, digest))
    return digest


def _mechanics(case):
    """The case with the output encoder's reading errors removed (READING_FIELDS)."""
    return dataclasses.replace(case, errors=dataclasses.replace(case.errors, **READING_FIELDS))


def _cached(store: dict, key, make):
    """store[key], made once; the least recently used entry leaves when the store is full (a fit
    revisits the unperturbed model's solves between its steps: clearing everything lost them)."""
    if key in store:
        store[key] = store.pop(key)          # most recently used last
        return store[key]
    value = make()
    while len(store) >= _CACHE_SIZE:
        store.pop(next(iter(store)))
    store[key] = value
    return value


def model_for(case, stiffness, digest: str | None = None):
    """The dynamics model of (case, stiffness), built once per content."""
    from dynamics.model import build_model
    key = (case, digest or stiffness_digest(stiffness))
    return _cached(_MODELS, key, lambda: build_model(case, stiffness))


def _carrier_key(case, stiffness, ang: np.ndarray, T: np.ndarray, direction: int, condition) -> tuple:
    """(cache key, the case's mechanics, stiffness digest) of one solve (module docstring)."""
    digest = stiffness_digest(stiffness)
    mech = _mechanics(case)
    return ((mech, digest, hashlib.sha256(ang.tobytes() + T.tobytes()).hexdigest(), int(direction), condition),
            mech, digest)


def quasi_static_te(case, stiffness, input_angle_deg: np.ndarray, torque_Nm,
                    direction: int, condition: Condition | None = None) -> np.ndarray:
    """TE [arcsec] of the dynamics model's static equilibria (dynamics.model.quasi_static, TE only).

    torque_Nm is the record's (signed, + resists forward rotation); quasi_static applies
    direction * its argument, so it gets direction * torque_Nm (= |T| for a steady record), plus
    the carrier's drag at `condition` (module docstring).
    The carrier angles are cached per mechanics (module docstring); the reading is the case's own."""
    ang = np.asarray(input_angle_deg, float)
    T = np.ascontiguousarray(np.broadcast_to(mechanism_torque(case, np.asarray(torque_Nm, float), direction,
                                                              condition), ang.shape))
    key, mech, digest = _carrier_key(case, stiffness, ang, T, direction, condition)
    carrier = _cached(_CARRIERS, key, lambda: _seeded(key, _carrier_deg(model_for(mech, stiffness, digest), ang, T,
                                                                       direction, _seeds_for(key))))
    model = model_for(case, stiffness, digest)
    out = model.measured_output_rad(np.deg2rad(carrier))
    return (np.rad2deg(out) - ang / model.ratio) * ARCSEC_PER_DEG


def _carrier_deg(model, ang, T, direction, seeds=None) -> tuple[np.ndarray, np.ndarray]:
    """(carrier angles [deg], states) of the static path on one grid (seeds: `static_path`)."""
    from dynamics.statics import static_path
    seeds, fallback = seeds if isinstance(seeds, tuple) else (seeds, None)
    # T is the record's torque (+ resists forward rotation): the load applied to the output in
    # either direction of motion, as quasi_static(model, ang, direction * T, direction) applies it
    carrier, Q = static_path(model, np.deg2rad(ang), T, int(direction), seeds=seeds, fallback_seeds=fallback)
    return np.rad2deg(carrier), Q


def _solve_grid(mech, stiffness, ang, T, direction, seeds=None, digest=None) -> tuple[np.ndarray, np.ndarray]:
    """One grid's (carrier angles [deg], states) (a worker's task: module-level, picklable). digest:
    the stiffness' content digest as the caller keyed the solve (a worker receives a new object per
    task, so it would hash the model again: 1.6 ms alone, the workers' time 93.2 -> 87.5 s over the
    1444 tasks of the 8 real records)."""
    return _carrier_deg(model_for(mech, stiffness, digest), ang, T, direction, seeds)


# Warm starts of the fit (statics.static_path `seeds`): within a `seeding()` scope, the states of the
# last model solved on each (grid, torque, direction, condition) start the next solve there. Scoped
# so that a run's results do not depend on what an earlier run in the same process solved (they
# agree to the Newton tolerance either way).
# Inside a `tangent_seeds(base case, base stiffness, tag)` scope (the extension's Jacobian column
# `tag` at an iterate, extension._jacobian) a grid's solve starts instead from the base model's
# states there plus the state change the same column made at the previous iterate (a first-order
# predictor of the column's equilibria: the column's step is the same, only the iterate moved),
# the last model's states as the fallback where that start fails: the same equilibria to the
# Newton tolerance, about 20 % fewer Newton iterations per column (RV-160N grids, 0 and 300 N m).
_SEEDS: dict | None = None
_STATES: dict = {}        # carrier key -> states of that solve (within a seeding scope)
_STEPS: dict = {}         # (tag, grid part of the key) -> column states - base states
_TANGENT: tuple | None = None    # (base case, base stiffness, tag) inside tangent_seeds


class seeding:
    """Context: seed store on (module comment above); nested scopes share the outer one."""

    def __enter__(self):
        global _SEEDS
        self.outer = _SEEDS is not None
        if not self.outer:
            _SEEDS = {}
            _STATES.clear()
            _STEPS.clear()
        return self

    def __exit__(self, *exc):
        global _SEEDS
        if not self.outer:
            _SEEDS = None
            _STATES.clear()
            _STEPS.clear()


class tangent_seeds:
    """Context: the solves inside are Jacobian column `tag` of the model (case, stiffness) (module
    comment above); no effect outside a `seeding()` scope."""

    def __init__(self, case, stiffness, tag):
        self.spec = (case, stiffness, tag)

    def __enter__(self):
        global _TANGENT
        self.prev, _TANGENT = _TANGENT, (self.spec if _SEEDS is not None else None)
        return self

    def __exit__(self, *exc):
        global _TANGENT
        _TANGENT = self.prev


def _base_states(key):
    """(tag, states of the tangent scope's base model on key's grid) or None."""
    if _TANGENT is None or _SEEDS is None:
        return None
    case, stiffness, tag = _TANGENT
    base = _STATES.get((_mechanics(case), stiffness_digest(stiffness)) + key[2:])
    return None if base is None else (tag, base)


def _seeds_for(key):
    """The seeds of a solve on key's grid: the last model's states, or in a tangent scope with a
    step known (predictor, last model's states) (statics.static_path's seeds and fallback)."""
    if _SEEDS is None:
        return None
    last = _SEEDS.get(key[2:])
    tb = _base_states(key)
    if tb is not None:
        step = _STEPS.get((tb[0], key[2:]))
        if step is not None and step.shape == tb[1].shape:
            return (tb[1] + step, last)
    return last


def _seeded(key, solved) -> np.ndarray:
    """Keep a solve's states as the seeds of its grid (the latest solve); its carrier angles."""
    carrier, Q = solved
    if _SEEDS is not None:
        _SEEDS[key[2:]] = Q
        _STATES.pop(key, None)              # replaced, not kept: the latest solve's states
        _cached(_STATES, key, lambda: Q)
        tb = _base_states(key)
        if tb is not None and np.shape(Q) == np.shape(tb[1]):
            _STEPS[(tb[0], key[2:])] = Q - tb[1]
    return carrier


def seed_tangents(case, stiffness, records, n: int, columns: dict) -> int:
    """Predictors for Jacobian columns not yet taken in this seeding scope (a fit's first iterate):
    column tag's state change on each steady record's grid as the sum over its terms of coef x
    (states of that term's model - states of (case, stiffness)), where the library's unit models
    and the base are still held (_STATES); `columns`: {tag: [(coef, (case_j, stiffness_j)), ...]}.
    Only a start: the same equilibria to the Newton tolerance (tangent_seeds). Returns the count of
    (column, grid) predictors set."""
    if _SEEDS is None:
        return 0
    count = 0
    for key, _, ang, T, d, cond in _steady_grids(case, stiffness, records, n):
        base = _STATES.get(key)
        if base is None:
            continue
        for tag, terms in columns.items():
            if (tag, key[2:]) in _STEPS:
                continue
            step = np.zeros_like(base)
            for coef, (cj, sj) in terms:
                Q = _STATES.get(_carrier_key(cj, sj, ang, T, d, cond)[0])
                if Q is None or Q.shape != base.shape:
                    break
                step += coef * (Q - base)
            else:
                _STEPS[(tag, key[2:])] = step
                count += 1
    return count


def _steady_grids(case, stiffness, records, n: int):
    """(carrier key, mechanics, grid angles, torques, direction, condition) of each steady record's
    grid of (case, stiffness): what quasi_static_te keys its solve by."""
    for r in records:
        if not _steady(case, r):
            continue
        d, cond = r.direction, record_condition(r)
        ang = periodic_grid_deg(case, n, d)
        T = np.full(ang.shape, mechanism_torque(case, np.float64(r.torque_Nm), d, cond))
        key, mech, _ = _carrier_key(case, stiffness, ang, T, d, cond)
        yield key, mech, ang, T, d, cond


def _grid_jobs(case, stiffness, records, n: int, jobs: dict) -> None:
    """Add to `jobs` the steady records' grids of (case, stiffness) missing from the carrier cache,
    each with its seeds as the current seed scope gives them (_seeds_for)."""
    for key, mech, ang, T, d, _ in _steady_grids(case, stiffness, records, n):
        if key not in _CARRIERS and key not in jobs:
            jobs[key] = (mech, stiffness, ang, T, d, _seeds_for(key))


def _prefetch(case, stiffness, records, n: int, pool) -> None:
    """Solve the steady records' grids missing from the carrier cache on `pool`'s processes."""
    prefetch_models([(case, stiffness, None)], records, n, pool)


def prefetch_models(models, records, n: int, pool, lazy: bool = False):
    """Solve on `pool` every steady record's grid of every model in `models`, a list of (case,
    stiffness, tangent) with tangent None or the (base case, base stiffness, tag) of a Jacobian
    column (tangent_seeds): the fit's re-taken columns go to the workers as one batch instead of
    one model at a time (each model has only as many grids as records, fewer than a batch keeps two
    workers busy with). Seeds and the kept states are those the solves one by one would use, but
    for the fallback seeds (the last model solved before the batch rather than the previous column):
    the same equilibria to the Newton tolerance.

    Returns None once every grid is solved and cached; with `lazy`, right after submitting, a
    `ready(i)` that waits for models 0..i (None: all) and caches them, in the order given, as the
    eager call does (the same cache and seed stores, bit for bit): the caller works on model i
    while the workers solve the later ones (the Jacobian's columns, extension._jacobian). The
    caller must reach ready() for every model before it solves anything else."""
    if pool is None:
        return None
    batches = []
    jobs: dict = {}
    futures: dict = {}
    unsent: list = []                           # jobs held while the batch has fewer than two
    for case, stiffness, tangent in models:     # (models may be a generator: each model's grids go to
        mine: dict = {}                         # the workers as soon as it is built)
        with tangent_seeds(*tangent) if tangent is not None else contextlib.nullcontext():
            _grid_jobs(case, stiffness, records, n, mine)
        mine = {k: v for k, v in mine.items() if k not in jobs}
        jobs.update(mine)
        batches.append((tangent, list(mine)))
        unsent.extend(mine.items())
        if len(jobs) >= 2:                      # fewer: solved where they are asked for (no pool's worth)
            for k, (mech, stiff, ang, T, d, seeds) in unsent:
                futures[k] = pool.submit(_solve_grid, mech, stiff, ang, T, d, seeds, k[1])
            unsent.clear()
    if len(jobs) < 2:
        return None
    done = [0]

    def ready(i: int | None = None) -> None:
        upto = len(batches) if i is None else min(i + 1, len(batches))
        while done[0] < upto:              # kept in the order the models were given, in their scopes
            tangent, keys = batches[done[0]]
            with tangent_seeds(*tangent) if tangent is not None else contextlib.nullcontext():
                for k in keys:
                    _cached(_CARRIERS, k, lambda: _seeded(k, futures[k].result()))
            done[0] += 1
    if lazy:
        return ready
    ready()
    return None


def simulate_records(te_model: TEModel, case, stiffness, records, points_per_rev: int | None = None,
                     pool=None) -> list[np.ndarray]:
    """simulate_record for each record; with a process `pool` (concurrent.futures) and the
    project's model (quasi_static_te, possibly wrapped: `__wrapped__`), the steady records'
    grids are first solved in parallel (results identical: each grid is one deterministic solve)."""
    n = default_points_per_rev(case) if points_per_rev is None else int(points_per_rev)
    if pool is not None and getattr(te_model, "__wrapped__", te_model) is quasi_static_te:
        _prefetch(case, stiffness, records, n, pool)
    return [simulate_record(te_model, case, stiffness, r, n) for r in records]


def process_pool(workers: int | None):
    """A pool of `workers` local processes (fork: the compiled kernels are inherited), or None
    for one worker. The caller shuts it down."""
    import multiprocessing as mp
    import os
    from concurrent.futures import ProcessPoolExecutor
    n = (os.cpu_count() or 1) if workers is None else int(workers)
    if n <= 1 or "fork" not in mp.get_all_start_methods():
        return None
    from pipeline.sweep import die_with_parent
    return ProcessPoolExecutor(max_workers=n, mp_context=mp.get_context("fork"), initializer=die_with_parent,
                               initargs=(os.getpid(),))


def _steady(case, record: BenchRecord) -> bool:
    return record.torque_spread_Nm <= STEADY_TORQUE * case.rated_torque_Nm


def simulation_indices(record: BenchRecord, points_per_rev: int) -> np.ndarray:
    """Samples to simulate: those nearest a uniform grid of <= points_per_rev per output rev in
    output travel (not in sample index: sampling need not be uniform), first and last included."""
    travel = np.maximum.accumulate(np.abs(record.output_angle_deg - record.output_angle_deg[0]))
    n_pts = max(int(np.ceil(travel[-1] / 360.0 * points_per_rev)), 2)
    if len(travel) <= 1.5 * n_pts:   # no thinning worth its interpolation error
        return np.arange(len(travel))
    grid = np.linspace(0.0, travel[-1], n_pts + 1)
    idx = np.clip(np.searchsorted(travel, grid), 0, len(travel) - 1)
    return np.unique(np.r_[0, idx, len(travel) - 1])


def periodic_grid_deg(case, points_per_rev: int, direction: int) -> np.ndarray:
    """Input angles of one output revolution from 0 in the direction of motion (the solver's
    warm start follows the motion): the same grid for every record of that direction."""
    return direction * np.arange(points_per_rev) * (360.0 * case.ratio / points_per_rev)


def trig_interp(grid_values: np.ndarray, phase: np.ndarray, upsample: int = 64) -> np.ndarray:
    """Trigonometric interpolation of one period sampled uniformly (grid_values[k] at phase k / n)
    at any phase (periodic): zero-padded FFT to upsample x n points, then linear interpolation
    (error <= (2 pi k / (upsample n))^2 / 8 of a line at order k: 3e-4 at the Nyquist order)."""
    n = len(grid_values)
    c = np.fft.rfft(grid_values)
    m = upsample * n
    if n % 2 == 0:                   # split the Nyquist term between +- n/2
        c[-1] *= 0.5
    fine = np.fft.irfft(c, m) * (m / n)
    return np.interp(np.mod(phase, 1.0) * m, np.arange(m + 1), np.r_[fine, fine[0]])


def simulate_record(te_model: TEModel, case, stiffness, record: BenchRecord,
                    points_per_rev: int | None = None) -> np.ndarray:
    """Simulated TE [arcsec] at every sample of `record` (same input angle, torque, direction and
    condition). points_per_rev: the grid per output revolution (default_points_per_rev)."""
    n = default_points_per_rev(case) if points_per_rev is None else int(points_per_rev)
    cond = record_condition(record)
    if _steady(case, record):
        period = 360.0 * case.ratio                      # input degrees per output revolution
        d = record.direction
        grid = periodic_grid_deg(case, n, d)
        te = np.asarray(call_te_model(te_model, case, stiffness, grid, record.torque_Nm, d, cond), float)
        return trig_interp(te[::d] if d > 0 else np.r_[te[0], te[:0:-1]], record.input_angle_deg / period)
    idx = simulation_indices(record, n)
    ang = record.input_angle_deg[idx]
    te = call_te_model(te_model, case, stiffness, ang, record.output_torque_Nm[idx], record.direction, cond)
    order = np.argsort(ang)
    return np.interp(record.input_angle_deg, ang[order], np.asarray(te)[order])


def call_te_model(te_model: TEModel, case, stiffness, ang, torque, direction: int, cond: Condition):
    """te_model with the record's condition when it takes one (a five-argument TEModel is
    condition-blind, as the quasi-static model was before the seam)."""
    try:
        params = inspect.signature(te_model).parameters
        takes = "condition" in params or any(p.kind is p.VAR_KEYWORD for p in params.values())
    except (TypeError, ValueError):
        takes = False
    if takes:
        return te_model(case, stiffness, ang, torque, direction, condition=cond)
    return te_model(case, stiffness, ang, torque, direction)
