"""Topology of triangulated surfaces: edges, borders, one-rings, disks, edge paths.

Everything here works on index arrays with numpy and ``scipy.sparse.csgraph``:
no Python loop runs over the vertices, edges or triangles of the mesh (only
over the vertices of one returned path), so the helpers stay fast
on meshes of 100k vertices and more. Loops and rings are put in order by list
ranking (pointer jumping) on successor arrays, which takes ``O(log L)`` numpy
passes for chains of length ``L``.

Conventions
-----------
* A triangle ``(a, b, c)`` has the **half-edges** ``a→b``, ``b→c``, ``c→a``;
  half-edge ``h = 3 t + k`` of triangle ``t`` goes from corner ``k`` to corner
  ``(k + 1) % 3``. Corner ``3 t + k`` is vertex ``triangles[t, k]`` of triangle ``t``.
* **Edges** are the undirected vertex pairs ``(i, j)``, ``i < j``, sorted.
* A **border edge** belongs to one triangle; border edges are given, and border
  loops walked, in the direction of that triangle's half-edge, so a
  counter-clockwise disk has a counter-clockwise outer border.
* A **border vertex** is on a border edge; an **interior vertex** is on a
  triangle and on no border edge. A vertex on no triangle is neither.
* The **one-ring** of vertex ``i`` lists its neighbours turning the way the
  triangles turn: consecutive neighbours ``j, k`` make the triangle ``(i, j, k)``
  (in that cyclic order). The ring of an interior vertex is closed (its last and
  first neighbours make a triangle too); that of a border vertex is open, from
  its successor along the border to its predecessor.

Build a :class:`MeshTopology` once and pass it instead of the
:class:`~tgsis.mesh.Surface` to reuse what it computed; every function accepts
either.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
import numpy.typing as npt
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components, dijkstra

from tgsis.interpolation.errors import InterpolationSetupError
from tgsis.mesh import Surface

__all__ = [
    "MeshTopology",
    "OneRings",
    "DiskCheck",
    "mesh_topology",
    "mesh_edges",
    "border_edges",
    "border_loops",
    "border_vertices",
    "interior_vertices",
    "one_rings",
    "one_ring",
    "shortest_edge_path",
    "check_disk",
]

IntArray = npt.NDArray[np.int64]
FloatArray = npt.NDArray[np.float64]
BoolArray = npt.NDArray[np.bool_]

_EMPTY = np.empty(0, dtype=np.int64)


def few(items: npt.ArrayLike, limit: int = 6) -> str:
    """``"1, 2, 3"``, or the first ``limit`` items and how many more (for messages)."""
    values = np.asarray(items).reshape(-1)
    shown = ", ".join(str(v) for v in values[:limit].tolist())
    return shown if len(values) <= limit else f"{shown} and {len(values) - limit} more"


_PLURALS = {
    "vertex": "vertices",
    "position": "positions",
    "edge": "edges",
    "triangle": "triangles",
    "control vertex": "control vertices",
    "border vertex": "border vertices",
    "non-manifold vertex": "non-manifold vertices",
}


def counted(count: int, noun: str) -> str:
    """``"1 vertex"``, ``"3 vertices"``."""
    return f"{count} {noun if count == 1 else _PLURALS.get(noun, noun + 's')}"


def named(noun: str, items: npt.ArrayLike, limit: int = 6) -> str:
    """``"vertex 5"``, ``"vertices 5, 6"`` (a few of them, see :func:`few`)."""
    size = np.size(items)
    return f"{noun if size == 1 else _PLURALS.get(noun, noun + 's')} {few(items, limit)}"


def few_pairs(pairs: npt.ArrayLike, limit: int = 4) -> str:
    """``"(1, 2), (3, 4)"``, or the first ``limit`` pairs and how many more (for messages)."""
    rows = np.asarray(pairs).reshape(-1, 2)
    shown = ", ".join(f"({a}, {b})" for a, b in rows[:limit].tolist())
    return shown if len(rows) <= limit else f"{shown} and {len(rows) - limit} more"


def _list_rank(pred: IntArray, longest: int) -> tuple[IntArray, BoolArray]:
    """Distance of every item from the head of its chain (Wyllie's pointer jumping).

    Parameters
    ----------
    pred : (q,) int64
        Predecessor of each item, -1 at chain heads.
    longest : int
        No chain has more items than this.

    Returns
    -------
    rank : (q,) int64
        Steps from the head (0 at heads).
    cyclic : (q,) bool
        Items that reach no head: they lie on a cycle (their rank is meaningless).
    """
    rank = (pred >= 0).astype(np.int64)
    jump = pred.copy()
    reach = 1
    while True:
        live = np.flatnonzero(jump >= 0)
        if live.size == 0:
            return rank, np.zeros(len(pred), dtype=bool)
        if reach >= longest:
            return rank, jump >= 0
        target = jump[live]
        rank[live] += rank[target]
        jump[live] = jump[target]
        reach *= 2


def _cycle_minimum(succ: IntArray) -> IntArray:
    """Smallest item of the cycle of every item of a permutation (pointer doubling)."""
    label = np.arange(len(succ), dtype=np.int64)
    jump = succ.copy()
    while True:
        widened = np.minimum(label, label[jump])
        if np.array_equal(widened, label):  # windows of 2^k items cover every cycle
            return label
        label = widened
        jump = jump[jump]


def _chain_minimum(nxt: IntArray, longest: int) -> IntArray:
    """Smallest item of the chain or cycle of every item (pointer doubling both ways).

    Parameters
    ----------
    nxt : (q,) int64
        Successor of each item, -1 at chain ends; every item has at most one predecessor.
    longest : int
        No chain or cycle has more items than this.
    """
    idx = np.arange(len(nxt), dtype=np.int64)
    pred = np.full(len(nxt), -1, dtype=np.int64)
    linked = nxt >= 0
    pred[nxt[linked]] = idx[linked]
    label = idx
    for pointer in (pred, nxt):  # minimum over all predecessors, then over all successors
        jump = np.where(pointer >= 0, pointer, idx)
        reach = 1
        while reach < longest:
            label = np.minimum(label, label[jump])
            jump = jump[jump]
            reach *= 2
    return label


@dataclass(frozen=True)
class OneRings:
    """Ordered one-ring neighbourhoods of all vertices, in compressed-row form.

    The ring of vertex ``i`` is ``neighbours[indptr[i]:indptr[i + 1]]``; the
    triangles around it, in the same order, are
    ``triangles[triangle_indptr[i]:triangle_indptr[i + 1]]``: triangle ``k``
    of vertex ``i`` is ``(i, ring[k], ring[(k + 1) % len(ring)])`` up to
    rotation of its corners.

    Attributes
    ----------
    indptr : (n + 1,) int64
        Start of each vertex's ring in ``neighbours``.
    neighbours : (r,) int64
        Neighbours, ring after ring, each ring turning like the triangles.
    closed : (n,) bool
        The ring is closed (interior vertex); open rings (border vertices) run
        from the border successor to the border predecessor and have one more
        neighbour than triangles. Vertices on no triangle have an empty, open ring.
    triangle_indptr : (n + 1,) int64
        Start of each vertex's triangles in ``triangles``.
    triangles : (3 m,) int64
        Triangle indices around each vertex, ring order.
    """

    indptr: IntArray
    neighbours: IntArray
    closed: BoolArray
    triangle_indptr: IntArray
    triangles: IntArray

    @property
    def degree(self) -> IntArray:
        """Number of neighbours of each vertex: (n,) int64."""
        return np.diff(self.indptr)

    def ring(self, vertex: int) -> IntArray:
        """Neighbours of ``vertex`` in ring order: (d,) int64 (a view)."""
        return self.neighbours[self.indptr[vertex] : self.indptr[vertex + 1]]

    def ring_triangles(self, vertex: int) -> IntArray:
        """Triangles around ``vertex`` in ring order: (d,) or (d - 1,) int64 (a view)."""
        return self.triangles[self.triangle_indptr[vertex] : self.triangle_indptr[vertex + 1]]


@dataclass(frozen=True)
class DiskCheck:
    """Whether a triangle set is a topological disk, and if not, why.

    A disk is connected, edge- and vertex-manifold, consistently oriented, has
    exactly one border loop and Euler characteristic ``V - E + F = 1``; every
    vertex is on a triangle.

    Attributes
    ----------
    reasons : tuple of str
        What makes it no disk, one sentence each (empty for a disk).
    n_vertices, n_edges, n_triangles : int
        V (vertices on a triangle), E and F.
    euler_characteristic : int
        ``V - E + F``.
    n_components : int
        Connected pieces (triangles joined across edges).
    n_border_loops : int
        Connected components of the border edges.
    nonmanifold_edges : (k, 2) int64
        Edges of more than two triangles.
    nonmanifold_vertices : (k,) int64
        Vertices whose triangles form more than one fan (joined across edges).
    inconsistent_edges : (k, 2) int64
        Edges whose two triangles run them in the same direction.
    unused_vertices : (k,) int64
        Vertices ``0..n-1`` on no triangle.
    """

    reasons: tuple[str, ...]
    n_vertices: int
    n_edges: int
    n_triangles: int
    euler_characteristic: int
    n_components: int
    n_border_loops: int
    nonmanifold_edges: IntArray
    nonmanifold_vertices: IntArray
    inconsistent_edges: IntArray
    unused_vertices: IntArray

    @property
    def ok(self) -> bool:
        """It is a topological disk."""
        return not self.reasons

    def summary(self) -> str:
        """``"a disk"`` or the reasons, separated by semicolons."""
        return "; ".join(self.reasons) if self.reasons else "a disk"


class MeshTopology:
    """Connectivity of a triangle set, computed on demand and kept.

    The arrays are used as given (not copied): do not change a surface's
    triangles while a topology built on them is in use.

    Parameters
    ----------
    triangles : (m, 3) array_like of int
        Vertex indices of each triangle.
    n_vertices : int, optional
        Number of vertices (default: largest index + 1).
    vertices : (n, 3) array_like of float, optional
        Coordinates, needed for edge lengths (:func:`shortest_edge_path`).

    Examples
    --------
    >>> topo = MeshTopology.of(surface)                    # doctest: +SKIP
    >>> loops = border_loops(topo); rings = one_rings(topo)  # doctest: +SKIP
    """

    def __init__(
        self, triangles: npt.ArrayLike, n_vertices: int | None = None, vertices: npt.ArrayLike | None = None
    ) -> None:
        tri = np.ascontiguousarray(triangles, dtype=np.int64).reshape(-1, 3)
        n = int(tri.max()) + 1 if n_vertices is None and tri.size else int(n_vertices or 0)
        if tri.size and (tri.min() < 0 or tri.max() >= n):
            raise InterpolationSetupError(f"triangles refer to vertices outside 0..{n - 1}")
        self.triangles: IntArray = tri
        self.n_vertices = n
        self.vertices: FloatArray | None = (
            None if vertices is None else np.ascontiguousarray(vertices, dtype=np.float64)
        )
        if self.vertices is not None and self.vertices.shape != (n, 3):
            raise InterpolationSetupError(f"vertices must be an ({n}, 3) array, got shape {self.vertices.shape}")

    @classmethod
    def of(cls, surface: Surface) -> MeshTopology:
        """Topology of a :class:`~tgsis.mesh.Surface` (with its coordinates)."""
        return cls(surface.triangles, surface.n_vertices, surface.vertices)

    @property
    def n_triangles(self) -> int:
        """Number of triangles m."""
        return len(self.triangles)

    # ---- edges

    @cached_property
    def corner_vertex(self) -> IntArray:
        """(3 m,) int64: vertex of corner ``3 t + k``, which is also where half-edge ``3 t + k`` starts."""
        return self.triangles.reshape(-1)

    @cached_property
    def next_corner(self) -> IntArray:
        """(3 m,) int64: the next corner of the same triangle (``3 t + (k + 1) % 3``)."""
        corners = np.arange(3 * self.n_triangles, dtype=np.int64).reshape(-1, 3)
        return np.ascontiguousarray(corners[:, [1, 2, 0]]).reshape(-1)

    @cached_property
    def previous_corner(self) -> IntArray:
        """(3 m,) int64: the previous corner of the same triangle (``3 t + (k + 2) % 3``)."""
        corners = np.arange(3 * self.n_triangles, dtype=np.int64).reshape(-1, 3)
        return np.ascontiguousarray(corners[:, [2, 0, 1]]).reshape(-1)

    @property
    def halfedges(self) -> IntArray:
        """(3 m, 2) int64: half-edge ``3 t + k`` runs from ``triangles[t, k]`` to ``triangles[t, (k + 1) % 3]``."""
        return np.stack([self.corner_vertex, self.corner_vertex[self.next_corner]], axis=1)

    @cached_property
    def _edge_data(self) -> tuple[IntArray, IntArray]:
        start, end = self.corner_vertex, self.corner_vertex[self.next_corner]
        n = max(self.n_vertices, 1)
        keys = np.minimum(start, end) * n + np.maximum(start, end)
        unique, inverse = np.unique(keys, return_inverse=True)
        edges = np.stack([unique // n, unique % n], axis=1)
        return edges.astype(np.int64), inverse.astype(np.int64).reshape(-1)

    @property
    def edges(self) -> IntArray:
        """(e, 2) int64 undirected edges ``(i, j)``, ``i < j``, in lexicographic order."""
        return self._edge_data[0]

    @property
    def halfedge_edge(self) -> IntArray:
        """(3 m,) int64: the edge of each half-edge."""
        return self._edge_data[1]

    @cached_property
    def edge_triangle_count(self) -> IntArray:
        """(e,) int64: number of triangles on each edge."""
        return np.bincount(self.halfedge_edge, minlength=len(self.edges)).astype(np.int64)

    @cached_property
    def _edge_first_last(self) -> tuple[IntArray, IntArray]:
        h = np.arange(len(self.halfedge_edge), dtype=np.int64)
        first = np.full(len(self.edges), len(h), dtype=np.int64)
        last = np.full(len(self.edges), -1, dtype=np.int64)
        np.minimum.at(first, self.halfedge_edge, h)
        np.maximum.at(last, self.halfedge_edge, h)
        return first, last

    @property
    def edge_halfedges(self) -> IntArray:
        """(e, 2) int64: the lowest and the highest half-edge of each edge (the same one on a border edge)."""
        return np.stack(self._edge_first_last, axis=1)

    @cached_property
    def edge_triangles(self) -> IntArray:
        """(e, 2) int64: the two triangles of each edge, -1 for the second on a border edge.

        On an edge of more than two triangles, the lowest and highest of them.
        """
        first, last = self._edge_first_last
        return np.stack([first // 3, np.where(self.edge_triangle_count == 1, -1, last // 3)], axis=1)

    @cached_property
    def twins(self) -> IntArray:
        """(3 m,) int64: the other half-edge of the same edge, -1 on border and non-manifold edges."""
        edge = self.halfedge_edge
        first, last = self._edge_first_last
        twin = first[edge] + last[edge] - np.arange(len(edge))
        return np.where(self.edge_triangle_count[edge] == 2, twin, -1).astype(np.int64)

    @cached_property
    def inconsistent_edges(self) -> BoolArray:
        """(e,) bool: edges of two triangles that both run them the same way (orientation flips there)."""
        forward = (self.corner_vertex < self.corner_vertex[self.next_corner]).astype(np.float64)
        forward_count = np.bincount(self.halfedge_edge, weights=forward, minlength=len(self.edges))
        return np.asarray((self.edge_triangle_count == 2) & (forward_count != 1))

    @property
    def is_border_edge(self) -> BoolArray:
        """(e,) bool: the edge belongs to exactly one triangle."""
        return np.asarray(self.edge_triangle_count == 1)

    def find_edges(self, pairs: npt.ArrayLike) -> IntArray:
        """Edge index of each vertex pair (either order), -1 where the mesh has no such edge.

        Parameters
        ----------
        pairs : (k, 2) array_like of int
            Vertex pairs, indices in ``0..n-1``.

        Returns
        -------
        (k,) int64
        """
        p = np.asarray(pairs, dtype=np.int64).reshape(-1, 2)
        n = self.n_vertices
        keys = np.minimum(p[:, 0], p[:, 1]) * n + np.maximum(p[:, 0], p[:, 1])
        edge_keys = self.edges[:, 0] * n + self.edges[:, 1]
        at = np.minimum(np.searchsorted(edge_keys, keys), max(len(edge_keys) - 1, 0))
        found = (edge_keys[at] == keys) if len(edge_keys) else np.zeros(len(keys), dtype=bool)
        return np.where(found, at, -1).astype(np.int64)

    # ---- border

    @cached_property
    def border_halfedges(self) -> IntArray:
        """(b, 2) int64: the border edges, each in the direction of its triangle."""
        on_border = self.edge_triangle_count[self.halfedge_edge] == 1
        return np.stack([self.corner_vertex[on_border], self.corner_vertex[self.next_corner][on_border]], axis=1)

    @cached_property
    def used_vertices(self) -> BoolArray:
        """(n,) bool: the vertex is on a triangle."""
        used = np.zeros(self.n_vertices, dtype=bool)
        used[self.corner_vertex] = True
        return used

    @cached_property
    def is_border_vertex(self) -> BoolArray:
        """(n,) bool: the vertex is on a border edge."""
        border = np.zeros(self.n_vertices, dtype=bool)
        border[self.border_halfedges.reshape(-1)] = True
        return border

    @cached_property
    def border_loops(self) -> tuple[IntArray, ...]:
        """Border loops as vertex sequences (first vertex not repeated), see :func:`border_loops`."""
        a, b = self.border_halfedges[:, 0], self.border_halfedges[:, 1]
        if a.size == 0:
            return ()
        n = self.n_vertices
        out_degree = np.bincount(a, minlength=n)
        in_degree = np.bincount(b, minlength=n)
        bad = np.flatnonzero((out_degree != in_degree) | (out_degree > 1))
        if bad.size:
            raise InterpolationSetupError(
                f"border loops are not defined: the border passes more than once through {named('vertex', bad)}, "
                "or the triangles there are oriented inconsistently",
                hint="check_disk() tells what is wrong with the mesh",
            )
        verts = np.flatnonzero(out_degree)
        local = np.full(n, -1, dtype=np.int64)
        local[verts] = np.arange(len(verts))
        succ = np.empty(len(verts), dtype=np.int64)
        succ[local[a]] = local[b]
        pred = np.empty(len(verts), dtype=np.int64)
        pred[succ] = np.arange(len(verts))
        label = _cycle_minimum(succ)
        heads = np.flatnonzero(label == np.arange(len(verts)))
        pred[heads] = -1
        rank, _ = _list_rank(pred, len(verts))
        loop = np.searchsorted(heads, label)
        offsets = np.concatenate([[0], np.cumsum(np.bincount(loop, minlength=len(heads)))])
        ordered = np.empty(len(verts), dtype=np.int64)
        ordered[offsets[loop] + rank] = verts
        return tuple(ordered[offsets[i] : offsets[i + 1]] for i in range(len(heads)))

    # ---- corners and fans

    @cached_property
    def wedge_next(self) -> IntArray | None:
        """(3 m,) int64: the corner that follows each corner around its vertex, -1 at a border.

        Corner ``3 t + k`` (vertex ``i``) turns around ``i`` from the next corner
        ``a`` of its triangle to the one after, ``b``; it is followed by the
        corner of ``i`` in the triangle across the edge ``(i, b)``. ``None`` when
        an edge is on more than two triangles or two triangles run an edge the
        same way (the turning is then not defined).
        """
        nxt: IntArray = self.twins[self.previous_corner]  # across the half-edge b -> i
        center = self.corner_vertex
        if (self.edge_triangle_count > 2).any() or (center[np.maximum(nxt, 0)] != center)[nxt >= 0].any():
            return None
        return nxt

    def corner_groups(self, blocked_edges: BoolArray | None = None) -> IntArray:
        """Group the corners of each vertex into fans joined across edges not blocked.

        Two corners of the same vertex are joined when their triangles share an
        edge through that vertex. Corners of a vertex fall in one group for a
        manifold vertex; cutting along edges (``blocked_edges``) splits them.

        Parameters
        ----------
        blocked_edges : (e,) bool, optional
            Edges that do not join.

        Returns
        -------
        (3 m,) int64
            The group of each corner ``3 t + k``, named by its lowest corner: a
            group holds corners of one vertex only, and the groups are the
            corners ``c`` with ``groups[c] == c``.
        """
        m3 = 3 * self.n_triangles
        h = np.arange(m3, dtype=np.int64)
        edge = self.halfedge_edge
        nxt = self.wedge_next
        if nxt is not None:  # a manifold, oriented mesh: fans are chains of corners
            if blocked_edges is not None:
                nxt = np.where(blocked_edges[edge[self.previous_corner]], -1, nxt)
            longest = int(np.bincount(self.corner_vertex).max()) if m3 else 1
            return _chain_minimum(nxt, longest)
        # otherwise join each half-edge's two corners to the corners of the same vertices in
        # the edge's lowest half-edge f (whichever way f runs): a star per edge and end vertex
        f = self._edge_first_last[0][edge]
        f_end = self.next_corner[f]
        h_end = self.next_corner
        same_way = self.corner_vertex[f] == self.corner_vertex
        keep = (f != h) if blocked_edges is None else (f != h) & ~blocked_edges[edge]
        rows = np.concatenate([h[keep], h_end[keep]])
        cols = np.concatenate([np.where(same_way, f, f_end)[keep], np.where(same_way, f_end, f)[keep]])
        graph = sp.csr_matrix((np.ones(len(rows), dtype=np.int8), (rows, cols)), shape=(m3, m3))
        count, labels = connected_components(graph, directed=False)
        lowest = np.full(count, m3, dtype=np.int64)
        np.minimum.at(lowest, labels, h)
        result: IntArray = lowest[labels]
        return result

    @cached_property
    def fans_per_vertex(self) -> IntArray:
        """(n,) int64: number of fans (corner groups) of each vertex; 1 for a manifold vertex, 0 if unused."""
        groups = self.corner_groups()
        roots = np.flatnonzero(groups == np.arange(len(groups)))
        return np.bincount(self.corner_vertex[roots], minlength=self.n_vertices).astype(np.int64)

    def triangle_components(self, blocked_edges: BoolArray | None = None) -> tuple[IntArray, int]:
        """Flood-fill the triangles across edges that are not blocked.

        Parameters
        ----------
        blocked_edges : (e,) bool, optional
            Edges not to cross.

        Returns
        -------
        labels : (m,) int64
            Component of each triangle, numbered in the order of their lowest triangle.
        count : int
        """
        m = self.n_triangles
        h = np.arange(3 * m, dtype=np.int64)
        edge = self.halfedge_edge
        f = self._edge_first_last[0][edge]
        keep = (f != h) if blocked_edges is None else (f != h) & ~blocked_edges[edge]
        graph = sp.csr_matrix((np.ones(int(keep.sum()), dtype=np.int8), (h[keep] // 3, f[keep] // 3)), shape=(m, m))
        count, labels = connected_components(graph, directed=False)
        lowest = np.full(count, m, dtype=np.int64)
        np.minimum.at(lowest, labels, np.arange(m, dtype=np.int64))
        rank = np.empty(count, dtype=np.int64)
        rank[np.argsort(lowest)] = np.arange(count, dtype=np.int64)
        return rank[labels], int(count)

    # ---- rings

    @cached_property
    def one_rings(self) -> OneRings:
        """Ordered one-rings of all vertices, see :func:`one_rings`."""
        n, m = self.n_vertices, self.n_triangles
        if m == 0:
            zeros = np.zeros(n + 1, dtype=np.int64)
            return OneRings(zeros, _EMPTY, np.zeros(n, dtype=bool), zeros, _EMPTY)
        center = self.corner_vertex
        after = center[self.next_corner]  # wedge 3 t + k turns around its corner from a ...
        before = center[self.previous_corner]  # ... to b
        nxt_or_none = self.wedge_next
        if nxt_or_none is None:
            bad = self.edges[(self.edge_triangle_count > 2) | self.inconsistent_edges]
            raise InterpolationSetupError(
                f"one-rings are not defined: edges {few_pairs(bad)} are on more than 2 triangles or their "
                "triangles are oriented inconsistently",
                hint="check_disk() tells what is wrong with the mesh",
            )
        nxt = nxt_or_none
        pred = np.full(3 * m, -1, dtype=np.int64)
        has_next = np.flatnonzero(nxt >= 0)
        pred[nxt[has_next]] = has_next
        wedges = np.bincount(center, minlength=n)
        open_heads = np.flatnonzero(pred < 0)
        heads_per_vertex = np.bincount(center[open_heads], minlength=n)
        if (heads_per_vertex > 1).any():
            bad = np.flatnonzero(heads_per_vertex > 1)
            raise InterpolationSetupError(
                f"one-rings are not defined: the triangles around {named('vertex', bad)} form several fans "
                "(non-manifold vertices)",
                hint="check_disk() tells what is wrong with the mesh",
            )
        closed = (heads_per_vertex == 0) & (wedges > 0)
        # closed rings start at the vertex's corner in its lowest triangle
        first_corner = np.full(n, 3 * m, dtype=np.int64)
        np.minimum.at(first_corner, center, np.arange(3 * m, dtype=np.int64))
        pred[first_corner[closed]] = -1
        rank, cyclic = _list_rank(pred, int(wedges.max()))
        if cyclic.any():
            raise InterpolationSetupError(
                f"one-rings are not defined: the triangles around {named('vertex', np.unique(center[cyclic]))} "
                "form several fans (non-manifold vertices)",
                hint="check_disk() tells what is wrong with the mesh",
            )
        degree = wedges + (~closed & (wedges > 0))
        indptr = np.concatenate([[0], np.cumsum(degree)]).astype(np.int64)
        neighbours = np.empty(int(indptr[-1]), dtype=np.int64)
        neighbours[indptr[center] + rank] = after
        last = np.flatnonzero(nxt < 0)  # last wedge of an open ring: add its b
        neighbours[indptr[center[last]] + rank[last] + 1] = before[last]
        triangle_indptr = np.concatenate([[0], np.cumsum(wedges)]).astype(np.int64)
        triangles = np.empty(3 * m, dtype=np.int64)
        triangles[triangle_indptr[center] + rank] = np.arange(3 * m) // 3
        return OneRings(indptr, neighbours, closed, triangle_indptr, triangles)


def mesh_topology(mesh: Surface | MeshTopology) -> MeshTopology:
    """The :class:`MeshTopology` of a surface (or the topology itself)."""
    return mesh if isinstance(mesh, MeshTopology) else MeshTopology.of(mesh)


def mesh_edges(mesh: Surface | MeshTopology) -> IntArray:
    """Undirected edges.

    Parameters
    ----------
    mesh : Surface or MeshTopology

    Returns
    -------
    (e, 2) int64
        ``(i, j)`` with ``i < j``, in lexicographic order.
    """
    return mesh_topology(mesh).edges


def border_edges(mesh: Surface | MeshTopology) -> IntArray:
    """Border edges (on one triangle), each oriented like its triangle.

    Parameters
    ----------
    mesh : Surface or MeshTopology

    Returns
    -------
    (b, 2) int64
        ``(i, j)``: the triangle runs ``i → j``, in triangle order.
    """
    return mesh_topology(mesh).border_halfedges


def border_loops(mesh: Surface | MeshTopology) -> list[IntArray]:
    """Border loops, each an ordered vertex sequence oriented like the triangles.

    Consecutive vertices (and last to first) are border edges ``i → j`` in the
    direction of their triangle. Each loop starts at its smallest vertex; loops
    come in the order of that vertex.

    Parameters
    ----------
    mesh : Surface or MeshTopology

    Returns
    -------
    list of (k_i,) int64
        One array per loop (empty list for a closed surface).

    Raises
    ------
    InterpolationSetupError
        The border passes twice through a vertex (non-manifold vertex) or the
        triangles along it are oriented inconsistently.
    """
    return list(mesh_topology(mesh).border_loops)


def border_vertices(mesh: Surface | MeshTopology) -> IntArray:
    """Vertices on a border edge: (k,) int64, ascending."""
    return np.flatnonzero(mesh_topology(mesh).is_border_vertex).astype(np.int64)


def interior_vertices(mesh: Surface | MeshTopology) -> IntArray:
    """Vertices on a triangle and on no border edge: (k,) int64, ascending."""
    topo = mesh_topology(mesh)
    return np.flatnonzero(topo.used_vertices & ~topo.is_border_vertex).astype(np.int64)


def one_rings(mesh: Surface | MeshTopology) -> OneRings:
    """Ordered one-ring neighbourhoods of all vertices (compressed rows).

    Parameters
    ----------
    mesh : Surface or MeshTopology
        A manifold, consistently oriented mesh.

    Returns
    -------
    OneRings
        Neighbours of each vertex turning like the triangles; interior rings
        closed and starting in the lowest-numbered triangle of the vertex, border rings open from
        the border successor to the border predecessor.

    Raises
    ------
    InterpolationSetupError
        A non-manifold edge or vertex, or inconsistent orientation.
    """
    return mesh_topology(mesh).one_rings


def one_ring(mesh: Surface | MeshTopology, vertex: int) -> IntArray:
    """Ordered one-ring of one vertex, computed from its triangles only.

    Parameters
    ----------
    mesh : Surface or MeshTopology
    vertex : int

    Returns
    -------
    (d,) int64
        As ``one_rings(mesh).ring(vertex)``, without computing the other rings.
    """
    topo = mesh_topology(mesh)
    if not 0 <= vertex < topo.n_vertices:
        raise InterpolationSetupError(f"vertex {vertex} is not in the mesh (0..{topo.n_vertices - 1})")
    fan = topo.triangles[(topo.triangles == vertex).any(axis=1)]
    used, local = np.unique(fan, return_inverse=True)
    local_topo = MeshTopology(local.reshape(-1, 3), len(used))
    return used[local_topo.one_rings.ring(int(np.searchsorted(used, vertex)))].astype(np.int64)


def shortest_edge_path(
    mesh: Surface | MeshTopology, start: int, end: int, *, avoid: npt.ArrayLike | None = None
) -> IntArray:
    """Shortest path along edges between two vertices, edge lengths as weights (Dijkstra).

    This is how fence paths are proposed: pass the other control vertices as
    ``avoid`` so that the path has no control vertex inside.

    Parameters
    ----------
    mesh : Surface or MeshTopology
        With coordinates (a :class:`MeshTopology` built with ``vertices``).
    start, end : int
        End vertices.
    avoid : array_like of int, optional
        Vertices the path must not pass through (``start`` and ``end`` excepted).

    Returns
    -------
    (k,) int64
        ``start, ..., end``; consecutive vertices share an edge.

    Raises
    ------
    InterpolationSetupError
        A vertex outside the mesh, no coordinates, or no path.
    """
    topo = mesh_topology(mesh)
    n = topo.n_vertices
    if topo.vertices is None:
        raise InterpolationSetupError("shortest_edge_path needs vertex coordinates: build MeshTopology(..., vertices=)")
    for which, v in (("start", start), ("end", end)):
        if not 0 <= v < n:
            raise InterpolationSetupError(f"shortest edge path: {which} vertex {v} is not in the mesh (0..{n - 1})")
    start, end = int(start), int(end)
    if start == end:
        return np.array([start], dtype=np.int64)
    edges = topo.edges
    keep = np.ones(len(edges), dtype=bool)
    avoided = _EMPTY
    if avoid is not None:
        avoided = np.setdiff1d(np.asarray(avoid, dtype=np.int64).reshape(-1), [start, end])
        blocked = np.zeros(n, dtype=bool)
        blocked[avoided[(avoided >= 0) & (avoided < n)]] = True
        keep = ~(blocked[edges[:, 0]] | blocked[edges[:, 1]])
    e = edges[keep]
    lengths = np.linalg.norm(topo.vertices[e[:, 1]] - topo.vertices[e[:, 0]], axis=1)
    weights = np.maximum(lengths, np.finfo(np.float64).tiny)  # a zero-length edge still joins
    graph = sp.csr_matrix((weights, (e[:, 0], e[:, 1])), shape=(n, n))
    dist, pred = dijkstra(graph, directed=False, indices=start, return_predecessors=True)
    if not np.isfinite(dist[end]):
        extra = f" avoiding {named('vertex', avoided)}" if avoided.size else ""
        raise InterpolationSetupError(f"no edge path from vertex {start} to vertex {end}{extra}")
    path = [end]
    while path[-1] != start:
        path.append(int(pred[path[-1]]))
    return np.array(path[::-1], dtype=np.int64)


def check_disk(mesh: Surface | MeshTopology, *, vertex_ids: npt.ArrayLike | None = None) -> DiskCheck:
    """Check that a mesh is a topological disk, and say precisely why not.

    Parameters
    ----------
    mesh : Surface or MeshTopology
    vertex_ids : (n,) array_like of int, optional
        The name of each vertex in messages and in the returned arrays (for a
        patch numbered ``0..n-1`` on its own: its vertices in the whole mesh).

    Returns
    -------
    DiskCheck
        ``ok`` for a disk; otherwise ``reasons`` names what is wrong (pieces,
        non-manifold edges and vertices, inconsistent orientation, border loops,
        Euler characteristic, vertices on no triangle).
    """
    topo = mesh_topology(mesh)
    reasons: list[str] = []
    unused = np.flatnonzero(~topo.used_vertices).astype(np.int64)
    empty2 = np.empty((0, 2), dtype=np.int64)
    if topo.n_triangles == 0:
        unused = unused if vertex_ids is None else np.asarray(vertex_ids, dtype=np.int64)[unused]
        return DiskCheck(("it has no triangle",), 0, 0, 0, 0, 0, 0, empty2, _EMPTY, empty2, unused)
    V = int(topo.used_vertices.sum())
    E = len(topo.edges)
    F = topo.n_triangles
    chi = V - E + F
    _, pieces = topo.triangle_components()
    count = topo.edge_triangle_count
    nonmanifold_edges = topo.edges[count > 2]
    inconsistent = topo.edges[topo.inconsistent_edges]
    fans = topo.fans_per_vertex
    nonmanifold_vertices = np.flatnonzero(fans > 1).astype(np.int64)
    if vertex_ids is not None:
        ids = np.asarray(vertex_ids, dtype=np.int64)
        unused, nonmanifold_vertices = ids[unused], ids[nonmanifold_vertices]
        nonmanifold_edges = np.sort(ids[nonmanifold_edges], axis=1)
        inconsistent = np.sort(ids[inconsistent], axis=1)
    border = topo.edges[count == 1]
    if len(border):
        graph = sp.coo_matrix(
            (np.ones(len(border), dtype=np.int8), (border[:, 0], border[:, 1])),
            shape=(topo.n_vertices, topo.n_vertices),
        ).tocsr()
        _, labels = connected_components(graph, directed=False)
        loops = len(np.unique(labels[np.unique(border)]))
    else:
        loops = 0
    if pieces > 1:
        reasons.append(f"it is in {pieces} pieces (triangles joined across edges)")
    if len(nonmanifold_edges):
        shared = count[count > 2]
        reasons.append(
            f"{counted(len(nonmanifold_edges), 'edge')} on more than 2 triangles: "
            + few_pairs(nonmanifold_edges)
            + f" (on {few(shared)} triangles)"
        )
    if len(nonmanifold_vertices):
        reasons.append(
            f"{counted(len(nonmanifold_vertices), 'non-manifold vertex')} (whose triangles form "
            f"separate fans): {few(nonmanifold_vertices)}"
        )
    if len(inconsistent):
        reasons.append(
            f"the triangles on {counted(len(inconsistent), 'edge')} are oriented inconsistently "
            f"(both run the edge the same way): {few_pairs(inconsistent)}"
        )
    if loops != 1:
        reasons.append("it has no border (a closed surface)" if loops == 0 else f"{loops} border loops")
    if chi != 1:
        manifold = pieces == 1 and not len(nonmanifold_edges) and not len(nonmanifold_vertices)
        genus = (2 - chi - loops) // 2 if manifold and not len(inconsistent) and (2 - chi - loops) % 2 == 0 else 0
        reasons.append(
            f"Euler characteristic V - E + F = {V} - {E} + {F} = {chi}, not 1"
            + (f" (genus {genus}: the surface has handles)" if genus > 0 else "")
        )
    if len(unused):
        reasons.append(f"{counted(len(unused), 'vertex')} on no triangle: {few(unused)}")
    return DiskCheck(
        tuple(reasons),
        V,
        E,
        F,
        chi,
        pieces,
        loops,
        nonmanifold_edges.astype(np.int64),
        nonmanifold_vertices,
        inconsistent.astype(np.int64),
        unused,
    )


def path_problems(topo: MeshTopology, path: npt.ArrayLike, label: str) -> tuple[IntArray, IntArray, list[str]]:
    """Check that ``path`` is an edge path: at least 2 vertices in the mesh, none twice, consecutive ones on an edge.

    Parameters
    ----------
    topo : MeshTopology
    path : (k,) array_like of int
        Vertex sequence.
    label : str
        How messages name the path (``"cutting path 0 ('f1')"``).

    Returns
    -------
    vertices : (k,) int64
        The path (empty if it is not a vector of integers).
    edges : (k - 1,) int64
        Edge index of each step, -1 where the vertices share no edge.
    problems : list of str
        One sentence per problem, each starting with ``label``.
    """
    problems: list[str] = []
    raw = np.asarray(path)
    if raw.ndim != 1 or (raw.size and raw.dtype.kind not in "iu"):
        return _EMPTY, _EMPTY, [f"{label} is not a sequence of vertex indices (shape {raw.shape}, type {raw.dtype})"]
    verts = raw.astype(np.int64)
    n = topo.n_vertices
    if len(verts) < 2:
        problems.append(f"{label} has {counted(len(verts), 'vertex')}: a path needs at least 2")
    outside = np.flatnonzero((verts < 0) | (verts >= n))
    if outside.size:
        problems.append(
            f"{label} refers to {named('vertex', verts[outside])} ({named('position', outside)}), "
            f"but the mesh has {n} vertices"
        )
        return verts, np.full(max(len(verts) - 1, 0), -1, dtype=np.int64), problems
    order = np.argsort(verts, kind="stable")
    repeated = np.flatnonzero(verts[order][1:] == verts[order][:-1])
    for r in repeated[:3]:
        problems.append(
            f"{label} passes twice through vertex {verts[order[r]]} (positions {order[r]} and {order[r + 1]})"
        )
    steps = np.stack([verts[:-1], verts[1:]], axis=1)
    edge_ids = topo.find_edges(steps)
    for i in np.flatnonzero((edge_ids < 0) & (steps[:, 0] != steps[:, 1]))[:3]:
        problems.append(
            f"{label} is not an edge path: vertices {verts[i]} and {verts[i + 1]} "
            f"(positions {i} and {i + 1}) share no edge"
        )
    return verts, edge_ids, problems
