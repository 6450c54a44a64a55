"""What the database modules of models 2 and 3 share (:mod:`tgsis.db.instants`, :mod:`tgsis.db.evolving`).

The class check, the new geometry row, per-instant feature properties, the
ordered binary COPY of a feature's rows, the assembly of a surface from its
rows, and the surface of a feature at t (:func:`get_at`: model 3's
``append_period`` starts a sudden change from it; :mod:`tgsis.db.temporal`,
which exports it, samples it). Moved here unchanged when ``db/temporal.py``
was split by model.
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping, Sequence
from contextlib import contextmanager
from typing import Any

import numpy as np
import numpy.typing as npt
import psycopg
from psycopg import sql

from tgsis._series import check_time
from tgsis.arguments import checked, no_nul
from tgsis.db._chunk_transfer import chunked_tables, instant_layout, instant_rows
from tgsis.db._transfer import (
    SEND_FUNCTIONS,
    consistent_read,
    copy_out,
    local_positions,
    packed_out,
    resolve_class,
    rows_by_geoid,
)
from tgsis.db.classes import FeatureClass, class_of_feature
from tgsis.db.copy import SQL_TYPES, numpy_dtype, wire_shape
from tgsis.drawing import Drawable, drawable
from tgsis.errors import InvalidInputError, InvalidPropertyError, NotFoundError, reraise
from tgsis.mesh import Surface
from tgsis.temporal import Convention, check_convention

Conn = psycopg.Connection[Any]


def temporal_class(conn: Conn, feature_class: str | FeatureClass, model: str) -> FeatureClass:
    fc = resolve_class(conn, feature_class)
    if fc.time_model != model:
        raise InvalidInputError(
            f"feature class {fc.name} has time model {fc.time_model}, not {model}",
            hint="SurfaceSeries go to INSTANTS classes, EvolvingSurface to EVOLVING classes",
        )
    return fc


def point_bounds(points: npt.NDArray[np.float64]) -> list[float] | None:
    """[xmin, ymin, zmin, xmax, ymax, zmax] of (..., 3) points, None when there are none."""
    flat = points.reshape(-1, 3)
    return None if len(flat) == 0 else [*flat.min(axis=0).tolist(), *flat.max(axis=0).tolist()]


def new_temporal_geometry(
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


def instant_property_rows(fc: FeatureClass, values: Mapping[str, npt.NDArray[Any]], count: int) -> list[list[Any]]:
    """Per-instant feature property values as ``count`` rows in the class's column order (missing: NULL)."""
    known = [p.name for p in fc.instant_properties]
    unknown = sorted(set(values) - set(known))
    if unknown:
        raise InvalidPropertyError(
            f"feature class {fc.name} has no per-instant properties {unknown}",
            hint=f"its per-instant properties: {known or 'none'}",
        )
    return [[values[name][i].item() if name in values else None for name in known] for i in range(count)]


def insert_instant_properties(
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


def ordered_copy(
    conn: Conn,
    table: sql.Composable,
    columns: Sequence[str],
    types: Sequence[str],
    geoid: int,
    key: str = "geoid",
    *,
    keys: int = 0,
) -> list[npt.NDArray[Any]]:
    """The ``columns`` of one geometry's rows, ordered by those columns' leading keys.

    With ``keys`` = k > 0, the first k columns are the rows' key (unique in
    the geometry), the k-th a local id (``int8``): the rows come packed by
    the server in groups of ids (:func:`~tgsis.db._transfer.packed_out`, not
    a COPY message per row) and are ordered here. Otherwise (or when a
    column has no fixed-width send form) a binary COPY ordered by the server.
    """
    if keys and types[keys - 1] == "int8" and all(wire_shape(w)[0] in SEND_FUNCTIONS for w in types):
        values = packed_out(
            conn,
            sql.SQL("SELECT {} FROM {} WHERE {} = {}").format(
                sql.SQL(", ").join(sql.Identifier(c) for c in columns), table, sql.Identifier(key), sql.Literal(geoid)
            ),
            list(zip(columns, types)),
            [columns[keys - 1]],
            columns[: keys - 1],
        )
        order = np.lexsort(values[keys - 1 :: -1])
        return [v[order] for v in values]
    names = sql.SQL(", ").join(sql.Identifier(c) for c in columns)
    return copy_out(
        conn,
        sql.SQL("SELECT {} FROM {} WHERE {} = {} ORDER BY {}").format(
            names, table, sql.Identifier(key), sql.Literal(geoid), names
        ),
        types,
    )


def tgsis_table(table: str) -> sql.Composed:
    return sql.SQL("tgsis.{}").format(sql.Identifier(table))


def instant_values(conn: Conn, fc: FeatureClass, geoid: int, keys: Sequence[str]) -> dict[tuple[float, ...], list[Any]]:
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
        # binary: the time keys (matched against the instants' bits) and the float values exact, whatever the
        # session's extra_float_digits (below 1, text rounds them: every key missed, its values silently NULL)
        binary=True,
    ).fetchall()
    return {tuple(float(v) for v in r[: len(keys)]): list(r[len(keys) :]) for r in rows}


def property_arrays(
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


def cell_columns(fc: FeatureClass) -> tuple[list[str], list[str]]:
    return [p.name for p in fc.cell_properties], [SQL_TYPES[p.type] for p in fc.cell_properties]


def assemble_surface(
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


def instant_snapshot(
    conn: Conn,
    table: str,
    geoids: Sequence[int],
    t: sql.Composable,
    convention: sql.Composable,
    columns: Sequence[str],
) -> list[npt.NDArray[Any]] | None:
    """Model 2's rows of ``tgsis.<table>`` at t of features ``geoids`` from the time table's chunks, decoded here.

    The instant of each feature is chosen by the server in the same query (``tgsis.instant_at``, as
    ``tgsis.vertices_at`` chooses it): never passed as text. ``columns``: the local id, then arrays.

    Returns
    -------
    list of ndarray or None
        ``[geoid, id, *columns]`` (n,) each, ordered by (geoid, id); None while the table is stored as rows
        (or the role may read the face only): the caller reads the face.
    """
    layout = instant_layout(conn, table, chunked_tables(conn))
    if layout is None:
        return None
    rows = instant_rows(
        conn, layout, geoids, sql.SQL("c.times = tgsis.instant_at(f.geoid, {}, {})").format(t, convention)
    )
    keys = sorted(rows)
    counts = [len(rows[k].ids) for k in keys]
    names = columns[1:]
    return [
        np.repeat(np.asarray([k[0] for k in keys], dtype=np.int64), counts),
        np.concatenate([np.empty(0, dtype=np.int64), *(rows[k].ids for k in keys)]),
        *(
            np.concatenate([np.empty(0, dtype=layout.columns.dtype(c)), *(rows[k].columns[c] for k in keys)])
            for c in names
        ),
    ]


def _stacked(
    objects: Sequence[tuple[int, npt.NDArray[np.int64], Sequence[npt.NDArray[Any]]]], dtypes: Sequence[Any]
) -> list[npt.NDArray[Any]]:
    """``[geoid, id, *columns]`` (n,) each from per-object ``(geoid, ids, columns)``, in the given object order."""
    counts = [len(ids) for _, ids, _ in objects]
    return [
        np.repeat(np.asarray([g for g, _, _ in objects], dtype=np.int64), counts),
        np.concatenate([np.empty(0, dtype=np.int64), *(ids for _, ids, _ in objects)]),
        *(
            np.concatenate([np.empty(0, dtype=dtype), *(columns[i] for _, _, columns in objects)])
            for i, dtype in enumerate(dtypes)
        ),
    ]


def evolving_vertices(conn: Conn, geoids: Sequence[int], t: sql.Composable) -> list[npt.NDArray[Any]] | None:
    """Model 3's vertices at t of features ``geoids`` from ``d4dvrtx``'s chunks, interpolated here as ``tgsis.vertices_at`` does.

    The frame (``tgsis.evolving_frame``: period, bracketing geometry instants t0 <= t <= t1, weight w) comes
    in binary; the chunks of the two instants, chosen by the server in the same query from the same frame,
    hold a node at the same slot (docs/storage.md, "Snapshots at t"), so ``x0 + w * (x1 - x0)`` is numpy on
    aligned arrays: the same IEEE operations in the same order as the SQL, the same bits. Nodes present at
    one of the two instants only (a psql delete) are left out, as the SQL's join leaves them out; at an
    instant exactly (t0 = t1) the stored positions.

    Returns
    -------
    list of ndarray or None
        ``[geoid, vrtxid, x, y, z]`` (n,) each, ordered by (geoid, vrtxid); None while ``d4dvrtx`` is stored as
        rows (or the role may read the face only): the caller reads the face.
    """
    layout = instant_layout(conn, "d4dvrtx", chunked_tables(conn))
    if layout is None:
        return None
    wanted = list(dict.fromkeys(int(g) for g in geoids))
    with conn.cursor(binary=True) as cursor:  # the frame's doubles by their bits
        frames = cursor.execute(
            sql.SQL(
                "SELECT f.geoid, fr.timem, fr.t0, fr.t1, fr.w FROM unnest({}::int8[]) AS f(geoid) "
                "CROSS JOIN LATERAL tgsis.evolving_frame(f.geoid, {}) fr ORDER BY f.geoid"
            ).format(sql.Literal(wanted), t)
        ).fetchall()
    rows = instant_rows(
        conn,
        layout,
        [int(f[0]) for f in frames],
        sql.SQL(
            "(c.timem, c.timet) IN (SELECT fr.timem, u.t FROM tgsis.evolving_frame(f.geoid, {}) fr, "
            "unnest(ARRAY[fr.t0, fr.t1]) AS u(t))"
        ).format(t),
    )
    columns = ("x", "y", "z")
    objects = []
    for geoid, timem, t0, t1, w in frames:
        first = rows.get((int(geoid), float(timem), float(t0)))
        if first is None:  # no node at that instant
            continue
        if not t0 < t1:  # at a geometry instant: the stored positions
            objects.append((int(geoid), first.ids, [first.columns[c] for c in columns]))
            continue
        second = rows.get((int(geoid), float(timem), float(t1)))
        if second is None:
            continue
        ids: npt.NDArray[np.int64] = first.ids
        i0: Any = slice(None)  # aligned slot for slot: every node at both instants
        i1: Any = slice(None)
        if not np.array_equal(first.ids, second.ids):  # the nodes at both (the SQL's join)
            ids, i0, i1 = np.intersect1d(first.ids, second.ids, assume_unique=True, return_indices=True)
        weight = np.float64(w)
        objects.append(
            (
                int(geoid),
                ids,
                [first.columns[c][i0] + weight * (second.columns[c][i1] - first.columns[c][i0]) for c in columns],
            )
        )
    return _stacked(objects, [np.float64] * 3)


def evolving_triangles(conn: Conn, geoids: Sequence[int], t: sql.Composable) -> list[npt.NDArray[Any]] | None:
    """Model 3's triangles at t of features ``geoids`` from ``d4dtrgl``'s chunks of the period containing t.

    The period is chosen by the server in the same query (``tgsis.evolving_frame``, as ``tgsis.triangles_at``).

    Returns
    -------
    list of ndarray or None
        ``[geoid, trglid, vrtxid1, vrtxid2, vrtxid3]`` (n,) each, ordered by (geoid, trglid), node ids as
        vertex ids; None while ``d4dtrgl`` is stored as rows (or the role may read the face only).
    """
    layout = instant_layout(conn, "d4dtrgl", chunked_tables(conn))
    if layout is None:
        return None
    rows = instant_rows(
        conn,
        layout,
        geoids,
        sql.SQL("c.timem = (SELECT fr.timem FROM tgsis.evolving_frame(f.geoid, {}) fr)").format(t),
    )
    names = ("nodeid1", "nodeid2", "nodeid3")
    objects = [(key[0], rows[key].ids, [rows[key].columns[c] for c in names]) for key in sorted(rows)]
    return _stacked([(int(g), i, c) for g, i, c in objects], [np.int64] * 3)


def chunk_snapshot(
    conn: Conn, model: str, geoids: Sequence[int], t: sql.Composable, convention: sql.Composable
) -> tuple[list[npt.NDArray[Any]] | None, list[npt.NDArray[Any]] | None]:
    """The vertices and triangles at t of features of time model ``model`` from their time tables' chunks.

    Model 2: the instant's chunks (:func:`instant_snapshot`); model 3: the period's triangles and its two
    geometry instants' node chunks, interpolated here (:func:`evolving_vertices`, :func:`evolving_triangles`).
    Each is None while its table is stored as rows (or for another model): the caller reads the face.
    ``convention`` is model 2's only (:func:`time_args` has checked it).
    """
    if model == "INSTANTS":
        return (
            instant_snapshot(conn, "times_vrtx", geoids, t, convention, ["vrtxid", "x", "y", "z"]),
            instant_snapshot(conn, "times_trgl", geoids, t, convention, ["trglid", "vrtxid1", "vrtxid2", "vrtxid3"]),
        )
    if model == "EVOLVING":
        return evolving_vertices(conn, geoids, t), evolving_triangles(conn, geoids, t)
    return None, None


def time_args(t: float, convention: str) -> tuple[sql.Literal, sql.Literal]:
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
        idx, value = packed_out(
            conn,
            sql.SQL(
                "SELECT idx, coalesce(value, 'NaN')::float8 AS value FROM tgsis.property_at({}, {}, {}, {}, {})"
            ).format(
                sql.Literal(fc.name),
                sql.Literal(feature_id),
                sql.Literal(prop.name),
                sql.Literal(float(t)),
                sql.Literal(convention),
            ),
            [("idx", "int8"), ("value", "float8")],
            ["idx"],
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

    Computed in SQL (``tgsis.vertices_at``, ``tgsis.triangles_at``), or, for
    time tables stored in chunks, from their chunks decoded here with the same
    answer bit for bit (:func:`chunk_snapshot`):
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
    t_lit, c_lit = time_args(t, convention)

    def read() -> Surface | None:
        """The surface and its properties of one state (:func:`consistent_read`)."""
        row = conn.execute(
            sql.SQL(
                "SELECT tgsis.exists_at(%s, {}, {}), geoname, geotype, timemodel FROM tgsis.geometry WHERE geoid = %s"
            ).format(t_lit, c_lit),
            (feature_id, feature_id),
        ).fetchone()
        if row is None:
            raise NotFoundError(f"feature {feature_id} does not exist", hint="`tgsis ls` lists the features")
        if row[2] != "SURFACE":
            raise InvalidInputError(f"feature {feature_id} is a {row[2]}, not a surface")
        if not row[0]:
            return None
        vertices, triangles = chunk_snapshot(conn, row[3], [feature_id], t_lit, c_lit)
        with _without_jit(conn):
            # packed by the server in groups of 1,024 ids (packed_out): a COPY message per row
            # cost most of the snapshot's time
            ids, x, y, z = (
                vertices[1:]
                if vertices is not None
                else packed_out(
                    conn,
                    sql.SQL("SELECT vrtxid, x, y, z FROM tgsis.vertices_at({}, {}, {})").format(
                        sql.Literal(feature_id), t_lit, c_lit
                    ),
                    [("vrtxid", "int8"), ("x", "float8"), ("y", "float8"), ("z", "float8")],
                    ["vrtxid"],
                )
            )
            # ordered by trglid here, not by the server: the rows come in no order
            tid, a, b, c = (
                triangles[1:]
                if triangles is not None
                else packed_out(
                    conn,
                    sql.SQL("SELECT trglid, vrtxid1, vrtxid2, vrtxid3 FROM tgsis.triangles_at({}, {}, {})").format(
                        sql.Literal(feature_id), t_lit, c_lit
                    ),
                    [("trglid", "int8"), ("vrtxid1", "int8"), ("vrtxid2", "int8"), ("vrtxid3", "int8")],
                    ["trglid"],
                )
            )
        order = rows_by_geoid(tid, tid, [feature_id])[feature_id]
        surface = assemble_surface(feature_id, ids, (x, y, z), (a[order], b[order], c[order]), row[1])
        if properties:  # read in the same state (they were read after it, in a snapshot of their own)
            _properties_at(conn, surface, feature_id, t, convention, np.sort(ids), tid[order])
        return surface

    with reraise():
        return consistent_read(conn, "get_at", read)


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
            binary=True,  # the instants bit for bit, whatever the session's extra_float_digits
        ).fetchone()
    if row is None:
        raise NotFoundError(f"feature {feature_id} does not exist", hint="`tgsis ls` lists the features")
    if row[0] == "STATIC" or row[2] is None:
        return None
    return float(row[2]), float(row[3]), bool(row[1])


# --------------------------------------------------------------------------- models 2 and 3 in the browser view


def draw_snapshot(conn: Conn, fc: FeatureClass, feature_id: int, t: float | None) -> Drawable | None:
    """What the view draws of a model-2 or model-3 feature: the SQL snapshot at t (:func:`get_at`).

    None outside the feature's life; the class's numeric properties at t come along to colour by.
    """
    if t is None:
        raise InvalidInputError(f"feature {feature_id} (class {fc.name}) is drawn at a time t")
    surface = get_at(conn, feature_id, t, properties=True)
    return None if surface is None else drawable(surface)


def slider_span(conn: Conn, feature_id: int) -> tuple[float, float] | None:
    """A model-2 or model-3 feature's span in the view's time slider: its first and last instant (:func:`lifespan`)."""
    span = lifespan(conn, feature_id)
    return None if span is None else (span[0], span[1])
