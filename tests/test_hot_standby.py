"""Reads on a hot standby (a streaming replica, the read replicas of production): right, whole, bit for bit.

A standby runs read-only transactions only (no transaction id, no temporary
table, no SERIALIZABLE), and its snapshots follow the primary's replayed
write-ahead log: `tgsis.db._transfer.consistent_read` compares the WAL
replayed there (docs/developing.md). A primary and its standby of this
test's own, both throwaway clusters of TGSIS_PG's binaries.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import tempfile
import threading
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import psycopg
import pytest
from psycopg.conninfo import make_conninfo

import tgsis
from tests.test_read_consistency import (  # the readers of every model, and the hook between their statements
    FEATURE,
    MARKERS,
    MARKERS_OF,
    READERS,
    SKIP,
    Interleave,
    build,
    interleave,  # noqa: F401 (a fixture)
)
from tgsis.db.local import LocalServer, throwaway_parent

pytestmark = pytest.mark.own_server  # two servers of TGSIS_PG's binaries, not the fixture pg's

Conn = psycopg.Connection[Any]


def _curved_surface(n: int, shift: float = 0.0) -> tgsis.Surface:
    """An n x n grid bent as a dome, its values not short decimals (every bit counts)."""
    x, y = np.meshgrid(np.linspace(0.0, 1000.0 / 3, n), np.linspace(0.0, 700.0 / 7, n))
    z = -2000.0 + 50.0 * np.sin(x / 97.0 + shift) * np.cos(y / 61.0) + 1e-9 * x
    vertices = np.column_stack([x.ravel(), y.ravel(), z.ravel()])
    i, j = np.meshgrid(np.arange(n - 1), np.arange(n - 1))
    a = (j * n + i).ravel()
    triangles = np.concatenate([np.column_stack([a, a + 1, a + n]), np.column_stack([a + 1, a + n + 1, a + n])])
    porosity = np.sqrt(np.arange(n * n, dtype=np.float64)) / 3.0
    return tgsis.Surface(vertices, triangles, vertex_properties={"porosity": porosity})


def _surface_of(feature: tgsis.Feature) -> tgsis.Surface:
    assert isinstance(feature.mesh, tgsis.Surface)
    return feature.mesh


def _caught_up(primary: Conn, standby: Conn, timeout: float = 60.0) -> None:
    """Wait until the standby has replayed everything the primary wrote so far."""
    # the insert position: an asynchronous commit (the throwaway clusters' synchronous_commit = off) may not be
    # written yet, and pg_current_wal_lsn() (the write position) would stop before it
    (target,) = primary.execute("SELECT pg_current_wal_insert_lsn()::text").fetchone()  # type: ignore[misc]
    deadline = time.monotonic() + timeout
    while True:
        row = standby.execute("SELECT pg_last_wal_replay_lsn() >= %s::pg_lsn", (target,)).fetchone()
        if row is not None and row[0]:
            return
        if time.monotonic() > deadline:
            raise AssertionError(f"the standby did not replay up to {target} in {timeout} s")
        time.sleep(0.05)


def _standby_of(primary: LocalServer) -> LocalServer:
    """A hot standby of ``primary`` (pg_basebackup -R, streaming), started."""
    root = Path(tempfile.mkdtemp(prefix="tgsis-standby-", dir=throwaway_parent()))
    standby = LocalServer(root, primary.binaries, durable=False)
    user = primary.os_user
    if user is not None:
        os.chown(root, user.uid, user.gid)
    root.chmod(0o755)
    result = subprocess.run(  # noqa: S603 - fixed argument list
        [str(primary.binaries.tool("pg_basebackup")), "-D", str(standby.data_dir), "-R", "-X", "stream", "-c", "fast"]
        + ["-d", primary.dsn()],
        capture_output=True,
        text=True,
        check=False,
        timeout=300,
        cwd=str(root),
        user=user.uid if user else None,
        group=user.gid if user else None,
        extra_groups=[] if user else None,
    )
    if result.returncode != 0:
        shutil.rmtree(root, ignore_errors=True)
        raise AssertionError(f"pg_basebackup failed: {result.stdout}{result.stderr}")
    # replay waits for the standby's queries rather than cancelling them: on a loaded machine the standby lags,
    # and a lag beyond max_standby_streaming_delay (30 s) cancels a query at its first recovery conflict
    # ("terminating connection due to conflict with recovery", a buffer pin: the whole suite met it)
    with (standby.data_dir / "postgresql.auto.conf").open("a", encoding="utf-8") as conf:
        conf.write("max_standby_streaming_delay = -1\nhot_standby_feedback = on\n")
    try:
        standby.start()
        standby.watch("throwaway")
    except BaseException:
        standby.destroy()
        raise
    return standby


@pytest.fixture(scope="module")
def replicated() -> Iterator[tuple[LocalServer, LocalServer]]:
    """A primary with a database per storage of model 1 (``rows``, ``chunks``), and its hot standby."""
    primary = LocalServer.throwaway(in_memory=True)
    standby: LocalServer | None = None
    try:
        with psycopg.connect(primary.dsn(), autocommit=True) as admin:
            for storage in ("rows", "chunks"):
                admin.execute(f"CREATE DATABASE geo_{storage}")
        for storage in ("rows", "chunks"):
            with psycopg.connect(make_conninfo(primary.dsn(), dbname=f"geo_{storage}")) as conn:
                tgsis.install(conn, storage=storage)  # type: ignore[arg-type]
                conn.commit()
        standby = _standby_of(primary)
        yield primary, standby
    finally:
        if standby is not None:
            standby.destroy()
        primary.destroy()


@dataclass
class Sessions:
    """One database on the primary (``writer``) and on the standby (``reader``, ``watcher``: waits for replay)."""

    writer: Conn
    reader: Conn
    watcher: Conn

    def caught_up(self) -> None:
        """Wait until the standby has replayed everything the writer wrote so far."""
        _caught_up(self.writer, self.watcher)


@pytest.fixture
def sessions(db_storage: str, replicated: tuple[LocalServer, LocalServer]) -> Iterator[Sessions]:
    """Sessions on the database of the test's storage of model 1, with no feature class left from before.

    The file runs on one storage on each server (tools/test-suites): both storages on both servers in all.
    """
    primary, standby = replicated
    name = f"geo_{db_storage}"
    with (
        psycopg.connect(make_conninfo(primary.dsn(), dbname=name)) as writer,
        psycopg.connect(make_conninfo(standby.dsn(), dbname=name)) as reader,
        psycopg.connect(make_conninfo(standby.dsn(), dbname=name), autocommit=True) as watcher,
    ):
        writer.execute("SELECT tgsis.drop_feature_class(classname, true) FROM tgsis.catalog")
        writer.commit()
        yield Sessions(writer, reader, watcher)


@pytest.fixture
def pair(sessions: Sessions) -> tuple[Conn, Conn]:
    """The writer on the primary and the reader on the standby, the class ``horizon`` made anew."""
    tgsis.create_feature_class(sessions.writer, "horizon", "SURFACE", cell_properties=[("porosity", "float8")])
    sessions.writer.commit()
    return sessions.writer, sessions.reader


def test_the_standby_is_in_recovery(pair: tuple[Conn, Conn]) -> None:
    writer, reader = pair
    assert writer.execute("SELECT pg_is_in_recovery()").fetchone() == (False,)
    assert reader.execute("SELECT pg_is_in_recovery()").fetchone() == (True,)
    reader.rollback()


def test_features_read_on_the_standby_are_the_primary_s_bit_for_bit(pair: tuple[Conn, Conn]) -> None:
    writer, reader = pair
    surfaces = [_curved_surface(40), _curved_surface(7, shift=1.0)]
    ids = [tgsis.insert_feature(writer, "horizon", s) for s in surfaces]
    writer.commit()
    _caught_up(writer, reader)
    reader.rollback()  # idle: each read below opens its own read-only snapshot
    for geoid, surface in zip(ids, surfaces, strict=True):
        got = _surface_of(tgsis.fetch_feature(reader, "horizon", geoid))
        assert got.vertices.tobytes() == surface.vertices.tobytes()
        assert np.array_equal(got.triangles, surface.triangles)
        assert got.vertex_properties["porosity"].tobytes() == surface.vertex_properties["porosity"].tobytes()
    many = tgsis.fetch_features(reader, "horizon")
    assert [f.id for f in many] == ids
    assert _surface_of(many[0]).vertices.tobytes() == surfaces[0].vertices.tobytes()
    box = np.array([[0.0, 0.0, -3000.0], [1.0, 1.0, 0.0]])
    assert sorted(tgsis.features_in_box(reader, "horizon", box)) == ids
    # psql through the relational face, one vertex by key and a whole object
    reader.execute("SET extra_float_digits = 3")
    row = reader.execute("SELECT x, y, z FROM tgsis.vrtx WHERE geoid = %s AND vrtxid = 17", (ids[0],)).fetchone()
    assert row == tuple(surfaces[0].vertices[17])
    (count,) = reader.execute("SELECT count(*) FROM tgsis.trgl WHERE geoid = %s", (ids[0],)).fetchone()  # type: ignore[misc]
    assert count == len(surfaces[0].triangles)
    reader.rollback()


def test_a_series_snapshot_at_t_on_the_standby(pair: tuple[Conn, Conn]) -> None:
    writer, reader = pair
    tgsis.create_feature_class(writer, "moving", "SURFACE", time_model="INSTANTS", time_unit="Ma")
    steps = [_curved_surface(9, shift=s) for s in (0.0, 0.5, 1.0)]
    series = tgsis.SurfaceSeries([0.0, 1.0, 2.0], [tgsis.Surface(s.vertices, s.triangles) for s in steps])
    geoid = tgsis.insert_feature(writer, "moving", series)
    writer.commit()
    _caught_up(writer, reader)
    reader.rollback()
    for t, want in ((0.5, steps[0]), (1.0, steps[1]), (2.0, steps[2])):
        got = tgsis.get_at(reader, geoid, t)
        assert got is not None and got.vertices.tobytes() == want.vertices.tobytes()
    assert tgsis.get_at(reader, geoid, 7.0) is None  # the series ends at its last instant (not alive)


def test_a_read_committed_read_on_the_standby_sees_one_state_while_the_primary_commits(pair: tuple[Conn, Conn]) -> None:
    """The standby's snapshots move as WAL is replayed: every multi-statement read gives one committed state."""
    writer, reader = pair
    old, new = _curved_surface(60), _curved_surface(60, shift=2.0)
    geoid = tgsis.insert_feature(writer, "horizon", old)
    writer.commit()
    _caught_up(writer, reader)
    stop = threading.Event()
    errors: list[BaseException] = []

    def flip() -> None:  # the primary swaps the surface's shape back and forth, committing each time
        try:
            shapes = [new, old]
            for i in range(10_000):
                if stop.is_set():
                    return
                tgsis.save_feature(writer, "horizon", geoid, shapes[i % 2])
                writer.commit()
        except BaseException as exc:  # noqa: BLE001 (reported by the test)
            errors.append(exc)

    thread = threading.Thread(target=flip)
    thread.start()
    try:
        seen = set()
        deadline = time.monotonic() + 8.0
        while time.monotonic() < deadline:
            reader.execute("SELECT 1")  # a READ COMMITTED transaction is open: each statement its own snapshot
            try:
                got = _surface_of(tgsis.fetch_feature(reader, "horizon", geoid))
            except tgsis.ConcurrentReadError:
                reader.rollback()
                continue  # five tries each interleaved by a commit: refused, never mixed
            whole = [s for s in (old, new) if got.vertices.tobytes() == s.vertices.tobytes()]
            assert len(whole) == 1, "a mix of two committed states"
            assert got.vertex_properties["porosity"].tobytes() == whole[0].vertex_properties["porosity"].tobytes()
            seen.add(id(whole[0]))
            reader.rollback()
    finally:
        stop.set()
        thread.join()
    assert not errors, errors
    assert seen, "no read succeeded"


def test_a_write_on_the_standby_is_refused_and_changes_nothing(pair: tuple[Conn, Conn]) -> None:
    writer, reader = pair
    surface = _curved_surface(5)
    geoid = tgsis.insert_feature(writer, "horizon", surface)
    writer.commit()
    _caught_up(writer, reader)
    with pytest.raises(tgsis.DatabaseError, match="read-only transaction") as caught:
        tgsis.insert_feature(reader, "horizon", surface)
    assert caught.value.sqlstate == "25006"  # read_only_sql_transaction, the server's own
    assert "hot standby" in (caught.value.hint or "") and "write on the primary" in (caught.value.hint or "")
    reader.rollback()
    assert [f.id for f in tgsis.fetch_features(reader, "horizon")] == [geoid]


@pytest.mark.parametrize("name", list(READERS))
def test_a_commit_replayed_between_the_statements_of_a_read_on_the_standby_is_not_mixed(
    sessions: Sessions,
    interleave: Callable[..., Interleave],  # noqa: F811 (the fixture imported above)
    name: str,
) -> None:
    """tests/test_read_consistency.py's case, the commit made on the primary and replayed on the standby."""
    writer, reader = sessions.writer, sessions.reader
    ids = build(writer)
    read, state, change = READERS[name]
    geoid = getattr(ids, FEATURE.get(name, "series"))

    def commit() -> None:  # on the primary, replayed on the standby before the reader's next statement
        for statement in change.format(id=geoid).split("; "):
            writer.execute(statement.encode())  # the test's own literal SQL
        writer.commit()
        sessions.caught_up()

    sessions.caught_up()
    reader.rollback()
    first = state(read(reader, ids))
    commit()
    before = state(read(reader, ids))
    assert first != before, "the change must show in what the reader returns"
    reader.execute("SELECT 1")  # the caller's READ COMMITTED transaction is open (psycopg's default)
    hook = interleave(reader, commit, MARKERS_OF.get(name, MARKERS), skip=SKIP.get(name, 0))
    got = state(read(reader, ids))
    assert hook.fired == 1
    reader.rollback()
    after = state(read(reader, ids))
    assert before != after
    assert got in (before, after), f"{name} mixed two states on the standby: {got} is neither {before} nor {after}"
