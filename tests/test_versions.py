"""The version tree: revision hand-out, session state, save, goto, delete (spec: versioning.md)."""

from __future__ import annotations

from typing import Any

import psycopg
import pytest

import tgsis
from tgsis.db.versions import format_tree, show_name

Conn = psycopg.Connection[Any]


def _tree(conn: Conn) -> dict[str, tuple[str | None, int | None, int, list[int]]]:
    rows = conn.execute(
        "SELECT name, parent, initrevision, workingrevision, revisions FROM tgsis.version_tree"
    ).fetchall()
    return {r[0]: (r[1], r[2], r[3], list(r[4])) for r in rows}


def _sets(conn: Conn) -> dict[str, list[int]]:
    return {name: list(ws) for name, ws in conn.execute("SELECT name, workingset FROM tgsis.versions").fetchall()}


def test_default_exists_with_revision_zero(conn: Conn) -> None:
    assert _tree(conn) == {"DEFAULT": (None, None, 0, [0])}
    assert tgsis.working_version(conn) == "DEFAULT"
    assert tgsis.working_revision(conn) == 0
    assert tgsis.revisions(conn) == [0] and tgsis.revisions(conn, viewing=False) == [0]


def test_hand_out_order_worked_out_by_hand(conn: Conn) -> None:
    # Rules: child.init := parent.working; parent gets next; child gets next.
    assert tgsis.create_version(conn, "a") == 2  # a.init 0, DEFAULT 1, a 2
    assert tgsis.create_version(conn, "b") == 4  # b.init 1, DEFAULT 3, b 4
    assert tgsis.create_version(conn, "a1", "a") == 6  # a1.init 2, a 5, a1 6
    tgsis.goto_version(conn, "a")
    assert tgsis.save_revision(conn, "checkpoint") == 5  # a's 5 frozen, a gets 7
    assert tgsis.create_version(conn, "a2", "a") == 9  # a2.init 7, a 8, a2 9
    assert tgsis.create_version(conn, "c", "DEFAULT") == 11  # c.init 3, DEFAULT 10, c 11
    assert tgsis.create_version(conn, "a1x", "a1") == 13  # a1x.init 6, a1 12, a1x 13
    assert _tree(conn) == {
        "DEFAULT": (None, None, 10, [0, 1, 3, 10]),
        "a": ("DEFAULT", 0, 8, [2, 5, 7, 8]),
        "a1": ("a", 2, 12, [6, 12]),
        "a1x": ("a1", 6, 13, [13]),
        "a2": ("a", 7, 9, [9]),
        "b": ("DEFAULT", 1, 4, [4]),
        "c": ("DEFAULT", 3, 11, [11]),
    }
    # working sets: own revisions plus the parent's set up to initrevision
    assert _sets(conn) == {
        "DEFAULT": [0, 1, 3, 10],
        "a": [0, 2, 5, 7, 8],
        "a1": [0, 2, 6, 12],
        "a1x": [0, 2, 6, 13],
        "a2": [0, 2, 5, 7, 9],
        "b": [0, 1, 4],
        "c": [0, 1, 3, 11],
    }
    assert [v.name for v in tgsis.list_versions(conn)] == ["DEFAULT", "a", "a1", "a1x", "a2", "b", "c"]
    saved = {v.name: v.saved for v in tgsis.list_versions(conn)}
    assert saved["a"] == {"checkpoint": 5} and saved["b"] == {}


def test_viewing_set_is_the_working_set_up_to_the_revision(conn: Conn) -> None:
    tgsis.create_version(conn, "a")  # a: {0, 2}
    tgsis.goto_version(conn, "a")
    tgsis.save_revision(conn, "s1")  # a: {0, 2, 3}
    tgsis.save_revision(conn, "s2")  # a: {0, 2, 3, 4}
    assert tgsis.revisions(conn, viewing=False) == [0, 2, 3, 4]
    tgsis.goto_revision(conn, "a", 3)
    assert tgsis.revisions(conn) == [0, 2, 3]
    assert tgsis.revisions(conn, viewing=False) == [0, 2, 3, 4]
    assert tgsis.viewing_revision(conn) == 3
    tgsis.goto_revision(conn, "a", 0)  # an ancestor's revision in a's history
    assert tgsis.revisions(conn) == [0]
    tgsis.goto_version(conn, "a")
    assert tgsis.viewing_revision(conn) is None and tgsis.revisions(conn) == [0, 2, 3, 4]


def test_goto_revision_outside_the_history_is_refused(conn: Conn) -> None:
    tgsis.create_version(conn, "a")  # DEFAULT gets 1 after a's creation: not in a's history
    with pytest.raises(tgsis.NotFoundError, match="revision 1 is not in the history of version 'a'"):
        tgsis.goto_revision(conn, "a", 1)
    assert tgsis.working_version(conn) == "DEFAULT"


def test_state_is_per_connection_and_survives_statements(conn: Conn, db_dsn: str) -> None:
    tgsis.create_version(conn, "a")
    tgsis.goto_version(conn, "a")
    conn.execute("SELECT 1")
    conn.commit()
    assert tgsis.working_version(conn) == "a"
    with psycopg.connect(db_dsn) as other:
        assert tgsis.working_version(other) == "DEFAULT"


def test_local_goto_ends_with_the_transaction(conn: Conn) -> None:
    tgsis.create_version(conn, "a")
    conn.commit()  # a transaction of its own, not a savepoint in an open one
    with conn.transaction():
        conn.execute("SELECT tgsis.goto_version('a', true)")
        assert tgsis.working_version(conn) == "a"
    assert tgsis.working_version(conn) == "DEFAULT"
    conn.commit()
    with conn.transaction():  # what a pooler in transaction mode needs
        conn.execute("SET LOCAL tgsis.version = 'a'")
        assert tgsis.working_revision(conn) == 2
    assert tgsis.working_revision(conn) == 1


def test_context_managers_restore_the_previous_state(conn: Conn) -> None:
    tgsis.create_version(conn, "a")
    tgsis.create_version(conn, "b")
    tgsis.goto_version(conn, "b")
    with tgsis.in_version(conn, "a"):
        assert tgsis.working_version(conn) == "a"
        with tgsis.at_revision(conn, 0):
            assert tgsis.revisions(conn) == [0] and tgsis.working_version(conn) == "a"
        assert tgsis.viewing_revision(conn) is None
    assert tgsis.working_version(conn) == "b"
    with pytest.raises(psycopg.errors.DivisionByZero), tgsis.in_version(conn, "a"):
        conn.execute("SELECT 1/0")
    assert tgsis.working_version(conn) == "b"
    with tgsis.in_version(conn, "a", local=True):  # inside an open transaction
        assert tgsis.working_version(conn) == "a"
    assert tgsis.working_version(conn) == "b"
    conn.commit()
    with tgsis.in_version(conn, "a", local=True):  # a transaction of its own
        assert tgsis.working_version(conn) == "a"
        assert conn.info.transaction_status == psycopg.pq.TransactionStatus.INTRANS
    # (mypy keeps the status narrowed to INTRANS by the assert in the block above, which has ended)
    assert conn.info.transaction_status == psycopg.pq.TransactionStatus.IDLE  # type: ignore[comparison-overlap]
    assert tgsis.working_version(conn) == "b"


def _wells(conn: Conn) -> None:
    conn.execute("CREATE TABLE wells (id integer PRIMARY KEY, depth double precision)")
    conn.execute("INSERT INTO wells VALUES (1, 1000)")
    conn.commit()
    tgsis.enable_versioning(conn, "wells", "id", "well")
    tgsis.create_version(conn, "edit")


def _depth(conn: Conn, version: str) -> float:
    with tgsis.in_version(conn, version):
        row = conn.execute("SELECT depth FROM wells WHERE id = 1").fetchone()
    assert row is not None
    return float(row[0])


def test_a_rollback_after_the_block_cannot_bring_its_version_back(conn: Conn) -> None:
    """The block committed midway and left a transaction open: a later rollback used to undo the restored version."""
    _wells(conn)
    with tgsis.in_version(conn, "edit"):
        conn.execute("UPDATE wells SET depth = 1100 WHERE id = 1")
        conn.commit()
        conn.execute("UPDATE wells SET depth = 1200 WHERE id = 1")
    assert conn.info.transaction_status == psycopg.pq.TransactionStatus.IDLE  # the block's transaction ended with it
    conn.rollback()
    assert tgsis.working_version(conn) == "DEFAULT"
    conn.execute("UPDATE wells SET depth = 900 WHERE id = 1")  # lands in DEFAULT, not in edit
    conn.commit()
    assert (_depth(conn, "DEFAULT"), _depth(conn, "edit")) == (900, 1200)


def test_a_block_that_raises_keeps_nothing_of_its_own_transaction(conn: Conn) -> None:
    _wells(conn)
    with pytest.raises(ZeroDivisionError), tgsis.in_version(conn, "edit"):
        conn.execute("UPDATE wells SET depth = 1100 WHERE id = 1")
        raise ZeroDivisionError  # Python's error, the transaction itself still fine
    assert conn.info.transaction_status == psycopg.pq.TransactionStatus.IDLE
    assert tgsis.working_version(conn) == "DEFAULT"
    assert (_depth(conn, "DEFAULT"), _depth(conn, "edit")) == (1000, 1000)


def test_an_error_caught_inside_the_block_drops_its_transaction_and_restores_the_version(conn: Conn) -> None:
    _wells(conn)
    with tgsis.in_version(conn, "edit"):
        conn.execute("UPDATE wells SET depth = 1100 WHERE id = 1")
        with pytest.raises(psycopg.errors.DivisionByZero):
            conn.execute("SELECT 1 / 0")
    assert conn.info.transaction_status == psycopg.pq.TransactionStatus.IDLE
    assert tgsis.working_version(conn) == "DEFAULT"
    assert _depth(conn, "edit") == 1000  # the failed transaction's write is not kept


def test_inside_the_callers_transaction_a_rollback_undoes_the_block_whole(conn: Conn) -> None:
    _wells(conn)
    conn.execute("SELECT 1")  # the caller's transaction
    with tgsis.in_version(conn, "edit"):
        conn.execute("UPDATE wells SET depth = 1100 WHERE id = 1")
    assert conn.info.transaction_status == psycopg.pq.TransactionStatus.INTRANS  # still the caller's
    conn.rollback()
    assert tgsis.working_version(conn) == "DEFAULT"
    assert _depth(conn, "edit") == 1000


def test_unknown_version_everywhere(conn: Conn) -> None:
    for call in (
        lambda: tgsis.goto_version(conn, "nope"),
        lambda: tgsis.create_version(conn, "x", "nope"),
        lambda: tgsis.delete_version(conn, "nope"),
        lambda: tgsis.goto_revision(conn, "nope", 0),
    ):
        with pytest.raises(tgsis.NotFoundError, match="version 'nope' does not exist"):
            call()
        conn.rollback()
    conn.execute("SET tgsis.version = 'gone'")
    with pytest.raises(tgsis.NotFoundError, match="version 'gone' does not exist") as err:
        tgsis.revisions(conn)
    assert err.value.hint and "goto_version('DEFAULT')" in err.value.hint
    conn.rollback()
    assert _tree(conn) == {"DEFAULT": (None, None, 0, [0])}


@pytest.mark.parametrize(
    "name",
    [
        "",
        " a",
        "a ",
        "x" * 64,
        "a\tb",
        "a\nb",
        "a\x7fb",
        "a\x85b",
        "a\u00a0b",
        "a\u200bb",
        "a\u202eb",
        "\ufeffa",
        "a@1",
        None,
    ],
)
def test_bad_version_names_are_refused_and_nothing_is_written(conn: Conn, name: Any) -> None:
    with pytest.raises(tgsis.InvalidNameError, match="version name") as err:
        tgsis.create_version(conn, name)
    assert "\n" not in err.value.message and len(err.value.message) < 200  # the name is shown bounded, escaped
    conn.rollback()
    assert _tree(conn) == {"DEFAULT": (None, None, 0, [0])}
    assert conn.execute("SELECT last_value, is_called FROM tgsis.revision_seq").fetchone() == (1, False)


# the design's names are free text (revisionname varchar(50)); docs/versioning.md saves 'first pick'
FREE_NAMES = [
    "first pick",
    "x" * 63,
    "-a",
    "a;drop",
    'it\'s "quoted"',
    "Robert'); DROP TABLE x;--",
    "été 2024 (v2)",
    "断层 模型",
    "%s %I %L",
]


@pytest.mark.parametrize("name", FREE_NAMES)
def test_free_text_revision_and_version_names(conn: Conn, name: str) -> None:
    tgsis.create_version(conn, name)
    tgsis.goto_version(conn, name)
    assert tgsis.working_version(conn) == name
    saved = tgsis.save_revision(conn, name)
    tgsis.save_revision(conn, name[:50] + "@2")  # @ is fine in a revision name
    [v] = [v for v in tgsis.list_versions(conn) if v.name == name]
    assert v.saved == {name: saved, name[:50] + "@2": saved + 1}
    tgsis.goto_revision(conn, name, saved)
    tgsis.goto_version(conn, "DEFAULT")
    assert show_name(name) in format_tree(tgsis.list_versions(conn))
    tgsis.delete_version(conn, name)


def test_bad_revision_names_are_refused_naming_the_name_bounded(conn: Conn) -> None:
    tgsis.create_version(conn, "a")
    tgsis.goto_version(conn, "a")
    before = _tree(conn)
    with pytest.raises(tgsis.InvalidNameError, match=r"revision name 'x{60}'\.\.\. is not allowed: it has 5000 char"):
        tgsis.save_revision(conn, "x" * 5000)
    conn.rollback()
    with pytest.raises(tgsis.InvalidNameError, match=r"revision name 'first<U\+000A>pick' is not allowed: character 6"):
        tgsis.save_revision(conn, "first\npick")
    conn.rollback()
    assert _tree(conn) == before


def test_duplicate_names(conn: Conn) -> None:
    tgsis.create_version(conn, "a")
    before = _tree(conn)
    with pytest.raises(tgsis.AlreadyExistsError, match="version 'a' exists already"):
        tgsis.create_version(conn, "a")
    conn.rollback()
    assert _tree(conn) == before
    tgsis.goto_version(conn, "a")
    tgsis.save_revision(conn, "s")
    with pytest.raises(tgsis.AlreadyExistsError, match="revision named 's'"):
        tgsis.save_revision(conn, "s")


def test_delete_version_refuses_default_and_parents(conn: Conn) -> None:
    tgsis.create_version(conn, "a")
    tgsis.create_version(conn, "a1", "a")
    with pytest.raises(tgsis.InUseError, match="version 'a' has child versions: 'a1'"):
        tgsis.delete_version(conn, "a")
    conn.rollback()
    with pytest.raises(tgsis.InvalidInputError, match="DEFAULT cannot be deleted"):
        tgsis.delete_version(conn, "DEFAULT")
    conn.rollback()
    tgsis.goto_version(conn, "a1")
    assert tgsis.delete_version(conn, "a1") == 0
    assert tgsis.working_version(conn) == "DEFAULT"  # the session left the deleted version
    assert tgsis.delete_version(conn, "a") == 0
    assert set(_tree(conn)) == {"DEFAULT"}
    assert conn.execute("SELECT count(*) FROM tgsis.revisions WHERE versionid <> 0").fetchone() == (0,)


def test_save_revision_refused_while_viewing(conn: Conn) -> None:
    tgsis.create_version(conn, "a")
    tgsis.goto_revision(conn, "a", 0)
    with pytest.raises(tgsis.ReadOnlyRevisionError, match="viewed at revision 0"):
        tgsis.save_revision(conn, "x")


def test_concurrent_create_version_never_shares_revisions(db_dsn: str) -> None:
    import threading

    errors: list[BaseException] = []

    def create(prefix: str) -> None:
        try:
            with psycopg.connect(db_dsn) as c:
                for i in range(15):
                    tgsis.create_version(c, f"{prefix}{i}")
        except BaseException as exc:  # noqa: BLE001 - reported below
            errors.append(exc)

    threads = [threading.Thread(target=create, args=(p,)) for p in "xyz"]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not errors
    with psycopg.connect(db_dsn) as c:
        owners = c.execute("SELECT revision, versionid FROM tgsis.revisions").fetchall()
        assert len(owners) == 1 + 45 * 2 and len({r for r, _ in owners}) == len(owners)
        default = c.execute("SELECT workingset FROM tgsis.versions WHERE name = 'DEFAULT'").fetchone()
        assert default is not None and len(default[0]) == 46
        # every child's initrevision is a DEFAULT revision, and no two children share one
        inits = [r[0] for r in c.execute("SELECT initrevision FROM tgsis.versions WHERE parentid = 0").fetchall()]
        assert len(set(inits)) == 45 and set(inits) <= set(default[0])
