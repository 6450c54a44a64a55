"""tgsis.object_merge: the three-way merge of one model-1 object of a version, read from the database (issue 39)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt
import psycopg
import pytest
from psycopg import sql
from psycopg.conninfo import make_conninfo

import tgsis
from tests.merge_data import SIDE, curved_surface, move
from tests.roles import login_roles
from tgsis.cli import main
from tgsis.db import _merge_states
from tgsis.db import features as F

Conn = psycopg.Connection[Any]


@pytest.fixture
def fault(conn: Conn, fault_clone: int) -> int:
    """One curved surface with a vertex property in DEFAULT, and version e1 based on it (make_fault's, cloned)."""
    return fault_clone


def _moved(vertices: npt.NDArray[np.float64], ids: npt.ArrayLike, shift: tuple[float, float, float]) -> None:
    """The same move made in Python (float8 + float8 in PostgreSQL and numpy are both IEEE: bit for bit)."""
    at = np.asarray(ids)
    for axis in range(3):
        vertices[at, axis] = vertices[at, axis] + shift[axis]


NORTH = np.arange(0, 2 * SIDE)  # the first two rows of the grid
SOUTH = np.arange((SIDE - 2) * SIDE, SIDE * SIDE)  # the last two


def test_disjoint_ends_merge_into_the_union(conn: Conn, fault: int) -> None:
    move(conn, "e1", fault, NORTH, (0.125, -3.3, 7.77))
    move(conn, "DEFAULT", fault, SOUTH, (-1.1, 0.0, -2.9))
    merge = tgsis.object_merge(conn, "e1", fault)
    assert merge.conflicts == ()
    assert sorted(r.sides for r in merge.regions) == ["child", "parent"]
    expected = curved_surface().vertices.copy()
    _moved(expected, NORTH, (0.125, -3.3, 7.77))
    _moved(expected, SOUTH, (-1.1, 0.0, -2.9))
    assert merge.merged is not None
    state = merge.merged.state
    np.testing.assert_array_equal(state.vertex_ids, np.arange(SIDE * SIDE))
    assert state.vertices.tobytes() == expected.tobytes()  # bit for bit
    surface = curved_surface()
    assert {tuple(c) for c in state.cells.tolist()} == {tuple(c) for c in surface.cells.tolist()}
    assert state.vertex_properties["porosity"].tobytes() == surface.vertex_properties["porosity"].tobytes()
    assert merge.merged.discards == ()


def _other_kind(geotype: str) -> tgsis.Mesh:
    """A point set, a polyline or a column of tetrahedra along x, with curved z, 40 vertices."""
    n = 40
    x = np.linspace(0.0, 3.9, n) * 1000.3
    vertices = np.stack([x, np.cos(x / 700.0) * 33.3, np.sin(x / 900.0) * 151.7], axis=1)
    if geotype == "MULTIPOINT":
        return tgsis.PointSet(vertices, np.arange(n).reshape(-1, 1))
    if geotype == "MULTILINESTRING":
        return tgsis.LineSet(vertices, np.stack([np.arange(n - 1), np.arange(1, n)], axis=1))
    vertices[1::2, 1] += 250.0  # a strip of tetrahedra: vertex i with its three followers
    vertices[2::4, 2] += 90.0
    i = np.arange(n - 3)
    return tgsis.TetraMesh(vertices, np.stack([i, i + 1, i + 2, i + 3], axis=1))


@pytest.mark.parametrize("geotype", ["MULTIPOINT", "MULTILINESTRING", "MULTITETRA"])
def test_points_lines_and_solids_merge_disjoint_ends_into_the_union(conn: Conn, geotype: str) -> None:
    F.create_feature_class(conn, "bodies", geotype)
    tgsis.enable_feature_versioning(conn)
    mesh = _other_kind(geotype)
    geoid = F.insert_feature(conn, "bodies", mesh)
    tgsis.create_version(conn, "e1")
    conn.commit()
    first, last = np.arange(0, 5), np.arange(34, 40)
    move(conn, "e1", geoid, first, (0.5, 0.25, -1.125))
    move(conn, "DEFAULT", geoid, last, (-3.3, 0.0, 2.2))
    merge = tgsis.object_merge(conn, "e1", geoid)
    assert merge.conflicts == () and merge.merged is not None
    assert merge.base.cell_size == mesh.cell_size
    expected = mesh.vertices.copy()
    _moved(expected, first, (0.5, 0.25, -1.125))
    _moved(expected, last, (-3.3, 0.0, 2.2))
    assert merge.merged.state.vertices.tobytes() == expected.tobytes()
    np.testing.assert_array_equal(merge.merged.state.cells, mesh.cells)
    move(conn, "DEFAULT", geoid, [2], (0.0, 0.0, 1.0))  # now the parent also moves one the child moved
    [region] = tgsis.object_merge(conn, "e1", geoid).conflicts
    assert 2 in region.parent_vertex_ids and 2 in region.child_vertex_ids


def test_overlapping_edits_are_one_conflict_region_with_the_edited_ids(conn: Conn, fault: int) -> None:
    child_ids = np.array([50, 51, 52])
    parent_ids = np.array([52, 53])  # vertex 52 moved by both, differently
    move(conn, "e1", fault, child_ids, (0.0, 0.0, 5.0))
    move(conn, "DEFAULT", fault, parent_ids, (0.0, 0.0, -4.0))
    merge = tgsis.object_merge(conn, "e1", fault)
    [region] = merge.conflicts
    assert len(merge.regions) == 1 and region.sides == "both"
    np.testing.assert_array_equal(region.child_vertex_ids, child_ids)
    np.testing.assert_array_equal(region.parent_vertex_ids, parent_ids)
    assert region.child_displacement == 5.0 and region.parent_displacement == 4.0
    assert merge.merged is None


def test_property_values_are_read_and_merged(conn: Conn, fault: int) -> None:
    """A vertex value changed in DEFAULT and a cell value changed in e1 are two regions, both kept."""
    fc = tgsis.get_feature_class(conn, "faults")
    vertex_table, cell_table = fc.property_table("VERTEX"), fc.property_table("CELL")
    assert vertex_table is not None and cell_table is not None
    conn.commit()
    with tgsis.in_version(conn, "DEFAULT"):
        conn.execute(
            sql.SQL("UPDATE {} SET porosity = 0.99 WHERE _geoid = %s AND _idx = 3").format(fc.qualified(vertex_table)),
            (fault,),
        )
    with tgsis.in_version(conn, "e1"):
        conn.execute(
            sql.SQL("UPDATE {} SET facies = 42 WHERE _geoid = %s AND _idx = 200").format(fc.qualified(cell_table)),
            (fault,),
        )
    merge = tgsis.object_merge(conn, "e1", fault)
    surface = curved_surface()
    assert merge.base.cell_properties["facies"].tolist() == surface.cell_properties["facies"].tolist()
    assert merge.base.vertex_properties["porosity"].tobytes() == surface.vertex_properties["porosity"].tobytes()
    assert {r.sides: (r.parent_vertex_ids.tolist(), r.child_cell_ids.tolist()) for r in merge.regions} == {
        "parent": ([3], []),
        "child": ([], [200]),
    }
    assert merge.merged is not None
    assert merge.merged.state.vertex_properties["porosity"][3] == 0.99
    assert merge.merged.state.cell_properties["facies"][200] == 42
    assert merge.merged.state.cell_properties["facies"][199] == 199 % 5


def test_base_is_the_state_at_the_initial_revision(conn: Conn, fault: int) -> None:
    """DEFAULT's edit after e1 was created is the parent's, not the base's."""
    original = curved_surface().vertices
    move(conn, "DEFAULT", fault, [7], (0.0, 0.0, 1.5))
    move(conn, "e1", fault, [100], (0.0, 0.0, 2.5))
    merge = tgsis.object_merge(conn, "e1", fault)
    assert merge.base.vertices.tobytes() == original.tobytes()
    assert merge.parent.vertices[7, 2] == original[7, 2] + 1.5 and merge.parent.vertices[100, 2] == original[100, 2]
    assert merge.child.vertices[100, 2] == original[100, 2] + 2.5 and merge.child.vertices[7, 2] == original[7, 2]
    [p] = [r for r in merge.regions if r.sides == "parent"]
    np.testing.assert_array_equal(p.parent_vertex_ids, [7])


def test_ids_are_read_as_stored_not_renumbered(conn: Conn, fault: int) -> None:
    """A removed vertex leaves a gap in the ids; the states keep it."""
    with tgsis.in_version(conn, "e1"):
        conn.execute("DELETE FROM tgsis.trgl WHERE geoid = %s AND %s IN (vrtxid1, vrtxid2, vrtxid3)", (fault, 0))
        conn.execute("DELETE FROM tgsis.vrtx WHERE geoid = %s AND vrtxid = 0", (fault,))
    move(conn, "DEFAULT", fault, SOUTH, (0.0, 0.0, 1.0))
    merge = tgsis.object_merge(conn, "e1", fault)
    np.testing.assert_array_equal(merge.child.vertex_ids, np.arange(1, SIDE * SIDE))
    assert merge.conflicts == () and merge.merged is not None
    np.testing.assert_array_equal(merge.merged.state.vertex_ids, np.arange(1, SIDE * SIDE))
    assert merge.merged.state.vertices[-1, 2] == curved_surface().vertices[-1, 2] + 1.0


def test_a_writer_committing_between_the_reads_does_not_change_the_answer(
    conn: Conn, fault: int, db_dsn: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    move(conn, "e1", fault, NORTH, (0.0, 0.0, 3.0))
    move(conn, "DEFAULT", fault, SOUTH, (0.0, 0.0, -3.0))
    before = tgsis.object_merge(conn, "e1", fault)
    read = _merge_states.columns_out_all  # type: ignore[attr-defined]
    calls: list[int] = []

    def write_then_read(*args: Any) -> Any:
        # after the revision sets are read, before the rows: another session writes in both sides and commits
        calls.append(len(args[1]))
        with psycopg.connect(db_dsn, autocommit=True) as other:
            for version in ("DEFAULT", "e1"):
                move(other, version, fault, [60, 61], (0.0, 0.0, 11.0))
        return read(*args)

    monkeypatch.setattr(_merge_states, "columns_out_all", write_then_read)
    during = tgsis.object_merge(conn, "e1", fault)
    assert len(calls) == 1  # one statement: the base's rows and the rows each side changed since it
    assert during.merged is not None and before.merged is not None
    for state in ("base", "parent", "child"):
        assert getattr(during, state).vertices.tobytes() == getattr(before, state).vertices.tobytes()
    assert during.merged.state.vertices.tobytes() == before.merged.state.vertices.tobytes()
    monkeypatch.setattr(_merge_states, "columns_out_all", read)
    after = tgsis.object_merge(conn, "e1", fault)  # the write is there for the next call
    assert after.child.vertices[60, 2] == before.child.vertices[60, 2] + 11.0


def test_a_read_committed_transaction_is_refused(conn: Conn, fault: int) -> None:
    move(conn, "e1", fault, NORTH, (0.0, 0.0, 3.0))
    move(conn, "DEFAULT", fault, SOUTH, (0.0, 0.0, -3.0))
    conn.execute("SELECT 1")  # the caller's READ COMMITTED transaction
    with pytest.raises(tgsis.InvalidInputError, match="one snapshot.*read committed"):
        tgsis.object_merge(conn, "e1", fault)
    conn.rollback()
    conn.isolation_level = psycopg.IsolationLevel.REPEATABLE_READ
    assert conn.execute("SELECT current_setting('transaction_isolation')").fetchone() == ("repeatable read",)
    assert tgsis.object_merge(conn, "e1", fault).conflicts == ()
    conn.rollback()


def test_the_session_stays_in_its_version(conn: Conn, fault: int) -> None:
    move(conn, "e1", fault, NORTH, (0.0, 0.0, 3.0))
    move(conn, "DEFAULT", fault, SOUTH, (0.0, 0.0, -3.0))
    tgsis.goto_version(conn, "e1")
    tgsis.object_merge(conn, "e1", fault)
    assert tgsis.working_version(conn) == "e1" and tgsis.viewing_revision(conn) is None
    conn.commit()
    conn.isolation_level = psycopg.IsolationLevel.REPEATABLE_READ  # in the caller's transaction too
    assert tgsis.working_version(conn) == "e1"  # the transaction has begun
    tgsis.object_merge(conn, "e1", fault)
    assert tgsis.working_version(conn) == "e1" and tgsis.viewing_revision(conn) is None
    conn.rollback()


def test_an_object_not_changed_on_both_sides_is_refused(conn: Conn, fault: int) -> None:
    move(conn, "e1", fault, NORTH, (0.0, 0.0, 3.0))
    with pytest.raises(
        tgsis.VersioningError, match=rf"feature {fault} of class faults was not changed both in version e1 "
    ) as caught:
        tgsis.object_merge(conn, "e1", fault)
    assert caught.value.hint is not None and "find_conflicts" in caught.value.hint
    with pytest.raises(tgsis.NotFoundError):
        tgsis.object_merge(conn, "e1", fault + 1000)


def test_an_object_of_another_model_is_refused(conn: Conn, fault: int) -> None:
    F.create_feature_class(conn, "collections", "GEOMETRYCOLLECTION")
    member = tgsis.Surface(curved_surface().vertices, curved_surface().cells)
    geoid = F.insert_feature(conn, "collections", tgsis.GeometryCollection([member]))
    tgsis.create_version(conn, "e2")  # e1 does not see what DEFAULT added after its base
    conn.commit()
    with pytest.raises(tgsis.NotFoundError, match=f"no feature class has a feature {geoid}"):
        tgsis.object_merge(conn, "e1", geoid)
    with pytest.raises(
        tgsis.InvalidInputError, match=rf"feature {geoid} of class collections is a geometry collection"
    ):
        tgsis.object_merge(conn, "e2", geoid)


def test_a_role_without_rights_on_the_class_is_refused(conn: Conn, fault: int, db_dsn: str) -> None:
    move(conn, "e1", fault, NORTH, (0.0, 0.0, 3.0))
    move(conn, "DEFAULT", fault, SOUTH, (0.0, 0.0, -3.0))
    conn.commit()
    with login_roles(db_dsn, {"rita": "tgsis_reader"}) as made:
        rita = made.connect("rita")
        assert tgsis.object_merge(rita, "e1", fault).conflicts == ()  # a reader may
        conn.execute("REVOKE SELECT ON public.faults FROM tgsis_reader")
        conn.commit()
        with pytest.raises(tgsis.MissingPrivilegeError, match="faults"):
            tgsis.object_merge(made.connect("rita"), "e1", fault)


@pytest.fixture
def cli_state(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("TGSIS_HOME", str(tmp_path))
    monkeypatch.delenv("TGSIS_VERSION", raising=False)


def _cli(dsn: str, capsys: pytest.CaptureFixture[str], *argv: str) -> str:
    assert main(["--dsn", dsn, *argv]) == 0, capsys.readouterr()
    return capsys.readouterr().out


@pytest.mark.usefixtures("cli_state")
def test_cli_regions_text_and_json(conn: Conn, fault: int, db_dsn: str, capsys: pytest.CaptureFixture[str]) -> None:
    move(conn, "e1", fault, [50, 51, 52], (0.0, 0.0, 5.0))  # overlaps the parent's edit at 52
    move(conn, "DEFAULT", fault, [52, 53], (0.0, 0.0, -4.0))
    move(conn, "e1", fault, SOUTH, (0.0, 2.0, 0.0))  # and an end of the child's own
    conn.commit()
    text = _cli(db_dsn, capsys, "version", "conflicts", "e1", "--regions")
    lines = text.splitlines()
    assert f"feature\t{fault}\tunsolved" in text
    assert "\tregions\t2 region(s), 1 in conflict: those need a solution, the others merge by themselves" in lines
    [conflict] = [line for line in lines if "\tconflict\t" in line]
    assert conflict.startswith("\tregion 0\tconflict\tchanged in both\tvertices 2 parent, 3 child")
    assert "largest displacement 4 parent, 5 child" in conflict
    [merges] = [line for line in lines if "\tmerges\t" in line]
    assert merges.startswith(f"\tregion 1\tmerges\tchanged in child\tvertices 0 parent, {len(SOUTH)} child")
    assert "largest displacement 0 parent, 2 child" in merges
    assert "\tregion" not in _cli(db_dsn, capsys, "version", "conflicts", "e1")  # only with --regions

    document = json.loads(_cli(db_dsn, capsys, "version", "conflicts", "e1", "--regions", "--json"))
    [entry] = document["conflicts"]
    regions = entry["regions"]
    assert regions["merges_by_region"] and not regions["merges_by_itself"]
    first, second = regions["regions"]
    assert (first["conflict"], first["changed_in"], first["merges_by_itself"]) == (True, "both", False)
    assert first["child"]["vertex_ids"] == [50, 51, 52] and first["parent"]["vertex_ids"] == [52, 53]
    assert first["parent"]["largest_displacement"] == 4.0 and first["child"]["largest_displacement"] == 5.0
    merge = tgsis.object_merge(conn, "e1", fault)
    assert first["bounds"] == merge.regions[0].bounds.tolist()
    assert (second["conflict"], second["changed_in"]) == (False, "child")
    assert second["child"]["vertex_ids"] == SOUTH.tolist()
    assert "regions" not in json.loads(_cli(db_dsn, capsys, "version", "conflicts", "e1", "--json"))["conflicts"][0]


@pytest.mark.usefixtures("cli_state")
def test_cli_regions_of_disjoint_edits(conn: Conn, fault: int, db_dsn: str, capsys: pytest.CaptureFixture[str]) -> None:
    """An object-level conflict today whose edits are apart: the CLI says it merges by itself."""
    move(conn, "e1", fault, [5], (0.0, 0.0, 1.0))
    move(conn, "DEFAULT", fault, [100], (0.0, 0.0, 1.0))
    conn.commit()
    text = _cli(db_dsn, capsys, "version", "conflicts", "e1", "--regions")
    assert "\tregions\t2 region(s), 0 in conflict: the object merges by itself" in text.splitlines()


@pytest.mark.usefixtures("cli_state")
def test_cli_regions_for_a_role_without_rights_is_the_permission_error(
    conn: Conn, fault: int, db_dsn: str, capsys: pytest.CaptureFixture[str]
) -> None:
    """No table of conflicts without the regions: the command fails as a whole."""
    move(conn, "e1", fault, NORTH, (0.0, 0.0, 3.0))
    move(conn, "DEFAULT", fault, SOUTH, (0.0, 0.0, -3.0))
    conn.execute("REVOKE SELECT ON public.faults FROM tgsis_reader")
    conn.commit()
    with login_roles(db_dsn, {"rita": "tgsis_reader"}) as made:
        rita_dsn = make_conninfo(db_dsn, user=made.name("rita"))
        assert main(["--dsn", rita_dsn, "version", "conflicts", "e1", "--regions"]) != 0
        captured = capsys.readouterr()
        assert captured.out == "" and "permission denied" in captured.err and "faults" in captured.err
        assert "feature" in _cli(rita_dsn, capsys, "version", "conflicts", "e1")  # the list without regions stays hers


def _fault_with_status(conn: Conn) -> int:
    """A curved surface of class 'faults' with a feature attribute 'status' = 'a' in DEFAULT; version e1 based on it."""
    F.create_feature_class(
        conn, "faults", "SURFACE", feature_properties=[("status", "text")], cell_properties=[("porosity", "float8")]
    )
    tgsis.enable_feature_versioning(conn)
    surface = curved_surface()
    plain = tgsis.Surface(surface.vertices, surface.cells, vertex_properties=dict(surface.vertex_properties))
    geoid = F.insert_feature(conn, "faults", plain, {"status": "a"})
    tgsis.create_version(conn, "e1")
    conn.commit()
    return geoid


def _set_status(conn: Conn, version: str, geoid: int, status: str) -> None:
    with tgsis.in_version(conn, version):
        conn.execute("UPDATE faults SET status = %s WHERE _geoid = %s", (status, geoid))
    conn.commit()


def test_a_feature_deleted_in_the_parent_is_no_merge_to_an_empty_mesh(conn: Conn) -> None:
    # was: no conflict and merged = a mesh without rows, while the version edited the feature the parent deleted
    geoid = _fault_with_status(conn)
    _set_status(conn, "e1", geoid, "b")
    with tgsis.in_version(conn, "DEFAULT"):
        F.delete_feature(conn, "faults", geoid)
    conn.commit()
    with pytest.raises(
        tgsis.InvalidInputError, match=rf"feature {geoid} of class faults was deleted in version DEFAULT"
    ):
        tgsis.object_merge(conn, "e1", geoid)
    move(conn, "e1", geoid, NORTH, (0.0, 0.0, 3.0))  # a geometry edit too: refused the same way
    with pytest.raises(tgsis.InvalidInputError, match="was deleted in version DEFAULT"):
        tgsis.object_merge(conn, "e1", geoid)


def test_a_feature_deleted_in_the_version_is_named_as_deleted(conn: Conn) -> None:
    # was: NotFoundError "no feature class has feature", for a conflict find_conflicts lists
    geoid = _fault_with_status(conn)
    move(conn, "DEFAULT", geoid, SOUTH, (0.0, 0.0, -3.0))
    with tgsis.in_version(conn, "e1"):
        F.delete_feature(conn, "faults", geoid)
    conn.commit()
    assert [c.objectkey for c in tgsis.find_conflicts(conn, "e1")] == [str(geoid)]
    with pytest.raises(tgsis.InvalidInputError, match=rf"feature {geoid} of class faults was deleted in version e1"):
        tgsis.object_merge(conn, "e1", geoid)


def test_feature_attributes_changed_on_both_sides_are_no_clean_merge(conn: Conn) -> None:
    # was: regions () and a merged mesh: the conflict (status 'b' against 'c') silently left out
    geoid = _fault_with_status(conn)
    _set_status(conn, "e1", geoid, "b")
    _set_status(conn, "DEFAULT", geoid, "c")
    with pytest.raises(tgsis.InvalidInputError, match=rf"feature {geoid} of class faults: its attributes .*status"):
        tgsis.object_merge(conn, "e1", geoid)
    _set_status(conn, "DEFAULT", geoid, "b")  # the same change on both sides: nothing to decide
    move(conn, "e1", geoid, NORTH, (0.0, 0.0, 3.0))
    move(conn, "DEFAULT", geoid, SOUTH, (0.0, 0.0, -3.0))
    merge = tgsis.object_merge(conn, "e1", geoid)
    assert merge.conflicts == () and merge.merged is not None
    _set_status(conn, "DEFAULT", geoid, "a")  # changed back in the parent only: the version's change stands
    assert tgsis.object_merge(conn, "e1", geoid).conflicts == ()


def test_a_class_in_a_schema_the_role_may_not_use_does_not_refuse_another_class(
    conn: Conn, fault: int, db_dsn: str
) -> None:
    # was: permission denied for schema vault (the search for the feature's class named every class's table)
    move(conn, "e1", fault, NORTH, (0.0, 0.0, 3.0))
    move(conn, "DEFAULT", fault, SOUTH, (0.0, 0.0, -3.0))
    conn.execute("CREATE SCHEMA vault")
    F.create_feature_class(conn, "vaulted", "SURFACE", schema="vault")
    conn.execute("REVOKE ALL ON SCHEMA vault FROM PUBLIC, tgsis_reader")
    conn.commit()
    with login_roles(db_dsn, {"rita": "tgsis_reader"}) as made:
        rita = made.connect("rita")
        assert rita.execute("SELECT has_schema_privilege('vault', 'USAGE')").fetchone() == (False,)
        rita.rollback()
        assert tgsis.object_merge(rita, "e1", fault).conflicts == ()
