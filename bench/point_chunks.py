"""Model 5's points (``tgsis.md_vertex``) switched into chunks by tgsis itself: bytes per point and the face's scan.

The layout's own bench (``bench/point_chunk_layout.py``) measured plain tables
shaped as chunks; this one measures tgsis's code paths (plan M, P): one object
of ``--side``^2 points in R^3 (x, y on the grid plus a random offset, z
random) written into the row table, its size with the GiST index on
``cube(coordinate)`` (``pg_total_relation_size`` after VACUUM), then
``tgsis.store_in_chunks('md_vertex')`` (timed: the conversion and its proof),
the chunk table's size, and a full scan of the object through the face against
the row table's (best of ``--repeat``, ratio in the same run). The face's rows
are checked equal to the rows' by ``array_send`` (bit for bit). Unversioned.

    python bench/point_chunks.py [--side 1000 --repeat 3]    # TGSIS_PG=system|embedded
"""

from __future__ import annotations

import argparse
import time

from timing import bench_database


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--side", type=int, default=1000)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    n = args.side * args.side
    figures: dict[str, float] = {}
    with bench_database() as conn:
        conn.execute(
            "INSERT INTO tgsis.md_vertex (geoid, vrtxid, coordinate)"
            " SELECT 1, i, ARRAY[(i %% %(s)s) + random(), (i / %(s)s) + random(), 100 * random()]"
            " FROM generate_series(0, %(n)s - 1) AS i",
            {"s": args.side, "n": n},
        )
        conn.commit()
        conn.autocommit = True
        conn.execute("VACUUM ANALYZE tgsis.md_vertex")
        conn.autocommit = False
        scan = "SELECT sum(cardinality(coordinate)) FROM tgsis.md_vertex WHERE geoid = 1"
        sent = "SELECT vrtxid, array_send(coordinate) FROM tgsis.md_vertex WHERE geoid = 1 ORDER BY vrtxid"

        def best(query: str) -> float:
            times = []
            for _ in range(args.repeat):
                start = time.perf_counter()
                conn.execute(query).fetchall()
                times.append(time.perf_counter() - start)
            conn.rollback()
            return min(times)

        row = conn.execute("SELECT pg_total_relation_size('tgsis.md_vertex')").fetchone()
        assert row is not None
        figures["rows_bytes_per_point"] = row[0] / n
        rows_scan = best(scan)
        before = conn.execute(sent).fetchall()
        conn.rollback()
        start = time.perf_counter()
        conn.execute("SELECT tgsis.store_in_chunks('md_vertex')")
        conn.commit()
        figures["switch_seconds"] = time.perf_counter() - start
        conn.autocommit = True
        conn.execute("VACUUM ANALYZE tgsis.md_vertex_chunk")
        conn.autocommit = False
        row = conn.execute("SELECT pg_total_relation_size('tgsis.md_vertex_chunk')").fetchone()
        assert row is not None
        figures["chunks_bytes_per_point"] = row[0] / n
        figures["bytes_ratio"] = figures["chunks_bytes_per_point"] / figures["rows_bytes_per_point"]
        face_scan = best(scan)
        figures["rows_scan_seconds"] = rows_scan
        figures["face_scan_seconds"] = face_scan
        figures["face_scan_ratio"] = face_scan / rows_scan
        same = conn.execute(sent).fetchall() == before
        conn.rollback()
        print(f"{n} points in R^3, one object; the face's rows equal the rows' bit for bit: {same}")
        for name, value in figures.items():
            print(f"{name}: {value:.3f}")


if __name__ == "__main__":
    main()
