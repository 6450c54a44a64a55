"""Check-in, merge and conflicts on tgsis's own model tables hash-partitioned by geoid (issue 20, docs/scaling.md).

tgsis creates its model tables as ordinary tables after CREATE EXTENSION
(tgsis.create_storage), so a DBA may partition them before storing data:
docs/scaling.md gives the statements, which :func:`partition_model_storage`
runs here. Every test of tests/test_checkin.py and tests/test_checkin_child.py
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
from tests.roles import login_roles
from tests.test_backup import _bindir_of, _restored
from tests.test_checkin import horizons
from tests.test_checkin_child import faults
from tgsis.testing import TestServer

Conn = psycopg.Connection[Any]
PARTITIONS = 4

# the tests of the two check-in modules, collected again here on partitioned storage
globals().update({name: test for module in (test_checkin, test_checkin_child)
                  for name, test in vars(module).items() if name.startswith("test_") and callable(test)})
__all__ = ["faults", "horizons"]


def partition_model_storage(conn: Conn, model: int, partitions: int) -> list[str]:
    """What docs/scaling.md tells a DBA to run before storing data: each table of ``model`` hash-partitioned by geoid.

    Each table is replaced by a partitioned table of the same definition
    (``LIKE ... INCLUDING ALL``: columns, defaults, checks, keys, comments)
    with ``partitions`` partitions, and the group roles' rights are granted
    again (``tgsis.grant_model_tables``). One transaction.
    """
    tables = [r[0] for r in conn.execute("SELECT tablename FROM tgsis.model_tables WHERE model = %s ORDER BY tablename",
                                         (model,)).fetchall()]
    with conn.transaction():
        for table in tables:
            plain = sql.Identifier("tgsis", f"{table}_plain")
            conn.execute(sql.SQL("ALTER TABLE {} RENAME TO {}").format(sql.Identifier("tgsis", table),
                                                                      sql.Identifier(f"{table}_plain")))
            conn.execute(sql.SQL("ALTER INDEX {} RENAME TO {}").format(sql.Identifier("tgsis", f"{table}_pkey"),
                                                                      sql.Identifier(f"{table}_plain_pkey")))
            conn.execute(sql.SQL("CREATE TABLE {} (LIKE {} INCLUDING ALL) PARTITION BY HASH (geoid)").format(
                sql.Identifier("tgsis", table), plain))
            for r in range(partitions):
                conn.execute(sql.SQL("CREATE TABLE {} PARTITION OF {} FOR VALUES WITH (MODULUS {}, REMAINDER {})").format(
                    sql.Identifier("tgsis", f"{table}_p{r}"), sql.Identifier("tgsis", table), sql.Literal(partitions),
                    sql.Literal(r)))
            conn.execute(sql.SQL("DROP TABLE {}").format(plain))
        conn.execute("SELECT tgsis.grant_model_tables(%s::smallint)", (model,))
    return tables


@pytest.fixture(autouse=True)
def partitioned(db_dsn: str) -> list[str]:
    """The test's database with the model-1 tables partitioned, before the test's own connection opens."""
    with psycopg.connect(db_dsn) as conn:
        return partition_model_storage(conn, 1, PARTITIONS)


def _grid(side: int) -> tgsis.Surface:
    u, v = np.meshgrid(np.arange(side, dtype=float), np.arange(side, dtype=float))
    vertices = np.stack([u.ravel(), v.ravel(), np.sin(u.ravel()) + v.ravel()], axis=1)
    idx = np.arange(side * side).reshape(side, side)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel()
    return tgsis.Surface(vertices, np.concatenate([np.stack([a, b, d], 1), np.stack([a, d, c], 1)]),
                         vertex_properties={"porosity": np.linspace(0, 1, side * side)})


def test_the_storage_is_partitioned_and_versioning_keeps_it_so(conn: Conn, partitioned: list[str],
                                                               horizons: Any) -> None:
    assert {"vrtx", "trgl", "segment", "point", "tetra"} <= set(partitioned)
    ids = [tgsis.insert_feature(conn, horizons, _grid(6)) for _ in range(12)]
    conn.commit()
    tgsis.enable_feature_versioning(conn)
    for table in ("vrtx", "trgl"):
        row = conn.execute("SELECT c.relkind, (SELECT count(*) FROM pg_inherits i WHERE i.inhparent = c.oid) "
                           "FROM pg_class c WHERE c.oid = %s::regclass", (f"tgsis.{table}_ver",)).fetchone()
        assert row == ("p", PARTITIONS), table
        used = conn.execute(sql.SQL("SELECT count(DISTINCT tableoid) FROM {}").format(
            sql.Identifier("tgsis", f"{table}_ver"))).fetchone()
        assert used is not None and used[0] > 1, table  # twelve geometries spread over the partitions
    assert all(tgsis.fetch_feature(conn, horizons, i).mesh.same_as(_grid(6)) for i in ids)


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
        assert tgsis.fetch_feature(editor, horizons.name, geoid).mesh.same_as(edited)
        # a partition by name is not the editor's to write: the parent's rights are
        with pytest.raises(psycopg.errors.InsufficientPrivilege):
            editor.execute("INSERT INTO tgsis.vrtx_p0 VALUES (1, 1, 0, 0, 0, 0)")
        editor.rollback()
    assert tgsis.fetch_feature(conn, horizons, geoid).mesh.same_as(mesh)  # DEFAULT untouched until the merge
    tgsis.merge_version(conn, "edit")
    conn.commit()
    assert tgsis.fetch_feature(conn, horizons, geoid).mesh.same_as(edited)
    closed = conn.execute("SELECT count(*) FROM tgsis.vrtx_ver WHERE geoid = %s AND revclosed", (geoid,)).fetchone()
    assert closed == (5,)  # the five moved vertices' old row versions, closed by the merge; nothing else


def test_dump_and_restore_keep_the_partitioned_model_storage(pg: TestServer, db_dsn: str, conn: Conn, horizons: Any,
                                                             tmp_path: Path) -> None:
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
        for table in ("vrtx_ver", "trgl_ver"):
            row = restored.execute("SELECT c.relkind, (SELECT count(*) FROM pg_inherits i WHERE i.inhparent = c.oid) "
                                   "FROM pg_class c WHERE c.oid = %s::regclass", (f"tgsis.{table}",)).fetchone()
            assert row == ("p", PARTITIONS), table
        assert tgsis.fetch_feature(restored, horizons.name, geoid).mesh.same_as(mesh)
        with tgsis.in_version(restored, "edit"):
            assert tgsis.fetch_feature(restored, horizons.name, geoid).mesh.same_as(edited)
        tgsis.merge_version(restored, "edit")
        restored.commit()
        assert tgsis.fetch_feature(restored, horizons.name, geoid).mesh.same_as(edited)
