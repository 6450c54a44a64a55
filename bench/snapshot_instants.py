"""Snapshot at t of a model-2 surface (instants) with its time tables in chunks vs the static download.

A 1000 x 1000 grid (1M vertices, 1,996,002 triangles) known at 2 instants
(``SurfaceSeries``: each instant its own vertices and triangles), stored with
model 2's time tables in chunks (``tgsis.store_in_chunks('times_vrtx')``,
``'times_trgl'``), and a static model-1 surface of the same size (in chunks,
the default). Timed in one process and database, in turn (medians):

- the static download (``fetch_feature``): the baseline;
- the snapshot at t (``get_at``) at an instant and between the two (the step
  convention takes one instant's surface: the same bytes), and the whole
  series (``fetch_series``);
- the upload of the series (``insert_series``) vs the static upload;
- ``tgsis.delete_instant`` of one instant on chunks (its chunk versions
  closed whole, ``tgsis.delete_chunk_slice``) vs the same on rows (the time
  tables switched back with ``tgsis.store_in_rows``, a second copy of the
  series deleted there), once each.

Each model-2 figure twice: the client's chunk paths (the instants' chunks
encoded and decoded by numpy, ``tgsis.db._chunk_transfer.instant_rows`` /
``upload_instants``) and, as before them, the faces (the server decodes the
chunks into rows, ``tgsis.vertices_at``, packed by the server; the upload by
``tgsis.insert_chunk_rows``), switched in this process by replacing those two
functions. Every snapshot is checked against the series first.

    python bench/snapshot_instants.py [--side 1000] [--repeat 3] [--no-faces-upload]   # TGSIS_PG=system|embedded
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
from tgsis.temporal import SurfaceSeries

Conn = psycopg.Connection[Any]


@contextlib.contextmanager
def through_faces() -> Iterator[None]:
    """The model-2 paths as before the client transferred chunks: reads through the faces, uploads through
    ``tgsis.insert_chunk_rows``."""
    with (
        mock.patch("tgsis.db._temporal_common.instant_snapshot", return_value=None),
        mock.patch("tgsis.db.instants.instant_layout", return_value=None),
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
        help="skip the upload through tgsis.insert_chunk_rows (minutes at 1M vertices); the reads are measured",
    )
    args = parser.parse_args()

    grid = grid_surface(args.side)
    static = tgsis.Surface(grid.vertices, grid.cells, name="static bench")
    shapes = []
    for k in range(2):
        vertices = grid.vertices.copy()
        vertices[:, 2] *= 1 + 0.1 * k
        shapes.append(tgsis.Surface(vertices, grid.cells))
    series = SurfaceSeries(np.asarray([0.0, 1.0]), shapes, name="instants bench")
    print(f"surface: {static.n_vertices} vertices, {static.n_cells} triangles; the series: 2 instants of it")
    with bench_database() as conn:
        conn.execute("SELECT tgsis.store_in_chunks('times_vrtx'), tgsis.store_in_chunks('times_trgl')")
        tgsis.create_feature_class(conn, "static_grid", "SURFACE")
        tgsis.create_feature_class(conn, "instants_grid", "SURFACE", time_model="INSTANTS")
        conn.commit()
        ids: dict[str, int] = {}

        def upload(key: str, cls: str, value: Any) -> None:
            ids[key] = tgsis.insert_feature(conn, cls, value)
            conn.commit()

        up_static = once(lambda: upload("static", "static_grid", static))
        up_chunks = once(lambda: upload("chunks", "instants_grid", series))
        upload("rows", "instants_grid", series)  # deleted from on rows at the end
        up_faces = float("nan")
        if args.faces_upload:
            with through_faces():
                up_faces = once(lambda: upload("faces", "instants_grid", series))
        conn.autocommit = True
        for table in ("vrtx_chunk", "trgl_chunk", "times_vrtx_chunk", "times_trgl_chunk", "times", "geometry"):
            conn.execute(f"VACUUM ANALYZE tgsis.{table}")
        conn.autocommit = False

        for key in ids.keys() - {
            "static",
            "rows",
        }:  # the figures are of correct snapshots, and both uploads stored the same
            for t, k in ((0.0, 0), (0.5, 0), (1.0, 1)):
                for path in (contextlib.nullcontext(), through_faces()):
                    with path:
                        got = tgsis.get_at(conn, ids[key], t)
                    assert got is not None and got.same_as(shapes[k]), (key, t)
            assert all(
                a.same_as(b) for a, b in zip(tgsis.fetch_series(conn, "instants_grid", ids[key]).surfaces, shapes)
            )
        conn.commit()

        def snapshot(t: float, faces: bool) -> Callable[[], object]:
            def run() -> None:
                with through_faces() if faces else contextlib.nullcontext():
                    tgsis.get_at(conn, ids["chunks"], t)
                conn.commit()

            return run

        def whole(faces: bool) -> Callable[[], object]:
            def run() -> None:
                with through_faces() if faces else contextlib.nullcontext():
                    tgsis.fetch_series(conn, "instants_grid", ids["chunks"])
                conn.commit()

            return run

        static_down, at_chunks, mid_chunks, series_chunks, at_faces, mid_faces, series_faces = paired(
            [
                lambda: (tgsis.fetch_feature(conn, "static_grid", ids["static"]), conn.commit()),
                snapshot(1.0, False),
                snapshot(0.5, False),
                whole(False),
                snapshot(1.0, True),
                snapshot(0.5, True),
                whole(True),
            ],
            args.repeat,
        )
        # delete_instant: on chunks, then on rows (the time tables switched back), one instant of a series each
        del_chunks = once(lambda: (tgsis.delete_instant(conn, ids["chunks"], 0.0), conn.commit()))
        conn.execute("SELECT tgsis.store_in_rows('times_trgl'), tgsis.store_in_rows('times_vrtx')")
        conn.commit()
        del_rows = once(lambda: (tgsis.delete_instant(conn, ids["rows"], 0.0), conn.commit()))

    print(f"upload, static surface (insert_feature):            {up_static:6.2f} s")
    print(
        f"upload, series of 2 instants, client chunks:        {up_chunks:6.2f} s  ({up_chunks / up_static:.2f}x static)"
    )
    print(
        f"upload, series of 2 instants, insert_chunk_rows:    {up_faces:6.2f} s  ({up_faces / up_static:.2f}x static)"
    )
    print(f"download, static surface (fetch_feature):           {static_down:6.2f} s")
    for name, (chunks, faces) in {
        "get_at at an instant": (at_chunks, at_faces),
        "get_at between instants": (mid_chunks, mid_faces),
        "fetch_series (2 instants)": (series_chunks, series_faces),
    }.items():
        print(
            f"{name:27s} client chunks {chunks:6.2f} s ({chunks / static_down:.2f}x static), "
            f"faces {faces:6.2f} s ({faces / static_down:.2f}x static)"
        )
    print(
        f"delete_instant of one instant: chunks {del_chunks:6.2f} s, rows {del_rows:6.2f} s "
        f"({del_chunks / del_rows:.2f}x rows)"
    )
    print(f"static_download_s: {static_down:.3f}")
    print(f"snapshot_instant_chunks_vs_static: {at_chunks / static_down:.2f}")
    print(f"snapshot_between_chunks_vs_static: {mid_chunks / static_down:.2f}")
    print(f"fetch_series_chunks_vs_static: {series_chunks / static_down:.2f}")
    print(f"snapshot_instant_faces_vs_static: {at_faces / static_down:.2f}")
    print(f"snapshot_between_faces_vs_static: {mid_faces / static_down:.2f}")
    print(f"fetch_series_faces_vs_static: {series_faces / static_down:.2f}")
    print(f"static_upload_s: {up_static:.3f}")
    print(f"series_upload_chunks_vs_static: {up_chunks / up_static:.2f}")
    print(f"series_upload_faces_vs_static: {up_faces / up_static:.2f}")
    print(f"delete_instant_rows_s: {del_rows:.3f}")
    print(f"delete_instant_chunks_vs_rows: {del_chunks / del_rows:.2f}")


if __name__ == "__main__":
    main()
