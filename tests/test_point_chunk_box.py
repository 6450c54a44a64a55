"""The box of each point chunk and ``tgsis.md_vertices_in_box`` on the chunks (issue 40, plan N, B1).

docs/storage.md, "The points in chunks": a chunk table of points whose row
table answered box queries by a GiST index (``tgsis.md_vertex``) gets a GiST
index on each chunk version's box (``tgsis.point_chunk_box``, an expression
of the chunk: every writer keeps it right), and ``tgsis.md_vertices_in_box``
reads only the chunks whose box meets the query's. Its answers are the rows',
bit for bit: the rows' function (by their per-point index) on a NaN-free
object, and the rows' test by a sequential scan over the face (which equals
the rows bit for bit) with NaN points, holes, points moved and deleted
through the face, points of fewer coordinates than the object's axes, a
version's edit and its merge. Boxes whose faces are the chunks' boxes' faces.
"""

from __future__ import annotations

from typing import Any

import psycopg

import tgsis
from tests.storage_data import tables_as_rows

Conn = psycopg.Connection[Any]

AXES = ["x", "y", "knowledge"]
#: the grid: vrtxid i at (i % 64, i // 64, i % 3); a chunk (1,024 ids) is 16 rows of y, so chunk c spans y 16c .. 16c + 15
SIDE = 64
ROWS = 80
#: boxes (axes, low, high): on the faces of the chunks' boxes, between them, inside one, over one axis, everywhere
BOXES: list[tuple[list[str], list[float], list[float]]] = [
    (["y"], [15], [15]),  # the top face of chunk 0
    (["y"], [16], [16]),  # the bottom face of chunk 1
    (["y"], [15.5], [15.75]),  # between two chunks' boxes: none
    (["y"], [15], [16]),  # both faces
    (["x", "y"], [10, 30], [12, 33]),
    (["x", "y", "knowledge"], [0, 0, 1], [63, 79, 1]),
    (["knowledge"], [2], [2]),
    (["x"], [63], [63]),
    (["x", "y"], [-1e300, 79], [1e300, 1e300]),  # the last row only
    (["x", "y"], [0, 0], [0, 0]),  # -0.0 lies there
    (["y"], [100], [200]),  # beyond the object
]


def _object(conn: Conn, geoid: int, axes: list[str] = AXES, nan: bool = False) -> None:
    """A model-5 object's points written as rows: the grid, a hole, -0.0 and an infinity; with ``nan``, NaN points."""
    conn.execute(
        "INSERT INTO tgsis.md_gmap (geoid, dimension, embedding, axes) VALUES (%s, 2, %s, %s)", (geoid, len(axes), axes)
    )
    conn.execute(
        "INSERT INTO tgsis.md_vertex (geoid, vrtxid, coordinate)"
        " SELECT %s, i, ARRAY[i %% %s, i / %s, i %% 3]::double precision[] FROM generate_series(0, %s - 1) AS i"
        " WHERE i <> 1030",  # a hole in chunk 1 (at y = 16)
        (geoid, SIDE, SIDE, SIDE * ROWS),
    )
    odd: dict[int, list[object]] = {0: ["-0", 0, 0], 64: ["-Infinity", 1, 1]}
    if nan:
        odd |= {5: ["NaN", 0, 0], 1031: ["NaN", "NaN", "NaN"], 3000: [7, 46, "NaN"]}
    for vrtxid, point in odd.items():
        conn.execute(
            "UPDATE tgsis.md_vertex SET coordinate = %s::double precision[] WHERE geoid = %s AND vrtxid = %s",
            ([str(c) for c in point], geoid, vrtxid),
        )
    if nan:  # a chunk whose every point has a NaN coordinate: no box, in no box query
        conn.execute(
            "UPDATE tgsis.md_vertex SET coordinate[3] = 'NaN' WHERE geoid = %s AND vrtxid BETWEEN 4096 AND 5119",
            (geoid,),
        )


def _in_box(conn: Conn, geoid: int, axes: list[str], low: list[float], high: list[float]) -> list[tuple[Any, ...]]:
    with conn.cursor(binary=True) as cursor:
        return cursor.execute(
            "SELECT vrtxid, array_send(coordinate) FROM tgsis.md_vertices_in_box(%s, %s, %s, %s)",
            (geoid, axes, [float(v) for v in low], [float(v) for v in high]),
        ).fetchall()


def _by_face(conn: Conn, geoid: int, axes: list[str], low: list[float], high: list[float]) -> list[tuple[Any, ...]]:
    """The rows' test of tgsis.md_vertices_in_box over the face by a sequential scan: what the chunk path must answer.

    (Not the rows' GiST index: among the 1,024 NaN points of ``_object(nan=True)`` it missed valid points, PostgreSQL
    15, until it was made partial: the NaN keys spoiled its inner boxes; docs/storage.md, "NaN coordinates and the box
    indexes", tests/test_nan_boxes.py.)"""
    conn.execute("SET enable_indexscan = off; SET jit = off")
    conn.execute("SET enable_bitmapscan = off; SET jit = off")
    try:
        with conn.cursor(binary=True) as cursor:
            return cursor.execute(
                "SELECT v.vrtxid, array_send(v.coordinate) FROM tgsis.md_vertex v, tgsis.md_gmap g"
                " WHERE g.geoid = %s AND v.geoid = g.geoid AND cube(v.coordinate) <@ tgsis.md_query_box(g.axes, %s, %s, %s)"
                " AND NOT 'NaN'::double precision = ANY (v.coordinate) AND cardinality(v.coordinate) = cardinality(g.axes)"
                " ORDER BY v.vrtxid",
                (geoid, axes, [float(v) for v in low], [float(v) for v in high]),
            ).fetchall()
    finally:
        conn.execute("RESET enable_indexscan; RESET enable_bitmapscan; RESET jit")


def _all_boxes(conn: Conn, geoid: int) -> list[list[tuple[Any, ...]]]:
    answers = []
    for axes, low, high in BOXES:
        low, high = [float(v) for v in low], [float(v) for v in high]
        got = _in_box(conn, geoid, axes, low, high)
        assert got == _by_face(conn, geoid, axes, low, high), (axes, low, high)
        answers.append(got)
    conn.rollback()
    return answers


def _index_scans(conn: Conn) -> int:
    """The index scans of the box index so far (its statistics, flushed now)."""
    conn.execute("SELECT pg_stat_force_next_flush()")
    conn.commit()
    conn.execute("SET stats_fetch_consistency = none")
    row = conn.execute(
        "SELECT idx_scan FROM pg_stat_user_indexes WHERE indexrelname = 'md_vertex_chunk_coordinate_box_idx'"
    ).fetchone()
    conn.rollback()
    assert row is not None
    return int(row[0])


def test_box_queries_read_the_chunks_boxes_and_answer_as_rows(conn: Conn) -> None:
    tables_as_rows(conn, ("md_vertex",))
    _object(conn, 1)
    _object(conn, 2)  # another object over the same boxes
    conn.commit()
    before = _all_boxes(conn, 1)  # the rows' function, by their per-point index, is the scan's
    assert [len(a) for a in before][:4] == [SIDE, SIDE - 1, 0, 2 * SIDE - 1], "the grid's rows (1030 is a hole)"
    conn.execute("SELECT tgsis.store_in_chunks('md_vertex')")
    conn.commit()
    boxes = dict(
        conn.execute(
            "SELECT chunk, tgsis.point_chunk_box(coordinate)::text FROM tgsis.md_vertex_chunk WHERE geoid = 1"
        ).fetchall()
    )
    assert boxes[0] == "(-Infinity, 0, 0),(63, 15, 2)" and boxes[1] == "(0, 16, 0),(63, 31, 2)", boxes
    conn.rollback()
    scans = _index_scans(conn)
    assert _all_boxes(conn, 1) == before
    assert _index_scans(conn) > scans, "the box index was read"
    # a point moved far through the face (its chunk's box grows), a chunk's points deleted (its box none), a point
    # moved into another chunk's box
    conn.execute("UPDATE tgsis.md_vertex SET coordinate = '{500,500,1}' WHERE geoid = 1 AND vrtxid = 10")
    conn.execute("DELETE FROM tgsis.md_vertex WHERE geoid = 1 AND vrtxid BETWEEN 1024 AND 2047")
    conn.execute("UPDATE tgsis.md_vertex SET coordinate = '{3,15,0}' WHERE geoid = 1 AND vrtxid = 4100")
    conn.commit()
    far = (["x", "y"], [499.0, 499.0], [501.0, 501.0])
    assert len(_in_box(conn, 1, *far)) == 1 and _in_box(conn, 1, *far) == _by_face(conn, 1, *far)
    after = _all_boxes(conn, 1)
    assert after[1] == [] and len(after[0]) == SIDE + 1  # row 16 deleted; 4100 moved to y 15, 10 away
    # the way back: the rows' per-point index answers the same
    conn.execute("SELECT tgsis.store_in_rows('md_vertex')")
    conn.commit()
    assert _all_boxes(conn, 1) == after


def test_nan_points_are_in_no_box_and_a_chunk_of_them_has_none(conn: Conn) -> None:
    tables_as_rows(conn, ("md_vertex",))
    _object(conn, 1, nan=True)
    conn.commit()
    conn.execute("SELECT tgsis.store_in_chunks('md_vertex')")
    conn.commit()
    boxes = dict(
        conn.execute(
            "SELECT chunk, tgsis.point_chunk_box(coordinate)::text FROM tgsis.md_vertex_chunk WHERE geoid = 1"
        ).fetchall()
    )
    assert boxes[0] == "(-Infinity, 0, 0),(63, 15, 2)" and boxes[4] is None, boxes  # NaN points out, a NaN chunk none
    assert conn.execute(
        "SELECT tgsis.point_chunk_box('{{1,2},{NaN,9},{NULL,NULL},{-1,5}}')::text, tgsis.point_chunk_box('{{NaN}}'),"
        " tgsis.point_chunk_box('{1,2}')"
    ).fetchone() == ("(-1, 2),(1, 5)", None, None)
    conn.rollback()
    answers = _all_boxes(conn, 1)  # each the scan's
    assert len(answers[5]) == 1363  # knowledge 1: a third of 5,120 less the NaN chunk's, a NaN point and -Infinity


def test_points_of_fewer_coordinates_than_the_axes_are_in_no_box(conn: Conn) -> None:
    """An object whose points have fewer coordinates than its axes (tgsis.check_md_geometry reports it): the cube
    type's <@ by a scan would find them, the rows' GiST index not; in no box, as rows by both plans and as chunks."""
    tables_as_rows(conn, ("md_vertex",))
    _object(conn, 1, ["x", "y", "knowledge", "scale"])  # 3 coordinates, 4 axes
    conn.commit()
    box = (["scale"], [5.0], [6.0])
    assert _in_box(conn, 1, *box) == [] == _by_face(conn, 1, *box)
    assert _in_box(conn, 1, ["x"], [0.0], [100.0]) == []  # found by the rows' index before (scale unbounded: 0 in it)
    conn.execute("SELECT tgsis.store_in_chunks('md_vertex')")
    conn.commit()
    assert _in_box(conn, 1, *box) == [] == _by_face(conn, 1, *box)
    assert _in_box(conn, 1, ["x"], [0.0], [100.0]) == []


def test_a_version_sees_its_edit_and_the_merge_brings_it(conn: Conn) -> None:
    tables_as_rows(conn, ("md_vertex",))
    tgsis.enable_feature_versioning(conn)
    conn.commit()
    _object(conn, 1)
    conn.commit()
    conn.execute("SELECT tgsis.store_in_chunks('md_vertex')")
    conn.commit()
    assert conn.execute("SELECT to_regclass('tgsis.md_vertex_chunk_coordinate_box_idx') IS NOT NULL").fetchone() == (
        True,
    )
    scans = _index_scans(conn)
    before = _all_boxes(conn, 1)
    assert _index_scans(conn) > scans, "the box index was read"
    tgsis.create_version(conn, "e1")
    conn.commit()
    with tgsis.in_version(conn, "e1"):
        conn.execute("UPDATE tgsis.md_vertex SET coordinate = '{500,500,1}' WHERE geoid = 1 AND vrtxid = 10")
        conn.execute("DELETE FROM tgsis.md_vertex WHERE geoid = 1 AND vrtxid BETWEEN 1024 AND 1100")
    conn.commit()
    with tgsis.in_version(conn, "e1"):
        moved = _in_box(conn, 1, ["x"], [500], [500])
        assert moved == _by_face(conn, 1, ["x"], [500], [500]) and len(moved) == 1
        edited = _all_boxes(conn, 1)
    conn.rollback()
    assert edited != before
    assert _in_box(conn, 1, ["x"], [500], [500]) == []
    assert _all_boxes(conn, 1) == before
    tgsis.merge_version(conn, "e1")
    conn.commit()
    assert _all_boxes(conn, 1) == edited
    assert len(_in_box(conn, 1, ["x"], [500], [500])) == 1
