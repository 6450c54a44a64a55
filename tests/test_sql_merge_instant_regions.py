"""The regions of a surface at instants found in SQL (issue 39): SQL find_conflicts stores what Python stores.

A psql user's ``tgsis.find_conflicts`` finds and stores the regions of a
model-2 feature changed on both sides (``tgsis.store_mesh_regions`` →
``tgsis.instants_merge_regions``: merge3 per instant the three states have
and a side changed, through ``tgsis.mesh_merge_work`` on that instant's rows),
numbered on through the instants. The oracle is the Python
``tgsis.find_conflicts`` (``tgsis._merge_slices.merge_sliced``): the same
``tgsis.conflict_regions`` rows, ids, boxes, displacements and instants
included; an object-level conflict has no regions either way.
"""

from __future__ import annotations

import dataclasses
import itertools
from typing import Any

import numpy as np
import psycopg
import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

import tgsis
from tests.merge_data import SIDE, with_duplicated_triangle
from tests.roles import merges_as
from tests.test_merge_instants import (
    CHILD_SHIFT,
    NORTH,
    PARENT_SHIFT,
    SOUTH,
    make_evolving,
    make_series,
    move,
    move3,
)
from tests.test_sql_merge_slices import _new_surface, _sql
from tests.test_sql_merge_write import _outcome, assert_same_merge, both_merges, everything, solve

Conn = psycopg.Connection[Any]

_COLUMNS = (
    "region, times, timem, conflict, changed_by, vertex_ids, cell_ids, parent_vertex_ids, parent_cell_ids,"
    " child_vertex_ids, child_cell_ids, bbox, parent_displacement, child_displacement, solution, childmark, parentmark"
)


def _stored(conn: Conn, version: str, geoid: int) -> list[tuple[Any, ...]]:
    return conn.execute(
        f"SELECT {_COLUMNS} FROM tgsis.conflict_regions"
        " WHERE versionid = tgsis.version_id(%s) AND objectkey = %s ORDER BY region",
        (version, str(geoid)),
    ).fetchall()


def sql_regions(conn: Conn, version: str, geoid: int) -> list[tuple[Any, ...]]:
    """What SQL tgsis.find_conflicts stores for the feature, no Python region call (rolled back)."""
    conn.execute("SELECT FROM tgsis.find_conflicts(%s)", (version,))
    rows = _stored(conn, version, geoid)
    conn.rollback()
    return rows


def python_regions(conn: Conn, version: str, geoid: int) -> list[tuple[Any, ...]]:
    """What the Python tgsis.find_conflicts stores (rolled back)."""
    tgsis.find_conflicts(conn, version)
    rows = _stored(conn, version, geoid)
    conn.rollback()
    return rows


def assert_same_regions(conn: Conn, version: str, geoid: int) -> list[tuple[Any, ...]]:
    mine, theirs = sql_regions(conn, version, geoid), python_regions(conn, version, geoid)
    assert mine == theirs
    return mine


@pytest.fixture
def series(conn: Conn, series_clone: int) -> int:
    return series_clone  # make_series's, built once (tests/conftest.py)


def test_regions_of_instants_both_sides_changed_are_stored_by_sql_as_by_python(conn: Conn, series: int) -> None:
    move(conn, "e1", series, 2.0, NORTH, CHILD_SHIFT)
    move(conn, "DEFAULT", series, 2.0, NORTH[:SIDE], PARENT_SHIFT)  # overlaps the version's: a conflict
    move(conn, "DEFAULT", series, 2.0, SOUTH, PARENT_SHIFT)  # the same instant, apart: merges by itself
    move(conn, "DEFAULT", series, 3.0, SOUTH, PARENT_SHIFT)  # another instant, the parent alone
    move(conn, "e1", series, 1.0, SOUTH, CHILD_SHIFT)  # another, the version alone
    regions = assert_same_regions(conn, "e1", series)
    assert [(r[0], r[1], r[3], r[4]) for r in regions] == [
        (0, 1.0, False, "child"),
        (1, 2.0, True, "both"),
        (2, 2.0, False, "parent"),
        (3, 3.0, False, "parent"),
    ]
    assert [r[14] for r in regions] == ["automatic", "unsolved", "automatic", "automatic"]


def test_triangles_and_values_changed_at_an_instant_both_sides_changed(conn: Conn, series: int) -> None:
    _sql(conn, "e1", "DELETE FROM tgsis.times_trgl WHERE geoid = %s AND times = 2 AND trglid = 7", (series,))
    _sql(
        conn,
        "DEFAULT",
        "UPDATE horizons_cellpros SET porosity = -0.0 WHERE _geoid = %s AND _times = 2 AND _idx BETWEEN 30 AND 33",
        (series,),
    )
    _sql(
        conn,
        "DEFAULT",
        "UPDATE horizons_cellpros SET porosity = porosity * 2 WHERE _geoid = %s AND _times = 2 AND _idx = 8",
        (series,),
    )
    regions = assert_same_regions(conn, "e1", series)
    assert len(regions) >= 2


def test_an_object_level_conflict_has_no_regions_either_way(conn: Conn, series: int) -> None:
    with tgsis.in_version(conn, "e1"):
        tgsis.delete_instant(conn, series, 2.0)
    conn.commit()
    move(conn, "DEFAULT", series, 2.0, NORTH, PARENT_SHIFT)
    move(conn, "DEFAULT", series, 3.0, NORTH, PARENT_SHIFT)
    assert assert_same_regions(conn, "e1", series) == []


def test_an_instant_added_on_one_side_has_no_region_but_the_instants_merged_have(conn: Conn, series: int) -> None:
    with tgsis.in_version(conn, "DEFAULT"):
        tgsis.add_instant(conn, "horizons", series, 4.0, _new_surface(2), {"throw": 44.0})
    conn.commit()
    move(conn, "e1", series, 3.0, NORTH, CHILD_SHIFT)
    regions = assert_same_regions(conn, "e1", series)
    assert [(r[1], r[4]) for r in regions] == [(3.0, "child")]


def test_a_role_that_may_not_read_the_class_stores_no_regions(conn: Conn, series: int, db_dsn: str) -> None:
    move(conn, "e1", series, 2.0, NORTH, CHILD_SHIFT)
    move(conn, "DEFAULT", series, 2.0, NORTH, PARENT_SHIFT)
    conn.execute("CREATE ROLE tgsis_test_blind LOGIN IN ROLE tgsis_editor")
    conn.execute("SELECT tgsis.grant_version('e1', 'write', 'tgsis_test_blind')")
    conn.execute("REVOKE SELECT ON horizons FROM tgsis_test_blind, tgsis_editor, tgsis_reader")
    conn.commit()
    with psycopg.connect(db_dsn, user="tgsis_test_blind") as other:
        other.execute("SELECT FROM tgsis.find_conflicts('e1')")
        other.commit()
    assert _stored(conn, "e1", series) == []


_versions = itertools.count()
_edit = st.sampled_from(["move", "move", "cells", "values", "delete", "none"])


def _apply(conn: Conn, version: str, geoid: int, t: float, edit: str, first: int, shift: float) -> None:
    ids = list(range(first, first + SIDE))
    if edit == "move":
        move(conn, version, geoid, t, ids, (shift, 0.0, -shift))
    elif edit == "cells":
        _sql(
            conn,
            version,
            "DELETE FROM tgsis.times_trgl WHERE geoid = %s AND times = %s AND trglid = %s",
            (geoid, t, first),
        )
    elif edit == "values":
        _sql(
            conn,
            version,
            "UPDATE horizons_cellpros SET porosity = porosity * %s WHERE _geoid = %s AND _times = %s AND _idx = ANY(%s)",
            (shift, geoid, t, ids),
        )
    elif edit == "delete":
        with tgsis.in_version(conn, version):
            tgsis.delete_instant(conn, geoid, t)
        conn.commit()


@settings(
    max_examples=8, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow]
)
@given(
    plan=st.lists(
        st.tuples(_edit, st.integers(0, SIDE * (SIDE - 1) - 1), _edit, st.integers(0, SIDE * (SIDE - 1) - 1)),
        min_size=3,
        max_size=3,
    )
)
def test_random_edits_of_both_sides_give_the_regions_python_gives(
    conn: Conn, plan: list[tuple[str, int, str, int]]
) -> None:
    if not conn.execute("SELECT 1 FROM tgsis.catalog WHERE classname = 'horizons'").fetchone():
        conn.rollback()
        make_series(conn)
    conn.rollback()
    geoid = int(conn.execute("SELECT geoid FROM tgsis.geometry ORDER BY geoid LIMIT 1").fetchone()[0])  # type: ignore[index]
    n = next(_versions)
    version = f"r{n}"
    tgsis.create_version(conn, version)
    conn.commit()
    with tgsis.in_version(conn, "DEFAULT"):
        times = [
            float(r[0]) for r in conn.execute("SELECT times FROM tgsis.times WHERE geoid = %s ORDER BY 1", (geoid,))
        ]
    conn.commit()
    for i, (t, (pedit, pfirst, cedit, cfirst)) in enumerate(zip(times, plan, strict=False)):
        pedit = "move" if pedit == "delete" else pedit  # (DEFAULT keeps its instants for the next examples)
        if cedit == "delete" and i == len(times) - 1:
            cedit = "move"  # the last instant is never deleted: a feature's only instant goes with the feature (TG202)
        _apply(conn, "DEFAULT", geoid, t, pedit, pfirst, 1.0 + n / 8.0)
        _apply(conn, version, geoid, t, cedit, cfirst, -0.5 - n / 8.0)
    assert_same_regions(conn, version, geoid)


# ------------------------------------------------------------------- the psql merge of an instant both sides changed


@pytest.mark.parametrize("action", ["merge", "refresh"])
def test_an_instant_both_sides_changed_apart_merges_in_psql_exactly_as_in_python(
    conn: Conn, series: int, action: str
) -> None:
    move(conn, "e1", series, 2.0, NORTH, CHILD_SHIFT)
    move(conn, "DEFAULT", series, 2.0, SOUTH, PARENT_SHIFT)  # the same instant, apart: two regions
    move(conn, "DEFAULT", series, 3.0, SOUTH, PARENT_SHIFT)
    assert_same_merge(conn, "e1", action)


def test_an_unsolved_region_of_an_instant_is_refused_and_its_regions_stored(conn: Conn, series: int) -> None:
    move(conn, "e1", series, 2.0, NORTH, CHILD_SHIFT)
    move(conn, "DEFAULT", series, 2.0, NORTH[:SIDE], PARENT_SHIFT)
    before = everything(conn)
    conn.commit()
    with pytest.raises(psycopg.Error) as err:
        conn.execute("SELECT tgsis.merge_version('e1')")
    assert err.value.sqlstate == "TG302"
    assert "tgsis version merge e1" in str(err.value.diag.message_hint)
    conn.rollback()
    assert everything(conn) == before


@pytest.mark.parametrize("solution", ["parent", "child", "base"])
@pytest.mark.parametrize("action", ["merge", "refresh"])
def test_a_conflicting_region_of_an_instant_solved_in_psql_merges_as_in_python(
    conn: Conn, series: int, solution: str, action: str
) -> None:
    move(conn, "e1", series, 2.0, NORTH, CHILD_SHIFT)
    move(conn, "DEFAULT", series, 2.0, NORTH[:SIDE], PARENT_SHIFT)  # overlaps: a conflict
    move(conn, "DEFAULT", series, 2.0, SOUTH, PARENT_SHIFT)  # merges by itself
    move(conn, "e1", series, 1.0, SOUTH, CHILD_SHIFT)  # another instant, the version alone
    solve(conn, "e1", series, solution)
    assert_same_merge(conn, "e1", action)


def test_the_refusal_names_the_unsolved_region_and_its_instant_as_python_does(conn: Conn, series: int) -> None:
    move(conn, "e1", series, 2.0, NORTH, CHILD_SHIFT)
    move(conn, "DEFAULT", series, 2.0, NORTH[:SIDE], PARENT_SHIFT)
    move(conn, "DEFAULT", series, 3.0, SOUTH, PARENT_SHIFT)
    with pytest.raises(tgsis.UnsolvedConflictsError, match=r"region 0 at instant 2\.0 unsolved"):
        tgsis.merge_version(conn, "e1")
    conn.rollback()
    with pytest.raises(psycopg.Error, match=r"region 0 at instant 2\.0 unsolved") as err:
        conn.execute("SELECT tgsis.refresh_version('e1')")
    assert err.value.sqlstate == "TG302"
    conn.rollback()


# ---------------------------------------------------------------------------- hostile cases of an instant both changed


def _both_at_two(conn: Conn, series: int) -> None:
    """Both sides change instant 2 apart (two regions that merge by themselves), the parent instant 3 too."""
    move(conn, "e1", series, 2.0, NORTH, CHILD_SHIFT)
    move(conn, "DEFAULT", series, 2.0, SOUTH, PARENT_SHIFT)
    move(conn, "DEFAULT", series, 3.0, SOUTH, PARENT_SHIFT)


@pytest.mark.parametrize(
    "statement",
    [
        "WITH m AS (SELECT tgsis.merge_version('e1') AS n) SELECT n FROM m",
        "SELECT pg_temp.merge_it('e1')",
        "SELECT pg_temp.refresh_it('e1')",
    ],
    ids=["cte", "function", "refresh-function"],
)
def test_a_psql_merge_of_an_instant_both_changed_in_a_cte_or_a_function(
    conn: Conn, series: int, statement: str
) -> None:
    _both_at_two(conn, series)
    theirs, _ = both_merges(conn, "e1", "refresh" if "refresh" in statement else "merge")
    conn.execute(
        "CREATE FUNCTION pg_temp.merge_it(v text) RETURNS bigint LANGUAGE sql AS $$ SELECT tgsis.merge_version(v) $$;"
        "CREATE FUNCTION pg_temp.refresh_it(v text) RETURNS bigint LANGUAGE sql AS $$ SELECT tgsis.refresh_version(v) $$"
    )
    conn.commit()
    mine = _outcome(conn, lambda: int(conn.execute(statement).fetchone()[0]))  # type: ignore[index]
    assert theirs[0] == mine[0] == "done", mine
    assert mine[1] == theirs[1]
    for table in theirs[2]:
        assert mine[2][table] == theirs[2][table], table


def test_a_role_without_rights_on_the_class_is_refused_as_in_python_and_nothing_is_written(
    conn: Conn, series: int, db_dsn: str
) -> None:
    from tests.roles import login_roles

    _both_at_two(conn, series)
    with login_roles(db_dsn, {"ed": "tgsis_editor"}) as made:
        tgsis.grant_version(conn, "e1", "all", made.name("ed"))
        tgsis.grant_version(conn, "DEFAULT", "merge", made.name("ed"))
        conn.execute("REVOKE INSERT, UPDATE, DELETE ON public.horizons FROM tgsis_editor")
        conn.commit()
        before = everything(conn)
        conn.commit()
        for action in ("merge", "refresh"):
            session = made.connect("ed")
            with pytest.raises(tgsis.MissingPrivilegeError) as python:
                if action == "merge":
                    tgsis.merge_version(session, "e1")
                else:
                    tgsis.refresh_version(session, "e1")
            session.rollback()
            with pytest.raises(psycopg.Error) as caught:
                session.execute(f"SELECT tgsis.{action}_version('e1')")
            session.rollback()
            assert caught.value.sqlstate == python.value.sqlstate == "42501", str(caught.value)
            assert everything(conn) == before
            conn.commit()


@pytest.mark.parametrize("revoked", ["DELETE", "INSERT, UPDATE, DELETE"])
def test_a_property_view_the_role_may_not_write_is_refused_as_in_python_and_nothing_is_written(
    conn: Conn, series: int, db_dsn: str, revoked: str
) -> None:
    from tests.roles import login_roles

    _both_at_two(conn, series)
    _sql(  # the parent's property rows at instant 2 come into the version: its rows there are closed
        conn,
        "DEFAULT",
        "UPDATE horizons_cellpros SET porosity = porosity * 3 WHERE _geoid = %s AND _times = 2 AND _idx > 130",
        (series,),
    )
    with login_roles(db_dsn, {"ed": "tgsis_editor"}) as made:
        tgsis.grant_version(conn, "e1", "all", made.name("ed"))
        tgsis.grant_version(conn, "DEFAULT", "merge", made.name("ed"))
        conn.execute(f"REVOKE {revoked} ON public.horizons_cellpros FROM tgsis_editor")
        conn.commit()
        before = everything(conn)
        conn.commit()
        session = made.connect("ed")
        theirs, mine = merges_as(conn, session, "e1")
        assert everything(conn) == before
        conn.commit()
        assert theirs == ("refused", "42501"), theirs  # PostgreSQL refuses the Python merge's statement
        assert mine == theirs, (revoked, theirs, mine)


def test_a_writer_in_the_version_during_the_psql_merge_of_an_instant_both_changed(
    conn: Conn, series: int, db_dsn: str
) -> None:
    from tests.sessions import Background, connect, wait_until_blocked
    from tests.test_merge_instants import instants, shifted

    _both_at_two(conn, series)
    conn.commit()
    writer = connect(db_dsn, "writer")
    tgsis.goto_version(writer, "e1")
    writer.execute("UPDATE tgsis.times_vrtx SET z = z + 1.5 WHERE geoid = %s AND times = 2 AND vrtxid = 70", (series,))
    merger = Background(db_dsn, "merger", lambda c: c.execute("SELECT tgsis.merge_version('e1')"))
    wait_until_blocked(conn, merger.pid, holder_pid := writer.info.backend_pid)
    assert holder_pid
    writer.commit()
    writer.close()
    merger.finish()
    from tests.test_merge_instants import _shape

    expected = shifted(shifted(shifted(_shape(1), NORTH, CHILD_SHIFT), SOUTH, PARENT_SHIFT), [70], (0.0, 0.0, 1.5))
    for version in ("DEFAULT", "e1"):
        assert instants(conn, version, series)[2.0][1].tobytes() == expected.tobytes()


def test_a_depth_positive_surface_merges_in_psql_exactly_as_in_python(conn: Conn) -> None:
    import numpy as np

    from tests.test_merge_instants import TIMES, _porosity, _shape
    from tgsis.temporal import SurfaceSeries

    tgsis.create_feature_class(
        conn,
        "horizons",
        "SURFACE",
        time_model="INSTANTS",
        cell_properties=[("porosity", "float8")],
        instant_properties=[("throw", "double precision")],
    )
    tgsis.enable_feature_versioning(conn)
    cells = _new_surface(0).cells
    surfaces = [
        tgsis.Surface(-_shape(i), cells, vertex_properties={"porosity": _porosity()}, metadata={"zpositive": "Depth"})
        for i in range(len(TIMES))
    ]
    series = SurfaceSeries(np.asarray(TIMES), surfaces, properties={"throw": np.asarray([10.0, 20.0, 30.0])})
    geoid = int(tgsis.insert_feature(conn, "horizons", series))
    tgsis.create_version(conn, "e1")
    conn.commit()
    move(conn, "e1", geoid, 2.0, NORTH, CHILD_SHIFT)
    move(conn, "DEFAULT", geoid, 2.0, NORTH[:SIDE], PARENT_SHIFT)  # a conflict
    move(conn, "DEFAULT", geoid, 2.0, SOUTH, PARENT_SHIFT)
    assert_same_regions(conn, "e1", geoid)
    solve(conn, "e1", geoid, "child")
    assert_same_merge(conn, "e1")


# ---------------------------------------------------------------------------- random edits of both sides, merged

_wedit = st.sampled_from(["move", "move", "cells", "values", "add", "none"])


def _apply_both(conn: Conn, version: str, geoid: int, t: float, edit: str, first: int, shift: float) -> None:
    if edit != "add":
        _apply(conn, version, geoid, t, edit, first, shift)
        return
    # a new vertex (id 1000 on both sides: a clash the merge renumbers unless its row is the same) and a triangle
    # on it and two vertices of the grid
    _sql(
        conn,
        version,
        "INSERT INTO tgsis.times_vrtx (geoid, times, vrtxid, x, y, z)"
        " SELECT geoid, times, 1000, x + %s, y, z FROM tgsis.times_vrtx WHERE geoid = %s AND times = %s AND vrtxid = %s",
        (shift, geoid, t, first),
    )
    _sql(
        conn,
        version,
        "INSERT INTO tgsis.times_trgl (geoid, times, trglid, vrtxid1, vrtxid2, vrtxid3) VALUES (%s, %s, 5000, %s, %s, 1000)",
        (geoid, t, first, first + 1),
    )


@settings(
    max_examples=8, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow]
)
@given(
    plan=st.lists(
        st.tuples(_wedit, st.integers(0, SIDE * (SIDE - 1) - 2), _wedit, st.integers(0, SIDE * (SIDE - 1) - 2)),
        min_size=3,
        max_size=3,
    ),
    solution=st.sampled_from(["parent", "child", "base"]),
    action=st.sampled_from(["merge", "refresh"]),
)
def test_random_edits_of_both_sides_merge_in_psql_exactly_as_in_python(
    conn: Conn, plan: list[tuple[str, int, str, int]], solution: str, action: str
) -> None:
    if not conn.execute("SELECT 1 FROM tgsis.catalog WHERE classname = 'horizons'").fetchone():
        conn.rollback()
        make_series(conn)
    conn.rollback()
    geoid = int(conn.execute("SELECT geoid FROM tgsis.geometry ORDER BY geoid LIMIT 1").fetchone()[0])  # type: ignore[index]
    n = next(_versions)
    version = f"m{n}"
    tgsis.create_version(conn, version)
    conn.commit()
    with tgsis.in_version(conn, "DEFAULT"):
        times = [
            float(r[0]) for r in conn.execute("SELECT times FROM tgsis.times WHERE geoid = %s ORDER BY 1", (geoid,))
        ]
        used = conn.execute(
            "SELECT 1 FROM tgsis.times_vrtx WHERE geoid = %s AND vrtxid = 1000 LIMIT 1", (geoid,)
        ).fetchone()
    conn.commit()
    for t, (pedit, pfirst, cedit, cfirst) in zip(times, plan, strict=False):
        if used:  # (an earlier example added vertex 1000 in DEFAULT: adds are moves from then on)
            pedit, cedit = ("move" if e == "add" else e for e in (pedit, cedit))
        _apply_both(conn, "DEFAULT", geoid, t, pedit, pfirst, 1.0 + n / 8.0)
        _apply_both(conn, version, geoid, t, cedit, cfirst, -0.5 - n / 8.0)
    conn.execute("SELECT FROM tgsis.find_conflicts(%s)", (version,))
    conflicting = conn.execute(
        "SELECT region FROM tgsis.conflict_regions WHERE versionid = tgsis.version_id(%s) AND objectkey = %s"
        " AND conflict ORDER BY region",
        (version, str(geoid)),
    ).fetchall()
    for (region,) in conflicting:
        conn.execute("SELECT tgsis.resolve_region(%s, 'feature', %s, %s, %s)", (version, str(geoid), region, solution))
    conn.commit()
    if not conn.execute(
        "SELECT 1 FROM tgsis.find_conflicts(%s) WHERE objectclass = 'feature' AND solution = 'unsolved'", (version,)
    ).fetchone():  # (no conflict left: nothing to merge by parts)
        conn.rollback()
        return
    conn.rollback()
    theirs, mine = both_merges(conn, version, action)
    assert mine[:2] == theirs[:2], (theirs[:3], mine[:3])
    if theirs[0] == "done":
        for table in theirs[2]:
            assert mine[2][table] == theirs[2][table], table


@settings(
    max_examples=8, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow]
)
@given(
    plan=st.lists(
        st.tuples(_wedit, st.integers(0, SIDE * (SIDE - 1) - 2), _wedit, st.integers(0, SIDE * (SIDE - 1) - 2)),
        min_size=3,
        max_size=3,
    ),
    action=st.sampled_from(["merge", "refresh"]),
)
@example(plan=[("move", 0, "move", 0), ("move", 0, "move", 0), ("move", 1, "cells", 0)], action="merge")
# the version re-values vertex 12 beside the region both sides moved at instant 3 (its own region): the average's
# corner row of 12 was the parent's, refused as "changes rows outside the region" (InvalidInputError)
@example(plan=[("move", 0, "move", 0), ("move", 0, "move", 0), ("move", 0, "values", 1)], action="merge")
def test_random_edits_of_both_sides_solved_average_merge_in_psql_exactly_as_in_python(
    conn: Conn, plan: list[tuple[str, int, str, int]], action: str
) -> None:
    """As the random test above, every conflicting region solved ``average`` by the Python client (its rows
    recorded): the psql merge writes what the Python merge writes, or refuses what it refuses."""
    if not conn.execute("SELECT 1 FROM tgsis.catalog WHERE classname = 'horizons'").fetchone():
        conn.rollback()
        make_series(conn)
    conn.rollback()
    geoid = int(conn.execute("SELECT geoid FROM tgsis.geometry ORDER BY geoid LIMIT 1").fetchone()[0])  # type: ignore[index]
    n = next(_versions)
    version = f"m{n}"
    tgsis.create_version(conn, version)
    conn.commit()
    with tgsis.in_version(conn, "DEFAULT"):
        times = [
            float(r[0]) for r in conn.execute("SELECT times FROM tgsis.times WHERE geoid = %s ORDER BY 1", (geoid,))
        ]
        used = conn.execute(
            "SELECT 1 FROM tgsis.times_vrtx WHERE geoid = %s AND vrtxid = 1000 LIMIT 1", (geoid,)
        ).fetchone()
    conn.commit()
    for t, (pedit, pfirst, cedit, cfirst) in zip(times, plan, strict=False):
        if used:  # (an earlier example added vertex 1000 in DEFAULT: adds are moves from then on)
            pedit, cedit = ("move" if e == "add" else e for e in (pedit, cedit))
        _apply_both(conn, "DEFAULT", geoid, t, pedit, pfirst, 1.0 + n / 8.0)
        _apply_both(conn, version, geoid, t, cedit, cfirst, -0.5 - n / 8.0)
    conflicts = tgsis.find_conflicts(conn, version)
    conn.commit()
    if not any(r.conflict for c in conflicts for r in c.regions):
        return  # (no conflicting region: nothing to average)
    try:
        tgsis.resolve_all_regions(conn, version, geoid, "average")
    except tgsis.RegionSolutionError:
        # (no average shape of these patches: nothing recorded, nothing to merge)
        conn.rollback()
        return
    conn.commit()
    theirs, mine = both_merges(conn, version, action)
    assert mine[:2] == theirs[:2] or (theirs[0] == mine[0] == "refused"), (
        theirs[:2],
        mine[:2],
        [x[2] for x in (theirs, mine) if x[0] == "refused"],
    )
    if theirs[0] == "done":
        for table in theirs[2]:
            assert mine[2][table] == theirs[2][table], table


def _conflict_at_two(conn: Conn, series: int) -> None:
    """Both sides move overlapping blocks of instant 2 (a conflict), the parent also a block apart there."""
    move(conn, "e1", series, 2.0, NORTH, CHILD_SHIFT)
    move(conn, "DEFAULT", series, 2.0, NORTH[:SIDE], PARENT_SHIFT)
    move(conn, "DEFAULT", series, 2.0, SOUTH, PARENT_SHIFT)
    tgsis.find_conflicts(conn, "e1")
    conn.commit()


def _instant_rows_recorded(conn: Conn, series: int) -> list[tuple[Any, ...]]:
    return conn.execute(
        "SELECT region, times, solution, cardinality(solution_vertex_ids) FROM tgsis.conflict_regions"
        " WHERE versionid = tgsis.version_id('e1') AND objectkey = %s AND solution IN ('average', 'manual')",
        (str(series),),
    ).fetchall()


@pytest.mark.parametrize("action", ["merge", "refresh"])
def test_an_average_solution_of_a_region_of_an_instant_merges_in_psql_exactly_as_in_python(
    conn: Conn, series: int, action: str
) -> None:
    """The Python client records an average for a region of an instant with its rows (was: the .npz alone, the
    psql merge refused it TG302): the psql merge applies them as the Python merge applies the .npz."""
    _conflict_at_two(conn, series)
    resolution = tgsis.resolve_region(conn, "e1", series, 0, "average")
    conn.commit()
    assert resolution.state is not None
    ((region, times, solution, nv),) = _instant_rows_recorded(conn, series)
    assert (region, times, solution) == (0, 2.0, "average") and nv == len(resolution.state.vertex_ids)
    conn.commit()
    assert_same_merge(conn, "e1", action)


@pytest.mark.parametrize("action", ["merge", "refresh"])
def test_a_manual_mesh_of_a_region_of_an_instant_merges_in_psql_exactly_as_in_python(
    conn: Conn, series: int, action: str
) -> None:
    """A manual mesh of the region: its average (not recorded), one vertex lifted 3 m further."""
    _conflict_at_two(conn, series)
    average = tgsis.resolve_region(conn, "e1", series, 0, "average").state
    conn.rollback()
    assert average is not None
    xyz = np.array(average.vertices, dtype=np.float64)
    xyz[0, 2] += 3.0
    manual = dataclasses.replace(average, vertices=xyz)
    tgsis.resolve_region(conn, "e1", series, 0, "manual", manual)
    conn.commit()
    assert [r[2] for r in _instant_rows_recorded(conn, series)] == ["manual"]
    assert_same_merge(conn, "e1", action)


def test_an_average_of_an_instant_recorded_with_its_npz_only_is_refused_by_name_in_psql(
    conn: Conn, series: int
) -> None:
    """An average recorded before its rows were taken (the .npz alone): the psql merge does not apply it (TG302,
    nothing written, the hint naming the command that does); the Python merge does."""
    _conflict_at_two(conn, series)
    tgsis.resolve_region(conn, "e1", series, 0, "average")
    conn.execute(
        "UPDATE tgsis.conflict_regions SET solution_vertex_ids = NULL, solution_vertices = NULL, solution_cell_ids = NULL,"
        " solution_cells = NULL, solution_vertex_columns = NULL, solution_vertex_values = NULL,"
        " solution_cell_columns = NULL, solution_cell_values = NULL WHERE versionid = tgsis.version_id('e1')"
    )
    conn.commit()
    theirs, mine = both_merges(conn, "e1")
    assert theirs[0] == "done", theirs
    assert mine[:2] == ("refused", "TG302"), mine
    assert "region 0 at instant 2 solved average with its mesh only" in mine[2], mine[2]
    assert "`tgsis version merge e1`" in mine[2], mine[2]


@pytest.mark.parametrize("solution", ["average", "manual"])
def test_psql_is_told_what_an_average_or_manual_solution_of_an_instant_discards_as_python_says_it(
    conn: Conn, series: int, solution: str
) -> None:
    _conflict_at_two(conn, series)
    state = tgsis.resolve_region(conn, "e1", series, 0, "average").state
    assert state is not None
    if solution == "manual":  # the average, one vertex put back where the parent has it
        conn.rollback()
        xyz = np.array(state.vertices, dtype=np.float64)
        xyz[0, 2] -= 1.0
        tgsis.resolve_region(conn, "e1", series, 0, "manual", dataclasses.replace(state, vertices=xyz))
    conn.commit()
    with conn.transaction(force_rollback=True):
        (merged,) = tgsis.merge_version(conn, "e1").objects
    expected = [
        f"region {d.region} at instant 2: {d.solution} discards the {d.side}'s edit there: {d.vertices} vertices,"
        f" {d.cells} cells, largest displacement {d.max_displacement:.6g}"
        for d in merged.discards
    ]
    assert {d.side for d in merged.discards} == {"parent", "child"}
    notices: list[str] = []
    conn.add_notice_handler(lambda d: notices.append(str(d.message_primary)))
    with conn.transaction(force_rollback=True):
        conn.execute("SELECT tgsis.merge_version('e1')")
    said = [n.split(": ", 1)[1] for n in notices if n.startswith(f"feature {series} of version 'e1': region")]
    assert said == expected


def test_after_pg_dump_and_restore_an_average_of_an_instant_merges_in_psql_as_in_python(
    conn: Conn, series: int, pg: Any, db_dsn: str, tmp_path: Any
) -> None:
    from tests.test_backup import _bindir_of, _restored

    _conflict_at_two(conn, series)
    tgsis.resolve_region(conn, "e1", series, 0, "average")
    conn.commit()
    with _restored(pg, _bindir_of(pg), db_dsn, "custom", tmp_path) as dsn, psycopg.connect(dsn) as restored:
        assert_same_merge(restored, "e1")


def _record_in_sql(conn: Conn, series: int, state: Any) -> None:
    """Record a manual state of region 0 as a psql user may, with its .npz and rows (no check of the Python client's)."""
    from tgsis.db.regions import _sql_rows, state_to_npz

    rows = _sql_rows(state)
    assert rows is not None
    conn.execute(
        "SELECT FROM tgsis.resolve_region('e1', 'feature', %s, 0, 'manual', %s, %s, %s::float8[], %s, %s,"
        " %s::text[], %s::float8[], %s::text[], %s::float8[])",
        (str(series), state_to_npz(state), *rows),
    )
    conn.commit()


def test_a_manual_mesh_that_makes_an_invalid_instant_is_refused_in_psql_as_in_python(conn: Conn, series: int) -> None:
    """A manual mesh recorded from psql with a second triangle on the vertices of one of its triangles: merge3's
    validity check refuses the merged instant in Python; the psql merge refuses it too (TG302), naming the same
    vertices, nothing written (it ran no validity check of an instant before)."""
    _conflict_at_two(conn, series)
    state = tgsis.resolve_region(conn, "e1", series, 0, "average").state
    conn.rollback()
    assert state is not None
    broken = with_duplicated_triangle(state)
    _record_in_sql(conn, series, broken)
    before = everything(conn)
    conn.commit()
    theirs, mine = both_merges(conn, "e1")
    assert theirs[0] == "refused" and mine[:2] == ("refused", "TG302"), (theirs, mine)
    key = ", ".join(str(v) for v in sorted(state.cells[0].tolist()))
    for said in (theirs[2], mine[2]):
        assert "invalid merge" in said and "duplicated triangles" in said and f"({key})" in said, said
    assert everything(conn) == before


@pytest.mark.parametrize("action", ["merge", "refresh"])
def test_a_manual_mesh_that_removes_a_triangle_no_side_changed_merges_in_psql_as_in_python(
    conn: Conn, series: int, action: str
) -> None:
    """A manual mesh may drop a triangle of its region no side changed (the margin; an average of two meshings
    moves such vertices: the random test): the version's row there, the base's, is closed as the Python merge
    closes it (the psql merge read no such row of the instant before)."""
    _conflict_at_two(conn, series)
    region = tgsis.find_conflicts(conn, "e1")[0].regions[0]
    conn.commit()
    margin = np.setdiff1d(region.cell_ids, np.union1d(region.parent_cell_ids, region.child_cell_ids))
    assert len(margin)
    state = tgsis.resolve_region(conn, "e1", series, 0, "average").state
    conn.rollback()
    assert state is not None
    keep = state.cell_ids != margin[0]
    holed = dataclasses.replace(
        state,
        cell_ids=state.cell_ids[keep],
        cells=state.cells[keep],
        cell_properties={k: np.asarray(v)[keep] for k, v in state.cell_properties.items()},
    )
    tgsis.resolve_region(conn, "e1", series, 0, "manual", holed)
    conn.commit()
    assert_same_merge(conn, "e1", action)


def test_session_settings_do_not_change_what_a_manual_solution_of_an_instant_writes(conn: Conn, series: int) -> None:
    """Coordinates with digits beyond 15 and a third as a value, recorded and merged under extra_float_digits = -15,
    another DateStyle and an empty search_path: the psql merge writes the bits the Python merge writes."""
    _conflict_at_two(conn, series)
    region = tgsis.find_conflicts(conn, "e1")[0].regions[0]
    conn.commit()
    state = tgsis.resolve_region(conn, "e1", series, 0, "average").state
    conn.rollback()
    assert state is not None
    at = np.isin(state.vertex_ids, region.vertex_ids)
    xyz = np.array(state.vertices, dtype=np.float64)
    xyz[at, 2] += 0.1 + 1e-13  # digits beyond 15
    values = {}
    for k, v in state.vertex_properties.items():
        values[k] = np.array(v, dtype=np.float64)
        values[k][at] = 1 / 3
    manual = dataclasses.replace(state, vertices=xyz, vertex_properties=values)
    conn.execute("SET extra_float_digits = -15")  # the recording too
    tgsis.resolve_region(conn, "e1", series, 0, "manual", manual)
    conn.commit()
    conn.execute("RESET ALL")
    conn.commit()
    theirs, _ = both_merges(conn, "e1")
    conn.execute("SET extra_float_digits = -15")
    conn.execute("SET DateStyle = 'SQL, DMY'")
    conn.execute("SET search_path = ''")
    conn.commit()
    mine = _outcome(conn, lambda: int(conn.execute("SELECT tgsis.merge_version('e1')").fetchone()[0]))  # type: ignore[index]
    conn.execute("RESET ALL")
    conn.commit()
    assert theirs[0] == "done" and mine[0] == "done", (theirs[:2], mine[:3])
    assert mine[1] == theirs[1]
    for table in theirs[2]:
        assert mine[2][table] == theirs[2][table], table


def test_rows_are_recorded_for_a_region_of_a_geometry_instant_of_a_period_too(conn: Conn) -> None:
    """Model 3 (a geometry instant of a period): the Python client records an average's rows beside its .npz,
    keyed by the slice's ids (node ids, triangle ids), as for an instant of model 2; a psql user's resolve_region
    with rows keeps them too."""
    from tgsis.db.regions import _sql_rows

    evolving = make_evolving(conn)
    move3(conn, "e1", evolving, 1.0, NORTH, CHILD_SHIFT)
    move3(conn, "DEFAULT", evolving, 1.0, NORTH, PARENT_SHIFT)
    tgsis.find_conflicts(conn, "e1")
    conn.commit()
    state = tgsis.resolve_region(conn, "e1", evolving, 0, "average").state
    conn.commit()
    assert state is not None
    rows = _sql_rows(state)
    assert rows is not None
    query = (
        "SELECT timem, times, solution, solution_mesh IS NOT NULL, solution_vertex_ids, solution_vertices,"
        " solution_cell_ids, solution_cells, solution_vertex_columns, solution_vertex_values,"
        " solution_cell_columns, solution_cell_values FROM tgsis.conflict_regions WHERE objectkey = %s AND region = 0"
    )
    recorded = conn.execute(query, (str(evolving),)).fetchall()
    assert recorded == [(1.0, 1.0, "average", True, *rows)], recorded
    nodes = conn.execute("SELECT nodeid FROM tgsis.node WHERE geoid = %s AND timem = 1", (evolving,)).fetchall()
    assert set(rows[0]) <= {n for (n,) in nodes}  # the period's node ids
    conn.execute(
        "SELECT FROM tgsis.resolve_region('e1', 'feature', %s, 0, 'manual', %s, %s, %s::float8[], %s, %s,"
        " %s::text[], %s::float8[], %s::text[], %s::float8[])",
        (str(evolving), tgsis.db.regions.state_to_npz(state), *rows),
    )
    recorded = conn.execute(query, (str(evolving),)).fetchall()
    assert recorded == [(1.0, 1.0, "manual", True, *rows)], recorded
    conn.rollback()


def test_a_whole_side_that_would_drop_the_other_sides_region_of_an_instant_is_refused_in_psql(
    conn: Conn, series: int
) -> None:
    """Both sides changed instant 2 only, apart: no slice only one side changed, so only the regions (which SQL
    find_conflicts now stores for a surface at instants) show that 'child' drops the parent's edit there."""
    move(conn, "e1", series, 2.0, NORTH, CHILD_SHIFT)
    move(conn, "DEFAULT", series, 2.0, SOUTH, PARENT_SHIFT)
    before = everything(conn)
    conn.commit()
    with pytest.raises(psycopg.Error) as caught:
        conn.execute("SELECT tgsis.resolve_conflict('e1', 'feature', %s, 'child')", (str(series),))
    assert caught.value.sqlstate == "TG307", str(caught.value)
    assert "would drop the parent's edits in regions 1" in str(caught.value), str(caught.value)
    conn.rollback()
    assert everything(conn) == before
