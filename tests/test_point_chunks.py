"""The points of G-maps (models 4 and 5) stored in chunks: the role ``point`` (issue 40, plan M, P).

docs/storage.md, "The points in chunks: the layout chosen": ``tgsis.md_vertex``
(keyed (geoid, chunk) by vrtxid) and ``tgsis.gmap_vertex`` ((geoid, timem,
timet, chunk) by nodeid) hold one 2-D ``double precision[]`` per chunk
version, slots x m, m the object's embedding; a hole is a row of m NULLs.
``tgsis.store_in_chunks`` / ``tgsis.store_in_rows`` switch them with their data
and back, the faces read and write them bit for bit as the row tables do, and
an object whose points are not all of one length is refused by name before
anything moves.
"""

from __future__ import annotations

import struct
from typing import Any

import psycopg
import pytest

import tgsis
from tests.merge_data import sqlstate
from tests.storage_data import tables_as_rows
from tests.test_gmap_chunks import _answers, _store

Conn = psycopg.Connection[Any]

POINTS = ("gmap_vertex", "md_vertex")
#: the G-map tables a test switches, darts and involutions with the points (a G-map in chunks whole)
TABLES = ("gmap_dart", "gmap_alpha", "md_dart", "md_alpha", *POINTS)
#: the faces' rows, every coordinate by its bits (array_send)
ROWS = {
    "gmap_vertex": "SELECT geoid, float8send(timem), float8send(timet), nodeid, array_send(coordinate) FROM tgsis.gmap_vertex"
    " ORDER BY geoid, timem, timet, nodeid",
    "md_vertex": "SELECT geoid, vrtxid, array_send(coordinate) FROM tgsis.md_vertex ORDER BY geoid, vrtxid",
}
#: doubles whose bits a text round trip or a comparison by = would lose: -0.0, a subnormal, a NaN with a payload
ODD = (-0.0, 5e-324, struct.unpack("<d", struct.pack("<Q", 0x7FF8_0000_0000_0ABC))[0])


@pytest.fixture(autouse=True)
def _gmaps_as_rows(conn: Conn) -> None:
    """The G-map tables as rows at each test's start, whatever TGSIS_TEST_TIME_STORAGE made them."""
    tables_as_rows(conn, TABLES)


def _switch(conn: Conn, to: str, tables: tuple[str, ...] = TABLES) -> None:
    for table in tables if to == "chunks" else reversed(tables):
        conn.execute(f"SELECT tgsis.store_in_{to}(%s)", (table,))
    conn.commit()


def _rows(conn: Conn) -> dict[str, list[tuple[Any, ...]]]:
    with conn.cursor(binary=True) as cursor:
        return {table: cursor.execute(query).fetchall() for table, query in ROWS.items()}


def _odd_points(conn: Conn, g4: int, g5: int) -> None:
    """Points whose coordinates are -0.0 and a subnormal, written through the faces."""
    # (the Python readers of _answers refuse a NaN point; model 4 interpolates between instants, where a
    # subnormal underflows on rows and chunks alike: NaN goes through the faces in the write test. -0.0 where it is
    # the largest value: an extent's min of -0.0 and 0.0 is whichever its scan meets first, on rows as on chunks)
    conn.execute(
        "UPDATE tgsis.md_vertex SET coordinate = ARRAY[0.5, %s, %s, 0.5]::float8[] WHERE geoid = %s AND vrtxid = 7",
        (ODD[1], ODD[0], g5),
    )
    conn.execute(
        "UPDATE tgsis.gmap_vertex SET coordinate = ARRAY[0.5, 2.5, 1.5]::float8[] WHERE geoid = %s AND nodeid = 1"
        " AND timet = 1.0",
        (g4,),
    )


def _same(got: dict[str, Any], expected: dict[str, Any]) -> None:
    """``got == expected`` for :func:`_everywhere`'s answers, naming the first answer that differs."""
    for version, (answers, rows) in expected.items():
        for name in answers:
            assert got[version][0][name] == answers[name], (version, name)
        for table in rows:
            assert got[version][1][table] == rows[table], (version, table)
    assert got == expected


def _everywhere(conn: Conn, g4: int, g5: int, versions: tuple[str, ...]) -> dict[str, Any]:
    found = {}
    for version in versions:
        with tgsis.in_version(conn, version):
            rows = _rows(conn)  # (first: _answers ends its transaction, and the version's setting with it)
            found[version] = (_answers(conn, g4, g5), rows)
        conn.rollback()
    return found


@pytest.mark.parametrize("versioned", [False, True])
def test_the_switch_and_back_keep_every_point_bit_for_bit(conn: Conn, versioned: bool) -> None:
    g4, g5 = _store(conn, versioned)
    versions: tuple[str, ...] = ("DEFAULT",)
    if versioned:  # a version whose psql user moves points to odd bits
        tgsis.create_version(conn, "e1")
        conn.commit()
        with tgsis.in_version(conn, "e1"):
            _odd_points(conn, g4, g5)
        conn.commit()
        versions = ("DEFAULT", "e1")
    else:
        _odd_points(conn, g4, g5)
        conn.commit()
    before = _everywhere(conn, g4, g5, versions)
    if versioned:
        assert before["e1"][1] != before["DEFAULT"][1]
    indexes = _indexes(conn)
    assert (
        "md_vertex_point_idx",
        "CREATE INDEX md_vertex_point_idx ON tgsis.{} USING gist (cube(coordinate))"
        " WHERE (NOT ('NaN'::double precision = ANY (coordinate)))",
    ) in {
        (name, definition.replace("md_vertex_ver ", "{} ").replace("md_vertex ", "{} ")) for name, definition in indexes
    }, indexes
    _switch(conn, "chunks")
    assert conn.execute(
        "SELECT bool_and(tgsis.stored_in_chunks(t)) FROM unnest(%s::text[]) t", (list(POINTS),)
    ).fetchone() == (True,)
    conn.execute("SELECT tgsis.check_chunk_conversion(t) FROM unnest(%s::text[]) t", (list(POINTS),))
    # the layout: (geoid, chunk) and (geoid, timem, timet, chunk); one 2-D double array per chunk, m the object's
    for table, key in (
        ("md_vertex", ["geoid", "chunk", "revision"]),
        ("gmap_vertex", ["geoid", "timem", "timet", "chunk", "revision"]),
    ):
        assert conn.execute(
            "SELECT array_agg(a.attname::text ORDER BY k.o) FROM pg_constraint c CROSS JOIN LATERAL unnest(c.conkey)"
            " WITH ORDINALITY k(n, o) JOIN pg_attribute a ON a.attrelid = c.conrelid AND a.attnum = k.n"
            " WHERE c.conrelid = %s::regclass AND c.contype = 'p'",
            (f"tgsis.{table}_chunk",),
        ).fetchone() == (key,)
    dims = conn.execute(
        "SELECT DISTINCT array_ndims(c.coordinate), array_length(c.coordinate, 2), g.embedding"
        " FROM tgsis.md_vertex_chunk c JOIN tgsis.md_gmap g USING (geoid)"
    ).fetchall()
    assert dims == [(2, 4, 4)]
    conn.commit()
    _same(_everywhere(conn, g4, g5, versions), before)
    _switch(conn, "rows")
    _same(_everywhere(conn, g4, g5, versions), before)
    # the row tables' own indexes (model 5's per-point GiST index) made again by name, as they were
    assert _indexes(conn) == indexes


def _indexes(conn: Conn) -> list[tuple[str, str]]:
    """Every index of the G-map point tables' row storage (versioned or not): name and definition."""
    return conn.execute(
        "SELECT c.relname::text, pg_get_indexdef(i.indexrelid) FROM pg_index i JOIN pg_class c ON c.oid = i.indexrelid"
        " WHERE i.indrelid = ANY (ARRAY(SELECT tgsis.storage_table('tgsis', t)::regclass FROM unnest(%s::text[]) t))"
        " ORDER BY 1",
        (list(POINTS),),
    ).fetchall()


STATEMENTS = (
    # (table, statement with %(g)s the object): each run on rows and on chunks, the faces compared by bits
    (
        "md_vertex",
        "UPDATE tgsis.md_vertex SET coordinate = coordinate || ARRAY[]::float8[] WHERE geoid = %(g)s AND vrtxid < 5",
    ),
    ("md_vertex", "UPDATE tgsis.md_vertex SET coordinate[4] = -0.0 WHERE geoid = %(g)s AND vrtxid %% 3 = 0"),
    ("md_vertex", "DELETE FROM tgsis.md_vertex WHERE geoid = %(g)s AND vrtxid IN (2, 10, 59)"),
    (
        "md_vertex",
        "INSERT INTO tgsis.md_vertex VALUES (%(g)s, 10, '{1,2,3,4}'), (%(g)s, 2000, ARRAY[%(nan)s, -0.0, 5e-324, 1])",
    ),
    ("md_vertex", "UPDATE tgsis.md_vertex SET vrtxid = vrtxid + 3000 WHERE geoid = %(g)s AND vrtxid BETWEEN 20 AND 25"),
    (
        "gmap_vertex",
        "UPDATE tgsis.gmap_vertex SET coordinate = ARRAY[coordinate[2], coordinate[1], -coordinate[3]]"
        " WHERE geoid = %(g)s AND timet = 2.0",
    ),
    ("gmap_vertex", "DELETE FROM tgsis.gmap_vertex WHERE geoid = %(g)s AND timet = 3.0 AND nodeid %% 2 = 1"),
    ("gmap_vertex", "INSERT INTO tgsis.gmap_vertex VALUES (%(g)s, 1.0, 3.0, 1025, '{7,8,9}')"),
)


def test_face_writes_answer_as_the_row_tables(conn: Conn) -> None:
    g4, g5 = _store(conn, False)
    objects = {"md_vertex": g5, "gmap_vertex": g4}

    def run() -> list[Any]:
        seen = []
        for table, statement in STATEMENTS:
            cursor = conn.execute(statement, {"g": objects[table], "nan": ODD[2]})
            seen.append((cursor.rowcount, _rows(conn)[table]))
        conn.rollback()
        return seen

    on_rows = run()
    _switch(conn, "chunks")
    assert run() == on_rows
    unchanged = _rows(conn)
    conn.rollback()
    # a point of another length than its chunk's, or of none: refused by name, nothing written
    for statement in (
        "INSERT INTO tgsis.md_vertex VALUES (%(g)s, 5000, '{1,2,3}')",
        "UPDATE tgsis.md_vertex SET coordinate = coordinate || 1.0::float8 WHERE geoid = %(g)s AND vrtxid = 1",
        "INSERT INTO tgsis.md_vertex VALUES (%(g)s, 6000, '{}')",
    ):
        state, message = sqlstate(conn, statement, {"g": g5})
        assert state == "TG100" and "not all of one length" in message, (statement, message)
        conn.rollback()
    # model 1's object writers carry no point arrays: refused by name, not written otherwise
    for call in (
        "SELECT tgsis.write_object_rows('md_vertex', %s, '{}', '{1}', '{{0}}', '{{0}}')",
        "SELECT tgsis.object_chunks_stage('md_vertex')",
        "SELECT tgsis.swap_object_chunks('md_vertex', %s, '{0}', '{NULL}')",
    ):
        state, message = sqlstate(conn, call, (g5,) if "%s" in call else ())
        assert state == "TG100" and "does not write: coordinate" in message, (call, message)
        conn.rollback()
    assert _rows(conn) == unchanged
    conn.rollback()
    _switch(conn, "rows")
    assert _rows(conn) == unchanged


@pytest.mark.parametrize("versioned", [False, True])
def test_an_object_of_points_of_two_lengths_is_refused_before_anything_moves(conn: Conn, versioned: bool) -> None:
    g4, g5 = _store(conn, versioned)
    conn.execute("UPDATE tgsis.md_vertex SET coordinate = '{1,2,3}' WHERE geoid = %s AND vrtxid = 4", (g5,))
    conn.execute("UPDATE tgsis.gmap_vertex SET coordinate = '{}' WHERE geoid = %s AND nodeid = 2 AND timet = 0", (g4,))
    conn.commit()
    before = _rows(conn)
    for table, named in (
        ("md_vertex", f"object {g5}: the point ({g5}, 4) has 3 coordinates"),
        ("gmap_vertex", f"object {g4}: the point ({g4}, 0, 0, 2) has 0 coordinates"),
    ):
        with pytest.raises(psycopg.Error) as refused:
            conn.execute("SELECT tgsis.store_in_chunks(%s)", (table,))
        conn.rollback()
        assert refused.value.sqlstate == "TG100" and "not all of one length" in str(refused.value)
        assert named in (refused.value.diag.message_detail or ""), refused.value.diag.message_detail
        assert conn.execute(
            "SELECT tgsis.stored_in_chunks(%s), to_regclass(%s)", (table, f"tgsis.{table}_chunk")
        ).fetchone() == (False, None)
    assert _rows(conn) == before
    # mended, the object goes
    conn.execute("UPDATE tgsis.md_vertex SET coordinate = '{1,2,3,0}' WHERE geoid = %s AND vrtxid = 4", (g5,))
    conn.execute("DELETE FROM tgsis.gmap_vertex WHERE geoid = %s AND nodeid = 2 AND timet = 0", (g4,))
    conn.commit()
    fixed = _rows(conn)
    _switch(conn, "chunks", POINTS)
    assert _rows(conn) == fixed


def test_the_server_upload_writes_points_into_chunks(conn: Conn) -> None:
    _switch(conn, "chunks")
    g4, g5 = _store(conn, True)
    answers = _answers(conn, g4, g5)
    rows = _rows(conn)
    conn.rollback()
    _switch(conn, "rows")
    assert _answers(conn, g4, g5) == answers
    assert _rows(conn) == rows


def test_pg_dump_and_restore_keep_the_points_in_chunks(pg: Any, db_dsn: str, conn: Conn, tmp_path: Any) -> None:
    from tests.test_backup import _bindir_of, _restored

    g4, g5 = _store(conn, True)
    _switch(conn, "chunks")
    before = _rows(conn)
    chunks = [
        "SELECT geoid, chunk, revision, lastrevs, holes, array_send(coordinate) FROM tgsis.md_vertex_chunk ORDER BY 1, 2, 3",
        "SELECT geoid, timem, timet, chunk, revision, holes, array_send(coordinate) FROM tgsis.gmap_vertex_chunk"
        " ORDER BY 1, 2, 3, 4, 5",
    ]
    stored = [conn.execute(q).fetchall() for q in chunks]
    conn.rollback()
    with _restored(pg, _bindir_of(pg), db_dsn, "custom", tmp_path) as dsn, psycopg.connect(dsn) as copy:
        assert [copy.execute(q).fetchall() for q in chunks] == stored
        assert _rows(copy) == before
        _switch(copy, "rows")
        assert _rows(copy) == before


def _checked(conn: Conn, *geoids: int) -> list[tuple[Any, ...]]:
    """tgsis.check_geometry's problems of each object, in order."""
    return [
        (g, *r)
        for g in geoids
        for r in conn.execute("SELECT * FROM tgsis.check_geometry(%s) ORDER BY 1", (g,)).fetchall()
    ]


@pytest.mark.parametrize("versioned", [False, True])
def test_an_object_of_points_of_one_other_length_than_its_embedding_goes_as_on_rows(
    conn: Conn, versioned: bool
) -> None:
    """Points all of one length other than the object's embedding: the row table holds them and
    tgsis.check_geometry reports them; chunks hold them too (m per chunk is the points', not the embedding's), so
    the switch takes them, bit for bit, check_geometry says the same, and the repair (every point given its
    embedding's length through the face) and a write of the stored length answer as on the rows twin."""
    g4, g5 = _store(conn, versioned)
    conn.execute("UPDATE tgsis.md_vertex SET coordinate = coordinate[1:3] WHERE geoid = %s", (g5,))
    conn.execute("UPDATE tgsis.gmap_vertex SET coordinate = coordinate || ARRAY[-0.0] WHERE geoid = %s", (g4,))
    conn.commit()
    stored, problems = _rows(conn), _checked(conn, g4, g5)
    assert {r[0] for r in problems} == {g4, g5}, problems

    def other_length() -> None:  # a write keeping the object's stored length
        conn.execute("UPDATE tgsis.md_vertex SET coordinate = %s WHERE geoid = %s AND vrtxid = 2", ([*ODD], g5))
        conn.execute("UPDATE tgsis.gmap_vertex SET coordinate = %s WHERE geoid = %s AND nodeid = 1", ([*ODD, 1.0], g4))

    def repair() -> None:  # every point given its embedding's length
        conn.execute("UPDATE tgsis.md_vertex SET coordinate = coordinate || ARRAY[0.0] WHERE geoid = %s", (g5,))
        conn.execute("UPDATE tgsis.gmap_vertex SET coordinate = coordinate[1:3] WHERE geoid = %s", (g4,))

    twin = {}
    for name, write in (("other length", other_length), ("repair", repair)):
        write()
        twin[name] = (_rows(conn), _checked(conn, g4, g5))
        conn.rollback()
    assert all("refresh_geometry" in p[1] for p in twin["repair"][1]), twin["repair"][1]  # the lengths mended
    _switch(conn, "chunks", POINTS)
    assert _rows(conn) == stored and _checked(conn, g4, g5) == problems
    assert conn.execute(
        "SELECT DISTINCT array_length(c.coordinate, 2), g.embedding FROM tgsis.md_vertex_chunk c"
        " JOIN tgsis.md_gmap g USING (geoid) WHERE geoid = %s",
        (g5,),
    ).fetchall() == [(3, 4)]
    conn.commit()
    for name, write in (("other length", other_length), ("repair", repair)):
        write()
        assert (_rows(conn), _checked(conn, g4, g5)) == twin[name], name
        conn.rollback()
    _switch(conn, "rows", POINTS)
    assert _rows(conn) == stored
