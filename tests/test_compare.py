"""Mesh comparison (tgsis.compare) against a slow reference of its definitions (no database).

``compare_reference.py`` states the definitions in plain Python; hypothesis
builds old meshes of every cell size (points, segments, triangles, tetrahedra)
and edits them adversarially — vertex and cell order shuffled, cells rotated
by even permutations, orientations reversed, edges flipped, ``-0.0`` for
``0.0``, vertices moved by one ulp, vertices and cells removed and added — and
``compare_meshes`` must give exactly the reference's answer. Then: the diff
applied to the old mesh gives the edited one back, a ``MeshIndex`` answers as
its mesh does, the collision path is exact, repeated vertices still pair one
to one, tolerance matching agrees with brute force, and the real CFM faults
of two releases compare as the data set's README says they should.
"""

from __future__ import annotations

import contextlib
import itertools
from collections import Counter
from collections.abc import Callable, Iterator, Sequence
from typing import Any
from unittest import mock

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

import tgsis
import tgsis._rows as R
from tgsis.compare import MeshDiff, MeshIndex, compare_meshes
from tgsis.formats.gocad import read_tsurf
from tgsis.mesh import LineSet, Mesh, PointSet, Surface, TetraMesh

from .compare_reference import oriented_cells_by_coordinates, permutation_parity, reference_compare
from .shared_data import cfm

MESH_TYPES: dict[int, type[Mesh]] = {1: PointSet, 2: LineSet, 3: Surface, 4: TetraMesh}
CELL_SIZES = sorted(MESH_TYPES)
EVEN_PERMUTATIONS = {k: [p for p in itertools.permutations(range(k)) if permutation_parity(p) == 0] for k in CELL_SIZES}
PROPERTY = settings(max_examples=100, deadline=None, suppress_health_check=[HealthCheck.too_slow])


def make_mesh(
    k: int, vertices: Sequence[Sequence[float]] | np.ndarray, cells: Sequence[Sequence[int]] | np.ndarray
) -> Mesh:
    return MESH_TYPES[k](
        np.asarray(vertices, dtype=np.float64).reshape(-1, 3), np.asarray(cells, dtype=np.int64).reshape(-1, k)
    )


# ---------------------------------------------------------------- strategies

#: coordinates on a coarse grid (0.1 steps: not exactly representable), so that meshes share some
COORDINATE = st.integers(-3, 3).map(lambda i: i * 0.1)
POINT = st.tuples(COORDINATE, COORDINATE, COORDINATE)
#: mostly kept, so that many cells survive to be matched
VERTEX_ACTIONS = st.sampled_from(["keep"] * 8 + ["move", "ulp", "signed_zero", "remove"])
CELL_ACTIONS = st.sampled_from(["keep"] * 3 + ["rotate"] * 2 + ["reverse", "reconnect", "remove", "reversed_twin"])


@st.composite
def grid_surface(draw: st.DrawFn) -> tuple[list[tuple[float, float, float]], list[tuple[int, ...]]]:
    """A small consistently oriented grid of triangles (quads split on one diagonal): edges to flip."""
    nx, ny = draw(st.integers(2, 5)), draw(st.integers(2, 5))
    z = draw(st.lists(COORDINATE, min_size=nx * ny, max_size=nx * ny))
    vertices = [(0.5 * i, 0.5 * j, z[i * ny + j]) for i in range(nx) for j in range(ny)]
    triangles: list[tuple[int, ...]] = []
    for i in range(nx - 1):
        for j in range(ny - 1):
            a, b, c, d = i * ny + j, (i + 1) * ny + j, i * ny + j + 1, (i + 1) * ny + j + 1
            triangles += [(a, b, d), (a, d, c)]
    return vertices, triangles


@st.composite
def random_mesh(
    draw: st.DrawFn, k: int, max_vertices: int = 20
) -> tuple[list[tuple[float, float, float]], list[tuple[int, ...]]]:
    """A normal mesh: distinct vertices, cells on distinct vertex sets (any orientation, any order)."""
    vertices = draw(st.lists(POINT, unique=True, max_size=max_vertices))
    n = len(vertices)
    if n < k:
        return vertices, []
    cell = st.lists(st.integers(0, n - 1), min_size=k, max_size=k, unique=True).map(tuple)
    cells = draw(st.lists(cell, unique_by=lambda c: tuple(sorted(c)), max_size=2 * n))
    return vertices, cells


def flip_edges(draw: st.DrawFn, cells: list[tuple[int, ...]]) -> None:
    """Flip the shared edge of a few pairs of neighbouring triangles, in place: (a,b,c)+(b,a,d) -> (a,d,c)+(d,b,c)."""
    for _ in range(draw(st.integers(0, 3))):
        if not cells:
            return
        first = draw(st.integers(0, len(cells) - 1))
        edges = {(t[i], t[(i + 1) % 3]): n for n, t in enumerate(cells) for i in range(3)}
        for i in range(3):
            a, b, c = (cells[first][(i + s) % 3] for s in range(3))
            second = edges.get((b, a))
            if second is not None and second != first:
                d = next(v for v in cells[second] if v not in (a, b))
                if c != d and (d, c) not in edges and (c, d) not in edges:  # else the flip would repeat an edge
                    cells[first], cells[second] = (a, d, c), (d, b, c)
                    break


@st.composite
def edited_pair(draw: st.DrawFn, k: int) -> tuple[Mesh, Mesh]:
    """An old mesh of cell size k and an adversarially edited copy of it."""
    if k == 3 and draw(st.booleans()):
        old_vertices, old_cells = draw(grid_surface())
    else:
        old_vertices, old_cells = draw(random_mesh(k))
    fresh = itertools.count(100)  # coordinates no other vertex has

    # vertices: logical id in the edited mesh -> coordinates
    survivor: dict[int, int] = {}  # old id -> edited logical id
    edited_vertices: list[tuple[float, ...]] = []
    removed = []
    for i, xyz in enumerate(old_vertices):
        action = draw(VERTEX_ACTIONS)
        if action == "remove":
            removed.append(i)
            continue
        if action == "move":
            xyz = (float(next(fresh)), xyz[1], xyz[2])
        elif action == "ulp":  # the smallest move there is: still edited
            axis = draw(st.integers(0, 2))
            moved = list(xyz)
            moved[axis] = float(np.nextafter(moved[axis], draw(st.sampled_from([-np.inf, np.inf]))))
            xyz = (moved[0], moved[1], moved[2])
        elif action == "signed_zero":  # -0.0 is the number 0: not edited
            xyz = tuple(-0.0 if c == 0 else c for c in xyz)  # type: ignore[assignment]
        survivor[i] = len(edited_vertices)
        edited_vertices.append(xyz)
    for i in removed:  # a vertex re-created where a removed one was is the same vertex
        if draw(st.booleans()):
            edited_vertices.append(old_vertices[i])
    for _ in range(draw(st.integers(0, 4))):
        edited_vertices.append((float(next(fresh)), draw(COORDINATE), draw(COORDINATE)))
    m = len(edited_vertices)

    def other_vertex(cell: Sequence[int]) -> int | None:
        choices = [v for v in range(m) if v not in cell]
        return draw(st.sampled_from(choices)) if choices else None

    edited_cells: list[tuple[int, ...]] = []
    for cell in old_cells:
        if any(v not in survivor for v in cell):
            continue  # a removed vertex takes its cells along
        renamed = tuple(survivor[v] for v in cell)
        action = draw(CELL_ACTIONS)
        if action == "remove":
            continue
        if action == "rotate":  # an even permutation: the same oriented cell
            renamed = tuple(renamed[p] for p in draw(st.sampled_from(EVEN_PERMUTATIONS[k])))
        elif action == "reverse" and k > 1:  # odd permutation: orientation reversed, edited
            renamed = (renamed[1], renamed[0], *renamed[2:])
        elif action == "reconnect":  # another cell on surviving vertices (usually one the old mesh lacks)
            w = other_vertex(renamed[1:])
            if w is not None:
                renamed = (w, *renamed[1:])
        elif action == "reversed_twin" and k > 1:  # coincident, opposite orientation: a different cell
            edited_cells.append((renamed[1], renamed[0], *renamed[2:]))
        edited_cells.append(renamed)
    if k == 3:
        flip_edges(draw, edited_cells)
    if m >= k:
        any_cell = st.lists(st.integers(0, m - 1), min_size=k, max_size=k, unique=True).map(tuple)
        edited_cells += draw(st.lists(any_cell, max_size=4))

    vertex_order = draw(st.permutations(range(m)))
    cell_order = draw(st.permutations(range(len(edited_cells))))
    new_id = {logical: position for position, logical in enumerate(vertex_order)}
    vertices = [edited_vertices[logical] for logical in vertex_order]
    cells = [tuple(new_id[v] for v in edited_cells[c]) for c in cell_order]
    return make_mesh(k, old_vertices, old_cells), make_mesh(k, vertices, cells)


@st.composite
def repeated_pair(draw: st.DrawFn, k: int) -> tuple[Mesh, Mesh]:
    """Meshes that are not normal: vertices and cells repeated in either mesh, drawn from a small pool."""
    pool = draw(st.lists(POINT, min_size=1, max_size=4, unique=True))

    def mesh() -> Mesh:
        vertices = draw(st.lists(st.sampled_from(pool), max_size=12))
        n = len(vertices)
        cells: list[list[int]] = []
        if n >= k:
            cells = draw(st.lists(st.lists(st.integers(0, n - 1), min_size=k, max_size=k, unique=True), max_size=15))
            cells += [cells[i] for i in draw(st.lists(st.integers(0, len(cells) - 1), max_size=4))] if cells else []
        return make_mesh(k, vertices, cells)

    return mesh(), mesh()


# ---------------------------------------------------------------- checks


def reference(old: Mesh, edited: Mesh, tolerance: float = 0.0) -> dict[str, list[int]]:
    r = reference_compare(
        old.vertices.tolist(), old.cells.tolist(), edited.vertices.tolist(), edited.cells.tolist(), tolerance
    )
    return {
        "vertex_map": r.vertex_map,
        "cell_map": r.cell_map,
        "removed_vertices": r.removed_vertices,
        "removed_cells": r.removed_cells,
    }


def as_lists(diff: MeshDiff) -> dict[str, list[int]]:
    for name in ("vertex_map", "cell_map", "removed_vertices", "removed_cells"):
        assert getattr(diff, name).dtype == np.int64, name
    return {
        "vertex_map": diff.vertex_map.tolist(),
        "cell_map": diff.cell_map.tolist(),
        "removed_vertices": diff.removed_vertices.tolist(),
        "removed_cells": diff.removed_cells.tolist(),
    }


def assert_valid(old: Mesh, edited: Mesh, diff: MeshDiff, tolerance: float = 0.0) -> None:
    """What must hold of any answer, whatever pairing it chose among equal rows."""
    vm, cm = diff.vertex_map, diff.cell_map
    assert vm.shape == (edited.n_vertices,) and cm.shape == (edited.n_cells,)
    assert (diff.n_old_vertices, diff.n_old_cells) == (old.n_vertices, old.n_cells)
    for mapping, count, removed in ((vm, old.n_vertices, diff.removed_vertices), (cm, old.n_cells, diff.removed_cells)):
        hit = mapping[mapping >= 0]
        assert np.all(hit < count) and len(np.unique(hit)) == len(hit), "one to one"
        assert sorted(set(range(count)) - set(hit.tolist())) == removed.tolist()
    kept = vm >= 0
    gap = np.linalg.norm(old.vertices[vm[kept]] - edited.vertices[kept], axis=1)
    assert np.all(gap <= tolerance) if tolerance else np.all(old.vertices[vm[kept]] == edited.vertices[kept])
    for j in np.flatnonzero(cm >= 0).tolist():  # a kept cell is the old cell on the same vertices, same orientation
        renamed = vm[edited.cells[j]].tolist()
        assert min(renamed) >= 0
        old_cell = old.cells[cm[j]].tolist()
        assert sorted(renamed) == sorted(old_cell)
        assert permutation_parity(renamed) == permutation_parity(old_cell)


def applied(old: Mesh, edited: Mesh, diff: MeshDiff) -> tuple[np.ndarray, np.ndarray]:
    """The old mesh with the diff applied, as the check-in would write it: old rows kept, new rows added."""
    kept_old = np.setdiff1d(np.arange(old.n_vertices), diff.removed_vertices)
    added = diff.added_vertices
    vertices = np.concatenate([old.vertices[kept_old], edited.vertices[added]])
    position_of_old = np.full(old.n_vertices, -1)
    position_of_old[kept_old] = np.arange(len(kept_old))
    position_of_edited = np.full(edited.n_vertices, -1)
    position_of_edited[added] = len(kept_old) + np.arange(len(added))
    mapped = diff.vertex_map >= 0
    position_of_edited[mapped] = position_of_old[diff.vertex_map[mapped]]
    kept_cells = np.setdiff1d(np.arange(old.n_cells), diff.removed_cells)
    cells = np.concatenate([position_of_old[old.cells[kept_cells]], position_of_edited[edited.cells[diff.added_cells]]])
    assert np.all(cells >= 0), "a kept cell uses a removed vertex"
    return vertices, cells.reshape(-1, old.cell_size)


def assert_diff_reproduces(old: Mesh, edited: Mesh, diff: MeshDiff) -> None:
    vertices, cells = applied(old, edited, diff)
    assert len(vertices) == edited.n_vertices and len(cells) == edited.n_cells
    assert Counter(map(tuple, vertices.tolist())) == Counter(map(tuple, edited.vertices.tolist()))
    assert oriented_cells_by_coordinates(vertices.tolist(), cells.tolist()) == oriented_cells_by_coordinates(
        edited.vertices.tolist(), edited.cells.tolist()
    )


# ---------------------------------------------------------------- properties against the reference


@pytest.mark.parametrize("meshes", [edited_pair, repeated_pair], ids=["edited", "repeated"])
@pytest.mark.parametrize("k", CELL_SIZES)
@PROPERTY
@given(data=st.data())
def test_matches_reference_and_reproduces_edited_mesh(
    meshes: Callable[[int], st.SearchStrategy[tuple[Mesh, Mesh]]], k: int, data: st.DataObject
) -> None:
    """Adversarial edits of a normal mesh; and meshes that repeat vertices and cells (not normal), which must
    still pair one to one (equal rows in index order, as the reference does)."""
    old, edited = data.draw(meshes(k))
    diff = compare_meshes(old, edited)
    assert_valid(old, edited, diff)
    assert as_lists(diff) == reference(old, edited)
    assert_diff_reproduces(old, edited, diff)


@pytest.mark.parametrize("k", CELL_SIZES)
@PROPERTY
@given(data=st.data())
def test_mesh_index_answers_as_its_mesh(k: int, data: st.DataObject) -> None:
    old, edited = data.draw(edited_pair(k))
    _, other = data.draw(edited_pair(k))
    index = MeshIndex(old)
    expected = as_lists(compare_meshes(old, edited))
    assert as_lists(compare_meshes(index, edited)) == expected
    if other.cell_size == old.cell_size:  # the index is not changed by use: again, after another comparison
        assert as_lists(compare_meshes(index, other)) == as_lists(compare_meshes(old, other))
    assert as_lists(compare_meshes(index, edited)) == expected


def low_entropy_hashes(buckets: int) -> Callable[[list[np.ndarray]], np.ndarray]:
    """A hash with only ``buckets`` values in the 32 bits that sorting uses, so that rows crowd together.

    One column keeps its value in the low bits (the implementation relies on
    a one-column hash being one-to-one); several columns are compared value by
    value, so their hash may be anything.
    """
    real = R.row_hashes

    def hashes(columns: list[np.ndarray]) -> np.ndarray:
        prefix = (real(columns) >> np.uint64(32)) % np.uint64(buckets)
        low = columns[0] if len(columns) == 1 else real(columns)
        if len(columns) == 1:
            assert np.all(low <= R._LOW)
        return (prefix << np.uint64(32)) | (low & R._LOW)

    return hashes


@contextlib.contextmanager
def crowded_hashes(buckets: int) -> Iterator[list[int]]:
    """Within: the low-entropy hash in use; yields the list of calls of the collision path (_match_crowded)."""
    calls: list[int] = []
    crowded = R._match_crowded

    def counting(*args: Any) -> None:
        calls.append(1)
        crowded(*args)

    with (
        mock.patch.object(R, "row_hashes", low_entropy_hashes(buckets)),
        mock.patch.object(R, "_match_crowded", counting),
    ):
        yield calls


@pytest.mark.parametrize("k", CELL_SIZES)
@PROPERTY
@given(data=st.data(), buckets=st.sampled_from([1, 2, 3, 16]))
def test_hash_collisions_still_exact(k: int, data: st.DataObject, buckets: int) -> None:
    old, edited = data.draw(edited_pair(k))
    with crowded_hashes(buckets) as calls:
        diff = compare_meshes(old, edited)
    assert as_lists(diff) == reference(old, edited)
    if buckets == 1 and min(old.n_vertices, edited.n_vertices) >= 1 and max(old.n_vertices, edited.n_vertices) >= 2:
        assert calls, "the collision path was not taken"


def test_collision_path_is_taken_and_exact_on_a_larger_mesh() -> None:
    rng = np.random.default_rng(5)
    points = rng.integers(0, 50, size=(400, 3)).astype(float)
    points = np.unique(points, axis=0)
    triangles = np.array([rng.choice(len(points), 3, replace=False) for _ in range(600)])
    old = Surface(points, triangles)
    keep = rng.permutation(len(points))[: len(points) - 20]
    edited_points = np.concatenate([points[keep], rng.random((10, 3)) + 100])
    inverse = np.full(len(points), -1)
    inverse[keep] = np.arange(len(keep))
    survivors = inverse[triangles]
    edited = Surface(edited_points, survivors[(survivors >= 0).all(axis=1)])
    with crowded_hashes(7) as calls:
        diff = compare_meshes(old, edited)
    assert len(calls) == 2  # vertices and cells
    assert as_lists(diff) == reference(old, edited)
    assert as_lists(diff) == as_lists(compare_meshes(old, edited))


@st.composite
def tolerance_pair(draw: st.DrawFn, k: int) -> tuple[Mesh, Mesh, float]:
    """Points on a small half-unit grid (many distances tie exactly, so that the order of ties shows), some shared
    by the two meshes, some a little off."""

    def point(scale: float) -> st.SearchStrategy[tuple[float, float, float]]:
        c = st.integers(-2, 2).map(lambda i: i * scale)
        return st.tuples(c, c, c)

    old_points = draw(st.lists(point(0.5), unique=True, max_size=16))
    new_points = draw(
        st.lists(
            st.one_of(st.sampled_from(old_points), point(0.5), point(0.25)) if old_points else point(0.5),
            unique=True,
            max_size=16,
        )
    )
    offset = draw(st.sampled_from([0.0, 0.0, 1e-9, 0.1]))
    new_points = [(x + offset, y, z) if draw(st.booleans()) else (x, y, z) for x, y, z in new_points]
    assume(len(set(new_points)) == len(new_points))
    tolerance = draw(
        st.one_of(
            st.sampled_from([0.25, 0.5, 0.75, 1.0, 1.5]), st.floats(1e-6, 2.0, allow_nan=False, allow_infinity=False)
        )
    )

    def cells(n: int) -> list[list[int]]:
        if n < k:
            return []
        return draw(st.lists(st.lists(st.integers(0, n - 1), min_size=k, max_size=k, unique=True), max_size=n))

    return (
        make_mesh(k, old_points, cells(len(old_points))),
        make_mesh(k, new_points, cells(len(new_points))),
        tolerance,
    )


@pytest.mark.parametrize("k", [1, 3])
@PROPERTY
@given(data=st.data())
def test_tolerance_matches_brute_force(k: int, data: st.DataObject) -> None:
    old, edited, tolerance = data.draw(tolerance_pair(k))
    diff = compare_meshes(old, edited, tolerance)
    assert as_lists(diff) == reference(old, edited, tolerance)
    assert_valid(old, edited, diff, tolerance)
    assert as_lists(compare_meshes(MeshIndex(old), edited, tolerance)) == as_lists(diff)


# ---------------------------------------------------------------- cases by hand

SQUARE = [(0.0, 0.0, 0.0), (1.0, 0.0, 0.0), (1.0, 1.0, 0.0), (0.0, 1.0, 0.0)]
TWO_TRIANGLES = [(0, 1, 2), (0, 2, 3)]


def test_identical_mesh_in_another_order_is_not_edited() -> None:
    old = Surface(SQUARE, TWO_TRIANGLES)
    # renumbered (edited vertex i is old vertex (2, 0, 3, 1)[i]), triangles rotated and in the other order
    edited = Surface([SQUARE[i] for i in (2, 0, 3, 1)], [(0, 2, 1), (3, 0, 1)])
    diff = compare_meshes(old, edited)
    assert diff.identical
    assert diff.vertex_map.tolist() == [2, 0, 3, 1] and diff.cell_map.tolist() == [1, 0]
    assert diff.counts() == {
        "vertices_kept": 4,
        "vertices_removed": 0,
        "vertices_added": 0,
        "cells_kept": 2,
        "cells_removed": 0,
        "cells_added": 0,
    }


def test_flipped_edge_edits_both_triangles_and_no_vertex() -> None:
    diff = compare_meshes(Surface(SQUARE, TWO_TRIANGLES), Surface(SQUARE, [(0, 1, 3), (1, 2, 3)]))
    assert diff.vertex_map.tolist() == [0, 1, 2, 3] and len(diff.removed_vertices) == 0
    assert diff.cell_map.tolist() == [-1, -1] and diff.removed_cells.tolist() == [0, 1]
    assert not diff.identical


def test_reversed_orientation_is_edited_even_permutation_is_not() -> None:
    old = TetraMesh(SQUARE + [(0.5, 0.5, 1.0)], [(0, 1, 2, 4)])
    assert compare_meshes(old, TetraMesh(old.vertices, [(1, 0, 4, 2)])).identical  # two swaps: even
    assert compare_meshes(old, TetraMesh(old.vertices, [(1, 0, 2, 4)])).cell_map.tolist() == [-1]
    segment = LineSet(SQUARE, [(0, 1)])
    assert compare_meshes(segment, LineSet(SQUARE, [(1, 0)])).cell_map.tolist() == [-1]


def test_negative_zero_equals_zero_and_one_ulp_does_not() -> None:
    old = PointSet([(0.0, 0.0, 0.0), (1.0, 2.0, 3.0)])
    signed = PointSet([(-0.0, 0.0, -0.0), (1.0, 2.0, 3.0)])
    assert compare_meshes(old, signed).identical and compare_meshes(signed, old).identical
    tiny = float(np.nextafter(0.0, 1.0))
    moved = PointSet([(0.0, 0.0, tiny), (1.0, float(np.nextafter(2.0, 0.0)), 3.0)])
    diff = compare_meshes(old, moved)
    assert diff.vertex_map.tolist() == [-1, -1] and diff.removed_vertices.tolist() == [0, 1]
    assert diff.cell_map.tolist() == [-1, -1]
    assert compare_meshes(old, moved, tolerance=1e-12).identical


@pytest.mark.parametrize("k", CELL_SIZES)
def test_empty_meshes(k: int) -> None:
    empty = make_mesh(k, np.empty((0, 3)), np.empty((0, k)))
    full = make_mesh(k, SQUARE + [(0.5, 0.5, 1.0)], [tuple(range(k))])
    diff = compare_meshes(empty, empty)
    assert diff.identical and diff.vertex_map.shape == (0,) and diff.cell_map.shape == (0,)
    diff = compare_meshes(empty, full, tolerance=1.0)
    assert diff.vertex_map.tolist() == [-1] * 5 and diff.cell_map.tolist() == [-1]
    diff = compare_meshes(full, empty)
    assert diff.removed_vertices.tolist() == [0, 1, 2, 3, 4] and diff.removed_cells.tolist() == [0]
    vertices_only = make_mesh(k, SQUARE, np.empty((0, k)))
    assert compare_meshes(full, vertices_only).removed_cells.tolist() == [0]


def test_tolerance_looks_past_vertices_already_taken() -> None:
    """Four old vertices near an edited one are taken by exact matches: a fifth within tolerance still counts."""
    near = [(0.1, 0.0, 0.0), (-0.1, 0.0, 0.0), (0.0, 0.1, 0.0), (0.0, -0.1, 0.0), (0.0, 0.0, 0.1)]
    old = PointSet(near + [(0.0, 0.0, 0.3)])
    edited = PointSet(near + [(0.0, 0.0, 0.0)])
    diff = compare_meshes(old, edited, tolerance=0.5)
    assert diff.vertex_map.tolist() == [0, 1, 2, 3, 4, 5]
    assert as_lists(diff) == reference(old, edited, 0.5)


def test_tolerance_pairs_nearest_first() -> None:
    old = PointSet([(0.0, 0.0, 0.0), (1.0, 0.0, 0.0)])
    edited = PointSet([(0.6, 0.0, 0.0), (0.9, 0.0, 0.0)])  # 0.6 is nearer 1.0 than 0, but 0.9 is nearer still
    diff = compare_meshes(old, edited, tolerance=0.7)
    assert diff.vertex_map.tolist() == [0, 1]
    assert compare_meshes(old, edited, tolerance=0.5).vertex_map.tolist() == [-1, 1]
    # a distance equal to the tolerance counts
    assert compare_meshes(old, PointSet([(0.5, 0.0, 0.0)]), tolerance=0.5).vertex_map.tolist() == [0]


@pytest.mark.parametrize("other", [LineSet, Surface, TetraMesh])
def test_different_cell_sizes_are_refused(other: type[Mesh]) -> None:
    points = PointSet(SQUARE + [(0.5, 0.5, 1.0)])
    mesh = make_mesh(other.cell_size, points.vertices, [tuple(range(other.cell_size))])
    with pytest.raises(tgsis.InvalidGeometryError, match="cells of 1 and"):
        compare_meshes(points, mesh)
    with pytest.raises(tgsis.InvalidGeometryError, match="cannot compare"):
        compare_meshes(MeshIndex(mesh), points)


@pytest.mark.parametrize("tolerance", [-1.0, -0.0 - 1e-300, float("nan"), float("inf"), float("-inf")])
def test_bad_tolerance_is_refused(tolerance: float) -> None:
    square = Surface(SQUARE, TWO_TRIANGLES)
    with pytest.raises(tgsis.InvalidInputError, match="tolerance must be a finite number >= 0"):
        compare_meshes(square, square, tolerance)


# ---------------------------------------------------------------- the real faults of two CFM releases

RE_EXPORTED = "GRFS-GRFZ-WEST-Garlock_fault-CFM5_1000m.ts"
RE_INTERPRETED = [
    "CRFA-OCNZ-MULT-Oceanic_fault-CFM5_1000m.ts",
    "CRFA-SLRS-MULT-San_Luis_Range_fault_system-CFM4_1000m.ts",
]
#: CFM 5.3 writes 5 decimals (metres), 6.1 the float32 values in full: a re-export moves a vertex by < 1e-5 m
ROUNDING = 1e-4


def releases(name: str) -> tuple[Surface, Surface]:
    return read_tsurf(cfm(f"cfm5.3/{name}")), read_tsurf(cfm(f"cfm6.1/{name}"))


def test_cfm_re_exported_fault_is_almost_unchanged_within_rounding() -> None:
    old, new = releases(RE_EXPORTED)
    assert (old.n_vertices, old.n_cells) == (new.n_vertices, new.n_cells)
    exact = compare_meshes(old, new)
    assert np.count_nonzero(exact.vertex_map >= 0) < 0.05 * new.n_vertices  # more digits: exactly, nearly all moved
    assert np.count_nonzero(exact.vertex_map != np.arange(new.n_vertices)) > 0.9 * new.n_vertices  # renumbered
    diff = compare_meshes(MeshIndex(old), new, tolerance=ROUNDING)
    assert_valid(old, new, diff, ROUNDING)
    assert np.all(diff.vertex_map >= 0) and len(diff.removed_vertices) == 0  # every vertex is the old one
    assert len(diff.added_cells) == len(diff.removed_cells) <= 0.01 * new.n_cells  # a few triangles redrawn
    # ... and those are edge flips: on surviving vertices, just another triangulation of them
    assert np.all(diff.vertex_map[new.cells[diff.added_cells]] >= 0)
    assert set(diff.vertex_map[new.cells[diff.added_cells]].ravel().tolist()) == set(
        old.cells[diff.removed_cells].ravel().tolist()
    )
    assert as_lists(diff) == reference(old, new, ROUNDING)
    assert_diff_reproduces_within(old, new, diff, ROUNDING)


@pytest.mark.parametrize("name", RE_INTERPRETED)
def test_cfm_re_interpreted_fault_keeps_a_minority(name: str) -> None:
    old, new = releases(name)
    diff = compare_meshes(old, new, tolerance=ROUNDING)
    assert_valid(old, new, diff, ROUNDING)
    vertices_kept = np.count_nonzero(diff.vertex_map >= 0) / new.n_vertices
    cells_kept = np.count_nonzero(diff.cell_map >= 0) / new.n_cells
    assert 0.1 < vertices_kept < 0.5 and 0.05 < cells_kept < 0.4  # measured: 0.27-0.31 and 0.13-0.17
    assert cells_kept < vertices_kept  # a triangle survives only when its three vertices do
    assert as_lists(diff) == reference(old, new, ROUNDING)
    assert_diff_reproduces_within(old, new, diff, ROUNDING)
    exact = compare_meshes(old, new)
    assert np.count_nonzero(exact.cell_map >= 0) == 0
    assert np.count_nonzero(exact.vertex_map >= 0) < 0.05 * new.n_vertices


@pytest.mark.parametrize("name", [RE_EXPORTED, *RE_INTERPRETED])
def test_cfm_fault_compared_with_itself_renumbered(name: str) -> None:
    _, new = releases(name)
    rng = np.random.default_rng(0)
    order, cell_order = rng.permutation(new.n_vertices), rng.permutation(new.n_cells)
    inverse = np.argsort(order)
    rotated = np.roll(inverse[new.cells[cell_order]], 1, axis=1)  # an even permutation of each triangle
    diff = compare_meshes(new, Surface(new.vertices[order], rotated))
    assert diff.identical
    assert diff.vertex_map.tolist() == order.tolist() and diff.cell_map.tolist() == cell_order.tolist()


def assert_diff_reproduces_within(old: Mesh, edited: Mesh, diff: MeshDiff, tolerance: float) -> None:
    """With a tolerance the kept vertices keep their old coordinates: the same mesh up to that distance."""
    vertices, cells = applied(old, edited, diff)
    assert len(vertices) == edited.n_vertices and len(cells) == edited.n_cells
    # the edited mesh with each kept vertex put back at its old position is the applied diff exactly
    snapped = edited.vertices.copy()
    kept = diff.vertex_map >= 0
    assert np.all(np.linalg.norm(snapped[kept] - old.vertices[diff.vertex_map[kept]], axis=1) <= tolerance)
    snapped[kept] = old.vertices[diff.vertex_map[kept]]
    assert Counter(map(tuple, vertices.tolist())) == Counter(map(tuple, snapped.tolist()))
    assert oriented_cells_by_coordinates(vertices.tolist(), cells.tolist()) == oriented_cells_by_coordinates(
        snapped.tolist(), edited.cells.tolist()
    )
