"""Mesh comparison in SQL (tgsis.compare_geometries and friends) against tgsis.compare_meshes.

Random meshes of every cell size are edited the ways a modeller's tool edits
them — vertex and cell order shuffled, cells rotated by even permutations,
orientations reversed, edges flipped, ``-0.0`` for ``0.0``, vertices moved by
one ulp or further, vertices and cells removed and added — and stored with
``insert_feature`` (ids 0..n-1 in upload order), so the SQL answer in stored
ids must be the Python answer in indices, pair for pair. Then the same for a
surface edited through the versioned views in a child version, and the
errors of bad calls.
"""

from __future__ import annotations

from collections.abc import Collection
from typing import Any

import numpy as np
import psycopg
import pytest

import tgsis
from tgsis.compare import MeshDiff, compare_meshes
from tgsis.db import features as F
from tgsis.db.compare import GeometryChanges, compare_stored, compare_versions
from tgsis.mesh import GeometryCollection, LineSet, Mesh, PointSet, Surface, TetraMesh

from .roles import login_roles
from .temporal_data import series

Conn = psycopg.Connection[Any]

MESH_TYPES: dict[int, type[Mesh]] = {1: PointSet, 2: LineSet, 3: Surface, 4: TetraMesh}
GEOTYPES = {1: "MULTIPOINT", 2: "MULTILINESTRING", 3: "SURFACE", 4: "MULTITETRA"}


# ---------------------------------------------------------------- meshes and edits


Point = tuple[float, float, float]


def _distinct_points(rng: np.random.Generator, n: int, exclude: Collection[Point] = ()) -> list[Point]:
    """n distinct points on a coarse grid (0.1 steps, so zeros occur and most values are inexact)."""
    points: list[Point] = []
    seen = set(exclude)
    while len(points) < n:
        x, y, z = (float(c) for c in rng.integers(-4, 5, 3) * 0.1)
        if (x, y, z) not in seen:
            seen.add((x, y, z))
            points.append((x, y, z))
    return points


def _random_cells(
    rng: np.random.Generator, n: int, k: int, m: int, taken: set[frozenset[int]]
) -> list[tuple[int, ...]]:
    """Up to m cells of k distinct vertices on vertex sets not in ``taken`` (a normal mesh)."""
    cells: list[tuple[int, ...]] = []
    for _ in range(20 * m):
        if len(cells) == m or n < k:
            break
        cell = tuple(int(i) for i in rng.choice(n, k, replace=False))
        if frozenset(cell) not in taken:
            taken.add(frozenset(cell))
            cells.append(cell)
    return cells


def old_mesh(rng: np.random.Generator, k: int) -> Mesh:
    """A normal mesh with k-vertex cells: a grid surface (edges to flip) for k = 3, random cells otherwise."""
    if k == 3:
        nx, ny = 6, 5
        z = rng.integers(-2, 3, nx * ny) * 0.1
        vertices = [(0.5 * i, 0.5 * j, float(z[i * ny + j])) for i in range(nx) for j in range(ny)]
        triangles = []
        for i in range(nx - 1):
            for j in range(ny - 1):
                a, b, c, d = i * ny + j, (i + 1) * ny + j, i * ny + j + 1, (i + 1) * ny + j + 1
                triangles += [(a, b, d), (a, d, c)]
        return Surface(vertices, triangles)
    vertices = _distinct_points(rng, 40)
    if k == 1:
        return PointSet(vertices)
    return MESH_TYPES[k](vertices, _random_cells(rng, len(vertices), k, 50, set()))


def edit(rng: np.random.Generator, mesh: Mesh) -> Mesh:
    """An edited copy of ``mesh``: every kind of change the comparison must see through or catch."""
    k, n = mesh.cell_size, mesh.n_vertices
    vertices = mesh.vertices.copy()
    action = rng.choice(["keep", "keep", "keep", "move", "ulp", "zero", "remove"], n)
    for i in np.flatnonzero(action == "ulp"):
        j = rng.integers(3)
        vertices[i, j] = np.nextafter(vertices[i, j], np.inf if rng.random() < 0.5 else -np.inf)
    signed = vertices[action == "zero"]
    vertices[action == "zero"] = np.where(signed == 0, -0.0, signed)
    taken = {(float(x), float(y), float(z)) for x, y, z in mesh.vertices.tolist()}
    moved = np.flatnonzero(action == "move")
    if len(moved):
        vertices[moved] = np.asarray(_distinct_points(rng, len(moved), taken)) + 0.05  # off the grid: new places
    survivors = np.flatnonzero(action != "remove")

    cells = mesh.cells.tolist()
    cell_action = rng.choice(["keep", "keep", "rotate", "reverse", "remove"], len(cells))
    if k == 3:  # flip the diagonal of some quads of the grid: (a, b, d), (a, d, c) -> (a, b, c), (b, d, c)
        half = len(cells) // 2
        for q in range(half):
            if cell_action[q] == cell_action[half + q] == "keep" and rng.random() < 0.3:
                (a, b, d), c = cells[q], cells[half + q][2]
                cells[q], cells[half + q] = [a, b, c], [b, d, c]
    edited_cells: list[list[int]] = []
    for cell, what in zip(cells, cell_action):
        if what == "remove":
            continue
        if what == "rotate" and k >= 3:
            cell = cell[1:] + cell[:1] if k == 3 else [cell[1], cell[0], cell[3], cell[2]]  # even permutations
        elif what == "reverse" and k >= 2:
            cell = [cell[1], cell[0], *cell[2:]]
        edited_cells.append(cell)

    # removed vertices take their cells with them; new vertices (one where a removed one was) and new cells
    alive = np.zeros(n, dtype=bool)
    alive[survivors] = True
    edited_cells = [c for c in edited_cells if alive[c].all()]
    renumber = np.full(n, -1)
    renumber[survivors] = np.arange(len(survivors))
    new_vertices: list[Point] = [(float(x), float(y), float(z)) for x, y, z in vertices[survivors].tolist()]
    gone = np.flatnonzero(action == "remove")
    if len(gone):
        x, y, z = mesh.vertices[gone[0]].tolist()
        new_vertices.append((x, y, z))  # back where an old vertex was: kept
    new_vertices += _distinct_points(rng, 4, set(new_vertices) | taken)
    cells_now = [[int(renumber[i]) for i in c] for c in edited_cells]
    sets = {frozenset(c) for c in cells_now}
    if k == 1:
        cells_now += [[i] for i in range(len(survivors), len(new_vertices))]
    else:
        cells_now += [list(c) for c in _random_cells(rng, len(new_vertices), k, 6, sets)]

    order = rng.permutation(len(new_vertices))  # shuffle vertices and cells
    position = np.empty_like(order)
    position[order] = np.arange(len(order))
    shuffled = np.asarray(new_vertices, dtype=np.float64).reshape(-1, 3)[order]
    cell_array = np.asarray(cells_now, dtype=np.int64).reshape(-1, k)
    cell_array = position[cell_array][rng.permutation(len(cell_array))]
    return type(mesh)(shuffled, cell_array)


# ---------------------------------------------------------------- expected answers in stored ids


def expected(
    diff: MeshDiff,
    vertex_ids_old: np.ndarray | None = None,
    vertex_ids_new: np.ndarray | None = None,
    cell_ids_old: np.ndarray | None = None,
    cell_ids_new: np.ndarray | None = None,
) -> GeometryChanges:
    """A MeshDiff in stored ids (default: the index itself, as a fresh insert_feature stores it)."""

    def ids(given: np.ndarray | None, count: int) -> np.ndarray:
        return np.arange(count, dtype=np.int64) if given is None else np.asarray(given, dtype=np.int64)

    vo, vn = ids(vertex_ids_old, diff.n_old_vertices), ids(vertex_ids_new, len(diff.vertex_map))
    co, cn = ids(cell_ids_old, diff.n_old_cells), ids(cell_ids_new, len(diff.cell_map))

    def pairs(mapping: np.ndarray, old: np.ndarray, new: np.ndarray) -> np.ndarray:
        kept = np.flatnonzero(mapping >= 0)
        p = np.stack([old[mapping[kept]], new[kept]], axis=1).reshape(-1, 2)
        return p[np.argsort(p[:, 1], kind="stable")]

    return GeometryChanges(
        vertices_kept=len(diff.kept_vertices),
        vertices_removed=np.sort(vo[diff.removed_vertices]),
        vertices_added=np.sort(vn[diff.added_vertices]),
        cells_kept=len(diff.kept_cells),
        cells_removed=np.sort(co[diff.removed_cells]),
        cells_added=np.sort(cn[diff.added_cells]),
        vertex_pairs=pairs(diff.vertex_map, vo, vn),
        cell_pairs=pairs(diff.cell_map, co, cn),
    )


def assert_same(got: GeometryChanges, want: GeometryChanges, with_pairs: bool = True) -> None:
    assert got.counts() == want.counts()
    for name in ("vertices_removed", "vertices_added", "cells_removed", "cells_added"):
        np.testing.assert_array_equal(getattr(got, name), getattr(want, name), err_msg=name)
        assert getattr(got, name).dtype == np.int64
    if with_pairs:
        assert got.vertex_pairs is not None and got.cell_pairs is not None
        np.testing.assert_array_equal(got.vertex_pairs, want.vertex_pairs, err_msg="vertex pairs")
        np.testing.assert_array_equal(got.cell_pairs, want.cell_pairs, err_msg="cell pairs")
    else:
        assert got.vertex_pairs is None and got.cell_pairs is None


def check_stored(conn: Conn, fc: F.FeatureClass, old: Mesh, new: Mesh) -> GeometryChanges:
    """Store both meshes, compare them in SQL both ways (summary, all rows), and against compare_meshes."""
    a, b = F.insert_feature(conn, fc, old), F.insert_feature(conn, fc, new)
    want = expected(compare_meshes(old, new))
    got = compare_stored(conn, a, b, pairs=True)
    assert_same(got, want)
    assert_same(compare_stored(conn, a, b), want, with_pairs=False)
    return got


# ---------------------------------------------------------------- stored geometries


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("k", [1, 2, 3, 4])
def test_random_edits_equal_compare_meshes(tx: Conn, k: int, seed: int) -> None:
    rng = np.random.default_rng(1000 * k + seed)
    fc = F.create_feature_class(tx, "meshes", GEOTYPES[k])
    for _ in range(3):
        old = old_mesh(rng, k)
        new = edit(rng, old)
        got = check_stored(tx, fc, old, new)
        assert got.vertices_removed.size and got.vertices_added.size and got.vertices_kept  # the edits did something
        check_stored(tx, fc, new, old)  # and back


def test_each_kind_of_edit(tx: Conn) -> None:
    fc = F.create_feature_class(tx, "surfaces", "SURFACE")
    vertices = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0.5], [2, 0, 1.0]], dtype=float)
    triangles = np.array([[0, 1, 3], [0, 3, 2], [1, 4, 3]])
    old = Surface(vertices, triangles)

    def run(new: Surface) -> GeometryChanges:
        return check_stored(tx, fc, old, new)

    # same mesh, vertices and triangles shuffled, triangles rotated, -0.0 for 0.0: nothing changed
    shuffled = vertices[[4, 2, 0, 3, 1]]
    same = run(Surface(np.where(shuffled == 0, -0.0, shuffled), [[4, 3, 2], [3, 1, 2], [0, 3, 4]]))
    assert same.identical and same.counts()["vertices_kept"] == 5 and same.counts()["cells_kept"] == 3
    # a reversed triangle is edited, its vertices are not
    reversed_one = run(Surface(vertices, [[0, 3, 1], [0, 3, 2], [1, 4, 3]]))
    assert reversed_one.counts() == {
        "vertices_kept": 5,
        "vertices_removed": 0,
        "vertices_added": 0,
        "cells_kept": 2,
        "cells_removed": 1,
        "cells_added": 1,
    }
    assert reversed_one.cells_removed.tolist() == [0] and reversed_one.cells_added.tolist() == [0]
    # an edge flip: two triangles edited although all four vertices survive
    flipped = run(Surface(vertices, [[0, 1, 2], [1, 3, 2], [1, 4, 3]]))
    assert flipped.counts()["cells_kept"] == 1 and flipped.cells_removed.tolist() == [0, 1]
    # a vertex moved by one ulp is a removed and an added vertex, and takes its triangles along
    moved = vertices.copy()
    moved[3, 2] = np.nextafter(0.5, 1.0)
    ulp = run(Surface(moved, triangles))
    assert ulp.vertices_removed.tolist() == [3] and ulp.vertices_added.tolist() == [3]
    assert ulp.counts()["cells_kept"] == 0


@pytest.mark.parametrize("k", [1, 2, 3, 4])
def test_coincident_vertices_and_cells_pair_in_id_order(tx: Conn, k: int) -> None:
    """Not normal meshes (a coordinate triple or a cell repeats): paired one to one, k-th with k-th, as in Python."""
    rng = np.random.default_rng(7 + k)
    fc = F.create_feature_class(tx, "crowded", GEOTYPES[k])
    points = _distinct_points(rng, 12)
    for _ in range(4):
        picks = rng.integers(0, len(points), 16)  # repeats
        old_vertices = np.asarray(points, dtype=float)[picks]
        new_vertices = np.asarray(points, dtype=float)[rng.integers(0, len(points), 14)]
        if k == 1:
            old_cells, new_cells = np.arange(16).reshape(-1, 1), rng.integers(0, 14, (20, 1))
        else:
            old_cells = np.asarray(_random_cells(rng, 16, k, 12, set()))
            old_cells = np.concatenate([old_cells, old_cells[:3]])  # the same cells twice
            new_cells = np.asarray(_random_cells(rng, 14, k, 12, set()))
            new_cells = np.concatenate([new_cells, new_cells[:2], new_cells[:1]])
        check_stored(tx, fc, MESH_TYPES[k](old_vertices, old_cells), MESH_TYPES[k](new_vertices, new_cells))


def test_empty_and_identical_geometries(tx: Conn) -> None:
    fc = F.create_feature_class(tx, "lines", "MULTILINESTRING")
    line = LineSet([[0, 0, 0], [1, 0, 0], [1, 1, 0]], [[0, 1], [1, 2]])
    empty = LineSet(np.empty((0, 3)), np.empty((0, 2)))
    a, b = F.insert_feature(tx, fc, line), F.insert_feature(tx, fc, empty)
    assert compare_stored(tx, a, a).identical
    gone = check_stored(tx, fc, line, empty)
    assert gone.vertices_removed.tolist() == [0, 1, 2] and gone.cells_removed.tolist() == [0, 1]
    assert check_stored(tx, fc, empty, empty).identical
    # the six rows a psql user sees: fixed order, NULL ids for kept rows
    rows = tx.execute("SELECT * FROM tgsis.compare_geometries(%s, %s)", (a, b)).fetchall()
    assert rows == [
        ("vertex", "kept", 0, None),
        ("vertex", "removed", 3, [0, 1, 2]),
        ("vertex", "added", 0, []),
        ("cell", "kept", 0, None),
        ("cell", "removed", 2, [0, 1]),
        ("cell", "added", 0, []),
    ]


# ---------------------------------------------------------------- versions


def _grid(side: int) -> Surface:
    u, v = np.meshgrid(np.arange(side, dtype=float), np.arange(side, dtype=float))
    vertices = np.stack([u.ravel(), v.ravel(), np.sin(u.ravel()) * np.cos(v.ravel())], axis=1)
    idx = np.arange(side * side).reshape(side, side)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel()
    return Surface(vertices, np.concatenate([np.stack([a, b, d], 1), np.stack([a, d, c], 1)]))


def _mesh_at(
    conn: Conn, geoid: int, version: str, revision: int | None = None
) -> tuple[Surface, np.ndarray, np.ndarray]:
    """The surface a version (at a revision) sees, read with tgsis.rows_at, with its vertex and triangle ids."""
    vertices = np.array(
        conn.execute(
            "SELECT vrtxid, x, y, z FROM tgsis.rows_at(NULL::tgsis.vrtx, %s, %s) WHERE geoid = %s ORDER BY vrtxid",
            (version, revision, geoid),
        ).fetchall(),
        dtype=np.float64,
    ).reshape(-1, 4)
    triangles = np.array(
        conn.execute(
            "SELECT trglid, vrtxid1, vrtxid2, vrtxid3 FROM tgsis.rows_at(NULL::tgsis.trgl, %s, %s) WHERE geoid = %s "
            "ORDER BY trglid",
            (version, revision, geoid),
        ).fetchall(),
        dtype=np.int64,
    ).reshape(-1, 4)
    vertex_ids = vertices[:, 0].astype(np.int64)
    return (Surface(vertices[:, 1:], np.searchsorted(vertex_ids, triangles[:, 1:])), vertex_ids, triangles[:, 0].copy())


def check_versions(conn: Conn, geoid: int, old: tuple[str, int | None], new: tuple[str, int | None]) -> GeometryChanges:
    """compare_versions (both forms) against compare_meshes on the rows each side sees."""
    (old_mesh_, vo, co), (new_mesh_, vn, cn) = _mesh_at(conn, geoid, *old), _mesh_at(conn, geoid, *new)
    want = expected(compare_meshes(old_mesh_, new_mesh_), vo, vn, co, cn)
    got = compare_versions(conn, geoid, old[0], new[0], old_revision=old[1], new_revision=new[1], pairs=True)
    assert_same(got, want)
    assert_same(
        compare_versions(conn, geoid, old[0], new[0], old_revision=old[1], new_revision=new[1]), want, with_pairs=False
    )
    return got


def _storage_rows(conn: Conn) -> dict[str, int]:
    """Rows of the storage (row versions, or chunk versions once a table is stored in chunks) and of the registry."""
    storage = [
        str(conn.execute("SELECT tgsis.storage_table('tgsis', %s)", (t,)).fetchone()[0])  # type: ignore[index]
        for t in ("geometry", "vrtx", "trgl")
    ]
    return {
        t: int(conn.execute(f"SELECT count(*) FROM {t}").fetchone()[0])  # type: ignore[index]
        for t in (*storage, "tgsis.versions", "tgsis.revisions")
    }


def test_surface_edited_in_a_child_version(conn: Conn, db_dsn: str) -> None:
    fc = F.create_feature_class(conn, "horizons", "SURFACE")
    geoid = F.insert_feature(conn, fc, _grid(12))  # 144 vertices, 242 triangles
    other = F.insert_feature(conn, fc, _grid(5))  # another geometry: never read
    tgsis.enable_feature_versioning(conn)
    tgsis.create_version(conn, "edit")
    with tgsis.in_version(conn, "edit"):
        # a psql user edits through the views: a move, a removed vertex with its triangles, a new vertex
        # with new triangles, a reversed triangle, a flipped edge, a -0.0, and a vertex moved away and back
        conn.execute("UPDATE tgsis.vrtx SET z = z + 1 WHERE geoid = %s AND vrtxid IN (5, 6)", (geoid,))
        conn.execute("DELETE FROM tgsis.trgl WHERE geoid = %s AND 30 IN (vrtxid1, vrtxid2, vrtxid3)", (geoid,))
        conn.execute("DELETE FROM tgsis.vrtx WHERE geoid = %s AND vrtxid = 30", (geoid,))
        conn.execute("INSERT INTO tgsis.vrtx (geoid, vrtxid, x, y, z) VALUES (%s, 1000, 2.5, 2.5, 7)", (geoid,))
        conn.execute(
            "INSERT INTO tgsis.trgl (geoid, trglid, vrtxid1, vrtxid2, vrtxid3) "
            "VALUES (%s, 1000, 1000, 100, 101), (%s, 1001, 1000, 101, 113)",
            (geoid, geoid),
        )
        conn.execute(
            "UPDATE tgsis.trgl SET vrtxid1 = vrtxid2, vrtxid2 = vrtxid1 WHERE geoid = %s AND trglid = 50", (geoid,)
        )
        # the quad of triangles 70 (a, b, d) and 70 + 121 (a, d, c) gets its other diagonal
        a, b, d = conn.execute(
            "SELECT vrtxid1, vrtxid2, vrtxid3 FROM tgsis.trgl WHERE geoid = %s AND trglid = 70", (geoid,)
        ).fetchone()  # type: ignore[misc]
        c = conn.execute("SELECT vrtxid3 FROM tgsis.trgl WHERE geoid = %s AND trglid = 191", (geoid,)).fetchone()[0]  # type: ignore[index]
        flip = "UPDATE tgsis.trgl SET vrtxid1 = %s, vrtxid2 = %s, vrtxid3 = %s WHERE geoid = %s AND trglid = %s"
        conn.execute(flip, (a, b, c, geoid, 70))
        conn.execute(flip, (b, d, c, geoid, 191))
        conn.execute("UPDATE tgsis.vrtx SET y = -0.0 WHERE geoid = %s AND vrtxid = 3", (geoid,))
        conn.execute("UPDATE tgsis.vrtx SET x = x + 1 WHERE geoid = %s AND vrtxid = 40", (geoid,))
        conn.execute("UPDATE tgsis.vrtx SET x = x - 1 WHERE geoid = %s AND vrtxid = 40", (geoid,))
        conn.commit()
        first = tgsis.save_revision(conn, "first_edits")
        conn.execute("UPDATE tgsis.vrtx SET x = x + 0.5 WHERE geoid = %s AND vrtxid = 77", (geoid,))
        conn.execute("DELETE FROM tgsis.trgl WHERE geoid = %s AND trglid = 1000", (geoid,))
        conn.commit()
    before = _storage_rows(conn)
    session = tgsis.working_version(conn)

    got = check_versions(conn, geoid, ("DEFAULT", None), ("edit", None))
    assert got.vertices_removed.tolist() == [5, 6, 30, 77] and got.vertices_added.tolist() == [5, 6, 77, 1000]
    assert got.cells_added.tolist()[-1] == 1001 and 50 in got.cells_added and 70 in got.cells_added
    check_versions(conn, geoid, ("edit", None), ("DEFAULT", None))
    rev = check_versions(conn, geoid, ("edit", first), ("edit", None))  # a revision against the working state
    assert rev.vertices_removed.tolist() == [77] and rev.vertices_added.tolist() == [77]
    # the triangles around vertex 77 are removed and added again; triangle 1000 is only removed
    assert 1000 in rev.cells_removed and len(rev.cells_added) == len(rev.cells_removed) - 1
    assert check_versions(conn, geoid, ("DEFAULT", 0), ("edit", 0)).identical  # the base, seen from both
    assert compare_versions(conn, other, "DEFAULT", "edit").identical

    # versions compared without moving the session, and nothing written
    assert tgsis.working_version(conn) == session and _storage_rows(conn) == before
    # in the child, the stored-geometry comparison reads the child's rows
    with tgsis.in_version(conn, "edit"):
        assert compare_stored(conn, geoid, geoid).identical
        in_child = compare_stored(conn, other, geoid)
    assert in_child.vertices_added.tolist()[-1] == 1000
    # a reader may compare too (the version functions read the storage tables, whose grants readers have)
    with login_roles(db_dsn, {"ann": "tgsis_reader"}) as roles:
        reader = roles.connect("ann")
        assert_same(compare_versions(reader, geoid, "DEFAULT", "edit", pairs=True), got)
        assert compare_stored(reader, other, other).identical


# ---------------------------------------------------------------- bad calls


def test_bad_calls_are_refused_with_our_sqlstates_and_change_nothing(conn: Conn) -> None:
    surfaces = F.create_feature_class(conn, "surfaces", "SURFACE")
    points = F.create_feature_class(conn, "points", "MULTIPOINT")
    blocks = F.create_feature_class(conn, "blocks", "GEOMETRYCOLLECTION")
    stepped = F.create_feature_class(conn, "stepped", "SURFACE", time_model="INSTANTS")
    s = F.insert_feature(conn, surfaces, _grid(3))
    p = F.insert_feature(conn, points, PointSet([[0, 0, 0], [1, 1, 1]]))
    block = F.insert_feature(conn, blocks, GeometryCollection([_grid(3), PointSet([[0, 0, 0]])]))
    temporal = F.insert_feature(conn, stepped, series(np.random.default_rng(0), [0.0, 1.0]))
    conn.commit()

    def refused(error: type[tgsis.Error], sqlstate: str, match: str, call: Any, *args: Any, **kwargs: Any) -> None:
        with pytest.raises(error, match=match) as info:
            call(conn, *args, **kwargs)
        assert info.value.sqlstate == sqlstate
        assert conn.execute("SELECT 1").fetchone() == (1,)  # the caller's transaction is still usable

    refused(tgsis.NotFoundError, "TG200", "geometry 999 does not exist", compare_stored, s, 999)
    refused(
        tgsis.InvalidInputError,
        "TG100",
        r"geometry \d+ \(SURFACE\) with geometry \d+ \(MULTIPOINT\)",
        compare_stored,
        s,
        p,
    )
    refused(tgsis.InvalidInputError, "TG100", "is a GEOMETRYCOLLECTION", compare_stored, block, block, pairs=True)
    row = conn.execute("SELECT geoids[1] FROM tgsis.geometry WHERE geoid = %s", (block,)).fetchone()
    assert row is not None
    member = row[0]
    assert compare_stored(conn, member, s).identical  # a member is a geometry of its own
    refused(tgsis.InvalidInputError, "TG100", "temporal surface", compare_stored, temporal, s)
    refused(tgsis.InvalidInputError, "TG100", "model 1 is not versioned", compare_versions, s, "DEFAULT", "DEFAULT")
    with pytest.raises(psycopg.Error) as raw:
        conn.execute("SELECT * FROM tgsis.compare_geometries(NULL, %s)", (s,))
    assert raw.value.sqlstate == "TG100"
    conn.rollback()

    tgsis.enable_feature_versioning(conn)
    tgsis.create_version(conn, "v1")
    with tgsis.in_version(conn, "v1"):
        added = F.insert_feature(conn, surfaces, _grid(4))
    before = _storage_rows(conn)
    refused(tgsis.NotFoundError, "TG200", "version 'nope' does not exist", compare_versions, s, "DEFAULT", "nope")
    refused(
        tgsis.NotFoundError,
        "TG200",
        "revision 99 is not in the history",
        compare_versions,
        s,
        "v1",
        "v1",
        old_revision=99,
    )
    refused(
        tgsis.NotFoundError,
        "TG200",
        f"geometry {added} does not exist in version 'DEFAULT'",
        compare_versions,
        added,
        "DEFAULT",
        "v1",
    )
    refused(
        tgsis.NotFoundError,
        "TG200",
        f"geometry {added} does not exist in version 'v1' at revision 0",
        compare_versions,
        added,
        "v1",
        "v1",
        old_revision=0,
        pairs=True,
    )
    refused(tgsis.InvalidInputError, "TG100", "temporal surface", compare_versions, temporal, "DEFAULT", "v1")
    refused(tgsis.InvalidInputError, "TG100", "GEOMETRYCOLLECTION", compare_versions, block, "DEFAULT", "v1")
    assert compare_versions(conn, added, "v1", "v1").identical
    assert _storage_rows(conn) == before
