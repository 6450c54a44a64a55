"""Object locks: a version takes objects so that no other version changes them (Workspace Manager's LockRows)."""

from __future__ import annotations

from typing import Any

import psycopg
import pytest

import tgsis
from tests.fetched import mesh_of
from tests.roles import login_roles
from tests.synthetic import flat_grid
from tgsis.db import features as F
from tgsis.errors import reraise

Conn = psycopg.Connection[Any]


@pytest.fixture
def tree(conn: Conn) -> Conn:
    """wells 1..4 in DEFAULT; versions v1, v2 (children of DEFAULT) and v3 (child of v1)."""
    conn.execute("CREATE TABLE wells (id bigint PRIMARY KEY, name text NOT NULL, depth float8)")
    conn.execute("INSERT INTO wells SELECT i, 'w' || i, 10 * i FROM generate_series(1, 4) i")
    conn.commit()
    tgsis.enable_versioning(conn, "wells", "id", "well")
    for name, parent in (("v1", "DEFAULT"), ("v2", "DEFAULT"), ("v3", "v1")):
        tgsis.create_version(conn, name, parent)
    return conn


def _write(conn: Conn, version: str, statement: str) -> None:
    """Run a statement in a version and commit it."""
    with reraise(), tgsis.in_version(conn, version, local=True):
        conn.execute(statement)
    conn.commit()


def _depths(conn: Conn, version: str) -> dict[int, float]:
    rows = conn.execute("SELECT id, depth FROM tgsis.rows_at(NULL::wells, %s)", (version,)).fetchall()
    conn.rollback()
    return dict(rows)


def test_a_locked_object_changes_only_in_its_version(tree: Conn) -> None:
    assert tgsis.lock_objects(tree, "v1", "well", [1]) == 1
    assert tgsis.lock_objects(tree, "v1", "well", [1]) == 0  # held already
    for version, statement in (
        ("v2", "UPDATE wells SET depth = 0 WHERE id = 1"),
        ("DEFAULT", "DELETE FROM wells WHERE id = 1"),
        ("v3", "UPDATE wells SET id = 10 WHERE id = 1"),  # a child of v1 is another version too
        ("v2", "INSERT INTO wells VALUES (1, 'again', 0)"),
    ):
        before = _depths(tree, version)
        with pytest.raises(
            tgsis.ObjectLockedError, match=r"object of class 'well' locked .*: 1 \(locked by version 'v1'"
        ):
            _write(tree, version, statement)
        tree.rollback()
        assert _depths(tree, version) == before, statement
    _write(tree, "v2", "UPDATE wells SET depth = 0 WHERE id = 2")  # other objects are free
    _write(tree, "v1", "UPDATE wells SET depth = 11 WHERE id = 1")  # the holder writes
    assert _depths(tree, "v1")[1] == 11 and _depths(tree, "v2") == {1: 10, 2: 0, 3: 30, 4: 40}

    locks = tgsis.object_locks(tree)
    assert [(lk.objectclass, lk.objectkey, lk.version, lk.exclusive) for lk in locks] == [("well", "1", "v1", False)]
    assert tgsis.unlock_objects(tree, "v1") == 1
    _write(tree, "v2", "UPDATE wells SET depth = 1 WHERE id = 1")


def test_locking_is_all_or_nothing(tree: Conn) -> None:
    tgsis.lock_objects(tree, "v1", "well", [2])
    with pytest.raises(tgsis.ObjectLockedError, match="locked by version 'v1'"):
        tgsis.lock_objects(tree, "v2", "well", [1, 2, 3])
    tree.rollback()
    assert [lk.objectkey for lk in tgsis.object_locks(tree)] == ["2"]  # 1 and 3 were not taken either
    with pytest.raises(tgsis.NotFoundError, match="version 'v2' has no object 7, 8 of class 'well'"):
        tgsis.lock_objects(tree, "v2", "well", [7, 1, 8])
    tree.rollback()
    with pytest.raises(tgsis.NotFoundError, match="object class 'wel' does not exist"):
        tgsis.lock_objects(tree, "v2", "wel", [1])
    tree.rollback()
    with pytest.raises(tgsis.InvalidInputError):
        tgsis.lock_objects(tree, "v2", "well", [])
    tree.rollback()
    with pytest.raises(tgsis.NotFoundError, match="object class 'wel' does not exist"):
        tgsis.unlock_objects(tree, "v1", "wel")
    tree.rollback()
    with pytest.raises(tgsis.NotFoundError, match="version 'v9' does not exist"):
        tgsis.unlock_objects(tree, "v9")
    tree.rollback()
    assert [lk.objectkey for lk in tgsis.object_locks(tree)] == ["2"]  # still held after the refusals
    _write(tree, "v2", "DELETE FROM wells WHERE id = 3")
    with pytest.raises(tgsis.NotFoundError, match="has no object 3"):  # deleted in v2: nothing to lock there
        tgsis.lock_objects(tree, "v2", "well", [3])
    tree.rollback()


def test_a_merge_leaves_objects_locked_elsewhere_alone(tree: Conn) -> None:
    _write(tree, "v2", "UPDATE wells SET depth = 33 WHERE id = 3")
    _write(tree, "v2", "UPDATE wells SET depth = 44 WHERE id = 4")
    tgsis.lock_objects(tree, "v1", "well", [3])  # after v2 changed it
    tree.commit()
    with pytest.raises(tgsis.ObjectLockedError, match="3 \\(locked by version 'v1'"):
        tgsis.merge_version(tree, "v2")
    tree.rollback()
    assert _depths(tree, "DEFAULT") == {1: 10, 2: 20, 3: 30, 4: 40}  # the whole merge was refused
    tgsis.merge_version(tree, "v1")  # the holder merges: its locks do not stop it
    tree.commit()
    tgsis.unlock_objects(tree, "v1", "well", [3])
    tgsis.merge_version(tree, "v2")
    assert _depths(tree, "DEFAULT") == {1: 10, 2: 20, 3: 33, 4: 44}


def test_locks_go_with_their_version(tree: Conn) -> None:
    tgsis.lock_objects(tree, "v3", "well", [1, 4])
    tgsis.delete_version(tree, "v3")
    assert tgsis.object_locks(tree) == []
    _write(tree, "v1", "DELETE FROM wells WHERE id = 4")


def test_exclusive_locks_stop_other_roles_in_the_same_version(tree: Conn, db_dsn: str) -> None:
    tree.execute("GRANT SELECT, INSERT, UPDATE, DELETE ON wells TO tgsis_editor")
    tree.commit()
    with login_roles(db_dsn, {"alice": "tgsis_editor", "bob": "tgsis_editor"}) as roles:
        alice, bob = roles.connect("alice"), roles.connect("bob")
        tgsis.create_version(alice, "a1")
        tgsis.grant_version(alice, "a1", "write", roles.name("bob"))
        tgsis.lock_objects(alice, "a1", "well", [1], exclusive=True)
        tgsis.lock_objects(bob, "a1", "well", [2])
        with pytest.raises(
            tgsis.ObjectLockedError, match=f"1 \\(locked by version 'a1', {roles.name('alice')}, exclusive\\)"
        ):
            _write(bob, "a1", "UPDATE wells SET depth = 0 WHERE id = 1")
        bob.rollback()
        _write(bob, "a1", "UPDATE wells SET depth = 2 WHERE id = 2")
        _write(alice, "a1", "UPDATE wells SET depth = 1 WHERE id = 1")
        with pytest.raises(tgsis.MissingPrivilegeError, match="exclusive locks of other roles"):
            tgsis.unlock_objects(bob, "a1")
        bob.rollback()
        assert tgsis.unlock_objects(alice, "a1") == 2  # the owner releases everybody's


def test_feature_locks_hold_for_vertices_and_deletes(conn: Conn) -> None:
    F.create_feature_class(conn, "horizons", "SURFACE")
    geoid = F.insert_feature(conn, "horizons", flat_grid(4, 1.0))
    conn.commit()
    tgsis.enable_feature_versioning(conn)
    tgsis.create_version(conn, "mine")
    tgsis.create_version(conn, "theirs")
    tgsis.lock_objects(conn, "mine", "feature", [geoid])
    with pytest.raises(tgsis.ObjectLockedError):
        _write(conn, "theirs", f"UPDATE tgsis.vrtx SET z = 5 WHERE geoid = {geoid} AND vrtxid = 0")
    conn.rollback()
    with pytest.raises(tgsis.ObjectLockedError), tgsis.in_version(conn, "theirs", local=True):
        F.delete_feature(conn, "horizons", geoid)  # the set-based delete path
    conn.rollback()
    _write(conn, "mine", f"UPDATE tgsis.vrtx SET z = 5 WHERE geoid = {geoid} AND vrtxid = 0")
    with tgsis.in_version(conn, "theirs", local=True):
        assert mesh_of(F.fetch_feature(conn, "horizons", geoid)).vertices[0, 2] == 1.0
    conn.rollback()
