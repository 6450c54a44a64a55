"""Model 3's ``fetch_evolving`` reads ``d4dvrtx`` and ``d4dtrgl`` from their chunks, decoded by the client.

With model 3's tables stored in chunks, ``fetch_evolving`` takes every period's node positions and triangles
from the chunks the session sees (``tgsis.db._chunk_transfer.instant_rows``, as model 2's ``fetch_series``),
not through the faces (the server decoding each chunk into rows). Compared bit for bit with the same feature
stored as rows: hostile coordinates (NaN with a payload, -0.0, subnormals), holes left by psql deletes, a
versioned class read at an old revision, a snapshot older than the switch, and a commit of another session
between the reads.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import psycopg
import pytest
from psycopg import sql

import tgsis
from tests.sessions import connect
from tests.test_model2_chunks import NAN_PAYLOAD, _bits
from tests.test_model3_client_chunks import SIDE, _class, _period, _store
from tgsis.temporal import EvolvingSurface

Conn = psycopg.Connection[Any]

HOLE = 2000  # a node of the second period (ids 1600..3199), deleted at every instant: a hole inside chunk 1


def _surface() -> EvolvingSurface:
    """Two periods; subnormals, the smallest normal and -0.0 among the coordinates of a middle instant (an upload
    refuses NaN: the edits write one)."""
    first, second = _period((-0.0, 0.1 + 0.2, 1.0)), _period((1.0, 2.0, 5.0))
    first.positions[1, 9] = (-5e-324, -0.0, 2.2250738585072014e-308)
    second.positions[1, 1030] = (-0.0, 5e-324, -2.2250738585072014e-308)
    return EvolvingSurface([first, second], name="evolving fault", color=(0.25, 0.5, 0.75))


def _edits(conn: Conn, geoid: int) -> None:
    """psql edits through the faces: a node of the second period deleted (its triangles, its positions at every
    instant, its node row, its porosity), a subnormal and a -0.0 written at one instant (a NaN makes no period: refused below)."""
    conn.execute(
        "DELETE FROM tgsis.d4dtrgl WHERE geoid = %s AND timem = 1.0 AND %s IN (nodeid1, nodeid2, nodeid3)",
        (geoid, HOLE),
    )
    conn.execute("DELETE FROM tgsis.d4dvrtx WHERE geoid = %s AND timem = 1.0 AND nodeid = %s", (geoid, HOLE))
    conn.execute("DELETE FROM tgsis.node WHERE geoid = %s AND timem = 1.0 AND nodeid = %s", (geoid, HOLE))
    fc = tgsis.get_feature_class(conn, "evolving")
    conn.execute(
        sql.SQL("DELETE FROM {} WHERE _geoid = %s AND _timem = 1.0 AND _idx = %s").format(
            sql.Identifier(fc.schema, fc.cellprotable)
        ),
        (geoid, HOLE),
    )
    conn.execute(
        "UPDATE tgsis.d4dvrtx SET x = %b, z = '-0'::float8 WHERE geoid = %s AND timem = 1.0 AND timet = 2.0 "
        "AND nodeid = 1700",
        (-5e-324, geoid),
    )
    conn.commit()


def _fetched(conn: Conn, geoid: int) -> list[Any]:
    """``fetch_evolving`` of the feature, doubles by their bits."""
    surface = tgsis.fetch_evolving(conn, "evolving", geoid)
    return [
        surface.name,
        surface.alive,
        None if surface.color is None else _bits(surface.color),
        [
            (
                _bits(p.times),
                p.triangles.tolist(),
                _bits(p.positions),
                _bits(p.vertex_properties["porosity"]),
                _bits(p.properties["throw"]),
            )
            for p in surface.periods
        ],
    ]


def _reads(conn: Conn, geoid: int, revision: int | None) -> dict[str, Any]:
    """The feature now and, versioned, at its first saved revision."""
    reads = {"now": _fetched(conn, geoid)}
    conn.rollback()
    if revision is not None:
        with tgsis.at_revision(conn, revision, "DEFAULT", local=True):
            reads["old"] = _fetched(conn, geoid)
    return reads


def _spy(monkeypatch: Any) -> list[str]:
    """The tables whose chunks ``fetch_evolving`` reads (its calls of ``instant_rows``)."""
    import tgsis.db._chunk_transfer as chunk_transfer

    reads: list[str] = []

    def instant_rows(connection: Conn, layout: Any, *args: Any, **kwargs: Any) -> Any:
        reads.append(layout.table)
        return chunk_transfer.instant_rows(connection, layout, *args, **kwargs)

    monkeypatch.setattr("tgsis.db.evolving.instant_rows", instant_rows)
    return reads


@pytest.mark.parametrize("versioned", [False, True])
def test_fetch_evolving_reads_the_chunks_bit_for_bit_as_the_rows(conn: Conn, versioned: bool, monkeypatch: Any) -> None:
    import tgsis.db._chunk_transfer as chunk_transfer

    reads = _spy(monkeypatch)
    _class(conn, versioned)
    sent = _surface()
    on_rows = tgsis.insert_feature(conn, "evolving", sent)
    conn.commit()
    first = tgsis.save_revision(conn, "first") if versioned else None
    _edits(conn, on_rows)
    expected = _reads(conn, on_rows, first)
    assert reads == []  # rows: through the faces
    # what was sent, bits kept; then the edits: the hole and the written bits
    sent_positions = [_bits(p.positions) for p in sent.periods]
    assert expected["now"][3][0][2] == sent_positions[0]
    if versioned:
        assert [p[2] for p in expected["old"][3]] == sent_positions
    second = expected["now"][3][1]
    positions = np.asarray(second[2]).reshape(3, SIDE * SIDE - 1, 3)  # the hole's node left out
    assert positions[1, 1700 - 1600].tolist() == [
        _bits([-5e-324])[0],
        np.asarray(sent_positions[1]).reshape(3, SIDE * SIDE, 3)[1, 100, 1],
        _bits([-0.0])[0],
    ]
    assert 0 < len(second[1]) < len(sent.periods[1].triangles)

    _store(conn, "chunks")  # the rows converted by the switch
    monkeypatch.setattr(chunk_transfer, "INSTANT_BLOCK_BITS", 0)  # an instant's chunks in blocks of one, joined here
    assert _reads(conn, on_rows, first) == expected
    # every fetch read both tables from their chunks (more when consistent_read read again)
    assert reads.count("d4dvrtx") >= len(expected) and reads.count("d4dtrgl") >= len(expected)

    # a twin uploaded into chunks by the client, edited the same way
    on_chunks = tgsis.insert_feature(conn, "evolving", sent)
    conn.commit()
    again = tgsis.save_revision(conn, "second") if versioned else None
    _edits(conn, on_chunks)
    assert _reads(conn, on_chunks, again) == expected
    # and back to rows: the faces give what the chunks gave
    monkeypatch.undo()
    _store(conn, "rows")
    assert _reads(conn, on_chunks, again) == expected


@pytest.mark.parametrize("edit", ["one instant", "NaN", "moved instant"])
def test_rows_that_make_no_period_are_refused_as_on_rows(conn: Conn, monkeypatch: Any, edit: str) -> None:
    """A node inserted at one geometry instant of its period only, a NaN position (with a payload) written
    through the face, or a node's position at one instant moved to an instant ``timet`` does not list (the
    count of rows still right: it was read misaligned, the next nodes' positions shifted):
    InvalidGeometryError, the same message from the chunks as from the rows."""
    reads = _spy(monkeypatch)
    _class(conn, False)
    geoid = tgsis.insert_feature(conn, "evolving", _surface())
    if edit == "NaN":
        conn.execute(
            "UPDATE tgsis.d4dvrtx SET y = %b WHERE geoid = %s AND timem = 1.0 AND timet = 5.0 AND nodeid = 1601",
            (NAN_PAYLOAD, geoid),
        )
    elif edit == "moved instant":
        conn.execute(
            "UPDATE tgsis.d4dvrtx SET timet = 3.0 WHERE geoid = %s AND timem = 1.0 AND timet = 2.0 AND nodeid = 2000",
            (geoid,),
        )
    else:
        conn.execute("INSERT INTO tgsis.d4dvrtx VALUES (%s, 1.0, 2.0, 9000, 1.0, 1.5, 5e-324)", (geoid,))
    conn.commit()
    messages = []
    for storage in ("rows", "chunks"):
        _store(conn, storage)
        with pytest.raises(tgsis.InvalidGeometryError) as refused:
            tgsis.fetch_evolving(conn, "evolving", geoid)
        conn.rollback()
        messages.append(str(refused.value).replace(str(geoid), "<geoid>"))
    assert messages[0] == messages[1]
    assert ("must be finite" if edit == "NaN" else "lacks node positions") in messages[0]
    assert "d4dvrtx" in reads


def test_a_snapshot_older_than_the_switch_reads_the_rows_or_40001(db_dsn: str, conn: Conn, monkeypatch: Any) -> None:
    """A REPEATABLE READ snapshot taken before the switch to chunks committed: the rows, or 40001 (then the
    retry reads the chunks), never an empty feature."""
    reads = _spy(monkeypatch)
    _class(conn, False)
    geoid = tgsis.insert_feature(conn, "evolving", _surface())
    conn.commit()
    expected = _fetched(conn, geoid)
    conn.rollback()
    reader = connect(db_dsn, "reader")
    reader.execute("SET TRANSACTION ISOLATION LEVEL REPEATABLE READ")
    reader.execute("SELECT count(*) FROM pg_catalog.pg_namespace")
    _store(conn, "chunks")
    try:
        got = _fetched(reader, geoid)
    except (psycopg.Error, tgsis.errors.Error) as exc:
        assert exc.sqlstate == "40001", exc
        reader.rollback()
        got = _fetched(reader, geoid)  # the retry
    assert got == expected
    reader.rollback()
    assert _fetched(reader, geoid) == expected
    assert "d4dvrtx" in reads and "d4dtrgl" in reads
    reader.close()


def test_a_commit_between_the_reads_gives_one_state(db_dsn: str, conn: Conn, monkeypatch: Any) -> None:
    """Another session commits a change to the triangles and the positions after fetch_evolving read the first
    table's chunks: the feature comes back as it was before that commit or after it, never mixed."""
    import tgsis.db._chunk_transfer as chunk_transfer

    _class(conn, False)
    _store(conn, "chunks")
    geoid = tgsis.insert_feature(conn, "evolving", _surface())
    conn.commit()
    before = _fetched(conn, geoid)
    conn.rollback()
    calls: list[str] = []

    def instant_rows(connection: Conn, layout: Any, *args: Any, **kwargs: Any) -> Any:
        result = chunk_transfer.instant_rows(connection, layout, *args, **kwargs)
        calls.append(layout.table)
        if len(calls) == 1:
            with psycopg.connect(db_dsn) as other:
                other.execute(
                    "UPDATE tgsis.d4dtrgl SET nodeid1 = nodeid2, nodeid2 = nodeid1 WHERE geoid = %s AND timem = 1.0",
                    (geoid,),
                )
                other.execute("UPDATE tgsis.d4dvrtx SET y = y + 1 WHERE geoid = %s AND timem = 1.0", (geoid,))
        return result

    monkeypatch.setattr("tgsis.db.evolving.instant_rows", instant_rows)
    conn.execute("SELECT 1")  # the caller's READ COMMITTED transaction is open
    got = _fetched(conn, geoid)
    conn.rollback()
    assert len(calls) >= 3  # read again after the commit
    monkeypatch.undo()
    after = _fetched(conn, geoid)
    conn.rollback()
    assert after != before
    assert got == after
