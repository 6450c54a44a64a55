"""NaN (and infinite) coordinates against the GiST indexes over boxes: the answer must not hang on the plan (plan N, N1).

docs/storage.md, "NaN coordinates and the box indexes". The cube type orders NaN as no float: a key with a NaN
coordinate in a GiST index spoils its inner boxes (their union is taken by < and >, which NaN fails both ways), so
an index scan misses valid keys a sequential scan finds. Each box query is run with the index forced and with a
sequential scan forced; both must give the same answer, which is the contract's (a NaN point is in no box).
"""

from __future__ import annotations

from typing import Any

import psycopg

from tests.storage_data import tables_as_rows

Conn = psycopg.Connection[Any]

INDEX = ("SET enable_seqscan = off; SET jit = off", "SET enable_bitmapscan = on; SET jit = off")
BITMAP = ("SET enable_seqscan = off; SET jit = off", "SET enable_indexscan = off; SET jit = off")
SCAN = ("SET enable_indexscan = off; SET jit = off", "SET enable_bitmapscan = off; SET jit = off")
PLANS = {"index": INDEX, "bitmap": BITMAP, "scan": SCAN}


def _planned(conn: Conn, plan: tuple[str, ...], query: str, params: tuple[Any, ...]) -> list[tuple[Any, ...]]:
    conn.execute("DISCARD PLANS")  # a function's cached plan is made again under these settings
    for setting in plan:
        conn.execute(setting)
    try:
        with conn.cursor(binary=True) as cursor:
            return cursor.execute(query, params).fetchall()
    finally:
        conn.execute("RESET enable_seqscan; RESET enable_indexscan; RESET enable_bitmapscan; RESET jit")


def _one(conn: Conn, query: str, params: tuple[Any, ...] = ()) -> Any:
    """The one value of a query's one row."""
    row = conn.execute(query, params).fetchone()
    assert row is not None, query
    return row[0]


def _md_object(conn: Conn, geoid: int) -> None:
    """A model-5 object of 64 x 80 grid points (x, y, knowledge), 1,024 of them of NaN z among the valid ones."""
    conn.execute(
        "INSERT INTO tgsis.md_gmap (geoid, dimension, embedding, axes) VALUES (%s, 2, 3, '{x,y,knowledge}')", (geoid,)
    )
    conn.execute(
        "INSERT INTO tgsis.md_vertex (geoid, vrtxid, coordinate)"
        " SELECT %s, i, ARRAY[i %% 64, i / 64, CASE WHEN i BETWEEN 2048 AND 3071 THEN 'NaN' ELSE (i %% 3)::double precision END]"
        "::double precision[] FROM generate_series(0, 5119) AS i",
        (geoid,),
    )
    conn.execute(
        "UPDATE tgsis.md_vertex SET coordinate = '{NaN,NaN,NaN}' WHERE geoid = %s AND vrtxid IN (5, 700, 4000)",
        (geoid,),
    )
    conn.execute("UPDATE tgsis.md_vertex SET coordinate = '{-Infinity,3,1}' WHERE geoid = %s AND vrtxid = 64", (geoid,))
    conn.execute("ANALYZE tgsis.md_vertex")


MD_BOXES: list[tuple[list[str], list[float], list[float]]] = [
    (["knowledge"], [1.0], [1.0]),
    (["x", "y"], [10.0, 30.0], [12.0, 40.0]),
    (["x", "y", "knowledge"], [0.0, 0.0, 0.0], [63.0, 79.0, 2.0]),
    (["x"], [float("-inf")], [0.0]),
    (["y"], [0.0], [1e300]),
]


def test_md_vertices_in_box_on_rows_answers_alike_by_index_and_by_scan(conn: Conn) -> None:
    tables_as_rows(conn, ("md_vertex",))
    _md_object(conn, 1)
    conn.commit()
    query = "SELECT vrtxid, array_send(coordinate) FROM tgsis.md_vertices_in_box(%s, %s, %s, %s)"
    for axes, low, high in MD_BOXES:
        answers = {name: _planned(conn, plan, query, (1, axes, low, high)) for name, plan in PLANS.items()}
        counts = {name: len(a) for name, a in answers.items()}
        assert answers["index"] == answers["scan"] == answers["bitmap"], (axes, low, high, counts)


def _index_scans(conn: Conn, index: str) -> int:
    """The scans of an index so far (its statistics, flushed now)."""
    conn.execute("SELECT pg_stat_force_next_flush()")
    conn.commit()
    conn.execute("SET stats_fetch_consistency = none")
    row = conn.execute("SELECT sum(idx_scan) FROM pg_stat_user_indexes WHERE indexrelname = %s", (index,)).fetchone()
    conn.rollback()
    return int(row[0]) if row and row[0] is not None else 0


def test_the_rows_per_point_index_leaves_nan_points_out_and_is_read(conn: Conn) -> None:
    """The index is partial (no key with a NaN coordinate) and md_vertices_in_box's query carries its predicate,
    so the index is what the forced plan reads: the test above compares an index scan with a scan."""
    tables_as_rows(conn, ("md_vertex",))
    _md_object(conn, 1)
    conn.commit()
    definition = _one(conn, "SELECT indexdef FROM pg_indexes WHERE indexname = 'md_vertex_point_idx'")
    assert definition.endswith("WHERE (NOT ('NaN'::double precision = ANY (coordinate)))"), definition
    scans = _index_scans(conn, "md_vertex_point_idx")
    query = "SELECT vrtxid FROM tgsis.md_vertices_in_box(%s, %s, %s, %s)"
    got = _planned(conn, INDEX, query, (1, ["knowledge"], [1.0], [1.0]))
    assert _index_scans(conn, "md_vertex_point_idx") > scans, "the forced plan read the index"
    assert len(got) == 1364  # knowledge 1: a third of the 4,093 points of no NaN, with -Infinity's


def test_md_vertices_in_box_on_chunks_answers_the_rows_by_every_plan(conn: Conn) -> None:
    tables_as_rows(conn, ("md_vertex",))
    _md_object(conn, 1)
    conn.commit()
    query = "SELECT vrtxid, array_send(coordinate) FROM tgsis.md_vertices_in_box(%s, %s, %s, %s)"
    rows = [_planned(conn, SCAN, query, (1, axes, low, high)) for axes, low, high in MD_BOXES]
    conn.execute("SELECT tgsis.store_in_chunks('md_vertex')")
    conn.commit()
    for (axes, low, high), want in zip(MD_BOXES, rows, strict=True):
        for name, plan in PLANS.items():
            assert _planned(conn, plan, query, (1, axes, low, high)) == want, (name, axes, low, high)
    conn.execute("SELECT tgsis.store_in_rows('md_vertex')")  # the way back makes the partial index again
    conn.commit()
    definition = _one(conn, "SELECT indexdef FROM pg_indexes WHERE indexname = 'md_vertex_point_idx'")
    assert "WHERE (NOT ('NaN'::double precision = ANY (coordinate)))" in definition, definition
    for (axes, low, high), want in zip(MD_BOXES, rows, strict=True):
        assert _planned(conn, INDEX, query, (1, axes, low, high)) == want, (axes, low, high)


#: 3-D boxes (low, high) for tgsis.geometries_in_box over the 100 x 200 grid of _geometries
GEOMETRY_BOXES = [
    ([10.0, 10.0, 0.0], [20.0, 20.0, 1.0]),
    ([0.0, 0.0, 0.0], [100.0, 200.0, 1.0]),
    ([50.0, 150.0, 0.0], [60.0, 190.0, 0.5]),
    ([float("-inf"), 0.0, 0.0], [0.0, 5.0, 1.0]),
]


def _geometries(conn: Conn) -> None:
    """20,000 geometry rows of unit boxes on a 100 x 200 grid (enough for inner pages in the GiST index); every
    7th with a NaN upper y, every 11th a NaN lower x (a vertex of NaN in the object: tgsis.static_extent's box
    holds it), one with an infinite lower x."""
    conn.execute(
        "INSERT INTO tgsis.geometry (geotype, geoname, bbox)"
        " SELECT 'SURFACE', 'g' || i, cube(ARRAY[CASE WHEN i % 11 = 0 THEN 'NaN' WHEN i = 3 THEN '-Infinity'"
        "                                          ELSE (i % 100)::double precision END, i / 100, 0]::double precision[],"
        "                                    ARRAY[i % 100 + 1, CASE WHEN i % 7 = 0 THEN 'NaN' ELSE (i / 100 + 1)::double precision END,"
        "                                          1]::double precision[])"
        "   FROM generate_series(1, 19999) AS i"
    )
    conn.execute("ANALYZE tgsis.geometry")


def test_geometries_in_box_answers_alike_by_index_and_by_scan(conn: Conn) -> None:
    """Before the bbox index was partial, a box of 10 x 10 found 375 geometries by the index, 464 by a scan."""
    _geometries(conn)
    conn.commit()
    query = "SELECT g FROM tgsis.geometries_in_box(%s, %s, %s, %s, %s, %s) AS g"
    nan = "SELECT count(*) FROM tgsis.geometry WHERE tgsis.cube_has_nan(bbox) AND geoid = ANY (%s)"
    scans = _index_scans(conn, "geometry_bbox_idx")
    for low, high in GEOMETRY_BOXES:
        answers = {name: _planned(conn, plan, query, (*low, *high)) for name, plan in PLANS.items()}
        assert answers["index"] == answers["bitmap"] == answers["scan"], (
            low,
            high,
            {n: len(a) for n, a in answers.items()},
        )
        assert answers["scan"], (low, high)
        assert conn.execute(nan, ([g for (g,) in answers["scan"]],)).fetchone() == (0,), "a NaN box is in none"
    assert _index_scans(conn, "geometry_bbox_idx") > scans, "the forced plans read the index"
    # geoid i's box is (i % 100, i // 100) + a unit square: 923 and 924 meet this one, 924 has a NaN upper y (7 | 924)
    assert _planned(conn, SCAN, query, (23.5, 9.5, 0.0, 24.5, 9.6, 1.0)) == [(923,)]
    assert conn.execute(
        "SELECT tgsis.cube_has_nan('(1, NaN),(2, 3)'), tgsis.cube_has_nan('(1, 2),(-Infinity, 3)'),"
        " tgsis.cube_has_nan('(NaN)'), tgsis.cube_has_nan(NULL)"
    ).fetchone() == (True, False, True, None)


def test_md_in_box_answers_alike_by_index_and_by_scan(conn: Conn) -> None:
    """Model 5's extents with a NaN (measured so before 0.3.0, kept where model 5 is versioned) among many: in no
    box, by the index as by a scan."""
    conn.execute("SELECT tgsis.register_feature_class('nanbox', 'GMAP', p_time_model => 'MULTIDIM', p_cell_level => 2)")
    geoids = [
        r[0]
        for r in conn.execute(
            "SELECT tgsis.new_geometry('GMAP', 'g' || i, NULL, 0, 0, p_timemodel => 'MULTIDIM')"
            " FROM generate_series(1, 5000) AS i"
        ).fetchall()
    ]
    conn.execute("INSERT INTO nanbox (_geoid) SELECT unnest(%s::bigint[])", (geoids,))
    conn.execute(
        "INSERT INTO tgsis.md_gmap (geoid, dimension, embedding, axes, extent)"
        " SELECT g, 0, 2, '{x,k}', cube(ARRAY[CASE WHEN o %% 11 = 0 THEN 'NaN' ELSE (o %% 50)::double precision END, o / 50]::double precision[],"
        "                              ARRAY[o %% 50 + 1, CASE WHEN o %% 7 = 0 THEN 'NaN' ELSE (o / 50 + 1)::double precision END]::double precision[])"
        "   FROM unnest(%s::bigint[]) WITH ORDINALITY AS u(g, o)",
        (geoids,),
    )
    conn.execute("ANALYZE tgsis.md_gmap")
    conn.commit()
    query = "SELECT g FROM tgsis.md_in_box('nanbox', %s, %s, %s) AS g"
    for axes, low, high in [(["x", "k"], [10.0, 10.0], [20.0, 20.0]), (["k"], [50.0], [80.0]), (["x"], [0.0], [3.0])]:
        answers = {name: _planned(conn, plan, query, (axes, low, high)) for name, plan in PLANS.items()}
        assert answers["index"] == answers["bitmap"] == answers["scan"], (axes, {n: len(a) for n, a in answers.items()})
        assert answers["scan"], axes


def test_a_model_1_object_with_a_nan_vertex_has_the_same_box_on_either_storage_and_is_in_no_box(conn: Conn) -> None:
    """tgsis.static_extent measures the box through the rows or the chunks (tgsis.chunk_object_extent) alike: a NaN
    coordinate makes the greatest x NaN (float8's order puts NaN last); such a box is in no box query, by any plan."""
    geoid = _one(conn, "SELECT tgsis.new_geometry('SURFACE', 'nan', NULL, 3, 1)")
    conn.execute(
        "INSERT INTO tgsis.vrtx (geoid, vrtxid, x, y, z) VALUES (%s, 0, 0, 0, 0), (%s, 1, 'NaN', 1, 1), (%s, 2, 1, 0, 1)",
        (geoid, geoid, geoid),
    )
    conn.execute("INSERT INTO tgsis.trgl (geoid, trglid, vrtxid1, vrtxid2, vrtxid3) VALUES (%s, 0, 0, 1, 2)", (geoid,))
    box = _one(conn, "SELECT bbox::text FROM tgsis.refresh_geometry(%s)", (geoid,))
    assert box == "(0, 0, 0),(NaN, 1, 1)"
    assert conn.execute(
        "SELECT tgsis.cube_has_nan(bbox) FROM tgsis.geometry WHERE geoid = %s", (geoid,)
    ).fetchone() == (True,)
    query = "SELECT g FROM tgsis.geometries_in_box(-10, -10, -10, 10, 10, 10) AS g"
    assert [_planned(conn, plan, query, ()) for plan in PLANS.values()] == [[], [], []]
