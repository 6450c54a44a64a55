"""What an install leaves and says (issue 36, points 10 and 12).

* A bare ``CREATE EXTENSION tgsis`` has no storage tables (``tgsis.create_storage()`` makes them:
  storage/create_storage.sql says why): every entry point that needs them refuses with TG001 and the
  statement to run, ``tgsis db status`` reports them missing, ``tgsis db install`` creates them and
  says so.
* ``tgsis db install`` says what it did; a non-superuser owner becomes a member of ``tgsis_admin``
  when it may grant that to itself, else the install names the ``GRANT`` a DBA must run.
* Within one version, a database built from other sources (another fingerprint) is refused by
  name, with what to do.
"""

from __future__ import annotations

import shutil
from collections.abc import Callable
from pathlib import Path
from typing import Any

import psycopg
import pytest
from psycopg.conninfo import make_conninfo

import tgsis
from tests.catalog import describe_tgsis_objects
from tgsis.cli import main
from tgsis.db.sqlsource import ExtensionSources
from tgsis.testing import TestServer

SQL_DIR = Path(__file__).resolve().parents[1] / "sql"
MakeDb = Callable[..., str]

# every SQL entry point that needs the storage, called as a psql user would after a bare CREATE EXTENSION
ENTRY_POINTS = [
    "SELECT tgsis.register_feature_class('horizon', 'SURFACE')",
    "SELECT tgsis.new_geometry('SURFACE', 'top', ARRAY[0, 0, 0, 1, 1, 0]::float8[], 3, 1)",
    "SELECT tgsis.create_model('resource', ARRAY[1]::bigint[])",
    "SELECT tgsis.add_to_model('resource', ARRAY[1]::bigint[])",
    "SELECT tgsis.remove_from_model('resource', ARRAY[1]::bigint[])",
    "SELECT * FROM tgsis.model_objects('resource')",
    "SELECT tgsis.enable_feature_versioning()",
    "SELECT tgsis.delete_geometry(1)",
    "SELECT tgsis.partition_model_storage(1::smallint, 4)",
]


@pytest.fixture
def bare(pg: TestServer, make_database: MakeDb) -> str:
    """A database where only `CREATE EXTENSION tgsis CASCADE` ran (what a DBA does in psql)."""
    if pg.extension_files is not None:
        pytest.fail(pg.extension_files, pytrace=False)
    dsn = make_database()
    with psycopg.connect(dsn, autocommit=True) as conn:
        conn.execute("CREATE EXTENSION tgsis CASCADE")
        assert conn.execute("SELECT to_regclass('tgsis.geometry')").fetchone() == (None,)
    return dsn


@pytest.mark.parametrize("statement", ENTRY_POINTS)
def test_every_entry_point_of_a_bare_create_extension_says_what_to_run(bare: str, statement: str) -> None:
    with psycopg.connect(bare, autocommit=True) as conn:
        before = describe_tgsis_objects(conn)
        with pytest.raises(psycopg.Error) as info:
            conn.execute(statement)
        assert info.value.sqlstate == "TG001", f"{statement}: {info.value}"
        assert "storage tables do not exist" in (info.value.diag.message_primary or "")
        assert "SELECT tgsis.create_storage();" in (info.value.diag.message_hint or "")
        assert "tgsis db install" in (info.value.diag.message_hint or "")
        assert describe_tgsis_objects(conn) == before


def test_the_python_api_on_a_bare_create_extension_says_what_to_run(bare: str) -> None:
    with psycopg.connect(bare) as conn:
        with pytest.raises(tgsis.InstallationError, match="storage tables do not exist") as info:
            tgsis.create_feature_class(conn, "horizon", "SURFACE")
        assert info.value.sqlstate == "TG001" and "SELECT tgsis.create_storage();" in (info.value.hint or "")
        conn.rollback()
        # a raw missing tgsis table (a COPY straight into storage) names the command that adds it
        with pytest.raises(tgsis.InstallationError, match='relation "tgsis.vrtx" does not exist') as raw:
            with tgsis.errors.reraise():
                conn.execute("SELECT count(*) FROM tgsis.vrtx")
        assert "tgsis db install" in (raw.value.hint or "") and "tgsis db status" in (raw.value.hint or "")


def test_db_status_reports_missing_storage_and_db_install_creates_it(
    bare: str, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["--dsn", bare, "db", "status"]) == 1
    out = capsys.readouterr().out
    assert "storage:  missing " in out and "tgsis.geometry" in out and "tgsis.vrtx" in out
    assert "state:    storage missing" in out and "SELECT tgsis.create_storage();" in out
    assert main(["--dsn", bare, "db", "status", "--json"]) == 1
    import json

    status = json.loads(capsys.readouterr().out)
    assert status["state"] == "storage missing" and "tgsis.geometry" in status["missing_storage"]
    assert main(["--dsn", bare, "db", "install"]) == 0
    out = capsys.readouterr().out
    assert f"tgsis {tgsis.__version__} is already installed (extension)" in out
    assert "created the storage tables the extension was created without (SELECT tgsis.create_storage())" in out
    assert "nothing to do" not in out
    assert main(["--dsn", bare, "db", "status"]) == 0
    assert "state:    up to date" in capsys.readouterr().out
    assert main(["--dsn", bare, "db", "install"]) == 0
    assert "nothing to do" in capsys.readouterr().out
    with psycopg.connect(bare) as conn:
        conn.execute("SELECT tgsis.register_feature_class('horizon', 'SURFACE')")


def test_db_install_says_what_it_did(pg: TestServer, make_database: MakeDb, capsys: pytest.CaptureFixture[str]) -> None:
    if pg.extension_files is not None:
        pytest.fail(pg.extension_files, pytrace=False)
    dsn = make_database()
    assert main(["--dsn", dsn, "db", "install", "--method", "extension"]) == 0
    # (the roles are created by the first install on the cluster: whichever test that is)
    assert [line for line in capsys.readouterr().out.splitlines() if not line.startswith("  created the roles ")] == [
        f"installed tgsis {tgsis.__version__} (extension)",
        "  created the extension(s) tgsis needs: cube",
        f"  created the extension tgsis {tgsis.__version__} (CREATE EXTENSION tgsis VERSION '{tgsis.__version__}' CASCADE)",
        "  created the storage tables (SELECT tgsis.create_storage())",
        "  stored in chunks: vrtx, point, segment, tetra, trgl, times_trgl, times_vrtx (docs/storage.md)",  # the default
    ]


def _same_version_other_sources(tmp_path: Path) -> ExtensionSources:
    """This version's sources with one comment changed: another build of the same version."""
    root = tmp_path / "sql-other-build"
    shutil.copytree(SQL_DIR, root, ignore=shutil.ignore_patterns("build"))
    version = root / "core" / "version.sql"
    version.write_text(version.read_text(encoding="utf-8") + "\n-- a commit later\n", encoding="utf-8")
    return ExtensionSources(root)


@pytest.mark.parametrize("method", ["sql", "extension"])
def test_another_build_of_this_version_is_refused_by_name(
    method: str, pg: TestServer, make_database: MakeDb, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    other = _same_version_other_sources(tmp_path)
    mine = ExtensionSources.default()
    assert other.version == mine.version and other.fingerprint != mine.fingerprint
    dsn = make_database()
    with psycopg.connect(dsn) as conn:
        tgsis.install(conn, method="sql", sources=other)
        if method == "extension":
            # a database made by CREATE EXTENSION at an earlier commit: its record says which build
            conn.execute("UPDATE tgsis.installation SET fingerprint = NULL")
        conn.commit()
        before = describe_tgsis_objects(conn)
        with pytest.raises(tgsis.InstallationError) as info:
            tgsis.install(conn)
        message, hint = str(info.value), info.value.hint or ""
        assert f"has tgsis {mine.version} built from other SQL sources than this client's {mine.version}" in message
        assert f"client: fingerprint {mine.fingerprint}" in message
        recorded = "none recorded" if method == "extension" else other.fingerprint
        assert f"database: fingerprint {recorded}" in message
        assert "no upgrade between two of its builds" in hint and "tgsis db install" in hint
        assert info.value.sqlstate == "TG001"
        assert describe_tgsis_objects(conn) == before
        status = tgsis.installation_status(conn)
        assert status.state == "other build" and not status.ok and status.fix == hint
    assert main(["--dsn", dsn, "db", "status"]) == 1
    out = capsys.readouterr().out
    assert "state:    other build" in out and mine.fingerprint in out
    assert main(["--dsn", dsn, "db", "install"]) == 1
    assert "built from other SQL sources" in capsys.readouterr().err


def test_installation_status_of_an_up_to_date_database(conn: psycopg.Connection[Any]) -> None:
    status = tgsis.installation_status(conn)
    assert status.ok and status.state == "up to date" and status.problem is None and status.fix is None
    assert status.installed is not None and status.installed.fingerprint == ExtensionSources.default().fingerprint
    assert status.missing_storage == ()


def test_a_role_that_may_not_read_the_installation_record_is_not_told_of_another_build(
    conn: psycopg.Connection[Any],
) -> None:
    """Only tgsis_reader's members may read tgsis.installation: for another role the fingerprint is unknown,
    which is no mismatch (it was reported as "other build", exit 1)."""
    conn.execute("CREATE ROLE nobody_in_particular")
    conn.execute("GRANT USAGE ON SCHEMA tgsis TO nobody_in_particular")
    conn.execute("SET ROLE nobody_in_particular")
    status = tgsis.installation_status(conn)
    assert status.installed is not None and status.installed.fingerprint is None
    assert status.state != "other build" and status.ok, status


@pytest.mark.own_server  # a server of TGSIS_PG's binaries, not the fixture pg's
def test_a_non_superuser_owner_is_made_admin_or_told_the_grant() -> None:
    """The owner registers classes and versions features, which tgsis allows tgsis_admin's members: an install
    by a role that may grant it to itself does; one that may not names the GRANT a DBA must run."""
    from tgsis.db.local import LocalServer

    server = LocalServer.throwaway(in_memory=True)  # a cluster of its own: roles are cluster-wide
    try:
        with psycopg.connect(server.dsn(), autocommit=True) as admin:
            admin.execute("CREATE ROLE alice LOGIN CREATEROLE")
            admin.execute("CREATE DATABASE geo OWNER alice")
            admin.execute("CREATE ROLE bob LOGIN")
            admin.execute("CREATE DATABASE geo2 OWNER bob")
        alice = make_conninfo(server.dsn(), user="alice", dbname="geo")
        with psycopg.connect(alice) as conn:
            result = tgsis.install(conn, method="sql")
            conn.commit()
            assert "created the roles tgsis_reader, tgsis_editor, tgsis_admin, tgsis_nobody" in result.steps
            # (PostgreSQL 16 and later make the creator of a role its member WITH ADMIN OPTION: no grant to make)
            member_by_creation = conn.execute("SELECT current_setting('server_version_num')::int >= 160000").fetchone()
            assert member_by_creation == (True,) or result.steps[-1].startswith("granted tgsis_admin to alice")
            assert result.still_needed == ()
            conn.execute("SELECT tgsis.register_feature_class('horizon', 'SURFACE')")
            conn.commit()
        with psycopg.connect(server.dsn(), autocommit=True) as admin:
            admin.execute("GRANT tgsis_nobody TO bob")  # what the roles' hint asks a DBA for, without the admin grant
        bob = make_conninfo(server.dsn(), user="bob", dbname="geo2")
        with psycopg.connect(bob) as conn:
            result = tgsis.install(conn, method="sql")
            conn.commit()
            assert result.action == "installed" and result.still_needed == ("GRANT tgsis_admin TO bob;",)
            with pytest.raises(tgsis.MissingPrivilegeError):
                tgsis.create_feature_class(conn, "horizon", "SURFACE")
            conn.rollback()
        import io
        from contextlib import redirect_stdout

        printed = io.StringIO()
        with redirect_stdout(printed):
            assert main(["--dsn", bob, "db", "install"]) == 0
        assert "still needed: a DBA runs `GRANT tgsis_admin TO bob;`" in printed.getvalue()
        with psycopg.connect(server.dsn(), autocommit=True) as admin:
            admin.execute("GRANT tgsis_admin TO bob")
        with psycopg.connect(bob) as conn:
            assert tgsis.install(conn).still_needed == ()
            tgsis.create_feature_class(conn, "horizon", "SURFACE")
    finally:
        server.destroy()
