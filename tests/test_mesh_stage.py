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


def test_an_empty_or_garbage_mesh_file_is_refused_with_the_command_that_fixes_it(tmp_path):
    (tmp_path / "empty.npz").write_bytes(b"")
    (tmp_path / "garbage.npz").write_bytes(bytes(range(256)) * 4)
    for name in ("empty.npz", "garbage.npz"):
        with pytest.raises(MeshError, match="not a mesh of the mesh stage.*rerun `python -m pipeline mesh`"):
            load_mesh3d(tmp_path / name, fingerprint="x")


@pytest.mark.parametrize("argv, needle", [
    (["mesh", "--crank-edge-mm", "1e-6"], "--crank-edge-mm = 1e-06 mm: allowed >= 0.85 mm and <= 8.5 mm"),
    (["mesh", "--crank-edge-mm", "9"], "--crank-edge-mm = 9 mm: allowed >= 0.85 mm and <= 8.5 mm"),
    (["fem", "--workers", "100000"], "--workers = 100000: allowed 1 to 64"),
    (["fem", "--mesh", "{file}"], "is a file; give the mesh stage's folder"),
    (["fem", "--mesh", "{empty}"], "not a mesh of the mesh stage"),
])
def test_a_bad_mesh_or_fem_option_is_one_line_before_any_meshing(tmp_path, capsys, argv, needle):
    from pipeline.cli import main
    (tmp_path / "afile").write_text("x")
    (tmp_path / "empty").mkdir()
    (tmp_path / "empty" / "crankshaft_mesh.npz").write_bytes(b"")
    argv = [a.format(file=tmp_path / "afile", empty=tmp_path / "empty") for a in argv]
    out = tmp_path / "out"
    out.mkdir()
    (out / "earlier.npz").write_bytes(b"earlier")
    rc = main([argv[0], "--case", str(case_path("rv40e-81")), "--out", str(out), *argv[1:]])
    err = capsys.readouterr().err
    assert rc == 2 and err.startswith("error: ") and err.count("\n") == 1 and needle in err, err
    assert sorted(p.name for p in out.iterdir()) == ["earlier.npz"] and (out / "earlier.npz").read_bytes() == b"earlier"
