"""Roles cannot go past their rights through tgsis's own tables (issue 15, part 2).

tgsis's SECURITY DEFINER functions run as tgsis's owner (a superuser here) and
act on what ``tgsis.catalog``, ``tgsis.versioned_tables`` and
``tgsis.versioning_dropped`` name, and EXECUTE the constraint definitions the
last one records. Every hole below was found with real login roles: carol is
a tgsis admin (not a superuser), alice an editor. The victims belong to the
test database's superuser: a table ``secrets`` none of them may read, and a
view ``secrets_v`` over it. Each refusal is checked by its SQLSTATE and by
comparing the catalog state, the victims and carol's role before and after.
"""

from __future__ import annotations

import uuid
from collections.abc import Callable, Iterator
from typing import Any

import psycopg
import pytest
from psycopg import sql
from psycopg.conninfo import conninfo_to_dict, make_conninfo

import tgsis
from tests.roles import Roles, login_roles
from tests.synthetic import flat_grid
from tgsis.db import features as F
from tgsis.errors import reraise

Conn = psycopg.Connection[Any]


@pytest.fixture
def roles(db_dsn: str) -> Iterator[Roles]:
    """carol (admin) registered horizons and versioned the features; the superuser owns secrets and vault."""
    with psycopg.connect(db_dsn, autocommit=True) as su:
        su.execute("CREATE TABLE secrets (id int PRIMARY KEY, secret text UNIQUE)")
        su.execute("INSERT INTO secrets VALUES (1, 'the combination')")
        su.execute("CREATE VIEW secrets_v AS SELECT id FROM secrets")
        # a superuser's versioned table, readable by readers
        su.execute("CREATE TABLE vault (id int PRIMARY KEY, note text UNIQUE)")
        su.execute("GRANT SELECT ON vault TO tgsis_reader")
        tgsis.enable_versioning(su, "vault", "id", "vault")
        su.execute("GRANT CREATE ON SCHEMA public TO tgsis_admin")
    with login_roles(db_dsn, {"carol": "tgsis_admin", "alice": "tgsis_editor"}) as made:
        carol = made.connect("carol")
        F.create_feature_class(carol, "horizons", "SURFACE", feature_properties={"age": "float8"})
        tgsis.enable_feature_versioning(carol)
        yield made


def _state(dsn: str) -> tuple[Any, ...]:
    """What a refusal must leave alone: tgsis's catalog tables, the relations, constraints and roles."""
    with psycopg.connect(dsn) as c:
        return tuple(
            c.execute(query).fetchall()
            for query in (
                "SELECT * FROM tgsis.catalog ORDER BY classname",
                "SELECT * FROM tgsis.versioned_tables ORDER BY schemaname, tablename",
                "SELECT * FROM tgsis.versioning_dropped ORDER BY id",
                "SELECT n.nspname, c.relname, c.relkind, c.relowner::regrole::text, c.relacl::text FROM pg_class c "
                "JOIN pg_namespace n ON n.oid = c.relnamespace WHERE n.nspname IN ('public', 'tgsis') ORDER BY 1, 2",
                "SELECT conrelid::regclass::text, conname, pg_get_constraintdef(oid) FROM pg_constraint "
                "WHERE connamespace IN ('public'::regnamespace, 'tgsis'::regnamespace) ORDER BY 1, 2",
                "SELECT rolname, rolsuper, rolcreaterole, rolcreatedb FROM pg_roles ORDER BY 1",
                "SELECT * FROM secrets ORDER BY id",
                "SELECT pg_get_viewdef('secrets_v'::regclass)",
                "SELECT * FROM vault_ver ORDER BY id, revision",
            )
        )


def _state_of(conn: Conn) -> tuple[Any, ...]:
    """tgsis's catalog tables and the relations of public, as a role that may read them sees them."""
    result = tuple(
        conn.execute(query).fetchall()
        for query in (
            "SELECT * FROM tgsis.versioned_tables ORDER BY schemaname, tablename",
            "SELECT * FROM tgsis.versioning_dropped ORDER BY id",
            "SELECT relname, relkind, relowner::regrole::text FROM pg_class WHERE relnamespace = 'public'::regnamespace "
            "ORDER BY 1",
        )
    )
    conn.rollback()
    return result


def _sqlstate(conn: Conn, statement: str, params: tuple[Any, ...] = ()) -> str:
    """Run a statement that must fail; roll back and return its SQLSTATE."""
    with pytest.raises(psycopg.Error) as caught:
        conn.execute(statement, params)
    conn.rollback()
    assert caught.value.sqlstate is not None
    return caught.value.sqlstate


def _refused(call: Callable[[], object]) -> tgsis.Error:
    with pytest.raises(tgsis.Error) as caught:
        with reraise():
            call()
    return caught.value


def _assert_not_escalated(roles: Roles, db_dsn: str) -> None:
    """carol still is no superuser and still may not read the victims."""
    carol = roles.connect("carol")
    assert carol.execute("SELECT rolsuper FROM pg_roles WHERE rolname = current_user").fetchone() == (False,)
    for victim in ("secrets", "secrets_v"):
        assert _sqlstate(carol, f"SELECT * FROM {victim}") == "42501"


# --- the tables definer code trusts are read-only outside tgsis's definer functions -------------------------------

_FORGED = [
    # the hole: a forged row whose definition disable_feature_versioning EXECUTEd as superuser
    "INSERT INTO tgsis.versioning_dropped (schemaname, tablename, name, definition, is_index, dropped_for) "
    "VALUES ('public', 'secrets', 'x', 'ALTER ROLE {carol} SUPERUSER', true, 'public.secrets')",
    "INSERT INTO tgsis.versioning_dropped (schemaname, tablename, name, definition, refschema, reftable, dropped_for) "
    "VALUES ('public', 'horizons', 'x', 'CHECK (true); ALTER ROLE {carol} SUPERUSER', 'tgsis', 'geometry', "
    "'public.horizons')",
    "UPDATE tgsis.versioning_dropped SET definition = 'ALTER ROLE {carol} SUPERUSER', is_index = true",
    "UPDATE tgsis.versioning_dropped SET schemaname = 'public', tablename = 'secrets'",
    "DELETE FROM tgsis.versioning_dropped",
    "TRUNCATE tgsis.versioning_dropped",
    # the hole: a forged class naming the superuser's table and view
    "INSERT INTO tgsis.catalog (classname, schemaname, geotype, featuretable, cellprotable, viewname, proalignment, srs) "
    "VALUES ('stolen', 'public', 'SURFACE', 'secrets', 'secrets', 'secrets_v', 'VERTEX', 0)",
    "UPDATE tgsis.catalog SET featuretable = 'secrets', viewname = 'secrets_v'",
    "UPDATE tgsis.catalog SET created_by = 'postgres'",
    "DELETE FROM tgsis.catalog",
    "INSERT INTO tgsis.versioned_tables (schemaname, tablename, shortname, objectkeyfield, objectclass, iudorder, "
    "keycolumns, pkeyname) VALUES ('public', 'secrets', 's', 'id', 'feature', 9, '{id}', 'secrets_pkey')",
    "UPDATE tgsis.versioned_tables SET tablename = 'secrets' WHERE tablename = 'vault'",
    "UPDATE tgsis.versioned_tables SET objectclass = 'feature' WHERE tablename = 'vault'",
    "DELETE FROM tgsis.versioned_tables",
    # the others definer code trusts (already read-only: confirmed here for admins)
    "UPDATE tgsis.versions SET owner = '{carol}'",
    "INSERT INTO tgsis.version_privileges (versionid, grantee, privilege, granted_by) VALUES (0, 'public', 'merge', 'x')",
    "DELETE FROM tgsis.revisions",
    "UPDATE tgsis.conflicts SET solution = 'child'",
    "INSERT INTO tgsis.object_locks SELECT * FROM tgsis.object_locks",
    "DELETE FROM tgsis.object_locks",
]


@pytest.mark.parametrize("statement", _FORGED)
def test_admins_may_not_write_the_tables_definer_code_trusts(roles: Roles, db_dsn: str, statement: str) -> None:
    carol = roles.connect("carol")
    before = _state(db_dsn)
    assert _sqlstate(carol, statement.replace("{carol}", roles.name("carol"))) == "42501"
    assert _state(db_dsn) == before
    # what the forged rows were for: the definer functions run over the (unchanged) tables
    tgsis.disable_feature_versioning(carol)
    tgsis.enable_feature_versioning(carol)
    _assert_not_escalated(roles, db_dsn)


def test_the_definer_helpers_record_only_the_callers_tables(roles: Roles, db_dsn: str) -> None:
    carol = roles.connect("carol")
    with psycopg.connect(db_dsn) as su:
        secret_key = su.execute("SELECT oid FROM pg_constraint WHERE conname = 'secrets_secret_key'").fetchone()
        owner = su.execute("SELECT relowner FROM pg_class WHERE oid = 'secrets'::regclass").fetchone()
        kept = su.execute("SELECT id FROM tgsis.versioning_dropped WHERE tablename = 'vault' LIMIT 1").fetchone()
    assert secret_key is not None and owner is not None and kept is not None
    before = _state(db_dsn)
    for statement, params, sqlstate in (
        # a superuser's table (tgsis's owner is that superuser, but tgsis did not create it)
        ("SELECT tgsis.record_dropped('secrets', %s)", secret_key, "TG002"),
        ("SELECT tgsis.check_registrable('public', 'secrets', %s)", owner, "TG002"),
        ("SELECT tgsis.enable_versioning('secrets', 'id', 'stolen')", (), "TG002"),
        ("SELECT tgsis.disable_versioning('vault', true)", (), "TG002"),
        ("SELECT tgsis.disable_versioning('horizons', true)", (), "TG002"),  # tgsis's: only through the feature calls
        ("SELECT tgsis.enable_versioning('tgsis.geometry_ver', 'geoid', 'feature')", (), "TG100"),
        (
            "SELECT tgsis.register_versioned_table('secrets_v', 'id', 'x', 0, NULL, 'secrets_pkey', NULL, '{}')",
            (),
            "TG100",
        ),
        (
            "SELECT tgsis.register_versioned_table('secrets', 'id', 'x', 0, NULL, 'secrets_pkey', NULL, '{}')",
            (),
            "TG100",
        ),
        # versioned tables: registered already, and not plain
        ("SELECT tgsis.register_versioned_table('vault', 'id', 'x', 0, 'v2', 'vault_pkey', NULL, '{}')", (), "TG002"),
        (
            "SELECT tgsis.register_versioned_table('horizons', '_geoid', 'feature', 3, 'h', 'horizons_pkey', NULL, '{}')",
            (),
            "TG201",
        ),
        ("SELECT tgsis.record_dropped('horizons', 0)", (), "TG100"),
        ("SELECT tgsis.unregister_versioned_table('public', 'vault')", (), "TG202"),
        # feature-class functions on classes that are not
        ("SELECT tgsis.version_class_tables('secrets')", (), "TG200"),
        ("SELECT tgsis.create_class_view('secrets')", (), "TG200"),
        ("SELECT tgsis.create_class_view('horizons')", (), "42501"),  # tgsis's view: carol may not replace it
        ("SELECT tgsis.drop_feature_class('secrets', true)", (), "TG200"),
    ):
        assert _sqlstate(carol, statement, params) == sqlstate, statement
    # forgetting a constraint that is still to be restored, or restoring another's: nothing happens
    assert carol.execute("SELECT tgsis.forget_dropped(%s)", kept).fetchone() == (False,)
    assert carol.execute("SELECT tgsis.restore_dropped_constraints('public', 'secrets')").fetchone() == (0,)
    assert carol.execute("SELECT tgsis.unregister_versioned_table('public', 'secrets')").fetchone() == (False,)
    carol.commit()
    assert _state(db_dsn) == before
    _assert_not_escalated(roles, db_dsn)


def test_the_feature_object_class_is_tgsis_s(roles: Roles, db_dsn: str) -> None:
    """disable_feature_versioning (definer) makes every 'feature' table plain: an admin's own table may not join it."""
    carol = roles.connect("carol")
    carol.execute("CREATE TABLE mine (id int PRIMARY KEY, code text UNIQUE)")
    carol.commit()
    before = _state(db_dsn)
    error = _refused(lambda: tgsis.enable_versioning(carol, "mine", "id", "feature"))
    assert isinstance(error, tgsis.InvalidInputError) and error.sqlstate == "TG100"
    assert "object class 'feature' holds tgsis's stored objects and the feature classes, not public.mine" in str(error)
    assert "an object class of its own" in (error.hint or "")
    carol.rollback()
    assert _state(db_dsn) == before
    tgsis.enable_versioning(carol, "mine", "id", "mine")  # an object class of its own: fine
    assert tgsis.disable_versioning(carol, "mine") == 0


def test_only_admins_version_their_tables(roles: Roles, db_dsn: str) -> None:
    alice = roles.connect("alice")
    with psycopg.connect(db_dsn, autocommit=True) as su:
        su.execute(sql.SQL("GRANT CREATE ON SCHEMA public TO {}").format(sql.Identifier(roles.name("alice"))))
    alice.execute("CREATE TABLE hers (id int PRIMARY KEY, code text UNIQUE)")
    alice.commit()
    before = _state(db_dsn)
    error = _refused(lambda: tgsis.enable_versioning(alice, "hers", "id", "hers"))
    assert isinstance(error, tgsis.MissingPrivilegeError)
    assert f"role {roles.name('alice')} may not version tables" in str(error)
    assert f"GRANT tgsis_admin TO {roles.name('alice')}" in (error.hint or "")
    alice.rollback()
    assert _state(db_dsn) == before
    # nor may she record or register through the helpers
    for statement in (
        "SELECT tgsis.record_dropped('hers', oid) FROM pg_constraint WHERE conname = 'hers_code_key'",
        "SELECT tgsis.register_versioned_table('hers', 'id', 'hers', 0, NULL, 'hers_pkey', NULL, '{}')",
        "SELECT tgsis.unregister_versioned_table('public', 'hers')",
        "SELECT tgsis.forget_dropped(1)",
    ):
        assert _sqlstate(alice, statement) == "42501", statement
    assert _state(db_dsn) == before


def test_tgsis_s_tables_are_versioned_only_as_features(conn: Conn) -> None:
    before = conn.execute(
        "SELECT relname, relkind FROM pg_class WHERE relnamespace = 'tgsis'::regnamespace ORDER BY 1"
    ).fetchall()
    error = _refused(lambda: tgsis.enable_versioning(conn, "tgsis.geometry", "geoid", "geo"))
    assert isinstance(error, tgsis.InvalidInputError) and error.sqlstate == "TG100"
    assert "tgsis.geometry is versioned with the features, in object class 'feature'" in str(error)
    assert "tgsis.enable_feature_versioning versions it" in (error.hint or "")
    conn.rollback()
    assert (
        conn.execute(
            "SELECT relname, relkind FROM pg_class WHERE relnamespace = 'tgsis'::regnamespace ORDER BY 1"
        ).fetchall()
        == before
    )
    assert conn.execute("SELECT count(*) FROM tgsis.versioned_tables").fetchone() == (0,)


def _definitions(conn: Conn) -> list[tuple[str, str]]:
    """mine's constraints and unique indexes, by name, as the catalogs give them with qualified names."""
    with conn.transaction():
        conn.execute("SET LOCAL search_path = pg_catalog")
        return conn.execute(
            "SELECT conname::text, pg_get_constraintdef(oid) FROM pg_constraint WHERE conrelid = 'public.mine'::regclass AND contype <> 'n' "
            "UNION ALL SELECT c.relname::text, pg_get_indexdef(i.indexrelid) FROM pg_index i JOIN pg_class c "
            "ON c.oid = i.indexrelid WHERE i.indrelid = 'public.mine'::regclass "
            "AND NOT EXISTS (SELECT FROM pg_constraint WHERE conindid = i.indexrelid) ORDER BY 1"
        ).fetchall()


def test_dropped_constraints_come_from_the_catalogs_and_return_to_their_table(roles: Roles, db_dsn: str) -> None:
    carol = roles.connect("carol")
    carol.execute(
        "CREATE TABLE mine (id int PRIMARY KEY, code text UNIQUE, depth int, EXCLUDE USING btree (depth WITH =))"
    )
    carol.execute("CREATE UNIQUE INDEX mine_lower_code ON mine (lower(code))")
    carol.execute("CREATE TABLE loose (id int PRIMARY KEY, code text UNIQUE)")
    carol.commit()
    definitions = _definitions(carol)
    # recorded for a constraint that is not dropped: harmless, and not restored elsewhere
    carol.execute("SELECT tgsis.record_dropped('loose', oid) FROM pg_constraint WHERE conname = 'loose_code_key'")
    carol.commit()

    tgsis.enable_versioning(carol, "mine", "id", "mine")
    # the caller names only the object; the definition is read from the catalogs
    recorded = carol.execute(
        "SELECT name, definition FROM tgsis.versioning_dropped WHERE dropped_for = 'public.mine' ORDER BY name"
    ).fetchall()
    assert recorded == [(name, definition) for name, definition in definitions if name != "mine_pkey"]
    carol.commit()

    tgsis.disable_versioning(carol, "mine")
    assert _definitions(carol) == definitions
    # only mine's rows were restored: loose's (never dropped) stays until loose is made plain
    assert carol.execute(
        "SELECT tablename, name FROM tgsis.versioning_dropped WHERE schemaname = 'public' "
        "AND tablename IN ('mine', 'loose')"
    ).fetchall() == [("loose", "loose_code_key")]
    tgsis.enable_versioning(carol, "loose", "id", "loose")
    tgsis.disable_versioning(carol, "loose")
    assert carol.execute("SELECT count(*) FROM pg_constraint WHERE conname = 'loose_code_key'").fetchone() == (1,)
    assert carol.execute(
        "SELECT count(*) FROM tgsis.versioning_dropped WHERE tablename IN ('mine', 'loose')"
    ).fetchone() == (0,)


def test_feature_classes_belong_to_tgsis_and_only_admins_register_them(roles: Roles, db_dsn: str) -> None:
    carol, alice = roles.connect("carol"), roles.connect("alice")
    tgsis_owner = carol.execute(
        "SELECT relowner::regrole::text FROM pg_class WHERE oid = 'tgsis.catalog'::regclass"
    ).fetchone()
    assert carol.execute(
        "SELECT DISTINCT relowner::regrole::text FROM pg_class "
        "WHERE relnamespace = 'public'::regnamespace AND relname LIKE 'horizons%%'"
    ).fetchall() == [tgsis_owner]
    assert carol.execute(
        "SELECT DISTINCT proowner::regrole::text FROM pg_proc WHERE proname LIKE 'horizons%%'"
    ).fetchall() == [tgsis_owner]
    assert carol.execute("SELECT created_by FROM tgsis.catalog WHERE classname = 'horizons'").fetchone() == (
        roles.name("carol"),
    )
    assert carol.execute(
        "SELECT DISTINCT enabled_by FROM tgsis.versioned_tables WHERE tablename LIKE 'horizons%%'"
    ).fetchall() == [(roles.name("carol"),)]
    carol.rollback()

    with psycopg.connect(db_dsn, autocommit=True) as su:
        su.execute("CREATE SCHEMA private")  # carol has no CREATE there
        # carol's own schema: as its owner she could drop tgsis's tables there and put hers in their place
        su.execute(sql.SQL("CREATE SCHEMA carols AUTHORIZATION {}").format(sql.Identifier(roles.name("carol"))))
    before = _state(db_dsn)
    for call, message, hint in (
        (
            lambda: F.create_feature_class(alice, "faults", "SURFACE"),
            f"role {roles.name('alice')} may not register feature classes",
            f"GRANT tgsis_admin TO {roles.name('alice')}",
        ),
        (
            lambda: F.drop_feature_class(alice, "horizons", force=True),
            f"role {roles.name('alice')} may not drop feature classes",
            f"GRANT tgsis_admin TO {roles.name('alice')}",
        ),
        (
            lambda: F.create_feature_class(carol, "faults", "SURFACE", schema="private"),
            f"role {roles.name('carol')} may not create tables in schema private",
            f"GRANT CREATE ON SCHEMA private TO {roles.name('carol')}",
        ),
        (
            lambda: F.create_feature_class(carol, "faults", "SURFACE", schema="carols"),
            f"schema carols belongs to {roles.name('carol')}, who could replace the tables of a feature class there",
            "ALTER SCHEMA carols OWNER TO",
        ),
    ):
        error = _refused(call)
        assert isinstance(error, tgsis.MissingPrivilegeError), message
        assert message in str(error) and hint in (error.hint or "")
        alice.rollback()
        carol.rollback()
    assert _state(db_dsn) == before

    geoid = F.insert_feature(alice, "horizons", flat_grid(3, 1.0), properties={"age": 1.0})
    alice.commit()
    assert F.drop_feature_class(carol, "horizons", force=True) == 1
    assert carol.execute("SELECT count(*) FROM tgsis.geometry WHERE geoid = %s", (geoid,)).fetchone() == (0,)
    assert carol.execute("SELECT count(*) FROM pg_class WHERE relname LIKE 'horizons%%'").fetchone() == (0,)


@pytest.mark.parametrize("schema", ["tgsis", "pg_catalog", "information_schema", "pg_toast", "pg_temp"])
def test_a_class_in_tgsis_s_or_a_system_schema_is_refused(roles: Roles, db_dsn: str, schema: str) -> None:
    """A class in schema tgsis made enable_feature_versioning fail for everyone (part 5): refused at registration."""
    carol = roles.connect("carol")
    before = _state(db_dsn)
    error = _refused(lambda: F.create_feature_class(carol, "faults", "SURFACE", schema=schema))
    assert isinstance(error, tgsis.InvalidNameError) and error.sqlstate == "TG101"
    assert f"feature classes may not go into schema '{schema}'" in str(error)
    assert "a schema of your own" in (error.hint or "")
    carol.rollback()
    assert _state(db_dsn) == before
    if schema == "tgsis":
        with psycopg.connect(db_dsn) as su:  # a superuser is refused too
            error = _refused(lambda: F.create_feature_class(su, "faults", "SURFACE", schema="tgsis"))
            assert error.sqlstate == "TG101"
    tgsis.disable_feature_versioning(carol)
    tgsis.enable_feature_versioning(carol)


def test_an_owner_that_is_no_superuser_runs_the_feature_classes(
    make_database: Callable[..., str], template_db: str
) -> None:
    """The plain-SQL install on managed PostgreSQL: tgsis's owner owns the database, not the cluster.

    (``template_db`` made the cluster's group roles, as a DBA would have.)
    """
    dsn = make_database()
    owner = f"tgsis_owner_{uuid.uuid4().hex[:6]}"
    database = conninfo_to_dict(dsn)["dbname"]
    with psycopg.connect(dsn, autocommit=True) as su:
        su.execute(sql.SQL("CREATE ROLE {} LOGIN").format(sql.Identifier(owner)))
        su.execute(sql.SQL("GRANT tgsis_nobody TO {}").format(sql.Identifier(owner)))  # as docs/install.md says
        su.execute(
            sql.SQL("ALTER DATABASE {} OWNER TO {}").format(sql.Identifier(str(database)), sql.Identifier(owner))
        )
        try:
            with psycopg.connect(make_conninfo(dsn, user=owner)) as own:
                assert tgsis.install(own, method="sql").method == "sql"
                own.execute("GRANT CREATE ON SCHEMA public TO tgsis_admin")
                own.commit()
            with login_roles(dsn, {"carol": "tgsis_admin", "alice": "tgsis_editor"}) as made:
                carol, alice = made.connect("carol"), made.connect("alice")
                F.create_feature_class(carol, "horizons", "SURFACE")
                # carol's own versioned table refers to the geometries: tgsis's owner may not drop its key
                carol.execute("CREATE TABLE picks (id int PRIMARY KEY, geoid bigint REFERENCES tgsis.geometry)")
                carol.commit()
                tgsis.enable_versioning(carol, "picks", "id", "pick")
                before = _state_of(carol)
                error = _refused(lambda: tgsis.enable_feature_versioning(carol))
                assert isinstance(error, tgsis.MissingPrivilegeError)
                assert (
                    f"foreign key picks_geoid_fkey of public.picks_ver refers to tgsis.geometry, and role {owner} may not drop it"
                    in str(error)
                )
                assert "the owner of public.picks_ver may drop the key" in (error.hint or "")
                carol.rollback()
                assert _state_of(carol) == before
                carol.execute("ALTER TABLE picks_ver DROP CONSTRAINT picks_geoid_fkey")
                carol.commit()
                assert tgsis.enable_feature_versioning(carol) > 0
                F.create_feature_class(carol, "faults", "SURFACE")  # versioned as it is created
                tgsis.create_version(alice, "a1")
                with tgsis.in_version(alice, "a1"):
                    F.insert_feature(alice, "faults", flat_grid(3, 1.0))
                    alice.commit()
                assert carol.execute(
                    "SELECT DISTINCT relowner::regrole::text FROM pg_class WHERE relname LIKE 'faults%%'"
                ).fetchall() == [(owner,)]
                assert tgsis.disable_feature_versioning(carol, force=True) > 0
                assert carol.execute("SELECT count(*) FROM tgsis.versioning_dropped").fetchone() == (0,)
                assert F.drop_feature_class(carol, "faults", force=True) == 0  # a1's feature went with the versions
                assert F.drop_feature_class(carol, "horizons") == 0
                carol.commit()
        finally:
            su.execute(
                sql.SQL("ALTER DATABASE {} OWNER TO {}").format(
                    sql.Identifier(str(database)), sql.Identifier(su.info.user)
                )
            )
            with psycopg.connect(dsn, autocommit=True) as su_db:
                su_db.execute(sql.SQL("DROP OWNED BY {} CASCADE").format(sql.Identifier(owner)))
            su.execute(sql.SQL("DROP ROLE {}").format(sql.Identifier(owner)))


def test_a_trigger_on_an_admins_own_storage_does_not_run_as_tgsis_s_owner(roles: Roles, db_dsn: str) -> None:
    carol = roles.connect("carol")
    carol.execute("CREATE TABLE mine (id int PRIMARY KEY, v int)")
    carol.execute("""CREATE FUNCTION escalate() RETURNS trigger LANGUAGE plpgsql AS $$
        BEGIN
            IF (SELECT rolsuper FROM pg_roles WHERE rolname = current_user) THEN
                EXECUTE format('ALTER ROLE %I SUPERUSER', session_user);
            END IF;
            RETURN NULL;
        END $$""")
    carol.commit()
    tgsis.enable_versioning(carol, "mine", "id", "mine")
    carol.execute(
        "CREATE TRIGGER escalate AFTER INSERT OR UPDATE OR DELETE ON mine_ver "
        "FOR EACH STATEMENT EXECUTE FUNCTION escalate()"
    )
    carol.commit()
    tgsis.create_version(carol, "c1")
    with tgsis.in_version(carol, "c1"):
        carol.execute("INSERT INTO mine VALUES (1, 1)")
        carol.commit()
    try:
        tgsis.delete_version(carol, "c1")  # definer code deletes c1's rows from mine_ver
        _assert_not_escalated(roles, db_dsn)
    finally:
        with psycopg.connect(db_dsn, autocommit=True) as su:
            su.execute(sql.SQL("ALTER ROLE {} NOSUPERUSER").format(sql.Identifier(roles.name("carol"))))
