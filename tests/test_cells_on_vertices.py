"""The cells on given vertices read by key on chunks (plan E, area O): each chunk's vertex-id bound ``vtop``.

A table stored in chunks has no index from a vertex to its cells, so the
one-ring readers of the merges by region (``tgsis.mesh_merge_work``'s margin,
``tgsis.merge_mesh_validity``, the Python reader of the change) decoded every
cell chunk of the object for a small change. Each chunk of a table with
vertex-id columns now carries ``vtop``, a bound of its vertex ids that every
writer fills (the client's upload, ``tgsis.write_chunk_rows``, the
conversion ``tgsis.rows_to_chunks``) and the encoding checks verify, and
``tgsis.storage_cells_on`` decodes only the chunks whose ``[vbase, vtop]``
holds one of the vertices asked for. These tests check that the bound is the
same whoever wrote the chunk and bounds every id, and that the cells found on
any set of vertices are exactly those the whole object holds (both storages;
on rows the function names the storage, as before).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import psycopg
import pytest

import tgsis
from tests.merge_data import curved_surface
from tgsis.db import features as F

Conn = psycopg.Connection[Any]

SIDE = 45  # 2,025 vertices (chunks 0 and 1), 3,872 triangles (chunks 0 to 3)

#: per chunk version of tgsis.trgl_chunk: its vtop, the canonical bound computed from its arrays by unnesting
#: (vbase + 2 * the largest relative value, at least 0; the largest id of a wide chunk) and its largest id
BOUNDS = """
SELECT c.chunk, c.revision, c.vtop,
       CASE WHEN c.vbase IS NULL
            THEN (SELECT max(greatest(u.a, u.b, u.c)) FROM unnest(c.vrtxid1_wide, c.vrtxid2_wide, c.vrtxid3_wide) AS u(a, b, c))
            ELSE least(c.vbase::numeric + 2 * greatest(0, (SELECT max(greatest(u.a, u.b, u.c))
                                                             FROM unnest(c.vrtxid1, c.vrtxid2, c.vrtxid3) AS u(a, b, c))),
                       9223372036854775807)::bigint END AS canonical,
       (SELECT max(greatest(r.vrtxid1, r.vrtxid2, r.vrtxid3)) FROM tgsis.trgl_chunk_rows r
         WHERE r.geoid = c.geoid AND r.trglid >> 10 = c.chunk AND r.revision = c.revision) AS largest
  FROM tgsis.trgl_chunk c WHERE c.geoid = %s ORDER BY 1, 2
"""


def _bounds(conn: Conn, geoid: int) -> list[tuple[int, int, int, int, int]]:
    rows = conn.execute(BOUNDS, (geoid,)).fetchall()
    assert rows
    return [(int(r[0]), int(r[1]), int(r[2]), int(r[3]), int(r[4])) for r in rows]


def _check_bounds(conn: Conn, geoid: int) -> None:
    for chunk, revision, vtop, canonical, largest in _bounds(conn, geoid):
        assert vtop == canonical, (chunk, revision, vtop, canonical)
        assert largest <= vtop, (chunk, revision, largest, vtop)


def _surface(spatial: bool) -> tgsis.Mesh:
    curved = curved_surface(SIDE)
    mesh = tgsis.Surface(curved.vertices, curved.cells, name="fault")  # (the class has no property)
    if spatial:  # a Morton order: chunks span distant ids where the curve jumps
        return tgsis.mesh.spatial_order(mesh)
    return mesh


@pytest.mark.storage("chunks")
def test_every_writer_of_a_chunk_gives_it_the_same_bound(db_dsn: str) -> None:
    """The client's upload, a face write (tgsis.write_chunk_rows), a check-in's write (tgsis.write_object_rows)."""
    with psycopg.connect(db_dsn) as conn:
        F.create_feature_class(conn, "faults", "SURFACE")
        tgsis.enable_feature_versioning(conn)
        geoid = F.insert_feature(conn, "faults", _surface(spatial=True))
        conn.commit()
        _check_bounds(conn, geoid)  # the client's encoding (numpy)
        # a triangle made to span far: the face's writer re-encodes its chunk
        conn.execute("UPDATE tgsis.trgl SET vrtxid3 = 2024 WHERE geoid = %s AND trglid = 5", (geoid,))
        conn.commit()
        # a check-in's write of triangles (the absolute ids of a wide chunk: a corner far above the others)
        conn.execute(
            "SELECT tgsis.write_object_rows('trgl', %s, '{}'::bigint[], ARRAY[3000, 3001]::bigint[], NULL, "
            "ARRAY[[0, 1], [1, 2], [2, 4294967296 + 7]]::bigint[])",
            (geoid,),
        )
        conn.commit()
        bounds = _bounds(conn, geoid)
        assert any(b[4] == 4294967296 + 7 for b in bounds)  # the wide chunk is there
        _check_bounds(conn, geoid)


@pytest.mark.storage("rows")
def test_the_conversion_gives_the_bound_the_client_gives(db_dsn: str) -> None:
    """tgsis.rows_to_chunks (the storage switch, the upgrade) computes vtop as the client's upload does."""
    with psycopg.connect(db_dsn) as conn:
        F.create_feature_class(conn, "faults", "SURFACE")
        tgsis.enable_feature_versioning(conn)
        geoid = F.insert_feature(conn, "faults", _surface(spatial=True))
        conn.commit()
        conn.execute(
            "SELECT tgsis.store_in_chunks(tablename) FROM tgsis.model_tables"
            " WHERE chunkdefault AND NOT tgsis.stored_in_chunks(tablename) ORDER BY model, iudorder, tablename"
        )
        conn.commit()
        converted = _bounds(conn, geoid)
        _check_bounds(conn, geoid)
        other = F.insert_feature(conn, "faults", _surface(spatial=True))  # the same mesh, uploaded by the client
        conn.commit()
        # the chunks the conversion wrote hold the bounds the client writes for the same mesh
        assert [(c, v) for c, _, v, _, _ in converted] == [(c, v) for c, _, v, _, _ in _bounds(conn, other)]


def _cells_on(conn: Conn, relation: str, geoid: int, ids: list[int]) -> list[tuple[int, ...]]:
    where = conn.execute("SELECT tgsis.cells_on_vertices_sql(3, %s::bigint[], '$9')", (ids,)).fetchone()
    assert where is not None
    exact = str(where[0]).replace("%", "%%").replace("$9", "%(ids)s::bigint[]")
    return [
        tuple(r)
        for r in conn.execute(
            f"SELECT v.trglid, v.vrtxid1, v.vrtxid2, v.vrtxid3, v.revision FROM {relation.replace('%', '%%')} v"  # noqa: S608
            f" WHERE v.geoid = %(g)s AND {exact} ORDER BY 1, 5",
            {"g": geoid, "ids": ids},
        ).fetchall()
    ]


@pytest.mark.parametrize("spatial", [False, True], ids=["file-order", "spatial-order"])
def test_the_cells_on_any_vertices_are_those_of_the_whole_object(db_dsn: str, spatial: bool) -> None:
    """tgsis.storage_cells_on against the whole storage: the same cell rows for every set of vertices.

    Sets: none, one vertex, each chunk's first and last vertex, a patch, scattered
    vertices, ids no vertex has; every chunk version (the face's write closes one).
    """
    with psycopg.connect(db_dsn) as conn:
        F.create_feature_class(conn, "faults", "SURFACE")
        tgsis.enable_feature_versioning(conn)
        geoid = F.insert_feature(conn, "faults", _surface(spatial))
        conn.commit()
        conn.execute("UPDATE tgsis.trgl SET vrtxid3 = 2024 WHERE geoid = %s AND trglid = 5", (geoid,))
        conn.commit()
        whole = conn.execute("SELECT tgsis.storage_row_versions('tgsis', 'trgl')").fetchone()
        assert whole is not None
        rng = np.random.default_rng(7)
        n = SIDE * SIDE
        sets: list[list[int]] = [
            [],
            [0],
            [1023, 1024, n - 1],
            [int(i) for i in np.arange(600, 700)],
            [int(i) for i in rng.choice(n, 40, replace=False)],
            [2024],
            [n + 5, 10**12],
        ]
        found = 0
        for ids in sets:
            keyed = conn.execute("SELECT tgsis.storage_cells_on('trgl', %s::bigint[])", (ids,)).fetchone()
            assert keyed is not None
            expected = _cells_on(conn, whole[0], geoid, ids)
            assert _cells_on(conn, keyed[0], geoid, ids) == expected, ids
            found += len(expected)
        assert found > 0
        chunked = conn.execute("SELECT tgsis.stored_in_chunks('trgl')").fetchone()
        if chunked == (True,):
            # a few vertices decode a few chunks, not the object's (the point of vtop)
            keyed = conn.execute("SELECT tgsis.storage_cells_on('trgl', ARRAY[0]::bigint[])").fetchone()
            assert keyed is not None
            decoded = conn.execute(
                f"SELECT count(DISTINCT v.trglid >> 10) FROM {keyed[0]} v WHERE v.geoid = %s",  # noqa: S608
                (geoid,),
            ).fetchone()
            total = conn.execute(
                "SELECT count(DISTINCT chunk) FROM tgsis.trgl_chunk WHERE geoid = %s", (geoid,)
            ).fetchone()
            assert decoded is not None and total is not None and decoded[0] < total[0], (decoded, total)


def test_the_client_bound_of_relative_wide_and_top_chunks() -> None:
    """The codec's vtop: vbase + twice the largest stored value; the largest id of a wide chunk; capped at 2^63 - 1."""
    from tgsis._chunks import ChunkColumns, encode

    spec = ChunkColumns(("vrtxid1", "vrtxid2", "vrtxid3"), refs=("vrtxid1", "vrtxid2", "vrtxid3"))
    top = 2**63 - 1
    ids = np.array([0, 1, 1024, 2048, 2049], dtype=np.int64)
    corners = np.array(
        [[10, 14, 11], [12, 10, 13], [5, 2**40, 6], [top - 3, top - 1, top], [top, top - 2, top - 3]], dtype=np.int64
    )
    chunks = encode(ids, {f"vrtxid{j + 1}": corners[:, j] for j in range(3)}, spec)
    assert chunks.wide.tolist() == [False, True, False]
    # chunk 0: vbase 10, stored 0, 4, 1 and 2, -2, 1: 10 + 2 * 4; chunk 1: its largest id; chunk 2: past the top, capped
    assert chunks.vtop.tolist() == [18, 2**40, top]
    assert all(chunks.vtop >= corners.max(axis=1)[[1, 2, 4]])


def test_a_merge_by_region_leaves_the_geometry_row_of_the_object_s_rows(db_dsn: str) -> None:
    """The Python merge writes part of the rows, then the box and counts (tgsis.static_extent on chunks, the faces
    on rows): they are those of the rows through the faces, with a corner vertex moved out of the box and back in."""
    with psycopg.connect(db_dsn) as conn:
        F.create_feature_class(conn, "faults", "SURFACE")
        tgsis.enable_feature_versioning(conn)
        geoid = F.insert_feature(conn, "faults", _surface(spatial=True))
        tgsis.create_version(conn, "e1")
        conn.commit()
        corner = int(np.argmax(_surface(spatial=True).vertices[:, 2]))  # the highest vertex: on the box's top
        with tgsis.in_version(conn, "e1"):
            conn.execute(
                "UPDATE tgsis.vrtx SET z = z - 500.25, x = x + 7000.5 WHERE geoid = %s AND vrtxid = %s", (geoid, corner)
            )
        conn.commit()
        far = (corner + SIDE * SIDE // 2) % (SIDE * SIDE)
        with tgsis.in_version(conn, "DEFAULT"):
            conn.execute("UPDATE tgsis.vrtx SET y = y - 0.125 WHERE geoid = %s AND vrtxid = %s", (geoid, far))
        conn.commit()
        tgsis.merge_version(conn, "e1")
        conn.commit()
        with tgsis.in_version(conn, "e1"):
            row = conn.execute(
                "SELECT nvrtx, ncell, cube_ll_coord(bbox, 1), cube_ll_coord(bbox, 2), cube_ll_coord(bbox, 3), "
                "cube_ur_coord(bbox, 1), cube_ur_coord(bbox, 2), cube_ur_coord(bbox, 3) FROM tgsis.geometry WHERE geoid = %s",
                (geoid,),
            ).fetchone()
            faces = conn.execute(
                "SELECT count(*), (SELECT count(*) FROM tgsis.trgl WHERE geoid = %s), min(x), min(y), min(z), "
                "max(x), max(y), max(z) FROM tgsis.vrtx WHERE geoid = %s",
                (geoid, geoid),
            ).fetchone()
        assert row is not None and faces is not None
        assert row == faces
        assert row[5] > 3200  # the moved corner is the box's new east side
