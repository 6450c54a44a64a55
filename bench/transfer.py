"""Upload and download of a 1M-vertex, 2M-triangle surface with one vertex property.

Baseline in the same run: raw binary COPY of the same rows (vertices,
triangles, property values; payloads built beforehand) into unindexed tables
with the same columns, and raw binary COPY TO of those tables parsed with
numpy. Also measured: the same raw COPY into tables that have the primary keys
tgsis uses, to show what index maintenance alone costs.

    python bench/transfer.py [--side 1000] [--repeat 3]    # TGSIS_PG=system|embedded
"""

from __future__ import annotations

import argparse

import numpy as np
import psycopg
from psycopg import sql
from timing import timed

import tgsis
from tgsis.db import features as F
from tgsis.db.copy import decode_rows, encode_rows
from tgsis.db.local import LocalServer, find_binaries


def grid_surface(side: int) -> tgsis.Surface:
    """A bumpy side x side grid: side**2 vertices, 2 (side-1)**2 triangles, property 'porosity'."""
    u, v = np.meshgrid(np.linspace(0, 10_000, side), np.linspace(0, 10_000, side))
    z = 200 * np.sin(u / 700) * np.cos(v / 900)
    vertices = np.stack([u.ravel(), v.ravel(), z.ravel()], axis=1)
    idx = np.arange(side * side).reshape(side, side)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel()
    triangles = np.concatenate([np.stack([a, b, d], 1), np.stack([a, d, c], 1)])
    porosity = np.random.default_rng(1).random(len(vertices))
    return tgsis.Surface(vertices, triangles, vertex_properties={"porosity": porosity}, name="bench")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--side", type=int, default=1000)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()

    surface = grid_surface(args.side)
    n, m = surface.n_vertices, surface.n_cells
    rows = n + m + n
    print(f"surface: {n} vertices, {m} triangles, 1 vertex property ({rows} rows)")
    binaries = find_binaries()
    print(f"server: {binaries.describe()} (throwaway cluster, fsync off)")
    server = LocalServer.throwaway(binaries)
    try:
        admin = psycopg.connect(server.dsn(), autocommit=True)
        admin.execute("CREATE DATABASE bench")
        conn = psycopg.connect(server.dsn("bench"))
        tgsis.install(conn, method="sql")  # this checkout's SQL, not an extension another build installed
        F.create_feature_class(conn, "horizon", "SURFACE", cell_properties={"porosity": "double precision"})

        geoid = np.full(max(n, m), 1, dtype=np.int64)
        payloads = {
            "vrtx": encode_rows(
                [
                    (geoid[:n], "int8"),
                    (np.arange(n), "int8"),
                    (surface.vertices[:, 0], "float8"),
                    (surface.vertices[:, 1], "float8"),
                    (surface.vertices[:, 2], "float8"),
                ]
            ),
            "trgl": encode_rows(
                [
                    (geoid[:m], "int8"),
                    (np.arange(m), "int8"),
                    (surface.cells[:, 0], "int8"),
                    (surface.cells[:, 1], "int8"),
                    (surface.cells[:, 2], "int8"),
                ]
            ),
            "prop": encode_rows(
                [(geoid[:n], "int8"), (np.arange(n), "int8"), (surface.vertex_properties["porosity"], "float8")]
            ),
        }
        columns = {
            "vrtx": "geoid int8, vrtxid int8, x float8, y float8, z float8",
            "trgl": "geoid int8, trglid int8, v1 int8, v2 int8, v3 int8",
            "prop": "geoid int8, idx int8, porosity float8",
        }
        keys = {"vrtx": "geoid, vrtxid", "trgl": "geoid, trglid", "prop": "geoid, idx"}
        for name, cols in columns.items():
            conn.execute(f"CREATE TABLE raw_{name} ({cols})")
            conn.execute(f"CREATE TABLE keyed_{name} ({cols}, PRIMARY KEY ({keys[name]}))")
        conn.commit()

        def raw_copy(prefix: str) -> None:
            for name, payload in payloads.items():
                conn.execute(f"TRUNCATE {prefix}_{name}")
                with conn.cursor().copy(f"COPY {prefix}_{name} FROM STDIN (FORMAT binary)") as copy:
                    copy.write(payload)
            conn.commit()

        def upload() -> None:
            conn.execute("TRUNCATE tgsis.vrtx, tgsis.trgl, horizon_cellpros, horizon, tgsis.geometry CASCADE")
            conn.commit()
            F.insert_feature(conn, "horizon", surface)
            conn.commit()

        raw_up = timed(lambda: raw_copy("raw"), args.repeat)
        keyed_up = timed(lambda: raw_copy("keyed"), args.repeat)
        up = timed(upload, args.repeat)
        feature_id = int(conn.execute("SELECT _geoid FROM horizon").fetchone()[0])  # type: ignore[index]
        conn.commit()

        def raw_download() -> None:
            for name, types in (
                ("vrtx", ["int8", "int8", "float8", "float8", "float8"]),
                ("trgl", ["int8"] * 5),
                ("prop", ["int8", "int8", "float8"]),
            ):
                with conn.cursor().copy(sql.SQL("COPY raw_{} TO STDOUT (FORMAT binary)").format(sql.SQL(name))) as copy:
                    decode_rows(b"".join(bytes(c) for c in copy), types)
            conn.commit()

        fetched: list[tgsis.Mesh] = []

        def download() -> None:
            fetched[:] = [F.fetch_feature(conn, "horizon", feature_id).mesh]  # type: ignore[list-item]
            conn.commit()

        raw_down = timed(raw_download, args.repeat)
        down = timed(download, args.repeat)
        assert fetched[0].same_as(surface), "downloaded surface differs from the uploaded one"
        conn.close()
        admin.close()
    finally:
        server.destroy()

    print(f"raw COPY into unindexed tables:     {raw_up:6.2f} s  {rows / raw_up:12,.0f} rows/s")
    print(f"raw COPY into keyed tables:         {keyed_up:6.2f} s  {rows / keyed_up:12,.0f} rows/s")
    print(f"tgsis upload (insert_feature):      {up:6.2f} s  {rows / up:12,.0f} rows/s")
    print(f"raw COPY TO + numpy parse:          {raw_down:6.2f} s  {rows / raw_down:12,.0f} rows/s")
    print(f"tgsis download (fetch_feature):     {down:6.2f} s  {rows / down:12,.0f} rows/s")
    print(f"upload_s: {up:.3f}")
    print(f"upload_rows_per_s: {rows / up:.0f}")
    print(f"upload_vs_raw_copy: {raw_up / up:.2f}")
    print(f"upload_vs_keyed_raw_copy: {keyed_up / up:.2f}")
    print(f"download_s: {down:.3f}")
    print(f"download_rows_per_s: {rows / down:.0f}")
    print(f"download_vs_raw_copy: {raw_down / down:.2f}")


if __name__ == "__main__":
    main()
