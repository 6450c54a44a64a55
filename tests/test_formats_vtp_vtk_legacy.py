""".vtp and legacy .vtk in tgsis itself: layout, the sections other writers use, and files tgsis refuses.

The libraries' side (pyvista and meshio reading what tgsis writes and the
reverse) is tests/test_formats_vtk_libraries.py.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest
import pyvista as pv

from tgsis import formats
from tgsis.errors import FileFormatError
from tgsis.formats.vtk import format_vtp, parse_vtp
from tgsis.formats.vtk_legacy import format_vtk, parse_vtk, parse_vtk_geometry
from tgsis.mesh import GeometryCollection, LineSet, PointSet, Surface, TetraMesh


def surface() -> Surface:
    return Surface(
        np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0.5]]),
        [[0, 1, 2], [1, 3, 2]],
        vertex_properties={
            "depth": np.array([0, 1, 2, 3.0]),
            "flag": np.array([True, False, True, True]),
            "small": np.array([1, 2, 3, 4], dtype=np.int8),
        },
        cell_properties={"zone": np.array([4, 5], dtype=np.int32)},
        name="h",
    )


def test_registry_and_extensions() -> None:
    assert formats.format_for("a.vtp").name == "vtp" and formats.format_for("a.VTK").name == "vtk"
    assert formats.format_for("a.dat", "vtk").name == "vtk" and formats.format_for("a.dat", ".vtp").name == "vtp"
    with pytest.raises(
        FileFormatError, match="vtp files store MULTIPOINT, MULTILINESTRING, SURFACE, not MULTITETRA"
    ) as info:
        formats.write(TetraMesh(np.eye(4, 3), [[0, 1, 2, 3]]), "t.vtp")
    assert info.value.hint is not None and "vtu (.vtu)" in info.value.hint and "vtk (.vtk)" in info.value.hint


def test_vtp_layout() -> None:
    root = ET.fromstring(format_vtp(surface(), compression=None))
    assert root.attrib == {"type": "PolyData", "version": "1.0", "byte_order": "LittleEndian", "header_type": "UInt64"}
    [piece] = root.findall("PolyData/Piece")
    assert piece.attrib == {
        "NumberOfPoints": "4",
        "NumberOfVerts": "0",
        "NumberOfLines": "0",
        "NumberOfStrips": "0",
        "NumberOfPolys": "2",
    }
    assert [e.get("Name") for e in piece.findall("Polys/DataArray")] == ["connectivity", "offsets"]
    assert [child.tag for child in piece] == ["PointData", "CellData", "Points", "Verts", "Lines", "Strips", "Polys"]
    compressed = ET.fromstring(format_vtp(surface()))
    assert compressed.get("compressor") == "vtkZLibDataCompressor"


@pytest.mark.parametrize("mesh", [surface(), PointSet(np.eye(3), name="p"), LineSet(np.eye(3), [[0, 1], [1, 2]])])
def test_vtp_round_trip(mesh: Surface) -> None:
    back = parse_vtp(format_vtp(mesh))
    assert type(back) is type(mesh) and back.same_as(mesh) and back.name == mesh.name
    if isinstance(mesh, Surface):  # VTK has no bool: flags come back as uint8
        assert back.vertex_properties["flag"].dtype == np.uint8 and back.vertex_properties["small"].dtype == np.int8


def test_legacy_layout_and_types() -> None:
    text = format_vtk(surface(), ascii=True).decode()
    lines = text.splitlines()
    assert lines[:4] == ["# vtk DataFile Version 5.1", "h", "ASCII", "DATASET UNSTRUCTURED_GRID"]
    assert "CELLS 3 6" in lines and "OFFSETS vtktypeint64" in lines and lines[lines.index("CELL_TYPES 2") + 1] == "5 5"
    assert "small 1 4 vtktypeint64" in lines and "depth 1 4 double" in lines  # small integers widened
    back = parse_vtk(format_vtk(surface()))
    assert back.same_as(
        Surface(
            surface().vertices,
            surface().cells,
            vertex_properties={
                **surface().vertex_properties,
                "flag": np.array([1, 0, 1, 1]),
                "small": np.array([1, 2, 3, 4]),
            },
            cell_properties={"zone": np.array([4, 5])},
        )
    )
    assert {k: v.dtype for k, v in back.vertex_properties.items()} == {
        "depth": np.float64,
        "flag": np.int64,
        "small": np.int64,
    }
    assert back.name == "h"


def test_legacy_ascii_is_exact() -> None:
    vertices = np.array([[0.1, 1 / 3, -0.0], [5e-324, 1e300, 2.0**0.5], [np.pi, np.e, 1e-310]])
    mesh = Surface(vertices, [[0, 1, 2]], vertex_properties={"x": np.array([np.nan, np.inf, -np.inf])})
    back = parse_vtk(format_vtk(mesh, ascii=True))
    assert back.vertices.view(np.int64).tolist() == vertices.view(np.int64).tolist()
    assert np.array_equal(back.vertex_properties["x"], mesh.vertex_properties["x"], equal_nan=True)


LEGACY_42 = """# vtk DataFile Version 4.2
written by hand as other tools do
ASCII
DATASET POLYDATA
FIELD FieldData 2
name 1 1 string
Big%20Spring
TIME 1 1 double
1.5
POINTS 5 float
0 0 0  1 0 0  0 1 0  1 1 0  2 2 0
METADATA
INFORMATION 0

POLYGONS 3 12
3 0 1 2
3 1 3 2
3 3 4 2
POINT_DATA 5
SCALARS temperature float
LOOKUP_TABLE default
10 11 12 13 14
VECTORS slip double
1 0 0 0 1 0 0 0 1 1 1 1 0 0 0
SCALARS two int 2
1 2 3 4 5 6 7 8 9 10
FIELD extra 2
unit 1 5 string
a
b
c
d
e
weight 1 5 unsigned_char
1 2 3 4 5
CELL_DATA 3
SCALARS rock short 1
LOOKUP_TABLE rocks
7 8 9
LOOKUP_TABLE rocks 2
0 0 0 1 1 1 1 1
COLOR_SCALARS rgb 3
0 0 1 0 1 0 1 0 0
"""


def test_legacy_sections_other_writers_use() -> None:
    mesh = parse_vtk(LEGACY_42.encode())
    assert isinstance(mesh, Surface) and mesh.name == "Big Spring"
    assert mesh.cells.tolist() == [[0, 1, 2], [1, 3, 2], [3, 4, 2]]
    props = mesh.vertex_properties
    assert list(props) == ["temperature", "slip", "two", "weight"]  # the string array is skipped
    assert props["temperature"].dtype == np.float32 and props["slip"].shape == (5, 3)
    assert props["two"].tolist() == [[1, 2], [3, 4], [5, 6], [7, 8], [9, 10]]
    assert mesh.cell_properties["rock"].tolist() == [7, 8, 9] and mesh.cell_properties["rgb"].shape == (3, 3)


def test_legacy_polylines_and_poly_vertices() -> None:
    text = (
        "# vtk DataFile Version 3.0\nx\nASCII\nDATASET POLYDATA\nPOINTS 4 double\n0 0 0 1 0 0 2 0 0 3 1 0\n"
        "LINES 2 7\n3 0 1 2\n2 2 3\nCELL_DATA 2\nSCALARS id int\nLOOKUP_TABLE default\n5 6\n"
    )
    lines = parse_vtk(text.encode())
    assert isinstance(lines, LineSet) and lines.cells.tolist() == [[0, 1], [1, 2], [2, 3]]
    assert lines.cell_properties["id"].tolist() == [5, 5, 6]
    text = "# vtk DataFile Version 3.0\nx\nASCII\nDATASET POLYDATA\nPOINTS 3 double\n0 0 0 1 0 0 2 0 0\nVERTICES 1 4\n3 0 1 2\n"
    points = parse_vtk(text.encode())
    assert isinstance(points, PointSet) and points.cells.tolist() == [[0], [1], [2]]


def test_a_legacy_collection_keeps_its_members() -> None:
    members = [
        surface(),
        PointSet(
            np.eye(3) + 5,
            name="wells",
            vertex_properties={k: v[:3] for k, v in surface().vertex_properties.items()},
            cell_properties={"zone": np.arange(3, dtype=np.int32)},
        ),
    ]
    geometry = parse_vtk_geometry(format_vtk(GeometryCollection(members, name="m")))
    assert isinstance(geometry, GeometryCollection) and geometry.name == "m"
    assert [m.name for m in geometry.members] == ["h", "wells"]
    with pytest.raises(FileFormatError, match="holds a GEOMETRYCOLLECTION of 2 members"):
        parse_vtk(format_vtk(GeometryCollection(members)))


# ---------------------------------------------------------------- hostile files


def test_vtp_files_tgsis_refuses(tmp_path: Path) -> None:
    warped = pv.Plane(i_resolution=2, j_resolution=1)
    warped.points[1, 2] = 0.25  # type: ignore[index]  # pyvista types __setitem__'s key int only
    # quads that are not planar: no one surface to split them into (issue 37)
    warped.save(tmp_path / "quads.vtp")
    with pytest.raises(FileFormatError, match=r"quads.vtp: PolyData cell 0 has 4 points and is not planar") as info:
        formats.read(tmp_path / "quads.vtp")
    assert info.value.hint is not None and "triangulate" in info.value.hint
    pv.Sphere(theta_resolution=6, phi_resolution=6).strip().save(tmp_path / "strips.vtp")
    with pytest.raises(FileFormatError, match="TRIANGLE_STRIP"):
        formats.read(tmp_path / "strips.vtp")
    (pv.Sphere(theta_resolution=6, phi_resolution=6) + pv.Line()).save(tmp_path / "mixed.vtp")
    with pytest.raises(FileFormatError, match=r"mixes cells of several kinds \(LINE \(1\), TRIANGLE \(48\)\)"):
        formats.read(tmp_path / "mixed.vtp")
    nan = pv.PolyData(np.array([[0, 0, 0], [1, 0, 0], [0, np.nan, 0.0]]), faces=[3, 0, 1, 2])
    nan.save(tmp_path / "nan.vtp")
    with pytest.raises(FileFormatError, match="vertex 2 has a non-finite y coordinate"):
        formats.read(tmp_path / "nan.vtp")
    data = format_vtp(surface(), compression=None)
    with pytest.raises(FileFormatError, match="expected one Piece in the PolyData, found 2"):
        parse_vtp(data.replace(b"</PolyData>", b'<Piece NumberOfPoints="0"/></PolyData>'))
    with pytest.raises(FileFormatError, match="DataArray 'Points' has 12 values, expected 5 x 3"):
        parse_vtp(data.replace(b'NumberOfPoints="4"', b'NumberOfPoints="5"'))
    ascii_file = (
        '<VTKFile type="PolyData"><PolyData><Piece NumberOfPoints="3" NumberOfPolys="1"><PointData>'
        '<DataArray type="Float64" Name="depth" format="ascii">1 2</DataArray></PointData>'
        '<Points><DataArray type="Float64" NumberOfComponents="3" format="ascii">0 0 0 1 0 0 0 1 0'
        '</DataArray></Points><Polys><DataArray type="Int64" Name="connectivity" format="ascii">0 1 2'
        '</DataArray><DataArray type="Int64" Name="offsets" format="ascii">3</DataArray></Polys>'
        "</Piece></PolyData></VTKFile>"
    )
    with pytest.raises(FileFormatError, match="DataArray 'depth' has 2 values, expected 3 x 1"):
        parse_vtp(ascii_file.encode())
    assert parse_vtp(ascii_file.replace(">1 2<", ">1 2 3<").encode()).vertex_properties["depth"].tolist() == [1, 2, 3]
    bad = data.replace(b'NumberOfPolys="2"', b'NumberOfPolys="3"')
    with pytest.raises(FileFormatError, match="<Polys> offsets do not describe 3 cells"):
        parse_vtp(bad)
    with pytest.raises(FileFormatError, match="not a VTK PolyData file") as info:
        parse_vtp(formats.format_vtu(surface()))
    assert info.value.hint == "a .vtu file is read as VTK UnstructuredGrid"


def test_legacy_files_tgsis_refuses(tmp_path: Path) -> None:
    pv.ImageData(dimensions=(2, 2, 2)).save(tmp_path / "image.vtk")
    with pytest.raises(FileFormatError, match="DATASET STRUCTURED_POINTS is not read by tgsis") as info:
        formats.read(tmp_path / "image.vtk")
    assert info.value.hint is not None and "cast_to_unstructured_grid" in info.value.hint
    with pytest.raises(FileFormatError, match="not a legacy VTK file") as info:
        parse_vtk(format_vtp(surface()))
    assert info.value.hint is not None and ".vtp" in info.value.hint
    data = format_vtk(surface())
    with pytest.raises(FileFormatError, match="the file ends after"):
        parse_vtk(data[: data.index(b"CONNECTIVITY") + 40])
    wrong = (
        "# vtk DataFile Version 2.0\nw\nASCII\nDATASET POLYDATA\nPOINTS 3 float\n0 0 0 1 0 0 0 1 0\n"
        "POLYGONS 1 4\n3 0 1 2\nPOINT_DATA 2\nSCALARS temperature float\nLOOKUP_TABLE default\n10 11\n"
    )
    with pytest.raises(FileFormatError, match="point_data array 'temperature' has 2 tuples, the dataset 3"):
        parse_vtk(wrong.encode())
    with pytest.raises(FileFormatError, match="unexpected section '12'"):  # more values than POINT_DATA says
        parse_vtk(wrong.replace("10 11", "10 11 12").encode())
    outside = LEGACY_42.replace("3 3 4 2", "3 3 9 2")
    with pytest.raises(FileFormatError, match="a cell refers to point 9, but the file has 5 points"):
        parse_vtk(outside.encode())
    quads = "# vtk DataFile Version 2.0\nq\nASCII\nDATASET POLYDATA\nPOINTS 4 float\n0 0 0 1 0 0 1 1 0 0 1 0\nPOLYGONS 1 5\n4 0 1 2 3\n"
    with pytest.raises(FileFormatError, match=r"POLYDATA cell 0 has 4 points and is not convex"):
        parse_vtk(quads.replace("1 1 0 0 1 0", "0.2 0.2 0 0 1 0").encode())  # a dart (a planar one is split)
    mixed = (
        "# vtk DataFile Version 2.0\nq\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 4 float\n0 0 0 1 0 0 1 1 0 0 1 1\n"
        "CELLS 2 7\n3 0 1 2\n2 2 3\nCELL_TYPES 2\n5\n3\n"
    )
    with pytest.raises(FileFormatError, match="mixes cells of several kinds"):
        parse_vtk(mixed.encode())
    hexahedra = mixed.replace(
        "CELLS 2 7\n3 0 1 2\n2 2 3\nCELL_TYPES 2\n5\n3\n", "CELLS 1 5\n4 0 1 2 3\nCELL_TYPES 1\n9\n"
    )
    with pytest.raises(FileFormatError, match=r"UNSTRUCTURED_GRID cell 0 has 4 points and is not planar"):
        parse_vtk(hexahedra.encode())
    with pytest.raises(FileFormatError, match=r"HEXAHEDRON \(12\) cells"):
        parse_vtk(
            hexahedra.replace(
                "CELLS 1 5\n4 0 1 2 3\nCELL_TYPES 1\n9", "CELLS 1 9\n8 0 1 2 3 0 1 2 3\nCELL_TYPES 1\n12"
            ).encode()
        )
    with pytest.raises(FileFormatError, match="CELL_TYPES gives 1 types for 2 cells"):
        parse_vtk(mixed.replace("CELL_TYPES 2\n5\n3\n", "CELL_TYPES 1\n5\n").encode())
    bits = quads.replace("POLYGONS 1 5\n4 0 1 2 3\n", "POINT_DATA 4\nSCALARS b bit\nLOOKUP_TABLE default\n0 1 0 1\n")
    with pytest.raises(FileFormatError, match="is a bit array, which tgsis does not read"):
        parse_vtk(bits.encode())
    with pytest.raises(FileFormatError, match="unexpected section 'HELLO'"):
        parse_vtk(quads.replace("POLYGONS", "HELLO").encode())
