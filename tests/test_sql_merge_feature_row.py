"""The psql merge by region brings the parent's edits of a feature's properties (its feature-table row), as Python does.

The oracle is the Python merge (``tgsis.merge_version(conn, v)``), as in
tests/test_sql_merge_write.py: from one committed state the Python merge runs
in a transaction rolled back, then the psql ``SELECT tgsis.merge_version(v)``;
every row version of the feature's storage (the feature table's included,
its timestamps and the bits of its doubles too), the revision notes, the
versions, conflicts and regions afterwards must be the same, and so must the
rows counted and the refusals (SQLSTATE).
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from typing import Any

import psycopg
import pytest
from psycopg import sql

import tgsis
from tests.conftest import BuiltOnce
from tests.merge_data import curved_surface, move
from tests.test_sql_merge_regions import NORTH, SOUTH, psql
from tests.test_sql_merge_write import everything

Conn = psycopg.Connection[Any]

PROPERTIES = [
    ("owner", "text"),
    ("dip", "float8"),
    ("strike", "float8"),
    ("depth", "float8"),
    ("seen", "timestamptz"),
    ("note", "text"),
    ("rank", "integer"),
    ("big", "bigint"),
    ("extra", "jsonb"),
    ("day", "date"),
    ("size", "real"),
    ("tiny", "smallint"),
    ("ok", "boolean"),
    ("ratio", "numeric"),
    ("born", "timestamptz"),
]


def feature_rows(conn: Conn) -> list[tuple[Any, ...]]:
    """Every row version of the class's feature storage, exactly: doubles by their bits, instants in UTC microseconds."""
    return conn.execute(
        "SELECT _geoid, owner, float8send(dip), float8send(strike), float8send(depth),"
        " (extract(epoch FROM seen) * 1000000)::numeric, note, revision, lastrevs, rank, big, extra::text, day - date '2000-01-01',"
        " float4send(size), tiny, ok, ratio::text, (extract(epoch FROM born) * 1000000)::numeric"
        " FROM public.faults_ver ORDER BY revision, _geoid"
    ).fetchall()


def _outcome(session: Conn, run: Callable[[], int]) -> tuple[Any, ...]:
    """(rows counted, everything after, the feature rows) of a merge, or (SQLSTATE, message) of its refusal; rolled back."""
    try:
        with session.transaction(force_rollback=True):
            rows = run()
            return ("done", rows, everything(session), feature_rows(session))
    except psycopg.Error as exc:
        return ("refused", exc.sqlstate, str(exc))
    except tgsis.Error as exc:
        return ("refused", exc.sqlstate, str(exc))
    finally:
        session.rollback()


def both_merges(conn: Conn, session: Conn, version: str, action: str) -> tuple[tuple[Any, ...], tuple[Any, ...]]:
    """(Python's outcome, SQL's outcome) of the same merge or refresh by ``session``'s role from one committed state."""
    conn.commit()
    seq = conn.execute("SELECT last_value, is_called FROM tgsis.revision_seq").fetchone()
    conn.commit()

    def python() -> int:
        if action == "merge":
            return int(tgsis.merge_version(session, version))
        return int(tgsis.refresh_version(session, version))

    def psql_merge() -> int:
        row = session.execute(sql.SQL("SELECT tgsis.{}(%s)").format(sql.Identifier(f"{action}_version")), (version,))
        return int(row.fetchone()[0])  # type: ignore[index]

    outcomes = []
    for run in (python, psql_merge):
        outcomes.append(_outcome(session, run))
        conn.execute("SELECT setval('tgsis.revision_seq', %s, %s)", seq)
        conn.commit()
    return outcomes[0], outcomes[1]


def assert_same(theirs: tuple[Any, ...], mine: tuple[Any, ...]) -> None:
    assert theirs[0] == "done", theirs[2]
    assert mine[0] == "done", mine
    assert mine[1] == theirs[1]  # rows counted
    for table in theirs[2]:
        assert mine[2][table] == theirs[2][table], table
    assert mine[3] == theirs[3]


def make_fault(conn: Conn, parent_mesh_edit: bool) -> int:
    """A curved fault whose feature row holds properties of several types, in DEFAULT, and version e1 (committed).

    The version moves vertices; the parent moves others, or (``parent_mesh_edit`` false) changes only the
    feature row.
    """
    tgsis.create_feature_class(conn, "faults", "SURFACE", feature_properties=PROPERTIES)
    tgsis.enable_feature_versioning(conn)
    geoid = tgsis.insert_feature(conn, "faults", curved_surface(), {"owner": "ann"}, drop_extra_properties=True)
    psql(
        conn,
        "DEFAULT",
        (
            "UPDATE public.faults SET dip = 0.1, strike = 271.30000000000001, depth = 12.5,"
            " seen = '2024-03-31 01:59:59.999999+00', note = 'first' WHERE _geoid = %s",
            (geoid,),
        ),
    )
    tgsis.create_version(conn, "e1")
    conn.commit()
    # both sides change the mesh in two regions apart
    move(conn, "e1", geoid, NORTH, (0.125, -3.3, 7.77))
    if parent_mesh_edit:
        move(conn, "DEFAULT", geoid, SOUTH, (-1.1, 0.0, -2.9))
    conn.commit()
    return geoid


def _built_fault(built_once: BuiltOnce, parent_mesh_edit: bool) -> tuple[str, int]:
    """(database, geoid) of ``make_fault``'s set-up, built once per session and case (tests/conftest.py)."""
    return built_once(
        f"feature_row_fault[{parent_mesh_edit}]", functools.partial(make_fault, parent_mesh_edit=parent_mesh_edit)
    )


@pytest.fixture(params=[True, False], ids=["parent-mesh-edit", "no-parent-mesh-edit"])
def parent_mesh_edit(request: pytest.FixtureRequest) -> bool:
    return bool(request.param)


@pytest.fixture
def db_dsn(make_database: Callable[..., str], built_once: BuiltOnce, parent_mesh_edit: bool) -> str:
    """Every test here starts from the fault: its database is a clone of ``make_fault``'s, built once."""
    return make_database(_built_fault(built_once, parent_mesh_edit)[0])


@pytest.fixture
def fault(conn: Conn, built_once: BuiltOnce, parent_mesh_edit: bool) -> int:
    """Geoid of ``make_fault``'s fault, already in the test's database (``db_dsn``)."""
    return _built_fault(built_once, parent_mesh_edit)[1]


def _parent_edits(conn: Conn, geoid: int, version: str = "DEFAULT") -> None:
    """The parent changes the feature row: -0.0, NaN, an instant in a DST change, NULL, text."""
    psql(
        conn,
        version,
        ("SET LOCAL TimeZone = 'Europe/Paris'", ()),
        (
            "UPDATE public.faults SET owner = 'bob é', dip = '-0', strike = 'NaN', seen = '2024-10-27 02:30:00.000001',"
            " note = NULL, rank = -2147483648, big = 9007199254740993, extra = '{\"k\": [1.50, null]}',"
            " day = '1999-12-31', size = '0.1', tiny = -32768, ok = false, ratio = 1.2300,"
            " born = '1850-07-01 00:00:00.5' WHERE _geoid = %s",
            (geoid,),
        ),
    )


@pytest.mark.parametrize("action", ["merge", "refresh"])
@pytest.mark.parametrize(
    ("timezone", "datestyle"),
    [("UTC", "ISO, MDY"), ("America/St_Johns", "SQL, DMY"), ("Asia/Kathmandu", "Postgres, YMD")],
)
def test_the_parents_feature_property_edits_come_along_in_psql_as_in_python(
    conn: Conn, fault: int, action: str, timezone: str, datestyle: str
) -> None:
    _parent_edits(conn, fault)
    conn.execute(sql.SQL("SET TimeZone = {}").format(sql.Literal(timezone)))
    conn.execute(sql.SQL("SET DateStyle = {}").format(sql.Literal(datestyle)))
    conn.execute("SET extra_float_digits = -3")
    conn.commit()
    theirs, mine = both_merges(conn, conn, "e1", action)
    assert_same(theirs, mine)
    # and what both wrote is the parent's values, bit for bit
    rows = [r for r in mine[3] if r[0] == fault]
    assert any(
        r[2] == b"\x80" + b"\x00" * 7 and r[1] == "bob é" and r[6] is None and r[3] == bytes.fromhex("7ff8000000000000")
        for r in rows
    ), rows


def test_the_parents_feature_property_edits_in_the_versions_own_working_revision(conn: Conn, fault: int) -> None:
    # the version's feature row is one of its working revision (changed, then put back as it was): the parent's
    # edits are written into that row in place
    psql(conn, "e1", ("UPDATE public.faults SET depth = 99.75 WHERE _geoid = %s", (fault,)))
    psql(conn, "e1", ("UPDATE public.faults SET depth = 12.5 WHERE _geoid = %s", (fault,)))
    _parent_edits(conn, fault)
    for action in ("merge", "refresh"):
        assert_same(*both_merges(conn, conn, "e1", action))


def test_a_feature_property_changed_on_both_sides_to_other_values_stays_an_object_conflict(
    conn: Conn, fault: int
) -> None:
    _parent_edits(conn, fault)
    psql(conn, "e1", ("UPDATE public.faults SET owner = 'cy' WHERE _geoid = %s", (fault,)))
    theirs, mine = both_merges(conn, conn, "e1", "merge")
    assert theirs[:2] == ("refused", "TG302") and mine[:2] == ("refused", "TG302"), (theirs, mine)
    assert "owner" in theirs[2] and "both" in theirs[2]
    # the whole row changed alike on both sides: nothing to bring, it merges
    _parent_edits(conn, fault, "e1")
    assert_same(*both_merges(conn, conn, "e1", "merge"))
    # the version changed another property (a row changed on both sides, as Python compares them): refused too
    psql(conn, "e1", ("UPDATE public.faults SET depth = 99.75 WHERE _geoid = %s", (fault,)))
    theirs, mine = both_merges(conn, conn, "e1", "refresh")
    assert theirs[:2] == ("refused", "TG302") and mine[:2] == ("refused", "TG302"), (theirs, mine)


@pytest.mark.parametrize("grant", ["SELECT, UPDATE", "SELECT", "SELECT, DELETE, UPDATE (dip, strike)"])
def test_a_role_with_or_without_update_on_the_class(conn: Conn, fault: int, db_dsn: str, grant: str) -> None:
    from tests.roles import login_roles

    _parent_edits(conn, fault)
    with login_roles(db_dsn, {"ed": "tgsis_editor"}) as made:
        tgsis.grant_version(conn, "e1", "all", made.name("ed"))
        tgsis.grant_version(conn, "DEFAULT", "merge", made.name("ed"))
        conn.execute("REVOKE ALL ON public.faults FROM tgsis_editor")
        conn.execute(sql.SQL("GRANT {} ON public.faults TO {}").format(sql.SQL(grant), sql.Identifier(made.name("ed"))))
        if grant == "SELECT, UPDATE":  # to compare the rows (a role of no SELECT on the class is refused anyway)
            conn.execute(sql.SQL("GRANT pg_read_all_data TO {}").format(sql.Identifier(made.name("ed"))))
        conn.commit()
        before = everything(conn), feature_rows(conn)
        conn.commit()
        session = made.connect("ed")
        for action in ("merge", "refresh"):
            theirs, mine = both_merges(conn, session, "e1", action)
            if grant == "SELECT, UPDATE":
                assert_same(theirs, mine)
            else:
                assert theirs[:2] == ("refused", "42501"), theirs
                assert mine[:2] == ("refused", "42501"), mine
                if "dip" in grant:  # UPDATE of some columns: those the parent changed and the role may not are named
                    assert "may not change the properties" in mine[2] and '"owner"' not in mine[2], mine
                    assert "owner" in mine[2] and "dip" not in mine[2].split("HINT")[0], mine
            assert (everything(conn), feature_rows(conn)) == before
            conn.commit()
        session.close()


def test_the_feature_row_is_written_as_the_class_owner_never_as_tgsis_owner(
    conn: Conn, fault: int, db_dsn: str
) -> None:
    from tests.roles import login_roles

    _parent_edits(conn, fault)
    with login_roles(db_dsn, {"carol": "tgsis_admin"}) as made:
        carol = made.name("carol")
        # carol owns the class's feature storage: tgsis writes it through her runner; her trigger logs who writes
        conn.execute(sql.SQL("ALTER TABLE public.faults_ver OWNER TO {}").format(sql.Identifier(carol)))
        conn.execute("SELECT tgsis.restore_storage_runner('public.faults')")
        conn.execute(
            """
            CREATE TABLE public.who_wrote (who name, what text);
            GRANT INSERT ON public.who_wrote TO PUBLIC;
            CREATE FUNCTION public.log_who() RETURNS trigger LANGUAGE plpgsql AS $$
                BEGIN INSERT INTO public.who_wrote VALUES (current_user, TG_OP); RETURN NULL; END $$;
            CREATE TRIGGER who AFTER INSERT OR UPDATE ON public.faults_ver
                FOR EACH STATEMENT EXECUTE FUNCTION public.log_who();
            """
        )
        conn.commit()
        for action in ("merge", "refresh"):
            theirs, mine = both_merges(conn, conn, "e1", action)
            assert_same(theirs, mine)
            with conn.transaction(force_rollback=True):
                conn.execute(sql.SQL("SELECT tgsis.{}(%s)").format(sql.Identifier(f"{action}_version")), ("e1",))
                log = conn.execute("SELECT who, what FROM public.who_wrote").fetchall()
            conn.rollback()
            assert ("UPDATE" in {w for _, w in log}) and {who for who, _ in log} == {carol}, (action, log)


def test_a_writer_of_the_versions_feature_row_during_a_psql_merge(conn: Conn, fault: int, db_dsn: str) -> None:
    from tests.sessions import Background, connect, wait_until_blocked

    _parent_edits(conn, fault)
    expected = feature_rows(conn)
    writer = connect(db_dsn, "writer")
    tgsis.goto_version(writer, "e1")
    # the version's row changed and put back as it was, not committed yet: the merge waits for it
    writer.execute("UPDATE public.faults SET depth = 99.75 WHERE _geoid = %s", (fault,))
    writer.execute("UPDATE public.faults SET depth = 12.5 WHERE _geoid = %s", (fault,))
    merger = Background(db_dsn, "merger", lambda c: c.execute("SELECT tgsis.merge_version('e1')"))
    wait_until_blocked(conn, merger.pid, writer.info.backend_pid)
    writer.commit()
    writer.close()
    merger.finish()
    # the parent's values, in the row the writer left in the version's working revision; the parent unchanged
    rows = feature_rows(conn)
    conn.commit()
    parent = [r for r in expected if r[7] == 1]
    assert parent and all(r in rows for r in parent), (expected, rows)
    mine = [r for r in rows if r[7] == 2]
    assert len(mine) == 1 and mine[0][1:7] == parent[0][1:7] and mine[0][9:] == parent[0][9:], (parent, mine)
    for version in ("DEFAULT", "e1"):
        with tgsis.in_version(conn, version):
            assert conn.execute("SELECT owner, note FROM public.faults").fetchall() == [("bob é", None)]
