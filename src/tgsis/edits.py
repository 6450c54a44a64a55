"""How to write an edited mesh over the old one with the fewest rows.

:func:`tgsis.compare_meshes` says which vertices and cells are non-edited by
the specification's definitions: a vertex that moved is a removed vertex plus
a new one, and every cell around it is edited too. Written that way, moving
1 % of a surface's vertices would rewrite about 6 % of its triangles.

An :class:`EditPlan` recognises moves: a new vertex whose cells are, one for
one, the cells of a removed old vertex (the same other vertices, the same
orientation) is that old vertex moved. Saving it rewrites one vertex row and
keeps every cell around it, with its id. The plan is found by matching, over
a few rounds (so that moved neighbours resolve each other), the cells that
miss exactly one vertex on each side. Whatever pairs it finds, the written
mesh is the edited mesh: a pairing only decides which rows can be kept.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from tgsis._rows import SortedRows, cell_columns, columns_of, match_rows, unmatched
from tgsis.compare import IndexMaps, MeshDiff, MeshIndex
from tgsis.mesh import Mesh

__all__ = ["EditPlan", "plan_edit"]

IntArray = npt.NDArray[np.int64]

_ROUNDS = 64  # each round resolves the ring of moved vertices next to resolved ones; stops early without progress


@dataclass(frozen=True)
class EditPlan(IndexMaps):
    """Rows to keep, rewrite, remove and add when an edited mesh replaces the old one.

    Attributes
    ----------
    diff : MeshDiff
        The comparison by the specification's definitions.
    vertex_map : (n_edited,) int64
        Per edited vertex, the old vertex whose row it keeps (non-edited or
        moved), or -1 for a new row.
    moved : (n_edited,) bool
        Edited vertices that are an old vertex moved (row rewritten, id kept).
    cell_map : (m_edited,) int64
        Per edited cell, the old cell whose row it keeps, or -1 for a new row.
        ``added_vertices`` and ``added_cells`` (from :class:`~tgsis.compare.IndexMaps`)
        are the edited rows written as new ones.
    removed_vertices, removed_cells : int64 arrays
        Old rows to remove, ascending.
    bounds : (2, 3) float64 or None
        The edited mesh's bounding box (None without vertices), for the
        geometry row; computed here, where the comparison runs.
    """

    diff: MeshDiff
    vertex_map: IntArray
    moved: npt.NDArray[np.bool_]
    cell_map: IntArray
    removed_vertices: IntArray
    removed_cells: IntArray
    bounds: npt.NDArray[np.float64] | None = None

    @property
    def moved_vertices(self) -> IntArray:
        """Edited vertices whose old row is rewritten with new coordinates."""
        return np.flatnonzero(self.moved).astype(np.int64)


def _one_missing_keys(
    cells: IntArray, mapped: IntArray, sentinel: int
) -> tuple[IntArray, IntArray, list[npt.NDArray[np.uint64]]]:
    """Cells missing exactly one vertex: their indices, that vertex, and keys with it replaced by ``sentinel``."""
    missing = mapped < 0
    rows = np.flatnonzero(missing.sum(axis=1) == 1)
    if len(rows) == 0:
        return rows.astype(np.int64), rows.astype(np.int64), [np.empty(0, dtype=np.uint64)]
    sub_missing = missing[rows]
    position = np.argmax(sub_missing, axis=1)
    vertex = cells[rows, position]
    keyed = mapped[rows].copy()
    keyed[np.arange(len(rows)), position] = sentinel
    return rows.astype(np.int64), vertex.astype(np.int64), cell_columns(columns_of(keyed), sentinel + 1)


def _pair_moves(
    old_cells: IntArray, new_cells: IntArray, sentinel: int, vertex_map: IntArray, old_free: npt.NDArray[np.bool_]
) -> int:
    """One round: pair new vertices with removed old ones whose one-missing cells match; returns pairs made.

    ``old_cells`` are the removed old cells, ``new_cells`` the added edited
    cells (the only ones a move can explain); ``sentinel`` is above every old
    vertex index.
    """
    old_mapped = np.where(old_free[old_cells], -1, old_cells)
    new_mapped = vertex_map[new_cells]
    old_rows, old_vertex, old_keys = _one_missing_keys(old_cells, old_mapped, sentinel)
    new_rows, new_vertex, new_keys = _one_missing_keys(new_cells, new_mapped, sentinel)
    if len(old_rows) == 0 or len(new_rows) == 0:
        return 0
    hit = match_rows(SortedRows.of(old_keys), SortedRows.of(new_keys))
    # votes: (new vertex, old vertex) per matched cell; a pair holds when it is each side's only candidate
    # and covers all the one-missing cells of both vertices
    matched = hit >= 0
    pair_new, pair_old = new_vertex[matched], old_vertex[hit[matched]]
    if len(pair_new) == 0:
        return 0
    pairs, votes = np.unique(pair_new * np.int64(sentinel + 1) + pair_old, return_counts=True)
    pair_new, pair_old = pairs // (sentinel + 1), pairs % (sentinel + 1)
    size = max(len(vertex_map), sentinel)
    new_cells_of = np.bincount(new_vertex, minlength=size)
    old_cells_of = np.bincount(old_vertex, minlength=size)
    candidates_of_new = np.bincount(pair_new, minlength=size)
    candidates_of_old = np.bincount(pair_old, minlength=size)
    good = (
        (candidates_of_new[pair_new] == 1)
        & (candidates_of_old[pair_old] == 1)
        & (votes == new_cells_of[pair_new])
        & (votes == old_cells_of[pair_old])
    )
    vertex_map[pair_new[good]] = pair_old[good]
    old_free[pair_old[good]] = False
    return int(good.sum())


def plan_edit(old: Mesh | MeshIndex, edited: Mesh, diff: MeshDiff) -> EditPlan:
    """The rows to keep, rewrite, remove and add to turn ``old`` into ``edited``.

    Parameters
    ----------
    old : Mesh or MeshIndex
        The old mesh (the one ``diff`` compared against).
    edited : Mesh
    diff : MeshDiff
        ``compare_meshes(old, edited)``.

    Returns
    -------
    EditPlan
    """
    old_mesh = old.mesh if isinstance(old, MeshIndex) else old
    vertex_map = diff.vertex_map.copy()
    old_free = np.zeros(old_mesh.n_vertices, dtype=bool)
    old_free[diff.removed_vertices] = True
    # only removed old cells and added edited cells can be explained by moves: work on them alone
    old_cells, new_cells = old_mesh.cells[diff.removed_cells], edited.cells[diff.added_cells]
    if edited.cell_size > 1 and old_free.any() and len(new_cells):
        for _ in range(_ROUNDS):
            if _pair_moves(old_cells, new_cells, old_mesh.n_vertices, vertex_map, old_free) == 0:
                break
    moved = (vertex_map >= 0) & (diff.vertex_map < 0)
    cell_map = diff.cell_map
    if moved.any():  # added cells around moved vertices may be removed old cells again
        cell_map = cell_map.copy()
        renamed = vertex_map[new_cells]
        survives = np.flatnonzero(renamed.min(axis=1) >= 0)
        if len(survives):
            hit = match_rows(
                SortedRows.of(cell_columns(columns_of(old_cells), old_mesh.n_vertices)),
                SortedRows.of(cell_columns(columns_of(renamed[survives]), old_mesh.n_vertices)),
            )
            found = hit >= 0
            cell_map[diff.added_cells[survives[found]]] = diff.removed_cells[hit[found]]
    return EditPlan(
        diff,
        vertex_map,
        moved,
        cell_map,
        unmatched(old_mesh.n_vertices, vertex_map),
        unmatched(old_mesh.n_cells, cell_map),
        edited.bounds() if edited.n_vertices else None,
    )
