"""Adding and renaming a vector property of a class stored in chunks (issue 40, plan L area C).

docs/storage.md, "Vector properties in chunks": ``tgsis.add_property`` / ``tgsis.rename_property`` of a
vector property on a class whose properties are in chunks alter the chunk table in place
(``tgsis.alter_chunk_table``), as for a scalar: a new 2-D array (slots x k) in every chunk version, the
default's k values at every present slot and k NULLs at every hole (NULL vectors everywhere without a
default), or the array renamed. ``tgsis.chunk_columns`` knows the vector by its own CHECK on the row
definition until the caller writes the catalog. These tests compare the chunks with those of a twin class
changed the same way in rows and converted after (the server's encoding), bit for bit; a dump and restore
of the result; and another session writing the face meanwhile. The property tables are chunks whatever
model 1's storage is, so the file runs unmarked.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import psycopg
import pytest
from psycopg import sql

import tgsis
from tests.merge_data import sqlstate
from tests.storage_data import classes_as_rows
from tests.test_vector_property_chunks import _insert_mesh, _vec
from tgsis.testing import TestServer

Conn = psycopg.Connection[Any]


@pytest.fixture(autouse=True)
def _classes_as_rows(db_dsn: str) -> None:
    """The classes these tests make start as rows: they switch them to chunks themselves, or compare with a rows
    twin (docs/storage.md, "Property chunks by default: the rule")."""
    classes_as_rows(db_dsn)


ADD_DIR = """SELECT tgsis.add_property('{c}', 'cell', '{{"name": "dir", "type": "real", "size": 2}}', '-0')"""
ADD_NUL = """SELECT tgsis.add_property('{c}', 'cell', '{{"name": "nul", "type": "double precision", "size": 3}}')"""
RENAME = "SELECT tgsis.rename_property('{c}', 'pair', 'couple')"
COLUMNS = ["_geoid", "chunk", "revision", "lastrevs", "holes", "normal", "t", "couple", "rgb", "dir", "nul"]


def _chunks(conn: Conn, name: str) -> list[tuple[Any, ...]]:
    """Every chunk version of the class, its columns named in COLUMNS in send form (arrays bit for bit)."""
    parts = [
        sql.SQL("array_send(c.{})" if n not in ("_geoid", "chunk", "revision") else "c.{}").format(sql.Identifier(n))
        for n in COLUMNS
    ]
    query = sql.SQL("SELECT {} FROM {} c ORDER BY c._geoid, c.chunk, c.revision").format(
        sql.SQL(", ").join(parts), sql.Identifier("public", f"{name}_cellpros_chunk")
    )
    return [tuple(bytes(v) if isinstance(v, memoryview) else v for v in r) for r in conn.execute(query).fetchall()]


def _face(conn: Conn, name: str) -> list[tuple[Any, ...]]:
    query = (
        "SELECT _geoid, _idx, array_send(normal), float4send(t), array_send(couple), array_send(rgb), "
        f"array_send(dir), array_send(nul) FROM public.{name}_cellpros ORDER BY 1, 2"
    )
    return [tuple(bytes(v) if isinstance(v, memoryview) else v for v in r) for r in conn.execute(query).fetchall()]


def _changed(conn: Conn, name: str) -> None:
    for statement in (ADD_DIR, ADD_NUL, RENAME):
        conn.execute(statement.format(c=name))


def test_add_and_rename_in_chunks_write_what_the_conversion_of_rows_writes(conn: Conn) -> None:
    """A collection class with holes, NULL vectors and odd bits in chunks, and its twin in rows: the same adds
    (a vector with a default, one without: NULL vectors) and rename on both, the twin converted after; every
    chunk array compared in send form, the faces' rows too, then a write of the new vectors through the face.
    Fails while the add or rename is refused, or when the new arrays differ in any bit from the server's
    encoding (dimensions, NULL rows at holes, the default's -0)."""
    _vec(conn, "vec")
    _vec(conn, "twin")
    conn.execute("SELECT tgsis.store_class_in_chunks('vec')")
    conn.commit()
    _changed(conn, "vec")
    _changed(conn, "twin")
    conn.commit()
    conn.execute("SELECT tgsis.store_class_in_chunks('twin')")
    conn.commit()
    roles = conn.execute(
        "SELECT name, role, size FROM tgsis.chunk_columns('public.vec_cellpros') WHERE role = 'vector' ORDER BY colorder"
    ).fetchall()
    assert roles == [
        ("normal", "vector", 3),
        ("couple", "vector", 2),
        ("rgb", "vector", 3),
        ("dir", "vector", 2),
        ("nul", "vector", 3),
    ]
    assert _chunks(conn, "vec") == _chunks(conn, "twin")
    assert _face(conn, "vec") == _face(conn, "twin")
    got = conn.execute(
        "SELECT dir::text, nul, couple FROM public.vec_cellpros WHERE _geoid = 1 AND _idx = 3"
    ).fetchone()
    assert got == ("{-0,-0}", None, [3, -3])
    for name in ("vec", "twin"):
        conn.execute(
            f"UPDATE public.{name}_cellpros SET dir = ARRAY[1, 2], nul = ARRAY['NaN', '-0', 3]::double precision[], "
            "couple[2] = 7 WHERE _geoid = 1 AND _idx % 100 = 0"
        )
    conn.commit()
    assert _face(conn, "vec") == _face(conn, "twin")
    assert sqlstate(conn, "SELECT tgsis.check_chunk_conversion('public.vec_cellpros')") == (None, "")
    # a vector of another size is refused as the twin's row table refuses it: 23514, the same constraint name
    answers = []
    for name in ("vec", "twin"):
        with pytest.raises(psycopg.errors.CheckViolation) as caught:
            conn.execute(f"UPDATE public.{name}_cellpros SET dir = ARRAY[1, 2, 3] WHERE _geoid = 1 AND _idx = 3")
        conn.rollback()
        answers.append(str(caught.value.diag.constraint_name).replace(name, "X"))
    assert answers[0] == answers[1] == "X_cellpros_dir_check"


def _ranked(conn: Conn, name: str) -> list[tuple[Any, ...]]:
    """:func:`_face` with each geoid replaced by its rank (the twins' objects have geoids of their own)."""
    rows = _face(conn, name)
    rank = {g: i for i, g in enumerate(sorted({r[0] for r in rows}))}
    return [(rank[r[0]], *r[1:]) for r in rows]


def test_a_versioned_class_adds_and_renames_in_every_chunk_version(conn: Conn) -> None:
    """Versioned, a surface in two versions (an edit and deletes in the child), then the adds (with defaults: a
    surface's vertices have every property) and the rename: both versions read the new vectors as the twin in
    rows does. Fails while the change is refused in chunks."""
    for name in ("twin", "vec"):
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
    geoids = {name: _insert_mesh(conn, name)[0] for name in ("twin", "vec")}
    tgsis.create_version(conn, "e1")
    conn.commit()
    conn.execute("SELECT tgsis.store_class_in_chunks('vec')")
    conn.commit()
    with tgsis.in_version(conn, "e1"):
        for name in ("twin", "vec"):
            table, g = f"public.{name}_cellpros", geoids[name]
            conn.execute(f"UPDATE {table} SET pair = ARRAY[0, 0] WHERE _geoid = {g} AND _idx % 3 = 0")
            conn.execute(f"DELETE FROM {table} WHERE _geoid = {g} AND _idx BETWEEN 10 AND 20")
        conn.commit()
    for name in ("twin", "vec"):
        conn.execute(ADD_DIR.format(c=name))
        conn.execute(ADD_NUL.format(c=name).replace("}')", "}', '2.5')"))
        conn.execute(RENAME.format(c=name))
    conn.commit()
    assert _ranked(conn, "vec") == _ranked(conn, "twin")
    # the added vectors' CHECKs are named as on the twin's row storage (<table>_ver_<column>_check), so a wrong
    # vector names the same constraint on both (23514)
    names = []
    for name in ("twin", "vec"):
        with pytest.raises(psycopg.errors.CheckViolation) as caught:
            conn.execute(
                f"UPDATE public.{name}_cellpros SET dir = ARRAY[1, 2, 3] WHERE _geoid = {geoids[name]} AND _idx = 3"
            )
        conn.rollback()
        names.append(str(caught.value.diag.constraint_name).replace(name, "X"))
    assert names[0] == names[1] == "X_cellpros_ver_dir_check", names
    with tgsis.in_version(conn, "e1"):
        assert _ranked(conn, "vec") == _ranked(conn, "twin")
        for name in ("twin", "vec"):
            conn.execute(
                f"UPDATE public.{name}_cellpros SET dir = ARRAY[3, 4] WHERE _geoid = {geoids[name]} AND _idx < 5"
            )
        conn.commit()
        assert _ranked(conn, "vec") == _ranked(conn, "twin")
    conn.commit()


@pytest.mark.parametrize("fmt", ["custom"])
def test_pg_dump_and_restore_keep_the_added_and_renamed_vectors(
    pg: TestServer, db_dsn: str, conn: Conn, tmp_path: Path, fmt: str
) -> None:
    """The result of the adds and the rename in chunks dumped and restored: the chunk arrays bit for bit (no NaN
    payload in the data: pg_dump writes floats as text), the face's rows, and a write through the restored face."""
    from tests.test_backup import _bindir_of, _restored

    _vec(conn, "vec")
    conn.execute(
        "UPDATE public.vec_cellpros SET normal = ARRAY(SELECT CASE WHEN x = 'NaN' THEN 'NaN' ELSE x END "
        "FROM unnest(normal) AS x) WHERE normal IS NOT NULL"
    )
    conn.execute("SELECT tgsis.store_class_in_chunks('vec')")
    conn.commit()
    _changed(conn, "vec")
    conn.commit()
    chunks, face = _chunks(conn, "vec"), _face(conn, "vec")
    conn.rollback()
    with _restored(pg, _bindir_of(pg), db_dsn, fmt, tmp_path) as dsn, psycopg.connect(dsn) as copy:
        assert _chunks(copy, "vec") == chunks
        assert _face(copy, "vec") == face
        copy.execute("UPDATE public.vec_cellpros SET dir = ARRAY[5, 6], couple = NULL WHERE _geoid = 1 AND _idx = 9")
        copy.commit()
        assert copy.execute("SELECT dir, couple FROM public.vec_cellpros WHERE _geoid = 1 AND _idx = 9").fetchone() == (
            [5.0, 6.0],
            None,
        )


def test_a_session_writing_the_face_meanwhile_is_waited_for_or_waits(db_dsn: str, conn: Conn) -> None:
    """Another session's open transaction that wrote through the face: the add waits for it (lock_timeout here:
    55P03) or is refused (TG202, its work tables), nothing changed; once it committed, the add succeeds while that
    session stays connected, idle (the face's work tables are ON COMMIT DROP), its row kept and given the default. An add in an open transaction: a writer waits for it (55P03), then
    writes the new vector. Fails when a row is lost or the add is refused otherwise."""
    _vec(conn, "vec")
    conn.execute("SELECT tgsis.store_class_in_chunks('vec')")
    conn.commit()
    other = psycopg.connect(db_dsn)
    other.execute("UPDATE public.vec_cellpros SET pair = ARRAY[41, 42] WHERE _geoid = 1 AND _idx = 4")
    conn.execute("SET lock_timeout = '1s'")
    state, _ = sqlstate(conn, ADD_DIR.format(c="vec"))
    assert state in ("55P03", "TG202"), state
    conn.rollback()
    names = "SELECT count(*) FROM tgsis.chunk_columns('public.vec_cellpros') WHERE name = 'dir'"
    assert conn.execute(names).fetchone() == (0,)
    conn.rollback()
    other.commit()  # and stays connected, idle
    conn.execute(ADD_DIR.format(c="vec"))
    # the add not committed: a writer of the face waits for it
    with psycopg.connect(db_dsn) as writer:
        writer.execute("SET lock_timeout = '1s'")
        state, _ = sqlstate(writer, "UPDATE public.vec_cellpros SET pair = ARRAY[1, 1] WHERE _geoid = 1 AND _idx = 6")
        assert state == "55P03", state
        writer.rollback()
        conn.commit()
        writer.execute("UPDATE public.vec_cellpros SET dir = ARRAY[8, 9] WHERE _geoid = 1 AND _idx = 6")
        writer.commit()
    got = conn.execute(
        "SELECT _idx, pair, dir FROM public.vec_cellpros WHERE _geoid = 1 AND _idx IN (4, 6) ORDER BY 1"
    ).fetchall()
    assert got == [(4, [41, 42], [-0.0, -0.0]), (6, [6, -6], [8.0, 9.0])]
    other.close()
