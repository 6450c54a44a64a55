"""Model 3 on chunks, the client's transfer: uploads encoded in numpy, snapshots interpolated on aligned arrays.

With ``d4dvrtx`` and ``d4dtrgl`` stored in chunks (``tgsis.store_in_chunks``, opt-in), ``insert_evolving`` and
``append_period`` encode the periods' chunks in the client and send one binary COPY per table as the user's
role (``tgsis.db._chunk_transfer.upload_instants``, shared with model 2), and ``get_at`` / ``surfaces_at`` read
the period's triangle chunks and the chunks of the two geometry instants around t, interpolating
``x0 + w (x1 - x0)`` in numpy as ``tgsis.vertices_at`` does in SQL (docs/storage.md, "Snapshots at t").
Everything is compared bit for bit with the same feature stored as rows.
"""

from __future__ import annotations

import struct
from typing import Any

import numpy as np
import psycopg
import pytest

import tgsis
from tests.merge_data import curved_surface
from tests.sessions import Background, connect, wait_until_blocked
from tests.test_model2_chunks import NAN_PAYLOAD, _bits, _insert_chunk_rows_calls, _surface_bits
from tgsis.temporal import EvolvingSurface, TopologyPeriod

Conn = psycopg.Connection[Any]

TABLES = ("d4dtrgl", "d4dvrtx")
FIRST = (-0.0, 0.1 + 0.2, 1.0)
SECOND = (1.0, 2.0, 5.0)
#: at every geometry instant, between them, before, after, at the ends, near a boundary
ASKED = (*FIRST, *SECOND, 0.15, 0.5, 0.999999999, 1.5, 3.0, 5.5, 6.0, -1.0, 0.0, 7.5)
SIDE = 40  # 1,600 nodes a period: the second period's ids start inside a chunk (1600 = 1024 + 576)


def _store(conn: Conn, to: str) -> None:
    """Model 3's tables in ``to``, whatever TGSIS_TEST_TIME_STORAGE made them."""
    for table in TABLES if to == "chunks" else reversed(TABLES):
        row = conn.execute("SELECT tgsis.stored_in_chunks(%s)", (table,)).fetchone()
        if (row == (True,)) != (to == "chunks"):
            conn.execute(f"SELECT tgsis.store_in_{to}(%s)", (table,))
    conn.commit()


def _class(conn: Conn, versioned: bool) -> None:
    _store(conn, "rows")
    tgsis.create_feature_class(
        conn,
        "evolving",
        "SURFACE",
        time_model="EVOLVING",
        cell_properties=[("porosity", "float8")],
        instant_properties=[("throw", "double precision")],
    )
    if versioned:
        tgsis.enable_feature_versioning(conn)
    conn.commit()


def _shape(t: float) -> np.ndarray:
    """The curved grid at time t: hostile values (-0.0, a subnormal, 2.5e15 moving by a unit) among curved ones."""
    s = curved_surface(SIDE)
    xyz: np.ndarray = (
        s.vertices
        + np.array([0.1 * t, 0.0, 0.0])
        + np.stack([np.zeros(SIDE * SIDE)] * 2 + [30.0 * np.sin(t + s.vertices[:, 0] / 500.0)], 1)
    )
    xyz[0] = (-0.0, -0.0, -0.0)
    xyz[5, 2], xyz[7, 0] = 5e-324, 2.5e15 + t
    return xyz


def _period(times: tuple[float, ...]) -> TopologyPeriod:
    porosity = np.stack([np.linspace(0.1, 0.3, SIDE * SIDE) * (1.0 + i) for i in range(len(times))])
    porosity[:, 3], porosity[:, 4] = NAN_PAYLOAD, -0.0
    return TopologyPeriod(
        np.asarray(times),
        curved_surface(SIDE).cells,
        np.stack([_shape(t) for t in times]),
        vertex_properties={"porosity": porosity},
        properties={"throw": np.asarray([10.0 * (i + 1) for i in range(len(times))])},
    )


def _surface() -> EvolvingSurface:
    return EvolvingSurface([_period(FIRST), _period(SECOND)], name="evolving fault")


def _edits(conn: Conn, geoid: int) -> None:
    """psql edits through the faces: a node known at one geometry instant only, far above the others (a hole
    run; the interpolations around it leave it out), a triangle deleted; then a third period from Python."""
    conn.execute("INSERT INTO tgsis.d4dvrtx VALUES (%s, 1.0, 2.0, 9000, '-0'::float8, 1.5, 5e-324)", (geoid,))
    conn.execute("DELETE FROM tgsis.d4dtrgl WHERE geoid = %s AND timem = 1.0 AND trglid = %s", (geoid, 3100))
    conn.commit()
    tgsis.append_period(conn, "evolving", geoid, _period((5.0, 6.0)))
    conn.commit()


def _python_reads(conn: Conn, geoid: int) -> dict[str, Any]:
    """What the Python readers of model 3 give of the feature, doubles by their bits."""
    reads: dict[str, Any] = {}
    for t in ASKED:
        reads[f"get_at {t!r}"] = _surface_bits(tgsis.get_at(conn, geoid, t, properties=True))
    reads["surfaces_at"] = {
        t: [_surface_bits(s)[:2] for g, s in sorted(tgsis.surfaces_at(conn, "evolving", t).items()) if g == geoid]
        for t in (0.5, 2.0, 5.5)
    }
    try:
        surface = tgsis.fetch_evolving(conn, "evolving", geoid)
    except tgsis.InvalidGeometryError as exc:  # (the node of one instant: refused, on rows as on chunks)
        reads["periods"] = str(exc).replace(f"feature {geoid}", "feature").replace(f"({geoid})", "()")
        conn.rollback()
        return reads
    reads["periods"] = [
        (_bits(p.times), p.triangles.tolist(), _bits(p.positions), _bits(p.vertex_properties["porosity"]))
        for p in surface.periods
    ]
    conn.rollback()
    return reads


def _send(value: float) -> bytes:
    """``float8send``'s bytes of a double."""
    return struct.pack(">d", value)


FACES = {
    "d4dvrtx": "SELECT float8send(timem), float8send(timet), nodeid, float8send(x), float8send(y), float8send(z) "
    "FROM tgsis.d4dvrtx WHERE geoid = %s ORDER BY timem, timet, nodeid",
    "d4dtrgl": "SELECT float8send(timem), trglid, nodeid1, nodeid2, nodeid3 FROM tgsis.d4dtrgl WHERE geoid = %s "
    "ORDER BY 1, 2",
}
CHUNKS = {
    "d4dvrtx": "SELECT float8send(timem), float8send(timet), chunk, holes, array_send(x), array_send(y), "
    "array_send(z) FROM tgsis.d4dvrtx_chunk WHERE geoid = %s AND NOT revclosed ORDER BY timem, timet, chunk",
    "d4dtrgl": "SELECT float8send(timem), chunk, holes, vbase, array_send(nodeid1), array_send(nodeid2), "
    "array_send(nodeid3) FROM tgsis.d4dtrgl_chunk WHERE geoid = %s AND NOT revclosed ORDER BY timem, chunk",
}


@pytest.mark.parametrize("versioned", [False, True])
def test_the_client_transfers_model3_chunks_bit_for_bit(conn: Conn, versioned: bool, monkeypatch: Any) -> None:
    import tgsis.db._chunk_transfer as chunk_transfer

    _class(conn, versioned)
    on_rows = tgsis.insert_feature(conn, "evolving", _surface())
    conn.commit()
    _edits(conn, on_rows)
    expected = _python_reads(conn, on_rows)
    assert expected["get_at 2.0"][0][-3:] == _bits([-0.0, 1.5, 5e-324])  # the node of one instant, at it
    assert len(expected["get_at 1.5"][0]) == 3 * SIDE * SIDE  # and not between its instant and the others
    assert len(expected["get_at 3.0"][1]) == len(curved_surface(SIDE).cells) - 1
    assert sum(v is None for k, v in expected.items() if k.startswith("get_at")) == 2  # before, after its life

    _store(conn, "chunks")
    reads: list[str] = []

    def spy(real: Any) -> Any:
        def instant_rows(connection: Conn, layout: Any, *args: Any, **kwargs: Any) -> Any:
            reads.append(layout.table)
            return real(connection, layout, *args, **kwargs)

        return instant_rows

    monkeypatch.setattr("tgsis.db._temporal_common.instant_rows", spy(chunk_transfer.instant_rows))
    # an instant's chunks in several blocks (one chunk each), joined by the client
    monkeypatch.setattr(chunk_transfer, "INSTANT_BLOCK_BITS", 0)
    assert _python_reads(conn, on_rows) == expected  # rows converted by the switch, read from chunks
    snapshots = sum(1 for k, v in expected.items() if k.startswith("get_at") and v is not None)
    # every snapshot and surfaces_at read both tables' chunks (more when consistent_read read again)
    assert min(reads.count("d4dvrtx"), reads.count("d4dtrgl")) >= snapshots + 3

    # the upload encodes the periods' chunks in the client: one COPY per table, no tgsis.insert_chunk_rows
    conn.execute("SET track_functions = 'all'")
    tgsis.get_at(conn, on_rows, 0.5)  # (a transaction is open: the upload runs in a savepoint of it)
    on_chunks = tgsis.insert_feature(conn, "evolving", _surface())
    assert _insert_chunk_rows_calls(conn) == 0
    revision = 0 if not versioned else conn.execute("SELECT revision FROM tgsis.write_revision()").fetchone()[0]  # type: ignore[index]
    stored = conn.execute(
        "SELECT float8send(timem), float8send(timet), chunk, revision, cardinality(x) FROM tgsis.d4dvrtx_chunk "
        "WHERE geoid = %s ORDER BY timem, timet, chunk",
        (on_chunks,),
    ).fetchall()
    first = [(_send(-0.0), _send(t), k, revision, n) for t in FIRST for k, n in ((0, 1024), (1, 576))]
    second = [(_send(1.0), _send(t), k, revision, n) for t in SECOND for k, n in ((1, 1024), (2, 1024), (3, 128))]
    assert stored == first + second  # the second period's nodes 1600.. from inside chunk 1, slot for slot per instant
    conn.commit()
    conn.execute("SET track_functions = 'all'")
    _edits(conn, on_chunks)
    assert _insert_chunk_rows_calls(conn) == 0  # the appended period too
    conn.commit()
    assert _python_reads(conn, on_chunks) == expected
    # what the client encoded is what the server decodes and what the conversion of the rows encoded
    for table in TABLES:
        assert conn.execute(FACES[table], (on_chunks,)).fetchall() == conn.execute(FACES[table], (on_rows,)).fetchall()
        assert (
            conn.execute(CHUNKS[table], (on_chunks,)).fetchall() == conn.execute(CHUNKS[table], (on_rows,)).fetchall()
        )
    conn.rollback()
    # and back to rows: the chunks written by the client give the rows the rows' upload wrote
    monkeypatch.undo()
    _store(conn, "rows")
    assert _python_reads(conn, on_chunks) == expected


def _counts(conn: Conn) -> tuple[Any, ...]:
    row = conn.execute(
        "SELECT (SELECT count(*) FROM tgsis.geometry), (SELECT count(*) FROM tgsis.d4dvrtx_chunk), "
        "(SELECT count(*) FROM tgsis.d4dtrgl_chunk), (SELECT count(*) FROM tgsis.node)"
    ).fetchone()
    conn.rollback()
    assert row is not None
    return tuple(row)


def test_a_period_changed_into_a_degenerate_one_is_refused_by_name(conn: Conn) -> None:
    """A triangle naming a node twice (changed after the period was checked): the rows' CHECK
    (d4dtrgl_distinct_nodes) refused it, the chunk table has none: the client refuses it, nothing written."""
    _class(conn, False)
    _store(conn, "chunks")
    geoid = tgsis.insert_feature(conn, "evolving", _surface())
    conn.commit()
    before = _counts(conn)
    bad = _period((5.0, 6.0))
    bad.triangles[3] = [2, 5, 2]
    with pytest.raises(tgsis.InvalidGeometryError, match=r"uses a vertex twice: \[3202, 3205, 3202\]"):
        tgsis.append_period(conn, "evolving", geoid, bad)
    conn.rollback()
    surface = _surface()
    surface.periods[0].triangles[7] = [9, 9, 10]
    with pytest.raises(tgsis.InvalidGeometryError, match=r"uses a vertex twice: \[9, 9, 10\]"):
        tgsis.insert_feature(conn, "evolving", surface)
    conn.rollback()
    assert _counts(conn) == before


def test_a_role_reads_and_writes_chunks_with_its_own_rights(db_dsn: str, conn: Conn, monkeypatch: Any) -> None:
    import tgsis.db._chunk_transfer as chunk_transfer
    from tests.roles import login_roles

    uploads: list[tuple[str, bool]] = []
    real = chunk_transfer.upload_instants

    def spy(connection: Conn, table: str, *args: Any, **kwargs: Any) -> bool:
        done = real(connection, table, *args, **kwargs)
        uploads.append((table, done))
        return done

    monkeypatch.setattr("tgsis.db._chunk_transfer.upload_instants", spy)  # (write_instants calls it)

    _class(conn, True)
    _store(conn, "chunks")
    geoid = tgsis.insert_feature(conn, "evolving", _surface())
    conn.commit()
    expected = _surface_bits(tgsis.get_at(conn, geoid, 1.5))
    conn.rollback()
    before = _counts(conn)
    with login_roles(db_dsn, {"reader": "tgsis_reader", "editor": "tgsis_editor"}) as roles:
        reader = roles.connect("reader")
        assert _surface_bits(tgsis.get_at(reader, geoid, 1.5)) == expected
        reader.rollback()
        uploads.clear()
        with pytest.raises(tgsis.errors.Error) as refused:  # (refused before its chunks: the feature's row lock)
            tgsis.append_period(reader, "evolving", geoid, _period((5.0, 6.0)))
        assert isinstance(refused.value, tgsis.errors.MissingPrivilegeError), refused.value
        reader.rollback()
        assert _counts(conn) == before
        editor = roles.connect("editor")
        tgsis.append_period(editor, "evolving", geoid, _period((5.0, 6.0)))
        assert uploads == [("d4dtrgl", True), ("d4dvrtx", True)]  # the client's COPY, as the editor
        editor.commit()
        assert _surface_bits(tgsis.get_at(reader, geoid, 5.5)) == _surface_bits(tgsis.get_at(conn, geoid, 5.5))


def test_two_writers_of_one_feature_wait_for_each_other(db_dsn: str, conn: Conn) -> None:
    """A psql writer of the feature's node positions in flight: the client's upload waits for its commit (the
    object's write lock), then writes; a second append of the same period waits, then is refused by name."""
    _class(conn, False)
    _store(conn, "chunks")
    geoid = tgsis.insert_feature(conn, "evolving", _surface())
    conn.commit()
    first = connect(db_dsn, "first")
    first.execute(
        "UPDATE tgsis.d4dvrtx SET x = x + 1 WHERE geoid = %s AND timem = 1.0 AND timet = 5.0 AND nodeid = 1700",
        (geoid,),
    )
    second = Background(db_dsn, "second", lambda s: tgsis.append_period(s, "evolving", geoid, _period((5.0, 6.0))))
    wait_until_blocked(conn, second.pid, first.info.backend_pid)
    conn.rollback()
    first.commit()
    second.finish()
    x = conn.execute(
        "SELECT x FROM tgsis.d4dvrtx WHERE geoid = %s AND timem = 1.0 AND timet = 5.0 AND nodeid = 1700", (geoid,)
    ).fetchone()
    assert x == (_shape(5.0)[100, 0] + 1,)
    assert [p.times.tolist() for p in tgsis.fetch_evolving(conn, "evolving", geoid).periods][-1] == [5.0, 6.0]
    conn.rollback()
    # two appends of one period: the second waits for the first (the feature's row), then sees its last instant
    one = connect(db_dsn, "one")
    tgsis.append_period(one, "evolving", geoid, _period((6.0, 7.0)))
    two = Background(db_dsn, "two", lambda s: tgsis.append_period(s, "evolving", geoid, _period((6.0, 7.0))))
    wait_until_blocked(conn, two.pid, one.info.backend_pid)
    conn.rollback()
    one.commit()
    one.close()
    with pytest.raises(tgsis.InvalidInputError, match="not at its last geometry instant"):
        two.finish()
    got = tgsis.fetch_evolving(conn, "evolving", geoid)
    assert [p.times.tolist() for p in got.periods][-2:] == [[5.0, 6.0], [6.0, 7.0]]
    assert conn.execute(
        "SELECT count(*) FROM tgsis.d4dvrtx_chunk WHERE geoid = %s AND timem = 6.0", (geoid,)
    ).fetchone() == (2 * 3,)  # two instants of nodes 4800..6399 (chunks 4, 5, 6), written once
    first.close()


@pytest.mark.parametrize("read", ["get_at", "surfaces_at"])
def test_an_older_snapshot_after_the_switch_reads_the_surface_or_40001(db_dsn: str, conn: Conn, read: str) -> None:
    """A REPEATABLE READ snapshot taken before the switch into chunks: the chunk tables are newer than it (it
    would read them empty); the client's read gets 40001 (tgsis.chunk_snapshot_guard), never an empty surface."""
    _class(conn, False)
    geoid = tgsis.insert_feature(conn, "evolving", _surface())
    conn.commit()
    expected = _surface_bits(tgsis.get_at(conn, geoid, 1.5))
    conn.rollback()
    reader = connect(db_dsn, "reader")
    reader.execute("SET TRANSACTION ISOLATION LEVEL REPEATABLE READ")
    reader.execute("SELECT count(*) FROM pg_catalog.pg_namespace")  # the snapshot, before the switch
    _store(conn, "chunks")

    def got() -> Any:
        if read == "get_at":
            return _surface_bits(tgsis.get_at(reader, geoid, 1.5))
        return _surface_bits(tgsis.surfaces_at(reader, "evolving", 1.5)[geoid])

    try:
        answer, state = got(), None
    except (psycopg.Error, tgsis.errors.Error) as exc:
        answer, state = None, exc.sqlstate
    reader.rollback()
    assert state == "40001" or answer == expected, (state, answer is None)
    assert got() == expected  # the retry, in a new snapshot
    reader.close()
