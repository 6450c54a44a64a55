"""Chunk codec of issue 40 (pure numpy): rows of one object in blocks of 1,024 consecutive ids, and their COPY form.

The contract (docs/storage.md, "Chunks and the mapping of ids"): a chunk table
``tgsis.<t>_chunk`` stores the rows of row table ``tgsis.<t>`` of one object in
rows ``(geoid, chunk, revision, lastrevs, revclosed, holes, [vbase], arrays...,
[<ref>_wide...])``:

* ``chunk = id >> 10``; array element i (1-based) is the row with id
  ``chunk * 1024 + i - 1``; arrays end at the last present slot;
* ``holes`` (``smallint[]``): the 1-based slots of absent ids below the last
  present slot, ascending, NULL when none; a hole's element is NULL in every
  array;
* a float8 column is a ``double precision[]`` of the same name (bit-exact);
* the *ref columns* (vertex ids ``vrtxid1..k`` of points, segments, triangles,
  tetrahedra): ``vbase bigint`` (the smallest of all ref values of the chunk),
  the first ref column as ``v1 - vbase`` and the others as ``vK - v1`` in
  ``integer[]``; a chunk where one of these differences does not fit int4 keeps
  ``vbase`` and the ``integer[]`` columns NULL and the ids in
  ``<ref>_wide bigint[]`` (NULL in the other chunks).

This module encodes rows (:func:`encode`) into :class:`ChunkSet` arrays and
back (:meth:`ChunkSet.rows`), writes the PostgreSQL binary COPY stream of a
chunk set (:func:`to_copy`, what ``COPY tgsis.<t>_chunk (cols...) FROM STDIN
(FORMAT binary)`` reads) and parses one (:func:`from_copy`, what ``COPY
(SELECT chunk, holes, ...) TO STDOUT (FORMAT binary)`` writes). Everything
is vectorised with numpy; the only Python loops are per chunk (about 1,000 per
million ids). No database here: psycopg is never imported.
"""

from __future__ import annotations

import struct
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import numpy.typing as npt

from tgsis.errors import InvalidInputError

__all__ = [
    "CHUNK_BITS",
    "CHUNK_SIZE",
    "ChunkColumns",
    "ChunkSet",
    "encode",
    "to_copy",
    "from_copy",
    "COPY_SIGNATURE",
]

#: ids per chunk: 2**CHUNK_BITS
CHUNK_BITS = 10
CHUNK_SIZE = 1 << CHUNK_BITS

#: The first 11 bytes of a PostgreSQL binary COPY stream.
COPY_SIGNATURE = b"PGCOPY\n\xff\r\n\x00"

#: element type OIDs of array_recv/array_send
_OID = {"float8": 701, "int8": 20, "int4": 23, "int2": 21, "float4": 700, "bool": 16}
_BIG_ENDIAN = {"float8": ">f8", "int8": ">i8", "int4": ">i4", "int2": ">i2", "float4": ">f4", "bool": "u1"}
_WIDTH = {kind: np.dtype(code).itemsize for kind, code in _BIG_ENDIAN.items()}
#: the element kinds a property column may have (docs/storage.md, "Property chunks: the contract"), and their values
PROPERTY_KINDS: dict[str, Any] = {
    "int2": np.int16,
    "int4": np.int32,
    "int8": np.int64,
    "float4": np.float32,
    "float8": np.float64,
    "bool": np.bool_,
}
_INT4_MIN, _INT4_MAX = -(2**31), 2**31 - 1
#: the types a key column between the object key and ``chunk`` may have (:attr:`ChunkColumns.instant_kinds`)
_KEY_KINDS = ("float8", "int2", "int4", "int8")

IntArray = npt.NDArray[np.int64]
BoolArray = npt.NDArray[np.bool_]


@dataclass(frozen=True)
class ChunkColumns:
    """The non-key columns of a row table as a chunk table stores them.

    Parameters
    ----------
    names : tuple of str
        The row table's non-key columns in its column order (``("x", "y", "z")``,
        ``("vrtxid1", "vrtxid2", "vrtxid3")``).
    refs : tuple of str
        Those of ``names`` that are vertex ids (stored relative, with ``vbase``
        and ``<name>_wide``); the first of them is the base of the others.
    integers : tuple of str
        Those of ``names`` that are other bigint columns (``bigint[]``); the rest are float8.
    properties : tuple of (str, str)
        Those of ``names`` that are a feature class's properties (docs/storage.md, "Property chunks: the
        contract"), with their element kind (a key of :data:`PROPERTY_KINDS`: ``int2``, ``int4``, ``int8``,
        ``float4``, ``float8``, ``bool``): arrays of that type whose elements may be NULL at present slots
        too (a value missing, not a hole: :attr:`ChunkSet.nulls`).
    key : str
        The chunk table's object key column (``geoid``; ``_geoid`` for a class's property table).
    instant : tuple of str
        The key columns after ``key`` (``("times",)`` for model 2's time tables, keyed ``(geoid, times, chunk)``;
        ``("level",)`` for a G-map's involutions, keyed ``(geoid, level, chunk)``); empty for the tables keyed by
        the object alone.
    instant_kinds : tuple of str
        The type of each of ``instant`` (``float8``, the default when empty, or ``int2``, ``int4``, ``int8``):
        how :func:`to_copy` writes its value.
    vectors : tuple of (str, int)
        Those of the properties that are vectors (a class's vector property, role ``vector``), with their size
        k >= 2: one two-dimensional array per chunk, slots x k from ``[1][1]``, whose row is k NULLs at a hole
        and at a NULL vector (docs/storage.md, "Vector properties in chunks"); their values are (n, k).
    points : tuple of str
        Those of ``names`` that are a G-map's points (role ``point``: ``gmap_vertex``, ``md_vertex``), float8: one
        two-dimensional array per chunk, slots x m from ``[1][1]``, m >= 1 the object's (not the table's: read
        from the values when encoded, from the array when decoded), a row of m NULLs at a hole and none elsewhere
        (docs/storage.md, "The points in chunks"); their values are (n, m).
    """

    names: tuple[str, ...]
    refs: tuple[str, ...] = ()
    integers: tuple[str, ...] = ()
    properties: tuple[tuple[str, str], ...] = ()
    key: str = "geoid"
    instant: tuple[str, ...] = ()
    instant_kinds: tuple[str, ...] = ()
    vectors: tuple[tuple[str, int], ...] = ()
    points: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        kinds = dict(self.properties)
        sizes = dict(self.vectors)
        if any(p not in self.names or p in kinds or p in self.refs or p in self.integers for p in self.points):
            raise InvalidInputError(
                f"chunk columns {list(self.names)}: points {list(self.points)} must be float8 columns among them"
            )
        if len(sizes) != len(self.vectors) or any(n not in kinds or int(k) < 2 for n, k in self.vectors):
            raise InvalidInputError(
                f"chunk columns {list(self.names)}: vectors {list(self.vectors)} must be distinct properties "
                "among them, of size 2 or more"
            )
        if (self.instant_kinds and len(self.instant_kinds) != len(self.instant)) or any(
            k not in _KEY_KINDS for k in self.instant_kinds
        ):
            raise InvalidInputError(
                f"chunk keys {list(self.instant)}: kinds {list(self.instant_kinds)} must be one per key, of "
                f"{list(_KEY_KINDS)}"
            )
        unknown = [c for c in (*self.refs, *self.integers, *kinds) if c not in self.names]
        if (
            unknown
            or len(set(self.names)) != len(self.names)
            or set(self.instant) & {*self.names, self.key}
            or set(self.refs) & set(self.integers)
            or set(kinds) & (set(self.refs) | set(self.integers))
            or len(kinds) != len(self.properties)
            or any(k not in PROPERTY_KINDS for k in kinds.values())
        ):
            raise InvalidInputError(
                f"chunk columns {list(self.names)}: refs {list(self.refs)}, integers {list(self.integers)} and "
                f"properties {list(self.properties)} must be distinct columns among them, properties of the kinds "
                f"{list(PROPERTY_KINDS)}"
            )

    def nullable(self, name: str) -> bool:
        """Whether column ``name`` is a property, whose elements may be NULL at present slots."""
        return any(name == n for n, _ in self.properties)

    def dtype(self, name: str) -> Any:
        """The numpy type of column ``name``'s decoded values (int64 ids for a ref column; a vector's elements')."""
        kind = self.kind(name)
        return np.int64 if name in self.refs else PROPERTY_KINDS[kind]

    def size(self, name: str) -> int:
        """The number of values of column ``name`` per row: a vector property's k, else 1."""
        return int(dict(self.vectors).get(name, 1))

    def shape(self, name: str, n: int) -> tuple[int, ...]:
        """The shape of ``n`` rows of column ``name``: ``(n,)``, ``(n, k)`` for a vector property, ``(n, 0)`` for a
        point (m unknown: the object's)."""
        if name in self.points:
            return (n, 0)
        k = self.size(name)
        return (n, k) if k > 1 else (n,)

    @property
    def ref_order(self) -> tuple[str, ...]:
        """The ref columns in column order (the first is stored as ``v1 - vbase``)."""
        return tuple(c for c in self.names if c in self.refs)

    def kind(self, name: str) -> str:
        """The element type of column ``name``'s array: ``float8``, ``int8``, (a ref column) ``int4``, or a property's."""
        if name in self.refs:
            return "int4"
        if name in self.integers:
            return "int8"
        return dict(self.properties).get(name, "float8")

    def copy_columns(self) -> list[str]:
        """The columns a binary COPY of :func:`to_copy` fills, in its order (``lastrevs``, ``revclosed`` left out)."""
        wide = [f"{c}_wide" for c in self.ref_order]
        return [
            self.key,
            *self.instant,
            "chunk",
            "revision",
            "holes",
            *(["vbase", "vtop"] if self.refs else []),
            *self.names,
            *wide,
        ]

    def select_columns(self) -> list[str]:
        """The columns :func:`from_copy` parses, in its order: ``chunk, holes, [vbase,] arrays..., [wide...]``.

        ``vtop`` (a bound the readers of the cells on given vertices filter by) is written, not read back; the
        keys (object, instant) and the revision are not read by the codec either.
        """
        skipped = {self.key, *self.instant, "revision", "vtop"}
        return [c for c in self.copy_columns() if c not in skipped]


@dataclass(frozen=True)
class ChunkSet:
    """The chunks of one object's rows of one table: the contract's arrays, flattened over all chunks.

    The *slots* of all chunks are concatenated: chunk k owns slots
    ``offsets[k]:offsets[k + 1]`` (``lengths[k]`` of them, its arrays' length).

    Attributes
    ----------
    columns : ChunkColumns
    chunk : (c,) int64
        Chunk numbers, ascending.
    lengths : (c,) int64
        Array length of each chunk (its last present slot, 1-based).
    present : (s,) bool
        False on a hole; s = lengths.sum().
    values : dict of str to (s,) or (s, k) array
        The float8, bigint and property columns (0 on holes); a vector property's (s, k).
    vbase : (c,) int64
        Smallest ref value of each chunk (-1 where ``wide`` or without ref columns).
    wide : (c,) bool
        The chunk's ref values are in the ``_wide`` columns.
    relative : dict of str to (s,) int32
        The ref columns as stored (first ``v1 - vbase``, others ``vK - v1``; 0 on holes and in wide chunks).
    absolute : dict of str to (s,) int64
        The ref columns' ids (0 on holes); stored (the ``_wide`` arrays) only for wide chunks.
    vtop : (c,) int64
        A bound of each chunk's ref values, as the column ``vtop`` stores it (:func:`ref_bound`; -1 without ref
        columns; empty when decoded, :func:`from_copy` does not read it).
    nulls : dict of str to (s,) bool
        Per property column (:attr:`ChunkColumns.properties`) that has any: True at a present slot whose value
        is NULL (its value in ``values`` is 0); a column not in it has none.
    """

    columns: ChunkColumns
    chunk: IntArray
    lengths: IntArray
    present: BoolArray
    values: dict[str, npt.NDArray[Any]] = field(default_factory=dict)
    vbase: IntArray = field(default_factory=lambda: np.empty(0, dtype=np.int64))
    wide: BoolArray = field(default_factory=lambda: np.empty(0, dtype=bool))
    relative: dict[str, npt.NDArray[np.int32]] = field(default_factory=dict)
    absolute: dict[str, IntArray] = field(default_factory=dict)
    vtop: IntArray = field(default_factory=lambda: np.empty(0, dtype=np.int64))
    nulls: dict[str, BoolArray] = field(default_factory=dict)

    @property
    def offsets(self) -> IntArray:
        """(c + 1,) int64: first slot of each chunk, then the total."""
        return np.concatenate([[0], np.cumsum(self.lengths)]).astype(np.int64)

    def slot_chunk(self) -> IntArray:
        """(s,) int64: the index (0..c-1) of the chunk of each slot."""
        return np.repeat(np.arange(len(self.chunk), dtype=np.int64), self.lengths)

    def ids(self) -> IntArray:
        """(s,) int64: the id of each slot (holes included)."""
        offsets = self.offsets
        index = self.slot_chunk()
        return (self.chunk[index] << CHUNK_BITS) + (np.arange(int(offsets[-1]), dtype=np.int64) - offsets[index])

    def holes(self, k: int) -> npt.NDArray[np.int16]:
        """The ``holes`` array of chunk index k (1-based slots, ascending; empty: the column is NULL)."""
        start, stop = int(self.offsets[k]), int(self.offsets[k + 1])
        return (np.flatnonzero(~self.present[start:stop]) + 1).astype(np.int16)

    def rows(self) -> tuple[IntArray, dict[str, npt.NDArray[Any]]]:
        """The rows: ids ascending (n,) int64 and each column (n,) (float64, int64; ref columns int64 ids)."""
        dense = bool(self.present.all())
        ids = self.ids() if dense else self.ids()[self.present]
        refs = self._ref_columns()  # new arrays: kept as they are when there is no hole
        out: dict[str, npt.NDArray[Any]] = {}
        for name in self.columns.names:
            if name in refs:
                out[name] = refs[name] if dense else refs[name][self.present]
            else:
                out[name] = self.values[name].copy() if dense else self.values[name][self.present]
        return ids, out

    def null_rows(self) -> dict[str, BoolArray]:
        """Per property column with NULL values: (n,) bool, True where the row's value is NULL (rows as :meth:`rows`)."""
        dense = bool(self.present.all())
        return {name: mask.copy() if dense else mask[self.present] for name, mask in self.nulls.items()}

    def _ref_columns(self) -> dict[str, IntArray]:
        """Every ref column's ids (s,) int64 (0 on holes), the first column decoded once for all of them."""
        refs = self.columns.ref_order
        if not refs:
            return {}
        if not self.wide.any():
            first = np.repeat(self.vbase, self.lengths) + self.relative[refs[0]]
            return {name: first if name == refs[0] else first + self.relative[name] for name in refs}
        index = self.slot_chunk()
        first = np.where(self.wide, 0, self.vbase)[index] + self.relative[refs[0]].astype(np.int64)
        wide = self.wide[index]
        return {
            name: np.where(
                wide, self.absolute[name], first if name == refs[0] else first + self.relative[name].astype(np.int64)
            )
            for name in refs
        }


def _int_ids(values: npt.ArrayLike, what: str) -> IntArray:
    array = np.asarray(values)
    if array.ndim != 1 or (array.size and array.dtype.kind not in "iu"):
        raise InvalidInputError(f"{what} must be a one-dimensional integer array, got {array.dtype} {array.shape}")
    if array.dtype.kind == "u" and array.size and int(array.max()) > np.iinfo(np.int64).max:
        raise InvalidInputError(f"{what} exceed the bigint range")
    result = array.astype(np.int64)
    if result.size and int(result.min()) < 0:
        raise InvalidInputError(
            f"{what} must be >= 0 (local ids are 0.. and chunk = id >> 10): {int(result.min())} found",
            detail=f"{int((result < 0).sum())} negative values",
        )
    return result


def encode(
    ids: npt.ArrayLike,
    columns: Mapping[str, npt.ArrayLike],
    spec: ChunkColumns,
    nulls: Mapping[str, npt.ArrayLike] | None = None,
) -> ChunkSet:
    """Rows (ids in any order) as chunks.

    Parameters
    ----------
    ids : (n,) array_like of int
        Distinct local ids, >= 0, in any order.
    columns : mapping of str to (n,) array_like
        One value per row for every column of ``spec.names``: float64 for
        float8 columns (kept bit for bit), integers for ref and bigint columns
        (ref values >= 0: vertex ids); a property column (``spec.properties``)
        of its kind's numpy type (float32 and float64 kept bit for bit, bool
        for ``bool``; integers that fit the kind); a vector property
        (``spec.vectors``) (n, k).
    spec : ChunkColumns
    nulls : mapping of str to (n,) array_like of bool, optional
        Property columns whose rows' values are NULL where True (the value
        given there is ignored; a vector's whole row).

    Returns
    -------
    ChunkSet

    Raises
    ------
    InvalidInputError
        Negative or repeated ids, negative ref values, missing or extra
        columns, columns of the wrong length or type, NULLs given for a
        column that is no property.
    """
    id_array = _int_ids(ids, "ids")
    n = len(id_array)
    if set(columns) != set(spec.names):
        raise InvalidInputError(f"columns {sorted(columns)} are not the chunk columns {list(spec.names)}")
    null_given = dict(nulls or {})
    if any(not spec.nullable(name) for name in null_given):
        raise InvalidInputError(
            f"NULL values given for {sorted(n for n in null_given if not spec.nullable(n))}: only property columns "
            f"({[name for name, _ in spec.properties]}) hold NULLs"
        )
    ascending = n < 2 or bool((id_array[1:] > id_array[:-1]).all())  # the usual case: ids 0..n-1 in order
    order = None if ascending else np.argsort(id_array, kind="stable")
    sorted_ids = id_array if order is None else id_array[order]
    if not ascending and bool((sorted_ids[1:] == sorted_ids[:-1]).any()):
        repeated = sorted_ids[1:][sorted_ids[1:] == sorted_ids[:-1]]
        raise InvalidInputError(f"ids repeat: {int(repeated[0])} (and {len(repeated) - 1} more)")
    chunk_of = sorted_ids >> CHUNK_BITS
    slot = sorted_ids & (CHUNK_SIZE - 1)
    starts = np.flatnonzero(np.concatenate([[True], chunk_of[1:] != chunk_of[:-1]])) if n else np.empty(0, np.int64)
    chunk = chunk_of[starts].astype(np.int64)
    ends = np.concatenate([starts[1:], [n]]).astype(np.int64)
    lengths = (slot[ends - 1] + 1).astype(np.int64) if n else np.empty(0, dtype=np.int64)
    offsets = np.concatenate([[0], np.cumsum(lengths)]).astype(np.int64)
    row_chunk = np.repeat(np.arange(len(chunk), dtype=np.int64), ends - starts)
    total = int(offsets[-1])
    dense = total == n  # no hole: row k is slot k
    position = None if dense else offsets[:-1][row_chunk] + slot  # each row's slot in the flat arrays
    present = np.ones(total, dtype=bool)
    if position is not None:
        present[:] = False
        present[position] = True

    def slotted(rows: npt.NDArray[Any], dtype: Any) -> npt.NDArray[Any]:
        """Values in id order (one per row) spread over the slots (0 on holes)."""
        if position is None:
            return np.array(rows, dtype=dtype)  # a copy: the caller's arrays are never shared
        flat = np.zeros((total, *rows.shape[1:]), dtype=dtype)
        flat[position] = rows
        return flat

    def in_id_order(values: npt.NDArray[Any]) -> npt.NDArray[Any]:
        return values if order is None else values[order]

    values: dict[str, npt.NDArray[Any]] = {}
    null_slots: dict[str, BoolArray] = {}
    refs: dict[str, IntArray] = {}
    for name in spec.names:
        raw = np.asarray(columns[name])
        if name in spec.points:  # (n, m): m the object's, one for all its points
            if raw.ndim != 2 or raw.shape[0] != n or raw.shape[1] < 1 or raw.dtype.newbyteorder("=") != np.float64:
                raise InvalidInputError(
                    f"column {name!r} holds points: (n, m) float64 with m >= 1 expected, got {raw.dtype} {raw.shape}"
                )
            values[name] = slotted(in_id_order(raw), np.float64)
            continue
        if raw.shape != spec.shape(name, n):
            raise InvalidInputError(f"column {name!r} has shape {raw.shape}, expected {spec.shape(name, n)}")
        if name in spec.refs:
            refs[name] = in_id_order(_int_ids(raw, f"column {name!r}"))
            continue
        kind = spec.kind(name)
        if spec.nullable(name):
            values[name] = slotted(in_id_order(_property_values(name, raw, kind)), PROPERTY_KINDS[kind])
            if name in null_given:
                mask = np.asarray(null_given[name])
                if mask.shape != (n,) or mask.dtype != np.bool_:
                    raise InvalidInputError(
                        f"NULLs of column {name!r}: (n,) bool expected, got {mask.dtype} {mask.shape}"
                    )
                if mask.any():
                    null_slots[name] = slotted(in_id_order(mask), np.bool_)
            continue
        if kind == "float8" and raw.size and raw.dtype.newbyteorder("=") != np.float64:  # either byte order
            raise InvalidInputError(f"column {name!r} must be float64, got {raw.dtype}")
        if kind == "int8" and raw.size and raw.dtype.kind not in "iu":
            raise InvalidInputError(f"column {name!r} must be integers, got {raw.dtype}")
        values[name] = slotted(in_id_order(raw), np.float64 if kind == "float8" else np.int64)

    c = len(chunk)
    vbase = np.full(c, -1, dtype=np.int64)
    wide = np.zeros(c, dtype=bool)
    relative: dict[str, npt.NDArray[np.int32]] = {}
    absolute: dict[str, IntArray] = {}
    ref_order = spec.ref_order
    if ref_order and n:
        smallest = refs[ref_order[0]]
        for r in ref_order[1:]:
            smallest = np.minimum(smallest, refs[r])
        vbase = np.minimum.reduceat(smallest, starts).astype(np.int64)
        first = refs[ref_order[0]]
        diffs = {ref_order[0]: first - np.repeat(vbase, ends - starts)}
        diffs.update({r: refs[r] - first for r in ref_order[1:]})
        too_far = np.zeros(n, dtype=bool)
        for d in diffs.values():
            too_far |= (d < _INT4_MIN) | (d > _INT4_MAX)
        wide = np.logical_or.reduceat(too_far, starts).astype(bool)
        vbase[wide] = -1
        row_wide = np.repeat(wide, ends - starts) if wide.any() else None
        for r in ref_order:
            relative[r] = slotted(diffs[r] if row_wide is None else np.where(row_wide, 0, diffs[r]), np.int32)
            absolute[r] = slotted(refs[r], np.int64)
        largest = refs[ref_order[0]]
        reach = np.zeros(n, dtype=np.int64)  # the largest stored relative value of each row, 0 at least
        for r in ref_order:
            largest = np.maximum(largest, refs[r])
            reach = np.maximum(reach, diffs[r])
        if row_wide is not None:
            reach[row_wide] = 0  # (not stored relative: their bound is their largest id)
        vtop = ref_bound(vbase, np.maximum.reduceat(reach, starts), np.maximum.reduceat(largest, starts), wide)
    else:
        for r in ref_order:
            relative[r] = np.zeros(total, dtype=np.int32)
            absolute[r] = np.zeros(total, dtype=np.int64)
        vtop = np.full(c, -1, dtype=np.int64)
    return ChunkSet(spec, chunk, lengths, present, values, vbase, wide, relative, absolute, vtop, null_slots)


def _property_values(name: str, raw: npt.NDArray[Any], kind: str) -> npt.NDArray[Any]:
    """A property column's values as its kind's numpy type: floats of that very type (bits kept), integers that fit."""
    target = np.dtype(PROPERTY_KINDS[kind])
    if not raw.size:
        return raw.astype(target)
    if kind in ("float4", "float8") or kind == "bool":
        if raw.dtype.newbyteorder("=") != target:  # either byte order; no rounding, no truthiness
            raise InvalidInputError(f"column {name!r} must be {target}, got {raw.dtype}")
        return raw
    if raw.dtype.kind not in "iu" and raw.dtype != np.bool_:
        raise InvalidInputError(f"column {name!r} must be integers, got {raw.dtype}")
    info = np.iinfo(target)
    if raw.dtype.itemsize >= target.itemsize and (int(raw.min()) < info.min or int(raw.max()) > info.max):
        raise InvalidInputError(f"column {name!r} holds values outside {kind}'s range {info.min}..{info.max}")
    return raw.astype(target)


def ref_bound(vbase: IntArray, reach: IntArray, largest: IntArray, wide: BoolArray) -> IntArray:
    """The column ``vtop`` of chunks: a bound of each chunk's vertex ids that C can check without unnesting.

    A relative chunk's ids are ``vbase + (v1 - vbase) + (vK - v1)``, each
    stored value at most the chunk's largest, ``reach`` (0 at least): so
    ``vbase + 2 * reach`` bounds them, and ``tgsis.chunk_encoding_checks``
    tests it with ``< ANY`` on the stored arrays (no per-slot sum). The
    largest bigint when that overflows. A wide chunk: its largest id.

    Parameters
    ----------
    vbase : (c,) int64
        The chunks' vbase (ignored where ``wide``).
    reach : (c,) int64
        The largest stored relative value of each chunk, 0 at least (ignored where ``wide``).
    largest : (c,) int64
        The largest vertex id of each chunk.
    wide : (c,) bool
        The chunk's ids are stored absolute (``_wide``).

    Returns
    -------
    (c,) int64
    """
    top = np.iinfo(np.int64).max
    base = np.where(wide, 0, vbase).astype(np.int64)
    twice = 2 * np.where(wide, 0, reach).astype(np.int64)  # reach < 2^31: no overflow
    headroom = top - base
    bound = np.where(twice > headroom, top, base + np.minimum(twice, headroom))
    return np.where(wide, largest, bound).astype(np.int64)


def _bound_of(chunks: ChunkSet) -> IntArray:
    """:func:`ref_bound` of chunks that carry none (decoded ones): from their stored ref values."""
    c = len(chunks.chunk)
    starts = chunks.offsets[:-1]
    if not c:
        return np.empty(0, dtype=np.int64)
    reach = np.zeros(len(chunks.present), dtype=np.int64)
    largest = np.zeros(len(chunks.present), dtype=np.int64)
    for r in chunks.columns.ref_order:
        reach = np.maximum(reach, np.where(chunks.present, chunks.relative[r], 0))
        largest = np.maximum(largest, np.where(chunks.present, chunks.absolute[r], 0))
    return ref_bound(
        chunks.vbase, np.maximum.reduceat(reach, starts), np.maximum.reduceat(largest, starts), chunks.wide
    )


# --------------------------------------------------------------------------- binary COPY


def _element_bytes(values: npt.NDArray[Any], kind: str, present: BoolArray) -> tuple[npt.NDArray[np.uint8], IntArray]:
    """Every slot's array element (length word, then the value unless NULL), flat; and each slot's byte end."""
    width = np.dtype(_BIG_ENDIAN[kind]).itemsize
    items = np.empty(len(values), dtype=[("l", ">i4"), ("v", _BIG_ENDIAN[kind])])
    items["l"] = np.where(present, width, -1)
    items["v"] = values
    raw = items.view(np.uint8).reshape(len(values), 4 + width)
    if bool(present.all()):
        sizes = np.full(len(values), 4 + width, dtype=np.int64)
        return raw.reshape(-1), np.cumsum(sizes)
    keep = np.ones(raw.shape, dtype=bool)
    keep[~present, 4:] = False
    return raw[keep], np.cumsum(np.where(present, 4 + width, 4).astype(np.int64))


def _array_field(body: bytes, kind: str, count: int, hasnull: bool, size: int = 1, matrix: bool = False) -> bytes:
    """One array value with its field length word (array_recv form, lower bounds 1).

    One dimension of ``count``; ``size`` > 1 or ``matrix``: two, ``count`` x ``size`` (a vector property's rows,
    a point's).
    """
    if size > 1 or matrix:
        return _FIELD_2D.pack(28 + len(body), 2, int(hasnull), _OID[kind], count, 1, size, 1) + body
    return _FIELD_1D.pack(20 + len(body), 1, int(hasnull), _OID[kind], count, 1) + body


#: an array field's length word and array_recv header, one and two dimensions (struct: one call per chunk and column)
_FIELD_1D = struct.Struct(">6i")
_FIELD_2D = struct.Struct(">8i")


def to_copy(chunks: ChunkSet, geoid: int, revision: int = 0, instant: tuple[float, ...] = ()) -> bytes:
    """The binary COPY stream of the chunk rows, columns :meth:`ChunkColumns.copy_columns`.

    Parameters
    ----------
    chunks : ChunkSet
    geoid : int
        The object's key.
    revision : int
        The revision that writes these chunks (0 for unversioned storage).
    instant : tuple of float or int
        The values of the key columns after the object's (:attr:`ChunkColumns.instant`), one each: a ``double
        precision`` one written bit for bit (``-0.0`` stays ``-0.0``), an integer one (``instant_kinds``) in its
        width.

    Raises
    ------
    InvalidInputError
        ``instant`` does not give one value per instant key column, or an integer key's value is out of its range.

    Returns
    -------
    bytes
        What ``COPY tgsis.<t>_chunk (<copy_columns>) FROM STDIN (FORMAT binary)`` reads:
        header, one row per chunk, trailer.
    """
    spec = chunks.columns
    if len(instant) != len(spec.instant):
        raise InvalidInputError(f"chunk keys {list(spec.instant)} need one value each, got {list(instant)}")
    c = len(chunks.chunk)
    offsets = chunks.offsets
    n_fields = len(spec.copy_columns())
    key_kinds = spec.instant_kinds or ("float8",) * len(spec.instant)
    for value, kind in zip(instant, key_kinds):
        if kind != "float8" and not np.iinfo(_BIG_ENDIAN[kind]).min <= int(value) <= np.iinfo(_BIG_ENDIAN[kind]).max:
            raise InvalidInputError(f"chunk key value {value!r} is out of the range of {kind}")
    times = (
        [(f"lt{i}", ">i4") for i in range(len(instant))],
        [(f"t{i}", _BIG_ENDIAN[kind]) for i, kind in enumerate(key_kinds)],
    )
    layout = [("nf", ">i2"), ("lg", ">i4"), ("g", ">i8")]
    layout += [field for pair in zip(*times) for field in pair]
    layout += [("lc", ">i4"), ("c", ">i8"), ("lr", ">i4"), ("r", ">i4")]
    head = np.empty(c, dtype=layout)
    head["nf"], head["lg"], head["g"], head["lc"], head["c"] = n_fields, 8, geoid, 8, chunks.chunk
    for i, (value, kind) in enumerate(zip(instant, key_kinds)):
        # float64 into >f8: the bits kept; an integer in its width
        head[f"lt{i}"], head[f"t{i}"] = np.dtype(_BIG_ENDIAN[kind]).itemsize, value
    head["lr"], head["r"] = 4, revision
    heads = head.view(np.uint8).reshape(c, -1) if c else np.empty((0, head.itemsize), dtype=np.uint8)

    has_holes = np.logical_not(np.logical_and.reduceat(chunks.present, offsets[:-1])) if c else np.empty(0, bool)
    vtop = chunks.vtop if len(chunks.vtop) == c or not spec.refs else _bound_of(chunks)
    null = np.array([-1], dtype=">i4").tobytes()

    # every array column's elements, flat over all slots, with the byte end of each slot
    # (kind, element bytes, slot byte ends, chunks where the column is NULL, chunks whose array has NULL elements,
    # values a slot: a vector property's k, its slot a row of k elements of the 2-D array)
    encoded: list[tuple[str, npt.NDArray[np.uint8], IntArray, BoolArray | None, BoolArray, int, bool]] = []
    empty = (np.empty(0, dtype=np.uint8), np.empty(0, dtype=np.int64))
    for name in spec.names:
        if name in spec.refs:
            relative = empty if chunks.wide.all() else _element_bytes(chunks.relative[name], "int4", chunks.present)
            encoded.append(("int4", *relative, chunks.wide, has_holes, 1, False))
        elif name in spec.points:  # m elements a slot, all NULL at a hole (never elsewhere)
            m = int(chunks.values[name].shape[1])
            flat, ends = _element_bytes(chunks.values[name].reshape(-1), "float8", np.repeat(chunks.present, m))
            encoded.append(("float8", flat, ends[m - 1 :: m], None, has_holes, m, True))
        else:
            kind = spec.kind(name)
            size = spec.size(name)
            missing = chunks.nulls.get(name)
            elements, hasnull = chunks.present, has_holes
            if missing is not None and missing.any():  # a property's NULL values: NULL elements at present slots too
                elements = chunks.present & ~missing
                hasnull = np.logical_not(np.logical_and.reduceat(elements, offsets[:-1])) if c else has_holes
            if size > 1:  # a vector: k elements a slot, all NULL at a hole and at a NULL vector
                flat, ends = _element_bytes(chunks.values[name].reshape(-1), kind, np.repeat(elements, size))
                encoded.append((kind, flat, ends[size - 1 :: size], None, hasnull, size, False))
            else:
                encoded.append((kind, *_element_bytes(chunks.values[name], kind, elements), None, hasnull, 1, False))
    for name in spec.ref_order:
        wide = _element_bytes(chunks.absolute[name], "int8", chunks.present) if chunks.wide.any() else empty
        encoded.append(("int8", *wide, ~chunks.wide, has_holes, 1, False))

    pieces: list[bytes] = [COPY_SIGNATURE, np.array([0, 0], dtype=">i4").tobytes()]
    for k in range(c):
        start, stop = int(offsets[k]), int(offsets[k + 1])
        count = stop - start
        pieces.append(heads[k].tobytes())
        if has_holes[k]:
            slots = np.flatnonzero(~chunks.present[start:stop]) + 1
            items = np.empty(len(slots), dtype=[("l", ">i4"), ("v", ">i2")])
            items["l"], items["v"] = 2, slots
            pieces.append(_array_field(items.tobytes(), "int2", len(slots), False))
        else:
            pieces.append(null)
        if spec.refs:
            if chunks.wide[k]:
                pieces.append(null)
            else:
                pieces.append(np.array([(8, chunks.vbase[k])], dtype=[("l", ">i4"), ("v", ">i8")]).tobytes())
            pieces.append(np.array([(8, vtop[k])], dtype=[("l", ">i4"), ("v", ">i8")]).tobytes())
        for kind, flat, ends, nulled, hasnull, size, matrix in encoded:
            if nulled is not None and nulled[k]:
                pieces.append(null)
                continue
            first = int(ends[start - 1]) if start else 0
            body = flat[first : int(ends[stop - 1])].tobytes()
            pieces.append(_array_field(body, kind, count, bool(hasnull[k]), size, matrix))
    pieces.append(np.array([-1], dtype=">i2").tobytes())
    return b"".join(pieces)


class _Reader:
    """A cursor over a binary COPY stream."""

    def __init__(self, payload: bytes) -> None:
        self.buf = memoryview(payload)
        self.pos = 0

    def int(self, size: int) -> int:
        if self.pos + size > len(self.buf):
            raise InvalidInputError(f"binary COPY data ends inside a value (byte {self.pos} of {len(self.buf)})")
        (value,) = _SIGNED[size].unpack_from(self.buf, self.pos)
        self.pos += size
        return int(value)


#: big-endian signed integers by size (struct: a few times faster than int.from_bytes of a slice, per value)
_SIGNED = {2: struct.Struct(">h"), 4: struct.Struct(">i"), 8: struct.Struct(">q")}
#: an array_send header of one dimension: ndim, hasnull, element oid, size, lower bound
_ARRAY_HEADER = struct.Struct(">5i")


def _parse_array(
    reader: _Reader, length: int, kind: str, present: BoolArray | None
) -> tuple[npt.NDArray[Any], BoolArray]:
    """An array value (array_send form) as (values, present); ``present`` is the chunk's slots when known."""
    end = reader.pos + length
    if length < 12 or end > len(reader.buf):
        raise InvalidInputError(f"binary COPY data ends inside an array (byte {reader.pos} of {len(reader.buf)})")
    ndim, hasnull, oid = reader.int(4), reader.int(4), reader.int(4)
    if oid != _OID[kind]:
        raise InvalidInputError(f"a chunk array has element type {oid}, expected {_OID[kind]} ({kind})")
    if ndim == 0:
        reader.pos = end
        return np.empty(0, dtype=_BIG_ENDIAN[kind]), np.empty(0, dtype=bool)
    if ndim != 1:
        raise InvalidInputError(f"a chunk array has {ndim} dimensions, expected 1")
    count, lbound = reader.int(4), reader.int(4)
    if lbound != 1:
        raise InvalidInputError(f"a chunk array has lower bound {lbound}, expected 1")
    width = np.dtype(_BIG_ENDIAN[kind]).itemsize
    start = reader.pos
    elements = length - 20
    if count < 0 or elements < 4 * count or elements > (4 + width) * count:
        raise InvalidInputError(f"a chunk array of {count} elements takes {elements} bytes: not {kind} elements")
    if not hasnull:
        if elements != (4 + width) * count:
            raise InvalidInputError(f"a chunk array of {count} elements takes {elements} bytes: not {kind} elements")
        items = np.frombuffer(reader.buf, dtype=[("l", ">i4"), ("v", _BIG_ENDIAN[kind])], count=count, offset=start)
        if bool((items["l"] != width).any()):
            raise InvalidInputError("a chunk array element has an unexpected length")
        reader.pos = end
        return items["v"], np.ones(count, dtype=bool)
    if present is None or len(present) != count:
        raise InvalidInputError("a chunk array has NULL elements but its chunk's holes column does not list them")
    sizes = np.where(present, 4 + width, 4)
    if int(sizes.sum()) != elements:
        raise InvalidInputError("a chunk array's NULL elements are not its chunk's holes")
    starts = start + np.concatenate([[0], np.cumsum(sizes)[:-1]])
    raw = np.frombuffer(reader.buf, dtype=np.uint8, count=end - start, offset=start)
    words = raw[(starts - start)[:, None] + np.arange(4)].copy().view(">i4").reshape(-1)
    if bool((words != np.where(present, width, -1)).any()):
        raise InvalidInputError("a chunk array's NULL elements are not its chunk's holes")
    picks = (starts[present] - start + 4)[:, None] + np.arange(width)
    values = np.zeros(count, dtype=_BIG_ENDIAN[kind])
    values[present] = raw[picks].copy().view(_BIG_ENDIAN[kind]).reshape(-1)
    reader.pos = end
    return values, present


def _parse_nullable(reader: _Reader, length: int, kind: str, present: BoolArray) -> tuple[npt.NDArray[Any], BoolArray]:
    """A property's array value (array_send form) with NULL elements anywhere: (values, which elements are not NULL).

    Its length is the chunk's and it is NULL at every hole (a present slot may be NULL too: a value missing).
    """
    end = reader.pos + length
    if length < 20 or end > len(reader.buf):
        raise InvalidInputError(f"binary COPY data ends inside an array (byte {reader.pos} of {len(reader.buf)})")
    ndim, _, oid, count, lbound = (reader.int(4) for _ in range(5))
    if oid != _OID[kind]:
        raise InvalidInputError(f"a chunk array has element type {oid}, expected {_OID[kind]} ({kind})")
    if ndim != 1 or lbound != 1 or count != len(present):
        raise InvalidInputError(f"a chunk's property array is not one-dimensional from 1 of its {len(present)} slots")
    width = np.dtype(_BIG_ENDIAN[kind]).itemsize
    elements = np.zeros(count, dtype=bool)
    starts = np.zeros(count, dtype=np.int64)
    pos = reader.pos
    for i in range(count):  # (only chunks whose property has NULL values come here)
        size = int.from_bytes(reader.buf[pos : pos + 4], "big", signed=True)
        if size == width:
            elements[i] = True
            starts[i] = pos + 4
            pos += 4 + width
        elif size == -1:
            pos += 4
        else:
            raise InvalidInputError("a chunk array element has an unexpected length")
        if pos > end:
            raise InvalidInputError("binary COPY data ends inside an array")
    if pos != end:
        raise InvalidInputError("a chunk array is longer than its elements")
    if bool((elements & ~present).any()):
        raise InvalidInputError("a chunk's property array has a value at a hole")
    values = np.zeros(count, dtype=_BIG_ENDIAN[kind])
    if elements.any():
        raw = np.frombuffer(reader.buf, dtype=np.uint8)
        picks = starts[elements][:, None] + np.arange(width)
        values[elements] = raw[picks].copy().view(_BIG_ENDIAN[kind]).reshape(-1)
    reader.pos = end
    return values, elements


def _parse_vector(
    reader: _Reader, length: int, kind: str, present: BoolArray, size: int
) -> tuple[npt.NDArray[Any], BoolArray]:
    """A vector property's 2-D array value (array_send form): (values (count, size), which rows are not NULL).

    Its rows are the chunk's slots, from ``[1][1]``; a row is k NULLs at every hole and at a NULL vector, and
    no row is partly NULL (it would read as a NULL vector: ``tgsis.chunk_encoding_checks`` refuses it too).
    """
    end = reader.pos + length
    if length < 28 or end > len(reader.buf):
        raise InvalidInputError(f"binary COPY data ends inside an array (byte {reader.pos} of {len(reader.buf)})")
    ndim, hasnull, oid, count, lbound, inner, inner_lbound = (reader.int(4) for _ in range(7))
    if oid != _OID[kind]:
        raise InvalidInputError(f"a chunk array has element type {oid}, expected {_OID[kind]} ({kind})")
    if ndim != 2 or lbound != 1 or inner_lbound != 1 or count != len(present) or inner != size:
        raise InvalidInputError(
            f"a chunk's vector array is not two-dimensional from [1][1] of its {len(present)} slots x {size}"
        )
    width = np.dtype(_BIG_ENDIAN[kind]).itemsize
    dtype = [("l", ">i4"), ("v", _BIG_ENDIAN[kind])]
    if not hasnull:
        if length != 28 + count * size * (4 + width) or not present.all():
            raise InvalidInputError("a chunk's vector array does not match the chunk's holes and size")
        items = np.frombuffer(reader.buf, dtype=dtype, count=count * size, offset=reader.pos)
        if bool((items["l"] != width).any()):
            raise InvalidInputError("a chunk array element has an unexpected length")
        reader.pos = end
        return items["v"].reshape(count, size), np.ones(count, dtype=bool)
    rows = np.zeros(count, dtype=bool)
    starts = np.zeros(count, dtype=np.int64)
    pos = reader.pos
    nulls = np.full(size, -1, dtype=">i4")
    for i in range(count):  # (only chunks with a hole or a NULL vector come here)
        first = int.from_bytes(reader.buf[pos : pos + 4], "big", signed=True)
        if first == -1:
            if pos + 4 * size > end or not np.array_equal(np.frombuffer(reader.buf, ">i4", size, pos), nulls):
                raise InvalidInputError("a chunk's vector array has a row partly NULL")
            pos += 4 * size
        elif first == width:
            if pos + size * (4 + width) > end:
                raise InvalidInputError("binary COPY data ends inside an array")
            if bool((np.frombuffer(reader.buf, dtype, size, pos)["l"] != width).any()):
                raise InvalidInputError("a chunk's vector array has a row partly NULL")
            rows[i] = True
            starts[i] = pos
            pos += size * (4 + width)
        else:
            raise InvalidInputError("a chunk array element has an unexpected length")
    if pos != end:
        raise InvalidInputError("a chunk array is longer than its elements")
    if bool((rows & ~present).any()):
        raise InvalidInputError("a chunk's vector array has a value at a hole")
    values = np.zeros((count, size), dtype=_BIG_ENDIAN[kind])
    if rows.any():
        raw = np.frombuffer(reader.buf, dtype=np.uint8)
        picks = (starts[rows][:, None] + 4 + np.arange(size) * (4 + width))[:, :, None] + np.arange(width)
        values[rows] = raw[picks].copy().view(_BIG_ENDIAN[kind]).reshape(-1, size)
    reader.pos = end
    return values, rows


def from_copy(payload: bytes, spec: ChunkColumns) -> ChunkSet:
    """Parse the binary COPY output of ``COPY (SELECT <spec.select_columns()> ...) TO STDOUT (FORMAT binary)``.

    Parameters
    ----------
    payload : bytes
        The whole stream (header, rows, trailer); rows in any chunk order.
    spec : ChunkColumns

    Returns
    -------
    ChunkSet
        Chunks in ascending chunk order.

    Raises
    ------
    InvalidInputError
        Not a binary COPY stream, or rows that break the contract (field
        count, element types, NULL elements that are not holes).
    """
    reader = _Reader(payload)
    if bytes(reader.buf[:11]) != COPY_SIGNATURE:
        raise InvalidInputError("not a PostgreSQL binary COPY stream (no PGCOPY signature)")
    reader.pos = 11
    reader.int(4)  # flags
    extension = reader.int(4)
    reader.pos += extension  # header extension (none today)
    fields = spec.select_columns()
    refs = spec.ref_order
    # (column, is a _wide column): its key in the parsed values
    columns = [(name, name, False) for name in spec.names] + [(f"{r}_wide", r, True) for r in refs]
    chunks: list[int] = []
    presents: list[BoolArray] = []
    vbases: list[int] = []
    wides: list[bool] = []
    # per column: the element bytes of the chunks without NULL elements (joined and converted at the end, in
    # one numpy pass), and the chunks with holes parsed one by one: {chunk index: values}
    batched: dict[tuple[str, bool], list[memoryview]] = {(key, w): [] for _, key, w in columns}
    in_batch: dict[tuple[str, bool], list[bool]] = {(key, w): [] for _, key, w in columns}
    with_holes: dict[tuple[str, bool], dict[int, npt.NDArray[Any]]] = {(key, w): {} for _, key, w in columns}
    null_parts: dict[str, dict[int, BoolArray]] = {}  # a property's NULL values at present slots, per chunk index
    vector_parts: dict[str, dict[int, npt.NDArray[Any]]] = {n: {} for n, _ in spec.vectors}  # (slots, k) per chunk
    point_parts: dict[str, dict[int, npt.NDArray[Any]]] = {n: {} for n in spec.points}  # (slots, m) per chunk
    while True:
        count = reader.int(2)
        if count == -1:
            break
        if count != len(fields):
            raise InvalidInputError(f"a chunk row has {count} fields, expected {len(fields)} ({', '.join(fields)})")
        if reader.int(4) != 8:
            raise InvalidInputError("a chunk number is not a bigint")
        number = reader.int(8)
        if number < 0:
            raise InvalidInputError(f"a chunk number is negative ({number}): ids are 0 or more")
        k = len(chunks)
        chunks.append(number)
        length = reader.int(4)
        holes = np.empty(0, dtype=np.int64)
        if length >= 0:
            holes = _parse_array(reader, length, "int2", None)[0].astype(np.int64)
        base = -1
        if refs:
            length = reader.int(4)
            if length == 8:
                base = reader.int(8)
                if base < 0:
                    raise InvalidInputError(f"chunk {number}: vbase is negative ({base}): vertex ids are 0 or more")
            elif length != -1:
                raise InvalidInputError(f"chunk {number}: vbase is not a bigint")
        is_wide = bool(refs) and base == -1
        wides.append(is_wide)
        vbases.append(base)
        present: BoolArray | None = None
        for name, key, wide_column in columns:
            length = reader.int(4)
            expect_null = key in spec.refs and wide_column != is_wide
            slot = (key, wide_column)
            if length == -1:
                if not expect_null:
                    raise InvalidInputError(f"chunk {number}: column {name} is NULL")
                in_batch[slot].append(False)
                continue
            if expect_null:
                raise InvalidInputError(
                    f"chunk {number}: column {name} is not NULL (vbase {'NULL' if is_wide else base})"
                )
            kind = "int8" if wide_column else spec.kind(key)
            if length < 20 or reader.pos + length > len(reader.buf):
                raise InvalidInputError(f"chunk {number}: binary COPY data ends inside column {name}")
            ndim, hasnull, oid, size, lbound = _ARRAY_HEADER.unpack_from(reader.buf, reader.pos)
            if present is None:
                if ndim in (1, 2) and size > CHUNK_SIZE:
                    raise InvalidInputError(
                        f"chunk {number}: column {name} has {size} elements, more than the {CHUNK_SIZE} ids of a chunk "
                        "(a chunk table of another chunk size?)"
                    )
                present = np.ones(max(size, 0) if ndim in (1, 2) else 0, dtype=bool)
                dense = not len(holes)  # present.all(), asked once per chunk rather than per column
                if len(holes):
                    if int(holes.min()) < 1 or int(holes.max()) >= len(present):
                        raise InvalidInputError(f"chunk {number}: holes {holes.tolist()} outside 1..{len(present) - 1}")
                    present[holes - 1] = False
            if key in point_parts:  # a point's 2-D array, slots x m (m the chunk's: from its header)
                m = (
                    int(np.frombuffer(reader.buf, dtype=">i4", count=1, offset=reader.pos + 20)[0])
                    if length >= 28
                    else 0
                )
                if m < 1:
                    raise InvalidInputError(f"chunk {number}: column {name} is not a 2-D array of points of m >= 1")
                point, rows = _parse_vector(reader, length, "float8", present, m)
                if not np.array_equal(rows, present):
                    raise InvalidInputError(f"chunk {number}: column {name} has a NULL point at a present slot")
                point_parts[key][k] = point
                in_batch[slot].append(False)
                continue
            if key in vector_parts:  # a vector property's 2-D array
                vector, rows = _parse_vector(reader, length, kind, present, spec.size(key))
                missing = present & ~rows
                if missing.any():
                    null_parts.setdefault(key, {})[k] = missing
                vector_parts[key][k] = vector
                in_batch[slot].append(False)
                continue
            width = _WIDTH[kind]
            if ndim == 1 and not hasnull and oid == _OID[kind] and lbound == 1 and length == 20 + size * (4 + width):
                if size != len(present) or not dense:
                    raise InvalidInputError(f"chunk {number}: column {name} does not match the chunk's holes and size")
                batched[slot].append(reader.buf[reader.pos + 20 : reader.pos + length])
                in_batch[slot].append(True)
                reader.pos += length
                continue
            if spec.nullable(key):
                parsed, elements = _parse_nullable(reader, length, kind, present)
                missing = present & ~elements
                if missing.any():
                    null_parts.setdefault(key, {})[k] = missing
            else:
                parsed, _ = _parse_array(reader, length, kind, present)
            if len(parsed) != len(present):
                raise InvalidInputError(f"chunk {number}: arrays of different lengths")
            with_holes[slot][k] = parsed
            in_batch[slot].append(False)
        if present is None:
            raise InvalidInputError(f"chunk {number}: every array is NULL")
        presents.append(present)

    lengths = np.array([len(p) for p in presents], dtype=np.int64)
    offsets = np.concatenate([[0], np.cumsum(lengths)]).astype(np.int64)

    def column(slot: tuple[str, bool], kind: str, dtype: Any) -> npt.NDArray[Any]:
        """One column over all slots in received chunk order (0 where NULL)."""
        parts = batched[slot]
        whole = len(parts) == len(lengths) and bool(len(parts))  # every chunk batched: its slots in order
        out = np.empty(int(offsets[-1]), dtype=dtype) if whole else np.zeros(int(offsets[-1]), dtype=dtype)
        if parts:
            items = np.frombuffer(b"".join(parts), dtype=[("l", ">i4"), ("v", _BIG_ENDIAN[kind])])
            if bool((items["l"] != _WIDTH[kind]).any()):
                raise InvalidInputError(f"a chunk array of column {slot[0]} has an element of an unexpected length")
            if whole:
                out[:] = items["v"]
            else:
                out[np.repeat(np.array(in_batch[slot], dtype=bool), lengths)] = items["v"]
        for k, values in with_holes[slot].items():
            out[offsets[k] : offsets[k + 1]] = values
        return out

    chunk = np.array(chunks, dtype=np.int64)
    order = np.argsort(chunk, kind="stable")
    if len(chunk) > 1 and bool((chunk[order][1:] == chunk[order][:-1]).any()):
        raise InvalidInputError(
            "the COPY data holds a chunk twice (two versions of it? select the visible versions of one object)"
        )
    in_order = bool((order == np.arange(len(order))).all())
    slot_order = (
        None
        if in_order
        else np.concatenate([np.arange(offsets[k], offsets[k + 1]) for k in order]).astype(np.int64)
        if len(order)
        else None
    )

    def sorted_slots(values: npt.NDArray[Any]) -> npt.NDArray[Any]:
        return values if slot_order is None else values[slot_order]

    present_all = np.concatenate(presents) if presents else np.empty(0, dtype=bool)
    values = {
        n: sorted_slots(column((n, False), spec.kind(n), spec.dtype(n)))
        for n in spec.names
        if n not in spec.refs and n not in vector_parts and n not in point_parts
    }
    for name, parts in point_parts.items():
        sizes = sorted({int(p.shape[1]) for p in parts.values()})
        if len(sizes) > 1:
            raise InvalidInputError(f"the chunks of column {name} hold points of different lengths {sizes}")
        out = np.zeros((int(offsets[-1]), sizes[0] if sizes else 0), dtype=np.float64)
        for k, point in parts.items():
            out[offsets[k] : offsets[k + 1]] = point
        values[name] = sorted_slots(out)
    for name, parts in vector_parts.items():
        out = np.zeros((int(offsets[-1]), spec.size(name)), dtype=spec.dtype(name))
        for k, vector in parts.items():
            out[offsets[k] : offsets[k + 1]] = vector
        values[name] = sorted_slots(out)
    nulls: dict[str, BoolArray] = {}
    for name, parts in null_parts.items():
        mask = np.zeros(int(offsets[-1]), dtype=bool)
        for k, part in parts.items():
            mask[offsets[k] : offsets[k + 1]] = part
        nulls[name] = sorted_slots(mask)
    relative = {r: sorted_slots(column((r, False), "int4", np.int32)) for r in refs}
    absolute = {r: sorted_slots(column((r, True), "int8", np.int64)) for r in refs}
    wide = np.array(wides, dtype=bool)
    result = ChunkSet(
        spec,
        chunk[order],
        lengths[order],
        sorted_slots(present_all),
        values,
        np.array(vbases, dtype=np.int64)[order],
        wide[order],
        relative,
        absolute,
        nulls=nulls,
    )
    dense = bool(present_all.all())
    for r, decoded in result._ref_columns().items():  # vertex ids are 0 or more: a negative one breaks the contract
        if decoded.size and int((decoded if dense else decoded[result.present]).min(initial=0)) < 0:
            raise InvalidInputError(f"a chunk's column {r} decodes to a negative vertex id")
    return result
