"""Chunk tables in SQL (issue 40, part 2): the registry, tgsis.create_chunk_table, the decoded face, the writer.

The contract is /work/helpers/CHUNKS.md, written into docs/storage.md ("Chunks
and the mapping of ids", "Versioning of chunks"). Nothing in today's storage
paths uses chunk tables yet: these tests create them and drive the writer
(``tgsis.write_chunk_rows``) directly, and read what it wrote through the
decoded face (``tgsis.<table>_chunk_rows``) and the raw arrays.
"""

from __future__ import annotations

import json
import struct
import threading
import time
from collections.abc import Iterable, Sequence
from typing import Any

import numpy as np
import psycopg
import pytest
from psycopg import sql

import tgsis
from tests.roles import login_roles
from tgsis.mesh import Surface

Conn = psycopg.Connection[Any]

# the chunk foundation: builds chunk tables beside the row tables, or switches them (docs/testing.md, the mark storage)
pytestmark = pytest.mark.storage("rows")

MODEL1 = {
    "vrtx": ("vrtxid", []),
    "point": ("pointid", ["vrtxid1"]),
    "segment": ("segid", ["vrtxid1", "vrtxid2"]),
    "trgl": ("trglid", ["vrtxid1", "vrtxid2", "vrtxid3"]),
    "tetra": ("tetraid", ["vrtxid1", "vrtxid2", "vrtxid3", "vrtxid4"]),
}
INT4_MAX = 2**31 - 1


def _make_chunks(conn: Conn, tables: Iterable[str] = MODEL1) -> None:
    for table in tables:
        conn.execute("SELECT tgsis.create_chunk_table(%s), tgsis.create_chunk_view(%s)", (table, table))
    conn.commit()


def _write(conn: Conn, table: str, rows: Sequence[Sequence[Any]], deletes: Sequence[Sequence[Any]] = ()) -> int:
    """Write ``rows`` (the row table's columns in order) and delete ``deletes`` (geoid, id) through the writer."""
    conn.execute("DROP TABLE IF EXISTS pg_temp.chunk_rows")
    conn.execute(
        sql.SQL("CREATE TEMP TABLE chunk_rows (LIKE tgsis.{}, _delete boolean NOT NULL DEFAULT false)").format(
            sql.Identifier(table)
        )
    )
    columns = [r[0] for r in conn.execute("SELECT * FROM pg_temp.chunk_rows LIMIT 0").description or []]
    width = len(columns) - 1
    with conn.cursor().copy("COPY pg_temp.chunk_rows FROM STDIN") as copy:
        for row in rows:
            copy.write_row([*row, False])
        for geoid, ident in deletes:
            # a deleted key's values are never read: any value that fits the column
            copy.write_row([geoid, ident, *([0] * (width - 2)), True])
    written = conn.execute("SELECT tgsis.write_chunk_rows(%s, 'pg_temp.chunk_rows')", (table,)).fetchone()
    assert written is not None
    return int(written[0])


def _visible(conn: Conn, table: str, geoid: int | None = None) -> list[tuple[Any, ...]]:
    """The decoded rows of the chunk versions the session's version sees (today's visibility test), in key order."""
    _, refs = MODEL1[table]
    ident, _ = MODEL1[table]
    values = refs or ["x", "y", "z"]
    query = sql.SQL(
        "SELECT geoid, {ident}, {values} FROM tgsis.{view} c "
        "WHERE (c.revision = ANY (tgsis.get_revisions(true))) IS TRUE AND NOT (c.lastrevs && tgsis.get_revisions(true)) "
        "{only} ORDER BY 1, 2"
    ).format(
        ident=sql.Identifier(ident),
        values=sql.SQL(", ").join(sql.Identifier(v) for v in values),
        view=sql.Identifier(f"{table}_chunk_rows"),
        only=sql.SQL("AND geoid = {}").format(geoid) if geoid is not None else sql.SQL(""),
    )
    return [tuple(r) for r in conn.execute(query).fetchall()]


def _chunk(conn: Conn, table: str, geoid: int, chunk: int) -> dict[str, Any] | None:
    """The visible version of one chunk, its columns by name (arrays as lists)."""
    row = conn.execute(
        sql.SQL(
            "SELECT to_jsonb(c) FROM tgsis.{} c WHERE geoid = %s AND chunk = %s "
            "AND (c.revision = ANY (tgsis.get_revisions(true))) IS TRUE AND NOT (c.lastrevs && tgsis.get_revisions(true))"
        ).format(sql.Identifier(f"{table}_chunk")),
        (geoid, chunk),
    ).fetchone()
    return None if row is None else dict(row[0])


def _sqlstate(conn: Conn, statement: str, params: Sequence[Any] = ()) -> str | None:
    try:
        with conn.transaction():
            conn.execute(statement, params)
    except psycopg.Error as exc:
        return exc.sqlstate
    return None


# --------------------------------------------------------------------------- the registry


def test_model1_tables_are_registered_for_chunks(conn: Conn) -> None:
    rows = conn.execute(
        "SELECT tablename, chunkcolumn, chunkrefs, chunksize FROM tgsis.model_tables WHERE model = 1 ORDER BY 1"
    ).fetchall()
    assert rows == [
        ("atom", None, [], None),
        ("part", None, [], None),
        ("point", "pointid", ["vrtxid1"], 1024),
        ("segment", "segid", ["vrtxid1", "vrtxid2"], 1024),
        ("tetra", "tetraid", ["vrtxid1", "vrtxid2", "vrtxid3", "vrtxid4"], 1024),
        ("trgl", "trglid", ["vrtxid1", "vrtxid2", "vrtxid3"], 1024),
        ("vrtx", "vrtxid", [], 1024),
    ]
    # model 2's time tables are stored in chunks by default in a new database (as model 1's); model 3's triangles and
    # node positions and the G-maps' darts, involutions and points (models 4 and 5) are registered for chunks, not stored in
    # them by default; the columns say what they are
    assert conn.execute(
        "SELECT array_agg(tablename || ':' || chunkcolumn || ':' || chunkdefault ORDER BY tablename) FROM tgsis.model_tables"
        " WHERE model <> 1 AND chunkcolumn IS NOT NULL"
    ).fetchone() == (
        [
            "d4dtrgl:trglid:false",
            "d4dvrtx:nodeid:false",
            "gmap_alpha:dartid:false",
            "gmap_dart:dartid:false",
            "gmap_vertex:nodeid:false",
            "md_alpha:dartid:false",
            "md_dart:dartid:false",
            "md_vertex:vrtxid:false",
            "times_trgl:trglid:true",
            "times_vrtx:vrtxid:true",
        ],
    )
    assert conn.execute(
        "SELECT bool_and(chunkdefault = (model IN (1, 2))) FROM tgsis.model_tables WHERE chunkcolumn IS NOT NULL"
    ).fetchone() == (True,)
    for column in ("chunkcolumn", "chunkrefs", "chunksize", "chunkdefault"):
        assert conn.execute(
            "SELECT col_description('tgsis.model_tables'::regclass, "
            "(SELECT attnum FROM pg_attribute WHERE attrelid = 'tgsis.model_tables'::regclass "
            "AND attname = %s))",
            (column,),
        ).fetchone() != (None,)
    # a block size is a power of two from 64 to 16384 (holes number slots as smallint), given with a chunk column only; refs only with one
    for update in (
        "chunksize = 1000",
        "chunksize = 32",
        "chunksize = 131072",
        "chunksize = 32768",
        "chunksize = NULL",
        "chunkcolumn = NULL",
    ):
        assert _sqlstate(conn, f"UPDATE tgsis.model_tables SET {update} WHERE tablename = 'trgl'") == "23514", update
    assert _sqlstate(conn, "UPDATE tgsis.model_tables SET chunkrefs = '{refid}' WHERE tablename = 'atom'") == "23514"
    assert _sqlstate(conn, "UPDATE tgsis.model_tables SET chunksize = 16384 WHERE tablename = 'trgl'") is None
    conn.rollback()


# --------------------------------------------------------------------------- the creator


def _expected_columns(table: str) -> list[tuple[str, str]]:
    chunkcolumn, refs = MODEL1[table]
    values = refs or ["x", "y", "z"]
    kind = "integer[]" if refs else "double precision[]"
    return (
        [("geoid", "bigint"), ("chunk", "bigint"), ("revision", "integer"), ("lastrevs", "integer[]")]
        + [("revclosed", "boolean"), ("holes", "smallint[]")]
        + ([("vbase", "bigint"), ("vtop", "bigint")] if refs else [])
        + [(v, kind) for v in values]
        + [(f"{r}_wide", "bigint[]") for r in refs]
    )


@pytest.mark.parametrize("versioned", [False, True], ids=["plain", "versioned"])
def test_chunk_tables_have_the_contract_s_columns_compression_indexes_comments_and_rights(
    conn: Conn, versioned: bool
) -> None:
    if versioned:
        tgsis.enable_feature_versioning(conn)
    _make_chunks(conn)
    lz4 = conn.execute(
        "SELECT 'lz4' = ANY (enumvals) FROM pg_settings WHERE name = 'default_toast_compression'"
    ).fetchone() == (True,)
    for table in MODEL1:
        chunk = f"tgsis.{table}_chunk"
        columns = conn.execute(
            "SELECT attname, format_type(atttypid, atttypmod), attcompression, attnotnull, "
            "       col_description(attrelid, attnum) FROM pg_attribute "
            "WHERE attrelid = %s::regclass AND attnum > 0 AND NOT attisdropped ORDER BY attnum",
            (chunk,),
        ).fetchall()
        assert [(c[0], c[1]) for c in columns] == _expected_columns(table), table
        for name, kind, compression, notnull, comment in columns:
            assert comment, (table, name)
            want = ("l" if lz4 else "p") if kind == "double precision[]" else "p" if kind.endswith("[]") else ""
            assert compression == want, (table, name, compression)
            assert notnull == (name in ("geoid", "chunk", "revision", "lastrevs")), (table, name)
        assert conn.execute("SELECT obj_description(%s::regclass, 'pg_class')", (chunk,)).fetchone() != (None,)
        assert conn.execute(
            "SELECT pg_get_expr(adbin, adrelid) FROM pg_attrdef WHERE adrelid = %s::regclass "
            "AND adnum = (SELECT attnum FROM pg_attribute WHERE attrelid = %s::regclass AND attname = 'revclosed')",
            (chunk, chunk),
        ).fetchone() == ("(cardinality(lastrevs) > 0)",)
        indexes = sorted(
            r[0]
            for r in conn.execute(
                "SELECT regexp_replace(pg_get_indexdef(indexrelid), ' ON \\S+', '') FROM pg_index WHERE indrelid = %s::regclass",
                (chunk,),
            )
        )
        assert indexes == sorted(
            [
                f"CREATE UNIQUE INDEX {table}_chunk_pkey USING btree (geoid, chunk, revision)",
                f"CREATE INDEX {table}_chunk_revision_idx USING brin (revision) WITH (autosummarize='on')",
                f"CREATE INDEX {table}_chunk_closed_idx USING btree (geoid) WHERE revclosed",
            ]
        ), table
        # the rights of the row table's storage: grants, row-level security and its policies
        storage = conn.execute("SELECT tgsis.storage_table('tgsis', %s)", (table,)).fetchone()
        assert storage is not None
        acl = "SELECT a.grantee::regrole::text, a.privilege_type FROM pg_class c, aclexplode(c.relacl) a WHERE c.oid = %s::regclass AND a.grantee <> c.relowner ORDER BY 1, 2"
        ours = conn.execute(acl, (chunk,)).fetchall()
        assert ours == conn.execute(acl, (storage[0],)).fetchall()
        assert ("tgsis_reader", "SELECT") in ours
        assert (("tgsis_editor", "UPDATE") in ours) == (not versioned)
        policies = "SELECT polname, polcmd, pg_get_expr(polqual, polrelid), obj_description(oid, 'pg_policy') FROM pg_policy WHERE polrelid = %s::regclass ORDER BY 1"
        assert conn.execute(policies, (chunk,)).fetchall() == conn.execute(policies, (storage[0],)).fetchall()
        assert len(conn.execute(policies, (chunk,)).fetchall()) == 4
        assert conn.execute("SELECT relrowsecurity FROM pg_class WHERE oid = %s::regclass", (chunk,)).fetchone() == (
            True,
        )
        # the decoded face: the row table's columns, then the versioning ones; commented, readers may read it
        view = f"tgsis.{table}_chunk_rows"
        face = conn.execute(
            "SELECT attname, format_type(atttypid, atttypmod), col_description(attrelid, attnum) FROM pg_attribute "
            "WHERE attrelid = %s::regclass AND attnum > 0 ORDER BY attnum",
            (view,),
        ).fetchall()
        row_columns = conn.execute(
            "SELECT attname, format_type(atttypid, atttypmod) FROM pg_attribute WHERE attrelid = %s::regclass "
            "AND attnum > 0 AND NOT attisdropped AND attname NOT IN ('revision', 'lastrevs', 'revclosed') ORDER BY attnum",
            (storage[0],),
        ).fetchall()
        assert [(f[0], f[1]) for f in face] == [
            *row_columns,
            ("revision", "integer"),
            ("lastrevs", "integer[]"),
            ("revclosed", "boolean"),
        ]
        assert all(f[2] for f in face), face
        assert conn.execute("SELECT has_table_privilege('tgsis_reader', %s, 'SELECT')", (view,)).fetchone() == (True,)


def test_the_creator_refuses_by_name(conn: Conn) -> None:
    for table in ("atom", "part", "no_such_table", "geometry"):
        assert _sqlstate(conn, "SELECT tgsis.create_chunk_table(%s)", (table,)) == "TG200", table
        assert _sqlstate(conn, "SELECT tgsis.create_chunk_view(%s)", (table,)) == "TG200", table
    # the face needs its chunk table; a second call of either refuses by name
    assert _sqlstate(conn, "SELECT tgsis.create_chunk_view('trgl')") == "TG200"
    assert _sqlstate(conn, "SELECT tgsis.write_chunk_rows('trgl', 'tgsis.trgl')") == "TG200"
    _make_chunks(conn, ["trgl"])
    assert _sqlstate(conn, "SELECT tgsis.create_chunk_table('trgl')") == "TG201"
    assert _sqlstate(conn, "SELECT tgsis.create_chunk_view('trgl')") == "TG201"
    conn.rollback()


# --------------------------------------------------------------------------- the writer


def _vertices(ids: Iterable[int], geoid: int = 1, scale: float = 1.0) -> list[tuple[int, int, float, float, float]]:
    return [(geoid, i, i * scale, -i * scale, 0.5 + i) for i in ids]


def test_writer_inserts_upserts_and_deletes_with_holes(conn: Conn) -> None:
    _make_chunks(conn, ["vrtx"])
    rng = np.random.default_rng(7)
    ids = sorted(int(i) for i in rng.choice(5000, size=3000, replace=False))
    expected = {(1, i): r for i, r in zip(ids, _vertices(ids), strict=True)}
    assert _write(conn, "vrtx", _vertices(ids)) == len({i >> 10 for i in ids})
    assert _visible(conn, "vrtx") == sorted(expected.values())
    # the raw layout: arrays end at the last present slot, holes lists the absent slots below it
    for c in {i >> 10 for i in ids}:
        raw = _chunk(conn, "vrtx", 1, c)
        assert raw is not None and raw["revision"] == 0 and raw["lastrevs"] == []
        present = [i - c * 1024 + 1 for i in ids if i >> 10 == c]
        assert len(raw["x"]) == max(present)
        holes = [s for s in range(1, max(present)) if s not in present]
        assert raw["holes"] == (holes or None)
        assert [s for s, x in enumerate(raw["x"], 1) if x is None] == holes
    # upserts of a few slots (new and existing) and a second object; another geometry untouched
    changes = _vertices([ids[0], ids[5], 4999 if 4999 not in ids else 4998, 1023], scale=10.0)
    changes += _vertices([0, 1], geoid=2)
    for row in changes:
        expected[row[0], row[1]] = row
    assert _write(conn, "vrtx", changes) == len({(r[0], r[1] >> 10) for r in changes})
    assert _visible(conn, "vrtx") == sorted(expected.values())
    # deletes: a hole in the middle, the last present slot of a chunk (its arrays shrink), a whole chunk
    last = max(i for i in ids if i >> 10 == 1)
    first_chunk = [i for i in expected if i[0] == 1 and i[1] >> 10 == 0 and i != (1, ids[3])]
    gone = [(1, ids[3]), (1, last), *first_chunk, (1, 99_999)]  # (an absent id: nothing to delete)
    for key in gone:
        expected.pop(key, None)
    written = _write(conn, "vrtx", [], gone)
    assert written == 2  # chunks 1 and 0; chunk 97 never existed
    assert _visible(conn, "vrtx") == sorted(expected.values())
    assert _chunk(conn, "vrtx", 1, 0) is None
    raw = _chunk(conn, "vrtx", 1, 1)
    assert raw is not None
    new_last = max(i[1] for i in expected if i[0] == 1 and i[1] >> 10 == 1)
    assert len(raw["x"]) == new_last - 1024 + 1
    assert raw["x"][-1] is not None
    assert conn.execute("SELECT count(*) FROM tgsis.vrtx_chunk WHERE geoid = 1 AND chunk = 0").fetchone() == (0,)
    conn.commit()


def test_writer_keeps_ids_beyond_int4_and_switches_to_wide_columns_and_back(conn: Conn) -> None:
    _make_chunks(conn, ["trgl", "vrtx"])
    big = 2**40 + 5
    # vertex ids beyond int4, triangle ids beyond int4: relative corners fit
    vertices = _vertices([big, big + 1, big + 2, 2**31 + 3])
    assert _write(conn, "vrtx", vertices) == 2
    assert _visible(conn, "vrtx") == sorted(vertices)
    tri = 2**33 + 2  # slot 3 of its chunk
    triangles = [(1, tri, big + 2, big, big + 1), (1, tri - 2, big, big + 1, big + 2)]
    assert _write(conn, "trgl", triangles) == 1
    raw = _chunk(conn, "trgl", 1, tri >> 10)
    assert raw is not None
    assert raw["vbase"] == big and raw["vrtxid1_wide"] is None
    assert raw["vtop"] == big + 2 * 2  # vbase + twice the largest relative value: bounds big + 2
    assert raw["vrtxid1"] == [0, None, 2] and raw["vrtxid2"] == [1, None, -2] and raw["holes"] == [2]
    assert len(raw["vrtxid3"]) == 3
    assert _visible(conn, "trgl") == sorted(triangles)
    # one corner far away: a difference beyond int4, so the chunk keeps absolute ids in the _wide columns
    far = (1, tri - 1, 3, big, INT4_MAX + 10)
    assert _write(conn, "trgl", [far]) == 1
    raw = _chunk(conn, "trgl", 1, tri >> 10)
    assert raw is not None
    assert raw["vbase"] is None and raw["vrtxid1"] is None and raw["vrtxid3"] is None
    assert raw["vrtxid1_wide"] == [big, 3, big + 2] and raw["holes"] is None
    assert raw["vtop"] == big + 2  # absolute ids: the largest
    assert _visible(conn, "trgl") == sorted([*triangles, far])
    # gone again: back to relative
    assert _write(conn, "trgl", [], [(1, tri - 1)]) == 1
    raw = _chunk(conn, "trgl", 1, tri >> 10)
    assert raw is not None
    assert raw["vbase"] == big and raw["vrtxid1_wide"] is None and raw["holes"] == [2]
    assert _visible(conn, "trgl") == sorted(triangles)
    # a difference of exactly the int4 bounds still fits; one more does not
    edge = [(2, 0, 0, INT4_MAX, 1), (2, 1, INT4_MAX, 0, 2)]  # differences +2^31-1 and -(2^31-1)
    _write(conn, "trgl", edge)
    assert (_chunk(conn, "trgl", 2, 0) or {})["vbase"] == 0
    assert (_chunk(conn, "trgl", 2, 0) or {})["vtop"] == 2 * INT4_MAX
    assert _visible(conn, "trgl", 2) == edge
    _write(conn, "trgl", [(2, 2, INT4_MAX + 1, 0, 1)])  # the first corner INT4_MAX + 1 above vbase
    assert (_chunk(conn, "trgl", 2, 0) or {})["vbase"] is None
    assert _visible(conn, "trgl", 2) == [*edge, (2, 2, INT4_MAX + 1, 0, 1)]
    # a later corner INT4_MAX above the first still fits; one more does not
    _write(conn, "trgl", [(3, 0, 10, 10 + INT4_MAX, 11)])
    assert (_chunk(conn, "trgl", 3, 0) or {})["vbase"] == 10
    _write(conn, "trgl", [(3, 0, 10, 11 + INT4_MAX, 11)])
    assert (_chunk(conn, "trgl", 3, 0) or {})["vbase"] is None
    assert _visible(conn, "trgl", 3) == [(3, 0, 10, 11 + INT4_MAX, 11)]
    conn.commit()


def test_writer_versions_chunks_as_rows_are_versioned(conn: Conn) -> None:
    tgsis.enable_feature_versioning(conn)
    _make_chunks(conn, ["vrtx"])
    base = _vertices(range(0, 1500))
    _write(conn, "vrtx", base)
    conn.commit()
    tgsis.create_version(conn, "child")
    tgsis.goto_version(conn, "child")
    w = conn.execute("SELECT tgsis.get_working_revision()").fetchone()
    assert w is not None
    moved = _vertices([3, 1100], scale=7.0)
    assert _write(conn, "vrtx", moved) == 2
    conn.commit()
    versions = conn.execute(
        "SELECT chunk, revision, lastrevs FROM tgsis.vrtx_chunk WHERE geoid = 1 ORDER BY chunk, revision"
    ).fetchall()
    parent = versions[0][1]
    assert versions == [(0, parent, [w[0]]), (0, w[0], []), (1, parent, [w[0]]), (1, w[0], [])]
    child_rows = {r[1]: r for r in base}
    child_rows.update({r[1]: r for r in moved})
    assert _visible(conn, "vrtx") == sorted(child_rows.values())
    # content the chunk holds already, bit for bit, is not written: no version closed, none added
    assert _write(conn, "vrtx", [*_vertices([3], scale=7.0), *base[1200:1210]], [(1, 5000)]) == 0
    assert conn.execute("SELECT count(*) FROM tgsis.vrtx_chunk WHERE geoid = 1").fetchone() == (4,)
    # a second write in the same working revision rewrites the child's version in place
    again = _vertices([4], scale=9.0)
    child_rows[4] = again[0]
    assert _write(conn, "vrtx", again) == 1
    conn.commit()
    assert conn.execute("SELECT count(*) FROM tgsis.vrtx_chunk WHERE geoid = 1").fetchone() == (4,)
    assert _visible(conn, "vrtx") == sorted(child_rows.values())
    # emptied in the child: its own version goes, the parent's stays closed for it
    assert _write(conn, "vrtx", [], [(1, i) for i in range(1024, 1500)]) == 1
    conn.commit()
    assert conn.execute("SELECT revision, lastrevs FROM tgsis.vrtx_chunk WHERE geoid = 1 AND chunk = 1").fetchall() == [
        (parent, [w[0]])
    ]
    assert _visible(conn, "vrtx") == sorted(r for r in child_rows.values() if r[1] < 1024)
    # the parent still sees its content
    tgsis.goto_version(conn, "DEFAULT")
    assert _visible(conn, "vrtx") == sorted(base)
    # unchanged content of a version another revision wrote is neither closed nor copied
    assert conn.execute("SELECT tgsis.get_working_revision() <> %s", (parent,)).fetchone() == (True,)
    assert _write(conn, "vrtx", base[:5]) == 0
    assert conn.execute("SELECT count(*) FROM tgsis.vrtx_chunk WHERE geoid = 1").fetchone() == (3,)


def test_writer_refuses_what_the_row_table_would(conn: Conn) -> None:
    _make_chunks(conn, ["trgl", "vrtx"])
    conn.execute(
        "CREATE TEMP TABLE loose (geoid bigint, trglid bigint, vrtxid1 bigint, vrtxid2 bigint, vrtxid3 bigint, _delete boolean)"
    )
    conn.commit()
    cases = {
        "(1, 0, 0, 1, NULL, false)": "TG100",  # a NULL value would become a hole
        "(1, NULL, 0, 1, 2, false)": "TG100",
        "(1, 0, 0, 1, 2, NULL)": "TG100",
        "(1, -1, 0, 1, 2, false)": "TG100",
        "(1, 0, -5, 1, 2, false)": "TG100",
        "(1, 0, 0, 1, 2, false), (1, 0, 3, 4, 5, true)": "TG100",  # a key twice
        "(1, 0, 0, 0, 2, false)": "23514",  # trgl_distinct_vertices
    }
    for values, state in cases.items():
        with conn.transaction():
            conn.execute("TRUNCATE loose")
            conn.execute(f"INSERT INTO loose VALUES {values}")
        assert _sqlstate(conn, "SELECT tgsis.write_chunk_rows('trgl', 'pg_temp.loose')") == state, values
    # a delete need not satisfy the checks: its values are not read
    with conn.transaction():
        conn.execute("TRUNCATE loose")
        conn.execute("INSERT INTO loose VALUES (1, 0, 0, 0, 0, true)")
    assert _sqlstate(conn, "SELECT tgsis.write_chunk_rows('trgl', 'pg_temp.loose')") is None
    # columns missing: the row table's, or _delete
    assert _sqlstate(conn, "SELECT tgsis.write_chunk_rows('vrtx', 'pg_temp.loose')") == "TG100"
    conn.execute("CREATE TEMP TABLE nodelete (LIKE tgsis.trgl)")
    assert _sqlstate(conn, "SELECT tgsis.write_chunk_rows('trgl', 'pg_temp.nodelete')") == "TG100"
    assert _sqlstate(conn, "SELECT tgsis.write_chunk_rows('atom', 'pg_temp.loose')") == "TG200"
    # nothing was written
    assert conn.execute("SELECT count(*) FROM tgsis.trgl_chunk").fetchone() == (0,)


def test_writer_keeps_doubles_bit_exact(conn: Conn) -> None:
    _make_chunks(conn, ["vrtx"])
    patterns = np.array(
        [
            0x8000000000000000,
            0x7FF8000000000123,
            0xFFF80000DEADBEEF,
            0x0000000000000001,
            0x000FFFFFFFFFFFFF,
            0x7FF0000000000000,
            0xFFF0000000000000,
            0x3FF0000000000001,
        ],
        dtype=np.uint64,
    ).view(np.int64)
    values = patterns.view(np.float64)
    conn.execute("CREATE TEMP TABLE exact (LIKE tgsis.vrtx, _delete boolean NOT NULL DEFAULT false)")
    with conn.cursor(binary=True).copy(
        "COPY pg_temp.exact (geoid, vrtxid, x, y, z, _delete) FROM STDIN (FORMAT BINARY)"
    ) as copy:
        copy.set_types(["int8", "int8", "float8", "float8", "float8", "bool"])
        for i, v in enumerate(values):
            copy.write_row([1, i * 700, float(v), float(values[-1 - i]), -float(v), False])
    assert conn.execute("SELECT tgsis.write_chunk_rows('vrtx', 'pg_temp.exact')").fetchone() == (5,)
    got = conn.execute(
        "SELECT float8send(x), float8send(y) FROM tgsis.vrtx_chunk_rows WHERE geoid = 1 ORDER BY vrtxid"
    ).fetchall()
    assert [bytes(g[0]) for g in got] == [struct.pack(">q", int(p)) for p in patterns]
    assert [bytes(g[1]) for g in got] == [struct.pack(">q", int(p)) for p in patterns[::-1]]
    # 0.0 and -0.0 are equal to SQL but not the same content: a change of sign bit is written
    assert _write(conn, "vrtx", [(1, 1401, 0.0, 0.0, 0.0)]) == 1
    assert _write(conn, "vrtx", [(1, 1401, -0.0, 0.0, 0.0)]) == 1
    assert _write(conn, "vrtx", [(1, 1401, -0.0, 0.0, 0.0)]) == 0
    assert conn.execute("SELECT float8send(x) FROM tgsis.vrtx_chunk_rows WHERE vrtxid = 1401").fetchone() == (
        struct.pack(">d", -0.0),
    )
    # and once more through a rewrite in place of the same chunks (another slot changed)
    _write(conn, "vrtx", _vertices([1]))
    got = conn.execute(
        "SELECT float8send(x) FROM tgsis.vrtx_chunk_rows WHERE geoid = 1 AND vrtxid NOT IN (1, 1401) ORDER BY vrtxid"
    ).fetchall()
    assert [bytes(g[0]) for g in got] == [struct.pack(">q", int(p)) for p in patterns]


def test_writer_takes_a_statement_of_100k_rows_in_one_pass(conn: Conn) -> None:
    _make_chunks(conn, ["trgl"])
    n = 100_000
    rng = np.random.default_rng(3)
    ids = rng.permutation(n + 2_000)[:n]
    corners = np.stack([ids * 2, ids * 2 + 1, ids * 2 + 5], axis=1)
    conn.execute("CREATE TEMP TABLE big (LIKE tgsis.trgl, _delete boolean NOT NULL DEFAULT false)")
    with conn.cursor().copy("COPY pg_temp.big (geoid, trglid, vrtxid1, vrtxid2, vrtxid3) FROM STDIN") as copy:
        for i, (a, b, c) in zip(ids.tolist(), corners.tolist(), strict=True):
            copy.write_row([1, i, a, b, c])
    assert conn.execute("SELECT tgsis.write_chunk_rows('trgl', 'pg_temp.big')").fetchone() == (
        len(set((ids >> 10).tolist())),
    )
    total = conn.execute(
        "SELECT count(*), sum(trglid), sum(vrtxid1), sum(vrtxid3 - vrtxid2) FROM tgsis.trgl_chunk_rows WHERE NOT revclosed"
    ).fetchone()
    assert total == (n, int(ids.sum()), int(corners[:, 0].sum()), 4 * n)
    assert conn.execute("SELECT count(*) FROM tgsis.trgl_chunk").fetchone() == (len(set((ids >> 10).tolist())),)


def test_a_scan_of_one_object_reads_only_its_chunks(conn: Conn) -> None:
    _make_chunks(conn, ["vrtx"])
    for geoid in (1, 2, 3):
        _write(conn, "vrtx", _vertices(range(0, 5000), geoid=geoid))
    conn.execute("ANALYZE tgsis.vrtx_chunk")
    conn.execute("SET enable_seqscan = off; SET jit = off")
    plan = conn.execute("EXPLAIN (ANALYZE, FORMAT JSON) SELECT * FROM tgsis.vrtx_chunk_rows WHERE geoid = 2").fetchone()
    assert plan is not None
    nodes: list[dict[str, Any]] = []

    def walk(node: dict[str, Any]) -> None:
        nodes.append(node)
        for child in node.get("Plans", []):
            walk(child)

    walk(plan[0][0]["Plan"])
    scans = [n for n in nodes if n.get("Relation Name") == "vrtx_chunk"]
    assert len(scans) == 1, json.dumps(plan[0])
    assert scans[0]["Actual Rows"] == 5  # chunks 0..4 of geoid 2, not the 15 of all
    assert "geoid = 2" in scans[0].get("Index Cond", "") or "geoid = 2" in scans[0].get("Recheck Cond", "")
    assert scans[0].get("Rows Removed by Filter", 0) == 0
    assert plan[0][0]["Plan"]["Actual Rows"] == 5000


def test_roles_with_fewer_rights(db_dsn: str, conn: Conn) -> None:
    tgsis.create_feature_class(conn, "alpha", "SURFACE")
    tgsis.create_feature_class(conn, "beta", "SURFACE")
    triangle = Surface(np.eye(3), np.array([[0, 1, 2]]))
    alpha = tgsis.insert_feature(conn, "alpha", triangle)
    beta = tgsis.insert_feature(conn, "beta", triangle)
    conn.execute("REVOKE ALL ON beta FROM tgsis_reader, tgsis_editor, tgsis_admin, PUBLIC")
    conn.commit()
    _make_chunks(conn, ["vrtx"])
    _write(conn, "vrtx", [*_vertices(range(10), geoid=alpha), *_vertices(range(4), geoid=beta)])
    conn.commit()
    with login_roles(db_dsn, {"reader": "tgsis_reader", "editor": "tgsis_editor"}) as roles:
        reader = roles.connect("reader")
        # the chunk table's row-level security is the row table's: a revoked class's chunks are not seen
        assert reader.execute("SELECT DISTINCT geoid FROM tgsis.vrtx_chunk").fetchall() == [(alpha,)]
        assert len(reader.execute("SELECT * FROM tgsis.vrtx_chunk_rows").fetchall()) == 10
        reader.rollback()
        for statement in (
            "INSERT INTO tgsis.vrtx_chunk (geoid, chunk, revision) VALUES (5, 0, 0)",
            "SELECT tgsis.create_chunk_table('trgl')",
            "SELECT tgsis.create_chunk_view('vrtx')",
            "SELECT tgsis.write_chunk_rows('vrtx', 'tgsis.vrtx')",
        ):
            assert _sqlstate(reader, statement) == "42501", statement
        editor = roles.connect("editor")
        for statement in (
            "SELECT tgsis.write_chunk_rows('vrtx', 'tgsis.vrtx')",
            "SELECT tgsis.create_chunk_table('trgl')",
            "SELECT tgsis.chunk_columns('vrtx')",
            # writes to the storage directly: not into a revoked class's chunks
            f"INSERT INTO tgsis.vrtx_chunk (geoid, chunk, revision) VALUES ({beta}, 7, 0)",
        ):
            assert _sqlstate(editor, statement) == "42501", statement
        assert editor.execute("UPDATE tgsis.vrtx_chunk SET holes = NULL WHERE geoid = %s", (beta,)).rowcount == 0
        editor.rollback()


def _waits_for_a_lock(conn: Conn, pid: int) -> bool:
    row = conn.execute("SELECT wait_event_type FROM pg_stat_activity WHERE pid = %s", (pid,)).fetchone()
    conn.rollback()
    return row is not None and row[0] == "Lock"


@pytest.mark.parametrize("case", ["existing chunk", "new chunk", "versioned"])
def test_two_writers_of_different_slots_of_one_chunk_keep_both(db_dsn: str, conn: Conn, case: str) -> None:
    if case == "versioned":
        tgsis.enable_feature_versioning(conn)
    _make_chunks(conn, ["vrtx"])
    if case != "new chunk":
        _write(conn, "vrtx", _vertices(range(0, 100)))
        conn.commit()
    if case == "versioned":
        tgsis.create_version(conn, "child")
    first = psycopg.connect(db_dsn)
    second = psycopg.connect(db_dsn)
    try:
        for session in (first, second):
            if case == "versioned":
                tgsis.goto_version(session, "child")
        pid = second.info.backend_pid
        a = _vertices([10, 500], scale=3.0)
        b = _vertices([20, 700], scale=5.0)
        assert _write(first, "vrtx", a) == 1  # open: holds the chunk's lock
        result: list[Any] = []

        def run() -> None:
            try:
                result.append(_write(second, "vrtx", b))
                second.commit()
            except Exception as exc:  # handed to the test's thread
                result.append(exc)

        worker = threading.Thread(target=run)
        worker.start()
        deadline = time.monotonic() + 60
        while not _waits_for_a_lock(conn, pid):
            assert worker.is_alive() and time.monotonic() < deadline, result
            time.sleep(0.05)
        first.commit()
        worker.join(60)
        assert result == [1]
    finally:
        first.close()
        second.close()
    if case == "versioned":
        tgsis.goto_version(conn, "child")
    expected = {} if case == "new chunk" else {r[1]: r for r in _vertices(range(0, 100))}
    expected.update({r[1]: r for r in [*a, *b]})
    assert _visible(conn, "vrtx") == sorted(expected.values())
    versions = conn.execute("SELECT count(*) FROM tgsis.vrtx_chunk WHERE NOT revclosed").fetchone()
    assert versions == (1,)


def test_writer_in_versioned_storage_writes_features_of_unversioned_classes_in_revision_0(conn: Conn) -> None:
    tgsis.enable_feature_versioning(conn)
    tgsis.create_feature_class(conn, "plain", "SURFACE", versioned=False)
    tgsis.create_feature_class(conn, "kept", "SURFACE")
    triangle = Surface(np.eye(3), np.array([[0, 1, 2]]))
    loose = tgsis.insert_feature(conn, "plain", triangle)
    kept = tgsis.insert_feature(conn, "kept", triangle)
    conn.commit()
    _make_chunks(conn, ["vrtx"])
    tgsis.create_version(conn, "child")
    # DEFAULT's working revision is not 0 any more; the unversioned feature's chunks are written in revision 0
    assert conn.execute("SELECT tgsis.get_working_revision()").fetchone() != (0,)
    assert _write(conn, "vrtx", _vertices([0, 1], geoid=loose)) == 1
    assert _write(conn, "vrtx", _vertices([2], geoid=loose)) == 1
    conn.commit()
    assert conn.execute("SELECT revision, lastrevs FROM tgsis.vrtx_chunk WHERE geoid = %s", (loose,)).fetchall() == [
        (0, [])
    ]
    # refused as a write of their rows is: mixed with a versioned feature (TG300), or in another version (TG305)
    with pytest.raises(psycopg.Error) as mixed:
        _write(conn, "vrtx", [*_vertices([5], geoid=loose), *_vertices([5], geoid=kept)])
    assert mixed.value.sqlstate == "TG300"
    conn.rollback()
    tgsis.goto_version(conn, "child")
    with pytest.raises(psycopg.Error) as elsewhere:
        _write(conn, "vrtx", _vertices([3], geoid=loose))
    assert elsewhere.value.sqlstate == "TG305"
    conn.rollback()
    # the child sees what DEFAULT wrote there, the one state of the feature
    assert _visible(conn, "vrtx", loose) == _vertices([0, 1, 2], geoid=loose)


def test_writer_in_plain_storage_refuses_a_session_in_another_version(conn: Conn) -> None:
    _make_chunks(conn, ["vrtx"])
    tgsis.create_version(conn, "child")
    tgsis.goto_version(conn, "child")
    with pytest.raises(psycopg.Error) as refused:
        _write(conn, "vrtx", _vertices([0]))
    assert refused.value.sqlstate == "TG305"


@pytest.mark.parametrize("isolation", ["REPEATABLE READ", "SERIALIZABLE"])
def test_writer_under_a_transaction_snapshot_refuses_what_changed_after_it(
    db_dsn: str, conn: Conn, isolation: str
) -> None:
    """Under REPEATABLE READ or SERIALIZABLE the writer keeps the transaction's snapshot (a session's default level).

    A chunk version another transaction changed after the snapshot fails the writer's lock, a chunk
    it inserted the writer's insert: 40001 as PostgreSQL answers, never a write over what the snapshot
    missed (another id of the chunk included: the chunk is the unit). With nothing changed meanwhile
    it writes. (Before: refused whatever happened, TG300.)
    """
    _make_chunks(conn, ["vrtx"])
    assert _write(conn, "vrtx", _vertices([0, 1])) == 1
    conn.commit()
    answers: list[int | str | None] = []
    for other_ids, mine in (([1], [2]), ([5000], [5001])):
        conn.execute(f"SET TRANSACTION ISOLATION LEVEL {isolation}")
        conn.execute("SELECT count(*) FROM tgsis.vrtx_chunk").fetchone()  # the snapshot
        with psycopg.connect(db_dsn) as other:
            assert _write(other, "vrtx", _vertices(other_ids, scale=2.0)) == 1
            other.commit()
        try:
            answers.append(_write(conn, "vrtx", _vertices(mine, scale=3.0)))
        except psycopg.Error as exc:
            answers.append(exc.sqlstate)
        conn.rollback()
    assert answers == ["40001", "40001"]
    conn.execute(f"SET TRANSACTION ISOLATION LEVEL {isolation}")
    assert _write(conn, "vrtx", _vertices([2, 5001], scale=3.0)) == 2
    conn.commit()
    assert _visible(conn, "vrtx") == sorted(
        _vertices([0]) + _vertices([1, 5000], scale=2.0) + _vertices([2, 5001], scale=3.0)
    )


@pytest.mark.parametrize("table", list(MODEL1))
def test_every_model1_table_round_trips_through_the_writer(conn: Conn, table: str) -> None:
    _make_chunks(conn, [table])
    ident, refs = MODEL1[table]
    rng = np.random.default_rng(len(table))
    ids = rng.choice(6000, size=2500, replace=False) + np.int64(2**32)
    rows: list[tuple[Any, ...]] = []
    for i in ids.tolist():
        if refs:
            # distinct corners near 3 * id, and in the chunk of ids 2**32 + 2048.. one far corner each (_wide)
            corners = [3 * i + k for k in range(len(refs))]
            if (i - 2**32) >> 10 == 2 and len(refs) > 1:
                corners[-1] = 7
            rows.append((1, i, *corners))
        else:
            rows.append((1, i, *rng.standard_normal(3).tolist()))
    assert _write(conn, table, rows) == len({i >> 10 for i in ids.tolist()})
    assert _visible(conn, table) == sorted(rows)
    wide = (
        conn.execute(
            sql.SQL("SELECT chunk FROM tgsis.{} WHERE vbase IS NULL ORDER BY 1").format(
                sql.Identifier(f"{table}_chunk")
            )
        ).fetchall()
        if refs
        else []
    )
    assert wide == ([((2**32 >> 10) + 2,)] if len(refs) > 1 else [])
    # half of them deleted, the rest moved: the same rows as a row table would hold
    gone = [(1, i) for i in ids[::2].tolist()]
    kept = {r[1]: r for r in rows if r[1] not in {g[1] for g in gone}}
    moved = [(r[0], r[1], *(v + 1 for v in r[2:])) for r in list(kept.values())[::3]]
    kept.update({r[1]: r for r in moved})
    _write(conn, table, moved, gone)
    assert _visible(conn, table) == sorted(kept.values())
    # the layout: holes below the last present slot only, arrays ending at a present slot
    first = (
        sql.SQL("x")
        if not refs
        else sql.SQL("coalesce({}::bigint[], {})").format(sql.Identifier(refs[0]), sql.Identifier(f"{refs[0]}_wide"))
    )
    bad = conn.execute(
        sql.SQL(
            "SELECT count(*) FROM (SELECT holes, {} AS a FROM tgsis.{}) c "
            "WHERE a[cardinality(a)] IS NULL OR holes[cardinality(holes)] >= cardinality(a) "
            "OR coalesce(cardinality(holes), 0) <> (SELECT count(*) FROM unnest(a) AS u(v) WHERE v IS NULL)"
        ).format(first, sql.Identifier(f"{table}_chunk"))
    ).fetchone()
    assert bad == (0,)
