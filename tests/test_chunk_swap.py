"""The client's chunk write of a check-in (tgsis.swap_object_chunks): the same chunks as the server's, no lost update.

A scattered edit touches nearly every chunk of an object; ``tgsis.write_object_rows``
re-aggregates each in SQL. The client path (``tgsis.db._chunk_write.swap_object_rows``)
reads the touched chunk versions with their places, merges the edit, encodes the chunks
itself and ``tgsis.swap_object_chunks`` swaps them in after the same checks, refusing
(TG300, nothing written) when a chunk's visible version is no longer the one read. These
tests switch their database to chunks themselves, whatever ``TGSIS_TEST_STORAGE`` says.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
import psycopg
import pytest
from psycopg import sql

import tgsis
from tests.roles import login_roles
from tests.test_chunk_checkin import _grid, _switch
from tgsis import _chunks
from tgsis.db import _chunk_write
from tgsis.db import features as F

Conn = psycopg.Connection[Any]

SIDE = 60  # 3,600 vertices (chunks 0..3, the last one partial) and 6,962 triangles (chunks 0..6)
N = SIDE * SIDE

#: a NaN with a payload, the smallest subnormal, -0.0: bit for bit through both paths
ODD = np.array([0x7FF8_0000_DEAD_BEEF, 1, 0x8000_0000_0000_0000], dtype=np.uint64).view(np.float64)


def _objects(conn: Conn, versioned: bool) -> tuple[int, int]:
    """Two objects holding the same grid, in chunks: one written by the server's path, one by the client's."""
    F.create_feature_class(conn, "horizons", "SURFACE", cell_properties={"porosity": "float8"})
    if versioned:
        tgsis.enable_feature_versioning(conn)
    a = F.insert_feature(conn, "horizons", _grid(SIDE))
    b = F.insert_feature(conn, "horizons", _grid(SIDE))
    conn.commit()
    _switch(conn)
    return a, b


def _digest(conn: Conn, table: str, geoid: int) -> list[tuple[Any, ...]]:
    """Every chunk version of the object, each column in its send form (arrays bit for bit), but geoid."""
    columns = conn.execute(
        "SELECT attname::text, format_type(atttypid, atttypmod) FROM pg_attribute "
        "WHERE attrelid = %s::regclass AND attnum > 0 AND NOT attisdropped AND attname <> 'geoid' ORDER BY attnum",
        (f"tgsis.{table}_chunk",),
    ).fetchall()
    parts = [
        sql.SQL("array_send(c.{})" if kind.endswith("[]") else "c.{}::text").format(sql.Identifier(name))
        for name, kind in columns
    ]
    query = sql.SQL("SELECT {} FROM {} c WHERE c.geoid = %s ORDER BY c.chunk, c.revision").format(
        sql.SQL(", ").join(parts), sql.Identifier("tgsis", f"{table}_chunk")
    )
    return [tuple(bytes(v) if isinstance(v, memoryview) else v for v in row) for row in conn.execute(query, (geoid,))]


def _both(conn: Conn, table: str, a: int, b: int, gone: list[int], ids: list[int], values: np.ndarray) -> None:
    """The edit written into ``a`` by the server's path and into ``b`` by the client's; the chunks compared."""
    vertices = table == "vrtx"
    floats, refs = (values, None) if vertices else (None, values)
    server = _chunk_write.write_object_rows(conn, table, a, gone, ids, floats=floats, refs=refs)
    client = _chunk_write.swap_object_rows(conn, table, b, gone, ids, floats=floats, refs=refs)
    conn.commit()
    assert client == server
    assert server > 0
    assert _digest(conn, table, b) == _digest(conn, table, a)


@pytest.mark.parametrize("versioned", [False, True], ids=["plain", "versioned"])
def test_the_client_writes_the_chunks_the_server_writes(conn: Conn, versioned: bool) -> None:
    """Scattered moves, ids at chunk boundaries and the last chunk, deletes, new ids, odd doubles; then a new revision.

    Fails when the client's encoding differs from tgsis.write_chunk_rows' in any
    byte (holes, vbase, vtop, wide refs, a NaN's payload, -0.0), or when an
    emptied chunk, an unchanged chunk or a chunk of an older revision is
    written otherwise (in place, closed, inserted, deleted).
    """
    a, b = _objects(conn, versioned)
    rng = np.random.default_rng(3)
    moved = sorted({0, 1023, 1024, 2047, 2048, 3071, 3072, N - 1, *rng.choice(N, 40, replace=False).tolist()} - {5})
    values = rng.random((len(moved), 3))
    values[:3] = ODD  # each of x, y, z of three vertices
    values[3:6] = ODD.reshape(3, 1)
    new = [N, N + 1, N + 1030]  # past the last chunk, one in a chunk of its own
    ids = moved + new
    values = np.concatenate([values, rng.random((len(new), 3))])
    _both(conn, "vrtx", a, b, [5, 1500, N - 2], ids, values)
    # the cells: changed, one far vertex (the chunk's refs become absolute, _wide), removed, added
    cells = [0, 1, 1023, 1024, 4000, 6961]
    refs = rng.integers(0, N, (len(cells), 3))
    refs[1] = [2**40, 3, 7]
    _both(conn, "trgl", a, b, [2, 5000], [*cells, 6962, 8000], np.concatenate([refs, [[1, 2, 3], [4, 5, 6]]]))
    # the same content written again: no chunk changes (both return 0 chunks written)
    assert _chunk_write.write_object_rows(conn, "vrtx", a, [], [0], floats=values[:1]) == 0
    assert _chunk_write.swap_object_rows(conn, "vrtx", b, [], [0], floats=values[:1]) == 0
    conn.commit()
    if versioned:
        tgsis.create_version(conn, "v1")  # DEFAULT gets a new working revision: the chunks are closed, written anew
        conn.commit()
    # a whole chunk emptied (the new one of N + 1030), moves in every other chunk
    _both(conn, "vrtx", a, b, [N + 1030], [7, 1030, 2060, N], rng.random((4, 3)))
    _both(conn, "trgl", a, b, list(range(2048, 3072)), [9], np.array([[9, 10, 11]]))
    face = "SELECT vrtxid, float8send(x), float8send(y), float8send(z) FROM tgsis.vrtx WHERE geoid = %s ORDER BY 1"
    assert conn.execute(face, (b,)).fetchall() == conn.execute(face, (a,)).fetchall()
    conn.commit()


def _with_writer_between(monkeypatch: pytest.MonkeyPatch, write: Callable[[], None]) -> None:
    """Run ``write`` (another session's committed write) after the client read its chunks, before it stages them."""

    def encode_then_write(*args: Any, **kwargs: Any) -> Any:
        write()
        return _chunks.encode(*args, **kwargs)

    monkeypatch.setattr(_chunk_write, "encode", encode_then_write)


@pytest.mark.parametrize("versioned", [False, True], ids=["plain", "versioned"])
@pytest.mark.parametrize("other", [1030, N + 5], ids=["changed-chunk", "new-chunk"])
def test_a_writer_between_read_and_swap_is_not_overwritten(
    conn: Conn, db_dsn: str, monkeypatch: pytest.MonkeyPatch, versioned: bool, other: int
) -> None:
    """Another session writes a chunk the edit touches after the client read it: TG300, its write kept.

    ``other``: a stored vertex of chunk 1 (its visible version changes), or a new
    vertex in a chunk no version held (one is inserted). Without the check of the
    places, the client's chunk (read before) would replace the other writer's.
    """
    a, _ = _objects(conn, versioned)
    before = _digest(conn, "vrtx", a)

    def other_writer() -> None:
        with psycopg.connect(db_dsn) as session:
            _chunk_write.write_object_rows(session, "vrtx", a, [], [other], floats=np.array([[9.0, 9.0, 9.0]]))
            session.commit()

    _with_writer_between(monkeypatch, other_writer)
    with pytest.raises(psycopg.Error) as caught:
        _chunk_write.swap_object_rows(conn, "vrtx", a, [], [1031, N + 6], floats=np.ones((2, 3)))
    assert caught.value.sqlstate == "TG300"
    conn.rollback()
    monkeypatch.undo()
    face = "SELECT vrtxid, x, y, z FROM tgsis.vrtx WHERE geoid = %s AND vrtxid = ANY (%s) ORDER BY 1"
    after = {r[0]: list(r[1:]) for r in conn.execute(face, (a, [other, 1031, N + 6])).fetchall()}
    conn.commit()
    assert after[other] == [9.0, 9.0, 9.0]  # the other writer's vertex is kept
    assert after[1031] != [1.0, 1.0, 1.0] and N + 6 not in after  # and nothing of this edit was written
    assert _digest(conn, "vrtx", a) != before
    # read again, the same edit goes through
    assert _chunk_write.swap_object_rows(conn, "vrtx", a, [], [1031, N + 6], floats=np.ones((2, 3)))
    conn.commit()


@pytest.mark.parametrize("versioned", [False, True], ids=["plain", "versioned"])
def test_a_check_in_that_loses_the_race_merges_as_the_server_does(
    conn: Conn, db_dsn: str, monkeypatch: pytest.MonkeyPatch, versioned: bool
) -> None:
    """The writer of a check-in (``_state_write.write_model_rows``) swaps; when the swap loses the race, it merges.

    A psql user's write through the face between the client's read and the swap
    must neither be lost nor make the check-in fail: the edit then goes through
    ``tgsis.write_object_rows`` (in the savepoint's place), which keeps both.
    Fails when the TG300 reaches the caller, or when the other write is lost.
    """
    from tgsis.db import _state_write
    from tgsis.db._transfer import Storage
    from tgsis.db.classes import get_feature_class

    a, _ = _objects(conn, versioned)
    fc = get_feature_class(conn, "horizons")

    def other_writer() -> None:
        with psycopg.connect(db_dsn) as session:
            session.execute("UPDATE tgsis.vrtx SET x = 9.0 WHERE geoid = %s AND vrtxid = 1030", (a,))
            session.commit()

    _with_writer_between(monkeypatch, other_writer)
    _state_write.write_model_rows(
        conn, Storage.of(conn, fc), "vrtx", "vrtxid", a, np.array([7]), np.array([1031, N + 6]), np.ones((2, 3))
    )
    conn.commit()
    monkeypatch.undo()
    face = "SELECT vrtxid, x, y, z FROM tgsis.vrtx WHERE geoid = %s AND vrtxid = ANY (%s) ORDER BY 1"
    after = {r[0]: list(r[1:]) for r in conn.execute(face, (a, [7, 1030, 1031, N + 6])).fetchall()}
    conn.commit()
    assert after[1030][0] == 9.0  # the other writer's value is kept
    assert after[1031] == [1.0, 1.0, 1.0] and after[N + 6] == [1.0, 1.0, 1.0]  # and the check-in's edit written
    assert 7 not in after


def test_roles_and_a_tampered_stage(conn: Conn, db_dsn: str) -> None:
    """An editor swaps through the stage; a role without DELETE falls back (and is refused the swap); bad chunks refused."""
    a, b = _objects(conn, True)
    before = _digest(conn, "vrtx", b)
    with login_roles(db_dsn, {"ed": "tgsis_editor", "ap": "tgsis_editor", "rd": "tgsis_reader"}) as made:
        ed = made.connect("ed")
        assert _chunk_write.swap_object_rows(ed, "vrtx", a, [3], [4, 2000], floats=np.ones((2, 3))) == 2
        ed.commit()
        # the stage and the grant on it end with the transaction: nothing of it keeps DROP ROLE from the role
        assert ed.execute("SELECT to_regclass('pg_temp.tgsis_object_chunks_vrtx')").fetchone() == (None,)
        ed.commit()
        held = conn.execute(
            "SELECT count(*) FROM pg_shdepend d JOIN pg_roles r ON r.oid = d.refobjid WHERE r.rolname = %s",
            (made.name("ed"),),
        ).fetchone()
        conn.commit()
        assert held == (0,)
        row = conn.execute("SELECT x, y, z FROM tgsis.vrtx WHERE geoid = %s AND vrtxid IN (3, 2000)", (a,)).fetchall()
        assert row == [(1.0, 1.0, 1.0)]  # 3 gone, 2000 written
        conn.commit()
        # a role without DELETE on the face: not this path (None, nothing done); a direct swap refused
        conn.execute(sql.SQL("REVOKE DELETE ON tgsis.vrtx FROM tgsis_editor"))
        conn.commit()
        ap = made.connect("ap")
        assert _chunk_write.swap_object_rows(ap, "vrtx", b, [], [1], floats=np.ones((1, 3))) is None
        ap.execute("SELECT tgsis.object_chunks_stage('vrtx')")
        with pytest.raises(psycopg.errors.InsufficientPrivilege):
            ap.execute("SELECT tgsis.swap_object_chunks('vrtx', %s, '{0}', '{NULL}')", (b,))
        ap.rollback()
        conn.execute(sql.SQL("GRANT DELETE ON tgsis.vrtx TO tgsis_editor"))
        conn.commit()
        # a reader may not write at all
        rd = made.connect("rd")
        assert _chunk_write.swap_object_rows(rd, "vrtx", b, [], [1], floats=np.ones((1, 3))) is None
        rd.rollback()
        # staged chunks not encoded as the readers read them, or of another object or chunk: 23514, nothing written
        for values in (
            f"({b}, 0, 0, NULL, '{{1,2}}', '{{1}}', '{{1,2}}')",  # arrays of unequal length
            f"({b}, 0, 0, '{{1}}', '{{1,2}}', '{{1,2}}', '{{1,2}}')",  # a hole that is not NULL
            f"({a}, 0, 0, NULL, '{{1}}', '{{1}}', '{{1}}')",  # another object
            f"({b}, 1, 0, NULL, '{{1}}', '{{1}}', '{{1}}')",  # a chunk not given
        ):
            stage = ed.execute("SELECT tgsis.object_chunks_stage('vrtx')").fetchone()
            assert stage is not None
            ed.execute(f"INSERT INTO {stage[0]} (geoid, chunk, revision, holes, x, y, z) VALUES {values}")
            place = ed.execute(
                "SELECT c.tableoid::text || ':' || c.ctid::text || ':' || c.xmin::text FROM tgsis.vrtx_chunk c "
                "WHERE c.geoid = %s AND c.chunk = 0 AND NOT c.revclosed",
                (b,),
            ).fetchone()
            assert place is not None
            with pytest.raises(psycopg.errors.CheckViolation):
                ed.execute("SELECT tgsis.swap_object_chunks('vrtx', %s, '{0}', %s::text[])", (b, [place[0]]))
            ed.rollback()
        # the base of another place (a stale read): TG300
        ed.execute("SELECT tgsis.object_chunks_stage('vrtx')")
        with pytest.raises(psycopg.Error) as caught:
            ed.execute("SELECT tgsis.swap_object_chunks('vrtx', %s, '{0}', %s::text[])", (b, ["0:(0,1):1"]))
        assert caught.value.sqlstate == "TG300"
        ed.rollback()
    assert _digest(conn, "vrtx", b) == before
