"""``tgsis view``: the database in a browser."""

from __future__ import annotations

import argparse
from typing import Any

from tgsis.cli._arguments import add_command, integer
from tgsis.cli._connection import split_version
from tgsis.cli._output import out
from tgsis.db import versions as V
from tgsis.db.connect import connect, resolve_target
from tgsis.db.install import installed_version
from tgsis.errors import (
    Error,
    NotFoundError,
)


def cmd_view(args: argparse.Namespace) -> int:
    from psycopg.conninfo import conninfo_to_dict, make_conninfo

    from tgsis.db.connect import local_dsn

    try:
        # the extra's libraries, checked before anything starts
        import jinja2  # noqa: F401
        import starlette  # noqa: F401
        import uvicorn  # noqa: F401

        from tgsis.view import serve
    except ImportError as exc:
        raise Error(
            f"tgsis view needs the optional extra 'view' ({exc.name} is not installed)",
            hint="pip install 'tgsis[view]'",
        ) from exc
    target = resolve_target(args.dsn)
    if target.dsn is None:
        conninfo = local_dsn(args.db or "tgsis")
    else:
        conninfo = make_conninfo(target.dsn, dbname=args.db) if args.db else target.dsn
    with connect(conninfo) as conn:
        if installed_version(conn) is None:
            raise NotFoundError(
                f"tgsis is not installed in database {conn.info.dbname}",
                hint="tgsis db install, or --db NAME for another database of the server (the demo's: --db tgsis_demo)",
            )
        if args.in_version:
            name, revision = split_version(args.in_version)
            if revision is None:
                V.goto_version(conn, name, local=True)
            else:
                V.goto_revision(conn, name, revision, local=True)
        database = conn.info.dbname
    shown = conninfo_to_dict(conninfo).get("dbname") or database
    serve(
        conninfo,
        host=args.host,
        port=args.port,
        writable=args.writable,
        database=str(shown),
        open_browser=args.open,
        default_version=args.in_version,
        on_listening=lambda url: out(
            f"tgsis view of database {shown} "
            f"({'writable' if args.writable else 'read-only'}) at {url} (Ctrl-C stops it)"
        ),
    )
    return 0


def add_view_parser(commands: Any) -> None:
    """``tgsis view``."""
    view = add_command(
        commands,
        "view",
        "look at the database in a browser: classes, features, versions, "
        "surfaces in 3D through time, versions compared (the extra tgsis[view])",
        [
            "tgsis view --open",
            "tgsis view --db tgsis_demo   # after tgsis demo",
            "tgsis --dsn 'host=db.example.org dbname=geo' view --port 8080",
        ],
        cmd_view,
    )
    view.add_argument(
        "--port", type=integer(0, 65535), default=8765, help="TCP port to listen on (default: 8765; 0: any free port)"
    )
    view.add_argument(
        "--host", default="127.0.0.1", help="address to listen on (default: 127.0.0.1, this machine only)"
    )
    view.add_argument("--db", metavar="NAME", help="another database of the same server (e.g. tgsis_demo, the demo's)")
    view.add_argument("--open", action="store_true", help="open the system's web browser on the first page")
    view.add_argument(
        "--writable", action="store_true", help="leave transactions writable (default: every transaction is read-only)"
    )
