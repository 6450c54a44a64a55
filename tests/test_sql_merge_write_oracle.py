"""The psql merge by region against its oracle, the Python merge: the scenarios a hostile review added.

Property rows missing on one side, -0.0, NaN and infinite values, integer, boolean and
real property columns, a class whose properties are per cell, parts kept as a
cell property column, atoms on vertices the other side moved, a region solved
``base`` where both sides removed rows, a version that has a child version, a
merge that removes the version while regions are solved, a refresh after the
merge (tests/test_sql_merge_write.py has the set-up and the first scenarios).
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np
import psycopg
import pytest

import tgsis
from tests.merge_data import SIDE, curved_surface, move
from tests.test_sql_merge_regions import NORTH, SOUTH, property_tables, psql
from tests.test_sql_merge_write import assert_same_merge, both_merges, solve

Conn = psycopg.Connection[Any]


@pytest.fixture
def fault(conn: Conn, fault_clone: int) -> int:
    return fault_clone  # tests.merge_data.make_fault's (tests/conftest.py)


def _typed_fault(conn: Conn, alignment: str = "VERTEX") -> int:
    """The curved fault in a class with properties of every scalar type (per vertex, or per cell), version e1."""
    props = [
        tgsis.Property("k8", "bigint"),
        tgsis.Property("k4", "integer"),
        tgsis.Property("k2", "smallint"),
        tgsis.Property("ok", "boolean"),
        tgsis.Property("r4", "real"),
        tgsis.Property("r8", "double precision"),
    ]
    tgsis.create_feature_class(conn, "faults", "SURFACE", cell_properties=props, alignment=alignment)  # type: ignore[arg-type]
    tgsis.enable_feature_versioning(conn)
    surface = curved_surface()
    n = len(surface.vertices) if alignment == "VERTEX" else len(surface.cells)
    ids = np.arange(n)
    values = {
        "k8": ids.astype(np.int64) * 10_000_000_000,
        "k4": ids.astype(np.int32) * 3,
        "k2": (ids % 7).astype(np.int16),
        "ok": ids % 2 == 0,
        "r4": (ids / 7.0).astype(np.float32),
        "r8": ids / 3.0,
    }
    if alignment == "VERTEX":
        mesh = tgsis.Surface(surface.vertices, surface.cells, vertex_properties=values)
    else:
        mesh = tgsis.Surface(surface.vertices, surface.cells, cell_properties=values)
    geoid = tgsis.insert_feature(conn, "faults", mesh)
    tgsis.create_version(conn, "e1")
    conn.commit()
    return geoid


def test_property_rows_missing_null_minus_zero_and_nan_merge_as_in_python(conn: Conn, fault: int) -> None:
    vp, cp = property_tables(conn, fault)
    psql(
        conn,
        "e1",
        (f"DELETE FROM {vp} WHERE _geoid = %s AND _idx = 5", (fault,)),
        (f"UPDATE {vp} SET porosity = '-0' WHERE _geoid = %s AND _idx = 10", (fault,)),
        (f"UPDATE {vp} SET porosity = 'NaN' WHERE _geoid = %s AND _idx = 12", (fault,)),
        (f"UPDATE {vp} SET porosity = '-0' WHERE _geoid = %s AND _idx = 60", (fault,)),  # parent: 0
        (f"UPDATE {vp} SET porosity = 'NaN' WHERE _geoid = %s AND _idx = 70", (fault,)),  # parent: NaN too
        (f"UPDATE {vp} SET porosity = 0.5 WHERE _geoid = %s AND _idx = 80", (fault,)),  # parent: no row
        (f"DELETE FROM {cp} WHERE _geoid = %s AND _idx = 9", (fault,)),
    )
    move(conn, "e1", fault, NORTH, (0.125, -3.3, 7.77))
    psql(
        conn,
        "DEFAULT",
        (f"DELETE FROM {vp} WHERE _geoid = %s AND _idx IN (110, 80)", (fault,)),
        (f"UPDATE {vp} SET porosity = 'NaN' WHERE _geoid = %s AND _idx IN (120, 70)", (fault,)),
        (f"UPDATE {vp} SET porosity = 0 WHERE _geoid = %s AND _idx = 60", (fault,)),
        (f"UPDATE {vp} SET porosity = '-0' WHERE _geoid = %s AND _idx = 125", (fault,)),
        (f"DELETE FROM {cp} WHERE _geoid = %s AND _idx = 180", (fault,)),
    )
    move(conn, "DEFAULT", fault, SOUTH, (-1.1, 0.0, -2.9))
    solve(conn, "e1", fault, "child")  # 80: a value in the version, no row in the parent
    for action in ("merge", "refresh"):
        assert_same_merge(conn, "e1", action)


def _typed_edits(conn: Conn, geoid: int, alignment: str) -> None:
    vp = property_tables(conn, geoid)[0 if alignment == "VERTEX" else 1]
    psql(
        conn,
        "e1",
        (f"UPDATE {vp} SET k8 = -1234567890123, ok = NOT ok WHERE _geoid = %s AND _idx = 3", (geoid,)),
        (f"UPDATE {vp} SET k4 = -2147483648, r4 = '-0' WHERE _geoid = %s AND _idx = 4", (geoid,)),
        (f"UPDATE {vp} SET k2 = -1, r8 = 'NaN', ok = NOT ok WHERE _geoid = %s AND _idx = 6", (geoid,)),
        (f"DELETE FROM {vp} WHERE _geoid = %s AND _idx = 9", (geoid,)),
    )
    move(conn, "e1", geoid, NORTH, (0.125, -3.3, 7.77))
    psql(
        conn,
        "DEFAULT",
        (f"UPDATE {vp} SET k8 = 4503599627370496, r4 = 'NaN' WHERE _geoid = %s AND _idx = 130", (geoid,)),
        (f"UPDATE {vp} SET k4 = k4 + 1, r8 = '-0', ok = NOT ok WHERE _geoid = %s AND _idx = 131", (geoid,)),
        (f"UPDATE {vp} SET r4 = '-Infinity', r8 = 'Infinity' WHERE _geoid = %s AND _idx = 132", (geoid,)),
    )
    move(conn, "DEFAULT", geoid, SOUTH, (-1.1, 0.0, -2.9))


def test_integer_boolean_and_real_properties_per_vertex_merge_as_in_python(conn: Conn) -> None:
    geoid = _typed_fault(conn, "VERTEX")
    _typed_edits(conn, geoid, "VERTEX")
    for action in ("merge", "refresh"):
        assert_same_merge(conn, "e1", action)


def test_a_class_whose_properties_are_per_cell_merges_as_in_python(conn: Conn) -> None:
    geoid = _typed_fault(conn, "CELL")
    _typed_edits(conn, geoid, "CELL")
    solve(conn, "e1", geoid, "parent")
    for action in ("merge", "refresh"):
        assert_same_merge(conn, "e1", action)


def test_parts_kept_as_a_cell_property_column_merge_as_in_python(conn: Conn) -> None:
    tgsis.create_feature_class(
        conn, "faults", "SURFACE", cell_properties=[tgsis.Property("part", "bigint", alignment="CELL")]
    )
    tgsis.enable_feature_versioning(conn)
    surface = curved_surface()
    parted = tgsis.Surface(
        surface.vertices, surface.cells, cell_properties={"part": (np.arange(len(surface.cells)) % 3).astype(np.int64)}
    )
    geoid = tgsis.insert_feature(conn, "faults", parted)
    tgsis.create_version(conn, "e1")
    conn.commit()
    cp = property_tables(conn, geoid)[1]
    n, m = SIDE * SIDE, 2 * (SIDE - 1) ** 2
    psql(conn, "DEFAULT", (f"UPDATE {cp} SET part = 7 WHERE _geoid = %s AND _idx BETWEEN 150 AND 160", (geoid,)))
    move(conn, "e1", geoid, NORTH, (0.125, -3.3, 7.77))
    psql(
        conn,
        "e1",
        ("DELETE FROM tgsis.trgl WHERE geoid = %s AND trglid = 3", (geoid,)),
        ("INSERT INTO tgsis.vrtx (geoid, vrtxid, x, y, z) VALUES (%s, %s, 50.0, -300.0, 0.0)", (geoid, n)),
        ("INSERT INTO tgsis.trgl (geoid, trglid, vrtxid1, vrtxid2, vrtxid3) VALUES (%s, %s, 1, 0, %s)", (geoid, m, n)),
        (f"INSERT INTO {cp} (_geoid, _idx, part) VALUES (%s, %s, 4)", (geoid, m)),
    )
    for action in ("merge", "refresh"):
        assert_same_merge(conn, "e1", action)


def test_atoms_on_vertices_the_other_side_moved_merge_as_in_python(conn: Conn, fault: int) -> None:

    atom = "INSERT INTO tgsis.atom (geoid, vrtxid, refid, patom) VALUES (%s, %s, %s, %s)"
    n, m = SIDE * SIDE, 2 * (SIDE - 1) ** 2
    psql(
        conn,
        "e1",
        (atom, (fault, 130, 131, False)),  # on the parent's moved SOUTH
        ("INSERT INTO tgsis.vrtx (geoid, vrtxid, x, y, z) VALUES (%s, %s, 9000.0, 2000.0, 1.0)", (fault, n)),
        (
            "INSERT INTO tgsis.trgl (geoid, trglid, vrtxid1, vrtxid2, vrtxid3) VALUES (%s, %s, %s, %s, %s)",
            (fault, m, SIDE - 1, 2 * SIDE - 1, n),
        ),
    )
    move(conn, "DEFAULT", fault, SOUTH, (-1.1, 0.0, -2.9))
    psql(
        conn,
        "DEFAULT",
        (atom, (fault, 3, 4, False)),  # on the child's moved NORTH
        ("INSERT INTO tgsis.vrtx (geoid, vrtxid, x, y, z) VALUES (%s, %s, -500.0, 2000.0, 1.0)", (fault, n)),
        (
            "INSERT INTO tgsis.trgl (geoid, trglid, vrtxid1, vrtxid2, vrtxid3) VALUES (%s, %s, %s, %s, %s)",
            (fault, m, SIDE * (SIDE - 1), SIDE * (SIDE - 2), n),
        ),
    )
    move(conn, "e1", fault, NORTH, (0.125, -3.3, 7.77))
    solve(conn, "e1", fault, "child")  # an atom on a vertex the other side moved is a conflict
    for action in ("merge", "refresh"):
        assert_same_merge(conn, "e1", action)


@pytest.mark.parametrize("edit", ["changed", "removed"])
def test_a_property_the_parent_changed_is_noted_by_the_merge_as_in_python(conn: Conn, fault: int, edit: str) -> None:
    """The merge writes the parent's property edits into the version and notes the property tables there, in
    SQL as in Python, the class's property tables in rows or in chunks: values changed, or every row of the
    object removed (in chunks its chunks are closed, nothing inserted: only the writer's own note says it). The
    counterpart of the test above, where a merged edit that leaves the property chunks as they were notes
    nothing."""
    vp, cp = property_tables(conn, fault)
    move(conn, "e1", fault, NORTH, (0.125, -3.3, 7.77))
    if edit == "changed":
        psql(
            conn,
            "DEFAULT",
            (f"UPDATE {vp} SET porosity = 0.75 WHERE _geoid = %s AND _idx = 130", (fault,)),
            (f"UPDATE {cp} SET facies = 9 WHERE _geoid = %s AND _idx = 200", (fault,)),
        )
    else:
        psql(
            conn,
            "DEFAULT",
            (f"DELETE FROM {vp} WHERE _geoid = %s", (fault,)),
            (f"DELETE FROM {cp} WHERE _geoid = %s", (fault,)),
        )
    move(conn, "DEFAULT", fault, SOUTH, (-1.1, 0.0, -2.9))
    conn.commit()
    if edit == "removed":
        solve(conn, "e1", fault, "parent")  # every vertex's value changed: one region, met by the child's move
    (working,) = conn.execute(
        "SELECT workingrevision FROM tgsis.versions WHERE versionid = tgsis.version_id('e1')"
    ).fetchone()  # type: ignore[misc]
    conn.rollback()
    mine = assert_same_merge(conn, "e1", "merge")
    noted = {(r[1], r[2]) for r in mine[2]["tgsis.revision_objects"] if r[0] == str(working) and r[3] == str(fault)}
    tables = {tuple(t.replace('"', "").split(".")) for t in (vp, cp)}
    assert tables <= noted, (tables, noted)


def test_a_region_solved_base_where_both_sides_removed_rows_merges_as_in_python(conn: Conn, fault: int) -> None:
    vp, cp = property_tables(conn, fault)
    for version, dz in (("e1", 5.0), ("DEFAULT", -4.0)):
        psql(
            conn,
            version,
            ("UPDATE tgsis.vrtx SET z = z + %s WHERE geoid = %s AND vrtxid IN (64, 65, 66)", (dz, fault)),
            ("DELETE FROM tgsis.trgl WHERE geoid = %s AND trglid = 110", (fault,)),
            (f"DELETE FROM {vp} WHERE _geoid = %s AND _idx = 65", (fault,)),
            (f"DELETE FROM {cp} WHERE _geoid = %s AND _idx = 111", (fault,)),
        )
    solve(conn, "e1", fault, "base")
    for action in ("merge", "refresh"):
        assert_same_merge(conn, "e1", action)


def test_merge_removing_the_version_while_regions_are_solved_as_in_python(conn: Conn, fault: int) -> None:
    move(conn, "e1", fault, NORTH, (0.125, -3.3, 7.77))
    move(conn, "e1", fault, [64, 65, 66], (0.0, 0.0, 5.0))
    move(conn, "DEFAULT", fault, [66, 67], (0.0, 0.0, -4.0))
    conn.commit()
    solve(conn, "e1", fault, "child")
    assert_same_merge(conn, "e1", "merge", remove=True)


def test_a_version_with_a_child_version_of_its_own_merges_as_in_python(conn: Conn, fault: int) -> None:
    tgsis.create_version(conn, "e2", parent="e1")
    conn.commit()
    move(conn, "e2", fault, [30, 31], (0.0, 1.0, 0.0))
    move(conn, "e1", fault, NORTH, (0.125, -3.3, 7.77))
    move(conn, "e1", fault, [64, 65, 66], (0.0, 0.0, 5.0))
    move(conn, "DEFAULT", fault, [66, 67], (0.0, 0.0, -4.0))
    move(conn, "DEFAULT", fault, SOUTH, (-1.1, 0.0, -2.9))
    conn.commit()
    solve(conn, "e1", fault, "parent")
    for action in ("merge", "refresh"):
        assert_same_merge(conn, "e1", action)
    conn.execute("SELECT tgsis.merge_version('e1')")
    conn.commit()
    move(conn, "e2", fault, SOUTH, (0.0, 0.0, 1.5))  # moves the parent's moved vertices again
    move(conn, "e1", fault, [30, 31, 32], (0.0, 0.5, 0.0))
    conn.commit()
    solve(conn, "e2", fault, "child")
    for action in ("merge", "refresh"):
        assert_same_merge(conn, "e2", action)


def test_a_refresh_after_a_psql_merge_by_region_as_in_python(conn: Conn, fault: int) -> None:
    move(conn, "e1", fault, NORTH, (0.125, -3.3, 7.77))
    move(conn, "DEFAULT", fault, SOUTH, (-1.1, 0.0, -2.9))
    conn.execute("SELECT tgsis.merge_version('e1')")
    conn.commit()
    move(conn, "e1", fault, [64, 65], (0.0, 0.0, 2.0))
    move(conn, "DEFAULT", fault, [65, 66], (0.0, 0.0, -3.0))
    move(conn, "DEFAULT", fault, NORTH, (0.0, 0.0, -3.0))
    conn.commit()
    solve(conn, "e1", fault, "child")
    assert_same_merge(conn, "e1", "refresh")
    conn.execute("SELECT tgsis.refresh_version('e1')")
    conn.commit()
    move(conn, "e1", fault, [100], (0.0, 0.0, 2.0))
    assert_same_merge(conn, "e1", "merge")


def test_the_region_detection_setting_is_put_back_after_a_psql_merge(conn: Conn, fault: int) -> None:
    move(conn, "e1", fault, NORTH, (0.125, -3.3, 7.77))
    move(conn, "DEFAULT", fault, SOUTH, (-1.1, 0.0, -2.9))
    conn.commit()
    for scope in ("SESSION", "LOCAL"):
        with conn.transaction(force_rollback=True):
            conn.execute(f"SET {scope} tgsis.region_detection = 'sql'")
            conn.execute("SELECT tgsis.merge_version('e1')")
            after = conn.execute("SELECT current_setting('tgsis.region_detection', true)").fetchone()
            assert after == ("sql",), scope
        conn.rollback()
        conn.execute("RESET tgsis.region_detection")
        conn.commit()


def test_bigint_values_beyond_two_to_the_53_are_merged_exactly_by_python_and_sql(conn: Conn) -> None:
    """A state with a missing property row read its integer columns as float64 (NaN for the row): 2**63 - 1
    came back -2**63, 2**53 + 1 came back 2**53, written so into the parent without a word."""
    geoid = _typed_fault(conn, "VERTEX")
    vp = property_tables(conn, geoid)[0]
    big = {130: 2**63 - 1, 131: 2**53 + 1, 132: -(2**62) - 3}
    n = SIDE * SIDE
    add = "INSERT INTO tgsis.vrtx (geoid, vrtxid, x, y, z) VALUES (%s, %s, 50.0, -300.0, 0.0)"
    row = f"INSERT INTO {vp} (_geoid, _idx, k8, k4, k2, ok, r4, r8) VALUES (%s, %s, %s, 1, 1, true, 1, 1)"
    # both add a vertex at one place, of values that differ only beyond float64: not the same vertex
    psql(conn, "e1", (add, (geoid, n)), (row, (geoid, n, 2**53 + 1)))
    psql(conn, "e1", (f"DELETE FROM {vp} WHERE _geoid = %s AND _idx = 9", (geoid,)))  # a row missing in the child
    move(conn, "e1", geoid, NORTH, (0.125, -3.3, 7.77))
    psql(
        conn,
        "DEFAULT",
        *((f"UPDATE {vp} SET k8 = %s WHERE _geoid = %s AND _idx = %s", (v, geoid, i)) for i, v in big.items()),
        (add, (geoid, n)),
        (row, (geoid, n, 2**53)),
        (f"DELETE FROM {vp} WHERE _geoid = %s AND _idx = 140", (geoid,)),
    )
    move(conn, "DEFAULT", geoid, SOUTH, (-1.1, 0.0, -2.9))
    assert_same_merge(conn, "e1", "refresh")
    assert_same_merge(conn, "e1", "merge")
    tgsis.merge_version(conn, "e1")
    conn.commit()
    for version in ("DEFAULT", "e1"):
        with tgsis.in_version(conn, version):
            rows = conn.execute(f"SELECT _idx, k8 FROM {vp} WHERE _geoid = %s AND _idx = ANY (%s)", (geoid, list(big)))
            assert dict(rows.fetchall()) == big, version
            added = conn.execute(
                f"SELECT p.k8 FROM tgsis.vrtx v JOIN {vp} p ON p._geoid = v.geoid AND p._idx = v.vrtxid"
                " WHERE v.geoid = %s AND v.x = 50 AND v.y = -300 ORDER BY 1",
                (geoid,),
            ).fetchall()
            assert added == [(2**53,), (2**53 + 1,)], version
        conn.rollback()


def test_a_class_in_a_schema_of_an_odd_name_and_odd_attribute_values_merge_as_in_python(conn: Conn) -> None:
    conn.execute('CREATE SCHEMA "Odd ""Schema"""')
    tgsis.create_feature_class(
        conn,
        "faults",
        "SURFACE",
        schema='Odd "Schema"',
        cell_properties=[tgsis.Property("porosity", "double precision")],
    )
    tgsis.enable_feature_versioning(conn)
    surface = curved_surface()
    mesh = tgsis.Surface(
        surface.vertices, surface.cells, vertex_properties={"porosity": np.linspace(0.1, 0.3, SIDE * SIDE)}
    )
    geoid = tgsis.insert_feature(conn, "faults", mesh)
    tgsis.create_version(conn, "e1")
    conn.commit()
    vp = property_tables(conn, geoid)[0]
    move(conn, "e1", geoid, NORTH, (0.125, -3.3, 7.77))
    move(conn, "e1", geoid, [64, 65, 66], (0.0, 0.0, 5.0))
    psql(conn, "e1", (f"UPDATE {vp} SET porosity = 2 WHERE _geoid = %s AND _idx = 3", (geoid,)))
    move(conn, "DEFAULT", geoid, [66, 67], (0.0, 0.0, -4.0))
    psql(
        conn,
        "DEFAULT",
        (f"UPDATE {vp} SET porosity = 3 WHERE _geoid = %s AND _idx = 140", (geoid,)),
        ("UPDATE tgsis.geometry SET colorred = 0.25, geoname = 'it''s; \"odd\"' WHERE geoid = %s", (geoid,)),
    )
    solve(conn, "e1", geoid, "child")
    for action in ("merge", "refresh"):
        assert_same_merge(conn, "e1", action)


def test_a_region_solution_changed_by_another_session_during_a_psql_merge_is_not_lost(
    conn: Conn, fault: int, db_dsn: str
) -> None:
    """The resolver records 'parent' (not committed yet) where 'child' was recorded; the merge started then
    must merge with what the resolver commits, or fail: never apply 'child' over the resolver's success."""
    from tests.sessions import Background, connect

    move(conn, "e1", fault, [64, 65, 66], (0.0, 0.0, 5.0))
    move(conn, "DEFAULT", fault, [66, 67], (0.0, 0.0, -4.0))
    conn.commit()
    solve(conn, "e1", fault, "child")
    parent_z = conn.execute(
        "SELECT z FROM tgsis.vrtx WHERE geoid = %s AND vrtxid IN (66, 67) ORDER BY vrtxid", (fault,)
    ).fetchall()
    conn.commit()
    resolver = connect(db_dsn, "resolver")
    (region,) = resolver.execute(
        "SELECT region FROM tgsis.conflict_regions WHERE versionid = tgsis.version_id('e1') AND conflict"
    ).fetchone()  # type: ignore[misc]
    resolver.execute("SELECT tgsis.resolve_region('e1', 'feature', %s, %s, 'parent')", (str(fault), region))
    merger = Background(db_dsn, "merger", lambda c: c.execute("SELECT tgsis.merge_version('e1')"))
    time.sleep(1.0)
    resolver.commit()
    resolver.close()
    try:
        merger.finish()
    except psycopg.Error:
        return  # refused: the resolver's solution stands, nothing merged
    z = conn.execute("SELECT z FROM tgsis.vrtx WHERE geoid = %s AND vrtxid IN (66, 67) ORDER BY vrtxid", (fault,))
    assert z.fetchall() == parent_z  # the solution the resolver was told it recorded


def test_a_region_resolved_while_a_psql_merge_holds_the_version_fails_once_it_is_merged(
    conn: Conn, fault: int, db_dsn: str
) -> None:
    from tests.sessions import Background, connect, wait_until_blocked

    move(conn, "e1", fault, [64, 65, 66], (0.0, 0.0, 5.0))
    move(conn, "DEFAULT", fault, [66, 67], (0.0, 0.0, -4.0))
    conn.commit()
    solve(conn, "e1", fault, "child")
    (region,) = conn.execute(
        "SELECT region FROM tgsis.conflict_regions WHERE versionid = tgsis.version_id('e1') AND conflict"
    ).fetchone()  # type: ignore[misc]
    conn.commit()
    merger = connect(db_dsn, "merger")
    merger.execute("SELECT tgsis.merge_version('e1')")
    resolver = Background(
        db_dsn,
        "resolver",
        lambda c: c.execute("SELECT tgsis.resolve_region('e1', 'feature', %s, %s, 'parent')", (str(fault), region)),
    )
    wait_until_blocked(conn, resolver.pid, merger.info.backend_pid)
    merger.commit()
    merger.close()
    try:
        resolver.finish()
    except psycopg.Error as exc:
        assert exc.sqlstate in ("TG200", "TG300", "TG307"), exc
    left = conn.execute("SELECT count(*) FROM tgsis.conflict_regions WHERE versionid = tgsis.version_id('e1')")
    assert left.fetchone() == (0,)  # no solution recorded for a conflict the merge settled


def test_coordinates_of_minus_zero_merge_as_in_python(conn: Conn, fault: int) -> None:
    psql(
        conn,
        "e1",
        ("UPDATE tgsis.vrtx SET z = '-0' WHERE geoid = %s AND vrtxid IN (0, 1)", (fault,)),
        ("UPDATE tgsis.vrtx SET x = '-0' WHERE geoid = %s AND vrtxid = 30", (fault,)),
    )
    psql(conn, "DEFAULT", ("UPDATE tgsis.vrtx SET z = 0 WHERE geoid = %s AND vrtxid IN (1, 130)", (fault,)))
    for action in ("merge", "refresh"):
        assert_same_merge(conn, "e1", action)


@pytest.mark.parametrize(("side", "value"), [("DEFAULT", "NaN"), ("e1", "Infinity"), ("e1", "-Infinity")])
def test_non_finite_coordinates_are_refused_as_python_refuses_them(
    conn: Conn, fault: int, side: str, value: str
) -> None:
    """merge3 takes no state with non-finite coordinates: the Python merge refuses it (TG302); the psql merge
    merged it and wrote the NaN into the parent."""
    move(conn, "e1", fault, NORTH, (0.125, -3.3, 7.77))
    move(conn, "DEFAULT", fault, SOUTH, (-1.1, 0.0, -2.9))
    psql(conn, side, ("UPDATE tgsis.vrtx SET y = %s::float8 WHERE geoid = %s AND vrtxid = 70", (value, fault)))
    for action in ("merge", "refresh"):
        theirs, mine = both_merges(conn, "e1", action)
        assert theirs[:2] == ("refused", "TG302"), theirs
        assert mine[:2] == theirs[:2], mine
        assert "vertices 70 have non-finite coordinates" in theirs[2] and "vertices 70 have non-finite" in mine[2]


def test_parent_new_cells_and_atoms_on_an_id_the_childs_new_vertex_is_renumbered_from(conn: Conn, fault: int) -> None:
    vp, cp = property_tables(conn, fault)
    n, m = SIDE * SIDE, 2 * (SIDE - 1) ** 2
    add = "INSERT INTO tgsis.vrtx (geoid, vrtxid, x, y, z) VALUES (%s, %s, %s, %s, %s)"
    tri = "INSERT INTO tgsis.trgl (geoid, trglid, vrtxid1, vrtxid2, vrtxid3) VALUES (%s, %s, %s, %s, %s)"
    atom = "INSERT INTO tgsis.atom (geoid, vrtxid, refid, patom) VALUES (%s, %s, %s, %s)"
    psql(
        conn,
        "e1",
        (add, (fault, n, 9000.0, 2000.0, 1.0)),  # renumbered: the parent's n is elsewhere
        (tri, (fault, m, SIDE - 1, 2 * SIDE - 1, n)),
        (f"INSERT INTO {vp} (_geoid, _idx, porosity) VALUES (%s, %s, 0.375)", (fault, n)),
        (atom, (fault, 20, n, False)),
    )
    psql(
        conn,
        "DEFAULT",
        (add, (fault, n, -500.0, 2000.0, 1.0)),
        (add, (fault, n + 1, -600.0, 2100.0, 1.0)),
        (tri, (fault, m, SIDE * (SIDE - 1), SIDE * (SIDE - 2), n)),
        (tri, (fault, m + 1, SIDE * (SIDE - 2), n, n + 1)),
        (f"INSERT INTO {cp} (_geoid, _idx, facies) VALUES (%s, %s, 2)", (fault, m + 1)),
        (atom, (fault, n + 1, n, False)),
        (atom, (fault, 130, n, False)),
    )
    move(conn, "DEFAULT", fault, SOUTH, (-1.1, 0.0, -2.9))
    for action in ("merge", "refresh"):
        assert_same_merge(conn, "e1", action)


def test_regions_stored_unsolved_then_the_overlap_undone_merge_as_in_python(conn: Conn, fault: int) -> None:
    """Regions stored with a conflict (psql find_conflicts), then the version takes its overlapping edit
    back: the stored regions are stale; both merges find the regions of now, which merge by themselves."""
    move(conn, "e1", fault, NORTH, (0.125, -3.3, 7.77))
    move(conn, "e1", fault, [64, 65, 66], (0.0, 0.0, 5.0))
    move(conn, "DEFAULT", fault, [66, 67], (0.0, 0.0, -4.0))
    conn.commit()
    conn.execute("SELECT FROM tgsis.find_conflicts('e1')")
    conn.commit()
    assert conn.execute("SELECT count(*) FROM tgsis.conflict_regions WHERE conflict").fetchone() == (1,)
    conn.commit()
    move(conn, "e1", fault, [64, 65, 66], (0.0, 0.0, -5.0))  # back where they were (up to rounding)
    # the stored row versions of revision 0 (<table>_ver, or the decoded chunk versions)
    (stored,) = conn.execute("SELECT tgsis.storage_row_versions('tgsis', 'vrtx')").fetchone()  # type: ignore[misc]
    conn.commit()
    psql(
        conn,
        "e1",
        (
            f"UPDATE tgsis.vrtx v SET z = b.z FROM {stored} b WHERE v.geoid = %s AND v.vrtxid IN (64, 65, 66)"
            " AND b.geoid = v.geoid AND b.vrtxid = v.vrtxid AND b.revision = 0",
            (fault,),
        ),
    )
    for action in ("merge", "refresh"):
        assert_same_merge(conn, "e1", action)


def test_a_refusal_after_another_feature_merged_by_region_leaves_nothing_written(conn: Conn) -> None:
    from tests.test_sql_merge_write import everything

    tgsis.create_feature_class(conn, "faults", "SURFACE")
    tgsis.enable_feature_versioning(conn)
    plain = curved_surface()
    first, second = (tgsis.insert_feature(conn, "faults", tgsis.Surface(plain.vertices, plain.cells)) for _ in range(2))
    tgsis.create_version(conn, "e1")
    conn.commit()
    for geoid in (first, second):
        move(conn, "e1", geoid, NORTH, (0.125, -3.3, 7.77))
        move(conn, "DEFAULT", geoid, SOUTH, (-1.1, 0.0, -2.9))
    psql(conn, "DEFAULT", ("UPDATE tgsis.vrtx SET y = 'NaN' WHERE geoid = %s AND vrtxid = 70", (second,)))
    before = everything(conn)
    conn.commit()
    for action in ("merge", "refresh"):
        theirs, mine = both_merges(conn, "e1", action)
        assert theirs[:2] == mine[:2] == ("refused", "TG302"), (theirs, mine)
        with pytest.raises(psycopg.Error):
            conn.execute(f"SELECT tgsis.{action}_version('e1')")
        conn.rollback()
        assert everything(conn) == before
        conn.rollback()
