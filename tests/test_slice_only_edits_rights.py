"""``tgsis.slice_only_edits`` and the rights on the class: no instant of a class the caller may not read is told.

The function names the slices (instants, geometry instants) only one side
changed; ``tgsis.resolve_conflict`` (SECURITY DEFINER) puts them in its TG307
message. A role that may not read the feature's class must learn nothing of
them — neither calling the function (executable by PUBLIC, like
``tgsis.mesh_merge_regions``) nor through a whole-object solution: both are
refused (42501) as ``mesh_merge_regions`` refuses, naming no instant.
"""

from __future__ import annotations

from typing import Any

import psycopg
import pytest

import tgsis
from tests.roles import login_roles
from tests.test_merge_instants import NORTH, SOUTH, make_series, move

Conn = psycopg.Connection[Any]

# instants the parent alone changed: the values a message of the function would name
PARENT_ONLY = (3.0, 1.0)


@pytest.fixture
def series(conn: Conn) -> int:
    geoid = make_series(conn)
    move(conn, "e1", geoid, 2.0, NORTH, (0.0, 0.0, 5.0))
    for t in PARENT_ONLY:
        move(conn, "DEFAULT", geoid, t, SOUTH, (0.0, 0.0, -3.0))
    conn.execute("SELECT tgsis.find_conflicts('e1')")
    conn.commit()
    return geoid


def test_the_owner_is_told_the_slices(conn: Conn, series: int) -> None:
    row = conn.execute("SELECT tgsis.slice_only_edits('e1', %s, 'parent')", (series,)).fetchone()
    assert row == ("instant 1, instant 3",)


def test_a_role_that_may_not_read_the_class_is_refused_by_the_function(conn: Conn, series: int, db_dsn: str) -> None:
    with login_roles(db_dsn, {"rita": "tgsis_reader"}) as made:
        conn.execute("REVOKE SELECT ON public.horizons FROM tgsis_reader")
        conn.commit()
        rita = made.connect("rita")
        with pytest.raises(psycopg.errors.InsufficientPrivilege) as caught:
            rita.execute("SELECT tgsis.slice_only_edits('e1', %s, 'parent')", (series,))
        text = str(caught.value) + (caught.value.diag.message_hint or "") + (caught.value.diag.message_detail or "")
        assert f"feature {series}" in text and "instant" not in text, text
        rita.rollback()
        conn.execute("GRANT SELECT ON public.horizons TO tgsis_reader")  # with the right, the answer
        conn.commit()
        assert rita.execute("SELECT tgsis.slice_only_edits('e1', %s, 'parent')", (series,)).fetchone() == (
            "instant 1, instant 3",
        )


def test_a_whole_object_solution_of_a_role_that_may_not_read_the_class_names_no_instant(
    conn: Conn, series: int, db_dsn: str
) -> None:
    with login_roles(db_dsn, {"ed": "tgsis_editor"}) as made:
        tgsis.grant_version(conn, "e1", "all", made.name("ed"))
        tgsis.grant_version(conn, "DEFAULT", "merge", made.name("ed"))
        conn.execute("REVOKE SELECT ON public.horizons FROM tgsis_reader, tgsis_editor")
        conn.commit()
        before = conn.execute("SELECT solution FROM tgsis.conflicts").fetchall()
        conn.commit()
        ed = made.connect("ed")
        for solution in ("child", "parent", "base"):
            with pytest.raises(psycopg.errors.InsufficientPrivilege) as caught:
                ed.execute("SELECT tgsis.resolve_conflict('e1', 'feature', %s, %s)", (str(series), solution))
            ed.rollback()
            text = str(caught.value) + (caught.value.diag.message_hint or "") + (caught.value.diag.message_detail or "")
            assert "instant" not in text, (solution, text)
        assert conn.execute("SELECT solution FROM tgsis.conflicts").fetchall() == before
        conn.commit()
