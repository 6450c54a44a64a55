"""Temporal feature classes in the database: surfaces at instants (model 2) and evolving surfaces (model 3).

Storage (see ``docs/data-models.md``):

* model 2: ``tgsis.times`` (instants), ``tgsis.times_vrtx`` and
  ``tgsis.times_trgl`` (the surface at each instant), the class's
  ``<name>_cellpros`` with ``_times`` and ``<name>_pros`` (per-instant
  feature properties);
* model 3: ``tgsis.timem`` (topology instants), ``tgsis.timet`` (geometry
  instants of each period), ``tgsis.node``, ``tgsis.d4dtrgl``,
  ``tgsis.d4dvrtx`` (node positions at each geometry instant), the class's
  tables with ``_timem, _timet``.

Uploads are one transaction with one binary COPY per table, into the
versioned storage of the session's working revision when the tables are
versioned (as for model 1). Snapshots at t are computed in SQL by
``tgsis.vertices_at`` / ``tgsis.triangles_at`` and downloaded with binary COPY.
:func:`export_series` writes snapshots at several times as a ParaView
``.pvd`` time series (the numpy side is :func:`tgsis.temporal.write_series_pvd`).
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Iterator, Mapping, Sequence
from contextlib import contextmanager
from typing import Any

import numpy as np
import numpy.typing as npt
import psycopg
from psycopg import sql

from tgsis import datamodels
from tgsis._series import check_time
from tgsis._zpositive import elevation, z_convention
from tgsis.arguments import checked, no_nul
from tgsis.db._continuity import check_continuity, checked_tolerance
from tgsis.db._transfer import (
    Storage,
    aligned_properties,
    class_name,
    class_property_arrays,
    concat,
    copy_out,
    insert_feature_row,
    local_positions,
    read_only_snapshot,
    resolve_class,
    row_keys,
    rows_by_geoid,
)
from tgsis.db.classes import FeatureClass, class_of_feature
from tgsis.db.copy import SQL_TYPES, numpy_dtype
from tgsis.errors import InvalidGeometryError, InvalidInputError, InvalidPropertyError, NotFoundError, reraise
from tgsis.formats._common import PathLike
from tgsis.formats.vtk import Encoding
from tgsis.mesh import Geotype, Surface
from tgsis.temporal import (
    Convention,
    EvolvingSurface,
    Period,
    SurfaceFrame,
    SurfaceSeries,
    TopologyPeriod,
    WrittenSeries,
    check_convention,
    even_times,
    write_frames_pvd,
)
from tgsis.temporal import sudden_change as sudden
from tgsis.view.meshes import Drawable, drawable

__all__ = [
    "insert_series",
    "insert_evolving",
    "add_instant",
    "delete_instant",
    "append_period",
    "delete_period",
    "instants",
    "get_at",
    "surfaces_at",
    "features_at",
    "fetch_series",
    "fetch_evolving",
    "lifespan",
    "frames_at",
    "export_series",
    "property_periods",
    "class_property_periods",
    "first_times",
]

log = logging.getLogger(__name__)

Conn = psycopg.Connection[Any]


def _temporal_class(conn: Conn, feature_class: str | FeatureClass, model: str) -> FeatureClass:
    fc = resolve_class(conn, feature_class)
    if fc.time_model != model:
        raise InvalidInputError(
            f"feature class {fc.name} has time model {fc.time_model}, not {model}",
            hint="SurfaceSeries go to INSTANTS classes, EvolvingSurface to EVOLVING classes",
        )
    return fc


def _bounds(points: npt.NDArray[np.float64]) -> list[float] | None:
    """[xmin, ymin, zmin, xmax, ymax, zmax] of (..., 3) points, None when there are none."""
    flat = points.reshape(-1, 3)
    return None if len(flat) == 0 else [*flat.min(axis=0).tolist(), *flat.max(axis=0).tolist()]


def _new_temporal_geometry(
    conn: Conn,
    fc: FeatureClass,
    name: str | None,
    bounds: list[float] | None,
    nvrtx: int,
    ncell: int,
    alive: bool,
    color: Sequence[float] | None,
    zpositive: str | None = None,
) -> int:
    row = conn.execute(
        "SELECT tgsis.new_geometry('SURFACE', %s, %s, %s, %s, NULL, NULL, %s, %s, %s::real[], "
        "p_zpositive => %s, p_class => %s)",
        (
            no_nul("geometry name", name),
            bounds,
            nvrtx,
            ncell,
            fc.time_model,
            alive,
            list(color) if color else None,
            zpositive,
            fc.name,
        ),
    ).fetchone()
    assert row is not None
    return int(row[0])


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


def _instant_rows(fc: FeatureClass, values: Mapping[str, npt.NDArray[Any]], count: int) -> list[list[Any]]:
    """Per-instant feature property values as ``count`` rows in the class's column order (missing: NULL)."""
    known = [p.name for p in fc.instant_properties]
    unknown = sorted(set(values) - set(known))
    if unknown:
        raise InvalidPropertyError(
            f"feature class {fc.name} has no per-instant properties {unknown}",
            hint=f"its per-instant properties: {known or 'none'}",
        )
    return [[values[name][i].item() if name in values else None for name in known] for i in range(count)]


def _insert_instant_properties(
    conn: Conn,
    fc: FeatureClass,
    geoid: int,
    keys: Sequence[Sequence[Any]],
    rows: Sequence[Sequence[Any]],
    key_columns: Sequence[str],
) -> None:
    """One row per instant into ``<name>_pros`` (few rows, any column type: a plain INSERT)."""
    if not fc.instant_properties or not rows:
        return
    assert fc.protable is not None
    columns = ["_geoid", *key_columns, *(p.name for p in fc.instant_properties)]
    with conn.cursor() as cur:
        cur.executemany(
            sql.SQL("INSERT INTO {} ({}) VALUES ({})").format(
                fc.qualified(fc.protable),
                sql.SQL(", ").join(sql.Identifier(c) for c in columns),
                sql.SQL(", ").join(sql.Placeholder() for _ in columns),
            ),
            [[geoid, *k, *r] for k, r in zip(keys, rows)],
        )


# --------------------------------------------------------------------------- model 2


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
    vertex_ids, triangle_ids = _local_ids(n), _local_ids(m)
    geoids_v = np.full(sum(n), geoid, dtype=np.int64)
    geoids_t = np.full(sum(m), geoid, dtype=np.int64)
    xyz = concat([s.vertices for s in surfaces])
    tri = concat([s.cells for s in surfaces])
    storage.copy(
        conn,
        "tgsis",
        "times_vrtx",
        [
            ("geoid", geoids_v, "int8"),
            ("times", np.repeat(np.asarray(times, dtype=np.float64), n), "float8"),
            ("vrtxid", vertex_ids, "int8"),
            ("x", xyz[:, 0], "float8"),
            ("y", xyz[:, 1], "float8"),
            ("z", xyz[:, 2], "float8"),
        ],
    )
    storage.copy(
        conn,
        "tgsis",
        "times_trgl",
        [
            ("geoid", geoids_t, "int8"),
            ("times", np.repeat(np.asarray(times, dtype=np.float64), m), "float8"),
            ("trglid", triangle_ids, "int8"),
            *((f"vrtxid{j + 1}", tri[:, j], "int8") for j in range(3)),
        ],
    )
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
    fc = _temporal_class(conn, feature_class, "INSTANTS")
    times = series.times.tolist()
    instant_rows = _instant_rows(fc, series.properties, len(times))
    surfaces, zpositive = _in_elevation(series.surfaces)
    with reraise(), conn.transaction():
        storage = Storage.of(conn, fc)
        storage.check("tgsis", "geometry")  # not "in" a version while the feature tables are plain
        geoid = _new_temporal_geometry(
            conn,
            fc,
            name if name is not None else series.name,
            _bounds(concat([s.vertices for s in surfaces])),
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
        _insert_instant_properties(conn, fc, geoid, [(t,) for t in times], instant_rows, ["_times"])
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
    fc = _temporal_class(conn, feature_class, "INSTANTS")
    rows = _instant_rows(fc, {k: np.asarray([v]) for k, v in (properties or {}).items()}, 1)
    [surface], _ = _in_elevation([surface])  # stored z is elevation
    bounds = _bounds(surface.vertices)
    with reraise(), conn.transaction():
        storage = Storage.of(conn, fc)
        storage.check("tgsis", "times")  # not "in" a version while the feature tables are plain
        conn.execute("SELECT tgsis.add_instant(%s, %s)", (feature_id, float(t)))
        _copy_instants(conn, fc, feature_id, [float(t)], [surface], storage, drop_extra_properties)
        _insert_instant_properties(conn, fc, feature_id, [(float(t),)], rows, ["_times"])
        conn.execute(
            "UPDATE tgsis.geometry SET nvrtx = nvrtx + %s, ncell = ncell + %s, "
            "bbox = CASE WHEN %s::float8[] IS NULL THEN bbox "
            "            WHEN bbox IS NULL THEN cube((%s::float8[])[1:3], (%s::float8[])[4:6]) "
            "            ELSE cube_union(bbox, cube((%s::float8[])[1:3], (%s::float8[])[4:6])) END "
            "WHERE geoid = %s",
            (surface.n_vertices, surface.n_cells, bounds, bounds, bounds, bounds, bounds, feature_id),
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


@checked
def instants(conn: Conn, feature_id: int) -> list[tuple[float, bool]]:
    """The instants of a temporal feature, ascending, with whether its topology is (re)defined there.

    Model 2: every instant (each has its own triangles). Model 3: every
    geometry instant; True where a topology period starts.
    """
    with reraise(), conn.transaction():  # a savepoint: an error leaves the caller's transaction usable
        rows = conn.execute("SELECT t, topology FROM tgsis.geometry_instants(%s)", (feature_id,)).fetchall()
    return [(float(r[0]), bool(r[1])) for r in rows]


# --------------------------------------------------------------------------- model 3


def _period_columns(fc: FeatureClass, surface: EvolvingSurface, drop_extra: bool) -> list[dict[str, npt.NDArray[Any]]]:
    """Per period, the class's vertex or cell property arrays (g, n) or (g, m), checked and cast."""
    return [
        class_property_arrays(
            fc,
            *(
                (p.vertex_properties, p.cell_properties)
                if fc.alignment == "VERTEX"
                else (p.cell_properties, p.vertex_properties)
            ),
            "vertex" if fc.alignment == "VERTEX" else "triangle",
            drop_extra,
            f"topology period {i}",
        )
        for i, p in enumerate(surface.periods)
    ]


def _copy_periods(
    conn: Conn,
    storage: Storage,
    fc: FeatureClass,
    geoid: int,
    periods: Sequence[TopologyPeriod],
    cell_values: Sequence[Mapping[str, npt.NDArray[Any]]],
    first_node: int,
    first_triangle: int,
) -> None:
    """COPY the rows of model-3 topology periods (instants, nodes, triangles, 4D vertices, vertex or cell properties).

    Nodes and triangles are numbered on from ``first_node`` and ``first_triangle``
    through the periods, so that ids stay unique in the feature.
    """
    starts = [p.start for p in periods]
    g = [len(p.times) for p in periods]
    n = [p.n_nodes for p in periods]
    m = [p.n_triangles for p in periods]
    node_offsets = first_node + np.cumsum([0, *n[:-1]])
    triangle_offsets = first_triangle + np.cumsum([0, *m[:-1]])

    def full(count: int) -> npt.NDArray[np.int64]:
        return np.full(count, geoid, dtype=np.int64)

    storage.copy(
        conn,
        "tgsis",
        "timem",
        [("geoid", full(len(periods)), "int8"), ("timem", np.asarray(starts, dtype=np.float64), "float8")],
    )
    storage.copy(
        conn,
        "tgsis",
        "timet",
        [
            ("geoid", full(sum(g)), "int8"),
            ("timem", np.repeat(starts, g).astype(np.float64), "float8"),
            ("timet", concat([p.times for p in periods]), "float8"),
        ],
    )
    storage.copy(
        conn,
        "tgsis",
        "node",
        [
            ("geoid", full(sum(n)), "int8"),
            ("timem", np.repeat(starts, n).astype(np.float64), "float8"),
            ("nodeid", first_node + np.arange(sum(n), dtype=np.int64), "int8"),
        ],
    )
    triangles = concat([p.triangles + off for p, off in zip(periods, node_offsets.tolist())])
    storage.copy(
        conn,
        "tgsis",
        "d4dtrgl",
        [
            ("geoid", full(sum(m)), "int8"),
            ("timem", np.repeat(starts, m).astype(np.float64), "float8"),
            ("trglid", first_triangle + np.arange(sum(m), dtype=np.int64), "int8"),
            *((f"nodeid{j + 1}", triangles[:, j], "int8") for j in range(3)),
        ],
    )
    # per period and geometry instant, every node: g_i * n_i rows
    samples = [gi * ni for gi, ni in zip(g, n)]
    xyz = concat([p.positions.reshape(-1, 3) for p in periods])
    storage.copy(
        conn,
        "tgsis",
        "d4dvrtx",
        [
            ("geoid", full(sum(samples)), "int8"),
            ("timem", np.repeat(starts, samples).astype(np.float64), "float8"),
            ("timet", concat([np.repeat(p.times, p.n_nodes) for p in periods]), "float8"),
            (
                "nodeid",
                concat(
                    [
                        np.tile(np.arange(p.n_nodes, dtype=np.int64) + off, len(p.times))
                        for p, off in zip(periods, node_offsets.tolist())
                    ]
                ),
                "int8",
            ),
            ("x", xyz[:, 0], "float8"),
            ("y", xyz[:, 1], "float8"),
            ("z", xyz[:, 2], "float8"),
        ],
    )
    if fc.cell_properties:
        per = n if fc.alignment == "VERTEX" else m
        offsets = node_offsets if fc.alignment == "VERTEX" else triangle_offsets
        rows = [gi * ci for gi, ci in zip(g, per)]
        storage.copy(
            conn,
            fc.schema,
            fc.cellprotable,
            [
                ("_geoid", full(sum(rows)), "int8"),
                ("_timem", np.repeat(starts, rows).astype(np.float64), "float8"),
                ("_timet", concat([np.repeat(p.times, c) for p, c in zip(periods, per)]), "float8"),
                (
                    "_idx",
                    concat(
                        [
                            np.tile(np.arange(c, dtype=np.int64) + off, len(p.times))
                            for p, c, off in zip(periods, per, offsets.tolist())
                        ]
                    ),
                    "int8",
                ),
                *(
                    (prop.name, concat([v[prop.name].reshape(-1) for v in cell_values]), SQL_TYPES[prop.type])
                    for prop in fc.cell_properties
                ),
            ],
        )


@checked
def insert_evolving(
    conn: Conn,
    feature_class: str | FeatureClass,
    surface: EvolvingSurface,
    properties: Mapping[str, Any] | None = None,
    *,
    name: str | None = None,
    drop_extra_properties: bool = False,
    tolerance: float | None = None,
    sudden_change: float | None = None,
) -> int:
    """Store an evolving surface as a new feature of an EVOLVING class; return its id.

    Nodes and triangles are numbered on through the periods (period 0 has
    nodes 0..n0-1, period 1 n0..n0+n1-1, ...), so ids are unique in the
    feature and ``_idx`` of properties names one node or triangle.

    Parameters
    ----------
    conn : psycopg.Connection
    feature_class : str or FeatureClass
        A class registered with ``time_model="EVOLVING"``.
    surface : EvolvingSurface
        Every period with exactly the class's vertex (or cell) properties,
        (g, n) or (g, m) arrays; per-instant feature properties in
        ``period.properties``.
    properties : mapping, optional
        Per-feature property values.
    name : str, optional
        Geometry name (default ``surface.name``).
    tolerance : float, optional
        The largest gap allowed between the last shape of a period and the
        first shape of the next (model units; default: the setting
        ``tgsis.period_tolerance``, else 1e-6 of the surface's extent).
        docs/time.md, "Topology changes", says how the gap is measured.
    sudden_change : float, optional
        Store every topology change as the design's sudden change: each
        period after the first starts in the last shape of the one before
        and reaches its own first shape this much later, linearly
        (:meth:`EvolvingSurface.with_sudden_changes`).

    Raises
    ------
    DiscontinuousPeriodsError
        A period starts farther than the tolerance from where the one before
        ends (the message names the period, the gap and the node).
    NotFoundError, InvalidInputError, InvalidPropertyError
        Nothing is written.
    """
    fc = _temporal_class(conn, feature_class, "EVOLVING")
    tolerance = checked_tolerance(tolerance)
    if sudden_change is not None:
        surface = surface.with_sudden_changes(sudden_change)
    cell_values = _period_columns(fc, surface, drop_extra_properties)
    periods = surface.periods
    n = [p.n_nodes for p in periods]
    m = [p.n_triangles for p in periods]
    instant_rows = [row for p in periods for row in _instant_rows(fc, dict(p.properties), len(p.times))]
    with reraise(), conn.transaction():
        storage = Storage.of(conn, fc)
        storage.check("tgsis", "geometry")  # not "in" a version while the feature tables are plain
        geoid = _new_temporal_geometry(
            conn,
            fc,
            name if name is not None else surface.name,
            _bounds(concat([p.positions.reshape(-1, 3) for p in periods])),
            sum(n),
            sum(m),
            surface.alive,
            surface.color,
        )
        _copy_periods(conn, storage, fc, geoid, periods, cell_values, 0, 0)
        keys = [(p.start, float(t)) for p in periods for t in p.times.tolist()]
        _insert_instant_properties(conn, fc, geoid, keys, instant_rows, ["_timem", "_timet"])
        if len(periods) > 1:
            check_continuity(conn, geoid, tolerance)
        insert_feature_row(conn, fc, geoid, properties)
    log.info(
        "stored %s feature %d: %d topology periods, %d nodes, %d triangles",
        fc.name,
        geoid,
        len(periods),
        sum(n),
        sum(m),
    )
    return geoid


@checked
def append_period(
    conn: Conn,
    feature_class: str | FeatureClass,
    feature_id: int,
    period: TopologyPeriod,
    *,
    drop_extra_properties: bool = False,
    tolerance: float | None = None,
    sudden_change: float | None = None,
) -> None:
    """Append a topology period to an evolving feature, after its last one (one transaction).

    The new period must start at the feature's last geometry instant (periods
    follow each other: :class:`~tgsis.temporal.EvolvingSurface`); its nodes
    and triangles are numbered on after the feature's.

    Parameters
    ----------
    conn : psycopg.Connection
    feature_class : str or FeatureClass
        The feature's EVOLVING class.
    feature_id : int
    period : TopologyPeriod
        With the class's vertex (or cell) and per-instant properties.
    drop_extra_properties : bool
        Ignore properties the class does not store instead of failing.
    tolerance : float, optional
        The largest gap allowed between the feature's last shape and the new
        period's first (as for :func:`insert_evolving`).
    sudden_change : float, optional
        The new period starts in the feature's last shape and reaches its
        own first shape this much later, linearly (:func:`tgsis.temporal.sudden_change`).

    Raises
    ------
    DiscontinuousPeriodsError
        The new period starts farther than the tolerance from the feature's
        last shape (the message names the gap and the node).
    NotFoundError, InvalidInputError, InvalidPropertyError
        Nothing is written.
    """
    fc = _temporal_class(conn, feature_class, "EVOLVING")
    tolerance = checked_tolerance(tolerance)
    with reraise(), conn.transaction():
        storage = Storage.of(conn, fc)
        storage.check("tgsis", "geometry")  # not "in" a version while the feature tables are plain
        conn.execute("SELECT tgsis.temporal_geometry(%s, 'EVOLVING')", (feature_id,))
        # one writer of the feature's periods at a time: a second append waits, then sees the new last instant
        conn.execute("SELECT FROM tgsis.geometry WHERE geoid = %s FOR UPDATE", (feature_id,))
        if (
            conn.execute(
                sql.SQL("SELECT FROM {}.{} WHERE _geoid = %s").format(
                    sql.Identifier(fc.schema), sql.Identifier(fc.featuretable)
                ),
                (feature_id,),
            ).fetchone()
            is None
        ):
            raise NotFoundError(f"feature {feature_id} is not a feature of class {fc.name}")
        row = conn.execute(
            "SELECT (SELECT max(timet) FROM tgsis.timet WHERE geoid = %(g)s), "
            "(SELECT coalesce(max(nodeid) + 1, 0) FROM tgsis.node WHERE geoid = %(g)s), "
            "(SELECT coalesce(max(trglid) + 1, 0) FROM tgsis.d4dtrgl WHERE geoid = %(g)s)",
            {"g": feature_id},
        ).fetchone()
        assert row is not None
        if row[0] is None or float(row[0]) != period.start:
            raise InvalidInputError(
                f"the new topology period of feature {feature_id} starts at {period.start!r}, not at its last geometry "
                f"instant {row[0]!r}",
                hint="periods follow each other: start the new one where the last one ends",
            )
        if sudden_change is not None:
            last = get_at(conn, feature_id, period.start)
            assert last is not None  # the feature has a shape at its last geometry instant
            period = sudden(last, period, sudden_change, label=f"the new topology period of feature {feature_id}")
        cell_values = _period_columns(fc, EvolvingSurface([period]), drop_extra_properties)
        instant_rows = _instant_rows(fc, dict(period.properties), len(period.times))
        _copy_periods(conn, storage, fc, feature_id, [period], cell_values, int(row[1]), int(row[2]))
        _insert_instant_properties(
            conn,
            fc,
            feature_id,
            [(period.start, float(t)) for t in period.times.tolist()],
            instant_rows,
            ["_timem", "_timet"],
        )
        conn.execute("SELECT tgsis.refresh_geometry(%s)", (feature_id,))
        check_continuity(conn, feature_id, tolerance, period.start)


@checked
def delete_period(conn: Conn, feature_id: int, start: float) -> bool:
    """Remove the first or last topology period of an evolving feature (``tgsis.delete_period``).

    Returns False when no period of it starts at ``start``.

    Raises
    ------
    NotFoundError
        No such feature.
    InUseError
        The only period (delete the feature), or one between others (it would leave a gap).
    """
    with reraise(), conn.transaction():
        row = conn.execute("SELECT tgsis.delete_period(%s, %s)", (feature_id, check_time(start))).fetchone()
    return bool(row and row[0])


# --------------------------------------------------------------------------- snapshots


def _time_args(t: float, convention: str) -> tuple[sql.Literal, sql.Literal]:
    return sql.Literal(check_time(t)), sql.Literal(check_convention(convention))


@contextmanager
def _without_jit(conn: Conn) -> Iterator[None]:
    """JIT off for the statements inside (in a transaction), then the caller's setting back.

    A snapshot query is costed above ``jit_above_cost``, and compiling it
    (1.1-1.3 s measured on PostgreSQL 15 for 1M nodes, see
    docs/performance.md) costs more than the few arithmetic operations per
    row it would speed up.
    """
    row = conn.execute("SELECT current_setting('jit'), set_config('jit', 'off', true)").fetchone()
    assert row is not None
    yield
    conn.execute("SELECT set_config('jit', %s, true)", (row[0],))


def _assemble(
    geoid: int,
    ids: npt.NDArray[np.int64],
    xyz: Sequence[npt.NDArray[np.float64]],
    triangles: Sequence[npt.NDArray[np.int64]],
    name: str | None,
) -> Surface:
    """A Surface from vertex rows (ids in any order) and triangle rows pointing at those ids."""
    order = rows_by_geoid(ids, ids, [geoid])[geoid]  # no sort when the rows come in id order
    sorted_ids = ids[order]
    vertices = np.stack([xyz[0][order], xyz[1][order], xyz[2][order]], axis=1)
    cells = (
        np.stack([local_positions(sorted_ids, t, "triangles", geoid) for t in triangles], axis=1)
        if len(triangles[0])
        else np.empty((0, 3), dtype=np.int64)
    )
    return Surface(vertices, cells, name=name)


#: Property types whose values at t can be interpolated (tgsis.property_at).
_NUMERIC = frozenset(("smallint", "integer", "bigint", "real", "double precision", "numeric"))


def _properties_at(
    conn: Conn,
    surface: Surface,
    feature_id: int,
    t: float,
    convention: Convention,
    vertex_ids: npt.NDArray[np.int64],
    triangle_ids: npt.NDArray[np.int64],
) -> None:
    """Attach the class's numeric vertex or cell properties at t (``tgsis.property_at``) to the snapshot."""
    fc = class_of_feature(conn, feature_id)
    ids, into = (
        (vertex_ids, surface.vertex_properties) if fc.alignment == "VERTEX" else (triangle_ids, surface.cell_properties)
    )
    for prop in fc.cell_properties:
        if prop.type not in _NUMERIC or prop.size != 1 or prop.alignment not in (None, fc.alignment):
            continue  # booleans, vectors and the other alignment's properties have no interpolated value here
        idx, value = copy_out(
            conn,
            sql.SQL("SELECT idx, coalesce(value, 'NaN') FROM tgsis.property_at({}, {}, {}, {}, {})").format(
                sql.Literal(fc.name),
                sql.Literal(feature_id),
                sql.Literal(prop.name),
                sql.Literal(float(t)),
                sql.Literal(convention),
            ),
            ["int8", "float8"],
        )
        values = np.full(len(ids), np.nan)
        if len(ids):
            where = np.minimum(np.searchsorted(ids, idx), len(ids) - 1)
            known = ids[where] == idx
            values[where[known]] = value[known]
        into[prop.name] = values


@checked
def get_at(
    conn: Conn, feature_id: int, t: float, *, convention: Convention = "left", properties: bool = False
) -> Surface | None:
    """The surface of a feature at model time ``t``, or None when it does not exist then.

    Computed in SQL (``tgsis.vertices_at``, ``tgsis.triangles_at``):
    model 3 interpolates node positions linearly inside the topology period
    containing t; model 2 takes the instant the step ``convention`` chooses;
    a static surface is returned whatever t. Vertex order is the stored id
    order. With ``properties``, the class's numeric vertex or cell
    properties at t come along (``tgsis.property_at``: interpolated as the
    positions are; NaN where NULL), as :meth:`tgsis.EvolvingSurface.at` gives them.

    Raises
    ------
    NotFoundError
        No geometry ``feature_id``.
    InvalidInputError
        NaN time or an unknown convention.
    """
    t_lit, c_lit = _time_args(t, convention)
    with reraise(), conn.transaction():
        row = conn.execute(
            sql.SQL("SELECT tgsis.exists_at(%s, {}, {}), geoname, geotype FROM tgsis.geometry WHERE geoid = %s").format(
                t_lit, c_lit
            ),
            (feature_id, feature_id),
        ).fetchone()
        if row is None:
            raise NotFoundError(f"feature {feature_id} does not exist", hint="`tgsis ls` lists the features")
        if row[2] != "SURFACE":
            raise InvalidInputError(f"feature {feature_id} is a {row[2]}, not a surface")
        if not row[0]:
            return None
        with _without_jit(conn):
            ids, x, y, z = copy_out(
                conn,
                sql.SQL("SELECT vrtxid, x, y, z FROM tgsis.vertices_at({}, {}, {})").format(
                    sql.Literal(feature_id), t_lit, c_lit
                ),
                ["int8", "float8", "float8", "float8"],
            )
            # ordered by trglid here, not by the server: a sort of every triangle there (on disk
            # past work_mem) where the rows mostly come in stored order already
            tid, a, b, c = copy_out(
                conn,
                sql.SQL("SELECT trglid, vrtxid1, vrtxid2, vrtxid3 FROM tgsis.triangles_at({}, {}, {})").format(
                    sql.Literal(feature_id), t_lit, c_lit
                ),
                ["int8", "int8", "int8", "int8"],
            )
    order = rows_by_geoid(tid, tid, [feature_id])[feature_id]
    surface = _assemble(feature_id, ids, (x, y, z), (a[order], b[order], c[order]), row[1])
    if properties:
        with reraise(), conn.transaction():
            _properties_at(conn, surface, feature_id, t, convention, np.sort(ids), tid[order])
    return surface


@checked
def features_at(
    conn: Conn, feature_class: str | FeatureClass, t: float, *, convention: Convention = "left"
) -> list[int]:
    """Ids of the features of a class that exist at ``t`` (``tgsis.features_at``), ascending."""
    name = class_name(feature_class)
    with reraise(), conn.transaction():
        rows = conn.execute(
            "SELECT * FROM tgsis.features_at(%s, %s, %s)", (name, check_time(t), check_convention(convention))
        ).fetchall()
    return [int(r[0]) for r in rows]


@checked
def surfaces_at(
    conn: Conn, feature_class: str | FeatureClass, t: float, *, convention: Convention = "left"
) -> dict[int, Surface]:
    """Every feature of a SURFACE class that exists at ``t`` with its surface then, by id.

    One COPY for the vertices and one for the triangles of all features.
    """
    fc = resolve_class(conn, feature_class)
    if fc.geotype != Geotype.SURFACE:
        raise InvalidInputError(
            f"feature class {fc.name} holds {fc.geotype.value} features, not surfaces",
            hint="features_at lists the features of any class that exist at t",
        )
    t_lit, c_lit = _time_args(t, convention)
    with reraise(), conn.transaction():
        alive = features_at(conn, fc, t, convention=convention)
        names = dict(
            conn.execute("SELECT geoid, geoname FROM tgsis.geometry WHERE geoid = ANY (%s)", (alive,)).fetchall()
        )
        wanted = sql.Literal(alive)
        vg, vid, x, y, z = copy_out(
            conn,
            sql.SQL(
                "SELECT f.geoid, v.vrtxid, v.x, v.y, v.z FROM unnest({}::bigint[]) AS f(geoid), "
                "LATERAL tgsis.vertices_at(f.geoid, {}, {}) v"
            ).format(wanted, t_lit, c_lit),
            ["int8", "int8", "float8", "float8", "float8"],
        )
        tg, tid, a, b, c = copy_out(
            conn,
            sql.SQL(
                "SELECT f.geoid, c.trglid, c.vrtxid1, c.vrtxid2, c.vrtxid3 FROM unnest({}::bigint[]) AS f(geoid), "
                "LATERAL tgsis.triangles_at(f.geoid, {}, {}) c"
            ).format(wanted, t_lit, c_lit),
            ["int8", "int8", "int8", "int8", "int8"],
        )
    vertex_rows = rows_by_geoid(vg, vid, alive) if alive else {}
    triangle_rows = rows_by_geoid(tg, tid, alive) if alive else {}
    result: dict[int, Surface] = {}
    for geoid in alive:
        v, tr = vertex_rows[geoid], triangle_rows[geoid]
        result[geoid] = _assemble(geoid, vid[v], (x[v], y[v], z[v]), (a[tr], b[tr], c[tr]), names.get(geoid))
    return result


# --------------------------------------------------------------------------- whole temporal features


def _ordered_copy(
    conn: Conn, table: sql.Composable, columns: Sequence[str], types: Sequence[str], geoid: int, key: str = "geoid"
) -> list[npt.NDArray[Any]]:
    """Binary COPY of ``columns`` of one geometry's rows, ordered by those columns' leading keys."""
    names = sql.SQL(", ").join(sql.Identifier(c) for c in columns)
    return copy_out(
        conn,
        sql.SQL("SELECT {} FROM {} WHERE {} = {} ORDER BY {}").format(
            names, table, sql.Identifier(key), sql.Literal(geoid), names
        ),
        types,
    )


def _tgsis(table: str) -> sql.Composed:
    return sql.SQL("tgsis.{}").format(sql.Identifier(table))


def _instant_values(
    conn: Conn, fc: FeatureClass, geoid: int, keys: Sequence[str]
) -> dict[tuple[float, ...], list[Any]]:
    """Per-instant feature property rows of a feature, by their time key."""
    if not fc.instant_properties or fc.protable is None:
        return {}
    rows = conn.execute(
        sql.SQL("SELECT {}, {} FROM {} WHERE _geoid = %s").format(
            sql.SQL(", ").join(sql.Identifier(k) for k in keys),
            sql.SQL(", ").join(sql.Identifier(p.name) for p in fc.instant_properties),
            fc.qualified(fc.protable),
        ),
        (geoid,),
    ).fetchall()
    return {tuple(float(v) for v in r[: len(keys)]): list(r[len(keys) :]) for r in rows}


def _property_arrays(
    fc: FeatureClass, values: Mapping[tuple[float, ...], list[Any]], keys: Sequence[tuple[float, ...]]
) -> dict[str, npt.NDArray[Any]]:
    """Per-instant numeric properties as arrays over ``keys``, in their column's dtype (float64 with NaN where a
    value is NULL or has no row); properties of other types are left out."""
    result: dict[str, npt.NDArray[Any]] = {}
    for i, prop in enumerate(fc.instant_properties):
        if prop.type not in SQL_TYPES or prop.type == "boolean":
            continue
        column = [values[k][i] if k in values else None for k in keys]
        complete = all(v is not None for v in column)
        result[prop.name] = (
            np.asarray(column, dtype=numpy_dtype(SQL_TYPES[prop.type]))
            if complete
            else np.asarray([np.nan if v is None else v for v in column], dtype=np.float64)
        )
    return result


def _cell_columns(fc: FeatureClass) -> tuple[list[str], list[str]]:
    return [p.name for p in fc.cell_properties], [SQL_TYPES[p.type] for p in fc.cell_properties]


@checked
def fetch_series(conn: Conn, feature_class: str | FeatureClass, feature_id: int) -> SurfaceSeries:
    """A model-2 feature as a :class:`~tgsis.temporal.SurfaceSeries`, with its cell and per-instant properties.

    Per-instant numeric properties come back as float64 or int64 arrays
    (NULLs as NaN); properties of other types are not included.

    Raises
    ------
    NotFoundError, InvalidInputError, InvalidGeometryError
    """
    fc = _temporal_class(conn, feature_class, "INSTANTS")
    names, types = _cell_columns(fc)
    with reraise(), conn.transaction():
        row = conn.execute(
            "SELECT geoname, alive, colorred, colorgreen, colorblue FROM tgsis.geometry "
            "WHERE geoid = %s AND timemodel = 'INSTANTS'",
            (feature_id,),
        ).fetchone()
        if row is None:
            raise NotFoundError(f"feature {feature_id} of class {fc.name} does not exist")
        (times,) = _ordered_copy(conn, _tgsis("times"), ["times"], ["float8"], feature_id)
        vt, vid, x, y, z = _ordered_copy(
            conn,
            _tgsis("times_vrtx"),
            ["times", "vrtxid", "x", "y", "z"],
            ["float8", "int8", "float8", "float8", "float8"],
            feature_id,
        )
        tt, tid, a, b, c = _ordered_copy(
            conn,
            _tgsis("times_trgl"),
            ["times", "trglid", "vrtxid1", "vrtxid2", "vrtxid3"],
            ["float8", "int8", "int8", "int8", "int8"],
            feature_id,
        )
        props = (
            _ordered_copy(
                conn,
                fc.qualified(fc.cellprotable),
                ["_times", "_idx", *names],
                ["float8", "int8", *types],
                feature_id,
                "_geoid",
            )
            if names
            else []
        )
        values = _instant_values(conn, fc, feature_id, ["_times"])
    surfaces = []
    for t in times.tolist():
        v = np.flatnonzero(vt == t)
        tr = np.flatnonzero(tt == t)
        surface = _assemble(feature_id, vid[v], (x[v], y[v], z[v]), (a[tr], b[tr], c[tr]), row[0])
        if names:
            p = np.flatnonzero(props[0] == t)
            target = surface.vertex_properties if fc.alignment == "VERTEX" else surface.cell_properties
            target.update({name: props[2 + i][p] for i, name in enumerate(names)})
        surfaces.append(surface)
    return SurfaceSeries(
        times,
        surfaces,
        properties=_property_arrays(fc, values, [(t,) for t in times.tolist()]),
        alive=bool(row[1]),
        name=row[0],
        color=None if row[2] is None else row[2:5],
    )


@checked
def fetch_evolving(conn: Conn, feature_class: str | FeatureClass, feature_id: int) -> EvolvingSurface:
    """A model-3 feature as an :class:`~tgsis.temporal.EvolvingSurface`, with its cell and per-instant properties.

    Node and triangle ids become 0-based positions in each period (in id
    order). Per-instant numeric properties come back as float64 or int64
    arrays (NULLs as NaN).

    Raises
    ------
    NotFoundError, InvalidInputError
    InvalidGeometryError
        Rows edited with plain SQL that do not form periods (see
        ``tgsis.check_geometry``).
    """
    fc = _temporal_class(conn, feature_class, "EVOLVING")
    names, types = _cell_columns(fc)
    with reraise(), conn.transaction():
        row = conn.execute(
            "SELECT geoname, alive, colorred, colorgreen, colorblue FROM tgsis.geometry "
            "WHERE geoid = %s AND timemodel = 'EVOLVING'",
            (feature_id,),
        ).fetchone()
        if row is None:
            raise NotFoundError(f"feature {feature_id} of class {fc.name} does not exist")
        tm, tt = _ordered_copy(conn, _tgsis("timet"), ["timem", "timet"], ["float8", "float8"], feature_id)
        cm, _, a, b, c = _ordered_copy(
            conn,
            _tgsis("d4dtrgl"),
            ["timem", "trglid", "nodeid1", "nodeid2", "nodeid3"],
            ["float8", "int8", "int8", "int8", "int8"],
            feature_id,
        )
        vm, vt, nid, x, y, z = _ordered_copy(
            conn,
            _tgsis("d4dvrtx"),
            ["timem", "timet", "nodeid", "x", "y", "z"],
            ["float8", "float8", "int8", "float8", "float8", "float8"],
            feature_id,
        )
        props = (
            _ordered_copy(
                conn,
                fc.qualified(fc.cellprotable),
                ["_timem", "_timet", "_idx", *names],
                ["float8", "float8", "int8", *types],
                feature_id,
                "_geoid",
            )
            if names
            else []
        )
        values = _instant_values(conn, fc, feature_id, ["_timem", "_timet"])
    periods = []
    for start in np.unique(tm).tolist():
        times = tt[tm == start]
        rows = np.flatnonzero(vm == start)
        nodes = np.unique(nid[rows])
        if len(rows) != len(times) * len(nodes):
            raise InvalidGeometryError(
                f"feature {feature_id}: the period starting at {start!r} lacks node positions",
                hint=f"SELECT * FROM tgsis.check_geometry({feature_id})",
            )
        xyz = np.stack([x[rows], y[rows], z[rows]], axis=1).reshape(len(times), len(nodes), 3)
        cells = np.flatnonzero(cm == start)
        triangles = np.stack([local_positions(nodes, k[cells], "triangles", feature_id) for k in (a, b, c)], axis=1)
        per_cell: dict[str, npt.NDArray[Any]] = {}
        if names:
            p = np.flatnonzero(props[0] == start)
            per_cell = {name: props[3 + i][p].reshape(len(times), -1) for i, name in enumerate(names)}
        keys = [(start, t) for t in times.tolist()]
        periods.append(
            TopologyPeriod(
                times,
                triangles,
                xyz,
                vertex_properties=per_cell if fc.alignment == "VERTEX" else None,
                cell_properties=per_cell if fc.alignment == "CELL" else None,
                properties=_property_arrays(fc, values, keys),
            )
        )
    return EvolvingSurface(periods, alive=bool(row[1]), name=row[0], color=None if row[2] is None else row[2:5])


# --------------------------------------------------------------------------- time series export


@checked
def lifespan(conn: Conn, feature_id: int) -> tuple[float, float, bool] | None:
    """First and last instant of a temporal feature, and whether it is alive after the last one.

    None for a static feature (it exists at every time).

    Raises
    ------
    NotFoundError
        No geometry ``feature_id``.
    """
    with reraise(), conn.transaction():
        row = conn.execute(
            "SELECT g.timemodel, g.alive, i.first, i.last FROM tgsis.geometry g, "
            "LATERAL (SELECT min(t) AS first, max(t) AS last FROM tgsis.geometry_instants(g.geoid)) i "
            "WHERE g.geoid = %s",
            (feature_id,),
        ).fetchone()
    if row is None:
        raise NotFoundError(f"feature {feature_id} does not exist", hint="`tgsis ls` lists the features")
    if row[0] == "STATIC" or row[2] is None:
        return None
    return float(row[2]), float(row[3]), bool(row[1])


@checked
def frames_at(
    conn: Conn,
    feature_id: int,
    times: npt.ArrayLike,
    *,
    convention: Convention = "left",
    progress: Callable[[int, int], None] | None = None,
) -> list[SurfaceFrame]:
    """The surface of a feature at each of ``times`` by the SQL snapshot (:func:`get_at`), all from one snapshot.

    ``progress(done, total)``, when given, is called after each frame.

    Returns
    -------
    list of (float, Surface or None)
        None where the feature does not exist; surfaces without properties.

    Raises
    ------
    NotFoundError, InvalidInputError
        As :func:`get_at`.
    """
    check_convention(convention)
    samples = [check_time(t) for t in np.atleast_1d(np.asarray(times, dtype=np.float64)).tolist()]
    with reraise(), read_only_snapshot(conn):
        frames = []
        for t in samples:
            frames.append((t, get_at(conn, feature_id, t, convention=convention)))
            if progress is not None:
                progress(len(frames), len(samples))
        return frames


@checked
def export_series(
    conn: Conn,
    feature_id: int,
    path: PathLike,
    *,
    start: float | None = None,
    end: float | None = None,
    steps: int | None = None,
    convention: Convention = "left",
    encoding: Encoding = "binary",
    progress: Callable[[int, int], None] | None = None,
) -> WrittenSeries:
    """Write a feature's surface over time as a ParaView ``.pvd`` time series, one ``.vtu`` per time.

    Each frame is the SQL snapshot (:func:`get_at`, the same float operations
    as :meth:`tgsis.EvolvingSurface.at`); a time where the feature does not
    exist is written as an empty grid (see :func:`tgsis.formats.pvd.write_pvd`).

    Parameters
    ----------
    conn : psycopg.Connection
    feature_id : int
        A surface feature: temporal (model 2 or 3), or static (the same
        surface at every time).
    path : str or path-like
        The ``.pvd`` file; frames go to ``<stem>/<stem>_000000.vtu``, ...
        beside it.
    start, end, steps : optional
        ``steps`` times evenly spaced from ``start`` to ``end``, both included
        (:func:`tgsis.temporal.even_times`). All three, or none: then the
        feature's own instants (:func:`instants`).
    convention : {"left", "right"}
        Step convention of a model-2 feature.
    encoding : {"binary", "appended"}
        Of the ``.vtu`` files.
    progress : callable, optional
        ``progress(done, total)``, called after each frame is computed.

    Returns
    -------
    WrittenSeries
        The files and the frames (surfaces without properties).

    Raises
    ------
    NotFoundError
        No feature ``feature_id``.
    InvalidInputError
        Some but not all of start, end, steps; bad values of them; no times
        given for a static feature; a feature that is not a surface.
    FileFormatError
        The files cannot be written.
    """
    given = [v is not None for v in (start, end, steps)]
    if any(given) and not all(given):
        raise InvalidInputError("give start, end and steps together, or none of them (the feature's own instants)")
    if start is not None and end is not None and steps is not None:
        times = even_times(start, end, steps)
    else:
        own = [t for t, _ in instants(conn, feature_id)]
        if not own:
            lifespan(conn, feature_id)  # NotFoundError for an unknown feature
            raise InvalidInputError(
                f"feature {feature_id} is static: it has no instants of its own to sample",
                hint="give start, end and steps",
            )
        times = np.asarray(own, dtype=np.float64)
    return write_frames_pvd(
        frames_at(conn, feature_id, times, convention=convention, progress=progress), path, encoding=encoding
    )


# --------------------------------------------------------------------------- temporal questions


@checked
def property_periods(
    conn: Conn,
    feature_class: str | FeatureClass,
    feature_id: int,
    prop: str,
    op: str,
    value: float,
    *,
    convention: Convention = "left",
) -> list[Period]:
    """The maximal periods over which a per-instant property of a feature satisfies ``prop op value``.

    Computed in SQL by ``tgsis.property_periods``: model 2 (INSTANTS) as a
    step function under ``convention`` (left-closed pieces ``[t_i, t_i+1)``,
    the last instant ``[t_k, t_k]``; right-closed ``(t_i-1, t_i]``, the first
    ``[t_0, t_0]``), model 3 (EVOLVING) linear between geometry instants with
    crossing times by interpolation (closed at a crossing for ``<=``, ``>=``,
    ``=``, open for ``<``, ``>``, ``<>``). An alive feature keeps its last
    value: the last period may end at ``inf``. NULL or NaN values never
    satisfy the condition. When the property first satisfies it is
    ``periods[0].start`` (right after it if ``not periods[0].start_closed``).

    Parameters
    ----------
    conn : psycopg.Connection
    feature_class : str or FeatureClass
        An INSTANTS or EVOLVING class.
    feature_id : int
        A feature of that class.
    prop : str
        A numeric per-instant property of the class (column of ``<class>_pros``).
    op : {"<", "<=", ">", ">=", "=", "<>"}
    value : float
        A number (infinities allowed, not NaN).
    convention : {"left", "right"}
        Step convention of model 2; not used by model 3.

    Returns
    -------
    list of Period
        Disjoint, ascending, not adjacent; empty when the condition never holds.

    Raises
    ------
    NotFoundError
        Unknown class, or the feature is not one of it.
    InvalidPropertyError
        Unknown or non-numeric per-instant property.
    InvalidInputError
        Static class, unknown operator or convention, NaN value.
    """
    with reraise(), conn.transaction():
        rows = conn.execute(
            "SELECT coalesce(lower(period), '-Infinity'), coalesce(upper(period), 'Infinity'), lower_inc(period), "
            "upper_inc(period) FROM tgsis.property_periods(%s, %s, %s, %s, %s, %s)",
            (class_name(feature_class), feature_id, prop, op, float(value), check_convention(convention)),
        ).fetchall()
    return [Period(float(r[0]), float(r[1]), bool(r[2]), bool(r[3])) for r in rows]


@checked
def first_times(
    conn: Conn,
    feature_class: str | FeatureClass,
    feature_id: int,
    prop: str,
    op: str,
    value: float,
    *,
    convention: Convention = "left",
) -> tuple[npt.NDArray[np.int64], npt.NDArray[np.float64]]:
    """For each vertex/node or cell of a feature, the first time its property satisfies ``prop op value``.

    Computed in SQL by ``tgsis.first_time`` and downloaded with one binary
    COPY into two arrays (for a million cells a dict would cost more than
    the query). The first time is the infimum of the times at which the
    condition holds (it may hold only right after it): model 2 stepwise,
    left-closed the instant ``t_i`` itself, right-closed the instant before it
    ``t_i-1`` (the value of ``t_i`` holds from right after ``t_i-1``), ``t_0``
    for the first instant; model 3 linear between the geometry instants of
    the topology period the node or triangle belongs to.

    Parameters
    ----------
    conn, feature_class, feature_id, op, value, convention
        As :func:`property_periods`.
    prop : str
        A numeric vertex or cell property of the class (column of ``<class>_cellpros``).

    Returns
    -------
    idx : (n,) ndarray of int64
        ``_idx`` (vertex/node or triangle id) of the n cells that ever satisfy
        the condition, ascending; the others are absent.
    t : (n,) ndarray of float64
        Their first times.

    Raises
    ------
    NotFoundError, InvalidPropertyError, InvalidInputError
        As :func:`property_periods`.
    """
    query = sql.SQL("SELECT idx, t FROM tgsis.first_time({}, {}, {}, {}, {}, {})").format(
        sql.Literal(class_name(feature_class)),
        sql.Literal(int(feature_id)),
        sql.Literal(prop),
        sql.Literal(op),
        sql.Literal(float(value)),
        sql.Literal(check_convention(convention)),
    )
    with reraise(), conn.transaction():
        idx, t = copy_out(conn, query, ["int8", "float8"])
    return idx, t


@checked
def class_property_periods(
    conn: Conn, feature_class: str | FeatureClass, prop: str, op: str, value: float, *, convention: Convention = "left"
) -> dict[int, list[Period]]:
    """For every feature of a class, the periods over which a per-instant property satisfies ``prop op value``.

    One query (``tgsis.class_property_periods``): :func:`property_periods` for
    each feature of the class. Features for which the condition never holds
    are left out; ``periods[0].start`` is when the property first satisfies
    it.

    Parameters
    ----------
    conn, feature_class, prop, op, value, convention
        As :func:`property_periods`.

    Returns
    -------
    dict of int to list of Period
        By feature id, ascending; each list ascending.
    """
    with reraise(), conn.transaction():
        rows = conn.execute(
            "SELECT geoid, coalesce(lower(period), '-Infinity'), coalesce(upper(period), 'Infinity'), lower_inc(period), "
            "upper_inc(period) FROM tgsis.class_property_periods(%s, %s, %s, %s, %s)",
            (class_name(feature_class), prop, op, float(value), check_convention(convention)),
        ).fetchall()
    found: dict[int, list[Period]] = {}
    for r in rows:
        found.setdefault(int(r[0]), []).append(Period(float(r[1]), float(r[2]), bool(r[3]), bool(r[4])))
    return found


# --------------------------------------------------------------------------- models 2 and 3 in the browser view


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
    """Models 2 and 3's drawing (:class:`tgsis.datamodels.DrawFunction`): the SQL snapshot at t (:func:`get_at`).

    None outside the feature's life; the class's numeric properties at t come along to colour by.
    """
    if t is None:
        raise InvalidInputError(f"feature {feature_id} (class {fc.name}) is drawn at a time t")
    surface = get_at(conn, feature_id, t, properties=True)
    return None if surface is None else drawable(surface)


def _life(conn: Conn, feature_id: int) -> tuple[float, float] | None:
    """Models 2 and 3's span in the view's time slider: the first and last instant (:func:`lifespan`)."""
    span = lifespan(conn, feature_id)
    return None if span is None else (span[0], span[1])


# models 2 and 3 in the registry of data models: insert_feature, fetch_object and the browser view come here
datamodels.register_storage("INSTANTS", insert=insert_series, fetch=fetch_series, draw=_draw_at, life=_life)
datamodels.register_storage("EVOLVING", insert=insert_evolving, fetch=fetch_evolving, draw=_draw_at, life=_life)
