"""The test harness itself: isolation, and failing (never skipping) without a server."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path
from typing import Any

import psycopg
import pytest

from tests.local_helpers import child_env
from tgsis.testing import (
    STORAGES,
    TestServer,
    default_storage,
    start_test_server,
    swapped_file,
    time_storage,
    time_swapped_file,
)

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


# ------------------------------------------------------------------ the mark storage (issue 40)


def _model1_storage(conn: psycopg.Connection[Any]) -> set[str]:
    """The storages of model 1's chunk tables in a database (one of them unless a test switched some)."""
    rows = conn.execute(
        "SELECT tgsis.stored_in_chunks(tablename) FROM tgsis.model_tables WHERE chunkdefault AND model = 1"
    ).fetchall()
    assert len(rows) == 5
    return {"chunks" if row[0] else "rows" for row in rows}


@pytest.mark.parametrize("storage", STORAGES)
def test_the_mark_storage_gives_databases_of_that_storage(
    request: pytest.FixtureRequest, storage: str, make_database: Any, storage_templates: Any
) -> None:
    # the parametrized mark, as a test would write pytest.param(..., marks=pytest.mark.storage(storage))
    request.node.add_marker(pytest.mark.storage(storage))
    for fixture in ("db_storage", "conn", "tx"):
        value = request.getfixturevalue(fixture)
        if fixture == "db_storage":
            assert value == storage
        else:
            assert _model1_storage(value) == {storage}, fixture
    with psycopg.connect(make_database(request.getfixturevalue("storage_template_db"))) as other:
        assert _model1_storage(other) == {storage}
    with psycopg.connect(make_database(storage_templates(storage))) as other:
        assert _model1_storage(other) == {storage}


@pytest.mark.parametrize("storage", STORAGES)
def test_model_2s_time_tables_follow_the_templates_storage_unless_forced(
    storage: str, make_database: Any, storage_templates: Any
) -> None:
    """Model 2's time tables are chunks by default (chunkdefault, as model 1's): a template of either storage holds
    them in that storage, so the per-file swap of model 1 swaps them too; TGSIS_TEST_TIME_STORAGE forces every time
    table of models 2 to 5 (docs/testing.md). Models 3 to 5 stay rows unless forced."""
    with psycopg.connect(make_database(storage_templates(storage))) as conn:
        got: dict[str, str] = dict(
            conn.execute(
                "SELECT tablename, CASE WHEN tgsis.stored_in_chunks(tablename) THEN 'chunks' ELSE 'rows' END"
                " FROM tgsis.model_tables WHERE model >= 2 AND chunkcolumn IS NOT NULL"
            ).fetchall()
        )
    forced = time_storage()
    assert got.pop("times_vrtx") == got.pop("times_trgl") == (forced or storage)
    assert got and set(got.values()) == {forced or "rows"}, got


def _time_storages(conn: psycopg.Connection[Any]) -> dict[str, str]:
    """The storage of each table of models 2 to 5 registered for chunks in a database."""
    return dict(
        conn.execute(
            "SELECT tablename, CASE WHEN tgsis.stored_in_chunks(tablename) THEN 'chunks' ELSE 'rows' END"
            " FROM tgsis.model_tables WHERE model >= 2 AND chunkcolumn IS NOT NULL"
        ).fetchall()
    )


@pytest.mark.parametrize(("storage", "time"), [(s, t) for s in STORAGES for t in STORAGES])
def test_a_template_of_two_storages_holds_model_1_in_one_and_model_2_in_the_other(
    storage: str, time: str, make_database: Any, storage_templates: Any
) -> None:
    """What an upgraded database holds (model 1 in chunks, model 2 kept in rows) and its mirror are templates of
    their own (TGSIS_TEST_TIME_STORAGE=by-file gives them to every other file); models 3 to 5 stay rows."""
    with psycopg.connect(make_database(storage_templates(storage, time))) as conn:
        assert _model1_storage(conn) == {storage}
        got = _time_storages(conn)
    forced = time_storage()
    assert got.pop("times_vrtx") == got.pop("times_trgl") == (forced or time)
    assert got and set(got.values()) == {forced or "rows"}, got


@pytest.mark.storage("rows")
def test_a_marked_test_takes_its_set_up_built_once_on_its_storage(
    conn: psycopg.Connection[Any], fault_clone: int
) -> None:
    assert _model1_storage(conn) == {"rows"}
    assert conn.execute("SELECT count(*) > 0 FROM tgsis.vrtx WHERE geoid = %s", (fault_clone,)).fetchone() == (True,)


@pytest.mark.storage("chunks")
def test_a_test_marked_chunks_takes_its_set_up_built_once_on_chunks(
    conn: psycopg.Connection[Any], fault_clone: int
) -> None:
    assert _model1_storage(conn) == {"chunks"}
    assert conn.execute("SELECT count(*) > 0 FROM tgsis.vrtx WHERE geoid = %s", (fault_clone,)).fetchone() == (True,)


def test_an_unmarked_test_has_the_default_storage(
    request: pytest.FixtureRequest,
    conn: psycopg.Connection[Any],
    tx: psycopg.Connection[Any],
    template_db: str,
    storage_template_db: str,
    db_time_storage: str,
) -> None:
    assert _model1_storage(conn) == _model1_storage(tx) == {default_storage(request.node)}
    assert template_db == storage_template_db
    assert _time_storages(conn)["times_vrtx"] == _time_storages(tx)["times_trgl"] == db_time_storage


@pytest.mark.parametrize("suite", STORAGES)
def test_storage_by_file_gives_every_other_file_the_other_storage(tmp_path: Path, suite: str) -> None:
    # TGSIS_TEST_STORAGE_BY_FILE=1: two suites of opposite storages run each file once on each storage
    assert (swapped_file("test_one.py"), swapped_file("test_two.py")) == (True, False)
    (tmp_path / "conftest.py").write_text('pytest_plugins = ["tgsis.testing"]\n')
    test = (
        "import pytest\n"
        "def test_db(db_storage):\n    print('STORAGE', __name__, db_storage)\n"
        "@pytest.mark.storage('rows')\ndef test_marked(db_storage):\n    print('STORAGE', __name__, 'marked', db_storage)\n"
    )
    (tmp_path / "test_one.py").write_text(test)
    (tmp_path / "test_two.py").write_text(test)
    other = "rows" if suite == "chunks" else "chunks"
    seen = {}
    for by_file in ("0", "1"):
        result = subprocess.run(
            [sys.executable, "-m", "pytest", "-q", "-s", "-p", "no:cacheprovider", str(tmp_path)],
            env=child_env(TGSIS_TEST_DSN=BAD_DSN, TGSIS_TEST_STORAGE=suite, TGSIS_TEST_STORAGE_BY_FILE=by_file),
            capture_output=True,
            text=True,
            timeout=120,
        )
        assert result.returncode == 0, result.stdout + result.stderr
        out = result.stdout.splitlines()  # (a line may start with the progress dots of -q)
        seen[by_file] = sorted(line[line.index("STORAGE") :] for line in out if "STORAGE " in line)
    assert seen["0"] == sorted([f"STORAGE test_one {suite}", f"STORAGE test_two {suite}"] + MARKED)
    assert seen["1"] == sorted([f"STORAGE test_one {other}", f"STORAGE test_two {suite}"] + MARKED)


MARKED = ["STORAGE test_one marked rows", "STORAGE test_two marked rows"]  # the mark wins in every case


@pytest.mark.parametrize("suite", STORAGES)
def test_time_storage_by_file_gives_every_other_file_model_2_in_the_other_storage(tmp_path: Path, suite: str) -> None:
    # TGSIS_TEST_TIME_STORAGE=by-file: the second bit of the name's CRC-32, independent of model 1's swap
    names = ("test_one.py", "test_two.py", "test_three.py", "test_four.py")
    assert [(swapped_file(n), time_swapped_file(n)) for n in names] == [
        (True, True),
        (False, False),
        (True, False),
        (False, True),
    ]
    (tmp_path / "conftest.py").write_text('pytest_plugins = ["tgsis.testing"]\n')
    test = (
        "import pytest\n"
        "def test_db(db_storage, db_time_storage):\n    print('STORAGE', __name__, db_storage, db_time_storage)\n"
        "@pytest.mark.storage('chunks')\ndef test_marked(db_storage, db_time_storage):\n"
        "    print('STORAGE', __name__, 'marked', db_storage, db_time_storage)\n"
    )
    for name in names:
        (tmp_path / name).write_text(test)
    other = {"rows": "chunks", "chunks": "rows"}
    result = subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-s", "-p", "no:cacheprovider", str(tmp_path)],
        env=child_env(
            TGSIS_TEST_DSN=BAD_DSN,
            TGSIS_TEST_STORAGE=suite,
            TGSIS_TEST_STORAGE_BY_FILE="1",
            TGSIS_TEST_TIME_STORAGE="by-file",
        ),
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert result.returncode == 0, result.stdout + result.stderr
    seen = sorted(line[line.index("STORAGE") :] for line in result.stdout.splitlines() if "STORAGE " in line)
    model1 = {n: other[suite] if swapped_file(n) else suite for n in names}
    expected = [
        f"STORAGE {n[:-3]} {model1[n]} {other[model1[n]] if time_swapped_file(n) else model1[n]}" for n in names
    ]
    # a test marked storage keeps model 2 with its model 1
    expected += [f"STORAGE {n[:-3]} marked chunks chunks" for n in names]
    assert seen == sorted(expected)


@pytest.mark.storage("rows")
class TestAMarkedClass:
    def test_its_tests_have_its_storage(self, conn: psycopg.Connection[Any], db_storage: str) -> None:
        assert db_storage == "rows"
        assert _model1_storage(conn) == {"rows"}


@pytest.mark.parametrize(
    ("files", "env", "message"),
    [
        (
            "import pytest\n@pytest.mark.storage('row')\ndef test_db(db_storage):\n    pass\n",
            {},
            "@pytest.mark.storage takes one storage of rows, chunks, not ('row',)",
        ),
        (
            "def test_db(db_storage):\n    pass\n",
            {"TGSIS_TEST_STORAGE": "chunk"},
            "TGSIS_TEST_STORAGE='chunk' names no storage",
        ),
        (
            "def test_db(db_time_storage):\n    pass\n",
            {"TGSIS_TEST_TIME_STORAGE": "by_file"},
            "TGSIS_TEST_TIME_STORAGE='by_file' names no storage: use one of rows, chunks or by-file",
        ),
        (
            "def test_db(db_storage):\n    pass\n",
            {"TGSIS_TEST_STORAGE_BY_FILE": "yes"},
            "TGSIS_TEST_STORAGE_BY_FILE='yes': use 1 (storage by file) or 0",
        ),
    ],
)
def test_a_storage_that_is_none_is_an_error_naming_it(
    tmp_path: Path, files: str, env: dict[str, str], message: str
) -> None:
    (tmp_path / "conftest.py").write_text('pytest_plugins = ["tgsis.testing"]\n')
    (tmp_path / "test_storage_mark.py").write_text(files)
    result = subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", str(tmp_path)],
        env=child_env(TGSIS_TEST_DSN=BAD_DSN, **env),
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert result.returncode == 1, result.stdout
    assert message in result.stdout, result.stdout
