"""OBJ, PLY, OFF and STL through trimesh: exactly what each format keeps and loses."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt
import pytest
import trimesh

from tests.shared_data import cfm
from tgsis import formats
from tgsis.errors import FileFormatError
from tgsis.formats.gocad import read_tsurf
from tgsis.formats.trimesh_io import read_trimesh_file, write_trimesh_file
from tgsis.mesh import LineSet, Surface


@pytest.fixture
def fault() -> Surface:
    """A real surface in UTM metres with vertex properties (azi, dip), plus cell properties of our own."""
    surface = read_tsurf(cfm("formats/CRFA-SJMZ-CHMN-Big_Spring_fault-50dip-CFM5.ts"))
    surface.cell_properties["part"] = np.arange(surface.n_cells, dtype=np.int64) % 4
    surface.cell_properties["quality"] = np.linspace(0, 1, surface.n_cells, dtype=np.float32)
    return surface


def without_properties(surface: Surface) -> Surface:
    return Surface(surface.vertices, surface.cells)


def text_tolerance(vertices: npt.NDArray[np.float64], decimals: int) -> npt.NDArray[np.float64]:
    """Fixed-point text with ``decimals`` places: half a unit in the last place plus one rounding of the double."""
    return np.asarray(0.5 * 10.0**-decimals + np.spacing(np.abs(vertices)), dtype=np.float64)


# ---------------------------------------------------------------- PLY: exact


def test_ply_round_trip_is_bit_exact_with_properties(fault: Surface, tmp_path: Path) -> None:
    write_trimesh_file(fault, tmp_path / "f.ply")
    back = read_trimesh_file(tmp_path / "f.ply")
    assert back.same_as(fault)
    assert back.vertices.view(np.int64).tolist() == fault.vertices.view(np.int64).tolist()
    # floats keep their type; integer properties come back as int64
    assert {k: v.dtype for k, v in back.vertex_properties.items()} == {"azi": np.float64, "dip": np.float64}
    assert back.cell_properties["part"].dtype == np.int64
    assert back.cell_properties["quality"].dtype == np.float32


def test_ply_is_standard_binary_with_double_coordinates(fault: Surface, tmp_path: Path) -> None:
    write_trimesh_file(fault, tmp_path / "f.ply")
    header = (tmp_path / "f.ply").read_bytes().split(b"end_header\n")[0].decode().splitlines()
    assert header[:2] == ["ply", "format binary_little_endian 1.0"]
    assert "property double x" in header and "property list uchar int vertex_indices" in header
    assert "property double azi" in header and "property int part" in header
    assert "property float quality" in header
    # trimesh itself reads the exact coordinates
    loaded: Any = trimesh.load(tmp_path / "f.ply", process=False, force="mesh")
    assert np.array_equal(loaded.vertices, fault.vertices) and np.array_equal(loaded.faces, fault.cells)


def test_trimesh_own_ply_writer_would_lose_bits(fault: Surface, tmp_path: Path) -> None:
    """Why tgsis writes PLY itself: trimesh stores float32 coordinates."""
    (tmp_path / "t.ply").write_bytes(trimesh.exchange.ply.export_ply(without_properties(fault).to_trimesh()))
    back = read_trimesh_file(tmp_path / "t.ply")
    assert not np.array_equal(back.vertices, fault.vertices)
    assert np.array_equal(back.vertices, fault.vertices.astype(np.float32).astype(np.float64))


def test_ply_property_types(tmp_path: Path) -> None:
    surface = Surface(
        np.eye(3), [[0, 1, 2]], vertex_properties={"ok": [True, False, True], "u": np.array([1, 2, 3], dtype=np.uint64)}
    )
    write_trimesh_file(surface, tmp_path / "s.ply")
    back = read_trimesh_file(tmp_path / "s.ply")
    assert back.vertex_properties["ok"].tolist() == [1, 0, 1]
    assert back.vertex_properties["u"].tolist() == [1, 2, 3]
    too_big = Surface(np.eye(3), [[0, 1, 2]], cell_properties={"id": [2**40]})
    with pytest.raises(FileFormatError, match="PLY has no 64-bit integers and property 'id'"):
        write_trimesh_file(too_big, tmp_path / "b.ply")
    clash = Surface(np.eye(3), [[0, 1, 2]], vertex_properties={"x": [1, 2, 3]})
    with pytest.raises(FileFormatError, match="clash with the PLY coordinate"):
        write_trimesh_file(clash, tmp_path / "c.ply")


def test_ply_from_another_writer_with_odd_names(tmp_path: Path) -> None:
    text = (
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
        "property uchar red\nproperty float Intensity\nelement face 1\nproperty list uchar int vertex_indices\n"
        "end_header\n0 0 0 255 0.5\n1 0 0 0 1.5\n0 1 0 7 2.5\n3 0 1 2\n"
    )
    (tmp_path / "a.ply").write_text(text)
    back = read_trimesh_file(tmp_path / "a.ply")
    assert back.vertices.tolist() == [[0, 0, 0], [1, 0, 0], [0, 1, 0]] and back.cells.tolist() == [[0, 1, 2]]
    assert back.vertex_properties["red"].tolist() == [255, 0, 7]
    assert back.vertex_properties["Intensity"].tolist() == [0.5, 1.5, 2.5]  # letter case kept: no renaming
    assert "ply_property_names" not in back.metadata


# ---------------------------------------------------------------- OBJ and OFF: text with fixed decimals


@pytest.mark.parametrize(("file_type", "decimals"), [("obj", 8), ("off", 10)])
def test_text_formats_keep_order_but_round_coordinates(
    fault: Surface, file_type: str, decimals: int, tmp_path: Path
) -> None:
    surface = without_properties(fault)
    path = tmp_path / f"f.{file_type}"
    write_trimesh_file(surface, path)
    back = read_trimesh_file(path)
    assert np.array_equal(back.cells, surface.cells)
    error = np.abs(back.vertices - surface.vertices)
    assert np.all(error <= text_tolerance(surface.vertices, decimals))
    # and it is not bit-exact: the UTM coordinates have more digits than that
    assert not np.array_equal(back.vertices, surface.vertices)


@pytest.mark.parametrize("file_type", ["obj", "off"])
def test_more_digits_on_request(fault: Surface, file_type: str, tmp_path: Path) -> None:
    surface = without_properties(fault)
    path = tmp_path / f"f.{file_type}"
    write_trimesh_file(surface, path, digits=12)
    back = read_trimesh_file(path)
    assert np.all(np.abs(back.vertices - surface.vertices) <= text_tolerance(surface.vertices, 12))


def test_obj_and_off_keep_unused_vertices(tmp_path: Path) -> None:
    surface = Surface([[0, 0, 0], [9, 9, 9], [1, 0, 0], [0, 1, 0]], [[0, 2, 3]])
    write_trimesh_file(surface, tmp_path / "s.obj")
    write_trimesh_file(surface, tmp_path / "s.off")
    # a point no face uses is data: kept (trimesh's OBJ reader dropped it, issue 36)
    assert read_trimesh_file(tmp_path / "s.obj").same_as(surface)
    assert read_trimesh_file(tmp_path / "s.off").same_as(surface)  # small integers: exact in any text


@pytest.mark.parametrize("file_type", ["obj", "off", "stl"])
def test_properties_are_refused_unless_dropped(fault: Surface, file_type: str, tmp_path: Path) -> None:
    path = tmp_path / f"f.{file_type}"
    lost = "azi, dip, quality" if file_type == "obj" else "azi, dip, part, quality"  # OBJ keeps parts as groups
    with pytest.raises(FileFormatError, match=f"{file_type.upper()} cannot store the properties {lost}") as info:
        write_trimesh_file(fault, path)
    assert "drop_properties=True" in str(info.value)
    write_trimesh_file(fault, path, drop_properties=True)
    assert read_trimesh_file(path).vertex_properties == {}


# ---------------------------------------------------------------- STL: float32 triangle soup


def test_stl_is_a_float32_triangle_soup(fault: Surface, tmp_path: Path) -> None:
    surface = without_properties(fault)
    write_trimesh_file(surface, tmp_path / "f.stl")
    back = read_trimesh_file(tmp_path / "f.stl")
    assert back.n_vertices == 3 * surface.n_cells
    assert back.cells.tolist() == np.arange(3 * surface.n_cells).reshape(-1, 3).tolist()
    corners = surface.vertices[surface.cells].reshape(-1, 3)
    assert np.array_equal(back.vertices, corners.astype(np.float32).astype(np.float64))


def test_stl_merge_vertices(tmp_path: Path) -> None:
    # float32-exact coordinates, vertices first used in index order: merging restores the surface
    vertices = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0.5], [2, 1, 0.25]])
    surface = Surface(vertices, [[0, 1, 2], [1, 3, 2], [1, 4, 3]])
    write_trimesh_file(surface, tmp_path / "s.stl")
    assert read_trimesh_file(tmp_path / "s.stl").n_vertices == 9
    assert read_trimesh_file(tmp_path / "s.stl", merge_vertices=True).same_as(surface)


# ---------------------------------------------------------------- errors and the registry


def test_errors(tmp_path: Path) -> None:
    (tmp_path / "g.ply").write_text("garbage\n")
    with pytest.raises(FileFormatError, match="not a PLY file"):
        read_trimesh_file(tmp_path / "g.ply")
    with pytest.raises(FileFormatError, match="cannot read the file"):
        read_trimesh_file(tmp_path / "missing.obj")
    lines = LineSet(np.eye(3), [[0, 1]])
    with pytest.raises(FileFormatError, match="OBJ stores triangle surfaces, not a LineSet"):
        write_trimesh_file(lines, tmp_path / "l.obj")  # type: ignore[arg-type]
    with pytest.raises(FileFormatError, match="digits= applies to OBJ and OFF"):
        write_trimesh_file(Surface(np.eye(3), [[0, 1, 2]]), tmp_path / "s.stl", digits=3)
    with pytest.raises(FileFormatError, match="unknown surface file type 'dxf'"):
        read_trimesh_file(tmp_path / "s.dxf")
    (tmp_path / "bad.obj").write_text("v 0 0 0\nv 1 0 0\nf 1 2 1\n")
    with pytest.raises(FileFormatError, match="not a valid surface"):
        read_trimesh_file(tmp_path / "bad.obj")


@pytest.mark.parametrize("extension", [".ply", ".obj", ".off", ".stl"])
def test_registry(fault: Surface, extension: str, tmp_path: Path) -> None:
    path = tmp_path / f"f{extension}"
    mesh = fault if extension == ".ply" else without_properties(fault)
    formats.write(mesh, path)
    [back] = formats.read(path)
    assert isinstance(back, Surface)
    if extension == ".ply":
        assert back.same_as(mesh)
    with pytest.raises(FileFormatError, match=f"{extension[1:]} files store SURFACE, not MULTILINESTRING"):
        formats.write(LineSet(np.eye(3), [[0, 1]]), path)
