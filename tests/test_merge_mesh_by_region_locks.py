"""``tgsis.merge_mesh_by_region`` called alone takes the merge's locks itself (plan I, A3).

It is internal (REVOKEd from PUBLIC; ``tgsis.merge_regions_in_sql`` calls it after
``tgsis.lock_for_region_merge``), but a superuser may call it alone from psql, as the tests do. Before plan I it then
read the three states without the merge's locks: a writer of the version with an uncommitted edit of a vertex the
merge brings from the parent made it plan the write on the state before that edit, wait for the writer's row, and
close the writer's row version when it went on: the writer's edit lost, silently. Now it takes
``tgsis.lock_version_pair`` first (parent, then version, waiting for their writers), so it reads after the writer
committed: the edit is kept (the vertex is changed on both sides now: the merge refuses or leaves it to the
conflict, never writes over it).
"""

from __future__ import annotations

from typing import Any

import psycopg
import pytest

import tgsis
from tests.merge_data import make_fault, move
from tests.sessions import Background, connect, wait_until_blocked

Conn = psycopg.Connection[Any]

CONFLICT = [50, 51, 62]  # moved on both sides: a conflicting region, solved 'child'
PARENT_ONLY = [5, 6]  # moved by the parent only: the merge brings them into e1


def _vertex_z(conn: Conn, version: str, geoid: int, vrtxid: int) -> float:
    with tgsis.in_version(conn, version):
        row = conn.execute("SELECT z FROM tgsis.vrtx WHERE geoid = %s AND vrtxid = %s", (geoid, vrtxid)).fetchone()
    conn.rollback()
    assert row is not None
    return float(row[0])


@pytest.mark.parametrize("action", ["merge", "refresh"])
def test_merge_mesh_by_region_alone_waits_for_a_writer_of_the_version_and_loses_nothing(
    db_dsn: str, conn: Conn, action: str
) -> None:
    geoid = make_fault(conn)
    move(conn, "DEFAULT", geoid, CONFLICT + PARENT_ONLY, (0.0, 0.0, 7.25))
    move(conn, "e1", geoid, CONFLICT, (0.0, 0.0, -3.5))
    conn.commit()
    conn.execute("SELECT FROM tgsis.find_conflicts('e1')")
    solved = conn.execute(
        "SELECT count(tgsis.resolve_region('e1', 'feature', %s, region, 'child')) FROM tgsis.conflict_regions"
        " WHERE versionid = tgsis.version_id('e1') AND conflict",
        (str(geoid),),
    ).fetchone()
    conn.commit()
    assert solved is not None and solved[0] >= 1

    # a writer of e1 (a psql user): an uncommitted edit of a vertex the parent moved
    writer = connect(db_dsn, "writer")
    tgsis.goto_version(writer, "e1")
    writer.commit()
    writer.execute("UPDATE tgsis.vrtx SET z = 4321.0 WHERE geoid = %s AND vrtxid = %s", (geoid, PARENT_ONLY[0]))

    def merge(c: Conn) -> Any:
        c.execute("SET TRANSACTION ISOLATION LEVEL READ COMMITTED")
        return c.execute("SELECT tgsis.merge_mesh_by_region('e1', %s, %s)", (action, geoid)).fetchone()

    merger = Background(db_dsn, "merger", merge)
    wait_until_blocked(conn, merger.pid, writer.info.backend_pid)
    writer.commit()
    writer.close()
    try:
        merger.finish()
    except psycopg.Error as exc:
        # the vertex is changed on both sides now, the stored regions are not the regions of now: refused by name
        assert exc.sqlstate == "TG302", exc
    assert _vertex_z(conn, "e1", geoid, PARENT_ONLY[0]) == 4321.0, "the writer's edit was lost"
