"""The signature atlas: each as-built error source alone, at a stated unit size, through the model.

For every source of `sources(case)` (geometry.params.Errors, one part off: crank 1, pin 1, disc 1
where the error belongs to one part) the quasi-static model (dynamics.statics.quasi_static, no
inertia) is solved over one output revolution at a few torques and both directions, and the
signature is the TE change against the ideal build at the same input angles, per unit size. Its
order spectrum (cycles per output revolution), the dependence of the main line on torque (a
log-log slope) and on direction (forward vs backward complex amplitude), and the groups of
sources whose signatures a record cannot tell apart (`groups`) all come from the model.

Angle grid (`points_per_rev`): N points per output revolution, N the smallest divisor of zp zc
above 2 max_order (max_order = 4 zp: m = 1..4 lobes of the pin ring at m zc and 1..4 zp are
resolved; N = 390 for zp = 40). Every sample then sits at the same phase of the cycloid-pin mesh
(zp zc cycles per revolution, a multiple of N): the mesh ripple and all its harmonics fold onto
the mean instead of onto a line, so the lines are those of the TE at one mesh phase (a
stroboscopic sample once per N-th of a revolution); the first-stage mesh (zp z2 x) folds to
zp z2 mod N. ~0.5 s per revolution (390 static solves) on the stand-in stiffness, ~1.5 min for
the whole atlas (29 sources x 3 torques x 2 directions).

Kinematics the atlas shows (DESIGN.md): a pin-ring pattern of m lobes is swept by each disc's
load zone at m zc x, the discs' load zones 180 deg apart cancel odd m and add even m; everything
that turns with the carrier (cranks, holes, disc patterns, main-bearing runout) repeats exactly
after 1/zp revolution (the state turned by one pin pitch is the same state: the pin ring is
zp-fold symmetric and the first-stage mesh advances by z2 whole teeth), so it has lines only at
multiples of zp; 1 x comes from the reading (encoder/mounting runout) or from a carrier-side
pattern crossed with a pin-ring pattern (m zp - m zc = m).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from dynamics.reducer import build_model
from dynamics.statics import quasi_static

TORQUE_FRACTIONS = (0.1, 0.5, 1.0)      # of rated torque: light (few teeth), half, rated
DIRECTIONS = (1, -1)                    # forward, backward (the other flank loaded)
LINE_SHARE = 0.1                        # lines >= this share of the strongest are listed
MAX_LINES = 6
NEGLIGIBLE_ARCSEC = 1e-3                # a source whose every line and mean shift stays below: no signature
TORQUE_FLAT = 0.15                      # |d ln A / d ln T| below this: independent of torque
SAME_DIRECTION = 0.25                   # |A_fw - A_bw| below this share of max(|A|): same in both
GROUP_COSINE = 0.9                      # signatures this similar (complete linkage) share a group


@dataclass(frozen=True)
class Source:
    id: str
    description: str
    unit: str                  # of the unit size
    unit_size: float
    kind: str                  # "housing" (fixed in the housing), "carrier" (turns with it), "reading", "clearance"
    errors: Callable           # (case, size) -> keyword arguments of ReducerCase.with_errors


def _one(n: int, size: float, k: int = 0) -> list:
    v = [0.0] * n
    v[k] = size
    return v


def sources(case) -> tuple[Source, ...]:
    """The atlas's sources for `case`: every key of geometry.params.Errors, one part off where the
    error belongs to one part (crank 1, pin 1, disc 1), lobes m = 1..4 of the pin ring."""
    nc, nd, zp = case.carrier.crank_count, case.cycloid.disc_count, case.cycloid.zp
    out = [Source(f"pin_radial_lobes_m{m}", f"pin-ring radial position, {m} lobe{'s' * (m > 1)}", "um", 1.0,
                  "housing", lambda c, s, m=m: {"pin_radial_lobes": [[m, s, 0.0]]}) for m in (1, 2, 3, 4)]
    out += [Source(f"pin_stiffness_lobes_m{m}", f"pin support (groove) stiffness, {m} lobe{'s' * (m > 1)}",
                   "fraction of the law", 0.1, "housing",
                   lambda c, s, m=m: {"pin_stiffness_lobes": [[m, s, 0.0]]}) for m in (1, 2, 4)]
    out += [
        Source("per_pin_radial", "pin 1 radial position", "um", 1.0, "housing",
               lambda c, s: {"per_pin_radial_um": _one(zp, s)}),
        Source("per_pin_tangential", "pin 1 tangential position", "um", 1.0, "housing",
               lambda c, s: {"per_pin_tangential_um": _one(zp, s)}),
        Source("per_pin_radius", "pin 1 radius", "um", 1.0, "housing",
               lambda c, s: {"per_pin_radius_um": _one(zp, s)}),
        Source("pin_radius", "every pin's radius", "um", 1.0, "housing", lambda c, s: {"pin_radius_um": s}),
        Source("pin_circle_radius", "pin circle radius", "um", 1.0, "housing",
               lambda c, s: {"pin_circle_radius_um": s}),
        Source("pin_ring_tilt", "pin ring axis tilted (centre +-t at the two disc planes)", "um", 1.0, "housing",
               lambda c, s: {"pin_ring_tilt_um": s}),
        Source("disc_pitch_lobes_m1", "disc 1 cumulative pitch (1 lobe)", "um", 1.0, "carrier",
               lambda c, s: {"disc_pitch_lobes": [[1, 1, s, 0.0]]}),
        Source("disc_pitch_lobes_m2", "disc 1 pitch, 2 lobes", "um", 1.0, "carrier",
               lambda c, s: {"disc_pitch_lobes": [[1, 2, s, 0.0]]}),
        Source("disc_profile_lobes_m2", "disc 1 profile, 2 lobes (normal)", "um", 1.0, "carrier",
               lambda c, s: {"disc_profile_lobes": [[1, 2, s, 0.0]]}),
        Source("disc_profile", "disc 1 profile (uniform, material added)", "um", 1.0, "carrier",
               lambda c, s: {"disc_profile_um": _one(nd, s)}),
        Source("crank_eccentricity", "crank 1 eccentricity (both eccentrics)", "um", 1.0, "carrier",
               lambda c, s: {"crank_eccentricity_um": _one(nc, s)}),
        Source("eccentric_error", "crank 1, disc 1's eccentric radius", "um", 1.0, "carrier",
               lambda c, s: {"eccentric_error_um": _one(nc, s)}),
        Source("crank_timing", "crank 1 timing (eccentrics vs planet gear)", "arcmin", 1.0, "carrier",
               lambda c, s: {"crank_timing_arcmin": _one(nc, s)}),
        Source("crank_hole_radial", "crank hole 1 radial position (both discs)", "um", 1.0, "carrier",
               lambda c, s: {"crank_hole_position_um": _one(nc, s)}),
        Source("crank_hole_tangential", "crank hole 1 tangential position (both discs)", "um", 1.0, "carrier",
               lambda c, s: {"crank_hole_tangential_um": _one(nc, s)}),
        Source("bearing_hole_radial", "crank 1 bearing seat radial position (carrier)", "um", 1.0, "carrier",
               lambda c, s: {"output_bearing_hole_um": _one(nc, s)}),
        Source("bearing_hole_tangential", "crank 1 bearing seat tangential position (carrier)", "um", 1.0,
               "carrier", lambda c, s: {"output_bearing_hole_tangential_um": _one(nc, s)}),
        Source("main_bearing_runout", "main bearing runout (carrier axis, turning)", "um", 1.0, "carrier",
               lambda c, s: {"main_bearing_runout_um": s}),
        Source("output_coaxiality", "encoder / output mounting runout (reading)", "um", 1.0, "reading",
               lambda c, s: {"output_coaxiality_um": s}),
        *(Source(f"output_reading_lobes_m{m}", f"encoder / output mounting, {m} lobes (reading)", "um", 1.0,
                 "reading", lambda c, s, m=m: {"output_reading_lobes": [[m, s, 0.0]]}) for m in (2, 3)),
        Source("turning_arm_clearance", "needle bearing radial clearance", "um", 1.0, "clearance",
               lambda c, s: {"turning_arm_clearance_um": s}),
        Source("support_clearance", "crank support bearing radial clearance", "um", 1.0, "clearance",
               lambda c, s: {"support_clearance_um": s}),
    ]
    if nd > 1:
        out += [Source("disc_phase", "disc 2's profile turned against disc 1's", "um", 1.0, "carrier",
                       lambda c, s: {"disc_phase_um": s}),
                Source("eccentric_phase", "crank 1, eccentrics off 180 deg", "arcmin", 1.0, "carrier",
                       lambda c, s: {"eccentric_phase_arcmin": _one(nc, s)})]
    return tuple(out)


def points_per_rev(case, max_order: int | None = None) -> int:
    """Smallest divisor of zp zc above 2 max_order (default 4 zp): see the module docstring."""
    zp, zc = case.cycloid.zp, case.cycloid.zc
    top = 4 * zp if max_order is None else int(max_order)
    mesh = zp * zc
    return next((n for n in range(2 * top + 1, mesh + 1) if mesh % n == 0), max(mesh, 2 * top + 1))


def folded(order: int, n: int) -> int:
    """The order a line at `order` shows up at when sampled n times per revolution (aliasing)."""
    k = order % n
    return min(k, n - k)


def input_angles_deg(case, n: int) -> np.ndarray:
    """n input angles over one output revolution (uniform in output angle)."""
    return np.arange(n) * 360.0 * case.ratio / n


@dataclass(frozen=True)
class Signature:
    """TE change per unit size of one source. spectrum[d, t, k]: complex single-sided amplitude of
    order k (k >= 1: A cos(k theta + phase) has |c| = A; k = 0: the mean shift), direction d
    (DIRECTIONS), torque t. A bench cannot see a constant offset (its zero is free), so what is
    `observable` has the mean shift's average over all conditions removed: what is left of it are
    the differences between torques and directions (lost motion, wind-up)."""
    source: Source
    torques_Nm: tuple
    directions: tuple
    spectrum: np.ndarray

    @property
    def offset_arcsec(self) -> float:
        """The part no bench can see: the mean shift averaged over every condition."""
        return float(self.spectrum[:, :, 0].real.mean())

    @property
    def observable(self) -> np.ndarray:
        out = self.spectrum.copy()
        out[:, :, 0] -= self.offset_arcsec
        return out

    @property
    def peak_arcsec(self) -> float:
        return float(np.abs(self.observable).max())

    @property
    def negligible(self) -> bool:
        return self.peak_arcsec < NEGLIGIBLE_ARCSEC

    def amplitude(self, order: int) -> np.ndarray:
        """(directions, torques) amplitude of `order` [arcsec per unit] (order 0: |observable mean
        shift|)."""
        return np.abs(self.observable[:, :, order])

    def lines(self) -> list[int]:
        """Orders >= 1 whose largest amplitude (any condition) reaches LINE_SHARE of the strongest
        line, strongest first (at most MAX_LINES)."""
        a = np.abs(self.spectrum[:, :, 1:]).max(axis=(0, 1))
        if a.max() < NEGLIGIBLE_ARCSEC:
            return []
        idx = np.argsort(a)[::-1]
        return [int(k) + 1 for k in idx[:MAX_LINES] if a[k] >= LINE_SHARE * a.max()]

    def main_order(self) -> int:
        """The strongest line, or 0 when the observable mean shift is larger than every line."""
        return int(np.argmax(np.abs(self.observable).max(axis=(0, 1))))

    def torque_exponent(self, order: int) -> float:
        """d ln A / d ln T of `order`, forward, least squares over the torques."""
        a = np.maximum(self.amplitude(order)[0], 1e-12)
        if len(self.torques_Nm) < 2:
            return 0.0
        return float(np.polyfit(np.log(self.torques_Nm), np.log(a), 1)[0])

    def torque_dependence(self, order: int) -> str:
        e = self.torque_exponent(order)
        return "independent" if abs(e) < TORQUE_FLAT else ("grows" if e > 0 else "falls")

    def direction(self, order: int) -> dict:
        """Backward against forward at the largest torque: amplitude ratio, phase shift [deg] and
        a class: "same", "reverses" (opposite sign: e.g. lost motion), "shifted" (same size, other
        phase) or "differs"."""
        if len(self.directions) < 2:
            return {"class": "not computed"}
        fw, bw = self.observable[0, -1, order], self.observable[1, -1, order]
        big = max(abs(fw), abs(bw))
        if big < NEGLIGIBLE_ARCSEC:
            return {"class": "none"}
        ratio, shift = abs(bw) / max(abs(fw), 1e-30), float(np.degrees(np.angle(bw / fw))) if abs(fw) > 0 else 0.0
        if abs(fw - bw) <= SAME_DIRECTION * big:
            cls = "same"
        elif abs(fw + bw) <= SAME_DIRECTION * big:
            cls = "reverses"
        elif abs(ratio - 1.0) <= SAME_DIRECTION:
            cls = "shifted"
        else:
            cls = "differs"
        return {"class": cls, "amplitude_ratio": float(ratio), "phase_shift_deg": shift}

    def direction_dependence(self, order: int) -> str:
        return self.direction(order)["class"]

    def vector(self, flip: bool = False) -> np.ndarray:
        """What a record sees, for grouping: line amplitudes |c_k| (k >= 1) and the signed observable
        mean shift, every condition; flip negates the mean shift (the same source at minus its size)."""
        ob = self.observable
        mean = ob[:, :, 0].real * (-1.0 if flip else 1.0)
        return np.concatenate([mean.ravel(), np.abs(ob[:, :, 1:]).ravel()])


def te_spectrum(te_arcsec: np.ndarray) -> np.ndarray:
    """Complex single-sided spectrum of one revolution sampled uniformly (c[0] = mean)."""
    c = np.fft.rfft(np.asarray(te_arcsec, float)) / len(te_arcsec)
    c[1:] *= 2.0
    return c


def torques_Nm(case) -> tuple:
    return tuple(f * case.rated_torque_Nm for f in TORQUE_FRACTIONS)


def baseline(case, stiffness, angles_deg, torques, directions=DIRECTIONS) -> np.ndarray:
    """(directions, torques, n) TE [arcsec] of `case` as given: one quasi-static path per torque
    and direction (TE only: the pin forces are not evaluated). Module-level and of picklable
    arguments: one task of `atlas`'s pool (the sources' cases are given with their error)."""
    model = build_model(case, stiffness)
    return np.array([[quasi_static(model, angles_deg, T, d, pin_forces=False).te_arcsec for T in torques]
                     for d in directions])


def _with_source(case, source: Source, size: float):
    return case.with_errors(**source.errors(case, size))


def signature(case, stiffness, source: Source, angles_deg, torques, base_te, directions=DIRECTIONS,
              size: float | None = None, te: np.ndarray | None = None) -> Signature:
    """The source at `size` (default its unit size) through the model, per unit size (te: its
    `baseline`, when already solved)."""
    size = source.unit_size if size is None else size
    if te is None:
        te = baseline(_with_source(case, source, size), stiffness, angles_deg, torques, directions)
    spec = np.array([[te_spectrum(te[i, j] - base_te[i, j]) for j in range(len(torques))]
                     for i in range(len(directions))]) / (size / source.unit_size)
    return Signature(source, tuple(float(t) for t in torques), tuple(directions), spec)


def _solved(jobs, pool, done=None) -> list[np.ndarray]:
    """`baseline` of each job (its argument tuple), in order: on `pool` (a concurrent.futures
    executor) when given, else here; done(i) once job i's result is in (in order). Each path is
    one deterministic solve: the same bits either way."""
    futures = [pool.submit(baseline, *j) for j in jobs] if pool is not None else None
    out = []
    for i, j in enumerate(jobs):
        out.append(futures[i].result() if futures is not None else baseline(*j))
        if done is not None:
            done(i)
    return out


def similarity(a: Signature, b: Signature) -> float:
    """Cosine of the two `vector`s, the better of b against a and against a at minus its size."""
    vb = b.vector()
    nb = np.linalg.norm(vb)
    best = -1.0
    for flip in (False, True):
        va = a.vector(flip)
        best = max(best, float(va @ vb / max(np.linalg.norm(va) * nb, 1e-300)))
    return best


def groups(signatures, cosine: float = GROUP_COSINE) -> list[list[int]]:
    """Indices of signatures that share a signature: complete linkage on `similarity` (every pair
    in a group at least `cosine`); negligible ones form no group."""
    from scipy.cluster.hierarchy import fcluster, linkage
    live = [i for i, s in enumerate(signatures) if not s.negligible]
    if len(live) < 2:
        return [[i] for i in live]
    D = np.array([[1.0 - similarity(signatures[i], signatures[j]) for j in live] for i in live])
    D = np.clip(np.minimum(D, D.T), 0.0, 2.0)
    cond = D[np.triu_indices(len(live), 1)]
    labels = fcluster(linkage(cond, method="complete"), t=1.0 - cosine, criterion="distance")
    out: dict[int, list[int]] = {}
    for i, lab in zip(live, labels):
        out.setdefault(int(lab), []).append(i)
    return sorted(out.values(), key=lambda g: g[0])


def atlas(case, stiffness, source_list=None, n: int | None = None, torques=None, directions=DIRECTIONS,
          progress=None, pool=None) -> tuple[list[Signature], dict]:
    """Every source's signature; returns (signatures, grid description). pool: a process executor
    the sources' solves run on (the same result as without)."""
    n = points_per_rev(case) if n is None else int(n)
    torques = torques_Nm(case) if torques is None else tuple(torques)
    ang = input_angles_deg(case, n)
    src = sources(case) if source_list is None else tuple(source_list)
    jobs = [(case, stiffness, ang, torques, directions)]
    jobs += [(_with_source(case, s, s.unit_size), stiffness, ang, torques, directions) for s in src]
    done = None if progress is None else (lambda i: i and progress(i, len(src), src[i - 1].id))
    base, *tes = _solved(jobs, pool, done)
    out = [signature(case, stiffness, s, ang, torques, base, directions, te=te) for s, te in zip(src, tes)]
    zp, zc, z2 = case.cycloid.zp, case.cycloid.zc, case.stage1.z2
    grid = {"points_per_output_rev": n, "orders_resolved_max": n // 2,
            "mesh_order_zp_zc": zp * zc, "mesh_order_folds_to": folded(zp * zc, n),
            "stage1_mesh_order_zp_z2": zp * z2, "stage1_mesh_order_folds_to": folded(zp * z2, n),
            "torques_Nm": list(torques), "directions": list(directions), "solver": "quasi_static"}
    return out, grid


STRUCTURE_RIGID = 1e6          # the housing stiffened this much: the rigid-housing reference


def housing_structure(case, stiffness, torques=None, directions=DIRECTIONS, pool=None) -> Signature | None:
    """The elastic housing's own lines (no error: its bolt pattern makes the pin support stiffness
    vary around the ring): the ideal build's TE against the same build with the housing held rigid,
    per torque and direction, on a grid fine enough for the bolt lobes (n_b-fold pattern: lines at
    multiples of gcd(zp, n_b) zc, resolved up to 2 n_b zc). None when the stiffness has no housing."""
    if "housing" not in stiffness.parts:
        return None
    from math import gcd
    torques = torques_Nm(case) if torques is None else tuple(torques)
    lobe = gcd(case.cycloid.zp, case.housing.bolt_count)
    n = points_per_rev(case, max_order=max(4 * case.cycloid.zp, 2 * lobe * case.cycloid.zc))
    ang = input_angles_deg(case, n)
    te, rigid = _solved([(case, stiffness, ang, torques, directions),
                         (case, stiffness.stiffened("housing", STRUCTURE_RIGID), ang, torques, directions)], pool)
    spec = np.array([[te_spectrum(te[i, j] - rigid[i, j]) for j in range(len(torques))]
                     for i in range(len(directions))])
    src = Source("housing_structure", f"the elastic housing as built: {case.housing.bolt_count} bolts, pin support "
                 f"stiffness lobes at multiples of {lobe} (no error: the structure itself)", "as built", 1.0,
                 "structure", lambda c, s: {})
    return Signature(src, tuple(float(t) for t in torques), tuple(directions), spec)
