"""Shared by the bench scripts (run from this folder: ``python bench/NAME.py``)."""

from __future__ import annotations

import contextlib
import statistics
import time
from collections.abc import Callable, Iterator
from typing import Any

import psycopg

import tgsis
from tgsis.db.local import LocalServer, find_binaries


def timed(action: Callable[[], object], repeat: int, setup: Callable[[], object] | None = None) -> float:
    """Median wall time of ``action`` over ``repeat`` runs, in seconds (``setup`` runs untimed before each)."""
    samples = []
    for _ in range(repeat):
        if setup is not None:
            setup()
        start = time.perf_counter()
        action()
        samples.append(time.perf_counter() - start)
    return statistics.median(samples)


def paired(actions: list[Callable[[], object]], repeat: int) -> list[float]:
    """Median times of actions run in turn (so that drift of the machine hits all alike)."""
    samples: list[list[float]] = [[] for _ in actions]
    for _ in range(repeat):
        for action, into in zip(actions, samples):
            start = time.perf_counter()
            action()
            into.append(time.perf_counter() - start)
    return [statistics.median(s) for s in samples]


@contextlib.contextmanager
def bench_database(storage: str = "chunks") -> Iterator[psycopg.Connection[Any]]:
    """A connection to a database ``bench`` with tgsis, on a throwaway cluster stopped afterwards.

    The server comes from ``TGSIS_PG`` (system or embedded, see
    :func:`tgsis.db.local.find_binaries`); tgsis is installed from the client's
    own SQL sources, not from an extension some other build put in the
    server's share dir, so the functions measured are this checkout's.
    ``storage``: model 1's storage (``chunks``, the default install, or ``rows``).
    """
    binaries = find_binaries()
    print(f"server: {binaries.describe()} (throwaway cluster, fsync off)")
    server = LocalServer.throwaway(binaries)
    try:
        with psycopg.connect(server.dsn(), autocommit=True) as admin:
            admin.execute("CREATE DATABASE bench")
        with psycopg.connect(server.dsn("bench")) as conn:
            tgsis.install(conn, method="sql", storage=storage)  # type: ignore[arg-type]
            yield conn
    finally:
        server.destroy()
