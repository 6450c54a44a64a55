"""The client's upload of G-map darts and involutions stored in chunks: chunks encoded in numpy, one binary COPY.

``insert_gmap`` (model 4) and ``insert_md_gmap`` (model 5) write ``gmap_dart`` /
``md_dart`` (keyed ``(geoid, chunk)``) and ``gmap_alpha`` / ``md_alpha``
(``(geoid, level, chunk)``) stored in chunks through
``tgsis.db._chunk_transfer.upload_rows``: the rows are grouped by their keys
before ``chunk``, encoded by :mod:`tgsis._chunks` and COPied in binary into
the chunk tables (docs/storage.md, "G-maps (models 4 and 5)"). The server's
set-based path (``tgsis.insert_chunk_rows``, what the upload did before and
still does when it declines) is the reference: the chunk rows of both are the
same, bit for bit (tests/test_gmap_chunks.py shows that those answer as the
rows do).
"""

from __future__ import annotations

import struct
from typing import Any

import numpy as np
import psycopg
import pytest

import tgsis
from tests.gmaps_shapes import grid
from tests.storage_data import tables_as_rows
from tests.test_gmap_chunks import TABLES, _switch
from tests.test_gmap_multidim import _class as _md_class
from tests.test_gmap_multidim import _interpretations
from tests.test_gmap_storage import _class as _gmap_class
from tests.test_gmap_storage import _evolving
from tgsis import gmaps
from tgsis.db import _chunk_transfer, _transfer, multidim
from tgsis.db import features as F
from tgsis.db import gmaps as G
from tgsis.db._gmap_common import orientation_signs
from tgsis.errors import InvalidInputError

Conn = psycopg.Connection[Any]


@pytest.fixture(autouse=True)
def _gmaps_as_rows(conn: Conn) -> None:
    """The G-map tables as rows at each test's start, whatever TGSIS_TEST_TIME_STORAGE made them."""
    tables_as_rows(conn, TABLES)


def _moebius() -> gmaps.GMap:
    """A Möbius strip of 8 triangles: not orientable, so its darts' ``positive`` is NULL (left out of the upload)."""
    top, bottom = [[i, 0.0, 1.0] for i in range(4)], [[i, 0.0, 0.0] for i in range(4)]
    triangles = [[i, 4 + i, 5 + i] for i in range(3)] + [[i, 5 + i, 1 + i] for i in range(3)]
    triangles += [[3, 7, 0], [3, 0, 4]]  # the last square glued back with a twist: top 3 to bottom 0
    g = gmaps.GMap.from_triangles(np.array(top + bottom), np.array(triangles))
    assert orientation_signs(g) is None
    return g


def _maps() -> list[tuple[str, Any, dict[str, Any]]]:
    """(class, G-map, keywords) of every shape the upload meets."""
    vertices, triangles = grid(40, 30)  # 14,400 darts: 15 chunks, the last one partial
    large = gmaps.GMap.from_triangles(vertices, triangles)
    return [
        ("blocks", _evolving(), {"name": "rising"}),  # model 4, two periods, a cell level (acellid)
        ("plain", large, {"name": "large"}),
        ("plain", _moebius(), {"name": "twisted"}),  # not orientable (positive NULL)
        ("knowledge", _interpretations()[2], {"name": "H1", "axes": ["x", "y", "z", "knowledge"]}),  # model 5
        ("flat", large, {"name": "flat", "axes": ["x", "y", "z"]}),
    ]


def _chunk_rows(conn: Conn, geoids: list[int]) -> dict[str, list[tuple[Any, ...]]]:
    """Every chunk row of the objects, in binary (the arrays' bits), without the geoid: per table."""
    got = {}
    for table in TABLES:
        with conn.cursor(binary=True) as cursor:
            rows = cursor.execute(
                f"SELECT array_position(%s::int8[], geoid), * FROM tgsis.{table}_chunk WHERE geoid = ANY (%s) "
                "ORDER BY 1, 3, 4",
                (geoids, geoids),
            ).fetchall()
        got[table] = [(r[0], *(_bits(v) for v in r[2:])) for r in rows]
    return got


def _bits(value: Any) -> Any:
    """A float as its 64 bits (NaN payloads and -0 compared, NaN equal to itself), lists element by element."""
    if isinstance(value, list):
        return [_bits(v) for v in value]
    return ("f8", struct.pack(">d", value)) if isinstance(value, float) else value


def _store_all(conn: Conn) -> list[int]:
    return [G.insert_gmap(conn, fc, g, **kw) for fc, g, kw in _maps()]


@pytest.mark.parametrize("versioned", ["no", "DEFAULT", "child"])
def test_the_client_upload_writes_the_server_paths_chunks_bit_for_bit(
    conn: Conn, monkeypatch: pytest.MonkeyPatch, versioned: str
) -> None:
    _gmap_class(conn)
    _md_class(conn)
    F.create_feature_class(conn, "plain", "GMAP", time_model="GMAP", cell_level=2)  # no cell property
    F.create_feature_class(conn, "flat", "GMAP", time_model="MULTIDIM", cell_level=2)
    if versioned != "no":
        tgsis.enable_feature_versioning(conn)
    _switch(conn, "chunks")
    if versioned == "child":  # written in the child's working revision, as the server path writes them
        tgsis.create_version(conn, "e1")
        tgsis.goto_version(conn, "e1")

    def refused(*args: Any) -> int:  # (the points too, in chunks under TGSIS_TEST_TIME_STORAGE=chunks: plan M, Q)
        raise AssertionError(f"tgsis.insert_chunk_rows called: {args[1]}")

    with monkeypatch.context() as m:  # the client's path alone: the server's set-based writer is never called
        m.setattr(_transfer, "insert_chunk_rows", refused)
        client = _store_all(conn)
        conn.commit()
    with monkeypatch.context() as m:  # the server's path: the upload declines
        m.setattr(G, "upload_rows", lambda *args: False)  # (insert_gmap's name for it)
        m.setattr(multidim, "upload_rows", lambda *args: False)  # (insert_md_gmap's)
        server = _store_all(conn)
        conn.commit()
    mine, theirs = _chunk_rows(conn, client), _chunk_rows(conn, server)
    assert {t: len(r) for t, r in mine.items()} == {t: len(r) for t, r in theirs.items()}
    assert sum(len(r) for r in mine.values()) > 40  # several chunks per table and level
    assert mine == theirs
    # a NULL orientation: an array of NULLs, as the server writes a column left out
    assert conn.execute(
        "SELECT count(*) FROM tgsis.gmap_dart WHERE geoid = %s AND positive IS NULL", (client[2],)
    ).fetchone() == (48,)
    if versioned == "child":
        revisions = " UNION ".join(f"SELECT revision FROM tgsis.{t}_chunk WHERE geoid = ANY (%(g)s)" for t in TABLES)
        working = "SELECT workingrevision FROM tgsis.versions WHERE name = 'e1'"
        assert conn.execute(revisions, {"g": client}).fetchall() == conn.execute(working).fetchall()
    if versioned != "no":  # noted as changed in the working revision, as the server path notes them
        noted = "SELECT count(*) FROM tgsis.revision_objects WHERE tablename = ANY (%s) AND objectkey = ANY (%s)"
        tables = list(TABLES)
        assert (
            conn.execute(noted, (tables, [str(g) for g in client])).fetchone()
            == conn.execute(noted, (tables, [str(g) for g in server])).fetchone()
        )
    back = G.fetch_gmap(conn, "plain", client[1]).at(0.0)
    assert back is not None and back.same_as(_maps()[1][1])
    assert conn.execute("SELECT count(*) FROM tgsis.gmap_check(%s)", (client[0],)).fetchone() == (0,)
    assert conn.execute("SELECT count(*) FROM tgsis.md_check(%s)", (client[3],)).fetchone() == (0,)


def test_an_editor_uploads_through_the_stage_as_the_owner_does(db_dsn: str, conn: Conn) -> None:
    """A role that row-level security applies to COPies into a temporary table first: the same chunks."""
    from tests.roles import login_roles

    _gmap_class(conn)
    _switch(conn, "chunks")
    owner = G.insert_gmap(conn, "blocks", _evolving(), name="rising")
    conn.commit()
    with login_roles(db_dsn, {"ed": "tgsis_editor"}) as made:
        ed = made.connect("ed")
        staged = ed.execute("SELECT row_security_active('tgsis.gmap_dart_chunk')").fetchone()
        theirs = G.insert_gmap(ed, "blocks", _evolving(), name="rising")
        ed.commit()
    mine = _chunk_rows(conn, [owner])
    assert mine == {t: [(1, *r[1:]) for r in rows] for t, rows in _chunk_rows(conn, [theirs]).items()}
    assert staged == (True,)


def test_bad_uploads_are_refused_and_a_second_one_declines(conn: Conn) -> None:
    _gmap_class(conn)
    _switch(conn, "chunks")
    geoid = G.insert_gmap(conn, "blocks", _evolving(), name="rising")
    conn.commit()
    before = _chunk_rows(conn, [geoid])
    storage = _transfer.Storage.of(conn)
    n = 5
    good = [
        ("geoid", np.full(n, geoid + 1000), "int8"),
        ("dartid", np.arange(n, dtype=np.int64), "int8"),
        ("timem", np.zeros(n), "float8"),
        ("nodeid", np.arange(n, dtype=np.int64), "int8"),
    ]
    for bad, message in [
        (good[:3], "once each"),  # the point left out (it may not be NULL)
        ([*good, ("extra", np.zeros(n), "float8")], "once each"),  # a column the table has not
        ([*good[:3], ("nodeid", np.arange(n + 1, dtype=np.int64), "int8")], "one value per row"),
        ([*good[:3], ("nodeid", -np.arange(1, n + 1, dtype=np.int64), "int8")], ">= 0"),
        ([*good, ("positive", np.zeros(n), "bool")], "must be bool"),  # floats as booleans: no truthiness
    ]:
        with pytest.raises(InvalidInputError, match=message):
            _chunk_transfer.upload_rows(conn, "gmap_dart", bad, storage)
        conn.rollback()
    # an object with chunks already: declined, nothing written (the caller takes the server's path)
    again = [(name, np.full(n, geoid) if name == "geoid" else v, w) for name, v, w in good]
    assert _chunk_transfer.upload_rows(conn, "gmap_dart", again, storage) is False
    conn.commit()
    assert _chunk_rows(conn, [geoid]) == before
    # the server's path then answers as the rows would: the key is there already
    with pytest.raises(psycopg.errors.UniqueViolation):
        storage.copy(conn, "tgsis", "gmap_dart", again)
    conn.rollback()
    assert _chunk_rows(conn, [geoid]) == before
    # a negative level: declined, so that the server's path applies the row table's CHECK (level >= 0)
    alpha = [
        ("geoid", np.full(2, geoid + 1000), "int8"),
        ("level", np.array([-1, -1], dtype=np.int16), "int2"),
        ("dartid", np.array([0, 1]), "int8"),
        ("dartid2", np.array([1, 0]), "int8"),
    ]
    assert _chunk_transfer.upload_rows(conn, "gmap_alpha", alpha, storage) is False
    with pytest.raises(psycopg.errors.CheckViolation):
        storage.copy(conn, "tgsis", "gmap_alpha", alpha)
    conn.rollback()
    with pytest.raises(InvalidInputError, match="are integers"):
        _chunk_transfer.upload_rows(
            conn, "gmap_alpha", [(n, v * 1.0, w) if n == "level" else (n, v, w) for n, v, w in alpha], storage
        )
    conn.rollback()
    assert conn.execute("SELECT count(*) FROM tgsis.gmap_alpha_chunk WHERE geoid = %s", (geoid + 1000,)).fetchone() == (
        0,
    )


@pytest.mark.parametrize("versioned", [False, True])
def test_left_out_columns_and_holes_are_written_as_the_server_writes_them(conn: Conn, versioned: bool) -> None:
    """Rows no G-map upload makes today but the upload takes: ids with holes, ``acellid`` and ``positive`` left out
    (NULL), a point far from the chunk's others (its ref stored wide), NaN payloads and -0 in ``timem``."""
    _gmap_class(conn)
    if versioned:
        tgsis.enable_feature_versioning(conn)
    _switch(conn, "chunks")
    ids = np.array([5, 0, 1, 2, 2000, 1030], dtype=np.int64)
    timem = np.array([0.0, -0.0, 1.5, np.nan, 2.0, 3.0])
    timem.view(np.int64)[3] = 0x7FF8_0000_0000_0ABC  # a NaN payload
    nodes = np.array([3, 0, 1, 2, 2**40, 7], dtype=np.int64)
    storage = _transfer.Storage.of(conn)

    def columns(geoid: int, *extra: tuple[str, Any, str]) -> list[tuple[str, Any, str]]:
        return [
            ("geoid", np.full(len(ids), geoid), "int8"),
            ("dartid", ids, "int8"),
            ("timem", timem, "float8"),
            ("nodeid", nodes, "int8"),
            *extra,
        ]

    cells = ("acellid", np.array([1, 2, 3, 4, 5, 6]), "int8")
    signs = ("positive", np.array([True, False, True, True, False, False]), "bool")
    cases = [(), (cells,), (signs,), (cells, signs)]
    client, server = [], []
    for k, extra in enumerate(cases):
        assert _chunk_transfer.upload_rows(conn, "gmap_dart", columns(900 + k, *extra), storage) is True
        storage.copy(conn, "tgsis", "gmap_dart", columns(950 + k, *extra))
        client.append(900 + k)
        server.append(950 + k)
    conn.commit()
    mine, theirs = _chunk_rows(conn, client)["gmap_dart"], _chunk_rows(conn, server)["gmap_dart"]
    assert len(mine) == 2 * len(cases)  # ids 0..5 and 1030, 2000
    assert mine == theirs
    assert conn.execute(
        "SELECT count(*) FROM tgsis.gmap_dart_chunk WHERE geoid = 900 AND holes IS NOT NULL AND nodeid_wide IS NOT NULL"
    ).fetchone() == (1,)
