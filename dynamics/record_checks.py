"""The checks a metrologist makes on a bench record before anything is read from it.

Pure functions over a record's arrays (and the few reducer figures each bound needs); each returns
what it found and, where the data stays usable, the repaired arrays. A `Finding` is one line that
names the record, the samples (0-based data-row index) and what was done; `severity` "error" means
the record cannot be used as it is (the caller refuses it, exit 2), "warning" that it was repaired.
The caller (pipeline.diagnosis.inputs) prints warnings on stderr and keeps them in the diagnosis'
notes. Checks, with their bounds and the input that triggers each:

  time unit   the input speed the samples give (median of |d input angle / dt|) against the
              record's `# input_speed_rpm:` comment: equal within UNIT_TOL -> nothing; a factor of
              1e-3, 1e-6 or 60 off (time in ms, us or minutes) -> time converted to seconds,
              warning; any other disagreement -> error. Without the comment: above
              MAX_SPEED_FACTOR x the case's rated input speed -> error; 1/1000 of the case's
              input speed (within a factor 2, below 1/100 of it: time in ms, or a real slow
              run) -> error asking the record to state its speed (the two readings differ by 1000
              and nothing in the record tells which).
  glitches    an encoder glitch is a sample whose TE leaves the running median of its
              GLITCH_WINDOW neighbours by more than the smaller of two bounds:
              (a) physics: what the reducer can do between two samples. The output can move
                  against its input only by its lost motion plus its wind-up, both ways, at the
                  momentary torque: range = LM + 2 T_mom / K; and no faster than the elastic
                  energy at T_mom allows (T_mom^2 / 2K = J v^2 / 2 with J the load inertia):
                  v_max = T_mom / sqrt(K J), so over one sample period dt at most v_max dt
                  (K the case's reference rigidity, catalog or bench; the kinematic TE of the
                  gears changes by < 0.1 arcsec per sample at any bench rate and is left out);
              (b) the record's own scatter: GLITCH_SIGMAS robust sigmas (95th percentile / 1.96
                  of the deviations; the MAD collapses on quantised encoders), floored at
                  MIN_NOISE_ARCSEC. (b) catches an input-encoder glitch, which reaches the TE
                  divided by the ratio, in a quiet record.
              Repair: each glitch sample's angles are replaced by linear interpolation in time
              between the nearest good samples (warning naming the samples); more than
              MAX_GLITCH_SHARE of the record -> error (the encoder signal is unusable).
  gaps        samples missing from the record's clock (the median time step): a step of n
              median steps drops n - 1 samples (steps under 1.5 median steps are jitter). The
              record is resampled onto its clock by linear interpolation in time (warning with
              the count, share and the largest gap) as long as no gap spans more than one period
              of the crank order (360 / zp deg of output: beyond it a whole cycle of the line
              that names the crank and pin causes is unmeasured) and at most MAX_MISSING_SHARE
              of the samples are missing; beyond either -> error.
  torque      a comment `# output_torque_Nm:` (or `torque_Nm:`) must agree with the torque
              column's median within TORQUE_TOL of it or TORQUE_TOL_RATED x the rated torque (a
              magnitude when the comment is unsigned); a comment naming another column of the
              record (e.g. `# oil_temperature_C: 25` beside an oil_temperature_C column) must
              agree with that column's median within COLUMN_TOL (relative) -> otherwise error.
  wind-up     a forward and a backward record sharing one encoder zero at one loaded torque:
              a load that resists the motion makes the output lag in both directions (forward
              mean TE below backward by the lost motion plus twice the wind-up); one that assists
              makes it lead by the wind-up less the lost motion. The column contradicts the motion
              when it says "resists" and the forward mean lies above the backward one by more than
              half the reference wind-up (2|T|/K), or says "assists" and the forward mean lies below
              by more than the lost motion plus half that wind-up -> error.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.ndimage import median_filter

from dynamics.records import comment_number
from dynamics.results import ARCSEC_PER_ARCMIN, ARCSEC_PER_RAD

UNIT_TOL = 0.05           # a stated speed agrees with the samples within 5 %
TIME_UNITS = {1e-3: "milliseconds", 1e-6: "microseconds", 60.0: "minutes"}   # factor to seconds
MAX_SPEED_FACTOR = 10.0   # ASSUMED: catalog maximum input speeds are 2-5 x rated; 10 x is no bench
GLITCH_SIGMAS = 10.0
GLITCH_WINDOW = 11        # running-median window (samples): bridges up to 5 consecutive glitches
MIN_NOISE_ARCSEC = 0.1    # floor of the scatter bound: below any bench encoder's resolution in TE
MAX_GLITCH_SHARE = 0.01
JITTER_STEPS = 1.5        # a time step under 1.5 median steps drops no sample
MAX_MISSING_SHARE = 0.5   # ASSUMED: resampling may invent at most as many samples as were measured
TORQUE_TOL = 0.05         # a stated torque agrees with the column within 5 % ...
TORQUE_TOL_RATED = 0.03   # ... or 3 % of rated (the catalog's lost-motion torque band)
COLUMN_TOL = 0.05
TORQUE_KEYS = ("output_torque_Nm", "torque_Nm")


@dataclass(frozen=True)
class Finding:
    check: str                      # time_unit, glitch, gap, torque_comment, column_comment, wind_up
    severity: str                   # "error" (refuse the record) or "warning" (repaired, said)
    message: str                    # one line: record, samples, what was found and done
    samples: tuple[int, ...] = ()   # 0-based data rows concerned

    @property
    def is_error(self) -> bool:
        return self.severity == "error"


def _samples_text(idx, limit: int = 8) -> str:
    idx = [int(i) for i in idx]
    head = ", ".join(str(i) for i in idx[:limit])
    return head + (f" and {len(idx) - limit} more" if len(idx) > limit else "")


def implied_speed_rpm(time_s, input_angle_deg) -> float:
    """Magnitude of the running input speed: the median sample-to-sample speed (a start-up ramp is
    not averaged in)."""
    dt = np.diff(time_s)
    ok = dt > 0
    return float(np.median(np.abs(np.diff(input_angle_deg)[ok] / dt[ok])) / 6.0)


# ------------------------------------------------------------------------------- time unit
def time_unit(name: str, time_s, input_angle_deg, stated_rpm: float | None, case_rpm: float,
              rated_input_rpm: float) -> tuple[float, Finding | None]:
    """(factor that turns the record's time into seconds, finding or None)."""
    speed = implied_speed_rpm(time_s, input_angle_deg)
    if stated_rpm is not None and stated_rpm > 0:
        ratio = speed / stated_rpm
        if abs(ratio - 1.0) <= UNIT_TOL:
            return 1.0, None
        for f, unit in TIME_UNITS.items():
            if abs(ratio / f - 1.0) <= UNIT_TOL:
                return f, Finding("time_unit", "warning", (
                    f"{name}: time_s read as {unit}: the samples give {speed:.4g} rpm, the record states "
                    f"input_speed_rpm {stated_rpm:g}; every sample's time converted to seconds (x {f:g})"))
        return 1.0, Finding("time_unit", "error", (
            f"{name}: the samples give an input speed of {speed:.4g} rpm, the record states "
            f"input_speed_rpm {stated_rpm:g}; they must agree within {UNIT_TOL:.0%} (time_s in seconds; "
            f"milliseconds, microseconds and minutes are recognised and converted)"))
    top = MAX_SPEED_FACTOR * rated_input_rpm
    if speed > top:
        return 1.0, Finding("time_unit", "error", (
            f"{name}: the samples give an input speed of {speed:.4g} rpm, above {top:.4g} rpm "
            f"({MAX_SPEED_FACTOR:g} x the case's rated input speed): time_s must be in seconds (or state the "
            f"speed: `# input_speed_rpm: N`)"))
    if speed < case_rpm / 100.0 and 0.5 <= speed * 1000.0 / case_rpm <= 2.0:
        return 1.0, Finding("time_unit", "error", (
            f"{name}: the samples give an input speed of {speed:.4g} rpm, 1/1000 of the case's "
            f"{case_rpm:g} rpm: time_s looks like milliseconds; state the speed in the record "
            f"(`# input_speed_rpm: {speed * 1000:.4g}` converts milliseconds, `# input_speed_rpm: "
            f"{speed:.4g}` keeps seconds)"))
    return 1.0, None


# ------------------------------------------------------------------------------- glitches
def glitch_bound_arcsec(dt_s, lost_motion_arcsec: float, rigidity_Nm_per_arcmin: float,
                        momentary_torque_Nm: float, load_inertia_kg_m2: float) -> np.ndarray:
    """Largest TE change [arcsec] the reducer can make over each time step (see module doc (a));
    inf where no rigidity is given."""
    dt = np.asarray(dt_s, float)
    if rigidity_Nm_per_arcmin <= 0 or momentary_torque_Nm <= 0:
        return np.full(dt.shape, np.inf)
    k = rigidity_Nm_per_arcmin * ARCSEC_PER_RAD / ARCSEC_PER_ARCMIN       # N m / rad
    span = lost_motion_arcsec + 2.0 * momentary_torque_Nm / k * ARCSEC_PER_RAD
    if load_inertia_kg_m2 <= 0:
        return np.full(dt.shape, span)
    v_max = momentary_torque_Nm / np.sqrt(k * load_inertia_kg_m2) * ARCSEC_PER_RAD   # arcsec / s
    return np.minimum(span, v_max * dt)


def glitches(te_arcsec, bound_arcsec) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(glitch sample indices, their deviation from the running median [arcsec], the threshold
    per sample [arcsec]); `bound_arcsec` per sample (the physical bound, module doc (a))."""
    te = np.asarray(te_arcsec, float)
    if len(te) < GLITCH_WINDOW:
        return np.zeros(0, int), np.zeros(0), np.full(te.shape, np.inf)
    dev = np.abs(te - median_filter(te, size=GLITCH_WINDOW, mode="nearest"))
    sigma = max(float(np.percentile(dev, 95)) / 1.96, 1.4826 * float(np.median(dev)), MIN_NOISE_ARCSEC)
    thr = np.minimum(np.asarray(bound_arcsec, float), GLITCH_SIGMAS * sigma)
    idx = np.flatnonzero(dev > thr)
    return idx, dev[idx], thr


def interpolate_over(time_s, values, bad) -> np.ndarray:
    """`values` with the samples `bad` replaced by linear interpolation in time between the
    nearest good samples (held at the ends)."""
    keep = np.ones(len(time_s), bool)
    keep[bad] = False
    out = np.asarray(values, float).copy()
    out[~keep] = np.interp(np.asarray(time_s)[~keep], np.asarray(time_s)[keep], out[keep])
    return out


def repair_glitches(name: str, time_s, input_angle_deg, output_angle_deg, ratio: float,
                    bound_arcsec) -> tuple[tuple[np.ndarray, np.ndarray] | None, Finding | None]:
    """((input, output) angles repaired, finding) or (None, None) for a clean record."""
    a_in, a_out = np.asarray(input_angle_deg, float), np.asarray(output_angle_deg, float)
    te = (a_out - a_in / ratio) * 3600.0
    idx, dev, thr = glitches(te, bound_arcsec)
    if not idx.size:
        return None, None
    share = idx.size / len(te)
    k = int(idx[np.argmax(dev)])
    if share > MAX_GLITCH_SHARE:
        return None, Finding("glitch", "error", (
            f"{name}: {idx.size} samples ({share:.1%}) leave their neighbours' TE by more than "
            f"{float(np.min(thr[idx])):.3g} arcsec (samples {_samples_text(idx)}): at most "
            f"{MAX_GLITCH_SHARE:.0%} glitches can be repaired; the encoder signal is unusable"), tuple(idx))
    fixed = (interpolate_over(time_s, a_in, idx), interpolate_over(time_s, a_out, idx))
    return fixed, Finding("glitch", "warning", (
        f"{name}: {idx.size} encoder glitch(es) at samples {_samples_text(idx)} (largest at sample {k}, "
        f"t = {time_s[k]:g} s: TE {float(np.max(dev)):.4g} arcsec off its neighbours; bound {float(thr[k]):.3g} "
        f"arcsec, the smaller of the reducer's reach in that sample period, {float(np.asarray(bound_arcsec)[k]):.4g} "
        f"arcsec, and {GLITCH_SIGMAS:g} sigma of the record's scatter): angles replaced by linear interpolation in time between the "
        f"nearest good samples"), tuple(int(i) for i in idx))


# ------------------------------------------------------------------------------- gaps
def missing_samples(time_s) -> tuple[float, np.ndarray, np.ndarray]:
    """(the record's clock: median time step [s], indices k of steps k -> k+1 that drop samples,
    how many each drops)."""
    dt = np.diff(np.asarray(time_s, float))
    clock = float(np.median(dt))
    steps = dt / clock
    gap = np.flatnonzero(steps >= JITTER_STEPS)
    return clock, gap, np.rint(steps[gap]).astype(int) - 1


def resample_gaps(name: str, time_s, columns: dict[str, np.ndarray], output_angle_deg, zp: int
                  ) -> tuple[tuple[np.ndarray, dict[str, np.ndarray]] | None, Finding | None]:
    """((time on the clock, columns resampled), warning) when samples are missing within the
    limits, (None, error) beyond them, (None, None) for a record on its clock."""
    t = np.asarray(time_s, float)
    clock, gap, drops = missing_samples(t)
    if not gap.size or drops.sum() == 0:
        return None, None
    a_out = np.asarray(output_angle_deg, float)
    spans = np.abs(a_out[gap + 1] - a_out[gap])
    j = int(np.argmax(spans))
    k = int(gap[j])
    n_missing = int(drops.sum())
    share = n_missing / (len(t) + n_missing)
    where = f"between samples {k} and {k + 1}, t = {t[k]:g} to {t[k + 1]:g} s"
    limit = 360.0 / zp
    if spans[j] > limit:
        return None, Finding("gap", "error", (
            f"{name}: a time gap spans {spans[j]:.3g} deg of output ({where}); a gap can be resampled "
            f"up to {limit:.3g} deg (one period of the crank order zp = {zp}: beyond it a whole cycle "
            f"of the crank line is unmeasured)"), (k, k + 1))
    if share > MAX_MISSING_SHARE:
        return None, Finding("gap", "error", (
            f"{name}: {n_missing} samples missing on the record's {clock:.4g} s clock ({share:.0%}); "
            f"at most {MAX_MISSING_SHARE:.0%} can be resampled"), tuple(int(g) for g in gap))
    n = int(round((t[-1] - t[0]) / clock)) + 1
    grid = t[0] + clock * np.arange(n)
    grid[-1] = min(grid[-1], t[-1])
    out = {c: np.interp(grid, t, np.asarray(v, float)) for c, v in columns.items()}
    return (grid, out), Finding("gap", "warning", (
        f"{name}: {n_missing} samples missing on the record's {clock:.4g} s clock ({share:.1%}, "
        f"{gap.size} gap(s), the largest {spans[j]:.3g} deg of output {where}): resampled onto the clock by linear interpolation in time"),
        tuple(int(g) for g in gap))


# ------------------------------------------------------------------------------- comments
def torque_against_comment(name: str, comments, torque_Nm, rated_torque_Nm: float) -> Finding | None:
    """Error when a stated torque comment disagrees with the torque column."""
    for key in TORQUE_KEYS:
        stated = comment_number(comments, key)
        if stated is None:
            continue
        col = float(np.median(torque_Nm))
        signed = stated < 0
        got = col if signed else abs(col)
        tol = max(TORQUE_TOL * abs(stated), TORQUE_TOL_RATED * rated_torque_Nm)
        if abs(got - stated) > tol:
            return Finding("torque_comment", "error", (
                f"{name}: the record states {key} {stated:g}, its output_torque_Nm column has a median of "
                f"{col:g} N m; they must agree within {tol:.3g} N m ({TORQUE_TOL:.0%} or "
                f"{TORQUE_TOL_RATED:.0%} of the rated {rated_torque_Nm:g} N m{'' if signed else ', as magnitudes'})"))
        return None
    return None


def columns_against_comments(name: str, comments, extra: dict[str, np.ndarray]) -> Finding | None:
    """Error when a comment `<column>: <number>` disagrees with that column of the record."""
    for col, values in extra.items():
        stated = comment_number(comments, col)
        v = np.asarray(values, float)
        v = v[np.isfinite(v)]
        if stated is None or not v.size:
            continue
        med = float(np.median(v))
        if abs(med - stated) > COLUMN_TOL * max(abs(stated), abs(med), 1.0):
            return Finding("column_comment", "error", (
                f"{name}: the record states {col} {stated:g}, its {col} column has a median of {med:g}; "
                f"they must agree within {COLUMN_TOL:.0%}"))
    return None


def wind_up_against_torque(fw_name: str, bw_name: str, te_fw_arcsec, te_bw_arcsec, torque_fw_Nm: float,
                           torque_bw_Nm: float, lost_motion_arcsec: float, rigidity_Nm_per_arcmin: float,
                           rated_torque_Nm: float) -> Finding | None:
    """Error when a pair sharing one encoder zero winds up against its torque column (module doc)."""
    T = 0.5 * (abs(torque_fw_Nm) + abs(torque_bw_Nm))
    if rigidity_Nm_per_arcmin <= 0 or T < TORQUE_TOL_RATED * rated_torque_Nm \
            or np.sign(torque_fw_Nm) == np.sign(torque_bw_Nm):
        return None
    wind = 2.0 * T / rigidity_Nm_per_arcmin * ARCSEC_PER_ARCMIN
    gap = float(np.mean(te_fw_arcsec) - np.mean(te_bw_arcsec))
    resists = torque_fw_Nm > 0
    said = (f"the torque column says the load {'resists' if resists else 'assists'} the motion "
            f"(forward {torque_fw_Nm:+g} N m, backward {torque_bw_Nm:+g} N m; + resists forward rotation)")
    if resists and gap > 0.5 * wind:
        why = (f"the output leads its motion in both directions: forward mean TE {gap:+.4g} arcsec from the "
               f"backward one, where a resisting load makes it lag (below by the lost motion plus the "
               f"wind-up, ~{wind:.3g} arcsec at the reference rigidity)")
    elif not resists and gap < -(lost_motion_arcsec + 0.5 * wind):
        why = (f"the output lags its motion in both directions: forward mean TE {gap:+.4g} arcsec from the "
               f"backward one, more than the lost motion ({lost_motion_arcsec:.3g} arcsec) and half the "
               f"wind-up ({0.5 * wind:.3g} arcsec at the reference rigidity) explain under an assisting load")
    else:
        return None
    return Finding("wind_up", "error", (
        f"{fw_name} and {bw_name}: {why}; {said}: if the column's sign is flipped, negate it"))
