"""The command line's layout (issue 38): a package with one module per command group, and no SQL in it.

Every question a command asks the database is a function of the database
layer (tgsis.db), so that a change of storage is made there once, tested
there, and read the same way by the CLI, the browser view and Python callers.
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

import tgsis.cli
from tgsis.cli import _main
from tgsis.cli import commands as command_modules

CLI = Path(tgsis.cli.__file__).parent


def _sources() -> list[Path]:
    return sorted(CLI.rglob("*.py"))


def test_the_cli_is_a_package_of_command_modules() -> None:
    assert CLI.name == "cli" and (CLI / "__init__.py").is_file() and (CLI / "__main__.py").is_file()
    modules = sorted(p.stem for p in (CLI / "commands").glob("*.py") if p.stem != "__init__")
    assert len(modules) >= 10, modules
    # each top-level command is added by a function of the module that handles it
    assert all(f.__module__.startswith(command_modules.__name__ + ".") for f in _main.COMMANDS)
    parser = _main.build_parser()
    sub = next(a for a in parser._actions if a.dest == "command")
    assert sub.choices is not None
    names = list(sub.choices)
    assert [f.__name__ for f in _main.COMMANDS] == [f"add_{n}_parser" for n in names]


def test_no_sql_in_the_command_line() -> None:
    """No statement is written in the CLI: no execute(), no cursor, no psycopg.sql, no SQL keywords in strings."""
    found = []
    for path in _sources():
        if path.name == "_hints.py":  # patterns that recognize SQL in hints, to say them in the CLI's words
            continue
        tree = ast.parse(path.read_text())
        for node in ast.walk(tree):
            if isinstance(node, ast.Attribute) and node.attr in ("execute", "executemany", "cursor", "copy"):
                found.append(f"{path.name}:{node.lineno}: .{node.attr}")
            if (
                isinstance(node, ast.ImportFrom)
                and node.module in ("psycopg.sql", "psycopg")
                and any(a.name == "sql" for a in node.names)
            ):
                found.append(f"{path.name}:{node.lineno}: imports psycopg.sql")
            if (
                isinstance(node, ast.Constant)
                and isinstance(node.value, str)
                and re.search(
                    r"\bSELECT\b.*\bFROM\b|\bINSERT INTO\b|\bUPDATE\b \w+ \bSET\b|\bDELETE FROM\b", node.value
                )
            ):
                found.append(f"{path.name}:{node.lineno}: SQL text {node.value[:40]!r}")
    assert found == []


def test_the_browser_view_reads_storage_through_tgsis_db() -> None:
    """tgsis.view asks tgsis.db for what it shows: no query and no table name of its own (transaction settings
    aside), so that a change of storage is made in the database layer only."""
    import tgsis.view

    found = []
    for path in sorted(Path(tgsis.view.__file__).parent.glob("*.py")):
        for node in ast.walk(ast.parse(path.read_text())):
            if (
                isinstance(node, ast.Constant)
                and isinstance(node.value, str)
                and re.search(r"\bFROM\b|\btgsis\.\w+\(|\bINSERT\b|\bUPDATE\b|\bDELETE\b|^tgsis\.\w+$", node.value)
            ):
                found.append(f"{path.name}:{node.lineno}: {node.value[:50]!r}")
    assert found == []


def test_handlers_hand_their_results_to_renderers() -> None:
    """A command module prints --json documents only through render(args, result, text, document): no handler
    builds its JSON inline, so the text and the document of a command come from the same result."""
    found = []
    for path in sorted((CLI / "commands").glob("*.py")):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id == "emit_json":
                found.append(f"{path.name}:{node.lineno}")
    assert found == []
    modules_with_json = [p.name for p in (CLI / "commands").glob("*.py") if "render(args" in p.read_text()]
    assert len(modules_with_json) >= 10, modules_with_json


def test_the_command_lines_plumbing_lives_in_its_package() -> None:
    """What only the command uses (hints in its words, output, progress, remembered state) is private to tgsis.cli,
    not public modules beside it: no tgsis.clihints, tgsis.cliout or tgsis.clistate."""
    import importlib.util

    top = sorted(p.name for p in CLI.parent.glob("cli*.py"))
    assert top == []
    assert all(importlib.util.find_spec(f"tgsis.{name}") is None for name in ("clihints", "cliout", "clistate"))
    assert {p.name for p in CLI.glob("_*.py")} >= {"_hints.py", "_output.py", "_progress.py", "_state.py"}
