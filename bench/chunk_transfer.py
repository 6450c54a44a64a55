"""Bulk transfer on chunks (tgsis.db._chunk_transfer) against today's insert_feature / fetch_feature and a bytea row.

The 1000 x 1000 grid of ``bench/transfer.py`` (1,000,000 vertices, 1,996,002
triangles) in the spatial order (``tgsis.mesh.spatial_order``), vertices and
triangles only: the property tables are not chunked yet. In one throwaway
cluster (``TGSIS_PG``: system or embedded), plain storage unless ``--versioned``:

- upload: ``upload_chunks`` of ``vrtx`` and ``trgl`` (numpy encode, one
  binary COPY per table, commit) into the tables of
  ``tgsis.create_chunk_table``; today's ``insert_feature`` of the same mesh
  (class without properties); one ``bytea`` row of the raw vertex and
  triangle bytes (``INSERT``);
- download, the (n, 3) vertices and (m, 3) corners built each time:
  ``download_tables`` (both tables' COPYs in one snapshot, one after the
  other); the two ideas of docs/storage.md: the two tables on two
  connections side by side (``side=``: the second imports the first's
  snapshot), and one COPY of both tables
  joined by ``UNION ALL`` (split by a tag); today's ``fetch_feature``; the
  ``bytea`` row's ``SELECT``.

Each figure is the median of ``--repeat`` runs taken in turn; every path is
checked bit-exact first. One ``name: value`` line per figure. ``--versioned``:
versioned storage, in a working revision other than 0 (the uploads note
their objects; the downloads filter by the session's set).

    python bench/chunk_transfer.py [--side 1000] [--repeat 3] [--versioned]
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Callable
from typing import Any

import numpy as np
import psycopg
from psycopg import sql
from timing import bench_database, paired
from transfer import grid_surface

import tgsis
from tgsis._chunks import from_copy
from tgsis.db._chunk_transfer import ObjectRows, chunk_table, download_tables, upload_chunks
from tgsis.mesh import Surface, spatial_order

Conn = psycopg.Connection[Any]


def copy_bytes(conn: Conn, query: sql.Composed) -> bytes:
    with conn.cursor().copy(query) as copy:
        return b"".join(bytes(block) for block in copy)


def union_query(conn: Conn, geoid: int) -> tuple[sql.Composed, dict[int, list[int]]]:
    """One COPY of both tables' chunks (no visibility filter: every chunk of the bench is live): a tag (1 vertices, 2 triangles), ``chunk, holes``, then the
    vertex arrays, then the triangles' ``vbase`` and arrays, each table's fields NULL in the other's rows."""
    v, t = chunk_table(conn, "vrtx"), chunk_table(conn, "trgl")
    vcols, tcols = v.columns.select_columns()[2:], t.columns.select_columns()[2:]
    types = {"x": "double precision[]", "y": "double precision[]", "z": "double precision[]", "vbase": "bigint"}

    def kind(column: str) -> str:
        return types.get(column, "bigint[]" if column.endswith("_wide") else "integer[]")

    def part(tag: int, table: str, mine: list[str]) -> sql.Composed:
        fields = [
            sql.SQL("c.{}").format(sql.Identifier(c)) if c in mine else sql.SQL("NULL::{}").format(sql.SQL(kind(c)))
            for c in ["chunk", "holes", *vcols, *tcols]
        ]
        return sql.SQL("SELECT {}::bigint, {} FROM tgsis.{} c WHERE c.geoid = {}").format(
            sql.Literal(tag), sql.SQL(", ").join(fields), sql.Identifier(f"{table}_chunk"), sql.Literal(geoid)
        )

    query = sql.SQL("COPY ({} UNION ALL {}) TO STDOUT (FORMAT binary)").format(
        part(1, "vrtx", ["chunk", "holes", *vcols]), part(2, "trgl", ["chunk", "holes", *tcols])
    )
    keep = {1: list(range(2 + len(vcols))), 2: [0, 1, *range(2 + len(vcols), 2 + len(vcols) + len(tcols))]}
    return query, keep


def split_tagged(payload: bytes, keep: dict[int, list[int]]) -> dict[int, bytes]:
    """Rows ``(tag bigint, fields...)`` as one stream per tag with the fields ``keep[tag]`` (the others NULL)."""
    view = memoryview(payload)
    header = bytes(view[:19])
    pieces: dict[int, list[Any]] = {tag: [header] for tag in keep}
    pos = 19
    while True:
        count = int.from_bytes(view[pos : pos + 2], "big", signed=True)
        if count == -1:
            break
        tag = int.from_bytes(view[pos + 6 : pos + 14], "big")
        pos += 14
        out = pieces[tag]
        out.append(len(keep[tag]).to_bytes(2, "big"))
        wanted = set(keep[tag])
        for i in range(count - 1):
            length = int.from_bytes(view[pos : pos + 4], "big", signed=True)
            end = pos + 4 + max(length, 0)
            if i in wanted:
                out.append(view[pos:end])
            pos = end
    return {tag: b"".join([*parts, b"\xff\xff"]) for tag, parts in pieces.items()}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--side", type=int, default=1000)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument(
        "--versioned", action="store_true", help="versioned storage, DEFAULT's working revision not 0 (notes written)"
    )
    args = parser.parse_args()

    started = time.perf_counter()
    surface = spatial_order(grid_surface(args.side))
    surface = Surface(surface.vertices, surface.cells, name="bench")  # no property: not chunked yet
    n_v, n_c = surface.n_vertices, surface.n_cells
    vids, tids = np.arange(n_v, dtype=np.int64), np.arange(n_c, dtype=np.int64)
    print(f"surface: {n_v} vertices, {n_c} triangles (grid of bench/transfer.py, spatial order, no property)")

    with bench_database() as conn:
        conn.autocommit = False
        if args.versioned:
            tgsis.enable_feature_versioning(conn)
            tgsis.create_version(conn, "other")  # DEFAULT's working revision is no longer 0
        tgsis.create_feature_class(conn, "horizon", "SURFACE")
        conn.execute("SELECT tgsis.create_chunk_table('vrtx'), tgsis.create_chunk_table('trgl')")
        conn.execute("CREATE TABLE public.bytea_row (id bigint PRIMARY KEY, vertices bytea, triangles bytea)")
        conn.execute(
            "ALTER TABLE public.bytea_row ALTER vertices SET STORAGE EXTERNAL, ALTER triangles SET STORAGE EXTERNAL"
        )
        conn.commit()
        row = conn.execute("SELECT version()").fetchone()
        print(f"server version: {row[0].split(',')[0] if row else '?'}")
        print(f"storage: {'versioned' if args.versioned else 'plain'}")
        geoids = iter(range(10**9, 10**9 + 10_000))
        features: list[int] = []

        def chunk_up() -> None:
            geoid = next(geoids)
            upload_chunks(
                conn, "vrtx", [ObjectRows(geoid, vids, {c: surface.vertices[:, i] for i, c in enumerate("xyz")})]
            )
            upload_chunks(
                conn, "trgl", [ObjectRows(geoid, tids, {f"vrtxid{i + 1}": surface.cells[:, i] for i in range(3)})]
            )
            conn.commit()

        def today_up() -> None:
            features.append(tgsis.insert_feature(conn, "horizon", surface))
            conn.commit()

        def bytea_up() -> None:
            conn.execute(
                "INSERT INTO public.bytea_row VALUES (%s, %s, %s)",
                (next(geoids), surface.vertices.tobytes(), surface.cells.tobytes()),
            )
            conn.commit()

        up_chunks, up_today, up_bytea = paired([chunk_up, today_up, bytea_up], args.repeat)

        stored = 10**9  # written by the first chunk_up
        bytea_id = conn.execute("SELECT min(id) FROM public.bytea_row").fetchone()
        conn.commit()
        other = psycopg.connect(conn.info.dsn, password=conn.info.password or None)
        vlayout, tlayout = chunk_table(conn, "vrtx"), chunk_table(conn, "trgl")
        conn.commit()

        def arrays(v: ObjectRows, t: ObjectRows) -> tuple[np.ndarray, np.ndarray]:
            return v.array(), t.array()

        def chunk_down() -> tuple[np.ndarray, np.ndarray]:
            got = download_tables(conn, {"vrtx": [stored], "trgl": [stored]})
            return arrays(got["vrtx"][stored], got["trgl"][stored])

        def two_connections() -> tuple[np.ndarray, np.ndarray]:
            got = download_tables(conn, {"vrtx": [stored], "trgl": [stored]}, side=other)
            return arrays(got["vrtx"][stored], got["trgl"][stored])

        union, keep = union_query(conn, stored)
        conn.commit()

        def union_all() -> tuple[np.ndarray, np.ndarray]:
            streams = split_tagged(copy_bytes(conn, union), keep)
            conn.commit()
            v, t = from_copy(streams[1], vlayout.columns).rows(), from_copy(streams[2], tlayout.columns).rows()
            return arrays(ObjectRows(stored, *v), ObjectRows(stored, *t))

        def today_down() -> tuple[np.ndarray, np.ndarray]:
            mesh = tgsis.fetch_feature(conn, "horizon", features[0]).mesh
            conn.commit()
            assert isinstance(mesh, Surface)
            return mesh.vertices, mesh.cells

        def bytea_down() -> tuple[np.ndarray, np.ndarray]:
            with conn.cursor(binary=True) as cursor:
                got = cursor.execute(
                    "SELECT vertices, triangles FROM public.bytea_row WHERE id = %s", bytea_id
                ).fetchone()
            assert got is not None
            conn.commit()
            return np.frombuffer(got[0]).reshape(-1, 3), np.frombuffer(got[1], dtype=np.int64).reshape(-1, 3)

        downs: list[Callable[[], tuple[np.ndarray, np.ndarray]]] = [
            chunk_down,
            two_connections,
            union_all,
            today_down,
            bytea_down,
        ]
        for down in downs:  # every path bit-exact first
            xyz, cells = down()
            assert np.array_equal(xyz.view(np.int64), surface.vertices.view(np.int64)), down.__name__
            assert np.array_equal(cells, surface.cells), down.__name__
        d_chunks, d_two, d_union, d_today, d_bytea = paired(list(downs), args.repeat)
        other.close()
        conn.autocommit = True
        conn.execute("VACUUM ANALYZE tgsis.vrtx_chunk, tgsis.trgl_chunk")
        sizes = conn.execute(
            "SELECT pg_total_relation_size('tgsis.vrtx_chunk') + pg_total_relation_size('tgsis.trgl_chunk'), "
            "(SELECT count(*) FROM tgsis.vrtx_chunk WHERE geoid = %s), (SELECT count(*) FROM tgsis.trgl_chunk WHERE geoid = %s)",
            (stored, stored),
        ).fetchone()
        objects = conn.execute("SELECT count(DISTINCT geoid) FROM tgsis.vrtx_chunk").fetchone()
        assert sizes is not None and objects is not None

    print(f"vertex / triangle chunks per object: {sizes[1]} / {sizes[2]}")
    print(f"bytes on disk per vertex, vertices + triangles chunks: {int(sizes[0]) / int(objects[0]) / n_v:.1f}")
    print(f"upload, chunks (upload_chunks vrtx + trgl, commit) (s): {up_chunks:.3f}")
    print(f"upload, today's insert_feature (s): {up_today:.3f}")
    print(f"upload, bytea row INSERT (s): {up_bytea:.3f}")
    print(f"upload, chunks vs bytea: {up_chunks / up_bytea:.2f}")
    print(f"upload, chunks vs insert_feature: {up_chunks / up_today:.2f}")
    print(f"download, chunks (download_tables, one snapshot) (s): {d_chunks:.3f}")
    print(f"download, chunks on two connections (s): {d_two:.3f}")
    print(f"download, chunks in one UNION ALL COPY (s): {d_union:.3f}")
    print(f"download, today's fetch_feature (s): {d_today:.3f}")
    print(f"download, bytea row SELECT (s): {d_bytea:.3f}")
    print(f"download, chunks vs bytea: {d_chunks / d_bytea:.2f}")
    print(f"download, two connections vs bytea: {d_two / d_bytea:.2f}")
    print(f"download, UNION ALL vs bytea: {d_union / d_bytea:.2f}")
    print(f"download, chunks vs fetch_feature: {d_chunks / d_today:.2f}")
    print(f"whole run (s): {time.perf_counter() - started:.0f}")


if __name__ == "__main__":
    main()
