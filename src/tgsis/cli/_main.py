"""The ``tgsis`` command: its parser, made of the command modules' parsers, and ``main``."""

from __future__ import annotations

import argparse
import logging
import os
import signal
import sys
import warnings
from collections.abc import Callable, Sequence
from typing import Any, NoReturn

import tgsis
from tgsis.cli._arguments import Handler
from tgsis.cli._hints import to_cli
from tgsis.cli._output import drop_stdout
from tgsis.cli.commands import (
    checkin,
    classes,
    db,
    demo,
    gmaps,
    info,
    interpolate,
    local,
    time,
    transfer,
    versions,
    view,
)
from tgsis.db.connect import release_local_server
from tgsis.errors import Error, SkippedObjectWarning

#: The top-level commands in the order ``tgsis --help`` lists them: each module adds its own parsers.
COMMANDS: tuple[Callable[[Any], None], ...] = (
    demo.add_demo_parser,
    view.add_view_parser,
    db.add_db_parser,
    classes.add_class_parser,
    transfer.add_import_parser,
    transfer.add_export_parser,
    time.add_at_parser,
    time.add_series_parser,
    checkin.add_checkout_parser,
    checkin.add_checkin_parser,
    interpolate.add_interpolate_parser,
    interpolate.add_corners_parser,
    info.add_info_parser,
    time.add_query_parser,
    interpolate.add_cut_parser,
    info.add_ls_parser,
    versions.add_version_parser,
    versions.add_versioning_parser,
    local.add_local_parser,
    gmaps.add_gmap_parser,
    gmaps.add_extrude_parser,
    gmaps.add_slice_parser,
)


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of the ``tgsis`` command.

    Every argument has a help text and every command examples (``--help``
    shows them; tests/test_cli_help.py walks the tree and fails on one without).
    """
    parser = argparse.ArgumentParser(
        prog="tgsis",
        description="tgsis: spatio-temporal geoscience information system on PostgreSQL",
        formatter_class=argparse.RawDescriptionHelpFormatter,
        epilog="examples:\n  tgsis demo\n  tgsis --dsn 'host=db.example.org dbname=geo' ls --class faults\n"
        "  tgsis --in cfm6 version current --json\nsee docs/cli.md",
    )
    parser.add_argument(
        "--version", action="version", version=f"tgsis {tgsis.__version__}", help="print the client's version and exit"
    )
    parser.add_argument(
        "--dsn",
        help="libpq connection string (default: $TGSIS_DSN, PG* variables, else the local server tgsis runs itself)",
    )
    parser.add_argument(
        "--in",
        dest="in_version",
        metavar="VERSION[@REVISION]",
        help="work in this version, or look at one of its revisions (default: $TGSIS_VERSION, "
        "else what `tgsis version goto` chose, else DEFAULT)",
    )
    parser.add_argument("-v", "--verbose", action="count", default=0, help="more log output (-vv: debug)")
    parser.add_argument("-q", "--quiet", action="store_true", help="errors only")
    commands = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)

    for add_parser in COMMANDS:
        add_parser(commands)
    return parser


def _configure_logging(verbose: int, quiet: bool) -> None:
    level = logging.ERROR if quiet else (logging.WARNING, logging.INFO, logging.DEBUG)[min(verbose, 2)]
    if env := os.environ.get("TGSIS_LOG_LEVEL"):
        level = logging.getLevelName(env.upper()) if isinstance(logging.getLevelName(env.upper()), int) else level
    logging.basicConfig(level=level, format="%(levelname)s %(name)s: %(message)s", stream=sys.stderr)


def _exit_on_sigterm(signum: int, frame: object) -> NoReturn:
    # SystemExit runs atexit handlers, which stop a local server we started.
    sys.exit(128 + signum)


def main(argv: Sequence[str] | None = None) -> int:
    """Run the ``tgsis`` command; return its exit status."""
    parser = build_parser()
    args = parser.parse_args(argv)
    _configure_logging(args.verbose, args.quiet)
    caller_sigterm = signal.signal(signal.SIGTERM, _exit_on_sigterm)  # given back at the end (main in a program)
    handler: Handler = args.handler
    try:
        with warnings.catch_warnings():
            # objects a reader skipped (any command that reads files): one line each, not a Python warning dump
            shown = warnings.showwarning

            def one_line(
                message: Warning | str,
                category: type[Warning],
                filename: str,
                lineno: int,
                file: Any = None,
                line: str | None = None,
            ) -> None:
                if issubclass(category, SkippedObjectWarning):
                    print(f"tgsis: warning: {message}", file=sys.stderr)
                else:
                    shown(message, category, filename, lineno, file, line)

            warnings.showwarning = one_line
            return handler(args)
    except Error as exc:
        exc.hint = to_cli(exc.hint)  # the hint in this interface's words (its flags and commands)
        print(f"tgsis: error: {exc}", file=sys.stderr)
        return 1
    except BrokenPipeError:  # the reader went away while something other than _out wrote to stdout
        drop_stdout()  # stdout to /dev/null, so that the flush at exit does not fail too
        return 0
    except OSError as exc:  # a file that cannot be read or written (full disk, no right, a folder gone)
        where = f": {exc.filename}" if exc.filename else ""
        print(f"tgsis: error: {exc.strerror or exc}{where}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print("tgsis: interrupted", file=sys.stderr)
        return 130
    finally:
        release_local_server()
        if caller_sigterm is not None:  # (None: a handler not installed from Python, left alone)
            signal.signal(signal.SIGTERM, caller_sigterm)
