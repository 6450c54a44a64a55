"""The small helpers the database modules share, each in one place (issue 38, part 6).

Found: the class given by name or as a FeatureClass was resolved in 8
copies, a read-only snapshot opened in 5, the session's version settings read
and put back in 2, and the name of a versioned table's storage made by
appending ``_ver`` in 3 places instead of asking SQL's ``tgsis.storage_table``
(the last one in the command line's message after ``versioning enable``).
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import psycopg
import pytest

import tgsis
from tests.storage_data import in_chunks
from tgsis.db._settings import read_version_settings, restore_version_settings
from tgsis.db._transfer import Storage, read_only_snapshot, resolve_class

DB = Path(tgsis.__file__).parent / "db"

Conn = psycopg.Connection[Any]


def _occurrences(text: str) -> dict[str, int]:
    found = {p.name: p.read_text(encoding="utf-8").count(text) for p in sorted(DB.glob("*.py"))}
    return {name: count for name, count in found.items() if count}


def _files_matching(pattern: str) -> list[str]:
    """The modules of the whole package (the command line and the view too) whose source matches ``pattern``."""
    found = re.compile(pattern)
    package = DB.parent
    return sorted(
        str(p.relative_to(package)) for p in package.rglob("*.py") if found.search(p.read_text(encoding="utf-8"))
    )


def test_each_helper_is_written_once() -> None:
    assert _occurrences("else get_feature_class(conn, feature_class)") == {"_transfer.py": 1}
    assert _files_matching(r"isinstance\(\w+, FeatureClass\)") == ["db/_transfer.py"]
    # checkin's check-out too opens its snapshot (after a first transaction of its own) with read_only_snapshot
    assert _files_matching("READ ONLY") == ["db/_transfer.py"]
    assert _occurrences("current_setting('tgsis.version', true)") == {"_settings.py": 1}
    assert _files_matching(r"(current_setting|set_config)\('tgsis\.(version|revision)'") == ["db/_settings.py"]
    # a versioned table's rows are where tgsis.storage_table says (quoted, with its schema), not at name + "_ver":
    # the command line's message too (tgsis.db.versions.storage_table)
    assert _occurrences('"_ver"') == {}
    assert _files_matching(r"""\}_ver\b|\+\s*["']_ver\b|["']_ver["']""") == []


def test_resolve_class(conn: Conn) -> None:
    fc = tgsis.create_feature_class(conn, "faults", "SURFACE")
    assert resolve_class(conn, fc) is fc
    assert resolve_class(conn, "faults") == fc
    with pytest.raises(tgsis.NotFoundError):
        resolve_class(conn, "nothing")


def test_a_read_only_snapshot_outside_a_transaction_refuses_writes(conn: Conn) -> None:
    conn.commit()
    with pytest.raises(psycopg.errors.ReadOnlySqlTransaction), read_only_snapshot(conn):
        assert conn.execute("SHOW transaction_isolation").fetchone() == ("repeatable read",)
        conn.execute("CREATE TABLE public.t (x int)")


def test_a_read_only_snapshot_inside_the_callers_transaction_is_a_savepoint_of_it(conn: Conn) -> None:
    conn.execute("CREATE TABLE public.t (x int)")
    with read_only_snapshot(conn):
        conn.execute("INSERT INTO public.t VALUES (1)")
    assert conn.execute("SELECT count(*) FROM public.t").fetchone() == (1,)


def test_version_settings_are_put_back_as_they_were(conn: Conn) -> None:
    tgsis.create_version(conn, "v1")
    conn.commit()
    before = read_version_settings(conn)
    with conn.transaction():
        tgsis.goto_version(conn, "v1")
        assert read_version_settings(conn) != before
        restore_version_settings(conn, before, local=True)
        # a setting never set (NULL) comes back as unset (''), which tgsis reads alike
        assert read_version_settings(conn) == (before[0] or "", before[1] or "")


def test_the_storage_of_a_versioned_table_is_the_one_sql_names(conn: Conn) -> None:
    tgsis.create_feature_class(conn, "faults", "SURFACE")
    tgsis.enable_feature_versioning(conn)
    storage = Storage.of(conn)
    assert ("tgsis", "vrtx") in storage.versioned
    for schema, table in storage.versioned:
        row = conn.execute("SELECT tgsis.storage_table(%s, %s)", (schema, table)).fetchone()
        assert row is not None and storage.table(schema, table).as_string(conn) == row[0]
    # the storage's own name: the chunk table once model 1 is stored in chunks (docs/storage.md), else _ver
    assert storage.table("tgsis", "vrtx").as_string(conn) == (
        "tgsis.vrtx_chunk" if in_chunks(conn) else "tgsis.vrtx_ver"
    )
    assert storage.table("public", "plain").as_string(conn) == '"public"."plain"'
