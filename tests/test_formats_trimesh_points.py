"""OBJ/PLY files of points without faces: read as points, never as an empty surface (issue 16, part 2)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from tgsis import formats
from tgsis.errors import FileFormatError
from tgsis.formats.trimesh_io import read_trimesh_file, write_trimesh_file
from tgsis.mesh import PointSet, Surface

DATA = Path(__file__).resolve().parent / "data" / "trimesh"
POINTS = [[0, 0, 0], [10, 0, 0], [0, 10, 1.5]]


@pytest.mark.parametrize("name", ["points.ply", "points.obj"])
def test_a_file_of_points_is_a_point_set(name: str) -> None:
    points = read_trimesh_file(DATA / name)
    assert isinstance(points, PointSet)
    assert points.vertices.tolist() == POINTS
    assert points.cells.tolist() == [[0], [1], [2]]
    [same] = formats.read(DATA / name)
    assert same.same_as(points)


def test_ply_point_properties_are_kept() -> None:
    points = read_trimesh_file(DATA / "points.ply")
    assert list(points.vertex_properties) == ["porosity"]
    assert points.vertex_properties["porosity"].tolist() == [0.25, 0.5, 0.75]


def test_merge_vertices_applies_to_points(tmp_path: Path) -> None:
    path = tmp_path / "twice.obj"
    path.write_text("v 0 0 0\nv 1 0 0\nv 0 0 0\n")
    points = read_trimesh_file(path, merge_vertices=True)
    assert isinstance(points, PointSet) and points.vertices.tolist() == [[0, 0, 0], [1, 0, 0]]


def test_a_file_without_vertices_is_an_error() -> None:
    with pytest.raises(FileFormatError, match="the OBJ file holds no vertex"):
        read_trimesh_file(DATA / "empty.obj")


def test_a_surface_without_triangles_keeps_its_vertices(tmp_path: Path) -> None:
    surface = Surface([[0.5, 0, 0], [1.0, 0, 0], [0.0, 1, 0]], np.empty((0, 3), dtype=np.int64))
    write_trimesh_file(surface, tmp_path / "s.ply")
    back = read_trimesh_file(tmp_path / "s.ply")
    assert isinstance(back, Surface) and back.same_as(surface)  # the PLY file declares its (empty) face element
