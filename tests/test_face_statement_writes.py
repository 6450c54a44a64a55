"""Writes of many rows through the relational face: one rewrite per touched chunk per statement (issue 40).

On chunks, ``tgsis.vrtx`` is a view whose row trigger (its generated ``tgsis.vrtx_face_row``) only keeps each
row, and whose statement trigger (``tgsis.chunk_face_write``) checks and writes all of them when the
statement ends (docs/storage.md, "The relational face: views with today's names"). Before, an INSERT
or a DELETE rewrote its chunk for every row. What must hold is what today's row storage does, so every
test runs on both storages (``TGSIS_TEST_STORAGE``) and checks the same outcomes; the count of chunk
writes is checked on chunks only. Hostile cases: the session's float output digits, a key inserted
twice or already there, savepoints, functions and CTEs, two sessions writing one chunk.
"""

from __future__ import annotations

import math
import struct
from typing import Any

import psycopg
import pytest

import tgsis
from tests.sessions import Background, connect, wait_until_blocked
from tests.storage_data import classes_as_rows

Conn = psycopg.Connection[Any]


@pytest.fixture(autouse=True)
def _classes_as_rows(db_dsn: str) -> None:
    """The classes these tests make start as rows: they switch them to chunks themselves, or compare with a rows
    twin (docs/storage.md, "Property chunks by default: the rule")."""
    classes_as_rows(db_dsn)


FIRST = 2048  # new ids 2048 .. 2048 + 3071: exactly chunks 2, 3 and 4 of the fault (ids 0 .. 143 in chunk 0)
NEW = 3072


def _chunk_writes(conn: Conn) -> int:
    """Tuples this transaction inserted, updated or deleted in the vertex chunks (pg_stat_xact_user_tables)."""
    row = conn.execute(
        "SELECT coalesce(sum(n_tup_ins + n_tup_upd + n_tup_del), 0) FROM pg_stat_xact_user_tables "
        "WHERE schemaname = 'tgsis' AND relname = 'vrtx_chunk'"
    ).fetchone()
    assert row is not None
    return int(row[0])


def _count(conn: Conn, geoid: int, where: str = "true") -> int:
    row = conn.execute(f"SELECT count(*) FROM tgsis.vrtx WHERE geoid = %s AND {where}", (geoid,)).fetchone()  # noqa: S608
    assert row is not None
    return int(row[0])


def _sqlstate(conn: Conn, statement: str, params: Any = ()) -> str | None:
    try:
        with conn.transaction():
            conn.execute(statement, params)
    except psycopg.Error as exc:
        return exc.sqlstate
    return None


def _insert(lo: int, hi: int) -> str:
    return (
        "INSERT INTO tgsis.vrtx SELECT %s, i, i * 0.5, -i * 0.25, i / 3.0 "  # noqa: S608
        f"FROM generate_series({lo}::bigint, {hi}::bigint) i"
    )


def test_insert_update_delete_of_thousands_of_rows_write_each_chunk_once(
    conn: Conn, fault_clone: int, db_storage: str
) -> None:
    geoid = fault_clone
    with tgsis.in_version(conn, "e1"):
        conn.commit()
        assert conn.execute(_insert(FIRST, FIRST + NEW - 1), (geoid,)).rowcount == NEW
        if db_storage == "chunks":
            assert _chunk_writes(conn) <= 3  # three new chunks, each written once (was one rewrite per row)
        # read your writes: the next statement of the transaction sees them
        assert _count(conn, geoid, f"vrtxid >= {FIRST}") == NEW
        conn.commit()
        assert (
            conn.execute(f"UPDATE tgsis.vrtx SET z = -z WHERE geoid = %s AND vrtxid >= {FIRST}", (geoid,)).rowcount
            == NEW
        )
        if db_storage == "chunks":
            # (in e1's working revision: a few tuple writes per chunk, the writer's own steps, not one per row)
            assert _chunk_writes(conn) <= 9
        conn.commit()
        deleted = conn.execute(
            f"DELETE FROM tgsis.vrtx WHERE geoid = %s AND vrtxid >= {FIRST} AND mod(vrtxid, 2) = 0 RETURNING vrtxid",
            (geoid,),
        ).fetchall()
        assert sorted(r[0] for r in deleted) == list(range(FIRST, FIRST + NEW, 2))
        if db_storage == "chunks":
            assert _chunk_writes(conn) <= 9  # 1,536 rows deleted
        conn.commit()
        row = conn.execute(
            f"SELECT count(*), sum(vrtxid), sum(z * 3 + vrtxid) FROM tgsis.vrtx WHERE geoid = %s AND vrtxid >= {FIRST}",
            (geoid,),
        ).fetchone()
        conn.rollback()
    odd = list(range(FIRST + 1, FIRST + NEW, 2))
    assert row is not None and row[0] == NEW // 2 and row[1] == sum(odd)
    assert abs(row[2]) < 1e-6  # z = -i / 3
    # DEFAULT never saw them, and the transaction's tables of kept rows are gone with it (ON COMMIT DROP)
    assert _count(conn, geoid, f"vrtxid >= {FIRST}") == 0
    if db_storage == "chunks":
        kept = conn.execute("SELECT to_regclass(tgsis.chunk_face_work('vrtx', 'rows'))").fetchone()
        assert kept == (None,)
    conn.rollback()


NAN_PAYLOAD = struct.unpack(">d", bytes.fromhex("7ff8000000000123"))[0]
NEGATIVE_NAN = struct.unpack(">d", bytes.fromhex("fff0000000000001"))[0]  # a signalling NaN's bits, sign set
VALUES = [
    -0.0,
    math.nan,
    NAN_PAYLOAD,
    NEGATIVE_NAN,
    5e-324,
    0.1 + 0.2,
    1 / 3,
    -1.7976931348623157e308,
    math.inf,
    2.0**-1074 * 3,
]


def _bits(value: float) -> bytes:
    return struct.pack(">d", value)


@pytest.mark.parametrize("digits", [-15, 3])
def test_values_are_written_bit_for_bit_whatever_the_session_s_float_digits(
    conn: Conn, fault_clone: int, digits: int
) -> None:
    """The rows are kept typed between the row and the statement trigger (never as text): every bit arrives, a NaN's
    payload and sign included, whatever the session's extra_float_digits (the values sent in binary: ``%b``)."""
    geoid = fault_clone
    assert _bits(NAN_PAYLOAD).hex() == "7ff8000000000123"  # (the client keeps the payload)
    with tgsis.in_version(conn, "e1"):
        conn.commit()
        conn.execute(f"SET extra_float_digits = {digits}")
        for k, value in enumerate(VALUES):
            conn.execute("INSERT INTO tgsis.vrtx VALUES (%s, %s, %b, %b, %s)", (geoid, FIRST + k, value, value, 1.0))
        # one INSERT ... SELECT of all of them (many rows of one statement)
        conn.execute(
            "INSERT INTO tgsis.vrtx SELECT geoid, vrtxid + 100, x, y, z FROM tgsis.vrtx "
            f"WHERE geoid = %s AND vrtxid >= {FIRST}",
            (geoid,),
        )
        conn.execute(
            f"UPDATE tgsis.vrtx SET z = y WHERE geoid = %s AND vrtxid >= {FIRST}", (geoid,)
        )  # an UPDATE keeps them too
        conn.execute(f"DELETE FROM tgsis.vrtx WHERE geoid = %s AND vrtxid = {FIRST + 101}", (geoid,))
        rows = conn.execute(
            f"SELECT vrtxid, float8send(x), float8send(z) FROM tgsis.vrtx WHERE geoid = %s AND vrtxid >= {FIRST} ORDER BY 1",
            (geoid,),
        ).fetchall()
        conn.rollback()
    expected = [(FIRST + k, _bits(v), _bits(v)) for k, v in enumerate(VALUES)]
    expected += [(FIRST + 100 + k, _bits(v), _bits(v)) for k, v in enumerate(VALUES) if k != 1]
    assert sorted((r[0], bytes(r[1]), bytes(r[2])) for r in rows) == sorted(expected)


def test_a_key_there_or_twice_fails_the_statement_and_writes_nothing(conn: Conn, fault_clone: int) -> None:
    geoid = fault_clone
    with tgsis.in_version(conn, "e1"):
        conn.commit()
        before = _count(conn, geoid)
        # one row of the INSERT ... SELECT is there (id 143): 23505, none of the other 3,000 written
        assert _sqlstate(conn, _insert(143, 3143), (geoid,)) == "23505"
        # the statement inserts one key twice
        twice = "INSERT INTO tgsis.vrtx SELECT %s, 5000 + mod(i, 3), 0, 0, 0 FROM generate_series(0, 3) i"
        assert _sqlstate(conn, twice, (geoid,)) == "23505"
        # a key moved onto a key that is there
        assert _sqlstate(conn, "UPDATE tgsis.vrtx SET vrtxid = 7 WHERE geoid = %s AND vrtxid = 8", (geoid,)) == "23505"
        assert _count(conn, geoid) == before
        # the failed statements left nothing behind for the next one of the same transaction
        assert conn.execute(_insert(FIRST, FIRST + 9), (geoid,)).rowcount == 10
        assert _count(conn, geoid) == before + 10
        conn.rollback()


def test_a_row_met_twice_by_one_statement_answers_as_the_row_view(conn: Conn, fault_clone: int) -> None:
    """Writable CTEs hand every sub-statement's rows to one flush: their order decides, as row by row on rows."""
    geoid = fault_clone
    bits = "SELECT float8send(x), float8send(y), float8send(z) FROM tgsis.vrtx WHERE geoid = %s AND vrtxid = %s"
    with tgsis.in_version(conn, "e1"):
        conn.commit()
        before = _count(conn, geoid)
        x20 = conn.execute("SELECT x FROM tgsis.vrtx WHERE geoid = %s AND vrtxid = 20", (geoid,)).fetchone()
        # a key deleted, then inserted again by the same statement: one write of its slot
        moved = conn.execute(
            "WITH d AS (DELETE FROM tgsis.vrtx WHERE geoid = %s AND vrtxid = 20 RETURNING *) "
            "INSERT INTO tgsis.vrtx SELECT geoid, vrtxid, x + 1, y, z FROM d",
            (geoid,),
        ).rowcount
        assert moved == 1
        assert x20 is not None
        assert conn.execute("SELECT x FROM tgsis.vrtx WHERE geoid = %s AND vrtxid = 20", (geoid,)).fetchone() == (
            x20[0] + 1,
        )
        assert _count(conn, geoid) == before
        kept = [conn.execute(bits, (geoid, i)).fetchone() for i in (21, 22, 23)]
        # a row updated twice (a join meeting it twice; two WITH queries): 21000, nothing written
        twice = (
            "UPDATE tgsis.vrtx v SET z = t.z FROM (VALUES (21, 1.0), (21, 2.0)) t(id, z) "
            "WHERE v.geoid = %s AND v.vrtxid = t.id"
        )
        assert _sqlstate(conn, twice, (geoid,)) == "21000"
        ctes = (
            "WITH a AS (UPDATE tgsis.vrtx SET y = 1 WHERE geoid = %s AND vrtxid = 22 RETURNING vrtxid), "
            "b AS (UPDATE tgsis.vrtx SET y = 2 WHERE geoid = %s AND vrtxid = 22 RETURNING vrtxid) SELECT 1"
        )
        assert _sqlstate(conn, ctes, (geoid, geoid)) == "21000"
        # a row updated, then deleted, by one statement (the main query reads a first): refused, nothing written
        # (the row view: 27000 in DEFAULT, 40001 in this version; the face: 27000)
        gone = (
            "WITH a AS (UPDATE tgsis.vrtx SET y = 5 WHERE geoid = %s AND vrtxid = 23 RETURNING vrtxid), "
            "b AS (DELETE FROM tgsis.vrtx WHERE geoid = %s AND vrtxid = 23 RETURNING vrtxid) "
            "SELECT (SELECT count(*) FROM a) + (SELECT count(*) FROM b)"
        )
        assert _sqlstate(conn, gone, (geoid, geoid)) in ("27000", "40001")
        assert [conn.execute(bits, (geoid, i)).fetchone() for i in (21, 22, 23)] == kept
        assert _count(conn, geoid) == before
        conn.rollback()


def test_a_row_deleted_then_updated_by_one_statement_is_deleted_and_the_update_skipped(
    conn: Conn, fault_clone: int
) -> None:
    """The row view skips an UPDATE of a row its statement deleted before (PostgreSQL's own rule for a row
    changed by the same command): the row is gone and the UPDATE counts 0. So does the face: its row trigger
    finds the key among the statement's deleted rows and skips the row (docs/storage.md)."""
    geoid = fault_clone
    with tgsis.in_version(conn, "e1"):
        conn.commit()
        before = _count(conn, geoid)
        got = conn.execute(
            "WITH a AS (UPDATE tgsis.vrtx SET y = 5 WHERE geoid = %s AND vrtxid = 24 RETURNING vrtxid), "
            "b AS (DELETE FROM tgsis.vrtx WHERE geoid = %s AND vrtxid = 24 RETURNING vrtxid) "
            "SELECT (SELECT count(*) FROM b), (SELECT count(*) FROM a)",
            (geoid, geoid),
        ).fetchone()
        assert got == (1, 0)
        assert _count(conn, geoid) == before - 1
        assert _count(conn, geoid, "vrtxid = 24") == 0
        conn.rollback()


def test_savepoints_functions_ctes_and_returning_see_the_statement_s_rows(conn: Conn, fault_clone: int) -> None:
    geoid = fault_clone
    conn.execute(
        "CREATE FUNCTION pg_temp.insert_and_count(g bigint, lo bigint, hi bigint) RETURNS bigint LANGUAGE plpgsql AS $$ "
        "BEGIN INSERT INTO tgsis.vrtx SELECT g, i, 1, 2, 3 FROM generate_series(lo, hi) i; "
        "RETURN (SELECT count(*) FROM tgsis.vrtx WHERE geoid = g AND vrtxid BETWEEN lo AND hi); END $$"
    )
    with tgsis.in_version(conn, "e1"):
        conn.commit()
        # a function's INSERT is written when its own statement ends: its next statement reads it
        assert conn.execute("SELECT pg_temp.insert_and_count(%s, 4000, 4099)", (geoid,)).fetchone() == (100,)
        # savepoint: the rows of the rolled back statement are not written, the ones around it are
        conn.execute(_insert(FIRST, FIRST + 9), (geoid,))
        conn.execute("SAVEPOINT s")
        conn.execute(_insert(FIRST + 10, FIRST + 19), (geoid,))
        conn.execute("ROLLBACK TO SAVEPOINT s")
        conn.execute(_insert(FIRST + 20, FIRST + 29), (geoid,))
        # a CTE's INSERT with RETURNING, and a DELETE in the same query
        returned = conn.execute(
            "WITH i AS (INSERT INTO tgsis.vrtx SELECT %s, i, 0, 0, 0 FROM generate_series(4100, 4104) i RETURNING vrtxid), "
            "d AS (DELETE FROM tgsis.vrtx WHERE geoid = %s AND vrtxid BETWEEN 4000 AND 4009 RETURNING vrtxid) "
            "SELECT (SELECT array_agg(vrtxid ORDER BY vrtxid) FROM i), (SELECT count(*) FROM d)",
            (geoid, geoid),
        ).fetchone()
        assert returned == ([4100, 4101, 4102, 4103, 4104], 10)
        conn.commit()
        ids = [
            r[0]
            for r in conn.execute(
                f"SELECT vrtxid FROM tgsis.vrtx WHERE geoid = %s AND vrtxid >= {FIRST} ORDER BY 1", (geoid,)
            )
        ]
        conn.rollback()
    want = [*range(FIRST, FIRST + 10), *range(FIRST + 20, FIRST + 30), *range(4010, 4105)]
    assert ids == want


def test_two_sessions_inserting_into_one_chunk_keep_both_rows(
    conn: Conn, fault_clone: int, db_dsn: str, db_storage: str
) -> None:
    """On chunks the second waits for the first's chunk lock, then merges into what it committed: no lost insert."""
    geoid = fault_clone
    a = connect(db_dsn, "first")
    observer = connect(db_dsn, "observer", autocommit=True)
    try:
        tgsis.goto_version(a, "e1")
        a.commit()
        a.execute(_insert(FIRST, FIRST + 499), (geoid,))  # chunk 2, not committed
        b = Background(
            db_dsn, "second", lambda c: c.execute(_insert(FIRST + 500, FIRST + 999), (geoid,)).rowcount, version="e1"
        )
        if db_storage == "chunks":
            wait_until_blocked(observer, b.pid, a.info.backend_pid)
        else:
            b.thread.join(30)  # rows: other keys, no wait
        a.commit()
        assert b.finish() == 500
        # and the other way round: the second session deletes rows the first then changed meanwhile
        a.execute(f"UPDATE tgsis.vrtx SET z = 99 WHERE geoid = %s AND vrtxid BETWEEN {FIRST} AND {FIRST + 9}", (geoid,))
        b = Background(
            db_dsn,
            "deleter",
            lambda c: c.execute(
                f"DELETE FROM tgsis.vrtx WHERE geoid = %s AND vrtxid BETWEEN {FIRST} AND {FIRST + 9}", (geoid,)
            ),
            version="e1",
        )
        wait_until_blocked(observer, b.pid, a.info.backend_pid)
        a.commit()
        with pytest.raises(psycopg.errors.SerializationFailure, match="concurrent update"):
            b.finish()
    finally:
        a.close()
        observer.close()
    with tgsis.in_version(conn, "e1"):
        conn.commit()
        row = conn.execute(
            f"SELECT count(*), count(*) FILTER (WHERE z = 99) FROM tgsis.vrtx WHERE geoid = %s AND vrtxid >= {FIRST}",
            (geoid,),
        ).fetchone()
        conn.rollback()
    assert row == (1000, 10)


# One key met by two or three writable WITH queries of one statement, in every order: the face answers as the row
# view. The row view is not written down here: each statement runs on a database stored in rows and on one in
# chunks (the same fault cloned), and the answers (the SQLSTATE, or each query's row count and the keys' rows
# after it, bit for bit) are compared. KEY is a vertex of the fault, NEWKEY none, NEXT the vertex a key change
# moves onto KEY ("m"; "v" updates NEXT in place, "x" deletes it); in DEFAULT (rows of the working revision,
# changed in place) and in e1 (inherited rows, closed and written anew).
KEY, NEXT, NEWKEY = 30, 31, 5000
_OPS = {
    "i": "INSERT INTO tgsis.vrtx VALUES (%(g)s, %(k)s, 7.5, -7.5, 0.125) RETURNING vrtxid",
    "u": "UPDATE tgsis.vrtx SET y = y + 1 WHERE geoid = %(g)s AND vrtxid = %(k)s RETURNING vrtxid",
    "d": "DELETE FROM tgsis.vrtx WHERE geoid = %(g)s AND vrtxid = %(k)s RETURNING vrtxid",
    "m": "UPDATE tgsis.vrtx SET vrtxid = %(k)s, z = z - 1 WHERE geoid = %(g)s AND vrtxid = %(n)s RETURNING vrtxid",
    "v": "UPDATE tgsis.vrtx SET x = x * 2 WHERE geoid = %(g)s AND vrtxid = %(n)s RETURNING vrtxid",  # NEXT in place
    "x": "DELETE FROM tgsis.vrtx WHERE geoid = %(g)s AND vrtxid = %(n)s RETURNING vrtxid",  # NEXT deleted
    # NEXT moved onto KEY by a join that meets it twice
    "M": "UPDATE tgsis.vrtx SET vrtxid = %(k)s, z = z - 1 FROM (VALUES (1), (2)) AS j(n) "
    "WHERE geoid = %(g)s AND vrtxid = %(n)s RETURNING vrtxid",
}
_ORDERS = [a + b for a in "iud" for b in "iud"] + [a + b + c for a in "iud" for b in "iud" for c in "iud"]
_ORDERS += [o for o in (a + b for a in "iudm" for b in "iudm") if "m" in o] + ["mv", "mx", "vm", "xm", "vdu", "vdi"]
_ORDERS += ["M", "Mv", "vM", "mvx"]  # a join meeting the row it moves twice; a move, an update, a delete of one row


def _sub_statements(order: str) -> str:
    """The WITH queries of ``order``, run in its order (the main query reads them one after the other)."""
    names = [f"w{n}" for n in range(len(order))]
    ctes = ", ".join(f"{name} AS ({_OPS[op]})" for name, op in zip(names, order, strict=True))
    return f"WITH {ctes} SELECT " + ", ".join(f"(SELECT count(*) FROM {name})" for name in names)  # noqa: S608


def _answers(dsn: str, geoid: int, version: str) -> list[tuple[str, str, Any]]:
    answers: list[tuple[str, str, Any]] = []
    with psycopg.connect(dsn) as db, tgsis.in_version(db, version):
        db.commit()
        for key in (KEY, NEWKEY):
            for order in _ORDERS:
                params = {"g": geoid, "k": key, "n": NEXT}
                try:
                    with db.transaction():
                        counts = db.execute(_sub_statements(order), params).fetchone()
                        after = db.execute(
                            "SELECT vrtxid, float8send(x), float8send(y), float8send(z) FROM tgsis.vrtx "
                            "WHERE geoid = %(g)s AND vrtxid IN (%(k)s, %(n)s) ORDER BY 1",
                            params,
                        ).fetchall()
                        answers.append((order, str(key), (counts, after)))
                        raise _Undo
                except _Undo:
                    pass
                except psycopg.Error as exc:
                    answers.append((order, str(key), exc.sqlstate))
        db.rollback()
    return answers


class _Undo(Exception):
    """Rolls a statement's savepoint back once its answer is read."""


@pytest.mark.parametrize("version", ["DEFAULT", "e1"])
def test_every_order_of_writes_on_one_key_in_one_statement_answers_as_the_row_view(
    make_database: Any, built_once_by_storage: Any, version: str
) -> None:
    on = {
        storage: _answers(
            make_database(built_once_by_storage(storage, "fault_clone")[0]),
            built_once_by_storage(storage, "fault_clone")[1],
            version,
        )
        for storage in ("rows", "chunks")
    }
    assert len(on["rows"]) == len(on["chunks"]) == 2 * len(_ORDERS)
    differing = [(a, b[2]) for a, b in zip(on["rows"], on["chunks"], strict=True) if a != b]
    # a key moved away by one UPDATE WITH query, then updated again by a second UPDATE WITH query (which fires no
    # BEFORE statement trigger of its own) or met again by the same UPDATE's join: skipped, as the row view skips
    # it (the row trigger marks the moved key when it keeps the row; the face refused these statements before)
    # the row view's own defect: a row of an UPDATE that is not the statement's first row of the view is queued and
    # written when the statement ends, where a key deleted by another WITH query meanwhile looks deleted by another
    # transaction: 40001 (a retry fails again); the face skips it, as the row view's one-row path does ("du")
    defect = [(a, b) for a, b in differing if a[0] == "vdu" and a[2] == "40001" and not isinstance(b, str)]
    assert [b[0] for _, b in defect] == [(1, 1, 0)] * len(defect)
    assert [d for d in differing if d not in defect] == []


def test_the_row_trigger_is_the_face_s_own_static_function(conn: Conn, fault_clone: int, db_storage: str) -> None:
    """The face's row trigger is its own function, generated with static SQL by tgsis.create_chunk_face
    (tgsis.vrtx_face_row: a name from the table's, stable across pg_dump/restore): no statement planned per row;
    the storage owner's, definer's rights with its search_path pinned, not PUBLIC's. Each row written is one call
    of it; the generic tgsis.chunk_face_queue runs once per statement only. The answers are the other tests'.
    Fails with the generic row function (its calls counted per row, no tgsis.vrtx_face_row)."""
    if db_storage != "chunks":
        pytest.skip("the face and its trigger exist on chunks only")
    row = conn.execute(
        "SELECT t.tgfoid::regprocedure::text, p.prosecdef, 'search_path=pg_catalog, pg_temp' = ANY (p.proconfig), "
        "p.proowner = c.relowner, NOT EXISTS (SELECT FROM aclexplode(p.proacl) a WHERE a.grantee = 0), "
        "p.prosrc !~* '\\mEXECUTE\\M|format\\(' "
        "FROM pg_trigger t JOIN pg_proc p ON p.oid = t.tgfoid, pg_class c "
        "WHERE t.tgrelid = 'tgsis.vrtx'::regclass AND t.tgname = 'tgsis_chunk_face' AND c.oid = 'tgsis.vrtx_chunk'::regclass"
    ).fetchone()
    assert row == ("tgsis.vrtx_face_row()", True, True, True, True, True)
    geoid = fault_clone
    calls = (
        "SELECT coalesce(sum(calls) FILTER (WHERE funcname = 'vrtx_face_row'), 0), "
        "coalesce(sum(calls) FILTER (WHERE funcname = 'chunk_face_queue'), 0) "
        "FROM pg_stat_xact_user_functions WHERE schemaname = 'tgsis'"
    )
    with tgsis.in_version(conn, "e1"):
        conn.commit()
        conn.execute("SET track_functions = 'all'")
        before = conn.execute(calls).fetchone()
        assert conn.execute("UPDATE tgsis.vrtx SET z = z + 1 WHERE geoid = %s AND vrtxid < 5", (geoid,)).rowcount == 5
        assert conn.execute(_insert(FIRST, FIRST + 2), (geoid,)).rowcount == 3
        after = conn.execute(calls).fetchone()
        assert before is not None and after is not None
        assert (after[0] - before[0], after[1] - before[1]) == (8, 2)  # 8 rows, 2 statements
        conn.rollback()


def test_the_row_function_is_made_and_dropped_with_the_face(conn: Conn, db_storage: str) -> None:
    """The way back into rows drops the face's generated row function with the face (model tables, a class's
    property table), the way into chunks makes it again, dropping the class drops it: none is left behind."""
    if db_storage != "chunks":
        pytest.skip("the face and its row function exist on chunks only")

    def made(function: str) -> bool:
        row = conn.execute("SELECT to_regprocedure(%s) IS NOT NULL", (function,)).fetchone()
        assert row is not None
        return bool(row[0])

    assert made("tgsis.vrtx_face_row()")
    conn.execute("SELECT tgsis.store_in_rows('vrtx')")
    conn.commit()
    assert not made("tgsis.vrtx_face_row()")
    conn.execute("SELECT tgsis.store_in_chunks('vrtx')")
    conn.commit()
    assert made("tgsis.vrtx_face_row()")
    tgsis.create_feature_class(conn, "rock", "SURFACE", cell_properties=[("porosity", "double precision")])
    conn.commit()
    table = conn.execute(
        "SELECT format('%I.%I', schemaname, cellprotable) FROM tgsis.catalog WHERE classname = 'rock'"
    ).fetchone()
    assert table is not None
    function = f"{table[0]}_face_row()"
    assert not made(function)
    for step, there in (
        ("store_class_in_chunks", True),
        ("store_class_in_rows", False),
        ("store_class_in_chunks", True),
    ):
        conn.execute(f"SELECT tgsis.{step}('rock')")  # noqa: S608
        conn.commit()
        assert made(function) == there, step
    conn.execute("SELECT tgsis.drop_feature_class('rock')")
    conn.commit()
    assert not made(function)
