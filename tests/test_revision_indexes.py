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

import re
from typing import Any

import numpy as np
import psycopg
import pytest

import tgsis
from tests.storage_data import in_chunks, storage_of
from tests.test_sql_merge_regions import assert_same_regions
from tgsis.db import _merge_states, regions
from tgsis.db import features as F
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
    assert properties is not None
    # the storage of each: <t>_ver, or its chunk table (a model table's, or a class's property table in chunks by
    # default: its chunk versions carry revision, revclosed)
    for schema, table in (("tgsis", "vrtx"), ("tgsis", "trgl"), ("tgsis", "geometry"), ("public", properties)):
        storage = storage_of(conn, table, schema)
        chunked = bool(conn.execute("SELECT tgsis.stored_in_chunks(%s, %s)", (schema, table)).fetchone()[0])  # type: ignore[index]
        assert storage.endswith("_chunk" if chunked else "_ver"), storage
        assert _has_revision_indexes(conn, storage, "_geoid" if schema == "public" else "geoid"), storage


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
        "SET enable_seqscan = off; SET jit = off",  # as on a large table: an index that serves the condition is taken
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
        "SET enable_seqscan = off; SET jit = off",
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
        "SET enable_seqscan = off; SET jit = off",
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


# --------------------------------------------------------------------------- the cells on given vertices (issue 39)


def test_cell_storage_has_a_brin_on_its_vertex_columns_and_making_it_again_adds_none(conn: Conn) -> None:
    for name, geotype in (
        ("wells", "MULTIPOINT"),
        ("traces", "MULTILINESTRING"),
        ("faults", "SURFACE"),
        ("bodies", "MULTITETRA"),
    ):
        tgsis.create_feature_class(conn, name, geotype)
    tgsis.enable_feature_versioning(conn)
    conn.commit()
    chunked = in_chunks(conn, "trgl")
    for table, k in (("point", 1), ("segment", 2), ("trgl", 3), ("tetra", 4)):
        columns = ", ".join(f"vrtxid{i + 1}" for i in range(k))
        storage = storage_of(conn, table)
        found = [d for am, d in _indexes(conn, storage) if am == "brin" and f"(geoid, {columns})" in d]
        # in chunks the vertex ids are inside arrays: no vertex BRIN (tgsis.create_revision_indexes); the cells
        # on given vertices are read from the object's chunks by the chunk table's key (_reads_the_ring)
        assert len(found) == (0 if chunked else 1), _indexes(conn, storage)
        before = _indexes(conn, storage)
        conn.execute("SELECT tgsis.create_revision_indexes('tgsis', %s, 'geoid')", (table,))  # as the upgrade calls it
        assert _indexes(conn, storage) == before
    # the triangles of models 2 and 3 get theirs by instant or topology period (ids repeat in each); the
    # vertices' storage gets none
    # (stored in chunks, model 2's by default: no vertex BRIN, as model 1's chunks have none)
    for name, columns in (
        ("times_trgl", "(geoid, times, vrtxid1, vrtxid2, vrtxid3)"),
        ("d4dtrgl", "(geoid, timem, nodeid1, nodeid2, nodeid3)"),
    ):
        table = storage_of(conn, name)
        found = [d for am, d in _indexes(conn, table) if am == "brin" and columns in d]
        assert len(found) == (0 if in_chunks(conn, name) else 1), _indexes(conn, table)
    assert not any("vrtxid1" in d for am, d in _indexes(conn, storage_of(conn, "vrtx")) if am == "brin")
    tgsis.disable_feature_versioning(conn)  # what versioning made goes
    conn.commit()
    for table in ("point", "segment", "trgl", "tetra"):
        # (a chunk table keeps the revision BRIN it was made with, versioned or not: tgsis.create_chunk_table)
        left = [d for am, d in _indexes(conn, storage_of(conn, table)) if am == "brin" and "(revision)" not in d]
        assert left == [] and storage_of(conn, table).endswith("_chunk" if chunked else f".{table}"), table


def _plans_of(conn: Conn, action: Any) -> list[str]:
    """The plans of every statement ``action`` runs, nested ones too (auto_explain at WARNING: the region
    functions pin client_min_messages), sequential scans made costly as on a large table."""
    plans: list[str] = []
    conn.add_notice_handler(lambda d: plans.append(d.message_primary or ""))
    for setting in (
        "LOAD 'auto_explain'",
        "SET auto_explain.log_min_duration = 0",
        "SET auto_explain.log_nested_statements = on",
        "SET auto_explain.log_level = warning",
        "SET enable_seqscan = off; SET jit = off",
    ):
        conn.execute(setting)
    try:
        action()
    finally:
        conn.rollback()
        conn.execute("RESET ALL")
    return plans


@pytest.fixture
def two_edits(conn: Conn) -> int:
    """A 300 x 300 grid surface whose parent moves a patch near one corner and whose version e1 one near the other.

    Large enough for its triangles to fill many of a BRIN's page ranges (128 pages): on a table of one range
    the planner rightly takes any index.
    """
    side = 300
    u, v = np.meshgrid(np.linspace(0.0, 29900.0, side), np.linspace(0.0, 29900.0, side))
    vertices = np.stack([u.ravel(), v.ravel(), 20.0 * np.sin(u.ravel() / 700.0)], axis=1)
    idx = np.arange(side * side).reshape(side, side)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel()
    surface = tgsis.Surface(vertices, np.concatenate([np.stack([a, b, d], 1), np.stack([a, d, c], 1)]))
    tgsis.create_feature_class(conn, "faults", "SURFACE")
    tgsis.enable_feature_versioning(conn)
    geoid = F.insert_feature(conn, "faults", surface)
    tgsis.create_version(conn, "e1")
    conn.commit()
    for version, ids, dz in (("DEFAULT", idx[3:8, 3:9], 5.0), ("e1", idx[290:296, 289:295], -3.0)):
        with tgsis.in_version(conn, version):
            conn.execute(
                "UPDATE tgsis.vrtx SET z = z + %s WHERE geoid = %s AND vrtxid = ANY(%s)",
                (dz, geoid, [int(i) for i in ids.ravel()]),
            )
        conn.commit()
    _vacuum_model_storage(conn)
    return geoid


def _vacuum_model_storage(conn: Conn) -> None:
    """VACUUM ANALYZE the storage of tgsis.trgl and tgsis.vrtx (rows or chunks), as on a table in use."""
    storages = f"{storage_of(conn, 'trgl')}, {storage_of(conn, 'vrtx')}"
    conn.commit()
    conn.autocommit = True
    conn.execute(f"VACUUM ANALYZE {storages}")
    conn.autocommit = False


def _cells(conn: Conn) -> str:
    """How the plans name the triangles' storage read: ``trgl_ver v`` (rows) or ``trgl_chunk`` (chunks)."""
    return "trgl_chunk" if in_chunks(conn, "trgl") else "trgl_ver v"


def _reads_the_ring(conn: Conn, plan: str) -> None:
    """The cells on the changed vertices: on rows through the vertex BRIN by spans of ids; on chunks (no vertex
    BRIN: the ids are inside arrays, tgsis.create_revision_indexes) from the object's cell chunks alone, found
    by the chunk table's key, never a scan of the storage."""
    if not in_chunks(conn, "trgl"):
        _reads_the_ring_by_spans(plan)
        return
    assert "Seq Scan on trgl_chunk" not in plan, plan
    assert re.search(r"Index Scan (on|using) trgl_chunk_pkey", plan), plan
    # the object's key (PostgreSQL 18 adds the revisions to the condition: "((geoid = ...) AND (revision = ...))")
    assert re.search(r"Index Cond: \(\(?geoid = ", plan), plan


def _reads_the_ring_by_spans(plan: str) -> None:
    """The cells on the changed vertices come from the vertex BRIN searched by spans of ids, not value by value."""
    assert "Seq Scan on trgl_ver" not in plan, plan
    assert re.search(r"Bitmap Index Scan on trgl_ver_geoid_vrtxid1_vrtxid2_vrtxid3_idx", plan), plan
    conditions = [line for line in plan.splitlines() if "Index Cond:" in line and "vrtxid" in line]
    assert conditions and not any("ANY" in line for line in conditions), plan  # each search one span
    assert not any("Join Filter:" in line and "ANY" in line for line in plan.splitlines()), plan


def test_sql_region_detection_reads_the_cells_on_changed_vertices_by_spans_of_the_vertex_brin(
    conn: Conn, two_edits: int
) -> None:
    found: list[Any] = []
    plans = _plans_of(
        conn,
        lambda: found.extend(
            conn.execute(
                "SELECT region, changed_by, cardinality(vertex_ids) FROM tgsis.mesh_merge_regions('e1', %s)",
                (two_edits,),
            ).fetchall()
        ),
    )
    assert found == [(0, "parent", 30), (1, "child", 36)]
    (ring,) = [
        p for p in plans if "INSERT INTO pg_temp.tgsis_mr_margin" in p.split("Query Text:", 1)[-1].split("\n\n")[0]
    ]
    _reads_the_ring(conn, ring)
    assert_same_regions(conn, "e1", two_edits)  # what it finds is merge3's


def test_the_python_merge_read_takes_the_cells_on_changed_vertices_by_spans_of_the_vertex_brin(
    conn: Conn, two_edits: int
) -> None:
    read: list[Any] = []
    plans = _plans_of(conn, lambda: read.append(_merge_states.read_merge_change(conn, "e1", two_edits)))
    assert read[0] is not None
    # the statement that finds the cells on given vertices (the others find cells by id)
    on_vertices = [p for p in plans if _cells(conn) in p and re.search(r'vrtxid2"?( \+ 0\))? = ANY', p)]
    assert len(on_vertices) == 1, plans
    _reads_the_ring(conn, on_vertices[0])


def test_scattered_edits_found_through_the_vertex_brin_give_merge3s_regions_in_sql_and_in_python(
    conn: Conn, two_edits: int
) -> None:
    """Shape changes all over the mesh (many gaps between their ids, more than spans): the spans cover them all,
    the exact test keeps only theirs; SQL and the Python read of the change give the regions of the whole states."""
    rng = np.random.default_rng(39)
    ids = rng.choice(np.arange(300 * 300), size=120, replace=False)
    for version, moved, dz in (("DEFAULT", ids[:60], 1.5), ("e1", ids[60:], -2.5)):
        with tgsis.in_version(conn, version):
            conn.execute(
                "UPDATE tgsis.vrtx SET z = z + %s WHERE geoid = %s AND vrtxid = ANY(%s)",
                (dz, two_edits, [int(i) for i in moved]),
            )
        conn.commit()
    with tgsis.in_version(conn, "e1"):  # and a vertex removed with its cells: a shape change of another kind
        conn.execute(
            "DELETE FROM tgsis.trgl WHERE geoid = %s AND %s IN (vrtxid1, vrtxid2, vrtxid3)", (two_edits, 45150)
        )
        conn.execute("DELETE FROM tgsis.vrtx WHERE geoid = %s AND vrtxid = %s", (two_edits, 45150))
    conn.commit()
    conn.execute("SET enable_seqscan = off; SET jit = off")  # the index is taken, as on a large table
    whole = {tuple(r["vertex_ids"]) for r in assert_same_regions(conn, "e1", two_edits)}
    assert len(whole) > 100
    conn.execute("SET enable_seqscan = off; SET jit = off")
    [conflict] = regions.find_conflicts(conn, "e1")  # Python, through read_merge_change
    conn.rollback()
    assert {tuple(int(i) for i in r.vertex_ids) for r in conflict.regions} == whole


@pytest.mark.parametrize(
    ("ids", "spans"),
    [
        ([5], [(5, 5)]),
        (list(range(100)), [(0, 99)]),
        ([1, 2, 3, 10, 11, 50, 51, 52, 1000], [(1, 3), (10, 11), (50, 52), (1000, 1000)]),
        ([1, 3, 5, 7, 9, 11, 13, 15], [(1, 1), (3, 3), (5, 5), (7, 15)]),  # ties: the first gaps cut
        ([-7, 0, 2**62, 2**62 + 1], [(-7, -7), (0, 0), (2**62, 2**62 + 1)]),
    ],
)
def test_the_spans_of_ids_cover_them_cut_at_the_widest_gaps(ids: list[int], spans: list[tuple[int, int]]) -> None:
    assert _merge_states._id_spans(np.asarray(ids, dtype=np.int64)) == spans


def test_the_sql_condition_of_cells_on_vertices_cuts_the_spans_as_the_python_reader(conn: Conn) -> None:
    rng = np.random.default_rng(7)
    for ids in ([5], [1, 2, 3, 10, 11, 50, 51, 52, 1000], rng.choice(10**6, size=300, replace=False).tolist()):
        (text,) = conn.execute("SELECT tgsis.cells_on_vertices_sql(3, %s, '$3')", (ids,)).fetchone()  # type: ignore[misc]
        spans = sorted(
            (int(lo), int(hi)) for lo, hi in set(re.findall(r"v\.vrtxid1 BETWEEN '(-?\d+)' AND '(-?\d+)'", text))
        )
        assert spans == _merge_states._id_spans(np.unique(np.asarray(ids, dtype=np.int64))), text
        assert text.count("BETWEEN") == 3 * len(spans)
        assert "(v.vrtxid3 + 0) = ANY ($3)" in text and "vrtxid4" not in text
    assert conn.execute("SELECT tgsis.cells_on_vertices_sql(2, '{}', '$3')").fetchone() == ("false",)
    for bad in ("'$3; DROP TABLE x'", "'3'"):
        with pytest.raises(psycopg.errors.InvalidParameterValue):
            conn.execute(f"SELECT tgsis.cells_on_vertices_sql(3, '{{1}}', {bad})")
        conn.rollback()


def test_the_spans_of_ids_at_both_ends_of_bigint_are_cut_without_overflow(conn: Conn) -> None:
    """Vertex ids are any bigint (a psql user writes them): a gap wider than bigint between two ids is a gap
    like any other, not a 22003 from the gap's subtraction."""
    ids = [-(2**63), -(2**63) + 1, 5, 2**63 - 1]  # gaps 1, 2^63 + 4, 2^63 - 6
    (text,) = conn.execute("SELECT tgsis.cells_on_vertices_sql(3, %s, '$3')", (ids,)).fetchone()  # type: ignore[misc]
    spans = sorted(
        (int(lo), int(hi)) for lo, hi in set(re.findall(r"v\.vrtxid1 BETWEEN '(-?\d+)' AND '(-?\d+)'", text))
    )
    assert spans == [(-(2**63), -(2**63) + 1), (5, 5), (2**63 - 1, 2**63 - 1)]
    # the Python reader cuts them the same way (its differences of int64 must not wrap)
    assert _merge_states._id_spans(np.asarray(ids, dtype=np.int64)) == spans


@pytest.mark.parametrize(
    "low",
    [
        # negative vertex ids cannot be stored in chunks, by design (docs/storage.md, "What differs from rows")
        pytest.param(-(2**63) + 5, marks=pytest.mark.storage("rows"), id="near-minus-2^63"),
        pytest.param(10**6, id="positive"),
    ],
)
def test_new_vertices_at_both_ends_of_bigint_give_merge3s_regions_in_sql(conn: Conn, low: int) -> None:
    """A side adds a vertex (and a triangle on it) with an id near -2^63 (rows; on any storage a positive one),
    the other one near 2^63: the SQL detection (its one-ring through the vertex BRIN, in chunks through the
    object's chunks) finds merge3's regions, as it did before the spans."""
    from tests.merge_data import make_fault
    from tests.test_sql_merge_regions import psql

    fault = make_fault(conn)
    high = 2**63 - 5
    add = "INSERT INTO tgsis.vrtx (geoid, vrtxid, x, y, z) VALUES (%s, %s, %s, %s, %s)"
    tri = "INSERT INTO tgsis.trgl (geoid, trglid, vrtxid1, vrtxid2, vrtxid3) VALUES (%s, %s, %s, %s, %s)"
    psql(conn, "e1", (add, (fault, low, 50.0, -300.0, 0.0)), (tri, (fault, 10**6, 1, 0, low)))
    psql(conn, "DEFAULT", (add, (fault, high, -500.0, 2000.0, 1.0)), (tri, (fault, 10**6 + 1, 3, 2, high)))
    found = assert_same_regions(conn, "e1", fault)
    assert {r["changed_by"] for r in found} == {"child", "parent"}


def test_partitioned_cell_storage_has_the_vertex_brin_on_every_partition_and_versioning_again_keeps_one(
    conn: Conn,
) -> None:
    """Model 1 hash-partitioned (tgsis.partition_model_storage): the vertex BRIN (in chunks: the revision BRIN)
    is made on the partitioned storage and so on each partition; disabling and enabling versioning twice leaves exactly one; the regions
    found through it are merge3's."""
    tgsis.partition_model_storage(conn, 1, 3)
    tgsis.create_feature_class(conn, "faults", "SURFACE")
    for _ in range(2):
        tgsis.enable_feature_versioning(conn)
        conn.commit()
        tgsis.disable_feature_versioning(conn)
        conn.commit()
    tgsis.enable_feature_versioning(conn)
    conn.commit()
    storage = storage_of(conn, "trgl")

    def brin(relation: str) -> list[str]:
        """Its vertex BRIN on rows; in chunks (no vertex column to index) its revision BRIN, made with the chunk
        table and partitioned with it (tgsis.create_chunk_table, partition_model_storage)."""
        wanted = "(revision)" if in_chunks(conn, "trgl") else "(geoid, vrtxid1, vrtxid2, vrtxid3)"
        return [d for am, d in _indexes(conn, relation) if am == "brin" and wanted in d]

    assert len(brin(storage)) == 1, _indexes(conn, storage)
    parts = conn.execute(
        "SELECT inhrelid::regclass::text FROM pg_inherits WHERE inhparent = %s::regclass", (storage,)
    ).fetchall()
    assert len(parts) == 3
    for (part,) in parts:
        assert len(brin(part)) == 1, (part, _indexes(conn, part))
    from tests.merge_data import curved_surface, move

    surface = curved_surface()
    geoid = F.insert_feature(conn, "faults", tgsis.Surface(surface.vertices, surface.cells))
    tgsis.create_version(conn, "e1")
    conn.commit()
    move(conn, "e1", geoid, [0, 1, 2], (0.0, 0.0, 1.0))
    move(conn, "DEFAULT", geoid, [60, 61], (0.0, 0.0, -1.0))
    conn.commit()
    conn.execute("SET enable_seqscan = off; SET jit = off")
    assert len(assert_same_regions(conn, "e1", geoid)) == 2


def test_the_sql_condition_of_cells_on_vertices_takes_nulls_and_duplicates(conn: Conn) -> None:
    """NULL ids are no ids (only NULLs: false, not the text '() AND (...)' that fails where it is run); duplicates
    are one id; a NULL column count or parameter is refused like a bad one."""
    for ids, spans in (("{NULL}", None), ("{NULL,NULL}", None), ("{7,NULL,7,7,8}", [(7, 8)])):
        (text,) = conn.execute("SELECT tgsis.cells_on_vertices_sql(2, %s::bigint[], '$3')", (ids,)).fetchone()  # type: ignore[misc]
        if spans is None:
            assert text == "false"
        else:
            assert (
                sorted(
                    (int(lo), int(hi))
                    for lo, hi in set(re.findall(r"v\.vrtxid1 BETWEEN '(-?\d+)' AND '(-?\d+)'", text))
                )
                == spans
            )
        condition = text.replace("$3", "'{7,8}'::bigint[]")
        conn.execute(f"SELECT count(*) FROM tgsis.segment v WHERE {condition}")  # it runs
    for call in ("NULL::integer, '{1}', '$3'", "3, '{1}', NULL::text"):
        with pytest.raises(psycopg.errors.InvalidParameterValue):
            conn.execute(f"SELECT tgsis.cells_on_vertices_sql({call})")
        conn.rollback()


def test_the_sql_merge_checks_validity_on_the_cells_near_the_change_by_spans_of_the_vertex_brin(
    conn: Conn, two_edits: int
) -> None:
    """The psql merge by region (tgsis.merge_mesh_validity): the cells on the vertices near what it changes come
    from the vertex BRIN by spans, on PostgreSQL 15 as on 18."""
    plans = _plans_of(conn, lambda: conn.execute("SELECT tgsis.merge_version('e1')"))
    local = [p for p in plans if "INSERT INTO pg_temp.tgsis_mw_local" in p and _cells(conn) in p]
    assert len(local) == 1, [p[:200] for p in plans]
    _reads_the_ring(conn, local[0])


def test_among_many_objects_the_ring_is_read_by_the_objects_ranges_alone(conn: Conn) -> None:
    """Vertex ids are local to their geometry (0..n-1): every object has the changed ids. With a BRIN on the
    vertex columns alone, each span matched ranges of every object and the planner ANDed the BRIN with the
    primary key's scan of all the object's cells (178,802 TIDs here); with geoid first in the BRIN, a span
    meets the object's own ranges: no scan of the object's cells by key."""
    side = 300
    u, v = np.meshgrid(np.linspace(0.0, 9900.0, side), np.linspace(0.0, 9900.0, side))
    vertices = np.stack([u.ravel(), v.ravel(), np.sin(u.ravel() / 700.0)], axis=1)
    idx = np.arange(side * side).reshape(side, side)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel()
    big = tgsis.Surface(vertices, np.concatenate([np.stack([a, b, d], 1), np.stack([a, d, c], 1)]))
    sub = idx[:150, :150]
    small = tgsis.Surface(
        vertices[: 150 * side].reshape(150, side, 3)[:, :150].reshape(-1, 3),
        np.concatenate([np.stack(p, 1) for p in _grid_triangles(150)]),
    )
    assert len(sub.ravel()) == len(small.vertices)
    tgsis.create_feature_class(conn, "faults", "SURFACE")
    tgsis.enable_feature_versioning(conn)
    for _ in range(10):
        F.insert_feature(conn, "faults", small)
    geoid = F.insert_feature(conn, "faults", big)
    for _ in range(10):
        F.insert_feature(conn, "faults", small)
    tgsis.create_version(conn, "e1")
    conn.commit()
    for version, ids, dz in (("DEFAULT", idx[16:19, 3:9], 5.0), ("e1", idx[283:286, 289:295], -3.0)):
        with tgsis.in_version(conn, version):
            conn.execute(
                "UPDATE tgsis.vrtx SET z = z + %s WHERE geoid = %s AND vrtxid = ANY(%s)",
                (dz, geoid, [int(i) for i in ids.ravel()]),
            )
        conn.commit()
    _vacuum_model_storage(conn)
    plans = _plans_of(
        conn, lambda: conn.execute("SELECT count(*) FROM tgsis.mesh_merge_regions('e1', %s)", (geoid,)).fetchall()
    )
    (ring,) = [p for p in plans if "INSERT INTO pg_temp.tgsis_mr_margin" in p]
    _reads_the_ring(conn, ring)
    assert in_chunks(conn, "trgl") or "trgl_ver_pkey" not in ring, ring
    read: list[Any] = []
    plans = _plans_of(conn, lambda: read.append(_merge_states.read_merge_change(conn, "e1", geoid)))
    on_vertices = [p for p in plans if _cells(conn) in p and re.search(r'vrtxid2"?( \+ 0\))? = ANY', p)]
    assert len(on_vertices) == 1, plans
    _reads_the_ring(conn, on_vertices[0])
    assert in_chunks(conn, "trgl") or "trgl_ver_pkey" not in on_vertices[0], on_vertices[0]
    assert_same_regions(conn, "e1", geoid)


def _grid_triangles(side: int) -> tuple[Any, Any]:
    idx = np.arange(side * side).reshape(side, side)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel()
    return (a, b, d), (a, d, c)
