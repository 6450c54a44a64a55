"""The chunk codec of issue 40 (tgsis._chunks): rows <-> chunk arrays <-> PostgreSQL binary COPY, bit-exact.

The pure tests check the contract's arrays (chunk numbers, holes, vbase, relative corners, the _wide
fallback) and round trips; the server tests COPY the encoded chunks into tables made with the contract's
DDL, read them back by binary COPY through the parser and by SQL ``unnest ... WITH ORDINALITY``, and
compare with the input.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import numpy.typing as npt
import psycopg
import pytest
from psycopg import sql

from tgsis._chunks import CHUNK_SIZE, ChunkColumns, ChunkSet, encode, from_copy, to_copy
from tgsis.errors import InvalidInputError

XYZ = ChunkColumns(("x", "y", "z"))
TRGL = ChunkColumns(("vrtxid1", "vrtxid2", "vrtxid3"), refs=("vrtxid1", "vrtxid2", "vrtxid3"))

#: doubles whose bits must survive: -0.0, NaNs with payloads and sign, subnormals, extremes
ODD_BITS = np.array(
    [
        0x8000000000000000,  # -0.0
        0x7FF8000000000001,  # quiet NaN, payload 1
        0x7FF0000000000001,  # signalling NaN bits
        0xFFF8DEADBEEF0000,  # negative NaN with a payload
        0x0000000000000001,  # smallest subnormal
        0x800FFFFFFFFFFFFF,  # largest negative subnormal
        0x7FEFFFFFFFFFFFFF,  # largest double
        0x7FF0000000000000,  # +inf
    ],
    dtype=np.uint64,
).view(np.float64)


def bits(a: npt.NDArray[Any]) -> npt.NDArray[np.int64]:
    return np.ascontiguousarray(a, dtype=np.float64).view(np.int64)


def random_rows(
    rng: np.random.Generator, n: int, span: int, offset: int = 0
) -> tuple[npt.NDArray[np.int64], dict[str, Any]]:
    ids = offset + rng.choice(span, size=n, replace=False).astype(np.int64)
    cols = {c: rng.normal(size=n) for c in "xyz"}
    return ids, cols


def assert_same_rows(ids: Any, cols: dict[str, Any], got: tuple[Any, dict[str, Any]]) -> None:
    order = np.argsort(ids)
    got_ids, got_cols = got
    assert np.array_equal(got_ids, np.asarray(ids)[order])
    for name, values in cols.items():
        expected = np.asarray(values)[order]
        if expected.dtype.kind == "f":
            assert np.array_equal(bits(got_cols[name]), bits(expected)), name
        else:
            assert np.array_equal(got_cols[name], expected), name


def via_copy(chunks: ChunkSet) -> ChunkSet:
    """The chunks through their COPY-in stream, cut to the select list (what COPY TO sends) and parsed."""
    spec = chunks.columns
    stream = to_copy(chunks, geoid=7, revision=3)
    return from_copy(_select_stream(stream, spec), spec)


def _select_stream(stream: bytes, spec: ChunkColumns) -> bytes:
    """A COPY-in stream with its geoid, revision and vtop fields removed (what a COPY of the select list sends)."""
    out = bytearray(stream[:19])
    pos = 19
    n_fields = len(spec.copy_columns())
    kept = [i for i, name in enumerate(spec.copy_columns()) if name in spec.select_columns()]
    while True:
        count = int.from_bytes(stream[pos : pos + 2], "big", signed=True)
        if count == -1:
            out += stream[pos : pos + 2]
            return bytes(out)
        assert count == n_fields
        out += len(kept).to_bytes(2, "big", signed=True)
        pos += 2
        for i in range(n_fields):
            length = int.from_bytes(stream[pos : pos + 4], "big", signed=True)
            end = pos + 4 + max(length, 0)
            if i in kept:  # (not geoid, revision, vtop)
                out += stream[pos:end]
            pos = end


# ------------------------------------------------------------------------------------------------ pure


def test_contract_arrays_of_a_small_object() -> None:
    ids = np.array([5, 0, 1, 1024 + 3, 3 * 1024 + 1023], dtype=np.int64)
    cols = {c: np.arange(5, dtype=np.float64) + i for i, c in enumerate("xyz")}
    chunks = encode(ids, cols, XYZ)
    assert chunks.chunk.tolist() == [0, 1, 3]
    assert chunks.lengths.tolist() == [6, 4, 1024]
    assert chunks.holes(0).tolist() == [3, 4, 5]  # ids 2, 3, 4 absent, below the last present slot 6
    assert chunks.holes(1).tolist() == [1, 2, 3]
    assert chunks.holes(2).tolist() == list(range(1, 1024))  # only slot 1024 present
    assert_same_rows(ids, cols, chunks.rows())


def test_round_trip_random_ids_with_holes_and_large_ids() -> None:
    rng = np.random.default_rng(40)
    for span, offset in ((5000, 0), (300_000, 0), (10_000, 2**31 - 3000), (4096, 2**40 + 17)):
        ids, cols = random_rows(rng, 2000 if span > 4096 else 1500, span, offset)
        chunks = encode(ids, cols, XYZ)
        assert_same_rows(ids, cols, chunks.rows())
        assert_same_rows(ids, cols, via_copy(chunks).rows())
        assert bool((chunks.chunk == np.unique(ids >> 10)).all())


def test_doubles_keep_their_bits() -> None:
    values = np.concatenate([ODD_BITS, -ODD_BITS, [0.1, 1e-310, -5e-324]])
    ids = np.arange(len(values), dtype=np.int64) * 3  # holes between them
    cols = {"x": values, "y": values[::-1].copy(), "z": np.roll(values, 3)}
    chunks = encode(ids, cols, XYZ)
    assert_same_rows(ids, cols, chunks.rows())
    assert_same_rows(ids, cols, via_copy(chunks).rows())


def test_an_object_without_holes_round_trips_whole_and_beside_chunks_with_holes() -> None:
    """Every chunk full (the usual upload): each column is taken whole; one chunk with holes among them: by mask."""
    rng = np.random.default_rng(7)
    n = 3 * 1024 + 100  # three full chunks and a partial last one, no hole
    ids = np.arange(n, dtype=np.int64)
    values = np.resize(np.concatenate([ODD_BITS, -ODD_BITS, rng.normal(size=50)]), n)
    cols = {"x": values, "y": np.roll(values, 5), "z": values[::-1].copy()}
    cells = np.stack([ids % 997, (ids * 7) % 1009, (ids * 13) % 1013], axis=1)
    corners = {f"vrtxid{i + 1}": cells[:, i] for i in range(3)}
    for keep in (np.ones(n, dtype=bool), ids != 1024 + 5):  # dense; chunk 1 with a hole among dense chunks
        chunks = via_copy(encode(ids[keep], {c: v[keep] for c, v in cols.items()}, XYZ))
        assert_same_rows(ids[keep], {c: v[keep] for c, v in cols.items()}, chunks.rows())
        triangles = via_copy(encode(ids[keep], {c: v[keep] for c, v in corners.items()}, TRGL))
        assert_same_rows(ids[keep], {c: v[keep] for c, v in corners.items()}, triangles.rows())


def test_relative_corners_and_vbase() -> None:
    ids = np.arange(3, dtype=np.int64) + 1024
    cells = np.array([[10, 11, 12], [9, 13, 11], [20, 3, 30]], dtype=np.int64)
    cols = {f"vrtxid{i + 1}": cells[:, i] for i in range(3)}
    chunks = encode(ids, cols, TRGL)
    assert chunks.vbase.tolist() == [3] and chunks.wide.tolist() == [False]
    assert chunks.relative["vrtxid1"].tolist() == [7, 6, 17]  # v1 - vbase
    assert chunks.relative["vrtxid2"].tolist() == [1, 4, -17]  # v2 - v1
    assert chunks.relative["vrtxid3"].tolist() == [2, 2, 10]  # v3 - v1
    assert_same_rows(ids, cols, chunks.rows())


def test_a_chunk_too_wide_for_int4_keeps_absolute_ids() -> None:
    far = 2**31 + 5
    ids = np.array([0, 1, 2, 1024, 1025, 2048], dtype=np.int64)
    cells = np.array(
        [
            [0, 1, 2],
            [1, 2, far],
            [far, 0, 1],
            [2**33, 2**33 + 1, 2**33 + 2],
            [2**33 + 5, 2**33 + 1, 7],
            [5, 6, 2**31 + 4],
        ]
    )
    cols = {f"vrtxid{i + 1}": cells[:, i] for i in range(3)}
    chunks = encode(ids, cols, TRGL)
    # chunk 0: v2 - v1 = far - 1 does not fit; chunk 1: v3 - v1 = 7 - (2**33 + 5) does not; chunk 2: 2**31 - 1 fits
    assert chunks.wide.tolist() == [True, True, False]
    assert chunks.vbase.tolist() == [-1, -1, 5]
    assert_same_rows(ids, cols, chunks.rows())
    assert_same_rows(ids, cols, via_copy(chunks).rows())


def test_empty_and_single_rows() -> None:
    empty = encode(np.empty(0, dtype=np.int64), {c: np.empty(0) for c in "xyz"}, XYZ)
    assert len(empty.chunk) == 0
    assert to_copy(empty, 1).endswith(b"\xff\xff") and len(to_copy(empty, 1)) == 21
    assert_same_rows([], {c: np.empty(0) for c in "xyz"}, via_copy(empty).rows())
    for single in (0, 1023, 2**45 + 1023):
        cols = {"x": np.array([-0.0]), "y": np.array([1.5]), "z": ODD_BITS[1:2]}
        chunks = encode([single], cols, XYZ)
        assert chunks.lengths.tolist() == [(single & 1023) + 1]
        assert_same_rows([single], cols, via_copy(chunks).rows())


def test_rows_of_a_copy_in_any_chunk_order() -> None:
    rng = np.random.default_rng(8)
    ids = rng.choice(6000, size=3000, replace=False).astype(np.int64)
    corners = rng.choice(2**33, size=(3000, 3), replace=False)
    low, high = ids < 3072, ids >= 3072  # at a chunk boundary
    corners[low] = rng.choice(5000, size=(int(low.sum()), 3), replace=False)  # relative; the high chunks wide
    cols = {f"vrtxid{i + 1}": corners[:, i] for i in range(3)}
    streams = [
        _select_stream(to_copy(encode(ids[part], {k: v[part] for k, v in cols.items()}, TRGL), 1), TRGL)
        for part in (high, low)  # the higher chunks first
    ]
    combined = streams[0][:-2] + streams[1][19:]
    chunks = from_copy(combined, TRGL)
    assert chunks.chunk.tolist() == sorted(chunks.chunk.tolist())
    assert chunks.wide.any() and not chunks.wide.all()
    assert_same_rows(ids, cols, chunks.rows())
    with pytest.raises(InvalidInputError, match="holds a chunk twice"):
        from_copy(streams[0][:-2] + streams[0][19:], TRGL)


def test_a_stream_that_breaks_the_contract_is_refused() -> None:
    chunks = encode([0, 2], {c: np.array([1.0, 2.0]) for c in "xyz"}, XYZ)  # chunk 0: slot 2 a hole
    stream = _select_stream(to_copy(chunks, 1), XYZ)
    hole = b"\x00\x00\x00\x02\x00\x02"  # the holes array's element: length 2, slot 2
    assert stream.count(hole) == 1
    with pytest.raises(InvalidInputError, match="NULL elements are not its chunk's holes"):
        from_copy(stream.replace(hole, b"\x00\x00\x00\x02\x00\x01"), XYZ)
    for cut in (3, 10, 40):
        with pytest.raises(InvalidInputError):
            from_copy(stream[:-cut], XYZ)
    with pytest.raises(InvalidInputError, match="fields"):
        from_copy(stream, TRGL)


def test_bad_input_is_refused_by_name() -> None:
    cols = {c: np.zeros(2) for c in "xyz"}
    with pytest.raises(InvalidInputError, match=">= 0"):
        encode([-1, 4], cols, XYZ)
    with pytest.raises(InvalidInputError, match="repeat"):
        encode([4, 4], cols, XYZ)
    with pytest.raises(InvalidInputError, match="not the chunk columns"):
        encode([1, 2], {"x": np.zeros(2)}, XYZ)
    with pytest.raises(InvalidInputError, match="float64"):
        encode([1, 2], {**cols, "x": np.zeros(2, dtype=np.float32)}, XYZ)
    with pytest.raises(InvalidInputError, match=">= 0"):
        encode([1, 2], {"vrtxid1": [0, -3], "vrtxid2": [1, 1], "vrtxid3": [2, 2]}, TRGL)
    with pytest.raises(InvalidInputError, match="PGCOPY"):
        from_copy(b"not a copy stream at all", XYZ)


#: a class's property table: one column of each property type (docs/storage.md, "The bulk paths of property chunks")
PROPS = ChunkColumns(
    ("a", "b", "c", "d", "e", "f"),
    properties=(("a", "int2"), ("b", "int4"), ("c", "int8"), ("d", "float4"), ("e", "float8"), ("f", "bool")),
    key="_geoid",
)


def _property_rows(n: int) -> dict[str, Any]:
    rng = np.random.default_rng(5)
    cols: dict[str, Any] = {
        "a": rng.integers(-32768, 32768, n).astype(np.int16),
        "b": rng.integers(-(2**31), 2**31, n, dtype=np.int64).astype(np.int32),
        "c": rng.integers(-(2**63), 2**63 - 1, n, dtype=np.int64),
        "d": np.array([0x80000000, 0x7FC00ABC, 1] * n, dtype=np.uint32)[:n].view(np.float32),
        "e": np.array([0x8000000000000000, 0x7FF8000000000ABC, 1] * n, dtype=np.uint64)[:n].view(np.float64),
        "f": rng.random(n) < 0.5,
    }
    return cols


def test_property_kinds_and_nulls_round_trip_apart_from_holes() -> None:
    ids = np.array([i for i in range(2500) if i % 97 != 5] + [2**40 + 3], dtype=np.int64)
    cols = _property_rows(len(ids))
    nulls = {"b": np.arange(len(ids)) % 7 == 0, "f": np.zeros(len(ids), dtype=bool)}
    order = np.random.default_rng(2).permutation(len(ids))  # ids in any order
    chunks = encode(ids[order], {k: v[order] for k, v in cols.items()}, PROPS, {k: v[order] for k, v in nulls.items()})
    assert set(chunks.nulls) == {"b"}  # (no NULL in f: no mask)
    back = via_copy(chunks)
    got_ids, got = back.rows()
    assert np.array_equal(got_ids, ids)
    for name, expected in cols.items():
        assert got[name].dtype == expected.dtype, name
        keep = ~nulls.get(name, np.zeros(len(ids), dtype=bool))
        if expected.dtype.kind == "f":
            width = np.int32 if expected.dtype == np.float32 else np.int64
            assert np.array_equal(got[name][keep].view(width), expected[keep].view(width)), name
        else:
            assert np.array_equal(got[name][keep], expected[keep]), name
    assert set(back.null_rows()) == {"b"} and np.array_equal(back.null_rows()["b"], nulls["b"])
    # holes stay holes, not NULL values
    assert np.array_equal(back.present, chunks.present) and not back.present.all()


def test_property_values_of_another_type_are_refused_by_name() -> None:
    ids = np.arange(3)
    cols = _property_rows(3)
    for name, wrong in (("d", cols["d"].astype(np.float64)), ("e", cols["e"].astype(np.float32)), ("f", np.ones(3))):
        with pytest.raises(InvalidInputError, match=repr(name)):
            encode(ids, {**cols, name: wrong}, PROPS)
    with pytest.raises(InvalidInputError, match="range"):
        encode(ids, {**cols, "a": np.array([0, 1, 40000])}, PROPS)
    with pytest.raises(InvalidInputError, match="only property columns"):
        encode(np.arange(2), {"x": np.zeros(2), "y": np.zeros(2), "z": np.zeros(2)}, XYZ, {"x": np.ones(2, bool)})
    # a value where the chunk has a hole: refused when parsed
    chunks = encode(np.array([0, 2]), {k: v[:2] for k, v in cols.items()}, PROPS)
    stream = _select_stream(to_copy(chunks, 1), PROPS)
    null_element = b"\xff\xff\xff\xff"
    one_b = (4).to_bytes(4, "big") + int(cols["b"][0]).to_bytes(4, "big", signed=True)
    hole_b = stream.index(one_b) + 8  # b's second element: the hole (NULL), then its third
    assert stream[hole_b : hole_b + 4] == null_element
    field = stream.index(one_b) - 24  # b's field length word (then the array's 20-byte header)
    length = int.from_bytes(stream[field : field + 4], "big") + 4
    forged = (
        stream[:field] + length.to_bytes(4, "big") + stream[field + 4 : hole_b] + (4).to_bytes(4, "big") + bytes(4)
    ) + stream[hole_b + 4 :]
    with pytest.raises(InvalidInputError, match="a value at a hole"):
        from_copy(forged, PROPS)


def test_chunk_of_every_id_is_id_shifted() -> None:
    rng = np.random.default_rng(3)
    ids = rng.choice(2**20, size=50_000, replace=False).astype(np.int64)
    chunks = encode(ids, {c: rng.normal(size=len(ids)) for c in "xyz"}, XYZ)
    assert np.array_equal(chunks.ids()[chunks.present], np.sort(ids))
    assert int(chunks.lengths.max()) <= CHUNK_SIZE


# ------------------------------------------------------------------------------------------------ server

# The contract's DDL for two chunk tables (docs/storage.md; /work/helpers/CHUNKS.md), made here in a schema of
# the test's own: the SQL creator (tgsis.create_chunk_table) is being written in parallel, and these tables
# move to it when it is merged.


def compression(conn: psycopg.Connection[Any]) -> str:
    row = conn.execute("SELECT 'lz4' = ANY (enumvals) FROM pg_settings WHERE name = 'default_toast_compression'")
    result = row.fetchone()
    return "lz4" if result and result[0] else "pglz"


def create_tables(conn: psycopg.Connection[Any]) -> None:
    floats = compression(conn)
    conn.execute("CREATE SCHEMA chunk_codec_test")
    conn.execute(
        sql.SQL(
            """CREATE TABLE chunk_codec_test.vrtx_chunk (
                geoid bigint NOT NULL, chunk bigint NOT NULL, revision integer NOT NULL,
                lastrevs integer[] NOT NULL DEFAULT '{{}}',
                revclosed boolean GENERATED ALWAYS AS (cardinality(lastrevs) > 0) STORED,
                holes smallint[] COMPRESSION pglz,
                x double precision[] COMPRESSION {f}, y double precision[] COMPRESSION {f},
                z double precision[] COMPRESSION {f},
                PRIMARY KEY (geoid, chunk, revision))"""
        ).format(f=sql.SQL(floats))
    )
    conn.execute(
        """CREATE TABLE chunk_codec_test.trgl_chunk (
            geoid bigint NOT NULL, chunk bigint NOT NULL, revision integer NOT NULL,
            lastrevs integer[] NOT NULL DEFAULT '{}',
            revclosed boolean GENERATED ALWAYS AS (cardinality(lastrevs) > 0) STORED,
            holes smallint[] COMPRESSION pglz, vbase bigint, vtop bigint,
            vrtxid1 integer[] COMPRESSION pglz, vrtxid2 integer[] COMPRESSION pglz, vrtxid3 integer[] COMPRESSION pglz,
            vrtxid1_wide bigint[] COMPRESSION pglz, vrtxid2_wide bigint[] COMPRESSION pglz,
            vrtxid3_wide bigint[] COMPRESSION pglz,
            PRIMARY KEY (geoid, chunk, revision))"""
    )


def copy_in(conn: psycopg.Connection[Any], table: str, chunks: ChunkSet, geoid: int, revision: int) -> None:
    query = sql.SQL("COPY chunk_codec_test.{} ({}) FROM STDIN (FORMAT binary)").format(
        sql.Identifier(table), sql.SQL(", ").join(map(sql.Identifier, chunks.columns.copy_columns()))
    )
    with conn.cursor().copy(query) as copy:
        copy.write(to_copy(chunks, geoid, revision))


def copy_out(conn: psycopg.Connection[Any], table: str, spec: ChunkColumns, geoid: int) -> ChunkSet:
    query = sql.SQL("COPY (SELECT {} FROM chunk_codec_test.{} WHERE geoid = {}) TO STDOUT (FORMAT binary)").format(
        sql.SQL(", ").join(map(sql.Identifier, spec.select_columns())), sql.Identifier(table), sql.Literal(geoid)
    )
    out = bytearray()
    with conn.cursor().copy(query) as copy:
        for block in copy:
            out += block
    return from_copy(bytes(out), spec)


def test_server_round_trip(tx: psycopg.Connection[Any]) -> None:
    rng = np.random.default_rng(11)
    create_tables(tx)
    # session settings that change text output of doubles, and the default compression: the binary path ignores them
    tx.execute("SET LOCAL extra_float_digits = -15")
    tx.execute("SET LOCAL default_toast_compression = 'pglz'")
    # vertices: holes, ids >= 2**31, one id alone in slot 1023 of its chunk, odd doubles
    ids = np.concatenate(
        [rng.choice(5000, size=3000, replace=False), 2**31 + rng.choice(3000, size=500, replace=False), [2**36 + 1023]]
    ).astype(np.int64)
    cols = {c: rng.normal(size=len(ids)) * 1e5 for c in "xyz"}
    cols["x"][: len(ODD_BITS) * 2] = np.concatenate([ODD_BITS, -ODD_BITS])
    cols["z"][-1] = ODD_BITS[3]
    vertices = encode(ids, cols, XYZ)
    # triangles: relative corners, and one chunk that needs _wide
    tids = np.concatenate([np.arange(2000), 4096 + rng.choice(1024, size=700, replace=False)]).astype(np.int64)
    corners = np.sort(rng.choice(5000, size=(len(tids), 3)), axis=1)
    corners[:, 1] += 1
    corners[:, 2] += 2
    corners[-5] = [3, 2**31 + 40, 2**36 + 1023]
    rng.shuffle(corners, axis=1)
    tcols = {f"vrtxid{i + 1}": corners[:, i] for i in range(3)}
    triangles = encode(tids, tcols, TRGL)
    assert triangles.wide.any() and not triangles.wide.all()
    for geoid in (1, 2):
        copy_in(tx, "vrtx_chunk", vertices, geoid, revision=0)
        copy_in(tx, "trgl_chunk", triangles, geoid, revision=4)

    # (a) binary COPY out, parsed: bit-exact
    assert_same_rows(ids, cols, copy_out(tx, "vrtx_chunk", XYZ, 2).rows())
    assert_same_rows(tids, tcols, copy_out(tx, "trgl_chunk", TRGL, 2).rows())

    # (b) SQL: unnest WITH ORDINALITY to rows; NULL elements are the holes
    rows = tx.execute(
        """SELECT (c.chunk << 10) + u.o - 1, float8send(u.x), float8send(u.y), float8send(u.z)
             FROM chunk_codec_test.vrtx_chunk c CROSS JOIN LATERAL unnest(c.x, c.y, c.z) WITH ORDINALITY u(x, y, z, o)
            WHERE c.geoid = 1 AND u.x IS NOT NULL ORDER BY 1"""
    ).fetchall()
    got_ids = np.array([r[0] for r in rows], dtype=np.int64)
    got = {
        c: np.frombuffer(b"".join(r[i + 1] for r in rows), dtype=">f8").astype(np.float64) for i, c in enumerate("xyz")
    }
    assert_same_rows(ids, cols, (got_ids, got))
    rows = tx.execute(
        """SELECT (c.chunk << 10) + u.o - 1,
                  coalesce(c.vbase + u.r1, u.w1), coalesce(c.vbase + u.r1 + u.r2, u.w2), coalesce(c.vbase + u.r1 + u.r3, u.w3)
             FROM chunk_codec_test.trgl_chunk c
            CROSS JOIN LATERAL unnest(c.vrtxid1, c.vrtxid2, c.vrtxid3, c.vrtxid1_wide, c.vrtxid2_wide, c.vrtxid3_wide)
                  WITH ORDINALITY u(r1, r2, r3, w1, w2, w3, o)
            WHERE c.geoid = 1 AND coalesce(u.r1::bigint, u.w1) IS NOT NULL ORDER BY 1"""
    ).fetchall()
    table = np.array(rows, dtype=np.int64)
    assert_same_rows(tids, tcols, (table[:, 0], {f"vrtxid{i}": table[:, i] for i in (1, 2, 3)}))

    # the holes column says what the NULL elements say, and the stored revision is the one written
    mismatched = tx.execute(
        """SELECT count(*) FROM chunk_codec_test.vrtx_chunk c
            WHERE coalesce(c.holes, '{}') IS DISTINCT FROM ARRAY(
                  SELECT o::smallint FROM unnest(c.x) WITH ORDINALITY u(x, o) WHERE x IS NULL ORDER BY o)"""
    ).fetchone()
    assert mismatched == (0,)
    assert tx.execute("SELECT DISTINCT revision, lastrevs, revclosed FROM chunk_codec_test.trgl_chunk").fetchall() == [
        (4, [], False)
    ]
    # arrays end at the last present slot: no trailing NULL
    trailing = tx.execute(
        "SELECT count(*) FROM chunk_codec_test.vrtx_chunk WHERE x[array_upper(x, 1)] IS NULL OR array_lower(x, 1) <> 1"
    ).fetchone()
    assert trailing == (0,)


def test_server_refuses_what_breaks_the_copy_format(tx: psycopg.Connection[Any]) -> None:
    """A stream whose array field lengths lie is refused by the server (the COPY form is checked, not trusted)."""
    create_tables(tx)
    chunks = encode([0, 1], {c: np.array([1.0, 2.0]) for c in "xyz"}, XYZ)
    stream = bytearray(to_copy(chunks, 1))
    stream[-14:-10] = (999).to_bytes(4, "big")  # the last element's length word: past the end of its field
    with pytest.raises(psycopg.Error):
        query = sql.SQL("COPY chunk_codec_test.vrtx_chunk ({}) FROM STDIN (FORMAT binary)").format(
            sql.SQL(", ").join(map(sql.Identifier, XYZ.copy_columns()))
        )
        with tx.cursor().copy(query) as copy:
            copy.write(bytes(stream))


def test_an_instant_key_is_written_bit_for_bit_after_the_object_key() -> None:
    """Model 2's chunk tables are keyed (geoid, times, chunk): the COPY carries the instant's float8 bits."""
    spec = ChunkColumns(("x", "y", "z"), instant=("times",))
    assert spec.copy_columns() == ["geoid", "times", "chunk", "revision", "holes", "x", "y", "z"]
    assert spec.select_columns() == XYZ.select_columns() == ["chunk", "holes", "x", "y", "z"]
    chunks = encode(np.arange(3), {c: np.arange(3.0) for c in "xyz"}, spec)
    stream = to_copy(chunks, 7, 5, (-0.0,))
    # header (19 bytes), field count 8, geoid (length 8, 7), then the instant (length 8, -0.0's bits)
    assert stream[19:21] == (8).to_bytes(2, "big")
    assert stream[21:33] == (8).to_bytes(4, "big") + (7).to_bytes(8, "big")
    assert stream[33:45] == (8).to_bytes(4, "big") + np.array([-0.0], dtype=">f8").tobytes()
    assert stream[45:57] == (8).to_bytes(4, "big") + (0).to_bytes(8, "big")  # chunk 0
    with pytest.raises(InvalidInputError, match="one value each"):
        to_copy(chunks, 7, 5)
    with pytest.raises(InvalidInputError):
        ChunkColumns(("x", "times"), instant=("times",))


def test_an_integer_key_is_written_in_its_width_and_refused_out_of_range() -> None:
    """A G-map's involutions are keyed (geoid, level smallint, chunk): the COPY carries a 2-byte level."""
    spec = ChunkColumns(("dartid2",), refs=("dartid2",), instant=("level",), instant_kinds=("int2",))
    chunks = encode(np.arange(3), {"dartid2": np.array([1, 0, 2])}, spec)
    stream = to_copy(chunks, 7, 5, (3,))
    assert stream[21:33] == (8).to_bytes(4, "big") + (7).to_bytes(8, "big")
    assert stream[33:39] == (2).to_bytes(4, "big") + (3).to_bytes(2, "big")  # level 3 as smallint
    assert stream[39:51] == (8).to_bytes(4, "big") + (0).to_bytes(8, "big")  # chunk 0
    for value in (2**15, -(2**15) - 1):
        with pytest.raises(InvalidInputError, match="out of the range of int2"):
            to_copy(chunks, 7, 5, (value,))
    for kinds in [("int2", "int2"), ("text",)]:  # one kind per key, of the kinds a key may have
        with pytest.raises(InvalidInputError, match="kinds"):
            ChunkColumns(("dartid2",), refs=("dartid2",), instant=("level",), instant_kinds=kinds)


POINTS = ChunkColumns(("coordinate",), points=("coordinate",))


@pytest.mark.parametrize("m", [1, 3])
def test_points_round_trip_as_two_dimensional_arrays_m_per_object(m: int) -> None:
    """A G-map's points (role ``point``): slots x m from [1][1], a hole m NULLs, m read back from the array."""
    ids = np.array([0, 2, 3, 1023, 1030, 5000], dtype=np.int64)
    points = np.resize(ODD_BITS, len(ids) * m).reshape(len(ids), m)
    chunks = encode(ids, {"coordinate": points}, POINTS)
    stream = to_copy(chunks, 1)
    # the first chunk's array: 2 dimensions, 4 slots x m, NULL bitmap (a hole at slot 2)
    first = _fields(stream)[0][-1]  # the first chunk's coordinate field (length word, then array_send)
    assert np.frombuffer(first, ">i4", 8).tolist()[1:] == [2, 1, 701, 1024, 1, m, 1]
    assert np.frombuffer(_fields(stream)[1][-1], ">i4", 8).tolist()[1:] == [
        2,
        1,
        701,
        7,
        1,
        m,
        1,
    ]  # 1024..1030: holes below 1030
    back = from_copy(_as_selected(stream, POINTS), POINTS)
    got_ids, got = back.rows()
    assert got_ids.tolist() == ids.tolist()
    assert got["coordinate"].shape == (len(ids), m)
    assert got["coordinate"].tobytes() == points.tobytes()


def _fields(stream: bytes) -> list[list[bytes]]:
    """The rows of a binary COPY stream, each field with its length word."""
    view = memoryview(stream)
    rows: list[list[bytes]] = []
    pos = 19
    while True:
        count = int.from_bytes(view[pos : pos + 2], "big", signed=True)
        if count == -1:
            return rows
        pos += 2
        fields = []
        for _ in range(count):
            length = int.from_bytes(view[pos : pos + 4], "big", signed=True)
            fields.append(bytes(view[pos : pos + 4 + max(length, 0)]))
            pos += 4 + max(length, 0)
        rows.append(fields)


def _as_selected(stream: bytes, spec: ChunkColumns) -> bytes:
    """A to_copy stream as from_copy reads it: without the geoid and revision fields."""
    out = [stream[:19]]
    for fields in _fields(stream):
        keep = [f for f, name in zip(fields, spec.copy_columns()) if name in spec.select_columns()]
        out.append(len(keep).to_bytes(2, "big") + b"".join(keep))
    out.append(b"\xff\xff")
    return b"".join(out)


def test_points_of_no_coordinates_or_two_lengths_are_refused() -> None:
    with pytest.raises(InvalidInputError, match="holds points"):
        encode([0, 1], {"coordinate": np.zeros((2, 0))}, POINTS)
    with pytest.raises(InvalidInputError, match="holds points"):
        encode([0, 1], {"coordinate": np.zeros(2)}, POINTS)
    two = to_copy(encode([0], {"coordinate": np.zeros((1, 2))}, POINTS), 1)
    three = to_copy(encode([1024], {"coordinate": np.zeros((1, 3))}, POINTS), 1)
    joined = two[:-2] + three[19:]
    with pytest.raises(InvalidInputError, match="different lengths"):
        from_copy(_as_selected(joined, POINTS), POINTS)
    with pytest.raises(InvalidInputError, match="must be float8 columns among them"):
        ChunkColumns(("v",), refs=("v",), points=("v",))
