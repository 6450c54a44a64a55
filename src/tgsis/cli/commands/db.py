"""``tgsis db``: install, upgrade or inspect tgsis in a database."""

from __future__ import annotations

import argparse
from dataclasses import dataclass
from typing import Any

from tgsis.cli._arguments import add_command
from tgsis.cli._output import out, render
from tgsis.db.connect import connect, resolve_target
from tgsis.db.inspect import server_version
from tgsis.db.install import InstallationStatus, install, installation_status, uninstall
from tgsis.errors import (
    Error,
)

# --------------------------------------------------------------------------- db


def cmd_db_install(args: argparse.Namespace) -> int:
    with connect(args.dsn) as conn:
        result = install(conn, method=args.method, storage=args.storage)
    if result.action == "unchanged":
        out(
            f"tgsis {result.version} is already installed ({result.method})"
            + (": nothing to do" if not result.steps else "")
        )
    elif result.action == "upgraded":
        out(f"upgraded tgsis {result.previous_version} -> {result.version} ({result.method})")
    else:
        out(f"installed tgsis {result.version} ({result.method})")
    for step in result.steps:
        out(f"  {step}")
    for statement in result.still_needed:
        out(
            f"still needed: a DBA runs `{statement}` (tgsis's owner registers classes and versions features "
            "as a member of tgsis_admin)"
        )
    return 0


def cmd_db_uninstall(args: argparse.Namespace) -> int:
    if not args.yes:
        raise Error(
            "uninstall removes every tgsis object and its data from the database", hint="repeat with --yes to do it"
        )
    with connect(args.dsn) as conn:
        removed = uninstall(conn, cascade=args.cascade)
    out(f"removed tgsis {removed.version} ({removed.method})" if removed else "tgsis was not installed")
    return 0


def cmd_db_status(args: argparse.Namespace) -> int:
    target = resolve_target(args.dsn)
    with connect(args.dsn) as conn:
        status = installation_status(conn)
        server = server_version(conn)
        db = conn.info.dbname
    render(args, DatabaseStatus(db, target.source, server, status), status_text, status_json)
    return 0 if status.ok else 1


@dataclass(frozen=True)
class DatabaseStatus:
    """The database a command reaches (and why that one), its server, and the state of tgsis in it."""

    database: str
    source: str
    server: str | None
    status: InstallationStatus


def status_text(args: argparse.Namespace, result: DatabaseStatus) -> None:
    status, current = result.status, result.status.installed
    out(f"database: {result.database} (from {result.source})")
    out(f"server:   {result.server or '?'}")
    fingerprint = (
        "unknown: this role may not read tgsis.installation"
        if current and current.fingerprint is None
        else (current.fingerprint if current else None) or "none recorded"
    )
    installed = f"{current.version} ({current.method}, fingerprint {fingerprint})" if current else "not installed"
    out(f"tgsis:    {installed}")
    out(f"client:   {status.client_version} (fingerprint {status.client_fingerprint})")
    if status.missing_storage:
        out(f"storage:  missing {len(status.missing_storage)} table(s): {', '.join(status.missing_storage)}")
    if status.ok:
        out("state:    up to date")
    else:
        out(f"state:    {status.state}: {status.problem}")
        out(f"{'upgrade' if status.state == 'upgrade' else 'fix'}: {status.fix}")


def status_json(result: DatabaseStatus) -> dict[str, Any]:
    status, current = result.status, result.status.installed
    return {
        "database": result.database,
        "source": result.source,
        "server": result.server,
        "tgsis": current.version if current else None,
        "method": current.method if current else None,
        "fingerprint": current.fingerprint if current else None,
        "client": status.client_version,
        "client_fingerprint": status.client_fingerprint,
        "missing_storage": list(status.missing_storage),
        "state": status.state,
        "problem": status.problem,
        "fix": status.fix,
    }


def add_db_parser(commands: Any) -> None:
    """``tgsis db install|uninstall|status``."""
    db = add_command(
        commands,
        "db",
        "install, upgrade or inspect tgsis in a database",
        ["tgsis --dsn 'host=db.example.org dbname=geo' db install"],
    )
    db_commands = db.add_subparsers(dest="db_command", metavar="ACTION", required=True)
    db_install = add_command(
        db_commands,
        "install",
        "install or upgrade tgsis (a no-op when up to date)",
        [
            "tgsis db install",
            "tgsis db install --method sql   # managed PostgreSQL",
            "tgsis db install --storage rows   # model 1 stored as rows",
        ],
        cmd_db_install,
    )
    db_install.add_argument(
        "--method",
        choices=("auto", "extension", "sql"),
        default="auto",
        help="extension: CREATE EXTENSION (needs the files on the server); "
        "sql: run the script from the client; auto: extension when available",
    )
    db_install.add_argument(
        "--storage",
        choices=("chunks", "rows"),
        default="chunks",
        help="how model 1's vertices and simplices are stored when created, or switched by an upgrade: "
        "chunks (the default, docs/storage.md) or rows",
    )
    db_uninstall = add_command(
        db_commands,
        "uninstall",
        "remove tgsis and all its data from the database",
        ["tgsis db uninstall --yes"],
        cmd_db_uninstall,
    )
    db_uninstall.add_argument("--yes", action="store_true", help="really do it")
    db_uninstall.add_argument("--cascade", action="store_true", help="also drop objects that depend on tgsis")
    add_command(
        db_commands,
        "status",
        "the database's tgsis against this client's (exit 1 unless up to date)",
        ["tgsis db status", "tgsis db status --json"],
        cmd_db_status,
        tabular=False,
    )
