"""Monte Carlo tolerance analysis on the four-bar model (beyond paper 000).

Every build draws all error sources of the crank pair from stated tolerance bands: the
eccentricity of crank A and of crank B (l1, l3), the disc crank-hole spacing (l2), the carrier
bearing-hole spacing (l4), each uniform in +-band (no process knowledge, so no bell curve is
assumed) or normal with band = 3 sigma; the radial clearances of the turning-arm and support
bearings of each crank, uniform in [0, max]. Its output-angle error is evaluated with
`dynamics.fourbar` at one crank angle (the paper's 90 deg), rigid (geometry, clearances taken up
along the load direction, no deflection) and elastic at a stated torque (plus the joint
compliance), with forces fixed at those of the nominal build (micron errors barely move the
load sharing). The elastic error includes the ideal build's windup (torsional stiffness, not
accuracy); the summary also gives it with that windup removed.

Determinism: block b of BLOCK consecutive samples draws from its own stream,
SeedSequence(seed, spawn_key=(b,)), and chunks are whole blocks, so results depend on (seed, i)
only: never on chunking, worker count or where a chunk runs (local or Dask). (One stream per
sample would cost ~40 us of generator set-up each, more than the physics.)

Limits: one disc, one crank pair, one crank angle; the yield is the share of builds whose error
at that point stays within the limit, not a full-revolution peak-to-peak.

Full model (`tolerance --model full`, `full_monte_carlo`): every build draws every as-built error
of geometry.params.Errors from the case's [tolerances] bands (`draw_build`: per crank, per
eccentric, per hole, per pin, per disc, the pin-ring lobes m = 1..4, clearances, runouts) and is
solved by the lumped model quasi-statically (dynamics.statics.quasi_static, no inertia) over one
output revolution at the signature atlas's grid (dynamics.signatures.points_per_rev: 390 points
for zp = 40, orders up to 195 >= 4 zc resolved, every sample at the same cycloid-pin mesh phase,
so the ideal build's mesh ripple folds onto the mean): TE peak-to-peak and sigma (offset-free),
its lines at the characteristic orders, and the catalog test at input 0 (dynamics.catalog:
lost motion at +-3 %, rigidity 50-100 % rated). The encoder/mounting coaxiality is a
reading, not the reducer: the reducer's TE and the TE a bench reads (with it) are both kept.
Sensitivity: one band at a time on the first builds (the same draws, every other band zero):
each band's share of the summed TE variance ranks which band to tighten first; a sum well
below the full variance would flag interaction. Determinism: build i draws from its own stream
SeedSequence(seed, spawn_key=(FULL_STREAM, i)) (the physics costs ~0.3 s a build, the stream
set-up 40 us), so results never depend on chunking or where a chunk runs.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Callable, Sequence

import numpy as np

from dynamics.fourbar import (ARCSEC_PER_RAD, Build, FourBarError, JointCompliance, PairGeometry,
                              PairLoads, rigid_and_elastic)

DISTRIBUTIONS = ("uniform", "normal")
MAX_BAND_UM = 100.0  # bands and clearances beyond 0.1 mm are no longer a tolerance of a precision reducer
BLOCK = 250          # samples per random stream; chunk sizes are rounded up to a multiple
DRAW_COLUMNS = ("d_l1_um", "d_l3_um", "d_l2_um", "d_l4_um", "turning_arm_clearance_a_um",
                "turning_arm_clearance_b_um", "support_clearance_a_um", "support_clearance_b_um")


@dataclass(frozen=True)
class ToleranceBands:
    """Tolerance bands [um]. Defaults: IT5-ish +-5 um on the three spacings/eccentricities (IT5 is
    11-13 um wide at 30-80 mm), a C2-class needle-bearing clearance up to 5 um, preloaded support
    bearings up to 2 um."""
    eccentricity_um: float = 5.0
    crank_hole_um: float = 5.0
    output_hole_um: float = 5.0
    turning_arm_clearance_um: float = 5.0
    support_clearance_um: float = 2.0
    distribution: str = "uniform"

    def __post_init__(self):
        for name in ("eccentricity_um", "crank_hole_um", "output_hole_um",
                     "turning_arm_clearance_um", "support_clearance_um"):
            v = getattr(self, name)
            if not (math.isfinite(v) and 0.0 <= v <= MAX_BAND_UM):
                raise FourBarError(f"tolerance band {name} = {v!r}: allowed 0 to {MAX_BAND_UM:g} um")
        if self.distribution not in DISTRIBUTIONS:
            raise FourBarError(f"distribution = {self.distribution!r}: allowed {', '.join(DISTRIBUTIONS)}")


def draw(bands: ToleranceBands, seed: int, start: int, stop: int) -> np.ndarray:
    """(stop - start, 8) draws in DRAW_COLUMNS order, um; sample i from block stream (seed, i // BLOCK)."""
    sym = np.array([bands.eccentricity_um, bands.eccentricity_um, bands.crank_hole_um, bands.output_hole_um])
    clr = np.array([bands.turning_arm_clearance_um] * 2 + [bands.support_clearance_um] * 2)
    parts = []
    for blk in range(start // BLOCK, (stop - 1) // BLOCK + 1):
        rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(blk,)))
        if bands.distribution == "uniform":
            s = rng.uniform(-1.0, 1.0, (BLOCK, 4))
        else:
            s = np.clip(rng.standard_normal((BLOCK, 4)) / 3.0, -1.0, 1.0)   # band = 3 sigma, truncated
        c = rng.uniform(0.0, 1.0, (BLOCK, 4))
        a, b = max(start - blk * BLOCK, 0), min(stop - blk * BLOCK, BLOCK)
        parts.append(np.hstack([s[a:b] * sym, c[a:b] * clr]))
    return np.vstack(parts)


@dataclass(frozen=True)
class ChunkTask:
    """Everything a chunk needs (picklable: ships to local processes or Dask workers)."""
    geom: PairGeometry
    loads: PairLoads
    compliance: JointCompliance
    bands: ToleranceBands
    seed: int


def evaluate_chunk(task: ChunkTask, start: int, stop: int) -> np.ndarray:
    """(stop - start, 8 + 2): the draws plus rigid and elastic output error [arcsec]."""
    d = draw(task.bands, task.seed, start, stop)
    mm = d * 1e-3
    build = Build(d_l1_mm=mm[:, 0], d_l3_mm=mm[:, 1], d_l2_mm=mm[:, 2], d_l4_mm=mm[:, 3],
                  turning_arm_clearance_mm=(mm[:, 4], mm[:, 5]),
                  support_clearance_mm=(mm[:, 6], mm[:, 7]))
    re = rigid_and_elastic(task.geom, build, task.loads, task.compliance)
    return np.column_stack([d, re.rigid.output_error_rad * ARCSEC_PER_RAD,
                            re.elastic.output_error_rad * ARCSEC_PER_RAD])


def chunk_bounds(samples: int, chunk_size: int) -> list[tuple[int, int]]:
    if samples < 1:
        raise FourBarError(f"samples = {samples}: need at least 1")
    if chunk_size < 1:
        raise FourBarError(f"chunk size = {chunk_size}: need at least 1")
    step = -(-chunk_size // BLOCK) * BLOCK     # whole blocks: a block never spans two tasks
    return [(a, min(a + step, samples)) for a in range(0, samples, step)]


@dataclass(frozen=True)
class MonteCarloResult:
    samples: np.ndarray               # (N, 10): DRAW_COLUMNS, rigid_error_arcsec, elastic_error_arcsec
    seed: int
    bands: ToleranceBands
    limit_arcsec: float
    nominal_elastic_arcsec: float     # elastic error of the ideal build (the load windup)
    meta: dict = field(default_factory=dict)

    columns = DRAW_COLUMNS + ("rigid_error_arcsec", "elastic_error_arcsec")

    @property
    def rigid_arcsec(self) -> np.ndarray:
        return self.samples[:, -2]

    @property
    def elastic_arcsec(self) -> np.ndarray:
        return self.samples[:, -1]

    def summary(self) -> dict:
        def stats(x):
            x = x[np.isfinite(x)]
            q = np.percentile(np.abs(x), [50, 95, 99]) if len(x) else [np.nan] * 3
            return {"mean_arcsec": float(np.mean(x)), "std_arcsec": float(np.std(x)),
                    "min_arcsec": float(np.min(x)), "max_arcsec": float(np.max(x)),
                    "abs_p50_arcsec": float(q[0]), "abs_p95_arcsec": float(q[1]),
                    "abs_p99_arcsec": float(q[2]),
                    "share_within_limit": float(np.mean(np.abs(x) <= self.limit_arcsec))}
        r, e = self.rigid_arcsec, self.elastic_arcsec
        return {"samples": int(len(self.samples)), "seed": self.seed,
                "not_assembled": int(np.sum(~np.isfinite(r) | ~np.isfinite(e))),
                "limit_arcsec": self.limit_arcsec,
                "bands": {k: getattr(self.bands, k) for k in self.bands.__dataclass_fields__},
                "rigid": stats(r), "elastic": stats(e),
                "elastic_minus_nominal_windup": stats(e - self.nominal_elastic_arcsec),
                "nominal_elastic_windup_arcsec": self.nominal_elastic_arcsec, **self.meta}


def monte_carlo(task: ChunkTask, samples: int, *, chunk_size: int = 20000,
                map_chunks: Callable[[Callable, Sequence[tuple]], list] | None = None,
                limit_arcsec: float = 60.0) -> MonteCarloResult:
    """Run all chunks through map_chunks(func, [(task, start, stop), ...]) (default: in process)."""
    if not (math.isfinite(limit_arcsec) and limit_arcsec > 0.0):
        raise FourBarError(f"accuracy limit = {limit_arcsec!r} arcsec: allowed > 0")
    bounds = chunk_bounds(samples, chunk_size)
    tasks = [(task, a, b) for a, b in bounds]
    parts = map_chunks(evaluate_chunk, tasks) if map_chunks else [evaluate_chunk(*t) for t in tasks]
    nominal = rigid_and_elastic(task.geom, Build(), task.loads, task.compliance)
    return MonteCarloResult(np.vstack(parts), task.seed, task.bands, float(limit_arcsec),
                            float(nominal.elastic.output_error_rad) * ARCSEC_PER_RAD,
                            {"torque_Nm": task.loads.torque_Nm,
                             "crank_angle_deg": math.degrees(task.loads.beta1_rad),
                             "force_source": task.loads.source, "chunks": len(bounds)})


# ---------------------------------------------------------------- full model

ARCMIN_PER_RAD = 180 * 60 / math.pi
FULL_STREAM = 1                     # spawn-key prefix of the full model's per-build streams
FULL_CHUNK = 10                     # builds per task by default: ~3 s, so pool start-up stays small
PIN_RING_LOBES = (1, 2, 3, 4)       # m lobes of the pin ring drawn (lines at m zc)
FULL_METRICS = ("te_pp_arcsec", "te_sigma_arcsec", "bench_te_pp_arcsec", "bench_te_sigma_arcsec",
                "bench_line_1x_arcsec", "lost_motion_arcmin", "rigidity_Nm_per_arcmin")
LOST_MOTION_LIMIT_ARCMIN = 1.0      # catalog: lost motion <= 1 arcmin at +-3 % rated


def band_names(case) -> tuple[str, ...]:
    """The [tolerances] bands that apply to the case (disc phase and pin-ring tilt need two discs)."""
    import dataclasses
    from geometry.params import Tolerances
    names = tuple(f.name for f in dataclasses.fields(Tolerances))
    return names if case.cycloid.disc_count > 1 else tuple(n for n in names
                                                            if n not in ("disc_phase_um", "pin_ring_tilt_um"))


def line_orders(case, n_points: int) -> tuple[int, ...]:
    """Characteristic orders (DESIGN.md) whose lines are kept: 1, n_crank, zc, zp, 2 zc, 2 zp, 4 zc."""
    c, nc = case.cycloid, case.carrier.crank_count
    return tuple(sorted({k for k in (1, nc, c.zc, c.zp, 2 * c.zc, 2 * c.zp, 4 * c.zc) if k <= n_points // 2}))


def check_tolerances(case) -> None:
    """Bands whose crank angle errors would leave geometry.params' range are refused up front:
    the eccentric phase reaches 2 b_ecc / E, the crank timing b_ecc / E + b_timing / r_planet."""
    from geometry.params import ANGLE_ERROR_ARCMIN_MAX, CaseError
    tl, E_um = case.tolerances, case.cycloid.eccentricity_mm * 1e3
    r2_um = case.stage1.module_mm * case.stage1.z2 / 2 * 1e3
    worst = {"eccentricity_um": 2 * tl.eccentricity_um / E_um,
             "crank_timing_um": tl.eccentricity_um / E_um + tl.crank_timing_um / r2_um}
    for key, rad in worst.items():
        if rad * ARCMIN_PER_RAD > ANGLE_ERROR_ARCMIN_MAX:
            raise CaseError(f"{case.source + ': ' if case.source else ''}[tolerances] {key} = "
                            f"{getattr(tl, key):g}: gives crank angle errors up to {rad * ARCMIN_PER_RAD:.3g} "
                            f"arcmin; allowed bands that keep them within {ANGLE_ERROR_ARCMIN_MAX:g} arcmin")




def _sym(rng, shape, distribution: str) -> np.ndarray:
    """Unit symmetric deviations in [-1, 1]: uniform, or normal with the band at 3 sigma (truncated)."""
    if distribution == "uniform":
        return rng.uniform(-1.0, 1.0, shape)
    return np.clip(rng.standard_normal(shape) / 3.0, -1.0, 1.0)


def draw_build(case, distribution: str, seed: int, i: int) -> dict[str, dict]:
    """Build i's errors per band: {band: keyword arguments of ReducerCase.with_errors}. Every band is
    drawn, in a fixed order, whatever its width (a zero band gives zeros), so switching bands off
    for the sensitivity leaves the others' numbers unchanged."""
    rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(FULL_STREAM, int(i))))
    tl, c = case.tolerances, case.cycloid
    nc, nd, zp = case.carrier.crank_count, c.disc_count, c.zp
    E_um, r2_um = c.eccentricity_mm * 1e3, case.stage1.module_mm * case.stage1.z2 / 2 * 1e3
    u = lambda shape: _sym(rng, shape, distribution)  # noqa: E731
    arcmin = lambda um, r_um: (um / r_um * ARCMIN_PER_RAD).tolist()  # noqa: E731
    out = {}
    # each eccentric centre (disc d, crank j): radial -> eccentricity, tangential -> angle about the crank
    rad, tan = u((nd, nc)) * tl.eccentricity_um, u((nd, nc)) * tl.eccentricity_um
    ecc = {"crank_eccentricity_um": rad[-1].tolist(), "crank_timing_arcmin": arcmin(tan[0], E_um)}
    if nd > 1:
        ecc |= {"eccentric_error_um": (rad[0] - rad[1]).tolist(),
                "eccentric_phase_arcmin": arcmin(tan[1] - tan[0], E_um)}
    out["eccentricity_um"] = ecc
    out["crank_timing_um"] = {"crank_timing_arcmin": arcmin(u(nc) * tl.crank_timing_um, r2_um)}
    out["crank_hole_um"] = {"crank_hole_position_um": (u(nc) * tl.crank_hole_um).tolist(),
                            "crank_hole_tangential_um": (u(nc) * tl.crank_hole_um).tolist()}
    out["bearing_hole_um"] = {"output_bearing_hole_um": (u(nc) * tl.bearing_hole_um).tolist(),
                              "output_bearing_hole_tangential_um": (u(nc) * tl.bearing_hole_um).tolist()}
    out["pin_position_um"] = {"per_pin_radial_um": (u(zp) * tl.pin_position_um).tolist(),
                              "per_pin_tangential_um": (u(zp) * tl.pin_position_um).tolist()}
    out["pin_radius_um"] = {"per_pin_radius_um": (u(zp) * tl.pin_radius_um).tolist()}
    amp, ph = rng.uniform(0, 1, len(PIN_RING_LOBES)) * tl.pin_ring_lobes_um, rng.uniform(0, 360, len(PIN_RING_LOBES))
    out["pin_ring_lobes_um"] = {"pin_radial_lobes": [[m, a, p] for m, a, p in zip(PIN_RING_LOBES, amp, ph)
                                                     if m <= zp // 2]}
    amp, ph = rng.uniform(0, 1, nd) * tl.disc_pitch_um, rng.uniform(0, 360, nd)
    out["disc_pitch_um"] = {"disc_pitch_lobes": [[d + 1, 1, amp[d], ph[d]] for d in range(nd)]}
    out["disc_profile_um"] = {"disc_profile_um": (u(nd) * tl.disc_profile_um).tolist()}
    phase = float(u(1)[0]) * tl.disc_phase_um
    if nd > 1:
        out["disc_phase_um"] = {"disc_phase_um": phase}
    clr = rng.uniform(0, 1, 2)
    out["turning_arm_clearance_um"] = {"turning_arm_clearance_um": clr[0] * tl.turning_arm_clearance_um}
    out["support_clearance_um"] = {"support_clearance_um": clr[1] * tl.support_clearance_um}
    run = rng.uniform(0, 1, 2)
    out["main_bearing_runout_um"] = {"main_bearing_runout_um": run[0] * tl.main_bearing_runout_um,
                                     "main_bearing_runout_phase_deg": run[1] * 360.0}
    coax = rng.uniform(0, 1, 2)
    out["output_coaxiality_um"] = {"output_coaxiality_um": coax[0] * tl.output_coaxiality_um,
                                   "output_coaxiality_phase_deg": coax[1] * 360.0}
    if nd > 1:   # drawn last: the bands before it keep the numbers they had without it
        tilt = rng.uniform(0, 1, 2)
        out["pin_ring_tilt_um"] = {"pin_ring_tilt_um": tilt[0] * tl.pin_ring_tilt_um,
                                   "pin_ring_tilt_phase_deg": tilt[1] * 360.0}
    return out


def merge_errors(parts) -> dict:
    """One with_errors() keyword set from several bands' (a key two bands share is summed)."""
    out: dict = {}
    for part in parts:
        for k, v in part.items():
            if k not in out:
                out[k] = v
            elif isinstance(v, list) and v and isinstance(v[0], list):
                out[k] = out[k] + v
            elif isinstance(v, list):
                out[k] = [a + b for a, b in zip(out[k], v)]
            else:
                out[k] = out[k] + v
    return out


@dataclass(frozen=True)
class FullTask:
    """What a chunk of full-model builds needs (picklable: local processes or Dask workers)."""
    case: object                      # geometry.params.ReducerCase (its [tolerances] are the bands)
    stiffness: object                 # fem.stiffness.StiffnessModel
    distribution: str
    seed: int
    torque_Nm: float                  # TE revolution, forward
    n_points: int                     # per output revolution


def catalog_point(model) -> tuple[float, float]:
    """(lost motion [arcmin], torsional rigidity [N m / arcmin]) at input 0 by dynamics.catalog's
    definitions (angle between +-3 % rated; 0.5 rated over the angle from 50 to 100 %, mean of the
    two directions), each torque solved alone from the touching pose: the catalog's continuous
    sweep also passes +-0.01 % and 0.5 % rated, where builds with clearances float in their free
    play and its warm-started solves fail on ~1 build in 6 (1 in 40 this way)."""
    from dynamics.statics import solve_static
    rated = model.case.rated_torque_Nm
    ang = {f: solve_static(model, 0.0, f * rated).output_angle_deg * 60.0 for f in (0.03, -0.03, 0.5, 1, -0.5, -1)}
    rigidity = np.mean([0.5 * rated / abs(ang[s] - ang[0.5 * s]) for s in (1, -1)])
    return abs(ang[0.03] - ang[-0.03]), float(rigidity)


def evaluate_build(task: FullTask, errors: dict) -> np.ndarray:
    """FULL_METRICS then the reducer's line amplitudes at `line_orders` [arcsec] of one build;
    NaN where no static equilibrium is found (everywhere when the revolution fails, the catalog
    figures alone when only they do) or the build is refused (an interference beyond the laws)."""
    from dynamics.reducer import DynamicsError, build_model
    from dynamics.signatures import input_angles_deg, te_spectrum
    from dynamics.statics import quasi_static
    from geometry.artifacts import InputError
    case = task.case
    orders = line_orders(case, task.n_points)
    row = np.full(len(FULL_METRICS) + len(orders), np.nan)
    failed = (DynamicsError, InputError, np.linalg.LinAlgError)   # singular: a body left unheld
    reading = {k: errors.pop(k) for k in ("output_coaxiality_um", "output_coaxiality_phase_deg") if k in errors}
    try:
        built = case.with_errors(**errors)
        model = build_model(built, task.stiffness)
        ang = input_angles_deg(case, task.n_points)
        res = quasi_static(model, ang, task.torque_Nm)
    except failed:
        return row
    te = res.te_arcsec
    carrier = np.deg2rad(res.output_angle_deg)          # no reading error in `model`
    bench = build_model(built.with_errors(**reading), task.stiffness) if reading else model
    bench_te = np.rad2deg(bench.measured_output_rad(carrier) - np.deg2rad(ang) / model.ratio) * 3600.0
    row[:5] = np.ptp(te), np.std(te), np.ptp(bench_te), np.std(bench_te), abs(te_spectrum(bench_te)[1])
    row[len(FULL_METRICS):] = np.abs(te_spectrum(te))[list(orders)]
    try:
        row[5:7] = catalog_point(model)
    except failed:
        pass
    return row


def evaluate_full_chunk(task: FullTask, start: int, stop: int, only: str | None = None) -> np.ndarray:
    """(stop - start, metrics) for builds start..stop-1; `only`: that band alone (sensitivity),
    "" : the ideal build (no band)."""
    rows = []
    for i in range(start, stop):
        bands = draw_build(task.case, task.distribution, task.seed, i)
        keep = bands if only is None else {k: v for k, v in bands.items() if k == only}
        rows.append(evaluate_build(task, merge_errors(keep.values())))
    return np.array(rows)


@dataclass(frozen=True)
class FullResult:
    samples: np.ndarray                       # (N, metrics): FULL_METRICS + line columns
    nominal: np.ndarray                       # (metrics,) the ideal build
    sensitivity: dict                         # band -> (K, metrics), that band alone
    columns: tuple
    limit_arcsec: float
    meta: dict = field(default_factory=dict)

    def column(self, name: str, rows: np.ndarray | None = None) -> np.ndarray:
        return (self.samples if rows is None else rows)[:, self.columns.index(name)]

    def summary(self) -> dict:
        def stats(x):
            x = x[np.isfinite(x)]
            if not len(x):
                return {}
            p = np.percentile(x, [5, 50, 95])
            return {"mean": float(np.mean(x)), "std": float(np.std(x)), "min": float(np.min(x)),
                    "p5": float(p[0]), "p50": float(p[1]), "p95": float(p[2]), "max": float(np.max(x))}

        lm, pp, bpp = (self.column(c) for c in ("lost_motion_arcmin", "te_pp_arcsec", "bench_te_pp_arcsec"))
        solved = np.isfinite(lm)
        share = lambda m, of: float(np.sum(m & of) / max(np.sum(of), 1))  # noqa: E731
        everyone = np.ones(len(lm), bool)
        with np.errstate(invalid="ignore"):     # NaN (not solved) compares False: never within
            good_lm, good_pp, good_bpp = lm <= LOST_MOTION_LIMIT_ARCMIN, pp <= self.limit_arcsec, bpp <= self.limit_arcsec
        return {
            "samples": int(len(lm)), "te_not_solved": int(np.sum(~np.isfinite(pp))),
            "catalog_not_solved": int(np.sum(~solved)),
            "limit_te_pp_arcsec": self.limit_arcsec, "limit_lost_motion_arcmin": LOST_MOTION_LIMIT_ARCMIN,
            "distributions": {c: stats(self.column(c)) for c in self.columns},
            "nominal": {c: float(v) for c, v in zip(self.columns, self.nominal)},
            "yield": {"te_pp": share(good_pp, everyone), "bench_te_pp": share(good_bpp, everyone),
                      "lost_motion": share(good_lm, everyone), "lost_motion_of_solved": share(good_lm, solved),
                      "lost_motion_and_te_pp": share(good_lm & good_pp, everyone),
                      "note": "shares of all builds (a build not solved counts as failing); "
                              "lost_motion_of_solved: of the builds whose catalog test was solved"},
            "sensitivity": self.ranking(), **self.meta}

    def ranking(self) -> list[dict]:
        """Bands by their share of the summed TE variance when alone (bench TE: the reading counts),
        largest first, with their mean TE sigma, p-p and lost-motion change against the ideal build."""
        # independent contributions add in variance: a band's own is its builds' minus the ideal build's
        v0 = self.nominal[self.columns.index("bench_te_sigma_arcsec")] ** 2
        var = {b: max(float(np.nanmean(self.column("bench_te_sigma_arcsec", r) ** 2)) - v0, 0.0)
               for b, r in self.sensitivity.items()}
        total = sum(v for v in var.values() if np.isfinite(v)) or 1.0
        lm0 = self.nominal[self.columns.index("lost_motion_arcmin")]
        full_var = float(np.nanmean(self.column("bench_te_sigma_arcsec") ** 2)) - v0
        out = [{"band": b, "te_variance_share": var[b] / total,
                "te_sigma_mean_arcsec": float(np.nanmean(self.column("bench_te_sigma_arcsec", r))),
                "te_pp_mean_arcsec": float(np.nanmean(self.column("bench_te_pp_arcsec", r))),
                "lost_motion_change_mean_arcmin": float(np.nanmean(self.column("lost_motion_arcmin", r)) - lm0),
                "builds": int(len(r)), "not_solved": int(np.sum(~np.isfinite(r[:, 0]))),
                "sum_over_full_variance": total / full_var if full_var > 0 else float("nan")}
               for b, r in self.sensitivity.items()]
        return sorted(out, key=lambda d: -d["te_variance_share"] if np.isfinite(d["te_variance_share"]) else 1.0)


def full_tasks(task: FullTask, samples: int, chunk_size: int, sensitivity_builds: int) -> list[tuple]:
    """Chunk tasks (task, start, stop, only): the builds, then each band alone on the first builds."""
    if samples < 1:
        raise FourBarError(f"samples = {samples}: need at least 1")
    if chunk_size < 1:
        raise FourBarError(f"chunk size = {chunk_size}: need at least 1")
    out = [(task, a, min(a + chunk_size, samples), None) for a in range(0, samples, chunk_size)]
    k = min(sensitivity_builds, samples)
    for band in band_names(task.case):
        if k and getattr(task.case.tolerances, band) > 0:
            out += [(task, a, min(a + chunk_size, k), band) for a in range(0, k, chunk_size)]
    return out


def full_monte_carlo(task: FullTask, samples: int, *, chunk_size: int = FULL_CHUNK, sensitivity_builds: int = 0,
                     map_chunks: Callable[[Callable, Sequence[tuple]], list] | None = None,
                     limit_arcsec: float = 60.0) -> FullResult:
    """Every build (and the one-band-at-a-time sensitivity builds) through map_chunks(func, tasks)."""
    check_tolerances(task.case)
    tasks = full_tasks(task, samples, chunk_size, sensitivity_builds)
    parts = map_chunks(evaluate_full_chunk, tasks) if map_chunks else [evaluate_full_chunk(*t) for t in tasks]
    main = np.vstack([p for p, t in zip(parts, tasks) if t[3] is None])
    sens: dict = {}
    for p, t in zip(parts, tasks):
        if t[3] is not None:
            sens[t[3]] = np.vstack([sens[t[3]], p]) if t[3] in sens else p
    nominal = evaluate_full_chunk(task, 0, 1, "")[0]
    orders = line_orders(task.case, task.n_points)
    cols = FULL_METRICS + tuple(f"line_{k}x_arcsec" for k in orders)
    return FullResult(main, nominal, sens, cols, float(limit_arcsec),
                      {"torque_Nm": task.torque_Nm, "points_per_output_rev": task.n_points,
                       "line_orders": list(orders), "distribution": task.distribution, "seed": task.seed,
                       "sensitivity_builds_per_band": min(sensitivity_builds, samples)})
