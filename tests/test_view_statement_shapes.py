"""Every statement shape PostgreSQL accepts on a plain table, through versioned views (issue 36, point 1).

Each shape runs twice: on two versioned tables (``a``, ``b``) and on two plain
tables (``pa``, ``pb``) holding the same rows. It must give the same row count
and leave the same data, or be refused with a clear error before anything is
written; either way no row may be left in the views' queues
(``<table>_ver_queue``) once the statement ended (docs/versioning.md, "How an
UPDATE is written" and "Statement shapes").
"""

from __future__ import annotations

from typing import Any

import psycopg
import pytest

import tgsis

Conn = psycopg.Connection[Any]

ROWS = 30
SETS = ({"a": "a", "b": "b", "ev": "ev", "s": "v"}, {"a": "pa", "b": "pb", "ev": "pev", "s": "p"})


@pytest.fixture
def shapes(conn: Conn) -> Conn:
    """Versioned a and b, their plain twins pa and pb, and per set the functions and triggers the shapes call."""
    for table in ("a", "b", "pa", "pb"):
        conn.execute(f"CREATE TABLE {table} (id int PRIMARY KEY, val int NOT NULL, note text)")
        conn.execute(f"INSERT INTO {table} SELECT g, g * 10, 'n' || g FROM generate_series(1, {ROWS}) g")  # noqa: S608
    tgsis.enable_versioning(conn, "a", "id", "obj_a")
    tgsis.enable_versioning(conn, "b", "id", "obj_b")
    for names in SETS:
        conn.execute(
            "CREATE FUNCTION bump_{s}(i int) RETURNS int LANGUAGE plpgsql AS $$ BEGIN "
            "UPDATE {b} SET val = val + 1000 WHERE id IN (i, i + 1); RETURN i; END $$".format(**names)
        )
        conn.execute(  # the view the statement updates, other rows
            "CREATE FUNCTION shift_{s}(i int) RETURNS int LANGUAGE plpgsql AS $$ BEGIN "
            "UPDATE {a} SET note = 'by ' || i WHERE id IN (i + 20, i + 21); RETURN -i; END $$".format(**names)
        )
        conn.execute(  # an error caught after its update: the update is undone, the statement goes on
            "CREATE FUNCTION safe_{s}(i int) RETURNS int LANGUAGE plpgsql AS $$ BEGIN "
            "UPDATE {b} SET val = val + i WHERE id <= i; "
            "IF i % 3 = 0 THEN RAISE EXCEPTION 'undone'; END IF; RETURN i; "
            "EXCEPTION WHEN raise_exception THEN RETURN -i; END $$".format(**names)
        )
        conn.execute(
            "CREATE FUNCTION safe_self_{s}(i int) RETURNS int LANGUAGE plpgsql AS $$ BEGIN "
            "UPDATE {a} SET note = 'safe ' || i WHERE id BETWEEN 20 + i AND 22 + i; "
            "IF i % 2 = 0 THEN RAISE EXCEPTION 'undone'; END IF; RETURN i; "
            "EXCEPTION WHEN raise_exception THEN RETURN -i; END $$".format(**names)
        )
        conn.execute("CREATE TABLE {ev} (n int)".format(**names))
        conn.execute(  # a user's trigger on another table whose side effect updates the view
            "CREATE FUNCTION on_{ev}() RETURNS trigger LANGUAGE plpgsql AS $$ BEGIN "
            "UPDATE {a} SET val = val + NEW.n WHERE id % 5 = NEW.n % 5; "
            "UPDATE {b} SET note = 'ev ' || NEW.n WHERE id % 7 = NEW.n; RETURN NEW; END $$".format(**names)
        )
        conn.execute(
            "CREATE TRIGGER before_{ev} BEFORE INSERT ON {ev} FOR EACH ROW EXECUTE FUNCTION on_{ev}()".format(**names)
        )
        conn.execute(
            "CREATE TRIGGER after_{ev} AFTER INSERT ON {ev} FOR EACH ROW EXECUTE FUNCTION on_{ev}()".format(**names)
        )
        conn.execute(
            "CREATE FUNCTION once_{ev}() RETURNS trigger LANGUAGE plpgsql AS $$ BEGIN "
            "UPDATE {a} SET note = 'statement' WHERE id > 25; RETURN NULL; END $$".format(**names)
        )
        conn.execute(
            "CREATE TRIGGER stmt_{ev} AFTER INSERT ON {ev} FOR EACH STATEMENT EXECUTE FUNCTION once_{ev}()".format(
                **names
            )
        )
    conn.commit()
    return conn


SHAPES: dict[str, list[str]] = {
    "cte-two-views": [
        "WITH x AS (UPDATE {a} SET val = val + 1 WHERE id <= 10 RETURNING id) "
        "UPDATE {b} SET val = val + 100 WHERE id IN (SELECT id FROM x)"
    ],
    "cte-two-views-unread": [
        "WITH x AS (UPDATE {a} SET val = val + 2 WHERE id > 15 RETURNING id) UPDATE {b} SET val = -val WHERE id <= 12"
    ],
    "cte-three-updates": [
        "WITH x AS (UPDATE {a} SET val = val + 2 WHERE id > 15 RETURNING id), "
        "y AS (UPDATE {b} SET note = 'y' WHERE id IN (SELECT id - 10 FROM x) RETURNING id) "
        "UPDATE {b} SET val = 0 WHERE id > 25"
    ],
    "cte-same-view-twice": [
        "WITH x AS (UPDATE {a} SET val = val + 3 WHERE id <= 10 RETURNING id) UPDATE {a} SET note = 'twice' WHERE id > 20"
    ],
    "cte-same-view-read": [
        "WITH x AS (UPDATE {a} SET val = val + 4 WHERE id <= 10 RETURNING id) "
        "UPDATE {a} SET note = 'after' WHERE id IN (SELECT id + 10 FROM x)"
    ],
    "cte-insert-and-update": [
        "WITH x AS (INSERT INTO {b} SELECT g, g, 'new' FROM generate_series(31, 35) g RETURNING id) "
        "UPDATE {a} SET val = val + 1 WHERE id IN (SELECT id - 25 FROM x)"
    ],
    "set-list-other-view": ["UPDATE {a} SET val = bump_{s}(id) WHERE id <= 10"],
    "set-list-same-view": ["UPDATE {a} SET val = shift_{s}(id) WHERE id <= 10"],
    "set-list-caught-error": ["UPDATE {a} SET val = safe_{s}(id) WHERE id <= 9"],
    "set-list-same-view-caught-error": ["UPDATE {a} SET val = safe_self_{s}(id) WHERE id <= 6"],
    "trigger-side-effect": ["INSERT INTO {ev} SELECT g FROM generate_series(1, 4) g"],
    "nested-do": [
        "DO $$ BEGIN UPDATE {a} SET val = val + 5 WHERE id <= 6; "
        "EXECUTE 'DO $x$ BEGIN UPDATE {a} SET val = val * 2 WHERE id <= 8; "
        "UPDATE {b} SET val = val + 1 WHERE id <= 9; END $x$'; "
        "UPDATE {b} SET note = 'do' WHERE id <= 4; UPDATE {a} SET val = val + 1 WHERE id <= 8; END $$"
    ],
    "do-loop": [
        "DO $$ BEGIN FOR i IN 1 .. 12 LOOP UPDATE {a} SET val = val + i WHERE id IN (i, i + 1, i + 2); "
        "UPDATE {b} SET val = val - i WHERE id > i; END LOOP; END $$"
    ],
    "caught-error-mid-statement": [
        "DO $$ BEGIN UPDATE {a} SET val = val + 7 WHERE id <= 5; "
        "BEGIN UPDATE {a} SET val = val / (id - 8) WHERE id <= 12; "
        "EXCEPTION WHEN division_by_zero THEN UPDATE {b} SET note = 'caught' WHERE id <= 3; END; "
        "UPDATE {a} SET note = 'after' WHERE id <= 14; END $$"
    ],
    "savepoints": [
        "UPDATE {a} SET val = val + 1 WHERE id <= 10",
        "SAVEPOINT s1",
        "UPDATE {a} SET val = val + 100 WHERE id <= 20",
        "WITH x AS (UPDATE {b} SET val = 0 WHERE id <= 5 RETURNING id) UPDATE {a} SET note = 'lost' WHERE id > 20",
        "ROLLBACK TO SAVEPOINT s1",
        "UPDATE {a} SET val = val + 10 WHERE id BETWEEN 5 AND 15",
        "SAVEPOINT s2",
        "UPDATE {b} SET val = val + 10 WHERE id <= 15",
        "RELEASE SAVEPOINT s2",
    ],
    "multi-statement-string": [
        "UPDATE {a} SET val = val + 1 WHERE id <= 4; UPDATE {a} SET val = val + 1 WHERE id <= 8"
    ],
    "on-conflict-do-nothing-without-conflict": [
        "INSERT INTO {b} SELECT g, g, 'oc' FROM generate_series(40, 44) g ON CONFLICT DO NOTHING"
    ],
}


def _data(conn: Conn, table: str) -> list[tuple[Any, ...]]:
    return conn.execute(f"SELECT id, val, note FROM {table} ORDER BY id").fetchall()  # noqa: S608


def _queued(conn: Conn) -> int:
    row = conn.execute("SELECT (SELECT count(*) FROM a_ver_queue) + (SELECT count(*) FROM b_ver_queue)").fetchone()
    assert row is not None
    return int(row[0])


def _run(conn: Conn, statements: list[str], names: dict[str, str]) -> list[int]:
    counts = []
    for statement in statements:
        counts.append(conn.execute(statement.format(**names)).rowcount)
        assert names["a"] == "pa" or _queued(conn) == 0, f"rows left queued after {statement!r}"
    return counts


@pytest.mark.parametrize("shape", list(SHAPES))
@pytest.mark.parametrize("version", ["DEFAULT", "child"])
def test_a_statement_shape_gives_the_plain_tables_result_and_leaves_nothing_queued(
    shapes: Conn, shape: str, version: str
) -> None:
    tgsis.create_version(shapes, "child")
    shapes.commit()
    with tgsis.in_version(shapes, version):
        shapes.commit()
        versioned = _run(shapes, SHAPES[shape], SETS[0])
        shapes.commit()
        assert _queued(shapes) == 0
    plain = _run(shapes, SHAPES[shape], SETS[1])
    shapes.commit()
    assert versioned == plain
    with tgsis.in_version(shapes, version, local=True):
        assert _data(shapes, "a") == _data(shapes, "pa")
        assert _data(shapes, "b") == _data(shapes, "pb")
        assert (
            shapes.execute("SELECT n FROM ev ORDER BY n").fetchall()
            == shapes.execute("SELECT n FROM pev ORDER BY n").fetchall()
        )
    shapes.rollback()
    if version == "child":  # DEFAULT did not move
        assert _data(shapes, "a") == [(i, i * 10, f"n{i}") for i in range(1, ROWS + 1)]
    shapes.rollback()


def test_every_shape_in_one_transaction_leaves_nothing_queued(shapes: Conn) -> None:
    """All the shapes one after the other in one transaction (the generations of both views move on)."""
    for names in SETS:
        for statements in SHAPES.values():
            for statement in statements:
                shapes.execute(statement.format(**names))
            if names["a"] == "a":
                assert _queued(shapes) == 0
        shapes.commit()
    assert _queued(shapes) == 0
    assert _data(shapes, "a") == _data(shapes, "pa")
    assert _data(shapes, "b") == _data(shapes, "pb")


def _storage(conn: Conn) -> list[tuple[Any, ...]]:
    rows = conn.execute(
        "SELECT 'a', id, revision, lastrevs, val, note FROM a_ver UNION ALL "
        "SELECT 'b', id, revision, lastrevs, val, note FROM b_ver ORDER BY 1, 2, 3"
    ).fetchall()
    conn.rollback()
    return rows


def test_on_conflict_do_nothing_meeting_a_conflict_is_refused_by_name(shapes: Conn) -> None:
    before = _storage(shapes)
    statement = "INSERT INTO {b} SELECT g, g, 'oc' FROM generate_series(28, 33) g ON CONFLICT DO NOTHING"
    assert shapes.execute(statement.format(b="pb")).rowcount == 3  # the plain table skips 28..30
    shapes.rollback()
    with pytest.raises(psycopg.Error) as caught:
        shapes.execute(statement.format(b="b"))
    assert caught.value.sqlstate == "TG306"
    assert "ON CONFLICT" in str(caught.value) and "public.b" in str(caught.value)
    assert caught.value.diag.message_hint is not None and "NOT EXISTS" in caught.value.diag.message_hint
    shapes.rollback()
    assert _storage(shapes) == before
    assert _queued(shapes) == 0


@pytest.mark.parametrize("clause", ["ON CONFLICT (id) DO NOTHING", "ON CONFLICT (id) DO UPDATE SET val = excluded.val"])
def test_on_conflict_with_a_target_is_refused_before_anything_is_written(shapes: Conn, clause: str) -> None:
    """A view has no unique index to infer: PostgreSQL itself refuses it, before the trigger runs."""
    before = _storage(shapes)
    with pytest.raises(psycopg.errors.InvalidColumnReference, match="ON CONFLICT"):
        shapes.execute(f"INSERT INTO b VALUES (1, 5, 'x'), (50, 5, 'y') {clause}")
    shapes.rollback()
    assert _storage(shapes) == before


def test_a_version_change_between_rows_is_refused_and_nothing_written(shapes: Conn) -> None:
    """A function of the SET list moves the session to another version at the fifth row."""
    tgsis.create_version(shapes, "child")
    shapes.execute(
        "CREATE FUNCTION hop(i int) RETURNS int LANGUAGE sql VOLATILE AS "
        "$$ SELECT CASE WHEN i = 5 THEN length(set_config('tgsis.version', 'child', true)) * 0 + i ELSE i END $$"
    )
    shapes.commit()
    before = _storage(shapes)
    with pytest.raises(psycopg.Error) as caught:
        shapes.execute("UPDATE a SET val = hop(id) * 7 WHERE id <= 10")
    assert caught.value.sqlstate == "TG306"
    assert "public.a" in str(caught.value) and "version" in str(caught.value)
    shapes.rollback()
    assert _storage(shapes) == before
    assert _queued(shapes) == 0


def test_a_version_change_after_the_last_row_is_refused(shapes: Conn) -> None:
    """The version changes after the view's last row was queued (a later CTE's function): its rows were read in
    one version and would be written in another."""
    tgsis.create_version(shapes, "child")
    shapes.execute(
        "CREATE FUNCTION hop_now(i int) RETURNS int LANGUAGE sql VOLATILE AS "
        "$$ SELECT length(set_config('tgsis.version', 'child', true)) * 0 + i $$"
    )
    shapes.commit()
    before = _storage(shapes)
    with pytest.raises(psycopg.Error) as caught:
        shapes.execute(
            "WITH x AS (UPDATE a SET val = 0 WHERE id <= 10 RETURNING id) "
            "UPDATE pb SET val = hop_now(pb.id) FROM x WHERE pb.id = x.id"
        )
    assert caught.value.sqlstate == "TG306"
    shapes.rollback()
    assert _storage(shapes) == before


def test_a_nested_update_of_a_row_the_statement_also_changes_is_refused(shapes: Conn) -> None:
    """The statement and a function it calls change the same row of the view. A row the function changed before
    the statement reached it: 27000, as a plain table; a row the statement queued and the function changes
    again: 21000 (a plain table applies both); nothing written either way."""
    shapes.execute(
        "CREATE FUNCTION same_row(i int) RETURNS int LANGUAGE plpgsql AS $$ BEGIN "
        "UPDATE a SET note = 'inner' WHERE id = 3; RETURN i; END $$"
    )
    shapes.commit()
    before = _storage(shapes)
    for table in ("a", "pa"):
        with pytest.raises(psycopg.errors.TriggeredDataChangeViolation):
            shapes.execute(f"UPDATE {table} SET val = same_row(id) WHERE id <= 5")
        shapes.rollback()
        shapes.execute(
            "CREATE OR REPLACE FUNCTION same_row(i int) RETURNS int LANGUAGE plpgsql AS $$ BEGIN "
            "UPDATE pa SET note = 'inner' WHERE id = 3; RETURN i; END $$"
        )
    shapes.execute(
        "CREATE OR REPLACE FUNCTION same_row(i int) RETURNS int LANGUAGE plpgsql AS $$ BEGIN "
        "IF i = 4 THEN UPDATE a SET note = 'inner' WHERE id = 3; END IF; RETURN i; END $$"
    )
    with pytest.raises(psycopg.errors.CardinalityViolation):
        shapes.execute("UPDATE a SET val = same_row(id) WHERE id <= 5")
    shapes.rollback()
    assert _storage(shapes) == before
    assert _queued(shapes) == 0


@pytest.mark.parametrize(
    "change",
    [
        "length(set_config('tgsis.revision', '0', true))",  # view an older revision from inside the statement
        "length(set_config('role', 'tgsis_admin', true))",  # act as another role from inside the statement
        "tgsis.save_revision('mid-statement')",  # freeze the working revision the rows are being written in
    ],
    ids=["revision", "role", "save-revision"],
)
@pytest.mark.parametrize("where", ["between-rows", "after-the-last-row"])
def test_a_revision_or_role_change_inside_an_update_is_refused(shapes: Conn, change: str, where: str) -> None:
    """As a version change: a function of the statement that changes the session's revision or role, or saves
    the working revision, makes the rows read in one and written in another; refused, nothing written."""
    shapes.execute(
        f"CREATE FUNCTION swap(i int) RETURNS int LANGUAGE sql VOLATILE AS "
        f"$$ SELECT CASE WHEN i = 5 THEN ({change}) * 0 + i ELSE i END $$"
    )
    shapes.commit()
    before = _storage(shapes)
    statement = (
        "UPDATE a SET val = swap(id) * 7 WHERE id <= 10"
        if where == "between-rows"
        else "WITH x AS (UPDATE a SET val = 0 WHERE id <= 10 RETURNING id) "
        "UPDATE pb SET val = swap(pb.id) FROM x WHERE pb.id = x.id"
    )
    with pytest.raises(psycopg.Error) as caught:
        shapes.execute(statement)
    assert caught.value.sqlstate == "TG306", caught.value.diag.message_primary
    assert "public.a" in str(caught.value)
    shapes.rollback()
    assert _storage(shapes) == before
    assert _queued(shapes) == 0


def test_on_conflict_inside_a_function_is_an_error_never_a_loss(shapes: Conn) -> None:
    """INSERT ... ON CONFLICT DO NOTHING meeting an existing row, run by a function: the top-level query text
    does not say ON CONFLICT, so TG306 cannot name it (docs/versioning.md); the duplicate is still an error
    (23505), and nothing is written."""
    shapes.execute(
        "CREATE FUNCTION add_some() RETURNS int LANGUAGE plpgsql AS $$ DECLARE n int; BEGIN "
        "INSERT INTO b SELECT g, g, 'oc' FROM generate_series(28, 33) g ON CONFLICT DO NOTHING; "
        "GET DIAGNOSTICS n = ROW_COUNT; RETURN n; END $$"
    )
    shapes.commit()
    before = _storage(shapes)
    with pytest.raises(psycopg.Error) as caught:
        shapes.execute("SELECT add_some()")
    assert caught.value.sqlstate in ("TG306", "23505"), caught.value.diag.message_primary
    shapes.rollback()
    assert _storage(shapes) == before
    assert _queued(shapes) == 0
