"""n-G-maps in numpy: builders, cells, Euler characteristics, borders, back to meshes (no database)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import tgsis
from tests import gmaps_shapes as shapes
from tgsis.gmaps import GMap, from_mesh, from_polygons, orbit_labels
from tgsis.mesh import LineSet, PointSet, Surface, TetraMesh


def counts(g: GMap) -> list[int]:
    return [g.n_cells(i) for i in range(g.dimension + 1)]


def n_borders(g: GMap) -> int:
    """Number of connected border pieces (closed curves of a surface)."""
    border = g.border()
    return border.components()[1] if border.n_darts else 0


# ---- closed and bordered surfaces


@pytest.mark.parametrize(
    ("shape", "expected"),
    [
        (shapes.octahedron, [6, 12, 8]),
        (shapes.icosahedron, [12, 30, 20]),
    ],
)
def test_spheres(shape: object, expected: list[int]) -> None:
    v, t = shape()  # type: ignore[operator]
    g = GMap.from_triangles(v, t)
    assert g.n_darts == 6 * len(t) and g.dimension == 2
    assert g.check().ok
    assert counts(g) == expected and g.euler_characteristic() == 2
    assert len(g.border_darts()) == 0 and g.border().n_darts == 0
    assert g.components()[1] == 1


def test_torus() -> None:
    v, t = shapes.grid(6, 5, wrap_x=True, wrap_y=True)
    g = GMap.from_triangles(v, t)
    assert g.check().ok
    assert counts(g) == [30, 90, 60] and g.euler_characteristic() == 0
    assert len(g.border_darts()) == 0


def test_disk_has_one_border() -> None:
    v, t = shapes.grid(4, 3)
    g = GMap.from_triangles(v, t)
    assert g.check().ok
    assert counts(g) == [20, 43, 24] and g.euler_characteristic() == 1
    assert n_borders(g) == 1
    border = g.border()
    # the border is a closed polygon of 14 edges through the 14 outer vertices
    assert border.dimension == 1 and border.check().ok
    assert counts(border) == [14, 14] and border.euler_characteristic() == 0
    outer = np.flatnonzero((v[:, 0] % 1 == 0) | (v[:, 1] % 1 == 0))
    assert sorted(set(border.vertex.tolist())) == outer.tolist()


def test_cylinder_has_two_borders() -> None:
    v, t = shapes.grid(5, 3, wrap_x=True)
    g = GMap.from_triangles(v, t)
    assert g.check().ok and g.euler_characteristic() == 0 and n_borders(g) == 2


def test_moebius_strip() -> None:
    v, t = shapes.grid(5, 2, wrap_x=True, twist=True)
    g = GMap.from_triangles(v, t)
    report = g.check()
    assert report.ok, report.summary()
    assert g.euler_characteristic() == 0
    assert n_borders(g) == 1  # a cylinder has two: the twist joins them
    assert len(g.border().vertex) == 2 * 2 * 5  # one loop of 10 edges, 2 darts each


def test_quads_and_mixed_polygons() -> None:
    v, _ = shapes.grid(2, 1)  # 3 x 2 vertices, index = 2 i + j
    quads = np.array([[0, 2, 3, 1], [2, 4, 5, 3]])
    g = GMap.from_polygons(v, quads)
    assert g.check().ok and counts(g) == [6, 7, 2] and g.euler_characteristic() == 1
    indices, offsets = g.polygons()
    assert offsets.tolist() == [0, 4, 8] and indices.tolist() == quads.ravel().tolist()
    # a quad and a triangle in one call, flat indices plus offsets
    flat, offs = np.array([0, 2, 3, 1, 2, 4, 3]), np.array([0, 4, 7])
    h = from_polygons(v, flat, offs)
    assert h.check().ok and counts(h) == [5, 6, 2] and h.n_darts == 14
    assert [a.tolist() for a in h.polygons()] == [flat.tolist(), offs.tolist()]


def test_polygon_errors() -> None:
    v, _ = shapes.grid(2, 1)
    with pytest.raises(tgsis.InvalidGeometryError, match="polygon 1 has 2 corners"):
        from_polygons(v, np.array([0, 2, 3, 1, 4]), np.array([0, 3, 5]))
    with pytest.raises(tgsis.InvalidGeometryError, match="offsets must start at 0 and end at len"):
        from_polygons(v, np.array([0, 2, 3]), np.array([0, 4]))
    with pytest.raises(tgsis.InvalidGeometryError, match=r"polygon 0 uses vertex 2 twice"):
        GMap.from_polygons(v, [[0, 2, 3, 2]])
    with pytest.raises(tgsis.InvalidGeometryError, match=r"edge \[0, 2\] is shared by 3 polygons \(\[0, 1, 2\]\)"):
        GMap.from_polygons(v, [[0, 2, 1], [0, 2, 3], [2, 0, 5]])


def test_non_manifold_edge_is_an_error_naming_it() -> None:
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1]], dtype=float)
    with pytest.raises(
        tgsis.InvalidGeometryError, match=r"edge \[0, 1\] is shared by 3 triangles \(\[0, 1, 2\]\)"
    ) as err:
        GMap.from_triangles(v, [[0, 1, 2], [1, 0, 3], [0, 1, 4]])
    assert "DETAIL: 1 edge shared by three or more triangles" in str(err.value)


@pytest.mark.parametrize(
    ("triangles", "message"),
    [
        ([[0, 1, 5]], r"triangles\[0, 2\] refers to vertex 5, but there are 3 vertices"),
        ([[0, 1, 1]], r"triangle 0 uses a vertex twice: \[0, 1, 1\]"),
        ([[0, 1]], r"triangles must be a \(c, 3\) array"),
        ([[0.0, 1.0, 2.0]], "must be integer vertex indices"),
    ],
)
def test_bad_triangles(triangles: object, message: str) -> None:
    v = np.eye(3)
    with pytest.raises(tgsis.InvalidGeometryError, match=message):
        GMap.from_triangles(v, triangles)  # type: ignore[arg-type]


def test_bad_vertices() -> None:
    with pytest.raises(tgsis.InvalidGeometryError, match=r"vertex 1 has a non-finite coordinate 2 \(nan\)"):
        GMap.from_triangles([[0.0, 0, 0], [1, 0, np.nan], [0.0, 1, 0]], [[0, 1, 2]])
    with pytest.raises(tgsis.InvalidGMapError, match="a 2-G-map needs points in R\\^m with m >= 2, got m = 1"):
        GMap.from_triangles([[0], [1], [2]], [[0, 1, 2]])


# ---- solids, segments, points


def test_cube_of_five_tetrahedra() -> None:
    v, t = shapes.cube_tetrahedra()
    g = GMap.from_tetrahedra(v, t)
    assert g.n_darts == 24 * 5 and g.check().ok
    assert counts(g) == [8, 18, 16, 5] and g.euler_characteristic() == 1
    border = g.border()
    assert border.dimension == 2 and border.check().ok
    assert counts(border) == [8, 18, 12] and border.euler_characteristic() == 2


def test_block_of_tetrahedra() -> None:
    v, t = shapes.block_tetrahedra(3)
    g = GMap.from_tetrahedra(v, t)
    assert g.check().ok and g.n_cells(3) == 6 * 27 and g.n_cells(0) == 64
    assert g.euler_characteristic() == 1 and g.border().euler_characteristic() == 2
    # interior faces are shared by two tetrahedra; the border has 2 triangles per cube face of the block
    assert g.border().n_cells(2) == 6 * 9 * 2


def test_non_manifold_face() -> None:
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [0, 0, -1], [1, 1, 1]], dtype=float)
    with pytest.raises(tgsis.InvalidGeometryError, match=r"face \[0, 1, 2\] is shared by 3 tetrahedra"):
        GMap.from_tetrahedra(v, [[0, 1, 2, 3], [0, 2, 1, 4], [1, 0, 2, 5]])


def test_segments_and_points() -> None:
    v = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0], [3, 1, 0], [5, 5, 5]], dtype=float)
    lines = GMap.from_segments(v, [[0, 1], [1, 2], [2, 3]])  # a polyline
    assert lines.dimension == 1 and lines.n_darts == 6 and lines.check().ok
    assert counts(lines) == [4, 3] and lines.euler_characteristic() == 1
    assert len(lines.border_darts()) == 2  # its two ends
    ends = lines.border()
    assert ends.dimension == 0 and ends.alpha.tolist() == [[0, 1]] and sorted(ends.vertex.tolist()) == [0, 3]
    with pytest.raises(tgsis.InvalidGeometryError, match=r"vertex \[1\] is shared by 3 segments"):
        GMap.from_segments(v, [[0, 1], [1, 2], [1, 3]])
    points = GMap.from_points(v)
    assert points.dimension == 0 and points.n_darts == 5 and points.check().ok
    assert counts(points) == [5] and points.euler_characteristic() == 5
    with pytest.raises(tgsis.InvalidInputError, match="has no border"):
        points.border()


# ---- back to meshes, cell for cell


def test_round_trips() -> None:
    v, t = shapes.octahedron()
    surface = Surface(v, t, cell_properties={"part": np.arange(8), "normal": np.arange(24.0).reshape(8, 3)})
    g = from_mesh(surface)
    assert list(g.cell_properties) == [2] and list(g.cell_properties[2]) == ["part", "normal"]
    assert g.cell_properties[2]["normal"].shape == (8, 3)  # vector properties: one row per cell
    back = g.to_mesh()
    assert isinstance(back, Surface) and back.same_as(surface)
    vt, tt = shapes.block_tetrahedra(2)
    solid = TetraMesh(vt, tt)
    assert GMap.from_mesh(solid).to_mesh().same_as(solid)
    lines = LineSet(v, [[0, 1], [3, 2], [5, 4]])
    assert from_mesh(lines).to_mesh().same_as(lines)
    pts = PointSet(v, [[4], [0]])
    assert from_mesh(pts).to_mesh().same_as(pts)
    with pytest.raises(tgsis.InvalidGeometryError, match="takes a PointSet, LineSet, Surface or TetraMesh"):
        from_mesh(tgsis.GeometryCollection([surface]))  # type: ignore[arg-type]


def test_simplices_refuses_other_cells() -> None:
    v, _ = shapes.grid(2, 1)
    g = GMap.from_polygons(v, [[0, 2, 3, 1], [2, 4, 5, 3]])
    with pytest.raises(tgsis.InvalidGMapError, match=r"2-cells 0, 1 are not simplices"):
        g.to_mesh()
    with pytest.raises(tgsis.InvalidGMapError, match="simplices in R\\^3: this is a 2-G-map in R\\^2"):
        GMap.from_triangles(v[:, :2], [[0, 2, 3]]).to_mesh()


# ---- incidence, adjacency, orbits, properties


def test_incidence_and_adjacency() -> None:
    v, t = shapes.octahedron()
    g = GMap.from_triangles(v, t)
    faces_of_vertices = g.incidence(0, 2)
    assert faces_of_vertices.shape == (6, 8)
    assert faces_of_vertices.sum(axis=1).tolist() == [4] * 6  # every vertex of an octahedron is in 4 faces
    edges_of_faces = g.incidence(2, 1)
    assert edges_of_faces.sum(axis=1).tolist() == [3] * 8
    face_adjacency = g.adjacency(2)
    assert face_adjacency.sum(axis=1).tolist() == [3] * 8 and (face_adjacency != face_adjacency.T).nnz == 0
    vertex_adjacency = g.adjacency(0)
    assert vertex_adjacency.sum(axis=1).tolist() == [4] * 6
    assert g.adjacency(1).sum(axis=1).tolist() == [6] * 12  # an edge meets 3 + 3 others at its ends
    with pytest.raises(tgsis.InvalidInputError, match="cell dimension 3 is not an involution of this 2-G-map"):
        g.cells(3)


def test_orbits_are_numbered_by_lowest_dart() -> None:
    v, t = shapes.icosahedron()
    g = GMap.from_triangles(v, t)
    labels, count = g.orbits([0, 1])
    assert count == 20 and labels.tolist() == np.repeat(np.arange(20), 6).tolist()
    assert g.cell_darts(2).tolist() == (6 * np.arange(20)).tolist()
    with pytest.raises(tgsis.InvalidInputError, match="involution 4 is not an involution"):
        g.orbits([0, 4])


@pytest.mark.parametrize("rounds", [0, 1, 2, 12])
def test_orbits_with_and_without_propagation(rounds: int) -> None:
    """A vertex shared by 400 triangles, a long orbit: propagation, scipy, or some of each give the same."""
    k = 400
    angles = np.arange(k) * 2 * np.pi / k
    v = np.concatenate([[[0.0, 0.0, 0.0]], np.stack([np.cos(angles), np.sin(angles), 0 * angles], axis=1)])
    t = np.stack([np.zeros(k, dtype=np.int64), 1 + np.arange(k), 1 + (np.arange(k) + 1) % k], axis=1)
    g = GMap.from_triangles(v, t)
    assert counts(g) == [k + 1, 2 * k, k] and g.euler_characteristic() == 1
    labels, count = orbit_labels(g.alpha, [1, 2], rounds=rounds)
    assert count == k + 1 and len(np.unique(labels[g.vertex == 0])) == 1
    # the same labels as plain scipy on the whole graph
    from scipy.sparse import csr_array
    from scipy.sparse.csgraph import connected_components

    a = g.alpha
    graph = csr_array((np.ones(2 * g.n_darts), (np.tile(np.arange(g.n_darts), 2), np.concatenate([a[1], a[2]]))))
    _, reference = connected_components(graph, directed=False)
    assert labels.tolist() == reference.tolist()  # scipy numbers components by lowest node too
    assert orbit_labels(a, [])[1] == g.n_darts


def test_cell_properties() -> None:
    v, t = shapes.octahedron()
    g = GMap.from_triangles(v, t, cell_properties={"rock": np.arange(8) % 2})
    assert g.cell_properties[2]["rock"].tolist() == [0, 1] * 4
    h = GMap(g.alpha, g.vertex, g.points, cell_properties={0: {"depth": np.arange(6.0)}, 2: {"rock": np.ones(8)}})
    assert h.cell_properties[0]["depth"].tolist() == list(range(6))
    with pytest.raises(tgsis.InvalidPropertyError, match="property 'rock' has 7 values for 8 2-cells"):
        GMap(g.alpha, g.vertex, g.points, cell_properties={2: {"rock": np.ones(7)}})
    with pytest.raises(tgsis.InvalidPropertyError, match="property level 3 is not a cell dimension"):
        GMap(g.alpha, g.vertex, g.points, cell_properties={3: {"rock": np.ones(8)}})
    with pytest.raises(tgsis.InvalidPropertyError, match="property name '2rock' is not allowed"):
        GMap(g.alpha, g.vertex, g.points, cell_properties={2: {"2rock": np.ones(8)}})
    assert (
        GMap(g.alpha, g.vertex, g.points, cell_properties={2: {"Rock": np.ones(8)}}).cell_properties[2]["Rock"].sum()
        == 8
    )


def test_arrays_are_read_only() -> None:
    v, t = shapes.octahedron()
    g = GMap.from_triangles(v, t)
    with pytest.raises(ValueError, match="read-only"):
        g.alpha[0, 0] = 1


@settings(max_examples=40, deadline=None)
@given(st.integers(2, 7), st.integers(1, 6), st.booleans(), st.integers(0, 2**32 - 1))
def test_random_grids(nx: int, ny: int, wrap: bool, seed: int) -> None:
    """Any triangulated grid, with triangles shuffled and re-oriented at random."""
    if wrap and nx < 3:
        nx = 3
    v, t = shapes.grid(nx, ny, wrap_x=wrap)
    rng = np.random.default_rng(seed)
    t = t[rng.permutation(len(t))]
    flip = rng.random(len(t)) < 0.5
    t[flip] = t[flip][:, ::-1]
    g = GMap.from_triangles(v, t)
    assert g.check().ok
    assert g.euler_characteristic() == (0 if wrap else 1)
    assert n_borders(g) == (2 if wrap else 1)
    assert np.array_equal(g.simplices(), t)
    assert g.n_cells(1) == len(
        np.unique(np.sort(np.concatenate([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]]), axis=1), axis=0)
    )


# ---- no database layer


def test_gmaps_imports_no_database_layer() -> None:
    """A fresh interpreter imports tgsis.gmaps without psycopg, tgsis.db or (until an orbit needs it) scipy."""
    program = (
        "import sys, tgsis.gmaps; print(' '.join(sorted(m for m in sys.modules if m == 'psycopg' "
        "or m.startswith(('psycopg.', 'tgsis.db', 'scipy')))))"
    )
    done = subprocess.run([sys.executable, "-c", program], capture_output=True, text=True, check=False)
    assert done.returncode == 0, done.stderr
    # scipy is imported when an orbit needs it, so that `import tgsis` (and the command line) stays light
    assert done.stdout.strip() == "", f"import tgsis.gmaps loaded {done.stdout.strip()}"
    # and the orbits still work in such an interpreter
    program = (
        "import sys, tgsis.gmaps as g; m = g.GMap.from_triangles([[0, 0], [1, 0], [0, 1]], [[0, 1, 2]]); "
        "print(m.euler_characteristic(), m.incidence(0, 2).shape, "
        "any(k.startswith(('psycopg', 'tgsis.db')) for k in sys.modules))"
    )
    done = subprocess.run([sys.executable, "-c", program], capture_output=True, text=True, check=False)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "1 (3, 1) False"


def test_the_documented_example() -> None:
    """docs/data-models.md's example runs and gives what its comments say."""
    text = (Path(__file__).resolve().parents[1] / "docs" / "data-models.md").read_text(encoding="utf-8")
    section = text[text.index("## Models 4 and 5") :]
    block = section[section.index("```python\n") + 10 : section.index("```", section.index("```python\n") + 10)]
    namespace: dict[str, object] = {}
    checked = 0
    for line in block.splitlines():
        code, _, comment = line.partition("  # ")
        if comment and not code.strip().startswith(("from", "import")) and "=" not in code.split("(")[0]:
            expected = comment.split(":")[0].strip()
            assert eval(code.strip(), namespace) == eval(expected), line  # noqa: S307 - our own docs
            checked += 1
        else:
            exec(code, namespace)  # noqa: S102 - our own docs
    assert checked == 4


def test_the_module_example() -> None:
    import doctest

    import tgsis.gmaps

    result = doctest.testmod(tgsis.gmaps)
    assert result.attempted >= 4 and result.failed == 0


def test_empty_maps() -> None:
    g = GMap.from_triangles(np.empty((0, 3)), np.empty((0, 3), dtype=np.int64))
    assert g.n_darts == 0 and g.check().ok and counts(g) == [0, 0, 0] and g.euler_characteristic() == 0
    assert g.cell_darts(2).tolist() == [] and g.simplices().shape == (0, 3) and g.border().n_darts == 0
    assert [a.tolist() for a in g.polygons()] == [[], [0]]
    kept = GMap.from_triangles(np.eye(3), [])  # vertices without triangles are kept
    assert kept.n_points == 3 and kept.to_mesh().same_as(Surface(np.eye(3), np.empty((0, 3), dtype=np.int64)))


@settings(max_examples=30, deadline=None)
@given(st.integers(0, 2**32 - 1), st.floats(0.2, 1.0))
def test_random_pieces_of_a_tetrahedral_block(seed: int, fraction: float) -> None:
    """Any subset of a valid tetrahedral mesh, shuffled and with vertex orders permuted, is a valid 3-G-map."""
    v, t = shapes.block_tetrahedra(3)
    rng = np.random.default_rng(seed)
    keep = t[rng.random(len(t)) < fraction]
    keep = np.take_along_axis(keep, rng.permuted(np.tile(np.arange(4), (len(keep), 1)), axis=1), axis=1)
    g = GMap.from_tetrahedra(v, keep)
    assert g.check().ok
    assert np.array_equal(g.simplices(), keep)
    faces = np.sort(np.concatenate([np.delete(keep, f, axis=1) for f in range(4)]), axis=1)
    unique, shared = np.unique(faces, axis=0, return_counts=True)
    assert g.n_cells(3) == len(keep) and g.n_cells(2) == len(unique)
    border = g.border()
    assert border.check().ok and border.n_cells(2) == int((shared == 1).sum())
    assert border.euler_characteristic() % 2 == 0  # closed surfaces (each component: 2 - 2 genus)


def test_simplices_of_any_dimension() -> None:
    """Two 4-simplices sharing a tetrahedron: 120 darts each, alpha4 sewn across the shared facet."""
    v = np.concatenate([np.zeros((1, 4)), np.eye(4), -np.ones((1, 4))])
    g = tgsis.gmaps.from_simplices(v, [[0, 1, 2, 3, 4], [1, 2, 0, 3, 5]])
    assert g.dimension == 4 and g.n_darts == 240 and g.check().ok
    assert counts(g) == [6, 14, 16, 9, 2] and g.euler_characteristic() == 1
    assert len(g.border_darts()) == 240 - 2 * 24
    border = g.border()  # the border of a 4-ball: a 3-sphere of 8 tetrahedra, chi 0
    assert border.check().ok and border.n_cells(3) == 8 and border.euler_characteristic() == 0


@pytest.mark.parametrize(
    ("shape", "orientable"),
    [
        (shapes.octahedron, True),
        (lambda: shapes.grid(4, 3, wrap_x=True, wrap_y=True), True),
        (lambda: shapes.grid(3, 2), True),
        (lambda: shapes.grid(5, 2, wrap_x=True, twist=True), False),
    ],
)
def test_orientation(shape: object, orientable: bool) -> None:
    v, t = shape()  # type: ignore[operator]
    rng = np.random.default_rng(3)
    flip = rng.random(len(t)) < 0.5
    t[flip] = t[flip][:, ::-1]  # the input's orientations do not matter
    g = GMap.from_triangles(v, t)
    assert g.is_orientable() is orientable
    if not orientable:
        with pytest.raises(tgsis.InvalidGMapError, match="the component of dart 0 is not orientable"):
            g.orientation()
        return
    positive = g.orientation()
    assert positive[0] and flips_everywhere(g, positive)
    assert positive.reshape(-1, 6).sum(axis=1).tolist() == [3] * len(t)  # half the darts of each triangle


def flips_everywhere(g: GMap, positive: np.ndarray) -> bool:
    darts = np.arange(g.n_darts)
    return all(
        bool(np.all(positive[g.alpha[i, g.alpha[i] != darts]] != positive[g.alpha[i] != darts]))
        for i in range(g.dimension + 1)
    )


def test_orientation_of_solids_and_several_components() -> None:
    v, t = shapes.cube_tetrahedra()
    solid = GMap.from_tetrahedra(v, t)
    assert solid.is_orientable() and flips_everywhere(solid, solid.orientation())
    one = GMap.from_triangles(*shapes.octahedron())
    two = GMap(
        np.concatenate([one.alpha, one.alpha + one.n_darts], axis=1),
        np.concatenate([one.vertex, one.vertex]),
        one.points,
    )
    positive = two.orientation()
    assert positive[0] and positive[one.n_darts]  # the lowest dart of each component is positive
    assert flips_everywhere(two, positive)
    assert extrude_cube_orientable()
    moebius = GMap.from_triangles(*shapes.grid(5, 2, wrap_x=True, twist=True))
    both = GMap(
        np.concatenate([one.alpha, moebius.alpha + one.n_darts], axis=1),
        np.concatenate([one.vertex, moebius.vertex + one.n_points]),
        np.concatenate([one.points, moebius.points]),
    )
    assert not both.is_orientable()
    with pytest.raises(tgsis.InvalidGMapError, match=f"the component of dart {one.n_darts} is not orientable"):
        both.orientation()


def extrude_cube_orientable() -> bool:
    from tgsis.gmaps import extrude

    return extrude(GMap.from_polygons([[0, 0], [1, 0], [1, 1], [0, 1]], [[0, 1, 2, 3]]), [0, 1, 2]).is_orientable()
