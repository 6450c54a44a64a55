"""Trajectories between a source mesh and its compatible target mesh, and the evolving surface they make.

Pure numpy/scipy; see the spec (``shared/spec/interpolation.md``, step 4,
"trajectories").

* Border vertices without constraint follow linear trajectories; a border
  vertex attached to one controlling surface follows its linear trajectory
  projected onto that surface, attached to two onto their intersection curve
  (the first and last samples are the given positions, which must lie on the
  surface or curve).
* Interior vertices: at every intermediate step t = 2..m-1 each is the convex
  combination of its neighbours with λ^t = λ^1 + s (λ^m - λ^1), s = (t-1)/(m-1),
  where λ^1 and λ^m are the mean value weights of the first and last mesh; the
  border at step t comes from the border trajectories; one sparse solve per
  step. The matrix of every step has the same sparsity pattern, built once;
  each step only fills its values and factorises afresh (SuperLU, the
  ``MMD_AT_PLUS_A`` column ordering found at the first step and reused),
  which measured faster than a warm-started BiCGSTAB preconditioned by one
  factorisation (``bench/interp_solvers.py``).
* :func:`evolving_surface` turns the trajectories into a
  :class:`tgsis.temporal.EvolvingSurface` with m evenly spaced instants.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence

import numpy as np
import numpy.typing as npt
from scipy.sparse import csc_matrix, csr_matrix
from scipy.sparse.linalg import splu

from tgsis.errors import InvalidInputError
from tgsis.interpolation._arrays import as_points, as_triangles, interior_mask
from tgsis.interpolation.parameterize import (
    WeightPattern,
    ParameterizationError,
    mean_value_data,
)
from tgsis.interpolation.projection import ControllingSurface, IntersectionCurve
from tgsis.temporal import EvolvingSurface, TopologyPeriod, even_times

__all__ = ["TrajectoryError", "Attachments", "border_trajectories", "InteriorSteps", "vertex_trajectories",
           "evolving_surface"]

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]
BoolArray = npt.NDArray[np.bool_]

#: Border vertex index -> the one or two controlling surfaces it is attached to.
Attachments = Mapping[int, Sequence[ControllingSurface]]


class TrajectoryError(InvalidInputError):
    """Trajectories that cannot be built: bad step count, meshes that do not match, attachments on interior
    vertices, to more than two surfaces, or to a surface (curve) the vertex is not on at the start or end."""


def _check_steps(steps: int) -> int:
    if isinstance(steps, bool) or not isinstance(steps, (int, np.integer)) or steps < 2:
        raise TrajectoryError(f"trajectories need m >= 2 samples, got {steps!r}")
    return int(steps)


def _linear(start: FloatArray, end: FloatArray, steps: int) -> FloatArray:
    """(steps, p, 3): w_j = v + (j-1)/(m-1) (u - v), exactly v and u at the ends."""
    s = np.arange(steps, dtype=np.float64) / (steps - 1)
    result: FloatArray = start[None] + s[:, None, None] * (end - start)[None]
    result[0], result[-1] = start, end
    return result


def _constraint(surfaces: Sequence[ControllingSurface]) -> tuple[
        str, Callable[[FloatArray], tuple[FloatArray, FloatArray]]]:
    """How messages name what a vertex is attached to, and its closest-point function (points, distances)."""
    if len(surfaces) == 1:
        surface = surfaces[0]

        def on_surface(points: FloatArray) -> tuple[FloatArray, FloatArray]:
            found = surface.closest(points)
            return found.points, found.distances

        return surface.label, on_surface
    curve = IntersectionCurve(surfaces[0], surfaces[1])
    return f"the intersection curve of {surfaces[0].label} and {surfaces[1].label}", curve.closest


def border_trajectories(source: npt.ArrayLike, target: npt.ArrayLike, vertices: npt.ArrayLike, steps: int,
                        attachments: Attachments | None = None, *,
                        tolerance: float | None = None) -> FloatArray:
    """Trajectories of border vertices: linear, projected onto controlling surfaces where attached.

    Parameters
    ----------
    source, target : (n, 3) array_like of float
        Positions at the first and last sample of all vertices.
    vertices : (b,) array_like of int
        The border vertices to follow.
    steps : int
        m >= 2 samples per trajectory.
    attachments : mapping of int to sequence of ControllingSurface, optional
        Vertex (one of ``vertices``) -> one surface (the vertex stays on it)
        or two (it stays on their intersection curve).
    tolerance : float, optional
        How far an attached vertex may be from its surface or curve at the
        first and last sample; default 1e-6 times the bounding-box diagonal
        of source and target.

    Returns
    -------
    (steps, b, 3) ndarray of float64
        Exactly the source and target positions at the first and last sample.

    Raises
    ------
    TrajectoryError
        An attached vertex that is not in ``vertices``, with no or more than
        two surfaces, or off its surface (curve) at the start or end;
        surfaces that do not cross.
    """
    m = _check_steps(steps)
    start = as_points(source, "source positions", ParameterizationError)
    end = as_points(target, "target positions", ParameterizationError)
    if start.shape != end.shape:
        raise TrajectoryError(f"source and target positions differ in shape: {start.shape} and {end.shape}")
    which = np.ascontiguousarray(vertices, dtype=np.int64).ravel()
    result = _linear(start[which], end[which], m)
    if not attachments:
        return result
    both = np.concatenate([start, end])
    scale = float(np.linalg.norm(both.max(axis=0) - both.min(axis=0)))
    limit = 1e-6 * scale if tolerance is None else float(tolerance)
    column = {int(v): i for i, v in enumerate(which.tolist())}
    groups: dict[tuple[int, ...], tuple[Sequence[ControllingSurface], list[int]]] = {}
    for vertex, surfaces in attachments.items():
        if int(vertex) not in column:
            raise TrajectoryError(f"vertex {vertex} is attached to a controlling surface but is not a border vertex",
                                  hint="only border vertices take attaching constraints")
        if len(surfaces) not in (1, 2) or not all(isinstance(s, ControllingSurface) for s in surfaces):
            raise TrajectoryError(f"vertex {vertex} must be attached to one or two ControllingSurface objects, "
                                  f"got {len(surfaces)}")
        key = tuple(sorted(id(s) for s in surfaces))
        groups.setdefault(key, (surfaces, []))[1].append(column[int(vertex)])
    for surfaces, columns in groups.values():
        cols = np.asarray(columns, dtype=np.int64)
        label, closest = _constraint(surfaces)
        for sample, name in ((0, "source"), (m - 1, "target")):
            d = closest(result[sample, cols])[1]
            if np.any(d > limit):
                i = int(np.argmax(d))
                raise TrajectoryError(f"vertex {int(which[cols[i]])} is {d[i]:.6g} from {label} in the {name} "
                                      f"mesh (tolerance {limit:.6g}): it cannot stay on it")
        if m > 2:
            inner = result[1:-1, cols].reshape(-1, 3)
            result[1:-1, cols] = closest(inner)[0].reshape(m - 2, len(cols), 3)
    return result


class InteriorSteps:
    """The interior solve of every trajectory step, with the sparsity pattern built once.

    At weight s the interior positions x_I solve (I - Λ_II(s)) x_I = Λ_IB(s) x_B
    with Λ(s) = Λ^1 + s (Λ^m - Λ^1).

    Parameters
    ----------
    first, last : (n, 3) ndarray of float64
        The first and last mesh (same topology).
    triangles : (m, 3) ndarray of int64
    interior : (n,) ndarray of bool
        True for interior vertices.

    Raises
    ------
    ParameterizationError
        Degenerate triangles at interior vertices in either mesh.
    """

    def __init__(self, first: FloatArray, last: FloatArray, triangles: IntArray, interior: BoolArray) -> None:
        n = len(first)
        pattern = WeightPattern.of(triangles, n)
        self.lam_first = mean_value_data(first, triangles, pattern, interior)
        self.lam_last = mean_value_data(last, triangles, pattern, interior)
        self.interior = np.flatnonzero(interior).astype(np.int64)
        self.border = np.flatnonzero(~interior).astype(np.int64)
        local = np.full(n, -1, dtype=np.int64)
        local[self.interior] = np.arange(len(self.interior))
        local[self.border] = np.arange(len(self.border))
        row_in = interior[pattern.rows]
        col_in = interior[pattern.indices]
        q = len(self.interior)
        # A = I - Λ_II: the diagonal, then the interior-interior non-zeros
        self.ii = np.flatnonzero(row_in & col_in)
        self.a_rows = np.concatenate([np.arange(q), local[pattern.rows[self.ii]]])
        self.a_cols = np.concatenate([np.arange(q), local[pattern.indices[self.ii]]])
        self.q = q
        self.permutation: IntArray | None = None  # symmetric ordering, found by the first solve
        self._structure(np.arange(q))
        # right-hand side Λ_IB x_B
        self.ib = np.flatnonzero(row_in & ~col_in)
        self.b_rows = local[pattern.rows[self.ib]]
        self.b_cols = local[pattern.indices[self.ib]]

    def _structure(self, permutation: IntArray) -> None:
        """CSC structure of P A P^T (row/column i of it is row/column ``permutation[i]`` of A), found once."""
        inverse = np.empty_like(permutation)
        inverse[permutation] = np.arange(len(permutation))
        order = csc_matrix((np.arange(1, len(self.a_rows) + 1, dtype=np.float64),
                            (inverse[self.a_rows], inverse[self.a_cols])), shape=(self.q, self.q))
        self.a_order = order.data.astype(np.int64) - 1
        self.a_indices, self.a_indptr = order.indices, order.indptr

    def matrix(self, s: float) -> tuple[csc_matrix, csr_matrix]:
        """A = I - Λ_II(s) (q, q), symmetrically permuted once :meth:`solve` has ordered it, and Λ_IB(s) (q, b)."""
        lam = self.lam_first + s * (self.lam_last - self.lam_first)
        values = np.concatenate([np.ones(self.q), -lam[self.ii]])[self.a_order]
        a = csc_matrix((values, self.a_indices, self.a_indptr), shape=(self.q, self.q))
        b = csr_matrix((lam[self.ib], (self.b_rows, self.b_cols)), shape=(self.q, len(self.border)))
        return a, b

    def solve(self, s: float, border_positions: FloatArray) -> FloatArray:
        """(q, 3) interior positions at weight s, given the border's (b, 3) (in ``self.border`` order).

        Every step factorises afresh (SuperLU, diagonal pivots); the first
        orders the columns (``MMD_AT_PLUS_A``) and the later ones reuse that
        symmetric permutation, the pattern being the same (28 % faster at
        100k vertices than ordering every step, see ``bench/interp_solvers.py``).
        """
        a, b = self.matrix(s)
        rhs = b @ border_positions
        try:
            if self.permutation is None:
                lu = splu(a, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0, options={"SymmetricMode": True})
                self.permutation = np.argsort(lu.perm_c).astype(np.int64)
                self._structure(self.permutation)
                result: FloatArray = lu.solve(rhs)
                return result
            lu = splu(a, permc_spec="NATURAL", diag_pivot_thresh=0.0, options={"SymmetricMode": True})
        except RuntimeError as exc:
            raise TrajectoryError(f"the interior system at step weight {s:g} cannot be solved: {exc}") from exc
        result = np.empty_like(rhs)
        result[self.permutation] = lu.solve(rhs[self.permutation])
        return result


def vertex_trajectories(source: npt.ArrayLike, target: npt.ArrayLike, triangles: npt.ArrayLike, steps: int,
                 attachments: Attachments | None = None, *, controls: npt.ArrayLike | None = None,
                 tolerance: float | None = None, interior_method: str = "auto") -> FloatArray:
    """Trajectories of every vertex from the source mesh to its compatible target mesh.

    Parameters
    ----------
    source : (n, 3) array_like of float
        The (refined) source mesh's vertices: the first sample.
    target : (n, 3) array_like of float
        The compatible target mesh's vertices: the last sample.
    triangles : (m, 3) array_like of int
        The topology both share.
    steps : int
        m >= 2 samples.
    attachments : mapping of int to sequence of ControllingSurface, optional
        Border vertex -> one or two controlling surfaces (see
        :func:`border_trajectories`). No attachment at all: every trajectory
        is linear.
    controls : (k,) array_like of int, optional
        The control vertices; when given, a vertex attached to two surfaces
        must be one of them.
    tolerance : float, optional
        See :func:`border_trajectories`.
    interior_method : {"auto", "solve", "linear"}
        ``"solve"``: interior vertices from the interpolated mean value
        weights at every intermediate step; ``"linear"``: linear
        trajectories; ``"auto"`` (the spec's rule): linear when there is no
        attachment at all, else solved.

    Returns
    -------
    (steps, n, 3) ndarray of float64
        Sample j of vertex i; sample 0 is ``source``, sample m-1 ``target``.

    Raises
    ------
    TrajectoryError, ParameterizationError
    """
    m = _check_steps(steps)
    first = as_points(source, "source positions", ParameterizationError)
    last = as_points(target, "target positions", ParameterizationError)
    if first.shape != last.shape:
        raise TrajectoryError(f"source and target must be compatible (same vertices): {len(first)} and "
                              f"{len(last)} vertices")
    n = len(first)
    tri = as_triangles(triangles, n, "triangles", ParameterizationError)
    interior = interior_mask(tri, n)
    if controls is not None and attachments:
        allowed = set(np.ascontiguousarray(controls, dtype=np.int64).ravel().tolist())
        for vertex, surfaces in attachments.items():
            if len(surfaces) == 2 and int(vertex) not in allowed:
                raise TrajectoryError(f"vertex {vertex} is attached to two surfaces but is not a control vertex")
    solve = interior_method == "solve" or (interior_method == "auto" and bool(attachments))
    if interior_method not in ("auto", "solve", "linear"):
        raise TrajectoryError(f"interior must be 'auto', 'solve' or 'linear', got {interior_method!r}")
    result = _linear(first, last, m)
    border = np.flatnonzero(~interior)
    if attachments:
        result[:, border] = border_trajectories(first, last, border, m, attachments, tolerance=tolerance)
    if solve and m > 2 and np.any(interior):
        system = InteriorSteps(first, last, tri, interior)
        for j in range(1, m - 1):
            result[j, system.interior] = system.solve(j / (m - 1), result[j, system.border])
    return result


def evolving_surface(triangles: npt.ArrayLike, trajectories: npt.ArrayLike, t0: float, t1: float, *,
                     name: str | None = None, color: Sequence[float] | None = None,
                     alive: bool = False) -> EvolvingSurface:
    """An evolving surface (model 3) of one topology period from trajectories sampled evenly on [t0, t1].

    Parameters
    ----------
    triangles : (k, 3) array_like of int
        The source topology.
    trajectories : (m, n, 3) array_like of float
        Sample j of vertex i at time t0 + j (t1 - t0) / (m - 1).
    t0, t1 : float
        Times of the source and of the compatible target, t0 < t1.
    name : str, optional
    color : (3,) sequence of float in [0, 1], optional
    alive : bool
        Whether the surface exists after t1 (keeping the target's shape).

    Returns
    -------
    EvolvingSurface
        ``at(t0)`` is the source, ``at(t1)`` the compatible target.

    Raises
    ------
    InvalidInputError
    """
    samples = np.ascontiguousarray(trajectories, dtype=np.float64)
    if samples.ndim != 3 or samples.shape[0] < 2 or samples.shape[2] != 3:
        raise TrajectoryError(f"trajectories must have shape (m, n, 3) with m >= 2, got {samples.shape}")
    times = even_times(t0, t1, samples.shape[0], labels=("t0", "t1", "steps"))
    period = TopologyPeriod(times, triangles, samples)
    return EvolvingSurface([period], name=name, color=color, alive=alive)
