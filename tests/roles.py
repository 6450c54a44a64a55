"""Login roles for the tests of version rights: real roles that log in with their own connection."""

from __future__ import annotations

import time
import uuid
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

import psycopg
from psycopg.conninfo import make_conninfo

Conn = psycopg.Connection[Any]


class Roles:
    """LOGIN roles of one test, by short name (``alice``): ``name()`` in the cluster, ``connect()`` as them."""

    def __init__(self, dsn: str, names: dict[str, str]) -> None:
        self._dsn = dsn
        self._names = names
        self.opened: list[Conn] = []

    def name(self, short: str) -> str:
        return self._names[short]

    def connect(self, short: str) -> Conn:
        """A new connection that logs in as the role (not SET ROLE)."""
        connection = psycopg.connect(make_conninfo(self._dsn, user=self._names[short]))
        self.opened.append(connection)
        return connection


@contextmanager
def login_roles(dsn: str, groups: dict[str, str]) -> Iterator[Roles]:
    """Create a LOGIN role per ``{short name: tgsis group role}`` for the database of ``dsn``.

    The roles belong to the cluster: they get unique names and are dropped,
    with what they own or were granted in that database, when the block ends.
    """
    suffix = uuid.uuid4().hex[:6]
    roles = Roles(dsn, {short: f"{short}_{suffix}" for short in groups})
    with psycopg.connect(dsn, autocommit=True) as admin:
        for short, group in groups.items():
            admin.execute(f"CREATE ROLE {roles.name(short)} LOGIN IN ROLE {group}")
        try:
            yield roles
        finally:
            for connection in roles.opened:
                connection.close()
            _wait_for_backends_to_end(admin, [roles.name(short) for short in groups])
            for short in groups:
                admin.execute(f"DROP OWNED BY {roles.name(short)} CASCADE")
                admin.execute(f"DROP ROLE {roles.name(short)}")


def _wait_for_backends_to_end(admin: Conn, names: list[str], seconds: float = 10.0) -> None:
    """Wait (a bounded time) until no session of the roles ``names`` is left in the cluster.

    A closed connection's backend drops its temporary tables as it exits,
    after the client has gone: a session that checked in on chunks has a
    stage table on which its role holds INSERT (``tgsis.object_chunks_stage``),
    and ``DROP OWNED BY`` the role then races that drop ("tuple concurrently
    deleted"). A backend leaves ``pg_stat_activity`` after its temporary
    tables are dropped.
    """
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        row = admin.execute("SELECT count(*) FROM pg_stat_activity WHERE usename = ANY (%s)", (names,)).fetchone()
        if row is None or row[0] == 0:
            return
        time.sleep(0.02)


def merges_as(conn: Conn, session: Conn, version: str, *, message: bool = False) -> tuple[tuple[Any, ...], ...]:
    """The Python merge, then the psql merge, of ``version`` run by ``session`` (a login role), each rolled back.

    ``conn`` (the owner's) puts the revision sequence back after each, so both
    number their revisions alike. Returns ``(python, psql)``, each
    ``("done", rows written)`` or ``("refused", SQLSTATE)`` (with the message's
    first 300 characters as a third item when ``message``).
    """
    import tgsis

    seq = conn.execute("SELECT last_value, is_called FROM tgsis.revision_seq").fetchone()
    conn.commit()

    def outcome(run: Any) -> tuple[Any, ...]:
        try:
            with session.transaction(force_rollback=True):
                return ("done", int(run()))
        except (psycopg.Error, tgsis.Error) as exc:
            return ("refused", exc.sqlstate, str(exc)[:300]) if message else ("refused", exc.sqlstate)
        finally:
            session.rollback()
            conn.execute("SELECT setval('tgsis.revision_seq', %s, %s)", seq)
            conn.commit()

    python = outcome(lambda: tgsis.merge_version(session, version))
    psql = outcome(lambda: session.execute("SELECT tgsis.merge_version(%s)", (version,)).fetchone()[0])  # type: ignore[index]
    return python, psql
