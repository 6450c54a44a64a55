"""What the ``tgsis`` command prints: lines, tables with headers, ``--json`` documents, broken pipes.

Kept in one place so that every command prints the same way:

* :func:`out` writes one line to standard output. When the reader of a pipe
  goes away (``tgsis ls | head -1``), the rest of the output is dropped
  silently and the command *goes on* to its end: a check-in piped into
  ``head`` still updates its check-out record, and exits 0.
* :func:`print_table` prints rows as tab-separated values under a header
  line (``--no-header`` leaves it out).
* :func:`emit_json` prints one JSON document (``--json``): strict JSON (no
  ``NaN``), non-finite numbers as the strings ``"Infinity"``,
  ``"-Infinity"``, ``"NaN"``, times as ISO 8601 with every digit.
* :func:`show_time` and :func:`show_moment` round model times and wall-clock
  times for people (``--json`` keeps them exact).
* :func:`render` is how a command shows its result: a handler computes the
  result (plain data: a dataclass, a list), and hands it with its two
  renderers — ``text(args, result)`` printing lines for people, and
  ``document(result)`` returning the ``--json`` document — to :func:`render`,
  which calls the one the flags ask for. The renderers read no database.

Progress on standard error is :mod:`tgsis.cli._progress`'s.
"""

from __future__ import annotations

import argparse
import contextlib
import datetime
import json
import math
import os
import sys
from collections.abc import Callable, Mapping, Sequence
from typing import Any, TypeVar

import numpy as np

_closed = False


def stdout_closed() -> bool:
    """Whether the reader of standard output went away (the rest of the output was dropped)."""
    return _closed


def drop_stdout() -> None:
    """Point standard output at /dev/null: the reader is gone, later writes (and the flush at exit) go nowhere."""
    global _closed
    _closed = True
    with contextlib.suppress(OSError, ValueError):
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        os.close(devnull)


def out(text: str) -> None:
    """Print one line to standard output, flushed; nothing once its reader went away."""
    if _closed:
        return
    try:
        print(text, flush=True)
    except BrokenPipeError:
        drop_stdout()


def table(header: Sequence[str], rows: Sequence[Sequence[Any]], *, header_shown: bool = True) -> None:
    """Rows as tab-separated lines under a header line of the column names (no line at all for no rows)."""
    if header_shown and rows:
        out("\t".join(header))
    for row in rows:
        out("\t".join("" if v is None else str(v) for v in row))


def jsonable(value: Any) -> Any:
    """``value`` as plain JSON values: numpy scalars and arrays, datetimes, paths, tuples, non-finite floats."""
    if isinstance(value, Mapping):
        return {str(k): jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple, set, frozenset)):
        return [jsonable(v) for v in value]
    if isinstance(value, np.ndarray):
        return jsonable(value.tolist())
    if isinstance(value, np.generic):
        return jsonable(value.item())
    if isinstance(value, bool) or value is None or isinstance(value, (int, str)):
        return value
    if isinstance(value, float):
        if math.isfinite(value):
            return value
        return "NaN" if math.isnan(value) else ("Infinity" if value > 0 else "-Infinity")
    if isinstance(value, (datetime.datetime, datetime.date, datetime.time)):
        return value.isoformat()
    if isinstance(value, os.PathLike):
        return os.fspath(value)
    return str(value)


def emit_json(document: Mapping[str, Any]) -> None:
    """Print one JSON document (strict JSON: ``allow_nan=False``) on standard output."""
    out(json.dumps(jsonable(document), allow_nan=False, ensure_ascii=False))


def show_time(t: float) -> str:
    """A model time for people: 12 significant digits (``-1.9``, not ``-1.9000000000000001``)."""
    if not math.isfinite(t):
        return repr(t)
    text = f"{t:.12g}"
    return text if ("e" in text or "." in text) else f"{text}.0"


def show_moment(moment: datetime.datetime | None) -> str:
    """A wall-clock time for people: to the second, with its UTC offset."""
    if moment is None:
        return ""
    return moment.replace(microsecond=0).isoformat(sep=" ")


def wants_json(args: argparse.Namespace) -> bool:
    """Whether the command prints one JSON document (``--json``) instead of lines for people."""
    return bool(getattr(args, "json", False))


def print_table(args: argparse.Namespace, header: Sequence[str], rows: Sequence[Sequence[Any]]) -> None:
    """Tab-separated rows under a header line (``--no-header`` leaves it out)."""
    table(header, rows, header_shown=not getattr(args, "no_header", False))


Result = TypeVar("Result")


def render(
    args: argparse.Namespace,
    result: Result,
    text: Callable[[argparse.Namespace, Result], None],
    document: Callable[[Result], Mapping[str, Any]],
) -> int:
    """Show a command's ``result``: ``document(result)`` as one JSON document with ``--json``, else ``text``.

    Returns the command's exit status (0).
    """
    if wants_json(args):
        emit_json(document(result))
    else:
        text(args, result)
    return 0
