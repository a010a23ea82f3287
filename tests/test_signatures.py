"""The signature atlas (dynamics.signatures, `python -m pipeline signatures`): the kinematics of
DESIGN.md read off the model, RV-40E ratio 81 on the tests' stand-in stiffness, rated torque.

What the model shows and these tests hold it to:
  - a pin-ring pattern of m lobes is swept by each disc's load zone at m zc x; the two discs' load
    zones sit 180 deg apart, so for odd m the discs turn opposite ways against the carrier and the
    lines largely cancel at the output, for even m they add;
  - a pin support stiffness pattern gives the same orders but grows with torque, a pin position
    pattern does not (what separates DESIGN.md's housing_stiffness_pattern from pin_ring_pattern);
  - everything that turns with the carrier (disc pitch, cranks, holes, main-bearing runout) repeats
    exactly after one pin pitch of output rotation (the pin ring is zp-fold symmetric and the
    first-stage mesh advances by z2 whole teeth), so it has lines only at multiples of zp: the disc's
    cumulative pitch (one lobe) gives zp x, not 1x; a 1x line needs the disc pattern crossed with a
    pin-ring pattern (zp - zc = 1) or comes from the reading (encoder / mounting runout).
"""
import json
import math
from types import SimpleNamespace

import numpy as np
import pytest

import dynamics.signatures as sg
from dynamics.model import build_model
from dynamics.results import ARCSEC_PER_RAD
from dynamics.statics import solve_static
from fem.stiffness import save
from geometry.params import load_case
from pipeline.cli import main
from support import case_path, stiffness_for_tests


@pytest.fixture(scope="module")
def rig():
    case = load_case(case_path("rv40e-81"))
    stiffness = stiffness_for_tests(case)
    ang = sg.input_angles_deg(case, sg.points_per_rev(case))
    T = (case.rated_torque_Nm,)
    return SimpleNamespace(case=case, stiffness=stiffness, ang=ang, T=T,
                           base=sg.baseline(case, stiffness, ang, T, (1,)),
                           src={s.id: s for s in sg.sources(case)})


def _sig(rig, source, torques=None, directions=(1,)):
    source = rig.src[source] if isinstance(source, str) else source
    if torques is None:
        return sg.signature(rig.case, rig.stiffness, source, rig.ang, rig.T, rig.base, directions)
    base = sg.baseline(rig.case, rig.stiffness, rig.ang, torques, directions)
    return sg.signature(rig.case, rig.stiffness, source, rig.ang, torques, base, directions)


def test_the_grid_samples_one_mesh_phase_and_resolves_four_lobes_of_the_pin_ring():
    for zp in (12, 30, 40, 60, 120):
        case = SimpleNamespace(cycloid=SimpleNamespace(zp=zp, zc=zp - 1))
        n = sg.points_per_rev(case)
        assert (zp * (zp - 1)) % n == 0 and n // 2 >= 4 * zp, (zp, n)
        assert sg.folded(zp * (zp - 1), n) == 0
    assert sg.points_per_rev(load_case(case_path("rv40e-81"))) == 390


def test_pin_ring_lobes_sweep_at_m_zc_and_the_two_discs_cancel_odd_m(rig):
    a = {m: _sig(rig, f"pin_radial_lobes_m{m}") for m in (1, 2, 3, 4)}
    zc = rig.case.cycloid.zc
    for m in (1, 2, 4):
        assert a[m].lines()[0] == m * zc, (m, a[m].lines())
    assert m * zc in a[3].lines()
    line = {m: a[m].amplitude(m * zc)[0, 0] for m in a}
    # odd m: a small remainder of what the even m beside it gives (model: 0.14 and 0.18)
    assert line[1] < 0.3 * line[2] and line[3] < 0.3 * line[4]
    assert line[2] > 0.5          # arcsec per um: an even pattern is seen almost in full


def test_for_odd_lobes_the_two_discs_turn_opposite_ways_against_the_carrier(rig):
    """The cancellation's mechanism: disc rotation minus carrier rotation, pattern minus ideal, at
    the m zc order (N = 195 points per output revolution: one mesh phase, resolves 78)."""
    n, zc = 195, rig.case.cycloid.zc
    ang = sg.input_angles_deg(rig.case, n)
    ideal = build_model(rig.case, rig.stiffness)

    def rel(model):
        out = []
        for a in ang:
            s = solve_static(model, a, rig.T[0])
            out.append(s.disc_pose[:, 2] - s.q[model.i_out])
        return np.array(out)

    r0 = rel(ideal)
    for m in (1, 2):
        r = rel(build_model(rig.case.with_errors(pin_radial_lobes=[[m, 1.0, 0.0]]), rig.stiffness)) - r0
        c = 2 * np.fft.rfft(r, axis=0)[m * zc] / n * ARCSEC_PER_RAD
        cos = (c[0] * np.conj(c[1])).real / (abs(c[0]) * abs(c[1]))
        if m == 1:
            assert cos < -0.9 and min(abs(c)) > 0.1, c        # opposite: they fight through the cranks
        else:
            assert max(abs(c)) < 0.1 * 1.9, c                 # together: the carrier follows, no fight


def test_a_tilted_pin_ring_gives_a_zc_line_of_t_over_e_zc_where_an_off_centre_ring_cancels(rig):
    """Rigid kinematics: a disc whose ring is shifted by t sits as if its eccentric were turned by
    t_perp / E and turns by t_perp / (E zc) (dynamics.couplings.pin, causes/pin_ring_tilt.py); with the
    shift opposite at the two disc planes (a tilt) the discs' zc x lines add to t / (E zc), with the same
    shift at both (a 1-lobe pattern) they cancel. 6 %: the closed form leaves out the radial part of
    the shift and the crank supports' compliance (measured 3-4 % below it on the RV-160N's FE stiffness
    and on this stand-in)."""
    T = tuple(f * rig.case.rated_torque_Nm for f in (0.1, 1.0))
    tilt, off = _sig(rig, "pin_ring_tilt", T, (1, -1)), _sig(rig, "pin_radial_lobes_m1", T, (1, -1))
    zc, si = rig.case.cycloid.zc, rig.case.si
    closed = 1e-6 / (si.eccentricity_m * zc) * ARCSEC_PER_RAD
    assert tilt.main_order() == zc
    assert np.allclose(tilt.amplitude(zc), closed, rtol=0.06), (tilt.amplitude(zc), closed)
    assert tilt.torque_dependence(zc) == "independent" and tilt.direction_dependence(zc) == "same"
    assert off.amplitude(zc).max() < 0.15 * closed


def test_a_pin_support_stiffness_pattern_grows_with_torque_a_pin_position_pattern_does_not(rig):
    T = tuple(f * rig.case.rated_torque_Nm for f in (0.1, 0.5, 1.0))
    stiff, pos = _sig(rig, "pin_stiffness_lobes_m2", T), _sig(rig, "pin_radial_lobes_m2", T)
    k = 2 * rig.case.cycloid.zc
    assert stiff.main_order() == pos.main_order() == k
    assert stiff.torque_exponent(k) > 0.3 and stiff.torque_dependence(k) == "grows"
    assert pos.torque_dependence(k) == "independent"


@pytest.mark.parametrize("source", ["disc_pitch_lobes_m1", "eccentric_error", "crank_timing", "crank_hole_tangential",
                                    "bearing_hole_radial", "main_bearing_runout", "eccentric_phase"])
def test_what_turns_with_the_carrier_repeats_every_pin_pitch(rig, source):
    """Lines only at multiples of zp; on the 390-point grid, multiples of zp above the Nyquist order
    fold onto multiples of gcd(zp, 390) = 10 (a small residue), never anywhere else."""
    s = _sig(rig, source)
    zp, n = rig.case.cycloid.zp, len(rig.ang)
    a = np.abs(s.spectrum[0, 0, 1:])
    k = np.arange(1, len(a) + 1)
    total = np.sum(a ** 2)
    assert s.lines()[0] == zp
    assert np.sum(a[k % math.gcd(zp, n) != 0] ** 2) < 1e-12 * total, source
    assert np.sum(a[k % zp != 0] ** 2) < 1e-3 * total, source


@pytest.mark.xfail(reason="issue 20/23: with the housing's torsion mode in the stand-in the crossed 1x line "
                          "falls to 0.42 of the expectation's 0.5 share: to re-derive", strict=False)
def test_a_disc_cumulative_pitch_gives_1x_only_crossed_with_a_pin_ring_pattern(rig):
    def src(errors):
        return sg.Source("x", "", "um", 10.0, "carrier", errors)
    disc = _sig(rig, src(lambda c, s: {"disc_pitch_lobes": [[1, 1, s, 0.0]]}))
    ring = _sig(rig, src(lambda c, s: {"pin_radial_lobes": [[1, s, 0.0]]}))
    both = _sig(rig, src(lambda c, s: {"disc_pitch_lobes": [[1, 1, s, 0.0]], "pin_radial_lobes": [[1, s, 0.0]]}))
    assert disc.amplitude(1)[0, 0] < 1e-6 and ring.amplitude(1)[0, 0] < 1e-6
    assert both.amplitude(1)[0, 0] > 0.5          # arcsec at 10 um each (model: 1.7)


def test_the_reading_error_is_1x_at_every_torque_and_direction(rig):
    T = (0.1 * rig.case.rated_torque_Nm, rig.case.rated_torque_Nm)
    s = _sig(rig, "output_coaxiality", T, (1, -1))
    e_over_r = 1e-6 / (rig.case.carrier.output_flange_radius_mm * 1e-3)
    assert s.main_order() == 1
    assert np.allclose(s.amplitude(1), e_over_r * ARCSEC_PER_RAD, rtol=1e-6)     # e / r, small angle
    assert s.torque_dependence(1) == "independent" and s.direction_dependence(1) == "same"


@pytest.mark.parametrize("m", [2, 3])
def test_a_reading_lobe_is_m_x_of_a_over_r_at_every_torque_and_direction(rig, m):
    T = (0.1 * rig.case.rated_torque_Nm, rig.case.rated_torque_Nm)
    s = _sig(rig, f"output_reading_lobes_m{m}", T, (1, -1))
    a_over_r = 1e-6 / (rig.case.carrier.output_flange_radius_mm * 1e-3)
    assert s.main_order() == m
    assert np.allclose(s.amplitude(m), a_over_r * ARCSEC_PER_RAD, rtol=1e-6)     # a / r, read directly
    assert s.torque_dependence(m) == "independent" and s.direction_dependence(m) == "same"


def test_clearances_read_as_lost_motion_and_share_one_signature_a_bench_offset_is_not_a_signature(rig):
    T = (0.1 * rig.case.rated_torque_Nm, rig.case.rated_torque_Nm)
    sigs = [_sig(rig, s, T, (1, -1)) for s in ("pin_radius", "turning_arm_clearance", "crank_timing")]
    for s in sigs[:2]:
        assert s.main_order() == 0 and s.direction_dependence(0) == "reverses"
    # crank timing shifts the mean by ~0.5 arcsec at every condition: invisible (free zero), its line is zp x
    assert abs(sigs[2].offset_arcsec) > 0.3 and sigs[2].main_order() == rig.case.cycloid.zp
    assert sg.groups(sigs) == [[0, 1], [2]]


def test_the_signatures_command_writes_the_atlas_with_its_provenance(rig, tmp_path, capsys):
    spath = tmp_path / "stiffness.json"
    save(rig.stiffness, spath)
    out = tmp_path / "sig"
    args = ["signatures", "--case", str(case_path("rv40e-81")), "--stiffness", str(spath), "--out", str(out),
            "--sources", "output_coaxiality,pin_radial_lobes_m2", "--quiet"]
    assert main(args) == 0
    data = json.loads((out / "signatures.json").read_text())
    assert (out / "signatures.png").stat().st_size > 10_000
    by_id = {s["id"]: s for s in data["sources"]}
    assert by_id["pin_radial_lobes_m2"]["main_order"] == 78 and by_id["pin_radial_lobes_m2"]["main_mechanism"] == "2 zc"
    assert by_id["output_coaxiality"]["main_mechanism"] == "1x"
    assert data["grid"]["points_per_output_rev"] == 390 and data["grid"]["mesh_order_folds_to"] == 0
    assert data["made_from"]["case_fingerprint"] == rig.stiffness.made_from.case_fingerprint
    assert data["made_from"]["inputs"]["stiffness"] == rig.stiffness.made_from.fingerprint
    assert main(args[:-3] + ["--sources", "no_such_source"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "no_such_source" in err and "pin_radial_lobes_m1" in err


def test_the_atlas_on_a_process_pool_is_the_atlas_solved_here(rig):
    """The command solves the sources on one process per core: the same bits as one process."""
    from pipeline.diagnosis.simulate import process_pool
    src = [rig.src["pin_radial_lobes_m2"], rig.src["crank_eccentricity"]]
    seen = []
    here, grid = sg.atlas(rig.case, rig.stiffness, src, torques=rig.T, directions=(1,),
                          progress=lambda i, n, sid: seen.append((i, n, sid)))
    pool = process_pool(2)
    try:
        there, grid2 = sg.atlas(rig.case, rig.stiffness, src, torques=rig.T, directions=(1,), pool=pool)
    finally:
        pool.shutdown()
    assert grid == grid2 and seen == [(1, 2, "pin_radial_lobes_m2"), (2, 2, "crank_eccentricity")]
    for a, b in zip(here, there):
        assert a.source.id == b.source.id and np.array_equal(a.spectrum, b.spectrum)
