"""Versioning a hash-partitioned table (issue 20, the step of docs/scaling.md measurable on one node).

The same edits, conflicts, merges, refreshes, compression, version deletion
and disabling are applied to a plain table and to a copy partitioned by the
object key; every version must see the same rows in both and both storages
must hold the same row versions. A row version is named by (tableoid, ctid):
a ctid alone is unique only within one partition, and the first try with
ctid alone closed rows of the same place in every partition.
"""

from __future__ import annotations

from typing import Any

import psycopg
import pytest
from psycopg import sql

import tgsis
from tests.roles import login_roles
from tests.sessions import Background, wait_until_blocked

Conn = psycopg.Connection[Any]
TABLES = ("flat", "part")


@pytest.fixture
def tables(conn: Conn) -> Conn:
    """flat and part (objid, k, val) with objects 1..20 of 5 rows, part hash-partitioned by objid in 4; versioned."""
    conn.execute("CREATE TABLE flat (objid int, k int, val int NOT NULL, PRIMARY KEY (objid, k))")
    conn.execute(
        "CREATE TABLE part (objid int, k int, val int NOT NULL, PRIMARY KEY (objid, k)) PARTITION BY HASH (objid)"
    )
    for r in range(4):
        conn.execute(
            sql.SQL("CREATE TABLE {} PARTITION OF part FOR VALUES WITH (MODULUS 4, REMAINDER {})").format(
                sql.Identifier(f"part{r}"), sql.Literal(r)
            )
        )
    for table in TABLES:
        conn.execute(
            sql.SQL(
                "INSERT INTO {} SELECT o, k, 100 * o + k FROM generate_series(1, 20) o, generate_series(1, 5) k"
            ).format(sql.Identifier(table))
        )
        tgsis.enable_versioning(conn, table, "objid", table)
    for version in ("a", "b", "gone"):
        tgsis.create_version(conn, version)
    conn.commit()
    return conn


def _both(conn: Conn, version: str, statement: str) -> None:
    """Run a statement (with {t} for the table) on both tables in a version."""
    with tgsis.in_version(conn, version):
        for table in TABLES:
            conn.execute(sql.SQL(statement).format(t=sql.Identifier(table)))
        conn.commit()


def _seen(conn: Conn, table: str, version: str) -> list[tuple[Any, ...]]:
    with tgsis.in_version(conn, version, local=True):
        rows = conn.execute(
            sql.SQL("SELECT objid, k, val FROM {} ORDER BY 1, 2").format(sql.Identifier(table))
        ).fetchall()
    conn.rollback()
    return rows


def _stored(conn: Conn, table: str) -> list[tuple[Any, ...]]:
    return conn.execute(
        sql.SQL("SELECT objid, k, val, revision, lastrevs FROM {} ORDER BY 1, 2, 4").format(
            sql.Identifier(table + "_ver")
        )
    ).fetchall()


def _same(conn: Conn) -> None:
    versions = [name for (name,) in conn.execute("SELECT name FROM tgsis.versions ORDER BY 1").fetchall()]
    for version in versions:
        assert _seen(conn, "part", version) == _seen(conn, "flat", version), version
    assert _stored(conn, "part") == _stored(conn, "flat")


def test_versioning_a_partitioned_table_keeps_its_partitions(tables: Conn) -> None:
    conn = tables
    kind = conn.execute("SELECT relkind FROM pg_class WHERE oid = 'part_ver'::regclass").fetchone()
    parts = conn.execute(
        "SELECT count(*), sum((SELECT count(*) FROM part_ver v WHERE v.tableoid = p.relid)) "
        "FROM pg_partition_tree('part_ver') p WHERE p.isleaf"
    ).fetchone()
    assert kind == ("p",) and parts == (4, 100)
    assert conn.execute("SELECT count(*) FROM part").fetchone() == (100,)


def test_edits_merges_and_cleanup_give_the_same_rows_as_a_plain_table(tables: Conn) -> None:
    conn = tables
    _both(conn, "a", "UPDATE {t} SET val = val + 1 WHERE objid IN (1, 2, 3)")  # inherited rows: closed, written anew
    _both(conn, "a", "UPDATE {t} SET val = val + 1 WHERE objid = 1")  # rows of its own: in place
    _both(conn, "a", "DELETE FROM {t} WHERE objid = 4 AND k = 2")
    _both(conn, "a", "INSERT INTO {t} VALUES (30, 1, 1)")
    _both(conn, "a", "UPDATE {t} SET objid = 31 WHERE objid = 5 AND k = 1")  # a new key: another partition
    _both(conn, "DEFAULT", "UPDATE {t} SET val = val + 10 WHERE objid IN (3, 6)")
    _both(conn, "b", "UPDATE {t} SET val = 0 WHERE objid IN (6, 7)")
    _both(conn, "gone", "UPDATE {t} SET val = -1 WHERE objid IN (8, 9)")
    _same(conn)

    conflicts = {(c.objectclass, c.objectkey) for c in tgsis.find_conflicts(conn, "a")}
    assert conflicts == {("flat", "3"), ("part", "3")}
    for table in TABLES:
        tgsis.resolve_conflict(conn, "a", table, 3, "child")
    tgsis.merge_version(conn, "a", remove=True)
    conn.commit()
    _same(conn)
    assert _seen(conn, "part", "DEFAULT")[:5] == [(1, k, 100 + k + 2) for k in range(1, 6)]

    assert {c.objectkey for c in tgsis.find_conflicts(conn, "b")} == {"6"}
    for table in TABLES:
        tgsis.resolve_conflict(conn, "b", table, 6, "parent")
    tgsis.refresh_version(conn, "b")
    conn.commit()
    _same(conn)
    tgsis.merge_version(conn, "b")
    conn.commit()
    _same(conn)

    tgsis.delete_version(conn, "gone")
    conn.execute("SELECT tgsis.compress_versions()")
    conn.commit()
    _same(conn)
    assert conn.execute("SELECT count(*) FROM part_ver WHERE objid IN (8, 9) AND val = -1").fetchone() == (0,)

    for table in TABLES:
        tgsis.disable_versioning(conn, table, force=True)
    conn.commit()
    assert conn.execute("SELECT relkind FROM pg_class WHERE oid = 'part'::regclass").fetchone() == ("p",)
    assert (
        conn.execute("SELECT * FROM part ORDER BY 1, 2").fetchall()
        == conn.execute("SELECT * FROM flat ORDER BY 1, 2").fetchall()
    )


def test_a_merge_waits_for_a_writer_holding_a_row_it_closes_in_a_partition(tables: Conn, db_dsn: str) -> None:
    """update_shared_rows finds the busy row by (tableoid, ctid), waits for its holder, then closes it."""
    conn = tables
    with tgsis.in_version(conn, "a"):
        conn.execute("UPDATE part SET val = 7 WHERE objid = 1")
        conn.commit()
    holder = psycopg.connect(db_dsn)
    try:
        tgsis.goto_version(holder, "b")
        holder.execute("UPDATE part SET val = 8 WHERE objid = 1 AND k = 1")  # locks DEFAULT's stored row (1, 1)
        merge = Background(db_dsn, "merge", lambda c: tgsis.merge_version(c, "a"))
        wait_until_blocked(conn, merge.pid, holder.info.backend_pid)
        holder.commit()
        assert merge.finish() == 10  # five rows closed in DEFAULT, five copied
    finally:
        holder.close()
    assert [v for _, _, v in _seen(conn, "part", "DEFAULT")[:5]] == [7] * 5
    assert [v for _, k, v in _seen(conn, "part", "b")[:5]] == [8, 102, 103, 104, 105]


def test_an_editor_writes_through_the_view_and_the_parent_never_a_partition(tables: Conn, db_dsn: str) -> None:
    """The storage's checks and notes are the parent's: an editor reaches the rows through them only."""
    conn = tables
    conn.execute("GRANT SELECT, INSERT, UPDATE, DELETE ON part TO tgsis_editor")
    conn.execute("GRANT SELECT, INSERT ON part_ver TO tgsis_editor")
    conn.commit()
    with login_roles(db_dsn, {"ed": "tgsis_editor"}) as roles:
        conn.execute("SELECT tgsis.grant_version('a', 'write', %s)", (roles.name("ed"),))
        conn.commit()
        ed = roles.connect("ed")
        tgsis.goto_version(ed, "a")
        ed.execute("UPDATE part SET val = 1 WHERE objid = 2")
        (working,) = ed.execute("SELECT revision FROM tgsis.write_revision()").fetchone()  # type: ignore[misc]
        with ed.cursor().copy("COPY part_ver (objid, k, val, revision) FROM STDIN") as copy:
            copy.write_row((40, 1, 1, working))
        ed.commit()
        with pytest.raises(psycopg.Error) as wrong:  # the parent's check: a row of another revision
            with ed.cursor().copy("COPY part_ver (objid, k, val, revision) FROM STDIN") as copy:
                copy.write_row((41, 1, 1, 0))
        assert wrong.value.sqlstate == "TG002"
        ed.rollback()
        partition = conn.execute(
            "SELECT p.relid::regclass::text FROM pg_partition_tree('part_ver') p WHERE p.isleaf LIMIT 1"
        ).fetchone()
        assert partition is not None
        with pytest.raises(psycopg.errors.InsufficientPrivilege):
            ed.execute(
                sql.SQL("INSERT INTO {} (objid, k, val, revision) VALUES (42, 1, 1, %s)").format(
                    sql.Identifier(partition[0])
                ),
                (working,),
            )
        ed.rollback()
    changed = {k for (k,) in conn.execute("SELECT objectkey FROM tgsis.changed_objects(%s::int[])", ([working],))}
    assert changed == {"2", "40"}
    assert [(o, v) for o, _, v in _seen(conn, "part", "a") if o in (2, 40)] == [(2, 1)] * 5 + [(40, 1)]
    assert conn.execute("SELECT count(*) FROM part_ver WHERE objid IN (41, 42)").fetchone() == (0,)
