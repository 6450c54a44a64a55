"""Concurrent sessions for the tests: a call run in a thread of its own whose lock wait a test can watch."""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from typing import Any

import psycopg
import pytest

import tgsis

Conn = psycopg.Connection[Any]

LOCK_TIMEOUT = "20s"  # safety net only: a wait that long is a failure, not a documented lock wait


def connect(dsn: str, role: str, *, autocommit: bool = False) -> Conn:
    """A connection named after the part it plays (``application_name``), with a safety-net lock timeout."""
    return psycopg.connect(
        dsn,
        autocommit=autocommit,
        application_name=f"tgsis-concurrency-{role}",
        options=f"-c lock_timeout={LOCK_TIMEOUT}",
    )


class Background:
    """A call run in a thread of its own, whose lock wait the test can watch."""

    def __init__(self, dsn: str, name: str, call: Callable[[Conn], Any], version: str | None = None) -> None:
        self.conn = connect(dsn, name)
        if version is not None:
            tgsis.goto_version(self.conn, version)
        self.pid = self.conn.info.backend_pid
        self.result: Any = None
        self.error: BaseException | None = None
        self.thread = threading.Thread(target=self._run, args=(call,), daemon=True)
        self.thread.start()

    def _run(self, call: Callable[[Conn], Any]) -> None:
        try:
            self.result = call(self.conn)
            self.conn.commit()
        except BaseException as exc:  # noqa: BLE001 - inspected by the test
            self.error = exc
            self.conn.rollback()

    def finish(self) -> Any:
        self.thread.join(30)
        assert not self.thread.is_alive(), "the background call did not finish"
        self.conn.close()
        if self.error is not None:
            raise self.error
        return self.result


def wait_until_blocked(observer: Conn, pid: int, by: int) -> None:
    """Wait until backend ``pid`` waits for a lock held by backend ``by``."""
    deadline = time.monotonic() + 15
    while time.monotonic() < deadline:
        row = observer.execute("SELECT %s = ANY (pg_blocking_pids(%s))", (by, pid)).fetchone()
        observer.rollback()
        if row == (True,):
            return
        time.sleep(0.02)
    pytest.fail(f"backend {pid} never waited for backend {by}")


def close_and_wait_gone(session: Conn, observer: Conn) -> None:
    """Close ``session`` and wait until its backend has left ``pg_stat_activity``.

    A closed session's backend that ever made a temporary object (the face's sequence ``tgsis_face_seq``, which
    lives as long as the session; a stage table) drops them in a transaction of its own as it exits, after the
    client has gone: a switch of storage run at once may meet that transaction's snapshot (TG202,
    ``tgsis.older_snapshots_check``). The face's work tables of its row type no longer outlive the transaction
    that wrote (ON COMMIT DROP), so a test need not close a session that wrote before a switch; one that does
    waits. A user retries, as the hint says."""
    pid = session.info.backend_pid
    session.close()
    deadline = time.monotonic() + 15
    while time.monotonic() < deadline:
        row = observer.execute("SELECT count(*) FROM pg_stat_activity WHERE pid = %s", (pid,)).fetchone()
        observer.rollback()
        if row == (0,):
            return
        time.sleep(0.02)
    pytest.fail(f"backend {pid} did not exit")
