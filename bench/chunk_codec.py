"""The chunk codec (tgsis._chunks) on the bench surface: encode + COPY in, COPY out + decode, against a bytea row.

The 1000 x 1000 grid of ``bench/transfer.py`` (1,000,000 vertices, 1,996,002
triangles) in the spatial order (``tgsis.mesh.spatial_order``), stored in a
throwaway cluster (``TGSIS_PG``: system or embedded) as

- chunk rows of the contract (docs/storage.md, "Chunks and the mapping of
  ids"): ``vrtx_chunk`` (x, y, z ``float8[]``, lz4 when the server has it) and
  ``trgl_chunk`` (vbase, relative corners ``int4[]``, the ``_wide`` columns;
  pglz), encoded by :func:`tgsis._chunks.to_copy` and sent by one binary COPY
  per table; read back by one binary COPY per table and
  :func:`tgsis._chunks.from_copy`, checked bit-exact;
- one ``bytea`` row of the raw vertex and triangle bytes (uncompressed), as
  ``bench/peers.py`` stores it.

Each figure is the median of ``--repeat`` runs taken in turn with its
``bytea`` counterpart; one ``name: value`` line per figure.

    python bench/chunk_codec.py [--side 1000] [--repeat 3]
"""

from __future__ import annotations

import argparse
import time
from typing import Any

import numpy as np
import psycopg
from psycopg import sql
from timing import bench_database, paired
from transfer import grid_surface

from tgsis._chunks import ChunkColumns, encode, from_copy, to_copy
from tgsis.mesh import spatial_order

XYZ = ChunkColumns(("x", "y", "z"))
TRGL = ChunkColumns(("vrtxid1", "vrtxid2", "vrtxid3"), refs=("vrtxid1", "vrtxid2", "vrtxid3"))


def create_tables(conn: psycopg.Connection[Any]) -> str:
    row = conn.execute("SELECT 'lz4' = ANY (enumvals) FROM pg_settings WHERE name = 'default_toast_compression'")
    result = row.fetchone()
    floats = "lz4" if result and result[0] else "pglz"
    key = """geoid bigint NOT NULL, chunk bigint NOT NULL, revision integer NOT NULL,
             lastrevs integer[] NOT NULL DEFAULT '{{}}',
             revclosed boolean GENERATED ALWAYS AS (cardinality(lastrevs) > 0) STORED,
             holes smallint[] COMPRESSION pglz"""
    conn.execute("CREATE SCHEMA chunks")
    conn.execute(
        sql.SQL(
            "CREATE TABLE chunks.vrtx_chunk (" + key + ", x double precision[] COMPRESSION {f}, "
            "y double precision[] COMPRESSION {f}, z double precision[] COMPRESSION {f}, "
            "PRIMARY KEY (geoid, chunk, revision))"
        ).format(f=sql.SQL(floats))
    )
    ints = ", ".join(f"vrtxid{i} integer[] COMPRESSION pglz" for i in (1, 2, 3))
    wides = ", ".join(f"vrtxid{i}_wide bigint[] COMPRESSION pglz" for i in (1, 2, 3))
    conn.execute(
        sql.SQL(
            "CREATE TABLE chunks.trgl_chunk (" + key + f", vbase bigint, {ints}, {wides}, "
            "PRIMARY KEY (geoid, chunk, revision))"
        ).format()
    )
    conn.execute("CREATE TABLE chunks.bytea_row (id bigint PRIMARY KEY, vertices bytea, triangles bytea)")
    conn.execute(
        "ALTER TABLE chunks.bytea_row ALTER vertices SET STORAGE EXTERNAL, ALTER triangles SET STORAGE EXTERNAL"
    )
    conn.commit()
    return floats


def copy_in(conn: psycopg.Connection[Any], table: str, spec: ChunkColumns, payload: bytes) -> None:
    query = sql.SQL("COPY chunks.{} ({}) FROM STDIN (FORMAT binary)").format(
        sql.Identifier(table), sql.SQL(", ").join(map(sql.Identifier, spec.copy_columns()))
    )
    with conn.cursor().copy(query) as copy:
        copy.write(payload)


def copy_out(conn: psycopg.Connection[Any], table: str, spec: ChunkColumns, geoid: int) -> bytes:
    query = sql.SQL("COPY (SELECT {} FROM chunks.{} WHERE geoid = {} ORDER BY chunk) TO STDOUT (FORMAT binary)").format(
        sql.SQL(", ").join(map(sql.Identifier, spec.select_columns())), sql.Identifier(table), sql.Literal(geoid)
    )
    out = bytearray()
    with conn.cursor().copy(query) as copy:
        for block in copy:
            out += block
    return bytes(out)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--side", type=int, default=1000)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()

    started = time.perf_counter()
    surface = spatial_order(grid_surface(args.side))
    n_v, n_c = surface.n_vertices, surface.n_cells
    vids, tids = np.arange(n_v, dtype=np.int64), np.arange(n_c, dtype=np.int64)
    vcols = {c: surface.vertices[:, i].copy() for i, c in enumerate("xyz")}
    tcols = {f"vrtxid{i + 1}": surface.cells[:, i].copy() for i in range(3)}
    print(f"surface: {n_v} vertices, {n_c} triangles (grid of bench/transfer.py, spatial order)")

    with bench_database() as conn:
        conn.autocommit = False
        floats = create_tables(conn)
        print(f"compression of the float8 arrays: {floats}")
        geoids = iter(range(1, 10_000))

        def encode_only() -> tuple[bytes, bytes]:
            return to_copy(encode(vids, vcols, XYZ), 0), to_copy(encode(tids, tcols, TRGL), 0)

        def chunk_up() -> None:
            geoid = next(geoids)
            copy_in(conn, "vrtx_chunk", XYZ, to_copy(encode(vids, vcols, XYZ), geoid))
            copy_in(conn, "trgl_chunk", TRGL, to_copy(encode(tids, tcols, TRGL), geoid))
            conn.commit()

        def bytea_up() -> None:
            conn.execute(
                "INSERT INTO chunks.bytea_row VALUES (%s, %s, %s)",
                (next(geoids), surface.vertices.tobytes(), surface.cells.tobytes()),
            )
            conn.commit()

        up_encode, up_chunks, up_bytea = paired([encode_only, chunk_up, bytea_up], args.repeat)
        vpayload, tpayload = encode_only()

        stored_geoid = 1  # written by the first chunk_up
        vbytes, tbytes = (
            copy_out(conn, "vrtx_chunk", XYZ, stored_geoid),
            copy_out(conn, "trgl_chunk", TRGL, stored_geoid),
        )
        conn.commit()
        _, got_v = from_copy(vbytes, XYZ).rows()
        _, got_t = from_copy(tbytes, TRGL).rows()
        for i, c in enumerate("xyz"):
            assert np.array_equal(got_v[c].view(np.int64), surface.vertices[:, i].view(np.int64)), c
        for i in range(3):
            assert np.array_equal(got_t[f"vrtxid{i + 1}"], surface.cells[:, i])
        bytea_id = conn.execute("SELECT min(id) FROM chunks.bytea_row").fetchone()

        def decode_only() -> None:
            from_copy(vbytes, XYZ).rows()
            from_copy(tbytes, TRGL).rows()

        def chunk_down() -> None:
            v = from_copy(copy_out(conn, "vrtx_chunk", XYZ, stored_geoid), XYZ).rows()[1]
            t = from_copy(copy_out(conn, "trgl_chunk", TRGL, stored_geoid), TRGL).rows()[1]
            conn.commit()
            np.stack([v["x"], v["y"], v["z"]], axis=1)
            np.stack([t["vrtxid1"], t["vrtxid2"], t["vrtxid3"]], axis=1)

        def bytea_down() -> None:
            with conn.cursor(binary=True) as cursor:
                row = cursor.execute(
                    "SELECT vertices, triangles FROM chunks.bytea_row WHERE id = %s", bytea_id
                ).fetchone()
            assert row is not None
            np.frombuffer(row[0]).reshape(-1, 3)
            np.frombuffer(row[1], dtype=np.int64).reshape(-1, 3)
            conn.commit()

        down_decode, down_chunks, down_bytea = paired([decode_only, chunk_down, bytea_down], args.repeat)
        conn.autocommit = True
        conn.execute("VACUUM ANALYZE chunks.vrtx_chunk, chunks.trgl_chunk")
        sizes = conn.execute(
            "SELECT pg_total_relation_size('chunks.vrtx_chunk'), pg_total_relation_size('chunks.trgl_chunk'), "
            "(SELECT count(*) FROM chunks.vrtx_chunk), (SELECT count(*) FROM chunks.trgl_chunk WHERE geoid = 1)"
        ).fetchone()
        assert sizes is not None
        copies = max(1, int(sizes[2]) // -(-n_v // 1024))  # objects stored (one per chunk_up)

    print(f"vertex chunks per object: {-(-n_v // 1024)}")
    print(f"triangle chunks per object: {int(sizes[3])}")
    print(f"COPY stream, vertices (MB): {len(vpayload) / 1e6:.1f}")
    print(f"COPY stream, triangles (MB): {len(tpayload) / 1e6:.1f}")
    print(f"bytes on disk per vertex, vertices + triangles: {(int(sizes[0]) + int(sizes[1])) / copies / n_v:.1f}")
    print(f"encode, vertices + triangles (s): {up_encode:.3f}")
    print(f"encode + COPY in, vertices + triangles (s): {up_chunks:.3f}")
    print(f"bytea row INSERT (s): {up_bytea:.3f}")
    print(f"upload vs bytea: {up_chunks / up_bytea:.2f}")
    print(f"decode, vertices + triangles (s): {down_decode:.3f}")
    print(f"COPY out + decode, vertices + triangles (s): {down_chunks:.3f}")
    print(f"bytea row SELECT (s): {down_bytea:.3f}")
    print(f"download vs bytea: {down_chunks / down_bytea:.2f}")
    print(f"whole run (s): {time.perf_counter() - started:.0f}")


if __name__ == "__main__":
    main()
