"""Hostile review of issue 40's second wave (the conversion, the face, the bulk transfer): the cases found wrong.

Each test here failed on main before its fix (or is a strict xfail naming what is left).
"""

from __future__ import annotations

import threading
import time
from typing import Any

import numpy as np
import psycopg
import pytest
from psycopg.conninfo import conninfo_to_dict, make_conninfo

import tgsis
from tests.merge_data import every_view, move
from tgsis.db._chunk_transfer import ObjectRows, download_tables, upload_chunks
from tgsis.errors import InvalidInputError
from tgsis.mesh import Surface

Conn = psycopg.Connection[Any]

# the chunk foundation: builds chunk tables beside the row tables, or switches them (docs/testing.md, the mark storage)
pytestmark = pytest.mark.storage("rows")


def _sqlstate(conn: Conn, statement: str, params: Any = ()) -> str | None:
    try:
        with conn.transaction():
            conn.execute(statement, params)
    except psycopg.Error as exc:
        return exc.sqlstate
    return None


def test_the_verification_catches_chunks_whose_encoding_is_wrong(conn: Conn, fault_clone: int) -> None:
    """A chunk version whose arrays decode to the right rows by one reader but not by another is a wrong chunk.

    The decoded view takes a slot as present when its first array's element is not NULL and numbers
    slots by ordinality; tgsis.vertex, the face's writer and the Python reader go by ``holes`` and by
    subscript. Each corruption below leaves ``_chunk_rows`` unchanged, so the verification must look at
    the encoding itself.
    """
    move(conn, "e1", fault_clone, [0, 1], (1.0, 2.0, 3.0))
    for table in ("vrtx", "trgl"):
        conn.execute("SELECT tgsis.create_chunk_table(%s), tgsis.create_chunk_view(%s)", (table, table))
    conn.commit()
    where = "WHERE geoid = %s AND chunk = 0 AND revision = (SELECT min(revision) FROM tgsis.vrtx_chunk)"
    for corruption in (
        # a hole listed in holes that is not one (the Python reader refuses the chunk)
        f"UPDATE tgsis.vrtx_chunk SET holes = '{{7}}' {where}",
        # arrays numbered from 0: ordinality decodes them, subscripts (tgsis.vertex) read the wrong slot
        f"UPDATE tgsis.vrtx_chunk SET x = '[0:0]={{0}}'::float8[] || x[2:], "
        f"y = '[0:0]={{0}}'::float8[] || y[2:], z = '[0:0]={{0}}'::float8[] || z[2:] {where}",
        # a trailing NULL: not a hole by holes, an element past the last present slot
        f"UPDATE tgsis.vrtx_chunk SET x = x || NULL::float8, y = y || NULL::float8, z = z || NULL::float8 {where}",
    ):
        conn.execute("SELECT tgsis.rows_to_chunks('vrtx')")
        rows = conn.execute("SELECT count(*) FROM tgsis.vrtx_chunk_rows").fetchone()
        assert conn.execute(corruption, (fault_clone,)).rowcount == 1, corruption
        assert conn.execute("SELECT count(*) FROM tgsis.vrtx_chunk_rows").fetchone() == rows, corruption
        assert _sqlstate(conn, "SELECT tgsis.check_chunk_conversion('vrtx')") == "TG000", corruption
        conn.rollback()


def _face_rows(conn: Conn, geoid: int, n: int) -> None:
    conn.execute("DROP TABLE IF EXISTS pg_temp.chunk_rows")
    conn.execute("CREATE TEMP TABLE chunk_rows (LIKE tgsis.vrtx, _delete boolean NOT NULL DEFAULT false)")
    with conn.cursor().copy("COPY pg_temp.chunk_rows FROM STDIN") as copy:
        for i in range(n):
            copy.write_row([geoid, i, float(i), float(-i), 0.5 + i, False])
    conn.execute("SELECT tgsis.write_chunk_rows('vrtx', 'pg_temp.chunk_rows')")


def _concurrent(db_dsn: str, conn: Conn, versions: tuple[str, str], statements: tuple[str, str]) -> list[Any]:
    """The first session writes and holds its transaction open; the second writes; the first commits."""
    first = psycopg.connect(db_dsn)
    second = psycopg.connect(db_dsn)
    result: list[Any] = []
    try:
        for session, version in zip((first, second), versions, strict=True):
            tgsis.goto_version(session, version)
            session.commit()
        first.execute(statements[0])

        def run() -> None:
            try:
                second.execute(statements[1])
                second.commit()
                result.append("ok")
            except psycopg.Error as exc:
                second.rollback()
                result.append(exc.sqlstate)

        worker = threading.Thread(target=run)
        worker.start()
        deadline = time.monotonic() + 60
        while worker.is_alive():  # until the second waits for a lock (or is done)
            row = conn.execute(
                "SELECT wait_event_type FROM pg_stat_activity WHERE pid = %s", (second.info.backend_pid,)
            ).fetchone()
            conn.rollback()
            if row is not None and row[0] == "Lock":
                break
            assert time.monotonic() < deadline
            time.sleep(0.05)
        first.commit()
        worker.join(60)
    finally:
        first.close()
        second.close()
    return result


def test_a_feature_without_versioning_is_written_through_the_face_from_default_only(db_dsn: str, conn: Conn) -> None:
    """A feature of a class without versioning lives in revision 0, which every version sees.

    Two face writers take the chunk's lock keyed by their version: were the child allowed to write revision 0,
    it would not wait for a writer in DEFAULT there and could merge a slot computed from an old row over the
    other's change. It is refused (TG305) before any lock, so the two writers are always in one version.
    """
    tgsis.enable_feature_versioning(conn)
    tgsis.create_feature_class(conn, "plainclass", "SURFACE", versioned=False)
    geoid = tgsis.insert_feature(conn, "plainclass", Surface(np.eye(3), np.array([[0, 1, 2]])))
    conn.commit()
    conn.execute("SELECT tgsis.create_chunk_table('vrtx'), tgsis.create_chunk_view('vrtx')")
    conn.execute("SELECT tgsis.create_chunk_face('vrtx', 'vrtx_face')")
    _face_rows(conn, geoid, 10)
    conn.commit()
    assert conn.execute("SELECT DISTINCT revision FROM tgsis.vrtx_chunk WHERE geoid = %s", (geoid,)).fetchall() == [
        (0,)
    ]
    tgsis.create_version(conn, "child")
    conn.commit()
    update = f"UPDATE tgsis.vrtx_face SET z = z + 1 WHERE geoid = {geoid} AND vrtxid = 1"
    assert _concurrent(db_dsn, conn, ("DEFAULT", "child"), (update, update)) == ["TG305"]
    assert _concurrent(db_dsn, conn, ("DEFAULT", "DEFAULT"), (update, update)) == ["40001"]
    z = conn.execute("SELECT z FROM tgsis.vrtx_face WHERE geoid = %s AND vrtxid = 1", (geoid,)).fetchone()
    conn.rollback()
    assert z == (3.5,)  # the two first sessions' increments, nothing else


def _every_set_agrees(conn: Conn, geoids: list[int]) -> int:
    """Rows of tgsis.vrtx (today's view) against the decoded chunks under every version and revision, as bits."""
    views = every_view(conn)  # every working set and every revision a version can look at
    cols = "geoid, vrtxid, float8send(x), float8send(y), float8send(z)"
    for version, revision in views:
        if revision is None:
            conn.execute("SELECT tgsis.goto_version(%s, true)", (version,))
        else:
            conn.execute("SELECT tgsis.goto_revision(%s, %s, true)", (version, revision))
        rows = conn.execute(f"SELECT {cols} FROM tgsis.vrtx WHERE geoid = ANY (%s) ORDER BY 1, 2", (geoids,)).fetchall()
        chunks = conn.execute(
            f"SELECT {cols} FROM tgsis.vrtx_chunk_rows c WHERE geoid = ANY (%s) AND "
            "(c.revision = ANY (tgsis.get_revisions(true))) IS TRUE AND NOT (c.lastrevs && tgsis.get_revisions(true)) "
            "ORDER BY 1, 2",
            (geoids,),
        ).fetchall()
        assert chunks == rows, (version, revision)
    conn.execute("SELECT tgsis.goto_version('DEFAULT', true)")
    return len(views)


def test_histories_the_authors_did_not_build_convert_and_agree_in_every_set(conn: Conn, fault_clone: int) -> None:
    """psql writes through today's views: a key deleted then inserted again in one version, a whole object
    deleted then written again under its geoid in a child, a deleted version, a feature of a class without
    versioning (revision 0) in versioned storage, saved revisions, then compress_versions."""
    geoid = fault_clone
    with tgsis.in_version(conn, "e1"):
        conn.execute("DELETE FROM tgsis.vrtx WHERE geoid = %s AND vrtxid IN (5, 6, 1023, 1024)", (geoid,))
        conn.commit()
    tgsis.goto_version(conn, "e1")
    tgsis.save_revision(conn, "e1 holes")
    conn.commit()
    with tgsis.in_version(conn, "e1"):
        conn.execute(
            "INSERT INTO tgsis.vrtx VALUES (%s, 5, -1, -1, -1), (%s, 1024, 7, 7, 7), (%s, 4000, 1, 2, 3)",
            (geoid, geoid, geoid),
        )
        conn.commit()
    tgsis.goto_version(conn, "DEFAULT")
    tgsis.create_version(conn, "again", "e1")
    conn.commit()
    with tgsis.in_version(conn, "again"):
        conn.execute("DELETE FROM tgsis.vrtx WHERE geoid = %s", (geoid,))
        conn.commit()
        conn.execute("INSERT INTO tgsis.vrtx VALUES (%s, 0, 9, 9, 9), (%s, 2047, 8, 8, 8)", (geoid, geoid))
        conn.commit()
    tgsis.create_version(conn, "doomed", "DEFAULT")
    conn.commit()
    move(conn, "doomed", geoid, [0, 1, 2], (0.25, 0.25, 0.25))
    conn.commit()
    tgsis.delete_version(conn, "doomed")
    conn.commit()
    tgsis.create_feature_class(conn, "plainclass", "SURFACE", versioned=False)
    plain = tgsis.insert_feature(conn, "plainclass", Surface(np.eye(3), np.array([[0, 1, 2]])))
    conn.commit()
    conn.execute("UPDATE tgsis.vrtx SET z = 5 WHERE geoid = %s AND vrtxid = 1", (plain,))
    conn.commit()
    conn.execute("SELECT tgsis.create_chunk_table('vrtx'), tgsis.create_chunk_view('vrtx')")
    assert int(conn.execute("SELECT tgsis.rows_to_chunks('vrtx')").fetchone()[0]) > 0  # type: ignore[index]
    assert _every_set_agrees(conn, [geoid, plain]) >= 5
    conn.rollback()
    tgsis.compress_versions(conn)
    conn.commit()
    conn.execute("SELECT tgsis.create_chunk_table('vrtx'), tgsis.create_chunk_view('vrtx')")
    assert int(conn.execute("SELECT tgsis.rows_to_chunks('vrtx')").fetchone()[0]) > 0  # type: ignore[index]
    assert _every_set_agrees(conn, [geoid, plain]) >= 3
    conn.rollback()


SHAPES = [
    # UPDATE ... FROM, keys kept (queued) and a key moved (per row)
    "UPDATE {v} t SET x = t.x + s.d FROM (VALUES (1, 0.5), (2, 1.5), (1030, 2.5)) s(id, d) "
    "WHERE t.geoid = {g} AND t.vrtxid = s.id",
    "UPDATE {v} t SET vrtxid = t.vrtxid + 5000 FROM (VALUES (3), (4)) s(id) WHERE t.geoid = {g} AND t.vrtxid = s.id",
    # DELETE ... USING a join that meets one row twice
    "DELETE FROM {v} t USING (VALUES (5), (5), (6)) s(id) WHERE t.geoid = {g} AND t.vrtxid = s.id",
    # INSERT ... SELECT of many rows over several chunks, holes between
    "INSERT INTO {v} SELECT {g}, 20000 + 3 * i, i, -i, i * 0.125 FROM generate_series(0, 1499) i",
    # keys kept in three chunks at once (queued, written after the statement)
    "UPDATE {v} SET x = x + 1 WHERE geoid = {g} AND vrtxid IN (1, 20000, 24497)",
    # ON CONFLICT on a key that is there, and ON CONFLICT DO UPDATE (no arbiter index on a view)
    "INSERT INTO {v} VALUES ({g}, 0, 1, 2, 3) ON CONFLICT DO NOTHING",
    "INSERT INTO {v} VALUES ({g}, 9999, 1, 2, 3) ON CONFLICT (geoid, vrtxid) DO UPDATE SET x = excluded.x",
    # chained writable CTEs: delete, then insert what was deleted elsewhere, then update another row
    "WITH d AS (DELETE FROM {v} WHERE geoid = {g} AND vrtxid IN (7, 8) RETURNING *), "
    "i AS (INSERT INTO {v} SELECT geoid, vrtxid + 7000, x, y, z FROM d RETURNING *), "
    "u AS (UPDATE {v} SET z = -z WHERE geoid = {g} AND vrtxid = 9 RETURNING *) "
    "SELECT (SELECT count(*) FROM i), (SELECT count(*) FROM u)",
    # a function that writes, called per row by an UPDATE of other rows
    "UPDATE {v} SET y = y + pg_temp.bump_{n}({g}, vrtxid) WHERE geoid = {g} AND vrtxid IN (10, 11)",
    # ... and one that writes the very rows the UPDATE is changing
    "UPDATE {v} SET y = y + pg_temp.bump_{n}({g}, vrtxid - 100) WHERE geoid = {g} AND vrtxid IN (12, 13)",
    # a key moved onto a key that is there
    "UPDATE {v} SET vrtxid = 15 WHERE geoid = {g} AND vrtxid = 14",
]


def test_psql_statement_shapes_through_the_face_do_what_today_s_view_does(conn: Conn, fault_clone: int) -> None:
    """The same statements on today's versioned view and on the face over the converted rows, in a child."""
    geoid = fault_clone
    conn.execute("SELECT tgsis.create_chunk_table('vrtx'), tgsis.create_chunk_view('vrtx')")
    conn.execute("SELECT tgsis.rows_to_chunks('vrtx')")
    conn.execute("SELECT tgsis.create_chunk_face('vrtx', 'vrtx_face')")
    conn.commit()
    for view in ("vrtx", "vrtx_face"):
        conn.execute(
            f"CREATE FUNCTION pg_temp.bump_{view}(g bigint, id bigint) RETURNS double precision LANGUAGE sql AS "
            f"$$UPDATE tgsis.{view} SET x = x + 1 WHERE geoid = g AND vrtxid = id + 100 RETURNING 1.0::float8$$"
        )
    conn.commit()
    tgsis.goto_version(conn, "e1")
    conn.commit()
    outcomes: dict[str, list[Any]] = {}
    for view in ("vrtx", "vrtx_face"):
        outcomes[view] = []
        for shape in SHAPES:
            statement = shape.format(v=f"tgsis.{view}", g=geoid, n=view)
            try:
                with conn.transaction():
                    cur = conn.execute(statement)
                    outcomes[view].append((cur.rowcount, cur.fetchall() if cur.description else None))
            except psycopg.Error as exc:
                outcomes[view].append(exc.sqlstate)
    cols = "geoid, vrtxid, float8send(x), float8send(y), float8send(z)"
    rows = conn.execute(f"SELECT {cols} FROM tgsis.vrtx WHERE geoid = %s ORDER BY 1, 2", (geoid,)).fetchall()
    face = conn.execute(f"SELECT {cols} FROM tgsis.vrtx_face WHERE geoid = %s ORDER BY 1, 2", (geoid,)).fetchall()
    conn.rollback()
    assert outcomes["vrtx_face"] == outcomes["vrtx"]
    assert len(face) == len(rows) and face == rows
    conn.execute("SELECT tgsis.goto_version('DEFAULT')")
    parent = conn.execute(f"SELECT {cols} FROM tgsis.vrtx WHERE geoid = %s ORDER BY 1, 2", (geoid,)).fetchall()
    assert conn.execute(f"SELECT {cols} FROM tgsis.vrtx_face WHERE geoid = %s ORDER BY 1, 2", (geoid,)).fetchall() == (
        parent
    )
    conn.rollback()


def test_two_sessions_locking_two_chunks_in_opposite_orders_deadlock_and_lose_nothing(db_dsn: str, conn: Conn) -> None:
    """A: chunk 0 then chunk 1; B: chunk 1 then chunk 0, through the face. One is 40P01 and rolls back whole,
    the other's writes are all kept: never a lost or half-applied update."""
    tgsis.enable_feature_versioning(conn)
    tgsis.create_feature_class(conn, "alpha", "SURFACE")
    geoid = tgsis.insert_feature(conn, "alpha", Surface(np.eye(3), np.array([[0, 1, 2]])))
    conn.commit()
    conn.execute("SELECT tgsis.create_chunk_table('vrtx'), tgsis.create_chunk_view('vrtx')")
    conn.execute("SELECT tgsis.create_chunk_face('vrtx', 'vrtx_face')")
    _face_rows(conn, geoid, 2048)
    conn.commit()
    tgsis.create_version(conn, "child")
    conn.commit()
    a = psycopg.connect(db_dsn)
    b = psycopg.connect(db_dsn)
    upd = "UPDATE tgsis.vrtx_face SET z = z + {d} WHERE geoid = %s AND vrtxid = %s"
    results: dict[str, str] = {}

    def cross(session: Conn, name: str, vrtxid: int, d: int) -> None:
        try:
            session.execute(upd.format(d=d), (geoid, vrtxid))
            session.commit()
            results[name] = "ok"
        except psycopg.Error as exc:
            session.rollback()
            results[name] = str(exc.sqlstate)

    try:
        for s in (a, b):
            tgsis.goto_version(s, "child")
            s.commit()
        a.execute(upd.format(d=1), (geoid, 10))  # A holds chunk 0
        b.execute(upd.format(d=100), (geoid, 1030))  # B holds chunk 1
        threads = [
            threading.Thread(target=cross, args=(a, "a", 1031, 1)),  # A waits for chunk 1
            threading.Thread(target=cross, args=(b, "b", 11, 100)),  # B waits for chunk 0: a deadlock
        ]
        for t in threads:
            t.start()
        for t in threads:
            t.join(60)
    finally:
        a.close()
        b.close()
    tgsis.goto_version(conn, "child")
    z = dict(
        conn.execute(
            "SELECT vrtxid, z FROM tgsis.vrtx_face WHERE geoid = %s AND vrtxid IN (10, 11, 1030, 1031)", (geoid,)
        ).fetchall()
    )
    conn.rollback()
    base = {i: 0.5 + i for i in (10, 11, 1030, 1031)}
    assert sorted(results.values()) == ["40P01", "ok"], results
    if results["a"] == "ok":
        assert z == {**base, 10: base[10] + 1, 1031: base[1031] + 1}
    else:
        assert z == {**base, 11: base[11] + 100, 1030: base[1030] + 100}


def test_keyed_reads_agree_with_the_face_for_odd_ids_in_every_view(conn: Conn, fault_clone: int) -> None:
    """tgsis.vertex / tgsis.vertices against the face: absent, repeated, NULL, negative and huge ids, in a
    child, in DEFAULT and viewing an older revision."""
    geoid = fault_clone
    move(conn, "e1", geoid, [0, 1, 2], (1.0, 1.0, 1.0))
    conn.commit()
    tgsis.goto_version(conn, "e1")
    tgsis.save_revision(conn, "moved once")
    conn.commit()
    move(conn, "e1", geoid, [1, 2], (5.0, 5.0, 5.0))
    with tgsis.in_version(conn, "e1"):
        conn.execute("DELETE FROM tgsis.vrtx WHERE geoid = %s AND vrtxid = 2", (geoid,))
        conn.commit()
    saved = conn.execute("SELECT revision FROM tgsis.revisions WHERE name = 'moved once'").fetchone()
    assert saved is not None
    conn.execute("SELECT tgsis.create_chunk_table('vrtx'), tgsis.create_chunk_view('vrtx')")
    conn.execute("SELECT tgsis.rows_to_chunks('vrtx')")
    conn.execute("SELECT tgsis.create_chunk_face('vrtx', 'vrtx_face')")
    ids = [2, 1, 1, None, -1, -1024, 2**63 - 1, 2**62, 1023, 1024, 0, 999999]
    for goto, args in (
        ("goto_version", ("e1", True)),
        ("goto_version", ("DEFAULT", True)),
        ("goto_revision", ("e1", saved[0], True)),
    ):
        conn.execute(f"SELECT tgsis.{goto}({', '.join(['%s'] * len(args))})", args)
        face = {
            r[0]: r[1:]
            for r in conn.execute(
                "SELECT vrtxid, float8send(x), float8send(y), float8send(z) FROM tgsis.vrtx_face WHERE geoid = %s",
                (geoid,),
            ).fetchall()
        }
        want = [(i, *face[i]) for i in ids if i is not None and i in face]
        got = conn.execute(
            "SELECT vrtxid, float8send(x), float8send(y), float8send(z) FROM tgsis.vertices(%s, %s)", (geoid, ids)
        ).fetchall()
        assert got == want, (goto, args)
        for i in ids:
            one = conn.execute(
                "SELECT float8send(x), float8send(y), float8send(z) FROM tgsis.vertex(%s, %s)", (geoid, i)
            ).fetchall()
            assert one == ([face[i]] if i in face else []), (goto, args, i)
    assert conn.execute("SELECT count(*) FROM tgsis.vertices(%s, NULL)", (geoid,)).fetchone() == (0,)
    assert conn.execute("SELECT count(*) FROM tgsis.vertices(NULL, ARRAY[1])").fetchone() == (0,)
    conn.rollback()


def test_a_face_made_on_unversioned_storage_shows_the_visible_chunks_once_versioning_is_enabled(conn: Conn) -> None:
    """The face decided at creation whether to filter by visibility: made before enable_feature_versioning,
    DEFAULT's face showed each vertex twice and a child's change (the writer, which decides per call, had
    written the child's chunk version correctly). tgsis.vertex, deciding per call, was right."""
    tgsis.create_feature_class(conn, "alpha", "SURFACE")
    geoid = tgsis.insert_feature(conn, "alpha", Surface(np.eye(3), np.array([[0, 1, 2]])))
    conn.commit()
    conn.execute("SELECT tgsis.create_chunk_table('vrtx'), tgsis.create_chunk_view('vrtx')")
    conn.execute("SELECT tgsis.rows_to_chunks('vrtx')")
    conn.execute("SELECT tgsis.create_chunk_face('vrtx', 'vrtx_face')")
    conn.commit()
    face = "SELECT vrtxid, x, y, z FROM tgsis.vrtx_face WHERE geoid = %s ORDER BY 1"
    rows = "SELECT vrtxid, x, y, z FROM tgsis.vrtx WHERE geoid = %s ORDER BY 1"
    assert conn.execute(face, (geoid,)).fetchall() == conn.execute(rows, (geoid,)).fetchall()
    tgsis.enable_feature_versioning(conn)
    tgsis.create_version(conn, "child")
    conn.commit()
    tgsis.goto_version(conn, "child")
    assert conn.execute("UPDATE tgsis.vrtx_face SET x = 42 WHERE geoid = %s AND vrtxid = 1", (geoid,)).rowcount == 1
    conn.commit()
    child = conn.execute(face, (geoid,)).fetchall()
    assert [r[:2] for r in child] == [(0, 1.0), (1, 42.0), (2, 0.0)]
    tgsis.goto_version(conn, "DEFAULT")
    conn.commit()
    assert conn.execute(face, (geoid,)).fetchall() == conn.execute(rows, (geoid,)).fetchall()
    assert conn.execute("SELECT x FROM tgsis.vertex(%s, 1)", (geoid,)).fetchall() == [(0.0,)]
    conn.rollback()


def test_a_side_connection_to_another_database_is_refused_not_read(db_dsn: str, conn: Conn) -> None:
    """download_tables(side=) with the same role on another database of the server (one where tgsis's tables
    would hold other objects): refused by name before anything is read (it was PostgreSQL's 0A000 from the
    second connection's thread, after the first tables' COPYs)."""

    conn.execute("SELECT tgsis.create_chunk_table('vrtx'), tgsis.create_chunk_table('trgl')")
    ids = np.arange(10)
    upload_chunks(conn, "vrtx", [ObjectRows(7, ids, {"x": ids * 1.0, "y": ids * 2.0, "z": ids * 3.0})])
    conn.commit()
    other = f"{conninfo_to_dict(db_dsn)['dbname']}_r3side"
    with psycopg.connect(db_dsn, autocommit=True) as admin:
        admin.execute(f'CREATE DATABASE "{other}" TEMPLATE template0')
    try:
        side = psycopg.connect(make_conninfo(db_dsn, dbname=other))
        try:
            with pytest.raises(InvalidInputError, match="to database"):
                download_tables(conn, {"vrtx": [7], "trgl": [7]}, side=side)
        finally:
            side.close()
    finally:
        conn.rollback()
        with psycopg.connect(db_dsn, autocommit=True) as admin:
            admin.execute(f'DROP DATABASE "{other}"')


def test_a_hostile_search_path_changes_nothing_the_face_and_keyed_reads_do(conn: Conn, fault_clone: int) -> None:
    """Relations and functions named like the internals, in pg_temp and public, first on the search path."""
    geoid = fault_clone
    # the storage switch (tgsis.vertex reads the chunks once they are the storage, not merely once they exist)
    conn.execute("SELECT tgsis.store_in_chunks('vrtx') WHERE NOT tgsis.stored_in_chunks('vrtx')")
    conn.commit()
    tgsis.goto_version(conn, "e1")
    conn.commit()
    read = "SELECT vrtxid, float8send(x) FROM tgsis.vrtx WHERE geoid = %s ORDER BY 1"
    before = conn.execute(read, (geoid,)).fetchall()
    one = conn.execute("SELECT float8send(x) FROM tgsis.vertex(%s, 3)", (geoid,)).fetchall()
    for name in ("vrtx_chunk", "versioned_tables", "model_tables", "versions", "revisions"):
        conn.execute(f"CREATE TEMP TABLE {name} (geoid bigint, chunk bigint, revision integer, tablename text)")
        conn.execute(f"CREATE TABLE public.{name} (geoid bigint, chunk bigint, revision integer, tablename text)")
    for fn in ("get_revisions", "write_chunk_rows", "check_class_write", "write_revision"):
        conn.execute(f"CREATE FUNCTION public.{fn}(variadic anyarray) RETURNS integer[] LANGUAGE sql AS 'SELECT NULL'")
    conn.execute(
        "CREATE FUNCTION public.get_revisions(boolean) RETURNS integer[] LANGUAGE sql AS 'SELECT ''{0}''::int[]'"
    )
    conn.execute("SET search_path = pg_temp, public, tgsis, pg_catalog")
    assert conn.execute(read, (geoid,)).fetchall() == before
    assert conn.execute("SELECT float8send(x) FROM tgsis.vertex(%s, 3)", (geoid,)).fetchall() == one
    assert conn.execute("UPDATE tgsis.vrtx SET x = 7 WHERE geoid = %s AND vrtxid = 3", (geoid,)).rowcount == 1
    assert conn.execute("INSERT INTO tgsis.vrtx VALUES (%s, 5000, 1, 2, 3)", (geoid,)).rowcount == 1
    conn.execute("RESET search_path")
    assert conn.execute("SELECT x FROM tgsis.vertex(%s, 3)", (geoid,)).fetchall() == [(7.0,)]
    assert conn.execute("SELECT x, y, z FROM tgsis.vertex(%s, 5000)", (geoid,)).fetchall() == [(1.0, 2.0, 3.0)]
    conn.execute("SELECT tgsis.goto_version('DEFAULT', true)")
    assert conn.execute("SELECT float8send(x) FROM tgsis.vertex(%s, 3)", (geoid,)).fetchall() != []
    assert conn.execute("SELECT count(*) FROM tgsis.vertex(%s, 5000)", (geoid,)).fetchone() == (0,)
    conn.rollback()


def test_keyed_reads_follow_the_storage_not_the_existence_of_a_chunk_table(conn: Conn, fault_clone: int) -> None:
    geoid = fault_clone
    conn.execute("SELECT tgsis.create_chunk_table('vrtx'), tgsis.create_chunk_view('vrtx')")
    conn.execute("SELECT tgsis.rows_to_chunks('vrtx')")  # the rows stay the storage
    conn.execute("UPDATE tgsis.vrtx SET x = 99 WHERE geoid = %s AND vrtxid = 3", (geoid,))
    assert conn.execute("SELECT x FROM tgsis.vrtx WHERE geoid = %s AND vrtxid = 3", (geoid,)).fetchall() == [(99.0,)]
    got = conn.execute("SELECT x FROM tgsis.vertex(%s, 3)", (geoid,)).fetchall()
    conn.rollback()
    assert got == [(99.0,)]
