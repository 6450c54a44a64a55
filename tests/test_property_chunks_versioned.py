"""A versioned feature class's property table in chunks (issue 40, plan F area P).

docs/storage.md, "Property chunks: the contract", "Versioning": ``tgsis.store_class_in_chunks`` switches a
versioned class with its history, and ``tgsis.enable_feature_versioning`` versions a class whose properties
are in chunks; the chunk table is then the class table's versioned storage (``tgsis.storage_table``,
``tgsis.storage_key``), guarded as ``<table>_ver`` was, and every versioned path (the face's reads at a
version and its writes, check-in by difference, merges, conflicts, compress) acts on chunk versions.
The tests compare each view (every version's working set and every revision) bit for bit against the
same operations on a class whose properties stay rows, in the same database. The property tables are
rows or chunks whatever model 1's storage is, so the file runs unmarked.
"""

from __future__ import annotations

import struct
from typing import Any

import numpy as np
import psycopg
import pytest
from psycopg import sql

import tgsis
from tests.merge_data import every_view, sqlstate, varied_history
from tests.storage_data import classes_as_rows
from tgsis.db import features as F
from tgsis.mesh import Surface

Conn = psycopg.Connection[Any]


@pytest.fixture(autouse=True)
def _classes_as_rows(db_dsn: str) -> None:
    """The classes these tests make start as rows: they switch them to chunks themselves, or compare with a rows
    twin (docs/storage.md, "Property chunks by default: the rule")."""
    classes_as_rows(db_dsn)


FAULTS = "public.faults_cellpros"


def _look(conn: Conn, version: str, revision: int | None) -> None:
    if revision is None:
        conn.execute("SELECT tgsis.goto_version(%s, true)", (version,))
    else:
        conn.execute("SELECT tgsis.goto_revision(%s, %s, true)", (version, revision))


def _faults_rows(conn: Conn) -> list[tuple[Any, ...]]:
    return [
        tuple(r)
        for r in conn.execute(
            "SELECT _geoid, _idx, float8send(porosity) FROM public.faults_cellpros ORDER BY 1, 2"
        ).fetchall()
    ]


def _every_view_rows(conn: Conn) -> dict[tuple[str, int | None], list[tuple[Any, ...]]]:
    seen = {}
    for version, revision in every_view(conn):
        _look(conn, version, revision)
        seen[(version, revision)] = _faults_rows(conn)
    conn.execute("SELECT tgsis.goto_version('DEFAULT', true)")
    return seen


def test_a_versioned_class_switches_with_its_history(conn: Conn, fault_clone: int) -> None:
    varied_history(conn, fault_clone)
    before = _every_view_rows(conn)
    assert len(before) >= 10 and len({tuple(v) for v in before.values()}) > 3  # views that differ
    written = conn.execute("SELECT tgsis.store_class_in_chunks('faults')").fetchone()
    conn.commit()
    assert written is not None and written[0] > 1
    assert conn.execute("SELECT tgsis.storage_table('public', 'faults_cellpros')").fetchone() == (
        "public.faults_cellpros_chunk",
    )
    assert _every_view_rows(conn) == before


#: what versioning made of a class table, read from the catalogs: the view (definition, defaults, comments,
#: grants, triggers), its <table>_ver (columns, constraints, indexes, comments, grants, triggers), the queue,
#: the write function and runner, and the registration
CATALOG = """
WITH r(rel) AS (VALUES (to_regclass(%(t)s::text)), (to_regclass(%(t)s::text || '_ver')), (to_regclass(%(t)s::text || '_ver_queue')))
SELECT 'rel', c.relname, c.relkind::text, c.relacl::text, obj_description(c.oid, 'pg_class'),
       pg_get_userbyid(c.relowner)::text, c.relrowsecurity::text
  FROM r JOIN pg_class c ON c.oid = r.rel
UNION ALL
SELECT 'view', pg_get_viewdef(%(t)s::text::regclass), NULL, NULL, NULL, NULL, NULL
UNION ALL
SELECT 'col', c.relname || '.' || a.attname, format_type(a.atttypid, a.atttypmod), a.attnotnull::text,
       col_description(c.oid, a.attnum), pg_get_expr(d.adbin, d.adrelid), a.attgenerated::text || a.attidentity::text
  FROM r JOIN pg_class c ON c.oid = r.rel JOIN pg_attribute a ON a.attrelid = c.oid AND a.attnum > 0 AND NOT a.attisdropped
  LEFT JOIN pg_attrdef d ON d.adrelid = c.oid AND d.adnum = a.attnum
UNION ALL
SELECT 'con', c.relname || '.' || con.conname, pg_get_constraintdef(con.oid), NULL, NULL, NULL, NULL
  FROM r JOIN pg_class c ON c.oid = r.rel JOIN pg_constraint con ON con.conrelid = c.oid
UNION ALL
SELECT 'idx', c.relname, pg_get_indexdef(i.indexrelid), NULL, NULL, NULL, NULL
  FROM r JOIN pg_class c ON c.oid = r.rel JOIN pg_index i ON i.indrelid = c.oid
UNION ALL
SELECT 'trg', c.relname || '.' || t.tgname, pg_get_triggerdef(t.oid), t.tgenabled::text, NULL, NULL, NULL
  FROM r JOIN pg_class c ON c.oid = r.rel JOIN pg_trigger t ON t.tgrelid = c.oid AND NOT t.tgisinternal
UNION ALL
SELECT 'fn', p.oid::regprocedure::text, md5(p.prosrc), p.proacl::text, obj_description(p.oid, 'pg_proc'),
       p.prosecdef::text, array_to_string(p.proconfig, ',')
  FROM pg_proc p WHERE p.pronamespace = 'public'::regnamespace AND p.proname LIKE split_part(%(t)s::text, '.', 2) || '_ver_%%'
UNION ALL
SELECT 'reg', to_jsonb(t)::text, NULL, NULL, NULL, NULL, NULL
  FROM tgsis.versioned_tables t WHERE format('%%I.%%I', t.schemaname, t.tablename) = %(t)s::text
ORDER BY 1, 2, 3
"""


def _catalog(conn: Conn, table: str) -> list[tuple[Any, ...]]:
    return [tuple(r) for r in conn.execute(CATALOG, {"t": table}).fetchall()]


def test_a_versioned_class_goes_back_to_rows_with_its_history(conn: Conn, fault_clone: int) -> None:
    """rows -> chunks -> rows: every version's and revision's rows bit for bit as before, and what versioning
    made of the table (view, <table>_ver, queue, write function, runner, grants, comments, registration) as
    enable_feature_versioning made it; then chunks again give the same chunk versions."""
    varied_history(conn, fault_clone)
    conn.execute("GRANT SELECT, INSERT, UPDATE, DELETE ON public.faults_cellpros TO tgsis_editor")
    conn.execute("GRANT SELECT ON public.faults_cellpros TO tgsis_reader WITH GRANT OPTION")
    conn.commit()
    before = _every_view_rows(conn)
    catalog = _catalog(conn, FAULTS)
    assert len(before) >= 10 and len({tuple(v) for v in before.values()}) > 3
    assert any(r[0] == "fn" and r[1].startswith("faults_cellpros_ver_run") for r in catalog)
    written = conn.execute("SELECT tgsis.store_class_in_chunks('faults')").fetchone()
    conn.commit()
    assert written is not None
    chunks = conn.execute(
        "SELECT _geoid, chunk, revision, lastrevs, holes, array_send(porosity) FROM public.faults_cellpros_chunk "
        "ORDER BY 1, 2, 3"
    ).fetchall()
    back = conn.execute("SELECT tgsis.store_class_in_rows('faults')").fetchone()
    conn.commit()
    assert back is not None and back[0] > 0
    assert conn.execute("SELECT tgsis.storage_table('public', 'faults_cellpros')").fetchone() == (
        "public.faults_cellpros_ver",
    )
    for gone in ("_chunk", "_chunk_rows", "_shape", "_face"):
        assert conn.execute("SELECT to_regclass(%s)", (FAULTS + gone,)).fetchone() == (None,)
    # <table>_ver's grants are made from the view's, as enable_versioning makes them from the table's: the roles'
    # SELECT and INSERT (guarded by the storage's triggers), not the grants <table>_ver had before the switch
    after = _catalog(conn, FAULTS)
    acl = [r for r in after if r[:2] == ("rel", "faults_cellpros_ver")]
    assert acl[0][3].split(",")[1:] == ["tgsis_reader=r*/postgres", "tgsis_editor=ar/postgres}"]  # (after the owner's)
    assert [r for r in after if r not in acl] == [r for r in catalog if r[:2] != ("rel", "faults_cellpros_ver")]
    assert [r[:3] + r[4:] for r in acl] == [r[:3] + r[4:] for r in catalog if r[:2] == ("rel", "faults_cellpros_ver")]
    assert _every_view_rows(conn) == before
    # and into chunks again: the same chunk versions, every view the same
    assert conn.execute("SELECT tgsis.store_class_in_chunks('faults')").fetchone() == written
    conn.commit()
    assert (
        conn.execute(
            "SELECT _geoid, chunk, revision, lastrevs, holes, array_send(porosity) FROM public.faults_cellpros_chunk "
            "ORDER BY 1, 2, 3"
        ).fetchall()
        == chunks
    )
    assert _every_view_rows(conn) == before


def test_back_to_rows_a_versioned_class_keeps_working_and_solved_conflicts_solved(conn: Conn) -> None:
    """After the way back the class is versioned on rows: writes in a version, a conflict solved while in chunks
    stays solved (the merge takes the child's side), compress and disable work."""
    geoid, _ = _versioned_layer(conn)
    with tgsis.in_version(conn, "e1"):
        conn.execute("UPDATE public.layer_cellpros SET porosity = 1.0 WHERE _geoid = %s AND _idx = 300", (geoid,))
        conn.commit()
    conn.execute("UPDATE public.layer_cellpros SET porosity = 2.0 WHERE _geoid = %s AND _idx = 300", (geoid,))
    conn.commit()
    with pytest.raises(tgsis.UnsolvedConflictsError):
        tgsis.merge_version(conn, "e1")
    conn.rollback()
    tgsis.resolve_conflict(conn, "e1", "feature", geoid, "child")
    conn.commit()
    assert conn.execute("SELECT tgsis.store_class_in_rows('layer')").fetchone() is not None
    conn.commit()
    tgsis.merge_version(conn, "e1")  # solved while in chunks: still solved
    conn.commit()
    assert [r[2] for r in _layer(conn, "_idx = 300")] == [struct.pack(">d", 1.0)]
    with tgsis.in_version(conn, "e1"):
        conn.execute("UPDATE public.layer_cellpros SET facies = 33 WHERE _geoid = %s AND _idx = 5", (geoid,))
        conn.commit()
        assert [r[3] for r in _layer(conn, "_idx = 5")] == [33]
    assert [r[3] for r in _layer(conn, "_idx = 5")] == [5 % 7 - 3]
    assert conn.execute("SELECT count(*) FROM public.layer_cellpros_ver WHERE revision <> 0").fetchone() != (0,)
    tgsis.merge_version(conn, "e1")
    tgsis.compress_versions(conn)
    conn.commit()
    assert [r[3] for r in _layer(conn, "_idx = 5")] == [33]
    final = _layer(conn)
    tgsis.disable_feature_versioning(conn, force=True)
    conn.commit()
    assert _layer(conn) == final


# --------------------------------------------------------------------------- the same operations on rows and on chunks

#: float8 bit patterns that must survive: -0.0, the smallest subnormal, a NaN with a payload, 1 + 1 ulp
PATTERNS = [0x8000000000000000, 0x0000000000000001, 0x7FF8000000000ABC, 0x3FF0000000000001]
TWINS = ("onrows", "inchunks")


def _double(bits: int) -> float:
    value: float = struct.unpack(">d", struct.pack(">Q", bits))[0]
    return value


def _twin_rows(conn: Conn, name: str) -> list[tuple[Any, ...]]:
    """The class's property rows as a psql user reads them, the feature named by its order (geoids differ)."""
    query = sql.SQL(
        "SELECT dense_rank() OVER (ORDER BY _geoid), _idx, float8send(porosity), facies FROM public.{} ORDER BY 1, 2"
    ).format(sql.Identifier(f"{name}_cellpros"))
    return [tuple(r) for r in conn.execute(query).fetchall()]


def _twin_views(conn: Conn) -> dict[str, dict[tuple[str, int | None], list[tuple[Any, ...]]]]:
    seen: dict[str, dict[tuple[str, int | None], list[tuple[Any, ...]]]] = {name: {} for name in TWINS}
    for version, revision in every_view(conn):
        _look(conn, version, revision)
        for name in TWINS:
            seen[name][(version, revision)] = _twin_rows(conn, name)
    conn.execute("SELECT tgsis.goto_version('DEFAULT', true)")
    conn.commit()
    return seen


def _surface(nan_payload: bool = True) -> Surface:
    """A curved surface with a double and an integer vertex property; the first doubles PATTERNS' bits (without
    ``nan_payload`` the NaN is the canonical one: pg_dump writes floats as text, which keeps no NaN payload)."""
    from tests.merge_data import curved_surface

    surface = curved_surface(40)  # 1,600 vertices: two chunks
    porosity = surface.vertex_properties["porosity"].copy()
    porosity[:4] = [_double(p if nan_payload or p != 0x7FF8000000000ABC else 0x7FF8000000000000) for p in PATTERNS]
    return Surface(
        surface.vertices,
        surface.cells,
        vertex_properties={"porosity": porosity, "facies": (np.arange(surface.n_vertices, dtype=np.int32) % 7) - 3},
    )


def _each(conn: Conn, version: str, statement: str, geoids: dict[str, int], params: tuple[Any, ...] = ()) -> None:
    """One psql statement on each twin's property table in ``version`` (``{table}``, ``%(g)s`` its feature)."""
    with tgsis.in_version(conn, version):
        for name in TWINS:
            conn.execute(
                sql.SQL(statement).format(table=sql.Identifier("public", f"{name}_cellpros")),
                {"g": geoids[name], "p": list(params)},
            )
        conn.commit()


def _edited(conn: Conn, name: str, geoid: int, change: dict[int, float], drop_last: int = 0) -> Surface:
    state = F.fetch_feature(conn, name, geoid).mesh
    assert isinstance(state, Surface)
    porosity = state.vertex_properties["porosity"].copy()
    for i, value in change.items():
        porosity[i] = value
    keep = np.arange(state.n_vertices - drop_last)
    inside = np.all(state.cells < len(keep), axis=1)
    return Surface(
        state.vertices[keep],
        state.cells[inside],
        vertex_properties={"porosity": porosity[keep], "facies": state.vertex_properties["facies"][keep]},
    )


@pytest.mark.parametrize("switch", ["before_versioning", "while_versioned"])
def test_every_view_equals_the_same_operations_on_rows(conn: Conn, switch: str) -> None:
    """Face writes in versions, a check-in by difference, merges of both sides' property edits (by region, and a
    conflict solved), compress: every version's and revision's rows equal, bit for bit, those of the twin class
    whose properties stay rows."""
    for name in TWINS:
        tgsis.create_feature_class(
            conn, name, "SURFACE", cell_properties=[("porosity", "double precision"), ("facies", "integer")]
        )
    if switch == "before_versioning":
        conn.execute("SELECT tgsis.store_class_in_chunks('inchunks')")
    tgsis.enable_feature_versioning(conn)
    conn.commit()
    mesh = _surface()
    geoids = {name: F.insert_feature(conn, name, mesh) for name in TWINS}
    tgsis.create_version(conn, "e1")
    conn.commit()
    # e1: psql writes through the face (one value, a bulk update, a delete, an insert)
    _each(conn, "e1", "UPDATE {table} SET porosity = '-0' WHERE _geoid = %(g)s AND _idx = 7", geoids)
    _each(conn, "e1", "UPDATE {table} SET facies = facies + 1 WHERE _geoid = %(g)s AND _idx < 40", geoids)
    _each(conn, "e1", "DELETE FROM {table} WHERE _geoid = %(g)s AND _idx = 100", geoids)
    _each(conn, "e1", "INSERT INTO {table} VALUES (%(g)s, 100, 'NaN', 5)", geoids)
    if switch == "while_versioned":
        assert conn.execute("SELECT tgsis.store_class_in_chunks('inchunks')").fetchone() is not None
        conn.commit()
    tgsis.goto_version(conn, "e1")
    tgsis.save_revision(conn, "e1 first")
    conn.commit()
    tgsis.create_version(conn, "e2", "e1")
    conn.commit()
    # e2: a check-in by difference changing values and deleting the grid's last row
    with tgsis.in_version(conn, "e2"):
        for name in TWINS:
            tgsis.save_feature(conn, name, geoids[name], _edited(conn, name, geoids[name], {200: 1.25, 1500: -3.5}, 40))
        conn.commit()
    # DEFAULT changes properties of the object too: a merge of e1 meets both sides' edits
    _each(conn, "DEFAULT", "UPDATE {table} SET porosity = 42.0 WHERE _geoid = %(g)s AND _idx = 800", geoids)
    tgsis.merge_version(conn, "e2")  # into e1 (only e2 changed since: no conflict)
    conn.commit()
    _each(conn, "e1", "UPDATE {table} SET facies = -9 WHERE _geoid = %(g)s AND _idx = 1201", geoids)
    result = tgsis.merge_version(conn, "e1")  # into DEFAULT: both changed the object, in other regions
    conn.commit()
    assert result is not None
    # the same vertex on both sides: a conflict solved by the child's side
    _each(conn, "e1", "UPDATE {table} SET porosity = 1.0 WHERE _geoid = %(g)s AND _idx = 300", geoids)
    _each(conn, "DEFAULT", "UPDATE {table} SET porosity = 2.0 WHERE _geoid = %(g)s AND _idx = 300", geoids)
    with pytest.raises(tgsis.UnsolvedConflictsError):
        tgsis.merge_version(conn, "e1")
    conn.rollback()
    for name in TWINS:
        tgsis.resolve_conflict(conn, "e1", "feature", geoids[name], "child")
    conn.commit()
    tgsis.merge_version(conn, "e1")
    conn.commit()
    views = _twin_views(conn)
    assert len(views["onrows"]) >= 8
    assert views["inchunks"] == views["onrows"]
    # what reports rows reads the decoded chunk versions: the same counts as on rows
    reports = {}
    for name in TWINS:
        table = f"public.{name}_cellpros"
        diff = conn.execute(
            "SELECT added, removed, changed FROM tgsis.diff_table(%s::regclass, 'e2', 'DEFAULT')", (table,)
        ).fetchall()
        at = conn.execute(
            sql.SQL("SELECT count(*), sum(facies) FROM tgsis.rows_at(NULL::{}, 'e2')").format(sql.SQL(table))
        ).fetchone()
        reports[name] = (diff, at)
    conn.rollback()
    assert reports["inchunks"] == reports["onrows"] and reports["onrows"][0] != [], reports
    with tgsis.in_version(conn, "DEFAULT"):
        final = dict((r[1], r[2:]) for r in _twin_rows(conn, "inchunks"))
    assert final[300][0] == struct.pack(">d", 1.0) and final[800][0] == struct.pack(">d", 42.0)
    assert final[1201][1] == -9 and final[100][1] == 5 and final[7][0] == struct.pack(">d", -0.0)
    assert final[2][0] == struct.pack(">Q", PATTERNS[2])  # the NaN payload kept through every path
    # the storage: chunk versions, guarded as <table>_ver was
    assert conn.execute("SELECT tgsis.storage_table('public', 'inchunks_cellpros')").fetchone() == (
        "public.inchunks_cellpros_chunk",
    )
    versions = conn.execute("SELECT count(*), count(DISTINCT chunk) FROM public.inchunks_cellpros_chunk").fetchone()
    assert versions is not None and versions[0] > versions[1]
    # compress keeps what every kept set sees
    tgsis.compress_versions(conn)
    conn.commit()
    kept = _twin_views(conn)
    assert kept["inchunks"] == kept["onrows"]
    assert kept["inchunks"] == {k: v for k, v in views["inchunks"].items() if k in kept["inchunks"]}


# --------------------------------------------------------------------------- refusals, sessions, rights, dump


def _versioned_layer(conn: Conn, nan_payload: bool = True) -> tuple[int, Surface]:
    """Class layer (porosity, facies), versioned, one surface stored, its properties in chunks; version e1."""
    tgsis.create_feature_class(
        conn, "layer", "SURFACE", cell_properties=[("porosity", "double precision"), ("facies", "integer")]
    )
    tgsis.enable_feature_versioning(conn)
    mesh = _surface(nan_payload)
    geoid = F.insert_feature(conn, "layer", mesh)
    tgsis.create_version(conn, "e1")
    conn.commit()
    conn.execute("SELECT tgsis.store_class_in_chunks('layer')")
    conn.commit()
    return geoid, mesh


def _layer(conn: Conn, where: str = "true") -> list[tuple[Any, ...]]:
    query = sql.SQL(
        "SELECT _geoid, _idx, float8send(porosity), facies FROM public.layer_cellpros WHERE {} ORDER BY 1, 2"
    ).format(sql.SQL(where))
    return [tuple(r) for r in conn.execute(query).fetchall()]


def test_what_is_not_built_for_a_versioned_class_is_refused_by_name(conn: Conn) -> None:
    geoid, _ = _versioned_layer(conn)
    before = _layer(conn)
    chunks = conn.execute("SELECT count(*) FROM public.layer_cellpros_chunk").fetchone()
    catalog = _catalog(conn, "public.layer_cellpros")
    assert sqlstate(conn, "SELECT tgsis.store_class_in_chunks('layer')")[0] == "TG201"
    # the way back of a versioned class: a user's view over the face blocks it by name, nothing changed
    conn.execute("CREATE VIEW public.layer_mine AS SELECT * FROM public.layer_cellpros")
    state, message = sqlstate(conn, "SELECT tgsis.store_class_in_rows('layer')")
    assert state == "2BP01" and "layer_mine" in message
    conn.execute("DROP VIEW public.layer_mine")
    # a chunk version the row definition does not allow (a NULL value written past the checks): refused by the
    # row versions' constraint, nothing changed
    conn.execute("ALTER TABLE public.layer_cellpros_chunk DISABLE TRIGGER USER")
    conn.execute("UPDATE public.layer_cellpros_chunk SET porosity[5] = NULL WHERE chunk = 0 AND revision = 0")
    state, message = sqlstate(conn, "SELECT tgsis.store_class_in_rows('layer')")
    assert state == "23502" and "porosity" in message and "layer_cellpros_ver" in message, message
    conn.rollback()
    assert conn.execute("SELECT tgsis.storage_table('public', 'layer_cellpros')").fetchone() == (
        "public.layer_cellpros_chunk",
    )
    assert _catalog(conn, "public.layer_cellpros") == catalog
    assert _layer(conn) == before
    assert conn.execute("SELECT count(*) FROM public.layer_cellpros_chunk").fetchone() == chunks
    assert geoid > 0


def test_two_sessions_writing_one_chunk_in_a_version_keep_both_values(db_dsn: str, conn: Conn) -> None:
    from tests.sessions import Background, connect, wait_until_blocked

    geoid, _ = _versioned_layer(conn)
    first = connect(db_dsn, "first")
    tgsis.goto_version(first, "e1")
    first.execute("UPDATE public.layer_cellpros SET facies = 41 WHERE _geoid = %s AND _idx = 1", (geoid,))

    def second_writer(session: Conn) -> None:
        tgsis.goto_version(session, "e1")
        session.execute("UPDATE public.layer_cellpros SET facies = 42 WHERE _geoid = %s AND _idx = 2", (geoid,))

    second = Background(db_dsn, "second", second_writer)
    wait_until_blocked(conn, second.pid, first.info.backend_pid)  # the chunk's lock
    conn.rollback()
    first.commit()
    first.close()
    second.finish()
    with tgsis.in_version(conn, "e1"):
        assert _layer(conn, "_idx IN (1, 2)") == [
            (geoid, 1, _layer(conn, "_idx = 1")[0][2], 41),
            (geoid, 2, _layer(conn, "_idx = 2")[0][2], 42),
        ]
    # DEFAULT still sees the chunk as it was: e1's writes are chunk versions of e1's revision
    assert [r[3] for r in _layer(conn, "_idx IN (1, 2)")] == [(1 % 7) - 3, (2 % 7) - 3]


def test_a_role_with_fewer_rights_reads_at_a_version_and_cannot_write(db_dsn: str, conn: Conn) -> None:
    from tests.roles import login_roles

    geoid, _ = _versioned_layer(conn)
    with tgsis.in_version(conn, "e1"):
        conn.execute("UPDATE public.layer_cellpros SET facies = 7 WHERE _geoid = %s AND _idx = 3", (geoid,))
        conn.commit()
    with login_roles(db_dsn, {"reader": "tgsis_reader", "editor": "tgsis_editor"}) as roles:
        reader = roles.connect("reader")
        tgsis.goto_version(reader, "e1")
        assert reader.execute(
            "SELECT facies FROM public.layer_cellpros WHERE _geoid = %s AND _idx = 3", (geoid,)
        ).fetchone() == (7,)
        update = "UPDATE public.layer_cellpros SET facies = 5 WHERE _geoid = %s AND _idx = 4"
        assert sqlstate(reader, update, (geoid,))[0] == "42501"
        # the chunk table itself: no UPDATE, DELETE; an INSERT of a chunk version needs the write right
        assert sqlstate(reader, "UPDATE public.layer_cellpros_chunk SET facies[1] = 0")[0] == "42501"
        assert sqlstate(reader, "DELETE FROM public.layer_cellpros_chunk")[0] == "42501"
        state, _ = sqlstate(
            reader,
            "INSERT INTO public.layer_cellpros_chunk (_geoid, chunk, revision, holes, porosity, facies) "
            "VALUES (%s, 99, 0, '{}', '{1.0}', '{1}')",
            (geoid,),
        )
        assert state is not None
        reader.rollback()
        editor = roles.connect("editor")
        tgsis.goto_version(editor, "e1")  # not the editor's version: no write right there
        assert sqlstate(editor, update, (geoid,))[0] == "TG002"
        tgsis.goto_version(editor, "DEFAULT")
        assert sqlstate(editor, update, (geoid,)) == (None, "")
        assert sqlstate(editor, "UPDATE public.layer_cellpros_chunk SET facies[1] = 0")[0] == "42501"
        editor.commit()
    with tgsis.in_version(conn, "e1"):
        assert [r[3] for r in _layer(conn, "_idx IN (3, 4)")] == [7, 1]  # e1 sees its own, not DEFAULT's later write
    assert [r[3] for r in _layer(conn, "_idx IN (3, 4)")] == [0, 5]


def test_back_to_rows_after_compress_and_a_deleted_version_keeps_every_view(conn: Conn) -> None:
    """Compressed chunk versions (revision numbers left as labels) and closed ones of a deleted version go back as
    row versions that every kept set sees as before."""
    geoid, _ = _versioned_layer(conn)
    tgsis.create_version(conn, "e2", "e1")
    conn.commit()
    with tgsis.in_version(conn, "e1"):
        conn.execute("UPDATE public.layer_cellpros SET facies = 70 WHERE _geoid = %s AND _idx = 1500", (geoid,))
        conn.commit()
        tgsis.save_revision(conn, "e1 saved")
        conn.commit()
    with tgsis.in_version(conn, "e2"):
        conn.execute("UPDATE public.layer_cellpros SET porosity = '-0' WHERE _geoid = %s AND _idx = 2", (geoid,))
        conn.execute("DELETE FROM public.layer_cellpros WHERE _geoid = %s AND _idx = 1599", (geoid,))
        conn.commit()
    tgsis.merge_version(conn, "e1")
    conn.commit()
    tgsis.delete_version(conn, "e2")
    tgsis.compress_versions(conn)
    conn.commit()
    views = {}
    for version, revision in every_view(conn):
        _look(conn, version, revision)
        views[(version, revision)] = _layer(conn)
    conn.execute("SELECT tgsis.goto_version('DEFAULT', true)")
    conn.commit()
    assert conn.execute("SELECT tgsis.store_class_in_rows('layer')").fetchone() is not None
    conn.commit()
    for (version, revision), rows in views.items():
        _look(conn, version, revision)
        assert _layer(conn) == rows, (version, revision)
    conn.execute("SELECT tgsis.goto_version('DEFAULT', true)")
    conn.rollback()
    assert [r[3] for r in _layer(conn, "_idx = 1500")] == [70]


def test_a_writer_waiting_on_the_way_back_refuses_it_and_writes_the_chunks(db_dsn: str, conn: Conn) -> None:
    """A psql write in e1 that waits for the way back's locks holds a snapshot older than the switch's commit (the
    statement's, taken before its lock wait; a REPEATABLE READ one would read the new row table empty): the way back
    is refused at its COMMIT (TG202 naming the writer, plan I), the writer writes through the face on the chunks once
    it goes on: its value in e1, nothing lost, DEFAULT unchanged; the way back done after it keeps them."""
    from tests.sessions import Background, connect, wait_until_blocked

    geoid, _ = _versioned_layer(conn)
    switcher = connect(db_dsn, "switcher")
    assert switcher.execute("SELECT tgsis.store_class_in_rows('layer')").fetchone() is not None

    def writer(session: Conn) -> None:
        session.execute("UPDATE public.layer_cellpros SET facies = 44 WHERE _geoid = %s AND _idx = 9", (geoid,))

    second = Background(db_dsn, "writer", writer, version="e1")
    wait_until_blocked(conn, second.pid, switcher.info.backend_pid)
    conn.rollback()
    with pytest.raises(psycopg.Error) as refused:
        switcher.commit()
    assert refused.value.sqlstate == "TG202"
    assert f"pid {second.pid} " in (refused.value.diag.message_detail or "")
    second.finish()
    assert conn.execute("SELECT tgsis.storage_table('public', 'layer_cellpros')").fetchone() == (
        "public.layer_cellpros_chunk",
    )
    conn.rollback()

    def values() -> tuple[list[Any], list[Any]]:
        with tgsis.in_version(conn, "e1"):
            in_e1 = [r[3] for r in _layer(conn, "_idx = 9")]
        in_default = [r[3] for r in _layer(conn, "_idx = 9")]
        conn.rollback()
        return in_e1, in_default

    assert values() == ([44], [9 % 7 - 3])  # on the chunks
    switcher.execute("SELECT tgsis.store_class_in_rows('layer')")  # done: nobody holds an older snapshot now
    switcher.commit()
    switcher.close()
    assert conn.execute("SELECT tgsis.storage_table('public', 'layer_cellpros')").fetchone() == (
        "public.layer_cellpros_ver",
    )
    conn.rollback()
    assert values() == ([44], [9 % 7 - 3])  # on rows


def test_a_role_with_fewer_rights_cannot_go_back_and_keeps_its_rights_after(db_dsn: str, conn: Conn) -> None:
    """Only a tgsis_admin member stores a versioned class as rows again; afterwards the reader reads at a version and
    the editor writes where its version rights let it, as before the switch."""
    from tests.roles import login_roles

    geoid, _ = _versioned_layer(conn)
    # (written by a session that ends: a session that wrote through the face and is still open blocks the way back)
    with psycopg.connect(db_dsn) as writer:
        with tgsis.in_version(writer, "e1"):
            writer.execute("UPDATE public.layer_cellpros SET facies = 7 WHERE _geoid = %s AND _idx = 3", (geoid,))
            writer.commit()
    with login_roles(db_dsn, {"reader": "tgsis_reader", "editor": "tgsis_editor", "admin": "tgsis_admin"}) as roles:
        for short in ("reader", "editor"):
            session = roles.connect(short)
            assert sqlstate(session, "SELECT tgsis.store_class_in_rows('layer')")[0] == "42501"
            session.close()
        assert conn.execute("SELECT tgsis.storage_table('public', 'layer_cellpros')").fetchone() == (
            "public.layer_cellpros_chunk",
        )
        admin = roles.connect("admin")
        assert sqlstate(admin, "SELECT tgsis.store_class_in_rows('layer')") == (None, "")
        admin.commit()
        admin.close()
        assert conn.execute("SELECT tgsis.storage_table('public', 'layer_cellpros')").fetchone() == (
            "public.layer_cellpros_ver",
        )
        reader = roles.connect("reader")
        tgsis.goto_version(reader, "e1")
        assert reader.execute(
            "SELECT facies FROM public.layer_cellpros WHERE _geoid = %s AND _idx = 3", (geoid,)
        ).fetchone() == (7,)
        update = "UPDATE public.layer_cellpros SET facies = 5 WHERE _geoid = %s AND _idx = 4"
        assert sqlstate(reader, update, (geoid,))[0] == "42501"
        assert sqlstate(reader, "UPDATE public.layer_cellpros_ver SET facies = 0")[0] == "42501"
        reader.rollback()
        editor = roles.connect("editor")
        tgsis.goto_version(editor, "e1")  # not the editor's version: no write right there
        assert sqlstate(editor, update, (geoid,))[0] == "TG002"
        tgsis.goto_version(editor, "DEFAULT")
        assert sqlstate(editor, update, (geoid,)) == (None, "")
        assert sqlstate(editor, "DELETE FROM public.layer_cellpros_ver")[0] == "42501"
        editor.commit()
    with tgsis.in_version(conn, "e1"):
        assert [r[3] for r in _layer(conn, "_idx IN (3, 4)")] == [7, 1]
    assert [r[3] for r in _layer(conn, "_idx IN (3, 4)")] == [0, 5]


def test_a_property_added_to_a_versioned_class_in_chunks_keeps_every_view(conn: Conn) -> None:
    """add_property on a versioned class in chunks (refused, TG300, while the class could not go back to rows):
    every version's and revision's values of the other properties bit for bit as before, the new one in every row,
    the class in chunks again."""
    geoid, _ = _versioned_layer(conn)
    with tgsis.in_version(conn, "e1"):
        conn.execute("UPDATE public.layer_cellpros SET facies = 7 WHERE _geoid = %s AND _idx = 3", (geoid,))
        conn.commit()
        tgsis.save_revision(conn, "after e1's edit")
        conn.commit()
    views = {}
    for version, revision in every_view(conn):
        _look(conn, version, revision)
        views[(version, revision)] = _layer(conn)
    conn.execute("SELECT tgsis.goto_version('DEFAULT', true)")
    conn.commit()
    assert len({tuple(v) for v in views.values()}) > 1
    tgsis.add_property(conn, "layer", ("grain", "real"), default="0.5")
    conn.commit()
    assert conn.execute("SELECT tgsis.storage_table('public', 'layer_cellpros')").fetchone() == (
        "public.layer_cellpros_chunk",
    )
    for (version, revision), rows in views.items():
        _look(conn, version, revision)
        assert _layer(conn) == rows, (version, revision)
        assert conn.execute(
            "SELECT count(*), count(*) FILTER (WHERE grain = 0.5) FROM public.layer_cellpros"
        ).fetchone() == (len(rows), len(rows))
    conn.execute("SELECT tgsis.goto_version('DEFAULT', true)")
    conn.rollback()


#: the chunk versions with their arrays' send forms (doubles by their bits)
CHUNK_BITS = (
    "SELECT _geoid, chunk, revision, lastrevs, holes, array_send(porosity), array_send(facies) "
    "FROM public.layer_cellpros_chunk ORDER BY 1, 2, 3"
)


def test_pg_dump_and_restore_keep_a_versioned_class_in_chunks(pg: Any, db_dsn: str, conn: Conn, tmp_path: Any) -> None:
    from tests.test_backup import _bindir_of, _restored

    geoid, _ = _versioned_layer(conn, nan_payload=False)
    with tgsis.in_version(conn, "e1"):
        conn.execute("UPDATE public.layer_cellpros SET facies = 11 WHERE _geoid = %s AND _idx = 1030", (geoid,))
        conn.commit()
    views = {}
    for version, revision in every_view(conn):
        _look(conn, version, revision)
        views[(version, revision)] = _layer(conn)
    conn.execute("SELECT tgsis.goto_version('DEFAULT', true)")
    chunks = conn.execute(CHUNK_BITS).fetchall()
    conn.rollback()
    with _restored(pg, _bindir_of(pg), db_dsn, "custom", tmp_path) as dsn, psycopg.connect(dsn) as copy:
        assert copy.execute(CHUNK_BITS).fetchall() == chunks
        for (version, revision), rows in views.items():
            _look(copy, version, revision)
            assert _layer(copy) == rows, (version, revision)
        # the restored storage is versioned and guarded: a write in e1 writes a chunk version of e1
        copy.execute("SELECT tgsis.goto_version('e1', true)")
        copy.execute("UPDATE public.layer_cellpros SET facies = 12 WHERE _geoid = %s AND _idx = 1031", (geoid,))
        copy.commit()
        copy.execute("SELECT tgsis.goto_version('e1', true)")
        assert [r[3] for r in _layer(copy, "_idx IN (1030, 1031)")] == [11, 12]
        copy.rollback()
        assert [r[3] for r in _layer(copy, "_idx IN (1030, 1031)")] == [1030 % 7 - 3, 1031 % 7 - 3]
        triggers = copy.execute(
            "SELECT count(*) FROM pg_trigger WHERE tgrelid = 'public.layer_cellpros_chunk'::regclass "
            "AND tgname LIKE 'tgsis_storage_%'"
        ).fetchone()
        assert triggers == (3,)


def test_a_feature_deleted_in_a_version_then_versioning_disabled_and_back_to_rows(conn: Conn) -> None:
    geoid, _ = _versioned_layer(conn)
    with tgsis.in_version(conn, "e1"):
        conn.execute("UPDATE public.layer_cellpros SET facies = 70 WHERE _geoid = %s AND _idx = 1500", (geoid,))
        conn.commit()
    tgsis.create_version(conn, "gone")
    conn.commit()
    default = _layer(conn)
    with tgsis.in_version(conn, "gone"):
        assert F.delete_feature(conn, "layer", geoid)
        conn.commit()
        assert _layer(conn) == []
    with tgsis.in_version(conn, "e1"):
        assert [r[3] for r in _layer(conn, "_idx = 1500")] == [70]
    assert _layer(conn) == default  # the deletion closed chunk versions in gone's revision only
    assert conn.execute("SELECT count(*) FROM public.layer_cellpros_chunk WHERE revclosed").fetchone() != (0,)
    # versioning off: DEFAULT's chunk versions stay, as revision 0; the class goes back to rows
    tgsis.disable_feature_versioning(conn, force=True)
    conn.commit()
    assert _layer(conn) == default
    assert conn.execute(
        "SELECT count(*) FILTER (WHERE revision <> 0 OR revclosed), count(*) FROM public.layer_cellpros_chunk"
    ).fetchone() == (0, 2)
    assert conn.execute("SELECT tgsis.store_class_in_rows('layer')").fetchone() == (len(default),)
    conn.commit()
    assert _layer(conn) == default


def test_a_check_in_is_refused_when_a_property_changed_since_the_check_out(conn: Conn) -> None:
    """The check-out's fingerprint covers the property chunks the version sees: a value changed through the face
    after the check-out (one chunk version, one slot) refuses the check-in; a check-in from a fresh check-out
    writes the property in the version only."""
    geoid, mesh = _versioned_layer(conn)
    tgsis.goto_version(conn, "e1")
    conn.commit()
    co = tgsis.checkout(conn, geoid)
    conn.commit()
    edited = co.mesh
    assert isinstance(edited, Surface)
    porosity = edited.vertex_properties["porosity"].copy()
    porosity[1100] = -0.0
    changed = Surface(
        edited.vertices, edited.cells, vertex_properties={**edited.vertex_properties, "porosity": porosity}
    )
    conn.execute("UPDATE public.layer_cellpros SET facies = 3 WHERE _geoid = %s AND _idx = 1500", (geoid,))
    conn.commit()
    with pytest.raises(tgsis.CheckoutConflictError):
        tgsis.checkin(conn, co, changed)
    conn.rollback()
    co = tgsis.checkout(conn, geoid)
    conn.commit()
    assert isinstance(co.mesh, Surface)
    porosity = co.mesh.vertex_properties["porosity"].copy()
    porosity[1100] = -0.0
    tgsis.checkin(
        conn,
        co,
        Surface(co.mesh.vertices, co.mesh.cells, vertex_properties={**co.mesh.vertex_properties, "porosity": porosity}),
    )
    conn.commit()
    assert _layer(conn, "_idx = 1100")[0][2] == struct.pack(">d", -0.0)
    tgsis.goto_version(conn, "DEFAULT")
    conn.commit()
    assert _layer(conn, "_idx = 1100")[0][2] == struct.pack(">d", float(mesh.vertex_properties["porosity"][1100]))


def test_tables_named_like_the_markers_beside_a_class_on_rows_change_nothing(conn: Conn) -> None:
    """Whoever may create tables in a class's schema could make <table>_shape and <table>_chunk beside its
    versioned view: the storage is still <table>_ver (the face's trigger is the marker, not the names)."""
    tgsis.create_feature_class(conn, "layer", "SURFACE", cell_properties=[("porosity", "double precision")])
    tgsis.enable_feature_versioning(conn)
    conn.execute("CREATE TABLE public.layer_cellpros_shape (a int)")
    conn.execute("CREATE TABLE public.layer_cellpros_chunk (a int)")
    assert conn.execute(
        "SELECT tgsis.storage_table('public', 'layer_cellpros'), tgsis.stored_in_chunks('public', 'layer_cellpros')"
    ).fetchone() == ("public.layer_cellpros_ver", False)
    conn.rollback()


def test_the_sql_merge_by_region_writes_property_chunks_as_rows(conn: Conn) -> None:
    """psql's merge by region (tgsis.merge_mesh_by_region, then tgsis.merge_version): both sides' property edits
    of one feature read from the chunk versions (merge_property_rows) and written into the version through the
    face; every view equals the twin class on rows."""
    for name in TWINS:
        tgsis.create_feature_class(
            conn, name, "SURFACE", cell_properties=[("porosity", "double precision"), ("facies", "integer")]
        )
    tgsis.enable_feature_versioning(conn)
    geoids = {name: F.insert_feature(conn, name, _surface()) for name in TWINS}
    tgsis.create_version(conn, "e1")
    conn.commit()
    conn.execute("SELECT tgsis.store_class_in_chunks('inchunks')")
    conn.commit()
    _each(conn, "e1", "UPDATE {table} SET porosity = '-0' WHERE _geoid = %(g)s AND _idx IN (10, 1100)", geoids)
    _each(conn, "DEFAULT", "UPDATE {table} SET facies = 77 WHERE _geoid = %(g)s AND _idx = 1300", geoids)
    conn.execute("SELECT FROM tgsis.find_conflicts('e1')")
    conn.commit()
    written = {}
    for name in TWINS:
        conn.execute("SET TRANSACTION ISOLATION LEVEL READ COMMITTED")
        row = conn.execute("SELECT tgsis.merge_mesh_by_region('e1', 'merge', %s)", (geoids[name],)).fetchone()
        conn.commit()
        assert row is not None and row[0] is not None, name
        written[name] = row[0]
    assert written["inchunks"] > 0
    conn.execute("SELECT tgsis.merge_version('e1')")
    conn.commit()
    views = _twin_views(conn)
    assert views["inchunks"] == views["onrows"]
    final = {r[1]: r[2:] for r in _twin_rows(conn, "inchunks")}
    assert final[10][0] == final[1100][0] == struct.pack(">d", -0.0) and final[1300][1] == 77


def test_the_sql_merge_by_region_writes_each_touched_property_chunk_once(conn: Conn) -> None:
    """psql's merge by region brings 300 property rows of the parent into the version in one bulk write
    (tgsis.write_property_rows: each touched chunk written once), not one chunk rewrite per row through the
    face: the chunk table's tuple writes in the merge's transaction are a few, not hundreds; every view still
    equals the twin class on rows."""
    for name in TWINS:
        tgsis.create_feature_class(
            conn, name, "SURFACE", cell_properties=[("porosity", "double precision"), ("facies", "integer")]
        )
    tgsis.enable_feature_versioning(conn)
    geoids = {name: F.insert_feature(conn, name, _surface()) for name in TWINS}
    tgsis.create_version(conn, "e1")
    conn.commit()
    conn.execute("SELECT tgsis.store_class_in_chunks('inchunks')")
    conn.commit()
    _each(conn, "e1", "UPDATE {table} SET porosity = 0.5 WHERE _geoid = %(g)s AND _idx = 1500", geoids)
    _each(conn, "DEFAULT", "UPDATE {table} SET facies = 7 WHERE _geoid = %(g)s AND _idx < 300", geoids)
    conn.execute("SELECT FROM tgsis.find_conflicts('e1')")
    conn.commit()
    written = {}
    for name in TWINS:
        conn.execute("SET TRANSACTION ISOLATION LEVEL READ COMMITTED")
        before = conn.execute(
            "SELECT coalesce(sum(n_tup_ins + n_tup_upd), 0) FROM pg_stat_xact_user_tables WHERE relname = %s",
            (f"{name}_cellpros_chunk",),
        ).fetchone()
        row = conn.execute("SELECT tgsis.merge_mesh_by_region('e1', 'merge', %s)", (geoids[name],)).fetchone()
        after = conn.execute(
            "SELECT coalesce(sum(n_tup_ins + n_tup_upd), 0) FROM pg_stat_xact_user_tables WHERE relname = %s",
            (f"{name}_cellpros_chunk",),
        ).fetchone()
        conn.commit()
        assert row is not None and row[0] is not None and before is not None and after is not None, name
        written[name] = (row[0], after[0] - before[0])
    # the rows written counted alike (300 closed, 300 written); through the face each of them was a chunk write
    assert written["inchunks"][0] == written["onrows"][0] >= 600
    assert 0 < written["inchunks"][1] <= 4, written
    views = _twin_views(conn)
    assert views["inchunks"] == views["onrows"]
    _look(conn, "e1", None)
    final = {r[1]: r[2:] for r in _twin_rows(conn, "inchunks")}  # the version: both sides' edits
    conn.execute("SELECT tgsis.goto_version('DEFAULT', true)")
    assert all(final[i][1] == 7 for i in range(300)) and final[1500][0] == struct.pack(">d", 0.5)


@pytest.mark.parametrize("storage", ["rows", "chunks"])
@pytest.mark.parametrize("writer_first", [True, False])
@pytest.mark.parametrize("row", [5, 1000])
def test_a_property_writer_in_the_version_during_psqls_merge_by_region_loses_nothing(
    db_dsn: str, conn: Conn, writer_first: bool, storage: str, row: int
) -> None:
    """Two sessions at once: a psql user writes a property value in the version through the face while psql's
    merge (tgsis.merge_version: the merge by region in SQL, tgsis.write_property_rows into the version, then the
    version into DEFAULT) brings the parent's edits of rows 0 to 299 (one chunk with row 1000). Whichever holds
    the version first, the other waits for it, then goes on or is refused by name; nothing is lost silently,
    and chunks end as rows do."""
    from tests.sessions import Background, connect, wait_until_blocked

    tgsis.create_feature_class(
        conn, "inchunks", "SURFACE", cell_properties=[("porosity", "double precision"), ("facies", "integer")]
    )
    tgsis.enable_feature_versioning(conn)
    geoid = F.insert_feature(conn, "inchunks", _surface())
    tgsis.create_version(conn, "e1")
    conn.commit()
    if storage == "chunks":
        conn.execute("SELECT tgsis.store_class_in_chunks('inchunks')")
        conn.commit()
    with tgsis.in_version(conn, "e1"):
        conn.execute("UPDATE public.inchunks_cellpros SET porosity = 0.5 WHERE _geoid = %s AND _idx = 1500", (geoid,))
    with tgsis.in_version(conn, "DEFAULT"):
        conn.execute("UPDATE public.inchunks_cellpros SET facies = 7 WHERE _geoid = %s AND _idx < 300", (geoid,))
    write = f"UPDATE public.inchunks_cellpros SET porosity = 0.25 WHERE _geoid = %s AND _idx = {row}"
    merge = "SELECT tgsis.merge_version('e1')"
    refused: dict[str, str] = {}
    if writer_first:
        writer = connect(db_dsn, "writer")
        tgsis.goto_version(writer, "e1")
        writer.execute(write, (geoid,))  # not committed
        merger = Background(db_dsn, "merger", lambda c: c.execute(merge))
        wait_until_blocked(conn, merger.pid, writer.info.backend_pid)
        writer.commit()
        writer.close()
        try:
            merger.finish()
        except psycopg.Error as exc:
            refused["merge"] = exc.sqlstate or ""
    else:
        merger_conn = connect(db_dsn, "merger")
        merger_conn.execute(merge)  # not committed
        writer_bg = Background(db_dsn, "writer", lambda c: c.execute(write, (geoid,)), version="e1")
        wait_until_blocked(conn, writer_bg.pid, merger_conn.info.backend_pid)
        merger_conn.commit()
        merger_conn.close()
        try:
            writer_bg.finish()
        except psycopg.Error as exc:
            refused["write"] = exc.sqlstate or ""
    _look(conn, "e1", None)
    child = {r[1]: r[2:] for r in _twin_rows(conn, "inchunks")}
    conn.execute("SELECT tgsis.goto_version('DEFAULT', true)")
    parent = {r[1]: r[2:] for r in _twin_rows(conn, "inchunks")}
    conn.commit()
    original = _surface_porosity_bits(row)
    quarter, half = struct.pack(">d", 0.25), struct.pack(">d", 0.5)
    merged = "merge" not in refused
    written = "write" not in refused
    assert child[row][0] == (quarter if written else original)
    assert child[1500][0] == half
    assert parent[1500][0] == (half if merged else _surface_porosity_bits(1500))
    assert all(parent[i][1] == 7 for i in range(300))
    assert all(child[i][1] == (7 if merged else (i % 7) - 3) for i in range(300))
    if writer_first and merged:
        assert parent[row][0] == quarter  # the merge saw the write it waited for
    if not writer_first:
        assert parent[row][0] == original  # the write came after the merge
    # row 5, which both sides changed: the merge after the write refuses the conflict by name (TG302); the write
    # after the merge would undo what it read changed (40001: retry), as on rows
    expected_refusal = {(5, True): {"merge": "TG302"}, (5, False): {"write": "40001"}}
    assert refused == expected_refusal.get((row, writer_first), {}), (storage, refused)


def _surface_porosity_bits(idx: int) -> bytes:
    return struct.pack(">d", float(_surface().vertex_properties["porosity"][idx]))
