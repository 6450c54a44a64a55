"""Concurrent writes of the same rows through versioned views (issue 15, part 1): as correct as a plain table.

Two sessions in one version write the same row. PostgreSQL re-checks a plain
table's row after waiting for the other writer and computes the new values
from the row as it is then; the view's trigger cannot recompute an UPDATE's
SET list, so it either applies the write to the row version that is current
when it gets its lock (when that row still holds the values the statement
read) or refuses it with 40001 (serialization_failure), which clients retry.
Never a stale value, a resurrected row, or a raw duplicate of the storage key.

Each interleaving runs the first writer's statement, starts the second one's
in a thread, waits until it waits for the first (``pg_blocking_pids``), then
commits or rolls back the first, in four places: DEFAULT on a row of an older
revision (its first change there closes it and writes a new row), DEFAULT on
a row of its working revision (changed in place), a child on a row it
inherits, a child on a row of its own.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from typing import Any

import psycopg
import pytest

import tgsis
from tests.conftest import BuiltOnce, cloned_or_built
from tests.sessions import Background, connect, wait_until_blocked
from tests.storage_data import stored_versions
from tests.synthetic import flat_grid
from tgsis.db import features as F

Conn = psycopg.Connection[Any]

# where the contested row lives: version, and whether it was rewritten in the version's working revision
PLACES = {
    "default-older": ("DEFAULT", False),
    "default-own": ("DEFAULT", True),
    "child-inherited": ("child", False),
    "child-own": ("child", True),
}


@pytest.fixture
def items(conn: Conn) -> Conn:
    """items (id, val, note) with rows 1..5 (val 100), versioned; a child version 'child' of DEFAULT."""
    conn.execute("CREATE TABLE items (id int PRIMARY KEY, val int NOT NULL, note text)")
    conn.execute("INSERT INTO items SELECT g, 100, 'seed' FROM generate_series(1, 5) g")
    tgsis.enable_versioning(conn, "items", "id", "item")
    tgsis.create_version(conn, "child")
    conn.commit()
    return conn


def _place(conn: Conn, place: str) -> str:
    """Put row 1 where the place says (rewritten in place or not) and return the version."""
    version, own = PLACES[place]
    if own:
        with tgsis.in_version(conn, version):
            conn.execute("UPDATE items SET note = 'own' WHERE id = 1")
            conn.commit()
            storage = conn.execute(
                "SELECT count(*) FROM items_ver WHERE id = 1 AND revision = %s", (tgsis.working_revision(conn),)
            ).fetchone()
            assert storage == (1,), "the row is not of the working revision"
            conn.commit()
    return version


def _value(conn: Conn, version: str, key: int = 1) -> tuple[Any, ...] | None:
    with tgsis.in_version(conn, version, local=True):
        row = conn.execute("SELECT val FROM items WHERE id = %s", (key,)).fetchone()
    conn.rollback()
    return row


def _storage_keys_unique(conn: Conn) -> None:
    """No key is visible twice in any version."""
    rows = conn.execute(
        "SELECT s.name, v.id, count(*) FROM tgsis.versions s JOIN items_ver v "
        "ON v.revision = ANY (s.workingset) AND NOT (v.lastrevs && s.workingset) GROUP BY 1, 2 HAVING count(*) > 1"
    ).fetchall()
    conn.rollback()
    assert rows == []


def _race(db_dsn: str, version: str, first: str, second: Callable[[Conn], Any], outcome: str) -> Background:
    """Run ``first`` in an open transaction, ``second`` in the background until it waits for it, then end the first."""
    a = connect(db_dsn, "first")
    observer = connect(db_dsn, "observer", autocommit=True)
    try:
        tgsis.goto_version(a, version)
        a.commit()
        a.execute(first)
        b = Background(db_dsn, "second", second, version)
        wait_until_blocked(observer, b.pid, a.info.backend_pid)
        if outcome == "commit":
            a.commit()
        else:
            a.rollback()
        b.thread.join(30)
        return b
    finally:
        a.close()
        observer.close()


def _rowcount(sql: str) -> Callable[[Conn], int]:
    return lambda c: c.execute(sql).rowcount


@pytest.mark.parametrize("outcome", ["commit", "rollback"])
@pytest.mark.parametrize("place", PLACES)
def test_update_waiting_for_an_update_never_writes_a_stale_value(
    items: Conn, db_dsn: str, place: str, outcome: str
) -> None:
    version = _place(items, place)
    b = _race(
        db_dsn,
        version,
        "UPDATE items SET val = val + 1 WHERE id = 1",
        _rowcount("UPDATE items SET val = val + 10 WHERE id = 1"),
        outcome,
    )
    if outcome == "commit":
        # a plain table would give 111; the view refuses the stale 110 and the retry gives 111
        with pytest.raises(
            psycopg.errors.SerializationFailure, match=r"row \(id\)=\(1\) of public.items in version '(DEFAULT|child)'"
        ):
            b.finish()
        with tgsis.in_version(items, version):
            assert items.execute("UPDATE items SET val = val + 10 WHERE id = 1").rowcount == 1
            items.commit()
        assert _value(items, version) == (111,)
    else:
        assert b.finish() == 1
        assert _value(items, version) == (110,)
    _storage_keys_unique(items)


@pytest.mark.parametrize("outcome", ["commit", "rollback"])
@pytest.mark.parametrize("place", PLACES)
def test_update_waiting_for_a_delete_does_not_bring_the_row_back(
    items: Conn, db_dsn: str, place: str, outcome: str
) -> None:
    """A one-row UPDATE (its first row: the row path) as on a plain table."""
    version = _place(items, place)
    b = _race(
        db_dsn,
        version,
        "DELETE FROM items WHERE id = 1",
        _rowcount("UPDATE items SET val = val + 10 WHERE id = 1"),
        outcome,
    )
    if outcome == "commit":
        assert b.finish() == 0  # as on a plain table: the row is gone, nothing updated
        assert _value(items, version) is None
    else:
        assert b.finish() == 1
        assert _value(items, version) == (110,)
    _storage_keys_unique(items)


@pytest.mark.parametrize("outcome", ["commit", "rollback"])
@pytest.mark.parametrize("place", PLACES)
def test_bulk_update_waiting_for_a_delete_refuses_and_its_retry_finds_the_row_gone(
    items: Conn, db_dsn: str, place: str, outcome: str
) -> None:
    """A row after the statement's first is queued: counted already when the delete commits, so the
    update refuses (40001) instead of bringing it back; the retry updates the others."""
    version = _place(items, place)
    b = _race(db_dsn, version, "DELETE FROM items WHERE id = 5", _rowcount("UPDATE items SET val = val + 10"), outcome)
    if outcome == "commit":
        with pytest.raises(
            psycopg.errors.SerializationFailure,
            match=r"concurrent delete of row \(id\)=\(5\) of public.items in version '(DEFAULT|child)'",
        ):
            b.finish()
        assert _value(items, version, 5) is None and _value(items, version) == (100,)
        with tgsis.in_version(items, version):
            assert items.execute("UPDATE items SET val = val + 10").rowcount == 4
            items.commit()
        assert _value(items, version, 5) is None and _value(items, version) == (110,)
    else:
        assert b.finish() == 5
        assert _value(items, version, 5) == (110,)
    _storage_keys_unique(items)


@pytest.mark.parametrize("outcome", ["commit", "rollback"])
@pytest.mark.parametrize("place", PLACES)
def test_delete_waiting_for_an_update_refuses_to_delete_a_row_it_did_not_see(
    items: Conn, db_dsn: str, place: str, outcome: str
) -> None:
    version = _place(items, place)
    b = _race(
        db_dsn,
        version,
        "UPDATE items SET val = val + 1 WHERE id = 1",
        _rowcount("DELETE FROM items WHERE id = 1"),
        outcome,
    )
    if outcome == "commit":
        with pytest.raises(psycopg.errors.SerializationFailure):
            b.finish()
        assert _value(items, version) == (101,)
        with tgsis.in_version(items, version):  # the retry deletes it
            assert items.execute("DELETE FROM items WHERE id = 1").rowcount == 1
            items.commit()
    else:
        assert b.finish() == 1
    assert _value(items, version) is None
    _storage_keys_unique(items)


@pytest.mark.parametrize("outcome", ["commit", "rollback"])
@pytest.mark.parametrize("place", PLACES)
def test_delete_waiting_for_a_delete_deletes_nothing_more(items: Conn, db_dsn: str, place: str, outcome: str) -> None:
    version = _place(items, place)
    b = _race(db_dsn, version, "DELETE FROM items WHERE id = 1", _rowcount("DELETE FROM items WHERE id = 1"), outcome)
    assert b.finish() == (0 if outcome == "commit" else 1)
    assert _value(items, version) is None
    _storage_keys_unique(items)


@pytest.mark.parametrize("outcome", ["commit", "rollback"])
@pytest.mark.parametrize("version", ["DEFAULT", "child"])
def test_insert_waiting_for_an_insert_of_the_same_key_is_the_tables_duplicate(
    items: Conn, db_dsn: str, version: str, outcome: str
) -> None:
    b = _race(
        db_dsn,
        version,
        "INSERT INTO items VALUES (50, 1, 'first')",
        _rowcount("INSERT INTO items VALUES (50, 2, 'second')"),
        outcome,
    )
    if outcome == "commit":
        with pytest.raises(psycopg.errors.UniqueViolation) as caught:
            b.finish()
        assert caught.value.diag.constraint_name == "items_pkey"  # the table's key, never items_ver_pkey
        assert _value(items, version, 50) == (1,)
    else:
        assert b.finish() == 1
        assert _value(items, version, 50) == (2,)
    _storage_keys_unique(items)


@pytest.mark.parametrize("outcome", ["commit", "rollback"])
@pytest.mark.parametrize("place", PLACES)
def test_insert_waiting_for_a_delete_of_the_same_key_goes_in_after_it(
    items: Conn, db_dsn: str, place: str, outcome: str
) -> None:
    version = _place(items, place)
    b = _race(
        db_dsn,
        version,
        "DELETE FROM items WHERE id = 1",
        _rowcount("INSERT INTO items VALUES (1, 7, 'again')"),
        outcome,
    )
    if outcome == "commit":
        assert b.finish() == 1  # as on a plain table: the key is free once the delete commits
        assert _value(items, version) == (7,)
    else:
        with pytest.raises(psycopg.errors.UniqueViolation) as caught:
            b.finish()
        assert caught.value.diag.constraint_name == "items_pkey"
        assert _value(items, version) == (100,)
    _storage_keys_unique(items)


@pytest.mark.parametrize("place", PLACES)
def test_a_key_change_waiting_for_an_insert_of_the_new_key_is_the_tables_duplicate(
    items: Conn, db_dsn: str, place: str
) -> None:
    version = _place(items, place)
    b = _race(
        db_dsn,
        version,
        "INSERT INTO items VALUES (60, 1, 'first')",
        _rowcount("UPDATE items SET id = 60 WHERE id = 1"),
        "commit",
    )
    with pytest.raises(psycopg.errors.UniqueViolation) as caught:
        b.finish()
    assert caught.value.diag.constraint_name == "items_pkey"
    assert _value(items, version) == (100,) and _value(items, version, 60) == (1,)
    _storage_keys_unique(items)


def test_a_write_after_the_other_committed_in_the_same_transaction_sees_its_row(items: Conn, db_dsn: str) -> None:
    """READ COMMITTED: a statement that starts after the other writer committed reads the new row, as on a table."""
    a, b = connect(db_dsn, "a"), connect(db_dsn, "b")
    try:
        for c in (a, b):
            tgsis.goto_version(c, "child")
            c.commit()
        b.execute("SELECT val FROM items WHERE id = 2")  # b's transaction is open, its next statement is later
        a.execute("UPDATE items SET val = val + 1 WHERE id = 2")
        a.commit()
        assert b.execute("UPDATE items SET val = val + 10 WHERE id = 2").rowcount == 1
        b.commit()
    finally:
        a.close()
        b.close()
    assert _value(items, "child", 2) == (111,)


@pytest.mark.parametrize("version", ["DEFAULT", "child"])
def test_repeatable_read_writers_get_serialization_failures_not_stale_writes(
    items: Conn, db_dsn: str, version: str
) -> None:
    a, b = connect(db_dsn, "a"), connect(db_dsn, "b")
    try:
        for c in (a, b):
            tgsis.goto_version(c, version)
            c.commit()
        b.execute("SET TRANSACTION ISOLATION LEVEL REPEATABLE READ")
        b.execute("SELECT val FROM items WHERE id = 3")  # b's snapshot
        a.execute("UPDATE items SET val = val + 1 WHERE id = 3")
        a.commit()
        with pytest.raises(psycopg.errors.SerializationFailure):
            b.execute("UPDATE items SET val = val + 10 WHERE id = 3")
        b.rollback()
    finally:
        a.close()
        b.close()
    assert _value(items, version, 3) == (101,)


# --------------------------------------------------------------------------- the counter


@pytest.mark.parametrize("version", ["DEFAULT", "child"])
def test_concurrent_increments_lose_nothing(items: Conn, db_dsn: str, version: str) -> None:
    """Sessions increment the same rows (of an older revision at first); 40001 is retried; every commit counts."""
    sessions, increments = 3, 200
    committed = [0] * 6
    retries = [0]
    errors: list[BaseException] = []
    lock = threading.Lock()
    barrier = threading.Barrier(sessions)

    def run(seed: int) -> None:
        try:
            with connect(db_dsn, f"counter{seed}") as c:
                tgsis.goto_version(c, version)
                c.commit()
                barrier.wait()
                for i in range(increments):
                    key = (i * (seed + 1) + seed) % 5 + 1
                    while True:
                        try:
                            c.execute("UPDATE items SET val = val + 1 WHERE id = %s", (key,))
                            c.commit()
                        except psycopg.errors.SerializationFailure:
                            c.rollback()
                            with lock:
                                retries[0] += 1
                            continue
                        with lock:
                            committed[key] += 1
                        break
        except BaseException as exc:  # noqa: BLE001 - reported below
            errors.append(exc)

    threads = [threading.Thread(target=run, args=(s,), daemon=True) for s in range(sessions)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(120)
    assert not errors, errors
    assert sum(committed) == sessions * increments
    with tgsis.in_version(items, version, local=True):
        values = dict(items.execute("SELECT id, val FROM items").fetchall())
    items.rollback()
    assert values == {k: 100 + committed[k] for k in range(1, 6)}, f"{retries[0]} retries"
    assert retries[0] > 0, "the sessions never met: the test did not test anything"
    _storage_keys_unique(items)
    # DEFAULT is untouched by the child's increments, and the other way round
    other = "child" if version == "DEFAULT" else "DEFAULT"
    with tgsis.in_version(items, other, local=True):
        assert items.execute("SELECT sum(val) FROM items").fetchone() == (500,)
    items.rollback()


# --------------------------------------------------------------------------- bulk writers against view writers


def make_surfaces(conn: Conn) -> int:
    """A versioned surface feature (3 x 3 grid) in DEFAULT, and its geoid; a child version, so that DEFAULT's
    working revision is a later one than the feature's rows (a write closes them and writes new ones)."""
    fc = F.create_feature_class(conn, "horizons", "SURFACE")
    tgsis.enable_feature_versioning(conn)
    geoid = F.insert_feature(conn, fc, flat_grid(3, 0.0))
    tgsis.create_version(conn, "child")
    conn.commit()
    return geoid


BUILT_ONCE = {"surfaces": make_surfaces}  # built once, cloned per test (db_dsn, tests/conftest.py)


@pytest.fixture
def surfaces(request: pytest.FixtureRequest, conn: Conn, built_once: BuiltOnce) -> tuple[Conn, int]:
    """The test's connection and ``make_surfaces``'s geoid, already in its database (cloned, not built again)."""
    return conn, cloned_or_built(request, conn, built_once, "surfaces", make_surfaces)


def test_a_bulk_delete_waits_for_a_view_writer_and_leaves_no_row_of_the_feature(
    surfaces: tuple[Conn, int], db_dsn: str
) -> None:
    conn, geoid = surfaces
    b = _race(
        db_dsn,
        "DEFAULT",
        f"UPDATE tgsis.vrtx SET z = 5 WHERE geoid = {geoid} AND vrtxid = 0",
        lambda c: F.delete_feature(c, "horizons", geoid),
        "commit",
    )
    assert b.finish() is True
    assert conn.execute("SELECT count(*) FROM tgsis.vrtx WHERE geoid = %s", (geoid,)).fetchone() == (0,)
    assert conn.execute("SELECT count(*) FROM tgsis.geometry WHERE geoid = %s", (geoid,)).fetchone() == (0,)


def test_a_view_writer_waiting_for_a_bulk_delete_refuses_and_its_retry_finds_the_rows_gone(
    surfaces: tuple[Conn, int], db_dsn: str
) -> None:
    conn, geoid = surfaces
    a = connect(db_dsn, "deleter")
    observer = connect(db_dsn, "observer", autocommit=True)
    try:
        assert F.delete_feature(a, "horizons", geoid)
        b = Background(db_dsn, "writer", _rowcount(f"UPDATE tgsis.vrtx SET z = 5 WHERE geoid = {geoid}"))
        wait_until_blocked(observer, b.pid, a.info.backend_pid)
        a.commit()
        # the update counted the rows it queued before it waited: it refuses, and its retry finds none
        with pytest.raises(psycopg.errors.SerializationFailure, match=r"concurrent delete of row \(geoid, vrtxid\)"):
            b.finish()
        assert conn.execute(f"UPDATE tgsis.vrtx SET z = 5 WHERE geoid = {geoid}").rowcount == 0
        conn.commit()
    finally:
        a.close()
        observer.close()
    assert conn.execute("SELECT count(*) FROM tgsis.vrtx WHERE geoid = %s", (geoid,)).fetchone() == (0,)


@pytest.mark.parametrize("first", ["checkin", "sql"])
def test_a_checkin_and_an_sql_update_of_the_same_vertex_never_lose_either(
    surfaces: tuple[Conn, int], db_dsn: str, first: str
) -> None:
    """Check-in racing a plain UPDATE of the vertex it moves: TG304 or 40001 for the later one, never 23505."""
    conn, geoid = surfaces
    with connect(db_dsn, "modeller") as modeller:
        out = tgsis.checkout(modeller, geoid)
        modeller.commit()
        edited = out.mesh.vertices.copy()
        edited[0, 2] = -7.0
        mesh = tgsis.Surface(edited, out.mesh.cells)
        if first == "sql":
            b = _race(
                db_dsn,
                "DEFAULT",
                f"UPDATE tgsis.vrtx SET z = 3 WHERE geoid = {geoid} AND vrtxid = 0",
                lambda c: tgsis.checkin(c, out, mesh),
                "commit",
            )
            with pytest.raises(tgsis.CheckoutConflictError):
                b.finish()
            expected = 3.0
        else:
            observer = connect(db_dsn, "observer", autocommit=True)
            try:
                with modeller.transaction():
                    tgsis.checkin(modeller, out, mesh)
                    b = Background(
                        db_dsn, "sql", _rowcount(f"UPDATE tgsis.vrtx SET z = 3 WHERE geoid = {geoid} AND vrtxid = 0")
                    )
                    wait_until_blocked(observer, b.pid, modeller.info.backend_pid)
                modeller.commit()
                with pytest.raises(psycopg.errors.SerializationFailure):
                    b.finish()
            finally:
                observer.close()
            expected = -7.0
    z = conn.execute("SELECT z FROM tgsis.vrtx WHERE geoid = %s AND vrtxid = 0", (geoid,)).fetchall()
    assert z == [(expected,)]


@pytest.mark.parametrize("isolation", ["REPEATABLE READ", "SERIALIZABLE"])
def test_merge_refresh_and_bulk_deletes_refuse_an_old_snapshot(surfaces: tuple[Conn, int], isolation: str) -> None:
    """They wait for writers and must see what those committed: a transaction's snapshot would miss it."""
    conn, geoid = surfaces
    before = stored_versions(conn, "vrtx")  # rows or chunk versions
    conn.commit()
    calls: list[Callable[[], object]] = [
        lambda: tgsis.merge_version(conn, "child"),
        lambda: tgsis.refresh_version(conn, "child"),
        lambda: F.delete_feature(conn, "horizons", geoid),
    ]
    for call in calls:
        conn.execute(f"SET TRANSACTION ISOLATION LEVEL {isolation}")
        with pytest.raises(tgsis.VersioningError, match=f"cannot run in a {isolation} transaction"):
            call()
        conn.rollback()
    assert stored_versions(conn, "vrtx") == before
