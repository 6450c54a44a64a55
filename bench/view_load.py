"""The browser view: a 1M-vertex, 2M-triangle surface from navigation to the scene drawn, in headless Chromium.

The surface is stored (model 1, one vertex property), the view is served in
this process (uvicorn in a thread, as ``tgsis view``), and the distribution's
Chromium (``/usr/bin/chromium``, WebGL on SwiftShader: no GPU) opens
``/scene?ids=ID``; the time runs from ``page.goto`` to the page saying it has
drawn the frame (``document.body.dataset.frame``), medians of ``--repeat``
fresh pages. Baselines in the same run: ``tgsis.fetch_feature`` alone (the
download the endpoint starts with) and a GET of the endpoint alone (download
+ packing + transfer, no browser); and the size the same arrays would have as
JSON lists.

    python bench/view_load.py [--side 1000] [--repeat 3]    # TGSIS_PG=system|embedded; target: view_load_s <= 3
"""

from __future__ import annotations

import argparse
import json
import socket
import statistics
import threading
import time
import urllib.request

import psycopg
import uvicorn
from playwright.sync_api import sync_playwright

import tgsis
from tgsis.db.local import LocalServer, find_binaries
from tgsis.view.app import ViewConfig, create_app
from transfer import grid_surface

CHROMIUM = "/usr/bin/chromium"
CHROMIUM_ARGS = ["--use-angle=swiftshader", "--enable-unsafe-swiftshader", "--ignore-gpu-blocklist"]


def serve(conninfo: str) -> tuple[uvicorn.Server, threading.Thread, str]:
    sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    sock.bind(("127.0.0.1", 0))
    sock.listen(64)
    server = uvicorn.Server(uvicorn.Config(create_app(ViewConfig(conninfo, False, "bench")), log_level="warning"))
    thread = threading.Thread(target=server.run, kwargs={"sockets": [sock]}, daemon=True)
    thread.start()
    while not server.started:
        time.sleep(0.02)
    return server, thread, f"http://127.0.0.1:{sock.getsockname()[1]}"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--side", type=int, default=1000)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()

    surface = grid_surface(args.side)
    print(f"surface: {surface.n_vertices} vertices, {surface.n_cells} triangles, 1 vertex property")
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
            fid = tgsis.insert_feature(conn, "grid", surface)
            conn.commit()
        with psycopg.connect(dsn) as conn:
            fetches = []
            for _ in range(args.repeat):
                start = time.perf_counter()
                tgsis.fetch_feature(conn, "grid", fid)
                fetches.append(time.perf_counter() - start)
                conn.rollback()
        server, thread, url = serve(dsn)
        try:
            gets = []
            for _ in range(args.repeat):
                start = time.perf_counter()
                with urllib.request.urlopen(f"{url}/api/mesh/{fid}", timeout=120) as response:
                    body = response.read()
                gets.append(time.perf_counter() - start)
            loads = []
            with sync_playwright() as playwright:
                browser = playwright.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
                print(f"browser: Chromium {browser.version} (headless, SwiftShader)")
                for _ in range(args.repeat):
                    page = browser.new_page(viewport={"width": 1100, "height": 900})
                    start = time.perf_counter()
                    page.goto(f"{url}/scene?ids={fid}")
                    page.wait_for_function("document.body.dataset.state === 'error' || "
                                           "Number(document.body.dataset.frame) >= 1", timeout=120_000)
                    loads.append(time.perf_counter() - start)
                    state, status = page.evaluate("document.body.dataset.state"), page.text_content("#status")
                    assert state == "ready", status
                    page.close()
                browser.close()
        finally:
            server.should_exit = True
            thread.join(30)
    finally:
        local.destroy()

    as_json = len(json.dumps({"positions": surface.vertices.ravel().tolist(),
                              "indices": surface.triangles.ravel().tolist(),
                              "values": surface.vertex_properties["porosity"].tolist()}))
    print(f"fetch_feature: {', '.join(f'{t:.2f}' for t in fetches)} s")
    print(f"GET /api/mesh: {', '.join(f'{t:.2f}' for t in gets)} s, {len(body) / 1e6:.1f} MB binary "
          f"(as JSON lists: {as_json / 1e6:.1f} MB)")
    print(f"navigation to the scene drawn: {', '.join(f'{t:.2f}' for t in loads)} s ({status})")
    print(f"view_load_s: {statistics.median(loads):.2f}")
    print(f"view_endpoint_s: {statistics.median(gets):.2f}")
    print(f"view_fetch_feature_s: {statistics.median(fetches):.2f}")
    print(f"view_body_mb: {len(body) / 1e6:.1f}")
    print(f"view_json_lists_mb: {as_json / 1e6:.1f}")
    print(f"view_load_target_met: {statistics.median(loads) <= 3.0}")


if __name__ == "__main__":
    main()
