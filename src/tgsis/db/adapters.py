"""psycopg adapters for tgsis's types: boxes as numpy arrays, model-time intervals as ranges of floats.

Without them psycopg gives a ``cube`` (tgsis's bounding boxes:
``tgsis.geometry.bbox``, the extents of model 5) as its text,
``"(326126.29688, 3.7e6, -5000),(...)"``, and a ``tgsis.timerange`` (the
periods of ``tgsis.property_periods``) as ``"[1,2)"``. After
:func:`register_types` on a connection (or cursor), queries of those types
give:

* ``cube``: a ``(2, d)`` float64 array, row 0 the low corner, row 1 the high
  one (``d = 3`` for bounding boxes; a point cube gives two equal rows);
  arrays of cubes give lists of them. Read in binary (``binary=True``) a
  cube comes bit for bit; its text form rounds every coordinate to 15
  significant digits in a session whose ``extra_float_digits`` is below 1
  (PostgreSQL's default, 1, prints them exactly). A ``(2, d)`` array passed as a query
  parameter *where PostgreSQL expects a cube* is dumped back as one
  (:class:`CubeDumper` is registered for :class:`Box`, see there).
* ``tgsis.timerange``: a :class:`psycopg.types.range.Range` of floats
  (``lower``, ``upper``, ``bounds``; ``None`` for an unbounded end);
  ``tgsis.timemultirange``: a :class:`psycopg.types.multirange.Multirange` of them.

Opt-in: code that reads the text forms keeps working on connections where
this is not called.
"""

from __future__ import annotations

import re
from typing import Any

import numpy as np
import numpy.typing as npt
import psycopg
from psycopg.adapt import Buffer, Dumper, Loader
from psycopg.pq import Format
from psycopg.types import TypeInfo
from psycopg.types.multirange import MultirangeInfo, register_multirange
from psycopg.types.range import RangeInfo, register_range

from tgsis.arguments import checked
from tgsis.errors import InstallationError, reraise

__all__ = ["register_types", "Box", "CubeLoader", "CubeBinaryLoader", "CubeDumper", "parse_cube", "unpack_cube"]

_NUMBER = re.compile(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?|[-+]?(?:inf(?:inity)?|nan)", re.IGNORECASE)

# the cube type of the cube extension, wherever it was created
_CUBE_OID = """
SELECT t.oid FROM pg_catalog.pg_type t
  JOIN pg_catalog.pg_depend d ON d.classid = 'pg_catalog.pg_type'::regclass AND d.objid = t.oid AND d.deptype = 'e'
  JOIN pg_catalog.pg_extension e ON e.oid = d.refobjid AND e.extname = 'cube'
 WHERE t.typname = 'cube'
"""


def parse_cube(text: str) -> npt.NDArray[np.float64]:
    """The ``(2, d)`` corners of a cube's text form (``"(1, 2, 3),(4, 5, 6)"`` or a point ``"(1, 2, 3)"``).

    Raises
    ------
    ValueError
        If ``text`` is no cube.
    """
    parts = text.strip().split("),(")
    corners = [[float(x) for x in _NUMBER.findall(part)] for part in parts]
    if not 1 <= len(corners) <= 2 or not corners[0] or len({len(c) for c in corners}) != 1:
        raise ValueError(f"not a cube: {text!r}")
    if len(corners) == 1:
        corners.append(corners[0])
    return np.array(corners, dtype=np.float64)


class Box(np.ndarray):
    """A ``(2, d)`` float64 array marked to be sent as a ``cube``: ``Box.of(corners)``.

    Plain numpy arrays are not adapted (psycopg could not tell a box from
    coordinates); wrap one to pass it where SQL expects a cube.
    """

    @classmethod
    def of(cls, corners: npt.ArrayLike) -> Box:
        """The box with these corners, ``(2, d)`` (low row, high row) or ``(d,)`` for a point."""
        array = np.asarray(corners, dtype=np.float64)
        if array.ndim == 1:
            array = np.stack([array, array])
        if array.ndim != 2 or array.shape[0] != 2 or not 1 <= array.shape[1] <= 100:
            raise ValueError(f"a box is (2, d) with 1 <= d <= 100 (low and high corners), got shape {array.shape}")
        return array.view(cls)


class CubeLoader(Loader):
    """Loads the text of a ``cube`` as its ``(2, d)`` float64 corners."""

    def load(self, data: Buffer) -> npt.NDArray[np.float64]:
        return parse_cube(bytes(data).decode("ascii"))


# cube's binary form (cube_send, cube 1.5): a big-endian int32 header, the dimension in its low 31 bits and
# bit 31 set for a point (one corner sent), then the float8 coordinates, low corner first
_CUBE_POINT_BIT = 0x80000000
_CUBE_DIM_MASK = 0x7FFFFFFF


def unpack_cube(data: bytes) -> npt.NDArray[np.float64]:
    """The ``(2, d)`` corners of a cube's binary form (what ``cube_send`` writes), bit for bit.

    Raises
    ------
    ValueError
        If ``data`` is no cube's binary form.
    """
    if len(data) < 4:
        raise ValueError(f"not a binary cube: {len(data)} bytes")
    header = int.from_bytes(data[:4], "big")
    dim, point = header & _CUBE_DIM_MASK, bool(header & _CUBE_POINT_BIT)
    count = dim if point else 2 * dim
    if dim < 1 or len(data) != 4 + 8 * count:
        raise ValueError(f"not a binary cube: header {header:#x}, {len(data)} bytes")
    corners = np.frombuffer(data, dtype=">f8", count=count, offset=4).astype(np.float64).reshape(-1, dim)
    return np.concatenate([corners, corners]) if point else corners


class CubeBinaryLoader(Loader):
    """Loads a ``cube`` read in binary (``binary=True``) as its ``(2, d)`` float64 corners, bit for bit.

    The text form rounds coordinates when the session's ``extra_float_digits``
    is below 1; the binary one never does.
    """

    format = Format.BINARY

    def load(self, data: Buffer) -> npt.NDArray[np.float64]:
        return unpack_cube(bytes(data))


class CubeDumper(Dumper):
    """Dumps a :class:`Box` as the text of a ``cube``."""

    def dump(self, obj: Any) -> Buffer:
        low, high = np.asarray(obj, dtype=np.float64)
        return ("(" + ", ".join(map(repr, low.tolist())) + "),(" + ", ".join(map(repr, high.tolist())) + ")").encode()


@checked
def register_types(conn: psycopg.Connection[Any] | psycopg.Cursor[Any]) -> None:
    """Make ``conn`` load cubes as numpy ``(2, d)`` arrays and ``tgsis.timerange`` as ranges of floats.

    Parameters
    ----------
    conn : psycopg.Connection or psycopg.Cursor
        Where to register: a connection (every cursor after) or one cursor.

    Raises
    ------
    InstallationError
        If tgsis (or the cube extension) is not installed in the database.
    """
    connection = conn if isinstance(conn, psycopg.Connection) else conn.connection
    with reraise():
        row = connection.execute(_CUBE_OID).fetchone()
        # tgsis.timerange is a domain (refusing NaN bounds) over this range type, and reaches the client as it
        timerange = RangeInfo.fetch(connection, "tgsis.modeltime_range")
        timemultirange = MultirangeInfo.fetch(connection, "tgsis.timemultirange")
    if row is None or timerange is None or timemultirange is None:
        raise InstallationError(
            "tgsis is not installed in this database: no cube or tgsis.modeltime_range type",
            hint="install it first (tgsis db install, or tgsis.install(conn))",
        )
    with reraise():
        array = connection.execute("SELECT typarray FROM pg_catalog.pg_type WHERE oid = %s", (row[0],)).fetchone()
    cube = TypeInfo("cube", int(row[0]), int(array[0]) if array else 0)
    cube.register(conn)
    conn.adapters.register_loader(cube.oid, CubeLoader)
    conn.adapters.register_loader(cube.oid, CubeBinaryLoader)
    dumper = type("BoxDumper", (CubeDumper,), {"oid": cube.oid})
    conn.adapters.register_dumper(Box, dumper)
    register_range(timerange, conn)
    register_multirange(timemultirange, conn)
