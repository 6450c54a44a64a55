"""tgsis.partition_model_storage of a model holding data, versioned: every version sees what it saw.

Model 1's atom and part stay rows beside its chunk tables (PostgreSQL 15
runs chunks), and on row storage (18) every model-1 table is rows: their row
path once needed the tables empty and unversioned, so a versioned model 1
with data could not be partitioned. Now the row storage (the table, or
``<table>_ver`` once versioned) is moved with its rows and verified
(``tgsis.partition_row_storage``). Checked here: every stored version (row
or chunk version) of every model-1 table, the rows every version and a saved
revision see through the views, the features fetched, before and after; the
guards of versioned storage and the rights made again; check-in and merge
afterwards.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import psycopg
import pytest
from psycopg import sql

import tgsis
from tests.roles import login_roles
from tests.storage_data import stored_versions

Conn = psycopg.Connection[Any]
PARTITIONS = 3
TABLES = ("vrtx", "point", "segment", "trgl", "tetra", "atom", "part")


def _grid(side: int, lift: float = 0.0) -> tgsis.Surface:
    u, v = np.meshgrid(np.arange(side, dtype=float), np.arange(side, dtype=float))
    vertices = np.stack([u.ravel(), v.ravel(), np.sin(u.ravel()) * np.cos(v.ravel()) + lift], axis=1)
    vertices[0, 2] = -0.0  # kept bit for bit
    idx = np.arange(side * side).reshape(side, side)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel()
    cells = np.concatenate([np.stack([a, b, d], 1), np.stack([a, d, c], 1)])
    return tgsis.Surface(vertices, cells, cell_properties={"part": (np.arange(len(cells)) % 7 < 3).astype(np.int64)})


def _seen(conn: Conn) -> dict[str, list[Any]]:
    """Every model-1 table's rows as the session sees them through its face, all columns, in order."""
    seen = {}
    for table in TABLES:
        rows = conn.execute(sql.SQL("SELECT t::text FROM tgsis.{} t ORDER BY 1").format(sql.Identifier(table)))
        seen[table] = rows.fetchall()
    return seen


def _state(conn: Conn, saved: int) -> dict[str, Any]:
    """What every version and the saved revision see, and every stored version of every table."""
    state: dict[str, Any] = {t: stored_versions(conn, t) for t in TABLES}
    for version in ("DEFAULT", "edit"):
        with tgsis.in_version(conn, version):
            state[version] = _seen(conn)
    with tgsis.at_revision(conn, saved, "DEFAULT"):
        state["saved"] = _seen(conn)
    conn.commit()
    return state


def _guards(conn: Conn) -> dict[str, Any]:
    """The triggers, grants, row-level security and policies of every model-1 storage table (names, texts)."""
    guards = {}
    for table in TABLES:
        storage = str(conn.execute("SELECT tgsis.storage_table('tgsis', %s)", (table,)).fetchone()[0])  # type: ignore[index]
        guards[table] = conn.execute(
            "SELECT (SELECT array_agg(replace(pg_get_triggerdef(t.oid), %s, '') ORDER BY t.tgname) FROM pg_trigger t "
            "        WHERE t.tgrelid = c.oid AND NOT t.tgisinternal), "
            "       c.relacl::text, c.relrowsecurity, c.relforcerowsecurity, "
            "       (SELECT array_agg(p.polname || ': ' || pg_get_expr(p.polqual, p.polrelid) ORDER BY p.polname) "
            "          FROM pg_policy p WHERE p.polrelid = c.oid) "
            "FROM pg_class c WHERE c.oid = %s::regclass",
            (storage, storage),
        ).fetchone()
    conn.commit()
    return guards


def _mesh(conn: Conn, geoid: int) -> tgsis.Mesh:
    mesh = tgsis.fetch_feature(conn, "horizons", geoid).mesh
    assert isinstance(mesh, tgsis.Mesh)
    return mesh


@pytest.fixture
def versioned_data(conn: Conn) -> tuple[list[int], int]:
    """Class horizons with four surfaces (parts, an atom), versioned; version edit moved and added, DEFAULT saved."""
    tgsis.create_feature_class(conn, "horizons", "SURFACE")
    ids = [tgsis.insert_feature(conn, "horizons", _grid(5, float(i))) for i in range(4)]
    conn.execute("INSERT INTO tgsis.atom (geoid, vrtxid, refid) VALUES (%s, 24, 3)", (ids[0],))
    conn.commit()
    tgsis.enable_feature_versioning(conn)
    saved = tgsis.save_revision(conn, "before the edit")
    tgsis.create_version(conn, "edit")
    conn.commit()
    with tgsis.in_version(conn, "edit"):
        conn.execute("UPDATE tgsis.vrtx SET z = z + 1.5 WHERE geoid = %s AND vrtxid < 5", (ids[1],))
        conn.execute("UPDATE tgsis.part SET part = 9 WHERE geoid = %s AND part = 1", (ids[2],))
        tgsis.insert_feature(conn, "horizons", _grid(4, 7.0))
    conn.execute("DELETE FROM tgsis.trgl WHERE geoid = %s AND trglid = 0", (ids[3],))  # DEFAULT, after the save
    conn.commit()
    return ids, saved


def test_a_versioned_model_1_with_data_is_partitioned_and_every_version_sees_the_same(
    conn: Conn, versioned_data: tuple[list[int], int]
) -> None:
    ids, saved = versioned_data
    before = _state(conn, saved)
    guards = _guards(conn)
    meshes = [_mesh(conn, i) for i in ids]
    conn.commit()
    assert sorted(tgsis.partition_model_storage(conn, 1, PARTITIONS)) == sorted(TABLES)
    conn.commit()
    for table in TABLES:
        storage = conn.execute(
            "SELECT c.relkind, (SELECT count(*) FROM pg_inherits i WHERE i.inhparent = c.oid) "
            "FROM pg_class c WHERE c.oid = tgsis.storage_table('tgsis', %s)::regclass",
            (table,),
        ).fetchone()
        assert storage == ("p", PARTITIONS), table
    assert _state(conn, saved) == before
    assert _guards(conn) == guards
    for i, mesh in zip(ids, meshes, strict=True):
        after = _mesh(conn, i)
        assert after.vertices.tobytes() == mesh.vertices.tobytes() and np.array_equal(after.cells, mesh.cells)
        assert after.cell_properties["part"].tobytes() == mesh.cell_properties["part"].tobytes()
    conn.commit()

    # and it goes on: a check-in in the version, the version merged, an editor's write through the views
    with tgsis.in_version(conn, "edit"):
        out = tgsis.checkout(conn, ids[0])
        edited = out.mesh.copy()
        edited.vertices[3, 2] += 2.0
        tgsis.checkin(conn, out, edited)
    conn.commit()
    tgsis.merge_version(conn, "edit")
    conn.commit()
    merged = _mesh(conn, ids[0])
    assert merged.vertices[3, 2] == meshes[0].vertices[3, 2] + 2.0
    parts = conn.execute("SELECT DISTINCT part FROM tgsis.part WHERE geoid = %s ORDER BY 1", (ids[2],)).fetchall()
    assert parts == [(0,), (9,)]
    conn.commit()


def test_an_editor_s_direct_write_into_the_storage_is_still_guarded(
    conn: Conn, versioned_data: tuple[list[int], int], db_dsn: str
) -> None:
    """tgsis's triggers of versioned storage are made again on the partitioned <table>_ver (or _chunk)."""
    ids, _ = versioned_data
    tgsis.partition_model_storage(conn, 1, PARTITIONS)
    conn.commit()
    with login_roles(db_dsn, {"ed": "tgsis_editor"}) as roles:
        ed = roles.connect("ed")
        storage = str(ed.execute("SELECT tgsis.storage_table('tgsis', 'atom')").fetchone()[0])  # type: ignore[index]
        # a version other than the session's: refused by the storage's row check
        with pytest.raises(psycopg.Error) as refused:
            ed.execute(
                sql.SQL("INSERT INTO {} (geoid, vrtxid, refid, revision) VALUES (%s, 20, 1, 0)").format(
                    sql.SQL(storage)
                ),
                (ids[0],),
            )
        ed.rollback()
        assert refused.value.sqlstate is not None and refused.value.sqlstate.startswith("TG"), refused.value
        with pytest.raises(psycopg.errors.InsufficientPrivilege):
            ed.execute(sql.SQL("DELETE FROM {}").format(sql.SQL(storage)))
        ed.rollback()
        ed.execute("INSERT INTO tgsis.atom (geoid, vrtxid, refid) VALUES (%s, 21, 2)", (ids[0],))  # the view: fine
        ed.commit()
    assert conn.execute("SELECT count(*) FROM tgsis.atom WHERE geoid = %s", (ids[0],)).fetchone() == (2,)


def test_a_users_trigger_on_versioned_storage_is_refused_by_name(
    conn: Conn, versioned_data: tuple[list[int], int]
) -> None:
    conn.execute(
        "CREATE FUNCTION public.seen() RETURNS trigger LANGUAGE plpgsql AS $$BEGIN RETURN NULL; END$$; "
        "CREATE TRIGGER seen AFTER INSERT ON tgsis.part_ver FOR EACH STATEMENT EXECUTE FUNCTION public.seen()"
    )
    conn.commit()
    before = {t: stored_versions(conn, t) for t in TABLES}
    with pytest.raises(tgsis.InUseError, match=r"tgsis\.part_ver is used by other objects") as refused:
        tgsis.partition_model_storage(conn, 1, PARTITIONS)
    conn.rollback()
    assert refused.value.detail == "used by: trigger seen on tgsis.part_ver"
    assert {t: stored_versions(conn, t) for t in TABLES} == before
    kinds = conn.execute(
        "SELECT array_agg(DISTINCT c.relkind) FROM tgsis.model_tables t "
        "JOIN pg_class c ON c.oid = tgsis.storage_table('tgsis', t.tablename)::regclass WHERE t.model = 1"
    ).fetchone()
    assert kinds == (["r"],)  # nothing partitioned
