"""Rights on versions, enforced in SQL and tested with roles that log in.

alice and bob are tgsis editors, carol is a tgsis admin, rita a reader. Every
refusal is checked to leave the version tree and the rows as they were.
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import psycopg
import pytest

import tgsis
from tests.fetched import geometry_of
from tests.roles import Roles, login_roles
from tests.synthetic import flat_grid
from tgsis.db import features as F
from tgsis.errors import reraise

Conn = psycopg.Connection[Any]


@pytest.fixture
def roles(db_dsn: str) -> Iterator[Roles]:
    with psycopg.connect(db_dsn, autocommit=True) as admin:
        admin.execute("CREATE TABLE wells (id bigint PRIMARY KEY, name text NOT NULL, depth float8)")
        admin.execute("INSERT INTO wells VALUES (1, 'w1', 10), (2, 'w2', 20)")
        admin.execute("GRANT SELECT ON wells TO tgsis_reader")
        admin.execute("GRANT INSERT, UPDATE, DELETE ON wells TO tgsis_editor")
        admin.execute("GRANT CREATE ON SCHEMA public TO tgsis_admin")  # where feature classes go
        tgsis.enable_versioning(admin, "wells", "id", "well")
    with login_roles(
        db_dsn, {"alice": "tgsis_editor", "bob": "tgsis_editor", "carol": "tgsis_admin", "rita": "tgsis_reader"}
    ) as made:
        yield made


def _state(dsn: str) -> tuple[list[Any], ...]:
    """The version tree, its revisions and grants, and every row version: what a refusal must leave alone."""
    with psycopg.connect(dsn) as c:
        return (
            c.execute("SELECT * FROM tgsis.versions ORDER BY versionid").fetchall(),
            c.execute("SELECT * FROM tgsis.revisions ORDER BY revision").fetchall(),
            c.execute("SELECT versionid, grantee, privilege FROM tgsis.version_privileges ORDER BY 1, 2, 3").fetchall(),
            c.execute("SELECT * FROM wells_ver ORDER BY id, revision").fetchall(),
        )


def _refused(conn: Conn, statement: str, params: tuple[Any, ...] = ()) -> tgsis.Error:
    """Run a statement that must fail; roll back and return the tgsis error."""
    with pytest.raises(tgsis.Error) as caught:
        with reraise():
            conn.execute(statement, params)
    conn.rollback()
    return caught.value


def _write_in(conn: Conn, version: str, statement: str) -> None:
    with tgsis.in_version(conn, version, local=True):
        conn.execute(statement)
    conn.commit()


def test_owner_writes_others_need_grants(roles: Roles, db_dsn: str) -> None:
    alice, bob = roles.connect("alice"), roles.connect("bob")
    tgsis.create_version(alice, "a1")  # editors may create children of DEFAULT
    assert alice.execute("SELECT owner FROM tgsis.versions WHERE name = 'a1'").fetchone() == (roles.name("alice"),)
    assert alice.execute(
        "SELECT DISTINCT created_by FROM tgsis.revisions r JOIN tgsis.versions v USING (versionid) WHERE v.name = 'a1'"
    ).fetchall() == [(roles.name("alice"),)]
    _write_in(alice, "a1", "UPDATE wells SET depth = 11 WHERE id = 1")

    before = _state(db_dsn)
    tgsis.goto_version(bob, "a1")
    error = _refused(bob, "UPDATE wells SET depth = 99 WHERE id = 2")
    assert isinstance(error, tgsis.MissingPrivilegeError)
    assert f"role {roles.name('bob')} may not write in version 'a1'" in str(error)
    assert "tgsis.grant_version('a1', 'write'" in (error.hint or "")
    for refused_call in (
        lambda: tgsis.save_revision(bob, "mine"),
        lambda: tgsis.create_version(bob, "b1", "a1"),
        lambda: tgsis.delete_version(bob, "a1"),
        lambda: tgsis.set_version_validity(bob, "a1", None),
        lambda: tgsis.grant_version(bob, "a1", "write", roles.name("bob")),
    ):
        with pytest.raises(tgsis.MissingPrivilegeError):
            refused_call()
        bob.rollback()
    assert _state(db_dsn) == before

    tgsis.grant_version(alice, "a1", "write", roles.name("bob"))
    assert tgsis.has_version_privilege(bob, "a1", "write")
    assert not tgsis.has_version_privilege(bob, "a1", "create")
    bob.rollback()
    bob.execute("UPDATE wells SET depth = 22 WHERE id = 2")
    bob.commit()
    tgsis.save_revision(bob, "bob-edit")  # write covers saving revisions
    assert [(g.grantee, g.privilege) for g in tgsis.version_privileges(alice, "a1")] == [(roles.name("bob"), "write")]

    tgsis.revoke_version(alice, "a1", "all", roles.name("bob"))
    alice.commit()  # alice's connection was inside a transaction
    assert _refused(bob, "UPDATE wells SET depth = 23 WHERE id = 2").sqlstate == "TG002"
    rows = dict(alice.execute("SELECT id, depth FROM tgsis.rows_at(NULL::wells, 'a1')").fetchall())
    assert rows == {1: 11, 2: 22}


def test_merging_into_default_is_an_admin_right(roles: Roles, db_dsn: str) -> None:
    alice, carol = roles.connect("alice"), roles.connect("carol")
    tgsis.create_version(alice, "a1")
    _write_in(alice, "a1", "UPDATE wells SET depth = 11 WHERE id = 1")
    tgsis.create_version(alice, "a2", "a1")  # the owner of a1 may create children of it
    _write_in(alice, "a2", "INSERT INTO wells VALUES (3, 'w3', 30)")

    tgsis.merge_version(alice, "a2", remove=True)  # into a1, which alice owns
    assert alice.execute("SELECT id FROM tgsis.rows_at(NULL::wells, 'a1') ORDER BY id").fetchall() == [(1,), (2,), (3,)]

    before = _state(db_dsn)
    with pytest.raises(tgsis.MissingPrivilegeError, match="may not merge into version 'DEFAULT'"):
        tgsis.merge_version(alice, "a1")
    alice.rollback()
    assert _state(db_dsn) == before

    assert not tgsis.has_version_privilege(carol, "a1", "write", roles.name("bob"))
    assert tgsis.has_version_privilege(carol, "a1", "write")  # admins hold every right
    tgsis.merge_version(carol, "a1")
    carol.commit()  # the checks above opened carol's transaction
    assert dict(carol.execute("SELECT id, depth FROM tgsis.rows_at(NULL::wells, 'DEFAULT')").fetchall()) == {
        1: 11,
        2: 20,
        3: 30,
    }

    # a right granted on DEFAULT lets an editor merge into it
    tgsis.grant_version(carol, "DEFAULT", "merge", roles.name("alice"))
    carol.commit()
    _write_in(alice, "a1", "DELETE FROM wells WHERE id = 3")
    tgsis.merge_version(alice, "a1", remove=True)
    assert carol.execute("SELECT count(*) FROM tgsis.rows_at(NULL::wells, 'DEFAULT')").fetchone() == (2,)


def test_rights_follow_role_membership_and_ownership(roles: Roles, db_dsn: str) -> None:
    alice, bob = roles.connect("alice"), roles.connect("bob")
    tgsis.create_version(alice, "a1")
    team = f"team_{roles.name('bob')}"
    with psycopg.connect(db_dsn, autocommit=True) as admin:
        admin.execute(f"CREATE ROLE {team} NOLOGIN")
        admin.execute(f"GRANT {team} TO {roles.name('bob')}")
    try:
        tgsis.grant_version(alice, "a1", "create", team)
        tgsis.create_version(bob, "b1", "a1")  # through the group role
        tgsis.grant_version(alice, "a1", "delete", "public")
        with pytest.raises(tgsis.InUseError):  # allowed now, but a1 has a child
            tgsis.delete_version(bob, "a1")
        bob.rollback()

        tgsis.set_version_owner(alice, "b1", roles.name("alice"))  # alice owns a1, so she may take b1
        with pytest.raises(tgsis.MissingPrivilegeError):
            tgsis.set_version_owner(bob, "b1", roles.name("bob"))  # bob no longer owns b1
        bob.rollback()
        tgsis.set_version_owner(alice, "a1", roles.name("bob"))
        _write_in(bob, "a1", "DELETE FROM wells WHERE id = 2")
        with pytest.raises(tgsis.MissingPrivilegeError):
            tgsis.grant_version(alice, "a1", "write", "public")
        alice.rollback()
        with pytest.raises(tgsis.NotFoundError, match="role 'nobody_at_all' does not exist"):
            tgsis.grant_version(bob, "a1", "write", "nobody_at_all")
        bob.rollback()
        with pytest.raises(tgsis.InvalidInputError, match="unknown version privilege 'read'"):
            tgsis.grant_version(bob, "a1", "read", "public")
        bob.rollback()
    finally:
        with psycopg.connect(db_dsn, autocommit=True) as admin:
            admin.execute("DELETE FROM tgsis.version_privileges WHERE grantee = %s", (team,))
            admin.execute(f"DROP ROLE {team}")


def test_readers_read_and_nobody_bypasses_the_functions(roles: Roles, db_dsn: str) -> None:
    alice, bob, rita = roles.connect("alice"), roles.connect("bob"), roles.connect("rita")
    tgsis.create_version(alice, "a1")
    _write_in(alice, "a1", "UPDATE wells SET depth = 11 WHERE id = 1")

    tgsis.goto_version(rita, "a1")
    assert rita.execute("SELECT depth FROM wells WHERE id = 1").fetchone() == (11,)
    rita.rollback()
    with pytest.raises(tgsis.MissingPrivilegeError, match="may not create a child of version 'DEFAULT'"):
        tgsis.create_version(rita, "r1")
    rita.rollback()

    before = _state(db_dsn)
    tgsis.goto_version(bob, "a1")
    # the tables behind the functions are read-only to editors
    for statement in (
        f"UPDATE tgsis.versions SET owner = '{roles.name('bob')}' WHERE name = 'a1'",
        "INSERT INTO tgsis.version_privileges (versionid, grantee, privilege, granted_by) "
        "SELECT versionid, 'public', 'write', 'x' FROM tgsis.versions WHERE name = 'a1'",
        "DELETE FROM tgsis.revisions",
        "SELECT tgsis.next_working_revision(1)",
        "SELECT tgsis.copy_object_state('well', '{1}', '{0}', '{0}', 0)",
    ):
        assert isinstance(_refused(bob, statement), tgsis.MissingPrivilegeError), statement
    # editors keep INSERT on storage (the client's COPY path), checked too; updates and deletes of
    # storage are the owner's (they go through the view and tgsis's functions)
    error = _refused(
        bob,
        "INSERT INTO wells_ver (id, name, depth, revision) "
        "SELECT 9, 'forged', 0, workingrevision FROM tgsis.versions WHERE name = 'a1'",
    )
    assert error.sqlstate == "TG002"
    assert _refused(bob, "DELETE FROM wells_ver").sqlstate == "42501"
    assert _refused(bob, "UPDATE wells_ver SET depth = 666").sqlstate == "42501"
    assert _state(db_dsn) == before


def test_feature_versioning_by_an_admin_and_feature_writes_by_rights(roles: Roles, db_dsn: str) -> None:
    alice, bob, carol = roles.connect("alice"), roles.connect("bob"), roles.connect("carol")
    F.create_feature_class(carol, "horizons", "SURFACE")
    carol.commit()
    with pytest.raises(tgsis.MissingPrivilegeError):
        tgsis.enable_feature_versioning(alice)
    alice.rollback()
    tgsis.enable_feature_versioning(carol)  # a tgsis_admin, not a superuser
    assert {t.objectclass for t in tgsis.versioned_tables(carol)} >= {"feature"}

    tgsis.create_version(alice, "a1")
    with tgsis.in_version(alice, "a1"):
        geoid = F.insert_feature(alice, "horizons", flat_grid(4, 1.0))  # bulk COPY into storage
        alice.commit()
    # (a rollback also undoes the session's goto, so each refusal gets its own block)
    with tgsis.in_version(bob, "a1"), pytest.raises(tgsis.MissingPrivilegeError, match="may not write in version 'a1'"):
        F.insert_feature(bob, "horizons", flat_grid(3, 2.0))
    bob.rollback()
    with tgsis.in_version(bob, "a1"), pytest.raises(tgsis.MissingPrivilegeError, match="may not write in version 'a1'"):
        F.delete_feature(bob, "horizons", geoid)
    bob.rollback()
    with tgsis.in_version(carol, "a1"):
        assert geometry_of(F.fetch_feature(carol, "horizons", geoid)).n_vertices == 16
    carol.rollback()
    assert F.fetch_features(carol, "horizons") == []  # DEFAULT does not see a1's feature


def test_bad_arguments_are_named_and_change_nothing(roles: Roles, db_dsn: str) -> None:
    alice = roles.connect("alice")
    tgsis.create_version(alice, "a1")
    before = _state(db_dsn)
    for call, error, message in (
        (
            lambda: tgsis.has_version_privilege(alice, "a1", "read"),
            tgsis.InvalidInputError,
            "unknown version privilege 'read'",
        ),
        (
            lambda: tgsis.has_version_privilege(alice, "a1", "write", "nobody_at_all"),
            tgsis.NotFoundError,
            "role 'nobody_at_all' does not exist",
        ),
        (
            lambda: tgsis.has_version_privilege(alice, "a1", "write", "public"),
            tgsis.NotFoundError,
            "role 'public' does not exist",
        ),  # public holds what is granted to it: no role to ask about
        (
            lambda: tgsis.has_version_privilege(alice, "nope", "write"),
            tgsis.NotFoundError,
            "version 'nope' does not exist",
        ),
        (
            lambda: tgsis.revoke_version(alice, "a1", "read", "public"),
            tgsis.InvalidInputError,
            "unknown version privilege 'read'",
        ),
        (
            lambda: tgsis.revoke_version(alice, "a1", "write", "nobody_at_all"),
            tgsis.NotFoundError,
            "role 'nobody_at_all' does not exist",
        ),
        (lambda: tgsis.set_version_owner(alice, "a1", "public"), tgsis.NotFoundError, "role 'public' does not exist"),
        (
            lambda: tgsis.grant_version(alice, "nope", "write", "public"),
            tgsis.NotFoundError,
            "version 'nope' does not exist",
        ),
    ):
        with pytest.raises(error, match=message):
            call()
        alice.rollback()
    assert _state(db_dsn) == before
    # 'all' asks for the four rights at once
    assert tgsis.has_version_privilege(alice, "a1", "all")
    assert not tgsis.has_version_privilege(alice, "DEFAULT", "all")  # editors: write and create only
    assert tgsis.has_version_privilege(alice, "DEFAULT", "create")
