"""A feature class's property table in chunks (issue 40, area K): the foundation, opt-in.

docs/storage.md, "Property chunks: the contract": ``<schema>.<class>_cellpros`` of a STATIC
class is chunked by ``_idx`` like the table it is aligned with, one array per property of the
property's own type, NULL values kept apart from holes. The chunk layer's functions take the
table as ``tgsis.chunk_registry`` names it (``'public.rock_cellpros'``); these tests build
rows (plain SQL and the public API), convert them both ways and compare value for value
(doubles and reals by their bits), unversioned and versioned. The property tables are rows
on both storages of model 1, so the file runs unmarked (chunks on 15, rows on 18).
"""

from __future__ import annotations

import math
import struct
from pathlib import Path
from typing import Any

import numpy as np
import psycopg
import pytest
from psycopg import sql

import tgsis
from tests.merge_data import SIDE, curved_surface, every_view, sqlstate, varied_history
from tests.roles import login_roles
from tests.sessions import Background, connect, wait_until_blocked
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


TYPES = [
    ("p_i2", "smallint"),
    ("p_i4", "integer"),
    ("p_i8", "bigint"),
    ("p_f4", "real"),
    ("p_f8", "double precision"),
    ("p_b", "boolean"),
]
ROCK = "public.rock_cellpros"
#: float8 bit patterns that must survive: -0.0, the smallest subnormal, a NaN with a payload, 1 + 1 ulp
PATTERNS = [0x8000000000000000, 0x0000000000000001, 0x7FF8000000000ABC, 0x3FF0000000000001]


def _double(bits: int) -> float:
    value: float = struct.unpack(">d", struct.pack(">Q", bits))[0]
    return value


def _columns(table: str) -> sql.Composable:
    """The compared columns of a property table: keys, then each property, floats by their bits."""
    out: list[sql.Composable] = [sql.SQL("_geoid"), sql.SQL("_idx")]
    for name, typename in TYPES if table.startswith("public.rock") else [("porosity", "double precision")]:
        if typename == "double precision":
            out.append(sql.SQL("float8send({})").format(sql.Identifier(name)))
        elif typename == "real":
            out.append(sql.SQL("float4send({})").format(sql.Identifier(name)))
        else:
            out.append(sql.Identifier(name))
    return sql.SQL(", ").join(out)


def _rows(conn: Conn, relation: str, where: str = "true") -> list[tuple[Any, ...]]:
    query = sql.SQL("SELECT {} FROM {} c WHERE {} ORDER BY 1, 2").format(
        _columns(relation), sql.SQL(relation), sql.SQL(where)
    )
    return [tuple(r) for r in conn.execute(query).fetchall()]


def _rock(conn: Conn, geotype: str = "SURFACE") -> None:
    """Class rock with one property of each type, and rows written by plain SQL: holes, odd values, a far id."""
    tgsis.create_feature_class(conn, "rock", geotype, cell_properties=TYPES)
    # 3 objects; object 1: ids 0..2999 with holes, object 2: a few ids and one beyond int4, object 3: one row
    conn.execute(
        "INSERT INTO public.rock_cellpros (_geoid, _idx, p_i2, p_i4, p_i8, p_f4, p_f8, p_b) "
        "SELECT 1, i, (i % 300 - 150)::smallint, i * 7 - 5000, i::bigint * 1000000007, (i / 3.0)::real, "
        "sin(i) * 1e3, i % 3 = 0 FROM generate_series(0, 2999) i WHERE i % 97 <> 5 AND i NOT IN (1024, 1025, 2047)"
    )
    for k, bits in enumerate(PATTERNS):
        conn.execute(
            "INSERT INTO public.rock_cellpros VALUES (2, %s, 32767, -2147483648, -9223372036854775808, "
            "'-0'::real, %s, false)",
            (k * 5, _double(bits)),
        )
    conn.execute(
        "INSERT INTO public.rock_cellpros VALUES (2, %s, -32768, 2147483647, 9223372036854775807, 'NaN'::real, "
        "'-Infinity', true)",
        (2**40 + 3,),
    )
    conn.execute("INSERT INTO public.rock_cellpros VALUES (3, 1023, 0, 0, 0, 0, 0, true)")


def _make(conn: Conn, table: str = ROCK) -> None:
    conn.execute("SELECT tgsis.create_chunk_table(%s), tgsis.create_chunk_view(%s)", (table, table))


def _storage(conn: Conn, table: str) -> str:
    schema, name = table.split(".")
    row = conn.execute("SELECT tgsis.storage_table(%s, %s)", (schema, name)).fetchone()
    assert row is not None
    return str(row[0])


# --------------------------------------------------------------------------- the layout and the round trip


def test_the_registry_knows_property_tables_of_models_1_to_3_and_nothing_else(conn: Conn) -> None:
    _rock(conn)
    tgsis.create_feature_class(conn, "series", "SURFACE", time_model="INSTANTS", cell_properties=[("t", "real")])
    tgsis.create_feature_class(conn, "cells", "GMAP", time_model="GMAP", cell_properties=[("t", "real")], cell_level=0)
    assert conn.execute("SELECT * FROM tgsis.chunk_registry(%s)", (ROCK,)).fetchall() == [
        ("public", "rock_cellpros", "_geoid", "_idx", [], 1024, "rock")
    ]
    assert conn.execute("SELECT count(*) FROM tgsis.chunk_registry('vrtx')").fetchone() == (1,)
    # an INSTANTS or EVOLVING class's table is registered (plan O area C), keyed by its instants too
    assert conn.execute("SELECT * FROM tgsis.chunk_registry('public.series_cellpros')").fetchall() == [
        ("public", "series_cellpros", "_geoid", "_idx", [], 1024, "series")
    ]
    # a G-map model's class table, the feature table, an unquoted name: not registered
    for name in ("public.cells_cellpros", "public.rock", "rock_cellpros", "public.nothere"):
        state, message = sqlstate(conn, "SELECT tgsis.create_chunk_table(%s)", (name,))
        assert state == "TG200" and "not registered for chunks" in message, (name, message)
    roles = conn.execute(
        "SELECT name, role, typename FROM tgsis.chunk_columns(%s) ORDER BY colorder", (ROCK,)
    ).fetchall()
    assert roles == [("_geoid", "key", "bigint"), ("_idx", "chunk", "bigint")] + [(n, "value", t) for n, t in TYPES]


def test_unversioned_rows_to_chunks_and_back_bit_for_bit(conn: Conn) -> None:
    _rock(conn)
    before = _rows(conn, ROCK)
    _make(conn)
    written = conn.execute("SELECT tgsis.rows_to_chunks(%s)", (ROCK,)).fetchone()
    expected = conn.execute("SELECT count(DISTINCT (_geoid, _idx >> 10)) FROM public.rock_cellpros").fetchone()
    assert expected is not None and written == expected and expected[0] == 3 + 2 + 1
    # the layout: the property's own array types, holes, revision 0
    types = conn.execute(
        "SELECT attname, format_type(atttypid, atttypmod) FROM pg_attribute "
        "WHERE attrelid = 'public.rock_cellpros_chunk'::regclass AND attnum > 0 ORDER BY attnum"
    ).fetchall()
    assert types == [
        ("_geoid", "bigint"),
        ("chunk", "bigint"),
        ("revision", "integer"),
        ("lastrevs", "integer[]"),
        ("revclosed", "boolean"),
        ("holes", "smallint[]"),
    ] + [(n, f"{t}[]") for n, t in TYPES]
    first = conn.execute(
        "SELECT revision, lastrevs, holes, cardinality(p_i4) FROM public.rock_cellpros_chunk WHERE _geoid = 1 AND chunk = 1"
    ).fetchone()
    # ids 1024, 1025 are holes; 2047 is absent too, so the arrays end at slot 1023 (no trailing hole)
    assert first is not None and first[:2] == (0, []) and first[2][:2] == [1, 2] and first[3] == 1023
    assert _rows(conn, "public.rock_cellpros_chunk_rows") == before
    # the way back, into the emptied rows, gives the same rows bit for bit
    conn.execute("DELETE FROM public.rock_cellpros")
    back = conn.execute("SELECT tgsis.chunks_to_rows(%s)", (ROCK,)).fetchone()
    assert back == (len(before),)
    assert _rows(conn, ROCK) == before
    bits = conn.execute(
        "SELECT float8send(p_f8) FROM public.rock_cellpros WHERE _geoid = 2 AND _idx < 100 ORDER BY _idx"
    )
    assert [bytes(b[0]) for b in bits.fetchall()] == [struct.pack(">Q", p) for p in PATTERNS]
    reals = conn.execute("SELECT float4send(p_f4) FROM public.rock_cellpros WHERE _geoid = 2 ORDER BY _idx").fetchall()
    assert bytes(reals[0][0]) == struct.pack(">f", -0.0) and math.isnan(struct.unpack(">f", bytes(reals[-1][0]))[0])


def test_null_values_are_kept_apart_from_holes(conn: Conn) -> None:
    # a collection's members may lack a property: its columns allow NULL
    _rock(conn, "GEOMETRYCOLLECTION")
    conn.execute("UPDATE public.rock_cellpros SET p_f8 = NULL, p_b = NULL WHERE _geoid = 1 AND _idx % 10 = 0")
    conn.execute("INSERT INTO public.rock_cellpros (_geoid, _idx) VALUES (3, 5000)")  # a row of NULLs only
    before = _rows(conn, ROCK)
    _make(conn)
    conn.execute("SELECT tgsis.rows_to_chunks(%s)", (ROCK,))
    assert _rows(conn, "public.rock_cellpros_chunk_rows") == before
    only_nulls = conn.execute(
        "SELECT holes, p_i4 FROM public.rock_cellpros_chunk WHERE _geoid = 3 AND chunk = 4"
    ).fetchone()
    assert only_nulls is not None and only_nulls[1][-1] is None and len(only_nulls[0]) == 5000 - 4096
    conn.execute("DELETE FROM public.rock_cellpros")
    conn.execute("SELECT tgsis.chunks_to_rows(%s)", (ROCK,))
    assert _rows(conn, ROCK) == before


def test_versioned_every_version_and_revision_sees_the_same(conn: Conn, fault_clone: int) -> None:
    varied_history(conn, fault_clone)
    table = "public.faults_cellpros"
    storage = _storage(conn, table)
    assert storage == "public.faults_cellpros_ver"
    closed = conn.execute(sql.SQL("SELECT count(*) FILTER (WHERE revclosed) FROM {}").format(sql.SQL(storage)))
    assert closed.fetchone() != (0,)  # a real history
    _make(conn, table)
    written = conn.execute("SELECT tgsis.rows_to_chunks(%s)", (table,)).fetchone()
    assert written is not None and written[0] > 1
    # rows_to_chunks proved every set (check_chunk_conversion); compare here too, through the versioned view
    visible = "(c.revision = ANY (tgsis.get_revisions(true))) IS TRUE AND NOT (c.lastrevs && tgsis.get_revisions(true))"
    compared = 0
    for version, revision in every_view(conn):
        if revision is None:
            conn.execute("SELECT tgsis.goto_version(%s, true)", (version,))
        else:
            conn.execute("SELECT tgsis.goto_revision(%s, %s, true)", (version, revision))
        assert _rows(conn, "public.faults_cellpros_chunk_rows", visible) == _rows(conn, table), (version, revision)
        compared += 1
    assert compared >= 10
    chunk_rows = conn.execute("SELECT * FROM public.faults_cellpros_chunk ORDER BY 1, 2, 3").fetchall()
    # the round trip: chunks -> rows -> chunks gives the same chunk versions
    conn.execute(sql.SQL("DELETE FROM {}").format(sql.SQL(storage)))
    conn.execute("SELECT tgsis.chunks_to_rows(%s)", (table,))
    conn.execute("DELETE FROM public.faults_cellpros_chunk")
    conn.execute("SELECT tgsis.rows_to_chunks(%s)", (table,))
    assert conn.execute("SELECT * FROM public.faults_cellpros_chunk ORDER BY 1, 2, 3").fetchall() == chunk_rows
    conn.rollback()


def test_verification_catches_a_changed_value_and_a_null_at_a_hole(conn: Conn) -> None:
    _rock(conn)
    _make(conn)
    conn.execute("SELECT tgsis.rows_to_chunks(%s)", (ROCK,))
    conn.commit()
    # a flipped sign bit of -0.0: the same number, not the same bits
    conn.execute("UPDATE public.rock_cellpros_chunk SET p_f8[1] = 0.0 WHERE _geoid = 2 AND chunk = 0")
    state, message = sqlstate(conn, "SELECT tgsis.check_chunk_conversion(%s)", (ROCK,))
    assert state == "TG000" and "differ from its rows" in message and "object _geoid 2" in message
    conn.rollback()
    # a value at a listed hole: not encoded as the readers read it
    conn.execute("UPDATE public.rock_cellpros_chunk SET p_i4[2] = 7 WHERE _geoid = 2 AND chunk = 0")
    state, message = sqlstate(conn, "SELECT tgsis.check_chunk_conversion(%s)", (ROCK,))
    assert state == "TG000" and "not encoded" in message
    conn.rollback()


def test_refusals_by_name(conn: Conn) -> None:
    # (vector properties have a chunk form: tests/test_vector_property_chunks.py)
    _rock(conn)
    _make(conn)
    conn.execute("SELECT tgsis.rows_to_chunks(%s)", (ROCK,))
    assert sqlstate(conn, "SELECT tgsis.rows_to_chunks(%s)", (ROCK,))[0] == "TG201"
    assert sqlstate(conn, "SELECT tgsis.chunks_to_rows(%s)", (ROCK,))[0] == "TG201"
    assert sqlstate(conn, "SELECT tgsis.create_chunk_table(%s)", (ROCK,))[0] == "TG201"


def test_the_chunk_table_keeps_the_class_tables_grants(db_dsn: str, conn: Conn) -> None:
    _rock(conn)
    _make(conn)
    conn.execute("SELECT tgsis.rows_to_chunks(%s)", (ROCK,))
    conn.commit()
    grants = (
        "SELECT grantee, privilege_type FROM information_schema.role_table_grants "
        "WHERE table_schema = 'public' AND table_name = %s AND grantee LIKE 'tgsis%%' ORDER BY 1, 2"
    )
    expected = conn.execute(grants, ("rock_cellpros",)).fetchall()
    # the class table's readers read the chunks (the decoded view is security_invoker); nobody but the owner writes them
    assert expected and conn.execute(grants, ("rock_cellpros_chunk",)).fetchall() == [
        g for g in expected if g[1] == "SELECT"
    ]
    with login_roles(db_dsn, {"reader": "tgsis_reader", "editor": "tgsis_editor"}) as roles:
        reader = roles.connect("reader")
        assert (
            reader.execute("SELECT count(*) FROM public.rock_cellpros_chunk_rows").fetchone()
            == reader.execute("SELECT count(*) FROM public.rock_cellpros").fetchone()
        )
        for statement in ("SELECT tgsis.rows_to_chunks('public.rock_cellpros')", "SELECT tgsis.chunk_registry('vrtx')"):
            assert sqlstate(reader, statement)[0] == "42501"
        # an editor writes through the face only: the chunk table grants roles SELECT alone
        editor = roles.connect("editor")
        state, _ = sqlstate(
            editor,
            "INSERT INTO public.rock_cellpros_chunk (_geoid, chunk, revision, holes, p_i2, p_i4, p_i8, p_f4, p_f8, p_b) "
            "VALUES (9, 0, 0, '{1}', '{1,2}', '{1,2}', '{1,2}', '{1,2}', '{1,2}', '{t,f}')",
        )
        assert state == "42501"


# --------------------------------------------------------------------------- the opt-in switch: the face over the chunks


def _surface_class(conn: Conn, name: str = "layer", nan_payload: bool = True) -> tuple[int, Any]:
    """A class with a double and an integer vertex property, and one curved surface stored in it.

    The first porosity values are PATTERNS' bits (-0.0, a subnormal, a NaN with a payload, 1 + 1 ulp); without
    ``nan_payload`` the NaN is the canonical one (pg_dump writes floats as text, which keeps no NaN payload:
    on rows as on chunks).
    """
    tgsis.create_feature_class(
        conn, name, "SURFACE", cell_properties=[("porosity", "double precision"), ("facies", "integer")]
    )
    surface = curved_surface()
    vertex_properties = {
        "porosity": surface.vertex_properties["porosity"].copy(),
        "facies": (np.arange(surface.n_vertices, dtype=np.int32) % 7) - 3,
    }
    vertex_properties["porosity"][:4] = [
        _double(p if nan_payload or p != 0x7FF8000000000ABC else 0x7FF8000000000000) for p in PATTERNS
    ]
    mesh = Surface(surface.vertices, surface.cells, vertex_properties=vertex_properties)
    geoid = F.insert_feature(conn, name, mesh)
    conn.commit()
    return geoid, mesh


def _layer_rows(conn: Conn, name: str = "layer") -> list[tuple[Any, ...]]:
    query = sql.SQL("SELECT _geoid, _idx, float8send(porosity), facies FROM public.{} ORDER BY 1, 2").format(
        sql.Identifier(f"{name}_cellpros")
    )
    return [tuple(r) for r in conn.execute(query).fetchall()]


def _same_properties(a: Any, b: Any) -> bool:
    return bool(
        np.array_equal(a.vertices.view(np.int64), b.vertices.view(np.int64))
        and np.array_equal(a.cells, b.cells)
        and np.array_equal(
            a.vertex_properties["porosity"].view(np.int64), b.vertex_properties["porosity"].view(np.int64)
        )
        and np.array_equal(a.vertex_properties["facies"], b.vertex_properties["facies"])
    )


def test_store_class_in_chunks_reads_writes_and_back(conn: Conn) -> None:
    geoid, mesh = _surface_class(conn)
    before_rows = _layer_rows(conn)
    before = F.fetch_feature(conn, "layer", geoid).mesh
    assert _same_properties(before, mesh)
    written = conn.execute("SELECT tgsis.store_class_in_chunks('layer')").fetchone()
    conn.commit()
    assert written == (-(-mesh.n_vertices // 1024),)
    assert conn.execute("SELECT relkind FROM pg_class WHERE oid = 'public.layer_cellpros'::regclass").fetchone() == (
        "v",
    )
    assert conn.execute("SELECT count(*) FROM public.layer_cellpros_chunk").fetchone() == written
    # the face reads what the rows held, and fetch_feature gives the same mesh, bits included
    assert _layer_rows(conn) == before_rows
    assert _same_properties(F.fetch_feature(conn, "layer", geoid).mesh, mesh)
    # one value changed through the face by psql: that value only
    conn.execute(
        "UPDATE public.layer_cellpros SET porosity = '-0'::double precision, facies = 99 WHERE _geoid = %s AND _idx = 7",
        (geoid,),
    )
    conn.commit()
    after = _layer_rows(conn)
    changed = [(a, b) for a, b in zip(before_rows, after, strict=True) if a != b]
    assert changed == [(before_rows[7], (geoid, 7, struct.pack(">d", -0.0), 99))]
    # a bulk UPDATE, an INSERT and a DELETE through the face
    conn.execute("UPDATE public.layer_cellpros SET facies = facies + 1 WHERE _geoid = %s AND _idx < 5", (geoid,))
    conn.execute("DELETE FROM public.layer_cellpros WHERE _geoid = %s AND _idx = 100", (geoid,))
    conn.execute("INSERT INTO public.layer_cellpros VALUES (%s, 5000, 1.5, 2)", (geoid,))
    assert sqlstate(conn, "INSERT INTO public.layer_cellpros VALUES (%s, 7, 1.0, 1)", (geoid,))[0] == "23505"
    # a NULL in a NOT NULL property: as the row table answers (23502 naming it, since the nineteenth session)
    state, message = sqlstate(conn, "INSERT INTO public.layer_cellpros VALUES (%s, 6000, NULL, 1)", (geoid,))
    assert state == "23502" and 'column "porosity"' in message, message
    conn.commit()
    now = {r[1]: r for r in _layer_rows(conn)}
    assert 100 not in now and now[5000] == (geoid, 5000, struct.pack(">d", 1.5), 2)
    assert [now[i][3] for i in range(5)] == [before_rows[i][3] + 1 for i in range(5)]
    holes = conn.execute(
        "SELECT holes FROM public.layer_cellpros_chunk WHERE _geoid = %s AND chunk = 0", (geoid,)
    ).fetchone()
    assert holes == ([101],)
    # the Python paths through the face: a new feature, fetched back, and deleted
    other = F.insert_feature(conn, "layer", mesh)
    conn.commit()
    assert _same_properties(F.fetch_feature(conn, "layer", other).mesh, mesh)
    assert F.delete_feature(conn, "layer", other)
    conn.commit()
    assert conn.execute("SELECT count(*) FROM public.layer_cellpros WHERE _geoid = %s", (other,)).fetchone() == (0,)
    # back to rows: the same rows, bit for bit, and a table again
    face = _layer_rows(conn)
    assert conn.execute("SELECT tgsis.store_class_in_rows('layer')").fetchone() == (len(face),)
    conn.commit()
    assert conn.execute("SELECT relkind FROM pg_class WHERE oid = 'public.layer_cellpros'::regclass").fetchone() == (
        "r",
    )
    assert _layer_rows(conn) == face
    for gone in ("layer_cellpros_chunk", "layer_cellpros_chunk_rows", "layer_cellpros_shape"):
        assert conn.execute("SELECT to_regclass(%s)", (f"public.{gone}",)).fetchone() == (None,)
    assert conn.execute(
        "SELECT obj_description('public.layer_cellpros'::regclass, 'pg_class') LIKE 'tgsis feature class layer: vertex%'"
    ).fetchone() == (True,)


def test_roles_keep_the_class_tables_rights_through_the_face(db_dsn: str, conn: Conn) -> None:
    geoid, _ = _surface_class(conn)
    conn.execute("SELECT tgsis.store_class_in_chunks('layer')")
    conn.commit()
    with login_roles(db_dsn, {"reader": "tgsis_reader", "editor": "tgsis_editor", "admin": "tgsis_admin"}) as roles:
        reader = roles.connect("reader")
        assert reader.execute("SELECT count(*) FROM public.layer_cellpros").fetchone() == (SIDE * SIDE,)
        update = "UPDATE public.layer_cellpros SET facies = 5 WHERE _geoid = %s AND _idx = 3"
        assert sqlstate(reader, update, (geoid,))[0] == "42501"
        assert sqlstate(reader, "SELECT tgsis.store_class_in_rows('layer')")[0] == "42501"
        editor = roles.connect("editor")
        assert sqlstate(editor, update, (geoid,)) == (None, "")
        editor.commit()
        assert sqlstate(editor, "SELECT tgsis.store_class_in_rows('layer')")[0] == "42501"
        # the chunk table itself: the editor's direct UPDATE of a chunk is not granted
        assert sqlstate(editor, "UPDATE public.layer_cellpros_chunk SET facies[1] = 0")[0] == "42501"
        # (the switch back takes the face's name: the others' transactions end first, or it waits for them)
        reader.rollback()
        editor.rollback()
        admin = roles.connect("admin")
        # the editor, idle after it wrote through the face, holds nothing of its row type (its work tables went
        # with its transaction: ON COMMIT DROP), so the way back goes through while it stays connected
        assert sqlstate(admin, "SELECT tgsis.store_class_in_rows('layer')") == (None, "")
        admin.commit()
    assert conn.execute(
        "SELECT facies FROM public.layer_cellpros WHERE _geoid = %s AND _idx = 3", (geoid,)
    ).fetchone() == (5,)


def test_what_is_not_built_is_refused_by_name_and_changes_nothing(conn: Conn) -> None:
    geoid, _ = _surface_class(conn)
    assert sqlstate(conn, "SELECT tgsis.store_class_in_rows('layer')")[0] == "TG200"
    conn.execute("SELECT tgsis.store_class_in_chunks('layer')")
    conn.commit()
    assert sqlstate(conn, "SELECT tgsis.store_class_in_chunks('layer')")[0] == "TG201"
    before = _layer_rows(conn)
    # (add_property, rename_property and drop_property on chunks: tests/test_property_chunk_transfer.py)
    # a feature property is no column of the property table: it is added as before
    assert sqlstate(conn, """SELECT tgsis.add_property('layer', 'feature', '{"name": "note", "type": "text"}')""") == (
        None,
        "",
    )
    assert _layer_rows(conn) == before
    assert sqlstate(conn, "SELECT tgsis.store_class_in_chunks('nothere')")[0] == "TG200"
    tgsis.create_feature_class(conn, "cells", "GMAP", time_model="GMAP", cell_properties=[("t", "real")], cell_level=0)
    assert sqlstate(conn, "SELECT tgsis.store_class_in_chunks('cells')")[0] == "TG100"
    # (a vector property is stored in chunks since plan K: tests/test_vector_property_chunks.py)
    tgsis.create_feature_class(conn, "bare", "SURFACE")  # no vertex or cell property: nothing to chunk
    state, message = sqlstate(conn, "SELECT tgsis.store_class_in_chunks('bare')")
    assert state == "TG100" and "no property column" in message
    # dropping the class drops its chunks too
    assert tgsis.drop_feature_class(conn, "layer", force=True) == 1
    conn.commit()
    for gone in ("layer_cellpros", "layer_cellpros_chunk", "layer_cellpros_chunk_rows", "layer_cellpros_shape"):
        assert conn.execute("SELECT to_regclass(%s)", (f"public.{gone}",)).fetchone() == (None,), gone
    assert geoid > 0


def test_a_class_registered_without_versioning_switches_beside_versioned_ones(conn: Conn) -> None:
    tgsis.create_feature_class(conn, "plain", "SURFACE", cell_properties=[("p", "real")], versioned=False)
    tgsis.enable_feature_versioning(conn)
    tgsis.create_feature_class(conn, "kept", "SURFACE", cell_properties=[("p", "real")])
    conn.commit()
    # a versioned class switches too (tests/test_property_chunks_versioned.py)
    assert conn.execute("SELECT tgsis.store_class_in_chunks('kept')").fetchone() == (0,)
    # a class registered without versioning switches, and is written in DEFAULT as its rows were
    assert conn.execute("SELECT tgsis.store_class_in_chunks('plain')").fetchone() == (0,)
    conn.execute("INSERT INTO public.plain_cellpros VALUES (1, 0, 2.5)")
    conn.commit()
    assert conn.execute("SELECT _geoid, _idx, p FROM public.plain_cellpros").fetchall() == [(1, 0, 2.5)]


def test_two_writers_of_one_chunk_keep_both_values(db_dsn: str, conn: Conn) -> None:
    geoid, _ = _surface_class(conn)
    conn.execute("SELECT tgsis.store_class_in_chunks('layer')")
    conn.commit()
    first = connect(db_dsn, "first")
    first.execute("UPDATE public.layer_cellpros SET facies = 41 WHERE _geoid = %s AND _idx = 1", (geoid,))

    def second_writer(session: Conn) -> None:
        session.execute("UPDATE public.layer_cellpros SET facies = 42 WHERE _geoid = %s AND _idx = 2", (geoid,))

    second = Background(db_dsn, "second", second_writer)
    wait_until_blocked(conn, second.pid, first.info.backend_pid)  # the chunk's lock
    conn.rollback()
    first.commit()
    first.close()
    second.finish()
    rows = conn.execute(
        "SELECT _idx, facies FROM public.layer_cellpros WHERE _geoid = %s AND _idx IN (1, 2) ORDER BY 1", (geoid,)
    ).fetchall()
    assert rows == [(1, 41), (2, 42)]  # no lost update: the second merged into what the first committed


#: the chunk versions with their arrays' send forms (doubles by their bits; Python's NaN equals no NaN)
CHUNK_BITS = (
    "SELECT _geoid, chunk, revision, lastrevs, holes, array_send(porosity), array_send(facies) "
    "FROM public.layer_cellpros_chunk ORDER BY 1, 2, 3"
)


@pytest.mark.parametrize("fmt", ["custom", "plain"])
def test_pg_dump_and_restore_keep_the_property_chunks(
    pg: TestServer, db_dsn: str, conn: Conn, tmp_path: Path, fmt: str
) -> None:
    from tests.test_backup import _bindir_of, _restored

    geoid, mesh = _surface_class(conn, nan_payload=False)
    conn.execute("SELECT tgsis.store_class_in_chunks('layer')")
    conn.commit()
    before = _layer_rows(conn)
    chunks = conn.execute(CHUNK_BITS).fetchall()
    conn.rollback()
    with _restored(pg, _bindir_of(pg), db_dsn, fmt, tmp_path) as dsn, psycopg.connect(dsn) as copy:
        assert _layer_rows(copy) == before
        assert copy.execute(CHUNK_BITS).fetchall() == chunks
        assert _same_properties(F.fetch_feature(copy, "layer", geoid).mesh, mesh)
        # the restored face is written as before, and goes back to rows
        copy.execute("UPDATE public.layer_cellpros SET facies = 77 WHERE _geoid = %s AND _idx = 9", (geoid,))
        copy.commit()
        assert copy.execute(
            "SELECT facies FROM public.layer_cellpros WHERE _geoid = %s AND _idx = 9", (geoid,)
        ).fetchone() == (77,)
        copy.rollback()  # idle (out of its transaction): it holds none of the face's work tables
        with psycopg.connect(dsn) as again:
            assert again.execute("SELECT tgsis.store_class_in_rows('layer')").fetchone() == (len(before),)
            again.commit()


def test_properties_named_as_the_chunk_layers_own_names_are_refused_by_name(conn: Conn) -> None:
    """A property named revision was left out of the chunks without an error (the versioning columns every row table
    leaves out) and its values lost with the rows; chunk, holes, slot, q, ... broke the switch or the face's writes.
    Each such name is refused by name (TG100) before anything is made."""
    reserved = [r[0] for r in conn.execute("SELECT unnest(tgsis.chunk_reserved_names())")]
    assert {"revision", "lastrevs", "revclosed", "chunk", "holes", "vbase", "vtop", "slot", "pad", "o", "q"} <= set(
        reserved
    )
    names = reserved
    tgsis.create_feature_class(conn, "odd", "SURFACE", cell_properties=[(n, "integer") for n in names], versioned=False)
    columns = sql.SQL(", ").join(sql.Identifier(n) for n in names)
    conn.execute(
        sql.SQL(
            "INSERT INTO public.odd_cellpros (_geoid, _idx, {}) SELECT 1, i, {} FROM generate_series(0, 1100) i"
        ).format(columns, sql.SQL(", ").join(sql.SQL("i + {}").format(k) for k in range(len(names))))
    )
    conn.commit()
    before = conn.execute(sql.SQL("SELECT _idx, {} FROM public.odd_cellpros ORDER BY 1").format(columns)).fetchall()
    state, message = sqlstate(conn, "SELECT tgsis.store_class_in_chunks('odd')")
    assert state == "TG100"
    listed = message.split("the properties ", 1)[1].split(" of public.odd_cellpros", 1)[0]
    assert sorted(n.strip("'") for n in listed.split(", ")) == sorted(names)
    conn.rollback()
    assert conn.execute("SELECT relkind FROM pg_class WHERE oid = 'public.odd_cellpros'::regclass").fetchone() == ("r",)
    assert conn.execute("SELECT to_regclass('public.odd_cellpros_chunk')").fetchone() == (None,)
    assert (
        conn.execute(sql.SQL("SELECT _idx, {} FROM public.odd_cellpros ORDER BY 1").format(columns)).fetchall()
        == before
    )


def test_names_near_the_reserved_ones_go_through_the_whole_switch(conn: Conn) -> None:
    """Properties whose names resemble the layer's own (another case, a suffix, two letters) are stored, read,
    written through the face and stored back as rows, value for value."""
    names = ["Revision", "revision_no", "holes2", "padding", "Slot", "vp", "sw", "qq", "id", "p", "t", "state", "rows"]
    tgsis.create_feature_class(
        conn, "near", "SURFACE", cell_properties=[(n, "integer") for n in names], versioned=False
    )
    columns = sql.SQL(", ").join(sql.Identifier(n) for n in names)
    conn.execute(
        sql.SQL(
            "INSERT INTO public.near_cellpros (_geoid, _idx, {}) SELECT 1, i, {} FROM generate_series(0, 1500) i"
        ).format(columns, sql.SQL(", ").join(sql.SQL("i * {}").format(k + 1) for k in range(len(names))))
    )
    conn.commit()
    read = sql.SQL("SELECT _geoid, _idx, {} FROM public.near_cellpros ORDER BY 1, 2").format(columns)
    before = conn.execute(read).fetchall()
    conn.execute("SELECT tgsis.store_class_in_chunks('near')")
    conn.commit()
    assert conn.execute(read).fetchall() == before
    conn.execute(
        sql.SQL("UPDATE public.near_cellpros SET {} WHERE _geoid = 1 AND _idx = 5").format(
            sql.SQL(", ").join(sql.SQL("{} = -1").format(sql.Identifier(n)) for n in names)
        )
    )
    conn.execute(
        sql.SQL("INSERT INTO public.near_cellpros (_geoid, _idx, {}) VALUES (1, 3000, {})").format(
            columns, sql.SQL(", ").join(sql.Literal(7) for _ in names)
        )
    )
    conn.execute("DELETE FROM public.near_cellpros WHERE _geoid = 1 AND _idx = 6")
    conn.commit()
    expected = [(1, 5, *[-1] * len(names)) if r[1] == 5 else r for r in before if r[1] != 6] + [
        (1, 3000, *[7] * len(names))
    ]
    assert conn.execute(read).fetchall() == expected
    conn.execute("SELECT tgsis.store_class_in_rows('near')")
    conn.commit()
    assert conn.execute(read).fetchall() == expected


@pytest.mark.parametrize(
    "setup",
    [
        "ALTER TABLE public.layer_cellpros ENABLE ROW LEVEL SECURITY",
        "CREATE POLICY porous ON public.layer_cellpros FOR SELECT USING (porosity > 0.1)",
        "CREATE FUNCTION public.audit() RETURNS trigger LANGUAGE plpgsql AS $$BEGIN RETURN NEW; END$$; "
        "CREATE TRIGGER audit BEFORE UPDATE ON public.layer_cellpros FOR EACH ROW EXECUTE FUNCTION public.audit()",
        "CREATE VIEW public.porous AS SELECT _geoid, _idx FROM public.layer_cellpros WHERE porosity > 0.1",
    ],
    ids=["row-level security", "policy", "trigger", "view"],
)
def test_what_a_face_could_not_carry_is_refused_by_name(conn: Conn, setup: str) -> None:
    """Row-level security, a policy, a user's trigger or view on the property table: the face (a view) could not
    carry them and the rows' drop would lose them without an error, so the switch is refused, nothing changed."""
    geoid, _ = _surface_class(conn)
    conn.execute(setup)
    conn.commit()
    before = _layer_rows(conn)
    state, message = sqlstate(conn, "SELECT tgsis.store_class_in_chunks('layer')")
    assert state == "TG202", message
    conn.rollback()
    assert conn.execute("SELECT relkind FROM pg_class WHERE oid = 'public.layer_cellpros'::regclass").fetchone() == (
        "r",
    )
    assert conn.execute("SELECT to_regclass('public.layer_cellpros_chunk')").fetchone() == (None,)
    assert _layer_rows(conn) == before and geoid in {r[0] for r in before}


def test_delete_feature_writes_each_chunk_once_by_the_chunk_writer(conn: Conn) -> None:
    """delete_feature of a feature whose class's properties are in chunks (unversioned): the object's rows go by
    tgsis.write_property_rows, one chunk row version per chunk (here each deleted), no face trigger call per row
    (tgsis.chunk_face_queue: one a row before). The deltas are read within one transaction (PostgreSQL 15's
    pg_stat_xact_* views may hold counts of earlier transactions not yet flushed). Fails while the rows go
    through the face."""
    tgsis.create_feature_class(conn, "rock", "SURFACE", cell_properties=[("porosity", "double precision")])
    surface = curved_surface(60)
    geoid, other = (F.insert_feature(conn, "rock", surface, drop_extra_properties=True) for _ in range(2))
    conn.commit()
    conn.execute("SELECT tgsis.store_class_in_chunks('rock')")
    conn.commit()
    chunks = conn.execute("SELECT count(*) FROM public.rock_cellpros_chunk WHERE _geoid = %s", (geoid,)).fetchone()
    assert chunks == (-(-surface.n_vertices // 1024),)
    kept = conn.execute("SELECT * FROM public.rock_cellpros WHERE _geoid = %s ORDER BY _idx", (other,)).fetchall()
    conn.execute("SET track_functions = 'all'")
    counts = (
        "SELECT (SELECT ARRAY[n_tup_ins, n_tup_upd, n_tup_del] FROM pg_stat_xact_user_tables "
        "WHERE relid = 'public.rock_cellpros_chunk'::regclass), (SELECT coalesce(sum(calls), 0) "
        "FROM pg_stat_xact_user_functions WHERE (funcname IN ('chunk_face_queue', 'chunk_face_write') OR funcname LIKE '%\\_face\\_row'))"
    )
    before = conn.execute(counts).fetchone()
    assert F.delete_feature(conn, "rock", geoid)
    after = conn.execute(counts).fetchone()
    assert before is not None and after is not None
    assert [a - b for a, b in zip(after[0], before[0])] == [0, 0, chunks[0]]
    assert after[1] == before[1]
    conn.commit()
    assert conn.execute("SELECT count(*) FROM public.rock_cellpros WHERE _geoid = %s", (geoid,)).fetchone() == (0,)
    assert (
        conn.execute("SELECT * FROM public.rock_cellpros WHERE _geoid = %s ORDER BY _idx", (other,)).fetchall() == kept
    )
