"""Bytes on disk of a class's vertex property in chunks (issue 40, area K), against the same property as rows.

The 1M-vertex grid of bench/transfer.py (one random double property, ``porosity``: incompressible, the hard
case) uploaded with ``insert_feature`` (vertices and triangles in chunks, model 1's default; the property as
rows), measured, then the class switched by ``tgsis.store_class_in_chunks`` (opt-in, unversioned classes only:
the switch of versioned classes is not built) and measured again, after VACUUM. Prints ``name: value`` lines.

    .venv/bin/python bench/property_chunks.py [--side 1000] [--order spatial|file]
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
    args = parser.parse_args()
    surface = grid_surface(args.side)
    n = surface.n_vertices
    with bench_database() as conn:
        conn.autocommit = False
        tgsis.create_feature_class(conn, "horizon", "SURFACE", cell_properties=[("porosity", "double precision")])
        conn.commit()
        start = time.perf_counter()
        geoid = F.insert_feature(conn, "horizon", surface, order=args.order)
        conn.commit()
        print(f"upload_s: {time.perf_counter() - start:.2f}")
        geometry = [storage_table(conn, "tgsis", "vrtx"), storage_table(conn, "tgsis", "trgl")]
        conn.commit()
        conn.autocommit = True
        conn.execute("VACUUM ANALYZE")
        rows = total(conn, "public.horizon_cellpros")
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
        chunks = total(conn, "public.horizon_cellpros_chunk")
        print(f"property_chunks_bytes_per_vertex: {chunks / n:.1f}")
        print(f"total_with_property_chunks_bytes_per_vertex: {(mesh + chunks) / n:.1f}")
        start = time.perf_counter()
        fetched = F.fetch_feature(conn, "horizon", geoid).mesh
        print(f"fetch_feature_through_the_face_s: {time.perf_counter() - start:.2f}")
        assert isinstance(fetched, tgsis.Surface) and fetched.n_vertices == n


if __name__ == "__main__":
    main()
