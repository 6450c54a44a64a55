"""Model 5 in the database: multiply indexed n-G-maps in R^m, whose extra axes are time, knowledge or scale.

A feature of a class of ``time_model="MULTIDIM"`` is one ``tgsis.geometry``
row (geotype ``GMAP``, time model ``MULTIDIM``) with its dimensions, axis
names and extent over all its axes in ``tgsis.md_gmap``, its points in
``tgsis.md_vertex``, its darts in ``tgsis.md_dart``, its involutions in
``tgsis.md_alpha`` and the cells of the class's property level in
``tgsis.md_cell``; property values are rows ``(_geoid, _idx = acellid)`` of
the class's ``<name>_cellpros``. :func:`tgsis.insert_gmap` stores one (it
hands a class of model 5 on to :func:`insert_md`); box queries over any
subset of the axes use the GiST indexes of the extents and points.
:func:`tgsis.db.gmaps.gmap_cells` and ``gmap_check`` serve both G-map models.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np
import numpy.typing as npt
from psycopg import sql

from tgsis import datamodels
from tgsis.arguments import checked, no_nul
from tgsis.db._chunk_transfer import point_rows, upload_rows
from tgsis.db._cube import cube_name
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
    consistent_read,
    copy_out,
    insert_feature_row,
    local_positions,
    resolve_class,
)
from tgsis.db.classes import FeatureClass
from tgsis.db.copy import SQL_TYPES
from tgsis.db.inspect import md_gmap_axes
from tgsis.drawing import Drawable, gmap_drawable
from tgsis.errors import InvalidGMapError, InvalidInputError, InvalidPropertyError, NotFoundError, reraise
from tgsis.gmaps import EvolvingGMap, GMap, GMapPeriod

__all__ = ["fetch_md_gmap", "md_in_box", "md_vertices_in_box"]


def _default_axes(m: int) -> tuple[str, ...]:
    return tuple(["x", "y", "z"][:m] + [f"axis{i + 1}" for i in range(3, m)])


def _md_values(fc: FeatureClass, g: GMap, drop_extra: bool) -> dict[str, npt.NDArray[Any]]:
    """The class's cell property arrays (c,) of a model-5 G-map, checked and cast."""
    given = dict(g.cell_properties.get(fc.cell_level, {})) if fc.cell_level is not None else {}
    other = sorted(level for level in g.cell_properties if level != fc.cell_level and g.cell_properties[level])
    if other and not drop_extra:
        raise InvalidPropertyError(
            f"feature class {fc.name} stores properties of {fc.cell_level}-cells, the G-map "
            f"has properties of {other}-cells",
            hint="drop the others (drop_extra_properties=True)",
        )
    period = GMapPeriod(
        [0.0],
        GMap(g.alpha, g.vertex, g.points),
        level=fc.cell_level if given else None,
        cell_values={k: np.asarray(v)[None] for k, v in given.items()},
    )
    values = class_values(fc, EvolvingGMap([period]), drop_extra)[0]
    return {k: v[0] for k, v in values.items()}


def insert_md(
    conn: Conn,
    fc: FeatureClass,
    g: GMap | EvolvingGMap,
    properties: Mapping[str, Any] | None,
    *,
    name: str | None,
    axes: Sequence[str] | None,
    drop_extra: bool,
) -> int:
    """Store a model-5 G-map: md_gmap, md_vertex, md_dart, md_alpha, md_cell and the class's cell values.

    :func:`tgsis.insert_gmap` hands a class of model 5 (``fc``, resolved) on here.
    """
    if not isinstance(g, GMap):
        raise InvalidInputError(
            f"feature class {fc.name} holds multiply indexed G-maps: give a tgsis.gmaps.GMap "
            f"(time is one of its axes), not a {type(g).__name__}",
            hint="tgsis.gmaps.extrude makes an axis of time or knowledge",
        )
    g.check(raise_=True)
    n, m, d = g.dimension, g.embedding_dimension, g.n_darts
    names = tuple(axes) if axes is not None else _default_axes(m)
    if len(names) != m or len(set(names)) != m or not all(isinstance(a, str) and a for a in names):
        raise InvalidInputError(f"axes must name each of the {m} axes once, got {list(names)!r}")
    if m > 100:
        raise InvalidGMapError(f"a multiply indexed G-map has at most 100 axes (the cube type's limit), got {m}")
    if fc.cell_level is not None and fc.cell_level > n:
        raise InvalidGMapError(
            f"feature class {fc.name} stores properties of {fc.cell_level}-cells, which a {n}-G-map does not have"
        )
    values = _md_values(fc, g, drop_extra)
    level = fc.cell_level
    cells: list[npt.NDArray[np.int64]] = []  # the darts' cells of the property level, once dart_rows made them

    def vertex_rows() -> Columns:
        return [
            ("geoid", np.full(g.n_points, geoid), "int8"),
            ("vrtxid", np.arange(g.n_points, dtype=np.int64), "int8"),
            ("coordinate", g.points, f"float8[{m}]"),
        ]

    def alpha_rows() -> Columns:
        return alpha_columns(geoid, g.alpha)

    def dart_rows() -> Columns:
        columns: list[tuple[str, npt.ArrayLike, str]] = [
            ("geoid", np.full(d, geoid), "int8"),
            ("dartid", np.arange(d, dtype=np.int64), "int8"),
            ("vrtxid", g.vertex, "int8"),
        ]
        if level is not None:
            cells.append(g.cells(level))
            columns.append(("acellid", cells[0], "int8"))
        signs = orientation_signs(g)
        if signs is not None:
            columns.append(("positive", signs, "bool"))
        return columns

    def cell_count() -> int:
        return int(cells[0].max()) + 1 if len(cells[0]) else 0

    def cell_rows() -> Columns:
        count = cell_count()
        return [
            ("geoid", np.full(count, geoid), "int8"),
            ("acellid", np.arange(count, dtype=np.int64), "int8"),
            ("celllevel", np.full(count, level, dtype=np.int16), "int2"),
        ]

    def value_rows() -> Columns:
        count = cell_count()
        return [
            ("_geoid", np.full(count, geoid), "int8"),
            ("_idx", np.arange(count, dtype=np.int64), "int8"),
            *((prop.name, values[prop.name], SQL_TYPES[prop.type]) for prop in fc.cell_properties),
        ]

    with reraise(), conn.transaction():
        storage = Storage.of(conn, fc)
        storage.check("tgsis", "geometry")
        period = EvolvingGMap([GMapPeriod([0.0], g)])
        row = conn.execute(
            "SELECT tgsis.new_geometry('GMAP', %s, %s, %s, %s, p_timemodel => 'MULTIDIM', p_class => %s)",
            (no_nul("geometry name", name), gmap_bounds(period), g.n_points, d, fc.name),
        ).fetchone()
        assert row is not None
        geoid = int(row[0])
        extent = None
        if g.n_points:
            low, high = g.points.min(axis=0), g.points.max(axis=0)
            extent = (
                "(" + ", ".join(repr(float(v)) for v in low) + "),(" + ", ".join(repr(float(v)) for v in high) + ")"
            )
        # one row: through the versioned view when versioning is on (its trigger writes the working revision)
        conn.execute(
            sql.SQL(
                "INSERT INTO tgsis.md_gmap (geoid, dimension, embedding, axes, extent) VALUES (%s, %s, %s, %s, %s::{})"
            ).format(cube_name(conn, "cube")),
            (geoid, n, m, list(names), extent),
        )
        # as insert_gmap: the involutions first, the darts' cells and orientation computed while they go in
        tables: list[tuple[str, str, Callable[[], Columns]]] = [
            ("tgsis", "md_alpha", alpha_rows),
            ("tgsis", "md_vertex", vertex_rows),
            ("tgsis", "md_dart", dart_rows),
        ]
        if level is not None:
            tables.append(("tgsis", "md_cell", cell_rows))
            if fc.cell_properties:
                tables.append((fc.schema, fc.cellprotable, value_rows))
        # the darts and involutions of tables stored in chunks: encoded here, one binary COPY each
        storage.copy_all(conn, tables, lambda table, columns: upload_rows(conn, table, columns, storage))
        insert_feature_row(conn, fc, geoid, properties)
    return geoid


@checked
def fetch_md_gmap(conn: Conn, feature_class: str | FeatureClass, feature_id: int) -> tuple[GMap, tuple[str, ...]]:
    """A stored multiply indexed G-map (model 5) with its cell values, and the names of its axes.

    Raises
    ------
    NotFoundError
        ``feature_id`` is not a feature of the class.
    InvalidGMapError
        Stored rows that do not make a G-map (see ``tgsis.md_check``).
    """
    fc = gmap_class(conn, feature_class, "MULTIDIM")

    def read() -> tuple[Any, ...]:
        """The G-map's rows of every table, of one state (:func:`consistent_read`)."""
        head = conn.execute(
            sql.SQL(
                "SELECT m.dimension, m.embedding, m.axes FROM {} f JOIN tgsis.md_gmap m "
                "ON m.geoid = f._geoid WHERE f._geoid = %s"
            ).format(fc.qualified(fc.featuretable)),
            (feature_id,),
        ).fetchone()
        if head is None:
            raise NotFoundError(f"feature class {fc.name} has no multiply indexed G-map feature {feature_id}")
        n, m, axes = int(head[0]), int(head[1]), tuple(head[2])
        # the points in chunks: decoded here (tgsis.db._chunk_transfer.point_rows), else read through the face
        vertex = point_rows(conn, "md_vertex", feature_id, m)
        if vertex is None:
            vertex = copy_rows(
                conn,
                "SELECT vrtxid, coordinate FROM tgsis.md_vertex WHERE geoid = {}",
                feature_id,
                ["int8", f"float8[{m}]"],
                [0],
            )
        dart = copy_rows(
            conn,
            "SELECT dartid, vrtxid, coalesce(acellid, -1) FROM tgsis.md_dart WHERE geoid = {}",
            feature_id,
            ["int8", "int8", "int8"],
            [0],
        )
        alpha = copy_rows(
            conn,
            "SELECT level, dartid, dartid2 FROM tgsis.md_alpha WHERE geoid = {}",
            feature_id,
            ["int2", "int8", "int8"],
            [1, 0],
        )
        values = []
        if fc.cell_properties:
            values = in_order(
                copy_out(
                    conn,
                    sql.SQL("SELECT _idx, {} FROM {} WHERE _geoid = {}").format(
                        sql.SQL(", ").join(sql.Identifier(p.name) for p in fc.cell_properties),
                        fc.qualified(fc.cellprotable),
                        sql.Literal(feature_id),
                    ),
                    ["int8", *(p.wire for p in fc.cell_properties)],
                ),
                [0],
            )
        return n, m, axes, vertex, dart, alpha, values

    with reraise():
        n, m, axes, vertex, dart, alpha, values = consistent_read(conn, "fetch_md_gmap", read)
    images = [alpha[2][alpha[0] == i] for i in range(n + 1)]
    if any(len(a) != len(dart[0]) for a in images):
        raise InvalidGMapError(
            f"G-map {feature_id}: the alpha rows do not cover its {len(dart[0])} darts",
            hint=f"SELECT * FROM tgsis.md_check({feature_id})",
        )
    topology = period_map(dart[0], dart[1], images, vertex[0], vertex[1].reshape(len(vertex[0]), m), feature_id)
    if fc.cell_level is None or not values or fc.cell_level > n:
        return topology, axes
    first = cell_ids(topology, fc.cell_level, dart[2])
    cell_values = {
        p.name: values[1 + j][local_positions(values[0], first, "cell values", feature_id)]
        for j, p in enumerate(fc.cell_properties)
    }
    return GMap(topology.alpha, topology.vertex, topology.points, cell_properties={fc.cell_level: cell_values}), axes


@checked
def md_in_box(
    conn: Conn, feature_class: str | FeatureClass, axes: Sequence[str], low: Sequence[float], high: Sequence[float]
) -> list[int]:
    """Ids of a class's multiply indexed G-maps whose extent meets a box over some of their axes (``tgsis.md_in_box``).

    The box is closed; an extent is that of the points without a NaN coordinate (a G-map whose points all have
    one, which only plain SQL edits can make, is in no box).
    """
    fc = gmap_class(conn, feature_class, "MULTIDIM")
    with reraise():
        rows = conn.execute(
            "SELECT * FROM tgsis.md_in_box(%s, %s, %s, %s)",
            (fc.name, list(axes), [float(v) for v in low], [float(v) for v in high]),
        ).fetchall()
    return sorted(int(r[0]) for r in rows)


@checked
def md_vertices_in_box(
    conn: Conn, feature_id: int, axes: Sequence[str], low: Sequence[float], high: Sequence[float]
) -> IntArray:
    """The ids of a model-5 G-map's points inside a box over some of its axes (``tgsis.md_vertices_in_box``).

    The box is closed; a point with a NaN coordinate is in none.
    """
    with reraise():
        rows = conn.execute(
            "SELECT vrtxid FROM tgsis.md_vertices_in_box(%s, %s, %s, %s)",
            (feature_id, list(axes), [float(v) for v in low], [float(v) for v in high]),
        ).fetchall()
    return np.array([r[0] for r in rows], dtype=np.int64)


def _fetch_md(conn: Conn, fc: FeatureClass, feature_id: int) -> GMap:
    """Model 5's fetch for :func:`tgsis.fetch_object`: the G-map of :func:`fetch_md_gmap`."""
    return fetch_md_gmap(conn, fc, feature_id)[0]


def _insert_feature(
    conn: Conn,
    fc: FeatureClass,
    obj: GMap,
    properties: Mapping[str, Any] | None = None,
    /,
    *,
    name: str | None = None,
    drop_extra_properties: bool = False,
) -> int:
    """Model 5's insert for :func:`tgsis.insert_feature`: :func:`tgsis.insert_gmap` of a MULTIDIM class (axes x, y, z, ...)."""
    return insert_md(
        conn, resolve_class(conn, fc), obj, properties, name=name, axes=None, drop_extra=drop_extra_properties
    )


# --------------------------------------------------------------------------- model 5 in the browser view


def _draw_md(
    conn: Conn,
    fc: FeatureClass,
    feature_id: int,
    t: float | None,
    /,
    *,
    colour: str | None = None,
    beside: Callable[[], Any] | None = None,
) -> Drawable:
    """Model 5's drawing: the whole map (time, if any, is one of its axes), its axes beyond z as values to colour by."""
    history, axes = fetch_md_gmap(conn, fc, feature_id)
    return gmap_drawable(history, axes)


def _md_colours(conn: Conn, fc: FeatureClass, feature_id: int) -> list[str]:
    """What the view colours a model-5 map by besides height: its axes beyond z."""
    axes = md_gmap_axes(conn, feature_id)
    return axes[3:] if axes is not None else []


# model 5 in the registry of data models: insert_feature, fetch_object and the browser view come here
datamodels.register_storage("MULTIDIM", insert=_insert_feature, fetch=_fetch_md, draw=_draw_md, colours=_md_colours)
