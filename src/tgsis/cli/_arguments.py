"""Argument types and the making of sub-commands, shared by the command modules."""

from __future__ import annotations

import argparse
import math
from collections.abc import Callable, Sequence
from typing import Any

from tgsis.datamodels import data_models
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


FEATURE_ID = integer(-(2**63), 2**63 - 1)  # feature ids (bigint)
INT4 = integer(-(2**31), 2**31 - 1)  # SRS ids, orders (integer)


def output_options(json_only: bool = False) -> argparse.ArgumentParser:
    """``--json`` (and, for tables, ``--no-header``): the options of every command that lists or reports."""
    parent = argparse.ArgumentParser(add_help=False)
    parent.add_argument(
        "--json",
        action="store_true",
        help="print one JSON document (its keys: docs/cli.md) instead of lines for people",
    )
    if not json_only:
        parent.add_argument("--no-header", action="store_true", help="leave out the header line of the table")
    return parent


def add_command(
    commands: Any,
    name: str,
    help: str,
    examples: Sequence[str],
    handler: Handler | None = None,
    tabular: bool | None = None,
) -> argparse.ArgumentParser:
    """A sub-command with its help, its examples (shown by ``--help``), and ``--json`` when it lists or reports.

    ``tabular``: None, no output options; False, ``--json``; True, ``--json`` and ``--no-header``.
    """
    parents = [] if tabular is None else [output_options(json_only=not tabular)]
    parser: argparse.ArgumentParser = commands.add_parser(
        name,
        help=help,
        description=help,
        parents=parents,
        formatter_class=argparse.RawDescriptionHelpFormatter,
        epilog=("example:\n" if len(examples) == 1 else "examples:\n") + "\n".join(f"  {e}" for e in examples),
    )
    if handler is not None:
        parser.set_defaults(handler=handler)
    return parser


# the geotypes of every data model, in the registry's order (tgsis.datamodels: no list typed here)
GEOTYPES = tuple(dict.fromkeys(g for m in data_models() for g in m.geotypes))


def feature_values(items: Sequence[str] | None) -> dict[str, str]:
    values = {}
    for item in items or []:
        name, sep, value = item.partition("=")
        if not sep or not name:
            raise InvalidInputError(f"--set {item!r} must be NAME=VALUE")
        values[name] = value
    return values


def box(text: str) -> list[float]:
    """An argparse type: ``XMIN,YMIN,ZMIN,XMAX,YMAX,ZMAX``, each min at most its max, else a usage error."""
    try:
        values = [float(part) for part in text.split(",")]
    except ValueError:
        values = []
    if len(values) != 6 or not all(math.isfinite(v) for v in values):
        raise argparse.ArgumentTypeError(f"{text!r} is not six numbers XMIN,YMIN,ZMIN,XMAX,YMAX,ZMAX")
    if any(values[i] > values[i + 3] for i in range(3)):
        raise argparse.ArgumentTypeError(
            f"{text!r}: each minimum must be at most its maximum (XMIN,YMIN,ZMIN,XMAX,YMAX,ZMAX)"
        )
    return values


def property_filters(items: Sequence[str] | None) -> dict[str, str]:
    """``--property NAME=VALUE`` items of a filter, by name (one value per name)."""
    values: dict[str, str] = {}
    for item in items or []:
        name, sep, value = item.partition("=")
        if not sep or not name:
            raise InvalidInputError(f"--property {item!r} must be NAME=VALUE", hint="e.g. --property release=6.1")
        if name in values and values[name] != value:
            raise InvalidInputError(f"--property {name} is given twice, as {values[name]!r} and {value!r}")
        values[name] = value
    return values
