"""The regions of an evolving surface (model 3) found in SQL, geometry instant by geometry instant (issue 39).

A geometry instant (timem, timet) that both sides changed is merged by the
Python client by merge3's regions of that slice (``tgsis._merge_slices``: the
period's nodes at their positions there, the period's triangles, the
property rows keyed (_timem, _timet, _idx)). The SQL region engine
(``tgsis.mesh_merge_work`` / ``tgsis.mesh_merge_regions`` with ``p_timem``)
finds the same regions on that slice's rows; the oracle is the Python
``tgsis.find_conflicts``, which stores each slice's regions numbered through
the object with their ``times`` (the geometry instant) and ``timem`` (the
period).
"""

from __future__ import annotations

import dataclasses
import itertools
from typing import Any

import numpy as np
import psycopg
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import tgsis
from tests.merge_data import SIDE, with_duplicated_triangle
from tests.roles import merges_as
from tests.test_merge_instants import CHILD_SHIFT, MIDDLE, NORTH, PARENT_SHIFT, SOUTH
from tests.test_sql_merge_instant_regions import assert_same_regions, python_regions
from tests.test_sql_merge_periods import FIRST, SECOND, _move, _node_ids, _period, _sql, make_periods
from tests.test_sql_merge_write import assert_same_merge, both_merges, everything, solve
from tgsis.temporal import EvolvingSurface

Conn = psycopg.Connection[Any]

_REGION = (
    "conflict, changed_by, vertex_ids, cell_ids, parent_vertex_ids, parent_cell_ids, child_vertex_ids,"
    " child_cell_ids, bbox, parent_displacement, child_displacement"
)


@pytest.fixture
def periods(conn: Conn, periods_clone: int) -> int:
    return periods_clone  # make_periods's, built once (tests/conftest.py)


def _engine_regions(conn: Conn, version: str, geoid: int, m: float, t: float) -> list[tuple[Any, ...]]:
    """The engine's regions of one geometry instant (numbered from 0 there; rolled back)."""
    rows = conn.execute(
        f"SELECT region, {_REGION} FROM tgsis.mesh_merge_regions(%s, %s, %s, %s) ORDER BY region",
        (version, geoid, t, m),
    ).fetchall()
    conn.rollback()
    return [tuple(r) for r in rows]


def _python_slices(conn: Conn, version: str, geoid: int) -> dict[tuple[float, float], list[tuple[Any, ...]]]:
    """Python's stored regions per slice (timem, timet), numbered from 0 in the slice, as the engine numbers them."""
    out: dict[tuple[float, float], list[tuple[Any, ...]]] = {}
    for row in python_regions(conn, version, geoid):
        key = (float(row[2]), float(row[1]))
        out.setdefault(key, []).append((len(out.get(key, [])), *row[3:14]))
    return out


def _assert_engine_as_python(conn: Conn, version: str, geoid: int) -> dict[tuple[float, float], list[tuple[Any, ...]]]:
    theirs = _python_slices(conn, version, geoid)
    assert theirs  # the case has regions
    for (m, t), regions in theirs.items():
        assert _engine_regions(conn, version, geoid, m, t) == regions, (m, t)
    return theirs


def test_the_engine_finds_the_regions_python_finds_at_a_geometry_instant_both_sides_changed(
    conn: Conn, periods: int
) -> None:
    ids = _node_ids(conn, periods, 1.0)
    _move(conn, "e1", periods, 1.0, 2.0, [ids[i] for i in NORTH], CHILD_SHIFT)
    _move(conn, "DEFAULT", periods, 1.0, 2.0, [ids[i] for i in NORTH[:SIDE]], PARENT_SHIFT)  # a conflict
    _move(conn, "DEFAULT", periods, 1.0, 2.0, [ids[i] for i in SOUTH], PARENT_SHIFT)  # apart: by itself
    theirs = _assert_engine_as_python(conn, "e1", periods)
    assert [(r[1], r[2]) for r in theirs[(1.0, 2.0)]] == [(True, "both"), (False, "parent")]


def test_the_engine_at_several_geometry_instants_of_two_periods_with_values_and_triangles(
    conn: Conn, periods: int
) -> None:
    first, second = _node_ids(conn, periods, 1.0), _node_ids(conn, periods, 3.0)
    _move(conn, "e1", periods, 1.0, 1.0, [first[i] for i in SOUTH], CHILD_SHIFT)
    _move(conn, "DEFAULT", periods, 1.0, 1.0, [first[i] for i in NORTH], PARENT_SHIFT)
    _move(conn, "e1", periods, 3.0, 4.0, [second[i] for i in NORTH], CHILD_SHIFT)
    _move(conn, "DEFAULT", periods, 3.0, 4.0, [second[i] for i in NORTH[SIDE:]], PARENT_SHIFT)
    _sql(
        conn,
        "e1",
        "UPDATE evolving_cellpros SET porosity = porosity + 0.5 WHERE _geoid = %s AND _timem = 3 AND _timet = 4"
        " AND _idx = ANY(%s)",
        (periods, second[5 * SIDE : 5 * SIDE + 3]),
    )
    _sql(
        conn,
        "DEFAULT",
        "UPDATE evolving_cellpros SET porosity = porosity - 0.25 WHERE _geoid = %s AND _timem = 3 AND _timet = 4"
        " AND _idx = ANY(%s)",
        (periods, second[5 * SIDE + 1 : 5 * SIDE + 2]),
    )
    theirs = _assert_engine_as_python(conn, "e1", periods)
    assert sorted(theirs) == [(1.0, 1.0), (3.0, 4.0)]


def test_the_engine_refuses_a_period_without_its_geometry_instant_and_a_slice_not_in_all_states(
    conn: Conn, periods: int
) -> None:
    ids = _node_ids(conn, periods, 1.0)
    _move(conn, "e1", periods, 1.0, 2.0, [ids[i] for i in NORTH], CHILD_SHIFT)
    _move(conn, "DEFAULT", periods, 1.0, 2.0, [ids[i] for i in SOUTH], PARENT_SHIFT)
    with pytest.raises(psycopg.errors.InvalidParameterValue):
        conn.execute("SELECT * FROM tgsis.mesh_merge_regions('e1', %s, NULL, 1.0)", (periods,))
    conn.rollback()
    with pytest.raises(psycopg.Error) as err:
        conn.execute("SELECT * FROM tgsis.mesh_merge_regions('e1', %s, 2.5, 1.0)", (periods,))
    assert err.value.sqlstate == "TG100"
    assert "geometry instant 2.5 of the period starting at 1" in str(err.value)
    conn.rollback()


def test_the_engine_where_one_side_changed_the_topology_and_the_other_moved_nodes(conn: Conn, periods: int) -> None:
    ids = _node_ids(conn, periods, 1.0)
    _sql(conn, "e1", "DELETE FROM tgsis.d4dtrgl WHERE geoid = %s AND timem = 1 AND trglid = ANY(%s)", (periods, [7, 8]))
    _move(conn, "DEFAULT", periods, 1.0, 2.0, [ids[i] for i in NORTH], PARENT_SHIFT)
    _move(conn, "DEFAULT", periods, 1.0, 3.0, [ids[i] for i in SOUTH], PARENT_SHIFT)
    theirs = _assert_engine_as_python(conn, "e1", periods)
    assert sorted(theirs) == [(1.0, 1.0), (1.0, 2.0), (1.0, 3.0)]


# ---------------------------------------------------------------------------- SQL find_conflicts stores them


def _conflict_at_two(conn: Conn, geoid: int) -> None:
    """Geometry instant 2 of the first period: a conflict (north) and the parent's edit apart (south); the second
    period's geometry instant 4 changed by the version alone."""
    first, second = _node_ids(conn, geoid, 1.0), _node_ids(conn, geoid, 3.0)
    _move(conn, "e1", geoid, 1.0, 2.0, [first[i] for i in NORTH], CHILD_SHIFT)
    _move(conn, "DEFAULT", geoid, 1.0, 2.0, [first[i] for i in NORTH[:SIDE]], PARENT_SHIFT)
    _move(conn, "DEFAULT", geoid, 1.0, 2.0, [first[i] for i in SOUTH], PARENT_SHIFT)
    _move(conn, "e1", geoid, 3.0, 4.0, [second[i] for i in SOUTH], CHILD_SHIFT)


def test_sql_find_conflicts_stores_the_regions_of_geometry_instants_as_python(conn: Conn, periods: int) -> None:
    _conflict_at_two(conn, periods)
    regions = assert_same_regions(conn, "e1", periods)
    assert [(r[0], r[1], r[2], r[3], r[4]) for r in regions] == [
        (0, 2.0, 1.0, True, "both"),
        (1, 2.0, 1.0, False, "parent"),
        (2, 4.0, 3.0, False, "child"),
    ]
    assert [r[14] for r in regions] == ["unsolved", "automatic", "automatic"]


def test_sql_find_conflicts_stores_the_regions_of_a_topology_change_beside_moves_as_python(
    conn: Conn, periods: int
) -> None:
    ids = _node_ids(conn, periods, 1.0)
    _sql(conn, "e1", "DELETE FROM tgsis.d4dtrgl WHERE geoid = %s AND timem = 1 AND trglid = ANY(%s)", (periods, [7, 8]))
    _move(conn, "DEFAULT", periods, 1.0, 2.0, [ids[i] for i in SOUTH], PARENT_SHIFT)
    assert len(assert_same_regions(conn, "e1", periods)) == 4


def test_no_regions_either_way_for_a_topology_changed_on_both_sides_or_a_period_two_topologies(
    conn: Conn, periods: int
) -> None:
    ids = _node_ids(conn, periods, 1.0)
    _sql(conn, "e1", "DELETE FROM tgsis.d4dtrgl WHERE geoid = %s AND timem = 1 AND trglid = 7", (periods,))
    _move(conn, "DEFAULT", periods, 1.0, 2.0, [ids[i] for i in SOUTH], PARENT_SHIFT)
    _sql(conn, "DEFAULT", "DELETE FROM tgsis.d4dtrgl WHERE geoid = %s AND timem = 1 AND trglid = 9", (periods,))
    assert assert_same_regions(conn, "e1", periods) == []


# ---------------------------------------------------------------------------- the psql merge by region


@pytest.mark.parametrize("action", ["merge", "refresh"])
def test_geometry_instants_both_sides_changed_apart_merge_in_psql_exactly_as_in_python(
    conn: Conn, periods: int, action: str
) -> None:
    first, second = _node_ids(conn, periods, 1.0), _node_ids(conn, periods, 3.0)
    _move(conn, "e1", periods, 1.0, 2.0, [first[i] for i in NORTH], CHILD_SHIFT)
    _move(conn, "DEFAULT", periods, 1.0, 2.0, [first[i] for i in SOUTH], PARENT_SHIFT)
    _move(conn, "e1", periods, 3.0, 4.0, [second[i] for i in SOUTH], CHILD_SHIFT)
    _move(conn, "DEFAULT", periods, 3.0, 4.0, [second[i] for i in NORTH], PARENT_SHIFT)
    _move(conn, "DEFAULT", periods, 3.0, 5.0, [second[i] for i in NORTH], PARENT_SHIFT)
    assert_same_merge(conn, "e1", action)


@pytest.mark.parametrize("solution", ["parent", "child", "base"])
@pytest.mark.parametrize("action", ["merge", "refresh"])
def test_a_conflicting_region_of_a_geometry_instant_solved_in_psql_merges_as_in_python(
    conn: Conn, periods: int, solution: str, action: str
) -> None:
    _conflict_at_two(conn, periods)
    solve(conn, "e1", periods, solution)
    assert_same_merge(conn, "e1", action)


def test_an_unsolved_region_of_a_geometry_instant_is_refused_naming_it_and_nothing_is_written(
    conn: Conn, periods: int
) -> None:
    _conflict_at_two(conn, periods)
    conn.commit()
    before = everything(conn)
    conn.rollback()
    theirs, mine = both_merges(conn, "e1")
    assert theirs[:2] == ("refused", "TG302")
    assert mine[:2] == ("refused", "TG302")
    assert "region 0 at geometry instant 2.0 of the period starting at 1.0 unsolved" in theirs[2]
    assert "region 0 at geometry instant 2.0 of the period starting at 1.0 unsolved" in mine[2]
    assert "tgsis version merge e1" in mine[2]
    assert everything(conn) == before
    conn.rollback()


def test_one_side_changed_the_topology_the_other_moved_nodes_merges_in_psql_as_in_python(
    conn: Conn, periods: int
) -> None:
    ids = _node_ids(conn, periods, 1.0)
    _sql(conn, "e1", "DELETE FROM tgsis.d4dtrgl WHERE geoid = %s AND timem = 1 AND trglid = ANY(%s)", (periods, [7, 8]))
    _move(conn, "DEFAULT", periods, 1.0, 1.0, [ids[i] for i in SOUTH], PARENT_SHIFT)
    _move(conn, "DEFAULT", periods, 1.0, 2.0, [ids[i] for i in SOUTH], PARENT_SHIFT)
    assert_same_merge(conn, "e1")


def test_one_side_changed_the_topology_the_other_moved_its_nodes_a_conflict_then_solved(
    conn: Conn, periods: int
) -> None:
    ids = _node_ids(conn, periods, 1.0)
    _sql(conn, "e1", "DELETE FROM tgsis.d4dtrgl WHERE geoid = %s AND timem = 1 AND trglid = ANY(%s)", (periods, [7, 8]))
    _move(conn, "DEFAULT", periods, 1.0, 2.0, [ids[i] for i in NORTH], PARENT_SHIFT)  # the triangles' nodes
    theirs, mine = both_merges(conn, "e1")
    assert theirs[:2] == mine[:2] == ("refused", "TG302")
    solve(conn, "e1", periods, "child")
    assert_same_merge(conn, "e1")


def test_a_solution_that_gives_one_geometry_instant_the_old_topology_is_refused_tg308_as_in_python(
    conn: Conn, periods: int
) -> None:
    """The parent removes triangles of the first period, the version moves their nodes at geometry instant 2: a
    conflict there; solved base, that geometry instant keeps the triangles the others lose (TG308 both ways)."""
    ids = _node_ids(conn, periods, 1.0)
    _sql(
        conn,
        "DEFAULT",
        "DELETE FROM tgsis.d4dtrgl WHERE geoid = %s AND timem = 1 AND trglid = ANY(%s)",
        (periods, [7, 8]),
    )
    _move(conn, "e1", periods, 1.0, 2.0, [ids[i] for i in NORTH], CHILD_SHIFT)
    solve(conn, "e1", periods, "base")
    conn.commit()
    before = everything(conn)
    conn.rollback()
    theirs, mine = both_merges(conn, "e1")
    assert theirs[:2] == ("refused", "TG308"), theirs
    assert mine[:2] == ("refused", "TG308"), mine
    assert "the topology period starting at 1" in mine[2] and "the topology period starting at 1" in theirs[2]
    assert everything(conn) == before
    conn.rollback()


def test_no_regions_either_way_for_a_geometry_instant_added_where_the_other_side_changed_the_topology(
    conn: Conn, periods: int
) -> None:
    """tgsis._merge_slices.fixed_period_refusal: no solution merges it (TG308), so neither stores regions."""
    from tests.test_sql_merge_periods import step

    ids = _node_ids(conn, periods, 1.0)
    step(conn, "DEFAULT", "topology 1 0", periods)
    step(conn, "e1", "add-instant 1 2 2.5", periods)
    _move(conn, "e1", periods, 1.0, 2.0, [ids[i] for i in SOUTH], CHILD_SHIFT)
    assert assert_same_regions(conn, "e1", periods) == []


# ---------------------------------------------------------------------------- random edits against Python

_features = itertools.count(1)
_ROWS = {"north": NORTH, "south": SOUTH, "middle": MIDDLE, "edge": NORTH[:SIDE]}
# (period, geometry instant) a side may edit: not the first period's last one, where the second starts
_SLICES = [(1.0, 1.0), (1.0, 2.0), (3.0, 4.0), (3.0, 5.0)]
_edit = st.tuples(
    st.sampled_from(["move", "move", "values", "topology"]),
    st.sampled_from(range(len(_SLICES))),
    st.sampled_from(sorted(_ROWS)),
)


@settings(
    max_examples=8, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow]
)
@given(
    edits=st.tuples(st.lists(_edit, min_size=1, max_size=3), st.lists(_edit, min_size=1, max_size=3)),
    solution=st.sampled_from(["none", "parent", "child", "base"]),
    action=st.sampled_from(["merge", "refresh"]),
)
def test_random_edits_of_geometry_instants_on_both_sides_merge_in_psql_exactly_as_in_python(
    conn: Conn, edits: tuple[list[tuple[str, int, str]], list[tuple[str, int, str]]], solution: str, action: str
) -> None:
    """Each side moves nodes, changes property rows or removes a triangle (the topology) at random geometry
    instants of two periods; the conflicting regions maybe solved alike. psql merges (or refuses, by SQLSTATE)
    exactly as Python does."""
    if not conn.execute("SELECT 1 FROM tgsis.catalog WHERE classname = 'evolving'").fetchone():
        conn.rollback()
        make_periods(conn)
    conn.rollback()
    n = next(_features)
    geoid = tgsis.insert_feature(conn, "evolving", EvolvingSurface([_period(FIRST, 0), _period(SECOND, 2)]))
    version = f"r{n}"
    tgsis.create_version(conn, version)
    conn.commit()
    for v, plan, shift in (("DEFAULT", edits[0], PARENT_SHIFT), (version, edits[1], CHILD_SHIFT)):
        for what, at, rows in plan:
            m, t = _SLICES[at]
            ids = _node_ids(conn, geoid, m)
            if what == "move":
                _move(conn, v, geoid, m, t, [ids[i] for i in _ROWS[rows]], shift)
            elif what == "values":
                _sql(
                    conn,
                    v,
                    "UPDATE evolving_cellpros SET porosity = porosity + %s WHERE _geoid = %s AND _timem = %s"
                    " AND _timet = %s AND _idx = ANY(%s)",
                    (shift[0], geoid, m, t, [ids[i] for i in _ROWS[rows][:3]]),
                )
            else:  # a triangle of the period on those rows removed
                _sql(
                    conn,
                    v,
                    "DELETE FROM tgsis.d4dtrgl WHERE geoid = %s AND timem = %s AND nodeid1 = ANY(%s)"
                    " AND trglid = (SELECT min(trglid) FROM tgsis.d4dtrgl WHERE geoid = %s AND timem = %s"
                    " AND nodeid1 = ANY(%s))",
                    (geoid, m, [ids[i] for i in _ROWS[rows]], geoid, m, [ids[i] for i in _ROWS[rows]]),
                )
    conn.execute("SELECT FROM tgsis.find_conflicts(%s)", (version,))
    conflicts = conn.execute(
        "SELECT count(*) FROM tgsis.conflict_regions WHERE versionid = tgsis.version_id(%s) AND conflict", (version,)
    ).fetchone()
    conn.rollback()
    if solution != "none" and conflicts is not None and conflicts[0] > 0:
        solve(conn, version, geoid, solution)
    theirs, mine = both_merges(conn, version, action)
    assert mine[:2] == theirs[:2], (theirs[:3], mine[:3])
    if theirs[0] == "done":
        for table in theirs[2]:
            assert mine[2][table] == theirs[2][table], table


# ---------------------------------------------------------------------------- hostile cases


def _apart_at_two(conn: Conn, geoid: int) -> None:
    """Geometry instant 2 of the first period: each side moves nodes apart, the parent changes property rows there."""
    ids = _node_ids(conn, geoid, 1.0)
    _move(conn, "e1", geoid, 1.0, 2.0, [ids[i] for i in NORTH], CHILD_SHIFT)
    _move(conn, "DEFAULT", geoid, 1.0, 2.0, [ids[i] for i in SOUTH], PARENT_SHIFT)
    _sql(
        conn,
        "DEFAULT",
        "UPDATE evolving_cellpros SET porosity = porosity * 3 WHERE _geoid = %s AND _timem = 1 AND _timet = 2"
        " AND _idx = ANY(%s)",
        (geoid, [ids[i] for i in SOUTH]),
    )


@pytest.mark.parametrize("revoked", ["DELETE", "INSERT, UPDATE, DELETE"])
def test_a_property_view_the_role_may_not_write_is_refused_as_in_python_and_nothing_is_written(
    conn: Conn, periods: int, db_dsn: str, revoked: str
) -> None:
    from tests.roles import login_roles

    _apart_at_two(conn, periods)
    with login_roles(db_dsn, {"ed": "tgsis_editor"}) as made:
        tgsis.grant_version(conn, "e1", "all", made.name("ed"))
        tgsis.grant_version(conn, "DEFAULT", "merge", made.name("ed"))
        conn.execute(f"REVOKE {revoked} ON public.evolving_cellpros FROM tgsis_editor")
        conn.commit()
        before = everything(conn)
        conn.commit()
        session = made.connect("ed")
        theirs, mine = merges_as(conn, session, "e1")
        assert everything(conn) == before
        conn.commit()
        assert theirs == ("refused", "42501"), theirs
        assert mine == theirs, (revoked, theirs, mine)


def test_solved_regions_of_geometry_instants_kept_by_pg_dump_and_restore_then_merged_in_psql(
    conn: Conn, periods: int, db_dsn: str, pg: Any, tmp_path: Any
) -> None:
    from tests.test_backup import _bindir_of, _restored
    from tests.test_sql_merge_write import _outcome

    _conflict_at_two(conn, periods)
    solve(conn, "e1", periods, "child")
    theirs, _ = both_merges(conn, "e1")
    assert theirs[0] == "done", theirs
    for fmt in ("plain", "custom"):
        with _restored(pg, _bindir_of(pg), db_dsn, fmt, tmp_path) as dsn, psycopg.connect(dsn) as restored:
            mine = _outcome(restored, lambda: int(restored.execute("SELECT tgsis.merge_version('e1')").fetchone()[0]))  # type: ignore[index]  # noqa: B023
            assert mine[0] == "done", mine
            assert mine[1] == theirs[1]
            for table in theirs[2]:
                assert mine[2][table] == theirs[2][table], (fmt, table)


@pytest.mark.parametrize("solution", ["parent", "child", "base"])
def test_psql_is_told_what_a_solution_of_a_geometry_instant_discards_as_python_says_it(
    conn: Conn, periods: int, solution: str
) -> None:
    _conflict_at_two(conn, periods)
    solve(conn, "e1", periods, solution)
    with conn.transaction(force_rollback=True):
        (merged,) = tgsis.merge_version(conn, "e1").objects
    expected = [
        f"region {d.region} at geometry instant 2 of the period starting at 1: {d.solution} discards the {d.side}'s"
        f" edit there: {d.vertices} vertices, {d.cells} cells, largest displacement {d.max_displacement:.6g}"
        for d in merged.discards
    ]
    assert expected
    notices: list[str] = []
    conn.add_notice_handler(lambda d: notices.append(str(d.message_primary)))
    with conn.transaction(force_rollback=True):
        conn.execute("SELECT tgsis.merge_version('e1')")
    said = [n.split(": ", 1)[1] for n in notices if n.startswith(f"feature {periods} of version 'e1': region")]
    assert said == expected


def test_session_settings_do_not_change_what_psql_merges_by_region(conn: Conn, periods: int) -> None:
    _conflict_at_two(conn, periods)
    solve(conn, "e1", periods, "parent")
    theirs, _ = both_merges(conn, "e1")
    assert theirs[0] == "done", theirs
    conn.execute("SET extra_float_digits = -15")
    conn.execute("SET search_path = public")
    conn.execute("SET enable_hashjoin = off; SET jit = off")
    conn.commit()
    _, mine = both_merges(conn, "e1")
    conn.execute("RESET ALL")
    conn.commit()
    assert mine[0] == "done", mine
    assert mine[1] == theirs[1]
    for table in theirs[2]:
        assert mine[2][table] == theirs[2][table], table


@pytest.mark.parametrize("action", ["merge", "refresh"])
def test_an_average_of_a_region_of_a_geometry_instant_merges_in_psql_as_in_python(
    conn: Conn, periods: int, action: str
) -> None:
    """The rows of an average of a region of a period's geometry instant are recorded with its mesh (keyed by the
    period's node and triangle ids): the psql merge applies them as the Python merge applies the mesh, row for row,
    and says what the average discards as Python says it."""
    _conflict_at_two(conn, periods)
    tgsis.find_conflicts(conn, "e1")
    tgsis.resolve_region(conn, "e1", periods, 0, "average")
    conn.commit()
    assert conn.execute(
        "SELECT solution_vertex_ids IS NOT NULL FROM tgsis.conflict_regions WHERE objectkey = %s AND region = 0",
        (str(periods),),
    ).fetchall() == [(True,)]
    conn.rollback()
    with conn.transaction(force_rollback=True):
        (merged,) = tgsis.merge_version(conn, "e1").objects
    expected = [
        f"region {d.region} at geometry instant 2 of the period starting at 1: {d.solution} discards the {d.side}'s"
        f" edit there: {d.vertices} vertices, {d.cells} cells, largest displacement {d.max_displacement:.6g}"
        for d in merged.discards
    ]
    assert {d.side for d in merged.discards} == {"parent", "child"}
    notices: list[str] = []
    conn.add_notice_handler(lambda d: notices.append(str(d.message_primary)))
    mine = assert_same_merge(conn, "e1", action)
    assert mine[1] > 0
    said = [n.split(": ", 1)[1] for n in notices if n.startswith(f"feature {periods} of version 'e1': region")]
    assert said == expected


def test_two_evolving_surfaces_merged_by_region_in_one_psql_merge_one_solved_then_both(conn: Conn) -> None:
    """Two evolving surfaces with a conflict at a geometry instant each (the work tables of the first reused by
    the second): one solved, the merge refuses the other by name; both solved, both merge in psql as in Python."""
    first = make_periods(conn)
    second = tgsis.insert_feature(conn, "evolving", EvolvingSurface([_period(FIRST, 0), _period(SECOND, 2)]))
    conn.commit()
    tgsis.create_version(conn, "e2")
    conn.commit()
    for geoid in (first, second):
        ids = _node_ids(conn, geoid, 1.0)
        _move(conn, "e2", geoid, 1.0, 2.0, [ids[i] for i in NORTH], CHILD_SHIFT)
        _move(conn, "DEFAULT", geoid, 1.0, 2.0, [ids[i] for i in NORTH[:SIDE]], PARENT_SHIFT)
    conn.execute("SELECT FROM tgsis.find_conflicts('e2')")
    conn.execute("SELECT tgsis.resolve_region('e2', 'feature', %s, 0, 'child')", (str(first),))
    conn.commit()
    theirs, mine = both_merges(conn, "e2")
    assert theirs[:2] == mine[:2] == ("refused", "TG302"), (theirs, mine)
    assert f"feature {second}: region 0 at geometry instant 2.0 of the period starting at 1.0 unsolved" in mine[2]
    conn.execute("SELECT tgsis.resolve_region('e2', 'feature', %s, 0, 'parent')", (str(second),))
    conn.commit()
    assert_same_merge(conn, "e2")


@pytest.mark.parametrize(
    "statement",
    ["WITH m AS (SELECT tgsis.refresh_version('e1') AS n) SELECT n FROM m", "SELECT pg_temp.merge_it('e1')"],
    ids=["cte", "function"],
)
def test_a_psql_merge_by_region_in_a_cte_or_a_function_writes_what_python_writes(
    conn: Conn, periods: int, statement: str
) -> None:
    from tests.test_sql_merge_write import _outcome

    _conflict_at_two(conn, periods)
    solve(conn, "e1", periods, "child")
    theirs, _ = both_merges(conn, "e1", "refresh" if "refresh" in statement else "merge")
    conn.execute(
        "CREATE FUNCTION pg_temp.merge_it(v text) RETURNS bigint LANGUAGE sql AS $$ SELECT tgsis.merge_version(v) $$"
    )
    conn.commit()
    mine = _outcome(conn, lambda: int(conn.execute(statement).fetchone()[0]))  # type: ignore[index]
    assert theirs[0] == mine[0] == "done", mine
    assert mine[1] == theirs[1]
    for table in theirs[2]:
        assert mine[2][table] == theirs[2][table], table


# ---------------------------------------------------------------------------- average and manual of a geometry instant


def _average_state(conn: Conn, geoid: int) -> Any:
    """Region 0's average (geometry instant 2 of the period starting at 1), not recorded."""
    _conflict_at_two(conn, geoid)
    tgsis.find_conflicts(conn, "e1")
    conn.commit()
    state = tgsis.resolve_region(conn, "e1", geoid, 0, "average").state
    conn.rollback()
    assert state is not None
    return state


def _record_in_sql(conn: Conn, geoid: int, state: Any) -> None:
    """Record a manual state of region 0 as a psql user may: its .npz and its rows."""
    from tgsis.db.regions import _sql_rows, state_to_npz

    rows = _sql_rows(state)
    assert rows is not None
    conn.execute(
        "SELECT FROM tgsis.resolve_region('e1', 'feature', %s, 0, 'manual', %s, %s, %s::float8[], %s, %s,"
        " %s::text[], %s::float8[], %s::text[], %s::float8[])",
        (str(geoid), state_to_npz(state), *rows),
    )
    conn.commit()


@pytest.mark.parametrize("by", ["python", "psql"])
@pytest.mark.parametrize("action", ["merge", "refresh"])
def test_a_manual_mesh_of_a_region_of_a_geometry_instant_merges_in_psql_as_in_python(
    conn: Conn, periods: int, action: str, by: str
) -> None:
    """A manual mesh of the region (its average, one node lifted 3 m and its values changed), recorded by the Python
    client or by a psql user's resolve_region with its rows: both merges write the same rows."""
    state = _average_state(conn, periods)
    xyz = np.array(state.vertices, dtype=np.float64)
    xyz[0, 2] += 3.0
    values = {k: np.array(v, dtype=np.float64) for k, v in state.vertex_properties.items()}
    for column in values.values():
        column[0] += 0.125
    manual = dataclasses.replace(state, vertices=xyz, vertex_properties=values)
    if by == "python":
        tgsis.resolve_region(conn, "e1", periods, 0, "manual", manual)
        conn.commit()
    else:
        _record_in_sql(conn, periods, manual)
    assert_same_merge(conn, "e1", action)


def test_a_manual_mesh_that_re_meshes_one_geometry_instant_of_a_period_with_several_is_refused_as_in_python(
    conn: Conn, periods: int
) -> None:
    """Dropping a triangle of the region no side changed at geometry instant 2 of a period with three: the merged
    period would have two topologies, TG308 in both merges (the psql merge did not read that triangle at the other
    geometry instants: what the solution did to it is compared), nothing written."""
    state = _average_state(conn, periods)
    stored = conn.execute(
        "SELECT cell_ids, parent_cell_ids, child_cell_ids FROM tgsis.conflict_regions"
        " WHERE versionid = tgsis.version_id('e1') AND objectkey = %s AND region = 0",
        (str(periods),),
    ).fetchone()
    conn.rollback()
    assert stored is not None
    margin = sorted(set(stored[0]) - set(stored[1]) - set(stored[2]))
    assert margin
    keep = state.cell_ids != margin[0]
    holed = dataclasses.replace(
        state,
        cell_ids=state.cell_ids[keep],
        cells=state.cells[keep],
        cell_properties={k: np.asarray(v)[keep] for k, v in state.cell_properties.items()},
    )
    tgsis.resolve_region(conn, "e1", periods, 0, "manual", holed)
    conn.commit()
    before = everything(conn)
    conn.rollback()
    theirs, mine = both_merges(conn, "e1")
    assert theirs[0] == "refused" and "a period has one topology" in theirs[2], theirs
    assert mine[:2] == ("refused", "TG308"), mine
    assert "period starting at 1" in mine[2] and "a period has one topology" in mine[2], mine[2]
    assert everything(conn) == before


def test_a_manual_mesh_that_makes_an_invalid_geometry_instant_is_refused_in_psql_as_in_python(
    conn: Conn, periods: int
) -> None:
    """A manual mesh recorded from psql with a second triangle on the nodes of one of its triangles: merge3's
    validity check refuses the merged geometry instant in both merges, naming the same nodes, nothing written."""
    state = _average_state(conn, periods)
    broken = with_duplicated_triangle(state)
    _record_in_sql(conn, periods, broken)
    before = everything(conn)
    conn.commit()
    theirs, mine = both_merges(conn, "e1")
    assert theirs[0] == "refused" and mine[:2] == ("refused", "TG302"), (theirs, mine)
    key = ", ".join(str(v) for v in sorted(state.cells[0].tolist()))
    for said in (theirs[2], mine[2]):
        assert "invalid merge" in said and "duplicated triangles" in said and f"({key})" in said, said
        assert "geometry instant 2.0 of the period starting at 1.0" in said, said
    assert everything(conn) == before


def test_after_pg_dump_and_restore_an_average_of_a_geometry_instant_merges_in_psql_as_in_python(
    conn: Conn, periods: int, pg: Any, db_dsn: str, tmp_path: Any
) -> None:
    from tests.test_backup import _bindir_of, _restored

    _conflict_at_two(conn, periods)
    tgsis.find_conflicts(conn, "e1")
    tgsis.resolve_region(conn, "e1", periods, 0, "average")
    conn.commit()
    with _restored(pg, _bindir_of(pg), db_dsn, "custom", tmp_path) as dsn, psycopg.connect(dsn) as restored:
        assert_same_merge(restored, "e1")
