"""Check-in, merge and conflicts on tgsis's own model tables hash-partitioned by geoid (issue 20, docs/scaling.md).

tgsis creates its model tables as ordinary tables after CREATE EXTENSION
(tgsis.create_storage), so they can be partitioned before data is stored:
``tgsis.partition_model_storage`` (docs/scaling.md), run here on each test's
database before the test connects. Every test of tests/test_checkin.py and tests/test_checkin_child.py
(save by difference, check-out / check-in, concurrent check-ins, conflicts
into a child version, merges, bad input) runs again in this module on
databases whose model-1 tables are partitioned in 4, with feature versioning
on partitioned ``<table>_ver`` storage wherever those tests turn it on.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import psycopg
import pytest
from psycopg import sql

import tgsis
from tests import test_checkin, test_checkin_child
from tests.fetched import geometry_of
from tests.roles import login_roles
from tests.sessions import Background, wait_until_blocked
from tests.test_backup import _bindir_of, _restored
from tests.test_checkin import horizons
from tests.test_checkin_child import faults
from tgsis.testing import TestServer

Conn = psycopg.Connection[Any]
PARTITIONS = 4

# the tests of the two check-in modules, collected again here on partitioned storage
globals().update(
    {
        name: test
        for module in (test_checkin, test_checkin_child)
        for name, test in vars(module).items()
        if name.startswith("test_") and callable(test)
    }
)
__all__ = ["faults", "horizons"]


@pytest.fixture(autouse=True)
def partitioned(db_dsn: str) -> list[str]:
    """The test's database with the model-1 tables partitioned, before the test's own connection opens."""
    with psycopg.connect(db_dsn) as conn:
        return tgsis.partition_model_storage(conn, 1, PARTITIONS)


def _in_chunks(conn: Conn, table: str) -> bool:
    """Whether the model table is stored in chunks (``tgsis.stored_in_chunks``)."""
    return bool(conn.execute("SELECT tgsis.stored_in_chunks(%s)", (table,)).fetchone() == (True,))


def _storage(conn: Conn, table: str) -> str:
    """The relation storing a model table's rows (``tgsis.storage_table``): <table>_ver, <table>_chunk or the table."""
    return str(conn.execute("SELECT tgsis.storage_table('tgsis', %s)", (table,)).fetchone()[0])  # type: ignore[index]


def _partitions(conn: Conn, relation: str) -> list[str]:
    """The partitions of a partitioned relation (``schema.name``), in order; [] for another kind."""
    return [
        r[0]
        for r in conn.execute(
            "SELECT format('%%I.%%I', n.nspname, c.relname) FROM pg_inherits i JOIN pg_class c ON c.oid = i.inhrelid "
            "JOIN pg_namespace n ON n.oid = c.relnamespace JOIN pg_class p ON p.oid = i.inhparent "
            "WHERE i.inhparent = %s::regclass AND p.relkind = 'p' ORDER BY c.relname",
            (relation,),
        ).fetchall()
    ]


def _grid(side: int) -> tgsis.Surface:
    u, v = np.meshgrid(np.arange(side, dtype=float), np.arange(side, dtype=float))
    vertices = np.stack([u.ravel(), v.ravel(), np.sin(u.ravel()) + v.ravel()], axis=1)
    idx = np.arange(side * side).reshape(side, side)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel()
    return tgsis.Surface(
        vertices,
        np.concatenate([np.stack([a, b, d], 1), np.stack([a, d, c], 1)]),
        vertex_properties={"porosity": np.linspace(0, 1, side * side)},
    )


def test_the_storage_is_partitioned_and_versioning_keeps_it_so(
    conn: Conn, partitioned: list[str], horizons: Any
) -> None:
    assert {"vrtx", "trgl", "segment", "point", "tetra"} <= set(partitioned)
    ids = [tgsis.insert_feature(conn, horizons, _grid(6)) for _ in range(12)]
    conn.commit()
    tgsis.enable_feature_versioning(conn)
    for table in ("vrtx", "trgl"):
        storage = _storage(conn, table)  # <table>_ver on rows, <table>_chunk on chunks
        assert len(_partitions(conn, storage)) == PARTITIONS, table
        used = conn.execute(sql.SQL("SELECT count(DISTINCT tableoid) FROM {}").format(sql.SQL(storage))).fetchone()
        assert used is not None and used[0] > 1, table  # twelve geometries spread over the partitions
    assert all(geometry_of(tgsis.fetch_feature(conn, horizons, i)).same_as(_grid(6)) for i in ids)


def test_an_editor_checks_in_and_a_merge_brings_it_home(db_dsn: str, conn: Conn, horizons: Any) -> None:
    mesh = _grid(8)
    geoid = tgsis.insert_feature(conn, horizons, mesh)
    conn.commit()
    tgsis.enable_feature_versioning(conn)
    tgsis.create_version(conn, "edit")
    with login_roles(db_dsn, {"ed": "tgsis_editor"}) as roles:
        conn.execute("SELECT tgsis.grant_version('edit', 'write', %s)", (roles.name("ed"),))
        conn.commit()
        editor = roles.connect("ed")
        tgsis.goto_version(editor, "edit")
        out = tgsis.checkout(editor, geoid, horizons.name)
        moved = out.mesh.vertices.copy()
        moved[:5, 2] += 10.0
        edited = tgsis.Surface(moved, out.mesh.cells, vertex_properties=out.mesh.vertex_properties)
        tgsis.checkin(editor, out, edited)
        editor.commit()
        assert geometry_of(tgsis.fetch_feature(editor, horizons.name, geoid)).same_as(edited)
        # a partition by name is not the editor's to write: the parent's rights are
        part = _partitions(editor, _storage(editor, "vrtx"))[0]
        editor.rollback()
        with pytest.raises(psycopg.errors.InsufficientPrivilege):
            editor.execute(sql.SQL("INSERT INTO {} (geoid) VALUES (1)").format(sql.SQL(part)))
        editor.rollback()
    assert geometry_of(tgsis.fetch_feature(conn, horizons, geoid)).same_as(mesh)  # DEFAULT untouched until the merge
    tgsis.merge_version(conn, "edit")
    conn.commit()
    assert geometry_of(tgsis.fetch_feature(conn, horizons, geoid)).same_as(edited)
    storage = _storage(conn, "vrtx")
    closed = conn.execute(
        sql.SQL("SELECT count(*) FROM {} WHERE geoid = %s AND revclosed").format(sql.SQL(storage)), (geoid,)
    ).fetchone()
    # the five moved vertices' old row versions, closed by the merge, nothing else; on chunks their one
    # chunk's old version (the counts are chunk versions there: docs/storage.md, "What differs from rows")
    assert closed == ((1,) if _in_chunks(conn, "vrtx") else (5,))


def test_dump_and_restore_keep_the_partitioned_model_storage(
    pg: TestServer, db_dsn: str, conn: Conn, horizons: Any, tmp_path: Path
) -> None:
    mesh = _grid(6)
    geoid = tgsis.insert_feature(conn, horizons, mesh)
    conn.commit()
    tgsis.enable_feature_versioning(conn)
    tgsis.create_version(conn, "edit")
    with tgsis.in_version(conn, "edit"):
        out = tgsis.checkout(conn, geoid, horizons.name)
        moved = out.mesh.vertices.copy()
        moved[0, 2] -= 3.0
        edited = tgsis.Surface(moved, out.mesh.cells, vertex_properties=out.mesh.vertex_properties)
        tgsis.checkin(conn, out, edited)
    conn.commit()
    with _restored(pg, _bindir_of(pg), db_dsn, "custom", tmp_path) as dsn, psycopg.connect(dsn) as restored:
        for table in ("vrtx", "trgl"):
            storage = _storage(restored, table)
            assert len(_partitions(restored, storage)) == PARTITIONS, table
        assert geometry_of(tgsis.fetch_feature(restored, horizons.name, geoid)).same_as(mesh)
        with tgsis.in_version(restored, "edit"):
            assert geometry_of(tgsis.fetch_feature(restored, horizons.name, geoid)).same_as(edited)
        tgsis.merge_version(restored, "edit")
        restored.commit()
        assert geometry_of(tgsis.fetch_feature(restored, horizons.name, geoid)).same_as(edited)


def _definition(conn: Conn, table: str) -> list[Any]:
    """What partitioning must keep of a model table: columns, constraints, index names and shapes, comments, owner,
    rights, row-level security and policies, triggers, a view's options and query; of a table stored in chunks,
    also of its chunk table, chunk view and row definition."""
    rels = [f"tgsis.{table}"]
    if _in_chunks(conn, table):
        rels += [f"tgsis.{table}_chunk", f"tgsis.{table}_chunk_rows", f"tgsis.{table}_shape"]
    return [_relation(conn, rel) for rel in rels]


def _relation(conn: Conn, rel: str) -> list[Any]:
    """What partitioning must keep of one relation (``_definition``)."""
    return [
        conn.execute(
            "SELECT array_agg((a.attname, format_type(a.atttypid, a.atttypmod), a.attnotnull, "
            "pg_get_expr(d.adbin, d.adrelid), col_description(a.attrelid, a.attnum)) ORDER BY a.attnum)::text "
            "FROM pg_attribute a LEFT JOIN pg_attrdef d ON d.adrelid = a.attrelid AND d.adnum = a.attnum "
            "WHERE a.attrelid = %s::regclass AND a.attnum > 0 AND NOT a.attisdropped",
            (rel,),
        ).fetchone(),
        conn.execute(
            "SELECT array_agg((conname, contype, pg_get_constraintdef(oid)) ORDER BY conname)::text "
            "FROM pg_constraint WHERE conrelid = %s::regclass",
            (rel,),
        ).fetchone(),
        conn.execute(
            "SELECT array_agg((c.relname, split_part(pg_get_indexdef(i.indexrelid), ' USING ', 2)) "
            "ORDER BY c.relname)::text FROM pg_index i JOIN pg_class c ON c.oid = i.indexrelid "
            "WHERE i.indrelid = %s::regclass",
            (rel,),
        ).fetchone(),
        conn.execute(
            "SELECT obj_description(c.oid, 'pg_class'), c.relowner::regrole::text, "
            "(SELECT array_agg(a::text ORDER BY a::text) FROM unnest(c.relacl) a) "
            "FROM pg_class c WHERE c.oid = %s::regclass",
            (rel,),
        ).fetchone(),
        conn.execute(
            "SELECT c.relrowsecurity, c.relforcerowsecurity, c.reloptions, "
            "CASE WHEN c.relkind = 'v' THEN pg_get_viewdef(c.oid) END, "
            "(SELECT array_agg((p.polname, p.polcmd, p.polroles::text, pg_get_expr(p.polqual, p.polrelid), "
            "pg_get_expr(p.polwithcheck, p.polrelid), obj_description(p.oid, 'pg_policy')) ORDER BY p.polname)::text "
            "FROM pg_policy p WHERE p.polrelid = c.oid), "
            "(SELECT array_agg(regexp_replace(pg_get_triggerdef(t.oid), ' ON \\S+ ', ' ON _ ') ORDER BY t.tgname) "
            "FROM pg_trigger t WHERE t.tgrelid = c.oid AND NOT t.tgisinternal) "
            "FROM pg_class c WHERE c.oid = %s::regclass",
            (rel,),
        ).fetchone(),
    ]


_MODELS = [m.number for m in tgsis.data_models()]


def test_partitioning_keeps_every_definition_of_every_model(make_database: Any, template_db: str) -> None:
    with psycopg.connect(make_database(template_db)) as plain:
        tables = {
            m: [
                r[0]
                for r in plain.execute("SELECT tablename FROM tgsis.model_tables WHERE model = %s", (m,)).fetchall()
            ]
            for m in _MODELS
        }
        before = {t: _definition(plain, t) for ts in tables.values() for t in ts}
    with psycopg.connect(make_database(template_db)) as conn:
        for model in _MODELS:
            assert sorted(tgsis.partition_model_storage(conn, model, 3)) == sorted(tables[model])
        for table, definition in before.items():
            assert _definition(conn, table) == definition, table
            storage = f"tgsis.{table}_chunk" if _in_chunks(conn, table) else f"tgsis.{table}"  # unversioned
            parts = conn.execute(
                "SELECT format('%%I.%%I', n.nspname, c.relname), obj_description(c.oid, 'pg_class'), c.relacl "
                "FROM pg_inherits i JOIN pg_class c ON c.oid = i.inhrelid JOIN pg_namespace n ON n.oid = c.relnamespace "
                "WHERE i.inhparent = %s::regclass ORDER BY 1",
                (storage,),
            ).fetchall()
            assert [p[0] for p in parts] == [f"{storage}_p{r}" for r in range(3)]
            assert all(p[1] and p[2] is None for p in parts)  # commented; no rights of their own


@pytest.mark.parametrize(
    "model, partitions, error, message",
    [
        (1, 1, tgsis.InvalidInputError, "number of partitions 1 is out of range"),
        (1, 5000, tgsis.InvalidInputError, "number of partitions 5000 is out of range"),
        (0, 4, tgsis.InvalidInputError, "the core tables"),
        (9, 4, tgsis.NotFoundError, "data model 9 does not exist"),
        (1, 4, tgsis.InUseError, r"tgsis\.\w+ is not a plain table"),  # partitioned already by the fixture
    ],
)
def test_bad_calls_are_refused(conn: Conn, model: int, partitions: int, error: type[Exception], message: str) -> None:
    with pytest.raises(error, match=message):
        tgsis.partition_model_storage(conn, model, partitions)


def test_storage_with_rows_and_versioning_is_partitioned_with_its_rows(conn: Conn, horizons: Any) -> None:
    """Rows are moved and verified (tgsis.partition_row_storage; until 2026-12-06 refused: TG202 'holds rows', and
    'is not a plain table' once versioned). tests/test_partition_with_data.py checks every version of model 1."""
    geoid = tgsis.insert_feature(conn, horizons, _grid(3))  # model 1 (partitioned by the fixture) holds rows
    conn.commit()
    tgsis.enable_feature_versioning(conn)
    conn.execute("INSERT INTO tgsis.times (geoid, times) SELECT %s, 0.0", (geoid,))  # a row in one model-2 table
    conn.execute("INSERT INTO tgsis.times (geoid, times) SELECT %s, -1e-310", (geoid,))  # a subnormal
    conn.commit()
    tables = [r[0] for r in conn.execute("SELECT tablename FROM tgsis.model_tables WHERE model = 2").fetchall()]
    stored = conn.execute(
        "SELECT geoid, float8send(times), revision, lastrevs FROM tgsis.times_ver ORDER BY 2"
    ).fetchall()
    assert len(stored) == 2
    assert sorted(tgsis.partition_model_storage(conn, 2, 4)) == sorted(tables)
    conn.commit()
    for table in tables:
        assert len(_partitions(conn, _storage(conn, table))) == 4, table
    after = conn.execute("SELECT geoid, float8send(times), revision, lastrevs FROM tgsis.times_ver ORDER BY 2")
    assert after.fetchall() == stored  # bit for bit
    assert conn.execute("SELECT count(*) FROM tgsis.times").fetchone() == (2,)


def test_only_the_owner_partitions(db_dsn: str) -> None:
    with login_roles(db_dsn, {"admin": "tgsis_admin"}) as roles:
        admin = roles.connect("admin")
        with pytest.raises(tgsis.MissingPrivilegeError):
            tgsis.partition_model_storage(admin, 2, 4)


@pytest.mark.parametrize(
    ("create", "user", "drop"),
    [
        (
            "CREATE VIEW public.moments AS SELECT geoid, times FROM tgsis.times",
            "view public.moments",
            "DROP VIEW public.moments",
        ),
        # a user's table whose rows point at instants: the swap would leave its key pointing at the old table
        (
            "CREATE TABLE public.picks (geoid bigint, times double precision, note text, "
            "CONSTRAINT picks_instant FOREIGN KEY (geoid, times) REFERENCES tgsis.times)",
            "constraint picks_instant on table public.picks",
            "DROP TABLE public.picks",
        ),
        # a user's trigger: LIKE ... INCLUDING ALL copies none, the swap dropped it without a word
        (
            "CREATE FUNCTION public.note_times() RETURNS trigger LANGUAGE plpgsql AS $$BEGIN RETURN NEW; END$$; "
            "CREATE TRIGGER note_times BEFORE INSERT ON tgsis.times FOR EACH ROW EXECUTE FUNCTION public.note_times()",
            "trigger note_times on tgsis.times",
            "DROP TRIGGER note_times ON tgsis.times",
        ),
    ],
    ids=["view", "foreign-key", "trigger"],
)
def test_a_table_other_objects_use_is_refused_naming_them(conn: Conn, create: str, user: str, drop: str) -> None:
    def kinds() -> list[tuple[str, str]]:
        """Each model-2 relation of the storage (a table, a face over chunks, a chunk table) and its relkind."""
        return conn.execute(
            "SELECT c.relname, c.relkind::text FROM pg_class c WHERE c.relnamespace = 'tgsis'::regnamespace"
            " AND c.relname IN (SELECT t.tablename || s FROM tgsis.model_tables t, unnest(ARRAY['', '_chunk']) AS s"
            "                    WHERE t.model = 2) ORDER BY 1"
        ).fetchall()

    conn.execute(create)
    conn.commit()
    before = kinds()
    assert before and all(kind != "p" for _, kind in before)
    with pytest.raises(tgsis.InUseError, match=r"tgsis\.times is used by other objects") as caught:
        tgsis.partition_model_storage(conn, 2, 4)
    assert caught.value.detail == f"used by: {user}"
    conn.rollback()
    assert kinds() == before  # nothing partitioned, nothing replaced (the time tables' faces, or their rows)
    conn.execute(drop)
    conn.commit()
    assert "times" in tgsis.partition_model_storage(conn, 2, 4)


@pytest.mark.parametrize("writer_commits", [True, False])
def test_a_writer_in_flight_is_waited_for(db_dsn: str, conn: Conn, writer_commits: bool) -> None:
    writer = psycopg.connect(db_dsn)
    try:
        writer.execute("INSERT INTO tgsis.times (geoid, times) VALUES (1, 0.0)")  # not committed yet
        call = Background(db_dsn, "partition", lambda c: tgsis.partition_model_storage(c, 2, 4))
        wait_until_blocked(conn, call.pid, writer.info.backend_pid)
        writer.commit() if writer_commits else writer.rollback()
        assert "times" in call.finish()
        assert conn.execute("SELECT relkind FROM pg_class WHERE oid = 'tgsis.times'::regclass").fetchone() == ("p",)
        # the row it waited for, committed, was moved into the partitioned table (before 2026-12-06: refused)
        rows = conn.execute("SELECT count(*) FROM tgsis.times WHERE geoid = 1").fetchone()
        assert rows == ((1,) if writer_commits else (0,))
    finally:
        writer.close()


@pytest.mark.storage("rows")
def test_switching_partitioned_rows_to_chunks_keeps_the_partitions_and_every_version(
    conn: Conn, partitioned: list[str], horizons: Any
) -> None:
    mesh = _grid(40)  # 1,600 vertices: two chunks of vertices per object
    ids = [tgsis.insert_feature(conn, horizons, mesh) for _ in range(4)]
    conn.commit()
    tgsis.enable_feature_versioning(conn)
    tgsis.create_version(conn, "edit")
    with tgsis.in_version(conn, "edit"):
        out = tgsis.checkout(conn, ids[0], horizons.name)
        moved = out.mesh.vertices.copy()
        moved[1500:1510, 2] += 4.0
        edited = tgsis.Surface(moved, out.mesh.cells, vertex_properties=out.mesh.vertex_properties)
        tgsis.checkin(conn, out, edited)
    conn.commit()

    def seen() -> dict[str, list[Any]]:
        views = {}
        for version in ("DEFAULT", "edit"):
            with tgsis.in_version(conn, version):
                views[version] = [
                    conn.execute("SELECT * FROM tgsis.vrtx ORDER BY geoid, vrtxid").fetchall(),
                    conn.execute("SELECT * FROM tgsis.trgl ORDER BY geoid, trglid").fetchall(),
                ]
        return views

    before = seen()
    chunked = [
        r[0]
        for r in conn.execute("SELECT tablename FROM tgsis.model_tables WHERE chunkdefault AND model = 1 ORDER BY 1")
    ]
    for table in chunked:  # what the upgrade does (model 1's storage switch), on partitioned row storage
        conn.execute("SELECT tgsis.store_in_chunks(%s)", (table,))
    conn.commit()
    for table in chunked:
        assert _in_chunks(conn, table), table
        assert len(_partitions(conn, _storage(conn, table))) == PARTITIONS, table  # partitioned as the rows were
    assert seen() == before
    tgsis.merge_version(conn, "edit")
    conn.commit()
    assert geometry_of(tgsis.fetch_feature(conn, horizons, ids[0])).same_as(edited)
    assert geometry_of(tgsis.fetch_feature(conn, horizons, ids[1])).same_as(mesh)
