"""tgsis.checkin(..., on_conflict="merge"): a check-in of a feature changed since check-out merges by region (issue 39)."""

from __future__ import annotations

from typing import Any

import numpy as np
import psycopg
import pytest

import tgsis
from tests.merge_data import SIDE, curved_surface, make_fault, merge_storage_state, move, moved, stored_state
from tests.storage_data import storage_of
from tgsis.cli import main

Conn = psycopg.Connection[Any]

NORTH = np.arange(0, 2 * SIDE)
SOUTH = np.arange((SIDE - 2) * SIDE, SIDE * SIDE)


@pytest.fixture
def fault(conn: Conn, fault_clone: int) -> int:
    return fault_clone  # make_fault's, built once (tests/conftest.py)


def test_disjoint_edits_since_check_out_merge_by_region(conn: Conn, fault: int) -> None:
    co = tgsis.checkout(conn, fault)
    conn.commit()
    move(conn, "DEFAULT", fault, SOUTH, (0.0, 1.25, -3.5))  # another writer, after the check-out
    conn.commit()
    mine = co.mesh.copy()
    for axis, shift in enumerate((0.5, 0.0, 2.75)):
        mine.vertices[NORTH, axis] = mine.vertices[NORTH, axis] + shift
    with pytest.raises(tgsis.CheckoutConflictError):  # the default still refuses
        tgsis.checkin(conn, co, mine)
    conn.rollback()
    result = tgsis.checkin(conn, co, mine, on_conflict="merge")
    conn.commit()
    assert result.conflict and result.version == "DEFAULT"
    expected = curved_surface().vertices.copy()
    moved(expected, SOUTH, (0.0, 1.25, -3.5))
    moved(expected, NORTH, (0.5, 0.0, 2.75))
    ids, xyz, cells, _ = stored_state(conn, "DEFAULT", fault)
    np.testing.assert_array_equal(ids, np.arange(SIDE * SIDE))  # ids kept
    assert xyz.tobytes() == expected.tobytes()
    assert cells == {(i, *map(int, c)) for i, c in enumerate(curved_surface().cells)}
    assert result.save.rows_written > 0


def test_a_new_vertex_and_cells_of_the_edit_get_new_ids(conn: Conn, fault: int) -> None:
    co = tgsis.checkout(conn, fault)
    conn.commit()
    move(conn, "DEFAULT", fault, SOUTH, (0.0, 0.0, -1.0))
    conn.commit()
    base = co.mesh
    # split the first triangle (cell 0: a, b, d) at its centroid into three
    a, b, d = (int(v) for v in base.cells[0])
    centroid = base.vertices[[a, b, d]].mean(axis=0)
    vertices = np.vstack([base.vertices, centroid])
    c = len(base.vertices)
    cells = np.vstack([base.cells[1:], [[a, b, c], [b, d, c], [d, a, c]]])
    porosity = np.append(base.vertex_properties["porosity"], 0.2)
    facies = np.append(base.cell_properties["facies"][1:], [1, 1, 1]).astype(np.int32)
    mine = tgsis.Surface(vertices, cells, vertex_properties={"porosity": porosity}, cell_properties={"facies": facies})
    result = tgsis.checkin(conn, co, mine, on_conflict="merge")
    conn.commit()
    assert result.conflict
    ids, xyz, stored_cells, porosities = stored_state(conn, "DEFAULT", fault)
    assert len(ids) == SIDE * SIDE + 1 and ids[-1] >= SIDE * SIDE
    assert xyz[-1].tobytes() == centroid.tobytes()
    assert porosities[int(ids[-1])] == 0.2
    expected = curved_surface().vertices.copy()
    moved(expected, SOUTH, (0.0, 0.0, -1.0))
    assert xyz[:-1].tobytes() == expected.tobytes()
    new = int(ids[-1])
    triangles = {tuple(sorted(c[1:])) for c in stored_cells}
    assert {tuple(sorted(t)) for t in ((a, b, new), (b, d, new), (d, a, new))} <= triangles
    assert tuple(sorted((a, b, d))) not in triangles
    assert len(stored_cells) == len(curved_surface().cells) + 2


def test_overlapping_edits_refuse_naming_the_regions_and_nothing_is_written(conn: Conn, fault: int) -> None:
    co = tgsis.checkout(conn, fault)
    conn.commit()
    move(conn, "DEFAULT", fault, [52, 53], (0.0, 0.0, -4.0))
    conn.commit()
    mine = co.mesh.copy()
    mine.vertices[[50, 51, 52], 2] += 5.0
    before = merge_storage_state(conn)
    with pytest.raises(tgsis.CheckoutConflictError, match=r"region 0: .*vertices") as caught:
        tgsis.checkin(conn, co, mine, on_conflict="merge")
    conn.rollback()
    assert "52" in str(caught.value) and "box" in str(caught.value)
    assert merge_storage_state(conn) == before


def test_unchanged_since_check_out_is_a_plain_check_in(conn: Conn, fault: int) -> None:
    co = tgsis.checkout(conn, fault)
    conn.commit()
    mine = co.mesh.copy()
    mine.vertices[NORTH, 2] += 1.0
    result = tgsis.checkin(conn, co, mine, on_conflict="merge")
    conn.commit()
    assert not result.conflict
    expected = curved_surface().vertices.copy()
    moved(expected, NORTH, (0.0, 0.0, 1.0))
    assert stored_state(conn, "DEFAULT", fault)[1].tobytes() == expected.tobytes()


def test_bad_on_conflict_names_merge(conn: Conn, fault: int) -> None:
    co = tgsis.checkout(conn, fault)
    conn.commit()
    with pytest.raises(tgsis.InvalidInputError, match="'merge'"):
        tgsis.checkin(conn, co, co.mesh, on_conflict="nope")  # type: ignore[arg-type]


def test_the_command_line_checks_in_with_on_conflict_merge(
    conn: Conn, fault: int, db_dsn: str, tmp_path: Any, monkeypatch: Any, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.setenv("TGSIS_HOME", str(tmp_path))
    monkeypatch.delenv("TGSIS_VERSION", raising=False)
    path = tmp_path / "fault.vtu"
    assert main(["--dsn", db_dsn, "checkout", str(fault), str(path)]) == 0
    move(conn, "DEFAULT", fault, SOUTH, (0.0, 0.0, -2.0))
    conn.commit()
    mesh = tgsis.formats.read_one(path)
    mesh.vertices[NORTH, 2] += 3.0
    tgsis.formats.write(mesh, path)
    capsys.readouterr()
    assert main(["--dsn", db_dsn, "checkin", str(path), "--on-conflict", "merge"]) == 0
    assert "merged" in capsys.readouterr().out
    expected = curved_surface().vertices.copy()
    moved(expected, SOUTH, (0.0, 0.0, -2.0))
    moved(expected, NORTH, (0.0, 0.0, 3.0))
    np.testing.assert_allclose(stored_state(conn, "DEFAULT", fault)[1], expected, rtol=0, atol=1e-9)


def test_the_merge_holds_the_features_write_lock_until_it_commits(conn: Conn, fault: int, db_dsn: str) -> None:
    from tests.sessions import Background, wait_until_blocked

    co = tgsis.checkout(conn, fault)
    conn.commit()
    move(conn, "DEFAULT", fault, SOUTH, (0.0, 0.0, -1.0))
    conn.commit()
    mine = co.mesh.copy()
    mine.vertices[NORTH, 2] += 2.0
    with conn.transaction():
        assert tgsis.checkin(conn, co, mine, on_conflict="merge").merged
        other = Background(db_dsn, "saver", lambda c: tgsis.save_feature(c, "faults", fault, curved_surface()))
        with psycopg.connect(db_dsn) as observer:  # a writer of the feature waits for the merge
            wait_until_blocked(observer, other.pid, conn.info.backend_pid)
    other.finish()  # then saves over the merged state
    assert stored_state(conn, "DEFAULT", fault)[1].tobytes() == curved_surface().vertices.tobytes()


def test_vertices_within_the_tolerance_are_unchanged_in_the_merge_as_in_a_plain_check_in(
    conn: Conn, fault: int
) -> None:
    """A file that rounds every coordinate (checked in with a tolerance) moved nothing but what it moved."""
    co = tgsis.checkout(conn, fault)
    conn.commit()
    move(conn, "DEFAULT", fault, SOUTH, (0.0, 1.25, -3.5))  # another writer, after the check-out
    conn.commit()
    mine = co.mesh.copy()
    mine.vertices[:] = np.round(mine.vertices, 3)  # the tool wrote millimetres: every vertex within 0.001
    mine.vertices[NORTH, 2] += 2.75
    result = tgsis.checkin(conn, co, mine, tolerance=0.001, on_conflict="merge")
    conn.commit()
    assert result.merged
    expected = curved_surface().vertices.copy()
    moved(expected, SOUTH, (0.0, 1.25, -3.5))  # theirs, bit for bit: not overwritten by a rounding
    expected[NORTH] = mine.vertices[NORTH]  # mine, as edited
    ids, xyz, _, _ = stored_state(conn, "DEFAULT", fault)
    np.testing.assert_array_equal(ids, np.arange(SIDE * SIDE))
    assert xyz.tobytes() == expected.tobytes()


def test_a_rename_made_since_check_out_is_kept_by_the_merge(conn: Conn, fault: int) -> None:
    co = tgsis.checkout(conn, fault)
    conn.commit()
    move(conn, "DEFAULT", fault, SOUTH, (0.0, 0.0, -1.0))
    conn.execute("UPDATE tgsis.geometry SET geoname = 'San Andreas (renamed)' WHERE geoid = %s", (fault,))
    conn.commit()
    mine = co.mesh.copy()  # the checked-out mesh, name and all
    mine.vertices[NORTH, 2] += 1.0
    assert tgsis.checkin(conn, co, mine, on_conflict="merge").merged
    conn.commit()
    name = conn.execute("SELECT geoname FROM tgsis.geometry WHERE geoid = %s", (fault,)).fetchone()
    assert name == ("San Andreas (renamed)",)


def test_both_renamed_differently_refuses_and_writes_nothing(conn: Conn, fault: int) -> None:
    co = tgsis.checkout(conn, fault)
    conn.commit()
    conn.execute("UPDATE tgsis.geometry SET geoname = 'theirs' WHERE geoid = %s", (fault,))
    conn.commit()
    mine = co.mesh.copy()
    mine.vertices[NORTH, 2] += 1.0
    before = merge_storage_state(conn)
    with pytest.raises(tgsis.CheckoutConflictError, match="name"):
        tgsis.checkin(conn, co, mine, name="mine", on_conflict="merge")
    conn.rollback()
    assert merge_storage_state(conn) == before


def _class_with_a_feature_property(conn: Conn) -> int:
    tgsis.create_feature_class(conn, "wells", "SURFACE", feature_properties=[("status", "text")])
    tgsis.enable_feature_versioning(conn)
    geoid = tgsis.insert_feature(conn, "wells", curved_surface(), {"status": "draft"}, drop_extra_properties=True)
    conn.commit()
    return geoid


def test_a_feature_property_both_changed_refuses_and_writes_nothing(conn: Conn) -> None:
    geoid = _class_with_a_feature_property(conn)
    co = tgsis.checkout(conn, geoid)
    conn.commit()
    conn.execute("UPDATE public.wells SET status = 'approved' WHERE _geoid = %s", (geoid,))
    conn.commit()
    mine = co.mesh.copy()
    mine.vertices[NORTH, 2] += 1.0
    before = merge_storage_state(conn)
    with pytest.raises(tgsis.CheckoutConflictError, match="status"):
        tgsis.checkin(conn, co, mine, {"status": "rejected"}, on_conflict="merge")
    conn.rollback()
    assert merge_storage_state(conn) == before
    assert conn.execute("SELECT status FROM public.wells WHERE _geoid = %s", (geoid,)).fetchone() == ("approved",)


def test_a_feature_property_only_the_edit_changed_is_written_by_the_merge(conn: Conn) -> None:
    geoid = _class_with_a_feature_property(conn)
    co = tgsis.checkout(conn, geoid)
    conn.commit()
    move(conn, "DEFAULT", geoid, SOUTH, (0.0, 0.0, -1.0))
    conn.commit()
    mine = co.mesh.copy()
    mine.vertices[NORTH, 2] += 1.0
    assert tgsis.checkin(conn, co, mine, {"status": "reviewed"}, on_conflict="merge").merged
    conn.commit()
    assert conn.execute("SELECT status FROM public.wells WHERE _geoid = %s", (geoid,)).fetchone() == ("reviewed",)


def test_the_parts_of_the_cells_the_edit_added_are_stored_by_the_merge(conn: Conn) -> None:
    """A GOCAD surface of two TFACEs (parts in tgsis.part): the triangles the edit adds keep the part it gave them."""
    tgsis.create_feature_class(
        conn,
        "faults",
        "SURFACE",
        cell_properties=[("porosity", "float8"), tgsis.Property("facies", "int", alignment="CELL")],
    )
    tgsis.enable_feature_versioning(conn)
    surface = curved_surface()
    half = surface.n_cells // 2
    surface.cell_properties["part"] = (np.arange(surface.n_cells) >= half).astype(np.int64)
    geoid = tgsis.insert_feature(conn, "faults", surface)
    conn.commit()
    co = tgsis.checkout(conn, geoid)
    conn.commit()
    assert np.array_equal(co.mesh.cell_properties["part"], surface.cell_properties["part"])
    move(conn, "DEFAULT", geoid, SOUTH, (0.0, 0.0, -1.0))
    conn.commit()
    base = co.mesh
    split = half  # a triangle of part 1 at the northern end, split at its centroid into three
    a, b, d = (int(v) for v in base.cells[split])
    c = base.n_vertices
    rest = np.arange(base.n_cells) != split
    mine = tgsis.Surface(
        np.vstack([base.vertices, base.vertices[[a, b, d]].mean(axis=0)]),
        np.vstack([base.cells[rest], [[a, b, c], [b, d, c], [d, a, c]]]),
        vertex_properties={"porosity": np.append(base.vertex_properties["porosity"], 0.2)},
        cell_properties={
            "facies": np.append(base.cell_properties["facies"][rest], [1, 1, 1]).astype(np.int32),
            "part": np.append(base.cell_properties["part"][rest], [1, 1, 1]),
        },
    )
    assert tgsis.checkin(conn, co, mine, on_conflict="merge").merged
    conn.commit()
    again = tgsis.checkout(conn, geoid)
    conn.commit()
    parts = again.mesh.cell_properties["part"]
    assert len(parts) == surface.n_cells + 2 and np.min(parts) >= 0  # -1: a triangle in no part
    assert np.array_equal(np.bincount(np.asarray(parts, dtype=np.int64)), [half, surface.n_cells - half + 2])


def _two_part_fault(conn: Conn) -> tuple[int, int]:
    tgsis.create_feature_class(
        conn,
        "faults",
        "SURFACE",
        cell_properties=[("porosity", "float8"), tgsis.Property("facies", "int", alignment="CELL")],
    )
    tgsis.enable_feature_versioning(conn)
    surface = curved_surface()
    half = surface.n_cells // 2
    surface.cell_properties["part"] = (np.arange(surface.n_cells) >= half).astype(np.int64)
    geoid = tgsis.insert_feature(conn, "faults", surface)
    conn.commit()
    return geoid, half


def test_an_edit_without_parts_leaves_its_new_cells_in_no_part_and_the_others_in_theirs(conn: Conn) -> None:
    """A mesh given without the cell property part (a tool that drops it) changed no part: the kept cells keep
    theirs, the cells it added are in none (as stored: no run), and the merge is written."""
    geoid, half = _two_part_fault(conn)
    co = tgsis.checkout(conn, geoid)
    conn.commit()
    move(conn, "DEFAULT", geoid, SOUTH, (0.0, 0.0, -1.0))
    conn.commit()
    base = co.mesh
    a, b, d = (int(v) for v in base.cells[half])
    c = base.n_vertices
    rest = np.arange(base.n_cells) != half
    mine = tgsis.Surface(
        np.vstack([base.vertices, base.vertices[[a, b, d]].mean(axis=0)]),
        np.vstack([base.cells[rest], [[a, b, c], [b, d, c], [d, a, c]]]),
        vertex_properties={"porosity": np.append(base.vertex_properties["porosity"], 0.2)},
        cell_properties={"facies": np.append(base.cell_properties["facies"][rest], [1, 1, 1]).astype(np.int32)},
    )
    assert tgsis.checkin(conn, co, mine, on_conflict="merge").merged
    conn.commit()
    again = tgsis.checkout(conn, geoid)
    conn.commit()
    parts = np.asarray(again.mesh.cell_properties["part"])
    assert np.array_equal(np.sort(parts), np.sort(np.append(base.cell_properties["part"][rest], [-1, -1, -1])))


def test_a_merge_says_which_meaning_of_the_file_it_did_not_apply(conn: Conn) -> None:
    """The colour changed in the edited mesh (a GOCAD file's header): the merge keeps the stored one, and says so."""
    fault = make_fault(conn, {"color": [1.0, 0.0, 0.0]})
    co = tgsis.checkout(conn, fault)
    conn.commit()
    assert list(co.mesh.metadata["color"]) == [1.0, 0.0, 0.0]
    move(conn, "DEFAULT", fault, SOUTH, (0.0, 0.0, -2.0))
    conn.commit()
    mine = co.mesh.copy()
    mine.vertices[NORTH, 2] += 3.0
    mine.metadata["color"] = [0.0, 0.0, 1.0]
    result = tgsis.checkin(conn, co, mine, on_conflict="merge")
    conn.commit()
    assert result.merged and result.not_applied == ("colour",)
    colour = conn.execute("SELECT colorred, colorblue FROM tgsis.geometry WHERE geoid = %s", (fault,)).fetchone()
    assert colour == (1.0, 0.0)  # the stored colour, as said
    from tgsis.cli.commands.checkin import CheckedIn, checkin_json

    assert checkin_json(CheckedIn(result, "triangle", None, None, []))["not_applied"] == ["colour"]


def test_a_merge_of_a_file_saying_what_is_stored_reports_nothing_not_applied(conn: Conn, fault: int) -> None:
    co = tgsis.checkout(conn, fault)
    conn.commit()
    move(conn, "DEFAULT", fault, SOUTH, (0.0, 0.0, -2.0))
    conn.commit()
    mine = co.mesh.copy()
    mine.vertices[NORTH, 2] += 3.0
    result = tgsis.checkin(conn, co, mine, on_conflict="merge")
    assert result.merged and result.not_applied == ()


def test_vertices_and_triangles_reordered_by_the_tool_keep_their_rows(conn: Conn, fault: int) -> None:
    """A tool that writes the vertices in another order and each triangle from another corner changed nothing there:
    the merge writes the moved vertices only, as a plain check-in does, and every triangle row stays as stored."""
    co = tgsis.checkout(conn, fault)
    conn.commit()
    move(conn, "DEFAULT", fault, SOUTH, (0.0, 0.0, -1.0))
    conn.commit()
    base = co.mesh
    order = np.random.default_rng(7).permutation(base.n_vertices)
    position = np.empty_like(order)
    position[order] = np.arange(len(order))
    vertices = base.vertices[order].copy()
    vertices[position[NORTH], 2] += 2.0
    mine = tgsis.Surface(
        vertices,
        np.roll(position[base.cells], 1, axis=1)[::-1],  # each triangle from its next corner (same orientation)
        vertex_properties={"porosity": base.vertex_properties["porosity"][order]},
        cell_properties={"facies": base.cell_properties["facies"][::-1]},
    )
    trgl = storage_of(conn, "trgl")
    before = conn.execute(f"SELECT count(*) FROM {trgl}").fetchone()
    result = tgsis.checkin(conn, co, mine, on_conflict="merge")
    conn.commit()
    assert result.merged
    expected = curved_surface().vertices.copy()
    moved(expected, SOUTH, (0.0, 0.0, -1.0))
    moved(expected, NORTH, (0.0, 0.0, 2.0))
    ids, xyz, cells, _ = stored_state(conn, "DEFAULT", fault)
    np.testing.assert_array_equal(ids, np.arange(SIDE * SIDE))
    assert xyz.tobytes() == expected.tobytes()
    assert cells == {(i, *map(int, c)) for i, c in enumerate(curved_surface().cells)}  # as stored, corner order too
    assert conn.execute(f"SELECT count(*) FROM {trgl}").fetchone() == before  # no triangle row (or chunk) rewritten
    assert result.save.rows_written == len(NORTH) * 2 + 1  # vertex rows closed and added, the geometry row
