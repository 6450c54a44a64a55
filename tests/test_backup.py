"""pg_dump and restore keep everything, on both install routes (docs/install.md, "Backup and restore").

One scenario per install route, through the public API: classes of every time
model with features, feature versioning, versions with edits, named
revisions, an unsolved and a solved conflict, object locks, rights on
versions, a versioned plain table. The database is dumped plain and
``-Fc``, each dump is restored into a new database of the same cluster, and
the restored databases must read exactly like the original: every version
and every revision of every versioned table (``tgsis.rows_at``), the version
tree, revisions, conflicts, locks, rights, catalog, every table's rows, every
sequence's next value, the objects and their rights and comments. Then goto,
fetch, check-out/check-in, new features and revisions, versioning new tables,
and merge work in the restored database, and no geoid or revision is handed
out again. Classes edited while versioned (a property added, one renamed:
tgsis.add_property, rename_property) keep every version's values and are
written through their rebuilt views after the restore.
"""

from __future__ import annotations

import contextlib
import subprocess
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import psycopg
import pytest
from psycopg import sql

import tgsis
from tests.catalog import describe_tgsis_objects
from tests.gmaps_shapes import block_tetrahedra
from tests.roles import Roles, login_roles
from tests.synthetic import flat_grid
from tests.temporal_data import evolving, series
from tgsis.db.local import find_binaries
from tgsis.testing import TestServer

Conn = psycopg.Connection[Any]
Snapshot = dict[str, Any]

# what the comparison reads besides the versioned tables: the catalog relations of docs/data-models.md
CATALOG = [
    "installation",
    "catalog",
    "versions",
    "revisions",
    "version_privileges",
    "object_locks",
    "conflicts",
    "conflict_regions",
    "versioned_tables",
    "versioning_dropped",
    "unversioned_features",
    "revision_objects",
]


def _bindir_of(pg: TestServer) -> Path:
    """The bin folder of the pg_dump/pg_restore/psql matching the test server's major version."""
    if pg.local is not None:
        return pg.local.binaries.bindir
    tried = []
    for selection in ("embedded", "system", f"/usr/lib/postgresql/{pg.major}/bin"):
        with contextlib.suppress(Exception):
            binaries = find_binaries(selection)
            out = subprocess.run([str(binaries.bindir / "pg_dump"), "--version"], capture_output=True, text=True)
            tried.append(f"{binaries.bindir}: {out.stdout.strip()}")
            if out.stdout.split()[-1].split(".")[0] == str(pg.major):
                return binaries.bindir
    pytest.fail(f"no pg_dump of PostgreSQL {pg.major} for the test server; tried {tried}", pytrace=False)


def _run(args: list[str]) -> str:
    out = subprocess.run(args, capture_output=True, text=True)
    assert out.returncode == 0, f"{' '.join(args[:3])} failed:\n{out.stderr}"
    assert "ERROR" not in out.stderr and "error:" not in out.stderr, out.stderr
    return out.stderr


@contextlib.contextmanager
def _restored(pg: TestServer, bindir: Path, source_dsn: str, fmt: str, tmp_path: Path) -> Iterator[str]:
    """Dump ``source_dsn`` in format ``fmt`` (plain or custom) and restore it into a new database; yield its DSN."""
    dump = tmp_path / f"dump.{fmt}"
    _run([str(bindir / "pg_dump"), f"--format={fmt}", f"--file={dump}", source_dsn])
    with pg.database("tgsis_restore") as (_, dsn):
        if fmt == "plain":
            _run([str(bindir / "psql"), "-X", "-q", "-v", "ON_ERROR_STOP=1", "-d", dsn, "-f", str(dump)])
        else:
            _run([str(bindir / "pg_restore"), "--exit-on-error", "-d", dsn, str(dump)])
        yield dsn


def _rows(conn: Conn, query: sql.Composed, params: tuple[Any, ...] = ()) -> list[str]:
    return [str(r[0]) for r in conn.execute(query, params).fetchall()]


def snapshot(conn: Conn) -> Snapshot:
    """Everything a restore must keep, read through tgsis's relations and functions, as comparable values."""
    snap: Snapshot = {}
    for table in CATALOG:
        snap[table] = _rows(conn, sql.SQL("SELECT t::text FROM tgsis.{} t ORDER BY 1").format(sql.Identifier(table)))
    revisions = conn.execute(
        "SELECT v.name, r.revision FROM tgsis.revisions r JOIN tgsis.versions v USING (versionid) ORDER BY 2"
    ).fetchall()
    versioned = conn.execute("SELECT schemaname, tablename FROM tgsis.versioned_tables ORDER BY 1, 2").fetchall()
    assert revisions and versioned
    for schema, table in versioned:
        rel = sql.Identifier(schema, table)
        for version, revision in [*((v, None) for v in {v for v, _ in revisions}), *revisions]:
            snap[f"{schema}.{table} in {version}@{revision}"] = _rows(
                conn,
                sql.SQL("SELECT t::text FROM tgsis.rows_at(NULL::{}, %s, %s) t ORDER BY 1").format(rel),
                (version, revision),
            )
    # every table as stored, and every sequence's next value
    tables = conn.execute(
        "SELECT n.nspname, c.relname FROM pg_class c JOIN pg_namespace n ON n.oid = c.relnamespace "
        "WHERE c.relkind = 'r' AND n.nspname IN ('public', 'tgsis') ORDER BY 1, 2"
    ).fetchall()
    for schema, table in tables:
        snap[f"table {schema}.{table}"] = _rows(
            conn, sql.SQL("SELECT t::text FROM {} t ORDER BY 1").format(sql.Identifier(schema, table))
        )
    snap["sequences"] = conn.execute(
        "SELECT schemaname, sequencename, last_value FROM pg_sequences "
        "WHERE schemaname IN ('public', 'tgsis') ORDER BY 1, 2"
    ).fetchall()
    # the objects: tgsis's (definitions, rights, comments, triggers) and the application's
    snap["tgsis objects"] = describe_tgsis_objects(conn)
    snap["public objects"] = conn.execute(
        "SELECT c.relname, c.relkind, c.relacl::text, obj_description(c.oid, 'pg_class'), "
        "       CASE WHEN c.relkind = 'v' THEN pg_get_viewdef(c.oid) END, "
        "       (SELECT array_agg(pg_get_triggerdef(g.oid) ORDER BY g.tgname) FROM pg_trigger g "
        "         WHERE g.tgrelid = c.oid AND NOT g.tgisinternal) "
        "  FROM pg_class c WHERE c.relnamespace = 'public'::regnamespace ORDER BY 1"
    ).fetchall()
    snap["public functions"] = conn.execute(
        "SELECT p.oid::regprocedure::text, pg_get_functiondef(p.oid), p.proacl::text FROM pg_proc p "
        " WHERE p.pronamespace = 'public'::regnamespace AND p.oid NOT IN "
        "       (SELECT objid FROM pg_depend WHERE deptype = 'e') ORDER BY 1"
    ).fetchall()
    snap["extensions"] = conn.execute("SELECT extname, extversion FROM pg_extension ORDER BY 1").fetchall()
    return snap


def build_scenario(conn: Conn, roles: Roles) -> dict[str, int]:
    """The small but complete state a backup must keep; returns the feature ids by name."""
    rng = np.random.default_rng(15)
    tgsis.create_feature_class(conn, "faults", "SURFACE", feature_properties={"release": "text"})
    tgsis.create_feature_class(
        conn,
        "moving",
        "SURFACE",
        time_model="EVOLVING",
        time_unit="Ma",
        cell_properties=[("porosity", "double precision")],
        instant_properties=[("throw", "double precision"), ("note_code", "integer")],
    )
    tgsis.create_feature_class(
        conn,
        "stepped",
        "SURFACE",
        time_model="INSTANTS",
        cell_properties=[("porosity", "double precision")],
        instant_properties=[("throw", "double precision")],
    )
    ids = {f"f{i}": tgsis.insert_feature(conn, "faults", flat_grid(3, float(i)), {"release": "5.3"}) for i in range(4)}
    ids["moving"] = tgsis.insert_feature(conn, "moving", evolving(rng, [0.0, 2.0], with_properties=True))
    ids["stepped"] = tgsis.insert_feature(conn, "stepped", series(rng, [0.0, 1.0], with_properties=True))
    # G-maps: model 4 (a block of tetrahedra with a porosity per volume) and model 5 (the block with a knowledge axis)
    tgsis.create_feature_class(
        conn, "blocks", "GMAP", time_model="GMAP", cell_level=3, cell_properties=[("porosity", "double precision")]
    )
    tgsis.create_feature_class(conn, "knowledge", "GMAP", time_model="MULTIDIM", cell_level=3)
    solid = tgsis.GMap.from_tetrahedra(*block_tetrahedra(1))
    ids["block"] = tgsis.insert_feature(
        conn,
        "blocks",
        tgsis.GMap(
            solid.alpha, solid.vertex, solid.points, cell_properties={3: {"porosity": rng.random(solid.n_cells(3))}}
        ),
    )
    ids["history"] = tgsis.insert_gmap(
        conn,
        "knowledge",
        tgsis.GMap(solid.alpha, solid.vertex, np.column_stack([solid.points, np.arange(solid.n_points) % 2])),
        axes=["x", "y", "z", "knowledge"],
    )
    conn.execute(
        "CREATE TABLE wells (id integer GENERATED ALWAYS AS IDENTITY PRIMARY KEY, name text NOT NULL, "
        "depth double precision)"
    )
    conn.execute("COMMENT ON TABLE wells IS 'boreholes'")
    conn.execute("INSERT INTO wells (name, depth) VALUES ('W-1', 1000), ('W-2', 1200), ('W-3', 800)")
    conn.execute(
        sql.SQL("GRANT SELECT, INSERT, UPDATE, DELETE ON wells TO {}").format(sql.Identifier(roles.name("ann")))
    )
    # a partitioned table, versioned: its storage stays partitioned through the dump
    conn.execute(
        "CREATE TABLE logs (well integer, at double precision, gamma double precision, PRIMARY KEY (well, at)) "
        "PARTITION BY HASH (well)"
    )
    for r in range(2):
        conn.execute(
            sql.SQL("CREATE TABLE {} PARTITION OF logs FOR VALUES WITH (MODULUS 2, REMAINDER {})").format(
                sql.Identifier(f"logs_{r}"), sql.Literal(r)
            )
        )
    conn.execute("INSERT INTO logs SELECT w, d, 10 * w + d FROM generate_series(1, 3) w, generate_series(0, 4) d")
    conn.execute(
        sql.SQL("GRANT SELECT, INSERT, UPDATE, DELETE ON logs TO {}").format(sql.Identifier(roles.name("ann")))
    )
    # a class without versioning (registered before feature versioning: its key to tgsis.geometry is dropped then)
    tgsis.create_feature_class(conn, "surveys", "SURFACE", feature_properties={"release": "text"}, versioned=False)
    ids["survey"] = tgsis.insert_feature(conn, "surveys", flat_grid(3, 7.0), {"release": "s1"})
    conn.commit()
    tgsis.enable_versioning(conn, "wells", "id", "well")
    tgsis.enable_versioning(conn, "logs", "well", "log")
    tgsis.enable_feature_versioning(conn)

    tgsis.create_version(conn, "edit", description="reinterpretation")
    tgsis.create_version(conn, "other")
    tgsis.create_version(conn, "deep", "edit")
    with tgsis.in_version(conn, "edit"):
        conn.execute("UPDATE tgsis.vrtx SET z = z + 5 WHERE geoid = %s AND vrtxid = 4", (ids["f0"],))
        conn.execute("UPDATE faults SET release = 'edit' WHERE _geoid = %s", (ids["f1"],))
        conn.execute("UPDATE tgsis.d4dvrtx SET z = z + 10 WHERE geoid = %s AND timem = 0", (ids["moving"],))
        conn.execute("UPDATE wells SET depth = 1250 WHERE name = 'W-1'")
        conn.execute("UPDATE logs SET gamma = gamma + 1 WHERE well = 1")
        conn.execute(
            "UPDATE tgsis.gmap_vertex SET coordinate[3] = coordinate[3] + 2 WHERE geoid = %s AND nodeid = 0",
            (ids["block"],),
        )
        conn.commit()
        tgsis.save_revision(conn, "first_pick")
        ids["new in edit"] = tgsis.insert_feature(conn, "faults", flat_grid(2, 9.0), {"release": "edit"})
        conn.execute("DELETE FROM wells WHERE name = 'W-3'")
        conn.commit()
    with tgsis.in_version(conn, "deep"):
        conn.execute("UPDATE tgsis.vrtx SET x = x - 1 WHERE geoid = %s AND vrtxid = 0", (ids["f2"],))
        conn.commit()
        tgsis.save_revision(conn, "deep_one")
    # DEFAULT changes f0 and f1 too: two conflicts in edit, one solved
    conn.execute("UPDATE tgsis.vrtx SET z = z - 5 WHERE geoid = %s AND vrtxid = 4", (ids["f0"],))
    conn.execute("UPDATE faults SET release = 'default' WHERE _geoid = %s", (ids["f1"],))
    conn.execute("INSERT INTO wells (name, depth) VALUES ('W-4', 300)")
    conn.execute("UPDATE tgsis.vrtx SET z = z + 1 WHERE geoid = %s AND vrtxid = 0", (ids["survey"],))  # in place
    conn.commit()
    tgsis.save_revision(conn, "default_after_edits")
    assert len(tgsis.find_conflicts(conn, "edit")) == 2
    tgsis.resolve_conflict(conn, "edit", "feature", ids["f1"], "child")
    tgsis.lock_objects(conn, "other", "feature", [ids["f3"]], exclusive=True)
    tgsis.lock_objects(conn, "edit", "well", [2])
    tgsis.grant_version(conn, "edit", "write", roles.name("ann"))
    tgsis.grant_version(conn, "other", "create", roles.name("bob"))
    tgsis.revoke_version(conn, "DEFAULT", "create", "tgsis_editor")  # a shipped right taken back stays taken
    # grants given after the install: on a catalog table and a function of the extension, on a versioned view
    bob = sql.Identifier(roles.name("bob"))
    conn.execute(sql.SQL("GRANT SELECT ON tgsis.conflicts TO {}").format(bob))
    conn.execute(sql.SQL("GRANT EXECUTE ON FUNCTION tgsis.compress_versions(boolean) TO {}").format(bob))
    conn.execute(sql.SQL("GRANT SELECT ON tgsis.vrtx, faults TO {}").format(bob))
    # a check-out edited and checked in, in a version
    with tgsis.in_version(conn, "other"):
        co = tgsis.checkout(conn, ids["f2"])
        tgsis.checkin(conn, co, _lifted(co.mesh, 1, 3.0))
    conn.commit()
    # classes edited while versioned (tgsis class alter): a new column in every version's rows, one renamed
    tgsis.add_property(conn, "faults", ("basin", "text"), kind="feature", default="Paris")
    tgsis.add_property(conn, "stepped", ("k", "real"), default=1.5)
    tgsis.rename_property(conn, "moving", "note_code", "note", kind="instant")
    with tgsis.in_version(conn, "edit"):
        conn.execute("UPDATE faults SET basin = 'edit basin' WHERE _geoid = %s", (ids["new in edit"],))
        conn.execute("UPDATE stepped_cellpros SET k = 3 WHERE _geoid = %s AND _idx = 0", (ids["stepped"],))
    conn.commit()
    # the new column changed the stored rows of f1 on both sides, not what either side chose: still solved
    # (docs/versioning.md, "Editing a versioned class")
    assert {c.objectkey: c.solution for c in tgsis.find_conflicts(conn, "edit")}[str(ids["f1"])] == "child"
    conn.commit()
    return ids


def _lifted(mesh: Any, vertex: int, dz: float) -> tgsis.Surface:
    """The checked-out surface with one vertex moved up."""
    vertices = mesh.vertices.copy()
    vertices[vertex, 2] += dz
    return tgsis.Surface(vertices, mesh.cells.copy(), vertex_properties=dict(mesh.vertex_properties), name=mesh.name)


def _surface(mesh: Any) -> tgsis.Surface:
    assert isinstance(mesh, tgsis.Surface)
    return mesh


def _fetch(conn: Conn, version: str, ids: dict[str, int]) -> dict[str, Any]:
    """What a user reads of every feature in a version: meshes, properties, and the temporal shapes at t."""
    seen: dict[str, Any] = {}
    with tgsis.in_version(conn, version):
        for key, fid in sorted(ids.items()):
            klass = {"moving": "moving", "stepped": "stepped", "survey": "surveys"}.get(key, "faults")
            if key == "block":
                g = tgsis.fetch_gmap(conn, "blocks", fid).at(0.0)
                assert g is not None
                seen[key] = (
                    g.alpha.tolist(),
                    g.points.tolist(),
                    g.cell_properties[3]["porosity"].tolist(),
                    tgsis.gmap_check(conn, fid),
                )
            elif key == "history":
                h, axes = tgsis.fetch_md_gmap(conn, "knowledge", fid)
                seen[key] = (h.alpha.tolist(), h.points.tolist(), axes, tgsis.gmap_check(conn, fid))
            elif klass in ("faults", "surveys"):
                try:
                    feature = tgsis.fetch_feature(conn, klass, fid)
                except tgsis.NotFoundError:
                    seen[key] = None
                    continue
                mesh = _surface(feature.mesh)
                seen[key] = (mesh.vertices.tolist(), mesh.triangles.tolist(), feature.properties)
            else:
                shape = tgsis.get_at(conn, fid, 0.5)
                assert shape is not None
                seen[key] = (shape.vertices.tolist(), shape.triangles.tolist())
    return seen


def _only(a: Any, b: Any) -> list[str]:
    """What of ``a`` is not in ``b``, for messages."""
    if isinstance(a, dict) and isinstance(b, dict):
        return [k for k in a if a[k] != b.get(k)]
    return [str(x) for x in a if x not in b][:5] if isinstance(a, list) and isinstance(b, list) else [str(a)]


def _check_backup(route: str, pg: TestServer, make_database: Any, tmp_path: Path) -> None:
    bindir = _bindir_of(pg)
    source = make_database()
    with psycopg.connect(source) as conn:
        assert tgsis.install(conn, method=route).method == route  # type: ignore[arg-type]
    with login_roles(source, {"ann": "tgsis_editor", "bob": "tgsis_editor"}) as roles, psycopg.connect(source) as conn:
        ids = build_scenario(conn, roles)
        before = snapshot(conn)
        read = {v: _fetch(conn, v, ids) for v in ("DEFAULT", "edit", "other", "deep")}
        max_geoid = conn.execute("SELECT max(geoid) FROM tgsis.geometry_ver").fetchone()
        max_revision = conn.execute("SELECT max(revision) FROM tgsis.revisions").fetchone()
        conn.rollback()
        for fmt in ("plain", "custom"):
            with _restored(pg, bindir, source, fmt, tmp_path) as dsn, psycopg.connect(dsn) as copy:
                after = snapshot(copy)
                assert after.keys() == before.keys()
                differing = [k for k in before if after[k] != before[k]]
                assert not differing, (
                    f"{route} route, {fmt} dump: differs after restore: {differing}; first: "
                    f"only before {_only(before[differing[0]], after[differing[0]])}, "
                    f"only after {_only(after[differing[0]], before[differing[0]])}"
                )
                assert {v: _fetch(copy, v, ids) for v in read} == read
                _use_restored(
                    copy, ids, roles, dsn, max_geoid[0] if max_geoid else 0, max_revision[0] if max_revision else 0
                )


def _use_restored(conn: Conn, ids: dict[str, int], roles: Roles, dsn: str, max_geoid: int, max_revision: int) -> None:
    """Versioning goes on in the restored database: goto, fetch, check-in, new features and revisions, merge."""
    tgsis.goto_version(conn, "edit")
    assert tgsis.working_version(conn) == "edit"
    tgsis.goto_version(conn, "DEFAULT")
    fid = tgsis.insert_feature(conn, "faults", flat_grid(2, 7.0), {"release": "after restore"})
    assert fid > max_geoid, "a restored database handed out an existing geoid again"
    with tgsis.in_version(conn, "edit"):
        co = tgsis.checkout(conn, ids["f0"])
        edited = _lifted(co.mesh, 0, 1.0)
        tgsis.checkin(conn, co, edited)
        assert _surface(tgsis.fetch_feature(conn, "faults", ids["f0"]).mesh).vertices[0, 2] == edited.vertices[0, 2]
        tgsis.save_revision(conn, "after_restore")
        revision = tgsis.working_revision(conn)
    assert revision > max_revision, "a restored database handed out an existing revision again"
    # the class without versioning: one state every version sees, written in DEFAULT only
    with tgsis.in_version(conn, "edit"), pytest.raises(tgsis.NotVersionedError, match="class surveys"):
        tgsis.save_feature(
            conn, "surveys", ids["survey"], _lifted(tgsis.fetch_feature(conn, "surveys", ids["survey"]).mesh, 1, 2.0)
        )
    lifted = _lifted(tgsis.fetch_feature(conn, "surveys", ids["survey"]).mesh, 1, 2.0)
    tgsis.save_feature(conn, "surveys", ids["survey"], lifted)
    conn.commit()
    with tgsis.in_version(conn, "deep"):
        np.testing.assert_array_equal(
            _surface(tgsis.fetch_feature(conn, "surveys", ids["survey"]).mesh).vertices, lifted.vertices
        )
    # versioning new tables: a feature class created now is versioned as created; a plain table too
    tgsis.create_feature_class(conn, "late", "MULTIPOINT")
    assert ("public", "late") in {(t.schema, t.table) for t in tgsis.versioned_tables(conn)}
    conn.execute("CREATE TABLE samples (id integer PRIMARY KEY, v text)")
    conn.commit()
    tgsis.enable_versioning(conn, "samples", "id", "sample")
    # rights on versions hold: ann may write in edit (granted), not in other
    with psycopg.connect(psycopg.conninfo.make_conninfo(dsn, user=roles.name("ann"))) as ann:
        with tgsis.in_version(ann, "edit"):
            ann.execute("UPDATE wells SET depth = 1300 WHERE name = 'W-1'")
            ann.execute("UPDATE logs SET gamma = 0 WHERE well = 2 AND at = 0")
            # several rows: all but the first go through the restored queue (owner-only, its index), for ann
            assert ann.execute("UPDATE logs SET gamma = gamma + 100 WHERE well = 3").rowcount == 5
            ann.commit()
        with tgsis.in_version(ann, "other"), pytest.raises(psycopg.Error) as refused:
            ann.execute("UPDATE wells SET depth = 1 WHERE name = 'W-1'")
        assert refused.value.sqlstate == "TG002"
        ann.rollback()
    # the edited classes: written through their rebuilt views in a version, edited again
    with tgsis.in_version(conn, "edit"):
        assert conn.execute("SELECT basin FROM faults WHERE _geoid = %s", (ids["new in edit"],)).fetchone() == (
            "edit basin",
        )
        conn.execute("UPDATE faults SET basin = 'after restore' WHERE _geoid = %s", (ids["new in edit"],))
        conn.execute("UPDATE moving_pros SET note = 7 WHERE _geoid = %s", (ids["moving"],))
        conn.commit()
        assert conn.execute("SELECT basin FROM faults WHERE _geoid = %s", (ids["new in edit"],)).fetchone() == (
            "after restore",
        )
        assert conn.execute("SELECT DISTINCT note FROM moving_pros WHERE _geoid = %s", (ids["moving"],)).fetchall() == [
            (7,)
        ]
        assert conn.execute(
            "SELECT DISTINCT k FROM stepped_cellpros WHERE _geoid = %s ORDER BY 1", (ids["stepped"],)
        ).fetchall() == [(1.5,), (3.0,)]
    conn.rollback()
    assert conn.execute("SELECT basin FROM faults WHERE _geoid = %s", (ids["f2"],)).fetchone() == ("Paris",)
    # the unsolved conflict is still there; solved, the merge goes through and DEFAULT sees edit's state
    unsolved = [c for c in tgsis.find_conflicts(conn, "edit") if c.solution == "unsolved"]
    assert [c.objectkey for c in unsolved] == [str(ids["f0"])]
    tgsis.resolve_conflict(conn, "edit", "feature", ids["f0"], "child")
    tgsis.merge_version(conn, "edit")
    with tgsis.in_version(conn, "edit"):
        in_edit = _surface(tgsis.fetch_feature(conn, "faults", ids["f0"]).mesh).vertices
    np.testing.assert_array_equal(_surface(tgsis.fetch_feature(conn, "faults", ids["f0"]).mesh).vertices, in_edit)
    assert conn.execute("SELECT depth FROM wells WHERE name = 'W-1'").fetchone() == (1300,)
    assert conn.execute("SELECT relkind FROM pg_class WHERE oid = 'logs_ver'::regclass").fetchone() == ("p",)
    assert conn.execute("SELECT well, at, gamma FROM logs WHERE at = 0 ORDER BY 1").fetchall() == [
        (1, 0.0, 11.0),
        (2, 0.0, 0.0),
        (3, 0.0, 130.0),
    ], "the merge brought edit's changes of the partitioned table"
    assert conn.execute("SELECT sum(gamma) FROM logs WHERE well = 3").fetchone() == (660.0,)
    assert conn.execute(
        "SELECT _geoid, basin FROM faults WHERE _geoid IN (%s, %s) ORDER BY 1", (ids["f1"], ids["new in edit"])
    ).fetchall() == [(ids["f1"], "Paris"), (ids["new in edit"], "after restore")]
    assert [
        p.name for p in tgsis.add_property(conn, "faults", ("crew", "text"), kind="feature").feature_properties
    ] == ["release", "basin", "crew"]
    conn.rollback()


@pytest.fixture
def extension_route(pg: TestServer) -> None:
    """CREATE EXTENSION must work on every server the suite runs against."""
    if pg.extension_files is not None:
        pytest.fail(pg.extension_files, pytrace=False)


def test_backup_of_an_extension_install(
    extension_route: None, pg: TestServer, make_database: Any, tmp_path: Path
) -> None:
    _check_backup("extension", pg, make_database, tmp_path)


def test_backup_of_a_plain_sql_install(pg: TestServer, make_database: Any, tmp_path: Path) -> None:
    _check_backup("sql", pg, make_database, tmp_path)


def test_create_extension_by_hand_is_completed_by_install(extension_route: None, make_database: Any) -> None:
    """The storage tables are no extension members: a bare CREATE EXTENSION leaves them to tgsis.install."""
    with psycopg.connect(make_database(), autocommit=True) as conn:
        conn.execute("CREATE EXTENSION tgsis CASCADE")
        assert conn.execute("SELECT to_regclass('tgsis.geometry')").fetchone() == (None,)
        assert tgsis.install(conn).action == "unchanged"
        members = conn.execute(
            "SELECT count(*) FROM pg_depend d JOIN pg_extension e ON e.oid = d.refobjid AND e.extname = 'tgsis' "
            "WHERE d.classid = 'pg_class'::regclass AND d.objid IN ('tgsis.geometry'::regclass, 'tgsis.vrtx'::regclass, "
            "'tgsis.geometry_geoid_seq'::regclass)"
        ).fetchone()
        assert members == (0,)
        config = conn.execute("SELECT array_length(extconfig, 1) FROM pg_extension WHERE extname = 'tgsis'").fetchone()
        assert config == (len(CATALOG) + 3,)
        assert conn.execute("SELECT count(*) FROM tgsis.geometry").fetchone() == (0,)


@pytest.mark.parametrize("route", ["extension", "sql"])
def test_nobody_else_can_replace_default_or_create_storage(route: str, pg: TestServer, make_database: Any) -> None:
    """The restore trigger turns an insert of DEFAULT into an update: only tgsis's owner may insert there."""
    if route == "extension" and pg.extension_files is not None:
        pytest.fail(pg.extension_files, pytrace=False)
    dsn = make_database()
    with psycopg.connect(dsn) as conn:
        tgsis.install(conn, method=route)  # type: ignore[arg-type]
        before = conn.execute("SELECT v::text FROM tgsis.versions v").fetchall()
    with login_roles(dsn, {"eve": "tgsis_admin"}) as roles:
        eve = roles.connect("eve")
        with pytest.raises(psycopg.errors.InsufficientPrivilege):
            eve.execute(
                "INSERT INTO tgsis.versions (versionid, name, workingrevision, workingset, owner) "
                "VALUES (0, 'DEFAULT', 99, '{99}', current_user)"
            )
        eve.rollback()
        with pytest.raises(psycopg.errors.InsufficientPrivilege):
            eve.execute("SELECT tgsis.create_storage()")
        eve.rollback()
    with psycopg.connect(dsn) as conn:
        assert conn.execute("SELECT v::text FROM tgsis.versions v").fetchall() == before
        assert conn.execute("SELECT tgsis.create_storage()").fetchone() == (False,)  # there already: nothing done
