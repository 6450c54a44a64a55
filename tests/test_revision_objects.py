"""The notes of changed objects (tgsis.revision_objects) that merges, refreshes and conflict checks read.

Every writer of versioned storage notes which objects it wrote or closed in a
revision; tgsis.changed_objects reads those objects' rows by key instead of
scanning every table. A missing note would be a change a merge never copies,
so each write path is checked against a scan of the storage itself, and the
notes are shown to be what the merge reads (take them away and it finds
nothing). Hostile cases: nobody writes notes by hand or in another version's
revisions, two writers of one object never wait for each other's note, and
deleting versions, compressing and disabling versioning leave no stale notes.
"""

from __future__ import annotations

from typing import Any

import psycopg
import pytest
from psycopg import sql

import tgsis
from tests.roles import login_roles
from tests.sessions import connect
from tests.storage_data import storage_of
from tests.synthetic import flat_grid
from tgsis.db import features as F

Conn = psycopg.Connection[Any]


@pytest.fixture
def items(conn: Conn) -> Conn:
    """items (objid, part, val) of objects 1..4 with 3 parts each, versioned as object class 'item'; version 'child'."""
    conn.execute("CREATE TABLE items (objid int, part int, val int NOT NULL, PRIMARY KEY (objid, part))")
    conn.execute("INSERT INTO items SELECT o, p, 0 FROM generate_series(1, 4) o, generate_series(1, 3) p")
    tgsis.enable_versioning(conn, "items", "objid", "item")
    tgsis.create_version(conn, "child")
    conn.commit()
    return conn


def _scanned(conn: Conn, revisions: list[int]) -> set[tuple[str, str, str]]:
    """(object class, key, short name) of every row version written or closed in the revisions: a scan of storage
    (``tgsis.storage_table``: ``<t>_ver``, or a model table's chunk versions)."""
    found: set[tuple[str, str, str]] = set()
    for schema, table, key, objectclass, shortname in conn.execute(
        "SELECT schemaname, tablename, objectkeyfield, objectclass, shortname FROM tgsis.versioned_tables"
    ).fetchall():
        rows = conn.execute(
            sql.SQL(
                "SELECT DISTINCT {}::text FROM {} WHERE revision = ANY (%(r)s::int[]) OR lastrevs && %(r)s::int[]"
            ).format(sql.Identifier(key), sql.SQL(storage_of(conn, table, schema))),
            {"r": revisions},
        ).fetchall()
        found |= {(objectclass, k, shortname) for (k,) in rows}
    return found


def _changed(conn: Conn, revisions: list[int]) -> set[tuple[str, str, str]]:
    rows = conn.execute(
        "SELECT objectclass, objectkey, shortname FROM tgsis.changed_objects(%s::int[])", (revisions,)
    ).fetchall()
    return {(c, k, s) for c, k, s in rows}


def _own(conn: Conn, version: str) -> list[int]:
    (revs,) = conn.execute("SELECT tgsis.own_working_revisions(tgsis.version_id(%s))", (version,)).fetchone()  # type: ignore[misc]
    return list(revs)


def _fails(conn: Conn, statement: str, sqlstate: str, match: str) -> None:
    with pytest.raises(psycopg.Error, match=match) as caught:
        conn.execute(statement)
    conn.rollback()
    assert caught.value.sqlstate == sqlstate


def _same_as_scan(conn: Conn, version: str) -> set[tuple[str, str, str]]:
    revisions = _own(conn, version)
    changed = _changed(conn, revisions)
    assert changed == _scanned(conn, revisions)
    return changed


def test_writes_through_the_view_are_noted_once_per_object(items: Conn) -> None:
    conn = items
    with tgsis.in_version(conn, "child"):
        conn.execute("UPDATE items SET val = 1 WHERE objid = 1")  # inherited rows: closed, written anew
        conn.execute("UPDATE items SET val = 2 WHERE objid = 1 AND part = 1")  # its own row, changed in place
        conn.execute("DELETE FROM items WHERE objid = 2 AND part = 3")  # an inherited row closed
        conn.execute("INSERT INTO items VALUES (9, 1, 5)")  # a new object
        conn.execute("UPDATE items SET objid = 7 WHERE objid = 3 AND part = 2")  # a key change: two objects
        conn.commit()
    assert _same_as_scan(conn, "child") == {("item", k, "items") for k in ("1", "2", "3", "7", "9")}
    (working,) = _own(conn, "child")
    notes = conn.execute(
        "SELECT objectkey, count(*) FROM tgsis.revision_objects WHERE revision = %s GROUP BY 1 ORDER BY 1", (working,)
    ).fetchall()
    assert notes == [(k, 1) for k in ("1", "2", "3", "7", "9")], "one note per object, not per row"
    # revision 0 (the rows enable_versioning found) is never noted: asked about it, changed_objects scans
    assert conn.execute("SELECT count(*) FROM tgsis.revision_objects WHERE revision = 0").fetchone() == (0,)
    assert _changed(conn, [0]) == _scanned(conn, [0]) == {("item", k, "items") for k in ("1", "2", "3", "4")}


def test_a_view_write_from_a_trigger_of_the_users_is_noted(items: Conn) -> None:
    conn = items
    conn.execute("CREATE TABLE inbox (objid int, part int, val int)")
    conn.execute(
        "CREATE FUNCTION inbox_to_items() RETURNS trigger LANGUAGE plpgsql AS $$ "
        "BEGIN INSERT INTO items VALUES (NEW.objid, NEW.part, NEW.val); RETURN NULL; END $$"
    )
    conn.execute("CREATE TRIGGER forward AFTER INSERT ON inbox FOR EACH ROW EXECUTE FUNCTION inbox_to_items()")
    with tgsis.in_version(conn, "child"):
        conn.execute("INSERT INTO inbox VALUES (11, 1, 1), (12, 1, 1)")
        conn.commit()
    assert _same_as_scan(conn, "child") == {("item", "11", "items"), ("item", "12", "items")}


def test_direct_inserts_into_storage_are_noted_for_owner_and_editor(items: Conn, db_dsn: str) -> None:
    conn = items
    with tgsis.in_version(conn, "child"):
        (working,) = conn.execute("SELECT revision FROM tgsis.write_revision()").fetchone()  # type: ignore[misc]
        conn.execute(
            "INSERT INTO items_ver (objid, part, val, revision) VALUES (20, 1, 1, %s), (20, 2, 1, %s)",
            (working, working),
        )
        with conn.cursor().copy("COPY items_ver (objid, part, val, revision) FROM STDIN") as copy:
            copy.write_row((21, 1, 1, working))
        conn.commit()
    conn.execute("GRANT SELECT, INSERT ON items, items_ver TO tgsis_editor")
    conn.execute("SELECT tgsis.grant_version('child', 'write', 'public')")
    conn.commit()
    with login_roles(db_dsn, {"ed": "tgsis_editor"}) as roles:
        ed = roles.connect("ed")
        tgsis.goto_version(ed, "child")
        with ed.cursor().copy("COPY items_ver (objid, part, val, revision) FROM STDIN") as copy:
            copy.write_row((22, 1, 1, working))
        ed.commit()
    assert _same_as_scan(conn, "child") == {("item", k, "items") for k in ("20", "21", "22")}


def test_uploads_deletes_and_merges_of_features_are_noted(conn: Conn) -> None:
    F.create_feature_class(conn, "horizons", "SURFACE", feature_properties={"note": "text"})
    tgsis.enable_feature_versioning(conn)
    kept = F.insert_feature(conn, "horizons", flat_grid(4, 1.0), {"note": "kept"})
    gone = F.insert_feature(conn, "horizons", flat_grid(4, 2.0), {"note": "gone"})
    tgsis.create_version(conn, "edit")
    conn.commit()
    with tgsis.in_version(conn, "edit"):
        new = F.insert_feature(conn, "horizons", flat_grid(3, 5.0), {"note": "new"})  # binary COPY into storage
        F.delete_feature(conn, "horizons", gone)  # set-based close
        conn.commit()
    changed = _same_as_scan(conn, "edit")
    assert {k for _, k, _ in changed} == {str(new), str(gone)}
    assert {s for _, k, s in changed if k == str(gone)} >= {"geometry", "vrtx", "trgl", "public.horizons"}
    tgsis.merge_version(conn, "edit")  # copies into DEFAULT's revision
    conn.commit()
    (parent,) = conn.execute(
        "SELECT revision FROM tgsis.revisions WHERE versionid = 0 ORDER BY revision DESC OFFSET 1 LIMIT 1"
    ).fetchone()  # type: ignore[misc]
    assert _changed(conn, [parent]) == _scanned(conn, [parent])
    assert {k for _, k, _ in _changed(conn, [parent])} == {str(new), str(gone)}
    assert str(kept) not in {k for _, k, _ in _changed(conn, [parent])}
    # a dropped class takes its tables' notes along
    notes = "SELECT count(*) FROM tgsis.revision_objects WHERE schemaname = 'public' AND tablename LIKE 'horizons%'"
    assert conn.execute(notes).fetchone() != (0,)
    tgsis.drop_feature_class(conn, "horizons", force=True)
    conn.commit()
    assert conn.execute(notes).fetchone() == (0,)


def test_the_notes_are_what_a_merge_reads(items: Conn) -> None:
    """Taken away, the merge finds nothing to copy: no test of a write path above can pass by a scan."""
    conn = items
    with tgsis.in_version(conn, "child"):
        conn.execute("UPDATE items SET val = 5 WHERE objid = 1")
        conn.commit()
    conn.execute("UPDATE items SET val = 6 WHERE objid = 1")  # DEFAULT too: a conflict
    conn.commit()
    assert [c.objectkey for c in tgsis.find_conflicts(conn, "child")] == ["1"]
    revisions = _own(conn, "child")
    conn.execute("DELETE FROM tgsis.revision_objects WHERE revision = ANY (%s)", (revisions,))
    assert _changed(conn, revisions) == set()
    assert tgsis.find_conflicts(conn, "child") == []
    conn.rollback()
    assert [c.objectkey for c in tgsis.find_conflicts(conn, "child")] == ["1"]


def test_nobody_writes_notes_by_hand_or_in_another_versions_revision(items: Conn, db_dsn: str) -> None:
    conn = items
    tgsis.create_version(conn, "other")
    conn.execute("GRANT SELECT, INSERT, UPDATE, DELETE ON items TO tgsis_editor")
    conn.commit()
    before = conn.execute("SELECT count(*) FROM tgsis.revision_objects").fetchone()
    with login_roles(db_dsn, {"ed": "tgsis_editor", "reader": "tgsis_reader"}) as roles:
        conn.execute("SELECT tgsis.grant_version('child', 'write', %s)", (roles.name("ed"),))
        conn.commit()
        ed = roles.connect("ed")
        for statement in (
            "INSERT INTO tgsis.revision_objects VALUES (99, 'public', 'items', '1')",
            "DELETE FROM tgsis.revision_objects",
            "UPDATE tgsis.revision_objects SET revision = 1",
            "SELECT tgsis.note_changed_objects('public', 'items', 99, ARRAY['1'])",
        ):
            with pytest.raises(psycopg.errors.InsufficientPrivilege):
                ed.execute(statement)
            ed.rollback()
        # through the function the views' triggers call: only in the caller's own working revision
        tgsis.goto_version(ed, "other")
        _fails(ed, "SELECT tgsis.record_changed_objects('public', 'items', ARRAY['1'])", "TG002", "'other'")
        _fails(
            ed,
            "SELECT tgsis.record_changed_objects('public', 'nope', ARRAY['1'])",
            "TG200",
            r"table public\.nope is not versioned",
        )
        tgsis.goto_version(ed, "child")
        ed.execute("SELECT tgsis.record_changed_objects('public', 'items', ARRAY['1'])")
        ed.commit()
        reader = roles.connect("reader")
        tgsis.goto_version(reader, "child")
        _fails(reader, "SELECT tgsis.record_changed_objects('public', 'items', ARRAY['2'])", "TG002", "'child'")
    after = conn.execute("SELECT revision, objectkey FROM tgsis.revision_objects").fetchall()
    assert before == (0,) and after == [(_own(conn, "child")[0], "1")]


def test_two_writers_of_one_object_do_not_wait_for_each_others_note(items: Conn, db_dsn: str) -> None:
    conn = items
    first, second = connect(db_dsn, "first"), connect(db_dsn, "second")
    try:
        for session in (first, second):
            tgsis.goto_version(session, "child")
        first.execute("UPDATE items SET val = 1 WHERE objid = 1 AND part = 1")  # its note not committed yet
        second.execute("SET lock_timeout = '2s'")
        second.execute("UPDATE items SET val = 1 WHERE objid = 1 AND part = 2")  # would wait on a unique note key
        second.commit()
        first.commit()
    finally:
        first.close()
        second.close()
    assert _same_as_scan(conn, "child") == {("item", "1", "items")}
    (working,) = _own(conn, "child")
    assert conn.execute("SELECT count(*) FROM tgsis.revision_objects WHERE revision = %s", (working,)).fetchone() == (
        2,
    ), "each session noted the object itself"


def test_deleting_compressing_and_disabling_leave_no_stale_notes(items: Conn) -> None:
    conn = items
    tgsis.create_version(conn, "gone")
    for version in ("child", "gone"):
        with tgsis.in_version(conn, version):
            conn.execute("UPDATE items SET val = 3 WHERE objid = 2")
            conn.commit()
    gone = _own(conn, "gone")
    assert conn.execute(
        "SELECT count(*) FROM tgsis.revision_objects WHERE revision = ANY (%s)", (gone,)
    ).fetchone() == (1,)
    tgsis.delete_version(conn, "gone")
    conn.commit()
    assert conn.execute(
        "SELECT count(*) FROM tgsis.revision_objects WHERE revision = ANY (%s)", (gone,)
    ).fetchone() == (0,)
    assert conn.execute(
        "SELECT count(*) FROM items_ver WHERE revision = ANY (%s::int[]) OR lastrevs && %s::int[]", (gone, gone)
    ).fetchone() == (0,), "its rows went, and the rows it closed are open again"
    # a merged version's old revisions go at the next compress, with their notes
    tgsis.merge_version(conn, "child")
    with tgsis.in_version(conn, "child"):
        conn.execute("UPDATE items SET val = 4 WHERE objid = 3")
        conn.commit()
    conn.execute("SELECT tgsis.compress_versions()")
    conn.commit()
    stale = conn.execute(
        "SELECT count(*) FROM tgsis.revision_objects o WHERE NOT EXISTS "
        "(SELECT FROM tgsis.revisions r WHERE r.revision = o.revision)"
    ).fetchone()
    assert stale == (0,)
    assert conn.execute("SELECT count(*) FROM tgsis.revision_objects").fetchone() != (0,)
    assert _same_as_scan(conn, "child") == {("item", "3", "items")}
    tgsis.merge_version(conn, "child", remove=True)
    tgsis.disable_versioning(conn, "items")
    conn.commit()
    assert conn.execute("SELECT count(*) FROM tgsis.revision_objects").fetchone() == (0,)
