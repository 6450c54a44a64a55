"""``tgsis view`` (issue 21): the command serves the view on 127.0.0.1, says where, and refuses what it cannot serve.

The command runs as a user runs it (a subprocess), on a free port; its first
line names the URL; the pages answer there; SIGTERM stops it. A database
without tgsis, and a port already taken, give one error line with a hint
in the command's flags.
"""

from __future__ import annotations

import os
import re
import signal
import socket
import subprocess
import sys

import psycopg

import tgsis
from tests.view_helpers import get
from tgsis.testing import TestServer


def _tgsis(*args: str) -> subprocess.Popen[str]:
    return subprocess.Popen(
        [sys.executable, "-m", "tgsis.cli", *args],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env={**os.environ, "PYTHONUNBUFFERED": "1"},
    )


def test_view_serves_the_database_and_stops_on_sigterm(db_dsn: str) -> None:
    with psycopg.connect(db_dsn) as conn:
        tgsis.create_feature_class(conn, "faults", "SURFACE")
        conn.commit()
    process = _tgsis("--dsn", db_dsn, "view", "--port", "0")
    try:
        assert process.stdout is not None
        line = process.stdout.readline()
        found = re.search(r"read-only\) at (http://127\.0\.0\.1:\d+/classes)", line)
        assert found, line + (process.stderr.read() if process.poll() is not None and process.stderr else "")
        status, body, _ = get(found.group(1))
        assert status == 200 and b'data-class="faults"' in body
        status, body, _ = get(found.group(1).replace("/classes", "/static/vendor/three/three.module.js"))
        assert (
            status == 200
            and b"REVISION" in get(found.group(1).replace("/classes", "/static/vendor/three/three.core.js"))[1]
        )
    finally:
        process.send_signal(signal.SIGTERM)
        process.wait(30)


def test_view_of_a_database_without_tgsis_is_refused(pg: TestServer, make_database: object) -> None:
    empty = make_database()  # type: ignore[operator]
    done = subprocess.run(
        [sys.executable, "-m", "tgsis.cli", "--dsn", empty, "view", "--port", "0"],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert done.returncode == 1
    assert "tgsis: error: tgsis is not installed in database" in done.stderr
    assert "--db NAME" in done.stderr


def test_view_on_a_port_in_use_says_so(db_dsn: str) -> None:
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen(1)
        port = taken.getsockname()[1]
        done = subprocess.run(
            [sys.executable, "-m", "tgsis.cli", "--dsn", db_dsn, "view", "--port", str(port)],
            capture_output=True,
            text=True,
            timeout=120,
        )
    assert done.returncode == 1
    assert f"cannot listen on 127.0.0.1:{port}" in done.stderr and "--port" in done.stderr
