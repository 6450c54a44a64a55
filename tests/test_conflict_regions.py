"""The store of conflicts per region (issue 39): tgsis.conflict_regions, record_conflict_regions, find_conflicts.

A curved fault (tests/merge_data.py) edited in both versions: the north end in
e1, the south end in DEFAULT, and a patch in the middle on both sides to other
places — three regions, the middle one a conflict. The regions are found by
the region-aware ``tgsis.find_conflicts`` and stored on the conflict's marks;
stale ones go, refusals change nothing, two sessions store at once, a role
without rights stores nothing, and pg_dump/restore keeps them.
"""

from __future__ import annotations

import json
import threading
from typing import Any

import numpy as np
import psycopg
import pytest

import tgsis
from tests.merge_data import SIDE, make_fault, move
from tests.roles import login_roles
from tgsis.db import regions as R

Conn = psycopg.Connection[Any]

NORTH = np.arange(0, 2 * SIDE)
SOUTH = np.arange((SIDE - 2) * SIDE, SIDE * SIDE)
MIDDLE = np.array([5 * SIDE + 5, 5 * SIDE + 6, 6 * SIDE + 5, 6 * SIDE + 6])


def three_regions(conn: Conn) -> int:
    """The fault with the north end moved in e1, the south end in DEFAULT, the middle on both sides (committed)."""
    geoid = make_fault(conn)
    move(conn, "e1", geoid, NORTH, (0.5, 0.0, 1.25))
    move(conn, "e1", geoid, MIDDLE, (0.0, 0.0, 5.0))
    move(conn, "DEFAULT", geoid, SOUTH, (-1.0, 0.0, -2.0))
    move(conn, "DEFAULT", geoid, MIDDLE, (0.0, 0.0, -7.0))
    conn.commit()
    return geoid


def stored(conn: Conn) -> list[tuple[Any, ...]]:
    """Every row of tgsis.conflict_regions as text, in order (what a refusal must leave as it was)."""
    rows = conn.execute("SELECT r::text FROM tgsis.conflict_regions r ORDER BY versionid, objectkey, region").fetchall()
    conn.rollback()
    return rows


def everything(conn: Conn) -> tuple[list[tuple[Any, ...]], list[tuple[Any, ...]]]:
    """The regions and the conflicts they belong to (solutions, marks), as text."""
    conflicts = conn.execute("SELECT k::text FROM tgsis.conflicts k ORDER BY versionid, objectkey").fetchall()
    conn.rollback()
    return stored(conn), conflicts


def by_side(regions: tuple[R.ConflictRegion, ...]) -> dict[str, R.ConflictRegion]:
    return {r.changed_by: r for r in regions}


@pytest.fixture
def fault(conn: Conn, three_regions_clone: int) -> int:
    return three_regions_clone  # three_regions's, built once (tests/conftest.py)


def test_find_conflicts_records_the_regions_of_a_mesh(conn: Conn, fault: int) -> None:
    [conflict] = tgsis.find_conflicts(conn, "e1")
    assert (conflict.objectclass, conflict.objectkey) == ("feature", str(fault))
    assert conflict.region_refusal is None
    regions = by_side(conflict.regions)
    assert sorted(regions) == ["both", "child", "parent"]
    middle = regions["both"]
    assert middle.conflict and middle.solution == "unsolved"
    assert regions["child"].solution == regions["parent"].solution == "automatic"
    assert not regions["child"].conflict and not regions["parent"].conflict
    np.testing.assert_array_equal(middle.parent_vertex_ids, MIDDLE)
    np.testing.assert_array_equal(middle.child_vertex_ids, MIDDLE)
    np.testing.assert_array_equal(regions["child"].child_vertex_ids, NORTH)
    np.testing.assert_array_equal(regions["parent"].parent_vertex_ids, SOUTH)
    assert middle.child_displacement == pytest.approx(5.0) and middle.parent_displacement == pytest.approx(7.0)
    assert middle.bbox is not None and len(middle.bbox) == 6
    assert middle.bbox[2] < middle.bbox[5]
    # as stored, with the conflict's marks
    rows = conn.execute(
        "SELECT r.region, r.conflict, r.changed_by, r.solution, r.vertex_ids, (r.childmark, r.parentmark) = "
        "       (k.childmark, k.parentmark)"
        "  FROM tgsis.conflict_regions r JOIN tgsis.conflicts k USING (versionid, objectclass, objectkey)"
        " ORDER BY r.region"
    ).fetchall()
    assert [(r[0], r[1], r[2], r[3]) for r in rows] == [
        (r.region, r.conflict, r.changed_by, r.solution) for r in conflict.regions
    ]
    assert all(r[5] for r in rows)
    assert [list(r[4]) for r in rows] == [r.vertex_ids.tolist() for r in conflict.regions]
    # the JSON of the command line carries them
    as_json = middle.as_json()
    assert as_json["child"]["vertex_ids"] == MIDDLE.tolist() and as_json["solution"] == "unsolved"


def test_an_edit_after_the_regions_were_found_drops_them(conn: Conn, fault: int) -> None:
    tgsis.find_conflicts(conn, "e1")
    assert len(stored(conn)) == 3
    move(conn, "e1", fault, [70], (0.0, 0.0, 0.5))
    conn.commit()
    conn.execute("SELECT FROM tgsis.find_conflicts('e1')")  # the SQL face: stale regions gone, found again in SQL
    stale = conn.execute(
        "SELECT count(*) FROM tgsis.conflict_regions r JOIN tgsis.conflicts k USING (versionid, objectclass, objectkey)"
        " WHERE (r.childmark, r.parentmark) <> (k.childmark, k.parentmark) OR NOT 70 = ANY (r.child_vertex_ids)"
    ).fetchone()
    assert stale == (len(stored(conn)) - 1,)  # every region on the new marks, one of them with vertex 70
    [conflict] = tgsis.find_conflicts(conn, "e1")  # found again on the new marks
    assert len(conflict.regions) >= 3 and len(stored(conn)) == len(conflict.regions)


def _marks(conn: Conn, geoid: int) -> tuple[str, str]:
    row = conn.execute(
        "SELECT childmark, parentmark FROM tgsis.find_conflicts('e1') WHERE objectkey = %s", (str(geoid),)
    ).fetchone()
    conn.commit()
    assert row is not None
    return row[0], row[1]


REGION = {
    "region": 0,
    "conflict": True,
    "changed_by": "both",
    "vertex_ids": [1, 2],
    "cell_ids": [3],
    "parent_vertex_ids": [1],
    "parent_cell_ids": [],
    "child_vertex_ids": [2],
    "child_cell_ids": [],
    "bbox": [0, 0, 0, 1, 1, 1],
    "parent_displacement": 1.5,
    "child_displacement": 0.0,
}


def test_record_conflict_regions_stores_and_keeps_solutions_found_again(conn: Conn, fault: int) -> None:
    marks = _marks(conn, fault)
    regions = [REGION, {**REGION, "region": 1, "conflict": False, "changed_by": "child", "vertex_ids": [9]}]
    count = conn.execute(
        "SELECT tgsis.record_conflict_regions('e1', 'feature', %s, %s, %s, %s)",
        (str(fault), *marks, json.dumps(regions)),
    ).fetchone()
    assert count == (2,)
    conn.execute("SELECT tgsis.resolve_region('e1', 'feature', %s, 0, 'child')", (str(fault),))
    conn.commit()
    # found again alike: the solution holds; the other region changed: it is replaced
    conn.execute(
        "SELECT tgsis.record_conflict_regions('e1', 'feature', %s, %s, %s, %s)",
        (str(fault), *marks, json.dumps([REGION])),
    )
    rows = conn.execute("SELECT region, solution, solved_by IS NOT NULL FROM tgsis.conflict_regions").fetchall()
    assert rows == [(0, "child", True)]
    conn.commit()
    changed = {**REGION, "child_vertex_ids": [1, 2]}
    conn.execute(
        "SELECT tgsis.record_conflict_regions('e1', 'feature', %s, %s, %s, %s)",
        (str(fault), *marks, json.dumps([changed])),
    )
    assert conn.execute("SELECT solution, solved_at FROM tgsis.conflict_regions").fetchall() == [("unsolved", None)]


def _sqlstate(conn: Conn, query: str, params: tuple[Any, ...]) -> tuple[str | None, str, str | None]:
    try:
        conn.execute(query, params)
    except psycopg.Error as exc:
        conn.rollback()
        return exc.sqlstate, str(exc.diag.message_primary), exc.diag.message_hint
    conn.rollback()
    raise AssertionError(f"not refused: {query} {params}")


BAD_SHAPES = [
    ({"a": 1}, "not a JSON array"),
    ([1], "is not a JSON object"),
    ([{**REGION, "region": 1}], '"region": 1 where 0 is due'),
    ([{**REGION, "colour": "red"}], "unknown keys colour"),
    ([{k: v for k, v in REGION.items() if k != "bbox"}], "lacks bbox"),
    ([{**REGION, "conflict": "yes"}], '"conflict": "yes"'),
    ([{**REGION, "changed_by": "nobody"}], '"changed_by": "nobody"'),
    ([{**REGION, "changed_by": "child"}], "a conflict is changed by both sides"),
    ([{**REGION, "vertex_ids": [1.5]}], "vertex_ids"),
    ([{**REGION, "child_cell_ids": "1,2"}], "child_cell_ids"),
    ([{**REGION, "bbox": [0, 0, 1]}], '"bbox"'),
    ([{**REGION, "parent_displacement": -1}], "parent_displacement"),
]


@pytest.mark.parametrize(("payload", "said"), BAD_SHAPES)
def test_record_refuses_bad_json_and_leaves_the_regions(conn: Conn, fault: int, payload: Any, said: str) -> None:
    tgsis.find_conflicts(conn, "e1")
    before = stored(conn)
    marks = _marks(conn, fault)
    state, message, _ = _sqlstate(
        conn,
        "SELECT tgsis.record_conflict_regions('e1', 'feature', %s, %s, %s, %s)",
        (str(fault), *marks, json.dumps(payload)),
    )
    assert state == "TG100" and said in message and "'e1'" in message, message
    assert stored(conn) == before


def test_record_refuses_stale_marks_and_unknown_objects(conn: Conn, fault: int) -> None:
    tgsis.find_conflicts(conn, "e1")
    before = stored(conn)
    marks = _marks(conn, fault)
    state, message, hint = _sqlstate(
        conn,
        "SELECT tgsis.record_conflict_regions('e1', 'feature', %s, %s, %s, '[]')",
        (str(fault), marks[0], "not-the-mark"),
    )
    assert state == "TG307" and "changed since" in message and hint is not None and "again" in hint
    state, message, _ = _sqlstate(
        conn, "SELECT tgsis.record_conflict_regions('e1', 'feature', '999', %s, %s, '[]')", marks
    )
    assert state == "TG200" and "'999'" in message
    assert stored(conn) == before


def test_a_conflict_that_does_not_merge_by_region_says_why(conn: Conn, fault_clone: int) -> None:
    geoid = fault_clone
    move(conn, "e1", geoid, NORTH, (0.5, 0.0, 1.25))
    with tgsis.in_version(conn, "DEFAULT"):
        tgsis.delete_feature(conn, "faults", geoid)
    conn.commit()
    [conflict] = tgsis.find_conflicts(conn, "e1")
    assert conflict.regions == () and conflict.region_refusal is not None
    assert "deleted" in conflict.region_refusal
    assert stored(conn) == []


def test_two_sessions_recording_at_once_both_succeed(db_dsn: str, conn: Conn, fault: int) -> None:
    results: list[Any] = []
    barrier = threading.Barrier(2)

    def run() -> None:
        with psycopg.connect(db_dsn) as other:
            barrier.wait()
            try:
                results.append(tgsis.find_conflicts(other, "e1"))
            except Exception as exc:  # noqa: BLE001 - reported below
                results.append(exc)

    threads = [threading.Thread(target=run) for _ in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert all(not isinstance(r, Exception) for r in results), results
    assert [len(r[0].regions) for r in results] == [3, 3]
    rows = conn.execute("SELECT count(*), count(DISTINCT region) FROM tgsis.conflict_regions").fetchone()
    assert rows == (3, 3)


def test_a_role_without_rights_records_nothing(db_dsn: str, conn: Conn, fault: int) -> None:
    with login_roles(db_dsn, {"reader": "tgsis_reader", "editor": "tgsis_editor"}) as roles:
        reader = roles.connect("reader")
        [conflict] = tgsis.find_conflicts(reader, "e1")  # computed for the reader, nothing stored
        assert len(conflict.regions) == 3 and stored(conn) == []
        marks = _marks(conn, fault)
        state, message, _ = _sqlstate(
            reader,
            "SELECT tgsis.record_conflict_regions('e1', 'feature', %s, %s, %s, '[]')",
            (str(fault), *marks),
        )
        assert state == "TG002" and roles.name("reader") in message
        tgsis.find_conflicts(conn, "e1")
        before = stored(conn)
        assert len(before) == 3
        state, _, _ = _sqlstate(reader, "DELETE FROM tgsis.conflict_regions", ())
        assert state == "42501"
        editor = roles.connect("editor")  # no right on e1
        state, _, _ = _sqlstate(editor, "UPDATE tgsis.conflict_regions SET solution = 'parent'", ())
        assert state == "42501"
        assert reader.execute("SELECT count(*) FROM tgsis.conflict_regions").fetchone() == (3,)  # readers read
        reader.rollback()
        assert stored(conn) == before


def test_the_sql_merge_hint_points_to_the_python_merge(conn: Conn, fault: int) -> None:
    tgsis.find_conflicts(conn, "e1")
    state, message, hint = _sqlstate(conn, "SELECT tgsis.merge_version('e1')", ())
    assert state == "TG302" and hint is not None
    assert "tgsis version merge e1" in hint and 'tgsis.merge_version(conn, "e1")' in hint, hint
    state, _, hint = _sqlstate(conn, "SELECT tgsis.refresh_version('e1')", ())
    assert state == "TG302" and hint is not None and "tgsis version refresh e1" in hint


def test_pg_dump_and_restore_keep_unresolved_and_resolved_regions(
    conn: Conn, fault: int, pg: Any, db_dsn: str, tmp_path: Any
) -> None:
    from tests.test_backup import _bindir_of, _restored

    lone = 8 * SIDE + 2  # a second conflicting region, left unsolved
    move(conn, "e1", fault, [lone], (0.0, 0.0, 3.0))
    move(conn, "DEFAULT", fault, [lone], (0.0, 0.0, -3.0))
    conn.commit()
    [conflict] = tgsis.find_conflicts(conn, "e1")
    conflicts = [r for r in conflict.regions if r.conflict]
    assert len(conflicts) == 2
    tgsis.resolve_region(conn, "e1", fault, conflicts[0].region, "child")
    before = stored(conn)
    assert len(before) == 4
    solutions = conn.execute("SELECT solution FROM tgsis.conflict_regions WHERE conflict ORDER BY region").fetchall()
    conn.rollback()
    assert solutions == [("child",), ("unsolved",)]
    for fmt in ("plain", "custom"):
        with _restored(pg, _bindir_of(pg), db_dsn, fmt, tmp_path) as dsn:
            with psycopg.connect(dsn) as restored:
                assert stored(restored) == before
                [again] = tgsis.find_conflicts(restored, "e1")  # the same marks there: the solutions hold
                assert [r.solution for r in again.regions if r.conflict] == ["child", "unsolved"]
                assert stored(restored) == before


def test_a_role_that_may_not_read_the_class_gets_the_list_with_why(db_dsn: str, conn: Conn, fault: int) -> None:
    conn.execute("REVOKE SELECT ON public.faults FROM tgsis_reader")
    conn.commit()
    with login_roles(db_dsn, {"rita": "tgsis_reader"}) as roles:
        [conflict] = tgsis.find_conflicts(roles.connect("rita"), "e1")
    assert conflict.objectkey == str(fault) and conflict.regions == ()
    assert conflict.region_refusal is not None and "may not read" in conflict.region_refusal
    assert stored(conn) == []


def test_inside_a_callers_read_committed_transaction_the_regions_are_stored_with_it(conn: Conn, fault: int) -> None:
    """How a merge calls it: in its own transaction (a savepoint here); a rollback takes the regions back."""
    conn.execute("SELECT 1")  # the caller's transaction is open (read committed)
    with conn.transaction():
        [conflict] = tgsis.find_conflicts(conn, "e1")
        assert len(conflict.regions) == 3
        assert conn.execute("SELECT count(*) FROM tgsis.conflict_regions").fetchone() == (3,)
    conn.rollback()
    assert stored(conn) == []
    with conn.transaction():
        tgsis.find_conflicts(conn, "e1")
    conn.commit()
    assert len(stored(conn)) == 3


def test_the_command_line_merge_hint_names_the_command(
    conn: Conn, db_dsn: str, fault: int, capsys: pytest.CaptureFixture[str]
) -> None:
    from tests.test_cli_hints import hint_of

    tgsis.find_conflicts(conn, "e1")
    hint = hint_of(db_dsn, capsys, "version", "merge", "e1")
    assert "tgsis version merge e1 merges them" in hint and "--region N" in hint, hint
    hint = hint_of(db_dsn, capsys, "version", "resolve", "e1", "feature", str(fault), "child")
    assert "tgsis version resolve e1" in hint and "--region N" in hint, hint
