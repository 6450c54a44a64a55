"""The versioning machinery on model tables stored in chunks (issue 40, docs/storage.md "Versioning of chunks").

After the storage switch (``tgsis.store_in_chunks``) a versioned model table's
storage is ``tgsis.<table>_chunk``: the functions that act on a versioned
table's storage generically (merge and refresh through
``tgsis.copy_object_state``, ``delete_version``, ``compress_versions``,
``close_object_rows``, ``disable_feature_versioning``, the diffs, ``rows_at``,
conflicts) act on chunk versions, and report rows by decoding them. Each test
builds its history in row storage through the public API and switches every
model-1 table (when the harness has not already: ``TGSIS_TEST_STORAGE=chunks``).
"""

from __future__ import annotations

from typing import Any

import psycopg
from psycopg import sql

import tgsis
from tests.merge_data import every_view, move, sqlstate, varied_history
from tests.roles import login_roles

Conn = psycopg.Connection[Any]

MODEL1 = ("vrtx", "point", "segment", "trgl", "tetra")


def switch_all(conn: Conn) -> bool:
    """Every model-1 table stored in chunks (committed); whether some were switched here (not by the harness)."""
    switched = False
    for table in MODEL1:
        if not (conn.execute("SELECT tgsis.stored_in_chunks(%s)", (table,)).fetchone() or (False,))[0]:
            conn.execute("SELECT tgsis.store_in_chunks(%s)", (table,))
            switched = True
    conn.commit()
    assert conn.execute("SELECT tgsis.storage_table('tgsis', 'vrtx')").fetchone() == ("tgsis.vrtx_chunk",)
    return switched


def vertices(conn: Conn) -> list[tuple[Any, ...]]:
    """What ``tgsis.vrtx`` shows the session, in key order, doubles as their bits."""
    return [
        tuple(r)
        for r in conn.execute(
            "SELECT geoid, vrtxid, float8send(x), float8send(y), float8send(z) FROM tgsis.vrtx ORDER BY 1, 2"
        ).fetchall()
    ]


def seen_by_every_view(conn: Conn) -> dict[tuple[str, int | None], list[tuple[Any, ...]]]:
    """The vertices under every working set and every revision (SET LOCAL: nothing committed)."""
    seen = {}
    for version, revision in every_view(conn):
        if revision is None:
            conn.execute("SELECT tgsis.goto_version(%s, true)", (version,))
        else:
            conn.execute("SELECT tgsis.goto_revision(%s, %s, true)", (version, revision))
        seen[(version, revision)] = vertices(conn)
    conn.rollback()
    return seen


def versions_of(conn: Conn) -> list[str]:
    return [str(r[0]) for r in conn.execute("SELECT name FROM tgsis.versions ORDER BY versionid").fetchall()]


def test_diffs_rows_at_and_conflict_reports_read_the_same_rows_after_the_switch(conn: Conn, fault_clone: int) -> None:
    # (failed before: diff_table, rows_at and conflict_rows read tgsis.vrtx_ver, which the switch drops)
    varied_history(conn, fault_clone)
    move(conn, "e1", fault_clone, [40, 41], (0.25, 0.0, 0.0))  # both sides of e2 change vertex 40: a conflict
    move(conn, "e2", fault_clone, [40], (0.0, -0.5, 0.0))
    conn.commit()
    names = versions_of(conn)
    pairs = [(a, b) for a in names for b in names if a != b]

    def report() -> dict[str, Any]:
        out: dict[str, Any] = {}
        for a, b in pairs:
            out[f"diff {a} {b}"] = conn.execute(
                "SELECT * FROM tgsis.diff_versions(%s, %s) ORDER BY 1, 2, 3", (a, b)
            ).fetchall()
        for version in names:
            out[f"rows {version}"] = conn.execute(
                "SELECT geoid, vrtxid, float8send(x), float8send(y), float8send(z) "
                "FROM tgsis.rows_at(NULL::tgsis.vrtx, %s) ORDER BY 1, 2",
                (version,),
            ).fetchall()
        named = conn.execute("SELECT revision FROM tgsis.revisions WHERE name = 'e1 first'").fetchone()
        assert named is not None
        out["rows at e1 first"] = conn.execute(
            "SELECT geoid, vrtxid, float8send(x) FROM tgsis.rows_at(NULL::tgsis.vrtx, 'e1', %s) ORDER BY 1, 2",
            (named[0],),
        ).fetchall()
        out["conflict rows"] = conn.execute(
            "SELECT shortname, side, rowkey, \"row\" FROM tgsis.conflict_rows('e2', 'feature', %s) "
            "WHERE shortname = 'vrtx' ORDER BY 1, 2, 3",
            (str(fault_clone),),
        ).fetchall()
        out["discards"] = conn.execute(
            "SELECT solution, discarded, rows_added, rows_removed, rows_changed, values_changed "
            "FROM tgsis.conflict_discards('e2') WHERE shortname = 'vrtx' ORDER BY 1, 2"
        ).fetchall()
        conn.rollback()
        return out

    before = report()
    # the rows that differ and only they: 40 (both sides), 41 (e1), 20 (e2, since varied_history's merge)
    assert {(r[1], r[2]["vrtxid"]) for r in before["conflict rows"]} >= {("child", 40), ("parent", 40), ("parent", 41)}
    assert {r[2]["vrtxid"] for r in before["conflict rows"]} == {20, 40, 41}
    assert any(rows for key, rows in before.items() if key.startswith("diff"))
    # only the moved vertices are edits: 40 and 41 in the parent, 40 and 20 in the version (rows storage counted the
    # parent's merged copies of the version's own base rows as 7 rows the parent added: fixed beside)
    assert [r[:5] for r in before["discards"]] == [
        ("base", "child", 0, 0, 2),
        ("base", "parent", 0, 0, 2),
        ("child", "parent", 0, 0, 2),
        ("parent", "child", 0, 0, 2),
    ]
    switch_all(conn)
    after = report()
    assert after == before


def test_merge_refresh_and_delete_version_write_chunk_versions(conn: Conn, fault_clone: int) -> None:
    # (failed before: tgsis.copy_object_state and delete_version wrote tgsis.vrtx_ver)
    varied_history(conn, fault_clone)
    switch_all(conn)
    conn.execute("SELECT tgsis.goto_version('DEFAULT')")
    default_before = vertices(conn)
    conn.rollback()
    move(conn, "e2", fault_clone, [5, 6], (0.0, 0.0, 2.5))
    conn.commit()
    written = conn.execute("SELECT tgsis.merge_version('e2')").fetchone()
    conn.commit()
    assert written is not None and written[0] > 0
    with tgsis.in_version(conn, "e1"):
        e1 = vertices(conn)
    with tgsis.in_version(conn, "e2"):
        e2 = vertices(conn)
    conn.rollback()
    assert e1 == e2  # the child's state is the parent's now
    # a second merge has nothing to copy: the parent holds the child's chunk versions' content
    assert conn.execute("SELECT tgsis.merge_version('e2')").fetchone() == (0,)
    conn.commit()
    # refresh: the parent's change reaches the child
    move(conn, "e1", fault_clone, [7], (1.0, 1.0, 1.0))
    conn.commit()
    conn.execute("SELECT tgsis.refresh_version('e2')")  # (no conflict: the new base shows it, nothing is written)
    conn.commit()
    with tgsis.in_version(conn, "e1"):
        e1 = vertices(conn)
    with tgsis.in_version(conn, "e2"):
        e2 = vertices(conn)
    conn.rollback()
    assert e1 == e2
    # a version deleted takes its chunk versions with it and reopens what it closed
    tgsis.create_version(conn, "tmp", "e1")
    conn.commit()
    move(conn, "tmp", fault_clone, [8, 9], (9.0, 9.0, 9.0))
    conn.commit()
    revisions = [
        r[0]
        for r in conn.execute(
            "SELECT revision FROM tgsis.revisions r JOIN tgsis.versions v USING (versionid) WHERE v.name = 'tmp'"
        ).fetchall()
    ]
    assert conn.execute(
        "SELECT count(*) FROM tgsis.vrtx_chunk WHERE revision = ANY (%s) OR lastrevs && %s::integer[]",
        (revisions, revisions),
    ).fetchone() != (0,)
    assert (conn.execute("SELECT tgsis.delete_version('tmp')").fetchone() or (0,))[0] > 0
    conn.commit()
    assert conn.execute(
        "SELECT count(*) FROM tgsis.vrtx_chunk WHERE revision = ANY (%s) OR lastrevs && %s::integer[]",
        (revisions, revisions),
    ).fetchone() == (0,)
    with tgsis.in_version(conn, "e1"):
        assert vertices(conn) == e1
    conn.execute("SELECT tgsis.goto_version('DEFAULT')")
    assert vertices(conn) == default_before  # no merge into DEFAULT was made
    conn.rollback()


def test_compress_versions_keeps_what_every_kept_view_sees_of_chunk_versions(conn: Conn, fault_clone: int) -> None:
    # (failed before: compress_versions read tgsis.vrtx_ver)
    varied_history(conn, fault_clone)
    switch_all(conn)
    before = seen_by_every_view(conn)
    stored = conn.execute("SELECT count(*) FROM tgsis.vrtx_chunk").fetchone()
    dry = conn.execute("SELECT what, name, removed FROM tgsis.compress_versions(true) ORDER BY 1, 2").fetchall()
    conn.commit()
    assert conn.execute("SELECT count(*) FROM tgsis.vrtx_chunk").fetchone() == stored  # a dry run changes nothing
    done = conn.execute("SELECT what, name, removed FROM tgsis.compress_versions() ORDER BY 1, 2").fetchall()
    conn.commit()
    assert done == dry
    assert ("rows", "tgsis.vrtx") in {(r[0], r[1]) for r in done}  # chunk versions nobody sees any more went
    after = seen_by_every_view(conn)
    assert set(after) <= set(before) and after
    for view, rows in after.items():
        assert rows == before[view], view


def test_feature_versioning_off_and_on_over_chunks_keeps_default_and_guards_the_chunk_table(
    db_dsn: str, conn: Conn, fault_clone: int
) -> None:
    # (failed before: disable_feature_versioning dropped a tgsis.vrtx_ver that is not there; the chunk table of a
    # versioned table kept UPDATE for the editors and took any revision from a direct INSERT)
    tgsis.disable_feature_versioning(conn)
    conn.commit()
    switch_all(conn)
    tgsis.enable_feature_versioning(conn)
    conn.commit()
    tgsis.create_version(conn, "child")
    conn.commit()
    default = vertices(conn)
    move(conn, "child", fault_clone, [1, 2], (0.0, 0.0, 4.0))
    conn.commit()
    triggers = conn.execute(
        "SELECT array_agg(tgname::text ORDER BY tgname) FROM pg_trigger WHERE tgrelid = 'tgsis.vrtx_chunk'::regclass"
    ).fetchone()
    # the guards of versioned storage, beside the check of direct inserts every chunk table has (tgsis.chunk_insert_check)
    assert triggers == (["tgsis_chunk_insert", "tgsis_storage_changes", "tgsis_storage_rows", "tgsis_storage_write"],)
    with login_roles(db_dsn, {"editor": "tgsis_editor"}) as roles:
        tgsis.grant_version(conn, "child", "write", roles.name("editor"))
        conn.commit()
        editor = roles.connect("editor")
        editor.execute("SELECT tgsis.goto_version('child')")
        editor.commit()
        # no direct change of stored chunk versions: they are every version's
        assert sqlstate(editor, "UPDATE tgsis.vrtx_chunk SET lastrevs = '{}'")[0] == "42501"
        assert sqlstate(editor, "DELETE FROM tgsis.vrtx_chunk")[0] == "42501"
        row = editor.execute("SELECT revision FROM tgsis.write_revision()").fetchone()
        assert row is not None
        working = int(row[0])
        insert = (
            "INSERT INTO tgsis.vrtx_chunk (geoid, chunk, revision, lastrevs, x, y, z) "
            "VALUES (%s, 77, %s, %s, '{1}', '{2}', '{3}')"
        )
        # a chunk version of another revision (DEFAULT's: 0), or one that comes in closed, is refused
        state, message = sqlstate(editor, insert, (fault_clone, 0, []))
        assert state == "TG002" and "vrtx_chunk" in message, message
        assert sqlstate(editor, insert, (fault_clone, working, [working]))[0] == "TG002"
        # one of its working revision is written, and noted as a change of the object in tgsis.vrtx
        assert sqlstate(editor, insert, (fault_clone, working, []))[0] is None
        editor.commit()
        assert conn.execute(
            "SELECT count(*) FROM tgsis.revision_objects WHERE revision = %s AND schemaname = 'tgsis' "
            "AND tablename = 'vrtx' AND objectkey = %s",
            (working, str(fault_clone)),
        ).fetchone() == (1,)
        editor.close()
    with tgsis.in_version(conn, "child"):
        assert conn.execute(
            "SELECT count(*) FROM tgsis.vrtx WHERE geoid = %s AND vrtxid = 77 * 1024", (fault_clone,)
        ).fetchone() == (1,)
    conn.rollback()
    # off again: DEFAULT's chunk versions stay as revision 0, the child's go, the storage's triggers go
    removed = tgsis.disable_feature_versioning(conn, force=True)
    conn.commit()
    assert removed > 0
    assert vertices(conn) == default
    assert conn.execute(
        "SELECT count(*) FILTER (WHERE revision <> 0 OR lastrevs <> '{}'), count(DISTINCT (geoid, chunk)) = count(*) "
        "FROM tgsis.vrtx_chunk"
    ).fetchone() == (0, True)
    assert conn.execute(
        "SELECT count(*) FROM pg_trigger WHERE tgrelid IN ('tgsis.vrtx_chunk'::regclass, 'tgsis.vrtx'::regclass) "
        "AND tgname IN ('tgsis_versioning_rights', 'tgsis_storage_write', 'tgsis_storage_rows', 'tgsis_storage_changes')"
    ).fetchone() == (0,)
    assert conn.execute("SELECT count(*) FROM tgsis.versioned_tables WHERE tablename = 'vrtx'").fetchone() == (0,)
    assert conn.execute("SELECT has_table_privilege('tgsis_editor', 'tgsis.vrtx_chunk', 'UPDATE')").fetchone() == (
        True,
    )  # given back from the face's
    # unversioned: a whole object's chunks go in one statement; some rows of an object are refused by name
    state, message = sqlstate(
        conn, "SELECT tgsis.delete_object_rows('tgsis', 'vrtx', 'geoid', %s, 'vrtxid', '{1}')", ([fault_clone],)
    )
    assert state == "TG100" and "stored in chunks" in message
    assert conn.execute(
        "SELECT tgsis.delete_object_rows('tgsis', 'trgl', 'geoid', %s)", ([fault_clone],)
    ).fetchone() == (1,)  # one chunk of triangles
    assert conn.execute("SELECT count(*) FROM tgsis.trgl WHERE geoid = %s", (fault_clone,)).fetchone() == (0,)
    conn.rollback()


def test_objects_deleted_in_a_version_close_their_chunk_versions(conn: Conn, fault_clone: int) -> None:
    # (failed before: close_object_rows wrote tgsis.vrtx_ver)
    switch_all(conn)
    default = vertices(conn)
    for table in ("vrtx", "trgl"):
        with tgsis.in_version(conn, "e1"):
            assert conn.execute(
                sql.SQL("SELECT tgsis.delete_object_rows('tgsis', {}, 'geoid', %s)").format(sql.Literal(table)),
                ([fault_clone],),
            ).fetchone() == (1,)  # the object's one chunk, closed
            conn.commit()
    with tgsis.in_version(conn, "e1"):
        assert conn.execute("SELECT count(*) FROM tgsis.vrtx WHERE geoid = %s", (fault_clone,)).fetchone() == (0,)
        state, message = sqlstate(
            conn, "SELECT tgsis.close_object_rows('tgsis', 'vrtx', 'geoid', %s, 'vrtxid', '{1, 2}')", ([fault_clone],)
        )
        assert state == "TG100" and "stored in chunks" in message
    conn.rollback()
    assert vertices(conn) == default  # DEFAULT's chunk version stays open
    assert conn.execute(
        "SELECT count(*) FROM tgsis.revision_objects o JOIN tgsis.versions v ON o.revision = v.workingrevision "
        "WHERE v.name = 'e1' AND o.tablename IN ('vrtx', 'trgl')"
    ).fetchone() == (2,)
    # the object's change in e1 is seen by the conflict machinery (tgsis.changed_objects) per chunk version
    changed = conn.execute(
        "SELECT shortname, objectkey FROM tgsis.changed_objects(ARRAY(SELECT workingrevision FROM tgsis.versions "
        "WHERE name = 'e1')) WHERE shortname IN ('vrtx', 'trgl') ORDER BY 1"
    ).fetchall()
    assert changed == [("trgl", str(fault_clone)), ("vrtx", str(fault_clone))]
    conn.rollback()


def test_a_reader_diffs_and_reads_versions_of_chunked_tables_with_its_own_rights(
    db_dsn: str, conn: Conn, fault_clone: int
) -> None:
    # (the decoded chunks are read as the caller: tgsis.storage_rows and storage_key are the tgsis roles' to run)
    switch_all(conn)
    move(conn, "e1", fault_clone, [3, 4], (0.5, 0.5, 0.5))
    conn.commit()
    diff = (
        "SELECT objectkey, shortname, added, removed, changed FROM tgsis.diff_versions('DEFAULT', 'e1') ORDER BY 1, 2"
    )
    rows = "SELECT count(*), sum(x) FROM tgsis.rows_at(NULL::tgsis.vrtx, 'e1')"
    expected = (conn.execute(diff).fetchall(), conn.execute(rows).fetchone())
    assert (str(fault_clone), "vrtx", 0, 0, 2) in expected[0]
    conn.rollback()
    with login_roles(db_dsn, {"reader": "tgsis_reader"}) as roles:
        reader = roles.connect("reader")
        assert (reader.execute(diff).fetchall(), reader.execute(rows).fetchone()) == expected
        assert reader.execute("SELECT count(*) FROM tgsis.changed_objects(ARRAY[1, 2, 3])").fetchone() != (0,)
        reader.close()


def test_solved_conflicts_keep_their_solutions_and_regions_across_the_switch(conn: Conn, fault_clone: int) -> None:
    # (the marks of a conflict fingerprint the stored versions: rows before the switch, chunk versions after it; the
    # next find_conflicts took every solved conflict for one changed again. tgsis.conflict_marks before the switch and
    # tgsis.renew_conflict_marks after it carry them)
    move(conn, "e1", fault_clone, [5], (0.0, 0.0, 1.0))
    move(conn, "DEFAULT", fault_clone, [5], (0.0, 0.0, -1.0))
    conn.commit()
    assert [c.solution for c in tgsis.find_conflicts(conn, "e1")] == ["unsolved"]
    conn.execute("SELECT tgsis.resolve_conflict('e1', 'feature', %s, 'child')", (str(fault_clone),))
    conn.commit()
    stored = "SELECT solution, childmark, parentmark FROM tgsis.conflicts ORDER BY objectkey"
    regions = "SELECT count(*) FROM tgsis.conflict_regions"
    solved = conn.execute(stored).fetchall()
    n_regions = conn.execute(regions).fetchone()
    assert [r[0] for r in solved] == ["child"] and n_regions != (0,)
    before = conn.execute("SELECT tgsis.conflict_marks()::text, jsonb_array_length(tgsis.conflict_marks())").fetchone()
    assert before is not None and before[1] == 1
    if switch_all(conn):  # the switch renews the marks (tgsis.store_in_chunks: conflict_marks, renew_conflict_marks)
        renewed_marks = conn.execute(stored).fetchall()
        assert renewed_marks[0][1:] != solved[0][1:]  # the marks are the chunk versions' now
        now = conn.execute("SELECT childmark, parentmark FROM tgsis.current_conflicts(1)").fetchall()
        assert now == [renewed_marks[0][1:]]
    assert conn.execute("SELECT solution FROM tgsis.find_conflicts('e1')").fetchall() == [("child",)]
    assert conn.execute(regions).fetchone() == n_regions
    conn.commit()
    # a later change on either side still shows: the object's marks move away from the stored ones
    renewed = conn.execute(stored).fetchall()
    move(conn, "e1", fault_clone, [5], (0.0, 0.0, 1.0))
    conn.commit()
    now = conn.execute("SELECT childmark, parentmark FROM tgsis.current_conflicts(1)").fetchall()
    assert now and now[0][0] != renewed[0][1] and now[0][1] == renewed[0][2]
    conn.rollback()


def test_guarding_the_chunk_table_of_a_table_switched_while_versioned(
    db_dsn: str, conn: Conn, fault_clone: int
) -> None:
    # (tgsis.store_in_chunks of a versioned table made the chunk table without the storage's triggers: a direct
    # INSERT of a chunk version of any revision went in; it calls tgsis.guard_chunk_storage now)
    switch_all(conn)
    guards = "SELECT count(*) FROM pg_trigger WHERE tgrelid = 'tgsis.trgl_chunk'::regclass AND tgname LIKE 'tgsis_storage_%%'"
    assert conn.execute(guards).fetchone() == (3,)  # by the switch itself
    for table in MODEL1:
        conn.execute("SELECT tgsis.guard_chunk_storage(%s)", (table,))  # again: the same triggers, once
    conn.commit()
    assert conn.execute(
        "SELECT count(*) FROM pg_trigger WHERE tgrelid = 'tgsis.trgl_chunk'::regclass AND tgname LIKE 'tgsis_storage_%%'"
    ).fetchone() == (3,)
    with login_roles(db_dsn, {"editor": "tgsis_editor"}) as roles:
        tgsis.grant_version(conn, "e1", "write", roles.name("editor"))
        conn.commit()
        editor = roles.connect("editor")
        editor.execute("SELECT tgsis.goto_version('e1')")
        editor.commit()
        state, message = sqlstate(
            editor,
            "INSERT INTO tgsis.vrtx_chunk (geoid, chunk, revision, x, y, z) VALUES (%s, 5, 0, '{1}', '{2}', '{3}')",
            (fault_clone,),
        )
        assert state == "TG002" and "vrtx_chunk" in message, message
        assert sqlstate(editor, "UPDATE tgsis.trgl_chunk SET lastrevs = '{}'")[0] == "42501"
        editor.close()
    state, message = sqlstate(conn, "SELECT tgsis.guard_chunk_storage('atom')")
    assert state == "TG200" and "atom" in message
