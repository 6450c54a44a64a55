"""add/rename/drop property on a class stored in chunks, in place (issue 40, plan F area Q2).

docs/storage.md, "Property chunks: the contract": ``tgsis.alter_class_table`` alters the chunk table
itself (``tgsis.alter_chunk_table``), versioned or not, instead of converting the table to rows and back:
the chunk table keeps its oid, the other properties' arrays keep their bytes in every chunk version, a new
property is its default at every present slot and NULL at every hole (the contract's encoding), the face is
made again with its grants. The property tables are rows or chunks whatever model 1's storage is, so the
file runs unmarked.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import psycopg
import pytest
from psycopg import sql

import tgsis
from tests.merge_data import curved_surface, every_view, sqlstate
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


#: float8 bits: -0.0, the smallest subnormal, NaN with a payload, -inf
F8_BITS = [0x8000000000000000, 0x0000000000000001, 0x7FF8000000000ABC, 0xFFF0000000000000]


def _values(n: int) -> dict[str, Any]:
    rng = np.random.default_rng(3)
    f8 = rng.standard_normal(n)
    f8[: len(F8_BITS)] = np.array(F8_BITS, dtype=np.uint64).view(np.float64)
    return {
        "p_i4": rng.integers(-(2**31), 2**31, n, dtype=np.int64).astype(np.int32),
        "p_f8": f8,
        "p_b": rng.random(n) < 0.5,
    }


def _class(conn: Conn, name: str, geotype: str = "SURFACE") -> None:
    tgsis.create_feature_class(
        conn, name, geotype, cell_properties=[("p_i4", "integer"), ("p_f8", "double precision"), ("p_b", "boolean")]
    )


def _arrays(conn: Conn, name: str) -> dict[str, dict[tuple[int, int, int], bytes]]:
    """Each property array's bytes (array_send) per chunk version, by column number of the chunk table."""
    chunk = f"public.{name}_cellpros_chunk"
    columns = conn.execute(
        "SELECT attnum, attname FROM pg_attribute WHERE attrelid = %s::regclass AND attnum > 0 AND NOT attisdropped "
        "AND attname NOT IN ('_geoid', 'chunk', 'revision', 'lastrevs', 'revclosed', 'holes') ORDER BY attnum",
        (chunk,),
    ).fetchall()
    seen = {}
    for attnum, attname in columns:
        rows = conn.execute(
            sql.SQL("SELECT _geoid, chunk, revision, array_send({}) FROM {} ORDER BY 1, 2, 3").format(
                sql.Identifier(attname), sql.SQL(chunk)
            )
        ).fetchall()
        seen[f"{attnum}:{attname}"] = {(r[0], r[1], r[2]): bytes(r[3]) for r in rows}
    return seen


def _oid(conn: Conn, name: str) -> int:
    row = conn.execute("SELECT %s::regclass::oid::bigint", (f"public.{name}_cellpros_chunk",)).fetchone()
    assert row is not None
    return int(row[0])


def _encoded_as_read(conn: Conn, name: str) -> bool:
    """Every chunk version meets tgsis.chunk_encoding_checks (the new array: present, the chunk's length, NULL at holes)."""
    checks = conn.execute("SELECT tgsis.chunk_encoding_checks(%s)", (f"public.{name}_cellpros",)).fetchone()
    assert checks is not None
    row = conn.execute(
        sql.SQL("SELECT bool_and({}) FROM public.{} c").format(
            sql.SQL(" AND ").join(sql.SQL(c) for c in checks[0]), sql.Identifier(f"{name}_cellpros_chunk")
        )
    ).fetchone()
    return row == (True,)


def _grants(conn: Conn, name: str) -> list[str]:
    return [
        r[0]
        for r in conn.execute(
            "SELECT format('%%s %%s', grantee, privilege_type) FROM information_schema.role_table_grants "
            "WHERE table_schema = 'public' AND table_name = %s AND grantee LIKE 'tgsis%%' ORDER BY 1",
            (f"{name}_cellpros",),
        ).fetchall()
    ]


def test_add_rename_drop_in_place_on_an_unversioned_class(db_dsn: str, conn: Conn) -> None:
    surface = curved_surface()
    n = surface.n_vertices
    values = _values(n)
    _class(conn, "alt")
    geoid = F.insert_feature(conn, "alt", Surface(surface.vertices, surface.cells, vertex_properties=values))
    conn.execute("SELECT tgsis.store_class_in_chunks('alt')")
    conn.execute("GRANT SELECT, INSERT, UPDATE ON public.alt_cellpros TO tgsis_editor")
    # a hole inside chunk 0 (slot 6): the new array must be NULL there and the default elsewhere
    conn.execute("DELETE FROM public.alt_cellpros WHERE _geoid = %s AND _idx = 5", (geoid,))
    conn.commit()
    oid, grants, before = _oid(conn, "alt"), _grants(conn, "alt"), _arrays(conn, "alt")
    assert "tgsis_editor UPDATE" in grants

    tgsis.add_property(conn, "alt", ("p_new", "real"), default="-0.0")
    conn.commit()
    assert _oid(conn, "alt") == oid and _grants(conn, "alt") == grants  # altered in place, the face's grants kept
    now = _arrays(conn, "alt")
    assert {k: v for k, v in now.items() if not k.endswith(":p_new")} == before  # the other arrays, byte for byte
    assert _encoded_as_read(conn, "alt")
    row = conn.execute(
        "SELECT bool_and(coalesce(array_positions(p_new, NULL), '{}') = coalesce(holes::integer[], '{}')), "
        "bool_and(cardinality(p_new) = cardinality(p_i4)), min(holes::text) FROM public.alt_cellpros_chunk"
    ).fetchone()
    assert row == (True, True, "{6}")
    counted = conn.execute(
        "SELECT count(*), count(*) FILTER (WHERE float4send(p_new) = float4send('-0'::real)) FROM public.alt_cellpros"
    ).fetchone()
    assert counted == (n - 1, n - 1)
    facts = conn.execute(
        "SELECT a.attcompression::text, col_description('public.alt_cellpros'::regclass, f.attnum) IS NOT NULL, "
        "(SELECT count(*) FROM pg_trigger t WHERE t.tgrelid = 'public.alt_cellpros'::regclass) "
        "FROM pg_attribute a, pg_attribute f WHERE a.attrelid = 'public.alt_cellpros_chunk'::regclass "
        "AND a.attname = 'p_new' AND f.attrelid = 'public.alt_cellpros'::regclass AND f.attname = 'p_new'"
    ).fetchone()
    # pglz as create_chunk_table chooses; commented; the face's four triggers (the row kept, the kept rows' table
    # checked, the flush, the snapshot check)
    assert facts == ("p", True, 4)

    # written through the face by a role with the face's grants, and by the bulk upload; read back bit-exact
    with login_roles(db_dsn, {"editor": "tgsis_editor"}) as roles:
        editor = roles.connect("editor")
        editor.execute("UPDATE public.alt_cellpros SET p_new = 1.5 WHERE _geoid = %s AND _idx = 0", (geoid,))
        editor.commit()
        # a role that is not tgsis_admin may not change the class: refused, nothing changed
        assert sqlstate(editor, "SELECT tgsis.drop_property('alt', 'p_new', p_force => true)")[0] == "TG002"
    assert conn.execute("SELECT p_new FROM public.alt_cellpros WHERE _idx = 0").fetchone() == (1.5,)
    props = values | {"p_new": np.arange(n, dtype=np.float32) - np.float32(0.5)}
    second = F.insert_feature(conn, "alt", Surface(surface.vertices, surface.cells, vertex_properties=props))
    conn.commit()
    back = F.fetch_feature(conn, "alt", second).mesh.vertex_properties  # type: ignore[union-attr]
    assert np.array_equal(back["p_new"].view(np.int32), props["p_new"].view(np.int32))
    assert np.array_equal(back["p_f8"].view(np.int64), values["p_f8"].view(np.int64))

    # renamed and dropped in place: the same chunk table, the other arrays' bytes kept
    before = _arrays(conn, "alt")
    tgsis.rename_property(conn, "alt", "p_f8", "p_double")
    tgsis.drop_property(conn, "alt", "p_i4", force=True)
    conn.commit()
    assert _oid(conn, "alt") == oid and _grants(conn, "alt") == grants
    expected = {k.replace(":p_f8", ":p_double"): v for k, v in before.items() if not k.endswith(":p_i4")}
    assert _arrays(conn, "alt") == expected
    shape = conn.execute(
        "SELECT array_agg(attname::text ORDER BY attnum) FROM pg_attribute "
        "WHERE attrelid = 'public.alt_cellpros'::regclass AND attnum > 0"
    ).fetchone()
    assert shape == (["_geoid", "_idx", "p_double", "p_b", "p_new"],)
    back = F.fetch_feature(conn, "alt", second).mesh.vertex_properties  # type: ignore[union-attr]
    assert np.array_equal(back["p_double"].view(np.int64), values["p_f8"].view(np.int64)) and "p_i4" not in back


def test_what_chunks_cannot_hold_is_refused_by_name_nothing_changed(conn: Conn) -> None:
    surface = curved_surface()
    _class(conn, "odd")
    F.insert_feature(
        conn, "odd", Surface(surface.vertices, surface.cells, vertex_properties=_values(surface.n_vertices))
    )
    conn.execute("SELECT tgsis.store_class_in_chunks('odd')")
    conn.commit()
    before = _arrays(conn, "odd")
    # (a vector property is added and renamed in place since plan L: tests/test_vector_property_alter.py)
    for statement in (
        """SELECT tgsis.add_property('odd', 'cell', '{"name": "holes", "type": "integer"}', '0')""",
        "SELECT tgsis.rename_property('odd', 'p_b', 'vtop')",
    ):
        state, message = sqlstate(conn, statement)
        assert state == "TG100" and any(w in message for w in ("normal", "holes", "vtop")), (statement, state, message)
    # a user's view over the face: refused by name (TG202), nothing changed
    conn.execute("CREATE VIEW public.odd_view AS SELECT _geoid, p_b FROM public.odd_cellpros")
    conn.commit()
    state, message = sqlstate(conn, "SELECT tgsis.drop_property('odd', 'p_i4', p_force => true)")
    assert state == "TG202" and "odd_view" in message, message
    assert _arrays(conn, "odd") == before
    conn.execute("DROP VIEW public.odd_view")
    conn.commit()
    tgsis.drop_property(conn, "odd", "p_i4", force=True)
    tgsis.drop_property(conn, "odd", "p_f8", force=True)
    conn.commit()
    assert _arrays(conn, "odd") == {k: v for k, v in before.items() if k.endswith(":p_b")}
    # the last property: a chunk holds one array per property, so the table is dropped from as rows and stays rows
    # (docs/storage.md, "Property chunks by default: the rule"; it was refused TG100 before)
    tgsis.drop_property(conn, "odd", "p_b", force=True)
    conn.commit()
    assert conn.execute("SELECT tgsis.stored_in_chunks('public', 'odd_cellpros')").fetchone() == (False,)
    assert conn.execute(
        "SELECT count(*) FROM pg_attribute WHERE attrelid = 'public.odd_cellpros'::regclass AND attname = 'p_b'"
    ).fetchone() == (0,)


def test_a_property_added_without_default_is_null_at_present_slots(conn: Conn) -> None:
    surface = curved_surface()
    _class(conn, "coll", "GEOMETRYCOLLECTION")
    member = Surface(surface.vertices, surface.cells, vertex_properties=_values(surface.n_vertices))
    F.insert_feature(conn, "coll", GeometryCollection([member]))
    conn.execute("SELECT tgsis.store_class_in_chunks('coll')")
    conn.commit()
    tgsis.add_property(conn, "coll", ("p_none", "bigint"))
    conn.commit()
    assert _encoded_as_read(conn, "coll")
    row = conn.execute("SELECT count(*), count(p_none) FROM public.coll_cellpros").fetchone()
    assert row == (surface.n_vertices, 0)  # every present slot a row, its value NULL (not a hole)


def test_an_upload_in_flight_is_waited_for_and_gets_the_new_property(db_dsn: str, conn: Conn) -> None:
    surface = curved_surface()
    values = _values(surface.n_vertices)
    _class(conn, "busy")
    conn.execute("SELECT tgsis.store_class_in_chunks('busy')")
    conn.commit()
    writer = connect(db_dsn, "writer")
    geoid = F.insert_feature(writer, "busy", Surface(surface.vertices, surface.cells, vertex_properties=values))

    def adder(session: Conn) -> Any:
        return sqlstate(session, "SELECT tgsis.add_property('busy', 'cell', '[\"p_new\", \"integer\"]', '5')")

    background = Background(db_dsn, "adder", adder)
    wait_until_blocked(conn, background.pid, writer.info.backend_pid)
    conn.rollback()
    writer.commit()
    writer.close()
    state, message = background.finish()
    assert state is None, message
    row = conn.execute("SELECT count(*), count(*) FILTER (WHERE p_new = 5) FROM public.busy_cellpros").fetchone()
    assert row == (surface.n_vertices, surface.n_vertices)  # the upload committed first got the default too
    back = F.fetch_feature(conn, "busy", geoid).mesh.vertex_properties  # type: ignore[union-attr]
    assert np.array_equal(back["p_f8"].view(np.int64), values["p_f8"].view(np.int64))


def test_another_session_inside_a_transaction_that_wrote_through_the_face_is_waited_for(
    db_dsn: str, conn: Conn
) -> None:
    """Its work tables (of the face's row type) and its lock live as long as its transaction: the add waits (here
    55P03 under a lock_timeout), nothing changed; once it commits, the add goes through while it stays connected
    (ON COMMIT DROP; before, the idle session blocked the add, TG202 naming its tables, until it disconnected)."""
    surface = curved_surface()
    _class(conn, "held")
    geoid = F.insert_feature(
        conn, "held", Surface(surface.vertices, surface.cells, vertex_properties=_values(surface.n_vertices))
    )
    conn.execute("SELECT tgsis.store_class_in_chunks('held')")
    conn.commit()
    other = connect(db_dsn, "other")
    other.execute("UPDATE public.held_cellpros SET p_i4 = 1 WHERE _geoid = %s AND _idx = 0", (geoid,))
    before = _arrays(conn, "held")
    conn.execute("SET lock_timeout = '300ms'")
    add = "SELECT tgsis.add_property('held', 'cell', '[\"p_new\", \"integer\"]', '5')"
    state, message = sqlstate(conn, add)
    assert state == "55P03", message
    assert _arrays(conn, "held") == before
    other.commit()  # still open, idle
    assert sqlstate(conn, add) == (None, "")
    conn.commit()
    assert conn.execute(
        "SELECT p_i4, p_new FROM public.held_cellpros WHERE _geoid = %s AND _idx = 0", (geoid,)
    ).fetchone() == (1, 5)
    other.close()


def _layer_rows(conn: Conn, columns: str) -> list[tuple[Any, ...]]:
    query = sql.SQL("SELECT _geoid, _idx, {} FROM public.layer_cellpros ORDER BY 1, 2").format(sql.SQL(columns))
    return [tuple(r) for r in conn.execute(query).fetchall()]


def _every_view(conn: Conn, columns: str) -> dict[tuple[str, int | None], list[tuple[Any, ...]]]:
    seen = {}
    for version, revision in every_view(conn):
        if revision is None:
            conn.execute("SELECT tgsis.goto_version(%s, true)", (version,))
        else:
            conn.execute("SELECT tgsis.goto_revision(%s, %s, true)", (version, revision))
        seen[(version, revision)] = _layer_rows(conn, columns)
    conn.execute("SELECT tgsis.goto_version('DEFAULT', true)")
    return seen


def test_add_rename_drop_in_place_on_a_versioned_class(conn: Conn) -> None:
    surface = curved_surface()
    n = surface.n_vertices
    porosity = np.random.default_rng(4).standard_normal(n)
    porosity[:4] = np.array(F8_BITS, dtype=np.uint64).view(np.float64)
    tgsis.create_feature_class(
        conn, "layer", "SURFACE", cell_properties=[("porosity", "double precision"), ("facies", "integer")]
    )
    tgsis.enable_feature_versioning(conn)
    props: dict[str, Any] = {"porosity": porosity, "facies": np.arange(n, dtype=np.int32) % 7}
    geoid = F.insert_feature(conn, "layer", Surface(surface.vertices, surface.cells, vertex_properties=props))
    tgsis.create_version(conn, "e1")
    conn.commit()
    conn.execute("SELECT tgsis.store_class_in_chunks('layer')")
    conn.commit()
    with tgsis.in_version(conn, "e1"):
        conn.execute("UPDATE public.layer_cellpros SET facies = 41 WHERE _geoid = %s AND _idx = 1", (geoid,))
        conn.execute("DELETE FROM public.layer_cellpros WHERE _geoid = %s AND _idx = 2", (geoid,))
    conn.commit()
    oid = _oid(conn, "layer")
    views = _every_view(conn, "float8send(porosity), facies")
    assert len(views) >= 3 and views[("e1", None)] != views[("DEFAULT", None)]

    tgsis.add_property(conn, "layer", ("grade", "smallint"), default="9")
    tgsis.rename_property(conn, "layer", "porosity", "phi")
    conn.commit()
    assert _oid(conn, "layer") == oid and _encoded_as_read(conn, "layer")
    after = _every_view(conn, "float8send(phi), facies, grade")
    assert {k: [r[:4] for r in v] for k, v in after.items()} == views  # every version and revision, bit for bit
    assert all(r[4] == 9 for rows in after.values() for r in rows)  # the default at every version

    # the new property is written in a version through the face, and seen there only
    with tgsis.in_version(conn, "e1"):
        conn.execute("UPDATE public.layer_cellpros SET grade = -3 WHERE _geoid = %s AND _idx = 0", (geoid,))
    conn.commit()
    with tgsis.in_version(conn, "e1"):
        assert conn.execute("SELECT grade FROM public.layer_cellpros WHERE _idx = 0").fetchone() == (-3,)
    assert conn.execute("SELECT grade FROM public.layer_cellpros WHERE _idx = 0").fetchone() == (9,)

    tgsis.drop_property(conn, "layer", "grade", force=True)
    conn.commit()
    assert _oid(conn, "layer") == oid
    assert _every_view(conn, "float8send(phi), facies") == views


def test_a_solved_conflict_stays_solved_across_an_add_in_place(conn: Conn) -> None:
    surface = curved_surface()
    n = surface.n_vertices
    tgsis.create_feature_class(
        conn, "layer", "SURFACE", cell_properties=[("porosity", "double precision"), ("facies", "integer")]
    )
    tgsis.enable_feature_versioning(conn)
    props: dict[str, Any] = {"porosity": np.linspace(0, 1, n), "facies": np.arange(n, dtype=np.int32) % 7}
    geoid = F.insert_feature(conn, "layer", Surface(surface.vertices, surface.cells, vertex_properties=props))
    tgsis.create_version(conn, "e1")
    conn.commit()
    conn.execute("SELECT tgsis.store_class_in_chunks('layer')")
    conn.commit()
    with tgsis.in_version(conn, "e1"):
        conn.execute("UPDATE public.layer_cellpros SET porosity = 1.0 WHERE _geoid = %s AND _idx = 3", (geoid,))
    conn.execute("UPDATE public.layer_cellpros SET porosity = 2.0 WHERE _geoid = %s AND _idx = 3", (geoid,))
    conn.commit()
    try:
        tgsis.merge_version(conn, "e1")
        raise AssertionError("the same vertex changed on both sides merged without a conflict")
    except tgsis.UnsolvedConflictsError:
        conn.rollback()
    tgsis.resolve_conflict(conn, "e1", "feature", geoid, "child")
    conn.commit()
    tgsis.add_property(conn, "layer", ("grade", "smallint"), default="9")
    conn.commit()
    tgsis.merge_version(conn, "e1")  # still solved: the change altered no value a version sees
    conn.commit()
    row = conn.execute("SELECT porosity, grade FROM public.layer_cellpros WHERE _geoid = %s AND _idx = 3", (geoid,))
    assert row.fetchone() == (1.0, 9)


def test_pg_dump_and_restore_after_changes_in_place(pg: Any, db_dsn: str, conn: Conn, tmp_path: Any) -> None:
    from tests.test_backup import _bindir_of, _restored

    surface = curved_surface()
    values = _values(surface.n_vertices)
    values["p_f8"][2] = float(
        "nan"
    )  # (a NaN payload does not survive pg_dump's text COPY of a double array, as before)
    _class(conn, "kept")
    geoid = F.insert_feature(conn, "kept", Surface(surface.vertices, surface.cells, vertex_properties=values))
    conn.execute("SELECT tgsis.store_class_in_chunks('kept')")
    conn.commit()
    tgsis.add_property(conn, "kept", ("p_new", "smallint"), default="4")
    tgsis.drop_property(conn, "kept", "p_i4", force=True)  # a dropped column left in the chunk table
    tgsis.rename_property(conn, "kept", "p_f8", "p_d")
    conn.commit()
    arrays = _arrays(conn, "kept")
    conn.rollback()
    with _restored(pg, _bindir_of(pg), db_dsn, "custom", tmp_path) as dsn, psycopg.connect(dsn) as copy:
        assert list(_arrays(copy, "kept").values()) == list(arrays.values())
        copy.execute("UPDATE public.kept_cellpros SET p_new = 5 WHERE _geoid = %s AND _idx = 1", (geoid,))
        copy.commit()
        assert copy.execute("SELECT p_new FROM public.kept_cellpros WHERE _idx IN (0, 1) ORDER BY _idx").fetchall() == [
            (4,),
            (5,),
        ]
