"""The check of a G-map (``tgsis.gmap_check`` / ``md_check``) reading the darts' chunk arrays (plan N, G).

docs/storage.md, "G-maps (models 4 and 5)": with ``gmap_dart`` / ``gmap_alpha`` (``md_dart`` /
``md_alpha``) stored in chunks, ``tgsis.gmap_conditions_hold`` reads the chunk tables as the caller
(``tgsis.gmap_chunk_arrays_sql``: a row per chunk version and level, its vbase beside it) instead of the
faces. Each test compares its answer with the keyed joins over the faces (``gmap_conditions_by_rows``, the
reference) on valid maps and on each kind of break the checks name, and the whole ``gmap_check`` /
``md_check`` with what the same map answers as rows.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import psycopg
import pytest
from psycopg import sql

import tgsis
from tests.storage_data import switch_tables, tables_as_rows
from tests.test_gmap_check import _evolving
from tests.test_gmap_check import _holds as _holds_as_read
from tgsis import gmaps
from tgsis.db import features as F
from tgsis.db import gmaps as G

from .gmaps_shapes import block_tetrahedra

Conn = psycopg.Connection[Any]

TABLES = ("gmap_dart", "gmap_alpha", "md_dart", "md_alpha")
MODEL4 = ("tgsis.gmap_dart", "tgsis.gmap_alpha", "nodeid", "timem")
MODEL5 = ("tgsis.md_dart", "tgsis.md_alpha", "vrtxid", None)


@pytest.fixture(autouse=True)
def _gmaps_as_rows(conn: Conn) -> None:
    """The G-map tables as rows at each test's start, whatever TGSIS_TEST_TIME_STORAGE made them."""
    tables_as_rows(conn, TABLES)


def _switch(conn: Conn, to: str) -> None:
    switch_tables(conn, TABLES, to)


def _store(conn: Conn) -> tuple[int, int]:
    """A model-4 map of two periods (1,152 + 144 darts: two chunks, the second one part full) and a model-5 one
    of 1,152 darts."""
    fc4 = F.create_feature_class(conn, "blocks", "GMAP", time_model="GMAP", cell_level=3)
    g4 = F.insert_feature(conn, fc4, _evolving(), tolerance=100.0)
    fc5 = F.create_feature_class(conn, "knowledge", "GMAP", time_model="MULTIDIM", cell_level=3)
    solid = gmaps.GMap.from_tetrahedra(*block_tetrahedra(2))
    points = np.column_stack([solid.points, np.arange(solid.n_points) % 3])
    g5 = G.insert_gmap(conn, fc5, gmaps.GMap(solid.alpha, solid.vertex, points), axes=["x", "y", "z", "k"])
    conn.commit()
    return g4, g5


def _answers(conn: Conn, geoid: int, tables: tuple[str, str, str, str | None]) -> tuple[Any, ...]:
    """What the one-statement proof, gmap_conditions and the keyed joins (the reference) say."""
    args = (geoid, 3, *tables)
    fast = conn.execute("SELECT problem, count, darts FROM tgsis.gmap_conditions(%s, %s, %s, %s, %s, %s)", args)
    reference = conn.execute(
        "SELECT problem, count, darts FROM tgsis.gmap_conditions_by_rows(%s, %s, %s, %s, %s, %s)", args
    )
    return _holds_as_read(conn, geoid, 3, tables), fast.fetchall(), reference.fetchall()


def _chunk_path(conn: Conn, tables: tuple[str, str, str, str | None]) -> bool:
    row = conn.execute("SELECT arrays IS NOT NULL FROM tgsis.gmap_chunk_arrays_sql(%s, %s, %s, %s)", tables).fetchone()
    return row is not None and bool(row[0])


def test_a_valid_map_is_proved_on_the_chunk_arrays_and_answers_as_rows(conn: Conn) -> None:
    g4, g5 = _store(conn)
    on_rows = [
        conn.execute(f"SELECT * FROM tgsis.{f}(%s)", (g,)).fetchall() for f, g in (("gmap_check", g4), ("md_check", g5))
    ]
    assert not _chunk_path(conn, MODEL4) and not _chunk_path(conn, MODEL5)
    _switch(conn, "chunks")
    assert _chunk_path(conn, MODEL4) and _chunk_path(conn, MODEL5)
    for geoid, tables in ((g4, MODEL4), (g5, MODEL5)):
        assert _answers(conn, geoid, tables) == (True, [], [])
    on_chunks = [
        conn.execute(f"SELECT * FROM tgsis.{f}(%s)", (g,)).fetchall() for f, g in (("gmap_check", g4), ("md_check", g5))
    ]
    assert on_chunks == on_rows == [[], []]
    _switch(conn, "rows")
    assert not _chunk_path(conn, MODEL4)


# Breaks through the faces: the shape kept (the tests find them) and the shape broken (the chunk rows' counts do).
BREAKS = {
    "non-involution": "UPDATE {alpha} SET dartid2 = dartid2 + 1 WHERE geoid = %(g)s AND level = 0 AND dartid = 8",
    "fixed point below n": "UPDATE {alpha} SET dartid2 = dartid WHERE geoid = %(g)s AND level = 1 AND dartid IN (30, 1100)",
    "composition": (
        "UPDATE {alpha} a SET dartid2 = a.dartid WHERE geoid = %(g)s AND level = 3 "
        "AND a.dartid IN (SELECT b.dartid FROM {alpha} b WHERE b.geoid = %(g)s AND b.level = 3 AND b.dartid2 <> b.dartid "
        "ORDER BY b.dartid LIMIT 1) OR geoid = %(g)s AND level = 3 AND a.dartid IN (SELECT b.dartid2 FROM {alpha} b "
        "WHERE b.geoid = %(g)s AND b.level = 3 AND b.dartid2 <> b.dartid ORDER BY b.dartid LIMIT 1)"
    ),
    "an image out of range": "UPDATE {alpha} SET dartid2 = 100000 WHERE geoid = %(g)s AND level = 2 AND dartid = 1030",
    "a point moved": "UPDATE {dart} SET {point} = {point} + 1 WHERE geoid = %(g)s AND dartid IN (0, 1151)",
    "an involution row missing": "DELETE FROM {alpha} WHERE geoid = %(g)s AND level = 1 AND dartid = 1040",
    "a level beyond n": "INSERT INTO {alpha} (geoid, level, dartid, dartid2) VALUES (%(g)s, 4, 5, 5)",
    "a row of a dart that is not": "INSERT INTO {alpha} (geoid, level, dartid, dartid2) VALUES (%(g)s, 0, 1300, 1300)",
    "the last dart gone": "DELETE FROM {dart} WHERE geoid = %(g)s AND dartid = (SELECT max(dartid) FROM {dart} WHERE geoid = %(g)s)",
}


@pytest.mark.parametrize("model", ["GMAP", "MULTIDIM"])
@pytest.mark.parametrize("breakage", list(BREAKS))
def test_each_break_is_reported_on_the_chunk_arrays_as_by_the_keyed_joins(
    conn: Conn, model: str, breakage: str
) -> None:
    g4, g5 = _store(conn)
    geoid, tables = (g4, MODEL4) if model == "GMAP" else (g5, MODEL5)
    statement = BREAKS[breakage].format(alpha=tables[1], dart=tables[0], point=tables[2])
    # the rows' answer first (the same break on the rows twin), then on chunks from the same map
    conn.execute(statement, {"g": geoid})
    as_rows = _answers(conn, geoid, tables)
    conn.rollback()
    _switch(conn, "chunks")
    assert _answers(conn, geoid, tables) == (True, [], [])
    conn.execute(statement, {"g": geoid})
    holds, fast, reference = _answers(conn, geoid, tables)
    assert reference, "the break went unnoticed"
    assert not holds
    assert fast == reference
    assert (holds, fast, reference) == as_rows


def test_a_second_period_and_a_version_are_read_with_the_session(conn: Conn) -> None:
    """A break of the periods' closure (model 4, darts of two periods), and a break made in a version only."""
    g4, _ = _store(conn)
    tgsis.enable_feature_versioning(conn)
    conn.commit()
    _switch(conn, "chunks")
    sent = "UPDATE tgsis.gmap_alpha SET dartid2 = 1160 WHERE geoid = %(g)s AND level = 3 AND dartid IN (1100, 1160)"
    conn.execute(sent, {"g": g4})
    holds, fast, reference = _answers(conn, g4, MODEL4)
    assert not holds and fast == reference and any("another topology period" in p for p, _, _ in reference)
    conn.rollback()
    tgsis.create_version(conn, "edit")
    with tgsis.in_version(conn, "edit"):
        conn.execute(BREAKS["non-involution"].format(alpha="tgsis.gmap_alpha"), {"g": g4})
        conn.commit()
        holds, fast, reference = _answers(conn, g4, MODEL4)
        assert not holds and fast == reference and "alpha_0 is not an involution" in [p for p, _, _ in fast]
        conn.commit()
    conn.commit()
    assert _answers(conn, g4, MODEL4) == (True, [], [])


def test_a_role_granted_the_faces_only_reads_them(db_dsn: str, conn: Conn) -> None:
    from tests.roles import login_roles

    g4, g5 = _store(conn)
    _switch(conn, "chunks")
    with login_roles(db_dsn, {"reader": "tgsis_reader"}) as roles:
        reader = roles.connect("reader")
        assert _chunk_path(reader, MODEL4)
        assert reader.execute("SELECT count(*) FROM tgsis.gmap_check(%s)", (g4,)).fetchone() == (0,)
        conn.execute("REVOKE SELECT ON tgsis.gmap_alpha_chunk FROM tgsis_reader")
        conn.commit()
        reader.commit()  # (a new transaction sees the grants as they are now)
        assert not _chunk_path(reader, MODEL4)
        assert reader.execute("SELECT count(*) FROM tgsis.gmap_check(%s)", (g4,)).fetchone() == (0,)
        assert reader.execute("SELECT count(*) FROM tgsis.md_check(%s)", (g5,)).fetchone() == (0,)


@pytest.mark.parametrize("deleted", [(), (0,), (1151,), (0, 500, 1023, 1024, 1295), tuple(range(1024, 1296))])
def test_the_darts_numbering_from_the_chunk_rows_is_the_faces(conn: Conn, deleted: tuple[int, ...]) -> None:
    """First and last id, how many, several periods: from the chunk rows as through the face, holes at either end."""
    g4, _ = _store(conn)
    _switch(conn, "chunks")
    if deleted:
        conn.execute("DELETE FROM tgsis.gmap_dart WHERE geoid = %s AND dartid = ANY (%s)", (g4, list(deleted)))
    face = conn.execute(
        "SELECT min(dartid), max(dartid), count(*), min(timem) < max(timem) FROM tgsis.gmap_dart WHERE geoid = %s",
        (g4,),
    ).fetchone()
    row = conn.execute("SELECT numbering FROM tgsis.gmap_chunk_arrays_sql(%s, %s, %s, %s)", MODEL4).fetchone()
    assert row is not None and row[0] is not None
    conn.execute(sql.SQL("PREPARE numbering (bigint, integer[]) AS {}").format(sql.SQL(row[0])))
    assert conn.execute(sql.SQL("EXECUTE numbering ({}, NULL)").format(sql.Literal(g4))).fetchone() == face
    assert face is not None and face[3] is (len(deleted) < 272)  # the second period's darts are 1152..1295


def test_gmap_check_reads_the_darts_periods_and_nodes_from_the_chunk_arrays(db_dsn: str, conn: Conn) -> None:
    """gmap_check's own test (the darts' nodes and periods exist) reads the chunk arrays, not the darts' face:
    a role that may read the chunk tables but not that face checks a valid map of two periods."""
    from tests.roles import login_roles

    g4, _ = _store(conn)
    _switch(conn, "chunks")
    with login_roles(db_dsn, {"reader": "tgsis_reader"}) as roles:
        reader = roles.connect("reader")
        assert reader.execute("SELECT * FROM tgsis.gmap_check(%s)", (g4,)).fetchall() == []
        conn.execute("REVOKE SELECT ON tgsis.gmap_dart, tgsis.gmap_alpha FROM tgsis_reader")
        conn.commit()
        reader.commit()
        assert reader.execute("SELECT has_table_privilege('tgsis.gmap_dart', 'SELECT')").fetchone() == (False,)
        assert _chunk_path(reader, MODEL4)
        assert reader.execute("SELECT * FROM tgsis.gmap_check(%s)", (g4,)).fetchall() == []


# dart breaks that only gmap_check's own test names (a dart's node or period missing), each made through the faces
OWN_BREAKS = {
    "a node gone": "DELETE FROM tgsis.gmap_node WHERE geoid = %(g)s AND nodeid = (SELECT nodeid FROM tgsis.gmap_dart "
    "WHERE geoid = %(g)s AND dartid = 1200)",
    "a dart's node beyond the period's": "UPDATE tgsis.gmap_dart SET nodeid = nodeid + 100000 WHERE geoid = %(g)s "
    "AND dartid IN (3, 1290)",
    "a period gone": "DELETE FROM tgsis.gmap_timem WHERE geoid = %(g)s AND timem = (SELECT max(timem) "
    "FROM tgsis.gmap_timem WHERE geoid = %(g)s)",
}


@pytest.mark.parametrize("versioned", [False, True])
@pytest.mark.parametrize("breakage", list(OWN_BREAKS))
def test_gmap_checks_own_breaks_are_named_on_chunks_as_on_rows(conn: Conn, breakage: str, versioned: bool) -> None:
    """Each break, made in the session (or in a version only), gives the same gmap_check on chunks as on rows."""
    g4, _ = _store(conn)
    if versioned:
        tgsis.enable_feature_versioning(conn)
        tgsis.create_version(conn, "edit")
        conn.commit()

    def broken() -> list[tuple[Any, ...]]:
        with tgsis.in_version(conn, "edit" if versioned else "DEFAULT"):
            conn.execute("SAVEPOINT broken")
            conn.execute(OWN_BREAKS[breakage], {"g": g4})
            found = conn.execute("SELECT * FROM tgsis.gmap_check(%s)", (g4,)).fetchall()
            conn.execute("ROLLBACK TO SAVEPOINT broken")
        conn.rollback()
        return found

    as_rows = broken()
    assert as_rows, "the break went unnoticed"
    _switch(conn, "chunks")
    assert broken() == as_rows
    assert conn.execute("SELECT * FROM tgsis.gmap_check(%s)", (g4,)).fetchall() == []
