"""A table's own code never runs as tgsis's owner (issue 15, part 2: definer code acts only on what tgsis created).

Merges, refreshes, deletes and compression of versions run as tgsis's owner
(a superuser here) and write every versioned table's storage. What a
statement on a table runs besides itself is the table owner's code: triggers,
check constraints, column defaults, index expressions, casts of its row type.
carol, an admin, versions a table of her own and plants all of those on its
storage; each logs the role it runs as into a table of hers. After each
version operation the log must show the operation did run her code (else the
test proves nothing) and only ever as a role that is not tgsis's owner. Then
the way around it: carol making her runner SECURITY INVOKER, and dave calling
carol's runner from his own.
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import psycopg
import pytest

import tgsis
from tests.roles import Roles, login_roles

Conn = psycopg.Connection[Any]

_SIG = "(boolean, text, text[], integer[], integer[], integer, bigint[])"

_TRAPS = """
CREATE TABLE public.trap_log (who name, what text);
GRANT INSERT ON public.trap_log TO PUBLIC;
CREATE FUNCTION public.trap(p_what text) RETURNS boolean LANGUAGE plpgsql VOLATILE AS $$
    BEGIN
        INSERT INTO public.trap_log VALUES (current_user, p_what);
        IF (SELECT rolsuper FROM pg_roles WHERE rolname = current_user) THEN
            EXECUTE format('ALTER ROLE %I SUPERUSER', session_user);
        END IF;
        RETURN true;
    END $$;
GRANT EXECUTE ON FUNCTION public.trap(text) TO PUBLIC;
CREATE FUNCTION public.trap_trigger() RETURNS trigger LANGUAGE plpgsql AS $$
    BEGIN PERFORM public.trap('trigger ' || TG_OP); RETURN NULL; END $$;
CREATE FUNCTION public.trap_default() RETURNS integer[] LANGUAGE plpgsql VOLATILE AS $$
    BEGIN PERFORM public.trap('default'); RETURN '{}'; END $$;
CREATE FUNCTION public.trap_index(p_id integer) RETURNS integer LANGUAGE plpgsql IMMUTABLE AS $$
    BEGIN PERFORM public.trap('index'); RETURN p_id; END $$;
CREATE FUNCTION public.trap_cast(p_row public.mine_ver) RETURNS text LANGUAGE plpgsql VOLATILE AS $$
    BEGIN PERFORM public.trap('cast'); RETURN 'x'; END $$;
CREATE TRIGGER trap AFTER INSERT OR UPDATE OR DELETE ON public.mine_ver
    FOR EACH STATEMENT EXECUTE FUNCTION public.trap_trigger();
ALTER TABLE public.mine_ver ADD CONSTRAINT trap CHECK (public.trap('check'));
ALTER TABLE public.mine_ver ALTER COLUMN lastrevs SET DEFAULT public.trap_default();
CREATE INDEX mine_ver_trap ON public.mine_ver ((public.trap_index(id)));
CREATE CAST (public.mine_ver AS text) WITH FUNCTION public.trap_cast(public.mine_ver);
"""


@pytest.fixture
def roles(db_dsn: str) -> Iterator[Roles]:
    """carol and dave (admins) version tables of their own; carol's storage carries every trap."""
    with psycopg.connect(db_dsn, autocommit=True) as su:
        su.execute("GRANT CREATE ON SCHEMA public TO tgsis_admin")
    with login_roles(db_dsn, {"carol": "tgsis_admin", "dave": "tgsis_admin", "alice": "tgsis_editor"}) as made:
        carol = made.connect("carol")
        carol.execute("CREATE TABLE mine (id int PRIMARY KEY, v int)")
        carol.execute("INSERT INTO mine VALUES (1, 1), (2, 2), (3, 3)")
        carol.execute("GRANT SELECT, INSERT, UPDATE, DELETE ON mine TO tgsis_editor")
        carol.commit()
        tgsis.enable_versioning(carol, "mine", "id", "mine")
        carol.execute(_TRAPS)
        carol.commit()
        yield made


def _log(carol: Conn) -> list[tuple[str, str]]:
    """The traps that ran since the last call, (role, trap), and empty the log."""
    rows = carol.execute("DELETE FROM trap_log RETURNING who::text, what").fetchall()
    carol.commit()
    return sorted(set(rows))


def _ran_only_as(carol: Conn, allowed: set[str], what: str) -> None:
    log = _log(carol)
    assert log, f"{what} ran none of the table's code: the test proves nothing"
    assert {who for who, _ in log} <= allowed, f"{what} ran the table's code as {log}"
    assert carol.execute("SELECT rolsuper FROM pg_roles WHERE rolname = current_user").fetchone() == (False,)


def _mine(conn: Conn, version: str = "DEFAULT") -> list[tuple[int, int]]:
    with tgsis.in_version(conn, version):
        rows = conn.execute("SELECT id, v FROM mine ORDER BY id").fetchall()
        conn.commit()
    return rows


def test_the_traps_are_real(roles: Roles) -> None:
    """Each trap runs, as whoever runs the statement: proof that the tests below could fail."""
    carol = roles.connect("carol")
    carol.execute("SELECT r::text FROM mine_ver r")
    carol.execute("INSERT INTO mine_ver (id, v, revision) VALUES (9, 9, 0)")
    assert {what for _, what in _log(carol)} == {"cast", "check", "default", "index", "trigger INSERT"}
    carol.rollback()


def test_version_operations_run_a_tables_code_as_its_owner(roles: Roles, db_dsn: str) -> None:
    carol, alice = roles.connect("carol"), roles.connect("alice")
    owner = {roles.name("carol")}
    tgsis.create_version(alice, "a1")
    with tgsis.in_version(alice, "a1"):
        alice.execute("UPDATE mine SET v = 10 WHERE id = 1")
        alice.execute("DELETE FROM mine WHERE id = 2")
        alice.execute("INSERT INTO mine VALUES (4, 4)")
        alice.commit()
    _log(carol)  # writes through the view: carol's trigger function

    tgsis.merge_version(carol, "a1")  # copies a1's rows into DEFAULT, closes the old ones
    _ran_only_as(carol, owner, "merge_version")
    assert _mine(carol) == [(1, 10), (3, 3), (4, 4)]

    tgsis.create_version(alice, "a2")
    with tgsis.in_version(alice, "a2"):
        alice.execute("UPDATE mine SET v = 30 WHERE id = 3")
        alice.commit()
    with tgsis.in_version(carol, "DEFAULT"):
        carol.execute("UPDATE mine SET v = 31 WHERE id = 3")
        carol.commit()
    _log(carol)
    assert [c.objectkey for c in tgsis.find_conflicts(alice, "a2")] == ["3"]  # reads rows as record_out, no cast
    # (a column named v, the alias tgsis reads rows with, is still a column: rows are read as v.*)
    assert alice.execute(
        "SELECT side, \"row\" FROM tgsis.conflict_rows('a2', 'mine', '3') ORDER BY side"
    ).fetchall() == [("child", {"id": 3, "v": 30}), ("parent", {"id": 3, "v": 31})]
    alice.rollback()
    tgsis.resolve_conflict(alice, "a2", "mine", 3, "parent")
    assert not [entry for entry in _log(carol) if entry[0] != roles.name("carol")]
    tgsis.refresh_version(alice, "a2")  # takes DEFAULT's row 3 into a2
    _ran_only_as(carol, owner, "refresh_version")
    assert _mine(alice, "a2") == [(1, 10), (3, 31), (4, 4)]

    tgsis.create_version(alice, "a3")
    with tgsis.in_version(alice, "a3"):
        alice.execute("UPDATE mine SET v = 40 WHERE id = 4")
        alice.commit()
    _log(carol)
    tgsis.delete_version(alice, "a3")  # deletes a3's rows
    _ran_only_as(carol, owner, "delete_version")

    tgsis.delete_version(alice, "a2")
    _log(carol)
    removed = tgsis.compress_versions(carol)  # deletes rows no version sees, trims lastrevs
    assert removed
    _ran_only_as(carol, owner, "compress_versions")
    assert _mine(carol) == [(1, 10), (3, 31), (4, 4)]

    with psycopg.connect(db_dsn) as su:  # the traps never made anyone a superuser
        assert su.execute(
            "SELECT count(*) FROM pg_roles WHERE rolname = ANY (%s) AND rolsuper",
            ([roles.name(r) for r in ("carol", "dave", "alice")],),
        ).fetchone() == (0,)


def test_a_runner_made_security_invoker_runs_as_nobody_and_changes_nothing(roles: Roles) -> None:
    carol, alice = roles.connect("carol"), roles.connect("alice")
    tgsis.create_version(alice, "a1")
    with tgsis.in_version(alice, "a1"):
        alice.execute("UPDATE mine SET v = 10 WHERE id = 1")
        alice.commit()
    carol.execute(f"ALTER FUNCTION mine_ver_run{_SIG} SECURITY INVOKER")
    carol.commit()
    _log(carol)
    with pytest.raises(tgsis.Error) as refused:
        tgsis.merge_version(carol, "a1")
    carol.rollback()
    assert refused.value.sqlstate == "42501"  # tgsis_nobody may not write mine_ver
    assert _mine(carol) == [(1, 1), (2, 2), (3, 3)]  # nothing merged
    assert carol.execute("SELECT rolsuper FROM pg_roles WHERE rolname = current_user").fetchone() == (False,)
    # the owner gives the table its runner back, and the merge goes through
    carol.execute("SELECT tgsis.restore_storage_runner('mine')")
    carol.commit()
    tgsis.merge_version(carol, "a1")
    assert _mine(carol) == [(1, 10), (2, 2), (3, 3)]


def test_no_one_calls_a_runner_but_tgsis(roles: Roles, db_dsn: str) -> None:
    """Not its owner directly, and not another owner's runner altered to call it (it would run as tgsis_nobody)."""
    carol, dave, alice = roles.connect("carol"), roles.connect("dave"), roles.connect("alice")
    refused = _sqlstate(
        carol, "SELECT * FROM mine_ver_run(true, 'UPDATE public.mine_ver SET v = 666', NULL, NULL, NULL, NULL, NULL)"
    )
    assert refused == "TG002"
    dave.execute("CREATE TABLE his (id int PRIMARY KEY, v int)")
    dave.execute("GRANT SELECT, INSERT, UPDATE, DELETE ON his TO tgsis_editor")
    dave.commit()
    tgsis.enable_versioning(dave, "his", "id", "his")
    # dave's runner, rewritten to call carol's with a statement of his, run as whoever calls it
    dave.execute("""CREATE OR REPLACE FUNCTION his_ver_run(p_dml boolean, p_sql text, p_1 text[], p_2 integer[],
                        p_3 integer[], p_4 integer, p_5 bigint[]) RETURNS SETOF text[] LANGUAGE sql SECURITY INVOKER
                     AS $$ SELECT * FROM public.mine_ver_run(true, 'UPDATE public.mine_ver SET v = 666',
                                                             NULL, NULL, NULL, NULL, NULL) $$""")
    dave.commit()
    tgsis.create_version(alice, "a1")
    with tgsis.in_version(alice, "a1"):
        alice.execute("INSERT INTO his VALUES (1, 1)")
        alice.commit()
    with pytest.raises(tgsis.MissingPrivilegeError, match="only tgsis may call public.mine_ver_run"):
        tgsis.merge_version(dave, "a1")
    dave.rollback()
    with psycopg.connect(db_dsn) as su:
        assert su.execute("SELECT count(*) FROM mine_ver WHERE v = 666").fetchone() == (0,)


def test_an_object_key_of_a_type_of_ones_own_is_refused(roles: Roles) -> None:
    carol = roles.connect("carol")
    carol.execute("CREATE DOMAIN mykey AS integer CHECK (public.trap('domain'))")
    carol.execute("CREATE TABLE keyed (id mykey PRIMARY KEY, v int)")
    carol.commit()
    with pytest.raises(tgsis.InvalidInputError, match="is not built into PostgreSQL") as refused:
        tgsis.enable_versioning(carol, "keyed", "id", "keyed")
    carol.rollback()
    assert "built-in type" in (refused.value.hint or "")
    assert carol.execute("SELECT relkind FROM pg_class WHERE relname = 'keyed'").fetchone() == ("r",)


def _sqlstate(conn: Conn, statement: str) -> str | None:
    try:
        conn.execute(statement)
    except psycopg.Error as exc:
        conn.rollback()
        return exc.sqlstate
    conn.rollback()
    return None


def test_a_key_type_changed_afterwards_is_refused_before_any_cast(roles: Roles) -> None:
    """The owner drops the view and gives the storage's key a domain of her own: definer code refuses to cast to it."""
    carol, alice = roles.connect("carol"), roles.connect("alice")
    carol.execute("CREATE DOMAIN mykey AS integer CHECK (public.trap('domain'))")
    carol.execute("DROP VIEW mine")
    carol.execute("ALTER TABLE mine_ver ALTER COLUMN id TYPE mykey")
    carol.commit()
    _log(carol)  # the rewrite checked each row, as carol
    tgsis.create_version(alice, "a1")
    with pytest.raises(tgsis.InvalidInputError, match="not built into PostgreSQL"):
        tgsis.lock_objects(alice, "a1", "mine", ["1"])
    alice.rollback()
    assert _log(carol) == []  # the domain's check never ran, as anyone
    assert carol.execute("SELECT rolsuper FROM pg_roles WHERE rolname = current_user").fetchone() == (False,)
