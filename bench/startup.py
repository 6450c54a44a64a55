"""Cost of the foundations: starting a local server, a fresh test database, installing tgsis.

Baselines in the same run: CREATE DATABASE from template0 (what any test
database costs) for the per-test clone of the tgsis template, and
CREATE EXTENSION for the client's plain-SQL install.

    python bench/startup.py            # TGSIS_PG=system|embedded picks the server
"""

from __future__ import annotations

import time
import uuid

import psycopg
from psycopg import sql
from timing import timed

import tgsis
from tgsis.db.local import LocalServer, find_binaries

REPEAT = 10


def main() -> None:
    binaries = find_binaries()
    print(f"server: {binaries.describe()}")

    start = time.perf_counter()
    server = LocalServer.throwaway(binaries)
    server_start = time.perf_counter() - start
    try:
        admin = psycopg.connect(server.dsn(), autocommit=True)

        def create(template: str) -> str:
            name = f"b_{uuid.uuid4().hex[:10]}"
            admin.execute(
                sql.SQL("CREATE DATABASE {} TEMPLATE {}").format(sql.Identifier(name), sql.Identifier(template))
            )
            return name

        template = create("template0")
        with psycopg.connect(server.dsn(template)) as conn:
            tgsis.install(conn, method="sql")

        plain_db = timed(lambda: create("template0"), REPEAT)
        tgsis_db = timed(lambda: create(template), REPEAT)

        def install(method: str) -> None:
            with psycopg.connect(server.dsn(create("template0"))) as conn:
                tgsis.install(conn, method=method)  # type: ignore[arg-type]

        empty_db_and_connect = timed(lambda: psycopg.connect(server.dsn(create("template0"))).close(), REPEAT)
        sql_install = timed(lambda: install("sql"), REPEAT) - empty_db_and_connect
        ext_install = (
            timed(lambda: install("extension"), REPEAT) - empty_db_and_connect
            if binaries.has_extension_control_path or binaries.flavor == "system"
            else float("nan")
        )
        admin.close()
    finally:
        server.destroy()

    print(f"throwaway server start (initdb + start): {server_start * 1000:.0f} ms")
    print(f"CREATE DATABASE from template0:           {plain_db * 1000:.1f} ms")
    print(f"CREATE DATABASE from the tgsis template:  {tgsis_db * 1000:.1f} ms")
    print(f"tgsis.install(method='sql'):              {sql_install * 1000:.1f} ms")
    print(f"CREATE EXTENSION tgsis:                   {ext_install * 1000:.1f} ms")
    print(f"server_start_ms: {server_start * 1000:.0f}")
    print(f"test_database_ms: {tgsis_db * 1000:.1f}")
    print(f"test_database_vs_template0: {tgsis_db / plain_db:.2f}")
    print(f"sql_install_ms: {sql_install * 1000:.1f}")
    print(f"sql_install_vs_create_extension: {sql_install / ext_install:.2f}")


if __name__ == "__main__":
    main()
