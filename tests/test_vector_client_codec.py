"""Vector properties in the client's chunk codec (issue 40, plan L area C).

docs/storage.md, "Vector properties in chunks": a vector property of size k is one two-dimensional
array per chunk, slots x k from ``[1][1]``, whose row is k NULLs at a hole and at a NULL vector. The
client codec (:mod:`tgsis._chunks`, ``ChunkColumns.vectors``) now encodes and decodes it as the server
does, so a class with vector properties takes the client's bulk paths too: ``insert_feature`` (the
chunk upload), ``fetch_feature`` (the chunk read) and the check-in's chunk swap. These tests compare
the client's bytes with the server's: a re-encoding of the server's chunks as one binary COPY stream,
the chunk rows of a class uploaded by the client against its twin converted by the server, and an
edit swapped by the client against the same edit written by ``tgsis.write_property_rows``. The
property tables are chunks whatever model 1's storage is, so the file runs unmarked.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import psycopg
import pytest
from psycopg import sql

import tgsis
from tests.merge_data import curved_surface
from tests.storage_data import classes_as_rows
from tests.test_vector_property_chunks import PATTERNS, PROPS, _double, _vec
from tgsis import _chunks
from tgsis.db import _property_chunks
from tgsis.db import features as F
from tgsis.db._chunk_transfer import PackedChunks
from tgsis.db.classes import get_feature_class
from tgsis.errors import InvalidInputError
from tgsis.mesh import Surface

Conn = psycopg.Connection[Any]


@pytest.fixture(autouse=True)
def _classes_as_rows(db_dsn: str) -> None:
    """The classes these tests make start as rows: they switch them to chunks themselves, or compare with a rows
    twin (docs/storage.md, "Property chunks by default: the rule")."""
    classes_as_rows(db_dsn)


ODD4 = np.array([0x7FC0_0ABC, 1, 0x8000_0000], dtype=np.uint32).view(np.float32)


def _digest(conn: Conn, table: str, geoid: int) -> list[tuple[Any, ...]]:
    """Every chunk version of the object in ``table`` (a chunk table), each column in send form, but _geoid."""
    columns = conn.execute(
        "SELECT attname::text, format_type(atttypid, atttypmod) FROM pg_attribute "
        "WHERE attrelid = %s::regclass AND attnum > 0 AND NOT attisdropped AND attname <> '_geoid' ORDER BY attnum",
        (table,),
    ).fetchall()
    parts = [
        sql.SQL("array_send(c.{})" if kind.endswith("[]") else "c.{}::text").format(sql.Identifier(name))
        for name, kind in columns
    ]
    query = sql.SQL("SELECT {} FROM {} c WHERE c._geoid = %s ORDER BY c.chunk, c.revision").format(
        sql.SQL(", ").join(parts), sql.SQL(table)
    )
    rows = conn.execute(query, (geoid,)).fetchall()
    assert rows
    return [tuple(bytes(v) if isinstance(v, memoryview) else v for v in row) for row in rows]


def _copy_out(conn: Conn, query: sql.Composed) -> bytes:
    out = bytearray()
    with conn.cursor().copy(sql.SQL("COPY ({}) TO STDOUT (FORMAT binary)").format(query)) as copy:
        for block in copy:
            out += block
    return bytes(out)


# --------------------------------------------------------------------------- the codec against the server's bytes


def test_the_codec_writes_the_servers_vector_chunks_byte_for_byte(conn: Conn) -> None:
    """Chunks the server encoded (holes, NULL vectors, a whole chunk of them, odd bits, an id beyond int4) are
    decoded by the client and encoded again into the very COPY stream the server sends of them. Fails when the
    codec has no vector form, or writes any byte of a 2-D array otherwise (dimensions, NULL rows, element order)."""
    _vec(conn, "vec")  # holes, odd bits, NULL vectors, a chunk of NULL only, an id beyond int4
    table = "public.vec_cellpros"
    face = conn.cursor(binary=True).execute(f"SELECT _geoid, _idx, normal, rgb FROM {table} ORDER BY 1, 2").fetchall()
    conn.execute("SELECT tgsis.store_class_in_chunks('vec')")
    layout = _property_chunks.property_chunks(conn, get_feature_class(conn, "vec"), "vec_cellpros")
    assert layout is not None and layout.columns.vectors == (("normal", 3), ("pair", 2), ("rgb", 3))
    spec = layout.columns
    decoded: dict[tuple[int, int], tuple[Any, ...]] = {}
    for geoid in (1, 2, 3):
        where = sql.SQL("FROM public.vec_cellpros_chunk WHERE _geoid = {} ORDER BY chunk").format(sql.Literal(geoid))
        read = _copy_out(
            conn,
            sql.SQL("SELECT {} {}").format(sql.SQL(", ").join(map(sql.Identifier, spec.select_columns())), where),
        )
        chunks = _chunks.from_copy(read, spec)
        ids, columns = chunks.rows()
        nulls = chunks.null_rows()
        assert columns["normal"].shape == (len(ids), 3) and columns["pair"].shape == (len(ids), 2)
        server = _copy_out(
            conn, sql.SQL("SELECT {} {}").format(sql.SQL(", ").join(map(sql.Identifier, spec.copy_columns())), where)
        )
        assert _chunks.to_copy(_chunks.encode(ids, columns, spec, nulls), geoid, 0) == server, geoid
        for i, k in enumerate(ids.tolist()):
            decoded[(geoid, k)] = tuple(
                None if name in nulls and nulls[name][i] else columns[name][i].tolist() for name in ("normal", "rgb")
            )
    assert len(decoded) == len(face)
    for geoid, idx, normal, rgb in face:  # the face's values (binary: the NaN payloads as they are), bit for bit
        got = decoded[(geoid, idx)]
        for mine, theirs, kind in ((got[0], normal, np.float64), (got[1], rgb, np.float32)):
            if theirs is None:
                assert mine is None, (geoid, idx)
            else:
                assert np.array_equal(
                    np.array(mine, dtype=kind).view(np.uint8), np.array(theirs, dtype=kind).view(np.uint8)
                )
    # a vector given as a scalar column is refused by name
    with pytest.raises(InvalidInputError, match="normal"):
        _chunks.encode(
            np.arange(2),
            {**{n: np.zeros(spec.shape(n, 2), spec.dtype(n)) for n in spec.names}, "normal": np.zeros(2)},
            spec,
        )


# --------------------------------------------------------------------------- the Python paths


def _mesh(n_rgb_odd: bool = True) -> Surface:
    surface = curved_surface(40)
    n = surface.n_vertices
    normal = np.stack([np.sin(np.arange(n)), np.cos(np.arange(n)), np.arange(n) / 7.0], axis=1)
    normal[:4, 0] = [_double(p) for p in PATTERNS]
    rgb = np.stack([np.arange(n) % 256, np.zeros(n), np.ones(n)], axis=1).astype(np.float32)
    rgb[0] = ODD4
    props = {
        "normal": normal,
        "t": (np.arange(n) / 3.0).astype(np.float32),
        "pair": np.stack([np.arange(n), -np.arange(n)], axis=1).astype(np.int32),
        "rgb": rgb,
    }
    return Surface(surface.vertices, surface.cells, vertex_properties=props)


def _same(a: Any, b: Any) -> bool:
    return all(
        np.array_equal(
            np.ascontiguousarray(a.vertex_properties[k]).view(np.uint8),
            np.ascontiguousarray(b.vertex_properties[k]).view(np.uint8),
        )
        and a.vertex_properties[k].shape == b.vertex_properties[k].shape
        for k, _, _ in PROPS
    )


def test_insert_and_fetch_take_the_client_path_and_write_what_the_server_writes(
    conn: Conn, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A class in chunks before its first feature: insert_feature uploads client-encoded chunks (one
    tgsis.write_property_chunks call, no face trigger, no tgsis.write_property_rows), whose rows are those the
    server's conversion writes for the same feature of a twin class in rows; fetch_feature reads them from the
    chunks (the client decodes), bit for bit. Fails when a vector class falls back to the server's paths."""
    mesh = _mesh()
    for name in ("layer", "twin"):
        tgsis.create_feature_class(conn, name, "SURFACE", cell_properties=[(n, t, k) for n, t, k in PROPS])
    conn.execute("SELECT tgsis.store_class_in_chunks('layer')")
    conn.commit()
    conn.execute("SET track_functions = 'all'")
    geoid = F.insert_feature(conn, "layer", mesh)
    calls = dict(
        conn.execute(
            "SELECT funcname::text, sum(calls) FROM pg_stat_xact_user_functions WHERE funcname IN "
            "('write_property_chunks', 'write_property_rows', 'chunk_face_write') GROUP BY 1"
        ).fetchall()
    )
    assert calls == {"write_property_chunks": 1}, calls
    twin = F.insert_feature(conn, "twin", mesh)
    conn.commit()
    conn.execute("SELECT tgsis.store_class_in_chunks('twin')")
    conn.commit()
    assert _digest(conn, "public.layer_cellpros_chunk", geoid) == _digest(conn, "public.twin_cellpros_chunk", twin)
    read: list[str] = []
    decode = PackedChunks.decode

    def spy(self: PackedChunks, *args: Any) -> Any:
        read.append(f"{self.layout.schema}.{self.layout.table}")
        return decode(self, *args)

    monkeypatch.setattr(PackedChunks, "decode", spy)
    assert _same(F.fetch_feature(conn, "layer", geoid).mesh, mesh)
    assert "public.layer_cellpros" in read  # (and the vertices and triangles when model 1 is in chunks)


def _columns(geoid: int, ids: list[int], rng: np.random.Generator, *, partial: bool = False) -> list[Any]:
    """The rows written: odd doubles and reals among them; ``partial``: pair not given (a NULL vector)."""
    n = len(ids)
    normal = rng.random((n, 3))
    rgb = rng.random((n, 3)).astype(np.float32)
    if n >= 4:
        normal[:4, 1] = [_double(p) for p in PATTERNS]
        rgb[:3, 2] = ODD4
    columns = [
        ("_geoid", np.full(n, geoid, dtype=np.int64), "int8"),
        ("_idx", np.asarray(ids, dtype=np.int64), "int8"),
        ("normal", normal, "float8[3]"),
        ("t", rng.random(n).astype(np.float32), "float4"),
        ("rgb", rgb, "float4[3]"),
    ]
    if not partial:
        columns.append(("pair", rng.integers(-5, 5, (n, 2)).astype(np.int32), "int4[2]"))
    return columns


@pytest.mark.parametrize("versioned", [False, True], ids=["plain", "versioned"])
def test_the_client_swap_writes_the_vector_chunks_the_server_writes(
    conn: Conn, versioned: bool, monkeypatch: pytest.MonkeyPatch
) -> None:
    """An edit of two identical objects: one by tgsis.write_property_rows (the client's swap off), one by the
    client's swap (tgsis.swap_object_chunks); every chunk version compared in send form. Scattered changes,
    deletes (holes), new ids past the last chunk, rows without a vector (NULL vectors), odd floats. Fails when
    the swap declines a vector class (the vectors' own CHECKs) or writes any byte otherwise."""
    tgsis.create_feature_class(conn, "rock", "SURFACE", cell_properties=[(n, t, k) for n, t, k in PROPS])
    if versioned:
        tgsis.enable_feature_versioning(conn)
    mesh = _mesh()
    a, b = (F.insert_feature(conn, "rock", mesh) for _ in range(2))
    conn.commit()
    conn.execute("SELECT tgsis.store_class_in_chunks('rock')")
    conn.execute("ALTER TABLE public.rock_cellpros_shape ALTER COLUMN pair DROP NOT NULL")
    conn.commit()
    n = mesh.n_vertices
    rng = np.random.default_rng(3)
    changed = sorted({0, 1023, 1024, n - 1, *rng.choice(n, 60, replace=False).tolist()} - {5, 1500})
    edits = [
        ([5, 1500, *changed], changed + [n, n + 1, n + 1030], {}),
        ([7, 1031], [7, 1031, n + 2], {"partial": True}),
        ([9], [], {}),
    ]
    for gone, ids, kw in edits:
        with monkeypatch.context() as patch:
            patch.setattr(_property_chunks, "_swapped", lambda *args: None)
            server = _property_chunks.write_property_rows(
                conn, "public", "rock_cellpros", a, gone, _columns(a, ids, np.random.default_rng(7), **kw)
            )
        client = _property_chunks.swap_property_rows(
            conn, "public", "rock_cellpros", b, gone, _columns(b, ids, np.random.default_rng(7), **kw)
        )
        conn.commit()
        assert client is not None and client == server and server > 0, (client, server)
        assert _digest(conn, "public.rock_cellpros_chunk", b) == _digest(conn, "public.rock_cellpros_chunk", a)
    nulls = conn.execute("SELECT count(*) FROM public.rock_cellpros WHERE _geoid = %s AND pair IS NULL", (b,))
    assert nulls.fetchone() == (3,)
    # a user's own CHECK on a vector still sends the edit to the server's path, which evaluates it
    conn.execute("ALTER TABLE public.rock_cellpros_shape ADD CONSTRAINT rock_normal_small CHECK (normal[1] < 2)")
    conn.commit()
    assert _property_chunks.swap_property_rows(conn, "public", "rock_cellpros", b, [0], _columns(b, [0], rng)) is None
    conn.rollback()
