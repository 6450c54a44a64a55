"""Region detection and solutions of the merge by region in SQL (issue 39, items 2, 4, 5 from psql).

The oracle is the Python three-way merge (tgsis.merge3 through
``tgsis.object_merge``): the regions SQL ``tgsis.find_conflicts`` stores
must be exactly those merge3 computes, for hand-written edits and random ones.
"""

from __future__ import annotations

import itertools
from typing import Any

import numpy as np
import psycopg
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import tgsis
from tests.merge_data import SIDE, move
from tgsis.db.classes import class_of_feature

Conn = psycopg.Connection[Any]

NORTH = np.arange(0, 2 * SIDE)
SOUTH = np.arange((SIDE - 2) * SIDE, SIDE * SIDE)
MIDDLE = np.array([5 * SIDE + 5, 5 * SIDE + 6, 6 * SIDE + 5, 6 * SIDE + 6])
_IDS = ("vertex_ids", "cell_ids", "parent_vertex_ids", "parent_cell_ids", "child_vertex_ids", "child_cell_ids")


def sql_regions(conn: Conn, version: str, geoid: int) -> list[dict[str, Any]]:
    """What SQL tgsis.find_conflicts stores for the feature, without any Python region call (then rolled back)."""
    conn.execute("SELECT FROM tgsis.find_conflicts(%s)", (version,))
    rows = conn.execute(
        "SELECT region, conflict, changed_by, vertex_ids, cell_ids, parent_vertex_ids, parent_cell_ids,"
        " child_vertex_ids, child_cell_ids, bbox, parent_displacement, child_displacement, solution"
        "  FROM tgsis.conflict_regions WHERE versionid = tgsis.version_id(%s) AND objectkey = %s ORDER BY region",
        (version, str(geoid)),
    ).fetchall()
    conn.rollback()
    names = ("region", "conflict", "changed_by", *_IDS, "bbox", "parent_displacement", "child_displacement", "solution")
    return [dict(zip(names, r, strict=True)) for r in rows]


def python_regions(conn: Conn, version: str, geoid: int) -> list[dict[str, Any]]:
    """The regions merge3 computes for the feature (tgsis.object_merge: read-only)."""
    merge = tgsis.object_merge(conn, version, geoid)
    conn.rollback()
    out = []
    for r in merge.regions:
        bounds = np.asarray(r.bounds, dtype=np.float64).ravel()
        out.append(
            {
                "region": r.index,
                "conflict": r.conflict,
                "changed_by": r.sides,
                **{n: [int(i) for i in getattr(r, n)] for n in _IDS},
                "bbox": [float(v) for v in bounds] if np.all(np.isfinite(bounds)) else None,
                "parent_displacement": float(r.parent_displacement),
                "child_displacement": float(r.child_displacement),
                "solution": "unsolved" if r.conflict else "automatic",
            }
        )
    return out


def assert_same_regions(conn: Conn, version: str, geoid: int) -> list[dict[str, Any]]:
    mine, theirs = sql_regions(conn, version, geoid), python_regions(conn, version, geoid)
    assert mine == theirs
    return mine


def test_three_regions_found_by_sql_as_merge3_finds_them(conn: Conn, fault_clone: int) -> None:
    geoid = fault_clone
    move(conn, "e1", geoid, NORTH, (0.5, 0.0, 1.25))
    move(conn, "e1", geoid, MIDDLE, (0.0, 0.0, 5.0))
    move(conn, "DEFAULT", geoid, SOUTH, (-1.0, 0.0, -2.0))
    move(conn, "DEFAULT", geoid, MIDDLE, (0.0, 0.0, -7.0))
    conn.commit()
    regions = assert_same_regions(conn, "e1", geoid)
    assert sorted(r["changed_by"] for r in regions) == ["both", "child", "parent"]
    assert [r["conflict"] for r in regions].count(True) == 1


def psql(conn: Conn, version: str, *statements: tuple[str, tuple[Any, ...]]) -> None:
    """Statements a psql user runs in ``version`` (committed)."""
    with tgsis.in_version(conn, version):
        for text, args in statements:
            conn.execute(text, args)
    conn.commit()


@pytest.fixture
def fault(conn: Conn, fault_clone: int) -> int:
    return fault_clone  # make_fault's, built once (tests/conftest.py)


def test_disjoint_edits_are_two_regions_that_merge_by_themselves(conn: Conn, fault: int) -> None:
    move(conn, "e1", fault, NORTH, (0.5, 0.0, 1.25))
    move(conn, "DEFAULT", fault, SOUTH, (-1.0, 0.0, -2.0))
    conn.commit()
    regions = assert_same_regions(conn, "e1", fault)
    assert [(r["changed_by"], r["conflict"], r["solution"]) for r in regions] == [
        ("child", False, "automatic"),
        ("parent", False, "automatic"),
    ]


def test_identical_rewrites_on_both_sides_merge_and_the_same_place_twice_is_no_conflict(conn: Conn, fault: int) -> None:
    move(conn, "e1", fault, MIDDLE, (0.0, 0.0, 5.0))
    move(conn, "DEFAULT", fault, MIDDLE, (0.0, 0.0, 5.0))
    move(conn, "DEFAULT", fault, SOUTH, (0.0, 0.0, 0.0))  # rewritten as it was: no edit at all
    conn.commit()
    regions = assert_same_regions(conn, "e1", fault)
    assert [(r["changed_by"], r["conflict"]) for r in regions] == [("both", False)]


def property_tables(conn: Conn, geoid: int) -> tuple[str, str]:
    """The quoted vertex and cell property tables of the feature's class."""
    fc = class_of_feature(conn, geoid)
    conn.rollback()
    return tuple(fc.qualified(fc.property_table(a) or "").as_string(conn) for a in ("VERTEX", "CELL"))  # type: ignore[return-value]


def test_values_changed_and_nulls_minus_zero_and_reorientations(conn: Conn, fault: int) -> None:
    """Property-only edits add no margin; NULL equals a missing value, -0.0 equals 0.0; an even rotation of a
    triangle's row is no edit, an odd one (the triangle turned over) is."""
    vp, cp = property_tables(conn, fault)
    psql(
        conn,
        "e1",
        (f"UPDATE {vp} SET porosity = porosity * 2 WHERE _geoid = %s AND _idx IN (3, 50)", (fault,)),
        (f"UPDATE {cp} SET facies = 7 WHERE _geoid = %s AND _idx = 40", (fault,)),
        (
            "UPDATE tgsis.trgl SET vrtxid1 = vrtxid2, vrtxid2 = vrtxid3, vrtxid3 = vrtxid1"
            " WHERE geoid = %s AND trglid = 10",
            (fault,),
        ),
        ("UPDATE tgsis.trgl SET vrtxid1 = vrtxid2, vrtxid2 = vrtxid1 WHERE geoid = %s AND trglid = 90", (fault,)),
    )
    psql(
        conn,
        "DEFAULT",
        (f"UPDATE {vp} SET porosity = 'NaN' WHERE _geoid = %s AND _idx = 100", (fault,)),
        (f"UPDATE {cp} SET facies = 1 WHERE _geoid = %s AND _idx = 40", (fault,)),
        (f"DELETE FROM {cp} WHERE _geoid = %s AND _idx = 120", (fault,)),
        (f"DELETE FROM {vp} WHERE _geoid = %s AND _idx = 101", (fault,)),
        ("UPDATE tgsis.vrtx SET z = -z WHERE geoid = %s AND vrtxid = 0 AND z = 0", (fault,)),
    )
    regions = assert_same_regions(conn, "e1", fault)
    assert [r["cell_ids"] for r in regions if r["conflict"]] == [[40]]
    assert len(regions) == 7  # 3, 50, triangle 90 turned over; 100, 101, 120; 40


def test_vertices_and_triangles_added_and_removed_with_the_same_new_ids_on_both_sides(conn: Conn, fault: int) -> None:
    """Both sides hand out the same new ids: the version's new vertex and triangle that are the parent's (same
    content) take its ids, the others fresh ids above every id (merge3's child renumbering)."""
    n, m = SIDE * SIDE, 2 * (SIDE - 1) ** 2
    add = "INSERT INTO tgsis.vrtx (geoid, vrtxid, x, y, z) VALUES (%s, %s, %s, %s, %s)"
    tri = "INSERT INTO tgsis.trgl (geoid, trglid, vrtxid1, vrtxid2, vrtxid3) VALUES (%s, %s, %s, %s, %s)"
    psql(
        conn,
        "e1",
        (add, (fault, n, 50.0, -300.0, 0.0)),  # the same vertex as the parent's n, beyond edge 0-1
        (tri, (fault, m, 1, 0, n)),  # the same triangle as the parent's m
        (add, (fault, n + 1, 9000.0, 2000.0, 1.0)),  # the parent's n + 1 is elsewhere
        (tri, (fault, m + 1, SIDE - 1, 2 * SIDE - 1, n + 1)),
        ("DELETE FROM tgsis.trgl WHERE geoid = %s AND trglid = 60", (fault,)),
    )
    psql(
        conn,
        "DEFAULT",
        (add, (fault, n, 50.0, -300.0, 0.0)),
        (tri, (fault, m, 1, 0, n)),
        (add, (fault, n + 1, -500.0, 2000.0, 1.0)),
        (tri, (fault, m + 1, SIDE * (SIDE - 1), SIDE * (SIDE - 2), n + 1)),
        ("DELETE FROM tgsis.trgl WHERE geoid = %s AND trglid = 61", (fault,)),
        ("DELETE FROM tgsis.trgl WHERE geoid = %s AND 77 IN (vrtxid1, vrtxid2, vrtxid3)", (fault,)),
        ("DELETE FROM tgsis.vrtx WHERE geoid = %s AND vrtxid = 77", (fault,)),
    )
    regions = assert_same_regions(conn, "e1", fault)
    child_ids = sorted({i for r in regions for i in r["child_vertex_ids"]})
    assert n + 2 in child_ids and n + 1 not in child_ids  # renumbered above every id


@pytest.mark.parametrize("geotype", ["MULTIPOINT", "MULTILINESTRING", "MULTITETRA"])
def test_points_lines_and_solids(conn: Conn, geotype: str) -> None:
    from tests.test_object_merge import _other_kind

    tgsis.create_feature_class(conn, "bodies", geotype)
    tgsis.enable_feature_versioning(conn)
    mesh = _other_kind(geotype)
    geoid = tgsis.insert_feature(conn, "bodies", mesh)
    tgsis.create_version(conn, "e1")
    conn.commit()
    move(conn, "e1", geoid, np.arange(0, 5), (0.5, 0.25, -1.125))
    move(conn, "e1", geoid, [20], (0.0, 1.0, 0.0))
    move(conn, "DEFAULT", geoid, np.arange(19, 23), (-3.3, 0.0, 2.2))
    move(conn, "DEFAULT", geoid, np.arange(34, 40), (-3.3, 0.0, 2.2))
    conn.commit()
    regions = assert_same_regions(conn, "e1", geoid)
    assert any(r["conflict"] for r in regions)


def test_parts_and_atoms_are_values_of_the_cells_and_vertices(conn: Conn) -> None:
    from tests.merge_data import curved_surface

    tgsis.create_feature_class(conn, "faults", "SURFACE")
    tgsis.enable_feature_versioning(conn)
    surface = curved_surface()
    half = len(surface.cells) // 2
    parted = tgsis.Surface(
        surface.vertices, surface.cells, cell_properties={"part": (np.arange(2 * half) >= half).astype(np.int64)}
    )
    geoid = tgsis.insert_feature(conn, "faults", parted)
    tgsis.create_version(conn, "e1")
    conn.commit()
    psql(conn, "DEFAULT", ("UPDATE tgsis.part SET part = 2 WHERE geoid = %s AND part = 1", (geoid,)))
    psql(
        conn,
        "e1",
        ("INSERT INTO tgsis.atom (geoid, vrtxid, refid) VALUES (%s, 5, 4)", (geoid,)),
        ("UPDATE tgsis.vrtx SET x = x + 1 WHERE geoid = %s AND vrtxid = 130", (geoid,)),
    )
    regions = assert_same_regions(conn, "e1", geoid)
    # a value-only edit adds no margin: each cell whose part the parent changed is a region of its own
    assert sum(len(r["parent_cell_ids"]) for r in regions) == half
    assert [r["child_vertex_ids"] for r in regions if r["changed_by"] == "child"] == [[5]]  # the new atom


def three_regions(conn: Conn, fault: int) -> None:
    """North end moved in e1, south end in DEFAULT, the middle on both sides to other places (committed)."""
    move(conn, "e1", fault, NORTH, (0.5, 0.0, 1.25))
    move(conn, "e1", fault, MIDDLE, (0.0, 0.0, 5.0))
    move(conn, "DEFAULT", fault, SOUTH, (-1.0, 0.0, -2.0))
    move(conn, "DEFAULT", fault, MIDDLE, (0.0, 0.0, -7.0))
    conn.commit()


def sqlstate(conn: Conn, query: str, args: tuple[Any, ...]) -> tuple[str | None, str, str | None]:
    try:
        conn.execute(query, args)
    except psycopg.Error as exc:
        conn.rollback()
        return exc.sqlstate, str(exc), exc.diag.message_hint
    conn.rollback()
    return None, "", None


@pytest.mark.parametrize("solution", ["child", "parent"])
def test_a_psql_whole_side_that_drops_the_other_sides_edits_is_refused_without_python(
    conn: Conn, fault: int, solution: str
) -> None:
    """Item 4 from psql: nobody ran the Python find_conflicts; resolve_conflict finds the regions itself."""
    three_regions(conn, fault)
    assert conn.execute("SELECT count(*) FROM tgsis.conflict_regions").fetchone() == (0,)
    conn.rollback()
    state, message, hint = sqlstate(
        conn, "SELECT tgsis.resolve_conflict('e1', 'feature', %s, %s)", (str(fault), solution)
    )
    assert state == "TG307", message
    assert "resolve_region" in (hint or "")
    assert conn.execute("SELECT solution FROM tgsis.conflicts").fetchall() in ([], [("unsolved",)])
    conn.rollback()
    # the manual solution (a merged object written into the version first) stays allowed
    state, message, _ = sqlstate(conn, "SELECT tgsis.resolve_conflict('e1', 'feature', %s, 'manual')", (str(fault),))
    assert state is None, message


def test_a_role_that_may_not_read_the_class_stores_no_regions(conn: Conn, fault: int, db_dsn: str) -> None:
    """SQL region detection reads with the calling role's rights on the class: a role that stores conflicts
    (it may write in the version) but may not read the class gets the conflicts and no regions."""
    from tests.roles import login_roles

    three_regions(conn, fault)
    with login_roles(db_dsn, {"ed": "tgsis_editor"}) as made:
        tgsis.grant_version(conn, "e1", "write", made.name("ed"))
        conn.execute("REVOKE SELECT ON public.faults FROM tgsis_editor, tgsis_reader")
        conn.commit()
        ed = made.connect("ed")
        rows = ed.execute("SELECT objectkey FROM tgsis.find_conflicts('e1')").fetchall()
        ed.commit()
        assert rows == [(str(fault),)]
        assert conn.execute("SELECT count(*) FROM tgsis.conflict_regions").fetchone() == (0,)
        conn.rollback()
        state, _, _ = sqlstate(ed, "SELECT * FROM tgsis.mesh_merge_regions('e1', %s)", (fault,))
        assert state == "42501"
        # the owner's find_conflicts stores them; the role still sees none (the table's read policy)
        regions = sql_regions(conn, "e1", fault)
        assert len(regions) == 3
        conn.execute("SELECT FROM tgsis.find_conflicts('e1')")
        conn.commit()
        assert ed.execute("SELECT count(*) FROM tgsis.conflict_regions").fetchone() == (0,)
        ed.rollback()


def test_works_with_an_empty_search_path_and_a_refusal_stores_nothing(conn: Conn, fault: int) -> None:
    three_regions(conn, fault)
    conn.execute("SET search_path = ''")
    assert len(sql_regions(conn, "e1", fault)) == 3
    # a deletion on one side: no regions (the object merges as a whole only), the conflict stays
    with tgsis.in_version(conn, "DEFAULT"):
        tgsis.delete_feature(conn, "faults", fault)
    conn.commit()
    conn.execute("SET search_path = ''")
    assert sql_regions(conn, "e1", fault) == []
    state, message, _ = sqlstate(conn, "SELECT * FROM tgsis.mesh_merge_regions('e1', %s)", (fault,))
    assert state == "TG100" and "deleted" in message


_pairs = itertools.count()
_SHIFTS = [(0.0, 0.0, 1.5), (0.25, -0.5, 0.0), (-3.3, 7.77, 0.125)]
# one edit of a side: (kind, where, which shift or value)
_edit = st.tuples(
    st.sampled_from(["move", "move", "move", "porosity", "facies", "delete", "flip", "add"]),
    st.integers(0, 2 * (SIDE - 1) ** 2 - 1),
    st.integers(0, 2),
)


def _apply(conn: Conn, version: str, geoid: int, edits: list[tuple[str, int, int]], vp: str, cp: str) -> None:
    """A side's random edits as psql statements; vertices by a 3 x 3 patch around a grid point, so that the
    two sides' edits meet, touch or stay apart."""
    statements: list[tuple[str, tuple[Any, ...]]] = []
    for kind, where, which in edits:
        row, col = (where // 2) // (SIDE - 1), (where // 2) % (SIDE - 1)
        patch = [r * SIDE + c for r in range(row, min(row + 2, SIDE)) for c in range(col, min(col + 2, SIDE))]
        if kind == "move":
            dx, dy, dz = _SHIFTS[which]
            statements.append(
                (
                    "UPDATE tgsis.vrtx SET x = x + %s, y = y + %s, z = z + %s WHERE geoid = %s AND vrtxid = ANY (%s)",
                    (dx, dy, dz, geoid, patch[: which + 1]),
                )
            )
        elif kind == "porosity":
            statements.append(
                (f"UPDATE {vp} SET porosity = %s WHERE _geoid = %s AND _idx = %s", (0.5 + which, geoid, patch[0]))
            )
        elif kind == "facies":
            statements.append((f"UPDATE {cp} SET facies = %s WHERE _geoid = %s AND _idx = %s", (which, geoid, where)))
        elif kind == "delete":
            statements.append(("DELETE FROM tgsis.trgl WHERE geoid = %s AND trglid = %s", (geoid, where)))
        elif kind == "flip":
            statements.append(
                (
                    "UPDATE tgsis.trgl SET vrtxid1 = vrtxid2, vrtxid2 = vrtxid1 WHERE geoid = %s AND trglid = %s",
                    (geoid, where),
                )
            )
        else:  # a new vertex over a triangle and a triangle on it, with the next ids (both sides hand out the same)
            statements.append(
                (
                    "INSERT INTO tgsis.vrtx (geoid, vrtxid, x, y, z)"
                    " SELECT %s, max(vrtxid) + 1, 1000.0 * %s, -400.0, %s FROM tgsis.vrtx WHERE geoid = %s",
                    (geoid, col, float(which), geoid),
                )
            )
            statements.append(
                (
                    "INSERT INTO tgsis.trgl (geoid, trglid, vrtxid1, vrtxid2, vrtxid3)"
                    " SELECT %s, (SELECT max(trglid) + 1 FROM tgsis.trgl WHERE geoid = %s), %s, %s, max(vrtxid)"
                    "   FROM tgsis.vrtx WHERE geoid = %s",
                    (geoid, geoid, col, col + 1, geoid),
                )
            )
    psql(conn, version, *statements)


@settings(
    max_examples=12, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow]
)
@given(
    child=st.lists(_edit, min_size=1, max_size=4),
    parent=st.lists(_edit, min_size=1, max_size=4),
)
def test_random_edits_give_exactly_merge3s_regions(
    conn: Conn, fault: int, child: list[tuple[str, int, int]], parent: list[tuple[str, int, int]]
) -> None:
    n = next(_pairs)
    parent_version, child_version = f"hp{n}", f"hc{n}"
    tgsis.create_version(conn, parent_version)
    conn.commit()
    tgsis.create_version(conn, child_version, parent=parent_version)
    conn.commit()
    vp, cp = property_tables(conn, fault)
    _apply(conn, child_version, fault, child, vp, cp)
    _apply(conn, parent_version, fault, parent, vp, cp)
    conflicts = conn.execute("SELECT objectkey FROM tgsis.find_conflicts(%s)", (child_version,)).fetchall()
    conn.rollback()
    if conflicts:
        assert_same_regions(conn, child_version, fault)


def test_a_region_found_again_on_new_marks_is_stale_for_a_solution_given_by_its_old_number(
    conn: Conn, fault: int
) -> None:
    """SQL finds the regions again when either side edits the object; a psql resolve_region of a number seen
    before is refused (TG307), as another region may now have that number."""
    three_regions(conn, fault)
    (conflict,) = [r for r in sql_regions(conn, "e1", fault) if r["conflict"]]
    conn.execute("SELECT FROM tgsis.find_conflicts('e1')")
    conn.commit()
    move(conn, "DEFAULT", fault, [70], (0.0, 0.0, 0.25))
    conn.commit()
    state, message, _ = sqlstate(
        conn, "SELECT tgsis.resolve_region('e1', 'feature', %s, %s, 'child')", (str(fault), conflict["region"])
    )
    assert state == "TG307" and "changed since" in message
    # found again (the refusal rolled back), it takes the solution
    conn.execute("SELECT FROM tgsis.find_conflicts('e1')")
    conn.commit()
    (again,) = [r for r in sql_regions(conn, "e1", fault) if r["conflict"]]
    state, message, _ = sqlstate(
        conn, "SELECT tgsis.resolve_region('e1', 'feature', %s, %s, 'child')", (str(fault), again["region"])
    )
    assert state is None, message


# ---------------------------------------------------------------------------- step 2: solutions per object in SQL


def notices(conn: Conn) -> list[str]:
    said: list[str] = []
    conn.add_notice_handler(lambda d: said.append(str(d.message_primary)))
    return said


@pytest.mark.parametrize("solution", ["parent", "child", "base"])
def test_psql_resolve_all_regions_records_and_says_what_python_says(
    conn: Conn, solution: str, two_conflicts_clone: int
) -> None:
    fault = two_conflicts_clone
    from tgsis.db import regions as R

    # the oracle: Python's resolve_all_regions, rolled back
    with conn.transaction(force_rollback=True):
        python = tgsis.resolve_all_regions(conn, "e1", fault, solution)
    conn.rollback()
    expected = [R.side_discard_text(t) for t in python.totals] + [R.discard_text(d) for d in python.discards]
    conn.execute("DELETE FROM tgsis.conflict_regions")  # nobody ran the Python find_conflicts: SQL finds them
    conn.commit()
    said = notices(conn)
    rows = conn.execute(
        "SELECT region, solution, solved_by IS NOT NULL FROM tgsis.resolve_all_regions('e1', 'feature', %s, %s)",
        (str(fault), solution),
    ).fetchall()
    conn.commit()
    assert rows == [(r.region, solution, True) for r in python.regions]
    assert [s.split(": ", 1)[1] for s in said] == expected  # nothing else: no notice of the work tables
    solutions = conn.execute("SELECT conflict, solution FROM tgsis.conflict_regions ORDER BY region").fetchall()
    assert {s for c, s in solutions if not c} == {"automatic"}
    # taken back at once
    back = conn.execute(
        "SELECT solution FROM tgsis.resolve_all_regions('e1', 'feature', %s, 'unsolved')", (str(fault),)
    )
    assert [r[0] for r in back.fetchall()] == ["unsolved", "unsolved"]
    conn.rollback()


def test_psql_resolve_all_regions_refusals_record_nothing(conn: Conn, db_dsn: str, two_conflicts_clone: int) -> None:
    fault = two_conflicts_clone
    conn.execute("SELECT FROM tgsis.find_conflicts('e1')")
    conn.commit()
    before = conn.execute("SELECT r::text FROM tgsis.conflict_regions r ORDER BY region").fetchall()
    conn.commit()
    key = str(fault)
    state, message, hint = sqlstate(
        conn, "SELECT * FROM tgsis.resolve_all_regions('e1', 'feature', %s, 'average')", (key,)
    )
    assert state == "TG307" and f"tgsis version resolve e1 {key} average --region all" in (hint or ""), message
    state, _, _ = sqlstate(conn, "SELECT * FROM tgsis.resolve_all_regions('e1', 'feature', %s, 'manual')", (key,))
    assert state == "TG100"
    state, _, _ = sqlstate(conn, "SELECT * FROM tgsis.resolve_all_regions('e1', 'feature', %s, 'theirs')", (key,))
    assert state == "TG100"
    state, _, _ = sqlstate(conn, "SELECT * FROM tgsis.resolve_all_regions('e1', 'feature', %s, NULL)", (key,))
    assert state == "TG100"
    from tests.roles import login_roles

    with login_roles(db_dsn, {"rita": "tgsis_reader"}) as made:
        state, message, _ = sqlstate(
            made.connect("rita"), "SELECT * FROM tgsis.resolve_all_regions('e1', 'feature', %s, 'child')", (key,)
        )
        assert state == "TG002", message
    assert conn.execute("SELECT r::text FROM tgsis.conflict_regions r ORDER BY region").fetchall() == before
    conn.commit()
    # stale: the object changed since the regions were seen
    move(conn, "e1", fault, [70], (0.0, 0.0, 0.25))
    conn.commit()
    state, message, _ = sqlstate(conn, "SELECT * FROM tgsis.resolve_all_regions('e1', 'feature', %s, 'child')", (key,))
    assert state == "TG307" and "changed since" in message


def test_psql_resolve_all_regions_of_an_object_that_merges_by_itself(conn: Conn, fault: int) -> None:
    move(conn, "e1", fault, NORTH, (0.5, 0.0, 1.25))
    move(conn, "DEFAULT", fault, SOUTH, (-1.0, 0.0, -2.0))
    conn.commit()
    state, message, _ = sqlstate(
        conn, "SELECT * FROM tgsis.resolve_all_regions('e1', 'feature', %s, 'child')", (str(fault),)
    )
    assert state == "TG307" and "merges by itself" in message


def test_a_psql_merge_of_a_mesh_that_merges_by_region_names_the_merge_that_does_it(conn: Conn, fault: int) -> None:
    """No Python call: the SQL merge and refresh refuse (TG302) a mesh with a region conflict not solved (the
    regions are stored now, so the hint names the command that merges it by region); disjoint edits the SQL
    merge merges by region itself (tests/test_sql_merge_write.py)."""
    three_regions(conn, fault)
    for action in ("merge", "refresh"):
        state, message, hint = sqlstate(conn, f"SELECT tgsis.{action}_version('e1')", ())
        assert state == "TG302", message
        assert f"tgsis version {action} e1" in (hint or ""), hint


def test_saying_the_client_finds_the_regions_does_not_let_a_whole_side_drop_edits(conn: Conn, fault: int) -> None:
    three_regions(conn, fault)
    conn.execute("SET tgsis.region_detection = 'client'")
    conn.execute("SELECT FROM tgsis.find_conflicts('e1')")
    assert conn.execute("SELECT count(*) FROM tgsis.conflict_regions").fetchone() == (0,)  # left to the client
    state, message, _ = sqlstate(conn, "SELECT tgsis.resolve_conflict('e1', 'feature', %s, 'child')", (str(fault),))
    assert state == "TG307", message


def test_two_psql_sessions_finding_the_regions_at_once_store_them_once(conn: Conn, fault: int, db_dsn: str) -> None:
    """Two sessions run SQL find_conflicts at once (READ COMMITTED, as psql does): the second waits for the
    first's conflict rows, then sees its regions stored and stores none again; neither fails."""
    import threading

    three_regions(conn, fault)
    results: list[Any] = []
    barrier = threading.Barrier(2)

    def run() -> None:
        with psycopg.connect(db_dsn) as other:
            barrier.wait()
            try:
                other.execute("SELECT FROM tgsis.find_conflicts('e1')")
                other.commit()
                results.append("ok")
            except Exception as exc:  # noqa: BLE001 - reported below
                results.append(exc)

    threads = [threading.Thread(target=run) for _ in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert results == ["ok", "ok"]
    assert conn.execute("SELECT count(*), count(DISTINCT region) FROM tgsis.conflict_regions").fetchone() == (3, 3)
    conn.rollback()
    assert_same_regions(conn, "e1", fault)
