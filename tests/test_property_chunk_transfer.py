"""The bulk upload and download of a class's property chunks (issue 40): whole chunks, not rows through the face.

docs/storage.md, "Property chunks: the contract" and "The bulk paths of property chunks": once
``tgsis.store_class_in_chunks`` made a STATIC class's property table a face over chunks,
``insert_feature`` encodes the properties' chunks in the client (``tgsis._chunks.encode``) and
``tgsis.write_property_chunks`` writes them after the face's checks; ``fetch_feature`` reads the chunk
versions and decodes them. These tests compare, for every property type, what a class in chunks stores
and gives back with what the same class on rows does (floats by their bits), with NULL values kept apart
from holes, and the server's refusals: a role without the right, a malformed chunk, a chunk that is
there, a face writer of the same chunk in another session. The property tables are rows on both storages
of model 1, so the file runs unmarked.
"""

from __future__ import annotations

import struct
from typing import Any

import numpy as np
import psycopg
import pytest
from psycopg import sql

import tgsis
import tgsis.db._property_chunks as property_chunks
from tests.merge_data import curved_surface, sqlstate
from tests.roles import login_roles
from tests.sessions import Background, connect, wait_until_blocked
from tests.storage_data import classes_as_rows
from tgsis.db import features as F
from tgsis.mesh import GeometryCollection, Surface

Conn = psycopg.Connection[Any]


@pytest.fixture(autouse=True)
def _classes_as_rows(db_dsn: str) -> None:
    """The classes these tests make start as rows: they switch them to chunks themselves, or compare with a rows
    twin (docs/storage.md, "Property chunks by default: the rule")."""
    classes_as_rows(db_dsn)


TYPES = [
    ("p_i2", "smallint", np.int16),
    ("p_i4", "integer", np.int32),
    ("p_i8", "bigint", np.int64),
    ("p_f4", "real", np.float32),
    ("p_f8", "double precision", np.float64),
    ("p_b", "boolean", np.bool_),
]
#: float8 bits that must survive: -0.0, the smallest subnormal, NaN with a payload, -inf, 1 + 1 ulp
F8_BITS = [0x8000000000000000, 0x0000000000000001, 0x7FF8000000000ABC, 0xFFF0000000000000, 0x3FF0000000000001]
F4_BITS = [0x80000000, 0x00000001, 0x7FC00ABC, 0xFF800000, 0x3F800001]


def _values(n: int, seed: int) -> dict[str, Any]:
    rng = np.random.default_rng(seed)
    values: dict[str, Any] = {
        "p_i2": rng.integers(-32768, 32768, n).astype(np.int16),
        "p_i4": rng.integers(-(2**31), 2**31, n, dtype=np.int64).astype(np.int32),
        "p_i8": rng.integers(-(2**63), 2**63 - 1, n, dtype=np.int64),
        "p_f4": rng.standard_normal(n).astype(np.float32),
        "p_f8": rng.standard_normal(n) * 1e3,
        "p_b": rng.random(n) < 0.5,
    }
    values["p_f8"][: len(F8_BITS)] = np.array(F8_BITS, dtype=np.uint64).view(np.float64)
    values["p_f4"][: len(F4_BITS)] = np.array(F4_BITS, dtype=np.uint32).view(np.float32)
    values["p_i2"][:2], values["p_i4"][:2], values["p_i8"][:2] = (
        [-32768, 32767],
        [-(2**31), 2**31 - 1],
        [-(2**63), 2**63 - 1],
    )
    return values


def _class(conn: Conn, name: str, geotype: str = "SURFACE", alignment: str = "VERTEX") -> None:
    tgsis.create_feature_class(
        conn,
        name,
        geotype,
        cell_properties=[(n, t) for n, t, _ in TYPES],
        alignment=alignment,  # type: ignore[arg-type]
    )


def _face_rows(conn: Conn, name: str) -> list[tuple[Any, ...]]:
    """The property table's rows through its name (table or face), floats by their bits, in key order."""
    query = sql.SQL(
        "SELECT _idx, p_i2, p_i4, p_i8, float4send(p_f4), float8send(p_f8), p_b FROM public.{} ORDER BY _geoid, _idx"
    ).format(sql.Identifier(f"{name}_cellpros"))
    return [tuple(r) for r in conn.execute(query).fetchall()]


def _bits(values: np.ndarray[Any, Any]) -> np.ndarray[Any, Any]:
    return values.view(np.int64 if values.dtype == np.float64 else np.int32) if values.dtype.kind == "f" else values


def _same(a: dict[str, Any], b: dict[str, Any]) -> bool:
    return set(a) == set(b) and all(a[k].dtype == b[k].dtype and np.array_equal(_bits(a[k]), _bits(b[k])) for k in a)


@pytest.fixture
def spy(monkeypatch: pytest.MonkeyPatch) -> dict[str, int]:
    """Counts the bulk paths taken (the upload's server calls, the chunk reads)."""
    counts = {"upload": 0, "download": 0}
    upload, request = property_chunks.upload_properties, property_chunks.property_request

    def counted_upload(*args: Any, **kwargs: Any) -> int:
        counts["upload"] += 1
        return upload(*args, **kwargs)

    def counted_request(*args: Any, **kwargs: Any) -> Any:
        made = request(*args, **kwargs)
        counts["download"] += made is not None
        return made

    import tgsis.db._static as static

    monkeypatch.setattr(static, "upload_properties", counted_upload)
    monkeypatch.setattr(static, "property_request", counted_request)
    return counts


@pytest.mark.parametrize("alignment", ["VERTEX", "CELL"])
def test_every_type_round_trips_bit_for_bit_as_on_rows(conn: Conn, spy: dict[str, int], alignment: str) -> None:
    surface = curved_surface()
    n = surface.n_vertices if alignment == "VERTEX" else surface.n_cells
    values = _values(n, 3)
    key = "vertex_properties" if alignment == "VERTEX" else "cell_properties"

    def surface_with(props: dict[str, Any]) -> Surface:
        if alignment == "VERTEX":
            return Surface(surface.vertices, surface.cells, vertex_properties=props)
        return Surface(surface.vertices, surface.cells, cell_properties=props)

    mesh = surface_with(values)
    _class(conn, "onrows", alignment=alignment)
    _class(conn, "inchunks", alignment=alignment)
    conn.execute("SELECT tgsis.store_class_in_chunks('inchunks')")
    conn.commit()
    on_rows = F.insert_feature(conn, "onrows", mesh)
    in_chunks = F.insert_feature(conn, "inchunks", mesh)
    conn.commit()
    assert spy["upload"] == 1  # the class in chunks only
    # stored: the face gives the rows' values, bits included; every chunk written whole (no face write)
    assert _face_rows(conn, "inchunks") == _face_rows(conn, "onrows")
    chunks = conn.execute(
        "SELECT count(*), max(revision), bool_and(holes IS NULL) FROM public.inchunks_cellpros_chunk WHERE _geoid = %s",
        (in_chunks,),
    ).fetchone()
    assert chunks == (-(-n // 1024), 0, True)
    assert conn.execute("SELECT tgsis.check_chunk_conversion('public.inchunks_cellpros')").fetchone() is not None
    # read back from the chunks: the mesh's properties, bit for bit, as the rows class gives them
    fetched = getattr(F.fetch_feature(conn, "inchunks", in_chunks).mesh, key)
    assert spy["download"] == 1
    assert _same(fetched, values)
    assert _same(fetched, getattr(F.fetch_feature(conn, "onrows", on_rows).mesh, key))
    # several features in one read
    other = F.insert_feature(conn, "inchunks", surface_with(_values(n, 4)))
    conn.commit()
    both = F.fetch_features(conn, "inchunks", [other, in_chunks])
    assert _same(getattr(both[1].mesh, key), values) and _same(getattr(both[0].mesh, key), _values(n, 4))


def test_a_collection_members_missing_properties_are_null_not_holes(conn: Conn, spy: dict[str, int]) -> None:
    surface = curved_surface()
    n = surface.n_vertices
    full, part = _values(n, 5), _values(n, 6)
    members = [
        Surface(surface.vertices, surface.cells, vertex_properties=full),
        Surface(surface.vertices, surface.cells, vertex_properties={k: part[k] for k in ("p_i4", "p_f8")}),
    ]
    for name in ("crows", "cchunks"):
        _class(conn, name, geotype="GEOMETRYCOLLECTION")
    conn.execute("SELECT tgsis.store_class_in_chunks('cchunks')")
    conn.commit()
    F.insert_feature(conn, "crows", GeometryCollection(members))
    geoid = F.insert_feature(conn, "cchunks", GeometryCollection(members))
    conn.commit()
    assert spy["upload"] == 1
    assert _face_rows(conn, "cchunks") == _face_rows(conn, "crows")
    # the second member's chunks: no hole, NULL values in the properties it lacks, values in the others
    second = conn.execute("SELECT geoids[2] FROM tgsis.geometry WHERE geoid = %s", (geoid,)).fetchone()
    assert second is not None
    row = conn.execute(
        "SELECT holes, array_positions(p_i2, NULL) = (SELECT array_agg(i) FROM generate_series(1, cardinality(p_i2)) i), "
        "array_positions(p_i4, NULL) = '{}' FROM public.cchunks_cellpros_chunk WHERE _geoid = %s AND chunk = 0",
        (second[0],),
    ).fetchone()
    assert row == (None, True, True)
    members_back = F.fetch_feature(conn, "cchunks", geoid).mesh
    assert isinstance(members_back, GeometryCollection)
    assert _same(members_back.members[0].vertex_properties, full)
    assert _same(members_back.members[1].vertex_properties, {k: part[k] for k in ("p_i4", "p_f8")})


def _chunk_row(holes: str | None, p_i2: str, other: str = "{1,2,3}", flags: str = "{t,f,t}", geoid: int = 8) -> str:
    """A ROW of the chunk table's type (literal arrays), for tgsis.write_property_chunks called by hand."""
    return (
        f"ROW({geoid}, 0, 0, '{{}}', NULL, {'NULL' if holes is None else repr(holes)}::smallint[], "
        f"'{p_i2}', '{other}', '{other}', '{other}', '{other}', '{flags}')::public.hand_cellpros_chunk"
    )


def test_the_server_checks_what_it_is_given(conn: Conn) -> None:
    _class(conn, "hand")
    conn.execute("SELECT tgsis.store_class_in_chunks('hand')")
    conn.commit()
    call = "SELECT tgsis.write_property_chunks('public.hand_cellpros', ARRAY[{}])"
    # a hole, a NULL value elsewhere: written, and the face shows the value NULL, the hole absent
    ok = call.format(_chunk_row("{2}", "{1,NULL,NULL}", "{1,NULL,3}", "{t,NULL,t}", geoid=7))
    assert conn.execute(ok).fetchone() == (1,)
    assert conn.execute("SELECT _idx, p_i2, p_i4, p_b FROM public.hand_cellpros ORDER BY 1").fetchall() == [
        (0, 1, 1, True),
        (2, None, 3, True),
    ]
    conn.commit()
    before = conn.execute("SELECT count(*) FROM public.hand_cellpros_chunk").fetchone()
    for statement, expected in (
        (call.format(_chunk_row("{2}", "{1,5,3}", "{1,NULL,3}", "{t,NULL,t}")), "23514"),  # a value at a hole
        (call.format(_chunk_row(None, "{1,2}")), "23514"),  # arrays of unequal length
        (call.format(_chunk_row("{3}", "{1,2,NULL}", "{1,2,NULL}", "{t,f,NULL}")), "23514"),  # ending on a hole
        (ok, "TG201"),  # the chunk is there
        ("SELECT tgsis.write_property_chunks('public.hand_cellpros', ARRAY[1, 2])", "TG100"),
        ("SELECT tgsis.write_property_chunks('public.nothere_cellpros', ARRAY[1])", "TG200"),
    ):
        assert sqlstate(conn, statement)[0] == expected, statement
    assert conn.execute("SELECT count(*) FROM public.hand_cellpros_chunk").fetchone() == before
    revision = call.format(_chunk_row(None, "{1,2,3}").replace("ROW(8, 0, 0,", "ROW(8, 0, 3,"))
    assert sqlstate(conn, revision)[0] == "23514"  # unversioned storage: revision 0 only


def test_a_role_writes_and_reads_as_its_rights_allow(db_dsn: str, conn: Conn, spy: dict[str, int]) -> None:
    surface = curved_surface()
    values = _values(surface.n_vertices, 8)
    mesh = Surface(surface.vertices, surface.cells, vertex_properties=values)
    _class(conn, "ranked")
    conn.execute("SELECT tgsis.store_class_in_chunks('ranked')")
    conn.commit()
    with login_roles(db_dsn, {"reader": "tgsis_reader", "editor": "tgsis_editor"}) as roles:
        reader = roles.connect("reader")
        with pytest.raises(tgsis.errors.Error):
            F.insert_feature(reader, "ranked", mesh)  # no INSERT on the class's tables
        reader.rollback()
        # the server call itself refuses a role without INSERT on the face, whatever it passes
        state, _ = sqlstate(
            reader,
            "SELECT tgsis.write_property_chunks('public.ranked_cellpros', "
            "(SELECT array_agg(c) FROM public.ranked_cellpros_chunk c))",
        )
        assert state == "42501"
        editor = roles.connect("editor")
        geoid = F.insert_feature(editor, "ranked", mesh)
        editor.commit()
        assert spy["upload"] == 1
        assert _same(F.fetch_feature(reader, "ranked", geoid).mesh.vertex_properties, values)  # type: ignore[union-attr]
        assert spy["download"] == 1
        # a role that may read the face but not the chunk table reads through the face, the same values
        conn.execute("REVOKE SELECT ON public.ranked_cellpros_chunk FROM tgsis_reader")
        conn.commit()
        reader.rollback()
        assert _same(F.fetch_feature(reader, "ranked", geoid).mesh.vertex_properties, values)  # type: ignore[union-attr]
        assert spy["download"] == 1
    assert conn.execute("SELECT count(DISTINCT _geoid) FROM public.ranked_cellpros_chunk").fetchone() == (1,)


def test_a_face_writer_of_an_uploaded_chunk_waits_and_is_refused(db_dsn: str, conn: Conn) -> None:
    surface = curved_surface()
    mesh = Surface(surface.vertices, surface.cells, vertex_properties=_values(surface.n_vertices, 9))
    _class(conn, "shared")
    conn.execute("SELECT tgsis.store_class_in_chunks('shared')")
    conn.commit()
    first = connect(db_dsn, "first")
    geoid = F.insert_feature(first, "shared", mesh)  # not committed yet

    def face_writer(session: Conn) -> Any:
        return sqlstate(session, "INSERT INTO public.shared_cellpros VALUES (%s, 3, 1, 1, 1, 1, 1, true)", (geoid,))

    second = Background(db_dsn, "second", face_writer)
    wait_until_blocked(conn, second.pid, first.info.backend_pid)  # the chunk's lock (or its key)
    conn.rollback()
    first.commit()
    first.close()
    state, _ = second.finish()
    assert state == "23505"  # the uploaded row is there: no second value, no lost one
    row = conn.execute("SELECT p_i2 FROM public.shared_cellpros WHERE _geoid = %s AND _idx = 3", (geoid,)).fetchone()
    assert row == (int(mesh.vertex_properties["p_i2"][3]),)


def test_struct_of_the_bits_compared() -> None:
    """(the comparison above sees a changed bit: a test of the test)"""
    a = {"x": np.array([struct.unpack(">d", struct.pack(">Q", F8_BITS[2]))[0]])}
    b = {"x": np.array([float("nan")])}
    assert not _same(a, b) and _same(a, {"x": a["x"].copy()})


def _chunk_table_facts(conn: Conn, name: str) -> tuple[Any, ...]:
    """The face's kind, grants and column comments, and the chunk table's array columns, of a class's property table."""
    face = f"public.{name}_cellpros"
    row = conn.execute(
        "SELECT (SELECT relkind::text FROM pg_class WHERE oid = %s::regclass), "
        "(SELECT array_agg(format('%%s %%s', grantee, privilege_type) ORDER BY grantee, privilege_type) "
        " FROM information_schema.role_table_grants WHERE table_schema = 'public' AND table_name = %s "
        " AND grantee LIKE 'tgsis%%'), "
        "(SELECT array_agg(format('%%s: %%s', attname, col_description(attrelid, attnum)) ORDER BY attnum) "
        " FROM pg_attribute WHERE attrelid = %s::regclass AND attnum > 0), "
        "(SELECT array_agg(format('%%s %%s', attname, format_type(atttypid, atttypmod)) ORDER BY attnum) "
        " FROM pg_attribute WHERE attrelid = %s::regclass AND attnum > 6 AND NOT attisdropped)",
        (face, f"{name}_cellpros", face, f"{face}_chunk"),
    ).fetchone()
    assert row is not None
    return tuple(row)


def test_add_rename_and_drop_a_property_of_a_class_in_chunks(conn: Conn) -> None:
    surface = curved_surface()
    values = _values(surface.n_vertices, 11)
    mesh = Surface(surface.vertices, surface.cells, vertex_properties=values)
    _class(conn, "grows")
    geoid = F.insert_feature(conn, "grows", mesh)
    conn.execute("SELECT tgsis.store_class_in_chunks('grows')")
    conn.execute("GRANT SELECT, INSERT ON public.grows_cellpros TO tgsis_editor")
    conn.commit()
    kind, grants, _, arrays = _chunk_table_facts(conn, "grows")
    assert kind == "v" and "tgsis_editor INSERT" in grants and len(arrays) == 6
    before = _face_rows(conn, "grows")

    # added: every stored vertex gets the default; the class stays in chunks, the face keeps its grants
    tgsis.add_property(conn, "grows", ("p_new", "real"), default="-0.0")
    conn.commit()
    kind, grants_now, comments, arrays = _chunk_table_facts(conn, "grows")
    assert (kind, grants_now) == ("v", grants) and arrays[-1] == "p_new real[]"
    assert any(c.startswith("p_new: ") and "None" not in c for c in comments)
    rows = conn.execute(
        "SELECT count(*), count(*) FILTER (WHERE float4send(p_new) = float4send('-0'::real)) FROM public.grows_cellpros"
    ).fetchone()
    assert rows == (surface.n_vertices, surface.n_vertices)
    assert _face_rows(conn, "grows") == before  # the other properties' values, bits included
    # renamed: the values follow; the bulk read gives them under the new name
    tgsis.rename_property(conn, "grows", "p_f8", "p_double")
    conn.commit()
    fetched = F.fetch_feature(conn, "grows", geoid).mesh
    assert fetched is not None
    props = fetched.vertex_properties  # type: ignore[union-attr]
    assert np.array_equal(props["p_double"].view(np.int64), values["p_f8"].view(np.int64)) and "p_f8" not in props
    assert np.all(props["p_new"].view(np.int32) == np.int32(-(2**31)))  # -0.0's bits
    # dropped: refused while it holds values unless forced; then gone from the chunks and the face
    assert sqlstate(conn, "SELECT tgsis.drop_property('grows', 'p_i2')")[0] == "TG202"
    tgsis.drop_property(conn, "grows", "p_i2", force=True)
    conn.commit()
    kind, grants_now, _, arrays = _chunk_table_facts(conn, "grows")
    assert (kind, grants_now) == ("v", grants) and not any(a.startswith("p_i2 ") for a in arrays)
    assert "p_i2" not in F.fetch_feature(conn, "grows", geoid).mesh.vertex_properties  # type: ignore[union-attr]
    # a property the chunks have no form for (a name of the chunk layer's own): refused by name, nothing changed
    # (a vector property is added in place: tests/test_vector_property_alter.py)
    state, message = sqlstate(
        conn, """SELECT tgsis.add_property('grows', 'cell', '{"name": "holes", "type": "integer"}', '0')"""
    )
    assert state == "TG100" and "holes" in message
    assert _chunk_table_facts(conn, "grows")[3] == arrays
    # in one transaction: an upload, a rename (a new chunk table), an upload of the renamed property
    props = {k: v for k, v in values.items() if k not in ("p_i2", "p_f8")}
    props |= {"p_double": values["p_f8"], "p_new": np.full(surface.n_vertices, 2.5, dtype=np.float32)}
    first = F.insert_feature(conn, "grows", Surface(surface.vertices, surface.cells, vertex_properties=props))
    tgsis.rename_property(conn, "grows", "p_double", "p_last")
    props["p_last"] = props.pop("p_double")
    second = F.insert_feature(conn, "grows", Surface(surface.vertices, surface.cells, vertex_properties=props))
    conn.commit()
    for feature in (first, second):
        assert _same(F.fetch_feature(conn, "grows", feature).mesh.vertex_properties, props)  # type: ignore[union-attr]
