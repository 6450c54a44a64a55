"""Model 2's time tables (times_vrtx, times_trgl) stored in chunks keyed (geoid, times, chunk) (issue 40).

docs/storage.md, "Snapshots at t (models 2 and 3)": the chunk key is a list
(``tgsis.chunk_key``), ``tgsis.store_in_chunks`` / ``tgsis.store_in_rows``
switch the time tables with their data and back, and every model-2 function
keeps its answers through the faces. The rest of the model-2 files run with the
time tables in chunks under ``TGSIS_TEST_TIME_STORAGE=chunks`` (docs/testing.md).
"""

from __future__ import annotations

import struct
from typing import Any

import numpy as np
import psycopg
import pytest

import tgsis
from tests.merge_data import curved_surface, sqlstate
from tgsis.temporal import SurfaceSeries

Conn = psycopg.Connection[Any]

TIME_TABLES = ("times_vrtx", "times_trgl")
#: an instant that is not exactly 0.3, a negative zero, a plain one
TIMES = (-0.0, 0.1 + 0.2, 2.0)


def _switch(conn: Conn, to: str) -> None:
    for table in TIME_TABLES if to == "chunks" else reversed(TIME_TABLES):
        conn.execute(f"SELECT tgsis.store_in_{to}(%s)", (table,))
    conn.commit()


def _series(conn: Conn, name: str = "horizons", times: tuple[float, ...] = TIMES, shift: float = 0.0) -> int:
    s = curved_surface()
    surfaces = [
        tgsis.Surface(
            s.vertices + shift + i / 3.0, s.cells, vertex_properties={"porosity": s.vertex_properties["porosity"]}
        )
        for i in range(len(times))
    ]
    geoid = tgsis.insert_feature(conn, name, SurfaceSeries(np.asarray(times), surfaces))
    conn.commit()
    return geoid


def _class(conn: Conn, versioned: bool) -> None:
    """The class ``horizons``, the time tables as rows whatever TGSIS_TEST_TIME_STORAGE made them (each test
    switches them itself)."""
    _store(conn, "rows")
    tgsis.create_feature_class(
        conn, "horizons", "SURFACE", time_model="INSTANTS", cell_properties=[("porosity", "float8")]
    )
    if versioned:
        tgsis.enable_feature_versioning(conn)
    conn.commit()


def _answers(conn: Conn, geoid: int) -> dict[str, Any]:
    """What the model-2 functions say of the feature, doubles by their bits."""

    def rows(query: str, *params: Any) -> list[tuple[Any, ...]]:
        with conn.cursor(binary=True) as cursor:
            return cursor.execute(query, params).fetchall()

    answers: dict[str, Any] = {}
    for t in (*TIMES, 1.0, 5.0):
        answers[f"vertices_at {t}"] = rows("SELECT * FROM tgsis.vertices_at(%s, %s) ORDER BY 1", geoid, t)
        answers[f"triangles_at {t}"] = rows("SELECT * FROM tgsis.triangles_at(%s, %s) ORDER BY 1", geoid, t)
    answers["extent"] = rows("SELECT * FROM tgsis.instants_extent(%s)", geoid)
    answers["check"] = rows("SELECT * FROM tgsis.check_temporal_geometry(%s)", geoid)
    answers["faces"] = rows(
        "SELECT geoid, float8send(times), vrtxid, float8send(x), float8send(y), float8send(z) FROM tgsis.times_vrtx "
        "WHERE geoid = %s ORDER BY 1, 2, 3",
        geoid,
    )
    answers["trgl"] = rows("SELECT * FROM tgsis.times_trgl WHERE geoid = %s ORDER BY 1, 2, 3", geoid)
    series = tgsis.fetch_series(conn, "horizons", geoid)
    answers["series times"] = series.times.view(np.int64).tolist()
    answers["series"] = [(s.vertices.view(np.int64).tolist(), s.cells.tolist()) for s in series.surfaces]
    conn.rollback()
    return answers


def _catalog(conn: Conn) -> list[tuple[Any, ...]]:
    """The time tables' relations as the catalog has them: kind, grants, row-level security, policies, triggers,
    comments of the relation and its columns."""
    rows = conn.execute(
        "SELECT c.relname, c.relkind, ARRAY(SELECT a::text FROM unnest(c.relacl) a ORDER BY 1), c.relrowsecurity,"
        " obj_description(c.oid, 'pg_class'),"
        " ARRAY(SELECT p.polname || ':' || coalesce(pg_get_expr(p.polqual, p.polrelid), '') || ':'"
        "       || coalesce(pg_get_expr(p.polwithcheck, p.polrelid), '') FROM pg_policy p WHERE p.polrelid = c.oid ORDER BY 1),"
        " ARRAY(SELECT t.tgname::text FROM pg_trigger t WHERE t.tgrelid = c.oid ORDER BY 1),"
        " ARRAY(SELECT a.attname || ':' || coalesce(col_description(c.oid, a.attnum), '') FROM pg_attribute a"
        "       WHERE a.attrelid = c.oid AND a.attnum > 0 AND NOT a.attisdropped ORDER BY a.attnum)"
        " FROM pg_class c WHERE c.relnamespace = 'tgsis'::regnamespace AND c.relname ~ '^times_(vrtx|trgl)'"
        " ORDER BY 1"
    ).fetchall()
    conn.rollback()
    return rows


@pytest.mark.parametrize("versioned", [False, True])
def test_the_switch_and_back_keep_every_answer_bit_for_bit(conn: Conn, versioned: bool) -> None:
    _class(conn, versioned)
    geoid = _series(conn)
    before = _answers(conn, geoid)
    catalog = _catalog(conn)
    assert conn.execute("SELECT tgsis.chunk_key('times_vrtx'), tgsis.chunk_key('vrtx')").fetchone() == (
        ["geoid", "times"],
        ["geoid"],
    )
    _switch(conn, "chunks")
    assert conn.execute(
        "SELECT bool_and(tgsis.stored_in_chunks(t)) FROM unnest(%s::text[]) t", (list(TIME_TABLES),)
    ).fetchone() == (True,)
    # one chunk per instant, its key with the instant's bits (-0.0 kept, 0.30000000000000004 not 0.3)
    keys = conn.execute(
        "SELECT float8send(times), chunk, cardinality(x) FROM tgsis.times_vrtx_chunk WHERE geoid = %s ORDER BY times",
        (geoid,),
    ).fetchall()
    assert [struct.unpack(">d", k[0])[0] for k in keys] == list(TIMES)
    assert bytes(keys[0][0]) == struct.pack(">d", -0.0)
    assert _answers(conn, geoid) == before
    conn.execute("SELECT tgsis.check_chunk_conversion(t) FROM unnest(%s::text[]) t", (list(TIME_TABLES),))
    _switch(conn, "rows")
    assert conn.execute(
        "SELECT count(*) FROM pg_class WHERE relname IN ('times_vrtx_chunk', 'times_vrtx_shape', 'times_trgl_chunk')"
    ).fetchone() == (0,)
    kind = conn.execute("SELECT relkind FROM pg_class WHERE oid = 'tgsis.times_vrtx'::regclass").fetchone()
    assert kind == (("v",) if versioned else ("r",))
    assert _answers(conn, geoid) == before
    assert _catalog(conn) == catalog  # the same relations, rights, policies, triggers and comments as before


@pytest.mark.parametrize("versioned", [False, True])
def test_model2_writes_and_reads_on_chunks(conn: Conn, versioned: bool) -> None:
    _class(conn, versioned)
    _switch(conn, "chunks")
    geoid = _series(conn)
    series = tgsis.fetch_series(conn, "horizons", geoid)
    assert series.times.view(np.int64).tolist() == np.asarray(TIMES).view(np.int64).tolist()
    assert np.array_equal(
        series.surfaces[1].vertices.view(np.int64), (curved_surface().vertices + 1 / 3.0).view(np.int64)
    )
    tgsis.add_instant(conn, "horizons", geoid, 5.0, series.surfaces[0])
    conn.commit()
    assert tgsis.fetch_series(conn, "horizons", geoid).times.tolist() == [*TIMES, 5.0]
    assert tgsis.delete_instant(conn, geoid, 2.0)
    conn.commit()
    assert tgsis.fetch_series(conn, "horizons", geoid).times.tolist() == [-0.0, 0.1 + 0.2, 5.0]
    assert conn.execute(
        "SELECT count(*) FROM tgsis.times_vrtx WHERE geoid = %s AND times = 2.0", (geoid,)
    ).fetchone() == (0,)
    assert conn.execute("SELECT * FROM tgsis.check_temporal_geometry(%s)", (geoid,)).fetchall() == []
    # a psql UPDATE through the face at the inexact instant
    conn.execute(
        "UPDATE tgsis.times_vrtx SET z = z + 1 WHERE geoid = %s AND times = 0.1::float8 + 0.2::float8 AND vrtxid = 3",
        (geoid,),
    )
    conn.commit()
    z = conn.execute("SELECT z FROM tgsis.vertices_at(%s, 0.3000000000000001) WHERE vrtxid = 3", (geoid,)).fetchone()
    assert z == (curved_surface().vertices[3, 2] + 1 / 3.0 + 1,)
    # a second feature, then each keeps its own
    other = _series(conn, shift=100.0)
    assert (
        tgsis.fetch_series(conn, "horizons", other).surfaces[0].vertices[0, 0]
        == curved_surface().vertices[0, 0] + 100.0
    )


def test_hostile_keys_and_inputs_are_refused_by_name(conn: Conn) -> None:
    _class(conn, False)
    geoid = _series(conn)
    assert sqlstate(conn, "SELECT tgsis.store_in_chunks('times')")[0] == "TG200"  # no chunk column: rows only
    assert sqlstate(conn, "SELECT tgsis.chunk_key('nope')")[0] == "TG200"
    assert sqlstate(conn, "SELECT tgsis.store_in_rows('times_vrtx')")[0] == "TG200"  # not in chunks yet
    # a new database stores the time tables in chunks (chunkdefault, as model 1's; an upgraded one keeps its rows:
    # tests/test_upgrade.py); this file's classes start from rows (_class)
    assert conn.execute(
        "SELECT array_agg(tablename ORDER BY tablename) FROM tgsis.model_tables"
        " WHERE model = 2 AND chunkcolumn IS NOT NULL AND chunkdefault"
    ).fetchone() == (["times_trgl", "times_vrtx"],)
    # rows of one chunk of an instant stored with both zeros (the rows' key tells them apart by vrtxid only): the
    # conversion's proof compares keys by their bits, so it refuses them rather than storing one zero for both
    with conn.transaction(force_rollback=True):
        conn.execute("INSERT INTO tgsis.times_vrtx VALUES (%s, 0.0, 500, 1, 2, 3)", (geoid,))  # (chunk 0, as -0.0's)
        assert sqlstate(conn, "SELECT tgsis.store_in_chunks('times_vrtx')")[0] == "TG000"
    conn.rollback()
    _switch(conn, "chunks")
    assert sqlstate(conn, "SELECT tgsis.store_in_chunks('times_vrtx')")[0] == "TG201"
    # the writers of chunks keyed by the object alone refuse the time tables by name
    assert sqlstate(conn, "SELECT tgsis.object_chunks_stage('times_vrtx')")[0] == "TG100"
    assert (
        sqlstate(conn, "SELECT tgsis.write_object_rows('times_vrtx', %s, '{}', '{1}', '{{1},{2},{3}}')", (geoid,))[0]
        == "TG100"
    )
    # a key equal to the stored instant but of other bits (0.0 where -0.0 is stored): refused, never rewritten
    state, message = sqlstate(conn, "INSERT INTO tgsis.times_vrtx VALUES (%s, 0.0, 5000, 1, 2, 3)", (geoid,))
    assert state == "TG100" and "other bits" in message
    # the same instant with its own bits is written
    assert sqlstate(conn, "INSERT INTO tgsis.times_vrtx VALUES (%s, '-0'::float8, 5000, 1, 2, 3)", (geoid,)) == (
        None,
        "",
    )
    conn.rollback()
    # a visible key: 23505 as on rows, through the face and through the bulk insert
    assert sqlstate(conn, "INSERT INTO tgsis.times_vrtx VALUES (%s, 2.0, 3, 0, 0, 0)", (geoid,))[0] == "23505"
    assert (
        sqlstate(
            conn,
            "SELECT tgsis.insert_chunk_rows('times_vrtx', '{geoid,vrtxid,times,x,y,z}', ARRAY[[%s],[3]]::bigint[], "
            "'{{2.0},{0},{0},{0}}'::float8[])",
            (geoid,),
        )[0]
        == "23505"
    )
    # columns that are not the table's, or of the wrong shape
    assert (
        sqlstate(
            conn, "SELECT tgsis.insert_chunk_rows('times_vrtx', '{geoid,vrtxid}', ARRAY[[1],[3]]::bigint[], NULL)"
        )[0]
        == "TG100"
    )
    assert (
        sqlstate(conn, "SELECT tgsis.insert_chunk_rows('times', '{geoid,times}', ARRAY[[1]]::bigint[], '{{1}}')")[0]
        == "TG100"
    )
    # two rows of one write at one instant with other bits
    state, _ = sqlstate(
        conn,
        "SELECT tgsis.insert_chunk_rows('times_vrtx', '{geoid,vrtxid,times,x,y,z}', ARRAY[[%s, %s],[7000, 7001]]::bigint[], "
        "ARRAY[[0.0, '-0'::float8],[0, 0],[0, 0],[0, 0]]::float8[])",
        (geoid + 1, geoid + 1),
    )
    assert state in ("TG100", "42501", "TG200")  # (no such feature: refused before or by the key check)


def test_a_session_printing_floats_short_writes_the_exact_instant(conn: Conn) -> None:
    _class(conn, False)
    _switch(conn, "chunks")
    geoid = _series(conn)
    conn.execute("SET extra_float_digits = -15")
    conn.execute(
        "UPDATE tgsis.times_vrtx SET x = 7 WHERE geoid = %s AND times = 0.1::float8 + 0.2::float8 AND vrtxid = 0",
        (geoid,),
    )
    conn.commit()
    conn.execute("RESET extra_float_digits")
    with conn.cursor(binary=True) as cursor:
        got = cursor.execute(
            "SELECT float8send(times), x FROM tgsis.times_vrtx WHERE geoid = %s AND vrtxid = 0 ORDER BY times", (geoid,)
        ).fetchall()
    assert [(struct.unpack(">d", t)[0], x) for t, x in got] == [
        (-0.0, curved_surface().vertices[0, 0]),
        (0.1 + 0.2, 7.0),
        (2.0, curved_surface().vertices[0, 0] + 2 / 3.0),
    ]


@pytest.mark.parametrize("same_vertex", [False, True])
def test_two_sessions_writing_one_instant_through_the_face(db_dsn: str, conn: Conn, same_vertex: bool) -> None:
    from tests.sessions import Background, connect, wait_until_blocked

    _class(conn, False)
    _switch(conn, "chunks")
    geoid = _series(conn)
    first = connect(db_dsn, "first")
    first.execute("SET extra_float_digits = 0")  # another setting than the second session's: the same chunk lock
    first.execute(
        "UPDATE tgsis.times_vrtx SET x = x + 1 WHERE geoid = %s AND times = 0.1::float8 + 0.2::float8 AND vrtxid = 1",
        (geoid,),
    )
    failures: list[str] = []

    def second_writer(session: Conn) -> None:
        try:
            session.execute(
                "UPDATE tgsis.times_vrtx SET x = x + 10 WHERE geoid = %s AND times = 0.1::float8 + 0.2::float8 AND vrtxid = %s",
                (geoid, 1 if same_vertex else 2),
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
    x = curved_surface().vertices[:3, 0] + 1 / 3.0
    got = [
        r[0]
        for r in conn.execute(
            "SELECT x FROM tgsis.times_vrtx WHERE geoid = %s AND times = 0.1::float8 + 0.2::float8 AND vrtxid IN (1, 2) ORDER BY vrtxid",
            (geoid,),
        ).fetchall()
    ]
    if same_vertex:  # the second read the row before the first's commit: its write would undo it
        assert failures == ["40001"]
        assert got == [x[1] + 1, x[2]]
    else:
        assert failures == []
        assert got == [x[1] + 1, x[2] + 10]


def test_a_role_with_fewer_rights_reads_and_cannot_write(db_dsn: str, conn: Conn) -> None:
    from tests.roles import login_roles

    _class(conn, True)
    _switch(conn, "chunks")
    geoid = _series(conn)
    with login_roles(db_dsn, {"reader": "tgsis_reader", "editor": "tgsis_editor"}) as roles:
        reader = roles.connect("reader")
        assert len(reader.execute("SELECT * FROM tgsis.vertices_at(%s, 2.0)", (geoid,)).fetchall()) == len(
            curved_surface().vertices
        )
        assert (
            sqlstate(reader, "UPDATE tgsis.times_vrtx SET x = 0 WHERE geoid = %s AND vrtxid = 1", (geoid,))[0]
            == "42501"
        )
        assert (
            sqlstate(
                reader,
                "SELECT tgsis.insert_chunk_rows('times_vrtx', '{geoid,vrtxid,times,x,y,z}', ARRAY[[%s],[9000]]::bigint[], "
                "'{{2.0},{0},{0},{0}}'::float8[])",
                (geoid,),
            )[0]
            == "42501"
        )
        assert sqlstate(reader, "UPDATE tgsis.times_vrtx_chunk SET x[1] = 0")[0] == "42501"
        assert sqlstate(reader, "SELECT tgsis.store_in_rows('times_vrtx')")[0] == "42501"
        editor = roles.connect("editor")
        series = tgsis.fetch_series(editor, "horizons", geoid)
        tgsis.add_instant(editor, "horizons", geoid, 7.0, series.surfaces[0])
        editor.commit()
    assert tgsis.fetch_series(conn, "horizons", geoid).times.tolist() == [*TIMES, 7.0]


def test_pg_dump_and_restore_keep_the_time_tables_in_chunks(pg: Any, db_dsn: str, conn: Conn, tmp_path: Any) -> None:
    from tests.test_backup import _bindir_of, _restored

    _class(conn, True)
    _switch(conn, "chunks")
    geoid = _series(conn)
    before = _answers(conn, geoid)
    chunks = "SELECT geoid, float8send(times), chunk, revision, lastrevs, array_send(x), array_send(y), array_send(z) FROM tgsis.times_vrtx_chunk ORDER BY 1, 2, 3, 4"
    stored = conn.execute(chunks).fetchall()
    conn.rollback()
    with _restored(pg, _bindir_of(pg), db_dsn, "custom", tmp_path) as dsn, psycopg.connect(dsn) as copy:
        assert copy.execute(chunks).fetchall() == stored
        assert copy.execute(
            "SELECT tgsis.stored_in_chunks('times_vrtx'), tgsis.stored_in_chunks('times_trgl')"
        ).fetchone() == (
            True,
            True,
        )
        assert _answers(copy, geoid) == before
        _switch(copy, "rows")
        assert _answers(copy, geoid) == before


# --------------------------------------------------------------------------- the client transfers model 2's chunks

#: a NaN with a payload of its own (a property value: kept bit for bit)
NAN_PAYLOAD = np.array([0x7FF8000000000123], dtype=np.int64).view(np.float64)[0]


def _hostile_series(times: tuple[float, ...] = TIMES, side: int = 40) -> SurfaceSeries:
    """A side x side curved grid (40: 2 vertex chunks, 3 triangle chunks) at ``times``, with -0.0, a subnormal, a
    large coordinate, and property values NaN (with a payload) and -0.0."""
    s = curved_surface(side)
    surfaces = []
    for i in range(len(times)):
        vertices = s.vertices + i / 3.0
        vertices[0] = (-0.0, -0.0, -0.0)
        vertices[5, 2], vertices[7, 0] = 5e-324, 2.5e15
        porosity = s.vertex_properties["porosity"].copy()
        porosity[3], porosity[4] = NAN_PAYLOAD, -0.0
        surfaces.append(tgsis.Surface(vertices, s.cells, vertex_properties={"porosity": porosity}))
    return SurfaceSeries(np.asarray(times), surfaces)


def _bits(values: Any) -> list[int]:
    return np.ascontiguousarray(values, dtype=np.float64).view(np.int64).ravel().tolist()


def _surface_bits(surface: tgsis.Surface | None) -> Any:
    if surface is None:
        return None
    return (
        _bits(surface.vertices),
        surface.cells.tolist(),
        sorted((k, _bits(v)) for k, v in surface.vertex_properties.items()),
    )


def _python_reads(conn: Conn, geoid: int) -> dict[str, Any]:
    """What the Python readers of model 2 give of the feature, doubles by their bits."""
    series = tgsis.fetch_series(conn, "horizons", geoid)
    reads: dict[str, Any] = {
        "times": _bits(series.times),
        "surfaces": [_surface_bits(s) for s in series.surfaces],
    }
    for t in (-0.0, 0.3, 0.1 + 0.2, 1.0, 2.0, 5.0, 7.0, 8.0):
        for convention in ("left", "right"):
            reads[f"get_at {t} {convention}"] = _surface_bits(
                tgsis.get_at(conn, geoid, t, convention=convention, properties=True)
            )
    reads["surfaces_at"] = {
        t: [_surface_bits(s)[:2] for g, s in sorted(tgsis.surfaces_at(conn, "horizons", t).items()) if g == geoid]
        for t in (0.3, 2.0)
    }
    conn.rollback()
    return reads


def _store(conn: Conn, to: str) -> None:
    """The time tables in ``to`` (whatever TGSIS_TEST_TIME_STORAGE made them)."""
    row = conn.execute("SELECT tgsis.stored_in_chunks('times_vrtx')").fetchone()
    if (row == (True,)) != (to == "chunks"):
        _switch(conn, to)


def _edits(conn: Conn, geoid: int) -> None:
    """psql edits through the faces that leave holes: a vertex far above the others (chunk 1's slots to it
    holes), a triangle deleted; then an instant added from Python."""
    conn.execute("INSERT INTO tgsis.times_vrtx VALUES (%s, 2.0, 2000, '-0'::float8, 1.5, 5e-324)", (geoid,))
    conn.execute("DELETE FROM tgsis.times_trgl WHERE geoid = %s AND times = 2.0 AND trglid = 5", (geoid,))
    conn.commit()
    tgsis.add_instant(conn, "horizons", geoid, 7.0, _hostile_series().surfaces[1])
    conn.commit()


def _insert_chunk_rows_calls(conn: Conn) -> int:
    row = conn.execute(
        "SELECT coalesce(sum(calls), 0) FROM pg_stat_xact_user_functions WHERE funcname = 'insert_chunk_rows'"
    ).fetchone()
    assert row is not None
    return int(row[0])


@pytest.mark.parametrize("versioned", [False, True])
def test_the_client_transfers_chunks_bit_for_bit(conn: Conn, versioned: bool, monkeypatch: Any) -> None:
    import tgsis.db._chunk_transfer as chunk_transfer

    _class(conn, versioned)
    _store(conn, "rows")
    on_rows = tgsis.insert_feature(conn, "horizons", _hostile_series())
    conn.commit()
    _edits(conn, on_rows)
    expected = _python_reads(conn, on_rows)
    assert expected["surfaces"][2][0][-3:] == _bits([-0.0, 1.5, 5e-324])  # the vertex far above the others
    assert len(expected["surfaces"][2][1]) == len(curved_surface(40).cells) - 1

    _store(conn, "chunks")
    # the readers take the instants' chunks (decoded by the client), not the faces
    reads: list[str] = []

    def spy(real: Any) -> Any:
        def instant_rows(connection: Conn, layout: Any, *args: Any, **kwargs: Any) -> Any:
            reads.append(layout.table)
            return real(connection, layout, *args, **kwargs)

        return instant_rows

    for module in ("tgsis.db.instants", "tgsis.db._temporal_common"):
        monkeypatch.setattr(f"{module}.instant_rows", spy(chunk_transfer.instant_rows))
    # an instant's chunks in several blocks (one chunk each), joined by the client
    monkeypatch.setattr(chunk_transfer, "INSTANT_BLOCK_BITS", 0)
    assert _python_reads(conn, on_rows) == expected  # rows converted by the switch, read from chunks
    snapshots = sum(1 for k, v in expected.items() if k.startswith("get_at") and v is not None)
    assert snapshots == 14  # (none after the last instant: not alive)
    # each reader read both tables' chunks (fetch_series, the snapshots, surfaces_at; more when consistent_read
    # read again because another transaction of the cluster completed meanwhile)
    assert min(reads.count("times_vrtx"), reads.count("times_trgl")) >= 1 + snapshots + 2
    # the upload encodes the instants' chunks in the client: one COPY per table, no tgsis.insert_chunk_rows
    conn.execute("SET track_functions = 'all'")
    tgsis.fetch_series(conn, "horizons", on_rows)  # (a transaction is open: the upload runs in a savepoint of it)
    on_chunks = tgsis.insert_feature(conn, "horizons", _hostile_series())
    assert _insert_chunk_rows_calls(conn) == 0
    stored = conn.execute(
        "SELECT float8send(times), chunk, revision, cardinality(x) FROM tgsis.times_vrtx_chunk WHERE geoid = %s "
        "ORDER BY times, chunk",
        (on_chunks,),
    ).fetchall()
    revision = 0 if not versioned else conn.execute("SELECT revision FROM tgsis.write_revision()").fetchone()[0]  # type: ignore[index]
    assert stored == [(struct.pack(">d", t), k, revision, 1024 if k == 0 else 576) for t in TIMES for k in (0, 1)]
    conn.commit()
    conn.execute("SET track_functions = 'all'")
    _edits(conn, on_chunks)
    assert _python_reads(conn, on_chunks) == expected
    # what the client encoded is what the server decodes: the faces give the same bits
    faces = (
        "SELECT float8send(times), vrtxid, float8send(x), float8send(y), float8send(z) FROM tgsis.times_vrtx "
        "WHERE geoid = %s ORDER BY times, vrtxid"
    )
    triangles = "SELECT float8send(times), trglid, vrtxid1, vrtxid2, vrtxid3 FROM tgsis.times_trgl WHERE geoid = %s ORDER BY 1, 2"
    assert conn.execute(faces, (on_chunks,)).fetchall() == conn.execute(faces, (on_rows,)).fetchall()
    assert conn.execute(triangles, (on_chunks,)).fetchall() == conn.execute(triangles, (on_rows,)).fetchall()
    conn.rollback()
    # and back to rows: the chunks written by the client give the rows the rows' upload wrote
    monkeypatch.undo()
    _store(conn, "rows")
    assert _python_reads(conn, on_chunks) == expected


@pytest.mark.parametrize("versioned", [False, True])
def test_an_instant_deleted_and_added_again_in_one_transaction(conn: Conn, versioned: bool) -> None:
    _class(conn, versioned)
    _store(conn, "chunks")
    series = _hostile_series(side=12)  # (a delete through the face rewrites a chunk per row: small)
    geoid = tgsis.insert_feature(conn, "horizons", series)
    conn.commit()
    if versioned:  # the instant's chunks of a saved revision: closed by the delete, kept
        tgsis.save_revision(conn, "uploaded")
        conn.commit()
    conn.execute("SET track_functions = 'all'")
    assert tgsis.delete_instant(conn, geoid, 2.0)
    tgsis.add_instant(conn, "horizons", geoid, 2.0, series.surfaces[0])
    left = conn.execute(
        "SELECT count(*) FROM tgsis.times_vrtx_chunk WHERE geoid = %s AND times = 2.0", (geoid,)
    ).fetchone()
    # unversioned, the delete removed the instant's chunks: the client's chunks go in; versioned, the closed
    # chunks of the saved revision stay (a new one's key would meet them): the server's writer takes the rows
    assert (left, _insert_chunk_rows_calls(conn)) == (((2,), 2) if versioned else ((1,), 0))
    conn.commit()
    got = tgsis.fetch_series(conn, "horizons", geoid)
    assert _bits(got.times) == _bits(TIMES)
    assert [_surface_bits(s) for s in got.surfaces] == [
        _surface_bits(s) for s in (series.surfaces[0], series.surfaces[1], series.surfaces[0])
    ]
    at = tgsis.get_at(conn, geoid, 2.0, properties=True)
    assert _surface_bits(at) == _surface_bits(series.surfaces[0])
    # a key visible already is still refused by name (the instant's row first: TG201)
    assert sqlstate(conn, "SELECT tgsis.add_instant(%s, 2.0)", (geoid,))[0] == "TG201"


def test_a_surface_changed_into_a_degenerate_one_is_refused_by_name(conn: Conn) -> None:
    """A triangle naming a vertex twice (changed after the surface was checked): the rows' CHECK
    (times_trgl_distinct_vertices) refused it with a raw 23514, the chunk table has none: the client's upload
    refuses it by name, nothing written."""
    _class(conn, False)
    _store(conn, "chunks")
    series = _hostile_series(side=12)
    series.surfaces[1].cells[3] = [2, 5, 2]
    counts = "SELECT (SELECT count(*) FROM tgsis.geometry), (SELECT count(*) FROM tgsis.times_trgl_chunk)"
    before = conn.execute(counts).fetchone()
    conn.rollback()
    with pytest.raises(tgsis.InvalidGeometryError, match=r"uses a vertex twice: \[2, 5, 2\]"):
        tgsis.insert_feature(conn, "horizons", series)
    conn.rollback()
    assert conn.execute(counts).fetchone() == before
