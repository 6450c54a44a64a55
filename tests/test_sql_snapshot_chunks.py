"""Model 3's SQL snapshot on the chunks' arrays: ``tgsis.vertices_at`` with d4dvrtx stored in chunks (issue 40).

docs/storage.md, "Snapshots at t (models 2 and 3)": once d4dvrtx is in chunks, the
switch makes ``tgsis.d4dvrtx_arrays`` (the visible chunk versions with their
arrays) and ``tgsis.vertices_at`` interpolates two instants' aligned chunks slot
by slot (``tgsis.evolving_chunk_vertices``) instead of joining two instants of
the face. Its answers must be the rows' bit for bit: at every instant, between
two, at a period's ends, before and after, with a node moved, with holes (a node
deleted at one instant, one at every instant of its period), hostile doubles
(-0.0, 2.5e15), edits made on rows and on chunks, versioned or not;
a reader who may read the face but not the arrays reads the face's answer.
"""

from __future__ import annotations

import json
from typing import Any

import numpy as np
import psycopg
import pytest

import tgsis
from tests.merge_data import curved_surface
from tests.storage_data import switch_tables, tables_as_rows
from tgsis.temporal import EvolvingSurface, TopologyPeriod

Conn = psycopg.Connection[Any]

TABLES = ("d4dtrgl", "d4dvrtx")
#: two periods, the first from -0.0 with an instant that is not exactly 0.3, the second from the first's end
FIRST = (-0.0, 0.1 + 0.2, 1.0)
SECOND = (1.0, 2.0, 5.0)
#: every instant, between them, before, after, the ends, +0.0 against the stored -0.0
ASKED = (*FIRST, *SECOND, 0.15, 0.5, 0.999, 1.5, 3.0, 4.75, -1.0, 6.0, 0.0)
#: 40 x 40 nodes: two chunks of 1,024 ids per geometry instant
SIDE = 40


@pytest.fixture(autouse=True)
def _model3_as_rows(conn: Conn) -> None:
    """Model 3's tables as rows at each test's start, whatever TGSIS_TEST_TIME_STORAGE made them."""
    tables_as_rows(conn, TABLES)


def _switch(conn: Conn, to: str) -> None:
    switch_tables(conn, TABLES, to)


def _period(times: tuple[float, ...], lift: float, first: bool) -> TopologyPeriod:
    surface = curved_surface(SIDE)
    positions = np.stack([surface.vertices + np.array([0.0, 0.0, lift + 7.25 * i]) for i in range(len(times))])
    # hostile doubles inside a period (its start is the last shape of the period before; a subnormal is refused by
    # the upload's checks: their products underflow)
    if first:
        positions[0, 3 * SIDE + 5, [0, 2]] = (-0.0, 2.5e15)
    positions[1, 4 * SIDE + 6, [0, 2]] = (-0.0, -2.5e15)
    return TopologyPeriod(np.asarray(times), surface.cells, positions)


def _insert(conn: Conn) -> int:
    geoid = tgsis.insert_feature(
        conn, "evolving", EvolvingSurface([_period(FIRST, 0.0, True), _period(SECOND, 14.5, False)], name="moving")
    )
    conn.commit()
    return geoid


def _answers(conn: Conn, geoid: int) -> dict[str, Any]:
    answers: dict[str, Any] = {}
    with conn.cursor(binary=True) as cursor:
        for t in ASKED:
            answers[repr(t)] = cursor.execute(
                "SELECT vrtxid, float8send(x), float8send(y), float8send(z) FROM tgsis.vertices_at(%s, %s) ORDER BY 1",
                (geoid, t),
            ).fetchall()
        answers["surfaces_at"] = cursor.execute(
            "SELECT geoid, vertices::text, triangles::text FROM tgsis.surfaces_at('evolving', 0.5) ORDER BY 1"
        ).fetchall()
    conn.rollback()
    return answers


def _arrays_read(conn: Conn, geoid: int, t: float) -> bool:
    """Whether tgsis.vertices_at at t read the arrays (tgsis.evolving_chunk_vertices ran and gave rows)."""
    plan = conn.execute("EXPLAIN (ANALYZE, FORMAT JSON) SELECT * FROM tgsis.vertices_at(%s, %s)", (geoid, t)).fetchone()
    conn.rollback()
    assert plan is not None
    found: list[bool] = []

    def walk(node: dict[str, Any]) -> None:
        if node.get("Function Name") == "evolving_chunk_vertices":
            found.append(node.get("Actual Loops", 0) > 0 and node.get("Actual Rows", 0) > 0)
        for child in node.get("Plans", []):
            walk(child)

    doc = plan[0] if isinstance(plan[0], list) else json.loads(plan[0])
    walk(doc[0]["Plan"])
    return any(found)


def _edit(conn: Conn, geoid: int, node: int) -> None:
    """A node moved at one instant, a node deleted at one instant (a hole there), one at every instant of its period."""
    conn.execute(
        "UPDATE tgsis.d4dvrtx SET x = x + 0.1, z = -z WHERE geoid = %s AND timem = 0 AND timet = 1 AND nodeid = %s",
        (geoid, node),
    )
    conn.execute(
        "DELETE FROM tgsis.d4dvrtx WHERE geoid = %s AND timem = 0 AND timet = 0.1::float8 + 0.2::float8 AND nodeid = %s",
        (geoid, node + 1),
    )
    conn.execute(
        "DELETE FROM tgsis.d4dvrtx WHERE geoid = %s AND timem = 1 AND nodeid = %s", (geoid, node + 2 + SIDE * SIDE)
    )
    conn.commit()


@pytest.mark.parametrize("versioned", [False, True])
def test_vertices_at_on_the_arrays_gives_the_rows_bits(conn: Conn, versioned: bool) -> None:
    tgsis.create_feature_class(conn, "evolving", "SURFACE", time_model="EVOLVING")
    if versioned:
        tgsis.enable_feature_versioning(conn)
    conn.commit()
    geoid = _insert(conn)
    first = conn.execute("SELECT min(nodeid) FROM tgsis.node WHERE geoid = %s", (geoid,)).fetchone()
    assert first is not None
    _edit(conn, geoid, first[0] + 1020)  # nodes about the end of the first chunk
    on_rows = _answers(conn, geoid)
    assert conn.execute("SELECT to_regclass('tgsis.d4dvrtx_arrays')").fetchone() == (None,)
    assert not _arrays_read(conn, geoid, 0.5)
    _switch(conn, "chunks")
    assert _arrays_read(conn, geoid, 0.5) and _arrays_read(conn, geoid, 4.75)  # between two instants
    assert not _arrays_read(conn, geoid, 2.0)  # at one: the face's single scan (as fast, no function's result set)
    assert _answers(conn, geoid) == on_rows
    # edits on chunks (holes written into the chunks by the face), compared with the rows after the way back
    _edit(conn, geoid, first[0] + 1030)
    on_chunks = _answers(conn, geoid)
    assert on_chunks != on_rows
    _switch(conn, "rows")
    assert conn.execute("SELECT to_regclass('tgsis.d4dvrtx_arrays')").fetchone() == (None,)
    assert _answers(conn, geoid) == on_chunks


def test_a_reader_without_the_arrays_reads_the_face(db_dsn: str, conn: Conn) -> None:
    from tests.roles import login_roles

    tgsis.create_feature_class(conn, "evolving", "SURFACE", time_model="EVOLVING")
    conn.commit()
    geoid = _insert(conn)
    _switch(conn, "chunks")
    expected = _answers(conn, geoid)
    with login_roles(db_dsn, {"reader": "tgsis_reader"}) as roles:
        reader = roles.connect("reader")
        assert _arrays_read(reader, geoid, 0.5)
        assert _answers(reader, geoid) == expected
        conn.execute("REVOKE SELECT ON tgsis.d4dvrtx_arrays FROM PUBLIC")
        conn.commit()
        assert not _arrays_read(reader, geoid, 0.5)  # the face's join instead, not 42501
        assert _answers(reader, geoid) == expected


def _refused(reader: Conn, geoid: int) -> None:
    """The face's answer to a role that may not read it, between two instants as at one (42501)."""
    for t in (0.5, 1.0):
        with pytest.raises(psycopg.errors.InsufficientPrivilege):
            reader.execute("SELECT * FROM tgsis.vertices_at(%s, %s)", (geoid, t))
        reader.rollback()


@pytest.mark.parametrize("when", ["before", "after"])
def test_a_grant_on_the_face_after_the_switch_reaches_the_arrays(db_dsn: str, conn: Conn, when: str) -> None:
    """The arrays answer a caller who may read the face, asked at each read (before: the face's grants were
    copied to the arrays once, at the switch: a role granted the face later read the face's join only). The
    face revoked from the readers before the switch or after it, then granted to one reader."""
    from tests.roles import login_roles

    tgsis.create_feature_class(conn, "evolving", "SURFACE", time_model="EVOLVING")
    conn.commit()
    geoid = _insert(conn)
    with login_roles(db_dsn, {"reader": "tgsis_reader"}) as roles:
        reader = roles.connect("reader")
        if when == "before":
            conn.execute("REVOKE SELECT ON tgsis.d4dvrtx FROM tgsis_reader")
            conn.commit()
        _switch(conn, "chunks")
        expected = _answers(conn, geoid)
        if when == "after":
            conn.execute("REVOKE SELECT ON tgsis.d4dvrtx FROM tgsis_reader")
            conn.commit()
        _refused(reader, geoid)
        conn.execute(f"GRANT SELECT ON tgsis.d4dvrtx TO {roles.name('reader')}")
        conn.commit()
        assert _arrays_read(reader, geoid, 0.5)
        assert _answers(reader, geoid) == expected


def test_a_revoke_on_the_face_after_the_switch_reaches_the_arrays(db_dsn: str, conn: Conn) -> None:
    """A role revoked from the face after the switch reads no node through the arrays (before: it still read
    them there, the arrays' grant copied at the switch, where the face refuses with 42501)."""
    from tests.roles import login_roles

    tgsis.create_feature_class(conn, "evolving", "SURFACE", time_model="EVOLVING")
    conn.commit()
    geoid = _insert(conn)
    _switch(conn, "chunks")
    with login_roles(db_dsn, {"reader": "tgsis_reader"}) as roles:
        reader = roles.connect("reader")
        assert _arrays_read(reader, geoid, 0.5)
        conn.execute("REVOKE SELECT ON tgsis.d4dvrtx FROM tgsis_reader")
        conn.commit()
        assert reader.execute("SELECT count(*) FROM tgsis.d4dvrtx_arrays").fetchone() == (0,)
        reader.rollback()
        _refused(reader, geoid)


def test_partitioning_model_3_keeps_the_arrays(conn: Conn) -> None:
    """tgsis.partition_model_storage hash-partitions d4dvrtx's chunk table: the arrays view is made again over it
    (it would otherwise be another user of the chunk table, TG202)."""
    tgsis.create_feature_class(conn, "evolving", "SURFACE", time_model="EVOLVING")
    conn.commit()
    geoid = _insert(conn)
    on_rows = _answers(conn, geoid)
    _switch(conn, "chunks")
    tgsis.partition_model_storage(conn, 3, 2)
    conn.commit()
    assert conn.execute(
        "SELECT c.relkind FROM pg_class c WHERE c.oid = 'tgsis.d4dvrtx_chunk'::regclass"
    ).fetchone() == ("p",)
    assert _arrays_read(conn, geoid, 0.5)
    assert _answers(conn, geoid) == on_rows
