"""Mesh comparison: which vertices and cells of an edited mesh are the old ones.

A modeller edits a stored surface in a desktop tool and saves it back: the
client holds the *edited* mesh, the database the *old* one. Writing only what
changed needs the answer to "what changed", by the definitions of
``../shared/spec/mesh-comparison.md``:

- an edited-mesh vertex is **non-edited** when an old vertex has exactly the
  same coordinates (that old vertex is non-edited too); all other vertices are
  edited (old ones to remove, new ones to insert);
- a cell is **non-edited** when its k vertices are non-edited and the other
  mesh has a cell on the corresponding vertices *with the same orientation*
  (an even permutation of them). A flipped edge makes two edited triangles
  although all four vertices survive; a triangle whose normal was reversed is
  edited too, since keeping the old row would lose the reversal.

Equality is of numbers: ``-0.0`` equals ``0.0`` (they are the same
coordinate), and a vertex moved by one ulp is edited. With ``tolerance > 0``
a vertex within that Euclidean distance of an old vertex is non-edited (for
clients that round coordinates); the old coordinates are then the ones kept.

The same code compares point sets, line sets, surfaces and tetrahedral meshes
(cells of k = 1, 2, 3, 4 vertices). Everything is vectorised numpy: rows
(coordinate triples, sorted vertex tuples) are hashed to 64 bits, both sides
sorted by hash and merged with ``searchsorted``, and every candidate pair is
verified for exact equality, so a hash collision can never make a false
match. ``scipy.spatial.cKDTree`` is used only for a non-zero tolerance.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from tgsis._rows import SortedRows, cell_columns, columns_of, coordinate_columns, match_rows, unmatched
from tgsis.errors import InvalidGeometryError, InvalidInputError
from tgsis.mesh import Mesh

__all__ = ["MeshDiff", "MeshIndex", "compare_meshes"]

IntArray = npt.NDArray[np.int64]
U64Array = npt.NDArray[np.uint64]


class MeshIndex:
    """An old mesh prepared for comparisons: its vertex and cell rows hashed and sorted once.

    :func:`tgsis.checkout` keeps one, so that a check-in hashes only the
    edited mesh. Comparing against a ``MeshIndex`` gives the same result as
    comparing against its mesh.

    Parameters
    ----------
    mesh : Mesh
        The old mesh (any of the four types).
    """

    def __init__(self, mesh: Mesh) -> None:
        self.mesh = mesh
        self._vertices = SortedRows.of(coordinate_columns(mesh.vertices))
        self._cells = SortedRows.of(cell_columns(columns_of(mesh.cells), mesh.n_vertices))
        for rows in (self._vertices, self._cells):
            rows.unique_hash  # noqa: B018 - computed once here, not by the first comparison
        self._tree: Any = None

    def tree(self) -> Any:
        """A ``scipy.spatial.cKDTree`` of the vertices (built on first use)."""
        if self._tree is None:
            from scipy.spatial import cKDTree

            self._tree = cKDTree(self.mesh.vertices)
        return self._tree


class IndexMaps:
    """The index sets of a ``vertex_map`` and ``cell_map`` (edited index -> old index, -1 for a new one).

    Shared by :class:`MeshDiff` and :class:`tgsis.edits.EditPlan`.
    """

    vertex_map: IntArray
    cell_map: IntArray

    @property
    def added_vertices(self) -> IntArray:
        """(a,) int64: edited-mesh indices of the new vertices, ascending."""
        return np.flatnonzero(self.vertex_map < 0).astype(np.int64)

    @property
    def added_cells(self) -> IntArray:
        """(b,) int64: edited-mesh indices of the new cells, ascending."""
        return np.flatnonzero(self.cell_map < 0).astype(np.int64)

    @property
    def kept_vertices(self) -> IntArray:
        """(n_edited - a,) int64: edited-mesh indices of the non-edited vertices."""
        return np.flatnonzero(self.vertex_map >= 0).astype(np.int64)

    @property
    def kept_cells(self) -> IntArray:
        """(m_edited - b,) int64: edited-mesh indices of the non-edited cells."""
        return np.flatnonzero(self.cell_map >= 0).astype(np.int64)


@dataclass(frozen=True)
class MeshDiff(IndexMaps):
    """What changed from an old mesh to an edited one (see the module documentation).

    Attributes
    ----------
    vertex_map : (n_edited,) int64
        Per edited-mesh vertex, the index of the same old vertex, or -1 for an
        edited (new) vertex.
    cell_map : (m_edited,) int64
        Per edited-mesh cell, the index of the same old cell, or -1 for an
        edited (new) cell.
    removed_vertices : (r,) int64
        Old vertex indices that no edited vertex matches, ascending.
    removed_cells : (s,) int64
        Old cell indices that no edited cell matches, ascending.
    n_old_vertices, n_old_cells : int
        Sizes of the old mesh.
    """

    vertex_map: IntArray
    cell_map: IntArray
    removed_vertices: IntArray
    removed_cells: IntArray
    n_old_vertices: int
    n_old_cells: int

    @property
    def identical(self) -> bool:
        """Whether nothing was edited (same vertices and oriented cells, in any order)."""
        return (
            len(self.removed_vertices) == 0
            and len(self.removed_cells) == 0
            and bool(np.all(self.vertex_map >= 0))
            and bool(np.all(self.cell_map >= 0))
        )

    def counts(self) -> dict[str, int]:
        """Numbers of kept, removed and added vertices and cells."""
        added_v, added_c = int(np.count_nonzero(self.vertex_map < 0)), int(np.count_nonzero(self.cell_map < 0))
        return {
            "vertices_kept": len(self.vertex_map) - added_v,
            "vertices_removed": len(self.removed_vertices),
            "vertices_added": added_v,
            "cells_kept": len(self.cell_map) - added_c,
            "cells_removed": len(self.removed_cells),
            "cells_added": added_c,
        }

    def __repr__(self) -> str:
        return "MeshDiff(" + ", ".join(f"{k}={v}" for k, v in self.counts().items()) + ")"


def _tolerance_matches(index: MeshIndex, edited: Mesh, vertex_map: IntArray, tolerance: float) -> None:
    """Match still-unmatched edited vertices to unmatched old vertices within ``tolerance``, nearest pairs first.

    Every pair of unmatched vertices within the tolerance is a candidate (not
    just a few nearest neighbours, which exact matches may have taken); the
    distance is ``sqrt(dx*dx + dy*dy + dz*dz)`` in float64, ties go to the
    lower old index, then the lower edited index.
    """
    free_new = np.flatnonzero(vertex_map < 0)
    if len(free_new) == 0 or index.mesh.n_vertices == 0:
        return
    from scipy.spatial import cKDTree

    taken = np.zeros(index.mesh.n_vertices, dtype=bool)
    taken[vertex_map[vertex_map >= 0]] = True
    points = edited.vertices[free_new]
    # all pairs within a slightly larger ball (cKDTree's own rounding must not lose one), then our distance decides
    pairs = cKDTree(points).sparse_distance_matrix(index.tree(), tolerance * (1 + 1e-9), output_type="ndarray")
    rows, pair_old = pairs["i"].astype(np.int64), pairs["j"].astype(np.int64)
    keep = ~taken[pair_old]
    rows, pair_old = rows[keep], pair_old[keep]
    delta = points[rows] - index.mesh.vertices[pair_old]
    distance = np.sqrt(delta[:, 0] * delta[:, 0] + delta[:, 1] * delta[:, 1] + delta[:, 2] * delta[:, 2])
    within = distance <= tolerance
    rows, pair_old, distance = rows[within], pair_old[within], distance[within]
    # a pair whose two vertices have no other candidate is matched whatever the order (the usual case: rounding)
    alone = (np.bincount(rows, minlength=len(free_new))[rows] == 1) & (
        np.bincount(pair_old, minlength=len(taken))[pair_old] == 1
    )
    vertex_map[free_new[rows[alone]]] = pair_old[alone]
    rows, pair_old, distance = rows[~alone], pair_old[~alone], distance[~alone]
    order = np.lexsort((rows, pair_old, distance))
    assigned_new = np.zeros(len(free_new), dtype=bool)
    for r, o in zip(rows[order].tolist(), pair_old[order].tolist()):  # greedy over the contested pairs
        if not assigned_new[r] and not taken[o]:
            assigned_new[r] = True
            taken[o] = True
            vertex_map[free_new[r]] = o


def compare_meshes(old: Mesh | MeshIndex, edited: Mesh, tolerance: float = 0.0) -> MeshDiff:
    """Compare an edited mesh with the old one it was made from.

    Parameters
    ----------
    old : Mesh or MeshIndex
        The old mesh (a :class:`MeshIndex` of it reuses its hashes).
    edited : Mesh
        The edited mesh, of the same type (same cell size).
    tolerance : float
        0 (default): vertices match when their coordinates are equal. > 0:
        when within this Euclidean distance (each old vertex matched at most
        once, nearest pairs first).

    Returns
    -------
    MeshDiff

    Raises
    ------
    InvalidGeometryError
        The meshes have cells of different sizes.
    InvalidInputError
        A negative or non-finite tolerance.
    """
    old_mesh = old.mesh if isinstance(old, MeshIndex) else old
    if old_mesh.cell_size != edited.cell_size:
        raise InvalidGeometryError(
            f"cannot compare a {type(old_mesh).__name__} with a {type(edited).__name__}: "
            f"cells of {old_mesh.cell_size} and {edited.cell_size} vertices"
        )
    if not (np.isfinite(tolerance) and tolerance >= 0):
        raise InvalidInputError(f"tolerance must be a finite number >= 0, got {tolerance}")
    index = old if isinstance(old, MeshIndex) else MeshIndex(old)

    vertex_map = match_rows(index._vertices, SortedRows.of(coordinate_columns(edited.vertices)))
    if tolerance > 0:
        _tolerance_matches(index, edited, vertex_map, tolerance)

    return _diff(old_mesh, vertex_map, _match_cells(index._cells, old_mesh.n_vertices, edited.cells, vertex_map))


def _match_cells(old_cells: SortedRows, n_old_vertices: int, cells: IntArray, vertex_map: IntArray) -> IntArray:
    """Per edited cell, the index of the same oriented old cell (one-to-one), or -1, given the vertex map.

    Edited cells on surviving vertices are renamed to old vertex indices and
    matched as oriented rows against the old cells' sorted rows.
    """
    cell_map = np.full(len(cells), -1, dtype=np.int64)
    if len(cells) == 0 or len(old_cells) == 0:
        return cell_map
    renamed = [vertex_map[column] for column in columns_of(cells)]
    unmatched = renamed[0].copy()  # negative where any vertex of the cell is unmatched (-1): or of the sign bits
    for column in renamed[1:]:
        unmatched |= column
    candidates = np.flatnonzero(unmatched >= 0)
    if len(candidates) == len(cells):
        return match_rows(old_cells, SortedRows.of(cell_columns(renamed, n_old_vertices)))
    if len(candidates):
        renamed = [column[candidates] for column in renamed]
        cell_map[candidates] = match_rows(old_cells, SortedRows.of(cell_columns(renamed, n_old_vertices)))
    return cell_map


def _diff(old_mesh: Mesh, vertex_map: IntArray, cell_map: IntArray) -> MeshDiff:
    """The MeshDiff of these maps (the removed rows are the old ones neither map hits)."""
    return MeshDiff(
        vertex_map=vertex_map,
        cell_map=cell_map,
        removed_vertices=unmatched(old_mesh.n_vertices, vertex_map),
        removed_cells=unmatched(old_mesh.n_cells, cell_map),
        n_old_vertices=old_mesh.n_vertices,
        n_old_cells=old_mesh.n_cells,
    )
