"""Downloads as a few wide values per table (issue 20): each column of a geometry arrives as one bytea
of packed binary values; what psql users write into the rows (any order, NULLs, versions) still reads right."""

from __future__ import annotations

import re
from typing import Any

import numpy as np
import psycopg
import pytest
from psycopg import sql

import tgsis
from tests.fetched import geometry_of
from tgsis.db import _static, _transfer
from tgsis.db import features as F
from tgsis.db._chunk_transfer import PackedChunks, chunked_tables, rows_request
from tgsis.db._static_drawing import drawable_surface, stored_surface
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
    return Surface(
        vertices,
        cells,
        name="packed",
        vertex_properties={
            "porosity": rng.random(side * side),
            "code": rng.integers(-5, 5, side * side).astype(np.int16),
            "normal": rng.standard_normal((side * side, 3)),
            "flag": rng.random(side * side) < 0.5,
        },
    )


@pytest.fixture
def horizons(conn: Conn) -> F.FeatureClass:
    """A class whose property table is rows whatever model 1's storage (these tests read and write the row table
    as a psql user would; property chunks have their own tests: tests/test_property_chunk_transfer.py)."""
    conn.execute("SET tgsis.storage = rows")
    try:
        return _horizons(conn)
    finally:
        conn.execute("RESET tgsis.storage")


def _horizons(conn: Conn) -> F.FeatureClass:
    return F.create_feature_class(
        conn,
        "horizon",
        "SURFACE",
        cell_properties=[
            {"name": "porosity", "type": "double precision"},
            {"name": "code", "type": "smallint"},
            {"name": "normal", "type": "double precision", "size": 3},
            {"name": "flag", "type": "boolean"},
        ],
    )


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
    # a psql user rewrites the rows in reverse order and renumbers the vertices with gaps (stored in chunks:
    # holes inside the chunks, ids beyond the first chunk)
    renumbered = {
        "tgsis.vrtx": ("vrtxid", "geoid, vrtxid * 10 + 7 AS vrtxid, x, y, z"),
        "tgsis.trgl": (
            "trglid",
            "geoid, trglid, vrtxid1 * 10 + 7 AS v1, vrtxid2 * 10 + 7 AS v2, vrtxid3 * 10 + 7 AS v3",
        ),
        "horizon_cellpros": ("_idx", "_geoid, _idx * 10 + 7 AS _idx, porosity, code, normal, flag"),
    }
    for table, (key, columns) in renumbered.items():
        geo = "_geoid" if table == "horizon_cellpros" else "geoid"
        conn.execute(
            f"CREATE TEMP TABLE keep AS SELECT {columns} FROM {table} WHERE {geo} = %s ORDER BY {key} DESC", (geoid,)
        )
        conn.execute(f"DELETE FROM {table} WHERE {geo} = %s", (geoid,))
        conn.execute(f"INSERT INTO {table} SELECT * FROM keep")
        conn.execute("DROP TABLE keep")
    assert conn.execute("SELECT max(vrtxid) FROM tgsis.vrtx WHERE geoid = %s", (geoid,)).fetchone() == (157,)
    assert geometry_of(F.fetch_feature(conn, horizons, geoid)).same_as(mesh)


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


def test_one_query_for_all_tables_and_versions_read_their_own_rows(
    conn: Conn, horizons: F.FeatureClass, monkeypatch: pytest.MonkeyPatch
) -> None:
    mesh = _surface(4)
    geoid = F.insert_feature(conn, horizons, mesh)
    conn.commit()
    tgsis.enable_feature_versioning(conn)
    tgsis.create_version(conn, "edit")
    shifted = mesh.vertices.copy()
    shifted[:, 2] += 1.0
    moved = Surface(shifted, mesh.cells, name="packed", vertex_properties=mesh.vertex_properties)
    with tgsis.in_version(conn, "edit"):
        conn.execute("UPDATE tgsis.vrtx SET z = z + 1 WHERE geoid = %s", (geoid,))
        calls: list[list[str]] = []
        real = _transfer.columns_out_all  # what _static imports

        def spy(conn: Conn, requests: Any) -> list[list[np.ndarray]]:
            calls.append([_source(conn, request) for request in requests])
            return real(conn, requests)

        monkeypatch.setattr(_static, "columns_out_all", spy)
        assert geometry_of(F.fetch_feature(conn, horizons, geoid)).same_as(moved)
        assert len(calls) == 1, calls  # one query, all three tables
        # the model tables' rows, or (stored in chunks) their chunks, not the face
        chunked = conn.execute("SELECT tgsis.stored_in_chunks('vrtx')").fetchone() == (True,)
        model = ["tgsis.vrtx_chunk", "tgsis.trgl_chunk"] if chunked else ["tgsis.vrtx", "tgsis.trgl"]
        read = sorted(name.replace('"', "") for name in calls[0])  # quoted or not, as the layout names it
        assert read == sorted(["public.horizon_cellpros", *model]), calls
    assert geometry_of(F.fetch_feature(conn, horizons, geoid)).same_as(mesh)  # DEFAULT does not see the edit


def _source(conn: Conn, request: Any) -> str:
    """The relation a part of ``columns_out_all`` reads: a Packed request's source, a chunk table's name."""
    if isinstance(request, PackedChunks):
        return request.layout.relation.as_string(conn)
    return str(request.source.as_string(conn))


def _chunked(conn: Conn) -> bool:
    return conn.execute("SELECT tgsis.stored_in_chunks('trgl')").fetchone() == (True,)


def _oriented(triangles: np.ndarray) -> np.ndarray:
    """Triangles as a sorted list, each turned to start at its smallest corner (orientation kept)."""
    t = np.asarray(triangles, dtype=np.int64).reshape(-1, 3)
    turned = np.stack([np.roll(row, -int(np.argmin(row))) for row in t]) if len(t) else t
    return turned[np.lexsort(turned.T[::-1])]


def test_corners_travel_packed_one_value_a_triangle(
    conn: Conn, horizons: F.FeatureClass, monkeypatch: pytest.MonkeyPatch
) -> None:
    mesh = _surface(6)
    geoid = F.insert_feature(conn, horizons, mesh)
    queries: list[str] = []
    real = _transfer.columns_out

    def spy(*args: Any) -> list[np.ndarray]:
        queries.append("columns")
        return real(*args)

    monkeypatch.setattr(_transfer, "columns_out", spy)
    got = _transfer.corners_out(conn, sql.SQL("tgsis.trgl"), "geoid", ["vrtxid1", "vrtxid2", "vrtxid3"], geoid)
    assert queries == []  # the packed path, no fallback
    assert got.dtype == np.int64 and np.array_equal(_oriented(got), _oriented(mesh.cells))
    # the largest ids that fit in 21 bits, in every position, keep their bits
    top = 2**21 - 1
    conn.execute(
        "UPDATE tgsis.trgl SET vrtxid1 = %s, vrtxid2 = %s, vrtxid3 = %s WHERE geoid = %s AND trglid = 0",
        (top, top - 1, top - 2, geoid),
    )
    got = _transfer.corners_out(conn, sql.SQL("tgsis.trgl"), "geoid", ["vrtxid1", "vrtxid2", "vrtxid3"], geoid)
    assert queries == [] and [top, top - 1, top - 2] in got.tolist()


@pytest.mark.parametrize("corner", [2**21, 2**40, -1])
def test_corners_out_of_the_packed_range_come_as_columns(conn: Conn, horizons: F.FeatureClass, corner: int) -> None:
    mesh = _surface(4)
    geoid = F.insert_feature(conn, horizons, mesh)
    if corner < 0 and _chunked(conn):  # chunks hold ids 0 and up: no such row to read
        with pytest.raises(psycopg.DatabaseError, match="negative id"):
            conn.execute("UPDATE tgsis.vrtx SET vrtxid = %s WHERE geoid = %s AND vrtxid = 5", (corner, geoid))
        conn.rollback()
        return
    # a psql user numbers one vertex out of the 21 bits (or below 0): its triangles must not mix their bits
    conn.execute("UPDATE tgsis.vrtx SET vrtxid = %s WHERE geoid = %s AND vrtxid = 5", (corner, geoid))
    for column in ("vrtxid1", "vrtxid2", "vrtxid3"):
        conn.execute(f"UPDATE tgsis.trgl SET {column} = %s WHERE geoid = %s AND {column} = 5", (corner, geoid))
    expected = np.where(mesh.cells == 5, corner, mesh.cells)
    got = _transfer.corners_out(conn, sql.SQL("tgsis.trgl"), "geoid", ["vrtxid1", "vrtxid2", "vrtxid3"], geoid)
    assert np.array_equal(_oriented(got), _oriented(expected))
    # the scene: vertices in id order (vertex 5 moved to the end, or the start), triangles as positions in it
    ids = np.where(np.arange(mesh.n_vertices) == 5, corner, np.arange(mesh.n_vertices))
    order = np.argsort(ids)
    position = np.empty(mesh.n_vertices, dtype=np.int64)
    position[order] = np.arange(mesh.n_vertices)
    drawn = drawable_surface(conn, horizons, geoid)
    assert _bits_equal(drawn.vertices, mesh.vertices[order])
    assert np.array_equal(_oriented(drawn.indices), _oriented(position[mesh.cells]))


def test_a_null_corner_written_by_psql_is_reported_naming_the_row(conn: Conn, horizons: F.FeatureClass) -> None:
    geoid = F.insert_feature(conn, horizons, _surface(3))
    if _chunked(conn):  # a NULL in a chunk's array that is no hole: the chunk's owner broke the contract
        conn.execute("UPDATE tgsis.trgl_chunk SET vrtxid2[4] = NULL WHERE geoid = %s AND chunk = 0", (geoid,))
        with pytest.raises(tgsis.InvalidInputError, match="NULL"):
            F.fetch_feature(conn, horizons, geoid)
        with pytest.raises(tgsis.InvalidInputError, match="NULL"):
            drawable_surface(conn, horizons, geoid)
        conn.rollback()
        return
    conn.execute("ALTER TABLE tgsis.trgl ALTER COLUMN vrtxid2 DROP NOT NULL")  # as the table's owner may
    conn.execute("UPDATE tgsis.trgl SET vrtxid2 = NULL WHERE geoid = %s AND trglid = 3", (geoid,))
    with pytest.raises(DatabaseError, match=r"column vrtxid2 of tgsis.trgl.* row geoid = \d+"):
        _transfer.corners_out(conn, sql.SQL("tgsis.trgl"), "geoid", ["vrtxid1", "vrtxid2", "vrtxid3"], geoid)
    conn.rollback()


def test_the_scene_draws_what_is_stored_in_the_session_version(conn: Conn, horizons: F.FeatureClass) -> None:
    mesh = _surface(5)
    geoid = F.insert_feature(conn, horizons, mesh)
    conn.commit()
    tgsis.enable_feature_versioning(conn)
    tgsis.create_version(conn, "edit")
    with tgsis.in_version(conn, "edit"):
        conn.execute("UPDATE tgsis.vrtx SET z = z + 1 WHERE geoid = %s", (geoid,))
        conn.execute("DELETE FROM tgsis.trgl WHERE geoid = %s AND trglid = 0", (geoid,))
        drawn = drawable_surface(conn, horizons, geoid, "porosity")
        stored = stored_surface(conn, horizons, geoid, "porosity")
    assert _bits_equal(drawn.vertices, stored.drawable.vertices)
    assert np.array_equal(drawn.vertices[:, 2], mesh.vertices[:, 2] + 1)
    assert np.array_equal(_oriented(drawn.indices), _oriented(mesh.cells[1:]))
    assert np.array_equal(_oriented(drawn.indices), _oriented(stored.drawable.indices))
    assert _bits_equal(drawn.vertex_values["porosity"], mesh.vertex_properties["porosity"])
    base = drawable_surface(conn, horizons, geoid)  # DEFAULT sees neither change
    assert _bits_equal(base.vertices, mesh.vertices) and np.array_equal(_oriented(base.indices), _oriented(mesh.cells))


def test_several_geometries_at_once_each_read_its_own_rows(conn: Conn, horizons: F.FeatureClass) -> None:
    first, second = _surface(4), _surface(6)
    a, b = F.insert_feature(conn, horizons, first), F.insert_feature(conn, horizons, second)
    # one aggregate per geometry (not one group per geometry): rows interleaved by a psql user read right
    conn.execute(
        "CREATE TEMP TABLE keep AS SELECT * FROM tgsis.vrtx WHERE geoid IN (%s, %s) ORDER BY vrtxid, geoid", (a, b)
    )
    conn.execute("DELETE FROM tgsis.vrtx WHERE geoid IN (%s, %s)", (a, b))
    conn.execute("INSERT INTO tgsis.vrtx SELECT * FROM keep")
    got = F.fetch_features(conn, horizons, [b, a, b])
    assert [f.id for f in got] == [b, a, b]
    assert geometry_of(got[0]).same_as(second) and geometry_of(got[1]).same_as(first)
    assert geometry_of(got[2]).same_as(second)
    conn.execute("ALTER TABLE horizon_cellpros ALTER COLUMN porosity DROP NOT NULL")  # as the table's owner may
    conn.execute("UPDATE horizon_cellpros SET porosity = NULL WHERE _geoid = %s AND _idx = 7", (b,))
    with pytest.raises(DatabaseError, match=rf"column porosity of .*horizon_cellpros.* row _geoid = {b}, _idx = 7"):
        F.fetch_features(conn, horizons, [a, b])
    conn.rollback()


@pytest.mark.parametrize("versioned", [False, True], ids=["plain", "versioned"])
def test_parallel_workers_read_the_tables_side_by_side_and_see_the_transactions_writes(
    conn: Conn, horizons: F.FeatureClass, versioned: bool
) -> None:
    """The tables' aggregates of one download as a Parallel Append (here forced by zero costs; the planner
    picks it by itself for a large geometry), through the versioned views too: the workers see what the
    session's transaction wrote and has not committed, in the session's version."""
    mesh = _surface(6)
    geoid = F.insert_feature(conn, horizons, mesh)
    conn.commit()
    if versioned:
        tgsis.enable_feature_versioning(conn)
        tgsis.create_version(conn, "edit")
        conn.commit()
    for setting in (
        "parallel_setup_cost",
        "parallel_tuple_cost",
        "min_parallel_table_scan_size",
        "min_parallel_index_scan_size",
    ):
        conn.execute(sql.SQL("SET {} = 0").format(sql.Identifier(setting)))
    conn.execute("SET max_parallel_workers_per_gather = 2")
    chunked = chunked_tables(conn)  # stored in chunks: the chunk tables' parts (never the face)
    requests = [
        rows_request(conn, "vrtx", [("vrtxid", "int8"), ("z", "float8")], [geoid], chunked),
        rows_request(conn, "trgl", [("trglid", "int8"), ("vrtxid1", "int8")], [geoid], chunked),
    ]
    query = sql.SQL(" UNION ALL ").join(r.query(i) for i, r in enumerate(requests))
    with tgsis.in_version(conn, "edit" if versioned else "DEFAULT"):
        conn.execute("UPDATE tgsis.vrtx SET z = -z WHERE geoid = %s", (geoid,))  # not committed
        plan = "\n".join(row[0] for row in conn.execute(sql.SQL("EXPLAIN (COSTS OFF) {}").format(query)))
        # workers read the versioned views too (their revision set is PARALLEL SAFE): the tables' aggregates
        # side by side (PostgreSQL 18); PostgreSQL 15 keeps the views' initplans above each aggregate, and
        # with the model views' per-class filter (a hashed subplan over tgsis.class_denied_geoids:
        # docs/security.md) it plans their scans serially (before that filter: a Gather per scan)
        assert ("Gather" in plan and "Workers Planned" in plan) or (versioned and conn.info.server_version < 180000), (
            plan
        )
        assert "Parallel Append" in plan or (versioned and conn.info.server_version < 180000), plan
        flipped = mesh.vertices.copy()
        flipped[:, 2] *= -1
        got = F.fetch_feature(conn, horizons, geoid).mesh
        assert isinstance(got, Surface) and np.array_equal(got.vertices, flipped)
        assert np.array_equal(_oriented(got.cells), _oriented(mesh.cells))
        vertices, triangles = _transfer.columns_out_all(conn, requests)
        assert np.array_equal(vertices[2][np.argsort(vertices[1])], flipped[:, 2])
        assert len(triangles[0]) == mesh.n_cells and set(triangles[0]) == {geoid}
        # the scans run in workers only (the leader takes none): they count the rows the transaction
        # deleted and has not committed as gone (PostgreSQL 15 then plans the versioned views' query serial)
        conn.execute("DELETE FROM tgsis.trgl WHERE geoid = %s AND trglid < 7", (geoid,))
        conn.execute("SET parallel_leader_participation = off")
        analyzed = [
            row[0] for row in conn.execute(sql.SQL("EXPLAIN (ANALYZE, COSTS OFF, TIMING OFF) {}").format(query))
        ]
        launched = [int(m.group(1)) for line in analyzed if (m := re.search(r"Workers Launched: (\d+)", line))]
        if not versioned or conn.info.server_version >= 180000:
            assert launched and all(n >= 1 for n in launched), analyzed
        scanned = [
            float(m.group(1)) * int(m.group(2))
            for line in analyzed
            if re.search(r"Scan (using \S+ )?on trgl", line)
            and "Bitmap Index Scan" not in line
            and (m := re.search(r"actual rows=([\d.]+) loops=(\d+)", line))
        ]
        assert sum(scanned) == (1 if chunked else mesh.n_cells - 7), analyzed  # chunks: the one visible chunk
        assert len(_transfer.columns_out_all(conn, requests)[1][0]) == mesh.n_cells - 7
    conn.rollback()
