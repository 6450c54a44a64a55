"""Bytes on disk of a class's vertex property in chunks (issue 40, area K), against the same property as rows.

The 1M-vertex grid of bench/transfer.py (one random double property, ``porosity``: incompressible, the hard
case) uploaded with ``insert_feature`` (vertices and triangles in chunks, model 1's default; the property as
rows), measured, then the class switched by ``tgsis.store_class_in_chunks`` (opt-in) and measured again, after
VACUUM. With ``--versioned``, feature versioning is on before the upload (issue 40 asks the disk figure
versioned): the property rows are measured in their ``_ver`` storage, the chunks in the chunk table that is then
the class's versioned storage (``tgsis.storage_table``). Prints ``name: value`` lines.

    .venv/bin/python bench/property_chunks.py [--side 1000] [--order spatial|file] [--versioned]
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


def total(conn: Conn, relation: str) -> int:
    """pg_total_relation_size of one relation (heap, TOAST, indexes)."""
    row = conn.execute("SELECT pg_total_relation_size(%s::regclass)", (relation,)).fetchone()
    assert row is not None
    return int(row[0])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--side", type=int, default=1000)
    parser.add_argument("--order", choices=("spatial", "file"), default="spatial")
    parser.add_argument("--versioned", action="store_true", help="feature versioning on before the upload")
    args = parser.parse_args()
    surface = grid_surface(args.side)
    n = surface.n_vertices
    with bench_database() as conn:
        conn.autocommit = False
        tgsis.create_feature_class(conn, "horizon", "SURFACE", cell_properties=[("porosity", "double precision")])
        if args.versioned:
            tgsis.enable_feature_versioning(conn)
        conn.commit()
        print(f"versioned: {int(args.versioned)}")
        start = time.perf_counter()
        geoid = F.insert_feature(conn, "horizon", surface, order=args.order)
        conn.commit()
        print(f"upload_s: {time.perf_counter() - start:.2f}")
        geometry = [storage_table(conn, "tgsis", "vrtx"), storage_table(conn, "tgsis", "trgl")]
        property_rows = storage_table(conn, "public", "horizon_cellpros")  # the table, or its _ver when versioned
        conn.commit()
        conn.autocommit = True
        conn.execute("VACUUM ANALYZE")
        rows = total(conn, property_rows)
        mesh = sum(total(conn, t) for t in geometry)
        print(f"vertices: {n}")
        print(f"mesh_bytes_per_vertex: {mesh / n:.1f}")
        print(f"property_rows_bytes_per_vertex: {rows / n:.1f}")
        print(f"total_with_property_rows_bytes_per_vertex: {(mesh + rows) / n:.1f}")
        conn.autocommit = False
        start = time.perf_counter()
        conn.execute("SELECT tgsis.store_class_in_chunks('horizon')")
        conn.commit()
        print(f"store_class_in_chunks_s: {time.perf_counter() - start:.2f}")
        conn.commit()
        conn.autocommit = True
        conn.execute("VACUUM ANALYZE")
        property_chunks = storage_table(conn, "public", "horizon_cellpros")
        assert property_chunks == "public.horizon_cellpros_chunk", property_chunks
        chunks = total(conn, property_chunks)
        print(f"property_chunks_bytes_per_vertex: {chunks / n:.1f}")
        print(f"total_with_property_chunks_bytes_per_vertex: {(mesh + chunks) / n:.1f}")
        start = time.perf_counter()
        fetched = F.fetch_feature(conn, "horizon", geoid).mesh
        print(f"fetch_feature_through_the_face_s: {time.perf_counter() - start:.2f}")
        assert isinstance(fetched, tgsis.Surface) and fetched.n_vertices == n


if __name__ == "__main__":
    main()
