"""A diagnosis cause is one object in a registry (pipeline.diagnosis.causes): adding one touches no
other file, the machinery never branches on a cause id, and each cause's physical bounds hold.

The toy cause registered at runtime is a fixed 5x line a sin(5 theta + phi) [arcsec] carried by the
stand-in model of test_diagnose_machinery (closed form, no dynamics solve): 5x is no characteristic
order of the RV-40E (1, 3, 39, 40, 81, ...), so only the toy cause can explain it.
"""
import ast
import dataclasses
from pathlib import Path

import numpy as np
import pytest

from geometry.clearance import closed_form_min_clearance_mm
from pipeline.diagnosis import causes
from pipeline.diagnosis.bench import bench_records, draw_effect, drawable_causes
from pipeline.diagnosis.causes.base import Cause, Evidence, Fitted, Param, polar
from pipeline.diagnosis.diagnose import diagnose
from pipeline.diagnosis.signatures import signature_columns, summarise

import test_diagnose_machinery as machinery

CASE, STIFF = machinery.CASE, machinery.STIFF
DIAGNOSIS = Path(__file__).parents[1] / "pipeline" / "diagnosis"
KEY = "toy_line5"   # where the toy model keeps its line: StiffnessModel.extras (free form)


class Line5(Cause):
    id = "toy_line5"
    description = "a fixed 5x line (test cause)"
    signature = "5x, independent of load and direction"
    unit_size = 1.0

    def params(self, case):
        return (Param("line5_cos_arcsec", "arcsec", (-20.0, 20.0)),
                Param("line5_sin_arcsec", "arcsec", (-20.0, 20.0)))

    def apply(self, case, stiffness, p):
        z = stiffness.extras.get(KEY, 0j) + complex(p[0], p[1])
        return case, dataclasses.replace(stiffness, extras={**stiffness.extras, KEY: z})

    def orders(self, case):
        return (5,)

    def report(self, fit: Fitted) -> dict:
        a, a_ci, ph, ph_ci = polar(fit.p, fit.cov, fit.tq)
        return {"line5_arcsec": a, "line5_arcsec_ci95": a_ci, "line5_phase_deg": ph, "line5_phase_deg_ci95": ph_ci}

    def evidence(self, ev: Evidence) -> str:
        return f"{ev.prefix}a 5x line of {ev.line_by_torque(5)}{ev.alternatives}."

    def draw(self, rng, case):
        a, ph = rng.uniform(3.0, 6.0), rng.uniform(-180.0, 180.0)
        return (a * np.cos(np.radians(ph)), a * np.sin(np.radians(ph))), {"line5_arcsec": a, "line5_phase_deg": ph}


def toy_te(case, stiffness, ang, torque, direction):
    """The machinery stand-in plus the toy line: a cos(phi) sin(5 theta) + a sin(phi) cos(5 theta)."""
    z = stiffness.extras.get(KEY, 0j)
    th5 = 5.0 * np.radians(np.asarray(ang) / case.ratio)
    return machinery.toy_te(case, stiffness, ang, torque, direction) + z.real * np.sin(th5) + z.imag * np.cos(th5)


def test_a_cause_registered_at_runtime_runs_through_the_whole_machinery(monkeypatch):
    monkeypatch.setattr(causes, "CAUSES", causes.CAUSES + (Line5(),))
    assert "toy_line5" in drawable_causes()
    eff = draw_effect(np.random.default_rng(4), CASE, "toy_line5")
    recs = bench_records(toy_te, CASE, STIFF, [eff], seed=4, torque_fractions=(0.1, 0.5), samples_per_rev=128)
    # its signature column comes from the model: a unit 5x line and nothing else
    base = [toy_te(CASE, STIFF, r.input_angle_deg, r.output_torque_Nm, r.direction) for r in recs]
    cols = signature_columns(lambda c, s: [toy_te(c, s, r.input_angle_deg, r.output_torque_Nm, r.direction)
                                           for r in recs], CASE, STIFF, Line5(), base)
    s = summarise("toy_line5", recs, cols, 60)
    assert s.orders == (5,) and s.line_arcsec[0] == pytest.approx(1.0, rel=0.02)
    d = diagnose(CASE, STIFF, recs, toy_te, points_per_rev=128)
    assert d.cause == "toy_line5" and d.extension.causes == ("toy_line5",)
    assert d.findings[0].evidence.startswith("(p = ") and "a 5x line of" in d.findings[0].evidence
    assert "toy_line5" in {x.cause for x in d.summaries}
    # tolerances: 5 % on a 3-6 arcsec line against 0.3 arcsec noise on 4 x 129 samples; phase 2 deg
    p = d.extension.parameters
    assert p["line5_arcsec"] == pytest.approx(eff.truth["line5_arcsec"], rel=0.05)
    assert p["line5_phase_deg"] == pytest.approx(eff.truth["line5_phase_deg"], abs=2.0)
    assert p["line5_arcsec_ci95"][0] < p["line5_arcsec"] < p["line5_arcsec_ci95"][1]
    assert d.extension.gain >= 0.6 and d.extension.holdout_gain >= 0.6
    assert d.extension.outside_bounds == ()
    monkeypatch.undo()
    assert "toy_line5" not in drawable_causes()


def test_no_diagnosis_module_outside_the_causes_names_a_cause_id():
    ids = {c.id for c in causes.CAUSES}
    hits = []
    for path in sorted(DIAGNOSIS.glob("*.py")):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Constant) and isinstance(node.value, str) and node.value in ids:
                hits.append(f"{path.name}:{node.lineno} {node.value!r}")
    assert not hits, hits
    # and the cause modules are where the ids live: the check above would see them
    assert all(f'"{c.id}"' in (DIAGNOSIS / "causes" / f"{c.id}.py").read_text() for c in causes.CAUSES)


def test_the_docstrings_list_the_registered_causes():
    from pipeline.diagnosis import diagnose as module
    for c in causes.CAUSES:
        assert f"  {c.id}: " in causes.__doc__ and f"  {c.id}: " in module.__doc__


def test_every_cause_is_complete_and_its_bounds_contain_the_case_as_given():
    for c in causes.CAUSES:
        ps = c.params(CASE)
        assert c.id and c.description and c.signature and c.unit_size > 0 and ps
        assert all(q.bounds[0] < 0.0 < q.bounds[1] for q in ps), c.id
        assert c.out_of_bounds(CASE, np.zeros(len(ps))) == ()
        case2, stiff2 = c.apply(CASE, STIFF, np.full(len(ps), c.unit_size))
        assert case2 != CASE or stiff2 is not STIFF, c.id     # a unit step changes the model
        assert causes.get(c.id) is c


def test_the_backlash_lower_bound_closes_the_clearance_and_a_negative_stiffness_is_out():
    # lower bound = -(minimum conjugate-pose gap, closed form dRr - dR sqrt(1 - K1^2)): at it the
    # gap is zero (first order, exact for the closed form); below it the pins interfere
    bl = causes.get("backlash")
    lo = bl.params(CASE)[0].bounds[0]
    assert lo == pytest.approx(-1e3 * closed_form_min_clearance_mm(CASE))
    closed, _ = bl.apply(CASE, STIFF, np.array([lo]))
    assert closed_form_min_clearance_mm(closed) == pytest.approx(0.0, abs=1e-12)
    assert bl.out_of_bounds(CASE, [lo - 0.1]) and not bl.out_of_bounds(CASE, [lo + 0.1])
    ts = causes.get("torsional_stiffness")
    # u = ln(1/c): no value is a negative stiffness; beyond c in [0.05, 20] it is a wrong model
    assert ts.out_of_bounds(CASE, [np.log(30.0)]) and ts.out_of_bounds(CASE, [-np.log(30.0)])
    assert not ts.out_of_bounds(CASE, [-np.log(0.4)])   # c = 0.4 (README: the real RV-160N fit)
    for u in (-50.0, 50.0):                             # any u is a positive, finite stiffness
        _, s = ts.apply(CASE, STIFF, [u])
        assert 0 < s.crankshaft_torsional_stiffness_Nm_per_rad < np.inf


def test_an_unknown_or_undrawable_cause_is_refused_naming_the_allowed():
    with pytest.raises(ValueError, match="allowed output_coaxiality"):
        draw_effect(np.random.default_rng(0), CASE, "gear_rattle")
    with pytest.raises(ValueError, match="crank_hole_position_error.*allowed"):
        draw_effect(np.random.default_rng(0), CASE, "crank_hole_position_error")   # no draw
    with pytest.raises(ValueError, match="allowed output_coaxiality, crank_eccentricity_error"):
        causes.get("gear_rattle")


def test_the_housing_seat_pattern_is_its_seats_as_housing_modes_and_grows_with_torque():
    # housing_stiffness_pattern: the softer seats condensed into each pin contact (no DOF) give the
    # TE of the same seats kept as housing modes (one per pin and direction, stiffness 1 / c_k:
    # dynamics.couplings.housing), and the 78x line of a 2-lobe pattern is absent at zero torque
    # and grows with it. Measured (RV-40E stand-in, 2 um/kN): 78x 0.09, 0.74 arcsec at 3 and 60 %
    # rated, condensed = modes to 1e-4 arcsec. Tolerances: 1e-3 arcsec (the two Newton solves' own
    # tolerance), growth x3 (a linear spring under a widening load zone).
    from dynamics.couplings.housing import seat_compliance
    from fem.components.housing import Entry
    from pipeline.diagnosis.orders import spectrum_of
    from pipeline.diagnosis.simulate import quasi_static_te
    support = pytest.importorskip("support", reason="tests/support.py (stiffness stand-in) not present")
    stiff = support.stiffness_for_tests(CASE)
    cause = causes.get("housing_stiffness_pattern")
    zp, zc = CASE.cycloid.zp, CASE.cycloid.zc
    p = np.array([2.0, 0.0, 0.0, 0.0])
    c2, s2 = cause.apply(CASE, stiff, p)
    c = seat_compliance(s2, zp)
    assert c.min() >= 0.0 and c.max() == pytest.approx(4e-9)     # A (1 + cos): 0 .. 2 A
    h = stiff.parts["housing"]
    keep = np.flatnonzero(c > 0)
    n = keep.size
    phi = np.zeros((zp, 2, 2 * n))
    phi[keep, 0, np.arange(n)] = 1.0
    phi[keep, 1, n + np.arange(n)] = 1.0
    modes = dataclasses.replace(stiff, parts=dict(stiff.parts, housing=Entry(
        np.hstack([h.phi, phi.reshape(2 * zp, -1)]), np.r_[h.stiffness_N_per_m, np.tile(1.0 / c[keep], 2)],
        np.r_[h.mass_kg, np.full(2 * n, 0.01)], h.residual_m_per_N)))
    ang = np.linspace(0.0, 360.0 * CASE.ratio, 200, endpoint=False)
    lines = []
    for frac in (0.0, 0.03, 0.6):
        T = frac * CASE.rated_torque_Nm
        base = quasi_static_te(CASE, stiff, ang, T, 1)
        cond = quasi_static_te(c2, s2, ang, T, 1)
        dof = quasi_static_te(CASE, modes, ang, T, 1)
        assert np.abs(cond - dof).max() < 1e-3
        lines.append(spectrum_of(ang / CASE.ratio, cond - base).at(2 * zc))
    assert lines[0] < 1e-3 and lines[2] > 3.0 * lines[1] > 0.0


def test_the_single_journal_is_read_off_the_crank_causes_line_not_their_radial_split():
    # a linear stand-in of the zp x line (complex per-crank coefficients c_j per um of radial error, d per
    # um of the tangential pattern's components, 90 deg apart: the RV-40E model's shape, 0.85 and ~1.1
    # arcsec/um): a fit that splits one journal's line between radial and tangential parameters
    # still reads as that journal; the radial reading alone would not. A model without the line
    # reads no journal (no division by its zero line).
    from pipeline.diagnosis.causes.crank_eccentricity_error import ARCMIN_PER_RAD
    cause = causes.get("crank_eccentricity_error")
    n, zp = CASE.carrier.crank_count, CASE.cycloid.zp
    c = 0.85 * np.exp(2j * np.pi * np.arange(n) / n)
    d = 1.1j * np.array([1.0, 1j])
    to_um = CASE.cycloid.eccentricity_mm * 1e3 / ARCMIN_PER_RAD

    def line_model(case, stiffness, ang, torque, direction, *rest):
        e = np.asarray(case.errors.eccentric_error_um, float) * np.ones(n)
        tang = np.asarray(case.errors.eccentric_phase_arcmin, float) * np.ones(n) * to_um
        x = 2 * np.pi * np.arange(n) / n            # the pattern's (cos, sin) from its per-crank values
        pattern = 2.0 / n * np.array([tang @ np.cos(x), tang @ np.sin(x)])
        z = c @ e + d @ pattern
        theta = np.radians(np.asarray(ang, float)) / case.ratio
        return np.real(z * np.exp(1j * zp * theta))

    target = -6.0 * c[0]                             # journal 1 alone, -6 um
    tang = np.array([0.8, -0.5])
    rest = target - d @ tang                         # radial part of the split: the least-norm solution
    A = np.vstack([c.real, c.imag])
    radial = np.linalg.lstsq(A, np.array([rest.real, rest.imag]), rcond=None)[0]
    fit = Fitted(np.concatenate([radial, tang]), np.eye(n + 2), 2.0, CASE, STIFF, line_model)
    j, e = cause.single_journal(fit)
    assert (j, e) == (0, pytest.approx(-6.0, rel=1e-9))
    assert abs(cause.report(fit)["crank_eccentricity_error_amplitude_um"] * n / 2 - 6.0) > 0.5   # the radial reading misses
    flat = Fitted(fit.p, fit.cov, 2.0, CASE, STIFF, lambda case, s, ang, *a: np.zeros(len(ang)))
    assert cause.single_journal(flat) == (0, 0.0)
