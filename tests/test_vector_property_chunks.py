"""Vector properties of a class stored in chunks (issue 40, plan K area V).

docs/storage.md, "Property chunks: the contract": a vector property (a column ``t[]`` of ``size``
k in the catalog) is one two-dimensional array per chunk, slots x k; a NULL vector (a collection
member lacking the property) is a row of k NULLs there, which no vector of the row table is (its
CHECK refuses a NULL element, so a "vector of NULLs" cannot be stored on rows either); a value that
is not k values is refused by every write into chunks as by the row table's CHECK (23514, its
constraint named: tests/test_vector_property_checks.py). The face decodes each
vector as ``ARRAY[...]`` of its components. These tests build rows by plain SQL and through the
public API, switch both ways and compare value for value (doubles and reals by their bits: NaN
payloads, -0.0, subnormals), and compare statements through the face with the same statements on
an identical class kept in rows. The property tables are rows on both storages of model 1, so the
file runs unmarked.
"""

from __future__ import annotations

import struct
from pathlib import Path
from typing import Any

import numpy as np
import psycopg
import pytest

import tgsis
from tests.merge_data import curved_surface, sqlstate
from tests.roles import login_roles
from tests.sessions import close_and_wait_gone
from tests.storage_data import classes_as_rows
from tgsis.db import features as F
from tgsis.mesh import Surface
from tgsis.testing import TestServer

Conn = psycopg.Connection[Any]


@pytest.fixture(autouse=True)
def _classes_as_rows(db_dsn: str) -> None:
    """The classes these tests make start as rows: they switch them to chunks themselves, or compare with a rows
    twin (docs/storage.md, "Property chunks by default: the rule")."""
    classes_as_rows(db_dsn)


PROPS = [("normal", "double precision", 3), ("t", "real", 1), ("pair", "integer", 2), ("rgb", "real", 3)]
VEC = "public.vec_cellpros"
#: float8 bit patterns that must survive: -0.0, the smallest subnormal, a NaN with a payload, 1 + 1 ulp
PATTERNS = [0x8000000000000000, 0x0000000000000001, 0x7FF8000000000ABC, 0x3FF0000000000001]
#: the compared columns: keys, then each property by its bits (array_send keeps shape and element bits)
COLUMNS = "_geoid, _idx, array_send(normal), float4send(t), array_send(pair), array_send(rgb)"


def _double(bits: int) -> float:
    value: float = struct.unpack(">d", struct.pack(">Q", bits))[0]
    return value


def _rows(conn: Conn, relation: str, where: str = "true") -> list[tuple[Any, ...]]:
    query = f"SELECT {COLUMNS} FROM {relation} WHERE {where} ORDER BY 1, 2"
    return [tuple(bytes(v) if isinstance(v, memoryview) else v for v in r) for r in conn.execute(query).fetchall()]


def _vec(conn: Conn, name: str = "vec", geotype: str = "GEOMETRYCOLLECTION") -> None:
    """Class ``name`` with vector and scalar properties, rows written by plain SQL: holes, odd bits, NULL vectors."""
    tgsis.create_feature_class(conn, name, geotype, cell_properties=[(n, t, k) for n, t, k in PROPS])
    table = f"public.{name}_cellpros"
    conn.execute(
        f"INSERT INTO {table} (_geoid, _idx, normal, t, pair, rgb) "
        "SELECT 1, i, ARRAY[sin(i), cos(i), i::double precision / 7], (i / 3.0)::real, ARRAY[i, -i], "
        "ARRAY[i % 256, 0, 1]::real[] FROM generate_series(0, 2999) i WHERE i % 97 <> 5 AND i NOT IN (1024, 1025, 2047)"
    )
    for k, bits in enumerate(PATTERNS):
        conn.execute(
            f"INSERT INTO {table} VALUES (2, %s, ARRAY[%s, %s, '-0']::double precision[], '-0'::real, "
            "ARRAY[-2147483648, 2147483647], ARRAY['NaN', '-0', 'Infinity']::real[])",
            (k * 5, _double(bits), _double(PATTERNS[(k + 1) % 4])),
        )
    if geotype == "GEOMETRYCOLLECTION":
        # members lacking a property: a NULL vector, NULL everywhere, and NULL among present ones
        conn.execute(f"INSERT INTO {table} (_geoid, _idx, t) VALUES (2, 1, 1.5), (3, 5000, NULL)")
        conn.execute(f"INSERT INTO {table} (_geoid, _idx, normal) VALUES (2, 2, ARRAY[1, 2, 3])")
    conn.execute(f"INSERT INTO {table} VALUES (2, %s, ARRAY[1, 2, 3], 0, ARRAY[0, 0], ARRAY[0, 0, 0])", (2**40 + 3,))


# --------------------------------------------------------------------------- the layout and the round trip


def test_layout_and_round_trip_bit_for_bit(conn: Conn) -> None:
    _vec(conn)
    roles = conn.execute("SELECT name, role, typename, size FROM tgsis.chunk_columns(%s) ORDER BY colorder", (VEC,))
    assert roles.fetchall() == [
        ("_geoid", "key", "bigint", None),
        ("_idx", "chunk", "bigint", None),
        ("normal", "vector", "double precision", 3),
        ("t", "value", "real", None),
        ("pair", "vector", "integer", 2),
        ("rgb", "vector", "real", 3),
    ]
    before = _rows(conn, VEC)
    conn.execute("SELECT tgsis.create_chunk_table(%s), tgsis.create_chunk_view(%s)", (VEC, VEC))
    written = conn.execute("SELECT tgsis.rows_to_chunks(%s)", (VEC,)).fetchone()
    assert written == conn.execute("SELECT count(DISTINCT (_geoid, _idx >> 10)) FROM public.vec_cellpros").fetchone()
    # two-dimensional arrays, slots x k, from [1][1]; a hole's and a NULL vector's row are k NULLs
    shape = conn.execute(
        "SELECT holes[1:3], array_dims(normal), array_dims(pair), array_dims(t), normal[1:2], pair[2:3] "
        "FROM public.vec_cellpros_chunk WHERE _geoid = 2 AND chunk = 0"
    ).fetchone()
    assert shape is not None
    assert shape[:4] == ([4, 5, 7], "[1:16][1:3]", "[1:16][1:2]", "[1:16]")
    assert shape[4][1] == [None, None, None] and shape[5] == [[None, None], [None, None]]
    assert _rows(conn, "public.vec_cellpros_chunk_rows") == before
    conn.execute("DELETE FROM public.vec_cellpros")
    assert conn.execute("SELECT tgsis.chunks_to_rows(%s)", (VEC,)).fetchone() == (len(before),)
    assert _rows(conn, VEC) == before
    bits = conn.execute(
        "SELECT float8send(normal[1]) FROM public.vec_cellpros WHERE _geoid = 2 AND _idx % 5 = 0 "
        "AND _idx < 20 ORDER BY _idx"
    ).fetchall()
    assert [bytes(b[0]) for b in bits] == [struct.pack(">Q", p) for p in PATTERNS]


def test_the_encoding_check_refuses_a_vector_partly_null_and_a_value_at_a_hole(conn: Conn) -> None:
    _vec(conn)
    conn.execute("SELECT tgsis.create_chunk_table(%s), tgsis.create_chunk_view(%s)", (VEC, VEC))
    conn.execute("SELECT tgsis.rows_to_chunks(%s)", (VEC,))
    conn.commit()
    for change in (
        "normal[3][2] = NULL",  # a vector partly NULL would read as a NULL vector
        "normal[5][1] = 1",  # a value at a hole (slot 5 of object 2's chunk 0 is one)
        "pair = pair[1:15]",  # shorter than the chunk
        "pair = array_cat(pair, ARRAY[[1, 2, 3]])",  # not k values a row: refused by PostgreSQL itself
    ):
        conn.execute("SELECT 1")  # (a transaction: sqlstate's savepoint is rolled back below)
        state, message = sqlstate(conn, f"UPDATE public.vec_cellpros_chunk SET {change} WHERE _geoid = 2 AND chunk = 0")
        if state is None:
            state, message = sqlstate(conn, "SELECT tgsis.check_chunk_conversion(%s)", (VEC,))
            assert state == "TG000" and "not encoded" in message, change
        else:
            assert state == "2202E", (change, state, message)
        conn.rollback()
    assert sqlstate(conn, "SELECT tgsis.check_chunk_conversion(%s)", (VEC,)) == (None, "")


# --------------------------------------------------------------------------- the switch and the face


def _surface_class(conn: Conn, name: str) -> tuple[int, Surface]:
    """A SURFACE class with a 3-vector, a scalar and a 2-vector per vertex; one curved surface stored in it."""
    tgsis.create_feature_class(
        conn,
        name,
        "SURFACE",
        cell_properties=[("normal", "double precision", 3), ("t", "real"), ("pair", "integer", 2), ("rgb", "real", 3)],
    )
    surface = curved_surface()
    n = surface.n_vertices
    normal = np.stack([np.sin(np.arange(n)), np.cos(np.arange(n)), np.arange(n) / 7.0], axis=1)
    normal[:4, 0] = [_double(p) for p in PATTERNS]
    props = {
        "normal": normal,
        "t": (np.arange(n) / 3.0).astype(np.float32),
        "pair": np.stack([np.arange(n), -np.arange(n)], axis=1).astype(np.int32),
        "rgb": np.stack([np.arange(n) % 256, np.zeros(n), np.ones(n)], axis=1).astype(np.float32),
    }
    props["rgb"][0] = [np.float32(-0.0), np.float32(np.nan), np.float32(1e-45)]
    mesh = Surface(surface.vertices, surface.cells, vertex_properties=props)
    geoid = F.insert_feature(conn, name, mesh)
    conn.commit()
    return geoid, mesh


def _same(a: Any, b: Any) -> bool:
    """The four properties of two meshes, bit for bit (shapes included: a vector's (n, k))."""
    return all(
        np.array_equal(
            np.ascontiguousarray(a.vertex_properties[k]).view(np.uint8),
            np.ascontiguousarray(b.vertex_properties[k]).view(np.uint8),
        )
        for k in ("normal", "t", "pair", "rgb")
    )


def test_store_class_in_chunks_face_and_python_paths_and_back(conn: Conn) -> None:
    geoid, mesh = _surface_class(conn, "layer")
    table = "public.layer_cellpros"
    before = _rows(conn, table)
    assert _same(F.fetch_feature(conn, "layer", geoid).mesh, mesh)
    written = conn.execute("SELECT tgsis.store_class_in_chunks('layer')").fetchone()
    conn.commit()
    assert written == (-(-mesh.n_vertices // 1024),)
    assert _rows(conn, table) == before
    assert _same(F.fetch_feature(conn, "layer", geoid).mesh, mesh)
    # one vector through the face, one component, a bulk UPDATE, an INSERT, a DELETE
    conn.execute(
        f"UPDATE {table} SET normal = ARRAY['-0', 'NaN', 2]::double precision[] WHERE _geoid = %s AND _idx = 7",
        (geoid,),
    )
    conn.execute(f"UPDATE {table} SET pair[2] = 99 WHERE _geoid = %s AND _idx = 8", (geoid,))
    conn.execute(f"UPDATE {table} SET rgb = ARRAY[rgb[3], rgb[2], rgb[1]] WHERE _geoid = %s AND _idx < 20", (geoid,))
    conn.execute(f"DELETE FROM {table} WHERE _geoid = %s AND _idx = 100", (geoid,))
    conn.execute(f"INSERT INTO {table} VALUES (%s, 5000, ARRAY[1, 2, 3], 1, ARRAY[4, 5], ARRAY[6, 7, 8])", (geoid,))
    conn.commit()
    now = {r[1]: r for r in _rows(conn, table)}
    assert 100 not in now and now[5000][2] is not None
    got = conn.execute(
        f"SELECT normal::text, pair, rgb[1:3] FROM {table} WHERE _geoid = %s AND _idx IN (7, 8, 5000) ORDER BY _idx",
        (geoid,),
    ).fetchall()
    assert got[0][0] == "{-0,NaN,2}" and got[1][1] == [8, 99] and got[2][1:] == ([4, 5], [6.0, 7.0, 8.0])
    assert [now[i] for i in range(20, 100)] == [b for b in before if 20 <= b[1] < 100]
    # the Python paths through the face: a new feature fetched back bit for bit, then deleted
    conn.execute("SET track_functions = 'all'")
    other = F.insert_feature(conn, "layer", mesh)
    # set-based (tgsis.write_property_rows: each chunk written once), not a face trigger per row
    calls = conn.execute(
        "SELECT coalesce(sum(calls), 0) FROM pg_stat_xact_user_functions WHERE funcname = 'chunk_face_write'"
    ).fetchone()
    assert calls == (0,)
    conn.commit()
    assert _same(F.fetch_feature(conn, "layer", other).mesh, mesh)
    assert F.delete_feature(conn, "layer", other)
    conn.commit()
    face = _rows(conn, table)
    assert conn.execute("SELECT tgsis.store_class_in_rows('layer')").fetchone() == (len(face),)
    conn.commit()
    assert conn.execute(f"SELECT relkind FROM pg_class WHERE oid = '{table}'::regclass").fetchone() == ("r",)
    assert _rows(conn, table) == face


def test_a_wrong_vector_is_refused_as_on_rows_and_changes_nothing(conn: Conn) -> None:
    geoid, _ = _surface_class(conn, "layer")
    conn.execute("SELECT tgsis.store_class_in_chunks('layer')")
    conn.commit()
    table = "public.layer_cellpros"
    before = _rows(conn, table)
    chunks = conn.execute("SELECT array_send(normal), array_send(pair) FROM public.layer_cellpros_chunk ORDER BY chunk")
    chunk_bits = chunks.fetchall()
    for statement in (
        f"UPDATE {table} SET normal = ARRAY[1, 2] WHERE _geoid = {geoid} AND _idx = 3",
        f"UPDATE {table} SET normal = ARRAY[1, 2, 3, 4] WHERE _geoid = {geoid} AND _idx < 3",
        f"UPDATE {table} SET normal = ARRAY[1, NULL, 3] WHERE _geoid = {geoid} AND _idx = 3",
        f"UPDATE {table} SET pair = '[0:1]={{1,2}}' WHERE _geoid = {geoid} AND _idx = 3",
        f"UPDATE {table} SET pair = '{{{{1,2}}}}' WHERE _geoid = {geoid} AND _idx = 3",
        f"INSERT INTO {table} VALUES ({geoid}, 9000, ARRAY[1, 2, 3], 1, ARRAY[1], ARRAY[1, 2, 3])",
    ):
        with conn.cursor() as cur:
            try:
                cur.execute(statement)
            except psycopg.Error as error:
                # the row table's CHECK, as on rows (tests/test_vector_property_checks.py compares with a twin)
                assert error.sqlstate == "23514", (statement, error)
                assert error.diag.constraint_name in ("layer_cellpros_normal_check", "layer_cellpros_pair_check")
                assert error.diag.message_detail and "values without NULL" in error.diag.message_detail
                assert error.diag.message_hint and "components" in error.diag.message_hint
            else:
                raise AssertionError(f"not refused: {statement}")
        conn.rollback()
    assert _rows(conn, table) == before
    assert (
        conn.execute(
            "SELECT array_send(normal), array_send(pair) FROM public.layer_cellpros_chunk ORDER BY chunk"
        ).fetchall()
        == chunk_bits
    )
    # the client's chunk swap encodes vectors (test_vector_client_codec): its server half stages them, 2-D arrays
    stage = conn.execute("SELECT tgsis.object_chunks_stage('public.layer_cellpros')").fetchone()
    assert stage is not None
    assert conn.execute(
        f"SELECT format_type(atttypid, atttypmod) FROM pg_attribute WHERE attrelid = '{stage[0]}'::regclass AND attname = 'normal'"
    ).fetchone() == ("double precision[]",)
    conn.rollback()
    # NOT NULL: a surface's vertices have every property (23502 naming it, as rows, since the nineteenth session)
    state, message = sqlstate(conn, f"UPDATE {table} SET pair = NULL WHERE _geoid = %s AND _idx = 3", (geoid,))
    assert state == "23502" and 'column "pair"' in message, message
    conn.rollback()


def test_a_null_vector_stays_null_through_the_face(conn: Conn) -> None:
    _vec(conn)
    conn.commit()
    conn.execute("SELECT tgsis.store_class_in_chunks('vec')")
    conn.commit()
    conn.execute(f"UPDATE {VEC} SET normal = NULL, pair = ARRAY[7, 8] WHERE _geoid = 1 AND _idx = 10")
    conn.execute(f"INSERT INTO {VEC} (_geoid, _idx, rgb) VALUES (1, 1025, ARRAY[1, 2, 3])")
    conn.commit()
    got = conn.execute(
        f"SELECT _idx, normal, pair, rgb FROM {VEC} WHERE _geoid = 1 AND _idx IN (10, 1025) ORDER BY _idx"
    ).fetchall()
    assert got == [(10, None, [7, 8], [10.0, 0.0, 1.0]), (1025, None, None, [1.0, 2.0, 3.0])]
    # on rows the same NULL vector, and a vector with a NULL element refused there too (the row table's CHECK)
    assert conn.execute("SELECT tgsis.store_class_in_rows('vec')").fetchone() is not None
    conn.commit()
    assert conn.execute(f"SELECT normal FROM {VEC} WHERE _geoid = 1 AND _idx = 10").fetchone() == (None,)
    assert sqlstate(conn, f"UPDATE {VEC} SET normal = ARRAY[1, NULL, 3] WHERE _geoid = 1 AND _idx = 10")[0] == "23514"


STATEMENTS = [
    "UPDATE {t} SET normal = ARRAY[normal[2], normal[1], normal[3]] WHERE _geoid = 1 AND _idx % 11 = 0",
    "UPDATE {t} SET pair[1] = pair[1] + 1000 WHERE _geoid = 1 AND _idx BETWEEN 1000 AND 1100",
    "UPDATE {t} SET normal = NULL WHERE _geoid = 2 AND _idx = 5",
    "DELETE FROM {t} WHERE _geoid = 1 AND _idx % 13 = 1",
    "INSERT INTO {t} VALUES (1, 1024, ARRAY[1, 2, 3], NULL, NULL, ARRAY['NaN', '-0', 1]::real[])",
    "INSERT INTO {t} VALUES (1, 1, ARRAY[1, 2, 3], 1, ARRAY[1, 2], ARRAY[1, 2, 3])",
    "UPDATE {t} SET _idx = _idx + 5000 WHERE _geoid = 3",
    "UPDATE {t} SET rgb = ARRAY[1, 2] WHERE _geoid = 1 AND _idx = 2",
    "UPDATE {t} SET rgb = ARRAY[1, 2, NULL] WHERE _geoid = 1 AND _idx = 2",
    "WITH d AS (DELETE FROM {t} WHERE _geoid = 2 AND _idx = 10 RETURNING *) "
    "INSERT INTO {t} SELECT _geoid, _idx + 1, normal, t, pair, rgb FROM d",
]


def test_statements_through_the_face_answer_as_on_rows(conn: Conn) -> None:
    _vec(conn, "vec")
    _vec(conn, "kept")
    conn.commit()
    conn.execute("SELECT tgsis.store_class_in_chunks('vec')")
    conn.commit()
    for statement in STATEMENTS:
        answers = []
        for table in (VEC, "public.kept_cellpros"):
            state, _ = sqlstate(conn, statement.format(t=table))
            # a wrong vector: the row table's CHECK (23514) on both
            answers.append(state)
            if state is None:
                conn.commit()
            else:
                conn.rollback()
        assert answers[0] == answers[1], (statement, answers)
        assert _rows(conn, VEC) == _rows(conn, "public.kept_cellpros"), statement


def test_add_rename_drop_of_a_vector_property_on_chunks(conn: Conn) -> None:
    geoid, _ = _surface_class(conn, "layer")
    conn.execute("SELECT tgsis.store_class_in_chunks('layer')")
    conn.commit()
    table = "public.layer_cellpros"
    before = _rows(conn, table)
    # (adding and renaming a vector property in chunks: tests/test_vector_property_alter.py)
    assert _rows(conn, table) == before
    # a scalar added beside the vectors, and a vector dropped: in place
    assert (
        w := sqlstate(conn, """SELECT tgsis.add_property('layer', 'cell', '{"name": "weight", "type": "real"}', '2')""")
    ) == (
        None,
        "",
    ), w
    conn.commit()
    assert conn.execute(f"SELECT pair, weight FROM {table} WHERE _geoid = %s AND _idx = 3", (geoid,)).fetchone() == (
        [3, -3],
        2.0,
    )
    assert sqlstate(conn, "SELECT tgsis.drop_property('layer', 'pair', p_force => true)") == (None, "")
    conn.commit()
    assert conn.execute(f"SELECT normal[3] FROM {table} WHERE _geoid = %s AND _idx = 7", (geoid,)).fetchone() == (1.0,)


def test_roles_through_the_face(db_dsn: str, conn: Conn) -> None:
    geoid, _ = _surface_class(conn, "layer")
    conn.execute("SELECT tgsis.store_class_in_chunks('layer')")
    conn.commit()
    with login_roles(db_dsn, {"reader": "tgsis_reader", "editor": "tgsis_editor"}) as roles:
        reader = roles.connect("reader")
        assert reader.execute(
            "SELECT normal FROM public.layer_cellpros WHERE _geoid = %s AND _idx = 5", (geoid,)
        ).fetchone() == ([np.sin(5), np.cos(5), 5 / 7.0],)
        update = "UPDATE public.layer_cellpros SET pair = ARRAY[1, 1] WHERE _geoid = %s AND _idx = 5"
        assert sqlstate(reader, update, (geoid,))[0] == "42501"
        assert _same_fetch(reader, geoid)
        reader.rollback()
        editor = roles.connect("editor")
        assert sqlstate(editor, update, (geoid,)) == (None, "")
        editor.commit()
        assert sqlstate(editor, "UPDATE public.layer_cellpros_chunk SET pair[1][1] = 0")[0] == "42501"
        editor.rollback()
        close_and_wait_gone(editor, conn)
    assert conn.execute(
        "SELECT pair FROM public.layer_cellpros WHERE _geoid = %s AND _idx = 5", (geoid,)
    ).fetchone() == ([1, 1],)


def _same_fetch(conn: Conn, geoid: int) -> bool:
    mesh: Any = F.fetch_feature(conn, "layer", geoid).mesh
    return bool(mesh.vertex_properties["normal"].shape == (mesh.n_vertices, 3))


@pytest.mark.parametrize("fmt", ["custom"])
def test_pg_dump_and_restore_keep_the_vector_chunks(
    pg: TestServer, db_dsn: str, conn: Conn, tmp_path: Path, fmt: str
) -> None:
    from tests.test_backup import _bindir_of, _restored

    _vec(conn)
    # (pg_dump writes floats as text, which keeps no NaN payload: on rows as on chunks)
    conn.execute(
        f"UPDATE {VEC} SET normal = ARRAY(SELECT CASE WHEN x = 'NaN' THEN 'NaN' ELSE x END FROM unnest(normal) AS x) "
        "WHERE normal IS NOT NULL"
    )
    conn.commit()
    conn.execute("SELECT tgsis.store_class_in_chunks('vec')")
    conn.commit()
    before = _rows(conn, VEC)
    bits = "SELECT _geoid, chunk, holes, array_send(normal), array_send(pair), array_send(rgb) FROM public.vec_cellpros_chunk ORDER BY 1, 2"
    chunks = conn.execute(bits).fetchall()
    conn.rollback()
    with _restored(pg, _bindir_of(pg), db_dsn, fmt, tmp_path) as dsn, psycopg.connect(dsn) as copy:
        assert copy.execute(bits).fetchall() == chunks
        assert _rows(copy, VEC) == before
        copy.execute(f"UPDATE {VEC} SET pair = ARRAY[5, 6] WHERE _geoid = 1 AND _idx = 9")
        copy.commit()
        assert copy.execute(f"SELECT pair FROM {VEC} WHERE _geoid = 1 AND _idx = 9").fetchone() == ([5, 6],)


# --------------------------------------------------------------------------- versioned: the same operations on rows and on chunks


def _twin_rows(conn: Conn, name: str) -> list[tuple[Any, ...]]:
    """The class's rows with each geoid replaced by its rank (the twins' objects have geoids of their own)."""
    rows = _rows(conn, f"public.{name}_cellpros")
    rank = {g: i for i, g in enumerate(sorted({r[0] for r in rows}))}
    return [(rank[r[0]], *r[1:]) for r in rows]


def test_a_versioned_class_answers_as_its_twin_on_rows(conn: Conn) -> None:
    """Two classes alike, versioned; one in chunks: edits in two versions, an insert, a merge, compress, every view."""
    geoids = {}
    for name in ("onrows", "inchunks"):
        tgsis.create_feature_class(
            conn,
            name,
            "SURFACE",
            cell_properties=[
                ("normal", "double precision", 3),
                ("t", "real"),
                ("pair", "integer", 2),
                ("rgb", "real", 3),
            ],
        )
    tgsis.enable_feature_versioning(conn)
    mesh = None
    for name in ("onrows", "inchunks"):
        geoids[name], mesh = _insert_mesh(conn, name)
    tgsis.create_version(conn, "e1")
    conn.commit()
    assert conn.execute("SELECT tgsis.store_class_in_chunks('inchunks')").fetchone() is not None
    conn.commit()
    assert _twin_rows(conn, "onrows") == _twin_rows(conn, "inchunks")
    edits = [
        ("e1", "UPDATE {t} SET normal = ARRAY[-1, -2, -3] WHERE _geoid = {g} AND _idx < 40"),
        ("e1", "UPDATE {t} SET pair[2] = 7 WHERE _geoid = {g} AND _idx BETWEEN 100 AND 110"),
        ("DEFAULT", "UPDATE {t} SET rgb = ARRAY[9, 9, 9] WHERE _geoid = {g} AND _idx >= 140"),
        ("e1", "DELETE FROM {t} WHERE _geoid = {g} AND _idx % 77 = 3"),
        (
            "DEFAULT",
            "INSERT INTO {t} VALUES ({g}, 4000, ARRAY['NaN', '-0', 1]::double precision[], 1, ARRAY[1, 2], ARRAY[1, 2, 3])",
        ),
    ]
    for version, edit in edits:
        for name in ("onrows", "inchunks"):
            with tgsis.in_version(conn, version):
                conn.execute(edit.format(t=f"public.{name}_cellpros", g=geoids[name]))
                conn.commit()
    with tgsis.in_version(conn, "e1"):
        new = {}
        for name in ("onrows", "inchunks"):
            assert mesh is not None
            new[name] = F.insert_feature(conn, name, mesh)
        conn.commit()
        assert _twin_rows(conn, "onrows") == _twin_rows(conn, "inchunks")
        # (the edited objects lack deleted vertices' rows: fetch_feature reads the new ones)
        a = F.fetch_feature(conn, "onrows", new["onrows"]).mesh
        b = F.fetch_feature(conn, "inchunks", new["inchunks"]).mesh
        assert mesh is not None and _same(a, mesh) and _same(b, mesh)
    conn.commit()
    assert _twin_rows(conn, "onrows") == _twin_rows(conn, "inchunks")
    tgsis.merge_version(conn, "e1")
    conn.commit()
    assert _twin_rows(conn, "onrows") == _twin_rows(conn, "inchunks")
    from tests.merge_data import every_view

    for version, revision in every_view(conn):
        if revision is None:
            conn.execute("SELECT tgsis.goto_version(%s, true)", (version,))
        else:
            conn.execute("SELECT tgsis.goto_revision(%s, %s, true)", (version, revision))
        assert _twin_rows(conn, "onrows") == _twin_rows(conn, "inchunks"), (version, revision)
    conn.execute("SELECT tgsis.goto_version('DEFAULT', true)")
    tgsis.compress_versions(conn)
    conn.commit()
    assert _twin_rows(conn, "onrows") == _twin_rows(conn, "inchunks")
    assert conn.execute("SELECT tgsis.store_class_in_rows('inchunks')").fetchone() is not None
    conn.commit()
    assert _twin_rows(conn, "onrows") == _twin_rows(conn, "inchunks")


def _insert_mesh(conn: Conn, name: str) -> tuple[int, Surface]:
    surface = curved_surface()
    n = surface.n_vertices
    normal = np.stack([np.sin(np.arange(n)), np.cos(np.arange(n)), np.arange(n) / 7.0], axis=1)
    normal[:4, 0] = [_double(p) for p in PATTERNS]
    props = {
        "normal": normal,
        "t": (np.arange(n) / 3.0).astype(np.float32),
        "pair": np.stack([np.arange(n), -np.arange(n)], axis=1).astype(np.int32),
        "rgb": np.stack([np.arange(n) % 256, np.zeros(n), np.ones(n)], axis=1).astype(np.float32),
    }
    mesh = Surface(surface.vertices, surface.cells, vertex_properties=props)
    return F.insert_feature(conn, name, mesh), mesh


def test_more_values_a_slot_than_the_readers_unnest_is_refused_by_name(conn: Conn) -> None:
    # 98 values a slot are stored (a vector counts its size); 99 are refused by name, nothing made
    tgsis.create_feature_class(conn, "wide", "SURFACE", cell_properties=[("v", "real", 97), ("t", "real")])
    tgsis.create_feature_class(conn, "wider", "SURFACE", cell_properties=[("v", "real", 98), ("t", "real")])
    conn.execute(
        "INSERT INTO public.wide_cellpros SELECT 1, i, array_fill(i::real, ARRAY[97]), 1 FROM generate_series(0, 9) i"
    )
    conn.commit()
    assert conn.execute("SELECT tgsis.store_class_in_chunks('wide')").fetchone() == (1,)
    assert conn.execute("SELECT v[97], t FROM public.wide_cellpros WHERE _idx = 9").fetchone() == (9.0, 1.0)
    conn.execute("UPDATE public.wide_cellpros SET v[5] = -1 WHERE _idx = 9")
    assert conn.execute("SELECT v[4:6] FROM public.wide_cellpros WHERE _idx = 9").fetchone() == ([9.0, -1.0, 9.0],)
    conn.commit()
    state, message = sqlstate(conn, "SELECT tgsis.store_class_in_chunks('wider')")
    assert state == "TG100" and "more than 98 property values" in message, message
    assert conn.execute("SELECT to_regclass('public.wider_cellpros_chunk')").fetchone() == (None,)
