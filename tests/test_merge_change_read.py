"""read_merge_change reads the change and its one-ring: merges of it equal merges of the three whole states.

For random edits on both sides made as SQL users make them (the edits of
tests/test_merge_states_read.py without GOCAD atoms and part runs, which are
read whole), in several revisions of each side: the states it reads must be
the whole states' rows of the ids it read, bit for bit, those ids must hold
the change and its one-ring (tgsis.merge3.change_neighbourhood, rings=1), its
largest ids must be the whole states', and three_way_merge of them (with
those ids) must give exactly the regions, renumbering and merged rows of the
merge of the whole states. Then find_conflicts and merge_version, which read
this way, record the same regions and write the same object as the
reference merge of the whole states computes.
"""

from __future__ import annotations

import re
from typing import Any
from unittest import mock

import numpy as np
import psycopg
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import tgsis
from tests.merge_data import curved_surface
from tests.test_merge3_partial import assert_restriction, region_key
from tests.test_merge_states_read import (
    _COUNTER,
    EDIT_KINDS,
    assert_identical,
    edit,
    faults,
    reference_states,
)
from tgsis.db import _merge_states, merging, regions
from tgsis.db import features as F
from tgsis.db.classes import FeatureClass
from tgsis.errors import InvalidMergeError
from tgsis.merge3 import (
    MeshState,
    apply_solutions,
    change_neighbourhood,
    changed_ids,
    largest_ids,
    restrict_state,
    three_way_merge,
)

Conn = psycopg.Connection[Any]

__all__ = ["faults"]  # the fixture, shared with tests/test_merge_states_read.py

# the edits of every kind but atoms and parts, drawn from those kinds (not filtered: Hypothesis's filter_too_much)
WITHOUT_ATOMS = st.one_of(*(kind for name, kind in EDIT_KINDS.items() if name not in ("atom", "parts")))
SIDES = st.lists(WITHOUT_ATOMS, min_size=1, max_size=6)


def change_states(conn: Conn, version: str, geoid: int) -> tuple[dict[str, MeshState], tuple[int, int]] | None:
    conn.rollback()
    conn.execute("SET TRANSACTION ISOLATION LEVEL REPEATABLE READ")
    try:
        read = _merge_states.read_merge_change(conn, version, geoid)
        return None if read is None else (read[0].states, read[1])
    finally:
        conn.rollback()


def edited(conn: Conn, fc: FeatureClass, parent_edits: list[Any], child_edits: list[Any]) -> tuple[int, str]:
    n = next(_COUNTER)
    geoid = F.insert_feature(conn, "faults", curved_surface())
    version = f"c{n}"
    tgsis.create_version(conn, version)
    conn.commit()
    edit(conn, fc, "DEFAULT", geoid, ("move", [0], 1.0))
    edit(conn, fc, version, geoid, ("move", [140], -1.0))
    for step in parent_edits:
        edit(conn, fc, "DEFAULT", geoid, step)
    for step in child_edits:
        edit(conn, fc, version, geoid, step)
    conn.commit()
    return geoid, version


@settings(
    max_examples=25,
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture],
)
@given(parent_edits=SIDES, child_edits=SIDES)
def test_the_read_of_the_change_merges_as_the_whole_states(
    conn: Conn, faults: FeatureClass, parent_edits: list[Any], child_edits: list[Any]
) -> None:
    geoid, version = edited(conn, faults, parent_edits, child_edits)
    whole = reference_states(conn, version, geoid)
    read = change_states(conn, version, geoid)
    assert read is not None
    part, top = read
    vids = np.unique(np.concatenate([s.vertex_ids for s in part.values()]))
    cids = np.unique(np.concatenate([s.cell_ids for s in part.values()]))
    for side in whole:  # the whole states' rows of the ids read, bit for bit
        assert_identical(part[side], restrict_state(whole[side], vids, cids))
    states = (whole["base"], whole["parent"], whole["child"])
    (pv, pc), (cv, cc) = changed_ids(states[0], states[1]), changed_ids(states[0], states[2])
    need_v, need_c = change_neighbourhood(states, np.concatenate([pv, cv]), np.concatenate([pc, cc]), rings=1)
    assert set(need_v.tolist()) <= set(vids.tolist())
    assert set(need_c.tolist()) <= set(cids.tolist())
    assert top == largest_ids(*states)
    expected = three_way_merge(*states)
    got = three_way_merge(part["base"], part["parent"], part["child"], top_ids=top)
    assert [region_key(r) for r in got.regions] == [region_key(r) for r in expected.regions]
    assert got.child_vertex_renumbering.tolist() == expected.child_vertex_renumbering.tolist()
    assert got.child_cell_renumbering.tolist() == expected.child_cell_renumbering.tolist()
    assert (got.merged is None) == (expected.merged is None)
    if got.merged is not None and expected.merged is not None:
        assert_restriction(expected.merged.state, got.merged.state, whole["parent"])
    for solution in ("parent", "child", "base"):  # the solutions the merge applies to what it read
        chosen = {r.index: solution for r in expected.conflicts}
        if chosen:
            try:
                want = apply_solutions(expected, chosen)  # type: ignore[arg-type]
            except InvalidMergeError as exc:
                with pytest.raises(InvalidMergeError, match=re.escape(exc.message)):
                    apply_solutions(got, chosen)  # type: ignore[arg-type]
                continue
            have = apply_solutions(got, chosen)  # type: ignore[arg-type]
            assert have.discards == want.discards
            assert_restriction(want.state, have.state, whole["parent"])


def test_an_object_with_atoms_is_read_whole(conn: Conn, faults: FeatureClass) -> None:
    geoid, version = edited(conn, faults, [("atom", [3, 9], 0)], [("move", [5], 0.5)])
    assert change_states(conn, version, geoid) is None
    whole = reference_states(conn, version, geoid)
    assert whole["parent"].vertex_properties["refid"].max() >= 0


def test_find_conflicts_and_merge_read_the_change_and_write_the_whole_merge(conn: Conn, faults: FeatureClass) -> None:
    geoid, version = edited(
        conn, faults, [("move", [3, 4], 0.5)], [("move", [120, 121], 2.0), ("vertex value", [121], 0.25)]
    )
    whole = reference_states(conn, version, geoid)
    expected = three_way_merge(whole["base"], whole["parent"], whole["child"])
    assert expected.merged is not None and not expected.conflicts
    # the reads of the whole object are not needed: refused here, the merge by region must not make them
    refused = mock.Mock(side_effect=AssertionError("read_merge_states called"))
    with (
        mock.patch.object(merging, "read_merge_states", refused),
        mock.patch.object(regions, "read_merge_states", refused),
    ):
        [conflict] = regions.find_conflicts(conn, version)
        assert [r.vertex_ids.tolist() for r in conflict.regions] == [r.vertex_ids.tolist() for r in expected.regions]
        assert [r.cell_ids.tolist() for r in conflict.regions] == [r.cell_ids.tolist() for r in expected.regions]
        conn.commit()
        merging.merge_version(conn, version)
        conn.commit()
    assert not refused.called
    merged = expected.merged.state
    with tgsis.in_version(conn, "DEFAULT"):
        rows = conn.execute(
            "SELECT vrtxid, x, y, z FROM tgsis.vrtx WHERE geoid = %s ORDER BY vrtxid", (geoid,)
        ).fetchall()
        cells = {
            tuple(r)
            for r in conn.execute(
                "SELECT trglid, vrtxid1, vrtxid2, vrtxid3 FROM tgsis.trgl WHERE geoid = %s", (geoid,)
            ).fetchall()
        }
        box = conn.execute(
            "SELECT nvrtx, ncell, cube_ll_coord(bbox, 3), cube_ur_coord(bbox, 3) FROM tgsis.geometry WHERE geoid = %s",
            (geoid,),
        ).fetchone()
    assert [r[0] for r in rows] == merged.vertex_ids.tolist()
    assert np.array(rows, dtype=np.float64)[:, 1:].tobytes() == merged.vertices.tobytes()
    assert cells == {(int(i), *map(int, c)) for i, c in zip(merged.cell_ids, merged.cells)}
    assert box is not None
    assert box[:2] == (merged.n_vertices, merged.n_cells)
    assert (box[2], box[3]) == (merged.vertices[:, 2].min(), merged.vertices[:, 2].max())
