"""Topology changes without jumps (issue 37, part 3): models 3 and 4.

The design: at a topology instant the pre-object (last shape of a period)
and the post-object (first shape of the next) share their geometry, so that
a snapshot never jumps. Refused at insert, at append_period and by the SQL
check (TG204, naming the period, the gap and the node or dart), with a
tolerance the user may set (argument, SET tgsis.period_tolerance), or
stored as an explicit short linear transition when asked (sudden_change).
"""

from __future__ import annotations

import re
from typing import Any

import numpy as np
import psycopg
import pytest

import tgsis
from tests.gmaps_shapes import grid as gmap_grid
from tests.temporal_data import grid, refine
from tgsis import gmaps
from tgsis.temporal import EvolvingSurface, TopologyPeriod

Conn = psycopg.Connection[Any]


def _dome(side: int, height: float = 300.0) -> tuple[np.ndarray, np.ndarray]:
    """A curved surface (a dome 1000 m wide, ``height`` high) on a side x side grid."""
    vertices, triangles = grid(side)
    vertices = vertices * 1000.0
    vertices[:, 2] = height * np.exp(-((vertices[:, 0] - 500) ** 2 + (vertices[:, 1] - 500) ** 2) / 2e5)
    return vertices, triangles


def _jumping(offset: float, *, same_nodes: bool = True) -> EvolvingSurface:
    """A dome rising from t = 0 to 1, then (a topology change at t = 1) re-triangulated or refined, ``offset`` m higher."""
    vertices, triangles = _dome(5)
    top = vertices * [1, 1, 2]
    first = TopologyPeriod([0.0, 1.0], triangles, np.stack([vertices, top]))
    if same_nodes:  # the same nodes, the other diagonal of each grid cell
        a, b, d = triangles[:16].T
        c = triangles[16:, 2]
        flipped = np.concatenate([np.stack([a, b, c], 1), np.stack([b, d, c], 1)])
        start = top + [0, 0, offset]
        return EvolvingSurface([first, TopologyPeriod([1.0, 2.0], flipped, np.stack([start, start + [0, 0, 50]]))])
    fine = refine(top, 5) + [0, 0, offset]
    _, fine_triangles = grid(9)
    return EvolvingSurface([first, TopologyPeriod([1.0, 2.0], fine_triangles, np.stack([fine, fine + [0, 0, 50]]))])


@pytest.fixture
def domes(conn: Conn) -> tgsis.FeatureClass:
    fc = tgsis.create_feature_class(conn, "domes", "SURFACE", time_model="EVOLVING")
    conn.commit()
    return fc


def _count(conn: Conn) -> tuple[int, int]:
    row = conn.execute("SELECT (SELECT count(*) FROM tgsis.geometry), (SELECT count(*) FROM tgsis.timem)").fetchone()
    assert row is not None
    return int(row[0]), int(row[1])


@pytest.mark.parametrize("same_nodes", [True, False])
def test_insert_refuses_a_jump_naming_period_gap_and_node(
    conn: Conn, domes: tgsis.FeatureClass, same_nodes: bool
) -> None:
    before = _count(conn)
    with pytest.raises(tgsis.DiscontinuousPeriodsError) as info:
        tgsis.insert_feature(conn, domes, _jumping(7.0, same_nodes=same_nodes))
    message = str(info.value)
    assert "topology period from 1 of geometry" in message and "where the period from 0 ends" in message
    gap = float(re.search(r"the shapes are ([0-9.e+-]+) apart", message)[1])  # type: ignore[index]
    assert 1.0 < gap <= 7.0 + 1e-9  # the distance to the other shape: 7 m on the dome's top, less on its flanks
    assert re.search(r"largest gap at node \d+ of the period from [01]", message)
    assert "triangles, both ways" in (info.value.detail or "")
    assert "sudden_change" in (info.value.hint or "") and "tolerance" in (info.value.hint or "")
    assert info.value.sqlstate == "TG204"
    conn.rollback()
    assert _count(conn) == before  # nothing written


@pytest.mark.parametrize("same_nodes", [True, False])
def test_a_change_of_topology_on_the_same_shape_is_stored(
    conn: Conn, domes: tgsis.FeatureClass, same_nodes: bool
) -> None:
    """Re-triangulating the same nodes, or refining (new nodes on the old triangles of a curved dome): no jump."""
    fid = tgsis.insert_feature(conn, domes, _jumping(0.0, same_nodes=same_nodes))
    conn.commit()
    rows = conn.execute("SELECT timem, previous, gap, matching FROM tgsis.period_gaps(%s)", (fid,)).fetchall()
    assert len(rows) == 1 and rows[0][:2] == (1.0, 0.0) and rows[0][2] < 1e-9
    assert rows[0][3] == ("node order" if same_nodes else "surface")
    assert conn.execute("SELECT count(*) FROM tgsis.check_geometry(%s)", (fid,)).fetchone() == (0,)


def test_a_shape_that_covers_less_is_a_jump_both_ways(conn: Conn, domes: tgsis.FeatureClass) -> None:
    """Every new node on the old dome, but the new shape is only half of it: the old nodes are off the new one."""
    vertices, triangles = _dome(5)
    first = TopologyPeriod([0.0, 1.0], triangles, np.stack([vertices, vertices]))
    half = vertices[:15]  # rows 0..2 of the 5 x 5 grid
    keep = np.all(triangles < 15, axis=1)
    second = TopologyPeriod([1.0, 2.0], triangles[keep], np.stack([half, half]))
    with pytest.raises(tgsis.DiscontinuousPeriodsError, match=r"of the period from 0\)"):
        tgsis.insert_feature(conn, domes, EvolvingSurface([first, second]))


def test_tolerance_argument_and_setting(conn: Conn, domes: tgsis.FeatureClass) -> None:
    with pytest.raises(tgsis.DiscontinuousPeriodsError):
        tgsis.insert_feature(conn, domes, _jumping(0.5), tolerance=0.4)
    conn.rollback()
    fid = tgsis.insert_feature(conn, domes, _jumping(0.5), tolerance=0.6)
    conn.execute("SET tgsis.period_tolerance TO '0.6'")
    tgsis.insert_feature(conn, domes, _jumping(0.5))
    assert conn.execute("SELECT count(*) FROM tgsis.check_geometry(%s)", (fid,)).fetchone() == (0,)
    conn.execute("RESET tgsis.period_tolerance")
    problem = conn.execute("SELECT problem FROM tgsis.check_geometry(%s)", (fid,)).fetchone()
    assert problem is not None and problem[0].startswith("shape jumps at a topology instant")
    # the default: 1e-6 of the diagonal of the geometry's box (here about 1.5 km: 1.5 mm)
    tolerance, diagonal = conn.execute(
        "SELECT tgsis.gap_tolerance(geoid), sqrt((cube_ur_coord(bbox, 1) - cube_ll_coord(bbox, 1)) ^ 2 + "
        "(cube_ur_coord(bbox, 2) - cube_ll_coord(bbox, 2)) ^ 2 + (cube_ur_coord(bbox, 3) - cube_ll_coord(bbox, 3)) ^ 2) "
        "FROM tgsis.geometry WHERE geoid = %s",
        (fid,),
    ).fetchone()  # type: ignore[misc]
    assert tolerance == pytest.approx(1e-6 * diagonal, rel=1e-12) and 1000 < diagonal < 2000
    for bad in (-1.0, float("nan"), float("inf")):
        with pytest.raises(tgsis.InvalidInputError, match="tolerance"):
            tgsis.insert_feature(conn, domes, _jumping(0.0), tolerance=bad)
    conn.rollback()
    conn.execute("SET tgsis.period_tolerance TO 'far'")
    with pytest.raises(psycopg.Error, match="is no number") as bad_setting:
        conn.execute("SELECT tgsis.check_period_continuity(%s)", (fid,))
    assert bad_setting.value.sqlstate == "TG100"
    conn.rollback()
    with pytest.raises(psycopg.Error, match="finite distance") as bad_argument:
        conn.execute("SELECT tgsis.check_period_continuity(%s, -1)", (fid,))
    assert bad_argument.value.sqlstate == "TG100"


def test_append_period_refuses_a_jump_and_takes_a_sudden_change(conn: Conn, domes: tgsis.FeatureClass) -> None:
    surface = _jumping(0.0)
    fid = tgsis.insert_feature(conn, domes, EvolvingSurface(surface.periods[:1]))
    conn.commit()
    last = surface.periods[0].positions[-1]
    vertices, triangles = _dome(5)
    seven_off = TopologyPeriod([1.0, 3.0], surface.periods[1].triangles, np.stack([last + [0, 0, 7], last + [0, 0, 9]]))
    with pytest.raises(
        tgsis.DiscontinuousPeriodsError, match=r"from 1 of geometry \d+ .* 7(\.0\d*)? apart \(largest gap at node \d+"
    ):
        tgsis.append_period(conn, domes, fid, seven_off)
    conn.rollback()
    assert [t for t, _ in tgsis.instants(conn, fid)] == [0.0, 1.0]  # unchanged
    tgsis.append_period(conn, domes, fid, seven_off, sudden_change=0.01)
    conn.commit()
    assert [t for t, starts in tgsis.instants(conn, fid)] == [0.0, 1.0, 1.01, 3.0]
    at = {t: s for t in (1.0, 1.005, 1.01) if (s := tgsis.get_at(conn, fid, t)) is not None}
    assert len(at) == 3, at  # a shape at each time
    np.testing.assert_allclose(at[1.0].vertices, last, atol=1e-6)  # starts in the old shape
    np.testing.assert_allclose(at[1.005].vertices, last + [0, 0, 3.5], atol=1e-6)  # halfway, linearly
    np.testing.assert_allclose(at[1.01].vertices, last + [0, 0, 7], atol=1e-9)  # its own first shape
    with pytest.raises(tgsis.InvalidInputError, match="must end before its second geometry instant"):
        tgsis.append_period(
            conn, domes, fid, TopologyPeriod([3.0, 3.5], triangles, np.stack([vertices, vertices])), sudden_change=1.0
        )


def test_sudden_change_at_insert_with_new_nodes(conn: Conn, domes: tgsis.FeatureClass) -> None:
    """A refined dome 7 m higher: its nodes start on the old dome (closest points) and rise over 0.001."""
    fid = tgsis.insert_feature(conn, domes, _jumping(7.0, same_nodes=False), sudden_change=0.001)
    conn.commit()
    assert conn.execute("SELECT count(*) FROM tgsis.check_geometry(%s)", (fid,)).fetchone() == (0,)
    got = tgsis.get_at(conn, fid, 1.001)
    assert got is not None and got.n_vertices == 81
    np.testing.assert_allclose(got.vertices, refine(_dome(5)[0] * [1, 1, 2], 5) + [0, 0, 7], atol=1e-9)


def test_plain_sql_rows_are_checked_by_the_sql_function(conn: Conn, domes: tgsis.FeatureClass) -> None:
    fid = tgsis.insert_feature(conn, domes, _jumping(0.0))
    conn.commit()
    conn.execute(
        "UPDATE tgsis.d4dvrtx SET z = z + 4 WHERE geoid = %s AND timem = 1 AND timet = 1 AND nodeid = 30", (fid,)
    )
    # node 30 is node 5 of the second period: the spike is at it, or at node 5 of the first below it
    with pytest.raises(
        psycopg.Error,
        match=r" [34]\.\d+ apart \(largest gap at node (30 of the period from 1|5 of the period from 0)\)",
    ) as jump:
        conn.execute("SELECT tgsis.check_period_continuity(%s)", (fid,))
    assert jump.value.sqlstate == "TG204"
    conn.rollback()
    conn.execute(
        "UPDATE tgsis.d4dvrtx SET z = z + 4 WHERE geoid = %s AND timem = 1 AND timet = 1 AND nodeid = 30", (fid,)
    )
    conn.execute("SELECT tgsis.check_period_continuity(%s, 4.5)", (fid,))
    conn.execute("SELECT tgsis.check_period_continuity(%s, p_from => 2)", (fid,))  # no topology instant from 2 on


# --------------------------------------------------------------------------- model 4


def _square_then(points_after: np.ndarray) -> gmaps.EvolvingGMap:
    """A unit square of 2 triangles at z = 0 for t in [0, 1], then a 2 x 2 grid of 8 triangles with the given points."""
    square = gmaps.GMap.from_triangles([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], [[0, 1, 2], [0, 2, 3]])
    vertices, triangles = gmap_grid(2, 2)
    fine = gmaps.GMap.from_triangles(points_after, triangles)
    assert len(vertices) == len(points_after)
    return gmaps.EvolvingGMap(
        [
            gmaps.GMapPeriod([0.0, 1.0], square),
            gmaps.GMapPeriod([1.0, 2.0], fine, np.stack([fine.points, fine.points + [0, 0, 1]])),
        ]
    )


@pytest.fixture
def blocks(conn: Conn) -> tgsis.FeatureClass:
    fc = tgsis.create_feature_class(conn, "blocks", "GMAP", time_model="GMAP", cell_level=2)
    conn.commit()
    return fc


def test_gmap_refined_on_its_edges_is_stored_and_a_jump_is_refused_naming_a_dart(
    conn: Conn, blocks: tgsis.FeatureClass
) -> None:
    vertices, _ = gmap_grid(2, 2)
    fid = tgsis.insert_feature(conn, blocks, _square_then(vertices))
    conn.commit()
    ((gap, matching),) = conn.execute("SELECT gap, matching FROM tgsis.period_gaps(%s)", (fid,)).fetchall()
    assert gap < 1e-12 and matching == "edges"
    before = _count(conn)
    with pytest.raises(
        tgsis.DiscontinuousPeriodsError,
        match=r"from 1 of geometry \d+ .* 7(\.0\d*)? apart \(largest gap at dart \d+ \(node \d+\) of the period from",
    ):
        tgsis.insert_feature(conn, blocks, _square_then(vertices + [0, 0, 7]))
    conn.rollback()
    assert _count(conn) == before
    fid = tgsis.insert_feature(conn, blocks, _square_then(vertices + [0, 0, 7]), sudden_change=0.5)
    got = tgsis.gmap_at(conn, fid, 1.25)
    assert got is not None
    np.testing.assert_allclose(np.sort(got.points[:, 2]), np.full(9, 3.5))


def test_evolving_surface_in_memory_sudden_changes() -> None:
    surface = _jumping(7.0)
    smooth = surface.with_sudden_changes(0.1)
    assert [list(p.times) for p in smooth.periods] == [[0.0, 1.0], [1.0, 1.1, 2.0]]
    np.testing.assert_allclose(smooth.at(1.0).vertices, surface.at(1.0).vertices - [0, 0, 7], atol=1e-6)  # type: ignore[union-attr]
    with pytest.raises(tgsis.InvalidInputError, match="finite time > 0"):
        surface.with_sudden_changes(0.0)
