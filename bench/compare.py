"""Mesh comparison: ``compare_meshes`` on a 1M-vertex, 2M-triangle surface vs a cKDTree baseline.

The old mesh is the bumpy 1000 x 1000 grid of ``transfer.py`` (1,000,000
vertices, 1,996,002 triangles). The edited mesh is the grid after a 1% edit:

- 1% of the vertices moved (z + 1 m),
- 1% removed, with their triangles (the holes are left open),
- 1% added: a vertex at the centre of as many intact quads, whose two
  triangles become a fan of four,
- the diagonal of 1% of the quads flipped (both triangles edited, no vertex),
- vertex and triangle order shuffled (an edited mesh comes back renumbered).

Timed, medians of ``--repeat`` runs:

- ``compare_meshes(old, edited)`` from scratch, and from a ``MeshIndex`` of
  the old mesh prepared beforehand (what a check-out keeps);
- the baseline, in the same run: the vertex matching by
  ``scipy.spatial.cKDTree`` (build over the old vertices, nearest-neighbour
  query of the edited ones with a tiny distance bound — a bound of 0 matches
  nothing — then exact verification of the coordinates), followed by the same
  cell matching step as ``compare_meshes``;
- the vertex matching alone, both ways;
- for information, cKDTree with the queries in sorted order (a stronger
  baseline than the issue's: it sorts the edited vertices first).

Both answers are checked to be the same exact diff before anything is timed.
No database here.

    python bench/compare.py [--side 1000] [--repeat 3] [--fraction 0.01]
"""

from __future__ import annotations

import argparse
import platform
from typing import Any

import numpy as np
import numpy.typing as npt
from scipy.spatial import cKDTree
from timing import timed
from transfer import grid_surface

import tgsis
from tgsis._rows import SortedRows, cell_columns, columns_of, coordinate_columns, match_rows
from tgsis.compare import MeshDiff, MeshIndex, _diff, _match_cells, compare_meshes

IntArray = npt.NDArray[np.int64]

#: far below the grid's spacing (10 m) and above 0: cKDTree's bound is strict, a bound of 0 finds nothing
TINY = 1e-9


def edited_grid(old: tgsis.Surface, side: int, fraction: float, seed: int = 7) -> tuple[tgsis.Surface, dict[str, int]]:
    """The grid after the edit described in the module documentation, and what the edit did."""
    rng = np.random.default_rng(seed)
    n = old.n_vertices
    quads = (side - 1) ** 2
    count = int(round(fraction * n))
    chosen = rng.permutation(n)
    moved, removed = chosen[:count], chosen[count : 2 * count]

    vertices = old.vertices.copy()
    vertices[moved, 2] += 1.0
    alive = np.ones(n, dtype=bool)
    alive[removed] = False
    # quad q is triangles q = (a, b, d) and quads + q = (a, d, c)
    a, b, d = (old.cells[:quads, i] for i in range(3))
    c = old.cells[quads:, 2]
    intact = alive[a] & alive[b] & alive[c] & alive[d]
    candidates = rng.permutation(np.flatnonzero(intact))
    fanned, flipped = np.sort(candidates[:count]), np.sort(candidates[count : 2 * count])
    redrawn = np.zeros(quads, dtype=bool)
    redrawn[fanned] = redrawn[flipped] = True

    centres = old.vertices[[a[fanned], b[fanned], c[fanned], d[fanned]]].mean(axis=0)
    e = n + np.arange(len(fanned))
    kept_cells = np.concatenate(
        [
            old.cells[:quads][alive[a] & alive[b] & alive[d] & ~redrawn],
            old.cells[quads:][alive[a] & alive[d] & alive[c] & ~redrawn],
        ]
    )
    fa, fb, fc, fd = a[fanned], b[fanned], c[fanned], d[fanned]
    fans = np.concatenate([np.stack(t, axis=1) for t in ((fa, fb, e), (fb, fd, e), (fd, fc, e), (fc, fa, e))])
    la, lb, lc, ld = a[flipped], b[flipped], c[flipped], d[flipped]
    flips = np.concatenate([np.stack([la, lb, lc], axis=1), np.stack([lb, ld, lc], axis=1)])
    all_vertices = np.concatenate([vertices, centres])
    all_cells = np.concatenate([kept_cells, fans, flips])

    # drop the removed vertices, then shuffle vertices and triangles
    present = np.concatenate([alive, np.ones(len(fanned), dtype=bool)])
    renumber = np.cumsum(present) - 1
    all_vertices, all_cells = all_vertices[present], renumber[all_cells]
    order = rng.permutation(len(all_vertices))
    position = np.empty(len(order), dtype=np.int64)
    position[order] = np.arange(len(order))
    edited = tgsis.Surface(all_vertices[order], position[all_cells[rng.permutation(len(all_cells))]], name="edited")
    return edited, {
        "moved": len(moved),
        "removed": len(removed),
        "added": len(fanned),
        "fanned_quads": len(fanned),
        "flipped_quads": len(flipped),
    }


def ckdtree_vertex_map(
    old_vertices: npt.NDArray[np.float64], new_vertices: npt.NDArray[np.float64], sort_queries: bool = False
) -> IntArray:
    """Per edited vertex, the old vertex with exactly its coordinates, or -1: cKDTree build + query + verification.

    A normal old mesh (no coincident vertices) is assumed: one candidate per
    query, so the match is one-to-one.
    """
    tree = cKDTree(old_vertices)
    if sort_queries:
        order = np.lexsort(new_vertices.T[::-1])
        distance, nearest = tree.query(new_vertices[order], k=1, distance_upper_bound=TINY)
        unsorted = np.empty_like(nearest)
        unsorted[order] = nearest
        nearest = unsorted
    else:
        distance, nearest = tree.query(new_vertices, k=1, distance_upper_bound=TINY)
    found = nearest < len(old_vertices)  # cKDTree answers n for "nothing within the bound"
    result = np.full(len(new_vertices), -1, dtype=np.int64)
    candidates = np.flatnonzero(found)
    exact = np.all(old_vertices[nearest[candidates]] == new_vertices[candidates], axis=1)
    result[candidates[exact]] = nearest[candidates[exact]]
    return result


def ckdtree_compare(old: tgsis.Surface, edited: tgsis.Surface, sort_queries: bool = False) -> MeshDiff:
    """The baseline: cKDTree vertex matching, then compare_meshes' own cell matching (old cells hashed here)."""
    vertex_map = ckdtree_vertex_map(old.vertices, edited.vertices, sort_queries)
    old_cells = SortedRows.of(cell_columns(columns_of(old.cells), old.n_vertices))
    return _diff(old, vertex_map, _match_cells(old_cells, old.n_vertices, edited.cells, vertex_map))


def hashed_vertex_map(old: tgsis.Surface, edited: tgsis.Surface) -> IntArray:
    """compare_meshes' vertex step alone, from scratch (both sides hashed and sorted)."""
    old_rows = SortedRows.of(coordinate_columns(old.vertices))
    return match_rows(old_rows, SortedRows.of(coordinate_columns(edited.vertices)))


def same_diff(x: MeshDiff, y: MeshDiff) -> bool:
    return all(
        np.array_equal(getattr(x, f), getattr(y, f))
        for f in ("vertex_map", "cell_map", "removed_vertices", "removed_cells")
    )


def compare_figures(side: int = 1000, repeat: int = 3, fraction: float = 0.01) -> dict[str, Any]:
    """Build the meshes, check both methods give the same diff, time them; print and return the figures."""
    old = grid_surface(side)
    old = tgsis.Surface(old.vertices, old.cells, name="old")  # geometry only
    edited, edit = edited_grid(old, side, fraction)
    print(
        f"old surface: {old.n_vertices} vertices, {old.n_cells} triangles; edited: {edited.n_vertices} vertices, "
        f"{edited.n_cells} triangles ({edit['moved']} moved, {edit['removed']} removed, {edit['added']} added "
        f"in fans, {edit['flipped_quads']} quad diagonals flipped, order shuffled)"
    )

    diff = compare_meshes(old, edited)
    counts = diff.counts()
    print("diff:", ", ".join(f"{k} {v}" for k, v in counts.items()))
    assert counts["vertices_removed"] == edit["moved"] + edit["removed"]
    assert counts["vertices_added"] == edit["moved"] + edit["added"]
    assert same_diff(diff, ckdtree_compare(old, edited)), "the baseline does not give the same diff"
    assert same_diff(diff, ckdtree_compare(old, edited, sort_queries=True))
    index = MeshIndex(old)
    assert same_diff(diff, compare_meshes(index, edited))
    assert np.array_equal(hashed_vertex_map(old, edited), diff.vertex_map)

    t_compare = timed(lambda: compare_meshes(old, edited), repeat)
    t_index_build = timed(lambda: MeshIndex(old), repeat)
    t_from_index = timed(lambda: compare_meshes(index, edited), repeat)
    t_baseline = timed(lambda: ckdtree_compare(old, edited), repeat)
    t_baseline_sorted = timed(lambda: ckdtree_compare(old, edited, sort_queries=True), repeat)
    t_vertices = timed(lambda: hashed_vertex_map(old, edited), repeat)
    t_vertices_ckdtree = timed(lambda: ckdtree_vertex_map(old.vertices, edited.vertices), repeat)
    t_vertices_ckdtree_sorted = timed(lambda: ckdtree_vertex_map(old.vertices, edited.vertices, True), repeat)

    print(
        f"machine: {platform.machine()}, {platform.python_implementation()} {platform.python_version()}, "
        f"numpy {np.__version__}; medians of {repeat}"
    )
    print(f"compare_meshes(old, edited), from scratch:      {t_compare:6.3f} s")
    print(f"  MeshIndex(old) alone:                         {t_index_build:6.3f} s")
    print(f"compare_meshes(index, edited), index prepared:  {t_from_index:6.3f} s")
    print(
        f"baseline: cKDTree vertices + same cell step:    {t_baseline:6.3f} s  "
        f"(compare is {t_baseline / t_compare:.2f}x faster; from the index {t_baseline / t_from_index:.2f}x)"
    )
    print(
        f"  with queries sorted first (stronger):         {t_baseline_sorted:6.3f} s  "
        f"(compare is {t_baseline_sorted / t_compare:.2f}x faster)"
    )
    print(f"vertex matching alone, hashed + sorted:          {t_vertices:6.3f} s")
    print(
        f"vertex matching alone, cKDTree build + query:    {t_vertices_ckdtree:6.3f} s  "
        f"({t_vertices_ckdtree / t_vertices:.2f}x the hashed one)"
    )
    print(
        f"  with queries sorted first:                     {t_vertices_ckdtree_sorted:6.3f} s  "
        f"({t_vertices_ckdtree_sorted / t_vertices:.2f}x)"
    )
    return {
        "compare_s": round(t_compare, 3),
        "compare_from_index_s": round(t_from_index, 3),
        "mesh_index_s": round(t_index_build, 3),
        "ckdtree_baseline_s": round(t_baseline, 3),
        "compare_vs_ckdtree": round(t_baseline / t_compare, 2),
        "compare_from_index_vs_ckdtree": round(t_baseline / t_from_index, 2),
        "ckdtree_sorted_baseline_s": round(t_baseline_sorted, 3),
        "compare_vs_ckdtree_sorted": round(t_baseline_sorted / t_compare, 2),
        "vertex_match_s": round(t_vertices, 3),
        "vertex_match_ckdtree_s": round(t_vertices_ckdtree, 3),
        "vertex_match_vs_ckdtree": round(t_vertices_ckdtree / t_vertices, 2),
        "vertex_match_ckdtree_sorted_s": round(t_vertices_ckdtree_sorted, 3),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--side", type=int, default=1000)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--fraction", type=float, default=0.01, help="fraction of vertices moved, removed, added")
    args = parser.parse_args()
    figures = compare_figures(args.side, args.repeat, args.fraction)
    for name, value in figures.items():
        print(f"{name}: {value}")


if __name__ == "__main__":
    main()
