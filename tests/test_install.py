"""Both install routes (CREATE EXTENSION and the client's plain SQL), upgrades, uninstall."""

from __future__ import annotations

import shutil
import threading
from collections.abc import Callable
from pathlib import Path
from typing import Any

import psycopg
import pytest

import tgsis
from tests.catalog import describe_tgsis_objects
from tgsis.db.sqlsource import ExtensionSources
from tgsis.testing import TestServer

SQL_DIR = Path(__file__).resolve().parents[1] / "sql"
MakeDb = Callable[..., str]


@pytest.fixture
def extension_route(pg: TestServer) -> None:
    """CREATE EXTENSION must work on every server the suite runs against."""
    if pg.extension_files is not None:
        pytest.fail(pg.extension_files, pytrace=False)


def _objects(dsn: str) -> dict[str, list[tuple[str, ...]]]:
    with psycopg.connect(dsn) as conn:
        return describe_tgsis_objects(conn)


def test_create_extension(extension_route: None, make_database: MakeDb) -> None:
    dsn = make_database()
    with psycopg.connect(dsn, autocommit=True) as conn:
        conn.execute("CREATE EXTENSION tgsis CASCADE")  # CASCADE: cube
        assert conn.execute("SELECT tgsis.version()").fetchone() == (tgsis.__version__,)
        ext = conn.execute(
            "SELECT extversion, extrelocatable, extnamespace::regnamespace::text "
            "FROM pg_extension WHERE extname = 'tgsis'"
        ).fetchone()
        assert ext == (tgsis.__version__, False, "tgsis")
        assert tgsis.installed_version(conn) == tgsis.InstalledVersion(tgsis.__version__, "extension")
        assert conn.execute("SELECT method FROM tgsis.installation").fetchall() == [("extension",)]


def test_plain_sql_install(make_database: MakeDb) -> None:
    dsn = make_database()
    with psycopg.connect(dsn) as conn:
        result = tgsis.install(conn, method="sql")
        assert result == tgsis.InstallResult("installed", "sql", tgsis.__version__)
        assert conn.execute("SELECT tgsis.version()").fetchone() == (tgsis.__version__,)
        assert conn.execute("SELECT count(*) FROM pg_extension WHERE extname = 'tgsis'").fetchone() == (0,)
        assert tgsis.installed_version(conn) == tgsis.InstalledVersion(tgsis.__version__, "sql")


def test_both_routes_make_the_same_objects(extension_route: None, make_database: MakeDb) -> None:
    by_extension, by_sql = make_database(), make_database()
    with psycopg.connect(by_extension) as conn:
        assert tgsis.install(conn, method="extension").method == "extension"
    with psycopg.connect(by_sql) as conn:
        assert tgsis.install(conn, method="sql").method == "sql"
    ext_objects, sql_objects = _objects(by_extension), _objects(by_sql)
    assert ext_objects["function"], "the comparison must see the objects"
    assert ext_objects["relation"]
    assert ext_objects == sql_objects


def test_auto_prefers_the_extension_when_its_files_are_there(extension_route: None, make_database: MakeDb) -> None:
    with psycopg.connect(make_database()) as conn:
        assert tgsis.install(conn).method == "extension"


@pytest.mark.parametrize("method", ["extension", "sql"])
def test_second_install_is_a_no_op(method: str, pg: TestServer, make_database: MakeDb) -> None:
    if method == "extension" and pg.extension_files is not None:
        pytest.fail(pg.extension_files, pytrace=False)
    with psycopg.connect(make_database()) as conn:
        tgsis.install(conn, method=method)  # type: ignore[arg-type]
        before = describe_tgsis_objects(conn)
        again = tgsis.install(conn, method="auto")
        assert again == tgsis.InstallResult("unchanged", method, tgsis.__version__, tgsis.__version__)  # type: ignore[arg-type]
        assert describe_tgsis_objects(conn) == before
        assert conn.execute("SELECT count(*) FROM tgsis.installation").fetchone() == (1,)


def test_concurrent_installs_install_once(make_database: MakeDb) -> None:
    dsn = make_database()
    results: list[tgsis.InstallResult] = []
    errors: list[BaseException] = []
    barrier = threading.Barrier(4)

    def worker() -> None:
        try:
            with psycopg.connect(dsn) as conn:
                barrier.wait()
                results.append(tgsis.install(conn, method="sql"))
        except BaseException as exc:  # noqa: BLE001 - reported below
            errors.append(exc)

    threads = [threading.Thread(target=worker) for _ in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not errors
    assert sorted(r.action for r in results) == ["installed", "unchanged", "unchanged", "unchanged"]


def test_install_inside_an_open_transaction_is_rolled_back_with_it(make_database: MakeDb) -> None:
    dsn = make_database()
    with psycopg.connect(dsn) as conn:
        conn.execute("SELECT 1")  # opens a transaction: install uses a savepoint
        tgsis.install(conn, method="sql")
        conn.rollback()
        assert tgsis.installed_version(conn) is None


def test_unknown_method_is_refused(make_database: MakeDb) -> None:
    with psycopg.connect(make_database()) as conn:
        with pytest.raises(tgsis.InstallationError, match="unknown install method 'fast'"):
            tgsis.install(conn, method="fast")  # type: ignore[arg-type]
        assert tgsis.installed_version(conn) is None


def test_a_foreign_tgsis_schema_is_refused(make_database: MakeDb) -> None:
    with psycopg.connect(make_database()) as conn:
        conn.execute("CREATE SCHEMA tgsis; CREATE TABLE tgsis.mine (x int)")
        conn.commit()
        with pytest.raises(tgsis.InstallationError, match="schema tgsis exists but holds no tgsis installation"):
            tgsis.install(conn)
        assert conn.execute("SELECT count(*) FROM pg_class WHERE relnamespace = 'tgsis'::regnamespace").fetchone() == (
            1,
        )


def _sources_at(tmp_path: Path, version: str, *, updates: dict[str, str] | None = None) -> ExtensionSources:
    """A copy of the SQL sources that says it is ``version``, with extra upgrade scripts."""
    root = tmp_path / f"sql-{version}"
    shutil.copytree(SQL_DIR, root, ignore=shutil.ignore_patterns("build"))
    control = root / "tgsis.control"
    control.write_text(control.read_text().replace(f"'{tgsis.__version__}'", f"'{version}'"))
    (root / "updates").mkdir(exist_ok=True)
    for name, text in (updates or {}).items():
        (root / "updates" / name).write_text(text)
    return ExtensionSources(root)


def _upgrade_script(old: str, new: str, extra: str = "", fingerprint: str = "") -> str:
    return f"""\\echo Use "CREATE EXTENSION tgsis" to load this file. \\quit
CREATE TABLE tgsis.added_in_upgrade (id int PRIMARY KEY);
CREATE OR REPLACE FUNCTION tgsis.version() RETURNS text LANGUAGE sql IMMUTABLE PARALLEL SAFE
AS $$ SELECT '{new}'::text $$;
{extra}
INSERT INTO tgsis.installation (version, method, fingerprint) VALUES ('{new}', 'sql', '{fingerprint}');
"""


def test_plain_sql_upgrade_applies_the_update_chain(tmp_path: Path, make_database: MakeDb) -> None:
    old = _sources_at(tmp_path, "0.0.9")
    new = _sources_at(tmp_path, "0.1.1")
    # (an upgrade script records the fingerprint of the version it leads to, as the assembled ones do)
    new = _sources_at(
        tmp_path / "new",
        "0.1.1",
        updates={"tgsis--0.0.9--0.1.1.sql": _upgrade_script("0.0.9", "0.1.1", fingerprint=new.fingerprint)},
    )
    with psycopg.connect(make_database()) as conn:
        tgsis.install(conn, method="sql", sources=old)
        result = tgsis.install(conn, sources=new)
        assert result == tgsis.InstallResult("upgraded", "sql", "0.1.1", "0.0.9")
        assert conn.execute("SELECT tgsis.version()").fetchone() == ("0.1.1",)
        assert conn.execute("SELECT to_regclass('tgsis.added_in_upgrade') IS NOT NULL").fetchone() == (True,)
        assert tgsis.installed_version(conn) == tgsis.InstalledVersion("0.1.1", "sql")
        assert tgsis.install(conn, sources=new).action == "unchanged"


def test_failed_upgrade_leaves_the_database_as_it_was(tmp_path: Path, make_database: MakeDb) -> None:
    old = _sources_at(tmp_path, "0.0.9")
    broken = _upgrade_script("0.0.9", "0.1.1", extra="SELECT 1/0;")
    new = _sources_at(tmp_path, "0.1.1", updates={"tgsis--0.0.9--0.1.1.sql": broken})
    with psycopg.connect(make_database()) as conn:
        tgsis.install(conn, method="sql", sources=old)
        before = describe_tgsis_objects(conn)
        with pytest.raises(tgsis.DatabaseError, match="division by zero"):
            tgsis.install(conn, sources=new)
        assert describe_tgsis_objects(conn) == before
        assert tgsis.installed_version(conn) == tgsis.InstalledVersion("0.0.9", "sql")


def test_no_upgrade_path_changes_nothing(tmp_path: Path, make_database: MakeDb) -> None:
    old = _sources_at(tmp_path, "0.0.9")
    new = _sources_at(tmp_path, "0.1.1")
    with psycopg.connect(make_database()) as conn:
        tgsis.install(conn, method="sql", sources=old)
        with pytest.raises(tgsis.InstallationError, match="no upgrade path from tgsis 0.0.9 to 0.1.1"):
            tgsis.install(conn, sources=new)
        assert tgsis.installed_version(conn) == tgsis.InstalledVersion("0.0.9", "sql")


def test_a_database_newer_than_the_client_is_refused(tmp_path: Path, make_database: MakeDb) -> None:
    newer = _sources_at(tmp_path, "9.0.0")
    with psycopg.connect(make_database()) as conn:
        tgsis.install(conn, method="sql", sources=newer)
        with pytest.raises(tgsis.InstallationError, match="newer than this client") as info:
            tgsis.install(conn)
        assert info.value.sqlstate == "TG001"
        assert "this client is older than the database: upgrade the client" in (info.value.hint or "")


def test_extension_method_without_files_is_refused(tmp_path: Path, make_database: MakeDb) -> None:
    unreleased = _sources_at(tmp_path, "7.7.7")
    with psycopg.connect(make_database()) as conn:
        with pytest.raises(tgsis.InstallationError, match="no extension files for tgsis 7.7.7") as info:
            tgsis.install(conn, method="extension", sources=unreleased)
        assert "make -C sql install" in (info.value.hint or "")
        assert tgsis.installed_version(conn) is None


@pytest.mark.parametrize("method", ["extension", "sql"])
def test_uninstall_then_install_again(method: str, pg: TestServer, make_database: MakeDb) -> None:
    if method == "extension" and pg.extension_files is not None:
        pytest.fail(pg.extension_files, pytrace=False)
    with psycopg.connect(make_database()) as conn:
        tgsis.install(conn, method=method)  # type: ignore[arg-type]
        removed = tgsis.uninstall(conn)
        assert removed == tgsis.InstalledVersion(tgsis.__version__, method)  # type: ignore[arg-type]
        assert conn.execute("SELECT to_regnamespace('tgsis')").fetchone() == (None,)
        assert tgsis.uninstall(conn) is None
        assert tgsis.install(conn, method=method).action == "installed"  # type: ignore[arg-type]


def test_uninstall_refuses_dependent_objects_without_cascade(make_database: MakeDb) -> None:
    with psycopg.connect(make_database()) as conn:
        tgsis.install(conn, method="sql")
        conn.execute("CREATE VIEW public.codes AS SELECT sqlstate FROM tgsis.error_codes")
        conn.execute("CREATE TABLE public.log (code char(5) REFERENCES tgsis.error_codes, note text)")
        conn.commit()
        before = describe_tgsis_objects(conn)
        with pytest.raises(tgsis.InUseError, match="would also drop 2 object") as info:
            tgsis.uninstall(conn)
        assert "view codes" in (info.value.detail or "")
        assert "constraint log_code_fkey on table log" in (info.value.detail or "")
        assert describe_tgsis_objects(conn) == before
        assert conn.execute("SELECT to_regclass('public.codes') IS NOT NULL").fetchone() == (True,)
        tgsis.uninstall(conn, cascade=True)
        assert conn.execute("SELECT to_regclass('public.codes')").fetchone() == (None,)
        assert conn.execute("SELECT count(*) FROM public.log").fetchone() == (0,), "the table itself stays"


def test_roles_form_a_hierarchy(conn: psycopg.Connection[Any]) -> None:
    def member(role: str, group: str) -> bool:
        row = conn.execute("SELECT pg_has_role(%s, %s, 'MEMBER')", (role, group)).fetchone()
        return bool(row and row[0])

    assert member("tgsis_admin", "tgsis_editor") and member("tgsis_editor", "tgsis_reader")
    assert member("tgsis_admin", "tgsis_reader")
    assert not member("tgsis_reader", "tgsis_editor")
    rows = conn.execute("SELECT rolname FROM pg_roles WHERE rolname LIKE 'tgsis\\_%' AND rolcanlogin").fetchall()
    assert rows == []


def test_reader_role_can_read_the_core_catalog(conn: psycopg.Connection[Any]) -> None:
    conn.execute("SET ROLE tgsis_reader")
    assert conn.execute("SELECT tgsis.version()").fetchone() == (tgsis.__version__,)
    assert conn.execute("SELECT count(*) > 0 FROM tgsis.error_codes").fetchone() == (True,)
    with pytest.raises(psycopg.errors.InsufficientPrivilege):
        conn.execute("INSERT INTO tgsis.error_codes VALUES ('TG999', 'x', 'core', 'x')")


@pytest.mark.own_server  # a server of TGSIS_PG's binaries, not the fixture pg's
def test_a_role_without_createrole_is_told_what_the_dba_must_run() -> None:
    """Managed PostgreSQL: the tgsis roles do not exist and the installer may not create roles."""
    from psycopg.conninfo import make_conninfo

    from tgsis.db.local import LocalServer

    server = LocalServer.throwaway(in_memory=True)  # a cluster of its own: roles are cluster-wide
    try:
        with psycopg.connect(server.dsn(), autocommit=True) as admin:
            admin.execute("CREATE ROLE alice LOGIN")
            admin.execute("CREATE DATABASE geo OWNER alice")
        alice = make_conninfo(server.dsn(), user="alice", dbname="geo")
        for method in ("sql", "auto"):
            with psycopg.connect(alice) as conn:
                with pytest.raises(tgsis.MissingPrivilegeError, match="role alice may not create roles") as info:
                    tgsis.install(conn, method=method)
                hint = info.value.hint or ""
                assert "CREATE ROLE tgsis_reader NOLOGIN;" in hint and "GRANT tgsis_editor TO tgsis_admin;" in hint
                assert "GRANT tgsis_admin TO alice;" in hint, "the owner registers classes: tgsis_admin"
                assert "CREATE ROLE tgsis_nobody NOLOGIN NOINHERIT; GRANT tgsis_nobody TO alice;" in hint
                assert tgsis.installed_version(conn) is None
        with psycopg.connect(server.dsn(), autocommit=True) as admin:
            admin.execute(info.value.hint.removeprefix("Ask a DBA to run once: "))  # type: ignore[union-attr]
        with psycopg.connect(alice) as conn:
            assert tgsis.install(conn, method="sql").action == "installed"
            owner = conn.execute("SELECT nspowner::regrole::text FROM pg_namespace WHERE nspname = 'tgsis'").fetchone()
            assert owner == ("alice",)
            conn.execute("SELECT tgsis.register_feature_class('horizon', 'SURFACE')")  # no grant left to make by hand
    finally:
        server.destroy()
