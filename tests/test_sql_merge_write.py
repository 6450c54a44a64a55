"""The merge by region written in SQL: a psql user's tgsis.merge_version / refresh_version (issue 39, items 2 and 5).

The oracle is the Python merge (``tgsis.merge_version(conn, v)``): from one
committed state the Python merge runs in a transaction rolled back (the
revision sequence put back), then the psql ``SELECT tgsis.merge_version(v)``;
every row version of the feature's storage, the revision notes, the versions,
conflicts and regions afterwards must be the same (timestamps aside), and so
must the rows counted and the refusals (SQLSTATE).
"""

from __future__ import annotations

import itertools
import time
from collections.abc import Callable, Mapping
from typing import Any

import psycopg
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from psycopg import sql

import tgsis
from tests.merge_data import SIDE, curved_surface, move, moved, stored_state
from tests.storage_data import storage_of
from tests.test_sql_merge_regions import MIDDLE, NORTH, SOUTH, _apply, _edit, property_tables, psql

Conn = psycopg.Connection[Any]

_TIMES = ("timestamp with time zone", "timestamp without time zone")


@pytest.fixture
def fault(conn: Conn, fault_clone: int) -> int:
    return fault_clone  # tests.merge_data.make_fault's (tests/conftest.py)


def everything(conn: Conn) -> dict[str, list[tuple[str, ...]]]:
    """Every row version of the feature storage and the versioning catalog, as exact text (timestamps left out)."""
    conn.execute("SET LOCAL extra_float_digits = 1")
    tables = [
        str(r[0])
        for r in conn.execute(
            "SELECT tgsis.storage_table(schemaname, tablename) FROM tgsis.versioned_tables"
            " WHERE objectclass = 'feature' ORDER BY 1"
        ).fetchall()
    ]
    tables += ["tgsis.revision_objects", "tgsis.versions", "tgsis.conflicts", "tgsis.conflict_regions"]
    found: dict[str, list[tuple[str, ...]]] = {}
    # every table's columns in one query (one per table cost about 30 round trips per call: 4-5 % of the merge files)
    named: dict[str, list[str]] = {
        str(t): [str(c) for c in cs]
        for t, cs in conn.execute(
            "SELECT t.name, array_agg(a.attname::text ORDER BY a.attnum) FROM unnest(%s::text[]) AS t(name)"
            " JOIN pg_attribute a ON a.attrelid = t.name::regclass AND a.attnum > 0 AND NOT a.attisdropped"
            " AND format_type(a.atttypid, a.atttypmod) <> ALL (%s) GROUP BY t.name",
            (tables, list(_TIMES)),
        ).fetchall()
    }
    for table in tables:
        columns = named[table]
        rows = conn.execute(
            sql.SQL("SELECT {} FROM {}").format(
                sql.SQL(", ").join(sql.SQL("{}::text").format(sql.Identifier(c)) for c in columns), sql.SQL(table)
            )
        ).fetchall()
        found[table] = sorted(tuple("\\N" if v is None else v for v in r) for r in rows)
    return found


def _outcome(conn: Conn, run: Callable[[], int]) -> tuple[Any, ...]:
    """(rows counted, everything after) of a merge, or (SQLSTATE, message) of its refusal; rolled back."""
    notices: list[str] = []
    conn.add_notice_handler(lambda d: notices.append(str(d.message_primary)))
    try:
        with conn.transaction(force_rollback=True):
            rows = run()
            return ("done", rows, everything(conn))
    except psycopg.Error as exc:
        return ("refused", exc.sqlstate, str(exc))
    except tgsis.Error as exc:
        return ("refused", exc.sqlstate, str(exc))
    finally:
        conn.rollback()


def both_merges(
    conn: Conn, version: str, action: str = "merge", remove: bool = False
) -> tuple[tuple[Any, ...], tuple[Any, ...]]:
    """(Python's outcome, SQL's outcome) of the same merge or refresh from the same committed state."""
    conn.commit()
    seq = conn.execute("SELECT last_value, is_called FROM tgsis.revision_seq").fetchone()
    conn.commit()

    def python() -> int:
        if action == "merge":
            return int(tgsis.merge_version(conn, version, remove=remove))
        return int(tgsis.refresh_version(conn, version))

    def psql_merge() -> int:
        if action == "merge":
            row = conn.execute("SELECT tgsis.merge_version(%s, %s)", (version, remove)).fetchone()
        else:
            row = conn.execute("SELECT tgsis.refresh_version(%s)", (version,)).fetchone()
        assert row is not None
        return int(row[0])

    theirs = _outcome(conn, python)
    conn.execute("SELECT setval('tgsis.revision_seq', %s, %s)", seq)
    conn.commit()
    mine = _outcome(conn, psql_merge)
    conn.execute("SELECT setval('tgsis.revision_seq', %s, %s)", seq)
    conn.commit()
    return theirs, mine


def assert_same_merge(conn: Conn, version: str, action: str = "merge", remove: bool = False) -> tuple[Any, ...]:
    theirs, mine = both_merges(conn, version, action, remove)
    assert theirs[0] == "done", theirs
    assert mine[0] == "done", mine
    assert mine[1] == theirs[1]  # rows counted
    for table in theirs[2]:
        assert mine[2][table] == theirs[2][table], table
    return mine


def solve(conn: Conn, version: str, geoid: int, solution: str) -> None:
    """Record ``solution`` for every conflicting region, as a psql user does (committed)."""
    conn.execute("SELECT FROM tgsis.find_conflicts(%s)", (version,))
    regions = conn.execute(
        "SELECT region FROM tgsis.conflict_regions WHERE versionid = tgsis.version_id(%s) AND objectkey = %s"
        " AND conflict ORDER BY region",
        (version, str(geoid)),
    ).fetchall()
    assert regions
    for (region,) in regions:
        conn.execute("SELECT tgsis.resolve_region(%s, 'feature', %s, %s, %s)", (version, str(geoid), region, solution))
    conn.commit()


# ---------------------------------------------------------------------------- merges that write, against Python


@pytest.mark.parametrize(("action", "remove"), [("merge", False), ("merge", True), ("refresh", False)])
def test_disjoint_moves_merge_in_psql_exactly_as_in_python(conn: Conn, fault: int, action: str, remove: bool) -> None:
    move(conn, "e1", fault, NORTH, (0.125, -3.3, 7.77))
    move(conn, "DEFAULT", fault, SOUTH, (-1.1, 0.0, -2.9))
    assert_same_merge(conn, "e1", action, remove)


@pytest.mark.parametrize("solution", ["parent", "child", "base"])
@pytest.mark.parametrize("action", ["merge", "refresh"])
def test_a_conflicting_region_solved_in_psql_merges_as_in_python(
    conn: Conn, fault: int, solution: str, action: str
) -> None:
    move(conn, "e1", fault, NORTH, (0.125, -3.3, 7.77))  # merges by itself
    move(conn, "e1", fault, [64, 65, 66], (0.0, 0.0, 5.0))  # overlaps the parent's edit at 66
    move(conn, "DEFAULT", fault, [66, 67], (0.0, 0.0, -4.0))
    move(conn, "DEFAULT", fault, SOUTH, (-1.1, 0.0, -2.9))
    conn.commit()
    solve(conn, "e1", fault, solution)
    assert_same_merge(conn, "e1", action)


def test_new_vertices_and_cells_with_clashing_ids_removed_cells_and_property_edits(conn: Conn, fault: int) -> None:
    """Both sides hand out the same new ids (the child's that are not the parent's content are renumbered above
    every id, their cells and property rows follow); cells removed; vertex and cell property values changed."""
    vp, cp = property_tables(conn, fault)
    n, m = SIDE * SIDE, 2 * (SIDE - 1) ** 2
    add = "INSERT INTO tgsis.vrtx (geoid, vrtxid, x, y, z) VALUES (%s, %s, %s, %s, %s)"
    tri = "INSERT INTO tgsis.trgl (geoid, trglid, vrtxid1, vrtxid2, vrtxid3) VALUES (%s, %s, %s, %s, %s)"
    psql(
        conn,
        "e1",
        (add, (fault, n, 50.0, -300.0, 0.0)),  # the same vertex and triangle as the parent's n, m
        (tri, (fault, m, 1, 0, n)),
        (f"INSERT INTO {vp} (_geoid, _idx, porosity) VALUES (%s, %s, 0.125)", (fault, n)),
        (f"INSERT INTO {cp} (_geoid, _idx, facies) VALUES (%s, %s, 3)", (fault, m)),
        (add, (fault, n + 1, 9000.0, 2000.0, 1.0)),  # the parent's n + 1 is elsewhere: renumbered
        (tri, (fault, m + 1, SIDE - 1, 2 * SIDE - 1, n + 1)),
        (f"INSERT INTO {vp} (_geoid, _idx, porosity) VALUES (%s, %s, 0.375)", (fault, n + 1)),
        (f"INSERT INTO {cp} (_geoid, _idx, facies) VALUES (%s, %s, 4)", (fault, m + 1)),
        ("DELETE FROM tgsis.trgl WHERE geoid = %s AND trglid = 60", (fault,)),
        (f"UPDATE {vp} SET porosity = porosity * 2 WHERE _geoid = %s AND _idx IN (30, 31)", (fault,)),
    )
    psql(
        conn,
        "DEFAULT",
        (add, (fault, n, 50.0, -300.0, 0.0)),
        (tri, (fault, m, 1, 0, n)),
        (f"INSERT INTO {vp} (_geoid, _idx, porosity) VALUES (%s, %s, 0.125)", (fault, n)),
        (f"INSERT INTO {cp} (_geoid, _idx, facies) VALUES (%s, %s, 3)", (fault, m)),
        (add, (fault, n + 1, -500.0, 2000.0, 1.0)),
        (tri, (fault, m + 1, SIDE * (SIDE - 1), SIDE * (SIDE - 2), n + 1)),
        (f"INSERT INTO {vp} (_geoid, _idx, porosity) VALUES (%s, %s, 0.5)", (fault, n + 1)),
        (f"INSERT INTO {cp} (_geoid, _idx, facies) VALUES (%s, %s, 1)", (fault, m + 1)),
        ("DELETE FROM tgsis.trgl WHERE geoid = %s AND trglid = 161", (fault,)),
        (f"UPDATE {cp} SET facies = 9 WHERE _geoid = %s AND _idx IN (150, 151)", (fault,)),
        (f"DELETE FROM {vp} WHERE _geoid = %s AND _idx = 101", (fault,)),
    )
    for action in ("merge", "refresh"):
        assert_same_merge(conn, "e1", action)


def test_a_vertex_removed_by_the_parent_that_the_childs_new_triangle_uses(conn: Conn, fault: int) -> None:
    """A conflict; solved each way, both merges write the same (and no solution leaves a dangling cell)."""
    v = 5 * SIDE + 5
    psql(
        conn,
        "DEFAULT",
        ("DELETE FROM tgsis.trgl WHERE geoid = %s AND %s IN (vrtxid1, vrtxid2, vrtxid3)", (fault, v)),
        ("DELETE FROM tgsis.vrtx WHERE geoid = %s AND vrtxid = %s", (fault, v)),
    )
    n, m = SIDE * SIDE, 2 * (SIDE - 1) ** 2
    psql(
        conn,
        "e1",
        ("INSERT INTO tgsis.vrtx (geoid, vrtxid, x, y, z) VALUES (%s, %s, 5000.0, 5000.0, 40.0)", (fault, n)),
        (
            "INSERT INTO tgsis.trgl (geoid, trglid, vrtxid1, vrtxid2, vrtxid3) VALUES (%s, %s, %s, %s, %s)",
            (fault, m, v, v + 1, n),
        ),
    )
    solve(conn, "e1", fault, "child")
    assert_same_merge(conn, "e1")


# ---------------------------------------------------------------------------- what SQL refuses, by name


def _psql_state(conn: Conn, query: str, args: tuple[Any, ...]) -> tuple[str | None, str, str | None]:
    try:
        conn.execute(query, args)
    except psycopg.Error as exc:
        conn.rollback()
        return exc.sqlstate, str(exc), exc.diag.message_hint
    conn.rollback()
    return None, "", None


def test_an_unsolved_region_is_refused_as_today_and_nothing_is_written(conn: Conn, fault: int) -> None:
    move(conn, "e1", fault, MIDDLE, (0.0, 0.0, 5.0))
    move(conn, "DEFAULT", fault, MIDDLE, (0.0, 0.0, -7.0))
    conn.commit()
    before = everything(conn)
    conn.commit()
    state, message, hint = _psql_state(conn, "SELECT tgsis.merge_version('e1')", ())
    assert state == "TG302", message
    assert "tgsis version merge" in (hint or "")
    assert everything(conn) == before
    conn.rollback()


def test_gocad_atoms_added_on_both_sides_and_one_on_a_renumbered_vertex_merge_as_in_python(
    conn: Conn, fault: int
) -> None:
    n, m = SIDE * SIDE, 2 * (SIDE - 1) ** 2
    atom = "INSERT INTO tgsis.atom (geoid, vrtxid, refid, patom) VALUES (%s, %s, %s, %s)"
    psql(conn, "DEFAULT", (atom, (fault, 60, 61, True)))  # in the base: a PATOM
    conn.execute("SELECT tgsis.merge_version('e1', true)")  # (nothing to merge; e1 made again on it)
    conn.commit()
    tgsis.create_version(conn, "e1")
    conn.commit()
    move(conn, "e1", fault, NORTH, (0.125, -3.3, 7.77))
    psql(
        conn,
        "e1",
        (atom, (fault, 5, 4, False)),
        ("INSERT INTO tgsis.vrtx (geoid, vrtxid, x, y, z) VALUES (%s, %s, 9000.0, 2000.0, 1.0)", (fault, n + 1)),
        (
            "INSERT INTO tgsis.trgl (geoid, trglid, vrtxid1, vrtxid2, vrtxid3) VALUES (%s, %s, %s, %s, %s)",
            (fault, m + 1, SIDE - 1, 2 * SIDE - 1, n + 1),
        ),
        (atom, (fault, 10, n + 1, False)),  # refers to a new vertex the merge renumbers
        ("UPDATE tgsis.atom SET refid = 49 WHERE geoid = %s AND vrtxid = 60", (fault,)),
    )
    move(conn, "DEFAULT", fault, SOUTH, (-1.1, 0.0, -2.9))
    psql(
        conn,
        "DEFAULT",
        (atom, (fault, 130, 131, False)),
        ("INSERT INTO tgsis.vrtx (geoid, vrtxid, x, y, z) VALUES (%s, %s, -500.0, 2000.0, 1.0)", (fault, n + 1)),
        (
            "INSERT INTO tgsis.trgl (geoid, trglid, vrtxid1, vrtxid2, vrtxid3) VALUES (%s, %s, %s, %s, %s)",
            (fault, m + 1, SIDE * (SIDE - 1), SIDE * (SIDE - 2), n + 1),
        ),
    )
    for action in ("merge", "refresh"):
        assert_same_merge(conn, "e1", action)


def test_session_settings_do_not_change_what_is_written(conn: Conn, fault: int) -> None:
    move(conn, "e1", fault, NORTH, (0.125, -3.3, 7.77))
    move(conn, "DEFAULT", fault, SOUTH, (-1.1, 0.0, -2.9))
    conn.commit()
    theirs, _ = both_merges(conn, "e1")
    conn.execute("SET extra_float_digits = -15")
    conn.execute("SET DateStyle = 'SQL, DMY'")
    conn.execute("SET search_path = ''")
    conn.commit()
    mine = _outcome(conn, lambda: int(conn.execute("SELECT tgsis.merge_version('e1')").fetchone()[0]))  # type: ignore[index]
    conn.execute("RESET ALL")
    conn.commit()
    assert mine[0] == "done", mine
    assert mine[1] == theirs[1]
    for table in theirs[2]:
        assert mine[2][table] == theirs[2][table], table


# ---------------------------------------------------------------------------- random edits


_pairs = itertools.count()


@settings(
    max_examples=8, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow]
)
@given(
    child=st.lists(_edit, min_size=1, max_size=3),
    parent=st.lists(_edit, min_size=1, max_size=3),
    solution=st.sampled_from(["parent", "child", "base"]),
    action=st.sampled_from(["merge", "refresh"]),
)
def test_random_edits_merge_in_psql_exactly_as_in_python(
    conn: Conn,
    fault: int,
    child: list[tuple[str, int, int]],
    parent: list[tuple[str, int, int]],
    solution: str,
    action: str,
) -> None:
    n = next(_pairs)
    parent_version, child_version = f"wp{n}", f"wc{n}"
    tgsis.create_version(conn, parent_version)
    conn.commit()
    tgsis.create_version(conn, child_version, parent=parent_version)
    conn.commit()
    vp, cp = property_tables(conn, fault)
    _apply(conn, child_version, fault, child, vp, cp)
    _apply(conn, parent_version, fault, parent, vp, cp)
    conn.execute("SELECT FROM tgsis.find_conflicts(%s)", (child_version,))
    for key, region in conn.execute(
        "SELECT objectkey, region FROM tgsis.conflict_regions WHERE versionid = tgsis.version_id(%s) AND conflict",
        (child_version,),
    ).fetchall():
        conn.execute("SELECT tgsis.resolve_region(%s, 'feature', %s, %s, %s)", (child_version, key, region, solution))
    conn.commit()
    theirs, mine = both_merges(conn, child_version, action)
    if theirs[0] == "refused":
        assert mine[0] == "refused" and mine[1] == theirs[1], (theirs, mine)
        return
    assert mine[0] == "done", mine
    assert mine[1] == theirs[1]
    for table in theirs[2]:
        assert mine[2][table] == theirs[2][table], table


# ---------------------------------------------------------------------------- more kinds, attributes


@pytest.mark.parametrize("geotype", ["MULTIPOINT", "MULTILINESTRING", "MULTITETRA"])
def test_points_lines_and_solids_with_a_cell_added_merge_as_in_python(conn: Conn, geotype: str) -> None:
    from tests.test_object_merge import _other_kind

    tgsis.create_feature_class(conn, "bodies", geotype)
    tgsis.enable_feature_versioning(conn)
    mesh = _other_kind(geotype)
    geoid = tgsis.insert_feature(conn, "bodies", mesh)
    tgsis.create_version(conn, "e1")
    conn.commit()
    move(conn, "e1", geoid, range(0, 5), (0.5, 0.25, -1.125))
    move(conn, "DEFAULT", geoid, range(34, 40), (-3.3, 0.0, 2.2))
    table, key = {
        "MULTIPOINT": ("point", "pointid"),
        "MULTILINESTRING": ("segment", "segid"),
        "MULTITETRA": ("tetra", "tetraid"),
    }[geotype]
    k = mesh.cell_size
    columns = ", ".join(f"vrtxid{j + 1}" for j in range(k))
    psql(
        conn,
        "e1",
        (
            f"INSERT INTO tgsis.{table} (geoid, {key}, {columns}) VALUES (%s, 1000, {', '.join(['%s'] * k)})",
            (geoid, *([0, 2, 4, 1][:k] if k > 1 else [3])),
        ),
    )
    assert_same_merge(conn, "e1")
    assert_same_merge(conn, "e1", "refresh")


def test_the_parents_attribute_edits_come_along_and_both_changed_is_refused_as_in_python(
    conn: Conn, fault: int
) -> None:
    move(conn, "e1", fault, NORTH, (0.125, -3.3, 7.77))
    move(conn, "DEFAULT", fault, SOUTH, (-1.1, 0.0, -2.9))
    psql(conn, "DEFAULT", ("UPDATE tgsis.geometry SET geoname = 'renamed', colorred = 0.25 WHERE geoid = %s", (fault,)))
    assert_same_merge(conn, "e1")
    assert_same_merge(conn, "e1", "refresh")
    psql(conn, "e1", ("UPDATE tgsis.geometry SET geoname = 'mine' WHERE geoid = %s", (fault,)))
    theirs, mine = both_merges(conn, "e1")
    assert theirs[:2] == ("refused", "TG302") and mine[:2] == ("refused", "TG302"), (theirs, mine)
    assert "geoname" in mine[2] and "both" in mine[2]


# ---------------------------------------------------------------------------- rights, sessions


def test_a_role_without_rights_on_the_class_or_the_version_is_refused_as_in_python_and_nothing_is_written(
    conn: Conn, fault: int, db_dsn: str
) -> None:
    from tests.roles import login_roles

    move(conn, "e1", fault, NORTH, (0.125, -3.3, 7.77))
    move(conn, "DEFAULT", fault, SOUTH, (-1.1, 0.0, -2.9))
    conn.commit()
    with login_roles(db_dsn, {"ed": "tgsis_editor", "rita": "tgsis_reader", "mo": "tgsis_editor"}) as made:
        tgsis.grant_version(conn, "e1", "all", made.name("ed"))
        tgsis.grant_version(conn, "DEFAULT", "merge", made.name("ed"))
        tgsis.grant_version(conn, "e1", "delete", made.name("mo"))
        tgsis.grant_version(conn, "DEFAULT", "merge", made.name("mo"))
        conn.execute("REVOKE INSERT, UPDATE, DELETE ON public.faults FROM tgsis_editor")
        conn.commit()
        before = everything(conn)
        conn.commit()
        for role, action, remove in (
            ("rita", "merge", False),
            ("ed", "merge", False),
            ("ed", "refresh", False),
            ("mo", "merge", True),  # may delete e1, not write the merged mesh in it
        ):
            session = made.connect(role)
            with pytest.raises(tgsis.MissingPrivilegeError) as python:
                if action == "merge":
                    tgsis.merge_version(session, "e1", remove=remove)
                else:
                    tgsis.refresh_version(session, "e1")
            session.rollback()
            query = f"SELECT tgsis.{action}_version('e1'{', true' if remove else ''})"
            state, message, _ = _psql_state(session, query, ())
            assert state == python.value.sqlstate and state in ("42501", "TG002"), (role, query, message)
            assert everything(conn) == before
            conn.commit()


def test_two_psql_sessions_merging_and_refreshing_at_once(conn: Conn, fault: int, db_dsn: str) -> None:
    from tests.sessions import Background, connect, wait_until_blocked

    move(conn, "e1", fault, NORTH, (0.125, -3.3, 7.77))
    move(conn, "DEFAULT", fault, SOUTH, (-1.1, 0.0, -2.9))
    conn.commit()
    theirs, _ = both_merges(conn, "e1")
    holder = connect(db_dsn, "holder")
    holder.execute("SELECT tgsis.lock_for_region_merge('e1', 'refresh')")  # both below wait for it
    merger = Background(db_dsn, "merger", lambda c: c.execute("SELECT tgsis.merge_version('e1')"))
    wait_until_blocked(conn, merger.pid, holder.info.backend_pid)
    refresher = Background(db_dsn, "refresher", lambda c: c.execute("SELECT tgsis.refresh_version('e1')"))
    time.sleep(0.3)
    holder.rollback()
    holder.close()
    merger.finish()
    refresher.finish()
    # the merge wrote what the Python merge writes; the refresh after it found nothing to bring
    after = everything(conn)
    conn.commit()
    for table in (storage_of(conn, "vrtx"), storage_of(conn, "trgl")):  # rows or chunk versions
        assert after[table] == theirs[2][table], table


def test_a_writer_in_the_version_during_a_psql_merge(conn: Conn, fault: int, db_dsn: str) -> None:
    from tests.sessions import Background, connect, wait_until_blocked

    move(conn, "e1", fault, NORTH, (0.125, -3.3, 7.77))
    move(conn, "DEFAULT", fault, SOUTH, (-1.1, 0.0, -2.9))
    conn.commit()
    writer = connect(db_dsn, "writer")
    tgsis.goto_version(writer, "e1")
    writer.execute("UPDATE tgsis.vrtx SET z = z + 1.5 WHERE geoid = %s AND vrtxid = 70", (fault,))
    merger = Background(db_dsn, "merger", lambda c: c.execute("SELECT tgsis.merge_version('e1')"))
    wait_until_blocked(conn, merger.pid, holder_pid := writer.info.backend_pid)
    assert holder_pid
    writer.commit()
    writer.close()
    merger.finish()
    expected = curved_surface().vertices.copy()
    moved(expected, NORTH, (0.125, -3.3, 7.77))
    moved(expected, SOUTH, (-1.1, 0.0, -2.9))
    moved(expected, [70], (0.0, 0.0, 1.5))
    for version in ("DEFAULT", "e1"):
        assert stored_state(conn, version, fault)[1].tobytes() == expected.tobytes()


def test_the_parents_edit_of_a_feature_property_comes_along_in_psql_as_in_python(conn: Conn) -> None:
    # (more types, session settings, rights, the class owner's runner: tests/test_sql_merge_feature_row.py)
    from tests.merge_data import curved_surface

    tgsis.create_feature_class(conn, "faults", "SURFACE", feature_properties=[("owner", "text")])
    tgsis.enable_feature_versioning(conn)
    geoid = tgsis.insert_feature(conn, "faults", curved_surface(), {"owner": "ann"}, drop_extra_properties=True)
    tgsis.create_version(conn, "e1")
    conn.commit()
    move(conn, "e1", geoid, NORTH, (0.125, -3.3, 7.77))
    move(conn, "DEFAULT", geoid, SOUTH, (-1.1, 0.0, -2.9))
    psql(conn, "DEFAULT", ("UPDATE public.faults SET owner = 'bob' WHERE _geoid = %s", (geoid,)))
    assert_same_merge(conn, "e1")
    assert_same_merge(conn, "e1", "refresh")


@pytest.mark.parametrize("solution", ["parent", "child", "base"])
def test_psql_is_told_what_a_solution_discards_as_python_says_it(conn: Conn, fault: int, solution: str) -> None:
    move(conn, "e1", fault, [64, 65, 66], (0.0, 0.0, 5.0))
    move(conn, "DEFAULT", fault, [66, 67], (0.0, 0.0, -4.0))
    conn.commit()
    solve(conn, "e1", fault, solution)
    with conn.transaction(force_rollback=True):
        (merged,) = tgsis.merge_version(conn, "e1").objects
    expected = [
        f"region {d.region}: {d.solution} discards the {d.side}'s edit there: {d.vertices} vertices, {d.cells} cells, "
        f"largest displacement {d.max_displacement:.6g}"
        for d in merged.discards
    ]
    assert expected
    notices: list[str] = []
    conn.add_notice_handler(lambda d: notices.append(str(d.message_primary)))
    with conn.transaction(force_rollback=True):
        conn.execute("SELECT tgsis.merge_version('e1')")
    said = [n.split(": ", 1)[1] for n in notices if n.startswith(f"feature {fault} of version 'e1': region")]
    assert said == expected


# ---------------------------------------------------------------------------- validity, against merge3's checks

_GRID = {i * 2 + j: (float(i), float(j), 0.25 * i) for i in range(4) for j in range(2)}
_TRIANGLES = {
    c: t
    for i in range(3)
    for c, t in ((2 * i, (2 * i, 2 * i + 2, 2 * i + 3)), (2 * i + 1, (2 * i, 2 * i + 3, 2 * i + 1)))
}


def _validity_in_sql(
    conn: Conn,
    merged_v: set[int],
    merged_c: dict[int, tuple[int, ...]],
    drop_v: list[int],
    drop_c: list[int],
    refs: dict[int, int],
) -> str | None:
    """tgsis.merge_mesh_validity on work tables that hold a whole small object: base = parent = version (the
    grid), the merged state given, the dropped ids one region taken from the version; its message or None."""
    conn.execute(
        "CREATE TEMPORARY TABLE tgsis_mr_v (id bigint, st smallint, x float8, y float8, z float8, val text, ref bigint)"
    )
    conn.execute("CREATE TEMPORARY TABLE tgsis_mr_c (id bigint, st smallint, v bigint[])")
    # the engine's info row: a model-1 mesh (no instant, no period: the base's cells of the whole object)
    conn.execute("CREATE TEMPORARY TABLE tgsis_mr_info AS SELECT NULL::float8 AS times, NULL::float8 AS timem")
    conn.execute("CREATE TEMPORARY TABLE tgsis_mr_vb (id bigint)")
    conn.execute("CREATE TEMPORARY TABLE tgsis_mr_margin (id bigint, v bigint[])")
    conn.execute("CREATE TEMPORARY TABLE tgsis_mw_node (kind text, id bigint, region integer)")
    conn.execute("CREATE TEMPORARY TABLE tgsis_mw_region (region integer, src smallint)")
    conn.execute(
        "CREATE TEMPORARY TABLE tgsis_mw_v (id bigint, present boolean, x float8, y float8, z float8, val text, ref bigint,"
        " src smallint)"
    )
    conn.execute("CREATE TEMPORARY TABLE tgsis_mw_c (id bigint, present boolean, v bigint[], src smallint)")
    for state in (1, 2, 4):
        for v in _GRID:
            conn.execute("INSERT INTO tgsis_mr_v VALUES (%s, %s, %s, %s, %s, NULL, NULL)", (v, state, *_GRID[v]))
        for c, t in _TRIANGLES.items():
            conn.execute("INSERT INTO tgsis_mr_c VALUES (%s, %s, %s)", (c, state, list(t)))
    for v in set(_GRID) | merged_v:
        conn.execute(
            "INSERT INTO tgsis_mw_v VALUES (%s, %s, %s, %s, %s, NULL, %s)", (v, v in merged_v, *_GRID[v], refs.get(v))
        )
    for c in set(_TRIANGLES) | set(merged_c):
        conn.execute("INSERT INTO tgsis_mw_c VALUES (%s, %s, %s)", (c, c in merged_c, list(merged_c.get(c, (0, 0, 0)))))
    conn.execute("INSERT INTO tgsis_mw_region VALUES (0, 4)")
    for kind, ids in (("v", drop_v), ("c", drop_c)):
        for i in ids:
            conn.execute("INSERT INTO tgsis_mw_node VALUES (%s, %s, 0)", (kind, i))
    try:
        with conn.transaction():
            conn.execute(
                "SELECT tgsis.merge_mesh_validity('feature 0 (base)', 3, 'triangle', 'trgl', -1, '{}', 'refused', 'hint')"
            )
    except psycopg.Error as exc:
        assert exc.sqlstate == "TG302"
        return str(exc.diag.message_primary).split("invalid merge: ", 1)[1]
    finally:
        conn.rollback()
    return None


def _validity_in_python(
    merged_v: set[int], merged_c: dict[int, tuple[int, ...]], drop_v: list[int], drop_c: list[int], refs: dict[int, int]
) -> str | None:
    import numpy as np

    from tgsis import merge3

    def state(
        verts: Mapping[int, tuple[float, ...]], cells: Mapping[int, tuple[int, ...]], atoms: Mapping[int, int]
    ) -> Any:
        vids, cids = sorted(verts), sorted(cells)
        like = merge3.MeshState(
            3,
            np.array([0]),
            np.zeros((1, 3)),
            np.empty(0, np.int64),
            np.empty((0, 3), np.int64),
            {},
            {},
            "feature 0 (base)",
        )
        return merge3._unchecked_state(
            like,
            np.array(vids, np.int64),
            np.array([verts[v] for v in vids], np.float64).reshape(-1, 3),
            np.array(cids, np.int64),
            np.array([cells[c] for c in cids], np.int64).reshape(-1, 3),
            {"refid": np.array([atoms.get(v, -1) for v in vids], np.int64)},
            {},
        )

    grid = state(_GRID, _TRIANGLES, {})
    merge = merge3.three_way_merge(grid, grid, grid)
    merged = state({v: _GRID[v] for v in merged_v}, merged_c, refs)
    try:
        merge3._check_valid(merge, merged, np.array(drop_v, np.int64), np.array(drop_c, np.int64), [])
    except tgsis.InvalidMergeError as exc:
        return exc.message
    return None


@pytest.mark.parametrize(
    ("case", "merged_v", "merged_c", "drop_v", "drop_c"),
    [
        ("a removed vertex cells use", set(_GRID) - {3}, _TRIANGLES, [3], []),
        ("a duplicated triangle", set(_GRID), {**_TRIANGLES, 6: (2, 3, 0)}, [], [6]),
        ("a non-manifold edge", set(_GRID), {**_TRIANGLES, 6: (0, 2, 5), 7: (2, 0, 7)}, [], [6, 7]),
        ("vertices left without triangles", set(_GRID), {c: t for c, t in _TRIANGLES.items() if c > 1}, [], [0, 1]),
        ("a valid change", set(_GRID), {**_TRIANGLES, 1: (0, 3, 1)}, [], [1]),
        (
            "an atom on a removed vertex",
            set(_GRID) - {5},
            {c: t for c, t in _TRIANGLES.items() if 5 not in t},
            [5, 6],
            [2, 3, 5],
        ),
    ],
)
def test_sql_validity_refuses_what_merge3_refuses_saying_the_same(
    conn: Conn,
    fault: int,
    case: str,
    merged_v: set[int],
    merged_c: dict[int, tuple[int, ...]],
    drop_v: list[int],
    drop_c: list[int],
) -> None:
    """The merges by region whose regions come from one side each cannot break validity (the regions join what
    they touch): the check is merge3's for what can, run here on work tables of a made-up merged state."""
    refs = {6: 5} if case == "an atom on a removed vertex" else {}
    expected = _validity_in_python(merged_v, merged_c, drop_v, drop_c, refs)
    assert (expected is None) == (case == "a valid change"), expected
    assert _validity_in_sql(conn, merged_v, merged_c, drop_v, drop_c, refs) == expected


def test_identical_edits_and_rows_rewritten_as_they_were_merge_as_in_python(conn: Conn, fault: int) -> None:
    """No region at all (rows rewritten as they were on both sides), then one region both changed alike."""
    move(conn, "e1", fault, NORTH, (0.0, 0.0, 0.0))
    move(conn, "DEFAULT", fault, SOUTH, (0.0, 0.0, 0.0))
    assert_same_merge(conn, "e1")
    move(conn, "e1", fault, MIDDLE, (0.0, 0.0, 5.0))
    move(conn, "DEFAULT", fault, MIDDLE, (0.0, 0.0, 5.0))
    assert_same_merge(conn, "e1")
    assert_same_merge(conn, "e1", "refresh")


def test_an_unsolved_region_found_by_the_merge_itself_is_named_in_the_refusal(conn: Conn, fault: int) -> None:
    """Nobody ran find_conflicts: the psql merge finds the regions, and refuses naming the mesh's regions."""
    move(conn, "e1", fault, MIDDLE, (0.0, 0.0, 5.0))
    move(conn, "DEFAULT", fault, MIDDLE, (0.0, 0.0, -7.0))
    conn.commit()
    assert conn.execute("SELECT count(*) FROM tgsis.conflict_regions").fetchone() == (0,)
    conn.rollback()
    for action in ("merge", "refresh"):
        state, message, hint = _psql_state(conn, f"SELECT tgsis.{action}_version('e1')", ())
        assert state == "TG302", message
        assert f"tgsis version {action} e1" in (hint or "") and f"feature {fault}" in (hint or ""), hint


def _parted_fault(conn: Conn) -> int:
    """The curved fault in two parts kept as runs in tgsis.part (rows of squares 8 and above: part 1), version e1."""
    import numpy as np

    from tests.merge_data import curved_surface

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
    return geoid


def test_parts_kept_as_runs_merge_as_in_python(conn: Conn) -> None:
    """The parent renumbers a part, the child moves vertices, deletes a triangle inside a run and adds one in no
    part, then on a second round gives cells another part: the runs are rewritten exactly as Python does."""
    geoid = _parted_fault(conn)
    psql(conn, "DEFAULT", ("UPDATE tgsis.part SET part = 2 WHERE geoid = %s AND part = 1", (geoid,)))
    move(conn, "e1", geoid, NORTH, (0.125, -3.3, 7.77))
    n, m = SIDE * SIDE, 2 * (SIDE - 1) ** 2
    psql(
        conn,
        "e1",
        ("DELETE FROM tgsis.trgl WHERE geoid = %s AND trglid = 3", (geoid,)),
        ("INSERT INTO tgsis.vrtx (geoid, vrtxid, x, y, z) VALUES (%s, %s, 50.0, -300.0, 0.0)", (geoid, n)),
        ("INSERT INTO tgsis.trgl (geoid, trglid, vrtxid1, vrtxid2, vrtxid3) VALUES (%s, %s, 1, 0, %s)", (geoid, m, n)),
    )
    for action in ("merge", "refresh"):
        assert_same_merge(conn, "e1", action)
    conn.execute("SELECT tgsis.merge_version('e1')")
    conn.commit()
    psql(conn, "e1", ("UPDATE tgsis.part SET part = 5 WHERE geoid = %s AND firstid = 0", (geoid,)))
    move(conn, "DEFAULT", geoid, SOUTH, (-1.1, 0.0, -2.9))
    for action in ("merge", "refresh"):
        assert_same_merge(conn, "e1", action)


def test_after_pg_dump_and_restore_the_solved_regions_merge_in_psql_as_in_python(
    conn: Conn, fault: int, pg: Any, db_dsn: str, tmp_path: Any
) -> None:
    from tests.test_backup import _bindir_of, _restored

    move(conn, "e1", fault, NORTH, (0.125, -3.3, 7.77))
    move(conn, "e1", fault, [64, 65, 66], (0.0, 0.0, 5.0))
    move(conn, "DEFAULT", fault, [66, 67], (0.0, 0.0, -4.0))
    conn.commit()
    solve(conn, "e1", fault, "child")
    with _restored(pg, _bindir_of(pg), db_dsn, "custom", tmp_path) as dsn, psycopg.connect(dsn) as restored:
        assert_same_merge(restored, "e1")


@pytest.mark.parametrize(
    "x", [0.0, -0.0, 1.0, 5.0, 0.1, 1234567.0, 999999.7, 0.0001, 0.00001234567, 123.456789, -2.5e-9, 7.77e12, 1e6]
)
def test_numbers_in_notices_are_written_as_python_writes_them(conn: Conn, x: float) -> None:
    (text,) = conn.execute("SELECT tgsis.merge_number_text(%s)", (x,)).fetchone()  # type: ignore[misc]
    conn.rollback()
    assert text == f"{x:.6g}"
