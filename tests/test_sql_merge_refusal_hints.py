"""The hint of the psql merge by region's own refusals names the commands with the version quoted (issue 39).

`tgsis.merge_mesh_by_region` refuses what only the Python client merges
(TG302) with a hint naming `tgsis version merge NAME` and
``tgsis.merge_version(conn, NAME)``: the name must be one shell word and one
Python literal, whatever it holds. (Was: the name bare in the command — three
words for ``north edit`` — and an SQL literal in the Python call —
``'o''brien'`` reads in Python as two adjacent strings, another version.)
"""

from __future__ import annotations

import ast
import shlex
from typing import Any

import psycopg
import pytest

import tgsis
from tests.merge_data import make_fault, move
from tests.test_sql_merge_regions import MIDDLE

Conn = psycopg.Connection[Any]


@pytest.mark.parametrize("name", ["north edit", 'o\'brien "x"'])
def test_a_solution_recorded_with_its_npz_only_names_the_commands_with_the_name_quoted(conn: Conn, name: str) -> None:
    fault = make_fault(conn)
    tgsis.create_version(conn, name)
    conn.commit()
    move(conn, name, fault, MIDDLE, (0.0, 0.0, 5.0))
    move(conn, "DEFAULT", fault, MIDDLE, (0.5, 0.0, -7.0))
    conn.commit()
    (conflict,) = tgsis.find_conflicts(conn, name)
    conn.commit()
    (region,) = [r.region for r in conflict.regions if r.conflict]
    tgsis.resolve_region(conn, name, fault, region, "average")
    conn.commit()
    (mesh,) = conn.execute(
        "SELECT solution_mesh FROM tgsis.conflict_regions WHERE versionid = tgsis.version_id(%s) AND region = %s",
        (name, region),
    ).fetchone()  # type: ignore[misc]
    # recorded again by a psql user with the .npz only: no rows SQL reads
    conn.execute("SELECT tgsis.resolve_region(%s, 'feature', %s, %s, 'average', %s)", (name, str(fault), region, mesh))
    conn.commit()
    for action in ("merge", "refresh"):
        with pytest.raises(psycopg.Error) as caught:
            conn.execute(f"SELECT tgsis.{action}_version(%s)", (name,))
        conn.rollback()
        assert caught.value.sqlstate == "TG302"
        hint = caught.value.diag.message_hint or ""
        assert "with its mesh only" in str(caught.value), str(caught.value)
        assert shlex.split(hint.split("`")[1]) == ["tgsis", "version", action, name], hint
        call = hint.split(f"tgsis.{action}_version(conn, ")[1].split(") in Python")[0]
        assert ast.literal_eval(call) == name, hint
