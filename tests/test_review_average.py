"""Hostile review of the object-level ``base`` (and ``average``) solutions of a conflict.

``base`` writes rows into a version for the caller: the rights, locks and
checks any other write into a version takes hold for it too — nobody gets in
through it, a writer of the version or a save in flight cannot make it write
into a frozen revision or leave a mix of states recorded ``manual``.
"""

from __future__ import annotations

import threading
import time
from typing import Any

import psycopg
import pytest

import tgsis
from tests.roles import login_roles
from tests.test_resolve_discards import private_state, story  # noqa: F401 - fixtures

Conn = psycopg.Connection[Any]


def _rocks(conn: Conn) -> None:
    """A versioned table rocks (class rock); rock 1 edited on both sides of version e1: a conflict."""
    conn.execute("CREATE TABLE rocks (id int PRIMARY KEY, kind text, grade float8)")
    conn.execute("INSERT INTO rocks VALUES (1, 'base', 1.0), (2, 'other', 2.0)")
    tgsis.enable_versioning(conn, "rocks", "id", "rock")
    tgsis.create_version(conn, "e1")
    conn.commit()
    with tgsis.in_version(conn, "e1"):
        conn.execute("UPDATE rocks SET kind = 'child', grade = 3.0 WHERE id = 1")
    conn.execute("UPDATE rocks SET kind = 'parent' WHERE id = 1")
    conn.commit()
    tgsis.find_conflicts(conn, "e1")
    conn.commit()


def _rows(conn: Conn, version: str) -> list[tuple[Any, ...]]:
    rows = conn.execute("SELECT id, kind, grade FROM tgsis.rows_at(NULL::rocks, %s) ORDER BY id", (version,)).fetchall()
    conn.commit()
    return rows


def _storage(conn: Conn) -> list[tuple[Any, ...]]:
    rows = conn.execute("SELECT id, kind, grade, revision, lastrevs FROM rocks_ver ORDER BY 1, 4").fetchall()
    conn.commit()
    return rows


def _refused(conn: Conn, query: str, params: tuple[Any, ...]) -> str | None:
    try:
        conn.execute(query, params)
    except psycopg.Error as exc:
        conn.rollback()
        return exc.sqlstate
    conn.commit()
    return None


def test_the_base_helper_is_not_callable_by_a_role_without_the_write_right(conn: Conn, db_dsn: str) -> None:
    """tgsis.resolve_conflict_base is SECURITY DEFINER: it must not be a way around resolve_conflict's checks."""
    _rocks(conn)
    with login_roles(db_dsn, {"rita": "tgsis_reader"}) as roles:
        conn.execute(f"GRANT SELECT ON rocks TO {roles.name('rita')}")
        conn.commit()
        before = _storage(conn)
        rita = roles.connect("rita")
        # resolve_conflict itself refuses her: no write right on e1
        assert _refused(rita, "SELECT tgsis.resolve_conflict('e1', 'rock', '1', 'base')", ()) == "TG002"
        state = _refused(rita, "SELECT tgsis.resolve_conflict_base('e1', 'rock', '1', '1')", ())
        assert state == "42501"  # permission denied for the function
        assert _storage(conn) == before
        assert _rows(conn, "e1")[0] == (1, "child", 3.0)


def test_base_needs_the_right_to_change_the_rows_of_the_table(conn: Conn, db_dsn: str) -> None:
    """A role that may only read rocks cannot revert the version's rows through base (as through the view)."""
    _rocks(conn)
    with login_roles(db_dsn, {"rita": "tgsis_editor"}) as roles:
        conn.execute(f"GRANT SELECT ON rocks TO {roles.name('rita')}")
        conn.execute("SELECT tgsis.grant_version('e1', 'write', %s)", (roles.name("rita"),))
        conn.commit()
        before = _storage(conn)
        rita = roles.connect("rita")
        # through the view she cannot change it
        rita.execute("SELECT set_config('tgsis.version', 'e1', false)")
        assert _refused(rita, "UPDATE rocks SET kind = 'base', grade = 1.0 WHERE id = 1", ()) == "42501"
        state = _refused(rita, "SELECT tgsis.resolve_conflict('e1', 'rock', '1', 'base')", ())
        assert state in ("42501", "TG002")
        assert _storage(conn) == before
        assert _rows(conn, "e1")[0] == (1, "child", 3.0)
        # with the rights, the Python route works for her (the locks it takes are hers to take)
        conn.execute(f"GRANT INSERT, UPDATE, DELETE ON rocks TO {roles.name('rita')}")
        conn.commit()
        solved = tgsis.resolve_conflict(rita, "e1", "rock", 1, "base")
        rita.commit()
        assert solved.solution == "manual"
        assert _rows(conn, "e1")[0] == (1, "base", 1.0)


def _blocked(admin: Conn, pid: int, seconds: float = 20.0) -> None:
    """Wait until backend pid waits for a lock."""
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        row = admin.execute("SELECT wait_event_type FROM pg_stat_activity WHERE pid = %s", (pid,)).fetchone()
        admin.commit()
        if row is not None and row[0] in ("Lock", "advisory"):
            return
        time.sleep(0.05)
    raise AssertionError(f"backend {pid} never waited for a lock")


def _run(target: Any) -> tuple[threading.Thread, list[BaseException]]:
    errors: list[BaseException] = []

    def body() -> None:
        try:
            target()
        except BaseException as exc:  # noqa: BLE001 - handed to the test
            errors.append(exc)

    thread = threading.Thread(target=body, daemon=True)
    thread.start()
    return thread, errors


def test_a_save_during_base_does_not_change_the_saved_revision_afterwards(conn: Conn, db_dsn: str) -> None:
    """base writes into the version's working revision: a save_revision in between must wait, not freeze it first.

    Otherwise the base's rows land in a revision already saved: what the saved revision shows changes after
    the save returned (a frozen revision rewritten).
    """
    _rocks(conn)
    holder = psycopg.connect(db_dsn)
    resolver = psycopg.connect(db_dsn, autocommit=True)
    saver = psycopg.connect(db_dsn)
    admin = psycopg.connect(db_dsn)
    try:
        holder.execute("LOCK TABLE rocks_ver IN EXCLUSIVE MODE")  # reads go on, base's first write waits
        pid = resolver.info.backend_pid
        t1, e1 = _run(lambda: resolver.execute("SELECT tgsis.resolve_conflict('e1', 'rock', '1', 'base')"))
        _blocked(admin, pid)
        seen: list[list[tuple[Any, ...]]] = []

        def save() -> None:
            saver.execute("SELECT set_config('tgsis.version', 'e1', false)")
            revision = tgsis.save_revision(saver, "checkpoint")
            saver.commit()
            seen.append(
                saver.execute(
                    "SELECT id, kind, grade FROM tgsis.rows_at(NULL::rocks, 'e1', %s) ORDER BY id", (revision,)
                ).fetchall()
            )
            saver.commit()
            seen.append([(revision,)])

        t2, e2 = _run(save)
        t2.join(1.0)  # the save waits for the base (fixed) or finishes at once (the defect)
        holder.rollback()
        t1.join(30)
        t2.join(30)
        assert not e1 and not e2, (e1, e2)
        [saved_rows, [(revision,)]] = seen
        now = admin.execute(
            "SELECT id, kind, grade FROM tgsis.rows_at(NULL::rocks, 'e1', %s) ORDER BY id", (revision,)
        ).fetchall()
        admin.commit()
        assert now == saved_rows  # a saved revision never changes
        assert _rows(conn, "e1")[0] == (1, "base", 1.0)
    finally:
        for c in (holder, resolver, saver, admin):
            c.close()


def test_base_waits_for_a_writer_of_the_object_in_the_version(conn: Conn, db_dsn: str) -> None:
    """A write of the object through the view in flight: base must wait for it and then write the whole base.

    Otherwise the version ends up with a mix (the writer's row over the base's), recorded manual.
    """
    _rocks(conn)
    writer = psycopg.connect(db_dsn)
    resolver = psycopg.connect(db_dsn, autocommit=True)
    admin = psycopg.connect(db_dsn)
    try:
        writer.execute("SELECT set_config('tgsis.version', 'e1', false)")
        writer.commit()
        writer.execute("UPDATE rocks SET kind = 'late', grade = 9.0 WHERE id = 1")
        writer.execute("INSERT INTO rocks VALUES (3, 'late', 9.0)")
        t1, e1 = _run(lambda: resolver.execute("SELECT tgsis.resolve_conflict('e1', 'rock', '1', 'base')"))
        t1.join(1.0)
        writer.commit()
        t1.join(30)
        assert not e1, e1
        rows = _rows(conn, "e1")
        assert rows[0] == (1, "base", 1.0), rows
        [c] = [c for c in tgsis.find_conflicts(conn, "e1") if c.objectkey == "1"]
        conn.commit()
        assert c.solution == "manual"
    finally:
        for c_ in (writer, resolver, admin):
            c_.close()


def test_base_in_a_repeatable_read_transaction_is_refused(conn: Conn, db_dsn: str) -> None:
    """A snapshot older than a writer's commit would leave that writer's rows beside the base's, recorded manual."""
    _rocks(conn)
    before = _storage(conn)
    reader = psycopg.connect(db_dsn)
    try:
        reader.execute("BEGIN ISOLATION LEVEL REPEATABLE READ")
        reader.execute("SELECT count(*) FROM tgsis.versions").fetchone()
        state = _refused(reader, "SELECT tgsis.resolve_conflict('e1', 'rock', '1', 'base')", ())
        assert state == "TG300"
    finally:
        reader.close()
    assert _storage(conn) == before


# --------------------------------------------------------------------------- average of two meshings: properties


def _with_zone(state: Any, zone: Any) -> Any:
    from tgsis.merge3 import MeshState

    return MeshState(
        state.cell_size,
        state.vertex_ids,
        state.vertices,
        state.cell_ids,
        state.cells,
        {**state.vertex_properties, "zone": zone},
        state.cell_properties,
    )


@pytest.mark.parametrize("parent_subdivides", [False, True], ids=["child-subdivides", "parent-subdivides"])
def test_average_of_two_meshings_keeps_an_integer_property_a_code(parent_subdivides: bool) -> None:
    """A code (an integer vertex property: a zone, a facies) is not averaged into a value no side has.

    The one-meshing average keeps a property that is not real-valued (the parent's, docs/merge.md); the
    average of two meshings must not interpolate zones 1 and 3 into 2, nor turn the column into floats.
    """
    import numpy as np

    from tests.test_merge_average import _base, _moved, _subdivided
    from tgsis.db import regions as R
    from tgsis.merge3 import apply_solutions, three_way_merge

    base = _base()
    codes = np.array([1, 3, 7], dtype=np.int64)
    base = _with_zone(base, codes[base.vertex_ids % 3])
    split = _subdivided(base)
    # the new (centroid) vertices get the code of their triangle's first corner
    new = split.vertex_ids[base.n_vertices :]
    first = split.cells[np.isin(split.cells[:, 2], new)]
    zone_new = np.empty(len(new), dtype=np.int64)
    zone_new[np.searchsorted(new, first[:, 2])] = codes[first[:, 0] % 3]
    split = _with_zone(split, np.concatenate([codes[base.vertex_ids % 3], zone_new]))
    moved = _with_zone(_moved(base), codes[base.vertex_ids % 3])
    parent, child = (split, moved) if parent_subdivides else (moved, split)
    merge = three_way_merge(base, parent, child)
    [region] = merge.conflicts
    average = R.average_region(merge, region)
    zone = np.asarray(average.vertex_properties["zone"])
    assert zone.dtype.kind == "i", zone.dtype
    assert np.isin(zone, codes).all(), sorted(set(zone.tolist()) - set(codes.tolist()))
    # the real-valued porosity is still averaged
    assert np.asarray(average.vertex_properties["porosity"]).dtype.kind == "f"
    resolved = apply_solutions(merge, {region.index: average}, names={region.index: "average"})
    assert np.asarray(resolved.state.vertex_properties["zone"]).dtype.kind == "i"


# --------------------------------------------------------------------------- bad keys


def test_average_of_a_key_that_is_no_feature_id_is_a_clear_error(conn: Conn, db_dsn: str, capsys: Any) -> None:
    """'abc' or '1.5' as a feature's key: InvalidInputError naming it (the command fails with it, exit 1), not a ValueError."""
    from tgsis.cli import main
    from tgsis.errors import InvalidInputError

    _rocks(conn)
    for key in ("abc", "1.5", ""):
        with pytest.raises(InvalidInputError, match="feature id"):
            tgsis.resolve_conflict(conn, "e1", "feature", key, "average")
        conn.rollback()
    capsys.readouterr()
    code = main(["--dsn", db_dsn, "version", "resolve", "e1", "feature", "abc", "average", "--discard-other"])
    err = capsys.readouterr().err
    assert code == 1 and "'abc'" in err and "Traceback" not in err, (code, err)


# --------------------------------------------------------------------------- what base says it discards


def _object_rows(conn: Conn, version: str, geoid: int) -> dict[str, dict[tuple[Any, ...], Any]]:
    """Per versioned table of class feature, the object's rows the version sees: {row key: the row as json}."""
    tables = conn.execute(
        "SELECT format('%I.%I', schemaname, tablename), objectkeyfield, keycolumns FROM tgsis.versioned_tables"
        " WHERE objectclass = 'feature'"
    ).fetchall()
    out: dict[str, dict[tuple[Any, ...], Any]] = {}
    for table, keyfield, keys in tables:
        rows = conn.execute(
            f"SELECT to_jsonb(r) FROM tgsis.rows_at(NULL::{table}, %s) r WHERE r.{keyfield} = %s", (version, geoid)
        ).fetchall()
        out[table] = {tuple(r[0][k] for k in keys): r[0] for (r,) in ((x,) for x in rows)}
    conn.commit()
    return out


def _diff(old: dict[tuple[Any, ...], Any], new: dict[tuple[Any, ...], Any]) -> tuple[int, int, int]:
    """(rows added, removed, changed) from old to new."""
    return (
        len(new.keys() - old.keys()),
        len(old.keys() - new.keys()),
        sum(1 for k in old.keys() & new.keys() if old[k] != new[k]),
    )


def test_what_base_says_it_discards_is_what_a_direct_diff_finds(conn: Conn, story: dict[str, int]) -> None:  # noqa: F811
    """conflict_discards(solution base) per side against a plain diff of the object's rows before and after."""
    a = story["A"]
    # the note set on both sides (DEFAULT: 'checked'): an object-level conflict, so that base may drop every edit
    # (a mesh whose regions merge by themselves refuses base, the SQL finding its regions first)
    with tgsis.in_version(conn, "edit"):
        conn.execute("UPDATE domes SET note = 'reviewed' WHERE _geoid = %s", (a,))
    conn.commit()
    conn.execute("SELECT tgsis.find_conflicts('edit')")
    conn.commit()
    said = {
        (d.discarded, d.tablename): (d.rows_added, d.rows_removed, d.rows_changed)
        for d in tgsis.conflict_discards(conn, "edit", "feature", a)
        if d.solution == "base"
    }
    conn.commit()
    parent, child = _object_rows(conn, "DEFAULT", a), _object_rows(conn, "edit", a)
    solved = tgsis.resolve_conflict(conn, "edit", "feature", a, "base")
    conn.commit()
    after = _object_rows(conn, "edit", a)
    found = {}
    for side, rows in (("parent", parent), ("child", child)):
        for table in rows:
            counts = _diff(after[table], rows[table])  # the side's edits against the base the version holds now
            if counts != (0, 0, 0):
                found[side, table] = counts
    assert said == found
    assert solved.discarded is not None
    assert {
        (d.discarded, d.tablename): (d.rows_added, d.rows_removed, d.rows_changed) for d in solved.discarded
    } == found


# --------------------------------------------------------------------------- average keeps the parent's attributes


def test_average_of_a_whole_object_keeps_the_attributes_only_the_parent_changed(conn: Conn) -> None:
    """The parent renames the feature and both move the mesh: average records manual, the merge takes the version's
    object whole — so the parent's new name must be in the version too (as the merge by region brings it), or the
    merge silently puts the old name back."""
    from tests.merge_data import make_fault, move
    from tests.test_conflict_regions import MIDDLE

    geoid = make_fault(conn)
    move(conn, "e1", geoid, MIDDLE, (0.0, 0.0, 5.0))
    move(conn, "DEFAULT", geoid, MIDDLE, (0.0, 0.0, -7.0))
    conn.execute("UPDATE tgsis.geometry SET geoname = 'renamed in DEFAULT' WHERE geoid = %s", (geoid,))
    conn.commit()
    solved = tgsis.resolve_conflict(conn, "e1", "feature", geoid, "average")
    conn.commit()
    assert solved.solution == "manual"
    tgsis.merge_version(conn, "e1")
    conn.commit()
    with tgsis.in_version(conn, "DEFAULT"):
        [(name,)] = conn.execute("SELECT geoname FROM tgsis.geometry WHERE geoid = %s", (geoid,)).fetchall()
    assert name == "renamed in DEFAULT"


def test_base_with_an_empty_search_path(conn: Conn) -> None:
    """search_path = '' (a careful DBA's session): base through the Python route."""
    _rocks(conn)
    conn.execute("SET search_path = ''")
    conn.commit()
    solved = tgsis.resolve_conflict(conn, "e1", "rock", 1, "base")
    conn.commit()
    assert solved.solution == "manual" and solved.discarded
    conn.execute("RESET search_path")
    assert _rows(conn, "e1")[0] == (1, "base", 1.0)


def test_average_with_an_empty_search_path(conn: Conn) -> None:
    """search_path = '': the object-level average reads, writes and records as with the default path."""
    from tests.merge_data import make_fault, move
    from tests.test_conflict_regions import MIDDLE

    geoid = make_fault(conn)
    move(conn, "e1", geoid, MIDDLE, (0.0, 0.0, 5.0))
    move(conn, "DEFAULT", geoid, MIDDLE, (0.0, 0.0, -7.0))
    conn.execute("SET search_path = ''")
    conn.commit()
    averaged = tgsis.resolve_conflict(conn, "e1", "feature", geoid, "average")
    conn.commit()
    assert averaged.solution == "manual"


@pytest.mark.parametrize("deleter", ["e1", "DEFAULT"])
def test_base_of_an_object_deleted_on_one_side(conn: Conn, deleter: str) -> None:
    """One side deletes rock 1, the other changes it: base brings the base's row back on both, saying so."""
    conn.execute("CREATE TABLE rocks (id int PRIMARY KEY, kind text, grade float8)")
    conn.execute("INSERT INTO rocks VALUES (1, 'base', 1.0)")
    tgsis.enable_versioning(conn, "rocks", "id", "rock")
    tgsis.create_version(conn, "e1")
    conn.commit()
    changer = "DEFAULT" if deleter == "e1" else "e1"
    with tgsis.in_version(conn, deleter):
        conn.execute("DELETE FROM rocks WHERE id = 1")
    with tgsis.in_version(conn, changer):
        conn.execute("UPDATE rocks SET kind = 'changed' WHERE id = 1")
    conn.commit()
    solved = tgsis.resolve_conflict(conn, "e1", "rock", 1, "base")
    conn.commit()
    assert solved.discarded is not None
    said = {(d.discarded, d.rows_added, d.rows_removed, d.rows_changed) for d in solved.discarded}
    side = {"e1": "child", "DEFAULT": "parent"}
    assert said == {(side[deleter], 0, 1, 0), (side[changer], 0, 0, 1)}
    assert _rows(conn, "e1") == [(1, "base", 1.0)]
    tgsis.merge_version(conn, "e1")
    conn.commit()
    assert _rows(conn, "DEFAULT") == [(1, "base", 1.0)]
    # an object only one side has is no conflict: base is refused, nothing written
    with tgsis.in_version(conn, "e1"):
        conn.execute("INSERT INTO rocks VALUES (5, 'new', 5.0)")
    conn.commit()
    with pytest.raises(tgsis.NotFoundError):
        tgsis.resolve_conflict(conn, "e1", "rock", 5, "base")
    conn.rollback()
    assert (5, "new", 5.0) in _rows(conn, "e1")


def test_base_from_python_on_a_connection_whose_default_is_repeatable_read(conn: Conn, db_dsn: str) -> None:
    """A client whose connections default to REPEATABLE READ: the Python base runs its own READ COMMITTED
    transaction (as average does) rather than failing; inside the caller's open REPEATABLE READ it is refused."""
    _rocks(conn)
    client = psycopg.connect(db_dsn)
    try:
        client.isolation_level = psycopg.IsolationLevel.REPEATABLE_READ
        solved = tgsis.resolve_conflict(client, "e1", "rock", 1, "base")
        client.commit()
        assert solved.solution == "manual"
        assert _rows(conn, "e1")[0] == (1, "base", 1.0)
        client.execute("SELECT 1")  # the caller's own REPEATABLE READ transaction, open
        with pytest.raises(tgsis.Error) as refused:
            tgsis.resolve_conflict(client, "e1", "rock", 1, "base")
        assert refused.value.sqlstate == "TG300"
        client.rollback()
    finally:
        client.close()


@pytest.mark.parametrize("parent_subdivides", [False, True], ids=["child-subdivides", "parent-subdivides"])
def test_average_of_two_meshings_does_not_spread_a_removed_property_value(parent_subdivides: bool) -> None:
    """One side removed the porosity of one vertex (NaN: no property row); the other re-meshed the block.

    The average may drop that vertex's value (halfway between a value and none, as for one meshing), but not
    its neighbours': a value both sides kept was turned into NaN, i.e. its property row silently deleted.
    """
    import numpy as np

    import tests.test_merge_average as T
    from tgsis.db import regions as R
    from tgsis.merge3 import MeshState, three_way_merge

    base = T._base()
    moved = T._moved(base)
    porosity = np.asarray(moved.vertex_properties["porosity"], dtype=np.float64).copy()
    removed = int(T.INNER[5])
    porosity[removed] = np.nan
    moved = MeshState(
        3, moved.vertex_ids, moved.vertices, moved.cell_ids, moved.cells, {"porosity": porosity}, moved.cell_properties
    )
    split = T._subdivided(base)
    parent, child = (split, moved) if parent_subdivides else (moved, split)
    merge = three_way_merge(base, parent, child)
    [region] = merge.conflicts
    average = R.average_region(merge, region)
    values = np.asarray(average.vertex_properties["porosity"])
    assert set(average.vertex_ids[np.isnan(values)].tolist()) <= {removed}


def test_what_python_base_returns_includes_an_edit_committed_while_it_waited(conn: Conn, db_dsn: str) -> None:
    """A writer of the object in the version commits a new row while base waits for it: base removes that row,
    so the discards it returns must count it (they were read before the wait)."""
    conn.execute("CREATE TABLE layers (obj int, k text, v float8, PRIMARY KEY (obj, k))")
    conn.execute("INSERT INTO layers VALUES (1, 'a', 1.0), (1, 'b', 2.0)")
    tgsis.enable_versioning(conn, "layers", "obj", "layer")
    tgsis.create_version(conn, "e1")
    conn.commit()
    with tgsis.in_version(conn, "e1"):
        conn.execute("UPDATE layers SET v = 10 WHERE obj = 1 AND k = 'a'")
    conn.execute("UPDATE layers SET v = 20 WHERE obj = 1 AND k = 'a'")
    conn.commit()
    writer = psycopg.connect(db_dsn)
    resolver = psycopg.connect(db_dsn)
    try:
        writer.execute("SELECT set_config('tgsis.version', 'e1', false)")
        writer.commit()
        writer.execute("INSERT INTO layers VALUES (1, 'late', 9.0)")  # open: holds the object's write lock
        result: list[Any] = []
        thread, errors = _run(lambda: result.append(tgsis.resolve_conflict(resolver, "e1", "layer", 1, "base")))
        thread.join(1.0)
        writer.commit()
        thread.join(30)
        resolver.commit()
        assert not errors, errors
        [solved] = result
        rows = conn.execute("SELECT obj, k, v FROM tgsis.rows_at(NULL::layers, 'e1') ORDER BY k").fetchall()
        conn.commit()
        assert rows == [(1, "a", 1.0), (1, "b", 2.0)]  # the late row went with the version's edits
        child = [d for d in solved.discarded if d.discarded == "child"]
        assert [(d.rows_added, d.rows_changed) for d in child] == [(1, 1)]
    finally:
        writer.close()
        resolver.close()


def test_base_with_quotes_and_percent_signs_in_every_name(conn: Conn) -> None:
    """A table, a class and a version whose names hold quotes, %, and a space: base works and says so."""
    from psycopg import sql

    table = sql.Identifier("we'ird %s", "Rock's %I")
    conn.execute(sql.SQL("CREATE SCHEMA {}").format(sql.Identifier("we'ird %s")))
    conn.execute(sql.SQL("CREATE TABLE {} (id int PRIMARY KEY, kind text)").format(table))
    conn.execute(sql.SQL("INSERT INTO {} VALUES (1, 'base')").format(table))
    tgsis.enable_versioning(conn, table.as_string(conn), "id", "o'k %L")
    tgsis.create_version(conn, "it's 100% v")
    conn.commit()
    with tgsis.in_version(conn, "it's 100% v"):
        conn.execute(sql.SQL("UPDATE {} SET kind = 'child' WHERE id = 1").format(table))
    conn.execute(sql.SQL("UPDATE {} SET kind = 'parent' WHERE id = 1").format(table))
    conn.commit()
    notices: list[str] = []
    conn.add_notice_handler(lambda d: notices.append(d.message_primary or ""))
    row = conn.execute("SELECT solution FROM tgsis.resolve_conflict(%s, %s, '1', 'base')", ("it's 100% v", "o'k %L"))
    assert row.fetchone() == ("manual",)
    conn.commit()
    assert any("(solution base)" in n and "'it''s 100% v'" in n for n in notices), notices
    rows = conn.execute(
        sql.SQL("SELECT id, kind FROM tgsis.rows_at(NULL::{}, {})").format(table, sql.Literal("it's 100% v"))
    ).fetchall()
    assert rows == [(1, "base")]
