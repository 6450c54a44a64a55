"""Storage-neutral test helpers: what a test asks the database about how model 1 is stored (issue 40).

A test runs on rows or on chunks (``TGSIS_TEST_STORAGE``, docs/testing.md).
It names storage through the product (``tgsis.storage_table``,
``tgsis.stored_in_chunks``), never by spelling ``tgsis.<t>_ver``; where the
two storages answer differently by design (docs/storage.md, "What differs
from rows"), it asks :func:`in_chunks` which answer is documented.
"""

from __future__ import annotations

from typing import Any

import psycopg
from psycopg import sql

from tgsis.db._transfer import copy_out
from tgsis.errors import translate

Conn = psycopg.Connection[Any]


def in_chunks(conn: Conn, table: str = "vrtx") -> bool:
    """Whether model table ``tgsis.<table>`` is stored in chunks (``tgsis.stored_in_chunks``)."""
    row = conn.execute("SELECT tgsis.stored_in_chunks(%s)", (table,)).fetchone()
    assert row is not None
    return bool(row[0])


def storage_of(conn: Conn, table: str, schema: str = "tgsis") -> str:
    """The quoted ``schema.name`` that stores ``table``'s rows: ``<t>_chunk``, ``<t>_ver`` or the table
    (``tgsis.storage_table``)."""
    row = conn.execute("SELECT tgsis.storage_table(%s, %s)", (schema, table)).fetchone()
    assert row is not None
    return str(row[0])


def stored_versions(conn: Conn, table: str, schema: str = "tgsis") -> list[tuple[Any, ...]]:
    """Every stored row or chunk version of ``table``, all columns, in key and revision order: what a refused
    write must leave alone, on either storage."""
    storage = storage_of(conn, table, schema)
    return conn.execute(f"SELECT * FROM {storage} AS s ORDER BY s::text").fetchall()


def row_versions(conn: Conn, table: str, schema: str = "tgsis") -> str:
    """A relation of the stored row versions of ``table``, one row each with the row table's columns and revision,
    lastrevs, revclosed: ``<t>_ver``, or in chunks each chunk version's rows decoded
    (``tgsis.storage_row_versions``, a parenthesized subquery or a relation name: alias it)."""
    row = conn.execute("SELECT tgsis.storage_row_versions(%s, %s)", (schema, table)).fetchone()
    assert row is not None
    return str(row[0])


def answer(conn: Conn, statement: str, name: str) -> tuple[Any, ...]:
    """What ``statement`` answers, to compare a class in chunks with its rows twin: SQLSTATE, message, constraint,
    column, table, schema and the user's exception class (``tgsis.errors.translate``), the class's ``name``
    replaced by ``X``; ``("written",)`` when it succeeds (in a savepoint, rolled back on error)."""
    try:
        with conn.transaction():
            conn.execute(statement)
    except psycopg.Error as exc:
        diag = exc.diag
        return tuple(
            None if v is None else str(v).replace(name, "X")
            for v in (
                exc.sqlstate,
                diag.message_primary,
                diag.constraint_name,
                diag.column_name,
                diag.table_name,
                diag.schema_name,
                type(translate(exc)).__name__,
            )
        )
    return ("written",)


def tables_as_rows(conn: Conn, tables: tuple[str, ...]) -> None:
    """Each model table ``tgsis.<t>`` of ``tables`` stored as rows (``tgsis.store_in_rows``, last first), committed:
    where a test that switches them itself starts, whatever ``TGSIS_TEST_TIME_STORAGE`` made them."""
    for table in reversed(tables):
        if conn.execute("SELECT tgsis.stored_in_chunks(%s)", (table,)).fetchone() == (True,):
            conn.execute("SELECT tgsis.store_in_rows(%s)", (table,))
    conn.commit()


def switch_tables(conn: Conn, tables: tuple[str, ...], to: str) -> None:
    """Each model table ``tgsis.<t>`` of ``tables`` stored in ``to`` (chunks: in order; rows: last first), committed."""
    for table in tables if to == "chunks" else reversed(tables):
        conn.execute(f"SELECT tgsis.store_in_{to}(%s)", (table,))
    conn.commit()


def classes_as_rows(dsn: str) -> None:
    """The classes of the database of ``dsn`` as rows: those it has (a set-up built once, e.g. ``fault_clone``)
    stored as rows (``tgsis.store_class_in_rows``), new ones made so in every later session
    (``ALTER DATABASE ... SET tgsis.storage = rows``): where a test that switches a class itself
    (``tgsis.store_class_in_chunks``) or compares it with a rows twin starts, whatever model 1's storage
    would give it (docs/storage.md, "Property chunks by default: the rule")."""
    with psycopg.connect(dsn, autocommit=True) as admin:
        admin.execute(sql.SQL("ALTER DATABASE {} SET tgsis.storage = rows").format(sql.Identifier(admin.info.dbname)))
        admin.execute(
            "SELECT tgsis.store_class_in_rows(c.classname) FROM tgsis.catalog c "
            "WHERE tgsis.stored_in_chunks(c.schemaname, c.cellprotable) "
            "OR (c.otherprotable IS NOT NULL AND tgsis.stored_in_chunks(c.schemaname, c.otherprotable))"
        )


#: every G-map table that can be stored in chunks (models 4 and 5: darts, involutions, points)
GMAP_TABLES = ("gmap_dart", "gmap_alpha", "md_dart", "md_alpha", "gmap_vertex", "md_vertex")


def recorded_copies(monkeypatch: Any, *modules: str) -> list[str]:
    """The statements sent through ``tgsis.db._transfer.copy_out`` as named in each of ``modules`` (e.g.
    ``"tgsis.db.gmaps"``), recorded while the test runs: the face reads a client-codec path must not make."""
    seen: list[str] = []

    def recording(conn: Conn, query: Any, types: Any) -> Any:
        seen.append(query.as_string(conn))
        return copy_out(conn, query, types)

    for module in modules:
        monkeypatch.setattr(f"{module}.copy_out", recording)
    return seen
