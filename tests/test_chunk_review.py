"""Hostile review of issue 40's foundation (chunk codec, SQL chunk tables, the writer): cases that broke it.

Each test here failed on main before its fix (or is marked xfail strict with the fix it needs).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import psycopg
import pytest
from psycopg import sql

from tests.test_chunk_tables import MODEL1, _make_chunks, _vertices, _visible
from tgsis._chunks import ChunkColumns, encode, to_copy

Conn = psycopg.Connection[Any]


def _rows_table(conn: Conn, name: str, table: str, rows: list[tuple[Any, ...]]) -> None:
    """A temporary table ``name`` LIKE tgsis.<table> plus _delete, holding ``rows`` (none deleted)."""
    conn.execute(
        sql.SQL("CREATE TEMP TABLE {} (LIKE tgsis.{}, _delete boolean NOT NULL DEFAULT false)").format(
            sql.Identifier(name), sql.Identifier(table)
        )
    )
    with conn.cursor().copy(sql.SQL("COPY pg_temp.{} FROM STDIN").format(sql.Identifier(name))) as copy:
        for row in rows:
            copy.write_row([*row, False])


@pytest.mark.parametrize("name", ["rows{cc}", "k", "v", "m{vis}", 'q"{K}'])
def test_writer_reads_the_rows_table_it_is_given_whatever_its_name(conn: Conn, name: str) -> None:
    """The writer's statement is a template whose {placeholders} were replaced one after the other, longest
    first, so a placeholder inside the rows table's name was replaced too (``rows{cc}`` became ``rowsvrtxid``:
    another table was read than the one checked); and the table's name was unqualified, so a temporary table
    named like one of the statement's CTEs (k, v, m...) was read as that CTE."""
    _make_chunks(conn, ["vrtx"])
    given = _vertices(range(0, 30), scale=2.0)
    _rows_table(conn, name, "vrtx", given)
    if name == "rows{cc}":  # what the name becomes once {cc} is replaced: rows that no check looked at
        _rows_table(conn, "rowsvrtxid", "vrtx", _vertices(range(100, 130), scale=-1.0))
    written = conn.execute(
        "SELECT tgsis.write_chunk_rows('vrtx', %s::regclass)", (sql.Identifier("pg_temp", name).as_string(conn),)
    ).fetchone()
    assert written == (1,)
    assert _visible(conn, "vrtx") == sorted(given)
