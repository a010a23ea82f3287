"""The mesh stage's artifact: stored with what it was made from, refused for another crankshaft."""
import numpy as np
import pytest

from fem.mesh import Mesh3D, MeshError, load_mesh3d, save_mesh3d
from fem.shaft import crankshaft_fingerprint
from geometry.params import load_case
from tests.support import case_path


def test_a_saved_mesh_comes_back_identical_for_its_own_crankshaft(tmp_path):
    case = load_case(case_path("rv40e-81"))
    m = Mesh3D(np.random.default_rng(1).random((5, 3)), np.array([[0, 1, 2, 3], [1, 2, 3, 4]]))
    save_mesh3d(tmp_path / "m.npz", m, fingerprint=crankshaft_fingerprint(case))
    got = load_mesh3d(tmp_path / "m.npz", fingerprint=crankshaft_fingerprint(case))
    assert np.array_equal(got.points, m.points) and np.array_equal(got.tetrahedra, m.tetrahedra)


def test_a_mesh_of_another_crankshaft_is_refused_with_the_command_that_fixes_it(tmp_path):
    a, b = load_case(case_path("rv40e-81")), load_case(case_path("rv160n-81"))
    # the two RV-40E cases share one second stage, hence one crankshaft; the RV-160N does not
    assert crankshaft_fingerprint(a) == crankshaft_fingerprint(load_case(case_path("rv40e-105")))
    m = Mesh3D(np.zeros((4, 3)), np.array([[0, 1, 2, 3]]))
    save_mesh3d(tmp_path / "m.npz", m, fingerprint=crankshaft_fingerprint(a))
    with pytest.raises(MeshError, match="rerun `python -m pipeline mesh`"):
        load_mesh3d(tmp_path / "m.npz", fingerprint=crankshaft_fingerprint(b))
    with pytest.raises(MeshError, match="mesh not found"):
        load_mesh3d(tmp_path / "none.npz", fingerprint="x")
