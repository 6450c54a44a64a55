"""The browser view's merge regions on a 1M-vertex surface: what they add to the conflict endpoint, in bytes and time.

A side x side bumpy grid (default 1000: 1M vertices, 2M triangles) stored and
versioned; DEFAULT moves a 25 x 40 block of 1,000 vertices in one corner, the
version e1 another 1,000-vertex block in the opposite corner (two regions that
merge by themselves), each one committed UPDATE through ``tgsis.vrtx``. The
view is served in a process of its own (``tgsis view --port 0``); medians of
``--repeat`` runs of:

- GET ``/api/mesh/ID?v=e1``: the mesh alone (the baseline);
- GET ``/api/conflict/ID?version=e1``: the mesh, who changed each vertex, and the regions (``tgsis.object_merge``
  in the same snapshot, then :func:`tgsis.view.regions.region_drawing`);
- ``tgsis.object_merge`` alone, and ``region_drawing`` alone;

the navigation to ``/conflicts?version=e1`` until the scene is drawn (headless Chromium, as
``bench/view_load.py``); and the bytes the regions add to the conflict body (their header entries, as
JSON, and the two uint32 arrays of positions), against the body's size and
against one float32 per vertex (what a per-vertex region array would cost).

    python bench/view_regions.py [--side 1000] [--repeat 3]
"""

from __future__ import annotations

import argparse
import json
import signal
import statistics
import time
import urllib.request

import numpy as np
import psycopg
from transfer import grid_surface
from view_load import drawn_navigations, serve

import tgsis
from tgsis.db.local import LocalServer, find_binaries
from tgsis.view.meshes import unpack
from tgsis.view.regions import region_drawing


def block(side: int, row: int, column: int) -> list[int]:
    """The ids of a 25 x 40 block of the grid from (row, column): 1,000 vertices."""
    return (((np.arange(25)[:, None] + row) * side) + np.arange(40)[None, :] + column).ravel().tolist()


def get(url: str) -> tuple[float, bytes]:
    start = time.perf_counter()
    with urllib.request.urlopen(url, timeout=600) as response:
        body = response.read()
    return time.perf_counter() - start, body


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--side", type=int, default=1000)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()

    side = args.side
    surface = grid_surface(side)
    print(f"surface: {surface.n_vertices} vertices, {surface.n_cells} triangles")
    binaries = find_binaries()
    print(f"server: {binaries.describe()} (throwaway cluster, fsync off)")
    local = LocalServer.throwaway(binaries)
    try:
        with psycopg.connect(local.dsn(), autocommit=True) as admin:
            admin.execute("CREATE DATABASE bench")
        dsn = local.dsn("bench")
        with psycopg.connect(dsn) as conn:
            tgsis.install(conn, method="sql")
            tgsis.create_feature_class(conn, "grid", "SURFACE", cell_properties={"porosity": "float8"})
            tgsis.enable_feature_versioning(conn)
            fid = tgsis.insert_feature(conn, "grid", surface)
            tgsis.create_version(conn, "e1")
            conn.commit()
            move = "UPDATE tgsis.vrtx SET z = z + %s WHERE geoid = %s AND vrtxid = ANY(%s)"
            conn.execute(move, (5.0, fid, block(side, 2, 2)))
            conn.commit()
            with tgsis.in_version(conn, "e1"):
                conn.execute(move, (-3.0, fid, block(side, side - 30, side - 45)))
                conn.commit()
        merges, drawings = [], []
        with psycopg.connect(dsn) as conn:
            for _ in range(args.repeat):
                start = time.perf_counter()
                merge = tgsis.object_merge(conn, "e1", fid)
                merges.append(time.perf_counter() - start)
                start = time.perf_counter()
                regions, arrays = region_drawing(merge, merge.child.vertex_ids, merge.child.cell_ids)
                drawings.append(time.perf_counter() - start)
        assert [r["state"] for r in regions] == ["merges-parent", "merges-child"], regions
        server, url = serve(dsn)
        try:
            meshes, conflicts = [], []
            for _ in range(args.repeat):
                t, mesh_body = get(f"{url}/api/mesh/{fid}?v=e1")
                meshes.append(t)
                t, body = get(f"{url}/api/conflict/{fid}?version=e1")
                conflicts.append(t)
            pages, _, _, status = drawn_navigations(f"{url}/conflicts?version=e1", args.repeat, timeout_ms=600_000)
        finally:
            server.send_signal(signal.SIGTERM)
            server.wait(30)
    finally:
        local.destroy()

    header, sent = unpack(body)
    assert [r["state"] for r in header["regions"]] == ["merges-parent", "merges-child"]
    region_json = len(json.dumps(header["regions"]))
    region_arrays = 4 * (len(sent["region_vertices"]) + len(sent["region_cells"]))
    added = region_json + region_arrays
    per_vertex = 4 * surface.n_vertices
    counts = [(r["ids"]["vertices"], r["ids"]["cells"]) for r in header["regions"]]
    print(f"regions (vertices, cells, margin included): {counts}")
    print(
        f"object_merge: {', '.join(f'{t:.2f}' for t in merges)} s; region_drawing: {', '.join(f'{t:.3f}' for t in drawings)} s"
    )
    print(f"GET /api/mesh: {', '.join(f'{t:.2f}' for t in meshes)} s, {len(mesh_body) / 1e6:.1f} MB")
    print(f"GET /api/conflict: {', '.join(f'{t:.2f}' for t in conflicts)} s, {len(body) / 1e6:.1f} MB")
    print(f"navigation to /conflicts drawn: {', '.join(f'{t:.2f}' for t in pages)} s ({status})")
    print(f"view_regions_json_bytes: {region_json}")
    print(f"view_regions_array_bytes: {region_arrays}")
    print(f"view_regions_added_bytes: {added}")
    print(f"view_regions_added_per_body: {added / len(body):.5f}")
    print(f"view_regions_added_per_vertex_array: {added / per_vertex:.4f}")
    print(f"view_region_drawing_s: {statistics.median(drawings):.3f}")
    print(f"view_object_merge_s: {statistics.median(merges):.2f}")
    print(f"view_mesh_endpoint_s: {statistics.median(meshes):.2f}")
    print(f"view_conflict_endpoint_s: {statistics.median(conflicts):.2f}")
    print(f"view_conflict_per_mesh_endpoint: {statistics.median(conflicts) / statistics.median(meshes):.2f}")
    print(f"view_conflicts_page_s: {statistics.median(pages):.2f}")


if __name__ == "__main__":
    main()
