"""The properties of the other alignment (``otherprotable``) in chunks (issue 40, plan M area O).

docs/storage.md, "Property chunks as the default of a static class: what blocks it", items 2 and
6: a STATIC class aligned by vertex may keep cell properties in ``<class>_simplexpros`` (and a
class aligned by cell vertex properties in ``<class>_vertexpros``). ``tgsis.chunk_registry``
knows that table too, chunked like the table it is aligned with; ``tgsis.store_class_in_chunks``
and ``tgsis.store_class_in_rows`` switch both tables in one transaction; the Python upload,
download and check-in take the chunk path for either. These tests compare a class in chunks
with a rows twin (floats by their bits) through both faces and the public API. The property
tables are rows on both storages of model 1 until switched here, so the file runs unmarked.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import psycopg
import pytest
from psycopg import sql

import tgsis
import tgsis.db._property_chunks as property_chunks
from tests.merge_data import curved_surface, sqlstate
from tests.roles import login_roles
from tests.sessions import connect
from tests.storage_data import classes_as_rows
from tgsis.db import features as F
from tgsis.mesh import Surface

Conn = psycopg.Connection[Any]


@pytest.fixture(autouse=True)
def _classes_as_rows(db_dsn: str) -> None:
    """The classes these tests make start as rows: they switch them to chunks themselves, or compare with a rows
    twin (docs/storage.md, "Property chunks by default: the rule")."""
    classes_as_rows(db_dsn)


#: a VERTEX class: porosity per vertex (cellpros), facies, a dip vector and a real per triangle (simplexpros)
PROPERTIES: list[tgsis.Property] = [
    tgsis.Property("porosity", "float8"),
    tgsis.Property("facies", "int", alignment="CELL"),
    tgsis.Property("dip", "float8", 3, alignment="CELL"),
    tgsis.Property("grade", "real", alignment="CELL"),
]
#: float8 bits that must survive: -0.0, the smallest subnormal, NaN with a payload, -inf, 1 + 1 ulp
F8_BITS = [0x8000000000000000, 0x0000000000000001, 0x7FF8000000000ABC, 0xFFF0000000000000, 0x3FF0000000000001]
SIDE = 40  # 1,600 vertices (2 chunks), 3,042 triangles (3 chunks)


def _surface(seed: int) -> Surface:
    surface = curved_surface(SIDE)
    rng = np.random.default_rng(seed)
    n, m = surface.n_vertices, surface.n_cells
    porosity = rng.standard_normal(n)
    dip = rng.standard_normal((m, 3)) * 1e3
    dip[: len(F8_BITS), 0] = np.array(F8_BITS, dtype=np.uint64).view(np.float64)
    grade = rng.standard_normal(m).astype(np.float32)
    grade[:2] = np.array([0x80000000, 0x7FC00ABC], dtype=np.uint32).view(np.float32)
    return Surface(
        surface.vertices,
        surface.cells,
        vertex_properties={"porosity": porosity},
        cell_properties={
            "facies": rng.integers(-(2**31), 2**31, m, dtype=np.int64).astype(np.int32),
            "dip": dip,
            "grade": grade,
        },
    )


def _class(conn: Conn, name: str) -> None:
    F.create_feature_class(conn, name, "SURFACE", cell_properties=PROPERTIES)


def _other_rows(conn: Conn, name: str, extra: str = "") -> list[tuple[Any, ...]]:
    """The other table's rows through its name (table or face), floats by their bits, in key order."""
    query = sql.SQL(
        "SELECT _geoid, _idx, facies, (SELECT array_agg(float8send(d)) FROM unnest(dip) d), float4send(grade){} "
        "FROM public.{} ORDER BY _geoid, _idx"
    ).format(sql.SQL(extra), sql.Identifier(f"{name}_simplexpros"))
    return [tuple(r) for r in conn.execute(query).fetchall()]


def _own_rows(conn: Conn, name: str) -> list[tuple[Any, ...]]:
    query = sql.SQL("SELECT _geoid, _idx, float8send(porosity) FROM public.{} ORDER BY _geoid, _idx").format(
        sql.Identifier(f"{name}_cellpros")
    )
    return [tuple(r) for r in conn.execute(query).fetchall()]


def _fetched(conn: Conn, name: str, geoid: int) -> Surface:
    mesh = F.fetch_feature(conn, name, geoid).mesh
    assert isinstance(mesh, Surface)
    return mesh


def _bits(values: np.ndarray[Any, Any]) -> np.ndarray[Any, Any]:
    return values.view(np.int64 if values.dtype == np.float64 else np.int32) if values.dtype.kind == "f" else values


def _same(a: dict[str, Any], b: dict[str, Any]) -> bool:
    return set(a) == set(b) and all(a[k].dtype == b[k].dtype and np.array_equal(_bits(a[k]), _bits(b[k])) for k in a)


def _kinds(conn: Conn, name: str) -> tuple[Any, ...]:
    """relkind of <name>_cellpros and <name>_simplexpros, and whether each has a chunk table."""
    row = conn.execute(
        "SELECT (SELECT relkind::text FROM pg_class WHERE oid = to_regclass(%s)), to_regclass(%s) IS NOT NULL, "
        "(SELECT relkind::text FROM pg_class WHERE oid = to_regclass(%s)), to_regclass(%s) IS NOT NULL",
        (
            f"public.{name}_cellpros",
            f"public.{name}_cellpros_chunk",
            f"public.{name}_simplexpros",
            f"public.{name}_simplexpros_chunk",
        ),
    ).fetchone()
    assert row is not None
    return tuple(row)


@pytest.fixture
def spy(monkeypatch: pytest.MonkeyPatch) -> dict[str, list[str]]:
    """The property tables the bulk paths took (the upload's server calls, the chunk reads)."""
    taken: dict[str, list[str]] = {"upload": [], "download": []}
    upload, request = property_chunks.upload_properties, property_chunks.property_request

    def counted_upload(conn: Conn, layout: Any, *args: Any, **kwargs: Any) -> int:
        taken["upload"].append(layout.table)
        return upload(conn, layout, *args, **kwargs)

    def counted_request(conn: Conn, fc: Any, table: str, *args: Any, **kwargs: Any) -> Any:
        made = request(conn, fc, table, *args, **kwargs)
        if made is not None:
            taken["download"].append(table)
        return made

    import tgsis.db._static as static

    monkeypatch.setattr(static, "upload_properties", counted_upload)
    monkeypatch.setattr(static, "property_request", counted_request)
    return taken


def test_the_registry_knows_the_other_table_with_its_alignments_chunk_size(conn: Conn) -> None:
    _class(conn, "tops")
    F.create_feature_class(
        conn,
        "blocks",
        "MULTITETRA",
        alignment="CELL",
        cell_properties=[("facies", "int"), tgsis.Property("porosity", "float8", alignment="VERTEX")],
    )
    rows = conn.execute(
        "SELECT r.tablename, r.chunksize, r.classname FROM unnest(ARRAY['public.tops_cellpros', "
        "'public.tops_simplexpros', 'public.blocks_cellpros', 'public.blocks_vertexpros']) t, "
        "LATERAL tgsis.chunk_registry(t) r"
    ).fetchall()
    sizes = dict(conn.execute("SELECT tablename, chunksize FROM tgsis.model_tables").fetchall())
    vrtx, tetra = (sizes["vrtx"],), (sizes["tetra"],)
    assert rows == [
        ("tops_cellpros", vrtx[0], "tops"),
        ("tops_simplexpros", sizes["trgl"], "tops"),  # aligned with the triangles
        ("blocks_cellpros", tetra[0], "blocks"),
        ("blocks_vertexpros", vrtx[0], "blocks"),  # aligned with the vertices
    ]
    conn.rollback()


def test_both_tables_switch_read_write_and_go_back_as_a_rows_twin(conn: Conn, spy: dict[str, list[str]]) -> None:
    _class(conn, "onrows")
    _class(conn, "inchunks")
    conn.commit()
    first, second = _surface(1), _surface(2)
    twin = [F.insert_feature(conn, "onrows", s) for s in (first, second)]
    stored = [F.insert_feature(conn, "inchunks", s) for s in (first, second)]
    conn.commit()
    assert len(set(twin + stored)) == 4
    # the switch: both tables, in one call (chunk versions: 2 + 3 per object)
    assert conn.execute("SELECT tgsis.store_class_in_chunks('inchunks')").fetchone() == (10,)
    conn.commit()
    assert _kinds(conn, "inchunks") == ("v", True, "v", True)
    assert conn.execute("SELECT tgsis.check_chunk_conversion('public.inchunks_simplexpros')").fetchone() is not None
    # the faces give the twin's rows, bits included (keys mapped object for object)
    remap = dict(zip(stored, twin, strict=True))

    def mapped(rows: list[tuple[Any, ...]]) -> list[tuple[Any, ...]]:
        return sorted((remap[r[0]], *r[1:]) for r in rows)

    assert mapped(_other_rows(conn, "inchunks")) == _other_rows(conn, "onrows")
    assert mapped(_own_rows(conn, "inchunks")) == _own_rows(conn, "onrows")
    # the download reads both tables' chunks, bit for bit as the twin
    for geoid, other, mesh in zip(stored, twin, (first, second), strict=True):
        got = _fetched(conn, "inchunks", geoid)
        ref = _fetched(conn, "onrows", other)
        assert _same(got.cell_properties, ref.cell_properties) and _same(got.cell_properties, mesh.cell_properties)
        assert _same(got.vertex_properties, ref.vertex_properties)
    assert sorted(set(spy["download"])) == ["inchunks_cellpros", "inchunks_simplexpros"]
    # the upload writes both tables' chunks whole
    third = _surface(3)
    spy["upload"].clear()
    new = F.insert_feature(conn, "inchunks", third)
    conn.commit()
    assert sorted(spy["upload"]) == ["inchunks_cellpros", "inchunks_simplexpros"]
    assert _same(_fetched(conn, "inchunks", new).cell_properties, third.cell_properties)
    F.delete_feature(conn, "inchunks", new)
    conn.commit()
    # writes through the other face as through the twin's table
    for name, geoid in (("onrows", twin[0]), ("inchunks", stored[0])):
        table = sql.Identifier(f"{name}_simplexpros")
        conn.execute(
            sql.SQL(
                "UPDATE public.{} SET facies = facies + 1, dip[2] = -0.0 WHERE _geoid = %s AND _idx %% 7 = 3"
            ).format(table),
            (geoid,),
        )
        conn.execute(
            sql.SQL("DELETE FROM public.{} WHERE _geoid = %s AND _idx BETWEEN 1000 AND 1100").format(table), (geoid,)
        )
        conn.execute(
            sql.SQL(
                "INSERT INTO public.{} (_geoid, _idx, facies, dip, grade) "
                "SELECT %s, i, -i, ARRAY[i, 'NaN', '-Infinity']::float8[], i / 3.0 "
                "FROM generate_series(1000, 1050) i"
            ).format(table),
            (geoid,),
        )
    conn.commit()
    assert mapped(_other_rows(conn, "inchunks")) == _other_rows(conn, "onrows")
    # a property added to the other table, in place, as on the twin
    for name in ("onrows", "inchunks"):
        tgsis.add_property(conn, name, tgsis.Property("rank", "smallint", alignment="CELL"), default=2)
        conn.commit()
    assert mapped(_other_rows(conn, "inchunks", ", rank")) == _other_rows(conn, "onrows", ", rank")
    assert _kinds(conn, "inchunks") == ("v", True, "v", True)
    # back to rows: both tables, verified; a second call has nothing to move
    conn.execute("SELECT tgsis.store_class_in_rows('inchunks')")
    conn.commit()
    assert _kinds(conn, "inchunks") == ("r", False, "r", False)
    assert mapped(_other_rows(conn, "inchunks", ", rank")) == _other_rows(conn, "onrows", ", rank")
    assert mapped(_own_rows(conn, "inchunks")) == _own_rows(conn, "onrows")
    assert sqlstate(conn, "SELECT tgsis.store_class_in_rows('inchunks')")[0] == "TG200"
    state, message = sqlstate(conn, "SELECT tgsis.store_class_in_chunks('inchunks')")
    assert state is None, message
    assert sqlstate(conn, "SELECT tgsis.store_class_in_chunks('inchunks')")[0] == "TG201"


def test_a_versioned_class_switches_both_tables_with_their_history(conn: Conn) -> None:
    for name in ("onrows", "inchunks"):
        _class(conn, name)
    tgsis.enable_feature_versioning(conn)
    twin, stored = F.insert_feature(conn, "onrows", _surface(4)), F.insert_feature(conn, "inchunks", _surface(4))
    conn.commit()
    tgsis.create_version(conn, "child")
    conn.commit()
    tgsis.goto_version(conn, "child")
    for name, geoid in (("onrows", twin), ("inchunks", stored)):
        conn.execute(
            sql.SQL("UPDATE public.{} SET grade = -grade WHERE _geoid = %s AND _idx < 40").format(
                sql.Identifier(f"{name}_simplexpros")
            ),
            (geoid,),
        )
    conn.commit()

    def both() -> tuple[list[Any], list[Any]]:
        out: tuple[list[Any], list[Any]] = ([], [])
        for version in ("DEFAULT", "child"):
            tgsis.goto_version(conn, version)
            out[0].extend((version, *r[1:]) for r in _other_rows(conn, "onrows"))
            out[1].extend((version, *r[1:]) for r in _other_rows(conn, "inchunks"))
            conn.commit()
        return out

    before = both()
    assert before[0] == before[1]
    conn.execute("SELECT tgsis.store_class_in_chunks('inchunks')")
    conn.commit()
    assert _kinds(conn, "inchunks") == ("v", True, "v", True)
    assert both() == before
    # edited in the child through the other face, merged, compressed: as the twin
    tgsis.goto_version(conn, "child")
    for name, geoid in (("onrows", twin), ("inchunks", stored)):
        conn.execute(
            sql.SQL("UPDATE public.{} SET facies = -1 WHERE _geoid = %s AND _idx BETWEEN 1020 AND 1030").format(
                sql.Identifier(f"{name}_simplexpros")
            ),
            (geoid,),
        )
        conn.commit()
    tgsis.goto_version(conn, "DEFAULT")
    conn.commit()
    tgsis.merge_version(conn, "child")
    conn.commit()
    removed = {(r[0], r[1]) for r in conn.execute("SELECT * FROM tgsis.compress_versions()").fetchall()}
    conn.commit()
    assert ("rows", "public.inchunks_simplexpros") in removed  # the chunk versions no kept set sees
    after = both()
    assert after[0] == after[1] and after != before
    conn.execute("SELECT tgsis.store_class_in_rows('inchunks')")
    conn.commit()
    assert _kinds(conn, "inchunks") == ("v", False, "v", False)  # the versioned views again
    assert both() == after


def test_a_refusal_on_the_other_table_moves_nothing(conn: Conn) -> None:
    _class(conn, "tops")
    F.insert_feature(conn, "tops", _surface(5))
    conn.execute("CREATE VIEW public.tops_mine AS SELECT _geoid, facies FROM public.tops_simplexpros")
    conn.commit()
    state, message = sqlstate(conn, "SELECT tgsis.store_class_in_chunks('tops')")
    assert state == "TG202" and "tops_simplexpros" in message
    assert _kinds(conn, "tops") == ("r", False, "r", False)


def test_a_users_function_of_the_face_row_name_is_refused_and_kept(conn: Conn) -> None:
    """A user's ``<table>_face_row()`` in the class's schema is not taken over by the face's generated row function:
    TG201 naming it, nothing moved, the user's function unchanged."""
    _class(conn, "tops")
    F.insert_feature(conn, "tops", _surface(5))
    body = "BEGIN RETURN NULL; END"
    conn.execute(
        "CREATE FUNCTION public.tops_simplexpros_face_row() RETURNS trigger LANGUAGE plpgsql AS $$" + body + "$$"
    )
    conn.commit()
    state, message = sqlstate(conn, "SELECT tgsis.store_class_in_chunks('tops')")
    assert state == "TG201" and "tops_simplexpros_face_row" in message, message
    assert _kinds(conn, "tops") == ("r", False, "r", False)
    assert conn.execute(
        "SELECT prosrc FROM pg_proc WHERE oid = 'public.tops_simplexpros_face_row()'::regprocedure"
    ).fetchone() == (body,)
    conn.execute("DROP FUNCTION public.tops_simplexpros_face_row()")
    conn.commit()
    conn.execute("SELECT tgsis.store_class_in_chunks('tops')")  # the name free: the switch goes through
    conn.commit()
    assert _kinds(conn, "tops") == ("v", True, "v", True)


def test_a_role_without_rights_is_refused_and_an_editor_writes_both_faces(db_dsn: str, conn: Conn) -> None:
    _class(conn, "tops")
    geoid = F.insert_feature(conn, "tops", _surface(6))
    conn.commit()
    with login_roles(db_dsn, {"reader": "tgsis_reader", "editor": "tgsis_editor"}) as roles:
        editor = roles.connect("editor")
        assert sqlstate(editor, "SELECT tgsis.store_class_in_chunks('tops')")[0] in ("TG002", "42501")
        conn.execute("SELECT tgsis.store_class_in_chunks('tops')")
        conn.commit()
        reader = roles.connect("reader")
        assert (
            sqlstate(reader, "UPDATE public.tops_simplexpros SET facies = 0 WHERE _geoid = %s", (geoid,))[0] == "42501"
        )
        assert sqlstate(reader, "SELECT tgsis.store_class_in_rows('tops')")[0] in ("TG002", "42501")
        editor.execute("UPDATE public.tops_simplexpros SET facies = 7 WHERE _geoid = %s AND _idx = 2000", (geoid,))
        editor.commit()
        assert reader.execute(
            "SELECT facies FROM public.tops_simplexpros WHERE _geoid = %s AND _idx = 2000", (geoid,)
        ).fetchone() == (7,)
        assert _same(
            _fetched(reader, "tops", geoid).cell_properties,
            _fetched(conn, "tops", geoid).cell_properties,
        )
    assert _kinds(conn, "tops") == ("v", True, "v", True)


def test_two_sessions_write_the_other_face_each_its_object(db_dsn: str, conn: Conn) -> None:
    _class(conn, "tops")
    a, b = F.insert_feature(conn, "tops", _surface(7)), F.insert_feature(conn, "tops", _surface(8))
    conn.execute("SELECT tgsis.store_class_in_chunks('tops')")
    conn.commit()
    one, two = connect(db_dsn, "one"), connect(db_dsn, "two")
    try:
        one.execute("UPDATE public.tops_simplexpros SET facies = 11 WHERE _geoid = %s AND _idx < 5", (a,))
        two.execute("UPDATE public.tops_simplexpros SET facies = 22 WHERE _geoid = %s AND _idx < 5", (b,))
        two.commit()
        one.commit()
    finally:
        one.close()
        two.close()
    assert conn.execute(
        "SELECT _geoid, array_agg(DISTINCT facies) FROM public.tops_simplexpros WHERE _idx < 5 GROUP BY 1 ORDER BY 1"
    ).fetchall() == [(a, [11]), (b, [22])]


def test_a_checkin_writes_both_tables_by_chunks_as_the_rows_twin(conn: Conn, monkeypatch: pytest.MonkeyPatch) -> None:
    import tgsis.db._state_write as state_write

    written: list[str] = []
    write = property_chunks.write_property_rows

    def counted(c: Conn, schema: str, table: str, *args: Any) -> int | None:
        made = write(c, schema, table, *args)
        if made is not None:
            written.append(table)
        return made

    monkeypatch.setattr(state_write, "write_property_rows", counted)
    _class(conn, "onrows")
    _class(conn, "inchunks")
    geoids = {name: F.insert_feature(conn, name, _surface(9)) for name in ("onrows", "inchunks")}
    conn.execute("SELECT tgsis.store_class_in_chunks('inchunks')")
    conn.commit()
    for name, geoid in geoids.items():
        out = tgsis.checkout(conn, geoid, name)
        mesh = out.mesh
        cells = {k: np.array(v, copy=True) for k, v in mesh.cell_properties.items()}
        cells["facies"][100:140] = -7
        cells["dip"][2050:2060] = np.array([0x8000000000000000] * 3, dtype=np.uint64).view(np.float64)
        points = {"porosity": np.array(mesh.vertex_properties["porosity"], copy=True)}
        points["porosity"][5] = float("nan")
        edited = Surface(mesh.vertices, mesh.cells, vertex_properties=points, cell_properties=cells)
        tgsis.checkin(conn, out, edited)
        conn.commit()
    assert sorted(written) == ["inchunks_cellpros", "inchunks_simplexpros"]
    a, b = (
        _fetched(conn, "onrows", geoids["onrows"]),
        _fetched(conn, "inchunks", geoids["inchunks"]),
    )
    assert _same(a.cell_properties, b.cell_properties) and _same(a.vertex_properties, b.vertex_properties)
    assert [r[1:] for r in _other_rows(conn, "inchunks")] == [r[1:] for r in _other_rows(conn, "onrows")]


@pytest.mark.parametrize("versioned", [False, True])
def test_fill_property_rows_on_a_class_in_chunks_as_on_its_rows_twin(conn: Conn, versioned: bool) -> None:
    """fill_property_rows (tgsis.insert_property_rows) on a table in chunks: through the face when unversioned,
    refused by name (TG103, nothing written) when versioned.

    Failed before: tgsis.insert_property_rows INSERTed row columns into the chunk table.
    """
    for name in ("onrows", "inchunks"):
        _class(conn, name)
    if versioned:
        tgsis.enable_feature_versioning(conn)
    geoids = {name: F.insert_feature(conn, name, _surface(10)) for name in ("onrows", "inchunks")}
    conn.execute("SELECT tgsis.store_class_in_chunks('inchunks')")
    conn.commit()
    # rows gone from the other table (as an older tgsis left a class), made again by fill_property_rows
    values = '{"facies": 4, "dip": -0.0, "grade": 0.5}'
    for name, geoid in geoids.items():
        conn.execute(
            sql.SQL("DELETE FROM public.{} WHERE _geoid = %s").format(sql.Identifier(f"{name}_simplexpros")), (geoid,)
        )
        conn.commit()
    made = conn.execute("SELECT * FROM tgsis.fill_property_rows('onrows', %s)", (values,)).fetchall()
    conn.commit()
    n = _surface(10).n_cells
    assert made == [("onrows_cellpros", 0, 0), ("onrows_simplexpros", 1, n)]
    if versioned:
        state, message = sqlstate(conn, "SELECT * FROM tgsis.fill_property_rows('inchunks', %s)", (values,))
        assert state == "TG103" and "inchunks_simplexpros" in message and "stored in chunks" in message
        assert conn.execute("SELECT count(*) FROM public.inchunks_simplexpros").fetchone() == (0,)
        return
    made = conn.execute("SELECT * FROM tgsis.fill_property_rows('inchunks', %s)", (values,)).fetchall()
    conn.commit()
    assert made == [("inchunks_cellpros", 0, 0), ("inchunks_simplexpros", 1, n)]
    assert [r[1:] for r in _other_rows(conn, "inchunks")] == [r[1:] for r in _other_rows(conn, "onrows")]
    assert _kinds(conn, "inchunks") == ("v", True, "v", True)
    fetched = _fetched(conn, "inchunks", geoids["inchunks"])
    assert _same(fetched.cell_properties, _fetched(conn, "onrows", geoids["onrows"]).cell_properties)


def test_a_table_without_a_property_column_stays_rows(conn: Conn) -> None:
    F.create_feature_class(conn, "tops", "SURFACE", cell_properties=[tgsis.Property("facies", "int", alignment="CELL")])
    F.create_feature_class(conn, "bare", "SURFACE")
    conn.commit()
    assert conn.execute("SELECT tgsis.store_class_in_chunks('tops')").fetchone() == (0,)
    conn.commit()
    assert _kinds(conn, "tops") == ("r", False, "v", True)
    assert sqlstate(conn, "SELECT tgsis.store_class_in_chunks('tops')")[0] == "TG201"
    assert sqlstate(conn, "SELECT tgsis.store_class_in_chunks('bare')")[0] == "TG100"  # nothing to chunk, as before
    conn.execute("SELECT tgsis.store_class_in_rows('tops')")
    conn.commit()
    assert _kinds(conn, "tops") == ("r", False, "r", False)


def _user_indexes(conn: Conn, name: str) -> list[tuple[str, str]]:
    """The indexes of both property tables' row storage (the table, or its _ver), by name and definition."""
    return conn.execute(
        "SELECT c.relname::text, pg_get_indexdef(i.indexrelid) FROM pg_index i JOIN pg_class c ON c.oid = i.indexrelid"
        " WHERE i.indrelid IN (to_regclass(tgsis.storage_table('public', %s)), to_regclass(tgsis.storage_table('public', %s)))"
        " ORDER BY 1",
        (f"{name}_cellpros", f"{name}_simplexpros"),
    ).fetchall()


@pytest.mark.parametrize("versioned", [False, True])
def test_the_tables_own_indexes_come_back_by_name(conn: Conn, versioned: bool) -> None:
    """A user's indexes on the property tables are kept by the switch and made again on the way back, as they were."""
    _class(conn, "indexed")
    F.insert_feature(conn, "indexed", _surface(5))
    if versioned:
        tgsis.enable_feature_versioning(conn)
    odd = "indexed ON public.indexed_simplexpros USING x"  # a quoted name holding what a definition's head holds
    for index, definition in (
        ("indexed_grade_idx", "(grade)"),
        ("indexed_facies_idx", "(facies) WHERE facies > 0"),
        (odd, "(grade DESC, facies)"),
        ("indexed_exact_idx", "(grade) WHERE grade > '0.30000000000000004'::float8"),  # kept exactly under any session
    ):
        conn.execute(
            sql.SQL("CREATE INDEX {} ON {} ").format(
                sql.Identifier(index),
                sql.SQL(
                    conn.execute("SELECT tgsis.storage_table('public', 'indexed_simplexpros')").fetchone()[0]  # type: ignore[index]
                ),
            )
            + sql.SQL(definition)
        )
    conn.commit()
    before = _user_indexes(conn, "indexed")
    assert {"indexed_grade_idx", "indexed_facies_idx", odd} <= {name for name, _ in before}
    conn.execute("SET extra_float_digits = -15")  # a session printing floats short: the predicate is not rounded
    conn.execute("SELECT tgsis.store_class_in_chunks('indexed')")
    conn.commit()
    assert _kinds(conn, "indexed")[3]  # the other table in chunks: its row storage gone, the indexes kept aside
    conn.execute("SELECT tgsis.store_class_in_rows('indexed')")
    conn.commit()
    conn.execute("RESET extra_float_digits")
    assert _user_indexes(conn, "indexed") == before


@pytest.mark.parametrize("unversioned", ["versioning off", "class without versioning"])
@pytest.mark.parametrize("where", ["version v1", "an older revision"])
def test_fill_property_rows_from_outside_default_in_chunks_as_on_its_rows_twin(
    conn: Conn, unversioned: str, where: str
) -> None:
    """fill_property_rows of an unversioned class from a session in another version (or viewing an older revision
    of DEFAULT): the rows twin's direct INSERT accepts, so the face's does too (the rows made are the one state
    every version reads); the session's settings are as they were after the call.

    Failed before: the face's trigger refused TG305 (tgsis.plain_write_check / tgsis.unversioned_revision).
    """
    for name in ("onrows", "inchunks"):
        if unversioned == "versioning off":
            _class(conn, name)
        else:
            F.create_feature_class(conn, name, "SURFACE", cell_properties=PROPERTIES, versioned=False)
    if unversioned == "class without versioning":
        tgsis.enable_feature_versioning(conn)
    geoids = {name: F.insert_feature(conn, name, _surface(11)) for name in ("onrows", "inchunks")}
    conn.execute("SELECT tgsis.store_class_in_chunks('inchunks')")
    conn.commit()
    for name, geoid in geoids.items():
        conn.execute(
            sql.SQL("DELETE FROM public.{} WHERE _geoid = %s").format(sql.Identifier(f"{name}_simplexpros")), (geoid,)
        )
        conn.commit()
    tgsis.create_version(conn, "v1")
    if where == "version v1":
        tgsis.goto_version(conn, "v1")
    else:
        tgsis.goto_revision(conn, "DEFAULT", 0)
    settings = conn.execute("SELECT current_setting('tgsis.version', true), current_setting('tgsis.revision', true)")
    before = settings.fetchone()
    values = '{"facies": -7, "dip": 2.5e-308, "grade": -0.0}'
    n = _surface(11).n_cells
    for name in ("onrows", "inchunks"):
        made = conn.execute("SELECT * FROM tgsis.fill_property_rows(%s, %s)", (name, values)).fetchall()
        assert made == [(f"{name}_cellpros", 0, 0), (f"{name}_simplexpros", 1, n)]
        assert (
            conn.execute(
                "SELECT current_setting('tgsis.version', true), current_setting('tgsis.revision', true)"
            ).fetchone()
            == before
        )
        conn.commit()
    tgsis.goto_version(conn, "DEFAULT")
    assert [r[1:] for r in _other_rows(conn, "inchunks")] == [r[1:] for r in _other_rows(conn, "onrows")]
    assert len(_other_rows(conn, "inchunks")) == n
    assert _kinds(conn, "inchunks") == ("v", True, "v", True)
    tgsis.goto_version(conn, "v1")
    assert [r[1:] for r in _other_rows(conn, "inchunks")] == [r[1:] for r in _other_rows(conn, "onrows")]


def _face_objects(conn: Conn, name: str) -> list[tuple[Any, ...]]:
    """Both faces' generated row functions (definition, owner, rights) and the triggers on the faces."""
    functions = conn.execute(
        "SELECT p.proname::text, pg_get_functiondef(p.oid), pg_get_userbyid(p.proowner)::text, p.proacl::text "
        "FROM pg_proc p WHERE p.pronamespace = 'public'::regnamespace AND p.proname IN (%s, %s) ORDER BY 1",
        (f"{name}_cellpros_face_row", f"{name}_simplexpros_face_row"),
    ).fetchall()
    triggers = conn.execute(
        "SELECT c.relname::text, t.tgname::text, pg_get_triggerdef(t.oid) FROM pg_trigger t "
        "JOIN pg_class c ON c.oid = t.tgrelid WHERE c.relname IN (%s, %s) AND NOT t.tgisinternal ORDER BY 1, 2",
        (f"{name}_cellpros", f"{name}_simplexpros"),
    ).fetchall()
    return [tuple(r) for r in functions] + [tuple(r) for r in triggers]


def _write_both_faces(conn: Conn, name: str, geoid: int) -> None:
    conn.execute(
        sql.SQL("UPDATE public.{} SET porosity = -0.0 WHERE _geoid = %s AND _idx IN (0, 1599)").format(
            sql.Identifier(f"{name}_cellpros")
        ),
        (geoid,),
    )
    conn.execute(
        sql.SQL(
            "UPDATE public.{} SET dip = ARRAY[1, 'NaN', 5e-324], grade = '-0' WHERE _geoid = %s AND _idx = 3000"
        ).format(sql.Identifier(f"{name}_simplexpros")),
        (geoid,),
    )
    conn.execute(
        sql.SQL("DELETE FROM public.{} WHERE _geoid = %s AND _idx = 7").format(sql.Identifier(f"{name}_simplexpros")),
        (geoid,),
    )
    conn.commit()


@pytest.mark.parametrize("versioned", [False, True])
def test_pg_dump_and_restore_of_a_class_with_both_tables_in_chunks(
    pg: Any, db_dsn: str, conn: Conn, tmp_path: Any, versioned: bool
) -> None:
    """Both property tables in chunks, dumped and restored (custom format): both faces' rows (floats by their bits;
    no NaN payload, which pg_dump's text COPY does not keep), the generated row functions <table>_face_row and the
    faces' triggers as they were, the feature fetched, and a write through each restored face equal to the same
    write on the source."""
    from tests.test_backup import _bindir_of, _restored

    _class(conn, "dumped")
    if versioned:
        tgsis.enable_feature_versioning(conn)
    surface = _surface(12)
    dip = surface.cell_properties["dip"]
    dip[2, 0] = np.nan  # the quiet NaN without payload
    grade = surface.cell_properties["grade"]
    grade[1] = np.float32(np.nan)
    geoid = F.insert_feature(conn, "dumped", surface)
    conn.execute("SELECT tgsis.store_class_in_chunks('dumped')")
    conn.commit()
    assert _kinds(conn, "dumped") == ("v", True, "v", True)
    objects, own, other = _face_objects(conn, "dumped"), _own_rows(conn, "dumped"), _other_rows(conn, "dumped")
    assert len(objects) >= 2 and len(own) == surface.n_vertices and len(other) == surface.n_cells
    fetched = _fetched(conn, "dumped", geoid)
    conn.rollback()
    with _restored(pg, _bindir_of(pg), db_dsn, "custom", tmp_path) as dsn, psycopg.connect(dsn) as copy:
        assert _kinds(copy, "dumped") == ("v", True, "v", True)
        assert _face_objects(copy, "dumped") == objects
        assert _own_rows(copy, "dumped") == own and _other_rows(copy, "dumped") == other
        again = _fetched(copy, "dumped", geoid)
        assert _same(again.cell_properties, fetched.cell_properties)
        assert _same(again.vertex_properties, fetched.vertex_properties)
        copy.rollback()
        _write_both_faces(copy, "dumped", geoid)
        _write_both_faces(conn, "dumped", geoid)
        assert _own_rows(copy, "dumped") == _own_rows(conn, "dumped")
        assert _other_rows(copy, "dumped") == _other_rows(conn, "dumped")
        assert len(_other_rows(copy, "dumped")) == surface.n_cells - 1
        copy.rollback()
        conn.rollback()
