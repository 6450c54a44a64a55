"""Readers of chunk tables outside the faces and chunk views, under a snapshot older than a change of storage (plan I, A2).

docs/storage.md, "Snapshots older than a change of storage": besides the faces, the chunk views and model 1's
download, the readers of chunk tables are (1) model 2's Python readers (``fetch_series``, ``get_at``,
``surfaces_at``: ``tgsis.db._chunk_transfer.instant_layout`` / ``instant_rows``, whose statements carry
``tgsis.chunk_snapshot_guard``), and (2) the merges' and check-in's SQL (``tgsis.mesh_merge_work``,
``tgsis.storage_rows``, ``tgsis.check_unchanged``, ...), which run only under READ COMMITTED
(``tgsis.require_read_committed``, TG300 otherwise) after their locks: each statement's snapshot is newer than
any switch it could meet. Each family is tested here with a REPEATABLE READ snapshot taken before another
session's switch committed: the rows, 40001 (retry), or the merge refused (TG300), never an empty read.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
import psycopg
import pytest

import tgsis
from tests.merge_data import curved_surface, make_fault, move
from tests.sessions import connect
from tgsis.temporal import SurfaceSeries

Conn = psycopg.Connection[Any]

TIME_TABLES = ("times_vrtx", "times_trgl")
TIMES = (0.0, 1.0, 2.0)


def _old_snapshot(db_dsn: str) -> Conn:
    reader = connect(db_dsn, "reader")
    reader.execute("SET TRANSACTION ISOLATION LEVEL REPEATABLE READ")
    reader.execute("SELECT count(*) FROM pg_catalog.pg_namespace")
    return reader


def _series(conn: Conn) -> tuple[int, int]:
    """A model-2 series of three instants, its time tables as rows: (geoid, vertices per instant)."""
    for table in reversed(TIME_TABLES):
        if conn.execute("SELECT tgsis.stored_in_chunks(%s)", (table,)).fetchone() == (True,):
            conn.execute("SELECT tgsis.store_in_rows(%s)", (table,))
    tgsis.create_feature_class(conn, "horizons", "SURFACE", time_model="INSTANTS")
    s = curved_surface()
    surfaces = [tgsis.Surface(s.vertices + i / 3.0, s.cells) for i in range(len(TIMES))]
    geoid = tgsis.insert_feature(conn, "horizons", SurfaceSeries(np.asarray(TIMES), surfaces))
    conn.commit()
    return geoid, s.n_vertices


def _model2_reads(reader: Conn, geoid: int) -> dict[str, Callable[[], int]]:
    """Vertices read by each model-2 Python reader (0 for nothing)."""

    def series() -> int:
        return sum(s.n_vertices for s in tgsis.fetch_series(reader, "horizons", geoid).surfaces)

    def at() -> int:
        surface = tgsis.get_at(reader, geoid, 1.0)
        return 0 if surface is None else surface.n_vertices

    def surfaces_at() -> int:
        return sum(s.n_vertices for g, s in tgsis.surfaces_at(reader, "horizons", 1.0).items() if g == geoid)

    return {"fetch_series": series, "get_at": at, "surfaces_at": surfaces_at}


@pytest.mark.parametrize("read", ["fetch_series", "get_at", "surfaces_at"])
def test_model2_python_readers_under_an_older_snapshot_read_or_refuse_never_empty(
    db_dsn: str, conn: Conn, read: str
) -> None:
    geoid, n = _series(conn)
    expected = {"fetch_series": n * len(TIMES), "get_at": n, "surfaces_at": n}[read]
    reader = _old_snapshot(db_dsn)
    for table in TIME_TABLES:
        conn.execute("SELECT tgsis.store_in_chunks(%s)", (table,))
    conn.commit()
    reads = _model2_reads(reader, geoid)
    try:
        got: Any = reads[read]()
    except (psycopg.Error, tgsis.errors.Error) as exc:
        reader.rollback()
        got = exc.sqlstate
        assert got == "40001", exc
        got = reads[read]()  # the retry
    assert got == expected
    # and the way back is refused while a snapshot older than it is held (TG202), that snapshot reading the chunks
    reader.rollback()
    reader.execute("SET TRANSACTION ISOLATION LEVEL REPEATABLE READ")
    assert reads[read]() == expected
    with pytest.raises(psycopg.Error) as refused:
        conn.execute("SELECT tgsis.store_in_rows('times_trgl')")
    assert refused.value.sqlstate == "TG202"
    conn.rollback()
    assert reads[read]() == expected
    reader.close()


@pytest.mark.parametrize("call", ["merge_version", "refresh_version", "find_conflicts"])
def test_merges_under_an_older_snapshot_are_refused_not_run_on_an_empty_table(
    db_dsn: str, conn: Conn, call: str
) -> None:
    """The merges' SQL reads the storage directly (tgsis.mesh_merge_work, tgsis.storage_rows): only under READ
    COMMITTED, each statement after the switch it waited for. A REPEATABLE READ snapshot older than a switch
    into chunks is refused by name (TG300) before reading anything; under READ COMMITTED the merge reads the
    chunks the switch wrote."""
    if conn.execute("SELECT tgsis.stored_in_chunks('vrtx')").fetchone() == (True,):
        pytest.skip("the switch into chunks is the point: model 1 as rows (TGSIS_TEST_STORAGE=rows)")
    geoid = make_fault(conn)
    move(conn, "DEFAULT", geoid, [3, 4], (0.0, 0.0, 2.5))
    move(conn, "e1", geoid, [100], (0.0, 0.0, -1.5))
    conn.commit()
    reader = _old_snapshot(db_dsn)
    conn.execute("SELECT tgsis.store_in_chunks('vrtx')")
    conn.commit()
    with pytest.raises(psycopg.Error) as refused:
        reader.execute(f"SELECT tgsis.{call}('e1')")
    # merge and refresh: READ COMMITTED only (TG300); find_conflicts, under any isolation: 40001 (was TG100, the new
    # storage's key column "missing" to the snapshot: tgsis.check_key_type asks tgsis.chunk_snapshot_guard first)
    assert refused.value.sqlstate == ("40001" if call == "find_conflicts" else "TG300"), refused.value
    reader.rollback()
    reader.close()
    conn.execute(f"SELECT tgsis.{call}('e1')")  # READ COMMITTED, after the switch: it runs on the chunks
    conn.commit()
    if call != "find_conflicts":
        with tgsis.in_version(conn, "e1" if call == "refresh_version" else "DEFAULT"):
            row = conn.execute(
                "SELECT count(*) FILTER (WHERE vrtxid IN (3, 4, 100)) FROM tgsis.vrtx WHERE geoid = %s", (geoid,)
            ).fetchone()
        conn.rollback()
        assert row == (3,)
