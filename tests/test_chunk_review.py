"""Hostile review of issue 40's foundation (chunk codec, SQL chunk tables, the writer): cases that broke it.

Each test here failed on main before its fix (or is marked xfail strict with the fix it needs).
"""

from __future__ import annotations

import threading
import time
from typing import Any

import numpy as np
import psycopg
import pytest
from psycopg import sql

import tgsis
from tgsis._chunks import ChunkColumns, encode, from_copy, to_copy
from tgsis.errors import InvalidInputError

Conn = psycopg.Connection[Any]

# the chunk foundation: builds chunk tables beside the row tables, or switches them (docs/testing.md, the mark storage)
pytestmark = pytest.mark.storage("rows")

TRGL = ChunkColumns(("vrtxid1", "vrtxid2", "vrtxid3"), refs=("vrtxid1", "vrtxid2", "vrtxid3"))
XYZ = ChunkColumns(("x", "y", "z"))
INT4_MAX = 2**31 - 1


def make_chunks(conn: Conn, tables: tuple[str, ...]) -> None:
    for table in tables:
        conn.execute("SELECT tgsis.create_chunk_table(%s), tgsis.create_chunk_view(%s)", (table, table))
    conn.commit()


def vertices(ids: range, scale: float) -> list[tuple[Any, ...]]:
    return [(1, i, i * scale, -i * scale, 0.5 + i) for i in ids]


def visible_vertices(conn: Conn) -> list[tuple[Any, ...]]:
    return [
        tuple(r)
        for r in conn.execute(
            "SELECT geoid, vrtxid, x, y, z FROM tgsis.vrtx_chunk_rows c WHERE NOT revclosed ORDER BY 1, 2"
        ).fetchall()
    ]


def _rows_table(conn: Conn, name: str, table: str, rows: list[tuple[Any, ...]]) -> None:
    """A temporary table ``name`` LIKE tgsis.<table> plus _delete, holding ``rows`` (none deleted)."""
    conn.execute(
        sql.SQL("CREATE TEMP TABLE {} (LIKE tgsis.{}, _delete boolean NOT NULL DEFAULT false)").format(
            sql.Identifier(name), sql.Identifier(table)
        )
    )
    with conn.cursor().copy(sql.SQL("COPY pg_temp.{} FROM STDIN").format(sql.Identifier(name))) as copy:
        for row in rows:
            copy.write_row([*row, False])


@pytest.mark.parametrize("name", ["rows{cc}", "k", "v", "m{vis}", 'q"{K}'])
def test_writer_reads_the_rows_table_it_is_given_whatever_its_name(conn: Conn, name: str) -> None:
    """The writer's statement is a template whose {placeholders} were replaced one after the other, longest
    first, so a placeholder inside the rows table's name was replaced too (``rows{cc}`` became ``rowsvrtxid``:
    another table was read than the one checked); and the table's name was unqualified, so a temporary table
    named like one of the statement's CTEs (k, v, m...) was read as that CTE."""
    make_chunks(conn, ("vrtx",))
    given = vertices(range(0, 30), scale=2.0)
    _rows_table(conn, name, "vrtx", given)
    if name == "rows{cc}":  # what the name becomes once {cc} is replaced: rows that no check looked at
        _rows_table(conn, "rowsvrtxid", "vrtx", vertices(range(100, 130), scale=-1.0))
    written = conn.execute(
        "SELECT tgsis.write_chunk_rows('vrtx', %s::regclass)", (sql.Identifier("pg_temp", name).as_string(conn),)
    ).fetchone()
    assert written == (1,)
    assert visible_vertices(conn) == sorted(given)


def _copy_rows(conn: Conn, name: str, table: str, types: list[str], ids: Any, columns: list[Any]) -> None:
    conn.execute(
        sql.SQL("CREATE TEMP TABLE {} (LIKE tgsis.{}, _delete boolean NOT NULL DEFAULT false)").format(
            sql.Identifier(name), sql.Identifier(table)
        )
    )
    names = [
        c[0]
        for c in conn.execute(sql.SQL("SELECT * FROM pg_temp.{} LIMIT 0").format(sql.Identifier(name))).description
        or []
    ]
    query = sql.SQL("COPY pg_temp.{} ({}) FROM STDIN (FORMAT BINARY)").format(
        sql.Identifier(name), sql.SQL(", ").join(map(sql.Identifier, names[:-1]))
    )
    with conn.cursor(binary=True).copy(query) as copy:
        copy.set_types(["int8", "int8", *types])
        for i, row in enumerate(ids.tolist()):
            copy.write_row([1, row, *(c[i] for c in columns)])


def _server_copy(conn: Conn, table: str, spec: ChunkColumns) -> bytes:
    query = sql.SQL(
        "COPY (SELECT {} FROM tgsis.{} WHERE geoid = 1 AND NOT revclosed ORDER BY chunk) TO STDOUT (FORMAT binary)"
    ).format(sql.SQL(", ").join(map(sql.Identifier, spec.copy_columns())), sql.Identifier(f"{table}_chunk"))
    out = bytearray()
    with conn.cursor().copy(query) as copy:
        for block in copy:
            out += block
    return bytes(out)


def test_the_sql_writer_and_the_codec_write_the_same_bytes(conn: Conn) -> None:
    """tgsis.write_chunk_rows and tgsis._chunks.encode/to_copy make the same chunk rows for the same rows, byte for
    byte: holes, arrays' ends, vbase or _wide (at the int4 bounds of both differences), doubles' bits."""
    make_chunks(conn, ("vrtx", "trgl"))
    rng = np.random.default_rng(40)
    # triangles: chunk 0 dense, chunk 1 with holes (one alone in the middle), chunks at the int4 bounds, one wide
    tids = [
        *range(0, 1024),
        *(1024 + s for s in (0, 1, 500, 1023)),
        5 * 1024 + 7,
        6 * 1024,
        6 * 1024 + 1,
        7 * 1024 + 3,
        8 * 1024,
        8 * 1024 + 2,
        2**40 + 5,
    ]
    corners: list[list[int]] = []
    for _t in tids:
        base = int(rng.integers(0, 2**30)) + (2**40 if _t > 2**32 else 0)
        corners.append([base, base + 1, base + 2 + int(rng.integers(0, 50))])
    corners[tids.index(5 * 1024 + 7)] = [7, 7 + INT4_MAX, 6]  # vK - v1 = INT4_MAX: fits
    corners[tids.index(6 * 1024)] = [INT4_MAX, 0, 1]  # v1 - vbase = INT4_MAX: fits
    corners[tids.index(6 * 1024 + 1)] = [3, 4, 5]
    corners[tids.index(7 * 1024 + 3)] = [INT4_MAX + 1, 0, 1]  # v1 - vbase = INT4_MAX + 1: wide
    corners[tids.index(8 * 1024)] = [2**62, 2**62 + 1, 2**53]  # far apart: wide
    corners[tids.index(8 * 1024 + 2)] = [2**62 + 2, 2**62 + 3, 2**62 + 4]
    ids = np.array(tids, dtype=np.int64)
    c = np.array(corners, dtype=np.int64)
    _copy_rows(conn, "tri", "trgl", ["int8"] * 3, ids, [c[:, 0].tolist(), c[:, 1].tolist(), c[:, 2].tolist()])
    conn.execute("SELECT tgsis.write_chunk_rows('trgl', 'pg_temp.tri')")
    expected = encode(ids, {f"vrtxid{k + 1}": c[:, k] for k in range(3)}, TRGL)
    assert expected.wide.tolist().count(True) == 2
    assert _server_copy(conn, "trgl", TRGL) == to_copy(expected, 1, 0)
    # vertices: odd doubles (NaN payloads, -0.0, subnormals, infinities), ids with holes up to 2**53
    odd = np.array(
        [
            0x8000000000000000,
            0x7FF8000000000123,
            0xFFF80000DEADBEEF,
            1,
            0x000FFFFFFFFFFFFF,
            0x7FF0000000000000,
            0xFFF0000000000000,
            0x7FF0000000000001,
        ],
        dtype=np.uint64,
    ).view(np.float64)
    vids = np.array([*range(0, 3000, 3), 2**31 - 1, 2**31, 2**31 + 1, 2**53, 2**53 + 1023], dtype=np.int64)
    xyz = rng.normal(size=(len(vids), 3))
    xyz[: len(odd), 0] = odd
    xyz[-len(odd) :, 2] = odd
    _copy_rows(conn, "vtx", "vrtx", ["float8"] * 3, vids, [xyz[:, 0].tolist(), xyz[:, 1].tolist(), xyz[:, 2].tolist()])
    conn.execute("SELECT tgsis.write_chunk_rows('vrtx', 'pg_temp.vtx')")
    expected = encode(vids, {a: xyz[:, k].copy() for k, a in enumerate("xyz")}, XYZ)
    assert _server_copy(conn, "vrtx", XYZ) == to_copy(expected, 1, 0)


def _sqlstate(conn: Conn, statement: str) -> str | None:
    try:
        with conn.transaction():
            conn.execute(statement)
    except psycopg.Error as exc:
        return exc.sqlstate
    return None


@pytest.mark.parametrize(
    ("table", "columns", "values"),
    [
        # a numeric corner was rounded (1.5 stored as 2) where the row table's bigint cannot hold 1.5
        ("trgl", "geoid bigint, trglid bigint, vrtxid1 numeric, vrtxid2 bigint, vrtxid3 bigint", "(1, 0, 1.5, 3, 4)"),
        # a numeric geoid: the chunk inserted under geoid 2, looked for under 1.5, five rounds, then 40001 "retry"
        ("vrtx", "geoid numeric, vrtxid bigint, x float8, y float8, z float8", "(1.5, 0, 1, 2, 3)"),
        # a text id: 42883 (no operator), not ours
        ("vrtx", "geoid bigint, vrtxid text, x float8, y float8, z float8", "(1, '7', 1, 2, 3)"),
        # a real coordinate: widened (0.1f is not 0.1): the caller's rows are not the row table's
        ("vrtx", "geoid bigint, vrtxid bigint, x real, y float8, z float8", "(1, 0, 0.1, 2, 3)"),
    ],
)
def test_writer_refuses_rows_of_other_types_by_name(conn: Conn, table: str, columns: str, values: str) -> None:
    make_chunks(conn, (table,))
    conn.execute(f"CREATE TEMP TABLE typed ({columns}, _delete boolean NOT NULL DEFAULT false)")
    conn.execute(f"INSERT INTO typed SELECT *, false FROM (VALUES {values}) v")
    conn.commit()
    assert _sqlstate(conn, f"SELECT tgsis.write_chunk_rows('{table}', 'pg_temp.typed')") == "TG100"
    assert conn.execute(
        sql.SQL("SELECT count(*) FROM tgsis.{}").format(sql.Identifier(f"{table}_chunk"))
    ).fetchone() == (0,)


def _waits_for_a_lock(conn: Conn, pid: int) -> bool:
    row = conn.execute("SELECT wait_event_type FROM pg_stat_activity WHERE pid = %s", (pid,)).fetchone()
    conn.rollback()
    return row is not None and row[0] == "Lock"


def test_writer_reads_its_rows_once_checked_not_again_changed(db_dsn: str, conn: Conn) -> None:
    """The writer checks its rows (NULLs, negative ids, keys twice) in one statement and writes them in later ones:
    a table that other sessions write (or a view over one) changed in between. The writer waited for a chunk's
    lock after the check; a key given twice meanwhile made the chunk's arrays one element too long (every later
    id shifted: silently another surface). It now takes only a temporary table of the session (TG100 otherwise)."""
    make_chunks(conn, ("vrtx",))
    conn.execute("CREATE TABLE public.shared (LIKE tgsis.vrtx, _delete boolean NOT NULL DEFAULT false)")
    conn.execute("INSERT INTO public.shared SELECT 1, i, i, -i, 0.5 + i, false FROM generate_series(0, 99) i")
    conn.execute("CREATE VIEW public.shared_view AS SELECT * FROM public.shared")
    conn.commit()
    for name in ("public.shared", "public.shared_view"):
        assert _sqlstate(conn, f"SELECT tgsis.write_chunk_rows('vrtx', '{name}')") == "TG100", name
    # the same rows through a temporary table: written
    conn.execute("CREATE TEMP TABLE mine AS SELECT * FROM public.shared")
    assert conn.execute("SELECT tgsis.write_chunk_rows('vrtx', 'pg_temp.mine')").fetchone() == (1,)
    conn.commit()
    expected = sorted(vertices(range(0, 100), scale=1.0))
    assert visible_vertices(conn) == expected

    # why: a writer of the shared table, waiting for the chunk's lock after its check, wrote a key given twice
    conn.execute("UPDATE public.shared SET x = x + 1000 WHERE vrtxid = 10")
    conn.commit()
    first = psycopg.connect(db_dsn)
    second = psycopg.connect(db_dsn)
    try:
        first.execute("CREATE TEMP TABLE one AS SELECT * FROM public.shared WHERE vrtxid = 20")
        first.execute("SELECT tgsis.write_chunk_rows('vrtx', 'pg_temp.one')")  # open: holds chunk 0's lock
        pid = second.info.backend_pid
        result: list[Any] = []

        def run() -> None:
            try:
                result.append(second.execute("SELECT tgsis.write_chunk_rows('vrtx', 'public.shared')").fetchone())
                second.commit()
            except psycopg.Error as exc:
                result.append(exc.sqlstate)
                second.rollback()

        worker = threading.Thread(target=run)
        worker.start()
        for _ in range(1200):
            if not worker.is_alive() or _waits_for_a_lock(conn, pid):
                break
            time.sleep(0.05)
        conn.execute("INSERT INTO public.shared VALUES (1, 10, -7, -7, -7, false)")  # vrtxid 10 twice
        conn.commit()
        first.commit()
        worker.join(60)
        assert result == ["TG100"]
    finally:
        first.close()
        second.close()
    assert visible_vertices(conn) == expected
    layout = conn.execute(
        "SELECT cardinality(x), cardinality(y), holes FROM tgsis.vrtx_chunk WHERE geoid = 1"
    ).fetchall()
    assert layout == [(100, 100, None)]


def _select_stream(conn: Conn, select: str) -> bytes:
    out = bytearray()
    with conn.cursor().copy(f"COPY ({select}) TO STDOUT (FORMAT binary)") as copy:
        for block in copy:
            out += block
    return bytes(out)


_ONE = "NULL::smallint[], {0}::float8[], {0}::float8[], {0}::float8[]"
_REFS = "NULL::smallint[], {0}, {1}::int[], '{{1,1}}'::int[], '{{2,2}}'::int[], {2}::bigint[], NULL::bigint[], NULL::bigint[]"
REFUSED = {
    # arrays the contract does not make: lower bound 0, two dimensions, in any column
    "lower bound 0": (XYZ, "SELECT 0::bigint, " + _ONE.format("'[0:1]={1,2}'")),
    "2-D": (XYZ, "SELECT 0::bigint, " + _ONE.format("'{{1,2},{3,4}}'")),
    "2-D holes": (
        XYZ,
        "SELECT 0::bigint, '{{2}}'::smallint[], '{1,NULL,3}'::float8[], '{1,NULL,3}'::float8[], '{1,NULL,3}'::float8[]",
    ),
    "trailing NULL": (XYZ, "SELECT 0::bigint, " + _ONE.format("'{1,NULL}'")),
    # accepted on main: arrays longer than a chunk (ids 1024.. of chunk 0 are chunk 1's: a chunk table of another
    # chunksize, which the registry allows, read as 1024), a negative chunk, negative vertex ids
    "1500 elements": (
        XYZ,
        "SELECT 0::bigint, NULL::smallint[], a, a, a "
        "FROM (SELECT array_agg(i::float8) a FROM generate_series(1, 1500) i) s",
    ),
    "negative chunk": (XYZ, "SELECT -1::bigint, " + _ONE.format("'{1}'")),
    "negative vbase": (TRGL, "SELECT 0::bigint, " + _REFS.format("-5::bigint", "'{0,1}'", "NULL")),
    "negative wide id": (
        TRGL,
        "SELECT 0::bigint, NULL::smallint[], NULL::bigint, NULL::int[], NULL::int[], NULL::int[], '{-1}'::bigint[], "
        "'{2}'::bigint[], '{3}'::bigint[]",
    ),
}


@pytest.mark.parametrize("case", sorted(REFUSED))
def test_the_parser_refuses_server_arrays_that_break_the_contract(conn: Conn, case: str) -> None:
    """Streams made by the server (COPY ... TO STDOUT (FORMAT binary) of crafted arrays), not by the codec."""
    spec, select = REFUSED[case]
    with pytest.raises(InvalidInputError):
        from_copy(_select_stream(conn, select), spec)


def test_the_chunk_size_cannot_change_under_a_chunk_table(conn: Conn) -> None:
    make_chunks(conn, ("vrtx",))
    conn.execute("CREATE TEMP TABLE mine (LIKE tgsis.vrtx, _delete boolean NOT NULL DEFAULT false)")
    conn.execute("INSERT INTO mine SELECT 1, i, i, -i, 0.5 + i, false FROM generate_series(0, 1500) i")
    conn.execute("SELECT tgsis.write_chunk_rows('vrtx', 'pg_temp.mine')")
    conn.commit()
    state = _sqlstate(conn, "UPDATE tgsis.model_tables SET chunksize = 2048 WHERE tablename = 'vrtx'")
    if state is None:  # what follows on main: the writer writes 2048-id chunks that the face reads as 1024
        conn.execute("TRUNCATE mine")
        conn.execute("INSERT INTO mine VALUES (1, 1500, 7, 7, 7, false)")
        conn.execute("SELECT tgsis.write_chunk_rows('vrtx', 'pg_temp.mine')")
        got = conn.execute("SELECT x FROM tgsis.vrtx_chunk_rows WHERE vrtxid = 1500 AND NOT revclosed").fetchall()
        conn.rollback()
        assert got == [(7.0,)]
    assert state == "TG202"
    # the other layout columns, a rename and a deletion of the row are refused alike; a table without chunks is free
    for statement in (
        "UPDATE tgsis.model_tables SET chunkcolumn = 'vrtxid' || '' , chunkrefs = '{x}' WHERE tablename = 'vrtx'",
        "UPDATE tgsis.model_tables SET tablename = 'vrtx2' WHERE tablename = 'vrtx'",
        "DELETE FROM tgsis.model_tables WHERE tablename = 'vrtx'",
    ):
        assert _sqlstate(conn, statement) == "TG202", statement
    assert _sqlstate(conn, "UPDATE tgsis.model_tables SET chunksize = 2048 WHERE tablename = 'trgl'") is None
    conn.rollback()
    # a description is not the layout: it may change
    assert _sqlstate(conn, "UPDATE tgsis.model_tables SET description = description WHERE tablename = 'vrtx'") is None
    conn.rollback()


def test_writers_in_two_versions_of_one_chunk_keep_their_own_content(db_dsn: str, conn: Conn) -> None:
    """Two versions (two working revisions) change the same chunk of the parent at once: each closes the parent's
    version for itself (lastrevs gets both), each sees its own content; the parent keeps its own."""
    tgsis.enable_feature_versioning(conn)
    make_chunks(conn, ("vrtx",))
    conn.execute(
        "CREATE TEMP TABLE base AS SELECT 1::bigint AS geoid, i::bigint AS vrtxid, i::float8 AS x, "
        "(-i)::float8 AS y, (0.5 + i)::float8 AS z, false AS _delete FROM generate_series(0, 99) i"
    )
    conn.execute("SELECT tgsis.write_chunk_rows('vrtx', 'pg_temp.base')")
    conn.commit()
    tgsis.create_version(conn, "one")
    tgsis.create_version(conn, "two")
    sessions = {name: psycopg.connect(db_dsn) for name in ("one", "two")}
    try:
        for name, session in sessions.items():
            tgsis.goto_version(session, name)
            session.execute(
                "CREATE TEMP TABLE mine AS SELECT 1::bigint AS geoid, %s::bigint AS vrtxid, 999.0::float8 AS x, "
                "9.0::float8 AS y, 9.0::float8 AS z, false AS _delete",
                (10 if name == "one" else 20,),
            )
        one, two = sessions["one"], sessions["two"]
        assert one.execute("SELECT tgsis.write_chunk_rows('vrtx', 'pg_temp.mine')").fetchone() == (1,)
        result: list[Any] = []

        def run() -> None:
            try:
                result.append(two.execute("SELECT tgsis.write_chunk_rows('vrtx', 'pg_temp.mine')").fetchone())
                two.commit()
            except psycopg.Error as exc:
                result.append(exc.sqlstate)

        worker = threading.Thread(target=run)
        worker.start()
        for _ in range(1200):
            if not worker.is_alive() or _waits_for_a_lock(conn, two.info.backend_pid):
                break
            time.sleep(0.05)
        one.commit()
        worker.join(60)
        assert result == [(1,)]
        for name, session in sessions.items():
            rows = session.execute(
                "SELECT vrtxid, x FROM tgsis.vrtx_chunk_rows c WHERE x = 999 "
                "AND (c.revision = ANY (tgsis.get_revisions(true))) IS TRUE AND NOT (c.lastrevs && tgsis.get_revisions(true))"
            ).fetchall()
            session.rollback()
            assert rows == [(10 if name == "one" else 20, 999.0)], name
    finally:
        for session in sessions.values():
            session.close()
    parent = conn.execute(
        "SELECT geoid, vrtxid, x, y, z FROM tgsis.vrtx_chunk_rows c WHERE (c.revision = ANY (tgsis.get_revisions(true))) "
        "IS TRUE AND NOT (c.lastrevs && tgsis.get_revisions(true)) ORDER BY 1, 2"
    ).fetchall()
    assert [tuple(r) for r in parent] == sorted(vertices(range(0, 100), scale=1.0))
    closed = conn.execute("SELECT cardinality(lastrevs) FROM tgsis.vrtx_chunk WHERE revclosed").fetchall()
    assert closed == [(2,)]


def test_the_decoded_face_reads_the_largest_ids(conn: Conn) -> None:
    """id 2^63 - 1 is slot 1024 of chunk 2^53 - 1: (chunk << 10) + slot overflowed before the - 1 (22003)."""
    make_chunks(conn, ("vrtx", "trgl"))
    top = 2**63 - 1
    ids = [0, 2**31 - 1, 2**31, 2**53, 2**62, top - 1, top]
    _rows_table(conn, "mine", "vrtx", [(1, i, float(k), 0.0, -0.0) for k, i in enumerate(ids)])
    conn.execute("SELECT tgsis.write_chunk_rows('vrtx', 'pg_temp.mine')")
    assert [r[0] for r in conn.execute("SELECT vrtxid FROM tgsis.vrtx_chunk_rows ORDER BY 1").fetchall()] == ids
    _rows_table(conn, "tri", "trgl", [(1, top, top - 2, top, top - 1), (1, 0, top, 0, 1)])
    conn.execute("SELECT tgsis.write_chunk_rows('trgl', 'pg_temp.tri')")
    got = conn.execute("SELECT trglid, vrtxid1, vrtxid2, vrtxid3 FROM tgsis.trgl_chunk_rows ORDER BY 1").fetchall()
    assert got == [(0, top, 0, 1), (top, top - 2, top, top - 1)]
    # the relational face decodes as the view does (it kept the overflow while it had a copy of the view's decoding)
    conn.execute("SELECT tgsis.create_chunk_face('vrtx', 'vrtx_face'), tgsis.create_chunk_face('trgl', 'trgl_face')")
    assert [r[0] for r in conn.execute("SELECT vrtxid FROM tgsis.vrtx_face ORDER BY 1").fetchall()] == ids
    got = conn.execute("SELECT trglid, vrtxid1, vrtxid2, vrtxid3 FROM tgsis.trgl_face ORDER BY 1").fetchall()
    assert got == [(0, top, 0, 1), (top, top - 2, top, top - 1)]


def test_the_codec_takes_big_endian_doubles_bit_for_bit() -> None:
    """A float64 column in big-endian order (a binary VTK or COPY buffer viewed as >f8) is float64: it was refused
    ("must be float64, got >f8"); its bits (NaN payloads, a signalling NaN, -0.0, a subnormal) are kept."""
    bits = np.array(
        [0x7FF8000000000123, 0xFFF80000DEADBEEF, 0x7FF4000000000001, 0x8000000000000000, 1], dtype=np.uint64
    )
    native = bits.view(np.float64)
    big = native.astype(">f8")
    chunks = encode(np.arange(5, dtype=">i8"), {"x": big, "y": native, "z": big}, XYZ)
    ids, cols = chunks.rows()
    assert ids.tolist() == [0, 1, 2, 3, 4]
    for name in "xyz":
        assert cols[name].dtype == np.float64 and cols[name].view(np.uint64).tolist() == bits.tolist()
    assert to_copy(chunks, 1) == to_copy(encode(np.arange(5), {c: native for c in "xyz"}, XYZ), 1)


@pytest.mark.parametrize(("table", "refs"), [("point", 1), ("segment", 2), ("tetra", 4)])
def test_after_upserts_and_deletes_the_writer_s_chunks_are_the_codec_s_bytes(conn: Conn, table: str, refs: int) -> None:
    """Three writes (inserts, moves of corners far away and back, deletes that empty slots, a chunk's last slot and a
    whole chunk): the chunk rows are byte for byte what the codec encodes from the rows that remain."""
    make_chunks(conn, (table,))
    spec = ChunkColumns(tuple(f"vrtxid{k + 1}" for k in range(refs)), refs=tuple(f"vrtxid{k + 1}" for k in range(refs)))
    ident = {"point": "pointid", "segment": "segid", "tetra": "tetraid"}[table]
    rng = np.random.default_rng(refs)
    state: dict[int, list[int]] = {}
    for step in range(3):
        ids = rng.choice(6000, size=2500, replace=False)
        if step == 2:
            ids = ids[(ids < 2048) | (ids >= 3072)]
        corners = np.sort(rng.choice(2**20, size=(len(ids), refs)), axis=1) + np.arange(refs)  # distinct corners
        far = rng.random(len(ids)) < (0.002 if step < 2 else 0.0)
        corners[far, -1] += 2**33  # a few corners beyond int4 of their chunk: _wide, then back in the last write
        deletes = [i for i in rng.choice(6000, size=800, replace=False).tolist() if i not in set(ids.tolist())]
        if step == 2:
            deletes = sorted({*deletes, *(i for i in state if 2048 <= i < 3072)})  # and a whole chunk
        name = f"rows{step}"
        conn.execute(
            sql.SQL("CREATE TEMP TABLE {} (LIKE tgsis.{}, _delete boolean NOT NULL DEFAULT false)").format(
                sql.Identifier(name), sql.Identifier(table)
            )
        )
        with conn.cursor().copy(sql.SQL("COPY pg_temp.{} FROM STDIN").format(sql.Identifier(name))) as copy:
            for i, c in zip(ids.tolist(), corners.tolist(), strict=True):
                copy.write_row([1, i, *c, False])
                state[i] = c
            for i in deletes:
                copy.write_row([1, i, *range(refs), True])
                state.pop(i, None)
        conn.execute("SELECT tgsis.write_chunk_rows(%s, %s::regclass)", (table, f"pg_temp.{name}"))
        keys = np.array(sorted(state), dtype=np.int64)
        values = np.array([state[int(k)] for k in keys], dtype=np.int64).reshape(len(keys), refs)
        expected = encode(keys, {f"vrtxid{k + 1}": values[:, k] for k in range(refs)}, spec)
        assert _server_copy(conn, table, spec) == to_copy(expected, 1, 0), (table, step, ident)


def test_writer_called_in_odd_statement_shapes_and_settings(conn: Conn) -> None:
    """From an SQL function, inside a CTE, with an empty search_path, extra columns in the rows, and settings that
    change plans and text output (held on main)."""
    make_chunks(conn, ("vrtx",))
    conn.execute("CREATE TEMP TABLE extra (LIKE tgsis.vrtx, _delete boolean NOT NULL DEFAULT false, note text)")
    conn.execute("INSERT INTO extra SELECT 1, i, i, 'NaN', '-0', false, 'x' FROM generate_series(0, 2999) i")
    conn.execute(
        "CREATE FUNCTION pg_temp.write_extra() RETURNS bigint LANGUAGE sql AS "
        "$$ SELECT tgsis.write_chunk_rows('vrtx', 'pg_temp.extra') $$"
    )
    conn.execute("SET LOCAL search_path = ''")
    conn.execute("SET LOCAL extra_float_digits = -15")
    conn.execute(
        "SET LOCAL enable_hashagg = off; SET LOCAL enable_hashjoin = off; SET LOCAL enable_sort = off; SET LOCAL jit = off"
    )
    assert conn.execute("SELECT pg_temp.write_extra()").fetchone() == (3,)
    conn.execute("UPDATE pg_temp.extra SET x = -x, _delete = (vrtxid % 7 = 0)")
    assert conn.execute(
        "WITH w AS (SELECT tgsis.write_chunk_rows('vrtx', 'pg_temp.extra') AS n) SELECT n FROM w"
    ).fetchone() == (3,)
    kept = [i for i in range(3000) if i % 7]
    got = conn.execute(
        "SELECT count(*), sum(x) = %s, bool_and(float8send(y) = float8send('NaN')), "
        "bool_and(float8send(z) = float8send('-0')) FROM tgsis.vrtx_chunk_rows",
        (-float(sum(kept)),),
    ).fetchone()
    assert got == (len(kept), True, True, True)


@pytest.mark.parametrize("versioned", [False, True])
def test_two_writers_of_the_same_slot_the_second_wins_and_nothing_else_moves(
    db_dsn: str, conn: Conn, versioned: bool
) -> None:
    """Same slot, two sessions: the second waits for the first's lock, then reads what it committed and writes
    over it, as two UPDATEs of one row would (no lost update of the other slots, one live version)."""
    if versioned:
        tgsis.enable_feature_versioning(conn)
    make_chunks(conn, ("vrtx",))
    _rows_table(conn, "base", "vrtx", vertices(range(0, 50), scale=1.0))
    conn.execute("SELECT tgsis.write_chunk_rows('vrtx', 'pg_temp.base')")
    conn.commit()
    if versioned:
        tgsis.create_version(conn, "child")
    sessions = [psycopg.connect(db_dsn), psycopg.connect(db_dsn)]
    try:
        for k, session in enumerate(sessions):
            if versioned:
                tgsis.goto_version(session, "child")
            _rows_table(session, "mine", "vrtx", [(1, 10, 100.0 + k, 0.0, 0.0), (1, 20 + k, 7.0, 7.0, 7.0)])
        first, second = sessions
        first.execute("SELECT tgsis.write_chunk_rows('vrtx', 'pg_temp.mine')")
        result: list[Any] = []

        def run() -> None:
            try:
                result.append(second.execute("SELECT tgsis.write_chunk_rows('vrtx', 'pg_temp.mine')").fetchone())
                second.commit()
            except psycopg.Error as exc:
                result.append(exc.sqlstate)

        worker = threading.Thread(target=run)
        worker.start()
        waited = False
        for _ in range(1200):
            waited = _waits_for_a_lock(conn, second.info.backend_pid)
            if waited or not worker.is_alive():
                break
            time.sleep(0.05)
        first.commit()
        worker.join(60)
        assert waited and result == [(1,)]
        rows = second.execute(
            "SELECT vrtxid, x FROM tgsis.vrtx_chunk_rows c WHERE (c.revision = ANY (tgsis.get_revisions(true))) IS TRUE "
            "AND NOT (c.lastrevs && tgsis.get_revisions(true)) AND vrtxid IN (10, 20, 21) ORDER BY 1"
        ).fetchall()
        live = second.execute("SELECT count(*) FROM tgsis.vrtx_chunk WHERE NOT revclosed").fetchone()
        second.rollback()
    finally:
        for session in sessions:
            session.close()
    assert rows == [(10, 101.0), (20, 7.0), (21, 7.0)]
    assert live == (1,)
