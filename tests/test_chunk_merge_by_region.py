"""The SQL merge by region on model-1 tables stored in chunks (issue 40): regions and merged rows as on rows.

The three states of a feature are built as rows (a fresh database, whatever
``TGSIS_TEST_STORAGE`` says), where the Python merge (merge3, the oracle) and
the SQL merge by region run first; then every table registered for chunks is
switched (``tgsis.store_in_chunks``) and the SQL merge runs again on the
chunks: the regions ``tgsis.find_conflicts`` stores must be merge3's, and the
mesh ``tgsis.merge_mesh_by_region`` writes into the version must be, row for
row and bit for bit, the one it wrote on rows. The surface is larger than one
chunk (1,024 ids) so that edits fall into several chunks and most chunks stay
unchanged.
"""

from __future__ import annotations

import struct
from collections.abc import Callable, Iterator
from typing import Any

import numpy as np
import psycopg
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import tgsis
from tests.merge_data import curved_surface, move
from tests.test_sql_merge_regions import python_regions, sql_regions
from tgsis.db import features as F
from tgsis.merge3 import MeshState
from tgsis.testing import TestServer

Conn = psycopg.Connection[Any]

SIDE = 40  # 1,600 vertices (chunks 0 and 1), 3,042 triangles (chunks 0 to 2)
CHUNKED = (
    "SELECT tgsis.store_in_chunks(tablename) FROM tgsis.model_tables WHERE chunkdefault"
    " AND NOT tgsis.stored_in_chunks(tablename) ORDER BY model, iudorder, tablename"
)


def grid_surface(side: int) -> tgsis.Surface:
    """A side x side curved grid (full mantissas), a vertex and a cell property (tests/merge_data.py's)."""
    return curved_surface(side)


@pytest.fixture(scope="module")
def rows_fault(pg: TestServer) -> Iterator[tuple[str, int]]:
    """(database, geoid): tgsis installed in a fresh database (rows), the grid in class faults of DEFAULT, version e1."""
    with pg.database("tgsis_w5rows") as (name, dsn):
        with psycopg.connect(dsn) as conn:
            # rows whatever the default: the switch of each test is the point
            tgsis.install(conn, method="extension" if pg.extension_files is None else "sql", storage="rows")
            conn.commit()
            F.create_feature_class(
                conn,
                "faults",
                "SURFACE",
                cell_properties=[("porosity", "float8"), tgsis.Property("facies", "int", alignment="CELL")],
            )
            tgsis.enable_feature_versioning(conn)
            geoid = F.insert_feature(conn, "faults", grid_surface(SIDE))
            tgsis.create_version(conn, "e1")
            conn.commit()
        yield name, geoid


class Clones:
    """``clones.new() -> conn``: a new connection to a new copy of the rows database; ``clones.dsn``: the last's."""

    def __init__(self, template: str, make_database: Callable[..., str]) -> None:
        self._template = template
        self._make = make_database
        self.dsn = ""
        self.opened: list[Conn] = []

    def new(self) -> Conn:
        self.dsn = self._make(self._template)
        self.opened.append(psycopg.connect(self.dsn))
        return self.opened[-1]


@pytest.fixture
def clones(rows_fault: tuple[str, int], make_database: Callable[..., str]) -> Iterator[Clones]:
    made = Clones(rows_fault[0], make_database)
    yield made
    for c in made.opened:
        c.close()


def switch_to_chunks(conn: Conn) -> None:
    conn.execute(CHUNKED)
    conn.commit()
    assert conn.execute("SELECT tgsis.stored_in_chunks('vrtx') AND tgsis.stored_in_chunks('trgl')").fetchone() == (
        True,
    )


def version_state(conn: Conn, version: str, geoid: int) -> tuple[list[tuple[Any, ...]], ...]:
    """The version's vertices (coordinates as bits), triangles and geometry row (counts, box corners as bits:
    tgsis.merge_geometry_row reads the chunk arrays on chunks, the rows on rows) as its views show them."""
    with tgsis.in_version(conn, version):
        geometry = [
            (int(r[0]), int(r[1]), *(None if c is None else struct.pack(">d", float(c)) for c in r[2:]))
            for r in conn.execute(
                "SELECT nvrtx, ncell, cube_ll_coord(bbox, 1), cube_ll_coord(bbox, 2), cube_ll_coord(bbox, 3),"
                " cube_ur_coord(bbox, 1), cube_ur_coord(bbox, 2), cube_ur_coord(bbox, 3)"
                " FROM tgsis.geometry WHERE geoid = %s",
                (geoid,),
            )
        ]
        vertices = [
            (int(r[0]), *(struct.pack(">d", float(c)) for c in r[1:]))
            for r in conn.execute("SELECT vrtxid, x, y, z FROM tgsis.vrtx WHERE geoid = %s ORDER BY 1", (geoid,))
        ]
        cells = [
            tuple(int(c) for c in r)
            for r in conn.execute(
                "SELECT trglid, vrtxid1, vrtxid2, vrtxid3 FROM tgsis.trgl WHERE geoid = %s ORDER BY 1", (geoid,)
            )
        ]
    conn.rollback()
    return vertices, cells, geometry


def by_region(conn: Conn, geoid: int) -> tuple[Any, ...]:
    """(rows written, e1's state, conflicts) of the SQL merge of the feature by region into e1 (committed), or
    (SQLSTATE, message) of its refusal."""
    try:
        conn.execute("SET TRANSACTION ISOLATION LEVEL READ COMMITTED")
        row = conn.execute("SELECT tgsis.merge_mesh_by_region('e1', 'merge', %s)", (geoid,)).fetchone()
        conn.commit()
    except psycopg.Error as exc:
        conn.rollback()
        return ("refused", exc.sqlstate, str(exc).split("\n")[0])
    assert row is not None
    solved = conn.execute(
        "SELECT objectkey, solution FROM tgsis.conflicts WHERE versionid = tgsis.version_id('e1') ORDER BY 1"
    ).fetchall()
    conn.rollback()
    versions = [str(r[0]) for r in conn.execute("SELECT name FROM tgsis.versions ORDER BY versionid").fetchall()]
    conn.rollback()
    states = [version_state(conn, v, geoid) for v in versions]
    return ("done", row[0], *states, solved)


# ids in both vertex chunks (chunk 1 starts at 1024), the sides' edits meeting in chunk 0 and apart in chunk 1
NORTH = np.arange(3 * SIDE, 4 * SIDE)
MIDDLE = np.array([10 * SIDE + 10, 10 * SIDE + 11, 11 * SIDE + 10])
SOUTH = np.arange(30 * SIDE + 5, 30 * SIDE + 12)
EAST = np.array([1024 + 7, 1024 + 8, 1100])


def three_sides(conn: Conn, geoid: int) -> None:
    """e1 and DEFAULT edit the feature (five regions, one conflicting); another version, e2, made after DEFAULT's
    edits, rewrites the same chunks (its chunk versions are in none of e1's three sets)."""
    move(conn, "e1", geoid, NORTH, (0.5, 0.0, 1.25))
    move(conn, "e1", geoid, MIDDLE, (0.0, 0.0, 5.0))
    move(conn, "e1", geoid, EAST, (-0.125, 0.0, 0.0))
    move(conn, "DEFAULT", geoid, SOUTH, (-1.0, 0.0, -2.0))
    move(conn, "DEFAULT", geoid, MIDDLE, (0.0, 0.0, -7.0))
    tgsis.create_version(conn, "e2")
    conn.commit()
    move(conn, "e2", geoid, np.concatenate([NORTH, MIDDLE, EAST, SOUTH]), (9.0, 9.0, 9.0))
    conn.commit()


def test_regions_on_chunks_are_merge3s(clones: Clones, rows_fault: tuple[str, int]) -> None:
    """find_conflicts on chunks stores merge3's regions (failed before: mesh_merge_work read tgsis.vrtx_ver)."""
    geoid = rows_fault[1]
    conn = clones.new()
    three_sides(conn, geoid)
    theirs = python_regions(conn, "e1", geoid)
    assert sql_regions(conn, "e1", geoid) == theirs
    assert len(theirs) == 5 and [r["conflict"] for r in theirs].count(True) == 1
    switch_to_chunks(conn)
    assert sql_regions(conn, "e1", geoid) == theirs


def test_merge_by_region_writes_the_same_mesh_into_chunks(clones: Clones, rows_fault: tuple[str, int]) -> None:
    """The merged mesh written into the version's chunks is the one written as rows; a conflicting region solved
    child, and the version's and the parent's states are those of the rows."""
    geoid = rows_fault[1]
    outcomes = []
    for chunks in (False, True):
        conn = clones.new()
        three_sides(conn, geoid)
        conn.execute("SELECT FROM tgsis.find_conflicts('e1')")
        conn.commit()
        region = conn.execute(
            "SELECT region FROM tgsis.conflict_regions WHERE versionid = tgsis.version_id('e1') AND conflict"
        ).fetchone()
        assert region is not None
        conn.execute("SELECT tgsis.resolve_region('e1', 'feature', %s, %s, 'child')", (str(geoid), region[0]))
        conn.commit()
        if chunks:
            switch_to_chunks(conn)
        outcomes.append(by_region(conn, geoid))
    rows, chunked = outcomes
    assert rows[0] == "done", rows
    assert chunked[0] == "done", chunked[1:]
    assert chunked == rows


def test_roles_on_chunks(clones: Clones, rows_fault: tuple[str, int]) -> None:
    """mesh_merge_regions runs as the calling role on the chunks: an editor of the version gets the owner's
    regions; once the class may not be read, 42501 (regions without its rows would be wrong)."""
    from tests.roles import login_roles

    geoid = rows_fault[1]
    conn = clones.new()
    three_sides(conn, geoid)
    switch_to_chunks(conn)
    query = "SELECT * FROM tgsis.mesh_merge_regions('e1', %s) ORDER BY 1"
    owners = conn.execute(query, (geoid,)).fetchall()
    conn.rollback()
    assert len(owners) == 5
    with login_roles(clones.dsn, {"ed": "tgsis_editor"}) as made:
        tgsis.grant_version(conn, "e1", "write", made.name("ed"))
        conn.commit()
        ed = made.connect("ed")
        assert ed.execute(query, (geoid,)).fetchall() == owners
        ed.rollback()
        conn.execute("REVOKE SELECT ON public.faults FROM tgsis_editor, tgsis_reader")
        conn.commit()
        with pytest.raises(psycopg.errors.InsufficientPrivilege):
            ed.execute(query, (geoid,))
        ed.rollback()


# one edit of a side, anywhere on the grid (both vertex chunks, the three triangle chunks): (kind, where, which)
_edit = st.tuples(
    st.sampled_from(["move", "move", "move", "porosity", "facies", "delete", "flip", "add"]),
    st.integers(0, 2 * (SIDE - 1) ** 2 - 1),
    st.integers(0, 2),
)
_SHIFTS = [(0.0, 0.0, 1.5), (0.25, -0.5, 0.0), (-3.3, 7.77, 0.125)]


def apply_edits(conn: Conn, version: str, geoid: int, edits: list[tuple[str, int, int]]) -> None:
    """A side's edits as a psql user's statements (committed); vertices by a 2 x 2 patch around a grid point."""
    vp, cp = (
        str(r[0])
        for r in conn.execute(
            "SELECT format('%I.%I', schemaname, t) FROM tgsis.catalog, unnest(ARRAY[cellprotable, otherprotable]) AS t"
            " WHERE classname = 'faults' ORDER BY proalignment = 'VERTEX' AND t = cellprotable DESC,"
            " proalignment = 'CELL' AND t = otherprotable DESC"
        ).fetchall()
    )
    conn.rollback()
    with tgsis.in_version(conn, version):
        for kind, where, which in edits:
            row, col = (where // 2) // (SIDE - 1), (where // 2) % (SIDE - 1)
            patch = [r * SIDE + c for r in (row, row + 1) for c in (col, col + 1)]
            if kind == "move":
                conn.execute(
                    "UPDATE tgsis.vrtx SET x = x + %s, y = y + %s, z = z + %s WHERE geoid = %s AND vrtxid = ANY (%s)",
                    (*_SHIFTS[which], geoid, patch[: which + 2]),
                )
            elif kind == "porosity":
                conn.execute(
                    f"UPDATE {vp} SET porosity = %s WHERE _geoid = %s AND _idx = %s", (0.5 + which, geoid, patch[0])
                )
            elif kind == "facies":
                conn.execute(f"UPDATE {cp} SET facies = %s WHERE _geoid = %s AND _idx = %s", (which, geoid, where))
            elif kind == "delete":
                conn.execute("DELETE FROM tgsis.trgl WHERE geoid = %s AND trglid = %s", (geoid, where))
            elif kind == "flip":
                conn.execute(
                    "UPDATE tgsis.trgl SET vrtxid1 = vrtxid2, vrtxid2 = vrtxid1 WHERE geoid = %s AND trglid = %s",
                    (geoid, where),
                )
            else:  # a new vertex and a triangle on it, with the next ids (both sides hand out the same)
                conn.execute(
                    "INSERT INTO tgsis.vrtx (geoid, vrtxid, x, y, z)"
                    " SELECT %s, max(vrtxid) + 1, 1000.0 * %s, -400.0, %s FROM tgsis.vrtx WHERE geoid = %s",
                    (geoid, col, float(which), geoid),
                )
                conn.execute(
                    "INSERT INTO tgsis.trgl (geoid, trglid, vrtxid1, vrtxid2, vrtxid3)"
                    " SELECT %s, (SELECT max(trglid) + 1 FROM tgsis.trgl WHERE geoid = %s), %s, %s, max(vrtxid)"
                    "   FROM tgsis.vrtx WHERE geoid = %s",
                    (geoid, geoid, patch[0], patch[1], geoid),
                )
    conn.commit()


def merge_on_chunks_as_on_rows(
    clones: Clones, geoid: int, child: list[tuple[str, int, int]], parent: list[tuple[str, int, int]], solution: str
) -> None:
    """The sides' edits (apply_edits) made twice, every conflicting region solved `solution`, then merged by region on
    rows and, after the switch, on chunks: the regions on rows are merge3's with the solutions recorded, the switch
    keeps them as they are (solutions included: store_in_chunks renews the conflicts' marks, docs/storage.md "The
    storage switch"), and the merge writes and records on chunks what it does on rows, or refuses alike."""
    outcomes = []
    solved: list[dict[str, Any]] = []
    for chunks in (False, True):
        with clones.new() as conn:  # (closed after each example: hypothesis runs many)
            apply_edits(conn, "e1", geoid, child)
            apply_edits(conn, "DEFAULT", geoid, parent)
            found = conn.execute("SELECT count(*) FROM tgsis.find_conflicts('e1') WHERE objectkey = %s", (str(geoid),))
            if found.fetchone() == (0,):
                conn.rollback()
                return  # (one side's edits undone by the other's: nothing to merge)
            conn.commit()
            if not chunks:
                theirs = python_regions(conn, "e1", geoid)
                assert sql_regions(conn, "e1", geoid) == theirs
            conn.execute(
                "SELECT tgsis.resolve_region('e1', 'feature', %s, region, %s) FROM tgsis.conflict_regions"
                " WHERE versionid = tgsis.version_id('e1') AND conflict ORDER BY region",
                (str(geoid), solution),
            )
            conn.commit()
            if chunks:
                switch_to_chunks(conn)
                # (the regions as stored on rows once solved: merge3's, a conflicting one with its solution; the
                # expectation was merge3's regions before any solution, `unsolved`, which held only without conflicts)
                assert sql_regions(conn, "e1", geoid) == solved
            else:
                solved = sql_regions(conn, "e1", geoid)
                assert solved == [dict(r, solution=solution) if r["conflict"] else r for r in theirs]
            outcomes.append(by_region(conn, geoid))
    rows, chunked = outcomes
    assert chunked[:3] == rows[:3]
    assert chunked == rows


@settings(
    max_examples=8, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow]
)
@given(
    child=st.lists(_edit, min_size=1, max_size=4),
    parent=st.lists(_edit, min_size=1, max_size=4),
    solution=st.sampled_from(["child", "parent", "base"]),
)
def test_random_edits_merge_on_chunks_as_on_rows(
    clones: Clones,
    rows_fault: tuple[str, int],
    child: list[tuple[str, int, int]],
    parent: list[tuple[str, int, int]],
    solution: str,
) -> None:
    """Random edits of both sides over several chunks: the regions on chunks are merge3's, and the merge by region
    (every conflicting region solved alike) writes into the chunks what it writes as rows, or refuses alike."""
    merge_on_chunks_as_on_rows(clones, rows_fault[1], child, parent, solution)


@pytest.mark.parametrize("solution", ["child", "parent", "base"])
def test_a_solved_region_keeps_its_solution_across_the_switch(
    clones: Clones, rows_fault: tuple[str, int], solution: str
) -> None:
    """The version moves vertices 0 and 1 once, the parent twice (one conflicting region): its solution, recorded on
    rows, is the region's after the switch, and the merge by region on chunks writes and records what it does on
    rows (the random test's first example with a conflict, seed 289922539507699643256275499697767470906: it expected
    the region `unsolved` after the switch)."""
    merge_on_chunks_as_on_rows(clones, rows_fault[1], [("move", 0, 0)], [("move", 0, 0), ("move", 0, 0)], solution)


def test_revision_indexes_of_a_chunked_table(clones: Clones) -> None:
    """create_revision_indexes leaves a table stored in chunks as it is (its chunk table has its own revision
    indexes): no error for the missing <table>_ver (failed before: relation tgsis.trgl_ver does not exist)."""
    conn = clones.new()
    switch_to_chunks(conn)
    indexes = "SELECT indexrelid::regclass::text FROM pg_index WHERE indrelid = 'tgsis.trgl_chunk'::regclass ORDER BY 1"
    before = conn.execute(indexes).fetchall()
    assert len(before) == 3  # the key, the BRIN on revision, the object key of closed chunk versions
    conn.execute("SELECT tgsis.create_revision_indexes('tgsis', 'trgl', 'geoid')")
    assert conn.execute(indexes).fetchall() == before
    conn.rollback()


def test_a_manual_solution_merges_into_chunks_as_into_rows(clones: Clones, rows_fault: tuple[str, int]) -> None:
    """A manual mesh (recorded with its rows by the Python resolve_region, on rows) that moves the conflicting
    region's vertices and one vertex of the region no side changed (a corner of a triangle the version removed):
    the SQL merge reads the base's rows under the solution from the chunks that hold them and writes what it
    writes on rows."""
    geoid = rows_fault[1]
    removed = 11 * (SIDE - 1) + 11  # triangle (451, 452, 492), next to the middle both sides moved
    outcomes = []
    for chunks in (False, True):
        conn = clones.new()
        three_sides(conn, geoid)
        with tgsis.in_version(conn, "e1"):
            conn.execute("DELETE FROM tgsis.trgl WHERE geoid = %s AND trglid = %s", (geoid, removed))
        conn.commit()
        tgsis.find_conflicts(conn, "e1")
        conn.commit()
        merge = tgsis.object_merge(conn, "e1", geoid)
        conn.rollback()
        (region,) = merge.conflicts
        untouched = np.setdiff1d(region.vertex_ids, np.union1d(region.parent_vertex_ids, region.child_vertex_ids))
        assert 452 in untouched.tolist()
        child = merge.child
        xyz = child.vertices.copy()
        xyz[np.isin(child.vertex_ids, np.append(MIDDLE, 452)), 2] += 0.25
        manual = MeshState(
            child.cell_size,
            child.vertex_ids,
            xyz,
            child.cell_ids,
            child.cells,
            child.vertex_properties,
            child.cell_properties,
        )
        tgsis.resolve_region(conn, "e1", geoid, region.index, "manual", manual)
        conn.commit()
        if chunks:
            switch_to_chunks(conn)
        outcomes.append(by_region(conn, geoid))
    rows, chunked = outcomes
    assert rows[0] == "done", rows
    assert chunked == rows


def test_a_solution_made_stale_before_the_switch_stays_stale(clones: Clones, rows_fault: tuple[str, int]) -> None:
    """The parent moves the solved region's vertices again before the switch: the switch renews only the marks that
    are still the objects', so on chunks as on rows the region is found again `unsolved` and the merge by region
    refuses it alike (TG302), nothing written."""
    geoid = rows_fault[1]
    outcomes = []
    for chunks in (False, True):
        conn = clones.new()
        apply_edits(conn, "e1", geoid, [("move", 0, 0)])
        apply_edits(conn, "DEFAULT", geoid, [("move", 0, 0), ("move", 0, 0)])
        conn.execute("SELECT FROM tgsis.find_conflicts('e1')")
        conn.commit()
        conn.execute(
            "SELECT tgsis.resolve_region('e1', 'feature', %s, region, 'child') FROM tgsis.conflict_regions"
            " WHERE versionid = tgsis.version_id('e1') AND conflict",
            (str(geoid),),
        )
        conn.commit()
        assert [r["solution"] for r in sql_regions(conn, "e1", geoid)] == ["child"]
        apply_edits(conn, "DEFAULT", geoid, [("move", 0, 2)])  # the parent changes the region again
        if chunks:
            switch_to_chunks(conn)
        regions = sql_regions(conn, "e1", geoid)
        assert [(r["vertex_ids"], r["solution"]) for r in regions] == [([0, 1, 40, 41], "unsolved")]
        outcomes.append(by_region(conn, geoid))
    rows, chunked = outcomes
    assert rows[:2] == ("refused", "TG302"), rows
    assert chunked == rows
