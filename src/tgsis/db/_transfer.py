"""The write and read plumbing every data model's database module shares.

Binary COPY in and out (:mod:`tgsis.db.copy` builds and parses the rows),
where bulk rows go (:class:`Storage`: a table, or a versioned table's
``_ver`` storage in the session's working revision), the (geoid, local id)
key columns of many geometries at once, and the class's property arrays of
a mesh checked against its columns. Private to ``tgsis.db``: the models'
modules (``features``, ``instants``, ``evolving``, ``gmaps``, ``multidim``, ``checkin``) import it; users do not.
"""

from __future__ import annotations

import concurrent.futures
import contextlib
import contextvars
import itertools
import json
import logging
import re
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import Any, Protocol, TypeVar, cast

import numpy as np
import numpy.typing as npt
import psycopg
from psycopg import sql

from tgsis.db._same_result import same_result
from tgsis.db.classes import FeatureClass, get_feature_class, stores_part_column
from tgsis.db.copy import SQL_TYPES, decode_packed, decode_rows, encode_chunks, encode_rows, numpy_dtype, wire_shape
from tgsis.errors import (
    ConcurrentReadError,
    DatabaseError,
    InUseError,
    InvalidGeometryError,
    InvalidInputError,
    InvalidPropertyError,
    NotVersionedError,
)
from tgsis.mesh import Mesh

log = logging.getLogger("tgsis.db.features")

Conn = psycopg.Connection[Any]


def resolve_class(conn: Conn, feature_class: str | FeatureClass) -> FeatureClass:
    """The class itself when given one, else the class of that name (:func:`~tgsis.db.classes.get_feature_class`)."""
    return feature_class if isinstance(feature_class, FeatureClass) else get_feature_class(conn, feature_class)


def class_name(feature_class: str | FeatureClass) -> str:
    """The name of a class given by name or as a :class:`FeatureClass` (no query)."""
    return feature_class.name if isinstance(feature_class, FeatureClass) else feature_class


@contextlib.contextmanager
def read_only_snapshot(conn: Conn) -> Iterator[None]:
    """A transaction for one statement's read, or for reads whose mixing the caller accepts.

    Outside a transaction, a new one that is ``REPEATABLE READ READ ONLY``;
    inside the caller's transaction, a savepoint of it (its isolation level is
    the caller's to choose, and it may write). Under ``READ COMMITTED`` each
    statement sees its own snapshot: a read of several statements that must
    see one state goes through :func:`consistent_read`.
    """
    with repeatable_read(conn, write=False):
        yield


_T = TypeVar("_T")

#: how many times :func:`consistent_read` runs a read that other sessions' commits interleaved, before it gives up
CONSISTENT_READ_TRIES = 5

# the connections (by id) inside a consistent_read of this thread: a nested one runs its read plainly
_reading: contextvars.ContextVar[frozenset[int]] = contextvars.ContextVar("tgsis_consistent_read", default=frozenset())


def consistent_read(conn: Conn, what: str, read: Callable[[], _T], *, tries: int = CONSISTENT_READ_TRIES) -> _T:
    """``read()``, a read of several statements, with every statement seeing one state of the database.

    - Outside a transaction: in a new ``REPEATABLE READ READ ONLY`` one
      (:func:`read_only_snapshot`).
    - In the caller's ``REPEATABLE READ`` or ``SERIALIZABLE`` transaction: in
      a savepoint of it (the transaction's one snapshot).
    - In the caller's ``READ COMMITTED`` transaction (psycopg's default: a
      connection that is not autocommit opens one at its first statement),
      where each statement takes a new snapshot: in a savepoint, between two
      statements reading the snapshot (``pg_current_snapshot()``: xmin, xmax
      and the transactions running) and, on a hot standby, the WAL replayed
      (``pg_last_wal_replay_lsn()``). Equal, no other transaction completed
      in between (xmax is the last completed transaction's id + 1, so a
      commit of one that is not listed changes xmax, and of one that is
      listed changes the list), so every statement of the read saw the same
      committed state; else the savepoint is rolled back and ``read`` runs
      again, up to ``tries`` times in all. Two tries in a row that others'
      commits interleaved but that read the same thing, bit for bit
      (:func:`~tgsis.db._same_result.same_result`), read one state: the
      commits changed nothing read (another database's, autovacuum's
      ``ANALYZE``, another application's: the snapshot is the whole
      cluster's), and the second try's result is returned. An error ``read``
      raises is raised when the state did not change during the try, or when
      two tries in a row raised it (else the try is run again: the error may
      come from states mixed). The caller's own uncommitted writes are seen
      (one transaction). What this cannot tell: commits between the tries'
      statements that change what one statement reads and change it back
      before the next try reads it (a write and its undo, each committed, in
      those few milliseconds) leave two equal tries of mixed states.

    A ``consistent_read`` inside another's ``read`` on the same connection runs
    its ``read`` plainly: the outer one checks (and retries) the whole.

    Parameters
    ----------
    what : str
        The read, as its error names it (e.g. ``"fetch_features"``).
    read : callable
        The statements, run on ``conn``; may run more than once, so it should have
        no effect outside the database, and it should not write: a try's writes are rolled back
        with its savepoint, also when its result is returned (two equal tries).
    tries : int

    Raises
    ------
    ConcurrentReadError
        In a ``READ COMMITTED`` transaction, other sessions committed during each of the ``tries``,
        and no two tries in a row read the same; the caller's transaction is left as it was.
    """
    if id(conn) in _reading.get():
        return read()
    token = _reading.set(_reading.get() | {id(conn)})
    try:
        return _consistent_read(conn, what, read, tries)
    finally:
        _reading.reset(token)


_SNAPSHOT_MARK = (
    "SELECT current_setting('transaction_isolation'), pg_catalog.pg_current_snapshot()::text, "
    "pg_catalog.pg_last_wal_replay_lsn()::text"
)


def _snapshot_mark(conn: Conn) -> tuple[str, str, str | None]:
    """The isolation level, the statement's snapshot and the WAL replayed (a standby's), read in one statement."""
    row = conn.execute(_SNAPSHOT_MARK).fetchone()
    assert row is not None
    return str(row[0]), str(row[1]), row[2]


@dataclass(frozen=True)
class _Try:
    """What one try of a read gave: its result, or the error it raised."""

    result: Any
    failure: Exception | None

    def same_as(self, other: _Try) -> bool:
        """The same result bit for bit, or the same error (class, SQLSTATE and message)."""
        if self.failure is None or other.failure is None:
            return self.failure is None and other.failure is None and same_result(self.result, other.result)
        return (
            type(self.failure) is type(other.failure)
            and getattr(self.failure, "sqlstate", None) == getattr(other.failure, "sqlstate", None)
            and str(self.failure) == str(other.failure)
        )


def _consistent_read(conn: Conn, what: str, read: Callable[[], _T], tries: int) -> _T:
    """:func:`consistent_read` of a connection not inside one already."""
    if conn.info.transaction_status == psycopg.pq.TransactionStatus.IDLE:
        with read_only_snapshot(conn):
            return read()
    before = _snapshot_mark(conn)
    if before[0] in ("repeatable read", "serializable"):
        with conn.transaction():
            return read()
    failure: Exception | None = None
    previous: _Try | None = None  # the last try whose statements others' commits interleaved
    for attempt in range(1, tries + 1):
        failure = None
        result: Any = None
        try:
            with conn.transaction() as savepoint:
                result = read()
                if _snapshot_mark(conn)[1:] == before[1:]:
                    return cast(_T, result)
                raise psycopg.Rollback(savepoint)  # others committed meanwhile: nothing of the try is kept
        except Exception as exc:  # noqa: BLE001 (raised below when the state did not change)
            failure = exc
        if failure is not None and conn.broken:
            raise failure  # no connection left to read on
        after = _snapshot_mark(conn)  # the savepoint is rolled back: the transaction reads on
        if failure is not None and after[1:] == before[1:]:
            raise failure  # an error of one state: the read's own
        this = _Try(result, failure)
        if previous is not None and previous.same_as(this):
            # two tries in a row read the same: the commits between their statements changed nothing they read
            log.debug("%s: try %d read what try %d read: one state", what, attempt, attempt - 1)
            if failure is not None:
                raise failure
            return cast(_T, result)
        log.debug("%s: other sessions committed during try %d of the read, read again", what, attempt)
        previous = this
        before = after
    raise ConcurrentReadError(
        f"{what} read several tables in a READ COMMITTED transaction while other sessions committed: "
        f"{tries} tries saw changes between its statements",
        detail="under READ COMMITTED each statement sees what others committed before it: "
        "the read would have mixed states",
        hint="read outside a transaction, or in a REPEATABLE READ transaction",
    ) from failure


@contextlib.contextmanager
def repeatable_read(conn: Conn, *, write: bool) -> Iterator[None]:
    """Outside a transaction, a new ``REPEATABLE READ`` one (``READ ONLY`` unless ``write``); inside, a savepoint.

    Inside the caller's transaction its isolation level is the caller's.
    """
    fresh = conn.info.transaction_status == psycopg.pq.TransactionStatus.IDLE
    with conn.transaction():
        if fresh:
            conn.execute("SET TRANSACTION ISOLATION LEVEL REPEATABLE READ" + ("" if write else " READ ONLY"))
        yield


@contextlib.contextmanager
def one_snapshot(conn: Conn) -> Iterator[bool]:
    """A transaction for a read of several statements; True when they all see the same snapshot.

    Outside a transaction, a new ``REPEATABLE READ READ ONLY`` one (True).
    Inside the caller's, a savepoint of it (the caller's transaction is left
    as it was): True when its isolation level keeps one snapshot for the
    whole transaction (``REPEATABLE READ``, ``SERIALIZABLE``), False under
    ``READ COMMITTED``, where each statement sees what others committed
    meanwhile.
    """
    if conn.info.transaction_status == psycopg.pq.TransactionStatus.IDLE:
        with read_only_snapshot(conn):
            yield True
        return
    row = conn.execute("SELECT current_setting('transaction_isolation')").fetchone()
    with conn.transaction():
        yield row is not None and row[0] in ("repeatable read", "serializable")


#: columns of a COPY: (name, values, wire type)
Columns = Sequence[tuple[str, npt.ArrayLike, str]]


def stored_cell_properties(fc: FeatureClass, mesh: Mesh) -> dict[str, npt.NDArray[Any]]:
    """The mesh's cell properties but ``part`` when that goes to ``tgsis.part``."""
    if stores_part_column(fc):
        return dict(mesh.cell_properties)
    return {k: v for k, v in mesh.cell_properties.items() if k != "part"}


def aligned_properties(
    fc: FeatureClass, mesh: Mesh, drop_extra: bool, what: str = "the mesh"
) -> dict[str, npt.NDArray[Any]]:
    """The mesh properties the class stores, checked and cast to the column types (``what`` names the mesh).

    The ``part`` cell property is not one of them unless the class has a
    ``part`` cell column: it is stored in ``tgsis.part``.
    """
    cells = stored_cell_properties(fc, mesh)
    sources = {"VERTEX": mesh.vertex_properties, "CELL": cells}
    kinds = {"VERTEX": "vertex", "CELL": mesh.cell_name}
    if fc.otherprotable is None:  # one alignment: the other's properties are extra
        other_alignment = "CELL" if fc.alignment == "VERTEX" else "VERTEX"
        result = class_property_arrays(
            fc, sources[fc.alignment], sources[other_alignment], kinds[fc.alignment], drop_extra, what
        )
    else:  # vertex and cell properties side by side: each side checked against its own columns
        result = {}
        for alignment in ("VERTEX", "CELL"):
            side = replace(fc, cell_properties=fc.aligned(alignment), alignment=alignment)
            result.update(class_property_arrays(side, sources[alignment], {}, kinds[alignment], drop_extra, what))
    for prop in fc.cell_properties:  # (n,) for a scalar property, (n, k) for a vector of k
        kind = kinds[fc.alignment_of(prop)]
        values = result[prop.name]
        if (values.ndim == 1) != (prop.size == 1) or (values.ndim == 2 and values.shape[1] != prop.size):
            shape = "one value" if prop.size == 1 else f"a vector of {prop.size} values"
            got = "one value" if values.ndim == 1 else f"a vector of {values.shape[1]} values"
            raise InvalidPropertyError(
                f"{kind} property {prop.name!r} of {what} has {got} per element, "
                f"but feature class {fc.name} stores {shape}"
            )
    return result


def class_property_arrays(
    fc: FeatureClass,
    stored: Mapping[str, npt.NDArray[Any]],
    other: Mapping[str, npt.NDArray[Any]],
    kind: str,
    drop_extra: bool,
    what: str,
) -> dict[str, npt.NDArray[Any]]:
    """The class's vertex/cell property arrays (any shape) out of ``stored``, checked and cast to the column types.

    ``other`` holds the properties of the other alignment (never stored);
    ``kind`` and ``what`` name them and their owner in messages.
    """
    wanted = {p.name: p for p in fc.cell_properties}
    missing = sorted(set(wanted) - set(stored))
    if missing:
        raise InvalidPropertyError(f"feature class {fc.name} needs {kind} properties {missing}, which {what} lacks")
    extra = sorted(set(stored) - set(wanted)) + sorted(other)
    if extra and not drop_extra:
        raise InvalidPropertyError(
            f"feature class {fc.name} has no column for properties {extra} of {what}",
            hint=f"it stores {fc.alignment.lower()} properties {sorted(wanted) or 'none'}; "
            "drop the others (drop_extra_properties=True) or register them in the class",
        )
    if extra:
        log.warning("not stored by feature class %s: properties %s of %s", fc.name, extra, what)
    result: dict[str, npt.NDArray[Any]] = {}
    for prop in fc.cell_properties:
        values = stored[prop.name]
        target = numpy_dtype(SQL_TYPES[prop.type])
        cast = values.astype(target)
        if target.kind in "iub" and not np.array_equal(cast, values):
            raise InvalidPropertyError(f"{kind} property {prop.name!r} has values that are not {prop.type} in {what}")
        result[prop.name] = cast
    return result


def feature_columns(fc: FeatureClass, properties: Mapping[str, Any] | None) -> dict[str, Any]:
    known = {p.name for p in fc.feature_properties}
    values = dict(properties or {})
    unknown = sorted(set(values) - known)
    if unknown:
        raise InvalidPropertyError(
            f"feature class {fc.name} has no feature properties {unknown}",
            hint=f"its feature properties: {sorted(known) or 'none'}",
        )
    return {k: (json.dumps(v) if isinstance(v, (dict, list)) else v) for k, v in values.items()}


def check_feature_values(conn: Conn, fc: FeatureClass, values: Mapping[str, Any]) -> None:
    """Refuse, naming the property, a text value that is no value of its feature property's type.

    PostgreSQL reads text such as the command line's ``--feature-property
    n=abc`` as the column's type when the row is written, and a bad one came
    back as a raw ``22P02`` (or ``22007``, ``22003``) naming no property. The
    values are cast first, all in one statement within a savepoint; only if
    that fails is each one cast alone to find which.

    Raises
    ------
    InvalidPropertyError
        The first value that is not one of its type (the server's words in ``detail``).
    """
    types = {p.name: p.type for p in fc.feature_properties}
    texts = [
        (name, value, types[name])
        for name, value in values.items()
        if isinstance(value, str) and types.get(name) not in (None, "text", "character varying", "varchar")
    ]
    if not texts:
        return

    def cast(items: Sequence[tuple[str, str, str]]) -> None:
        with conn.transaction():
            conn.execute(
                sql.SQL("SELECT {}").format(
                    sql.SQL(", ").join(
                        sql.SQL("CAST({} AS {})").format(sql.Placeholder(), sql.SQL(kind)) for _, _, kind in items
                    )
                ),
                [value for _, value, _ in items],
            )

    try:
        cast(texts)
    except psycopg.DataError:
        for item in texts:
            try:
                cast([item])
            except psycopg.DataError as exc:
                name, value, kind = item
                shown = repr(value) if len(value) <= 100 else f"{value[:100]!r}... ({len(value)} characters)"
                raise InvalidPropertyError(
                    f"value {shown} of feature property {name!r} of class {fc.name} is not a valid {kind}",
                    detail=(exc.diag.message_primary or "")[:500],
                    hint=f"give a value PostgreSQL reads as {kind}",
                ) from None
        raise


def check_class_unchanged(conn: Conn, fc: FeatureClass) -> None:
    """After a feature's rows are written: refuse if vertex or cell properties were added meanwhile to a table it wrote none to.

    An upload writes rows to a vertex or cell property table only for the
    properties its :class:`FeatureClass` lists. ``tgsis.add_property`` gives
    every stored feature its rows and locks the feature table until it
    commits, so an upload whose feature row waited for it reads the new
    catalog here: with a property the upload wrote no rows for, the feature
    would be unreadable ("... has 0 rows for N vertices"), so it is refused
    and nothing of it is stored. Only classes with no property of an
    alignment pay the query (elsewhere the new column's NOT NULL refuses the
    stale rows itself).
    """
    other = "CELL" if fc.alignment == "VERTEX" else "VERTEX"
    if fc.aligned(fc.alignment) and (fc.otherprotable is None or fc.aligned(other)):
        return
    row = conn.execute(
        "SELECT jsonb_array_length(cell_properties) FROM tgsis.catalog WHERE classname = %s", (fc.name,)
    ).fetchone()
    if row is not None and int(row[0]) != len(fc.cell_properties):
        raise InUseError(
            f"feature class {fc.name} gained vertex or cell properties while the feature was written: "
            "nothing of it was stored",
            hint="read the class again (tgsis.get_feature_class) and give the new properties' values",
        )


def _copy_statement(table: sql.Composable, columns: Sequence[str]) -> sql.Composed:
    return sql.SQL("COPY {} ({}) FROM STDIN (FORMAT binary)").format(
        table, sql.SQL(", ").join(sql.Identifier(c) for c in columns)
    )


def copy_in(conn: Conn, table: sql.Composable, columns: Sequence[str], payload: bytes) -> None:
    with staged(conn, table, columns) as target, conn.cursor().copy(_copy_statement(target, columns)) as copy:
        copy.write(payload)


def insert_chunk_rows(conn: Conn, table: str, columns: Sequence[tuple[str, npt.ArrayLike, str]]) -> int:
    """Insert rows of the model table ``tgsis.<table>`` stored in chunks: one call of ``tgsis.insert_chunk_rows``.

    ``columns``: ``(name, values (n,), wire type)``, integer (``int8``, ``int4``, ``int2``: sent as bigint and cast
    by the server), double precision (``float8``) or boolean (``bool``), every column of the row table once but those that may be NULL (then NULL, as a COPY leaves them);
    sent in binary (the doubles bit for bit). Returns the chunks written.

    Raises
    ------
    InvalidInputError
        A column of another wire type (nothing is sent).
    """
    return _chunk_rows_call(conn, "insert_chunk_rows", table, columns)


def delete_chunk_rows(conn: Conn, table: str, keys: Sequence[tuple[str, npt.ArrayLike, str]]) -> int:
    """Delete rows of the model table ``tgsis.<table>`` stored in chunks by key: one call of ``tgsis.delete_chunk_rows``.

    ``keys``: ``(name, values (n,), wire type)``, every column of the row table's key once (``int8`` or
    ``float8``, the doubles sent bit for bit); keys not there are skipped. Returns the rows deleted.

    Raises
    ------
    InvalidInputError
        A column of another wire type (nothing is sent).
    """
    return _chunk_rows_call(conn, "delete_chunk_rows", table, keys)


def replace_chunk_rows(
    conn: Conn,
    table: str,
    keys: Sequence[tuple[str, npt.ArrayLike, str]],
    columns: Sequence[tuple[str, npt.ArrayLike, str]],
) -> tuple[int, int]:
    """Delete rows of the model table ``tgsis.<table>`` stored in chunks by key and insert others: one call of
    ``tgsis.replace_chunk_rows``, each touched chunk written once.

    ``keys`` as :func:`delete_chunk_rows` takes them, ``columns`` as :func:`insert_chunk_rows`; a key deleted and
    inserted again is replaced. Returns (rows deleted, chunks written).

    Raises
    ------
    InvalidInputError
        A column of another wire type (nothing is sent).
    """
    deleted = _chunk_rows_arguments(table, keys)
    inserted = _chunk_rows_arguments(table, columns)
    row = conn.execute(
        "SELECT * FROM tgsis.replace_chunk_rows(%s, %s::text[], %b::bigint[], %b::float8[],"
        " %s::text[], %b::bigint[], %b::float8[], %b::boolean[])",
        (table, *deleted[:3], *inserted),
    ).fetchone()
    return (int(row[0]), int(row[1])) if row is not None else (0, 0)


def _chunk_rows_arguments(
    table: str, columns: Sequence[tuple[str, npt.ArrayLike, str]]
) -> tuple[list[str], Any, Any, Any]:
    """(names, ints, floats, bools) of ``tgsis.insert_chunk_rows`` and its kin: the integer, double and boolean
    columns, each as (columns x rows) lists (floats and bools None when there are none). A point of a G-map's
    vertex table (wire type ``float8[m]``, values (rows, m)) goes as m double rows of its name in a row."""
    ints = [(n, np.asarray(v, dtype=np.int64)) for n, v, w in columns if w in ("int8", "int4", "int2")]
    floats: list[tuple[str, npt.NDArray[np.float64]]] = []
    for n, v, w in columns:
        if w == "float8":
            floats.append((n, np.asarray(v, dtype=np.float64)))
        elif re.fullmatch(r"float8\[\d+\]", w):
            coordinates = np.asarray(v, dtype=np.float64)
            if coordinates.ndim != 2 or coordinates.shape[1] != int(w[7:-1]):
                raise InvalidInputError(
                    f"tgsis.{table}: the points of column {n} are ({len(coordinates)}, {w[7:-1]}) doubles",
                    detail=f"shape {coordinates.shape}",
                )
            floats.extend((n, coordinates[:, i]) for i in range(coordinates.shape[1]))
    bools = [(n, np.asarray(v, dtype=np.bool_)) for n, v, w in columns if w == "bool"]
    if len(ints) + len({n for n, _ in floats}) + len(bools) != len(columns):
        raise InvalidInputError(
            f"tgsis.{table}: rows stored in chunks are written as integer, double precision and boolean columns only",
            detail=f"columns {[(n, w) for n, _, w in columns]}",
        )
    count = len(ints[0][1]) if ints else 0
    int_rows = np.stack([v for _, v in ints]) if ints else np.empty((0, count), dtype=np.int64)
    float_rows = np.stack([v for _, v in floats]) if floats else None
    bool_rows = np.stack([v for _, v in bools]) if bools else None
    return (
        [n for n, _ in (*ints, *floats, *bools)],
        int_rows.tolist(),
        float_rows.tolist() if float_rows is not None and count else None,
        bool_rows.tolist() if bool_rows is not None and count else None,
    )


def _chunk_rows_call(conn: Conn, function: str, table: str, columns: Sequence[tuple[str, npt.ArrayLike, str]]) -> int:
    """``tgsis.<function>(table, names, ints, floats[, bools])``: the integer, double and boolean columns, as (columns x rows).

    The boolean array is sent only when there are boolean columns (``tgsis.insert_chunk_rows`` takes it, a
    G-map dart's ``positive``; ``tgsis.delete_chunk_rows``' keys have none).
    """
    names, ints, floats, bools = _chunk_rows_arguments(table, columns)
    row = conn.execute(
        sql.SQL("SELECT tgsis.{}(%s, %s::text[], %b::bigint[], %b::float8[]{})").format(
            sql.Identifier(function), sql.SQL(", %b::boolean[]" if bools is not None else "")
        ),
        (table, names, ints, floats, *([bools] if bools is not None else [])),
    ).fetchone()
    return int(row[0]) if row is not None else 0


@contextlib.contextmanager
def staged(conn: Conn, table: sql.Composable, columns: Sequence[str]) -> Iterator[sql.Composable]:
    """Where a COPY into ``table`` goes: the table, or a temporary table moved into it when the COPY ends.

    PostgreSQL refuses ``COPY FROM`` into a table whose row-level security
    applies to the role ("COPY FROM not supported with row-level security"):
    the model tables every feature class shares keep the rows of classes a role
    may not change from it that way (``tgsis.protect_model_tables``). For such
    a role the rows go into a temporary table of the same columns first, then
    into the table with one ``INSERT ... SELECT``, whose policies check every
    row (docs/security.md, "Per-class rights at the model tables"). Owners and
    superusers, whom row security spares, COPY straight in.
    """
    guarded = conn.execute(
        sql.SQL("SELECT row_security_active({}::regclass)").format(sql.Literal(table.as_string(conn)))
    ).fetchone()
    if not guarded or not guarded[0]:
        yield table
        return
    names = sql.SQL(", ").join(sql.Identifier(c) for c in columns)
    stage = sql.Identifier(f"tgsis_stage_{next(_STAGES)}")
    conn.execute(
        sql.SQL("CREATE TEMPORARY TABLE {} ON COMMIT DROP AS SELECT {} FROM {} WITH NO DATA").format(
            stage, names, table
        )
    )
    yield stage
    conn.execute(sql.SQL("INSERT INTO {} ({}) SELECT {} FROM {}").format(table, names, names, stage))
    conn.execute(sql.SQL("DROP TABLE {}").format(stage))


#: numbers of the temporary tables of :func:`staged` (unique in the session)
_STAGES = itertools.count()


@dataclass(frozen=True)
class Storage:
    """Where bulk rows go: the tables themselves, or for versioned tables their
    ``_ver`` storage with the session's working revision (no trigger per row).

    ``version`` and ``viewing`` are the session's working version and viewing
    revision when it is *not* in DEFAULT's working revision (else ``None``):
    then a write to a plain table is refused (:meth:`check`), since it would
    land in DEFAULT.
    """

    versioned: frozenset[tuple[str, str]]
    revision: int | None
    version: str | None = None
    viewing: int | None = None
    #: the relation storing each versioned table's rows, quoted, as SQL's ``tgsis.storage_table`` names it
    stored_in: Mapping[tuple[str, str], str] = field(default_factory=dict)
    #: versioned property tables stored in chunks (``tgsis.store_class_in_chunks``): rows go through their face,
    #: whose trigger writes the chunks in the working revision
    faces: frozenset[tuple[str, str]] = frozenset()
    #: model tables stored in chunks (``tgsis.stored_in_chunks``; versioned or not): rows COPied into them go in
    #: one set-based call of ``tgsis.insert_chunk_rows`` (model 2's times_vrtx and times_trgl once switched)
    chunked: frozenset[tuple[str, str]] = frozenset()

    @classmethod
    def of(cls, conn: Conn, fc: FeatureClass | None = None) -> Storage:
        """The targets of the session's writes; of the features of ``fc`` when given.

        A class registered without versioning (``fc.versioned`` false) has
        features of no version: their rows in versioned storage carry
        revision 0 (``tgsis.unversioned_features``), and they are written
        in DEFAULT's working revision only.

        Raises
        ------
        NotVersionedError
            ``fc`` has no versioning and the session is elsewhere (nothing is written).
        """
        tables = conn.execute(
            "SELECT schemaname, tablename, tgsis.storage_table(schemaname, tablename),"
            " schemaname <> 'tgsis' AND tgsis.stored_in_chunks(schemaname, tablename) FROM tgsis.versioned_tables"
        ).fetchall()
        stored_in = {(r[0], r[1]): str(r[2]) for r in tables}
        faces = frozenset((r[0], r[1]) for r in tables if r[3])
        versioned = frozenset(stored_in)
        session = conn.execute(
            "SELECT tgsis.get_working_version(), tgsis.get_viewing_revision(), "
            "(SELECT workingrevision FROM tgsis.versions WHERE name = tgsis.get_working_version())"
        ).fetchone()
        assert session is not None
        version, viewing, working = session
        elsewhere = version != "DEFAULT" or (viewing is not None and viewing != working)
        chunked = frozenset(
            ("tgsis", str(r[0]))
            for r in conn.execute(
                "SELECT tablename FROM tgsis.model_tables WHERE chunkcolumn IS NOT NULL AND tgsis.stored_in_chunks(tablename)"
            ).fetchall()
        )
        storage = cls(
            versioned, None, version if elsewhere else None, viewing if elsewhere else None, stored_in, faces, chunked
        )
        unversioned = fc is not None and not fc.versioned
        if unversioned:
            assert fc is not None
            storage.check_unversioned(fc)
        if not versioned:
            return storage
        row = conn.execute("SELECT revision FROM tgsis.write_revision()").fetchone()  # TG301 when read-only
        assert row is not None
        return replace(storage, revision=0 if unversioned else int(row[0]))

    def check_unversioned(self, fc: FeatureClass) -> None:
        """Refuse a write of the features of ``fc``, a class without versioning, outside DEFAULT's working revision.

        Raises
        ------
        NotVersionedError
            Nothing is written.
        """
        if self.version is None:
            return
        if self.version != "DEFAULT":
            raise NotVersionedError(
                f"features of class {fc.name} are not versioned: a write in version {self.version!r} would change "
                "them in every version",
                detail=f"the connection works in version {self.version!r}, but class {fc.name} was registered "
                "without versioning: its features hold one state, which every version reads; nothing was written",
                hint="tgsis.goto_version(conn, 'DEFAULT') to write them",
            )
        raise NotVersionedError(
            f"features of class {fc.name} are not versioned: DEFAULT viewed at revision {self.viewing} cannot write them",
            detail=f"the connection looks at an older revision; class {fc.name} holds only the current state of its "
            "features; nothing was written",
            hint="tgsis.goto_version(conn, 'DEFAULT') to write the current state",
        )

    def check(self, schema: str, table: str) -> None:
        """Refuse a write to a plain ``schema.table`` while the session is not in DEFAULT's working revision.

        Raises
        ------
        NotVersionedError
            The write would land in DEFAULT (nothing is written).
        """
        if self.version is None or (schema, table) in self.versioned:
            return
        if self.version != "DEFAULT":
            raise NotVersionedError(
                f"table {schema}.{table} is not versioned: a write in version {self.version!r} would change DEFAULT, "
                "which every version reads",
                detail=f"the connection works in version {self.version!r}, but feature versioning is off, so the "
                "feature tables hold one state for all versions; nothing was written",
                hint="tgsis.enable_feature_versioning(conn) to write features in versions, or write in DEFAULT "
                "(tgsis.goto_version(conn, 'DEFAULT'), or outside tgsis.in_version)",
            )
        raise NotVersionedError(
            f"table {schema}.{table} is not versioned: DEFAULT viewed at revision {self.viewing} cannot be written",
            detail="the connection looks at an older revision; the table holds only the current state; "
            "nothing was written",
            hint="tgsis.goto_version(conn, 'DEFAULT') to write the current state",
        )

    def copy(self, conn: Conn, schema: str, table: str, columns: Sequence[tuple[str, npt.ArrayLike, str]]) -> None:
        """COPY ``(name, values, wire type)`` columns into ``schema.table`` in the working revision.

        A model table stored in chunks (:attr:`chunked`) takes them in one call of ``tgsis.insert_chunk_rows``
        (its checks are the face's; a key already there is refused as on rows).
        """
        if (schema, table) in self.chunked:
            self.check(schema, table)
            insert_chunk_rows(conn, table, columns)
            return
        copy_in(conn, *self._prepared(schema, table, columns))

    def copy_all(
        self,
        conn: Conn,
        tables: Sequence[tuple[str, str, Callable[[], Columns]]],
        upload: Callable[[str, Columns], bool] | None = None,
    ) -> None:
        """COPY several tables in turn, the client's work overlapping the server's.

        ``upload(table, columns)``, when given, writes the columns of a model table stored in chunks
        (:attr:`chunked`) itself (the G-map uploads: chunks encoded by the client,
        ``tgsis.db._chunk_transfer.upload_rows``) and returns whether it did; where it did not, or without it,
        they go through :meth:`copy` (``tgsis.insert_chunk_rows``).

        ``tables``: ``(schema, table, columns)`` where ``columns()`` gives the
        ``(name, values, wire type)`` columns. The callables start at once and
        run one after the other in order, in one worker thread (a later one
        may use what an earlier one computed); a second thread encodes the
        rows in pieces (:func:`tgsis.db.copy.encode_chunks`), one piece ahead
        of the one the server is taking. numpy and the socket wait release
        the GIL: a 6M-dart G-map's orientation is computed while its 18M
        alpha rows go in (bench/gmaps_db.py). An exception of a callable or of
        the encoding is raised here; the caller's transaction then holds
        nothing of it.
        """
        with concurrent.futures.ThreadPoolExecutor(1) as makers, concurrent.futures.ThreadPoolExecutor(1) as coders:
            made = [makers.submit(columns) for _, _, columns in tables]
            try:
                for (schema, table, _), future in zip(tables, made):
                    if (schema, table) in self.chunked:
                        if upload is None or not upload(table, future.result()):
                            self.copy(conn, schema, table, future.result())
                        continue
                    target, columns = self._target(schema, table, future.result())
                    chunks = encode_chunks([(values, wire) for _, values, wire in columns])
                    ahead = coders.submit(next, chunks, None)
                    names = [name for name, _, _ in columns]
                    with staged(conn, target, names) as into, conn.cursor().copy(_copy_statement(into, names)) as copy:
                        while (piece := ahead.result()) is not None:
                            ahead = coders.submit(next, chunks, None)
                            copy.write(piece)
            finally:
                for future in made:
                    future.cancel()

    def table(self, schema: str, table: str) -> sql.Composable:
        """The relation that stores the rows of ``schema.table``: itself, or its versioned storage
        (``tgsis.storage_table``, read with the set of versioned tables)."""
        stored = None if (schema, table) in self.faces else self.stored_in.get((schema, table))
        return sql.Identifier(schema, table) if stored is None else sql.SQL(stored)  # quoted by format('%I.%I')

    def _target(self, schema: str, table: str, columns: Columns) -> tuple[sql.Composable, Columns]:
        """Where ``columns`` go: the table, or its versioned storage with the revision column added."""
        self.check(schema, table)
        if (schema, table) in self.faces:
            return sql.Identifier(schema, table), columns
        count = len(np.asarray(columns[0][1])) if columns else 0
        if (schema, table) in self.versioned:
            assert self.revision is not None
            columns = [*columns, ("revision", np.full(count, self.revision, dtype=np.int32), "int4")]
        return self.table(schema, table), columns

    def _prepared(self, schema: str, table: str, columns: Columns) -> tuple[sql.Composable, list[str], bytes]:
        """Where ``columns`` go, their names and their payload."""
        target, columns = self._target(schema, table, columns)
        return (target, [name for name, _, _ in columns], encode_rows([(values, wire) for _, values, wire in columns]))


def concat(arrays: Sequence[npt.NDArray[Any]]) -> npt.NDArray[Any]:
    """The arrays one after the other (no copy for one array)."""
    return arrays[0] if len(arrays) == 1 else np.concatenate(arrays)


def row_keys(geoids: Sequence[int], counts: Sequence[int]) -> tuple[npt.NDArray[np.int64], npt.NDArray[np.int64]]:
    """(geoid, local id) columns for ``counts[i]`` rows of each ``geoids[i]``: ids 0..counts[i]-1."""
    total = int(sum(counts))
    if len(counts) == 1:
        return np.full(total, geoids[0], dtype=np.int64), np.arange(total, dtype=np.int64)
    starts = np.cumsum([0, *counts[:-1]])
    return (
        np.repeat(np.asarray(geoids, dtype=np.int64), counts),
        np.arange(total, dtype=np.int64) - np.repeat(starts, counts).astype(np.int64),
    )


def copy_out(conn: Conn, query: sql.Composable, types: Sequence[str]) -> list[npt.NDArray[Any]]:
    statement = sql.SQL("COPY ({}) TO STDOUT (FORMAT binary)").format(query)
    with conn.cursor().copy(statement) as copy:
        data = b"".join(bytes(chunk) for chunk in copy)
    return decode_rows(data, types)


#: :func:`packed_out` groups rows by each key column shifted right by this many bits (1,024 ids a group)
PACKED_GROUP_BITS = 10


def packed_out(
    conn: Conn,
    query: sql.Composable,
    columns: Sequence[tuple[str, str]],
    keys: Sequence[str],
    exact: Sequence[str] = (),
) -> list[npt.NDArray[Any]]:
    """The rows of a query, as columns, sent by the server packed in groups of rows, not one COPY message per row.

    What :func:`copy_out` gives (rows in no order), for a query of many rows
    whose fixed-width columns include integer keys: the server packs each
    row's values in their binary send forms (``int8send(vrtxid) ||
    float8send(x) || ...``) and aggregates them by blocks of keys
    (``GROUP BY geoid >> 10, vrtxid >> 10``, :data:`PACKED_GROUP_BITS`), so
    that the client decodes about one value per 1,024 rows with one numpy
    structured array. Reading a COPY message per row cost the snapshot at t
    of a 1M-vertex surface most of its time (docs/performance.md). A group
    holds at most 1,024 rows per distinct value of each key, so a group's
    bytes stay far below a ``bytea``'s 1 GB when the keys identify the rows.

    Parameters
    ----------
    query : Composable
        A ``SELECT`` whose output names every column of ``columns`` and ``keys``.
    columns : sequence of (str, str)
        The columns returned, as (name, wire type: ``int8``, ``float8``, ...).
    keys : sequence of str
        Integer columns of the query (usually the geoid and the local id) that group its rows.
    exact : sequence of str
        Columns of the query that group its rows by their values (an instant ``times``), before ``keys``.

    Returns
    -------
    list of ndarray
        One (n,) array per column, native byte order, rows in no order.

    Raises
    ------
    DatabaseError
        A row holds a NULL (the aggregate would skip it: counted, reported, not dropped).
    """
    sends = []
    for name, wire in columns:
        base, size = wire_shape(wire)
        send = "array_send" if size is not None else SEND_FUNCTIONS[base]
        sends.append(sql.SQL("{}(q.{})").format(sql.Identifier(send), sql.Identifier(name)))
    statement = sql.SQL(
        "SELECT count(*)::int8, string_agg({row}, ''::bytea) FROM ({query}) q GROUP BY {groups}"
    ).format(
        row=sql.SQL(" || ").join(sends),
        query=query,
        groups=sql.SQL(", ").join(
            [
                *(sql.SQL("q.{}").format(sql.Identifier(k)) for k in exact),
                *(sql.SQL("q.{} >> {}").format(sql.Identifier(k), sql.Literal(PACKED_GROUP_BITS)) for k in keys),
            ]
        ),
    )
    groups = conn.execute(statement, binary=True).fetchall()
    return decode_packed(
        b"".join(bytes(data) for _, data in groups if data is not None),
        [wire for _, wire in columns],
        sum(int(count) for count, _ in groups),
        f"columns {', '.join(name for name, _ in columns)} of {query.as_string(conn)}",
    )


#: the function that gives a value of each wire type in its binary COPY form
SEND_FUNCTIONS = {
    "int2": "int2send",
    "int4": "int4send",
    "int8": "int8send",
    "float4": "float4send",
    "float8": "float8send",
    "bool": "boolsend",
}


class PartRequest(Protocol):
    """A part of :func:`columns_out_all`'s one query: :class:`Packed` rows, or a chunk table's rows
    (:class:`tgsis.db._chunk_transfer.PackedChunks`)."""

    def query(self, part: int) -> sql.Composed:
        """The rows ``(part int4, geoid int8, count int8, packed bytea)``: one per geometry that has rows here."""
        ...

    def decode(self, conn: Conn, groups: Sequence[tuple[int, int, bytes]]) -> list[npt.NDArray[Any]]:
        """The columns ``[geoid, *columns]`` (rows in no order) from its geometries' ``(geoid, count, packed)``."""
        ...


@dataclass(frozen=True)
class Packed:
    """One request of :func:`columns_out_all`: the rows of ``source`` whose ``key`` is one of ``geoids``.

    ``source`` is a table or view (the versioned views read the session's
    revision), ``key`` its geoid column, ``columns`` its fixed-width columns
    as (name, wire type).
    """

    source: sql.Composable
    key: str
    columns: Sequence[tuple[str, str]]
    geoids: Sequence[int]

    def query(self, part: int) -> sql.Composed:
        """The rows ``(part, geoid, count, packed rows)``: one per geometry that has rows here."""
        sends = []
        for name, wire in self.columns:
            base, size = wire_shape(wire)
            send = "array_send" if size is not None else SEND_FUNCTIONS[base]
            sends.append(sql.SQL("{}({})").format(sql.Identifier(send), sql.Identifier(name)))
        row = sql.SQL(" || ").join(sends)
        if len(self.geoids) == 1:  # one aggregate, no grouping: a group's state of tens of MB is not hashed or sorted
            return sql.SQL(
                "SELECT {part}::int4, {geoid}::int8, count(*), string_agg({row}, ''::bytea) FROM {source} "
                "WHERE {key} = {geoid}"
            ).format(
                part=sql.Literal(part),
                key=sql.Identifier(self.key),
                row=row,
                source=self.source,
                geoid=sql.Literal(int(self.geoids[0])),
            )
        # one such aggregate per geometry, one after the other: memory for one geometry's values at a time
        return sql.SQL(
            "SELECT {part}::int4, g.k, a.n, a.v FROM (SELECT DISTINCT unnest({geoids}::int8[]) AS k) g "
            "CROSS JOIN LATERAL (SELECT count(*) AS n, string_agg({row}, ''::bytea) AS v "
            "FROM {source} WHERE {key} = g.k) a"
        ).format(
            part=sql.Literal(part),
            key=sql.Identifier(self.key),
            row=row,
            source=self.source,
            geoids=sql.Literal([int(g) for g in self.geoids]),
        )

    def decode(self, conn: Conn, groups: Sequence[tuple[int, int, bytes]]) -> list[npt.NDArray[Any]]:
        """The columns ``[geoid, *columns]`` from the rows of :meth:`query` (:class:`PartRequest`)."""
        return _decode_groups(conn, self, groups)


def columns_out_all(conn: Conn, requests: Sequence[PartRequest]) -> list[list[npt.NDArray[Any]]]:
    """The rows of several :class:`Packed` requests, as columns: ``[key, *columns]`` for each.

    The rows stay rows in storage, but do not travel one by one: the server
    packs each row's values in their binary send forms
    (``int8send(vrtxid) || float8send(x) || ...``) and aggregates a
    geometry's rows into one ``bytea`` (``string_agg``); the client decodes
    a few large values with one numpy structured array instead of a COPY
    message per row (issue 20; docs/performance.md compares the ways
    measured). The requests go as one query, their aggregates joined by
    ``UNION ALL``: for a large geometry the planner runs them side by side
    in parallel workers (a Parallel Append of the tables' aggregates, when
    the server has workers to give), one geometry's vertices, cells and
    properties in the time of the largest instead of their sum; small ones
    stay one plain plan. Rows come in no particular order, as from
    :func:`copy_out`.

    Parameters
    ----------
    requests : sequence of Packed (or other :class:`PartRequest`)
        The tables and geometries. A row with a NULL (the concatenation is
        NULL and the aggregate skips it) is reported, not dropped. A table
        stored in chunks is read by its chunks
        (:class:`tgsis.db._chunk_transfer.PackedChunks`), in the same query.

    Returns
    -------
    list of list of ndarray
        For each request: (n,) int64 geoids, then one (n,) or (n, k) array per column.

    Raises
    ------
    DatabaseError
        A row holds a NULL or a value of another size (message names the
        columns, the table and the row).
    """
    if not requests:
        return []
    query = sql.SQL(" UNION ALL ").join(request.query(part) for part, request in enumerate(requests))
    groups: list[list[tuple[int, int, bytes]]] = [[] for _ in requests]
    with conn.cursor(binary=True) as cursor:
        for part, geoid, count, data in cursor.execute(query).fetchall():
            if count:
                groups[part].append((int(geoid), int(count), data or b""))
    return [request.decode(conn, found) for request, found in zip(requests, groups, strict=True)]


def columns_out(
    conn: Conn, source: sql.Composable, key: str, columns: Sequence[tuple[str, str]], geoids: Sequence[int]
) -> list[npt.NDArray[Any]]:
    """The rows of ``source`` whose ``key`` is one of ``geoids``, as columns: ``[key, *columns]``.

    One :class:`Packed` request of :func:`columns_out_all` (its parameters and errors).
    """
    return columns_out_all(conn, [Packed(source, key, columns, geoids)])[0]


def _decode_groups(conn: Conn, request: Packed, groups: Sequence[tuple[int, int, bytes]]) -> list[npt.NDArray[Any]]:
    """The columns of ``request`` from its geometries' ``(geoid, count, packed rows)``."""
    counts = [count for _, count, _ in groups]
    what = f"columns {', '.join(name for name, _ in request.columns)} of {request.source.as_string(conn)}"
    try:
        values = decode_packed(
            b"".join(data for _, _, data in groups), [wire for _, wire in request.columns], sum(counts), what
        )
    except DatabaseError as exc:  # the rare path: find the row to name
        raise _bad_row(conn, request.source, request.key, request.columns, request.geoids) or exc from None
    return [np.repeat(np.asarray([geoid for geoid, _, _ in groups], dtype=np.int64), counts), *values]


def corners_out(
    conn: Conn, source: sql.Composable, key: str, corners: Sequence[str], geoid: int
) -> npt.NDArray[np.int64]:
    """The corner ids of one geometry's cells (rows of ``source``), in no order and without the cells' ids.

    For a mesh that is drawn, not written back (the browser view): when a
    row's k corner ids all lie in 0 .. 2**(63 // k) - 1 (vertex ids are
    local to a geometry, so that is the usual case: 2,097,151 for
    triangles), they travel packed in one ``int8`` (``a << 42 | b << 21 |
    c``): one value for the server to send per row instead of k + 1 (a
    third less server time for 2M triangles; docs/performance.md). A row
    out of that range or with a NULL sends nothing, which the count shows:
    the corners then come as columns (:func:`columns_out`, which names a
    NULL).

    Parameters
    ----------
    source : Composable
        A table or view of cells (a versioned view reads the session's revision).
    key : str
        The geoid column.
    corners : sequence of str
        The k >= 2 integer corner columns.
    geoid : int
        The geometry.

    Returns
    -------
    (m, k) int64
        The corner ids, one row per cell.
    """
    k = len(corners)
    bits = 63 // k
    packed = sql.SQL(" | ").join(
        sql.SQL("({}::int8 << {})").format(sql.Identifier(c), sql.Literal(bits * (k - 1 - i)))
        if i < k - 1
        else sql.SQL("{}::int8").format(sql.Identifier(c))
        for i, c in enumerate(corners)
    )
    # every corner in 0 .. 2**bits - 1 exactly when their bitwise or is (a negative id sets the sign bit)
    in_range = sql.SQL("({}) BETWEEN 0 AND {}").format(
        sql.SQL(" | ").join(sql.SQL("{}::int8").format(sql.Identifier(c)) for c in corners),
        sql.Literal((1 << bits) - 1),
    )
    query = sql.SQL(
        "SELECT count(*), string_agg(CASE WHEN {in_range} THEN int8send({packed}) END, ''::bytea) "
        "FROM {source} WHERE {key} = {geoid}"
    ).format(in_range=in_range, packed=packed, source=source, key=sql.Identifier(key), geoid=sql.Literal(geoid))
    with conn.cursor(binary=True) as cursor:
        row = cursor.execute(query).fetchone()
    assert row is not None
    count, data = int(row[0]), row[1] or b""
    if len(data) != 8 * count:  # a corner out of range, or a NULL: as columns, which names a NULL
        return np.stack(columns_out(conn, source, key, [(c, "int8") for c in corners], [geoid])[1:], axis=1)
    values = np.frombuffer(data, dtype=">i8").astype(np.int64)
    mask = (1 << bits) - 1
    return np.stack([(values >> (bits * (k - 1 - i))) & mask for i in range(k)], axis=1)


def _bad_row(
    conn: Conn, source: sql.Composable, key: str, columns: Sequence[tuple[str, str]], geoids: Sequence[int]
) -> DatabaseError | None:
    """The error naming a row of :func:`columns_out` that holds a NULL or a vector of another length."""
    for name, wire in columns:
        size = wire_shape(wire)[1]
        bad = (
            sql.SQL("{} IS NULL").format(sql.Identifier(name))
            if size is None
            else sql.SQL(
                "{} IS NULL OR array_ndims({}) IS DISTINCT FROM 1 OR cardinality({}) <> {} OR array_position({}, NULL) "
                "IS NOT NULL"
            ).format(*(sql.Identifier(name),) * 3, size, sql.Identifier(name))
        )
        row = conn.execute(
            sql.SQL("SELECT {}, {} FROM {} WHERE {} = ANY({}) AND ({}) LIMIT 1").format(
                sql.Identifier(key),
                sql.Identifier(columns[0][0]),
                source,
                sql.Identifier(key),
                sql.Literal(list(geoids)),
                bad,
            )
        ).fetchone()
        if row is not None:
            return DatabaseError(
                f"column {name} of {source.as_string(conn)} is NULL or not {wire} in the row "
                f"{key} = {row[0]}, {columns[0][0]} = {row[1]}",
                hint=f"SELECT * FROM tgsis.check_geometry({row[0]})",
            )
    return None


def rows_by_geoid(
    geoids: npt.NDArray[np.int64], ids: npt.NDArray[np.int64], wanted: Sequence[int]
) -> dict[int, npt.NDArray[np.int64]]:
    """Row positions of each wanted geoid, ordered by the local id."""

    def ascending(values: npt.NDArray[np.int64]) -> bool:
        return bool(np.all(values[1:] >= values[:-1]))

    if len(wanted) == 1:  # the common case: skip the two-key sort
        order = np.arange(len(ids)) if ascending(ids) else np.argsort(ids, kind="stable")
        return {wanted[0]: order}
    order = np.lexsort((ids, geoids))
    sorted_geoids = geoids[order]
    starts = np.searchsorted(sorted_geoids, wanted, side="left")
    ends = np.searchsorted(sorted_geoids, wanted, side="right")
    return {g: order[s:e] for g, s, e in zip(wanted, starts.tolist(), ends.tolist())}


def local_positions(
    ids: npt.NDArray[np.int64], lookup: npt.NDArray[np.int64], what: str, geoid: int
) -> npt.NDArray[np.int64]:
    """Indices of ``lookup`` values in the sorted ``ids`` (vertex ids to mesh indices)."""
    if len(ids) and ids[-1] - ids[0] == len(ids) - 1:
        positions = lookup - ids[0] if ids[0] else lookup  # ids k..k+n-1 (unique): index = id - k
        if len(lookup) and (positions.min() < 0 or positions.max() >= len(ids)):
            raise InvalidGeometryError(
                f"geometry {geoid}: {what} refer to missing vertices",
                hint=f"SELECT * FROM tgsis.check_geometry({geoid})",
            )
        return positions
    positions = np.searchsorted(ids, lookup)
    if len(lookup) and (np.any(positions >= len(ids)) or np.any(ids[np.minimum(positions, len(ids) - 1)] != lookup)):
        raise InvalidGeometryError(
            f"geometry {geoid}: {what} refer to missing vertices", hint=f"SELECT * FROM tgsis.check_geometry({geoid})"
        )
    return positions


def insert_feature_row(conn: Conn, fc: FeatureClass, geoid: int, properties: Mapping[str, Any] | None) -> None:
    """The feature row of a new feature: its id and per-feature property values (unknown names refused)."""
    values = feature_columns(fc, properties)
    check_feature_values(conn, fc, values)
    columns = ["_geoid", *values]
    conn.execute(
        sql.SQL("INSERT INTO {} ({}) VALUES ({})").format(
            fc.qualified(fc.featuretable),
            sql.SQL(", ").join(sql.Identifier(c) for c in columns),
            sql.SQL(", ").join(sql.Placeholder() for _ in columns),
        ),
        [geoid, *values.values()],
    )
    check_class_unchanged(conn, fc)
