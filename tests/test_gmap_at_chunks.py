"""``tgsis.db.gmaps.gmap_at`` (model 4's snapshot at t in Python) reads the chunk arrays through the client codec.

docs/storage.md, "G-maps (models 4 and 5)": with ``gmap_dart``, ``gmap_alpha``
and ``gmap_vertex`` in chunks, the snapshot decodes the period's chunks in
numpy (``tgsis.db._chunk_transfer.object_rows`` / ``instant_rows``), as
``fetch_feature`` reads model 1, instead of the faces' rows; the answer is the
rows' bit for bit, in every version, and a role granted the faces only reads
them as before.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import psycopg
import pytest

import tgsis
from tests.storage_data import GMAP_TABLES, recorded_copies, switch_tables, tables_as_rows
from tests.test_gmap_chunks import ASKED, _store
from tgsis.db import gmaps as G

Conn = psycopg.Connection[Any]

#: model 4's chunked tables, darts and involutions with the points
TABLES = ("gmap_dart", "gmap_alpha", "gmap_vertex")
#: doubles a comparison by = would not tell apart: -0.0 and 0.0
ZERO = -0.0


@pytest.fixture(autouse=True)
def _gmaps_as_rows(conn: Conn) -> None:
    """The model-4 tables as rows at each test's start, whatever TGSIS_TEST_TIME_STORAGE made them."""
    tables_as_rows(conn, GMAP_TABLES)


def _bits(conn: Conn, g4: int) -> dict[float, Any]:
    """Python's snapshot at each asked t, every array by its bytes (a -0.0 is not a 0.0 here)."""
    found: dict[float, Any] = {}
    for t in ASKED:
        got = G.gmap_at(conn, g4, t)
        found[t] = (
            None
            if got is None
            else (
                got.alpha.dtype.str,
                got.alpha.tobytes(),
                got.vertex.tobytes(),
                got.points.dtype.str,
                got.points.shape,
                got.points.tobytes(),
                {
                    level: {k: np.asarray(v).tobytes() for k, v in sorted(values.items())}
                    for level, values in sorted(got.cell_properties.items())
                },
            )
        )
    conn.rollback()
    return found


@pytest.mark.parametrize("versioned", [False, True])
def test_gmap_at_decodes_the_chunks_and_answers_as_the_rows_bit_for_bit(
    conn: Conn, versioned: bool, monkeypatch: pytest.MonkeyPatch
) -> None:
    g4, _ = _store(conn, versioned)
    # a -0.0 where the two instants agree (not mixed: kept as stored) and a -0.0 the mix of a period meets
    conn.execute(
        "UPDATE tgsis.gmap_vertex SET coordinate[2] = %s WHERE geoid = %s AND nodeid = 0 AND timet IN (0.0, 1.0)",
        (ZERO, g4),
    )
    conn.commit()
    versions: tuple[str, ...] = ("DEFAULT",)
    if versioned:  # a version whose psql user moves a point and frees nothing
        tgsis.create_version(conn, "e1")
        conn.commit()
        with tgsis.in_version(conn, "e1"):
            conn.execute(
                "UPDATE tgsis.gmap_vertex SET coordinate[3] = coordinate[3] + 0.25 WHERE geoid = %s AND nodeid = 1",
                (g4,),
            )
        conn.commit()
        versions = ("DEFAULT", "e1")

    def everywhere() -> dict[str, Any]:
        found = {}
        for version in versions:
            with tgsis.in_version(conn, version):
                found[version] = _bits(conn, g4)
        return found

    before = everywhere()
    if versioned:
        assert before["e1"] != before["DEFAULT"]
    switch_tables(conn, TABLES, "chunks")
    seen = recorded_copies(monkeypatch, "tgsis.db.gmaps")
    assert everywhere() == before
    # the darts, involutions and points came from the chunks: no statement read their faces
    assert [q for q in seen if any(f"tgsis.{t} " in q for t in TABLES)] == []
    switch_tables(conn, TABLES, "rows")
    assert everywhere() == before
    assert any("tgsis.gmap_dart " in q for q in seen)


def test_a_role_granted_the_faces_only_reads_them_with_the_same_answer(
    conn: Conn, db_dsn: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    g4, _ = _store(conn, False)
    before = _bits(conn, g4)
    switch_tables(conn, TABLES, "chunks")
    role = "gmap_at_faces_only"
    conn.execute(f"DROP ROLE IF EXISTS {role}")
    conn.execute(f"CREATE ROLE {role} LOGIN")
    conn.execute(f"GRANT USAGE ON SCHEMA tgsis TO {role}")
    conn.execute(f"GRANT SELECT ON ALL TABLES IN SCHEMA tgsis TO {role}")
    conn.execute(f"GRANT SELECT ON ALL TABLES IN SCHEMA public TO {role}")
    conn.execute(f"REVOKE SELECT ON {', '.join(f'tgsis.{t}_chunk' for t in TABLES)} FROM {role}")
    conn.commit()
    seen = recorded_copies(monkeypatch, "tgsis.db.gmaps")
    try:
        with psycopg.connect(db_dsn, user=role) as other:
            assert _bits(other, g4) == before
        assert all(any(f"tgsis.{t} " in q for q in seen) for t in TABLES)
    finally:
        conn.rollback()
        conn.execute(f"DROP OWNED BY {role}")
        conn.execute(f"DROP ROLE {role}")
        conn.commit()
