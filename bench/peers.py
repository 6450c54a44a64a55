"""tgsis against its peers on the same mesh and server: PostGIS ``TIN Z`` and three ``bytea`` arrays (issue 20).

A side x side grid surface (default 1000: 1M vertices, 2M triangles, one
vertex property) stored three ways in one throwaway cluster of the system
PostgreSQL (PostGIS comes from the distribution's packages, installed for
it; ``TGSIS_PG`` can point elsewhere if PostGIS is there):

- tgsis: ``insert_feature`` / ``fetch_feature`` (and ``checkout``, which
  downloads the same rows with their ids);
- PostGIS: one row of ``geometry(TINZ)``, uploaded as the EWKB that
  ``tgsis.postgis.mesh_to_ewkb`` builds (timed), downloaded as
  ``ST_AsEWKB`` and parsed by ``tgsis.postgis.mesh_from_wkb``;
- bytea: one row of three ``bytea`` columns (vertices (n, 3) float64,
  triangles (m, 3) int64, the property (n,) float64; ``STORAGE EXTERNAL``:
  not compressed), the physical limit of getting these bytes in and out of
  PostgreSQL here.

The TIN keeps the server's default TOAST compression (pglz on PostgreSQL
15), which is what makes it small on disk and slow to upload.

Every side runs in turn within each repetition (drift hits all alike),
medians of ``--repeat``. Storage: ``pg_total_relation_size`` of each table
(heap, TOAST, indexes) and ``pg_indexes_size`` of each.

Model 1 is stored as tgsis installs it (chunks by default since issue 40;
``--storage rows`` for the row tables): truncations and sizes go through
``tgsis.storage_table``, so each figure is of the storage in use. Issue 40's
figures are printed beside: bytes per vertex, the download and upload
against the ``bytea`` row, and one vertex read by key through the view
``tgsis.vrtx`` (what a psql user types) and through ``tgsis.vertex``.

The class's property table is stored in chunks by default
(``--property-storage chunks``: ``tgsis.store_class_in_chunks`` on the new,
empty class before the upload, unless the class is in chunks already, as
the flip of a static class's default makes it) or as rows
(``--property-storage rows``: ``tgsis.store_class_in_rows`` if the class was
made in chunks). The upload and download then move the property's chunks
whole (docs/storage.md, "The bulk paths of property chunks").

``--edit`` (with ``--versioned`` and ``--repeat 1``: a repetition's
upload deletes the object before, and on versioned storage the closed
versions stay) adds the versioned disk figure: after the timed runs, the
1 % spatially local edit of ``bench/checkin.py --bytes`` (``region``: a
square of 1 % of the vertices moved, their porosity changed, the diagonals
of its quads flipped) is checked in as a new version (a child of DEFAULT);
the storage is then measured holding both versions of the object
(``bytes_per_vertex_before_edit``, ``bytes_per_vertex``,
``storage_vs_tin``).

    python bench/peers.py [--side 1000] [--repeat 3] [--versioned] [--storage chunks|rows]
        [--property-storage chunks|rows] [--edit] [--order file|spatial]

``--order spatial`` uploads the surface renumbered by ``tgsis.mesh.spatial_order``
(``insert_feature(..., order="spatial")``): a local edit then touches few chunks.
"""

from __future__ import annotations

import argparse
import os
from typing import Any

import numpy as np
import psycopg
from checkin import local_edit, same_grid_surface
from timing import paired
from transfer import grid_surface

import tgsis
from tgsis.db import checkin as C
from tgsis.db import features as F
from tgsis.db import versions as V
from tgsis.db.copy import encode_rows
from tgsis.db.local import LocalServer, find_binaries
from tgsis.mesh import spatial_order
from tgsis.postgis import mesh_from_wkb, mesh_to_ewkb


def sizes(conn: psycopg.Connection[Any], tables: list[str]) -> dict[str, tuple[int, int]]:
    """(total bytes, index bytes) of each table."""
    result = {}
    for table in tables:
        row = conn.execute(
            "SELECT pg_total_relation_size(%s::regclass), pg_indexes_size(%s::regclass)", (table, table)
        ).fetchone()
        assert row is not None
        result[table] = (int(row[0]), int(row[1]))
    return result


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--side", type=int, default=1000)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--versioned", action="store_true", help="feature versioning on (rows go to _ver storage)")
    parser.add_argument("--storage", choices=("chunks", "rows"), default="chunks", help="model 1's storage")
    parser.add_argument(
        "--property-storage",
        choices=("chunks", "rows"),
        default="chunks",
        help="the class's property table: chunks (store_class_in_chunks) or rows",
    )
    parser.add_argument(
        "--edit",
        action="store_true",
        help="versioned disk figure: a 1 %% local edit checked in as a new version before the sizes",
    )
    parser.add_argument("--order", choices=("file", "spatial"), default="file", help="insert_feature's order")
    args = parser.parse_args()
    if args.edit and (not args.versioned or args.repeat != 1):
        parser.error("--edit measures one object's two versions: give --versioned and --repeat 1")

    surface = grid_surface(args.side)
    n, m = surface.n_vertices, surface.n_cells
    print(f"surface: {n} vertices, {m} triangles, 1 vertex property")
    binaries = find_binaries(os.environ.get("TGSIS_PG", "system"))
    print(f"server: {binaries.describe()} (throwaway cluster, fsync off)")
    server = LocalServer.throwaway(binaries)
    try:
        with psycopg.connect(server.dsn(), autocommit=True) as admin:
            admin.execute("CREATE DATABASE bench")
        conn = psycopg.connect(server.dsn("bench"))
        tgsis.install(conn, method="sql", storage=args.storage)
        conn.execute("CREATE EXTENSION postgis")
        print("PostGIS", conn.execute("SELECT postgis_lib_version()").fetchone()[0])  # type: ignore[index]
        F.create_feature_class(conn, "horizon", "SURFACE", cell_properties={"porosity": "double precision"})
        conn.commit()
        in_chunks = V.storage_table(conn, "public", "horizon_cellpros") != "public.horizon_cellpros"
        if args.property_storage == "chunks" and not in_chunks:
            conn.execute("SELECT tgsis.store_class_in_chunks('horizon')")
        elif args.property_storage == "rows" and in_chunks:
            conn.execute("SELECT tgsis.store_class_in_rows('horizon')")
        if args.versioned:
            tgsis.enable_feature_versioning(conn)
        conn.commit()
        # the relations that hold model 1's rows and the property rows: chunk tables, _ver tables or the tables
        tables = [
            V.storage_table(conn, s, t)
            for s, t in (("tgsis", "vrtx"), ("tgsis", "trgl"), ("public", "horizon_cellpros"))
        ]
        print("storage:", ", ".join(tables), f"(property: {args.property_storage})")
        conn.execute("CREATE TABLE tin_peer (id int PRIMARY KEY, geom geometry(TINZ))")
        conn.execute("CREATE TABLE bytea_peer (id int PRIMARY KEY, vertices bytea, triangles bytea, porosity bytea)")
        for column in ("vertices", "triangles", "porosity"):  # the raw bytes: out of line, not compressed
            conn.execute(f"ALTER TABLE bytea_peer ALTER COLUMN {column} SET STORAGE EXTERNAL")
        # the bound of any upload keeping rows and keys: raw binary COPY of payloads built beforehand
        # into tables with the same columns and primary keys
        conn.execute(
            "CREATE TABLE keyed_vrtx (geoid int8, vrtxid int8, x float8, y float8, z float8, "
            "PRIMARY KEY (geoid, vrtxid))"
        )
        conn.execute(
            "CREATE TABLE keyed_trgl (geoid int8, trglid int8, v1 int8, v2 int8, v3 int8, PRIMARY KEY (geoid, trglid))"
        )
        conn.execute("CREATE TABLE keyed_prop (geoid int8, idx int8, porosity float8, PRIMARY KEY (geoid, idx))")
        conn.commit()
        porosity = surface.vertex_properties["porosity"]
        one = np.ones(max(n, m), dtype=np.int64)
        payloads = {
            "vrtx": encode_rows(
                [
                    (one[:n], "int8"),
                    (np.arange(n), "int8"),
                    (surface.vertices[:, 0], "float8"),
                    (surface.vertices[:, 1], "float8"),
                    (surface.vertices[:, 2], "float8"),
                ]
            ),
            "trgl": encode_rows(
                [
                    (one[:m], "int8"),
                    (np.arange(m), "int8"),
                    (surface.cells[:, 0], "int8"),
                    (surface.cells[:, 1], "int8"),
                    (surface.cells[:, 2], "int8"),
                ]
            ),
            "prop": encode_rows([(one[:n], "int8"), (np.arange(n), "int8"), (porosity, "float8")]),
        }

        def keyed_copy() -> None:
            conn.execute("TRUNCATE keyed_vrtx, keyed_trgl, keyed_prop")
            conn.commit()
            for name, payload in payloads.items():
                with conn.cursor().copy(f"COPY keyed_{name} FROM STDIN (FORMAT binary)") as copy:
                    copy.write(payload)
            conn.commit()

        state: dict[str, Any] = {}

        def tgsis_up() -> None:
            if not args.versioned:
                conn.execute(f"TRUNCATE {', '.join(tables)}, horizon, tgsis.geometry CASCADE")
            if args.versioned and "geoid" in state:
                F.delete_feature(conn, "horizon", state["geoid"])
            conn.commit()
            state["geoid"] = F.insert_feature(conn, "horizon", surface, order=args.order)
            conn.commit()

        def postgis_up() -> None:
            conn.execute("TRUNCATE tin_peer")
            conn.commit()
            conn.execute("INSERT INTO tin_peer VALUES (1, ST_GeomFromEWKB(%b))", (mesh_to_ewkb(surface, srid=None),))
            conn.commit()

        def bytea_up() -> None:
            conn.execute("TRUNCATE bytea_peer")
            conn.commit()
            conn.execute(
                "INSERT INTO bytea_peer VALUES (1, %b, %b, %b)",
                (surface.vertices.tobytes(), surface.cells.astype(np.int64).tobytes(), porosity.tobytes()),
            )
            conn.commit()

        ups = paired([tgsis_up, postgis_up, bytea_up, keyed_copy], args.repeat)
        conn.execute("ANALYZE")
        conn.commit()
        fetched: dict[str, tgsis.Mesh] = {}

        def tgsis_down() -> None:
            fetched["tgsis"] = F.fetch_feature(conn, "horizon", state["geoid"]).mesh  # type: ignore[assignment]
            conn.commit()

        def tgsis_checkout() -> None:
            fetched["checkout"] = C.checkout(conn, state["geoid"], "horizon").mesh
            conn.commit()

        def postgis_down() -> None:
            with conn.cursor(binary=True) as cursor:
                row = cursor.execute("SELECT ST_AsEWKB(geom) FROM tin_peer WHERE id = 1").fetchone()
            assert row is not None
            fetched["postgis"] = mesh_from_wkb(row[0])
            conn.commit()

        def bytea_down() -> None:
            with conn.cursor(binary=True) as cursor:
                row = cursor.execute("SELECT vertices, triangles, porosity FROM bytea_peer WHERE id = 1").fetchone()
            assert row is not None
            fetched["bytea"] = tgsis.Surface(
                np.frombuffer(row[0]).reshape(-1, 3),
                np.frombuffer(row[1], dtype=np.int64).reshape(-1, 3),
                vertex_properties={"porosity": np.frombuffer(row[2])},
            )
            conn.commit()

        downs = paired([tgsis_down, tgsis_checkout, postgis_down, bytea_down], args.repeat)
        stored_as = spatial_order(surface) if args.order == "spatial" else surface  # the stored ids' order
        assert fetched["tgsis"].same_as(stored_as), "tgsis: downloaded surface differs from the uploaded one"
        assert fetched["checkout"].same_as(stored_as), "checkout: surface differs from the uploaded one"
        assert np.array_equal(fetched["bytea"].vertices, surface.vertices)
        assert fetched["postgis"].n_cells == m, "PostGIS: triangle count differs"
        # one vertex by key, as a psql user asks it of the view, and through tgsis.vertex (warm, medians)
        probe = int(n // 2 + 17)
        expected = tuple(float(c) for c in stored_as.vertices[probe])

        def by_view() -> None:
            row = conn.execute(
                "SELECT x, y, z FROM tgsis.vrtx WHERE geoid = %s AND vrtxid = %s", (state["geoid"], probe)
            ).fetchone()
            assert row == expected, row
            conn.commit()

        def by_function() -> None:
            row = conn.execute("SELECT x, y, z FROM tgsis.vertex(%s, %s)", (state["geoid"], probe)).fetchone()
            assert row == expected, row
            conn.commit()

        keyed = paired([by_view, by_function], max(args.repeat, 5))
        before_edit: dict[str, tuple[int, int]] = {}
        if args.edit:
            conn.autocommit = True
            conn.execute("VACUUM")
            conn.autocommit = False
            before_edit = sizes(conn, tables)
            conn.commit()
            tgsis.create_version(conn, "edit")
            conn.commit()
            with tgsis.in_version(conn, "edit"):
                co = C.checkout(conn, state["geoid"], "horizon")
                assert co.mesh is not None
                edited = local_edit(co.mesh, args.side, "region")
                tgsis.checkin(conn, co, edited)
                conn.commit()
                stored_edit = F.fetch_feature(conn, "horizon", state["geoid"]).mesh
            assert isinstance(stored_edit, tgsis.Mesh) and same_grid_surface(stored_edit, edited, args.side)
            conn.commit()
        # what narrower rows would store: int4 local ids, columns ordered for alignment (same keys)
        conn.execute("CREATE TABLE narrow_vrtx AS SELECT geoid, x, y, z, vrtxid::int4 AS vrtxid FROM tgsis.vrtx")
        conn.execute(
            "CREATE TABLE narrow_trgl AS SELECT geoid, trglid::int4 AS trglid, vrtxid1::int4 AS vrtxid1, "
            "vrtxid2::int4 AS vrtxid2, vrtxid3::int4 AS vrtxid3 FROM tgsis.trgl"
        )
        conn.execute("CREATE TABLE narrow_prop AS SELECT _geoid, porosity, _idx::int4 AS _idx FROM horizon_cellpros")
        conn.execute("ALTER TABLE narrow_vrtx ADD PRIMARY KEY (geoid, vrtxid)")
        conn.execute("ALTER TABLE narrow_trgl ADD PRIMARY KEY (geoid, trglid)")
        conn.execute("ALTER TABLE narrow_prop ADD PRIMARY KEY (_geoid, _idx)")
        conn.commit()
        conn.autocommit = True
        conn.execute("VACUUM")
        narrow = ["narrow_vrtx", "narrow_trgl", "narrow_prop"]
        stored = sizes(conn, [*tables, *narrow, "tin_peer", "bytea_peer"])
        conn.close()
    finally:
        server.destroy()

    names = [
        "tgsis upload (insert_feature)",
        "PostGIS TIN Z upload (EWKB built + INSERT)",
        "bytea upload",
        "raw COPY into keyed tables (payloads prebuilt)",
    ]
    for name, t in zip(names, ups):
        print(f"{name:48s} {t:7.3f} s")
    names = ["tgsis download (fetch_feature)", "tgsis checkout", "PostGIS TIN Z download + parse", "bytea download"]
    for name, t in zip(names, downs):
        print(f"{name:48s} {t:7.3f} s")
    for table, (total, index) in stored.items():
        print(f"{table:24s} {total / 1e6:8.1f} MB total, {index / 1e6:7.1f} MB indexes")
    tgsis_bytes = sum(stored[t][0] for t in tables)
    print(f"tgsis_upload_s: {ups[0]:.3f}")
    print(f"postgis_upload_s: {ups[1]:.3f}")
    print(f"bytea_upload_s: {ups[2]:.3f}")
    print(f"keyed_copy_upload_s: {ups[3]:.3f}")
    print(f"tgsis_download_s: {downs[0]:.3f}")
    print(f"tgsis_checkout_s: {downs[1]:.3f}")
    print(f"postgis_download_s: {downs[2]:.3f}")
    print(f"bytea_download_s: {downs[3]:.3f}")
    print(f"tgsis_bytes: {tgsis_bytes}")
    print(f"tin_bytes: {stored['tin_peer'][0]}")
    print(f"bytea_bytes: {stored['bytea_peer'][0]}")
    print(f"download_vs_bytea: {downs[0] / downs[3]:.2f}")
    print(f"checkout_vs_bytea: {downs[1] / downs[3]:.2f}")
    print(f"postgis_download_vs_tgsis: {downs[2] / downs[0]:.2f}")
    print(f"upload_vs_postgis: {ups[0] / ups[1]:.2f}")
    print(f"storage_vs_tin: {tgsis_bytes / stored['tin_peer'][0]:.2f}")
    narrow_bytes = sum(stored[t][0] for t in narrow)
    print(f"narrow_bytes: {narrow_bytes}")
    print(f"narrow_storage_vs_tin: {narrow_bytes / stored['tin_peer'][0]:.2f}")
    print(f"keyed_copy_vs_postgis: {ups[3] / ups[1]:.2f}")
    print(f"one_vertex_by_view_ms: {keyed[0] * 1e3:.2f}")
    print(f"one_vertex_by_function_ms: {keyed[1] * 1e3:.3f}")
    print(f"bytes_per_vertex: {tgsis_bytes / n:.1f}")
    print(f"bytes_per_vertex_without_property: {sum(stored[t][0] for t in tables[:2]) / n:.1f}")
    print(f"property_storage: {args.property_storage}")
    print(f"order: {args.order}")
    print(f"property_bytes_per_vertex: {stored[tables[2]][0] / n:.1f}")
    print(f"upload_vs_bytea: {ups[0] / ups[2]:.2f}")
    if before_edit:
        whole = sum(before_edit[t][0] for t in tables)
        print(f"bytes_per_vertex_before_edit: {whole / n:.1f}")
        print(f"storage_vs_tin_before_edit: {whole / stored['tin_peer'][0]:.2f}")
        print(f"edit_growth_share_pct: {100 * (tgsis_bytes - whole) / whole:.2f}")
        for table in tables:
            print(
                f"{table:24s} {before_edit[table][0] / 1e6:8.1f} MB before the edit, {stored[table][0] / 1e6:8.1f} after"
            )


if __name__ == "__main__":
    main()
