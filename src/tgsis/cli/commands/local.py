"""``tgsis local``: the local PostgreSQL server tgsis runs by itself."""

from __future__ import annotations

import argparse
import sys
from dataclasses import dataclass
from typing import Any

from tgsis.cli._arguments import add_command
from tgsis.cli._output import out, render
from tgsis.db.connect import connect
from tgsis.db.install import install
from tgsis.db.local import LocalServer, find_binaries

# --------------------------------------------------------------------------- local


def _local_server() -> LocalServer:
    return LocalServer.persistent(find_binaries())


def cmd_local_start(args: argparse.Namespace) -> int:
    server = _local_server()
    started = server.start_explicitly()
    server.ensure_database("tgsis")
    with connect(server.dsn("tgsis")) as conn:
        install(conn)
    out(("started" if started else "already running:") + f" {server.binaries.describe()} in {server.root}")
    out(server.dsn("tgsis"))
    return 0


def cmd_local_stop(args: argparse.Namespace) -> int:
    server = _local_server()
    stopped = server.stop_explicitly(force=args.force)
    out(f"stopped the server in {server.root}" if stopped else f"no server was running in {server.root}")
    return 0


def cmd_local_status(args: argparse.Namespace) -> int:
    server = _local_server()
    running = server.is_running()
    state = LocalStatus(
        cluster=str(server.root),
        binaries=server.binaries.describe(),
        running=running,
        initialized=server.is_initialized(),
        pid=server.pid() if running else None,
        started_by=server.started_by() if running else None,
        dsn=server.dsn("tgsis"),
    )
    render(args, state, local_status_text, local_status_json)
    return 0 if running else 3


@dataclass(frozen=True)
class LocalStatus:
    """The local server: its cluster folder, binaries, whether it runs (pid, who started it: None is outside
    tgsis) and the DSN of its tgsis database."""

    cluster: str
    binaries: str
    running: bool
    initialized: bool
    pid: int | None
    started_by: str | None
    dsn: str


def local_status_text(args: argparse.Namespace, state: LocalStatus) -> None:
    out(f"cluster:  {state.cluster}")
    out(f"binaries: {state.binaries}")
    if state.running:
        out(f"status:   running (pid {state.pid}, started {state.started_by or 'outside tgsis'})")
        out(f"dsn:      {state.dsn}")
    else:
        out("status:   " + ("stopped" if state.initialized else "not created yet"))


def local_status_json(state: LocalStatus) -> dict[str, Any]:
    return {
        "cluster": state.cluster,
        "binaries": state.binaries,
        "status": "running" if state.running else "stopped" if state.initialized else "not created",
        "pid": state.pid,
        "started_by": (state.started_by or "outside tgsis") if state.running else None,
        "dsn": state.dsn,
    }


def cmd_local_dsn(args: argparse.Namespace) -> int:
    server = _local_server()
    out(server.dsn("tgsis"))
    if not server.is_running():
        print("note: the server is not running; `tgsis local start` starts it", file=sys.stderr)
    return 0


def add_local_parser(commands: Any) -> None:
    """``tgsis local start|stop|status|dsn``."""
    local = add_command(
        commands,
        "local",
        "the local PostgreSQL server tgsis runs by itself",
        ['tgsis local start && psql "$(tgsis local dsn)"'],
    )
    local_commands = local.add_subparsers(dest="local_command", metavar="ACTION", required=True)
    add_command(local_commands, "start", "start it and keep it running", ["tgsis local start"], cmd_local_start)
    local_stop = add_command(local_commands, "stop", "stop it", ["tgsis local stop"], cmd_local_stop)
    local_stop.add_argument("--force", action="store_true", help="stop it even while other tgsis commands use it")
    add_command(
        local_commands,
        "status",
        "where it is and whether it runs (exit 3: stopped)",
        ["tgsis local status", "tgsis local status --json"],
        cmd_local_status,
        tabular=False,
    )
    add_command(local_commands, "dsn", "print its connection string", ['psql "$(tgsis local dsn)"'], cmd_local_dsn)
