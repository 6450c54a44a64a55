"""A three-way merge of the change and its rings equals the merge of the whole states (tgsis.merge3, no database).

``three_way_merge(..., top_ids=...)`` on the three states restricted to the
rows :func:`tgsis.merge3.change_neighbourhood` names (the changed rows, any
superset of them, and one or two rings of cells around) must give exactly what the
merge of the whole states gives: the same regions (ids, edits, boxes,
displacements bit for bit, conflicts), the same renumbering of the child's
new ids, the same refusal of an invalid merge, and a merged state whose rows
are the whole merge's rows of those ids, the rest of the whole merge being
the parent's rows, untouched. Then the solutions parent, child and base give
the same rows and discards, with one ring or two (a manual mesh may drop a
cell of the ring: docs/merge.md). This is what lets a merge read only the
change from the database.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from tests.test_merge3 import Rows, any_edits, disjoint_edits
from tgsis.errors import InvalidMergeError
from tgsis.merge3 import (
    MergeRegion,
    MeshMerge,
    MeshState,
    ResolvedMerge,
    apply_solutions,
    change_neighbourhood,
    changed_ids,
    largest_ids,
    restrict_state,
    three_way_merge,
)

PROPERTY = settings(max_examples=250, deadline=None, suppress_health_check=[HealthCheck.too_slow])


def region_key(r: MergeRegion) -> tuple[Any, ...]:
    return (
        r.index,
        r.vertex_ids.tolist(),
        r.cell_ids.tolist(),
        r.parent_vertex_ids.tolist(),
        r.parent_cell_ids.tolist(),
        r.child_vertex_ids.tolist(),
        r.child_cell_ids.tolist(),
        r.bounds.tobytes(),
        np.float64(r.parent_displacement).tobytes(),
        np.float64(r.child_displacement).tobytes(),
        r.conflict,
    )


def vertex_rows(state: MeshState) -> dict[int, tuple[Any, ...]]:
    """Per vertex id: coordinates as bits and property values as bits."""
    props = [
        np.asarray(v, dtype=np.float64).reshape(state.n_vertices, max(1, v[0].size if len(v) else 1))
        for v in state.vertex_properties.values()
    ]
    return {
        int(i): (state.vertices[n].tobytes(), *(p[n].tobytes() for p in props))
        for n, i in enumerate(state.vertex_ids.tolist())
    }


def cell_rows(state: MeshState) -> dict[int, tuple[Any, ...]]:
    """Per cell id: its vertex ids in order and property values as bits."""
    props = [
        np.asarray(v, dtype=np.float64).reshape(state.n_cells, max(1, v[0].size if len(v) else 1))
        for v in state.cell_properties.values()
    ]
    return {
        int(i): (tuple(state.cells[n].tolist()), *(p[n].tobytes() for p in props))
        for n, i in enumerate(state.cell_ids.tolist())
    }


def assert_restriction(whole: MeshState, part: MeshState, parent: MeshState) -> None:
    """``part`` holds exactly ``whole``'s rows of its ids; ``whole``'s other rows are ``parent``'s."""
    for rows in (vertex_rows, cell_rows):
        got, expected, untouched = rows(part), rows(whole), rows(parent)
        assert set(got) <= set(expected)
        assert all(got[i] == expected[i] for i in got)
        assert all(expected[i] == untouched.get(i) for i in set(expected) - set(got))


def neighbourhood(
    base: MeshState, parent: MeshState, child: MeshState, extra_v: list[int], extra_c: list[int], rings: int = 2
) -> tuple[MeshState, MeshState, MeshState]:
    (pv, pc), (cv, cc) = changed_ids(base, parent), changed_ids(base, child)
    vids, cids = change_neighbourhood(
        (base, parent, child),
        np.concatenate([pv, cv, extra_v]).astype(np.int64),
        np.concatenate([pc, cc, extra_c]),
        rings=rings,
    )
    return tuple(restrict_state(s, vids, cids) for s in (base, parent, child))  # type: ignore[return-value]


def merged_or_refusal(action: Any) -> tuple[Any, str | None]:
    try:
        return action(), None
    except InvalidMergeError as exc:
        return None, str(exc)


def assert_same_merge(case: tuple[Rows, Rows, Rows], data: st.DataObject, rings: int = 2) -> None:
    base, parent, child = (rows.state() for rows in case)
    # rows changed or not: what the database reads is any superset of the changed rows (rows rewritten alike)
    extra_v = data.draw(st.lists(st.sampled_from(base.vertex_ids.tolist()), max_size=3)) if base.n_vertices else []
    extra_c = data.draw(st.lists(st.sampled_from(base.cell_ids.tolist()), max_size=3)) if base.n_cells else []
    parts = neighbourhood(base, parent, child, extra_v, extra_c, rings)
    whole, whole_refusal = merged_or_refusal(lambda: three_way_merge(base, parent, child))
    part, part_refusal = merged_or_refusal(lambda: three_way_merge(*parts, top_ids=largest_ids(base, parent, child)))
    assert part_refusal == whole_refusal
    if whole is None:
        return
    assert isinstance(whole, MeshMerge) and isinstance(part, MeshMerge)
    assert [region_key(r) for r in part.regions] == [region_key(r) for r in whole.regions]
    assert part.child_vertex_renumbering.tolist() == whole.child_vertex_renumbering.tolist()
    assert part.child_cell_renumbering.tolist() == whole.child_cell_renumbering.tolist()
    assert (part.merged is None) == (whole.merged is None)
    if whole.merged is not None and part.merged is not None:
        assert part.merged.discards == whole.merged.discards == ()
        assert_restriction(whole.merged.state, part.merged.state, parent)
    if whole.conflicts:
        solution = data.draw(st.sampled_from(["parent", "child", "base"]))
        chosen = {r.index: solution for r in whole.conflicts}
        got, got_refusal = merged_or_refusal(lambda: apply_solutions(part, chosen))  # type: ignore[arg-type]
        expected, expected_refusal = merged_or_refusal(lambda: apply_solutions(whole, chosen))  # type: ignore[arg-type]
        assert got_refusal == expected_refusal
        if expected is not None:
            assert isinstance(got, ResolvedMerge) and isinstance(expected, ResolvedMerge)
            assert got.discards == expected.discards
            assert_restriction(expected.state, got.state, parent)


@PROPERTY
@given(any_edits(), st.data())
def test_a_merge_of_the_change_and_two_rings_is_the_merge_of_the_whole_states(
    case: tuple[Rows, Rows, Rows], data: st.DataObject
) -> None:
    assert_same_merge(case, data)


@PROPERTY
@given(any_edits(), st.data())
def test_one_ring_is_enough_for_the_regions_an_automatic_merge_and_the_side_solutions(
    case: tuple[Rows, Rows, Rows], data: st.DataObject
) -> None:
    assert_same_merge(case, data, rings=1)


@PROPERTY
@given(disjoint_edits(), st.data())
def test_disjoint_edits_of_a_curved_grid_merge_alike_from_the_change_only(
    case: tuple[Rows, Rows, Rows], data: st.DataObject
) -> None:
    assert_same_merge(case, data)


def test_a_clashing_new_id_is_renumbered_above_the_whole_states_not_the_restricted_ones() -> None:
    # 0..9 on a line and a far vertex 500; both sides add another vertex 100: the child's is renumbered above 500
    xyz = np.stack([np.arange(11.0), np.zeros(11), np.zeros(11)], axis=1)
    ids = np.array([*range(10), 500])
    base = MeshState(2, ids, xyz, np.arange(9), np.stack([ids[:9], ids[1:10]], axis=1))
    added = np.append(ids, 100)
    cells = np.concatenate([base.cells, [[0, 100]]])
    parent = MeshState(2, added, np.concatenate([xyz, [[0.0, 1.0, 0.0]]]), np.arange(10), cells)
    child = MeshState(2, added, np.concatenate([xyz, [[0.0, -1.0, 0.0]]]), np.append(np.arange(9), 10), cells)
    whole = three_way_merge(base, parent, child)
    parts = neighbourhood(base, parent, child, [], [])
    assert 500 not in parts[0].vertex_ids  # the far vertex is not read
    assert three_way_merge(*parts).child_vertex_renumbering.tolist() == [[100, 101]]  # what it would be wrongly
    part = three_way_merge(*parts, top_ids=largest_ids(base, parent, child))
    assert whole.child_vertex_renumbering.tolist() == part.child_vertex_renumbering.tolist() == [[100, 501]]
