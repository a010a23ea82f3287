"""FEM stage meshing: side effects of the tet mesher."""
import os

import cadquery as cq

from fem.mesh import tet_mesh_from_solid


def test_tet_meshing_leaves_the_working_directory_clean_and_unchanged(tmp_path, monkeypatch):
    # fTetWild writes `__tracked_surface.stl` into the cwd; the mesher must run in a scratch folder
    monkeypatch.chdir(tmp_path)
    m = tet_mesh_from_solid(cq.Workplane("XY").box(10, 10, 10), 10e-3, tolerance_m=1e-3)
    assert len(m.tetrahedra) > 0
    assert os.getcwd() == str(tmp_path)
    assert list(tmp_path.iterdir()) == []
