"""Reads of several statements inside a caller's READ COMMITTED transaction see one state (plan G, R).

Found: the multi-statement readers (``fetch_features``, ``get_at``, ``surfaces_at``, ``frames_at``,
``fetch_series``, ``fetch_evolving``, ``fetch_gmap``, ``fetch_md_gmap``, ``checkout``, the chunk
download) opened a ``REPEATABLE READ READ ONLY`` transaction of their own only when the connection was
idle. Inside the caller's transaction (psycopg's default: a connection that is not autocommit opens one
at its first statement) they ran in a savepoint, and under ``READ COMMITTED`` each statement took a new
snapshot: a commit of another session between the name's and the vertices' statements gave an object of
two states, without an error. Now each read is :func:`tgsis.db._transfer.consistent_read`: the snapshot
is compared before and after the read, which runs again when another transaction completed in between,
and after a few tries raises ``TG003``.

Made deterministic without triggers: psycopg's ``Cursor.execute`` and ``Cursor.copy`` are wrapped so
that the other session commits right after the reader's statement that reads the object's name (or the
chunk table's first COPY), on the reader's connection only. The other session's commit changes the name
(or a triangle) and the vertices together: a result with one but not the other is two states.
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import Any

import numpy as np
import psycopg
import pytest
from psycopg import sql

import tgsis
from tests.temporal_data import evolving, series
from tgsis import gmaps
from tgsis.db import _transfer
from tgsis.db._chunk_transfer import download_tables

Conn = psycopg.Connection[Any]


@dataclass
class Ids:
    static: int
    series: int
    evolving: int
    gmap: int
    md: int


def build(conn: Conn) -> Ids:
    """A feature of each model, committed."""
    rng = np.random.default_rng(40)
    surface = tgsis.Surface([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]], [[0, 1, 2], [1, 3, 2]], name="tri")
    square = gmaps.GMap.from_triangles([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], [[0, 1, 2], [0, 2, 3]])
    lifted = gmaps.GMap.from_triangles([[0, 0, 0, 0.5], [1, 0, 0, 0.5], [1, 1, 0, 0.5]], [[0, 1, 2]])
    ids = []
    for name, time_model, obj in [
        ("tops", "STATIC", surface),
        ("steps", "INSTANTS", series(rng, [0.0, 1.0, 2.0])),
        ("moving", "EVOLVING", evolving(rng, [0.0, 2.0])),
        (
            "maps",
            "GMAP",
            gmaps.EvolvingGMap([gmaps.GMapPeriod([0.0, 1.0], square, [square.points, square.points * 2])]),
        ),
        ("md", "MULTIDIM", lifted),
    ]:
        geotype = "GMAP" if isinstance(obj, gmaps.GMap | gmaps.EvolvingGMap) else "SURFACE"
        fc = tgsis.create_feature_class(
            conn,
            name,
            geotype,
            time_model=time_model,  # type: ignore[arg-type]
            cell_level=2 if geotype == "GMAP" else None,
        )
        ids.append(tgsis.insert_feature(conn, fc, obj))  # type: ignore[arg-type]
    conn.commit()
    return Ids(*ids)


@pytest.fixture
def ids(conn: Conn) -> Ids:
    return build(conn)


@pytest.fixture
def other(db_dsn: str) -> Iterator[Conn]:
    """The second session: autocommit, each change committed at once."""
    with psycopg.connect(db_dsn, autocommit=True) as connection:
        connection.execute("SET lock_timeout = '10s'")
        yield connection


def _text(cursor: psycopg.Cursor[Any], query: Any) -> str:
    return query.as_string(cursor.connection) if isinstance(query, sql.Composable) else str(query)


class Interleave:
    """Runs ``commit()`` after ``times`` statements of ``reader`` whose text has a marker, the first ``skip`` left out."""

    def __init__(
        self, reader: Conn, commit: Callable[[], None], markers: tuple[str, ...], times: int = 1, skip: int = 0
    ) -> None:
        self.reader, self.commit, self.markers, self.left, self.skip = reader, commit, markers, times, skip
        self.fired = 0

    def after(self, cursor: psycopg.Cursor[Any], query: Any) -> None:
        if self.left and cursor.connection is self.reader and any(m in _text(cursor, query) for m in self.markers):
            if self.skip:
                self.skip -= 1
                return
            self.left -= 1
            self.fired += 1
            self.commit()


@pytest.fixture
def interleave(monkeypatch: pytest.MonkeyPatch) -> Callable[..., Interleave]:
    """``interleave(reader, commit, markers, times=1)``: hooks psycopg's cursors for the test."""
    hooks: list[Interleave] = []
    execute, copy = psycopg.Cursor.execute, psycopg.Cursor.copy

    def hooked_execute(self: psycopg.Cursor[Any], query: Any, *args: Any, **kwargs: Any) -> Any:
        result = execute(self, query, *args, **kwargs)
        for hook in hooks:
            hook.after(self, query)
        return result

    @contextlib.contextmanager
    def hooked_copy(self: psycopg.Cursor[Any], statement: Any, *args: Any, **kwargs: Any) -> Iterator[Any]:
        with copy(self, statement, *args, **kwargs) as c:
            yield c
        for hook in hooks:
            hook.after(self, statement)

    monkeypatch.setattr(psycopg.Cursor, "execute", hooked_execute)
    monkeypatch.setattr(psycopg.Cursor, "copy", hooked_copy)

    def make(
        reader: Conn, commit: Callable[[], None], markers: tuple[str, ...], times: int = 1, skip: int = 0
    ) -> Interleave:
        hooks.append(Interleave(reader, commit, markers, times, skip))
        return hooks[-1]

    return make


def _xsum(points: Any) -> float:
    return round(float(np.asarray(points, dtype=np.float64)[..., 0].sum()), 9)


# reader name -> (read(conn, ids), its state: names and coordinates, the other session's change)
NAME_AND_X = "UPDATE tgsis.geometry SET geoname = coalesce(geoname, '') || '+' WHERE geoid = {id}; "


def _surface(s: Any) -> tuple[Any, float]:
    return s.name, _xsum(s.vertices)


READERS: dict[str, tuple[Callable[[Conn, Ids], Any], Callable[[Any], Any], str]] = {
    "fetch_features": (
        lambda c, i: tgsis.fetch_features(c, "tops", [i.static]),
        lambda r: (r[0].name, _xsum(r[0].mesh.vertices)),
        NAME_AND_X + "UPDATE tgsis.vrtx SET x = x + 1 WHERE geoid = {id}",
    ),
    "get_at": (
        lambda c, i: tgsis.get_at(c, i.series, 1.0),
        _surface,
        NAME_AND_X + "UPDATE tgsis.times_vrtx SET x = x + 1 WHERE geoid = {id}",
    ),
    "surfaces_at": (
        lambda c, i: tgsis.surfaces_at(c, "steps", 1.0)[i.series],
        _surface,
        NAME_AND_X + "UPDATE tgsis.times_vrtx SET x = x + 1 WHERE geoid = {id}",
    ),
    "frames_at": (
        lambda c, i: tgsis.frames_at(c, i.series, [0.0, 1.0, 2.0]),
        lambda frames: [_surface(s) for _, s in frames],
        NAME_AND_X + "UPDATE tgsis.times_vrtx SET x = x + 1 WHERE geoid = {id}",
    ),
    "fetch_series": (
        lambda c, i: tgsis.fetch_series(c, "steps", i.series),
        lambda s: [_surface(x) for x in s.surfaces],
        NAME_AND_X + "UPDATE tgsis.times_vrtx SET x = x + 1 WHERE geoid = {id}",
    ),
    "fetch_evolving": (
        lambda c, i: tgsis.fetch_evolving(c, "moving", i.evolving),
        lambda e: (e.name, [_xsum(p.positions) for p in e.periods]),
        NAME_AND_X + "UPDATE tgsis.d4dvrtx SET x = x + 1 WHERE geoid = {id}",
    ),
    "fetch_gmap": (
        lambda c, i: tgsis.fetch_gmap(c, "maps", i.gmap),
        lambda g: (g.name, [_xsum(p.positions) for p in g.periods]),
        NAME_AND_X + "UPDATE tgsis.gmap_vertex SET coordinate[1] = coordinate[1] + 1 WHERE geoid = {id}",
    ),
    "gmap_at": (
        lambda c, i: tgsis.gmap_at(c, i.gmap, 0.5),
        lambda g: _xsum(g.points),
        "UPDATE tgsis.gmap_vertex SET coordinate[1] = coordinate[1] + 1 WHERE geoid = {id}",
    ),
    "fetch_md_gmap": (
        lambda c, i: tgsis.fetch_md_gmap(c, "md", i.md),
        lambda r: (r[1], _xsum(r[0].points)),
        "UPDATE tgsis.md_gmap SET axes = ARRAY(SELECT a || '+' FROM unnest(axes) a) WHERE geoid = {id}; "
        "UPDATE tgsis.md_vertex SET coordinate[1] = coordinate[1] + 1 WHERE geoid = {id}",
    ),
    "checkout": (
        lambda c, i: tgsis.checkout(c, i.static, "tops"),
        lambda out: (out.mesh.name, _xsum(out.mesh.vertices)),
        NAME_AND_X + "UPDATE tgsis.vrtx SET x = x + 1 WHERE geoid = {id}",
    ),
}

FEATURE = {
    "fetch_features": "static",
    "checkout": "static",
    "fetch_evolving": "evolving",
    "fetch_gmap": "gmap",
    "gmap_at": "gmap",
    "fetch_md_gmap": "md",
}
# the reader's statement after which the other session commits: the first that reads the name (or axes)
MARKERS = ("geoname", "m.axes")
# but the check-out's look-up of the feature before its read (in a transaction of its own)
SKIP = {"checkout": 1}
# gmap_at reads no name: after its COPY of the positions at the instant before t (then those after t); with the
# darts in chunks (read by the client codec, the points of both instants in one statement) after the darts' COPY
MARKERS_OF = {"gmap_at": ("FROM tgsis.gmap_vertex", '"gmap_dart_chunk"')}


def _change(other: Conn, reader: str, ids: Ids) -> Callable[[], None]:
    geoid = getattr(ids, FEATURE.get(reader, "series"))

    def commit() -> None:
        with other.transaction():
            for statement in READERS[reader][2].format(id=geoid).split("; "):
                other.execute(statement.encode())  # the test's own literal SQL

    return commit


def _states(conn: Conn, other: Conn, reader: str, ids: Ids) -> tuple[Any, Any]:
    """The reader's state before and after the other session's change (read idle, then the change undone)."""
    read, state, _ = READERS[reader]
    conn.rollback()
    before = state(read(conn, ids))
    _change(other, reader, ids)()
    after = state(read(conn, ids))
    conn.rollback()
    assert before != after, "the change must show in what the reader returns"
    return before, after


@pytest.mark.parametrize("reader", list(READERS))
def test_a_commit_between_the_statements_of_a_read_in_a_read_committed_transaction_is_not_mixed(
    conn: Conn, other: Conn, ids: Ids, interleave: Callable[..., Interleave], reader: str
) -> None:
    read, state, _ = READERS[reader]
    _, before = _states(conn, other, reader, ids)  # the state committed now; the hook's commit changes it again
    conn.execute("SELECT 1")  # the caller's READ COMMITTED transaction is open (psycopg's default)
    assert conn.info.transaction_status == psycopg.pq.TransactionStatus.INTRANS
    hook = interleave(conn, _change(other, reader, ids), MARKERS_OF.get(reader, MARKERS), skip=SKIP.get(reader, 0))
    got = state(read(conn, ids))
    assert hook.fired == 1
    conn.rollback()
    after = state(read(conn, ids))  # the committed state now, read idle
    assert before != after
    assert got in (before, after), f"{reader} mixed two states: {got} is neither {before} nor {after}"


def test_the_chunk_download_of_several_tables_in_a_read_committed_transaction_is_one_state(
    conn: Conn, other: Conn, ids: Ids, interleave: Callable[..., Interleave]
) -> None:
    if "vrtx" not in _transfer_chunked(conn):
        pytest.skip("model 1 is stored in rows here: no chunk download")

    def state() -> tuple[float, list[int]]:
        got = download_tables(conn, {"vrtx": [ids.static], "trgl": [ids.static]})
        trgl = got["trgl"][ids.static]
        return _xsum(got["vrtx"][ids.static].columns["x"][:, None]), [int(trgl.columns["vrtxid1"][0])]

    def commit() -> None:
        with other.transaction():
            other.execute("UPDATE tgsis.vrtx SET x = x + 1 WHERE geoid = %s", (ids.static,))
            other.execute(
                "UPDATE tgsis.trgl SET vrtxid1 = vrtxid2, vrtxid2 = vrtxid1 WHERE geoid = %s AND trglid = 0",
                (ids.static,),
            )

    conn.rollback()
    before = state()
    conn.execute("SELECT 1")
    hook = interleave(conn, commit, ("vrtx_chunk",))
    got = state()
    assert hook.fired == 1
    conn.rollback()
    after = state()
    assert before != after
    assert got == after, f"the download mixed two states: {got} is neither {before} nor {after}"


def _transfer_chunked(conn: Conn) -> set[str]:
    from tgsis.db._chunk_transfer import chunked_tables

    return set(chunked_tables(conn))


def test_a_read_that_others_interleave_at_every_try_raises_tg003_and_leaves_the_transaction_as_it_was(
    conn: Conn, other: Conn, ids: Ids, interleave: Callable[..., Interleave]
) -> None:
    conn.execute("UPDATE tgsis.geometry SET geoname = 'mine' WHERE geoid = %s", (ids.series,))  # the caller's write
    hook = interleave(conn, _change(other, "fetch_features", ids), MARKERS, times=1000)
    with pytest.raises(tgsis.Error) as info:
        tgsis.fetch_features(conn, "tops", [ids.static])
    assert info.value.sqlstate == "TG003"
    assert "fetch_features" in info.value.message
    assert info.value.hint is not None and "REPEATABLE READ" in info.value.hint
    assert hook.fired == _transfer.CONSISTENT_READ_TRIES
    assert conn.info.transaction_status == psycopg.pq.TransactionStatus.INTRANS  # usable, its write kept
    assert conn.execute("SELECT geoname FROM tgsis.geometry WHERE geoid = %s", (ids.series,)).fetchone() == ("mine",)
    hook.left = 0
    assert tgsis.fetch_features(conn, "tops", [ids.static])[0].mesh is not None  # now it reads


def test_a_repeatable_read_caller_sees_its_snapshot_and_nothing_is_read_again(
    conn: Conn, other: Conn, ids: Ids, interleave: Callable[..., Interleave]
) -> None:
    _, before = _states(conn, other, "get_at", ids)
    conn.execute("SET TRANSACTION ISOLATION LEVEL REPEATABLE READ")
    conn.execute("SELECT 1")  # the transaction's snapshot
    hook = interleave(conn, _change(other, "get_at", ids), MARKERS)
    read, state, _ = READERS["get_at"]
    assert state(read(conn, ids)) == before
    assert hook.fired == 1
    assert state(read(conn, ids)) == before  # still the snapshot of the transaction's first statement
    conn.rollback()


@pytest.mark.parametrize("autocommit", [True, False])
def test_a_new_connection_reads_one_state(
    db_dsn: str, conn: Conn, other: Conn, ids: Ids, interleave: Callable[..., Interleave], autocommit: bool
) -> None:
    """Autocommit: the read's own REPEATABLE READ transaction. Not autocommit: the class's look-up before the read
    opens psycopg's implicit READ COMMITTED transaction (the case this file is about: on main it mixed states)."""
    _, before = _states(conn, other, "fetch_series", ids)
    with psycopg.connect(db_dsn, autocommit=autocommit) as reader:
        hook = interleave(reader, _change(other, "fetch_series", ids), MARKERS)
        read, state, _ = READERS["fetch_series"]
        got = state(read(reader, ids))
        assert hook.fired == 1
        reader.rollback()
        after = state(read(reader, ids))
        assert before != after
        if autocommit:
            assert got == before  # the snapshot of its first statement
            assert reader.info.transaction_status == psycopg.pq.TransactionStatus.IDLE
        else:
            assert got in (before, after)


def test_the_callers_own_uncommitted_write_is_seen(conn: Conn, ids: Ids) -> None:
    conn.execute("UPDATE tgsis.geometry SET geoname = 'mine' WHERE geoid = %s", (ids.series,))
    conn.execute("UPDATE tgsis.times_vrtx SET x = x + 10 WHERE geoid = %s", (ids.series,))
    got = tgsis.fetch_series(conn, "steps", ids.series)
    assert conn.info.transaction_status == psycopg.pq.TransactionStatus.INTRANS
    assert {s.name for s in got.surfaces} == {"mine"}
    conn.rollback()
    assert {s.name for s in tgsis.fetch_series(conn, "steps", ids.series).surfaces} == {"stepped horizon"}
    assert (
        got.surfaces[0].vertices[0, 0] == tgsis.fetch_series(conn, "steps", ids.series).surfaces[0].vertices[0, 0] + 10
    )


def test_a_role_with_fewer_rights_reads_one_state_in_its_read_committed_transaction(
    db_dsn: str, conn: Conn, other: Conn, ids: Ids, interleave: Callable[..., Interleave]
) -> None:
    """The snapshot's functions (pg_current_snapshot, pg_last_wal_replay_lsn) need no right a reader lacks."""
    from tests.roles import login_roles

    _, before = _states(conn, other, "fetch_features", ids)
    with login_roles(db_dsn, {"ann": "tgsis_reader"}) as roles:
        reader = roles.connect("ann")
        read, state, _ = READERS["fetch_features"]
        reader.execute("SELECT 1")
        hook = interleave(reader, _change(other, "fetch_features", ids), MARKERS)
        got = state(read(reader, ids))
        assert hook.fired == 1
        reader.rollback()
        after = state(read(reader, ids))
        assert before != after and got in (before, after)
        reader.rollback()


def test_an_error_of_a_try_that_others_interleaved_is_read_again_an_error_of_one_state_is_raised(
    conn: Conn, other: Conn, ids: Ids
) -> None:
    """Statements of two states may raise what neither state would (a triangle naming a vertex not read yet)."""
    calls: list[int] = []

    def read() -> int:
        calls.append(len(calls))
        conn.execute("SELECT count(*) FROM tgsis.geometry").fetchone()
        if len(calls) == 1:
            other.execute("UPDATE tgsis.geometry SET geoname = 'x' WHERE geoid = %s", (ids.static,))
            raise tgsis.InvalidGeometryError("what two states gave")
        return len(calls)

    conn.execute("SELECT 1")
    assert _transfer.consistent_read(conn, "a test", read) == 2
    calls.clear()

    def failing() -> int:
        calls.append(len(calls))
        conn.execute("SELECT 1/0").fetchone()  # an error of the state itself: in the savepoint, rolled back
        return 0

    with pytest.raises(psycopg.errors.DivisionByZero):
        _transfer.consistent_read(conn, "a test", failing)
    assert calls == [0]
    assert conn.info.transaction_status == psycopg.pq.TransactionStatus.INTRANS  # the caller's, usable
    assert conn.execute("SELECT 2").fetchone() == (2,)


def test_a_consistent_read_inside_another_on_the_same_connection_runs_plainly(conn: Conn) -> None:
    marks: list[str] = []
    execute = psycopg.Cursor.execute

    def counting(self: psycopg.Cursor[Any], query: Any, *args: Any, **kwargs: Any) -> Any:
        if "pg_current_snapshot" in _text(self, query):
            marks.append("mark")
        return execute(self, query, *args, **kwargs)

    conn.execute("SELECT 1")
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(psycopg.Cursor, "execute", counting)
        inner = _transfer.consistent_read(conn, "outer", lambda: _transfer.consistent_read(conn, "inner", lambda: 7))
    assert inner == 7
    assert marks == ["mark", "mark"]  # the outer's before and after, none of the inner's


@pytest.fixture
def unrelated(conn: Conn, other: Conn) -> Callable[[], None]:
    """A commit of the other session that changes nothing a reader reads (a table of its own)."""
    other.execute("CREATE TABLE IF NOT EXISTS unrelated_log (n bigint)")

    def commit() -> None:
        other.execute("INSERT INTO unrelated_log VALUES (1)")

    return commit


@pytest.mark.parametrize("reader", list(READERS))
def test_commits_that_change_nothing_read_at_every_try_do_not_stop_the_read(
    conn: Conn, other: Conn, ids: Ids, interleave: Callable[..., Interleave], unrelated: Callable[[], None], reader: str
) -> None:
    """Found by CI: on a busy server (autovacuum's ANALYZE, other databases: the snapshot is the cluster's) a
    commit landed inside each of the five tries of a read that nothing changed, and the read raised TG003."""
    read, state, _ = READERS[reader]
    conn.rollback()
    expected = state(read(conn, ids))
    markers = MARKERS_OF.get(reader, MARKERS)
    # the marked statements of one try, counted in a REPEATABLE READ transaction (one try, always): under READ
    # COMMITTED an autovacuum's commit during the count made it two tries (the whole suite met it on PG18)
    conn.rollback()
    conn.execute("SET TRANSACTION ISOLATION LEVEL REPEATABLE READ")
    counter = interleave(conn, lambda: None, markers, times=1000, skip=SKIP.get(reader, 0))
    assert state(read(conn, ids)) == expected
    per_try = counter.fired
    counter.left = 0
    conn.rollback()
    conn.execute("SELECT 1")  # the caller's READ COMMITTED transaction
    hook = interleave(conn, unrelated, markers, times=1000, skip=SKIP.get(reader, 0))
    assert state(read(conn, ids)) == expected
    assert per_try >= 1 and hook.fired == 2 * per_try  # two tries read the same: one state
    assert conn.info.transaction_status == psycopg.pq.TransactionStatus.INTRANS
    conn.rollback()


def test_a_change_at_every_try_that_gives_the_same_result_twice_is_that_result(
    conn: Conn, other: Conn, ids: Ids, interleave: Callable[..., Interleave]
) -> None:
    """A commit that writes what is already there (the same name again) changes no row read: the result stands."""
    conn.rollback()
    expected = tgsis.fetch_features(conn, "tops", [ids.static])[0].name

    def same_again() -> None:
        other.execute("UPDATE tgsis.geometry SET geoname = geoname WHERE geoid = %s", (ids.static,))

    conn.execute("SELECT 1")
    hook = interleave(conn, same_again, MARKERS, times=1000)
    assert tgsis.fetch_features(conn, "tops", [ids.static])[0].name == expected
    assert hook.fired == 2
    conn.rollback()


def test_the_same_error_in_two_interleaved_tries_is_raised_not_tg003(conn: Conn, unrelated: Callable[[], None]) -> None:
    calls: list[int] = []

    def read() -> int:
        calls.append(len(calls))
        conn.execute("SELECT 1").fetchone()
        unrelated()  # each try interleaved
        raise tgsis.InvalidGeometryError("the state's own defect")

    conn.execute("SELECT 1")
    with pytest.raises(tgsis.InvalidGeometryError, match="the state's own defect"):
        _transfer.consistent_read(conn, "a test", read)
    assert calls == [0, 1]
    assert conn.execute("SELECT 2").fetchone() == (2,)
    conn.rollback()


def test_the_chunk_download_with_commits_that_change_nothing_read_is_read_twice_and_returned(
    conn: Conn, ids: Ids, interleave: Callable[..., Interleave], unrelated: Callable[[], None]
) -> None:
    if "vrtx" not in _transfer_chunked(conn):
        pytest.skip("model 1 is stored in rows here: no chunk download")
    conn.rollback()
    expected = download_tables(conn, {"vrtx": [ids.static], "trgl": [ids.static]})
    conn.execute("SELECT 1")
    hook = interleave(conn, unrelated, ("vrtx_chunk",), times=1000)
    got = download_tables(conn, {"vrtx": [ids.static], "trgl": [ids.static]})
    assert hook.fired == 2
    for table in ("vrtx", "trgl"):
        for name, column in expected[table][ids.static].columns.items():
            assert np.array_equal(got[table][ids.static].columns[name], column)
    conn.rollback()


def test_feature_properties_of_every_type_compare_across_two_tries(
    conn: Conn, interleave: Callable[..., Interleave], unrelated: Callable[[], None]
) -> None:
    """numeric, date, timestamptz and jsonb feature properties come as Decimal, date, datetime and dicts: two tries
    that read them alike are one state (before, Decimal and datetime compared as never the same: TG003)."""
    import datetime
    import decimal

    tgsis.create_feature_class(
        conn,
        "typed",
        "SURFACE",
        feature_properties=[
            ("grade", "numeric"),
            ("day", "date"),
            ("seen", "timestamptz"),
            ("notes", "jsonb"),
            ("label", "text"),
        ],
    )
    surface = tgsis.Surface([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]], name="one")
    props = {
        "grade": decimal.Decimal("1.50"),
        "day": datetime.date(2026, 12, 7),
        "seen": datetime.datetime(2026, 12, 7, 1, 2, 3, tzinfo=datetime.timezone.utc),
        "notes": {"a": [1.5, None]},
        "label": "x",
    }
    geoid = tgsis.insert_feature(conn, "typed", surface, props)
    conn.commit()
    expected = tgsis.fetch_features(conn, "typed", [geoid])[0].properties
    conn.execute("SELECT 1")
    hook = interleave(conn, unrelated, MARKERS, times=1000)
    got = tgsis.fetch_features(conn, "typed", [geoid])[0].properties
    assert got == expected and got["grade"] == decimal.Decimal("1.50")
    assert hook.fired == 2
    conn.rollback()
