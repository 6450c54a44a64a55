"""The session's version settings (``tgsis.version``, ``tgsis.revision``): read them, and put them back.

A function that moves the session to another version or revision for a
while (:func:`tgsis.in_version`, a check-out of a frozen revision) reads them
first and restores them after, as they were: unset stays unset (``''``).
"""

from __future__ import annotations

from typing import Any

import psycopg

__all__ = ["VersionSettings", "read_version_settings", "restore_statement", "restore_version_settings"]

#: ``current_setting('tgsis.version')``, ``current_setting('tgsis.revision')``; None when never set.
VersionSettings = tuple[str | None, str | None]


def read_version_settings(conn: psycopg.Connection[Any]) -> VersionSettings:
    """The session's version and revision settings as they are now."""
    row = conn.execute(
        "SELECT current_setting('tgsis.version', true), current_setting('tgsis.revision', true)"
    ).fetchone()
    assert row is not None
    return row[0], row[1]


def restore_statement(settings: VersionSettings, *, local: bool) -> tuple[str, tuple[Any, ...]]:
    """The statement (SQL, parameters) that puts ``settings`` back: for the transaction (``local``) or the session."""
    return (
        "SELECT set_config('tgsis.version', coalesce(%s, ''), %s), set_config('tgsis.revision', coalesce(%s, ''), %s)",
        (settings[0], local, settings[1], local),
    )


def restore_version_settings(conn: psycopg.Connection[Any], settings: VersionSettings, *, local: bool) -> None:
    """Put ``settings`` back (see :func:`restore_statement`)."""
    conn.execute(*restore_statement(settings, local=local))
