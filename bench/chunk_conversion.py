"""Rows into chunks (issue 40, ``tgsis.rows_to_chunks``) of a 1M-vertex surface in one version, vs a plain copy.

The side x side grid of bench/transfer.py (no property) uploaded into model 1 stored in rows, versioning on,
then the chunk tables made beside the row tables (``create_chunk_table``/``create_chunk_view``) and each of
``vrtx`` and ``trgl`` converted, its verification (``check_chunk_conversion``) timed again on its own. The
baseline, in the same process: ``CREATE TABLE ... AS SELECT *`` of the same row storage (the rows copied,
nothing encoded). This was tests/test_chunk_conversion.py's measuring test until 2026-12-06; the test now
checks the same at 10,000 vertices. Prints ``name: value`` lines.

    .venv/bin/python bench/chunk_conversion.py [--side 1000]
"""

from __future__ import annotations

import argparse
import time
from typing import Any

import psycopg
from timing import bench_database
from transfer import grid_surface

import tgsis
from tgsis.db import features as F
from tgsis.db.versions import storage_table

Conn = psycopg.Connection[Any]


def seconds(conn: Conn, statement: str, params: tuple[Any, ...] = ()) -> float:
    """Wall time of one statement, committed."""
    start = time.perf_counter()
    conn.execute(statement, params)
    conn.commit()
    return time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--side", type=int, default=1000)
    args = parser.parse_args()
    surface = grid_surface(args.side)
    surface = tgsis.Surface(surface.vertices, surface.cells, name="bench")
    with bench_database(storage="rows") as conn:
        conn.autocommit = False
        tgsis.create_feature_class(conn, "big", "SURFACE")
        tgsis.enable_feature_versioning(conn)
        F.insert_feature(conn, "big", surface)
        conn.commit()
        for table, n in (("vrtx", surface.n_vertices), ("trgl", surface.n_cells)):
            rows = storage_table(conn, "tgsis", table)
            conn.execute("SELECT tgsis.create_chunk_table(%s), tgsis.create_chunk_view(%s)", (table, table))
            conn.commit()
            copy = seconds(conn, f"CREATE TABLE public.copy_{table} AS SELECT * FROM {rows}")
            start = time.perf_counter()
            row = conn.execute("SELECT tgsis.rows_to_chunks(%s)", (table,)).fetchone()
            conn.commit()
            convert = time.perf_counter() - start
            assert row is not None and row[0] == -(-n // 1024), row
            check = seconds(conn, "SELECT tgsis.check_chunk_conversion(%s)", (table,))
            print(
                f"{table}: {n} rows -> {row[0]} chunks in {convert:.2f} s (verification alone {check:.2f} s); "
                f"plain copy of the rows {copy:.2f} s"
            )
            print(f"{table}_rows_to_chunks_s: {convert:.2f}")
            print(f"{table}_check_chunk_conversion_s: {check:.2f}")
            print(f"{table}_rows_to_chunks_vs_plain_copy: {convert / copy:.1f}")


if __name__ == "__main__":
    main()
