"""PostgreSQL binary COPY rows to and from numpy arrays, without per-row Python.

A binary COPY row of fixed-width, non-NULL columns has always the same size:
an int16 field count, then per field an int32 length and the big-endian
value. So a whole payload is one numpy structured array (built with vector
assignments, parsed with ``np.frombuffer``).

A one-dimensional array of k non-NULL elements of a fixed-width type (a
vector property, ``float8[3]`` here) has a fixed width too: the array header
(ndim, has-NULL flag, element type, length, lower bound: five int32) and k
(int32 length, value) pairs. Its values are (n, k) numpy arrays.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from typing import Any

import numpy as np
import numpy.typing as npt

from tgsis.errors import DatabaseError, InvalidPropertyError

__all__ = [
    "PG_TYPES",
    "SQL_TYPES",
    "encode_rows",
    "decode_rows",
    "decode_packed",
    "numpy_dtype",
    "array_wire",
    "wire_shape",
]

#: binary wire format of each fixed-width PostgreSQL type
PG_TYPES: dict[str, str] = {
    "int2": ">i2",
    "int4": ">i4",
    "int8": ">i8",
    "float4": ">f4",
    "float8": ">f8",
    "bool": "?",
}
#: SQL type names (as tgsis.property_types spells them) to wire types
SQL_TYPES: dict[str, str] = {
    "smallint": "int2",
    "integer": "int4",
    "bigint": "int8",
    "real": "float4",
    "double precision": "float8",
    "boolean": "bool",
}

#: element type oids of the array wire types
_ELEMENT_OIDS: dict[str, int] = {"int2": 21, "int4": 23, "int8": 20, "float4": 700, "float8": 701, "bool": 16}


def array_wire(wire: str, size: int) -> str:
    """The wire type of a one-dimensional array of ``size`` ``wire`` values (``"float8[3]"``); ``wire`` for size 1."""
    return wire if size == 1 else f"{wire}[{size}]"


def wire_shape(wire: str) -> tuple[str, int | None]:
    """``("float8", 3)`` for ``"float8[3]"``, ``("float8", None)`` for a scalar ``"float8"``."""
    base, _, rest = wire.partition("[")
    return (base, int(rest.rstrip("]"))) if rest else (base, None)


_SIGNATURE = b"PGCOPY\n\xff\r\n\x00"
_HEADER = _SIGNATURE + b"\x00\x00\x00\x00" + b"\x00\x00\x00\x00"
_TRAILER = b"\xff\xff"


def numpy_dtype(wire: str) -> np.dtype[Any]:
    """Native numpy dtype of a wire type's values (``"float8"`` and ``"float8[3]"`` -> float64)."""
    return np.dtype(PG_TYPES[wire_shape(wire)[0]]).newbyteorder("=")


def _field_dtype(wire: str) -> np.dtype[Any]:
    """The on-wire layout of one value of a wire type (after its int32 length)."""
    base, size = wire_shape(wire)
    if size is None:
        return np.dtype(PG_TYPES[base])
    return np.dtype(
        [
            ("ndim", ">i4"),
            ("hasnull", ">i4"),
            ("elemtype", ">i4"),
            ("dim", ">i4"),
            ("lbound", ">i4"),
            ("elems", [("len", ">i4"), ("val", PG_TYPES[base])], (size,)),
        ]
    )


def _row_dtype(types: Sequence[str]) -> np.dtype[Any]:
    fields: list[tuple[str, Any]] = [("count", ">i2")]
    for i, wire in enumerate(types):
        fields += [(f"len{i}", ">i4"), (f"val{i}", _field_dtype(wire))]
    return np.dtype(fields)  # packed: no alignment padding, as on the wire


def encode_rows(columns: Sequence[tuple[npt.ArrayLike, str]]) -> bytes:
    """Binary COPY payload (header, rows, trailer) from column arrays.

    Parameters
    ----------
    columns : sequence of (array_like (n,), wire type)
        One entry per column, all of length n; wire types from :data:`PG_TYPES`.

    Returns
    -------
    bytes
        Ready for ``COPY ... FROM STDIN (FORMAT binary)``.
    """
    return b"".join(encode_chunks(columns, None))


def encode_chunks(
    columns: Sequence[tuple[npt.ArrayLike, str]], rows_per_chunk: int | None = 1 << 20
) -> Iterator[bytes]:
    """The binary COPY payload of :func:`encode_rows` in pieces of at most ``rows_per_chunk`` rows, made as asked for.

    The first piece starts with the header, the last ends with the trailer
    (a table of no rows: one piece). ``None``: one piece. Written one after
    the other into one COPY, the pieces are :func:`encode_rows`'s payload;
    made while the previous one travels, the encoding overlaps the server's
    work (:meth:`tgsis.db._transfer.Storage.copy_all`).
    """
    arrays = [np.asarray(values) for values, _ in columns]
    n = len(arrays[0]) if arrays else 0
    if any(len(a) != n for a in arrays):
        raise InvalidPropertyError("COPY columns have different lengths: " + ", ".join(str(len(a)) for a in arrays))
    types = [wire for _, wire in columns]
    for i, (values, wire) in enumerate(zip(arrays, types)):
        size = wire_shape(wire)[1]
        if size is not None and values.shape != (n, size):
            raise InvalidPropertyError(f"COPY column {i} of {wire} values has shape {values.shape}, not ({n}, {size})")
    step = max(n, 1) if rows_per_chunk is None else rows_per_chunk
    starts = list(range(0, n, step)) or [0]
    for k, start in enumerate(starts):
        piece = _encoded(arrays, types, start, min(start + step, n))
        yield (_HEADER if k == 0 else b"") + piece + (_TRAILER if k == len(starts) - 1 else b"")


def _encoded(arrays: Sequence[npt.NDArray[Any]], types: Sequence[str], start: int, stop: int) -> bytes:
    """Rows start..stop of the columns in binary COPY form (no header, no trailer)."""
    rows = np.empty(stop - start, dtype=_row_dtype(types))
    rows["count"] = len(types)
    for i, (values, wire) in enumerate(zip(arrays, types)):
        base, size = wire_shape(wire)
        rows[f"len{i}"] = _field_dtype(wire).itemsize
        if size is None:
            rows[f"val{i}"] = values[start:stop]
            continue
        value = rows[f"val{i}"]
        value["ndim"], value["hasnull"], value["elemtype"] = 1, 0, _ELEMENT_OIDS[base]
        value["dim"], value["lbound"] = size, 1
        value["elems"]["len"] = np.dtype(PG_TYPES[base]).itemsize
        value["elems"]["val"] = values[start:stop]
        rows[f"val{i}"] = value
    return rows.tobytes()


def decode_rows(data: bytes | bytearray | memoryview, types: Sequence[str]) -> list[npt.NDArray[Any]]:
    """Column arrays (native byte order) from a binary COPY TO payload.

    Parameters
    ----------
    data : bytes
        Everything ``COPY ... TO STDOUT (FORMAT binary)`` sent.
    types : sequence of str
        Wire type of each column, in order.

    Raises
    ------
    DatabaseError
        The payload is not binary COPY of those columns (or holds NULLs).
    """
    view = memoryview(data)
    if bytes(view[:11]) != _SIGNATURE:
        raise DatabaseError("not a binary COPY payload (bad signature)")
    extension = int.from_bytes(view[15:19], "big")
    body = view[19 + extension :]
    if bytes(body[-2:]) != _TRAILER:
        raise DatabaseError("binary COPY payload has no trailer")
    body = body[:-2]
    dtype = _row_dtype(types)
    if len(body) % dtype.itemsize:
        raise DatabaseError(f"binary COPY rows are not {dtype.itemsize} bytes each: NULLs or other column types")
    rows = np.frombuffer(body, dtype=dtype)
    if len(rows) and (
        np.any(rows["count"] != len(types))
        or any(np.any(rows[f"len{i}"] != _field_dtype(w).itemsize) for i, w in enumerate(types))
    ):
        raise DatabaseError("binary COPY rows hold NULLs or columns of other types than expected")
    columns = []
    for i, wire in enumerate(types):
        base, size = wire_shape(wire)
        value = rows[f"val{i}"]
        if size is None:
            columns.append(value.astype(numpy_dtype(wire)))
            continue
        if len(rows) and (
            np.any(value["ndim"] != 1)
            or np.any(value["hasnull"] != 0)
            or np.any(value["dim"] != size)
            or np.any(value["elems"]["len"] != np.dtype(PG_TYPES[base]).itemsize)
        ):
            raise DatabaseError(f"binary COPY column {i} holds arrays that are not {size} non-NULL values")
        columns.append(value["elems"]["val"].astype(numpy_dtype(wire)).reshape(len(rows), size))
    return columns


def decode_packed(
    data: bytes | bytearray | memoryview, types: Sequence[str], count: int, what: str
) -> list[npt.NDArray[Any]]:
    """Columns from ``count`` rows sent as their values' binary send forms, one row after the other.

    What ``string_agg(int8send(vrtxid) || float8send(x) || ..., '')`` gives:
    each value in the wire format of a binary COPY field, without the
    field's length word and without the row's field count. Vector values
    (``"float8[3]"``) are whole one-dimensional arrays, checked as
    :func:`decode_rows` checks them.

    Parameters
    ----------
    data : bytes
        The packed rows.
    types : sequence of str
        Wire type of each column (:data:`PG_TYPES`, or ``"float8[3]"``).
    count : int
        How many rows the server aggregated: a row with a NULL (which the
        aggregate skips) or a value of another size shows as a length that
        does not match.
    what : str
        Names the columns in messages.

    Returns
    -------
    list of ndarray
        One (count,) or (count, k) array per column, native byte order.

    Raises
    ------
    DatabaseError
        The bytes are not ``count`` rows of non-NULL values of ``types``.
    """
    dtype = np.dtype([(f"val{i}", _field_dtype(wire)) for i, wire in enumerate(types)])
    if len(data) != count * dtype.itemsize:
        raise DatabaseError(
            f"{what}: {len(data)} bytes for {count} rows of {dtype.itemsize}: NULLs or values of other sizes"
        )
    rows = np.frombuffer(data, dtype=dtype)
    columns = []
    for i, wire in enumerate(types):
        base, size = wire_shape(wire)
        value = rows[f"val{i}"]
        if size is None:
            columns.append(value.astype(numpy_dtype(wire)))
            continue
        if count and (
            np.any(value["ndim"] != 1)
            or np.any(value["hasnull"] != 0)
            or np.any(value["dim"] != size)
            or np.any(value["elems"]["len"] != np.dtype(PG_TYPES[base]).itemsize)
        ):
            raise DatabaseError(f"{what}: column {i + 1} holds arrays that are not {size} non-NULL values")
        columns.append(value["elems"]["val"].astype(numpy_dtype(wire)).reshape(count, size))
    return columns
