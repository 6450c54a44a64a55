"""How the browser view sends what it draws (:mod:`tgsis.drawing`): binary typed arrays (no database).

A mesh travels to the browser as one ``application/octet-stream`` body:

- 4 bytes: ``n``, the length of the JSON header (uint32, little-endian);
- ``n`` bytes: the header, UTF-8 JSON, padded with spaces so that the arrays
  start on a multiple of 4 bytes;
- the arrays the header lists in ``arrays`` (``{"name", "type", "count"}``,
  ``type`` ``float32`` or ``uint32``), one after the other, little-endian.

Positions are float32 offsets from ``origin`` (float64 in the header): a
UTM coordinate (millions of metres) in float32 would keep 0.25 m, an offset
from the middle of the box keeps millimetres. ``kind`` says what the
indices are: ``triangles`` (3 per cell), ``lines`` (2) or ``points`` (none).
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from typing import Any

import numpy as np
import numpy.typing as npt

__all__ = ["pack", "unpack"]


def pack(header: Mapping[str, Any], arrays: Mapping[str, npt.NDArray[Any]]) -> bytes:
    """One body: the header (with the list of arrays added) then the arrays, float32 or uint32 little-endian.

    Parameters
    ----------
    header : mapping
        JSON-serialisable facts (``kind``, ``origin``, counts, ...).
    arrays : mapping of str to array
        Float arrays are sent as float32, integer ones as uint32 (flattened).
    """
    wire = []
    listed = []
    for name, array in arrays.items():
        a = np.asarray(array)
        out = a.astype("<u4") if np.issubdtype(a.dtype, np.integer) else a.astype("<f4")
        wire.append(np.ascontiguousarray(out).ravel())
        listed.append({"name": name, "type": "uint32" if out.dtype.kind == "u" else "float32", "count": int(out.size)})
    text = json.dumps({**header, "arrays": listed}, allow_nan=False).encode()
    text += b" " * (-len(text) % 4)
    return b"".join([np.uint32(len(text)).astype("<u4").tobytes(), text, *(w.tobytes() for w in wire)])


def unpack(body: bytes) -> tuple[dict[str, Any], dict[str, npt.NDArray[Any]]]:
    """The header and arrays of a body made by :func:`pack` (what the browser's code reads)."""
    n = int(np.frombuffer(body[:4], dtype="<u4")[0])
    header = json.loads(body[4 : 4 + n])
    arrays = {}
    offset = 4 + n
    for item in header["arrays"]:
        dtype = np.dtype("<u4" if item["type"] == "uint32" else "<f4")
        arrays[item["name"]] = np.frombuffer(body, dtype=dtype, count=item["count"], offset=offset)
        offset += item["count"] * 4
    return header, arrays
