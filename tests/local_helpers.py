"""Helpers for tests of the local server: private homes and process checks."""

from __future__ import annotations

import contextlib
import os
import shutil
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Iterator
from pathlib import Path

from tgsis.db.local import LocalServer, find_binaries

SRC = Path(__file__).resolve().parents[1] / "src"


def process_alive(pid: int | None) -> bool:
    """Whether ``pid`` runs (a zombie waiting for a parent that never reaps counts as gone)."""
    if pid is None:
        return False
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return False
    return stat.rsplit(")", 1)[1].split()[0] != "Z"


def wait_until(condition: Callable[[], bool], timeout: float = 30, step: float = 0.1) -> bool:
    """Poll ``condition`` until it holds or ``timeout`` seconds pass; return its last value."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if condition():
            return True
        time.sleep(step)
    return condition()


@contextlib.contextmanager
def private_home() -> Iterator[Path]:
    """A TGSIS_HOME the server's OS user can reach (pytest's tmp_path is private to root).

    Any server left in it is stopped on exit.
    """
    home = Path(tempfile.mkdtemp(prefix="tgsis-home-"))
    home.chmod(0o755)
    try:
        yield home
    finally:
        for root in home.glob("pg*"):
            with contextlib.suppress(Exception):
                LocalServer(root, find_binaries()).stop("immediate")
        shutil.rmtree(home, ignore_errors=True)


def child_env(**extra: str) -> dict[str, str]:
    """Environment for a child Python that uses this checkout and the same binaries."""
    env = {k: v for k, v in os.environ.items() if k not in ("TGSIS_TEST_DSN", "TGSIS_DSN") and not k.startswith("PG")}
    env["TGSIS_PG"] = str(find_binaries().bindir)
    env["TGSIS_TEST_DOCKER"] = "0"
    env.update(extra)
    return env


def tgsis_cli(*args: str, home: Path, timeout: float = 120, **env: str) -> subprocess.CompletedProcess[str]:
    """Run the ``tgsis`` console script of this venv with a private TGSIS_HOME (and more ``env``)."""
    return subprocess.run(
        [str(Path(sys.executable).parent / "tgsis"), *args],
        env=child_env(TGSIS_HOME=str(home), **env),
        capture_output=True,
        text=True,
        timeout=timeout,
        check=False,
    )
