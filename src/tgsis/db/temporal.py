"""Temporal feature classes in the database: what surfaces at instants (model 2) and evolving surfaces (model 3) share.

The storage of each model is in its own module: :mod:`tgsis.db.instants`
(model 2: ``insert_series``, ``add_instant``, ``delete_instant``,
``fetch_series``) and :mod:`tgsis.db.evolving` (model 3: ``insert_evolving``,
``append_period``, ``delete_period``, ``fetch_evolving``); this module
exports their names too, as it did before it was split by model (their
tables: docs/data-models.md).

Here are the questions over time both models (and static surfaces) answer. Snapshots at t are
computed in SQL by ``tgsis.vertices_at`` / ``tgsis.triangles_at`` and
downloaded packed by the server in groups of rows (:func:`get_at`,
:func:`surfaces_at`; ``tgsis.db._transfer.packed_out``).
:func:`export_series` writes snapshots at several times as a ParaView
``.pvd`` time series (the numpy side is :func:`tgsis.temporal.write_series_pvd`).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
import numpy.typing as npt
from psycopg import sql

from tgsis._series import check_time
from tgsis.arguments import checked
from tgsis.db._temporal_common import Conn, assemble_surface, chunk_snapshot, get_at, lifespan, time_args
from tgsis.db._transfer import class_name, consistent_read, packed_out, resolve_class, rows_by_geoid
from tgsis.db.classes import FeatureClass
from tgsis.db.evolving import append_period, delete_period, fetch_evolving, insert_evolving
from tgsis.db.instants import add_instant, delete_instant, fetch_series, insert_series
from tgsis.errors import InvalidInputError, reraise
from tgsis.formats._common import PathLike
from tgsis.formats.vtk import Encoding
from tgsis.mesh import Geotype, Surface
from tgsis.temporal import (
    Convention,
    Period,
    SurfaceFrame,
    WrittenSeries,
    check_convention,
    even_times,
    write_frames_pvd,
)

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


@checked
def instants(conn: Conn, feature_id: int) -> list[tuple[float, bool]]:
    """The instants of a temporal feature, ascending, with whether its topology is (re)defined there.

    Model 2: every instant (each has its own triangles). Model 3: every
    geometry instant; True where a topology period starts.
    """
    with reraise(), conn.transaction():  # a savepoint: an error leaves the caller's transaction usable
        # binary: the instants bit for bit, whatever the session's extra_float_digits (text rounds them below 1)
        rows = conn.execute(
            "SELECT t, topology FROM tgsis.geometry_instants(%s)", (feature_id,), binary=True
        ).fetchall()
    return [(float(r[0]), bool(r[1])) for r in rows]


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
    t_lit, c_lit = time_args(t, convention)

    def read() -> tuple[list[int], dict[int, str], list[npt.NDArray[Any]], list[npt.NDArray[Any]]]:
        """The features alive at t, their names, vertices and triangles, of one state (:func:`consistent_read`)."""
        alive = features_at(conn, fc, t, convention=convention)
        names = dict(
            conn.execute("SELECT geoid, geoname FROM tgsis.geometry WHERE geoid = ANY (%s)", (alive,)).fetchall()
        )
        wanted = sql.Literal(alive)
        # models 2 and 3 with their time tables in chunks: decoded here, else the faces
        vertices, triangles = chunk_snapshot(conn, fc.time_model, alive, t_lit, c_lit)
        if vertices is not None and triangles is not None:
            return alive, names, vertices, triangles
        vertices = packed_out(
            conn,
            sql.SQL(
                "SELECT f.geoid, v.vrtxid, v.x, v.y, v.z FROM unnest({}::bigint[]) AS f(geoid), "
                "LATERAL tgsis.vertices_at(f.geoid, {}, {}) v"
            ).format(wanted, t_lit, c_lit),
            [("geoid", "int8"), ("vrtxid", "int8"), ("x", "float8"), ("y", "float8"), ("z", "float8")],
            ["geoid", "vrtxid"],
        )
        triangles = packed_out(
            conn,
            sql.SQL(
                "SELECT f.geoid, c.trglid, c.vrtxid1, c.vrtxid2, c.vrtxid3 FROM unnest({}::bigint[]) AS f(geoid), "
                "LATERAL tgsis.triangles_at(f.geoid, {}, {}) c"
            ).format(wanted, t_lit, c_lit),
            [("geoid", "int8"), ("trglid", "int8"), ("vrtxid1", "int8"), ("vrtxid2", "int8"), ("vrtxid3", "int8")],
            ["geoid", "trglid"],
        )
        return alive, names, vertices, triangles

    with reraise():
        alive, names, (vg, vid, x, y, z), (tg, tid, a, b, c) = consistent_read(conn, "surfaces_at", read)
    vertex_rows = rows_by_geoid(vg, vid, alive) if alive else {}
    triangle_rows = rows_by_geoid(tg, tid, alive) if alive else {}
    result: dict[int, Surface] = {}
    for geoid in alive:
        v, tr = vertex_rows[geoid], triangle_rows[geoid]
        result[geoid] = assemble_surface(geoid, vid[v], (x[v], y[v], z[v]), (a[tr], b[tr], c[tr]), names.get(geoid))
    return result


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

    def read() -> list[SurfaceFrame]:
        """Every frame, of one state (:func:`consistent_read`; ``progress`` starts again if it reads again)."""
        frames = []
        for t in samples:
            frames.append((t, get_at(conn, feature_id, t, convention=convention)))
            if progress is not None:
                progress(len(frames), len(samples))
        return frames

    with reraise():
        return consistent_read(conn, "frames_at", read)


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
            binary=True,  # the bounds bit for bit, whatever the session's extra_float_digits
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

    Computed in SQL by ``tgsis.first_time`` and downloaded packed
    (``packed_out``) into two arrays (for a million cells a dict would cost more than
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
        # packed by the server in groups of ids (not a COPY message per cell), ordered here
        idx, t = packed_out(conn, query, [("idx", "int8"), ("t", "float8")], ["idx"])
    order = np.argsort(idx, kind="stable")
    return idx[order], t[order]


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
            binary=True,  # the bounds bit for bit, whatever the session's extra_float_digits
        ).fetchall()
    found: dict[int, list[Period]] = {}
    for r in rows:
        found.setdefault(int(r[0]), []).append(Period(float(r[1]), float(r[2]), bool(r[3]), bool(r[4])))
    return found
