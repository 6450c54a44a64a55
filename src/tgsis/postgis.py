"""PostGIS geometries as (E)WKB and tgsis meshes, both ways (no database, no PostGIS).

PostGIS hands geometries to clients as extended WKB (psycopg gives a
``geometry`` column as its hex text), and ``ST_GeomFromEWKB`` (or the cast
from ``bytea``) reads it back. These functions convert between that form and
the mesh types of :mod:`tgsis.mesh`, the same way the database does
(``tgsis.ewkb_geometry`` and ``tgsis.mesh_from_postgis``, docs/postgis.md):

============================== ==========================================
tgsis                          PostGIS
============================== ==========================================
:class:`~tgsis.Surface`        ``TIN Z`` (one ``TRIANGLE Z`` per triangle)
:class:`~tgsis.TetraMesh`      ``POLYHEDRALSURFACE Z`` of its boundary
:class:`~tgsis.LineSet`        ``MULTILINESTRING Z`` (one line per segment)
:class:`~tgsis.PointSet`       ``MULTIPOINT Z``
============================== ==========================================

Reading also takes ``POLYHEDRALSURFACE``, ``(MULTI)POLYGON`` and ``TRIANGLE``
(faces of more than three corners are fanned into triangles) and
``(MULTI)LINESTRING``/``(MULTI)POINT``; corners at the same coordinates are
one vertex. Coordinates pass bit for bit.
"""

from __future__ import annotations

import struct
from typing import Any

import numpy as np
import numpy.typing as npt

from tgsis._polygons import fan_triangles, polyline_segments
from tgsis.errors import InvalidGeometryError, InvalidInputError
from tgsis.mesh import LineSet, Mesh, PointSet, Surface, TetraMesh

__all__ = ["mesh_from_wkb", "mesh_to_ewkb", "wkb_srid"]

# WKB type codes (ISO and EWKB share them below 1000)
_POINT, _LINESTRING, _POLYGON, _MULTIPOINT, _MULTILINESTRING, _MULTIPOLYGON, _COLLECTION = 1, 2, 3, 4, 5, 6, 7
_POLYHEDRALSURFACE, _TIN, _TRIANGLE = 15, 16, 17
_EWKB_Z, _EWKB_M, _EWKB_SRID = 0x80000000, 0x40000000, 0x20000000
_NAMES = {
    1: "POINT",
    2: "LINESTRING",
    3: "POLYGON",
    4: "MULTIPOINT",
    5: "MULTILINESTRING",
    6: "MULTIPOLYGON",
    7: "GEOMETRYCOLLECTION",
    15: "POLYHEDRALSURFACE",
    16: "TIN",
    17: "TRIANGLE",
}


class _Reader:
    """A cursor over (E)WKB bytes; each geometry header sets the byte order for what follows it."""

    def __init__(self, data: bytes) -> None:
        self.data = data
        self.pos = 0
        self.order = ">"

    def take(self, fmt: str) -> tuple[Any, ...]:
        size = struct.calcsize(self.order + fmt)
        if self.pos + size > len(self.data):
            raise InvalidGeometryError(f"WKB ends at byte {len(self.data)}, inside a geometry (at byte {self.pos})")
        values = struct.unpack_from(self.order + fmt, self.data, self.pos)
        self.pos += size
        return values

    def header(self) -> tuple[int, bool, int | None]:
        """(type code, has z, srid) of the geometry starting here."""
        if self.pos >= len(self.data):
            raise InvalidGeometryError(f"WKB ends at byte {len(self.data)} where a geometry should start")
        flag = self.data[self.pos]
        if flag not in (0, 1):
            raise InvalidGeometryError(f"byte {self.pos} of the WKB is {flag}, not a byte order (0 or 1)")
        self.order = "<" if flag == 1 else ">"
        self.pos += 1
        (word,) = self.take("I")
        srid = None
        if word & _EWKB_SRID:
            (srid,) = self.take("i")
        has_z, has_m = bool(word & _EWKB_Z), bool(word & _EWKB_M)
        code = word & 0x0FFFFFFF
        if code >= 1000:  # ISO WKB: 1000 z, 2000 m, 3000 zm
            has_z, has_m = has_z or (code // 1000) in (1, 3), has_m or (code // 1000) in (2, 3)
            code %= 1000
        if code not in _NAMES:
            raise InvalidGeometryError(
                f"WKB geometry type {code} is none tgsis reads",
                hint="give a TIN, POLYHEDRALSURFACE, polygons, lines or points",
            )
        if has_m:
            raise InvalidGeometryError(f"the {_NAMES[code]} has measures (M)", hint="ST_Force3DZ(geom) drops them")
        return code, has_z, srid

    def points(self, n: int, has_z: bool) -> npt.NDArray[np.float64]:
        if not has_z:
            raise InvalidGeometryError(
                "the geometry has no z coordinates (2D)", hint="ST_Force3DZ(geom) gives it z = 0, in SQL"
            )
        size = 24 * n
        if self.pos + size > len(self.data):
            raise InvalidGeometryError(f"WKB ends at byte {len(self.data)}, inside {n} points (at byte {self.pos})")
        out = (
            np.frombuffer(
                self.data, dtype=np.dtype("<f8" if self.order == "<" else ">f8"), count=3 * n, offset=self.pos
            )
            .reshape(n, 3)
            .astype(np.float64)
        )
        self.pos += size
        return out


def _as_bytes(data: bytes | bytearray | memoryview | str) -> bytes:
    if isinstance(data, str):
        try:
            return bytes.fromhex(data)
        except ValueError as exc:
            raise InvalidInputError(
                "data is text but not hex-encoded WKB (as psycopg gives a geometry column)",
                hint="pass the bytes, or the hex text PostGIS prints",
            ) from exc
    if isinstance(data, (bytes, bytearray, memoryview)):
        return bytes(data)
    raise InvalidInputError(f"data must be WKB bytes or hex text, not {type(data).__name__}")


def _read(reader: _Reader, parts: list[tuple[int, npt.NDArray[np.float64]]], depth: int = 0) -> int:
    """Append (kind, points) per face, line or point of the geometry; return its type code."""
    code, has_z, _ = reader.header()
    if code == _POINT:
        parts.append((_POINT, reader.points(1, has_z)))
    elif code == _LINESTRING:
        (n,) = reader.take("I")
        parts.append((_LINESTRING, reader.points(n, has_z)))
    elif code in (_POLYGON, _TRIANGLE):
        (rings,) = reader.take("I")
        if rings > 1:
            raise InvalidGeometryError(
                f"a face of the geometry has {rings - 1} holes (inner rings)",
                hint="triangulate it first (ST_TriangulatePolygon)",
            )
        for _ in range(rings):
            (n,) = reader.take("I")
            parts.append((_POLYGON, reader.points(n, has_z)))
    else:
        if depth > 0 and code == _COLLECTION:
            raise InvalidGeometryError("a GEOMETRYCOLLECTION inside another is none tgsis reads")
        (n,) = reader.take("I")
        for _ in range(n):
            _read(reader, parts, depth + 1)
    return code


def _record_dtype(order: str, sub: int) -> np.dtype[Any]:
    """The layout of one sub-geometry of the regular multi-geometries tgsis writes (and PostGIS gives)."""
    f8, u4 = np.dtype(order + "f8"), np.dtype(order + "u4")
    if sub in (_TRIANGLE, _POLYGON):  # one ring of four corners, the last repeating the first
        return np.dtype([("order", "u1"), ("type", u4), ("rings", u4), ("n", u4), ("p", f8, (4, 3))])
    if sub == _LINESTRING:  # two points
        return np.dtype([("order", "u1"), ("type", u4), ("n", u4), ("p", f8, (2, 3))])
    return np.dtype([("order", "u1"), ("type", u4), ("p", f8, (1, 3))])


def _regular_parts(raw: bytes) -> tuple[int, npt.NDArray[np.float64]] | None:
    """(kind, points of every part) of a TIN, POLYHEDRALSURFACE, MULTIPOLYGON, MULTILINESTRING or MULTIPOINT whose
    parts are all triangles, two-point lines or points of the same byte order: read in one step, or None."""
    reader = _Reader(raw)
    code, has_z, _ = reader.header()
    subs = {
        _TIN: (_TRIANGLE,),
        _POLYHEDRALSURFACE: (_POLYGON,),
        _MULTIPOLYGON: (_POLYGON,),
        _MULTILINESTRING: (_LINESTRING,),
        _MULTIPOINT: (_POINT,),
    }.get(code)
    if subs is None or not has_z:
        return None
    (count,) = reader.take("I")
    if count == 0 or reader.pos >= len(raw):
        return None
    order = "<" if raw[reader.pos] == 1 else ">"
    dtype = _record_dtype(order, subs[0])
    if len(raw) - reader.pos != count * dtype.itemsize:
        return None
    records = np.frombuffer(raw, dtype=dtype, count=count, offset=reader.pos)
    expected = {"order": 1 if order == "<" else 0, "type": _EWKB_Z | subs[0]}
    if subs[0] in (_TRIANGLE, _POLYGON):
        expected |= {"rings": 1, "n": 4}
    elif subs[0] == _LINESTRING:
        expected["n"] = 2
    for field, value in expected.items():
        if field == "type":  # EWKB (flag) or ISO (1000 + code) z
            if not np.all((records[field] == value) | (records[field] == 1000 + subs[0])):
                return None
        elif not np.all(records[field] == value):
            return None
    kind = _POLYGON if subs[0] in (_TRIANGLE, _POLYGON) else subs[0]
    points = np.ascontiguousarray(records["p"], dtype=np.float64)
    if kind == _POLYGON:
        if not np.array_equal(points[:, 0], points[:, 3]):
            return None
        points = np.ascontiguousarray(points[:, :3])
    return kind, points


def wkb_srid(data: bytes | bytearray | memoryview | str) -> int | None:
    """The SRID an EWKB geometry carries, or ``None`` (plain WKB, or EWKB without one).

    Parameters
    ----------
    data : bytes or str
        EWKB bytes, or their hex text (what psycopg gives for a geometry column).
    """
    return _Reader(_as_bytes(data)).header()[2]


def mesh_from_wkb(data: bytes | bytearray | memoryview | str, *, name: str | None = None) -> Mesh:
    """A tgsis mesh from a PostGIS geometry in (E)WKB with z.

    Parameters
    ----------
    data : bytes or str
        (E)WKB bytes in either byte order, or their hex text (psycopg gives a
        ``geometry`` column as that text; ``ST_AsEWKB(geom)`` gives bytes).
    name : str, optional
        Name of the mesh.

    Returns
    -------
    Mesh
        A :class:`~tgsis.Surface` (TIN, POLYHEDRALSURFACE, polygons,
        triangles), :class:`~tgsis.LineSet` (lines: one segment per pair of
        consecutive points) or :class:`~tgsis.PointSet`. Corners at equal
        coordinates are one vertex, numbered by first appearance; the SRID is
        in ``metadata["srid"]`` when the EWKB has one.

    Raises
    ------
    InvalidGeometryError
        Truncated or malformed WKB, no z (2D) or measures, holes in a face,
        an empty geometry, a mix of surfaces, lines and points, or a
        degenerate face or segment.
    InvalidInputError
        ``data`` is neither bytes nor hex text.
    """
    raw = _as_bytes(data)
    code, _, srid = _Reader(raw).header()
    regular = _regular_parts(raw)
    if regular is not None:  # the usual case (what tgsis and PostGIS write): one step, no loop per cell
        kind, grouped = regular
        everything = grouped.reshape(-1, 3)
        sizes = np.full(len(grouped), grouped.shape[1])
    else:
        reader = _Reader(raw)
        parts: list[tuple[int, npt.NDArray[np.float64]]] = []
        _read(reader, parts)
        if reader.pos != len(raw):
            raise InvalidGeometryError(f"WKB has {len(raw) - reader.pos} bytes after the geometry")
        kinds = {kind for kind, _ in parts}
        if not parts or all(len(p) == 0 for _, p in parts):
            raise InvalidGeometryError(f"the {_NAMES[code]} is empty", hint="a tgsis object has at least one vertex")
        if len(kinds) > 1:
            raise InvalidGeometryError(
                f"the {_NAMES[code]} mixes " + ", ".join(sorted(_NAMES[k] for k in kinds)),
                hint="store surfaces, lines and points as separate features",
            )
        kind = kinds.pop()
        if kind == _POLYGON:  # drop each ring's closing corner
            rings = [p[:-1] if len(p) > 1 and np.array_equal(p[0], p[-1]) else p for _, p in parts]
        else:
            rings = [p for _, p in parts]
        everything = np.concatenate(rings)
        sizes = np.array([len(r) for r in rings])
    keys = np.ascontiguousarray(everything).view(np.dtype((np.void, 24))).ravel()
    _, first, inverse = np.unique(keys, return_index=True, return_inverse=True)
    order = np.argsort(first, kind="stable")  # vertices by first appearance
    rank = np.empty_like(order)
    rank[order] = np.arange(len(order))
    index = rank[inverse.ravel()]
    vertices = everything[first[order]]
    if kind == _POLYGON and np.any(sizes < 3):
        raise InvalidGeometryError(f"a face of the {_NAMES[code]} has {int(sizes[sizes < 3][0])} corners")
    if np.all(sizes == sizes[0]) and (kind != _POLYGON or sizes[0] == 3) and (kind != _LINESTRING or sizes[0] == 2):
        cell_array = index.reshape(len(sizes), int(sizes[0])).astype(np.int64)  # triangles, segments or points
    elif kind == _POLYGON:  # a fan from the first corner of each face
        cell_array = fan_triangles(index, np.concatenate([[0], np.cumsum(sizes)]))[0]
    else:  # polylines of different lengths (points always have one corner each: the first case)
        cell_array = polyline_segments(index, np.concatenate([[0], np.cumsum(sizes)]))
    if cell_array.shape[1] > 1:
        ordered = np.sort(cell_array, axis=1)
        bad = np.flatnonzero(np.any(ordered[:, 1:] == ordered[:, :-1], axis=1))
        if len(bad):
            raise InvalidGeometryError(
                f"cell {int(bad[0])} of the {_NAMES[code]} repeats a vertex (a degenerate face or zero-length segment)",
                hint="ST_RemoveRepeatedPoints(geom), in SQL",
            )
    metadata = {"srid": srid} if srid is not None else None
    mesh_type: type[Mesh] = Surface if kind == _POLYGON else LineSet if kind == _LINESTRING else PointSet
    return mesh_type(vertices, cell_array, name=name, metadata=metadata)


def _header(code: int, srid: int | None) -> bytes:
    if srid is None:
        return struct.pack(">BI", 0, _EWKB_Z | code)
    return struct.pack(">BIi", 0, _EWKB_Z | _EWKB_SRID | code, srid)


def _boundary_faces(mesh: TetraMesh) -> npt.NDArray[np.int64]:
    """The faces of a tetrahedral mesh that belong to one tetrahedron, oriented outwards (as tgsis.ewkb_geometry)."""
    t = mesh.cells
    faces = np.concatenate([t[:, [0, 1, 2]], t[:, [0, 1, 3]], t[:, [0, 2, 3]], t[:, [1, 2, 3]]])
    opposite = np.concatenate([t[:, 3], t[:, 2], t[:, 1], t[:, 0]])
    tetra = np.concatenate([np.arange(len(t))] * 4)
    _, inverse, counts = np.unique(np.sort(faces, axis=1), axis=0, return_inverse=True, return_counts=True)
    keep = counts[inverse.ravel()] == 1
    faces, opposite = faces[keep], opposite[keep]
    order = np.lexsort((faces[:, 2], faces[:, 1], faces[:, 0], tetra[keep]))  # the SQL's ORDER BY
    faces, opposite = faces[order], opposite[order]
    p = mesh.vertices
    a, b, c, o = p[faces[:, 0]], p[faces[:, 1]], p[faces[:, 2]], p[opposite]
    inwards = np.einsum("ij,ij->i", np.cross(b - a, c - a), o - a) > 0
    faces[inwards] = faces[inwards][:, [0, 2, 1]]
    return np.asarray(faces, dtype=np.int64)


def mesh_to_ewkb(mesh: Mesh, srid: int | None = 0) -> bytes:
    """A tgsis mesh as PostGIS EWKB (big-endian), byte for byte what ``tgsis.ewkb_geometry`` gives in SQL.

    Parameters
    ----------
    mesh : Mesh
        A :class:`~tgsis.Surface` (``TIN Z``), :class:`~tgsis.TetraMesh`
        (``POLYHEDRALSURFACE Z`` of its boundary), :class:`~tgsis.LineSet`
        (``MULTILINESTRING Z``) or :class:`~tgsis.PointSet` (``MULTIPOINT Z``).
    srid : int or None
        SRID to write (0: unknown); ``None`` writes none.

    Returns
    -------
    bytes
        For ``ST_GeomFromEWKB`` (or a ``bytea`` parameter cast to ``geometry``).
    """
    if srid is not None and (not isinstance(srid, int) or srid < 0):
        raise InvalidInputError(f"srid must be an integer >= 0 or None, not {srid!r}")
    p = mesh.vertices
    if isinstance(mesh, Surface):
        code, cells, sub = _TIN, mesh.cells, _TRIANGLE
    elif isinstance(mesh, TetraMesh):
        code, cells, sub = _POLYHEDRALSURFACE, _boundary_faces(mesh), _POLYGON
    elif isinstance(mesh, LineSet):
        code, cells, sub = _MULTILINESTRING, mesh.cells, _LINESTRING
    elif isinstance(mesh, PointSet):
        code, cells, sub = _MULTIPOINT, mesh.cells, _POINT
    else:
        raise InvalidInputError(f"mesh must be a Surface, TetraMesh, LineSet or PointSet, not {type(mesh).__name__}")
    records = np.zeros(len(cells), dtype=_record_dtype(">", sub))
    records["type"] = _EWKB_Z | sub
    if sub in (_TRIANGLE, _POLYGON):
        records["rings"], records["n"] = 1, 4
        records["p"] = p[np.concatenate([cells, cells[:, :1]], axis=1)]  # the ring closes on its first corner
    else:
        if sub == _LINESTRING:
            records["n"] = 2
        records["p"] = p[cells]
    return _header(code, srid) + struct.pack(">I", len(cells)) + records.tobytes()
