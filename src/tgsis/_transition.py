"""Sudden changes at topology instants as short linear transitions (models 3 and 4), on numpy arrays.

The design: at a topology instant the object is duplicated into a
pre-object (old topology) and a post-object (new topology) that share their
geometry, and "a sudden change is a linear change over a very short
period". So a sudden change becomes: the post-object starts at the topology
instant t0 in the pre-object's geometry, and reaches its own first shape at
t0 + duration, linearly. Where the post-object starts (its nodes on the
pre-object):

* when both have as many nodes and the same cells, node i is node i (the
  same topology: the change is a motion);
* otherwise each node of the post-object starts at the closest point of the
  pre-object's shape (its triangles for a surface, its edges for a G-map)
  after the post-object's offset as a whole is taken out (:func:`start_on`).

No database here: :func:`tgsis.temporal.sudden_change` and
:func:`tgsis.gmaps.sudden_gmap_change` use these helpers.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np
import numpy.typing as npt

from tgsis.errors import InvalidInputError


def _kd_tree(points: npt.NDArray[np.float64]) -> Any:
    """A scipy k-d tree of ``points``; scipy is imported here, when a transition needs it, so that importing
    tgsis.temporal or tgsis.gmaps stays light (tests/test_gmaps.py)."""
    from scipy.spatial import cKDTree

    return cKDTree(points)


FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]

#: Nearest triangle centroids tried per point (the closest point found lies on the surface whatever it is).
_CANDIDATES = 16


def transition_times(times: FloatArray, duration: float, label: str) -> FloatArray:
    """``times`` with ``times[0] + duration`` inserted after the first: the transition's end.

    Raises
    ------
    InvalidInputError
        A duration that is not finite and > 0, or that does not end before
        the period's second geometry instant (named by ``label``).
    """
    value = float(duration)
    if not math.isfinite(value) or value <= 0:
        raise InvalidInputError(f"the duration of a sudden change must be a finite time > 0, got {duration!r}")
    end = float(times[0]) + value
    if end <= float(times[0]) or (len(times) > 1 and end >= float(times[1])):
        raise InvalidInputError(
            f"a sudden change of {value!r} at the start of {label} (t = {float(times[0])!r}) must end before its "
            f"second geometry instant {float(times[1]) if len(times) > 1 else float('nan')!r}",
            hint="a sudden change is a change over a very short period: give a shorter duration",
        )
    return np.concatenate([times[:1], [end], times[1:]]).astype(np.float64)


def closest_on_triangles(vertices: FloatArray, triangles: IntArray, points: FloatArray) -> FloatArray:
    """(k, 3) points of the triangle mesh (vertices (n, 3), triangles (m, 3)) close to each of ``points`` (k, 3).

    Each is the closest point among the triangles whose centroids are the
    nearest few to the point: always a point of the surface, the closest
    one unless a large triangle's centroid lies farther than the others'.
    """
    if len(triangles) == 0:
        return np.asarray(
            vertices[_kd_tree(vertices).query(points)[1]] if len(vertices) else points.copy(), dtype=np.float64
        )
    from trimesh.triangles import closest_point

    corners = vertices[triangles]
    k = min(_CANDIDATES, len(triangles))
    _, candidates = _kd_tree(corners.mean(axis=1)).query(points, k=k)
    candidates = np.asarray(candidates).reshape(len(points), k)
    repeated = np.repeat(points, k, axis=0)
    found = np.asarray(
        closest_point(corners[candidates.reshape(-1)], repeated),  # type: ignore[no-untyped-call]
        dtype=np.float64,
    ).reshape(len(points), k, 3)
    distances = np.linalg.norm(found - points[:, None, :], axis=2)
    return np.asarray(found[np.arange(len(points)), np.argmin(distances, axis=1)], dtype=np.float64)


def closest_on_segments(points: FloatArray, segments: IntArray, queries: FloatArray) -> FloatArray:
    """(k, m) points of the segments (s, 2) between ``points`` (n, m) close to each of ``queries`` (k, m).

    As :func:`closest_on_triangles`: the closest among the segments whose
    midpoints are the nearest few; with no segment, the nearest point.
    """
    if len(segments) == 0:
        return np.asarray(points[_kd_tree(points).query(queries)[1]], dtype=np.float64)
    a, b = points[segments[:, 0]], points[segments[:, 1]]
    k = min(_CANDIDATES, len(segments))
    _, candidates = _kd_tree((a + b) / 2).query(queries, k=k)
    candidates = np.asarray(candidates).reshape(len(queries), k)
    ca, cb = a[candidates], b[candidates]  # (k_q, k, m)
    ab = cb - ca
    length = np.einsum("ijk,ijk->ij", ab, ab)
    s = np.where(
        length > 0, np.einsum("ijk,ijk->ij", queries[:, None, :] - ca, ab) / np.where(length > 0, length, 1), 0
    )
    found = ca + np.clip(s, 0, 1)[..., None] * ab
    distances = np.linalg.norm(found - queries[:, None, :], axis=2)
    return np.asarray(found[np.arange(len(queries)), np.argmin(distances, axis=1)], dtype=np.float64)


def start_on(before: Callable[[FloatArray], FloatArray], after: FloatArray, rounds: int = 20) -> FloatArray:
    """Where the nodes ``after`` (k, m) start on the shape before: ``before(q)`` gives points of it close to q.

    The shape after may be moved as a whole (a sudden offset): the offset is
    estimated first (the mean of ``q - before(q)``, refined a few times, a
    translation-only iterative closest point), then each node starts at the
    point of the shape before closest to it minus the offset. A rigid
    offset is undone exactly; otherwise each node starts at a nearby point
    of the shape before.
    """
    offset = np.zeros(after.shape[1])
    for _ in range(rounds):
        moved = after - offset
        step = np.mean(moved - before(moved), axis=0)
        offset = offset + step
        if float(np.linalg.norm(step)) <= 1e-12 * (1.0 + float(np.abs(after).max(initial=0.0))):
            break
    return before(after - offset)


def prepend_first(
    values: npt.NDArray[np.generic], first: npt.NDArray[np.generic] | None = None
) -> npt.NDArray[np.generic]:
    """(g + 1, ...) ``values`` (g, ...) with ``first`` (default: ``values[0]``) put before them."""
    head = values[:1] if first is None else np.asarray(first, dtype=values.dtype)[None]
    return np.concatenate([head, values])
