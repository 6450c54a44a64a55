"""Snapshot at t of a model-3 surface (one topology period) with d4dvrtx/d4dtrgl in chunks vs the static download.

A side x side grid (1000: 1M nodes, 1,996,002 triangles) known at 2 geometry
instants of one topology period (``EvolvingSurface``: the nodes move, the
triangles stay), and a static model-1 surface of the same size (in chunks, the
default). Timed in one process and database (medians, in turn):

1. model 3's tables as rows (the default): the upload (``insert_evolving``)
   and ``get_at`` at an instant and between the two, against the static
   download (``fetch_feature``);
2. then ``tgsis.store_in_chunks('d4dtrgl')``, ``'d4dvrtx'``: the upload by the
   client (the period's chunks encoded by numpy, one COPY per table:
   ``tgsis.db._chunk_transfer.upload_instants``), ``get_at`` reading the chunks
   and interpolating on aligned arrays in numpy
   (``tgsis.db._temporal_common.evolving_vertices`` / ``evolving_triangles``)
   and, as before them, through the faces (the server decodes the chunks into
   rows, ``tgsis.vertices_at``), switched in this process by replacing those
   functions; each against the static download in the same run.

The SQL snapshot too (what psql users read: every row of
``SELECT * FROM tgsis.vertices_at(geoid, t)`` fetched in binary), against
``tgsis.vertices_at`` of the static surface (its ``vrtx`` face) in the same
run: on rows; on chunks, where ``vertices_at`` between two instants
interpolates the aligned chunk arrays (``tgsis.d4dvrtx_arrays``,
``tgsis.evolving_chunk_vertices``; at an instant it reads the face), and, as
before it, the join of two instants of the face (``FACE_JOIN``, the rows'
branch of ``vertices_at``, run as text). Their answers are compared bit for bit
first.

Every snapshot is checked against the surface first (bit for bit: same_as).

    python bench/snapshot_evolving.py [--side 1000] [--repeat 3] [--no-faces-upload]   # TGSIS_PG=system|embedded
"""

from __future__ import annotations

import argparse
import contextlib
import time
from collections.abc import Callable, Iterator
from typing import Any
from unittest import mock

import numpy as np
import psycopg
from timing import bench_database, paired
from transfer import grid_surface

import tgsis
from tgsis.temporal import EvolvingSurface, TopologyPeriod

Conn = psycopg.Connection[Any]


#: model 3's branch of tgsis.vertices_at before the arrays (and on rows): two instants of the face joined on nodeid
FACE_JOIN = """
    WITH f AS MATERIALIZED (SELECT * FROM tgsis.evolving_frame(%(g)s, %(t)s))
    SELECT a.nodeid, a.x + (SELECT f.w FROM f) * (b.x - a.x), a.y + (SELECT f.w FROM f) * (b.y - a.y),
           a.z + (SELECT f.w FROM f) * (b.z - a.z)
      FROM tgsis.d4dvrtx a
      JOIN tgsis.d4dvrtx b ON b.nodeid = a.nodeid
     WHERE a.geoid = %(g)s AND a.timem = (SELECT f.timem FROM f) AND a.timet = (SELECT f.t0 FROM f)
       AND b.geoid = %(g)s AND b.timem = (SELECT f.timem FROM f) AND b.timet = (SELECT f.t1 FROM f)
       AND (SELECT f.t0 < f.t1 FROM f)
    UNION ALL
    SELECT a.nodeid, a.x, a.y, a.z
      FROM tgsis.d4dvrtx a
     WHERE a.geoid = %(g)s AND a.timem = (SELECT f.timem FROM f) AND a.timet = (SELECT f.t0 FROM f)
       AND (SELECT f.t0 = f.t1 FROM f)
"""
VERTICES_AT = "SELECT * FROM tgsis.vertices_at(%(g)s, %(t)s)"


@contextlib.contextmanager
def through_faces() -> Iterator[None]:
    """Model 3's paths as before the client transferred its chunks: reads through the faces, uploads through
    ``tgsis.insert_chunk_rows``."""
    with (
        mock.patch("tgsis.db._temporal_common.evolving_vertices", return_value=None),
        mock.patch("tgsis.db._temporal_common.evolving_triangles", return_value=None),
        mock.patch("tgsis.db._chunk_transfer.upload_instants", return_value=False),
    ):
        yield


def once(action: Callable[[], object]) -> float:
    start = time.perf_counter()
    action()
    return time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--side", type=int, default=1000)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument(
        "--no-faces-upload",
        dest="faces_upload",
        action="store_false",
        help="skip the upload through tgsis.insert_chunk_rows (minutes at 1M nodes); the reads are measured",
    )
    args = parser.parse_args()

    grid = grid_surface(args.side)
    static = tgsis.Surface(grid.vertices, grid.cells, name="static bench")
    positions = np.stack([grid.vertices * np.array([1.0, 1.0, 1.0 + 0.1 * k]) for k in range(2)])
    surface = EvolvingSurface([TopologyPeriod(np.asarray([0.0, 1.0]), grid.cells, positions)], name="evolving bench")
    expected = {
        0.0: tgsis.Surface(positions[0], grid.cells),
        0.5: tgsis.Surface(positions[0] + 0.5 * (positions[1] - positions[0]), grid.cells),
        1.0: tgsis.Surface(positions[1], grid.cells),
    }
    print(f"surface: {static.n_vertices} vertices, {static.n_cells} triangles; evolving: 2 geometry instants of it")
    with bench_database() as conn:
        tgsis.create_feature_class(conn, "static_grid", "SURFACE")
        tgsis.create_feature_class(conn, "evolving_grid", "SURFACE", time_model="EVOLVING")
        conn.commit()
        ids: dict[str, int] = {}

        def upload(key: str, cls: str, value: Any) -> None:
            ids[key] = tgsis.insert_feature(conn, cls, value)
            conn.commit()

        def vacuum() -> None:
            conn.autocommit = True
            for table in ("vrtx_chunk", "trgl_chunk", "d4dvrtx", "d4dtrgl", "timet", "timem", "node", "geometry"):
                if conn.execute("SELECT to_regclass(%s)", (f"tgsis.{table}",)).fetchone() != (None,):
                    conn.execute(f"VACUUM ANALYZE tgsis.{table}")
            conn.autocommit = False

        def check(key: str) -> None:
            for t, shape in expected.items():
                for path in (contextlib.nullcontext(), through_faces()):
                    with path:
                        got = tgsis.get_at(conn, ids[key], t)
                    assert got is not None and got.same_as(shape), (key, t)
            conn.commit()

        def snapshot(key: str, t: float, faces: bool) -> Callable[[], object]:
            def run() -> None:
                with through_faces() if faces else contextlib.nullcontext():
                    tgsis.get_at(conn, ids[key], t)
                conn.commit()

            return run

        def sql_rows(key: str, t: float, query: str) -> list[Any]:
            with conn.cursor(binary=True) as cursor:
                rows = cursor.execute(query, {"g": ids[key], "t": t}).fetchall()
            conn.commit()
            return rows

        def sql(key: str, t: float, query: str = VERTICES_AT) -> Callable[[], object]:
            return lambda: sql_rows(key, t, query)

        def sql_check(key: str, faces: bool) -> None:
            for t in expected:
                got = sorted(sql_rows(key, t, VERTICES_AT))
                assert len(got) == static.n_vertices, (key, t)
                if faces:
                    assert got == sorted(sql_rows(key, t, FACE_JOIN)), (key, t)  # bit for bit: the doubles' bytes

        def static_down() -> None:
            tgsis.fetch_feature(conn, "static_grid", ids["static"])
            conn.commit()

        up_static = once(lambda: upload("static", "static_grid", static))
        up_rows = once(lambda: upload("rows", "evolving_grid", surface))
        vacuum()
        check("rows")
        sql_check("rows", True)
        rows_answers = {t: sorted(sql_rows("rows", t, VERTICES_AT)) for t in expected}
        static_rows, at_rows, mid_rows, sql_static_rows, sql_at_rows, sql_mid_rows = paired(
            [
                static_down,
                snapshot("rows", 1.0, False),
                snapshot("rows", 0.5, False),
                sql("static", 0.5),
                sql("rows", 1.0),
                sql("rows", 0.5),
            ],
            args.repeat,
        )

        conn.execute("SELECT tgsis.store_in_chunks('d4dtrgl'), tgsis.store_in_chunks('d4dvrtx')")
        conn.commit()
        up_chunks = once(lambda: upload("chunks", "evolving_grid", surface))
        up_faces = float("nan")
        if args.faces_upload:
            with through_faces():
                up_faces = once(lambda: upload("faces", "evolving_grid", surface))
        vacuum()
        for key in ids.keys() - {"static"}:  # the figures are of correct snapshots, and every upload stored the same
            check(key)
            sql_check(key, True)
            assert {t: sorted(sql_rows(key, t, VERTICES_AT)) for t in expected} == rows_answers, key
        (
            static_chunks,
            at_chunks,
            mid_chunks,
            at_faces,
            mid_faces,
            sql_static_chunks,
            sql_at_chunks,
            sql_mid_chunks,
            sql_at_faces,
            sql_mid_faces,
        ) = paired(
            [
                static_down,
                snapshot("chunks", 1.0, False),
                snapshot("chunks", 0.5, False),
                snapshot("chunks", 1.0, True),
                snapshot("chunks", 0.5, True),
                sql("static", 0.5),
                sql("chunks", 1.0),
                sql("chunks", 0.5),
                sql("chunks", 1.0, FACE_JOIN),
                sql("chunks", 0.5, FACE_JOIN),
            ],
            args.repeat,
        )

    print(f"upload, static surface (insert_feature):             {up_static:6.2f} s")
    print(f"upload, evolving (2 instants), rows:                 {up_rows:6.2f} s  ({up_rows / up_static:.2f}x static)")
    print(
        f"upload, evolving (2 instants), client chunks:        {up_chunks:6.2f} s  ({up_chunks / up_static:.2f}x "
        f"static, {up_chunks / up_rows:.2f}x rows)"
    )
    print(
        f"upload, evolving (2 instants), insert_chunk_rows:    {up_faces:6.2f} s  ({up_faces / up_static:.2f}x static)"
    )
    print(f"download, static surface (fetch_feature), run 1 / 2: {static_rows:6.2f} s / {static_chunks:6.2f} s")
    for name, value, base in (
        ("get_at at an instant, rows", at_rows, static_rows),
        ("get_at between instants, rows", mid_rows, static_rows),
        ("get_at at an instant, client chunks", at_chunks, static_chunks),
        ("get_at between instants, client chunks", mid_chunks, static_chunks),
        ("get_at at an instant, chunks via faces", at_faces, static_chunks),
        ("get_at between instants, chunks via faces", mid_faces, static_chunks),
    ):
        print(f"{name:42s} {value:6.2f} s ({value / base:.2f}x static)")
    print(f"SQL: vertices_at of the static surface, run 1 / 2:   {sql_static_rows:6.2f} s / {sql_static_chunks:6.2f} s")
    for name, value, base in (
        ("SQL vertices_at at an instant, rows", sql_at_rows, sql_static_rows),
        ("SQL vertices_at between instants, rows", sql_mid_rows, sql_static_rows),
        ("SQL vertices_at at an instant, chunks", sql_at_chunks, sql_static_chunks),
        ("SQL vertices_at between instants, arrays", sql_mid_chunks, sql_static_chunks),
        ("SQL at an instant, face join", sql_at_faces, sql_static_chunks),
        ("SQL between instants, face join", sql_mid_faces, sql_static_chunks),
    ):
        print(f"{name:42s} {value:6.2f} s ({value / base:.2f}x static SQL)")
    print(f"sql_between_arrays_vs_face_join: {sql_mid_chunks / sql_mid_faces:.2f}")
    print(f"sql_instant_chunks_vs_face_join: {sql_at_chunks / sql_at_faces:.2f}")
    print(f"static_download_s: {static_chunks:.3f}")
    print(f"snapshot_instant_rows_vs_static: {at_rows / static_rows:.2f}")
    print(f"snapshot_between_rows_vs_static: {mid_rows / static_rows:.2f}")
    print(f"snapshot_instant_chunks_vs_static: {at_chunks / static_chunks:.2f}")
    print(f"snapshot_between_chunks_vs_static: {mid_chunks / static_chunks:.2f}")
    print(f"snapshot_instant_faces_vs_static: {at_faces / static_chunks:.2f}")
    print(f"snapshot_between_faces_vs_static: {mid_faces / static_chunks:.2f}")
    print(f"static_upload_s: {up_static:.3f}")
    print(f"evolving_upload_rows_vs_static: {up_rows / up_static:.2f}")
    print(f"evolving_upload_chunks_vs_static: {up_chunks / up_static:.2f}")
    print(f"evolving_upload_chunks_vs_rows: {up_chunks / up_rows:.2f}")
    print(f"evolving_upload_faces_vs_static: {up_faces / up_static:.2f}")


if __name__ == "__main__":
    main()
