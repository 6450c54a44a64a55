"""What a merge or refresh wrote, counted per unit (tgsis.MergeResult): rows by region, rows and chunk versions copied.

Before these counts one ``int`` added the rows a merge by region wrote into
the version to what the SQL merge wrote into the parent, which where model 1
is stored in chunks counts chunk versions of the vertex and cell tables (and
rows of the others). Here each count is checked against the storage itself:
the stored versions written (or closed) in the parent's working revision,
per storage table, on both storages (the test's storage: PostgreSQL 15 runs
chunks, 18 rows).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import psycopg
import pytest

import tgsis
from tests.merge_data import SIDE, move
from tests.storage_data import in_chunks
from tgsis.cli import main

Conn = psycopg.Connection[Any]

NORTH = np.arange(0, 2 * SIDE)
SOUTH = np.arange((SIDE - 2) * SIDE, SIDE * SIDE)


@pytest.fixture
def private_state(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    monkeypatch.setenv("TGSIS_HOME", str(tmp_path))  # the command line's remembered version: this test's own
    monkeypatch.delenv("TGSIS_VERSION", raising=False)
    return tmp_path / "cli-state.json"


@pytest.fixture
def fault(conn: Conn, fault_clone: int) -> int:
    return fault_clone  # make_fault's: class faults, feature versioning, version e1 (tests/conftest.py)


def _working_revision(conn: Conn, version: str) -> int:
    row = conn.execute("SELECT workingrevision FROM tgsis.versions WHERE name = %s", (version,)).fetchone()
    assert row is not None
    return int(row[0])


def _written_in(conn: Conn, revision: int) -> tuple[int, int]:
    """(rows, chunk versions) of the feature tables' storage written or closed in ``revision``."""
    rows = chunks = 0
    tables = conn.execute(
        "SELECT tgsis.storage_table(schemaname, tablename), format('%I.%I', schemaname, tablename || '_ver') "
        "FROM tgsis.versioned_tables WHERE objectclass = 'feature'"
    ).fetchall()
    for storage, as_rows in tables:
        row = conn.execute(
            f"SELECT count(*) FROM {storage} WHERE revision = %s OR %s = ANY (lastrevs)", (revision, revision)
        ).fetchone()
        assert row is not None
        if storage == as_rows:
            rows += int(row[0])
        else:
            chunks += int(row[0])
    return rows, chunks


def _edits_on_both_sides(conn: Conn, fault: int) -> None:
    """Disjoint moves in e1 and DEFAULT; DEFAULT's saved, so that its working revision holds the merge's writes only."""
    move(conn, "e1", fault, NORTH, (0.125, -3.3, 7.77))
    move(conn, "DEFAULT", fault, SOUTH, (-1.1, 0.0, -2.9))
    conn.commit()
    with tgsis.in_version(conn, "DEFAULT"):
        tgsis.save_revision(conn, "south moved")
    conn.commit()


def test_a_merge_counts_rows_by_region_rows_and_chunk_versions_apart(conn: Conn, fault: int) -> None:
    _edits_on_both_sides(conn, fault)
    parent_revision = _working_revision(conn, "DEFAULT")
    result = tgsis.merge_version(conn, "e1")
    conn.commit()
    assert [o.objectkey for o in result.objects] == [str(fault)]
    assert result.rows_by_region == result.objects[0].rows_written > 0
    rows, chunk_versions = _written_in(conn, parent_revision)
    assert (result.rows_copied, result.chunk_versions_copied) == (rows, chunk_versions)
    if in_chunks(conn):
        # the vertex chunks of e1's moves, closed and written anew; the geometry row (the box) as rows
        assert chunk_versions == 2 * len(np.unique(NORTH // 1024)) and rows > 0
    else:
        assert chunk_versions == 0 and rows >= 2 * len(NORTH)
    # the deprecated int: the sum of the three, as before
    assert int(result) == result.rows_by_region + result.rows_copied + result.chunk_versions_copied
    assert str(result) == str(int(result))
    assert "chunk_versions_copied=" in repr(result)


def test_a_refresh_counts_apart(conn: Conn, fault: int) -> None:
    """Both sides changed the fault: merged by region into the version (rows), then copied into the version's new
    working revision (the refresh's copy of a solved conflict: rows, and chunk versions where in chunks)."""
    _edits_on_both_sides(conn, fault)
    before = _working_revision(conn, "e1")
    result = tgsis.refresh_version(conn, "e1")
    conn.commit()
    after = _working_revision(conn, "e1")
    assert after != before and [o.objectkey for o in result.objects] == [str(fault)]
    assert result.rows_by_region == result.objects[0].rows_written > 0
    rows, chunk_versions = _written_in(conn, after)
    assert (result.rows_copied, result.chunk_versions_copied) == (rows, chunk_versions)
    assert (chunk_versions > 0) == in_chunks(conn) and rows + chunk_versions > 0


def test_a_psql_users_merge_returns_the_sum_and_a_stray_setting_does_not_break_it(
    conn: Conn, fault: int, db_dsn: str
) -> None:
    """The SQL function's result is unchanged (rows and chunk versions); the setting it adds the chunk versions
    to, left with a value that is not a count by a user, restarts from 0 instead of failing the merge."""
    move(conn, "e1", fault, NORTH, (0.125, -3.3, 7.77))
    conn.commit()
    parent_revision = _working_revision(conn, "DEFAULT")
    with psycopg.connect(db_dsn) as psql:
        psql.execute("SET tgsis.chunk_versions_written = 'not a count'")
        total = psql.execute("SELECT tgsis.merge_version('e1')").fetchone()
        setting = psql.execute("SELECT current_setting('tgsis.chunk_versions_written')").fetchone()
        psql.commit()
    rows, chunk_versions = _written_in(conn, parent_revision)
    assert total == (rows + chunk_versions,)
    assert setting == (str(chunk_versions) if chunk_versions else "not a count",)


def test_the_command_line_prints_the_units_apart(
    conn: Conn, fault: int, db_dsn: str, capsys: pytest.CaptureFixture[str], private_state: Path
) -> None:
    _edits_on_both_sides(conn, fault)
    parent_revision = _working_revision(conn, "DEFAULT")
    assert main(["--dsn", db_dsn, "version", "merge", "e1"]) == 0
    out = capsys.readouterr().out
    rows, chunk_versions = _written_in(conn, parent_revision)
    first, by_region = out.splitlines()[:2]
    if chunk_versions:
        assert first == f"merged e1 into its parent: {chunk_versions} chunk version(s) and {rows} row(s) written"
    else:
        assert first == f"merged e1 into its parent: {rows} row(s) written"
    assert by_region.startswith(f"  feature {fault} merged by region (") and "row(s) written into the version" in out
