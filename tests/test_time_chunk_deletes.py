"""``tgsis.delete_instant`` / ``tgsis.delete_period`` on time tables stored in chunks: set-based (issue 40).

The slice's chunk versions are deleted (the working revision's) or closed
whole by ``tgsis.delete_chunk_slice``, one statement per table, not a chunk
rewrite per row through the face's trigger (docs/storage.md, "Snapshots at t").
Each test compares with the rows storage: the same answers, the same refusals.
"""

from __future__ import annotations

from typing import Any

import psycopg
import pytest

import tgsis
from tests.merge_data import curved_surface, sqlstate
from tests.sessions import Background, connect, wait_until_blocked
from tests.test_model2_chunks import TIME_TABLES, _answers, _class, _series, _store
from tests.test_model2_chunks import _switch as _switch2

Conn = psycopg.Connection[Any]

#: the instant deleted: not exactly 0.3 (its bits must be matched by the float8 = of the rows' key)
GONE = 0.1 + 0.2
#: the revision saved before each feature's delete
saved: dict[int, int] = {}


def _calls(conn: Conn, function: str) -> int:
    row = conn.execute(
        "SELECT coalesce(sum(calls), 0) FROM pg_stat_xact_user_functions WHERE schemaname = 'tgsis' AND funcname = %s",
        (function,),
    ).fetchone()
    assert row is not None
    return int(row[0])


def _without_geoid(answers: dict[str, Any]) -> dict[str, Any]:
    """The answers with the face rows' geoid left out (two features compared)."""
    return {k: [r[1:] for r in v] if k in ("faces", "trgl") else v for k, v in answers.items()}


def _delete_and_read(conn: Conn, versioned: bool, name: str) -> tuple[dict[str, Any], int]:
    """A series, saved when versioned (its chunks then an older revision's: closed, not deleted), its instant
    GONE deleted: (the answers, the geoid)."""
    geoid = _series(conn, name)
    if versioned:
        saved[geoid] = tgsis.save_revision(conn, f"before {geoid}")
        conn.commit()
    conn.execute("SET track_functions = 'all'")
    assert tgsis.delete_instant(conn, geoid, GONE)
    # on chunks: no face trigger ran, one set-based call per time table
    stored = conn.execute("SELECT tgsis.stored_in_chunks('times_vrtx')").fetchone() == (True,)
    assert (_calls(conn, "chunk_face_write"), _calls(conn, "delete_chunk_slice")) == ((0, 2) if stored else (0, 0))
    conn.commit()
    return _without_geoid(_answers(conn, geoid)), geoid


@pytest.mark.parametrize("versioned", [False, True])
def test_delete_instant_on_chunks_answers_as_on_rows(conn: Conn, versioned: bool) -> None:
    _class(conn, versioned)
    on_rows, _ = _delete_and_read(conn, versioned, "horizons")
    _switch2(conn, "chunks")
    on_chunks, geoid = _delete_and_read(conn, versioned, "horizons")
    assert on_chunks == on_rows
    assert on_chunks["series times"] == _answers(conn, geoid)["series times"]
    # the instant's chunk versions: closed when another revision wrote them, deleted when none still sees them
    closed, present = conn.execute(
        "SELECT count(*) FILTER (WHERE cardinality(lastrevs) > 0), count(*) FROM tgsis.times_vrtx_chunk"
        " WHERE geoid = %s AND times = %s",
        (geoid, GONE),
    ).fetchone()  # type: ignore[misc]
    assert (closed, present) == ((present, present) if versioned else (0, 0))
    if versioned:
        assert present > 0
        # the saved revision still sees the instant
        tgsis.goto_revision(conn, "DEFAULT", saved[geoid])
        at = conn.execute(
            "SELECT count(*) FROM tgsis.times_vrtx WHERE geoid = %s AND times = %s", (geoid, GONE)
        ).fetchone()
        conn.rollback()
        tgsis.goto_version(conn, "DEFAULT")
        assert at == (curved_surface().n_vertices,)
    # the way back keeps the deletion
    conn.execute("SELECT tgsis.check_chunk_conversion(t) FROM unnest(%s::text[]) t", (list(TIME_TABLES),))
    conn.commit()
    _switch2(conn, "rows")
    assert _without_geoid(_answers(conn, geoid)) == on_rows


@pytest.mark.parametrize("storage", ["rows", "chunks"])
def test_a_role_with_fewer_rights_cannot_delete_an_instant(db_dsn: str, conn: Conn, storage: str) -> None:
    from tests.roles import login_roles

    _class(conn, True)
    _store(conn, storage)
    geoid = _series(conn)
    before = _answers(conn, geoid)
    with login_roles(db_dsn, {"reader": "tgsis_reader", "editor": "tgsis_editor"}) as roles:
        reader = roles.connect("reader")
        assert sqlstate(reader, "SELECT tgsis.delete_instant(%s, 2.0)", (geoid,))[0] == "42501"
        if storage == "chunks":  # called directly, the internal refuses as the face would
            assert (
                sqlstate(reader, "SELECT tgsis.delete_chunk_slice('times_vrtx', %s, ARRAY[2.0])", (geoid,))[0]
                == "42501"
            )
        reader.close()
        assert _answers(conn, geoid) == before
        editor = roles.connect("editor")
        assert tgsis.delete_instant(editor, geoid, 2.0)
        editor.commit()
        editor.close()
    assert conn.execute(
        "SELECT count(*) FROM tgsis.times_vrtx WHERE geoid = %s AND times = 2.0", (geoid,)
    ).fetchone() == (0,)


def test_bad_arguments_of_the_slice_delete_are_refused_by_name(conn: Conn) -> None:
    _class(conn, False)
    _store(conn, "chunks")
    geoid = _series(conn)
    before = _answers(conn, geoid)
    for args in (
        ("vrtx", geoid, [2.0]),  # not stored in chunks here, or not a time table
        ("times_vrtx", geoid, []),
        ("times_vrtx", geoid, [2.0, 1.0]),  # (geoid, times) has one value after the object
        ("times_vrtx", None, [2.0]),
        ("times_vrtx", geoid, [None]),
    ):
        state, _ = sqlstate(conn, "SELECT tgsis.delete_chunk_slice(%s, %s, %s::float8[])", args)
        assert state in ("TG100", "TG200"), args
    assert _answers(conn, geoid) == before


@pytest.mark.parametrize("storage", ["rows", "chunks"])
@pytest.mark.parametrize("isolation", ["READ COMMITTED", "REPEATABLE READ"])
def test_delete_instant_after_a_concurrent_face_edit(db_dsn: str, conn: Conn, storage: str, isolation: str) -> None:
    """A psql UPDATE of a vertex of the instant in flight: the delete waits for it; then it deletes the instant
    with the edit (READ COMMITTED) or is refused 40001 (REPEATABLE READ, its snapshot older than the edit), as on
    rows; never an instant half gone or the edit resurrected."""
    _class(conn, False)
    _store(conn, storage)
    geoid = _series(conn)
    first = connect(db_dsn, "first")
    first.execute("UPDATE tgsis.times_vrtx SET x = x + 1 WHERE geoid = %s AND times = 2.0 AND vrtxid = 1", (geoid,))
    failures: list[str] = []

    def deleter(session: Conn) -> None:
        session.execute(f"SET TRANSACTION ISOLATION LEVEL {isolation}")
        session.execute("SELECT count(*) FROM tgsis.times WHERE geoid = %s", (geoid,))  # the snapshot
        try:
            session.execute("SELECT tgsis.delete_instant(%s, 2.0)", (geoid,))
            session.commit()
        except psycopg.Error as exc:
            failures.append(exc.sqlstate or "")
            session.rollback()

    second = Background(db_dsn, "second", deleter)
    wait_until_blocked(conn, second.pid, first.info.backend_pid)
    conn.rollback()
    first.commit()
    first.close()
    second.finish()
    left = conn.execute(
        "SELECT count(*), count(*) FILTER (WHERE vrtxid = 1) FROM tgsis.times_vrtx WHERE geoid = %s AND times = 2.0",
        (geoid,),
    ).fetchone()
    assert left is not None
    if isolation == "READ COMMITTED":
        assert failures == []
        assert left == (0, 0)
    else:
        assert failures == ["40001"]
        assert left[0] > 0 and left[1] == 1
    assert conn.execute("SELECT * FROM tgsis.check_temporal_geometry(%s)", (geoid,)).fetchall() == []


def test_delete_instant_under_a_snapshot_older_than_the_switch_is_40001(db_dsn: str, conn: Conn) -> None:
    _class(conn, False)
    geoid = _series(conn)
    old = connect(db_dsn, "old")
    old.execute("SET TRANSACTION ISOLATION LEVEL REPEATABLE READ")
    old.execute("SELECT count(*) FROM pg_catalog.pg_namespace")  # the snapshot, before the switch
    _switch2(conn, "chunks")
    before = _answers(conn, geoid)
    refused = sqlstate(old, "SELECT tgsis.delete_instant(%s, 2.0)", (geoid,))
    assert refused[0] == "40001", refused
    old.close()
    assert _answers(conn, geoid) == before


# --------------------------------------------------------------------------- model 3: delete_period


@pytest.mark.parametrize("versioned", [False, True])
def test_delete_period_on_chunks_answers_as_on_rows(conn: Conn, versioned: bool) -> None:
    from tests.test_model3_chunks import TABLES, _insert
    from tests.test_model3_chunks import _answers as answers3
    from tests.test_model3_chunks import _class as class3
    from tests.test_model3_chunks import _switch as switch3

    for table in reversed(TABLES):  # model 3 as rows first, whatever TGSIS_TEST_TIME_STORAGE made it
        if conn.execute("SELECT tgsis.stored_in_chunks(%s)", (table,)).fetchone() == (True,):
            conn.execute("SELECT tgsis.store_in_rows(%s)", (table,))
    conn.commit()
    class3(conn, versioned)

    def delete_and_read() -> dict[str, Any]:
        geoid = _insert(conn)
        if versioned:
            tgsis.save_revision(conn, f"before {geoid}")
            conn.commit()
        conn.execute("SET track_functions = 'all'")
        assert tgsis.delete_period(conn, geoid, 1.0)  # the last period
        stored = conn.execute("SELECT tgsis.stored_in_chunks('d4dvrtx')").fetchone() == (True,)
        assert (_calls(conn, "chunk_face_write"), _calls(conn, "delete_chunk_slice")) == ((0, 2) if stored else (0, 0))
        conn.commit()
        return {
            k: [r[1:] for r in v] if k in ("d4dvrtx", "d4dtrgl", "node") else v
            for k, v in answers3(conn, geoid).items()
        }

    on_rows = delete_and_read()
    switch3(conn, "chunks")
    assert delete_and_read() == on_rows


# --------------------------------------------------------------------------- the merge's deletes (check-in likewise)


def _function_calls(conn: Conn, names: tuple[str, ...]) -> dict[str, int]:
    """Calls of tgsis functions counted by the server so far (this session's flushed first)."""
    conn.execute("SELECT pg_stat_force_next_flush()")
    conn.commit()
    conn.execute("SELECT pg_stat_clear_snapshot()")
    rows = conn.execute(
        "SELECT funcname, calls FROM pg_stat_user_functions WHERE schemaname = 'tgsis' AND funcname = ANY (%s)",
        (list(names),),
    ).fetchall()
    conn.commit()
    return {n: dict(rows).get(n, 0) for n in names}


@pytest.mark.parametrize("storage", ["rows", "chunks"])
def test_a_merge_deleting_rows_of_an_instant_writes_chunks_set_based(conn: Conn, storage: str) -> None:
    """The child moves vertices and deletes a triangle at an instant, the parent moves others: the merge writes
    the difference into DEFAULT, its deletes and inserts in one ``tgsis.replace_chunk_rows`` (or
    ``delete_chunk_rows`` when it only deletes) per table on chunks (no face trigger), the same rows as on rows."""
    from tests.test_merge_instants import (
        CHILD_SHIFT,
        NORTH,
        PARENT_SHIFT,
        SOUTH,
        TIMES,
        _cells,
        _shape,
        instants,
        make_series,
        move,
        shifted,
    )

    _store(conn, storage)
    geoid = make_series(conn)
    move(conn, "e1", geoid, 2.0, NORTH, CHILD_SHIFT)
    with tgsis.in_version(conn, "e1"):
        conn.execute("DELETE FROM tgsis.times_trgl WHERE geoid = %s AND times = 2.0 AND trglid = 7", (geoid,))
    conn.commit()
    move(conn, "DEFAULT", geoid, 2.0, SOUTH, PARENT_SHIFT)
    conn.execute("SET track_functions = 'all'")
    names = ("chunk_face_write", "delete_chunk_rows", "insert_chunk_rows", "replace_chunk_rows", "chunk_rows_write")
    before = _function_calls(conn, names)
    result = tgsis.merge_version(conn, "e1")
    assert [(o.objectkey, o.how) for o in result.objects] == [(str(geoid), "automatic")]
    calls = {n: c - before[n] for n, c in _function_calls(conn, names).items()}
    if storage == "chunks":
        assert calls["chunk_face_write"] == 0, calls
        # a table's deletes and inserts in one call (each touched chunk written once)
        assert calls["delete_chunk_rows"] + calls["replace_chunk_rows"] >= 1, calls
        assert calls["chunk_rows_write"] == sum(calls[n] for n in names[1:4]), calls
    else:
        assert calls == {n: 0 for n in names}
    got = instants(conn, "DEFAULT", geoid)
    expected = shifted(shifted(_shape(1), NORTH, CHILD_SHIFT), SOUTH, PARENT_SHIFT)
    assert got[2.0][1].tobytes() == expected.tobytes()
    assert got[2.0][2] == {c for c in _cells() if c[0] != 7}
    assert [got[t][2] == _cells() for t in TIMES] == [True, False, True]
    assert conn.execute("SELECT * FROM tgsis.check_temporal_geometry(%s)", (geoid,)).fetchall() == []


def test_delete_chunk_rows_deletes_the_visible_keys_and_refuses_bad_arguments(db_dsn: str, conn: Conn) -> None:
    from tests.roles import login_roles

    _class(conn, True)
    _store(conn, "chunks")
    geoid = _series(conn)
    call = "SELECT tgsis.delete_chunk_rows('times_vrtx', '{geoid,vrtxid,times}', %s::bigint[], %s::float8[])"
    before = _answers(conn, geoid)
    for args in (
        ([[geoid], [1]], None),  # times missing
        ([[geoid, geoid], [1, 2]], [[2.0]]),  # floats shorter than the keys
        ([[geoid], [1], [3]], [[2.0]]),  # a bigint column too many
    ):
        assert sqlstate(conn, call, args)[0] == "TG100", args
    assert sqlstate(conn, call.replace("'times_vrtx'", "'vrtx'"), ([[geoid], [1]], [[2.0]]))[0] == "TG100"
    assert _answers(conn, geoid) == before
    with login_roles(db_dsn, {"reader": "tgsis_reader"}) as roles:
        reader = roles.connect("reader")
        assert sqlstate(reader, call, ([[geoid], [1]], [[2.0]]))[0] == "42501"
        reader.close()
    assert _answers(conn, geoid) == before
    # one key there, one not: the one there goes, the count says one
    # (a triangle: a vertex of triangles cannot go, TG at commit as on rows)
    row = conn.execute(
        call.replace("'times_vrtx', '{geoid,vrtxid,times}'", "'times_trgl', '{geoid,trglid,times}'"),
        ([[geoid, geoid], [1, 99999]], [[2.0, 2.0]]),
    ).fetchone()
    conn.commit()
    assert row == (1,)
    left = conn.execute(
        "SELECT trglid FROM tgsis.times_trgl WHERE geoid = %s AND times = 2.0 AND trglid < 3 ORDER BY 1", (geoid,)
    ).fetchall()
    assert left == [(0,), (2,)]
    after = _answers(conn, geoid)
    assert after["triangles_at -0.0"] == before["triangles_at -0.0"]
    assert len(after["triangles_at 2.0"]) == len(before["triangles_at 2.0"]) - 1
