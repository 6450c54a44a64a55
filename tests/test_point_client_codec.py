"""The client codec of G-map points in chunks (issue 40, plan M, Q): uploads encoded in numpy, downloads decoded.

Since plan M (P) ``tgsis.md_vertex`` and ``tgsis.gmap_vertex`` may be stored in
chunks (role ``point``: one 2-D ``double precision[]`` per chunk, slots x m, a
hole a row of m NULLs; docs/storage.md, "The points in chunks"). The uploads
(``insert_gmap`` of models 4 and 5) now encode those chunks in the client
(``tgsis.db._chunk_transfer.upload_rows``) and the downloads (``fetch_gmap``,
``fetch_md_gmap``) decode them (``point_rows``). The server's set-based writer
(``tgsis.insert_chunk_rows``) and the faces are the references: the chunk rows
the same bit for bit (``array_send``), the points read back the same.
"""

from __future__ import annotations

import struct
from typing import Any

import numpy as np
import psycopg
import pytest

import tgsis
from tests.storage_data import tables_as_rows
from tests.test_gmap_chunk_upload import _bits, _maps
from tests.test_gmap_multidim import _class as _md_class
from tests.test_gmap_storage import _class as _gmap_class
from tgsis.db import _chunk_transfer, _transfer, multidim
from tgsis.db import features as F
from tgsis.db import gmaps as G
from tgsis.db._gmap_common import copy_rows
from tgsis.errors import DatabaseError, InvalidInputError

Conn = psycopg.Connection[Any]

POINTS = ("gmap_vertex", "md_vertex")
TABLES = ("gmap_dart", "gmap_alpha", "md_dart", "md_alpha", *POINTS)
#: doubles whose bits a text round trip or a comparison by = would lose: -0.0, a subnormal, a NaN with a payload
ODD = (-0.0, 5e-324, struct.unpack("<d", struct.pack("<Q", 0x7FF8_0000_0000_0ABC))[0])
#: the keys of each point table's chunk rows, their order
KEYS = {"md_vertex": "chunk, revision", "gmap_vertex": "timem, timet, chunk, revision"}


@pytest.fixture(autouse=True)
def _gmaps_as_rows(conn: Conn) -> None:
    """The G-map tables as rows at each test's start, whatever TGSIS_TEST_TIME_STORAGE made them."""
    tables_as_rows(conn, TABLES)


def _switch(conn: Conn, tables: tuple[str, ...] = TABLES) -> None:
    for table in tables:
        conn.execute("SELECT tgsis.store_in_chunks(%s)", (table,))
    conn.commit()


def _chunks(conn: Conn, table: str, geoid: int) -> list[tuple[Any, ...]]:
    """The object's chunk rows of a point table without the geoid, every value by its bits."""
    with conn.cursor(binary=True) as cursor:
        rows = cursor.execute(
            f"SELECT * FROM tgsis.{table}_chunk WHERE geoid = %s ORDER BY {KEYS[table]}", (geoid,)
        ).fetchall()
    return [tuple(_bits(v) for v in r[1:]) for r in rows]


def _face(conn: Conn, table: str, geoid: int, m: int) -> list[Any]:
    """The object's points read through the face (what the downloads read before), as bytes."""
    query = {
        "md_vertex": ("SELECT vrtxid, coordinate FROM tgsis.md_vertex WHERE geoid = {}", ["int8"], [0]),
        "gmap_vertex": (
            "SELECT timem, timet, nodeid, coordinate FROM tgsis.gmap_vertex WHERE geoid = {}",
            ["float8", "float8", "int8"],
            [0, 1, 2],
        ),
    }[table]
    return _as_bytes(copy_rows(conn, query[0], geoid, [*query[1], f"float8[{m}]"], query[2]))


def _as_bytes(columns: list[Any]) -> list[Any]:
    return [(str(c.dtype), c.shape, np.ascontiguousarray(c).tobytes()) for c in columns]


def _decoded(conn: Conn, table: str, geoid: int, m: int) -> list[Any]:
    got = _chunk_transfer.point_rows(conn, table, geoid, m)
    assert got is not None
    return _as_bytes([np.asarray(c, dtype=np.float64) if c.dtype.kind == "f" else c for c in got])


@pytest.mark.parametrize("versioned", ["no", "DEFAULT", "child"])
def test_uploads_encode_the_servers_point_chunks_and_downloads_decode_them(
    conn: Conn, monkeypatch: pytest.MonkeyPatch, versioned: str
) -> None:
    _gmap_class(conn)
    _md_class(conn)
    F.create_feature_class(conn, "plain", "GMAP", time_model="GMAP", cell_level=2)
    F.create_feature_class(conn, "flat", "GMAP", time_model="MULTIDIM", cell_level=2)
    if versioned != "no":
        tgsis.enable_feature_versioning(conn)
    _switch(conn)
    if versioned == "child":
        tgsis.create_version(conn, "e1")
        tgsis.goto_version(conn, "e1")

    def refused(*args: Any) -> int:
        raise AssertionError(f"tgsis.insert_chunk_rows called: {args[1]}")

    maps = _maps()
    with monkeypatch.context() as m:  # the client's path alone, points included
        m.setattr(_transfer, "insert_chunk_rows", refused)
        client = [G.insert_gmap(conn, fc, g, **kw) for fc, g, kw in maps]
        conn.commit()
    with monkeypatch.context() as m:  # the server's path
        m.setattr(G, "upload_rows", lambda *args: False)
        m.setattr(multidim, "upload_rows", lambda *args: False)
        server = [G.insert_gmap(conn, fc, g, **kw) for fc, g, kw in maps]
        conn.commit()
    tables = ["gmap_vertex", "gmap_vertex", "gmap_vertex", "md_vertex", "md_vertex"]
    written = 0
    for table, mine, theirs in zip(tables, client, server):
        assert _chunks(conn, table, mine) == _chunks(conn, table, theirs), table
        written += len(_chunks(conn, table, mine))
    assert written >= 9  # the large grid: 1,271 points in 2 chunks per instant, twice
    # downloads: the points decoded here, the same as through the face, every G-map the same as it went in
    for (fc, g, _kw), table, geoid in zip(maps, tables, client):
        m_ = int(g.embedding_dimension) if hasattr(g, "embedding_dimension") else 3
        fetch: Any = multidim.fetch_md_gmap if table == "md_vertex" else G.fetch_gmap
        assert _decoded(conn, table, geoid, m_) == _face(conn, table, geoid, m_)
        with monkeypatch.context() as m:  # the face's read, as before
            m.setattr(G, "point_rows", lambda *args: None)
            m.setattr(multidim, "point_rows", lambda *args: None)
            before = fetch(conn, fc, geoid)
        conn.rollback()
        got = fetch(conn, fc, geoid)
        conn.rollback()
        assert _same_fetch(got, before), (fc, table)


def _same_fetch(a: Any, b: Any) -> bool:
    """Two fetched G-maps equal, points by their bits."""
    if isinstance(a, tuple):
        return a[1] == b[1] and _same_fetch(a[0], b[0])
    if hasattr(a, "periods"):
        return len(a.periods) == len(b.periods) and all(
            np.asarray(p.times).tobytes() == np.asarray(q.times).tobytes()
            and _same_fetch(p.gmap, q.gmap)
            and np.array_equal(p.positions, q.positions)
            and np.asarray(p.positions).tobytes() == np.asarray(q.positions).tobytes()
            for p, q in zip(a.periods, b.periods)
        )
    return bool(
        np.array_equal(a.alpha, b.alpha)
        and np.array_equal(a.vertex, b.vertex)
        and np.asarray(a.points).tobytes() == np.asarray(b.points).tobytes()
    )


def _odd_columns(table: str, geoid: int) -> list[tuple[str, Any, str]]:
    """Points with holes (ids missing below a chunk's last and a chunk alone far off) and odd bits, m = 4 / 3."""
    rng = np.random.default_rng(7)
    ids = np.setdiff1d(np.arange(2100, dtype=np.int64), [0, 5, 1023, 1024, 2000])
    ids = np.concatenate([ids, [9000]])
    if table == "md_vertex":
        points = rng.normal(size=(len(ids), 4))
        points[:3, 1] = ODD
        points[-1] = [ODD[2], ODD[0], ODD[1], 1.0]
        return [
            ("geoid", np.full(len(ids), geoid), "int8"),
            ("vrtxid", ids, "int8"),
            ("coordinate", points, "float8[4]"),
        ]
    points = rng.normal(size=(2 * len(ids), 3))
    points[:3, 2] = ODD
    times = [
        (0.0, 0.1 + 0.2),
        (0.0, 1.0),
    ]  # (an instant whose bits a text round trip would change: 0.30000000000000004)
    return [
        ("geoid", np.full(2 * len(ids), geoid), "int8"),
        ("timem", np.repeat([t[0] for t in times], len(ids)), "float8"),
        ("timet", np.repeat([t[1] for t in times], len(ids)), "float8"),
        ("nodeid", np.concatenate([ids, ids]), "int8"),
        ("coordinate", points, "float8[3]"),
    ]


@pytest.mark.parametrize("versioned", [False, True])
@pytest.mark.parametrize("table", POINTS)
def test_odd_bits_and_holes_bit_for_bit_both_ways(conn: Conn, table: str, versioned: bool) -> None:
    if versioned:
        tgsis.enable_feature_versioning(conn)
    _switch(conn, (table,))
    m = 4 if table == "md_vertex" else 3
    storage = _transfer.Storage.of(conn)
    assert _chunk_transfer.upload_rows(conn, table, _odd_columns(table, 901), storage) is True
    _transfer.insert_chunk_rows(conn, table, _odd_columns(table, 902))
    conn.commit()
    assert _chunks(conn, table, 901) == _chunks(conn, table, 902)
    assert len(_chunks(conn, table, 901)) == (4 if table == "md_vertex" else 8)  # chunks 0, 1, 2 and 8 (per instant)
    assert _decoded(conn, table, 901, m) == _face(conn, table, 901, m)
    conn.rollback()
    # holes made by deletes, points moved to odd bits, through the face; in a child version when versioned
    if versioned:
        tgsis.create_version(conn, "e1")
        tgsis.goto_version(conn, "e1")
    idcol = "vrtxid" if table == "md_vertex" else "nodeid"
    conn.execute(f"DELETE FROM tgsis.{table} WHERE geoid = 901 AND {idcol} IN (1, 700, 9000)")
    conn.execute(
        f"UPDATE tgsis.{table} SET coordinate[1] = %s WHERE geoid = 901 AND {idcol} BETWEEN 10 AND 12", (ODD[2],)
    )
    conn.commit()
    assert _decoded(conn, table, 901, m) == _face(conn, table, 901, m)
    conn.rollback()
    if versioned:  # DEFAULT still sees what was uploaded
        tgsis.goto_version(conn, "DEFAULT")
        assert _decoded(conn, table, 901, m) == _face(conn, table, 901, m) == _face(conn, table, 902, m)
        conn.rollback()
    # an embedding other than the chunks' is refused by name
    with pytest.raises(DatabaseError, match="901 have \\[.\\] coordinates, not its embedding's 2"):
        _chunk_transfer.point_rows(conn, table, 901, 2)
    conn.rollback()


@pytest.mark.parametrize("table", POINTS)
def test_a_point_of_another_length_is_refused_by_name_and_nothing_is_written(conn: Conn, table: str) -> None:
    _switch(conn, (table,))
    storage = _transfer.Storage.of(conn)
    good = _odd_columns(table, 903)
    *keys, (name, points, wire) = good
    ragged = [list(p) for p in points]
    ragged[17] = ragged[17][:-1]
    for bad in (ragged, points[:, :-1], np.zeros((len(points), 0))):
        with pytest.raises(InvalidInputError, match="the points of object 903 are not all of its") as refused:
            _chunk_transfer.upload_rows(conn, table, [*keys, (name, bad, wire)], storage)
        assert "nothing was written" in (refused.value.detail or "")
        conn.rollback()
    with pytest.raises(InvalidInputError, match="float8\\[m\\], m >= 1"):
        _chunk_transfer.upload_rows(conn, table, [*keys, (name, np.zeros((len(points), 0)), "float8[0]")], storage)
    conn.rollback()
    assert conn.execute(f"SELECT count(*) FROM tgsis.{table}_chunk WHERE geoid = 903").fetchone() == (0,)
    assert _chunk_transfer.upload_rows(conn, table, good, storage) is True  # the good one goes
    conn.commit()
    assert conn.execute(f"SELECT count(*) > 0 FROM tgsis.{table}_chunk WHERE geoid = 903").fetchone() == (True,)


def test_a_role_granted_the_face_alone_reads_through_it(db_dsn: str, conn: Conn) -> None:
    """Without SELECT on the chunk table the download reads the face (decoded by the server), as before."""
    from tests.roles import login_roles

    _switch(conn, ("md_vertex",))
    _transfer.insert_chunk_rows(conn, "md_vertex", _odd_columns("md_vertex", 904))
    conn.execute("REVOKE SELECT ON tgsis.md_vertex_chunk FROM tgsis_reader")  # (this test's database only)
    conn.commit()
    expected = _face(conn, "md_vertex", 904, 4)
    conn.rollback()
    with login_roles(db_dsn, {"reader": "tgsis_reader"}) as made:
        reader = made.connect("reader")
        assert reader.execute("SELECT has_table_privilege('tgsis.md_vertex_chunk', 'SELECT')").fetchone() == (False,)
        assert _chunk_transfer.point_rows(reader, "md_vertex", 904, 4) is None
        assert _face(reader, "md_vertex", 904, 4) == expected


def test_points_of_one_coordinate_are_2d_arrays_as_the_servers(conn: Conn) -> None:
    """m = 1 (a G-map on a line): slots x 1, not a one-dimensional array."""
    _switch(conn, ("md_vertex",))
    ids = np.array([0, 1, 3, 1030], dtype=np.int64)
    points = np.array([[ODD[0]], [ODD[1]], [ODD[2]], [2.5]])

    def columns(geoid: int) -> list[tuple[str, Any, str]]:
        return [("geoid", np.full(4, geoid), "int8"), ("vrtxid", ids, "int8"), ("coordinate", points, "float8[1]")]

    assert _chunk_transfer.upload_rows(conn, "md_vertex", columns(905), _transfer.Storage.of(conn)) is True
    _transfer.insert_chunk_rows(conn, "md_vertex", columns(906))
    conn.commit()
    assert _chunks(conn, "md_vertex", 905) == _chunks(conn, "md_vertex", 906)
    assert conn.execute(
        "SELECT array_agg(array_ndims(coordinate) ORDER BY chunk) FROM tgsis.md_vertex_chunk WHERE geoid = 905"
    ).fetchone() == ([2, 2],)
    assert _decoded(conn, "md_vertex", 905, 1) == _face(conn, "md_vertex", 905, 1) == _face(conn, "md_vertex", 906, 1)
