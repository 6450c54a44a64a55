"""Hints that print a command line name a version as one shell word: ``tgsis version merge 'my version'``.

A version name is free text (``create_version`` takes spaces, quotes, ``$``):
pasted into a shell, ``tgsis version merge my version`` is three arguments,
and ``o'brien`` opens a quote. Every hint that prints a command with a version
name quotes it as ``shlex.quote`` does — the command line's mapping of the SQL
and Python hints (tgsis.cli._hints), the Python library's own, the SQL
functions' (``tgsis.shell_quote``, equal to ``shlex.quote``) — and a plain name
stays as it is.
"""

from __future__ import annotations

import json
import shlex
from typing import Any

import psycopg
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import tgsis
from tests.merge_data import make_fault, move
from tgsis.cli._hints import to_cli

Conn = psycopg.Connection[Any]

NAMES = ["my version", "o'brien", "a$b `c`", "e1", "x;rm -rf y", "a)b (c", "dev\\ana's", "a E'b"]


def _sql(name: str) -> str:
    """``name`` as format's %L writes it: E'...' with the backslashes doubled when it holds one."""
    quoted = "'" + name.replace("'", "''").replace("\\", "\\\\") + "'"
    return "E" + quoted if "\\" in name else quoted


def _cases(name: str) -> list[tuple[str, list[str]]]:
    """(an SQL or Python hint naming version ``name``, the commands its CLI form must hold).

    The Python library's hints name it as ``repr`` does (``tgsis.find_conflicts(conn, {version!r})``), the SQL
    functions' as ``%L`` does.
    """
    q, lit = shlex.quote(name), _sql(name)
    return [
        (
            f"record a solution for each: SELECT tgsis.resolve_conflict({lit}, class, key, 'parent'|'child'|'manual')",
            [f"tgsis version resolve {q} CLASS KEY", f"tgsis version conflicts {q} lists them"],
        ),
        (f"find the regions again: tgsis.find_conflicts(conn, {name!r})", [f"tgsis version conflicts {q}"]),
        (
            f"a role that may read the class finds its regions with SELECT FROM tgsis.find_conflicts({lit}), or the "
            "class's owner lets this role read it",
            [f"finds its regions with tgsis version conflicts {q}"],
        ),
        (
            f"tgsis.find_conflicts(conn, {name!r}) finds and records them (tgsis version conflicts {q})",
            [f"tgsis version conflicts {q} finds and records them"],
        ),
        (
            f"SELECT region, conflict, solution FROM tgsis.conflict_regions WHERE versionid = tgsis.version_id({lit}) "
            "lists them; tgsis.find_conflicts in Python finds them",
            [f"tgsis version conflicts {q} --json"],
        ),
        (
            "only a region with conflict = true takes a solution: SELECT region FROM tgsis.conflict_regions WHERE "
            f"versionid = tgsis.version_id({lit}) AND conflict",
            [f"tgsis version conflicts {q} --json"],
        ),
        (
            f"solve the conflicting regions with SELECT tgsis.resolve_region({lit}, 'feature', '12', region, 'child'); "
            "the merge takes the rest by itself",
            [f"tgsis version resolve {q} 12 child --region N"],
        ),
        (
            f"the meshes 12 merge by region: `tgsis version merge {name}` or tgsis.merge_version(conn, {json.dumps(name, ensure_ascii=False)}) in "
            f"Python merges them (solve their conflicting regions first: SELECT tgsis.resolve_region({lit}, "
            f"'feature', key, region, 'parent'|'child'|'base')); record a solution for the others: SELECT "
            f"tgsis.resolve_conflict({lit}, class, key, 'parent'|'child'|'manual')",
            [
                f"tgsis version merge {q} merges them",
                f"tgsis version resolve {q} ID",
                f"tgsis version resolve {q} CLASS",
            ],
        ),
        (
            f"tgsis.find_conflicts(conn, {name!r}) lists the objects changed on both sides",
            [f"tgsis version conflicts {q} lists"],
        ),
        (f"SELECT * FROM tgsis.find_conflicts({lit}) lists the conflicts", [f"tgsis version conflicts {q} lists"]),
        (
            f"SELECT tgsis.goto_version({lit}) to work in its working revision",
            [f"--in {q} (or tgsis version goto {q})"],
        ),
        (
            f"the owner or a tgsis_admin can run SELECT tgsis.grant_version({lit}, 'write', 'ana')",
            [f"tgsis version grant {q} write ana"],
        ),
    ]


@pytest.mark.parametrize("name", NAMES)
def test_the_mapped_hints_quote_the_version_name(name: str) -> None:
    for hint, commands in _cases(name):
        said = to_cli(hint) or ""
        for command in commands:
            assert command in said, (hint, said)
        if " " in name:
            assert f" {name} " not in said.replace(shlex.quote(name), "QUOTED"), said


@settings(max_examples=200, deadline=None)
@given(st.text(alphabet=st.characters(min_codepoint=1, max_codepoint=0x2FF), max_size=12))
def test_sql_shell_quote_is_shlex_quote(pg_conn_for_quote: Conn, name: str) -> None:
    row = pg_conn_for_quote.execute("SELECT tgsis.shell_quote(%s)", (name,)).fetchone()
    assert row == (shlex.quote(name),)


@pytest.fixture(scope="module")
def pg_conn_for_quote(pg: Any, template_db: str) -> Any:
    with pg.database("tgsis_shell_quote", template_db) as (_, dsn), psycopg.connect(dsn, autocommit=True) as conn:
        yield conn


def test_the_python_and_sql_hints_of_a_version_with_a_space(conn: Conn) -> None:
    """The library's hints (object_merge; resolve_conflict's TG307 of a model-2 feature) from the database."""
    from tests.test_merge_instants import NORTH, SOUTH, make_series
    from tests.test_merge_instants import move as move_at

    series = make_series(conn)
    tgsis.create_version(conn, "my version")
    conn.commit()
    move_at(conn, "my version", series, 2.0, NORTH, (0.0, 0.0, 5.0))
    move_at(conn, "DEFAULT", series, 3.0, SOUTH, (0.0, 0.0, -3.0))
    with pytest.raises(tgsis.InvalidInputError) as caught:
        tgsis.object_merge(conn, "my version", series)
    assert "(tgsis version conflicts 'my version')" in (caught.value.hint or ""), caught.value.hint
    conn.rollback()
    conn.execute("SELECT tgsis.find_conflicts('my version')")
    conn.commit()
    with pytest.raises(psycopg.Error) as sql_caught:
        conn.execute("SELECT tgsis.resolve_conflict('my version', 'feature', %s, 'child')", (str(series),))
    hint = sql_caught.value.diag.message_hint or ""
    assert "tgsis version merge 'my version' merges it" in hint and "tgsis version conflicts 'my version'" in hint
    conn.rollback()


def test_the_command_line_prints_the_name_quoted(db_dsn: str, conn: Conn, capsys: pytest.CaptureFixture[str]) -> None:
    from tests.test_cli_hints import hint_of

    geoid = make_fault(conn)
    tgsis.create_version(conn, "north edit")
    conn.commit()
    move(conn, "north edit", geoid, [5], (0.0, 0.0, 3.0))
    move(conn, "DEFAULT", geoid, [5], (0.0, 0.0, -3.0))
    conn.execute("CREATE TABLE notes (id int PRIMARY KEY, note text)")
    conn.execute("INSERT INTO notes VALUES (1, 'a')")
    conn.commit()
    tgsis.enable_versioning(conn, "notes", "id", "note")
    conn.commit()
    tgsis.create_version(conn, "o'brien")
    conn.commit()
    with tgsis.in_version(conn, "o'brien"):
        conn.execute("UPDATE notes SET note = 'b'")
    conn.commit()
    conn.execute("UPDATE notes SET note = 'c'")
    conn.commit()
    hint = hint_of(db_dsn, capsys, "version", "merge", "north edit")
    assert "tgsis version merge 'north edit' merges them" in hint, hint
    hint = hint_of(db_dsn, capsys, "version", "merge", "o'brien")
    assert "tgsis version resolve 'o'\"'\"'brien' CLASS KEY" in hint, hint
    assert shlex.split(hint.split("tgsis version resolve ")[1])[0] == "o'brien"


PYTHON_NAMES = ["my version", "o'brien", "a)b", "back\\slash", 'say "hi"', "both ' and \"", "e1"]


def _python_cases(name: str) -> list[tuple[str, str]]:
    """(a hint as the Python library writes it — the name as ``repr`` — and the command its CLI form must be)."""
    q = shlex.quote(name)
    return [  # the f-strings of tgsis.db.regions, tgsis.db.merging and tgsis.db._merge_states
        (
            f"find the regions again: tgsis.find_conflicts(conn, {name!r}), or tgsis version conflicts {q}",
            f"find the regions again: tgsis version conflicts {q}",
        ),
        (
            f"find the regions again: tgsis.find_conflicts(conn, {name!r})",
            f"find the regions again: tgsis version conflicts {q}",
        ),
        (
            f"tgsis.find_conflicts(conn, {name!r}) finds and records them (tgsis version conflicts {q})",
            f"tgsis version conflicts {q} finds and records them",
        ),
        (
            f"its regions, each with its slice: tgsis.find_conflicts(conn, {name!r}) finds and records them "
            f"(tgsis version conflicts {q})",
            f"its regions, each with its slice: tgsis version conflicts {q} finds and records them",
        ),
        (
            f"tgsis.find_conflicts(conn, {name!r}) lists the objects changed on both sides",
            f"tgsis version conflicts {q} lists the objects changed on both sides",
        ),
    ]


@pytest.mark.parametrize("name", PYTHON_NAMES)
def test_the_python_hints_map_the_name_as_repr_wrote_it(name: str) -> None:
    """The library's hints name the version as Python's repr: the whole hint becomes the command, nothing left over.

    (Was: 'my version' gave ``tgsis version conflicts 'my version' version'``, a name with ``)`` cut the command
    short, a backslash was doubled, a name with a quote stayed in Python's terms.)
    """
    for hint, expected in _python_cases(name):
        said = to_cli(hint)
        assert said == expected, (hint, said)
        assert shlex.split(said.split("tgsis version conflicts ")[1])[0] == name


def test_the_sql_hint_naming_find_conflicts_in_python_without_a_name() -> None:
    """tgsis.resolve_all_regions' TG307 names no version: the command line says VERSION, nothing of Python is left."""
    hint = "find the regions again: tgsis.find_conflicts(conn, version) in Python, or tgsis version conflicts"
    assert to_cli(hint) == "find the regions again: tgsis version conflicts VERSION"


def test_the_sql_merge_refusal_prints_the_command_with_the_name_quoted(conn: Conn) -> None:
    """psql's TG302 of a merge whose meshes merge by region names `tgsis version merge NAME` quoted as the shell wants.

    (Was: `tgsis version merge north edit`, three arguments when pasted; only the command line's mapping quoted it.)
    """
    geoid = make_fault(conn)
    tgsis.create_version(conn, "north edit")
    conn.commit()
    move(conn, "north edit", geoid, [5], (0.0, 0.0, 3.0))
    move(conn, "DEFAULT", geoid, [5], (0.0, 0.0, -3.0))
    conn.execute("SELECT tgsis.find_conflicts('north edit')")
    conn.commit()
    for action in ("merge", "refresh"):
        with pytest.raises(psycopg.Error) as caught:
            conn.execute(f"SELECT tgsis.{action}_version('north edit')")
        conn.rollback()
        hint = caught.value.diag.message_hint or ""
        assert f"`tgsis version {action} 'north edit'`" in hint, hint
        assert f"tgsis version {action} 'north edit' merges them" in (to_cli(hint) or ""), to_cli(hint)


@pytest.mark.parametrize("name", ['o\'brien "x"', "back\\slash's"])
def test_the_python_calls_psql_hints_print_name_the_version_itself(conn: Conn, name: str) -> None:
    """A psql hint that prints a Python call writes the name as a Python literal that is the name.

    (Was: ``tgsis.merge_version(conn, 'o''brien')``, an SQL literal: Python reads two adjacent strings, the
    version ``obrien`` — another version, merged if it exists; ``E'...'`` of a backslash is no Python at all.)
    """
    import ast
    import re

    geoid = make_fault(conn)
    tgsis.create_version(conn, name)
    conn.commit()
    move(conn, name, geoid, [5], (0.0, 0.0, 3.0))
    move(conn, "DEFAULT", geoid, [5], (0.0, 0.0, -3.0))
    conn.execute("SELECT tgsis.find_conflicts(%s)", (name,))
    conn.commit()
    calls = []
    for statement in (
        "SELECT tgsis.merge_version(%s)",
        "SELECT tgsis.refresh_version(%s)",
        f"SELECT tgsis.resolve_all_regions(%s, 'feature', '{geoid}', 'average')",
    ):
        with pytest.raises(psycopg.Error) as caught:
            conn.execute(statement, (name,))
        conn.rollback()
        hint = caught.value.diag.message_hint or ""
        found = re.search(r"tgsis\.(\w+)\(conn, (.*?)(?:, \d+, 'average')?\) in Python", hint)
        assert found, hint
        calls.append(found[1])
        assert ast.literal_eval(found[2]) == name, hint
        if found[1] != "resolve_all_regions":  # the CLI's words (the E'' literal of a backslash too)
            said = to_cli(hint) or ""
            assert f"tgsis version {found[1].split('_')[0]} {shlex.quote(name)} merges them" in said, said
    assert calls == ["merge_version", "refresh_version", "resolve_all_regions"]
