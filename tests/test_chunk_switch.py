"""The storage switch of one model table (issue 40): tgsis.store_in_chunks, tgsis.stored_in_chunks, the shape table.

docs/storage.md, "The storage switch": a table's rows move into chunks, its
row storage goes, and ``tgsis.<table>`` becomes the face over the chunks with
the same columns and grants; every version and every saved revision shows the
same rows afterwards, doubles by their bits.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import psycopg
import pytest
from psycopg import sql

import tgsis
from tests.merge_data import MODEL1_COLUMNS, every_view, sqlstate, varied_history
from tests.roles import login_roles
from tgsis.testing import TestServer

Conn = psycopg.Connection[Any]

# the chunk foundation: builds chunk tables beside the row tables, or switches them (docs/testing.md, the mark storage)
pytestmark = pytest.mark.storage("rows")

MODEL1 = MODEL1_COLUMNS


def _face_rows(conn: Conn, table: str) -> list[tuple[Any, ...]]:
    """What ``tgsis.<table>`` shows the session, in key order, doubles as their bits."""
    ident, values = MODEL1[table]
    columns = [sql.SQL("geoid"), sql.Identifier(ident)] + [
        sql.SQL("float8send({})").format(sql.Identifier(v)) if table == "vrtx" else sql.Identifier(v) for v in values
    ]
    query = sql.SQL("SELECT {} FROM tgsis.{} ORDER BY 1, 2").format(sql.SQL(", ").join(columns), sql.Identifier(table))
    return [tuple(r) for r in conn.execute(query).fetchall()]


def _everything_seen(conn: Conn) -> dict[tuple[str, int | None, str], list[tuple[Any, ...]]]:
    """The rows of every model-1 table under every working set and every revision (SET LOCAL: nothing committed)."""
    seen = {}
    for version, revision in every_view(conn):
        if revision is None:
            conn.execute("SELECT tgsis.goto_version(%s, true)", (version,))
        else:
            conn.execute("SELECT tgsis.goto_revision(%s, %s, true)", (version, revision))
        for table in MODEL1:
            seen[(version, revision, table)] = _face_rows(conn, table)
    conn.execute("SELECT tgsis.goto_version('DEFAULT', true)")
    return seen


def _grants(conn: Conn, table: str) -> set[tuple[str, str]]:
    rows = conn.execute(
        "SELECT a.privilege_type, CASE WHEN a.grantee = 0 THEN 'PUBLIC' ELSE pg_get_userbyid(a.grantee) END "
        "FROM pg_class c, aclexplode(c.relacl) a WHERE c.oid = format('tgsis.%%I', %s::text)::regclass "
        "AND a.grantee <> c.relowner",
        (table,),
    ).fetchall()
    return {(str(r[0]), str(r[1])) for r in rows}


def _switch_all(conn: Conn) -> dict[str, int]:
    return {t: int((conn.execute("SELECT tgsis.store_in_chunks(%s)", (t,)).fetchone() or (0,))[0]) for t in MODEL1}


def test_a_versioned_history_is_seen_the_same_by_every_version_and_revision_after_the_switch(
    conn: Conn, fault_clone: int
) -> None:
    varied_history(conn, fault_clone)
    before = _everything_seen(conn)
    assert sum(len(rows) for rows in before.values()) > 1000 and len(before) >= 10 * len(MODEL1)
    grants = {t: _grants(conn, t) for t in MODEL1}
    assert grants["vrtx"]  # the tgsis roles' rights on today's view
    written = _switch_all(conn)
    conn.commit()
    assert written["vrtx"] > 0 and written["trgl"] > 0
    assert _everything_seen(conn) == before
    for table in MODEL1:
        kinds = conn.execute(
            "SELECT (SELECT relkind FROM pg_class WHERE oid = to_regclass(format('tgsis.%%I', t))), "
            "to_regclass(format('tgsis.%%I', t || '_ver')), to_regclass(format('tgsis.%%I', t || '_ver_queue')), "
            "tgsis.storage_table('tgsis', t), tgsis.stored_in_chunks(t) FROM (SELECT %s::text AS t) s",
            (table,),
        ).fetchone()
        assert kinds == ("v", None, None, f"tgsis.{table}_chunk", True), table
        assert _grants(conn, table) == grants[table], table
    # still versioned: registered once, and no runner or write function of the row storage is left
    assert conn.execute(
        "SELECT count(*) FROM tgsis.versioned_tables WHERE schemaname = 'tgsis' AND tablename IN "
        "('vrtx', 'point', 'segment', 'trgl', 'tetra')"
    ).fetchone() == (5,)
    assert conn.execute(
        "SELECT count(*) FROM pg_proc WHERE pronamespace = 'tgsis'::regnamespace AND proname ~ '^(vrtx|trgl)_ver_'"
    ).fetchone() == (0,)


def test_an_unversioned_switch_then_versioning_keeps_each_version_its_own_rows(conn: Conn, fault_clone: int) -> None:
    tgsis.disable_feature_versioning(conn)
    conn.commit()
    before = _face_rows(conn, "vrtx")
    _switch_all(conn)
    conn.commit()
    assert _face_rows(conn, "vrtx") == before
    assert conn.execute("SELECT count(*) FROM tgsis.versioned_tables WHERE tablename = 'vrtx'").fetchone() == (0,)
    assert tgsis.enable_feature_versioning(conn) > 0
    conn.commit()
    registered = conn.execute(
        "SELECT keycolumns, pkeyname, objectkeyfield FROM tgsis.versioned_tables WHERE tablename = 'vrtx'"
    ).fetchone()
    assert registered == (["geoid", "vrtxid"], "vrtx_pkey", "geoid")
    assert _face_rows(conn, "vrtx") == before  # revision 0 is DEFAULT's
    tgsis.create_version(conn, "child")
    conn.commit()
    tgsis.goto_version(conn, "child")
    assert (
        conn.execute("UPDATE tgsis.vrtx SET z = z + 1000 WHERE geoid = %s AND vrtxid < 3", (fault_clone,)).rowcount == 3
    )
    conn.commit()
    moved = _face_rows(conn, "vrtx")
    assert moved != before and len(moved) == len(before)
    tgsis.goto_version(conn, "DEFAULT")
    conn.commit()
    assert _face_rows(conn, "vrtx") == before  # the child's write is the child's
    # the face of a versioned table checks the write right on the version, as today's views do
    assert conn.execute(
        "SELECT count(*) FROM pg_trigger WHERE tgrelid = 'tgsis.vrtx'::regclass AND tgname = 'tgsis_versioning_rights'"
    ).fetchone() == (1,)


def test_the_shape_holds_no_rows_and_nobody_but_the_owner_reaches_it(conn: Conn, fault_clone: int) -> None:
    _switch_all(conn)
    conn.commit()
    state, message = sqlstate(conn, "INSERT INTO tgsis.trgl_shape VALUES (%s, 999999, 0, 1, 2)", (fault_clone,))
    assert state == "23514" and "trgl_shape_holds_no_rows" in message
    # its CHECKs are the row table's: the writer still refuses a degenerate triangle through the face
    state, message = sqlstate(conn, "INSERT INTO tgsis.trgl VALUES (%s, 999999, 0, 0, 2)", (fault_clone,))
    assert state == "23514" and "trgl_distinct_vertices" in message
    assert conn.execute("SELECT count(*) FROM tgsis.trgl_shape").fetchone() == (0,)
    assert _grants(conn, "trgl_shape") == set()
    assert conn.execute(
        "SELECT obj_description('tgsis.vrtx'::regclass) LIKE 'model 1: vertices%%', "
        "col_description('tgsis.vrtx'::regclass, 3) = col_description('tgsis.vrtx_shape'::regclass, 3)"
    ).fetchone() == (True, True)


def test_refusals_change_nothing(conn: Conn, fault_clone: int) -> None:
    state, message = sqlstate(conn, "SELECT tgsis.store_in_chunks('atom')")
    assert state == "TG200" and "atom" in message
    # a view of the user's own over the table: PostgreSQL names it, nothing is switched
    conn.execute("CREATE VIEW public.my_vertices AS SELECT * FROM tgsis.vrtx")
    conn.commit()
    state, message = sqlstate(conn, "SELECT tgsis.store_in_chunks('vrtx')")
    assert state == "2BP01" and "my_vertices" in message
    assert conn.execute(
        "SELECT tgsis.stored_in_chunks('vrtx'), to_regclass('tgsis.vrtx_chunk'), to_regclass('tgsis.vrtx_shape'), "
        "tgsis.storage_table('tgsis', 'vrtx')"
    ).fetchone() == (False, None, None, "tgsis.vrtx_ver")
    conn.execute("DROP VIEW public.my_vertices")
    conn.commit()
    conn.execute("SELECT tgsis.store_in_chunks('vrtx')")
    conn.commit()
    state, message = sqlstate(conn, "SELECT tgsis.store_in_chunks('vrtx')")
    assert state == "TG201" and "stored in chunks already" in message


@pytest.mark.storage("rows")
def test_partitioned_storage_is_switched_into_chunks_partitioned_alike(conn: Conn) -> None:
    """Switching storage the DBA partitioned keeps the partitioning: the chunk table is partitioned the same way."""
    tgsis.partition_model_storage(conn, 1, 4)
    conn.commit()
    conn.execute("SELECT tgsis.store_in_chunks('trgl')")
    conn.commit()
    assert conn.execute(
        "SELECT tgsis.stored_in_chunks('trgl'), c.relkind, (SELECT count(*) FROM pg_inherits i WHERE i.inhparent = c.oid) "
        "FROM pg_class c WHERE c.oid = 'tgsis.trgl_chunk'::regclass"
    ).fetchone() == (True, "p", 4)
    # storage partitioned otherwise (a partition detached: 3 partitions of modulus 4) is refused, nothing changed
    conn.execute("ALTER TABLE tgsis.vrtx DETACH PARTITION tgsis.vrtx_p3")
    conn.commit()
    state, message = sqlstate(conn, "SELECT tgsis.store_in_chunks('vrtx')")
    assert state == "TG100" and "partitioned otherwise" in message, message
    assert conn.execute(
        "SELECT tgsis.stored_in_chunks('vrtx'), to_regclass('tgsis.vrtx_chunk'), "
        "(SELECT relkind FROM pg_class WHERE oid = 'tgsis.vrtx'::regclass)"
    ).fetchone() == (False, None, "p")


@pytest.mark.storage("rows")
def test_storage_in_chunks_is_partitioned_beside_rows(conn: Conn) -> None:
    conn.execute("SELECT tgsis.store_in_chunks('point')")
    conn.commit()
    tables = tgsis.partition_model_storage(conn, 1, 4)
    assert {"point", "vrtx"} <= set(tables)
    kinds = conn.execute(
        "SELECT c.relname, c.relkind FROM pg_class c WHERE c.oid IN ('tgsis.vrtx'::regclass, 'tgsis.point_chunk'::regclass, "
        "'tgsis.point'::regclass) ORDER BY 1"
    ).fetchall()
    assert kinds == [("point", "v"), ("point_chunk", "p"), ("vrtx", "p")]  # the face stays a view over its chunks


def test_roles_of_tgsis_may_not_switch(db_dsn: str, conn: Conn, fault_clone: int) -> None:
    with login_roles(db_dsn, {"reader": "tgsis_reader", "editor": "tgsis_editor", "admin": "tgsis_admin"}) as roles:
        for short in ("reader", "editor", "admin"):
            session = roles.connect(short)
            for statement in ("SELECT tgsis.store_in_chunks('vrtx')", "SELECT tgsis.row_shape('vrtx')"):
                assert sqlstate(session, statement)[0] == "42501", (short, statement)
            # whether a table is stored in chunks is for everybody to ask (tgsis.storage_table asks it)
            assert session.execute("SELECT tgsis.stored_in_chunks('vrtx')").fetchone() == (False,)
    assert conn.execute("SELECT tgsis.stored_in_chunks('vrtx'), to_regclass('tgsis.vrtx_chunk')").fetchone() == (
        False,
        None,
    )


@pytest.mark.parametrize("fmt", ["custom", "plain"])
def test_a_switched_database_is_dumped_and_restored_whole(
    pg: TestServer, db_dsn: str, conn: Conn, fault_clone: int, tmp_path: Path, fmt: str
) -> None:
    from tests.test_backup import _bindir_of, _restored

    varied_history(conn, fault_clone)
    _switch_all(conn)
    conn.commit()
    before = _everything_seen(conn)
    conn.rollback()
    with _restored(pg, _bindir_of(pg), db_dsn, fmt, tmp_path) as dsn, psycopg.connect(dsn) as copy:
        assert copy.execute(
            "SELECT bool_and(tgsis.stored_in_chunks(t)), min(tgsis.storage_table('tgsis', t)) "
            "FROM unnest(ARRAY['vrtx', 'point', 'segment', 'trgl', 'tetra']) t"
        ).fetchone() == (True, "tgsis.point_chunk")
        assert _everything_seen(copy) == before
        assert copy.execute("SELECT count(*) FROM tgsis.vrtx_shape").fetchone() == (0,)
        # its row trigger is still its own generated function, whose static SQL names the work tables by the
        # table's name (a view's oid would have changed with the restore)
        assert copy.execute(
            "SELECT tgfoid::regprocedure::text FROM pg_trigger WHERE tgrelid = 'tgsis.vrtx'::regclass AND tgname = 'tgsis_chunk_face'"
        ).fetchone() == ("tgsis.vrtx_face_row()",)
        # the restored face is written as before: in a child version, through today's names
        tgsis.create_version(copy, "after restore")
        copy.commit()
        tgsis.goto_version(copy, "after restore")
        copy.execute("UPDATE tgsis.vrtx SET x = x + 1 WHERE geoid = %s AND vrtxid = 40", (fault_clone,))
        copy.commit()
        moved = copy.execute("SELECT x FROM tgsis.vertex(%s, 40)", (fault_clone,)).fetchone()
        tgsis.goto_version(copy, "DEFAULT")
        copy.commit()
        kept = copy.execute("SELECT x FROM tgsis.vertex(%s, 40)", (fault_clone,)).fetchone()
        assert moved is not None and kept is not None and moved[0] == kept[0] + 1
        # and a key-moving UPDATE, a DELETE and an INSERT, each through the row function's static SQL
        with tgsis.in_version(copy, "after restore"):
            copy.execute("UPDATE tgsis.vrtx SET vrtxid = 100000 WHERE geoid = %s AND vrtxid = 40", (fault_clone,))
            copy.execute("DELETE FROM tgsis.vrtx WHERE geoid = %s AND vrtxid = 41", (fault_clone,))
            copy.execute("INSERT INTO tgsis.vrtx VALUES (%s, 100001, 1, 2, 3)", (fault_clone,))
            copy.commit()
            assert copy.execute(
                "SELECT array_agg(vrtxid ORDER BY vrtxid) FROM tgsis.vrtx WHERE geoid = %s AND vrtxid IN (40, 41, 100000, 100001)",
                (fault_clone,),
            ).fetchone() == ([100000, 100001],)
