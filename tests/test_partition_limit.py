"""tgsis.partition_model_storage takes what the server's lock table holds and refuses the rest up front (issue 36, point 2).

Each partition made holds locks until the transaction ends; PostgreSQL's
lock table is sized max_locks_per_transaction x (max_connections +
max_prepared_transactions). Model 1 in 512 partitions was accepted and then
failed half-way with 53200 on a default server. Now a call needing more is
refused with TG100 naming the largest number the server takes, nothing
changed, and that number itself succeeds, within the documented size.
"""

from __future__ import annotations

import re
from typing import Any

import psycopg
import pytest

import tgsis

Conn = psycopg.Connection[Any]


def _room(conn: Conn) -> int:
    row = conn.execute(
        "SELECT current_setting('max_locks_per_transaction')::int * "
        "(current_setting('max_connections')::int + current_setting('max_prepared_transactions')::int)"
    ).fetchone()
    assert row is not None
    return int(row[0])


def _plain(conn: Conn) -> list[Any]:
    """Model 1's tables and the kind of the relation storing each (the table, or its chunk table)."""
    return conn.execute(
        "SELECT t.tablename, c.relkind FROM tgsis.model_tables t JOIN pg_class c "
        "ON c.oid = tgsis.storage_table('tgsis', t.tablename)::regclass WHERE t.model = 1 ORDER BY 1"
    ).fetchall()


def test_both_sides_of_the_limit(conn: Conn) -> None:
    before = _plain(conn)
    assert {kind for _, kind in before} == {"r"}
    with pytest.raises(
        tgsis.InvalidInputError,
        match=r"data model 1 in 1024 partitions needs about \d+ locks in one "
        r"transaction, more than this server's lock table holds",
    ) as caught:
        tgsis.partition_model_storage(conn, 1, 1024)
    assert f"= {_room(conn)} locks of all sessions" in str(caught.value.detail)
    hint = str(caught.value.hint)
    found = re.fullmatch(
        r"give at most (\d+) partitions, or raise max_locks_per_transaction \(a server restart\) for more", hint
    )
    assert found, hint
    most = int(found[1])
    assert 64 <= most < 512  # the default server's figure: what failed with 53200 is refused
    conn.rollback()
    assert _plain(conn) == before
    # one more than the limit: refused, nothing changed
    with pytest.raises(tgsis.InvalidInputError, match=f"data model 1 in {most + 1} partitions needs"):
        tgsis.partition_model_storage(conn, 1, most + 1)
    conn.rollback()
    assert _plain(conn) == before
    # the limit itself: done, holding no more locks than the lock table's documented size
    tables = tgsis.partition_model_storage(conn, 1, most)
    held = conn.execute(
        "SELECT count(DISTINCT (locktype, database, relation, classid, objid, objsubid)) "
        "FROM pg_locks WHERE pid = pg_backend_pid()"
    ).fetchone()
    assert held is not None and held[0] <= _room(conn)
    conn.commit()
    assert set(tables) == {name for name, _ in before}
    assert {kind for _, kind in _plain(conn)} == {"p"}
    row = conn.execute(
        "SELECT count(*) FROM pg_inherits WHERE inhparent = tgsis.storage_table('tgsis', 'vrtx')::regclass"
    ).fetchone()
    assert row == (most,)
