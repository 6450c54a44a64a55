"""The test harness itself: isolation, and failing (never skipping) without a server."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path
from typing import Any

import psycopg
import pytest

from tests.local_helpers import child_env
from tgsis.testing import TestServer, start_test_server

BAD_DSN = "host=/nonexistent-socket-dir port=1 dbname=x connect_timeout=2"


def test_rolled_back_fixture_isolates_tests_part_1(tx: psycopg.Connection[Any]) -> None:
    tx.execute("CREATE TABLE public.leak_probe (x int)")
    with pytest.raises(psycopg.ProgrammingError):
        tx.commit()


def test_rolled_back_fixture_isolates_tests_part_2(tx: psycopg.Connection[Any]) -> None:
    assert tx.execute("SELECT to_regclass('public.leak_probe')").fetchone() == (None,)


def test_fresh_database_per_test_part_1(conn: psycopg.Connection[Any]) -> None:
    conn.execute("CREATE TABLE public.committed_probe (x int)")
    conn.commit()


def test_fresh_database_per_test_part_2(conn: psycopg.Connection[Any], pg: TestServer) -> None:
    assert conn.execute("SELECT to_regclass('public.committed_probe')").fetchone() == (None,)
    assert conn.execute("SELECT tgsis.version()").fetchone() is not None
    assert pg.server_version and pg.major >= 15


def test_a_database_is_dropped_with_the_sessions_a_test_left_open(pg: TestServer, template_db: str) -> None:
    with pg.database("tgsis_left_open", template_db) as (name, dsn):
        left = psycopg.connect(dsn)
        left.execute("SELECT 1")
        closed = psycopg.connect(dsn)
        closed.close()
    with psycopg.connect(pg.admin_dsn) as admin:
        assert admin.execute("SELECT count(*) FROM pg_database WHERE datname = %s", (name,)).fetchone() == (0,)
    with pytest.raises(psycopg.OperationalError):  # ended by the drop
        left.execute("SELECT 1")
    left.close()


def test_databases_are_still_made_after_a_test_ended_the_harness_session(pg: TestServer, template_db: str) -> None:
    # the harness keeps one connection to the maintenance database: a test may end it (or every session)
    with pg.database("tgsis_first", template_db):
        pass
    assert pg._admin is not None
    with psycopg.connect(pg.admin_dsn, autocommit=True) as admin:
        ended = admin.execute("SELECT pg_terminate_backend(%s)", (pg._admin.info.backend_pid,)).fetchone()
        assert ended == (True,)
    with pg.database("tgsis_after", template_db) as (_, dsn), psycopg.connect(dsn) as conn:
        assert conn.execute("SELECT tgsis.version()").fetchone() is not None


def test_unreachable_test_dsn_is_an_error_naming_it(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("TGSIS_TEST_DSN", BAD_DSN)
    with pytest.raises(RuntimeError, match="no PostgreSQL server for the tests") as info:
        start_test_server()
    assert "TGSIS_TEST_DSN: OperationalError" in str(info.value)
    assert "nonexistent-socket-dir" in str(info.value)


def test_a_run_without_server_fails_instead_of_skipping(tmp_path: Path) -> None:
    (tmp_path / "conftest.py").write_text('pytest_plugins = ["tgsis.testing"]\n')
    (tmp_path / "test_needs_db.py").write_text("def test_db(conn):\n    pass\n")
    result = subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", str(tmp_path)],
        env=child_env(TGSIS_TEST_DSN=BAD_DSN),
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert result.returncode == 1, result.stdout
    assert "1 error" in result.stdout and "skipped" not in result.stdout
    assert "no PostgreSQL server for the tests" in result.stdout
