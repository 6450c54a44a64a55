"""Downloads as a few wide values per table (issue 20): each column of a geometry arrives as one bytea
of packed binary values; what psql users write into the rows (any order, NULLs, versions) still reads right."""

from __future__ import annotations

from typing import Any

import numpy as np
import psycopg
import pytest

import tgsis
from tgsis.db import _static
from tgsis.db import features as F
from tgsis.db.copy import decode_packed
from tgsis.errors import DatabaseError
from tgsis.mesh import Surface

Conn = psycopg.Connection[Any]


def _surface(side: int = 5) -> Surface:
    rng = np.random.default_rng(3)
    u, v = np.meshgrid(np.arange(side, dtype=float), np.arange(side, dtype=float))
    vertices = np.stack([u.ravel(), v.ravel(), rng.standard_normal(side * side)], axis=1)
    vertices[0] = [np.nextafter(0.0, 1.0), -0.0, 1e308]  # subnormal, signed zero, huge: bits must survive
    idx = np.arange(side * side).reshape(side, side)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel()
    cells = np.concatenate([np.stack([a, b, d], 1), np.stack([a, d, c], 1)])
    return Surface(vertices, cells, name="packed", vertex_properties={
        "porosity": rng.random(side * side), "code": rng.integers(-5, 5, side * side).astype(np.int16),
        "normal": rng.standard_normal((side * side, 3)), "flag": rng.random(side * side) < 0.5})


@pytest.fixture
def horizons(conn: Conn) -> F.FeatureClass:
    return F.create_feature_class(conn, "horizon", "SURFACE", cell_properties=[
        {"name": "porosity", "type": "double precision"}, {"name": "code", "type": "smallint"},
        {"name": "normal", "type": "double precision", "size": 3}, {"name": "flag", "type": "boolean"}])


def _bits_equal(a: np.ndarray, b: np.ndarray) -> bool:
    return a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()


def test_decode_packed_checks_lengths_and_arrays() -> None:
    values = np.array([1.5, -0.0, np.nan])
    ids = np.array([7, -1, 2**62])
    packed = np.empty(3, dtype=[("i", ">i8"), ("v", ">f8")])
    packed["i"], packed["v"] = ids, values
    got = decode_packed(packed.tobytes(), ["int8", "float8"], 3, "x")
    assert _bits_equal(got[0], ids) and _bits_equal(got[1], values)
    with pytest.raises(DatabaseError, match="columns i, v of t: 32 bytes for 3 rows of 16"):
        decode_packed(packed[:2].tobytes(), ["int8", "float8"], 3, "columns i, v of t")
    with pytest.raises(DatabaseError, match="NULLs"):
        decode_packed(b"\x00" * 12, ["int4"], 2, "column k")


def test_round_trip_is_bit_exact_with_every_property_kind(conn: Conn, horizons: F.FeatureClass) -> None:
    mesh = _surface()
    got = F.fetch_feature(conn, horizons, F.insert_feature(conn, horizons, mesh)).mesh
    assert isinstance(got, Surface) and got.same_as(mesh)
    assert _bits_equal(got.vertices, mesh.vertices) and np.array_equal(got.cells, mesh.cells)
    for name, values in mesh.vertex_properties.items():
        assert _bits_equal(got.vertex_properties[name], values), name


def test_rows_written_in_any_order_with_gaps_read_in_id_order(conn: Conn, horizons: F.FeatureClass) -> None:
    mesh = _surface(4)
    geoid = F.insert_feature(conn, horizons, mesh)
    # a psql user rewrites the rows in reverse physical order and renumbers the vertices with gaps
    for table, key in (("tgsis.vrtx", "vrtxid"), ("tgsis.trgl", "trglid"), ("horizon_cellpros", "_idx")):
        geo = "_geoid" if table == "horizon_cellpros" else "geoid"
        conn.execute(f"CREATE TEMP TABLE keep AS SELECT * FROM {table} WHERE {geo} = %s ORDER BY {key} DESC", (geoid,))
        conn.execute(f"DELETE FROM {table} WHERE {geo} = %s", (geoid,))
        conn.execute(f"INSERT INTO {table} SELECT * FROM keep")
        conn.execute("DROP TABLE keep")
    conn.execute("UPDATE tgsis.vrtx SET vrtxid = vrtxid * 10 + 7 WHERE geoid = %s", (geoid,))
    conn.execute("UPDATE tgsis.trgl SET vrtxid1 = vrtxid1 * 10 + 7, vrtxid2 = vrtxid2 * 10 + 7, "
                 "vrtxid3 = vrtxid3 * 10 + 7 WHERE geoid = %s", (geoid,))
    conn.execute("UPDATE horizon_cellpros SET _idx = _idx * 10 + 7 WHERE _geoid = %s", (geoid,))
    assert F.fetch_feature(conn, horizons, geoid).mesh.same_as(mesh)


def test_a_null_written_by_psql_is_reported_naming_the_column(conn: Conn, horizons: F.FeatureClass) -> None:
    geoid = F.insert_feature(conn, horizons, _surface(3))
    conn.execute("ALTER TABLE horizon_cellpros ALTER COLUMN porosity DROP NOT NULL")  # as the table's owner may
    conn.execute("UPDATE horizon_cellpros SET porosity = NULL WHERE _geoid = %s AND _idx = 4", (geoid,))
    with pytest.raises(DatabaseError, match=r"column porosity of .*horizon_cellpros.* row _geoid = \d+, _idx = 4"):
        F.fetch_feature(conn, horizons, geoid)
    conn.rollback()


def test_a_short_vector_written_by_psql_is_reported(conn: Conn, horizons: F.FeatureClass) -> None:
    geoid = F.insert_feature(conn, horizons, _surface(3))
    conn.execute("ALTER TABLE horizon_cellpros DROP CONSTRAINT horizon_cellpros_normal_check")  # as its owner may
    conn.execute("UPDATE horizon_cellpros SET normal = ARRAY[1.0, 2.0] WHERE _geoid = %s AND _idx = 2", (geoid,))
    with pytest.raises(DatabaseError, match=r"column normal of .* not float8\[3\] in the row _geoid = \d+, _idx = 2"):
        F.fetch_feature(conn, horizons, geoid)
    conn.rollback()


def test_one_query_per_table_and_versions_read_their_own_rows(conn: Conn, horizons: F.FeatureClass,
                                                              monkeypatch: pytest.MonkeyPatch) -> None:
    mesh = _surface(4)
    geoid = F.insert_feature(conn, horizons, mesh)
    conn.commit()
    tgsis.enable_feature_versioning(conn)
    tgsis.create_version(conn, "edit")
    shifted = mesh.vertices.copy()
    shifted[:, 2] += 1.0
    moved = Surface(shifted, mesh.cells, name="packed",
                    vertex_properties=mesh.vertex_properties)
    with tgsis.in_version(conn, "edit"):
        conn.execute("UPDATE tgsis.vrtx SET z = z + 1 WHERE geoid = %s", (geoid,))
        sources: list[str] = []
        real = _static.columns_out

        def spy(conn: Conn, source: Any, key: str, columns: Any, geoids: Any) -> list[np.ndarray]:
            sources.append(source.as_string(conn))
            return real(conn, source, key, columns, geoids)

        monkeypatch.setattr(_static, "columns_out", spy)
        assert F.fetch_feature(conn, horizons, geoid).mesh.same_as(moved)
        assert sorted(sources) == sorted(['"public"."horizon_cellpros"', "tgsis.vrtx", 'tgsis."trgl"']), sources
    assert F.fetch_feature(conn, horizons, geoid).mesh.same_as(mesh)  # DEFAULT does not see the edit
