"""The SQL merge by region of a mesh whose parts are runs (``tgsis.part``) reads the changed spans only (issue 40).

A class without a cell property ``part`` keeps the parts of its features as
runs of cell ids in ``tgsis.part``; a check-in that changes a part rewrites
every run of the object. ``tgsis.mesh_merge_work`` took every cell of every run
some state saw otherwise for a changed key, reading every cell version of the
object (on chunks: every chunk version decoded), and ``tgsis.merge_mesh_by_region``
rebuilt the version's runs from every cell of the version. Now the changed keys
are the cells of the id spans whose part differs between the states, read from
the chunks holding those spans, and the merge rebuilds the runs only when the
cells it writes change their part. The states are built on rows and the merge
runs on a copy of them on rows and on another copy switched to chunks: the
regions and the written mesh and runs are the same, and on chunks the work
holds and reads only the changed spans (counted in ``pg_stat_xact_user_tables``
and in the work table ``tgsis_mr_c``).
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from typing import Any

import numpy as np
import psycopg
import pytest

import tgsis
from tests.merge_data import curved_surface, move
from tgsis.db import features as F
from tgsis.testing import TestServer

Conn = psycopg.Connection[Any]

SIDE = 64  # 4,096 vertices (chunks 0 to 3), 7,938 triangles (chunks 0 to 7)
N_CELLS = 2 * (SIDE - 1) ** 2
HALF = N_CELLS // 2
CHUNKED = (
    "SELECT tgsis.store_in_chunks(tablename) FROM tgsis.model_tables WHERE chunkcolumn IS NOT NULL"
    " ORDER BY model, iudorder, tablename"
)


@pytest.fixture(scope="module")
def rows_fault(pg: TestServer) -> Iterator[tuple[str, int]]:
    """(database, geoid): tgsis on rows, the curved grid with two parts (runs) in class faults, version e1."""
    with pg.database("tgsis_g_runs") as (name, dsn):
        with psycopg.connect(dsn) as conn:
            tgsis.install(conn, method="extension" if pg.extension_files is None else "sql", storage="rows")
            conn.commit()
            F.create_feature_class(conn, "faults", "SURFACE", cell_properties=[("porosity", "float8")])
            tgsis.enable_feature_versioning(conn)
            surface = curved_surface(SIDE)
            parts = np.zeros(surface.n_cells, dtype=np.int64)
            parts[HALF:] = 1
            surface.cell_properties = {"part": parts}
            geoid = F.insert_feature(conn, "faults", surface)
            tgsis.create_version(conn, "e1")
            conn.commit()
            assert conn.execute("SELECT count(*) FROM tgsis.part WHERE geoid = %s", (geoid,)).fetchone() == (2,)
        yield name, geoid


def rewrite_runs(conn: Conn, version: str, geoid: int, runs: list[tuple[int, int, int]]) -> None:
    """Every run of the object rewritten in ``version`` (as a check-in that changes a part writes them), committed."""
    with tgsis.in_version(conn, version):
        conn.execute("DELETE FROM tgsis.part WHERE geoid = %s", (geoid,))
        for first, last, part in runs:
            conn.execute(
                "INSERT INTO tgsis.part (geoid, firstid, lastid, part) VALUES (%s, %s, %s, %s)",
                (geoid, first, last, part),
            )
    conn.commit()


def child_changes_parts(conn: Conn, geoid: int) -> None:
    """e1: cells 10 .. 19 (chunk 0) into part 2, every run rewritten, and vertices of chunk 0 moved; DEFAULT: vertices
    of chunk 3 moved (another region)."""
    rewrite_runs(conn, "e1", geoid, [(0, 9, 0), (10, 19, 2), (20, HALF - 1, 0), (HALF, N_CELLS - 1, 1)])
    move(conn, "e1", geoid, [5 * SIDE + 5, 5 * SIDE + 6], (0.0, 0.0, 2.5))
    conn.commit()
    move(conn, "DEFAULT", geoid, [60 * SIDE + 50, 60 * SIDE + 51], (0.0, 0.0, -1.5))
    conn.commit()


def both_change_parts(conn: Conn, geoid: int) -> None:
    """As above, and DEFAULT moves the last 30 cells into part 3 (chunk 7) and the first 5 into part 4: the merged
    runs are neither side's."""
    child_changes_parts(conn, geoid)
    rewrite_runs(
        conn,
        "DEFAULT",
        geoid,
        [(0, 4, 4), (5, HALF - 1, 0), (HALF, N_CELLS - 31, 1), (N_CELLS - 30, N_CELLS - 1, 3)],
    )


def merged(conn: Conn, geoid: int) -> tuple[Any, ...]:
    """(rows written, e1's vertices, cells and runs) of the SQL merge by region into e1, committed."""
    conn.execute("SELECT tgsis.find_conflicts('e1')")
    conn.commit()
    written = conn.execute("SELECT tgsis.merge_mesh_by_region('e1', 'merge', %s)", (geoid,)).fetchone()
    conn.commit()
    with tgsis.in_version(conn, "e1"):
        vertices = conn.execute(
            "SELECT vrtxid, float8send(x), float8send(y), float8send(z) FROM tgsis.vrtx WHERE geoid = %s ORDER BY 1",
            (geoid,),
        ).fetchall()
        cells = conn.execute(
            "SELECT trglid, vrtxid1, vrtxid2, vrtxid3 FROM tgsis.trgl WHERE geoid = %s ORDER BY 1", (geoid,)
        ).fetchall()
        runs = conn.execute(
            "SELECT firstid, lastid, part FROM tgsis.part WHERE geoid = %s ORDER BY 1", (geoid,)
        ).fetchall()
    conn.rollback()
    return written, vertices, cells, runs


def chunk_reads(conn: Conn) -> int:
    """TOAST tuples of tgsis.trgl_chunk fetched so far in this transaction: each decoded chunk version fetches its
    arrays' (a seq scan's tuple count of the few chunk rows says nothing of what was decoded)."""
    row = conn.execute(
        "SELECT coalesce(s.idx_tup_fetch, 0) FROM pg_stat_xact_all_tables s"
        " WHERE s.relid = (SELECT c.reltoastrelid FROM pg_class c WHERE c.oid = 'tgsis.trgl_chunk'::regclass)"
    ).fetchone()
    return int(row[0]) if row else 0


def moves_only(conn: Conn, geoid: int) -> None:
    """The moves of child_changes_parts, the runs untouched."""
    move(conn, "e1", geoid, [5 * SIDE + 5, 5 * SIDE + 6], (0.0, 0.0, 2.5))
    conn.commit()
    move(conn, "DEFAULT", geoid, [60 * SIDE + 50, 60 * SIDE + 51], (0.0, 0.0, -1.5))
    conn.commit()


def work_reads(conn: Conn, geoid: int) -> tuple[int, Any]:
    """(TOAST tuples of the cell chunks fetched, (distinct ids, largest id) of its cell rows) of mesh_merge_work."""
    before = chunk_reads(conn)
    assert conn.execute("SELECT tgsis.mesh_merge_work('e1', %s)", (geoid,)).fetchone() is not None
    read = chunk_reads(conn) - before
    keys = conn.execute("SELECT count(DISTINCT id), max(id) FROM pg_temp.tgsis_mr_c").fetchone()
    conn.rollback()
    return read, keys


@pytest.mark.parametrize("scenario", [child_changes_parts, both_change_parts])
def test_part_runs_merge_on_chunks_as_on_rows(
    rows_fault: tuple[str, int], make_database: Callable[..., str], scenario: Callable[[Conn, int], None]
) -> None:
    template, geoid = rows_fault
    with psycopg.connect(make_database(template)) as built:
        scenario(built, geoid)
        built.commit()
        states = built.info.dbname
    with psycopg.connect(make_database(states)) as rows, psycopg.connect(make_database(states)) as chunks:
        expected = merged(rows, geoid)
        chunks.execute(CHUNKED)
        chunks.commit()
        assert chunks.execute("SELECT tgsis.stored_in_chunks('trgl')").fetchone() == (True,)
        got = merged(chunks, geoid)
    assert got == expected
    written, _, _, runs = got
    assert written[0] is not None and written[0] > 0
    if scenario is child_changes_parts:  # the child's runs kept: the merge did not rewrite them
        assert runs == [(0, 9, 0), (10, 19, 2), (20, HALF - 1, 0), (HALF, N_CELLS - 1, 1)]
    else:  # the parent's runs outside the child's region, the child's inside
        assert runs == [
            (0, 4, 4),
            (5, 9, 0),
            (10, 19, 2),
            (20, HALF - 1, 0),
            (HALF, N_CELLS - 31, 1),
            (N_CELLS - 30, N_CELLS - 1, 3),
        ]


def test_part_runs_work_reads_the_changed_spans_only(
    rows_fault: tuple[str, int], make_database: Callable[..., str]
) -> None:
    """Every run rewritten by the child, one of them changed: the work's cells are those of the changed span and
    of the moved vertices (not the object's 7,938), and the cell chunks it decodes beyond those of the same moves
    without a part change are the changed span's (chunk 0), not the object's."""
    template, geoid = rows_fault
    reads = {}
    for scenario in (moves_only, child_changes_parts):
        with psycopg.connect(make_database(template)) as conn:
            scenario(conn, geoid)
            conn.execute(CHUNKED)
            conn.commit()
            reads[scenario.__name__] = work_reads(conn, geoid)
            if scenario is child_changes_parts:
                before = chunk_reads(conn)
                whole = conn.execute("SELECT count(*) FROM tgsis.trgl_chunk_rows WHERE geoid = %s", (geoid,)).fetchone()
                assert whole == (N_CELLS,)
                whole_reads = chunk_reads(conn) - before
                conn.rollback()
    read, keys = reads["child_changes_parts"]
    # the span of cells 10 .. 19 and the cells on the moved vertices: a few dozen, not the object's cells
    assert keys is not None and keys[0] < 100, keys
    assert reads["child_changes_parts"][1][0] - reads["moves_only"][1][0] == 10, (reads, keys)
    # one decoding of the object's 8 chunks fetches whole_reads; the part change costs a few decodings of its one
    # chunk (the span's cells, then their rows in the three states: 2 on PostgreSQL 15, 4 on 18 by the plans),
    # where every chunk version of the object was decoded (at least whole_reads more)
    extra = read - reads["moves_only"][0]
    assert whole_reads > 0 and extra < whole_reads, (read, reads, whole_reads)
