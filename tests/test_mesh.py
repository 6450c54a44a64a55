"""Mesh types: validation errors, flagged defects, trimesh conversion (no database)."""

from __future__ import annotations

import numpy as np
import pytest

import tgsis
from tgsis.mesh import Geotype, LineSet, PointSet, Surface, TetraMesh, mesh_class

SQUARE = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], dtype=float)
TWO_TRIANGLES = np.array([[0, 1, 2], [0, 2, 3]])


def test_arrays_are_normalised() -> None:
    s = Surface(SQUARE.tolist(), TWO_TRIANGLES.astype(np.int32))
    assert s.vertices.dtype == np.float64 and s.vertices.flags.c_contiguous
    assert s.cells.dtype == np.int64 and s.triangles is s.cells
    assert (s.n_vertices, s.n_cells) == (4, 2)
    assert s.bounds().tolist() == [[0, 0, 0], [1, 1, 0]]


@pytest.mark.parametrize(
    ("vertices", "message"),
    [
        (np.zeros((4, 2)), r"vertices must be an \(n, 3\) array, got shape \(4, 2\)"),
        ([[0, 0, 0], [1, np.nan, 0], [0, 1, 0]], r"vertex 1 has a non-finite y coordinate \(nan\)"),
        ([[0, 0, 0], [1, 0, 0], [0, 1, np.inf]], r"vertex 2 has a non-finite z coordinate \(inf\)"),
        ([["a", 0, 0]], "vertices are not numbers"),
    ],
)
def test_bad_vertices(vertices: object, message: str) -> None:
    with pytest.raises(tgsis.InvalidGeometryError, match=message):
        Surface(vertices, [[0, 1, 2]] if np.ndim(vertices) == 2 and len(vertices) >= 3 else [])  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("cells", "message"),
    [
        ([[0, 1, 4]], "triangle 0 refers to vertex 4, but the mesh has 4 vertices"),
        ([[0, 1, 2], [0, -1, 2]], "triangle 1 refers to vertex -1"),
        ([[0, 1, 2], [2, 3, 2]], r"triangle 1 uses a vertex twice: \[2, 3, 2\]"),
        ([[0, 1]], r"triangles must be an \(m, 3\) array of vertex indices, got shape \(1, 2\)"),
        ([[0.5, 1, 2]], "triangle indices must be integers"),
    ],
)
def test_bad_triangles(cells: object, message: str) -> None:
    with pytest.raises(tgsis.InvalidGeometryError, match=message):
        Surface(SQUARE, cells)  # type: ignore[arg-type]


def test_bad_tetrahedra_and_segments_name_their_cell_kind() -> None:
    with pytest.raises(tgsis.InvalidGeometryError, match="tetrahedron 0 uses a vertex twice"):
        TetraMesh(SQUARE, [[0, 1, 2, 1]])
    with pytest.raises(tgsis.InvalidGeometryError, match="segment 0 uses a vertex twice"):
        LineSet(SQUARE, [[3, 3]])


@pytest.mark.parametrize(
    ("props", "message"),
    [
        ({"porosity": np.ones(3)}, "vertex property 'porosity' has 3 values for 4 vertices"),
        ({"Poro sity": np.ones(4)}, "vertex property name 'Poro sity' is not allowed"),
        ({"_idx": np.ones(4)}, "not allowed"),
        ({"label": np.array(["a", "b", "c", "d"])}, "has values of type <U1, not numbers"),
        ({"vec": np.ones((4, 2, 2))}, r"must be one value or one vector of values per vertex, got shape \(4, 2, 2\)"),
        ({"vec": np.ones((4, 0))}, r"got shape \(4, 0\)"),
    ],
)
def test_bad_vertex_properties(props: dict[str, object], message: str) -> None:
    with pytest.raises(tgsis.InvalidPropertyError, match=message):
        Surface(SQUARE, TWO_TRIANGLES, vertex_properties=props)  # type: ignore[arg-type]


def test_bad_cell_property_length() -> None:
    with pytest.raises(tgsis.InvalidPropertyError, match="triangle property 'facies' has 3 values for 2 triangles"):
        Surface(SQUARE, TWO_TRIANGLES, cell_properties={"facies": [1, 2, 3]})


def test_report_flags_duplicates_and_degenerate_cells() -> None:
    vertices = np.vstack([SQUARE, np.array([[1, 0, 0], [2, 0, 0], [-0.0, 0.0, 0.0]])])  # 4 = copy of 1, 6 = copy of 0
    triangles = [[0, 1, 2], [0, 1, 5], [0, 2, 3], [1, 4, 2]]  # 1: collinear (zero area); 3: uses a duplicate
    report = Surface(vertices, triangles).report()
    assert report.duplicate_vertices.tolist() == [[0, 6], [1, 4]]
    assert report.degenerate_cells.tolist() == [1, 3]
    assert not report.ok and report.summary() == "2 duplicate vertices, 2 degenerate cells"
    assert Surface(SQUARE, TWO_TRIANGLES).report().ok


def test_degenerate_tetrahedra_and_segments() -> None:
    flat = TetraMesh(np.vstack([SQUARE, [[0, 0, 1]]]), [[0, 1, 2, 3], [0, 1, 2, 4]])
    assert flat.report().degenerate_cells.tolist() == [0]
    assert flat.cell_measures()[1] == pytest.approx(1 / 6)
    lines = LineSet([[0, 0, 0], [0, 0, 0], [1, 0, 0]], [[0, 1], [1, 2]])
    assert lines.report().degenerate_cells.tolist() == [0]


def test_point_set_defaults_to_one_cell_per_vertex() -> None:
    points = PointSet(SQUARE, vertex_properties={"depth": [1.0, 2.0, 3.0, 4.0]})
    assert points.cells.tolist() == [[0], [1], [2], [3]]
    assert points.report().degenerate_cells.size == 0


def test_same_as_is_bit_exact() -> None:
    a = Surface(SQUARE, TWO_TRIANGLES, vertex_properties={"p": [1.0, np.nan, 2.0, 3.0]})
    b = a.copy()
    assert a.same_as(b)
    b.vertices[0, 0] = -0.0
    assert not a.same_as(b), "-0.0 and 0.0 differ in bits"
    c = a.copy()
    c.vertices[1, 0] = np.nextafter(1.0, 2.0)
    assert not a.same_as(c)


def test_trimesh_round_trip_keeps_order_and_properties() -> None:
    s = Surface(
        SQUARE,
        TWO_TRIANGLES,
        vertex_properties={"p": [1.0, 2.0, 3.0, 4.0]},
        cell_properties={"facies": [7, 8]},
        name="sq",
    )
    tm = s.to_trimesh()
    assert tm.vertices.tolist() == SQUARE.tolist() and tm.faces.tolist() == TWO_TRIANGLES.tolist()
    back = Surface.from_trimesh(tm)
    assert back.same_as(s) and back.name == "sq"


@pytest.mark.parametrize(
    ("geotype", "cls"),
    [("SURFACE", Surface), ("multipoint", PointSet), (Geotype.MULTITETRA, TetraMesh), ("MULTILINESTRING", LineSet)],
)
def test_mesh_class(geotype: object, cls: type) -> None:
    assert mesh_class(geotype) is cls  # type: ignore[arg-type]


def test_mesh_class_refuses_collections_and_nonsense() -> None:
    for bad in ("GEOMETRYCOLLECTION", "POLYGON"):
        with pytest.raises(tgsis.InvalidGeometryError, match="no mesh type for geotype"):
            mesh_class(bad)
