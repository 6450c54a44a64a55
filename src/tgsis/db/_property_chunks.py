"""Bulk upload and download of a class's property chunks (issue 40): the properties of whole features, encoded here.

docs/storage.md, "Property chunks: the contract": once a STATIC class's property
table ``<schema>.<class>_cellpros`` is stored in chunks
(``tgsis.store_class_in_chunks``), it is a view (the face) over
``<class>_cellpros_chunk``, one array per property of the property's own type.
Writing a feature's properties through the face goes row by row through its
trigger; these paths move whole chunks instead, as model 1's vertex chunks move
(:mod:`tgsis.db._chunk_transfer`):

* :func:`upload_properties` encodes the rows with :func:`tgsis._chunks.encode`
  (NULL values of a collection member's missing properties kept apart from
  holes), sends them in one binary COPY into a temporary table of the session,
  and ``tgsis.write_property_chunks`` writes them as the chunk table's owner
  after the face's checks (the role's INSERT on the face, locks, the
  encoding, new chunks only);
* :func:`property_request` reads them in :func:`~tgsis.db._transfer.columns_out_all`'s
  one query (:class:`~tgsis.db._chunk_transfer.PackedChunks`), decoded here;
* :func:`write_property_rows` writes an edit of one object's property rows (the
  check-in by difference, the merges' written states), versioned or not: the
  rows that go and the new and changed rows at once, sent by one binary COPY
  and written by ``tgsis.write_property_rows``, each touched chunk rewritten
  once (through the face, each row rewrote its chunk).

The upload and the download are taken only where they give what the face
gives: a role that may read the chunk table (download) or insert into the face
(upload); otherwise the callers go through the face as before. A versioned
class's download reads the chunk versions the session sees (the face's
visibility test); its upload writes each new object by
:func:`write_property_rows` (revision, rights and locks of the face checked on
the server), not by :func:`upload_properties` (chunks of revision 0 only). The edit's write has the face's checks
server-side (rights, version, locks) and serves every role the face serves. Private to ``tgsis.db``.
"""

from __future__ import annotations

import hashlib
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt
import psycopg
from psycopg import sql

from tgsis._chunks import CHUNK_BITS, CHUNK_SIZE, ChunkColumns, encode, to_copy
from tgsis.db._chunk_transfer import ChunkTable, ObjectRows, PackedChunks
from tgsis.db._chunk_write import open_stage, read_chunks, swap_chunks
from tgsis.db._transfer import copy_in
from tgsis.db.classes import FeatureClass
from tgsis.db.copy import encode_rows
from tgsis.errors import InvalidInputError

__all__ = [
    "PropertyChunks",
    "property_chunks",
    "property_request",
    "swap_property_rows",
    "upload_properties",
    "write_property_rows",
]

Conn = psycopg.Connection[Any]

#: the array types of a property chunk table, as format_type spells them, and their element kinds
_KINDS = {
    "smallint[]": "int2",
    "integer[]": "int4",
    "bigint[]": "int8",
    "real[]": "float4",
    "double precision[]": "float8",
    "boolean[]": "bool",
}


@dataclass(frozen=True)
class PropertyChunks(ChunkTable):
    """A class's property table stored in chunks, as the session's role may use it in bulk.

    Attributes (besides :class:`~tgsis.db._chunk_transfer.ChunkTable`'s)
    ------------------------------------------------------------------
    insertable : bool
        The role may INSERT into the face (the property table's name) and make temporary tables: the bulk
        upload is open to it.
    name : str
        The table as the chunk layer names it (``format('%I.%I', schema, table)``, ``tgsis.chunk_registry``).
    oid : int
        The chunk table's (made anew when a property is added, renamed or dropped).
    """

    insertable: bool = False
    name: str = ""
    oid: int = 0


def property_chunks(conn: Conn, fc: FeatureClass, table: str) -> PropertyChunks | None:
    """The chunk layout of the class's property table ``table`` if its bulk paths are open, else None.

    None: the table is rows (or anything but the face of ``tgsis.store_class_in_chunks``), or its chunk
    table has a column this client does not encode. A vector property (size k in the catalog) is a 2-D
    array, slots x k (:attr:`~tgsis._chunks.ChunkColumns.vectors`), its values (n, k). ``versioned``: the table is versioned (a download reads
    the chunk versions the session sees, as the face; an upload goes by :func:`write_property_rows`, not
    :func:`upload_properties`). Read from the catalog.
    """
    return _property_layout(conn, fc.schema, table)


def _property_layout(conn: Conn, schema: str, table: str) -> PropertyChunks | None:
    """:func:`property_chunks` of the property table ``schema.table``."""
    row = conn.execute(
        "SELECT c.oid, f.relkind::text, has_table_privilege(c.oid, 'SELECT'), "
        "has_table_privilege(f.oid, 'INSERT') AND has_database_privilege(current_database(), 'TEMP'), "
        "EXISTS (SELECT FROM tgsis.versioned_tables t WHERE t.schemaname = %s AND t.tablename = %s), "
        "format('%%I.%%I', %s::text, %s::text) "
        "FROM pg_class c JOIN pg_namespace n ON n.oid = c.relnamespace, pg_class f "
        "WHERE n.nspname = %s AND c.relname = %s AND f.oid = to_regclass(format('%%I.%%I', %s::text, %s::text))",
        (schema, table, schema, table, schema, f"{table}_chunk", schema, table),
    ).fetchone()
    if row is None or row[1] != "v":
        return None
    oid, _, readable, insertable, versioned, name = row
    # a vector property (size k in the catalog, as tgsis.chunk_columns reads it): a 2-D chunk array, slots x k,
    # typed t[] as a scalar property's, so the catalog tells them apart (the properties of this table: the class's
    # alignment in cellprotable, the other's in otherprotable)
    vectors = dict(
        conn.execute(
            "SELECT p ->> 'name', (p ->> 'size')::integer FROM tgsis.catalog c "
            "CROSS JOIN LATERAL jsonb_array_elements(c.cell_properties) AS p "
            "WHERE c.schemaname = %s AND %s IN (c.cellprotable, c.otherprotable) "
            "AND p ? 'size' AND (p ->> 'size')::integer > 1 "
            "AND (coalesce(p ->> 'alignment', c.proalignment) = c.proalignment) = (c.cellprotable = %s)",
            (schema, table, table),
        ).fetchall()
    )
    attributes = conn.execute(
        "SELECT attname::text, format_type(atttypid, atttypmod) FROM pg_catalog.pg_attribute "
        "WHERE attrelid = %s AND attnum > 0 AND NOT attisdropped ORDER BY attnum",
        (oid,),
    ).fetchall()
    names = [n for n, _ in attributes]
    fixed = ("revision", "lastrevs", "revclosed", "holes")
    arrays = [(n, t) for n, t in attributes if n not in ("_geoid", "chunk", *fixed)]
    # the chunk size is the aligned table's (tgsis.chunk_registry, not the role's to call): every one this client's
    size = conn.execute(
        "SELECT bool_and(chunksize = %s) FROM tgsis.model_tables WHERE chunkcolumn IS NOT NULL", (CHUNK_SIZE,)
    ).fetchone()
    if names[:2] != ["_geoid", "chunk"] or any(t not in _KINDS for _, t in arrays) or size != (True,):
        return None  # (a layout this client does not know: the face still reads and writes it)
    kinds = tuple((n, _KINDS[t]) for n, t in arrays)
    if set(vectors) - {n for n, _ in arrays}:
        return None
    columns = ChunkColumns(
        tuple(n for n, _ in arrays),
        properties=kinds,
        key="_geoid",
        vectors=tuple((n, int(vectors[n])) for n, _ in arrays if n in vectors),
    )
    return PropertyChunks(
        table, columns, bool(versioned), bool(readable), schema, bool(insertable), str(name), int(oid)
    )


def property_request(
    conn: Conn, fc: FeatureClass, table: str, names: Sequence[str], geoids: Sequence[int]
) -> PackedChunks | None:
    """The part of :func:`~tgsis.db._transfer.columns_out_all` that reads properties ``names`` from chunks, or None.

    ``[_geoid, _idx, *names]`` as the face's packed read gives them (rows in id order per object), read from
    the chunk versions; a NULL value among ``names`` is refused as there (:class:`~tgsis.errors.DatabaseError`).
    None when the bulk read is not open (:func:`property_chunks`, or the role may not read the chunk table).
    """
    layout = property_chunks(conn, fc, table)
    if layout is None or not layout.readable:
        return None
    return PackedChunks(layout, geoids, ["_idx", *names])


def upload_properties(
    conn: Conn,
    layout: PropertyChunks,
    geoids: Sequence[int],
    counts: Sequence[int],
    values: Sequence[Mapping[str, npt.NDArray[Any]]],
) -> int:
    """Write the properties of new geometries as chunks: ids 0..n-1 of each, one COPY and one server call.

    Parameters
    ----------
    layout : PropertyChunks
        Of :func:`property_chunks`, ``insertable``.
    geoids : sequence of int
        The geometries (distinct), new: their chunks must not be there.
    counts : sequence of int
        Rows of each (its vertices or cells).
    values : sequence of mapping of str to (n_i,) or (n_i, k) ndarray
        Per geometry, the properties it has, cast to their column types (a vector property (n_i, k)); a
        property of the table it lacks (a collection member's) is NULL in its rows, as on rows.

    Returns
    -------
    int
        The chunk rows written.

    Raises
    ------
    AlreadyExistsError
        A chunk of one of them is there (TG201, from the server): nothing is written.
    psycopg.errors.InsufficientPrivilege
        The role may not INSERT into the face.
    """
    if layout.versioned:
        raise InvalidInputError(f"{layout.name} is versioned: write its new objects with write_property_rows")
    spec = layout.columns
    objects = []
    for geoid, n, given in zip(geoids, counts, values, strict=True):
        unknown = sorted(set(given) - set(spec.names))
        if unknown:
            raise InvalidInputError(f"{layout.name} has no properties {unknown}")
        columns = {
            name: given[name] if name in given else np.zeros(spec.shape(name, n), dtype=spec.dtype(name))
            for name in spec.names
        }
        nulls = {name: np.ones(n, dtype=bool) for name in spec.names if name not in given}
        objects.append(ObjectRows(int(geoid), np.arange(n, dtype=np.int64), columns, nulls=nulls))
    encoded = [(o.geoid, encode(o.ids, o.columns, spec, o.nulls)) for o in objects if len(o.ids)]
    if not encoded:
        return 0
    staged = _staged_name(layout)
    copy_columns = spec.copy_columns()
    conn.execute(
        sql.SQL("CREATE TEMP TABLE IF NOT EXISTS {} (LIKE {} INCLUDING DEFAULTS) ON COMMIT DROP").format(
            staged, layout.relation
        )
    )
    # uncompressed: the values are read once, into the server call's array (compressed there, once)
    conn.execute(
        sql.SQL("ALTER TABLE {} {}").format(
            staged,
            sql.SQL(", ").join(
                sql.SQL("ALTER COLUMN {} SET STORAGE EXTERNAL").format(sql.Identifier(n))
                for n in ("holes", *spec.names)
            ),
        )
    )
    statement = sql.SQL("COPY {} ({}) FROM STDIN (FORMAT binary)").format(
        staged, sql.SQL(", ").join(map(sql.Identifier, copy_columns))
    )
    with conn.cursor().copy(statement) as copy:
        for k, (geoid, chunks) in enumerate(encoded):
            stream = to_copy(chunks, geoid, 0)
            # one stream: the header once, the trailer once
            copy.write(memoryview(stream)[19 if k else 0 : -2 if k < len(encoded) - 1 else None])
    attributes = conn.execute(
        "SELECT attname::text, attgenerated <> '', format_type(atttypid, atttypmod) FROM pg_catalog.pg_attribute "
        "WHERE attrelid = to_regclass(%s) AND attnum > 0 AND NOT attisdropped ORDER BY attnum",
        (layout.relation.as_string(conn),),
    ).fetchall()
    fields = sql.SQL(", ").join(
        sql.SQL("NULL::{}").format(sql.SQL(typename)) if generated else sql.SQL("s.{}").format(sql.Identifier(name))
        for name, generated, typename in attributes
    )
    row = conn.execute(
        sql.SQL("SELECT tgsis.write_property_chunks({}, (SELECT array_agg(ROW({})::{}) FROM {} s))").format(
            sql.Literal(layout.name), fields, layout.relation, staged
        )
    ).fetchone()
    conn.execute(sql.SQL("TRUNCATE {}").format(staged))
    return int(row[0]) if row is not None and row[0] is not None else 0


def _staged_name(layout: PropertyChunks) -> sql.Composed:
    """The session's temporary table of an upload into ``layout``'s chunk table (one per chunk table and its columns).

    The columns are in the name: a property added, renamed or dropped in place (``tgsis.alter_chunk_table``)
    keeps the chunk table's oid, and an upload after it in the same transaction needs a table of the new columns.
    """
    digest = hashlib.sha256(repr(layout.columns.properties).encode()).hexdigest()[:16]
    return sql.SQL("pg_temp.{}").format(sql.Identifier(f"tgsis_upload_{layout.oid}_{digest}"))


def write_property_rows(
    conn: Conn,
    schema: str,
    table: str,
    geoid: int,
    deleted: npt.ArrayLike,
    columns: Sequence[tuple[str, npt.ArrayLike, str]],
) -> int | None:
    """Write an edit of object ``geoid``'s rows of the property table ``schema.table`` if it is stored in chunks.

    The rows ``deleted`` go (or change: a row of ``columns`` replaces the row of its id) and the rows of
    ``columns`` are written, in the caller's transaction and the session's version: one binary COPY into a
    temporary table of the transaction, then ``tgsis.write_property_rows``, which makes the face's checks for
    the whole set and rewrites each touched chunk once (``tgsis.write_chunk_rows``).

    Parameters
    ----------
    schema, table : str
        The class's property table (the face of ``tgsis.store_class_in_chunks``).
    geoid : int
    deleted : (d,) int
        Ids whose rows go, or change (then also in ``columns``).
    columns : sequence of (name, (n,) array, wire type)
        ``_geoid`` (all ``geoid``), ``_idx`` and the properties, as :meth:`~tgsis.db._transfer.Storage.copy`
        takes them.

    Returns
    -------
    int or None
        Chunks written; None when the table is not stored in chunks (nothing done: write its rows).
    """
    row = conn.execute(
        "SELECT %s::text <> 'tgsis' AND tgsis.stored_in_chunks(%s, %s)", (schema, schema, table)
    ).fetchone()
    if row is None or not row[0]:
        return None
    gone = np.asarray(deleted, dtype=np.int64).reshape(-1)
    count = len(np.asarray(columns[0][1])) if columns else 0
    if not len(gone) and not count:
        return 0
    swapped = _swapped(conn, schema, table, geoid, gone, columns if count else [])
    if swapped is not None:
        return swapped
    face = sql.Identifier(schema, table)
    stage = sql.Identifier(f"tgsis_property_edit_{hashlib.sha256(f'{schema}.{table}'.encode()).hexdigest()[:16]}")
    # made anew each time: a property added, renamed or dropped in the transaction changes the face's columns
    conn.execute(sql.SQL("DROP TABLE IF EXISTS pg_temp.{}").format(stage))
    conn.execute(sql.SQL("CREATE TEMP TABLE {} (LIKE {}) ON COMMIT DROP").format(stage, face))
    names = [name for name, _, _ in columns]
    if count:
        copy_in(conn, sql.SQL("pg_temp.{}").format(stage), names, encode_rows([(v, w) for _, v, w in columns]))
    fields = conn.execute(
        "SELECT attname::text FROM pg_catalog.pg_attribute WHERE attrelid = to_regclass(%s) AND attnum > 0 "
        "AND NOT attisdropped ORDER BY attnum",
        (face.as_string(conn),),
    ).fetchall()
    rows = sql.SQL("(SELECT coalesce(array_agg(ROW({})::{}), '{{}}') FROM pg_temp.{} s)").format(
        sql.SQL(", ").join(sql.SQL("s.{}").format(sql.Identifier(f)) for (f,) in fields), face, stage
    )
    written = conn.execute(
        sql.SQL("SELECT tgsis.write_property_rows(format('%%I.%%I', %s::text, %s::text), %s, %s::bigint[], {})").format(
            rows
        ),
        (schema, table, int(geoid), gone.tolist()),
    ).fetchone()
    conn.execute(sql.SQL("DROP TABLE pg_temp.{}").format(stage))
    return int(written[0]) if written is not None and written[0] is not None else 0


def _swapped(
    conn: Conn,
    schema: str,
    table: str,
    geoid: int,
    gone: npt.NDArray[np.int64],
    columns: Sequence[tuple[str, npt.ArrayLike, str]],
) -> int | None:
    """:func:`swap_property_rows` in a savepoint; None when it does not apply or lost a race (nothing written then).

    A chunk another transaction wrote between the client's read and the swap (a psql user's write through the
    face) makes the swap refuse (TG300, nothing written): the edit then goes by ``tgsis.write_property_rows``,
    which merges it into the chunks as they are now.
    """
    try:
        with conn.transaction():
            return swap_property_rows(conn, schema, table, geoid, gone, columns)
    except psycopg.Error as error:
        if error.sqlstate != "TG300":
            raise
        return None


def swap_property_rows(
    conn: Conn,
    schema: str,
    table: str,
    geoid: int,
    deleted: npt.ArrayLike,
    columns: Sequence[tuple[str, npt.ArrayLike, str]],
) -> int | None:
    """:func:`write_property_rows`, the touched chunks encoded here: read, merged, encoded, staged and swapped in.

    The client's path of a check-in of a class's properties in chunks (``tgsis.write_property_rows``
    re-aggregates each touched chunk in SQL, about 30 ms a chunk: a scattered edit touches nearly all), as
    model 1's (:func:`~tgsis.db._chunk_write.swap_object_rows`): the visible versions of the touched chunks
    read with their places in one binary COPY, the edit merged into their rows (the NULL values of the rows
    kept kept apart from holes), the chunks encoded (:func:`tgsis._chunks.encode`) and COPied into the
    transaction's stage (``tgsis.object_chunks_stage``), then ``tgsis.swap_object_chunks`` makes the checks of
    ``tgsis.write_property_rows`` (INSERT and DELETE on the face, the version's write right or TG305, the
    object's lock, NOT NULL properties), verifies the encoding and that every chunk's visible version is still
    the one read (TG300, nothing written) and writes them as ``tgsis.write_chunk_rows`` would, bit for bit.

    Parameters
    ----------
    schema, table : str
        The class's property table (the face of ``tgsis.store_class_in_chunks``).
    geoid : int
    deleted : (d,) int
        Ids whose rows go, or change (then also in ``columns``).
    columns : sequence of (name, (n,) array, wire type)
        ``_geoid`` (all ``geoid``), ``_idx`` and properties; a property not given is NULL in the rows written.

    Returns
    -------
    int or None
        Chunks written; None when this path does not apply and nothing was written: the table's layout is not
        one this client encodes, the role may not read the chunk table or lacks INSERT or DELETE on the face,
        the transaction is not READ COMMITTED, the row definition has CHECK constraints, or the rows are not
        the server path's to refuse or accept alone (another object's, an id twice, a present id written
        without its delete: ``tgsis.write_property_rows`` raises what it raises there).
    """
    gone = np.asarray(deleted, dtype=np.int64).reshape(-1)
    given = {name: np.asarray(values) for name, values, _ in columns}
    written = np.asarray(given.get("_idx", np.empty(0, dtype=np.int64)), dtype=np.int64).reshape(-1)
    if not len(gone) and not len(written):
        return 0
    layout = _property_layout(conn, schema, table)
    if layout is None or not layout.readable:
        return None
    spec = layout.columns
    keys = given.get("_geoid", np.full(len(written), geoid, dtype=np.int64))
    if (
        set(given) - {"_geoid", "_idx", *spec.names}
        or any(
            v.shape != (spec.shape(name, len(written)) if name in spec.names else (len(written),))
            for name, v in given.items()
        )
        or len(np.unique(written)) != len(written)
        or bool((written < 0).any())
        or not bool((np.asarray(keys) == geoid).all())
    ):
        return None  # (the server path refuses such rows by name)
    # (READ COMMITTED asked first, as open_stage asks it: no chunk read at all where the path does not apply)
    # (a vector property's own CHECK, as the class made it, is held by the encoding: tgsis.swap_object_chunks
    # passes it by the same text)
    checks = conn.execute(
        "SELECT EXISTS (SELECT FROM pg_constraint con WHERE con.conrelid = to_regclass(%s) AND con.contype = 'c' "
        "AND con.conname <> %s AND pg_get_expr(con.conbin, con.conrelid) NOT IN ("
        "SELECT format('((array_ndims(%%1$I) = 1) AND (array_lower(%%1$I, 1) = 1) AND (cardinality(%%1$I) = %%2$s) "
        "AND (array_position(%%1$I, NULL::%%3$s) IS NULL))', v.name, v.size, left(format_type(a.atttypid, a.atttypmod), -2)) "
        "FROM unnest(%s::text[], %s::int[]) AS v(name, size) JOIN pg_attribute a ON a.attrelid = to_regclass(%s) "
        "AND a.attname = v.name)) OR current_setting('transaction_isolation') <> 'read committed'",
        (
            sql.Identifier(schema, f"{table}_shape").as_string(conn),
            f"{table}_shape_holds_no_rows",
            [n for n, _ in spec.vectors],
            [k for _, k in spec.vectors],
            sql.Identifier(schema, f"{table}_shape").as_string(conn),
        ),
    ).fetchone()
    if checks is None or checks[0]:
        return None
    touched = np.unique(np.concatenate([gone, written]) >> CHUNK_BITS)
    old, bases = read_chunks(conn, layout, geoid, touched)
    old_ids, old_columns = old.rows()
    old_nulls = old.null_rows()
    if bool(np.isin(np.setdiff1d(written, gone), old_ids).any()):
        return None  # a present id written without its delete: the face's 23505, raised by the server path
    stage = open_stage(conn, layout.name, sql.Identifier(schema, table), layout)
    if stage is None:
        return None
    keep = ~np.isin(old_ids, np.concatenate([gone, written]))
    new_ids = np.concatenate([old_ids[keep], written])
    values: dict[str, npt.NDArray[Any]] = {}
    nulls: dict[str, npt.NDArray[np.bool_]] = {}
    for name in spec.names:
        dtype = spec.dtype(name)
        edit = given[name].astype(dtype) if name in given else np.zeros(spec.shape(name, len(written)), dtype=dtype)
        values[name] = np.concatenate([old_columns[name][keep].astype(dtype), edit])
        kept = old_nulls[name][keep] if name in old_nulls else np.zeros(int(keep.sum()), dtype=bool)
        fresh = np.zeros(len(written), dtype=bool) if name in given else np.ones(len(written), dtype=bool)
        mask = np.concatenate([kept, fresh])
        if mask.any():
            nulls[name] = mask
    return swap_chunks(conn, layout.name, stage, geoid, touched, bases, encode(new_ids, values, spec, nulls))
