"""Hostile review of region detection in SQL (tgsis.mesh_merge_regions, SQL find_conflicts / resolve_conflict).

Each case is a shape or a session the tests of tests/test_sql_merge_regions.py do not cover; the oracle is the
Python three-way merge (tgsis.merge3 through tgsis.object_merge).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import psycopg
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import tgsis
from tests.merge_data import SIDE, make_fault, move
from tests.test_sql_merge_regions import (
    MIDDLE,
    NORTH,
    SOUTH,
    assert_same_regions,
    property_tables,
    psql,
    python_regions,
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


def test_editor_calls_mesh_merge_regions_directly(conn: Conn, db_dsn: str, three_regions_clone: int) -> None:
    from tests.roles import login_roles

    fault = three_regions_clone  # make_fault's fault and three_regions' moves (tests/conftest.py)
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


def test_a_vector_property_in_chunks_is_read_by_the_regions(conn: Conn) -> None:
    """The class in chunks whatever the file's storage: the regions' reader of a vector property's chunk versions
    raised 40001 ("added after this transaction's snapshot") on chunks holding every array, the decoding's
    missing-array call being of constants only, which the planner may evaluate to estimate an expression."""
    n = SIDE * SIDE
    geoid = _class_with(
        conn,
        [tgsis.Property("dip", "double precision", size=3), tgsis.Property("k", "bigint")],
        {"dip": np.linspace(0, 1, 3 * n).reshape(n, 3), "k": np.arange(n, dtype=np.int64) * 3},
    )
    if not conn.execute("SELECT tgsis.stored_in_chunks('public', 'bodies_cellpros')").fetchone() == (True,):
        conn.execute("SELECT tgsis.store_class_in_chunks('bodies')")
        conn.commit()
    vp, _ = property_tables(conn, geoid)
    psql(conn, "e1", (f"UPDATE {vp} SET dip[2] = 'NaN' WHERE _geoid = %s AND _idx = 5", (geoid,)))
    psql(conn, "DEFAULT", (f"UPDATE {vp} SET k = 9 WHERE _geoid = %s AND _idx = 41", (geoid,)))
    assert_same_regions(conn, "e1", geoid)


def test_isolated_vertex_moved_both_sides(conn: Conn, fault_clone: int) -> None:
    fault = fault_clone
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


def test_new_ids_at_the_top_of_bigint_refuse_the_merge_by_region_not_find_conflicts(
    conn: Conn, fault_clone: int
) -> None:
    """Both sides add a different vertex with id 2^63 - 1: the version's must be renumbered above every id,
    which bigint cannot hold. It was: SQL find_conflicts failed (22003 bigint out of range) for the whole
    version, so a psql user could list no conflict at all; now that feature has no regions (it merges as a
    whole object) and mesh_merge_regions refuses it by name (TG100)."""
    fault = fault_clone
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


_rpairs = iter(range(10**6))
_hedit = st.tuples(
    st.sampled_from(["move", "dropvertex", "reconnect", "atom", "addsame", "addother", "nan", "negzero", "flip"]),
    st.integers(0, 2 * (SIDE - 1) ** 2 - 1),
    st.integers(0, 2),
)


def _statements(geoid: int, edits: list[tuple[str, int, int]], vp: str, cp: str) -> list[tuple[str, tuple[Any, ...]]]:
    out: list[tuple[str, tuple[Any, ...]]] = []
    for kind, where, which in edits:
        row, col = (where // 2) // (SIDE - 1), (where // 2) % (SIDE - 1)
        v = row * SIDE + col
        if kind == "move":
            out.append(
                (
                    "UPDATE tgsis.vrtx SET z = z + %s WHERE geoid = %s AND vrtxid = ANY (%s)",
                    (0.5 + which, geoid, [v, v + 1][: which + 1]),
                )
            )
        elif kind == "dropvertex":
            out.append(("DELETE FROM tgsis.trgl WHERE geoid = %s AND %s IN (vrtxid1, vrtxid2, vrtxid3)", (geoid, v)))
            out.append((f"DELETE FROM {vp} WHERE _geoid = %s AND _idx = %s", (geoid, v)))
            out.append(("DELETE FROM tgsis.vrtx WHERE geoid = %s AND vrtxid = %s", (geoid, v)))
        elif kind == "reconnect":
            out.append(
                (
                    "UPDATE tgsis.trgl SET vrtxid3 = %s WHERE geoid = %s AND trglid = %s AND %s NOT IN"
                    " (vrtxid1, vrtxid2) AND EXISTS (SELECT FROM tgsis.vrtx WHERE geoid = %s AND vrtxid = %s)",
                    (
                        v + SIDE + 1 if v + SIDE + 1 < SIDE * SIDE else 0,
                        geoid,
                        where,
                        v + SIDE + 1 if v + SIDE + 1 < SIDE * SIDE else 0,
                        geoid,
                        v + SIDE + 1 if v + SIDE + 1 < SIDE * SIDE else 0,
                    ),
                )
            )
        elif kind == "atom":
            out.append(
                (
                    "INSERT INTO tgsis.atom (geoid, vrtxid, refid) SELECT %s, %s, %s WHERE NOT EXISTS"
                    " (SELECT FROM tgsis.atom WHERE geoid = %s AND vrtxid = %s)"
                    " AND EXISTS (SELECT FROM tgsis.vrtx WHERE geoid = %s AND vrtxid IN (%s, %s))"
                    " AND (SELECT count(*) FROM tgsis.vrtx WHERE geoid = %s AND vrtxid IN (%s, %s)) = 2",
                    (geoid, v, v + 1, geoid, v, geoid, v, v + 1, geoid, v, v + 1),
                )
            )
        elif kind in ("addsame", "addother"):
            x = 1000.0 * col if kind == "addsame" else 1000.0 * col + 0.5 + which
            out.append(
                (
                    "INSERT INTO tgsis.vrtx (geoid, vrtxid, x, y, z)"
                    " SELECT %s, max(vrtxid) + 1, %s, -400.0, 0.0 FROM tgsis.vrtx WHERE geoid = %s",
                    (geoid, x, geoid),
                )
            )
            out.append(
                (
                    "INSERT INTO tgsis.trgl (geoid, trglid, vrtxid1, vrtxid2, vrtxid3)"
                    " SELECT %s, (SELECT max(trglid) + 1 FROM tgsis.trgl WHERE geoid = %s), %s, %s, max(vrtxid)"
                    "   FROM tgsis.vrtx WHERE geoid = %s"
                    " HAVING (SELECT count(*) FROM tgsis.vrtx WHERE geoid = %s AND vrtxid IN (%s, %s)) = 2",
                    (geoid, geoid, col, col + 1, geoid, geoid, col, col + 1),
                )
            )
        elif kind == "nan":
            out.append((f"UPDATE {vp} SET porosity = 'NaN' WHERE _geoid = %s AND _idx = %s", (geoid, v)))
        elif kind == "negzero":
            out.append((f"UPDATE {vp} SET porosity = '-0' WHERE _geoid = %s AND _idx = %s", (geoid, v + which)))
        else:
            out.append(
                (
                    "UPDATE tgsis.trgl SET vrtxid1 = vrtxid2, vrtxid2 = vrtxid3, vrtxid3 = vrtxid1"
                    " WHERE geoid = %s AND trglid = %s",
                    (geoid, where),
                )
            )
    return out


@settings(
    max_examples=int(__import__("os").environ.get("REV_EXAMPLES", "40")),
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)
@given(child=st.lists(_hedit, min_size=1, max_size=5), parent=st.lists(_hedit, min_size=1, max_size=5))
def test_more_random_edits_give_merge3s_regions(
    conn: Conn, child: list[tuple[str, int, int]], parent: list[tuple[str, int, int]]
) -> None:
    global _FAULT
    if _FAULT is None or _FAULT[0] is not conn:
        _FAULT = (conn, make_fault(conn))
    fault = _FAULT[1]
    n = next(_rpairs)
    pv, cv = f"rp{n}", f"rc{n}"
    tgsis.create_version(conn, pv)
    conn.commit()
    tgsis.create_version(conn, cv, parent=pv)
    conn.commit()
    vp, cp = property_tables(conn, fault)
    psql(conn, cv, *_statements(fault, child, vp, cp))
    psql(conn, pv, *_statements(fault, parent, vp, cp))
    conflicts = conn.execute("SELECT objectkey FROM tgsis.find_conflicts(%s)", (cv,)).fetchall()
    conn.rollback()
    if conflicts:
        try:
            python_regions(conn, cv, fault)
        except tgsis.Error:
            conn.rollback()
            return  # not a valid merge state for merge3 (its own refusal): nothing to compare
        assert_same_regions(conn, cv, fault)


_FAULT: tuple[Conn, int] | None = None


def test_a_whole_side_from_a_role_that_may_not_read_the_class_is_not_left_unchecked(
    conn: Conn, db_dsn: str, three_regions_clone: int
) -> None:
    """A role that may write in the version but not read the feature's class gets no regions computed (SQL
    region detection reads with its rights). It was: its resolve_conflict(..., 'child') then found no regions,
    so the rule that refuses a whole side dropping the parent's edits in regions that merge by themselves did
    not apply, and 'child' was recorded: the merge would drop the parent's south-end edit. Now refused
    (42501) until the regions are stored; once someone who may read found them, the rule refuses it (TG307)."""
    from tests.roles import login_roles

    fault = three_regions_clone
    with login_roles(db_dsn, {"ed": "tgsis_editor"}) as made:
        tgsis.grant_version(conn, "e1", "write", made.name("ed"))
        conn.execute("REVOKE SELECT ON public.faults FROM tgsis_editor, tgsis_reader")
        conn.commit()
        ed = made.connect("ed")
        for solution in ("child", "parent"):
            state, message, _ = sqlstate(
                ed, "SELECT tgsis.resolve_conflict('e1', 'feature', %s, %s)", (str(fault), solution)
            )
            assert state == "42501", message
        assert conn.execute("SELECT solution FROM tgsis.conflicts").fetchall() in ([], [("unsolved",)])
        conn.rollback()
        # 'manual' and 'base' stay its to give (no rule about the other side's edits)
        state, message, _ = sqlstate(ed, "SELECT tgsis.resolve_conflict('e1', 'feature', %s, 'manual')", (str(fault),))
        assert state is None, message
        conn.execute("SELECT FROM tgsis.find_conflicts('e1')")  # the owner finds and stores the regions
        conn.commit()
        state, message, _ = sqlstate(ed, "SELECT tgsis.resolve_conflict('e1', 'feature', %s, 'child')", (str(fault),))
        assert state == "TG307", message


def test_many_region_detections_in_one_transaction_hold_no_locks_and_leave_no_tables(
    conn: Conn, three_regions_clone: int
) -> None:
    """Each SQL region detection made about 12 temporary work tables (with indexes and TOAST tables) and dropped
    them: a relation created and dropped keeps its lock until the transaction ends, about 100 locks per mesh.
    It was: 100 detections in one transaction (a find_conflicts over 100 conflicting meshes, or a psql loop)
    held 10,250 locks, beyond the lock table's nominal 6,400 (max_locks_per_transaction 64 x 100 connections):
    some hundreds of meshes fail with 53200 out of shared memory, and take the lock table from every other
    session meanwhile."""
    fault = three_regions_clone
    expected = conn.execute("SELECT * FROM tgsis.mesh_merge_regions('e1', %s)", (fault,)).fetchall()
    conn.rollback()
    before = conn.execute("SELECT count(*) FROM pg_locks WHERE pid = pg_backend_pid()").fetchone()
    for _ in range(100):
        assert conn.execute("SELECT * FROM tgsis.mesh_merge_regions('e1', %s)", (fault,)).fetchall() == expected
    after = conn.execute("SELECT count(*) FROM pg_locks WHERE pid = pg_backend_pid()").fetchone()
    assert before is not None and after is not None and after[0] - before[0] < 50
    left = conn.execute("SELECT count(*) FROM pg_class WHERE relname LIKE 'tgsis\\_mr\\_%%'").fetchone()
    assert left == (0,)
    conn.rollback()
    assert len(expected) == 3
    assert_same_regions(conn, "e1", fault)


def test_psql_conflicts_of_a_g_map_and_an_evolving_surface_regions_by_slice_and_solve_whole(conn: Conn) -> None:
    """A g-map and an evolving surface (model 3) in conflict, from psql only: SQL find_conflicts stores no regions
    for the g-map (it does not merge by region), and for the evolving surface the regions of each geometry instant
    both sides changed, as the Python find_conflicts stores them (each with its slice: timem, times); the region
    engine without a slice refuses both (TG100); resolve_conflict records a whole side."""
    from tests.temporal_data import evolving
    from tests.test_gmap_storage import _class, _evolving
    from tests.test_temporal_versioning import STARTS

    fc = _class(conn)
    geoid = F.insert_feature(conn, fc, _evolving())
    moving = F.create_feature_class(conn, "moving", "SURFACE", time_model="EVOLVING")
    fid = F.insert_feature(conn, moving, evolving(np.random.default_rng(8), STARTS))
    conn.commit()
    tgsis.enable_feature_versioning(conn)
    tgsis.create_version(conn, "other")
    conn.commit()
    move_g = "UPDATE tgsis.gmap_vertex SET coordinate = %s::float8[] WHERE geoid = %s AND timet = 3 AND nodeid = 4"
    move_e = "UPDATE tgsis.d4dvrtx SET x = x + %s WHERE geoid = %s AND nodeid = 0"
    psql(conn, "DEFAULT", (move_g, ([7, 7, 7], geoid)), (move_e, (1.0, fid)))
    psql(conn, "other", (move_g, ([8, 8, 8], geoid)), (move_e, (-1.0, fid)))
    keys = conn.execute("SELECT objectkey FROM tgsis.find_conflicts('other') ORDER BY objectkey::bigint").fetchall()
    assert sorted(int(k) for (k,) in keys) == sorted([geoid, fid])
    assert conn.execute(
        "SELECT count(*) FROM tgsis.conflict_regions WHERE objectkey = %s", (str(geoid),)
    ).fetchone() == (0,)
    stored = conn.execute(
        "SELECT timem, times, conflict, vertex_ids FROM tgsis.conflict_regions WHERE objectkey = %s ORDER BY region",
        (str(fid),),
    ).fetchall()
    slices = conn.execute(
        "SELECT timem, timet FROM tgsis.d4dvrtx WHERE geoid = %s AND nodeid = 0 ORDER BY timem, timet", (fid,)
    ).fetchall()
    # node 0 moved by each side otherwise at every geometry instant it has: one conflicting region there, on node 0
    assert [(m, t, c, v) for (m, t, c, v) in stored] == [(m, t, True, [0]) for (m, t) in slices], (stored, slices)
    mine = sorted(
        conn.execute("SELECT timem, times, conflict, vertex_ids, cell_ids FROM tgsis.conflict_regions").fetchall()
    )
    conn.rollback()  # SQL find_conflicts rolled back: the Python one finds them afresh
    tgsis.find_conflicts(conn, "other")
    theirs = sorted(
        conn.execute("SELECT timem, times, conflict, vertex_ids, cell_ids FROM tgsis.conflict_regions").fetchall()
    )
    assert mine == theirs
    for g in (geoid, fid):
        state, message, _ = sqlstate(conn, "SELECT * FROM tgsis.mesh_merge_regions('other', %s)", (g,))
        assert state == "TG100", message
    for g in (geoid, fid):
        conn.execute("SELECT tgsis.resolve_conflict('other', 'feature', %s, 'child')", (str(g),))
    conn.commit()
    assert conn.execute("SELECT array_agg(DISTINCT solution) FROM tgsis.conflicts").fetchone() == (["child"],)


def test_regions_of_a_mesh_in_partitioned_model_storage(conn: Conn) -> None:
    tgsis.partition_model_storage(conn, 1, 4)
    conn.commit()
    fault = make_fault(conn)
    three_regions(conn, fault)
    assert len(assert_same_regions(conn, "e1", fault)) == 3


def test_resolving_conflicts_one_by_one_does_not_find_every_other_objects_regions_again(conn: Conn) -> None:
    """Each SQL resolve_conflict / resolve_region / resolve_all_regions runs find_conflicts for the marks of
    now. It was: that find_conflicts also tried to find the regions of every other unsolved mesh without
    stored regions (a feature deleted on one side, attributes set alike on both: no regions, tried each time),
    so solving n such conflicts one by one from psql checked them n (n + 1) / 2 times: quadratic. Now a
    solution finds the regions of its own object only (counted with track_functions)."""
    F.create_feature_class(conn, "small", "SURFACE")
    tgsis.enable_feature_versioning(conn)
    verts = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]], dtype=float)
    cells = np.array([[0, 1, 2], [1, 3, 2]])
    ids = [F.insert_feature(conn, "small", tgsis.Surface(verts, cells)) for _ in range(20)]
    tgsis.create_version(conn, "e1")
    conn.commit()
    psql(conn, "e1", ("UPDATE tgsis.vrtx SET z = 1 WHERE geoid = ANY (%s) AND vrtxid = 0", (ids,)))
    with tgsis.in_version(conn, "DEFAULT"):
        for g in ids:
            F.delete_feature(conn, "small", g)
    conn.commit()
    assert len(conn.execute("SELECT * FROM tgsis.find_conflicts('e1')").fetchall()) == len(ids)
    conn.commit()
    conn.execute("SET track_functions = 'pl'")
    for g in ids:
        conn.execute("SELECT tgsis.resolve_conflict('e1', 'feature', %s, 'child')", (str(g),))
    calls = conn.execute(
        "SELECT coalesce(sum(calls), 0) FROM pg_stat_xact_user_functions WHERE funcname = 'region_merge_refusal'"
    ).fetchone()
    conn.rollback()
    assert calls is not None and 0 < calls[0] <= 3 * len(ids), calls


# every statement compiled and optimised by LLVM: 10-15 s per call of tgsis.mesh_merge_regions on PostgreSQL 15
JIT_EVERYWHERE = "jit = on; SET jit_above_cost = 0; SET jit_optimize_above_cost = 0"


@pytest.mark.parametrize(
    "setting",
    [
        "extra_float_digits = -15",
        "DateStyle = 'SQL, DMY'",
        "lc_numeric = 'C'",
        "enable_seqscan = off; SET jit = off",
        JIT_EVERYWHERE,
        "search_path = pg_temp, public",
    ],
)
def test_the_regions_are_the_same_under_other_session_settings(
    conn: Conn, setting: str, three_regions_clone: int
) -> None:
    """Stored under the setting, read back (and compared with merge3) without it: the text this session
    reads floats in is the setting's, not what was stored. Under JIT the direct call is left out: find_conflicts
    runs tgsis.mesh_merge_regions under the setting too (store_mesh_regions), and what it stores is compared."""
    fault = three_regions_clone
    conn.execute("SET " + setting)
    conn.commit()
    if setting != JIT_EVERYWHERE:
        assert len(conn.execute("SELECT * FROM tgsis.mesh_merge_regions('e1', %s)", (fault,)).fetchall()) == 3
    conn.execute("SELECT FROM tgsis.find_conflicts('e1')")
    conn.commit()
    conn.execute("RESET ALL")
    conn.commit()
    assert len(assert_same_regions(conn, "e1", fault)) == 3


_KINDS = {
    "MULTIPOINT": ("point", "pointid", 1),
    "MULTILINESTRING": ("segment", "segid", 2),
    "MULTITETRA": ("tetra", "tetraid", 4),
}
_other_edit = st.tuples(st.sampled_from(["move", "delete", "flip", "rotate"]), st.integers(0, 35), st.integers(0, 2))
_other_pairs = iter(range(10**6))
_BODIES: dict[str, int] = {}


@pytest.mark.parametrize("geotype", list(_KINDS))
@settings(
    max_examples=12, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow]
)
@given(child=st.lists(_other_edit, min_size=1, max_size=4), parent=st.lists(_other_edit, min_size=1, max_size=4))
def test_random_edits_of_points_lines_and_solids_give_merge3s_regions(
    conn: Conn, geotype: str, child: list[tuple[str, int, int]], parent: list[tuple[str, int, int]]
) -> None:
    from tests.test_object_merge import _other_kind

    table, key, k = _KINDS[geotype]
    if conn.info.dbname not in _BODIES:
        F.create_feature_class(conn, "bodies", geotype)
        tgsis.enable_feature_versioning(conn)
        _BODIES[conn.info.dbname] = F.insert_feature(conn, "bodies", _other_kind(geotype))
        conn.commit()
    geoid = _BODIES[conn.info.dbname]
    n = next(_other_pairs)
    pv, cv = f"op{n}", f"oc{n}"
    tgsis.create_version(conn, pv)
    conn.commit()
    tgsis.create_version(conn, cv, parent=pv)
    conn.commit()

    def statements(edits: list[tuple[str, int, int]]) -> list[tuple[str, tuple[Any, ...]]]:
        out: list[tuple[str, tuple[Any, ...]]] = []
        for kind, where, which in edits:
            if kind == "move":
                out.append(
                    (
                        "UPDATE tgsis.vrtx SET y = y + %s WHERE geoid = %s AND vrtxid = ANY (%s)",
                        (0.25 + which, geoid, list(range(where, where + which + 1))),
                    )
                )
            elif kind == "delete":
                out.append((f"DELETE FROM tgsis.{table} WHERE geoid = %s AND {key} = %s", (geoid, where)))
            elif kind == "flip" and k >= 2:
                out.append(
                    (
                        f"UPDATE tgsis.{table} SET vrtxid1 = vrtxid2, vrtxid2 = vrtxid1"
                        f" WHERE geoid = %s AND {key} = %s",
                        (geoid, where),
                    )
                )
            elif kind == "rotate" and k >= 3:
                out.append(
                    (
                        f"UPDATE tgsis.{table} SET vrtxid1 = vrtxid2, vrtxid2 = vrtxid3, vrtxid3 = vrtxid1"
                        f" WHERE geoid = %s AND {key} = %s",
                        (geoid, where),
                    )
                )
        return out or [("UPDATE tgsis.vrtx SET z = z + 1 WHERE geoid = %s AND vrtxid = 0", (geoid,))]

    psql(conn, cv, *statements(child))
    psql(conn, pv, *statements(parent))
    conflicts = conn.execute("SELECT objectkey FROM tgsis.find_conflicts(%s)", (cv,)).fetchall()
    conn.rollback()
    if conflicts:
        assert_same_regions(conn, cv, geoid)
