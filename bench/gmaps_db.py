"""Model 4 in the database: store, fetch, check and snapshot a 1M-triangle surface (6M darts) and a solid.

Meshes as in ``bench/gmaps.py``: a grid of ``--nx`` x ``--ny`` quads split
into triangles (1000 x 500: 1M triangles, 6M darts, 18M alpha rows) with a
porosity per face, and a block of tetrahedra (``--cubes``^3 cubes, 6 each)
evolving between two geometry instants. Timed, medians of ``--repeat`` runs:

- ``insert_gmap`` (checks in numpy, one binary COPY per table, one
  transaction) against a raw binary COPY of the same rows (payloads built
  beforehand) into tables with the same keys, in the same run;
- ``fetch_gmap`` against raw ``COPY TO`` of those tables parsed with numpy;
- ``tgsis.gmap_check`` in SQL over the 6M darts, against reading the 18M
  alpha rows in key order as one array (what any check that reads them
  costs), run in turn;
- the snapshot at t of the evolving solid (``tgsis.gmap_at`` +
  ``gmap_points_at`` through :func:`tgsis.gmap_at`, points interpolated
  between its two instants) against the download of the same solid stored
  static (``fetch_gmap``).

    python bench/gmaps_db.py [--nx 1000 --ny 500 --cubes 26 --repeat 3]    # TGSIS_PG=system|embedded
"""

from __future__ import annotations

import argparse

import numpy as np
import psycopg
from gmaps import block_tetrahedra, grid_triangles
from timing import paired, timed

import tgsis
from tgsis import gmaps
from tgsis.db import features as F
from tgsis.db import gmaps as G
from tgsis.db.copy import decode_rows, encode_rows
from tgsis.db.local import LocalServer, find_binaries

RAW = {  # the rows insert_gmap writes for a one-period, one-instant map, as plain keyed tables
    "dart": ("geoid int8, dartid int8, timem float8, nodeid int8, acellid int8, positive bool", "geoid, dartid"),
    "alpha": ("geoid int8, level int2, dartid int8, dartid2 int8", "geoid, dartid, level"),
    "vertex": (
        "geoid int8, timem float8, timet float8, nodeid int8, coordinate float8[]",
        "geoid, timem, timet, nodeid",
    ),
    "cell": ("geoid int8, acellid int8, timem float8, celllevel int2", "geoid, acellid"),
    "prop": ("geoid int8, timem float8, timet float8, idx int8, porosity float8", "geoid, timem, timet, idx"),
}


def payloads(g: gmaps.GMap, porosity: np.ndarray) -> dict[str, tuple[bytes, list[str]]]:
    d, k, n = g.n_darts, g.n_points, g.dimension
    cells = g.cells(2)
    c = int(cells.max()) + 1
    one = np.ones(max(d * (n + 1), k), dtype=np.int64)
    zero = np.zeros(max(d, k, c))
    rows = {
        "dart": [
            (one[:d], "int8"),
            (np.arange(d), "int8"),
            (zero[:d], "float8"),
            (g.vertex, "int8"),
            (cells, "int8"),
            (g.orientation(), "bool"),
        ],
        "alpha": [
            (one[: d * (n + 1)], "int8"),
            (np.tile(np.arange(n + 1, dtype=np.int16), d), "int2"),  # key order
            (np.repeat(np.arange(d), n + 1), "int8"),
            (np.ascontiguousarray(g.alpha.T).reshape(-1), "int8"),
        ],
        "vertex": [
            (one[:k], "int8"),
            (zero[:k], "float8"),
            (zero[:k], "float8"),
            (np.arange(k), "int8"),
            (g.points, "float8[3]"),
        ],
        "cell": [(one[:c], "int8"), (np.arange(c), "int8"), (zero[:c], "float8"), (np.full(c, 2, np.int16), "int2")],
        "prop": [
            (one[:c], "int8"),
            (zero[:c], "float8"),
            (zero[:c], "float8"),
            (np.arange(c), "int8"),
            (porosity, "float8"),
        ],
    }
    return {name: (encode_rows(columns), [w for _, w in columns]) for name, columns in rows.items()}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--nx", type=int, default=1000)
    parser.add_argument("--ny", type=int, default=500)
    parser.add_argument("--cubes", type=int, default=26)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()

    vs, ts = grid_triangles(args.nx, args.ny)
    porosity = np.random.default_rng(4).random(len(ts))
    surface = gmaps.GMap.from_triangles(vs, ts, cell_properties={"porosity": porosity})
    vt, tt = block_tetrahedra(args.cubes)
    solid = gmaps.GMap.from_tetrahedra(vt, tt)
    moving = gmaps.EvolvingGMap([gmaps.GMapPeriod([0.0, 1.0], solid, np.stack([solid.points, solid.points * 1.5]))])
    raw = payloads(surface, porosity)
    rows = surface.n_darts * (surface.dimension + 2) + surface.n_points + 2 * surface.n_cells(2)
    print(
        f"surface: {surface.n_darts} darts, {surface.n_points} points, {surface.n_cells(2)} faces ({rows} rows); "
        f"solid: {solid.n_darts} darts, {len(tt)} tetrahedra"
    )
    binaries = find_binaries()
    print(f"server: {binaries.describe()} (throwaway cluster, fsync off)")
    server = LocalServer.throwaway(binaries)
    try:
        admin = psycopg.connect(server.dsn(), autocommit=True)
        admin.execute("CREATE DATABASE bench")
        conn = psycopg.connect(server.dsn("bench"))
        tgsis.install(conn, method="sql")  # this checkout's SQL
        F.create_feature_class(
            conn, "faces", "GMAP", time_model="GMAP", cell_level=2, cell_properties={"porosity": "float8"}
        )
        F.create_feature_class(conn, "solids", "GMAP", time_model="GMAP", cell_level=3)
        for name, (columns, key) in RAW.items():
            conn.execute(f"CREATE TABLE raw_{name} ({columns}, PRIMARY KEY ({key}))")
        conn.commit()

        def raw_empty() -> None:
            conn.execute("TRUNCATE " + ", ".join(f"raw_{name}" for name in raw))
            conn.commit()

        def raw_copy() -> None:
            for name, (payload, _) in raw.items():
                with conn.cursor().copy(f"COPY raw_{name} FROM STDIN (FORMAT binary)") as copy:
                    copy.write(payload)
            conn.commit()

        def empty() -> None:
            # as the raw tables: the previous copy deleted, then the tables emptied (no dead rows, untimed)
            conn.execute("SELECT tgsis.delete_stored_geometries(array_agg(_geoid)) FROM faces")
            conn.execute(
                "TRUNCATE faces, faces_cellpros, tgsis.gmap, tgsis.gmap_timem, tgsis.gmap_timet, "
                "tgsis.gmap_node, tgsis.gmap_vertex, tgsis.gmap_dart, tgsis.gmap_alpha, tgsis.gmap_cell"
            )
            conn.commit()

        def store() -> None:
            F.insert_feature(conn, "faces", surface)
            conn.commit()

        raw_up = timed(raw_copy, args.repeat, raw_empty)
        up = timed(store, args.repeat, empty)
        geoid = int(conn.execute("SELECT _geoid FROM faces").fetchone()[0])  # type: ignore[index]
        conn.commit()

        def raw_download() -> None:
            for name, (_, types) in raw.items():
                with conn.cursor().copy(f"COPY raw_{name} TO STDOUT (FORMAT binary)") as copy:
                    decode_rows(b"".join(bytes(c) for c in copy), types)
            conn.commit()

        fetched: list[gmaps.EvolvingGMap] = []

        def fetch() -> None:
            fetched[:] = [G.fetch_gmap(conn, "faces", geoid)]
            conn.commit()

        raw_down = timed(raw_download, args.repeat)
        down = timed(fetch, args.repeat)
        back = fetched[0].at(0.0)
        assert back is not None and back.same_as(surface), "the fetched G-map differs from the stored one"

        def check() -> None:
            problems = G.gmap_check(conn, geoid)
            conn.commit()
            assert problems == [], problems

        def ordered_read() -> None:
            # the floor of any check that reads the involutions in key order: the 18M alpha rows as one array
            conn.execute("SET LOCAL enable_sort = off")
            conn.execute(
                "SELECT cardinality(ARRAY(SELECT dartid2 FROM tgsis.gmap_alpha WHERE geoid = %s "
                "ORDER BY dartid, level))",
                (geoid,),
            )
            conn.commit()

        t_read, t_check = paired([ordered_read, check], args.repeat)
        static = F.insert_feature(conn, "solids", solid)
        evolving = F.insert_feature(conn, "solids", moving)
        conn.commit()
        snap: list[gmaps.GMap | None] = []

        def static_download() -> None:
            G.fetch_gmap(conn, "solids", static)
            conn.commit()

        def snapshot() -> None:
            snap[:] = [G.gmap_at(conn, evolving, 0.25)]
            conn.commit()

        t_static = timed(static_download, args.repeat)
        t_snap = timed(snapshot, args.repeat)
        expected = moving.at(0.25)
        assert snap[0] is not None and expected is not None and snap[0].same_as(expected), "snapshot differs"
        conn.close()
        admin.close()
    finally:
        server.destroy()

    print(f"raw COPY into keyed tables:          {raw_up:7.2f} s  {rows / raw_up:12,.0f} rows/s")
    print(f"insert_gmap (checks, COPY per table): {up:7.2f} s  {rows / up:12,.0f} rows/s")
    print(f"raw COPY TO + numpy parse:           {raw_down:7.2f} s")
    print(f"fetch_gmap:                          {down:7.2f} s")
    print(f"alpha rows read in key order (floor): {t_read:7.2f} s")
    print(f"tgsis.gmap_check, {surface.n_darts} darts:    {t_check:7.2f} s")
    print(f"solid stored static, fetch_gmap:     {t_static:7.2f} s")
    print(f"evolving solid, gmap_at(t):          {t_snap:7.2f} s")
    print(f"store_s: {up:.3f}")
    print(f"store_vs_raw_copy: {raw_up / up:.2f}")
    print(f"fetch_s: {down:.3f}")
    print(f"fetch_vs_raw_copy: {raw_down / down:.2f}")
    print(f"gmap_check_s: {t_check:.3f}")
    print(f"gmap_check_vs_ordered_read: {t_check / t_read:.2f}")
    print(f"snapshot_s: {t_snap:.3f}")
    print(f"snapshot_vs_static_fetch: {t_snap / t_static:.2f}")


if __name__ == "__main__":
    main()
