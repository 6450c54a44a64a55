"""Connecting to a tgsis database.

Where to connect, first match wins:

1. the ``dsn`` argument (``--dsn`` on the command line);
2. ``$TGSIS_DSN``;
3. libpq's own environment (``PGHOST``, ``PGDATABASE``, ``PGSERVICE``, ...):
   an empty DSN lets libpq read it;
4. the local server tgsis runs by itself (:mod:`tgsis.db.local`), database
   ``tgsis``, with tgsis installed. The server is started on first use and
   stopped when the process exits, unless ``tgsis local start`` started it.
"""

from __future__ import annotations

import atexit
import os
import threading
from dataclasses import dataclass
from typing import Any, Literal

import psycopg
from psycopg.rows import TupleRow

from tgsis.arguments import checked
from tgsis.db.install import install
from tgsis.db.local import Lease, LocalServer
from tgsis.errors import reraise

__all__ = ["Target", "resolve_target", "connect", "local_dsn", "release_local_server", "LIBPQ_ENV"]

LOCAL_DATABASE = "tgsis"

#: libpq environment variables that name a server or database.
LIBPQ_ENV = ("PGHOST", "PGHOSTADDR", "PGPORT", "PGDATABASE", "PGUSER", "PGSERVICE")

Source = Literal["argument", "TGSIS_DSN", "libpq environment", "local server"]


@dataclass(frozen=True)
class Target:
    """Where :func:`connect` goes.

    Attributes
    ----------
    dsn : str or None
        Connection string; ``None`` means the local server.
    source : str
        Which rule chose it.
    """

    dsn: str | None
    source: Source


def resolve_target(dsn: str | None = None) -> Target:
    """Decide where to connect (see the module documentation for the order)."""
    if dsn:
        return Target(dsn, "argument")
    if env := os.environ.get("TGSIS_DSN"):
        return Target(env, "TGSIS_DSN")
    if any(os.environ.get(name) for name in LIBPQ_ENV):
        return Target("", "libpq environment")
    return Target(None, "local server")


_lock = threading.Lock()
_lease: Lease | None = None
_installed = False


def local_dsn(dbname: str = LOCAL_DATABASE) -> str:
    """DSN of a database of the local server, started (and tgsis installed) if needed.

    The server is held for this process until :func:`release_local_server` or
    exit.
    """
    global _lease, _installed
    with _lock:
        if _lease is None or not _lease.active:
            _lease = LocalServer.persistent().acquire()
            atexit.register(release_local_server)
        server = _lease.server
        if dbname == LOCAL_DATABASE and not _installed:
            server.ensure_database(LOCAL_DATABASE)
            with psycopg.connect(server.dsn(LOCAL_DATABASE)) as conn:
                install(conn)
            _installed = True
        return server.dsn(dbname)


def release_local_server() -> None:
    """Give up this process's use of the local server (it stops if no one else uses it)."""
    global _lease, _installed
    with _lock:
        if _lease is not None:
            _lease.release()
        _lease = None
        _installed = False


@checked
def connect(dsn: str | None = None, *, autocommit: bool = False, **kwargs: Any) -> psycopg.Connection[TupleRow]:
    """Open a connection to a tgsis database.

    Parameters
    ----------
    dsn : str, optional
        libpq connection string or URI. ``None``: ``$TGSIS_DSN``, libpq's
        environment, or the local server (started if needed, tgsis installed).
    autocommit : bool
        Passed to :func:`psycopg.connect`.
    **kwargs
        Passed to :func:`psycopg.connect`.

    Returns
    -------
    psycopg.Connection

    Raises
    ------
    LocalServerError
        The local server was needed and could not be started.
    DatabaseError
        The connection failed.
    """
    target = resolve_target(dsn)
    conninfo = target.dsn if target.dsn is not None else local_dsn()
    with reraise():
        return psycopg.connect(conninfo, autocommit=autocommit, **kwargs)
