"""Cutting a surface along paths: the faults and fractures that open into gaps in the target.

The mesh is cut along each path by duplicating the path's vertices and edges;
how many copies a vertex gets follows from where it is:

* ``"both_border"``: both ends on the border, a crack across the surface (or
  from border to border): every path vertex is duplicated;
* ``"start_inside"`` / ``"end_inside"``: one end inside the surface, a crack
  that ends there: every path vertex but that end is duplicated;
* ``"both_inside"``: a crack closed at both ends: every path vertex but the two
  ends is duplicated (so it needs at least 3 vertices).

The copies of a path vertex are the fans of its triangles once the path's edges
no longer join them, so several paths may meet or cross at a vertex (they may
not share an edge). Cutting never moves geometry: copies stand at the original
coordinates, the triangles keep their corner order (orientation) and a vertex
that is not duplicated keeps its index; copies get indices ``n, n + 1, ...``.
The triangles left of a path (those that run its edges in the path's
direction) keep the original vertices; those on its right get the copies.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal, get_args

import numpy as np
import numpy.typing as npt

from tgsis.interpolation.errors import InterpolationSetupError
from tgsis.interpolation.topology import MeshTopology, named, path_problems
from tgsis.mesh import Surface

__all__ = ["CutEnds", "CutResult", "cut_along_paths", "cut_ends"]

IntArray = npt.NDArray[np.int64]

#: Which ends of a cutting path lie on the border (see the module documentation).
CutEnds = Literal["both_border", "start_inside", "end_inside", "both_inside"]

_ENDS: tuple[str, ...] = get_args(CutEnds)


@dataclass(frozen=True)
class CutResult:
    """A surface cut along paths.

    Attributes
    ----------
    surface : Surface
        The cut surface: ``n'`` vertices (the ``n`` original ones first, then
        the copies), the same triangles in the same order and orientation,
        vertex properties carried over to the copies.
    original_vertex : (n',) int64
        The original vertex of each new vertex (``arange(n)`` then the
        originals of the copies).
    paths : tuple of (k_i,) int64
        The cutting paths, as validated (original indices).
    ends : tuple of CutEnds
        The end case of each path.
    """

    surface: Surface
    original_vertex: IntArray
    paths: tuple[IntArray, ...]
    ends: tuple[CutEnds, ...]

    @property
    def n_copies(self) -> int:
        """Number of vertices added by the cut."""
        return int(np.count_nonzero(self.original_vertex != np.arange(len(self.original_vertex))))


def _label(index: int, names: Sequence[str | None] | None) -> str:
    name = names[index] if names is not None and index < len(names) else None
    return f"cutting path {index}" + (f" ({name!r})" if name else "")


def cut_ends(is_border_start: bool, is_border_end: bool) -> CutEnds:
    """The end case of a path whose start and end vertex are (not) on the border."""
    if is_border_start and is_border_end:
        return "both_border"
    if is_border_start:
        return "end_inside"
    if is_border_end:
        return "start_inside"
    return "both_inside"


def _left_corners(topo: MeshTopology, paths: list[IntArray]) -> IntArray:
    """Corners at both ends of each path edge in the triangle that runs the edge in the path's direction."""
    n = topo.n_vertices
    corner_vertex = topo.corner_vertex
    keys = corner_vertex * n + corner_vertex[topo.next_corner]
    order = np.argsort(keys)
    want = np.concatenate([p[:-1] * n + p[1:] for p in paths])
    at = np.minimum(np.searchsorted(keys[order], want), len(keys) - 1)
    h = order[at][keys[order[at]] == want]
    return np.concatenate([h, topo.next_corner[h]])


def _edges_at(steps: IntArray, at: IntArray) -> str:
    """``"edge (3, 4) (positions 2 and 3) is"``, ``"edges (3, 4), (4, 5) (from positions 2, 3) are"``."""
    pairs = [f"({a}, {b})" for a, b in steps[at].tolist()]
    if len(at) == 1:
        return f"edge {pairs[0]} (positions {at[0]} and {at[0] + 1}) is"
    return f"{named('edge', pairs)} (from {named('position', at)}) are"


def _where(is_border: bool) -> str:
    return "on the border" if is_border else "inside the surface"


def cut_along_paths(
    surface: Surface,
    paths: Sequence[npt.ArrayLike],
    *,
    names: Sequence[str | None] | None = None,
    ends: Sequence[CutEnds | None] | None = None,
) -> CutResult:
    """Cut a surface along paths by duplicating their vertices and edges.

    Parameters
    ----------
    surface : Surface
        The mesh to cut (not changed).
    paths : sequence of (k_i,) array_like of int
        Cutting paths: vertex sequences, consecutive vertices on an interior
        edge, no vertex twice, only the end vertices on the border.
    names : sequence of str or None, optional
        Names of the paths, for messages.
    ends : sequence of CutEnds or None, optional
        The end case the user means for each path; checked against where the
        end vertices are (``None``: whatever they are).

    Returns
    -------
    CutResult
        The cut surface and the map new vertex -> original vertex.

    Raises
    ------
    InterpolationSetupError
        Naming each path at fault: not an edge path, a vertex twice, an edge on
        the border already or on more than two triangles, an inner vertex on the
        border or non-manifold, a declared end case that the end vertices
        contradict, a crack closed at both ends with no vertex between them,
        two paths sharing an edge.

    Examples
    --------
    >>> cut = cut_along_paths(surface, [[12, 13, 14]])          # doctest: +SKIP
    >>> cut.surface.vertices[cut.original_vertex].tolist() == surface.vertices.tolist()  # doctest: +SKIP

    Notes
    -----
    Only the triangles around the path vertices are looked at (everything a
    cut needs to know is there), so a cut costs little more than copying the
    surface, however large it is.
    """
    n = surface.n_vertices
    on_path = np.zeros(n, dtype=bool)
    for path in paths:
        raw = np.asarray(path)
        if raw.ndim == 1 and raw.dtype.kind in "iu":
            on_path[raw[(raw >= 0) & (raw < n)]] = True
    near = np.flatnonzero(on_path[surface.triangles].any(axis=1))
    topo = MeshTopology(surface.triangles[near], n)  # the triangles around the paths
    count = topo.edge_triangle_count
    on_border = topo.is_border_vertex
    problems: list[str] = []
    valid: list[IntArray] = []
    cases: list[CutEnds] = []
    edge_owner: dict[int, int] = {}
    for i, path in enumerate(paths):
        label = _label(i, names)
        verts, edge_ids, found = path_problems(topo, path, label)
        declared = ends[i] if ends is not None and i < len(ends) else None
        if declared is not None and declared not in _ENDS:
            found.append(f"{label}: unknown end case {declared!r} (use one of {', '.join(_ENDS)})")
        if found:
            problems.extend(found)
            continue
        steps = np.stack([verts[:-1], verts[1:]], axis=1)
        on_edge_border = np.flatnonzero(count[edge_ids] == 1)
        crowded = np.flatnonzero(count[edge_ids] > 2)
        if on_edge_border.size:
            found.append(f"{label}: {_edges_at(steps, on_edge_border)} on the border already: there is nothing to cut")
        if crowded.size:
            found.append(
                f"{label}: {_edges_at(steps, crowded)} on more than 2 triangles (non-manifold): "
                "a cut cannot follow a non-manifold edge"
            )
        inner = np.flatnonzero(on_border[verts[1:-1]]) + 1
        if inner.size and not on_edge_border.size:
            found.append(
                f"{label} passes through {named('border vertex', verts[inner])} ({named('position', inner)}): "
                "only its end vertices may be on the border; split it there into several cutting paths"
            )
        tangled = np.flatnonzero(topo.fans_per_vertex[verts] > 1)
        if tangled.size:
            found.append(
                f"{label} passes through {named('non-manifold vertex', verts[tangled])} "
                f"({named('position', tangled)}): the triangles there form separate fans"
            )
        start, end = int(verts[0]), int(verts[-1])
        actual = cut_ends(bool(on_border[start]), bool(on_border[end]))
        if declared is not None and declared != actual:
            found.append(
                f"{label} is declared {declared!r}, but its start vertex {start} is "
                f"{_where(bool(on_border[start]))} and its end vertex {end} is "
                f"{_where(bool(on_border[end]))} ({actual!r})"
            )
        elif actual == "both_inside" and len(verts) < 3:
            found.append(
                f"{label} ends inside the surface at both ends but has only the 2 vertices {start} and "
                f"{end}: a crack closed at both ends needs a vertex between them"
            )
        for j, e in enumerate(edge_ids.tolist()):
            other = edge_owner.setdefault(e, i)
            if other != i:
                found.append(
                    f"{_label(other, names)} and {label} share the edge ({verts[j]}, {verts[j + 1]}): "
                    "cutting paths may meet at vertices only"
                )
                break
        if found:
            problems.extend(found)
            continue
        valid.append(verts)
        cases.append(actual)
    if problems:
        raise InterpolationSetupError.collect("cutting paths", problems)
    original = np.arange(n, dtype=np.int64)
    new_corners = surface.triangles.reshape(-1).copy()
    if valid:
        blocked = np.zeros(len(topo.edges), dtype=bool)
        blocked[np.fromiter(edge_owner, dtype=np.int64)] = True
        labels = topo.corner_groups(blocked)  # each fan named by its lowest corner
        corner_vertex = topo.corner_vertex
        cut_here = np.zeros(n, dtype=bool)
        cut_here[np.concatenate(valid)] = True
        corners = np.flatnonzero(cut_here[corner_vertex])
        group = labels[corners]
        groups = np.unique(group)
        group_vertex = corner_vertex[groups]
        # the fan left of the path (holding the triangle that runs a path edge forwards) keeps the index
        left = np.ones(len(labels), dtype=np.int64)
        left[labels[_left_corners(topo, valid)]] = 0
        order = np.lexsort((groups, left[groups], group_vertex))
        groups, group_vertex = groups[order], group_vertex[order]
        keeps = np.concatenate([[True], group_vertex[1:] != group_vertex[:-1]])
        new_index = np.empty(len(labels), dtype=np.int64)
        new_index[groups[keeps]] = group_vertex[keeps]
        new_index[groups[~keeps]] = n + np.arange(int((~keeps).sum()), dtype=np.int64)
        original = np.concatenate([original, group_vertex[~keeps]])
        new_corners[3 * near[corners // 3] + corners % 3] = new_index[group]
    cut = Surface(
        surface.vertices[original],
        new_corners.reshape(-1, 3),
        vertex_properties={k: v[original] for k, v in surface.vertex_properties.items()},
        cell_properties={k: v.copy() for k, v in surface.cell_properties.items()},
        name=surface.name,
        metadata=surface.metadata,
    )
    return CutResult(cut, original, tuple(valid), tuple(cases))
