"""Closest points on triangle meshes and on the intersection curve of two of them.

Pure numpy/scipy, vectorised over the query points. Used for

* the error between two meshes (distance from the interior vertices of one to
  the other, :func:`closest_points`),
* border vertices attached to one controlling surface (their linear
  trajectory is projected onto it, :meth:`ControllingSurface.project`) or to two
  (projected onto the intersection curve of both, :class:`IntersectionCurve`).

The search is exact: a k-d tree on primitive centres (triangle centroids,
segment midpoints) gives an upper bound of each point's distance from a few
nearest primitives; then every primitive whose bounding sphere comes within
that bound is tested exactly (Ericson's closest point on a triangle).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from tgsis.errors import InvalidInputError
from tgsis.interpolation._arrays import as_points

__all__ = [
    "ProjectionError",
    "ClosestPoints",
    "closest_points",
    "ControllingSurface",
    "IntersectionCurve",
    "intersection_curve",
]

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]
BoolArray = npt.NDArray[np.bool_]

#: Pairs (point, primitive) examined at once; bounds the memory of one query.
_CHUNK_PAIRS = 1 << 21


class ProjectionError(InvalidInputError):
    """A controlling surface or an intersection curve that cannot be used (empty, degenerate, not meeting)."""


def _dot(a: FloatArray, b: FloatArray) -> FloatArray:
    result: FloatArray = np.einsum("ij,ij->i", a, b)
    return result


def _as_mesh(vertices: npt.ArrayLike, triangles: npt.ArrayLike, what: str) -> tuple[FloatArray, IntArray]:
    xyz = as_points(vertices, f"vertices of {what}", ProjectionError)
    tri = np.ascontiguousarray(triangles, dtype=np.int64)
    if tri.ndim != 2 or tri.shape[1] != 3 or len(tri) == 0:
        raise ProjectionError(f"triangles of {what} must have shape (m, 3) with m >= 1, got {tri.shape}")
    if tri.min() < 0 or tri.max() >= len(xyz):
        raise ProjectionError(f"triangles of {what} use a vertex index outside 0..{len(xyz) - 1}")
    return xyz, tri


def closest_on_segments(p: FloatArray, a: FloatArray, b: FloatArray) -> FloatArray:
    """Closest points of segments [a, b] to points p, row by row.

    Parameters
    ----------
    p, a, b : (q, 3) ndarray of float64

    Returns
    -------
    (q, 3) ndarray of float64
        A zero-length segment gives its end point.
    """
    ab = b - a
    length2 = _dot(ab, ab)
    with np.errstate(invalid="ignore", divide="ignore"):
        t = np.where(length2 > 0, _dot(p - a, ab) / length2, 0.0)
    t = np.clip(t, 0.0, 1.0)
    result: FloatArray = a + t[:, None] * ab
    return result


def closest_on_triangles(p: FloatArray, a: FloatArray, b: FloatArray, c: FloatArray) -> FloatArray:
    """Closest points of triangles (a, b, c) to points p, row by row (Ericson, Real-Time Collision Detection 5.1.5).

    Parameters
    ----------
    p, a, b, c : (q, 3) ndarray of float64

    Returns
    -------
    (q, 3) ndarray of float64
        Degenerate (zero-area) triangles give the closest point of their edges.
    """
    ab, ac = b - a, c - a
    ap, bp, cp = p - a, p - b, p - c
    d1, d2 = _dot(ab, ap), _dot(ac, ap)
    d3, d4 = _dot(ab, bp), _dot(ac, bp)
    d5, d6 = _dot(ab, cp), _dot(ac, cp)
    va, vb, vc = d3 * d6 - d5 * d4, d5 * d2 - d1 * d6, d1 * d4 - d3 * d2
    with np.errstate(invalid="ignore", divide="ignore"):
        on_ab = a + (d1 / (d1 - d3))[:, None] * ab
        on_ac = a + (d2 / (d2 - d6))[:, None] * ac
        on_bc = b + ((d4 - d3) / ((d4 - d3) + (d5 - d6)))[:, None] * (c - b)
        denominator = va + vb + vc
        inside = a + (vb / denominator)[:, None] * ab + (vc / denominator)[:, None] * ac
    conditions = [
        ((d1 <= 0) & (d2 <= 0))[:, None],
        ((d3 >= 0) & (d4 <= d3))[:, None],
        ((vc <= 0) & (d1 >= 0) & (d3 <= 0))[:, None],
        ((d6 >= 0) & (d5 <= d6))[:, None],
        ((vb <= 0) & (d2 >= 0) & (d6 <= 0))[:, None],
        ((va <= 0) & (d4 - d3 >= 0) & (d5 - d6 >= 0))[:, None],
    ]
    result: FloatArray = np.select(conditions, [a, b, on_ab, c, on_ac, on_bc], inside)
    bad = ~np.all(np.isfinite(result), axis=1)
    if np.any(bad):  # zero-area triangle not caught by the region tests: nearest of its edges
        q = p[bad]
        edges = [closest_on_segments(q, u[bad], v[bad]) for u, v in ((a, b), (b, c), (c, a))]
        distances = np.stack([np.linalg.norm(e - q, axis=1) for e in edges])
        result[bad] = np.stack(edges)[np.argmin(distances, axis=0), np.arange(len(q))]
    return result


def _pairs_within(tree: cKDTree, points: FloatArray, radii: FloatArray) -> tuple[IntArray, IntArray]:
    """All (i, j) with tree point j within ``radii[i]`` of ``points[i]``; i ascending."""
    lists = tree.query_ball_point(points, radii, return_sorted=False)
    counts = np.fromiter((len(x) for x in lists), dtype=np.int64, count=len(points))
    total = int(counts.sum())
    rows = np.repeat(np.arange(len(points), dtype=np.int64), counts)
    cols = np.fromiter((j for x in lists for j in x), dtype=np.int64, count=total)
    return rows, cols


class _Nearest:
    """Exact nearest-primitive search for primitives with a centre, a bounding radius and a closest-point function.

    Parameters
    ----------
    centres : (s, 3) ndarray of float64
    radii : (s,) ndarray of float64
        Every point of primitive j is within ``radii[j]`` of ``centres[j]``.
    closest : callable (points (q, 3), primitive indices (q,)) -> (q, 3)
    """

    def __init__(
        self, centres: FloatArray, radii: FloatArray, closest: Callable[[FloatArray, IntArray], FloatArray]
    ) -> None:
        self.centres = centres
        self.radii = radii
        self.closest = closest
        self.tree = cKDTree(centres)
        # primitives in classes of similar radius, a tree each: a few large (sliver) ones then widen the
        # search of their class only
        bounds = np.unique(np.quantile(radii, [0.5, 0.9, 0.99, 1.0]))
        label = np.searchsorted(bounds, radii)
        self.classes: list[tuple[cKDTree, IntArray, float]] = []
        for c in range(len(bounds)):
            members = np.flatnonzero(label == c).astype(np.int64)
            if len(members):
                self.classes.append((cKDTree(centres[members]), members, float(radii[members].max())))

    def query(self, points: FloatArray) -> tuple[FloatArray, FloatArray, IntArray]:
        """Closest points (p, 3), distances (p,), primitive index (p,)."""
        n = len(points)
        k = min(4, len(self.centres))
        best = np.empty((n, 3))
        dist = np.full(n, np.inf)
        index = np.zeros(n, dtype=np.int64)
        step = max(1, _CHUNK_PAIRS // 16)
        for start in range(0, n, step):
            block = points[start : start + step]
            _, seeds = self.tree.query(block, k=k)
            seeds = np.asarray(seeds, dtype=np.int64).reshape(len(block), k)
            rows = np.repeat(np.arange(len(block)), k)
            self._update(
                block,
                rows,
                seeds.ravel(),
                best[start : start + step],
                dist[start : start + step],
                index[start : start + step],
            )
            for tree, members, largest in self.classes:
                bound = dist[start : start + step] * (1 + 1e-12)
                rows, local = _pairs_within(tree, block, bound + largest)
                cols = members[local]
                # lower bound |p - centre| - radius must not exceed the best distance found
                gap = np.linalg.norm(block[rows] - self.centres[cols], axis=1) - self.radii[cols]
                keep = gap <= bound[rows]
                rows, cols = rows[keep], cols[keep]
                for s in range(0, len(rows), _CHUNK_PAIRS):
                    self._update(
                        block,
                        rows[s : s + _CHUNK_PAIRS],
                        cols[s : s + _CHUNK_PAIRS],
                        best[start : start + step],
                        dist[start : start + step],
                        index[start : start + step],
                    )
        return best, dist, index

    def _update(
        self, block: FloatArray, rows: IntArray, cols: IntArray, best: FloatArray, dist: FloatArray, index: IntArray
    ) -> None:
        """Improve best/dist/index (views of one block) with the candidate pairs (rows, cols)."""
        if len(rows) == 0:
            return
        q = self.closest(block[rows], cols)
        d = np.linalg.norm(q - block[rows], axis=1)
        order = np.lexsort((d, rows))  # by point, then distance
        first = np.ones(len(order), dtype=bool)
        first[1:] = rows[order][1:] != rows[order][:-1]
        pick = order[first]
        r = rows[pick]
        better = d[pick] < dist[r]
        r, pick = r[better], pick[better]
        best[r] = q[pick]
        dist[r] = d[pick]
        index[r] = cols[pick]


def _triangle_search(xyz: FloatArray, tri: IntArray) -> _Nearest:
    corners = xyz[tri]
    centroids = corners.mean(axis=1)
    radii = np.linalg.norm(corners - centroids[:, None, :], axis=2).max(axis=1)

    def closest(points: FloatArray, which: IntArray) -> FloatArray:
        t = corners[which]
        return closest_on_triangles(points, t[:, 0], t[:, 1], t[:, 2])

    return _Nearest(centroids, radii, closest)


@dataclass(frozen=True)
class ClosestPoints:
    """Closest points of query points on a triangle mesh.

    Attributes
    ----------
    points : (p, 3) ndarray of float64
        The closest point of each query point.
    distances : (p,) ndarray of float64
    triangles : (p,) ndarray of int64
        Index of the triangle holding each closest point (one of them when
        several are equally close).
    """

    points: FloatArray
    distances: FloatArray
    triangles: IntArray


def closest_points(points: npt.ArrayLike, vertices: npt.ArrayLike, triangles: npt.ArrayLike) -> ClosestPoints:
    """Exact closest points of ``points`` on the triangle mesh (vertices, triangles).

    Parameters
    ----------
    points : (p, 3) array_like of float
    vertices : (n, 3) array_like of float
    triangles : (m, 3) array_like of int, m >= 1

    Returns
    -------
    ClosestPoints

    Raises
    ------
    ProjectionError
        Wrong shapes, non-finite values, indices out of range.
    """
    query = as_points(points, "query points", ProjectionError)
    xyz, tri = _as_mesh(vertices, triangles, "the mesh")
    if len(query) == 0:
        return ClosestPoints(np.empty((0, 3)), np.empty(0), np.empty(0, dtype=np.int64))
    best, dist, index = _triangle_search(xyz, tri).query(query)
    return ClosestPoints(best, dist, index)


class ControllingSurface:
    """A triangle mesh that border vertices can be attached to (they stay on it during the evolution).

    Parameters
    ----------
    vertices : (n, 3) array_like of float
    triangles : (m, 3) array_like of int
    name : str, optional
        Used in error messages.

    Raises
    ------
    ProjectionError
    """

    def __init__(self, vertices: npt.ArrayLike, triangles: npt.ArrayLike, *, name: str | None = None) -> None:
        self.name = name
        label = f"controlling surface {name!r}" if name else "a controlling surface"
        self.vertices, self.triangles = _as_mesh(vertices, triangles, label)
        self._search: _Nearest | None = None

    @property
    def label(self) -> str:
        """How messages name the surface."""
        return f"controlling surface {self.name!r}" if self.name else "controlling surface"

    @property
    def scale(self) -> float:
        """Diagonal of the bounding box."""
        return float(np.linalg.norm(self.vertices.max(axis=0) - self.vertices.min(axis=0)))

    def closest(self, points: npt.ArrayLike) -> ClosestPoints:
        """Closest points on the surface; see :func:`closest_points`."""
        query = as_points(points, "query points", ProjectionError)
        if self._search is None:
            self._search = _triangle_search(self.vertices, self.triangles)
        if len(query) == 0:
            return ClosestPoints(np.empty((0, 3)), np.empty(0), np.empty(0, dtype=np.int64))
        best, dist, index = self._search.query(query)
        return ClosestPoints(best, dist, index)

    def project(self, points: npt.ArrayLike) -> FloatArray:
        """(p, 3): the closest point on the surface of each point."""
        return self.closest(points).points

    def distance(self, points: npt.ArrayLike) -> FloatArray:
        """(p,): the distance of each point from the surface."""
        return self.closest(points).distances


def _plane_crossings(corners: FloatArray, signed: FloatArray) -> tuple[FloatArray, FloatArray, BoolArray]:
    """Where triangles cross a plane, given the signed distances of their corners.

    Parameters
    ----------
    corners : (q, 3, 3)
    signed : (q, 3), exact zeros for corners on the plane

    Returns
    -------
    first, second : (q, 3)
        The two ends of each triangle's intersection with the plane.
    ok : (q,) bool
        False where the triangle only touches the plane at one corner.
    """
    q = len(corners)
    candidates = np.zeros((q, 6, 3))
    valid = np.zeros((q, 6), dtype=bool)
    for k in range(3):
        j = (k + 1) % 3
        candidates[:, 2 * k] = corners[:, k]
        valid[:, 2 * k] = signed[:, k] == 0
        sk, sj = signed[:, k], signed[:, j]
        crossing = sk * sj < 0
        with np.errstate(invalid="ignore", divide="ignore"):
            t = np.where(crossing, sk / (sk - sj), 0.0)
        candidates[:, 2 * k + 1] = corners[:, k] + t[:, None] * (corners[:, j] - corners[:, k])
        valid[:, 2 * k + 1] = crossing
    order = np.argsort(~valid, axis=1, kind="stable")
    rows = np.arange(q)
    ok = valid.sum(axis=1) >= 2
    return candidates[rows, order[:, 0]], candidates[rows, order[:, 1]], ok


def _triangle_pairs(
    a_xyz: FloatArray, a_tri: IntArray, b_xyz: FloatArray, b_tri: IntArray
) -> tuple[IntArray, IntArray]:
    """Triangle pairs (i of A, j of B) whose bounding boxes overlap."""
    a_corners, b_corners = a_xyz[a_tri], b_xyz[b_tri]
    a_centres, b_centres = a_corners.mean(axis=1), b_corners.mean(axis=1)
    a_radii = np.linalg.norm(a_corners - a_centres[:, None], axis=2).max(axis=1)
    b_radii = np.linalg.norm(b_corners - b_centres[:, None], axis=2).max(axis=1)
    rows, cols = _pairs_within(cKDTree(b_centres), a_centres, a_radii + b_radii.max())
    keep = np.linalg.norm(a_centres[rows] - b_centres[cols], axis=1) <= a_radii[rows] + b_radii[cols]
    rows, cols = rows[keep], cols[keep]
    overlap = np.all(
        (a_corners[rows].min(axis=1) <= b_corners[cols].max(axis=1))
        & (b_corners[cols].min(axis=1) <= a_corners[rows].max(axis=1)),
        axis=1,
    )
    return rows[overlap], cols[overlap]


def intersection_segments(a: ControllingSurface, b: ControllingSurface) -> FloatArray:
    """Segments where the triangles of two meshes cross, (s, 2, 3); touching and coplanar pairs give none.

    Corners within ``1e-12`` times the scale of a triangle's plane count as on
    it, so that a curve passing through vertices or along edges is found once
    per crossing rather than missed.
    """
    scale = max(a.scale, b.scale, np.finfo(float).tiny)
    eps = 1e-12 * scale
    rows, cols = _triangle_pairs(a.vertices, a.triangles, b.vertices, b.triangles)
    ta, tb = a.vertices[a.triangles[rows]], b.vertices[b.triangles[cols]]

    def plane(t: FloatArray) -> tuple[FloatArray, FloatArray]:
        normal = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])
        length = np.linalg.norm(normal, axis=1)
        with np.errstate(invalid="ignore", divide="ignore"):
            unit = normal / length[:, None]
        return unit, length

    na, la = plane(ta)
    nb, lb = plane(tb)
    sa = np.einsum("qkj,qj->qk", ta - tb[:, :1], nb)  # corners of A against the plane of B
    sb = np.einsum("qkj,qj->qk", tb - ta[:, :1], na)
    sa[np.abs(sa) <= eps] = 0.0
    sb[np.abs(sb) <= eps] = 0.0
    direction = np.cross(na, nb)
    dlen = np.linalg.norm(direction, axis=1)
    candidate = (
        (la > 0)
        & (lb > 0)
        & (dlen > 1e-12)
        & ~np.all(sa > 0, axis=1)
        & ~np.all(sa < 0, axis=1)
        & ~np.all(sb > 0, axis=1)
        & ~np.all(sb < 0, axis=1)
    )
    ta, tb, sa, sb, direction = ta[candidate], tb[candidate], sa[candidate], sb[candidate], direction[candidate]
    a0, a1, ok_a = _plane_crossings(ta, sa)
    b0, b1, ok_b = _plane_crossings(tb, sb)
    ends = np.stack([a0, a1, b0, b1], axis=1)  # (q, 4, 3) on the common line
    t = np.einsum("qkj,qj->qk", ends, direction)
    lo_a, hi_a = np.minimum(t[:, 0], t[:, 1]), np.maximum(t[:, 0], t[:, 1])
    lo_b, hi_b = np.minimum(t[:, 2], t[:, 3]), np.maximum(t[:, 2], t[:, 3])
    rows_q = np.arange(len(t))
    start = np.where(lo_a >= lo_b, np.where(t[:, 0] <= t[:, 1], 0, 1), np.where(t[:, 2] <= t[:, 3], 2, 3))
    stop = np.where(hi_a <= hi_b, np.where(t[:, 0] >= t[:, 1], 0, 1), np.where(t[:, 2] >= t[:, 3], 2, 3))
    p0, p1 = ends[rows_q, start], ends[rows_q, stop]
    keep = ok_a & ok_b & (np.maximum(lo_a, lo_b) < np.minimum(hi_a, hi_b)) & (np.linalg.norm(p1 - p0, axis=1) > eps)
    result: FloatArray = np.stack([p0[keep], p1[keep]], axis=1)
    return result


def _chain(segments: FloatArray, tolerance: float) -> tuple[FloatArray, list[IntArray]]:
    """Merge segment ends closer than ``tolerance`` and chain the segments into polylines.

    Returns the merged nodes (q, 3) and each polyline as node indices (a
    closed curve repeats its first node at the end).
    """
    ends = segments.reshape(-1, 3)
    pairs = cKDTree(ends).query_pairs(tolerance, output_type="ndarray")
    graph = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(len(ends), len(ends)))
    _, label = connected_components(graph, directed=False)
    label = np.asarray(label, dtype=np.int64)
    nodes = np.zeros((int(label.max()) + 1 if len(label) else 0, 3))
    np.add.at(nodes, label, ends)
    nodes /= np.bincount(label)[:, None]
    edges = label.reshape(-1, 2)
    edges = edges[edges[:, 0] != edges[:, 1]]
    edges = np.unique(np.sort(edges, axis=1), axis=0)
    neighbours: dict[int, list[int]] = {}
    for u, v in edges.tolist():
        neighbours.setdefault(u, []).append(v)
        neighbours.setdefault(v, []).append(u)
    used: set[tuple[int, int]] = set()
    polylines: list[IntArray] = []
    # open chains start at nodes of odd degree (ends, or branch points); cycles anywhere
    starts = [u for u, n in neighbours.items() if len(n) != 2] + list(neighbours)
    for first in starts:
        for second in neighbours[first]:
            if (min(first, second), max(first, second)) in used:
                continue
            line = [first]
            prev, cur = first, second
            used.add((min(prev, cur), max(prev, cur)))
            line.append(cur)
            while len(neighbours[cur]) == 2 and cur != first:
                nxt = neighbours[cur][0] if neighbours[cur][1] == prev else neighbours[cur][1]
                key = (min(cur, nxt), max(cur, nxt))
                if key in used:
                    break
                used.add(key)
                prev, cur = cur, nxt
                line.append(cur)
            polylines.append(np.asarray(line, dtype=np.int64))
    return nodes, polylines


class IntersectionCurve:
    """The curve where two controlling surfaces meet, as polylines; projection onto it.

    Parameters
    ----------
    first, second : ControllingSurface

    Attributes
    ----------
    nodes : (q, 3) ndarray of float64
        Polyline vertices (segment ends closer than 1e-9 times the surfaces'
        scale merged).
    polylines : list of (r,) ndarray of int64
        Each chain of segments as node indices; a closed curve repeats its
        first node at the end.
    segments : (s, 2, 3) ndarray of float64
        The segments of all polylines.

    Raises
    ------
    ProjectionError
        The surfaces do not cross.
    """

    def __init__(self, first: ControllingSurface, second: ControllingSurface) -> None:
        self.surfaces = (first, second)
        raw = intersection_segments(first, second)
        if len(raw) == 0:
            raise ProjectionError(f"{first.label} and {second.label} do not cross: no intersection curve to attach to")
        tolerance = 1e-9 * max(first.scale, second.scale)
        self.nodes, self.polylines = _chain(raw, tolerance)
        pieces = [np.stack([self.nodes[line[:-1]], self.nodes[line[1:]]], axis=1) for line in self.polylines]
        self.segments: FloatArray = np.concatenate(pieces) if pieces else np.empty((0, 2, 3))
        a, b = self.segments[:, 0], self.segments[:, 1]
        centres = (a + b) / 2
        radii = np.linalg.norm(b - a, axis=1) / 2

        def closest(points: FloatArray, which: IntArray) -> FloatArray:
            return closest_on_segments(points, a[which], b[which])

        self._search = _Nearest(centres, radii, closest)

    def closest(self, points: npt.ArrayLike) -> tuple[FloatArray, FloatArray]:
        """Closest points on the curve (p, 3) and their distances (p,)."""
        query = as_points(points, "query points", ProjectionError)
        if len(query) == 0:
            return np.empty((0, 3)), np.empty(0)
        best, dist, _ = self._search.query(query)
        return best, dist

    def project(self, points: npt.ArrayLike) -> FloatArray:
        """(p, 3): the closest point on the curve of each point."""
        return self.closest(points)[0]


def intersection_curve(first: ControllingSurface, second: ControllingSurface) -> IntersectionCurve:
    """The intersection curve of two controlling surfaces; see :class:`IntersectionCurve`."""
    return IntersectionCurve(first, second)
