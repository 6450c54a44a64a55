"""Model 3's triangles and node positions (d4dtrgl, d4dvrtx) stored in chunks, by choice (issue 40).

docs/storage.md, "Snapshots at t (models 2 and 3)": d4dtrgl is keyed
(geoid, timem, chunk) by trglid, d4dvrtx (geoid, timem, timet, chunk) by nodeid
(``tgsis.chunk_key``); ``tgsis.store_in_chunks`` / ``tgsis.store_in_rows``
switch them with their data and back, and every model-3 function keeps its
answers through the faces. The instants (timem, timet) and the nodes stay rows.
The rest of the model-3 files run with these tables in chunks under
``TGSIS_TEST_TIME_STORAGE=chunks`` (docs/testing.md).
"""

from __future__ import annotations

import struct
from typing import Any

import numpy as np
import psycopg
import pytest

import tgsis
from tests.merge_data import curved_surface, sqlstate
from tests.storage_data import switch_tables, tables_as_rows
from tests.test_sql_merge_periods import _period
from tgsis.temporal import EvolvingSurface, TopologyPeriod

Conn = psycopg.Connection[Any]

TABLES = ("d4dtrgl", "d4dvrtx")
#: the first period starts at a negative zero, holds an instant that is not exactly 0.3; the second starts on its end
FIRST = (-0.0, 0.1 + 0.2, 1.0)
SECOND = (1.0, 2.0, 5.0)
#: where the answers are asked: every instant, between them, before, after, at the ends
ASKED = (*FIRST, *SECOND, 0.15, 0.5, 1.5, 3.0, -1.0, 6.0, 0.0)


@pytest.fixture(autouse=True)
def _model3_as_rows(conn: Conn) -> None:
    """Model 3's tables as rows at each test's start, whatever TGSIS_TEST_TIME_STORAGE made them: each test
    switches them itself."""
    tables_as_rows(conn, TABLES)


def _switch(conn: Conn, to: str) -> None:
    switch_tables(conn, TABLES, to)


def _class(conn: Conn, versioned: bool) -> None:
    tgsis.create_feature_class(
        conn,
        "evolving",
        "SURFACE",
        time_model="EVOLVING",
        cell_properties=[("porosity", "float8")],
        instant_properties=[("throw", "double precision")],
    )
    if versioned:
        tgsis.enable_feature_versioning(conn)
    conn.commit()


def _surface(shift: float = 0.0) -> EvolvingSurface:
    periods = [_period(FIRST, 0), _period(SECOND, 2)]
    return EvolvingSurface(
        [
            TopologyPeriod(
                p.times,
                p.triangles,
                p.positions + shift,
                vertex_properties=p.vertex_properties,
                properties=p.properties,
            )
            for p in periods
        ],
        name="evolving fault",
    )


def _insert(conn: Conn, shift: float = 0.0) -> int:
    geoid = tgsis.insert_feature(conn, "evolving", _surface(shift))
    conn.commit()
    return geoid


def _bits(a: np.ndarray) -> list[Any]:
    bits: list[Any] = np.ascontiguousarray(a, dtype=np.float64).view(np.int64).tolist()
    return bits


def _answers(conn: Conn, geoid: int) -> dict[str, Any]:
    """What the model-3 functions, faces and Python readers say of the feature, doubles by their bits."""

    def rows(query: str, *params: Any) -> list[tuple[Any, ...]]:
        with conn.cursor(binary=True) as cursor:
            return cursor.execute(query, params).fetchall()

    answers: dict[str, Any] = {}
    for t in ASKED:
        answers[f"vertices_at {t!r}"] = rows(
            "SELECT vrtxid, float8send(x), float8send(y), float8send(z) FROM tgsis.vertices_at(%s, %s) ORDER BY 1",
            geoid,
            t,
        )
        answers[f"triangles_at {t!r}"] = rows("SELECT * FROM tgsis.triangles_at(%s, %s) ORDER BY 1", geoid, t)
        got = tgsis.get_at(conn, geoid, t)
        answers[f"get_at {t!r}"] = None if got is None else (_bits(got.vertices), got.triangles.tolist())
    answers["extent"] = rows("SELECT * FROM tgsis.evolving_extent(%s)", geoid)
    answers["check"] = rows("SELECT * FROM tgsis.check_temporal_geometry(%s)", geoid)
    answers["gaps"] = rows("SELECT * FROM tgsis.period_gaps(%s)", geoid)
    answers["d4dvrtx"] = rows(
        "SELECT geoid, float8send(timem), float8send(timet), nodeid, float8send(x), float8send(y), float8send(z)"
        " FROM tgsis.d4dvrtx WHERE geoid = %s ORDER BY 1, 2, 3, 4",
        geoid,
    )
    answers["d4dtrgl"] = rows(
        "SELECT geoid, float8send(timem), trglid, nodeid1, nodeid2, nodeid3 FROM tgsis.d4dtrgl WHERE geoid = %s"
        " ORDER BY 1, 2, 3",
        geoid,
    )
    answers["node"] = rows(
        "SELECT geoid, float8send(timem), nodeid FROM tgsis.node WHERE geoid = %s ORDER BY 1, 2, 3", geoid
    )
    surface = tgsis.fetch_evolving(conn, "evolving", geoid)
    answers["periods"] = [
        (
            _bits(p.times),
            p.triangles.tolist(),
            _bits(p.positions),
            {k: _bits(v) for k, v in sorted(p.vertex_properties.items())},
            {k: _bits(v) for k, v in sorted(p.properties.items())},
        )
        for p in surface.periods
    ]
    conn.rollback()
    return answers


def _in_each_version(conn: Conn, geoid: int, versions: tuple[str, ...]) -> dict[str, Any]:
    found: dict[str, Any] = {}
    for version in versions:
        with tgsis.in_version(conn, version):
            found[version] = _answers(conn, geoid)
        conn.rollback()
    return found


def _catalog(conn: Conn) -> list[tuple[Any, ...]]:
    """The tables' relations as the catalog has them: kind, grants, row-level security, policies, triggers,
    comments of the relation and its columns."""
    rows = conn.execute(
        "SELECT c.relname, c.relkind, ARRAY(SELECT a::text FROM unnest(c.relacl) a ORDER BY 1), c.relrowsecurity,"
        " obj_description(c.oid, 'pg_class'),"
        " ARRAY(SELECT p.polname || ':' || coalesce(pg_get_expr(p.polqual, p.polrelid), '') || ':'"
        "       || coalesce(pg_get_expr(p.polwithcheck, p.polrelid), '') FROM pg_policy p WHERE p.polrelid = c.oid ORDER BY 1),"
        " ARRAY(SELECT t.tgname::text FROM pg_trigger t WHERE t.tgrelid = c.oid ORDER BY 1),"
        " ARRAY(SELECT a.attname || ':' || coalesce(col_description(c.oid, a.attnum), '') FROM pg_attribute a"
        "       WHERE a.attrelid = c.oid AND a.attnum > 0 AND NOT a.attisdropped ORDER BY a.attnum)"
        " FROM pg_class c WHERE c.relnamespace = 'tgsis'::regnamespace AND c.relname ~ '^(d4dvrtx|d4dtrgl|node)'"
        " ORDER BY 1"
    ).fetchall()
    conn.rollback()
    return rows


def _edit_in_a_version(conn: Conn, geoid: int) -> None:
    """Revisions to keep apart: a version e1 whose psql user moves a node, DEFAULT moving another one later."""
    tgsis.create_version(conn, "e1")
    conn.commit()
    with tgsis.in_version(conn, "e1"):
        conn.execute(
            "UPDATE tgsis.d4dvrtx SET z = z + 1 WHERE geoid = %s AND timem = '-0'::float8 AND timet = 0.1::float8 + 0.2::float8"
            " AND nodeid = 2",
            (geoid,),
        )
    conn.commit()
    conn.execute(
        "UPDATE tgsis.d4dvrtx SET x = x - 1 WHERE geoid = %s AND timem = 1 AND timet = 5 AND nodeid = (SELECT min(nodeid)"
        " FROM tgsis.node WHERE geoid = %s AND timem = 1)",
        (geoid, geoid),
    )
    conn.commit()


@pytest.mark.parametrize("versioned", [False, True])
def test_the_switch_and_back_keep_every_answer_bit_for_bit(conn: Conn, versioned: bool) -> None:
    _class(conn, versioned)
    geoid = _insert(conn)
    other = _insert(conn, shift=0.5)
    versions: tuple[str, ...] = ("DEFAULT",)
    if versioned:
        _edit_in_a_version(conn, geoid)
        versions = ("DEFAULT", "e1")
    before = {g: _in_each_version(conn, g, versions) for g in (geoid, other)}
    if versioned:  # the edits are seen where they were made only
        assert before[geoid]["e1"]["d4dvrtx"] != before[geoid]["DEFAULT"]["d4dvrtx"]
    catalog = _catalog(conn)
    assert conn.execute("SELECT tgsis.chunk_key('d4dvrtx'), tgsis.chunk_key('d4dtrgl')").fetchone() == (
        ["geoid", "timem", "timet"],
        ["geoid", "timem"],
    )
    _switch(conn, "chunks")
    assert conn.execute(
        "SELECT bool_and(tgsis.stored_in_chunks(t)) FROM unnest(%s::text[]) t", (list(TABLES),)
    ).fetchone() == (True,)
    # one chunk per geometry instant (each period's nodes number less than a chunk), its keys with the instants' bits
    keys = conn.execute(
        "SELECT DISTINCT float8send(timem), float8send(timet), chunk FROM tgsis.d4dvrtx_chunk WHERE geoid = %s"
        " ORDER BY 1, 2",
        (geoid,),
    ).fetchall()
    found = sorted({(struct.unpack(">d", m)[0], struct.unpack(">d", t)[0]) for m, t, _ in keys})
    assert found == sorted({(FIRST[0], t) for t in FIRST} | {(SECOND[0], t) for t in SECOND})
    assert struct.pack(">d", -0.0) in {bytes(m) for m, _, _ in keys}
    assert _in_each_version(conn, geoid, versions) == before[geoid]
    assert _in_each_version(conn, other, versions) == before[other]
    conn.execute("SELECT tgsis.check_chunk_conversion(t) FROM unnest(%s::text[]) t", (list(TABLES),))
    conn.rollback()
    _switch(conn, "rows")
    assert conn.execute("SELECT count(*) FROM pg_class WHERE relname ~ '^d4d(vrtx|trgl)_(chunk|shape)'").fetchone() == (
        0,
    )
    kind = conn.execute("SELECT relkind FROM pg_class WHERE oid = 'tgsis.d4dvrtx'::regclass").fetchone()
    assert kind == (("v",) if versioned else ("r",))
    assert {g: _in_each_version(conn, g, versions) for g in (geoid, other)} == before
    assert _catalog(conn) == catalog  # the same relations, rights, policies, triggers and comments as before


@pytest.mark.parametrize("versioned", [False, True])
def test_model3_writes_and_reads_on_chunks(conn: Conn, versioned: bool) -> None:
    _class(conn, versioned)
    _switch(conn, "chunks")
    geoid = _insert(conn)
    expected = _surface()
    got = tgsis.fetch_evolving(conn, "evolving", geoid)
    assert [_bits(p.positions) for p in got.periods] == [_bits(p.positions) for p in expected.periods]
    assert [_bits(p.times) for p in got.periods] == [_bits(p.times) for p in expected.periods]
    # a third period, then it goes again
    tgsis.append_period(conn, "evolving", geoid, _period((5.0, 6.0), 4))
    conn.commit()
    assert [p.times[0] for p in tgsis.fetch_evolving(conn, "evolving", geoid).periods] == [0.0, 1.0, 5.0]
    assert tgsis.delete_period(conn, geoid, 5.0)
    conn.commit()
    assert conn.execute("SELECT count(*) FROM tgsis.d4dvrtx WHERE geoid = %s AND timem = 5", (geoid,)).fetchone() == (
        0,
    )
    assert conn.execute("SELECT * FROM tgsis.check_temporal_geometry(%s)", (geoid,)).fetchall() == []
    # a psql UPDATE through the face at the inexact instant
    conn.execute(
        "UPDATE tgsis.d4dvrtx SET z = z + 1 WHERE geoid = %s AND timem = '-0'::float8 AND timet = 0.1::float8 + 0.2::float8"
        " AND nodeid = 3",
        (geoid,),
    )
    conn.commit()
    z = conn.execute(
        "SELECT z FROM tgsis.vertices_at(%s, 0.1::float8 + 0.2::float8) WHERE vrtxid = 3", (geoid,)
    ).fetchone()
    assert z == (expected.periods[0].positions[1, 3, 2] + 1,)
    # a psql DELETE and INSERT of a triangle through the face
    cell = conn.execute(
        "DELETE FROM tgsis.d4dtrgl WHERE geoid = %s AND timem = 1 AND trglid = (SELECT max(trglid) FROM tgsis.d4dtrgl"
        " WHERE geoid = %s AND timem = 1) RETURNING trglid, nodeid1, nodeid2, nodeid3",
        (geoid, geoid),
    ).fetchone()
    assert cell is not None
    conn.commit()
    assert (
        len(conn.execute("SELECT * FROM tgsis.triangles_at(%s, 2.0)", (geoid,)).fetchall())
        == len(expected.periods[1].triangles) - 1
    )
    conn.execute("INSERT INTO tgsis.d4dtrgl VALUES (%s, 1, %s, %s, %s, %s)", (geoid, *cell))
    conn.commit()
    assert len(conn.execute("SELECT * FROM tgsis.triangles_at(%s, 2.0)", (geoid,)).fetchall()) == len(
        expected.periods[1].triangles
    )
    # a second feature, then each keeps its own
    other = _insert(conn, shift=0.5)
    assert tgsis.fetch_evolving(conn, "evolving", other).periods[0].positions[2, 0, 2] == (
        expected.periods[0].positions[2, 0, 2] + 0.5
    )
    assert conn.execute("SELECT * FROM tgsis.check_temporal_geometry(%s)", (other,)).fetchall() == []
    assert tgsis.delete_feature(conn, "evolving", geoid)
    conn.commit()
    assert conn.execute("SELECT count(*) FROM tgsis.d4dvrtx WHERE geoid = %s", (geoid,)).fetchone() == (0,)
    assert conn.execute("SELECT count(*) FROM tgsis.d4dvrtx WHERE geoid = %s", (other,)).fetchone() == (
        sum(p.positions.shape[0] * p.positions.shape[1] for p in expected.periods),
    )


def test_hostile_keys_and_inputs_are_refused_by_name(conn: Conn) -> None:
    _class(conn, False)
    geoid = _insert(conn)
    for table in ("node", "timem", "timet"):  # no chunk column: rows only
        assert sqlstate(conn, "SELECT tgsis.store_in_chunks(%s)", (table,))[0] == "TG200", table
    assert sqlstate(conn, "SELECT tgsis.store_in_rows('d4dvrtx')")[0] == "TG200"  # not in chunks yet
    # the default storage does not switch them: only tgsis.store_in_chunks does
    assert conn.execute(
        "SELECT array_agg(tablename ORDER BY tablename) FROM tgsis.model_tables"
        " WHERE model = 3 AND chunkcolumn IS NOT NULL AND NOT chunkdefault"
    ).fetchone() == (["d4dtrgl", "d4dvrtx"],)
    assert conn.execute(
        "SELECT bool_or(tgsis.stored_in_chunks(t)) FROM unnest(%s::text[]) t", (list(TABLES),)
    ).fetchone() == (False,)
    before = _answers(conn, geoid)["d4dvrtx"]
    _switch(conn, "chunks")
    assert sqlstate(conn, "SELECT tgsis.store_in_chunks('d4dvrtx')")[0] == "TG201"
    # the writers of chunks keyed by the object alone refuse the model-3 tables by name
    assert sqlstate(conn, "SELECT tgsis.object_chunks_stage('d4dvrtx')")[0] == "TG100"
    # a key equal to the stored instant but of other bits (0.0 where -0.0 is stored): refused, never rewritten
    state, message = sqlstate(conn, "INSERT INTO tgsis.d4dvrtx VALUES (%s, 0.0, 1.0, 5000, 1, 2, 3)", (geoid,))
    assert state == "TG100" and "other bits" in message
    conn.rollback()
    # a visible key: 23505 as on rows
    first_node = conn.execute("SELECT min(nodeid) FROM tgsis.node WHERE geoid = %s AND timem = 1", (geoid,)).fetchone()
    assert first_node is not None
    assert (
        sqlstate(conn, "INSERT INTO tgsis.d4dvrtx VALUES (%s, 1.0, 2.0, %s, 0, 0, 0)", (geoid, first_node[0]))[0]
        == "23505"
    )
    assert (
        sqlstate(conn, "INSERT INTO tgsis.d4dtrgl VALUES (%s, 1.0, 0, 1, 1, 2)", (geoid,))[0] == "23514"
    )  # the rows' check: distinct nodes
    conn.rollback()
    assert _answers(conn, geoid)["d4dvrtx"] == before


def test_a_session_printing_floats_short_writes_the_exact_instant(conn: Conn) -> None:
    _class(conn, False)
    _switch(conn, "chunks")
    geoid = _insert(conn)
    conn.execute("SET extra_float_digits = -15")
    conn.execute(
        "UPDATE tgsis.d4dvrtx SET x = 7 WHERE geoid = %s AND timem = '-0'::float8 AND timet = 0.1::float8 + 0.2::float8"
        " AND nodeid = 0",
        (geoid,),
    )
    conn.commit()
    conn.execute("RESET extra_float_digits")
    with conn.cursor(binary=True) as cursor:
        got = cursor.execute(
            "SELECT float8send(timem), float8send(timet), x FROM tgsis.d4dvrtx WHERE geoid = %s AND nodeid = 0"
            " ORDER BY timet",
            (geoid,),
        ).fetchall()
    first = _surface().periods[0].positions[:, 0, 0]
    assert [(struct.unpack(">d", m)[0], struct.unpack(">d", t)[0], x) for m, t, x in got] == [
        (-0.0, -0.0, first[0]),
        (-0.0, 0.1 + 0.2, 7.0),
        (-0.0, 1.0, first[2]),
    ]
    assert bytes(got[0][0]) == struct.pack(">d", -0.0)


@pytest.mark.parametrize("same_node", [False, True])
def test_two_sessions_writing_one_instant_through_the_face(db_dsn: str, conn: Conn, same_node: bool) -> None:
    from tests.sessions import Background, connect, wait_until_blocked

    _class(conn, False)
    _switch(conn, "chunks")
    geoid = _insert(conn)
    where = "geoid = %s AND timem = '-0'::float8 AND timet = 0.1::float8 + 0.2::float8"
    first = connect(db_dsn, "first")
    first.execute("SET extra_float_digits = 0")  # another setting than the second session's: the same chunk lock
    first.execute(f"UPDATE tgsis.d4dvrtx SET x = x + 1 WHERE {where} AND nodeid = 1", (geoid,))
    failures: list[str] = []

    def second_writer(session: Conn) -> None:
        try:
            session.execute(
                f"UPDATE tgsis.d4dvrtx SET x = x + 10 WHERE {where} AND nodeid = %s", (geoid, 1 if same_node else 2)
            )
            session.commit()
        except psycopg.Error as exc:
            failures.append(exc.sqlstate or "")
            session.rollback()

    second = Background(db_dsn, "second", second_writer)
    wait_until_blocked(conn, second.pid, first.info.backend_pid)  # the chunk's lock
    conn.rollback()
    first.commit()
    first.close()
    second.finish()
    x = _surface().periods[0].positions[1, :3, 0]
    got = [
        r[0]
        for r in conn.execute(
            f"SELECT x FROM tgsis.d4dvrtx WHERE {where} AND nodeid IN (1, 2) ORDER BY nodeid", (geoid,)
        ).fetchall()
    ]
    if same_node:  # the second read the row before the first's commit: its write would undo it
        assert failures == ["40001"]
        assert got == [x[1] + 1, x[2]]
    else:
        assert failures == []
        assert got == [x[1] + 1, x[2] + 10]


def test_a_role_with_fewer_rights_reads_and_cannot_write(db_dsn: str, conn: Conn) -> None:
    from tests.roles import login_roles

    _class(conn, True)
    _switch(conn, "chunks")
    geoid = _insert(conn)
    with login_roles(db_dsn, {"reader": "tgsis_reader", "editor": "tgsis_editor"}) as roles:
        reader = roles.connect("reader")
        assert len(reader.execute("SELECT * FROM tgsis.vertices_at(%s, 2.0)", (geoid,)).fetchall()) == len(
            curved_surface().vertices
        )
        assert (
            sqlstate(reader, "UPDATE tgsis.d4dvrtx SET x = 0 WHERE geoid = %s AND nodeid = 1", (geoid,))[0] == "42501"
        )
        assert sqlstate(reader, "UPDATE tgsis.d4dvrtx_chunk SET x[1] = 0")[0] == "42501"
        assert sqlstate(reader, "SELECT tgsis.store_in_rows('d4dvrtx')")[0] == "42501"
        editor = roles.connect("editor")
        tgsis.append_period(editor, "evolving", geoid, _period((5.0, 7.0), 4))
        editor.commit()
        assert reader.execute("SELECT count(*) FROM tgsis.triangles_at(%s, 6.0)", (geoid,)).fetchone() == (
            len(curved_surface().cells),
        )
    assert [p.times[-1] for p in tgsis.fetch_evolving(conn, "evolving", geoid).periods] == [1.0, 5.0, 7.0]


def test_the_psql_merge_of_periods_writes_chunks_as_it_writes_rows(conn: Conn) -> None:
    from tests.test_sql_merge_periods import step
    from tests.test_sql_merge_write import assert_same_merge

    _class(conn, True)
    geoid = _insert(conn)
    tgsis.create_version(conn, "e1")
    conn.commit()
    _switch(conn, "chunks")
    step(conn, "e1", "move 1.0 2.0 north", geoid)
    step(conn, "DEFAULT", "move 1.0 5.0 south", geoid)
    assert_same_merge(conn, "e1")  # (Python's merge and psql's write the same rows and chunks)
    before = _answers(conn, geoid)
    assert int(conn.execute("SELECT tgsis.merge_version('e1', false)").fetchone()[0]) > 0  # type: ignore[index]
    conn.commit()
    merged = _answers(conn, geoid)
    assert merged != before
    with tgsis.in_version(conn, "e1"):
        e1 = _answers(conn, geoid)
    conn.rollback()
    assert merged["d4dvrtx"] == e1["d4dvrtx"]  # e1 saw DEFAULT's move and its own; DEFAULT now holds both
    _switch(conn, "rows")
    assert _answers(conn, geoid) == merged


def test_pg_dump_and_restore_keep_the_tables_in_chunks(pg: Any, db_dsn: str, conn: Conn, tmp_path: Any) -> None:
    from tests.test_backup import _bindir_of, _restored

    _class(conn, True)
    _switch(conn, "chunks")
    geoid = _insert(conn)
    before = _answers(conn, geoid)
    chunks = (
        "SELECT geoid, float8send(timem), float8send(timet), chunk, revision, lastrevs, array_send(x), array_send(y),"
        " array_send(z) FROM tgsis.d4dvrtx_chunk ORDER BY 1, 2, 3, 4, 5"
    )
    stored = conn.execute(chunks).fetchall()
    conn.rollback()
    with _restored(pg, _bindir_of(pg), db_dsn, "custom", tmp_path) as dsn, psycopg.connect(dsn) as copy:
        assert copy.execute(chunks).fetchall() == stored
        assert copy.execute(
            "SELECT tgsis.stored_in_chunks('d4dvrtx'), tgsis.stored_in_chunks('d4dtrgl')"
        ).fetchone() == (True, True)
        assert _answers(copy, geoid) == before
        _switch(copy, "rows")
        assert _answers(copy, geoid) == before
