"""Partitioning model tables stored in chunks (issue 40, docs/storage.md "partition_model_storage and Citus").

``tgsis.partition_model_storage`` hash-partitions the chunk table
``tgsis.<table>_chunk`` of a table stored in chunks by geoid, as it partitions
row storage, with its data and under versioning (as row storage since
2026-12-06, tgsis.partition_row_storage): the chunk versions are moved (verified bit for bit), and the face ``tgsis.<table>``,
the chunk view, the rights, the row-level security and the guards of a versioned
table are made again (``tgsis.partition_chunk_storage``). Each test stores
model 1 in chunks first when the harness installed rows, so the module runs the
same in both test storages.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import psycopg
import pytest
from psycopg import sql

import tgsis
from tests.fetched import geometry_of
from tests.merge_data import make_fault, varied_history
from tests.roles import login_roles
from tests.sessions import Background, wait_until_blocked
from tests.test_backup import _bindir_of, _restored
from tests.test_checkin import horizons
from tgsis.testing import TestServer

Conn = psycopg.Connection[Any]
PARTITIONS = 4
CHUNKED = ("point", "segment", "tetra", "trgl", "vrtx")
__all__ = ["horizons"]


@pytest.fixture(autouse=True)
def chunked(db_dsn: str) -> None:
    """The test's database with model 1's tables stored in chunks (the template's rows switched when needed)."""
    with psycopg.connect(db_dsn) as conn:
        conn.execute(
            "SELECT tgsis.store_in_chunks(t.tablename) FROM tgsis.model_tables t "
            "WHERE t.chunkdefault AND NOT tgsis.stored_in_chunks(t.tablename) ORDER BY t.tablename"
        )


def _grid(side: int) -> tgsis.Surface:
    u, v = np.meshgrid(np.arange(side, dtype=float), np.arange(side, dtype=float))
    vertices = np.stack([u.ravel(), v.ravel(), np.sin(u.ravel()) * 0.1 + v.ravel()], axis=1)
    idx = np.arange(side * side).reshape(side, side)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel()
    return tgsis.Surface(
        vertices,
        np.concatenate([np.stack([a, b, d], 1), np.stack([a, d, c], 1)]),
        vertex_properties={"porosity": np.linspace(0, 1, side * side)},
    )


def _edited(conn: Conn, geoid: int, fc: Any, ids: slice, dz: float) -> tgsis.Surface:
    out = tgsis.checkout(conn, geoid, fc.name)
    moved = out.mesh.vertices.copy()
    moved[ids, 2] += dz
    edited = tgsis.Surface(moved, out.mesh.cells, vertex_properties=out.mesh.vertex_properties)
    tgsis.checkin(conn, out, edited)
    return edited


def _chunk_rows(conn: Conn) -> dict[str, list[Any]]:
    """Every chunk version of model 1's chunk tables, as text (what partitioning must keep)."""
    return {
        t: [
            r[0]
            for r in conn.execute(
                sql.SQL("SELECT c::text FROM tgsis.{} c ORDER BY geoid, chunk, revision").format(
                    sql.Identifier(f"{t}_chunk")
                )
            )
        ]
        for t in CHUNKED
    }


def _seen(conn: Conn) -> dict[tuple[str, int | None], list[Any]]:
    """What each version and each kept revision sees through the faces of vrtx and trgl."""
    views: list[tuple[str, int | None]] = [(r[0], None) for r in conn.execute("SELECT name FROM tgsis.versions")]
    views += [
        (r[0], r[1])
        for r in conn.execute(
            "SELECT v.name, r.revision FROM tgsis.revisions r JOIN tgsis.versions v USING (versionid) "
            "WHERE r.visibleset IS NOT NULL"
        )
    ]
    conn.commit()
    seen = {}
    for version, revision in views:
        if revision is None:
            tgsis.goto_version(conn, version)
        else:
            tgsis.goto_revision(conn, version, revision)
        seen[(version, revision)] = [
            conn.execute("SELECT * FROM tgsis.vrtx ORDER BY geoid, vrtxid").fetchall(),
            conn.execute("SELECT * FROM tgsis.trgl ORDER BY geoid, trglid").fetchall(),
        ]
        conn.commit()
    tgsis.goto_version(conn, "DEFAULT")
    return seen


def _kinds(conn: Conn) -> dict[str, Any]:
    """Each chunk table's kind and number of partitions."""
    return {
        t: conn.execute(
            "SELECT c.relkind, (SELECT count(*) FROM pg_inherits i WHERE i.inhparent = c.oid) "
            "FROM pg_class c WHERE c.oid = %s::regclass",
            (f"tgsis.{t}_chunk",),
        ).fetchone()
        for t in CHUNKED
    }


def _triggers(conn: Conn, rel: str) -> list[str]:
    return [
        r[0]
        for r in conn.execute(
            "SELECT regexp_replace(pg_get_triggerdef(oid), ' ON \\S+ ', ' ON _ ') FROM pg_trigger "
            "WHERE tgrelid = %s::regclass AND NOT tgisinternal ORDER BY tgname",
            (rel,),
        )
    ]


def test_versioned_chunks_are_partitioned_with_every_version_kept(db_dsn: str, conn: Conn, horizons: Any) -> None:
    mesh = _grid(40)  # 1,600 vertices: two chunks of vertices, four of triangles per object
    ids = [tgsis.insert_feature(conn, horizons, mesh) for _ in range(5)]
    conn.commit()
    fault = make_fault(conn)  # versioning on; a varied history: saved revisions, deletions, merges, versions
    varied_history(conn, fault)
    tgsis.create_version(conn, "edit")
    with tgsis.in_version(conn, "edit"):
        edited = _edited(conn, ids[0], horizons, slice(0, 5), 10.0)
    conn.commit()
    chunks, seen = _chunk_rows(conn), _seen(conn)
    guards = _triggers(conn, "tgsis.vrtx_chunk")
    assert guards  # versioned chunk storage is guarded

    # the chunk layer's part partitions versioned chunk tables with their data (as the storage switch of
    # partitioned rows does); model 1's atom and part stay rows, versioned, partitioned with their rows
    # (tgsis.partition_row_storage; before 2026-12-06 they refused partition_model_storage by name)
    atoms = conn.execute("SELECT * FROM tgsis.atom_ver ORDER BY 1, 2, 3").fetchall()
    assert "atom" in tgsis.partition_model_storage(conn, 1, PARTITIONS)
    conn.commit()
    assert conn.execute("SELECT * FROM tgsis.atom_ver ORDER BY 1, 2, 3").fetchall() == atoms
    assert _kinds(conn) == {t: ("p", PARTITIONS) for t in CHUNKED}
    assert _chunk_rows(conn) == chunks  # every chunk version, with its revision and lastrevs
    assert _seen(conn) == seen  # so every version and kept revision sees what it saw
    assert _triggers(conn, "tgsis.vrtx_chunk") == guards
    used = conn.execute("SELECT count(DISTINCT tableoid) FROM tgsis.vrtx_chunk").fetchone()
    assert used is not None and used[0] > 1  # six objects spread over the partitions

    # the guards hold on the partitioned storage, and the work goes on: an editor checks in, a merge brings it home
    with login_roles(db_dsn, {"ed": "tgsis_editor"}) as roles:
        conn.execute("SELECT tgsis.grant_version('edit', 'write', %s)", (roles.name("ed"),))
        conn.commit()
        editor = roles.connect("ed")
        for statement in (
            "UPDATE tgsis.vrtx_chunk SET lastrevs = '{}'",
            "DELETE FROM tgsis.vrtx_chunk",
            "INSERT INTO tgsis.vrtx_chunk_p0 (geoid, chunk, revision) VALUES (1, 0, 0)",
        ):
            with pytest.raises(psycopg.errors.InsufficientPrivilege):
                editor.execute(statement)
            editor.rollback()
        tgsis.goto_version(editor, "edit")
        again = _edited(editor, ids[2], horizons, slice(700, 720), 1.5)
        editor.commit()
    assert _chunk_rows(conn)["vrtx"] != chunks["vrtx"]
    tgsis.merge_version(conn, "edit")
    conn.commit()
    assert geometry_of(tgsis.fetch_feature(conn, horizons, ids[0])).same_as(edited)
    assert geometry_of(tgsis.fetch_feature(conn, horizons, ids[2])).same_as(again)
    assert geometry_of(tgsis.fetch_feature(conn, horizons, ids[3])).same_as(mesh)


def test_the_face_keeps_its_rights_for_roles_with_fewer(db_dsn: str, conn: Conn, horizons: Any) -> None:
    geoid = tgsis.insert_feature(conn, horizons, _grid(5))
    conn.commit()
    with login_roles(db_dsn, {"reader": "tgsis_reader", "admin": "tgsis_admin"}) as roles:
        reader = roles.connect("reader")
        before = reader.execute("SELECT * FROM tgsis.vrtx WHERE geoid = %s ORDER BY vrtxid", (geoid,)).fetchall()
        reader.commit()
        for role in (reader, roles.connect("admin")):  # only tgsis's owner partitions
            with pytest.raises(tgsis.MissingPrivilegeError):
                tgsis.partition_model_storage(role, 1, PARTITIONS)
        assert _kinds(conn) == {t: ("r", 0) for t in CHUNKED}
        conn.commit()
        tgsis.partition_model_storage(conn, 1, PARTITIONS)
        assert (
            reader.execute("SELECT * FROM tgsis.vrtx WHERE geoid = %s ORDER BY vrtxid", (geoid,)).fetchall() == before
        )
        reader.commit()
        for statement in (
            "INSERT INTO tgsis.vrtx VALUES (%s, 99, 0, 0, 0)",
            "UPDATE tgsis.vrtx SET z = 1 WHERE geoid = %s",
            "DELETE FROM tgsis.vrtx_chunk WHERE geoid = %s",
        ):
            with pytest.raises(psycopg.errors.InsufficientPrivilege):
                reader.execute(statement, (geoid,))
            reader.rollback()


def test_direct_chunk_inserts_are_still_checked_once_partitioned(db_dsn: str, conn: Conn, horizons: Any) -> None:
    """The insert check (tgsis_chunk_insert) is made again on the partitioned chunk table, not dropped with the old one."""
    geoid = tgsis.insert_feature(conn, horizons, _grid(5))
    conn.commit()
    tgsis.partition_model_storage(conn, 1, PARTITIONS)
    assert [t for t in _triggers(conn, "tgsis.vrtx_chunk") if "chunk_insert_check" in t]
    with login_roles(db_dsn, {"ed": "tgsis_editor"}) as roles:
        editor = roles.connect("ed")
        # x has 2 elements, y and z 1: readers would decode it differently
        with pytest.raises(psycopg.errors.CheckViolation):
            editor.execute(
                "INSERT INTO tgsis.vrtx_chunk (geoid, chunk, revision, x, y, z) VALUES (%s, 5, 0, '{1,2}', '{1}', '{1}')",
                (geoid,),
            )
        editor.rollback()
        editor.execute(  # a well-formed chunk goes in (the client's upload is this right)
            "INSERT INTO tgsis.vrtx_chunk (geoid, chunk, revision, x, y, z) VALUES (%s, 6, 0, '{1}', '{2}', '{3}')",
            (geoid,),
        )
        editor.rollback()


@pytest.mark.parametrize(
    ("create", "user"),
    [
        ("CREATE VIEW public.raw AS SELECT geoid, chunk FROM tgsis.trgl_chunk", "view public.raw"),
        (
            "CREATE FUNCTION public.noop() RETURNS trigger LANGUAGE plpgsql AS 'BEGIN RETURN NULL; END'; "
            "CREATE TRIGGER audit AFTER INSERT ON tgsis.point_chunk FOR EACH STATEMENT EXECUTE FUNCTION public.noop()",
            "trigger audit on tgsis.point_chunk",
        ),
    ],
    ids=["view", "trigger"],
)
def test_what_users_built_on_a_chunk_table_is_refused_by_name(
    conn: Conn, horizons: Any, create: str, user: str
) -> None:
    tgsis.insert_feature(conn, horizons, _grid(4))
    conn.execute(create)
    conn.commit()
    chunks = _chunk_rows(conn)
    with pytest.raises(tgsis.InUseError, match=r"tgsis\.\w+ is used by other objects") as caught:
        tgsis.partition_model_storage(conn, 1, PARTITIONS)
    assert caught.value.detail == f"used by: {user}"
    conn.rollback()
    assert _kinds(conn) == {t: ("r", 0) for t in CHUNKED}  # nothing partitioned, not even the tables checked before
    assert _chunk_rows(conn) == chunks


def test_the_face_stays_the_same_view_for_users_views_and_writing_sessions(
    db_dsn: str, conn: Conn, horizons: Any
) -> None:
    geoid = tgsis.insert_feature(conn, horizons, _grid(5))
    conn.execute("CREATE VIEW public.tops AS SELECT geoid, vrtxid, z FROM tgsis.vrtx")
    conn.execute("CREATE VIEW public.decoded AS SELECT geoid, segid FROM tgsis.segment_chunk_rows")
    conn.commit()
    face = conn.execute("SELECT 'tgsis.vrtx'::regclass::oid").fetchone()
    writer = psycopg.connect(db_dsn)  # a session that wrote through the face keeps its work tables (typed by its row)
    try:
        writer.execute("UPDATE tgsis.vrtx SET z = z + 1 WHERE geoid = %s AND vrtxid < 3", (geoid,))
        writer.commit()
        before = conn.execute("SELECT * FROM public.tops ORDER BY vrtxid").fetchall()
        conn.commit()
        tgsis.partition_model_storage(conn, 1, PARTITIONS)
        assert conn.execute("SELECT 'tgsis.vrtx'::regclass::oid").fetchone() == face
        assert conn.execute("SELECT * FROM public.tops ORDER BY vrtxid").fetchall() == before
        conn.commit()
        writer.execute("UPDATE tgsis.vrtx SET z = z + 1 WHERE geoid = %s AND vrtxid < 3", (geoid,))
        writer.commit()
    finally:
        writer.close()
    after = conn.execute("SELECT * FROM public.tops ORDER BY vrtxid").fetchall()
    assert after == [(g, i, z + 1 if i < 3 else z) for g, i, z in before]
    assert _kinds(conn)["vrtx"] == ("p", PARTITIONS)


def test_partitioned_chunks_are_refused_a_second_time(conn: Conn) -> None:
    tgsis.partition_model_storage(conn, 1, PARTITIONS)
    with pytest.raises(tgsis.InUseError, match=r"tgsis\.\w+ is not a plain table") as caught:
        tgsis.partition_model_storage(conn, 1, 2)
    assert "partitioned already" in str(caught.value.detail)


def test_a_face_writer_in_flight_is_waited_for_and_kept(db_dsn: str, conn: Conn, horizons: Any) -> None:
    geoid = tgsis.insert_feature(conn, horizons, _grid(4))
    conn.commit()
    writer = psycopg.connect(db_dsn)
    try:
        writer.execute("UPDATE tgsis.vrtx SET z = 42 WHERE geoid = %s AND vrtxid = 3", (geoid,))  # not committed
        call = Background(db_dsn, "partition", lambda c: tgsis.partition_model_storage(c, 1, PARTITIONS))
        wait_until_blocked(conn, call.pid, writer.info.backend_pid)
        writer.commit()
        assert set(CHUNKED) <= set(call.finish())  # chunk storage is partitioned with its data: the write kept
    finally:
        writer.close()
    assert _kinds(conn)["vrtx"] == ("p", PARTITIONS)
    row = conn.execute("SELECT z FROM tgsis.vrtx WHERE geoid = %s AND vrtxid = 3", (geoid,)).fetchone()
    assert row == (42.0,)


def test_dump_and_restore_keep_partitioned_chunks(
    pg: TestServer, db_dsn: str, conn: Conn, horizons: Any, tmp_path: Path
) -> None:
    geoid = tgsis.insert_feature(conn, horizons, _grid(6))
    conn.commit()
    tgsis.partition_model_storage(conn, 1, PARTITIONS)  # with data on chunks; then versioning and an edit
    tgsis.enable_feature_versioning(conn)
    tgsis.create_version(conn, "edit")
    with tgsis.in_version(conn, "edit"):
        edited = _edited(conn, geoid, horizons, slice(0, 1), -3.0)
    conn.commit()
    chunks, seen = _chunk_rows(conn), _seen(conn)
    with _restored(pg, _bindir_of(pg), db_dsn, "custom", tmp_path) as dsn, psycopg.connect(dsn) as restored:
        assert _kinds(restored) == {t: ("p", PARTITIONS) for t in CHUNKED}
        assert _chunk_rows(restored) == chunks
        assert _seen(restored) == seen
        assert _triggers(restored, "tgsis.vrtx_chunk") == _triggers(conn, "tgsis.vrtx_chunk")
        tgsis.merge_version(restored, "edit")
        restored.commit()
        assert geometry_of(tgsis.fetch_feature(restored, horizons.name, geoid)).same_as(edited)
