"""What the ``tgsis`` command reads about stored things: a feature's summary row and properties, the features of a
class, counts, the z convention, whether versions or revisions exist.

The command line holds no SQL (docs/developing.md, "Add a command"): every
question it asks the database is a function here, or in the module of its
topic. The reads see the session's working version, as the command's other
reads do.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt
import psycopg
from psycopg import sql

from tgsis.arguments import checked
from tgsis.db._chunk_transfer import chunked_tables, rows_request
from tgsis.db._cube import box_corners
from tgsis.db._transfer import columns_out, columns_out_all, corners_out
from tgsis.db.classes import FeatureClass, readable_class_names  # FeatureClass at run time: @checked reads the hints
from tgsis.errors import NotFoundError, reraise

Conn = psycopg.Connection[Any]

__all__ = [
    "static_triangle_corners",
    "static_triangle_rows",
    "static_vertex_property_rows",
    "static_vertex_rows",
    "may_read_features",
    "class_has_feature",
    "count_features",
    "feature_name",
    "md_gmap_axes",
    "version_validity",
    "conflicts_with_solutions",
    "FeatureRow",
    "GeometrySummary",
    "ShapeSizes",
    "features_named",
    "feature_property_values",
    "features_versioned",
    "geometry_summary",
    "list_features",
    "lock_feature_name",
    "other_versions_exist",
    "revision_exists",
    "server_version",
    "shape_sizes",
    "stored_rows",
    "stored_zpositive",
]


def _named(fc: FeatureClass) -> sql.Composable:
    """The feature table of class ``fc``, quoted."""
    return sql.SQL("{}.{}").format(sql.Identifier(fc.schema), sql.Identifier(fc.featuretable))


@checked
def server_version(conn: Conn) -> str | None:
    """The server's ``version()`` string."""
    with reraise():
        row = conn.execute("SELECT version()").fetchone()
    return str(row[0]) if row else None


@checked
def stored_rows(conn: Conn, fc: FeatureClass, table: str) -> tuple[int, int]:
    """How many rows table ``table`` of class ``fc`` holds as the working version reads them, and of how many
    geometries: ``(rows, geometries)``."""
    with reraise():
        row = conn.execute(
            sql.SQL("SELECT count(*), count(DISTINCT _geoid) FROM {}").format(fc.qualified(table))
        ).fetchone()
    assert row is not None
    return int(row[0]), int(row[1])


@checked
def other_versions_exist(conn: Conn) -> bool:
    """Whether the database has versions other than DEFAULT."""
    with reraise():
        row = conn.execute("SELECT count(*) > 1 FROM tgsis.versions").fetchone()
    return bool(row and row[0])


@checked
def revision_exists(conn: Conn, revision: int) -> bool:
    """Whether revision number ``revision`` is still recorded (``tgsis version compress`` removes revisions)."""
    with reraise():
        row = conn.execute("SELECT EXISTS (SELECT FROM tgsis.revisions WHERE revision = %s)", (revision,)).fetchone()
    return row == (True,)


@checked
def features_versioned(conn: Conn) -> bool:
    """Whether the feature tables are versioned (``tgsis versioning enable features`` was run)."""
    with reraise():
        row = conn.execute(
            "SELECT EXISTS (SELECT FROM tgsis.versioned_tables WHERE objectclass = 'feature')"
        ).fetchone()
    return row == (True,)


@checked
def lock_feature_name(conn: Conn, fc: FeatureClass, name: str, purpose: str) -> None:
    """Take the transaction-level advisory lock on class ``fc`` and feature name ``name`` for ``purpose``.

    Two writers of one name that take it take turns: the second sees the
    first's feature once it is committed (``tgsis import`` warns, or replaces
    it with ``--replace``, instead of both adding a feature of that name).
    """
    with reraise():
        conn.execute(
            "SELECT pg_advisory_xact_lock(hashtextextended(%s, 0))",
            (f"{purpose}: {fc.schema}.{fc.featuretable}: {name}",),
        )


@checked
def features_named(conn: Conn, fc: FeatureClass, name: str) -> list[int]:
    """The ids of the features of class ``fc`` named ``name`` (as the working version sees them), in order."""
    with reraise():
        rows = conn.execute(
            sql.SQL(
                "SELECT g.geoid FROM {} f JOIN tgsis.geometry g ON g.geoid = f._geoid "
                "WHERE g.geoname = %s ORDER BY g.geoid"
            ).format(_named(fc)),
            (name,),
        ).fetchall()
    return [int(r[0]) for r in rows]


@dataclass(frozen=True)
class GeometrySummary:
    """What ``tgsis.geometry`` records of one feature: name, type, counts, time model, and its box.

    ``box``: ``(xmin, xmax, ymin, ymax, zmin, zmax)``, None members when it has none.
    """

    name: str | None
    geotype: str
    n_vertices: int
    n_cells: int
    members: int | None
    time_model: str | None
    alive: bool | None
    box: tuple[float | None, float | None, float | None, float | None, float | None, float | None]


@checked
def geometry_summary(conn: Conn, geoid: int) -> GeometrySummary:
    """The :class:`GeometrySummary` of feature ``geoid``; :class:`NotFoundError` when there is none."""
    with reraise():
        row = conn.execute(
            sql.SQL(
                "SELECT geoname, geotype, nvrtx, ncell, cardinality(geoids), timemodel, alive, {} "
                "FROM tgsis.geometry WHERE geoid = %s"
            ).format(box_corners(conn, sql.Identifier("bbox"), "axes")),
            (geoid,),
            binary=True,  # the box bit for bit, whatever the session's extra_float_digits
        ).fetchone()
    if row is None:
        raise NotFoundError(f"feature {geoid} does not exist")
    return GeometrySummary(row[0], row[1], row[2], row[3], row[4], row[5], row[6], tuple(row[7:13]))


@checked
def feature_property_values(conn: Conn, fc: FeatureClass, geoid: int) -> dict[str, Any]:
    """The feature properties of feature ``geoid`` of class ``fc``, by name, in the class's (the table's) order.

    Read in binary: float values bit for bit, whatever the session's
    ``extra_float_digits`` (the class's properties only: binary has every
    property type's loader, not that of a column added by hand).
    """
    names = [p.name for p in fc.feature_properties]
    if not names:
        return {}
    with reraise():
        row = conn.execute(
            sql.SQL("SELECT {} FROM {} WHERE _geoid = %s").format(
                sql.SQL(", ").join(sql.Identifier(n) for n in names), _named(fc)
            ),
            (geoid,),
            binary=True,
        ).fetchone()
    return dict(zip(names, row or ()))


@dataclass(frozen=True)
class ShapeSizes:
    """The sizes of the shapes of a surface in time: ``vertices[i]``, ``cells[i]`` of shape i in time order
    (model 2: per instant; model 3: per topology period), and how many instants or periods it has."""

    vertices: Sequence[int]
    cells: Sequence[int]
    count: int


@checked
def shape_sizes(conn: Conn, time_model: str, geoid: int) -> ShapeSizes | None:
    """How many vertices and cells each shape of feature ``geoid`` has, where ``tgsis.geometry`` adds up the rows
    of every instant or period; None for time models other than INSTANTS and EVOLVING, or with no shape."""
    if time_model == "INSTANTS":
        query = (
            "SELECT (SELECT array_agg(n ORDER BY t) FROM (SELECT times, count(*) FROM tgsis.times_vrtx WHERE geoid = %s"
            "        GROUP BY times) AS v(t, n)),"
            "       (SELECT array_agg(n ORDER BY t) FROM (SELECT times, count(*) FROM tgsis.times_trgl WHERE geoid = %s"
            "        GROUP BY times) AS c(t, n)), (SELECT count(*) FROM tgsis.times WHERE geoid = %s)"
        )
    elif time_model == "EVOLVING":
        query = (
            "SELECT (SELECT array_agg(n ORDER BY t) FROM (SELECT timem, count(*) FROM tgsis.node WHERE geoid = %s"
            "        GROUP BY timem) AS v(t, n)),"
            "       (SELECT array_agg(n ORDER BY t) FROM (SELECT timem, count(*) FROM tgsis.d4dtrgl WHERE geoid = %s"
            "        GROUP BY timem) AS c(t, n)), (SELECT count(DISTINCT timem) FROM tgsis.node WHERE geoid = %s)"
        )
    else:
        return None
    with reraise():
        counts = conn.execute(query, (geoid, geoid, geoid)).fetchone()
    if counts is None or not counts[0]:
        return None
    return ShapeSizes([int(n) for n in counts[0]], [int(n) for n in counts[1] or [0]], int(counts[2]))


@checked
def stored_zpositive(conn: Conn, geoid: int) -> str | None:
    """The z convention (``ZPOSITIVE``) the file of feature ``geoid`` had, as stored; None when none was kept."""
    with reraise():
        row = conn.execute("SELECT zpositive FROM tgsis.geometry WHERE geoid = %s", (geoid,)).fetchone()
    return None if row is None or row[0] is None else str(row[0])


@dataclass(frozen=True)
class FeatureRow:
    """A feature as the pages list it."""

    id: int
    feature_class: str
    name: str | None
    geotype: str
    vertices: int | None
    cells: int | None
    time_model: str
    first: float | None
    last: float | None
    alive: bool | None
    properties: dict[str, Any]
    box: list[float] | None
    members: int | None = None  # of a collection; None for other geometries


@checked
def list_features(
    conn: Conn,
    fc: FeatureClass,
    *,
    name: str | None = None,
    box: Sequence[float] | None = None,
    ids: Sequence[int] | None = None,
    properties: Mapping[str, str] | None = None,
    limit: int | None = None,
) -> list[FeatureRow]:
    """The features of class ``fc`` as the working version sees them, by id, with their feature properties.

    Parameters
    ----------
    name : a part of the name, in any case
    box : ``(xmin, ymin, zmin, xmax, ymax, zmax)``: features whose bounding box meets it
    ids : only these features
    properties : feature property name -> value: features whose property equals the value (the text is read as
        the property's type; a value of another type fails with :class:`InvalidInputError`)
    limit : at most this many
    """
    props = [p.name for p in fc.feature_properties]
    conditions: list[sql.Composable] = [sql.SQL("true")]
    params: list[Any] = []
    if name:
        conditions.append(sql.SQL("strpos(lower(g.geoname), lower(%s)) > 0"))
        params.append(name)
    if box is not None:
        conditions.append(sql.SQL("g.geoid IN (SELECT b FROM tgsis.geometries_in_box(%s, %s, %s, %s, %s, %s) b)"))
        params += list(box)
    if ids is not None:
        conditions.append(sql.SQL("g.geoid = ANY(%s)"))
        params.append(list(ids))
    for prop, value in (properties or {}).items():
        if prop not in props:
            raise NotFoundError(
                f"class {fc.name} has no feature property {prop!r}",
                hint=f"its feature properties: {', '.join(props) or 'none'}",
            )
        # the value is an untyped literal: PostgreSQL reads it as the column's type (22P02 when it is not one)
        conditions.append(sql.SQL("f.{} = %s").format(sql.Identifier(prop)))
        params.append(value)
    query = sql.SQL(
        "SELECT g.geoid, g.geoname, g.geotype, g.nvrtx, g.ncell, g.timemodel, g.alive, i.first, i.last, "
        "{}, cardinality(g.geoids){} "
        "FROM {} f JOIN tgsis.geometry g ON g.geoid = f._geoid "
        "LEFT JOIN LATERAL (SELECT min(t) AS first, max(t) AS last "
        "                     FROM (SELECT t FROM tgsis.geometry_instants(g.geoid) "
        "                            WHERE g.timemodel IN ('INSTANTS', 'EVOLVING') "
        "                           UNION ALL SELECT timet FROM tgsis.gmap_timet "
        "                            WHERE geoid = g.geoid AND g.timemodel = 'GMAP') AS lives (t)) i ON true "
        "WHERE {} ORDER BY g.geoid {}"
    ).format(
        box_corners(conn, sql.Identifier("g", "bbox")),
        sql.SQL("").join(sql.SQL(", f.{}").format(sql.Identifier(p)) for p in props),
        fc.qualified(fc.featuretable),
        sql.SQL(" AND ").join(conditions),
        sql.SQL("LIMIT {}").format(sql.Literal(limit)) if limit is not None else sql.SQL(""),
    )
    with reraise():
        # binary: first and last instants, box and float values bit for bit, whatever the session's extra_float_digits
        rows = conn.execute(query, params, binary=True).fetchall()
    return [
        FeatureRow(
            int(r[0]),
            fc.name,
            r[1],
            r[2],
            r[3],
            r[4],
            r[5],
            None if r[7] is None else float(r[7]),
            None if r[8] is None else float(r[8]),
            None if r[7] is None else bool(r[6]),
            dict(zip(props, r[16:])),
            None if r[9] is None else [float(v) for v in r[9:15]],
            r[15],
        )
        for r in rows
    ]


@checked
def may_read_features(conn: Conn, fc: FeatureClass) -> bool:
    """Whether the session's role may read the feature table of class ``fc``."""
    with reraise():
        return fc.name in readable_class_names(conn)


@checked
def class_has_feature(conn: Conn, fc: FeatureClass, geoid: int) -> bool:
    """Whether class ``fc`` holds feature ``geoid`` as the working version sees it."""
    with reraise():
        row = conn.execute(sql.SQL("SELECT 1 FROM {} WHERE _geoid = %s").format(_named(fc)), (geoid,)).fetchone()
    return row is not None


@checked
def count_features(conn: Conn, fc: FeatureClass) -> int:
    """How many features class ``fc`` holds as the working version sees them."""
    with reraise():
        row = conn.execute(sql.SQL("SELECT count(*) FROM {}").format(_named(fc))).fetchone()
    return int(row[0]) if row else 0


@checked
def feature_name(conn: Conn, geoid: int) -> str | None:
    """The name of feature ``geoid`` (None: no name, or no such feature)."""
    with reraise():
        row = conn.execute("SELECT geoname FROM tgsis.geometry WHERE geoid = %s", (geoid,)).fetchone()
    return None if row is None else row[0]


@checked
def md_gmap_axes(conn: Conn, geoid: int) -> list[str] | None:
    """The names of the axes of the multiply indexed G-map ``geoid`` (model 5), None when there is none."""
    with reraise():
        row = conn.execute("SELECT axes FROM tgsis.md_gmap WHERE geoid = %s", (geoid,)).fetchone()
    return None if row is None else list(row[0])


@checked
def version_validity(conn: Conn) -> dict[str, tuple[Any, Any]]:
    """Each version's period of belief, by name: ``(valid_from, valid_to)`` (None where unset)."""
    with reraise():
        rows = conn.execute("SELECT name, valid_from, valid_to FROM tgsis.versions").fetchall()
    return {r[0]: (r[1], r[2]) for r in rows}


@checked
def conflicts_with_solutions(conn: Conn, version: str) -> list[dict[str, Any]]:
    """The conflicts of ``version`` with its parent, each with the tables changed on both sides, in the child, in
    the parent, and the recorded solution (``unsolved`` when none): ``{"objectclass", "objectkey", "both",
    "child", "parent", "solution"}``, by class and key."""
    with reraise():
        rows = conn.execute(
            "SELECT c.objectclass, c.objectkey, c.conflicttype, c.childtables, c.parenttables, "
            "       coalesce(k.solution, 'unsolved') "
            "FROM tgsis.current_conflicts(tgsis.version_id(%s)) c "
            "LEFT JOIN tgsis.conflicts k ON k.versionid = tgsis.version_id(%s) AND k.objectclass = c.objectclass "
            "      AND k.objectkey = c.objectkey AND k.childmark = c.childmark AND k.parentmark = c.parentmark "
            "ORDER BY 1, 2",
            (version, version),
        ).fetchall()
    return [
        {
            "objectclass": r[0],
            "objectkey": r[1],
            "both": list(r[2]),
            "child": list(r[3]),
            "parent": list(r[4]),
            "solution": r[5],
        }
        for r in rows
    ]


# --------------------------------------------------------------------------- model 1 rows, packed (the browser view)

_CORNERS = [("vrtxid1", "int8"), ("vrtxid2", "int8"), ("vrtxid3", "int8")]


@checked
def static_vertex_rows(
    conn: Conn, geoid: int
) -> tuple[npt.NDArray[np.int64], npt.NDArray[np.float64], npt.NDArray[np.float64], npt.NDArray[np.float64]]:
    """The stored vertices of static feature ``geoid`` as the working version sees them, in no set order:
    ``(vrtxid, x, y, z)``, (n,) arrays each, through one packed query (:func:`tgsis.db._transfer.columns_out`;
    stored in chunks: the chunks, :class:`tgsis.db._chunk_transfer.PackedChunks`)."""
    with reraise():
        columns = [("vrtxid", "int8"), ("x", "float8"), ("y", "float8"), ("z", "float8")]
        _, vid, x, y, z = columns_out_all(conn, [rows_request(conn, "vrtx", columns, [geoid], chunked_tables(conn))])[0]
    return vid, x, y, z


@checked
def static_triangle_rows(
    conn: Conn, geoid: int
) -> tuple[npt.NDArray[np.int64], npt.NDArray[np.int64], npt.NDArray[np.int64], npt.NDArray[np.int64]]:
    """The stored triangles of static feature ``geoid``, in no set order: ``(trglid, vrtxid1, vrtxid2, vrtxid3)``."""
    with reraise():
        request = rows_request(conn, "trgl", [("trglid", "int8"), *_CORNERS], [geoid], chunked_tables(conn))
        _, tid, a, b, c = columns_out_all(conn, [request])[0]
    return tid, a, b, c


@checked
def static_triangle_corners(conn: Conn, geoid: int) -> npt.NDArray[np.int64]:
    """The corners of the stored triangles of static feature ``geoid``, (m, 3) vertex ids, in no set order; packed
    one value a triangle on the wire (:func:`tgsis.db._transfer.corners_out`), about a third less server time;
    stored in chunks, the chunks' relative corners (:func:`static_triangle_rows` without the ids)."""
    with reraise():
        if "trgl" in chunked_tables(conn):
            return np.stack(static_triangle_rows(conn, geoid)[1:], axis=1)
        return corners_out(conn, sql.SQL("tgsis.trgl"), "geoid", [name for name, _ in _CORNERS], geoid)


@checked
def static_vertex_property_rows(
    conn: Conn, fc: FeatureClass, geoid: int, prop: str, wire: str
) -> tuple[npt.NDArray[np.int64], npt.NDArray[Any]]:
    """The stored values of vertex property ``prop`` (sent as ``wire``) of feature ``geoid``: ``(_idx, values)``."""
    table = fc.property_table("VERTEX")
    if table is None:
        raise NotFoundError(f"class {fc.name} has no vertex properties")
    with reraise():
        _, idx, column = columns_out(conn, fc.qualified(table), "_geoid", [("_idx", "int8"), (prop, wire)], [geoid])
    return idx, column
