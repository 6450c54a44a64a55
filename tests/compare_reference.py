"""A slow, obviously correct mesh comparison, to check :func:`tgsis.compare_meshes` against (tests only).

The definitions of ``../shared/spec/mesh-comparison.md`` as plain Python on
lists, dicts and tuples, with no hashing tricks and no numpy:

- an edited vertex is non-edited when an old vertex has numerically equal
  coordinates (Python floats: ``-0.0 == 0.0`` and they hash alike; a vertex
  moved by one ulp is a different tuple);
- a cell is non-edited when all its vertices are non-edited and the old mesh
  has a cell on the corresponding old vertices with the same orientation: the
  key of a cell is (its sorted vertex ids, the parity of the permutation that
  sorts it), so an even permutation (a rotation of a triangle) is the same
  cell and an odd one (a reversed triangle, a reversed segment) is not;
- matching is one-to-one. Where a mesh repeats a vertex or a cell (not a
  normal mesh), equal ones are paired in index order: the i-th edited one
  with the i-th old one;
- with ``tolerance > 0``, vertices left unmatched by the exact step are then
  paired with unmatched old vertices at Euclidean distance
  ``sqrt(dx*dx + dy*dy + dz*dz) <= tolerance`` (float64, summed x, y, z),
  greedily over all such pairs, nearest first; equal distances are taken by
  lower old index, then lower edited index.
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Sequence
from dataclasses import dataclass

#: a cell by its coordinates: (sorted coordinate tuples, orientation parity or None)
CellByCoordinates = tuple[tuple[tuple[float, ...], ...], int | None]


@dataclass(frozen=True)
class ReferenceDiff:
    """What :class:`tgsis.MeshDiff` holds, as lists."""

    vertex_map: list[int]
    cell_map: list[int]
    removed_vertices: list[int]
    removed_cells: list[int]


def permutation_parity(ids: Sequence[int]) -> int:
    """0 when ``ids`` is an even permutation of its ascending order, 1 when odd (by counting inversions)."""
    inversions = sum(1 for i in range(len(ids)) for j in range(i + 1, len(ids)) if ids[i] > ids[j])
    return inversions % 2


def oriented_key(ids: Sequence[int]) -> tuple[tuple[int, ...], int]:
    """A cell as (sorted vertex ids, permutation parity): equal for the same cell with the same orientation."""
    return tuple(sorted(ids)), permutation_parity(ids)


def distance(a: Sequence[float], b: Sequence[float]) -> float:
    dx, dy, dz = a[0] - b[0], a[1] - b[1], a[2] - b[2]
    return math.sqrt(dx * dx + dy * dy + dz * dz)


def reference_compare(
    old_vertices: Sequence[Sequence[float]],
    old_cells: Sequence[Sequence[int]],
    new_vertices: Sequence[Sequence[float]],
    new_cells: Sequence[Sequence[int]],
    tolerance: float = 0.0,
) -> ReferenceDiff:
    """Compare an edited mesh (``new_*``) with the old one by the definitions above."""
    old_v = [tuple(float(c) for c in v) for v in old_vertices]
    new_v = [tuple(float(c) for c in v) for v in new_vertices]

    # vertices: exact coordinates, one-to-one, in index order
    waiting_vertices: dict[tuple[float, ...], deque[int]] = {}
    for i, xyz in enumerate(old_v):
        waiting_vertices.setdefault(xyz, deque()).append(i)
    vertex_map = []
    for xyz in new_v:
        queue = waiting_vertices.get(xyz)
        vertex_map.append(queue.popleft() if queue else -1)

    if tolerance > 0:  # brute force: every (edited, old) pair of still unmatched vertices
        taken = set(o for o in vertex_map if o >= 0)
        free_old = [i for i in range(len(old_v)) if i not in taken]
        pairs = sorted(
            (d, i, j)
            for j in range(len(new_v))
            if vertex_map[j] < 0
            for i in free_old
            if (d := distance(new_v[j], old_v[i])) <= tolerance
        )
        for _d, i, j in pairs:
            if vertex_map[j] < 0 and i not in taken:
                vertex_map[j] = i
                taken.add(i)

    # cells: renamed to old vertex ids, then the same oriented cell, one-to-one, in index order
    waiting_cells: dict[tuple[tuple[int, ...], int], deque[int]] = {}
    for i, cell in enumerate(old_cells):
        waiting_cells.setdefault(oriented_key([int(v) for v in cell]), deque()).append(i)
    cell_map = []
    for cell in new_cells:
        renamed = [vertex_map[int(v)] for v in cell]
        queue = waiting_cells.get(oriented_key(renamed)) if min(renamed) >= 0 else None
        cell_map.append(queue.popleft() if queue else -1)

    matched_vertices, matched_cells = set(vertex_map), set(cell_map)
    return ReferenceDiff(
        vertex_map=vertex_map,
        cell_map=cell_map,
        removed_vertices=[i for i in range(len(old_v)) if i not in matched_vertices],
        removed_cells=[i for i in range(len(old_cells)) if i not in matched_cells],
    )


def oriented_cells_by_coordinates(
    vertices: Sequence[Sequence[float]], cells: Sequence[Sequence[int]]
) -> dict[CellByCoordinates, int]:
    """The multiset of cells as (sorted coordinate tuples, orientation parity): independent of vertex numbering.

    The parity is None for a cell on coincident points (possible only in a mesh that is not normal).
    """
    counts: dict[CellByCoordinates, int] = {}
    for cell in cells:
        points = [tuple(float(c) for c in vertices[int(v)]) for v in cell]
        # the order of the coordinate tuples plays the part of the vertex ids; a cell on coincident
        # points (not in a normal mesh) has no orientation that coordinates could tell
        rank = sorted(range(len(points)), key=lambda p: points[p])
        position = [0] * len(points)
        for r, p in enumerate(rank):
            position[p] = r
        parity = permutation_parity(position) if len(set(points)) == len(points) else None
        key = (tuple(sorted(points)), parity)
        counts[key] = counts.get(key, 0) + 1
    return counts
