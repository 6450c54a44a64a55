"""The relational face over chunks (issue 40, part 4): versioned views with today's names, their writes, keyed reads.

``tgsis.create_chunk_face(table, view)`` builds the view that will stand in
``tgsis.<table>``'s place once model 1 is stored in chunks; nothing switches
yet, so these tests build it beside today's live table (``tgsis.vrtx_face``)
and compare it with the chunks' decoded content, and its writes with today's
rows view. ``tgsis.vertex`` and ``tgsis.vertices`` read today's rows until
``tgsis.vrtx_chunk`` exists, chunks after: both branches are tested.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Iterable, Sequence
from typing import Any

import numpy as np
import psycopg
import pytest
from psycopg import sql

import tgsis
from tests.roles import login_roles
from tgsis.mesh import Surface

Conn = psycopg.Connection[Any]

REFS = {"vrtx": [], "point": ["vrtxid1"], "segment": ["vrtxid1", "vrtxid2"], "trgl": ["vrtxid1", "vrtxid2", "vrtxid3"]}
IDS = {"vrtx": "vrtxid", "point": "pointid", "segment": "segid", "trgl": "trglid"}


def _faces(conn: Conn, tables: Iterable[str] = ("vrtx",)) -> None:
    for table in tables:
        conn.execute("SELECT tgsis.create_chunk_table(%s), tgsis.create_chunk_view(%s)", (table, table))
        conn.execute("SELECT tgsis.create_chunk_face(%s, %s)", (table, f"{table}_face"))
    conn.commit()


def _write(conn: Conn, table: str, rows: Sequence[Sequence[Any]]) -> None:
    """Write ``rows`` (the row table's columns in order) into the chunks through the writer."""
    conn.execute("DROP TABLE IF EXISTS pg_temp.chunk_rows")
    conn.execute(
        sql.SQL("CREATE TEMP TABLE chunk_rows (LIKE tgsis.{}, _delete boolean NOT NULL DEFAULT false)").format(
            sql.Identifier(table)
        )
    )
    with conn.cursor().copy("COPY pg_temp.chunk_rows FROM STDIN") as copy:
        for row in rows:
            copy.write_row([*row, False])
    conn.execute("SELECT tgsis.write_chunk_rows(%s, 'pg_temp.chunk_rows')", (table,))


def _decoded(conn: Conn, table: str) -> list[tuple[Any, ...]]:
    """The decoded rows of the chunk versions the session sees (today's visibility), in key order."""
    values = REFS[table] or ["x", "y", "z"]
    query = sql.SQL(
        "SELECT geoid, {ident}, {values} FROM tgsis.{view} c "
        "WHERE (c.revision = ANY (tgsis.get_revisions(true))) IS TRUE AND NOT (c.lastrevs && tgsis.get_revisions(true)) "
        "ORDER BY 1, 2"
    ).format(
        ident=sql.Identifier(IDS[table]),
        values=sql.SQL(", ").join(sql.Identifier(v) for v in values),
        view=sql.Identifier(f"{table}_chunk_rows"),
    )
    return [tuple(r) for r in conn.execute(query).fetchall()]


def _face(conn: Conn, table: str = "vrtx", where: str = "") -> list[tuple[Any, ...]]:
    return [
        tuple(r)
        for r in conn.execute(
            sql.SQL("SELECT * FROM tgsis.{} {} ORDER BY 1, 2").format(sql.Identifier(f"{table}_face"), sql.SQL(where))
        ).fetchall()
    ]


def _vertices(ids: Iterable[int], geoid: int = 1, scale: float = 1.0) -> list[tuple[int, int, float, float, float]]:
    return [(geoid, i, i * scale, -i * scale, 0.5 + i) for i in ids]


def _sqlstate(conn: Conn, statement: str, params: Sequence[Any] = ()) -> str | None:
    try:
        with conn.transaction():
            conn.execute(statement, params)
    except psycopg.Error as exc:
        return exc.sqlstate
    return None


# --------------------------------------------------------------------------- the view


@pytest.mark.parametrize("versioned", [False, True], ids=["plain", "versioned"])
def test_the_face_has_the_row_table_s_columns_and_shows_the_visible_chunks(conn: Conn, versioned: bool) -> None:
    if versioned:
        tgsis.enable_feature_versioning(conn)
    _faces(conn, ["vrtx", "trgl"])
    for table in ("vrtx", "trgl"):
        face = conn.execute(
            "SELECT attname, format_type(atttypid, atttypmod), col_description(attrelid, attnum) FROM pg_attribute "
            "WHERE attrelid = %s::regclass AND attnum > 0 ORDER BY attnum",
            (f"tgsis.{table}_face",),
        ).fetchall()
        today = conn.execute(
            "SELECT attname, format_type(atttypid, atttypmod), col_description(attrelid, attnum) FROM pg_attribute "
            "WHERE attrelid = %s::regclass AND attnum > 0 AND NOT attisdropped ORDER BY attnum",
            (f"tgsis.{table}",),
        ).fetchall()
        assert face == today, table
        assert all(c[2] for c in face), face
        assert conn.execute(
            "SELECT obj_description(%s::regclass, 'pg_class')", (f"tgsis.{table}_face",)
        ).fetchone() != (None,)
        # the grants of today's relation, a security barrier owned by the storage's owner
        acl = (
            "SELECT a.grantee::regrole::text, a.privilege_type FROM pg_class c, aclexplode(c.relacl) a "
            "WHERE c.oid = %s::regclass AND a.grantee <> c.relowner ORDER BY 1, 2"
        )
        assert (
            conn.execute(acl, (f"tgsis.{table}_face",)).fetchall() == conn.execute(acl, (f"tgsis.{table}",)).fetchall()
        )
        options = conn.execute("SELECT reloptions FROM pg_class WHERE oid = %s::regclass", (f"tgsis.{table}_face",))
        assert options.fetchone() == (["security_barrier=true"],)
    rows = _vertices([0, 1, 2, 5, 1023, 1024, 3000])
    _write(conn, "vrtx", rows)
    triangles = [(1, 0, 0, 1, 2), (1, 1, 2**40, 2**40 + 1, 5), (1, 2000, 7, 8, 9)]  # the second chunk's ids are wide
    _write(conn, "trgl", triangles)
    conn.commit()
    assert _face(conn) == rows == _decoded(conn, "vrtx")
    assert _face(conn, "trgl") == triangles == _decoded(conn, "trgl")
    if not versioned:
        return
    # in a child version: the child's writes seen there, the parent's content in the parent
    tgsis.create_version(conn, "child")
    tgsis.goto_version(conn, "child")
    changed = _vertices([1, 4000], scale=2.0)
    _write(conn, "vrtx", changed)
    conn.commit()
    child = sorted({r[1]: r for r in [*rows, *changed]}.values())
    assert _face(conn) == child == _decoded(conn, "vrtx")
    tgsis.goto_version(conn, "DEFAULT")
    assert _face(conn) == rows == _decoded(conn, "vrtx")
    tgsis.goto_version(conn, "child")
    assert _face(conn, where="WHERE geoid = 1 AND vrtxid = 4000") == [changed[1]]


def test_the_creator_refuses_by_name(conn: Conn) -> None:
    assert _sqlstate(conn, "SELECT tgsis.create_chunk_face('vrtx', 'vrtx_face')") == "TG200"  # no chunk table
    assert _sqlstate(conn, "SELECT tgsis.create_chunk_face('atom', 'atom_face')") == "TG200"
    _faces(conn)
    assert _sqlstate(conn, "SELECT tgsis.create_chunk_face('vrtx', 'vrtx_face')") == "TG201"
    assert _sqlstate(conn, "SELECT tgsis.create_chunk_face('vrtx')") == "TG201"  # today's table has the name


# --------------------------------------------------------------------------- writes


def _feature(conn: Conn, feature_class: str = "alpha") -> int:
    if conn.execute("SELECT to_regclass(%s)", (feature_class,)).fetchone() == (None,):
        tgsis.create_feature_class(conn, feature_class, "SURFACE")
    geoid = tgsis.insert_feature(conn, feature_class, Surface(np.eye(3), np.array([[0, 1, 2]])))
    conn.commit()
    return geoid


def test_writes_through_the_face_in_a_child_version_leave_the_parent_unchanged(conn: Conn) -> None:
    tgsis.enable_feature_versioning(conn)
    geoid = _feature(conn)
    _faces(conn)
    rows = _vertices(range(10), geoid=geoid)
    _write(conn, "vrtx", rows)
    conn.commit()
    tgsis.create_version(conn, "child")
    tgsis.goto_version(conn, "child")
    expected = {r[1]: r for r in rows}
    inserted = conn.execute("INSERT INTO tgsis.vrtx_face VALUES (%s, 2000, 1.5, 2.5, 3.5) RETURNING *", (geoid,))
    assert inserted.fetchall() == [(geoid, 2000, 1.5, 2.5, 3.5)]
    expected[2000] = (geoid, 2000, 1.5, 2.5, 3.5)
    updated = conn.execute(
        "UPDATE tgsis.vrtx_face SET z = -z WHERE geoid = %s AND vrtxid IN (3, 4) RETURNING vrtxid, z", (geoid,)
    ).fetchall()
    assert sorted(updated) == [(3, -3.5), (4, -4.5)]
    for i in (3, 4):
        expected[i] = (*expected[i][:4], -expected[i][4])
    deleted = conn.execute("DELETE FROM tgsis.vrtx_face WHERE geoid = %s AND vrtxid = 7 RETURNING vrtxid", (geoid,))
    assert deleted.fetchall() == [(7,)]
    del expected[7]
    moved = conn.execute(
        "UPDATE tgsis.vrtx_face SET vrtxid = 5000 WHERE geoid = %s AND vrtxid = 8 RETURNING vrtxid, x", (geoid,)
    ).fetchall()
    assert moved == [(5000, 8.0)]
    expected[5000] = (geoid, 5000, *expected.pop(8)[2:])
    # a statement with writable CTEs: an UPDATE (queued, written when the query ends) beside an INSERT
    counts = conn.execute(
        "WITH u AS (UPDATE tgsis.vrtx_face SET x = x + 100 WHERE geoid = %s AND vrtxid < 3 RETURNING vrtxid), "
        "i AS (INSERT INTO tgsis.vrtx_face VALUES (%s, 6000, 0, 0, 0) RETURNING vrtxid) "
        "SELECT (SELECT count(*) FROM u), (SELECT count(*) FROM i)",
        (geoid, geoid),
    ).fetchone()
    assert counts == (3, 1)
    for i in (0, 1, 2):
        expected[i] = (geoid, i, expected[i][2] + 100, *expected[i][3:])
    expected[6000] = (geoid, 6000, 0.0, 0.0, 0.0)
    conn.commit()
    assert _face(conn) == sorted(expected.values()) == _decoded(conn, "vrtx")
    # the object is noted as changed in the child's working revision, as today's triggers note it
    noted = conn.execute(
        "SELECT count(*) FROM tgsis.revision_objects WHERE revision = tgsis.get_working_revision() "
        "AND tablename = 'vrtx' AND objectkey = %s",
        (str(geoid),),
    ).fetchone()
    assert noted == (1,)
    # a visible key inserted again: 23505 naming today's key, as today's view of rows says it
    face_dup = _sqlstate(conn, "INSERT INTO tgsis.vrtx_face VALUES (%s, 0, 1, 1, 1)", (geoid,))
    rows_dup = _sqlstate(conn, "INSERT INTO tgsis.vrtx VALUES (%s, 0, 1, 1, 1)", (geoid,))
    assert face_dup == rows_dup == "23505"
    for statement in (
        "INSERT INTO tgsis.{} VALUES (%s, 0, 1, 1, 1)",
        "UPDATE tgsis.{} SET vrtxid = 1 WHERE geoid = %s AND vrtxid = 2",
    ):
        names = []
        for view in ("vrtx_face", "vrtx"):
            with pytest.raises(psycopg.errors.UniqueViolation) as dup:
                with conn.transaction():
                    conn.execute(sql.SQL(statement).format(sql.Identifier(view)), (geoid,))
            names.append(dup.value.diag.constraint_name)
        assert names[0] == names[1] is not None, names
    # the parent keeps its content
    tgsis.goto_version(conn, "DEFAULT")
    assert _face(conn) == rows == _decoded(conn, "vrtx")
    conn.commit()


def test_plain_storage_writes_in_revision_0_and_refuses_another_version(conn: Conn) -> None:
    geoid = _feature(conn)
    _faces(conn)
    _write(conn, "vrtx", _vertices(range(3), geoid=geoid))
    conn.commit()
    conn.execute("UPDATE tgsis.vrtx_face SET x = 42 WHERE geoid = %s AND vrtxid = 1", (geoid,))
    conn.execute("DELETE FROM tgsis.vrtx_face WHERE geoid = %s AND vrtxid = 2", (geoid,))
    conn.commit()
    assert _face(conn) == [(geoid, 0, 0.0, 0.0, 0.5), (geoid, 1, 42.0, -1.0, 1.5)]
    assert conn.execute("SELECT DISTINCT revision FROM tgsis.vrtx_chunk").fetchall() == [(0,)]
    tgsis.create_version(conn, "child")
    tgsis.goto_version(conn, "child")
    assert _sqlstate(conn, "UPDATE tgsis.vrtx_face SET x = 1 WHERE geoid = %s", (geoid,)) == "TG305"
