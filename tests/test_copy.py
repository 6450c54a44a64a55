"""Binary COPY payloads built and parsed with numpy, checked against a real server."""

from __future__ import annotations

from typing import Any

import numpy as np
import psycopg
import pytest

import tgsis
from tgsis.db.copy import decode_rows, encode_chunks, encode_rows

TYPES = ["int2", "int4", "int8", "float4", "float8", "bool"]


def _columns(n: int) -> list[tuple[np.ndarray, str]]:
    rng = np.random.default_rng(7)
    return [
        (rng.integers(-(2**15), 2**15, n).astype(np.int16), "int2"),
        (rng.integers(-(2**31), 2**31, n).astype(np.int32), "int4"),
        (rng.integers(-(2**62), 2**62, n), "int8"),
        (rng.standard_normal(n).astype(np.float32), "float4"),
        (np.concatenate([[np.nan, -0.0, np.inf, 5e-324], rng.standard_normal(n - 4)]), "float8"),
        (rng.random(n) < 0.5, "bool"),
    ]


def test_round_trip_through_the_server(tx: psycopg.Connection[Any]) -> None:
    columns = _columns(1000)
    tx.execute("CREATE TEMP TABLE t (a int2, b int4, c int8, d float4, e float8, f bool)")
    with tx.cursor().copy("COPY t FROM STDIN (FORMAT binary)") as copy:
        copy.write(encode_rows(columns))
    assert tx.execute("SELECT count(*), sum(c::numeric) FROM t").fetchone() == (
        1000,
        sum(int(v) for v in columns[2][0]),
    )
    with tx.cursor().copy("COPY t TO STDOUT (FORMAT binary)") as copy:
        data = b"".join(bytes(chunk) for chunk in copy)
    decoded = decode_rows(data, TYPES)
    for (expected, _), got in zip(columns, decoded):
        assert got.dtype == expected.dtype
        assert np.array_equal(got.view(np.uint8), expected.view(np.uint8)), "bit-exact, NaN and -0.0 included"


def test_empty_payload(tx: psycopg.Connection[Any]) -> None:
    tx.execute("CREATE TEMP TABLE e (a int8)")
    with tx.cursor().copy("COPY e FROM STDIN (FORMAT binary)") as copy:
        copy.write(encode_rows([(np.empty(0, np.int64), "int8")]))
    with tx.cursor().copy("COPY e TO STDOUT (FORMAT binary)") as copy:
        data = b"".join(bytes(chunk) for chunk in copy)
    assert decode_rows(data, ["int8"])[0].shape == (0,)


def test_nulls_are_refused_not_misread(tx: psycopg.Connection[Any]) -> None:
    with tx.cursor().copy("COPY (SELECT 1::int8, NULL::float8) TO STDOUT (FORMAT binary)") as copy:
        data = b"".join(bytes(chunk) for chunk in copy)
    with pytest.raises(tgsis.DatabaseError, match="NULLs"):
        decode_rows(data, ["int8", "float8"])


def test_unequal_columns_are_refused() -> None:
    with pytest.raises(tgsis.InvalidPropertyError, match="different lengths: 2, 3"):
        encode_rows([(np.zeros(2), "float8"), (np.zeros(3), "float8")])


def test_a_payload_in_pieces_is_the_payload_and_each_piece_holds_whole_rows() -> None:
    columns = [
        (np.arange(10, dtype=np.int64), "int8"),
        (np.linspace(0, 1, 30).reshape(10, 3), "float8[3]"),
        (np.arange(10) % 2 == 0, "bool"),
    ]
    whole = encode_rows(columns)
    pieces = list(encode_chunks(columns, 4))
    assert len(pieces) == 3 and b"".join(pieces) == whole
    header, trailer = 19, 2  # PGCOPY signature, flags, extension; the -1 trailer
    row = (len(whole) - header - trailer) // 10
    assert [len(p) for p in pieces] == [header + 4 * row, 4 * row, 2 * row + trailer]
    assert decode_rows(whole, ["int8", "float8[3]", "bool"])[0].tolist() == list(range(10))
    assert list(encode_chunks([(np.empty(0, dtype=np.int64), "int8")], 4)) == [
        encode_rows([(np.empty(0, np.int64), "int8")])
    ]
    with pytest.raises(tgsis.InvalidPropertyError, match="different lengths"):
        next(encode_chunks([(np.arange(3), "int8"), (np.arange(4), "int8")], 2))
