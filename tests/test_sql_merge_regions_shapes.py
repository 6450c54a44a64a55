"""The merge by region's detection on shapes the fault tests do not reach (issue 39): point sets, polylines,
tetrahedra; many small scattered regions, long chains, one region touching many, vertices left without cells,
new dangling vertices; the one-ring read through the vertex BRIN (sequential scans off).

Three readers must agree: SQL ``tgsis.find_conflicts`` (tgsis.mesh_merge_work: spans, union-find), the Python
read of the change (``tgsis.db.regions.find_conflicts`` through ``read_merge_change``) and merge3 of the whole
states (``tgsis.object_merge``).
"""

from __future__ import annotations

import itertools
from typing import Any

import psycopg
import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

import tgsis
from tests.storage_data import in_chunks
from tests.test_sql_merge_regions import psql, python_regions, sql_regions
from tgsis.db import features as F
from tgsis.db import regions

Conn = psycopg.Connection[Any]

N = 40  # vertices of tests.test_object_merge._other_kind's meshes
_pairs = itertools.count()
_CELLS = {
    "MULTIPOINT": ("point", "pointid", 1),
    "MULTILINESTRING": ("segment", "segid", 2),
    "MULTITETRA": ("tetra", "tetraid", 4),
}

# (kind, first, width, step): vertices first, first + step, ... (width of them) moved; or a cell / vertex removed
_edit = st.tuples(
    st.sampled_from(["move", "move", "move", "drop_cell", "drop_vertex", "dangling"]),
    st.integers(0, N - 1),
    st.integers(1, 12),
    st.sampled_from([1, 2, 3, 5]),
)


def _apply(
    conn: Conn, version: str, geoid: int, geotype: str, edits: list[tuple[str, int, int, int]], dz: float
) -> None:
    table, cellid, k = _CELLS[geotype]
    corners = ", ".join(f"vrtxid{i + 1}" for i in range(k))
    statements: list[tuple[str, tuple[Any, ...]]] = []
    added: set[int] = set()
    for kind, first, width, step in edits:
        if kind == "move":
            ids = [i for i in range(first, first + width * step, step) if i < N]
            statements.append(
                (
                    "UPDATE tgsis.vrtx SET z = z + %s, x = x + %s WHERE geoid = %s AND vrtxid = ANY (%s)",
                    (dz, dz / 8, geoid, ids),
                )
            )
        elif kind == "drop_cell":
            statements.append((f"DELETE FROM tgsis.{table} WHERE geoid = %s AND {cellid} = %s", (geoid, first)))
        elif kind == "drop_vertex":  # the vertex and its cells: its neighbours may be left without any cell
            statements.append((f"DELETE FROM tgsis.{table} WHERE geoid = %s AND %s IN ({corners})", (geoid, first)))
            statements.append(("DELETE FROM tgsis.vrtx WHERE geoid = %s AND vrtxid = %s", (geoid, first)))
        else:  # a new vertex on no cell, with an id far from the others (some at the ends of bigint)
            far = 10**12 * (first + 1) if first % 3 else 2**63 - 1 - first
            # the parent's negative (down to -2**63); chunks refuse negative ids by design (docs/storage.md,
            # "What differs from rows"): there, other far ids near the child's
            new_id = far if dz > 0 else far - 5000 if in_chunks(conn) else -far - 1
            if new_id in added:  # the same vertex twice: once (the versioned views refuse ON CONFLICT on a key there)
                continue
            added.add(new_id)
            statements.append(
                (
                    "INSERT INTO tgsis.vrtx (geoid, vrtxid, x, y, z) VALUES (%s, %s, %s, 0.0, %s)",
                    (geoid, new_id, 100.0 * first, dz),
                )
            )
    psql(conn, version, *statements)


@pytest.fixture(params=["MULTIPOINT", "MULTILINESTRING", "MULTITETRA"])
def body(request: pytest.FixtureRequest, conn: Conn) -> tuple[int, str]:
    from tests.test_object_merge import _other_kind

    geotype = str(request.param)
    F.create_feature_class(conn, "bodies", geotype)
    tgsis.enable_feature_versioning(conn)
    geoid = F.insert_feature(conn, "bodies", _other_kind(geotype))
    conn.commit()
    return geoid, geotype


@settings(
    max_examples=10, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow]
)
@given(child=st.lists(_edit, min_size=1, max_size=5), parent=st.lists(_edit, min_size=1, max_size=5))
# the parent's new vertex -2**63 (merge3's id tables overflowed; the regions' record refused 19-digit ids)
@example(child=[("drop_cell", 0, 1, 1)], parent=[("dangling", 0, 1, 1)])
@example(child=[("move", 0, 1, 1)], parent=[("dangling", 0, 1, 1)])
# the same new vertex twice on one side (was: INSERT ... ON CONFLICT DO NOTHING, which the versioned views refuse)
@example(child=[("move", 0, 1, 1)], parent=[("dangling", 0, 1, 1), ("dangling", 0, 1, 1)])
# new vertices 2**63 - 1 and -2**63: the spans' gap between them overflowed bigint
@example(child=[("dangling", 0, 1, 1), ("move", 3, 2, 1)], parent=[("dangling", 0, 1, 1), ("move", 30, 3, 2)])
def test_random_edits_of_points_lines_and_solids_give_merge3s_regions_in_sql_and_in_the_python_read(
    conn: Conn, body: tuple[int, str], child: list[tuple[str, int, int, int]], parent: list[tuple[str, int, int, int]]
) -> None:
    geoid, geotype = body
    n = next(_pairs)
    parent_version, child_version = f"sp{n}", f"sc{n}"
    tgsis.create_version(conn, parent_version)
    conn.commit()
    tgsis.create_version(conn, child_version, parent=parent_version)
    conn.commit()
    _apply(conn, child_version, geoid, geotype, child, 1.5)
    _apply(conn, parent_version, geoid, geotype, parent, -2.25)
    conflicts = conn.execute("SELECT objectkey FROM tgsis.find_conflicts(%s)", (child_version,)).fetchall()
    conn.rollback()
    if not conflicts:
        return
    conn.execute("SET enable_seqscan = off; SET jit = off")  # the one-ring through the vertex BRIN, as on a large table
    mine = sql_regions(conn, child_version, geoid)
    theirs = python_regions(conn, child_version, geoid)
    assert mine == theirs
    conn.execute("SET enable_seqscan = off; SET jit = off")
    [conflict] = regions.find_conflicts(conn, child_version)  # the Python read of the change and its ring
    conn.rollback()
    assert [sorted(int(i) for i in r.vertex_ids) for r in conflict.regions] == [r["vertex_ids"] for r in theirs]
    assert [sorted(int(i) for i in r.cell_ids) for r in conflict.regions] == [r["cell_ids"] for r in theirs]


@pytest.mark.storage("chunks")
def test_a_vertex_at_the_top_of_bigint_in_chunks_is_read_by_the_merge(conn: Conn) -> None:
    """A chunk whose last slot is id 2**63 - 1 (its last id read as chunk * 1024 + length - 1 overflowed bigint
    before the subtraction): the Python read of the change and the SQL regions agree, and the merge writes it."""
    from tests.test_object_merge import _other_kind

    F.create_feature_class(conn, "bodies", "MULTIPOINT")
    tgsis.enable_feature_versioning(conn)
    geoid = F.insert_feature(conn, "bodies", _other_kind("MULTIPOINT"))
    tgsis.create_version(conn, "sp")
    conn.commit()
    tgsis.create_version(conn, "sc", parent="sp")
    conn.commit()
    _apply(conn, "sc", geoid, "MULTIPOINT", [("dangling", 0, 1, 1), ("move", 3, 2, 1)], 1.5)  # adds 2**63 - 1
    _apply(conn, "sp", geoid, "MULTIPOINT", [("move", 30, 3, 2)], -2.25)
    mine = sql_regions(conn, "sc", geoid)
    assert mine == python_regions(conn, "sc", geoid)
    [conflict] = regions.find_conflicts(conn, "sc")
    conn.rollback()
    assert [sorted(int(i) for i in r.vertex_ids) for r in conflict.regions] == [r["vertex_ids"] for r in mine]
    assert any(2**63 - 1 in r["vertex_ids"] for r in mine)
    tgsis.merge_version(conn, "sc")
    with tgsis.in_version(conn, "sp"):
        top = conn.execute("SELECT max(vrtxid) FROM tgsis.vrtx WHERE geoid = %s", (geoid,)).fetchone()
    assert top == (2**63 - 1,)
