"""Random one-sided edits of a surface at instants: the psql merge writes exactly what the Python merge writes.

Hypothesis draws, per instant of a model-2 surface, which side edits it
(none, the parent, the version, or both alike) and how (vertices moved, a
triangle removed, vertex property values changed, the per-instant property
changed, the instant removed), and whether a side adds an instant; then a
psql ``tgsis.merge_version`` or ``refresh_version`` must write every row
version, revision note, version and conflict the Python merge writes, and
count the same rows (tests.test_sql_merge_write.assert_same_merge). A few
examples only (CI time): 6 per run, each a new version on the committed state
the examples before left in DEFAULT.
"""

from __future__ import annotations

import itertools
from typing import Any

import psycopg
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import tgsis
from tests.merge_data import SIDE
from tests.test_merge_instants import make_series, move
from tests.test_sql_merge_slices import _new_surface, _sql
from tests.test_sql_merge_write import assert_same_merge

Conn = psycopg.Connection[Any]

_versions = itertools.count()

_edit = st.sampled_from(["move", "cells", "values", "throw", "delete"])
_side = st.sampled_from(["none", "parent", "child", "both"])


def _apply(conn: Conn, version: str, geoid: int, t: float, edit: str, first: int, shift: float) -> None:
    ids = list(range(first, first + SIDE))
    if edit == "move":
        move(conn, version, geoid, t, ids, (shift, 0.0, -shift))
    elif edit == "cells":
        _sql(
            conn,
            version,
            "DELETE FROM tgsis.times_trgl WHERE geoid = %s AND times = %s AND trglid = %s",
            (geoid, t, first),
        )
    elif edit == "values":
        _sql(
            conn,
            version,
            "UPDATE horizons_cellpros SET porosity = porosity * %s WHERE _geoid = %s AND _times = %s AND _idx = ANY(%s)",
            (shift, geoid, t, ids),
        )
    elif edit == "throw":
        _sql(conn, version, "UPDATE horizons_pros SET throw = %s WHERE _geoid = %s AND _times = %s", (shift, geoid, t))
    else:
        with tgsis.in_version(conn, version):
            tgsis.delete_instant(conn, geoid, t)
        conn.commit()


@settings(
    max_examples=6, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow]
)
@given(
    plan=st.lists(st.tuples(_side, _edit, st.integers(0, SIDE * (SIDE - 1) - 1)), min_size=3, max_size=3),
    adder=_side,
    action=st.sampled_from(["merge", "refresh"]),
)
def test_random_one_sided_edits_of_instants_merge_in_psql_exactly_as_in_python(
    conn: Conn, plan: list[tuple[str, str, int]], adder: str, action: str
) -> None:
    if not conn.execute("SELECT 1 FROM tgsis.catalog WHERE classname = 'horizons'").fetchone():
        conn.rollback()
        make_series(conn)
    conn.rollback()
    geoid = int(conn.execute("SELECT geoid FROM tgsis.geometry ORDER BY geoid LIMIT 1").fetchone()[0])  # type: ignore[index]
    n = next(_versions)
    version = f"h{n}"
    tgsis.create_version(conn, version)
    conn.commit()
    with tgsis.in_version(conn, "DEFAULT"):
        times = [
            float(r[0]) for r in conn.execute("SELECT times FROM tgsis.times WHERE geoid = %s ORDER BY 1", (geoid,))
        ]
    conn.commit()
    removed = 0
    for t, (side, edit, first) in zip(times, plan, strict=False):
        if edit == "delete" and (side == "both" or removed == len(times) - 1):
            edit = "move"  # (an instant removed on both sides merges too, but keep one instant at least)
        removed += edit == "delete"
        sides = {"none": [], "parent": ["DEFAULT"], "child": [version], "both": ["DEFAULT", version]}[side]
        for who in sides:
            _apply(conn, who, geoid, t, edit, first, 1.0 + n / 8.0)
    if adder != "none":
        added = 10.0 + n
        for who in {"parent": ["DEFAULT"], "child": [version], "both": ["DEFAULT", version]}[adder]:
            with tgsis.in_version(conn, who):
                tgsis.add_instant(conn, "horizons", geoid, added, _new_surface(n % 3), {"throw": added})
            conn.commit()
    if not conn.execute(
        "SELECT 1 FROM tgsis.find_conflicts(%s) WHERE objectclass = 'feature'", (version,)
    ).fetchone():  # (no edit on one side: nothing to merge by parts; the plain merge, which the others test)
        conn.rollback()
        return
    conn.rollback()
    assert_same_merge(conn, version, action)
