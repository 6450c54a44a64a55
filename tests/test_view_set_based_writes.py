"""UPDATEs through versioned views that keep their rows' keys, written set-based when the statement ends.

The row trigger writes the statement's first row by the row path and only
queues the others' new and old values in ``<table>_ver_queue``; the same
function, fired after the statement, writes them all (docs/versioning.md,
"How an UPDATE is written"). What it writes
must be what the row path writes, in every place a row can live (a row of an
older revision closed and written anew, one of the working revision changed
in place, in DEFAULT and in a child), with the same checks (rights, object
locks, features of no version, the notes of changed objects, rows changed or
deleted meanwhile: tests/test_concurrent_writes.py), and the queue must stay
the storage owner's, empty outside a statement.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import psycopg
import pytest

import tgsis
from tests.roles import login_roles
from tests.storage_data import row_versions

Conn = psycopg.Connection[Any]

ROWS = 40


@pytest.fixture
def items(conn: Conn) -> Conn:
    """items keyed by (id, code) with values of several kinds (a domain, a collation, NULLs), versioned, a child."""
    conn.execute("CREATE DOMAIN grade AS numeric(6, 2) CHECK (VALUE >= 0)")
    conn.execute(
        'CREATE TABLE items (id int, code text COLLATE "C", val int NOT NULL, g grade, tags text[], '
        "note text DEFAULT 'none', PRIMARY KEY (id, code))"
    )
    conn.execute("CREATE TABLE twin (LIKE items INCLUDING ALL)")  # the same statements on a plain table
    for table in ("items", "twin"):
        conn.execute(
            f"INSERT INTO {table} SELECT g, 'k' || g % 3, g * 10, g / 4.0, "  # noqa: S608
            f"CASE WHEN g % 5 = 0 THEN NULL ELSE ARRAY['t' || g] END, "
            f"CASE WHEN g % 7 = 0 THEN NULL ELSE 'n' || g END FROM generate_series(1, {ROWS}) g"
        )
    tgsis.enable_versioning(conn, "items", "id", "item")
    tgsis.create_version(conn, "child")
    conn.commit()
    return conn


def _rows(conn: Conn, table: str, version: str = "DEFAULT") -> list[tuple[Any, ...]]:
    with tgsis.in_version(conn, version, local=True):
        rows = conn.execute(f"SELECT * FROM {table} ORDER BY id, code").fetchall()  # noqa: S608
    conn.rollback()
    return rows


def _storage(conn: Conn) -> list[tuple[Any, ...]]:
    rows = conn.execute("SELECT id, revision, lastrevs, val FROM items_ver ORDER BY id, revision").fetchall()
    conn.rollback()
    return rows


def _queued(conn: Conn) -> int:
    row = conn.execute("SELECT count(*) FROM items_ver_queue").fetchone()
    assert row is not None
    return int(row[0])


STATEMENTS = [
    "UPDATE {t} SET val = val + 1, g = g * 2 WHERE id <= 30",
    "UPDATE {t} SET tags = tags || 'x'::text, note = NULL WHERE id % 2 = 0",
    "UPDATE {t} SET note = DEFAULT, code = code WHERE id > 10",
    "UPDATE {t} SET val = x.v FROM (SELECT g AS id, -g AS v FROM generate_series(5, 25) g) x WHERE {t}.id = x.id",
]


@pytest.mark.parametrize("place", ["default-older", "default-own", "child-inherited", "child-own"])
def test_a_bulk_update_writes_what_a_plain_table_holds(items: Conn, place: str) -> None:
    version = "child" if place.startswith("child") else "DEFAULT"
    if place.endswith("own"):  # the rows are of the version's working revision: changed in place
        with tgsis.in_version(items, version, local=True):
            items.execute("UPDATE items SET note = note")
        items.commit()
    before = len(_storage(items))
    with tgsis.in_version(items, version):
        items.commit()
        for statement in STATEMENTS:
            for table in ("items", "twin"):
                items.execute(statement.format(t=table))
            assert _queued(items) == 0  # nothing left behind in the open transaction
        items.commit()
        written = tgsis.working_revision(items)
        items.rollback()
    assert _rows(items, "items", version) == _rows(items, "twin", "DEFAULT")
    storage = _storage(items)
    changed = {r[0] for r in storage if r[1] == written}
    assert changed == set(range(1, ROWS + 1))  # every row was changed by some statement
    if place.endswith("own"):
        assert len(storage) == before  # in place
    else:
        assert len(storage) == before + ROWS  # each closed once and written anew once
        assert all(written in r[2] for r in storage if r[1] != written)
    if version == "child":  # DEFAULT did not move
        assert [r[2] for r in _rows(items, "items")] == [r * 10 for r in range(1, ROWS + 1)]


def test_many_statements_of_one_do_block_each_write_their_own_rows(items: Conn) -> None:
    """The statements of one DO block share their transaction: the view's generation (tgsis.queue_<view oid>,
    counted up by each flush) tells their rows apart, the same row changed by each of them, and a row changed
    twice in a loop."""
    body = "; ".join(statement.format(t=table) for statement in STATEMENTS for table in ("items", "twin"))
    loop = (
        "FOR i IN 1 .. 30 LOOP UPDATE items SET val = val + i WHERE id = 1 + i % 7; "
        "UPDATE twin SET val = val + i WHERE id = 1 + i % 7; END LOOP"
    )
    with tgsis.in_version(items, "child"):
        items.execute(f"DO $$ BEGIN {body}; {loop}; END $$")
        assert _queued(items) == 0
        items.commit()
    assert _rows(items, "items", "child") == _rows(items, "twin")


def test_a_role_changing_the_generation_in_its_own_update_harms_no_other_transaction(items: Conn, db_dsn: str) -> None:
    """A function the statement calls moves the view's generation (tgsis.queue_<view oid>) at its fifth row: the
    rows queued before stay unwritten in the queue, carrying that transaction; another transaction's updates
    neither see nor write them."""
    items.execute(
        "CREATE FUNCTION bump(v int) RETURNS int LANGUAGE sql VOLATILE AS "
        "$$ SELECT CASE WHEN v = 51 THEN set_config('tgsis.queue_' || 'items'::regclass::oid, '7', true)::int * 0 + v "
        "ELSE v END $$"
    )
    items.commit()
    with tgsis.in_version(items, "child"):
        items.execute("UPDATE items SET val = bump(val + 1) WHERE id <= 9")
        items.commit()
    left = _queued(items)
    assert left > 0  # its own rows of other generations, left unwritten (its own statement's loss)
    before = _rows(items, "items", "child")
    with psycopg.connect(db_dsn) as other:
        with tgsis.in_version(other, "child"):
            assert other.execute("UPDATE items SET val = val WHERE id <= 9").rowcount == 9
            other.commit()
        assert _queued(other) == left  # the other transaction's flush read none of them
    assert _rows(items, "items", "child") == before  # and wrote none of their values


def test_row_count_and_returning_are_those_of_the_statement(items: Conn) -> None:
    cur = items.execute("UPDATE items SET val = val * 2 WHERE id BETWEEN 3 AND 7 RETURNING id, val")
    assert cur.rowcount == 5
    assert sorted(cur.fetchall()) == [(i, i * 20) for i in range(3, 8)]
    assert items.execute("UPDATE items SET val = 0 WHERE id > 1000").rowcount == 0
    items.commit()
    assert [r[2] for r in _rows(items, "items")][2:7] == [i * 20 for i in range(3, 8)]


def test_key_changes_and_key_keeping_rows_in_one_statement(items: Conn) -> None:
    statement = "UPDATE {t} SET id = CASE WHEN id = 1 THEN 100 ELSE id END, val = val + 5 WHERE id <= 4"
    for table in ("items", "twin"):
        assert items.execute(statement.format(t=table)).rowcount == 4
    items.commit()
    assert _rows(items, "items") == _rows(items, "twin")
    assert items.execute("SELECT count(*) FROM items_ver WHERE id = 1 AND revclosed").fetchone() == (1,)


@pytest.mark.parametrize("pairs", ["(2, 1), (2, 2), (3, 3)", "(2, 1), (2, 2)"], ids=["queued-twice", "first-row-again"])
def test_a_row_changed_twice_by_one_statement_is_refused_and_nothing_written(items: Conn, pairs: str) -> None:
    """Twice in the queue, or the statement's first row (written by the row path) queued again."""
    before = _storage(items)
    with pytest.raises(psycopg.errors.CardinalityViolation, match="one statement changed a row of public.items twice"):
        items.execute(f"UPDATE items SET val = x.v FROM (VALUES {pairs}) x(id, v) WHERE items.id = x.id")
    items.rollback()
    assert _storage(items) == before
    assert _queued(items) == 0


def test_a_failed_statement_leaves_nothing_queued_and_the_next_one_works(items: Conn) -> None:
    items.execute("SAVEPOINT s")
    with pytest.raises(psycopg.errors.CheckViolation):  # the domain's check, after some rows were queued
        items.execute("UPDATE items SET g = CASE WHEN id = 9 THEN -1 ELSE g END")
    items.execute("ROLLBACK TO SAVEPOINT s")
    assert _queued(items) == 0
    assert items.execute("UPDATE items SET val = 2 WHERE id <= 2").rowcount == 2
    items.commit()
    assert [r[2] for r in _rows(items, "items")][:3] == [2, 2, 30]


def test_a_view_update_inside_the_statement_keeps_its_own_rows(items: Conn) -> None:
    """Updates run while another is queued or flushed: by a function of its SET list, by a trigger of the storage."""
    items.execute("""CREATE FUNCTION touch(p_id int) RETURNS int LANGUAGE sql
                     BEGIN ATOMIC UPDATE items SET note = 'touched ' || p_id WHERE id = 40; SELECT p_id; END""")
    items.execute("CREATE TABLE log (id int, val int)")
    items.execute("""CREATE FUNCTION log_val() RETURNS trigger LANGUAGE plpgsql AS $$
                     BEGIN
                         IF NEW.id = 1 AND NOT NEW.revclosed THEN
                             UPDATE public.items SET note = 'flushed' WHERE id = 39;  -- the view, from inside its flush
                         END IF;
                         INSERT INTO public.log VALUES (NEW.id, NEW.val);
                         RETURN NULL;
                     END $$""")
    items.execute("CREATE TRIGGER log_val AFTER INSERT OR UPDATE ON items_ver FOR EACH ROW EXECUTE FUNCTION log_val()")
    assert items.execute("UPDATE items SET val = touch(id) + 1000 WHERE id <= 3").rowcount == 3
    assert _queued(items) == 0
    items.commit()
    rows = {r[0]: r for r in _rows(items, "items")}
    assert [rows[i][2] for i in (1, 2, 3)] == [1001, 1002, 1003]
    assert rows[40][5] == "touched 3" and rows[39][5] == "flushed"
    assert items.execute("SELECT count(*) FROM items_ver v WHERE v.id = 39 AND NOT v.revclosed").fetchone() == (1,)


def test_merge_into_the_view_is_written_as_an_update(items: Conn, pg: Any) -> None:
    merge = (
        "MERGE INTO items i USING (SELECT g AS id FROM generate_series(1, 5) g) s ON i.id = s.id "
        "WHEN MATCHED THEN UPDATE SET val = -i.val"
    )
    if pg.major < 17:  # MERGE on a view with INSTEAD OF triggers came with PostgreSQL 17
        with pytest.raises(psycopg.errors.FeatureNotSupported):
            items.execute(merge)
        items.rollback()
        return
    assert items.execute(merge).rowcount == 5
    items.commit()
    assert [r[2] for r in _rows(items, "items")][:6] == [-10, -20, -30, -40, -50, 60]


def test_the_queue_is_the_owners_alone(items: Conn, db_dsn: str) -> None:
    items.execute("ALTER DEFAULT PRIVILEGES GRANT ALL ON TABLES TO PUBLIC")  # a DBA's habit: not for the queue
    items.execute("CREATE TABLE other (id int PRIMARY KEY, val int)")
    tgsis.enable_versioning(items, "other", "id", "other")
    items.commit()
    with login_roles(db_dsn, {"clerk": "tgsis_editor"}) as roles:
        items.execute(f"GRANT SELECT, UPDATE (val) ON items TO {roles.name('clerk')}")
        items.commit()
        clerk = roles.connect("clerk")
        assert clerk.execute("UPDATE items SET val = 7 WHERE id = 1").rowcount == 1
        clerk.commit()
        with pytest.raises(psycopg.errors.InsufficientPrivilege):
            clerk.execute("UPDATE items SET note = 'x' WHERE id = 1")
        clerk.rollback()
        mine = "pg_current_xact_id(), 0"  # rows the clerk's own statement would look for
        for table, values in (("items_ver_queue", f"({mine}, 1, 'k1', 0)"), ("other_ver_queue", f"({mine}, 1, 0)")):
            for statement in (
                f"INSERT INTO {table} VALUES {values}",
                f"SELECT * FROM {table}",  # noqa: S608
                f"DELETE FROM {table}",
            ):  # noqa: S608
                with pytest.raises(psycopg.errors.InsufficientPrivilege):
                    clerk.execute(statement)
                clerk.rollback()
    queues = items.execute(
        "SELECT c.relname, c.relpersistence, pg_get_userbyid(c.relowner) = current_user, "
        "       (SELECT count(*) FROM aclexplode(c.relacl) a WHERE a.grantee <> c.relowner) "
        "FROM pg_class c WHERE c.relname IN ('items_ver_queue', 'other_ver_queue') ORDER BY 1"
    ).fetchall()
    assert queues == [("items_ver_queue", "u", True, 0), ("other_ver_queue", "u", True, 0)]
    other = items.execute(
        "SELECT count(*) FROM pg_class c, aclexplode(c.relacl) a WHERE c.relname = 'other' AND a.grantee = 0"
    ).fetchone()
    assert other is not None and other[0] > 0  # the default privileges did apply to the other new tables
    assert [r[2] for r in _rows(items, "items")][:2] == [7, 20]


def test_queue_columns_keep_the_storage_types(items: Conn) -> None:
    columns = items.execute(
        "SELECT a.attname, format_type(a.atttypid, a.atttypmod), a.attcollation::regcollation::text "
        "FROM pg_attribute a WHERE a.attrelid = 'items_ver_queue'::regclass AND a.attnum > 0 ORDER BY a.attnum"
    ).fetchall()
    storage = [
        ("id", "integer"),
        ("code", "text"),
        ("val", "integer"),
        ("g", "grade"),
        ("tags", "text[]"),
        ("note", "text"),
    ]
    tags = ["tgsis_xact", "tgsis_generation"]
    assert [c[0] for c in columns] == tags + [f"n{i}" for i in range(1, 7)] + [f"o{i}" for i in range(1, 7)]
    assert [c[1] for c in columns[2:8]] == [t for _, t in storage] == [c[1] for c in columns[8:]]
    assert columns[3][2] == '"C"' and columns[9][2] == '"C"'
    # a statement's rows are found by the index, not by a scan of what earlier statements deleted
    index = items.execute(
        "SELECT pg_get_indexdef(i.indexrelid), obj_description(i.indexrelid, 'pg_class') FROM pg_index i "
        "WHERE i.indrelid = 'items_ver_queue'::regclass"
    ).fetchall()
    assert len(index) == 1 and "(tgsis_xact, tgsis_generation)" in index[0][0] and index[0][1]
    comment = items.execute("SELECT obj_description('items_ver_queue'::regclass, 'pg_class')").fetchone()
    assert comment is not None and "empty outside a statement" in comment[0]


def test_features_of_no_version_and_versioned_ones_in_one_statement(conn: Conn) -> None:
    tgsis.enable_feature_versioning(conn)
    tgsis.create_feature_class(conn, "horizons", "SURFACE")
    tgsis.create_feature_class(conn, "wells", "SURFACE", versioned=False)
    surface = tgsis.Surface(np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], dtype=float), np.array([[0, 1, 2]]))
    horizon = tgsis.insert_feature(conn, "horizons", surface)
    well = tgsis.insert_feature(conn, "wells", surface)
    tgsis.create_version(conn, "v1")
    conn.commit()
    statement = "UPDATE tgsis.vrtx SET z = z + 1 WHERE geoid = ANY (%s)"
    with tgsis.in_version(conn, "v1"):
        with pytest.raises(psycopg.Error) as caught:
            conn.execute(statement, ([horizon, well],))
        assert caught.value.sqlstate == "TG305"
        conn.rollback()
    assert conn.execute(statement, ([horizon, well],)).rowcount == 6
    conn.commit()
    stored = conn.execute(
        f"SELECT geoid, revision, revclosed, z FROM {row_versions(conn, 'vrtx')} v WHERE geoid = ANY (%s) "
        "ORDER BY geoid, revclosed DESC, vrtxid",
        ([horizon, well],),
    ).fetchall()
    assert [r[1:] for r in stored if r[0] == well] == [(0, False, 1.0)] * 3  # in place, of no version
    assert [(r[2], r[3]) for r in stored if r[0] == horizon] == [(True, 0.0)] * 3 + [(False, 1.0)] * 3
    notes = conn.execute("SELECT objectkey FROM tgsis.revision_objects WHERE tablename = 'vrtx'").fetchall()
    assert (str(horizon),) in notes and (str(well),) not in notes


def test_a_locked_object_refuses_a_bulk_update_from_another_version(conn: Conn) -> None:
    conn.execute("CREATE TABLE items (id int PRIMARY KEY, val int)")
    conn.execute("INSERT INTO items SELECT g, g FROM generate_series(1, 10) g")
    tgsis.enable_versioning(conn, "items", "id", "item")
    tgsis.create_version(conn, "v1")
    conn.execute("SELECT tgsis.lock_objects('v1', 'item', ARRAY['4'])")
    conn.commit()
    with pytest.raises(psycopg.Error) as caught:
        conn.execute("UPDATE items SET val = 0")
    assert caught.value.sqlstate == "TG303"
    conn.rollback()
    assert conn.execute("UPDATE items SET val = 0 WHERE id <> 4").rowcount == 9
    conn.commit()
