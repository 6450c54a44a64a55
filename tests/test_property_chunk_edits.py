"""The check-in's and the merges' property writes of a class in chunks: each touched chunk written once (issue 40).

docs/storage.md, "The bulk paths of property chunks": a check-in by difference (and a merge's written state)
of a class whose property table is the face of ``tgsis.store_class_in_chunks`` sends the rows that go and the
new and changed rows at once to ``tgsis.write_property_rows``, which rewrites each touched chunk once, where the
face rewrote a chunk per row. The property tables are rows or chunks whatever model 1's storage is, so the file
runs unmarked.
"""

from __future__ import annotations

import struct
from typing import Any

import numpy as np
import psycopg
import pytest

import tgsis
from tests.merge_data import curved_surface, sqlstate
from tests.storage_data import classes_as_rows
from tgsis.db import features as F
from tgsis.mesh import Surface

Conn = psycopg.Connection[Any]


@pytest.fixture(autouse=True)
def _classes_as_rows(db_dsn: str) -> None:
    """The classes these tests make start as rows: they switch them to chunks themselves, or compare with a rows
    twin (docs/storage.md, "Property chunks by default: the rule")."""
    classes_as_rows(db_dsn)


NAN_PAYLOAD = struct.unpack(">d", struct.pack(">Q", 0x7FF8000000000ABC))[0]
TWINS = ("inchunks", "onrows")


def _surface() -> Surface:
    surface = curved_surface(40)  # 1,600 vertices: two chunks of 1,024
    porosity = surface.vertex_properties["porosity"].copy()
    return Surface(
        surface.vertices,
        surface.cells,
        vertex_properties={"porosity": porosity, "facies": (np.arange(surface.n_vertices, dtype=np.int32) % 7) - 3},
    )


def _classes(conn: Conn, versioned: bool = True) -> dict[str, int]:
    """Twin classes (porosity, facies) with the same surface; ``inchunks``'s properties in chunks; version e1."""
    for name in TWINS:
        tgsis.create_feature_class(
            conn, name, "SURFACE", cell_properties=[("porosity", "double precision"), ("facies", "integer")]
        )
    if versioned:
        tgsis.enable_feature_versioning(conn)
    geoids = {name: F.insert_feature(conn, name, _surface()) for name in TWINS}
    if versioned:
        tgsis.create_version(conn, "e1")
    conn.commit()
    conn.execute("SELECT tgsis.store_class_in_chunks('inchunks')")
    conn.commit()
    return geoids


def _rows(conn: Conn, name: str) -> list[tuple[Any, ...]]:
    return [
        tuple(r)
        for r in conn.execute(
            f"SELECT _idx, float8send(porosity), facies FROM public.{name}_cellpros ORDER BY _idx"
        ).fetchall()
    ]


def _edited(conn: Conn, name: str, geoid: int, change: dict[int, float], drop_last: int = 0) -> Surface:
    mesh = F.fetch_feature(conn, name, geoid).mesh
    assert isinstance(mesh, Surface)
    porosity = mesh.vertex_properties["porosity"].copy()
    for i, value in change.items():
        porosity[i] = value
    keep = np.arange(mesh.n_vertices - drop_last)
    inside = np.all(mesh.cells < len(keep), axis=1)
    return Surface(
        mesh.vertices[keep],
        mesh.cells[inside],
        vertex_properties={"porosity": porosity[keep], "facies": mesh.vertex_properties["facies"][keep]},
    )


def _chunk_writes(conn: Conn) -> int:
    """Tuples inserted, updated or deleted in inchunks' chunk table that this backend has not reported yet.

    Since PostgreSQL 15 a backend reports its table counts at most once a second, when idle outside a transaction:
    the counts of transactions committed just before are still pending and add to this one's. Take the difference
    of two readings inside one transaction (nothing is reported inside it).
    """
    row = conn.execute(
        "SELECT n_tup_ins + n_tup_upd + n_tup_del FROM pg_stat_xact_user_tables "
        "WHERE relid = 'public.inchunks_cellpros_chunk'::regclass"
    ).fetchone()
    assert row is not None
    return int(row[0])


def test_a_check_in_writes_each_touched_chunk_once_and_equals_rows(conn: Conn) -> None:
    """A check-in in e1 changing 300 values over both chunks, deleting the last 40 vertices: each touched chunk is
    written once (closed + new version; through the face it was a write per row), e1 sees the edit and DEFAULT the
    old values, bit for bit as the twin on rows (-0.0, a NaN payload)."""
    geoids = _classes(conn)
    change = {int(i): float(i) / 7.0 for i in range(0, 1500, 5)}
    change[3], change[1100] = -0.0, NAN_PAYLOAD
    before = {name: _rows(conn, name) for name in TWINS}
    with tgsis.in_version(conn, "e1"):
        for name in TWINS:
            edited = _edited(conn, name, geoids[name], change, drop_last=40)
            conn.commit()
            conn.execute("SELECT 1")  # the caller's transaction: the check-in's writes are counted in it
            pending = _chunk_writes(conn)
            tgsis.save_feature(conn, name, geoids[name], edited)
            if name == "inchunks":
                # two chunks, each closed in DEFAULT's revision and written anew in e1's: 4 tuples, not 300+
                assert 2 <= _chunk_writes(conn) - pending <= 4
            conn.commit()
        seen = {name: _rows(conn, name) for name in TWINS}
    assert seen["inchunks"] == seen["onrows"]
    assert len(seen["inchunks"]) == 1560
    assert seen["inchunks"][3][1] == struct.pack(">d", -0.0)
    assert seen["inchunks"][1100][1] == struct.pack(">Q", 0x7FF8000000000ABC)
    assert {name: _rows(conn, name) for name in TWINS} == before  # DEFAULT unchanged
    versions = conn.execute(
        "SELECT count(*) FILTER (WHERE revision <> 0), count(*) FILTER (WHERE lastrevs <> '{}') "
        "FROM public.inchunks_cellpros_chunk"
    ).fetchone()
    assert versions == (2, 2)
    # a second check-in in e1: the working revision's chunk versions rewritten in place, none added
    with tgsis.in_version(conn, "e1"):
        for name in TWINS:
            edited = _edited(conn, name, geoids[name], {10: 1.5, 1200: 2.5})
            conn.commit()
            tgsis.save_feature(conn, name, geoids[name], edited)
            conn.commit()
        assert _rows(conn, "inchunks") == _rows(conn, "onrows")
    assert conn.execute("SELECT count(*) FROM public.inchunks_cellpros_chunk").fetchone() == (4,)


def test_the_merges_write_property_chunks_whole_and_conflicts_are_still_found(conn: Conn) -> None:
    """e1's check-in merged into DEFAULT, which changed other values: DEFAULT gets both, as the twin on rows; the
    same value changed on both sides is a conflict, solved by the child's value."""
    geoids = _classes(conn)
    with tgsis.in_version(conn, "e1"):
        for name in TWINS:
            edited = _edited(conn, name, geoids[name], {int(i): 0.5 for i in range(0, 1600, 3)})
            conn.commit()
            tgsis.save_feature(conn, name, geoids[name], edited)
            conn.commit()
    for name in TWINS:
        conn.execute(f"UPDATE public.{name}_cellpros SET facies = 99 WHERE _idx = 1301")
    conn.commit()
    tgsis.merge_version(conn, "e1")
    conn.commit()
    assert _rows(conn, "inchunks") == _rows(conn, "onrows")
    assert _rows(conn, "inchunks")[1301][2] == 99 and _rows(conn, "inchunks")[3][1] == struct.pack(">d", 0.5)
    # the same vertex changed on both sides: still a conflict
    with tgsis.in_version(conn, "e1"):
        for name in TWINS:
            edited = _edited(conn, name, geoids[name], {700: -1.0})
            conn.commit()
            tgsis.save_feature(conn, name, geoids[name], edited)
            conn.commit()
    for name in TWINS:
        conn.execute(f"UPDATE public.{name}_cellpros SET porosity = -2.0 WHERE _idx = 700")
    conn.commit()
    with pytest.raises(tgsis.UnsolvedConflictsError):
        tgsis.merge_version(conn, "e1")
    conn.rollback()
    for name in TWINS:
        tgsis.resolve_conflict(conn, "e1", "feature", geoids[name], "child")
    conn.commit()
    tgsis.merge_version(conn, "e1")
    conn.commit()
    assert _rows(conn, "inchunks") == _rows(conn, "onrows")
    assert _rows(conn, "inchunks")[700][1] == struct.pack(">d", -1.0)


def test_an_unversioned_class_check_in_writes_chunks_whole(conn: Conn) -> None:
    geoids = _classes(conn, versioned=False)
    for name in TWINS:
        edited = _edited(conn, name, geoids[name], {5: 0.25, 1300: -0.0}, drop_last=10)
        conn.commit()
        conn.execute("SELECT 1")  # the caller's transaction: the check-in's writes are counted in it
        pending = _chunk_writes(conn)
        tgsis.save_feature(conn, name, geoids[name], edited)
        if name == "inchunks":
            assert 1 <= _chunk_writes(conn) - pending <= 4  # two chunks, in place (revision 0 is the one state): not 14
        conn.commit()
    assert _rows(conn, "inchunks") == _rows(conn, "onrows")
    assert conn.execute("SELECT count(*) FROM public.inchunks_cellpros_chunk").fetchone() == (2,)


def _call(conn: Conn, geoid: int, deleted: str, rows: str) -> tuple[str | None, str]:
    statement = f"SELECT tgsis.write_property_rows('public.inchunks_cellpros', %s, {deleted}::bigint[], {rows})"
    return sqlstate(conn, statement, (geoid,) * statement.count("%s"))


def test_bad_calls_are_refused_by_name_and_change_nothing(conn: Conn) -> None:
    geoids = _classes(conn)
    g = geoids["inchunks"]
    before = _rows(conn, "inchunks")
    chunks = conn.execute("SELECT count(*) FROM public.inchunks_cellpros_chunk").fetchone()
    row = "ROW(%s, {}, 1.0, 1)::public.inchunks_cellpros"
    # an id present now, written without its delete: the face's INSERT of a present key
    state, message = _call(conn, g, "'{}'", f"ARRAY[{row.format(5)}]")
    assert state == "23505" and "inchunks_cellpros_pkey" in message
    # a row of another object
    state, _ = sqlstate(
        conn,
        "SELECT tgsis.write_property_rows('public.inchunks_cellpros', %s, '{}', "
        "ARRAY[ROW(%s, 5000, 1.0, 1)::public.inchunks_cellpros])",
        (g, g + 1000),
    )
    assert state == "TG100"
    # rows of another type, a table not in chunks, a NULL id
    assert _call(conn, g, "'{}'", "ARRAY[1, 2]")[0] == "TG100"
    assert _call(conn, g, "'{NULL}'", "'{}'::public.inchunks_cellpros[]")[0] == "TG100"
    assert (
        sqlstate(
            conn, "SELECT tgsis.write_property_rows('public.onrows_cellpros', 1, '{}', '{}'::public.onrows_cellpros[])"
        )[0]
        == "TG200"
    )
    # a NULL into the NOT NULL key column is refused by the writer as the row table refuses it (23502 naming the
    # column, since the nineteenth session: tests/test_property_not_null_chunks.py)
    state, message = _call(conn, g, "'{}'", "ARRAY[ROW(%s, NULL, 1.0, 1)::public.inchunks_cellpros]")
    assert state == "23502" and 'column "_idx"' in message, message
    conn.rollback()
    assert _rows(conn, "inchunks") == before
    assert conn.execute("SELECT count(*) FROM public.inchunks_cellpros_chunk").fetchone() == chunks


def test_a_role_with_fewer_rights(db_dsn: str, conn: Conn) -> None:
    """A reader may not write (42501), an editor not in a version it has no write right to (TG002), and writes in
    DEFAULT; nothing changes by the refusals."""
    from tests.roles import login_roles

    geoids = _classes(conn)
    g = geoids["inchunks"]
    before = _rows(conn, "inchunks")
    call = (
        "SELECT tgsis.write_property_rows('public.inchunks_cellpros', %s, '{5}', "
        "ARRAY[ROW(%s, 5, 1.0, 1)::public.inchunks_cellpros])"
    )
    with login_roles(db_dsn, {"reader": "tgsis_reader", "editor": "tgsis_editor"}) as roles:
        reader = roles.connect("reader")
        assert sqlstate(reader, call, (g, g))[0] == "42501"
        edited = _edited(reader, "inchunks", g, {5: 9.0})
        reader.rollback()
        with pytest.raises(tgsis.MissingPrivilegeError):
            tgsis.save_feature(reader, "inchunks", g, edited)
        reader.rollback()
        editor = roles.connect("editor")
        tgsis.goto_version(editor, "e1")
        assert sqlstate(editor, call, (g, g))[0] == "TG002"
        editor.rollback()
        tgsis.goto_version(editor, "DEFAULT")
        editor.commit()
        tgsis.save_feature(editor, "inchunks", g, _edited(editor, "inchunks", g, {5: 9.0}))
        editor.commit()
    after = _rows(conn, "inchunks")
    assert after[5][1] == struct.pack(">d", 9.0) and after[:5] == before[:5] and after[6:] == before[6:]


def test_a_face_writer_of_the_object_waits_for_the_check_in_and_both_are_kept(db_dsn: str, conn: Conn) -> None:
    """Session A's check-in (not yet committed) holds the object's write lock: session B's psql UPDATE of another
    value of the same chunk in the same version waits, then writes into A's chunk version: both values kept."""
    from tests.sessions import Background, connect, wait_until_blocked

    geoids = _classes(conn)
    g = geoids["inchunks"]
    first = connect(db_dsn, "first")
    tgsis.goto_version(first, "e1")
    first.commit()
    tgsis.save_feature(first, "inchunks", g, _edited(first, "inchunks", g, {10: 4.5, 11: 5.5}))

    def second_writer(session: Conn) -> None:
        tgsis.goto_version(session, "e1")
        session.execute("UPDATE public.inchunks_cellpros SET facies = 77 WHERE _geoid = %s AND _idx = 12", (g,))

    second = Background(db_dsn, "second", second_writer)
    wait_until_blocked(conn, second.pid, first.info.backend_pid)
    conn.rollback()
    first.commit()
    first.close()
    second.finish()
    with tgsis.in_version(conn, "e1"):
        rows = _rows(conn, "inchunks")
    assert rows[10][1] == struct.pack(">d", 4.5) and rows[11][1] == struct.pack(">d", 5.5) and rows[12][2] == 77
