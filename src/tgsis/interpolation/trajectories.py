"""Trajectories between a source mesh and its compatible target mesh, and the evolving surface they make.

Pure numpy/scipy; see the spec (``shared/spec/interpolation.md``, step 4,
"trajectories").

* Border vertices without constraint follow linear trajectories; a border
  vertex attached to one controlling surface follows its linear trajectory
  projected onto that surface, attached to two onto their intersection curve
  (the first and last samples are the given positions, which must lie on the
  surface or curve).
* Interior vertices (solved when anything is attached): their differential
  coordinates δ = (I - Λ̄) x, the offsets of each vertex from the mean-value
  combination of its neighbours, go linearly in time from the first mesh's
  to the last's, and the border trajectories are the constraints. Λ̄ is the
  mean of the first and last mesh's mean value weights, so one matrix
  I - Λ̄_II serves every step: it is factorised once (SuperLU,
  ``MMD_AT_PLUS_A``) and each step is a pair of triangular solves. Both
  known shapes come out of the solve, an identity or a rigid translation is
  exact at every step, and the interior leaves its straight path by at
  most what the border is moved off its straight path (discrete maximum
  principle: the weights are positive and sum to 1). The source design's
  rule, a convex combination of the neighbours with weights interpolated in
  time (its Eq. 4.34-4.36), is not used: a convex combination cannot hold a
  non-planar vertex, so it flattened every curved surface between the known
  instants (docs/interpolation.md).
* :func:`evolving_surface` turns the trajectories into a
  :class:`tgsis.temporal.EvolvingSurface` with m evenly spaced instants.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence

import numpy as np
import numpy.typing as npt
from scipy.sparse import csc_matrix, csr_matrix, identity
from scipy.sparse.csgraph import connected_components
from scipy.sparse.linalg import SuperLU, splu

from tgsis.errors import InvalidInputError
from tgsis.interpolation._arrays import as_points, as_triangles, interior_mask
from tgsis.interpolation.parameterize import (
    ParameterizationError,
    WeightPattern,
    mean_value_data,
)
from tgsis.interpolation.projection import ControllingSurface, IntersectionCurve
from tgsis.temporal import EvolvingSurface, TopologyPeriod, even_times

__all__ = [
    "TrajectoryError",
    "Attachments",
    "border_trajectories",
    "InteriorSteps",
    "vertex_trajectories",
    "evolving_surface",
]

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


def _weights(steps: int) -> FloatArray:
    """(steps,): the step weights s_j = j / (m - 1), 0 and 1 exactly at the ends."""
    return np.arange(steps, dtype=np.float64) / (steps - 1)


def _lerp(start: FloatArray, end: FloatArray, s: FloatArray) -> FloatArray:
    """(k, p, 3): v + s (u - v) for every weight s of ``s`` (k,), written from the nearer end.

    From v while s <= 1/2 and as u - (1 - s) (u - v) after, so that s = 0
    gives v and s = 1 gives u bit for bit (no end is reset afterwards), the
    same difference u - v moves every vertex (a translation stays rigid to
    rounding), and swapping v and u with s and 1 - s gives the same numbers.
    """
    delta = end - start
    early = s <= 0.5
    result = np.empty((len(s), *start.shape), dtype=np.float64)
    result[early] = start[None] + s[early, None, None] * delta[None]
    result[~early] = end[None] - (1.0 - s[~early])[:, None, None] * delta[None]
    return result


def _linear(start: FloatArray, end: FloatArray, steps: int) -> FloatArray:
    """(steps, p, 3): w_j = v + (j-1)/(m-1) (u - v), v and u exactly at the ends (see :func:`_lerp`)."""
    return _lerp(start, end, _weights(steps))


def _constraint(
    surfaces: Sequence[ControllingSurface],
) -> tuple[str, Callable[[FloatArray], tuple[FloatArray, FloatArray]]]:
    """How messages name what a vertex is attached to, and its closest-point function (points, distances)."""
    if len(surfaces) == 1:
        surface = surfaces[0]

        def on_surface(points: FloatArray) -> tuple[FloatArray, FloatArray]:
            found = surface.closest(points)
            return found.points, found.distances

        return surface.label, on_surface
    curve = IntersectionCurve(surfaces[0], surfaces[1])
    return f"the intersection curve of {surfaces[0].label} and {surfaces[1].label}", curve.closest


def border_trajectories(
    source: npt.ArrayLike,
    target: npt.ArrayLike,
    vertices: npt.ArrayLike,
    steps: int,
    attachments: Attachments | None = None,
    *,
    tolerance: float | None = None,
) -> FloatArray:
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
            raise TrajectoryError(
                f"vertex {vertex} is attached to a controlling surface but is not a border vertex",
                hint="only border vertices take attaching constraints",
            )
        if len(surfaces) not in (1, 2) or not all(isinstance(s, ControllingSurface) for s in surfaces):
            raise TrajectoryError(
                f"vertex {vertex} must be attached to one or two ControllingSurface objects, got {len(surfaces)}"
            )
        key = tuple(sorted(id(s) for s in surfaces))
        groups.setdefault(key, (surfaces, []))[1].append(column[int(vertex)])
    for surfaces, columns in groups.values():
        cols = np.asarray(columns, dtype=np.int64)
        label, closest = _constraint(surfaces)
        for sample, name in ((0, "source"), (m - 1, "target")):
            d = closest(result[sample, cols])[1]
            if np.any(d > limit):
                i = int(np.argmax(d))
                raise TrajectoryError(
                    f"vertex {int(which[cols[i]])} is {d[i]:.6g} from {label} in the {name} "
                    f"mesh (tolerance {limit:.6g}): it cannot stay on it"
                )
        if m > 2:
            inner = result[1:-1, cols].reshape(-1, 3)
            result[1:-1, cols] = closest(inner)[0].reshape(m - 2, len(cols), 3)
    return result


class InteriorSteps:
    """The interior solve of every trajectory step: one matrix and one factorisation for the topology.

    With Λ̄ = (Λ^1 + Λ^m) / 2, the mean of the first and last mesh's mean
    value weights (positive, rows summing to 1), the differential
    coordinates of a shape x are δ = (I - Λ̄) x on the interior rows. At
    weight s the interior positions x_I solve

        (I - Λ̄_II) x_I = (1 - s) δ^1_I + s δ^m_I + Λ̄_IB x_B(s),

    the border positions x_B(s) given. Written around the straight paths
    ℓ(s) = x^1 + s (x^m - x^1) (which satisfy it with ℓ_B on the border),
    this is x_I = ℓ_I(s) + c_I with

        (I - Λ̄_II) c_I = Λ̄_IB (x_B(s) - ℓ_B(s)):

    the interior leaves its straight path only as far as the border was
    moved off its own (by the controlling surfaces), each coordinate of c_I
    a convex combination of the border's, so never farther. Solving this
    form keeps rounding at the size of the border's departure: exact
    (bit for bit) where the border follows its straight paths, as at the
    two ends. The weights are symmetric in time: swapping the first and
    last mesh gives the same trajectories, reversed.

    Interior vertices of a part of the mesh that reaches no border vertex
    (a closed component) have nothing to follow but their straight paths,
    and keep them.

    Parameters
    ----------
    first, last : (n, 3) ndarray of float64
        The first and last mesh (same topology).
    triangles : (m, 3) ndarray of int64
    interior : (n,) ndarray of bool
        True for interior vertices.

    Attributes
    ----------
    interior, border : ndarray of int64
        The interior vertices (the rows of :meth:`solve`'s result) and the
        border vertices (the columns of its input), ascending.
    solved : ndarray of int64
        Positions in ``interior`` of the vertices the solve moves (those
        whose part of the mesh reaches the border).
    matrix : (r, r) scipy.sparse.csc_matrix
        I - Λ̄ on the solved vertices, r = len(solved).
    to_border : (r, b) scipy.sparse.csr_matrix
        Λ̄ from the solved vertices to the border vertices.
    factorizations : int
        Sparse factorisations done: one, at construction (none when no
        interior vertex reaches the border).

    Raises
    ------
    ParameterizationError
        Degenerate triangles at interior vertices in either mesh.
    TrajectoryError
        The matrix cannot be factorised.
    """

    def __init__(self, first: FloatArray, last: FloatArray, triangles: IntArray, interior: BoolArray) -> None:
        n = len(first)
        pattern = WeightPattern.of(triangles, n)
        lam = 0.5 * (
            mean_value_data(first, triangles, pattern, interior) + mean_value_data(last, triangles, pattern, interior)
        )
        self.interior = np.flatnonzero(interior).astype(np.int64)
        self.border = np.flatnonzero(~interior).astype(np.int64)
        self._first, self._last = first[self.interior], last[self.interior]
        self._border_first, self._border_last = first[self.border], last[self.border]
        local = np.full(n, -1, dtype=np.int64)
        local[self.interior] = np.arange(len(self.interior))
        local[self.border] = np.arange(len(self.border))
        row_in = interior[pattern.rows]
        col_in = interior[pattern.indices]
        q, b = len(self.interior), len(self.border)
        ii = np.flatnonzero(row_in & col_in)
        ib = np.flatnonzero(row_in & ~col_in)
        coupling = csr_matrix((lam[ii], (local[pattern.rows[ii]], local[pattern.indices[ii]])), shape=(q, q))
        self.to_border = csr_matrix((lam[ib], (local[pattern.rows[ib]], local[pattern.indices[ib]])), shape=(q, b))
        # interior vertices of a component with no border neighbour: the system is singular there
        _, component = connected_components(coupling, directed=False)
        reached = np.zeros(int(component.max(initial=-1)) + 1, dtype=bool)
        reached[component[np.diff(self.to_border.indptr) > 0]] = True
        self.solved = np.flatnonzero(reached[component]).astype(np.int64)
        system = identity(q, format="csr") - coupling
        if len(self.solved) < q:
            system = system[self.solved][:, self.solved]
            self.to_border = self.to_border[self.solved]
        self.matrix = csc_matrix(system)
        self.factorizations = 0
        self._lu: SuperLU | None = None
        if len(self.solved):
            try:
                self._lu = splu(
                    self.matrix, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0, options={"SymmetricMode": True}
                )
            except RuntimeError as exc:
                raise TrajectoryError(f"the interior system of the trajectories cannot be solved: {exc}") from exc
            self.factorizations = 1

    def solve(self, weights: npt.ArrayLike, border_positions: npt.ArrayLike) -> FloatArray:
        """(k, q, 3) interior positions at the step weights (k,), given the border's (k, b, 3).

        The border positions are in ``self.border`` order; the result is in
        ``self.interior`` order. Each step is one triangular solve pair for
        its three coordinates with the factorisation made at construction
        (SuperLU solves many right-hand sides at once 2-4 times slower per
        column than three at a time, at 100k vertices).
        """
        s = np.ascontiguousarray(weights, dtype=np.float64).ravel()
        placed = np.ascontiguousarray(border_positions, dtype=np.float64)
        if placed.shape != (len(s), len(self.border), 3):
            raise TrajectoryError(
                f"border positions must have shape {(len(s), len(self.border), 3)}, got {placed.shape}"
            )
        result = _lerp(self._first, self._last, s)
        if self._lu is None:
            return result
        straight = _lerp(self._border_first, self._border_last, s)
        for j in range(len(s)):
            departure = placed[j] - straight[j]  # (b, 3): off the straight paths
            result[j, self.solved] += self._lu.solve(np.asfortranarray(self.to_border @ departure))
        return result


def vertex_trajectories(
    source: npt.ArrayLike,
    target: npt.ArrayLike,
    triangles: npt.ArrayLike,
    steps: int,
    attachments: Attachments | None = None,
    *,
    controls: npt.ArrayLike | None = None,
    tolerance: float | None = None,
    interior_method: str = "auto",
) -> FloatArray:
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
        ``"solve"``: interior vertices solved at every step from their
        differential coordinates, interpolated linearly in time, with the
        border trajectories as constraints (see :class:`InteriorSteps`);
        ``"linear"``: linear trajectories; ``"auto"`` (the spec's rule):
        linear when there is no attachment at all, else solved. Without
        attachments both give the same trajectories, bit for bit.

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
        raise TrajectoryError(
            f"source and target must be compatible (same vertices): {len(first)} and {len(last)} vertices"
        )
    n = len(first)
    tri = as_triangles(triangles, n, "triangles", ParameterizationError)
    interior = interior_mask(tri, n)
    if controls is not None and attachments:
        allowed = set(np.ascontiguousarray(controls, dtype=np.int64).ravel().tolist())
        for vertex, surfaces in attachments.items():
            if len(surfaces) == 2 and int(vertex) not in allowed:
                raise TrajectoryError(f"vertex {vertex} is attached to two surfaces but is not a control vertex")
    if interior_method not in ("auto", "solve", "linear"):
        raise TrajectoryError(f"interior must be 'auto', 'solve' or 'linear', got {interior_method!r}")
    solve = interior_method == "solve" or (interior_method == "auto" and bool(attachments))
    result = _linear(first, last, m)
    border = np.flatnonzero(~interior)
    if attachments:
        result[:, border] = border_trajectories(first, last, border, m, attachments, tolerance=tolerance)
    if solve and np.any(interior):
        # every step, the two ends included, comes out of the one factorisation
        system = InteriorSteps(first, last, tri, interior)
        result[:, system.interior] = system.solve(_weights(m), result[:, system.border])
    return result


def evolving_surface(
    triangles: npt.ArrayLike,
    trajectories: npt.ArrayLike,
    t0: float,
    t1: float,
    *,
    name: str | None = None,
    color: Sequence[float] | None = None,
    alive: bool = False,
) -> EvolvingSurface:
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
