"""Hostile review (issue 39) of a manual mesh read from a file (tgsis.db.regions._file_ids, 934817b).

A file vertex's ``vrtxid`` is a stored id, or marks a new vertex (NaN, a negative that is no stored id),
which gets an id above every state's. A whole non-negative ``vrtxid`` that is no stored id is taken as
given. These cases must never give two vertices one id, nor read an id as another.

Negative vertex ids are stored on rows only (tests/test_manual_file_negative_ids.py): these tests run on rows.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import psycopg
import pytest

import tgsis
from tests.test_manual_file_negative_ids import PATCH, exported_conflict, merged_state, move_patch, negative_fault

Conn = psycopg.Connection[Any]

pytestmark = pytest.mark.storage("rows")  # negative vertex ids: rows only


def _edited_with_two_new_vertices(conn: Conn, tmp_path: Path, marks: tuple[float, float]) -> tuple[int, int, Any]:
    geoid, region, mesh, ids = exported_conflict(conn, tmp_path)
    inside = set((-1 - PATCH).tolist())
    rows = [i for i, cell in enumerate(mesh.cells.tolist()) if {int(ids[v]) for v in cell} <= inside][:2]
    vertices, cells, n = mesh.vertices, mesh.cells, mesh.n_vertices
    new_cells = []
    for j, row in enumerate(rows):
        a, b, c = mesh.cells[row].tolist()
        vertices = np.vstack([vertices, mesh.vertices[[a, b, c]].mean(axis=0)])
        new_cells += [[a, b, n + j], [b, c, n + j], [c, a, n + j]]
    cells = np.vstack([np.delete(cells, rows, axis=0), new_cells])
    props = {"vrtxid": np.append(ids, marks)}
    edited = tgsis.Surface(vertices, cells, vertex_properties=props, name=mesh.name)
    return geoid, region.region, edited


@pytest.mark.parametrize("marks", [(0.0, np.nan), (np.nan, 0.0)])
def test_a_new_vertex_never_gets_the_id_another_file_vertex_gives(
    conn: Conn, tmp_path: Path, marks: tuple[float, float]
) -> None:
    """Stored ids -1 .. -144: a new vertex (NaN) gets 0, above every state's; another new vertex given vrtxid 0
    (a whole non-negative value, taken as an id) must not share it."""
    geoid, index, edited = _edited_with_two_new_vertices(conn, tmp_path, marks)
    # was refused: "vertex ids 0 are given twice" (the file gives 0 once; the fresh id was 0 too)
    tgsis.resolve_region(conn, "e1", geoid, index, "manual", edited)
    conn.commit()
    merge, state = merged_state(conn, geoid)
    assert len(np.unique(state.vertex_ids)) == state.n_vertices
    assert state.n_vertices == merge.child.n_vertices + 2


@pytest.mark.parametrize("solution", ["child", "average"])
def test_an_atom_referring_to_a_negative_vertex_id_survives_the_merge(conn: Conn, solution: str) -> None:
    """Negative stored ids (a psql user's): a GOCAD atom in the patch both sides move refers to vertex -1. The merge
    rewrites the atom's vertex row: its atom must come along (refid -1 is a vertex, not 'no atom')."""
    geoid = negative_fault(conn)
    atom_v = int(-1 - PATCH[0])
    conn.execute("INSERT INTO tgsis.atom (geoid, vrtxid, refid, patom) VALUES (%s, %s, -1, true)", (geoid, atom_v))
    conn.commit()
    tgsis.create_version(conn, "e2")
    conn.commit()
    with tgsis.in_version(conn, "e2"):
        conn.execute(
            "UPDATE tgsis.vrtx SET z = z + 5 WHERE geoid = %s AND vrtxid = ANY(%s)", (geoid, (-1 - PATCH).tolist())
        )
    conn.commit()
    move_patch(conn, "DEFAULT", geoid, -7.0)
    [conflict] = tgsis.find_conflicts(conn, "e2")
    conn.commit()
    [region] = [r for r in conflict.regions if r.conflict]
    tgsis.resolve_region(conn, "e2", geoid, region.region, solution)
    conn.commit()
    tgsis.merge_version(conn, "e2")
    conn.commit()
    atoms = conn.execute("SELECT vrtxid, refid FROM tgsis.atom WHERE geoid = %s", (geoid,)).fetchall()
    conn.rollback()
    assert atoms == [(atom_v, -1)]
