"""``average`` of a region the two sides meshed differently (issue 39 item 3): the morphological average shape.

A curved sheet (tests/merge_data.py: z = 150 sin x cos y, not flat) where one
side splits the triangles of a 6 x 6 block at their centroids (lifted onto the
curved surface: the same shape, another meshing) and the other side lifts the
block's interior in a smooth bump. ``average`` of that region is
``tgsis.interpolation.average_shape`` of the two sides' region patches, the
unchanged rest's vertices on the patch border as control vertices: the
result is a valid mesh attached to the rest without a seam (the rest bit for
bit, the same border edges), halfway between the two sides (Hausdorff
distance), and it merges through ``tgsis.merge_version`` into a valid parent.
Sides of one meshing keep the exact midpoint of today. Line sets and
tetrahedral solids, where the average shape of two meshings is not defined,
are refused with TG307 saying so.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import numpy.typing as npt
import psycopg
import pytest

import tgsis
from tests.merge_data import SIDE, curved_surface, make_fault
from tgsis.db import regions as R
from tgsis.db._state_write import write_state_difference
from tgsis.db.classes import class_of_feature
from tgsis.errors import RegionSolutionError
from tgsis.interpolation import check_disk, closest_points
from tgsis.merge3 import MeshMerge, MeshState, apply_solutions, three_way_merge

Conn = psycopg.Connection[Any]

GRID = np.arange(SIDE * SIDE).reshape(SIDE, SIDE)  # GRID[row, col]: u (x) along the columns, v (y) along the rows
BLOCK = GRID[3:9, 3:9].ravel()  # the patch one side re-meshes
INNER = GRID[4:8, 4:8].ravel()  # its interior: what the other side moves (the block's ring stays put)
BUMP = 60.0  # metres, the largest lift of the moved side
HALF_TOLERANCE = 0.05  # the average's distance to each side is within 5 % of half the distance between the sides


def _surface_z(xy: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]:
    """The curved sheet's height at (x, y): curved_surface's z = 150 sin u cos v."""
    return np.asarray(150.0 * np.sin(xy[:, 0] / 1000.3) * np.cos(xy[:, 1] / 997.1), dtype=np.float64)


def _base() -> MeshState:
    return MeshState.from_mesh(curved_surface())


def _moved(base: MeshState) -> MeshState:
    """The block's interior lifted in a smooth bump (sin x sin over the block: zero on its ring)."""
    rows, cols = np.divmod(INNER, SIDE)
    weight = np.sin(np.pi * (rows - 3) / 5) * np.sin(np.pi * (cols - 3) / 5)
    xyz = base.vertices.copy()
    xyz[INNER, 2] += BUMP * weight
    return MeshState(3, base.vertex_ids, xyz, base.cell_ids, base.cells, base.vertex_properties, base.cell_properties)


def _subdivided(base: MeshState) -> MeshState:
    """Every triangle of the block split at its centroid, the new vertex on the curved surface (a conforming re-meshing)."""
    inside = np.isin(base.cells, BLOCK).all(axis=1)
    at = np.flatnonzero(inside)
    corners = base.cells[at]
    centroid = base.vertices[corners].mean(axis=1)
    centroid[:, 2] = _surface_z(centroid)
    new_v = base.n_vertices + np.arange(len(at))
    new_c = base.n_cells + np.arange(2 * len(at))
    cells = base.cells.copy()
    a, b, c = corners.T
    cells[at] = np.stack([a, b, new_v], axis=1)  # the first third keeps the triangle's id
    added = np.concatenate([np.stack([b, c, new_v], axis=1), np.stack([c, a, new_v], axis=1)])
    porosity = np.asarray(base.vertex_properties["porosity"])
    facies = np.asarray(base.cell_properties["facies"])
    return MeshState(
        3,
        np.concatenate([base.vertex_ids, new_v]),
        np.vstack([base.vertices, centroid]),
        np.concatenate([base.cell_ids, new_c]),
        np.vstack([cells, added]),
        {"porosity": np.concatenate([porosity, porosity[corners].mean(axis=1)])},
        {"facies": np.concatenate([facies, facies[at], facies[at]]).astype(facies.dtype)},
    )


def _merge(parent_subdivides: bool) -> MeshMerge:
    base = _base()
    moved, split = _moved(base), _subdivided(base)
    parent, child = (split, moved) if parent_subdivides else (moved, split)
    return three_way_merge(base, parent, child)


def _surface(state: MeshState) -> tgsis.Surface:
    return tgsis.Surface(state.vertices, np.searchsorted(state.vertex_ids, state.cells))


def _samples(surface: tgsis.Surface, n: int = 6) -> npt.NDArray[np.float64]:
    """Points on every triangle (a barycentric grid of n + 1 points a side, corners included)."""
    i, j = np.meshgrid(np.arange(n + 1), np.arange(n + 1))
    keep = i + j <= n
    w = np.stack([i[keep], j[keep], n - i[keep] - j[keep]], axis=1) / n  # (s, 3)
    corners = surface.vertices[surface.cells]  # (m, 3, 3)
    return np.asarray(np.einsum("sk,mkd->msd", w, corners).reshape(-1, 3), dtype=np.float64)


def hausdorff(a: tgsis.Surface, b: tgsis.Surface) -> float:
    """The symmetric Hausdorff distance between two triangle meshes, from dense samples to exact closest points."""
    one = closest_points(_samples(a), b.vertices, b.cells).distances.max()
    two = closest_points(_samples(b), a.vertices, a.cells).distances.max()
    return float(max(one, two))


def _boundary_edges(cells: npt.NDArray[np.int64]) -> set[tuple[int, int]]:
    """The directed edges of these triangles that no other of them has (the patch's border, as oriented)."""
    edges = np.concatenate([cells[:, [0, 1]], cells[:, [1, 2]], cells[:, [2, 0]]])
    undirected = np.sort(edges, axis=1)
    keys, counts = np.unique(undirected, axis=0, return_counts=True)
    once = {tuple(k) for k in keys[counts == 1].tolist()}
    return {(int(a), int(b)) for a, b in edges.tolist() if tuple(sorted((a, b))) in once}


def _check_attached_and_halfway(merge: MeshMerge, state: MeshState, region: Any) -> None:
    """The merged state: a valid disk, the rest bit for bit, the region's border the rest's, halfway between the sides."""
    surface = _surface(state)
    disk = check_disk(surface)
    assert disk.ok, disk.reasons  # manifold, one piece, one border, no vertex on no triangle
    assert len(np.unique(np.sort(state.cells, axis=1), axis=0)) == state.n_cells  # no duplicated triangle
    # the rest (every vertex both sides left where the base has it) bit for bit
    base = merge.base
    kept = base.vertex_ids[~np.isin(base.vertex_ids, INNER)]
    at = np.searchsorted(state.vertex_ids, kept)
    assert np.array_equal(state.vertex_ids[at], kept)
    assert state.vertices[at].tobytes() == base.vertices[np.searchsorted(base.vertex_ids, kept)].tobytes()
    # every triangle off the region as the parent has it; the region's border is the rest's, as oriented
    outside = ~np.isin(state.cell_ids, region.cell_ids)
    p_out = ~np.isin(merge.parent.cell_ids, region.cell_ids)
    assert np.array_equal(state.cell_ids[outside], merge.parent.cell_ids[p_out])
    assert np.array_equal(state.cells[outside], merge.parent.cells[p_out])
    in_region = state.cells[~outside]
    assert _boundary_edges(in_region) == _boundary_edges(merge.parent.cells[~p_out])
    assert set(np.unique(in_region).tolist()) >= set(np.setdiff1d(BLOCK, INNER).tolist())
    # halfway: the distance to each side about half the distance between the sides
    between = hausdorff(_surface(merge.parent), _surface(merge.child))
    assert between == pytest.approx(BUMP * np.sin(2 * np.pi / 5) ** 2, rel=0.1)  # the bump's top, sampled
    for side in (merge.parent, merge.child):
        distance = hausdorff(surface, _surface(side))
        assert abs(distance - between / 2) <= HALF_TOLERANCE * between / 2, (distance, between)


@pytest.mark.parametrize("parent_subdivides", [False, True], ids=["child-subdivides", "parent-subdivides"])
def test_average_of_a_patch_one_side_subdivided_and_the_other_moved(parent_subdivides: bool) -> None:
    merge = _merge(parent_subdivides)
    [region] = merge.conflicts
    average = R.average_region(merge, region)
    assert average.name.endswith("average")
    resolved = apply_solutions(merge, {region.index: average}, names={region.index: "average"})
    _check_attached_and_halfway(merge, resolved.state, region)
    # what it discards of each side is said, under the name average
    assert {d.side for d in resolved.discards} == {"parent", "child"}
    assert {d.solution for d in resolved.discards} == {"average"}
    mover = next(d for d in resolved.discards if d.side == ("child" if parent_subdivides else "parent"))
    assert 0.4 * BUMP < mover.max_displacement < 0.6 * BUMP  # the bump's top came half the way down
    # no id of the result clashes with one a side gave something else: ids are the finer side's (no new ones)
    split = merge.parent if parent_subdivides else merge.child
    assert np.isin(average.vertex_ids, split.vertex_ids).all() and np.isin(average.cell_ids, split.cell_ids).all()
    # the vertex property travels: each new vertex's porosity between its neighbours', as both sides have it
    porosity = np.asarray(average.vertex_properties["porosity"])
    assert np.isfinite(porosity).all() and porosity.min() >= 0.1 - 1e-12 and porosity.max() <= 0.3 + 1e-12


def test_the_same_meshing_keeps_the_exact_midpoint() -> None:
    """Both sides move the block's interior (other bumps): every region vertex at (p + c) / 2, bit for bit, as before."""
    base = _base()
    up = _moved(base)
    down_xyz = base.vertices.copy()
    down_xyz[INNER, 2] -= 0.37 * (up.vertices[INNER, 2] - base.vertices[INNER, 2]) + 1.0
    down = MeshState(
        3, base.vertex_ids, down_xyz, base.cell_ids, base.cells, base.vertex_properties, base.cell_properties
    )
    merge = three_way_merge(base, up, down)
    [region] = merge.conflicts
    average = R.average_region(merge, region)
    at = np.searchsorted(average.vertex_ids, INNER)
    expected = 0.5 * up.vertices[INNER] + 0.5 * down.vertices[INNER]
    assert average.vertices[at].tobytes() == expected.tobytes()
    assert np.array_equal(average.cells, base.cells[np.isin(base.cell_ids, average.cell_ids)])


def test_a_value_the_version_changed_on_a_corner_of_the_region_is_kept_by_the_average() -> None:
    """The version re-values a vertex of the block's ring (a corner of the region's cells, a region of its own:
    a value change puts no cell in a footprint): the average's corner row is the one the merge gives the rest,
    the version's, not the parent's (which was refused as "changes rows outside the region")."""
    base = _base()
    up = _moved(base)
    down_xyz = base.vertices.copy()
    down_xyz[GRID[5:7, 5:7].ravel(), 2] -= 7.0  # inside what the parent lifts: the ring's cells are the parent's
    ring = int(GRID[3, 5])  # on the block's ring: a corner of triangles on vertices the parent alone moved
    porosity = np.asarray(base.vertex_properties["porosity"]).copy()
    porosity[ring] = 0.99
    down = MeshState(
        3, base.vertex_ids, down_xyz, base.cell_ids, base.cells, {"porosity": porosity}, base.cell_properties
    )
    merge = three_way_merge(base, up, down)
    [region] = merge.conflicts
    assert ring not in region.vertex_ids.tolist()
    average = R.average_region(merge, region)
    assert ring in average.vertex_ids.tolist()  # a corner of the region's cells
    state = apply_solutions(merge, {region.index: average}).state
    assert state.vertex_properties["porosity"][np.searchsorted(state.vertex_ids, ring)] == 0.99
    moved = region.vertex_ids
    at = np.searchsorted(state.vertex_ids, moved)
    assert state.vertices[at].tobytes() == (0.5 * up.vertices[moved] + 0.5 * down.vertices[moved]).tobytes()


def _line_merge() -> MeshMerge:
    """A curved line of 20 vertices: the parent lifts its middle, the child splits its middle segments."""
    t = np.linspace(0.0, 3.0, 20)
    xyz = np.stack([t * 1000.0, np.zeros_like(t), 150.0 * np.sin(t)], axis=1)
    segs = np.stack([np.arange(19), np.arange(1, 20)], axis=1)
    base = MeshState(2, np.arange(20), xyz, np.arange(19), segs)
    lifted = xyz.copy()
    lifted[8:12, 2] += 30.0
    parent = MeshState(2, np.arange(20), lifted, np.arange(19), segs)
    mids = 0.5 * (xyz[8:11] + xyz[9:12])
    new_v = 20 + np.arange(3)
    split = segs.copy()
    split[8:11, 1] = new_v
    child = MeshState(
        2,
        np.arange(23),
        np.vstack([xyz, mids]),
        np.arange(22),
        np.vstack([split, np.stack([new_v, np.arange(9, 12)], axis=1)]),
    )
    return three_way_merge(base, parent, child)


def _tetra_merge() -> MeshMerge:
    """Two tetrahedra on a shared face: the parent moves an apex, the child splits that tetrahedron at its centroid."""
    xyz = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.1], [0.0, 1.0, 0.2], [0.2, 0.3, 1.0], [0.3, 0.2, -1.0]]) * 100.0
    tets = np.array([[0, 1, 2, 3], [0, 2, 1, 4]])
    base = MeshState(4, np.arange(5), xyz, np.arange(2), tets)
    moved = xyz.copy()
    moved[3] += [0.0, 0.0, 25.0]
    parent = MeshState(4, np.arange(5), moved, np.arange(2), tets)
    centre = xyz[:4].mean(axis=0)
    a, b, c, d = 0, 1, 2, 3
    split = np.array([[a, b, c, 5], [a, b, 5, d], [a, 5, c, d], [5, b, c, d], [0, 2, 1, 4]])
    child = MeshState(4, np.arange(6), np.vstack([moved[:3], xyz[3:], centre]), np.array([0, 2, 3, 4, 1]), split)
    return three_way_merge(base, parent, child)


@pytest.mark.parametrize("make, word", [(_line_merge, "segment"), (_tetra_merge, "tetrahedr")])
def test_average_of_two_meshings_of_lines_or_solids_is_refused(make: Any, word: str) -> None:
    merge = make()
    [region] = merge.conflicts
    with pytest.raises(RegionSolutionError, match=rf"{word}.*average_shape.*triangulated surfaces") as refused:
        R.average_region(merge, region)
    assert refused.value.sqlstate == "TG307"
    assert refused.value.hint and "manual" in refused.value.hint


def test_a_region_patch_that_is_no_disk_is_refused_saying_why() -> None:
    """The re-meshing side also drops a triangle inside the block: its patch has a hole, no disk to map."""
    base = _base()
    split = _subdivided(base)
    hole = np.flatnonzero(np.isin(split.cells, INNER[5:6]).any(axis=1))[:1]  # one triangle at an inner vertex
    keep = np.setdiff1d(np.arange(split.n_cells), hole)
    holed = MeshState(
        3,
        split.vertex_ids,
        split.vertices,
        split.cell_ids[keep],
        split.cells[keep],
        split.vertex_properties,
        {n: np.asarray(v)[keep] for n, v in split.cell_properties.items()},
    )
    merge = three_way_merge(base, _moved(base), holed)
    [region] = merge.conflicts
    with pytest.raises(RegionSolutionError, match=r"region 0: .*no topological disk \(2 border loops") as refused:
        R.average_region(merge, region)
    assert refused.value.sqlstate == "TG307"


def test_an_average_that_folds_the_surface_is_refused_naming_the_triangles() -> None:
    """The version pushes one column of the block 900 m (three grid steps) past its neighbours: folded, halfway too."""
    base = _base()
    xyz = base.vertices.copy()
    column = INNER[INNER % SIDE == 4]
    xyz[column, 0] += 900.0
    pushed = MeshState(3, base.vertex_ids, xyz, base.cell_ids, base.cells, base.vertex_properties, base.cell_properties)
    merge = three_way_merge(base, _subdivided(base), pushed)
    [region] = merge.conflicts
    with pytest.raises(RegionSolutionError, match=r"region 0: .*turns triangles \d+, .* over \(a fold\)") as refused:
        R.average_region(merge, region)
    assert refused.value.sqlstate == "TG307"


# --------------------------------------------------------------------------- through the database


def _write(conn: Conn, version: str, geoid: int, old: MeshState, new: MeshState) -> None:
    with tgsis.in_version(conn, version):
        write_state_difference(conn, class_of_feature(conn, geoid), geoid, old, new)
    conn.commit()


def test_merge_version_with_the_average_of_two_meshings_gives_a_valid_parent(conn: Conn) -> None:
    geoid = make_fault(conn)
    base = MeshState.from_mesh(curved_surface())  # as uploaded: ids 0..n-1, the class's property columns
    _write(conn, "e1", geoid, base, _subdivided(base))
    _write(conn, "DEFAULT", geoid, base, _moved(base))
    [conflict] = tgsis.find_conflicts(conn, "e1")
    [region] = [r for r in conflict.regions if r.conflict]
    resolution = tgsis.resolve_region(conn, "e1", geoid, region.region, "average")
    conn.commit()
    assert resolution.region.solution == "average" and resolution.state is not None
    assert {d.side for d in resolution.discards} == {"parent", "child"}
    merge = tgsis.object_merge(conn, "e1", geoid)
    result = tgsis.merge_version(conn, "e1")
    conn.commit()
    assert [o.how for o in result.objects] == ["solutions"]
    # DEFAULT as a psql user reads it: a valid curved sheet, the rest bit for bit, halfway in the block
    with tgsis.in_version(conn, "DEFAULT"):
        vertices = conn.execute("SELECT vrtxid, x, y, z FROM tgsis.vrtx WHERE geoid = %s ORDER BY vrtxid", (geoid,))
        vrows = vertices.fetchall()
        cells = conn.execute(
            "SELECT trglid, vrtxid1, vrtxid2, vrtxid3 FROM tgsis.trgl WHERE geoid = %s ORDER BY trglid", (geoid,)
        ).fetchall()
    conn.rollback()
    state = MeshState(
        3,
        np.array([r[0] for r in vrows], dtype=np.int64),
        np.array([r[1:] for r in vrows], dtype=np.float64),
        np.array([r[0] for r in cells], dtype=np.int64),
        np.array([r[1:] for r in cells], dtype=np.int64),
    )
    [conflicting] = merge.conflicts
    _check_attached_and_halfway(merge, state, conflicting)
    assert not tgsis.find_conflicts(conn, "e1")


def test_average_of_all_regions_with_one_re_meshed_merges_into_a_valid_parent(conn: Conn) -> None:
    """Two conflicting regions, the version splitting a triangle of one: ``resolve_all_regions(..., 'average')``."""
    from tests.merge_data import stored_state
    from tests.test_resolve_all_regions import WEST, _two_conflicts

    fault = _two_conflicts(conn, remesh_west=True)
    [conflict] = tgsis.find_conflicts(conn, "e1")
    conn.commit()
    conflicting = [r for r in conflict.regions if r.conflict]
    assert len(conflicting) == 2
    result = tgsis.resolve_all_regions(conn, "e1", fault, "average")
    conn.commit()
    assert {r.solution for r in result.regions} == {"average"} and len(result.regions) == 2
    west = next(r for r in conflicting if np.isin(WEST, r.vertex_ids).all())
    assert {d.side for d in result.discards if d.region == west.region} == {"parent", "child"}
    merge = tgsis.object_merge(conn, "e1", fault)
    tgsis.merge_version(conn, "e1")
    conn.commit()
    ids, xyz, cells, _ = stored_state(conn, "DEFAULT", fault)
    triangles = np.array(sorted(cells))[:, 1:]
    surface = tgsis.Surface(xyz, np.searchsorted(ids, triangles))
    assert check_disk(surface).ok
    assert len(ids) == SIDE * SIDE + 1  # the version's new vertex kept: its finer meshing carries the average
    west_z = xyz[np.searchsorted(ids, WEST), 2]
    p_z = merge.parent.vertices[np.searchsorted(merge.parent.vertex_ids, WEST), 2]
    c_z = merge.child.vertices[np.searchsorted(merge.child.vertex_ids, WEST), 2]
    assert np.all((west_z > np.minimum(p_z, c_z)) & (west_z < np.maximum(p_z, c_z)))  # between the sides (+3, -2)
