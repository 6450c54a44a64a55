"""Snapshots at t sent packed (issue 40): rows grouped by the server, not a COPY message per row.

``tgsis.db._transfer.packed_out`` reads a query's rows as the server's
``string_agg`` of their binary send forms, grouped by blocks of keys;
``get_at`` (vertices, triangles and properties at t) and ``surfaces_at``
read through it. Checked here: the values are bit for bit what a binary
COPY gives (-0.0, NaN payloads, subnormals, negative keys), a NULL is
reported and not dropped, no rows give empty columns, and snapshots of
models 2 and 3 spanning many groups are bit for bit the numpy side's.
"""

from __future__ import annotations

from typing import Any, Literal

import numpy as np
import psycopg
import pytest
from psycopg import sql

import tgsis
from tests.temporal_data import evolving, series
from tgsis.db import _chunk_transfer, _transfer
from tgsis.db.copy import encode_rows
from tgsis.errors import DatabaseError
from tgsis.temporal import EvolvingSurface, TopologyPeriod

Conn = psycopg.Connection[Any]

#: doubles whose bits a text round trip or an arithmetic path would change
_SPECIAL = np.array([0x8000000000000000, 0x7FF8000000000001, 0xFFF0DEADBEEF0000, 0x0000000000000001], dtype=np.uint64)


def _table(conn: Conn, keys: np.ndarray, values: np.ndarray) -> None:
    conn.execute("CREATE TEMP TABLE packed_rows (k bigint, v double precision) ON COMMIT DROP")
    with conn.cursor().copy("COPY packed_rows (k, v) FROM STDIN (FORMAT binary)") as copy:
        copy.write(encode_rows([(keys, "int8"), (values, "float8")]))


def _bits(values: np.ndarray) -> np.ndarray:
    return np.ascontiguousarray(values, dtype=np.float64).view(np.uint64)


@pytest.mark.parametrize("bits", [0, 3, 10])
def test_packed_out_is_copy_out_bit_for_bit(tx: Conn, monkeypatch: pytest.MonkeyPatch, bits: int) -> None:
    monkeypatch.setattr(_transfer, "PACKED_GROUP_BITS", bits)
    rng = np.random.default_rng(3)
    keys = rng.permutation(np.arange(-2500, 2500, dtype=np.int64))
    values = rng.normal(size=len(keys))
    values[: len(_SPECIAL)] = _SPECIAL.view(np.float64)
    _table(tx, keys, values)
    query = sql.SQL("SELECT k, v FROM packed_rows")
    k1, v1 = _transfer.packed_out(tx, query, [("k", "int8"), ("v", "float8")], ["k"])
    k2, v2 = _transfer.copy_out(tx, query, ["int8", "float8"])
    assert k1.dtype == np.int64 and v1.dtype == np.float64
    o1, o2 = np.argsort(k1), np.argsort(k2)
    np.testing.assert_array_equal(k1[o1], np.sort(keys))
    np.testing.assert_array_equal(k1[o1], k2[o2])
    np.testing.assert_array_equal(_bits(v1[o1]), _bits(v2[o2]))
    np.testing.assert_array_equal(_bits(v1[o1]), _bits(values[np.argsort(keys)]))


def test_packed_out_reports_a_null_instead_of_dropping_it(tx: Conn) -> None:
    _table(tx, np.arange(3000, dtype=np.int64), np.ones(3000))
    tx.execute("UPDATE packed_rows SET v = NULL WHERE k = 2047")
    with pytest.raises(DatabaseError, match="NULLs"):
        _transfer.packed_out(tx, sql.SQL("SELECT k, v FROM packed_rows"), [("k", "int8"), ("v", "float8")], ["k"])
    tx.execute("UPDATE packed_rows SET v = 1, k = NULL WHERE k IS NOT DISTINCT FROM 2047")  # a NULL key is a group
    with pytest.raises(DatabaseError, match="NULLs"):
        _transfer.packed_out(tx, sql.SQL("SELECT k, v FROM packed_rows"), [("k", "int8"), ("v", "float8")], ["k"])


def test_packed_out_of_no_rows(tx: Conn) -> None:
    k, v = _transfer.packed_out(
        tx, sql.SQL("SELECT 1::int8 AS k, 2::float8 AS v WHERE false"), [("k", "int8"), ("v", "float8")], ["k"]
    )
    assert k.shape == (0,) and k.dtype == np.int64 and v.shape == (0,) and v.dtype == np.float64


def _same(got: tgsis.Surface | None, expected: tgsis.Surface | None) -> None:
    assert got is not None and expected is not None
    np.testing.assert_array_equal(_bits(got.vertices), _bits(expected.vertices))
    np.testing.assert_array_equal(got.triangles, expected.triangles)


@pytest.mark.parametrize("bits", [2, 10])
def test_snapshots_spanning_many_groups_are_bit_exact(tx: Conn, monkeypatch: pytest.MonkeyPatch, bits: int) -> None:
    monkeypatch.setattr(_transfer, "PACKED_GROUP_BITS", bits)
    # model 3: 1,089 nodes in the second period (two groups of 1,024 ids), 2,048 triangles
    fault = evolving(np.random.default_rng(11), [0.0, 2.0], instants_per_period=3, side=17, with_properties=True)
    other = evolving(np.random.default_rng(12), [0.0], instants_per_period=3, side=9, with_properties=True)
    horizon = series(np.random.default_rng(13), [0.0, 1.0, 2.5], alive=True, with_properties=True)
    tgsis.create_feature_class(
        tx, "faults", "SURFACE", time_model="EVOLVING", cell_properties=[("porosity", "float8")],
        instant_properties=[("throw", "float8"), ("note_code", "integer")],
    )  # fmt: skip
    tgsis.create_feature_class(
        tx, "horizons", "SURFACE", time_model="INSTANTS", cell_properties=[("porosity", "float8")],
        instant_properties=[("throw", "float8")],
    )  # fmt: skip
    fid = tgsis.insert_feature(tx, "faults", fault)
    oid = tgsis.insert_feature(tx, "faults", other)
    hid = tgsis.insert_feature(tx, "horizons", horizon, drop_extra_properties=True)
    for t in (0.0, 0.7, 2.0, 2.3, 2.9):  # instants and between them, both periods
        got = tgsis.get_at(tx, fid, t, properties=True)
        expected = fault.at(t)
        _same(got, expected)
        assert got is not None and expected is not None
        np.testing.assert_array_equal(
            _bits(got.vertex_properties["porosity"]), _bits(expected.vertex_properties["porosity"])
        )
    for t in (0.0, 0.5, 1.0, 3.0):
        got = tgsis.get_at(tx, hid, t, properties=True)
        expected = horizon.at(t)
        _same(got, expected)
        assert got is not None and expected is not None
        np.testing.assert_array_equal(
            _bits(got.vertex_properties["porosity"]), _bits(expected.vertex_properties["porosity"])
        )
    both = tgsis.surfaces_at(tx, "faults", 0.4)
    assert sorted(both) == sorted([fid, oid])
    _same(both[fid], fault.at(0.4))
    _same(both[oid], other.at(0.4))


@pytest.mark.parametrize("bits", [2, 10])
def test_whole_features_of_models_2_and_3_come_back_bit_exact(
    tx: Conn, monkeypatch: pytest.MonkeyPatch, bits: int
) -> None:
    """fetch_evolving / fetch_series read the geometry and property rows packed and order them on the client."""
    monkeypatch.setattr(_transfer, "PACKED_GROUP_BITS", bits)
    fault = evolving(np.random.default_rng(21), [0.0, 2.0], instants_per_period=3, side=9, with_properties=True)
    first = fault.periods[0]
    positions = first.positions.copy()
    positions.reshape(-1)[1 : 1 + len(_SPECIAL) - 2] = _SPECIAL[[0, 3]].view(np.float64)  # -0.0, a subnormal
    fault = EvolvingSurface([TopologyPeriod(first.times, first.triangles, positions,
                                            vertex_properties=first.vertex_properties, properties=first.properties),
                             *fault.periods[1:]], name="packed")  # fmt: skip
    horizon = series(np.random.default_rng(22), [0.0, 1.0, 2.5, 4.0], with_properties=True)
    tgsis.create_feature_class(
        tx, "faults", "SURFACE", time_model="EVOLVING", cell_properties=[("porosity", "float8")],
        instant_properties=[("throw", "float8"), ("note_code", "integer")],
    )  # fmt: skip
    tgsis.create_feature_class(
        tx, "horizons", "SURFACE", time_model="INSTANTS", cell_properties=[("porosity", "float8")],
        instant_properties=[("throw", "float8")],
    )  # fmt: skip
    fid = tgsis.insert_feature(tx, "faults", fault)
    hid = tgsis.insert_feature(tx, "horizons", horizon, drop_extra_properties=True)
    back = tgsis.fetch_evolving(tx, "faults", fid)
    assert len(back.periods) == len(fault.periods)
    for got, sent in zip(back.periods, fault.periods):
        np.testing.assert_array_equal(_bits(got.times), _bits(sent.times))
        np.testing.assert_array_equal(got.triangles, sent.triangles)
        np.testing.assert_array_equal(_bits(got.positions), _bits(sent.positions))
        np.testing.assert_array_equal(
            _bits(got.vertex_properties["porosity"]), _bits(sent.vertex_properties["porosity"])
        )
    steps = tgsis.fetch_series(tx, "horizons", hid)
    np.testing.assert_array_equal(steps.times, horizon.times)
    for got_surface, sent_surface in zip(steps.surfaces, horizon.surfaces):
        _same(got_surface, sent_surface)
        np.testing.assert_array_equal(
            _bits(got_surface.vertex_properties["porosity"]), _bits(sent_surface.vertex_properties["porosity"])
        )


def test_first_times_come_back_ascending_whatever_the_groups(tx: Conn, monkeypatch: pytest.MonkeyPatch) -> None:
    """first_times reads packed (groups come in any order) and orders by id: as the SQL function's ORDER BY."""
    fault = evolving(np.random.default_rng(31), [0.0, 2.0], instants_per_period=4, side=9, with_properties=True)
    tgsis.create_feature_class(
        tx, "faults", "SURFACE", time_model="EVOLVING", cell_properties=[("porosity", "float8")],
        instant_properties=[("throw", "float8"), ("note_code", "integer")],
    )  # fmt: skip
    fid = tgsis.insert_feature(tx, "faults", fault)
    expected = tx.execute(
        "SELECT idx, t FROM tgsis.first_time('faults', %s, 'porosity', '>', 0.2, 'left')", (fid,)
    ).fetchall()
    assert len(expected) > 100
    for bits in (0, 10):  # one id a group: the groups come in the hash's order
        monkeypatch.setattr(_transfer, "PACKED_GROUP_BITS", bits)
        idx, t = tgsis.first_times(tx, "faults", fid, "porosity", ">", 0.2)
        assert idx.tolist() == [r[0] for r in expected]
        np.testing.assert_array_equal(_bits(t), _bits(np.array([r[1] for r in expected])))


@pytest.mark.parametrize("model", ["EVOLVING", "INSTANTS"])
def test_a_snapshot_is_of_one_state_whatever_commits_between_its_reads(
    conn: Conn, db_dsn: str, monkeypatch: pytest.MonkeyPatch, model: Literal["EVOLVING", "INSTANTS"]
) -> None:
    """get_at reads vertices, triangles and properties in several statements: all of one state.

    Another session commits a change to the feature's triangles and vertex
    properties after get_at read its vertices. The snapshot must be the surface
    as it was before that commit, not its vertices with the new triangles.
    Fails when the reads run in a READ COMMITTED transaction (each statement
    its own snapshot).
    """
    from tgsis.db import _temporal_common
    from tgsis.db.classes import get_feature_class

    rng = np.random.default_rng(41)
    if model == "EVOLVING":
        surface: Any = evolving(rng, [0.0], instants_per_period=2, side=5, with_properties=True)
        triangles, corner = "d4dtrgl", "nodeid"
    else:
        surface = series(rng, [0.0, 1.0], with_properties=True)
        triangles, corner = "times_trgl", "vrtxid"
    tgsis.create_feature_class(
        conn, "faults", "SURFACE", time_model=model, cell_properties=[("porosity", "float8")],
        instant_properties=[("throw", "float8"), ("note_code", "integer")],
    )  # fmt: skip
    fid = tgsis.insert_feature(conn, "faults", surface, drop_extra_properties=True)
    fc = get_feature_class(conn, "faults")
    conn.commit()
    before = tgsis.get_at(conn, fid, 0.0, properties=True)
    conn.commit()
    assert before is not None
    reads = []

    def read_then_commit_another_change(read: Any) -> Any:
        def hooked(*args: Any, **kwargs: Any) -> Any:
            result = read(*args, **kwargs)
            reads.append(1)
            after_a_read()
            return result

        return hooked

    def after_a_read() -> None:
        if len(reads) == 1:  # the vertices are read: another session changes the rest
            with psycopg.connect(db_dsn) as other:
                other.execute(
                    sql.SQL("UPDATE {} SET {a} = {b}, {b} = {a} WHERE geoid = %s").format(
                        sql.Identifier("tgsis", triangles),
                        a=sql.Identifier(corner + "1"),
                        b=sql.Identifier(corner + "2"),
                    ),
                    (fid,),
                )
                other.execute(
                    sql.SQL("UPDATE {} SET porosity = -1 WHERE _geoid = %s").format(
                        sql.Identifier(fc.schema, fc.cellprotable)
                    ),
                    (fid,),
                )

    monkeypatch.setattr(_temporal_common, "packed_out", read_then_commit_another_change(_transfer.packed_out))
    # model 2 with its time tables in chunks (TGSIS_TEST_TIME_STORAGE=chunks) reads the instant's chunks
    monkeypatch.setattr(
        "tgsis.db._temporal_common.instant_rows", read_then_commit_another_change(_chunk_transfer.instant_rows)
    )
    got = tgsis.get_at(conn, fid, 0.0, properties=True)
    conn.commit()
    assert len(reads) >= 2
    assert got is not None
    _same(got, before)
    np.testing.assert_array_equal(_bits(got.vertex_properties["porosity"]), _bits(before.vertex_properties["porosity"]))
    monkeypatch.undo()
    after = tgsis.get_at(conn, fid, 0.0, properties=True)
    conn.commit()
    assert after is not None and not np.array_equal(after.triangles, before.triangles)  # the change was made
