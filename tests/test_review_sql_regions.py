"""Hostile review of region detection in SQL (tgsis.mesh_merge_regions, SQL find_conflicts / resolve_conflict).

Each case is a shape or a session the tests of tests/test_sql_merge_regions.py do not cover; the oracle is the
Python three-way merge (tgsis.merge3 through tgsis.object_merge).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import psycopg

import tgsis
from tests.merge_data import SIDE, make_fault, move
from tests.test_sql_merge_regions import (
    MIDDLE,
    NORTH,
    SOUTH,
    assert_same_regions,
    property_tables,
    psql,
    sql_regions,
    sqlstate,
)
from tgsis.db import features as F

Conn = psycopg.Connection[Any]


def three_regions(conn: Conn, fault: int) -> None:
    move(conn, "e1", fault, NORTH, (0.5, 0.0, 1.25))
    move(conn, "e1", fault, MIDDLE, (0.0, 0.0, 5.0))
    move(conn, "DEFAULT", fault, SOUTH, (-1.0, 0.0, -2.0))
    move(conn, "DEFAULT", fault, MIDDLE, (0.0, 0.0, -7.0))
    conn.commit()


def test_editor_calls_mesh_merge_regions_directly(conn: Conn, db_dsn: str) -> None:
    from tests.roles import login_roles

    fault = make_fault(conn)
    three_regions(conn, fault)
    with login_roles(db_dsn, {"ed": "tgsis_editor"}) as made:
        tgsis.grant_version(conn, "e1", "write", made.name("ed"))
        conn.commit()
        ed = made.connect("ed")
        rows = ed.execute("SELECT region FROM tgsis.mesh_merge_regions('e1', %s)", (fault,)).fetchall()
        ed.rollback()
        assert len(rows) == 3


def _class_with(conn: Conn, props: list[Any], values: dict[str, Any]) -> int:
    from tests.merge_data import curved_surface

    F.create_feature_class(conn, "bodies", "SURFACE", cell_properties=props)
    tgsis.enable_feature_versioning(conn)
    s = curved_surface()
    mesh = tgsis.Surface(s.vertices, s.cells, vertex_properties=values)
    geoid = F.insert_feature(conn, "bodies", mesh)
    tgsis.create_version(conn, "e1")
    conn.commit()
    return geoid


def test_vector_bool_real_properties(conn: Conn) -> None:
    n = SIDE * SIDE
    geoid = _class_with(
        conn,
        [
            tgsis.Property("dip", "double precision", size=3),
            tgsis.Property("ok", "boolean"),
            tgsis.Property("r", "real"),
            tgsis.Property("k", "bigint"),
        ],
        {
            "dip": np.linspace(0, 1, 3 * n).reshape(n, 3),
            "ok": np.arange(n) % 2 == 0,
            "r": np.linspace(0, 1, n).astype(np.float32),
            "k": np.arange(n, dtype=np.int64) * 3,
        },
    )
    vp, _ = property_tables(conn, geoid)
    psql(
        conn,
        "e1",
        (f"UPDATE {vp} SET dip[2] = 'NaN' WHERE _geoid = %s AND _idx = 5", (geoid,)),
        (f"UPDATE {vp} SET ok = NOT ok WHERE _geoid = %s AND _idx = 20", (geoid,)),
        (f"UPDATE {vp} SET r = 0.1 WHERE _geoid = %s AND _idx = 30", (geoid,)),
        (f"UPDATE {vp} SET k = 7 WHERE _geoid = %s AND _idx = 40", (geoid,)),
        (f"UPDATE {vp} SET dip = '{{-0.0,0,0}}' WHERE _geoid = %s AND _idx = 0", (geoid,)),
    )
    psql(
        conn,
        "DEFAULT",
        (f"UPDATE {vp} SET dip[2] = 'NaN' WHERE _geoid = %s AND _idx = 5", (geoid,)),
        (f"UPDATE {vp} SET ok = NOT ok WHERE _geoid = %s AND _idx = 20", (geoid,)),
        (f"UPDATE {vp} SET r = 0.1 WHERE _geoid = %s AND _idx = 30", (geoid,)),
        (f"UPDATE {vp} SET k = 9 WHERE _geoid = %s AND _idx = 41", (geoid,)),
    )
    assert_same_regions(conn, "e1", geoid)


def test_isolated_vertex_moved_both_sides(conn: Conn) -> None:
    fault = make_fault(conn)
    add = "INSERT INTO tgsis.vrtx (geoid, vrtxid, x, y, z) VALUES (%s, %s, %s, %s, %s)"
    with tgsis.in_version(conn, "DEFAULT"):
        conn.execute(add, (fault, 1000, 1.0, 2.0, 3.0))
    conn.commit()
    tgsis.create_version(conn, "e2")
    conn.commit()
    move(conn, "e2", fault, [1000], (1.0, 0.0, 0.0))
    move(conn, "DEFAULT", fault, [1000], (2.0, 0.0, 0.0))
    move(conn, "DEFAULT", fault, [0], (2.0, 0.0, 0.0))
    conn.commit()
    assert_same_regions(conn, "e2", fault)


def test_new_ids_at_the_top_of_bigint_refuse_the_merge_by_region_not_find_conflicts(conn: Conn) -> None:
    """Both sides add a different vertex with id 2^63 - 1: the version's must be renumbered above every id,
    which bigint cannot hold. It was: SQL find_conflicts failed (22003 bigint out of range) for the whole
    version, so a psql user could list no conflict at all; now that feature has no regions (it merges as a
    whole object) and mesh_merge_regions refuses it by name (TG100)."""
    fault = make_fault(conn)
    top = 2**63 - 1
    add = "INSERT INTO tgsis.vrtx (geoid, vrtxid, x, y, z) VALUES (%s, %s, %s, %s, %s)"
    psql(conn, "e1", (add, (fault, top, 1.0, 2.0, 3.0)))
    psql(conn, "DEFAULT", (add, (fault, top, 5.0, 2.0, 3.0)))
    state, message, _ = sqlstate(conn, "SELECT * FROM tgsis.find_conflicts('e1')", ())
    assert state is None, message
    assert sql_regions(conn, "e1", fault) == []
    state, message, hint = sqlstate(conn, "SELECT * FROM tgsis.mesh_merge_regions('e1', %s)", (fault,))
    assert state == "TG100" and str(top) in message, message
    assert "resolve_conflict" in (hint or "")
    # the same ids with the same content: nothing to renumber, the regions are found
    psql(conn, "e1", ("UPDATE tgsis.vrtx SET x = 5.0 WHERE geoid = %s AND vrtxid = %s", (fault, top)))
    assert len(sql_regions(conn, "e1", fault)) == 1


def test_attribute_only_conflict_leaves_no_work_tables(conn: Conn, db_dsn: str) -> None:
    from tests.roles import login_roles
    from tests.test_object_merge import _fault_with_status, _set_status

    geoid = _fault_with_status(conn)
    _set_status(conn, "e1", geoid, "b")
    _set_status(conn, "DEFAULT", geoid, "b")
    with login_roles(db_dsn, {"ed": "tgsis_editor"}) as made:
        tgsis.grant_version(conn, "e1", "write", made.name("ed"))
        conn.commit()
        ed = made.connect("ed")
        assert ed.execute("SELECT objectkey FROM tgsis.find_conflicts('e1')").fetchall() == [(str(geoid),)]
        left = ed.execute("SELECT count(*) FROM pg_class WHERE relname LIKE 'tgsis\\_mr\\_%%' AND relpersistence = 't'")
        assert left.fetchone() == (0,)
        rows = ed.execute("SELECT * FROM tgsis.mesh_merge_regions('e1', %s)", (geoid,)).fetchall()
        ed.rollback()
        assert rows == []
