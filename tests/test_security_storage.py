"""Roles cannot write past their version rights (issue 15, part 2): storage, views, locks, definer code.

Each hole found by a hostile review is tried with real login roles, and its
variants: editors rewriting another editor's version, a frozen revision or
DEFAULT straight in the storage, ``<table>_ver`` or a model table's chunks
``tgsis.<t>_chunk`` (by UPDATE, DELETE, TRUNCATE, INSERT, binary COPY),
an operator shadowing ``=`` for the storage trigger, a statement switching
the session's version between rows, a reader holding the version lock. Every
refusal leaves the database as it was (``_state``). What docs/security.md
promises about reading (a version is no confidentiality boundary; table
rights are) is tested here too.
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import numpy as np
import psycopg
import pytest
from psycopg import sql

import tgsis
from tests.conftest import BuiltOnce
from tests.roles import Roles, login_roles
from tests.storage_data import in_chunks, stored_versions
from tests.synthetic import flat_grid
from tgsis._chunks import encode, to_copy
from tgsis.db import features as F
from tgsis.db._chunk_transfer import chunk_table
from tgsis.db._transfer import copy_in
from tgsis.db.copy import encode_rows
from tgsis.errors import reraise

Conn = psycopg.Connection[Any]


def make_storage(admin: Conn) -> int:
    """wells (versioned) and a feature class with one surface, written by the superuser (autocommit)."""
    admin.autocommit = True
    admin.execute("CREATE TABLE wells (id bigint PRIMARY KEY, name text NOT NULL, depth float8)")
    admin.execute("INSERT INTO wells VALUES (1, 'w1', 10), (2, 'w2', 20)")
    admin.execute("GRANT SELECT ON wells TO tgsis_reader")
    admin.execute("GRANT INSERT, UPDATE, DELETE ON wells TO tgsis_editor")
    tgsis.enable_versioning(admin, "wells", "id", "well")
    F.create_feature_class(admin, "horizons", "SURFACE")
    tgsis.enable_feature_versioning(admin)
    return int(F.insert_feature(admin, "horizons", flat_grid(3, 0.0)))


BUILT_ONCE = {"storage": make_storage}  # built once, cloned per test (db_dsn, tests/conftest.py)


@pytest.fixture
def storage(db_dsn: str, built_once: BuiltOnce) -> int:
    """Geoid of ``make_storage``'s surface, already in the test's database (cloned, not built again): it
    needs no login role (the group roles tgsis_reader and tgsis_editor are the session's)."""
    return built_once(f"{__name__}.storage", make_storage)[1]


@pytest.fixture
def roles(db_dsn: str, storage: int) -> Iterator[Roles]:
    """``make_storage``'s wells and feature class; alice's version a1 with an edit and a saved revision; DEFAULT
    writable by editors. alice and bob are editors, rita a reader, nora logs in with no tgsis role."""
    with login_roles(
        db_dsn, {"alice": "tgsis_editor", "bob": "tgsis_editor", "rita": "tgsis_reader", "nora": "pg_read_all_settings"}
    ) as made:
        alice = made.connect("alice")
        tgsis.create_version(alice, "a1")
        with tgsis.in_version(alice, "a1"):
            alice.execute("UPDATE wells SET depth = 11 WHERE id = 1")
            alice.commit()
            tgsis.save_revision(alice, "picked")
        yield made


def _state(dsn: str) -> tuple[list[Any], ...]:
    """The version tree and every stored row version: what a refusal must leave alone."""
    with psycopg.connect(dsn) as c:
        return (
            c.execute("SELECT * FROM tgsis.versions ORDER BY versionid").fetchall(),
            c.execute("SELECT * FROM tgsis.revisions ORDER BY revision").fetchall(),
            c.execute("SELECT * FROM tgsis.conflicts ORDER BY 1, 2, 3").fetchall(),
            c.execute("SELECT * FROM wells_ver ORDER BY id, revision").fetchall(),
            stored_versions(c, "vrtx"),  # rows or chunk versions (tgsis.storage_table)
            stored_versions(c, "trgl"),
            c.execute("SELECT geoid, geoname, revision, lastrevs FROM tgsis.geometry_ver ORDER BY 1, 3").fetchall(),
        )


def _refused(conn: Conn, statement: str, params: tuple[Any, ...] = ()) -> BaseException:
    """Run a statement that must fail; roll back and return the error."""
    with pytest.raises((tgsis.Error, psycopg.Error)) as caught:
        with reraise():
            conn.execute(statement, params)
    conn.rollback()
    return caught.value


def _sqlstate(error: BaseException) -> str | None:
    return getattr(error, "sqlstate", None)


def _revision_of(conn: Conn, version: str) -> int:
    row = conn.execute("SELECT workingrevision FROM tgsis.versions WHERE name = %s", (version,)).fetchone()
    conn.rollback()
    assert row is not None
    return int(row[0])


# --------------------------------------------------------------------------- storage written directly


# each attack on storage as rows (<t>_ver) and as chunks (<t>_chunk, the same meaning on the layout's own objects)
STORAGE_ATTACKS: dict[str, tuple[str, str]] = {
    "update-wells": ("UPDATE wells_ver SET depth = 666",) * 2,
    "update-vertices": ("UPDATE tgsis.vrtx_ver SET z = 666", "UPDATE tgsis.vrtx_chunk SET z[1] = 666"),
    "update-chunk-revision": ("UPDATE tgsis.vrtx_ver SET revision = 0", "UPDATE tgsis.vrtx_chunk SET revision = 0"),
    "reopen-closed": ("UPDATE tgsis.vrtx_ver SET lastrevs = '{}'", "UPDATE tgsis.vrtx_chunk SET lastrevs = '{}'"),
    "delete-triangles": ("DELETE FROM tgsis.trgl_ver", "DELETE FROM tgsis.trgl_chunk"),
    "delete-wells": ("DELETE FROM wells_ver WHERE revision = 0",) * 2,
    "truncate-vertices": ("TRUNCATE tgsis.vrtx_ver", "TRUNCATE tgsis.vrtx_chunk"),
    "truncate-triangles": ("TRUNCATE tgsis.trgl_ver", "TRUNCATE tgsis.trgl_chunk"),
    "update-properties": ("UPDATE horizons_ver SET _geoid = _geoid",) * 2,
    "upsert-wells": (
        "INSERT INTO wells_ver (id, name, depth, revision) VALUES (1, 'x', 666, 0) "
        "ON CONFLICT (id, revision) DO UPDATE SET depth = 666",
    )
    * 2,
    "upsert-vertices": (
        "INSERT INTO tgsis.vrtx_ver (geoid, vrtxid, x, y, z, revision) SELECT geoid, vrtxid, x, y, z, revision"
        " FROM tgsis.vrtx_ver ON CONFLICT (geoid, vrtxid, revision) DO UPDATE SET z = 666",
        "INSERT INTO tgsis.vrtx_chunk (geoid, chunk, revision, x, y, z) SELECT geoid, chunk, revision, x, y, z"
        " FROM tgsis.vrtx_chunk ON CONFLICT (geoid, chunk, revision) DO UPDATE SET z[1] = 666",
    ),
}


@pytest.mark.parametrize("attack", sorted(STORAGE_ATTACKS))
def test_editors_cannot_update_or_delete_storage(roles: Roles, db_dsn: str, attack: str) -> None:
    bob = roles.connect("bob")
    statement = STORAGE_ATTACKS[attack][in_chunks(bob)]
    bob.rollback()
    before = _state(db_dsn)
    assert _sqlstate(_refused(bob, statement)) == "42501", statement  # permission denied: only storage's owner may
    assert _state(db_dsn) == before


@pytest.mark.parametrize("where", ["a1", "a1-saved", "DEFAULT-old"])
def test_editors_cannot_insert_rows_of_another_revision(roles: Roles, db_dsn: str, where: str) -> None:
    """bob may write in DEFAULT; rows labelled for alice's version, her saved revision or an old DEFAULT revision fail."""
    bob = roles.connect("bob")
    label = {
        "a1": _revision_of(bob, "a1"),
        "a1-saved": int(bob.execute("SELECT revision FROM tgsis.revisions WHERE name = 'picked'").fetchone()[0]),  # type: ignore[index]
        "DEFAULT-old": 0,
    }[where]
    bob.rollback()
    before = _state(db_dsn)
    error = _refused(bob, "INSERT INTO wells_ver (id, name, depth, revision) VALUES (9, 'forged', 0, %s)", (label,))
    assert _sqlstate(error) == "TG002" and "not live rows of revision" in str(error)
    # nor rows closed from the start, which would hide other rows of any version
    error = _refused(
        bob,
        "INSERT INTO wells_ver (id, name, depth, revision, lastrevs) VALUES (9, 'x', 0, %s, %s)",
        (_revision_of(bob, "DEFAULT"), [label]),
    )
    assert _sqlstate(error) == "TG002"
    # the same into the model storage, a vertex row or a chunk (of the surface, whose class bob may change)
    geoid = int(bob.execute("SELECT min(geoid) FROM tgsis.geometry").fetchone()[0])  # type: ignore[index]
    forged = (
        "INSERT INTO tgsis.vrtx_chunk (geoid, chunk, revision, lastrevs, x, y, z) "
        "VALUES (%s, 7, %s, %s, '{0}', '{0}', '{666}')"
        if in_chunks(bob)
        else "INSERT INTO tgsis.vrtx_ver (geoid, vrtxid, x, y, z, revision, lastrevs) VALUES (%s, 7000, 0, 0, 666, %s, %s)"
    )
    bob.rollback()
    for revision, lastrevs in ((label, []), (_revision_of(bob, "DEFAULT"), [label])):
        error = _refused(bob, forged, (geoid, revision, lastrevs))
        assert _sqlstate(error) == "TG002", (forged, revision, lastrevs, error)
    assert _state(db_dsn) == before


def test_a_binary_copy_with_a_forged_revision_is_refused_whole(roles: Roles, db_dsn: str) -> None:
    """The client's bulk path, with rows of alice's version slipped in among bob's own."""
    bob = roles.connect("bob")
    own, alices = _revision_of(bob, "DEFAULT"), _revision_of(bob, "a1")
    storage, columns, payload = _forged_vertices(bob, own, alices)
    before = _state(db_dsn)
    # the model tables are under row-level security (per-class rights): PostgreSQL refuses a role's COPY
    # into them, and the client stages its rows (tgsis.db._transfer.staged); the check holds on that path
    names = sql.SQL(", ").join(map(sql.Identifier, columns))
    with pytest.raises(psycopg.errors.FeatureNotSupported, match="row-level security"):
        with bob.cursor().copy(sql.SQL("COPY {} ({}) FROM STDIN (FORMAT binary)").format(storage, names)) as cp:
            cp.write(payload)
    bob.rollback()
    with pytest.raises(tgsis.MissingPrivilegeError, match="1 row"):
        with reraise(), bob.transaction():
            copy_in(bob, storage, columns, payload)
    bob.rollback()
    assert _state(db_dsn) == before


def _forged_vertices(conn: Conn, own: int, alices: int) -> tuple[sql.Composable, list[str], bytes]:
    """A vertex of each of two new objects (geoids 50 and 51), the second labelled with alice's revision: the
    storage of tgsis.vrtx in use, its columns and their binary COPY payload (rows, or one chunk per object)."""
    if not in_chunks(conn):
        payload = encode_rows(
            [
                (np.array([50, 51]), "int8"),
                (np.array([0, 0]), "int8"),
                (np.zeros(2), "float8"),
                (np.zeros(2), "float8"),
                (np.full(2, 666.0), "float8"),
                (np.array([own, alices]), "int4"),
            ]
        )
        return sql.SQL("tgsis.vrtx_ver"), ["geoid", "vrtxid", "x", "y", "z", "revision"], payload
    layout = chunk_table(conn, "vrtx")
    vertex = encode([0], {"x": [0.0], "y": [0.0], "z": [666.0]}, layout.columns)
    first, second = (to_copy(vertex, geoid, revision) for geoid, revision in ((50, own), (51, alices)))
    # one stream, as the client's upload writes several objects: the header once, the trailer once
    return sql.SQL("tgsis.vrtx_chunk"), layout.columns.copy_columns(), first[:-2] + second[19:]


def test_a_role_without_the_write_right_cannot_upload_into_its_version(roles: Roles, db_dsn: str) -> None:
    bob = roles.connect("bob")
    tgsis.goto_version(bob, "a1")
    before = _state(db_dsn)
    with pytest.raises(tgsis.MissingPrivilegeError, match="may not write in version 'a1'"):
        F.insert_feature(bob, "horizons", flat_grid(3, 1.0))
    bob.rollback()
    assert _state(db_dsn) == before


def test_the_storage_check_cannot_be_fooled_by_an_operator_of_the_writer(roles: Roles, db_dsn: str) -> None:
    """An editor's own '=' for oid (true for anything) first in the search_path: the checks pin theirs."""
    with psycopg.connect(db_dsn, autocommit=True) as admin:
        admin.execute(f"CREATE SCHEMA trap AUTHORIZATION {roles.name('bob')}")
    bob = roles.connect("bob")
    bob.execute("CREATE FUNCTION trap.yes(oid, oid) RETURNS boolean LANGUAGE sql IMMUTABLE AS 'SELECT true'")
    bob.execute("CREATE OPERATOR trap.= (LEFTARG = oid, RIGHTARG = oid, FUNCTION = trap.yes)")
    bob.execute("CREATE FUNCTION trap.yes(text, text) RETURNS boolean LANGUAGE sql IMMUTABLE AS 'SELECT true'")
    bob.execute("CREATE OPERATOR trap.= (LEFTARG = text, RIGHTARG = text, FUNCTION = trap.yes)")
    bob.commit()
    bob.execute("SET search_path = trap, pg_catalog, public")
    tgsis.goto_version(bob, "a1")
    before = _state(db_dsn)
    for statement in (
        "INSERT INTO wells_ver (id, name, depth, revision) "
        "SELECT 9, 'forged', 0, workingrevision FROM tgsis.versions WHERE name = 'a1'",
        "UPDATE wells SET depth = 666 WHERE id = 1",
        "SELECT tgsis.delete_object_rows('public', 'wells', 'id', '{1}')",
    ):
        error = _refused(bob, statement)
        assert isinstance(error, tgsis.MissingPrivilegeError), (statement, error)
        bob.execute("SET search_path = trap, pg_catalog, public")
        tgsis.goto_version(bob, "a1")
    assert _state(db_dsn) == before


def test_every_definer_and_trigger_function_pins_its_search_path(roles: Roles, db_dsn: str) -> None:
    with psycopg.connect(db_dsn) as c:
        unpinned = c.execute(
            "SELECT p.oid::regprocedure::text FROM pg_proc p JOIN pg_namespace n ON n.oid = p.pronamespace "
            "WHERE (p.prosecdef OR p.prorettype = 'trigger'::regtype) "
            "  AND (n.nspname = 'tgsis' OR p.proname LIKE '%\\_ver\\_write') "
            "  AND NOT EXISTS (SELECT FROM unnest(p.proconfig) AS s WHERE s LIKE 'search\\_path=%')"
        ).fetchall()
        generated = c.execute("SELECT count(*) FROM pg_proc WHERE proname LIKE '%\\_ver\\_write'").fetchone()
    assert unpinned == []
    assert generated is not None and generated[0] >= 3  # the check saw the generated trigger functions


# --------------------------------------------------------------------------- views and bulk paths


def test_a_statement_switching_the_version_between_rows_is_checked_per_row(roles: Roles, db_dsn: str) -> None:
    """bob may write in DEFAULT; a function in his UPDATE moves the session to a1 after the statement's check."""
    bob = roles.connect("bob")
    before = _state(db_dsn)
    error = _refused(bob, "UPDATE wells SET depth = depth + (SELECT 0 FROM set_config('tgsis.version', 'a1', true))")
    assert isinstance(error, tgsis.MissingPrivilegeError) and "'a1'" in str(error)
    error = _refused(
        bob,
        "INSERT INTO wells (id, name, depth) "
        "SELECT 9, 'x' || (SELECT '' FROM set_config('tgsis.version', 'a1', true)), 0",
    )
    assert isinstance(error, tgsis.MissingPrivilegeError)
    assert _state(db_dsn) == before


def test_set_based_deletes_need_the_table_right_and_the_version_right(roles: Roles, db_dsn: str) -> None:
    rita, bob = roles.connect("rita"), roles.connect("bob")
    geoid = int(bob.execute("SELECT min(geoid) FROM tgsis.geometry").fetchone()[0])  # type: ignore[index]
    bob.rollback()
    before = _state(db_dsn)
    assert isinstance(
        _refused(rita, "SELECT tgsis.delete_object_rows('tgsis', 'vrtx', 'geoid', %s)", ([geoid],)),
        tgsis.MissingPrivilegeError,
    )  # a reader: no DELETE on the table
    assert isinstance(
        _refused(rita, "SELECT tgsis.close_object_rows('tgsis', 'vrtx', 'geoid', %s)", ([geoid],)),
        tgsis.MissingPrivilegeError,
    )
    tgsis.goto_version(bob, "a1")
    assert isinstance(
        _refused(bob, "SELECT tgsis.delete_object_rows('tgsis', 'vrtx', 'geoid', %s)", ([geoid],)),
        tgsis.MissingPrivilegeError,
    )  # an editor, in alice's version
    assert isinstance(
        _refused(bob, "SELECT tgsis.close_object_rows('tgsis', 'vrtx', 'x', %s)", ([geoid],)), tgsis.InvalidInputError
    )  # only by the registered object key
    assert isinstance(
        _refused(bob, "SELECT tgsis.close_object_rows('public', 'nothere', 'id', '{1}')"), tgsis.NotFoundError
    )
    assert _state(db_dsn) == before


def test_a_reader_cannot_hold_locks_that_stop_saves_children_and_merges(roles: Roles, db_dsn: str) -> None:
    rita, bob = roles.connect("rita"), roles.connect("bob")
    bob.execute("UPDATE wells SET depth = 12 WHERE id = 1")  # DEFAULT changes what a1 changed: a conflict
    bob.commit()
    with pytest.raises(tgsis.MissingPrivilegeError):
        with reraise():
            rita.execute("SELECT * FROM tgsis.write_revision()")
    rita.rollback()
    # rita reads a1 and its conflicts in a transaction she keeps open
    tgsis.goto_version(rita, "a1")
    assert len(rita.execute("SELECT * FROM tgsis.find_conflicts('a1')").fetchall()) == 1
    rita.execute("SELECT * FROM wells").fetchall()
    alice = roles.connect("alice")
    alice.execute("SET lock_timeout = '3s'")
    alice.commit()
    tgsis.resolve_conflict(alice, "a1", "well", 1, "child")
    alice.commit()
    with tgsis.in_version(alice, "a1"):
        tgsis.save_revision(alice, "second")
    tgsis.create_version(alice, "a2", "a1")
    alice.commit()
    with psycopg.connect(db_dsn) as admin:
        admin.execute("SET lock_timeout = '3s'")
        tgsis.merge_version(admin, "a2")
        tgsis.merge_version(admin, "a1")
    rita.rollback()


def test_find_conflicts_by_a_reader_computes_without_storing(roles: Roles, db_dsn: str) -> None:
    alice, bob, rita = roles.connect("alice"), roles.connect("bob"), roles.connect("rita")
    bob.execute("UPDATE wells SET depth = 12 WHERE id = 1")  # DEFAULT changes what a1 changed too
    bob.commit()
    before = _state(db_dsn)
    seen = tgsis.find_conflicts(rita, "a1")
    rita.rollback()
    assert [(c.objectclass, c.objectkey, c.solution) for c in seen] == [("well", "1", "unsolved")]
    assert _state(db_dsn) == before  # nothing stored, nothing locked
    stored = tgsis.find_conflicts(alice, "a1")
    alice.commit()
    assert [(c.objectclass, c.objectkey) for c in stored] == [("well", "1")]
    tgsis.resolve_conflict(alice, "a1", "well", 1, "child")
    alice.commit()
    assert [c.solution for c in tgsis.find_conflicts(rita, "a1")] == ["child"]  # the reader sees the solution
    rita.rollback()


# --------------------------------------------------------------------------- reading: what a version is not


def test_a_version_is_no_confidentiality_boundary_table_rights_are(roles: Roles, db_dsn: str) -> None:
    """docs/security.md: whoever may read a table reads every version of it; whoever may not, none."""
    rita, nora = roles.connect("rita"), roles.connect("nora")
    assert rita.execute("SELECT depth FROM tgsis.rows_at(NULL::wells, 'a1') WHERE id = 1").fetchone() == (11,)
    tgsis.goto_version(rita, "a1")
    assert rita.execute("SELECT depth FROM wells WHERE id = 1").fetchone() == (11,)
    rita.rollback()
    for statement in (
        "SELECT * FROM wells",
        "SELECT * FROM wells_ver",
        "SELECT * FROM tgsis.rows_at(NULL::wells, 'a1')",
        "SELECT * FROM tgsis.vrtx",
    ):
        assert _sqlstate(_refused(nora, statement)) == "42501", statement
