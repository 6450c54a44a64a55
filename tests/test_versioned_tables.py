"""Versioned tables: an application written for a plain table runs unchanged (spec: versioning.md, row-level storage)."""

from __future__ import annotations

import uuid
from typing import Any

import psycopg
import pytest

import tgsis

Conn = psycopg.Connection[Any]

WELLS = """CREATE TABLE wells (
    id     serial PRIMARY KEY,
    name   text NOT NULL UNIQUE,
    depth  double precision DEFAULT 100 CHECK (depth >= 0),
    twice  double precision GENERATED ALWAYS AS (2 * depth) STORED,
    note   text)"""


def _app(conn: Conn) -> list[tuple[Any, ...]]:
    """What an application written for the plain table does: plain SQL strings only."""
    conn.execute("INSERT INTO wells (name, depth) VALUES ('w3', 30)")
    conn.execute("UPDATE wells SET depth = depth + 1, note = 'deepened' WHERE name = 'w1'")
    conn.execute("DELETE FROM wells WHERE name = 'w2'")
    row = conn.execute("INSERT INTO wells (name) VALUES ('w4') RETURNING depth").fetchone()
    assert row == (100.0,)
    return conn.execute("SELECT name, depth, twice, note FROM wells ORDER BY name").fetchall()


@pytest.fixture
def wells(conn: Conn) -> Conn:
    conn.execute(WELLS)
    conn.execute("COMMENT ON TABLE wells IS 'wells of the field'")
    conn.execute("COMMENT ON COLUMN wells.depth IS 'depth in m'")
    conn.execute("INSERT INTO wells (name, depth) VALUES ('w1', 10), ('w2', 20)")
    conn.commit()
    return conn


def _definition(conn: Conn, name: str = "wells") -> list[Any]:
    return conn.execute(
        "SELECT c.relkind, (SELECT array_agg(attname ORDER BY attnum) FROM pg_attribute "
        "                   WHERE attrelid = c.oid AND attnum > 0 AND NOT attisdropped), "
        "       (SELECT array_agg(pg_get_constraintdef(oid) ORDER BY conname) FROM pg_constraint WHERE conrelid = c.oid) "
        "FROM pg_class c WHERE c.oid = to_regclass(%s)",
        (name,),
    ).fetchall()


def test_application_runs_unchanged_in_a_version(wells: Conn) -> None:
    expected = _app(wells)
    wells.rollback()  # the plain table's answers, undone
    tgsis.enable_versioning(wells, "wells", "id", "well")
    tgsis.create_version(wells, "v1")
    tgsis.create_version(wells, "v2")
    tgsis.goto_version(wells, "v1")
    assert _app(wells) == expected  # same answers through the view, in v1
    wells.commit()
    tgsis.goto_version(wells, "v2")
    assert wells.execute("SELECT name, depth, note FROM wells ORDER BY name").fetchall() == [
        ("w1", 10.0, None),
        ("w2", 20.0, None),
    ]
    tgsis.goto_version(wells, "DEFAULT")
    assert wells.execute("SELECT name, depth FROM wells ORDER BY name").fetchall() == [("w1", 10.0), ("w2", 20.0)]
    # the view keeps the table's name, columns, comments
    assert [
        r[0]
        for r in wells.execute(
            "SELECT attname FROM pg_attribute WHERE attrelid = 'wells'::regclass AND attnum > 0 ORDER BY attnum"
        )
    ] == ["id", "name", "depth", "twice", "note"]
    assert wells.execute("SELECT col_description('wells'::regclass, 3)").fetchone() == ("depth in m",)
    assert "wells of the field" in str(wells.execute("SELECT obj_description('wells'::regclass)").fetchone())


def test_only_changed_rows_are_stored(conn: Conn) -> None:
    conn.execute("CREATE TABLE pts (oid int, pid int, x float8, PRIMARY KEY (oid, pid))")
    conn.execute("INSERT INTO pts SELECT 1, i, i FROM generate_series(0, 99999) i")
    tgsis.enable_versioning(conn, "pts", "oid", "pointset")
    tgsis.create_version(conn, "edit")
    tgsis.goto_version(conn, "edit")
    assert conn.execute("UPDATE pts SET x = -1 WHERE oid = 1 AND pid = 500").rowcount == 1
    conn.commit()
    counts = conn.execute(
        "SELECT count(*), count(*) FILTER (WHERE lastrevs <> '{}'), count(*) FILTER (WHERE revision <> 0) FROM pts_ver"
    ).fetchone()
    assert counts == (100_001, 1, 1)  # one new row, one closed, nothing copied
    assert conn.execute("SELECT x FROM pts WHERE pid = 500").fetchone() == (-1.0,)
    tgsis.goto_version(conn, "DEFAULT")
    assert conn.execute("SELECT x FROM pts WHERE pid = 500").fetchone() == (500.0,)
    # a second update in the same revision changes that row in place
    tgsis.goto_version(conn, "edit")
    conn.execute("UPDATE pts SET x = -2 WHERE pid = 500")
    assert conn.execute("SELECT count(*) FROM pts_ver").fetchone() == (100_001,)


def test_one_object_fetch_uses_an_index(conn: Conn) -> None:
    conn.execute("CREATE TABLE parts (objid int, k int, v float8, PRIMARY KEY (k))")
    conn.execute("INSERT INTO parts SELECT i / 100, i, i FROM generate_series(0, 49999) i")
    tgsis.enable_versioning(conn, "parts", "objid", "thing")  # object key is not the primary key's first column
    conn.execute("ANALYZE parts_ver")
    plan = "\n".join(r[0] for r in conn.execute("EXPLAIN SELECT * FROM parts WHERE objid = 7").fetchall())
    assert "parts_ver_object_idx" in plan and "Seq Scan" not in plan, plan
    assert conn.execute("SELECT count(*) FROM parts WHERE objid = 7").fetchone() == (100,)


def test_duplicate_keys_per_version(wells: Conn) -> None:
    tgsis.enable_versioning(wells, "wells", "id", "well")
    tgsis.create_version(wells, "a")
    tgsis.create_version(wells, "b")
    for version in ("a", "b"):  # the same new key in two sibling versions is fine
        tgsis.goto_version(wells, version)
        wells.execute("INSERT INTO wells (id, name) VALUES (50, %s)", (f"in {version}",))
        wells.commit()
    with pytest.raises(psycopg.errors.UniqueViolation, match='"wells_pkey"') as err:
        wells.execute("INSERT INTO wells (id, name) VALUES (1, 'again')")  # w1 is visible in b
    assert err.value.diag.message_detail == "Key (id)=(1) already exists in version 'b'."
    wells.rollback()
    wells.execute("DELETE FROM wells WHERE id = 1")
    wells.execute("INSERT INTO wells (id, name) VALUES (1, 'reborn')")  # a deleted key may come back
    assert wells.execute("SELECT name FROM wells WHERE id = 1").fetchone() == ("reborn",)


def test_key_change_is_delete_plus_insert(wells: Conn) -> None:
    tgsis.enable_versioning(wells, "wells", "id", "well")
    tgsis.create_version(wells, "a")
    tgsis.goto_version(wells, "a")
    wells.execute("UPDATE wells SET id = 10 WHERE id = 1")
    assert wells.execute("SELECT id, name FROM wells ORDER BY id").fetchall() == [(2, "w2"), (10, "w1")]
    with pytest.raises(psycopg.errors.UniqueViolation):
        wells.execute("UPDATE wells SET id = 2 WHERE id = 10")
    wells.rollback()
    tgsis.goto_version(wells, "DEFAULT")
    assert wells.execute("SELECT id FROM wells ORDER BY id").fetchall() == [(1,), (2,)]


def test_writes_while_viewing_an_old_revision_fail_and_change_nothing(wells: Conn) -> None:
    tgsis.enable_versioning(wells, "wells", "id", "well")
    tgsis.create_version(wells, "a")
    tgsis.goto_version(wells, "a")
    wells.execute("UPDATE wells SET depth = 11 WHERE id = 1")
    saved = tgsis.save_revision(wells, "before")
    wells.execute("UPDATE wells SET depth = 12 WHERE id = 1")
    wells.commit()
    stored = wells.execute("SELECT * FROM wells_ver ORDER BY id, revision").fetchall()
    tgsis.goto_revision(wells, "a", saved)
    wells.commit()  # a rollback below must not undo the goto
    assert wells.execute("SELECT depth FROM wells WHERE id = 1").fetchone() == (11.0,)
    for statement in (
        "INSERT INTO wells (name) VALUES ('x')",
        "UPDATE wells SET depth = 0",
        "DELETE FROM wells WHERE id = 2",
    ):
        with pytest.raises(psycopg.Error, match="viewed at revision") as err:
            wells.execute(statement)
        assert err.value.sqlstate == "TG301"
        assert (
            err.value.diag.message_detail is not None
            and "saved as 'before' and is frozen" in err.value.diag.message_detail
        )
        wells.rollback()
    tgsis.goto_version(wells, "a")
    assert wells.execute("SELECT * FROM wells_ver ORDER BY id, revision").fetchall() == stored


def test_defaults_identity_generated_and_copy_through_the_view(conn: Conn) -> None:
    conn.execute(
        "CREATE TABLE samples (id int GENERATED ALWAYS AS IDENTITY PRIMARY KEY, "
        "v float8 DEFAULT 1.5, v2 float8 GENERATED ALWAYS AS (v * 2) STORED, at date DEFAULT '2020-01-01')"
    )
    tgsis.enable_versioning(conn, "samples", "id", "sample")
    conn.execute("INSERT INTO samples DEFAULT VALUES")
    conn.execute("INSERT INTO samples (v) VALUES (4)")
    with conn.cursor().copy("COPY samples (v) FROM STDIN") as copy:
        copy.write_row([7.0])
    assert conn.execute("SELECT id, v, v2, at::text FROM samples ORDER BY id").fetchall() == [
        (1, 1.5, 3.0, "2020-01-01"),
        (2, 4.0, 8.0, "2020-01-01"),
        (3, 7.0, 14.0, "2020-01-01"),
    ]
    tgsis.disable_versioning(conn, "samples")
    assert conn.execute(
        "SELECT attidentity FROM pg_attribute WHERE attrelid = 'samples'::regclass AND attname = 'id'"
    ).fetchone() == ("a",)  # GENERATED ALWAYS again


def test_rows_at_reads_other_versions_without_moving(wells: Conn) -> None:
    tgsis.enable_versioning(wells, "wells", "id", "well")
    tgsis.create_version(wells, "a")
    tgsis.goto_version(wells, "a")
    wells.execute("UPDATE wells SET depth = 99 WHERE id = 2")
    wells.commit()
    tgsis.goto_version(wells, "DEFAULT")
    rows = wells.execute("SELECT id, depth FROM tgsis.rows_at(NULL::wells, 'a') ORDER BY id").fetchall()
    assert rows == [(1, 10.0), (2, 99.0)]
    assert wells.execute("SELECT id, depth FROM tgsis.rows_at(NULL::wells, 'a', 0) ORDER BY id").fetchall() == [
        (1, 10.0),
        (2, 20.0),
    ]
    assert tgsis.working_version(wells) == "DEFAULT"
    with pytest.raises(psycopg.Error, match="table tgsis.catalog is not versioned") as err:
        wells.execute("SELECT * FROM tgsis.rows_at(NULL::tgsis.catalog, 'a')")
    assert err.value.sqlstate == "TG200"
    wells.rollback()
    with pytest.raises(psycopg.Error, match="rows_at takes a row of the versioned table, not a integer") as err:
        wells.execute("SELECT * FROM tgsis.rows_at(NULL::int, 'a')")
    assert err.value.sqlstate == "TG100"


def test_delete_version_removes_its_rows_and_reopens_closed_ones(wells: Conn) -> None:
    tgsis.enable_versioning(wells, "wells", "id", "well")
    before = wells.execute("SELECT * FROM wells_ver ORDER BY id").fetchall()
    tgsis.create_version(wells, "a")
    tgsis.goto_version(wells, "a")
    _app(wells)
    wells.commit()
    assert tgsis.delete_version(wells, "a") == 3  # w1 new value, w3, w4
    assert wells.execute("SELECT * FROM wells_ver ORDER BY id").fetchall() == before


def test_disable_keeps_default_rows_and_restores_constraints(wells: Conn) -> None:
    definition = _definition(wells)
    tgsis.enable_versioning(wells, "wells", "id", "well")
    assert wells.execute("SELECT name FROM tgsis.versioning_dropped").fetchall() == [("wells_name_key",)]
    wells.execute("UPDATE wells SET depth = 15 WHERE id = 1")
    tgsis.create_version(wells, "a")
    tgsis.goto_version(wells, "a")
    wells.execute("INSERT INTO wells (name) VALUES ('only in a')")
    tgsis.goto_version(wells, "DEFAULT")
    wells.commit()
    with pytest.raises(tgsis.InUseError, match="versions other than DEFAULT changed public.wells: a"):
        tgsis.disable_versioning(wells, "wells")
    # only a's row goes: DEFAULT's update was made in its working revision 0, in place
    assert tgsis.disable_versioning(wells, "wells", force=True) == 1
    assert _definition(wells) == definition
    assert wells.execute("SELECT name, depth FROM wells ORDER BY id").fetchall() == [("w1", 15.0), ("w2", 20.0)]
    assert wells.execute("SELECT count(*) FROM tgsis.versioning_dropped").fetchone() == (0,)
    assert wells.execute("SELECT obj_description('wells'::regclass)").fetchone() == ("wells of the field",)


def test_foreign_keys_between_versioned_tables_are_dropped_and_restored(conn: Conn) -> None:
    conn.execute("CREATE TABLE surf (sid int PRIMARY KEY, name text)")
    conn.execute("CREATE TABLE node (sid int REFERENCES surf ON DELETE CASCADE, nid int, PRIMARY KEY (sid, nid))")
    with pytest.raises(
        tgsis.InUseError, match=r"foreign keys of plain tables refer to public.surf: public.node \(node_sid_fkey\)"
    ):
        tgsis.enable_versioning(conn, "surf", "sid", "surface")
    assert _definition(conn, "surf")[0][0] == "r"
    tgsis.enable_versioning(conn, "node", "sid", "surface", 1)  # its key to the plain surf stays
    assert conn.execute("SELECT count(*) FROM pg_constraint WHERE conname = 'node_sid_fkey'").fetchone() == (1,)
    tgsis.enable_versioning(conn, "surf", "sid", "surface", 0)  # now both versioned: the key goes
    assert conn.execute("SELECT count(*) FROM pg_constraint WHERE conname = 'node_sid_fkey'").fetchone() == (0,)
    tgsis.disable_versioning(conn, "surf")
    assert conn.execute("SELECT count(*) FROM pg_constraint WHERE conname = 'node_sid_fkey'").fetchone() == (0,)
    tgsis.disable_versioning(conn, "node")  # both plain again: restored
    assert conn.execute(
        "SELECT pg_get_constraintdef(oid) FROM pg_constraint WHERE conname = 'node_sid_fkey'"
    ).fetchone() == ("FOREIGN KEY (sid) REFERENCES surf(sid) ON DELETE CASCADE",)


@pytest.mark.parametrize(
    ("setup", "call", "error", "message"),
    [
        ("CREATE TABLE t (a int)", ("t", "a"), tgsis.InvalidInputError, "has no primary key"),
        (
            "CREATE TABLE t (a int PRIMARY KEY); CREATE VIEW tv AS SELECT * FROM t",
            ("tv", "a"),
            tgsis.InvalidInputError,
            "is not a table: only ordinary and partitioned tables can be versioned",
        ),
        (
            "CREATE TABLE t (a int PRIMARY KEY) PARTITION BY HASH (a); "
            "CREATE TABLE t0 PARTITION OF t FOR VALUES WITH (MODULUS 1, REMAINDER 0); GRANT INSERT ON t0 TO tgsis_editor",
            ("t", "a"),
            tgsis.InvalidInputError,
            r"partitions of public\.t grant rights to other roles: public\.t0 \(tgsis_editor\)",
        ),
        (
            "CREATE TABLE t (a int PRIMARY KEY); CREATE VIEW tv AS SELECT * FROM t",
            ("t", "a"),
            tgsis.InUseError,
            "views depend on public.t: public.tv",
        ),
        (
            "CREATE TABLE t (a int PRIMARY KEY, revision int)",
            ("t", "a"),
            tgsis.InvalidInputError,
            "column named revision",
        ),
        ("CREATE TABLE t (a int PRIMARY KEY)", ("t", "b"), tgsis.NotFoundError, "has no column 'b'"),
        ("CREATE TABLE t (a int PRIMARY KEY)", ("nope", "a"), tgsis.NotFoundError, "table 'nope' does not exist"),
        (
            "CREATE TABLE t (a int PRIMARY KEY)",
            ("tgsis.catalog", "classname"),
            tgsis.InvalidInputError,
            "part of tgsis's own catalog",
        ),
        ('CREATE TABLE "%s" (a int PRIMARY KEY)' % ("x" * 55), ("x" * 55, "a"), tgsis.InvalidNameError, "too long"),
    ],
)
def test_enable_versioning_refusals_leave_everything_as_it_was(
    conn: Conn, setup: str, call: tuple[str, str], error: type[Exception], message: str
) -> None:
    conn.execute(setup)
    conn.commit()
    before = conn.execute(
        "SELECT relname, relkind FROM pg_class WHERE relnamespace = 'public'::regnamespace ORDER BY relname"
    ).fetchall()
    with pytest.raises(error, match=message):
        tgsis.enable_versioning(conn, call[0], call[1], "things")
    after = conn.execute(
        "SELECT relname, relkind FROM pg_class WHERE relnamespace = 'public'::regnamespace ORDER BY relname"
    ).fetchall()
    assert after == before
    assert conn.execute("SELECT count(*) FROM tgsis.versioned_tables").fetchone() == (0,)


def test_enable_twice_is_refused(wells: Conn) -> None:
    tgsis.enable_versioning(wells, "wells", "id", "well")
    with pytest.raises(tgsis.AlreadyExistsError, match="versioned already"):
        tgsis.enable_versioning(wells, "wells", "id", "well")
    with pytest.raises(tgsis.NotFoundError, match="is not versioned"):
        tgsis.disable_versioning(wells, "tgsis.catalog")


def test_a_role_with_table_rights_writes_through_the_view(wells: Conn) -> None:
    role = f"app_{uuid.uuid4().hex[:8]}"
    wells.execute(f"CREATE ROLE {role} NOLOGIN")
    try:
        wells.execute(f"GRANT SELECT, INSERT, UPDATE ON wells TO {role}")
        wells.execute(f"GRANT USAGE ON SEQUENCE wells_id_seq TO {role}")
        tgsis.enable_versioning(wells, "wells", "id", "well")
        wells.commit()
        wells.execute(f"SET ROLE {role}")
        # table rights say which tables, version rights which versions
        with pytest.raises(psycopg.Error, match=f"role {role} may not write in version 'DEFAULT'") as refused:
            wells.execute("INSERT INTO wells (name) VALUES ('by app')")
        assert refused.value.sqlstate == "TG002"
        wells.rollback()
        tgsis.grant_version(wells, "DEFAULT", "write", role)
        wells.commit()
        wells.execute(f"SET ROLE {role}")
        wells.execute("INSERT INTO wells (name) VALUES ('by app')")
        wells.execute("UPDATE wells SET depth = 1 WHERE name = 'w1'")
        with pytest.raises(psycopg.errors.InsufficientPrivilege):
            wells.execute("DELETE FROM wells")  # not granted on the table, so not on the view
        wells.rollback()
        wells.execute(f"SET ROLE {role}")
        # the view needed no right on schema tgsis; rows_at does (tgsis_reader)
        with pytest.raises(psycopg.errors.InsufficientPrivilege, match="schema tgsis"):
            wells.execute("SELECT count(*) FROM tgsis.rows_at(NULL::wells, 'DEFAULT')")
        wells.rollback()
        wells.execute(f"GRANT tgsis_reader TO {role}")
        wells.commit()
        wells.execute(f"SET ROLE {role}")
        # the storage keeps the table's grants, so that rows_at works for the same roles
        assert wells.execute("SELECT count(*) FROM tgsis.rows_at(NULL::wells, 'DEFAULT')").fetchone() == (2,)
        wells.rollback()
    finally:
        wells.rollback()
        tgsis.revoke_version(wells, "DEFAULT", "all", role)
        wells.execute(f"DROP OWNED BY {role}")
        wells.execute(f"DROP ROLE {role}")
        wells.commit()


def test_create_version_waits_for_writers_of_the_parent(wells: Conn, db_dsn: str) -> None:
    """A row written in the parent's working revision by an open transaction must not slip into a child."""
    tgsis.enable_versioning(wells, "wells", "id", "well")
    wells.execute("INSERT INTO wells (name) VALUES ('in flight')")  # holds DEFAULT's revision 0, not committed
    with psycopg.connect(db_dsn) as other:
        other.execute("SET lock_timeout = '300ms'")
        with pytest.raises(tgsis.DatabaseError, match="lock timeout"):
            tgsis.create_version(other, "child")
        other.rollback()
        wells.commit()  # the writer is done
        assert tgsis.create_version(other, "child") == 2
        tgsis.goto_version(other, "child")
        assert ("in flight",) in other.execute("SELECT name FROM wells").fetchall()
    wells.execute("INSERT INTO wells (name) VALUES ('after')")  # DEFAULT's new working revision 1
    wells.commit()
    rows = wells.execute("SELECT name FROM tgsis.rows_at(NULL::wells, 'child') ORDER BY id").fetchall()
    assert ("after",) not in rows and ("in flight",) in rows


def test_names_that_need_quoting(conn: Conn) -> None:
    conn.execute("""CREATE TABLE "Odd Table" ("o'k" int, "my%col" int, "v" text, PRIMARY KEY ("o'k", "my%col"))""")
    conn.execute("""INSERT INTO "Odd Table" VALUES (1, 2, 'a')""")
    t = tgsis.enable_versioning(conn, '"Odd Table"', "o'k", "odd class")
    assert (t.table, t.keycolumns) == ("Odd Table", ("o'k", "my%col"))
    tgsis.create_version(conn, "v")
    tgsis.goto_version(conn, "v")
    conn.execute("""UPDATE "Odd Table" SET v = 'b' WHERE "o'k" = 1""")
    conn.commit()
    with pytest.raises(psycopg.errors.UniqueViolation) as err:
        conn.execute("""INSERT INTO "Odd Table" VALUES (1, 2, 'c')""")
    assert err.value.diag.message_detail == """Key ("o'k", "my%col")=(1, 2) already exists in version 'v'."""
    conn.rollback()
    assert conn.execute('SELECT v FROM "Odd Table"').fetchall() == [("b",)]
    tgsis.goto_version(conn, "DEFAULT")
    assert conn.execute('SELECT v FROM "Odd Table"').fetchall() == [("a",)]
