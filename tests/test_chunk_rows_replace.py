"""``tgsis.replace_chunk_rows``: a model-2/3 difference's deletes and inserts of one table in one write (issue 40).

The check-in and merges of models 2 and 3 by difference delete the rows whose
key went or whose values changed and insert the new and changed ones. On a
time table stored in chunks that was ``tgsis.delete_chunk_rows`` then
``tgsis.insert_chunk_rows``: every changed chunk written twice (two chunk
versions, the first dead at once). One call of ``tgsis.replace_chunk_rows``
writes each touched chunk once, with the answers of the two calls
(docs/storage.md, "Snapshots at t").
"""

from __future__ import annotations

from typing import Any

import numpy as np
import psycopg
import pytest

import tgsis
from tests.merge_data import sqlstate
from tests.sessions import Background, connect, wait_until_blocked
from tests.test_model2_chunks import NAN_PAYLOAD, _bits, _class, _hostile_series, _store

Conn = psycopg.Connection[Any]

#: the instant whose rows are replaced (not exactly 0.3)
AT = 0.1 + 0.2
DELETE = "tgsis.delete_chunk_rows('times_vrtx', '{geoid,vrtxid,times}', %b::bigint[], %b::float8[])"
INSERT = "tgsis.insert_chunk_rows('times_vrtx', '{geoid,vrtxid,times,x,y,z}', %b::bigint[], %b::float8[])"
REPLACE = (
    "tgsis.replace_chunk_rows('times_vrtx', '{geoid,vrtxid,times}', %b::bigint[], %b::float8[],"
    " '{geoid,vrtxid,times,x,y,z}', %b::bigint[], %b::float8[])"
)


def _chunk_writes(conn: Conn) -> tuple[int, int, int]:
    """(inserted, updated, deleted) chunk row versions of times_vrtx_chunk not yet in pg_stat_user_tables: those
    of this transaction and of earlier ones not yet flushed (so compared before and after, in one transaction)."""
    row = conn.execute(
        "SELECT coalesce(sum(n_tup_ins), 0), coalesce(sum(n_tup_upd), 0), coalesce(sum(n_tup_del), 0)"
        " FROM pg_stat_xact_user_tables WHERE schemaname = 'tgsis' AND relname = 'times_vrtx_chunk'"
    ).fetchone()
    assert row is not None
    return int(row[0]), int(row[1]), int(row[2])


def _arguments(geoid: int) -> tuple[Any, ...]:
    """The keys to delete and the rows to insert at AT: vertices 0..9 changed (-0.0, a subnormal, NaN with a
    payload), a key that is not there (skipped), a new vertex 2000 (chunk 1's slots to it holes). (A vertex that
    triangles use cannot go: the commit refuses it, on rows as on chunks.)"""
    gone = [*range(10), 99999]
    ids = [*range(10), 2000]
    x = [-0.0, 5e-324, float(NAN_PAYLOAD), *np.linspace(1.0, 2.0, 7).tolist(), 7.5]
    return (
        [[geoid] * len(gone), gone],
        [[AT] * len(gone)],
        [[geoid] * len(ids), ids],
        [[AT] * len(ids), x, [-0.0] * len(ids), list(reversed(x))],
    )


def _faces(conn: Conn, geoid: int) -> list[tuple[Any, ...]]:
    rows = conn.execute(
        "SELECT float8send(times), vrtxid, float8send(x), float8send(y), float8send(z) FROM tgsis.times_vrtx"
        " WHERE geoid = %s ORDER BY 1, 2",
        (geoid,),
    ).fetchall()
    conn.rollback()
    return rows


def _x_bits(conn: Conn, geoid: int, ids: tuple[int, ...]) -> dict[int, int]:
    """Vertex id: the bits of its x at AT, of those of ``ids`` there."""
    rows = conn.execute(
        "SELECT vrtxid, float8send(x) FROM tgsis.times_vrtx WHERE geoid = %s AND times = %s AND vrtxid = ANY (%s)",
        (geoid, AT, list(ids)),
    ).fetchall()
    conn.rollback()
    return {int(i): int.from_bytes(bytes(x), "big", signed=True) for i, x in rows}


@pytest.mark.parametrize("versioned", [False, True])
def test_replace_answers_as_delete_then_insert_and_writes_each_chunk_once(conn: Conn, versioned: bool) -> None:
    """Twin series: one by delete_chunk_rows then insert_chunk_rows, the other by replace_chunk_rows; the same
    rows bit for bit, the same count of rows deleted, and each touched chunk written once (unversioned: one
    in-place rewrite each; versioned, after a saved revision: each closed and written anew once), where the two
    calls rewrote chunk 0 twice."""
    _class(conn, versioned)
    _store(conn, "chunks")
    series = _hostile_series()  # 1600 vertices an instant: chunks 0 and 1
    a = tgsis.insert_feature(conn, "horizons", series)
    b = tgsis.insert_feature(conn, "horizons", series)
    conn.commit()
    if versioned:
        tgsis.save_revision(conn, "before")
        conn.commit()
    deletes, times, inserts, values = _arguments(a)
    start = _chunk_writes(conn)
    two = conn.execute(f"SELECT {DELETE}", (deletes, times)).fetchone()
    conn.execute(f"SELECT {INSERT}", (inserts, values))
    two_writes = tuple(e - s for e, s in zip(_chunk_writes(conn), start, strict=True))
    conn.commit()
    start = _chunk_writes(conn)
    one = conn.execute(f"SELECT * FROM {REPLACE}", _arguments(b)).fetchone()
    one_writes = tuple(e - s for e, s in zip(_chunk_writes(conn), start, strict=True))
    conn.commit()
    assert two == (10,) and one == (10, 2)  # 99999 skipped; chunks 0 and 1 written
    assert _faces(conn, a) == _faces(conn, b)
    got = _x_bits(conn, b, (0, 1, 2, 2000))
    assert [got[i] for i in (0, 1, 2, 2000)] == _bits([-0.0, 5e-324, NAN_PAYLOAD, 7.5])
    # (inserted, updated, deleted) chunk row versions: the two calls rewrote chunk 0 twice
    if versioned:
        assert (one_writes, two_writes) == ((2, 2, 0), (2, 3, 0))
    else:
        assert (one_writes, two_writes) == ((0, 2, 0), (0, 3, 0))
    check = "SELECT * FROM tgsis.check_temporal_geometry(%s)"  # (the NaN vertex is named: the same on both)
    assert conn.execute(check, (a,)).fetchall() == conn.execute(check, (b,)).fetchall()
    conn.rollback()


def test_replace_refuses_as_the_two_calls_refuse(db_dsn: str, conn: Conn) -> None:
    from tests.roles import login_roles

    _class(conn, True)
    _store(conn, "chunks")
    geoid = tgsis.insert_feature(conn, "horizons", _hostile_series(side=12))
    conn.commit()
    before = _faces(conn, geoid)
    deletes, times, inserts, values = _arguments(geoid)
    # a row whose key is there and not deleted: 23505, as insert_chunk_rows (nothing written)
    kept = ([[geoid, geoid], [0, 20]], [[AT, AT], [1.0, 1.0], [2.0, 2.0], [3.0, 3.0]])
    assert sqlstate(conn, f"SELECT {INSERT}", kept)[0] == "23505"
    assert sqlstate(conn, f"SELECT * FROM {REPLACE}", ([[geoid], [0]], [[AT]], *kept))[0] == "23505"
    # keys or rows of another shape, a table not in chunks: TG100 by name
    assert sqlstate(conn, f"SELECT * FROM {REPLACE}", ([[geoid], [0]], None, inserts, values))[0] == "TG100"
    assert sqlstate(conn, f"SELECT * FROM {REPLACE}", (deletes, times, inserts, values[:2]))[0] == "TG100"
    other = REPLACE.replace("'times_vrtx'", "'vrtx'", 1)
    assert sqlstate(conn, f"SELECT * FROM {other}", (deletes, times, inserts, values))[0] == "TG100"
    with login_roles(db_dsn, {"reader": "tgsis_reader"}) as roles:
        reader = roles.connect("reader")
        assert sqlstate(reader, f"SELECT * FROM {REPLACE}", (deletes, times, inserts, values))[0] == "42501"
        assert sqlstate(reader, f"SELECT {DELETE}", (deletes, times))[0] == "42501"
        reader.close()
    assert _faces(conn, geoid) == before


def test_a_second_session_replacing_rows_of_the_object_waits_then_writes(db_dsn: str, conn: Conn) -> None:
    """Two sessions replace rows of one object at once: the second waits for the first's object lock, then reads
    what it committed (READ COMMITTED): it deletes the first's new vertex and replaces one the first replaced;
    nothing lost, nothing twice."""
    _class(conn, False)
    _store(conn, "chunks")
    geoid = tgsis.insert_feature(conn, "horizons", _hostile_series(side=12))  # 144 vertices: chunk 0
    conn.commit()
    first = connect(db_dsn, "first")
    row = first.execute(f"SELECT * FROM {REPLACE}", _arguments(geoid)).fetchone()
    assert row == (10, 2)
    answers: list[Any] = []

    def second_writer(session: Conn) -> None:
        answers.append(
            session.execute(
                f"SELECT * FROM {REPLACE}",
                ([[geoid] * 2, [2000, 5]], [[AT] * 2], [[geoid], [5]], [[AT], [9.0], [1.0], [2.0]]),
            ).fetchone()
        )
        session.commit()

    second = Background(db_dsn, "second", second_writer)
    wait_until_blocked(conn, second.pid, first.info.backend_pid)
    conn.rollback()
    first.commit()
    first.close()
    second.finish()
    assert answers == [(2, 2)]  # both keys visible after the first's commit; chunk 0 rewritten, chunk 1 emptied
    got = _x_bits(conn, geoid, (0, 5, 6, 2000))
    assert sorted(got) == [0, 5, 6]
    assert [got[i] for i in (0, 5, 6)] == _bits([-0.0, 9.0, np.linspace(1.0, 2.0, 7)[3]])


def test_a_merge_writes_each_changed_chunk_once(conn: Conn) -> None:
    """A model-2 merge by difference moving vertices at an instant (the child's north, the parent's south): the
    changed chunk of times_vrtx is written once (one chunk version), where the delete and insert calls wrote it
    twice (an insert, then an in-place rewrite); the rows are the expected ones bit for bit."""
    from tests.test_merge_instants import (
        CHILD_SHIFT,
        NORTH,
        PARENT_SHIFT,
        SOUTH,
        _shape,
        instants,
        make_series,
        move,
        shifted,
    )

    _store(conn, "chunks")
    geoid = make_series(conn)
    move(conn, "e1", geoid, 2.0, NORTH, CHILD_SHIFT)
    move(conn, "DEFAULT", geoid, 2.0, SOUTH, PARENT_SHIFT)
    tgsis.save_revision(conn, "before the merge")  # DEFAULT's chunks an older revision's: closed by the merge
    conn.commit()
    conn.execute("SET track_functions = 'all'")
    start = _chunk_writes(conn)
    result = tgsis.merge_version(conn, "e1")
    inserted, updated, deleted = (e - s for e, s in zip(_chunk_writes(conn), start, strict=True))
    calls = conn.execute(
        "SELECT coalesce(sum(calls) FILTER (WHERE funcname = 'replace_chunk_rows'), 0),"
        " coalesce(sum(calls) FILTER (WHERE funcname IN ('delete_chunk_rows', 'insert_chunk_rows')), 0)"
        " FROM pg_stat_xact_user_functions WHERE schemaname = 'tgsis'"
    ).fetchone()
    conn.commit()
    assert [(o.objectkey, o.how) for o in result.objects] == [(str(geoid), "automatic")]
    assert calls == (1, 0), (calls, inserted, updated, deleted)  # times_vrtx: one call; times_trgl unchanged
    # one changed chunk (instant 2.0, chunk 0): one version inserted, DEFAULT's older one closed, and the merge's
    # one other update; the delete and insert calls wrote (1, 3, 0): the new version rewritten once more
    assert (inserted, updated, deleted) == (1, 2, 0), (inserted, updated, deleted)
    got = instants(conn, "DEFAULT", geoid)
    expected = shifted(shifted(_shape(1), NORTH, CHILD_SHIFT), SOUTH, PARENT_SHIFT)
    assert got[2.0][1].tobytes() == expected.tobytes()


def test_a_key_deleted_and_inserted_again_with_other_bits_is_written_as_the_two_calls_wrote(conn: Conn) -> None:
    """Every vertex of the instant -0.0 deleted and inserted again at 0.0 (equal by float8 =, not by bits): the
    chunk keeps one key for its slots, so the deletes go first (the chunk emptied), then the rows (a chunk keyed
    0.0), as delete_chunk_rows then insert_chunk_rows do; the same rows as they give, bit for bit."""
    _class(conn, False)
    _store(conn, "chunks")
    series = _hostile_series(side=12)  # 144 vertices an instant: one chunk
    a = tgsis.insert_feature(conn, "horizons", series)
    b = tgsis.insert_feature(conn, "horizons", series)
    conn.commit()
    ids = list(range(144))
    x, y, z = (series.surfaces[0].vertices[:, i].tolist() for i in range(3))

    def arguments(geoid: int) -> tuple[Any, ...]:
        return ([[geoid] * 144, ids], [[-0.0] * 144], [[geoid] * 144, ids], [[0.0] * 144, x, y, z])

    deletes, times, inserts, values = arguments(a)
    assert conn.execute(f"SELECT {DELETE}", (deletes, times)).fetchone() == (144,)
    conn.execute(f"SELECT {INSERT}", (inserts, values))
    assert conn.execute(f"SELECT * FROM {REPLACE}", arguments(b)).fetchone() == (144, 2)  # emptied, then new
    keys = "SELECT DISTINCT float8send(times) FROM tgsis.times_vrtx_chunk WHERE geoid = %s AND times = 0 ORDER BY 1"
    assert conn.execute(keys, (b,)).fetchall() == conn.execute(keys, (a,)).fetchall() == [(bytes(8),)]
    rows = "SELECT float8send(times), vrtxid, float8send(x) FROM tgsis.times_vrtx WHERE geoid = %s ORDER BY 1, 2"
    assert conn.execute(rows, (a,)).fetchall() == conn.execute(rows, (b,)).fetchall()
    conn.rollback()  # (the instants' table still says -0.0)
