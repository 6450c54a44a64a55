"""``make installcheck``: the pg_regress tests of sql/test run against the session's server.

What a DBA or packager runs after ``make install`` (docs/install.md): the
server's own pg_regress, through the server's own PGXS, on the installed
extension files. Here against the suite's server, on both PostgreSQL 15 and the
embedded 18, whose throwaway clusters both read this checkout's files (15: a
private copy of its share folder, ``tgsis.db.local.with_private_share``).
"""

from __future__ import annotations

import os
import shutil
import subprocess
from pathlib import Path

import psycopg
import pytest
from psycopg.conninfo import conninfo_to_dict

from tgsis.testing import TestServer

SQL_DIR = Path(__file__).resolve().parents[1] / "sql"


def _pg_config(pg: TestServer) -> str:
    if pg.local is not None:
        return str(pg.local.binaries.tool("pg_config"))
    found = shutil.which("pg_config")
    if found is None:
        pytest.fail(
            "no pg_config for the server of TGSIS_TEST_DSN on PATH: make installcheck needs its PGXS", pytrace=False
        )
    return found


def _installcheck(
    pg: TestServer, dbname: str, *, inputdir: str = "test", outputdir: Path, regress: str | None = None
) -> subprocess.CompletedProcess[str]:
    """``make -C sql installcheck`` against the session's server, in database ``dbname`` (dropped after)."""
    params = conninfo_to_dict(pg.admin_dsn)
    env = dict(
        os.environ,
        PGHOST=str(params.get("host", "")),
        PGPORT=str(params.get("port", "5432")),
        PGUSER=str(params.get("user", "postgres")),
    )
    if params.get("password"):
        env["PGPASSWORD"] = str(params["password"])
    args = [
        "make",
        "--no-print-directory",
        "-C",
        str(SQL_DIR),
        "installcheck",
        f"PG_CONFIG={_pg_config(pg)}",
        f"REGRESS_OPTS=--inputdir={inputdir} --outputdir={outputdir} --dbname={dbname}",
    ]
    if regress is not None:
        args.append(f"REGRESS={regress}")
    try:
        return subprocess.run(args, env=env, capture_output=True, text=True, timeout=600, check=False)
    finally:
        with psycopg.connect(pg.admin_dsn, autocommit=True) as conn:
            conn.execute(f'DROP DATABASE IF EXISTS "{dbname}"')


def test_make_installcheck_passes(pg: TestServer, tmp_path: Path) -> None:
    if pg.extension_files is not None:
        pytest.fail(pg.extension_files, pytrace=False)
    result = _installcheck(pg, f"tgsis_installcheck_{os.getpid()}", outputdir=tmp_path)
    diffs = tmp_path / "regression.diffs"
    assert result.returncode == 0, result.stdout + result.stderr + (diffs.read_text() if diffs.exists() else "")
    for name in ("install", "features", "versioning", "upgrade"):
        assert (tmp_path / "results" / f"{name}.out").is_file(), f"{name} did not run"


def test_a_wrong_expectation_fails_installcheck(pg: TestServer, tmp_path: Path) -> None:
    """The check compares output: a test whose expected output differs fails (it can fail)."""
    if pg.extension_files is not None:
        pytest.fail(pg.extension_files, pytrace=False)
    inputs = tmp_path / "in"
    (inputs / "sql").mkdir(parents=True)
    (inputs / "expected").mkdir()
    (inputs / "sql" / "wrong.sql").write_text("SELECT 1 AS one;\n")
    (inputs / "expected" / "wrong.out").write_text("SELECT 1 AS one;\n one \n-----\n   2\n(1 row)\n\n")
    result = _installcheck(
        pg, f"tgsis_installcheck_wrong_{os.getpid()}", inputdir=str(inputs), outputdir=tmp_path / "out", regress="wrong"
    )
    assert result.returncode != 0
    assert "wrong" in result.stdout and (tmp_path / "out" / "regression.diffs").read_text().count("-   2") == 1
