"""Where tgsis.connect() goes: argument, TGSIS_DSN, libpq environment, local server."""

from __future__ import annotations

import pytest

import tgsis
from tests.local_helpers import private_home
from tgsis.db.connect import release_local_server, resolve_target
from tgsis.db.local import LocalServer, find_binaries


@pytest.fixture
def clean_env(monkeypatch: pytest.MonkeyPatch) -> pytest.MonkeyPatch:
    for name in ("TGSIS_DSN", "PGHOST", "PGHOSTADDR", "PGPORT", "PGDATABASE", "PGUSER", "PGSERVICE"):
        monkeypatch.delenv(name, raising=False)
    return monkeypatch


def test_target_order(clean_env: pytest.MonkeyPatch) -> None:
    assert resolve_target(None).source == "local server"
    clean_env.setenv("PGDATABASE", "geo")
    assert resolve_target(None) == tgsis.db.Target("", "libpq environment")
    clean_env.setenv("TGSIS_DSN", "dbname=fromenv")
    assert resolve_target(None) == tgsis.db.Target("dbname=fromenv", "TGSIS_DSN")
    assert resolve_target("dbname=given") == tgsis.db.Target("dbname=given", "argument")


def test_connect_with_a_dsn(db_dsn: str) -> None:
    with tgsis.connect(db_dsn) as conn:
        assert conn.execute("SELECT tgsis.version()").fetchone() == (tgsis.__version__,)
        assert not conn.autocommit


def test_connect_through_libpq_environment(db_dsn: str, clean_env: pytest.MonkeyPatch) -> None:
    from psycopg.conninfo import conninfo_to_dict

    params = conninfo_to_dict(db_dsn)
    for key, env in (
        ("host", "PGHOST"),
        ("port", "PGPORT"),
        ("user", "PGUSER"),
        ("dbname", "PGDATABASE"),
        ("password", "PGPASSWORD"),
    ):
        if params.get(key):
            clean_env.setenv(env, str(params[key]))
    with tgsis.connect() as conn:
        assert conn.info.dbname == params["dbname"]


@pytest.mark.own_server  # a server of TGSIS_PG's binaries, not the fixture pg's
def test_connect_without_dsn_starts_installs_and_releases_the_local_server(clean_env: pytest.MonkeyPatch) -> None:
    with private_home() as home:
        clean_env.setenv("TGSIS_HOME", str(home))
        try:
            with tgsis.connect(autocommit=True) as conn:
                assert conn.info.dbname == "tgsis"
                assert conn.execute("SELECT tgsis.version()").fetchone() == (tgsis.__version__,)
            server = LocalServer.persistent(find_binaries(), home=home)
            assert server.is_running(), "held until the process releases it"
        finally:
            release_local_server()
        assert not server.is_running()
