"""The indexes that find a versioned table's row versions by revision (tgsis.create_revision_indexes, issue 39's figures).

Every versioned storage gets a BRIN on ``revision`` and a btree on the
object key of closed rows; tgsis.copy_object_state (every merge, refresh and
object-level solution) states its rows' condition in a form they serve, so
a merge of a small edit of a large object reads the edit, not the object.
The plans are taken from the server (auto_explain, as notices) with
sequential scans made costly, as on a large table: the rows a merge acts on
must come from those indexes. What the merge writes is the same as before
(tests/test_merge_rows.py, tests/test_merge.py check the rows).
"""

from __future__ import annotations

from typing import Any

import psycopg

import tgsis
from tgsis.db import versions as V

Conn = psycopg.Connection[Any]


def _indexes(conn: Conn, table: str) -> list[tuple[str, str]]:
    rows = conn.execute(
        "SELECT a.amname, pg_get_indexdef(i.indexrelid) FROM pg_index i JOIN pg_class c ON c.oid = i.indexrelid"
        " JOIN pg_am a ON a.oid = c.relam WHERE i.indrelid = %s::regclass ORDER BY 2",
        (table,),
    ).fetchall()
    return [(str(r[0]), str(r[1])) for r in rows]


def _has_revision_indexes(conn: Conn, table: str, key: str) -> bool:
    found = _indexes(conn, table)
    brin = any(am == "brin" and "(revision)" in d for am, d in found)
    closed = any(am == "btree" and f"({key}) WHERE revclosed" in d for am, d in found)
    return brin and closed


def test_versioned_storage_has_the_revision_indexes_and_making_them_again_adds_none(conn: Conn) -> None:
    conn.execute("CREATE TABLE samples (obj int, k int, v float8, PRIMARY KEY (obj, k))")
    tgsis.enable_versioning(conn, "samples", "obj", "sample")
    conn.commit()
    assert _has_revision_indexes(conn, "public.samples_ver", "obj")
    before = _indexes(conn, "public.samples_ver")
    conn.execute("SELECT tgsis.create_revision_indexes('public', 'samples', 'obj')")  # as the upgrade calls it
    assert _indexes(conn, "public.samples_ver") == before
    tgsis.disable_versioning(conn, "samples")  # the columns go, their indexes with them
    conn.commit()
    assert all("revision" not in d and "revclosed" not in d for _, d in _indexes(conn, "public.samples"))


def test_feature_storage_has_the_revision_indexes(conn: Conn) -> None:
    tgsis.create_feature_class(conn, "faults", "SURFACE", cell_properties={"throw": "double precision"})
    tgsis.enable_feature_versioning(conn)
    conn.commit()
    properties = tgsis.get_feature_class(conn, "faults").property_table("VERTEX")
    for table in ("tgsis.vrtx_ver", "tgsis.trgl_ver", "tgsis.geometry_ver", f"public.{properties}_ver"):
        assert _has_revision_indexes(conn, table, "_geoid" if table.startswith("public") else "geoid"), table


def test_a_merge_finds_the_rows_it_writes_through_the_revision_indexes(conn: Conn) -> None:
    conn.execute("CREATE TABLE samples (obj int, k int, v float8, PRIMARY KEY (obj, k))")
    conn.execute("INSERT INTO samples SELECT o, k, k FROM generate_series(1, 2) o, generate_series(1, 20000) k")
    tgsis.enable_versioning(conn, "samples", "obj", "sample")
    tgsis.create_version(conn, "e1")
    conn.commit()
    with tgsis.in_version(conn, "e1"):
        conn.execute("UPDATE samples SET v = -v WHERE obj = 1 AND k <= 10")
    with tgsis.in_version(conn, "DEFAULT"):
        conn.execute("UPDATE samples SET v = v + 0.5 WHERE obj = 2 AND k > 19990")
    conn.commit()
    conn.autocommit = True
    conn.execute("VACUUM ANALYZE samples_ver")
    conn.autocommit = False
    assert V.find_conflicts(conn, "e1") == []
    conn.commit()
    plans: list[str] = []
    conn.add_notice_handler(lambda d: plans.append(d.message_primary or ""))
    for setting in (
        "LOAD 'auto_explain'",
        "SET auto_explain.log_min_duration = 0",
        "SET auto_explain.log_nested_statements = on",
        "SET auto_explain.log_level = notice",
        "SET enable_seqscan = off",  # as on a large table: an index that serves the condition is taken
    ):
        conn.execute(setting)
    written = V.merge_version(conn, "e1")
    conn.commit()
    assert written == 20  # of object 1: 10 rows closed in the parent, 10 copied
    acting = [p for p in plans if "samples_ver v" in p and any(w in p for w in ("INSERT INTO", "UPDATE", "DELETE"))]
    assert len(acting) >= 3, plans
    for plan in acting:
        assert "Seq Scan on samples_ver v" not in plan, plan
    # the closing of the parent's rows and the copy of the child's: by revision, not by the object's rows
    for verb in ("UPDATE public.samples_ver v", "INSERT INTO public.samples_ver"):
        (plan,) = [p for p in acting if verb in p]
        # the rows written in the two sides' revisions, found by an index (the BRIN, or on a small table the
        # primary key skipping over the row keys), or-ed with the closed rows of the object
        conditions = [line for line in plan.splitlines() if "Index Cond:" in line]
        assert any("revision = ANY ('{1,2}'" in line for line in conditions), plan
        assert "Bitmap Index Scan on samples_ver_obj_idx" in plan, plan
    with tgsis.in_version(conn, "DEFAULT"):
        rows = conn.execute("SELECT obj, k, v FROM samples WHERE v < 0 OR v <> round(v) ORDER BY obj, k").fetchall()
    assert rows == [(1, k, -float(k)) for k in range(1, 11)] + [(2, k, k + 0.5) for k in range(19991, 20001)]


def test_the_conflict_check_finds_the_changed_rows_through_the_revision_indexes(conn: Conn) -> None:
    conn.execute("CREATE TABLE samples (obj int, k int, v float8, PRIMARY KEY (obj, k))")
    conn.execute("INSERT INTO samples SELECT 1, k, k FROM generate_series(1, 20000) k")
    tgsis.enable_versioning(conn, "samples", "obj", "sample")
    tgsis.create_version(conn, "e1")
    conn.commit()
    with tgsis.in_version(conn, "e1"):
        conn.execute("UPDATE samples SET v = -v WHERE obj = 1 AND k <= 10")
    with tgsis.in_version(conn, "DEFAULT"):
        conn.execute("UPDATE samples SET v = v + 0.5 WHERE obj = 1 AND k > 19990")
    conn.commit()
    conn.autocommit = True
    conn.execute("VACUUM ANALYZE samples_ver")
    conn.autocommit = False
    plans: list[str] = []
    conn.add_notice_handler(lambda d: plans.append(d.message_primary or ""))
    for setting in (
        "LOAD 'auto_explain'",
        "SET auto_explain.log_min_duration = 0",
        "SET auto_explain.log_nested_statements = on",
        "SET auto_explain.log_level = notice",
        "SET enable_seqscan = off",
    ):
        conn.execute(setting)
    (conflict,) = V.find_conflicts(conn, "e1")
    conn.commit()
    assert conflict.objectkey == "1"
    reads = [p for p in plans if "md5(string_agg" in p and "samples_ver v" in p]
    assert reads, plans
    for plan in reads:  # each side's changed rows: written in its revisions (by index), or closed (the partial index)
        assert "Seq Scan on samples_ver v" not in plan, plan
        assert "Bitmap Index Scan on samples_ver_obj_idx" in plan, plan


def test_what_a_solution_discards_is_read_through_the_revision_indexes(conn: Conn) -> None:
    conn.execute("CREATE TABLE samples (obj int, k int, v float8, PRIMARY KEY (obj, k))")
    conn.execute("INSERT INTO samples SELECT 1, k, k FROM generate_series(1, 20000) k")
    tgsis.enable_versioning(conn, "samples", "obj", "sample")
    tgsis.create_version(conn, "e1")
    conn.commit()
    with tgsis.in_version(conn, "e1"):
        conn.execute("UPDATE samples SET v = -v WHERE obj = 1 AND k <= 10")
    with tgsis.in_version(conn, "DEFAULT"):
        conn.execute("UPDATE samples SET v = v + 0.5 WHERE obj = 1 AND k > 19990")
        conn.execute("DELETE FROM samples WHERE obj = 1 AND k = 5000")
    conn.commit()
    conn.autocommit = True
    conn.execute("VACUUM ANALYZE samples_ver")
    conn.autocommit = False
    plans: list[str] = []
    conn.add_notice_handler(lambda d: plans.append(d.message_primary or ""))
    for setting in (
        "LOAD 'auto_explain'",
        "SET auto_explain.log_min_duration = 0",
        "SET auto_explain.log_nested_statements = on",
        "SET auto_explain.log_level = notice",
        "SET enable_seqscan = off",
    ):
        conn.execute(setting)
    rows = conn.execute(
        "SELECT solution, discarded, rows_added, rows_removed, rows_changed FROM tgsis.conflict_discards('e1') WHERE solution <> 'base'"
        " ORDER BY solution"
    ).fetchall()
    conn.commit()
    assert rows == [("child", "parent", 0, 1, 10), ("parent", "child", 0, 0, 10)]
    reads = [p for p in plans if "WITH seen AS" in p and "samples_ver v" in p]
    assert reads, plans
    for plan in reads:  # the rows not all three sets see alike: written or closed in a revision not in all three
        assert "Seq Scan on samples_ver v" not in plan, plan
        assert "Bitmap Index Scan on samples_ver_obj_idx" in plan, plan
