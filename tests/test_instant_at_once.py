"""``tgsis.vertices_at`` / ``triangles_at`` of a model-2 surface choose its instant once per call, not once per row.

The instant is ``tgsis.instant_at(geoid, t, convention)`` (three reads of
``tgsis.times``). Written as a plain comparison (``times = instant_at(...)``)
it is a constant to the planner only when it becomes an index condition; over
the versioned view of a row table it stayed a filter, evaluated per row of
the surface's every instant: a snapshot at t of a 1,600-vertex versioned
surface took 10-27 s on PostgreSQL 15 (the 41 s test of
``test_model2_chunks.py``, docs/testing.md). As a scalar subquery (an
InitPlan) it is evaluated once whatever the plan; counted here with
``track_functions``, not timed.
"""

from __future__ import annotations

from typing import Any

import psycopg
import pytest

Conn = psycopg.Connection[Any]


def _instant_at_calls(conn: Conn) -> int:
    row = conn.execute(
        "SELECT coalesce(sum(calls), 0) FROM pg_stat_xact_user_functions WHERE schemaname = 'tgsis' AND funcname = 'instant_at'"
    ).fetchone()
    assert row is not None
    return int(row[0])


@pytest.mark.parametrize("reader", ["vertices_at", "triangles_at"])
@pytest.mark.parametrize(("t", "instant"), [(1.0, 1.0), (2.5, 2.0)])
def test_the_instant_is_chosen_once_per_call_of_a_versioned_surface(
    conn: Conn, series_clone: int, reader: str, t: float, instant: float
) -> None:
    conn.execute("SET track_functions = 'all'")
    table = "times_vrtx" if reader == "vertices_at" else "times_trgl"
    expected = conn.execute(
        f"SELECT count(*) FROM tgsis.{table} WHERE geoid = %s AND times = %s", (series_clone, instant)
    ).fetchone()
    assert expected is not None and expected[0] > 100
    for query in (
        f"SELECT count(*) FROM tgsis.{reader}(%s, %s)",
        # as the Python readers call it (tgsis.db._temporal_common): the geoid a column of the outer query
        f"SELECT count(*) FROM unnest(ARRAY[%s]::bigint[]) f(geoid), LATERAL tgsis.{reader}(f.geoid, %s) v",
    ):
        before = _instant_at_calls(conn)
        (rows,) = conn.execute(query, (series_clone, t)).fetchone()  # type: ignore[misc]
        calls = _instant_at_calls(conn) - before
        assert rows == expected[0], query
        assert 1 <= calls <= 2, f"tgsis.instant_at ran {calls} times for {rows} rows: {query}"
