"""Three-way merge of one mesh (tgsis.merge3, docs/merge.md) against a plain-Python reference (no database).

Hypothesis edits curved surfaces (grids on a cylinder, ids neither dense nor
from 0), tetrahedra, segments and points on both sides. Disjoint edits must
merge into exactly the union (coordinates bit for bit, cell rows as each side
has them); the regions and conflicts must be those of the rule in
docs/merge.md, worked out here with dictionaries and networkx; identical
edits are no conflict; the order of the two sides changes nothing but the
numbering; each solution gives the mesh it says, and reports what it
discards; merges that would give an invalid mesh are refused naming the ids.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from typing import Any, Literal
from unittest import mock

import networkx as nx
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import tgsis
import tgsis.merge3
from tgsis.merge3 import MeshMerge, MeshState, apply_solutions, three_way_merge

PROPERTY = settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
NAME = "faults 42"


# ---------------------------------------------------------------- a mesh as plain dictionaries


@dataclass
class Rows:
    """An object's rows by id: what a test edits and what the reference reasons on."""

    k: int
    verts: dict[int, tuple[float, float, float]]
    vprop: dict[int, float]
    cells: dict[int, tuple[int, ...]]
    cprop: dict[int, float]
    next_id: list[int] = field(default_factory=lambda: [0])

    def copy(self) -> Rows:
        return Rows(self.k, dict(self.verts), dict(self.vprop), dict(self.cells), dict(self.cprop), list(self.next_id))

    def new_id(self) -> int:
        """The next id above every id of this side (what a database writer hands out): both sides collide."""
        value = max([*self.verts, *self.cells, self.next_id[0]]) + 1
        self.next_id[0] = value
        return value

    def state(self) -> MeshState:
        vids = list(self.verts)
        cids = list(self.cells)
        return MeshState(
            self.k,
            np.array(vids, dtype=np.int64),
            np.array([self.verts[i] for i in vids], dtype=np.float64).reshape(-1, 3),
            np.array(cids, dtype=np.int64),
            np.array([self.cells[i] for i in cids], dtype=np.int64).reshape(-1, self.k),
            {"porosity": np.array([self.vprop[i] for i in vids], dtype=np.float64)},
            {"facies": np.array([self.cprop[i] for i in cids], dtype=np.float64)},
            NAME,
        )

    def remove_vertex(self, v: int) -> None:
        del self.verts[v], self.vprop[v]
        for c in [c for c, row in self.cells.items() if v in row]:
            del self.cells[c], self.cprop[c]


def rows_of(state: MeshState) -> Rows:
    return Rows(
        state.cell_size,
        {int(i): tuple(float(x) for x in xyz) for i, xyz in zip(state.vertex_ids, state.vertices)},  # type: ignore[misc]
        {int(i): float(p) for i, p in zip(state.vertex_ids, state.vertex_properties["porosity"])},
        {int(i): tuple(int(v) for v in row) for i, row in zip(state.cell_ids, state.cells)},
        {int(i): float(p) for i, p in zip(state.cell_ids, state.cell_properties["facies"])},
    )


def bits(xyz: Iterable[float]) -> tuple[int, ...]:
    return tuple(int(np.float64(x).view(np.int64)) for x in xyz)


def assert_same_rows(got: MeshState, expected: Rows) -> None:
    """Exactly these rows: the same ids, coordinates bit for bit, properties, oriented cells."""
    rows = rows_of(got)
    assert {i: bits(x) for i, x in rows.verts.items()} == {i: bits(x) for i, x in expected.verts.items()}
    # cells as oriented cells: a row rotated by an even permutation is the same cell (either row may be kept)
    assert {c: canonical(r) for c, r in rows.cells.items()} == {c: canonical(r) for c, r in expected.cells.items()}
    assert rows.vprop == expected.vprop and rows.cprop == expected.cprop


# ---------------------------------------------------------------- base meshes


@st.composite
def curved_grid(draw: st.DrawFn, min_columns: int = 4) -> tuple[Rows, dict[int, int]]:
    """A grid of triangles wrapped on a cylinder (not flat), ids with an offset and a stride; id -> column."""
    nx_, ny = draw(st.integers(min_columns, min_columns + 5)), draw(st.integers(2, 5))
    radius = draw(st.floats(5.0, 50.0))
    offset = draw(st.sampled_from([0, 7, 1 << 40]))
    stride = draw(st.sampled_from([1, 3, 1 << 30]))  # 1 << 30: ids too sparse for a lookup table
    ids = [offset + stride * i for i in range(nx_ * ny)]
    verts, vprop, column = {}, {}, {}
    for i in range(nx_):
        for j in range(ny):
            angle = 0.15 * i
            vid = ids[i * ny + j]
            verts[vid] = (radius * math.sin(angle), 0.7 * j, radius * math.cos(angle) + 0.01 * j * j)
            vprop[vid] = float(i + 10 * j)
            column[vid] = i
    cells: dict[int, tuple[int, ...]] = {}
    cprop: dict[int, float] = {}
    cell_ids = itertools.count(draw(st.sampled_from([0, 5, 1 << 35])), draw(st.sampled_from([1, 2])))
    for i in range(nx_ - 1):
        for j in range(ny - 1):
            a, b, c, d = (ids[x] for x in (i * ny + j, (i + 1) * ny + j, i * ny + j + 1, (i + 1) * ny + j + 1))
            for tri in ((a, b, d), (a, d, c)):
                cid = next(cell_ids)
                cells[cid], cprop[cid] = tri, float(cid % 7)
    return Rows(3, verts, vprop, cells, cprop), column


@st.composite
def random_rows(draw: st.DrawFn, k: int) -> Rows:
    """A random mesh of cell size k on a curved cloud: distinct cells (as vertex sets), ids shuffled."""
    n = draw(st.integers(k + 1, 14))
    ids = draw(st.permutations(range(0, 3 * n, 3)))[:n]
    verts = {v: (math.cos(0.4 * v), math.sin(0.4 * v), 0.05 * v * v) for v in ids}
    vprop = {v: float(v) for v in ids}
    cell = st.lists(st.sampled_from(ids), min_size=k, max_size=k, unique=True).map(tuple)
    rows = draw(st.lists(cell, unique_by=lambda c: frozenset(c), max_size=2 * n))
    cells = {10 * i + 1: row for i, row in enumerate(rows)}
    return Rows(k, verts, vprop, cells, {c: 0.0 for c in cells})


# ---------------------------------------------------------------- edits


def edit(draw: Callable[[st.SearchStrategy[Any]], Any], rows: Rows, zone: set[int] | None, count: int) -> None:
    """``count`` random edits of the rows, touching only vertices of ``zone`` (None: anywhere), in place."""
    k = rows.k
    for _ in range(count):
        inside = sorted(v for v in rows.verts if zone is None or v in zone)
        cells_inside = sorted(c for c, row in rows.cells.items() if all(v in inside for v in row))
        if not inside:
            return
        action = draw(
            st.sampled_from(
                ["move", "move", "ulp", "prop", "cprop", "remove_vertex", "split", "add_cell", "rotate", "reverse"]
            )
        )
        v = draw(st.sampled_from(inside))
        if action == "move":
            x, y, z = rows.verts[v]
            rows.verts[v] = (x, y, z + draw(st.sampled_from([0.25, -1.5, 3.0])))
        elif action == "ulp":
            x, y, z = rows.verts[v]
            rows.verts[v] = (float(np.nextafter(x, np.inf)), y, z)
        elif action == "prop":
            rows.vprop[v] = rows.vprop[v] + 1.0
        elif action == "cprop" and cells_inside:
            c = draw(st.sampled_from(cells_inside))
            rows.cprop[c] = rows.cprop[c] + 0.5
        elif action == "remove_vertex":
            rows.remove_vertex(v)
        elif action == "split" and cells_inside and k >= 2:
            c = draw(st.sampled_from(cells_inside))
            corners = rows.cells.pop(c)
            rows.cprop.pop(c)
            x = rows.new_id()
            centre = np.mean([rows.verts[u] for u in corners], axis=0) + np.array([0.0, 0.0, 0.125])
            rows.verts[x], rows.vprop[x] = (float(centre[0]), float(centre[1]), float(centre[2])), -1.0
            for i in range(k):  # the cell's k facets each with the new vertex: a fan
                new = list(corners)
                new[i] = x
                rows.cells[rows.new_id()] = tuple(new)
                rows.cprop[max(rows.cells)] = 2.0
        elif action == "rotate" and cells_inside and k >= 3:  # the same oriented cell in another row: no change
            c = draw(st.sampled_from(cells_inside))
            rows.cells[c] = (
                rows.cells[c][1:] + rows.cells[c][:1]
                if k == 3
                else rows.cells[c][1:3]
                + (
                    rows.cells[c][0],
                    rows.cells[c][3],
                )
            )
        elif action == "reverse" and cells_inside and k >= 2:  # the cell turned over: a change
            c = draw(st.sampled_from(cells_inside))
            rows.cells[c] = rows.cells[c][::-1] if k != 3 else (rows.cells[c][1], rows.cells[c][0], rows.cells[c][2])
        elif action == "add_cell" and len(inside) >= k - 1:
            x = rows.new_id()
            base_xyz = rows.verts[v]
            rows.verts[x], rows.vprop[x] = (base_xyz[0] + 0.5, base_xyz[1], base_xyz[2] - 0.5), 3.0
            others = draw(st.permutations(inside))[: k - 1]
            rows.cells[rows.new_id()] = (x, *others)
            rows.cprop[max(rows.cells)] = 1.0


# ---------------------------------------------------------------- the region rule, by hand


def canonical(row: tuple[int, ...]) -> tuple[tuple[int, ...], int]:
    inversions = sum(1 for i in range(len(row)) for j in range(i + 1, len(row)) if row[i] > row[j])
    return tuple(sorted(row)), inversions % 2


def same_vertex(a: Rows, b: Rows, v: int) -> bool:
    if (v in a.verts) != (v in b.verts):
        return False
    return v not in a.verts or (a.verts[v] == b.verts[v] and a.vprop[v] == b.vprop[v])


def same_cell(a: Rows, b: Rows, c: int) -> bool:
    if (c in a.cells) != (c in b.cells):
        return False
    return c not in a.cells or (canonical(a.cells[c]) == canonical(b.cells[c]) and a.cprop[c] == b.cprop[c])


def reference_regions(base: Rows, parent: Rows, child: Rows) -> list[tuple[frozenset[int], frozenset[int], bool]]:
    """(vertex ids, cell ids, conflict) of every region, by docs/merge.md's rule (child already renumbered)."""
    graph = nx.Graph()
    changed: dict[str, set[tuple[str, int]]] = {}
    for name, side in (("parent", parent), ("child", child)):
        vertices = set(base.verts) | set(side.verts)
        cells = set(base.cells) | set(side.cells)
        changed_v = {v for v in vertices if not same_vertex(base, side, v)}
        shape_v = {v for v in changed_v if (v in base.verts) != (v in side.verts) or base.verts[v] != side.verts[v]}
        changed_c = {c for c in cells if not same_cell(base, side, c)}
        topology = {
            c
            for c in changed_c
            if (c in base.cells) != (c in side.cells) or canonical(base.cells[c]) != canonical(side.cells[c])
        }
        foot_v = changed_v | {v for c in topology for s in (base, side) if c in s.cells for v in s.cells[c]}
        foot_c = changed_c | {c for c, row in base.cells.items() if set(row) & shape_v}
        graph.add_nodes_from(("v", v) for v in foot_v)
        graph.add_nodes_from(("c", c) for c in foot_c)
        for c in foot_c:
            for s in (base, side):
                for v in s.cells.get(c, ()):
                    if v in foot_v:
                        graph.add_edge(("c", c), ("v", v))
        changed[name] = {("v", v) for v in changed_v} | {("c", c) for c in changed_c}
    found = []
    for component in nx.connected_components(graph):
        both = bool(component & changed["parent"]) and bool(component & changed["child"])
        differ = any(
            not (same_vertex(parent, child, i) if kind == "v" else same_cell(parent, child, i)) for kind, i in component
        )
        found.append(
            (
                frozenset(i for kind, i in component if kind == "v"),
                frozenset(i for kind, i in component if kind == "c"),
                both and differ,
            )
        )
    return found


def regions_of(merge: MeshMerge) -> list[tuple[frozenset[int], frozenset[int], bool]]:
    return [(frozenset(r.vertex_ids.tolist()), frozenset(r.cell_ids.tolist()), r.conflict) for r in merge.regions]


def renumbered_child(child: Rows, merge: MeshMerge) -> Rows:
    """The child's rows with the merge's renumbering applied (checked against merge.child)."""
    vmap = dict(merge.child_vertex_renumbering.tolist())
    cmap = dict(merge.child_cell_renumbering.tolist())
    out = Rows(
        child.k,
        {vmap.get(v, v): xyz for v, xyz in child.verts.items()},
        {vmap.get(v, v): p for v, p in child.vprop.items()},
        {cmap.get(c, c): tuple(vmap.get(v, v) for v in row) for c, row in child.cells.items()},
        {cmap.get(c, c): p for c, p in child.cprop.items()},
    )
    assert_same_rows(merge.child, out)
    return out


def check_renumbering(base: Rows, parent: Rows, child: Rows, merge: MeshMerge) -> None:
    """Only the child's new ids the parent uses for something else change, to fresh ids above all."""
    vmap = dict(merge.child_vertex_renumbering.tolist())
    for kind, renumbering, mine, theirs, known in (
        ("v", merge.child_vertex_renumbering, child.verts, parent.verts, base.verts),
        ("c", merge.child_cell_renumbering, child.cells, parent.cells, base.cells),
    ):
        mapping = dict(renumbering.tolist())
        top = max([*known, *theirs, *mine], default=-1)  # fresh ids: above every id of this kind of row
        new = set(mine) - set(known)
        assert set(mapping) <= new
        for old in new:
            if old in theirs and old not in mapping:  # kept: the parent's new row of that id is the same row
                if kind == "v":
                    assert (child.verts[old], child.vprop[old]) == (parent.verts[old], parent.vprop[old])
                else:
                    row = tuple(vmap.get(v, v) for v in child.cells[old])
                    assert (canonical(row), child.cprop[old]) == (canonical(parent.cells[old]), parent.cprop[old])
            to = mapping.get(old, old)
            assert to == old or to > top or (to in theirs and to not in known)
            if to != old and to in theirs:  # taken over by the parent's new row: only when it is the same row
                if kind == "v":
                    assert (child.verts[old], child.vprop[old]) == (parent.verts[to], parent.vprop[to])
                else:
                    row = tuple(vmap.get(v, v) for v in child.cells[old])
                    assert (canonical(row), child.cprop[old]) == (canonical(parent.cells[to]), parent.cprop[to])
        assert len(set(mapping.values())) == len(mapping)


def expected_merge(base: Rows, parent: Rows, child: Rows, merge: MeshMerge, solution: str) -> Rows:
    """Each element from the side its region says: conflicts from ``solution``, child-only regions from the child."""
    result = parent.copy()
    for region in merge.regions:
        # an automatic region: the side that changed it (both alike: the parent's, which is the same)
        taken = solution if region.conflict else ("child" if region.sides == "child" else "parent")
        source = {"parent": parent, "child": child, "base": base}[taken]
        for v in region.vertex_ids.tolist():
            result.verts.pop(v, None), result.vprop.pop(v, None)
            if v in source.verts:
                result.verts[v], result.vprop[v] = source.verts[v], source.vprop[v]
        for c in region.cell_ids.tolist():
            result.cells.pop(c, None), result.cprop.pop(c, None)
            if c in source.cells:
                result.cells[c], result.cprop[c] = source.cells[c], source.cprop[c]
    return result


# ---------------------------------------------------------------- disjoint edits: exactly the union


@st.composite
def disjoint_edits(draw: st.DrawFn) -> tuple[Rows, Rows, Rows]:
    base, column = draw(curved_grid(min_columns=8))
    split = draw(st.integers(1, max(column.values()) - 5))
    parent, child = base.copy(), base.copy()
    edit(draw, parent, {v for v, c in column.items() if c <= split}, draw(st.integers(1, 6)))
    edit(draw, child, {v for v, c in column.items() if c >= split + 3}, draw(st.integers(1, 6)))
    return base, parent, child


@PROPERTY
@given(disjoint_edits())
def test_disjoint_edits_merge_into_exactly_the_union(case: tuple[Rows, Rows, Rows]) -> None:
    base, parent, child = case
    merge = three_way_merge(base.state(), parent.state(), child.state())
    assert merge.conflicts == ()
    assert merge.merged is not None and merge.merged.discards == ()
    check_renumbering(base, parent, child, merge)
    mapped = renumbered_child(child, merge)
    # the union by hand: the parent, with every row the child changed taken from the child
    expected = parent.copy()
    for v in set(base.verts) | set(mapped.verts):
        if not same_vertex(base, mapped, v):
            expected.verts.pop(v, None), expected.vprop.pop(v, None)
            if v in mapped.verts:
                expected.verts[v], expected.vprop[v] = mapped.verts[v], mapped.vprop[v]
    for c in set(base.cells) | set(mapped.cells):
        if not same_cell(base, mapped, c):
            expected.cells.pop(c, None), expected.cprop.pop(c, None)
            if c in mapped.cells:
                expected.cells[c], expected.cprop[c] = mapped.cells[c], mapped.cprop[c]
    assert_same_rows(merge.merged.state, expected)
    # the cells as sets of coordinates: what a reader of the merged surface sees
    got = merge.merged.state.to_mesh()
    assert {frozenset(map(tuple, got.vertices[t])) for t in got.cells} == {
        frozenset(expected.verts[v] for v in row) for row in expected.cells.values()
    }


def test_two_ends_of_one_curved_fault_edited_in_two_versions_merge_both() -> None:
    # the story on a fault-like surface of 60 x 20 vertices bent on a cylinder
    surface = tgsis.Surface(*_cylinder(60, 20), vertex_properties={"throw": np.linspace(0, 1, 1200)})
    base = MeshState.from_mesh(surface, name=NAME)
    north, south = np.arange(0, 100), np.arange(1100, 1200)
    p_xyz, c_xyz = surface.vertices.copy(), surface.vertices.copy()
    p_xyz[north] += [0.0, 0.0, 2.5]
    c_xyz[south] *= 1.01
    parent = MeshState.from_mesh(tgsis.Surface(p_xyz, surface.cells, vertex_properties=surface.vertex_properties))
    child = MeshState.from_mesh(tgsis.Surface(c_xyz, surface.cells, vertex_properties=surface.vertex_properties))
    merge = three_way_merge(base, parent, child)
    assert [r.sides for r in merge.regions] == ["parent", "child"] and not merge.conflicts
    assert merge.merged is not None
    expected = surface.vertices.copy()
    expected[north], expected[south] = p_xyz[north], c_xyz[south]
    assert np.array_equal(merge.merged.state.vertices.view(np.int64), expected.view(np.int64))
    assert np.array_equal(merge.merged.state.cells, surface.cells)
    region = merge.regions[0]
    assert region.parent_displacement == pytest.approx(2.5)
    assert np.array_equal(region.parent_vertex_ids, north) and region.child_vertex_ids.size == 0
    # the box of the region's vertices and of its cells' corners, in the three states
    corners = np.union1d(region.vertex_ids, surface.cells[region.cell_ids].ravel())
    xyz = np.concatenate([surface.vertices[corners], p_xyz[corners]])
    assert np.array_equal(region.bounds, [xyz.min(axis=0), xyz.max(axis=0)])


def _cylinder(nu: int, nv: int) -> tuple[np.ndarray, np.ndarray]:
    u, v = np.meshgrid(np.linspace(0, 1.2, nu), np.linspace(0, 900, nv), indexing="ij")
    vertices = np.stack([1000 * np.sin(u).ravel(), v.ravel(), 1000 * np.cos(u).ravel()], axis=1)
    idx = np.arange(nu * nv).reshape(nu, nv)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[1:, :-1].ravel(), idx[:-1, 1:].ravel(), idx[1:, 1:].ravel()
    return vertices, np.concatenate([np.stack([a, b, d], 1), np.stack([a, d, c], 1)])


# ---------------------------------------------------------------- any edits: the regions of the rule


@st.composite
def any_edits(draw: st.DrawFn) -> tuple[Rows, Rows, Rows]:
    k = draw(st.sampled_from([1, 2, 3, 3, 4]))
    base = draw(curved_grid())[0] if k == 3 and draw(st.booleans()) else draw(random_rows(k))
    parent, child = base.copy(), base.copy()
    edit(draw, parent, None, draw(st.integers(0, 4)))
    edit(draw, child, None, draw(st.integers(0, 4)))
    same = draw(st.integers(0, 3))  # the same move of the first vertices on both sides too
    for side in (parent, child):
        for v in sorted(set(parent.verts) & set(child.verts))[:same]:
            side.verts[v] = (side.verts[v][0], side.verts[v][1], side.verts[v][2] + 7.0)
    return base, parent, child


@PROPERTY
@given(any_edits())
def test_regions_and_conflicts_are_those_of_the_rule(case: tuple[Rows, Rows, Rows]) -> None:
    base, parent, child = case
    merge = three_way_merge(base.state(), parent.state(), child.state())
    check_renumbering(base, parent, child, merge)
    mapped = renumbered_child(child, merge)
    got, expected = regions_of(merge), reference_regions(base, parent, mapped)
    assert len(got) == len(expected) and set(got) == set(expected)
    for region in merge.regions:  # each side's edit within the region
        for side, vids, cids in (
            (parent, region.parent_vertex_ids, region.parent_cell_ids),
            (mapped, region.child_vertex_ids, region.child_cell_ids),
        ):
            assert set(vids.tolist()) == {v for v in region.vertex_ids.tolist() if not same_vertex(base, side, v)}
            assert set(cids.tolist()) == {c for c in region.cell_ids.tolist() if not same_cell(base, side, c)}


@PROPERTY
@given(any_edits(), st.sampled_from(["parent", "child", "base"]))
def test_every_solution_gives_the_stated_mesh_and_says_what_it_discards(
    case: tuple[Rows, Rows, Rows], solution: Literal["parent", "child", "base"]
) -> None:
    base, parent, child = case
    merge = three_way_merge(base.state(), parent.state(), child.state())
    mapped = renumbered_child(child, merge)
    resolved = apply_solutions(merge, {r.index: solution for r in merge.conflicts})
    expected = expected_merge(base, parent, mapped, merge, solution)
    assert_same_rows(resolved.state, expected)
    if not merge.conflicts:
        assert merge.merged is not None
        assert_same_rows(merge.merged.state, expected)
    # what is discarded: per conflict and side, the side's changed rows the result holds otherwise
    found = {(d.region, d.side): d for d in resolved.discards}
    for region in merge.conflicts:
        for name, side, vids, cids in (
            ("parent", parent, region.parent_vertex_ids, region.parent_cell_ids),
            ("child", mapped, region.child_vertex_ids, region.child_cell_ids),
        ):
            lost_v = [v for v in vids.tolist() if not same_vertex(side, expected, v)]
            lost_c = [c for c in cids.tolist() if not same_cell(side, expected, c)]
            moved = [
                float(np.linalg.norm(np.subtract(side.verts[v], expected.verts[v])))
                for v in lost_v
                if v in side.verts and v in expected.verts
            ]
            if lost_v or lost_c:
                d = found.pop((region.index, name))
                assert (d.solution, d.vertices, d.cells) == (solution, len(lost_v), len(lost_c))
                assert d.max_displacement == pytest.approx(max(moved, default=0.0))
    assert found == {}


@PROPERTY
@given(any_edits())
def test_the_order_of_the_sides_changes_only_the_numbering(case: tuple[Rows, Rows, Rows]) -> None:
    base, parent, child = case
    one = three_way_merge(base.state(), parent.state(), child.state())
    two = three_way_merge(base.state(), child.state(), parent.state())
    assert len(one.regions) == len(two.regions) and len(one.conflicts) == len(two.conflicts)
    # the regions over base ids (new ids are numbered by whoever is the parent)
    known_v, known_c = set(base.verts), set(base.cells)
    assert sorted(
        (sorted(set(r.vertex_ids.tolist()) & known_v), sorted(set(r.cell_ids.tolist()) & known_c), r.conflict)
        for r in one.regions
    ) == sorted(
        (sorted(set(r.vertex_ids.tolist()) & known_v), sorted(set(r.cell_ids.tolist()) & known_c), r.conflict)
        for r in two.regions
    )
    if one.merged is not None:
        assert two.merged is not None
        assert _geometry(one.merged.state) == _geometry(two.merged.state)


def _geometry(state: MeshState) -> tuple[object, ...]:
    """The mesh without its ids: vertex rows and cells (by their vertices' rows, as oriented cells) as multisets."""
    vrow = {
        int(i): (bits(xyz), float(p))
        for i, xyz, p in zip(state.vertex_ids, state.vertices, state.vertex_properties["porosity"])
    }
    cells = sorted(
        (_oriented([vrow[int(v)] for v in row]), float(p))
        for row, p in zip(state.cells, state.cell_properties["facies"])
    )
    return tuple(sorted(vrow.values())), tuple(cells)


def _oriented(corners: list[object]) -> tuple[object, ...]:
    """An oriented cell by its corners' values: the rotation of the list starting with the smallest (even shifts)."""
    k = len(corners)
    if k < 3:
        return tuple(corners)
    order = sorted(range(k), key=lambda i: repr(corners[i]))
    parity = sum(1 for i in range(k) for j in range(i + 1, k) if order[i] > order[j]) % 2
    return (tuple(sorted(corners, key=repr)), parity)


@PROPERTY
@given(st.data())
def test_identical_edits_on_both_sides_are_no_conflict(data: st.DataObject) -> None:
    base, column = data.draw(curved_grid())
    parent = base.copy()
    edit(data.draw, parent, None, data.draw(st.integers(1, 6)))
    child = parent.copy()  # the same rows, the same new ids
    merge = three_way_merge(base.state(), parent.state(), child.state())
    assert merge.conflicts == () and merge.merged is not None
    assert_same_rows(merge.merged.state, parent)
    assert {r.sides for r in merge.regions} <= {"both"}
    assert len(merge.child_vertex_renumbering) == 0 and len(merge.child_cell_renumbering) == 0


def test_the_same_new_vertex_under_another_id_is_the_same_edit() -> None:
    base, _ = _small_grid()
    parent, child = base.copy(), base.copy()
    child.new_id()  # the child handed out an id before: its new vertex gets another id than the parent's
    for side in (parent, child):
        x = side.new_id()
        side.verts[x], side.vprop[x] = (9.0, 9.0, 9.0), 1.0
        side.cells[side.new_id()] = (x, 0, 1)
        side.cprop[max(side.cells)] = 0.0
    merge = three_way_merge(base.state(), parent.state(), child.state())
    assert merge.conflicts == () and merge.merged is not None
    assert_same_rows(merge.merged.state, parent)
    assert merge.child_vertex_renumbering.tolist() == [[max(child.verts), max(parent.verts)]]


def test_the_same_new_id_meaning_two_things_is_renumbered_and_both_are_kept() -> None:
    base, column = _small_grid(columns=10)
    parent, child = base.copy(), base.copy()
    for side, v, dz in ((parent, 0, 1.0), (child, 18, -1.0)):  # far apart: columns 0 and 9
        x = side.new_id()
        side.verts[x], side.vprop[x] = (side.verts[v][0], side.verts[v][1] + 0.5, dz), 2.0
        side.cells[side.new_id()] = (x, v, v + 1)
        side.cprop[max(side.cells)] = 0.0
    assert max(parent.verts) == max(child.verts)
    merge = three_way_merge(base.state(), parent.state(), child.state())
    assert not merge.conflicts and merge.merged is not None
    ((old_v, new_v),) = merge.child_vertex_renumbering.tolist()
    ((old_c, new_c),) = merge.child_cell_renumbering.tolist()
    assert (old_v, new_v) == (max(child.verts), max([*parent.verts, *child.verts]) + 1)
    assert (old_c, new_c) == (max(child.cells), max([*parent.cells, *child.cells]) + 1)
    state = merge.merged.state
    assert state.n_vertices == len(base.verts) + 2 and state.n_cells == len(base.cells) + 2
    row = state.cells[state.cell_ids == new_c][0]
    assert row.tolist() == [new_v, 18, 19]


def _small_grid(columns: int = 4, rows: int = 2) -> tuple[Rows, dict[int, int]]:
    verts = {
        i * rows + j: (math.sin(0.3 * i), float(j), math.cos(0.3 * i)) for i in range(columns) for j in range(rows)
    }
    cells: dict[int, tuple[int, ...]] = {}
    for i in range(columns - 1):
        a, b, c, d = i * rows, (i + 1) * rows, i * rows + 1, (i + 1) * rows + 1
        cells[2 * i], cells[2 * i + 1] = (a, b, d), (a, d, c)
    base = Rows(3, verts, {v: 0.0 for v in verts}, cells, {c: 0.0 for c in cells})
    return base, {v: v // rows for v in verts}


# ---------------------------------------------------------------- solutions and refusals


def _conflict_on_one_edge() -> tuple[Rows, Rows, Rows, MeshMerge]:
    """Both sides add a triangle on the same boundary edge (0, 2) of the grid, each with a new vertex."""
    base, _ = _small_grid()
    parent, child = base.copy(), base.copy()
    for side, y in ((parent, -1.0), (child, -2.0)):
        x = side.new_id()
        side.verts[x], side.vprop[x] = (0.1, y, 1.0), 0.0
        side.cells[side.new_id()] = (2, 0, x)
        side.cprop[max(side.cells)] = 0.0
    return base, parent, child, three_way_merge(base.state(), parent.state(), child.state())


def test_triangles_added_on_one_edge_by_both_sides_are_a_conflict_region() -> None:
    base, parent, child, merge = _conflict_on_one_edge()
    (region,) = merge.conflicts
    new_p, new_c = max(parent.cells), int(merge.child_cell_renumbering[0, 1])
    assert set(region.parent_cell_ids.tolist()) == {new_p} and set(region.child_cell_ids.tolist()) == {new_c}
    assert {0, 2} <= set(region.vertex_ids.tolist())
    with pytest.raises(tgsis.UnsolvedConflictsError, match=f"{NAME}: regions 0 changed on both sides"):
        apply_solutions(merge, {})
    with pytest.raises(tgsis.UnsolvedConflictsError):
        merge.resolve({})


def test_a_manual_mesh_keeping_both_triangles_on_one_edge_is_refused_as_non_manifold() -> None:
    base, parent, child, merge = _conflict_on_one_edge()
    (region,) = merge.conflicts
    both = rows_of(merge.parent)
    both.verts.update(rows_of(merge.child).verts), both.vprop.update(rows_of(merge.child).vprop)
    both.cells.update(rows_of(merge.child).cells), both.cprop.update(rows_of(merge.child).cprop)
    # the base's triangle (0, 1, 3)... on edge (0, 2): (0, 3, 2) and the two new ones: three triangles on it
    with pytest.raises(
        tgsis.InvalidMergeError,
        match=rf"{NAME}: the merge would make non-manifold edges .* vertex ids \(0, 2\), cells 0, ",
    ) as caught:
        apply_solutions(merge, {region.index: both.state()})
    assert str(max(parent.cells)) in str(caught.value)
    # the same manual mesh without the child's triangle but with its vertex leaves that vertex without cells
    one = both.copy()
    new_v, new_c = int(merge.child_vertex_renumbering[0, 1]), int(merge.child_cell_renumbering[0, 1])
    del one.cells[new_c], one.cprop[new_c]
    with pytest.raises(tgsis.InvalidMergeError, match=rf"would leave vertices {new_v} without triangles"):
        apply_solutions(merge, {region.index: one.state()})
    # without both it is a solution, which says what it discards of the child's edit
    del one.verts[new_v], one.vprop[new_v]
    resolved = apply_solutions(merge, {region.index: one.state()})
    assert [(d.solution, d.side, d.vertices, d.cells) for d in resolved.discards] == [("manual", "child", 1, 1)]
    assert_same_rows(resolved.state, rows_of(merge.parent))


def test_a_vertex_one_side_removes_and_the_others_new_cell_uses_is_a_conflict_and_never_dangles() -> None:
    base, _ = _small_grid(columns=5)
    parent, child = base.copy(), base.copy()
    parent.remove_vertex(4)
    x = child.new_id()
    child.verts[x], child.vprop[x] = (0.5, 0.5, 3.0), 0.0
    child.cells[child.new_id()] = (4, x, 6)
    child.cprop[max(child.cells)] = 0.0
    merge = three_way_merge(base.state(), parent.state(), child.state())
    (region,) = merge.conflicts
    assert 4 in region.parent_vertex_ids and 4 in region.vertex_ids
    new_c = int(merge.child_cell_renumbering[0, 1]) if len(merge.child_cell_renumbering) else max(child.cells)
    assert new_c in region.child_cell_ids
    for solution in ("parent", "child", "base"):
        apply_solutions(merge, {region.index: solution})  # each side's rows are a valid mesh
    # a manual mesh that keeps the child's new cell without vertex 4 is refused, naming both
    manual = rows_of(merge.parent)
    manual.cells[new_c], manual.cprop[new_c] = rows_of(merge.child).cells[new_c], 0.0
    xv = rows_of(merge.child).cells[new_c][1]
    manual.verts[xv], manual.vprop[xv] = rows_of(merge.child).verts[xv], 0.0
    with pytest.raises(tgsis.InvalidGeometryError, match="use vertex ids 4 that the mesh does not have"):
        manual.state()  # a state is checked on its own first
    merged = MeshState(
        3,
        np.array(sorted(manual.verts)),
        np.array([manual.verts[v] for v in sorted(manual.verts)]),
        np.array(sorted(set(manual.cells) - {new_c})),
        np.array([manual.cells[c] for c in sorted(set(manual.cells) - {new_c})]),
        {"porosity": np.zeros(len(manual.verts))},
        {"facies": np.zeros(len(manual.cells) - 1)},
        NAME,
    )
    # the child's new vertex kept without its cell: no side has it without a cell
    with pytest.raises(tgsis.InvalidMergeError, match=rf"{NAME}: the merge would leave vertices {xv} without"):
        apply_solutions(merge, {region.index: merged})


def test_a_manual_mesh_with_a_duplicated_cell_is_refused() -> None:
    base, parent, child, merge = _conflict_on_one_edge()
    (region,) = merge.conflicts
    manual = rows_of(merge.parent)
    twin = manual.new_id() + 1000
    first = base.cells[0]
    manual.cells[twin], manual.cprop[twin] = (first[1], first[2], first[0]), 0.0  # cell 0 again, another row
    with pytest.raises(
        tgsis.InvalidMergeError, match=rf"{NAME}: the merge would make duplicated triangles .*cells 0, {twin}"
    ):
        apply_solutions(merge, {region.index: manual.state()})


def test_solutions_are_only_for_conflicts_and_a_manual_mesh_stays_in_its_region() -> None:
    base, column = _small_grid(columns=12)
    parent, child = base.copy(), base.copy()
    parent.verts[0] = (0.0, 0.0, 5.0)
    child.verts[0] = (0.0, 0.0, 6.0)
    child.verts[22] = (1.0, 1.0, 1.0)  # far away: an automatic region of the child
    merge = three_way_merge(base.state(), parent.state(), child.state())
    assert [r.sides for r in merge.regions] == ["both", "child"] and merge.merged is None
    with pytest.raises(tgsis.InvalidInputError, match="region 1 is no conflict"):
        apply_solutions(merge, {0: "parent", 1: "parent"})  # would drop the child's edit outside the conflict
    with pytest.raises(tgsis.InvalidInputError, match="region 5 is not a region"):
        apply_solutions(merge, {0: "parent", 5: "child"})
    with pytest.raises(tgsis.InvalidInputError, match="unknown solution 'average'"):
        apply_solutions(merge, {0: "average"})  # type: ignore[dict-item]
    outside = parent.copy()
    outside.verts[10] = (0.0, 0.0, 0.0)
    with pytest.raises(tgsis.InvalidInputError, match="changes rows outside the region: vertices 10"):
        apply_solutions(merge, {0: outside.state()})
    manual = parent.copy()
    manual.verts[0] = (0.0, 0.0, 5.5)  # the middle of the two: what `average` will hand in
    with pytest.raises(tgsis.InvalidInputError, match="changes rows outside the region: vertices 22, cells none"):
        apply_solutions(merge, {0: manual.state()})  # the parent's whole object would undo the child's vertex 22
    manual.verts[22] = child.verts[22]
    resolved = apply_solutions(merge, {0: manual.state()})
    assert resolved.state.vertices[0].tolist() == [0.0, 0.0, 5.5]
    assert resolved.state.vertices[22].tolist() == [1.0, 1.0, 1.0]  # the child's other edit is kept
    assert sorted((d.side, d.vertices, d.max_displacement) for d in resolved.discards) == [
        ("child", 1, 0.5),
        ("parent", 1, 0.5),
    ]


def test_states_that_cannot_be_merged_are_refused() -> None:
    base, _ = _small_grid()
    state = base.state()
    a = np.asarray
    lines = MeshState(
        2,
        a([0, 1]),
        a([[0, 0, 0], [1, 1, 1.0]]),
        a([0]),
        a([[0, 1]]),
        {"porosity": a([0, 0])},
        {"facies": a([0])},
        NAME,
    )
    with pytest.raises(tgsis.InvalidGeometryError, match="cannot merge cells of 3 and 2 vertices"):
        three_way_merge(state, state, lines)
    other = MeshState(3, state.vertex_ids, state.vertices, state.cell_ids, state.cells, {}, {}, NAME)
    with pytest.raises(tgsis.InvalidPropertyError, match="vertex properties differ"):
        three_way_merge(state, other, state)
    with pytest.raises(tgsis.InvalidGeometryError, match="vertex ids 1 are given twice"):
        MeshState(1, a([1, 1]), a([[0, 0, 0], [1, 1, 1.0]]), a([], dtype=np.int64), a([], dtype=np.int64))
    with pytest.raises(tgsis.InvalidGeometryError, match="points 3 use vertex ids 9"):
        MeshState(1, a([1, 2]), a([[0, 0, 0], [1, 1, 1.0]]), a([3]), a([[9]]))


def test_a_mesh_state_round_trips_a_mesh_and_sorts_rows_by_id() -> None:
    surface = tgsis.Surface(*_cylinder(4, 3), vertex_properties={"p": np.arange(12.0)})
    state = MeshState.from_mesh(surface, vertex_ids=np.arange(12)[::-1] * 5, cell_ids=np.arange(12)[::-1] + 3)
    assert np.all(np.diff(state.vertex_ids) > 0) and np.all(np.diff(state.cell_ids) > 0)
    assert state.vertex_properties["p"].tolist() == list(np.arange(12.0)[::-1])
    back = state.to_mesh()
    assert {frozenset(map(tuple, back.vertices[t])) for t in back.cells} == {
        frozenset(map(tuple, surface.vertices[t])) for t in surface.cells
    }


def test_a_manual_mesh_removing_a_vertex_that_cells_outside_its_region_use_is_refused() -> None:
    base, _ = _small_grid()
    parent, child = base.copy(), base.copy()
    del parent.cells[0], parent.cprop[0]  # the triangle (0, 2, 3): its corners join the parent's region
    child.verts[0] = (0.0, 0.0, 4.0)  # the cells around vertex 0 join the child's
    merge = three_way_merge(base.state(), parent.state(), child.state())
    (region,) = merge.conflicts
    assert set(region.vertex_ids.tolist()) == {0, 2, 3} and set(region.cell_ids.tolist()) == {0, 1}
    manual = parent.copy()
    manual.remove_vertex(3)  # and its cells: 1 of the region, 3 outside it (which the manual mesh leaves out)
    manual.cells, manual.cprop = {}, {}
    with pytest.raises(tgsis.InvalidMergeError, match=rf"{NAME}: the merge would keep triangles 3 on vertices 3 that"):
        apply_solutions(merge, {region.index: manual.state()})


def test_the_same_answers_when_ids_are_looked_up_through_tables() -> None:
    # large meshes look ids up through a table of positions (small ones by binary search): both must agree
    with mock.patch.object(tgsis.merge3, "_TABLE_FROM", 1):
        test_disjoint_edits_merge_into_exactly_the_union()
        test_regions_and_conflicts_are_those_of_the_rule()
        test_every_solution_gives_the_stated_mesh_and_says_what_it_discards()


def test_values_are_compared_as_numbers_nan_equal_nan_and_vectors_by_component() -> None:
    surface = tgsis.Surface(*_cylinder(6, 4))
    n = surface.n_vertices
    dip = np.zeros((n, 2))
    dip[3] = np.nan  # a NULL of the database, on every side: no change
    base = MeshState.from_mesh(
        tgsis.Surface(surface.vertices, surface.cells, vertex_properties={"dip": dip}), name=NAME
    )
    vertices = surface.vertices.copy()
    vertices[0, 0] = -0.0  # the same number as 0.0: not moved
    assert surface.vertices[0, 0] == 0.0
    parent_dip = dip.copy()
    parent_dip[20, 1] = 7.0  # one component of a vector changed
    child_dip = dip.copy()
    child_dip[5, 0] = np.nan  # a value made NULL
    parent = MeshState.from_mesh(tgsis.Surface(vertices, surface.cells, vertex_properties={"dip": parent_dip}))
    child = MeshState.from_mesh(tgsis.Surface(surface.vertices, surface.cells, vertex_properties={"dip": child_dip}))
    merge = three_way_merge(base, parent, child)
    assert [(r.sides, r.vertex_ids.tolist(), r.cell_ids.tolist()) for r in merge.regions] == [
        ("child", [5], []),
        ("parent", [20], []),
    ]
    assert merge.merged is not None
    got = merge.merged.state.vertex_properties["dip"]
    assert got[20, 1] == 7.0 and np.isnan(got[5, 0]) and np.isnan(got[3]).all()


def _strip() -> tuple[np.ndarray, np.ndarray]:
    """Four triangles on six vertices: a strip along x."""
    vertices = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0], [2, 0, 0], [2, 1, 0]], dtype=np.float64)
    return vertices, np.array([[0, 1, 2], [1, 3, 2], [1, 4, 3], [4, 5, 3]], dtype=np.int64)


def test_an_integer_column_read_as_float_on_one_side_keeps_its_nulls_and_values() -> None:
    # the database step reads an integer column as int64 where every row has a value and as float64 with NaN
    # where one row has none: the merged values must not be cast back to the parent's integers (NaN -> -2**63)
    vertices, cells = _strip()
    facies = np.arange(6, dtype=np.int64)
    base = MeshState(3, np.arange(6), vertices, np.arange(4), cells, {"facies": facies}, name=NAME)
    parent = MeshState(3, np.arange(6), vertices, np.arange(4), cells, {"facies": facies.copy()}, name=NAME)
    child_facies = np.array([0, 1, 2, 3, 4, 5, np.nan, 2.5])
    child_facies[5] = 7.5  # a changed value that is not an integer
    child = MeshState(
        3,
        np.arange(8),
        np.vstack([vertices, [[3, 0, 0], [3, 1, 0]]]),
        np.arange(6),
        np.vstack([cells, [[4, 6, 5], [6, 7, 5]]]),
        {"facies": child_facies},
        name=NAME,
    )
    merge = three_way_merge(base, parent, child)
    assert merge.merged is not None
    got = merge.merged.state.vertex_properties["facies"]
    assert got[5] == 7.5 and np.isnan(got[6]) and got[7] == 2.5
    assert got[:5].tolist() == [0, 1, 2, 3, 4]


def test_a_conflict_with_vector_properties_is_solved_and_its_discards_counted() -> None:
    # a region where one side changed no vertex (or a manual mesh with nothing outside its region) compares
    # empty selections of a vector property: that must not fail
    vertices, cells = _strip()
    dip = {"dip": np.zeros((6, 2))}
    base = MeshState(3, np.arange(6), vertices, np.arange(4), cells, dip, name=NAME)
    flipped = cells.copy()
    flipped[0] = [0, 2, 1]  # the parent turns triangle 0 over
    parent = MeshState(3, np.arange(6), vertices, np.arange(4), flipped, dip, name=NAME)
    moved = vertices.copy()
    moved[0, 2] = 1.0  # the child lifts one of its corners
    child = MeshState(3, np.arange(6), moved, np.arange(4), cells, dip, name=NAME)
    merge = three_way_merge(base, parent, child)
    assert [r.index for r in merge.conflicts] == [0]
    resolved = apply_solutions(merge, {0: "child"})
    assert [(d.side, d.vertices, d.cells) for d in resolved.discards] == [("parent", 0, 1)]
    region = merge.regions[0]
    manual = MeshState(
        3,
        region.vertex_ids,
        moved[region.vertex_ids],
        region.cell_ids,
        flipped[region.cell_ids],
        {"dip": np.zeros((len(region.vertex_ids), 2))},
        name=NAME,
    )
    both = apply_solutions(merge, {0: manual})
    assert both.state.cells[0].tolist() == [0, 2, 1] and both.state.vertices[0, 2] == 1.0


def test_the_same_point_added_on_both_sides_is_one_point_when_a_column_is_int_on_one_side_float_on_the_other() -> None:
    # both sides add point 6 at the same place with refid 3; the parent's column reads as int64, the child's
    # as float64 (a NULL elsewhere in it): the same edit made twice, not a second point on top of the first
    xyz = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0], [3, 0, 0], [4, 0, 0], [5, 0, 0]], dtype=np.float64)
    ids = np.arange(6)
    refid = np.full(6, -1, dtype=np.int64)
    base = MeshState(1, ids, xyz, ids, ids[:, None], {"refid": refid}, name=NAME)
    more = np.vstack([xyz, [[9, 9, 9]]])
    parent = MeshState(1, np.arange(7), more, np.arange(7), np.arange(7)[:, None], {"refid": np.append(refid, 3)})
    child = MeshState(
        1, np.arange(7), more, np.arange(7), np.arange(7)[:, None], {"refid": np.append(refid, 3).astype(np.float64)}
    )
    merge = three_way_merge(base, parent, child)
    assert merge.child_vertex_renumbering.size == 0 and merge.child_cell_renumbering.size == 0
    assert merge.merged is not None
    assert merge.merged.state.vertex_ids.tolist() == list(range(7))
    assert merge.merged.state.n_cells == 7


def test_one_whole_manual_mesh_solves_two_conflicting_regions() -> None:
    # `average` hands in the whole object (the averaged regions attached to the unchanged rest): the same mesh
    # given for both conflicting regions must be accepted, each region taking its rows from it
    base, column = _small_grid(columns=12)
    parent, child = base.copy(), base.copy()
    parent.verts[0], child.verts[0] = (0.0, 0.0, 5.0), (0.0, 0.0, 6.0)
    far = max(v for v, c in column.items() if c == 11)
    parent.verts[far], child.verts[far] = (11.0, 1.0, 2.0), (11.0, 1.0, 3.0)
    merge = three_way_merge(base.state(), parent.state(), child.state())
    assert [r.sides for r in merge.conflicts] == ["both", "both"]
    whole = parent.copy()
    whole.verts[0], whole.verts[far] = (0.0, 0.0, 5.5), (11.0, 1.0, 2.5)
    resolved = apply_solutions(merge, {r.index: whole.state() for r in merge.conflicts})
    assert_same_rows(resolved.state, whole)
    assert sorted((d.region, d.side, d.vertices) for d in resolved.discards) == [
        (0, "child", 1),
        (0, "parent", 1),
        (1, "child", 1),
        (1, "parent", 1),
    ]


def test_an_atom_of_a_renumbered_new_vertex_follows_it() -> None:
    # GOCAD atoms come as the vertex property refid (docs/merge.md): a vertex id, not a value. Both sides add
    # vertex 6, meaning two things; the child's 6 is renumbered, and the child's atom 7 of its 6 must follow it
    # rather than point at the parent's vertex 6
    xyz = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0], [3, 0, 0], [4, 0, 0], [5, 0, 0]], dtype=np.float64)
    segments = np.array([[0, 1], [1, 2], [2, 3], [3, 4], [4, 5]])
    none = np.full(6, -1, dtype=np.int64)
    base = MeshState(2, np.arange(6), xyz, np.arange(5), segments, {"refid": none}, name=NAME)
    parent = MeshState(
        2, np.arange(7), np.vstack([xyz, [[6, 0, 0]]]), np.arange(6), np.vstack([segments, [[5, 6]]]),
        {"refid": np.append(none, -1)}, name=NAME,
    )  # fmt: skip
    child = MeshState(
        2, np.arange(8), np.vstack([xyz, [[-1, 0, 0], [-1, 0, 0]]]), np.arange(6), np.vstack([segments, [[6, 0]]]),
        {"refid": np.append(none, [-1, 6])}, name=NAME,
    )  # fmt: skip
    merge = three_way_merge(base, parent, child)
    assert merge.child_vertex_renumbering.tolist() == [[6, 8]]
    assert merge.merged is not None
    state = merge.merged.state
    refid = dict(zip(state.vertex_ids.tolist(), state.vertex_properties["refid"].tolist()))
    assert refid[7] == 8 and state.vertices[state.vertex_ids == 8].tolist() == [[-1.0, 0.0, 0.0]]


def test_an_atom_of_a_vertex_the_other_side_removes_is_refused() -> None:
    # the parent removes vertex 5; the child, far from it, adds an atom of 5 (refid 5): merged, the atom would
    # refer to a vertex the object no longer has
    xyz = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0], [3, 0, 0], [4, 0, 0], [5, 0, 0]], dtype=np.float64)
    segments = np.array([[0, 1], [1, 2], [2, 3], [3, 4], [4, 5]])
    none = np.full(6, -1, dtype=np.int64)
    base = MeshState(2, np.arange(6), xyz, np.arange(5), segments, {"refid": none}, name=NAME)
    parent = MeshState(2, np.arange(5), xyz[:5], np.arange(4), segments[:4], {"refid": none[:5]}, name=NAME)
    child = MeshState(
        2, np.arange(7), np.vstack([xyz, [[5, 0, 0]]]), np.arange(6), np.vstack([segments, [[0, 6]]]),
        {"refid": np.append(none, 5)}, name=NAME,
    )  # fmt: skip
    with pytest.raises(tgsis.InvalidMergeError, match=rf"{NAME}: .*vertices 6, .*refer to vertices 5"):
        three_way_merge(base, parent, child)


def test_a_region_index_that_is_not_an_integer_is_refused_clearly() -> None:
    # a region index read from JSON or a command line is a string; True is no region either
    base, _ = _small_grid(columns=6)
    parent, child = base.copy(), base.copy()
    parent.verts[0], child.verts[0] = (0.0, 0.0, 5.0), (0.0, 0.0, 6.0)
    merge = three_way_merge(base.state(), parent.state(), child.state())
    assert [r.index for r in merge.conflicts] == [0]
    for index in ("0", 0.5, True):
        with pytest.raises(tgsis.InvalidInputError, match=f"region {index!r} is not a region"):
            apply_solutions(merge, {0: "parent", index: "parent"})  # type: ignore[dict-item]
    assert apply_solutions(merge, {np.int64(0): "parent"}).discards[0].side == "child"  # type: ignore[dict-item]


def test_new_ids_that_would_need_renumbering_past_int64_are_refused_by_name() -> None:
    """Both sides add a different vertex (and cell) with the largest id there is: no id is left above it."""
    top = 2**63 - 1
    base = MeshState(
        3,
        np.array([0, 1, 2]),
        np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]),
        np.array([0]),
        np.array([[0, 1, 2]]),
        {},
        {},
        "fault",
    )

    def with_vertex(z: float) -> MeshState:
        return MeshState(
            3,
            np.array([0, 1, 2, top]),
            np.vstack([base.vertices, [[1.0, 1.0, z]]]),
            np.array([0, 1]),
            np.array([[0, 1, 2], [1, top, 2]]),
            {},
            {},
            "fault",
        )

    # was: OverflowError (Python int too large to convert to C long) out of numpy
    with pytest.raises(tgsis.InvalidMergeError, match=r"fault: .*vertex .*9223372036854775807.*no id"):
        three_way_merge(base, with_vertex(1.0), with_vertex(2.0))


def test_two_manual_meshes_adding_one_new_id_differently_are_refused_not_one_silently_kept() -> None:
    # two conflicting regions, each solved by a manual mesh that adds a vertex no state has, both with id 1000
    # but at different places: the merged mesh cannot hold both, and neither may silently win
    base, column = _small_grid(columns=12)
    parent, child = base.copy(), base.copy()
    parent.verts[0], child.verts[0] = (0.0, 0.0, 5.0), (0.0, 0.0, 6.0)
    far = max(v for v, c in column.items() if c == 11)
    parent.verts[far], child.verts[far] = (11.0, 1.0, 2.0), (11.0, 1.0, 3.0)
    merge = three_way_merge(base.state(), parent.state(), child.state())
    first, second = merge.conflicts
    near_zero, near_far = parent.copy(), parent.copy()
    near_zero.verts[1000], near_zero.vprop[1000] = (0.5, -1.0, 1.0), 0.0
    near_zero.cells[2000], near_zero.cprop[2000] = (2, 0, 1000), 0.0
    near_far.verts[1000], near_far.vprop[1000] = (10.5, 2.0, 1.0), 0.0
    near_far.cells[2001], near_far.cprop[2001] = (far, far - 1, 1000), 0.0
    with pytest.raises(tgsis.InvalidMergeError, match="two vertex rows the id 1000"):
        apply_solutions(merge, {first.index: near_zero.state(), second.index: near_far.state()})
