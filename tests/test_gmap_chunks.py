"""The darts and involutions of G-maps (models 4 and 5) stored in chunks, by choice (issue 40).

docs/storage.md, "G-maps (models 4 and 5)": gmap_dart / md_dart are keyed
(geoid, chunk) by dartid, gmap_alpha / md_alpha (geoid, level, chunk); the
dart's point and the involution's image are vertex-id columns (relative to
the chunk's smallest), a dart's acellid and positive arrays of their own type
that may hold NULL. ``tgsis.store_in_chunks`` / ``tgsis.store_in_rows`` switch
them with their data and back, and every function of models 4 and 5 keeps its
answers through the faces. The points (gmap_vertex, md_vertex: a 2-D float8
array per chunk) have their own file, tests/test_point_chunks.py. The rest of the G-map files run with these tables in chunks
under ``TGSIS_TEST_TIME_STORAGE=chunks`` (docs/testing.md).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import psycopg
import pytest

import tgsis
from tests.merge_data import sqlstate
from tests.storage_data import switch_tables, tables_as_rows
from tests.test_gmap_multidim import _class as _md_class
from tests.test_gmap_multidim import _interpretations
from tests.test_gmap_storage import _class as _gmap_class
from tests.test_gmap_storage import _evolving
from tgsis.db import gmaps as G

Conn = psycopg.Connection[Any]

TABLES = ("gmap_dart", "gmap_alpha", "md_dart", "md_alpha")
#: where the model-4 answers are asked: every instant, between them, before, after
ASKED = (0.0, 0.5, 1.0, 1.5, 2.0, 3.0, -1.0, 4.0)


@pytest.fixture(autouse=True)
def _gmaps_as_rows(conn: Conn) -> None:
    """The G-map tables as rows at each test's start, whatever TGSIS_TEST_TIME_STORAGE made them: each test
    switches them itself."""
    tables_as_rows(conn, TABLES)


def _switch(conn: Conn, to: str) -> None:
    switch_tables(conn, TABLES, to)


def _store(conn: Conn, versioned: bool) -> tuple[int, int]:
    """A model-4 G-map in time (two topology periods) and a model-5 one (a horizon's history of knowledge)."""
    fc4 = _gmap_class(conn)
    fc5 = _md_class(conn)
    if versioned:
        tgsis.enable_feature_versioning(conn)
    conn.commit()
    g4 = G.insert_gmap(conn, fc4, _evolving(), name="rising")
    g5 = G.insert_gmap(conn, fc5, _interpretations()[2], name="H1", axes=["x", "y", "z", "knowledge"])
    conn.commit()
    return g4, g5


def _answers(conn: Conn, g4: int, g5: int) -> dict[str, Any]:
    """What the model-4 and model-5 functions, faces and Python readers say of the two G-maps."""

    def rows(query: str, *params: Any) -> list[tuple[Any, ...]]:
        with conn.cursor(binary=True) as cursor:
            return cursor.execute(query, params).fetchall()

    answers: dict[str, Any] = {}
    for t in ASKED:
        answers[f"gmap_at {t!r}"] = rows("SELECT * FROM tgsis.gmap_at(%s, %s) ORDER BY 1", g4, t)
        answers[f"gmap_points_at {t!r}"] = rows("SELECT * FROM tgsis.gmap_points_at(%s, %s) ORDER BY 1", g4, t)
        answers[f"gmap_frame {t!r}"] = rows("SELECT * FROM tgsis.gmap_frame(%s, %s)", g4, t)
        answers[f"porosity {t!r}"] = rows(
            "SELECT * FROM tgsis.gmap_property_at('blocks', %s, 'porosity', %s) ORDER BY 1", g4, t
        )
        for level in range(3):
            answers[f"gmap_cells {level} {t!r}"] = rows(
                "SELECT * FROM tgsis.gmap_cells(%s, %s, %s) ORDER BY 1", g4, level, t
            )
        got = G.gmap_at(conn, g4, t)
        answers[f"python gmap_at {t!r}"] = (
            None if got is None else (got.alpha.tolist(), got.vertex.tolist(), got.points.tolist())
        )
    answers["gmap_edges_at"] = rows("SELECT * FROM tgsis.gmap_edges_at(%s, 1.0, 2.0) ORDER BY 1, 2", g4)
    answers["gmap_check"] = rows("SELECT * FROM tgsis.gmap_check(%s)", g4)
    answers["md_check"] = rows("SELECT * FROM tgsis.md_check(%s)", g5)
    answers["check_geometry"] = rows("SELECT * FROM tgsis.check_geometry(%s)", g4) + rows(
        "SELECT * FROM tgsis.check_geometry(%s)", g5
    )
    answers["extents"] = rows("SELECT tgsis.gmap_extent(%s)::text, tgsis.md_extent(%s)::text", g4, g5)
    for level in range(4):
        answers[f"md_cells {level}"] = rows("SELECT * FROM tgsis.md_cells(%s, %s) ORDER BY 1", g5, level)
    answers["md_vertices_in_box"] = rows(
        "SELECT * FROM tgsis.md_vertices_in_box(%s, '{knowledge}', '{0.5}', '{1.5}') ORDER BY 1", g5
    )
    answers["md_in_box"] = rows("SELECT * FROM tgsis.md_in_box('knowledge', '{x,knowledge}', '{0,1}', '{1,2}')")
    for table, cols in (
        ("gmap_dart", "geoid, dartid, float8send(timem), nodeid, acellid, positive"),
        ("gmap_alpha", "geoid, level, dartid, dartid2"),
        ("md_dart", "geoid, dartid, vrtxid, acellid, positive"),
        ("md_alpha", "geoid, level, dartid, dartid2"),
    ):
        answers[table] = rows(
            f"SELECT {cols} FROM tgsis.{table} ORDER BY geoid, dartid{', level' if 'alpha' in table else ''}"
        )
    e = G.fetch_gmap(conn, "blocks", g4)
    answers["fetch_gmap"] = [
        (
            p.times.tolist(),
            p.gmap.alpha.tolist(),
            p.gmap.vertex.tolist(),
            p.positions.tolist(),
            p.level,
            {k: np.asarray(v).tolist() for k, v in sorted(p.cell_values.items())},
        )
        for p in e.periods
    ]
    md, axes = G.fetch_md_gmap(conn, "knowledge", g5)
    answers["fetch_md_gmap"] = (axes, md.alpha.tolist(), md.vertex.tolist(), md.points.tolist())
    conn.rollback()
    return answers


@pytest.mark.parametrize("versioned", [False, True])
def test_the_switch_and_back_keep_every_answer(conn: Conn, versioned: bool) -> None:
    g4, g5 = _store(conn, versioned)
    versions: tuple[str, ...] = ("DEFAULT",)
    if versioned:  # a version whose psql user turns a dart's orientation around and frees nothing
        tgsis.create_version(conn, "e1")
        conn.commit()
        with tgsis.in_version(conn, "e1"):
            conn.execute("UPDATE tgsis.gmap_dart SET positive = NOT positive WHERE geoid = %s AND dartid = 3", (g4,))
            conn.execute("UPDATE tgsis.md_dart SET acellid = NULL WHERE geoid = %s AND dartid = 5", (g5,))
        conn.commit()
        versions = ("DEFAULT", "e1")

    def everywhere() -> dict[str, Any]:
        found = {}
        for version in versions:
            with tgsis.in_version(conn, version):
                found[version] = _answers(conn, g4, g5)
            conn.rollback()
        return found

    before = everywhere()
    if versioned:
        assert before["e1"]["gmap_dart"] != before["DEFAULT"]["gmap_dart"]
        assert before["e1"]["md_dart"] != before["DEFAULT"]["md_dart"]
    assert conn.execute("SELECT tgsis.chunk_key('gmap_dart'), tgsis.chunk_key('md_alpha')").fetchone() == (
        ["geoid"],
        ["geoid", "level"],
    )
    _switch(conn, "chunks")
    assert conn.execute(
        "SELECT bool_and(tgsis.stored_in_chunks(t)) FROM unnest(%s::text[]) t", (list(TABLES),)
    ).fetchone() == (True,)
    conn.execute("SELECT tgsis.check_chunk_conversion(t) FROM unnest(%s::text[]) t", (list(TABLES),))
    # the involutions' chunk table is keyed (geoid, level, chunk, revision); the partner relative to the chunk's base
    assert conn.execute(
        "SELECT array_agg(a.attname ORDER BY k.o) FROM pg_constraint c CROSS JOIN LATERAL unnest(c.conkey) WITH ORDINALITY"
        " k(n, o) JOIN pg_attribute a ON a.attrelid = c.conrelid AND a.attnum = k.n"
        " WHERE c.conrelid = 'tgsis.gmap_alpha_chunk'::regclass AND c.contype = 'p'"
    ).fetchone() == (["geoid", "level", "chunk", "revision"],)
    assert conn.execute(
        "SELECT format_type(atttypid, atttypmod) FROM pg_attribute WHERE attrelid = 'tgsis.gmap_dart_chunk'::regclass"
        " AND attname IN ('acellid', 'positive', 'nodeid', 'timem') ORDER BY attname"
    ).fetchall() == [("bigint[]",), ("integer[]",), ("boolean[]",), ("double precision[]",)]
    conn.commit()
    assert everywhere() == before
    _switch(conn, "rows")
    assert everywhere() == before


def test_writes_through_the_faces_keep_null_apart_from_false_and_holes(conn: Conn) -> None:
    g4, g5 = _store(conn, False)
    _switch(conn, "chunks")
    # a dart of no cell and no orientation, then one with positive false: NULL is kept apart from false
    conn.execute("UPDATE tgsis.gmap_dart SET acellid = NULL, positive = NULL WHERE geoid = %s AND dartid = 2", (g4,))
    conn.execute("UPDATE tgsis.gmap_dart SET positive = false WHERE geoid = %s AND dartid = 4", (g4,))
    conn.commit()
    got = conn.execute(
        "SELECT dartid, acellid IS NULL, positive FROM tgsis.gmap_dart WHERE geoid = %s AND dartid IN (2, 4) ORDER BY 1",
        (g4,),
    ).fetchall()
    assert got == [(2, True, None), (4, False, False)]
    stored = conn.execute(
        "SELECT acellid[3] IS NULL, positive[3] IS NULL, positive[5], holes FROM tgsis.gmap_dart_chunk"
        " WHERE geoid = %s AND chunk = 0",
        (g4,),
    ).fetchone()
    assert stored == (True, True, False, None)
    # a dart deleted in the middle is a hole; its NULL acellid neighbour stays present
    darts = conn.execute("SELECT count(*) FROM tgsis.gmap_dart WHERE geoid = %s", (g4,)).fetchone()
    conn.execute("DELETE FROM tgsis.gmap_dart WHERE geoid = %s AND dartid = 3", (g4,))
    conn.commit()
    assert conn.execute("SELECT count(*) FROM tgsis.gmap_dart WHERE geoid = %s", (g4,)).fetchone() == (darts[0] - 1,)  # type: ignore[index]
    assert conn.execute("SELECT holes FROM tgsis.gmap_dart_chunk WHERE geoid = %s AND chunk = 0", (g4,)).fetchone() == (
        [4],
    )
    assert conn.execute(
        "SELECT dartid FROM tgsis.gmap_dart WHERE geoid = %s AND acellid IS NULL", (g4,)
    ).fetchall() == [(2,)]
    # the check names the dart missing from the involutions' partners
    assert conn.execute("SELECT count(*) > 0 FROM tgsis.gmap_check(%s)", (g4,)).fetchone() == (True,)
    # model 5: a dart's acellid set NULL through the face stays a present dart (its point says so, not its cell)
    conn.execute("UPDATE tgsis.md_dart SET acellid = NULL WHERE geoid = %s AND dartid = 5", (g5,))
    assert conn.execute(
        "SELECT vrtxid IS NOT NULL, acellid FROM tgsis.md_dart WHERE geoid = %s AND dartid = 5", (g5,)
    ).fetchall() == [(True, None)]
    assert conn.execute("SELECT holes FROM tgsis.md_dart_chunk WHERE geoid = %s AND chunk = 0", (g5,)).fetchone() == (
        None,
    )
    # model 5: the involution of a level moved through the face; the check sees it
    conn.execute("UPDATE tgsis.md_alpha SET dartid2 = dartid WHERE geoid = %s AND level = 0 AND dartid = 0", (g5,))
    problems = conn.execute("SELECT * FROM tgsis.md_check(%s)", (g5,)).fetchall()
    assert problems
    conn.rollback()
    _switch(conn, "rows")
    assert conn.execute(
        "SELECT dartid, acellid IS NULL, positive FROM tgsis.gmap_dart WHERE geoid = %s AND dartid IN (2, 3, 4) ORDER BY 1",
        (g4,),
    ).fetchall() == [(2, True, None), (4, False, False)]


def test_hostile_rows_and_tables_are_refused_by_name(conn: Conn) -> None:
    g4, _ = _store(conn, False)
    _switch(conn, "chunks")
    before = _answers(conn, g4, _)["gmap_dart"]
    # a NOT NULL column left out, a NULL point, a negative partner: refused, nothing written
    assert (
        sqlstate(
            conn,
            "SELECT tgsis.insert_chunk_rows('gmap_dart', '{geoid,dartid}', ARRAY[[%s],[900]]::bigint[], NULL)",
            (g4,),
        )[0]
        == "TG100"
    )
    conn.rollback()
    assert (
        sqlstate(
            conn,
            "SELECT tgsis.insert_chunk_rows('gmap_dart', '{geoid,dartid,nodeid,timem}', ARRAY[[%s],[900],[NULL]]::bigint[],"
            " '{{0}}')",
            (g4,),
        )[0]
        == "TG100"
    )
    conn.rollback()
    assert sqlstate(conn, "INSERT INTO tgsis.gmap_alpha VALUES (%s, 0, 900, -1)", (g4,))[0] == "TG100"
    conn.rollback()
    assert sqlstate(conn, "INSERT INTO tgsis.gmap_dart VALUES (%s, 0, 0, 0)", (g4,))[0] == "23505"
    conn.rollback()
    # booleans of a wrong shape; a boolean array where the table has no boolean column named
    assert (
        sqlstate(
            conn,
            "SELECT tgsis.insert_chunk_rows('gmap_dart', '{geoid,dartid,nodeid,timem,positive}',"
            " ARRAY[[%s],[900],[0]]::bigint[], '{{0}}', '{{true,false}}')",
            (g4,),
        )[0]
        == "TG100"
    )
    conn.rollback()
    assert _answers(conn, g4, _)["gmap_dart"] == before
    # nullable columns left out are NULL, as in a COPY; a smallint key travels among the bigints
    conn.execute(
        "SELECT tgsis.insert_chunk_rows('gmap_dart', '{geoid,dartid,nodeid,timem}', ARRAY[[%s],[2000],[0]]::bigint[], '{{0}}')",
        (g4,),
    )
    conn.execute(
        "SELECT tgsis.insert_chunk_rows('gmap_alpha', '{geoid,level,dartid,dartid2}', ARRAY[[%s],[1],[2000],[2000]]::bigint[],"
        " NULL)",
        (g4,),
    )
    assert conn.execute(
        "SELECT d.acellid, d.positive, a.dartid2 FROM tgsis.gmap_dart d JOIN tgsis.gmap_alpha a USING (geoid, dartid)"
        " WHERE geoid = %s AND dartid = 2000",
        (g4,),
    ).fetchall() == [(None, None, 2000)]
    assert (
        sqlstate(
            conn,
            "SELECT tgsis.insert_chunk_rows('gmap_alpha', '{geoid,level,dartid,dartid2}', ARRAY[[%s],[70000],[2001],[2001]]::bigint[],"
            " NULL)",
            (g4,),
        )[0]
        == "22003"
    )  # a level out of smallint's range: the cast's error, as a COPY's
    conn.rollback()
    # model 1's object writers carry no 'value' arrays: refused by name rather than leaving acellid and positive NULL
    for call in (
        "SELECT tgsis.write_object_rows('gmap_dart', %s, '{}', '{1}', '{{0}}', '{{0}}')",
        "SELECT tgsis.object_chunks_stage('gmap_dart')",
        "SELECT tgsis.swap_object_chunks('gmap_dart', %s, '{0}', '{NULL}')",
    ):
        state, message = sqlstate(conn, call, (g4,) if "%s" in call else ())
        assert state == "TG100" and "does not write: acellid, positive" in message, (call, message)
        conn.rollback()
    # a table not registered for chunks: refused by name (the points are, since plan M: tests/test_point_chunks.py)
    assert sqlstate(conn, "SELECT tgsis.store_in_chunks('md_cell')")[0] == "TG200"
    conn.rollback()


def test_a_role_with_fewer_rights_reads_and_cannot_write(db_dsn: str, conn: Conn) -> None:
    from tests.roles import login_roles

    g4, g5 = _store(conn, True)
    _switch(conn, "chunks")
    with login_roles(db_dsn, {"reader": "tgsis_reader"}) as roles:
        reader = roles.connect("reader")
        assert reader.execute("SELECT count(*) FROM tgsis.gmap_check(%s)", (g4,)).fetchone() == (0,)
        assert reader.execute("SELECT count(*) FROM tgsis.md_check(%s)", (g5,)).fetchone() == (0,)
        assert G.fetch_md_gmap(reader, "knowledge", g5)[0].same_as(_interpretations()[2])
        assert sqlstate(reader, "UPDATE tgsis.gmap_dart SET positive = NULL WHERE geoid = %s", (g4,))[0] == "42501"
        assert sqlstate(reader, "UPDATE tgsis.md_alpha_chunk SET dartid2[1] = 0")[0] == "42501"
        assert sqlstate(reader, "SELECT tgsis.store_in_rows('gmap_dart')")[0] == "42501"


def test_pg_dump_and_restore_keep_the_tables_in_chunks(pg: Any, db_dsn: str, conn: Conn, tmp_path: Any) -> None:
    from tests.test_backup import _bindir_of, _restored

    g4, g5 = _store(conn, True)
    _switch(conn, "chunks")
    before = _answers(conn, g4, g5)
    chunks = [
        f"SELECT * FROM tgsis.{t}_chunk ORDER BY geoid, {'level, ' if 'alpha' in t else ''}chunk, revision"
        for t in TABLES
    ]
    stored = [conn.execute(q).fetchall() for q in chunks]
    conn.rollback()
    with _restored(pg, _bindir_of(pg), db_dsn, "custom", tmp_path) as dsn, psycopg.connect(dsn) as copy:
        assert [copy.execute(q).fetchall() for q in chunks] == stored
        assert copy.execute(
            "SELECT bool_and(tgsis.stored_in_chunks(t)) FROM unnest(%s::text[]) t", (list(TABLES),)
        ).fetchone() == (True,)
        assert _answers(copy, g4, g5) == before
        _switch(copy, "rows")
        assert _answers(copy, g4, g5) == before
