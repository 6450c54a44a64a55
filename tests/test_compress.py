"""Compress: revisions and row versions nobody can reach go; what every version and kept revision sees stays."""

from __future__ import annotations

from collections import Counter
from pathlib import Path
from typing import Any

import psycopg
import pytest
from psycopg import sql

import tgsis
from tests.synthetic import flat_grid
from tgsis.cli import main
from tgsis.db import features as F

Conn = psycopg.Connection[Any]
Snapshot = dict[tuple[str, int | None], dict[str, list[str]]]


def _write(conn: Conn, version: str, query: str, params: tuple[Any, ...] = ()) -> None:
    with tgsis.in_version(conn, version):
        conn.execute(query, params)
        conn.commit()


def _z(conn: Conn, version: str, geoid: int, vertex: int, z: float) -> None:
    _write(conn, version, "UPDATE tgsis.vrtx SET z = %s WHERE geoid = %s AND vrtxid = %s", (z, geoid, vertex))


def _depth(conn: Conn, version: str, well: int, depth: float) -> None:
    _write(conn, version, "UPDATE wells SET depth = %s WHERE id = %s", (depth, well))


def _one(conn: Conn, query: str, params: Any = ()) -> Any:
    row = conn.execute(query, params).fetchone()
    assert row is not None
    return row[0]


def _working(conn: Conn, version: str) -> int:
    return next(v.workingrevision for v in tgsis.list_versions(conn) if v.name == version)


def _save(conn: Conn, version: str, name: str) -> int:
    with tgsis.in_version(conn, version):
        return tgsis.save_revision(conn, name)


@pytest.fixture
def tree(conn: Conn) -> dict[str, Any]:
    """A versioned table `wells` and feature versioning, with a history that leaves things to compress.

    DEFAULT gets a revision whose rows are all superseded later (and whose
    child is deleted), a named revision, a version merged without removal
    (side), a conflicting one merged after it (edit, which has a child with a
    solved conflict against it), one merged with removal (gone), one
    refreshed and then left with an unsolved conflict (fresh).
    """
    F.create_feature_class(conn, "horizons", "SURFACE", feature_properties={"note": "text"})
    conn.execute("CREATE TABLE wells (id int PRIMARY KEY, depth float8)")
    conn.execute("INSERT INTO wells VALUES (1, 10), (2, 20), (3, 30)")
    conn.commit()
    tgsis.enable_versioning(conn, "wells", "id", "well")
    tgsis.enable_feature_versioning(conn)
    ids = {
        n: F.insert_feature(conn, "horizons", flat_grid(4, z), {"note": n})
        for n, z in (("A", 1.0), ("B", 2.0), ("C", 3.0))
    }
    conn.commit()
    a, b, c = ids["A"], ids["B"], ids["C"]

    tgsis.create_version(conn, "tmp")
    superseded = tgsis.working_revision(conn)
    _depth(conn, "DEFAULT", 1, 11)
    _z(conn, "DEFAULT", a, 5, 11)
    tgsis.create_version(conn, "tmp2")  # freezes `superseded` as tmp2's base
    _depth(conn, "DEFAULT", 1, 12)  # everything `superseded` wrote is superseded
    _z(conn, "DEFAULT", a, 5, 12)
    tgsis.delete_version(conn, "tmp2")
    tgsis.delete_version(conn, "tmp")
    release = _save(conn, "DEFAULT", "release1")

    for name in ("edit", "side", "fresh"):
        tgsis.create_version(conn, name)
    _depth(conn, "edit", 2, 22)
    _z(conn, "edit", b, 1, 22)
    _write(conn, "edit", "DELETE FROM wells WHERE id = 3")
    _save(conn, "edit", "edit-s1")
    _depth(conn, "edit", 2, 23)
    tgsis.create_version(conn, "child", "edit")
    _depth(conn, "edit", 2, 24)
    _z(conn, "edit", a, 0, 50)  # edit changes A after child's base: a conflict for child
    _z(conn, "child", a, 0, 60)
    _depth(conn, "child", 1, 100)
    _save(conn, "child", "child-s1")
    _depth(conn, "child", 1, 101)

    _z(conn, "side", a, 0, 70)  # closes the row A.0 that child and edit closed too
    _z(conn, "side", c, 0, 70)
    side_merged = _working(conn, "side")
    tgsis.merge_version(conn, "side")
    tgsis.resolve_conflict(conn, "edit", "feature", a, "child")  # side's merge changed A in DEFAULT too
    edit_merged = _working(conn, "edit")
    tgsis.merge_version(conn, "edit")

    tgsis.create_version(conn, "gone")
    _z(conn, "gone", c, 3, 33)
    tgsis.merge_version(conn, "gone", remove=True)

    _depth(conn, "fresh", 1, 13)
    tgsis.refresh_version(conn, "fresh")
    _depth(conn, "DEFAULT", 1, 14)
    _depth(conn, "fresh", 1, 15)  # unsolved conflict of fresh on well 1

    [conflict] = tgsis.find_conflicts(conn, "child")
    assert (conflict.objectkey, conflict.solution) == (str(a), "unsolved")
    tgsis.resolve_conflict(conn, "child", "feature", a, "child")
    conn.commit()
    return {
        "ids": ids,
        "superseded": superseded,
        "release": release,
        "side_merged": side_merged,
        "edit_merged": edit_merged,
    }


# --------------------------------------------------------------------------- helpers


def _storage(conn: Conn, schema: str, table: str) -> sql.Composable:
    """The relation storing a versioned table's row versions (``tgsis.storage_table``: ``_ver`` or chunks)."""
    return sql.SQL(str(_one(conn, "SELECT tgsis.storage_table(%s, %s)", (schema, table))))


def _first_vertex(conn: Conn) -> str:
    """The condition naming vertex 0 of an object in the vertices' storage: its row, or its chunk (chunk 0)."""
    return "chunk = 0" if _one(conn, "SELECT tgsis.stored_in_chunks('vrtx')") else "vrtxid = 0"


def _tables(conn: Conn) -> list[tuple[str, str]]:
    return [
        (r[0], r[1])
        for r in conn.execute("SELECT schemaname, tablename FROM tgsis.versioned_tables ORDER BY 1, 2").fetchall()
    ]


def _content(conn: Conn, version: str, revision: int | None) -> dict[str, list[str]]:
    """Every versioned table as (version, revision) sees it, through tgsis.rows_at."""
    return {
        f"{s}.{t}": [
            r[0]
            for r in conn.execute(
                sql.SQL("SELECT to_jsonb(r)::text FROM tgsis.rows_at(NULL::{}, %s, %s) AS r ORDER BY 1").format(
                    sql.Identifier(s, t)
                ),
                (version, revision),
            ).fetchall()
        ]
        for s, t in _tables(conn)
    }


def _histories(conn: Conn) -> list[tuple[str, int | None]]:
    """(version, None) for every working state, (version, r) for every revision goto_revision accepts."""
    pairs: list[tuple[str, int | None]] = []
    for name, revs in conn.execute(
        "SELECT v.name, ARRAY(SELECT r.revision FROM tgsis.revisions r "
        "                      WHERE r.revision <> v.workingrevision "
        "                        AND (r.revision = ANY (v.workingset) OR r.versionid = v.versionid) ORDER BY 1) "
        "  FROM tgsis.versions v ORDER BY v.versionid"
    ).fetchall():
        pairs += [(name, None)] + [(name, int(r)) for r in revs]
    return pairs


def _snapshot(conn: Conn) -> Snapshot:
    snap = {pair: _content(conn, *pair) for pair in _histories(conn)}
    conn.commit()
    return snap


def _raw(conn: Conn) -> dict[str, list[tuple[Any, ...]]]:
    """Every stored row (or chunk) version of the versioned tables' storage and of the version catalog."""
    raw = {
        f"{s}.{t}_ver": conn.execute(
            sql.SQL("SELECT * FROM {} ORDER BY 1, 2, revision").format(_storage(conn, s, t))
        ).fetchall()
        for s, t in _tables(conn)
    }
    raw["versions"] = conn.execute("SELECT * FROM tgsis.versions ORDER BY versionid").fetchall()
    raw["revisions"] = conn.execute("SELECT * FROM tgsis.revisions ORDER BY revision").fetchall()
    raw["conflicts"] = conn.execute("SELECT * FROM tgsis.conflicts ORDER BY 1, 2, 3").fetchall()
    conn.commit()
    return raw


def _conflicts(conn: Conn) -> list[tuple[Any, ...]]:
    """The conflicts of every version as find_conflicts computes them now, with their fingerprints."""
    for (name,) in conn.execute("SELECT name FROM tgsis.versions WHERE parentid IS NOT NULL").fetchall():
        tgsis.find_conflicts(conn, name)
    rows = conn.execute(
        "SELECT v.name, c.objectclass, c.objectkey, c.conflicttype, c.childtables, c.parenttables, "
        "       c.childmark, c.parentmark, c.solution "
        "  FROM tgsis.conflicts c JOIN tgsis.versions v USING (versionid) ORDER BY 1, 2, 3"
    ).fetchall()
    conn.commit()
    return rows


def _expected_report(conn: Conn) -> Counter[tuple[str, str]]:
    """What compress must remove, worked out in Python from the stored rows and the rule row ∈ S ⇔
    revision ∈ S and lastrevs ∩ S = ∅."""
    versions = conn.execute(
        "SELECT versionid, name, parentid, initrevision, workingrevision, workingset FROM tgsis.versions"
    ).fetchall()
    revisions = conn.execute("SELECT revision, versionid, name, visibleset FROM tgsis.revisions").fetchall()
    owner = {rev: vid for rev, vid, _, _ in revisions}
    names = {v[0]: v[1] for v in versions}
    working_set = {v[0]: set(v[5]) for v in versions}
    # what a version's merge and conflict check read: its own revisions in its working set, its parent's since its base
    checked = {
        rev for vid, _, parent, init, _, ws in versions if parent is not None for rev in ws if owner.get(rev) == vid
    }
    checked |= {
        rev
        for _, _, parent, init, _, _ in versions
        if parent is not None
        for rev, vid, _, _ in revisions
        if vid == parent and rev > init
    }
    keep = (
        {v[4] for v in versions}
        | {v[3] for v in versions if v[3] is not None}
        | {rev for rev, _, name, _ in revisions if name is not None}
        | checked
    )
    sets = [set(ws) for ws in working_set.values()] + [
        set(vs) for rev, _, _, vs in revisions if rev in keep and vs is not None
    ]
    seen = set().union(*sets)
    report: Counter[tuple[str, str]] = Counter()
    still_used: set[int] = set()
    for s, t in _tables(conn):
        for revision, lastrevs in conn.execute(
            sql.SQL("SELECT revision, lastrevs FROM {}").format(_storage(conn, s, t))
        ).fetchall():
            closed = set(lastrevs)
            if not closed & checked and not any(revision in S and not closed & S for S in sets):
                report["rows", f"{s}.{t}"] += 1
                continue
            if not closed & checked:
                report["lastrevs", f"{s}.{t}"] += len(closed - seen)
                closed &= seen
            still_used |= {revision} | closed
    for rev, vid, _, _ in revisions:
        if rev not in keep:
            report["revisions", names[vid]] += 1
    unused = seen - keep - still_used - {0}  # 0 labels the rows of tables versioned later: in every set for good
    for vid, ws in working_set.items():
        report["set entries", names[vid]] += len(ws & unused)
    for rev, vid, _, vs in revisions:
        if rev in keep and vs is not None:
            report["set entries", names[vid]] += len(set(vs) & unused)
    return +report  # without the zeros


def _report(items: list[tgsis.Compressed]) -> Counter[tuple[str, str]]:
    assert all(item.removed > 0 for item in items)
    assert len({(i.what, i.name) for i in items}) == len(items)
    return Counter({(i.what, i.name): i.removed for i in items})


# --------------------------------------------------------------------------- tests


def test_compress_keeps_what_every_version_and_kept_revision_sees(conn: Conn, tree: dict[str, Any]) -> None:
    before = _snapshot(conn)
    named_and_bases = {
        (r[0], int(r[1]))
        for r in conn.execute(
            "SELECT v.name, r.revision FROM tgsis.revisions r JOIN tgsis.versions v USING (versionid) "
            " WHERE r.name IS NOT NULL UNION ALL "
            "SELECT p.name, c.initrevision FROM tgsis.versions c JOIN tgsis.versions p ON p.versionid = c.parentid"
        ).fetchall()
    }
    expected = _expected_report(conn)
    report = _report(tgsis.compress_versions(conn))
    after = _snapshot(conn)
    kept = set(after)
    assert named_and_bases < kept < set(before)
    assert {pair: before[pair] for pair in kept} == after
    assert report == expected
    # there was something of every kind to remove
    assert {what for what, _ in report} == {"rows", "lastrevs", "revisions", "set entries"}
    # and every dropped one is refused now
    for version, revision in set(before) - kept:
        assert revision is not None
        with pytest.raises(tgsis.NotFoundError, match=f"revision {revision} is not in the history of version"):
            tgsis.goto_revision(conn, version, revision)


def test_a_revision_whose_rows_were_all_superseded_goes_with_its_rows(conn: Conn, tree: dict[str, Any]) -> None:
    superseded = tree["superseded"]
    vertices = _one(conn, "SELECT tgsis.storage_table('tgsis', 'vrtx')")  # (one row or chunk per object written)
    count = (
        "SELECT (SELECT count(*) FROM wells_ver WHERE revision = %(r)s), "
        f"       (SELECT count(*) FROM {vertices} WHERE revision = %(r)s)"
    )
    assert conn.execute(count, {"r": superseded}).fetchone() == (1, 1)
    tgsis.goto_revision(conn, "DEFAULT", superseded)  # viewable before
    tgsis.goto_version(conn, "DEFAULT")
    tgsis.compress_versions(conn)
    assert conn.execute(count, {"r": superseded}).fetchone() == (0, 0)
    assert conn.execute("SELECT count(*) FROM tgsis.revisions WHERE revision = %s", (superseded,)).fetchone() == (0,)
    assert superseded not in _one(conn, "SELECT workingset FROM tgsis.versions WHERE name = 'DEFAULT'")
    conn.commit()
    with pytest.raises(tgsis.NotFoundError, match=f"revision {superseded} is not in the history of version 'DEFAULT'"):
        tgsis.goto_revision(conn, "DEFAULT", superseded)
    # the named revision after it still shows the depths it saw
    with tgsis.at_revision(conn, tree["release"], "DEFAULT"):
        assert conn.execute("SELECT id, depth FROM wells ORDER BY id").fetchall() == [(1, 12), (2, 20), (3, 30)]


def test_merged_away_revisions_go_unless_a_child_reads_them(conn: Conn, tree: dict[str, Any]) -> None:
    side, edit = tree["side_merged"], tree["edit_merged"]
    a, c = tree["ids"]["A"], tree["ids"]["C"]
    vertices = _one(conn, "SELECT tgsis.storage_table('tgsis', 'vrtx')")  # (one row or chunk per object written)
    written = f"SELECT count(*) FROM {vertices} WHERE revision = %s"
    lastrevs = f"SELECT lastrevs FROM {vertices} WHERE geoid = %s AND {_first_vertex(conn)} AND revision = 0"
    assert (_one(conn, written, (side,)), _one(conn, written, (edit,))) == (2, 1)
    assert side in _one(conn, lastrevs, (a,)) and side in _one(conn, lastrevs, (c,))
    tgsis.compress_versions(conn)
    kept = {r for (r,) in conn.execute("SELECT revision FROM tgsis.revisions").fetchall()}
    assert side not in kept  # side's merged changes are DEFAULT's now
    assert edit in kept  # child's conflict check compares with it
    assert (_one(conn, written, (side,)), _one(conn, written, (edit,))) == (0, 1)
    # side's revision is trimmed from lastrevs, except on the row child's conflict fingerprints
    assert side not in _one(conn, lastrevs, (c,))
    assert side in _one(conn, lastrevs, (a,))


def test_conflicts_and_their_solutions_stay(conn: Conn, tree: dict[str, Any]) -> None:
    before = _conflicts(conn)
    assert [(r[0], r[8]) for r in before] == [("child", "child"), ("fresh", "unsolved")]
    tgsis.compress_versions(conn)
    assert _conflicts(conn) == before
    # and a later change still unsolves the solved one
    _z(conn, "edit", tree["ids"]["A"], 1, 51)
    assert [c.solution for c in tgsis.find_conflicts(conn, "child")] == ["unsolved"]


def test_merges_and_refreshes_after_compress_give_what_they_gave_before(conn: Conn, tree: dict[str, Any]) -> None:
    def run(compress: bool) -> tuple[dict[str, dict[str, list[str]]], list[tuple[Any, ...]]]:
        with conn.transaction(force_rollback=True):
            if compress:
                assert tgsis.compress_versions(conn) != []
            tgsis.merge_version(conn, "child", remove=True)
            tgsis.resolve_conflict(conn, "fresh", "well", 1, "parent")
            tgsis.refresh_version(conn, "fresh")
            tgsis.resolve_conflict(conn, "edit", "well", 1, "child")  # child's well 1 against DEFAULT's
            tgsis.merge_version(conn, "edit", remove=True)
            if compress:  # what the merges left behind, compressed again
                assert tgsis.compress_versions(conn) != []
            contents = {
                name: _content(conn, name, None)
                for (name,) in conn.execute("SELECT name FROM tgsis.versions ORDER BY 1").fetchall()
            }
            conflicts = [
                (c.objectclass, c.objectkey, c.conflicttype, c.solution)
                for (name,) in conn.execute(
                    "SELECT name FROM tgsis.versions WHERE parentid IS NOT NULL ORDER BY 1"
                ).fetchall()
                for c in tgsis.find_conflicts(conn, name)
            ]
            return contents, conflicts

    conn.commit()
    assert run(compress=True) == run(compress=False)


def test_second_compress_and_dry_run_change_nothing(conn: Conn, tree: dict[str, Any]) -> None:
    raw = _raw(conn)
    dry = tgsis.compress_versions(conn, dry_run=True)
    assert _raw(conn) == raw
    assert _report(dry) == _expected_report(conn)
    assert tgsis.compress_versions(conn) == dry  # the dry run said what compress does
    conn.commit()
    raw = _raw(conn)
    assert tgsis.compress_versions(conn) == []
    assert tgsis.compress_versions(conn, dry_run=True) == []
    assert _raw(conn) == raw


def test_nothing_to_compress_without_history(conn: Conn) -> None:
    conn.execute("CREATE TABLE wells (id int PRIMARY KEY, depth float8)")
    conn.execute("INSERT INTO wells VALUES (1, 10)")
    tgsis.enable_versioning(conn, "wells", "id", "well")
    tgsis.create_version(conn, "a")
    _depth(conn, "a", 1, 11)
    _depth(conn, "DEFAULT", 1, 12)
    assert tgsis.compress_versions(conn) == []


def test_tables_versioned_after_compress_are_seen_everywhere(conn: Conn) -> None:
    tgsis.create_version(conn, "a")
    _write(conn, "a", "SELECT 1")
    tgsis.delete_version(conn, "a")  # revision 0 is no base any more, and no row mentions it
    tgsis.create_version(conn, "b")
    expected = _expected_report(conn)
    report = _report(tgsis.compress_versions(conn))
    assert report == expected and report["revisions", "DEFAULT"] == 1
    assert conn.execute("SELECT count(*) FROM tgsis.revisions WHERE revision = 0").fetchone() == (0,)
    # a table versioned now has its rows labelled 0, which every version still sees
    conn.execute("CREATE TABLE wells (id int PRIMARY KEY, depth float8)")
    conn.execute("INSERT INTO wells VALUES (1, 10), (2, 20)")
    tgsis.enable_versioning(conn, "wells", "id", "well")
    for version in ("DEFAULT", "b"):
        assert conn.execute("SELECT count(*) FROM tgsis.rows_at(NULL::wells, %s)", (version,)).fetchone() == (2,)


def test_rows_a_deleted_version_leaves_behind_go_at_the_next_compress(conn: Conn) -> None:
    """A dropped revision can still label rows a child sees; delete_version no longer finds them."""
    conn.execute("CREATE TABLE wells (id int PRIMARY KEY, depth float8)")
    conn.execute("INSERT INTO wells VALUES (1, 10)")
    tgsis.enable_versioning(conn, "wells", "id", "well")
    tgsis.create_version(conn, "v")
    edited = _working(conn, "v")
    _depth(conn, "v", 1, 11)
    tgsis.create_version(conn, "x", "v")
    tgsis.delete_version(conn, "x")
    tgsis.create_version(conn, "c", "v")  # c sees v's edit
    tgsis.merge_version(conn, "v")  # v moves on: `edited` is no base, not v's, not read by c
    assert ("revisions", "v") in _report(tgsis.compress_versions(conn))
    assert _one(conn, "SELECT count(*) FROM tgsis.revisions WHERE revision = %s", (edited,)) == 0
    assert conn.execute("SELECT depth FROM tgsis.rows_at(NULL::wells, 'c')").fetchall() == [(11,)]
    tgsis.delete_version(conn, "c")
    tgsis.delete_version(conn, "v")
    left = "SELECT count(*) FROM wells_ver WHERE revision = %s"
    assert _one(conn, left, (edited,)) == 1  # seen by nobody now
    assert conn.execute("SELECT depth FROM tgsis.rows_at(NULL::wells, 'DEFAULT')").fetchall() == [(11,)]
    expected = _expected_report(conn)
    assert _report(tgsis.compress_versions(conn)) == expected and expected["rows", "public.wells"] == 1
    assert _one(conn, left, (edited,)) == 0
    assert conn.execute("SELECT depth FROM tgsis.rows_at(NULL::wells, 'DEFAULT')").fetchall() == [(11,)]


def test_only_admins_compress(conn: Conn, tree: dict[str, Any]) -> None:
    raw = _raw(conn)
    conn.execute("SET ROLE tgsis_editor")
    with pytest.raises(tgsis.MissingPrivilegeError, match="permission denied for function compress_versions"):
        tgsis.compress_versions(conn, dry_run=True)
    conn.rollback()
    conn.execute("SET ROLE tgsis_admin")
    assert tgsis.compress_versions(conn, dry_run=True) != []
    conn.execute("RESET ROLE")
    conn.commit()
    assert _raw(conn) == raw


def test_compress_waits_for_writers(conn: Conn, tree: dict[str, Any], db_dsn: str) -> None:
    with psycopg.connect(db_dsn) as writer:
        tgsis.goto_version(writer, "fresh")
        writer.execute("UPDATE wells SET depth = 16 WHERE id = 2")  # in flight: fresh is share-locked
        conn.execute("SET lock_timeout = '300ms'")
        assert tgsis.compress_versions(conn, dry_run=True) != []  # a dry run does not wait
        with pytest.raises(tgsis.DatabaseError, match="lock timeout"):
            tgsis.compress_versions(conn)
        conn.rollback()
        writer.commit()
    assert tgsis.compress_versions(conn) != []
    conn.commit()
    assert conn.execute("SELECT depth FROM tgsis.rows_at(NULL::wells, 'fresh') WHERE id = 2").fetchone() == (16,)


def test_version_compress_command(
    db_dsn: str,
    conn: Conn,
    tree: dict[str, Any],
    capsys: pytest.CaptureFixture[str],
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setenv("TGSIS_HOME", str(tmp_path))
    monkeypatch.delenv("TGSIS_VERSION", raising=False)
    expected = dict(_expected_report(conn))
    conn.commit()

    def run(*argv: str) -> list[str]:
        assert main(["--dsn", db_dsn, *argv]) == 0
        return capsys.readouterr().out.splitlines()

    def lines(out: list[str]) -> dict[tuple[str, str], int]:
        return {(w, n): int(k) for w, n, k in (line.split("\t") for line in out)}

    superseded = tree["superseded"]
    run("version", "goto", f"DEFAULT@{superseded}")  # a revision compress drops
    out = run("version", "compress", "--dry-run")
    assert out[0] == "what\tname\tremoved"  # the header line
    assert lines(out[1:-1]) == expected
    assert out[-1].startswith("compress would remove ") and out[-1].endswith("(dry run: nothing changed)")
    assert run("version", "current")[0].startswith(
        f"DEFAULT\tworking revision {_working(conn, 'DEFAULT')}\tviewing revision {superseded}"
    )
    out = run("version", "compress")
    assert lines(out[1:-2]) == expected
    rows = sum(n for (what, _), n in expected.items() if what == "rows")
    assert out[-2].startswith(f"compress removed {rows} row version(s), ")
    assert (
        out[-1] == f"revision {superseded} is gone: commands on this database work in DEFAULT again "
        f"(was DEFAULT@{superseded})"
    )
    assert "viewing" not in run("version", "current")[0]
    assert run("version", "compress") == ["compress removed nothing"]
    assert run("version", "compress", "--dry-run") == ["compress would remove nothing (dry run)"]
