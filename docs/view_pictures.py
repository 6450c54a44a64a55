"""The pictures of the browser view in docs/pictures (README, docs/view.md), taken in headless Chromium.

Runs ``tgsis view --db tgsis_demo`` (the database ``tgsis demo`` leaves on
the local server, or ``--dsn``) in a process of its own, opens its pages in
the distribution's Chromium (``/usr/bin/chromium``, Playwright from the test
extra) and writes small PNGs of the demo's faults, the fault history at
-1 Ma and release 6.1 of a fault coloured by its displacement from 5.3.
``make pictures`` runs it after the demo.

    python docs/view_pictures.py [--dsn DSN] [--dir build/pictures]
"""

from __future__ import annotations

import argparse
import io
import os
import re
import signal
import subprocess
import sys
from pathlib import Path

from PIL import Image
from playwright.sync_api import sync_playwright

CHROMIUM = "/usr/bin/chromium"
CHROMIUM_ARGS = ["--use-angle=swiftshader", "--enable-unsafe-swiftshader", "--ignore-gpu-blocklist"]
WIDTH = 640  # pixels of the written pictures


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--dsn", help="the server whose database tgsis_demo to show (default: the local server)")
    parser.add_argument("--dir", default="build/pictures", help="where the PNGs go")
    args = parser.parse_args()
    folder = Path(args.dir)
    folder.mkdir(parents=True, exist_ok=True)
    command = [sys.executable, "-m", "tgsis.cli", *(["--dsn", args.dsn] if args.dsn else []),
               "view", "--db", "tgsis_demo", "--port", "0"]
    server = subprocess.Popen(command, stdout=subprocess.PIPE, text=True, env={**os.environ, "PYTHONUNBUFFERED": "1"})
    try:
        assert server.stdout is not None
        found = re.search(r"(http://127\.0\.0\.1:\d+)/classes", server.stdout.readline())
        assert found, "tgsis view did not start (run tgsis demo first)"
        url = found.group(1)
        with sync_playwright() as playwright:
            browser = playwright.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
            page = browser.new_page(viewport={"width": 1000, "height": 820})
            page.goto(f"{url}/classes?class=faults")
            faults = page.locator("#features tbody tr").evaluate_all("rows => rows.map(r => r.dataset.id)")
            page.goto(f"{url}/classes?class=fault_history")
            history = page.locator("#features tbody tr").evaluate_all("rows => rows.map(r => r.dataset.id)")
            shots = {
                "view_scene.png": f"/scene?ids={','.join(faults)}",
                "view_time.png": f"/scene?ids={history[0]}&t=-1&exaggeration=2",
                "view_compare.png": f"/compare?id={faults[0]}&a=DEFAULT&b=cfm6.1&mode=displacement&marks=0",
            }
            for name, path in shots.items():
                page.goto(url + path)
                page.wait_for_function("document.body.dataset.state === 'error' || "
                                       "Number(document.body.dataset.frame) >= 1", timeout=120_000)
                assert page.evaluate("document.body.dataset.state") == "ready", page.text_content("#status")
                box = page.locator("main").bounding_box()
                assert box is not None
                png = page.screenshot(clip={"x": 0, "y": 0, "width": 1000, "height": box["y"] + box["height"]})
                image = Image.open(io.BytesIO(png)).convert("RGB")
                image = image.resize((WIDTH, round(image.height * WIDTH / image.width)), Image.LANCZOS)
                image.quantize(colors=128).save(folder / name, optimize=True)
                print(f"wrote {folder / name} ({url}{path})")
            browser.close()
    finally:
        server.send_signal(signal.SIGTERM)
        server.wait(60)


if __name__ == "__main__":
    main()
