"""Merge and refresh: the two-editors story, solutions, unchanged rows untouched, atomicity."""

from __future__ import annotations

import threading
import time
from typing import Any

import psycopg
import pytest

import tgsis
from tests.conftest import BuiltOnce, cloned_or_built
from tests.synthetic import flat_grid
from tgsis.db import features as F

Conn = psycopg.Connection[Any]


def make_story(conn: Conn) -> int:
    """Surfaces A, B, C in DEFAULT; editors' sibling versions e1 and e2; A's geoid (B's, C's follow)."""
    F.create_feature_class(conn, "horizons", "SURFACE", feature_properties={"note": "text"})
    tgsis.enable_feature_versioning(conn)
    ids = [
        F.insert_feature(conn, "horizons", flat_grid(5, z), {"note": name})
        for name, z in (("A", 1.0), ("B", 2.0), ("C", 3.0))
    ]
    assert ids == list(range(ids[0], ids[0] + 3)), ids
    tgsis.create_version(conn, "e1")
    tgsis.create_version(conn, "e2")
    conn.commit()
    return ids[0]


BUILT_ONCE = {"story": make_story}  # built once, cloned per test (db_dsn, tests/conftest.py)


@pytest.fixture
def story(request: pytest.FixtureRequest, conn: Conn, built_once: BuiltOnce) -> dict[str, int]:
    """``make_story``'s surfaces by name, already in the test's database (cloned, not built again)."""
    first = cloned_or_built(request, conn, built_once, "story", make_story)
    return {name: first + i for i, name in enumerate("ABC")}


def _z(conn: Conn, version: str, geoid: int) -> list[float]:
    with tgsis.in_version(conn, version):
        mesh = F.fetch_feature(conn, "horizons", geoid).mesh
    assert isinstance(mesh, tgsis.Mesh)
    return [float(z) for z in mesh.vertices[:, 2]]


def _set_z(conn: Conn, version: str, geoid: int, vertex: int, z: float) -> None:
    with tgsis.in_version(conn, version):
        conn.execute("UPDATE tgsis.vrtx SET z = %s WHERE geoid = %s AND vrtxid = %s", (z, geoid, vertex))
        conn.commit()


def _storage(conn: Conn, table: str) -> str:
    """The relation storing a model table's row versions: ``tgsis.<table>_ver``, or its chunk versions."""
    row = conn.execute("SELECT tgsis.storage_table('tgsis', %s)", (table,)).fetchone()
    assert row is not None
    return str(row[0])


def _rows(conn: Conn, geoid: int) -> list[tuple[Any, ...]]:
    """Every stored row (or chunk) version of an object (to show what a merge did not touch)."""
    return conn.execute(
        f"SELECT * FROM {_storage(conn, 'vrtx')} WHERE geoid = %s ORDER BY 2, revision", (geoid,)
    ).fetchall()


def _edit_both(conn: Conn, ids: dict[str, int]) -> None:
    _set_z(conn, "e1", ids["A"], 0, 10.0)  # both editors change A
    _set_z(conn, "e1", ids["B"], 0, 20.0)  # e1 alone changes B
    _set_z(conn, "e2", ids["A"], 0, 30.0)
    _set_z(conn, "e2", ids["C"], 0, 40.0)  # e2 alone changes C


def test_first_merge_succeeds_second_reports_exactly_the_shared_surface(conn: Conn, story: dict[str, int]) -> None:
    _edit_both(conn, story)
    assert tgsis.merge_version(conn, "e1") == 4  # A and B: one vertex row closed and one copied each
    assert _z(conn, "DEFAULT", story["A"])[0] == 10.0 and _z(conn, "DEFAULT", story["B"])[0] == 20.0
    assert tgsis.find_conflicts(conn, "e1") == []
    with pytest.raises(
        tgsis.UnsolvedConflictsError,
        match=rf"merge of version 'e2' refused: 1 unsolved conflict\(s\): "
        rf"feature {story['A']} \(vrtx\)",
    ):
        tgsis.merge_version(conn, "e2")
    [conflict] = tgsis.find_conflicts(conn, "e2")
    assert (conflict.objectkey, conflict.conflicttype) == (str(story["A"]), ("vrtx",))


@pytest.mark.parametrize("solution", ["parent", "child", "manual"])
def test_each_solution_gives_the_expected_parent(conn: Conn, story: dict[str, int], solution: str) -> None:
    _edit_both(conn, story)
    tgsis.merge_version(conn, "e1")
    untouched_b = _rows(conn, story["B"])
    if solution == "manual":
        _set_z(conn, "e2", story["A"], 0, 20.0)  # the editor writes the merged object (here: the average)
    tgsis.resolve_conflict(conn, "e2", "feature", story["A"], solution)
    tgsis.merge_version(conn, "e2")
    expected_a = {"parent": 10.0, "child": 30.0, "manual": 20.0}[solution]
    assert _z(conn, "DEFAULT", story["A"])[0] == expected_a
    assert _z(conn, "DEFAULT", story["A"])[1:] == [1.0] * 24
    assert _z(conn, "DEFAULT", story["C"])[0] == 40.0
    assert _z(conn, "DEFAULT", story["B"])[0] == 20.0
    assert _rows(conn, story["B"]) == untouched_b  # no row of any other object changed
    # the merged version goes on from the merged state, with no conflicts left
    assert _z(conn, "e2", story["A"])[0] == expected_a and tgsis.find_conflicts(conn, "e2") == []


def test_unchanged_rows_are_not_copied_and_the_version_goes_on(conn: Conn, story: dict[str, int]) -> None:
    _set_z(conn, "e1", story["A"], 3, 7.0)
    vertices = _storage(conn, "vrtx")
    before = conn.execute(f"SELECT count(*) FROM {vertices}").fetchone()
    assert tgsis.merge_version(conn, "e1") == 2  # one row (or chunk) closed, one copied: not 25
    after = conn.execute(f"SELECT count(*) FROM {vertices}").fetchone()
    assert before is not None and after is not None and after[0] == before[0] + 1
    _set_z(conn, "e1", story["A"], 4, 8.0)  # go on working; merge again
    assert tgsis.find_conflicts(conn, "e1") == []
    tgsis.merge_version(conn, "e1", remove=True)
    assert _z(conn, "DEFAULT", story["A"])[3:5] == [7.0, 8.0]
    assert "e1" not in [v.name for v in tgsis.list_versions(conn)]


def test_history_survives_a_merge(conn: Conn, story: dict[str, int]) -> None:
    _set_z(conn, "e1", story["A"], 0, 5.0)
    with tgsis.in_version(conn, "e1"):
        saved = tgsis.save_revision(conn, "first")
    _set_z(conn, "e1", story["A"], 0, 6.0)
    tgsis.merge_version(conn, "e1")
    _set_z(conn, "e1", story["A"], 0, 7.0)
    with tgsis.at_revision(conn, saved, "e1"):
        mesh = F.fetch_feature(conn, "horizons", story["A"]).mesh
    assert isinstance(mesh, tgsis.Mesh) and mesh.vertices[0, 2] == 5.0


def test_refresh_brings_the_parents_changes(conn: Conn, story: dict[str, int]) -> None:
    _set_z(conn, "e1", story["B"], 0, 20.0)
    _set_z(conn, "e2", story["C"], 0, 40.0)
    _set_z(conn, "e2", story["B"], 1, 50.0)
    tgsis.merge_version(conn, "e1")  # DEFAULT now has e1's B
    with pytest.raises(tgsis.UnsolvedConflictsError, match=f"refresh of version 'e2' refused.*feature {story['B']}"):
        tgsis.refresh_version(conn, "e2")
    tgsis.resolve_conflict(conn, "e2", "feature", story["B"], "parent")
    tgsis.refresh_version(conn, "e2")
    assert _z(conn, "e2", story["B"])[:2] == [20.0, 2.0]  # the parent's B, e2's own edit of B dropped
    assert _z(conn, "e2", story["C"])[0] == 40.0  # e2's own change kept
    assert tgsis.find_conflicts(conn, "e2") == []
    _set_z(conn, "DEFAULT", story["A"], 0, 11.0)
    tgsis.refresh_version(conn, "e2")
    assert _z(conn, "e2", story["A"])[0] == 11.0
    tgsis.merge_version(conn, "e2")
    assert [_z(conn, "DEFAULT", story[k])[0] for k in "ABC"] == [11.0, 20.0, 40.0]


def test_refresh_keeping_the_child(conn: Conn, story: dict[str, int]) -> None:
    _set_z(conn, "e1", story["A"], 0, 10.0)
    _set_z(conn, "e1", story["A"], 1, 11.0)
    _set_z(conn, "DEFAULT", story["A"], 1, 99.0)
    _set_z(conn, "DEFAULT", story["A"], 2, 98.0)
    tgsis.resolve_conflict(conn, "e1", "feature", story["A"], "child")
    tgsis.refresh_version(conn, "e1")
    assert _z(conn, "e1", story["A"])[:3] == [10.0, 11.0, 1.0]  # exactly e1's object
    assert _z(conn, "DEFAULT", story["A"])[:3] == [1.0, 99.0, 98.0]


def test_merge_refusals_change_nothing(conn: Conn, story: dict[str, int]) -> None:
    tgsis.create_version(conn, "e1a", "e1")
    state = conn.execute("SELECT * FROM tgsis.versions ORDER BY versionid").fetchall()
    with pytest.raises(tgsis.InUseError, match="has child versions and cannot be removed"):
        tgsis.merge_version(conn, "e1", remove=True)
    with pytest.raises(tgsis.InvalidInputError, match="DEFAULT has no parent"):
        tgsis.merge_version(conn, "DEFAULT")
    with pytest.raises(tgsis.NotFoundError, match="version 'nope' does not exist"):
        tgsis.refresh_version(conn, "nope")
    with pytest.raises(tgsis.NotFoundError, match="version 'nope' does not exist"):
        tgsis.merge_version(conn, "nope")
    with pytest.raises(tgsis.NotFoundError, match="version 'nope' does not exist"):
        tgsis.diff_versions(conn, "DEFAULT", "nope")
    conn.rollback()
    with pytest.raises(tgsis.NotFoundError, match="revision 2 is not in the history of version 'e2'"):
        tgsis.diff_versions(conn, "DEFAULT", "e2", b_revision=2)  # e1's revision
    conn.rollback()
    assert conn.execute("SELECT * FROM tgsis.versions ORDER BY versionid").fetchall() == state


def test_killing_the_backend_mid_merge_leaves_both_sides_as_they_were(
    conn: Conn, story: dict[str, int], db_dsn: str
) -> None:
    with tgsis.in_version(conn, "e1"):
        conn.execute("UPDATE tgsis.vrtx SET z = z + 1 WHERE geoid = %s", (story["A"],))
        # (the same triangles, their corners rotated: new content, which storage in chunks writes too)
        conn.execute(
            "UPDATE tgsis.trgl SET vrtxid1 = vrtxid2, vrtxid2 = vrtxid3, vrtxid3 = vrtxid1 WHERE geoid = %s",
            (story["A"],),
        )
        conn.commit()
    # a pause inside the merge, after the vertices are written and while the triangles are
    conn.execute("""CREATE FUNCTION pause() RETURNS trigger LANGUAGE plpgsql AS
                    $$ BEGIN PERFORM pg_sleep(30); RETURN NULL; END $$""")
    storages = (_storage(conn, "vrtx"), _storage(conn, "trgl"))
    conn.execute(f"CREATE TRIGGER pause AFTER INSERT ON {storages[1]} FOR EACH STATEMENT EXECUTE FUNCTION pause()")
    conn.commit()
    snapshot = "SELECT * FROM {} ORDER BY 1, 2, revision"
    before = {t: conn.execute(snapshot.format(t)).fetchall() for t in storages}
    versions = conn.execute("SELECT * FROM tgsis.versions ORDER BY versionid").fetchall()
    conn.commit()

    merger = psycopg.connect(db_dsn)
    pid = merger.info.backend_pid
    outcome: list[BaseException | None] = []

    def merge() -> None:
        try:
            tgsis.merge_version(merger, "e1")
            outcome.append(None)
        except BaseException as exc:  # noqa: BLE001 - inspected below
            outcome.append(exc)

    thread = threading.Thread(target=merge)
    thread.start()
    deadline = time.monotonic() + 20
    while time.monotonic() < deadline:  # wait until the merge sleeps in the trigger
        row = conn.execute("SELECT wait_event FROM pg_stat_activity WHERE pid = %s", (pid,)).fetchone()
        conn.commit()
        if row and row[0] == "PgSleep":
            break
        time.sleep(0.05)
    else:
        pytest.fail("the merge never reached the pause")
    assert conn.execute("SELECT pg_terminate_backend(%s)", (pid,)).fetchone() == (True,)
    conn.commit()
    thread.join(10)
    assert outcome and outcome[0] is not None
    merger.close()
    assert {t: conn.execute(snapshot.format(t)).fetchall() for t in before} == before
    assert conn.execute("SELECT * FROM tgsis.versions ORDER BY versionid").fetchall() == versions


def test_diff_between_versions_and_revisions(conn: Conn, story: dict[str, int]) -> None:
    assert tgsis.diff_versions(conn, "DEFAULT", "e1") == []
    _set_z(conn, "e1", story["A"], 0, 10.0)
    _set_z(conn, "e1", story["A"], 1, 11.0)
    with tgsis.in_version(conn, "e1"):
        F.delete_feature(conn, "horizons", story["C"])
        conn.commit()
    diff = {(d.objectkey, d.table): (d.added, d.removed, d.changed) for d in tgsis.diff_versions(conn, "DEFAULT", "e1")}
    a, c = str(story["A"]), str(story["C"])
    assert diff == {
        (a, "vrtx"): (0, 0, 2),
        (c, "geometry"): (0, 1, 0),
        (c, "vrtx"): (0, 25, 0),
        (c, "trgl"): (0, 32, 0),
        (c, "public.horizons"): (0, 1, 0),
    }
    # after a merge the parent holds copies with equal values: no difference, though the row versions differ
    tgsis.merge_version(conn, "e1")
    assert tgsis.diff_versions(conn, "DEFAULT", "e1") == []
    # against a revision of the past: DEFAULT at 0 still had the old A and C
    back = {(d.objectkey, d.table) for d in tgsis.diff_versions(conn, "DEFAULT", "DEFAULT", a_revision=0)}
    assert (a, "vrtx") in back and (c, "trgl") in back
