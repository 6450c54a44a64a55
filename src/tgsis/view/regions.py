"""The merge regions of a conflicting object as the browser view draws them on the mesh (no database).

A region (:class:`tgsis.merge3.MergeRegion`) travels as a few facts in the
JSON header — its index, what happens there (its *state*, below), the solution,
each side's count of changed vertices and cells and largest displacement, its
box — and as the *positions* of its vertices and cells (margin included) in the
drawn mesh's own arrays: two flat uint32 arrays, ``region_vertices`` and
``region_cells``, the regions one after the other (``drawn`` in each header
entry says how many are its). Nothing of the mesh is copied: the bytes follow
the size of the regions, not of the mesh.

The drawn mesh is the version's (the child's) rows with their stored ids.
The merge names the child's new rows in the merged numbering (where the parent
gave the same new id to something else, :attr:`MeshMerge.child_vertex_renumbering`),
so the drawn ids are renamed to the merged ones before they are looked up: a
region of the parent never colours the child's row that happens to share the
parent's id. What a region holds that the drawn mesh does not (the parent's
new rows, rows the child removed) is counted as ``missing``.

States (the legend of the page):

- ``merges-parent``, ``merges-child``: changed on one side only, merges by itself from that side;
- ``merges-both``: changed on both sides to the same rows, merges by itself;
- ``unsolved``: a conflict no solution is recorded for;
- ``solved-parent``, ``solved-child``, ``solved-base``, ``solved-average``, ``solved-manual``: a
  conflict and the solution recorded for it.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, Literal

import numpy as np
import numpy.typing as npt

from tgsis._merge_slices import SlicedMerge, SliceKey
from tgsis.drawing import Drawable, tetra_boundary, vertex_flags
from tgsis.errors import InvalidInputError
from tgsis.merge3 import MergeRegion, MeshMerge, MeshState

__all__ = [
    "REGION_STATES",
    "REGION_LABELS",
    "REGION_COLOURS",
    "CONFLICT_SOLUTIONS",
    "region_state",
    "region_drawing",
    "slice_at",
    "slice_json",
    "sliced_region_drawing",
    "state_drawable",
    "edit_flags",
    "edit_counts",
    "sliced_edit_counts",
]

#: what can happen in a region, in the order of the legend
REGION_STATES = (
    "merges-parent",
    "merges-child",
    "merges-both",
    "unsolved",
    "solved-parent",
    "solved-child",
    "solved-base",
    "solved-average",
    "solved-manual",
)
#: what the legend and the pointer's facts say of each state
REGION_LABELS = {
    "merges-parent": "merges by itself from the parent",
    "merges-child": "merges by itself from the child",
    "merges-both": "merges by itself: identical on both sides",
    "unsolved": "conflict, unsolved",
    "solved-parent": "conflict, solved with the parent's",
    "solved-child": "conflict, solved with the child's",
    "solved-base": "conflict, solved with the base's",
    "solved-average": "conflict, solved with the average",
    "solved-manual": "conflict, solved with a manual mesh",
}
#: each state's colour (sRGB), drawn unlit over the mesh (grey, lit): nine colours told apart, none a grey
REGION_COLOURS = {
    "merges-parent": "#2666ff",
    "merges-child": "#ff8c00",
    "merges-both": "#00a651",
    "unsolved": "#e00000",
    "solved-parent": "#00b5d8",
    "solved-child": "#b8860b",
    "solved-base": "#8b4513",
    "solved-average": "#8a2be2",
    "solved-manual": "#e0119d",
}
#: the solutions of a conflicting region (``tgsis.conflict_regions.solution`` but ``automatic``)
CONFLICT_SOLUTIONS = ("unsolved", "parent", "child", "base", "average", "manual")


def region_state(region: MergeRegion, solution: str | None = None) -> str:
    """What happens in a region: one of :data:`REGION_STATES`.

    Parameters
    ----------
    region : MergeRegion
    solution : str, optional
        The solution recorded for it: ``automatic`` (or None) for a region
        that merges by itself; ``unsolved`` (or None), ``parent``, ``child``,
        ``base``, ``average`` or ``manual`` for a conflict.

    Raises
    ------
    InvalidInputError
        A solution that does not fit the region (a conflict cannot be
        ``automatic``; a region that merges by itself takes no other).
    """
    if not region.conflict:
        if solution not in (None, "automatic"):
            raise InvalidInputError(
                f"region {region.index} merges by itself (changed by {region.sides}): its solution is 'automatic', "
                f"not {solution!r}"
            )
        return "merges-both" if region.sides == "both" else f"merges-{region.sides}"
    if solution is None or solution == "unsolved":
        return "unsolved"
    if solution not in CONFLICT_SOLUTIONS:
        raise InvalidInputError(
            f"region {region.index} is a conflict: its solution is one of {', '.join(CONFLICT_SOLUTIONS)}, "
            f"not {solution!r}"
        )
    return f"solved-{solution}"


def _merged_ids(stored: npt.NDArray[np.int64], renumbering: npt.NDArray[np.int64]) -> npt.NDArray[np.int64]:
    """The drawn (stored) ids in the merge's numbering: the renumbered new ids of the child renamed."""
    if len(renumbering) == 0:
        return stored
    old, new = renumbering[:, 0], renumbering[:, 1]
    order = np.argsort(old)
    old, new = old[order], new[order]
    at = np.minimum(np.searchsorted(old, stored), len(old) - 1)
    return np.where(old[at] == stored, new[at], stored)


class _Lookup:
    """Positions in a drawn array of given ids (by a sort of the drawn ids, once)."""

    def __init__(self, ids: npt.NDArray[np.int64]) -> None:
        # ids in increasing order (a state's rows, a drawing of one) need no sort: positions are the places found
        self.order: npt.NDArray[np.int64] | None = (
            None if np.all(ids[1:] > ids[:-1]) else np.argsort(ids, kind="stable")
        )
        self.sorted = ids if self.order is None else ids[self.order]

    def positions(self, wanted: npt.NDArray[np.int64]) -> tuple[npt.NDArray[np.int64], int]:
        """(every position of each wanted id that is drawn, how many wanted ids are not drawn).

        An id may be drawn several times (the boundary faces of one tetrahedron): all its positions come.
        """
        left = np.searchsorted(self.sorted, wanted, side="left")
        many = np.searchsorted(self.sorted, wanted, side="right") - left
        starts = np.cumsum(many) - many
        at = np.repeat(left, many) + (np.arange(int(many.sum())) - np.repeat(starts, many))
        found = at if self.order is None else self.order[at]
        return found.astype(np.int64), int(np.count_nonzero(many == 0))


def _lookup(ids: npt.ArrayLike, renumbering: npt.NDArray[np.int64], merged: bool) -> _Lookup:
    stored = np.asarray(ids, dtype=np.int64).ravel()
    return _Lookup(stored if merged else _merged_ids(stored, renumbering))


def _side(region: MergeRegion, side: str) -> dict[str, Any]:
    return {
        "vertices": len(getattr(region, f"{side}_vertex_ids")),
        "cells": len(getattr(region, f"{side}_cell_ids")),
        "largest_displacement": float(getattr(region, f"{side}_displacement")),
    }


def state_drawable(state: MeshState) -> tuple[Drawable, npt.NDArray[np.int64] | None]:
    """What the view draws of a merge's state, and the id of the stored cell of each drawn cell.

    Triangles, segments and points as they are; a tetrahedral solid by its
    boundary faces (each face carries its tetrahedron's id; tetrahedra inside
    have none). Vertices in id order; cell ids None for a point set (its
    points are drawn as its vertices).
    """
    vids = state.vertex_ids
    dense = len(vids) == 0 or (vids[0] == 0 and vids[-1] == len(vids) - 1)  # ids 0..n-1 (kept in order): positions
    corners = (state.cells if dense else np.searchsorted(vids, state.cells)).reshape(-1, state.cell_size)
    no_values: dict[str, npt.NDArray[np.float64]] = {}
    if state.cell_size == 1:
        empty = np.empty((0, 0), dtype=np.int64)
        return Drawable("points", state.vertices, empty, no_values, np.empty(0, dtype=np.int64)), None
    if state.cell_size == 4:
        faces, owner = tetra_boundary(corners)
        return Drawable("triangles", state.vertices, faces, no_values, owner), state.cell_ids[owner]
    kind: Literal["triangles", "lines"] = "triangles" if state.cell_size == 3 else "lines"
    rows = np.arange(len(corners), dtype=np.int64)
    return Drawable(kind, state.vertices, corners, no_values, rows), state.cell_ids


def region_drawing(
    merge: MeshMerge,
    vertex_ids: npt.ArrayLike,
    cell_ids: npt.ArrayLike | None,
    solutions: Mapping[int, str] | None = None,
    *,
    merged: bool = False,
) -> tuple[list[dict[str, Any]], dict[str, npt.NDArray[np.int64]]]:
    """The regions of a merge as the view sends them with the drawn mesh.

    Parameters
    ----------
    merge : MeshMerge
        :func:`tgsis.object_merge` of the object.
    vertex_ids : (n,) array_like of int
        The stored id of each drawn vertex, in the drawn order (the version's rows: the child's numbering).
    cell_ids : (m,) array_like of int, or None
        The stored id of each drawn cell, in the drawn order (an id drawn several times, as a solid's
        boundary faces, gives them all); None when no cell is drawn (a point set).
    solutions : mapping of int to str, optional
        The solution recorded for a region (by index); a conflict without one is ``unsolved``.
    merged : bool
        The ids are already in the merge's numbering (a drawing of ``merge.child``, :func:`state_drawable`).

    Returns
    -------
    regions : list of dict
        Per region, in index order: ``index``, ``conflict``, ``changed_by`` (``parent``, ``child`` or
        ``both``), ``state`` (:func:`region_state`), ``solution``, ``parent`` and ``child`` (``vertices``,
        ``cells``: the counts of the rows that side changed; ``largest_displacement``), ``ids`` (the region's
        vertex and cell counts, margin included), ``drawn`` and ``missing`` (how many of them the drawn mesh
        has, and has not), ``bounds`` ([[xmin, ymin, zmin], [xmax, ymax, zmax]]).
    arrays : dict
        ``region_vertices`` (sum of ``drawn.vertices``,) and ``region_cells`` (sum of ``drawn.cells``,) int64:
        the positions in the drawn arrays, region after region.

    Raises
    ------
    InvalidInputError
        A solution for no region of the merge, or one that does not fit its region.
    """
    solutions = dict(solutions or {})
    known = {r.index for r in merge.regions}
    unknown = sorted(set(solutions) - known)
    if unknown:
        raise InvalidInputError(
            f"a solution for no region {unknown[0]} of this merge: it has regions 0 to {len(known) - 1}"
            if known
            else f"a solution for no region {unknown[0]}: this merge has no region"
        )
    vertices = _lookup(vertex_ids, merge.child_vertex_renumbering, merged)
    cells = None if cell_ids is None else _lookup(cell_ids, merge.child_cell_renumbering, merged)
    entries: list[dict[str, Any]] = []
    found_vertices, found_cells = [], []
    for region in merge.regions:
        state = region_state(region, solutions.get(region.index))
        v, v_missing = vertices.positions(region.vertex_ids)
        c, c_missing = (np.empty(0, dtype=np.int64), 0) if cells is None else cells.positions(region.cell_ids)
        found_vertices.append(v)
        found_cells.append(c)
        entries.append(
            {
                "index": region.index,
                "conflict": region.conflict,
                "changed_by": region.sides,
                "state": state,
                "solution": "automatic" if not region.conflict else solutions.get(region.index, "unsolved"),
                "parent": _side(region, "parent"),
                "child": _side(region, "child"),
                "ids": {"vertices": len(region.vertex_ids), "cells": len(region.cell_ids)},
                "drawn": {"vertices": len(v), "cells": len(c)},
                "missing": {"vertices": v_missing, "cells": c_missing},
                "bounds": np.asarray(region.bounds, dtype=np.float64).tolist(),
            }
        )
    empty = np.empty(0, dtype=np.int64)
    return entries, {
        "region_vertices": np.concatenate(found_vertices) if found_vertices else empty,
        "region_cells": np.concatenate(found_cells) if found_cells else empty,
    }


def edit_flags(merge: MeshMerge, vertex_ids: npt.ArrayLike, *, merged: bool = False) -> npt.NDArray[np.float32]:
    """Who changed each drawn vertex, from the merge's edits: the child (1), the parent (2), both (3), none (0).

    A vertex is changed by a side when that side moved, added or changed it,
    or changed a cell on it (added, removed, reconnected, gave other values to;
    its corners as that side or the base has them). The merge knows it already,
    by id: no comparison of the meshes by content.

    Parameters
    ----------
    merge : MeshMerge
    vertex_ids : (n,) array_like of int
    merged : bool
        As for :func:`region_drawing`.

    Returns
    -------
    (n,) float32
    """
    vids = np.asarray(vertex_ids, dtype=np.int64).ravel()
    vertices = _lookup(vids, merge.child_vertex_renumbering, merged)
    cells_of = {id(s): _Lookup(s.cell_ids) for s in (merge.base, merge.parent, merge.child)}  # ids kept in order
    marks = []
    for flag, side in ((1, "child"), (2, "parent")):
        state = getattr(merge, side)
        for region in merge.regions:
            changed = getattr(region, f"{side}_cell_ids")
            corners = [getattr(region, f"{side}_vertex_ids")]
            for holder in (state, merge.base):  # a removed cell is the base's only
                at = cells_of[id(holder)].positions(changed)[0] if len(changed) else np.empty(0, np.int64)
                corners.append(holder.cells[at].ravel())
            marks.append((flag, vertices.positions(np.unique(np.concatenate(corners)))[0]))
    return vertex_flags(len(vids), marks)


def edit_counts(merge: MeshMerge) -> dict[str, dict[str, int]]:
    """``{"child": {"vertices": n, "cells": m}, "parent": {...}}``: the rows each side changed, over all regions."""
    return {
        side: {
            "vertices": sum(len(getattr(r, f"{side}_vertex_ids")) for r in merge.regions),
            "cells": sum(len(getattr(r, f"{side}_cell_ids")) for r in merge.regions),
        }
        for side in ("child", "parent")
    }


# --------------------------------------------------------------------------- models 2 and 3: the regions of a slice


def slice_json(key: SliceKey) -> dict[str, float]:
    """A slice as the header names it: ``times`` (and model 3's ``timem``), as ``tgsis.conflict_regions`` does."""
    return {"times": float(key[1]), "timem": float(key[0])} if len(key) == 2 else {"times": float(key[0])}


def slice_at(merge: SlicedMerge, t: float | None, timem: float | None = None) -> SliceKey | None:
    """The merged slice the view draws at time ``t``, or None when none is at ``t``.

    A slice is at ``t`` when its instant is ``t`` exactly (model 2: the
    instant; model 3: the geometry instant of the period starting at
    ``timem``, else of the latest period that has one at ``t``: a period's
    last geometry instant is the next one's start, two slices at one time).
    No ``t``: the first slice with a conflicting region, else the first
    merged slice (None when no slice merged).
    """
    keys = sorted(merge.merges)
    if t is None:
        first = sorted({r.key for r in merge.conflicts}) or keys
        return first[0] if first else None
    at = [k for k in keys if k[-1] == t and (timem is None or len(k) == 1 or k[0] == timem)]
    return at[-1] if at else None


def sliced_region_drawing(
    merge: SlicedMerge, key: SliceKey | None, solutions: Mapping[int, str] | None = None
) -> tuple[list[dict[str, Any]], dict[str, npt.NDArray[np.int64]]]:
    """The regions of a model-2/3 merge, those of the slice ``key`` drawn on that slice's child mesh.

    Every region of the object is listed, in its number in the object
    (``index``), with its ``slice`` (``times``, and model 3's ``timem``) and
    ``at_t`` (it is of the drawn slice). The drawn slice's regions are as
    :func:`region_drawing` gives them on :func:`state_drawable` of
    ``merge.merges[key].child``; the others are not drawn (``drawn`` and
    ``missing`` zero): their ids are of another mesh.

    Parameters
    ----------
    merge : SlicedMerge
    key : SliceKey or None
        The drawn slice (:func:`slice_at`), None when no merged slice is drawn.
    solutions : mapping of int to str, optional
        The solution recorded for a region (by its number in the object).

    Returns
    -------
    regions, arrays
        As :func:`region_drawing`'s, the arrays holding the drawn slice's regions only.
    """
    solutions = dict(solutions or {})
    unknown = sorted(set(solutions) - {r.index for r in merge.regions})
    if unknown:
        raise InvalidInputError(f"a solution for no region {unknown[0]} of {merge.base.name}")
    entries: list[dict[str, Any]] = []
    empty = np.empty(0, dtype=np.int64)
    arrays = {"region_vertices": empty, "region_cells": empty}
    for k in sorted(merge.merges):
        mine = [r for r in merge.regions if r.key == k]
        local = {r.region.index: solutions[r.index] for r in mine if r.index in solutions}
        mm = merge.merges[k]
        if k == key:
            _, drawn_cells = state_drawable(mm.child)
            found, arrays = region_drawing(mm, mm.child.vertex_ids, drawn_cells, local, merged=True)
        else:
            found, _ = region_drawing(mm, empty, None if mm.child.cell_size == 1 else empty, local, merged=True)
            for entry in found:
                entry["drawn"] = entry["missing"] = {"vertices": 0, "cells": 0}
        number = {r.region.index: r.index for r in mine}
        for entry in found:
            entry.update(index=number[entry["index"]], slice=slice_json(k), at_t=k == key)
        entries += found
    return entries, arrays


def sliced_edit_counts(merge: SlicedMerge) -> dict[str, dict[str, int]]:
    """:func:`edit_counts` over every merged slice of a model-2/3 merge."""
    counts = [edit_counts(mm) for mm in merge.merges.values()]
    return {
        side: {what: sum(c[side][what] for c in counts) for what in ("vertices", "cells")}
        for side in ("child", "parent")
    }
