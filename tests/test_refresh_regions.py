"""tgsis.refresh_version by region: the parent's edits of a mesh come into the version beside its own (issue 39)."""

from __future__ import annotations

from typing import Any

import numpy as np
import psycopg
import pytest

import tgsis
from tests.merge_data import SIDE, curved_surface, merge_storage_state, move, moved, stored_state
from tests.roles import login_roles

Conn = psycopg.Connection[Any]

NORTH = np.arange(0, 2 * SIDE)
SOUTH = np.arange((SIDE - 2) * SIDE, SIDE * SIDE)
CHILD_SHIFT = (0.375, 2.2, -6.51)
PARENT_SHIFT = (4.4, -0.5, 1.03)


@pytest.fixture
def fault(conn: Conn, fault_clone: int) -> int:
    return fault_clone  # make_fault's, built once (tests/conftest.py)


def test_disjoint_edits_refresh_into_the_union_and_the_parent_is_unchanged(conn: Conn, fault: int) -> None:
    move(conn, "e1", fault, NORTH, CHILD_SHIFT)
    move(conn, "DEFAULT", fault, SOUTH, PARENT_SHIFT)
    conn.commit()
    parent_before = stored_state(conn, "DEFAULT", fault)
    result = tgsis.refresh_version(conn, "e1")
    assert [(o.objectkey, o.how) for o in result.objects] == [(str(fault), "automatic")]
    expected = curved_surface().vertices.copy()
    moved(expected, NORTH, CHILD_SHIFT)
    moved(expected, SOUTH, PARENT_SHIFT)
    ids, xyz, cells, _ = stored_state(conn, "e1", fault)
    np.testing.assert_array_equal(ids, np.arange(SIDE * SIDE))
    assert xyz.tobytes() == expected.tobytes()
    assert cells == {(i, *map(int, c)) for i, c in enumerate(curved_surface().cells)}
    after = stored_state(conn, "DEFAULT", fault)
    assert after[1].tobytes() == parent_before[1].tobytes() and after[2] == parent_before[2]
    assert tgsis.find_conflicts(conn, "e1") == []  # the version's base moved: nothing left to merge
    # the version goes on: a later edit of the parent elsewhere refreshes in again
    move(conn, "DEFAULT", fault, [70], (0.0, 0.0, 1.0))
    conn.commit()
    tgsis.refresh_version(conn, "e1")
    moved(expected, [70], (0.0, 0.0, 1.0))
    assert stored_state(conn, "e1", fault)[1].tobytes() == expected.tobytes()


def test_an_unsolved_region_refuses_the_refresh_and_nothing_changes(conn: Conn, fault: int) -> None:
    move(conn, "e1", fault, [50, 51, 52], (0.0, 0.0, 5.0))
    move(conn, "DEFAULT", fault, [52, 53], (0.0, 0.0, -4.0))
    conn.commit()
    before = merge_storage_state(conn)
    with pytest.raises(tgsis.UnsolvedConflictsError, match=rf"feature {fault}: region 0 unsolved"):
        tgsis.refresh_version(conn, "e1")
    assert merge_storage_state(conn) == before


def test_a_role_that_may_not_write_in_the_version_cannot_refresh(conn: Conn, fault: int, db_dsn: str) -> None:
    move(conn, "e1", fault, NORTH, CHILD_SHIFT)
    move(conn, "DEFAULT", fault, SOUTH, PARENT_SHIFT)
    conn.commit()
    before = merge_storage_state(conn)
    with login_roles(db_dsn, {"rita": "tgsis_reader"}) as made:
        with pytest.raises(tgsis.MissingPrivilegeError, match="refresh"):
            tgsis.refresh_version(made.connect("rita"), "e1")
    assert merge_storage_state(conn) == before


def test_a_caller_repeatable_read_transaction_is_refused(conn: Conn, fault: int) -> None:
    move(conn, "e1", fault, NORTH, CHILD_SHIFT)
    move(conn, "DEFAULT", fault, SOUTH, PARENT_SHIFT)
    conn.commit()
    conn.isolation_level = psycopg.IsolationLevel.REPEATABLE_READ
    with pytest.raises(tgsis.Error, match="(?i)read committed"):
        tgsis.refresh_version(conn, "e1")
    conn.rollback()
    conn.isolation_level = None
