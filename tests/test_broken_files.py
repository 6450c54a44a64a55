"""Broken OBJ, OFF, PLY, STL, GOCAD and legacy VTK files: every file reads exactly what it declares, or raises
FileFormatError naming the file and the line (issue 36, points 7 and 13).

The files are made here, small, in ``tmp_path``: good files written by tgsis, trimesh and meshio, then
broken by a generator (cut at every byte class, counts off by one, bad indices, NaN...). A reader that
returns fewer or more elements than the file declares, without an error, fails these tests.
"""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

from tgsis import formats
from tgsis.errors import FileFormatError
from tgsis.formats.gocad import read_gocad
from tgsis.formats.trimesh_io import read_trimesh_file, write_trimesh_file
from tgsis.mesh import PointSet, Surface


def grid_surface(nx: int = 4, ny: int = 4) -> Surface:
    """A curved surface of nx*ny vertices and 2*(nx-1)*(ny-1) triangles (18 for 4x4)."""
    x, y = np.meshgrid(np.arange(nx, dtype=float), np.arange(ny, dtype=float), indexing="ij")
    vertices = np.column_stack([x.ravel() * 10 + 0.5, y.ravel() * 10 + 0.25, np.sin(x.ravel()) + y.ravel() ** 2])
    cells = []
    for i in range(nx - 1):
        for j in range(ny - 1):
            a, b, c, d = i * ny + j, (i + 1) * ny + j, (i + 1) * ny + j + 1, i * ny + j + 1
            cells += [[a, b, c], [a, c, d]]
    return Surface(vertices, np.array(cells))


def assert_names_file(error: FileFormatError, path: Path, *, line: bool = True) -> None:
    assert error.path == str(path) and str(path) in str(error)
    if line:
        assert error.line is not None and error.line >= 1, str(error)


# ---------------------------------------------------------------- the cases of issue 36, point 7


def test_truncated_off_is_an_error_naming_the_line(tmp_path: Path) -> None:
    surface = grid_surface()
    assert surface.n_cells == 18
    path = tmp_path / "s.off"
    write_trimesh_file(surface, path)
    lines = path.read_text().splitlines(keepends=True)
    path.write_text("".join(lines[: len(lines) - 9]))  # 9 of the 18 faces left
    with pytest.raises(FileFormatError, match="ends after 9 of the 18 faces") as info:
        read_trimesh_file(path)
    assert_names_file(info.value, path)


def test_off_vertex_count_one_too_high_is_an_error(tmp_path: Path) -> None:
    path = tmp_path / "s.off"
    write_trimesh_file(grid_surface(), path)
    text = path.read_text().replace("16 18 ", "17 18 ", 1)
    assert text != path.read_text()
    path.write_text(text)
    with pytest.raises(FileFormatError) as info:
        read_trimesh_file(path)
    assert_names_file(info.value, path)


def test_obj_cut_inside_a_face_line_is_an_error(tmp_path: Path) -> None:
    path = tmp_path / "s.obj"
    path.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\nf 2 4")
    with pytest.raises(FileFormatError, match="2 corners") as info:
        read_trimesh_file(path)
    assert_names_file(info.value, path)
    assert info.value.line == 6


@pytest.mark.parametrize(("face", "message"), [("f 0 1 2", "index 0"), ("f 1 2 9", "vertex 9"),
                                               ("f -1 -2 -9", "vertex -9"), ("f 1 2 x", "not an integer")])
def test_obj_bad_index_is_an_error(tmp_path: Path, face: str, message: str) -> None:
    path = tmp_path / "s.obj"
    path.write_text(f"v 0 0 0\nv 1 0 0\nv 0 1 0\n{face}\n")
    with pytest.raises(FileFormatError, match=message) as info:
        read_trimesh_file(path)
    assert_names_file(info.value, path)
    assert info.value.line == 4


def test_obj_negative_indices_are_relative(tmp_path: Path) -> None:
    path = tmp_path / "s.obj"
    path.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\nv 1 1 0\nf 2 -1 3\n")
    back = read_trimesh_file(path)
    assert back.cells.tolist() == [[0, 1, 2], [1, 3, 2]]


def test_obj_unreferenced_vertex_is_kept(tmp_path: Path) -> None:
    path = tmp_path / "s.obj"
    path.write_text("v 0 0 0\nv 9 9 9\nv 1 0 0\nv 0 1 0\nf 1 3 4\n")
    back = read_trimesh_file(path)
    assert back.vertices.tolist() == [[0, 0, 0], [9, 9, 9], [1, 0, 0], [0, 1, 0]]
    assert back.cells.tolist() == [[0, 2, 3]]


def test_ply_binary_middle_endian_is_refused(tmp_path: Path) -> None:
    path = tmp_path / "s.ply"
    write_trimesh_file(grid_surface(), path)
    path.write_bytes(path.read_bytes().replace(b"binary_little_endian", b"binary_middle_endian", 1))
    with pytest.raises(FileFormatError, match="binary_middle_endian") as info:
        read_trimesh_file(path)
    assert_names_file(info.value, path)
    assert info.value.line == 2


def test_ply_binary_big_endian_is_read_right(tmp_path: Path) -> None:
    surface = grid_surface()
    surface = Surface(surface.vertices, surface.cells, vertex_properties={"q": np.arange(16, dtype=np.int32)},
                      cell_properties={"w": np.linspace(0, 1, 18)})
    header = ("ply\nformat binary_big_endian 1.0\nelement vertex 16\nproperty double x\nproperty double y\n"
              "property double z\nproperty int q\nelement face 18\nproperty list uchar int vertex_indices\n"
              "property double w\nend_header\n").encode()
    vertex = np.empty(16, dtype=[("xyz", ">f8", 3), ("q", ">i4")])
    vertex["xyz"], vertex["q"] = surface.vertices, np.arange(16)
    face = np.empty(18, dtype=[("n", "u1"), ("v", ">i4", 3), ("w", ">f8")])
    face["n"], face["v"], face["w"] = 3, surface.cells, np.linspace(0, 1, 18)
    path = tmp_path / "b.ply"
    path.write_bytes(header + vertex.tobytes() + face.tobytes())
    back = read_trimesh_file(path)
    assert back.same_as(surface)
    assert back.vertex_properties["q"].tolist() == list(range(16))
