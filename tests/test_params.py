"""Case files: the shipped cases load; every invalid input names key, value and allowed range."""
from pathlib import Path

import numpy as np
import pytest

from geometry.params import CaseError, case_from_dict, load_case

CASES = Path(__file__).resolve().parents[1] / "cases"


def raw(name="rv40e-105"):
    import tomllib
    return tomllib.loads((CASES / f"{name}.toml").read_text())


@pytest.mark.parametrize("name, ratio", [("rv40e-105", 105), ("rv40e-81", 81), ("rv160n-81", 81)])
def test_shipped_cases_load_with_the_paper_ratio(name, ratio):
    # i = 1 + (z2/z1) zp: paper 000 gives 105, paper 001 and the dataset give 81
    assert load_case(CASES / f"{name}.toml").ratio == ratio


def test_paper_000_figures_are_in_the_reference_case():
    c = load_case(CASES / "rv40e-105.toml")
    assert (c.cycloid.pin_circle_radius_mm, c.cycloid.pin_radius_mm, c.cycloid.zc, c.cycloid.zp,
            c.stage1.z1, c.stage1.z2, c.cycloid.eccentricity_mm, c.operation.input_speed_rpm) == \
        (64.0, 3.0, 39, 40, 10, 26, 1.3, 525.0)


def test_every_assumed_figure_is_marked_in_the_case_files():
    for path in CASES.glob("*.toml"):
        for line in path.read_text().splitlines():
            if "=" in line and not line.lstrip().startswith("#") and "name =" not in line:
                assert "#" in line, f"{path.name}: figure without its source: {line!r}"


@pytest.mark.parametrize("section, key, value, words", [
    ("cycloid", "zc", 38, "zc = zp - 1"),
    ("cycloid", "eccentricity_mm", 1.7, "cusps"),            # 1.7 * 40 = 68 >= 64
    ("cycloid", "pin_radius_mm", -3.0, "outside the allowed range"),
    ("cycloid", "width_mm", 0.0, "outside the allowed range"),
    ("cycloid", "pin_radius_mm", 6.0, "overlap"),
    ("material", "poisson_ratio", 0.6, "outside the allowed range"),
    ("stage1", "z1", 10.5, "whole number"),
    ("cycloid", "zp", "forty", "must be a number"),
    ("carrier", "crank_circle_radius_mm", 30.0, "centre distance"),
])
def test_invalid_values_name_key_value_and_range(section, key, value, words):
    data = raw()
    data[section][key] = value
    with pytest.raises(CaseError) as exc:
        case_from_dict(data, source="x.toml")
    msg = str(exc.value)
    assert f"[{section}] {key}" in msg or key in msg
    assert words in msg


def test_unknown_and_missing_keys_are_named():
    data = raw()
    data["cycloid"]["teeth"] = 3
    with pytest.raises(CaseError, match=r"\[cycloid\] teeth: unknown key"):
        case_from_dict(data)
    data = raw()
    del data["cycloid"]["width_mm"]
    with pytest.raises(CaseError, match=r"\[cycloid\] width_mm: missing"):
        case_from_dict(data)


def test_error_tuples_take_one_value_or_one_per_crank():
    c = load_case(CASES / "rv40e-105.toml")
    assert c.with_errors(crank_eccentricity_um=[1, 2, 3]).errors.crank_eccentricity_um == (1, 2, 3)
    with pytest.raises(CaseError, match="one per crank"):
        c.with_errors(crank_eccentricity_um=[1, 2])


def test_missing_file_is_a_case_error(tmp_path):
    with pytest.raises(CaseError, match="not found"):
        load_case(tmp_path / "nope.toml")


# ----------------------------------------------------------------------------- validation limits
def one_line_case_error(fn, *args):
    with pytest.raises(CaseError) as exc:
        fn(*args)
    msg = str(exc.value)
    assert "\n" not in msg, msg
    return msg


@pytest.mark.parametrize("nu, ok", [(0.0, True), (0.3, True), (0.4999, True), (0.5, False), (-0.1, False)])
def test_poisson_ratio_must_lie_in_zero_to_one_half_open(nu, ok):
    # 0.5 is incompressible: plane-strain FE divides by 1 - 2 nu; the range is [0, 0.5)
    data = raw()
    data["material"]["poisson_ratio"] = nu
    if ok:
        assert case_from_dict(data).material.poisson_ratio == nu
    else:
        msg = one_line_case_error(case_from_dict, data, "x.toml")
        assert "x.toml: [material] poisson_ratio" in msg and f"= {nu}" in msg and "[0.0, 0.5)" in msg


def test_a_pin_count_above_any_real_cycloid_reducer_is_refused_before_any_geometry():
    # zp = 400 (a valid profile otherwise: E zp < R, pins fit, no undercut) asked the geometry
    # stage for 30 GiB; the limit is ZP_MAX = 120 (Sumitomo Cyclo 119:1), with the reason
    from geometry.params import ZP_MAX
    data = raw()
    data["cycloid"] |= dict(zp=400, zc=399, eccentricity_mm=0.13, pin_radius_mm=0.3)
    msg = one_line_case_error(case_from_dict, data, "x.toml")
    assert "[cycloid] zp = 400" in msg and f"[3, {ZP_MAX}]" in msg and "Cyclo" in msg


def test_the_largest_pin_count_allowed_loads_and_its_gaps_are_cheap():
    # zp = 120, K1 = 0.8125, pin radius 0.4 mm (below the 1.59 mm tip radius of curvature)
    import time

    from geometry import clearance
    data = raw()
    data["cycloid"] |= dict(zp=120, zc=119, eccentricity_mm=0.4333, pin_radius_mm=0.4)
    case = case_from_dict(data)
    t0 = time.perf_counter()
    gaps = clearance.pin_distances_mm(case, 0.1)
    assert gaps.shape == (120,) and np.all(gaps > 0)
    assert time.perf_counter() - t0 < 5.0


@pytest.mark.parametrize("name", ["../evil", "a/b", "a\\b", ".", "..", "has space", "tab\t", "", "x" * 101,
                                  "caf\u00e9"])
def test_the_case_name_must_be_a_plain_file_name_token(name):
    # the name becomes build/<name>/: no path separators, no '.'/'..', [A-Za-z0-9._-]{1,100}
    data = raw()
    data["name"] = name
    msg = one_line_case_error(case_from_dict, data, "x.toml")
    assert "name" in msg
    if name:
        assert repr(name) in msg and "file-name token" in msg


@pytest.mark.parametrize("name", ["rv40e-105", "RV_40E.v2", "a"])
def test_plain_names_are_accepted(name):
    data = raw()
    data["name"] = name
    assert case_from_dict(data).name == name


def test_a_non_utf8_case_file_is_a_one_line_case_error(tmp_path):
    p = tmp_path / "latin1.toml"
    p.write_bytes((CASES / "rv40e-105.toml").read_bytes().replace(b"# RV-40E", "# RV-40E \u00e9".encode("latin-1")))
    msg = one_line_case_error(load_case, p)
    assert str(p) in msg and "not a UTF-8 text file" in msg


def test_a_binary_file_given_as_a_case_is_a_one_line_case_error(tmp_path):
    p = tmp_path / "blob.toml"
    p.write_bytes(bytes(range(256)) * 4)
    msg = one_line_case_error(load_case, p)
    assert str(p) in msg


def test_a_binary_utf8_file_with_nul_bytes_is_not_valid_toml(tmp_path):
    p = tmp_path / "nul.toml"
    p.write_bytes(b'name = "a"\x00\x00\n[cycloid\n')
    msg = one_line_case_error(load_case, p)
    assert str(p) in msg and "not valid TOML" in msg


def test_a_directory_given_as_a_case_is_a_one_line_case_error(tmp_path):
    msg = one_line_case_error(load_case, tmp_path)
    assert str(tmp_path) in msg and "is a directory" in msg


def test_an_unreadable_case_file_is_a_one_line_case_error(tmp_path, monkeypatch):
    # root reads anything, so the permission error is raised where the file is read
    p = tmp_path / "locked.toml"
    p.write_text((CASES / "rv40e-105.toml").read_text())

    def denied(self):
        raise PermissionError(13, "Permission denied", str(self))
    monkeypatch.setattr(Path, "read_bytes", denied)
    msg = one_line_case_error(load_case, p)
    assert str(p) in msg and "permission denied" in msg


def test_a_device_or_huge_file_is_refused_before_reading(tmp_path):
    from geometry.params import CASE_FILE_MAX_BYTES
    if Path("/dev/zero").exists():
        assert "not a regular file" in one_line_case_error(load_case, "/dev/zero")
    p = tmp_path / "huge.toml"
    p.write_bytes(b"#" * (CASE_FILE_MAX_BYTES + 1))
    assert f"at most {CASE_FILE_MAX_BYTES} bytes" in one_line_case_error(load_case, p)


def test_a_case_file_with_a_utf8_byte_order_mark_loads(tmp_path):
    p = tmp_path / "bom.toml"
    p.write_bytes(b"\xef\xbb\xbf" + (CASES / "rv40e-105.toml").read_bytes())
    assert load_case(p).name == "rv40e-105"


# ----------------------------------------------------------------------------- stage 1 (involute)
def test_the_iso53_rack_formulas_meet_their_textbook_values():
    from geometry import spur
    # undercut limit 1 - z sin^2(alpha) / 2 (the rack's straight flank ends 1.25 - 0.38 (1 - sin 20)
    # = 0.99997 m deep): 0.298 for z = 12, 0.415 for z = 10, 17.1 teeth at x = 0
    assert spur.undercut_limit(12, 20.0) == pytest.approx(1 - 6 * np.sin(np.radians(20)) ** 2, abs=1e-4)
    assert spur.undercut_limit(17, 20.0) > 0 > spur.undercut_limit(18, 20.0)
    # a rack tooth (z -> inf) is pi/2 - 2 tan(alpha) modules thick at its tip (0.8428); the tip
    # thins as x grows
    rack_tip = np.pi / 2 - 2 * np.tan(np.radians(20))
    assert spur.tip_thickness_of_module(10 ** 7, 20.0, 0.0) == pytest.approx(rack_tip, abs=1e-5)
    assert spur.tip_thickness_of_module(12, 20.0, 0.3) < spur.tip_thickness_of_module(12, 20.0, 0.0)
    # eps_alpha of a 20/20 tooth standard pair at 20 deg: 1.557 (Niemann & Winter, the usual example)
    assert spur.transverse_contact_ratio(20, 20, 1.0, 20.0) == pytest.approx(1.557, abs=1e-3)
    with pytest.raises(ValueError, match="zero-sum"):
        spur.transverse_contact_ratio(12, 24, 2.0, 20.0, 0.3, 0.0)


@pytest.mark.parametrize("name, x1", [("rv40e-81", 0.30), ("rv40e-105", 0.42), ("rv160n-81", 0.0)])
def test_the_shipped_suns_carry_the_smallest_rounded_shift_free_of_undercut(name, x1):
    from geometry import spur
    s = load_case(CASES / f"{name}.toml").stage1
    assert s.profile_shift == x1 and s.planet_profile_shift == -x1
    x_min = spur.undercut_limit(s.z1, s.pressure_angle_deg)
    assert x_min <= x1 < max(x_min, 0.0) + 0.01     # rounded up to the next hundredth (or none needed)


@pytest.mark.parametrize("name, changes, words", [
    # z1 = 12 unshifted: undercut (x_min 0.298), the issue-11 audit's finding
    ("rv40e-81", dict(profile_shift=0.0), ["undercut below x1 = 0.298", "allowed x1 in [0.298, 0.404]"]),
    # z2 = 24 planets at x2 = -0.45 < -0.404: undercut
    ("rv40e-81", dict(profile_shift=0.45), ["planets (x2 = -x1) are undercut"]),
    # z1 = 10 at x = 0.5: tip 0.199 m < 0.2 m (pointed) before the planets undercut (0.521)
    ("rv40e-105", dict(profile_shift=0.5), ["thinner than 0.2 module (pointed)", "[0.415, 0.499]"]),
    ("rv40e-81", dict(profile_shift=1.5), ["outside the allowed range [-1.0, 1.0]", "pointed"]),
    # z1 = 6 at 20 deg: undercut below 0.649, pointed above ~0.2: no shift works
    ("rv40e-81", dict(z1=6, z2=30), ["[stage1] z1 = 6", "no profile shift"]),
])
def test_an_undercut_or_pointed_stage1_is_a_one_line_error_naming_the_allowed_shift(name, changes, words):
    data = raw(name)
    data["stage1"] |= changes
    with pytest.raises(CaseError) as exc:
        case_from_dict(data, source="x.toml")
    msg = str(exc.value)
    assert "\n" not in msg and msg.startswith("x.toml: [stage1]")
    for w in words:
        assert w in msg


def test_the_si_view_is_the_case_s_sizes_converted_once():
    # geometry.case_si: m = mm * 1e-3 in the arithmetic the stages used inline (bit for bit)
    case = load_case(CASES / "rv40e-81.toml")
    c, m, s1 = case.cycloid, case.modification, case.stage1
    si = case.si
    assert si is case.si                                             # made once per case
    assert si.eccentricity_m == c.eccentricity_mm * 1e-3
    assert si.modified_pin_circle_radius_m == (c.pin_circle_radius_mm + m.offset_mm) * 1e-3
    assert si.modified_pin_radius_m == (c.pin_radius_mm + m.equidistant_mm) * 1e-3
    assert si.sun_pitch_radius_m == s1.module_mm * s1.z1 / 2 * 1e-3
    assert si.youngs_modulus_Pa == case.material.youngs_modulus_GPa * 1e9
    assert case.replace("cycloid", eccentricity_mm=1.2).si.eccentricity_m == 1.2e-3   # a copy gets its own


def test_a_tolerance_band_stays_half_the_error_range_so_the_difference_of_two_draws_is_an_error():
    from geometry.params import ERROR_UM_MAX, TOLERANCE_UM_MAX
    assert TOLERANCE_UM_MAX == ERROR_UM_MAX / 2
