"""Download of a whole model-3 surface (``fetch_evolving``): d4dvrtx/d4dtrgl as rows vs in chunks.

A side x side grid (317: 100,489 nodes, 199,712 triangles) known at ``--instants``
geometry instants (10) of one topology period (``EvolvingSurface``: the nodes
move, the triangles stay), and a static model-1 surface of the same grid (in
chunks, the default) as the baseline. Timed in one process and database
(medians, in turn):

1. model 3's tables as rows (the default): ``fetch_evolving`` against the
   static download (``fetch_feature``);
2. then ``tgsis.store_in_chunks('d4dtrgl')``, ``'d4dvrtx'`` (the feature's
   rows converted): ``fetch_evolving`` reading the chunks and decoding them in
   numpy (``tgsis.db._chunk_transfer.instant_rows``) and, as before it,
   through the faces (the server decodes the chunks into rows), switched in
   this process by replacing ``tgsis.db.evolving.instant_layout``; each
   against the static download in the same run.

Every download is checked against the surface first (positions bit for bit).

    python bench/fetch_evolving.py [--side 317] [--instants 10] [--repeat 3]   # TGSIS_PG=system|embedded
"""

from __future__ import annotations

import argparse
import contextlib
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


@contextlib.contextmanager
def through_faces() -> Iterator[None]:
    """``fetch_evolving`` as before it read the chunks: d4dvrtx and d4dtrgl through their faces."""
    with mock.patch("tgsis.db.evolving.instant_layout", return_value=None):
        yield


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--side", type=int, default=317)
    parser.add_argument("--instants", type=int, default=10)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()

    grid = grid_surface(args.side)
    static = tgsis.Surface(grid.vertices, grid.cells, name="static bench")
    times = np.arange(args.instants, dtype=np.float64)
    positions = np.stack([grid.vertices * np.array([1.0, 1.0, 1.0 + 0.1 * k]) for k in range(args.instants)])
    surface = EvolvingSurface([TopologyPeriod(times, grid.cells, positions)], name="evolving bench")
    nodes = static.n_vertices * args.instants
    print(
        f"surface: {static.n_vertices} nodes, {static.n_cells} triangles; evolving: {args.instants} geometry "
        f"instants of it ({nodes} node positions)"
    )
    with bench_database() as conn:
        tgsis.create_feature_class(conn, "static_grid", "SURFACE")
        tgsis.create_feature_class(conn, "evolving_grid", "SURFACE", time_model="EVOLVING")
        conn.commit()
        static_id = tgsis.insert_feature(conn, "static_grid", static)
        geoid = tgsis.insert_feature(conn, "evolving_grid", surface)
        conn.commit()

        def vacuum() -> None:
            conn.autocommit = True
            for table in ("vrtx_chunk", "trgl_chunk", "d4dvrtx", "d4dtrgl", "d4dvrtx_chunk", "d4dtrgl_chunk"):
                if conn.execute("SELECT to_regclass(%s)", (f"tgsis.{table}",)).fetchone() != (None,):
                    conn.execute(f"VACUUM ANALYZE tgsis.{table}")
            conn.autocommit = False

        def check(faces: bool) -> None:
            with through_faces() if faces else contextlib.nullcontext():
                got = tgsis.fetch_evolving(conn, "evolving_grid", geoid)
            conn.commit()
            (period,) = got.periods
            assert np.array_equal(period.positions.view(np.int64), positions.view(np.int64))
            assert np.array_equal(period.triangles, grid.cells) and np.array_equal(period.times, times)

        def fetch(faces: bool) -> Callable[[], object]:
            def run() -> None:
                with through_faces() if faces else contextlib.nullcontext():
                    tgsis.fetch_evolving(conn, "evolving_grid", geoid)
                conn.commit()

            return run

        def static_down() -> None:
            tgsis.fetch_feature(conn, "static_grid", static_id)
            conn.commit()

        vacuum()
        check(False)
        static_rows, rows = paired([static_down, fetch(False)], args.repeat)

        conn.execute("SELECT tgsis.store_in_chunks('d4dtrgl'), tgsis.store_in_chunks('d4dvrtx')")
        conn.commit()
        vacuum()
        check(False)
        check(True)
        static_chunks, chunks, faces = paired([static_down, fetch(False), fetch(True)], args.repeat)

    print(f"download, static surface (fetch_feature), run 1 / 2: {static_rows:6.3f} s / {static_chunks:6.3f} s")
    print(f"fetch_evolving, rows:                 {rows:6.3f} s ({rows / static_rows:.2f}x static)")
    print(f"fetch_evolving, client chunks:        {chunks:6.3f} s ({chunks / static_chunks:.2f}x static)")
    print(f"fetch_evolving, chunks via the faces: {faces:6.3f} s ({faces / static_chunks:.2f}x static)")
    print(f"fetch_chunks_vs_rows: {chunks / rows:.2f}")
    print(f"fetch_chunks_vs_faces: {chunks / faces:.2f}")
    print(f"fetch_rows_vs_static: {rows / static_rows:.2f}")
    print(f"fetch_chunks_vs_static: {chunks / static_chunks:.2f}")
    print(f"fetch_faces_vs_static: {faces / static_chunks:.2f}")


if __name__ == "__main__":
    main()
