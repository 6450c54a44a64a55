"""Hostile review of the psql merge of an evolving surface (model 3) by its regions (issue 39, review R39).

Shapes the authors' tests (tests/test_sql_merge_period_regions.py) did not cover: several geometry instants of
one period each with a conflicting region solved otherwise, a depth-positive class, node ids far from 0..n-1 in
a topology change beside the other side's moves, integer and real property columns with NaN and -0, the
per-instant properties changed beside an instant merged by region, a solution recorded before a side wrote
again, odd session settings and a SERIALIZABLE transaction, a role that may not read a property view. The
oracle is the Python merge (row version by row version) and the Python find_conflicts.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import psycopg
import pytest

import tgsis
from tests.merge_data import SIDE
from tests.roles import merges_as
from tests.storage_data import tables_as_rows
from tests.test_merge_instants import CHILD_SHIFT, MIDDLE, NORTH, PARENT_SHIFT, SOUTH
from tests.test_sql_merge_instant_regions import assert_same_regions
from tests.test_sql_merge_periods import _move, _node_ids, _sql
from tests.test_sql_merge_write import assert_same_merge, both_merges

Conn = psycopg.Connection[Any]


@pytest.fixture
def periods(conn: Conn, periods_clone: int) -> int:
    return periods_clone  # make_periods's, built once (tests/conftest.py)


def _conflict(conn: Conn, geoid: int, m: float, t: float) -> None:
    ids = _node_ids(conn, geoid, m)
    _move(conn, "e1", geoid, m, t, [ids[i] for i in NORTH], CHILD_SHIFT)
    _move(conn, "DEFAULT", geoid, m, t, [ids[i] for i in NORTH[:SIDE]], PARENT_SHIFT)
    _move(conn, "DEFAULT", geoid, m, t, [ids[i] for i in SOUTH], PARENT_SHIFT)


def _solve(conn: Conn, geoid: int, solutions: dict[tuple[float, float], str]) -> None:
    conn.execute("SELECT FROM tgsis.find_conflicts('e1')")
    rows = conn.execute(
        "SELECT region, timem, times FROM tgsis.conflict_regions WHERE versionid = tgsis.version_id('e1')"
        " AND objectkey = %s AND conflict ORDER BY region",
        (str(geoid),),
    ).fetchall()
    assert {(float(r[1]), float(r[2])) for r in rows} == set(solutions), rows
    for region, m, t in rows:
        conn.execute(
            "SELECT tgsis.resolve_region('e1', 'feature', %s, %s, %s)",
            (str(geoid), region, solutions[(float(m), float(t))]),
        )
    conn.commit()


@pytest.mark.parametrize("action", ["merge", "refresh"])
def test_conflicts_at_several_geometry_instants_of_both_periods_solved_each_otherwise(
    conn: Conn, periods: int, action: str
) -> None:
    plan = {(1.0, 1.0): "parent", (1.0, 2.0): "child", (3.0, 4.0): "base", (3.0, 5.0): "child"}
    for m, t in plan:
        _conflict(conn, periods, m, t)
    assert_same_regions(conn, "e1", periods)
    _solve(conn, periods, plan)
    assert_same_merge(conn, "e1", action)


def test_a_depth_positive_evolving_surface_merged_by_region(conn: Conn, periods: int) -> None:
    _sql(conn, "DEFAULT", "UPDATE tgsis.geometry SET zpositive = 'Depth' WHERE geoid = %s", (periods,))
    _conflict(conn, periods, 1.0, 2.0)
    assert_same_regions(conn, "e1", periods)
    _solve(conn, periods, {(1.0, 2.0): "child"})
    assert_same_merge(conn, "e1")


def test_per_instant_properties_changed_beside_a_geometry_instant_merged_by_region(conn: Conn, periods: int) -> None:
    _conflict(conn, periods, 1.0, 2.0)
    _sql(conn, "DEFAULT", "UPDATE evolving_pros SET throw = -0.0 WHERE _geoid = %s AND _timet = 2", (periods,))
    _sql(conn, "e1", "UPDATE evolving_pros SET throw = 'NaN' WHERE _geoid = %s AND _timet = 4", (periods,))
    _solve(conn, periods, {(1.0, 2.0): "parent"})
    assert_same_merge(conn, "e1")
    assert_same_merge(conn, "e1", "refresh")


@pytest.mark.parametrize("writer", ["DEFAULT", "e1"])
def test_a_solution_recorded_before_a_side_wrote_again_at_that_geometry_instant(
    conn: Conn, periods: int, writer: str
) -> None:
    _conflict(conn, periods, 1.0, 2.0)
    _solve(conn, periods, {(1.0, 2.0): "child"})
    ids = _node_ids(conn, periods, 1.0)
    _move(conn, writer, periods, 1.0, 2.0, [ids[i] for i in MIDDLE], (0.5, -0.25, 0.75))
    theirs, mine = both_merges(conn, "e1")
    assert mine[:2] == theirs[:2], (theirs[:3], mine[:3])


def _rows_for_ids_far_from_0_to_n(conn: Conn) -> None:
    """Model 3's geometry tables as rows: a negative node id is a rows case (chunks refuse it by name, TG100,
    docs/storage.md), so the tests of ids far from 0..n run on rows whatever
    ``TGSIS_TEST_TIME_STORAGE`` made the tables."""
    tables_as_rows(conn, ("d4dvrtx", "d4dtrgl"))


def test_node_ids_far_from_0_to_n_added_by_a_topology_change_beside_the_parents_moves(conn: Conn, periods: int) -> None:
    """The version adds nodes -7 and 2**53 + 1 to the first period (at each of its geometry instants) and a
    triangle on them; the parent moves nodes at geometry instant 2 apart: that slice merges by its regions."""
    _rows_for_ids_far_from_0_to_n(conn)
    ids = _node_ids(conn, periods, 1.0)
    big = 2**53 + 1
    for t in (1.0, 2.0, 3.0):
        for nid, dx in ((-7, 0.25), (big, 0.5)):
            _sql(
                conn,
                "e1",
                "INSERT INTO tgsis.d4dvrtx (geoid, timem, timet, nodeid, x, y, z)"
                " SELECT geoid, timem, timet, %s, x + %s, y, z FROM tgsis.d4dvrtx"
                " WHERE geoid = %s AND timem = 1 AND timet = %s AND nodeid = %s",
                (nid, dx, periods, t, ids[5]),
            )
    _sql(
        conn,
        "e1",
        "INSERT INTO tgsis.d4dtrgl (geoid, timem, trglid, nodeid1, nodeid2, nodeid3) VALUES (%s, 1, 9000, %s, -7, %s)",
        (periods, ids[5], big),
    )
    _move(conn, "DEFAULT", periods, 1.0, 2.0, [ids[i] for i in SOUTH], PARENT_SHIFT)
    assert_same_regions(conn, "e1", periods)
    assert_same_merge(conn, "e1")


@pytest.mark.parametrize(
    "settings",
    [
        "SET TRANSACTION ISOLATION LEVEL SERIALIZABLE",
        "SET LOCAL extra_float_digits = -15; SET LOCAL DateStyle = 'SQL, DMY'; SET LOCAL jit = on",
        "SET LOCAL enable_indexscan = off; SET LOCAL enable_bitmapscan = off; SET LOCAL jit = off",
        "SET LOCAL search_path = public, pg_temp; SET LOCAL lc_numeric = 'C'; SET LOCAL work_mem = '64kB'",
    ],
    ids=["serializable", "floats-dates", "no-index", "path-memory"],
)
def test_a_geometry_instant_merged_by_region_under_odd_session_settings(
    conn: Conn, periods: int, settings: str
) -> None:
    from tests.test_sql_merge_write import _outcome

    _conflict(conn, periods, 1.0, 2.0)
    _solve(conn, periods, {(1.0, 2.0): "child"})
    theirs, _ = both_merges(conn, "e1")

    def odd() -> int:
        for s in settings.split("; "):
            conn.execute(s)
        return int(conn.execute("SELECT tgsis.merge_version('e1')").fetchone()[0])  # type: ignore[index]

    mine = _outcome(conn, odd)
    if settings.startswith("SET TRANSACTION"):
        assert mine[0] == "refused", mine
        return
    assert mine[0] == theirs[0] == "done", mine
    assert mine[1] == theirs[1]
    for table in theirs[2]:
        assert mine[2][table] == theirs[2][table], table


@pytest.mark.parametrize("table", ["evolving_cellpros", "evolving_pros"])
def test_a_role_that_may_not_read_a_property_view_merges_by_region_only_as_python(
    conn: Conn, periods: int, db_dsn: str, table: str
) -> None:
    from tests.roles import login_roles

    _conflict(conn, periods, 1.0, 2.0)
    _solve(conn, periods, {(1.0, 2.0): "child"})
    with login_roles(db_dsn, {"ed": "tgsis_editor"}) as made:
        tgsis.grant_version(conn, "e1", "all", made.name("ed"))
        tgsis.grant_version(conn, "DEFAULT", "merge", made.name("ed"))
        conn.execute(f"REVOKE SELECT ON public.{table} FROM tgsis_editor, tgsis_reader")
        conn.commit()
        session = made.connect("ed")
        theirs, mine = merges_as(conn, session, "e1", message=True)
        assert mine[:2] == theirs[:2], (theirs, mine)


@pytest.mark.parametrize("table", ["none", "evolving_cellpros", "evolving_pros"])
def test_a_role_that_may_not_read_a_property_view_finds_the_regions_as_python(
    conn: Conn, periods: int, db_dsn: str, table: str
) -> None:
    from tests.roles import login_roles
    from tests.test_sql_merge_instant_regions import _stored

    _conflict(conn, periods, 1.0, 2.0)
    with login_roles(db_dsn, {"ed": "tgsis_editor"}) as made:
        tgsis.grant_version(conn, "e1", "all", made.name("ed"))
        if table != "none":
            conn.execute(f"REVOKE SELECT ON public.{table} FROM tgsis_editor, tgsis_reader")
        conn.commit()
        session = made.connect("ed")

        def found(run: Any) -> Any:
            try:
                run()
                session.commit()
                return _stored(conn, "e1", periods)
            except (psycopg.Error, tgsis.Error) as exc:
                return ("refused", exc.sqlstate)
            finally:
                session.rollback()
                conn.rollback()
                conn.execute("DELETE FROM tgsis.conflict_regions WHERE versionid = tgsis.version_id('e1')")
                conn.execute("DELETE FROM tgsis.conflicts WHERE versionid = tgsis.version_id('e1')")
                conn.commit()

        mine = found(lambda: session.execute("SELECT FROM tgsis.find_conflicts('e1')"))
        theirs = found(lambda: tgsis.find_conflicts(session, "e1"))
        assert mine == theirs, (theirs, mine)
        if table == "none":
            assert len(mine) == 2, mine


@pytest.mark.parametrize("table", ["horizons_cellpros", "horizons_pros"])
def test_a_role_that_may_not_read_a_property_view_finds_the_regions_of_instants_as_python(
    conn: Conn, db_dsn: str, series_clone: int, table: str
) -> None:
    """The same for a surface at instants (model 2): the SQL find_conflicts stored its regions for that role."""
    from tests.roles import login_roles
    from tests.test_merge_instants import move
    from tests.test_sql_merge_instant_regions import _stored

    series = series_clone  # make_series's, built once (tests/conftest.py)
    move(conn, "e1", series, 2.0, NORTH, CHILD_SHIFT)
    move(conn, "DEFAULT", series, 2.0, NORTH[:SIDE], PARENT_SHIFT)
    with login_roles(db_dsn, {"ed": "tgsis_editor"}) as made:
        tgsis.grant_version(conn, "e1", "all", made.name("ed"))
        conn.execute(f"REVOKE SELECT ON public.{table} FROM tgsis_editor, tgsis_reader")
        conn.commit()
        session = made.connect("ed")
        stored = []
        for run in (
            lambda: session.execute("SELECT FROM tgsis.find_conflicts('e1')"),
            lambda: tgsis.find_conflicts(session, "e1"),
        ):
            run()
            session.commit()
            stored.append(_stored(conn, "e1", series))
            conn.execute("DELETE FROM tgsis.conflict_regions WHERE versionid = tgsis.version_id('e1')")
            conn.execute("DELETE FROM tgsis.conflicts WHERE versionid = tgsis.version_id('e1')")
            conn.commit()
        assert stored[0] == stored[1] == [], stored


@pytest.mark.parametrize("alignment", ["VERTEX", "CELL"])
def test_integer_and_real_properties_of_an_evolving_surface_merge_by_region_as_in_python(
    conn: Conn, alignment: str
) -> None:
    from tests.merge_data import curved_surface
    from tests.test_merge_instants import _shape
    from tgsis.temporal import EvolvingSurface, TopologyPeriod

    tgsis.create_feature_class(
        conn,
        "counts",
        "SURFACE",
        time_model="EVOLVING",
        alignment=alignment,  # type: ignore[arg-type]
        cell_properties=[("n", "integer"), ("k", "bigint"), ("w", "real")],
    )
    tgsis.enable_feature_versioning(conn)
    cells = curved_surface().cells
    size = SIDE * SIDE if alignment == "VERTEX" else len(cells)
    times = (1.0, 2.0, 3.0)
    values: dict[str, Any] = {
        "n": np.stack([np.arange(size, dtype=np.int32)] * 3),
        "k": np.stack([np.arange(size, dtype=np.int64) * 3 - 2**40] * 3),
        "w": np.stack([np.linspace(0, 1, size).astype(np.float32)] * 3),
    }
    period = TopologyPeriod(
        np.asarray(times),
        cells,
        np.stack([_shape(i) for i in range(3)]),
        vertex_properties=values if alignment == "VERTEX" else None,
        cell_properties=values if alignment == "CELL" else None,
    )
    geoid = int(tgsis.insert_feature(conn, "counts", EvolvingSurface([period])))
    tgsis.create_version(conn, "e1")
    conn.commit()
    ids = _node_ids(conn, geoid, 1.0)
    _move(conn, "e1", geoid, 1.0, 2.0, [ids[i] for i in NORTH], CHILD_SHIFT)
    _move(conn, "DEFAULT", geoid, 1.0, 2.0, [ids[i] for i in SOUTH], PARENT_SHIFT)
    t = "counts_cellpros"
    _sql(conn, "e1", f"UPDATE {t} SET n = n + 1000, w = -0.0 WHERE _geoid = %s AND _timet = 2 AND _idx < 5", (geoid,))
    _sql(conn, "DEFAULT", f"UPDATE {t} SET w = 'NaN' WHERE _geoid = %s AND _timet = 2 AND _idx > 100", (geoid,))
    _sql(conn, "DEFAULT", f"UPDATE {t} SET n = -n, k = k + 1 WHERE _geoid = %s AND _timet = 2 AND _idx = 3", (geoid,))
    assert_same_regions(conn, "e1", geoid)
    conn.execute("SELECT FROM tgsis.find_conflicts('e1')")
    for (region,) in conn.execute(
        "SELECT region FROM tgsis.conflict_regions WHERE versionid = tgsis.version_id('e1') AND conflict"
    ).fetchall():
        conn.execute("SELECT tgsis.resolve_region('e1', 'feature', %s, %s, 'parent')", (str(geoid), region))
    conn.commit()
    assert_same_merge(conn, "e1")


# each: steps beside geometry instant 2 of the first period, which both sides change apart (north / south)
_BESIDE: dict[str, list[tuple[str, str]]] = {
    "the version changes the second period's topology": [("e1", "topology 3 4")],
    "the parent changes the second period's topology": [("DEFAULT", "topology 3 4")],
    "the version adds a geometry instant to the first period": [("e1", "add-instant 1 1 1.5")],
    "the parent removes geometry instant 1": [("DEFAULT", "drop-instant 1 1")],
    # (its tgsis.timet row closed and written anew: in chunks the engine keeps every slot of the period's changed
    # chunks as keys, as merge_periods_by_slice reads the period whole, not the slots that differ only)
    "the version removes geometry instant 2 and adds it anew": [
        ("e1", "drop-instant 1 2"),
        ("e1", "add-instant 1 1 2"),
    ],
    "the version removes the second period": [("e1", "drop-period 3")],
    "the parent appends a period": [("DEFAULT", "append")],
    "the version changes values and throw at 2": [("e1", "values 1 2"), ("e1", "throw 1 2 -0.0")],
    "the parent changes values at 2, the version its throw": [("DEFAULT", "values 1 2"), ("e1", "throw 1 2 5.5")],
    "both move the same nodes alike at 1": [("e1", "same 1 1 north"), ("DEFAULT", "same 1 1 north")],
}


@pytest.mark.parametrize("beside", sorted(_BESIDE))
@pytest.mark.parametrize("action", ["merge", "refresh"])
def test_a_geometry_instant_merged_by_region_beside_other_edits(
    conn: Conn, periods: int, beside: str, action: str
) -> None:
    from tests.test_sql_merge_periods import step

    for version, what in _BESIDE[beside]:
        step(conn, version, what, periods)
    step(conn, "e1", "move 1 2 north", periods)
    step(conn, "DEFAULT", "move 1 2 south", periods)
    assert_same_regions(conn, "e1", periods)
    theirs, mine = both_merges(conn, "e1", action)
    assert mine[:2] == theirs[:2], (theirs[:3], mine[:3])
    if theirs[0] == "done":
        for table in theirs[2]:
            assert mine[2][table] == theirs[2][table], table


def test_a_reader_finds_and_stores_the_regions_of_geometry_instants_as_python(
    conn: Conn, periods: int, db_dsn: str
) -> None:
    from tests.roles import login_roles
    from tests.test_sql_merge_instant_regions import _stored

    _conflict(conn, periods, 1.0, 2.0)
    ids = _node_ids(conn, periods, 3.0)
    _move(conn, "e1", periods, 3.0, 4.0, [ids[i] for i in NORTH], CHILD_SHIFT)
    _move(conn, "DEFAULT", periods, 3.0, 4.0, [ids[i] for i in SOUTH], PARENT_SHIFT)
    with login_roles(db_dsn, {"rd": "tgsis_reader"}) as made:
        session = made.connect("rd")
        session.execute("SELECT FROM tgsis.find_conflicts('e1')")
        mine = _stored(session, "e1", periods)
        session.rollback()
        tgsis.find_conflicts(session, "e1")
        theirs = _stored(session, "e1", periods)
        session.rollback()
        assert mine == theirs


@pytest.mark.parametrize("digits", ["1", "0", "-15"])
def test_an_unsolved_region_at_geometry_instants_of_no_short_decimal_is_named_as_python_names_it(
    conn: Conn, digits: str
) -> None:
    """Geometry instants 0.1, 0.2 and 0.1 + 0.2 (0.30000000000000004): the psql refusal names the unsolved region's
    geometry instant and period as the Python merge does, whatever the session's extra_float_digits; SQL
    find_conflicts stores the same regions."""
    from tests.merge_data import curved_surface
    from tests.test_merge_instants import _shape
    from tgsis.temporal import EvolvingSurface, TopologyPeriod

    tgsis.create_feature_class(conn, "tenths", "SURFACE", time_model="EVOLVING")
    tgsis.enable_feature_versioning(conn)
    times = (0.1, 0.2, 0.1 + 0.2)
    period = TopologyPeriod(np.asarray(times), curved_surface().cells, np.stack([_shape(i) for i in range(3)]))
    geoid = int(tgsis.insert_feature(conn, "tenths", EvolvingSurface([period])))
    tgsis.create_version(conn, "e1")
    conn.commit()
    _conflict(conn, geoid, 0.1, 0.1 + 0.2)
    assert_same_regions(conn, "e1", geoid)
    conn.execute(f"SET extra_float_digits = {digits}")
    conn.commit()
    theirs, mine = both_merges(conn, "e1")
    conn.execute("RESET extra_float_digits")
    conn.commit()
    assert theirs[:2] == mine[:2] == ("refused", "TG302"), (theirs, mine)
    named = "region 0 at geometry instant 0.30000000000000004 of the period starting at 0.1 unsolved"
    assert named in theirs[2], theirs
    assert named in mine[2], mine


@pytest.mark.parametrize("action", ["merge", "refresh"])
def test_regions_stored_by_the_python_find_conflicts_solved_in_psql_then_merged_in_psql(
    conn: Conn, periods: int, action: str
) -> None:
    _conflict(conn, periods, 1.0, 2.0)
    _conflict(conn, periods, 3.0, 4.0)
    tgsis.find_conflicts(conn, "e1")
    conn.commit()
    rows = conn.execute(
        "SELECT region, timem FROM tgsis.conflict_regions WHERE versionid = tgsis.version_id('e1') AND conflict"
        " ORDER BY region"
    ).fetchall()
    assert len(rows) == 2, rows
    for region, m in rows:
        conn.execute(
            "SELECT tgsis.resolve_region('e1', 'feature', %s, %s, %s)",
            (str(periods), region, "child" if m == 1.0 else "base"),
        )
    conn.commit()
    assert_same_merge(conn, "e1", action)


@pytest.mark.parametrize("solution", ["none", "parent", "child", "base"])
def test_new_nodes_far_from_0_to_n_in_a_conflict_with_the_parents_moves(
    conn: Conn, periods: int, solution: str
) -> None:
    """The version adds nodes -7 and 2**53 + 1 and a triangle on them (the first period's topology); the parent moves
    the nodes around them at geometry instant 2: a conflict there, maybe solved (TG308 when a solution gives that
    geometry instant another topology than the period's others)."""
    _rows_for_ids_far_from_0_to_n(conn)
    ids = _node_ids(conn, periods, 1.0)
    big = 2**53 + 1
    for t in (1.0, 2.0, 3.0):
        for nid, dx in ((-7, 0.25), (big, 0.5)):
            _sql(
                conn,
                "e1",
                "INSERT INTO tgsis.d4dvrtx (geoid, timem, timet, nodeid, x, y, z)"
                " SELECT geoid, timem, timet, %s, x + %s, y, z FROM tgsis.d4dvrtx"
                " WHERE geoid = %s AND timem = 1 AND timet = %s AND nodeid = %s",
                (nid, dx, periods, t, ids[5]),
            )
    _sql(
        conn,
        "e1",
        "INSERT INTO tgsis.d4dtrgl (geoid, timem, trglid, nodeid1, nodeid2, nodeid3) VALUES (%s, 1, 9000, %s, -7, %s)",
        (periods, ids[5], big),
    )
    _move(conn, "DEFAULT", periods, 1.0, 2.0, [ids[i] for i in range(12)], PARENT_SHIFT)
    assert_same_regions(conn, "e1", periods)
    if solution != "none":
        conn.execute("SELECT FROM tgsis.find_conflicts('e1')")
        n = conn.execute(
            "SELECT count(*) FROM tgsis.conflict_regions WHERE versionid = tgsis.version_id('e1') AND conflict"
        ).fetchone()
        conn.rollback()
        if n is not None and n[0] > 0:
            from tests.test_sql_merge_write import solve

            solve(conn, "e1", periods, solution)
    for action in ("merge", "refresh"):
        theirs, mine = both_merges(conn, "e1", action)
        assert mine[:2] == theirs[:2], (theirs[:3], mine[:3])
        if theirs[0] == "done":
            for table in theirs[2]:
                assert mine[2][table] == theirs[2][table], table


@pytest.mark.parametrize("remover", ["e1", "DEFAULT"])
@pytest.mark.parametrize("near", [False, True])
def test_a_node_removed_from_a_period_on_one_side_the_other_moving_nodes_at_a_geometry_instant(
    conn: Conn, periods: int, remover: str, near: bool
) -> None:
    """One side removes a corner node of the first period (its triangles, its rows at each geometry instant, its
    property rows, its row in tgsis.node); the other moves nodes at geometry instant 2, near it or apart."""
    ids = _node_ids(conn, periods, 1.0)
    for m in (1.0, 3.0):  # (from both periods: the second starts where the first ends)
        corner = _node_ids(conn, periods, m)[0]
        _sql(
            conn,
            remover,
            "DELETE FROM tgsis.d4dtrgl WHERE geoid = %s AND timem = %s AND %s IN (nodeid1, nodeid2, nodeid3)",
            (periods, m, corner),
        )
        for table in ("d4dvrtx", "node"):
            _sql(
                conn,
                remover,
                f"DELETE FROM tgsis.{table} WHERE geoid = %s AND timem = %s AND nodeid = %s",
                (periods, m, corner),
            )
        _sql(
            conn,
            remover,
            "DELETE FROM evolving_cellpros WHERE _geoid = %s AND _timem = %s AND _idx = %s",
            (periods, m, corner),
        )
    other = "DEFAULT" if remover == "e1" else "e1"
    rows = [1, 2, SIDE, SIDE + 1] if near else list(SOUTH)
    _move(conn, other, periods, 1.0, 2.0, [ids[i] for i in rows], PARENT_SHIFT if other == "DEFAULT" else CHILD_SHIFT)
    _move(conn, remover, periods, 1.0, 2.0, [ids[i] for i in NORTH[SIDE:]], (0.0, 0.0, 0.5))
    assert_same_regions(conn, "e1", periods)
    for action in ("merge", "refresh"):
        theirs, mine = both_merges(conn, "e1", action)
        assert mine[:2] == theirs[:2], (theirs[:3], mine[:3])
        if theirs[0] == "done":
            for table in theirs[2]:
                assert mine[2][table] == theirs[2][table], table


@pytest.mark.parametrize("table", ["d4dtrgl", "node", "d4dvrtx"])
@pytest.mark.parametrize("revoked", ["DELETE", "INSERT"])
def test_a_role_that_may_not_write_the_triangles_the_parent_removed_beside_a_geometry_instant_merged_by_region(
    conn: Conn, periods: int, db_dsn: str, table: str, revoked: str
) -> None:
    """The parent removes triangles (and a corner node) of both periods and moves nodes at geometry instant 2; the
    version moves others there: the merge writes the parent's removal into the version through the model's views.
    A role without that right is refused as the Python merge refuses it (42501), nothing written."""
    from psycopg import sql

    from tests.roles import login_roles
    from tests.test_sql_merge_write import everything

    ids = _node_ids(conn, periods, 1.0)
    for m in (1.0, 3.0):
        corner = _node_ids(conn, periods, m)[0]
        _sql(
            conn,
            "DEFAULT",
            "DELETE FROM tgsis.d4dtrgl WHERE geoid = %s AND timem = %s AND %s IN (nodeid1, nodeid2, nodeid3)",
            (periods, m, corner),
        )
        for t in ("d4dvrtx", "node"):
            _sql(
                conn,
                "DEFAULT",
                f"DELETE FROM tgsis.{t} WHERE geoid = %s AND timem = %s AND nodeid = %s",
                (periods, m, corner),
            )
        _sql(
            conn,
            "DEFAULT",
            "DELETE FROM evolving_cellpros WHERE _geoid = %s AND _timem = %s AND _idx = %s",
            (periods, m, corner),
        )
    _move(conn, "DEFAULT", periods, 1.0, 2.0, [ids[i] for i in SOUTH], PARENT_SHIFT)
    _move(conn, "e1", periods, 1.0, 2.0, [ids[i] for i in MIDDLE], CHILD_SHIFT)
    with login_roles(db_dsn, {"ed": "tgsis_editor"}) as made:
        tgsis.grant_version(conn, "e1", "all", made.name("ed"))
        tgsis.grant_version(conn, "DEFAULT", "merge", made.name("ed"))
        conn.execute(
            sql.SQL("REVOKE {} ON {} FROM tgsis_editor").format(sql.SQL(revoked), sql.Identifier("tgsis", table))
        )
        conn.commit()
        before = everything(conn)
        conn.commit()
        session = made.connect("ed")
        theirs, mine = merges_as(conn, session, "e1")
        assert everything(conn) == before
        conn.commit()
        assert mine[:2] == theirs[:2], (theirs, mine)


# ---------------------------------------------------------------------------------------- cost: rows read


def _evolving_grid_edited(conn: Conn, n: int) -> int:
    """A n x n grid, one topology period of 3 geometry instants (1, 2, 3); each side moves one node of geometry
    instant 2, apart; VACUUMed (BRINs summarized)."""
    from tests.test_sql_merge_instant_regions_hostile import _grid
    from tgsis.temporal import EvolvingSurface, TopologyPeriod

    tgsis.create_feature_class(
        conn, "egrid", "SURFACE", time_model="EVOLVING", cell_properties=[("porosity", "float8")]
    )
    tgsis.enable_feature_versioning(conn)
    shapes = [_grid(n, i) for i in range(3)]
    period = TopologyPeriod(
        np.asarray([1.0, 2.0, 3.0]),
        shapes[0].cells,
        np.stack([s.vertices for s in shapes]),
        vertex_properties={"porosity": np.stack([s.vertex_properties["porosity"] for s in shapes])},
    )
    geoid = int(tgsis.insert_feature(conn, "egrid", EvolvingSurface([period])))
    tgsis.create_version(conn, "e1")
    conn.commit()
    ids = _node_ids(conn, geoid, 1.0)
    _move(conn, "e1", geoid, 1.0, 2.0, [ids[n * 10 + 10]], CHILD_SHIFT)
    _move(conn, "DEFAULT", geoid, 1.0, 2.0, [ids[n * 90 + 90]], PARENT_SHIFT)
    conn.autocommit = True
    conn.execute("VACUUM ANALYZE")
    conn.autocommit = False
    return geoid


def _evolving_rows_read(conn: Conn) -> dict[str, int]:
    return {
        str(r[0]): int(r[1])
        for r in conn.execute(
            "SELECT relname, coalesce(seq_tup_read, 0) + coalesce(idx_tup_fetch, 0) FROM pg_stat_xact_user_tables"
            " WHERE relname LIKE 'd4d%' OR relname LIKE 'node%' OR relname LIKE 'egrid%'"
        ).fetchall()
    }


_ON_ROWS = (
    "on rows the psql steps read more model-3 geometry rows than one geometry instant holds (PG15 2026-12-08: "
    "find_conflicts 10,878 d4dvrtx and 46,172 d4dtrgl rows, the merge 50,527 and 75,007), as model 2's do on rows "
    "(test_sql_merge_instant_regions_hostile: the revision BRIN's last page range read whole by each search of the "
    "changed rows, the recount); what reads them was not taken apart here. Known, docs/performance.md"
)


@pytest.mark.parametrize("step", ["find_conflicts", "merge"])
def test_a_one_node_edit_on_each_side_of_one_geometry_instant_reads_rows_proportional_to_the_change(
    conn: Conn, step: str
) -> None:
    """A 100 x 100 evolving grid (one period, 3 geometry instants); each side moves one node of geometry instant 2,
    apart: the psql step reads fewer rows of the model-3 geometry tables (tgsis.d4dvrtx, tgsis.d4dtrgl) than one
    geometry instant holds (n*n nodes), as model 2's instant does (test_sql_merge_instant_regions_hostile).

    In chunks (TGSIS_TEST_TIME_STORAGE=chunks) the changed keys of the period are the slots that differ between
    base, parent and version (tgsis.storage_changed_rows) in tgsis.merge_periods_by_slice and
    tgsis.mesh_merge_work alike; every slot of a changed chunk was a key, read with its rows at each geometry
    instant: 197,268 and 198,178 chunk rows before (PG15, 2026-12-08, docs/performance.md). Not counted: the class's
    property table's revision BRIN's last page range and the recount's count of tgsis.node (rows in both storages),
    the known costs of model 2's test."""
    n = 100
    _evolving_grid_edited(conn, n)
    rows = conn.execute("SELECT tgsis.stored_in_chunks('d4dvrtx')").fetchone() == (False,)
    conn.rollback()
    sql = "SELECT tgsis.merge_version('e1')" if step == "merge" else "SELECT FROM tgsis.find_conflicts('e1')"
    before = _evolving_rows_read(conn)
    conn.execute(sql)
    after = _evolving_rows_read(conn)
    conn.rollback()
    read = {k: after[k] - before.get(k, 0) for k in after if after[k] != before.get(k, 0)}
    geometry = sum(v for k, v in read.items() if k.startswith("d4d"))
    if rows:
        assert geometry >= n * n, f"{step} reads {read} rows on rows now: take the expected failure away"
        pytest.xfail(_ON_ROWS)
    assert 0 < geometry < n * n, read
