"""The psql merge of model-3 surfaces (evolving surfaces), period by period (issue 39).

A psql user's ``SELECT tgsis.merge_version(v)`` / ``tgsis.refresh_version(v)``
merges an evolving surface whose topology periods and geometry instants were
each changed on one side only (or alike on both): a period appended or
removed on one side, a geometry instant added, removed or moved on one side,
a period's topology changed on one side with the other side's edits in
another period, property rows, the per-instant feature properties column by
column (docs/merge.md, "Model 3 from psql"). The oracle is the Python merge
(``tgsis.merge_version(conn, v)``), row version for row version
(tests.test_sql_merge_write.both_merges). A geometry instant changed on both
sides differently (its regions) is refused from psql (TG302) naming
``tgsis version merge NAME``; what the Python merge leaves unsolved or
refuses (TG308) is refused alike, nothing written.
"""

from __future__ import annotations

import itertools
from typing import Any

import numpy as np
import psycopg
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from psycopg import sql

import tgsis
from tests.merge_data import curved_surface
from tests.roles import merges_as
from tests.test_merge_instants import CHILD_SHIFT, NORTH, PARENT_SHIFT, SOUTH, _porosity, _shape
from tests.test_sql_merge_write import _outcome, assert_same_merge, both_merges, everything
from tgsis.temporal import EvolvingSurface, TopologyPeriod

Conn = psycopg.Connection[Any]

FIRST = (1.0, 2.0, 3.0)  # the first period's geometry instants
SECOND = (3.0, 4.0, 5.0)  # the second's: it starts on the first's last shape


def _period(times: tuple[float, ...], start: int, lift: float = 0.0) -> TopologyPeriod:
    positions = np.stack([_shape(start + i) + np.array([0.0, 0.0, lift * i]) for i in range(len(times))])
    return TopologyPeriod(
        np.asarray(times),
        curved_surface().cells,
        positions,
        vertex_properties={"porosity": np.stack([_porosity() * (1.0 + i) for i in range(len(times))])},
        properties={"throw": np.asarray([10.0 * (start + i + 1) for i in range(len(times))])},
    )


def make_periods(conn: Conn) -> int:
    """A model-3 surface of two topology periods (a vertex property, a per-instant property) in DEFAULT, version e1."""
    tgsis.create_feature_class(
        conn,
        "evolving",
        "SURFACE",
        time_model="EVOLVING",
        cell_properties=[("porosity", "float8")],
        instant_properties=[("throw", "double precision")],
    )
    tgsis.enable_feature_versioning(conn)
    second = _period(SECOND, 2)
    first = _period(FIRST, 0)
    geoid = tgsis.insert_feature(conn, "evolving", EvolvingSurface([first, second], name="evolving fault"))
    tgsis.create_version(conn, "e1")
    conn.commit()
    return geoid


@pytest.fixture
def periods(conn: Conn, periods_clone: int) -> int:
    return periods_clone  # make_periods's, built once (tests/conftest.py)


def _sql(conn: Conn, version: str, text: str, args: tuple[Any, ...] = ()) -> None:
    """One statement a psql user runs in ``version`` (committed)."""
    with tgsis.in_version(conn, version):
        conn.execute(text, args)
    conn.commit()


def _move(conn: Conn, version: str, geoid: int, m: float, t: float, ids: Any, shift: tuple[float, ...]) -> None:
    _sql(
        conn,
        version,
        "UPDATE tgsis.d4dvrtx SET x = x + %s, y = y + %s, z = z + %s"
        " WHERE geoid = %s AND timem = %s AND timet = %s AND nodeid = ANY(%s)",
        (*shift, geoid, m, t, [int(i) for i in np.asarray(ids)]),
    )


def _node_ids(conn: Conn, geoid: int, m: float) -> list[int]:
    with tgsis.in_version(conn, "DEFAULT"):
        rows = conn.execute(
            "SELECT nodeid FROM tgsis.node WHERE geoid = %s AND timem = %s ORDER BY nodeid", (geoid, m)
        ).fetchall()
    conn.commit()
    return [int(r[0]) for r in rows]


def step(conn: Conn, version: str, step: str, geoid: int) -> None:
    """One side's edit, as a psql user (or the Python client) makes it; committed."""
    what, *args = step.split()
    shift = CHILD_SHIFT if version != "DEFAULT" or what == "same" else PARENT_SHIFT
    if what in ("move", "same"):  # move M T north|south: nodes of the period starting at M at instant T
        m, t = float(args[0]), float(args[1])
        ids = np.asarray(_node_ids(conn, geoid, m))
        rows = NORTH if args[2] == "north" else SOUTH
        _move(conn, version, geoid, m, t, ids[rows], shift)
    elif what == "append":  # a third period, starting on the second's last shape
        with tgsis.in_version(conn, version):
            tgsis.append_period(conn, "evolving", geoid, _period((5.0, 6.5), 4, lift=0.25 if args else 0.5))
        conn.commit()
    elif what == "drop-period":  # the period starting at M removed, as a psql user removes it
        m = float(args[0])
        for table in ("d4dvrtx", "d4dtrgl", "node", "timet", "timem"):
            _sql(conn, version, f"DELETE FROM tgsis.{table} WHERE geoid = %s AND timem = %s", (geoid, m))
        for table in ("evolving_cellpros", "evolving_pros"):
            _sql(conn, version, f"DELETE FROM {table} WHERE _geoid = %s AND _timem = %s", (geoid, m))
    elif what == "add-instant":  # a geometry instant between two of the period M, the nodes where they are at T
        m, t, new = float(args[0]), float(args[1]), float(args[2])
        _sql(conn, version, "INSERT INTO tgsis.timet VALUES (%s, %s, %s)", (geoid, m, new))
        _sql(
            conn,
            version,
            "INSERT INTO tgsis.d4dvrtx SELECT geoid, timem, %s, nodeid, x, y, z + 0.5 FROM tgsis.d4dvrtx"
            " WHERE geoid = %s AND timem = %s AND timet = %s",
            (new, geoid, m, t),
        )
        _sql(
            conn,
            version,
            "INSERT INTO evolving_cellpros SELECT _geoid, _timem, %s, _idx, porosity * 3 FROM evolving_cellpros"
            " WHERE _geoid = %s AND _timem = %s AND _timet = %s",
            (new, geoid, m, t),
        )
        _sql(conn, version, "INSERT INTO evolving_pros VALUES (%s, %s, %s, 77.0)", (geoid, m, new))
    elif what == "drop-instant":  # geometry instant T of the period M removed with its rows
        m, t = float(args[0]), float(args[1])
        for table in ("d4dvrtx", "timet"):
            _sql(
                conn,
                version,
                f"DELETE FROM tgsis.{table} WHERE geoid = %s AND timem = %s AND timet = %s",
                (geoid, m, t),
            )
        for table in ("evolving_cellpros", "evolving_pros"):
            _sql(conn, version, f"DELETE FROM {table} WHERE _geoid = %s AND _timem = %s AND _timet = %s", (geoid, m, t))
    elif what == "topology":  # the period M's triangle N removed (at every geometry instant)
        m, n = float(args[0]), int(args[1])
        _sql(
            conn,
            version,
            "DELETE FROM tgsis.d4dtrgl WHERE geoid = %s AND timem = %s AND trglid = ("
            " SELECT trglid FROM tgsis.d4dtrgl WHERE geoid = %s AND timem = %s ORDER BY trglid OFFSET %s LIMIT 1)",
            (geoid, m, geoid, m, n),
        )
    elif what == "values":  # porosity of some nodes at (M, T) changed, one property row removed
        m, t = float(args[0]), float(args[1])
        nodes = _node_ids(conn, geoid, m)
        _sql(
            conn,
            version,
            "UPDATE evolving_cellpros SET porosity = -0.0 WHERE _geoid = %s AND _timem = %s AND _timet = %s"
            " AND _idx = ANY(%s)",
            (geoid, m, t, nodes[30:34]),
        )
        _sql(
            conn,
            version,
            "DELETE FROM evolving_cellpros WHERE _geoid = %s AND _timem = %s AND _timet = %s AND _idx = %s",
            (geoid, m, t, nodes[50]),
        )
    elif what == "throw":  # the per-instant property at (M, T)
        m, t, value = float(args[0]), float(args[1]), float(args[2])
        _sql(
            conn,
            version,
            "UPDATE evolving_pros SET throw = %s WHERE _geoid = %s AND _timem = %s AND _timet = %s",
            (value, geoid, m, t),
        )
    elif what == "drop":  # the whole feature
        with tgsis.in_version(conn, version):
            tgsis.delete_feature(conn, "evolving", geoid)
        conn.commit()
    else:
        raise AssertionError(step)


# what each side does, as (version, step) pairs: every one merges period by period in Python
SCENARIOS: dict[str, list[tuple[str, str]]] = {
    "edits at different geometry instants of one period": [("e1", "move 1 1 north"), ("DEFAULT", "move 1 2 south")],
    "edits in different periods": [("e1", "move 3 4 north"), ("DEFAULT", "move 1 2 south")],
    "the version appends a period, the parent moves nodes": [("e1", "append"), ("DEFAULT", "move 1 2 south")],
    "the parent appends a period, the version moves nodes": [("DEFAULT", "append"), ("e1", "move 3 4 north")],
    "both append the same period alike": [("e1", "append"), ("DEFAULT", "append"), ("e1", "move 1 1 north")],
    "the version removes a period, the parent moves in the other": [
        ("e1", "drop-period 3"),
        ("DEFAULT", "move 1 2 south"),
    ],
    "the version adds a geometry instant, the parent moves another": [
        ("e1", "add-instant 1 2 2.5"),
        ("DEFAULT", "move 1 1 south"),
    ],
    "the parent adds a geometry instant, the version moves another period": [
        ("DEFAULT", "add-instant 3 4 4.5"),
        ("e1", "move 1 2 north"),
    ],
    "the version removes a geometry instant, the parent moves another": [
        ("e1", "drop-instant 1 2"),
        ("DEFAULT", "move 1 1 south"),
    ],
    # (the version's geometry instant 2 is new rows at the old key: its period is read whole, not by the slots that
    # differ, in chunks as on rows)
    "the version removes a geometry instant and adds it anew, the parent moves another of the period": [
        ("e1", "drop-instant 1 2"),
        ("e1", "add-instant 1 1 2"),
        ("DEFAULT", "move 1 1 south"),
    ],
    "the version changes a period's topology, the parent moves in the other": [
        ("e1", "topology 1 0"),
        ("DEFAULT", "move 3 4 south"),
    ],
    "the parent changes a period's topology, the version moves in the other": [
        ("DEFAULT", "topology 3 5"),
        ("e1", "move 1 1 north"),
    ],
    "property values on one side, positions on the other": [("e1", "values 1 2"), ("DEFAULT", "move 3 5 south")],
    "per-instant properties of other instants on each side": [
        ("DEFAULT", "throw 1 2 25"),
        ("e1", "throw 3 4 35"),
        ("e1", "move 1 1 north"),
    ],
    "the same period removed on both sides, nodes moved in the other on each": [
        ("e1", "drop-period 3"),
        ("DEFAULT", "drop-period 3"),
        ("e1", "move 1 1 north"),
        ("DEFAULT", "move 1 2 south"),
    ],
    "the same geometry instant removed on both sides, nodes moved at others on each": [
        ("e1", "drop-instant 1 2"),
        ("DEFAULT", "drop-instant 1 2"),
        ("e1", "move 1 1 north"),
        ("DEFAULT", "move 3 4 south"),
    ],
    "the same edit on both sides, one more in the version": [
        ("e1", "same 1 2 north"),
        ("DEFAULT", "same 1 2 north"),
        ("e1", "move 3 4 south"),
    ],
}


@pytest.mark.parametrize("scenario", list(SCENARIOS))
def test_periods_changed_on_one_side_merge_in_psql_exactly_as_in_python(
    conn: Conn, periods: int, scenario: str
) -> None:
    for version, what in SCENARIOS[scenario]:
        step(conn, version, what, periods)
    assert_same_merge(conn, "e1")


@pytest.mark.parametrize(("action", "remove"), [("merge", True), ("refresh", False)])
def test_a_refresh_and_a_merge_that_removes_the_version(conn: Conn, periods: int, action: str, remove: bool) -> None:
    step(conn, "e1", "append", periods)
    step(conn, "DEFAULT", "move 1 2 south", periods)
    step(conn, "DEFAULT", "throw 1 3 12", periods)
    assert_same_merge(conn, "e1", action, remove)


# what the Python merge leaves unsolved (TG302) or refuses (TG308), or merges where psql refuses naming it
REFUSED: dict[str, tuple[list[tuple[str, str]], str]] = {
    "a period removed on one side and changed on the other": (
        [("e1", "drop-period 3"), ("DEFAULT", "move 3 4 south")],
        "TG302",
    ),
    "a geometry instant removed on one side and changed on the other": (
        [("e1", "drop-instant 1 2"), ("DEFAULT", "move 1 2 south")],
        "TG302",
    ),
    "a period appended on both sides differently": ([("e1", "append"), ("DEFAULT", "append other")], "TG302"),
    "a period's topology changed on both sides differently": (
        [("e1", "topology 1 0"), ("DEFAULT", "topology 1 5")],
        "TG302",
    ),
    "a per-instant property changed on both sides": (
        [("e1", "throw 1 2 21"), ("DEFAULT", "throw 1 2 22")],
        "TG302",
    ),
    "the feature deleted in the version, nodes moved in the parent": (
        [("e1", "drop"), ("DEFAULT", "move 1 2 south")],
        "TG302",
    ),
    "a period appended where the other side moved the last shape": (  # the periods would not join
        [("e1", "append"), ("DEFAULT", "move 3 5 south")],
        "TG302",
    ),
    "a geometry instant added to a period whose topology the other side changed": (
        [("DEFAULT", "topology 1 0"), ("e1", "add-instant 1 2 2.5")],
        "TG308",
    ),
    "a geometry instant moved on both sides differently": (
        [("e1", "move 1 2 north"), ("DEFAULT", "move 1 2 south")],
        "python",
    ),
    "a period's topology changed on one side, its nodes moved on the other": (
        [("e1", "topology 1 0"), ("DEFAULT", "move 1 2 south")],
        "python",
    ),
}


@pytest.mark.parametrize("scenario", list(REFUSED))
def test_what_psql_does_not_merge_period_by_period_is_refused_and_nothing_is_written(
    conn: Conn, periods: int, scenario: str
) -> None:
    steps, python = REFUSED[scenario]
    for version, what in steps:
        step(conn, version, what, periods)
    before = everything(conn)
    conn.commit()
    theirs, mine = both_merges(conn, "e1")
    if python == "python":  # merged by its regions in psql as in Python (test_sql_merge_period_regions.py)
        assert theirs[0] == "done", theirs
        assert mine[:2] == theirs[:2], mine
        assert mine[2] == theirs[2]
    else:
        assert theirs[:2] == ("refused", python), theirs
        assert mine[:2] == ("refused", python), mine
    if python == "TG308":
        assert "period starting at 1" in mine[2] and "period starting at 1" in theirs[2]
    assert everything(conn) == before
    conn.commit()


# ---------------------------------------------------------------------------- hostile cases


def _one_side_each(conn: Conn, geoid: int) -> None:
    """The version moves nodes of the second period and appends a third, the parent changes property rows of the
    first and a per-instant property."""
    for version, what in (
        ("e1", "move 3 4 north"),
        ("e1", "append"),
        ("DEFAULT", "values 1 2"),
        ("DEFAULT", "throw 1 1 25"),
    ):
        step(conn, version, what, geoid)


def test_session_settings_do_not_change_what_psql_writes(conn: Conn, periods: int) -> None:
    _one_side_each(conn, periods)
    theirs, _ = both_merges(conn, "e1")
    conn.execute("SET extra_float_digits = -15")
    conn.execute("SET search_path = ''")
    conn.execute("SET enable_indexscan = off; SET jit = off")
    conn.commit()
    mine = _outcome(conn, lambda: int(conn.execute("SELECT tgsis.merge_version('e1')").fetchone()[0]))  # type: ignore[index]
    conn.execute("RESET ALL")
    conn.commit()
    assert theirs[0] == mine[0] == "done", mine
    assert mine[1] == theirs[1]
    for table in theirs[2]:
        assert mine[2][table] == theirs[2][table], table


@pytest.mark.parametrize(
    "statement",
    [
        "WITH m AS (SELECT tgsis.merge_version('e1') AS n) SELECT n FROM m",
        "SELECT pg_temp.merge_it('e1')",
    ],
    ids=["cte", "function"],
)
def test_a_psql_merge_in_a_cte_or_a_function_writes_what_python_writes(
    conn: Conn, periods: int, statement: str
) -> None:
    _one_side_each(conn, periods)
    theirs, _ = both_merges(conn, "e1")
    conn.execute(
        "CREATE FUNCTION pg_temp.merge_it(v text) RETURNS bigint LANGUAGE sql AS $$ SELECT tgsis.merge_version(v) $$"
    )
    conn.commit()
    mine = _outcome(conn, lambda: int(conn.execute(statement).fetchone()[0]))  # type: ignore[index]
    assert theirs[0] == mine[0] == "done", mine
    assert mine[1] == theirs[1]
    for table in theirs[2]:
        assert mine[2][table] == theirs[2][table], table


def test_a_depth_positive_surface_and_the_parents_attribute_edit(conn: Conn, periods: int) -> None:
    """The parent marks the surface depth-positive (an attribute of its geometry row) and edits a period; the
    version edits the other: psql brings the attribute and the period as Python does."""
    _sql(conn, "DEFAULT", "UPDATE tgsis.geometry SET zpositive = 'Depth' WHERE geoid = %s", (periods,))
    step(conn, "DEFAULT", "move 1 2 south", periods)
    step(conn, "e1", "move 3 4 north", periods)
    mine = assert_same_merge(conn, "e1")
    assert any("Depth" in row for row in mine[2]["tgsis.geometry_ver"])


@pytest.mark.parametrize("revoked", ["DELETE", "INSERT on the storage", "INSERT, UPDATE, DELETE"])
@pytest.mark.parametrize("table", ["evolving_cellpros", "evolving_pros", "d4dvrtx"])
def test_a_role_that_may_not_write_a_table_is_refused_as_in_python_and_nothing_is_written(
    conn: Conn, periods: int, db_dsn: str, table: str, revoked: str
) -> None:
    from tests.roles import login_roles

    _one_side_each(conn, periods)
    step(conn, "DEFAULT", "move 1 1 south", periods)
    schema = "tgsis" if table == "d4dvrtx" else "public"
    with login_roles(db_dsn, {"ed": "tgsis_editor"}) as made:
        tgsis.grant_version(conn, "e1", "all", made.name("ed"))
        tgsis.grant_version(conn, "DEFAULT", "merge", made.name("ed"))
        if revoked == "INSERT on the storage":  # (the Python client COPYs new row versions there)
            # (<table>_ver, or its chunk table once stored in chunks: TGSIS_TEST_TIME_STORAGE=chunks)
            storage = conn.execute("SELECT tgsis.storage_table(%s, %s)", (schema, table)).fetchone()
            assert storage is not None
            conn.execute(sql.SQL("REVOKE INSERT ON {} FROM tgsis_editor").format(sql.SQL(storage[0])))
        else:
            conn.execute(
                sql.SQL("REVOKE {} ON {} FROM tgsis_editor").format(sql.SQL(revoked), sql.Identifier(schema, table))
            )
        conn.commit()
        before = everything(conn)
        conn.commit()
        session = made.connect("ed")
        theirs, mine = merges_as(conn, session, "e1")
        assert everything(conn) == before
        conn.commit()
        if revoked == "INSERT, UPDATE, DELETE":
            assert theirs == ("refused", "42501"), theirs  # PostgreSQL refuses the Python merge's statement
        assert mine == theirs, (table, revoked, theirs, mine)


# ---------------------------------------------------------------------------- Hypothesis: random one-sided edits

_features = itertools.count()
_edit = st.sampled_from(["none", "move", "values", "throw", "drop-instant"])
_side = st.sampled_from(["none", "parent", "child", "both"])


@settings(
    max_examples=6, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow]
)
@given(
    sides=st.tuples(_side, _side),
    edits=st.tuples(st.lists(_edit, min_size=3, max_size=3), st.lists(_edit, min_size=3, max_size=3)),
    topology=st.tuples(st.booleans(), st.booleans()),
    adder=_side,
    action=st.sampled_from(["merge", "refresh"]),
)
def test_random_one_sided_edits_of_periods_merge_in_psql_exactly_as_in_python(
    conn: Conn,
    sides: tuple[str, str],
    edits: tuple[list[str], list[str]],
    topology: tuple[bool, bool],
    adder: str,
    action: str,
) -> None:
    """Per period a side (none, parent, version, both alike) edits its geometry instants (nodes moved, property
    rows, the per-instant property, an instant removed) and maybe its topology; a side may append a period. Every
    such merge is one psql merges as Python does, or refuses as Python refuses (SQLSTATE)."""
    if not conn.execute("SELECT 1 FROM tgsis.catalog WHERE classname = 'evolving'").fetchone():
        conn.rollback()
        make_periods(conn)
    conn.rollback()
    n = next(_features)
    geoid = tgsis.insert_feature(conn, "evolving", EvolvingSurface([_period(FIRST, 0), _period(SECOND, 2)]))
    version = f"h{n}"
    tgsis.create_version(conn, version)
    conn.commit()
    who = {"none": [], "parent": ["DEFAULT"], "child": [version], "both": ["DEFAULT", version]}
    for (m, times), side, plan, topo in zip(((1.0, FIRST), (3.0, SECOND)), sides, edits, topology, strict=True):
        for v in who[side]:
            if topo:
                step(conn, v, f"topology {m:g} {n % 7}", geoid)
            for t, edit in zip(times, plan, strict=True):
                if edit == "none" or (edit == "drop-instant" and t == times[0]):
                    continue  # (a period keeps its first geometry instant: the topology instant)
                if adder != "none" and t == SECOND[-1] and edit in ("move", "drop-instant"):
                    continue  # (an appended period starts on the last shape: append_period checks it)
                if edit in ("move", "values"):
                    step(
                        conn,
                        v,
                        f"{'same' if edit == 'move' else edit} {m:g} {t:g}" + (" north" if edit == "move" else ""),
                        geoid,
                    )
                elif edit == "throw":
                    step(conn, v, f"throw {m:g} {t:g} {n + 0.5}", geoid)
                else:
                    step(conn, v, f"drop-instant {m:g} {t:g}", geoid)
    for v in who[adder]:
        step(conn, v, "append", geoid)
    if not conn.execute("SELECT 1 FROM tgsis.find_conflicts(%s) WHERE objectclass = 'feature'", (version,)).fetchone():
        conn.rollback()
        return  # (no edit on one side: the plain merge, which the others test)
    conn.rollback()
    theirs, mine = both_merges(conn, version, action)
    assert mine[:2] == theirs[:2], (theirs[:3], mine[:3])
    if theirs[0] == "done":
        for table in theirs[2]:
            assert mine[2][table] == theirs[2][table], table


def test_a_class_with_triangle_properties(conn: Conn) -> None:
    """Integer properties per triangle (alignment CELL) at each geometry instant: the version edits and removes
    some at one instant, the parent moves nodes at another; both merges write the same rows."""
    tgsis.create_feature_class(
        conn, "evolving", "SURFACE", time_model="EVOLVING", cell_properties=[("facies", "int")], alignment="CELL"
    )
    tgsis.enable_feature_versioning(conn)
    cells = curved_surface().cells
    facies = np.stack([np.arange(len(cells)) % 5] * len(FIRST))
    positions = np.stack([_shape(i) for i in range(len(FIRST))])
    period = TopologyPeriod(np.asarray(FIRST), cells, positions, cell_properties={"facies": facies})
    geoid = tgsis.insert_feature(conn, "evolving", EvolvingSurface([period]))
    tgsis.create_version(conn, "e1")
    conn.commit()
    _sql(
        conn,
        "e1",
        "UPDATE evolving_cellpros SET facies = 9 WHERE _geoid = %s AND _timet = 1 AND _idx BETWEEN 10 AND 14",
        (geoid,),
    )
    _sql(conn, "e1", "DELETE FROM evolving_cellpros WHERE _geoid = %s AND _timet = 1 AND _idx = 20", (geoid,))
    ids = np.asarray(_node_ids(conn, geoid, 1.0))
    _move(conn, "DEFAULT", geoid, 1.0, 3.0, ids[SOUTH], PARENT_SHIFT)
    mine = assert_same_merge(conn, "e1")
    assert any("9" in row for row in mine[2]["public.evolving_cellpros_ver"])  # (the version's edit kept)


def test_two_evolving_surfaces_and_a_surface_at_instants_in_one_merge(conn: Conn) -> None:
    """One psql merge of three features changed on both sides: two evolving surfaces (the work tables made by the
    first, emptied for the second) and a surface at instants (model 2's merge in the same transaction)."""
    from tests.test_merge_instants import TIMES, move
    from tgsis.temporal import SurfaceSeries

    tgsis.create_feature_class(
        conn, "horizons", "SURFACE", time_model="INSTANTS", cell_properties=[("porosity", "float8")]
    )
    cells = curved_surface().cells
    series = SurfaceSeries(
        np.asarray(TIMES),
        [tgsis.Surface(_shape(i), cells, vertex_properties={"porosity": _porosity()}) for i in range(len(TIMES))],
    )
    flat = tgsis.insert_feature(conn, "horizons", series)
    conn.commit()
    first = make_periods(conn)  # (versions e1 on both)
    second = tgsis.insert_feature(conn, "evolving", EvolvingSurface([_period(FIRST, 0), _period(SECOND, 2)]))
    conn.commit()
    tgsis.create_version(conn, "e2")
    conn.commit()
    for geoid in (first, second):
        step(conn, "e2", "move 3 4 north", geoid)
        step(conn, "DEFAULT", "move 1 2 south", geoid)
    step(conn, "e2", "append", second)
    move(conn, "e2", flat, TIMES[0], NORTH, CHILD_SHIFT)
    move(conn, "DEFAULT", flat, TIMES[2], SOUTH, PARENT_SHIFT)
    mine = assert_same_merge(conn, "e2")
    assert mine[1] > 0


def _rows_read(conn: Conn, schema: str, table: str) -> int:
    """The rows this transaction has fetched from a table's storage so far (pg_stat_xact_user_tables: rows of
    sequential scans and rows fetched through an index)."""
    row = conn.execute(
        "SELECT coalesce(s.seq_tup_read, 0) + coalesce(s.idx_tup_fetch, 0) FROM pg_stat_xact_user_tables s"
        " WHERE s.relid = tgsis.storage_table(%s, %s)::regclass",
        (schema, table),
    ).fetchone()
    return int(row[0]) if row is not None else 0


def test_the_psql_merge_reads_the_changed_nodes_not_the_whole_period(conn: Conn, periods: int) -> None:
    """The psql merge of an evolving surface reads, in a touched period, the rows of the nodes some side changed
    (at every geometry instant of their period: one topology), not the whole period. Counted on the vertex property
    rows' storage (pg_stat_xact_user_tables) around the model-3 merge itself, as merge_regions_in_sql calls it, with
    index reads only (enable_seqscan off: a table this small is otherwise scanned whatever is read): the search of
    the changed keys (which finds them among the object's rows here: one range of the revision BRIN) and the 4
    changed nodes at 3 geometry instants; reading the touched period whole read one more object's worth. What the
    merge writes is the Python merge's, row for row."""
    nodes = _node_ids(conn, periods, 1.0)
    _move(conn, "e1", periods, 1.0, 1.0, nodes[:2], CHILD_SHIFT)
    _move(conn, "DEFAULT", periods, 1.0, 2.0, nodes[-2:], PARENT_SHIFT)
    assert_same_merge(conn, "e1")
    storage = conn.execute("SELECT tgsis.storage_table('public', 'evolving_cellpros')").fetchone()
    assert storage is not None
    stored = conn.execute(sql.SQL("SELECT count(*) FROM {}").format(sql.SQL(str(storage[0])))).fetchone()
    conn.rollback()
    with conn.transaction(force_rollback=True):
        conn.execute("SET LOCAL enable_seqscan = off; SET LOCAL jit = off")
        conn.execute("SELECT tgsis.lock_for_region_merge('e1', 'merge', false)")
        conn.execute("SELECT set_config('tgsis.region_detection', 'client', true)")
        conn.execute("SELECT FROM tgsis.find_conflicts('e1')")
        before = _rows_read(conn, "public", "evolving_cellpros")
        conn.execute("SELECT tgsis.merge_periods_by_slice('e1', 'merge', %s)", (periods,))
        read = _rows_read(conn, "public", "evolving_cellpros") - before
    conn.rollback()
    assert stored is not None
    # the object's rows once (the changed keys' search) and the 4 nodes' rows at 3 geometry instants, in up to
    # 2 row versions each; the whole touched period was 144 nodes at 3 geometry instants more
    assert 0 < read <= int(stored[0]) + 4 * 3 * 2, (read, stored[0])
