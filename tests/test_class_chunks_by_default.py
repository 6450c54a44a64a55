"""The flip: a STATIC class's property tables are made in chunks when model 1 is in chunks (issue 40).

docs/storage.md, "Property chunks by default: the rule": ``tgsis.register_feature_class`` (so
``create_feature_class``, the CLI, GOCAD import) stores a new STATIC class's property tables in
chunks when ``tgsis.vrtx`` is stored in chunks in that database and ``tgsis.chosen_storage()`` is
``chunks``; ``tgsis.storage = rows`` keeps rows, a temporal class stays rows, a class with no
property column stays rows until ``add_property`` gives its table the first one. The switch runs
as tgsis's owner, whoever registers. Each test names the storage of model 1 it needs.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import psycopg
import pytest

import tgsis
from tests.merge_data import curved_surface, sqlstate
from tests.roles import login_roles
from tgsis.db import features as F

Conn = psycopg.Connection[Any]


def _chunked(conn: Conn, table: str, schema: str = "public") -> bool:
    row = conn.execute("SELECT tgsis.stored_in_chunks(%s, %s)", (schema, table)).fetchone()
    assert row is not None
    return bool(row[0])


def _same_feature(conn: Conn, name: str, geoid: int, surface: tgsis.Surface) -> None:
    mesh = F.fetch_feature(conn, name, geoid).mesh
    assert isinstance(mesh, tgsis.Surface)
    for key, values in surface.vertex_properties.items():
        assert np.array_equal(np.asarray(mesh.vertex_properties[key]), values)
    for key, values in surface.cell_properties.items():
        assert np.array_equal(np.asarray(mesh.cell_properties[key]), values)


@pytest.mark.storage("chunks")
def test_a_static_class_is_made_in_chunks_when_model_1_is(conn: Conn) -> None:
    tgsis.create_feature_class(
        conn,
        "layer",
        "SURFACE",
        cell_properties=[("porosity", "double precision"), {"name": "facies", "type": "integer", "alignment": "CELL"}],
    )
    assert _chunked(conn, "layer_cellpros") and _chunked(conn, "layer_simplexpros")
    surface = curved_surface()
    geoid = F.insert_feature(conn, "layer", surface)
    _same_feature(conn, "layer", geoid, surface)
    # a second switch finds nothing to do
    assert sqlstate(conn, "SELECT tgsis.store_class_in_chunks('layer')")[0] == "TG201"
    # temporal classes stay rows; so does a class without a property column
    tgsis.create_feature_class(conn, "series", "SURFACE", time_model="INSTANTS", cell_properties=[("t", "real")])
    tgsis.create_feature_class(conn, "bare", "SURFACE")
    assert not _chunked(conn, "series_cellpros") and not _chunked(conn, "bare_cellpros")
    # tgsis.storage = rows keeps rows; a value naming no storage refuses the class (TG001), nothing made
    conn.execute("SET tgsis.storage = rows")
    tgsis.create_feature_class(conn, "kept", "SURFACE", cell_properties=[("porosity", "double precision")])
    assert not _chunked(conn, "kept_cellpros")
    conn.execute("SET tgsis.storage = chunk")
    assert (
        sqlstate(conn, "SELECT tgsis.register_feature_class('typo', 'SURFACE', '[]', '[[\"p\", \"real\"]]')")[0]
        == "TG001"
    )
    conn.execute("RESET tgsis.storage")
    assert conn.execute("SELECT count(*) FROM tgsis.catalog WHERE classname = 'typo'").fetchone() == (0,)


@pytest.mark.storage("chunks")
def test_a_class_in_a_schema_of_an_odd_name_is_made_in_chunks(conn: Conn) -> None:
    """The schema's name read as text, not cast to regnamespace (which parses it as an identifier: 42602)."""
    conn.execute('CREATE SCHEMA "Odd ""Schema"""')
    tgsis.create_feature_class(
        conn,
        "odd",
        "SURFACE",
        cell_properties=[("porosity", "double precision"), {"name": "facies", "type": "integer", "alignment": "CELL"}],
        schema='Odd "Schema"',
    )
    assert conn.execute("SELECT tgsis.stored_in_chunks('Odd \"Schema\"', 'odd_cellpros')").fetchone() == (True,)
    surface = curved_surface()
    geoid = F.insert_feature(conn, "odd", surface)
    _same_feature(conn, "odd", geoid, surface)
    conn.execute("SELECT tgsis.store_class_in_rows('odd')")
    conn.execute("SELECT tgsis.store_class_in_chunks('odd')")
    _same_feature(conn, "odd", geoid, surface)


@pytest.mark.storage("rows")
def test_class_tables_stay_rows_when_model_1_is_rows(conn: Conn) -> None:
    tgsis.create_feature_class(conn, "layer", "SURFACE", cell_properties=[("porosity", "double precision")])
    assert not _chunked(conn, "layer_cellpros")
    assert conn.execute("SELECT tgsis.chunk_class_by_default('layer')").fetchone() == (False,)


@pytest.mark.storage("chunks")
def test_the_first_property_of_a_bare_class_puts_it_in_chunks(conn: Conn) -> None:
    tgsis.create_feature_class(conn, "bare", "SURFACE")
    surface = curved_surface()
    geoid = F.insert_feature(conn, "bare", surface, drop_extra_properties=True)
    assert not _chunked(conn, "bare_cellpros")
    conn.execute("""SELECT tgsis.add_property('bare', 'cell', '["porosity", "double precision"]', '0.25')""")
    assert _chunked(conn, "bare_cellpros")
    rows = conn.execute(
        "SELECT count(*), min(porosity), max(porosity) FROM public.bare_cellpros WHERE _geoid = %s", (geoid,)
    )
    assert rows.fetchone() == (len(surface.vertices), 0.25, 0.25)
    # a class kept rows by choice stays rows when it gets more properties
    conn.execute("SET tgsis.storage = rows")
    tgsis.create_feature_class(conn, "kept", "SURFACE", cell_properties=[("porosity", "double precision")])
    conn.execute("RESET tgsis.storage")
    conn.execute("""SELECT tgsis.add_property('kept', 'cell', '["depth", "real"]')""")
    assert not _chunked(conn, "kept_cellpros")


@pytest.mark.storage("chunks")
def test_a_versioned_class_is_made_in_chunks_and_versioned(conn: Conn) -> None:
    tgsis.enable_feature_versioning(conn)
    tgsis.create_feature_class(conn, "layer", "SURFACE", cell_properties=[("porosity", "double precision")])
    assert _chunked(conn, "layer_cellpros")
    assert conn.execute(
        "SELECT count(*) FROM tgsis.versioned_tables WHERE schemaname = 'public' AND tablename = 'layer_cellpros'"
    ).fetchone() == (1,)
    surface = curved_surface()
    geoid = F.insert_feature(conn, "layer", surface, drop_extra_properties=True)
    conn.commit()
    _same_feature(
        conn,
        "layer",
        geoid,
        tgsis.Surface(surface.vertices, surface.cells, vertex_properties=dict(surface.vertex_properties)),
    )


@pytest.mark.storage("chunks")
def test_an_admin_who_is_not_the_owner_gets_the_chunk_tables_with_the_class_grants(db_dsn: str) -> None:
    with login_roles(db_dsn, {"admin": "tgsis_admin", "reader": "tgsis_reader", "editor": "tgsis_editor"}) as roles:
        with psycopg.connect(db_dsn, autocommit=True) as owner:
            owner.execute(f"GRANT CREATE ON SCHEMA public TO {roles.name('admin')}")
        admin = roles.connect("admin")
        admin.execute("""SELECT tgsis.register_feature_class('layer', 'SURFACE', '[]', '[["porosity", "real"]]')""")
        admin.commit()
        assert _chunked(admin, "layer_cellpros")
        owners = admin.execute(
            "SELECT DISTINCT pg_get_userbyid(relowner) FROM pg_class "
            "WHERE oid IN ('public.layer'::regclass, 'public.layer_cellpros'::regclass, 'public.layer_cellpros_chunk'::regclass)"
        ).fetchall()
        assert len(owners) == 1 and owners[0][0] != roles.name("admin")
        editor = roles.connect("editor")
        editor.execute("INSERT INTO public.layer_cellpros (_geoid, _idx, porosity) VALUES (1, 0, 0.5)")
        editor.commit()
        reader = roles.connect("reader")
        assert reader.execute("SELECT porosity FROM public.layer_cellpros").fetchall() == [(0.5,)]
        assert (
            sqlstate(reader, "INSERT INTO public.layer_cellpros (_geoid, _idx, porosity) VALUES (1, 1, 0.5)")[0]
            == "42501"
        )
        # the switch itself stays the admins': not callable by an editor
        assert sqlstate(editor, "SELECT tgsis.chunk_class_by_default('layer')")[0] == "42501"


@pytest.mark.storage("chunks")
def test_dropping_properties_of_a_class_in_chunks(conn: Conn) -> None:
    tgsis.create_feature_class(
        conn, "layer", "SURFACE", cell_properties=[("porosity", "double precision"), ("depth", "real")]
    )
    surface = curved_surface()
    geoid = F.insert_feature(
        conn,
        "layer",
        tgsis.Surface(
            surface.vertices,
            surface.cells,
            vertex_properties={
                "porosity": surface.vertex_properties["porosity"],
                "depth": np.ones(len(surface.vertices)),
            },
        ),
    )
    # the values held are counted per vertex, not per chunk
    state, message = sqlstate(conn, "SELECT tgsis.drop_property('layer', 'depth')")
    assert state == "TG202" and f"holds {len(surface.vertices)} value(s)" in message
    conn.execute("SELECT tgsis.drop_property('layer', 'depth', p_force => true)")
    assert _chunked(conn, "layer_cellpros")
    # the last one: the table has nothing a chunk would hold, so it is rows again; a new property puts it back
    conn.execute("SELECT tgsis.drop_property('layer', 'porosity', p_force => true)")
    assert not _chunked(conn, "layer_cellpros")
    assert F.fetch_feature(conn, "layer", geoid).mesh is not None
    conn.execute("""SELECT tgsis.add_property('layer', 'cell', '["porosity", "double precision"]', '0.5')""")
    assert _chunked(conn, "layer_cellpros")
    _same_feature(
        conn,
        "layer",
        geoid,
        tgsis.Surface(
            surface.vertices, surface.cells, vertex_properties={"porosity": np.full(len(surface.vertices), 0.5)}
        ),
    )
