"""Model 5 in numpy: extrusion along a new axis, slices at a value of one axis, round trips."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import tgsis
from tests import gmaps_shapes as shapes
from tgsis.gmaps import GMap, extrude, slice


def counts(g: GMap) -> list[int]:
    return [g.n_cells(i) for i in range(g.dimension + 1)]


def product_counts(g: GMap, intervals: int) -> list[int]:
    """Cells of g x (a chain of k intervals): c_i = sum over a + b = i of c_a(g) c_b(chain)."""
    return np.convolve(counts(g), [intervals + 1, intervals]).tolist()


SQUARE = GMap.from_polygons([[0, 0], [1, 0], [1, 1], [0, 1]], [[0, 1, 2, 3]])


def test_square_extruded_is_a_cube() -> None:
    cube = extrude(SQUARE, [0.0, 1.0])
    assert cube.dimension == 3 and cube.n_darts == 48 and cube.check().ok
    assert counts(cube) == [8, 12, 6, 1] and cube.euler_characteristic() == 1
    assert cube.points.tolist() == [
        [0, 0, 0],
        [1, 0, 0],
        [1, 1, 0],
        [0, 1, 0],
        [0, 0, 1],
        [1, 0, 1],
        [1, 1, 1],
        [0, 1, 1],
    ]
    border = cube.border()
    assert border.check().ok and counts(border) == [8, 12, 6] and border.euler_characteristic() == 2
    indices, face_offsets, cell_offsets = cube.polyhedra()  # its one volume: six quads
    assert cell_offsets.tolist() == [0, 6] and np.diff(face_offsets).tolist() == [4] * 6
    assert sorted(tuple(sorted(indices[a:b].tolist())) for a, b in zip(face_offsets[:-1], face_offsets[1:])) == [
        (0, 1, 2, 3),
        (0, 1, 4, 5),
        (0, 3, 4, 7),
        (1, 2, 5, 6),
        (2, 3, 6, 7),
        (4, 5, 6, 7),
    ]
    faces, offsets = border.polygons()
    assert np.diff(offsets).tolist() == [4] * 6
    assert sorted(tuple(sorted(faces[a:b].tolist())) for a, b in zip(offsets[:-1], offsets[1:])) == [
        (0, 1, 2, 3),
        (0, 1, 4, 5),
        (0, 3, 4, 7),
        (1, 2, 5, 6),
        (2, 3, 6, 7),
        (4, 5, 6, 7),
    ]


def test_several_intervals() -> None:
    column = extrude(SQUARE, [0, 1, 3, 4])
    assert column.check().ok and counts(column) == [16, 28, 16, 3] == product_counts(SQUARE, 3)
    assert column.euler_characteristic() == 1
    # inner layers are sewn: only the bottom, top and side faces are on the border
    assert column.border().n_cells(2) == 2 + 4 * 3
    _, face_offsets, cell_offsets = column.polyhedra()  # three cubes: the inner faces are listed twice
    assert cell_offsets.tolist() == [0, 6, 12, 18] and len(face_offsets) == 19
    with pytest.raises(tgsis.InvalidInputError, match="a 2-G-map has no volumes"):
        SQUARE.polyhedra()


@pytest.mark.parametrize(
    ("shape", "chi"),
    [
        (lambda: shapes.grid(3, 2), 1),  # disk
        (shapes.octahedron, 2),  # sphere
        (lambda: shapes.grid(4, 3, wrap_x=True, wrap_y=True), 0),  # torus
        (lambda: shapes.grid(5, 2, wrap_x=True, twist=True), 0),  # Möbius strip
    ],
)
def test_triangle_meshes_extruded_twice(shape: object, chi: int) -> None:
    g = GMap.from_triangles(*shape())  # type: ignore[operator]
    once = extrude(g, [0.0, 0.5, 2.0])
    twice = extrude(once, [-1.0, 1.0])
    for h, dim in ((once, 3), (twice, 4)):
        report = h.check()
        assert report.ok, report.summary()
        assert h.dimension == dim and h.embedding_dimension == dim + 1
        assert h.euler_characteristic() == chi  # chi(g x I) = chi(g) chi(I) = chi(g)
    assert counts(once) == product_counts(g, 2)
    assert counts(twice) == product_counts(once, 1)
    assert twice.n_darts == g.n_darts * (2 * 3 * 2) * (2 * 4 * 1)


def test_sphere_extruded_is_a_shell() -> None:
    shell = extrude(GMap.from_triangles(*shapes.octahedron()), [1.0, 2.0])
    border = shell.border()
    assert border.components()[1] == 2 and border.euler_characteristic() == 4  # inner and outer sphere


def test_points_segments_and_tetrahedra() -> None:
    v = np.array([[0, 0, 0], [1, 0, 0], [2, 1, 0]], dtype=float)
    lines = extrude(GMap.from_points(v), [0, 1, 2])  # three vertical polylines of 2 segments
    assert lines.dimension == 1 and lines.check().ok and counts(lines) == [9, 6]
    assert lines.euler_characteristic() == 3 and len(lines.border_darts()) == 6
    strip = extrude(GMap.from_segments(v, [[0, 1], [1, 2]]), [0, 1])
    assert strip.check().ok and counts(strip) == [6, 7, 2]
    assert strip.polygons()[1].tolist() == [0, 4, 8]
    solid = GMap.from_tetrahedra(*shapes.cube_tetrahedra())
    four = extrude(solid, [0, 1])
    assert four.dimension == 4 and four.check().ok
    assert counts(four) == product_counts(solid, 1) and four.euler_characteristic() == 1


def test_properties_follow_the_top_cells() -> None:
    v, t = shapes.octahedron()
    g = GMap(
        GMap.from_triangles(v, t).alpha,
        GMap.from_triangles(v, t).vertex,
        v,
        cell_properties={2: {"rock": np.arange(8)}, 0: {"depth": np.arange(6.0)}},
    )
    ex = extrude(g, [0, 1, 2])
    assert list(ex.cell_properties) == [3]  # lower levels are dropped
    assert ex.cell_properties[3]["rock"].tolist() == list(range(8)) * 2
    # cell j * 8 + c of the prism layer j is triangle c
    assert ex.cells(3)[ex.cell_darts(3)].tolist() == list(range(16))


@pytest.mark.parametrize("values", [[0.0], [[0, 1]], [0, 1, 1], [1, 0], [0, np.nan], ["a", "b"]])
def test_bad_values(values: object) -> None:
    with pytest.raises(tgsis.InvalidInputError, match="values must be"):
        extrude(SQUARE, values)  # type: ignore[arg-type]


# ---- slices


@pytest.mark.parametrize(
    "shape",
    [
        lambda: GMap.from_triangles(*shapes.grid(3, 2)),
        lambda: GMap.from_triangles(*shapes.grid(5, 2, wrap_x=True, twist=True)),
        lambda: GMap.from_tetrahedra(*shapes.cube_tetrahedra()),
        lambda: GMap.from_segments(np.eye(3), [[0, 1], [1, 2]]),
        lambda: SQUARE,
        lambda: GMap.from_polygons([[-0.0, 0], [1, -0.0], [1.0, 1], [0.0, 1]], [[0, 1, 2, 3]]),  # -0.0 kept as it is
    ],
)
def test_slices_of_an_extrusion_give_it_back(shape: object) -> None:
    g = shape()  # type: ignore[operator]
    c = g.n_cells(g.dimension)
    g = GMap(
        g.alpha,
        g.vertex,
        g.points,
        cell_properties={g.dimension: {"code": np.arange(c) * 10, "dip": np.arange(2.0 * c).reshape(c, 2)}},
    )
    values = [0.0, 0.5, 2.0, 3.0]
    ex = extrude(g, values)
    axis = g.embedding_dimension
    for value in values:  # at a layer: the same darts, points and properties
        back = slice(ex, axis, value)
        assert back.same_as(g), value
    for value in (0.25, 1.0, 2.9):  # between layers: the interpolated layer, here the same shape again
        between = slice(ex, axis, value)
        assert between.same_as(g), value
    assert slice(ex, axis, 3.5).n_darts == 0 and slice(ex, axis, -1).dimension == g.dimension
    # tgsis exports them under model-5 names
    assert tgsis.slice_gmap is slice and tgsis.extrude_gmap is extrude


def test_slice_of_a_moving_shape_is_interpolated() -> None:
    """A square moving in time: a polyhedron in 2D x time whose slices are the square in between."""
    cube = extrude(SQUARE, [0.0, 1.0])
    points = cube.points.copy()
    points[4:, 0] += 2.0  # at t = 1 the square has moved by 2 along x
    moving = GMap(cube.alpha, cube.vertex, points)
    assert moving.check().ok
    mid = slice(moving, 2, 0.25)
    assert mid.points.tolist() == [[0.5, 0], [1.5, 0], [1.5, 1], [0.5, 1]]
    assert np.array_equal(mid.alpha, SQUARE.alpha) and np.array_equal(mid.vertex, SQUARE.vertex)


def test_sections_of_a_tetrahedral_solid() -> None:
    solid = GMap.from_tetrahedra(*shapes.cube_tetrahedra())
    for z in (0.0, 1.0):  # the bottom and top faces: a square of 2 triangles
        face = slice(solid, 2, z)
        assert face.check().ok and counts(face) == [4, 5, 2] and face.euler_characteristic() == 1
        assert sorted(map(tuple, face.points.tolist())) == [(0, 0), (0, 1), (1, 0), (1, 1)]
    mid = slice(solid, 2, 0.5)  # a section through every tetrahedron: a polygon per tetrahedron
    assert mid.check().ok and mid.n_cells(2) == 5 and mid.euler_characteristic() == 1
    assert mid.border().components()[1] == 1
    assert np.allclose(mid.points.min(axis=0), [0, 0]) and np.allclose(mid.points.max(axis=0), [1, 1])
    loop = slice(GMap.from_triangles(*shapes.octahedron()), 0, 0.0)  # the octahedron's equator
    assert loop.dimension == 1 and loop.check().ok and counts(loop) == [4, 4]
    assert len(loop.border_darts()) == 0


def test_refused_slices() -> None:
    v = np.array([[0, 0, 0], [0.5, 0, 0], [1, 1, 0], [0, 1, 0]], dtype=float)
    g = GMap.from_triangles(v, [[0, 1, 2], [0, 2, 3]])
    with pytest.raises(tgsis.InvalidInputError, match="passes through vertices and crosses edges"):
        slice(g, 0, 0.5)
    with pytest.raises(tgsis.InvalidInputError, match=r"axis must be an integer in 0..2, got 3"):
        slice(g, 3, 0.5)
    with pytest.raises(tgsis.InvalidInputError, match="value must be finite"):
        slice(g, 0, float("nan"))
    with pytest.raises(tgsis.InvalidInputError, match="cannot be sliced"):
        slice(GMap.from_points(v), 0, 0.5)
    # a plane through a vertex that no face in the plane holds (the apex of a triangle)
    with pytest.raises(tgsis.InvalidInputError, match="point 2 lies in the plane 1 = 1.0 but on no face in it"):
        slice(GMap.from_triangles(v, [[0, 1, 2]]), 1, 1.0)
    # an edge in the plane with both its triangles on the same side: which one to take is not defined
    folded = GMap.from_triangles([[0.0, 0, 0], [1.0, 0, 0], [0.5, 1, 0], [0.5, 1, 1]], [[0, 1, 2], [1, 0, 3]])
    with pytest.raises(
        tgsis.InvalidInputError,
        match=r"the face of dart \d+ lies in the plane 1 = 0.0 but does "
        "not separate a cell above from a cell below",
    ):
        slice(folded, 1, 0.0)


@settings(max_examples=25, deadline=None)
@given(
    st.integers(1, 5),
    st.integers(1, 4),
    st.booleans(),
    st.lists(st.floats(-1e6, 1e6, allow_nan=False, width=32), min_size=2, max_size=5, unique=True),
)
def test_random_extrusions_round_trip(nx: int, ny: int, wrap: bool, raw_values: list[float]) -> None:
    v, t = shapes.grid(max(nx, 3) if wrap else nx, ny, wrap_x=wrap)
    g = GMap.from_triangles(v, t)
    values = np.sort(np.array(raw_values, dtype=np.float64))
    ex = extrude(g, values)
    assert ex.check().ok and counts(ex) == product_counts(g, len(values) - 1)
    for value in values:
        assert slice(ex, 3, value).same_as(g)
    for lo, hi in zip(values[:-1], values[1:]):
        mid = lo + (hi - lo) / 2
        if lo < mid < hi:
            assert slice(ex, 3, mid).same_as(g)
