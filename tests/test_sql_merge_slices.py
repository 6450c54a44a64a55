"""The psql merge of model-2 surfaces (surfaces at instants), instant by instant (issue 39, item 2).

A psql user's ``SELECT tgsis.merge_version(v)`` / ``tgsis.refresh_version(v)``
merges a surface at instants whose instants were each changed on one side
only (or alike on both): an instant moved, added or removed on one side, the
other side's edits at other instants, the per-instant feature properties
column by column (docs/merge.md, "Models 2 and 3"). The oracle is the Python
merge (``tgsis.merge_version(conn, v)``), row version for row version
(tests.test_sql_merge_write.both_merges). An instant changed on both sides
differently merges by region (tests/test_sql_merge_instant_regions.py); one
with an unsolved conflicting region, and what cannot be split, are refused
as in Python.
"""

from __future__ import annotations

import ast
import shlex
import time
from typing import Any

import numpy as np
import psycopg
import pytest

import tgsis
from tests.test_merge_instants import CHILD_SHIFT, NORTH, PARENT_SHIFT, SOUTH, TIMES, move
from tests.test_sql_merge_write import _outcome, assert_same_merge, both_merges, everything

Conn = psycopg.Connection[Any]


@pytest.fixture
def series(conn: Conn, series_clone: int) -> int:
    return series_clone  # make_series's, built once (tests/conftest.py)


def _sql(conn: Conn, version: str, text: str, args: tuple[Any, ...] = ()) -> None:
    """One statement a psql user runs in ``version`` (committed)."""
    with tgsis.in_version(conn, version):
        conn.execute(text, args)
    conn.commit()


@pytest.mark.parametrize(("action", "remove"), [("merge", False), ("merge", True), ("refresh", False)])
def test_edits_at_different_instants_merge_in_psql_exactly_as_in_python(
    conn: Conn, series: int, action: str, remove: bool
) -> None:
    move(conn, "e1", series, TIMES[0], NORTH, CHILD_SHIFT)
    move(conn, "DEFAULT", series, TIMES[2], SOUTH, PARENT_SHIFT)
    assert_same_merge(conn, "e1", action, remove)


def _new_surface(i: int, factor: float = 2.0) -> Any:
    from tests.merge_data import curved_surface
    from tests.test_merge_instants import _porosity, _shape

    return tgsis.Surface(_shape(i), curved_surface().cells, vertex_properties={"porosity": _porosity() * factor})


def _add_instant(conn: Conn, version: str, geoid: int, t: float, throw: float) -> None:
    with tgsis.in_version(conn, version):
        tgsis.add_instant(conn, "horizons", geoid, t, _new_surface(int(t) + 4), {"throw": throw})
    conn.commit()


def _delete_instant(conn: Conn, version: str, geoid: int, t: float) -> None:
    with tgsis.in_version(conn, version):
        tgsis.delete_instant(conn, geoid, t)
    conn.commit()


# what each side does, as (version, step) pairs: every one merges instant by instant in Python
SCENARIOS: dict[str, list[tuple[str, str]]] = {
    "parent adds an instant, version moves": [("DEFAULT", "add 4"), ("e1", "move 2 north")],
    "version adds an instant, parent moves": [("e1", "add 4"), ("DEFAULT", "move 2 south")],
    "both add the same instant alike": [("e1", "add 4"), ("DEFAULT", "add 4"), ("e1", "move 1 north")],
    "version removes an instant, parent moves another": [("e1", "delete 2"), ("DEFAULT", "move 3 south")],
    "parent removes an instant, version moves another": [("DEFAULT", "delete 1"), ("e1", "move 3 north")],
    "same edit on both sides, one more in the version": [
        ("e1", "same 2 north"),
        ("DEFAULT", "same 2 north"),
        ("e1", "move 3 south"),
    ],
    "version edits triangles and properties of an instant the parent moved elsewhere": [
        ("e1", "cells 2"),
        ("DEFAULT", "move 1 south"),
        ("DEFAULT", "move 3 south"),
    ],
    "parent edits triangles and properties, version moves": [("DEFAULT", "cells 2"), ("e1", "move 1 north")],
    "parent changes a per-instant property, version moves": [("DEFAULT", "throw 2 25"), ("e1", "move 3 north")],
    "both change per-instant properties of other instants": [
        ("DEFAULT", "throw 2 25"),
        ("e1", "throw 3 35"),
        ("e1", "move 1 north"),
    ],
    "version moves an instant twice, parent another": [
        ("e1", "move 2 north"),
        ("e1", "move 2 north"),
        ("DEFAULT", "move 3 south"),
    ],
}


def _step(conn: Conn, version: str, step: str, geoid: int) -> None:
    what, *args = step.split()
    if what in ("move", "same"):  # same: the version's shift on either side
        shift = CHILD_SHIFT if version == "e1" or what == "same" else PARENT_SHIFT
        move(conn, version, geoid, float(args[0]), NORTH if args[1] == "north" else SOUTH, shift)
    elif what == "add":
        _add_instant(conn, version, geoid, float(args[0]), 44.0)
    elif what == "delete":
        _delete_instant(conn, version, geoid, float(args[0]))
    elif what == "drop":  # the whole feature
        with tgsis.in_version(conn, version):
            tgsis.delete_feature(conn, "horizons", geoid)
        conn.commit()
    elif what == "throw":
        _sql(
            conn,
            version,
            "UPDATE horizons_pros SET throw = %s WHERE _geoid = %s AND _times = %s",
            (float(args[1]), geoid, float(args[0])),
        )
    elif what == "cells":  # a triangle removed, one added on existing vertices, property values changed
        t = float(args[0])
        _sql(conn, version, "DELETE FROM tgsis.times_trgl WHERE geoid = %s AND times = %s AND trglid = 7", (geoid, t))
        _sql(
            conn,
            version,
            "INSERT INTO tgsis.times_trgl (geoid, times, trglid, vrtxid1, vrtxid2, vrtxid3)"
            " SELECT geoid, times, 100000, vrtxid1, vrtxid3, vrtxid2 FROM tgsis.times_trgl"
            " WHERE geoid = %s AND times = %s AND trglid = 40",
            (geoid, t),
        )
        _sql(
            conn,
            version,
            "UPDATE horizons_cellpros SET porosity = -0.0 WHERE _geoid = %s AND _times = %s AND _idx BETWEEN 30 AND 33",
            (geoid, t),
        )
        _sql(conn, version, "DELETE FROM horizons_cellpros WHERE _geoid = %s AND _times = %s AND _idx = 50", (geoid, t))
    else:
        raise AssertionError(step)


@pytest.mark.parametrize("scenario", list(SCENARIOS))
def test_instants_changed_on_one_side_merge_in_psql_exactly_as_in_python(
    conn: Conn, series: int, scenario: str
) -> None:
    for version, step in SCENARIOS[scenario]:
        _step(conn, version, step, series)
    assert_same_merge(conn, "e1")


# what the Python merge leaves unsolved (TG302), as the psql merge does (an instant both sides changed differently,
# overlapping: a conflicting region without a solution)
REFUSED: dict[str, tuple[list[tuple[str, str]], str]] = {
    "an instant removed on one side and changed on the other": (
        [("e1", "delete 2"), ("DEFAULT", "move 2 south")],
        "TG302",
    ),
    "an instant added on both sides differently": (
        [("e1", "add 4"), ("DEFAULT", "add 4"), ("DEFAULT", "move 4 south")],
        "TG302",
    ),
    "the feature deleted in the version, an instant moved in the parent": (
        [("e1", "drop"), ("DEFAULT", "move 2 south")],
        "TG302",
    ),
    "the feature deleted in the parent, an instant moved in the version": (
        [("DEFAULT", "drop"), ("e1", "move 2 north")],
        "TG302",
    ),
    "a per-instant property changed on both sides": ([("e1", "throw 2 21"), ("DEFAULT", "throw 2 22")], "TG302"),
    "an instant moved on both sides differently, overlapping": (
        [("e1", "move 2 north"), ("DEFAULT", "move 2 north")],
        "TG302",
    ),
}


@pytest.mark.parametrize("scenario", list(REFUSED))
def test_what_psql_does_not_merge_instant_by_instant_is_refused_and_nothing_is_written(
    conn: Conn, series: int, scenario: str
) -> None:
    steps, python = REFUSED[scenario]
    for version, step in steps:
        _step(conn, version, step, series)
    before = everything(conn)
    conn.commit()
    theirs, mine = both_merges(conn, "e1")
    assert mine[:2] == ("refused", "TG302"), mine
    assert theirs[:2] == ("refused", python), theirs
    assert everything(conn) == before
    conn.commit()


# ---------------------------------------------------------------------------- hostile cases


def _one_side_each(conn: Conn, geoid: int) -> None:
    """The version moves instant 1 and adds 4, the parent moves 3 and changes a per-instant property of 2."""
    for version, step in (
        ("e1", "move 1 north"),
        ("e1", "add 4"),
        ("DEFAULT", "move 3 south"),
        ("DEFAULT", "throw 2 25"),
    ):
        _step(conn, version, step, geoid)


def test_session_settings_do_not_change_what_psql_writes(conn: Conn, series: int) -> None:
    _one_side_each(conn, series)
    theirs, _ = both_merges(conn, "e1")
    conn.execute("SET extra_float_digits = -15")
    conn.execute("SET DateStyle = 'SQL, DMY'")
    conn.execute("SET TimeZone = 'Pacific/Chatham'")
    conn.execute("SET search_path = ''")
    conn.commit()
    mine = _outcome(conn, lambda: int(conn.execute("SELECT tgsis.merge_version('e1')").fetchone()[0]))  # type: ignore[index]
    conn.execute("RESET ALL")
    conn.commit()
    assert theirs[0] == mine[0] == "done", mine
    assert mine[1] == theirs[1]
    for table in theirs[2]:
        assert mine[2][table] == theirs[2][table], table


def test_a_role_without_rights_is_refused_as_in_python_and_nothing_is_written(
    conn: Conn, series: int, db_dsn: str
) -> None:
    from tests.roles import login_roles

    _one_side_each(conn, series)
    with login_roles(db_dsn, {"ed": "tgsis_editor", "rita": "tgsis_reader", "mo": "tgsis_editor"}) as made:
        tgsis.grant_version(conn, "e1", "all", made.name("ed"))
        tgsis.grant_version(conn, "DEFAULT", "merge", made.name("ed"))
        tgsis.grant_version(conn, "e1", "delete", made.name("mo"))
        tgsis.grant_version(conn, "DEFAULT", "merge", made.name("mo"))
        conn.execute("REVOKE INSERT, UPDATE, DELETE ON public.horizons FROM tgsis_editor")
        conn.commit()
        before = everything(conn)
        conn.commit()
        for role, action, remove in (
            ("rita", "merge", False),
            ("ed", "merge", False),
            ("ed", "refresh", False),
            ("mo", "merge", True),  # may delete e1, not write the merged surface in it
        ):
            session = made.connect(role)
            with pytest.raises(tgsis.MissingPrivilegeError) as python:
                if action == "merge":
                    tgsis.merge_version(session, "e1", remove=remove)
                else:
                    tgsis.refresh_version(session, "e1")
            session.rollback()
            query = f"SELECT tgsis.{action}_version('e1'{', true' if remove else ''})"
            with pytest.raises(psycopg.Error) as caught:
                session.execute(query)
            session.rollback()
            assert caught.value.sqlstate == python.value.sqlstate, (role, query, str(caught.value))
            assert caught.value.sqlstate in ("42501", "TG002"), (role, query, str(caught.value))
            assert everything(conn) == before
            conn.commit()


@pytest.mark.parametrize(
    "statement",
    [
        "WITH m AS (SELECT tgsis.merge_version('e1') AS n) SELECT n FROM m",
        "SELECT pg_temp.merge_it('e1')",
    ],
    ids=["cte", "function"],
)
def test_a_psql_merge_in_a_cte_or_a_function_writes_what_python_writes(conn: Conn, series: int, statement: str) -> None:
    _one_side_each(conn, series)
    theirs, _ = both_merges(conn, "e1")
    conn.execute(
        "CREATE FUNCTION pg_temp.merge_it(v text) RETURNS bigint LANGUAGE sql AS $$ SELECT tgsis.merge_version(v) $$"
    )
    conn.commit()
    mine = _outcome(conn, lambda: int(conn.execute(statement).fetchone()[0]))  # type: ignore[index]
    assert theirs[0] == mine[0] == "done", mine
    assert mine[1] == theirs[1]
    for table in theirs[2]:
        assert mine[2][table] == theirs[2][table], table


def test_two_psql_sessions_merging_and_refreshing_at_once(conn: Conn, series: int, db_dsn: str) -> None:
    from tests.sessions import Background, connect, wait_until_blocked

    _one_side_each(conn, series)
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
    storages = conn.execute(  # (the time tables' storage: <table>_ver, or <table>_chunk once stored in chunks)
        "SELECT tgsis.storage_table('tgsis', t) FROM unnest(ARRAY['times', 'times_vrtx', 'times_trgl']) AS t"
    ).fetchall()
    conn.rollback()
    for table in (*(str(r[0]) for r in storages), "public.horizons_pros_ver", "public.horizons_cellpros_ver"):
        assert after[table] == theirs[2][table], table


def test_a_writer_of_an_instant_in_the_version_during_a_psql_merge(conn: Conn, series: int, db_dsn: str) -> None:
    from tests.sessions import Background, connect, wait_until_blocked

    _one_side_each(conn, series)
    writer = connect(db_dsn, "writer")
    tgsis.goto_version(writer, "e1")
    writer.execute("UPDATE tgsis.times_vrtx SET z = z + 1.5 WHERE geoid = %s AND times = 2 AND vrtxid = 70", (series,))
    merger = Background(db_dsn, "merger", lambda c: c.execute("SELECT tgsis.merge_version('e1')"))
    wait_until_blocked(conn, merger.pid, writer.info.backend_pid)
    writer.commit()
    writer.close()
    merger.finish()
    # the writer's edit (instant 2, which the parent's per-instant property edit also touched) came along
    z = {}
    for version in ("DEFAULT", "e1"):
        with tgsis.in_version(conn, version):
            z[version] = conn.execute(
                "SELECT z FROM tgsis.times_vrtx WHERE geoid = %s AND times = 2 AND vrtxid = 70", (series,)
            ).fetchone()
            z[version + " throw"] = conn.execute(
                "SELECT throw FROM horizons_pros WHERE _geoid = %s AND _times = 2", (series,)
            ).fetchone()
        conn.commit()
    assert z["DEFAULT"] == z["e1"] and z["DEFAULT throw"] == z["e1 throw"] == (25.0,)
    from tests.test_merge_instants import _shape

    assert z["DEFAULT"] == (float(_shape(1)[70, 2] + 1.5),)


def test_a_version_with_children_and_a_refresh_after_the_merge(conn: Conn, series: int) -> None:
    _one_side_each(conn, series)
    tgsis.create_version(conn, "e2", "e1")  # a child of e1, not merged
    conn.commit()
    assert_same_merge(conn, "e1")
    conn.execute("SELECT tgsis.merge_version('e1')")  # the psql merge, kept
    conn.commit()
    for version, step in (("e1", "move 2 south"), ("DEFAULT", "delete 4"), ("DEFAULT", "move 1 south")):
        _step(conn, version, step, series)
    assert_same_merge(conn, "e1", "refresh")
    theirs, mine = both_merges(conn, "e1", "merge", True)  # removing a version with children: refused alike
    assert theirs[:2] == mine[:2] == ("refused", "TG202"), (theirs, mine)


def test_conflicts_of_instants_kept_by_pg_dump_and_restore_then_merged_in_psql(
    conn: Conn, series: int, db_dsn: str, pg: Any, tmp_path: Any
) -> None:
    from tests.test_backup import _bindir_of, _restored

    _one_side_each(conn, series)
    [conflict] = tgsis.find_conflicts(conn, "e1")  # the slices' regions stored by the Python client
    assert [(r.times, r.changed_by) for r in conflict.regions] == [(1.0, "child"), (3.0, "parent")]
    conn.commit()
    theirs, _ = both_merges(conn, "e1")
    for fmt in ("plain", "custom"):
        with _restored(pg, _bindir_of(pg), db_dsn, fmt, tmp_path) as dsn, psycopg.connect(dsn) as restored:
            mine = _outcome(restored, lambda: int(restored.execute("SELECT tgsis.merge_version('e1')").fetchone()[0]))  # type: ignore[index]
            assert mine[0] == "done", mine
            assert mine[1] == theirs[1]
            for table in theirs[2]:
                assert mine[2][table] == theirs[2][table], (fmt, table)


@pytest.mark.parametrize("name", ["north edit", 'o\'brien "x"'])
def test_the_refusal_of_an_unsolved_region_of_an_instant_names_the_commands_with_the_name_quoted(
    conn: Conn, series: int, name: str
) -> None:
    tgsis.create_version(conn, name)
    conn.commit()
    move(conn, name, series, 2.0, NORTH, CHILD_SHIFT)
    move(conn, "DEFAULT", series, 2.0, NORTH[:4], PARENT_SHIFT)  # overlaps: a conflicting region, unsolved
    with pytest.raises(psycopg.Error) as caught:
        conn.execute("SELECT tgsis.merge_version(%s)", (name,))
    conn.rollback()
    hint = caught.value.diag.message_hint or ""
    command = hint.split("`")[1]
    assert shlex.split(command) == ["tgsis", "version", "merge", name], hint
    call = hint.split("tgsis.merge_version(conn, ")[1].split(") in Python")[0]
    assert ast.literal_eval(call) == name, hint


def _second_series(conn: Conn) -> int:
    """Another surface at TIMES in the class of make_series, in DEFAULT and (through the version's base) in e1."""
    from tests.test_merge_instants import _porosity, _shape
    from tgsis.temporal import SurfaceSeries

    cells = _new_surface(0).cells
    surfaces = [tgsis.Surface(_shape(i) + 100.0, cells, vertex_properties={"porosity": _porosity()}) for i in range(3)]
    series = SurfaceSeries(np.asarray(TIMES), surfaces, properties={"throw": np.asarray([1.0, 2.0, 3.0])})
    return int(tgsis.insert_feature(conn, "horizons", series))


@pytest.mark.parametrize("first", ["merges", "conflicts"])
def test_two_surfaces_at_instants_in_one_psql_merge(conn: Conn, first: str) -> None:
    """Each merged by its own call in one transaction: the work tables of the one before (left when it found an
    object-level conflict) are no obstacle; a conflict of one refuses the whole merge, as in Python."""
    tgsis.create_feature_class(
        conn,
        "horizons",
        "SURFACE",
        time_model="INSTANTS",
        cell_properties=[("porosity", "float8")],
        instant_properties=[("throw", "double precision")],
    )
    tgsis.enable_feature_versioning(conn)
    a = _second_series(conn)
    b = _second_series(conn)
    tgsis.create_version(conn, "e1")
    conn.commit()
    if first == "conflicts":  # an instant removed in the version and moved in the parent: object-level
        _step(conn, "e1", "delete 2", a)
        _step(conn, "DEFAULT", "move 2 south", a)
    else:
        _step(conn, "e1", "move 1 north", a)
        _step(conn, "DEFAULT", "move 2 south", a)
    _step(conn, "e1", "add 4", b)
    _step(conn, "DEFAULT", "move 3 south", b)
    if first == "merges":
        assert_same_merge(conn, "e1")
    else:
        theirs, mine = both_merges(conn, "e1")
        assert theirs[:2] == mine[:2] == ("refused", "TG302"), (theirs, mine)


def test_a_row_the_version_rewrote_alike_at_an_instant_only_it_changed_merges_as_in_python(
    conn: Conn, series: int
) -> None:
    """A triangle's vertices rotated (the same oriented triangle: merge3 sees no change) at an instant the version
    moved elsewhere: the psql merge runs merge3's regions on that instant (tgsis.merge_instant_by_region), so it
    keeps the parent's row there as the Python merge does (it refused it by name before)."""
    move(conn, "e1", series, 2.0, NORTH, CHILD_SHIFT)
    _sql(
        conn,
        "e1",
        "UPDATE tgsis.times_trgl SET vrtxid1 = vrtxid2, vrtxid2 = vrtxid3, vrtxid3 = vrtxid1"
        " WHERE geoid = %s AND times = 2 AND trglid = 150",
        (series,),
    )
    move(conn, "DEFAULT", series, 3.0, SOUTH, PARENT_SHIFT)
    assert_same_merge(conn, "e1")


def test_a_psql_merge_of_many_surfaces_holds_no_lock_per_surface(conn: Conn) -> None:
    """Each surface's merge works in the same work tables: a merge of many objects must not run out of the shared
    lock table (a table created and dropped per object keeps its lock until the transaction ends)."""
    tgsis.create_feature_class(
        conn,
        "horizons",
        "SURFACE",
        time_model="INSTANTS",
        cell_properties=[("porosity", "float8")],
        instant_properties=[("throw", "double precision")],
    )
    tgsis.enable_feature_versioning(conn)
    ids = [_second_series(conn) for _ in range(4)]
    tgsis.create_version(conn, "e1")
    conn.commit()
    for geoid in ids:
        _step(conn, "e1", "move 1 north", geoid)
        _step(conn, "DEFAULT", "move 3 south", geoid)
    conn.execute("SELECT tgsis.merge_version('e1')")
    gone = conn.execute(
        "SELECT count(*) FROM pg_locks WHERE pid = pg_backend_pid() AND locktype = 'relation'"
        " AND relation NOT IN (SELECT oid FROM pg_class)"
    ).fetchone()
    conn.rollback()
    assert gone == (0,)


def test_the_class_property_rows_are_written_as_the_class_owner_never_as_tgsis_owner(
    conn: Conn, series: int, db_dsn: str
) -> None:
    from psycopg import sql

    from tests.roles import login_roles

    _one_side_each(conn, series)  # writes vertex property rows (instant 4) and a per-instant row (instant 2)
    with login_roles(db_dsn, {"carol": "tgsis_admin"}) as made:
        carol = made.name("carol")
        # carol owns the class's property storage: tgsis reads and writes it through her runners; her trigger logs
        conn.execute(
            """
            CREATE TABLE public.who_wrote (who name, what text);
            GRANT INSERT ON public.who_wrote TO PUBLIC;
            CREATE FUNCTION public.log_who() RETURNS trigger LANGUAGE plpgsql AS $$
                BEGIN INSERT INTO public.who_wrote VALUES (current_user, TG_TABLE_NAME || ' ' || TG_OP); RETURN NULL; END $$;
            """
        )
        for table in ("horizons_cellpros", "horizons_pros"):
            conn.execute(
                sql.SQL("ALTER TABLE {} OWNER TO {}").format(
                    sql.Identifier("public", f"{table}_ver"), sql.Identifier(carol)
                )
            )
            conn.execute("SELECT tgsis.restore_storage_runner(%s)", (f"public.{table}",))
            conn.execute(
                sql.SQL(
                    "CREATE TRIGGER who AFTER INSERT OR UPDATE OR DELETE ON {} FOR EACH STATEMENT EXECUTE FUNCTION public.log_who()"
                ).format(sql.Identifier("public", f"{table}_ver"))
            )
        conn.commit()
        assert_same_merge(conn, "e1")
        with conn.transaction(force_rollback=True):
            conn.execute("SELECT tgsis.merge_version('e1')")
            log = conn.execute("SELECT who, what FROM public.who_wrote").fetchall()
        conn.rollback()
        assert {what.split()[0] for _, what in log} == {"horizons_cellpros_ver", "horizons_pros_ver"}, log
        assert {who for who, _ in log} == {carol}, log
