"""The :class:`GMap` type: darts, involutions, embedding, orbits, cells, checks."""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np
import numpy.typing as npt

from tgsis.errors import InvalidGMapError, InvalidInputError, InvalidPropertyError
from tgsis.gmaps._arrays import FloatArray, IntArray
from tgsis.gmaps._arrays import as_points as _as_points
from tgsis.gmaps._build import Parts, mesh_parts, polygons_parts, simplices_parts
from tgsis.mesh import PROPERTY_NAME_RE

if TYPE_CHECKING:
    import scipy.sparse as sp

    from tgsis.mesh import Mesh

Properties = dict[int, dict[str, npt.NDArray[Any]]]

#: Rounds of label propagation before the rest of an orbit computation goes to scipy.
_PROPAGATION_ROUNDS = 12
#: How many offending darts an error message names.
_NAMED = 10


def _named(darts: IntArray) -> str:
    shown = ", ".join(str(int(d)) for d in darts[:_NAMED])
    return shown + (f", ... ({len(darts)} in all)" if len(darts) > _NAMED else "")


def _as_int_array(values: npt.ArrayLike, what: str, ndim: int) -> IntArray:
    raw = np.asarray(values)
    if raw.size == 0:
        raw = raw.astype(np.int64)
    if raw.dtype.kind not in "iu":
        raise InvalidGMapError(f"{what} must be integers, got {raw.dtype}")
    if raw.ndim != ndim:
        raise InvalidGMapError(f"{what} must be a {ndim}-D array, got shape {raw.shape}")
    return np.ascontiguousarray(raw, dtype=np.int64)


def orbit_labels(
    alpha: IntArray, involutions: Sequence[int], *, rounds: int = _PROPAGATION_ROUNDS
) -> tuple[IntArray, int]:
    """Label the orbits of the darts under a subset of the involutions.

    Parameters
    ----------
    alpha : (n + 1, d) int64
        The involutions (any permutations work: orbits are the connected
        components of the undirected graph d -- alpha[i, d]).
    involutions : sequence of int
        The indices i of the involutions that generate the orbits.
    rounds : int
        Rounds of label propagation to try before handing the rest to scipy
        (0: scipy does it all).

    Returns
    -------
    labels : (d,) int64
        Orbit of each dart, numbered 0, 1, ... in the order of each orbit's
        lowest-numbered dart.
    count : int
        Number of orbits.

    Notes
    -----
    A few rounds of vectorised min-label propagation with pointer jumping
    settle the small orbits of meshes (edges, faces, vertex stars); what is
    left is contracted and finished by
    :func:`scipy.sparse.csgraph.connected_components`.
    """
    d = alpha.shape[1]
    involutions = sorted(set(int(i) for i in involutions))
    if d == 0:
        return np.empty(0, dtype=np.int64), 0
    labels = np.arange(d, dtype=np.int64)
    if not involutions:
        return labels, d
    maps = [alpha[i] for i in involutions]
    settled = False
    for _ in range(rounds):
        new = labels
        for a in maps:
            new = np.minimum(new, new[a])
        new = new[new]
        new = new[new]
        if np.array_equal(new, labels):
            # a fixpoint is the answer when labels agree across every link (always, for permutations)
            settled = all(np.array_equal(labels[a], labels) for a in maps)
            break
        labels = new
    if not settled:
        import scipy.sparse as sp  # imported when needed: `import tgsis` stays light
        from scipy.sparse.csgraph import connected_components

        # contract each current label class and finish on the (much smaller) quotient graph
        roots, inverse = np.unique(labels, return_inverse=True)
        rows = np.concatenate([inverse] * len(maps))
        cols = np.concatenate([inverse[a] for a in maps])
        keep = rows != cols
        k = len(roots)
        graph = sp.csr_array((np.ones(int(keep.sum()), dtype=np.int8), (rows[keep], cols[keep])), shape=(k, k))
        _, components = connected_components(graph, directed=True, connection="weak")
        # lowest dart of each component, then number components in that order
        lowest = np.full(int(components.max()) + 1, d, dtype=np.int64)
        np.minimum.at(lowest, components, roots)
        labels = lowest[components[inverse]]
    is_root = labels == np.arange(d)
    dense = np.cumsum(is_root, dtype=np.int64) - 1
    return dense[labels], int(dense[-1]) + 1


def _first_darts(labels: IntArray, count: int) -> IntArray:
    """The lowest dart of each orbit, for labels numbered by first appearance (as orbit_labels numbers them)."""
    if len(labels) == 0:
        return np.empty(0, dtype=np.int64)
    first = np.empty(count, dtype=np.int64)
    # a new label appears exactly where it exceeds every label before it
    starts = np.flatnonzero(np.concatenate([[True], labels[1:] > np.maximum.accumulate(labels)[:-1]]))
    first[labels[starts]] = starts
    return first


@dataclass(frozen=True)
class GMapReport:
    """What :meth:`GMap.check` found; each mapping holds only violated conditions.

    Attributes
    ----------
    dimension : int
        n of the n-G-map checked.
    not_involutions : dict of int to (q,) int64
        Condition (i): for each i, the darts d with alpha_i(alpha_i(d)) != d.
    fixed_points : dict of int to (q,) int64
        Condition (ii): for each i < n, the darts with alpha_i(d) == d.
    not_involutive_compositions : dict of (int, int) to (q,) int64
        Condition (iii): for each i + 2 <= j, the darts d with
        (alpha_i alpha_j)(alpha_i alpha_j)(d) != d.
    split_vertices : dict of int to (q,) int64
        The embedding: for each i >= 1, the darts d whose vertex differs from
        that of alpha_i(d) (all darts of a 0-cell must share one point).
    crossing_periods : dict of int to (q,) int64
        Topology periods (model 4), when ``periods`` were given: for each i,
        the darts d whose alpha_i(d) belongs to another period.
    """

    dimension: int
    not_involutions: dict[int, IntArray] = field(default_factory=dict)
    fixed_points: dict[int, IntArray] = field(default_factory=dict)
    not_involutive_compositions: dict[tuple[int, int], IntArray] = field(default_factory=dict)
    split_vertices: dict[int, IntArray] = field(default_factory=dict)
    crossing_periods: dict[int, IntArray] = field(default_factory=dict)

    @property
    def ok(self) -> bool:
        """No condition is violated."""
        return not (
            self.not_involutions
            or self.fixed_points
            or self.not_involutive_compositions
            or self.split_vertices
            or self.crossing_periods
        )

    def problems(self) -> list[str]:
        """One sentence per violated condition, naming (the first) offending darts."""
        out = [f"alpha{i} is not an involution at darts {_named(d)}" for i, d in self.not_involutions.items()]
        out += [
            f"alpha{i} has fixed points (only alpha{self.dimension} may) at darts {_named(d)}"
            for i, d in self.fixed_points.items()
        ]
        out += [
            f"alpha{i} o alpha{j} is not an involution at darts {_named(d)}"
            for (i, j), d in self.not_involutive_compositions.items()
        ]
        out += [
            f"darts joined by alpha{i} have different vertices (a 0-cell with two points) at darts {_named(d)}"
            for i, d in self.split_vertices.items()
        ]
        out += [
            f"alpha{i} joins darts of different topology periods at darts {_named(d)}"
            for i, d in self.crossing_periods.items()
        ]
        return out

    def summary(self) -> str:
        """One line for logs."""
        return "a valid G-map" if self.ok else "; ".join(self.problems())


class GMap:
    """An n-G-map with a linear embedding: darts, involutions alpha_0..alpha_n, points.

    Parameters
    ----------
    alpha : (n + 1, d) array_like of int
        ``alpha[i, x]`` is the dart that alpha_i sends dart ``x`` to; a dart
        free in alpha_i (on the border, only allowed for i = n) has
        ``alpha[i, x] == x``. Stored as int64.
    vertex : (d,) array_like of int
        The embedding: the point of each dart (all darts of a 0-cell share it).
    points : (k, m) array_like of float
        Coordinates, m >= n. Points no dart uses are kept.
    cell_properties : mapping of int to mapping of str to (n_cells(level),) or (n_cells(level), k) array_like, optional
        Numeric properties of the i-cells of a level: ``{level: {name: values}}``,
        values (or rows of k values: vector properties) in the order of
        :meth:`cells` labels.

    Raises
    ------
    InvalidGMapError
        Wrong shapes or dtypes, an involution value or vertex index out of
        range, non-finite coordinates, fewer coordinates than dimensions.
    InvalidPropertyError
        A bad property name, level or number of values.

    Notes
    -----
    Construction checks only what the arrays must satisfy to be read; the
    conditions of a G-map are checked by :meth:`check`, so that a broken map
    can be held and reported on. The arrays are made read-only: orbits are
    cached.
    """

    alpha: IntArray
    vertex: IntArray
    points: FloatArray
    cell_properties: Properties

    def __init__(
        self,
        alpha: npt.ArrayLike,
        vertex: npt.ArrayLike,
        points: npt.ArrayLike,
        *,
        cell_properties: Mapping[int, Mapping[str, npt.ArrayLike]] | None = None,
    ) -> None:
        a = _as_int_array(alpha, "alpha", 2)
        if a.shape[0] == 0:
            raise InvalidGMapError("alpha must have n + 1 >= 1 rows (alpha_0 .. alpha_n), got none")
        n, d = a.shape[0] - 1, a.shape[1]
        outside = (a < 0) | (a >= d)
        if outside.any():
            i, x = (int(v) for v in np.argwhere(outside)[0])
            raise InvalidGMapError(
                f"alpha{i} sends dart {x} to {a[i, x]}, but the map has {d} darts",
                detail=f"{int(outside.sum())} involution values are out of range",
            )
        v = _as_int_array(vertex, "vertex", 1)
        if len(v) != d:
            raise InvalidGMapError(f"vertex must hold one point index per dart: {len(v)} for {d} darts")
        p = _as_points(points)
        if p.shape[1] < n:
            raise InvalidGMapError(f"a {n}-G-map needs points in R^m with m >= {n}, got m = {p.shape[1]}")
        bad = (v < 0) | (v >= len(p))
        if bad.any():
            x = int(np.flatnonzero(bad)[0])
            raise InvalidGMapError(
                f"dart {x} has vertex {v[x]}, but there are {len(p)} points",
                detail=f"{int(bad.sum())} darts have out-of-range vertices",
            )
        for array in (a, v, p):
            array.flags.writeable = False
        self.alpha, self.vertex, self.points = a, v, p
        self._orbits: dict[tuple[int, ...], tuple[IntArray, int]] = {}
        self.cell_properties = self._as_properties(cell_properties)

    def _as_properties(self, props: Mapping[int, Mapping[str, npt.ArrayLike]] | None) -> Properties:
        out: Properties = {}
        for level, named in (props or {}).items():
            if not isinstance(level, (int, np.integer)) or not 0 <= int(level) <= self.dimension:
                raise InvalidPropertyError(
                    f"property level {level!r} is not a cell dimension of this "
                    f"{self.dimension}-G-map (0..{self.dimension})"
                )
            count = self.n_cells(int(level))
            into = out.setdefault(int(level), {})
            for name, values in named.items():
                if not isinstance(name, str) or not PROPERTY_NAME_RE.match(name):
                    raise InvalidPropertyError(
                        f"property name {name!r} is not allowed",
                        hint="use letters, digits and underscores, starting with a letter (at most 63)",
                    )
                array = np.ascontiguousarray(values)
                if array.dtype.kind not in "biuf" or array.ndim not in (1, 2):
                    raise InvalidPropertyError(
                        f"property {name!r} of {level}-cells must be a numeric array of "
                        f"one value (or one row of values) per cell, got {array.dtype} of "
                        f"shape {array.shape}"
                    )
                if len(array) != count:
                    raise InvalidPropertyError(f"property {name!r} has {len(array)} values for {count} {level}-cells")
                into[name] = array
        return out

    # ---- facts

    @property
    def dimension(self) -> int:
        """n: the map has involutions alpha_0 .. alpha_n."""
        return int(self.alpha.shape[0]) - 1

    @property
    def n_darts(self) -> int:
        """Number of darts d."""
        return int(self.alpha.shape[1])

    @property
    def n_points(self) -> int:
        """Number of points k (rows of :attr:`points`)."""
        return int(self.points.shape[0])

    @property
    def embedding_dimension(self) -> int:
        """m: the points are in R^m."""
        return int(self.points.shape[1])

    def __repr__(self) -> str:
        return (
            f"GMap(dimension={self.dimension}, n_darts={self.n_darts}, n_points={self.n_points}, "
            f"embedding_dimension={self.embedding_dimension})"
        )

    def same_as(self, other: GMap) -> bool:
        """Identical involutions, vertices, points (bit for bit) and properties."""

        def same_props(a: Properties, b: Properties) -> bool:
            return a.keys() == b.keys() and all(
                a[k].keys() == b[k].keys() and all(np.array_equal(a[k][n], b[k][n]) for n in a[k]) for k in a
            )

        return (
            self.alpha.shape == other.alpha.shape
            and np.array_equal(self.alpha, other.alpha)
            and np.array_equal(self.vertex, other.vertex)
            and self.points.shape == other.points.shape
            and bool(np.all(self.points.view(np.int64) == other.points.view(np.int64)))
            and same_props(self.cell_properties, other.cell_properties)
        )

    # ---- orbits and cells

    def _check_levels(self, levels: Iterable[int], what: str) -> tuple[int, ...]:
        out = tuple(sorted(set(int(i) for i in levels)))
        bad = [i for i in out if not 0 <= i <= self.dimension]
        if bad:
            raise InvalidInputError(
                f"{what} {bad[0]} is not an involution of this {self.dimension}-G-map (0..{self.dimension})"
            )
        return out

    def orbits(self, involutions: Iterable[int]) -> tuple[IntArray, int]:
        """The orbits of the darts under the given involutions.

        Parameters
        ----------
        involutions : iterable of int
            Indices i in 0..n.

        Returns
        -------
        labels : (d,) int64
            Orbit of each dart, numbered in the order of each orbit's lowest dart.
        count : int
            Number of orbits.
        """
        key = self._check_levels(involutions, "involution")
        if key not in self._orbits:
            self._orbits[key] = orbit_labels(self.alpha, key)
        return self._orbits[key]

    def cells(self, i: int) -> IntArray:
        """i-cell of each dart: (d,) int64 labels 0..n_cells(i)-1 (the orbit of all involutions but alpha_i).

        Cells are numbered in the order of their lowest-numbered dart: the
        builders lay darts out so that n-cells come in the order of the input
        cells.
        """
        (level,) = self._check_levels([i], "cell dimension")
        return self.orbits([j for j in range(self.dimension + 1) if j != level])[0]

    def n_cells(self, i: int) -> int:
        """Number of i-cells."""
        (level,) = self._check_levels([i], "cell dimension")
        return self.orbits([j for j in range(self.dimension + 1) if j != level])[1]

    def components(self) -> tuple[IntArray, int]:
        """Connected components: (d,) int64 labels and their count (orbits of all involutions)."""
        return self.orbits(range(self.dimension + 1))

    def _orientation_cover(self) -> tuple[IntArray, IntArray]:
        """Components of the orientation double cover: dart (x, b) goes by alpha_i to (alpha_i(x), 1 - b).

        Returns the cover's labels of (x, 0) and of (x, 1); a component of the
        map is orientable exactly when its two copies stay apart.
        """
        d = self.n_darts
        darts = np.arange(d, dtype=np.int64)
        free = self.alpha == darts
        # cover dart 2x + b; a free dart stays where it is
        cover = np.where(
            free[:, :, None],
            (2 * darts)[None, :, None] + np.arange(2)[None, None, :],
            (2 * self.alpha)[:, :, None] + (1 - np.arange(2))[None, None, :],
        ).reshape(len(self.alpha), 2 * d)
        labels, _ = orbit_labels(cover, range(len(cover)))
        return labels[0::2], labels[1::2]

    def is_orientable(self) -> bool:
        """Whether every connected component can be oriented (a Möbius strip cannot)."""
        even, odd = self._orientation_cover()
        return bool(np.all(even != odd))

    def orientation(self) -> npt.NDArray[np.bool_]:
        """A sign per dart, (d,) bool, flipped by every alpha_i between distinct darts (the SQL ``positive``).

        In each connected component the lowest dart is positive.

        Raises
        ------
        InvalidGMapError
            A component is not orientable (the message names one of its darts).
        """
        even, odd = self._orientation_cover()
        bad = np.flatnonzero(even == odd)
        if len(bad):
            raise InvalidGMapError(
                f"the component of dart {int(bad[0])} is not orientable: no sign per dart "
                "is flipped by every involution",
                hint="is_orientable() tells beforehand",
            )
        component, count = self.components()
        lowest = _first_darts(component, count)
        # positive: in the same cover component as (lowest dart of its component, 0)
        return np.asarray(even == even[lowest[component]])

    def euler_characteristic(self) -> int:
        """Sum over i of (-1)^i times the number of i-cells."""
        return sum((-1) ** i * self.n_cells(i) for i in range(self.dimension + 1))

    def cell_darts(self, i: int) -> IntArray:
        """The lowest-numbered dart of each i-cell: (n_cells(i),) int64."""
        return _first_darts(self.cells(i), self.n_cells(i))

    def incidence(self, i: int, j: int) -> sp.csr_array:
        """Incidence between i-cells and j-cells: (n_cells(i), n_cells(j)) sparse bool, True where they share a dart.

        For i != j two cells are incident when one is a face of the other
        (they share a dart).
        """
        import scipy.sparse as sp

        a, b = self.cells(i), self.cells(j)
        m = sp.coo_array((np.ones(self.n_darts, dtype=bool), (a, b)), shape=(self.n_cells(i), self.n_cells(j)))
        out = m.tocsr()
        out.sum_duplicates()
        out.data[:] = True
        return out

    def adjacency(self, i: int) -> sp.csr_array:
        """Adjacency of i-cells: (n_cells(i), n_cells(i)) sparse bool, symmetric, no diagonal.

        For i >= 1 two i-cells are adjacent when they share an (i-1)-cell (two
        faces sharing an edge, two edges sharing a vertex); 0-cells are
        adjacent when they bound a common edge.
        """
        import scipy.sparse as sp

        (level,) = self._check_levels([i], "cell dimension")
        if level == 0 and self.dimension == 0:
            return sp.csr_array((self.n_cells(0), self.n_cells(0)), dtype=bool)
        inc = self.incidence(level, level - 1 if level >= 1 else 1).astype(np.int64)
        prod = (inc @ inc.T).tocoo()
        keep = prod.row != prod.col
        n = self.n_cells(level)
        return sp.csr_array((np.ones(int(keep.sum()), dtype=bool), (prod.row[keep], prod.col[keep])), shape=(n, n))

    # ---- the border

    def border_darts(self) -> IntArray:
        """Darts free in alpha_n (the border of the object): (q,) int64."""
        n = self.dimension
        return np.flatnonzero(self.alpha[n] == np.arange(self.n_darts)).astype(np.int64)

    def border(self) -> GMap:
        """The border as an (n-1)-G-map: the darts free in alpha_n, with the same points.

        alpha_i for i <= n - 2 is restricted to those darts; alpha_{n-1} of a
        border dart turns around its (n-2)-cell (alpha_{n-1}, then alpha_n
        alpha_{n-1} until a free dart). The border of a closed object has no
        dart; that of a 1-G-map is the free ends of its lines, as a 0-G-map
        whose darts are all free.

        Raises
        ------
        InvalidInputError
            A 0-G-map has no border.
        InvalidGMapError
            The map breaks condition (iii), so the border cannot be built.
        """
        n = self.dimension
        if n == 0:
            raise InvalidInputError("a 0-G-map (points) has no border")
        free = self.border_darts()
        index = np.full(self.n_darts, -1, dtype=np.int64)
        index[free] = np.arange(len(free))
        rows = [index[self.alpha[i, free]] for i in range(n - 1)]
        if n == 1:  # the ends of lines: points, each its own free dart
            return GMap(np.arange(len(free), dtype=np.int64).reshape(1, -1), self.vertex[free], self.points)
        cur = self.alpha[n - 1, free]
        todo = np.flatnonzero(self.alpha[n, cur] != cur)
        for _ in range(self.n_darts + 1):
            if len(todo) == 0:
                break
            cur[todo] = self.alpha[n - 1, self.alpha[n, cur[todo]]]
            todo = todo[self.alpha[n, cur[todo]] != cur[todo]]
        rows.append(index[cur])
        stacked = np.array(rows, dtype=np.int64).reshape(n, len(free))
        if len(todo) or (stacked < 0).any():
            raise InvalidGMapError(
                "the border cannot be built: an involution leads a border dart off the border", hint="run check() first"
            )
        return GMap(stacked, self.vertex[free], self.points)

    # ---- checks

    def check(self, periods: npt.ArrayLike | None = None, *, raise_: bool = False) -> GMapReport:
        """Check the conditions of an n-G-map and of its embedding.

        Parameters
        ----------
        periods : (d,) array_like of int, optional
            Topology period of each dart (model 4): each period's dart set
            must be closed under every involution.
        raise_ : bool
            Raise :class:`InvalidGMapError` instead of returning a report with
            violations.

        Returns
        -------
        GMapReport
            (i) involutions, (ii) no fixed points below alpha_n, (iii)
            alpha_i o alpha_j involutions for i + 2 <= j, shared vertices
            along alpha_1..alpha_n, and period closure.

        Raises
        ------
        InvalidGMapError
            With ``raise_=True``, when a condition is violated (the message
            names the offending darts).
        InvalidInputError
            ``periods`` is not one integer per dart.
        """
        a, n, d = self.alpha, self.dimension, self.n_darts
        darts = np.arange(d)
        report = GMapReport(n)
        for i in range(n + 1):
            bad = np.flatnonzero(a[i, a[i]] != darts)
            if len(bad):
                report.not_involutions[i] = bad
            if i < n:
                bad = np.flatnonzero(a[i] == darts)
                if len(bad):
                    report.fixed_points[i] = bad
            if i >= 1:
                bad = np.flatnonzero(self.vertex[a[i]] != self.vertex)
                if len(bad):
                    report.split_vertices[i] = bad
        for i in range(n + 1):
            for j in range(i + 2, n + 1):
                ij = a[i, a[j]]
                bad = np.flatnonzero(ij[ij] != darts)
                if len(bad):
                    report.not_involutive_compositions[(i, j)] = bad
        if periods is not None:
            raw = np.asarray(periods)
            if raw.dtype.kind not in "iu" or raw.shape != (d,):
                raise InvalidInputError(
                    f"periods must be one integer per dart, shape ({d},), got {raw.dtype} of shape {raw.shape}"
                )
            for i in range(n + 1):
                bad = np.flatnonzero(raw[a[i]] != raw)
                if len(bad):
                    report.crossing_periods[i] = bad
        if raise_ and not report.ok:
            problems = report.problems()
            raise InvalidGMapError(
                f"not a valid {n}-G-map: {problems[0]}",
                detail="; ".join(problems[1:]) or None,
                hint="GMap.check() returns the report with every offending dart",
            )
        return report

    # ---- back to meshes

    def _walk(self, starts: IntArray, sequence: Sequence[int]) -> IntArray:
        out = starts
        for i in sequence:
            out = self.alpha[i, out]
        return out

    def polygons(self) -> tuple[IntArray, IntArray]:
        """The 2-cells as polygons: flat vertex indices and offsets.

        Returns
        -------
        indices : (s,) int64
            Point indices of every face's boundary cycle, face after face.
        offsets : (f + 1,) int64
            Face j has ``indices[offsets[j]:offsets[j + 1]]``; faces in the
            order of :meth:`cells` (2).

        Notes
        -----
        Each cycle starts at the point of the face's lowest dart and follows
        alpha_0, then alpha_1: for a map built from polygons it is the input
        polygon.

        Raises
        ------
        InvalidInputError
            The map has no 2-cells (n < 2).
        """
        if self.dimension < 2:
            raise InvalidInputError(f"a {self.dimension}-G-map has no faces (2-cells)")
        return self._cycles(self.cell_darts(2))

    def _cycles(self, start: IntArray) -> tuple[IntArray, IntArray]:
        """The alpha_0 alpha_1 cycle of points from each start dart: flat indices and offsets."""
        f = len(start)
        # a face's darts under <alpha0, alpha1>: its size is half its dart count
        face_of = self.orbits([0, 1])[0]
        sizes = np.bincount(face_of)[face_of[start]] // 2 if f else np.empty(0, dtype=np.int64)
        offsets = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
        indices = np.empty(int(offsets[-1]), dtype=np.int64)
        cur = start.copy()
        active = np.arange(f)
        for step in range(int(sizes.max()) if f else 0):
            active = active[sizes[active] > step]
            indices[offsets[active] + step] = self.vertex[cur[active]]
            cur[active] = self.alpha[1, self.alpha[0, cur[active]]]
        return indices, offsets

    def polyhedra(self) -> tuple[IntArray, IntArray, IntArray]:
        """The 3-cells as polyhedra: the faces of each, as polygons.

        Returns
        -------
        indices : (s,) int64
            Point indices of the faces' boundary cycles, face after face.
        face_offsets : (q + 1,) int64
            Face j has ``indices[face_offsets[j]:face_offsets[j + 1]]``.
        cell_offsets : (c + 1,) int64
            3-cell i (in the order of :meth:`cells` (3)) has faces
            ``cell_offsets[i]:cell_offsets[i + 1]``, in the order of their
            lowest darts; a face between two 3-cells is listed in both.

        Raises
        ------
        InvalidInputError
            The map has no 3-cells (n < 3).
        """
        if self.dimension < 3:
            raise InvalidInputError(f"a {self.dimension}-G-map has no volumes (3-cells)")
        face_of, n_faces = self.orbits([0, 1])  # a face as seen from one 3-cell
        volume = self.cells(3)
        first = _first_darts(face_of, n_faces)
        owner = volume[first]
        order = np.lexsort((first, owner))
        indices, face_offsets = self._cycles(first[order])
        per_cell = np.bincount(owner, minlength=self.n_cells(3))
        cell_offsets = np.concatenate([[0], np.cumsum(per_cell)]).astype(np.int64)
        return indices, face_offsets, cell_offsets

    def simplices(self) -> IntArray:
        """The n-cells as simplices: (c, n + 1) int64 point indices, cells in the order of :meth:`cells` (n).

        Vertex k of a cell is the point of alpha_0 alpha_1 ... alpha_{k-1}
        applied to the cell's lowest dart: for a map built from simplices, the
        input simplex in its own vertex order.

        Raises
        ------
        InvalidGMapError
            An n-cell is not a simplex ((n + 1)! darts on n + 1 distinct points).
        """
        n = self.dimension
        start = self.cell_darts(n)
        counts = np.bincount(self.cells(n), minlength=len(start))
        factorial = int(np.prod(np.arange(1, n + 2)))
        cols = [self.vertex[self._walk(start, range(k - 1, -1, -1))] for k in range(n + 1)]
        out = np.stack(cols, axis=1) if cols else np.empty((0, n + 1), dtype=np.int64)
        ordered = np.sort(out, axis=1)
        repeated = (ordered[:, 1:] == ordered[:, :-1]).any(axis=1) if n >= 1 else np.zeros(len(out), bool)
        bad = np.flatnonzero((counts != factorial) | repeated)
        if len(bad):
            raise InvalidGMapError(
                f"{n}-cells {_named(bad.astype(np.int64))} are not simplices "
                f"(a simplex has {factorial} darts on {n + 1} distinct points)",
                hint="use polygons() for faces of any size",
            )
        return out.astype(np.int64)

    def to_mesh(self) -> Mesh:
        """The map as a mesh of model 1: PointSet (n = 0), LineSet (1), Surface (2), TetraMesh (3).

        Vertices are :attr:`points` (all of them, in order); cells are
        :meth:`simplices`; properties of the n-cells become cell properties.

        Raises
        ------
        InvalidGMapError
            Points not in R^3, n > 3, or n-cells that are not simplices.
        """
        from tgsis.mesh import LineSet, PointSet, Surface, TetraMesh

        if self.embedding_dimension != 3 or self.dimension > 3:
            raise InvalidGMapError(
                f"a mesh is made of simplices in R^3: this is a {self.dimension}-G-map in R^{self.embedding_dimension}",
                hint="use simplices() or polygons()",
            )
        cls = (PointSet, LineSet, Surface, TetraMesh)[self.dimension]
        return cls(self.points, self.simplices(), cell_properties=self.cell_properties.get(self.dimension, {}))

    # ---- builders (implemented in tgsis.gmaps._build)

    @classmethod
    def from_simplices(
        cls,
        vertices: npt.ArrayLike,
        simplices: npt.ArrayLike,
        *,
        cell_properties: Mapping[str, npt.ArrayLike] | None = None,
    ) -> GMap:
        """See :func:`tgsis.gmaps.from_simplices`."""
        return from_simplices(vertices, simplices, cell_properties=cell_properties)

    @classmethod
    def from_points(
        cls,
        vertices: npt.ArrayLike,
        points: npt.ArrayLike | None = None,
        *,
        cell_properties: Mapping[str, npt.ArrayLike] | None = None,
    ) -> GMap:
        """A 0-G-map: one free dart per point (``points`` (c,) or (c, 1) indices; default every vertex)."""
        pts = np.arange(len(np.asarray(vertices))) if points is None else np.asarray(points)
        return from_simplices(vertices, pts.reshape(-1, 1), cell_properties=cell_properties)

    @classmethod
    def from_segments(
        cls,
        vertices: npt.ArrayLike,
        segments: npt.ArrayLike,
        *,
        cell_properties: Mapping[str, npt.ArrayLike] | None = None,
    ) -> GMap:
        """A 1-G-map of segments (c, 2): 2 darts per segment, alpha_1 sewn where two segments share a vertex."""
        return from_simplices(vertices, segments, cell_properties=cell_properties, size=2)

    @classmethod
    def from_triangles(
        cls,
        vertices: npt.ArrayLike,
        triangles: npt.ArrayLike,
        *,
        cell_properties: Mapping[str, npt.ArrayLike] | None = None,
    ) -> GMap:
        """A 2-G-map of triangles (c, 3): 6 darts per triangle, alpha_2 sewn across shared edges."""
        return from_simplices(vertices, triangles, cell_properties=cell_properties, size=3)

    @classmethod
    def from_tetrahedra(
        cls,
        vertices: npt.ArrayLike,
        tetrahedra: npt.ArrayLike,
        *,
        cell_properties: Mapping[str, npt.ArrayLike] | None = None,
    ) -> GMap:
        """A 3-G-map of tetrahedra (c, 4): 24 darts per tetrahedron, alpha_3 sewn across shared faces."""
        return from_simplices(vertices, tetrahedra, cell_properties=cell_properties, size=4)

    @classmethod
    def from_polygons(
        cls,
        vertices: npt.ArrayLike,
        polygons: npt.ArrayLike,
        offsets: npt.ArrayLike | None = None,
        *,
        cell_properties: Mapping[str, npt.ArrayLike] | None = None,
    ) -> GMap:
        """See :func:`tgsis.gmaps.from_polygons`."""
        return from_polygons(vertices, polygons, offsets, cell_properties=cell_properties)

    @classmethod
    def from_mesh(cls, mesh: Mesh) -> GMap:
        """See :func:`tgsis.gmaps.from_mesh`."""
        return from_mesh(mesh)


def _assembled(parts: Parts) -> GMap:
    return GMap(parts.alpha, parts.vertex, parts.points, cell_properties=parts.cell_properties)


def from_simplices(
    vertices: npt.ArrayLike,
    simplices: npt.ArrayLike,
    *,
    cell_properties: Mapping[str, npt.ArrayLike] | None = None,
    size: int | None = None,
) -> GMap:
    """The n-G-map of a simplicial mesh: (n + 1)! darts per simplex, alpha_n sewn across shared facets.

    Dart ``t * (n + 1)! + j`` is the flag of simplex ``t`` given by the j-th
    permutation ``p`` (lexicographic order) of its local vertices: vertex
    ``p[0]``, edge ``{p[0], p[1]}``, ..., facet ``{p[0] .. p[n - 1]}``. For
    i < n, alpha_i swaps ``p[i]`` and ``p[i + 1]``; alpha_n goes to the other
    simplex with the same facet, to the flag with the same global vertices.
    Orientations need not agree (non-orientable objects are fine).

    Parameters
    ----------
    vertices : (k, m) array_like of float
        Points; every one is kept, used or not.
    simplices : (c, n + 1) array_like of int
        Vertex indices of each simplex.
    cell_properties : mapping of str to (c,) array_like, optional
        Properties of the simplices: the map's n-cells, in input order.
    size : int, optional
        Required number of vertices per simplex (n + 1), for the error message.

    Returns
    -------
    GMap
        alpha (n + 1, c (n + 1)!); n-cell t is simplex t.

    Raises
    ------
    InvalidGeometryError
        Bad shapes, indices out of range, a simplex using a vertex twice, or
        a facet (the edge of triangles, the face of tetrahedra) shared by
        three or more simplices: not a quasi-manifold (the message names it).
    """
    return _assembled(simplices_parts(vertices, simplices, cell_properties=cell_properties, size=size))


def from_polygons(
    vertices: npt.ArrayLike,
    polygons: npt.ArrayLike,
    offsets: npt.ArrayLike | None = None,
    *,
    cell_properties: Mapping[str, npt.ArrayLike] | None = None,
) -> GMap:
    """The 2-G-map of polygonal faces of any sizes: 2 darts per polygon side, alpha_2 across shared edges.

    Parameters
    ----------
    vertices : (k, m) array_like of float
        Points, m >= 2.
    polygons : (f, s) array_like of int, or (q,) with ``offsets``
        Vertex cycles: one row per polygon of s >= 3 corners (quads: s = 4),
        or all polygons' corners one after another.
    offsets : (f + 1,) array_like of int, optional
        With a flat ``polygons``: polygon j is ``polygons[offsets[j]:offsets[j + 1]]``;
        ``offsets[0] == 0``, ``offsets[-1] == q``.
    cell_properties : mapping of str to (f,) array_like, optional
        Properties of the polygons (the 2-cells, in input order).

    Returns
    -------
    GMap
        Darts ``2 c`` and ``2 c + 1`` are the side from corner c to the next
        one, at corner c and at the next corner; :meth:`GMap.polygons` gives
        the input back.

    Raises
    ------
    InvalidGeometryError
        Bad shapes or offsets, a polygon with fewer than 3 corners or using a
        vertex twice, an edge shared by three or more polygons (named).
    """
    return _assembled(polygons_parts(vertices, polygons, offsets, cell_properties=cell_properties))


def from_mesh(mesh: Mesh) -> GMap:
    """The G-map of a model-1 mesh: PointSet (0), LineSet (1), Surface (2), TetraMesh (3).

    The mesh's cell properties become properties of the map's n-cells (in
    the mesh's cell order); vertex properties are not carried (a vertex may
    be several 0-cells, at a non-manifold point).

    Raises
    ------
    InvalidGeometryError
        A GeometryCollection, or a mesh that is not a quasi-manifold.
    """
    return _assembled(mesh_parts(mesh))
