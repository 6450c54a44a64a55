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
Then ``tgsis.md_vertices_in_box`` over three x-y windows (10 x 10 points,
100 x 100, a quarter of the object): the rows' per-point GiST index against
the chunks' box index (plan N, B1; the answers compared bit for bit), and the
face's read that answered on chunks before it (``face_ratio (before)``); the box
index's bytes per point.

With ``--transfer`` (plan M, Q) it measures the client codec instead: the
points of one model-5 object of ``--side``^2 points in R^3 (odd bits among them)
uploaded into ``md_vertex`` stored in chunks by the client's encoder
(``tgsis.db._chunk_transfer.upload_rows``: one binary COPY of chunks) against
the server's path (``tgsis.insert_chunk_rows``, what the upload did before),
and downloaded by the client's decoder (``point_rows``) against the face's
read (``copy_rows`` of ``tgsis.md_vertex``, what ``fetch_md_gmap`` did before);
each a fresh object, paths alternated, best of ``--repeat``, ratios in the same
run; the chunk rows of both uploads and the points of both downloads checked
equal, bit for bit. The points' table alone: the darts and involutions had their
client codec already (docs/performance.md, "G-maps in chunks").

    python bench/point_chunks.py [--side 1000 --repeat 3] [--transfer]    # TGSIS_PG=system|embedded
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from timing import bench_database

from tgsis.db import _chunk_transfer, _transfer
from tgsis.db._gmap_common import copy_rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--side", type=int, default=1000)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--transfer", action="store_true", help="the client codec against the server's path")
    args = parser.parse_args()
    if args.transfer:
        transfer(args.side, args.repeat)
        return
    n = args.side * args.side
    figures: dict[str, float] = {}
    with bench_database() as conn:
        conn.execute(
            "INSERT INTO tgsis.md_vertex (geoid, vrtxid, coordinate)"
            " SELECT 1, i, ARRAY[(i %% %(s)s) + random(), (i / %(s)s) + random(), 100 * random()]"
            " FROM generate_series(0, %(n)s - 1) AS i",
            {"s": args.side, "n": n},
        )
        conn.execute("INSERT INTO tgsis.md_gmap (geoid, dimension, embedding, axes) VALUES (1, 2, 3, '{x,y,z}')")
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
        boxes = _boxes(args.side)
        in_box = "SELECT vrtxid, array_send(coordinate) FROM tgsis.md_vertices_in_box(1, {})"
        rows_boxes = {name: best(in_box.format(box)) for name, box in boxes.items()}
        rows_answers = {name: conn.execute(in_box.format(box)).fetchall() for name, box in boxes.items()}
        conn.rollback()
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
        row = conn.execute("SELECT pg_relation_size('tgsis.md_vertex_chunk_coordinate_box_idx')").fetchone()
        assert row is not None
        figures["chunk_box_index_bytes_per_point"] = row[0] / n
        # the index's cost on every write: tgsis.point_chunk_box of each chunk (of 1,024 points)
        figures["chunk_box_seconds_per_chunk"] = best(
            "SELECT count(tgsis.point_chunk_box(coordinate)) FROM tgsis.md_vertex_chunk"
        ) / (n / 1024)
        same_boxes = True
        for name, box in boxes.items():
            chunks = best(in_box.format(box))
            same_boxes &= conn.execute(in_box.format(box)).fetchall() == rows_answers[name]
            conn.rollback()
            # what md_vertices_in_box did on chunks before the box: the rows' test over the face, every point decoded
            face = best(
                "SELECT vrtxid, array_send(coordinate) FROM tgsis.md_vertex WHERE geoid = 1"
                f" AND cube(coordinate) <@ tgsis.md_query_box('{{x,y,z}}', {box})"
                " AND NOT 'NaN'::double precision = ANY (coordinate) ORDER BY vrtxid"
            )
            figures[f"box {name}: rows_seconds"] = rows_boxes[name]
            figures[f"box {name}: chunks_seconds"] = chunks
            figures[f"box {name}: chunks_ratio"] = chunks / rows_boxes[name]
            figures[f"box {name}: face_ratio (before)"] = face / rows_boxes[name]
        print(f"{n} points in R^3, one object; the face's rows equal the rows' bit for bit: {same}")
        print(f"md_vertices_in_box answers equal on chunks and rows, bit for bit: {same_boxes}")
        for name, value in figures.items():
            print(f"{name}: {value:.3f}")


def _boxes(side: int) -> dict[str, str]:
    """The x-y windows of the grid: 10 x 10 points, 100 x 100, a quarter of the object, as md_query_box's arguments."""
    windows = {"10x10": (side / 2, 10), "100x100": (side / 2, 100), "quarter": (0, side / 2)}
    return {
        name: f"'{{x,y}}', '{{{at},{at}}}', '{{{at + width},{at + width}}}'" for name, (at, width) in windows.items()
    }


def transfer(side: int, repeat: int) -> None:
    """Upload and download of one object's points: the client codec against the server's path."""
    n = side * side
    rng = np.random.default_rng(1)
    grid = np.arange(n)
    points = np.stack([grid % side + rng.random(n), grid // side + rng.random(n), 100 * rng.random(n)], axis=1)
    points[:3, 2] = (-0.0, 5e-324, float(np.frombuffer(np.uint64(0x7FF8_0000_0000_0ABC).tobytes(), np.float64)[0]))
    ids = np.arange(n, dtype=np.int64)
    times: dict[str, list[float]] = {}
    with bench_database() as conn:
        conn.execute("SELECT tgsis.store_in_chunks('md_vertex')")
        conn.commit()
        storage = _transfer.Storage.of(conn)
        geoid = 0
        objects: dict[str, list[int]] = {"client": [], "server": []}
        reads: dict[str, bytes] = {}

        def columns(g: int) -> list[tuple[str, object, str]]:
            return [("geoid", np.full(n, g), "int8"), ("vrtxid", ids, "int8"), ("coordinate", points, "float8[3]")]

        for k in range(repeat):
            for path in ("client", "server") if k % 2 == 0 else ("server", "client"):
                geoid += 1
                start = time.perf_counter()
                if path == "client":
                    assert _chunk_transfer.upload_rows(conn, "md_vertex", columns(geoid), storage)
                else:
                    _transfer.insert_chunk_rows(conn, "md_vertex", columns(geoid))
                conn.commit()
                times.setdefault(f"upload_{path}_seconds", []).append(time.perf_counter() - start)
                objects[path].append(geoid)
        conn.autocommit = True
        conn.execute("VACUUM ANALYZE tgsis.md_vertex_chunk")
        conn.autocommit = False
        chunk_rows = "SELECT chunk, revision, holes, array_send(coordinate) FROM tgsis.md_vertex_chunk WHERE geoid = %s ORDER BY 1"
        same_chunks = (
            conn.execute(chunk_rows, (objects["client"][0],)).fetchall()
            == conn.execute(chunk_rows, (objects["server"][0],)).fetchall()
        )
        conn.rollback()
        target = objects["client"][0]
        for k in range(repeat):
            for path in ("client", "face") if k % 2 == 0 else ("face", "client"):
                start = time.perf_counter()
                if path == "client":
                    got = _chunk_transfer.point_rows(conn, "md_vertex", target, 3)
                    assert got is not None
                else:
                    got = copy_rows(
                        conn,
                        "SELECT vrtxid, coordinate FROM tgsis.md_vertex WHERE geoid = {}",
                        target,
                        ["int8", "float8[3]"],
                        [0],
                    )
                conn.rollback()
                times.setdefault(f"download_{path}_seconds", []).append(time.perf_counter() - start)
                reads[path] = b"".join(
                    np.ascontiguousarray(np.asarray(c, dtype=c.dtype.newbyteorder("="))).tobytes() for c in got
                )
    best = {name: min(values) for name, values in times.items()}
    print(
        f"{n} points in R^3, one model-5 object, unversioned; chunk rows equal bit for bit: {same_chunks}; "
        f"points read equal bit for bit: {reads['client'] == reads['face']}"
    )
    for name, value in best.items():
        print(f"{name}: {value:.3f}")
    print(f"upload_server_over_client: {best['upload_server_seconds'] / best['upload_client_seconds']:.2f}")
    print(f"download_face_over_client: {best['download_face_seconds'] / best['download_client_seconds']:.2f}")


if __name__ == "__main__":
    main()
