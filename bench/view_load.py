"""The browser view: a 1M-vertex, 2M-triangle surface from navigation to the scene drawn, in headless Chromium.

The surface is stored (model 1, one vertex property), the view is served in
a process of its own (``tgsis view --port 0``), and the distribution's
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
import os
import re
import signal
import statistics
import subprocess
import sys
import time
import urllib.request

import psycopg
from playwright.sync_api import sync_playwright
from transfer import grid_surface

import tgsis
from tgsis.db.local import LocalServer, find_binaries

CHROMIUM = "/usr/bin/chromium"
CHROMIUM_ARGS = ["--use-angle=swiftshader", "--enable-unsafe-swiftshader", "--ignore-gpu-blocklist"]


def serve(conninfo: str) -> tuple[subprocess.Popen[str], str]:
    """``tgsis view`` in a process of its own, as a user runs it; its base URL."""
    process = subprocess.Popen(
        [sys.executable, "-m", "tgsis.cli", "--dsn", conninfo, "view", "--port", "0"],
        stdout=subprocess.PIPE,
        text=True,
        env={**os.environ, "PYTHONUNBUFFERED": "1"},
    )
    assert process.stdout is not None
    found = re.search(r"(http://127\.0\.0\.1:\d+)/classes", process.stdout.readline())
    assert found, "tgsis view did not start"
    return process, found.group(1)


def drawn_navigations(
    url: str, repeat: int, timeout_ms: float = 120_000
) -> tuple[list[float], list[dict[str, float]], str, str]:
    """Navigations to ``url`` in headless Chromium until the scene's first frame, ``repeat`` times, each page fresh.

    Returns the seconds of each, the page's own timings of each (``document.body.dataset.timings``, empty when
    the page keeps none), the browser's version and the last page's status line.
    """
    loads: list[float] = []
    phases: list[dict[str, float]] = []
    with sync_playwright() as playwright:
        browser = playwright.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
        try:
            for _ in range(repeat):
                page = browser.new_page(viewport={"width": 1100, "height": 900})
                start = time.perf_counter()
                page.goto(url)
                page.wait_for_function(
                    "document.body.dataset.state === 'error' || Number(document.body.dataset.frame) >= 1",
                    timeout=timeout_ms,
                )
                loads.append(time.perf_counter() - start)
                state, status = page.evaluate("document.body.dataset.state"), page.text_content("#status") or ""
                assert state == "ready", status
                phases.append(json.loads(page.evaluate("document.body.dataset.timings || '{}'")))
                page.close()
            return loads, phases, str(browser.version), status
        finally:
            browser.close()


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
        server, url = serve(dsn)
        try:
            gets = []
            for _ in range(args.repeat):
                start = time.perf_counter()
                with urllib.request.urlopen(f"{url}/api/mesh/{fid}", timeout=120) as response:
                    body = response.read()
                gets.append(time.perf_counter() - start)
            loads, phases, version, status = drawn_navigations(f"{url}/scene?ids={fid}", args.repeat)
            print(f"browser: Chromium {version} (headless, SwiftShader)")
        finally:
            server.send_signal(signal.SIGTERM)
            server.wait(30)
    finally:
        local.destroy()

    as_json = len(
        json.dumps(
            {
                "positions": surface.vertices.ravel().tolist(),
                "indices": surface.triangles.ravel().tolist(),
                "values": surface.vertex_properties["porosity"].tolist(),
            }
        )
    )
    print(f"fetch_feature: {', '.join(f'{t:.2f}' for t in fetches)} s")
    print(
        f"GET /api/mesh: {', '.join(f'{t:.2f}' for t in gets)} s, {len(body) / 1e6:.1f} MB binary "
        f"(as JSON lists: {as_json / 1e6:.1f} MB)"
    )
    print(f"navigation to the scene drawn: {', '.join(f'{t:.2f}' for t in loads)} s ({status})")
    for name in ("start", "download", "build", "draw"):
        print(f"  in the page, {name}: {', '.join(f'{p[name] / 1000:.2f}' for p in phases)} s")
    print(f"view_load_s: {statistics.median(loads):.2f}")
    print(f"view_endpoint_s: {statistics.median(gets):.2f}")
    print(f"view_fetch_feature_s: {statistics.median(fetches):.2f}")
    print(f"view_body_mb: {len(body) / 1e6:.1f}")
    print(f"view_json_lists_mb: {as_json / 1e6:.1f}")
    print(f"view_load_target_met: {statistics.median(loads) <= 3.0}")


if __name__ == "__main__":
    main()
