"""The psql merge by region applies ``average`` and ``manual`` solutions (issue 39, items 3 and 5).

A region solved ``average`` or ``manual`` (from Python or the CLI, which
compute its mesh) is recorded with its rows in a form SQL reads
(``tgsis.conflict_regions.solution_*``) beside the .npz; ``SELECT
tgsis.merge_version(v)`` / ``refresh_version(v)`` then merges the object as
the Python merge does. The oracle is the Python merge, bit for bit
(tests/test_sql_merge_write.py: every stored row version, revision notes,
versions, conflicts and regions afterwards). A solution recorded with its
.npz only (before this change, or by a psql user) keeps today's refusal
(TG302 naming the Python command).
"""

from __future__ import annotations

import itertools
from typing import Any

import numpy as np
import psycopg
import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

import tgsis
from tests.merge_data import SIDE, curved_surface, make_fault, move
from tests.test_merge_average import _moved, _subdivided, _write
from tests.test_sql_merge_regions import MIDDLE, _apply, _edit, property_tables
from tests.test_sql_merge_write import _psql_state, assert_same_merge, both_merges, everything
from tgsis.merge3 import MeshState

Conn = psycopg.Connection[Any]


@pytest.fixture
def fault(conn: Conn, fault_clone: int) -> int:
    return fault_clone  # tests.merge_data.make_fault's (tests/conftest.py)


def _both_moved(conn: Conn, fault: int) -> int:
    """One conflicting region: the middle moved up in the version, down in DEFAULT; its index."""
    move(conn, "e1", fault, MIDDLE, (0.0, 0.0, 5.0))
    move(conn, "DEFAULT", fault, MIDDLE, (0.5, 0.0, -7.0))
    conn.commit()
    (conflict,) = tgsis.find_conflicts(conn, "e1")
    conn.commit()
    (region,) = [r for r in conflict.regions if r.conflict]
    return region.region


def _rows_recorded(conn: Conn, fault: int) -> list[tuple[Any, ...]]:
    rows = conn.execute(
        "SELECT region, solution, cardinality(solution_vertex_ids), cardinality(solution_cell_ids)"
        " FROM tgsis.conflict_regions WHERE versionid = tgsis.version_id('e1') AND objectkey = %s"
        " AND solution IN ('average', 'manual') ORDER BY region",
        (str(fault),),
    ).fetchall()
    conn.rollback()
    return rows


@pytest.mark.parametrize("action", ["merge", "refresh"])
def test_average_of_a_region_both_sides_moved_merges_in_psql_as_in_python(conn: Conn, fault: int, action: str) -> None:
    index = _both_moved(conn, fault)
    tgsis.resolve_region(conn, "e1", fault, index, "average")
    conn.commit()
    [(_, _, nv, _)] = _rows_recorded(conn, fault)
    assert nv and nv >= len(MIDDLE)
    assert_same_merge(conn, "e1", action)


@pytest.mark.parametrize("action", ["merge", "refresh"])
def test_average_of_differently_meshed_sides_merges_in_psql_as_in_python(conn: Conn, action: str) -> None:
    geoid = make_fault(conn)
    base = MeshState.from_mesh(curved_surface())  # as uploaded: ids 0..n-1
    _write(conn, "e1", geoid, base, _subdivided(base))  # new vertices and triangles in the version
    _write(conn, "DEFAULT", geoid, base, _moved(base))
    [conflict] = tgsis.find_conflicts(conn, "e1")
    conn.commit()
    [region] = [r for r in conflict.regions if r.conflict]
    tgsis.resolve_region(conn, "e1", geoid, region.region, "average")
    conn.commit()
    assert_same_merge(conn, "e1", action)


@pytest.mark.parametrize("action", ["merge", "refresh"])
def test_a_manual_mesh_merges_in_psql_as_in_python(conn: Conn, fault: int, action: str) -> None:
    index = _both_moved(conn, fault)
    merge = tgsis.object_merge(conn, "e1", fault)
    conn.rollback()
    side = merge.child
    xyz = side.vertices.copy()
    at = np.isin(side.vertex_ids, MIDDLE)
    xyz[at, 2] += np.linspace(0.1, 0.9, int(at.sum()))  # a hand-made shape, values of no side
    porosity = np.asarray(side.vertex_properties["porosity"], dtype=np.float64).copy()
    porosity[at] = 0.123456789
    manual = MeshState(3, side.vertex_ids, xyz, side.cell_ids, side.cells, {"porosity": porosity}, side.cell_properties)
    tgsis.resolve_region(conn, "e1", fault, index, "manual", manual)
    conn.commit()
    [(_, solution, nv, _)] = _rows_recorded(conn, fault)
    assert solution == "manual" and nv
    assert_same_merge(conn, "e1", action)


def test_after_pg_dump_and_restore_an_average_merges_in_psql_as_in_python(
    conn: Conn, fault: int, pg: Any, db_dsn: str, tmp_path: Any
) -> None:
    from tests.test_backup import _bindir_of, _restored

    index = _both_moved(conn, fault)
    tgsis.resolve_region(conn, "e1", fault, index, "average")
    conn.commit()
    with _restored(pg, _bindir_of(pg), db_dsn, "custom", tmp_path) as dsn, psycopg.connect(dsn) as restored:
        assert_same_merge(restored, "e1")


def test_a_solution_recorded_with_its_npz_only_is_refused_as_before(conn: Conn, fault: int) -> None:
    """A psql user's resolve_region with an .npz (or one recorded before the rows were stored): TG302, nothing written."""
    index = _both_moved(conn, fault)
    tgsis.resolve_region(conn, "e1", fault, index, "average")
    conn.commit()
    (mesh,) = conn.execute(
        "SELECT solution_mesh FROM tgsis.conflict_regions WHERE versionid = tgsis.version_id('e1') AND region = %s",
        (index,),
    ).fetchone()  # type: ignore[misc]
    conn.execute("SELECT tgsis.resolve_region('e1', 'feature', %s, %s, 'average', %s)", (str(fault), index, mesh))
    conn.commit()
    before = everything(conn)
    conn.commit()
    state, message, hint = _psql_state(conn, "SELECT tgsis.merge_version('e1')", ())
    assert state == "TG302", message
    assert "average" in message and "tgsis version merge" in (hint or "")
    assert everything(conn) == before
    conn.rollback()


def test_a_role_without_rights_is_refused_as_in_python_and_nothing_is_written(
    conn: Conn, fault: int, db_dsn: str
) -> None:
    from tests.roles import login_roles

    index = _both_moved(conn, fault)
    tgsis.resolve_region(conn, "e1", fault, index, "average")
    conn.commit()
    with login_roles(db_dsn, {"ed": "tgsis_editor", "rita": "tgsis_reader"}) as made:
        tgsis.grant_version(conn, "e1", "all", made.name("ed"))
        tgsis.grant_version(conn, "DEFAULT", "merge", made.name("ed"))
        conn.execute("REVOKE INSERT, UPDATE, DELETE ON public.faults FROM tgsis_editor")
        conn.commit()
        before = everything(conn)
        conn.commit()
        for role in ("rita", "ed"):
            session = made.connect(role)
            with pytest.raises(tgsis.Error) as python:
                tgsis.merge_version(session, "e1")
            session.rollback()
            state, message, _ = _psql_state(session, "SELECT tgsis.merge_version('e1')", ())
            assert state == python.value.sqlstate and state in ("42501", "TG002"), (role, message)
            assert everything(conn) == before
            conn.commit()


@pytest.mark.parametrize("solution", ["average", "manual"])
def test_psql_is_told_what_an_average_or_manual_solution_discards_as_python_says_it(
    conn: Conn, fault: int, solution: str
) -> None:
    index = _both_moved(conn, fault)
    manual = None
    if solution == "manual":  # the version's rows, one vertex of the region put back where the parent has it
        merge = tgsis.object_merge(conn, "e1", fault)
        conn.rollback()
        xyz = merge.child.vertices.copy()
        at = np.searchsorted(merge.child.vertex_ids, MIDDLE[0])
        xyz[at] = merge.parent.vertices[np.searchsorted(merge.parent.vertex_ids, MIDDLE[0])]
        manual = MeshState(
            3,
            merge.child.vertex_ids,
            xyz,
            merge.child.cell_ids,
            merge.child.cells,
            merge.child.vertex_properties,
            merge.child.cell_properties,
        )
    tgsis.resolve_region(conn, "e1", fault, index, solution, manual)
    conn.commit()
    with conn.transaction(force_rollback=True):
        (merged,) = tgsis.merge_version(conn, "e1").objects
    expected = [
        f"region {d.region}: {d.solution} discards the {d.side}'s edit there: {d.vertices} vertices, {d.cells} cells, "
        f"largest displacement {d.max_displacement:.6g}"
        for d in merged.discards
    ]
    assert {d.side for d in merged.discards} == {"parent", "child"}
    notices: list[str] = []
    conn.add_notice_handler(lambda d: notices.append(str(d.message_primary)))
    with conn.transaction(force_rollback=True):
        conn.execute("SELECT tgsis.merge_version('e1')")
    said = [n.split(": ", 1)[1] for n in notices if n.startswith(f"feature {fault} of version 'e1': region")]
    assert said == expected


def _record_in_sql(conn: Conn, fault: int, index: int, state: MeshState) -> None:
    """Record a manual state as a psql user may, with its .npz and rows (no check of the Python client's)."""
    from tgsis.db.regions import _sql_rows, state_to_npz

    rows = _sql_rows(state)
    assert rows is not None
    conn.execute(
        "SELECT FROM tgsis.resolve_region('e1', 'feature', %s, %s, 'manual', %s, %s, %s::float8[], %s, %s,"
        " %s::text[], %s::float8[], %s::text[], %s::float8[])",
        (str(fault), index, state_to_npz(state), *rows),
    )
    conn.commit()


def _with_vertex_moved(state: MeshState, vertex: int, dz: float) -> MeshState:
    xyz = state.vertices.copy()
    xyz[np.searchsorted(state.vertex_ids, vertex), 2] += dz
    return MeshState(
        3, state.vertex_ids, xyz, state.cell_ids, state.cells, state.vertex_properties, state.cell_properties
    )


def test_recorded_rows_that_change_a_row_outside_the_region_are_refused_as_in_python(conn: Conn, fault: int) -> None:
    index = _both_moved(conn, fault)
    merge = tgsis.object_merge(conn, "e1", fault)
    conn.rollback()
    (region,) = merge.conflicts
    outside = int(np.setdiff1d(merge.child.vertex_ids, region.vertex_ids)[0])
    _record_in_sql(conn, fault, index, _with_vertex_moved(merge.child, outside, 1.0))
    theirs, mine = both_merges(conn, "e1")
    # refused both: Python TG100 (merge3's InvalidInputError), psql TG302 (the psql merge's refusal), nothing written
    assert theirs[:2] == ("refused", "TG100") and mine[:2] == ("refused", "TG302"), mine
    for said in (theirs[2], mine[2]):
        assert f"vertices {outside}" in said and "outside the region" in said


@pytest.mark.parametrize("action", ["merge", "refresh"])
def test_a_manual_mesh_that_rewrites_margin_cells_merges_in_psql_as_in_python(
    conn: Conn, fault: int, action: str
) -> None:
    """Margin cells (in the region, changed by no side) rewritten: one rotated, one with a facies of no side."""
    index = _both_moved(conn, fault)
    merge = tgsis.object_merge(conn, "e1", fault)
    conn.rollback()
    (region,) = merge.conflicts
    margin = np.setdiff1d(region.cell_ids, np.union1d(region.parent_cell_ids, region.child_cell_ids))
    assert len(margin) >= 2
    side = merge.child
    cells = side.cells.copy()
    at = np.searchsorted(side.cell_ids, margin[:2])
    cells[at[0]] = np.roll(cells[at[0]], 1)  # the same oriented triangle, another row
    facies = np.asarray(side.cell_properties["facies"]).copy()
    facies[at[1]] = 42
    manual = MeshState(
        3, side.vertex_ids, side.vertices, side.cell_ids, cells, side.vertex_properties, {"facies": facies}
    )
    tgsis.resolve_region(conn, "e1", fault, index, "manual", manual)
    conn.commit()
    assert_same_merge(conn, "e1", action)


@pytest.mark.parametrize("action", ["merge", "refresh"])
def test_average_of_all_regions_one_re_meshed_merges_in_psql_as_in_python(conn: Conn, action: str) -> None:
    from tests.test_resolve_all_regions import _two_conflicts

    fault = _two_conflicts(conn, remesh_west=True)
    tgsis.find_conflicts(conn, "e1")
    conn.commit()
    result = tgsis.resolve_all_regions(conn, "e1", fault, "average")
    conn.commit()
    assert len(result.regions) == 2
    assert [r[1] for r in _rows_recorded(conn, fault)] == ["average", "average"]
    assert all(r[2] for r in _rows_recorded(conn, fault))
    assert_same_merge(conn, "e1", action)


def test_rows_given_in_part_or_not_fitting_are_refused_and_nothing_is_recorded(conn: Conn, fault: int) -> None:
    index = _both_moved(conn, fault)
    tgsis.resolve_region(conn, "e1", fault, index, "average")
    conn.commit()
    (mesh, *rows) = conn.execute(
        "SELECT solution_mesh, solution_vertex_ids, solution_vertices, solution_cell_ids, solution_cells,"
        " solution_vertex_columns, solution_vertex_values, solution_cell_columns, solution_cell_values"
        " FROM tgsis.conflict_regions WHERE versionid = tgsis.version_id('e1') AND region = %s",
        (index,),
    ).fetchone()  # type: ignore[misc]
    conn.commit()
    before = everything(conn)
    conn.commit()
    query = (
        "SELECT FROM tgsis.resolve_region('e1', 'feature', %s, %s, 'average', %s, %s, %s::float8[], %s, %s,"
        " %s::text[], %s::float8[], %s::text[], %s::float8[])"
    )
    for arrays in (
        [mesh, rows[0], *[None] * 7],  # ids only
        [None, *rows],  # rows without the mesh
        [mesh, rows[0], rows[1][:-1], *rows[2:]],  # a coordinate short
        [mesh, *rows[:3], rows[3][:-1], *rows[4:]],  # cells not of k vertices
        [mesh, *rows[:5], rows[5][:-1], *rows[6:]],  # a value short
        [mesh, rows[0], [float("nan")] * len(rows[1]), *rows[2:]],  # non-finite coordinates
    ):
        state, message, _ = _psql_state(conn, query, (str(fault), index, *arrays))
        assert state == "TG100", message
        assert everything(conn) == before
        conn.rollback()


def test_regions_found_again_alike_keep_the_rows_and_merge_in_psql_as_in_python(conn: Conn, fault: int) -> None:
    index = _both_moved(conn, fault)
    tgsis.resolve_region(conn, "e1", fault, index, "average")
    conn.commit()
    recorded = _rows_recorded(conn, fault)
    tgsis.find_conflicts(conn, "e1")  # Python: records the regions again (the same: solutions kept)
    conn.execute("SELECT FROM tgsis.find_conflicts('e1')")  # SQL alike
    conn.commit()
    assert _rows_recorded(conn, fault) == recorded
    assert_same_merge(conn, "e1")
    tgsis.resolve_region(conn, "e1", fault, index, "unsolved")  # taken back: the rows go with the .npz
    conn.commit()
    assert _rows_recorded(conn, fault) == []
    (rows,) = conn.execute(
        "SELECT count(*) FROM tgsis.conflict_regions WHERE solution_vertex_ids IS NOT NULL OR solution_mesh IS NOT NULL"
    ).fetchone()  # type: ignore[misc]
    conn.rollback()
    assert rows == 0


def test_a_manual_mesh_without_a_margin_cell_merges_in_psql_as_in_python(conn: Conn, fault: int) -> None:
    """A margin cell the manual mesh lacks is removed (a hole there), as the Python merge removes it."""
    index = _both_moved(conn, fault)
    merge = tgsis.object_merge(conn, "e1", fault)
    conn.rollback()
    (region,) = merge.conflicts
    margin = np.setdiff1d(region.cell_ids, np.union1d(region.parent_cell_ids, region.child_cell_ids))[0]
    side = merge.child
    keep = side.cell_ids != margin
    manual = MeshState(
        3,
        side.vertex_ids,
        side.vertices,
        side.cell_ids[keep],
        side.cells[keep],
        side.vertex_properties,
        {n: np.asarray(v)[keep] for n, v in side.cell_properties.items()},
    )
    tgsis.resolve_region(conn, "e1", fault, index, "manual", manual)
    conn.commit()
    assert_same_merge(conn, "e1")


def test_gocad_atoms_in_an_averaged_region_and_a_manual_refid_merge_in_psql_as_in_python(
    conn: Conn, fault: int
) -> None:
    from tests.test_sql_merge_regions import psql

    atom = "INSERT INTO tgsis.atom (geoid, vrtxid, refid, patom) VALUES (%s, %s, %s, %s)"
    psql(conn, "DEFAULT", (atom, (fault, int(MIDDLE[0]), int(MIDDLE[1]), True)))  # in the base: a PATOM
    conn.execute("SELECT tgsis.merge_version('e1', true)")
    conn.commit()
    tgsis.create_version(conn, "e1")
    conn.commit()
    psql(conn, "e1", (atom, (fault, int(MIDDLE[2]), int(MIDDLE[3]), False)))  # the version adds one in the region
    index = _both_moved(conn, fault)
    tgsis.resolve_region(conn, "e1", fault, index, "average")
    conn.commit()
    for action in ("merge", "refresh"):
        assert_same_merge(conn, "e1", action)
    # manual: the PATOM refers to another vertex of the region, the version's atom is gone
    merge = tgsis.object_merge(conn, "e1", fault)
    conn.rollback()
    side = merge.child
    refid = np.asarray(side.vertex_properties["refid"], dtype=np.float64).copy()
    refid[np.searchsorted(side.vertex_ids, MIDDLE[0])] = MIDDLE[3]
    refid[np.searchsorted(side.vertex_ids, MIDDLE[2])] = -1
    props = {**side.vertex_properties, "refid": refid}
    manual = MeshState(3, side.vertex_ids, side.vertices, side.cell_ids, side.cells, props, side.cell_properties)
    tgsis.resolve_region(conn, "e1", fault, index, "manual", manual)
    conn.commit()
    for action in ("merge", "refresh"):
        assert_same_merge(conn, "e1", action)


def test_parts_kept_as_runs_with_an_average_and_a_manual_part_merge_in_psql_as_in_python(conn: Conn) -> None:
    from tests.test_sql_merge_write import _parted_fault

    geoid = _parted_fault(conn)
    index = _both_moved(conn, geoid)
    tgsis.resolve_region(conn, "e1", geoid, index, "average")
    conn.commit()
    assert_same_merge(conn, "e1")
    merge = tgsis.object_merge(conn, "e1", geoid)
    conn.rollback()
    (region,) = merge.conflicts
    side = merge.child
    part = np.asarray(side.cell_properties["part"], dtype=np.float64).copy()
    part[np.isin(side.cell_ids, region.cell_ids[:3])] = 7  # three cells of the region in another part
    props = {**side.cell_properties, "part": part}
    manual = MeshState(3, side.vertex_ids, side.vertices, side.cell_ids, side.cells, side.vertex_properties, props)
    tgsis.resolve_region(conn, "e1", geoid, index, "manual", manual)
    conn.commit()
    for action in ("merge", "refresh"):
        assert_same_merge(conn, "e1", action)


_pairs = itertools.count()


@settings(
    max_examples=6, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow]
)
@given(
    child=st.lists(_edit, min_size=0, max_size=2),
    parent=st.lists(_edit, min_size=0, max_size=2),
    where=st.integers(0, 2 * (SIDE - 1) ** 2 - 1),
    shifts=st.sampled_from([(0, 1), (1, 2), (2, 0), (0, 2)]),
    action=st.sampled_from(["merge", "refresh"]),
)
# found by Hypothesis: the parent removes cells beside the patch both sides move, so the region's average is of
# two meshings, which resamples vertices of the region no side changed (vertex 86 moves ~90 m): psql writes them
# as the Python merge does (was refused, TG302)
@example(child=[], parent=[("delete", 78, 0)], where=176, shifts=(0, 1), action="merge")
def test_random_edits_solved_average_merge_in_psql_exactly_as_in_python(
    conn: Conn,
    fault: int,
    child: list[tuple[str, int, int]],
    parent: list[tuple[str, int, int]],
    where: int,
    shifts: tuple[int, int],
    action: str,
) -> None:
    """Both sides move one patch, each its own way (a conflict), with random other edits around."""
    child = [("move", where, shifts[0]), *child]
    parent = [("move", where, shifts[1]), *parent]
    n = next(_pairs)
    parent_version, child_version = f"ap{n}", f"ac{n}"
    tgsis.create_version(conn, parent_version)
    conn.commit()
    tgsis.create_version(conn, child_version, parent=parent_version)
    conn.commit()
    vp, cp = property_tables(conn, fault)
    _apply(conn, child_version, fault, child, vp, cp)
    _apply(conn, parent_version, fault, parent, vp, cp)
    conflicts = tgsis.find_conflicts(conn, child_version)
    conn.commit()
    if not any(r.conflict for c in conflicts for r in c.regions):
        return
    try:
        tgsis.resolve_all_regions(conn, child_version, fault, "average")
    except tgsis.Error:  # no average there (a hole, a fold): nothing recorded
        conn.rollback()
        return
    conn.commit()
    theirs, mine = both_merges(conn, child_version, action)
    if theirs[0] == "refused":
        assert mine[0] == "refused" and mine[1] == theirs[1], (theirs, mine)
        return
    assert mine[0] == "done", mine
    assert mine[1] == theirs[1]
    for table in theirs[2]:
        assert mine[2][table] == theirs[2][table], table


def test_session_settings_do_not_change_what_a_manual_solution_writes(conn: Conn, fault: int) -> None:
    from tests.test_sql_merge_write import _outcome

    index = _both_moved(conn, fault)
    merge = tgsis.object_merge(conn, "e1", fault)
    conn.rollback()
    side = merge.child
    xyz = side.vertices.copy()
    at = np.isin(side.vertex_ids, MIDDLE)
    xyz[at, 2] += 0.1 + 1e-13  # digits beyond 15
    porosity = np.asarray(side.vertex_properties["porosity"], dtype=np.float64).copy()
    porosity[at] = 1 / 3
    manual = MeshState(3, side.vertex_ids, xyz, side.cell_ids, side.cells, {"porosity": porosity}, side.cell_properties)
    conn.execute("SET extra_float_digits = -15")  # the recording too
    tgsis.resolve_region(conn, "e1", fault, index, "manual", manual)
    conn.commit()
    conn.execute("RESET ALL")
    conn.commit()
    theirs, _ = both_merges(conn, "e1")
    conn.execute("SET extra_float_digits = -15")
    conn.execute("SET DateStyle = 'SQL, DMY'")
    conn.execute("SET search_path = ''")
    conn.commit()
    mine = _outcome(conn, lambda: int(conn.execute("SELECT tgsis.merge_version('e1')").fetchone()[0]))  # type: ignore[index]
    conn.execute("RESET ALL")
    conn.commit()
    assert mine[0] == "done", mine
    assert mine[1] == theirs[1]
    for table in theirs[2]:
        assert mine[2][table] == theirs[2][table], table


@pytest.mark.parametrize("solution", ["average", "manual"])
def test_real_and_smallint_properties_are_written_as_python_writes_them(conn: Conn, solution: str) -> None:
    """A real vertex property given float8 values (rounded to float4 as numpy rounds them), a smallint cell one."""
    from tgsis.db import features as F

    F.create_feature_class(
        conn,
        "faults",
        "SURFACE",
        cell_properties=[("porosity", "real"), tgsis.Property("facies", "smallint", alignment="CELL")],
    )
    tgsis.enable_feature_versioning(conn)
    geoid = F.insert_feature(conn, "faults", curved_surface())
    tgsis.create_version(conn, "e1")
    conn.commit()
    from tests.test_sql_merge_regions import psql

    psql(
        conn, "e1", ("UPDATE tgsis.vrtx SET z = z + 1 WHERE geoid = %s AND vrtxid = ANY (%s)", (geoid, MIDDLE.tolist()))
    )
    psql(
        conn,
        "DEFAULT",
        ("UPDATE tgsis.vrtx SET z = z - 2.5 WHERE geoid = %s AND vrtxid = ANY (%s)", (geoid, MIDDLE.tolist())),
    )
    (conflict,) = tgsis.find_conflicts(conn, "e1")
    conn.commit()
    (region,) = [r for r in conflict.regions if r.conflict]
    manual = None
    if solution == "manual":
        merge = tgsis.object_merge(conn, "e1", geoid)
        conn.rollback()
        side = merge.child
        porosity = np.asarray(side.vertex_properties["porosity"], dtype=np.float64).copy()
        at = np.isin(side.vertex_ids, region.vertex_ids)
        porosity[at] = np.linspace(1 / 3, 2 / 3, int(at.sum()))  # no float4 holds them
        facies = np.asarray(side.cell_properties["facies"], dtype=np.float64).copy()
        facies[np.isin(side.cell_ids, region.cell_ids)] = 3.75  # truncated to 3, as numpy's astype
        manual = MeshState(
            3, side.vertex_ids, side.vertices, side.cell_ids, side.cells, {"porosity": porosity}, {"facies": facies}
        )
    tgsis.resolve_region(conn, "e1", geoid, region.region, solution, manual)
    conn.commit()
    assert_same_merge(conn, "e1")


def test_two_solutions_giving_the_same_new_id_are_refused_and_nothing_is_written(conn: Conn) -> None:
    from tests.test_resolve_all_regions import _two_conflicts

    fault = _two_conflicts(conn)
    tgsis.find_conflicts(conn, "e1")
    conn.commit()
    merge = tgsis.object_merge(conn, "e1", fault)
    conn.rollback()
    side = merge.child
    new = int(max(merge.base.vertex_ids.max(), merge.parent.vertex_ids.max(), side.vertex_ids.max())) + 1
    for region in merge.conflicts:  # each region's vertices (no cells) and the same new vertex: forged rows
        at = np.flatnonzero(np.isin(side.vertex_ids, region.vertex_ids))
        state = MeshState(
            3,
            np.append(side.vertex_ids[at], new),
            np.vstack([side.vertices[at], [[1.0, 2.0, float(region.index)]]]),
            np.empty(0, np.int64),
            np.empty((0, 3), np.int64),
            {n: np.append(np.asarray(v, dtype=np.float64)[at], 0.5) for n, v in side.vertex_properties.items()},
            {n: np.asarray(v)[:0] for n, v in side.cell_properties.items()},
        )
        _record_in_sql(conn, fault, region.index, state)
    before = everything(conn)
    conn.commit()
    state_, message, hint = _psql_state(conn, "SELECT tgsis.merge_version('e1')", ())
    assert state_ == "TG302", message
    assert f"vertex {new} given by regions" in message and "tgsis version merge" in (hint or "")
    assert everything(conn) == before
    conn.rollback()


def _average_of_two_meshings(conn: Conn, fault: int) -> tuple[int, np.ndarray]:
    """Hypothesis's case as a plain test: both sides move the patch at 176, the parent also removes triangle 78
    beside it, so the region's average is of two meshings and resamples vertices of the region no side changed.
    Recorded ``average`` (the Python client); (region, the unchanged vertex ids the recorded rows move)."""
    vp, cp = property_tables(conn, fault)
    _apply(conn, "e1", fault, [("move", 176, 0)], vp, cp)
    _apply(conn, "DEFAULT", fault, [("move", 176, 1), ("delete", 78, 0)], vp, cp)
    tgsis.find_conflicts(conn, "e1")
    conn.commit()
    tgsis.resolve_all_regions(conn, "e1", fault, "average")
    conn.commit()
    merge = tgsis.object_merge(conn, "e1", fault)
    conn.rollback()
    (region,) = merge.conflicts
    unchanged = np.setdiff1d(region.vertex_ids, np.union1d(region.parent_vertex_ids, region.child_vertex_ids))
    ids, xyz = conn.execute(
        "SELECT solution_vertex_ids, solution_vertices FROM tgsis.conflict_regions"
        " WHERE versionid = tgsis.version_id('e1') AND objectkey = %s AND region = %s",
        (str(fault), region.index),
    ).fetchone()  # type: ignore[misc]
    conn.rollback()
    ids, xyz = np.asarray(ids, dtype=np.int64), np.asarray(xyz, dtype=np.float64).reshape(-1, 3)
    at = np.isin(ids, unchanged)
    base = merge.base.vertices[np.searchsorted(merge.base.vertex_ids, ids[at])]
    return region.index, ids[at][(xyz[at] != base).any(axis=1)]


@pytest.mark.parametrize("action", ["merge", "refresh"])
def test_an_average_moving_region_vertices_no_side_changed_merges_in_psql_as_in_python(
    conn: Conn, fault: int, action: str
) -> None:
    """It was refused (TG302, "its solution changes rows of its regions no side changed"): the psql merge wrote no
    region vertex no side changed. Now it writes them as the Python merge does (the base's row closed, the
    average's written), and says what the average discards of each side as Python says it."""
    _, moved = _average_of_two_meshings(conn, fault)
    assert len(moved) > 0  # the case: the average moves vertices no side changed
    if action == "merge":
        with conn.transaction(force_rollback=True):
            (merged,) = tgsis.merge_version(conn, "e1").objects
        expected = [
            f"region {d.region}: {d.solution} discards the {d.side}'s edit there: {d.vertices} vertices, "
            f"{d.cells} cells, largest displacement {d.max_displacement:.6g}"
            for d in merged.discards
        ]
        assert expected
        notices: list[str] = []
        conn.add_notice_handler(lambda d: notices.append(str(d.message_primary)))
        with conn.transaction(force_rollback=True):
            conn.execute("SELECT tgsis.merge_version('e1')")
        said = [n.split(": ", 1)[1] for n in notices if n.startswith(f"feature {fault} of version 'e1': region")]
        assert said == expected
    assert_same_merge(conn, "e1", action)
    rows = conn.execute(
        "SELECT count(*) FROM tgsis.vrtx WHERE geoid = %s AND vrtxid = ANY (%s)", (fault, moved.tolist())
    ).fetchone()
    conn.rollback()
    assert rows == (len(moved),)  # each moved vertex once in the merged object (its base row closed)
