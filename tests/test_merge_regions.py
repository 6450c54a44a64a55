"""tgsis.merge_version by region: disjoint edits of one mesh on both sides merge into the union (issue 39)."""

from __future__ import annotations

import itertools
import time
from typing import Any

import numpy as np
import psycopg
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from psycopg import sql

import tgsis
from tests.merge_data import (
    SIDE,
    curved_surface,
    merge_storage_state,
    move,
    moved,
    rewrites_same_values,
    stored_state,
    stored_unit,
)
from tests.roles import login_roles
from tests.sessions import Background, connect, wait_until_blocked
from tests.storage_data import storage_of
from tgsis.db import merging
from tgsis.db.classes import class_of_feature

Conn = psycopg.Connection[Any]

NORTH = np.arange(0, 2 * SIDE)  # the first two rows of the grid
SOUTH = np.arange((SIDE - 2) * SIDE, SIDE * SIDE)  # the last two
CHILD_SHIFT = (0.125, -3.3, 7.77)
PARENT_SHIFT = (-1.1, 0.0, -2.9)


@pytest.fixture
def fault(conn: Conn, fault_clone: int) -> int:
    return fault_clone  # make_fault's, built once (tests/conftest.py)


def _union() -> Any:
    expected = curved_surface().vertices.copy()
    moved(expected, NORTH, CHILD_SHIFT)
    moved(expected, SOUTH, PARENT_SHIFT)
    return expected


def _cells() -> set[tuple[int, ...]]:
    cells = curved_surface().cells
    return {(i, *map(int, c)) for i, c in enumerate(cells)}


def test_disjoint_edits_merge_into_the_union_bit_for_bit(conn: Conn, fault: int) -> None:
    move(conn, "e1", fault, NORTH, CHILD_SHIFT)
    move(conn, "DEFAULT", fault, SOUTH, PARENT_SHIFT)
    conn.commit()
    result = tgsis.merge_version(conn, "e1")
    assert isinstance(result, merging.MergeResult)
    assert [(o.objectkey, o.how) for o in result.objects] == [(str(fault), "automatic")]
    assert int(result) > 0 and result.objects[0].rows_written > 0
    for version in ("DEFAULT", "e1"):  # the version goes on from the merged state
        ids, xyz, cells, porosity = stored_state(conn, version, fault)
        np.testing.assert_array_equal(ids, np.arange(SIDE * SIDE))
        assert xyz.tobytes() == _union().tobytes()
        assert cells == _cells()
        assert np.array(list(porosity.values())).tobytes() == curved_surface().vertex_properties["porosity"].tobytes()
    assert tgsis.find_conflicts(conn, "e1") == []


def test_a_psql_user_sees_the_merged_object_and_its_box(conn: Conn, fault: int, db_dsn: str) -> None:
    move(conn, "e1", fault, NORTH, CHILD_SHIFT)
    move(conn, "DEFAULT", fault, SOUTH, PARENT_SHIFT)
    conn.commit()
    tgsis.merge_version(conn, "e1")
    with psycopg.connect(db_dsn, autocommit=True) as psql:
        psql.execute("SELECT tgsis.goto_version('DEFAULT')")
        rows = psql.execute("SELECT x, y, z FROM tgsis.vrtx WHERE geoid = %s ORDER BY vrtxid", (fault,)).fetchall()
        assert np.array(rows).tobytes() == _union().tobytes()
        box = psql.execute(
            "SELECT cube_ll_coord(bbox, 3), cube_ur_coord(bbox, 3), nvrtx FROM tgsis.geometry WHERE geoid = %s",
            (fault,),
        ).fetchone()
    union = _union()
    assert box == (union[:, 2].min(), union[:, 2].max(), SIDE * SIDE)


def test_identical_edits_on_both_sides_merge(conn: Conn, fault: int) -> None:
    move(conn, "e1", fault, [60, 61], (0.0, 0.0, 5.5))
    move(conn, "DEFAULT", fault, [60, 61], (0.0, 0.0, 5.5))
    conn.commit()
    tgsis.merge_version(conn, "e1")
    expected = curved_surface().vertices.copy()
    moved(expected, [60, 61], (0.0, 0.0, 5.5))
    assert stored_state(conn, "DEFAULT", fault)[1].tobytes() == expected.tobytes()


def test_rows_written_are_proportional_to_the_change(conn: Conn, fault: int) -> None:
    move(conn, "e1", fault, [3, 4, 5], CHILD_SHIFT)  # three vertices in the child
    move(conn, "DEFAULT", fault, [140], PARENT_SHIFT)  # one in the parent
    conn.commit()
    parent_rev, child_rev = conn.execute(
        "SELECT p.workingrevision, c.workingrevision FROM tgsis.versions c JOIN tgsis.versions p "
        "ON p.versionid = c.parentid WHERE c.name = 'e1'"
    ).fetchone()  # type: ignore[misc]
    conn.commit()
    tgsis.merge_version(conn, "e1")

    def added(table: str, revision: int) -> int:
        storage = storage_of(conn, table)  # <table>_ver, or the chunk table
        return int(conn.execute(f"SELECT count(*) FROM {storage} WHERE revision = %s", (revision,)).fetchone()[0])  # type: ignore[index]

    def versions(ids: list[int]) -> int:  # the stored versions holding these vertices: a row each, or their chunks
        unit = stored_unit(conn, "tgsis", "vrtx")
        return len({unit((str(fault), str(i))) for i in ids})

    # each side's working revision holds its own edit and the other side's merged in: the child's 3 + the
    # parent's 1, and the parent's 1 + the child's 3 (the parent's own row is not written again: that rows are
    # not rewritten is shown apart, test_the_merge_writes_into_the_parent_exactly_the_rows_the_child_changed);
    # on chunks the chunk versions holding those vertices (a chunk written in the working revision is
    # rewritten in place, docs/storage.md)
    assert added("vrtx", child_rev) == versions([3, 4, 5, 140])
    assert added("vrtx", parent_rev) == versions([140, 3, 4, 5])
    assert added("trgl", parent_rev) == 0
    assert added("trgl", child_rev) == 0
    notes = {
        r[0]
        for r in conn.execute(
            "SELECT revision FROM tgsis.revision_objects WHERE schemaname = 'tgsis' AND tablename = 'vrtx' "
            "AND objectkey = %s",
            (str(fault),),
        ).fetchall()
    }
    assert {parent_rev, child_rev} <= notes  # the revision notes of the merge's writes are kept


def test_a_region_conflict_refuses_naming_the_region_and_leaves_everything_unchanged(conn: Conn, fault: int) -> None:
    other = tgsis.db.features.insert_feature(conn, "faults", curved_surface())  # merges by region on its own
    conn.commit()
    tgsis.delete_version(conn, "e1")
    tgsis.create_version(conn, "e1")
    conn.commit()
    move(conn, "e1", other, NORTH, CHILD_SHIFT)
    move(conn, "DEFAULT", other, SOUTH, PARENT_SHIFT)
    move(conn, "e1", fault, [50, 51, 52], (0.0, 0.0, 5.0))  # overlaps the parent's edit at 52
    move(conn, "DEFAULT", fault, [52, 53], (0.0, 0.0, -4.0))
    conn.commit()
    before = merge_storage_state(conn)
    with pytest.raises(tgsis.UnsolvedConflictsError) as caught:
        tgsis.merge_version(conn, "e1")
    message = str(caught.value)
    assert f"feature {fault}" in message and "region 0" in message and "unsolved" in message
    assert f"feature {other}:" not in message  # the other merged by region (then rolled back with the rest)
    assert merge_storage_state(conn) == before


def test_merge_after_refresh_equals_the_merge(conn: Conn, fault: int) -> None:
    tgsis.delete_version(conn, "e1")
    for name in ("p1", "p2"):
        tgsis.create_version(conn, name)
    conn.commit()
    for parent, child in (("p1", "c1"), ("p2", "c2")):
        tgsis.create_version(conn, child, parent=parent)
        conn.commit()
        move(conn, child, fault, NORTH, CHILD_SHIFT)
        move(conn, parent, fault, SOUTH, PARENT_SHIFT)
    conn.commit()
    tgsis.refresh_version(conn, "c1")
    tgsis.merge_version(conn, "c1")
    tgsis.merge_version(conn, "c2")
    first, second = stored_state(conn, "p1", fault), stored_state(conn, "p2", fault)
    assert first[1].tobytes() == second[1].tobytes() == _union().tobytes()
    assert first[2] == second[2] == _cells()
    assert stored_state(conn, "c1", fault)[1].tobytes() == stored_state(conn, "c2", fault)[1].tobytes()


_pairs = itertools.count()
_rows = st.lists(st.integers(0, SIDE - 1), min_size=1, max_size=8, unique=True)
_shift = st.tuples(*(st.floats(-50.0, 50.0, allow_nan=False, allow_subnormal=False) for _ in range(3)))


@settings(
    max_examples=15, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow]
)
@given(
    child_rows=st.lists(st.integers(0, 3), min_size=1, max_size=3, unique=True),
    parent_rows=st.lists(st.integers(7, SIDE - 1), min_size=1, max_size=4, unique=True),
    child_cols=_rows,
    parent_cols=_rows,
    child_shift=_shift,
    parent_shift=_shift,
)
def test_random_disjoint_edits_merge_into_exactly_the_union(
    conn: Conn,
    fault: int,
    child_rows: list[int],
    parent_rows: list[int],
    child_cols: list[int],
    parent_cols: list[int],
    child_shift: tuple[float, float, float],
    parent_shift: tuple[float, float, float],
) -> None:
    # rows 0-3 and 7-11: the one-ring margins (a row either side) never meet
    n = next(_pairs)
    parent, child = f"hp{n}", f"hc{n}"
    tgsis.create_version(conn, parent)
    conn.commit()
    tgsis.create_version(conn, child, parent=parent)
    conn.commit()
    start = stored_state(conn, parent, fault)[1]
    child_ids = [r * SIDE + c for r in child_rows for c in child_cols]
    parent_ids = [r * SIDE + c for r in parent_rows for c in parent_cols]
    move(conn, child, fault, child_ids, child_shift)
    move(conn, parent, fault, parent_ids, parent_shift)
    conn.commit()
    result = tgsis.merge_version(conn, child, remove=True)
    expected = start.copy()
    moved(expected, child_ids, child_shift)
    moved(expected, parent_ids, parent_shift)
    # merged by region when both sides changed the object; a move by a shift that leaves every value's bits as
    # they were changes it on rows (a new row version), not on chunks (nothing written)
    child_moved, parent_moved = start.copy(), start.copy()
    moved(child_moved, child_ids, child_shift)
    moved(parent_moved, parent_ids, parent_shift)
    both = rewrites_same_values(conn) or (
        child_moved.tobytes() != start.tobytes() and parent_moved.tobytes() != start.tobytes()
    )
    assert [o.how for o in result.objects] == (["automatic"] if both else [])
    ids, xyz, cells, _ = stored_state(conn, parent, fault)
    np.testing.assert_array_equal(ids, np.arange(SIDE * SIDE))
    assert xyz.tobytes() == expected.tobytes()
    assert cells == _cells()


def _wait_until_waiting(observer: Conn, pid: int) -> None:
    deadline = time.monotonic() + 15
    while time.monotonic() < deadline:
        row = observer.execute("SELECT cardinality(pg_blocking_pids(%s)) > 0", (pid,)).fetchone()
        observer.rollback()
        if row == (True,):
            return
        time.sleep(0.02)
    pytest.fail(f"backend {pid} never waited")


def test_two_sessions_merging_and_refreshing_at_once(conn: Conn, fault: int, db_dsn: str) -> None:
    move(conn, "e1", fault, NORTH, CHILD_SHIFT)
    move(conn, "DEFAULT", fault, SOUTH, PARENT_SHIFT)
    conn.commit()
    holder = connect(db_dsn, "holder")
    holder.execute("SELECT tgsis.lock_for_region_merge('e1', 'refresh')")  # both below wait for it
    merger = Background(db_dsn, "merger", lambda c: tgsis.merge_version(c, "e1"))
    wait_until_blocked(conn, merger.pid, holder.info.backend_pid)
    refresher = Background(db_dsn, "refresher", lambda c: tgsis.refresh_version(c, "e1"))
    _wait_until_waiting(conn, refresher.pid)  # for the holder, or behind the merger in the queue of the row lock
    holder.rollback()
    holder.close()
    merger.finish()
    refresher.finish()
    for version in ("DEFAULT", "e1"):
        ids, xyz, cells, _ = stored_state(conn, version, fault)
        assert xyz.tobytes() == _union().tobytes()
        assert cells == _cells()


def test_a_writer_in_the_version_during_the_merge(conn: Conn, fault: int, db_dsn: str) -> None:
    move(conn, "e1", fault, NORTH, CHILD_SHIFT)
    move(conn, "DEFAULT", fault, SOUTH, PARENT_SHIFT)
    conn.commit()
    writer = connect(db_dsn, "writer")
    tgsis.goto_version(writer, "e1")
    writer.execute("UPDATE tgsis.vrtx SET z = z + 1.5 WHERE geoid = %s AND vrtxid = 70", (fault,))
    merger = Background(db_dsn, "merger", lambda c: tgsis.merge_version(c, "e1"))
    wait_until_blocked(conn, merger.pid, writer.info.backend_pid)  # the merge waits for the writer
    writer.commit()
    writer.close()
    merger.finish()
    expected = _union()
    moved(expected, [70], (0.0, 0.0, 1.5))
    assert stored_state(conn, "DEFAULT", fault)[1].tobytes() == expected.tobytes()


def test_a_role_without_rights_on_the_class_gets_the_permission_error_and_nothing_is_written(
    conn: Conn, fault: int, db_dsn: str
) -> None:
    move(conn, "e1", fault, NORTH, CHILD_SHIFT)
    move(conn, "DEFAULT", fault, SOUTH, PARENT_SHIFT)
    conn.commit()
    with login_roles(db_dsn, {"ed": "tgsis_editor", "rita": "tgsis_reader"}) as made:
        tgsis.grant_version(conn, "e1", "all", made.name("ed"))
        tgsis.grant_version(conn, "DEFAULT", "merge", made.name("ed"))
        conn.execute("REVOKE INSERT, UPDATE, DELETE ON public.faults FROM tgsis_editor")
        conn.commit()
        before = merge_storage_state(conn)
        with pytest.raises(tgsis.MissingPrivilegeError):
            tgsis.merge_version(made.connect("rita"), "e1")
        assert merge_storage_state(conn) == before
        with pytest.raises(tgsis.MissingPrivilegeError):
            tgsis.merge_version(made.connect("ed"), "e1")
        assert merge_storage_state(conn) == before


def test_remove_needs_the_right_to_write_the_merged_mesh_into_the_version(conn: Conn, fault: int, db_dsn: str) -> None:
    move(conn, "e1", fault, NORTH, CHILD_SHIFT)
    move(conn, "DEFAULT", fault, SOUTH, PARENT_SHIFT)
    conn.commit()
    with login_roles(db_dsn, {"mo": "tgsis_editor"}) as made:
        tgsis.grant_version(conn, "e1", "delete", made.name("mo"))
        tgsis.grant_version(conn, "DEFAULT", "merge", made.name("mo"))
        conn.commit()
        before = merge_storage_state(conn)
        with pytest.raises(tgsis.MissingPrivilegeError, match="write"):
            tgsis.merge_version(made.connect("mo"), "e1", remove=True)
        assert merge_storage_state(conn) == before


def test_the_command_line_merges_by_region_and_says_so(
    conn: Conn, fault: int, db_dsn: str, capsys: pytest.CaptureFixture[str], tmp_path: Any, monkeypatch: Any
) -> None:
    from tgsis.cli import main

    monkeypatch.setenv("TGSIS_HOME", str(tmp_path))
    monkeypatch.delenv("TGSIS_VERSION", raising=False)
    move(conn, "e1", fault, NORTH, CHILD_SHIFT)
    move(conn, "DEFAULT", fault, SOUTH, PARENT_SHIFT)
    conn.commit()
    assert main(["--dsn", db_dsn, "version", "refresh", "e1"]) == 0
    out = capsys.readouterr().out
    assert f"feature {fault} merged by region (2 region(s), every region merged by itself)" in out
    assert main(["--dsn", db_dsn, "version", "merge", "e1"]) == 0
    assert "merged e1 into its parent: " in capsys.readouterr().out
    assert stored_state(conn, "DEFAULT", fault)[1].tobytes() == _union().tobytes()


def test_parts_changed_in_the_parent_are_merged_with_the_childs_moves(conn: Conn) -> None:
    """Parts kept in tgsis.part (runs of cell ids) go through the merge as the cell property ``part``."""
    tgsis.create_feature_class(conn, "faults", "SURFACE")
    tgsis.enable_feature_versioning(conn)
    surface = curved_surface()
    half = len(surface.cells) // 2
    square_row = np.concatenate([np.arange(half), np.arange(half)]) // (SIDE - 1)
    parted = tgsis.Surface(
        surface.vertices, surface.cells, cell_properties={"part": (square_row >= 8).astype(np.int64)}
    )
    geoid = tgsis.insert_feature(conn, "faults", parted)
    tgsis.create_version(conn, "e1")
    conn.commit()
    runs = conn.execute("SELECT firstid, lastid, part FROM tgsis.part WHERE geoid = %s ORDER BY firstid", (geoid,))
    assert [r[2] for r in runs.fetchall()] == [0, 1, 0, 1]
    conn.execute("UPDATE tgsis.part SET part = 2 WHERE geoid = %s AND part = 1", (geoid,))  # DEFAULT: the south
    conn.commit()
    move(conn, "e1", geoid, NORTH, CHILD_SHIFT)
    conn.commit()
    result = tgsis.merge_version(conn, "e1")
    assert [o.how for o in result.objects] == ["automatic"]
    for version in ("DEFAULT", "e1"):
        with tgsis.in_version(conn, version):
            parts = conn.execute(
                "SELECT firstid, lastid, part FROM tgsis.part WHERE geoid = %s ORDER BY firstid", (geoid,)
            ).fetchall()
            mesh = tgsis.fetch_feature(conn, "faults", geoid).mesh
        conn.commit()
        assert [p[2] for p in parts] == [0, 2, 0, 2]
        expected = surface.vertices.copy()
        moved(expected, NORTH, CHILD_SHIFT)
        assert isinstance(mesh, tgsis.Surface)
        assert mesh.vertices.tobytes() == expected.tobytes()
        np.testing.assert_array_equal(mesh.cell_properties["part"], np.where(square_row >= 8, 2, 0))


@pytest.mark.parametrize("solution", ["parent", "child"])
def test_recorded_region_solutions_are_applied_by_the_merge(conn: Conn, fault: int, solution: str) -> None:
    move(conn, "e1", fault, NORTH, CHILD_SHIFT)  # merges by itself
    move(conn, "e1", fault, [64, 65, 66], (0.0, 0.0, 5.0))  # overlaps the parent's edit at 66
    move(conn, "DEFAULT", fault, [66, 67], (0.0, 0.0, -4.0))
    conn.commit()
    conflicts = tgsis.find_conflicts(conn, "e1")  # the region-aware one: records the regions
    conn.commit()
    (conflict,) = conflicts
    (region,) = [r for r in conflict.regions if r.conflict]
    with pytest.raises(tgsis.UnsolvedConflictsError, match=rf"feature {fault}: region {region.region} unsolved"):
        tgsis.merge_version(conn, "e1")
    conn.rollback()
    tgsis.resolve_region(conn, "e1", fault, region.region, solution)
    conn.commit()
    result = tgsis.merge_version(conn, "e1")
    (merged,) = result.objects
    assert (merged.how, merged.solved) == ("solutions", 1)
    assert [d.side for d in merged.discards] == ["child" if solution == "parent" else "parent"]
    expected = curved_surface().vertices.copy()
    moved(expected, NORTH, CHILD_SHIFT)
    if solution == "parent":
        moved(expected, [66, 67], (0.0, 0.0, -4.0))
    else:
        moved(expected, [64, 65, 66], (0.0, 0.0, 5.0))
    for version in ("DEFAULT", "e1"):
        assert stored_state(conn, version, fault)[1].tobytes() == expected.tobytes()


@pytest.mark.parametrize("geotype", ["MULTIPOINT", "MULTILINESTRING", "MULTITETRA"])
def test_points_lines_and_solids_merge_by_region_with_cells_added_on_one_side(conn: Conn, geotype: str) -> None:
    from tests.test_object_merge import _other_kind

    tgsis.create_feature_class(conn, "bodies", geotype)
    tgsis.enable_feature_versioning(conn)
    mesh = _other_kind(geotype)
    geoid = tgsis.insert_feature(conn, "bodies", mesh)
    tgsis.create_version(conn, "e1")
    conn.commit()
    first, last = np.arange(0, 5), np.arange(34, 40)
    move(conn, "e1", geoid, first, (0.5, 0.25, -1.125))
    move(conn, "DEFAULT", geoid, last, (-3.3, 0.0, 2.2))
    table, key = {
        "MULTIPOINT": ("point", "pointid"),
        "MULTILINESTRING": ("segment", "segid"),
        "MULTITETRA": ("tetra", "tetraid"),
    }[geotype]
    k = mesh.cell_size
    with tgsis.in_version(conn, "e1"):  # the child adds a cell on the first vertices (a new id)
        columns = ", ".join(f"vrtxid{j + 1}" for j in range(k))
        conn.execute(
            f"INSERT INTO tgsis.{table} (geoid, {key}, {columns}) VALUES (%s, 1000, {', '.join(['%s'] * k)})",
            (geoid, *([0, 2, 4, 1][:k] if k > 1 else [3])),
        )
    conn.commit()
    result = tgsis.merge_version(conn, "e1")
    assert [o.how for o in result.objects] == ["automatic"]
    expected = mesh.vertices.copy()
    moved(expected, first, (0.5, 0.25, -1.125))
    moved(expected, last, (-3.3, 0.0, 2.2))
    with tgsis.in_version(conn, "DEFAULT"):
        rows = conn.execute("SELECT x, y, z FROM tgsis.vrtx WHERE geoid = %s ORDER BY vrtxid", (geoid,)).fetchall()
        cells = conn.execute(f"SELECT {key} FROM tgsis.{table} WHERE geoid = %s ORDER BY 1", (geoid,)).fetchall()
    conn.commit()
    assert np.array(rows).tobytes() == expected.tobytes()
    assert [c[0] for c in cells] == [*range(len(mesh.cells)), 1000]


def test_a_triangle_added_in_psql_to_a_surface_of_parts_merges_in_no_part(conn: Conn) -> None:
    """A multi-part surface (tgsis.part runs) whose version gained a triangle by a psql INSERT (in no run: part -1
    as read): the merge by region writes it, in no part, and keeps every other triangle in its part."""
    from tests.merge_data import curved_surface, move

    tgsis.create_feature_class(conn, "sheets", "SURFACE")
    tgsis.enable_feature_versioning(conn)
    surface = curved_surface()
    surface.vertex_properties.clear()
    surface.cell_properties.clear()
    half = surface.n_cells // 2
    surface.cell_properties["part"] = (np.arange(surface.n_cells) >= half).astype(np.int64)
    geoid = tgsis.insert_feature(conn, "sheets", surface)
    tgsis.create_version(conn, "e1")
    conn.commit()
    with tgsis.in_version(conn, "e1"):  # edge 0 -> 1 of triangle (0, 1, 13) is on the boundary: a triangle beyond it
        n = surface.n_vertices
        conn.execute("INSERT INTO tgsis.vrtx (geoid, vrtxid, x, y, z) VALUES (%s, %s, 50.0, -300.0, 0.0)", (geoid, n))
        conn.execute(
            "INSERT INTO tgsis.trgl (geoid, trglid, vrtxid1, vrtxid2, vrtxid3) VALUES (%s, %s, 1, 0, %s)",
            (geoid, surface.n_cells, n),
        )
        conn.execute("UPDATE tgsis.geometry SET nvrtx = nvrtx + 1, ncell = ncell + 1 WHERE geoid = %s", (geoid,))
    move(conn, "DEFAULT", geoid, np.arange(130, 144), (0.0, 0.0, -1.0))
    conn.commit()
    tgsis.merge_version(conn, "e1")
    conn.commit()
    merged = tgsis.checkout(conn, geoid)
    conn.commit()
    parts = np.asarray(merged.mesh.cell_properties["part"])
    assert len(parts) == surface.n_cells + 1
    assert np.array_equal(parts, np.append(surface.cell_properties["part"], -1))


def _object_rows(conn: Conn, version: str, geoid: int) -> dict[tuple[str, str], dict[tuple[str, ...], tuple[str, ...]]]:
    """Per versioned table of the feature class: the object's visible rows, key -> content, all as exact text."""
    conn.execute("SET extra_float_digits = 1")  # floats as their shortest exact text (-0 is not 0)
    rows: dict[tuple[str, str], dict[tuple[str, ...], tuple[str, ...]]] = {}
    for schema, table, keys, objectkey in conn.execute(
        "SELECT schemaname, tablename, keycolumns, objectkeyfield FROM tgsis.versioned_tables "
        "WHERE objectclass = 'feature' ORDER BY 1, 2"
    ).fetchall():
        cursor = conn.execute(
            sql.SQL("SELECT v::text, {} FROM tgsis.rows_at(NULL::{}.{}, %s) v WHERE {} = %s").format(
                sql.SQL(", ").join(sql.SQL("{}::text").format(sql.Identifier(k)) for k in keys),
                sql.Identifier(schema),
                sql.Identifier(table),
                sql.Identifier(objectkey),
            ),
            (version, geoid),
        )
        rows[schema, table] = {tuple(r[1:]): (r[0],) for r in cursor.fetchall()}
    conn.commit()
    return rows


def _written_in(
    conn: Conn, revision: int, geoid: int
) -> dict[tuple[str, str], tuple[set[tuple[str, ...]], set[tuple[str, ...]]]]:
    """Per table: (keys of the stored versions written in ``revision``, keys of those closed in it) of one object.

    The stored versions are rows, or chunk versions keyed by their chunk (``tgsis.storage_key``).
    """
    found = {}
    for schema, table, keys, objectkey, storage in conn.execute(
        "SELECT schemaname, tablename, tgsis.storage_key(v), objectkeyfield, tgsis.storage_table(schemaname, tablename) "
        "FROM tgsis.versioned_tables v WHERE objectclass = 'feature' ORDER BY 1, 2"
    ).fetchall():
        key = sql.SQL(", ").join(sql.SQL("{}::text").format(sql.Identifier(k)) for k in keys)
        storage = sql.SQL(storage)  # quoted by tgsis.storage_table
        written = conn.execute(
            sql.SQL("SELECT {} FROM {} WHERE {} = %s AND revision = %s").format(
                key, storage, sql.Identifier(objectkey)
            ),
            (geoid, revision),
        ).fetchall()
        closed = conn.execute(
            sql.SQL("SELECT {} FROM {} WHERE {} = %s AND %s = ANY (lastrevs)").format(
                key, storage, sql.Identifier(objectkey)
            ),
            (geoid, revision),
        ).fetchall()
        found[schema, table] = ({tuple(r) for r in written}, {tuple(r) for r in closed})
    conn.commit()
    return found


def test_the_merge_writes_into_the_parent_exactly_the_rows_the_child_changed(conn: Conn, fault: int) -> None:
    """Not the parent's own edits again: only the rows whose content the merge changes (issue 39, item 5)."""
    fc = class_of_feature(conn, fault)
    vertex_table, cell_table = fc.property_table("VERTEX") or "", fc.property_table("CELL") or ""
    vertex_props, cell_props = fc.qualified(vertex_table), fc.qualified(cell_table)
    move(conn, "e1", fault, NORTH, CHILD_SHIFT)
    with tgsis.in_version(conn, "e1"):
        conn.execute(
            sql.SQL("UPDATE {} SET porosity = porosity + 0.01 WHERE _geoid = %s AND _idx IN (30, 31)").format(
                vertex_props
            ),
            (fault,),
        )
        conn.execute(sql.SQL("UPDATE {} SET facies = 4 WHERE _geoid = %s AND _idx = 5").format(cell_props), (fault,))
    conn.commit()
    move(conn, "DEFAULT", fault, SOUTH, PARENT_SHIFT)
    with tgsis.in_version(conn, "DEFAULT"):
        conn.execute(
            sql.SQL("UPDATE {} SET porosity = 0.5 WHERE _geoid = %s AND _idx IN (130, 131)").format(vertex_props),
            (fault,),
        )
        tgsis.save_revision(conn, "parent's edits")  # frozen: the merge writes in a revision of its own
    conn.commit()
    (merge_revision,) = conn.execute("SELECT workingrevision FROM tgsis.versions WHERE name = 'DEFAULT'").fetchone()  # type: ignore[misc]
    conn.commit()
    before = _object_rows(conn, "DEFAULT", fault)
    result = tgsis.merge_version(conn, "e1")
    after = _object_rows(conn, "DEFAULT", fault)
    assert after == _object_rows(conn, "e1", fault)
    written = _written_in(conn, merge_revision, fault)
    units = {table: stored_unit(conn, *table) for table in after}  # a row's stored version: itself, or its chunk
    for table, rows in after.items():
        new, closed = written[table]
        unit = units[table]
        changed = {unit(k) for k in rows.keys() | before[table].keys() if before[table].get(k) != rows.get(k)}
        assert new == changed & {unit(k) for k in rows}, table
        assert closed == changed & {unit(k) for k in before[table]}, table
    vrtx = units["tgsis", "vrtx"]
    assert written["tgsis", "vrtx"][0] == {vrtx((str(fault), str(i))) for i in NORTH}  # the child's moves, not SOUTH
    on_vertex, on_cell = units[fc.schema, vertex_table], units[fc.schema, cell_table]  # rows, or their chunks
    assert written[fc.schema, vertex_table][0] == {on_vertex((str(fault), "30")), on_vertex((str(fault), "31"))}
    assert written[fc.schema, cell_table][0] == {on_cell((str(fault), "5"))}
    assert written["tgsis", "trgl"] == (set(), set())
    (merged,) = result.objects
    assert int(result) - merged.rows_written == sum(len(n) + len(c) for n, c in written.values())
