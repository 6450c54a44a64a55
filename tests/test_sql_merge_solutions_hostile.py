"""A hostile review of the psql merge of regions solved ``average`` / ``manual`` (issue 39, items 3 to 5).

The rows of such a solution (``tgsis.conflict_regions.solution_*``) are
recorded by any role that may resolve conflicts in the version, from Python
or straight from psql, and applied by the psql merge of another role later.
These tests forge, stale, overflow and race them: each case is either merged
exactly as the Python merge merges it (the oracle: tests/test_sql_merge_write.py)
or refused, naming what is wrong, with nothing written.
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
from tests.test_sql_merge_write import _outcome, _psql_state, assert_same_merge, both_merges, everything
from tgsis.merge3 import MeshState, restrict_state

Conn = psycopg.Connection[Any]


@pytest.fixture
def fault(conn: Conn, fault_clone: int) -> int:
    return fault_clone  # tests.merge_data.make_fault's (tests/conftest.py)


def _replace(state: MeshState, **changes: Any) -> MeshState:
    fields: dict[str, Any] = {
        "cell_size": state.cell_size,
        "vertex_ids": state.vertex_ids,
        "vertices": state.vertices,
        "cell_ids": state.cell_ids,
        "cells": state.cells,
        "vertex_properties": state.vertex_properties,
        "cell_properties": state.cell_properties,
    }
    fields.update(changes)
    return MeshState(
        fields["cell_size"],
        fields["vertex_ids"],
        fields["vertices"],
        fields["cell_ids"],
        fields["cells"],
        fields["vertex_properties"],
        fields["cell_properties"],
    )


def _conflict(conn: Conn, fault: int, hole: bool = False) -> tuple[int, Any]:
    """The middle moved on both sides (one conflicting region): its index and the object's merge. ``hole``: the
    version also removes triangle 48 (corners 52, 53, 65): vertices 52 and 53, which no side changed, are then
    in the region (the footprint of a removed cell holds its corners)."""
    if hole:
        psql(conn, "e1", ("DELETE FROM tgsis.trgl WHERE geoid = %s AND trglid = 48", (fault,)))
    index = _both_moved(conn, fault)
    merge = tgsis.object_merge(conn, "e1", fault)
    conn.rollback()
    return index, merge


def _psql_refuses_what_python_merges(conn: Conn, *words: str) -> str:
    """Python merges it; psql refuses (TG302, the hint naming the Python command), nothing written; the message."""
    before = everything(conn)
    conn.commit()
    theirs, _ = both_merges(conn, "e1")
    assert theirs[0] == "done", theirs
    state, message, hint = _psql_state(conn, "SELECT tgsis.merge_version('e1')", ())
    assert state == "TG302", message
    assert "tgsis version merge e1" in (hint or ""), hint
    for word in words:
        assert word in message, message
    assert everything(conn) == before
    conn.rollback()
    return message


def _refused_alike(conn: Conn, *words: str) -> tuple[Any, Any]:
    """Both merges refuse, nothing written; the psql refusal names ``words``. (Python's outcome, psql's.)"""
    before = everything(conn)
    conn.commit()
    theirs, mine = both_merges(conn, "e1")
    assert theirs[0] == "refused" and mine[0] == "refused", (theirs[:2], mine[:2])
    for word in words:
        assert word in mine[2], mine
    assert everything(conn) == before
    conn.rollback()
    return theirs, mine


# --------------------------------------------------------------------------- (a) a region row no side changed


def _margin_vertex(merge: Any) -> int:
    """A vertex of the (one) conflicting region that no side changed: 52 or 53, corners of the removed triangle."""
    (region,) = merge.conflicts
    margin = np.setdiff1d(region.vertex_ids, np.union1d(region.parent_vertex_ids, region.child_vertex_ids))
    assert set(margin.tolist()) >= {52, 53}
    return int(margin[0])


@pytest.mark.parametrize("action", ["merge", "refresh"])
def test_rows_moving_a_vertex_of_the_region_no_side_changed_merge_in_psql_as_in_python(
    conn: Conn, fault: int, action: str
) -> None:
    """A vertex of the region no side changed, moved by the solution's rows: merge3 takes the manual mesh's rows of
    the region's ids; so does psql (was refused, TG302): the base's row closed, the solution's written."""
    index, merge = _conflict(conn, fault, hole=True)
    vertex = _margin_vertex(merge)
    xyz = merge.child.vertices.copy()
    xyz[np.searchsorted(merge.child.vertex_ids, vertex), 2] += 0.25
    _record_in_sql(conn, fault, index, _replace(merge.child, vertices=xyz))
    assert_same_merge(conn, "e1", action)


def test_rows_changing_the_value_of_a_region_vertex_no_side_changed_merge_in_psql_as_in_python(
    conn: Conn, fault: int
) -> None:
    """The same vertex keeps its place but gets a porosity of no side: written as the Python merge writes it (was
    refused by psql)."""
    index, merge = _conflict(conn, fault, hole=True)
    vertex = _margin_vertex(merge)
    porosity = np.asarray(merge.child.vertex_properties["porosity"], dtype=np.float64).copy()
    porosity[np.searchsorted(merge.child.vertex_ids, vertex)] = 0.987654321
    _record_in_sql(conn, fault, index, _replace(merge.child, vertex_properties={"porosity": porosity}))
    assert_same_merge(conn, "e1")


@pytest.mark.parametrize("where", ["inside", "outside"])
def test_rows_giving_an_atom_to_a_vertex_no_side_changed_merge_or_are_refused_as_in_python(
    conn: Conn, fault: int, where: str
) -> None:
    """An atom (refid) given to a vertex no side changed: inside the region it is written as the Python merge
    writes it; outside, both refuse it (a row outside the region). psql compared no refid there: the row was
    taken as the base's and the atom dropped, unsaid."""
    atom = "INSERT INTO tgsis.atom (geoid, vrtxid, refid, patom) VALUES (%s, %s, %s, %s)"
    psql(conn, "DEFAULT", (atom, (fault, 0, 1, False)))  # an atom in the base: every state has the refid column
    conn.execute("SELECT tgsis.merge_version('e1', true)")
    conn.commit()
    tgsis.create_version(conn, "e1")
    conn.commit()
    index, merge = _conflict(conn, fault, hole=True)
    (region,) = merge.conflicts
    vertex = (
        _margin_vertex(merge) if where == "inside" else int(np.setdiff1d(merge.child.vertex_ids, region.vertex_ids)[-1])
    )
    refid = np.asarray(merge.child.vertex_properties["refid"], dtype=np.float64).copy()
    refid[np.searchsorted(merge.child.vertex_ids, vertex)] = int(MIDDLE[0])
    props = {**merge.child.vertex_properties, "refid": refid}
    _record_in_sql(conn, fault, index, _replace(merge.child, vertex_properties=props))
    if where == "inside":
        assert_same_merge(conn, "e1")
    else:
        theirs, mine = _refused_alike(conn, "outside the region", f"vertices {vertex}")
        assert (theirs[1], mine[1]) == ("TG100", "TG302"), (theirs[:2], mine[:2])


def test_rows_lacking_a_vertex_of_the_region_no_side_changed_are_refused_alike(conn: Conn, fault: int) -> None:
    """The solution lacks such a vertex and its cells in the region: merge3 removes it, and the cells outside the
    region still on it make the merge invalid: both merges refuse it (was psql's own refusal), nothing written."""
    index, merge = _conflict(conn, fault, hole=True)
    (region,) = merge.conflicts
    vertex = _margin_vertex(merge)
    side = merge.child
    on = (side.cells == vertex).any(axis=1)
    assert (on & ~np.isin(side.cell_ids, region.cell_ids)).any()  # cells on the vertex outside the region: kept
    cells = np.setdiff1d(region.cell_ids, side.cell_ids[on])
    corners = side.cells[np.searchsorted(side.cell_ids, cells)].ravel()
    # the region's rows (and its cells' corners) without the vertex and its cells there
    state = restrict_state(side, np.setdiff1d(np.union1d(region.vertex_ids, corners), [vertex]), cells)
    _record_in_sql(conn, fault, index, state)
    theirs, mine = _refused_alike(conn, "invalid merge", f"on vertices {vertex} that it removes")
    assert theirs[1] == mine[1] == "TG302", (theirs[:2], mine[:2])


# --------------------------------------------------------------------------- (b) the internals' rights

# reached only through the SECURITY DEFINER merge and resolve functions
_INTERNALS = (
    "tgsis.merge_solution_rows(bigint, integer, text, text)",
    "tgsis.npz_rows_differ(bytea, bigint[], float8[], bigint[], bigint[], text[], float8[], text[], float8[])",
    "tgsis.merge_geometry_row(bigint, text, integer[])",
    "tgsis.merge_feature_row(bigint, text[], integer[], integer, integer[])",
    "tgsis.merge_attribute_edits(text, bigint, integer[], integer[], integer[])",
)
# reached also through tgsis.mesh_merge_regions, which a reader may call directly (as itself)
_READERS = (
    "tgsis.cells_on_vertices_sql(integer, bigint[], text)",
    "tgsis.merge_value_text(text, text)",
    "tgsis.merge_property_rows(tgsis.versioned_tables, bigint, integer[], bigint[], integer[], integer[], integer[], float8, float8)",
)


def test_the_psql_merge_internals_are_not_executable_by_public_and_an_editor_still_merges(
    conn: Conn, fault: int, db_dsn: str
) -> None:
    """The helpers of the psql merge by region were executable by PUBLIC. Now the merge's own are reached through
    the SECURITY DEFINER merge and resolve functions only; those tgsis.mesh_merge_regions runs are the tgsis
    roles' (tgsis_reader). An editor with the rights merges a region solved average in psql as before, exactly
    as the Python merge does, and computes regions with mesh_merge_regions."""
    from tests.roles import login_roles

    for signature in (*_INTERNALS, *_READERS):
        (public, reader) = conn.execute(
            "SELECT has_function_privilege('public', %s::regprocedure, 'EXECUTE'),"
            " has_function_privilege('tgsis_reader', %s::regprocedure, 'EXECUTE')",
            (signature, signature),
        ).fetchone()  # type: ignore[misc]
        assert (public, reader) == (False, signature in _READERS), signature
    conn.rollback()
    index = _both_moved(conn, fault)
    tgsis.resolve_region(conn, "e1", fault, index, "average")
    conn.commit()
    with login_roles(db_dsn, {"ed": "tgsis_editor"}) as made:
        tgsis.grant_version(conn, "e1", "all", made.name("ed"))
        tgsis.grant_version(conn, "DEFAULT", "merge", made.name("ed"))
        conn.commit()
        session = made.connect("ed")
        state, message, _ = _psql_state(session, "SELECT tgsis.merge_solution_rows(1, 1, 'x', 'y')", ())
        assert state == "42501", message
        regions = session.execute("SELECT region, conflict FROM tgsis.mesh_merge_regions('e1', %s)", (fault,))
        assert (index, True) in regions.fetchall()
        session.rollback()
        seq = conn.execute("SELECT last_value, is_called FROM tgsis.revision_seq").fetchone()
        conn.commit()
        theirs = _outcome(session, lambda: int(tgsis.merge_version(session, "e1")))
        conn.execute("SELECT setval('tgsis.revision_seq', %s, %s)", seq)
        conn.commit()
        mine = _outcome(session, lambda: int(session.execute("SELECT tgsis.merge_version('e1')").fetchone()[0]))  # type: ignore[index]
        assert theirs[0] == "done" and mine[0] == "done", (theirs[:2], mine[:2])
        assert mine[1] == theirs[1]
        conn.execute("SELECT setval('tgsis.revision_seq', %s, %s)", seq)
        conn.commit()
        assert mine[2] == theirs[2]


# --------------------------------------------------------------------------- stale rows, signed zeros


def test_an_average_recorded_before_the_version_moved_the_region_again_is_not_applied(conn: Conn, fault: int) -> None:
    """The version edits the region again after its average was recorded (the same ids: only the marks tell): the
    stale rows are not merged; both merges leave the conflict unsolved (TG302), nothing written."""
    index = _both_moved(conn, fault)
    tgsis.resolve_region(conn, "e1", fault, index, "average")
    conn.commit()
    move(conn, "e1", fault, MIDDLE, (0.0, 0.0, 3.0))
    conn.commit()
    theirs, mine = _refused_alike(conn, "unsolved conflict")
    assert theirs[1] == mine[1] == "TG302"


@pytest.mark.parametrize(
    ("value", "shown"), [(1e10, "10000000000"), (float("inf"), "Infinity"), (-1e19, "-1e+19"), (2.0**31, "2147483648")]
)
def test_manual_values_an_integer_column_cannot_hold_are_refused_not_wrapped(
    conn: Conn, fault: int, value: float, shown: str
) -> None:
    """A manual solution's cell value beyond the integer column facies (1e10, inf, -1e19, 2**31): the Python merge
    wrote it wrapped (1e10 as 1410065408, inf as 0) and said done, psql failed with a raw 22003. Both refuse it now
    (TG302: the object stays an unsolved conflict), naming the property, value and ids; nothing written."""
    index, merge = _conflict(conn, fault)
    (region,) = merge.conflicts
    facies = np.asarray(merge.child.cell_properties["facies"], dtype=np.float64).copy()
    changed = region.child_cell_ids if len(region.child_cell_ids) else region.cell_ids
    facies[np.isin(merge.child.cell_ids, changed)] = value
    _record_in_sql(conn, fault, index, _replace(merge.child, cell_properties={"facies": facies}))
    theirs, mine = _refused_alike(conn, "facies (integer)", shown)
    assert theirs[1] == mine[1] == "TG302"
    assert "cell property facies (integer)" in theirs[2] and "do not fit the column" in theirs[2], theirs


def test_minus_zero_in_manual_coordinates_and_values_merges_in_psql_as_in_python(conn: Conn, fault: int) -> None:
    """-0.0 where the version has other values (x of the region's vertices, porosity): written as Python writes it."""
    index, merge = _conflict(conn, fault)
    porosity = np.asarray(merge.child.vertex_properties["porosity"], dtype=np.float64).copy()
    at = np.isin(merge.child.vertex_ids, MIDDLE)
    porosity[at] = -0.0
    xyz = merge.child.vertices.copy()
    xyz[at, 0] = -0.0
    manual = _replace(merge.child, vertices=xyz, vertex_properties={"porosity": porosity})
    tgsis.resolve_region(conn, "e1", fault, index, "manual", manual)
    conn.commit()
    theirs, mine = both_merges(conn, "e1")
    assert theirs[0] == "done" and mine[0] == "done"
    assert mine[2] == theirs[2]


# --------------------------------------------------------------------------- the .npz and the rows disagree


def _record_apart(conn: Conn, fault: int, index: int, mesh: MeshState, rows_of: MeshState) -> None:
    """A psql user's resolve_region with the .npz of one mesh and the rows of another (nothing ties them in SQL)."""
    from tgsis.db.regions import _sql_rows, state_to_npz

    conn.execute(
        "SELECT FROM tgsis.resolve_region('e1', 'feature', %s, %s, 'manual', %s, %s, %s::float8[], %s, %s,"
        " %s::text[], %s::float8[], %s::text[], %s::float8[])",
        (str(fault), index, state_to_npz(mesh), *(_sql_rows(rows_of) or ())),
    )
    conn.commit()


def test_a_solution_whose_rows_are_not_its_mesh_is_refused_when_recorded_and_by_both_merges(
    conn: Conn, fault: int
) -> None:
    """The .npz says the region is 11 m up, the rows say it is where the parent has it: the Python merge applied
    the .npz and the psql merge the rows, two results of one recorded solution, each said done. resolve_region
    now refuses such rows (TG100, nothing recorded); rows stored before (an older client, a dump) are refused by
    both merges, naming the region; nothing written."""
    from tgsis.db.regions import _sql_rows, state_to_npz

    index, merge = _conflict(conn, fault)
    xyz = merge.child.vertices.copy()
    xyz[np.isin(merge.child.vertex_ids, MIDDLE), 2] += 11.0
    shown = _replace(merge.child, vertices=xyz)
    before = everything(conn)
    conn.commit()
    args = (str(fault), index, state_to_npz(shown), *(_sql_rows(merge.parent) or ()))
    state, message, _ = _psql_state(conn, _RECORD, args)
    assert state == "TG100" and "are not those of its .npz: its vertices" in message, message
    assert everything(conn) == before
    conn.rollback()
    _record_apart(conn, fault, index, shown, shown)
    rows = _sql_rows(merge.parent) or ()
    conn.execute(
        "UPDATE tgsis.conflict_regions SET solution_vertices = %s WHERE versionid = tgsis.version_id('e1') AND region = %s",
        (rows[1], index),
    )
    conn.commit()
    before = everything(conn)
    conn.commit()
    for action in ("merge", "refresh"):
        with pytest.raises(tgsis.Error) as refused:
            if action == "merge":
                tgsis.merge_version(conn, "e1")
            else:
                tgsis.refresh_version(conn, "e1")
        conn.rollback()
        assert f"region {index}" in str(refused.value) and "are not those of its mesh" in str(refused.value)
        state, message, _ = _psql_state(conn, f"SELECT tgsis.{action}_version('e1')", ())
        assert state == "TG302" and f"not those of its .npz (region {index}: its vertices" in message, message
        assert everything(conn) == before
        conn.rollback()


def test_a_solution_whose_rows_are_its_mesh_merges_as_before(conn: Conn, fault: int) -> None:
    """The check compares bit for bit and NaN with NaN: the Python client's own recording (NaN values) passes."""
    index, merge = _conflict(conn, fault)
    porosity = np.asarray(merge.child.vertex_properties["porosity"], dtype=np.float64).copy()
    porosity[np.isin(merge.child.vertex_ids, MIDDLE)] = np.nan
    manual = _replace(merge.child, vertex_properties={"porosity": porosity})
    _record_apart(conn, fault, index, manual, manual)
    theirs, mine = both_merges(conn, "e1")
    assert theirs[0] == "done" and mine[0] == "done", (theirs[:2], mine[:2])
    assert mine[1:] == theirs[1:]


# --------------------------------------------------------------------------- a cell on one vertex twice

_RECORD = (
    "SELECT FROM tgsis.resolve_region('e1', 'feature', %s, %s, 'manual', %s, %s, %s::float8[], %s, %s,"
    " %s::text[], %s::float8[], %s::text[], %s::float8[])"
)


def _rows_with_a_cell_on_a_vertex_twice(merge: Any) -> tuple[list[Any], int]:
    """The version's rows as a solution's, one region triangle (a, b, c) made (a, b, b) and the region triangle
    across (a, b) left out: no edge of the merged mesh is in three triangles (merge_mesh_validity passes it)."""
    from tgsis.db.regions import _sql_rows

    (region,) = merge.conflicts
    side = merge.child
    rows = list(_sql_rows(side) or ())
    cells = side.cells.copy()
    inside = np.flatnonzero(np.isin(side.cell_ids, region.cell_ids))
    c, d = next(
        (c, d) for c in inside for d in inside if d != c and cells[c, 0] in cells[d] and cells[c, 1] in cells[d]
    )
    cells[c, 2] = cells[c, 1]
    keep = np.arange(len(side.cell_ids)) != d
    rows[2] = side.cell_ids[keep].tolist()
    rows[3] = cells[keep].ravel().tolist()
    rows[7] = np.asarray(rows[7]).reshape(len(side.cell_ids), len(rows[6]))[keep].ravel().tolist()
    return rows, int(side.cell_ids[c])


def _npz_of_rows(k: int, rows: list[Any]) -> bytes:
    """An .npz as tgsis.db.regions.state_to_npz writes one, of the eight arrays of rows (float64 property values)."""
    import io

    arrays: dict[str, Any] = {
        "cell_size": np.asarray(k, dtype=np.int64),
        "vertex_ids": np.asarray(rows[0], dtype=np.int64),
        "vertices": np.asarray(rows[1], dtype=np.float64).reshape(-1, 3),
        "cell_ids": np.asarray(rows[2], dtype=np.int64),
        "cells": np.asarray(rows[3], dtype=np.int64).reshape(-1, k),
    }
    for prefix, columns, values, count in (
        ("vertex:", rows[4], rows[5], len(rows[0])),
        ("cell:", rows[6], rows[7], len(rows[2])),
    ):
        table = np.asarray(values, dtype=np.float64).reshape(count, len(columns))
        for j, name in enumerate(columns):
            arrays[prefix + name] = table[:, j].copy()
    buffer = io.BytesIO()
    np.savez(buffer, **arrays)
    return buffer.getvalue()


def test_rows_with_a_cell_on_one_vertex_twice_are_refused_when_recorded(conn: Conn, fault: int) -> None:
    """Such rows were recorded; the psql merge then failed with the storage's raw 23514 (trgl_distinct_vertices)."""
    from tgsis.db.regions import state_to_npz

    index, merge = _conflict(conn, fault)
    rows, cell = _rows_with_a_cell_on_a_vertex_twice(merge)
    before = everything(conn)
    conn.commit()
    state, message, _ = _psql_state(conn, _RECORD, (str(fault), index, state_to_npz(merge.child), *rows))
    assert state == "TG100", message
    assert f"cells {cell} use a vertex twice" in message
    assert everything(conn) == before
    conn.rollback()


def test_stored_rows_with_a_cell_on_one_vertex_twice_are_refused_by_the_psql_merge(conn: Conn, fault: int) -> None:
    """Rows stored before resolve_region refused them (an older client, a restored dump): TG302 naming the cell,
    not a raw 23514 from the storage; nothing written."""
    index, merge = _conflict(conn, fault)
    rows, cell = _rows_with_a_cell_on_a_vertex_twice(merge)
    _record_in_sql(conn, fault, index, merge.child)
    conn.execute(  # with an .npz of the same rows (no MeshState holds them: numpy.savez writes them)
        "UPDATE tgsis.conflict_regions SET solution_cell_ids = %s, solution_cells = %s, solution_cell_values = %s,"
        " solution_mesh = %s WHERE versionid = tgsis.version_id('e1') AND region = %s",
        (rows[2], rows[3], rows[7], _npz_of_rows(3, rows), index),
    )
    conn.commit()
    before = everything(conn)
    conn.commit()
    for action in ("merge", "refresh"):
        state, message, hint = _psql_state(conn, f"SELECT tgsis.{action}_version('e1')", ())
        assert state == "TG302", message
        assert f"region {index}: cells {cell} use a vertex twice" in message
        assert everything(conn) == before
        conn.rollback()


# --------------------------------------------------------------------------- rights, two sessions


def test_a_role_that_may_resolve_but_not_change_the_class_records_no_rows(conn: Conn, fault: int, db_dsn: str) -> None:
    """Rows of an average/manual solution are written into the class by the merge of maybe another role: a role
    with the version's write right but no UPDATE on the class records none (42501, from Python and psql alike);
    parent/child stay open to it. A role that may not read the class sees no region rows (the policy)."""
    from tests.roles import login_roles
    from tgsis.db.regions import _sql_rows, state_to_npz

    index, merge = _conflict(conn, fault)
    with login_roles(db_dsn, {"ed": "tgsis_editor"}) as made:
        tgsis.grant_version(conn, "e1", "all", made.name("ed"))
        conn.execute("REVOKE INSERT, UPDATE, DELETE ON public.faults FROM tgsis_editor")
        conn.commit()
        before = everything(conn)
        conn.commit()
        session = made.connect("ed")
        with pytest.raises(tgsis.MissingPrivilegeError):
            tgsis.resolve_region(session, "e1", fault, index, "average")
        session.rollback()
        rows = _sql_rows(merge.child) or ()
        state, message, _ = _psql_state(session, _RECORD, (str(fault), index, state_to_npz(merge.child), *rows))
        assert state == "42501", message
        assert everything(conn) == before
        conn.rollback()
        session.execute("SELECT FROM tgsis.resolve_region('e1', 'feature', %s, %s, 'child')", (str(fault), index))
        session.commit()
        _record_in_sql(conn, fault, index, merge.child)
        conn.execute("REVOKE SELECT ON public.faults FROM tgsis_reader, tgsis_editor")
        conn.commit()
        assert session.execute("SELECT count(*) FROM tgsis.conflict_regions").fetchone() == (0,)
        session.rollback()


def test_a_merge_while_another_session_records_a_solution_waits_and_merges_that_one(
    conn: Conn, fault: int, db_dsn: str
) -> None:
    """Session B records a manual mesh over an average, not committed yet; session A's psql merge waits for it (the
    regions' rows are locked) and merges B's mesh once B commits: never a mix of the two solutions' rows."""
    import threading
    import time

    from tgsis.db.regions import _sql_rows, state_to_npz

    index, merge = _conflict(conn, fault)
    tgsis.resolve_region(conn, "e1", fault, index, "average")
    conn.commit()
    xyz = merge.child.vertices.copy()
    xyz[np.isin(merge.child.vertex_ids, MIDDLE), 2] += 2.0
    manual = _replace(merge.child, vertices=xyz)
    with psycopg.connect(db_dsn) as b:
        b.execute(_RECORD, (str(fault), index, state_to_npz(manual), *(_sql_rows(manual) or ())))
        done: dict[str, Any] = {}

        def merge_in_a() -> None:
            with psycopg.connect(db_dsn) as a:
                done["rows"] = a.execute("SELECT tgsis.merge_version('e1')").fetchone()

        thread = threading.Thread(target=merge_in_a)
        thread.start()
        waited = False
        for _ in range(100):
            (waiting,) = conn.execute(
                "SELECT count(*) FROM pg_stat_activity WHERE datname = current_database() AND wait_event_type = 'Lock'"
                " AND query LIKE 'SELECT tgsis.merge_version%%'"
            ).fetchone()  # type: ignore[misc]
            conn.rollback()
            if waiting:
                waited = True
                break
            time.sleep(0.1)
        assert waited and thread.is_alive()
        b.commit()
        thread.join(60)
    assert done["rows"] is not None
    with tgsis.in_version(conn, "DEFAULT"):
        got = conn.execute(
            "SELECT vrtxid, z FROM tgsis.vrtx WHERE geoid = %s AND vrtxid = ANY (%s) ORDER BY vrtxid",
            (fault, MIDDLE.tolist()),
        ).fetchall()
    conn.rollback()
    at = np.searchsorted(manual.vertex_ids, MIDDLE)
    assert [(int(i), float(z)) for i, z in got] == list(zip(MIDDLE.tolist(), manual.vertices[at, 2].tolist()))


# --------------------------------------------------------------------------- GOCAD atoms and parts that are no whole numbers


@pytest.mark.parametrize("ref", [5.5, 5.9, 1e19])
def test_a_manual_refid_that_is_no_vertex_id_is_refused_by_both_merges(conn: Conn, fault: int, ref: float) -> None:
    """A manual mesh's atom refid 5.5 or 5.9: Python wrote the atom on vertex 5 (truncated), psql on vertex 6
    (rounded), each said done; 1e19: Python wrote refid -2**63. Both refuse it now, naming the atom's vertex."""
    atom = "INSERT INTO tgsis.atom (geoid, vrtxid, refid, patom) VALUES (%s, %s, %s, %s)"
    psql(conn, "DEFAULT", (atom, (fault, int(MIDDLE[0]), int(MIDDLE[1]), True)))
    conn.execute("SELECT tgsis.merge_version('e1', true)")
    conn.commit()
    tgsis.create_version(conn, "e1")
    conn.commit()
    index, merge = _conflict(conn, fault)
    side = merge.child
    refid = np.asarray(side.vertex_properties["refid"], dtype=np.float64).copy()
    refid[np.searchsorted(side.vertex_ids, MIDDLE[0])] = ref
    _record_in_sql(conn, fault, index, _replace(side, vertex_properties={**side.vertex_properties, "refid": refid}))
    theirs, mine = _refused_alike(conn, f"refid {ref:g}" if ref < 1e6 else "refid", f"ids {MIDDLE[0]}")
    assert theirs[1] == mine[1] == "TG302"
    assert "atoms (refid)" in theirs[2] and f"at ids [{MIDDLE[0]}]" in theirs[2], theirs


def test_a_manual_part_that_is_no_part_number_is_refused_by_both_merges(conn: Conn) -> None:
    """Cells of parts 2.5 and 2.7 side by side: Python wrote two runs of part 2, psql one run of part 3."""
    from tests.test_sql_merge_write import _parted_fault

    geoid = _parted_fault(conn)
    index, merge = _conflict(conn, geoid)
    (region,) = merge.conflicts
    side = merge.child
    part = np.asarray(side.cell_properties["part"], dtype=np.float64).copy()
    at = np.flatnonzero(np.isin(side.cell_ids, region.cell_ids))
    part[at[:2]] = 2.5
    part[at[2:4]] = 2.7
    _record_in_sql(conn, geoid, index, _replace(side, cell_properties={**side.cell_properties, "part": part}))
    theirs, mine = _refused_alike(conn, "part 2.5", f"ids {side.cell_ids[at[0]]}")
    assert theirs[1] == mine[1] == "TG302"
    assert "cell parts" in theirs[2] and "no part numbers" in theirs[2], theirs


# --------------------------------------------------------------------------- a real column


@pytest.mark.parametrize(("value", "shown"), [(1e39, "1e+39"), (-1e39, "-1e+39"), (1e-46, "1e-46")])
def test_manual_values_a_real_column_cannot_hold_are_refused_by_both_merges(
    conn: Conn, value: float, shown: str
) -> None:
    """A real vertex property given 1e39 (float4 overflows) or 1e-46 (float4 underflows to 0): Python wrote inf and 0
    and said done, psql failed with a raw 22003. Both refuse it now, naming the property; nothing written."""
    from tests.merge_data import curved_surface
    from tgsis.db import features as F

    F.create_feature_class(
        conn,
        "faults",
        "SURFACE",
        cell_properties=[("porosity", "real"), tgsis.Property("facies", "int", alignment="CELL")],
    )
    tgsis.enable_feature_versioning(conn)
    geoid = F.insert_feature(conn, "faults", curved_surface())
    tgsis.create_version(conn, "e1")
    conn.commit()
    index, merge = _conflict(conn, geoid)
    side = merge.child
    porosity = np.asarray(side.vertex_properties["porosity"], dtype=np.float64).copy()
    porosity[np.isin(side.vertex_ids, MIDDLE)] = value
    _record_in_sql(conn, geoid, index, _replace(side, vertex_properties={"porosity": porosity}))
    theirs, mine = _refused_alike(conn, "vertex property porosity (real)", shown)
    assert theirs[1] == mine[1] == "TG302"
    assert "vertex property porosity (real)" in theirs[2] and "do not fit the column" in theirs[2], theirs


# --------------------------------------------------------------------------- average of an integer property


def test_average_keeps_the_parents_value_of_an_integer_property_read_with_gaps(conn: Conn, fault: int) -> None:
    """facies is an integer column; one cell of the object has no facies row, so the states read facies as float64
    (NaN for none). The average took the middle of the two sides' facies there (4 and 1: written 2, a code no side
    gave, by both merges, each said done); the rule is the middle of real-valued properties only, the parent's
    value of any other. Now both merges write the parent's 4."""
    from tests.test_sql_merge_regions import property_tables

    _, cp = property_tables(conn, fault)
    psql(conn, "DEFAULT", (f"DELETE FROM {cp} WHERE _geoid = %s AND _idx = 0", (fault,)))
    conn.execute("SELECT tgsis.merge_version('e1', true)")
    conn.commit()
    tgsis.create_version(conn, "e1")
    conn.commit()
    psql(conn, "e1", (f"UPDATE {cp} SET facies = 1 WHERE _geoid = %s AND _idx IN (59, 60)", (fault,)))
    psql(conn, "DEFAULT", (f"UPDATE {cp} SET facies = 4 WHERE _geoid = %s AND _idx IN (59, 60)", (fault,)))
    index, merge = _conflict(conn, fault)
    assert np.asarray(merge.child.cell_properties["facies"]).dtype.kind == "f"  # read with a gap
    result = tgsis.resolve_region(conn, "e1", fault, index, "average")
    conn.commit()
    assert result.state is not None
    at = np.isin(result.state.cell_ids, [59, 60])
    assert np.asarray(result.state.cell_properties["facies"])[at].tolist() == [4.0, 4.0]
    theirs, mine = both_merges(conn, "e1")
    assert theirs[0] == mine[0] == "done", (theirs[:2], mine[:2])
    assert mine[1:] == theirs[1:]
    conn.execute("SELECT tgsis.merge_version('e1')")
    with tgsis.in_version(conn, "DEFAULT"):
        facies = conn.execute(f"SELECT _idx, facies FROM {cp} WHERE _geoid = %s AND _idx IN (59, 60)", (fault,))
        assert sorted(facies.fetchall()) == [(59, 4), (60, 4)]
    conn.rollback()


def test_average_of_two_meshings_keeps_an_integer_vertex_property_read_with_gaps(conn: Conn) -> None:
    """The two-meshings average (average_shape) carried every float vertex array halfway, an integer column read as
    floats too: its values became fractions, written truncated (codes no side gave). Now only real columns."""
    from tests.merge_data import curved_surface
    from tests.test_merge_average import _moved, _subdivided, _write
    from tests.test_sql_merge_regions import property_tables
    from tgsis.db import features as F

    F.create_feature_class(
        conn,
        "faults",
        "SURFACE",
        cell_properties=[("porosity", "float8"), ("code", "int"), tgsis.Property("facies", "int", alignment="CELL")],
    )
    tgsis.enable_feature_versioning(conn)
    surface = curved_surface()
    surface.vertex_properties["code"] = np.arange(len(surface.vertices), dtype=np.int64) * 3
    geoid = F.insert_feature(conn, "faults", surface)
    conn.commit()
    vp, _ = property_tables(conn, geoid)
    psql(conn, "DEFAULT", (f"DELETE FROM {vp} WHERE _geoid = %s AND _idx = 0", (geoid,)))  # vertex 0: no row
    tgsis.create_version(conn, "e1")
    conn.commit()
    base = MeshState.from_mesh(surface)
    props = {n: np.asarray(v, dtype=np.float64).copy() for n, v in base.vertex_properties.items()}
    for values in props.values():
        values[0] = np.nan
    base = _replace(base, vertex_properties=props)
    code = props["code"]
    finer = _subdivided(base)
    new = finer.n_vertices - base.n_vertices
    finer = _replace(
        finer, vertex_properties={**finer.vertex_properties, "code": np.concatenate([code, np.full(new, 5.0)])}
    )
    _write(conn, "e1", geoid, base, finer)
    _write(conn, "DEFAULT", geoid, base, _moved(base))
    [conflict] = tgsis.find_conflicts(conn, "e1")
    conn.commit()
    [region] = [r for r in conflict.regions if r.conflict]
    result = tgsis.resolve_region(conn, "e1", geoid, region.region, "average")
    conn.commit()
    assert result.state is not None
    values = np.asarray(result.state.vertex_properties["code"], dtype=np.float64)
    values = values[~np.isnan(values)]
    assert np.array_equal(values, np.trunc(values)), values[values != np.trunc(values)][:5]
    theirs, mine = both_merges(conn, "e1")
    assert theirs[0] == mine[0] == "done", (theirs[:2], mine[:2])
    assert mine[1:] == theirs[1:]


def test_a_bigint_property_beyond_2_53_records_no_rows_and_python_merges_it_exactly(conn: Conn) -> None:
    """float8 rows cannot hold 2**53 + 1: the average is recorded with its .npz only; psql refuses it naming the
    Python command, and the Python merge writes the values exactly."""
    from tests.merge_data import curved_surface
    from tgsis.db import features as F

    F.create_feature_class(conn, "faults", "SURFACE", cell_properties=[("code", "bigint")])
    tgsis.enable_feature_versioning(conn)
    surface = curved_surface()
    codes = np.arange(len(surface.vertices), dtype=np.int64) + 2**53 + 1
    surface = tgsis.Surface(surface.vertices, surface.cells, vertex_properties={"code": codes}, name="fault")
    geoid = F.insert_feature(conn, "faults", surface)
    tgsis.create_version(conn, "e1")
    conn.commit()
    index = _both_moved(conn, geoid)
    tgsis.resolve_region(conn, "e1", geoid, index, "average")
    conn.commit()
    (rows,) = conn.execute(
        "SELECT solution_vertex_ids IS NULL AND solution_mesh IS NOT NULL FROM tgsis.conflict_regions"
        " WHERE versionid = tgsis.version_id('e1') AND region = %s",
        (index,),
    ).fetchone()  # type: ignore[misc]
    conn.rollback()
    assert rows
    message = _psql_refuses_what_python_merges(conn, "average with its mesh only")
    assert f"feature {geoid}" in message
    tgsis.merge_version(conn, "e1")
    conn.commit()
    with tgsis.in_version(conn, "DEFAULT"):
        got = dict(conn.execute("SELECT _idx, code FROM public.faults_cellpros WHERE _geoid = %s", (geoid,)).fetchall())
    conn.rollback()
    assert got == {i: int(c) for i, c in enumerate(codes)}


def test_sql_reads_the_npz_of_every_property_type_the_python_client_records(conn: Conn) -> None:
    """tgsis.npz_rows_differ: the .npz numpy.savez writes of float64 (NaN, -0.0), float32 (NaN, inf), signed and
    unsigned integers of each width and booleans holds exactly its rows; one value, id or coordinate changed in the
    rows is named."""
    from tgsis.db.regions import _sql_rows, state_to_npz

    n = 4
    vprops: dict[str, Any] = {
        "f8": np.array([0.1, -0.0, np.nan, 1e300]),
        "f4": np.array([0.1, np.nan, np.inf, -2.5], dtype=np.float32),
        "i1": np.array([-128, 127, 0, -1], dtype=np.int8),
        "u1": np.array([0, 255, 7, 128], dtype=np.uint8),
        "i2": np.array([-32768, 32767, 5, -2], dtype=np.int16),
        "u2": np.array([65535, 0, 1, 2], dtype=np.uint16),
        "i4": np.array([-(2**31), 2**31 - 1, 3, -4], dtype=np.int32),
        "u4": np.array([2**32 - 1, 0, 1, 2], dtype=np.uint32),
        "i8": np.array([-(2**53), 2**53, 9, -9], dtype=np.int64),
        "b1": np.array([True, False, True, False]),
    }
    state = MeshState(
        3,
        np.array([3, 5, 2**60, 11], dtype=np.int64)[np.argsort([3, 5, 2**60, 11])],
        np.array([[0.0, 0.0, 0.0], [1.0, 0.0, -0.0], [0.0, 1.0, 0.5], [1.0, 1.0, 1e-300]]),
        np.array([7, 8], dtype=np.int64),
        np.array([[3, 5, 2**60], [5, 11, 2**60]], dtype=np.int64),
        vprops,
        {"facies": np.array([1, 2], dtype=np.int32)},
    )
    mesh = state_to_npz(state)
    rows = list(_sql_rows(state) or ())
    query = (
        "SELECT tgsis.npz_rows_differ(%s, %s, %s::float8[], %s, %s, %s::text[], %s::float8[], %s::text[], %s::float8[])"
    )
    assert conn.execute(query, (mesh, *rows)).fetchone() == (None,)
    columns = rows[4]
    for name in vprops:
        for i in range(n):
            values = list(rows[5])
            at = i * len(columns) + columns.index(name)
            values[at] = 0.25 if values[at] != 0.25 else 0.5
            changed = [*rows[:5], values, *rows[6:]]
            (why,) = conn.execute(query, (mesh, *changed)).fetchone()  # type: ignore[misc]
            assert why is not None and f"vertex property {name} " in why, (name, i, why)
    for k, word in ((0, "vertex_ids"), (1, "vertices"), (2, "cell_ids"), (3, "cells")):
        changed = list(rows)
        changed[k] = [*rows[k][:-1], rows[k][-1] + 1]
        (why,) = conn.execute(query, (mesh, *changed)).fetchone()  # type: ignore[misc]
        assert why == f"its {word} are not the rows'", why
    conn.rollback()
