"""Polygons cut into triangles and polylines into segments, vectorised (no database): shared by the PostGIS reader and the browser view."""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

__all__ = ["fan_triangles", "polyline_segments"]


def fan_triangles(indices: npt.ArrayLike, offsets: npt.ArrayLike) -> tuple[npt.NDArray[np.int64], npt.NDArray[np.int64]]:
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
