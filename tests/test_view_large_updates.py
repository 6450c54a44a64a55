"""Large UPDATEs through versioned views, and the locks their flush takes (issue 36, point 2).

A flush writing up to tgsis.object_lock_limit() objects holds each object's
write lock shared (tgsis.object_lock_key); above it, the class's lock in the
version exclusively (tgsis.object_class_lock_key), which every bulk writer
(tgsis.object_write_lock) holds shared: one lock instead of one per object,
which a default server's shared lock table could not hold for 50,000 rows
(53200). docs/versioning.md, "How an UPDATE is written".
"""

from __future__ import annotations

from typing import Any

import psycopg
import pytest

import tgsis
from tests.sessions import Background, connect, wait_until_blocked

Conn = psycopg.Connection[Any]


def _items(conn: Conn, rows: int) -> Conn:
    """items keyed by id, one object per row (the object key is the key), versioned, and a child version."""
    conn.execute("CREATE TABLE items (id int PRIMARY KEY, val int NOT NULL)")
    conn.execute("INSERT INTO items SELECT g, g FROM generate_series(1, %s) g", (rows,))
    tgsis.enable_versioning(conn, "items", "id", "item")
    tgsis.create_version(conn, "child")
    conn.commit()
    return conn


@pytest.fixture
def items(conn: Conn) -> Conn:
    return _items(conn, 5000)


def _limit(conn: Conn) -> int:
    row = conn.execute("SELECT tgsis.object_lock_limit(), current_setting('max_locks_per_transaction')::int").fetchone()
    assert row is not None and row[0] == row[1] // 2
    return int(row[0])


def _advisory(conn: Conn) -> tuple[int, int]:
    """The advisory locks this session holds: (shared, exclusive)."""
    row = conn.execute(
        "SELECT count(*) FILTER (WHERE mode = 'ShareLock'), count(*) FILTER (WHERE mode = 'ExclusiveLock') "
        "FROM pg_locks WHERE locktype = 'advisory' AND pid = pg_backend_pid() AND granted"
    ).fetchone()
    assert row is not None
    return int(row[0]), int(row[1])


def _holds_class_lock(conn: Conn, version: str, mode: str) -> bool:
    row = conn.execute(
        "SELECT EXISTS (SELECT FROM pg_locks l WHERE l.locktype = 'advisory' AND l.pid = pg_backend_pid() "
        "AND l.mode = %s AND l.objsubid = 1 "
        "AND ((l.classid::bigint << 32) | l.objid::bigint) = tgsis.object_class_lock_key('item', tgsis.version_id(%s)))",
        (mode, version),
    ).fetchone()
    assert row is not None
    return bool(row[0])


def test_an_update_of_50000_rows_through_a_view_succeeds(conn: Conn) -> None:
    """53200 out of shared memory with a lock per object (one per row here)."""
    items, version = _items(conn, 50000), "child"
    with tgsis.in_version(items, version):
        items.commit()
        assert items.execute("UPDATE items SET val = val + 1").rowcount == 50000
        assert _advisory(items)[0] <= 2  # the first row's object, not one lock per row
        assert _holds_class_lock(items, version, "ExclusiveLock")
        items.commit()
        row = items.execute("SELECT count(*), sum(val - id) FROM items").fetchone()
        items.rollback()
    assert row == (50000, 50000)
    assert items.execute("SELECT count(*) FROM items_ver_queue").fetchone() == (0,)


def test_up_to_the_limit_the_objects_are_locked_one_by_one(items: Conn) -> None:
    limit = _limit(items)
    items.commit()
    # the first row goes the row path (its object's lock), the others are queued and flushed
    items.execute("UPDATE items SET val = -val WHERE id <= %s", (limit,))
    assert _advisory(items) == (limit, 0)
    assert not _holds_class_lock(items, "DEFAULT", "ExclusiveLock")
    items.rollback()
    items.execute("UPDATE items SET val = -val WHERE id <= %s", (limit + 1,))
    assert _advisory(items) == (1, 1)  # the first row's object; then the class's lock in the version
    assert _holds_class_lock(items, "DEFAULT", "ExclusiveLock")
    items.rollback()


def test_the_objects_a_transaction_locked_are_counted_across_statements(items: Conn) -> None:
    """One-row statements in a loop: the objects' locks up to the limit, then the class's lock; the same object
    again counts once; another version counts afresh."""
    limit = _limit(items)
    items.commit()
    items.execute(
        f"DO $$ BEGIN FOR i IN 1 .. {limit * 3} LOOP UPDATE items SET val = val + 1 WHERE id = 1; END LOOP; END $$"
    )
    assert _advisory(items) == (1, 0)
    items.execute(
        f"DO $$ BEGIN FOR i IN 2 .. {limit} LOOP UPDATE items SET val = val + 1 WHERE id = i; END LOOP; END $$"
    )
    assert _advisory(items) == (limit, 0)
    items.execute("UPDATE items SET val = val + 1 WHERE id = 5000")
    assert _advisory(items) == (limit, 1)
    with tgsis.in_version(items, "child", local=True):
        items.execute("UPDATE items SET val = val + 1 WHERE id = 5000")
    assert _advisory(items) == (limit + 1, 1)
    items.rollback()


def test_an_insert_of_10000_rows_through_a_view_succeeds(items: Conn) -> None:
    """Inserts go the row path: 53200 with a lock per object; its locks escalate as the flush's."""
    assert items.execute("INSERT INTO items SELECT g, g FROM generate_series(100001, 110000) g").rowcount == 10000
    assert _advisory(items)[0] <= _limit(items)
    assert _holds_class_lock(items, "DEFAULT", "ExclusiveLock")
    items.commit()
    assert items.execute("SELECT count(*) FROM items").fetchone() == (15000,)


@pytest.mark.parametrize(
    "statement",
    ["DELETE FROM items WHERE id <= 1000", "UPDATE items SET id = id + 100000 WHERE id <= 1000"],
    ids=["delete", "key-change"],
)
def test_row_by_row_writes_escalate_too(items: Conn, statement: str) -> None:
    """Deletes and key changes go the row path: its locks escalate as the flush's."""
    assert items.execute(statement).rowcount == 1000
    assert _advisory(items)[0] <= _limit(items)
    assert _holds_class_lock(items, "DEFAULT", "ExclusiveLock")
    items.commit()


def test_a_bulk_writer_holds_the_class_lock_shared(items: Conn) -> None:
    items.execute("SELECT tgsis.object_write_lock('item', ARRAY['1', '2', '3'])")
    assert _advisory(items) == (1, 3)
    assert _holds_class_lock(items, "DEFAULT", "ShareLock")
    items.rollback()


@pytest.mark.parametrize("outcome", ["commit", "rollback"])
def test_a_bulk_writer_waits_for_a_large_view_update(items: Conn, db_dsn: str, outcome: str) -> None:
    """The large flush holds the class lock exclusively: a bulk writer of one of its objects waits for its end,
    a bulk writer in another version does not."""
    a = connect(db_dsn, "large-update")
    observer = connect(db_dsn, "observer", autocommit=True)
    try:
        assert a.execute("UPDATE items SET val = val + 1 WHERE id <= 1000").rowcount == 1000
        other = Background(
            db_dsn,
            "other-version",
            lambda c: c.execute("SELECT tgsis.object_write_lock('item', ARRAY['5'])").fetchone(),
            "child",
        )
        other.finish()  # another version: not waiting
        b = Background(
            db_dsn,
            "bulk-writer",
            lambda c: [
                c.execute("SELECT tgsis.object_write_lock('item', ARRAY['5'])"),
                c.execute("SELECT val FROM items WHERE id = 5").fetchone(),  # read after the lock: a new snapshot
            ][1],
        )
        wait_until_blocked(observer, b.pid, a.info.backend_pid)
        if outcome == "commit":
            a.commit()
        else:
            a.rollback()
        # it decides from the state the update left
        assert b.finish() == ((6,) if outcome == "commit" else (5,))
    finally:
        a.close()
        observer.close()


@pytest.mark.parametrize("outcome", ["commit", "rollback"])
def test_a_large_view_update_waits_for_a_bulk_writer(items: Conn, db_dsn: str, outcome: str) -> None:
    """A bulk writer holds object 5 (and the class lock shared): a large UPDATE through the view waits for it,
    then writes on the state it left (a row it changed meanwhile is 40001, as for the per-object locks)."""
    a = connect(db_dsn, "bulk-writer")
    observer = connect(db_dsn, "observer", autocommit=True)
    try:
        a.execute("SELECT tgsis.object_write_lock('item', ARRAY['5'])")
        small = Background(
            db_dsn,
            "small-update",
            lambda c: c.execute("UPDATE items SET val = val + 1 WHERE id BETWEEN 100 AND 110").rowcount,
        )
        assert small.finish() == 11  # other objects, locked one by one: not waiting
        b = Background(
            db_dsn,
            "large-update",
            lambda c: c.execute("UPDATE items SET val = val + 1 WHERE id BETWEEN 1 AND 1000").rowcount,
        )
        wait_until_blocked(observer, b.pid, a.info.backend_pid)
        a.execute("UPDATE items_ver SET val = -5 WHERE id = 5")  # a bulk writer writes the storage itself
        if outcome == "commit":
            a.commit()
            with pytest.raises(psycopg.errors.SerializationFailure):
                b.finish()
        else:
            a.rollback()
            assert b.finish() == 1000
    finally:
        a.close()
        observer.close()
    expected = {"commit": -5, "rollback": 6}[outcome]
    assert items.execute("SELECT val FROM items WHERE id = 5").fetchone() == (expected,)


def test_a_session_claiming_the_class_lock_in_its_settings_still_takes_it(items: Conn, db_dsn: str) -> None:
    """The count of locked objects is a setting the session can change itself: saying it holds the class's lock
    skips nothing, so that a bulk writer still waits for its view writes."""
    version = items.execute("SELECT tgsis.version_id('DEFAULT')").fetchone()
    assert version is not None
    items.execute("SELECT set_config('tgsis.object_locks_' || 'items'::regclass::oid, %s, true)", (f"{version[0]}:*",))
    assert items.execute("INSERT INTO items VALUES (100000, 1)").rowcount == 1
    assert _holds_class_lock(items, "DEFAULT", "ExclusiveLock")
    observer = connect(db_dsn, "observer", autocommit=True)
    try:
        b = Background(
            db_dsn,
            "bulk-writer",
            lambda c: c.execute("SELECT tgsis.object_write_lock('item', ARRAY['100000'])").fetchone(),
        )
        wait_until_blocked(observer, b.pid, items.info.backend_pid)
        items.commit()
        b.finish()
    finally:
        observer.close()
