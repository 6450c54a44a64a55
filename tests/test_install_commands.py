"""The install commands the documentation shows, and the Docker image's first start, work as written (issue 16, part 3).

``CREATE EXTENSION tgsis`` as README.md and docs/install.md showed it failed
(``cube`` was not installed: it needs ``CASCADE``), and so did the Docker
image's first start, whose init script runs the same statement under
``ON_ERROR_STOP``. Here every ``psql ... -c '...'`` of the documentation's
shell blocks runs, as written, on a fresh database of the test server, and
``docker/initdb/*.sql`` runs the way the image's entrypoint runs it (psql,
``ON_ERROR_STOP=1``) on a fresh cluster of the image's PostgreSQL 15 with
PostGIS, whichever server the rest of the suite uses.
"""

from __future__ import annotations

import re
import shlex
import subprocess
from collections.abc import Callable, Iterator
from pathlib import Path

import psycopg
import pytest

from tgsis.db.local import LocalServer, find_binaries
from tgsis.db.sqlsource import ExtensionSources

ROOT = Path(__file__).resolve().parents[1]
DOCS = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md")), ROOT / "docker" / "README.md"]
INITDB = sorted((ROOT / "docker" / "initdb").glob("*.sql"))


def _psql_commands() -> list[tuple[str, list[str]]]:
    """(file, the -c statements) of every psql command that creates or installs something."""
    found = []
    for path in DOCS:
        if not path.exists():
            continue
        for block in re.findall(r"```(?:sh|bash|console)\n(.*?)```", path.read_text(encoding="utf-8"), re.S):
            for line in block.splitlines():
                if not line.strip().startswith("psql"):
                    continue
                words = shlex.split(line, comments=True)
                statements = [words[i + 1] for i, word in enumerate(words[:-1]) if word == "-c"]
                if any(re.search(r"\b(CREATE|install|create_storage)\b", s, re.I) for s in statements):
                    found.append((path.name, statements))
    return found


COMMANDS = _psql_commands()


def test_the_documentation_shows_how_to_create_the_extension() -> None:
    assert any("CREATE EXTENSION tgsis" in s for _, statements in COMMANDS for s in statements)
    assert INITDB, "docker/initdb has no init script"


@pytest.mark.parametrize("where, statements", COMMANDS, ids=[f"{w}: {' / '.join(s)}" for w, s in COMMANDS])
def test_a_documented_psql_command_works_on_a_fresh_database(
    where: str, statements: list[str], make_database: Callable[..., str]
) -> None:
    dsn = make_database()  # from template0: nothing installed
    with psycopg.connect(dsn, autocommit=True) as conn:  # psql -c: each statement on its own
        for statement in statements:
            try:
                conn.execute(statement)
            except psycopg.Error as exc:
                pytest.fail(f"{where}: `{statement}` fails on a fresh database: {exc}")
        assert conn.execute("SELECT tgsis.version()").fetchone() == (ExtensionSources.default().version,)
        assert conn.execute("SELECT to_regclass('tgsis.vrtx') IS NOT NULL").fetchone() == (True,)


@pytest.fixture(scope="module")
def image_server() -> Iterator[LocalServer]:
    """A fresh cluster of the Docker image's PostgreSQL (15, the system's) with PostGIS and this checkout's tgsis."""
    binaries = find_binaries("system")
    sharedir = binaries.sharedir
    assert sharedir is not None, f"{binaries.describe()} has no pg_config"
    if not (sharedir / "extension" / "postgis.control").exists():
        pytest.fail(
            f"PostGIS is not installed for {binaries.describe()} (as in the Docker image): "
            "apt-get install postgresql-15-postgis-3",
            pytrace=False,
        )
    server = LocalServer.throwaway(
        binaries, in_memory=True
    )  # this checkout's extension files in a share folder of its own
    try:
        sources = ExtensionSources.default()
        assert server.binaries.sharedir is not None
        installed = server.binaries.sharedir / "extension" / f"tgsis--{sources.version}.sql"
        assert installed.read_text(encoding="utf-8") == sources.script(), f"{installed} is not this checkout's SQL"
        yield server
    finally:
        server.destroy()


@pytest.mark.parametrize("script", INITDB, ids=[p.name for p in INITDB])
def test_the_docker_init_script_runs_as_the_image_runs_it(image_server: LocalServer, script: Path) -> None:
    database = f"initdb_{script.stem.replace('-', '_')}"
    image_server.ensure_database(database)
    # what docker-entrypoint.sh runs for each *.sql of /docker-entrypoint-initdb.d
    done = subprocess.run(
        [
            str(image_server.binaries.tool("psql")),
            "-v",
            "ON_ERROR_STOP=1",
            "--no-psqlrc",
            "--dbname",
            image_server.dsn(database),
            "--file",
            str(script),
        ],
        capture_output=True,
        text=True,
        check=False,
    )
    assert done.returncode == 0, f"{script.name} failed under ON_ERROR_STOP:\n{done.stderr}"
    with psycopg.connect(image_server.dsn(database)) as conn:
        assert conn.execute("SELECT tgsis.version()").fetchone() == (ExtensionSources.default().version,)
        assert conn.execute("SELECT postgis_lib_version() IS NOT NULL").fetchone() == (True,)
        assert conn.execute("SELECT to_regclass('tgsis.geometry') IS NOT NULL").fetchone() == (True,)
