"""Conflicts between a version and its parent: detection per object class and key, solutions, both sides' rows."""

from __future__ import annotations

from typing import Any

import psycopg
import pytest

import tgsis
from tests.conftest import BuiltOnce, cloned_or_built
from tests.synthetic import flat_grid
from tgsis.db import features as F

Conn = psycopg.Connection[Any]


def make_surfaces(conn: Conn) -> int:
    """Three surfaces A, B, C in DEFAULT, versioned, and a child version 'edit'; A's geoid (B's, C's follow)."""
    F.create_feature_class(conn, "horizons", "SURFACE", feature_properties={"note": "text"})
    tgsis.enable_feature_versioning(conn)
    ids = [F.insert_feature(conn, "horizons", flat_grid(4, z)) for z in (1.0, 2.0, 3.0)]
    assert ids == list(range(ids[0], ids[0] + 3)), ids
    tgsis.create_version(conn, "edit")
    conn.commit()
    return ids[0]


BUILT_ONCE = {"surfaces": make_surfaces}  # built once, cloned per test (db_dsn, tests/conftest.py)


@pytest.fixture
def surfaces(request: pytest.FixtureRequest, conn: Conn, built_once: BuiltOnce) -> dict[str, int]:
    """``make_surfaces``'s surfaces by name, already in the test's database (cloned, not built again)."""
    first = cloned_or_built(request, conn, built_once, "surfaces", make_surfaces)
    return {name: first + i for i, name in enumerate("ABC")}


def _move_vertex(conn: Conn, geoid: int, dz: float) -> None:
    conn.execute("UPDATE tgsis.vrtx SET z = z + %s WHERE geoid = %s AND vrtxid = 0", (dz, geoid))


def test_only_objects_changed_on_both_sides_conflict(conn: Conn, surfaces: dict[str, int]) -> None:
    with tgsis.in_version(conn, "edit"):
        _move_vertex(conn, surfaces["A"], 1)
        _move_vertex(conn, surfaces["B"], 1)
        conn.commit()
    _move_vertex(conn, surfaces["A"], -1)  # DEFAULT moves A too
    conn.execute("UPDATE horizons SET note = 'checked' WHERE _geoid = %s", (surfaces["C"],))  # and C alone
    conn.commit()
    conflicts = tgsis.find_conflicts(conn, "edit")
    assert conflicts == [tgsis.Conflict("feature", str(surfaces["A"]), ("vrtx",), ("vrtx",), ("vrtx",), "unsolved")]
    # both sides' rows of A: the moved vertex, once per side
    rows = tgsis.conflict_rows(conn, "edit", "feature", surfaces["A"])
    assert [(t, side, key) for t, side, key, _ in rows] == [
        ("vrtx", "child", {"geoid": surfaces["A"], "vrtxid": 0}),
        ("vrtx", "parent", {"geoid": surfaces["A"], "vrtxid": 0}),
    ]
    assert rows[0][3]["z"] == 2.0 and rows[1][3]["z"] == 0.0
    with pytest.raises(tgsis.NotFoundError, match="object class 'features' does not exist"):
        tgsis.conflict_rows(conn, "edit", "features", surfaces["A"])
    conn.rollback()


def test_different_tables_of_one_object_still_conflict(conn: Conn, surfaces: dict[str, int]) -> None:
    with tgsis.in_version(conn, "edit"):
        _move_vertex(conn, surfaces["B"], 1)
        conn.commit()
    conn.execute("UPDATE horizons SET note = 'parent' WHERE _geoid = %s", (surfaces["B"],))
    conn.commit()
    [conflict] = tgsis.find_conflicts(conn, "edit")
    assert (conflict.conflicttype, conflict.childtables, conflict.parenttables) == ((), ("vrtx",), ("public.horizons",))


def test_solutions_hold_until_either_side_changes_again(conn: Conn, surfaces: dict[str, int]) -> None:
    a = surfaces["A"]
    with tgsis.in_version(conn, "edit"):
        _move_vertex(conn, a, 1)
        conn.commit()
    _move_vertex(conn, a, -1)
    conn.commit()
    assert tgsis.resolve_conflict(conn, "edit", "feature", a, "child").solution == "child"
    assert [c.solution for c in tgsis.find_conflicts(conn, "edit")] == ["child"]  # nothing changed since
    _move_vertex(conn, a, -1)  # the parent again
    conn.commit()
    assert [c.solution for c in tgsis.find_conflicts(conn, "edit")] == ["unsolved"]
    # manual: write the merged object into the version, then record it
    with tgsis.in_version(conn, "edit"):
        conn.execute("UPDATE tgsis.vrtx SET z = 1.5 WHERE geoid = %s AND vrtxid = 0", (a,))
        conn.commit()
    assert tgsis.resolve_conflict(conn, "edit", "feature", a, "MANUAL").solution == "manual"
    assert [c.solution for c in tgsis.find_conflicts(conn, "edit")] == ["manual"]
    row = conn.execute("SELECT solved_by IS NOT NULL, solved_at IS NOT NULL FROM tgsis.conflicts").fetchone()
    assert row == (True, True)


def test_a_conflict_that_went_away_is_removed(conn: Conn, surfaces: dict[str, int]) -> None:
    with tgsis.in_version(conn, "edit"):
        conn.execute("UPDATE tgsis.vrtx SET z = z + 1 WHERE geoid = %s AND vrtxid = 3", (surfaces["A"],))
        conn.commit()
    conn.execute("UPDATE tgsis.vrtx SET z = z + 1 WHERE geoid = %s AND vrtxid = 3", (surfaces["A"],))
    conn.commit()
    assert len(tgsis.find_conflicts(conn, "edit")) == 1
    tgsis.delete_version(conn, "edit")  # its conflicts go with it
    assert conn.execute("SELECT count(*) FROM tgsis.conflicts").fetchone() == (0,)


def test_errors_write_nothing(conn: Conn, surfaces: dict[str, int]) -> None:
    with pytest.raises(tgsis.NotFoundError, match="version 'nope' does not exist"):
        tgsis.find_conflicts(conn, "nope")
    with pytest.raises(tgsis.InvalidInputError, match="DEFAULT has no parent"):
        tgsis.find_conflicts(conn, "DEFAULT")
    with pytest.raises(
        tgsis.InvalidInputError, match="solution 'mine' is not parent, child, base, average, manual or unsolved"
    ):
        tgsis.resolve_conflict(conn, "edit", "feature", surfaces["A"], "mine")
    with pytest.raises(tgsis.NotFoundError, match=f"object '{surfaces['A']}' of class 'feature' is not in conflict"):
        tgsis.resolve_conflict(conn, "edit", "feature", surfaces["A"], "child")
    assert conn.execute("SELECT count(*) FROM tgsis.conflicts").fetchone() == (0,)
