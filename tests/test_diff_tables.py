"""The diff of two versions table by table (issue 38, point 2): the same rows as the one-statement diff, one snapshot.

`tgsis version diff` was silent for 30-53 s on a 2M-row diff: tgsis.diff_versions is one statement over every
versioned table. tgsis.diff_table diffs one table, and tgsis.diff_versions(..., progress=) calls it table by
table so that the command can show how far it got. The tables are read in one REPEATABLE READ snapshot, so a
session committing between two tables changes nothing of the result.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import psycopg
import pytest

import tgsis
from tgsis import gmaps
from tgsis.db import versions as V
from tgsis.errors import NotFoundError

Conn = psycopg.Connection[Any]


def _objects() -> dict[str, object]:
    """One object of every shipped data model."""
    from tests.temporal_data import evolving, series

    rng = np.random.default_rng(38)
    return {
        "STATIC": tgsis.Surface([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]], name="tri"),
        "INSTANTS": series(rng, [0.0, 1.0, 2.0]),
        "EVOLVING": evolving(rng, [0.0, 2.0]),
        "GMAP": gmaps.GMap.from_triangles([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], [[0, 1, 2], [0, 2, 3]]),
        "MULTIDIM": gmaps.GMap.from_triangles([[0, 0, 0, 0.5], [1, 0, 0, 0.5], [1, 1, 0, 0.5]], [[0, 1, 2]]),
    }


@pytest.fixture
def changed(conn: Conn) -> dict[str, Any]:
    """Two features of every model in DEFAULT; in version v, of every model one deleted and one added."""
    objects = _objects()
    assert set(objects) == {m.time_model for m in tgsis.data_models()}
    kept: dict[str, list[int]] = {}
    for time_model, obj in objects.items():
        geotype = "GMAP" if isinstance(obj, gmaps.GMap) else "SURFACE"
        fc = tgsis.create_feature_class(
            conn,
            time_model.lower(),
            geotype,
            time_model=time_model,  # type: ignore[arg-type]
            cell_level=2 if geotype == "GMAP" else None,
        )
        kept[fc.name] = [tgsis.insert_feature(conn, fc, obj) for _ in range(2)]  # type: ignore[arg-type]
    tgsis.enable_feature_versioning(conn)
    tgsis.create_version(conn, "v")
    with tgsis.in_version(conn, "v"):
        for time_model, obj in objects.items():
            tgsis.delete_feature(conn, time_model.lower(), kept[time_model.lower()][0])
            tgsis.insert_feature(conn, time_model.lower(), obj)  # type: ignore[arg-type]
    conn.commit()
    return {"objects": objects, "kept": kept}


def _whole(conn: Conn, a: str, b: str) -> list[V.Difference]:
    """The one-statement diff, as SQL callers get it."""
    rows = conn.execute("SELECT * FROM tgsis.diff_versions(%s, %s)", (a, b)).fetchall()
    conn.commit()
    return [V.Difference(r[0], r[1], r[2], int(r[3]), int(r[4]), int(r[5])) for r in rows]


def _table_names(conn: Conn) -> list[str]:
    rows = conn.execute(
        "SELECT format('%I.%I', schemaname, tablename) FROM tgsis.versioned_tables"
        " ORDER BY objectclass, iudorder, shortname"
    ).fetchall()
    conn.commit()
    return [str(r[0]) for r in rows]


def test_table_by_table_is_the_whole_diff(conn: Conn, changed: dict[str, Any]) -> None:
    whole = _whole(conn, "DEFAULT", "v")
    # every model's tables differ, not only model 1's: the comparison is not vacuous
    geoids = {int(d.objectkey) for d in whole if d.objectclass == "feature"}
    for fids in changed["kept"].values():
        assert fids[0] in geoids and fids[1] not in geoids
    assert len({d.table for d in whole}) >= 8, sorted({d.table for d in whole})
    calls: list[tuple[int, int]] = []
    stepwise = V.diff_versions(conn, "DEFAULT", "v", progress=lambda done, total: calls.append((done, total)))
    assert stepwise == whole  # the same rows in the same order
    tables = _table_names(conn)
    assert calls == [(i, len(tables)) for i in range(1, len(tables) + 1)]
    by_table = [d for t in tables for d in V.diff_table(conn, t, "DEFAULT", "v")]
    assert by_table == whole
    assert V.diff_versions(conn, "DEFAULT", "v") == whole
    # the other way round, and against a revision
    assert V.diff_versions(conn, "v", "DEFAULT", progress=lambda d, t: None) == _whole(conn, "v", "DEFAULT")
    at_zero = conn.execute("SELECT * FROM tgsis.diff_versions('v', 'DEFAULT', NULL, 0)").fetchall()
    stepwise = V.diff_versions(conn, "v", "DEFAULT", b_revision=0, progress=lambda done, total: None)
    assert at_zero and [(d.objectclass, d.objectkey, d.table, d.added, d.removed, d.changed) for d in stepwise] == [
        tuple(r) for r in at_zero
    ]


def test_a_commit_between_two_tables_changes_nothing(db_dsn: str, conn: Conn, changed: dict[str, Any]) -> None:
    """Another session commits a feature into v after the first table is read: the later tables do not see it."""
    before = _whole(conn, "DEFAULT", "v")
    surface = changed["objects"]["STATIC"]
    added: list[int] = []

    def commit_elsewhere(done: int, total: int) -> None:
        if done == 1:
            with psycopg.connect(db_dsn) as other, tgsis.in_version(other, "v"):
                added.append(tgsis.insert_feature(other, "static", surface))

    assert V.diff_versions(conn, "DEFAULT", "v", progress=commit_elsewhere) == before
    assert added and str(added[0]) in {d.objectkey for d in _whole(conn, "DEFAULT", "v")}  # it did commit


@pytest.mark.parametrize("isolation", ["READ COMMITTED", "REPEATABLE READ", "SERIALIZABLE"])
def test_in_the_callers_transaction_it_is_one_snapshot_too(
    db_dsn: str, conn: Conn, changed: dict[str, Any], isolation: str
) -> None:
    """Inside a READ COMMITTED transaction each statement would see new commits: one statement then."""
    before = _whole(conn, "DEFAULT", "v")
    surface = changed["objects"]["STATIC"]
    tables = _table_names(conn)
    calls: list[tuple[int, int]] = []

    def commit_elsewhere(done: int, total: int) -> None:
        calls.append((done, total))
        if done == 1 and total > 1:
            with psycopg.connect(db_dsn) as other, tgsis.in_version(other, "v"):
                tgsis.insert_feature(other, "static", surface)

    conn.execute(f"SET TRANSACTION ISOLATION LEVEL {isolation}")
    assert V.diff_versions(conn, "DEFAULT", "v", progress=commit_elsewhere) == before
    assert calls[-1] == (len(tables), len(tables))
    assert len(calls) == (1 if isolation == "READ COMMITTED" else len(tables))
    assert conn.info.transaction_status == psycopg.pq.TransactionStatus.INTRANS  # the caller's, still open
    conn.rollback()


def test_diff_table_refuses_what_is_not_a_versioned_table(conn: Conn, changed: dict[str, Any]) -> None:
    with pytest.raises(NotFoundError, match="not versioned"):
        V.diff_table(conn, "tgsis.catalog", "DEFAULT", "v")
    conn.rollback()
    with pytest.raises(tgsis.Error):
        V.diff_table(conn, "tgsis.no_such_table", "DEFAULT", "v")
    conn.rollback()
    with pytest.raises(NotFoundError, match="nope"):
        V.diff_table(conn, "tgsis.vrtx", "DEFAULT", "nope")
    conn.rollback()
    with pytest.raises(NotFoundError, match="nope"):
        V.diff_versions(conn, "DEFAULT", "nope", progress=lambda d, t: None)


def test_diff_table_is_documented_in_sql(conn: Conn) -> None:
    comment = conn.execute(
        "SELECT obj_description('tgsis.diff_table(regclass, text, text, integer, integer)'::regprocedure)"
    ).fetchone()
    assert comment is not None and "one versioned table" in str(comment[0])


def test_a_role_that_may_not_read_a_table_gets_the_permission_error_not_a_partial_diff(
    db_dsn: str, conn: Conn, changed: dict[str, Any]
) -> None:
    from tests.roles import login_roles

    whole = _whole(conn, "DEFAULT", "v")
    with login_roles(db_dsn, {"rita": "tgsis_reader"}) as made:
        rita = made.connect("rita")
        assert V.diff_versions(rita, "DEFAULT", "v") == whole  # a reader may
        assert V.diff_versions(rita, "DEFAULT", "v", progress=lambda done, total: None) == whole
        rita.close()
        conn.execute("REVOKE SELECT ON public.static, public.static_ver FROM tgsis_reader, PUBLIC")
        conn.commit()
        rita = made.connect("rita")
        for progress in (None, lambda done, total: None):
            with pytest.raises(tgsis.MissingPrivilegeError, match="static"):
                V.diff_versions(rita, "DEFAULT", "v", progress=progress)
            rita.rollback()
        with pytest.raises(psycopg.errors.InsufficientPrivilege, match="static"):  # in psql: PostgreSQL's 42501
            rita.execute("SELECT * FROM tgsis.diff_table('public.static', 'DEFAULT', 'v')").fetchall()
