"""Solutions per object for a mesh that merges by region (issue 39 items 3, 4): tgsis.resolve_all_regions.

The fault of tests/test_conflict_regions.py (north end moved in e1, south end
in DEFAULT, a middle patch on both sides) with a second conflicting patch at
the west edge: one object, two conflicting regions, two automatic ones.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import psycopg
import pytest

import tgsis
from tests.merge_data import SIDE, move, stored_state
from tests.test_conflict_regions import MIDDLE, NORTH, everything, three_regions
from tgsis.cli import main
from tgsis.db import regions as R
from tgsis.errors import InvalidInputError, RegionSolutionError
from tgsis.merge3 import apply_solutions

Conn = psycopg.Connection[Any]

WEST = np.array([6 * SIDE + 1, 6 * SIDE + 2])  # three columns away from MIDDLE: a region of its own


def two_conflicts(conn: Conn) -> int:
    """three_regions and a fourth region, a second conflict in the west (committed; tests/conftest.py clones it)."""
    return _two_conflicts(conn)


def _two_conflicts(conn: Conn, *, remesh_west: bool = False, hole_west: bool = False) -> int:
    geoid = three_regions(conn)
    move(conn, "e1", geoid, WEST, (0.0, 0.0, 3.0))
    move(conn, "DEFAULT", geoid, WEST, (0.0, 0.0, -2.0))
    if hole_west:  # the version removes every triangle on the west patch: no shape of it there to average
        with tgsis.in_version(conn, "e1"):
            gone = conn.execute(
                "DELETE FROM tgsis.trgl WHERE geoid = %s AND (vrtxid1 = ANY(%s) OR vrtxid2 = ANY(%s) OR vrtxid3 = ANY(%s))",
                (geoid, *([int(v) for v in WEST],) * 3),
            ).rowcount
            conn.execute("UPDATE tgsis.geometry SET ncell = ncell - %s WHERE geoid = %s", (gone, geoid))
    if remesh_west:  # the version splits a triangle of the west patch with a new vertex: another meshing there
        with tgsis.in_version(conn, "e1"):
            n, cells = SIDE * SIDE, 2 * (SIDE - 1) * (SIDE - 1)
            a, b, c = conn.execute(
                "SELECT vrtxid1, vrtxid2, vrtxid3 FROM tgsis.trgl WHERE geoid = %s AND %s IN (vrtxid1, vrtxid2, vrtxid3)"
                " ORDER BY trglid LIMIT 1",
                (geoid, int(WEST[0])),
            ).fetchone() or (0, 0, 0)
            trgl = conn.execute(
                "SELECT trglid FROM tgsis.trgl WHERE geoid = %s AND (vrtxid1, vrtxid2, vrtxid3) = (%s, %s, %s)",
                (geoid, a, b, c),
            ).fetchone()
            assert trgl is not None
            conn.execute(
                "INSERT INTO tgsis.vrtx (geoid, vrtxid, x, y, z) SELECT geoid, %s, avg(x), avg(y), avg(z)"
                " FROM tgsis.vrtx WHERE geoid = %s AND vrtxid = ANY(%s) GROUP BY geoid",
                (n, geoid, [a, b, c]),
            )
            conn.execute("UPDATE tgsis.trgl SET vrtxid3 = %s WHERE geoid = %s AND trglid = %s", (n, geoid, trgl[0]))
            conn.execute(
                "INSERT INTO tgsis.trgl (geoid, trglid, vrtxid1, vrtxid2, vrtxid3) VALUES (%s, %s, %s, %s, %s),"
                " (%s, %s, %s, %s, %s)",
                (geoid, cells, b, c, n, geoid, cells + 1, c, a, n),
            )
            conn.execute("UPDATE tgsis.geometry SET nvrtx = nvrtx + 1, ncell = ncell + 2 WHERE geoid = %s", (geoid,))
    conn.commit()
    return geoid


def _conflicting(conn: Conn) -> list[R.ConflictRegion]:
    [conflict] = tgsis.find_conflicts(conn, "e1")
    conn.commit()
    regions = [r for r in conflict.regions if r.conflict]
    assert len(regions) == 2 and any(not r.conflict for r in conflict.regions)
    return regions


def _solved_state(conn: Conn, fault: int) -> Any:
    merge = tgsis.object_merge(conn, "e1", fault)
    with conn.transaction():
        solutions: dict[int, Any] = dict(R.region_solutions(conn, "e1", "feature", str(fault), merge))
    conn.commit()
    return merge, solutions, apply_solutions(merge, solutions).state


@pytest.mark.parametrize("solution", ["parent", "child", "base", "average"])
def test_every_conflicting_region_is_solved_at_once_as_region_by_region(
    conn: Conn, solution: str, two_conflicts_clone: int
) -> None:
    fault = two_conflicts_clone
    regions = _conflicting(conn)
    result = tgsis.resolve_all_regions(conn, "e1", fault, solution)
    conn.commit()
    assert sorted(r.region for r in result.regions) == sorted(r.region for r in regions)
    assert all(r.solution == solution and r.solved_by is not None for r in result.regions)
    stored = {r.region: r.solution for r in tgsis.find_conflicts(conn, "e1")[0].regions}
    conn.commit()
    assert {i: s for i, s in stored.items() if i in {r.region for r in regions}} == dict.fromkeys(
        (r.region for r in regions), solution
    )
    assert {s for i, s in stored.items() if i not in {r.region for r in regions}} <= {"unsolved", "automatic"}
    merge, solutions, at_once = _solved_state(conn, fault)
    assert set(solutions) == {r.region for r in regions}
    # the same, one region at a time
    for region in regions:
        tgsis.resolve_region(conn, "e1", fault, region.region, "unsolved")
        conn.commit()
    for region in regions:
        tgsis.resolve_region(conn, "e1", fault, region.region, solution)
        conn.commit()
    _, _, one_by_one = _solved_state(conn, fault)
    assert at_once.vertex_ids.tobytes() == one_by_one.vertex_ids.tobytes()
    assert at_once.vertices.tobytes() == one_by_one.vertices.tobytes()
    assert at_once.cells.tobytes() == one_by_one.cells.tobytes()
    # the child's edits outside the conflicts are kept, whatever the object's solution
    north = np.searchsorted(at_once.vertex_ids, NORTH)
    child_north = merge.child.vertices[np.searchsorted(merge.child.vertex_ids, NORTH)]
    assert at_once.vertices[north].tobytes() == child_north.tobytes()
    # and the merge writes exactly that
    tgsis.merge_version(conn, "e1")
    conn.commit()
    ids, xyz, _, _ = stored_state(conn, "DEFAULT", fault)
    assert ids.tobytes() == at_once.vertex_ids.tobytes() and xyz.tobytes() == at_once.vertices.tobytes()


def test_the_discards_are_summed_per_side_before_anything_is_recorded(conn: Conn, two_conflicts_clone: int) -> None:
    fault = two_conflicts_clone
    regions = _conflicting(conn)
    before = everything(conn)
    with pytest.raises(RegionSolutionError, match=r"discards .*version's edit of 6 vertices") as refused:
        tgsis.resolve_all_regions(conn, "e1", fault, "parent", discard_other=False)
    conn.rollback()
    assert everything(conn) == before
    assert "region" in str(refused.value)
    result = tgsis.resolve_all_regions(conn, "e1", fault, "parent")
    conn.commit()
    assert {d.region for d in result.discards} == {r.region for r in regions}
    assert {d.side for d in result.discards} == {"child"}
    [total] = result.totals
    assert total.side == "child" and total.solution == "parent"
    assert total.vertices == len(MIDDLE) + len(WEST) == sum(d.vertices for d in result.discards)
    assert total.cells == sum(d.cells for d in result.discards)
    # the largest displacement of the child's edits thrown away: the middle's +5 against the parent's -7
    assert total.max_displacement == pytest.approx(12.0)
    assert total.max_displacement == max(d.max_displacement for d in result.discards)
    assert "6 vertices" in result.summary() and "12" in result.summary()


def test_a_region_that_refuses_records_nothing_and_is_named(conn: Conn) -> None:
    fault = _two_conflicts(conn, hole_west=True)
    regions = _conflicting(conn)
    west = next(r for r in regions if np.isin(WEST, r.vertex_ids).all())
    tgsis.resolve_region(conn, "e1", fault, west.region, "child")  # a solution recorded before stays as it was
    conn.commit()
    before = everything(conn)
    with pytest.raises(RegionSolutionError, match=rf"region {west.region}\b.*no triangle in the region"):
        tgsis.resolve_all_regions(conn, "e1", fault, "average")
    conn.rollback()
    assert everything(conn) == before
    with pytest.raises(InvalidInputError, match="manual"):
        tgsis.resolve_all_regions(conn, "e1", fault, "manual")
    conn.rollback()
    with pytest.raises(InvalidInputError, match="not parent, child, base"):
        tgsis.resolve_all_regions(conn, "e1", fault, "theirs")
    conn.rollback()
    assert everything(conn) == before


def test_the_command_line_solves_the_object_with_region_all(
    conn: Conn, db_dsn: str, capsys: pytest.CaptureFixture[str], two_conflicts_clone: int
) -> None:
    fault = two_conflicts_clone
    regions = _conflicting(conn)
    before = everything(conn)
    args = ["--dsn", db_dsn, "version", "resolve", "e1", str(fault), "child", "--region", "all"]
    assert main(args) == 1  # it discards the parent's edits in both regions: refused without --discard-other
    err = capsys.readouterr().err
    assert "--discard-other" in err and "4 vertices" in err
    assert everything(conn) == before
    assert main([*args, "--discard-other"]) == 0
    said = capsys.readouterr().out
    assert said.index("discards") < said.index("recorded")
    assert f"{len(MIDDLE) + len(WEST)} vertices" in said  # the sum over the regions
    assert all(f"region {r.region}" in said for r in regions)
    merge, solutions, _ = _solved_state(conn, fault)
    assert solutions == {r.region: "child" for r in regions}
    with pytest.raises(SystemExit) as usage:  # argparse's usage error, as for any bad flag value
        main(["--dsn", db_dsn, "version", "resolve", "e1", str(fault), "child", "--region", "north"])
    assert usage.value.code == 2 and "give its index N or all" in capsys.readouterr().err
    assert main(["--dsn", db_dsn, "version", "resolve", "e1", str(fault), "manual", "--region", "all"]) == 1
    assert "manual is a region's" in capsys.readouterr().err
    args_mesh = ["--dsn", db_dsn, "version", "resolve", "e1", str(fault), "child", "--region", "all", "--mesh", "x.ts"]
    assert main(args_mesh) == 1 and "without --mesh" in capsys.readouterr().err
    # without --region the object-level resolve is as it was: it refuses a side that drops edits outside the conflicts
    assert main(["--dsn", db_dsn, "version", "resolve", "e1", "feature", str(fault), "child"]) == 1


def test_a_role_without_rights_and_a_stale_state_record_nothing(
    db_dsn: str, conn: Conn, two_conflicts_clone: int
) -> None:
    from tests.roles import login_roles
    from tgsis.errors import MissingPrivilegeError

    fault = two_conflicts_clone
    regions = _conflicting(conn)
    before = everything(conn)
    with login_roles(db_dsn, {"reader": "tgsis_reader"}) as roles:
        reader = roles.connect("reader")
        with pytest.raises(MissingPrivilegeError, match="resolve conflicts"):
            tgsis.resolve_all_regions(reader, "e1", fault, "child")
        reader.rollback()
    assert everything(conn) == before
    move(conn, "e1", fault, [70], (0.0, 0.0, 0.25))  # the version edits the object again: the regions are stale
    conn.commit()
    with pytest.raises(RegionSolutionError, match="changed since"):
        tgsis.resolve_all_regions(conn, "e1", fault, "child")
    conn.rollback()
    # found again, solved at once and taken back at once
    assert len([r for r in tgsis.find_conflicts(conn, "e1")[0].regions if r.conflict]) == len(regions)
    conn.commit()
    tgsis.resolve_all_regions(conn, "e1", fault, "child")
    conn.commit()
    back = tgsis.resolve_all_regions(conn, "e1", fault, "unsolved")
    conn.commit()
    assert [r.solution for r in back.regions] == ["unsolved"] * len(regions) and back.discards == ()
    assert {r.solution for r in tgsis.find_conflicts(conn, "e1")[0].regions if r.conflict} == {"unsolved"}
    conn.commit()


def test_an_object_without_conflicting_regions_is_refused(conn: Conn) -> None:
    from tests.merge_data import make_fault

    fault = make_fault(conn)
    move(conn, "e1", fault, NORTH, (0.0, 0.0, 1.0))
    move(conn, "DEFAULT", fault, MIDDLE, (0.0, 0.0, -1.0))
    conn.commit()
    [conflict] = tgsis.find_conflicts(conn, "e1")  # both sides changed the object, in disjoint regions
    conn.commit()
    assert conflict.regions and not any(r.conflict for r in conflict.regions)
    before = everything(conn)
    with pytest.raises(RegionSolutionError, match="no region of the feature is a conflict"):
        tgsis.resolve_all_regions(conn, "e1", fault, "child")
    conn.rollback()
    assert everything(conn) == before
