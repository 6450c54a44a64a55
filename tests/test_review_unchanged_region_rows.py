"""Hostile review (issue 39): the psql merge of ``average`` / ``manual`` rows of region vertices no side changed.

The psql merge now writes such rows as the Python merge writes them (the
base's row closed, the solution's written, one the solution lacks removed).
These cases go where its tests did not: GOCAD atoms on and to such a vertex,
one removed with all its cells, integer and NaN property values, and
tetrahedra and lines (not only triangles). Each must merge in psql exactly
as in Python (the oracle, tests/test_sql_merge_write.py) or be refused alike.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import psycopg
import pytest

import tgsis
from tests.merge_data import move
from tests.test_sql_merge_average import _both_moved, _record_in_sql
from tests.test_sql_merge_regions import MIDDLE, psql
from tests.test_sql_merge_solutions_hostile import _conflict, _margin_vertex, _replace
from tests.test_sql_merge_write import assert_same_merge, both_merges
from tgsis.db import features as F
from tgsis.merge3 import restrict_state

Conn = psycopg.Connection[Any]

ATOM = "INSERT INTO tgsis.atom (geoid, vrtxid, refid, patom) VALUES (%s, %s, %s, %s)"


@pytest.fixture
def fault(conn: Conn, fault_clone: int) -> int:
    return fault_clone  # tests.merge_data.make_fault's (tests/conftest.py)


def _atoms_in_base(conn: Conn, fault: int, *atoms: tuple[int, int, bool]) -> None:
    """GOCAD atoms stored in DEFAULT, version e1 made again on it (so the base has them)."""
    for vrtxid, refid, patom in atoms:
        psql(conn, "DEFAULT", (ATOM, (fault, vrtxid, refid, patom)))
    conn.execute("SELECT tgsis.merge_version('e1', true)")
    conn.commit()
    tgsis.create_version(conn, "e1")
    conn.commit()


def _same_or_refused_alike(conn: Conn, action: str = "merge") -> None:
    theirs, mine = both_merges(conn, "e1", action)
    if theirs[0] == "refused":
        assert mine[0] == "refused", (theirs[:2], mine[:2])
        return
    assert mine[0] == "done", mine
    assert mine[1] == theirs[1]
    for table in theirs[2]:
        assert mine[2][table] == theirs[2][table], table


# --------------------------------------------------------------------------- atoms on and to such a vertex


@pytest.mark.parametrize("how", ["dropped", "moved", "retargeted"])
def test_an_atom_on_a_region_vertex_no_side_changed_merges_as_in_python(conn: Conn, fault: int, how: str) -> None:
    """The margin vertex 52 or 53 is a GOCAD atom in the base; the manual rows drop its atom (refid -1), move
    it, or point it elsewhere: the base's atom row closed as Python closes it."""
    _atoms_in_base(conn, fault, (52, 0, False), (53, 1, True))
    index, merge = _conflict(conn, fault, hole=True)
    vertex = _margin_vertex(merge)
    side = merge.child
    refid = np.asarray(side.vertex_properties["refid"], dtype=np.float64).copy()
    refid[np.searchsorted(side.vertex_ids, vertex)] = {"dropped": -1, "moved": 0, "retargeted": 2}[how]
    xyz = side.vertices.copy()
    if how == "moved":
        xyz[np.searchsorted(side.vertex_ids, vertex), 2] += 0.25
    props = {**side.vertex_properties, "refid": refid}
    _record_in_sql(conn, fault, index, _replace(side, vertices=xyz, vertex_properties=props))
    _same_or_refused_alike(conn)


def test_an_atom_to_a_region_vertex_no_side_changed_that_moves_merges_as_in_python(conn: Conn, fault: int) -> None:
    """Vertex 0 (outside the region, unchanged) is an atom of margin vertex 52/53, which the manual rows move."""
    _atoms_in_base(conn, fault, (0, 52, True), (1, 53, False))
    index, merge = _conflict(conn, fault, hole=True)
    vertex = _margin_vertex(merge)
    xyz = merge.child.vertices.copy()
    xyz[np.searchsorted(merge.child.vertex_ids, vertex), 2] += 0.25
    _record_in_sql(conn, fault, index, _replace(merge.child, vertices=xyz))
    assert_same_merge(conn, "e1")
    assert_same_merge(conn, "e1", "refresh")


# --------------------------------------------------------------------------- a vertex removed with all its cells


def _isolated(conn: Conn, fault: int) -> tuple[int, Any, int]:
    """The version removes every triangle on vertex ``x`` (beside the middle both sides move), keeping the vertex:
    x is then in the region, no side changed its row, and no cell uses it. (region index, merge, x)."""
    x = int(MIDDLE[0]) - 1
    psql(
        conn,
        "e1",
        ("DELETE FROM tgsis.trgl WHERE geoid = %s AND %s IN (vrtxid1, vrtxid2, vrtxid3)", (fault, x)),
    )
    index = _both_moved(conn, fault)
    merge = tgsis.object_merge(conn, "e1", fault)
    conn.rollback()
    (region,) = merge.conflicts
    assert x in region.vertex_ids.tolist()
    assert x not in np.union1d(region.parent_vertex_ids, region.child_vertex_ids).tolist()
    return index, merge, x


@pytest.mark.parametrize("atom", ["none", "on it", "to it"])
def test_rows_removing_a_cell_less_region_vertex_no_side_changed_merge_or_refuse_as_in_python(
    conn: Conn, fault: int, atom: str
) -> None:
    if atom == "on it":
        _atoms_in_base(conn, fault, (int(MIDDLE[0]) - 1, 0, False))
    elif atom == "to it":
        _atoms_in_base(conn, fault, (0, int(MIDDLE[0]) - 1, True))
    index, merge, x = _isolated(conn, fault)
    (region,) = merge.conflicts
    side = merge.child
    cells = region.cell_ids[np.isin(region.cell_ids, side.cell_ids)]
    corners = side.cells[np.searchsorted(side.cell_ids, cells)].ravel()
    state = restrict_state(side, np.setdiff1d(np.union1d(region.vertex_ids, corners), [x]), cells)
    _record_in_sql(conn, fault, index, state)
    _same_or_refused_alike(conn)
    _same_or_refused_alike(conn, "refresh")


# --------------------------------------------------------------------------- values: integer, real, NaN


@pytest.mark.parametrize("value", ["same", "nan", "integer"])
def test_values_of_a_region_vertex_no_side_changed_merge_as_in_python(conn: Conn, value: str) -> None:
    """A class with an integer and a real vertex property; the base holds NULL (NaN) for the margin vertex."""
    F.create_feature_class(
        conn,
        "faults",
        "SURFACE",
        cell_properties=[
            tgsis.Property("grade", "int", alignment="VERTEX"),
            tgsis.Property("density", "real", alignment="VERTEX"),
        ],
    )
    tgsis.enable_feature_versioning(conn)
    from tests.merge_data import curved_surface

    surface = curved_surface()
    n = len(surface.vertices)
    surface = tgsis.Surface(
        surface.vertices,
        surface.cells,
        vertex_properties={
            "grade": np.arange(n, dtype=np.int64) * 3,
            "density": np.where(np.isin(np.arange(n), [52, 53]), np.nan, np.linspace(1.0, 2.0, n)),
        },
    )
    geoid = F.insert_feature(conn, "faults", surface)
    tgsis.create_version(conn, "e1")
    conn.commit()
    index, merge = _conflict(conn, geoid, hole=True)
    vertex = _margin_vertex(merge)
    side = merge.child
    at = np.searchsorted(side.vertex_ids, vertex)
    props = {k: np.asarray(v, dtype=np.float64).copy() for k, v in side.vertex_properties.items()}
    if value == "nan":
        props["density"][at] = np.nan
    elif value == "integer":
        props["grade"][at] = 7.0
    xyz = side.vertices.copy()
    if value == "same":
        xyz[at, 2] += 0.125  # moved, values as the base's
    _record_in_sql(conn, geoid, index, _replace(side, vertices=xyz, vertex_properties=props))
    assert_same_merge(conn, "e1")


# --------------------------------------------------------------------------- tetrahedra and lines


@pytest.mark.parametrize("geotype", ["MULTILINESTRING", "MULTITETRA"])
@pytest.mark.parametrize("solution", ["manual"])  # (average: refused for two meshings but triangles)
def test_solids_and_lines_with_region_vertices_no_side_changed_merge_as_in_python(
    conn: Conn, geotype: str, solution: str
) -> None:
    from tests.test_object_merge import _other_kind

    tgsis.create_feature_class(conn, "bodies", geotype)
    tgsis.enable_feature_versioning(conn)
    mesh = _other_kind(geotype)
    geoid = tgsis.insert_feature(conn, "bodies", mesh)
    tgsis.create_version(conn, "e1")
    conn.commit()
    table, key = {"MULTILINESTRING": ("segment", "segid"), "MULTITETRA": ("tetra", "tetraid")}[geotype]
    psql(conn, "e1", (f"DELETE FROM tgsis.{table} WHERE geoid = %s AND {key} = 21", (geoid,)))
    move(conn, "e1", geoid, range(18, 22), (0.0, 0.0, 5.0))
    move(conn, "DEFAULT", geoid, range(18, 22), (0.5, 0.0, -7.0))
    conn.commit()
    (conflict,) = tgsis.find_conflicts(conn, "e1")
    conn.commit()
    regions = [r for r in conflict.regions if r.conflict]
    merge = tgsis.object_merge(conn, "e1", geoid)
    conn.rollback()
    for region in merge.conflicts:
        unchanged = np.setdiff1d(region.vertex_ids, np.union1d(region.parent_vertex_ids, region.child_vertex_ids))
        assert len(unchanged) > 0, region
        if solution == "average":
            tgsis.resolve_region(conn, "e1", geoid, region.index, "average")
        else:
            side = merge.child
            xyz = side.vertices.copy()
            xyz[np.isin(side.vertex_ids, unchanged), 2] += 0.375
            _record_in_sql_k(conn, geoid, region.index, _replace(side, vertices=xyz))
        conn.commit()
    assert regions
    assert_same_merge(conn, "e1")
    assert_same_merge(conn, "e1", "refresh")


def _record_in_sql_k(conn: Conn, geoid: int, index: int, state: Any) -> None:
    _record_in_sql(conn, geoid, index, state)


# --------------------------------------------------------------------------- an atom left on a removed vertex


def _atoms_and_vertex(conn: Conn, fault: int, x: int) -> tuple[list[Any], Any]:
    atoms = conn.execute("SELECT vrtxid, refid FROM tgsis.atom WHERE geoid = %s ORDER BY 1", (fault,)).fetchall()
    there = conn.execute("SELECT count(*) FROM tgsis.vrtx WHERE geoid = %s AND vrtxid = %s", (fault, x)).fetchone()
    return atoms, there


@pytest.mark.parametrize("who", ["python", "psql"])
def test_a_solution_removing_the_vertex_an_unchanged_atom_refers_to_leaves_no_dangling_atom(
    conn: Conn, fault: int, who: str
) -> None:
    """Vertex 0 (outside the region, no side changed it) is an atom of x; the manual rows remove x (cell-less in
    the version). merge3 excuses dangling refids on the parent's own rows, so the merge writes atom 0 -> x and
    removes x: a dangling GOCAD atom in DEFAULT, unsaid (both merges alike)."""
    x = int(MIDDLE[0]) - 1
    _atoms_in_base(conn, fault, (0, x, True))
    index, merge, x = _isolated(conn, fault)
    (region,) = merge.conflicts
    side = merge.child
    cells = region.cell_ids[np.isin(region.cell_ids, side.cell_ids)]
    corners = side.cells[np.searchsorted(side.cell_ids, cells)].ravel()
    _record_in_sql(
        conn, fault, index, restrict_state(side, np.setdiff1d(np.union1d(region.vertex_ids, corners), [x]), cells)
    )
    try:
        if who == "python":
            tgsis.merge_version(conn, "e1")
        else:
            conn.execute("SELECT tgsis.merge_version('e1')")
    except (tgsis.Error, psycopg.Error) as exc:
        conn.rollback()
        assert f"atoms (refid) that refer to vertices {x}, which it removes" in str(exc), str(exc)
        return
    with tgsis.in_version(conn, "DEFAULT"):
        atoms, there = _atoms_and_vertex(conn, fault, x)
    conn.rollback()
    assert not (any(int(r[1]) == x for r in atoms) and there == (0,)), (atoms, there)


@pytest.mark.parametrize("setting", ["extra_float_digits = -15", "jit = on"])
def test_session_settings_do_not_change_which_unchanged_region_rows_are_rewritten(
    conn: Conn, fault: int, setting: str
) -> None:
    """The manual rows are the child's, one margin vertex moved: the others, as the base has them, stay (compared
    through canonical texts and float8send, not the session's float output)."""
    index, merge = _conflict(conn, fault, hole=True)
    vertex = _margin_vertex(merge)
    xyz = merge.child.vertices.copy()
    xyz[np.searchsorted(merge.child.vertex_ids, vertex), 0] += 1e-9
    _record_in_sql(conn, fault, index, _replace(merge.child, vertices=xyz))
    theirs, _ = both_merges(conn, "e1")
    conn.execute(f"SET {setting}")
    conn.commit()
    _, mine = both_merges(conn, "e1")
    conn.execute("RESET ALL")
    conn.commit()
    assert theirs[0] == mine[0] == "done", (theirs[:2], mine[:2])
    assert mine[1] == theirs[1]
    for table in theirs[2]:
        assert mine[2][table] == theirs[2][table], table
