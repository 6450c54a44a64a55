"""Model 1 in the browser view: a static surface's rows straight into what the browser draws.

:func:`tgsis.fetch_feature` builds a validated :class:`~tgsis.Surface` with
every vertex and cell property, its parts and atoms and its file's z
convention: what a client that edits and writes back needs. The view only
draws: it takes the stored vertices and triangles (``tgsis.vrtx``,
``tgsis.trgl`` as the session's version sees them, two packed queries of
:mod:`tgsis.db.inspect`), and one vertex property only when
the page colours by it: with the stored ids for the comparisons
(:func:`stored_surface`), or for the scene without the triangles' ids, their
corners packed one value a triangle (:func:`drawable_surface`). The scene's
download of a 1M-vertex surface is a fraction of the time of
``fetch_feature`` (bench/view_load.py). Model 1's hooks of the registry of
data models (:mod:`tgsis.db.features`: ``draw``, ``surface``) call these; the
view itself names no model.
"""

from __future__ import annotations

import concurrent.futures
from collections.abc import Callable
from typing import Any, TypeVar

import numpy as np
import numpy.typing as npt
import psycopg

from tgsis.db._transfer import local_positions
from tgsis.db.classes import FeatureClass
from tgsis.db.inspect import (
    static_triangle_corners,
    static_triangle_rows,
    static_vertex_property_rows,
    static_vertex_rows,
)
from tgsis.drawing import Drawable, StoredSurface
from tgsis.errors import InvalidInputError

__all__ = ["drawable_surface", "stored_surface"]

Conn = psycopg.Connection[Any]


def stored_surface(
    conn: Conn, fc: FeatureClass, feature_id: int, prop: str | None = None, *, beside: Conn | None = None
) -> StoredSurface:
    """The stored vertices and triangles of a static surface (and the vertex property ``prop``), with their ids.

    ``beside``: a second connection that sees what ``conn`` sees (the same
    snapshot and version): the triangles come through it while the vertices
    come through ``conn``, the two queries running side by side on the server.

    Raises
    ------
    InvalidInputError
        ``prop`` is not a numeric scalar vertex property of the class.
    InvalidGeometryError
        Triangles that name vertices the geometry does not have.
    """

    def triangles(on: Conn) -> tuple[npt.NDArray[np.int64], ...]:
        return static_triangle_rows(on, feature_id)

    vertex_ids, vertices, (tid, a, b, c) = _side_by_side(conn, feature_id, triangles, beside)
    torder = np.argsort(tid, kind="stable")
    corners = np.stack([a[torder], b[torder], c[torder]], axis=1)
    drawable = _drawable(conn, fc, feature_id, prop, vertex_ids, vertices, corners)
    return StoredSurface(drawable, vertex_ids, tid[torder])


def drawable_surface(
    conn: Conn, fc: FeatureClass, feature_id: int, prop: str | None = None, *, beside: Conn | None = None
) -> Drawable:
    """What the scene draws of a static surface: :func:`stored_surface` without the triangles' ids or order.

    The triangles' corners travel packed (:func:`tgsis.db._transfer.corners_out`,
    one value per triangle instead of four: about a third less server time
    for the triangles of a large surface) and are not sorted by id on the
    client (docs/performance.md, "The browser view").

    Raises
    ------
    InvalidInputError
        ``prop`` is not a numeric scalar vertex property of the class.
    InvalidGeometryError
        Triangles that name vertices the geometry does not have.
    """

    def triangles(on: Conn) -> npt.NDArray[np.int64]:
        return static_triangle_corners(on, feature_id)

    vertex_ids, vertices, corners = _side_by_side(conn, feature_id, triangles, beside)
    return _drawable(conn, fc, feature_id, prop, vertex_ids, vertices, corners)


_T = TypeVar("_T")


def _side_by_side(
    conn: Conn, feature_id: int, triangles: Callable[[Conn], _T], beside: Conn | None
) -> tuple[npt.NDArray[np.int64], npt.NDArray[np.float64], _T]:
    """The vertices (ids ascending, (n, 3) coordinates) through ``conn`` and ``triangles(beside)`` at the same time."""
    with concurrent.futures.ThreadPoolExecutor(1) as pool:
        later = pool.submit(triangles, beside) if beside is not None else None
        vid, x, y, z = static_vertex_rows(conn, feature_id)
        cells = later.result() if later is not None else triangles(conn)
    vertices = np.empty((len(vid), 3))
    if np.all(vid[1:] > vid[:-1]):  # the rows came in id order (as stored by one upload): nothing to sort
        vertices[:, 0], vertices[:, 1], vertices[:, 2] = x, y, z
        return vid, vertices, cells
    vorder = np.argsort(vid, kind="stable")
    vertices[:, 0], vertices[:, 1], vertices[:, 2] = x[vorder], y[vorder], z[vorder]
    return vid[vorder], vertices, cells


def _drawable(
    conn: Conn,
    fc: FeatureClass,
    feature_id: int,
    prop: str | None,
    vertex_ids: npt.NDArray[np.int64],
    vertices: npt.NDArray[np.float64],
    corners: npt.NDArray[np.int64],
) -> Drawable:
    indices = local_positions(vertex_ids, corners.ravel(), "tgsis.trgl rows", feature_id).reshape(-1, 3)
    values: dict[str, npt.NDArray[np.float64]] = {}
    if prop is not None:
        values[prop] = _vertex_property(conn, fc, feature_id, prop, vertex_ids)
    return Drawable("triangles", vertices, indices.astype(np.int64), values, np.arange(len(indices), dtype=np.int64))


def _vertex_property(
    conn: Conn, fc: FeatureClass, feature_id: int, prop: str, vertex_ids: npt.NDArray[np.int64]
) -> npt.NDArray[np.float64]:
    found = [p for p in fc.aligned("VERTEX") if p.name == prop and p.size == 1]
    table = fc.property_table("VERTEX")
    if not found or table is None:
        raise InvalidInputError(f"feature {feature_id} has no numeric vertex property {prop!r}")
    idx, column = static_vertex_property_rows(conn, fc, feature_id, prop, found[0].wire)
    values = np.full(len(vertex_ids), np.nan)
    values[local_positions(vertex_ids, idx, f"{table} rows", feature_id)] = column.astype(np.float64)
    return values
