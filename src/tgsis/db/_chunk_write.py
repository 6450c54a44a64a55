"""Edits of model-1 objects stored in chunks (issue 40): the one client path of check-in, save and merge writes.

Once a model table is switched to chunks (``tgsis.store_in_chunks``:
``tgsis.stored_in_chunks(table)``), its rows are no longer rows of storage
that a COPY adds and ``tgsis.delete_object_rows`` closes: an edit names the
ids that go and the rows that are new or changed, and
``tgsis.write_object_rows`` rewrites each touched chunk once (closed and
written anew in the working revision, or in place when it is the working
revision's), after the checks of today's row path, for the calling role.
:func:`write_rows` takes either path, so that the callers (``db/_state_write``,
``db/checkin``) hold one write per table. Private to ``tgsis.db``.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import numpy.typing as npt
import psycopg
from psycopg import sql

from tgsis._chunks import CHUNK_SIZE
from tgsis.db._chunk_transfer import chunk_table

__all__ = ["last_id", "next_id", "stored_in_chunks", "write_object_rows"]

Conn = psycopg.Connection[Any]
IntArray = npt.NDArray[np.int64]


def stored_in_chunks(conn: Conn, table: str) -> bool:
    """Whether the model table ``tgsis.<table>`` is stored in chunks (``tgsis.stored_in_chunks``)."""
    row = conn.execute("SELECT tgsis.stored_in_chunks(%s)", (table,)).fetchone()
    return bool(row and row[0])


def last_id(conn: Conn, table: str, alias: str = "c") -> sql.Composable:
    """The last present id of a chunk version ``alias`` of ``tgsis.<table>_chunk``, as an SQL expression.

    A chunk version's arrays end at its last present slot, so its last id is
    ``chunk * chunksize + (length - 1)`` (of the first array, or of its
    ``_wide`` twin when the chunk's vertex ids are absolute): no decoding.
    """
    # the layout from the catalog, which every role may read (tgsis.chunk_columns is internal)
    layout = chunk_table(conn, table)
    name = layout.columns.names[0]
    role = "ref" if name in layout.columns.refs else "float"
    size = CHUNK_SIZE  # chunk_table refuses a chunk table of another size
    a = sql.Identifier(alias)
    length = (
        sql.SQL("cardinality({}.{})").format(a, sql.Identifier(name))
        if role == "float"
        else sql.SQL("coalesce(cardinality({a}.{}), cardinality({a}.{}))").format(
            sql.Identifier(name), sql.Identifier(f"{name}_wide"), a=a
        )
    )
    # (length - 1) first: the last slot of the last chunk is id 2**63 - 1, and chunk * size + length is 2**63
    return sql.SQL("({}.chunk * {} + ({} - 1))").format(a, sql.Literal(int(size)), length)


def next_id(conn: Conn, table: str, geoid: int) -> int:
    """The first local id above every id object ``geoid`` ever had in chunked ``tgsis.<table>`` (every chunk version).

    Read from the chunk table itself (:func:`last_id` of each version), as
    today's path reads the row storage (every row version).
    """
    row = conn.execute(
        sql.SQL("SELECT max({}) FROM {} c WHERE c.geoid = %s").format(
            last_id(conn, table), sql.Identifier("tgsis", f"{table}_chunk")
        ),
        (geoid,),
    ).fetchone()
    return 0 if row is None or row[0] is None else int(row[0]) + 1


def write_object_rows(
    conn: Conn,
    table: str,
    geoid: int,
    deleted: npt.ArrayLike,
    ids: npt.ArrayLike,
    floats: npt.NDArray[np.float64] | None = None,
    refs: npt.NDArray[np.int64] | None = None,
) -> int:
    """Delete ids ``deleted`` (d,) and write rows ``ids`` (n,) of object ``geoid`` of chunked ``tgsis.<table>``.

    One call of ``tgsis.write_object_rows`` (the caller's transaction, READ
    COMMITTED): every chunk the ids touch rewritten once in the session's
    working revision, the object noted as changed there.

    Parameters
    ----------
    table : str
        ``vrtx``, ``point``, ``segment``, ``trgl`` or ``tetra``, stored in chunks.
    geoid : int
    deleted : (d,) int
        Ids that go (not among ``ids``).
    ids : (n,) int
        Ids written: new ones, or ones whose row is replaced.
    floats : (n, f) float64, optional
        The double precision columns' values in column order (vertices: x, y, z).
    refs : (n, k) int64, optional
        The vertex-id columns' values in column order (cells: vrtxid1..k).

    Returns
    -------
    int
        Chunks written (an unchanged chunk is not).
    """
    gone = np.asarray(deleted, dtype=np.int64).reshape(-1)
    written = np.asarray(ids, dtype=np.int64).reshape(-1)
    if not len(gone) and not len(written):
        return 0
    # the doubles in binary (%b): bit for bit, NaN payloads too, as the row path's binary COPY sends them
    row = conn.execute(
        "SELECT tgsis.write_object_rows(%s, %s, %s::bigint[], %s::bigint[], %b::float8[], %s::bigint[])",
        (
            table,
            int(geoid),
            gone.tolist(),
            written.tolist(),
            None if floats is None or not len(written) else np.asarray(floats, dtype=np.float64).T.tolist(),
            None if refs is None or not len(written) else np.asarray(refs, dtype=np.int64).T.tolist(),
        ),
    ).fetchone()
    return int(row[0]) if row and row[0] is not None else 0
