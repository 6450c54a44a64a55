"""The psql merge of model-2 surfaces (surfaces at instants), instant by instant (issue 39, item 2).

A psql user's ``SELECT tgsis.merge_version(v)`` / ``tgsis.refresh_version(v)``
merges a surface at instants whose instants were each changed on one side
only (or alike on both): an instant moved, added or removed on one side, the
other side's edits at other instants, the per-instant feature properties
column by column (docs/merge.md, "Models 2 and 3"). The oracle is the Python
merge (``tgsis.merge_version(conn, v)``), row version for row version
(tests.test_sql_merge_write.both_merges). An instant changed on both sides
differently (its regions) is still refused from psql (TG302) naming
``tgsis version merge NAME``; what cannot be split is refused as in Python.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import psycopg
import pytest

import tgsis
from tests.test_merge_instants import CHILD_SHIFT, NORTH, PARENT_SHIFT, SOUTH, TIMES, make_series, move
from tests.test_sql_merge_write import assert_same_merge, both_merges, everything

Conn = psycopg.Connection[Any]


@pytest.fixture
def series(conn: Conn) -> int:
    return make_series(conn)


def _sql(conn: Conn, version: str, text: str, args: tuple[Any, ...] = ()) -> None:
    """One statement a psql user runs in ``version`` (committed)."""
    with tgsis.in_version(conn, version):
        conn.execute(text, args)
    conn.commit()


@pytest.mark.parametrize(("action", "remove"), [("merge", False), ("merge", True), ("refresh", False)])
def test_edits_at_different_instants_merge_in_psql_exactly_as_in_python(
    conn: Conn, series: int, action: str, remove: bool
) -> None:
    move(conn, "e1", series, TIMES[0], NORTH, CHILD_SHIFT)
    move(conn, "DEFAULT", series, TIMES[2], SOUTH, PARENT_SHIFT)
    assert_same_merge(conn, "e1", action, remove)


def _new_surface(i: int, factor: float = 2.0) -> Any:
    from tests.merge_data import curved_surface
    from tests.test_merge_instants import _porosity, _shape

    return tgsis.Surface(_shape(i), curved_surface().cells, vertex_properties={"porosity": _porosity() * factor})


def _add_instant(conn: Conn, version: str, geoid: int, t: float, throw: float) -> None:
    with tgsis.in_version(conn, version):
        tgsis.add_instant(conn, "horizons", geoid, t, _new_surface(int(t) + 4), {"throw": throw})
    conn.commit()


def _delete_instant(conn: Conn, version: str, geoid: int, t: float) -> None:
    with tgsis.in_version(conn, version):
        tgsis.delete_instant(conn, geoid, t)
    conn.commit()


# what each side does, as (version, step) pairs: every one merges instant by instant in Python
SCENARIOS: dict[str, list[tuple[str, str]]] = {
    "parent adds an instant, version moves": [("DEFAULT", "add 4"), ("e1", "move 2 north")],
    "version adds an instant, parent moves": [("e1", "add 4"), ("DEFAULT", "move 2 south")],
    "both add the same instant alike": [("e1", "add 4"), ("DEFAULT", "add 4"), ("e1", "move 1 north")],
    "version removes an instant, parent moves another": [("e1", "delete 2"), ("DEFAULT", "move 3 south")],
    "parent removes an instant, version moves another": [("DEFAULT", "delete 1"), ("e1", "move 3 north")],
    "same edit on both sides, one more in the version": [
        ("e1", "same 2 north"),
        ("DEFAULT", "same 2 north"),
        ("e1", "move 3 south"),
    ],
    "version edits triangles and properties of an instant the parent moved elsewhere": [
        ("e1", "cells 2"),
        ("DEFAULT", "move 1 south"),
        ("DEFAULT", "move 3 south"),
    ],
    "parent edits triangles and properties, version moves": [("DEFAULT", "cells 2"), ("e1", "move 1 north")],
    "parent changes a per-instant property, version moves": [("DEFAULT", "throw 2 25"), ("e1", "move 3 north")],
    "both change per-instant properties of other instants": [
        ("DEFAULT", "throw 2 25"),
        ("e1", "throw 3 35"),
        ("e1", "move 1 north"),
    ],
    "version moves an instant twice, parent another": [
        ("e1", "move 2 north"),
        ("e1", "move 2 north"),
        ("DEFAULT", "move 3 south"),
    ],
}


def _step(conn: Conn, version: str, step: str, geoid: int) -> None:
    what, *args = step.split()
    if what in ("move", "same"):  # same: the version's shift on either side
        shift = CHILD_SHIFT if version == "e1" or what == "same" else PARENT_SHIFT
        move(conn, version, geoid, float(args[0]), NORTH if args[1] == "north" else SOUTH, shift)
    elif what == "add":
        _add_instant(conn, version, geoid, float(args[0]), 44.0)
    elif what == "delete":
        _delete_instant(conn, version, geoid, float(args[0]))
    elif what == "throw":
        _sql(conn, version, "UPDATE horizons_pros SET throw = %s WHERE _geoid = %s AND _times = %s",
             (float(args[1]), geoid, float(args[0])))
    elif what == "cells":  # a triangle removed, one added on existing vertices, property values changed
        t = float(args[0])
        _sql(conn, version, "DELETE FROM tgsis.times_trgl WHERE geoid = %s AND times = %s AND trglid = 7", (geoid, t))
        _sql(conn, version, "INSERT INTO tgsis.times_trgl (geoid, times, trglid, vrtxid1, vrtxid2, vrtxid3)"
             " SELECT geoid, times, 100000, vrtxid1, vrtxid3, vrtxid2 FROM tgsis.times_trgl"
             " WHERE geoid = %s AND times = %s AND trglid = 40", (geoid, t))
        _sql(conn, version, "UPDATE horizons_cellpros SET porosity = -0.0 WHERE _geoid = %s AND _times = %s"
             " AND _idx BETWEEN 30 AND 33", (geoid, t))
        _sql(conn, version, "DELETE FROM horizons_cellpros WHERE _geoid = %s AND _times = %s AND _idx = 50", (geoid, t))
    else:
        raise AssertionError(step)


@pytest.mark.parametrize("scenario", list(SCENARIOS))
def test_instants_changed_on_one_side_merge_in_psql_exactly_as_in_python(
    conn: Conn, series: int, scenario: str
) -> None:
    for version, step in SCENARIOS[scenario]:
        _step(conn, version, step, series)
    assert_same_merge(conn, "e1")


# what the Python merge leaves unsolved (TG302), or merges where psql refuses naming it (an instant both sides
# changed differently: its regions)
REFUSED: dict[str, tuple[list[tuple[str, str]], str]] = {
    "an instant removed on one side and changed on the other": (
        [("e1", "delete 2"), ("DEFAULT", "move 2 south")],
        "TG302",
    ),
    "an instant added on both sides differently": ([("e1", "add 4"), ("DEFAULT", "add 4"), ("DEFAULT", "move 4 south")], "TG302"),
    "a per-instant property changed on both sides": ([("e1", "throw 2 21"), ("DEFAULT", "throw 2 22")], "TG302"),
    "an instant moved on both sides differently": ([("e1", "move 2 north"), ("DEFAULT", "move 2 south")], "python"),
}


@pytest.mark.parametrize("scenario", list(REFUSED))
def test_what_psql_does_not_merge_instant_by_instant_is_refused_and_nothing_is_written(
    conn: Conn, series: int, scenario: str
) -> None:
    steps, python = REFUSED[scenario]
    for version, step in steps:
        _step(conn, version, step, series)
    before = everything(conn)
    conn.commit()
    theirs, mine = both_merges(conn, "e1")
    assert mine[:2] == ("refused", "TG302"), mine
    if python == "python":  # Python merges it (the instant's regions); psql names the command that does
        assert theirs[0] == "done"
        assert "instants 2 were changed both in the version and in its parent" in mine[2]
        assert "`tgsis version merge e1`" in mine[2]
    else:
        assert theirs[:2] == ("refused", "TG302"), theirs
    assert everything(conn) == before
    conn.commit()
