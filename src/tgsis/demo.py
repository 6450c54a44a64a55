"""The demo scenario behind ``tgsis demo`` (the README's first command).

It connects (starting the local server when no DSN is given), makes sure tgsis
is installed, and reports what it talks to. Later parts of the product extend
it with the application scenarios (salt dome, versions of a fault model, ...).
"""

from __future__ import annotations

from collections.abc import Callable

from tgsis.db.connect import connect, resolve_target
from tgsis.db.install import install, installed_version

__all__ = ["run_demo"]


def run_demo(dsn: str | None = None, *, out: Callable[[str], None] = print) -> None:
    """Run the demo against ``dsn`` (``None``: the local server).

    Parameters
    ----------
    dsn : str, optional
        Where to run it; see :func:`tgsis.connect`.
    out : callable
        Receives each line of the report.
    """
    target = resolve_target(dsn)
    with connect(dsn) as conn:
        install(conn)
        current = installed_version(conn)
        assert current is not None
        row = conn.execute("SELECT tgsis.version(), current_setting('server_version')").fetchone()
        assert row is not None
        tgsis_version, server_version = row
        roles = [r[0] for r in conn.execute(
            "SELECT rolname FROM pg_roles WHERE rolname LIKE 'tgsis\\_%' ORDER BY oid").fetchall()]
        dbname, server_dsn = conn.info.dbname, conn.info.dsn
    out(f"PostgreSQL {server_version}, database {dbname!r} ({target.source})")
    out(f"tgsis {tgsis_version} (installed as {current.method})")
    out(f"roles: {', '.join(roles)}")
    if target.dsn is None:
        from tgsis.db.connect import local_dsn

        out(f"dsn: {local_dsn()}")
        out("the local server stops when this command ends; `tgsis local start` keeps it running")
    else:
        out(f"dsn: {server_dsn}")
