"""Polygons cut into triangles and polylines into segments, vectorised (no database): shared by the PostGIS reader and the browser view."""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

__all__ = ["fan_triangles", "polyline_segments", "PolygonError", "POLYGON_TOLERANCE", "split_convex_polygons"]


def fan_triangles(
    indices: npt.ArrayLike, offsets: npt.ArrayLike
) -> tuple[npt.NDArray[np.int64], npt.NDArray[np.int64]]:
    """Polygons cut into triangles around their first corner.

    Parameters
    ----------
    indices : (s,) array_like of int
        The polygons' corners, polygon after polygon (as :meth:`tgsis.GMap.polygons` gives them).
    offsets : (f + 1,) array_like of int
        Polygon j has ``indices[offsets[j]:offsets[j + 1]]``; polygons of fewer than 3 corners give no triangle.

    Returns
    -------
    triangles : (t, 3) int64
    polygon : (t,) int64
        The polygon each triangle comes from.
    """
    idx, off = np.asarray(indices, dtype=np.int64), np.asarray(offsets, dtype=np.int64)
    counts = np.maximum(np.diff(off) - 2, 0)
    polygon = np.repeat(np.arange(len(counts), dtype=np.int64), counts)
    # the k-th triangle of a polygon: its corners 0, k + 1, k + 2
    k = np.arange(int(counts.sum()), dtype=np.int64) - np.repeat(np.cumsum(counts) - counts, counts)
    start = off[:-1][polygon]
    return np.stack([idx[start], idx[start + k + 1], idx[start + k + 2]], axis=1), polygon


def polyline_segments(indices: npt.ArrayLike, offsets: npt.ArrayLike) -> npt.NDArray[np.int64]:
    """Polylines cut into their segments, in order.

    Parameters
    ----------
    indices : (s,) array_like of int
        The polylines' points, polyline after polyline.
    offsets : (f + 1,) array_like of int
        Polyline j has ``indices[offsets[j]:offsets[j + 1]]``; polylines of fewer than 2 points give no segment.

    Returns
    -------
    segments : (t, 2) int64
    """
    idx, off = np.asarray(indices, dtype=np.int64), np.asarray(offsets, dtype=np.int64)
    # every point but the last of its polyline starts a segment
    starts = np.ones(len(idx), dtype=bool)
    starts[off[1:][off[1:] > 0] - 1] = False
    first = np.flatnonzero(starts)
    return np.stack([idx[first], idx[first + 1]], axis=1)


class PolygonError(ValueError):
    """A polygon that is not split into triangles: not planar, not convex, or of no area.

    Attributes
    ----------
    polygon : int
        Its index among the polygons given.
    reason : str
        What is wrong, for a message.
    """

    def __init__(self, polygon: int, reason: str) -> None:
        super().__init__(f"polygon {polygon} {reason}")
        self.polygon = polygon
        self.reason = reason


#: How far (relative to its size) a polygon's corner may lie off its plane, or turn the wrong way, and still count
#: as planar and convex: rounding of the coordinates a file wrote, not a shape.
POLYGON_TOLERANCE = 1e-6


def split_convex_polygons(
    vertices: npt.NDArray[np.float64],
    indices: npt.ArrayLike,
    offsets: npt.ArrayLike,
) -> tuple[npt.NDArray[np.int64], npt.NDArray[np.int64], int]:
    """Polygons cut into a fan of triangles when each is planar and convex, so the cut changes no shape.

    A planar convex polygon is the union of the triangles of any fan over it:
    splitting it adds no vertex and moves nothing. A non-planar polygon has no
    one surface (each diagonal gives another), and a fan over a non-convex one
    covers what is not the polygon: those are refused.

    Parameters
    ----------
    vertices : (n, 3) float64
    indices : (s,) array_like of int
        The polygons' corners (valid vertex indices), polygon after polygon.
    offsets : (f + 1,) array_like of int
        Polygon j has ``indices[offsets[j]:offsets[j + 1]]``, at least 3 corners.

    Returns
    -------
    triangles : (t, 3) int64
    polygon : (t,) int64
        The polygon each triangle comes from.
    split : int
        How many polygons had more than 3 corners.

    Raises
    ------
    PolygonError
        The first polygon (lowest index) of more than 3 corners that is not
        planar, not convex (also a star that turns twice around), or has
        no area, within :data:`POLYGON_TOLERANCE` of its size.
    """
    idx, off = np.asarray(indices, dtype=np.int64), np.asarray(offsets, dtype=np.int64)
    sizes = np.diff(off)
    bad: list[tuple[int, str]] = []
    for k in np.unique(sizes[sizes > 3]).tolist():
        which = np.flatnonzero(sizes == k)
        corners = idx[off[which][:, None] + np.arange(k)]
        problem = _not_convex_planar(vertices[corners])
        failed = np.flatnonzero(problem != "")
        if len(failed):
            bad.append((int(which[failed[0]]), str(problem[failed[0]])))
    if bad:
        polygon, reason = min(bad)
        raise PolygonError(polygon, reason)
    triangles, polygon_of = fan_triangles(idx, off)
    return triangles, polygon_of, int(np.count_nonzero(sizes > 3))


def _not_convex_planar(points: npt.NDArray[np.float64]) -> npt.NDArray[np.str_]:
    """For (p, k, 3) polygons: "" for each planar convex one, else what it is not."""
    centred = points - points.mean(axis=1, keepdims=True)
    size = np.sqrt((centred**2).sum(-1)).max(axis=1)  # (p,)
    ahead = np.roll(centred, -1, axis=1)
    normal = np.cross(centred, ahead).sum(axis=1)  # Newell: twice the area vector
    area2 = np.sqrt((normal**2).sum(-1))
    tol = POLYGON_TOLERANCE * np.maximum(size, np.finfo(np.float64).tiny)
    result = np.full(len(points), "", dtype=object)
    flat = area2 <= tol * size
    result[flat] = "has no area (its corners are on one line or one point)"
    unit = normal / np.where(area2 > 0, area2, 1.0)[:, None]
    off_plane = np.abs((centred * unit[:, None, :]).sum(-1)).max(axis=1)
    result[(result == "") & (off_plane > tol)] = "is not planar"
    edges = ahead - centred  # edge i: corner i -> i + 1
    before = np.roll(edges, 1, axis=1)  # the edge into corner i
    turn = (np.cross(before, edges) * unit[:, None, :]).sum(-1)  # > 0: a left turn about the normal
    lengths = np.sqrt((edges**2).sum(-1)) * np.sqrt((before**2).sum(-1))
    reflex = (turn < -tol[:, None] * size[:, None]).any(axis=1)
    result[(result == "") & reflex] = "is not convex"
    angle = np.arctan2(turn, (before * edges).sum(-1))  # the turn at each corner
    twice = np.abs(angle.sum(axis=1)) > 3 * np.pi  # a star: it turns 4 pi, not 2 pi
    result[(result == "") & twice & (lengths.min(axis=1) > 0)] = "is not convex (it winds around twice)"
    return result.astype(str)
