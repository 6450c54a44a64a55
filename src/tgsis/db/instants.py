"""Model 2 in the database: surfaces at instants (``time_model="INSTANTS"``), each instant with its own triangles.

A feature of an INSTANTS class is one ``tgsis.geometry`` row with its
instants in ``tgsis.times``, the surface at each instant in
``tgsis.times_vrtx`` and ``tgsis.times_trgl``, its vertex or cell property
values in the class's ``<name>_cellpros`` (with ``_times``) and its
per-instant feature properties in ``<name>_pros``. Uploads are one
transaction with one binary COPY per table, into the versioned storage of
the session's working revision when the tables are versioned (as for model
1). The questions over time both temporal models answer (the surface at t,
the instants, exports) are in :mod:`tgsis.db.temporal`.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np
import numpy.typing as npt
from psycopg import sql

from tgsis import datamodels
from tgsis._zpositive import elevation, z_convention
from tgsis.arguments import checked
from tgsis.db._chunk_transfer import (
    InstantKey,
    ObjectRows,
    chunked_tables,
    instant_layout,
    instant_rows,
    write_instants,
)
from tgsis.db._cube import cube_name
from tgsis.db._temporal_common import (
    Conn,
    assemble_surface,
    cell_columns,
    draw_snapshot,
    insert_instant_properties,
    instant_property_rows,
    instant_values,
    new_temporal_geometry,
    ordered_copy,
    point_bounds,
    property_arrays,
    slider_span,
    temporal_class,
    tgsis_table,
)
from tgsis.db._transfer import Storage, aligned_properties, concat, consistent_read, insert_feature_row, row_keys
from tgsis.db.classes import FeatureClass
from tgsis.db.copy import SQL_TYPES
from tgsis.drawing import Drawable
from tgsis.errors import NotFoundError, reraise
from tgsis.mesh import Surface
from tgsis.temporal import SurfaceSeries

__all__ = ["insert_series", "add_instant", "delete_instant", "fetch_series"]

log = logging.getLogger("tgsis.db.temporal")  # the logger of these functions before db/temporal.py was split


def _in_elevation(surfaces: Sequence[Surface]) -> tuple[list[Surface], str | None]:
    """The surfaces as stored, z up (a ``Depth`` one negated), and the z convention they all name (None: not one).

    Stored z is elevation whatever a surface's file said (tgsis.db.meaning); the
    convention is recorded so that a snapshot written to GOCAD says it again.

    Raises
    ------
    InvalidGeometryError
        A ``metadata["zpositive"]`` other than Elevation or Depth.
    """
    named = {z_convention(s.metadata) for s in surfaces}
    return [elevation(s) for s in surfaces], (named.pop() if len(named) == 1 else None)


def _local_ids(counts: Sequence[int]) -> npt.NDArray[np.int64]:
    """Ids 0..counts[i]-1 for each of the consecutive groups."""
    return row_keys([0] * len(counts), counts)[1]


def _copy_instants(
    conn: Conn,
    fc: FeatureClass,
    geoid: int,
    times: Sequence[float],
    surfaces: Sequence[Surface],
    storage: Storage,
    drop_extra: bool,
) -> None:
    """COPY the vertices, triangles and cell properties of surfaces at instants of geometry ``geoid``."""
    cell_values = [
        aligned_properties(fc, s, drop_extra, f"the surface at instant {t!r}") for t, s in zip(times, surfaces)
    ]
    n = [s.n_vertices for s in surfaces]
    m = [s.n_cells for s in surfaces]
    xyz = concat([s.vertices for s in surfaces])
    tri = concat([s.cells for s in surfaces])
    vertex_columns = {"x": xyz[:, 0], "y": xyz[:, 1], "z": xyz[:, 2]}
    # a time table stored in chunks takes the instants' chunks encoded here (one COPY), unless it holds chunks of
    # these instants already (a delete and add again in one revision: tgsis.insert_chunk_rows then)
    instants = [(t,) for t in times]
    write_instants(conn, "times_vrtx", geoid, instants, n, vertex_columns, storage, keys=["times"], idcolumn="vrtxid")
    triangle_columns = {f"vrtxid{j + 1}": tri[:, j] for j in range(3)}
    write_instants(conn, "times_trgl", geoid, instants, m, triangle_columns, storage, keys=["times"], idcolumn="trglid")
    if fc.cell_properties:
        counts = n if fc.alignment == "VERTEX" else m
        idx = _local_ids(counts)
        storage.copy(
            conn,
            fc.schema,
            fc.cellprotable,
            [
                ("_geoid", np.full(sum(counts), geoid, dtype=np.int64), "int8"),
                ("_times", np.repeat(np.asarray(times, dtype=np.float64), counts), "float8"),
                ("_idx", idx, "int8"),
                *((p.name, concat([v[p.name] for v in cell_values]), SQL_TYPES[p.type]) for p in fc.cell_properties),
            ],
        )


@checked
def insert_series(
    conn: Conn,
    feature_class: str | FeatureClass,
    series: SurfaceSeries,
    properties: Mapping[str, Any] | None = None,
    *,
    name: str | None = None,
    drop_extra_properties: bool = False,
) -> int:
    """Store a surface known at instants as a new feature of an INSTANTS class; return its id.

    Parameters
    ----------
    conn : psycopg.Connection
    feature_class : str or FeatureClass
        A class registered with ``time_model="INSTANTS"``.
    series : SurfaceSeries
        Each surface with exactly the class's vertex (or cell) properties;
        ``series.properties`` holds per-instant feature properties.
    properties : mapping, optional
        Per-feature property values.
    name : str, optional
        Geometry name (default ``series.name``).
    drop_extra_properties : bool
        Ignore surface properties the class does not store.

    Raises
    ------
    NotFoundError, InvalidInputError, InvalidPropertyError
        Nothing is written.
    """
    fc = temporal_class(conn, feature_class, "INSTANTS")
    times = series.times.tolist()
    instant_rows = instant_property_rows(fc, series.properties, len(times))
    surfaces, zpositive = _in_elevation(series.surfaces)
    with reraise(), conn.transaction():
        storage = Storage.of(conn, fc)
        storage.check("tgsis", "geometry")  # not "in" a version while the feature tables are plain
        geoid = new_temporal_geometry(
            conn,
            fc,
            name if name is not None else series.name,
            point_bounds(concat([s.vertices for s in surfaces])),
            sum(s.n_vertices for s in surfaces),
            sum(s.n_cells for s in surfaces),
            series.alive,
            series.color,
            zpositive,
        )
        storage.copy(
            conn,
            "tgsis",
            "times",
            [("geoid", np.full(len(times), geoid, dtype=np.int64), "int8"), ("times", series.times, "float8")],
        )
        _copy_instants(conn, fc, geoid, times, surfaces, storage, drop_extra_properties)
        insert_instant_properties(conn, fc, geoid, [(t,) for t in times], instant_rows, ["_times"])
        insert_feature_row(conn, fc, geoid, properties)
    log.info("stored %s feature %d: %d instants", fc.name, geoid, len(times))
    return geoid


@checked
def add_instant(
    conn: Conn,
    feature_class: str | FeatureClass,
    feature_id: int,
    t: float,
    surface: Surface,
    properties: Mapping[str, Any] | None = None,
    *,
    drop_extra_properties: bool = False,
) -> None:
    """Store the surface of feature ``feature_id`` at a new instant ``t`` (model 2).

    Parameters
    ----------
    t : float
        Finite; the feature must not have this instant yet.
    surface : Surface
        With exactly the class's vertex (or cell) properties.
    properties : mapping, optional
        Per-instant feature property values at ``t`` (missing: NULL).

    Raises
    ------
    NotFoundError, InvalidInputError, AlreadyExistsError, InvalidPropertyError
        Nothing is written.
    """
    fc = temporal_class(conn, feature_class, "INSTANTS")
    rows = instant_property_rows(fc, {k: np.asarray([v]) for k, v in (properties or {}).items()}, 1)
    [surface], _ = _in_elevation([surface])  # stored z is elevation
    bounds = point_bounds(surface.vertices)
    with reraise(), conn.transaction():
        storage = Storage.of(conn, fc)
        storage.check("tgsis", "times")  # not "in" a version while the feature tables are plain
        conn.execute("SELECT tgsis.add_instant(%s, %s)", (feature_id, float(t)))
        _copy_instants(conn, fc, feature_id, [float(t)], [surface], storage, drop_extra_properties)
        insert_instant_properties(conn, fc, feature_id, [(float(t),)], rows, ["_times"])
        conn.execute(
            sql.SQL(
                "UPDATE tgsis.geometry SET nvrtx = nvrtx + %(n)s, ncell = ncell + %(m)s, "
                "bbox = CASE WHEN %(b)s::float8[] IS NULL THEN bbox "
                "            WHEN bbox IS NULL THEN {cube}((%(b)s::float8[])[1:3], (%(b)s::float8[])[4:6]) "
                "            ELSE {union}(bbox, {cube}((%(b)s::float8[])[1:3], (%(b)s::float8[])[4:6])) END "
                "WHERE geoid = %(g)s"
            ).format(cube=cube_name(conn, "cube"), union=cube_name(conn, "cube_union")),
            {"n": surface.n_vertices, "m": surface.n_cells, "b": bounds, "g": feature_id},
        )


@checked
def delete_instant(conn: Conn, feature_id: int, t: float) -> bool:
    """Delete instant ``t`` of a model-2 feature with its surface and properties; False if it had none.

    Raises
    ------
    NotFoundError, InvalidInputError, InUseError
        InUseError for the feature's only instant (delete the feature instead).
    """
    with reraise(), conn.transaction():
        Storage.of(conn).check("tgsis", "times")  # not "in" a version while the feature tables are plain
        row = conn.execute("SELECT tgsis.delete_instant(%s, %s)", (feature_id, float(t))).fetchone()
    return bool(row and row[0])


def _instant_arrays(
    rows: Mapping[InstantKey, ObjectRows], columns: Sequence[str], dtypes: Sequence[Any]
) -> list[npt.NDArray[Any]]:
    """``[times, ids, *columns]`` (n,) each of one object's instants read from chunks, ordered by (times, id)."""
    keys = sorted(rows, key=lambda k: k[1])
    counts = [len(rows[k].ids) for k in keys]
    times = np.repeat(np.asarray([k[1] for k in keys], dtype=np.float64), counts)
    ids = np.concatenate([np.empty(0, dtype=np.int64), *(rows[k].ids for k in keys)])
    values = [
        np.concatenate([np.empty(0, dtype=dtype), *(rows[k].columns[c] for k in keys)])
        for c, dtype in zip(columns, dtypes)
    ]
    return [times, ids, *values]


def _instants_read(
    conn: Conn, table: str, geoid: int, chunked: frozenset[str], columns: Sequence[str], types: Sequence[str]
) -> list[npt.NDArray[Any]]:
    """Every instant's rows of ``tgsis.<table>`` of one feature, ``[times, id, *columns]`` ordered by (times, id):
    from its chunks, decoded here, when the time table is stored in them; else its rows, packed by the server."""
    layout = instant_layout(conn, table, chunked)
    if layout is not None:
        names = columns[1:]
        return _instant_arrays(instant_rows(conn, layout, [geoid]), names, [layout.columns.dtype(c) for c in names])
    return ordered_copy(conn, tgsis_table(table), ["times", *columns], ["float8", *types], geoid, keys=2)


@checked
def fetch_series(conn: Conn, feature_class: str | FeatureClass, feature_id: int) -> SurfaceSeries:
    """A model-2 feature as a :class:`~tgsis.temporal.SurfaceSeries`, with its cell and per-instant properties.

    Per-instant numeric properties come back as float64 or int64 arrays
    (NULLs as NaN); properties of other types are not included.

    Raises
    ------
    NotFoundError, InvalidInputError, InvalidGeometryError
    """
    fc = temporal_class(conn, feature_class, "INSTANTS")
    names, types = cell_columns(fc)

    def read() -> tuple[Any, ...]:
        """Every table's rows of the feature, of one state (:func:`consistent_read`)."""
        row = conn.execute(
            "SELECT geoname, alive, colorred, colorgreen, colorblue FROM tgsis.geometry "
            "WHERE geoid = %s AND timemodel = 'INSTANTS'",
            (feature_id,),
            binary=True,  # the colour bit for bit, whatever the session's extra_float_digits
        ).fetchone()
        if row is None:
            raise NotFoundError(f"feature {feature_id} of class {fc.name} does not exist")
        (times,) = ordered_copy(conn, tgsis_table("times"), ["times"], ["float8"], feature_id)
        chunked = chunked_tables(conn)
        vt, vid, x, y, z = _instants_read(
            conn, "times_vrtx", feature_id, chunked, ["vrtxid", "x", "y", "z"], ["int8", "float8", "float8", "float8"]
        )
        tt, tid, a, b, c = _instants_read(
            conn,
            "times_trgl",
            feature_id,
            chunked,
            ["trglid", "vrtxid1", "vrtxid2", "vrtxid3"],
            ["int8", "int8", "int8", "int8"],
        )
        props = (
            ordered_copy(
                conn,
                fc.qualified(fc.cellprotable),
                ["_times", "_idx", *names],
                ["float8", "int8", *types],
                feature_id,
                "_geoid",
                keys=2,
            )
            if names
            else []
        )
        values = instant_values(conn, fc, feature_id, ["_times"])
        return row, times, vt, vid, x, y, z, tt, tid, a, b, c, props, values

    with reraise():
        row, times, vt, vid, x, y, z, tt, tid, a, b, c, props, values = consistent_read(conn, "fetch_series", read)
    surfaces = []
    for t in times.tolist():
        v = np.flatnonzero(vt == t)
        tr = np.flatnonzero(tt == t)
        surface = assemble_surface(feature_id, vid[v], (x[v], y[v], z[v]), (a[tr], b[tr], c[tr]), row[0])
        if names:
            p = np.flatnonzero(props[0] == t)
            target = surface.vertex_properties if fc.alignment == "VERTEX" else surface.cell_properties
            target.update({name: props[2 + i][p] for i, name in enumerate(names)})
        surfaces.append(surface)
    return SurfaceSeries(
        times,
        surfaces,
        properties=property_arrays(fc, values, [(t,) for t in times.tolist()]),
        alive=bool(row[1]),
        name=row[0],
        color=None if row[2] is None else row[2:5],
    )


# --------------------------------------------------------------------------- model 2 in the browser view


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
    """Model 2's drawing (:class:`tgsis.datamodels.DrawFunction`): the SQL snapshot at t, None outside its life."""
    return draw_snapshot(conn, fc, feature_id, t)


def _life(conn: Conn, feature_id: int) -> tuple[float, float] | None:
    """Model 2's span in the view's time slider: its first and last instant."""
    return slider_span(conn, feature_id)


# model 2 in the registry of data models: insert_feature, fetch_object and the browser view come here
datamodels.register_storage("INSTANTS", insert=insert_series, fetch=fetch_series, draw=_draw_at, life=_life)
