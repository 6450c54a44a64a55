"""EditPlan: the rows to keep, rewrite, remove and add; moved vertices recognised (numpy only)."""

from __future__ import annotations

import numpy as np
import pytest

import tgsis
from tgsis.edits import EditPlan, plan_edit


def _grid(side: int) -> tgsis.Surface:
    u, v = np.meshgrid(np.arange(side, dtype=float), np.arange(side, dtype=float))
    vertices = np.stack([u.ravel(), v.ravel(), np.zeros(side * side)], axis=1)
    idx = np.arange(side * side).reshape(side, side)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel()
    return tgsis.Surface(vertices, np.concatenate([np.stack([a, b, d], 1), np.stack([a, d, c], 1)]))


def _apply(
    old: tgsis.Mesh, edited: tgsis.Mesh, plan: EditPlan
) -> tuple[dict[int, tuple[float, ...]], set[tuple[int, ...]]]:
    """What the database holds after writing the plan: vertex rows by id, cells as oriented id tuples.

    Old rows keep ids 0..n-1; new rows get ids from n on. Cells are
    normalised to their smallest rotation-equivalent (even permutation) form.
    """
    rows = {i: tuple(old.vertices[i]) for i in range(old.n_vertices)}
    for i in plan.removed_vertices.tolist():
        del rows[i]
    ids = np.where(plan.vertex_map >= 0, plan.vertex_map, -1)
    new_ids = old.n_vertices + np.arange(len(plan.added_vertices))
    ids[plan.added_vertices] = new_ids
    for i in plan.moved_vertices.tolist():  # rewritten under the old id
        rows[int(ids[i])] = tuple(edited.vertices[i])
    for i, nid in zip(plan.added_vertices.tolist(), new_ids.tolist()):
        rows[nid] = tuple(edited.vertices[i])
    cells = {tuple(c) for j, c in enumerate(old.cells.tolist()) if j not in set(plan.removed_cells.tolist())}
    cells |= {tuple(ids[edited.cells[j]].tolist()) for j in plan.added_cells.tolist()}
    return rows, {_oriented(c) for c in cells}


def _oriented(cell: tuple[int, ...]) -> tuple[int, ...]:
    """The even permutation of ``cell`` that starts with its smallest id (a canonical oriented form, k <= 3)."""
    k = int(np.argmin(cell))
    return tuple(cell[k:] + cell[:k])


def _expected(edited: tgsis.Mesh) -> tuple[set[tuple[float, ...]], set[tuple[tuple[float, ...], ...]]]:
    coords = [tuple(v) for v in edited.vertices]
    return set(coords), {_oriented_coords(tuple(coords[i] for i in c)) for c in edited.cells.tolist()}


def _oriented_coords(cell: tuple[tuple[float, ...], ...]) -> tuple[tuple[float, ...], ...]:
    k = min(range(len(cell)), key=lambda i: cell[i])
    return cell[k:] + cell[:k]


def _check_written(old: tgsis.Mesh, edited: tgsis.Mesh, plan: EditPlan) -> None:
    rows, cells = _apply(old, edited, plan)
    want_vertices, want_cells = _expected(edited)
    assert set(rows.values()) == want_vertices and len(rows) == edited.n_vertices
    assert {_oriented_coords(tuple(rows[i] for i in c)) for c in cells} == want_cells
    assert len(cells) == edited.n_cells


def _shuffle(mesh: tgsis.Surface, rng: np.random.Generator) -> tgsis.Surface:
    vperm, cperm = rng.permutation(mesh.n_vertices), rng.permutation(mesh.n_cells)
    rank = np.empty_like(vperm)
    rank[vperm] = np.arange(len(vperm))
    return tgsis.Surface(mesh.vertices[vperm], rank[mesh.cells[cperm]])


def test_isolated_moves_keep_every_cell() -> None:
    old = _grid(30)
    vertices = old.vertices.copy()
    moved = np.array([31, 95, 400, 777])
    vertices[moved, 2] = 1.0
    edited = _shuffle(tgsis.Surface(vertices, old.cells), np.random.default_rng(0))
    diff = tgsis.compare_meshes(old, edited)
    assert diff.counts()["vertices_removed"] == 4 and diff.counts()["cells_removed"] > 20
    plan = plan_edit(old, edited, diff)
    assert len(plan.moved_vertices) == 4 and len(plan.removed_vertices) == 0 and len(plan.added_vertices) == 0
    assert len(plan.removed_cells) == 0 and len(plan.added_cells) == 0
    assert sorted(plan.vertex_map[plan.moved_vertices].tolist()) == moved.tolist()
    _check_written(old, edited, plan)


def test_a_moved_block_resolves_ring_by_ring() -> None:
    old = _grid(30)
    vertices = old.vertices.copy()
    block = (vertices[:, 0] >= 5) & (vertices[:, 0] <= 20) & (vertices[:, 1] >= 5) & (vertices[:, 1] <= 20)
    vertices[block, 2] = 3.0  # a 16 x 16 block lifted: 8 rings
    edited = tgsis.Surface(vertices, old.cells)
    plan = plan_edit(old, edited, tgsis.compare_meshes(old, edited))
    assert len(plan.moved_vertices) == block.sum() and len(plan.added_cells) == 0
    _check_written(old, edited, plan)


def test_flips_removals_and_additions_stay_edits() -> None:
    rng = np.random.default_rng(3)
    old = _grid(20)
    cells = old.cells.copy()
    half = len(cells) // 2
    a, b, d = cells[7]
    c = cells[half + 7][2]
    cells[7], cells[half + 7] = (a, b, c), (b, d, c)  # a flipped diagonal: both triangles new
    keep = ~np.isin(cells, [210]).any(axis=1)  # vertex 210 removed with its triangles
    vertices = np.concatenate([old.vertices, [[50.0, 50.0, 0.0]]])
    cells = np.concatenate([cells[keep], [[0, 1, len(vertices) - 1]]])
    used = np.unique(cells)
    renumber = np.full(len(vertices), -1)
    renumber[used] = np.arange(len(used))
    edited = _shuffle(tgsis.Surface(vertices[used], renumber[cells]), rng)
    plan = plan_edit(old, edited, tgsis.compare_meshes(old, edited))
    assert len(plan.moved_vertices) == 0  # nothing explains the new vertex as 210 moved
    assert plan.removed_vertices.tolist() == [210] and len(plan.added_vertices) == 1
    assert len(plan.added_cells) == 3 and len(plan.removed_cells) == 2 + 6
    _check_written(old, edited, plan)


@pytest.mark.parametrize("seed", range(6))
def test_any_random_edit_writes_the_edited_mesh(seed: int) -> None:
    rng = np.random.default_rng(seed)
    old = _grid(15)
    vertices = old.vertices.copy()
    vertices[rng.choice(old.n_vertices, 40, replace=False), 2] += rng.random(40)
    cells = old.cells[rng.permutation(old.n_cells)[: old.n_cells - 10]]  # 10 triangles dropped
    edited = _shuffle(tgsis.Surface(vertices, cells), rng)
    plan = plan_edit(old, edited, tgsis.compare_meshes(old, edited))
    assert len(plan.moved_vertices) > 0
    _check_written(old, edited, plan)


def test_point_sets_have_no_moves() -> None:
    old = tgsis.PointSet(np.random.default_rng(1).random((50, 3)))
    vertices = old.vertices.copy()
    vertices[3] += 1.0
    edited = tgsis.PointSet(vertices)
    plan = plan_edit(old, edited, tgsis.compare_meshes(old, edited))
    assert len(plan.moved_vertices) == 0 and plan.removed_vertices.tolist() == [3]
