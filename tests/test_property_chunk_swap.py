"""The client's chunk write of a class's property edit (tgsis.swap_object_chunks on a property table, issue 40).

docs/storage.md, "The bulk paths of property chunks": a check-in of a class whose properties are in chunks
sent its rows to ``tgsis.write_property_rows``, which re-aggregates every touched chunk in SQL (a scattered
edit: ~30 ms a chunk, 7.1x rows). Now the client reads the touched chunk versions with their places, merges
the edit, encodes the chunks (NULL values kept apart from holes) and ``tgsis.swap_object_chunks`` swaps them
in after the same checks, refusing (TG300, nothing written) when a chunk's visible version is no longer the one
read. These tests compare it, chunk version for chunk version in send form, with the server's path. The
property tables are chunks whatever model 1's storage is, so the file runs unmarked.
"""

from __future__ import annotations

import struct
from collections.abc import Callable
from typing import Any

import numpy as np
import psycopg
import pytest
from psycopg import sql

import tgsis
from tests.merge_data import curved_surface, sqlstate
from tests.roles import login_roles
from tests.storage_data import classes_as_rows
from tgsis import _chunks
from tgsis.db import _property_chunks
from tgsis.db import features as F
from tgsis.mesh import Surface

Conn = psycopg.Connection[Any]


@pytest.fixture(autouse=True)
def _classes_as_rows(db_dsn: str) -> None:
    """The classes these tests make start as rows: they switch them to chunks themselves, or compare with a rows
    twin (docs/storage.md, "Property chunks by default: the rule")."""
    classes_as_rows(db_dsn)


N = 1600  # curved_surface(40): chunks 0 and 1 (partial)
TABLE = "public.rock_cellpros"
#: a NaN with a payload, the smallest subnormal, -0.0: bit for bit through both paths
ODD = np.array([0x7FF8_0000_DEAD_BEEF, 1, 0x8000_0000_0000_0000], dtype=np.uint64).view(np.float64)
ODD4 = np.array([0x7FC0_0ABC, 1, 0x8000_0000], dtype=np.uint32).view(np.float32)


def _objects(conn: Conn, versioned: bool) -> tuple[int, int]:
    """Two objects of class rock with the same surface, properties in chunks, some values NULL (a face UPDATE)."""
    tgsis.create_feature_class(
        conn,
        "rock",
        "SURFACE",
        cell_properties=[("porosity", "double precision"), ("facies", "integer"), ("perm", "real")],
    )
    if versioned:
        tgsis.enable_feature_versioning(conn)
    surface = curved_surface(40)
    mesh = Surface(
        surface.vertices,
        surface.cells,
        vertex_properties={
            "porosity": surface.vertex_properties["porosity"],
            "facies": (np.arange(N, dtype=np.int32) % 7) - 3,
            "perm": np.linspace(0, 1, N, dtype=np.float32),
        },
    )
    a, b = (F.insert_feature(conn, "rock", mesh) for _ in range(2))
    conn.commit()
    conn.execute("SELECT tgsis.store_class_in_chunks('rock')")
    # NULL values at present slots (a collection member's missing property): kept apart from holes
    conn.execute(
        "ALTER TABLE public.rock_cellpros_shape ALTER COLUMN facies DROP NOT NULL, ALTER COLUMN perm DROP NOT NULL"
    )
    conn.execute(
        "UPDATE public.rock_cellpros SET facies = NULL, perm = NULL WHERE _idx IN (2, 1030, 1500) "
        "AND _geoid = ANY (%s)",
        ([a, b],),
    )
    conn.commit()
    return a, b


def _digest(conn: Conn, geoid: int) -> list[tuple[Any, ...]]:
    """Every chunk version of the object, each column in its send form (arrays bit for bit), but _geoid."""
    columns = conn.execute(
        "SELECT attname::text, format_type(atttypid, atttypmod) FROM pg_attribute "
        "WHERE attrelid = 'public.rock_cellpros_chunk'::regclass AND attnum > 0 AND NOT attisdropped "
        "AND attname <> '_geoid' ORDER BY attnum"
    ).fetchall()
    parts = [
        sql.SQL("array_send(c.{})" if kind.endswith("[]") else "c.{}::text").format(sql.Identifier(name))
        for name, kind in columns
    ]
    query = sql.SQL("SELECT {} FROM public.rock_cellpros_chunk c WHERE c._geoid = %s ORDER BY c.chunk, c.revision")
    rows = conn.execute(query.format(sql.SQL(", ").join(parts)), (geoid,)).fetchall()
    return [tuple(bytes(v) if isinstance(v, memoryview) else v for v in row) for row in rows]


def _columns(geoid: int, ids: list[int], rng: np.random.Generator, *, partial: bool = False) -> list[Any]:
    """The rows written: odd doubles and reals among them; ``partial``: facies not given (NULL in them)."""
    n = len(ids)
    porosity = rng.random(n)
    perm = rng.random(n).astype(np.float32)
    if n >= 3:
        porosity[:3], perm[:3] = ODD, ODD4
    columns = [
        ("_geoid", np.full(n, geoid, dtype=np.int64), "int8"),
        ("_idx", np.asarray(ids, dtype=np.int64), "int8"),
        ("porosity", porosity, "float8"),
        ("perm", perm, "float4"),
    ]
    if not partial:
        columns.append(("facies", rng.integers(-5, 5, n).astype(np.int32), "int4"))
    return columns


def _server(conn: Conn, geoid: int, gone: list[int], columns: list[Any], monkeypatch: pytest.MonkeyPatch) -> int:
    """The edit by tgsis.write_property_rows (the client's swap switched off)."""
    with monkeypatch.context() as patch:
        patch.setattr(_property_chunks, "_swapped", lambda *args: None)
        written = _property_chunks.write_property_rows(conn, "public", "rock_cellpros", geoid, gone, columns)
    assert written is not None
    return written


def _both(
    conn: Conn, a: int, b: int, gone: list[int], ids: list[int], monkeypatch: pytest.MonkeyPatch, **kw: Any
) -> int:
    """The edit written into ``a`` by the server's path and into ``b`` by the client's; the chunks compared."""
    server = _server(conn, a, gone, _columns(a, ids, np.random.default_rng(7), **kw), monkeypatch)
    client = _property_chunks.swap_property_rows(
        conn, "public", "rock_cellpros", b, gone, _columns(b, ids, np.random.default_rng(7), **kw)
    )
    conn.commit()
    assert client == server
    assert _digest(conn, b) == _digest(conn, a)
    return server


@pytest.mark.parametrize("versioned", [False, True], ids=["plain", "versioned"])
def test_the_client_writes_the_chunks_the_server_writes(
    conn: Conn, versioned: bool, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Scattered changes, deletes (holes), new ids past the last chunk, rows without a property (NULL values), odd
    floats; an unchanged write; then a new revision. Fails when the client's encoding or the write of any chunk
    version (in place, closed, inserted, deleted) differs from tgsis.write_chunk_rows' in any byte."""
    a, b = _objects(conn, versioned)
    rng = np.random.default_rng(3)
    changed = sorted({0, 1023, 1024, N - 1, *rng.choice(N, 60, replace=False).tolist()} - {5, 2, 1030})
    new = [N, N + 1, N + 1030]  # past the last chunk, one in a chunk of its own
    assert _both(conn, a, b, [5, 1500, *changed], changed + new, monkeypatch) > 0
    # rows written without facies: NULL there; a delete only
    assert _both(conn, a, b, [7, 1031], [7, 1031, N + 2], monkeypatch, partial=True) > 0
    assert _both(conn, a, b, [9], [], monkeypatch) > 0
    # the same content again: no chunk written by either
    rows = (
        conn.cursor(binary=True)
        .execute("SELECT porosity, facies, perm FROM public.rock_cellpros WHERE _geoid = %s AND _idx = 0", (a,))
        .fetchone()
    )  # in binary: the NaN's payload read as it is
    assert rows is not None
    same = [
        ("_geoid", np.array([b]), "int8"),
        ("_idx", np.array([0]), "int8"),
        ("porosity", np.array([rows[0]]), "float8"),
        ("facies", np.array([rows[1]], dtype=np.int32), "int4"),
        ("perm", np.array([rows[2]], dtype=np.float32), "float4"),
    ]
    assert _property_chunks.swap_property_rows(conn, "public", "rock_cellpros", b, [0], same) == 0
    conn.commit()
    if versioned:
        tgsis.create_version(conn, "v1")  # DEFAULT gets a new working revision: the chunks are closed, written anew
        conn.commit()
    # a whole chunk emptied (the one of N + 1030), changes in the others
    assert _both(conn, a, b, [N + 1030, 11, 1040], [11, 1040], monkeypatch) > 0
    face = (
        "SELECT _idx, float8send(porosity), facies, float4send(perm) FROM public.rock_cellpros "
        "WHERE _geoid = %s ORDER BY 1"
    )
    seen_a, seen_b = conn.execute(face, (a,)).fetchall(), conn.execute(face, (b,)).fetchall()
    assert seen_b == seen_a
    by_id = {r[0]: r for r in seen_b}
    assert by_id[2][2] is None and by_id[2][3] is None  # the NULL values kept, not holes
    assert 5 not in by_id and 9 not in by_id and N + 1030 not in by_id
    assert by_id[N + 2][2] is None  # written without facies
    conn.commit()


def test_a_check_in_takes_the_client_path_bit_for_bit(conn: Conn, monkeypatch: pytest.MonkeyPatch) -> None:
    """save_feature of a scattered edit swaps the chunks the client encoded (one swap, no server aggregation) and
    reads back what it saved: -0.0 and a NaN payload."""
    a, _ = _objects(conn, True)
    # (a mesh's property has a value at every vertex: fetch_feature refuses NULL values)
    conn.execute("UPDATE public.rock_cellpros SET facies = 0, perm = 0 WHERE facies IS NULL AND _geoid = %s", (a,))
    tgsis.create_version(conn, "e1")
    conn.commit()
    calls: list[int | None] = []
    swap = _property_chunks.swap_property_rows

    def spy(*args: Any) -> int | None:
        calls.append(swap(*args))
        return calls[-1]

    monkeypatch.setattr(_property_chunks, "swap_property_rows", spy)
    with tgsis.in_version(conn, "e1"):
        mesh = F.fetch_feature(conn, "rock", a).mesh
        conn.commit()
        assert isinstance(mesh, Surface)
        porosity = mesh.vertex_properties["porosity"].copy()
        porosity[::50] += 1.0
        porosity[3], porosity[1100] = ODD[2], ODD[0]
        edited = Surface(mesh.vertices, mesh.cells, vertex_properties={**mesh.vertex_properties, "porosity": porosity})
        tgsis.save_feature(conn, "rock", a, edited)
        conn.commit()
        assert calls and calls[-1] == 2  # the two chunks, closed in DEFAULT's revision, written anew in e1's
        got = conn.execute(
            "SELECT float8send(porosity) FROM public.rock_cellpros WHERE _geoid = %s AND _idx IN (3, 1100) ORDER BY 1",
            (a,),
        ).fetchall()
        assert sorted(g[0] for g in got) == sorted([struct.pack(">d", -0.0), ODD[:1].byteswap().tobytes()])
    conn.commit()


def _with_writer_between(monkeypatch: pytest.MonkeyPatch, write: Callable[[], None]) -> None:
    """Run ``write`` (another session's committed write) after the client read its chunks, before it stages them."""

    def encode_then_write(*args: Any, **kwargs: Any) -> Any:
        write()
        return _chunks.encode(*args, **kwargs)

    monkeypatch.setattr(_property_chunks, "encode", encode_then_write)


@pytest.mark.parametrize("versioned", [False, True], ids=["plain", "versioned"])
def test_a_writer_between_read_and_swap_is_kept(
    conn: Conn, db_dsn: str, monkeypatch: pytest.MonkeyPatch, versioned: bool
) -> None:
    """A psql UPDATE through the face between the client's read and the swap: the swap refuses (TG300, nothing
    written) and the edit goes by tgsis.write_property_rows, which keeps both. Fails when the client's chunk,
    read before, replaces the other writer's value."""
    a, _ = _objects(conn, versioned)

    def other_writer() -> None:
        with psycopg.connect(db_dsn) as session:
            session.execute("UPDATE public.rock_cellpros SET facies = 99 WHERE _geoid = %s AND _idx = 1030", (a,))
            session.commit()

    _with_writer_between(monkeypatch, other_writer)
    columns = _columns(a, [1031, N + 6], np.random.default_rng(1))
    with pytest.raises(psycopg.Error) as caught:
        _property_chunks.swap_property_rows(conn, "public", "rock_cellpros", a, [1031], columns)
    assert caught.value.sqlstate == "TG300"
    conn.rollback()
    # the writer of a check-in: the swap loses the race again, the server's path merges
    _with_writer_between(monkeypatch, other_writer)
    assert _property_chunks.write_property_rows(conn, "public", "rock_cellpros", a, [1031], columns)
    conn.commit()
    monkeypatch.undo()
    rows = dict(
        conn.execute(
            "SELECT _idx, facies FROM public.rock_cellpros WHERE _geoid = %s AND _idx IN (1030, 1031, %s)", (a, N + 6)
        ).fetchall()
    )
    assert rows[1030] == 99 and set(rows) == {1030, 1031, N + 6}
    assert rows[1031] == int(columns[4][1][0])
    conn.commit()


def test_roles_constraints_and_a_tampered_stage(conn: Conn, db_dsn: str, monkeypatch: pytest.MonkeyPatch) -> None:
    """An editor swaps; a reader is not this path (None) and is refused the swap; a NULL at a present slot of a NOT
    NULL property is refused by name; a class with a CHECK constraint goes by the server (which checks it); a
    present id written without its delete is the face's 23505. Nothing changes by a refusal."""
    a, b = _objects(conn, True)
    with login_roles(db_dsn, {"ed": "tgsis_editor", "rd": "tgsis_reader"}) as made:
        ed = made.connect("ed")
        assert (
            _property_chunks.swap_property_rows(
                ed, "public", "rock_cellpros", a, [3], _columns(a, [3, 2000], np.random.default_rng(2))
            )
            == 2
        )
        ed.commit()
        rd = made.connect("rd")
        before = _digest(conn, b)
        conn.commit()
        assert (
            _property_chunks.swap_property_rows(
                rd, "public", "rock_cellpros", b, [4], _columns(b, [4], np.random.default_rng(2))
            )
            is None
        )
        rd.rollback()
        rd.execute("SELECT tgsis.object_chunks_stage(%s)", (TABLE,))
        with pytest.raises(psycopg.errors.InsufficientPrivilege):
            rd.execute("SELECT tgsis.swap_object_chunks(%s, %s, '{0}', '{NULL}')", (TABLE, b))
        rd.rollback()
        # a tampered stage: a NULL facies at a present slot once facies is NOT NULL (the row definition's)
        conn.execute("ALTER TABLE public.rock_cellpros_shape ALTER COLUMN facies SET NOT NULL")
        conn.commit()
        stage = ed.execute("SELECT tgsis.object_chunks_stage(%s)", (TABLE,)).fetchone()
        assert stage is not None
        ed.execute(
            f"INSERT INTO {stage[0]} (_geoid, chunk, revision, holes, porosity, facies, perm) "
            "VALUES (%s, 5, 0, NULL, '{1}', '{NULL}', '{1}')",
            (b,),
        )
        with pytest.raises(psycopg.Error) as caught:
            ed.execute("SELECT tgsis.swap_object_chunks(%s, %s, '{5}', '{NULL}')", (TABLE, b))
        assert caught.value.sqlstate == "TG100" and "NOT NULL" in str(caught.value)
        ed.rollback()
        conn.execute("ALTER TABLE public.rock_cellpros_shape ALTER COLUMN facies DROP NOT NULL")
        # a CHECK constraint: the client's path does not apply (None), the server's refuses the bad row
        conn.execute("ALTER TABLE public.rock_cellpros_shape ADD CONSTRAINT positive CHECK (porosity >= 0)")
        conn.commit()
        bad = _columns(b, [20], np.random.default_rng(2))
        bad[2] = ("porosity", np.array([-1.0]), "float8")
        assert _property_chunks.swap_property_rows(ed, "public", "rock_cellpros", b, [20], bad) is None
        with pytest.raises(psycopg.errors.CheckViolation):
            _property_chunks.write_property_rows(ed, "public", "rock_cellpros", b, [20], bad)
        ed.rollback()
        conn.execute("ALTER TABLE public.rock_cellpros_shape DROP CONSTRAINT positive")
        conn.commit()
        # a present id written without its delete: the face's INSERT of a present key
        state, message = sqlstate(ed, "SELECT 1")
        assert state is None
        with pytest.raises(psycopg.errors.UniqueViolation):
            _property_chunks.write_property_rows(
                ed, "public", "rock_cellpros", b, [], _columns(b, [30], np.random.default_rng(2))
            )
        ed.rollback()
    assert _digest(conn, b) == before


def test_repeatable_read_takes_the_server_path(conn: Conn) -> None:
    """Under REPEATABLE READ the client's path does not apply (None, no chunk read): the server's path writes."""
    a, _ = _objects(conn, False)
    conn.isolation_level = psycopg.IsolationLevel.REPEATABLE_READ
    try:
        columns = _columns(a, [40], np.random.default_rng(4))
        assert _property_chunks.swap_property_rows(conn, "public", "rock_cellpros", a, [40], columns) is None
        assert _property_chunks.write_property_rows(conn, "public", "rock_cellpros", a, [40], columns) == 1
        conn.commit()
    finally:
        conn.isolation_level = None
    got = conn.execute("SELECT facies FROM public.rock_cellpros WHERE _geoid = %s AND _idx = 40", (a,)).fetchone()
    assert got == (int(columns[4][1][0]),)
    conn.commit()
