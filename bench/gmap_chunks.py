"""G-map darts and involutions (model 4) in rows vs in chunks: bytes on disk per dart, upload, fetch, check.

A block of ``--cubes``^3 unit cubes, 6 tetrahedra each, as a 3-G-map
(24 darts per tetrahedron: 13^3 cubes give 316,368 darts and 1,265,472
involution rows), stored static with a cell per volume. In one process, on
one throwaway cluster: first with ``tgsis.gmap_dart`` and ``gmap_alpha`` as
rows, then emptied and switched to chunks (``tgsis.store_in_chunks``) and
stored again: the client encodes the chunks in numpy and sends them in one
binary COPY per table (``tgsis.db._chunk_transfer.upload_rows``); then,
still on chunks, stored with that upload declining, so that the rows go
through ``tgsis.insert_chunk_rows`` (the server's set-based path, what the
client did before plan K; ``store_server_path``). Bytes are
``pg_total_relation_size`` (heap, TOAST, indexes) of the two tables' storage
(``tgsis.storage_table``), emptied by TRUNCATE after the timed runs, holding
the map stored once more, after a VACUUM, divided by the darts; the points,
nodes and cells stay rows and are left out. Times are medians of
``--repeat`` runs of each side, rows first (not interleaved: the switch
lies between them). On chunks the check is timed twice: as the bench's
superuser (``gmap_conditions_hold`` reads the chunk arrays) and as a role
granted the faces only (it reads the faces, as every role did before plan
N, G). The snapshot at t (``tgsis.db.gmaps.gmap_at``) is timed the same two
ways: on chunks it decodes the period's chunk arrays in the client (plan O,
E), a role granted the faces only reads them; so is the whole map's read (``tgsis.db.gmaps.fetch_gmap``),
which decodes the object's darts and involutions (and points in chunks) in the client on chunks (plan O,
F). ``--points chunks`` switches
the positions (``tgsis.gmap_vertex``) to chunks with the darts (their bytes
are not counted; the default leaves them rows, as the figures before plan O).

    python bench/gmap_chunks.py [--cubes 13 --repeat 3 --points rows|chunks]    # TGSIS_PG=system|embedded
"""

from __future__ import annotations

import argparse
from typing import Any

import numpy as np
import psycopg
from gmaps import block_tetrahedra
from psycopg import sql
from timing import bench_database, timed

from tgsis import gmaps
from tgsis.db import features as F
from tgsis.db import gmaps as G

TABLES = ("gmap_dart", "gmap_alpha")


def storage_names(conn: psycopg.Connection[Any]) -> dict[str, str]:
    """The relation storing each table (rows, or its chunk table), quoted by the server (format('%I.%I'))."""
    stored: dict[str, str] = {}
    for t in TABLES:
        row = conn.execute("SELECT tgsis.storage_table('tgsis', %s)", (t,)).fetchone()
        assert row is not None
        stored[t] = str(row[0])
    conn.commit()
    return stored


def sizes(conn: psycopg.Connection[Any]) -> dict[str, int]:
    """Bytes of each table's storage (heap, TOAST, indexes), after a VACUUM."""
    conn.commit()
    stored = storage_names(conn)
    conn.autocommit = True
    for name in stored.values():
        conn.execute(sql.SQL("VACUUM (ANALYZE) {}").format(sql.SQL(name)))  # type: ignore[arg-type]
    conn.autocommit = False
    got = {}
    for t, name in stored.items():
        row = conn.execute("SELECT pg_total_relation_size(%s::regclass)", (name,)).fetchone()
        assert row is not None
        got[t] = int(row[0])
    conn.commit()
    return got


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--cubes", type=int, default=13)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--points", choices=("rows", "chunks"), default="rows")
    args = parser.parse_args()

    vt, tt = block_tetrahedra(args.cubes)
    solid = gmaps.GMap.from_tetrahedra(vt, tt)
    darts = solid.n_darts
    print(f"solid: {len(tt)} tetrahedra, {darts} darts, {darts * (solid.dimension + 1)} involution rows")
    results: dict[str, dict[str, float]] = {}
    with bench_database() as conn:
        F.create_feature_class(conn, "solids", "GMAP", time_model="GMAP", cell_level=3)
        conn.commit()

        def empty() -> None:
            conn.execute("SELECT tgsis.delete_stored_geometries(array_agg(_geoid)) FROM solids")
            conn.execute("DELETE FROM solids")
            conn.commit()

        for storage in ("rows", "chunks"):
            if storage == "chunks":
                empty()
                for t in (*TABLES, *(("gmap_vertex",) if args.points == "chunks" else ())):
                    conn.execute("SELECT tgsis.store_in_chunks(%s)", (t,))
                conn.commit()
            geoids: list[int] = []

            def store() -> None:
                geoids[:] = [F.insert_feature(conn, "solids", solid)]
                conn.commit()

            t_store = timed(store, args.repeat, empty)
            # the bytes of one fresh store: emptied tables (no dead rows of the timed runs), the map stored once more
            empty()
            conn.execute(
                sql.SQL("TRUNCATE {}").format(
                    sql.SQL(", ").join(sql.SQL(n) for n in storage_names(conn).values())  # type: ignore[arg-type]
                )
            )
            conn.commit()
            store()
            geoid = geoids[0]
            size = sizes(conn)
            fetched: list[Any] = []

            def fetch() -> None:
                fetched[:] = [G.fetch_gmap(conn, "solids", geoid)]
                conn.commit()

            def check() -> None:
                problems = G.gmap_check(conn, geoid)
                conn.commit()
                assert problems == [], problems

            snapshot: list[Any] = []

            def at() -> None:
                snapshot[:] = [G.gmap_at(conn, geoid, 0.0)]
                conn.commit()

            t_fetch = timed(fetch, args.repeat)
            back = fetched[0].at(0.0)
            assert back is not None and back.same_as(solid), f"the G-map fetched from {storage} differs"
            t_at = timed(at, args.repeat)
            assert snapshot[0] is not None and snapshot[0].same_as(solid), f"gmap_at on {storage} differs"
            t_check = timed(check, args.repeat)
            results[storage] = {
                "store": t_store,
                "fetch": t_fetch,
                "at": t_at,
                "check": t_check,
                **{f"bytes_{t}": float(size[t]) for t in TABLES},
            }
            if storage == "chunks":  # the check through the faces (before plan N, G), as a role granted them only
                conn.execute("CREATE ROLE bench_faces_only IN ROLE tgsis_reader")
                # (the points' chunk table too when they are in chunks: the role reads their face)
                points = "SELECT tgsis.storage_table('tgsis', 'gmap_vertex')" if args.points == "chunks" else None
                extra = [str(r[0]) for r in conn.execute(points).fetchall()] if points else []
                for name in [*storage_names(conn).values(), *extra]:
                    revoke = sql.SQL("REVOKE SELECT ON {} FROM tgsis_reader").format(sql.SQL(name))  # type: ignore[arg-type]
                    conn.execute(revoke)
                conn.execute("SET ROLE bench_faces_only")
                conn.commit()
                results[storage]["check_faces"] = timed(check, args.repeat)
                results[storage]["at_faces"] = timed(at, args.repeat)
                results[storage]["fetch_faces"] = timed(fetch, args.repeat)
                back = fetched[0].at(0.0)
                assert back is not None and back.same_as(solid), "the G-map fetched through the faces differs"
                conn.execute("RESET ROLE")
                conn.commit()
            if storage == "chunks":  # the server's set-based path (the client's upload declining), for the ratio
                client_upload = G.upload_rows  # (insert_gmap's name for it)
                G.upload_rows = lambda *args: False  # type: ignore[assignment]
                try:
                    results[storage]["store_server_path"] = timed(store, args.repeat, empty)
                finally:
                    G.upload_rows = client_upload
            if storage == "chunks":  # every dart in one chunk per 1024 ids (and per level)
                chunks = conn.execute("SELECT count(*) FROM tgsis.gmap_alpha_chunk").fetchone()
                print(f"gmap_alpha_chunk rows: {chunks[0] if chunks else 0}")  # type: ignore[index]
                conn.commit()

    for storage, r in results.items():
        per = {t: r[f"bytes_{t}"] / darts for t in TABLES}
        print(
            f"{storage:6}: dart {per['gmap_dart']:6.1f} B/dart, alpha {per['gmap_alpha']:6.1f} B/dart, "
            f"both {sum(per.values()):6.1f} B/dart; store {r['store']:6.2f} s, fetch {r['fetch']:6.2f} s, "
            f"gmap_check {r['check']:6.2f} s"
        )
    rows, chunks = results["rows"], results["chunks"]
    both = {s: sum(results[s][f"bytes_{t}"] for t in TABLES) / darts for s in results}
    print(f"darts: {darts}")
    print(f"rows_bytes_per_dart: {both['rows']:.1f}")
    print(f"chunks_bytes_per_dart: {both['chunks']:.1f}")
    print(f"chunks_vs_rows_bytes: {both['chunks'] / both['rows']:.3f}")
    print(f"chunks_dart_bytes_per_dart: {chunks['bytes_gmap_dart'] / darts:.1f}")
    print(f"chunks_alpha_bytes_per_dart: {chunks['bytes_gmap_alpha'] / darts:.1f}")
    print(f"store_rows_s: {rows['store']:.3f}")
    print(f"store_chunks_vs_rows: {chunks['store'] / rows['store']:.2f}")
    print(f"store_chunks_server_path_vs_rows: {chunks['store_server_path'] / rows['store']:.2f}")
    print(f"store_chunks_client_vs_server_path: {chunks['store'] / chunks['store_server_path']:.3f}")
    print(f"fetch_rows_s: {rows['fetch']:.3f}")
    print(f"fetch_chunks_vs_rows: {chunks['fetch'] / rows['fetch']:.2f}")
    print(f"fetch_chunks_through_faces_vs_rows: {chunks['fetch_faces'] / rows['fetch']:.2f}")
    print(f"gmap_check_chunks_vs_rows: {chunks['check'] / rows['check']:.2f}")
    print(f"gmap_check_chunks_through_faces_vs_rows: {chunks['check_faces'] / rows['check']:.2f}")
    print(f"points: {args.points}")
    print(f"gmap_at_rows_s: {rows['at']:.3f}")
    print(f"gmap_at_chunks_vs_rows: {chunks['at'] / rows['at']:.2f}")
    print(f"gmap_at_chunks_through_faces_vs_rows: {chunks['at_faces'] / rows['at']:.2f}")
    assert np.isfinite(both["chunks"])


if __name__ == "__main__":
    main()
