"""The connection of a command: the chosen database and version, this client's build."""

from __future__ import annotations

import argparse
import contextlib
import os
from collections.abc import Iterator
from typing import Any

import psycopg

from tgsis.cli._state import remembered_version
from tgsis.db import versions as V
from tgsis.db.connect import connect, resolve_target
from tgsis.db.install import installation_status, installed_version
from tgsis.db.sqlsource import ExtensionSources
from tgsis.errors import (
    InstallationError,
    InvalidInputError,
)

# --------------------------------------------------------------------------- working version


def target_key(args: argparse.Namespace) -> str:
    target = resolve_target(args.dsn)
    return target.dsn if target.dsn is not None else "local"


def chosen_version(args: argparse.Namespace) -> str | None:
    """--in, else $TGSIS_VERSION, else what `tgsis version goto` remembered for this database."""
    return args.in_version or os.environ.get("TGSIS_VERSION") or remembered_version(target_key(args))


def split_version(text: str) -> tuple[str, int | None]:
    """``VERSION`` or ``VERSION@REVISION``."""
    name, sep, revision = text.partition("@")
    if not sep:
        return name, None
    if not (revision.isascii() and revision.isdigit()):  # '²' is a digit to str.isdigit, not to int()
        raise InvalidInputError(f"{text!r} is not VERSION or VERSION@REVISION")
    if int(revision) > 2**31 - 1:
        raise InvalidInputError(f"revision {revision} of {text!r} is out of range: revisions go up to {2**31 - 1}")
    return name, int(revision)


def require_this_build(conn: psycopg.Connection[Any]) -> None:
    """Refuse to work on a database whose tgsis is another version (or, when recorded, another build) than this
    client's, naming both and the command that fixes it, before the command meets a missing function or column."""
    current = installed_version(conn)
    if current is None:
        return  # the command says what it misses (tgsis db install)
    sources = ExtensionSources.default()
    if current.version == sources.version and current.fingerprint in (None, sources.fingerprint):
        return  # (no fingerprint: a role that may not read tgsis.installation; db status tells)
    status = installation_status(conn, sources=sources)
    if not status.ok and status.state != "storage missing":
        raise InstallationError(status.problem or status.state, hint=status.fix)


@contextlib.contextmanager
def connection(args: argparse.Namespace) -> Iterator[psycopg.Connection[Any]]:
    """A connection working in the chosen version, or looking at VERSION@REVISION (DEFAULT when none is chosen)."""
    with connect(args.dsn) as conn:
        require_this_build(conn)
        chosen = chosen_version(args)
        if chosen is not None:
            name, revision = split_version(chosen)
            if revision is None:
                V.goto_version(conn, name)
            else:
                V.goto_revision(conn, name, revision)
        conn.commit()  # the checks' reads end: the command starts outside a transaction (a snapshot of its own)
        yield conn
