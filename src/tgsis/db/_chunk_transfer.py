"""Bulk transfer of model-1 objects on chunk tables (issue 40, part 5): upload and download of whole objects.

The two bulk paths the storage switch will call (docs/storage.md, "What each
bulk path does on chunks"); nothing of today's storage calls them yet. A
chunk table ``tgsis.<t>_chunk`` (made by ``tgsis.create_chunk_table``)
holds an object's rows of ``tgsis.<t>`` in blocks of 1,024 ids
(:mod:`tgsis._chunks` encodes and parses them):

* :func:`upload_chunks` writes new objects: their chunk rows, encoded by
  numpy, in ONE binary COPY per table, in the session's working revision
  (what a COPY into ``<t>_ver`` gets today: :class:`~tgsis.db._transfer.Storage`;
  0 for unversioned storage and for features of classes without versioning),
  and notes the objects changed in that revision as the storage's insert
  trigger notes a COPY's (``tgsis.record_changed_objects``). An object that
  has a chunk already is refused: this is no edit path.
* :func:`download_chunks` reads the chunk versions the session's version sees
  (today's versioned views' test, ``tgsis.get_revisions(true)``; every chunk
  of unversioned storage) of one or many objects with one
  ``COPY (SELECT ...) TO STDOUT (FORMAT binary)`` per table, inside one
  state for several tables (:func:`~tgsis.db._transfer.consistent_read`),
  and parses them into ids and arrays per object.

Rights are the role's own: the COPY runs as it, so the chunk table's grants
and row-level security (the row storage's, copied by
``tgsis.create_chunk_table``) decide; under row-level security the rows go
through a temporary table first (:func:`~tgsis.db._transfer.staged`).
Private to ``tgsis.db``.
"""

from __future__ import annotations

import concurrent.futures
import re
import struct
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, cast

import numpy as np
import numpy.typing as npt
import psycopg
from psycopg import sql

from tgsis._chunks import CHUNK_SIZE, COPY_SIGNATURE, ChunkColumns, ChunkSet, encode, from_copy, to_copy
from tgsis.db._transfer import Packed, PartRequest, Storage, consistent_read, read_only_snapshot, staged
from tgsis.errors import AlreadyExistsError, DatabaseError, InvalidGeometryError, InvalidInputError, NotFoundError

__all__ = [
    "ChunkTable",
    "ObjectRows",
    "chunk_table",
    "chunked_tables",
    "PackedChunks",
    "rows_request",
    "records_as_copy",
    "upload_chunks",
    "visible_versions",
    "download_chunks",
    "download_tables",
    "object_rows",
    "chunk_copy_query",
    "visible_chunks",
    "split_copy",
    "split_first_field",
    "instant_layout",
    "InstantKey",
    "instant_rows",
    "repeated_corners",
    "upload_instants",
    "write_instants",
    "upload_rows",
    "point_rows",
    "INSTANT_BLOCK_BITS",
]

Conn = psycopg.Connection[Any]

#: the columns of every chunk table that are neither key nor array of the row table
_FIXED = ("revision", "lastrevs", "revclosed", "holes", "vbase", "vtop")


@dataclass(frozen=True)
class ChunkTable:
    """A chunk table as the client sees it in the catalog.

    Attributes
    ----------
    table : str
        The row table (``vrtx``, ``trgl``, ...); the chunk table is ``tgsis.<table>_chunk``.
    columns : ChunkColumns
        Its arrays: ``double precision[]`` columns as float8, ``integer[]`` ones as ref columns.
    versioned : bool
        The row table is versioned (``tgsis.versioned_tables``): chunk versions are filtered by the session's set.
    readable : bool
        The role may SELECT from the chunk table (a role granted only the face ``tgsis.<table>`` reads through it).
    schema : str
        The chunk table's schema: ``tgsis`` for a model table, the class's for a class's property table.
    """

    table: str
    columns: ChunkColumns
    versioned: bool
    readable: bool = True
    schema: str = "tgsis"

    @property
    def relation(self) -> sql.Composed:
        """``<schema>.<table>_chunk``, quoted."""
        return sql.SQL("{}.{}").format(sql.Identifier(self.schema), sql.Identifier(f"{self.table}_chunk"))


@dataclass(frozen=True)
class ObjectRows:
    """One object's rows of a chunked table: what an upload writes and a download returns.

    Attributes
    ----------
    geoid : int
    ids : (n,) int64
        Local ids (vrtxid, trglid, ...), >= 0, distinct; ascending in a download.
    columns : dict of str to (n,) ndarray
        Every non-key column of the row table: float64 for float8 columns, int64 vertex ids for ref columns.
    holes : (h,) int64
        Download only: the ids absent inside the stored chunks (below each chunk's last present id), ascending.
    nulls : dict of str to (n,) bool
        A class's property columns whose value is NULL in some rows (True there; the value in ``columns`` is
        then 0): written as NULL by an upload, read back so by a download; a column not in it has none.
    """

    geoid: int
    ids: npt.NDArray[np.int64]
    columns: dict[str, npt.NDArray[Any]]
    holes: npt.NDArray[np.int64] = field(default_factory=lambda: np.empty(0, dtype=np.int64))
    nulls: dict[str, npt.NDArray[np.bool_]] = field(default_factory=dict)

    def array(self) -> npt.NDArray[Any]:
        """(n, k) the columns side by side in column order: vertices (n, 3) float64, cells (n, k) int64."""
        values = list(self.columns.values())
        if len({v.dtype for v in values}) > 1:
            raise InvalidInputError(f"columns {list(self.columns)} differ in type: take them one by one")
        return np.stack(values, axis=1) if values else np.empty((len(self.ids), 0))


def chunked_tables(conn: Conn) -> frozenset[str]:
    """The model tables whose rows are stored in chunks (``tgsis.stored_in_chunks``): their bulk paths take chunks.

    Returns
    -------
    frozenset of str
        Row table names (``vrtx``, ``trgl``, ...) of ``tgsis.model_tables`` stored in chunks; empty while rows are.
    """
    rows = conn.execute(
        "SELECT tablename::text FROM tgsis.model_tables WHERE chunkcolumn IS NOT NULL AND tgsis.stored_in_chunks(tablename)"
    ).fetchall()
    return frozenset(str(r[0]) for r in rows)


def chunk_table(conn: Conn, table: str, *, instants: bool = False, values: bool = False) -> ChunkTable:
    """The chunk table of ``tgsis.<table>``, read from the catalog (any role may read it).

    Parameters
    ----------
    instants : bool
        Expect a time table's key ``geoid, <instant keys>, chunk``, its instant keys one or more ``double
        precision`` columns (model 2's ``times_vrtx``, ``times_trgl``: ``times``; model 3's ``d4dvrtx``:
        ``timem, timet``, ``d4dtrgl``: ``timem``; :func:`instant_rows`, :func:`upload_instants`) instead of
        model 1's ``geoid, chunk``. They are read from the catalog (the row table's primary key less its id).
    values : bool
        Expect a G-map's darts or involutions (``gmap_dart``, ``md_dart``, ``gmap_alpha``, ``md_alpha``:
        :func:`upload_rows`): key ``geoid, [integer keys,] chunk`` (``level smallint``), its ref columns the
        ``integer[]`` ones with a ``<name>_wide``, and its ``value`` columns (``smallint[]``, ``integer[]``,
        ``bigint[]``, ``real[]``, ``boolean[]``: a dart's ``acellid``, ``positive``) as nullable columns.

    Raises
    ------
    NotFoundError
        ``tgsis.<table>_chunk`` does not exist (TG200).
    InvalidInputError
        Its layout is not the one this client encodes (key ``geoid, chunk``, or ``geoid``, ``double precision``
        instant keys, ``chunk`` with ``instants``; 1,024 ids per chunk).
    """
    row = conn.execute(
        "SELECT to_regclass(format('tgsis.%%I', %s::text || '_chunk'))::oid, "
        "EXISTS (SELECT FROM tgsis.versioned_tables t WHERE t.schemaname = 'tgsis' AND t.tablename = %s), "
        "(SELECT m.chunksize FROM tgsis.model_tables m WHERE m.tablename = %s), "
        "has_table_privilege(to_regclass(format('tgsis.%%I', %s::text || '_chunk')), 'SELECT'), "
        # a G-map's points: the face's double precision[] columns (role 'point': one 2-D array per chunk)
        "ARRAY(SELECT a.attname::text FROM pg_catalog.pg_attribute a WHERE a.attrelid = to_regclass(format('tgsis.%%I', "
        "%s::text)) AND a.attnum > 0 AND NOT a.attisdropped AND a.atttypid = 'double precision[]'::regtype)",
        (table, table, table, table, table),
    ).fetchone()
    if row is None or row[0] is None:
        raise NotFoundError(
            f"tgsis.{table} has no chunk table",
            detail=f"tgsis.{table}_chunk does not exist (tgsis.create_chunk_table makes it)",
        )
    oid, versioned, size, readable, points = row
    # the columns as the snapshot sees them: none if the table was made (a storage switch) or a property added after
    # it, which the snapshot would read empty: 40001 then (tgsis.chunk_snapshot_guard), not a layout refused
    attributes = conn.execute(
        "SELECT attname::text, format_type(atttypid, atttypmod) FROM pg_catalog.pg_attribute "
        "WHERE attrelid = %s AND attnum > 0 AND NOT attisdropped AND (SELECT tgsis.chunk_snapshot_guard(%s::oid::regclass)) "
        "ORDER BY attnum",
        (oid, oid),
    ).fetchall()
    names = [name for name, _ in attributes]
    keys = names[: names.index("revision")] if "revision" in names else names
    arrays = [(n, t) for n, t in attributes if n not in keys and n not in _FIXED and not n.endswith("_wide")]
    if values:  # a ref column has its _wide; a value column of type integer[] has none
        refs = tuple(n for n, t in arrays if t == "integer[]" and f"{n}_wide" in names)
    else:
        refs = tuple(n for n, t in arrays if t == "integer[]")
    types = dict(attributes)
    instant = tuple(keys[1:-1]) if instants or values else ()
    key_types = ("smallint", "integer", "bigint", "double precision") if values else ("double precision",)
    kinds = {n: _VALUE_KINDS.get(t) for n, t in arrays if values and n not in refs and t != "double precision[]"}
    if (
        keys != ["geoid", *instant, "chunk"]
        or (instants and not instant)
        or any(types[k] not in key_types for k in instant)
        or size != CHUNK_SIZE
        or any(t not in ("integer[]", "double precision[]") for n, t in arrays if n not in kinds)
        or None in kinds.values()
    ):
        what = "time" if instants else "G-map" if values else "model-1"
        raise InvalidInputError(
            f"tgsis.{table}_chunk is not a {what} chunk table of {CHUNK_SIZE} ids per chunk",
            detail=f"key {keys}, chunk size {size}, arrays {arrays}",
        )
    spec = ChunkColumns(
        tuple(n for n, _ in arrays),
        refs=refs,
        properties=tuple((n, str(k)) for n, k in kinds.items()),
        instant=instant,
        instant_kinds=tuple(_KEY_KINDS[types[k]] for k in instant) if values else (),
        points=tuple(n for n in points if n in dict(arrays)),
    )
    return ChunkTable(table, spec, bool(versioned), bool(readable))


#: the element kind (:data:`tgsis._chunks.PROPERTY_KINDS`) of a G-map chunk table's value column, by its type
_VALUE_KINDS = {"smallint[]": "int2", "integer[]": "int4", "bigint[]": "int8", "real[]": "float4", "boolean[]": "bool"}
#: the kind of an integer key column between ``geoid`` and ``chunk`` (a G-map involution's ``level``)
_KEY_KINDS = {"smallint": "int2", "integer": "int4", "bigint": "int8", "double precision": "float8"}


def upload_chunks(conn: Conn, table: str, objects: Sequence[ObjectRows], storage: Storage | None = None) -> int:
    """Write new objects' rows of ``tgsis.<table>`` as chunk rows: one binary COPY for all of them.

    Parameters
    ----------
    conn : psycopg.Connection
        Its role writes (the chunk table's grants and row-level security apply).
    table : str
        A row table with a chunk table (``vrtx``, ``point``, ``segment``, ``trgl``, ``tetra``).
    objects : sequence of ObjectRows
        One per object (distinct geoids); ``columns`` (n,) each, by name.
    storage : Storage, optional
        Where the session writes (:meth:`Storage.of`; of a class without versioning: revision 0).
        Default: ``Storage.of(conn)``.

    Returns
    -------
    int
        The chunk rows written.

    Raises
    ------
    AlreadyExistsError
        An object has chunks already in ``tgsis.<table>_chunk`` (of any version, among those the role may
        read: a class it may not read cannot be written either), or a concurrent upload of it in the same
        revision committed first: nothing is written.
    NotVersionedError, ReadOnlyRevisionError
        The session may not write here (as for today's COPY into storage).
    InvalidInputError
        Repeated geoids, ids or columns the codec refuses.
    psycopg.errors.InsufficientPrivilege
        The role lacks INSERT on the chunk table, or the class's right (row-level security).
    """
    layout = chunk_table(conn, table)
    geoids = [int(o.geoid) for o in objects]
    if len(set(geoids)) != len(geoids):
        raise InvalidInputError(f"geoids repeat in one upload of tgsis.{table}: {geoids}")
    storage = storage if storage is not None else Storage.of(conn)
    storage.check("tgsis", table)
    revision = int(storage.revision or 0) if ("tgsis", table) in storage.versioned else 0
    # encode first: bad input is refused before anything is sent
    encoded = [encode(o.ids, o.columns, layout.columns) for o in objects]
    if not objects:
        return 0
    existing = conn.execute(
        sql.SQL("SELECT array_agg(DISTINCT geoid ORDER BY geoid) FROM {} WHERE geoid = ANY (%s)").format(
            layout.relation
        ),
        (geoids,),
    ).fetchone()
    if existing is not None and existing[0]:
        raise AlreadyExistsError(
            f"objects {existing[0]} have chunks in tgsis.{table}_chunk already: an upload writes new objects only",
            detail="nothing was written",
        )
    names = layout.columns.copy_columns()
    statement = sql.SQL("COPY {} ({}) FROM STDIN (FORMAT binary)")
    try:
        with staged(conn, layout.relation, names) as into:
            with conn.cursor().copy(statement.format(into, sql.SQL(", ").join(map(sql.Identifier, names)))) as copy:
                for k, (chunks, geoid) in enumerate(zip(encoded, geoids)):
                    stream = to_copy(chunks, geoid, revision)
                    # one stream: the header once, the trailer once
                    copy.write(memoryview(stream)[19 if k else 0 : -2 if k < len(encoded) - 1 else None])
    except psycopg.errors.UniqueViolation as exc:
        # a concurrent upload of the same object in the same revision committed first (this one waited for it)
        raise AlreadyExistsError(
            f"objects {geoids} of tgsis.{table}_chunk were written meanwhile by another transaction",
            detail=f"{(exc.diag.message_detail or '')[:300]}; nothing was written",
        ) from exc
    if layout.versioned and revision != 0:
        conn.execute("SELECT tgsis.record_changed_objects('tgsis', %s, %s::text[])", (table, [str(g) for g in geoids]))
    return sum(len(c.chunk) for c in encoded)


def visible_chunks(layout: ChunkTable, revisions: Sequence[int] | None = None) -> sql.Composable:
    """The session's visibility test of chunk versions (today's versioned views'; none when unversioned), guarded.

    The guard: ``tgsis.chunk_snapshot_guard`` once per statement, 40001 when the statement's snapshot predates
    the chunk table's file (rewritten by an added property, made by a storage switch), which it would read empty.

    ``revisions``: the set to test with (the session's ``tgsis.get_revisions(true)`` read beforehand), for a
    statement run on another connection, whose session may be in another version.
    """
    # a snapshot older than the chunk table's file (an add's rewrite, a storage switch) would read it empty:
    # 40001 instead, once per statement (tgsis.chunk_snapshot_guard, an InitPlan)
    guard = sql.SQL("(SELECT tgsis.chunk_snapshot_guard(format('%I.%I', {}::text, {}::text)::regclass))").format(
        sql.Literal(layout.schema), sql.Literal(f"{layout.table}_chunk")
    )
    if not layout.versioned:
        return guard
    if revisions is not None:
        revision_set: sql.Composable = sql.SQL("{}::integer[]").format(sql.Literal([int(r) for r in revisions]))
    else:
        revision_set = sql.SQL("(SELECT tgsis.get_revisions(true))::integer[]")
    return sql.SQL("{} AND {}").format(guard, visible_versions("c", revision_set))


def visible_versions(alias: str, revision_set: sql.Composable) -> sql.Composed:
    """The visibility predicate of stored versions, ``tgsis.visible_versions(alias, set)``'s text.

    A version (row or chunk) seen by the revision set: made in a revision of the set, live or closed in none of it.
    ``alias`` is the versions' range variable (quoted as ``quote_ident`` quotes it, but for a keyword),
    ``revision_set`` an SQL expression of type ``integer[]`` (written
    twice). tests/test_visible_versions.py compares the rendered text with the SQL function's.
    """
    return sql.SQL("({a}.revision = ANY ({s})) IS TRUE AND (NOT {a}.revclosed OR NOT ({a}.lastrevs && {s}))").format(
        a=sql.SQL(alias) if re.fullmatch(r"[a-z_][a-z0-9_]*", alias) else sql.Identifier(alias), s=revision_set
    )


def chunk_copy_query(
    layout: ChunkTable,
    geoids: Sequence[int],
    revisions: Sequence[int] | None = None,
    *,
    where: sql.Composable | None = None,
) -> sql.Composed:
    """The COPY of the visible chunk versions of ``geoids``: their columns for :func:`~tgsis._chunks.from_copy`.

    For one object the stream is :func:`from_copy`'s as it is; for several, each row starts with
    ``geoid`` (rows in no order), which :func:`split_copy` takes off. ``revisions``: the set of
    :func:`visible_chunks` (default: the session's). ``where``: an SQL condition on the chunk ``c`` choosing
    the chunks read (e.g. those holding a G-map period's darts, :func:`object_rows`); None: every chunk.
    """
    columns = sql.SQL(", ").join(sql.SQL("c.{}").format(sql.Identifier(c)) for c in layout.columns.select_columns())
    key = sql.Identifier(layout.columns.key)
    visible = visible_chunks(layout, revisions)
    if where is not None:
        visible = sql.SQL("({}) AND {}").format(where, visible)
    if len(geoids) == 1:
        select = sql.SQL("SELECT {} FROM {} c WHERE c.{} = {} AND {}").format(
            columns, layout.relation, key, sql.Literal(int(geoids[0])), visible
        )
    else:
        select = sql.SQL("SELECT c.{}, {} FROM {} c WHERE c.{} = ANY ({}::bigint[]) AND {}").format(
            key, columns, layout.relation, key, sql.Literal([int(g) for g in geoids]), visible
        )
    return sql.SQL("COPY ({}) TO STDOUT (FORMAT binary)").format(select)


def split_copy(payload: bytes) -> dict[int, bytes]:
    """A binary COPY stream whose rows start with a ``bigint`` geoid as one stream per geoid, without that field.

    Walks the rows' field lengths (a few thousand rows per million ids); the values are not parsed here.

    Raises
    ------
    InvalidInputError
        Not a binary COPY stream, or a row whose first field is not a bigint.
    """
    view = memoryview(payload)
    if bytes(view[:11]) != COPY_SIGNATURE:
        raise InvalidInputError("not a PostgreSQL binary COPY stream (no PGCOPY signature)")
    pos = 19 + int.from_bytes(view[15:19], "big")
    header = bytes(view[:pos])
    pieces: dict[int, list[Any]] = {}
    try:
        while True:
            count = int.from_bytes(view[pos : pos + 2], "big", signed=True)
            if count == -1:
                break
            if count < 1 or int.from_bytes(view[pos + 2 : pos + 6], "big", signed=True) != 8:
                raise InvalidInputError("a chunk row does not start with a bigint geoid")
            geoid = int.from_bytes(view[pos + 6 : pos + 14], "big", signed=True)
            start = pos + 14
            pos = start
            for _ in range(count - 1):
                length = int.from_bytes(view[pos : pos + 4], "big", signed=True)
                pos += 4 + max(length, 0)
            if pos > len(view):
                raise IndexError
            out = pieces.setdefault(geoid, [header])
            out.append((count - 1).to_bytes(2, "big", signed=True))
            out.append(view[start:pos])
    except IndexError:
        raise InvalidInputError("binary COPY data ends inside a row") from None
    trailer = b"\xff\xff"
    return {geoid: b"".join([*parts, trailer]) for geoid, parts in pieces.items()}


def split_first_field(payload: bytes) -> tuple[list[bytes | None], bytes]:
    """A binary COPY stream as each row's first field (its raw bytes, None when NULL) and the stream without it.

    For a COPY whose rows start with a value the codec does not read (the place of a chunk version a
    check-in bases its chunk on), read in the same statement as the chunks themselves.

    Raises
    ------
    InvalidInputError
        Not a binary COPY stream, or one that ends inside a row.
    """
    view = memoryview(payload)
    if bytes(view[:11]) != COPY_SIGNATURE:
        raise InvalidInputError("not a PostgreSQL binary COPY stream (no PGCOPY signature)")
    pos = 19 + int.from_bytes(view[15:19], "big")
    out: list[Any] = [view[:pos]]
    firsts: list[bytes | None] = []
    try:
        while True:
            count = int.from_bytes(view[pos : pos + 2], "big", signed=True)
            if count == -1:
                break
            if count < 1:
                raise InvalidInputError("a COPY row without fields")
            length = int.from_bytes(view[pos + 2 : pos + 6], "big", signed=True)
            firsts.append(None if length < 0 else bytes(view[pos + 6 : pos + 6 + length]))
            start = pos + 6 + max(length, 0)
            pos = start
            for _ in range(count - 1):
                length = int.from_bytes(view[pos : pos + 4], "big", signed=True)
                pos += 4 + max(length, 0)
            if pos > len(view):
                raise IndexError
            out.append((count - 1).to_bytes(2, "big", signed=True))
            out.append(view[start:pos])
    except IndexError:
        raise InvalidInputError("binary COPY data ends inside a row") from None
    out.append(b"\xff\xff")
    return firsts, b"".join(out)


def _copy_out(conn: Conn, query: sql.Composed) -> bytes:
    with conn.cursor().copy(query) as copy:
        return b"".join(bytes(block) for block in copy)


def _objects(layout: ChunkTable, geoids: Sequence[int], payload: bytes) -> dict[int, ObjectRows]:
    """Each wanted object's rows from the COPY of :func:`chunk_copy_query` (no chunk: no rows)."""
    streams = {int(geoids[0]): payload} if len(geoids) == 1 else split_copy(payload)
    result: dict[int, ObjectRows] = {}
    for geoid in geoids:
        stream = streams.get(int(geoid))
        chunks = from_copy(stream, layout.columns) if stream is not None else None
        result[int(geoid)] = _rows(int(geoid), chunks, layout.columns)
    return result


def _rows(geoid: int, chunks: ChunkSet | None, spec: ChunkColumns) -> ObjectRows:
    if chunks is None or not len(chunks.chunk):
        empty = {n: np.empty(spec.shape(n, 0), dtype=spec.dtype(n)) for n in spec.names}
        return ObjectRows(geoid, np.empty(0, dtype=np.int64), empty)
    ids, columns = chunks.rows()
    holes = np.empty(0, dtype=np.int64) if chunks.present.all() else chunks.ids()[~chunks.present]
    return ObjectRows(geoid, ids, columns, holes, chunks.null_rows())


def object_rows(conn: Conn, layout: ChunkTable, geoid: int, where: sql.Composable | None = None) -> ObjectRows:
    """One object's rows of a chunk table keyed ``geoid, chunk`` from the chunk versions the session sees, decoded here.

    One binary COPY (:func:`chunk_copy_query`) with the role's rights, as :func:`download_chunks` reads.

    Parameters
    ----------
    layout : ChunkTable
        :func:`chunk_table` of a table without instant keys (``vrtx``, ``gmap_dart``, ``md_vertex``, ...).
    geoid : int
    where : sql.Composable, optional
        An SQL condition on the chunk ``c`` choosing the chunks read (the rows of the others are not in the
        answer); None: every chunk.

    Returns
    -------
    ObjectRows
        Ids ascending (n,), each column (n,) or (n, m) for points, the holes; nothing when no chunk is read.

    Raises
    ------
    InvalidInputError
        A layout with instant keys, or chunks that break the contract (the codec refuses them).
    """
    if layout.columns.instant:
        raise InvalidInputError(
            f"tgsis.{layout.table}_chunk is keyed by {list(layout.columns.instant)} too: read it by instant_rows"
        )
    return _objects(layout, [geoid], _copy_out(conn, chunk_copy_query(layout, [geoid], where=where)))[int(geoid)]


def download_chunks(conn: Conn, table: str, geoids: Sequence[int]) -> dict[int, ObjectRows]:
    """The rows of ``tgsis.<table>`` of objects ``geoids`` as the session's version sees them, from their chunks.

    One ``COPY ... TO STDOUT (FORMAT binary)`` of the visible chunk versions (today's visibility test of the
    versioned views; every chunk of unversioned storage), read with the role's rights (the chunk table's
    grants and row-level security: a class the role may not read has no rows).

    Parameters
    ----------
    table : str
        A row table with a chunk table.
    geoids : sequence of int

    Returns
    -------
    dict of int to ObjectRows
        Per geoid (every one asked; an object without visible chunks has no rows): ids ascending,
        the columns in id order, the holes.
    """
    return download_tables(conn, {table: geoids})[table]


def download_tables(
    conn: Conn, requests: Mapping[str, Sequence[int]], side: Conn | None = None
) -> dict[str, dict[int, ObjectRows]]:
    """:func:`download_chunks` of several tables, one COPY each, all of one state (:func:`consistent_read`).

    Outside a transaction the COPYs run in one read-only repeatable-read transaction: a writer that
    commits between them is seen by none or all of them. Inside the caller's ``READ COMMITTED``
    one, they are read again when another session committed between them (our ``TG003`` after a few tries).

    Parameters
    ----------
    conn : psycopg.Connection
    requests : mapping of str to sequence of int
        The geoids to read of each table.
    side : psycopg.Connection, optional
        A second connection of the same role, outside a transaction: the last table's COPY runs on it,
        side by side with the others (bench/chunk_transfer.py measures what that gains), in the snapshot
        ``conn`` exports to it (``pg_export_snapshot``) and with ``conn``'s session's set of revisions.
        Used only when ``conn`` is outside a transaction too (a snapshot is not exported from a savepoint)
        and more than one table is asked; else everything runs on ``conn``.

    Raises
    ------
    InvalidInputError
        ``side`` logs in as another role than ``conn``, to another database, or is inside a transaction.
    """
    wanted = {table: list(dict.fromkeys(int(g) for g in geoids)) for table, geoids in requests.items()}
    idle = psycopg.pq.TransactionStatus.IDLE
    parallel = side is not None and len(wanted) > 1 and conn.info.transaction_status == idle

    def read() -> dict[str, dict[int, ObjectRows]]:
        """Every table's COPY, of one state (:func:`~tgsis.db._transfer.consistent_read`)."""
        result: dict[str, dict[int, ObjectRows]] = {}
        asked = dict(wanted)
        with concurrent.futures.ThreadPoolExecutor(1) as pool:
            layouts = {table: chunk_table(conn, table) for table in asked}
            pending = None
            if parallel and side is not None:
                row = conn.execute(
                    "SELECT pg_export_snapshot(), current_user::text, tgsis.get_revisions(true), current_database()::text"
                ).fetchone()
                assert row is not None
                snapshot, role, revisions, database = row
                if side.info.dbname != database:
                    raise InvalidInputError(
                        f"the second connection of a download is to database {side.info.dbname!r}, not {database!r}",
                        detail="a snapshot is shared within one database only",
                    )
                last = list(asked)[-1]
                pending = pool.submit(_side_copy, side, snapshot, role, layouts[last], asked[last], revisions)
                asked = {table: geoids for table, geoids in asked.items() if table != last}
            for table, geoids in asked.items():
                layout = layouts[table]
                result[table] = (
                    _objects(layout, geoids, _copy_out(conn, chunk_copy_query(layout, geoids))) if geoids else {}
                )
            if pending is not None:
                table, payload, geoids = pending.result()
                result[table] = _objects(layouts[table], geoids, payload) if geoids else {}
        return result

    result = consistent_read(conn, "download_tables", read)
    return {table: result[table] for table in requests}


def _side_copy(
    side: Conn, snapshot: str, role: str, layout: ChunkTable, geoids: list[int], revisions: Sequence[int]
) -> tuple[str, bytes, list[int]]:
    """One table's COPY on the second connection of :func:`download_tables`, in the snapshot it was given."""
    if side.info.transaction_status != psycopg.pq.TransactionStatus.IDLE:
        raise InvalidInputError("the second connection of a download is inside a transaction")
    with read_only_snapshot(side):
        side.execute(sql.SQL("SET TRANSACTION SNAPSHOT {}").format(sql.Literal(snapshot)))
        row = side.execute("SELECT current_user::text").fetchone()
        if row is None or row[0] != role:
            raise InvalidInputError(
                f"the second connection of a download logs in as {row[0] if row else None!r}, not as {role!r}",
                detail="it would read with another role's rights",
            )
        payload = _copy_out(side, chunk_copy_query(layout, geoids, revisions)) if geoids else b""
    return layout.table, payload, geoids


@dataclass(frozen=True)
class PackedChunks:
    """A chunk table's part of :func:`~tgsis.db._transfer.columns_out_all`: an object's rows, read from its chunks.

    What a :class:`~tgsis.db._transfer.Packed` request of ``tgsis.<table>`` gives (``[geoid, ids,
    *columns]``, rows in no order), from the chunk versions the session sees (:func:`download_chunks`'s
    test), in the same query as the other parts (one snapshot, whatever the isolation level). Per object
    the server sends its chunk rows as ``record_send`` values joined into one ``bytea``
    (:func:`records_as_copy` makes them a binary COPY stream for :func:`~tgsis._chunks.from_copy`).

    Attributes
    ----------
    layout : ChunkTable
    geoids : sequence of int
    columns : sequence of str
        The row table's columns wanted after ``geoid``: the local id (its chunk column, e.g. ``vrtxid``)
        first, then array columns of the chunk table, in any order.
    """

    layout: ChunkTable
    geoids: Sequence[int]
    columns: Sequence[str]

    def __post_init__(self) -> None:
        unknown = [c for c in self.columns[1:] if c not in self.layout.columns.names]
        if not self.columns or unknown:
            raise InvalidInputError(
                f"tgsis.{self.layout.table}_chunk has no arrays {unknown} (it has {list(self.layout.columns.names)})"
            )

    @property
    def source(self) -> sql.Composed:
        """The relation read: ``tgsis.<table>_chunk`` (as :attr:`Packed.source <tgsis.db._transfer.Packed>`)."""
        return self.layout.relation

    def query(self, part: int) -> sql.Composed:
        """The rows ``(part, geoid, chunk rows, their record_send values joined)``: one per object with chunks."""
        record = sql.SQL("record_send(ROW({}))").format(
            sql.SQL(", ").join(sql.SQL("c.{}").format(sql.Identifier(c)) for c in self.layout.columns.select_columns())
        )
        visible = visible_chunks(self.layout)
        if len(self.geoids) == 1:
            return sql.SQL(
                "SELECT {part}::int4, {geoid}::int8, count(*), string_agg({record}, ''::bytea) FROM {source} c "
                "WHERE c.{key} = {geoid} AND {visible}"
            ).format(
                key=sql.Identifier(self.layout.columns.key),
                part=sql.Literal(part),
                geoid=sql.Literal(int(self.geoids[0])),
                record=record,
                source=self.layout.relation,
                visible=visible,
            )
        return sql.SQL(
            "SELECT {part}::int4, g.k, a.n, a.v FROM (SELECT DISTINCT unnest({geoids}::int8[]) AS k) g "
            "CROSS JOIN LATERAL (SELECT count(*) AS n, string_agg({record}, ''::bytea) AS v FROM {source} c "
            "WHERE c.{key} = g.k AND {visible}) a"
        ).format(
            key=sql.Identifier(self.layout.columns.key),
            part=sql.Literal(part),
            geoids=sql.Literal([int(g) for g in self.geoids]),
            record=record,
            source=self.layout.relation,
            visible=visible,
        )

    def decode(self, conn: Conn, groups: Sequence[tuple[int, int, bytes]]) -> list[npt.NDArray[Any]]:
        """``[geoid, ids, *columns]`` (n,) each from the objects' ``(geoid, chunk rows, record_send values)``."""
        spec = self.layout.columns
        objects = [_rows(geoid, from_copy(records_as_copy(data, count), spec), spec) for geoid, count, data in groups]
        for o in objects:  # a NULL value where a value is read: as the rows' packed read refuses it
            missing = [name for name in self.columns[1:] if name in o.nulls and o.nulls[name].any()]
            if missing:
                raise DatabaseError(
                    f"{self.layout.schema}.{self.layout.table}: object {o.geoid} has NULL values of {missing} "
                    f"({int(o.nulls[missing[0]].sum())} of {missing[0]})",
                    detail="a mesh property holds a value for every vertex or cell",
                )
        counts = [len(o.ids) for o in objects]
        geoids = np.repeat(np.asarray([o.geoid for o in objects], dtype=np.int64), counts)
        ids = np.concatenate([np.empty(0, dtype=np.int64), *(o.ids for o in objects)])
        values = [
            np.concatenate([np.empty(spec.shape(name, 0), dtype=spec.dtype(name)), *(o.columns[name] for o in objects)])
            for name in self.columns[1:]
        ]
        return [geoids, ids, *values]


def rows_request(
    conn: Conn, table: str, columns: Sequence[tuple[str, str]], geoids: Sequence[int], chunked: frozenset[str]
) -> PartRequest:
    """A model table's part of :func:`~tgsis.db._transfer.columns_out_all`: from its chunks when it is stored in them.

    Parameters
    ----------
    table : str
        A model-1 table of ``tgsis`` keyed by ``geoid`` (``vrtx``, ``trgl``, ...).
    columns : sequence of (str, str)
        ``(name, wire type)`` after ``geoid``: the local id first.
    geoids : sequence of int
    chunked : frozenset of str
        :func:`chunked_tables`.

    Returns
    -------
    Packed or PackedChunks
        The rows of ``tgsis.<table>`` (rows storage), or of ``tgsis.<table>_chunk``; of the face
        ``tgsis.<table>`` still for a role that may read the face but not the chunk table (a DBA's grant
        on the relation users query: it reads what it read before the switch, decoded by the server).
    """
    if table in chunked:
        layout = chunk_table(conn, table)
        if layout.readable:
            return PackedChunks(layout, geoids, [name for name, _ in columns])
    return Packed(sql.SQL("tgsis.{}").format(sql.Identifier(table)), "geoid", columns, geoids)


def records_as_copy(data: bytes, count: int) -> bytes:
    """``count`` joined ``record_send`` values as one binary COPY stream of their rows (header, rows, trailer).

    A ``record_send`` value is ``int4`` fields, then per field its type's oid, length and bytes; a COPY row is
    ``int2`` fields, then per field its length and bytes. Walks the fields (a few per chunk row).

    Raises
    ------
    InvalidInputError
        The values end inside a record, or bytes are left after ``count`` records.
    """
    view = memoryview(data)
    out: list[Any] = [COPY_SIGNATURE + bytes(8)]  # flags 0, no header extension
    pos = 0
    size = len(view)
    unpack = _INT4.unpack_from  # a few times faster than int.from_bytes of a slice, per value
    try:
        for _ in range(count):
            (fields,) = unpack(view, pos)
            out.append(fields.to_bytes(2, "big", signed=True))
            pos += 4
            for _ in range(fields):
                (length,) = unpack(view, pos + 4)
                end = pos + 8 + max(length, 0)
                if end > size:
                    raise IndexError
                out.append(view[pos + 4 : end])
                pos = end
    except (IndexError, OverflowError, struct.error):
        raise InvalidInputError("chunk records end inside a record") from None
    if pos != len(view):
        raise InvalidInputError(f"{len(view) - pos} bytes after {count} chunk records")
    out.append(b"\xff\xff")
    return b"".join(out)


#: a big-endian int4 (the counts and lengths of record_send values)
_INT4 = struct.Struct(">i")


# --------------------------------------------------------------------------- the time tables of models 2 and 3

#: what :func:`instant_rows` returns: per object and instant, ``(geoid, *instant keys)``, its rows
InstantKey = tuple[float, ...]


def instant_layout(conn: Conn, table: str, chunked: frozenset[str]) -> ChunkTable | None:
    """The chunk table of a time table (``times_vrtx``, ``times_trgl``, ``d4dvrtx``, ``d4dtrgl``) when its rows are read from it.

    Parameters
    ----------
    chunked : frozenset of str
        :func:`chunked_tables`.

    Returns
    -------
    ChunkTable or None
        None while the table is stored as rows, or for a role that may read the face but not the chunk
        table (it reads through the face, decoded by the server, what it read before). Its
        ``columns.instant`` are the instant keys (``("times",)``, ``("timem", "timet")``, ``("timem",)``).
    """
    if table not in chunked:
        return None
    layout = chunk_table(conn, table, instants=True)
    return layout if layout.readable else None


def instant_rows(
    conn: Conn, layout: ChunkTable, geoids: Sequence[int], where: sql.Composable | None = None
) -> dict[InstantKey, ObjectRows]:
    """The rows of a time table (models 2 and 3) of objects ``geoids`` at their instants, from the chunks the session sees.

    One query: per object and instant the server joins the visible chunk versions' ``record_send`` values
    (the versioned views' test, :func:`visible_chunks`; every chunk of unversioned storage) into one ``bytea``,
    decoded here (:func:`records_as_copy`, :func:`~tgsis._chunks.from_copy`), as model 1's download
    (:class:`PackedChunks`). Read with the role's rights (grants, row-level security). The instants come
    in binary (their bits); no value travels as text.

    Parameters
    ----------
    layout : ChunkTable
        :func:`instant_layout`.
    geoids : sequence of int
    where : sql.Composable, optional
        An SQL condition choosing the instants read, in terms of the object's ``f.geoid`` and the chunk's
        instant keys ``c.<key>`` (e.g. ``c.times = tgsis.instant_at(f.geoid, t, convention)``: the snapshot's
        instant, chosen in the same query); None: every instant.

    Returns
    -------
    dict of tuple to ObjectRows
        Per ``(geoid, *instant keys)`` with chunks (the instant keys as the chunks store them): ids ascending,
        the columns in id order. An instant with no visible chunk is not in it.

    Raises
    ------
    InvalidInputError
        Chunks that break the contract (the codec refuses them).
    """
    spec = layout.columns
    record = sql.SQL("record_send(ROW({}))").format(
        sql.SQL(", ").join(sql.SQL("c.{}").format(sql.Identifier(c)) for c in spec.select_columns())
    )
    at = sql.SQL("") if where is None else sql.SQL(" AND ({})").format(where)
    keys = sql.SQL(", ").join(sql.SQL("c.{}").format(sql.Identifier(k)) for k in spec.instant)
    # grouped by blocks of chunks too: a bytea holds 1 GB at most, and array_send writes 4 bytes per element
    # more (a 40M-triangle instant in one value would pass it); the client joins an instant's blocks
    query = sql.SQL(
        "SELECT f.geoid, a.* FROM unnest({geoids}::int8[]) AS f(geoid) "
        "CROSS JOIN LATERAL (SELECT {keys}, count(*) AS n, string_agg({record}, ''::bytea) AS v FROM {source} c "
        "WHERE c.geoid = f.geoid{at} AND {visible} GROUP BY {keys}, c.chunk >> {bits}) a"
    ).format(
        geoids=sql.Literal(list(dict.fromkeys(int(g) for g in geoids))),
        keys=keys,
        record=record,
        source=layout.relation,
        at=at,
        visible=visible_chunks(layout),
        bits=sql.Literal(INSTANT_BLOCK_BITS),
    )
    with conn.cursor(binary=True) as cursor:
        groups = cursor.execute(query).fetchall()
    blocks: dict[InstantKey, list[tuple[int, bytes]]] = {}
    k = len(spec.instant)
    for row in groups:  # (an instant's -0.0 and 0.0 are one key, as the face groups them)
        key = (int(row[0]), *(float(v) for v in row[1 : 1 + k]))
        blocks.setdefault(key, []).append((int(row[1 + k]), bytes(row[2 + k])))
    result: dict[InstantKey, ObjectRows] = {}
    for key, parts in blocks.items():
        data = parts[0][1] if len(parts) == 1 else b"".join(d for _, d in parts)
        chunks = from_copy(records_as_copy(data, sum(n for n, _ in parts)), spec)
        result[key] = _rows(int(key[0]), chunks, spec)
    return result


#: :func:`instant_rows` sends an instant's chunks in blocks of 2**8 chunks (262,144 ids, about 10 MB)
INSTANT_BLOCK_BITS = 8


def repeated_corners(corners: Sequence[npt.NDArray[np.int64]]) -> npt.NDArray[np.bool_]:
    """(m,) bool: the cells whose corners (k columns of (m,) vertex ids) name a vertex twice.

    What the row tables' CHECK refuses (``<table>_distinct_vertices``, ``d4dtrgl_distinct_nodes``) and the
    chunk tables have not: a client upload checks it (a mesh's cells changed after it was made).
    Every pair of corners compared: k(k - 1)/2 passes, cheaper than sorting each row for k <= 4.
    """
    repeated = np.zeros(len(corners[0]) if corners else 0, dtype=bool)
    for i in range(len(corners)):
        for j in range(i + 1, len(corners)):
            repeated |= corners[i] == corners[j]
    return repeated


def _repeated_refs(layout: ChunkTable, columns: Mapping[str, npt.NDArray[Any]]) -> None:
    """Refuse a cell naming a vertex (node) twice (:func:`repeated_corners`).

    Raises
    ------
    InvalidGeometryError
        Naming the first such row (nothing is sent).
    """
    refs = [np.asarray(columns[c]) for c in layout.columns.ref_order]
    repeated = repeated_corners(refs)
    if repeated.any():
        row = int(np.flatnonzero(repeated)[0])
        raise InvalidGeometryError(
            f"tgsis.{layout.table}: cell row {row} uses a vertex twice: {[int(r[row]) for r in refs]}",
            detail=f"{int(repeated.sum())} cells repeat a vertex (the row table's CHECK of distinct vertices); "
            "nothing was written",
        )


def upload_instants(
    conn: Conn,
    table: str,
    geoid: int,
    instants: Sequence[InstantKey],
    counts: Sequence[int],
    columns: Mapping[str, npt.NDArray[Any]],
    storage: Storage,
    first_ids: Sequence[int] | None = None,
) -> bool:
    """Write new instants' rows of a time table (models 2 and 3) as chunk rows encoded here: one binary COPY.

    The upload of model 2 (``insert_series``, ``add_instant``: ``times_vrtx``, ``times_trgl``) and model 3
    (``insert_evolving``, ``append_period``: ``d4dvrtx``, ``d4dtrgl``) into a time table stored in chunks, as
    model 1's :func:`upload_chunks`: the rows of instant ``instants[i]`` (its instant keys, e.g. ``(times,)``
    or ``(timem, timet)``) are ``counts[i]`` consecutive rows of ``columns`` with ids
    ``first_ids[i] .. first_ids[i] + counts[i] - 1`` (default from 0); each instant's chunks are encoded by
    numpy with the instant's bits as key and COPied into ``tgsis.<table>_chunk`` in the session's working
    revision (0 for unversioned storage and features of classes without versioning) as the role (the chunk
    table's grants and row-level security: the class's right; its insert trigger checks the encoding and,
    unversioned, revision 0), after the checks ``tgsis.insert_chunk_rows`` makes of an existing object: the
    row table's CHECK of distinct cell corners, not locked by another version (TG303), its write lock taken
    (no face writer of it in flight). The object is noted as changed in the working revision.

    Returns
    -------
    bool
        False, with nothing written, when the chunk table holds chunks of one of these instants of the
        object already (in any version or revision, of these bits or others): the caller then writes
        through ``tgsis.insert_chunk_rows`` (:meth:`Storage.copy`), which refuses a visible key (23505),
        a key of other bits (TG100), and rewrites a chunk of the working revision in place.

    Raises
    ------
    InvalidInputError
        Columns that are not the table's, instant keys that are not its, or values the codec refuses
        (nothing is sent).
    InvalidGeometryError
        A cell naming one vertex twice (nothing is sent).
    NotVersionedError, ReadOnlyRevisionError
        The session may not write here.
    psycopg.errors.InsufficientPrivilege
        The role lacks INSERT on the chunk table, or the class's right.
    """
    layout = chunk_table(conn, table, instants=True)
    if sorted(columns) != sorted(layout.columns.names):
        raise InvalidInputError(
            f"tgsis.{table}: an upload gives the columns {sorted(layout.columns.names)}, not {sorted(columns)}"
        )
    keys_of = [tuple(float(v) for v in key) for key in instants]
    width = len(layout.columns.instant)
    if any(len(key) != width for key in keys_of) or len(counts) != len(keys_of):
        raise InvalidInputError(
            f"tgsis.{table}: each of the {len(counts)} instants is given by {list(layout.columns.instant)}",
            detail=f"instants {keys_of[:5]}",
        )
    storage.check("tgsis", table)
    versioned = ("tgsis", table) in storage.versioned
    revision = int(storage.revision or 0) if versioned else 0
    _repeated_refs(layout, columns)
    starts = np.cumsum([0, *counts]).tolist()
    firsts = [0] * len(counts) if first_ids is None else [int(f) for f in first_ids]
    encoded = [  # encode first: bad input is refused before anything is sent
        encode(
            np.arange(first, first + n, dtype=np.int64),
            {k: v[start : start + n] for k, v in columns.items()},
            layout.columns,
        )
        for start, n, first in zip(starts, counts, firsts)
    ]
    if not keys_of:
        return True
    objects = [str(int(geoid))]
    if versioned:
        conn.execute("SELECT tgsis.check_objects_unlocked('feature', %s::text[])", (objects,))  # TG303
    conn.execute("SELECT tgsis.object_write_lock('feature', %s::text[])", (objects,))  # no face writer of it in flight
    names = layout.columns.instant
    existing = conn.execute(  # (the instants' bits in binary: never through text)
        sql.SQL("SELECT EXISTS (SELECT FROM {} c WHERE c.geoid = %s AND ({}) IN (SELECT * FROM unnest({})))").format(
            layout.relation,
            sql.SQL(", ").join(sql.SQL("c.{}").format(sql.Identifier(k)) for k in names),
            sql.SQL(", ").join(sql.SQL("%b::float8[]") for _ in names),
        ),
        (int(geoid), *([key[i] for key in keys_of] for i in range(width))),
    ).fetchone()
    if existing is None or existing[0]:
        return False
    copy_columns = layout.columns.copy_columns()
    statement = sql.SQL("COPY {} ({}) FROM STDIN (FORMAT binary)")
    with staged(conn, layout.relation, copy_columns) as into:
        with conn.cursor().copy(statement.format(into, sql.SQL(", ").join(map(sql.Identifier, copy_columns)))) as copy:
            for k, (chunks, key) in enumerate(zip(encoded, keys_of)):
                stream = to_copy(chunks, int(geoid), revision, key)
                # one stream: the header once, the trailer once
                copy.write(memoryview(stream)[19 if k else 0 : -2 if k < len(encoded) - 1 else None])
    if layout.versioned and revision != 0:
        conn.execute("SELECT tgsis.record_changed_objects('tgsis', %s, %s::text[])", (table, objects))
    return True


def write_instants(
    conn: Conn,
    table: str,
    geoid: int,
    instants: Sequence[InstantKey],
    counts: Sequence[int],
    columns: Mapping[str, npt.NDArray[Any]],
    storage: Storage,
    first_ids: Sequence[int] | None = None,
    *,
    keys: Sequence[str],
    idcolumn: str,
) -> None:
    """Write new instants' rows of a time table (models 2 and 3): chunks encoded here, else rows.

    The rows are :func:`upload_instants`' (instant ``instants[i]``, whose key columns are ``keys``, has
    ``counts[i]`` consecutive rows of ``columns`` with ``idcolumn`` ``first_ids[i] ..``, default from 0). A
    table stored in chunks takes them by :func:`upload_instants` (one binary COPY of chunks) unless it
    declines (chunks of one of these instants there already); then, and for a table stored as rows, they
    go through :meth:`Storage.copy` (a COPY of rows, or ``tgsis.insert_chunk_rows``). Columns of floats
    travel as ``float8``, the others as ``int8``.

    Raises
    ------
    InvalidInputError, InvalidGeometryError, NotVersionedError, ReadOnlyRevisionError
        As :func:`upload_instants` and :meth:`Storage.copy` (nothing is written).
    """
    if ("tgsis", table) in storage.chunked and upload_instants(
        conn, table, geoid, instants, counts, columns, storage, first_ids
    ):
        return
    firsts = list(first_ids) if first_ids is not None else [0] * len(counts)
    total = int(sum(counts))
    ids = [np.arange(c, dtype=np.int64) + f for c, f in zip(counts, firsts, strict=True)]
    storage.copy(
        conn,
        "tgsis",
        table,
        [
            ("geoid", np.full(total, geoid, dtype=np.int64), "int8"),
            *(
                (name, np.repeat(np.asarray([k[i] for k in instants], dtype=np.float64), counts), "float8")
                for i, name in enumerate(keys)
            ),
            (idcolumn, np.concatenate(ids) if ids else np.zeros(0, dtype=np.int64), "int8"),
            *((name, values, "float8" if values.dtype.kind == "f" else "int8") for name, values in columns.items()),
        ],
    )


def upload_rows(conn: Conn, table: str, columns: Sequence[tuple[str, npt.ArrayLike, str]], storage: Storage) -> bool:
    """Write a new G-map's darts, involutions or points as chunk rows encoded here: one binary COPY (plan K G2; M, Q).

    The upload of ``insert_gmap`` / ``insert_md_gmap`` into ``gmap_dart``, ``md_dart``, ``gmap_alpha``,
    ``md_alpha``, ``gmap_vertex`` or ``md_vertex`` stored in chunks (:meth:`Storage.copy_all`), as model 1's :func:`upload_chunks` and models 2
    and 3's :func:`upload_instants`: the rows are grouped by their keys before ``chunk`` (``geoid``, and
    ``level`` for the involutions), each group's chunks encoded by numpy (:func:`~tgsis._chunks.encode`: the
    point or image a ref column relative to the chunk's smallest, ``acellid`` and ``positive`` arrays that may
    hold NULL) and COPied in binary into ``tgsis.<table>_chunk`` in the session's working revision (0 for
    unversioned storage and features of classes without versioning) as the role: the chunk table's grants and
    row-level security (the class's right), its insert trigger (the encoding, and revision 0 when
    unversioned); after the checks ``tgsis.insert_chunk_rows`` makes: not locked by another version (TG303),
    the object's write lock taken. The objects are noted as changed in the working revision.

    A G-map's points (``gmap_vertex``, ``md_vertex``: wire type ``float8[m]``, values (n, m)) are encoded as
    the server's writer encodes them (role ``point``: one 2-D array per chunk, slots x m, a hole m NULLs); every
    point has the object's m coordinates (the wire type's, the embedding the upload states), checked before
    anything is sent.

    Parameters
    ----------
    columns : sequence of (str, (n,) array_like, str)
        ``(name, values, wire type)`` as :meth:`Storage.copy` takes them: every column of the row table once
        (the key columns, the id column, the arrays), those that may be NULL (``acellid``, ``positive``) left
        out when NULL in every row; a point column (n, m).

    Returns
    -------
    bool
        False, with nothing written, when the chunk table holds chunks of one of these objects already (in any
        version or revision), or the role may not read the chunk table (granted the face alone), or a key is
        negative (a ``level``: the row table's CHECK, which the server's path applies): the caller then writes
        through ``tgsis.insert_chunk_rows`` (:meth:`Storage.copy`), which answers as the rows would.

    Raises
    ------
    InvalidInputError
        Columns that are not the table's, keys that are not integers, or values the codec refuses (nothing is
        sent).
    NotVersionedError, ReadOnlyRevisionError
        The session may not write here.
    psycopg.errors.InsufficientPrivilege
        The role lacks INSERT on the chunk table, or the class's right.
    """
    layout = chunk_table(conn, table, values=True)
    if not layout.readable:  # a role granted the face alone: the server's path, which answers as the rows
        return False
    spec = layout.columns
    if not spec.points and any(wire.startswith("float8[") for _, _, wire in columns):
        raise InvalidInputError(f"tgsis.{table} has no points: columns {[(n, w) for n, _, w in columns]}")
    given = {
        name: _points(table, name, values, wire, columns) if name in spec.points else np.asarray(values)
        for name, values, wire in columns
    }
    keys = ("geoid", *spec.instant)
    extra = [n for n in given if n not in keys and n not in spec.names]
    missing = [n for n in (*keys, *spec.names) if n not in given and not spec.nullable(n)]
    if len(given) != len(columns) or len(extra) != 1 or missing:
        raise InvalidInputError(
            f"tgsis.{table}: an upload gives the keys {list(keys)}, one id column and the columns "
            f"{list(spec.names)} once each (those that may be NULL may be left out)",
            detail=f"given {[name for name, _, _ in columns]}",
        )
    ids = given[extra[0]]
    count = len(ids)
    if any(v.shape[:1] != (count,) or (v.ndim != 1 and n not in spec.points) for n, v in given.items()):
        raise InvalidInputError(
            f"tgsis.{table}: every column of an upload has one value per row ({count})",
            detail=f"shapes {[(n, v.shape) for n, v in given.items()]}",
        )
    floats = {k for k, kind in zip(spec.instant, spec.instant_kinds) if kind == "float8"}  # a point's timem, timet
    if any(given[k].size and given[k].dtype.kind not in ("f" if k in floats else "iu") for k in keys):
        raise InvalidInputError(
            f"tgsis.{table}: the key columns {list(keys)} of an upload are integers"
            + (f" ({sorted(floats)} float64)" if floats else ""),
            detail=f"types {[(k, str(given[k].dtype)) for k in keys]}",
        )
    if any(given[k].size and int(given[k].min()) < 0 for k in keys if k not in floats):
        return False  # the row table's CHECK (level >= 0), which the server's path applies (23514)
    if any(
        given[k].size and bool((np.isnan(given[k]) | ((given[k] == 0) & np.signbit(given[k]))).any()) for k in floats
    ):
        return False  # an instant -0.0 or NaN: equal to other bits as a key; the server's path answers as the rows
    storage.check("tgsis", table)
    revision = int(storage.revision or 0) if ("tgsis", table) in storage.versioned else 0
    # the groups of rows by their keys before chunk (an object's darts; an object's involution of one level)
    # (a float key by its bits: one group per instant as given)
    stacked = np.stack(
        [given[k].astype(np.float64).view(np.int64) if k in floats else given[k].astype(np.int64) for k in keys], axis=1
    )
    groups, inverse, sizes = np.unique(stacked, axis=0, return_inverse=True, return_counts=True)
    order = np.argsort(inverse.reshape(-1), kind="stable")
    bounds = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
    encoded = []  # encode first: bad input is refused before anything is sent
    for g in range(len(groups)):
        rows = order[bounds[g] : bounds[g + 1]]
        values: dict[str, npt.NDArray[Any]] = {}
        nulls: dict[str, npt.NDArray[np.bool_]] = {}
        for name in spec.names:
            if name in given:
                values[name] = given[name][rows]
            else:  # left out: NULL in every row, as a COPY leaves it
                values[name] = np.zeros(len(rows), dtype=spec.dtype(name))
                nulls[name] = np.ones(len(rows), dtype=bool)
        key = tuple(
            float(np.int64(v).view(np.float64)) if name in floats else int(v) for name, v in zip(keys, groups[g])
        )
        encoded.append((encode(ids[rows], values, spec, nulls), key))
    if not encoded:
        return True
    objects = [str(g) for g in sorted({int(key[0]) for _, key in encoded})]
    if ("tgsis", table) in storage.versioned:
        conn.execute("SELECT tgsis.check_objects_unlocked('feature', %s::text[])", (objects,))  # TG303
    conn.execute("SELECT tgsis.object_write_lock('feature', %s::text[])", (objects,))  # no face writer in flight
    existing = conn.execute(
        sql.SQL("SELECT EXISTS (SELECT FROM {} WHERE geoid = ANY (%s::int8[]))").format(layout.relation),
        ([int(g) for g in objects],),
    ).fetchone()
    if existing is None or existing[0]:
        return False
    copy_columns = spec.copy_columns()
    statement = sql.SQL("COPY {} ({}) FROM STDIN (FORMAT binary)")
    with staged(conn, layout.relation, copy_columns) as into:
        with conn.cursor().copy(statement.format(into, sql.SQL(", ").join(map(sql.Identifier, copy_columns)))) as copy:
            for k, (chunks, key) in enumerate(encoded):
                stream = to_copy(chunks, int(key[0]), revision, key[1:])
                # one stream: the header once, the trailer once
                copy.write(memoryview(stream)[19 if k else 0 : -2 if k < len(encoded) - 1 else None])
    if layout.versioned and revision != 0:
        conn.execute("SELECT tgsis.record_changed_objects('tgsis', %s, %s::text[])", (table, objects))
    return True


def _points(
    table: str, name: str, values: npt.ArrayLike, wire: str, columns: Sequence[tuple[str, npt.ArrayLike, str]]
) -> npt.NDArray[np.float64]:
    """A point column of :func:`upload_rows` as (n, m) float64, every point of the object's m coordinates.

    m is the wire type's (``float8[m]``: the embedding the upload states); a point of another length (a ragged
    sequence) or of none is refused by name, before anything is sent.

    Raises
    ------
    InvalidInputError
        Naming the table, the column, the object and the first point of another length.
    """
    m = int(wire[7:-1]) if wire.startswith("float8[") and wire.endswith("]") and wire[7:-1].isdigit() else 0
    if m < 1:
        raise InvalidInputError(
            f"tgsis.{table}: column {name} holds points: its wire type is float8[m], m >= 1, not {wire}"
        )
    try:
        points: npt.NDArray[np.float64] | None = np.asarray(values, dtype=np.float64)
    except ValueError:  # a ragged sequence: points of several lengths
        points = None
    if points is not None and points.ndim == 2 and points.shape[1] == m:
        return points
    if points is not None and points.ndim == 2:  # (n, m') with m' != m: the first point is of another length
        row, length = 0, int(points.shape[1])
    else:
        lengths = [int(np.asarray(p).size) for p in cast(Sequence[Any], values)]
        row = next((i for i, n in enumerate(lengths) if n != m), 0)
        length = lengths[row] if lengths else 0
    geoid = next((int(np.asarray(v)[row]) for n, v, _ in columns if n == "geoid" and len(np.asarray(v)) > row), None)
    raise InvalidInputError(
        f"tgsis.{table}: the points of object {geoid} are not all of its {m} coordinates",
        detail=f"column {name}: row {row} has {length} coordinates; nothing was written",
        hint="every point of a G-map has the embedding's number of coordinates",
    )


def point_rows(
    conn: Conn, table: str, geoid: int, m: int, chunked: frozenset[str] | None = None
) -> list[npt.NDArray[Any]] | None:
    """A G-map's points read from their chunks, decoded here: ``[*keys, id, coordinate (n, m)]`` in key order.

    What ``copy_rows`` of the face gives (``gmap_vertex``: ``timem, timet, nodeid, coordinate``; ``md_vertex``:
    ``vrtxid, coordinate``), bit for bit, from the chunk versions the session sees (:func:`visible_chunks`),
    one query, the role's rights.

    Parameters
    ----------
    table : str
        ``gmap_vertex`` or ``md_vertex``.
    m : int
        The object's embedding: every point has m coordinates.
    chunked : frozenset of str, optional
        :func:`chunked_tables` (read when not given).

    Returns
    -------
    list of ndarray, or None
        None when the table is stored as rows, or the role may not read its chunk table (it reads the face).

    Raises
    ------
    InvalidInputError
        Chunks that break the contract.
    DatabaseError
        Points of another length than m.
    """
    if table not in (chunked if chunked is not None else chunked_tables(conn)):
        return None
    layout = chunk_table(conn, table, instants=table == "gmap_vertex")
    if not layout.readable or not layout.columns.points:
        return None
    point = layout.columns.points[0]
    if layout.columns.instant:
        groups = sorted(instant_rows(conn, layout, [geoid]).items())
    else:
        groups = [((geoid,), _objects(layout, [geoid], _copy_out(conn, chunk_copy_query(layout, [geoid])))[geoid])]
    sizes = {int(o.columns[point].shape[1]) for _, o in groups if len(o.ids)}
    if sizes - {m}:  # (as the face's read refuses them: a value of another size)
        raise DatabaseError(
            f"tgsis.{table}: the points of object {geoid} have {sorted(sizes)} coordinates, not its embedding's {m}"
        )
    counts = [len(o.ids) for _, o in groups]
    keys = [
        np.repeat(np.asarray([key[1 + i] for key, _ in groups], dtype=np.float64), counts)
        for i in range(len(layout.columns.instant))
    ]
    ids = np.concatenate([np.empty(0, dtype=np.int64), *(o.ids for _, o in groups)])
    points = np.concatenate([np.empty((0, m)), *(o.columns[point].reshape(-1, m) for _, o in groups)])
    return [*keys, ids, points]
