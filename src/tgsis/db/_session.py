"""Session and transaction settings of a reader that must see one state of the database (the browser view).

The view opens a connection per request and runs each page in one
``REPEATABLE READ`` transaction; a second connection reading beside the
first (two tables side by side) imports the first one's snapshot, so the
two see the same rows. These are the statements; :mod:`tgsis.view.app`
composes no SQL of its own.
"""

from __future__ import annotations

from typing import Any

import psycopg
from psycopg import sql

from tgsis.errors import reraise

__all__ = ["export_snapshot", "read_only_by_default", "see_one_state"]

Conn = psycopg.Connection[Any]


def read_only_by_default(conn: Conn) -> None:
    """Every later transaction of the session is read-only (``default_transaction_read_only``); committed."""
    with reraise():
        conn.execute("SET default_transaction_read_only = on")
    conn.commit()


def see_one_state(conn: Conn, snapshot: str | None = None) -> None:
    """Make the transaction just begun ``REPEATABLE READ``, seeing ``snapshot`` (of :func:`export_snapshot`) if given.

    Call it first in the transaction: PostgreSQL refuses both settings after
    the transaction's first query.
    """
    with reraise():
        conn.execute("SET TRANSACTION ISOLATION LEVEL REPEATABLE READ")
        if snapshot is not None:
            conn.execute(sql.SQL("SET TRANSACTION SNAPSHOT {}").format(sql.Literal(snapshot)))


def export_snapshot(conn: Conn) -> str:
    """The snapshot of ``conn``'s transaction, for another session to see the same state (``pg_export_snapshot()``)."""
    with reraise():
        row = conn.execute("SELECT pg_export_snapshot()").fetchone()
    assert row is not None
    return str(row[0])
