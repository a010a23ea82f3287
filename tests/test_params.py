"""Case files: the shipped cases load; every invalid input names key, value and allowed range."""
from pathlib import Path

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
