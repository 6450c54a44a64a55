"""Model 3 in the database: continuously evolving surfaces (``time_model="EVOLVING"``), in topology periods.

A feature of an EVOLVING class is one ``tgsis.geometry`` row with its
topology instants in ``tgsis.timem``, the geometry instants of each period
in ``tgsis.timet``, its nodes in ``tgsis.node``, its triangles in
``tgsis.d4dtrgl``, the node positions at each geometry instant in
``tgsis.d4dvrtx``, and the class's tables with ``_timem, _timet``. Uploads
are one transaction with one binary COPY per table, into the versioned
storage of the session's working revision when the tables are versioned;
every write of more than one period is checked for continuity by the
database (``tgsis.check_period_continuity``). The questions over time both
temporal models answer (the surface at t, the instants, exports) are in
:mod:`tgsis.db.temporal`.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np
import numpy.typing as npt
from psycopg import sql

from tgsis import datamodels
from tgsis._series import check_time
from tgsis.arguments import checked
from tgsis.db._chunk_transfer import chunked_tables, instant_layout, instant_rows, write_instants
from tgsis.db._continuity import check_continuity, checked_tolerance
from tgsis.db._temporal_common import (
    Conn,
    cell_columns,
    draw_snapshot,
    get_at,
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
from tgsis.db._transfer import (
    Storage,
    class_property_arrays,
    concat,
    consistent_read,
    insert_feature_row,
    local_positions,
)
from tgsis.db.classes import FeatureClass
from tgsis.db.copy import SQL_TYPES
from tgsis.drawing import Drawable
from tgsis.errors import InvalidGeometryError, InvalidInputError, NotFoundError, reraise
from tgsis.temporal import EvolvingSurface, TopologyPeriod
from tgsis.temporal import sudden_change as sudden

__all__ = ["insert_evolving", "append_period", "delete_period", "fetch_evolving"]

log = logging.getLogger("tgsis.db.temporal")  # the logger of these functions before db/temporal.py was split


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
    triangle_columns = {f"nodeid{j + 1}": triangles[:, j] for j in range(3)}
    # a table stored in chunks takes the periods' chunks encoded here (one COPY), unless it holds chunks of these
    # instants already (a period deleted and appended again in one revision: tgsis.insert_chunk_rows then)
    write_instants(
        conn,
        "d4dtrgl",
        geoid,
        [(s,) for s in starts],
        m,
        triangle_columns,
        storage,
        triangle_offsets.tolist(),
        keys=["timem"],
        idcolumn="trglid",
    )
    # per period and geometry instant, every node: g_i * n_i rows
    xyz = concat([p.positions.reshape(-1, 3) for p in periods])
    vertex_columns = {"x": xyz[:, 0], "y": xyz[:, 1], "z": xyz[:, 2]}
    # chunked: one object per geometry instant (timem, timet), its nodes' ids the period's run, so a node keeps
    # its chunk and slot at every instant of its period (the snapshot interpolates on aligned arrays)
    instants = [(p.start, float(t)) for p in periods for t in p.times.tolist()]
    write_instants(
        conn,
        "d4dvrtx",
        geoid,
        instants,
        [p.n_nodes for p in periods for _ in p.times],
        vertex_columns,
        storage,
        [off for p, off in zip(periods, node_offsets.tolist()) for _ in p.times],
        keys=["timem", "timet"],
        idcolumn="nodeid",
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
    fc = temporal_class(conn, feature_class, "EVOLVING")
    tolerance = checked_tolerance(tolerance)
    if sudden_change is not None:
        surface = surface.with_sudden_changes(sudden_change)
    cell_values = _period_columns(fc, surface, drop_extra_properties)
    periods = surface.periods
    n = [p.n_nodes for p in periods]
    m = [p.n_triangles for p in periods]
    instant_rows = [row for p in periods for row in instant_property_rows(fc, dict(p.properties), len(p.times))]
    with reraise(), conn.transaction():
        storage = Storage.of(conn, fc)
        storage.check("tgsis", "geometry")  # not "in" a version while the feature tables are plain
        geoid = new_temporal_geometry(
            conn,
            fc,
            name if name is not None else surface.name,
            point_bounds(concat([p.positions.reshape(-1, 3) for p in periods])),
            sum(n),
            sum(m),
            surface.alive,
            surface.color,
        )
        _copy_periods(conn, storage, fc, geoid, periods, cell_values, 0, 0)
        keys = [(p.start, float(t)) for p in periods for t in p.times.tolist()]
        insert_instant_properties(conn, fc, geoid, keys, instant_rows, ["_timem", "_timet"])
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
    fc = temporal_class(conn, feature_class, "EVOLVING")
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
            binary=True,  # the last instant bit for bit, whatever the session's extra_float_digits
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
        instant_rows = instant_property_rows(fc, dict(period.properties), len(period.times))
        _copy_periods(conn, storage, fc, feature_id, [period], cell_values, int(row[1]), int(row[2]))
        insert_instant_properties(
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


def _period_rows(
    conn: Conn,
    table: str,
    geoid: int,
    chunked: frozenset[str],
    keys: Sequence[str],
    columns: Sequence[str],
    types: Sequence[str],
) -> list[npt.NDArray[Any]]:
    """Every row of ``tgsis.<table>`` (``d4dtrgl``, ``d4dvrtx``) of one feature, ``[*keys, id, *columns]`` (n,) each
    ordered by (keys, id): from its chunks, decoded here (:func:`~tgsis.db._chunk_transfer.instant_rows`, as
    model 2's ``fetch_series`` reads them), when the table is stored in chunks and the role may read them; else
    its rows through the face, packed by the server (:func:`ordered_copy`).

    ``keys`` are the table's instant keys (``timem``; ``timem, timet``), ``columns`` the local id then the values.
    """
    layout = instant_layout(conn, table, chunked)
    if layout is None:
        return ordered_copy(
            conn,
            tgsis_table(table),
            [*keys, *columns],
            [*(["float8"] * len(keys)), *types],
            geoid,
            keys=len(keys) + 1,
        )
    rows = instant_rows(conn, layout, [geoid])
    # (geoid, *instant keys) ascending: no time is NaN (tgsis.check_time), and -0.0 and 0.0 are one key
    order = sorted(rows, key=lambda k: k[1:])
    counts = [len(rows[k].ids) for k in order]
    names = columns[1:]
    return [
        *(np.repeat(np.asarray([k[1 + i] for k in order], dtype=np.float64), counts) for i in range(len(keys))),
        np.concatenate([np.empty(0, dtype=np.int64), *(rows[k].ids for k in order)]),
        *(
            np.concatenate([np.empty(0, dtype=layout.columns.dtype(c)), *(rows[k].columns[c] for k in order)])
            for c in names
        ),
    ]


def _period_nodes(ids: npt.NDArray[np.int64], instants: int) -> npt.NDArray[np.int64] | None:
    """The node ids of a period whose position rows ``ids`` (ordered by geometry instant, then id) hold every node
    at each of its ``instants`` geometry instants, ascending; None when they do not.

    Each instant's block must equal the first one, whose ids must ascend strictly: no sort or hash of every row.
    (The test before, ``np.unique(ids)`` and ``len(ids) == instants * len(unique)``, also let through rows at an
    instant ``timet`` does not list when their count came out right, and read the positions misaligned.)
    """
    per = len(ids) // instants if instants else 0
    if len(ids) != instants * per:
        return None
    nodes = ids[:per]
    if per and not (bool(np.all(nodes[1:] > nodes[:-1])) and bool(np.all(ids.reshape(instants, per) == nodes))):
        return None
    return nodes


@checked
def fetch_evolving(conn: Conn, feature_class: str | FeatureClass, feature_id: int) -> EvolvingSurface:
    """A model-3 feature as an :class:`~tgsis.temporal.EvolvingSurface`, with its cell and per-instant properties.

    Node and triangle ids become 0-based positions in each period (in id
    order). With ``d4dvrtx`` and ``d4dtrgl`` stored in chunks, their chunks
    are read and decoded here (docs/storage.md, "Snapshots at t"), the same
    bits as their rows. Per-instant numeric properties come back as float64 or int64
    arrays (NULLs as NaN).

    Raises
    ------
    NotFoundError, InvalidInputError
    InvalidGeometryError
        Rows edited with plain SQL that do not form periods (see
        ``tgsis.check_geometry``).
    """
    fc = temporal_class(conn, feature_class, "EVOLVING")
    names, types = cell_columns(fc)

    def read() -> tuple[Any, ...]:
        """Every table's rows of the feature, of one state (:func:`consistent_read`)."""
        row = conn.execute(
            "SELECT geoname, alive, colorred, colorgreen, colorblue FROM tgsis.geometry "
            "WHERE geoid = %s AND timemodel = 'EVOLVING'",
            (feature_id,),
            binary=True,  # the colour bit for bit, whatever the session's extra_float_digits
        ).fetchone()
        if row is None:
            raise NotFoundError(f"feature {feature_id} of class {fc.name} does not exist")
        tm, tt = ordered_copy(conn, tgsis_table("timet"), ["timem", "timet"], ["float8", "float8"], feature_id)
        chunked = chunked_tables(conn)
        cm, _, a, b, c = _period_rows(
            conn,
            "d4dtrgl",
            feature_id,
            chunked,
            ["timem"],
            ["trglid", "nodeid1", "nodeid2", "nodeid3"],
            ["int8", "int8", "int8", "int8"],
        )
        vm, vt, nid, x, y, z = _period_rows(
            conn,
            "d4dvrtx",
            feature_id,
            chunked,
            ["timem", "timet"],
            ["nodeid", "x", "y", "z"],
            ["int8", "float8", "float8", "float8"],
        )
        props = (
            ordered_copy(
                conn,
                fc.qualified(fc.cellprotable),
                ["_timem", "_timet", "_idx", *names],
                ["float8", "float8", "int8", *types],
                feature_id,
                "_geoid",
                keys=3,
            )
            if names
            else []
        )
        values = instant_values(conn, fc, feature_id, ["_timem", "_timet"])
        return row, tm, tt, cm, a, b, c, vm, vt, nid, x, y, z, props, values

    with reraise():
        row, tm, tt, cm, a, b, c, vm, vt, nid, x, y, z, props, values = consistent_read(conn, "fetch_evolving", read)
    periods = []
    for start in np.unique(tm).tolist():
        times = tt[tm == start]
        rows = np.flatnonzero(vm == start)
        nodes = _period_nodes(nid[rows], len(times))
        if nodes is None:
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
                properties=property_arrays(fc, values, keys),
            )
        )
    return EvolvingSurface(periods, alive=bool(row[1]), name=row[0], color=None if row[2] is None else row[2:5])


# --------------------------------------------------------------------------- model 3 in the browser view


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
    """Model 3's drawing (:class:`tgsis.datamodels.DrawFunction`): the SQL snapshot at t, None outside its life."""
    return draw_snapshot(conn, fc, feature_id, t)


def _life(conn: Conn, feature_id: int) -> tuple[float, float] | None:
    """Model 3's span in the view's time slider: its first and last instant."""
    return slider_span(conn, feature_id)


# model 3 in the registry of data models: insert_feature, fetch_object and the browser view come here
datamodels.register_storage("EVOLVING", insert=insert_evolving, fetch=fetch_evolving, draw=_draw_at, life=_life)
