"""crank_eccentricity_error: the eccentrics of the crankshafts off their nominal positions.

The crank causes together: the crank-order (zp x) line of one disc turned against the other
comes from where each crank's eccentric centre sits, radially (its radius) and tangentially (its
eccentric phase, and the crank's timing against its planet gear). The radial error alone puts the
line in one quadrature per crank pattern, the eccentric phase in the other (the model, RV-40E FE:
5 um radial on crank 1 -> 3.6 arcsec at -90 deg, 5 um tangential -> 5.4 arcsec at 0 deg, loaded),
so together they span a zp x line of any phase and amplitude, each within its tolerance's range.
Parameters, in this order:
  e_1 .. e_n [um]        per crank, the radius error of disc 1's eccentric (below);
  phase cos, sin [um]    a zero-mean pattern p_j = c cos(2 pi j / n) + s sin(2 pi j / n) of the
                         angle between crank j's eccentrics (Errors.eccentric_phase_arcmin), as the
                         tangential shift E * angle of disc 2's eccentric centre;
  (timing)               a crank turned against its planet gear (Errors.crank_timing_arcmin) moves
                         its eccentrics tangentially as well: on the real records a separate timing
                         pattern was collinear with the eccentric phase (95 % intervals wider than
                         the range, the whole cause dropped), so the tangential pattern stands for
                         both; the report says so.
Bounds: +-50 um radial; tangential +-(60 arcmin x E) / sqrt(2) per component (the case's angle
errors are validated to 60 arcmin: a pattern's crank value stays inside).
Radial error details (e_1 .. e_n): per crank, the radius error of the eccentric under disc 1 only
(added to Errors.eccentric_error_um; e.g. one journal ground off size). Disc 1 alone is displaced,
so it turns against disc 2 by a misfit at the crankshaft order: a zp x line (the model, RV-40E on
the tests' stand-in stiffness: 0.85 arcsec per um, linear, nearly torque-independent; 2 zp x and a
mean shift, even in e, only at light load, hence `dc_even`: named on its lines, refitted in the
loop). The line's complex amplitude is linear in the e_j with a crank-dependent phase (crank j at
360 j / n deg), so the zero-mean pattern e_j - mean(e) = A cos(phi - 2 pi j / n) is what the line
measures (amplitude A, phase phi: which crank); the common part (disc 1's whole eccentricity) has
no line and is read from the mean shifts alone. Why not Errors.crank_eccentricity_um: it changes
BOTH eccentrics of a crank (180 deg apart), the two discs turn by +d and -d, the zp x line cancels
in the carrier and only a rectified 2 zp x threshold response remains, unlike real benches.
Caution in the evidence: zp x is also the order of a one-disc tooth or crank-hole pattern error.
Reported: e_j with intervals, (A, phi) and the single-journal reading (crank, signed size), the
latter read off the fitted zp x line (`single_journal`: the radial and tangential patterns trade
against each other in the fit, the line they make does not).
Unit size 2 um; bounds +-50 um per crank (five times the tolerance-class sizes drawn below; a
journal further off size is a wrong part). Virtual bench: disc 1's eccentric on one crank j
(uniform over the cranks) off by e, |e| in [4, 10] um, either sign (3.4-8.5 arcsec at zp x).
"""
from __future__ import annotations

import math

import numpy as np

from geometry.params import ANGLE_ERROR_ARCMIN_MAX
from pipeline.diagnosis.causes.base import Cause, Evidence, Fitted, Param, ci, per_crank, polar

UNIT_UM = 2.0
BOUND_UM = 50.0
ARCMIN_PER_RAD = 60.0 * 180.0 / math.pi


def tangential_bound_um(case) -> float:
    """Largest tangential pattern component [um] whose crank values stay within the case's angle
    limit (ANGLE_ERROR_ARCMIN_MAX at the eccentricity E), and within BOUND_UM."""
    return min(BOUND_UM, ANGLE_ERROR_ARCMIN_MAX / ARCMIN_PER_RAD * case.cycloid.eccentricity_mm * 1e3 / math.sqrt(2.0))


def crank_pattern(n: int, c: float, s: float) -> np.ndarray:
    """Zero-mean per-crank values c cos(2 pi j / n) + s sin(2 pi j / n)."""
    x = 2.0 * np.pi * np.arange(n) / n
    return c * np.cos(x) + s * np.sin(x)


def eccentric_pattern(values_um) -> tuple[float, float, float]:
    """(A, phi [deg], mean) of per-crank values v_j = mean + A cos(phi - 2 pi j / n): the part the
    zp x line of a disc-1 eccentric error measures (A, phi) and the common part (mean)."""
    v = np.asarray(values_um, float)
    n = len(v)
    z = 2.0 / n * np.sum((v - v.mean()) * np.exp(1j * 2 * np.pi * np.arange(n) / n))
    return float(abs(z)), float(np.degrees(np.angle(z))), float(v.mean())


def _zp_line(te_model, case, stiffness, base) -> complex:
    """Complex amplitude [arcsec] of the zp x line of the model's TE over one output revolution at 30 %
    rated torque, forward, on the diagnosis' stroboscopic grid, less `base` (the unperturbed case's)."""
    from pipeline.diagnosis.simulate import default_points_per_rev
    npt = default_points_per_rev(case)
    k = np.arange(npt)
    te = te_model(case, stiffness, 360.0 * case.ratio * k / npt, 0.3 * case.rated_torque_Nm, 1)
    z = 2.0 / npt * np.sum(te * np.exp(-2j * np.pi * case.cycloid.zp * k / npt))
    return complex(z) - (0.0 if base is None else base)


class CrankEccentricityError(Cause):
    id = "crank_eccentricity_error"
    description = ("an eccentric of a crankshaft off its radius (disc 1's journal): the disc turns "
                   "at the crankshaft order")
    signature = "zp x (crankshaft order) of any phase, nearly independent of load; 2 zp x and a mean shift at light load"
    unit_size = UNIT_UM
    dc_even = True

    def params(self, case):
        t = tangential_bound_um(case)
        return tuple(Param(f"eccentric_error_crank{j + 1}_um", "um", (-BOUND_UM, BOUND_UM))
                     for j in range(case.carrier.crank_count)) + tuple(
            Param(f"eccentric_phase_pattern_{part}_um", "um", (-t, t)) for part in ("cos", "sin"))

    def apply(self, case, stiffness, p):
        n = case.carrier.crank_count
        p = np.asarray(p, float)
        to_arcmin = ARCMIN_PER_RAD / (case.cycloid.eccentricity_mm * 1e3)
        return case.with_errors(
            eccentric_error_um=per_crank(case, "eccentric_error_um", p[:n]),
            eccentric_phase_arcmin=per_crank(case, "eccentric_phase_arcmin", crank_pattern(n, *p[n:n + 2]) * to_arcmin)
        ), stiffness

    def orders(self, case):
        return (case.cycloid.zp,)

    def report(self, fit: Fitted) -> dict:
        # the zp x line measures the zero-mean pattern A cos(phi - 2 pi j / n) (phi: crank j at
        # 360 j / n deg); a single journal off by e on crank j reads A = 2 |e| / n at
        # phi = 360 j / n (e > 0) or + 180 (e < 0)
        c, tq = self.id, fit.tq
        n = fit.case.carrier.crank_count
        p, cp = fit.p[:n], fit.cov[:n, :n]
        out = {f"{c}_um": [float(v) for v in p],
               f"{c}_um_ci95": [ci(float(v), float(s), tq) for v, s in zip(p, fit.sd[:n])]}
        to_arcmin = ARCMIN_PER_RAD / (fit.case.cycloid.eccentricity_mm * 1e3)
        for k, what in ((n, "eccentric_phase"),):   # or timing: the records cannot separate them
            a, a_ci, ph, ph_ci = polar(fit.p[k:k + 2], fit.cov[k:k + 2, k:k + 2], tq)
            out.update({f"{c}_{what}_pattern_um": a, f"{c}_{what}_pattern_um_ci95": a_ci,
                        f"{c}_{what}_pattern_phase_deg": ph,
                        f"{c}_{what}_arcmin": [float(v) for v in crank_pattern(n, *fit.p[k:k + 2]) * to_arcmin]})
        Z = 2.0 / n * np.exp(1j * 2 * np.pi * np.arange(n) / n)
        Z = Z - Z.mean()
        M = np.vstack([Z.real, Z.imag])                  # (Re z, Im z) = M p
        a, a_ci, ph, ph_ci = polar(M @ p, M @ cp @ M.T, tq)
        out.update({f"{c}_amplitude_um": a, f"{c}_amplitude_um_ci95": a_ci,
                    f"{c}_phase_deg": ph, f"{c}_phase_deg_ci95": ph_ci})
        j, e = self.single_journal(fit)
        out[f"{c}_crank"] = j + 1
        out[f"{c}_single_um"] = e
        return out

    def single_journal(self, fit: Fitted) -> tuple[int, float]:
        """(crank index, signed size [um]) of the one journal error that alone puts this cause's fitted
        zp x line where the fit put it. The line is what the records determine; its split between the
        radial pattern and the tangential one is not (both span a zp x line of any phase, told apart
        only by second-order mean shifts), so the reading comes from the line, not from the radial
        parameters alone (which the fit can trade against the tangential ones: a drawn -6.16 um journal
        came back as -6.87 radial plus 0.44 um tangential, the line itself right). The model's own zp x
        line per um of each journal (linear: 0.85 arcsec/um, nearly torque-independent), at 30 % rated
        forward on the diagnosis' stroboscopic grid."""
        n = fit.case.carrier.crank_count
        base = _zp_line(fit.te_model, fit.case, fit.stiffness, None)
        line = _zp_line(fit.te_model, *self.apply(fit.case, fit.stiffness, fit.p), base)
        best = None
        for j in range(n):
            unit = np.zeros(len(fit.p))
            unit[j] = UNIT_UM
            per = _zp_line(fit.te_model, *self.apply(fit.case, fit.stiffness, unit), base) / UNIT_UM
            if per == 0.0:                         # a stand-in model without this journal's line
                continue
            e = (line / per).real                  # the size along this journal's own line
            miss = abs(line - e * per)             # what it leaves of the fitted line
            if best is None or miss < best[2]:
                best = (j, float(e), miss)
        return (best[0], best[1]) if best else (0, 0.0)

    def evidence(self, ev: Evidence) -> str:
        zp = self.orders(ev.case)[0]
        return (f"{ev.prefix}residual line at the crankshaft order zp = {zp}x ({ev.line_by_torque(zp)} "
                f"; the model's line is nearly the same at every torque, unlike a stiffness effect): the model's "
                f"signature of an eccentric of one crankshaft off its radius, which turns one disc "
                f"against the other once per crank revolution (orders {list(ev.summary.orders)[:4]}). "
                f"Caution: zp x is also the order of a disc-tooth or crank-hole pattern error of one "
                f"disc (and of the crank bearings); the order alone does not separate them, the "
                f"crank-to-crank phase and a teardown do{ev.alternatives}.")

    def draw(self, rng, case):
        n = case.carrier.crank_count
        j, e = int(rng.integers(n)), rng.uniform(4.0, 10.0) * (1.0 if rng.random() < 0.5 else -1.0)
        p = np.zeros(n)
        p[j] = e
        a, ph, _ = eccentric_pattern(p)
        return tuple(float(v) for v in p) + (0.0,) * 2, {
            "crank_eccentricity_error_um": [float(v) for v in p], "crank_eccentricity_error_crank": j + 1,
            "crank_eccentricity_error_single_um": float(e), "crank_eccentricity_error_amplitude_um": a,
            "crank_eccentricity_error_phase_deg": ph}


CAUSE = CrankEccentricityError()
