"""Parameterisation of disk patches onto a regular polygon, and compatible meshes.

Pure numpy/scipy; see the spec (``shared/spec/interpolation.md``, step 4,
"Calculating").

* :func:`parameterize_patch` maps a disk patch onto the unit regular k-polygon:
  control vertices to the corners, each border path between two of them by
  chord length, the interior by mean value coordinates (Floater 2003), two
  sparse solves. With a convex border and positive weights the map is a
  bijection (no parameter triangle flips).
* :class:`PointLocator` finds many points in a 2D triangle mesh at once with
  barycentric coordinates (exact at vertices and on edges).
* :func:`compatible_patch` maps every source vertex through g_s and then the
  inverse of g_t (the target's parameterisation), giving the source topology
  with every vertex on the target, and refines the source until the error to
  the target is at most the tolerance.

Weights are computed for all triangles at once; the sparse matrices are
assembled through a :class:`WeightPattern`, which fixes the CSR structure of a
topology once so that new weights only fill its value array.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
from scipy.sparse import csc_matrix, csr_matrix, identity
from scipy.sparse.linalg import splu

from tgsis.errors import InvalidInputError
from tgsis.interpolation._arrays import as_points, as_triangles, interior_mask
from tgsis.interpolation.projection import ClosestPoints, closest_points

__all__ = [
    "ParameterizationError",
    "WeightPattern",
    "mean_value_weights",
    "border_loop",
    "polygon_corners",
    "Parameterization",
    "mean_value_embedding",
    "parameterize_patch",
    "PointLocator",
    "locate_points",
    "CompatiblePatch",
    "compatible_patch",
    "mesh_error",
    "sparse_solve",
]

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]

# directed edges (row, column) of a triangle (a, b, c), and the corner whose angle weighs each
_ROW = np.array([0, 0, 1, 1, 2, 2])
_COL = np.array([1, 2, 2, 0, 0, 1])


class ParameterizationError(InvalidInputError):
    """A patch that cannot be parameterised (not a disk, bad control vertices, degenerate triangles) or a
    compatible mesh that cannot be built (points outside the target's parameter domain, refinement that does
    not reach the tolerance)."""


# --------------------------------------------------------------------------- weights


@dataclass(frozen=True)
class WeightPattern:
    """CSR structure of the vertex adjacency of a triangle mesh, fixed once for a topology.

    Attributes
    ----------
    n : int
        Number of vertices.
    indptr : (n + 1,) ndarray of int64
    indices : (nnz,) ndarray of int64
        Columns, ascending within each row; row i holds the neighbours of i.
    rows : (nnz,) ndarray of int64
        Row of each non-zero.
    slots : (m, 6) ndarray of int64
        Non-zero receiving each directed edge (a,b), (a,c), (b,c), (b,a),
        (c,a), (c,b) of each triangle (a, b, c).
    """

    n: int
    indptr: IntArray
    indices: IntArray
    rows: IntArray
    slots: IntArray

    @classmethod
    def of(cls, triangles: npt.ArrayLike, n: int) -> WeightPattern:
        """The pattern of ``triangles`` (m, 3) over ``n`` vertices."""
        tri = as_triangles(triangles, n, "triangles", ParameterizationError)
        keys = tri[:, _ROW] * n + tri[:, _COL]
        unique, inverse = np.unique(keys.ravel(), return_inverse=True)
        rows = unique // n
        indptr = np.zeros(n + 1, dtype=np.int64)
        np.cumsum(np.bincount(rows, minlength=n), out=indptr[1:])
        return cls(n, indptr, unique % n, rows, inverse.reshape(-1, 6).astype(np.int64))

    def matrix(self, data: FloatArray) -> csr_matrix:
        """(n, n) CSR matrix with this pattern and values ``data`` (nnz,)."""
        return csr_matrix((data, self.indices, self.indptr), shape=(self.n, self.n))


def mean_value_data(
    vertices: FloatArray, triangles: IntArray, pattern: WeightPattern, needed: npt.NDArray[np.bool_] | None = None
) -> FloatArray:
    """Mean value coordinates λ_ij as the value array (nnz,) of ``pattern``; rows sum to 1.

    w_ij = (tan(α_{j-1}/2) + tan(α_j/2)) / |v_j - v_i|, λ_ij = w_ij / Σ_k w_ik,
    with tan(α/2) = |e1 × e2| / (|e1| |e2| + e1 · e2) for the angle α at v_i
    between the edges e1, e2 of a triangle (stable for small angles).

    Parameters
    ----------
    vertices : (n, 3) ndarray of float64
    triangles : (m, 3) ndarray of int64
    pattern : WeightPattern
        Of ``triangles``.
    needed : (n,) ndarray of bool, optional
        Rows that must be defined (default: all). A degenerate triangle whose
        corners are all outside them (an ear of three border vertices on a
        straight line, say) contributes nothing; rows left without weight
        are zero.

    Raises
    ------
    ParameterizationError
        A zero-length edge or a zero-area triangle at a needed vertex.
    """
    corners = vertices[triangles]  # (m, 3, 3)
    e1 = corners[:, [1, 2, 0]] - corners  # edge to the next corner
    e2 = corners[:, [2, 0, 1]] - corners  # edge to the previous corner
    l1 = np.linalg.norm(e1, axis=2)
    l2 = np.linalg.norm(e2, axis=2)
    cross = np.linalg.norm(np.cross(e1, e2), axis=2)
    dot = np.einsum("mkj,mkj->mk", e1, e2)
    denominator = l1 * l2 + dot
    bad = np.any((l1 <= 0) | (cross <= 1e-14 * l1 * l2) | (denominator <= 0), axis=1)
    if np.any(bad):
        fatal = bad if needed is None else bad & np.any(needed[triangles], axis=1)
        if np.any(fatal):
            t = int(np.argmax(fatal))
            raise ParameterizationError(
                f"triangle {t} {triangles[t].tolist()} is degenerate (zero length or area): "
                "mean value weights are undefined"
            )
    with np.errstate(invalid="ignore", divide="ignore"):
        half_tan = np.where(bad[:, None], 0.0, cross / denominator)  # (m, 3): tan(α/2) at each corner
        # contributions in the order of _ROW/_COL: (a,b) (a,c) (b,c) (b,a) (c,a) (c,b)
        contributions = np.empty((len(triangles), 6))
        contributions[:, 0::2] = np.where(bad[:, None], 0.0, half_tan / l1)  # corner k to the next corner
        contributions[:, 1::2] = np.where(bad[:, None], 0.0, half_tan / l2)  # corner k to the previous corner
    weights = np.bincount(pattern.slots.ravel(), weights=contributions.ravel(), minlength=len(pattern.indices))
    sums = np.bincount(pattern.rows, weights=weights, minlength=pattern.n)
    result: FloatArray = weights / np.where(sums > 0, sums, 1.0)[pattern.rows]
    return result


def mean_value_weights(vertices: npt.ArrayLike, triangles: npt.ArrayLike) -> csr_matrix:
    """Mean value coordinates of every vertex in its neighbours, as an (n, n) CSR matrix whose rows sum to 1.

    Parameters
    ----------
    vertices : (n, 3) array_like of float
    triangles : (m, 3) array_like of int

    Returns
    -------
    (n, n) scipy.sparse.csr_matrix
        Row i holds λ_ij > 0 for the neighbours j of vertex i.

    Raises
    ------
    ParameterizationError
    """
    xyz = as_points(vertices, "vertices", ParameterizationError)
    tri = as_triangles(triangles, len(xyz), "triangles", ParameterizationError)
    pattern = WeightPattern.of(tri, len(xyz))
    return pattern.matrix(mean_value_data(xyz, tri, pattern))


def sparse_solve(matrix: csc_matrix, rhs: FloatArray) -> FloatArray:
    """Solve ``matrix @ x = rhs`` for one or more right-hand sides with SuperLU.

    Column ordering ``MMD_AT_PLUS_A`` with diagonal pivoting preferred (the
    matrices here, I - λ restricted to interior vertices, are diagonally
    dominant M-matrices, so the symmetric ordering keeps the diagonal).

    Parameters
    ----------
    matrix : (q, q) sparse matrix
    rhs : (q,) or (q, r) ndarray of float64

    Raises
    ------
    ParameterizationError
        A singular matrix.
    """
    try:
        lu = splu(
            csc_matrix(matrix), permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0, options={"SymmetricMode": True}
        )
    except RuntimeError as exc:
        raise ParameterizationError(f"sparse system cannot be solved: {exc}") from exc
    result: FloatArray = lu.solve(np.ascontiguousarray(rhs))
    return result


# --------------------------------------------------------------------------- border


def _directed_edges(tri: IntArray, n: int) -> tuple[IntArray, IntArray]:
    """Half-edges (a, b) of all triangles; raises on non-manifold or inconsistently oriented edges."""
    a = tri.ravel()
    b = tri[:, [1, 2, 0]].ravel()
    keys = a * n + b
    order = np.sort(keys)
    if np.any(order[1:] == order[:-1]):
        key = int(order[1:][order[1:] == order[:-1]][0])
        raise ParameterizationError(
            f"edge ({key // n}, {key % n}) is used twice in the same direction: "
            "triangles not consistently oriented, or an edge with more than two triangles"
        )
    return a, b


def border_loop(triangles: npt.ArrayLike, n: int | None = None) -> IntArray:
    """The border of a disk-shaped triangle mesh as one closed vertex loop.

    Parameters
    ----------
    triangles : (m, 3) array_like of int
        Consistently oriented triangles.
    n : int, optional
        Number of vertices (default: largest index + 1).

    Returns
    -------
    (b,) ndarray of int64
        Border vertices in the direction of the triangles' orientation (a
        counter-clockwise mesh gives a counter-clockwise loop), starting at
        the smallest border vertex.

    Raises
    ------
    ParameterizationError
        Not a topological disk: no border, several border loops, a border
        that touches itself, or holes (Euler characteristic not 1).
    """
    tri = np.ascontiguousarray(triangles, dtype=np.int64)
    count = int(tri.max()) + 1 if n is None else n
    tri = as_triangles(tri, count, "triangles", ParameterizationError)
    a, b = _directed_edges(tri, count)
    keys = a * count + b
    reverse = b * count + a
    sorted_keys = np.sort(keys)
    position = np.minimum(np.searchsorted(sorted_keys, reverse), len(sorted_keys) - 1)
    on_border = sorted_keys[position] != reverse
    start, end = a[on_border], b[on_border]
    if len(start) == 0:
        raise ParameterizationError("the patch has no border (a closed surface is not a disk)")
    outgoing = np.bincount(start, minlength=count)
    if np.any(outgoing > 1):
        raise ParameterizationError(
            f"the border touches itself at vertex {int(np.argmax(outgoing > 1))}: the patch is not a disk"
        )
    following = np.full(count, -1, dtype=np.int64)
    following[start] = end
    first = int(start.min())
    loop = [first]
    current = int(following[first])
    while current != first and len(loop) <= len(start):
        loop.append(current)
        current = int(following[current])
    if len(loop) != len(start):
        raise ParameterizationError(
            f"the border has several loops ({len(loop)} of {len(start)} border edges in the "
            "first): the patch has holes or several parts"
        )
    used = np.unique(tri).size
    edges = (len(keys) + len(start)) // 2
    if used - edges + len(tri) != 1:
        raise ParameterizationError(
            f"the patch is not a disk: Euler characteristic {used - edges + len(tri)} (a disk has 1)"
        )
    return np.asarray(loop, dtype=np.int64)


def polygon_corners(k: int) -> FloatArray:
    """(k, 2): corners (cos(2π(i-1)/k), sin(2π(i-1)/k)), i = 1..k, of the unit regular k-polygon."""
    angles = 2 * np.pi * np.arange(k) / k
    result: FloatArray = np.stack([np.cos(angles), np.sin(angles)], axis=1)
    return result


def _ordered_border(loop: IntArray, controls: IntArray, n: int) -> IntArray:
    """The loop turned to start at controls[0] and to run through the controls in their order."""
    k = len(controls)
    if k < 3:
        raise ParameterizationError(f"a patch needs at least 3 control vertices, got {k}")
    if len(np.unique(controls)) != k:
        raise ParameterizationError(f"control vertices must be distinct, got {controls.tolist()}")
    if controls.min() < 0 or controls.max() >= n:
        raise ParameterizationError(f"control vertices must be vertex indices 0..{n - 1}, got {controls.tolist()}")
    where = np.full(n, -1, dtype=np.int64)
    where[loop] = np.arange(len(loop))
    position = where[controls]
    if np.any(position < 0):
        raise ParameterizationError(
            f"control vertex {int(controls[np.argmax(position < 0)])} is not on the border of the patch"
        )
    b = len(loop)
    forward = (position - position[0]) % b
    backward = (position[0] - position) % b
    if np.all(np.diff(forward) > 0):
        return np.roll(loop, -int(position[0]))
    if np.all(np.diff(backward) > 0):
        return np.roll(loop[::-1], int(position[0]) + 1)
    raise ParameterizationError(f"control vertices {controls.tolist()} are not in the cyclic order of the border")


def _chord_border(xyz: FloatArray, border: IntArray, controls: IntArray) -> FloatArray:
    """(b, 2) parameter points of the border (starting at controls[0]) on the polygon, by chord length."""
    k = len(controls)
    corners = polygon_corners(k)
    is_control = np.zeros(len(xyz), dtype=bool)
    is_control[controls] = True
    closed = np.append(border, border[0])
    lengths = np.linalg.norm(xyz[closed[1:]] - xyz[closed[:-1]], axis=1)
    side = np.cumsum(is_control[border]) - 1  # side index of each border vertex (control i starts side i)
    cumulative = np.concatenate([[0.0], np.cumsum(lengths)])
    side_start = cumulative[:-1][is_control[border]]  # arc length at each control
    side_length = np.diff(np.append(side_start, cumulative[-1]))
    if np.any(side_length <= 0):
        i = int(np.argmax(side_length <= 0))
        raise ParameterizationError(
            f"border path from control vertex {int(controls[i])} to {int(controls[(i + 1) % k])} has zero length"
        )
    s = (cumulative[:-1] - side_start[side]) / side_length[side]
    result: FloatArray = corners[side] + s[:, None] * (corners[(side + 1) % k] - corners[side])
    result[is_control[border]] = corners  # exactly the corners
    return result


# --------------------------------------------------------------------------- parameterisation


@dataclass(frozen=True)
class Parameterization:
    """A disk patch mapped onto the unit regular k-polygon.

    Attributes
    ----------
    uv : (n, 2) ndarray of float64
        Parameter point of each vertex.
    border : (b,) ndarray of int64
        Border loop starting at ``controls[0]``, running through the control
        vertices in their order.
    controls : (k,) ndarray of int64
        Control vertices; ``controls[i]`` sits on corner i of the polygon.
    interior : (n - b,) ndarray of int64
        Interior vertices, ascending.
    orientation : int
        +1 when the triangles are counter-clockwise in the parameter plane,
        -1 when clockwise (controls given against the triangles' orientation).
    """

    uv: FloatArray
    border: IntArray
    controls: IntArray
    interior: IntArray
    orientation: int

    @property
    def corners(self) -> FloatArray:
        """(k, 2): the polygon's corners."""
        return polygon_corners(len(self.controls))


def _split_system(weights: csr_matrix, interior: IntArray, border: IntArray) -> tuple[csc_matrix, csr_matrix]:
    """A = I - λ_II (interior × interior) and λ_IB (interior × border) of a row-normalised weight matrix."""
    rows = weights[interior]
    a = identity(len(interior), format="csc") - csc_matrix(rows[:, interior])
    return a, csr_matrix(rows[:, border])


def mean_value_embedding(
    vertices: npt.ArrayLike, triangles: npt.ArrayLike, fixed: npt.ArrayLike, values: npt.ArrayLike
) -> FloatArray:
    """Values at every vertex: given at ``fixed`` vertices, elsewhere the mean value combination of the neighbours.

    Solves x_i = Σ_j λ_ij x_j for every free vertex i (λ: :func:`mean_value_weights`
    of the 3D mesh), one sparse factorisation for all columns of ``values``.
    With ``fixed`` the border of a disk and ``values`` on a convex polygon
    this is Floater's parameterisation; a planar mesh whose fixed values are
    an affine image of its vertices gets that affine map everywhere (linear
    reproduction).

    Parameters
    ----------
    vertices : (n, 3) array_like of float
    triangles : (m, 3) array_like of int
    fixed : (b,) array_like of int
        Distinct vertices whose values are given; every connected part of the
        mesh must hold one.
    values : (b,) or (b, d) array_like of float

    Returns
    -------
    (n, d) ndarray of float64 ((n,) for 1D ``values``)

    Raises
    ------
    ParameterizationError
    """
    xyz = as_points(vertices, "vertices", ParameterizationError)
    n = len(xyz)
    tri = as_triangles(triangles, n, "triangles", ParameterizationError)
    where = np.ascontiguousarray(fixed, dtype=np.int64).ravel()
    given = np.asarray(values, dtype=np.float64)
    if given.shape[:1] != where.shape or given.ndim not in (1, 2) or not np.all(np.isfinite(given)):
        raise ParameterizationError(
            f"values must be finite with shape ({len(where)},) or ({len(where)}, d), got {given.shape}"
        )
    if len(where) and (where.min() < 0 or where.max() >= n):
        raise ParameterizationError(f"fixed vertices must be vertex indices 0..{n - 1}")
    is_fixed = np.zeros(n, dtype=bool)
    is_fixed[where] = True
    if int(is_fixed.sum()) != len(where):
        raise ParameterizationError("fixed vertices must be distinct")
    free = np.flatnonzero(~is_fixed).astype(np.int64)
    result = np.zeros((n,) + given.shape[1:])
    result[where] = given
    if len(free):
        used = np.zeros(n, dtype=bool)
        used[tri.ravel()] = True
        if not np.all(used[free]):
            raise ParameterizationError(f"vertex {int(free[np.argmin(used[free])])} is not used by any triangle")
        pattern = WeightPattern.of(tri, n)
        a, b = _split_system(pattern.matrix(mean_value_data(xyz, tri, pattern, ~is_fixed)), free, where)
        result[free] = sparse_solve(a, b @ given)
    return result


def parameterize_patch(vertices: npt.ArrayLike, triangles: npt.ArrayLike, controls: npt.ArrayLike) -> Parameterization:
    """Map a disk patch onto the unit regular k-polygon (chord-length border, mean value interior).

    Parameters
    ----------
    vertices : (n, 3) array_like of float
        Every vertex must be used by a triangle.
    triangles : (m, 3) array_like of int
        A consistently oriented topological disk.
    controls : (k,) array_like of int, k >= 3
        Border vertices in their cyclic order along the border (either
        direction); control i goes to corner (cos(2π i/k), sin(2π i/k)).

    Returns
    -------
    Parameterization

    Raises
    ------
    ParameterizationError
        Not a disk, unused vertices, bad control vertices, degenerate
        triangles, a singular system.
    """
    xyz = as_points(vertices, "vertices", ParameterizationError)
    n = len(xyz)
    tri = as_triangles(triangles, n, "triangles", ParameterizationError)
    used = np.zeros(n, dtype=bool)
    used[tri.ravel()] = True
    if not np.all(used):
        raise ParameterizationError(f"vertex {int(np.argmin(used))} is not used by any triangle")
    control = np.ascontiguousarray(controls, dtype=np.int64).ravel()
    loop = border_loop(tri, n)
    border = _ordered_border(loop, control, n)
    is_border = np.zeros(n, dtype=bool)
    is_border[border] = True
    interior = np.flatnonzero(~is_border).astype(np.int64)
    uv = mean_value_embedding(xyz, tri, border, _chord_border(xyz, border, control))
    # + when the border runs with the triangles' orientation (then they are counter-clockwise like the corners)
    where = int(np.flatnonzero(loop == border[0])[0])
    orientation = 1 if loop[(where + 1) % len(loop)] == border[1] else -1
    return Parameterization(uv, border, control, interior, orientation)


# --------------------------------------------------------------------------- point location


def _barycentric(points: FloatArray, corners: FloatArray) -> FloatArray:
    """(q, 3) barycentric coordinates of points (q, 2) in triangles (q, 3, 2), each from its own sub-area.

    A point equal to a corner gets exactly 1 there and 0 elsewhere.
    """

    def area(p: FloatArray, q: FloatArray, r: FloatArray) -> FloatArray:
        result: FloatArray = (q[:, 0] - p[:, 0]) * (r[:, 1] - p[:, 1]) - (q[:, 1] - p[:, 1]) * (r[:, 0] - p[:, 0])
        return result

    a, b, c = corners[:, 0], corners[:, 1], corners[:, 2]
    total = area(a, b, c)
    with np.errstate(invalid="ignore", divide="ignore"):
        result: FloatArray = (
            np.stack([area(points, b, c), area(a, points, c), area(a, b, points)], axis=1) / total[:, None]
        )
    return result


class PointLocator:
    """Locate many points in a 2D triangle mesh (a parameter mesh) with barycentric coordinates.

    A uniform grid over the mesh: every triangle is listed in each cell its
    bounding box (grown by the tolerance) overlaps, so that the triangle
    holding a point, or within the tolerance of it, is among the candidates of
    the point's cell. Each point takes the candidate where its smallest
    barycentric coordinate is largest.

    Parameters
    ----------
    uv : (n, 2) array_like of float
    triangles : (m, 3) array_like of int
    tolerance : float, optional
        Points this far outside every triangle (in parameter units) are still
        located, on the nearest; default 1e-9 times the mesh's extent.
    """

    def __init__(self, uv: npt.ArrayLike, triangles: npt.ArrayLike, tolerance: float | None = None) -> None:
        self.uv = np.ascontiguousarray(uv, dtype=np.float64)
        if self.uv.ndim != 2 or self.uv.shape[1] != 2 or not np.all(np.isfinite(self.uv)):
            raise ParameterizationError(f"parameter points must be finite with shape (n, 2), got {self.uv.shape}")
        self.triangles = as_triangles(triangles, len(self.uv), "triangles", ParameterizationError)
        self.corners = self.uv[self.triangles]  # (m, 3, 2)
        lo, hi = self.corners.min(axis=1), self.corners.max(axis=1)
        extent = float(np.max(hi.max(axis=0) - lo.min(axis=0)))
        self.tolerance = 1e-9 * extent if tolerance is None else float(tolerance)
        lo, hi = lo - self.tolerance, hi + self.tolerance
        self.origin = lo.min(axis=0)
        span = np.maximum(hi.max(axis=0) - self.origin, np.finfo(float).tiny)
        m = len(self.triangles)
        cells = max(1, int(np.ceil(np.sqrt(m))))
        while True:
            self.shape = np.maximum(1, np.ceil(cells * span / span.max()).astype(np.int64))
            self.size = span / self.shape
            first = self._cell(lo)
            last = self._cell(hi)
            widths = last - first + 1
            counts = widths[:, 0] * widths[:, 1]
            if counts.sum() <= 16 * m + 64 or cells == 1:
                break
            cells = max(1, cells // 2)
        owner = np.repeat(np.arange(m, dtype=np.int64), counts)
        offset = np.arange(int(counts.sum()), dtype=np.int64) - np.repeat(np.cumsum(counts) - counts, counts)
        cx = first[owner, 0] + offset % widths[owner, 0]
        cy = first[owner, 1] + offset // widths[owner, 0]
        cell = cy * self.shape[0] + cx
        order = np.argsort(cell, kind="stable")
        self.cell_triangles = owner[order]
        self.cell_start = np.zeros(int(self.shape.prod()) + 1, dtype=np.int64)
        np.cumsum(np.bincount(cell, minlength=int(self.shape.prod())), out=self.cell_start[1:])

    def _cell(self, points: FloatArray) -> IntArray:
        index = np.floor((points - self.origin) / self.size).astype(np.int64)
        result: IntArray = np.clip(index, 0, self.shape - 1)
        return result

    def locate(self, points: npt.ArrayLike) -> tuple[IntArray, FloatArray, FloatArray]:
        """Triangle and barycentric coordinates of each point.

        Parameters
        ----------
        points : (p, 2) array_like of float

        Returns
        -------
        triangle : (p,) ndarray of int64
            Triangle holding the point, -1 where none is within the tolerance.
        bary : (p, 3) ndarray of float64
            Barycentric coordinates in that triangle, non-negative, summing
            to 1 (a point slightly outside is put on the triangle's border).
        distance : (p,) ndarray of float64
            Distance from the point to the located triangle (0 inside; inf
            where not found).
        """
        query = np.ascontiguousarray(points, dtype=np.float64).reshape(-1, 2)
        p = len(query)
        triangle = np.full(p, -1, dtype=np.int64)
        bary = np.zeros((p, 3))
        distance = np.full(p, np.inf)
        if p == 0:
            return triangle, bary, distance
        cxy = self._cell(query)
        cell = cxy[:, 1] * self.shape[0] + cxy[:, 0]
        counts = self.cell_start[cell + 1] - self.cell_start[cell]
        step = max(1, (1 << 21) // max(1, int(counts.max())))
        for s in range(0, p, step):
            c, k = cell[s : s + step], counts[s : s + step]
            rows = np.repeat(np.arange(s, s + len(c), dtype=np.int64), k)
            offset = np.arange(int(k.sum()), dtype=np.int64) - np.repeat(np.cumsum(k) - k, k)
            cand = self.cell_triangles[self.cell_start[c].repeat(k) + offset]
            coords = _barycentric(query[rows], self.corners[cand])
            score = np.nan_to_num(coords.min(axis=1), nan=-np.inf)
            order = np.lexsort((-score, rows))  # by point, best score first
            first = np.ones(len(order), dtype=bool)
            first[1:] = rows[order][1:] != rows[order][:-1]
            pick = order[first]
            r = rows[pick]
            chosen = np.clip(np.nan_to_num(coords[pick], nan=0.0), 0.0, None)
            total = chosen.sum(axis=1)
            chosen = np.where(total[:, None] > 0, chosen / np.where(total > 0, total, 1.0)[:, None], 1.0 / 3)
            placed = np.einsum("qk,qkj->qj", chosen, self.corners[cand[pick]])
            gap = np.where(score[pick] >= 0, 0.0, np.linalg.norm(placed - query[r], axis=1))
            ok = gap <= self.tolerance
            triangle[r[ok]] = cand[pick][ok]
            bary[r[ok]] = chosen[ok]
            distance[r[ok]] = gap[ok]
        return triangle, bary, distance


def locate_points(
    points: npt.ArrayLike, uv: npt.ArrayLike, triangles: npt.ArrayLike, tolerance: float | None = None
) -> tuple[IntArray, FloatArray]:
    """Triangle (p,) and barycentric coordinates (p, 3) of 2D points in a 2D mesh; -1 where outside.

    See :class:`PointLocator`.
    """
    triangle, bary, _ = PointLocator(uv, triangles, tolerance).locate(points)
    return triangle, bary


# --------------------------------------------------------------------------- compatible meshes


def mesh_error(
    a_vertices: npt.ArrayLike, a_triangles: npt.ArrayLike, b_vertices: npt.ArrayLike, b_triangles: npt.ArrayLike
) -> float:
    """The error between meshes A and B: the larger of the largest distance from an interior vertex of A to B
    and from an interior vertex of B to A (border vertices are not counted).

    Parameters
    ----------
    a_vertices, b_vertices : (n, 3) array_like of float
    a_triangles, b_triangles : (m, 3) array_like of int
    """
    ax = as_points(a_vertices, "vertices", ParameterizationError)
    bx = as_points(b_vertices, "vertices", ParameterizationError)
    at = as_triangles(a_triangles, len(ax), "triangles", ParameterizationError)
    bt = as_triangles(b_triangles, len(bx), "triangles", ParameterizationError)
    d_ab = closest_points(ax[interior_mask(at, len(ax))], bx, bt).distances
    d_ba = closest_points(bx[interior_mask(bt, len(bx))], ax, at).distances
    return float(max(d_ab.max(initial=0.0), d_ba.max(initial=0.0)))


@dataclass(frozen=True)
class CompatiblePatch:
    """A source patch, refined, and its compatible mesh on the target.

    Attributes
    ----------
    source_vertices : (n, 3) ndarray of float64
        The source's vertices followed by those refinement added (each inside
        a source triangle, so the source's shape is unchanged).
    triangles : (m, 3) ndarray of int64
        The refined source topology, shared by the compatible mesh.
    target_positions : (n, 3) ndarray of float64
        Compatible mesh L_st: each vertex's image on the target.
    source_uv : (n, 2) ndarray of float64
        Parameter point of each vertex (g_s).
    source : Parameterization
        Of the original (unrefined) source.
    target : Parameterization
        Of the target.
    error : float
        Error between L_st and the target (interior vertices only).
    rounds : int
        Refinement rounds done.
    """

    source_vertices: FloatArray
    triangles: IntArray
    target_positions: FloatArray
    source_uv: FloatArray
    source: Parameterization
    target: Parameterization
    error: float
    rounds: int


def _map_to_target(uv: FloatArray, locator: PointLocator, target_xyz: FloatArray) -> FloatArray:
    """3D points of the target at parameter points ``uv`` (the inverse of g_t)."""
    triangle, bary, _ = locator.locate(uv)
    if np.any(triangle < 0):
        i = int(np.argmax(triangle < 0))
        raise ParameterizationError(
            f"{int(np.sum(triangle < 0))} parameter points fall outside the target's "
            f"parameter mesh (first: {uv[i].tolist()})"
        )
    result: FloatArray = np.einsum("pk,pkj->pj", bary, target_xyz[locator.triangles[triangle]])
    return result


def _plan_splits(
    tri: IntArray, lengths: FloatArray, held: IntArray, order: IntArray, method: str
) -> tuple[IntArray, IntArray, IntArray]:
    """Which triangles to split at their centroid and which interior edges at their midpoint, this round.

    ``held`` (f,) are the triangles holding the closest points of the target
    vertices that are too far, ``order`` the processing order (farthest
    first), ``lengths`` (m, 3) the length of edge k -> k+1 of each triangle.
    With ``method="centroid"`` every such triangle is split at its centroid
    (the spec's rule). With ``"auto"`` a triangle whose longest edge is
    interior has that edge split at its midpoint instead (both triangles of
    the edge into two: longest-edge bisection, which shrinks the triangles
    where centroid splits leave every old edge in place); a longest edge on
    the border (shared with the neighbouring patch) is never split, that
    triangle is split at its centroid. No triangle is split twice in a round.

    Returns centroid-split triangles (c,), split edges (e, 2) and, for each
    split edge, its two triangles (e, 2).
    """
    n = int(tri.max()) + 1
    used = np.zeros(len(tri), dtype=bool)
    centroid: list[int] = []
    edges: list[tuple[int, int]] = []
    owners: list[tuple[int, int]] = []
    a = tri.ravel()
    b = tri[:, [1, 2, 0]].ravel()
    keys = np.minimum(a, b) * n + np.maximum(a, b)
    sort = np.argsort(keys, kind="stable")
    sorted_keys = keys[sort]
    for t in held[order].tolist():
        if used[t]:
            continue
        if method == "auto":
            k = int(np.argmax(lengths[t]))
            u, v = int(tri[t, k]), int(tri[t, (k + 1) % 3])
            key = min(u, v) * n + max(u, v)
            lo, hi = np.searchsorted(sorted_keys, [key, key + 1])
            if hi - lo == 2:  # an interior edge: split it if both its triangles are free
                pair = sort[lo:hi] // 3
                if not used[pair].any():
                    used[pair] = True
                    edges.append((u, v))
                    owners.append((int(pair[0]), int(pair[1])))
                continue
        used[t] = True
        centroid.append(t)
    return (
        np.asarray(centroid, dtype=np.int64),
        np.asarray(edges, dtype=np.int64).reshape(-1, 2),
        np.asarray(owners, dtype=np.int64).reshape(-1, 2),
    )


def _split_edges(tri: IntArray, edges: IntArray, owners: IntArray, new: IntArray) -> IntArray:
    """Triangles with each edge (u, v) of ``edges`` split at the new vertex ``new[i]``, both of its triangles."""
    if len(edges) == 0:
        return tri
    tri = tri.copy()
    added = []
    for side in range(2):
        t = owners[:, side]
        corners = tri[t]
        # rotate each triangle so that the split edge is its first one, (x, y, z) with {x, y} = {u, v}
        opposite = np.argmax((corners != edges[:, :1]) & (corners != edges[:, 1:]), axis=1)
        shift = (opposite + 1) % 3
        rows = np.arange(len(t))[:, None]
        rotated = corners[rows, (shift[:, None] + np.arange(3)) % 3]
        x, y, z = rotated[:, 0], rotated[:, 1], rotated[:, 2]
        tri[t] = np.stack([x, new, z], axis=1)
        added.append(np.stack([new, y, z], axis=1))
    return np.concatenate([tri, *added])


def _refinement_error(
    error: float,
    tolerance: float,
    rounds: int,
    to_source: ClosestPoints,
    to_target: FloatArray,
    target_index: IntArray,
    tri: IntArray,
    is_interior: npt.NDArray[np.bool_],
) -> ParameterizationError:
    """What to say when refinement stops above the tolerance: which vertex, and why if it can be told."""
    head = (
        f"the compatible mesh is still {error:.6g} from the target after {rounds} refinement rounds "
        f"(tolerance {tolerance:.6g})"
    )
    if to_source.distances.max(initial=0.0) < to_target.max(initial=0.0):
        return ParameterizationError(f"{head}: compatible vertices off the target (numerical trouble)")
    worst = int(np.argmax(to_source.distances))
    where = (
        f"; the farthest is target vertex {int(target_index[worst])} at {np.round(to_source.points[worst], 6).tolist()}"
    )
    if not np.all(is_interior[tri[to_source.triangles[worst]]]):
        return ParameterizationError(
            head + where + ", next to the patch border",
            hint="refinement never splits patch borders (the neighbouring patch must still match): give the source "
            "border more vertices where the target's border bends, or raise the tolerance",
        )
    return ParameterizationError(head + where, hint="raise the tolerance or the number of rounds")


def compatible_patch(
    source_vertices: npt.ArrayLike,
    source_triangles: npt.ArrayLike,
    source_controls: npt.ArrayLike,
    target_vertices: npt.ArrayLike,
    target_triangles: npt.ArrayLike,
    target_controls: npt.ArrayLike,
    tolerance: float,
    *,
    max_rounds: int = 30,
    split: str = "auto",
) -> CompatiblePatch:
    """The compatible mesh of a source patch on a target patch, refined until the error is at most ``tolerance``.

    Both patches are parameterised onto the same polygon (source control i
    and target control i on corner i). Every source vertex goes through g_s
    and then the inverse of g_t (located in the target's parameter mesh,
    barycentric interpolation of the target's vertices), giving L_st with the
    source topology and every vertex on the target. While some interior
    target vertex is farther than ``tolerance`` from L_st, each source
    triangle holding the closest point of such a vertex is split into three
    at its centroid: the new vertex is the centroid of the 3D triangle (the
    source's shape does not change) and, g_s being linear on the triangle,
    its parameter point is the centroid of the parameter triangle. With
    ``split="auto"`` a triangle whose longest edge (on L_st) is interior has
    that edge split at its midpoint instead (on the source, parameter point
    the parameter edge's midpoint). Only the new vertices are mapped; a
    round splits each triangle at most once, farthest target vertices first.

    Parameters
    ----------
    source_vertices : (ns, 3) array_like of float
    source_triangles : (ms, 3) array_like of int
    source_controls : (k,) array_like of int
    target_vertices : (nt, 3) array_like of float
    target_triangles : (mt, 3) array_like of int
    target_controls : (k,) array_like of int
        Paired with ``source_controls`` in order.
    tolerance : float
        ε > 0, in the meshes' length unit.
    max_rounds : int
        Refinement rounds before giving up.
    split : {"auto", "centroid"}
        ``"centroid"``: always the spec's rule (split the triangle holding
        the closest point at its centroid). Centroid splits never shorten an
        existing edge, so the error can stall above the tolerance where the
        target bends across an edge of L_st; ``"auto"`` (default) bisects
        the longest edge of the triangle when it is interior (see above).
        Patch borders are never split, so neighbouring patches still match.

    Returns
    -------
    CompatiblePatch

    Raises
    ------
    ParameterizationError
        Either patch cannot be parameterised, the control vertex counts
        differ, or the error is still above ``tolerance`` after
        ``max_rounds`` rounds.
    """
    if not tolerance > 0:
        raise ParameterizationError(f"tolerance must be positive, got {tolerance!r}")
    if split not in ("auto", "centroid"):
        raise ParameterizationError(f"split must be 'auto' or 'centroid', got {split!r}")
    sx = as_points(source_vertices, "source vertices", ParameterizationError)
    tx = as_points(target_vertices, "target vertices", ParameterizationError)
    st = as_triangles(source_triangles, len(sx), "source triangles", ParameterizationError)
    tt = as_triangles(target_triangles, len(tx), "target triangles", ParameterizationError)
    sc = np.ascontiguousarray(source_controls, dtype=np.int64).ravel()
    tc = np.ascontiguousarray(target_controls, dtype=np.int64).ravel()
    if len(sc) != len(tc):
        raise ParameterizationError(f"source has {len(sc)} control vertices, target {len(tc)}: they must pair up")
    gs = parameterize_patch(sx, st, sc)
    gt = parameterize_patch(tx, tt, tc)
    locator = PointLocator(gt.uv, tt)
    target_index = np.flatnonzero(interior_mask(tt, len(tx)))
    target_interior = tx[target_index]
    xyz, uv, tri = sx, gs.uv, st
    positions = _map_to_target(uv, locator, tx)
    is_interior = interior_mask(st, len(sx))
    rounds = 0
    while True:
        to_source = closest_points(target_interior, positions, tri)
        to_target = closest_points(positions[is_interior], tx, tt).distances
        error = float(max(to_source.distances.max(initial=0.0), to_target.max(initial=0.0)))
        if error <= tolerance:
            return CompatiblePatch(xyz, tri, positions, uv, gs, gt, error, rounds)
        far = np.flatnonzero(to_source.distances > tolerance)
        if rounds == max_rounds or len(far) == 0:
            raise _refinement_error(error, tolerance, rounds, to_source, to_target, target_index, tri, is_interior)
        rounds += 1
        held = to_source.triangles[far]
        order = np.argsort(-to_source.distances[far], kind="stable")
        corners = positions[tri]
        lengths = np.linalg.norm(corners[:, [1, 2, 0]] - corners, axis=2)
        centroid, edges, owners = _plan_splits(tri, lengths, held, order, split)
        n = len(xyz)
        at_centroid = np.arange(n, n + len(centroid), dtype=np.int64)
        at_middle = np.arange(n + len(centroid), n + len(centroid) + len(edges), dtype=np.int64)
        old = tri[centroid]
        xyz = np.concatenate([xyz, xyz[old].mean(axis=1), xyz[edges].mean(axis=1)])
        uv = np.concatenate([uv, uv[old].mean(axis=1), uv[edges].mean(axis=1)])
        positions = np.concatenate([positions, _map_to_target(uv[n:], locator, tx)])
        tri = tri.copy()
        tri[centroid] = np.stack([old[:, 0], old[:, 1], at_centroid], axis=1)
        tri = np.concatenate(
            [
                tri,
                np.stack([old[:, 1], old[:, 2], at_centroid], axis=1),
                np.stack([old[:, 2], old[:, 0], at_centroid], axis=1),
            ]
        )
        tri = _split_edges(tri, edges, owners, at_middle)
        is_interior = np.concatenate([is_interior, np.ones(len(xyz) - n, dtype=bool)])
