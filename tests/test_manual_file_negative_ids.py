"""A manual solution read from an exported file, for a mesh whose stored vertex ids are negative.

A psql user may store any bigint as a vertex id, negative ones included; the
export writes them in the vertex property ``vrtxid``. Reading the edited file
back, a negative ``vrtxid`` that is a stored id is that vertex (a negative
that is no stored id, or NaN, marks a vertex added in the tool): else the
region's vertices would come back under fresh ids and every cell on them as
a new cell — ids that change for unchanged rows, without a word.

Negative vertex ids cannot be stored in chunks (docs/storage.md, "What differs from rows"): these tests run
on rows (``@pytest.mark.storage("rows")``); on chunks, the psql user's UPDATE is refused by name, nothing
changed (the last test).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import psycopg
import pytest

import tgsis
from tests.merge_data import SIDE, curved_surface
from tgsis import formats
from tgsis.db import features as F
from tgsis.db import regions as R
from tgsis.merge3 import apply_solutions

Conn = psycopg.Connection[Any]

pytestmark = pytest.mark.storage("rows")  # negative vertex ids: rows only

PATCH = np.array([5 * SIDE + 5, 5 * SIDE + 6, 6 * SIDE + 5, 6 * SIDE + 6])  # stored as -1 - id


def negative_fault(conn: Conn, corner: int = -1) -> int:
    """The curved fault, its vertex ids rewritten by a psql user as -1 - id (DEFAULT), version e1 based on it.

    Vertex 0 (-1) becomes ``corner``.
    """
    F.create_feature_class(conn, "faults", "SURFACE")
    tgsis.enable_feature_versioning(conn)
    geoid = F.insert_feature(conn, "faults", curved_surface(), drop_extra_properties=True)
    conn.commit()
    conn.execute("UPDATE tgsis.trgl SET vrtxid1 = -1 - vrtxid1, vrtxid2 = -1 - vrtxid2, vrtxid3 = -1 - vrtxid3")
    conn.execute("UPDATE tgsis.vrtx SET vrtxid = -1 - vrtxid WHERE geoid = %s", (geoid,))
    if corner != -1:
        for k in (1, 2, 3):
            conn.execute(f"UPDATE tgsis.trgl SET vrtxid{k} = %s WHERE vrtxid{k} = -1", (corner,))
        conn.execute("UPDATE tgsis.vrtx SET vrtxid = %s WHERE geoid = %s AND vrtxid = -1", (corner, geoid))
    conn.commit()
    tgsis.create_version(conn, "e1")
    conn.commit()
    return geoid


def move_patch(conn: Conn, version: str, geoid: int, dz: float) -> None:
    with tgsis.in_version(conn, version):
        conn.execute(
            "UPDATE tgsis.vrtx SET z = z + %s WHERE geoid = %s AND vrtxid = ANY(%s)",
            (dz, geoid, (-1 - PATCH).tolist()),
        )
    conn.commit()


def exported_conflict(conn: Conn, tmp_path: Path) -> tuple[int, Any, Any, Any]:
    """The negative fault's patch moved on both sides (one conflicting region), the child's state exported as VTU
    and read back: (geoid, the region, the file's mesh, its vrtxid as float64)."""
    geoid = negative_fault(conn)
    move_patch(conn, "e1", geoid, 5.0)
    move_patch(conn, "DEFAULT", geoid, -7.0)
    [conflict] = tgsis.find_conflicts(conn, "e1")
    conn.commit()
    [region] = [r for r in conflict.regions if r.conflict]
    tgsis.export_conflict(conn, "e1", geoid, tmp_path, format="vtu", picture=False)
    [child_file] = tmp_path.glob(f"{geoid}_*_child.vtu")
    mesh = formats.read_one(child_file)
    ids = np.asarray(mesh.vertex_properties["vrtxid"], dtype=np.float64)
    return geoid, region, mesh, ids


def merged_state(conn: Conn, geoid: int) -> tuple[Any, Any]:
    """The object's merge and its state with the recorded solutions applied (what the merge writes)."""
    merge = tgsis.object_merge(conn, "e1", geoid)
    with conn.transaction():
        solutions: dict[int, Any] = R.region_solutions(conn, "e1", "feature", str(geoid), merge)
    return merge, apply_solutions(merge, solutions).state


def test_an_edited_export_keeps_the_negative_stored_ids(conn: Conn, tmp_path: Path) -> None:
    geoid, region, mesh, ids = exported_conflict(conn, tmp_path)
    assert int(region.vertex_ids.max()) < 0  # the ids are the stored negative ones
    assert ids.max() < 0
    vertices = mesh.vertices.copy()
    vertices[np.isin(ids, -1 - PATCH), 2] += 0.5  # the geologist's own choice
    edited = tgsis.Surface(vertices, mesh.cells, vertex_properties=mesh.vertex_properties, name=mesh.name)
    tgsis.resolve_region(conn, "e1", geoid, region.region, "manual", edited)
    conn.commit()
    merge, state = merged_state(conn, geoid)
    # the same ids as every state: no vertex renumbered, no cell re-created
    assert np.array_equal(state.vertex_ids, merge.child.vertex_ids)
    assert np.array_equal(state.cell_ids, merge.child.cell_ids)
    at = np.searchsorted(state.vertex_ids, np.sort(-1 - PATCH))
    child_at = np.searchsorted(merge.child.vertex_ids, np.sort(-1 - PATCH))
    assert np.all(state.vertices[at, 2] == merge.child.vertices[child_at, 2] + 0.5)


def test_a_vertex_added_in_the_tool_still_gets_a_fresh_id(conn: Conn, tmp_path: Path) -> None:
    """NaN (and a negative that is no stored id) still marks a new vertex."""
    geoid, region, mesh, ids = exported_conflict(conn, tmp_path)
    inside = set((-1 - PATCH).tolist())
    row = next(i for i, cell in enumerate(mesh.cells.tolist()) if {int(ids[v]) for v in cell} <= inside)
    a, b, c = mesh.cells[row].tolist()
    n = mesh.n_vertices
    vertices = np.vstack([mesh.vertices, mesh.vertices[[a, b, c]].mean(axis=0)])
    cells = np.vstack([np.delete(mesh.cells, row, axis=0), [[a, b, n], [b, c, n], [c, a, n]]])
    props = {"vrtxid": np.append(ids, -99999.0)}  # a tool's no-data value, no stored id
    edited = tgsis.Surface(vertices, cells, vertex_properties=props, name=mesh.name)
    tgsis.resolve_region(conn, "e1", geoid, region.region, "manual", edited)
    conn.commit()
    merge, state = merged_state(conn, geoid)
    assert state.n_vertices == merge.child.n_vertices + 1
    top = max(int(s.vertex_ids.max()) for s in (merge.base, merge.parent, merge.child))
    assert int(state.vertex_ids.max()) == top + 1
    assert len(set(state.cell_ids.tolist()) & set(merge.child.cell_ids.tolist())) == merge.child.n_cells - 1


def test_integer_ids_past_float64_precision_are_read_as_they_are(conn: Conn, tmp_path: Path) -> None:
    """An int64 ``vrtxid`` is never rounded through float64 (2**53 + 1 would read as 2**53, another vertex)."""
    big = 2**53
    geoid = negative_fault(conn, corner=big + 1)
    move_patch(conn, "e1", geoid, 5.0)
    move_patch(conn, "DEFAULT", geoid, -7.0)
    [conflict] = tgsis.find_conflicts(conn, "e1")
    conn.commit()
    [region] = [r for r in conflict.regions if r.conflict]
    merge = tgsis.object_merge(conn, "e1", geoid)
    mesh = merge.child.to_mesh()
    ids = merge.child.vertex_ids.copy()
    assert big + 1 in ids.tolist()
    mesh.vertex_properties["vrtxid"] = ids  # int64, as an in-memory edit keeps it
    mesh.vertices[np.isin(ids, -1 - PATCH), 2] += 0.5
    tgsis.resolve_region(conn, "e1", geoid, region.region, "manual", mesh)
    conn.commit()
    merge, state = merged_state(conn, geoid)
    assert np.array_equal(state.vertex_ids, merge.child.vertex_ids)


@pytest.mark.storage("chunks")
def test_on_chunks_the_psql_users_update_to_negative_ids_is_refused_by_name(conn: Conn) -> None:
    """What negative_fault does, on chunks: each UPDATE refused by name (TG100), the stored rows as they were."""
    F.create_feature_class(conn, "faults", "SURFACE")
    tgsis.enable_feature_versioning(conn)
    geoid = F.insert_feature(conn, "faults", curved_surface(), drop_extra_properties=True)
    conn.commit()
    read = {
        "vrtx": "SELECT vrtxid, float8send(x), float8send(y), float8send(z) FROM tgsis.vrtx WHERE geoid = %s ORDER BY 1",
        "trgl": "SELECT trglid, vrtxid1, vrtxid2, vrtxid3 FROM tgsis.trgl WHERE geoid = %s ORDER BY 1",
        "chunk versions": "SELECT count(*), max(revision) FROM tgsis.vrtx_chunk WHERE geoid = %s",
    }
    before = {name: conn.execute(q, (geoid,)).fetchall() for name, q in read.items()}
    for update in (
        "UPDATE tgsis.vrtx SET vrtxid = -1 - vrtxid WHERE geoid = %s",
        "UPDATE tgsis.trgl SET vrtxid1 = -1 - vrtxid1, vrtxid2 = -1 - vrtxid2, vrtxid3 = -1 - vrtxid3 WHERE geoid = %s",
        "UPDATE tgsis.vrtx SET vrtxid = -5 WHERE geoid = %s AND vrtxid = 0",
    ):
        with pytest.raises(psycopg.Error) as info:
            conn.execute(update, (geoid,))
        assert info.value.sqlstate == "TG100", (update, info.value)
        assert "negative" in str(info.value.diag.message_primary), (update, info.value.diag.message_primary)
        conn.rollback()
        assert {name: conn.execute(q, (geoid,)).fetchall() for name, q in read.items()} == before
