"""A session idle after it wrote through a face blocks no change of the face (issue 40, plan L, W1).

docs/storage.md, "The relational face over chunks": the face's work tables (``pg_temp.tgsis_face_rows_*``,
``_dels_*``, ``_queue_*``, ``_now_*``, of the face's row type) are ``ON COMMIT DROP``, made by each transaction
that writes through the face. A session that wrote, committed and stays connected holds nothing of the face's
row type, so ``add_property``, ``rename_property``, ``drop_property`` (``tgsis.alter_chunk_table``), the way
back into rows and into chunks again go through at once (under a ``lock_timeout``, so a wait fails here rather
than hangs); before, each was refused (``TG202``/``2BP01`` naming the idle session's tables) until it
disconnected. A session inside an open transaction that wrote is still waited for. A transaction writes the
face after a ``ROLLBACK TO`` that dropped its tables, in two statements and twice in one statement; a
transaction that wrote through a face still cannot be ``PREPARE``d.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import psycopg
import pytest

import tgsis
from tests.merge_data import curved_surface, sqlstate
from tests.sessions import connect
from tests.storage_data import classes_as_rows
from tgsis.db import features as F
from tgsis.mesh import Surface

Conn = psycopg.Connection[Any]


@pytest.fixture(autouse=True)
def _classes_as_rows(db_dsn: str) -> None:
    """The classes these tests make start as rows: they switch them to chunks themselves, or compare with a rows
    twin (docs/storage.md, "Property chunks by default: the rule")."""
    classes_as_rows(db_dsn)


#: the face's work tables the session holds (its sequence, which depends on nothing, left out)
WORK_TABLES = (
    "SELECT count(*) FROM pg_class WHERE relnamespace = pg_my_temp_schema() AND relname LIKE 'tgsis\\_face\\_%' "
    "AND relkind = 'r'"
)


def _layer(conn: Conn, name: str) -> int:
    surface = curved_surface()
    tgsis.create_feature_class(
        conn, name, "SURFACE", cell_properties=[("p_i4", "integer"), ("p_f8", "double precision")]
    )
    n = surface.n_vertices
    values: dict[str, Any] = {"p_i4": np.arange(n, dtype=np.int32), "p_f8": np.linspace(-1.0, 1.0, n)}
    geoid = F.insert_feature(conn, name, Surface(surface.vertices, surface.cells, vertex_properties=values))
    conn.execute("SELECT tgsis.store_class_in_chunks(%s)", (name,))
    conn.commit()
    return geoid


def _admin(conn: Conn, statement: str, args: tuple[Any, ...] = ()) -> None:
    """Run ``statement`` and commit; a lock wait longer than a second fails (55P03) instead of hanging."""
    conn.execute("SET lock_timeout = '1s'")
    state, message = sqlstate(conn, statement, args)
    assert state is None, f"{statement}: {state} {message}"
    conn.commit()


def test_a_session_idle_after_writing_a_class_face_blocks_no_change_of_the_class(db_dsn: str, conn: Conn) -> None:
    geoid = _layer(conn, "idle")
    idle = connect(db_dsn, "idle")
    update = "UPDATE public.idle_cellpros SET p_i4 = %s WHERE _geoid = %s AND _idx = 0"
    assert idle.execute(update, (-1, geoid)).rowcount == 1
    assert idle.execute(WORK_TABLES).fetchone() != (0,)  # made by the writing transaction
    idle.commit()
    assert idle.execute(WORK_TABLES).fetchone() == (0,)  # and gone with it
    idle.rollback()
    # the session stays connected, idle: every change of the face goes through at once
    _admin(conn, "SELECT tgsis.add_property('idle', 'cell', '[\"p_new\", \"integer\"]', '5')")
    _admin(conn, "SELECT tgsis.rename_property('idle', 'p_new', 'p_renamed')")
    _admin(conn, "SELECT tgsis.drop_property('idle', 'p_renamed', p_force => true)")
    _admin(conn, "SELECT tgsis.store_class_in_rows('idle')")
    _admin(conn, "SELECT tgsis.store_class_in_chunks('idle')")
    # the idle session writes the new face again (its work tables made again), in two statements of one transaction
    assert idle.execute(update, (-2, geoid)).rowcount == 1
    assert (
        idle.execute(
            "UPDATE public.idle_cellpros SET p_f8 = '-0'::float8 WHERE _geoid = %s AND _idx = 1", (geoid,)
        ).rowcount
        == 1
    )
    idle.commit()
    _admin(conn, "SELECT tgsis.add_property('idle', 'cell', '[\"p_last\", \"integer\"]', '7')")
    row = conn.execute(
        "SELECT p_i4, (SELECT p_f8::text FROM public.idle_cellpros WHERE _geoid = %s AND _idx = 1), p_last "
        "FROM public.idle_cellpros WHERE _geoid = %s AND _idx = 0",
        (geoid, geoid),
    ).fetchone()
    assert row == (-2, "-0", 7)
    idle.close()


def test_a_session_inside_a_transaction_that_wrote_is_still_waited_for(db_dsn: str, conn: Conn) -> None:
    geoid = _layer(conn, "busy")
    writer = connect(db_dsn, "writer")
    assert (
        writer.execute("UPDATE public.busy_cellpros SET p_i4 = 9 WHERE _geoid = %s AND _idx = 3", (geoid,)).rowcount
        == 1
    )
    conn.execute("SET lock_timeout = '300ms'")
    for statement in (
        "SELECT tgsis.add_property('busy', 'cell', '[\"p_new\", \"integer\"]', '5')",
        "SELECT tgsis.store_class_in_rows('busy')",
    ):
        state, message = sqlstate(conn, statement)
        assert state == "55P03", f"{statement}: {state} {message}"  # it waits for the open writer
    writer.commit()
    _admin(conn, "SELECT tgsis.add_property('busy', 'cell', '[\"p_new\", \"integer\"]', '5')")
    assert conn.execute(
        "SELECT p_i4, p_new FROM public.busy_cellpros WHERE _geoid = %s AND _idx = 3", (geoid,)
    ).fetchone() == (9, 5)
    writer.close()


@pytest.mark.storage("chunks")
def test_a_session_idle_after_writing_vrtx_blocks_neither_way_of_the_switch(
    db_dsn: str, conn: Conn, fault_clone: int
) -> None:
    idle = connect(db_dsn, "idle")
    update = "UPDATE tgsis.vrtx SET z = %s WHERE geoid = %s AND vrtxid = 0"
    assert idle.execute(update, (1234.5, fault_clone)).rowcount == 1
    idle.commit()
    _admin(conn, "SELECT tgsis.store_in_rows('vrtx')")
    assert conn.execute("SELECT tgsis.stored_in_chunks('vrtx')").fetchone() == (False,)
    conn.commit()
    _admin(conn, "SELECT tgsis.store_in_chunks('vrtx')")
    assert idle.execute(update, (2345.5, fault_clone)).rowcount == 1
    idle.commit()
    _admin(conn, "SELECT tgsis.store_in_rows('vrtx')")
    assert conn.execute("SELECT z FROM tgsis.vrtx WHERE geoid = %s AND vrtxid = 0", (fault_clone,)).fetchone() == (
        2345.5,
    )
    idle.close()


def test_a_transaction_writes_the_face_after_rolling_its_work_tables_back_and_twice_in_one_statement(
    conn: Conn,
) -> None:
    geoid = _layer(conn, "again")
    update = "UPDATE public.again_cellpros SET p_i4 = %s WHERE _geoid = %s AND _idx = %s"
    conn.execute("SAVEPOINT a")
    assert conn.execute(update, (100, geoid, 0)).rowcount == 1  # the work tables made inside the savepoint
    conn.execute("ROLLBACK TO SAVEPOINT a")
    assert conn.execute(WORK_TABLES).fetchone() == (0,)  # and rolled back with it
    assert conn.execute(update, (101, geoid, 1)).rowcount == 1  # made again
    conn.execute("SAVEPOINT b")
    assert conn.execute(update, (102, geoid, 2)).rowcount == 1
    conn.execute("ROLLBACK TO SAVEPOINT b")  # the tables, made before b, stay; b's row is gone
    conn.execute(
        "DO $$ BEGIN "
        f"UPDATE public.again_cellpros SET p_i4 = 103 WHERE _geoid = {geoid} AND _idx = 3; "
        f"UPDATE public.again_cellpros SET p_i4 = 104 WHERE _geoid = {geoid} AND _idx = 4; "
        "END $$"
    )
    conn.commit()
    assert conn.execute(WORK_TABLES).fetchone() == (0,)
    rows = conn.execute(
        "SELECT _idx, p_i4 FROM public.again_cellpros WHERE _geoid = %s AND _idx < 5 ORDER BY 1", (geoid,)
    ).fetchall()
    assert rows == [(0, 0), (1, 101), (2, 2), (3, 103), (4, 104)]
    conn.rollback()
    # two-phase commit refuses a transaction that wrote through the face, as before: nothing written
    assert conn.execute(update, (105, geoid, 5)).rowcount == 1
    with pytest.raises(psycopg.errors.FeatureNotSupported, match="temporary objects"):
        conn.execute("PREPARE TRANSACTION 'tgsis_face_w1'")
    conn.rollback()
    assert conn.execute(
        "SELECT p_i4 FROM public.again_cellpros WHERE _geoid = %s AND _idx = 5", (geoid,)
    ).fetchone() == (5,)
