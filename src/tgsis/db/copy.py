"""PostgreSQL binary COPY rows to and from numpy arrays, without per-row Python.

A binary COPY row of fixed-width, non-NULL columns has always the same size:
an int16 field count, then per field an int32 length and the big-endian
value. So a whole payload is one numpy structured array (built with vector
assignments, parsed with ``np.frombuffer``).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
import numpy.typing as npt

from tgsis.errors import DatabaseError, InvalidPropertyError

__all__ = ["PG_TYPES", "SQL_TYPES", "encode_rows", "decode_rows", "numpy_dtype"]

#: binary wire format of each fixed-width PostgreSQL type
PG_TYPES: dict[str, str] = {
    "int2": ">i2", "int4": ">i4", "int8": ">i8", "float4": ">f4", "float8": ">f8", "bool": "?",
}
#: SQL type names (as tgsis.property_types spells them) to wire types
SQL_TYPES: dict[str, str] = {
    "smallint": "int2", "integer": "int4", "bigint": "int8",
    "real": "float4", "double precision": "float8", "boolean": "bool",
}

_SIGNATURE = b"PGCOPY\n\xff\r\n\x00"
_HEADER = _SIGNATURE + b"\x00\x00\x00\x00" + b"\x00\x00\x00\x00"
_TRAILER = b"\xff\xff"


def numpy_dtype(wire: str) -> np.dtype[Any]:
    """Native numpy dtype of a wire type (``"float8"`` -> float64)."""
    return np.dtype(PG_TYPES[wire]).newbyteorder("=")


def _row_dtype(types: Sequence[str]) -> np.dtype[Any]:
    fields: list[tuple[str, str]] = [("count", ">i2")]
    for i, wire in enumerate(types):
        fields += [(f"len{i}", ">i4"), (f"val{i}", PG_TYPES[wire])]
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
    arrays = [np.asarray(values) for values, _ in columns]
    n = len(arrays[0]) if arrays else 0
    if any(len(a) != n for a in arrays):
        raise InvalidPropertyError("COPY columns have different lengths: " + ", ".join(str(len(a)) for a in arrays))
    types = [wire for _, wire in columns]
    rows = np.empty(n, dtype=_row_dtype(types))
    rows["count"] = len(types)
    for i, (values, wire) in enumerate(zip(arrays, types)):
        rows[f"len{i}"] = np.dtype(PG_TYPES[wire]).itemsize
        rows[f"val{i}"] = values
    return _HEADER + rows.tobytes() + _TRAILER


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
    body = view[19 + extension:]
    if bytes(body[-2:]) != _TRAILER:
        raise DatabaseError("binary COPY payload has no trailer")
    body = body[:-2]
    dtype = _row_dtype(types)
    if len(body) % dtype.itemsize:
        raise DatabaseError(f"binary COPY rows are not {dtype.itemsize} bytes each: NULLs or other column types")
    rows = np.frombuffer(body, dtype=dtype)
    if len(rows) and (np.any(rows["count"] != len(types)) or any(
            np.any(rows[f"len{i}"] != np.dtype(PG_TYPES[w]).itemsize) for i, w in enumerate(types))):
        raise DatabaseError("binary COPY rows hold NULLs or columns of other types than expected")
    return [rows[f"val{i}"].astype(numpy_dtype(w)) for i, w in enumerate(types)]
