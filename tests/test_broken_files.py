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


@pytest.mark.parametrize(
    ("face", "message"),
    [("f 0 1 2", "index 0"), ("f 1 2 9", "vertex 9"), ("f -1 -2 -9", "vertex -9"), ("f 1 2 x", "not an integer")],
)
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
    surface = Surface(
        surface.vertices,
        surface.cells,
        vertex_properties={"q": np.arange(16, dtype=np.int32)},
        cell_properties={"w": np.linspace(0, 1, 18)},
    )
    header = (
        b"ply\nformat binary_big_endian 1.0\nelement vertex 16\nproperty double x\nproperty double y\n"
        b"property double z\nproperty int q\nelement face 18\nproperty list uchar int vertex_indices\n"
        b"property double w\nend_header\n"
    )
    vertex = np.empty(16, dtype=[("xyz", ">f8", 3), ("q", ">i4")])
    vertex["xyz"], vertex["q"] = surface.vertices, np.arange(16)
    face = np.empty(18, dtype=[("n", "u1"), ("v", ">i4", 3), ("w", ">f8")])
    face["n"], face["v"], face["w"] = 3, surface.cells, np.linspace(0, 1, 18)
    path = tmp_path / "b.ply"
    path.write_bytes(header + vertex.tobytes() + face.tobytes())
    back = read_trimesh_file(path)
    assert back.same_as(surface)
    assert back.vertex_properties["q"].tolist() == list(range(16))


# ---------------------------------------------------------------- files real tools write still read


def test_files_real_tools_write_still_read(tmp_path: Path) -> None:
    import meshio
    import trimesh

    sphere = trimesh.creation.icosphere(1)
    uv = np.random.default_rng(1).random((len(sphere.vertices), 2))
    sphere.visual = trimesh.visual.TextureVisuals(uv=uv)  # type: ignore[no-untyped-call]  # trimesh: no annotations
    n, m = len(sphere.vertices), len(sphere.faces)
    files = {
        "normals_uv.obj": trimesh.exchange.obj.export_obj(  # type: ignore[no-untyped-call]  # trimesh: no annotations
            sphere, include_normals=True, include_texture=True
        ),
        "trimesh.off": trimesh.exchange.off.export_off(sphere),
        "normals_uv.ply": trimesh.exchange.ply.export_ply(sphere, encoding="ascii", vertex_normal=True),
        "binary_normals.ply": trimesh.exchange.ply.export_ply(sphere, encoding="binary", vertex_normal=True),
        "ascii.stl": trimesh.exchange.stl.export_stl_ascii(sphere),
        "binary.stl": trimesh.exchange.stl.export_stl(sphere),
    }
    for name, content in files.items():
        (tmp_path / name).write_bytes(content if isinstance(content, bytes) else content.encode())
    mesh = meshio.Mesh(sphere.vertices, [("triangle", sphere.faces)], point_data={"p": np.arange(n, dtype=float)})
    for extension in ("obj", "off", "ply", "stl"):
        meshio.write(
            tmp_path / f"meshio.{extension}",
            mesh if extension == "ply" else meshio.Mesh(sphere.vertices, [("triangle", sphere.faces)]),
        )
    # CRLF line ends, comments, no newline at the end, quads split into triangles
    (tmp_path / "crlf.obj").write_bytes(
        b"# a quad and a pentagon\r\nv 0 0 0\r\nv 1 0 0\r\nv 1 1 0\r\nv 0 1 0 # the fourth\r\nv 0.5 2 0\r\n"
        b"vt 0 0\r\nvn 0 0 1\r\ng part\r\ns off\r\nf 1/1/1 2/1/1 3/1/1 4/1/1\r\nf 4//1 3//1 \\\r\n 5//1\r\no x"
    )
    (tmp_path / "quad.off").write_bytes(
        b"OFF\r\n# a comment\r\n4 1 4\r\n0 0 0\r\n1 0 0\r\n1 1 0\r\n0 1 0\r\n4 0 1 2 3 255 0 0"
    )
    (tmp_path / "coff.off").write_bytes(
        b"COFF 3 1 0\n0 0 0 255 0 0 255\n1 0 0 0 255 0 255\n0 1 0 0 0 255 255\n3 0 1 2\n"
    )
    (tmp_path / "quad.ply").write_bytes(
        b"ply\r\nformat ascii 1.0\r\ncomment made by hand\r\nelement vertex 4\r\n"
        b"property float x\r\nproperty float y\r\nproperty float z\r\n"
        b"element face 1\r\nproperty list uchar int vertex_indices\r\n"
        b"end_header\r\n0 0 0\r\n1 0 0\r\n1 1 0\r\n0 1 0\r\n4 0 1 2 3"
    )
    for name in files:
        back = read_trimesh_file(tmp_path / name)
        expected_n = 3 * m if name.endswith(".stl") else n
        assert (back.n_vertices, back.n_cells) == (expected_n, m), name
        assert np.allclose(back.vertices[back.cells], sphere.vertices[sphere.faces], atol=1e-6), name
    for extension in ("obj", "off", "ply", "stl"):
        back = read_trimesh_file(tmp_path / f"meshio.{extension}")
        assert back.n_cells == m and np.allclose(back.vertices[back.cells], sphere.vertices[sphere.faces])
    assert read_trimesh_file(tmp_path / "meshio.ply").vertex_properties["p"].tolist() == list(range(n))
    crlf = read_trimesh_file(tmp_path / "crlf.obj")
    assert crlf.n_vertices == 5 and crlf.cells.tolist() == [[0, 1, 2], [0, 2, 3], [3, 2, 4]]
    for name in ("quad.off", "quad.ply"):
        back = read_trimesh_file(tmp_path / name)
        assert back.cells.tolist() == [[0, 1, 2], [0, 2, 3]] and back.n_vertices == 4, name
    assert read_trimesh_file(tmp_path / "coff.off").cells.tolist() == [[0, 1, 2]]


# ---------------------------------------------------------------- the generator of broken files


def _text_off(surface: Surface) -> bytes:
    lines = ["OFF", f"{surface.n_vertices} {surface.n_cells} 0"]
    lines += [" ".join(repr(float(v)) for v in row) for row in surface.vertices]
    lines += ["3 " + " ".join(str(int(i)) for i in row) for row in surface.cells]
    return ("\n".join(lines) + "\n").encode()


def _text_obj(surface: Surface) -> bytes:
    lines = ["# made by the test"] + ["v " + " ".join(repr(float(v)) for v in row) for row in surface.vertices]
    lines += ["f " + " ".join(str(int(i) + 1) for i in row) for row in surface.cells]
    return ("\n".join(lines) + "\n").encode()


def _ascii_ply(surface: Surface, n_vertices: int | None = None, n_faces: int | None = None) -> bytes:
    header = [
        "ply",
        "format ascii 1.0",
        f"element vertex {surface.n_vertices if n_vertices is None else n_vertices}",
        "property double x",
        "property double y",
        "property double z",
        f"element face {surface.n_cells if n_faces is None else n_faces}",
        "property list uchar int vertex_indices",
        "end_header",
    ]
    lines = header + [" ".join(repr(float(v)) for v in row) for row in surface.vertices]
    lines += ["3 " + " ".join(str(int(i)) for i in row) for row in surface.cells]
    return ("\n".join(lines) + "\n").encode()


def _binary_ply(surface: Surface, order: str = "<", n_vertices: int | None = None, n_faces: int | None = None) -> bytes:
    name = {"<": "binary_little_endian", ">": "binary_big_endian"}[order]
    header = (
        f"ply\nformat {name} 1.0\nelement vertex {surface.n_vertices if n_vertices is None else n_vertices}\n"
        "property double x\nproperty double y\nproperty double z\n"
        f"element face {surface.n_cells if n_faces is None else n_faces}\n"
        "property list uchar int vertex_indices\nend_header\n"
    ).encode()
    face = np.empty(surface.n_cells, dtype=[("n", "u1"), ("v", order + "i4", 3)])
    face["n"], face["v"] = 3, surface.cells
    return header + surface.vertices.astype(order + "f8").tobytes() + face.tobytes()


def _binary_stl(surface: Surface, count: int | None = None) -> bytes:
    table = np.zeros(surface.n_cells, dtype=[("normal", "<f4", 3), ("corners", "<f4", (3, 3)), ("a", "<u2")])
    table["corners"] = surface.vertices[surface.cells]
    header = b"binary STL made by the test".ljust(80, b" ")
    return header + np.uint32(surface.n_cells if count is None else count).tobytes() + table.tobytes()


def _ascii_stl(surface: Surface, drop: str = "") -> bytes:
    lines = ["solid test"]
    for triangle in surface.vertices[surface.cells]:
        lines += ["facet normal 0 0 1", "  outer loop"]
        lines += [f"    vertex {x!r} {y!r} {z!r}" for x, y, z in triangle.tolist()]
        lines += ["  endloop", "endfacet"]
    lines.append("endsolid test")
    if drop:
        lines.remove(next(line for line in lines if line.strip() == drop))
    return ("\n".join(lines) + "\n").encode()


def _gocad(surface: Surface) -> bytes:
    from tgsis.formats.gocad import format_gocad

    return format_gocad(surface).encode()


def _vtk(surface: Surface, ascii: bool) -> bytes:
    from tgsis.formats.vtk_legacy import format_vtk

    return format_vtk(surface, ascii=ascii)


BASE = grid_surface(3, 3)  # 9 vertices, 8 triangles
NV, NC = BASE.n_vertices, BASE.n_cells

# name -> (extension, content, declares counts); a format without declared counts (OBJ) may read a prefix
GOOD: dict[str, tuple[str, bytes, bool]] = {
    "off": (".off", _text_off(BASE), True),
    "obj": (".obj", _text_obj(BASE), False),
    "ascii_ply": (".ply", _ascii_ply(BASE), True),
    "binary_ply_le": (".ply", _binary_ply(BASE, "<"), True),
    "binary_ply_be": (".ply", _binary_ply(BASE, ">"), True),
    "binary_stl": (".stl", _binary_stl(BASE), True),
    "ascii_stl": (".stl", _ascii_stl(BASE), True),
    "tsurf": (".ts", _gocad(BASE), True),
    "vtk_ascii": (".vtk", _vtk(BASE, True), True),
    "vtk_binary": (".vtk", _vtk(BASE, False), True),
}
BINARY = {"binary_ply_le", "binary_ply_be", "binary_stl", "vtk_binary"}


def _counts(name: str) -> tuple[int, int]:
    return (3 * NC if name.endswith("stl") else NV), NC


def _read(path: Path) -> tuple[int, int] | FileFormatError:
    """(vertices, triangles) of the only mesh read (a PointSet has none), or the FileFormatError raised."""
    try:
        meshes = formats.read(path)
    except FileFormatError as exc:
        return exc
    assert len(meshes) == 1, path
    return meshes[0].n_vertices, 0 if isinstance(meshes[0], PointSet) else meshes[0].n_cells


# refusals of a whole file, which have no line to name
WHOLE_FILE = (
    "is empty",
    "holds no",
    "no GOCAD object",
    "not a legacy VTK",
    "ends",
    "not a PLY file",
    "has no END",
    "not STL",
    "not a valid",
)


def _check_error(error: FileFormatError, path: Path, content: bytes) -> None:
    """The error names the file, is short, and for a text file names the line (unless it is about the whole file)."""
    assert error.path == str(path), str(error)
    assert len(str(error)) < 1000, f"an unbounded message: {str(error)[:200]}"
    binary = b"\x00" in content or b"binary" in content[:200] or b"BINARY" in content[:200]
    if not binary and not any(words in str(error) for words in WHOLE_FILE):
        assert error.line is not None, str(error)


@pytest.mark.parametrize("name", sorted(GOOD))
def test_the_good_files_read(name: str, tmp_path: Path) -> None:
    extension, content, _ = GOOD[name]
    path = tmp_path / f"good{extension}"
    path.write_bytes(content)
    assert _read(path) == _counts(name)


@pytest.mark.parametrize("name", sorted(GOOD))
def test_truncated_at_every_byte(name: str, tmp_path: Path) -> None:
    """Cut after every byte (inside the header, inside a vertex line, inside a face line, ...): an error,
    or all declared elements (only a trailing line end or the last digits of the last number were cut)."""
    extension, content, declares = GOOD[name]
    full = _counts(name)
    path = tmp_path / f"cut{extension}"
    silent = []
    for cut in range(len(content)):
        path.write_bytes(content[:cut])
        result = _read(path)
        if isinstance(result, FileFormatError):
            _check_error(result, path, content[:cut])
        elif declares and result != full:
            silent.append((cut, result))
        elif not declares:  # OBJ: the elements before the cut, the last one perhaps cut short
            whole_lines = content[:cut].count(b"\n")
            assert result[0] <= full[0] and result[1] <= full[1], (cut, result)
            assert result[0] + result[1] >= whole_lines - 1 - 1, (cut, result)  # the comment line, the cut one
    assert not silent, f"{name}: read without error but with other counts than declared: {silent[:5]}"


def _count_mutations() -> list[tuple[str, str, bytes]]:
    """Files whose declared counts are off by one: each must be refused."""
    cases: list[tuple[str, str, bytes]] = []
    off = _text_off(BASE)
    for dv, dc in ((1, 0), (-1, 0), (0, 1), (0, -1)):
        header = f"{NV} {NC} 0".encode()
        cases.append((f"off_{dv}_{dc}", ".off", off.replace(header, f"{NV + dv} {NC + dc} 0".encode(), 1)))
        cases.append((f"ascii_ply_{dv}_{dc}", ".ply", _ascii_ply(BASE, NV + dv, NC + dc)))
        for order in "<>":
            cases.append((f"binary_ply{order}_{dv}_{dc}", ".ply", _binary_ply(BASE, order, NV + dv, NC + dc)))
    for d in (1, -1, 1000):
        cases.append((f"binary_stl_{d}", ".stl", _binary_stl(BASE, NC + d)))
    vtk = _vtk(BASE, True)
    for old, new in (
        (f"POINTS {NV} ", f"POINTS {NV + 1} "),
        (f"POINTS {NV} ", f"POINTS {NV - 1} "),
        (f"CELLS {NC + 1} ", f"CELLS {NC + 2} "),
        (f"CELLS {NC + 1} ", f"CELLS {NC} "),
        (f"CELL_TYPES {NC}", f"CELL_TYPES {NC + 1}"),
        (f"CELL_TYPES {NC}", f"CELL_TYPES {NC - 1}"),
    ):
        assert old.encode() in vtk, old
        cases.append((f"vtk_{new.strip()}", ".vtk", vtk.replace(old.encode(), new.encode(), 1)))
    return cases


@pytest.mark.parametrize(
    ("label", "extension", "content"), [pytest.param(*case, id=case[0]) for case in _count_mutations()]
)
def test_counts_off_by_one_are_refused(label: str, extension: str, content: bytes, tmp_path: Path) -> None:
    path = tmp_path / f"{label}{extension}"
    path.write_bytes(content)
    result = _read(path)
    assert isinstance(result, FileFormatError), f"{label}: read {result} without error"
    _check_error(result, path, content)


def _index_mutations() -> list[tuple[str, str, bytes]]:
    """Files with a bad index, a NaN or infinite coordinate, a broken STL loop, ...: each must be refused."""
    cases: list[tuple[str, str, bytes]] = []
    obj = _text_obj(BASE)
    last_face = obj.splitlines()[-1]
    for bad in (b"0", f"{NV + 1}".encode(), f"-{NV + 1}".encode(), b"1.5", b"", b"1/", b"x"):
        cases.append((f"obj_index_{bad!r}", ".obj", obj.replace(last_face, last_face.rsplit(b" ", 1)[0] + b" " + bad)))
    for extra in (
        b"l 1 2\n",
        b"curv 0 1 1 2\n",
        b"vertex 1 2 3\n",
        b"f 1 2 3 \\\n",
        b"v 1 2\n",
        b"v 1 2 3 4 5\n",
        b"f 1/ 2/ 3/\n",
        b"f 1///1 2 3\n",
        b"f 1 2 3 # fine\nf 1 2 -99\n",
    ):
        cases.append((f"obj_extra_{extra[:8]!r}", ".obj", obj + extra))
    off = _text_off(BASE)
    for bad in (b"-1", f"{NV}".encode(), b"2.0"):
        cases.append((f"off_index_{bad!r}", ".off", off.rstrip(b"\n").rsplit(b" ", 1)[0] + b" " + bad + b"\n"))
    ply = _ascii_ply(BASE)
    for bad in (b"-1", f"{NV}".encode()):
        cases.append((f"ply_index_{bad!r}", ".ply", ply.rstrip(b"\n").rsplit(b" ", 1)[0] + b" " + bad + b"\n"))
    for order in "<>":
        cells = BASE.cells.copy()
        cells[-1, -1] = NV
        cases.append((f"binary_ply{order}_index", ".ply", _binary_ply_cells(order, cells)))
    for coordinate in (b"nan", b"inf", b"-inf", b"1e999", b"NaN", b"1_0"):
        first = repr(float(BASE.vertices[1, 2])).encode()
        cases.append((f"obj_{coordinate!r}", ".obj", obj.replace(b" " + first + b"\n", b" " + coordinate + b"\n", 1)))
        cases.append((f"off_{coordinate!r}", ".off", off.replace(b" " + first + b"\n", b" " + coordinate + b"\n", 1)))
        cases.append((f"ply_{coordinate!r}", ".ply", ply.replace(b" " + first + b"\n", b" " + coordinate + b"\n", 1)))
    nan_vertices = BASE.vertices.copy()
    nan_vertices[2, 0] = np.nan
    cases.append(("binary_ply_nan", ".ply", _binary_ply_cells("<", BASE.cells, nan_vertices)))
    cases.append(("binary_stl_nan", ".stl", _binary_stl_nan()))
    for drop in ("endloop", "endfacet", "outer loop", "endsolid test"):
        cases.append((f"ascii_stl_no_{drop}", ".stl", _ascii_stl(BASE, drop)))
    ascii_stl = _ascii_stl(BASE)
    cases.append(
        ("ascii_stl_four_vertices", ".stl", ascii_stl.replace(b"  endloop", b"    vertex 0 0 0\n  endloop", 1))
    )
    # PLY headers that lie or are not PLY
    for old, new in (
        (b"format ascii 1.0", b"format binary_middle_endian 1.0"),
        (b"format ascii 1.0", b"format ascii 2.0"),
        (b"property double z\n", b""),
        (b"property double z\n", b"property double z\nproperty double w\n"),
        (b"property list uchar int vertex_indices", b"property list uchar int other"),
    ):
        cases.append((f"ply_header_{new!r}", ".ply", ply.replace(old, new, 1)))
    # GOCAD: a TRGL with a missing vertex, a repeated VRTX id, a cut line, a NaN
    tsurf = _gocad(BASE)
    cases.append(("tsurf_missing", ".ts", tsurf.replace(b"TRGL 1 4 5", b"TRGL 1 4 99", 1)))
    cases.append(("tsurf_repeated", ".ts", tsurf.replace(b"VRTX 2 ", b"VRTX 1 ", 1)))
    cases.append(("tsurf_cut_trgl", ".ts", tsurf.replace(b"TRGL 1 4 5", b"TRGL 1 4", 1)))
    cases.append(("tsurf_cut_vrtx", ".ts", tsurf.replace(b"VRTX 2 0.5 10.25", b"VRTX 2 0.5", 1)))
    cases.append(("tsurf_nan", ".ts", tsurf.replace(b"VRTX 2 0.5 ", b"VRTX 2 nan ", 1)))
    cases.append(("tsurf_no_end", ".ts", tsurf.replace(b"\nEND", b"\n", 1)))
    vtk = _vtk(BASE, True)
    connectivity = vtk.split(b"CONNECTIVITY vtktypeint64\n")[1].split(b"\n")[0]
    cases.append(("vtk_index", ".vtk", vtk.replace(connectivity, connectivity.rsplit(b" ", 1)[0] + f" {NV}".encode())))
    cases.append(("vtk_negative", ".vtk", vtk.replace(connectivity, b"-1" + connectivity[1:])))
    return cases


def _binary_ply_cells(order: str, cells: np.ndarray, vertices: np.ndarray | None = None) -> bytes:
    """A binary PLY of the cells and vertices as given, unchecked: the file must hold the bad values."""
    name = {"<": "binary_little_endian", ">": "binary_big_endian"}[order]
    vertices = BASE.vertices if vertices is None else vertices
    header = (
        f"ply\nformat {name} 1.0\nelement vertex {len(vertices)}\nproperty double x\nproperty double y\n"
        f"property double z\nelement face {len(cells)}\nproperty list uchar int vertex_indices\n"
        "end_header\n"
    ).encode()
    face = np.empty(len(cells), dtype=[("n", "u1"), ("v", order + "i4", 3)])
    face["n"], face["v"] = 3, cells
    return header + vertices.astype(order + "f8").tobytes() + face.tobytes()


def _binary_stl_nan() -> bytes:
    content = bytearray(_binary_stl(BASE))
    content[84 + 12 + 4 : 84 + 12 + 8] = np.float32(np.nan).tobytes()
    return bytes(content)


@pytest.mark.parametrize(
    ("label", "extension", "content"), [pytest.param(*case, id=case[0]) for case in _index_mutations()]
)
def test_bad_values_are_refused(label: str, extension: str, content: bytes, tmp_path: Path) -> None:
    path = tmp_path / f"bad{extension}"
    path.write_bytes(content)
    result = _read(path)
    assert isinstance(result, FileFormatError), f"{label}: read {result} without error"
    _check_error(result, path, content)


def test_gocad_ids_out_of_order_read_exactly(tmp_path: Path) -> None:
    """VRTX ids need not be ordered nor start at 1: the triangles follow the ids, not the order."""
    text = (
        "GOCAD TSurf 1\nHEADER {\nname: s\n}\nTFACE\nVRTX 30 0 0 0\nVRTX 7 1 0 0\nVRTX 12 0 1 0\n"
        "VRTX 5 1 1 0\nTRGL 30 7 12\nTRGL 7 5 12\nEND\n"
    )
    path = tmp_path / "s.ts"
    path.write_text(text)
    [surface] = read_gocad(path)
    assert surface.vertices[surface.cells].tolist() == [
        [[0, 0, 0], [1, 0, 0], [0, 1, 0]],
        [[1, 0, 0], [1, 1, 0], [0, 1, 0]],
    ]


# ---------------------------------------------------------------- issue 36, point 13: bounded messages and memory


def test_a_long_bad_word_is_quoted_short(tmp_path: Path) -> None:
    """A 500,000-character number (under the line limit) is named by its start and its length, not echoed."""
    word = "1x" * 250_000
    path = tmp_path / "s.ts"
    path.write_text(
        f"GOCAD TSurf 1\nHEADER {{\nname: s\n}}\nTFACE\nVRTX 1 {word} 0 0\nVRTX 2 1 0 0\nVRTX 3 0 1 0\n"
        "TRGL 1 2 3\nEND\n"
    )
    with pytest.raises(FileFormatError) as info:
        read_gocad(path)
    assert len(str(info.value)) < 400 and "500,000 characters" in str(info.value) and info.value.line == 6
    for extension, text in (
        (".obj", f"v 0 0 {word}\n"),
        (".off", f"OFF\n1 0 0\n0 0 {word}\n"),
        (
            ".ply",
            "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
            f"property float z\nend_header\n0 0 {word}\n",
        ),
    ):
        path = tmp_path / f"s{extension}"
        path.write_text(text)
        with pytest.raises(FileFormatError) as info:
            read_trimesh_file(path)
        assert len(str(info.value)) < 400 and "500,000 characters" in str(info.value), extension


HUGE = 100 * 1024 * 1024  # bytes of the one long line
_CHILD = textwrap.dedent("""
    import resource, sys
    limit = 3 << 30  # the machine is shared: a reader that wants gigabytes gets a MemoryError, not the machine
    resource.setrlimit(resource.RLIMIT_AS, (limit, limit))
    from tgsis import formats
    from tgsis.errors import FileFormatError
    try:
        formats.read(sys.argv[1])
        outcome = "read -1 0"
    except FileFormatError as exc:
        outcome = f"error {exc.line} {len(str(exc))}"
    except MemoryError:
        outcome = "memory -1 0"
    print(outcome, resource.getrusage(resource.RUSAGE_SELF).ru_maxrss)
""")


def _huge_files() -> list[tuple[str, str, bytes, bytes, int]]:
    """(label, extension, text before the long line, the repeated words, line number of the long line)."""
    return [
        ("obj_face", ".obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf ", b"1 2 3 ", 4),
        ("off_face", ".off", b"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n%d " % (HUGE // 2), b"0 1 2 ", 6),
        (
            "ply_face",
            ".ply",
            b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
            b"property float z\nelement face 1\nproperty list int int vertex_indices\nend_header\n"
            b"0 0 0\n1 0 0\n0 1 0\n%d " % (HUGE // 2),
            b"0 1 2 ",
            13,
        ),
        ("stl_vertex", ".stl", b"solid s\nfacet normal 0 0 1\nouter loop\nvertex ", b"1 ", 4),
        ("tsurf_vrtx_values", ".ts", b"GOCAD TSurf 1\nHEADER {\nname: s\n}\nTFACE\nVRTX 1 ", b"1 ", 6),
        ("tsurf_vrtx_number", ".ts", b"GOCAD TSurf 1\nHEADER {\nname: s\n}\nTFACE\nVRTX 1 0 0 ", b"7", 6),
        ("tsurf_properties", ".ts", b"GOCAD TSurf 1\nHEADER {\nname: s\n}\nPROPERTIES ", b"p ", 5),
        (
            "vtk_keyword_line",
            ".vtk",
            b"# vtk DataFile Version 5.1\nx\nASCII\nDATASET UNSTRUCTURED_GRID\nFIELD FieldData 1 ",
            b"x ",
            5,
        ),
        (
            "vtk_points_left_over",
            ".vtk",
            b"# vtk DataFile Version 5.1\nx\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 1 double\n",
            b"0 ",
            6,
        ),
    ]


@pytest.mark.parametrize(
    ("label", "extension", "head", "words", "line"), [pytest.param(*case, id=case[0]) for case in _huge_files()]
)
def test_a_100_mb_line_is_refused_in_bounded_memory(
    label: str, extension: str, head: bytes, words: bytes, line: int, tmp_path: Path
) -> None:
    """A 100 MB line is refused with its number and a short message; the reading process stays under 1 GB
    (measured: peak RSS of a child process; trimesh took 5.5 GB on a 100 MB OBJ face line)."""
    path = tmp_path / f"huge{extension}"
    with open(path, "wb") as handle:
        handle.write(head + words * (HUGE // len(words)) + b"\nEND\n")
    try:
        env = {**os.environ, "OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1"}
        result = subprocess.run(
            [sys.executable, "-c", _CHILD, str(path)], capture_output=True, text=True, timeout=600, env=env
        )
    finally:
        path.unlink()
    assert result.returncode == 0, result.stderr[-2000:]
    outcome, error_line, message_length, peak_kib = result.stdout.split()
    assert outcome == "error", result.stdout
    assert int(error_line) == line
    assert int(message_length) < 1000
    print(f"{label}: peak RSS {int(peak_kib) // 1024} MiB")
    assert int(peak_kib) < 1024 * 1024, f"peak RSS {int(peak_kib) // 1024} MiB"


def test_the_fast_and_the_line_by_line_readings_agree(monkeypatch: pytest.MonkeyPatch) -> None:
    """OBJ, OFF and ASCII PLY are read in C when the file is plain, line by line otherwise (which names
    the bad line): both give the same surface."""
    from tgsis.formats import _surface_files as sf

    quads = (
        b"v 0 0 0\r\nv 1 0 0\r\nv 1 1 0\r\nv 0 1 0\r\nv 2 2 0\r\nvt 0 0\r\nvn 0 0 1\r\n"
        b"f 1/1/1 2/1/1 3/1/1 4/1/1\r\nf 1//1 2//1 5//1 4//1\r\n"
    )
    obj_cases = [_text_obj(BASE), quads, _text_obj(BASE).replace(b"\n", b"\r\n")]
    for data in obj_cases:
        fast, slow = sf._obj_fast(data), sf._obj_slow(data, "x.obj")
        assert fast is not None
        assert np.array_equal(fast.vertices, slow.vertices) and np.array_equal(fast.triangles, slow.triangles)
    off = _text_off(BASE)
    fast = sf.parse_off(off, "x.off")
    slow = sf.parse_off(off.replace(b"\n", b" # comment\n", 3), "x.off")  # a comment: line by line
    assert np.array_equal(fast.vertices, slow.vertices) and np.array_equal(fast.triangles, slow.triangles)
    ply = _ascii_ply(BASE)
    fast = sf.parse_ply(ply, "x.ply")
    monkeypatch.setattr(sf, "_ply_ascii_fast", lambda *args: None)
    slow = sf.parse_ply(ply, "x.ply")
    assert np.array_equal(fast.vertices, slow.vertices) and np.array_equal(fast.triangles, slow.triangles)
    assert np.array_equal(fast.vertices, BASE.vertices) and np.array_equal(fast.triangles, BASE.cells)


def test_an_obj_face_block_the_fast_reader_declines_is_read_without_backtracking(tmp_path: Path) -> None:
    """Face lines with slashes and a trailing comment make the fast OBJ reader give up and read line by line;
    its check of the corners once backtracked exponentially in the number of lines (3 lines never ended).
    Run in a child process so that a regression fails (after 120 s) instead of hanging the suite."""
    path = tmp_path / "commented.obj"
    corners = "123/45/67 891/23/45 678/90/12"  # runs of several digits: the old check could split them
    path.write_text(
        "".join(f"v {i} {i % 7} {i % 3}\n" for i in range(1, 1001))
        + "\n".join([f"f {corners}"] * 40)
        + " # the last face\n"
    )
    code = (
        "import sys\nfrom tgsis.formats.trimesh_io import read_trimesh_file\n"
        "try:\n    m = read_trimesh_file(sys.argv[1])\n    print(m.n_vertices, m.n_cells)\n"
        "except Exception as e:\n    print(type(e).__name__, e)\n"
    )
    done = subprocess.run(
        [sys.executable, "-c", code, str(path)], capture_output=True, text=True, timeout=120, check=True
    )
    assert done.stdout.split()[:2] == ["1000", "40"] or done.stdout.startswith("FileFormatError"), done.stdout
