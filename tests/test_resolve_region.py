"""Solutions per region (issue 39 items 3, 4): tgsis.resolve_region, region_solutions, and what resolve_conflict refuses.

The fault of tests/test_conflict_regions.py: north end moved in e1, south end
in DEFAULT, a middle patch on both sides to other places (the one conflict).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt
import psycopg
import pytest

import tgsis
from tests.merge_data import SIDE, curved_surface
from tests.roles import login_roles
from tests.storage_data import storage_of
from tests.test_conflict_regions import MIDDLE, NORTH, SOUTH, by_side, everything, stored
from tgsis import formats
from tgsis.cli import main
from tgsis.db import regions as R
from tgsis.errors import InvalidInputError, MissingPrivilegeError, NotFoundError, RegionSolutionError
from tgsis.merge3 import MeshState, apply_solutions

Conn = psycopg.Connection[Any]


@pytest.fixture
def fault(conn: Conn, three_regions_clone: int) -> int:
    return three_regions_clone  # three_regions's, built once (tests/conftest.py)


def _middle(conn: Conn) -> R.ConflictRegion:
    [conflict] = tgsis.find_conflicts(conn, "e1")
    return by_side(conflict.regions)["both"]


def _merge(conn: Conn, fault: int) -> Any:
    return tgsis.object_merge(conn, "e1", fault)


def _solutions(conn: Conn, fault: int) -> tuple[Any, dict[int, Any]]:
    merge = _merge(conn, fault)
    with conn.transaction():
        solutions = R.region_solutions(conn, "e1", "feature", str(fault), merge)
    conn.commit()
    return merge, solutions


@pytest.mark.parametrize("solution", ["parent", "child", "base"])
def test_a_side_solution_is_recorded_with_what_it_discards(conn: Conn, fault: int, solution: str) -> None:
    middle = _middle(conn)
    result = tgsis.resolve_region(conn, "e1", fault, middle.region, solution)
    assert result.region.solution == solution and result.region.solved_by is not None
    lost = {d.side: d for d in result.discards}
    expected_sides = {"parent": {"child"}, "child": {"parent"}, "base": {"parent", "child"}}[solution]
    assert set(lost) == expected_sides
    for side in expected_sides:
        assert lost[side].vertices == len(MIDDLE)
        assert lost[side].max_displacement == pytest.approx(
            {"parent": 7.0, "child": 5.0}[side] + (0.0 if solution == "base" else {"parent": 5.0, "child": 7.0}[side])
        )
    merge, solutions = _solutions(conn, fault)
    assert solutions == {middle.region: solution}
    state = apply_solutions(merge, solutions).state  # the merge the apply engineer makes of it
    source = {"parent": merge.parent, "child": merge.child, "base": merge.base}[solution]
    at = np.searchsorted(state.vertex_ids, MIDDLE)
    assert state.vertices[at].tobytes() == source.vertices[np.searchsorted(source.vertex_ids, MIDDLE)].tobytes()
    north = np.searchsorted(state.vertex_ids, NORTH)  # the automatic regions merge as ever
    assert (
        state.vertices[north].tobytes()
        == merge.child.vertices[np.searchsorted(merge.child.vertex_ids, NORTH)].tobytes()
    )


def test_region_solutions_are_empty_for_a_merge_of_other_states(conn: Conn, fault: int) -> None:
    middle = _middle(conn)
    tgsis.resolve_region(conn, "e1", fault, middle.region, "child")
    old_merge = _merge(conn, fault)
    from tests.merge_data import move

    move(conn, "e1", fault, [70], (0.0, 0.0, 0.25))  # the marks change: the recorded solution no longer holds
    conn.commit()
    new_merge = _merge(conn, fault)
    with conn.transaction():
        assert R.region_solutions(conn, "e1", "feature", str(fault), old_merge) == {}
        assert R.region_solutions(conn, "e1", "feature", str(fault), new_merge) == {}


def test_average_is_a_valid_mesh_attached_to_the_unchanged_rest(conn: Conn, fault: int) -> None:
    middle = _middle(conn)
    result = tgsis.resolve_region(conn, "e1", fault, middle.region, "average")
    assert result.region.solution == "average" and result.state is not None
    assert {d.side for d in result.discards} == {"parent", "child"}
    merge, solutions = _solutions(conn, fault)
    assert isinstance(solutions[middle.region], MeshState)
    resolved = apply_solutions(merge, solutions)
    state = resolved.state
    state.to_mesh()  # a valid mesh: every cell on vertices it has
    assert state.n_vertices == SIDE * SIDE and state.n_cells == curved_surface().n_cells
    region = set(middle.vertex_ids.tolist())
    rest = np.array([i for i in state.vertex_ids.tolist() if i not in region and i not in set(NORTH.tolist())])
    at, at_p = np.searchsorted(state.vertex_ids, rest), np.searchsorted(merge.parent.vertex_ids, rest)
    assert state.vertices[at].tobytes() == merge.parent.vertices[at_p].tobytes()  # the rest bit for bit
    pz = merge.parent.vertices[np.searchsorted(merge.parent.vertex_ids, MIDDLE), 2]
    cz = merge.child.vertices[np.searchsorted(merge.child.vertex_ids, MIDDLE), 2]
    z = state.vertices[np.searchsorted(state.vertex_ids, MIDDLE), 2]
    assert np.all((z > np.minimum(pz, cz)) & (z < np.maximum(pz, cz)))  # between the two sides
    np.testing.assert_allclose(z, (pz + cz) / 2)
    margin = np.setdiff1d(middle.vertex_ids, MIDDLE)  # the region's vertices shared with the rest stay put
    at_m = np.searchsorted(state.vertex_ids, margin)
    assert (
        state.vertices[at_m].tobytes() == merge.base.vertices[np.searchsorted(merge.base.vertex_ids, margin)].tobytes()
    )
    assert {c.tolist().__len__() for c in state.cells} == {3}


def _refused(conn: Conn, fault: int, error: type[Exception], match: str, *args: Any, **kwargs: Any) -> None:
    before = everything(conn)
    with pytest.raises(error, match=match):
        tgsis.resolve_region(conn, "e1", fault, *args, **kwargs)
    conn.rollback()
    assert everything(conn) == before


def test_every_refusal_leaves_the_database_unchanged(conn: Conn, fault: int) -> None:
    middle = _middle(conn)
    automatic = next(r for r in tgsis.find_conflicts(conn, "e1")[0].regions if not r.conflict)
    _refused(conn, fault, RegionSolutionError, "not a conflict", automatic.region, "child")
    _refused(conn, fault, InvalidInputError, "not parent, child", middle.region, "theirs")
    _refused(conn, fault, InvalidInputError, "automatic", middle.region, "automatic")
    _refused(conn, fault, InvalidInputError, "takes no mesh", middle.region, "parent", mesh=_merge(conn, fault).child)
    _refused(conn, fault, InvalidInputError, "needs the region's mesh", middle.region, "manual")
    _refused(conn, fault, NotFoundError, "not a stored region", 99, "child")
    _refused(conn, fault, RegionSolutionError, "discards", middle.region, "child", discard_other=False)
    # a manual mesh that edits outside the region
    child = _merge(conn, fault).child
    edited = child.vertices.copy()
    edited[np.searchsorted(child.vertex_ids, SOUTH[0]), 2] += 40.0
    wrong = MeshState(
        3, child.vertex_ids, edited, child.cell_ids, child.cells, child.vertex_properties, child.cell_properties
    )
    _refused(conn, fault, InvalidInputError, "outside the region", middle.region, "manual", mesh=wrong)
    # stale: either side changed the object since the regions were found
    from tests.merge_data import move

    move(conn, "DEFAULT", fault, [70], (0.0, 0.0, 0.25))
    conn.commit()
    _refused(conn, fault, RegionSolutionError, "changed since", middle.region, "child")


def test_the_sql_face_refuses_with_our_sqlstates(conn: Conn, fault: int) -> None:
    middle = _middle(conn)
    automatic = next(r for r in tgsis.find_conflicts(conn, "e1")[0].regions if not r.conflict)
    before = stored(conn)
    cases = [
        ((automatic.region, "child", None), "TG307", "merges by itself"),
        ((middle.region, "child", b"PK\x03\x04"), "TG100", "takes no mesh"),
        ((middle.region, "manual", None), "TG100", "needs the region's mesh"),
        ((middle.region, "manual", b"not a zip"), "TG100", "no .npz"),
        ((middle.region, "automatic", None), "TG100", "is not parent"),
        ((42, "child", None), "TG200", "not a stored region"),
    ]
    for (region, solution, mesh), state, said in cases:
        with pytest.raises(psycopg.Error) as caught:
            conn.execute(
                "SELECT tgsis.resolve_region('e1', 'feature', %s, %s, %s, %s)", (str(fault), region, solution, mesh)
            )
        conn.rollback()
        assert caught.value.sqlstate == state and said in str(caught.value.diag.message_primary), str(caught.value)
        assert f"region {region}" in str(caught.value.diag.message_primary) or state == "TG100"
    assert stored(conn) == before


def test_resolve_conflict_refuses_a_side_that_drops_edits_outside_the_conflicts(conn: Conn, fault: int) -> None:
    tgsis.find_conflicts(conn, "e1")
    before = stored(conn)
    for solution, lost in (("parent", "version's"), ("child", "parent's")):
        with pytest.raises(psycopg.Error) as caught:
            conn.execute("SELECT tgsis.resolve_conflict('e1', 'feature', %s, %s)", (str(fault), solution))
        conn.rollback()
        error = caught.value
        assert error.sqlstate == "TG307" and lost in str(error.diag.message_primary)
        assert "tgsis.resolve_region" in str(error.diag.message_hint)
        with pytest.raises(RegionSolutionError):
            tgsis.resolve_conflict(conn, "e1", "feature", fault, solution)
        conn.rollback()
    assert stored(conn) == before
    assert conn.execute("SELECT solution FROM tgsis.conflicts").fetchall() == [("unsolved",)]
    conn.rollback()
    tgsis.resolve_conflict(conn, "e1", "feature", fault, "manual")  # manual stays allowed
    conn.commit()
    assert conn.execute("SELECT solution FROM tgsis.conflicts").fetchall() == [("manual",)]


def test_a_role_without_rights_gets_the_permission_error(db_dsn: str, conn: Conn, fault: int) -> None:
    middle = _middle(conn)
    before = stored(conn)
    with login_roles(db_dsn, {"reader": "tgsis_reader"}) as roles:
        reader = roles.connect("reader")
        with pytest.raises(MissingPrivilegeError, match="resolve conflicts"):
            tgsis.resolve_region(reader, "e1", fault, middle.region, "child")
        reader.rollback()
        with pytest.raises(psycopg.Error) as caught:
            reader.execute("SELECT tgsis.resolve_region('e1', 'feature', %s, %s, 'child')", (str(fault), middle.region))
        assert caught.value.sqlstate == "TG002"
    assert stored(conn) == before


def test_manual_through_the_command_line_from_an_exported_file(
    conn: Conn, db_dsn: str, fault: int, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    middle = _middle(conn)
    assert main(["--dsn", db_dsn, "version", "conflicts", "e1", "--export", str(tmp_path)]) == 0
    [child_file] = tmp_path.glob(f"{fault}_*_child.ts")
    mesh = formats.read_one(child_file)
    ids = np.asarray(mesh.vertex_properties["vrtxid"]).astype(np.int64)
    at = np.flatnonzero(np.isin(ids, MIDDLE))
    vertices = mesh.vertices.copy()
    vertices[at, 2] = 111.25  # the geologist's own choice, made in GOCAD
    edited = type(mesh)(
        vertices, mesh.cells, vertex_properties=mesh.vertex_properties, name=mesh.name, metadata=mesh.metadata
    )
    edited_file = tmp_path / "edited.ts"
    formats.write(edited, edited_file)
    capsys.readouterr()
    args = [
        "--dsn",
        db_dsn,
        "version",
        "resolve",
        "e1",
        str(fault),
        "manual",
        "--region",
        str(middle.region),
        "--mesh",
        str(edited_file),
    ]
    assert main(args) == 1  # it discards both sides' edits there: refused without --discard-other
    err = capsys.readouterr().err
    assert "discards" in err and "--discard-other" in err
    assert main([*args, "--discard-other"]) == 0
    said = capsys.readouterr().out
    assert said.index("discards") < said.index("recorded")
    merge, solutions = _solutions(conn, fault)
    state = apply_solutions(merge, solutions).state
    z = state.vertices[np.searchsorted(state.vertex_ids, MIDDLE), 2]
    assert np.all(z == 111.25)
    # the regions of the command line say the solution; so does the JSON
    assert main(["--dsn", db_dsn, "version", "conflicts", "e1", "--regions"]) == 0
    [line] = [x for x in capsys.readouterr().out.splitlines() if x.startswith(f"\tregion {middle.region}\t")]
    assert line.endswith("\tsolution manual")
    assert main(["--dsn", db_dsn, "version", "conflicts", "e1", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    [region] = [r for r in data["conflicts"][0]["conflict_regions"] if r["conflict"]]
    assert region["solution"] == "manual" and region["child"]["vertex_ids"] == MIDDLE.tolist()
    assert len(region["bbox"]) == 6


def test_a_manual_mesh_may_remesh_the_region_with_new_ids(conn: Conn, fault: int) -> None:
    middle = _middle(conn)
    child = _merge(conn, fault).child
    inside = set(middle.vertex_ids.tolist())
    at = next(
        i
        for i, cid in enumerate(child.cell_ids.tolist())
        if cid in set(middle.cell_ids.tolist()) and set(child.cells[i].tolist()) <= inside
    )
    a, b, c = child.cells[at].tolist()
    new_v = int(child.vertex_ids.max()) + 1
    new_c = int(child.cell_ids.max()) + 1
    centre = child.vertices[np.searchsorted(child.vertex_ids, [a, b, c])].mean(axis=0) + [0.0, 0.0, 2.5]
    cells = child.cells.copy()
    cells[at] = [a, b, new_v]
    remeshed = MeshState(
        3,
        np.append(child.vertex_ids, new_v),
        np.vstack([child.vertices, centre]),
        np.append(child.cell_ids, [new_c, new_c + 1]),
        np.vstack([cells, [[b, c, new_v], [c, a, new_v]]]),
        {n: np.append(v, 0.2) for n, v in child.vertex_properties.items()},
        {n: np.append(v, [1, 1]).astype(v.dtype) for n, v in child.cell_properties.items()},
    )
    result = tgsis.resolve_region(conn, "e1", fault, middle.region, "manual", remeshed)
    assert result.region.solution == "manual"
    merge, solutions = _solutions(conn, fault)
    state = apply_solutions(merge, solutions).state
    mesh = state.to_mesh()  # valid: no dangling vertex, every cell on vertices it has
    assert new_v in state.vertex_ids and mesh.n_cells == curved_surface().n_cells + 2
    np.testing.assert_array_equal(state.vertices[np.searchsorted(state.vertex_ids, new_v)], centre)
    south = np.searchsorted(state.vertex_ids, SOUTH)  # the parent's edit elsewhere is kept
    assert (
        state.vertices[south].tobytes()
        == merge.parent.vertices[np.searchsorted(merge.parent.vertex_ids, SOUTH)].tobytes()
    )


def test_average_of_sides_that_meshed_the_region_differently_and_of_one_meshing() -> None:
    from tgsis.merge3 import three_way_merge

    surface = curved_surface()
    base = MeshState.from_mesh(surface)
    middle = 5 * SIDE + 5
    moved = base.vertices.copy()
    moved[middle, 2] += 4.0
    parent = MeshState(
        3, base.vertex_ids, moved, base.cell_ids, base.cells, base.vertex_properties, base.cell_properties
    )
    # the child moves it the other way and splits a triangle on it with a new vertex
    at = int(np.flatnonzero((base.cells == middle).any(axis=1))[0])
    a, b, c = base.cells[at].tolist()
    other = base.vertices.copy()
    other[middle, 2] -= 4.0
    new_v, new_c = base.n_vertices, base.n_cells
    cells = base.cells.copy()
    cells[at] = [a, b, new_v]
    child = MeshState(
        3,
        np.append(base.vertex_ids, new_v),
        np.vstack([other, other[[a, b, c]].mean(axis=0)]),
        np.append(base.cell_ids, [new_c, new_c + 1]),
        np.vstack([cells, [[b, c, new_v], [c, a, new_v]]]),
        {n: np.append(v, 0.2) for n, v in base.vertex_properties.items()},
        {n: np.append(v, [1, 1]).astype(v.dtype) for n, v in base.cell_properties.items()},
    )
    merge = three_way_merge(base, parent, child)
    [region] = merge.conflicts
    # the average shape of the two meshings (tests/test_merge_average.py): the version's finer meshing, a valid merge
    remeshed = R.average_region(merge, region)
    assert new_v in remeshed.vertex_ids and np.isin(remeshed.cell_ids, child.cell_ids).all()
    z = remeshed.vertices[np.searchsorted(remeshed.vertex_ids, middle), 2]
    assert abs(z - base.vertices[middle, 2]) < 1.0  # +4 and -4, about the middle
    apply_solutions(merge, {region.index: remeshed}).state.to_mesh()
    # one meshing on both sides: the middle of the two positions, the margin put
    same = MeshState(3, base.vertex_ids, other, base.cell_ids, base.cells, base.vertex_properties, base.cell_properties)
    merge = three_way_merge(base, parent, same)
    [region] = merge.conflicts
    average = R.average_region(merge, region)
    z = average.vertices[np.searchsorted(average.vertex_ids, middle), 2]
    assert z == base.vertices[middle, 2]  # +4 and -4: back in the middle
    resolved = apply_solutions(merge, {region.index: average}).state
    resolved.to_mesh()


def test_a_file_with_a_vertex_added_in_paraview_gives_new_ids(conn: Conn, fault: int, tmp_path: Path) -> None:
    """An exported VTU edited in ParaView: a vertex added (no vrtxid: NaN) splits a triangle of the region."""
    middle = _middle(conn)
    assert (
        main(["--dsn", str(conn.info.dsn), "version", "conflicts", "e1", "--export", str(tmp_path), "--format", "vtu"])
        == 0
    )
    [child_file] = tmp_path.glob(f"{fault}_*_child.vtu")
    mesh = formats.read_one(child_file)
    ids = np.asarray(mesh.vertex_properties["vrtxid"], dtype=np.float64)
    inside = set(middle.vertex_ids.tolist())
    row = next(i for i, cell in enumerate(mesh.cells.tolist()) if {int(ids[v]) for v in cell} <= inside)
    a, b, c = mesh.cells[row].tolist()
    n = mesh.n_vertices
    vertices = np.vstack([mesh.vertices, mesh.vertices[[a, b, c]].mean(axis=0)])
    cells = np.vstack([np.delete(mesh.cells, row, axis=0), [[a, b, n], [b, c, n], [c, a, n]]])
    props = {k: np.append(np.asarray(v, dtype=np.float64), np.nan) for k, v in mesh.vertex_properties.items()}
    edited = tgsis.Surface(vertices, cells, vertex_properties=props, name=mesh.name)
    result = tgsis.resolve_region(conn, "e1", fault, middle.region, "manual", edited)
    assert result.state is not None
    merge, solutions = _solutions(conn, fault)
    state = apply_solutions(merge, solutions).state
    state.to_mesh()
    top = max(int(s.vertex_ids.max()) for s in (merge.base, merge.parent, merge.child))
    assert state.n_vertices == SIDE * SIDE + 1 and int(state.vertex_ids.max()) == top + 1  # a fresh id
    assert state.n_cells == curved_surface().n_cells + 2
    kept = set(state.cell_ids.tolist()) & set(merge.child.cell_ids.tolist())
    assert len(kept) == merge.child.n_cells - 1  # the other cells kept their ids; the split one became three new


def test_a_role_that_may_not_read_the_class_reads_nothing_of_its_regions(db_dsn: str, conn: Conn, fault: int) -> None:
    """The regions hold ids, boxes, displacements and (average, manual) the rows of a mesh: no more readable than
    the mesh's own rows (tgsis.vrtx, per-class row security)."""
    middle = _middle(conn)
    tgsis.resolve_region(conn, "e1", fault, middle.region, "average")
    conn.execute("REVOKE SELECT ON public.faults FROM tgsis_reader")
    storage = storage_of(conn, "vrtx")  # <table>_ver or the chunk table: the class's row security on either
    conn.commit()
    with login_roles(db_dsn, {"reader": "tgsis_reader"}) as roles:
        reader = roles.connect("reader")
        assert reader.execute(f"SELECT count(*) FROM {storage} WHERE geoid = %s", (fault,)).fetchone() == (0,)
        assert reader.execute("SELECT count(*) FROM tgsis.vrtx WHERE geoid = %s", (fault,)).fetchone() == (0,)
        rows = reader.execute(
            "SELECT bbox, parent_displacement, solution_mesh FROM tgsis.conflict_regions WHERE objectkey = %s",
            (str(fault),),
        ).fetchall()
        assert rows == []
        assert reader.execute("SELECT count(*) FROM tgsis.conflicts").fetchone() == (1,)  # that it conflicts
    # the roles that may read the class still read them
    assert len(conn.execute("SELECT * FROM tgsis.conflict_regions").fetchall()) == 3


def test_ids_a_tool_rewrote_as_float32_beyond_exact_integers_are_refused(
    conn: Conn, fault: int, tmp_path: Path
) -> None:
    """float32 holds integers exactly only up to 2**24: above, a vrtxid may name a neighbour's vertex."""
    middle = _middle(conn)
    assert (
        main(["--dsn", str(conn.info.dsn), "version", "conflicts", "e1", "--export", str(tmp_path), "--format", "vtu"])
        == 0
    )
    [child_file] = tmp_path.glob(f"{fault}_*_child.vtu")
    mesh = formats.read_one(child_file)
    ids = np.asarray(mesh.vertex_properties["vrtxid"], dtype=np.float32)
    tgsis.resolve_region(  # float32 ids below 2**24 are exact: accepted
        conn, "e1", fault, middle.region, "manual", _with_ids(mesh, ids)
    )
    big = ids.copy()
    big[-1] = np.float32(2**24 + 2)  # was: matched as if exact (any of 2**24 + 1 .. 2**24 + 3 reads so)
    with pytest.raises(tgsis.InvalidInputError, match=r"vrtxid.*float32.*16777216"):
        tgsis.resolve_region(conn, "e1", fault, middle.region, "manual", _with_ids(mesh, big))


def _with_ids(mesh: tgsis.Mesh, ids: npt.NDArray[Any]) -> tgsis.Surface:
    return tgsis.Surface(
        mesh.vertices, mesh.cells, vertex_properties={**mesh.vertex_properties, "vrtxid": ids}, name=mesh.name
    )
