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
