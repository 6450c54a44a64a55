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

from tgsis._chunks import CHUNK_BITS, CHUNK_SIZE, ChunkSet, encode, from_copy, to_copy
from tgsis.db._chunk_transfer import ChunkTable, chunk_table, split_first_field, visible_chunks
from tgsis.errors import InvalidInputError

__all__ = [
    "last_id",
    "next_id",
    "open_stage",
    "read_chunks",
    "stored_in_chunks",
    "swap_chunks",
    "swap_object_rows",
    "write_object_rows",
]

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


def swap_object_rows(
    conn: Conn,
    table: str,
    geoid: int,
    deleted: npt.ArrayLike,
    ids: npt.ArrayLike,
    floats: npt.NDArray[np.float64] | None = None,
    refs: npt.NDArray[np.int64] | None = None,
) -> int | None:
    """:func:`write_object_rows`, the touched chunks encoded here: read, merged, encoded, staged and swapped in.

    The client's path of a check-in on chunks (``tgsis.write_object_rows``
    re-aggregates each touched chunk in SQL, 3-5 ms a chunk: a scattered edit
    touches nearly all). In the caller's transaction: the visible versions
    of the touched chunks read with their places in one binary COPY, the
    edit merged into their rows, the chunks encoded (:func:`tgsis._chunks.encode`,
    as the upload does) and COPied into the transaction's stage
    (``tgsis.object_chunks_stage``), then ``tgsis.swap_object_chunks`` checks
    the rights, locks, verifies the encoding and that every chunk's visible
    version is still the one read (TG300, nothing written, when another
    transaction wrote one in between) and writes them as
    ``tgsis.write_chunk_rows`` would, bit for bit.

    Parameters
    ----------
    table, geoid, deleted, ids, floats, refs
        As :func:`write_object_rows`: ``deleted`` (d,), ``ids`` (n,), ``floats`` (n, f), ``refs`` (n, k).

    Returns
    -------
    int or None
        Chunks written; None when this path does not apply and nothing was
        done: the role may not read the chunk table or lacks INSERT or
        DELETE on the face (an add-only role: ``tgsis.write_object_rows``
        tells additions from changes), or the transaction is not READ
        COMMITTED (``tgsis.write_object_rows`` writes an add-only edit at
        any level).
    """
    gone = np.asarray(deleted, dtype=np.int64).reshape(-1)
    written = np.asarray(ids, dtype=np.int64).reshape(-1)
    if not len(gone) and not len(written):
        return 0
    layout = chunk_table(conn, table)
    stage = open_stage(conn, table, sql.Identifier("tgsis", table), layout)
    if stage is None:
        return None
    spec = layout.columns
    touched = np.unique(np.concatenate([gone, written]) >> CHUNK_BITS)
    old, bases = read_chunks(conn, layout, geoid, touched)
    old_ids, old_columns = old.rows()
    keep = ~np.isin(old_ids, np.concatenate([gone, written]))
    new_ids = np.concatenate([old_ids[keep], written])
    columns: dict[str, npt.NDArray[Any]] = {}
    float_names = [n for n in spec.names if n not in spec.refs]

    def edit_column(values: npt.ArrayLike | None, dtype: Any, names: list[str], name: str) -> npt.NDArray[Any]:
        """Column ``name`` of the written rows' values (n, len(names))."""
        if not len(written):
            return np.empty(0, dtype=dtype)
        array = None if values is None else np.asarray(values, dtype=dtype)
        if array is None or array.shape != (len(written), len(names)):
            raise InvalidInputError(
                f"the rows to write into tgsis.{table} do not match its columns",
                detail=f"{len(written)} ids; values of shape {None if array is None else array.shape} "
                f"for the columns {names}",
            )
        return array[:, names.index(name)]

    for name in spec.names:
        if name in spec.refs:
            edit = edit_column(refs, np.int64, list(spec.ref_order), name)
            columns[name] = np.concatenate([old_columns[name][keep].astype(np.int64), edit])
        else:
            edit = edit_column(floats, np.float64, float_names, name)
            columns[name] = np.concatenate([old_columns[name][keep].astype(np.float64), edit])
    return swap_chunks(conn, table, stage, geoid, touched, bases, encode(new_ids, columns, spec))


def open_stage(conn: Conn, name: str, face: sql.Composable, layout: ChunkTable) -> str | None:
    """The transaction's stage of ``tgsis.object_chunks_stage(name)`` if the client's swap is open to the role, else None.

    Open: the role may INSERT into and DELETE from the face ``face``, SELECT from the chunk table, and the
    transaction is READ COMMITTED (one statement, nothing made otherwise).
    """
    row = conn.execute(
        sql.SQL(
            "SELECT CASE WHEN {ok} THEN tgsis.object_chunks_stage(%s) END FROM (SELECT "
            "has_table_privilege({face}::regclass, 'INSERT') AND has_table_privilege({face}::regclass, 'DELETE') "
            "AND has_table_privilege({chunk}::regclass, 'SELECT') "
            "AND current_setting('transaction_isolation') = 'read committed' AS ok) p"
        ).format(
            ok=sql.SQL("p.ok"),
            face=sql.Literal(face.as_string(conn)),
            chunk=sql.Literal(layout.relation.as_string(conn)),
        ),
        (name,),
    ).fetchone()
    return None if row is None or row[0] is None else str(row[0])


def read_chunks(conn: Conn, layout: ChunkTable, geoid: int, touched: IntArray) -> tuple[ChunkSet, list[str | None]]:
    """The visible versions of chunks ``touched`` (c,) of object ``geoid`` and each one's place (None: no version).

    One binary COPY: the places ``tgsis.swap_object_chunks`` checks are those of the content returned.
    """
    spec = layout.columns
    visible = visible_chunks(layout)  # the session's set, and the old-snapshot guard (40001)
    query = sql.SQL(
        "COPY (SELECT c.tableoid::text || ':' || c.ctid::text || ':' || c.xmin::text, {} FROM {} c "
        "WHERE c.{} = {} AND c.chunk = ANY ({}::bigint[]) AND {}) TO STDOUT (FORMAT binary)"
    ).format(
        sql.SQL(", ").join(sql.SQL("c.{}").format(sql.Identifier(c)) for c in spec.select_columns()),
        layout.relation,
        sql.Identifier(spec.key),
        sql.Literal(int(geoid)),
        sql.Literal(touched.tolist()),
        visible,
    )
    with conn.cursor().copy(query) as copy:
        payload = b"".join(bytes(block) for block in copy)
    places, stream = split_first_field(payload)
    old = from_copy(stream, spec)  # chunks ascending
    bases: list[str | None] = [None] * len(touched)
    for place, chunk in zip(places, _row_chunks(stream), strict=True):
        bases[int(np.searchsorted(touched, chunk))] = None if place is None else place.decode()
    return old, bases


def swap_chunks(
    conn: Conn, name: str, stage: str, geoid: int, touched: IntArray, bases: list[str | None], chunks: ChunkSet
) -> int:
    """COPY the encoded ``chunks`` into ``stage`` and swap them in (``tgsis.swap_object_chunks(name, ...)``).

    ``touched`` (c,): the chunks the edit touches, with ``bases`` their places read by :func:`read_chunks`;
    one of them absent from ``chunks`` is left without rows. Returns the chunks written.
    """
    names = chunks.columns.copy_columns()
    statement = sql.SQL("COPY {} ({}) FROM STDIN (FORMAT binary)").format(
        sql.SQL(stage), sql.SQL(", ").join(map(sql.Identifier, names))
    )
    with conn.cursor().copy(statement) as copy:
        copy.write(to_copy(chunks, int(geoid)))
    result = conn.execute(
        "SELECT tgsis.swap_object_chunks(%s, %s, %s::bigint[], %s::text[])",
        (name, int(geoid), touched.tolist(), bases),
    ).fetchone()
    return int(result[0]) if result and result[0] is not None else 0


def _row_chunks(stream: bytes) -> list[int]:
    """The chunk number (first field, bigint) of each row of a binary COPY stream, in row order."""
    view = memoryview(stream)
    pos = 19 + int.from_bytes(view[15:19], "big")
    chunks: list[int] = []
    while True:
        count = int.from_bytes(view[pos : pos + 2], "big", signed=True)
        if count == -1:
            return chunks
        chunks.append(int.from_bytes(view[pos + 6 : pos + 14], "big", signed=True))
        pos += 2
        for _ in range(count):
            length = int.from_bytes(view[pos : pos + 4], "big", signed=True)
            pos += 4 + max(length, 0)
