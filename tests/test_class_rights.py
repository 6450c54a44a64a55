"""Per-class rights hold at the model tables every class shares (issue 36, point 8).

docs/security.md advises granting per feature class. A class's features keep
their geometry in the model tables of every class (``tgsis.geometry``,
``tgsis.vrtx``, ``tgsis.trgl``, the tables of models 2 to 5), so those rights
must hold there too: with every right on class ``beta`` revoked (and kept on
``alpha``), a reader, an editor, an admin and a role of no tgsis group neither
read nor write beta's rows through any model table, plain or versioned, in
DEFAULT or a child version, nor through the views' triggers, set-based
deletes, check-in or merges; alpha stays fully usable, and tgsis's owner
(the test database's superuser) still sees and does everything. Before the
fix, each of them read all of beta's vertices and triangles and the editor
moved them.
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import numpy as np
import psycopg
import pytest
from psycopg.conninfo import make_conninfo

import tgsis
from tests.gmaps_shapes import icosahedron
from tests.roles import Roles, login_roles
from tests.storage_data import in_chunks
from tests.synthetic import flat_grid
from tests.temporal_data import evolving, series
from tgsis import gmaps
from tgsis.datamodels import TimeModel
from tgsis.db import features as F
from tgsis.db._chunk_transfer import ObjectRows, chunked_tables, upload_chunks
from tgsis.db._transfer import Storage
from tgsis.db.inspect import static_triangle_corners, static_triangle_rows, static_vertex_rows

Conn = psycopg.Connection[Any]

ROLES = {"reader": "tgsis_reader", "editor": "tgsis_editor", "admin": "tgsis_admin", "outsider": "pg_read_all_settings"}


class World:
    """The login roles, the superuser's connection and the features: alpha's (allowed) and beta's (revoked)."""

    def __init__(self, roles: Roles, su: Conn, alpha: int, beta: int, temporal: dict[str, int]) -> None:
        self.roles, self.su, self.alpha, self.beta = roles, su, alpha, beta
        #: features of models 2 to 4: alpha_steps (allowed), beta_steps, beta_moves and beta_gmap (revoked)
        self.temporal = temporal

    @property
    def revoked(self) -> list[int]:
        """Every feature of a revoked class (models 1 to 4)."""
        return [self.beta, self.temporal["beta_steps"], self.temporal["beta_moves"], self.temporal["beta_gmap"]]


def _geoid_tables(conn: Conn) -> list[tuple[str, str]]:
    """Every model table holding rows per geoid, with its geoid column (the registry)."""
    return [
        (r[0], r[1])
        for r in conn.execute(
            "SELECT tablename, geoidcolumn FROM tgsis.model_tables WHERE geoidcolumn IS NOT NULL ORDER BY 1"
        ).fetchall()
    ]


def _count(conn: Conn, table: str, geoid: int) -> int:
    row = conn.execute(f"SELECT count(*) FROM tgsis.{table} WHERE geoid = %s", (geoid,)).fetchone()
    conn.rollback()
    assert row is not None
    return int(row[0])


def _sqlstate(conn: Conn, statement: str, params: tuple[Any, ...] = ()) -> str:
    with pytest.raises(psycopg.Error) as caught:
        conn.execute(statement, params)
    conn.rollback()
    assert caught.value.sqlstate is not None
    return caught.value.sqlstate


def _rows(su: Conn, geoid: int) -> Any:
    """beta's stored rows as tgsis's owner sees them (every revision)."""
    return (
        su.execute("SELECT * FROM tgsis.geometry WHERE geoid = %s", (geoid,)).fetchall(),
        su.execute("SELECT * FROM tgsis.vrtx WHERE geoid = %s ORDER BY vrtxid", (geoid,)).fetchall(),
        su.execute("SELECT * FROM tgsis.trgl WHERE geoid = %s ORDER BY trglid", (geoid,)).fetchall(),
    )


@pytest.fixture(params=["plain", "versioned"])
def world(request: pytest.FixtureRequest, db_dsn: str) -> Iterator[World]:
    """alpha and beta, one 5x5 surface each; every right on beta revoked from every role but tgsis's owner."""
    with psycopg.connect(db_dsn, autocommit=True) as su, login_roles(db_dsn, ROLES) as roles:
        F.create_feature_class(su, "alpha", "SURFACE")
        F.create_feature_class(su, "beta", "SURFACE")
        alpha = F.insert_feature(su, "alpha", flat_grid(5, 1.0))
        beta = F.insert_feature(su, "beta", flat_grid(5, 2.0))
        # models 2 and 3: a surface at instants and an evolving one
        rng = np.random.default_rng(36)
        temporal = {}
        models: list[tuple[str, TimeModel]] = [
            ("alpha_steps", "INSTANTS"),
            ("beta_steps", "INSTANTS"),
            ("beta_moves", "EVOLVING"),
        ]
        for name, model in models:
            tgsis.create_feature_class(su, name, "SURFACE", time_model=model, time_unit="Ma")
            shape = series(rng, [0.0, 1.0, 2.0]) if model == "INSTANTS" else evolving(rng, [0.0, 1.0])
            temporal[name] = F.insert_feature(su, name, shape)
        # model 4: a G-map
        F.create_feature_class(su, "beta_gmap", "GMAP", time_model="GMAP", cell_level=2)
        temporal["beta_gmap"] = F.insert_feature(su, "beta_gmap", gmaps.GMap.from_triangles(*icosahedron()))
        if request.param == "versioned":
            tgsis.enable_feature_versioning(su)
        for (table,) in su.execute("SELECT tablename FROM tgsis.class_tables WHERE classname LIKE 'beta%'").fetchall():
            su.execute(f"REVOKE ALL ON {table} FROM tgsis_reader, tgsis_editor, tgsis_admin, PUBLIC")
        # a role of no tgsis group, granted reading of alpha and of the model tables only
        outsider = roles.name("outsider")
        su.execute(f"GRANT USAGE ON SCHEMA tgsis TO {outsider}")
        su.execute(
            f"GRANT SELECT ON tgsis.catalog, tgsis.versions, tgsis.revisions, tgsis.versioned_tables TO {outsider}"
        )
        for (table,) in su.execute("SELECT tablename FROM tgsis.class_tables WHERE classname LIKE 'alpha%'").fetchall():
            su.execute(f"GRANT SELECT ON {table} TO {outsider}")
        for table, _ in _geoid_tables(su):
            su.execute(f"GRANT SELECT ON tgsis.{table} TO {outsider}")
        yield World(roles, su, alpha, beta, temporal)


@pytest.mark.parametrize("who", list(ROLES))
def test_no_role_reads_a_revoked_class_through_any_model_table(world: World, who: str) -> None:
    conn = world.roles.connect(who)
    stored = {table: sum(_count(world.su, table, g) for g in world.revoked) for table, _ in _geoid_tables(world.su)}
    assert {"vrtx", "trgl", "times", "node", "d4dvrtx", "d4dtrgl", "gmap"} <= {t for t, n in stored.items() if n > 0}
    for table, _ in _geoid_tables(conn):
        for geoid in world.revoked:
            assert _count(conn, table, geoid) == 0, (table, geoid)
    assert _count(conn, "geometry", world.temporal["alpha_steps"]) == 1
    assert _count(conn, "vrtx", world.alpha) == 25
    assert _count(conn, "trgl", world.alpha) == 32
    assert _count(conn, "geometry", world.alpha) == 1
    # no way round: a scan of everything, a join, a box query
    seen = {r[0] for r in conn.execute("SELECT DISTINCT geoid FROM tgsis.vrtx").fetchall()}
    assert world.beta not in seen and world.alpha in seen
    box = conn.execute("SELECT array_agg(b) FROM tgsis.geometries_in_box(-1, -1, -1, 10, 10, 10) AS b").fetchone()
    assert box is not None and world.beta not in (box[0] or [])
    conn.rollback()
    # tgsis's owner still reads everything
    assert _count(world.su, "vrtx", world.beta) == 25


@pytest.mark.parametrize("world", ["versioned"], indirect=True)  # versions need feature versioning
def test_a_child_version_hides_the_class_too(world: World) -> None:
    editor = world.roles.connect("editor")
    tgsis.create_version(editor, "e1")
    tgsis.goto_version(editor, "e1")
    assert _count(editor, "vrtx", world.beta) == 0
    assert _count(editor, "trgl", world.beta) == 0
    assert _count(editor, "vrtx", world.alpha) == 25
    # nor the storage of every revision (rows, or chunks)
    stored = editor.execute("SELECT tgsis.storage_table('tgsis', 'vrtx')").fetchone()
    assert stored is not None
    assert editor.execute(f"SELECT count(*) FROM {stored[0]} WHERE geoid = %s", (world.beta,)).fetchone() == (0,)
    editor.rollback()


@pytest.mark.parametrize("who", ["editor", "admin"])
def test_writers_cannot_change_a_revoked_class(world: World, who: str) -> None:
    before = _rows(world.su, world.beta)
    conn = world.roles.connect(who)
    for statement in (
        "UPDATE tgsis.vrtx SET z = z + 100 WHERE geoid = %s",
        "DELETE FROM tgsis.trgl WHERE geoid = %s",
        "UPDATE tgsis.geometry SET geoname = 'stolen' WHERE geoid = %s",
    ):
        cursor = conn.execute(statement, (world.beta,))
        assert cursor.rowcount == 0, statement  # rows it may not read are not there for it
        conn.commit()
    # every row, not only the filtered ones: it changes those it may, and nothing of beta
    visible = world.su.execute("SELECT count(*) FROM tgsis.vrtx WHERE geoid <> %s", (world.beta,)).fetchone()
    assert conn.execute("UPDATE tgsis.vrtx SET z = z + 100").rowcount == visible[0] > 0  # type: ignore[index]
    conn.commit()
    assert (
        _sqlstate(conn, "INSERT INTO tgsis.vrtx (geoid, vrtxid, x, y, z) VALUES (%s, 999, 0, 0, 0)", (world.beta,))
        == "42501"
    )
    assert (
        _sqlstate(
            conn,
            "INSERT INTO tgsis.trgl (geoid, trglid, vrtxid1, vrtxid2, vrtxid3) VALUES (%s, 999, 0, 1, 2)",
            (world.beta,),
        )
        == "42501"
    )
    assert _rows(world.su, world.beta) == before


def test_reading_without_writing_is_refused_at_the_write(world: World) -> None:
    """A role that may read beta but not change it: its writes of beta's rows are refused or change nothing."""
    editor = world.roles.connect("editor")
    world.su.execute(f"GRANT SELECT ON beta, beta_cellpros TO {world.roles.name('editor')}")
    before = _rows(world.su, world.beta)
    assert _count(editor, "vrtx", world.beta) == 25
    versioned = world.su.execute("SELECT count(*) > 0 FROM tgsis.versioned_tables").fetchone() == (True,)
    # a versioned view's trigger, or the face over chunks (versioned or not: docs/storage.md, "What differs from
    # rows"), refuses by name; on a plain table, row-level security skips the rows silently
    by_name = versioned or in_chunks(world.su)
    for statement in (
        "UPDATE tgsis.vrtx SET z = z + 100 WHERE geoid = %s",
        "UPDATE tgsis.vrtx SET z = z + 100 WHERE geoid = %s AND vrtxid = 0",
        "DELETE FROM tgsis.trgl WHERE geoid = %s",
    ):
        if by_name:  # the view's or the face's trigger refuses, naming the class
            with pytest.raises(psycopg.errors.InsufficientPrivilege, match="beta"):
                editor.execute(statement, (world.beta,))
            editor.rollback()
        else:  # row-level security on the plain table: PostgreSQL skips the rows
            assert editor.execute(statement, (world.beta,)).rowcount == 0
            editor.commit()
    assert (
        _sqlstate(editor, "INSERT INTO tgsis.vrtx (geoid, vrtxid, x, y, z) VALUES (%s, 999, 0, 0, 0)", (world.beta,))
        == "42501"
    )
    assert _rows(world.su, world.beta) == before


def test_the_permitted_class_stays_fully_usable(world: World) -> None:
    editor = world.roles.connect("editor")
    # an upload (binary COPY, staged through a temporary table under row-level security)
    geoid = F.insert_feature(editor, "alpha", flat_grid(4, 3.0))
    fetched = F.fetch_feature(editor, "alpha", geoid)
    assert fetched.mesh is not None and fetched.mesh.n_vertices == 16
    editor.execute("UPDATE tgsis.vrtx SET z = z + 1 WHERE geoid = %s", (world.alpha,))
    editor.commit()
    assert editor.execute("SELECT min(z) FROM tgsis.vrtx WHERE geoid = %s", (world.alpha,)).fetchone() == (2.0,)
    editor.rollback()
    assert F.delete_feature(editor, "alpha", geoid)
    assert _count(editor, "vrtx", geoid) == 0
    # the admin, granted beta again, does everything on it
    admin = world.roles.connect("admin")
    world.su.execute(f"GRANT ALL ON beta, beta_cellpros TO {world.roles.name('admin')}")
    assert _count(admin, "vrtx", world.beta) == 25
    admin.execute("UPDATE tgsis.vrtx SET z = z + 1 WHERE geoid = %s", (world.beta,))
    admin.commit()
    assert admin.execute("SELECT min(z) FROM tgsis.vrtx WHERE geoid = %s", (world.beta,)).fetchone() == (3.0,)
    admin.rollback()
    assert F.delete_feature(admin, "beta", world.beta)
    admin.commit()
    assert _count(world.su, "vrtx", world.beta) == 0


def test_upload_into_a_revoked_class_is_refused(world: World) -> None:
    """An editor's upload of rows for beta's feature (its geoid) is refused, nothing stored."""
    editor = world.roles.connect("editor")
    before = _rows(world.su, world.beta)
    with pytest.raises(psycopg.errors.InsufficientPrivilege), editor.transaction():
        storage = Storage.of(editor)
        if "vrtx" in chunked_tables(editor):  # the chunk upload (binary COPY of chunks, staged the same way)
            zeros = {name: np.zeros(3) for name in ("x", "y", "z")}
            upload_chunks(editor, "vrtx", [ObjectRows(world.beta, np.arange(1100, 1103, dtype=np.int64), zeros)])
        else:
            storage.copy(
                editor,
                "tgsis",
                "vrtx",
                [
                    ("geoid", np.full(3, world.beta, dtype=np.int64), "int8"),
                    ("vrtxid", np.arange(100, 103, dtype=np.int64), "int8"),
                    ("x", np.zeros(3), "float8"),
                    ("y", np.zeros(3), "float8"),
                    ("z", np.zeros(3), "float8"),
                ],
            )
    assert _rows(world.su, world.beta) == before
    # nor a new feature of the class, its definition given (so that no catalog read refuses first)
    with pytest.raises((tgsis.MissingPrivilegeError, psycopg.errors.InsufficientPrivilege)):
        F.insert_feature(editor, F.get_feature_class(world.su, "beta"), flat_grid(4, 3.0))
    editor.rollback()
    assert _rows(world.su, world.beta) == before


@pytest.mark.parametrize("world", ["versioned"], indirect=True)  # versions need feature versioning
def test_merge_of_changes_to_a_revoked_class_is_refused(world: World) -> None:
    # a version in which the superuser moved beta's vertices
    tgsis.create_version(world.su, "work")
    with tgsis.in_version(world.su, "work"):
        world.su.execute("UPDATE tgsis.vrtx SET z = z + 5 WHERE geoid = %s", (world.beta,))
    admin = world.roles.connect("admin")
    tgsis.grant_version(world.su, "work", "write", world.roles.name("admin"))
    before = _rows(world.su, world.beta)
    with pytest.raises(tgsis.Error) as caught:
        tgsis.merge_version(admin, "work")
    assert "beta" in str(caught.value)
    admin.rollback()
    assert _rows(world.su, world.beta) == before
    # with the right on beta, the same merge goes through
    world.su.execute(f"GRANT UPDATE ON beta TO {world.roles.name('admin')}")
    tgsis.merge_version(admin, "work")
    assert world.su.execute("SELECT min(z) FROM tgsis.vrtx WHERE geoid = %s", (world.beta,)).fetchone() == (7.0,)


@pytest.mark.parametrize("who", list(ROLES))
def test_the_view_s_downloads_by_geoid_return_nothing_of_a_revoked_class(world: World, who: str) -> None:
    """The browser view's reads take a geoid, no class: the storage's rights decide (rows, or chunks read
    directly once stored in chunks), as for the model tables."""
    conn = world.roles.connect(who)
    for geoid, n, m in ((world.alpha, 25, 32), (world.beta, 0, 0)):
        assert len(static_vertex_rows(conn, geoid)[0]) == n, (who, geoid)
        assert len(static_triangle_rows(conn, geoid)[0]) == m, (who, geoid)
        assert static_triangle_corners(conn, geoid).shape == (m, 3), (who, geoid)
    fetched = F.fetch_feature(conn, "alpha", world.alpha).mesh  # every role may read alpha: all of it
    assert fetched is not None and (fetched.n_vertices, fetched.n_cells) == (25, 32)
    conn.rollback()


@pytest.mark.parametrize("who", ["reader", "outsider"])
def test_tgsis_functions_return_nothing_of_a_revoked_class(world: World, who: str) -> None:
    """Snapshots at t, shapes in time, versioned rows: nothing of beta's features, all of alpha's."""
    conn = world.roles.connect(who)
    for geoid in world.revoked:
        for function in ("vertices_at", "triangles_at"):
            row = conn.execute(f"SELECT count(*) FROM tgsis.{function}(%s, 0.5)", (geoid,)).fetchone()
            assert row == (0,), (function, geoid)
    assert conn.execute(
        "SELECT count(*) > 0 FROM tgsis.vertices_at(%s, 0.5)", (world.temporal["alpha_steps"],)
    ).fetchone() == (True,)
    conn.rollback()
    # the class tables themselves: refused as before
    assert _sqlstate(conn, "SELECT * FROM tgsis.features_at('beta_steps', 0.5)") == "42501"
    if who == "reader" and world.su.execute("SELECT count(*) > 0 FROM tgsis.versioned_tables").fetchone() == (True,):
        rows = conn.execute(
            "SELECT count(*) FILTER (WHERE geoid = %s), count(*) FROM tgsis.rows_at(NULL::tgsis.vrtx, 'DEFAULT')",
            (world.beta,),
        ).fetchone()
        assert rows is not None and rows[0] == 0 and rows[1] > 0
        conn.rollback()


@pytest.mark.parametrize("world", ["versioned"], indirect=True)  # versions need feature versioning
def test_version_diffs_and_conflict_rows_hide_a_revoked_class(world: World) -> None:
    tgsis.create_version(world.su, "work")
    with tgsis.in_version(world.su, "work"):
        world.su.execute("UPDATE tgsis.vrtx SET z = z + 5 WHERE geoid IN (%s, %s)", (world.alpha, world.beta))
    world.su.execute("UPDATE tgsis.vrtx SET z = z - 5 WHERE geoid IN (%s, %s)", (world.alpha, world.beta))
    reader = world.roles.connect("reader")
    diff = reader.execute(
        "SELECT objectkey, shortname, changed FROM tgsis.diff_versions('DEFAULT', 'work') WHERE shortname = 'vrtx'"
    ).fetchall()
    assert [d[0] for d in diff] == [str(world.alpha)]
    reader.rollback()
    rows = reader.execute(
        "SELECT count(*) FROM tgsis.conflict_rows('work', 'feature', %s)", (str(world.beta),)
    ).fetchone()
    assert rows == (0,)
    rows = reader.execute(
        "SELECT count(*) FROM tgsis.conflict_rows('work', 'feature', %s)", (str(world.alpha),)
    ).fetchone()
    assert rows is not None and rows[0] > 0


def test_pg_dump_and_restore_keep_the_class_rights(world: World, pg: Any, db_dsn: str, tmp_path: Any) -> None:
    """The storage tables are no extension members: their policies go into the dump and come back."""
    from tests.test_backup import _bindir_of, _restored

    with _restored(pg, _bindir_of(pg), db_dsn, "custom", tmp_path) as dsn:
        reader = psycopg.connect(make_conninfo(dsn, user=world.roles.name("reader")))
        try:
            for geoid in world.revoked:
                assert (
                    _count(reader, "vrtx", geoid) + _count(reader, "times", geoid) + _count(reader, "node", geoid) == 0
                )
            assert _count(reader, "vrtx", world.alpha) == 25
            editor = psycopg.connect(make_conninfo(dsn, user=world.roles.name("editor")))
            try:
                assert (
                    _sqlstate(
                        editor,
                        "INSERT INTO tgsis.vrtx (geoid, vrtxid, x, y, z) VALUES (%s, 999, 0, 0, 0)",
                        (world.beta,),
                    )
                    == "42501"
                )
            finally:
                editor.close()
        finally:
            reader.close()


def test_every_model_table_and_partitioned_storage_carry_the_policies(conn: Conn) -> None:
    """Every model table with rows per geoid (the registry's), also after partition_model_storage swaps them: the
    table itself, or for a table stored in chunks its chunk table, under the class policies, and its face a
    security_barrier view filtering by the class rights (docs/storage.md, "The relational face over chunks")."""

    def protected() -> dict[str, int]:
        return {
            r[0]: r[1]
            for r in conn.execute(
                "SELECT t.tablename, count(p.polname) FILTER (WHERE p.polname LIKE 'tgsis_class_%%') "
                "  FROM tgsis.model_tables t JOIN pg_class c"
                "    ON c.relname = t.tablename || CASE WHEN tgsis.stored_in_chunks(t.tablename) THEN '_chunk' ELSE '' END"
                "   AND c.relnamespace = 'tgsis'::regnamespace AND c.relrowsecurity "
                "  LEFT JOIN pg_policy p ON p.polrelid = c.oid "
                " WHERE t.geoidcolumn IS NOT NULL GROUP BY t.tablename"
            ).fetchall()
        }

    def faces() -> list[str]:  # the faces over chunks: security_barrier views with the class rights' filter
        return [
            r[0]
            for r in conn.execute(
                "SELECT t.tablename FROM tgsis.model_tables t"
                "  JOIN pg_class c ON c.relname = t.tablename AND c.relnamespace = 'tgsis'::regnamespace"
                " WHERE tgsis.stored_in_chunks(t.tablename) AND c.relkind = 'v'"
                "   AND 'security_barrier=true' = ANY (c.reloptions)"
                "   AND pg_get_viewdef(c.oid) LIKE '%%class_denied_geoids%%' ORDER BY 1"
            ).fetchall()
        ]

    chunked = [
        r[0]
        for r in conn.execute(
            "SELECT tablename FROM tgsis.model_tables WHERE tgsis.stored_in_chunks(tablename) ORDER BY 1"
        ).fetchall()
    ]
    assert faces() == chunked

    expected = [
        r[0]
        for r in conn.execute(
            "SELECT tablename FROM tgsis.model_tables WHERE geoidcolumn IS NOT NULL ORDER BY 1"
        ).fetchall()
    ]
    assert protected() == {t: 4 for t in expected}
    conn.execute("SELECT tgsis.partition_model_storage(1::smallint, 4)")
    assert protected() == {t: 4 for t in expected}
    assert faces() == chunked


@pytest.mark.parametrize(
    "call",
    [
        "tgsis.class_denied_geoids('DROP')",
        "tgsis.class_denied_geoids(NULL)",
        "tgsis.check_class_write(ARRAY[1]::bigint[], 'SELECT')",
    ],
)
def test_a_privilege_the_checks_do_not_know_is_refused(conn: Conn, call: str) -> None:
    with pytest.raises(psycopg.Error) as caught:
        conn.execute(f"SELECT {call}")
    assert caught.value.sqlstate == "TG100" and "privilege" in str(caught.value)


@pytest.mark.parametrize("world", ["plain"], indirect=True)  # a versioned class's <table>_ver is its storage
def test_a_table_named_like_a_class_storage_does_not_hide_the_class(world: World) -> None:
    """Where a class's rows are stored is read from what its table is, not from a relation's name: an
    empty beta_ver made beside the plain table beta (by any role that may create tables in public) does not
    stand for beta's features."""
    world.su.execute("CREATE TABLE public.beta_ver (_geoid bigint)")
    world.su.execute("GRANT ALL ON public.beta_ver TO PUBLIC")
    for who in ROLES:
        conn = world.roles.connect(who)
        assert _count(conn, "vrtx", world.beta) == 0, who
        assert (
            _sqlstate(conn, "INSERT INTO tgsis.vrtx (geoid, vrtxid, x, y, z) VALUES (%s, 999, 0, 0, 0)", (world.beta,))
            == "42501"
        ), who


def test_a_geometry_is_not_slipped_into_a_revoked_class_s_collection(world: World) -> None:
    """A row of tgsis.geometry whose collection is a feature of beta is beta's (its member): a role that may
    not change beta may not make one, by INSERT or by UPDATE of its own rows (one row: the row path of a
    versioned view; several: its set-based flush), and the rows stay its own."""
    editor = world.roles.connect("editor")
    assert (
        _sqlstate(editor, "INSERT INTO tgsis.geometry (geotype, collection) VALUES ('MULTIPOINT', %s)", (world.beta,))
        == "42501"
    )
    mine = [
        editor.execute("INSERT INTO tgsis.geometry (geotype) VALUES ('MULTIPOINT') RETURNING geoid").fetchone()[0]  # type: ignore[index]
        for _ in range(3)
    ]
    editor.commit()
    for chosen in (mine[:1], mine):
        assert (
            _sqlstate(editor, "UPDATE tgsis.geometry SET collection = %s WHERE geoid = ANY (%s)", (world.beta, chosen))
            == "42501"
        ), chosen
    # the rows after the first (a versioned view writes them in its flush), the first one harmless
    for first in mine:
        assert (
            _sqlstate(
                editor,
                "UPDATE tgsis.geometry SET collection = CASE WHEN geoid = %s THEN NULL ELSE %s END "
                "WHERE geoid = ANY (%s)",
                (first, world.beta, mine),
            )
            == "42501"
        ), first
    members = world.su.execute("SELECT count(*) FROM tgsis.geometry WHERE collection = %s", (world.beta,)).fetchone()
    assert members == (0,)
    # its own collection, of a class it may change, takes them
    own = F.insert_feature(editor, "alpha", flat_grid(2, 1.0))
    editor.execute("UPDATE tgsis.geometry SET collection = %s WHERE geoid = ANY (%s)", (own, mine))
    editor.commit()
    assert world.su.execute("SELECT count(*) FROM tgsis.geometry WHERE collection = %s", (own,)).fetchone() == (3,)


def test_a_lesser_role_s_definer_function_reads_with_its_own_class_rights(world: World) -> None:
    """A SECURITY DEFINER function runs with its owner's rights, whoever calls it: one that the editor
    (no right on beta) wrote, called by the admin (every right on beta), sees none of beta's rows, by the
    model tables or their versioned views; the admin's own statements see them all."""
    editor_name, admin_name = world.roles.name("editor"), world.roles.name("admin")
    world.su.execute(f"CREATE SCHEMA lesser AUTHORIZATION {editor_name}")
    world.su.execute(f"GRANT USAGE ON SCHEMA lesser TO {admin_name}")
    world.su.execute(f"GRANT ALL ON beta, beta_cellpros TO {admin_name}")
    editor = world.roles.connect("editor")
    editor.execute(
        "CREATE FUNCTION lesser.peek(g bigint, t text) RETURNS bigint LANGUAGE plpgsql SECURITY DEFINER "
        "SET search_path = pg_catalog AS $$ DECLARE n bigint; "
        "BEGIN EXECUTE format('SELECT count(*) FROM tgsis.%I WHERE geoid = $1', t) INTO n USING g; "
        "RETURN n; END $$"
    )
    editor.execute(f"GRANT EXECUTE ON FUNCTION lesser.peek(bigint, text) TO {admin_name}")
    editor.commit()
    admin = world.roles.connect("admin")
    for table in ("vrtx", "trgl", "geometry"):
        assert admin.execute(f"SELECT count(*) > 0 FROM tgsis.{table} WHERE geoid = %s", (world.beta,)).fetchone() == (
            True,
        ), table
        assert admin.execute("SELECT lesser.peek(%s, %s)", (world.beta, table)).fetchone() == (0,), table
        assert admin.execute("SELECT lesser.peek(%s, %s) > 0", (world.alpha, table)).fetchone() == (True,), table
    admin.rollback()


@pytest.mark.parametrize("who", ["reader", "editor", "admin", "outsider"])
def test_deleting_a_revoked_class_s_feature_is_refused_or_finds_nothing(world: World, who: str) -> None:
    """Neither the client's delete_feature nor SQL's tgsis.delete_geometry removes a row of beta's features for
    a role without UPDATE or DELETE on beta: refused, or not there for it; every row stays."""
    classes = {world.beta: "beta", **{geoid: name for name, geoid in world.temporal.items() if name.startswith("beta")}}
    before = {g: _rows(world.su, g) for g in classes}
    conn = world.roles.connect(who)
    for geoid, classname in classes.items():
        try:
            assert not F.delete_feature(conn, classname, geoid)
        except tgsis.Error:
            conn.rollback()
        try:  # not there for it (false), or refused
            assert conn.execute("SELECT tgsis.delete_geometry(%s)", (geoid,)).fetchone() == (False,), geoid
            conn.commit()
        except psycopg.errors.InsufficientPrivilege:
            conn.rollback()
    assert {g: _rows(world.su, g) for g in classes} == before


def test_deleting_a_feature_the_role_may_read_but_not_change_is_refused(world: World) -> None:
    """With SELECT on beta (it sees the feature) and neither UPDATE nor DELETE, its deletion is refused by name,
    by the client and by SQL, and nothing of it goes. (Before, on plain tables, delete_feature answered True and
    tgsis.delete_geometry false, deleting nothing: row-level security hid the rows from its locking read.)"""
    editor = world.roles.connect("editor")
    world.su.execute(f"GRANT SELECT ON beta, beta_cellpros TO {world.roles.name('editor')}")
    before = _rows(world.su, world.beta)
    with pytest.raises(tgsis.Error, match="beta"):
        F.delete_feature(editor, "beta", world.beta)
    editor.rollback()
    assert _sqlstate(editor, "SELECT tgsis.delete_geometry(%s)", (world.beta,)) == "42501"
    assert _rows(world.su, world.beta) == before
