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
