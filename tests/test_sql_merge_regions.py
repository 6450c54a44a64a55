"""Region detection and solutions of the merge by region in SQL (issue 39, items 2, 4, 5 from psql).

The oracle is the Python three-way merge (tgsis.merge3 through
``tgsis.object_merge``): the regions SQL ``tgsis.find_conflicts`` stores
must be exactly those merge3 computes, for hand-written edits and random ones.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import psycopg
import pytest

import tgsis
from tests.merge_data import SIDE, make_fault, move

Conn = psycopg.Connection[Any]

NORTH = np.arange(0, 2 * SIDE)
SOUTH = np.arange((SIDE - 2) * SIDE, SIDE * SIDE)
MIDDLE = np.array([5 * SIDE + 5, 5 * SIDE + 6, 6 * SIDE + 5, 6 * SIDE + 6])
_IDS = ("vertex_ids", "cell_ids", "parent_vertex_ids", "parent_cell_ids", "child_vertex_ids", "child_cell_ids")


def sql_regions(conn: Conn, version: str, geoid: int) -> list[dict[str, Any]]:
    """What SQL tgsis.find_conflicts stores for the feature, without any Python region call (then rolled back)."""
    conn.execute("SELECT FROM tgsis.find_conflicts(%s)", (version,))
    rows = conn.execute(
        "SELECT region, conflict, changed_by, vertex_ids, cell_ids, parent_vertex_ids, parent_cell_ids,"
        " child_vertex_ids, child_cell_ids, bbox, parent_displacement, child_displacement, solution"
        "  FROM tgsis.conflict_regions WHERE versionid = tgsis.version_id(%s) AND objectkey = %s ORDER BY region",
        (version, str(geoid)),
    ).fetchall()
    conn.rollback()
    names = ("region", "conflict", "changed_by", *_IDS, "bbox", "parent_displacement", "child_displacement", "solution")
    return [dict(zip(names, r, strict=True)) for r in rows]


def python_regions(conn: Conn, version: str, geoid: int) -> list[dict[str, Any]]:
    """The regions merge3 computes for the feature (tgsis.object_merge: read-only)."""
    merge = tgsis.object_merge(conn, version, geoid)
    conn.rollback()
    out = []
    for r in merge.regions:
        bounds = np.asarray(r.bounds, dtype=np.float64).ravel()
        out.append(
            {
                "region": r.index,
                "conflict": r.conflict,
                "changed_by": r.sides,
                **{n: [int(i) for i in getattr(r, n)] for n in _IDS},
                "bbox": [float(v) for v in bounds] if np.all(np.isfinite(bounds)) else None,
                "parent_displacement": float(r.parent_displacement),
                "child_displacement": float(r.child_displacement),
                "solution": "unsolved" if r.conflict else "automatic",
            }
        )
    return out


def assert_same_regions(conn: Conn, version: str, geoid: int) -> list[dict[str, Any]]:
    mine, theirs = sql_regions(conn, version, geoid), python_regions(conn, version, geoid)
    assert mine == theirs
    return mine


def test_three_regions_found_by_sql_as_merge3_finds_them(conn: Conn) -> None:
    geoid = make_fault(conn)
    move(conn, "e1", geoid, NORTH, (0.5, 0.0, 1.25))
    move(conn, "e1", geoid, MIDDLE, (0.0, 0.0, 5.0))
    move(conn, "DEFAULT", geoid, SOUTH, (-1.0, 0.0, -2.0))
    move(conn, "DEFAULT", geoid, MIDDLE, (0.0, 0.0, -7.0))
    conn.commit()
    regions = assert_same_regions(conn, "e1", geoid)
    assert sorted(r["changed_by"] for r in regions) == ["both", "child", "parent"]
    assert [r["conflict"] for r in regions].count(True) == 1
