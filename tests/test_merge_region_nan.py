"""The merge by region with NaN or infinite coordinates (plan G, X3): refused by name, never silently merged.

A psql UPDATE stores NaN coordinates bit for bit. PostgreSQL's float8 comparisons take NaN as equal to NaN
and above every number (not IEEE's "false"), so SQL region detection sees such a vertex as changed or not as
merge3 would; but merge3 takes no mesh with non-finite coordinates. The merge of such an object, in SQL as in
Python, is refused (TG302, naming the state and the vertices, nothing written), and SQL region detection
stores no region for it (as Python's and the instants' detection), so that no region is offered for a
solution the merge will refuse. Runs on model 1's storage of the run (TGSIS_TEST_STORAGE rows or chunks).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import psycopg
import pytest

import tgsis
import tgsis.errors
from tests.merge_data import SIDE, merge_storage_state, move, sqlstate

Conn = psycopg.Connection[Any]

NORTH = np.arange(0, 2 * SIDE)


@pytest.fixture
def fault(conn: Conn, fault_clone: int) -> int:
    return fault_clone  # make_fault's, built once (tests/conftest.py)


def _nan_in(conn: Conn, version: str, geoid: int, vrtxid: int, value: str = "NaN") -> None:
    with tgsis.in_version(conn, version):
        conn.execute("UPDATE tgsis.vrtx SET x = %s::float8 WHERE geoid = %s AND vrtxid = %s", (value, geoid, vrtxid))
    conn.commit()


def _state(conn: Conn) -> str:
    """What "nothing written" compares: the stored versions, as text (NaN equals NaN there, not in a tuple)."""
    return repr(merge_storage_state(conn))


def _regions(conn: Conn, geoid: int) -> int:
    row = conn.execute(
        "SELECT count(*) FROM tgsis.conflict_regions WHERE versionid = tgsis.version_id('e1') AND objectkey = %s",
        (str(geoid),),
    ).fetchone()
    assert row is not None
    return int(row[0])


@pytest.mark.parametrize("value", ["NaN", "Infinity"])
@pytest.mark.parametrize("where", ["conflict", "own region"])
def test_a_non_finite_coordinate_in_a_changed_region_is_refused_by_name(
    conn: Conn, fault: int, where: str, value: str
) -> None:
    move(conn, "e1", fault, NORTH, (0.5, 0.0, 1.25))
    move(conn, "DEFAULT", fault, NORTH[:5] if where == "conflict" else [SIDE * SIDE - 1], (-1.0, 0.0, -2.0))
    _nan_in(conn, "e1", fault, 3, value)
    before = _state(conn)

    # SQL (psql): refused by name, nothing written
    state, message = sqlstate(conn, "SELECT tgsis.merge_version('e1')")
    assert state == "TG302", message
    assert "non-finite coordinates" in message and "(child)" in message, message
    conn.rollback()
    assert _state(conn) == before

    # SQL region detection stores no region for it (Python's does not either)
    conn.execute("SELECT FROM tgsis.find_conflicts('e1')")
    assert _regions(conn, fault) == 0
    conn.rollback()

    # Python: refused (merge3 takes no such mesh), nothing written
    with pytest.raises(tgsis.errors.Error) as refused:
        tgsis.merge_version(conn, "e1")
    assert "finite" in str(refused.value), (type(refused.value), str(refused.value))
    conn.rollback()
    assert _state(conn) == before


def test_after_the_coordinate_is_corrected_the_merge_goes_through(conn: Conn, fault: int) -> None:
    move(conn, "e1", fault, NORTH, (0.5, 0.0, 1.25))
    move(conn, "DEFAULT", fault, [SIDE * SIDE - 1], (-1.0, 0.0, -2.0))
    _nan_in(conn, "e1", fault, 3)
    assert sqlstate(conn, "SELECT tgsis.merge_version('e1')")[0] == "TG302"
    conn.rollback()
    _nan_in(conn, "e1", fault, 3, "7.5")
    tgsis.merge_version(conn, "e1")
    conn.commit()
    row = conn.execute("SELECT x FROM tgsis.vrtx WHERE geoid = %s AND vrtxid = 3", (fault,)).fetchone()
    assert row == (7.5,)
