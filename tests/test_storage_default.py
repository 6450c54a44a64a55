"""Chunks are the default storage of model 1 (issue 40, docs/storage.md "The storage switch"; docs/install.md).

``tgsis.create_storage`` switches every table registered for chunks right
after creating it, on both install routes, unless the setting
``tgsis.storage`` is ``rows``: ``tgsis.install(conn, storage="rows")``,
``tgsis db install --storage rows``, or ``SET tgsis.storage = rows`` before
the plain-SQL script or ``SELECT tgsis.create_storage()`` in psql. A value
naming no storage is refused by name, nothing created. A table switched empty
and then versioned is the same as one versioned and then switched.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import psycopg
import pytest

import tgsis
from tests.catalog import describe_tgsis_objects
from tgsis.cli import main
from tgsis.db.sqlsource import ExtensionSources
from tgsis.testing import TestServer

MakeDb = Callable[..., str]
Conn = psycopg.Connection[Any]

CHUNKED = [
    "vrtx",
    "point",
    "segment",
    "tetra",
    "trgl",
    "times_trgl",
    "times_vrtx",
]  # chunkdefault (model 1, model 2), install order


def _storages(conn: Conn) -> dict[str, bool]:
    """Table registered for chunks -> whether it is stored in chunks."""
    return {
        str(name): bool(chunked)
        for name, chunked in conn.execute(
            "SELECT tablename, tgsis.stored_in_chunks(tablename) FROM tgsis.model_tables"
            " WHERE chunkdefault ORDER BY tablename"
        ).fetchall()
    }


def _route(method: str, pg: TestServer) -> None:
    if method == "extension" and pg.extension_files is not None:
        pytest.fail(pg.extension_files, pytrace=False)


def test_the_registry_lists_the_tables_this_file_expects(tx: Conn) -> None:
    assert sorted(_storages(tx)) == sorted(CHUNKED)


@pytest.mark.parametrize("method", ["extension", "sql"])
def test_an_install_stores_model_1_in_chunks_by_default(method: str, pg: TestServer, make_database: MakeDb) -> None:
    _route(method, pg)
    with psycopg.connect(make_database()) as conn:
        result = tgsis.install(conn, method=method)  # type: ignore[arg-type]
        conn.commit()
        assert _storages(conn) == dict.fromkeys(CHUNKED, True)
        assert f"stored in chunks: {', '.join(CHUNKED)} (docs/storage.md)" in result.steps
        # empty, and written through the faces as rows were
        assert conn.execute("SELECT count(*) FROM tgsis.vrtx_chunk").fetchone() == (0,)
        assert conn.execute(
            "SELECT to_regclass('tgsis.vrtx_ver'), to_regclass('tgsis.vrtx_shape')::text"
        ).fetchone() == (
            None,
            "tgsis.vrtx_shape",
        )
        assert conn.execute("SELECT current_setting('tgsis.storage', true)").fetchone() in ((None,), ("",)), (
            "the install's setting does not outlive it"
        )


@pytest.mark.parametrize("method", ["extension", "sql"])
def test_storage_rows_keeps_rows_on_both_routes(method: str, pg: TestServer, make_database: MakeDb) -> None:
    _route(method, pg)
    with psycopg.connect(make_database()) as conn:
        result = tgsis.install(conn, method=method, storage="rows")  # type: ignore[arg-type]
        conn.commit()
        assert _storages(conn) == dict.fromkeys(CHUNKED, False)
        assert conn.execute("SELECT to_regclass('tgsis.vrtx_chunk')").fetchone() == (None,)
        assert f"stored as rows: {', '.join(CHUNKED)} (storage='rows')" in result.steps
        # a second install (default chunks) leaves an installed database as it is
        assert tgsis.install(conn).action == "unchanged"
        assert _storages(conn) == dict.fromkeys(CHUNKED, False)


def test_install_inside_a_transaction_gives_back_the_callers_setting(make_database: MakeDb) -> None:
    with psycopg.connect(make_database()) as conn:
        conn.execute("SET LOCAL tgsis.storage = 'rows'")
        tgsis.install(conn, storage="chunks")
        assert _storages(conn) == dict.fromkeys(CHUNKED, True)
        assert conn.execute("SELECT current_setting('tgsis.storage')").fetchone() == ("rows",)


def test_an_unknown_storage_is_refused_by_the_client(make_database: MakeDb) -> None:
    with psycopg.connect(make_database()) as conn:
        with pytest.raises(tgsis.InstallationError, match="unknown storage 'row': use 'chunks' or 'rows'"):
            tgsis.install(conn, storage="row")  # type: ignore[arg-type]
        assert conn.execute("SELECT to_regnamespace('tgsis')").fetchone() == (None,)


def test_the_plain_sql_script_in_psql_honours_the_session_setting(make_database: MakeDb) -> None:
    """What a DBA without the client does: SET tgsis.storage, then the script (its search path set as install does)."""
    sources = ExtensionSources.default()
    script = sources.script(psql_guard=False)
    for setting, chunked in (("rows", False), ("chunks", True), ("", True)):
        with psycopg.connect(make_database()) as conn:
            for name in sources.requires:
                conn.execute(f"CREATE EXTENSION IF NOT EXISTS {name}")
            conn.execute("SELECT set_config('search_path', 'tgsis, public, pg_temp', true)")
            conn.execute("SELECT set_config('tgsis.storage', %s, true)", (setting,))
            conn.execute(script.encode("utf-8"))
            assert _storages(conn) == dict.fromkeys(CHUNKED, chunked), setting


@pytest.mark.parametrize("value", ["row", "CHUNK", "none", "rows;chunks"])
def test_a_bad_setting_is_refused_by_name_before_anything_is_made(
    value: str, pg: TestServer, make_database: MakeDb
) -> None:
    _route("extension", pg)
    with psycopg.connect(make_database(), autocommit=True) as conn:
        conn.execute("CREATE EXTENSION tgsis CASCADE")
        conn.execute("SELECT set_config('tgsis.storage', %s, false)", (value,))
        with pytest.raises(psycopg.Error) as info:
            conn.execute("SELECT tgsis.create_storage()")
        assert info.value.sqlstate == "TG001"
        assert info.value.diag.message_primary == (f"the setting tgsis.storage is '{value}', which names no storage")
        assert "SET tgsis.storage = chunks (or rows)" in str(info.value.diag.message_hint)
        assert conn.execute("SELECT to_regclass('tgsis.geometry'), to_regclass('tgsis.vrtx')").fetchone() == (
            None,
            None,
        )
        # upper case and blanks are the same storage
        conn.execute("SELECT set_config('tgsis.storage', ' ROWS ', false)")
        assert conn.execute("SELECT tgsis.create_storage()").fetchone() == (True,)
        assert _storages(conn) == dict.fromkeys(CHUNKED, False)


def test_create_storage_after_a_bare_create_extension_stores_chunks(pg: TestServer, make_database: MakeDb) -> None:
    _route("extension", pg)
    with psycopg.connect(make_database(), autocommit=True) as conn:
        conn.execute("CREATE EXTENSION tgsis CASCADE")
        assert conn.execute("SELECT tgsis.create_storage()").fetchone() == (True,)
        assert _storages(conn) == dict.fromkeys(CHUNKED, True)
        # what the switch made is no extension member: pg_dump keeps it with the data
        members = conn.execute(
            "SELECT count(*) FROM pg_depend d JOIN pg_class c ON d.classid = 'pg_class'::regclass AND c.oid = d.objid"
            " WHERE d.deptype = 'e' AND d.refobjid = (SELECT oid FROM pg_extension WHERE extname = 'tgsis')"
            "   AND c.relname ~ '^(vrtx|point|segment|trgl|tetra)(_chunk|_chunk_rows|_shape)?$'"
        ).fetchone()
        assert members == (0,)


@pytest.mark.parametrize(
    ("flag", "chunked"), [([], True), (["--storage", "rows"], False), (["--storage", "chunks"], True)]
)
def test_the_cli_installs_the_storage_asked(
    flag: list[str], chunked: bool, make_database: MakeDb, capsys: pytest.CaptureFixture[str]
) -> None:
    dsn = make_database()
    assert main(["--dsn", dsn, "db", "install", "--method", "sql", *flag]) == 0
    printed = capsys.readouterr().out
    assert ("stored in chunks: vrtx" in printed) is chunked and ("stored as rows: vrtx" in printed) is not chunked
    with psycopg.connect(dsn) as conn:
        assert _storages(conn) == dict.fromkeys(CHUNKED, chunked)


def test_the_cli_refuses_a_storage_that_is_none(make_database: MakeDb, capsys: pytest.CaptureFixture[str]) -> None:
    dsn = make_database()
    with pytest.raises(SystemExit) as exited:
        main(["--dsn", dsn, "db", "install", "--storage", "row"])
    assert exited.value.code == 2
    assert "invalid choice: 'row'" in capsys.readouterr().err
    with psycopg.connect(dsn) as conn:
        assert conn.execute("SELECT to_regnamespace('tgsis')").fetchone() == (None,)


# a surface, versioned, in a second version with a change of its own (as tests/test_upgrade.py's _USE)
_USE = """
SELECT tgsis.register_feature_class('horizon', 'SURFACE', '[{"name": "unit", "type": "text"}]',
                                    '[{"name": "depth", "type": "double precision"}]');
WITH g AS (SELECT tgsis.new_geometry('SURFACE', 'top', ARRAY[0, 0, 0, 1, 1, 0]::float8[], 3, 1) AS geoid),
     v AS (INSERT INTO tgsis.vrtx SELECT geoid, i, i % 2, i / 2, 0 FROM g, generate_series(0, 2) i),
     t AS (INSERT INTO tgsis.trgl SELECT geoid, 0, 0, 1, 2 FROM g)
INSERT INTO public.horizon (_geoid, unit) SELECT geoid, 'Triassic' FROM g;
SELECT tgsis.enable_feature_versioning();
SELECT tgsis.create_version('survey2', 'DEFAULT', 'the second survey');
SELECT tgsis.goto_version('survey2', true);
UPDATE tgsis.vrtx SET z = -5 WHERE vrtxid = 2;
SELECT tgsis.save_revision('survey2');
SELECT tgsis.goto_version('DEFAULT', true);
"""


@pytest.mark.storage("rows")
def test_switched_then_versioned_is_versioned_then_switched(
    conn: Conn, make_database: MakeDb, storage_templates: Any
) -> None:
    """The objects of a table switched empty and then versioned (a fresh install's) equal those of one switched
    while versioned (an upgraded database's): the face's and decoded view's comments do not depend on when."""
    conn.execute(_USE)
    conn.execute(
        "SELECT tgsis.store_in_chunks(tablename) FROM tgsis.model_tables WHERE chunkdefault"
        " ORDER BY model, iudorder, tablename"
    )
    conn.commit()
    with psycopg.connect(make_database(storage_templates("chunks"))) as fresh:
        fresh.execute(_USE)
        fresh.commit()
        want = describe_tgsis_objects(fresh)
    got = describe_tgsis_objects(conn)
    differences = [
        f"{kind}: only {where}: {row}"
        for kind in want
        for where, rows in (
            ("switched while versioned", set(got[kind]) - set(want[kind])),
            ("fresh", set(want[kind]) - set(got[kind])),
        )
        for row in sorted(rows)
    ]
    assert differences == [], "\n".join(differences)


def test_docs_name_the_option() -> None:
    docs = Path(__file__).resolve().parents[1] / "docs"
    install = (docs / "install.md").read_text(encoding="utf-8")
    assert "--storage rows" in install and 'storage="rows"' in install and "SET tgsis.storage = rows" in install
