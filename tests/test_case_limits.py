"""A case whose modification gives more backlash, or more interference, than a reducer can have is
refused in the keys' words (geometry.clearance_limits), not in the backlash solver's ("backlash root
not bracketed near 179487 rad" for a 1e-9 mm eccentricity); just inside each limit the solver
finds the backlash (the hard end of the range)."""
import copy
import math
import tomllib
from pathlib import Path

import pytest

from geometry.clearance import backlash_arcmin, closed_form_backlash
from geometry.clearance_limits import MAX_BACKLASH_ARCMIN, MAX_INTERFERENCE_UM
from geometry.params import CaseError, case_from_dict
from pipeline.cli import main

ROOT = Path(__file__).parents[1]
RAW = tomllib.loads((ROOT / "cases" / "rv40e-81.toml").read_text())


def _case(section, key, value):
    raw = copy.deepcopy(RAW)
    raw[section][key] = value
    return case_from_dict(raw, source="x.toml")


def test_a_vanishing_eccentricity_is_refused_naming_the_key_and_the_smallest_allowed():
    with pytest.raises(CaseError, match=r"\[cycloid\] eccentricity_mm = 1e-09 .* allowed at most 60 arcmin: "
                                        r"eccentricity_mm >= 0\.0103"):
        _case("cycloid", "eccentricity_mm", 1e-9)


def test_just_inside_the_backlash_limit_the_solver_finds_the_backlash():
    # b0 = 7 um / (E 39) = 60 arcmin at E = 0.01028 mm; the numerical backlash is ~2x the first-order one there
    case = _case("cycloid", "eccentricity_mm", 0.0104)
    assert closed_form_backlash(case).total_arcmin / 2 <= MAX_BACKLASH_ARCMIN
    b = backlash_arcmin(case)
    assert math.isfinite(b) and 60.0 < b < 240.0


@pytest.mark.parametrize("section,key,value", [("modification", "offset_mm", 0.1),
                                               ("modification", "equidistant_mm", -0.1)])
def test_an_interference_beyond_a_preload_is_refused_with_the_allowed_offset(section, key, value):
    with pytest.raises(CaseError, match=r"\[modification\] offset_mm = .* an interference; allowed down to -3 um"):
        _case(section, key, value)


def test_just_inside_the_interference_limit_the_solver_finds_a_negative_backlash():
    # clearance = 4 - 0.0115 * 1000 * sqrt(1 - 0.8125^2) = -2.7 um > -3 um
    case = _case("modification", "offset_mm", 0.0115)
    assert -MAX_INTERFERENCE_UM < 4.0 - 11.5 * math.sqrt(1 - 0.8125 ** 2) < 0
    assert -5.0 < backlash_arcmin(case) < 0.0


def test_the_cli_says_it_in_one_line(tmp_path, capsys):
    text = (ROOT / "cases" / "rv40e-81.toml").read_text().replace("eccentricity_mm = 1.3 ", "eccentricity_mm = 1e-9 ")
    (tmp_path / "c.toml").write_text(text)
    rc = main(["geometry", "--case", str(tmp_path / "c.toml"), "--out", str(tmp_path / "g")])
    err = capsys.readouterr().err
    assert rc == 2 and err.count("\n") == 1 and "eccentricity_mm = 1e-09" in err and "not bracketed" not in err
