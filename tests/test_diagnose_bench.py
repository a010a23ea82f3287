"""Blind diagnosis through the project's model: the virtual bench hides an effect (seeded cause,
size, phase; encoder quantisation 2^22 counts/turn and 0.3 arcsec noise), diagnose finds it.

Model: dynamics.model quasi-static path with tests/support.py's closed-form stiffness (RV-40E i=81).
Records: forward/backward pairs at 3, 30 and 60 % of rated torque, one output revolution of 256
samples each; the 30 % pair is held out of the fit (hold-out rule of diagnose.py).
Tolerances: parameters within 5 % of the drawn value (the noise moves them < 0.5 % on these lines;
5 % leaves room for the model's nonlinearity between the unit signature and the drawn size).
crank_eccentricity_error (one eccentric journal, disc 1, off by 4-10 um on a drawn crank): a zp x
line of ~0.85 arcsec/um (tests/test_dynamics_static.py). Its records are at 10, 30 and 60 % rated
(30 % held out): at 3 % rated the model adds a second-order part (2 zp x, a mean shift even in the
error) that the linear library leaves to other causes (one trial: hold-out gain 0.59; not tested). Tolerances:
the drawn crank exactly; the single-journal size within the 5 % of the other causes: it is read off the
fitted zp x line (CrankEccentricityError.single_journal), which the records determine, not off the
radial parameters, which the fit trades against the tangential pattern (measured 2026-11-29: drawn
7.58 / -6.16 / -7.52 um, read 7.56 / -6.13 / -7.52; from the radial pattern -6.87 for the second, 11.5 % off).
"""
import numpy as np
import pytest

from geometry.params import load_case
from pipeline.diagnosis.bench import bench_records, draw_effect
from pipeline.diagnosis.diagnose import diagnose
from pipeline.diagnosis.simulate import quasi_static_te
from pathlib import Path

support = pytest.importorskip("support", reason="tests/support.py (stiffness stand-in) not present")
CASE = load_case(Path(__file__).parents[1] / "cases" / "rv40e-81.toml")
STIFF = support.stiffness_for_tests(CASE)
PPR = 256
CASES = [(c, s) for c in ("output_coaxiality", "torsional_stiffness", "backlash") for s in range(4)] \
    + [("crank_eccentricity_error", s) for s in range(3)] \
    + [(c, s) for c in ("pin_ring_pattern", "pin_ring_tilt", "housing_stiffness_pattern", "disc_cumulative_pitch",
                        "output_reading_lobes") for s in range(2)]
TRUTH_KEY = {"output_coaxiality": "output_coaxiality_um", "torsional_stiffness": "compliance_factor",
             "backlash": "pin_clearance_um", "crank_eccentricity_error": "crank_eccentricity_error_single_um",
             "disc_cumulative_pitch": "disc_cumulative_pitch_um", "pin_ring_tilt": "pin_ring_tilt_um"}
# the carrier- and housing-side patterns shift the lost motion at light load (even in their size,
# `dc_even`): at 3 % rated that shift is named as backlash first; from 10 % rated the lines lead
TORQUES = {c: (0.1, 0.3, 0.6) for c in ("crank_eccentricity_error", "disc_cumulative_pitch", "pin_ring_pattern")}
# zp x is shared (dynamics.signatures.groups): a hidden disc pitch error may be named as the
# eccentric journal of its group, said as an alternative; either name is right on a zp x line alone
SAME_SIGNATURE = {"disc_cumulative_pitch": {"disc_cumulative_pitch", "crank_eccentricity_error"}}


def _truth_key(cause, truth):
    """The drawn size's key: fixed per cause, or the drawn lobe's (pin ring, housing)."""
    if cause in TRUTH_KEY:
        return TRUTH_KEY[cause]
    return next(k for k, v in truth.items() if k.endswith(("_um", "_fraction", "_um_per_kN")))


def _records(effects, seed, torque_fractions=(0.03, 0.3, 0.6)):
    return bench_records(quasi_static_te, CASE, STIFF, effects, seed=seed, samples_per_rev=PPR,
                         torque_fractions=torque_fractions)


# Known failures: none. Measured 2026-11-27 to -29: crank_eccentricity_error seed 1 came back named right
# (gain 0.918, held-out 0.914) but its single journal -6.87 um against the drawn -6.16 (11.5 % off), read
# off the radial pattern the fit had traded against the tangential one; read off the fitted zp x line
# (2026-11-29, CrankEccentricityError.single_journal) it is -6.13 um.
# pin_ring_pattern seeds 0/1 (named backlash first until issue 23's fit changes, extension.py:
# backlash's column re-taken beside the pattern's, refits warm-started, a fit still improving
# significantly at its budget goes on) now pass: the joint fit reaches the pattern alone, the other
# causes fall below the noise floor; seed 0: m4 5.98 um (drawn 5.98), gain 0.969, held-out 0.967;
# seed 1: m2 4.79 um (drawn 4.80), gain 0.956, held-out 0.954.
KNOWN_FAILING: set[tuple[str, int]] = set()


@pytest.mark.parametrize("cause,seed", [pytest.param(c, s, marks=pytest.mark.xfail(
    reason="issue 23: blind naming on the assembled-reducer stand-in (see KNOWN_FAILING)", strict=False))
    if (c, s) in KNOWN_FAILING else (c, s) for c, s in CASES])
def test_the_model_finds_a_hidden_effect_blind(cause, seed):
    eff = draw_effect(np.random.default_rng(100 + seed), CASE, cause)
    d = diagnose(CASE, STIFF, _records([eff], 100 + seed, TORQUES.get(cause, (0.03, 0.3, 0.6))),
                 points_per_rev=PPR)
    if cause in SAME_SIGNATURE:
        assert d.cause in SAME_SIGNATURE[cause], [(f.cause, f.score) for f in d.findings]
        assert d.extension.gain >= 0.6 and d.extension.holdout_gain >= 0.6
        return
    assert d.cause == cause, [(f.cause, f.score) for f in d.findings]
    assert d.extension.gain >= 0.6 and d.extension.holdout_gain >= 0.6
    key = _truth_key(cause, eff.truth)
    assert d.extension.parameters[key] == pytest.approx(eff.truth[key], rel=0.05)
    if cause == "crank_eccentricity_error":
        assert d.extension.parameters["crank_eccentricity_error_crank"] == eff.truth["crank_eccentricity_error_crank"]
    if cause == "output_coaxiality":
        assert d.extension.parameters["output_coaxiality_phase_deg"] == pytest.approx(
            eff.truth["output_coaxiality_phase_deg"], abs=2.0)


def test_clean_records_through_the_model_name_no_cause():
    d = diagnose(CASE, STIFF, _records([], 500), points_per_rev=PPR)
    assert d.cause is None and d.extension is None
    assert d.residual_rms_arcsec < 0.5   # noise 0.3 arcsec + quantisation 0.09 arcsec


def test_coaxiality_and_softer_reducer_together_give_two_findings():
    rng = np.random.default_rng(600)
    effs = [draw_effect(rng, CASE, "output_coaxiality"), draw_effect(rng, CASE, "torsional_stiffness")]
    d = diagnose(CASE, STIFF, _records(effs, 600), points_per_rev=PPR)
    assert {f.cause for f in d.findings} >= {"output_coaxiality", "torsional_stiffness"}
    assert d.extension.gain >= 0.6


def test_both_eccentrics_of_a_crank_misfit_show_at_twice_the_crankshaft_order_even_in_its_size():
    # crank_eccentricity_um (both discs' eccentrics; the crank_hole_position_error signature's shape)
    from pipeline.diagnosis.orders import spectrum_of
    from pipeline.diagnosis.causes.crank_hole_position_error import crank_pattern_um
    zp, T = CASE.cycloid.zp, 0.03 * CASE.rated_torque_Nm
    ang = np.linspace(0.0, 360.0 * CASE.ratio, PPR + 1)
    base = quasi_static_te(CASE, STIFF, ang, T, 1)

    def lines(de_um):
        c = CASE.with_errors(crank_eccentricity_um=tuple(float(v) for v in de_um))
        sp = spectrum_of(ang / CASE.ratio, quasi_static_te(c, STIFF, ang, T, 1) - base)
        return sp.at(zp), sp.at(2 * zp)
    de = crank_pattern_um(3, (10.0, 0.0))              # A = 10 um, phi = 0
    z1, z2 = lines(de)
    _, m2 = lines(-de)
    _, n2 = lines(de / 10.0)
    # measured through this model (RV-40E, 3 % rated): 10 um -> 2 zp x 7.7 arcsec, zp x 0.45: the
    # zp x line is what the two discs' unequal supports leave (the crank axis per disc plane: the
    # end-plate side gives more than the clamped flange side); with one lateral spring per crank
    # it was 0.003. -10 um -> the same 2 zp x; 1 um -> second order (inside the elastic approach).
    # Tolerances: factor-level bounds, 5 % on the evenness.
    assert z2 > 5.0 and z1 < 0.1 * z2
    assert m2 == pytest.approx(z2, rel=0.05)
    assert n2 < 0.05 * z2
