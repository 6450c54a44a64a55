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

from typing import Any

import psycopg
import pytest

from tests.merge_data import SIDE
from tests.test_merge_instants import CHILD_SHIFT, NORTH, PARENT_SHIFT, SOUTH
from tests.test_sql_merge_instant_regions import python_regions
from tests.test_sql_merge_periods import _move, _node_ids, _sql, make_periods

Conn = psycopg.Connection[Any]

_REGION = (
    "conflict, changed_by, vertex_ids, cell_ids, parent_vertex_ids, parent_cell_ids, child_vertex_ids,"
    " child_cell_ids, bbox, parent_displacement, child_displacement"
)


@pytest.fixture
def periods(conn: Conn) -> int:
    return make_periods(conn)


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
