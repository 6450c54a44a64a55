"""What the database modules of models 4 and 5 share (:mod:`tgsis.db.gmaps`, :mod:`tgsis.db.multidim`).

Both store n-G-maps: the class check, the class's cell property arrays, the
box of the points, the orientation of the darts, the rows of the
involutions, and, reading, the rows of a COPY in key order and a G-map from
its dart rows. Moved here unchanged when ``db/gmaps.py`` was split by model.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
import numpy.typing as npt
import psycopg
from psycopg import sql

from tgsis.db._transfer import copy_out, local_positions, resolve_class
from tgsis.db.classes import FeatureClass
from tgsis.db.copy import SQL_TYPES, numpy_dtype
from tgsis.errors import InvalidGMapError, InvalidInputError, InvalidPropertyError
from tgsis.gmaps import EvolvingGMap, GMap

Conn = psycopg.Connection[Any]
IntArray = npt.NDArray[np.int64]


def gmap_class(conn: Conn, feature_class: str | FeatureClass, model: str = "GMAP") -> FeatureClass:
    fc = resolve_class(conn, feature_class)
    if fc.time_model != model:
        what = "G-maps in time" if model == "GMAP" else "multiply indexed G-maps"
        raise InvalidInputError(
            f"feature class {fc.name} holds {fc.time_model} {fc.geotype.value} features, not {what}",
            hint=f"create a class with time_model={model!r} and a cell_level for {what}",
        )
    return fc


def class_values(fc: FeatureClass, obj: EvolvingGMap, drop_extra: bool) -> list[dict[str, npt.NDArray[Any]]]:
    """Per period, the class's cell property arrays (g, c), checked and cast to the column types."""
    wanted = {p.name: p for p in fc.cell_properties}
    if obj.level is not None and obj.level != fc.cell_level:
        raise InvalidPropertyError(
            f"the G-map's cell values belong to {obj.level}-cells, feature class {fc.name} "
            f"stores values of {fc.cell_level}-cells"
        )
    if fc.cell_level is not None and fc.cell_level > obj.dimension:
        raise InvalidGMapError(
            f"feature class {fc.name} stores properties of {fc.cell_level}-cells, which a "
            f"{obj.dimension}-G-map does not have"
        )
    out = []
    for i, period in enumerate(obj.periods):
        given = dict(period.cell_values)
        missing = sorted(set(wanted) - set(given))
        if missing:
            raise InvalidPropertyError(
                f"feature class {fc.name} needs cell properties {missing}, which period {i} of the G-map lacks"
            )
        extra = sorted(set(given) - set(wanted))
        if extra and not drop_extra:
            raise InvalidPropertyError(
                f"feature class {fc.name} has no column for cell properties {extra} of period {i}",
                hint="drop the others (drop_extra_properties=True) or register them in the class",
            )
        values: dict[str, npt.NDArray[Any]] = {}
        for name, prop in wanted.items():
            target = numpy_dtype(SQL_TYPES[prop.type])
            cast = given[name].astype(target)
            if target.kind in "iub" and not np.array_equal(cast, given[name]):
                raise InvalidPropertyError(f"cell property {name!r} has values that are not {prop.type} in period {i}")
            values[name] = cast
        out.append(values)
    return out


def gmap_bounds(obj: EvolvingGMap) -> list[float] | None:
    """The box of the first three coordinates of every position (0 for missing ones), as tgsis.gmap_extent."""
    boxes = []
    for period in obj.periods:
        xyz = period.positions.reshape(-1, period.positions.shape[2])[:, :3]
        if len(xyz):
            if xyz.shape[1] < 3:
                xyz = np.hstack([xyz, np.zeros((len(xyz), 3 - xyz.shape[1]))])
            boxes.append(np.stack([xyz.min(axis=0), xyz.max(axis=0)]))
    if not boxes:
        return None
    stacked = np.stack(boxes)
    return [float(v) for v in np.concatenate([stacked[:, 0].min(axis=0), stacked[:, 1].max(axis=0)])]


def orientation_signs(g: GMap) -> npt.NDArray[np.bool_] | None:
    return g.orientation() if g.is_orientable() else None


def alpha_columns(geoid: int, images: IntArray) -> list[tuple[str, npt.ArrayLike, str]]:
    """The rows of ``gmap_alpha`` / ``md_alpha`` for involutions ``images`` ((n + 1, d) int64), in key order.

    Written dart by dart, level by level (the order of the key (geoid, dartid, level)), so that the table holds
    them in the order ``tgsis.gmap_check`` reads them (``tgsis.gmap_alpha_array``) and ``fetch_gmap`` asks for.
    """
    levels, darts = images.shape
    return [
        ("geoid", np.full(levels * darts, geoid), "int8"),
        ("level", np.tile(np.arange(levels, dtype=np.int16), darts), "int2"),
        ("dartid", np.repeat(np.arange(darts, dtype=np.int64), levels), "int8"),
        ("dartid2", np.ascontiguousarray(images.T).reshape(-1), "int8"),
    ]


def period_map(
    dartids: IntArray,
    nodeids: IntArray,
    alpha: Sequence[IntArray],
    node_ids: IntArray,
    points: npt.NDArray[np.float64],
    geoid: int,
) -> GMap:
    """A period's G-map from its dart rows (sorted by dartid) and its nodes (sorted by nodeid)."""
    local = np.stack([local_positions(dartids, a, "alpha rows", geoid) for a in alpha])
    vertex = local_positions(node_ids, nodeids, "darts", geoid)
    return GMap(local, vertex, points)


def cell_ids(topology: GMap, level: int, acellids: IntArray) -> IntArray:
    """The stored cell id (``acellid``) of each of the G-map's ``level``-cells, in ``topology.cells(level)`` order.

    The darts of one cell share its id; ``acellids`` : (n_darts,) int64 are the darts' ids.
    """
    labels = topology.cells(level)
    ids = np.full(int(labels.max()) + 1 if len(labels) else 0, -1, dtype=np.int64)
    ids[labels[::-1]] = acellids[::-1]  # reversed: the last write wins, so the first dart's id
    return ids


def copy_rows(conn: Conn, query: str, geoid: int, types: Sequence[str], order: Sequence[int]) -> list[npt.NDArray[Any]]:
    """The rows of ``query`` (``{}``: the geoid) as columns, sorted by the columns at the positions ``order``."""
    return in_order(copy_out(conn, sql.SQL(query).format(sql.Literal(geoid)), types), order)


def in_order(columns: list[npt.NDArray[Any]], order: Sequence[int]) -> list[npt.NDArray[Any]]:
    """The rows sorted by the columns at the positions ``order`` (most significant first).

    The server is never asked to sort: on tables just loaded (no statistics yet) its plan sorted 18M rows on
    disk; the rows come in the order they were written, usually the key's, and then only the check runs here.
    """
    keys = [columns[i] for i in order]
    if len(keys[0]) < 2:
        return columns
    later, tied = np.zeros(len(keys[0]) - 1, dtype=bool), np.ones(len(keys[0]) - 1, dtype=bool)
    for key in keys:
        later |= tied & (key[1:] > key[:-1])
        tied &= key[1:] == key[:-1]
    if bool(np.all(later | tied)):
        return columns
    rows = np.lexsort(tuple(reversed(keys)))
    return [column[rows] for column in columns]
