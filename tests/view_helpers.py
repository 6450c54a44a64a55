"""What the browser view's tests share: a database to look at, the view served in a thread, headless Chromium.

The browser is the distribution's Chromium (``/usr/bin/chromium``, Debian
package ``chromium``) driven by Playwright: nothing is downloaded at test
time. WebGL runs on SwiftShader (software), so the scenes render without a GPU.
"""

from __future__ import annotations

import io
import socket
import threading
import time
import urllib.error
import urllib.request
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any

import numpy as np
import psycopg
import uvicorn
from PIL import Image

import tgsis
from tests.synthetic import flat_grid
from tgsis.view.app import ViewConfig, create_app

CHROMIUM = "/usr/bin/chromium"
CHROMIUM_ARGS = ["--use-angle=swiftshader", "--enable-unsafe-swiftshader", "--ignore-gpu-blocklist"]
BACKGROUND = np.array([244, 244, 240])  # the scenes' background (0xf4f4f0)
QUOTED_NAME = 'o\'brien "fault" <b>'


@dataclass
class ViewData:
    """The ids of what :func:`fill_view_database` stored."""

    top: int
    base: int
    quoted: int
    block: int
    moving: int
    layers: int
    hidden: int


def _bumpy(side: int, z: float, name: str) -> tgsis.Surface:
    grid = flat_grid(side, z)
    v = grid.vertices.copy()
    v[:, 2] += np.sin(v[:, 0] / 3.0) * np.cos(v[:, 1] / 4.0)
    return tgsis.Surface(v, grid.triangles, vertex_properties={"porosity": v[:, 0] / side}, name=name)


def fill_view_database(dsn: str) -> ViewData:
    """Classes of models 1 (surfaces, tetrahedra), 2 and 3, a class tgsis_reader may not read, versions and a conflict."""
    with psycopg.connect(dsn) as conn:
        tgsis.create_feature_class(
            conn,
            "horizons",
            "SURFACE",
            feature_properties={"unit": "text"},
            cell_properties={"porosity": "float8"},
            description="layer tops",
        )
        top = tgsis.insert_feature(conn, "horizons", _bumpy(20, 0.0, "top"), {"unit": "A"})
        base = tgsis.insert_feature(conn, "horizons", _bumpy(20, -6.0, "base"), {"unit": "B"})
        quoted = tgsis.insert_feature(conn, "horizons", _bumpy(4, 40.0, QUOTED_NAME), {"unit": "C"})
        tgsis.create_feature_class(conn, "blocks", "MULTITETRA")
        cube = (
            np.array(
                [[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0], [0, 0, 1], [1, 0, 1], [0, 1, 1], [1, 1, 1]], dtype=float
            )
            * 4
        )
        tets = [[0, 1, 3, 5], [0, 3, 2, 6], [0, 5, 4, 6], [3, 5, 6, 7], [0, 3, 5, 6]]
        block = tgsis.insert_feature(conn, "blocks", tgsis.TetraMesh(cube, tets, name="block"))
        tgsis.create_feature_class(conn, "moving", "SURFACE", time_model="EVOLVING", time_unit="Ma")
        start = flat_grid(12, -10.0)
        end = start.vertices + np.array([0.0, 0.0, 8.0]) * (start.vertices[:, [0]] / 11.0)
        moving = tgsis.insert_feature(
            conn,
            "moving",
            tgsis.EvolvingSurface(
                [tgsis.TopologyPeriod([-10.0, 0.0], start.triangles, [start.vertices, end])], name="tilting"
            ),
        )
        tgsis.create_feature_class(conn, "layers", "SURFACE", time_model="INSTANTS", time_unit="Ma")
        flat, dome = flat_grid(10, 20.0), flat_grid(10, 20.0)
        dome.vertices[:, 2] += 6 - ((dome.vertices[:, :2] - 4.5) ** 2).sum(axis=1) / 7
        layers = tgsis.insert_feature(conn, "layers", tgsis.SurfaceSeries([-5.0, -1.0], [flat, dome], name="salt"))
        tgsis.create_feature_class(conn, "secret", "SURFACE")
        hidden = tgsis.insert_feature(conn, "secret", flat_grid(3, 5.0))
        conn.execute("REVOKE SELECT ON public.secret FROM tgsis_reader")
        conn.commit()
        tgsis.enable_feature_versioning(conn)
        tgsis.create_version(conn, "edit", description="the top lifted in the west")
        conn.commit()
        with tgsis.in_version(conn, "edit"):
            conn.execute("UPDATE tgsis.vrtx SET z = z + 3 WHERE geoid = %s AND x < 5", (top,))
            conn.commit()
        conn.execute("UPDATE tgsis.vrtx SET z = z - 2 WHERE geoid = %s AND x > 15", (top,))
        conn.commit()
    return ViewData(top, base, quoted, block, moving, layers, hidden)


@contextmanager
def running_view(
    conninfo: str, *, writable: bool = False, default_version: str | None = None, host: str = "127.0.0.1"
) -> Iterator[str]:
    """The view of ``conninfo`` served by uvicorn in a thread on a free port of ``host``; yields its base URL.

    It answers the host names ``tgsis view --host HOST`` answers.
    """
    app = create_app(ViewConfig(conninfo, writable, "test", default_version), hosts=["127.0.0.1", "localhost", host])
    sock = socket.socket(socket.AF_INET6 if ":" in host else socket.AF_INET, socket.SOCK_STREAM)
    sock.bind((host, 0))
    sock.listen(64)
    server = uvicorn.Server(uvicorn.Config(app, log_level="warning"))
    thread = threading.Thread(target=server.run, kwargs={"sockets": [sock]}, daemon=True)
    thread.start()
    deadline = time.monotonic() + 20
    while not server.started:
        assert thread.is_alive() and time.monotonic() < deadline, "the view did not start"
        time.sleep(0.02)
    try:
        yield f"http://{f'[{host}]' if ':' in host else host}:{sock.getsockname()[1]}"
    finally:
        server.should_exit = True
        thread.join(20)
        sock.close()


def get(url: str) -> tuple[int, bytes, str]:
    """(status, body, content type) of a GET, errors included."""
    try:
        with urllib.request.urlopen(url, timeout=60) as response:
            return response.status, response.read(), response.headers.get("Content-Type", "")
    except urllib.error.HTTPError as exc:
        return exc.code, exc.read(), exc.headers.get("Content-Type", "")


@contextmanager
def chromium() -> Iterator[Any]:
    """Headless Chromium of the distribution, driven by Playwright."""
    from playwright.sync_api import sync_playwright

    with sync_playwright() as playwright:
        browser = playwright.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
        try:
            yield browser
        finally:
            browser.close()


@contextmanager
def watched_page(browser: Any, width: int, height: int) -> Iterator[Any]:
    """A page of its own browser context, ``width`` x ``height``; a script error on it fails the test at the end."""
    context = browser.new_context(viewport={"width": width, "height": height})
    page = context.new_page()
    errors: list[str] = []
    page.on("pageerror", lambda e: errors.append(str(e)))
    yield page
    context.close()
    assert errors == []


def wait_drawn(page: Any, frames: int = 1, timeout: float = 60_000) -> None:
    """Wait until the page has drawn ``frames`` frames (or failed: then the test fails with its message)."""
    page.wait_for_function(
        f"document.body.dataset.state === 'error' || "
        f"(document.body.dataset.state === 'ready' && Number(document.body.dataset.frame) >= {frames})",
        timeout=timeout,
    )
    state = page.evaluate("document.body.dataset.state")
    assert state == "ready", page.text_content("#status")


def canvas_pixels(page: Any) -> np.ndarray:
    """The scene's canvas as (h, w, 3) uint8, from a screenshot."""
    png = page.locator("#scene").screenshot()
    return np.asarray(Image.open(io.BytesIO(png)).convert("RGB"))


def drawn_fraction(pixels: np.ndarray) -> float:
    """The fraction of pixels that are not the background."""
    return float(np.mean(np.abs(pixels.astype(int) - BACKGROUND).sum(axis=2) > 30))


def changed_fraction(a: np.ndarray, b: np.ndarray) -> float:
    """The fraction of pixels that differ between two screenshots."""
    return float(np.mean(np.abs(a.astype(int) - b.astype(int)).sum(axis=2) > 30))
