"""Three-way merge of one mesh: ``three_way_merge`` on a 1M-vertex surface with two disjoint 1,000-vertex edits.

The base is the bumpy 1000 x 1000 grid of ``transfer.py`` (1,000,000 vertices,
1,996,002 triangles, one vertex property), as id-keyed rows (ids 0..n-1, as
uploaded). The parent moves a 40 x 25 patch of vertices (1,000) near one
corner, the child another near the opposite corner and changes the property
of 100 of them; neither adds or removes rows. Timed, medians of ``--repeat``
runs, in the same process:

- ``three_way_merge(base, parent, child)``: both edits found by id, the
  regions, the merged state and its validity check;
- the baseline: ``compare_meshes(base, parent)`` of the same meshes (the
  comparison check-in by difference runs on one edit today);
- with conflicts: the child's patch moved onto the parent's (overlapping
  edits), ``three_way_merge`` and then ``apply_solutions`` with ``child``;
- edits that add and remove rows: the parent removes 500 vertices of its
  patch with their triangles, the child splits 500 triangles of its patch
  into fans of three around a new vertex, its new ids the same as the
  parent's would be (renumbered), so that rows are inserted, not rewritten.

The merged state is checked to be exactly the union of the two edits before
anything is timed. No database here.

    python bench/merge3.py [--side 1000] [--repeat 3]
"""

from __future__ import annotations

import argparse
import platform
from typing import Any

import numpy as np
from timing import timed
from transfer import grid_surface

import tgsis
from tgsis.merge3 import MeshState, apply_solutions, three_way_merge


def patch(side: int, row0: int, col0: int, rows: int = 40, cols: int = 25) -> np.ndarray:
    """Vertex ids of a rows x cols block of the grid (ids are row * side + col)."""
    r, c = np.meshgrid(np.arange(row0, row0 + rows), np.arange(col0, col0 + cols), indexing="ij")
    return (r * side + c).ravel()


def edited(
    surface: tgsis.Surface, moved: np.ndarray, dz: float, changed_property: np.ndarray | None = None
) -> MeshState:
    vertices = surface.vertices.copy()
    vertices[moved, 2] += dz
    porosity = surface.vertex_properties["porosity"].copy()
    if changed_property is not None:
        porosity[changed_property] = 0.5
    return MeshState.from_mesh(tgsis.Surface(vertices, surface.cells, vertex_properties={"porosity": porosity}))


def remove_vertices(state: MeshState, gone: np.ndarray) -> MeshState:
    """The state without these vertex ids and the cells on them."""
    keep_v = ~np.isin(state.vertex_ids, gone)
    keep_c = ~np.isin(state.cells, gone).any(axis=1)
    return MeshState(
        3,
        state.vertex_ids[keep_v],
        state.vertices[keep_v],
        state.cell_ids[keep_c],
        state.cells[keep_c],
        {n: v[keep_v] for n, v in state.vertex_properties.items()},
        {n: v[keep_c] for n, v in state.cell_properties.items()},
        state.name,
    )


def split_cells(state: MeshState, cells: np.ndarray) -> MeshState:
    """The state with these cell ids (positions, ids 0..m-1) split into three around a new vertex at the centre."""
    rows = state.cells[cells]
    first_v = int(state.vertex_ids.max()) + 1
    first_c = int(state.cell_ids.max()) + 1
    new_v = first_v + np.arange(len(cells))
    centres = state.vertices[rows].mean(axis=1) + [0.0, 0.0, 1.0]
    a, b, c = rows[:, 0], rows[:, 1], rows[:, 2]
    fans = np.concatenate([np.stack(t, axis=1) for t in ((a, b, new_v), (b, c, new_v), (c, a, new_v))])
    keep = np.ones(state.n_cells, dtype=bool)
    keep[cells] = False
    return MeshState(
        3,
        np.concatenate([state.vertex_ids, new_v]),
        np.concatenate([state.vertices, centres]),
        np.concatenate([state.cell_ids[keep], first_c + np.arange(len(fans))]),
        np.concatenate([state.cells[keep], fans]),
        {n: np.concatenate([v, np.zeros(len(cells))]) for n, v in state.vertex_properties.items()},
        {},
        state.name,
    )


def merge_figures(side: int = 1000, repeat: int = 3) -> dict[str, Any]:
    surface = grid_surface(side)
    base = MeshState.from_mesh(surface, name="bench")
    p_moved, c_moved = patch(side, 10, 10), patch(side, side - 60, side - 60)
    parent = edited(surface, p_moved, 5.0)
    child = edited(surface, c_moved, -3.0, changed_property=c_moved[:100])
    print(
        f"base: {base.n_vertices} vertices, {base.n_cells} triangles; parent moved {len(p_moved)} vertices, "
        f"child moved {len(c_moved)} (and changed a property of 100)"
    )

    merge = three_way_merge(base, parent, child)
    assert merge.merged is not None and not merge.conflicts and len(merge.regions) == 2
    expected = surface.vertices.copy()
    expected[p_moved, 2] += 5.0
    expected[c_moved, 2] -= 3.0
    state = merge.merged.state
    assert np.array_equal(state.vertices.view(np.int64), expected.view(np.int64))
    assert np.array_equal(state.cells, base.cells)
    assert np.count_nonzero(state.vertex_properties["porosity"] != surface.vertex_properties["porosity"]) == 100

    overlapping = edited(surface, patch(side, 30, 20), -3.0)
    conflicting = three_way_merge(base, parent, overlapping)
    assert len(conflicting.conflicts) == 1
    solution = {conflicting.conflicts[0].index: "child"}

    # rows added and removed: the parent removes vertices, the child splits triangles (their new ids collide)
    removed = patch(side, 10, 10)[::2]
    c_quads = patch(side - 1, side - 60, side - 60)[:500]
    rows_parent = remove_vertices(base, removed)
    rows_child = split_cells(base, c_quads)
    rows_parent = MeshState(
        3,
        np.concatenate([rows_parent.vertex_ids, [base.n_vertices]]),
        np.concatenate([rows_parent.vertices, [[0.0, 0.0, 0.0]]]),
        rows_parent.cell_ids,
        rows_parent.cells,
        {"porosity": np.concatenate([rows_parent.vertex_properties["porosity"], [0.0]])},
        {},
        "bench",
    )  # a lone new vertex of the parent: the child's first new id is renumbered
    structural = three_way_merge(base, rows_parent, rows_child)
    assert structural.merged is not None and not structural.conflicts
    merged = structural.merged.state
    assert merged.n_vertices == base.n_vertices - len(removed) + 1 + 500
    assert merged.n_cells == rows_parent.n_cells + 2 * 500
    assert structural.child_vertex_renumbering.tolist() == [[base.n_vertices, base.n_vertices + 500]]
    t_structural = timed(lambda: three_way_merge(base, rows_parent, rows_child), repeat)

    base_mesh, parent_mesh = base.to_mesh(), parent.to_mesh()
    t_merge = timed(lambda: three_way_merge(base, parent, child), repeat)
    t_compare = timed(lambda: tgsis.compare_meshes(base_mesh, parent_mesh), repeat)
    t_conflict = timed(lambda: three_way_merge(base, parent, overlapping), repeat)
    t_solve = timed(lambda: apply_solutions(conflicting, solution), repeat)

    print(
        f"machine: {platform.machine()}, {platform.python_implementation()} {platform.python_version()}, "
        f"numpy {np.__version__}; medians of {repeat}"
    )
    print(f"three_way_merge, two disjoint edits:         {t_merge:6.3f} s")
    print(f"baseline: compare_meshes(base, parent):      {t_compare:6.3f} s  (merge is {t_merge / t_compare:.2f}x)")
    print(f"three_way_merge, overlapping edits:          {t_conflict:6.3f} s  (1 conflicting region)")
    print(f"apply_solutions(child) of that conflict:     {t_solve:6.3f} s")
    print(f"three_way_merge, rows added and removed:     {t_structural:6.3f} s  (500 vertices removed, 500 split)")
    return {
        "merge_disjoint_s": round(t_merge, 3),
        "compare_baseline_s": round(t_compare, 3),
        "merge_vs_compare": round(t_merge / t_compare, 2),
        "merge_overlapping_s": round(t_conflict, 3),
        "apply_solution_s": round(t_solve, 3),
        "merge_rows_added_removed_s": round(t_structural, 3),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--side", type=int, default=1000)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    for name, value in merge_figures(args.side, args.repeat).items():
        print(f"{name}: {value}")


if __name__ == "__main__":
    main()
