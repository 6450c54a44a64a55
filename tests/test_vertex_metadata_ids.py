"""GOCAD vertex flags and property control nodes name the same vertices after every edit (stored by vertex id).

A check-in by difference gives vertices inserted in the middle of a file ids
above every id the object had, so the fetched mesh has them at the end; a
check-in that deletes vertices shifts the places of the others. Flags and
control nodes kept as places of the file named other vertices afterwards,
without any error (found in review, 2026-12-06). They are stored by id, as
atoms are (``tgsis._vertex_metadata``).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import psycopg
import pytest

import tgsis
from tests.merge_data import make_fault, move
from tgsis import formats
from tgsis._vertex_metadata import places_of_ids, renumbered
from tgsis.db import features as F

Conn = psycopg.Connection[Any]

FLAGGED = 5  # the vertex that carries the flag (CNXYZ)
NODE = 7  # the vertex that is a control node of porosity


def _fetched(conn: Conn, geoid: int) -> tgsis.Surface:
    mesh = F.fetch_feature(conn, "faults", geoid).mesh
    assert isinstance(mesh, tgsis.Surface)
    return mesh


def _flagged_fault(conn: Conn) -> tuple[int, tgsis.Surface]:
    geoid = make_fault(
        conn,
        {
            "gocad_vertex_flags": {"CNXYZ": [[FLAGGED, FLAGGED + 1]]},
            "gocad_property_control_nodes": {"porosity": [NODE]},
        },
    )
    return geoid, _fetched(conn, geoid)


def _with_vertex_inserted(mesh: tgsis.Surface, at: int) -> tgsis.Surface:
    """The mesh with a new vertex at place ``at`` (used by one new triangle); flags and nodes follow their vertices."""
    vertices = np.insert(mesh.vertices, at, mesh.vertices[0] + [0.1, 0.1, 0.0], axis=0)
    cells = mesh.cells.copy()
    cells[cells >= at] += 1
    cells = np.vstack([cells, [[at + 1, at + 2, at]]])
    shift = np.arange(mesh.n_vertices) + (np.arange(mesh.n_vertices) >= at)
    return tgsis.Surface(
        vertices,
        cells,
        vertex_properties={k: np.insert(v, at, v[0], axis=0) for k, v in mesh.vertex_properties.items()},
        cell_properties={k: np.concatenate([v, v[:1]]) for k, v in mesh.cell_properties.items()},
        metadata=renumbered(mesh.metadata, mesh.n_vertices, shift.astype(np.int64), None, "test"),
    )


def _flagged_vertices(mesh: Any) -> tuple[list[list[float]], list[list[float]]]:
    flags = mesh.metadata["gocad_vertex_flags"]["CNXYZ"]
    nodes = mesh.metadata["gocad_property_control_nodes"]["porosity"]
    flagged = [mesh.vertices[i].tolist() for a, b in flags for i in range(a, b)]
    return flagged, [mesh.vertices[i].tolist() for i in nodes]


def test_a_vertex_inserted_mid_file_by_save_feature_keeps_flags_on_their_vertices(conn: Conn, tmp_path: Path) -> None:
    geoid, stored = _flagged_fault(conn)
    expected = ([stored.vertices[FLAGGED].tolist()], [stored.vertices[NODE].tolist()])
    assert _flagged_vertices(stored) == expected
    edited = _with_vertex_inserted(stored, 2)
    assert _flagged_vertices(edited) == expected  # the edit itself is right
    tgsis.save_feature(conn, "faults", geoid, edited)
    conn.commit()
    back = _fetched(conn, geoid)
    assert not np.array_equal(back.vertices, edited.vertices)  # the new vertex comes back last: places moved
    assert _flagged_vertices(back) == expected
    # and in the GOCAD file a geomodeller gets
    formats.write(back, tmp_path / "fault.ts", drop_cell_properties=True)
    (again,) = formats.read(tmp_path / "fault.ts")  # a GOCAD file holds a list of objects
    assert _flagged_vertices(again) == expected
    # the other version still has the stored state of before: the same vertices flagged
    with tgsis.in_version(conn, "e1"):
        assert _flagged_vertices(_fetched(conn, geoid)) == expected
        conn.rollback()


def test_checkout_and_checkin_keep_flags_on_their_vertices(conn: Conn) -> None:
    geoid, stored = _flagged_fault(conn)
    expected = ([stored.vertices[FLAGGED].tolist()], [stored.vertices[NODE].tolist()])
    tgsis.save_feature(conn, "faults", geoid, _with_vertex_inserted(stored, 1))
    conn.commit()
    out = tgsis.checkout(conn, geoid)
    assert isinstance(out.mesh, tgsis.Surface)
    assert _flagged_vertices(out.mesh) == expected  # the check-out's places, not the stored ids
    tgsis.checkin(conn, out, _with_vertex_inserted(out.mesh, 3))
    conn.commit()
    assert _flagged_vertices(_fetched(conn, geoid)) == expected


def test_a_mesh_without_metadata_keeps_the_stored_flags_on_their_vertices(conn: Conn) -> None:
    """An edit built from arrays (no metadata) deletes vertices before the flagged ones: the stored flags stay right."""
    geoid, stored = _flagged_fault(conn)
    expected = ([stored.vertices[FLAGGED].tolist()], [stored.vertices[NODE].tolist()])
    keep = np.ones(stored.n_vertices, dtype=bool)
    keep[[0, 1]] = False
    inside = keep[stored.cells].all(axis=1)
    new_of_old = np.cumsum(keep) - 1
    edited = tgsis.Surface(
        stored.vertices[keep],
        new_of_old[stored.cells[inside]],
        vertex_properties={k: v[keep] for k, v in stored.vertex_properties.items()},
        cell_properties={k: v[inside] for k, v in stored.cell_properties.items()},
    )
    tgsis.save_feature(conn, "faults", geoid, edited)
    conn.commit()
    back = _fetched(conn, geoid)
    assert _flagged_vertices(back) == expected
    # a flagged vertex deleted: its flag and node go with it
    gone = np.ones(back.n_vertices, dtype=bool)
    gone[np.argmax((back.vertices == expected[0][0]).all(axis=1))] = False
    gone[np.argmax((back.vertices == expected[1][0]).all(axis=1))] = False
    inside = gone[back.cells].all(axis=1)
    renumber = np.cumsum(gone) - 1
    tgsis.save_feature(
        conn,
        "faults",
        geoid,
        tgsis.Surface(
            back.vertices[gone],
            renumber[back.cells[inside]],
            vertex_properties={k: v[gone] for k, v in back.vertex_properties.items()},
            cell_properties={k: v[inside] for k, v in back.cell_properties.items()},
        ),
    )
    conn.commit()
    after = _fetched(conn, geoid)
    assert after.metadata["gocad_vertex_flags"] == {}
    assert after.metadata["gocad_property_control_nodes"] == {"porosity": []}


def test_flags_that_name_no_vertex_are_refused_and_nothing_changes(conn: Conn) -> None:
    geoid, stored = _flagged_fault(conn)
    before = conn.execute("SELECT metadata FROM tgsis.geometry WHERE geoid = %s", (geoid,)).fetchone()
    bad = tgsis.Surface(
        stored.vertices,
        stored.cells,
        vertex_properties=stored.vertex_properties,
        cell_properties=stored.cell_properties,
        metadata={**stored.metadata, "gocad_property_control_nodes": {"porosity": [stored.n_vertices + 3]}},
    )
    bad.vertices[0, 2] += 1.0  # a real edit besides
    with pytest.raises(tgsis.InvalidGeometryError, match="gocad_property_control_nodes") as caught:
        tgsis.save_feature(conn, "faults", geoid, bad)
    assert caught.value.hint == "correct or remove that metadata entry"
    conn.rollback()
    assert conn.execute("SELECT metadata FROM tgsis.geometry WHERE geoid = %s", (geoid,)).fetchone() == before


def test_metadata_written_by_hand_in_sql_is_given_back_as_stored(conn: Conn, caplog: pytest.LogCaptureFixture) -> None:
    geoid, _ = _flagged_fault(conn)
    conn.execute(
        'UPDATE tgsis.geometry SET metadata = metadata || \'{"gocad_vertex_flags": {"CNXYZ": "all"}}\' WHERE geoid = %s',
        (geoid,),
    )
    conn.commit()
    back = _fetched(conn, geoid)
    assert back.metadata["gocad_vertex_flags"] == {"CNXYZ": "all"}
    assert "gocad_vertex_flags" in caplog.text and "given back as stored" in caplog.text


def test_renumbered_and_placed_are_inverse_for_any_ids() -> None:
    rng = np.random.default_rng(7)
    n = 500
    for _ in range(20):
        ids = np.sort(rng.choice(10**12, size=n, replace=False)).astype(np.int64)
        order = rng.permutation(n)  # the edited mesh's places, in any order of ids
        starts = np.sort(rng.choice(n, size=6, replace=False))
        ranges = [[int(a), int(min(a + rng.integers(0, 30), n))] for a in starts]  # may overlap, may be empty
        nodes = sorted(int(v) for v in rng.choice(n, size=9, replace=False))
        meta = {"gocad_vertex_flags": {"CN": ranges}, "gocad_property_control_nodes": {"p": nodes}, "other": [1]}
        stored = renumbered(meta, n, ids[order], None, "test")
        placed = places_of_ids(stored, ids)
        flagged = {int(order[i]) for a, b in ranges for i in range(a, b)}
        assert {i for a, b in placed["gocad_vertex_flags"].get("CN", []) for i in range(a, b)} == flagged
        assert placed["gocad_property_control_nodes"] == {"p": sorted(int(order[i]) for i in nodes)}
        assert placed["other"] == [1]
        # ids no vertex has any more name nothing
        keep = np.sort(rng.choice(n, size=n // 2, replace=False))
        partly = places_of_ids(stored, ids[keep])
        kept = set(keep.tolist())
        assert {int(keep[i]) for a, b in partly["gocad_vertex_flags"].get("CN", []) for i in range(a, b)} == (
            flagged & kept
        )


def test_a_conflicts_three_files_flag_the_same_vertex_in_each_state(conn: Conn, tmp_path: Path) -> None:
    """The parent deletes vertex 0: its file's places are one off against the ids; each file flags vertex id 5."""
    geoid, _ = _flagged_fault(conn)
    move(conn, "e1", geoid, [50, 51, 52], (0.0, 0.0, 5.0))
    move(conn, "DEFAULT", geoid, [52, 53], (0.0, 0.0, -4.0))
    with tgsis.in_version(conn, "DEFAULT"):
        conn.execute("DELETE FROM tgsis.trgl WHERE geoid = %s AND 0 IN (vrtxid1, vrtxid2, vrtxid3)", (geoid,))
        conn.execute("DELETE FROM tgsis.vrtx WHERE geoid = %s AND vrtxid = 0", (geoid,))
    conn.commit()
    written = tgsis.export_conflict(conn, "e1", geoid, tmp_path / "out", picture=False)
    files = [p for p in written if p.suffix == ".ts"]
    assert len(files) == 3
    for path in files:
        mesh = formats.read_one(path)
        ids = mesh.vertex_properties["vrtxid"].astype(np.int64)
        flags = mesh.metadata["gocad_vertex_flags"]["CNXYZ"]
        assert [int(ids[i]) for a, b in flags for i in range(a, b)] == [FLAGGED], path.name
        nodes = mesh.metadata["gocad_property_control_nodes"]["porosity"]
        assert [int(ids[i]) for i in nodes] == [NODE], path.name
