"""First-stage involute mesh (fem.involute, ISO 6336-1 method B): the case's profile shift reaches
both the single-pair stiffness and the contact ratio."""
from pathlib import Path

import pytest

from fem import involute

CASES = Path(__file__).resolve().parents[1] / "cases"


@pytest.fixture(scope="module")
def case():
    from geometry.params import load_case
    return load_case(CASES / "rv40e-81.toml")


def test_the_shifted_tips_give_the_contact_ratio(case):
    # z1 = 12, z2 = 24, m = 2, 20 deg, x1 = 0.3, x2 = -0.3: tip radii 12 + 2 (1.3) = 14.6 mm and
    # 24 + 2 (0.7) = 25.4 mm, base radii 11.276 and 22.553 mm, centre distance 36 mm:
    # (sqrt(14.6^2 - 11.276^2) + sqrt(25.4^2 - 22.553^2) - 36 sin 20) / (pi 2 cos 20) = 1.4644
    # (unshifted: 1.5111)
    r = involute.mesh_stiffness(case)
    assert r["contact_ratio"] == pytest.approx(1.4644, abs=2e-4)
    assert r["profile_shift"] == (0.3, -0.3)


def test_the_iso_single_pair_stiffness_takes_the_shifts(case):
    # ISO 6336-1 eq. 74: q' = 0.04723 + 0.15551/12 + 0.25791/24 - 0.00635 (0.3) - 0.11654 (0.3)/12
    # - 0.00193 (-0.3) - 0.24188 (-0.3)/24 + 0.00529 (0.09) + 0.00182 (0.09) = 0.070359 mm um/N;
    # c' = 0.8 / q' = 11.370 N/(mm um) (unshifted 0.8 / 0.070935 = 11.278: +0.8 %), times b = 10 mm
    r = involute.mesh_stiffness(case)
    assert r["single_pair_stiffness_N_per_m"] == pytest.approx(11.370e7, rel=2e-4)
    # mean over the pitch: c' (0.75 eps + 0.25), ISO eq. 77
    assert r["mean_stiffness_N_per_m"] == pytest.approx(r["single_pair_stiffness_N_per_m"]
                                                         * (0.75 * r["contact_ratio"] + 0.25), rel=1e-12)
