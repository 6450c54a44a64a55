"""What the old-snapshot guard costs (plan H, issue 40): one vertex by key through the face, a 1M download.

``tgsis.chunk_snapshot_guard(chunk table)`` runs once per query (an InitPlan) in every chunk face and chunk
view and in the Python chunk readers' statements: a snapshot older than the chunk table's file (a storage
switch into chunks made it) gets 40001 instead of reading it empty. Measured in one process, in turn
(``paired``: drift hits both alike): the real guard, and the same queries with the guard replaced by a
function returning true (``CREATE OR REPLACE``, the throwaway database only), for

- a psql-style ``SELECT x, y, z FROM tgsis.vrtx WHERE geoid = 1 AND vrtxid = k`` (one vertex by key through
  the face, a ``--n``-vertex object written by ``tgsis.write_chunk_rows``, versioning on as bench/chunk_face.py);
- ``fetch_feature`` of a ``--side`` x ``--side`` grid with one double property in chunks
  (``store_class_in_chunks``), the download of model 1 and of property chunks.

Prints ``name: value`` lines.

    PYTHONPATH=src:bench .venv/bin/python bench/snapshot_guard.py [--n 1000000] [--side 1000] [--repeat 21]
"""

from __future__ import annotations

import argparse
from typing import Any

import psycopg
from timing import bench_database, paired
from transfer import grid_surface

import tgsis
from tgsis.db import features as F

Conn = psycopg.Connection[Any]

TRIVIAL = (
    "CREATE OR REPLACE FUNCTION tgsis.chunk_snapshot_guard(p_chunk regclass) RETURNS boolean "
    "LANGUAGE sql STABLE PARALLEL SAFE AS 'SELECT true'"
)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--n", type=int, default=1_000_000)
    parser.add_argument("--side", type=int, default=1000)
    parser.add_argument("--repeat", type=int, default=21)
    args = parser.parse_args()
    with bench_database() as conn:
        conn.prepare_threshold = None  # no prepared plan kept across the function's replacement
        conn.autocommit = False
        real = conn.execute(
            "SELECT pg_get_functiondef('tgsis.chunk_snapshot_guard(regclass)'::regprocedure)"
        ).fetchone()
        assert real is not None
        tgsis.create_feature_class(conn, "horizon", "SURFACE", cell_properties=[("porosity", "double precision")])
        conn.execute("SELECT tgsis.store_class_in_chunks('horizon')")
        conn.commit()
        surface = grid_surface(args.side)
        geoid = F.insert_feature(conn, "horizon", surface)
        conn.commit()
        conn.execute("SELECT tgsis.enable_feature_versioning()")
        select = "SELECT 10000001::bigint AS geoid, i AS vrtxid, i::float8 AS x, -i::float8 AS y, 0.5::float8 AS z"
        conn.execute(
            f"CREATE TEMP TABLE big AS {select}, false AS _delete FROM generate_series(0::bigint, %s) i", (args.n - 1,)
        )
        conn.execute("SELECT tgsis.write_chunk_rows('vrtx', 'pg_temp.big')")
        conn.commit()
        conn.execute("ANALYZE tgsis.vrtx_chunk")
        conn.commit()
        key = args.n * 2 // 3 + 7
        face_read = "SELECT x, y, z FROM tgsis.vrtx WHERE geoid = 10000001 AND vrtxid = %s"

        def one_vertex() -> None:
            assert conn.execute(face_read, (key,)).fetchall() == [(float(key), -float(key), 0.5)]
            conn.rollback()

        def download() -> None:
            mesh = F.fetch_feature(conn, "horizon", geoid).mesh
            assert mesh is not None and mesh.n_vertices == args.side**2
            conn.rollback()

        def use(definition: str) -> None:
            conn.execute(definition)
            conn.commit()

        results: dict[str, list[float]] = {}
        for label, definition in (("guard", real[0]), ("none", TRIVIAL), ("guard2", real[0])):
            use(definition)
            face, fetch = paired([one_vertex, download], 1)  # warm
            face = paired([one_vertex], args.repeat)[0]
            fetch = paired([download], max(3, args.repeat // 7))[0]
            results[label] = [face, fetch]
        use(real[0])
        guard = [min(a, b) for a, b in zip(results["guard"], results["guard2"], strict=True)]
        none = results["none"]
        print(f"face_one_vertex_guard_ms: {guard[0] * 1000:.2f}")
        print(f"face_one_vertex_no_guard_ms: {none[0] * 1000:.2f}")
        print(f"face_one_vertex_guard_to_none: {guard[0] / none[0]:.3f}")
        print(f"fetch_feature_{args.side**2}_guard_s: {guard[1]:.3f}")
        print(f"fetch_feature_{args.side**2}_no_guard_s: {none[1]:.3f}")
        print(f"fetch_feature_guard_to_none: {guard[1] / none[1]:.3f}")


if __name__ == "__main__":
    main()
