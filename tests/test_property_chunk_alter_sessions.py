"""add/rename/drop property on a versioned class in chunks while another version's session writes (plan G, X2).

``tgsis.alter_chunk_table`` locks the face and the chunk table ACCESS EXCLUSIVE and adds an array without a
rewrite of the chunk table (an UPDATE fills it). Another session writing properties through the face in another
version must
lose no write: it waits for the alter (or the alter for it), or gets a clear error, never a write that
silently did nothing.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
import psycopg
import pytest

import tgsis
from tests.merge_data import curved_surface, sqlstate
from tests.sessions import Background, connect, wait_until_blocked
from tests.storage_data import classes_as_rows
from tgsis.db import features as F
from tgsis.mesh import Surface

Conn = psycopg.Connection[Any]


@pytest.fixture(autouse=True)
def _classes_as_rows(db_dsn: str) -> None:
    """The classes these tests make start as rows: they switch them to chunks themselves, or compare with a rows
    twin (docs/storage.md, "Property chunks by default: the rule")."""
    classes_as_rows(db_dsn)


ALTERS = {
    "add": "SELECT tgsis.add_property('layer', 'cell', '[\"grade\", \"smallint\"]', '9')",
    "rename": "SELECT tgsis.rename_property('layer', 'facies', 'rock')",
    "drop": "SELECT tgsis.drop_property('layer', 'facies', p_kind => 'cell', p_force => true)",
}


def _versioned_in_chunks(conn: Conn) -> int:
    surface = curved_surface()
    n = surface.n_vertices
    tgsis.create_feature_class(
        conn, "layer", "SURFACE", cell_properties=[("porosity", "double precision"), ("facies", "integer")]
    )
    tgsis.enable_feature_versioning(conn)
    props: dict[str, Any] = {"porosity": np.linspace(0, 1, n), "facies": np.arange(n, dtype=np.int32) % 7}
    geoid = F.insert_feature(conn, "layer", Surface(surface.vertices, surface.cells, vertex_properties=props))
    tgsis.create_version(conn, "e2")
    conn.commit()
    conn.execute("SELECT tgsis.store_class_in_chunks('layer')")
    conn.commit()
    return geoid


def _porosity(conn: Conn, version: str, geoid: int, idx: int) -> Any:
    with tgsis.in_version(conn, version):
        row = conn.execute(
            "SELECT porosity FROM public.layer_cellpros WHERE _geoid = %s AND _idx = %s", (geoid, idx)
        ).fetchone()
    conn.commit()
    return row


@pytest.mark.parametrize("alter", sorted(ALTERS))
def test_a_write_in_another_version_waits_for_the_alter_and_is_kept(db_dsn: str, conn: Conn, alter: str) -> None:
    geoid = _versioned_in_chunks(conn)
    conn.execute(ALTERS[alter])  # not committed: the face and the chunk table locked

    def write(session: Conn) -> Any:
        cur = session.execute(
            "UPDATE public.layer_cellpros SET porosity = 5.0 WHERE _geoid = %s AND _idx = 0", (geoid,)
        )
        return cur.rowcount

    writer = Background(db_dsn, "writer", write, version="e2")
    observer = connect(db_dsn, "observer")
    wait_until_blocked(observer, writer.pid, conn.info.backend_pid)
    conn.commit()
    assert writer.finish() == 1
    observer.close()
    assert _porosity(conn, "e2", geoid, 0) == (5.0,)
    assert _porosity(conn, "DEFAULT", geoid, 0) == (0.0,)


WRITES = {
    "update": "UPDATE public.layer_cellpros SET porosity = 5.0 WHERE _geoid = %s AND _idx = 0",
    "delete": "DELETE FROM public.layer_cellpros WHERE _geoid = %s AND _idx = 0",
}


@pytest.mark.parametrize("write", sorted(WRITES))
@pytest.mark.parametrize("alter", sorted(ALTERS))
def test_a_repeatable_read_writer_whose_snapshot_predates_the_alter_loses_nothing(
    db_dsn: str, conn: Conn, alter: str, write: str
) -> None:
    """A rewrite of the chunk table is not MVCC-safe: an older snapshot sees it empty. The write must not
    silently change nothing: it is written, or refused with an error (40001 after an add, which rewrites)."""
    geoid = _versioned_in_chunks(conn)
    n = curved_surface().n_vertices
    writer = connect(db_dsn, "writer")
    tgsis.goto_version(writer, "e2")
    writer.commit()
    writer.execute("SET TRANSACTION ISOLATION LEVEL REPEATABLE READ")
    writer.execute("SELECT 1")  # the snapshot, before the alter (no lock on the class's tables)
    conn.execute(ALTERS[alter])
    conn.commit()
    state, message = None, ""
    try:
        count = writer.execute(WRITES[write], (geoid,)).rowcount
        writer.commit()
    except psycopg.Error as exc:
        writer.rollback()
        state, message = exc.sqlstate, str(exc)
    writer.close()
    if alter == "add":
        assert state == "40001", message
    if state is not None:
        assert _porosity(conn, "e2", geoid, 0) == (0.0,)
    else:
        assert count == 1
        assert _porosity(conn, "e2", geoid, 0) == ((5.0,) if write == "update" else None)
    assert _porosity(conn, "DEFAULT", geoid, 0) == (0.0,)
    assert conn.execute("SELECT count(*) FROM public.layer_cellpros").fetchone() == (n,)


def test_an_uncommitted_write_in_another_version_is_waited_for(db_dsn: str, conn: Conn) -> None:
    geoid = _versioned_in_chunks(conn)
    writer = connect(db_dsn, "writer")
    tgsis.goto_version(writer, "e2")
    writer.commit()
    writer.execute("UPDATE public.layer_cellpros SET porosity = 5.0 WHERE _geoid = %s AND _idx = 0", (geoid,))

    def adder(session: Conn) -> Any:
        return sqlstate(session, ALTERS["add"])

    background = Background(db_dsn, "adder", adder)
    wait_until_blocked(conn, background.pid, writer.info.backend_pid)
    writer.commit()
    state, message = background.finish()
    # the writer's session is still open, idle: its work tables of the face's row type went with its transaction
    # (ON COMMIT DROP), so the add waited for the write only, and then went through
    assert state is None, message
    writer.close()
    assert _porosity(conn, "e2", geoid, 0) == (5.0,)
    with tgsis.in_version(conn, "e2"):
        assert conn.execute(
            "SELECT grade FROM public.layer_cellpros WHERE _geoid = %s AND _idx = 0", (geoid,)
        ).fetchone() == (9,)
    conn.commit()


def _old_snapshot(db_dsn: str, version: str | None = None) -> Conn:
    """A REPEATABLE READ session whose snapshot is taken now, before what the test does next (no lock taken)."""
    reader = connect(db_dsn, "reader")
    if version is not None:
        tgsis.goto_version(reader, version)
        reader.commit()
    reader.execute("SET TRANSACTION ISOLATION LEVEL REPEATABLE READ")
    reader.execute("SELECT 1")
    return reader


def _read_or_state(reader: Conn, read: Callable[[Conn], Any]) -> tuple[Any, str | None]:
    """What ``read(reader)`` gives, or the SQLSTATE it raised (the reader's transaction rolled back)."""
    try:
        return read(reader), None
    except psycopg.Error as exc:
        reader.rollback()
        return None, exc.sqlstate
    except tgsis.errors.Error as exc:
        reader.rollback()
        return None, exc.sqlstate or type(exc).__name__


def _fetched_porosity(reader: Conn, geoid: int) -> tuple[int, float]:
    """The Python read of the feature (tgsis.fetch_feature: the chunks read directly): (vertices, sum of porosity)."""
    mesh = F.fetch_feature(reader, "layer", geoid).mesh
    assert isinstance(mesh, Surface)
    porosity = mesh.vertex_properties["porosity"]
    return len(porosity), float(np.sum(porosity))


READS: dict[str, Callable[[Conn, int], Any]] = {
    "face": lambda reader, geoid: reader.execute(
        "SELECT count(*), sum(porosity) FROM public.layer_cellpros WHERE _geoid = %s", (geoid,)
    ).fetchone(),
    "chunk view": lambda reader, geoid: reader.execute(
        "SELECT count(*), sum(porosity) FROM public.layer_cellpros_chunk_rows WHERE _geoid = %s AND NOT revclosed",
        (geoid,),
    ).fetchone(),
    "python": lambda reader, geoid: _fetched_porosity(reader, geoid),
}


@pytest.mark.parametrize("read", sorted(READS))
@pytest.mark.parametrize("alter", sorted(ALTERS))
def test_a_repeatable_read_reader_whose_snapshot_predates_the_alter_reads_the_rows(
    db_dsn: str, conn: Conn, alter: str, read: str
) -> None:
    """An older snapshot's read gives the rows, never an empty set (plan G, A; plan H). An add rewrote the chunk
    table, which that snapshot saw EMPTY; it now adds the array without a rewrite and fills it by an UPDATE
    (MVCC): the rows are read. A rename or a drop rewrites nothing: the rows are read."""
    geoid = _versioned_in_chunks(conn)
    n = curved_surface().n_vertices
    expected = (n, float(np.sum(np.linspace(0, 1, n))))
    reader = _old_snapshot(db_dsn)
    conn.execute(ALTERS[alter])
    conn.commit()
    got, state = _read_or_state(reader, lambda r: READS[read](r, geoid))
    reader.rollback()
    if read == "python" and alter != "add":
        # the class's property list read in the old snapshot still names the renamed or dropped column: an error by name
        # (42703, as on rows), not a silent read
        assert state in (None, "42703"), state
    else:
        assert state is None, state
        assert got[0] == expected[0] and got[1] == pytest.approx(expected[1])
    # the retry reads the rows
    got, state = _read_or_state(reader, lambda r: READS[read](r, geoid))
    assert state is None, state
    assert got[0] == expected[0] and got[1] == pytest.approx(expected[1])
    reader.close()


def test_a_read_committed_reader_and_the_adders_own_reads_are_not_refused(db_dsn: str, conn: Conn) -> None:
    geoid = _versioned_in_chunks(conn)
    n = curved_surface().n_vertices
    reader = connect(db_dsn, "reader", autocommit=True)  # READ COMMITTED, no transaction left open between reads
    assert reader.execute("SELECT count(*) FROM public.layer_cellpros WHERE _geoid = %s", (geoid,)).fetchone() == (n,)
    conn.execute(ALTERS["add"])
    # the adder's own transaction reads its filled table
    assert conn.execute(
        "SELECT count(*), min(grade) FROM public.layer_cellpros WHERE _geoid = %s", (geoid,)
    ).fetchone() == (n, 9)
    conn.commit()
    # READ COMMITTED: the next statement's snapshot is newer than the add
    assert reader.execute(
        "SELECT count(*), min(grade) FROM public.layer_cellpros WHERE _geoid = %s", (geoid,)
    ).fetchone() == (n, 9)
    reader.close()
