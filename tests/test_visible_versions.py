"""One visibility predicate of stored versions: ``tgsis.visible_versions(alias, set)`` (issue 40, plan O, B1).

The readers of row versions (``<table>_ver``) and chunk versions (``<table>_chunk``) build their WHERE clause
from it: the versioned views (``tgsis.versioned_view_source``), the chunk faces (``tgsis.create_chunk_face``),
the versioning triggers, ``tgsis.rows_at``, ``tgsis.mesh_changes``, ``tgsis.chunk_object_extent``,
``tgsis.gmap_chunk_arrays_sql``, ``tgsis.table_fingerprint``, the face writers' "held" tests, and on the
client ``tgsis.db._chunk_transfer.visible_chunks``. The readers with a static query keep the text: these tests
compare it with the function's, so that the copies cannot drift; and a view built from the function's text is
stored as the hand-written one was (the views of databases made before it stay equal to new ones).
"""

from __future__ import annotations

from typing import Any

import psycopg
import pytest
from psycopg import sql

from tgsis.db._chunk_transfer import visible_versions

Conn = psycopg.Connection[Any]

SESSION_SET = "(SELECT tgsis.get_revisions(true))::integer[]"


def _helper(conn: Conn, alias: str, revision_set: str) -> str:
    row = conn.execute("SELECT tgsis.visible_versions(%s, %s)", (alias, revision_set)).fetchone()
    assert row is not None
    return str(row[0])


def test_the_predicate_is_the_versioned_views_test(conn: Conn) -> None:
    assert _helper(conn, "c", "$2") == (
        "(c.revision = ANY ($2)) IS TRUE AND (NOT c.revclosed OR NOT (c.lastrevs && $2))"
    )
    assert _helper(conn, "Odd", "v_set").startswith('("Odd".revision = ANY (v_set))')  # the alias quoted


@pytest.mark.parametrize(
    ("function", "alias", "revision_set"),
    [
        ("vertices", "c", "v_set"),  # model 1's keyed read of the chunks
        ("md_vertices_in_box", "c", "v_set"),  # model 5's points in a box, from the chunks
        ("comparable_geometry", "g", "p_revisions"),  # tgsis.geometry_ver
    ],
)
def test_a_static_reader_carries_the_predicate_s_text(conn: Conn, function: str, alias: str, revision_set: str) -> None:
    sources = [
        str(src)
        for (src,) in conn.execute(
            "SELECT p.prosrc FROM pg_proc p WHERE p.pronamespace = 'tgsis'::regnamespace AND p.proname = %s",
            (function,),
        ).fetchall()
    ]
    assert sources, function
    # (a static query may break the text over lines: compared with the whitespace made single spaces)
    flat = [" ".join(src.split()) for src in sources]
    assert any(_helper(conn, alias, revision_set) in src for src in flat), function


@pytest.mark.parametrize("revision_set", ["$2", SESSION_SET, "'{1,2}'::integer[]"])
def test_the_client_s_predicate_is_the_function_s(conn: Conn, revision_set: str) -> None:
    assert visible_versions("c", sql.SQL(revision_set)).as_string(conn) == _helper(conn, "c", revision_set)


def test_a_view_built_from_the_function_is_stored_as_the_hand_written_one_was(conn: Conn) -> None:
    """The set of a view is a scalar subquery; its cast (needed on the ANY side) is kept by PostgreSQL on
    neither side, so that the views and faces of a database made before the function read the same."""
    conn.execute("CREATE TEMP TABLE t_ver (id integer, revision integer, lastrevs integer[], revclosed boolean)")
    conn.execute(
        "CREATE TEMP VIEW by_hand AS SELECT v.id FROM t_ver v "
        "WHERE (v.revision = ANY ((SELECT tgsis.get_revisions(true))::integer[])) IS TRUE "
        "AND (NOT v.revclosed OR NOT (v.lastrevs && (SELECT tgsis.get_revisions(true))))"
    )
    conn.execute(
        sql.SQL("CREATE TEMP VIEW by_function AS SELECT v.id FROM t_ver v WHERE {}").format(
            sql.SQL(_helper(conn, "v", SESSION_SET))
        )
    )
    defs = conn.execute(
        "SELECT pg_get_viewdef('by_hand'::regclass), pg_get_viewdef('by_function'::regclass)"
    ).fetchone()
    assert defs is not None and defs[0] == defs[1]
    conn.rollback()
