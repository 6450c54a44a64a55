"""What a small change costs on chunks, against a whole-object read (issue 40, plan E area O).

A bumpy 1000 x 1000 grid (1,000,000 vertices, 1,996,002 triangles, one
vertex property, ``transfer.grid_surface``) in the spatial order
(``tgsis.mesh.spatial_order``: the order a region's ids fall in few chunks)
is uploaded into a versioned class on the storage a fresh install makes
(chunks, model 1's default). Version ``v``
moves a 100 x 100 patch (10,000 vertices, 1 % of them, spatially local) by
``z - 3``; DEFAULT moves another patch by ``z + 5`` (each written as a
check-in writes, ``tgsis.write_object_rows``): the object changed on
both sides, disjointly. Timed in one process (medians of ``--repeat``, every
write rolled back), each next to the whole-object reads of the same run:

- ``whole_fetch_s``: ``tgsis.fetch_feature`` of the object (the download);
- ``whole_face_scan_s``: ``count(*)`` of the object's vertices and triangles
  through the faces ``tgsis.vrtx`` / ``tgsis.trgl`` (every chunk decoded);
- ``sql_regions_s``: ``tgsis.mesh_merge_regions('v', geoid)`` (the SQL region
  detection, ``tgsis.mesh_merge_work``: its step 5, the one-ring margin);
- ``sql_merge_s``: the psql ``tgsis.merge_version('v')`` (regions, the merge's
  validity check ``tgsis.merge_mesh_validity``, the write);
- ``py_read_change_s``: ``read_merge_change`` (``_read_change``: the change
  and its one-ring, what the Python merge by region reads);
- ``sql_merge_mesh_merge_work_s``, ``sql_merge_merge_mesh_validity_s``,
  ``sql_merge_merge_geometry_row_s``: those functions' own times in the psql
  merge (``track_functions``, ``pg_stat_xact_user_functions``);
- ``py_merge_s``: the Python ``tgsis.db.merging.merge_version('v')`` (what it
  wrote printed: the same at every repeat, every repeat rolled back);
- ``geometry_row_s``: ``_update_geometry_row_from_rows`` (after a partial
  write: the box and counts of the object);
- ``check_static_geometry_s``, ``ewkb_geometry_s``, ``compare_geometries_s``
  (the object against a second upload of the same surface): the SQL readers
  of a whole object (by nature object-sized: for the ratio);
- ``write_object_rows_rr_s``: ``tgsis.write_object_rows`` of 100 moved
  vertices in a REPEATABLE READ transaction (refused ``TG300`` after deciding
  whether a stored row changes) and ``write_object_rows_rc_s`` the same write
  in READ COMMITTED.

``--parts``: the surface has two GOCAD parts, kept as runs in ``tgsis.part``
(the class has no cell property ``part``), and ``v`` also moves the first
1 % of the cell ids into a third part, every run of the object rewritten
(as a check-in that changes a part writes them).

Each ``_s`` figure is printed with ``_vs_fetch`` (its ratio to
``whole_fetch_s``). The machine is shared: ratios in one run, not times.

    python bench/object_costs.py [--side 1000] [--repeat 3] [--parts]   # TGSIS_PG=system|embedded
"""

from __future__ import annotations

import argparse
import os
import time
from collections.abc import Callable
from typing import Any

import numpy as np
import psycopg
from timing import bench_database, timed
from transfer import grid_surface

import tgsis
from tgsis.db import _merge_states, _state_write
from tgsis.db import features as F
from tgsis.db import merging as M

Conn = psycopg.Connection[Any]


def rolled_back(conn: Conn, action: Callable[[], Any], isolation: str | None = None) -> Callable[[], Any]:
    """``action`` in a transaction rolled back afterwards.

    The transaction is open before ``action`` runs: a function that opens its own when the connection is
    idle (``conn.transaction()``, ``tgsis.in_version``: the Python merge, the geometry row's update) would
    commit it, and the next repeat would time a merge with nothing left to merge (the 0.03 s ``py_merge_s``
    of plan F's runs). Opened, such a function runs in a savepoint this rollback undoes.
    """

    def run() -> Any:
        conn.rollback()
        conn.execute(f"SET TRANSACTION ISOLATION LEVEL {isolation or 'READ COMMITTED'}")  # (opens it)
        try:
            return action()
        finally:
            conn.rollback()

    return run


def patch_ids(vertices: np.ndarray, x0: float, y0: float, width: float) -> np.ndarray:
    """The ids of the vertices in the square [x0, x0 + width) x [y0, y0 + width)."""
    inside = (
        (vertices[:, 0] >= x0) & (vertices[:, 0] < x0 + width) & (vertices[:, 1] >= y0) & (vertices[:, 1] < y0 + width)
    )
    return np.flatnonzero(inside).astype(np.int64)


def move(conn: Conn, version: str, geoid: int, ids: np.ndarray, xyz: np.ndarray, dz: float) -> None:
    """Move vertices ``ids`` (at ``xyz`` (n, 3)) by ``dz`` in ``version`` as a check-in writes them, committed."""
    moved = xyz.copy()
    moved[:, 2] += dz
    with tgsis.in_version(conn, version):
        if conn.execute("SELECT tgsis.stored_in_chunks('vrtx')").fetchone() == (True,):
            conn.execute(
                "SELECT tgsis.write_object_rows('vrtx', %s, '{}'::bigint[], %s, %s)",
                (geoid, ids.tolist(), moved.T.tolist()),
            )
        else:  # rows: the row path's update by key
            conn.execute(
                "UPDATE tgsis.vrtx SET z = z + %s WHERE geoid = %s AND vrtxid = ANY(%s)", (dz, geoid, ids.tolist())
            )
    conn.commit()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--side", type=int, default=1000)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument(
        "--parts",
        action="store_true",
        help="two GOCAD parts kept as runs (tgsis.part); v also moves the first 1 %% of the cell ids into part 2,"
        " every run rewritten as a check-in writes them",
    )
    args = parser.parse_args()

    surface = tgsis.mesh.spatial_order(grid_surface(args.side))
    n = surface.n_vertices
    half = surface.n_cells // 2
    if args.parts:
        parts = np.zeros(surface.n_cells, dtype=np.int64)
        parts[half:] = 1
        surface.cell_properties = {**surface.cell_properties, "part": parts}
    step = 10_000 / (args.side - 1)
    width = step * args.side / 10  # a tenth of the side: 1 % of the vertices
    child_patch = patch_ids(surface.vertices, 2_000, 2_000, width)
    parent_patch = patch_ids(surface.vertices, 6_000, 6_000, width)
    with bench_database() as conn:
        storage = conn.execute("SELECT tgsis.storage_table('tgsis', 'vrtx')").fetchone()
        print(f"storage: tgsis.vrtx stored in {storage[0] if storage else '?'}")
        F.create_feature_class(conn, "horizon", "SURFACE", cell_properties={"porosity": "double precision"})
        tgsis.enable_feature_versioning(conn)
        conn.commit()
        start = time.perf_counter()
        geoid = F.insert_feature(conn, "horizon", surface)
        conn.commit()
        other = F.insert_feature(conn, "horizon", surface)  # compare_geometries' second object
        conn.commit()
        print(
            f"surface: {n} vertices, {surface.n_cells} triangles, spatial order, uploaded in "
            f"{time.perf_counter() - start:.2f} s"
        )
        conn.autocommit = True
        conn.execute("VACUUM ANALYZE")
        conn.autocommit = False
        tgsis.create_version(conn, "v")
        conn.commit()
        move(conn, "v", geoid, child_patch, surface.vertices[child_patch], -3.0)
        move(conn, "DEFAULT", geoid, parent_patch, surface.vertices[parent_patch], 5.0)
        if args.parts:  # v's part change: every run rewritten (as _state_write._write_parts writes them)
            span = (0, surface.n_cells // 100 - 1)
            runs = [(0, span[1], 2), (span[1] + 1, half - 1, 0), (half, surface.n_cells - 1, 1)]
            with tgsis.in_version(conn, "v"):
                conn.execute("DELETE FROM tgsis.part WHERE geoid = %s", (geoid,))
                for first, last, part in runs:
                    conn.execute(
                        "INSERT INTO tgsis.part (geoid, firstid, lastid, part) VALUES (%s, %s, %s, %s)",
                        (geoid, first, last, part),
                    )
            conn.commit()
            print(f"parts: runs {runs} (v), two runs (DEFAULT)")
        print(
            f"version v moved {len(child_patch)} vertices, DEFAULT {len(parent_patch)} others "
            f"({100 * len(child_patch) / n:.2f} % each)"
        )

        fig: dict[str, float] = {}
        r = args.repeat
        fig["whole_fetch_s"] = timed(rolled_back(conn, lambda: tgsis.fetch_feature(conn, "horizon", geoid)), r)
        fig["whole_face_scan_s"] = timed(
            rolled_back(
                conn,
                lambda: (
                    conn.execute("SELECT count(*) FROM tgsis.vrtx WHERE geoid = %s", (geoid,)).fetchone(),
                    conn.execute("SELECT count(*) FROM tgsis.trgl WHERE geoid = %s", (geoid,)).fetchone(),
                ),
            ),
            r,
        )
        regions = rolled_back(
            conn, lambda: conn.execute("SELECT * FROM tgsis.mesh_merge_regions('v', %s)", (geoid,)).fetchall()
        )()
        print(f"regions (SQL): {len(regions)}")
        fig["sql_regions_s"] = timed(
            rolled_back(
                conn, lambda: conn.execute("SELECT * FROM tgsis.mesh_merge_regions('v', %s)", (geoid,)).fetchall()
            ),
            r,
        )
        fig["py_read_change_s"] = timed(
            rolled_back(conn, lambda: _merge_states.read_merge_change(conn, "v", geoid), "REPEATABLE READ"), r
        )

        def geometry_row() -> None:
            with tgsis.in_version(conn, "v"):
                _state_write._update_geometry_row_from_rows(conn, geoid, "trgl")

        fig["geometry_row_s"] = timed(rolled_back(conn, geometry_row), r)
        for name, query in (
            ("check_static_geometry_s", "SELECT * FROM tgsis.check_static_geometry(%s)"),
            ("ewkb_geometry_s", "SELECT length(tgsis.ewkb_geometry(%s))"),
            ("compare_geometries_s", "SELECT count(*) FROM tgsis.compare_geometries(%s, %s)"),
        ):
            params = (geoid, other) if query.count("%s") == 2 else (geoid,)
            try:
                fig[name] = timed(rolled_back(conn, lambda q=query, p=params: conn.execute(q, p).fetchall()), r)
            except psycopg.Error as error:
                conn.rollback()
                print(f"{name}: not measured ({type(error).__name__}: {str(error).splitlines()[0]})")

        moved = child_patch[:100]
        xyz = surface.vertices[moved].copy()
        xyz[:, 2] += 1.0
        write = "SELECT tgsis.write_object_rows('vrtx', %s, '{}'::bigint[], %s, %s)"
        wargs = (geoid, moved.tolist(), xyz.T.tolist())

        def write_rr() -> None:
            try:
                conn.execute(write, wargs)
                raise AssertionError("write_object_rows was not refused in REPEATABLE READ")
            except psycopg.Error as error:
                assert error.sqlstate == "TG300", error.sqlstate

        if storage == ("tgsis.vrtx_chunk",):
            fig["write_object_rows_rr_s"] = timed(rolled_back(conn, write_rr, "REPEATABLE READ"), r)
            fig["write_object_rows_rc_s"] = timed(rolled_back(conn, lambda: conn.execute(write, wargs)), r)
        fig["sql_merge_s"] = timed(rolled_back(conn, lambda: conn.execute("SELECT tgsis.merge_version('v')")), r)
        # the psql merge's parts by the functions' own times (track_functions), medians of --repeat merges, each
        # rolled back
        own: dict[str, list[float]] = {}
        for _ in range(r):
            conn.rollback()
            conn.execute("SET track_functions = 'all'")
            conn.execute("SELECT tgsis.merge_version('v')")
            for name, total in conn.execute(
                "SELECT funcname, total_time FROM pg_stat_xact_user_functions"
                " WHERE funcname IN ('mesh_merge_work', 'merge_mesh_validity', 'merge_geometry_row')"
            ):
                own.setdefault(f"sql_merge_{name}_s", []).append(float(total) / 1000)
            conn.rollback()
        fig.update({name: float(np.median(values)) for name, values in sorted(own.items())})
        merged: list[tuple[int, int, int, int]] = []

        def py_merge() -> None:
            result = M.merge_version(conn, "v")
            merged.append(
                (result.rows_by_region, result.rows_copied, result.chunk_versions_copied, len(result.objects))
            )

        fig["py_merge_s"] = timed(rolled_back(conn, py_merge), r)
        # every repeat merged the same (nothing of an earlier one was kept), and something
        assert len(set(merged)) == 1 and sum(merged[0][:3]) > 0, merged
        print(
            "py_merge wrote: {} rows by region, {} rows and {} chunk versions copied, {} object(s) by region".format(
                *merged[0]
            )
        )

        load = os.getloadavg()[0]
        print(f"load: {load:.1f} (1 min, {os.cpu_count()} cores)")
        for name, value in fig.items():
            print(f"{name}: {value:.3f}")
        for name, value in fig.items():
            if name != "whole_fetch_s":
                print(f"{name[:-2]}_vs_fetch: {value / fig['whole_fetch_s']:.2f}")


if __name__ == "__main__":
    main()
