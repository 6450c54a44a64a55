"""The ``tgsis`` command line (see docs/cli.md).

Every command that needs a database takes ``--dsn``; without it the database
comes from ``$TGSIS_DSN``, libpq's ``PG*`` variables, or the local server that
tgsis starts for the command and stops afterwards (``tgsis local start`` keeps
one running).
"""

from __future__ import annotations

import argparse
import logging
import os
import signal
import sys
from collections.abc import Callable, Sequence
from typing import NoReturn

import tgsis
from tgsis.db.connect import connect, release_local_server, resolve_target
from tgsis.db.install import install, installed_version, uninstall
from tgsis.db.local import LocalServer, find_binaries
from tgsis.errors import Error

__all__ = ["main", "build_parser"]

Handler = Callable[[argparse.Namespace], int]


def _out(text: str) -> None:
    print(text, flush=True)


# --------------------------------------------------------------------------- db


def cmd_db_install(args: argparse.Namespace) -> int:
    with connect(args.dsn) as conn:
        result = install(conn, method=args.method)
    if result.action == "unchanged":
        _out(f"tgsis {result.version} is already installed ({result.method}): nothing to do")
    elif result.action == "upgraded":
        _out(f"upgraded tgsis {result.previous_version} -> {result.version} ({result.method})")
    else:
        _out(f"installed tgsis {result.version} ({result.method})")
    return 0


def cmd_db_uninstall(args: argparse.Namespace) -> int:
    if not args.yes:
        raise Error("uninstall removes every tgsis object and its data from the database",
                    hint="repeat with --yes to do it")
    with connect(args.dsn) as conn:
        removed = uninstall(conn, cascade=args.cascade)
    _out(f"removed tgsis {removed.version} ({removed.method})" if removed else "tgsis was not installed")
    return 0


def cmd_db_status(args: argparse.Namespace) -> int:
    target = resolve_target(args.dsn)
    with connect(args.dsn) as conn:
        current = installed_version(conn)
        server = conn.execute("SELECT version()").fetchone()
        db = conn.info.dbname
    _out(f"database: {db} (from {target.source})")
    _out(f"server:   {server[0] if server else '?'}")
    _out(f"tgsis:    {f'{current.version} ({current.method})' if current else 'not installed'}")
    _out(f"client:   {tgsis.__version__}")
    return 0


# --------------------------------------------------------------------------- local


def _local_server() -> LocalServer:
    return LocalServer.persistent(find_binaries())


def cmd_local_start(args: argparse.Namespace) -> int:
    server = _local_server()
    started = server.start_explicitly()
    server.ensure_database("tgsis")
    with connect(server.dsn("tgsis")) as conn:
        install(conn)
    _out(("started" if started else "already running:") + f" {server.binaries.describe()} in {server.root}")
    _out(server.dsn("tgsis"))
    return 0


def cmd_local_stop(args: argparse.Namespace) -> int:
    server = _local_server()
    stopped = server.stop_explicitly(force=args.force)
    _out(f"stopped the server in {server.root}" if stopped else f"no server was running in {server.root}")
    return 0


def cmd_local_status(args: argparse.Namespace) -> int:
    server = _local_server()
    running = server.is_running()
    _out(f"cluster:  {server.root}")
    _out(f"binaries: {server.binaries.describe()}")
    if running:
        _out(f"status:   running (pid {server.pid()}, started {server.started_by() or 'outside tgsis'})")
        _out(f"dsn:      {server.dsn('tgsis')}")
    else:
        _out("status:   " + ("stopped" if server.is_initialized() else "not created yet"))
    return 0 if running else 3


def cmd_local_dsn(args: argparse.Namespace) -> int:
    server = _local_server()
    _out(server.dsn("tgsis"))
    if not server.is_running():
        print("note: the server is not running; `tgsis local start` starts it", file=sys.stderr)
    return 0


# --------------------------------------------------------------------------- demo


def cmd_demo(args: argparse.Namespace) -> int:
    from tgsis.demo import run_demo

    run_demo(args.dsn, out=_out)
    return 0


# --------------------------------------------------------------------------- parser


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of the ``tgsis`` command."""
    parser = argparse.ArgumentParser(
        prog="tgsis",
        description="tgsis: spatio-temporal geoscience information system on PostgreSQL",
    )
    parser.add_argument("--version", action="version", version=f"tgsis {tgsis.__version__}")
    parser.add_argument("--dsn", help="libpq connection string (default: $TGSIS_DSN, PG* variables, "
                                      "else the local server tgsis runs itself)")
    parser.add_argument("-v", "--verbose", action="count", default=0, help="more log output (-vv: debug)")
    parser.add_argument("-q", "--quiet", action="store_true", help="errors only")
    commands = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)

    demo = commands.add_parser("demo", help="run the demo scenario")
    demo.set_defaults(handler=cmd_demo)

    db = commands.add_parser("db", help="install, upgrade or inspect tgsis in a database")
    db_commands = db.add_subparsers(dest="db_command", metavar="ACTION", required=True)
    db_install = db_commands.add_parser("install", help="install or upgrade tgsis (a no-op when up to date)")
    db_install.add_argument("--method", choices=("auto", "extension", "sql"), default="auto",
                            help="extension: CREATE EXTENSION (needs the files on the server); "
                                 "sql: run the script from the client; auto: extension when available")
    db_install.set_defaults(handler=cmd_db_install)
    db_uninstall = db_commands.add_parser("uninstall", help="remove tgsis and all its data from the database")
    db_uninstall.add_argument("--yes", action="store_true", help="really do it")
    db_uninstall.add_argument("--cascade", action="store_true", help="also drop objects that depend on tgsis")
    db_uninstall.set_defaults(handler=cmd_db_uninstall)
    db_status = db_commands.add_parser("status", help="server and tgsis versions")
    db_status.set_defaults(handler=cmd_db_status)

    local = commands.add_parser("local", help="the local PostgreSQL server tgsis runs by itself")
    local_commands = local.add_subparsers(dest="local_command", metavar="ACTION", required=True)
    local_start = local_commands.add_parser("start", help="start it and keep it running")
    local_start.set_defaults(handler=cmd_local_start)
    local_stop = local_commands.add_parser("stop", help="stop it")
    local_stop.add_argument("--force", action="store_true", help="stop it even while other tgsis commands use it")
    local_stop.set_defaults(handler=cmd_local_stop)
    local_status = local_commands.add_parser("status", help="where it is and whether it runs (exit 3: stopped)")
    local_status.set_defaults(handler=cmd_local_status)
    local_dsn = local_commands.add_parser("dsn", help="print its connection string")
    local_dsn.set_defaults(handler=cmd_local_dsn)
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
    signal.signal(signal.SIGTERM, _exit_on_sigterm)
    handler: Handler = args.handler
    try:
        return handler(args)
    except Error as exc:
        print(f"tgsis: error: {exc}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print("tgsis: interrupted", file=sys.stderr)
        return 130
    finally:
        release_local_server()


if __name__ == "__main__":
    sys.exit(main())
