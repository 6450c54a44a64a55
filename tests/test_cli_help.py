"""Every argument of the `tgsis` command has help text, and every command an example (shown by --help)."""

from __future__ import annotations

import argparse
from collections.abc import Iterator

import pytest

from tgsis.cli import build_parser


def _commands(
    parser: argparse.ArgumentParser, path: tuple[str, ...] = ()
) -> Iterator[tuple[tuple[str, ...], argparse.ArgumentParser]]:
    yield path, parser
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                yield from _commands(sub, (*path, name))


COMMANDS = list(_commands(build_parser()))


def test_the_walk_finds_the_commands() -> None:
    names = {" ".join(path) for path, _ in COMMANDS}
    assert {"ls", "import", "version conflicts", "version tree", "local dsn", "class list"} <= names
    assert len(names) > 45


@pytest.mark.parametrize("path, parser", COMMANDS, ids=[" ".join(p) or "tgsis" for p, _ in COMMANDS])
def test_every_argument_has_help_and_every_command_an_example(
    path: tuple[str, ...], parser: argparse.ArgumentParser
) -> None:
    missing = [
        a.dest
        for a in parser._actions
        if not isinstance(a, argparse._SubParsersAction) and (not a.help or a.help == argparse.SUPPRESS)
    ]
    assert not missing, f"tgsis {' '.join(path)}: arguments without help: {missing}"
    assert parser.epilog and "example" in parser.epilog and "tgsis" in parser.epilog, (
        f"tgsis {' '.join(path)} has no example"
    )
    assert not path or path[-1] in parser.epilog, f"the example of tgsis {' '.join(path)} does not use it"
    assert "example" in parser.format_help()  # --help shows it as written


def test_commands_that_list_or_report_take_json() -> None:
    takes = {" ".join(path) for path, parser in COMMANDS if any(a.dest == "json" for a in parser._actions)}
    assert {
        "ls",
        "class list",
        "version list",
        "version tree",
        "version conflicts",
        "version diff",
        "version current",
        "import",
        "checkin",
        "series",
        "info",
        "query",
        "db status",
        "version locks",
        "version privileges",
        "version chain",
        "version compress",
        "versioning list",
        "corners",
    } <= takes
