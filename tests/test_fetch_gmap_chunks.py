"""``tgsis.db.gmaps.fetch_gmap`` (a whole model-4 G-map) reads the chunk arrays through the client codec.

docs/storage.md, "G-maps (models 4 and 5)": with ``gmap_dart``, ``gmap_alpha``
and ``gmap_vertex`` in chunks, ``fetch_gmap`` decodes the object's darts,
involutions (``tgsis.db._chunk_transfer.object_rows`` / ``instant_rows``) and
points (``point_rows``) in numpy, as ``gmap_at`` reads a period's, instead of
the faces' rows; the rows it builds the G-map from are the faces' bit for bit
(dtypes, order, a NULL cell as -1), in every version, and a role granted the
faces only reads them as before.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import psycopg
import pytest

import tgsis
from tests.storage_data import GMAP_TABLES, recorded_copies, switch_tables, tables_as_rows
from tests.test_gmap_chunks import _store
from tgsis.db import gmaps as G
from tgsis.db._transfer import consistent_read
from tgsis.errors import InvalidGMapError

Conn = psycopg.Connection[Any]

#: model 4's chunked tables: darts and involutions with the points
TABLES = ("gmap_dart", "gmap_alpha", "gmap_vertex")


@pytest.fixture(autouse=True)
def _gmaps_as_rows(conn: Conn) -> None:
    """The model-4 tables as rows at each test's start, whatever TGSIS_TEST_TIME_STORAGE made them."""
    tables_as_rows(conn, GMAP_TABLES)


def _arrays(value: Any) -> Any:
    """``value`` with every array replaced by its dtype, shape and bytes (a -0.0 is not a 0.0 here)."""
    if isinstance(value, np.ndarray):
        return (value.dtype.str, value.shape, value.tobytes())
    if isinstance(value, (list, tuple)):
        return tuple(_arrays(v) for v in value)
    if isinstance(value, dict):
        return {k: _arrays(v) for k, v in sorted(value.items())}
    return value


def _bits(conn: Conn, g4: int, monkeypatch: pytest.MonkeyPatch) -> Any:
    """The rows ``fetch_gmap`` builds the G-map from (its read's answer) and the G-map it returns, by their bits."""
    read: list[Any] = []
    original = consistent_read

    def recording(conn: Conn, name: str, reader: Any) -> Any:
        got = original(conn, name, reader)
        read.append(got)
        return got

    with monkeypatch.context() as m:
        m.setattr("tgsis.db.gmaps.consistent_read", recording)
        try:
            got = G.fetch_gmap(conn, "blocks", g4)
        except InvalidGMapError as error:  # rows that make no G-map: what was read, and the error
            conn.rollback()
            return _arrays(read[0]), str(error)
    conn.rollback()
    periods = [
        (
            _arrays(p.times),
            _arrays(p.gmap.alpha),
            _arrays(p.gmap.vertex),
            _arrays(p.positions),
            p.level,
            _arrays(dict(p.cell_values)),
        )
        for p in got.periods
    ]
    return _arrays(read[0]), periods, got.alive, got.name


@pytest.mark.parametrize("versioned", [False, True])
def test_fetch_gmap_decodes_the_chunks_and_reads_as_the_rows_bit_for_bit(
    conn: Conn, versioned: bool, monkeypatch: pytest.MonkeyPatch
) -> None:
    g4, _ = _store(conn, versioned)
    # a dart without a cell (NULL: -1 in the rows read) and a -0.0 coordinate kept as stored
    conn.execute("UPDATE tgsis.gmap_dart SET acellid = NULL WHERE geoid = %s AND dartid = 1", (g4,))
    conn.execute(
        "UPDATE tgsis.gmap_vertex SET coordinate[2] = %s WHERE geoid = %s AND nodeid = 0 AND timet = 0.0",
        (-0.0, g4),
    )
    conn.commit()
    versions: tuple[str, ...] = ("DEFAULT",)
    if versioned:  # a version whose psql user moves a point and takes another dart's cell away
        tgsis.create_version(conn, "e1")
        conn.commit()
        with tgsis.in_version(conn, "e1"):
            conn.execute(
                "UPDATE tgsis.gmap_vertex SET coordinate[3] = coordinate[3] + 0.25 WHERE geoid = %s AND nodeid = 1",
                (g4,),
            )
            conn.execute("UPDATE tgsis.gmap_dart SET acellid = NULL WHERE geoid = %s AND dartid = 2", (g4,))
        conn.commit()
        versions = ("DEFAULT", "e1")

    def everywhere() -> dict[str, Any]:
        found = {}
        for version in versions:
            with tgsis.in_version(conn, version):
                found[version] = _bits(conn, g4, monkeypatch)
        return found

    before = everywhere()
    assert bool(np.any(np.frombuffer(before["DEFAULT"][0][7][3][2], dtype=np.int64) == -1))  # the NULL cell came as -1
    if versioned:
        assert before["e1"] != before["DEFAULT"]
    switch_tables(conn, TABLES, "chunks")
    seen = recorded_copies(monkeypatch, "tgsis.db._gmap_common", "tgsis.db.gmaps")
    assert everywhere() == before
    # the darts, involutions and points came from the chunks: no statement read their faces
    assert [q for q in seen if any(f"tgsis.{t} " in q for t in TABLES)] == []
    switch_tables(conn, TABLES, "rows")
    assert everywhere() == before
    assert all(any(f"tgsis.{t} " in q for q in seen) for t in TABLES)


def test_a_role_granted_the_faces_only_reads_them_with_the_same_answer(
    conn: Conn, db_dsn: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    g4, _ = _store(conn, False)
    before = _bits(conn, g4, monkeypatch)
    switch_tables(conn, TABLES, "chunks")
    role = "fetch_gmap_faces_only"
    conn.execute(f"DROP ROLE IF EXISTS {role}")
    conn.execute(f"CREATE ROLE {role} LOGIN")
    conn.execute(f"GRANT USAGE ON SCHEMA tgsis TO {role}")
    conn.execute(f"GRANT SELECT ON ALL TABLES IN SCHEMA tgsis TO {role}")
    conn.execute(f"GRANT SELECT ON ALL TABLES IN SCHEMA public TO {role}")
    conn.execute(f"REVOKE SELECT ON {', '.join(f'tgsis.{t}_chunk' for t in TABLES)} FROM {role}")
    conn.commit()
    seen = recorded_copies(monkeypatch, "tgsis.db._gmap_common", "tgsis.db.gmaps")
    try:
        with psycopg.connect(db_dsn, user=role) as other:
            assert _bits(other, g4, monkeypatch) == before
        assert all(any(f"tgsis.{t} " in q for q in seen) for t in TABLES)
    finally:
        conn.rollback()
        conn.execute(f"DROP OWNED BY {role}")
        conn.execute(f"DROP ROLE {role}")
        conn.commit()


def test_involutions_missing_at_a_level_are_read_as_the_rows_in_key_order(
    conn: Conn, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Levels that do not hold the same darts: the decoded rows sorted by (dartid, level) as the face's, the same error."""
    g4, _ = _store(conn, False)
    conn.execute("DELETE FROM tgsis.gmap_alpha WHERE geoid = %s AND dartid = 3 AND level = 1", (g4,))
    conn.commit()
    before = _bits(conn, g4, monkeypatch)
    assert isinstance(before[1], str) and "alpha_1" in before[1]
    switch_tables(conn, TABLES, "chunks")
    seen = recorded_copies(monkeypatch, "tgsis.db._gmap_common", "tgsis.db.gmaps")
    assert _bits(conn, g4, monkeypatch) == before
    assert [q for q in seen if "tgsis.gmap_alpha " in q] == []
