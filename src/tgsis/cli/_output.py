"""What commands print: lines for people, tables, or (``--json``) one document (through cliout)."""

from __future__ import annotations

import argparse
from collections.abc import Sequence
from typing import Any

from tgsis import cliout


def out(text: str) -> None:
    cliout.out(text)


def wants_json(args: argparse.Namespace) -> bool:
    """Whether the command prints one JSON document (``--json``) instead of lines for people."""
    return bool(getattr(args, "json", False))


def print_table(args: argparse.Namespace, header: Sequence[str], rows: Sequence[Sequence[Any]]) -> None:
    """Tab-separated rows under a header line (``--no-header`` leaves it out)."""
    cliout.table(header, rows, header_shown=not getattr(args, "no_header", False))
