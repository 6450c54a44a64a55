"""Bulk transfer on chunks (issue 40, part 5): tgsis.db._chunk_transfer's upload and download of model-1 objects.

Nothing of today's storage calls these paths yet: the tests make the chunk
tables (``tgsis.create_chunk_table``) in the test database, upload through
the module, and read back through it, through the decoded face
(``tgsis.<t>_chunk_rows``) and through the raw chunk rows; content written
by the SQL writer (``tgsis.write_chunk_rows``: holes, a child's edit) is read
back through the module.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Iterable, Sequence
from typing import Any

import numpy as np
import numpy.typing as npt
import psycopg
import pytest
from psycopg import sql

import tgsis
import tgsis.db._chunk_transfer as transfer
from tests.roles import login_roles
from tgsis._chunks import from_copy
from tgsis.db._chunk_transfer import (
    ObjectRows,
    PackedChunks,
    chunk_table,
    download_chunks,
    download_tables,
    records_as_copy,
    rows_request,
    split_copy,
    upload_chunks,
)
from tgsis.db._transfer import Packed, Storage, columns_out_all
from tgsis.errors import AlreadyExistsError, InvalidInputError, NotFoundError, NotVersionedError
from tgsis.mesh import Surface

Conn = psycopg.Connection[Any]


def make_chunks(conn: Conn, tables: Iterable[str] = ("vrtx", "trgl")) -> None:
    """The chunk tables beside the rows; made by the storage switch already when the tables are stored in chunks."""
    for table in tables:
        if conn.execute("SELECT tgsis.stored_in_chunks(%s)", (table,)).fetchone() != (True,):
            conn.execute("SELECT tgsis.create_chunk_table(%s), tgsis.create_chunk_view(%s)", (table, table))
    conn.commit()


def odd_doubles(n: int, seed: int) -> npt.NDArray[np.float64]:
    """n doubles with -0.0, NaNs with payloads, infinities, subnormals and extremes among random ones."""
    rng = np.random.default_rng(seed)
    values = rng.normal(size=n) * 10.0 ** rng.integers(-300, 300, size=n)
    special = np.array(
        [-0.0, 0.0, np.inf, -np.inf, 5e-324, -5e-324, 2.2250738585072014e-308, 1.7976931348623157e308], dtype=np.float64
    )
    nans = np.array([0x7FF8000000000001, 0xFFF0000000000ABC, 0x7FF4000000000000], dtype=np.uint64).view(np.float64)
    picks = np.concatenate([special, nans])
    where = rng.choice(n, size=min(n, len(picks)), replace=False)
    values[where] = picks[: len(where)]
    return values


def vertices(geoid: int, ids: npt.ArrayLike, seed: int = 1) -> ObjectRows:
    ids = np.asarray(ids, dtype=np.int64)
    n = len(ids)
    return ObjectRows(
        geoid,
        ids,
        {"x": odd_doubles(n, seed), "y": odd_doubles(n, seed + 1), "z": odd_doubles(n, seed + 2)},
    )


def triangles(geoid: int, ids: npt.ArrayLike, corners: npt.NDArray[np.int64]) -> ObjectRows:
    return ObjectRows(
        geoid, np.asarray(ids, dtype=np.int64), {f"vrtxid{j + 1}": corners[:, j].astype(np.int64) for j in range(3)}
    )


def assert_same(got: ObjectRows, want: ObjectRows) -> None:
    """Same ids (got ascending) and the same values, doubles by bits."""
    order = np.argsort(want.ids, kind="stable")
    assert got.geoid == want.geoid
    assert np.array_equal(got.ids, want.ids[order])
    assert list(got.columns) == list(want.columns)
    for name, values in want.columns.items():
        mine = got.columns[name]
        assert mine.dtype == values.dtype, name
        if values.dtype == np.float64:
            assert np.array_equal(mine.view(np.uint64), values[order].view(np.uint64)), name
        else:
            assert np.array_equal(mine, values[order]), name


def face_rows(conn: Conn, table: str, geoid: int) -> list[tuple[Any, ...]]:
    """The decoded visible rows of one object through the face (doubles as their bits)."""
    ident, values = ("vrtxid", ["x", "y", "z"]) if table == "vrtx" else ("trglid", ["vrtxid1", "vrtxid2", "vrtxid3"])
    shown = [
        sql.SQL("float8send({})").format(sql.Identifier(v)) if table == "vrtx" else sql.Identifier(v) for v in values
    ]
    return [
        tuple(r)
        for r in conn.execute(
            sql.SQL(
                "SELECT {}, {} FROM tgsis.{} c WHERE geoid = %s "
                "AND (c.revision = ANY (tgsis.get_revisions(true))) IS TRUE AND NOT (c.lastrevs && tgsis.get_revisions(true)) "
                "ORDER BY 1"
            ).format(sql.Identifier(ident), sql.SQL(", ").join(shown), sql.Identifier(f"{table}_chunk_rows")),
            (geoid,),
        ).fetchall()
    ]


def write_rows(conn: Conn, table: str, rows: Sequence[Sequence[Any]], deletes: Sequence[tuple[int, int]] = ()) -> None:
    """Upserts and deletes through the SQL writer tgsis.write_chunk_rows."""
    conn.execute("DROP TABLE IF EXISTS pg_temp.transfer_rows")
    conn.execute(
        sql.SQL("CREATE TEMP TABLE transfer_rows (LIKE tgsis.{}, _delete boolean NOT NULL DEFAULT false)").format(
            sql.Identifier(table)
        )
    )
    width = len(conn.execute("SELECT * FROM pg_temp.transfer_rows LIMIT 0").description or []) - 1
    with conn.cursor().copy("COPY pg_temp.transfer_rows FROM STDIN") as copy:
        for row in rows:
            copy.write_row([*row, False])
        for geoid, ident in deletes:
            copy.write_row([geoid, ident, *([0] * (width - 2)), True])
    conn.execute("SELECT tgsis.write_chunk_rows(%s, 'pg_temp.transfer_rows')", (table,))


def grid(n: int) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.int64]]:
    """An n x n vertex grid and its 2 (n-1)^2 triangles."""
    u, v = np.meshgrid(np.arange(n, dtype=np.float64), np.arange(n, dtype=np.float64))
    xyz = np.stack([u.ravel(), v.ravel(), np.sin(u.ravel()) * 0.1], axis=1)
    i = (np.arange(n - 1)[:, None] * n + np.arange(n - 1)[None, :]).ravel()
    cells = np.concatenate([np.stack([i, i + 1, i + n], axis=1), np.stack([i + 1, i + n + 1, i + n], axis=1)])
    return xyz, cells.astype(np.int64)


# --------------------------------------------------------------------------- round trips


@pytest.mark.parametrize("versioned", [False, True], ids=["plain", "versioned"])
def test_upload_then_download_is_bit_exact_for_several_objects(conn: Conn, versioned: bool) -> None:
    if versioned:
        tgsis.enable_feature_versioning(conn)
        tgsis.create_version(conn, "other")  # DEFAULT's working revision is not 0 any more
    make_chunks(conn)
    rng = np.random.default_rng(3)
    objects = [
        vertices(101, np.arange(5000), seed=1),  # dense, 5 chunks, the last one partial
        vertices(102, rng.permutation(np.concatenate([np.arange(3, 900), [2**33, 2**33 + 5, 2**40]])), seed=4),
        vertices(103, [0], seed=9),
    ]
    cells = rng.integers(0, 5000, size=(7000, 3))
    cells[5000:5003] = [[0, 2**40, 7], [2**35, 1, 2**35 + 2], [3, 3, 2**31 + 9]]  # a chunk too wide for int4
    meshes = [triangles(101, np.arange(7000), cells), triangles(102, [5, 1024, 3000], np.array([[1, 2, 3]] * 3))]
    assert upload_chunks(conn, "vrtx", objects) == 5 + 3 + 1
    assert upload_chunks(conn, "trgl", meshes) == 7 + 3
    conn.commit()
    revision = conn.execute("SELECT tgsis.get_working_revision()").fetchone()
    expected = revision[0] if versioned and revision is not None else 0
    assert conn.execute("SELECT DISTINCT revision, lastrevs FROM tgsis.vrtx_chunk").fetchall() == [(expected, [])]
    assert conn.execute(
        "SELECT count(*) FROM tgsis.trgl_chunk WHERE vbase IS NULL AND vrtxid1_wide IS NOT NULL"
    ).fetchone() == (1,)
    # the uploaded objects are noted as changed in the working revision, as a COPY into <t>_ver notes them
    notes = conn.execute(
        "SELECT revision, tablename, objectkey FROM tgsis.revision_objects WHERE tablename IN ('vrtx', 'trgl') "
        "ORDER BY 2, 3"
    ).fetchall()
    if versioned:
        assert expected != 0
        assert notes == [(expected, "trgl", "101"), (expected, "trgl", "102")] + [
            (expected, "vrtx", str(g)) for g in (101, 102, 103)
        ]
    else:
        assert notes == []
    # several objects, one COPY per table, one snapshot; an object without chunks has no rows
    got = download_tables(conn, {"vrtx": [101, 102, 103, 999], "trgl": [102, 101]})
    for want in objects:
        assert_same(got["vrtx"][want.geoid], want)
        assert len(got["vrtx"][want.geoid].holes) == 0 or want.geoid == 102
    assert len(got["vrtx"][999].ids) == 0 and list(got["vrtx"][999].columns) == ["x", "y", "z"]
    for want in meshes:
        assert_same(got["trgl"][want.geoid], want)
    # the single-object path (no geoid column in the stream) gives the same
    alone = download_chunks(conn, "vrtx", [102])[102]
    assert_same(alone, objects[1])
    # holes: the absent ids inside stored chunks (chunk 0 of object 102 holds 3..899: ids 0..2 absent)
    assert alone.holes.tolist() == [0, 1, 2, 2**33 + 1, 2**33 + 2, 2**33 + 3, 2**33 + 4]
    assert got["vrtx"][101].array().shape == (5000, 3) and got["vrtx"][101].array().dtype == np.float64
    assert got["trgl"][101].array().shape == (7000, 3) and got["trgl"][101].array().dtype == np.int64
    # what the server decodes (the face) is what was uploaded
    assert face_rows(conn, "vrtx", 103) == [(0, *(v.tobytes()[::-1] for v in (objects[2].columns[c] for c in "xyz")))]
    assert [r[0] for r in face_rows(conn, "trgl", 101)] == list(range(7000))
    assert face_rows(conn, "trgl", 101)[5000:5003] == [(5000 + i, *map(int, cells[5000 + i])) for i in range(3)]


def test_upload_refuses_an_object_that_has_chunks_and_bad_input(conn: Conn) -> None:
    make_chunks(conn, ["vrtx"])
    upload_chunks(conn, "vrtx", [vertices(7, range(10))])
    conn.commit()
    with pytest.raises(AlreadyExistsError) as exists:
        upload_chunks(conn, "vrtx", [vertices(8, range(3)), vertices(7, [20])])
    assert exists.value.sqlstate == "TG201" and "[7]" in str(exists.value)
    conn.rollback()
    # even when only a closed or another version's chunk exists: an upload writes new objects only
    conn.execute("UPDATE tgsis.vrtx_chunk SET revision = 5, lastrevs = '{6}' WHERE geoid = 7")
    with pytest.raises(AlreadyExistsError):
        upload_chunks(conn, "vrtx", [vertices(7, [20])])
    conn.rollback()
    with pytest.raises(InvalidInputError):
        upload_chunks(conn, "vrtx", [vertices(8, range(3)), vertices(8, [20])])
    with pytest.raises(InvalidInputError):
        upload_chunks(conn, "vrtx", [vertices(8, [1, 1])])
    with pytest.raises(InvalidInputError):
        upload_chunks(conn, "vrtx", [ObjectRows(8, np.arange(2), {"x": np.zeros(2), "y": np.zeros(2)})])
    with pytest.raises(NotFoundError):  # atoms stay rows
        upload_chunks(conn, "atom", [ObjectRows(8, np.arange(1), {"refid": np.zeros(1, np.int64)})])
    with pytest.raises(NotFoundError):
        download_chunks(conn, "atom", [7])
    conn.rollback()
    assert conn.execute("SELECT geoid, count(*) FROM tgsis.vrtx_chunk GROUP BY 1").fetchall() == [(7, 1)]


def test_upload_writes_where_a_copy_into_storage_would(conn: Conn) -> None:
    """Plain storage in another version is refused (NotVersionedError) as today's COPY is; a class without
    versioning writes revision 0 in versioned storage."""
    make_chunks(conn, ["vrtx"])
    tgsis.create_version(conn, "child")
    tgsis.goto_version(conn, "child")
    with pytest.raises(NotVersionedError):
        upload_chunks(conn, "vrtx", [vertices(1, range(3))])
    conn.rollback()
    tgsis.goto_version(conn, "DEFAULT")
    tgsis.enable_feature_versioning(conn)
    tgsis.create_feature_class(conn, "loose", "SURFACE", versioned=False)
    fc = tgsis.get_feature_class(conn, "loose")
    upload_chunks(conn, "vrtx", [vertices(2, range(3))], Storage.of(conn, fc))
    conn.commit()
    assert conn.execute("SELECT revision FROM tgsis.vrtx_chunk WHERE geoid = 2").fetchall() == [(0,)]
    assert conn.execute("SELECT count(*) FROM tgsis.revision_objects WHERE tablename = 'vrtx'").fetchone() == (0,)
    # revision 0 is seen in every version, as the rows of such features are
    tgsis.create_version(conn, "other")
    tgsis.goto_version(conn, "other")
    assert download_chunks(conn, "vrtx", [2])[2].ids.tolist() == [0, 1, 2]


def test_holes_written_by_the_sql_writer_are_read_back(conn: Conn) -> None:
    make_chunks(conn, ["vrtx", "trgl"])
    upload_chunks(conn, "vrtx", [vertices(5, np.arange(3000), seed=2)])
    conn.commit()
    deleted = [0, 1, 500, 1023, 1024, 2047, 2999]  # a chunk's first and last slots, and the object's last id
    write_rows(conn, "vrtx", [(5, 4000, 1.5, -0.0, 2.5)], [(5, i) for i in deleted])
    write_rows(conn, "trgl", [(5, i, i, i + 1, i + 2) for i in (3, 9, 2000)])
    conn.commit()
    got = download_chunks(conn, "vrtx", [5])[5]
    want = vertices(5, np.arange(3000), seed=2)
    keep = ~np.isin(want.ids, deleted)
    assert np.array_equal(got.ids, np.concatenate([want.ids[keep], [4000]]))
    for c in "xyz":
        assert np.array_equal(got.columns[c][:-1].view(np.uint64), want.columns[c][keep].view(np.uint64))
    assert got.columns["y"][-1].tobytes() == np.float64(-0.0).tobytes()
    # holes: slots absent below each stored chunk's last present slot (chunk 2 now ends at id 2998; chunk 3 at 4000)
    assert got.holes.tolist() == [0, 1, 500, 1024, *range(3072, 4000)]
    cells = download_chunks(conn, "trgl", [5])[5]
    assert cells.ids.tolist() == [3, 9, 2000]
    assert cells.array().tolist() == [[3, 4, 5], [9, 10, 11], [2000, 2001, 2002]]
    assert cells.holes.tolist() == [0, 1, 2, *range(4, 9), *range(1024, 2000)]


def test_a_child_downloads_its_change_the_parent_its_content(conn: Conn) -> None:
    tgsis.enable_feature_versioning(conn)
    make_chunks(conn, ["vrtx"])
    base = vertices(11, np.arange(2500), seed=5)
    upload_chunks(conn, "vrtx", [base, vertices(12, np.arange(10), seed=6)])
    conn.commit()
    tgsis.create_version(conn, "child")
    tgsis.goto_version(conn, "child")
    write_rows(conn, "vrtx", [(11, 1500, 7.0, 8.0, 9.0), (11, 3000, 1.0, 2.0, 3.0)], [(11, 2)])
    conn.commit()
    child = download_tables(conn, {"vrtx": [11, 12]})["vrtx"]
    assert child[11].ids.tolist() == [i for i in range(2500) if i != 2] + [3000]
    at = int(np.searchsorted(child[11].ids, 1500))
    assert [child[11].columns[c][at] for c in "xyz"] == [7.0, 8.0, 9.0]
    assert_same(child[12], vertices(12, np.arange(10), seed=6))
    # a child upload of a new object is the child's; the parent does not see it
    upload_chunks(conn, "vrtx", [vertices(13, np.arange(4), seed=8)])
    conn.commit()
    assert len(download_chunks(conn, "vrtx", [13])[13].ids) == 4
    tgsis.goto_version(conn, "DEFAULT")
    parent = download_tables(conn, {"vrtx": [11, 12, 13]})["vrtx"]
    assert_same(parent[11], base)
    assert len(parent[13].ids) == 0
    # back in the child: its content again
    tgsis.goto_version(conn, "child")
    assert len(download_chunks(conn, "vrtx", [11])[11].ids) == 2500


def test_packed_chunks_read_what_download_reads_in_one_query_with_rows(conn: Conn) -> None:
    """PackedChunks, the chunk tables' part of columns_out_all (fetch_feature's one query): the child's and the
    parent's content as download_tables gives it, several objects (one without chunks), beside a Packed part."""
    tgsis.enable_feature_versioning(conn)
    make_chunks(conn, ["vrtx"])
    base = vertices(11, np.arange(2500), seed=5)
    upload_chunks(conn, "vrtx", [base, vertices(12, np.arange(10), seed=6)])
    conn.commit()
    tgsis.create_version(conn, "child")
    tgsis.goto_version(conn, "child")
    write_rows(conn, "vrtx", [(11, 1500, 7.0, 8.0, 9.0), (11, 3000, 1.0, 2.0, 3.0)], [(11, 2)])
    conn.commit()
    columns = [("vrtxid", "int8"), ("z", "float8"), ("x", "float8")]  # any order of the arrays
    for version in ("child", "DEFAULT"):
        tgsis.goto_version(conn, version)
        want = download_tables(conn, {"vrtx": [11, 12, 99]})["vrtx"]
        one, packed = columns_out_all(
            conn,
            [
                PackedChunks(chunk_table(conn, "vrtx"), [12, 11, 99], ["vrtxid", "z", "x"]),
                Packed(sql.SQL("tgsis.geometry"), "geoid", [("nvrtx", "int8")], [11]),
            ],
        )
        assert len(packed[0]) == 0  # no geometry rows: the Packed part answers beside it, empty
        for geoid in (11, 12):
            mine = one[0] == geoid
            order = np.argsort(one[1][mine])
            assert np.array_equal(one[1][mine][order], want[geoid].ids)
            for k, (name, _) in enumerate(columns[1:]):
                assert_same_bits(one[2 + k][mine][order], want[geoid].columns[name])
        assert 99 not in set(one[0].tolist())
        single = columns_out_all(conn, [rows_request(conn, "vrtx", columns, [11], frozenset({"vrtx"}))])[0]
        assert np.array_equal(np.sort(single[1]), want[11].ids)


def assert_same_bits(got: npt.NDArray[Any], want: npt.NDArray[Any]) -> None:
    assert got.dtype == want.dtype and np.array_equal(got.view(np.int64), want.view(np.int64))


def test_records_as_copy_refuses_cut_or_padded_records(conn: Conn) -> None:
    make_chunks(conn, ["vrtx"])
    upload_chunks(conn, "vrtx", [vertices(5, np.arange(1500), seed=2)])
    layout = chunk_table(conn, "vrtx")
    fields = sql.SQL(", ").join(sql.Identifier(c) for c in layout.columns.select_columns())
    with conn.cursor(binary=True) as cursor:
        count, data = cursor.execute(
            sql.SQL(
                "SELECT count(*), string_agg(record_send(ROW({})), ''::bytea) FROM tgsis.vrtx_chunk WHERE geoid = 5"
            ).format(fields)
        ).fetchone()  # type: ignore[misc]
    data = bytes(data)
    got = from_copy(records_as_copy(data, count), layout.columns)
    assert_same(ObjectRows(5, *got.rows()), vertices(5, np.arange(1500), seed=2))
    with pytest.raises(InvalidInputError, match="end inside a record"):
        records_as_copy(data[:-3], count)
    with pytest.raises(InvalidInputError, match="bytes after"):
        records_as_copy(data + b"\x00", count)
    with pytest.raises(InvalidInputError):
        records_as_copy(data, count + 1)
    conn.rollback()


def test_two_uploads_of_one_new_object_one_is_refused(db_dsn: str, conn: Conn) -> None:
    """The second waits for the first's chunk keys, then is refused by name: the object has its chunks."""
    make_chunks(conn, ["vrtx"])
    first = psycopg.connect(db_dsn)
    second = psycopg.connect(db_dsn)
    try:
        upload_chunks(first, "vrtx", [vertices(41, range(2000), seed=1)])  # open: holds the new keys
        result: list[Any] = []

        def run() -> None:
            try:
                result.append(upload_chunks(second, "vrtx", [vertices(41, range(10), seed=2)]))
            except Exception as exc:  # handed to the test's thread
                result.append(exc)

        worker = threading.Thread(target=run)
        worker.start()
        deadline = time.monotonic() + 60
        while True:
            row = conn.execute(
                "SELECT wait_event_type FROM pg_stat_activity WHERE pid = %s", (second.info.backend_pid,)
            ).fetchone()
            conn.rollback()
            if row is not None and row[0] == "Lock":
                break
            assert worker.is_alive() and time.monotonic() < deadline, result
            time.sleep(0.05)
        first.commit()
        worker.join(60)
        assert len(result) == 1 and isinstance(result[0], AlreadyExistsError), result
        assert result[0].sqlstate == "TG201"
        second.rollback()
    finally:
        first.close()
        second.close()
    assert_same(download_chunks(conn, "vrtx", [41])[41], vertices(41, range(2000), seed=1))


# --------------------------------------------------------------------------- rights


def test_roles_read_and_write_with_their_own_rights(db_dsn: str, conn: Conn) -> None:
    tgsis.create_feature_class(conn, "alpha", "SURFACE")
    tgsis.create_feature_class(conn, "beta", "SURFACE")
    triangle = Surface(np.eye(3), np.array([[0, 1, 2]]))
    alpha = tgsis.insert_feature(conn, "alpha", triangle)
    beta = tgsis.insert_feature(conn, "beta", triangle)
    other = tgsis.insert_feature(conn, "alpha", triangle)
    conn.execute("REVOKE ALL ON beta FROM tgsis_reader, tgsis_editor, tgsis_admin, PUBLIC")
    conn.commit()
    make_chunks(conn)
    # the features' own chunks (written by insert_feature once the tables are stored in chunks) make way
    conn.execute("DELETE FROM tgsis.vrtx_chunk")
    conn.execute("DELETE FROM tgsis.trgl_chunk")
    upload_chunks(conn, "vrtx", [vertices(alpha, range(10)), vertices(beta, range(4))])
    conn.commit()
    with login_roles(db_dsn, {"reader": "tgsis_reader", "editor": "tgsis_editor"}) as roles:
        reader = roles.connect("reader")
        got = download_tables(reader, {"vrtx": [alpha, beta]})["vrtx"]
        assert_same(got[alpha], vertices(alpha, range(10)))
        assert len(got[beta].ids) == 0  # the class the role may not read: nothing
        assert len(download_chunks(reader, "vrtx", [beta])[beta].ids) == 0
        with pytest.raises(psycopg.errors.InsufficientPrivilege):
            upload_chunks(reader, "vrtx", [vertices(other, range(3))])
        reader.rollback()
        editor = roles.connect("editor")
        # into a class it may write: through a staged table (COPY is refused under row-level security)
        assert upload_chunks(editor, "vrtx", [vertices(other, range(1500))]) == 2
        editor.commit()
        assert_same(download_chunks(reader, "vrtx", [other])[other], vertices(other, range(1500)))
        # not into a revoked class's chunks, nor by two objects one of which is revoked's
        with pytest.raises(psycopg.errors.InsufficientPrivilege):
            upload_chunks(editor, "trgl", [triangles(beta, [0], np.array([[0, 1, 2]]))])
        editor.rollback()
        with pytest.raises(psycopg.errors.InsufficientPrivilege):
            upload_chunks(
                editor,
                "trgl",
                [triangles(alpha, [0], np.array([[0, 1, 2]])), triangles(beta, [0], np.array([[0, 1, 2]]))],
            )
        editor.rollback()
    assert conn.execute("SELECT count(*) FROM tgsis.trgl_chunk").fetchone() == (0,)


# --------------------------------------------------------------------------- sessions and snapshots


def test_odd_session_settings_change_nothing(conn: Conn) -> None:
    make_chunks(conn)
    want = vertices(21, np.arange(1200), seed=3)
    upload_chunks(conn, "vrtx", [want])
    conn.commit()
    conn.execute("SET extra_float_digits = -15")
    conn.execute("SET DateStyle = 'SQL, DMY'")
    conn.execute("SET search_path = ''")
    conn.execute("SET bytea_output = 'escape'")
    conn.commit()
    assert_same(download_tables(conn, {"vrtx": [21, 22]})["vrtx"][21], want)
    cells = triangles(22, np.arange(5), np.arange(15).reshape(5, 3))
    upload_chunks(conn, "trgl", [cells])
    conn.commit()
    assert_same(download_chunks(conn, "trgl", [22])[22], cells)
    assert conn.execute("SELECT current_setting('search_path')").fetchone() == ('""',)


@pytest.mark.parametrize(
    "inside", ["outside a transaction", "with a side connection", "inside repeatable read", "inside read committed"]
)
def test_tables_are_read_in_one_snapshot_while_a_writer_commits(
    db_dsn: str, conn: Conn, monkeypatch: pytest.MonkeyPatch, inside: str
) -> None:
    """A writer commits a new object's vertices and triangles after the download's first statement: its COPYs
    (on one connection, or one of them on a side connection) see neither; in the caller's own READ COMMITTED
    transaction (a snapshot per statement) the download sees the commit and reads again (consistent_read), so
    that its COPYs see both."""
    make_chunks(conn)
    xyz, cells = grid(40)
    upload_chunks(conn, "vrtx", [ObjectRows(31, np.arange(1600), {c: xyz[:, i].copy() for i, c in enumerate("xyz")})])
    upload_chunks(conn, "trgl", [triangles(31, np.arange(len(cells)), cells)])
    conn.commit()
    reader = psycopg.connect(db_dsn)
    writer = psycopg.connect(db_dsn)
    real = transfer.chunk_table
    calls: list[str] = []

    def chunk_table_then_a_writer(connection: Conn, table: str) -> transfer.ChunkTable:
        if connection is not reader:  # the writer's own uploads
            return real(connection, table)
        calls.append(table)
        if calls == ["vrtx", "trgl"]:  # after the download's first statement, before its COPYs (once)
            upload_chunks(writer, "vrtx", [vertices(32, range(3))])
            upload_chunks(writer, "trgl", [triangles(32, [0], np.array([[0, 1, 2]]))])
            writer.commit()
        return real(connection, table)

    try:
        if inside == "inside repeatable read":
            reader.execute("SET TRANSACTION ISOLATION LEVEL REPEATABLE READ")
            reader.execute("SELECT 1")
        elif inside == "inside read committed":
            reader.execute("SELECT 1")
        monkeypatch.setattr(transfer, "chunk_table", chunk_table_then_a_writer)
        # with a side connection: the triangles' COPY runs there, in the snapshot the reader exports to it
        side = psycopg.connect(db_dsn) if inside == "with a side connection" else None
        got = download_tables(reader, {"vrtx": [31, 32], "trgl": [31, 32]}, side=side)
        if side is not None:
            assert side.info.transaction_status == psycopg.pq.TransactionStatus.IDLE
            side.close()
        monkeypatch.undo()
        assert calls == ["vrtx", "trgl"] * (2 if inside == "inside read committed" else 1)
        assert len(got["vrtx"][31].ids) == 1600 and len(got["trgl"][31].ids) == len(cells)
        # the download's first statement (the tables' layouts) ran before the writer's commit, its COPYs after
        if inside == "inside read committed":  # a snapshot per statement: read again after the commit
            assert (len(got["vrtx"][32].ids), len(got["trgl"][32].ids)) == (3, 1)
        else:
            assert (len(got["vrtx"][32].ids), len(got["trgl"][32].ids)) == (0, 0)
        reader.rollback()
        after = download_tables(reader, {"vrtx": [32], "trgl": [32]})
        assert len(after["vrtx"][32].ids) == 3 and len(after["trgl"][32].ids) == 1
    finally:
        reader.close()
        writer.close()


def test_a_side_connection_reads_the_session_s_version_with_the_same_role(db_dsn: str, conn: Conn) -> None:
    tgsis.enable_feature_versioning(conn)
    make_chunks(conn)
    upload_chunks(conn, "vrtx", [vertices(51, np.arange(1500), seed=1)])
    upload_chunks(conn, "trgl", [triangles(51, np.arange(3), np.arange(9).reshape(3, 3))])
    conn.commit()
    tgsis.create_version(conn, "child")
    tgsis.goto_version(conn, "child")
    write_rows(conn, "trgl", [(51, 1, 7, 8, 9)], [(51, 0)])
    conn.commit()
    side = psycopg.connect(db_dsn)  # its session is in DEFAULT: the child's set is what it reads with
    try:
        got = download_tables(conn, {"vrtx": [51], "trgl": [51]}, side=side)
        assert got["trgl"][51].array().tolist() == [[7, 8, 9], [6, 7, 8]]
        assert_same(got["vrtx"][51], vertices(51, np.arange(1500), seed=1))
        assert download_tables(side, {"trgl": [51]})["trgl"][51].array().tolist() == [[0, 1, 2], [3, 4, 5], [6, 7, 8]]
        side.execute("SELECT 1")  # inside a transaction: refused
        with pytest.raises(InvalidInputError):
            download_tables(conn, {"vrtx": [51], "trgl": [51]}, side=side)
        side.rollback()
    finally:
        side.close()
    with login_roles(db_dsn, {"reader": "tgsis_reader"}) as roles:
        other = roles.connect("reader")  # another role: it would read with other rights
        with pytest.raises(InvalidInputError):
            download_tables(conn, {"vrtx": [51], "trgl": [51]}, side=other)


def test_split_copy_refuses_what_is_not_a_stream_of_geoid_rows() -> None:
    with pytest.raises(InvalidInputError):
        split_copy(b"not a copy stream at all")
    header = b"PGCOPY\n\xff\r\n\x00" + bytes(8)
    row = (2).to_bytes(2, "big") + (4).to_bytes(4, "big") + bytes(4) + (8).to_bytes(4, "big") + bytes(8)
    with pytest.raises(InvalidInputError):
        split_copy(header + row + b"\xff\xff")  # the first field is no bigint
    good = (2).to_bytes(2, "big") + (8).to_bytes(4, "big") + (7).to_bytes(8, "big") + (8).to_bytes(4, "big") + bytes(8)
    assert split_copy(header + good + b"\xff\xff") == {7: header + (1).to_bytes(2, "big") + good[14:] + b"\xff\xff"}
    with pytest.raises(InvalidInputError):
        split_copy(header + good[:-3])
