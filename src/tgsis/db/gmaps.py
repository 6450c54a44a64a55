"""Model 4 in the database: n-G-maps in R^m evolving in valid time, stored and fetched by binary COPY.

A feature of a class of G-maps (``time_model="GMAP"``) is one
``tgsis.geometry`` row (geotype and time model ``GMAP``) with its dimensions
in ``tgsis.gmap``, its topology periods in ``tgsis.gmap_timem``, their
geometry instants in ``tgsis.gmap_timet``, the points of each period in
``tgsis.gmap_node`` and their positions at each instant in
``tgsis.gmap_vertex``, the darts in ``tgsis.gmap_dart``, the involutions in
``tgsis.gmap_alpha`` and the cells of the class's property level in
``tgsis.gmap_cell``; property values are rows ``(_geoid, _timem, _timet,
_idx = acellid)`` of the class's ``<name>_cellpros``. Ids of darts, nodes and
cells are unique within the geometry, numbered on through the periods.

Every write is one transaction, one COPY per table; a map that breaks a
condition of an n-G-map is refused with the offending darts named and
nothing written. Snapshots at t come from SQL (``tgsis.gmap_at``,
``tgsis.gmap_points_at``, ``tgsis.gmap_property_at``), equal to
:meth:`tgsis.gmaps.EvolvingGMap.at` of the fetched object.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt
from psycopg import sql

from tgsis import datamodels
from tgsis._chunks import CHUNK_SIZE
from tgsis._series import check_time
from tgsis.arguments import checked, no_nul
from tgsis.db._chunk_transfer import (
    ChunkTable,
    ObjectRows,
    chunk_table,
    chunked_tables,
    instant_rows,
    object_rows,
    point_rows,
    upload_rows,
)
from tgsis.db._continuity import check_continuity, checked_tolerance
from tgsis.db._gmap_common import (
    Conn,
    IntArray,
    alpha_columns,
    cell_ids,
    class_values,
    copy_rows,
    gmap_bounds,
    gmap_class,
    in_order,
    orientation_signs,
    period_map,
)
from tgsis.db._transfer import (
    Columns,
    Storage,
    concat,
    consistent_read,
    copy_out,
    insert_feature_row,
    local_positions,
    resolve_class,
)
from tgsis.db.classes import FeatureClass, class_of_feature
from tgsis.db.copy import SQL_TYPES
from tgsis.db.multidim import fetch_md_gmap, insert_md, md_in_box, md_vertices_in_box
from tgsis.drawing import Drawable, gmap_drawable
from tgsis.errors import InvalidGMapError, InvalidInputError, NotFoundError, reraise
from tgsis.gmaps import EvolvingGMap, GMap, GMapPeriod

__all__ = [
    "insert_gmap",
    "fetch_gmap",
    "fetch_md_gmap",
    "gmap_at",
    "gmap_cells",
    "gmap_check",
    "md_in_box",
    "md_vertices_in_box",
    "GMapProblem",
]


@dataclass(frozen=True)
class GMapProblem:
    """A violated condition of a stored G-map (``tgsis.gmap_check``): what, how many darts, the first of them."""

    problem: str
    count: int
    darts: tuple[int, ...]


def _as_evolving(obj: GMap | EvolvingGMap, fc: FeatureClass) -> EvolvingGMap:
    """A plain G-map is one period known at t = 0 that lasts (alive), with its properties of the class's level."""
    if isinstance(obj, EvolvingGMap):
        return obj
    if isinstance(obj, GMap):
        values = (
            {k: np.asarray(v)[None] for k, v in obj.cell_properties.get(fc.cell_level, {}).items()}
            if fc.cell_level is not None
            else {}
        )
        return EvolvingGMap(
            [GMapPeriod([0.0], obj, level=fc.cell_level if values else None, cell_values=values)], alive=True, name=None
        )
    raise InvalidInputError(f"a G-map feature is a tgsis.gmaps.GMap or EvolvingGMap, got {type(obj).__name__}")


@checked
def insert_gmap(
    conn: Conn,
    feature_class: str | FeatureClass,
    obj: GMap | EvolvingGMap,
    properties: Mapping[str, Any] | None = None,
    *,
    name: str | None = None,
    drop_extra_properties: bool = False,
    axes: Sequence[str] | None = None,
    tolerance: float | None = None,
    sudden_change: float | None = None,
) -> int:
    """Store a G-map (or a G-map evolving in time) as a new feature of a class of G-maps; return its id.

    Parameters
    ----------
    conn : psycopg.Connection
    feature_class : str or FeatureClass
        A class with ``time_model="GMAP"`` (model 4) or ``"MULTIDIM"`` (model 5).
    obj : GMap or EvolvingGMap
        Model 4: a plain :class:`~tgsis.gmaps.GMap` is one period known at
        t = 0 that lasts for ever (its properties of the class's cell level
        stored at t = 0). Every period must be a valid G-map, with exactly
        the class's cell properties (of the class's cell level). Model 5: a
        GMap whose extra axes (time, knowledge, ...) are coordinates.
    properties : mapping, optional
        Per-feature property values.
    name : str, optional
        Geometry name (default: the object's).
    drop_extra_properties : bool
        Ignore cell values the class does not store instead of failing.
    axes : sequence of str, optional
        Model 5: the name of each of the m axes (default x, y, z, axis4, ...).
    tolerance : float, optional
        Model 4: the largest gap allowed between the last shape of a period
        and the first shape of the next (default: the setting
        ``tgsis.period_tolerance``, else 1e-6 of the G-map's extent; docs/time.md,
        "Topology changes").
    sudden_change : float, optional
        Model 4: store every topology change as a short linear transition of
        this duration (:meth:`EvolvingGMap.with_sudden_changes`).

    Raises
    ------
    DiscontinuousPeriodsError
        Model 4: a period starts farther than the tolerance from where the
        one before ends (the message names the period, the gap and a dart).
    InvalidGMapError
        A period breaks a condition of an n-G-map (the message names the
        darts); nothing is written.
    InvalidPropertyError, InvalidInputError, NotFoundError
    """
    fc = resolve_class(conn, feature_class)
    if fc.time_model == "MULTIDIM":
        return insert_md(conn, fc, obj, properties, name=name, axes=axes, drop_extra=drop_extra_properties)
    if axes is not None:
        raise InvalidInputError(f"feature class {fc.name} holds G-maps in time: their axes are x, y, z (axes=None)")
    fc = gmap_class(conn, fc)
    tolerance = checked_tolerance(tolerance)
    evolving = _as_evolving(obj, fc)
    if sudden_change is not None:
        evolving = evolving.with_sudden_changes(sudden_change)
    evolving.check(raise_=True)
    values = class_values(fc, evolving, drop_extra_properties)
    periods = evolving.periods
    n, m = evolving.dimension, evolving.embedding_dimension
    darts = [p.gmap.n_darts for p in periods]
    nodes = [len(p.gmap.points) for p in periods]
    dart0 = np.cumsum([0, *darts[:-1]]).astype(np.int64)
    node0 = np.cumsum([0, *nodes[:-1]]).astype(np.int64)
    level = fc.cell_level if fc.cell_level is not None and fc.cell_level <= n else None
    starts = np.array([p.start for p in periods])
    instants = [len(p.times) for p in periods]
    rows = [len(p.times) * k for p, k in zip(periods, nodes)]
    cells: dict[str, Any] = {}  # the cells of the property level, made by the dart rows' callable, used after

    def gmap_rows() -> Columns:
        return [
            ("geoid", np.array([geoid]), "int8"),
            ("dimension", np.array([n], np.int16), "int2"),
            ("embedding", np.array([m], np.int16), "int2"),
        ]

    def timem_rows() -> Columns:
        return [("geoid", np.full(len(periods), geoid), "int8"), ("timem", starts, "float8")]

    def timet_rows() -> Columns:
        return [
            ("geoid", np.full(sum(instants), geoid), "int8"),
            ("timem", np.repeat(starts, instants), "float8"),
            ("timet", concat([p.times for p in periods]), "float8"),
        ]

    def alpha_rows() -> Columns:
        return alpha_columns(
            geoid, np.stack([concat([p.gmap.alpha[i] + o for p, o in zip(periods, dart0)]) for i in range(n + 1)])
        )

    def dart_rows() -> Columns:
        # the orientation and the cells (orbits over every dart) are made here, while the alpha rows go in
        labels = [p.gmap.cells(level) for p in periods] if level is not None else []
        cells["counts"] = [int(c.max()) + 1 if len(c) else 0 for c in labels]
        cells["first"] = np.cumsum([0, *cells["counts"][:-1]]).astype(np.int64)
        signs = [orientation_signs(p.gmap) for p in periods]
        columns: list[tuple[str, npt.ArrayLike, str]] = [
            ("geoid", np.full(sum(darts), geoid), "int8"),
            ("dartid", np.arange(sum(darts), dtype=np.int64), "int8"),
            ("timem", np.repeat(starts, darts), "float8"),
            ("nodeid", concat([p.gmap.vertex + o for p, o in zip(periods, node0)]), "int8"),
        ]
        if level is not None:
            columns.append(("acellid", concat([c + o for c, o in zip(labels, cells["first"])]), "int8"))
        if all(s is not None for s in signs):
            columns.append(("positive", concat([s for s in signs if s is not None]), "bool"))
        return columns

    def node_rows() -> Columns:
        return [
            ("geoid", np.full(sum(nodes), geoid), "int8"),
            ("timem", np.repeat(starts, nodes), "float8"),
            ("nodeid", np.arange(sum(nodes), dtype=np.int64), "int8"),
        ]

    def vertex_rows() -> Columns:
        return [
            ("geoid", np.full(sum(rows), geoid), "int8"),
            ("timem", np.repeat(starts, rows), "float8"),
            ("timet", concat([np.repeat(p.times, k) for p, k in zip(periods, nodes)]), "float8"),
            (
                "nodeid",
                concat(
                    [np.tile(np.arange(k, dtype=np.int64) + o, len(p.times)) for p, k, o in zip(periods, nodes, node0)]
                ),
                "int8",
            ),
            ("coordinate", concat([p.positions.reshape(-1, m) for p in periods]), f"float8[{m}]"),
        ]

    def cell_rows() -> Columns:
        counts = cells["counts"]
        return [
            ("geoid", np.full(sum(counts), geoid), "int8"),
            ("acellid", np.arange(sum(counts), dtype=np.int64), "int8"),
            ("timem", np.repeat(starts, counts), "float8"),
            ("celllevel", np.full(sum(counts), level, dtype=np.int16), "int2"),
        ]

    def value_rows() -> Columns:
        counts = cells["counts"]
        per = [len(p.times) * c for p, c in zip(periods, counts)]
        return [
            ("_geoid", np.full(sum(per), geoid), "int8"),
            ("_timem", np.repeat(starts, per), "float8"),
            ("_timet", concat([np.repeat(p.times, c) for p, c in zip(periods, counts)]), "float8"),
            (
                "_idx",
                concat(
                    [
                        np.tile(np.arange(c, dtype=np.int64) + o, len(p.times))
                        for p, c, o in zip(periods, counts, cells["first"])
                    ]
                ),
                "int8",
            ),
            *(
                (prop.name, concat([v[prop.name].reshape(-1) for v in values]), SQL_TYPES[prop.type])
                for prop in fc.cell_properties
            ),
        ]

    with reraise(), conn.transaction():
        storage = Storage.of(conn, fc)
        storage.check("tgsis", "geometry")
        row = conn.execute(
            "SELECT tgsis.new_geometry('GMAP', %s, %s, %s, %s, p_timemodel => 'GMAP', p_alive => %s, p_class => %s)",
            (
                no_nul("geometry name", name if name is not None else evolving.name),
                gmap_bounds(evolving),
                sum(nodes),
                sum(darts),
                evolving.alive,
                fc.name,
            ),
        ).fetchone()
        assert row is not None
        geoid = int(row[0])
        # the largest table first: its rows need nothing but the involutions, and while the server takes them
        # the darts' orientation and cells are computed (Storage.copy_all)
        tables: list[tuple[str, str, Callable[[], Columns]]] = [
            ("tgsis", "gmap", gmap_rows),
            ("tgsis", "gmap_timem", timem_rows),
            ("tgsis", "gmap_timet", timet_rows),
            ("tgsis", "gmap_alpha", alpha_rows),
            ("tgsis", "gmap_dart", dart_rows),
            ("tgsis", "gmap_node", node_rows),
            ("tgsis", "gmap_vertex", vertex_rows),
        ]
        if level is not None:
            tables.append(("tgsis", "gmap_cell", cell_rows))
            if fc.cell_properties:
                tables.append((fc.schema, fc.cellprotable, value_rows))
        # the darts and involutions of tables stored in chunks: encoded here, one binary COPY each
        storage.copy_all(conn, tables, lambda table, columns: upload_rows(conn, table, columns, storage))
        if len(periods) > 1:
            check_continuity(conn, geoid, tolerance)
        insert_feature_row(conn, fc, geoid, properties)
    return geoid


def _key_ordered_images(alpha: Sequence[npt.NDArray[Any]], dartids: IntArray, n: int) -> IntArray | None:
    """The involutions ((n + 1, d) int64) of alpha rows (level, dartid, dartid2 in key order) with one row per dart and level.

    ``None`` when the rows are not exactly that (then each period's rows are picked out one by one).
    """
    levels, darts = n + 1, len(dartids)
    if (
        len(alpha[1]) != levels * darts
        or not np.array_equal(alpha[1], np.repeat(dartids, levels))
        or not np.array_equal(alpha[0], np.tile(np.arange(levels, dtype=alpha[0].dtype), darts))
    ):
        return None
    images: IntArray = alpha[2].reshape(darts, levels).T
    return images


def _period_images(
    alpha: Sequence[npt.NDArray[Any]], dartids: IntArray, n: int, start: float, feature_id: int
) -> list[IntArray]:
    """The involutions of one period's darts (sorted ``dartids``) from alpha rows of any shape, or an error."""
    images = []
    for i in range(n + 1):
        rows = (alpha[0] == i) & np.isin(alpha[1], dartids)
        if int(rows.sum()) != len(dartids):
            raise InvalidGMapError(
                f"G-map {feature_id}: period {float(start)!r} has {int(rows.sum())} alpha_{i} rows for "
                f"{len(dartids)} darts",
                hint=f"SELECT * FROM tgsis.gmap_check({feature_id})",
            )
        images.append(alpha[2][rows])
    return images


@checked
def fetch_gmap(conn: Conn, feature_class: str | FeatureClass, feature_id: int) -> EvolvingGMap:
    """A stored G-map feature with its periods, positions and cell values (one COPY per table).

    Raises
    ------
    NotFoundError
        ``feature_id`` is not a feature of the class.
    InvalidGMapError
        Stored rows that do not make a G-map (see ``tgsis.gmap_check``).
    """
    fc = gmap_class(conn, feature_class)

    def read() -> tuple[Any, ...]:
        """The G-map's rows of every table, of one state (:func:`consistent_read`)."""
        head = conn.execute(
            sql.SQL(
                "SELECT g.geoname, g.alive, m.dimension, m.embedding FROM {} f "
                "JOIN tgsis.geometry g ON g.geoid = f._geoid JOIN tgsis.gmap m ON m.geoid = f._geoid "
                "WHERE f._geoid = %s"
            ).format(fc.qualified(fc.featuretable)),
            (feature_id,),
        ).fetchone()
        if head is None:
            raise NotFoundError(f"feature class {fc.name} has no G-map feature {feature_id}")
        name, alive, n, m = head[0], bool(head[1]), int(head[2]), int(head[3])
        times = copy_rows(
            conn, "SELECT timem, timet FROM tgsis.gmap_timet WHERE geoid = {}", feature_id, ["float8", "float8"], [0, 1]
        )
        nodes = copy_rows(
            conn, "SELECT timem, nodeid FROM tgsis.gmap_node WHERE geoid = {}", feature_id, ["float8", "int8"], [0, 1]
        )
        chunked = chunked_tables(conn)
        # the points in chunks: decoded here (tgsis.db._chunk_transfer.point_rows), else read through the face
        vertex = point_rows(conn, "gmap_vertex", feature_id, m, chunked)
        if vertex is None:
            vertex = copy_rows(
                conn,
                "SELECT timem, timet, nodeid, coordinate FROM tgsis.gmap_vertex WHERE geoid = {}",
                feature_id,
                ["float8", "float8", "int8", f"float8[{m}]"],
                [0, 1, 2],
            )
        # the darts and involutions in chunks that the role may read: decoded here (the client codec, as gmap_at
        # reads a period's), the same columns in the same order as the faces' rows; else read through the faces
        dart = _object_darts(conn, feature_id, chunked)
        if dart is None:
            dart = copy_rows(
                conn,
                "SELECT timem, dartid, nodeid, coalesce(acellid, -1) FROM tgsis.gmap_dart WHERE geoid = {}",
                feature_id,
                ["float8", "int8", "int8", "int8"],
                [1],
            )
        alpha = _object_alpha(conn, feature_id, chunked)
        if alpha is None:
            alpha = copy_rows(
                conn,
                "SELECT level, dartid, dartid2 FROM tgsis.gmap_alpha WHERE geoid = {}",
                feature_id,
                ["int2", "int8", "int8"],
                [1, 0],
            )
        values = []
        if fc.cell_properties:
            values = in_order(
                copy_out(
                    conn,
                    sql.SQL("SELECT _timem, _timet, _idx, {} FROM {} WHERE _geoid = {}").format(
                        sql.SQL(", ").join(sql.Identifier(p.name) for p in fc.cell_properties),
                        fc.qualified(fc.cellprotable),
                        sql.Literal(feature_id),
                    ),
                    ["float8", "float8", "int8", *(p.wire for p in fc.cell_properties)],
                ),
                [0, 1, 2],
            )
        return name, alive, n, m, times, nodes, vertex, dart, alpha, values

    with reraise():
        name, alive, n, m, times, nodes, vertex, dart, alpha, values = consistent_read(conn, "fetch_gmap", read)
    aligned = _key_ordered_images(alpha, dart[1], n)
    periods = []
    for start in np.unique(times[0]):
        instants = times[1][times[0] == start]
        in_nodes = nodes[1][nodes[0] == start]
        in_darts = dart[0] == start
        dartids, nodeids, acellids = dart[1][in_darts], dart[2][in_darts], dart[3][in_darts]
        images = (
            list(aligned[:, in_darts]) if aligned is not None else _period_images(alpha, dartids, n, start, feature_id)
        )
        at = vertex[0] == start
        positions = vertex[3][at].reshape(len(instants), len(in_nodes), m)
        topology = period_map(dartids, nodeids, images, in_nodes, positions[0], feature_id)
        period_values: dict[str, npt.NDArray[Any]] = {}
        if fc.cell_level is not None and values and fc.cell_level <= n:
            first = cell_ids(topology, fc.cell_level, acellids)
            here = values[0] == start
            for j, prop in enumerate(fc.cell_properties):
                column = values[3 + j][here].reshape(len(instants), -1)
                ids = values[2][here].reshape(len(instants), -1)[0]
                period_values[prop.name] = column[:, local_positions(ids, first, "cell values", feature_id)]
        periods.append(
            GMapPeriod(
                instants, topology, positions, level=fc.cell_level if period_values else None, cell_values=period_values
            )
        )
    if not periods:
        raise InvalidGMapError(
            f"G-map {feature_id} has no topology period", hint=f"SELECT * FROM tgsis.gmap_check({feature_id})"
        )
    return EvolvingGMap(periods, alive=alive, name=name)


def _mix(a: npt.NDArray[np.float64], b: npt.NDArray[np.float64], w: float, same: bool) -> npt.NDArray[np.float64]:
    """a + w (b - a), the formula of the SQL snapshot (``tgsis.gmap_points_at``, ``gmap_property_at``), to the bit."""
    return a if same else a + w * (b - a)


def _readable_chunks(conn: Conn, table: str, chunked: frozenset[str], *, instants: bool = False) -> ChunkTable | None:
    """The chunk table of a model-4 table when its rows are read from it: stored in chunks and the role may read it."""
    if table not in chunked:
        return None
    layout = chunk_table(conn, table, instants=instants, values=not instants)
    return layout if layout.readable else None


def _object_darts(conn: Conn, feature_id: int, chunked: frozenset[str]) -> list[npt.NDArray[Any]] | None:
    """A G-map's darts from their chunks, decoded here: ``timem, dartid, nodeid, acellid`` (-1 for NULL) by dartid.

    What :func:`fetch_gmap` reads of the face (``copy_rows`` ordered by ``dartid``), bit for bit; None when the
    darts are rows or the role may not read their chunk table (it reads the face).
    """
    layout = _readable_chunks(conn, "gmap_dart", chunked)
    if layout is None:
        return None
    return _dart_columns(object_rows(conn, layout, feature_id))


def _dart_columns(rows: ObjectRows) -> list[npt.NDArray[Any]]:
    """``timem`` (d,) float64, ``dartid``, ``nodeid``, ``acellid`` (d,) int64 (-1 for NULL) of decoded dart rows."""
    nulls = rows.nulls.get("acellid")
    acellid = rows.columns["acellid"].astype(np.int64)
    if nulls is not None:
        acellid = np.where(nulls, -1, acellid)
    timem = rows.columns["timem"].astype(np.float64)
    return [timem, rows.ids.astype(np.int64), rows.columns["nodeid"].astype(np.int64), acellid]


def _object_alpha(conn: Conn, feature_id: int, chunked: frozenset[str]) -> list[npt.NDArray[Any]] | None:
    """A G-map's involutions from their chunks, decoded here: ``level`` int16, ``dartid``, ``dartid2`` by (dartid, level).

    What :func:`fetch_gmap` reads of the face (``copy_rows`` ordered by ``dartid, level``), bit for bit; None when
    the involutions are rows or the role may not read their chunk table (it reads the face).
    """
    layout = _readable_chunks(conn, "gmap_alpha", chunked)
    if layout is None:
        return None
    found = instant_rows(conn, layout, [feature_id])
    levels = sorted((int(key[1]), rows) for key, rows in found.items() if int(key[0]) == feature_id)
    if not levels:
        return [np.empty(0, dtype=np.int16), np.empty(0, dtype=np.int64), np.empty(0, dtype=np.int64)]
    ids = levels[0][1].ids
    if all(np.array_equal(rows.ids, ids) for _, rows in levels):  # every level of every dart: interleaved as is
        width = len(levels)
        level = np.tile(np.array([lv for lv, _ in levels], dtype=np.int16), len(ids))
        image = np.stack([rows.columns["dartid2"].astype(np.int64) for _, rows in levels], axis=1).reshape(-1)
        return [level, np.repeat(ids.astype(np.int64), width), image]
    columns = [
        np.concatenate([np.full(len(rows.ids), lv, dtype=np.int16) for lv, rows in levels]),
        np.concatenate([rows.ids.astype(np.int64) for _, rows in levels]),
        np.concatenate([rows.columns["dartid2"].astype(np.int64) for _, rows in levels]),
    ]
    return in_order(columns, [1, 0])


def _period_darts(
    conn: Conn, feature_id: int, timem: float, chunked: frozenset[str]
) -> list[npt.NDArray[np.int64]] | None:
    """A period's darts from their chunks (``dartid, nodeid, acellid`` with -1 for NULL, by dartid), or None: the face.

    Only the chunks holding a dart of the period are sent (``timem = ANY (c.timem)``), decoded here.
    """
    layout = _readable_chunks(conn, "gmap_dart", chunked)
    if layout is None:
        return None
    rows = object_rows(conn, layout, feature_id, sql.SQL("{} = ANY (c.timem)").format(sql.Literal(timem)))
    columns = _dart_columns(rows)
    here = columns[0] == timem  # (float8's =: -0.0 is 0.0, as the face's WHERE)
    return [column[here] for column in columns[1:]]


def _period_alpha(
    conn: Conn, feature_id: int, n: int, low: int, high: int, chunked: frozenset[str]
) -> list[npt.NDArray[Any]] | None:
    """The involutions of darts low..high from their chunks (``level, dartid, dartid2``, level-major), or None: the face."""
    layout = _readable_chunks(conn, "gmap_alpha", chunked)
    if layout is None:
        return None
    span = sql.SQL("c.chunk BETWEEN {} AND {}").format(sql.Literal(low // CHUNK_SIZE), sql.Literal(high // CHUNK_SIZE))
    levels = instant_rows(conn, layout, [feature_id], span) if high >= low else {}
    parts: list[list[npt.NDArray[Any]]] = [[], [], []]
    for level in range(n + 1):
        rows = levels.get((feature_id, float(level)))
        if rows is None:
            continue
        inside = (rows.ids >= low) & (rows.ids <= high)
        parts[0].append(np.full(int(inside.sum()), level, dtype=np.int16))
        parts[1].append(rows.ids[inside])
        parts[2].append(rows.columns["dartid2"].astype(np.int64)[inside])
    kinds = (np.int16, np.int64, np.int64)
    return [np.concatenate([np.empty(0, dtype=k), *p]) for k, p in zip(kinds, parts, strict=True)]


def _period_points(
    conn: Conn, feature_id: int, m: int, timem: float, instants: tuple[float, float], chunked: frozenset[str]
) -> list[list[npt.NDArray[Any]]] | None:
    """The period's points at its two bracketing instants from their chunks (``nodeid``, (k, m) coordinates), or None."""
    layout = _readable_chunks(conn, "gmap_vertex", chunked, instants=True)
    if layout is None or not layout.columns.points:
        return None
    point = layout.columns.points[0]
    where = sql.SQL("c.timem = {} AND c.timet IN ({}, {})").format(
        sql.Literal(timem), sql.Literal(instants[0]), sql.Literal(instants[1])
    )
    found = instant_rows(conn, layout, [feature_id], where)
    ends = []
    for at in instants:
        rows = next((o for key, o in found.items() if key[1] == timem and key[2] == at), None)
        if rows is None:
            ends.append([np.empty(0, dtype=np.int64), np.empty((0, m))])
            continue
        coordinates = rows.columns[point]
        if len(rows.ids) and coordinates.shape[1] != m:  # (as the face's read refuses a value of another size)
            raise InvalidGMapError(
                f"G-map {feature_id}: its points at {at!r} have {coordinates.shape[1]} coordinates, not its embedding's {m}",
                hint=f"SELECT * FROM tgsis.check_geometry({feature_id})",
            )
        ends.append([rows.ids, coordinates.reshape(-1, m)])
    return ends


@checked
def gmap_at(conn: Conn, feature_id: int, t: float) -> GMap | None:
    """The G-map of a feature at model time ``t``: the period and weight from SQL (``tgsis.gmap_frame``), its rows by COPY.

    The topology is the period's darts and involutions; points and the
    class's numeric cell properties are interpolated between the bracketing
    geometry instants with the SQL snapshot's formula (``tgsis.gmap_points_at``,
    ``tgsis.gmap_property_at``: equal to the bit), as :meth:`EvolvingGMap.at`
    does. None when the feature does not exist at ``t``. The rows travel as
    binary COPY, not as one array per dart (``tgsis.gmap_at`` is the same
    snapshot for psql).
    """
    t = check_time(t)
    fc = gmap_class(conn, class_of_feature(conn, feature_id))

    def read() -> tuple[Any, ...] | None:
        """The period's rows at t, of one state (:func:`consistent_read`)."""
        n_row = conn.execute("SELECT dimension, embedding FROM tgsis.gmap WHERE geoid = %s", (feature_id,)).fetchone()
        # binary: the period's key and the weight bit for bit, whatever the session's extra_float_digits (below 1,
        # text rounds them: the period's rows are missed, or the points mixed with another weight)
        frame = conn.execute(
            "SELECT timem, t0, t1, w FROM tgsis.gmap_frame(%s, %s)", (feature_id, t), binary=True
        ).fetchone()
        if n_row is None or frame is None:
            return None
        n, m = int(n_row[0]), int(n_row[1])
        timem, t0, t1, w = (float(v) for v in frame)
        key = [sql.Literal(feature_id), sql.Literal(timem)]
        # a table in chunks that the role may read: its chunks decoded here (the client codec, as fetch_feature
        # reads model 1), not the face's rows decoded by the server; else the face
        chunked = chunked_tables(conn)
        dart = _period_darts(conn, feature_id, timem, chunked)
        if dart is None:
            dart = copy_out(
                conn,
                sql.SQL(
                    "SELECT dartid, nodeid, coalesce(acellid, -1) FROM tgsis.gmap_dart "
                    "WHERE geoid = {} AND timem = {} ORDER BY dartid"
                ).format(*key),
                ["int8", "int8", "int8"],
            )
        # the involutions of the period's darts: one range of the key (geoid, dartid, level), whatever the planner's
        # statistics say (a join planned on freshly loaded tables ran for minutes), then only the period's darts
        low, high = (int(dart[0].min()), int(dart[0].max())) if len(dart[0]) else (0, -1)
        span = [sql.Literal(low), sql.Literal(high)]
        alpha = _period_alpha(conn, feature_id, n, low, high, chunked)
        if alpha is None:
            alpha = copy_out(
                conn,
                sql.SQL(
                    "SELECT a.level, a.dartid, a.dartid2 FROM tgsis.gmap_alpha a WHERE a.geoid = {} "
                    "AND a.dartid BETWEEN {} AND {} ORDER BY a.dartid, a.level"
                ).format(key[0], *span),
                ["int2", "int8", "int8"],
            )
        keep = np.isin(alpha[1], dart[0])
        alpha = [column[keep] for column in alpha]
        ends = _period_points(conn, feature_id, m, timem, (t0, t1), chunked)
        if ends is None:
            ends = [
                copy_out(
                    conn,
                    sql.SQL(
                        "SELECT nodeid, coordinate FROM tgsis.gmap_vertex WHERE geoid = {} AND timem = {} "
                        "AND timet = {} ORDER BY nodeid"
                    ).format(*key, sql.Literal(at)),
                    ["int8", f"float8[{m}]"],
                )
                for at in (t0, t1)
            ]
        props = [p for p in fc.cell_properties if p.size == 1 and p.type != "boolean"]
        values = (
            [
                copy_out(
                    conn,
                    sql.SQL(
                        "SELECT _idx, {} FROM {} WHERE _geoid = {} AND _timem = {} AND _timet = {} ORDER BY _idx"
                    ).format(
                        sql.SQL(", ").join(sql.SQL("{}::float8").format(sql.Identifier(p.name)) for p in props),
                        fc.qualified(fc.cellprotable),
                        *key,
                        sql.Literal(at),
                    ),
                    ["int8", *(["float8"] * len(props))],
                )
                for at in (t0, t1)
            ]
            if props and fc.cell_level is not None
            else []
        )
        return n, m, t0, t1, w, dart, alpha, ends, props, values

    with reraise():
        found = consistent_read(conn, "gmap_at", read)
    if found is None:
        return None
    n, m, t0, t1, w, dart, alpha, ends, props, values = found
    same = t0 == t1
    if not np.array_equal(ends[0][0], ends[1][0]):
        raise InvalidGMapError(
            f"G-map {feature_id}: the nodes at {t0!r} and {t1!r} differ",
            hint=f"SELECT * FROM tgsis.check_geometry({feature_id})",
        )
    points = _mix(ends[0][1].reshape(-1, m), ends[1][1].reshape(-1, m), w, same)
    images = [alpha[2][alpha[0] == i] for i in range(n + 1)]
    topology = period_map(dart[0], dart[1], images, ends[0][0], points, feature_id)
    if not values or fc.cell_level is None or fc.cell_level > n:
        return topology
    first = cell_ids(topology, fc.cell_level, dart[2])
    order = local_positions(values[0][0], first, "cell values", feature_id)
    cell_values = {p.name: _mix(values[0][1 + j], values[1][1 + j], w, same)[order] for j, p in enumerate(props)}
    return GMap(topology.alpha, topology.vertex, topology.points, cell_properties={fc.cell_level: cell_values})


def _model_of(conn: Conn, feature_id: int) -> str:
    with reraise():
        row = conn.execute("SELECT timemodel FROM tgsis.geometry WHERE geoid = %s", (feature_id,)).fetchone()
    if row is None or row[0] not in ("GMAP", "MULTIDIM"):
        raise NotFoundError(f"no G-map feature {feature_id}", hint="`tgsis ls` lists the features")
    return str(row[0])


@checked
def gmap_cells(conn: Conn, feature_id: int, level: int, t: float | None = None) -> tuple[IntArray, IntArray]:
    """The ``level``-cells of a feature's G-map (at ``t`` for model 4) from SQL (``tgsis.gmap_cells``, ``md_cells``).

    Returns
    -------
    dartids : (d,) int64
        The darts of the period containing t, ascending.
    cells : (d,) int64
        The cell of each, numbered 0.. in the order of the cells' least
        darts (:meth:`GMap.cells` of the snapshot). Both empty when the
        feature does not exist at t.
    """
    params: tuple[Any, ...]
    if _model_of(conn, feature_id) == "MULTIDIM":
        if t is not None:
            raise InvalidInputError(
                f"feature {feature_id} is a multiply indexed G-map: time is one of its axes (t=None)"
            )
        query, params = "SELECT dartid, cell FROM tgsis.md_cells(%s, %s)", (feature_id, level)
    else:
        if t is None:
            raise InvalidInputError(f"feature {feature_id} is a G-map in time: give the time t of its cells")
        query, params = "SELECT dartid, cell FROM tgsis.gmap_cells(%s, %s, %s)", (feature_id, level, check_time(t))
    with reraise(), conn.transaction():
        rows = conn.execute(query, params).fetchall()
    return np.array([r[0] for r in rows], dtype=np.int64), np.array([r[1] for r in rows], dtype=np.int64)


@checked
def gmap_check(conn: Conn, feature_id: int) -> list[GMapProblem]:
    """The violated conditions of a stored G-map with their first darts (``tgsis.gmap_check``, ``md_check``); empty: valid."""
    function = "md_check" if _model_of(conn, feature_id) == "MULTIDIM" else "gmap_check"
    with reraise():
        rows = conn.execute(
            sql.SQL("SELECT problem, count, darts FROM tgsis.{}(%s)").format(sql.Identifier(function)), (feature_id,)
        ).fetchall()
    return [GMapProblem(str(p), int(c), tuple(int(d) for d in darts)) for p, c, darts in rows]


# --------------------------------------------------------------------------- model 4 in the browser view


def _draw_at(
    conn: Conn,
    fc: FeatureClass,
    feature_id: int,
    t: float | None,
    /,
    *,
    colour: str | None = None,
    beside: Callable[[], Any] | None = None,
) -> Drawable | None:
    """Model 4's drawing (:class:`tgsis.datamodels.DrawFunction`): the SQL snapshot at t (:func:`gmap_at`), None outside its life."""
    if t is None:
        raise InvalidInputError(f"feature {feature_id} (class {fc.name}) is drawn at a time t")
    snapshot = gmap_at(conn, feature_id, t)
    return None if snapshot is None else gmap_drawable(snapshot)


def _life(conn: Conn, feature_id: int) -> tuple[float, float] | None:
    """Model 4's span in the view's time slider: its first and last geometry instant (``tgsis.gmap_timet``)."""
    with reraise():
        row = conn.execute(
            "SELECT min(timet), max(timet) FROM tgsis.gmap_timet WHERE geoid = %s", (feature_id,), binary=True
        ).fetchone()
    return None if row is None or row[0] is None else (float(row[0]), float(row[1]))


# model 4 in the registry of data models: insert_feature, fetch_object and the view come here (model 5: db/multidim.py)
datamodels.register_storage("GMAP", insert=insert_gmap, fetch=fetch_gmap, draw=_draw_at, life=_life)
