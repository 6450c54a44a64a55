"""Upgrades from every release: a database of each released version (sql/upgrade/releases.txt) updated to
this version equals a fresh install and keeps its data.

Each release is frozen in ``sql/upgrade/tgsis--X.sql`` (the built install
script of its commit); the upgrades between releases are frozen in
``sql/updates``, and the one from the last release is assembled from
``sql/upgrade/tgsis--LAST--THIS.sql`` and the current sources
(``tgsis.db._upgrade``). Both routes: ``ALTER EXTENSION tgsis UPDATE`` (the
server's extension files: the embedded PostgreSQL 18 reads this checkout's,
PostgreSQL 15 those of the private copy of its share folder the throwaway
cluster runs on, this checkout's too) and the plain-SQL upgrade of
``tgsis.install``.
"""

from __future__ import annotations

import re
import subprocess
import threading
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import psycopg
import pytest

import tgsis
from tests.catalog import describe_tgsis_objects
from tests.roles import login_roles
from tests.test_backup import _bindir_of
from tgsis.db import _upgrade
from tgsis.db.sqlsource import ExtensionSources
from tgsis.testing import TestServer

SQL_DIR = Path(__file__).resolve().parents[1] / "sql"
RELEASES = [
    line.split()[0]
    for line in (SQL_DIR / "upgrade" / "releases.txt").read_text(encoding="utf-8").splitlines()
    if line.strip() and not line.startswith("#")
]
OLD = RELEASES[-1]  # the last release: the upgrade in the making starts there
MakeDb = Callable[..., str]

# what a user of 0.1.0 did, in SQL both versions understand: a feature class,
# a surface, feature versioning, a version with its own change, a saved revision
_USE = """
SELECT tgsis.register_feature_class('horizon', 'SURFACE', '[{"name": "unit", "type": "text"}]',
                                    '[{"name": "depth", "type": "double precision"}]');
WITH g AS (SELECT tgsis.new_geometry('SURFACE', 'top', ARRAY[0, 0, 0, 1, 1, 0]::float8[], 3, 1) AS geoid),
     v AS (INSERT INTO tgsis.vrtx SELECT geoid, i, i % 2, i / 2, 0 FROM g, generate_series(0, 2) i),
     t AS (INSERT INTO tgsis.trgl SELECT geoid, 0, 0, 1, 2 FROM g),
     p AS (INSERT INTO public.horizon_cellpros SELECT geoid, i, 10 * i FROM g, generate_series(0, 2) i)
INSERT INTO public.horizon (_geoid, unit) SELECT geoid, 'Triassic' FROM g;
SELECT tgsis.enable_feature_versioning();
SELECT tgsis.create_version('survey2', 'DEFAULT', 'the second survey');
SELECT tgsis.goto_version('survey2', true);
UPDATE tgsis.vrtx SET z = -5 WHERE vrtxid = 2;
UPDATE public.horizon SET unit = 'Jurassic';
UPDATE public.horizon_cellpros SET depth = 25 WHERE _idx = 2;
SELECT tgsis.save_revision('survey2');
"""


# model 2's time tables are stored in chunks by default in a new database (chunkdefault), but an upgrade keeps an
# existing database's where they are, as rows (docs/storage.md, "The storage switch"): what a fresh install
# switches back to be compared with an upgraded database
_KEPT = ("times_trgl", "times_vrtx")
_KEPT_AS_ROWS = "SELECT tgsis.store_in_rows(t) FROM unnest(ARRAY['times_trgl', 'times_vrtx']) t"

# the objects noted as changed per revision and table (tgsis.revision_objects), new in 0.3.0
_NOTES = "SELECT DISTINCT revision, schemaname, tablename, objectkey FROM tgsis.revision_objects ORDER BY 1, 2, 3, 4"


def _objects(conn: psycopg.Connection[Any]) -> dict[str, list[tuple[str, ...]]]:
    """The tgsis catalog, the class's tables in public, and what belongs to the extension."""
    objects = describe_tgsis_objects(conn)
    objects.update(
        {
            f"public {kind}": rows
            for kind, rows in describe_tgsis_objects(conn, schema="public").items()
            if kind in ("relation", "column", "constraint", "index", "view", "trigger")
        }
    )
    objects["extension member"] = sorted(
        (str(r[0]),)
        for r in conn.execute(
            "SELECT pg_describe_object(classid, objid, objsubid) FROM pg_depend "
            "WHERE deptype = 'e' AND refobjid = (SELECT oid FROM pg_extension WHERE extname = 'tgsis')"
        ).fetchall()
    )
    return objects


def _differences(got: dict[str, list[tuple[str, ...]]], want: dict[str, list[tuple[str, ...]]]) -> list[str]:
    return [
        f"{kind}: only in the {where}: {row}"
        for kind in want
        for where, rows in (("first", set(got[kind]) - set(want[kind])), ("second", set(want[kind]) - set(got[kind])))
        for row in sorted(rows)
    ]


def _frozen(tmp_path: Path, version: str) -> ExtensionSources:
    """The sources of a released version, split back out of its frozen install script."""
    root = tmp_path / f"sql-{version}"
    root.mkdir()
    files = _upgrade.split_script((SQL_DIR / "upgrade" / f"tgsis--{version}.sql").read_text(encoding="utf-8"))
    for name, text in files.items():
        (root / name).parent.mkdir(parents=True, exist_ok=True)
        (root / name).write_text(text, encoding="utf-8")
    (root / "sources.txt").write_text("\n".join(files) + "\n", encoding="utf-8")
    control = (SQL_DIR / "tgsis.control").read_text(encoding="utf-8")
    control = re.sub(r"^default_version = '[^']*'", f"default_version = '{version}'", control, flags=re.MULTILINE)
    (root / "tgsis.control").write_text(control, encoding="utf-8")
    return ExtensionSources(root)


def _state(conn: psycopg.Connection[Any]) -> dict[str, list[tuple[Any, ...]]]:
    """The user's data and versions, as rows."""
    queries = {
        "versions": "SELECT * FROM tgsis.versions ORDER BY versionid",
        "revisions": "SELECT * FROM tgsis.revisions ORDER BY 1, 2",
        "catalog": "SELECT classname, schemaname, geotype, timemodel, featuretable FROM tgsis.catalog",
        "default vrtx": "SELECT geoid, vrtxid, x, y, z FROM tgsis.vrtx ORDER BY 1, 2",
        "default horizon": "SELECT _geoid, unit FROM public.horizon ORDER BY 1",
    }
    state = {name: conn.execute(q).fetchall() for name, q in queries.items()}
    conn.execute("SELECT tgsis.goto_version('survey2', true)")
    state["survey2 vrtx"] = conn.execute(queries["default vrtx"]).fetchall()
    state["survey2 horizon"] = conn.execute(queries["default horizon"]).fetchall()
    conn.execute("SELECT tgsis.goto_version('DEFAULT', true)")
    return state


def _upgrade_route(method: str, pg: TestServer) -> None:
    if method == "extension" and pg.extension_files is not None:
        pytest.fail(pg.extension_files, pytrace=False)


@pytest.mark.parametrize("old", RELEASES)
@pytest.mark.parametrize("method", ["extension", "sql"])
def test_upgraded_database_equals_a_fresh_install(
    method: str, old: str, pg: TestServer, make_database: MakeDb, tmp_path: Path
) -> None:
    _upgrade_route(method, pg)
    upgraded, fresh = make_database(), make_database()
    with psycopg.connect(upgraded) as conn:
        assert tgsis.install(conn, method=method, sources=_frozen(tmp_path, old)).version == old  # type: ignore[arg-type]
        assert conn.execute("SELECT tgsis.version()").fetchone() == (old,)
        conn.execute(_USE)
        conn.commit()
        before = _state(conn)
        conn.commit()
        if method == "extension":
            conn.execute("ALTER EXTENSION tgsis UPDATE")  # what a DBA runs in psql: the script alone is enough
        else:
            assert tgsis.install(conn).action == "upgraded"
        conn.commit()
        assert conn.execute("SELECT tgsis.version()").fetchone() == (tgsis.__version__,)
        assert tgsis.installed_version(conn) == tgsis.InstalledVersion(tgsis.__version__, method)  # type: ignore[arg-type]
        assert tgsis.install(conn).action == "unchanged"
        assert _state(conn) == before, f"the data and versions of {old} are kept"
        fingerprint = conn.execute(
            "SELECT fingerprint FROM tgsis.installation WHERE version = %s", (tgsis.__version__,)
        ).fetchone()
        assert fingerprint == (ExtensionSources.default().fingerprint,), "the upgrade records the build it gives"
        got = _objects(conn)
        got_notes = conn.execute(_NOTES).fetchall()
    with psycopg.connect(fresh) as conn:
        tgsis.install(conn, method=method)  # type: ignore[arg-type]
        # an upgraded database keeps its time tables as rows (docs/storage.md): a fresh one keeping them so too
        conn.execute(_KEPT_AS_ROWS)
        # and keeps its classes where they are, as rows: a fresh one registers them under tgsis.storage = rows
        conn.execute("SET tgsis.storage = rows")
        conn.execute(_USE)
        conn.execute("RESET tgsis.storage")
        conn.commit()
        want = _objects(conn)
        want_notes = conn.execute(_NOTES).fetchall()
    assert got_notes == want_notes and want_notes, "the upgrade notes what the writes of a fresh install note"
    assert got["function"] and got["relation"] and got["public relation"], "the comparison must see the objects"
    differences = [
        f"{kind}: only in the {where}: {row}"
        for kind in want
        for where, rows in (
            ("upgraded database", set(got[kind]) - set(want[kind])),
            ("fresh install", set(want[kind]) - set(got[kind])),
        )
        for row in sorted(rows)
    ]
    assert differences == [], "\n".join(differences)
    assert got == want


@pytest.mark.parametrize("old", RELEASES)
@pytest.mark.parametrize("method", ["extension", "sql"])
def test_data_of_a_release_is_readable_and_writable_after_the_upgrade(
    method: str, old: str, pg: TestServer, make_database: MakeDb, tmp_path: Path
) -> None:
    _upgrade_route(method, pg)
    with psycopg.connect(make_database()) as conn:
        tgsis.install(conn, method=method, sources=_frozen(tmp_path, old))  # type: ignore[arg-type]
        conn.execute(_USE)
        conn.commit()
        tgsis.install(conn)
        conn.commit()
        (geoid,) = conn.execute("SELECT _geoid FROM public.horizon").fetchone()  # type: ignore[misc]
        stored = tgsis.fetch_feature(conn, "horizon", geoid)
        assert isinstance(stored.mesh, tgsis.Surface)
        assert stored.mesh.vertices.tolist() == [[0, 0, 0], [1, 0, 0], [0, 1, 0]]
        assert stored.properties["unit"] == "Triassic"
        with tgsis.in_version(conn, "survey2"):
            changed = tgsis.fetch_feature(conn, "horizon", geoid)
        assert isinstance(changed.mesh, tgsis.Surface)
        assert changed.mesh.vertices[2].tolist() == [0, 1, -5] and changed.properties["unit"] == "Jurassic"
        # written after: a new feature in the version, a change saved, the old revision still there
        mesh = tgsis.Surface(
            np.array([[0, 0, 1], [2, 0, 1], [0, 2, 1]], float),
            np.array([[0, 1, 2]]),
            vertex_properties={"depth": [1.0, 2.0, 3.0]},
        )
        with tgsis.in_version(conn, "survey2"):
            new = tgsis.insert_feature(conn, "horizon", mesh, properties={"unit": "Cretaceous"})
        conn.commit()
        assert conn.execute("SELECT tgsis.save_revision('survey2')").fetchone()[0] > 0  # type: ignore[index]
        with tgsis.in_version(conn, "survey2"):
            assert tgsis.fetch_feature(conn, "horizon", new).properties["unit"] == "Cretaceous"
        assert conn.execute("SELECT count(*) FROM public.horizon").fetchone() == (1,), "DEFAULT does not see it"
        # the models new in 0.2.0 work in the upgraded database
        assert conn.execute("SELECT count(*) FROM tgsis.data_models").fetchone() == (6,)
        with tgsis.in_version(conn, "survey2"):
            tgsis.create_model(conn, "resource", [geoid, new])
            assert sorted(o.id for o in tgsis.model_objects(conn, "resource")) == sorted([geoid, new])
        conn.commit()
        # the changes made under the old version were noted by the upgrade (tgsis.revision_objects): the merge copies them
        tgsis.merge_version(conn, "survey2")
        merged = tgsis.fetch_feature(conn, "horizon", geoid)
        assert isinstance(merged.mesh, tgsis.Surface)
        assert merged.mesh.vertices[2].tolist() == [0, 1, -5] and merged.properties["unit"] == "Jurassic"
        assert tgsis.fetch_feature(conn, "horizon", new).properties["unit"] == "Cretaceous"


def test_every_changed_file_is_in_the_upgrade() -> None:
    """A changed or new source file that re-running cannot apply (a table, rows) is dealt with by hand."""
    upgrade = ExtensionSources.default().upgrade(OLD)
    assert upgrade.unhandled == [], (
        f"changed since {OLD} and not replaceable: include them (-- @include FILE) or write their ALTERs and mark them "
        f"(-- @handled FILE) in sql/upgrade/tgsis--{OLD}--{tgsis.__version__}.sql (docs/developing.md, 'An upgrade script')"
    )


def test_shape_changes_are_dropped_before_the_new_definitions() -> None:
    old = {
        "a.sql": "CREATE FUNCTION tgsis.f(p_x int) RETURNS int LANGUAGE sql AS $$ SELECT 1 $$;\n"
        "CREATE FUNCTION tgsis.g(p_x int DEFAULT 1) RETURNS int LANGUAGE sql AS $$ SELECT 1 $$;\n"
        "CREATE FUNCTION tgsis.gone() RETURNS int LANGUAGE sql AS $$ SELECT 1; $$;\n"
        "CREATE VIEW tgsis.v AS SELECT 1 AS a;\n",
        "t.sql": "CREATE TABLE tgsis.t (a int);\n",
    }
    new = {
        "a.sql": "CREATE FUNCTION tgsis.f(p_x int) RETURNS int LANGUAGE sql AS $$ SELECT 2 $$;\n"
        "CREATE FUNCTION tgsis.g(p_x int DEFAULT 1, p_y text = 'a;b') RETURNS bigint\n"
        "LANGUAGE sql AS $$ SELECT 1 $$;\n"
        "CREATE VIEW tgsis.v AS SELECT 1 AS a, 2 AS b;\n"
        "COMMENT ON VIEW tgsis.v IS 'x';\n",
        "t.sql": "CREATE TABLE tgsis.t (a int, b int);\n",
    }
    upgrade = _upgrade.Upgrade(old, new, "-- @sources\n")
    drops = [line for line in upgrade.generated().splitlines() if line.startswith("DROP")]
    assert drops == [
        "DROP VIEW IF EXISTS tgsis.v;",
        "DROP FUNCTION IF EXISTS tgsis.g(p_x int);",
        "DROP FUNCTION IF EXISTS tgsis.gone();",
    ]
    assert "CREATE OR REPLACE FUNCTION tgsis.f(p_x int)" in upgrade.generated()
    assert upgrade.unhandled == ["t.sql"]
    assert "NOT HANDLED" in upgrade.script("--")
    handled = _upgrade.Upgrade(old, new, "ALTER TABLE tgsis.t ADD b int;\n-- @handled t.sql\n")
    assert handled.unhandled == []


def test_a_moved_file_is_the_same_file_under_its_new_name() -> None:
    """`-- @moved OLD NEW` says a source file of the old version moved: its tables and rows are compared
    with the new file's, and the directives may name it by either name; a moved file whose tables
    changed is still unhandled."""
    old = {"a/t.sql": "CREATE TABLE tgsis.t (a int);\n", "a/u.sql": "CREATE TABLE tgsis.u (a int);\n"}
    new = {"b/t.sql": "CREATE TABLE tgsis.t (a int);\n", "b/u.sql": "CREATE TABLE tgsis.u (a int, b int);\n"}
    assert _upgrade.Upgrade(old, new, "").unhandled == ["b/t.sql", "b/u.sql", "a/t.sql", "a/u.sql"]
    moved = "-- @moved a/t.sql b/t.sql\n-- @moved a/u.sql b/u.sql\n"
    assert _upgrade.Upgrade(old, new, moved).unhandled == ["b/u.sql"]
    assert _upgrade.Upgrade(old, new, moved + "ALTER TABLE tgsis.u ADD b int;\n-- @handled a/u.sql\n").unhandled == []
    included = _upgrade.Upgrade(old, new, moved + "-- @include a/u.sql\n")
    assert included.unhandled == []
    assert "-- ==== b/u.sql (included) ====\nCREATE TABLE tgsis.u (a int, b int);" in included.script("--")
    with pytest.raises(ValueError, match="moved twice"):
        _ = _upgrade.Upgrade(old, new, moved + "-- @moved a/t.sql c/t.sql\n").unhandled


def test_only_new_grants_and_those_of_dropped_objects_run_again() -> None:
    grants = "GRANT SELECT ON tgsis.t TO tgsis_reader;\nREVOKE ALL ON FUNCTION tgsis.g(int) FROM PUBLIC;\n"
    old = {"a.sql": "CREATE FUNCTION tgsis.g(p_x int) RETURNS int LANGUAGE sql AS $$ SELECT 1 $$;\n" + grants}
    new = {
        "a.sql": "CREATE FUNCTION tgsis.g(p_x int) RETURNS bigint LANGUAGE sql AS $$ SELECT 1 $$;\n"
        + grants
        + "GRANT SELECT ON tgsis.u TO tgsis_reader;\n"
    }
    generated = _upgrade.Upgrade(old, new, "").generated()
    assert "DROP FUNCTION IF EXISTS tgsis.g(p_x int);" in generated
    assert "REVOKE ALL ON FUNCTION tgsis.g(int) FROM PUBLIC" in generated, "g was dropped: its rights are made again"
    assert "GRANT SELECT ON tgsis.u TO tgsis_reader" in generated, "a new grant"
    assert "GRANT SELECT ON tgsis.t TO tgsis_reader" not in generated, "unchanged: its ACL is kept as it is"


def _old_database(method: str, pg: TestServer, make_database: MakeDb, tmp_path: Path) -> str:
    _upgrade_route(method, pg)
    dsn = make_database()
    with psycopg.connect(dsn) as conn:
        tgsis.install(conn, method=method, sources=_frozen(tmp_path, OLD))  # type: ignore[arg-type]
        conn.execute(_USE)
    return dsn


@pytest.mark.parametrize("method", ["extension", "sql"])
def test_an_editor_cannot_upgrade_and_nothing_changes(
    method: str, pg: TestServer, make_database: MakeDb, tmp_path: Path
) -> None:
    dsn = _old_database(method, pg, make_database, tmp_path)
    with psycopg.connect(dsn) as conn:
        before = _objects(conn)
    with login_roles(dsn, {"eve": "tgsis_editor"}) as roles, roles.connect("eve") as eve:
        if method == "extension":
            # (PostgreSQL runs the script as eve, who may not create in schema tgsis)
            with pytest.raises(psycopg.errors.InsufficientPrivilege):
                eve.execute("ALTER EXTENSION tgsis UPDATE")
        else:
            # (the first statement of the upgrade that needs the owner's rights says which: a table, the schema)
            with pytest.raises(
                tgsis.MissingPrivilegeError, match="permission denied for schema tgsis|must be owner of"
            ):
                tgsis.install(eve)
        eve.rollback()
    with psycopg.connect(dsn) as conn:
        assert conn.execute("SELECT tgsis.version()").fetchone() == (OLD,)
        assert _objects(conn) == before


def test_two_sessions_upgrading_at_once_upgrade_once(pg: TestServer, make_database: MakeDb, tmp_path: Path) -> None:
    dsn = _old_database("sql", pg, make_database, tmp_path)
    results: list[str] = []
    errors: list[BaseException] = []
    barrier = threading.Barrier(2)

    def worker() -> None:
        try:
            with psycopg.connect(dsn) as conn:
                barrier.wait()
                results.append(tgsis.install(conn).action)
        except BaseException as exc:  # noqa: BLE001 - reported below
            errors.append(exc)

    threads = [threading.Thread(target=worker) for _ in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not errors
    assert sorted(results) == ["unchanged", "upgraded"]
    with psycopg.connect(dsn) as conn:
        rows = conn.execute("SELECT version FROM tgsis.installation ORDER BY version").fetchall()
        assert rows == [(OLD,), (tgsis.__version__,)]


def test_an_upgraded_database_dumps_and_restores_whole(pg: TestServer, make_database: MakeDb, tmp_path: Path) -> None:
    """The storage tables the upgrade made are no extension members: pg_dump keeps them and their rows."""
    dsn = _old_database("extension", pg, make_database, tmp_path)
    with psycopg.connect(dsn) as conn:
        # a DBA's own grants on tgsis objects: the upgrade must not make them "initial" (pg_dump would drop them)
        conn.execute("GRANT EXECUTE ON FUNCTION tgsis.version() TO tgsis_nobody")
        conn.execute("GRANT SELECT ON tgsis.catalog TO tgsis_nobody")
        conn.commit()
        conn.execute("ALTER EXTENSION tgsis UPDATE")
        conn.commit()
        with tgsis.in_version(conn, "survey2"):
            tgsis.create_model(conn, "resource", [1])
        conn.commit()
        want = _objects(conn), _state(conn)
    bindir = _bindir_of(pg)
    dump = tmp_path / "upgraded.dump"
    done = subprocess.run(
        [str(bindir / "pg_dump"), "--format=custom", f"--file={dump}", dsn], capture_output=True, text=True, check=False
    )
    assert done.returncode == 0, done.stderr
    restored = make_database()
    done = subprocess.run(
        [str(bindir / "pg_restore"), "--exit-on-error", "-d", restored, str(dump)],
        capture_output=True,
        text=True,
        check=False,
    )
    assert done.returncode == 0, done.stderr
    with psycopg.connect(restored) as conn:
        got = _objects(conn)
        assert _differences(got, want[0]) == [], "\n".join(_differences(got, want[0]))
        assert _state(conn) == want[1]
        with tgsis.in_version(conn, "survey2"):
            assert [o.id for o in tgsis.model_objects(conn, "resource")] == [1]


def test_a_function_beside_a_table_flows_and_a_changed_trigger_is_flagged() -> None:
    old = {
        "r.sql": "CREATE FUNCTION tgsis.trg() RETURNS trigger LANGUAGE plpgsql AS $$ BEGIN RETURN NEW; END $$;\n"
        "CREATE TRIGGER t BEFORE INSERT ON tgsis.x FOR EACH ROW EXECUTE FUNCTION tgsis.trg();\n"
    }
    body_only = {"r.sql": old["r.sql"].replace("RETURN NEW;", "RETURN NULL;")}
    upgrade = _upgrade.Upgrade(old, body_only, "")
    assert upgrade.unhandled == []
    assert "CREATE OR REPLACE FUNCTION tgsis.trg()" in upgrade.generated() and "RETURN NULL" in upgrade.generated()
    assert "CREATE TRIGGER" not in upgrade.generated()
    trigger = {"r.sql": old["r.sql"].replace("BEFORE INSERT", "BEFORE INSERT OR UPDATE")}
    assert _upgrade.Upgrade(old, trigger, "").unhandled == ["r.sql"]


def test_rows_upserts_the_shipped_rows(conn: psycopg.Connection[Any]) -> None:
    conn.execute("CREATE TABLE public.codes (code text PRIMARY KEY, name text, note text)")
    conn.execute("INSERT INTO public.codes VALUES ('A', 'old a', 'x'), ('B', 'b', 'y')")
    new = {
        "c.sql": "CREATE TABLE public.codes (code text PRIMARY KEY, name text, note text);\n"
        "INSERT INTO public.codes (code, name, note) VALUES ('A', 'a', 'x'), ('C', 'c; new', 'z');\n"
    }
    script = _upgrade.Upgrade({}, new, "-- @rows c.sql\n").script("--")
    conn.execute(script.split("-- ---- generated")[0])
    assert conn.execute("SELECT * FROM public.codes ORDER BY code").fetchall() == [
        ("A", "a", "x"),
        ("B", "b", "y"),
        ("C", "c; new", "z"),
    ]
    with pytest.raises(ValueError, match="@rows takes INSERT INTO table"):
        _upgrade.Upgrade({}, {"d.sql": "INSERT INTO t VALUES (1);\n"}, "-- @rows d.sql\n").script("--")


def test_the_frozen_upgrade_between_releases_gives_the_later_release(
    pg: TestServer, make_database: MakeDb, tmp_path: Path
) -> None:
    """sql/updates/tgsis--0.1.0--0.2.0.sql (frozen) makes a 0.1.0 database what a fresh 0.2.0 is."""
    _upgrade_route("extension", pg)
    upgraded, fresh = make_database(), make_database()
    with psycopg.connect(upgraded) as conn:
        tgsis.install(conn, method="extension", sources=_frozen(tmp_path, "0.1.0"))
        conn.execute(_USE)
        conn.execute("ALTER EXTENSION tgsis UPDATE TO '0.2.0'")
        conn.commit()
        assert conn.execute("SELECT tgsis.version()").fetchone() == ("0.2.0",)
        got = _objects(conn)
    with psycopg.connect(fresh) as conn:
        tgsis.install(conn, method="extension", sources=_frozen(tmp_path, "0.2.0"))
        conn.execute(_USE)
        conn.commit()
        want = _objects(conn)
    assert _differences(got, want) == [], "\n".join(_differences(got, want))


@pytest.mark.parametrize("method", ["extension", "sql"])
def test_a_database_of_the_released_0_2_0_is_upgraded_by_db_install_then_import_and_checkout_work(
    method: str, pg: TestServer, make_database: MakeDb, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Issue 36, point 10: `tgsis db install` said "nothing to do" to a database of 0.2.0, and import and checkout
    then failed. The release's own install script made the database here."""
    from tgsis.cli import main

    _upgrade_route(method, pg)
    dsn = make_database()
    with psycopg.connect(dsn) as conn:
        tgsis.install(conn, method=method, sources=_frozen(tmp_path, "0.2.0"))  # type: ignore[arg-type]
        conn.execute(_USE)
    off = tmp_path / "tri.off"
    off.write_text("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", encoding="utf-8")
    # before the upgrade, a command that works on features says what to run instead of failing on the way
    assert main(["--dsn", dsn, "import", str(off), "--class", "horizon"]) == 1
    err = capsys.readouterr().err
    assert f"database {psycopg.conninfo.conninfo_to_dict(dsn)['dbname']} has tgsis 0.2.0" in err
    assert f"run `tgsis db install` (0.2.0 -> {tgsis.__version__})" in err
    assert main(["--dsn", dsn, "db", "status"]) == 1, "status says the database needs the upgrade"
    status = capsys.readouterr().out
    assert "tgsis:    0.2.0" in status and f"client:   {tgsis.__version__}" in status
    assert f"upgrade: run `tgsis db install` (0.2.0 -> {tgsis.__version__})" in status
    assert main(["--dsn", dsn, "db", "install"]) == 0
    out = capsys.readouterr().out
    assert f"upgraded tgsis 0.2.0 -> {tgsis.__version__} ({method})" in out and "nothing to do" not in out
    assert main(["--dsn", dsn, "db", "status"]) == 0
    assert "up to date" in capsys.readouterr().out
    assert main(["--dsn", dsn, "class", "create", "faults", "--geotype", "SURFACE"]) == 0
    assert main(["--dsn", dsn, "import", str(off), "--class", "faults"]) == 0
    fid = capsys.readouterr().out.splitlines()[-1].split("\t")[0]
    checked_out = tmp_path / "out.off"
    assert main(["--dsn", dsn, "checkout", fid, str(checked_out)]) == 0, capsys.readouterr().err
    assert checked_out.read_text(encoding="utf-8").split()[:4] == ["OFF", "3", "1", "0"]


@pytest.mark.parametrize("method", ["extension", "sql"])
def test_a_users_view_over_the_old_period_type_stops_the_upgrade_and_survives(
    method: str, pg: TestServer, make_database: MakeDb, tmp_path: Path
) -> None:
    """0.3.0 makes tgsis.timerange a domain (the old range type and the functions over it are dropped and made
    again). A user's view built on one of those functions must not be dropped with them without a word: the
    upgrade stops with PostgreSQL's error naming the view, and the view and the release stay as they were."""
    _upgrade_route(method, pg)
    dsn = _old_database(method, pg, make_database, tmp_path)
    with psycopg.connect(dsn, autocommit=True) as conn:
        conn.execute("CREATE VIEW public.my_periods AS SELECT p.times, p.period FROM tgsis.instant_periods(1) p")
        before = _objects(conn)
    with psycopg.connect(dsn) as conn:
        with pytest.raises((psycopg.Error, tgsis.Error), match="my_periods"):
            if method == "extension":
                conn.execute("ALTER EXTENSION tgsis UPDATE")
            else:
                tgsis.install(conn)
        conn.rollback()
    with psycopg.connect(dsn) as conn:
        assert conn.execute("SELECT tgsis.version()").fetchone() == (OLD,)
        assert conn.execute("SELECT to_regclass('public.my_periods') IS NOT NULL").fetchone() == (True,)
        assert _objects(conn) == before


# ------------------------------------------------------------------ issue 40: the upgrade stores model 1 in chunks

_CHUNKED = ("vrtx", "point", "segment", "tetra", "trgl")  # model 1's tables registered for chunks

# more history than _USE: a third version from survey2 with its own saved change, a point set and a vertex deleted
_MORE = """
SELECT tgsis.create_version('survey3', 'survey2', 'the third survey');
SELECT tgsis.goto_version('survey3', true);
WITH g AS (SELECT tgsis.new_geometry('MULTIPOINT', 'wells', ARRAY[0, 0, 0, 1, 1, 0]::float8[], 3, 1) AS geoid),
     v AS (INSERT INTO tgsis.vrtx SELECT geoid, i, 10 + i, 20 + i, 30 + i FROM g, generate_series(0, 1) i)
INSERT INTO tgsis.point SELECT geoid, i, i FROM g, generate_series(0, 1) i;
UPDATE tgsis.vrtx SET x = 0.5, y = -0.0 WHERE vrtxid = 1 AND z = 0;
SELECT tgsis.save_revision('survey3');
SELECT tgsis.goto_version('DEFAULT', true);
"""


def _every_set(conn: psycopg.Connection[Any]) -> dict[str, list[tuple[Any, ...]]]:
    """What each version and each revision sees of model 1's tables (rows, doubles as their text bits)."""
    reads = {
        "vrtx": "SELECT geoid, vrtxid, float8send(x), float8send(y), float8send(z) FROM tgsis.vrtx ORDER BY 1, 2",
        "point": "SELECT geoid, pointid, vrtxid1 FROM tgsis.point ORDER BY 1, 2",
        "trgl": "SELECT geoid, trglid, vrtxid1, vrtxid2, vrtxid3 FROM tgsis.trgl ORDER BY 1, 2",
    }
    seen: dict[str, list[tuple[Any, ...]]] = {}
    for (name,) in conn.execute("SELECT name FROM tgsis.versions ORDER BY versionid").fetchall():
        conn.execute("SELECT tgsis.goto_version(%s, true)", (name,))
        seen.update({f"{name} {t}": conn.execute(q).fetchall() for t, q in reads.items()})
    for revision, name in conn.execute(
        "SELECT r.revision, v.name FROM tgsis.revisions r JOIN tgsis.versions v USING (versionid)"
        " WHERE r.saved_at IS NOT NULL ORDER BY 1"
    ).fetchall():
        conn.execute("SELECT tgsis.goto_version(%s, true)", (name,))
        conn.execute("SELECT set_config('tgsis.revision', %s, false)", (str(revision),))
        seen.update({f"revision {revision} {t}": conn.execute(q).fetchall() for t, q in reads.items()})
        conn.execute("RESET tgsis.revision")
    conn.execute("SELECT tgsis.goto_version('DEFAULT', true)")
    return seen


def _chunked(conn: psycopg.Connection[Any]) -> dict[str, bool]:
    return {t: conn.execute("SELECT tgsis.stored_in_chunks(%s)", (t,)).fetchone() == (True,) for t in _CHUNKED}


def _upgrade_now(conn: psycopg.Connection[Any], method: str, storage: str | None = None) -> list[str]:
    """Upgrade as a DBA would (ALTER EXTENSION in psql, or tgsis.install); the WARNINGs it gave."""
    warnings: list[str] = []
    conn.add_notice_handler(
        lambda d: (
            warnings.append(f"{d.message_primary} | {d.message_detail} | {d.message_hint}")
            if d.severity_nonlocalized == "WARNING"
            else None
        )
    )
    if method == "extension":
        if storage is not None:
            conn.execute("SELECT set_config('tgsis.storage', %s, false)", (storage,))
        conn.execute("ALTER EXTENSION tgsis UPDATE")
    else:
        assert tgsis.install(conn, storage=storage or "chunks").action == "upgraded"  # type: ignore[arg-type]
    conn.commit()
    return warnings


@pytest.mark.parametrize("method", ["extension", "sql"])
def test_the_upgrade_stores_model_1_in_chunks_and_every_version_and_revision_sees_the_same(
    method: str, pg: TestServer, make_database: MakeDb, tmp_path: Path
) -> None:
    dsn = _old_database(method, pg, make_database, tmp_path)
    with psycopg.connect(dsn) as conn:
        conn.execute(_MORE)
        conn.commit()
        before = _every_set(conn)
        conn.commit()
        assert before["survey3 point"] and before["survey3 vrtx"] != before["survey2 vrtx"] != before["DEFAULT vrtx"]
        assert len([k for k in before if k.startswith("revision")]) >= 6, "saved revisions are compared too"
        assert _upgrade_now(conn, method) == []
        assert _chunked(conn) == dict.fromkeys(_CHUNKED, True)
        assert conn.execute("SELECT to_regclass('tgsis.vrtx_ver'), to_regclass('tgsis.trgl_ver')").fetchone() == (
            None,
            None,
        )
        assert _every_set(conn) == before
        # the classes of 0.2.0 stay where they were, as rows; a class registered now is made in chunks, as in a
        # new database (docs/storage.md, "Property chunks by default: the rule")
        assert conn.execute("SELECT tgsis.stored_in_chunks('public', 'horizon_cellpros')").fetchone() == (False,)
        conn.execute("""SELECT tgsis.register_feature_class('later', 'SURFACE', '[]', '[["depth", "real"]]')""")
        assert conn.execute("SELECT tgsis.stored_in_chunks('public', 'later_cellpros')").fetchone() == (True,)
        # and it goes on working: a change saved in survey3, DEFAULT unchanged
        conn.execute("SELECT tgsis.goto_version('survey3', true)")
        conn.execute("UPDATE tgsis.vrtx SET z = 7 WHERE vrtxid = 0 AND x = 10")
        conn.execute("SELECT tgsis.save_revision('survey3 after the upgrade')")
        conn.execute("SELECT tgsis.goto_version('DEFAULT', true)")
        conn.commit()
        after = _every_set(conn)
        assert after["DEFAULT vrtx"] == before["DEFAULT vrtx"] and after["survey3 vrtx"] != before["survey3 vrtx"]


@pytest.mark.parametrize("method", ["extension", "sql"])
def test_the_upgrade_with_storage_rows_keeps_rows(
    method: str, pg: TestServer, make_database: MakeDb, tmp_path: Path
) -> None:
    dsn = _old_database(method, pg, make_database, tmp_path)
    with psycopg.connect(dsn) as conn:
        before = _every_set(conn)
        conn.commit()
        assert _upgrade_now(conn, method, storage="rows") == []
        assert _chunked(conn) == dict.fromkeys(_CHUNKED, False)
        assert conn.execute("SELECT to_regclass('tgsis.vrtx_ver') IS NOT NULL").fetchone() == (True,)
        assert _every_set(conn) == before


@pytest.mark.parametrize("method", ["extension", "sql"])
def test_a_table_that_cannot_switch_stays_rows_with_a_warning_and_the_upgrade_goes_on(
    method: str, pg: TestServer, make_database: MakeDb, tmp_path: Path
) -> None:
    """A user's view over tgsis.point (PostgreSQL would have to drop it) and a tgsis.segment partitioned by hand:
    both stay rows, each named in a WARNING with why and how to switch later; the others are switched."""
    dsn = _old_database(method, pg, make_database, tmp_path)
    with psycopg.connect(dsn) as conn:
        conn.execute(_MORE)
        conn.execute("CREATE VIEW public.my_wells AS SELECT geoid, pointid FROM tgsis.point")
        # (enable_feature_versioning made tgsis.segment a view of segment_ver: its storage is partitioned here)
        storage = conn.execute("SELECT to_regclass('tgsis.segment_ver') IS NOT NULL").fetchone()
        assert storage == (True,)
        conn.execute(
            "ALTER TABLE tgsis.segment_ver RENAME TO segment_ver_plain;"
            "CREATE TABLE tgsis.segment_ver (LIKE tgsis.segment_ver_plain INCLUDING ALL) PARTITION BY HASH (geoid);"
            "CREATE TABLE tgsis.segment_ver_p0 PARTITION OF tgsis.segment_ver FOR VALUES WITH (MODULUS 1, REMAINDER 0);"
        )
        conn.commit()
        before = _every_set(conn)
        conn.commit()
        warnings = _upgrade_now(conn, method)
        assert _chunked(conn) == {"vrtx": True, "point": False, "segment": False, "tetra": True, "trgl": True}
        assert len(warnings) == 2, warnings
        point, segment = sorted(warnings)
        assert (
            point.startswith("tgsis.point stays stored as rows: cannot drop")
            and "view public.my_wells depends on" in point
        )
        assert "SELECT tgsis.store_in_chunks('point')" in point
        assert segment.startswith("tgsis.segment stays stored as rows: ") and "partitioned" in segment
        assert "SELECT tgsis.store_in_chunks('segment')" in segment
        assert _every_set(conn) == before
        conn.execute("SELECT tgsis.goto_version('survey3', true)")
        assert conn.execute("SELECT count(*) FROM public.my_wells").fetchone() == (2,), "the user's view works on"
        conn.execute("SELECT tgsis.goto_version('DEFAULT', true)")
        # once the view is gone, the switch named in the hint works
        conn.execute("DROP VIEW public.my_wells")
        conn.execute("SELECT tgsis.store_in_chunks('point')")
        conn.commit()
        assert _chunked(conn)["point"] and _every_set(conn) == before


# ------------------------------------------------------------------ model 2's time tables: new installs only

# a surface known at two instants in the 0.2.0 database, in SQL both versions understand; -0.0 and a subnormal
_INSTANTS = """
SELECT tgsis.register_feature_class('layer', 'SURFACE', p_time_model => 'INSTANTS');
WITH g AS (SELECT tgsis.new_geometry('SURFACE', 'moving', ARRAY[0, 0, 0, 1, 1, 1]::float8[], 3, 1,
                                     p_timemodel => 'INSTANTS') AS geoid),
     t AS (INSERT INTO tgsis.times SELECT geoid, ts FROM g, unnest(ARRAY[0.0, 2.5]) ts),
     v AS (INSERT INTO tgsis.times_vrtx SELECT geoid, ts, i, i % 2, -0.0, ts * 4.9e-324 FROM g,
                 unnest(ARRAY[0.0, 2.5]) ts, generate_series(0, 2) i),
     c AS (INSERT INTO tgsis.times_trgl SELECT geoid, ts, 0, 0, 1, 2 FROM g, unnest(ARRAY[0.0, 2.5]) ts)
INSERT INTO public.layer (_geoid) SELECT geoid FROM g;
"""
_INSTANT_READS = (
    "SELECT geoid, times, vrtxid, float8send(x), float8send(y), float8send(z) FROM tgsis.times_vrtx ORDER BY 1, 2, 3",
    "SELECT geoid, times, trglid, vrtxid1, vrtxid2, vrtxid3 FROM tgsis.times_trgl ORDER BY 1, 2, 3",
)


@pytest.mark.parametrize("method", ["extension", "sql"])
def test_the_upgrade_keeps_model_2s_time_tables_as_rows_and_a_new_install_stores_them_in_chunks(
    method: str, pg: TestServer, make_database: MakeDb, tmp_path: Path
) -> None:
    """Only new installs get chunks for times_vrtx / times_trgl; an upgraded database keeps its rows, says so,
    reads and writes them as before, and moves them when asked (tgsis.store_in_chunks), bit for bit."""
    _upgrade_route(method, pg)
    with psycopg.connect(make_database()) as conn:
        tgsis.install(conn, method=method, sources=_frozen(tmp_path, OLD))  # type: ignore[arg-type]
        conn.execute(_INSTANTS)
        conn.commit()
        before = [conn.execute(q).fetchall() for q in _INSTANT_READS]
        assert len(before[0]) == 6 and len(before[1]) == 2
        conn.commit()
        if method == "extension":
            conn.execute("ALTER EXTENSION tgsis UPDATE")
            steps: list[str] = []
        else:
            result = tgsis.install(conn)
            assert result.action == "upgraded"
            steps = list(result.steps)
        conn.commit()
        registry = conn.execute(
            "SELECT tablename, chunkdefault, tgsis.stored_in_chunks(tablename) FROM tgsis.model_tables"
            " WHERE model = 2 AND chunkcolumn IS NOT NULL ORDER BY 1"
        ).fetchall()
        assert registry == [(t, True, False) for t in _KEPT], "registered as a fresh install, kept as rows"
        assert conn.execute("SELECT to_regclass('tgsis.times_vrtx_chunk')").fetchone() == (None,)
        assert _chunked(conn) == dict.fromkeys(_CHUNKED, True), "model 1 is moved all the same"
        if method == "sql":
            assert any(
                s.startswith("kept as rows: times_trgl, times_vrtx (an upgrade moves model 1 only") for s in steps
            )
            assert not any("the upgrade's warnings say why" in s for s in steps), steps
        assert [conn.execute(q).fetchall() for q in _INSTANT_READS] == before
        # written after the upgrade, on rows; then moved when asked, every bit kept
        conn.execute("UPDATE tgsis.times_vrtx SET z = 7 WHERE vrtxid = 1 AND times = 2.5")
        conn.commit()
        after = [conn.execute(q).fetchall() for q in _INSTANT_READS]
        assert after != before
        conn.execute("SELECT tgsis.store_in_chunks(t) FROM unnest(ARRAY['times_vrtx', 'times_trgl']) t")
        conn.commit()
        assert conn.execute(
            "SELECT bool_and(tgsis.stored_in_chunks(t)) FROM unnest(ARRAY['times_vrtx', 'times_trgl']) t"
        ).fetchone() == (True,)
        assert [conn.execute(q).fetchall() for q in _INSTANT_READS] == after
    with psycopg.connect(make_database()) as conn:
        tgsis.install(conn, method=method)  # type: ignore[arg-type]
        conn.commit()
        assert conn.execute(
            "SELECT array_agg(tablename ORDER BY tablename) FROM tgsis.model_tables"
            " WHERE model = 2 AND tgsis.stored_in_chunks(tablename)"
        ).fetchone() == (list(_KEPT),), "a new install stores model 2's time tables in chunks"


_MD_NAN = """
SELECT tgsis.create_storage();
WITH g AS (SELECT tgsis.new_geometry('GMAP', 'nan', NULL, 3, 0, p_timemodel => 'MULTIDIM') AS geoid),
     m AS (INSERT INTO tgsis.md_gmap (geoid, dimension, embedding, axes) SELECT geoid, 0, 2, '{x,k}' FROM g)
INSERT INTO tgsis.md_vertex SELECT geoid, i, c FROM g,
       (VALUES (0, '{0,0}'::double precision[]), (1, '{NaN,5}'), (2, '{-1,0.5}')) AS p (i, c);
SELECT tgsis.refresh_geometry(geoid) FROM tgsis.md_gmap;
"""


@pytest.mark.parametrize("method", ["extension", "sql"])
def test_the_upgrade_measures_again_the_model_5_extents_0_2_0_measured_with_a_nan(
    method: str, pg: TestServer, make_database: MakeDb, tmp_path: Path
) -> None:
    """0.2.0's md_extent counted a NaN as the largest value; the upgrade recomputes those boxes without NaN points."""
    _upgrade_route(method, pg)
    with psycopg.connect(make_database()) as conn:
        tgsis.install(conn, method=method, sources=_frozen(tmp_path, OLD))  # type: ignore[arg-type]
        conn.execute(_MD_NAN)
        boxes = "SELECT m.extent::text, g.bbox::text FROM tgsis.md_gmap m JOIN tgsis.geometry g USING (geoid)"
        assert conn.execute(boxes).fetchall() == [("(-1, 0),(NaN, 5)", "(-1, 0, 0),(NaN, 5, 0)")]
        conn.commit()
        assert _upgrade_now(conn, method) == []
        assert conn.execute(boxes).fetchall() == [("(-1, 0),(0, 0.5)", "(-1, 0, 0),(0, 0.5, 0)")]
        geoid = conn.execute("SELECT geoid FROM tgsis.md_gmap").fetchone()
        assert geoid is not None
        assert [r[0] for r in conn.execute("SELECT problem FROM tgsis.check_geometry(%s)", geoid)] == [
            "point without 2 finite coordinates"
        ]


@pytest.mark.parametrize("method", ["extension", "sql"])
def test_the_upgrade_leaves_versioned_model_5_extents_measured_with_a_nan_and_warns(
    method: str, pg: TestServer, make_database: MakeDb, tmp_path: Path
) -> None:
    """Where model 5 is versioned, each version holds its own boxes: the upgrade rewrites none, a WARNING names
    the geoids and how to refresh them; every row of the G-map is as before, and the refresh the hint names
    then measures the box without the NaN point."""
    _upgrade_route(method, pg)
    with psycopg.connect(make_database()) as conn:
        tgsis.install(conn, method=method, sources=_frozen(tmp_path, OLD))  # type: ignore[arg-type]
        conn.execute(_MD_NAN)
        conn.execute("SELECT tgsis.enable_feature_versioning()")
        conn.commit()
        reads = (
            "SELECT m.geoid, m.extent::text, g.bbox::text FROM tgsis.md_gmap m JOIN tgsis.geometry g USING (geoid)",
            "SELECT geoid, vrtxid, array_send(coordinate) FROM tgsis.md_vertex ORDER BY 1, 2",
            "SELECT geoid, extent::text, revision, revclosed FROM tgsis.md_gmap_ver ORDER BY 1, 3",
            "SELECT geoid, bbox::text, revision, revclosed FROM tgsis.geometry_ver ORDER BY 1, 3",
        )
        before = [conn.execute(q).fetchall() for q in reads]
        ((geoid, extent, bbox),) = before[0]
        assert (extent, bbox) == ("(-1, 0),(NaN, 5)", "(-1, 0, 0),(NaN, 5, 0)")
        conn.commit()
        warnings = _upgrade_now(conn, method)
        assert len(warnings) == 1, warnings
        message, detail, hint = warnings[0].split(" | ")
        assert message == "the extents of 1 multiply indexed G-maps hold a NaN, as measured before 0.3.0"
        assert detail == f"geoids {geoid}; they are versioned and were left as they are."
        assert "tgsis.refresh_geometry" in hint
        assert [conn.execute(q).fetchall() for q in reads] == before
        conn.commit()
        # the refresh the hint names, in the version holding them: measured without the NaN point
        conn.execute("SELECT tgsis.refresh_geometry(%s)", (geoid,))
        assert conn.execute(reads[0]).fetchall() == [(geoid, "(-1, 0),(0, 0.5)", "(-1, 0, 0),(0, 0.5, 0)")]
