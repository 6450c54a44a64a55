"""Argument types and the making of sub-commands, shared by the command modules."""

from __future__ import annotations

import argparse
from collections.abc import Callable, Sequence
from typing import Any

from tgsis.errors import InvalidInputError

Handler = Callable[[argparse.Namespace], int]


def integer(low: int, high: int) -> Callable[[str], int]:
    """An argparse type: an integer from ``low`` to ``high`` (the range of its SQL column), else a usage error."""
    def integer(text: str) -> int:
        value = int(text)  # ValueError: argparse says "invalid integer value"
        if not low <= value <= high:
            raise argparse.ArgumentTypeError(f"{value} is out of range: from {low} to {high}")
        return value
    return integer


FEATURE_ID = integer(-(2**63), 2**63 - 1)     # feature ids (bigint)
INT4 = integer(-(2**31), 2**31 - 1)   # SRS ids, orders (integer)


def output_options(json_only: bool = False) -> argparse.ArgumentParser:
    """``--json`` (and, for tables, ``--no-header``): the options of every command that lists or reports."""
    parent = argparse.ArgumentParser(add_help=False)
    parent.add_argument("--json", action="store_true",
                        help="print one JSON document (its keys: docs/cli.md) instead of lines for people")
    if not json_only:
        parent.add_argument("--no-header", action="store_true", help="leave out the header line of the table")
    return parent


def add_command(commands: Any, name: str, help: str, examples: Sequence[str], handler: Handler | None = None,
             tabular: bool | None = None) -> argparse.ArgumentParser:
    """A sub-command with its help, its examples (shown by ``--help``), and ``--json`` when it lists or reports.

    ``tabular``: None, no output options; False, ``--json``; True, ``--json`` and ``--no-header``.
    """
    parents = [] if tabular is None else [output_options(json_only=not tabular)]
    parser: argparse.ArgumentParser = commands.add_parser(
        name, help=help, description=help, parents=parents, formatter_class=argparse.RawDescriptionHelpFormatter,
        epilog=("example:\n" if len(examples) == 1 else "examples:\n") + "\n".join(f"  {e}" for e in examples))
    if handler is not None:
        parser.set_defaults(handler=handler)
    return parser


GEOTYPES = ("MULTIPOINT", "MULTILINESTRING", "SURFACE", "MULTITETRA", "GEOMETRYCOLLECTION", "GMAP")


def feature_values(items: Sequence[str] | None) -> dict[str, str]:
    values = {}
    for item in items or []:
        name, sep, value = item.partition("=")
        if not sep or not name:
            raise InvalidInputError(f"--set {item!r} must be NAME=VALUE")
        values[name] = value
    return values
