"""One UPDATE of a million rows through a versioned view vs the same UPDATE of a plain table (issue 36, point 2).

A table of ``--rows`` rows (default 1,000,000) whose object key is its
primary key (one object per row: the case where a flush used to take one
advisory lock per row and failed with 53200 from some 10,000 rows on a
default server) is versioned; a plain table holds the same rows. In the same
process, on a throwaway server with the default ``max_locks_per_transaction``
and ``max_connections``, we time

- ``view_update_1m``: ``UPDATE t SET val = val + 1`` through the view while
  the rows are inherited (of revision 0, as enable_versioning left them):
  each row is closed in the working revision and written anew;
- ``view_update_1m_own``: the same once the rows are the working revision's
  own: changed in place;

each against ``UPDATE plain SET val = val + 1``, every repetition rolled back
and both tables vacuumed between repetitions (not timed). The target is
≤ 10× the plain table (docs/performance.md).

    python bench/view_bulk_update.py [--rows 1000000] [--repeat 3]    # TGSIS_PG=system|embedded
"""

from __future__ import annotations

import argparse
import statistics
import time
from typing import Any

import psycopg

import tgsis
from tgsis.db.local import LocalServer, find_binaries

Conn = psycopg.Connection[Any]

UPDATE = "UPDATE {t} SET val = val + 1"


def vacuum(conn: Conn, *tables: str) -> None:
    conn.commit()
    conn.autocommit = True
    for table in tables:
        conn.execute(f"VACUUM ANALYZE {table}")
    conn.autocommit = False


def timed_update(conn: Conn, table: str, rows: int) -> float:
    start = time.perf_counter()
    count = conn.execute(UPDATE.format(t=table)).rowcount
    elapsed = time.perf_counter() - start
    assert count == rows, (table, count)
    queued = conn.execute("SELECT count(*) FROM t_ver_queue").fetchone()
    assert queued == (0,), queued
    conn.rollback()
    return elapsed


def paired(conn: Conn, rows: int, repeat: int) -> tuple[float, float]:
    """Median seconds of the view's UPDATE and the plain table's, run alternately, each rolled back."""
    view: list[float] = []
    plain: list[float] = []
    for _ in range(repeat):
        view.append(timed_update(conn, "t", rows))
        vacuum(conn, "t_ver", "t_ver_queue")
        plain.append(timed_update(conn, "plain", rows))
        vacuum(conn, "plain")
    return statistics.median(view), statistics.median(plain)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--rows", type=int, default=1_000_000)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()

    binaries = find_binaries()
    print(f"server: {binaries.describe()} (throwaway cluster, fsync off)")
    server = LocalServer.throwaway(binaries)
    try:
        with psycopg.connect(server.dsn(), autocommit=True) as admin:
            admin.execute("CREATE DATABASE bench")
        with psycopg.connect(server.dsn("bench")) as conn:
            tgsis.install(conn, method="sql")  # this checkout's SQL
            settings = conn.execute(
                "SELECT current_setting('max_locks_per_transaction'), current_setting('max_connections'), "
                "current_setting('shared_buffers'), tgsis.object_lock_limit()"
            ).fetchone()
            assert settings is not None
            print(
                f"max_locks_per_transaction {settings[0]}, max_connections {settings[1]}, "
                f"shared_buffers {settings[2]}: a flush locks up to {settings[3]} objects one by one"
            )
            for table in ("t", "plain"):
                conn.execute(f"CREATE TABLE {table} (id int PRIMARY KEY, val int NOT NULL, note text)")
                conn.execute(
                    f"INSERT INTO {table} SELECT g, g, 'row ' || g FROM generate_series(1, %s) g",  # noqa: S608
                    (args.rows,),
                )
            conn.commit()
            tgsis.enable_versioning(conn, "t", "id", "row")
            conn.commit()
            vacuum(conn, "t_ver", "plain")
            figures = {"view_update_1m": paired(conn, args.rows, args.repeat)}
            conn.execute(UPDATE.format(t="t"))  # the rows become the working revision's own
            conn.commit()
            vacuum(conn, "t_ver", "t_ver_queue")
            figures["view_update_1m_own"] = paired(conn, args.rows, args.repeat)
    finally:
        server.destroy()

    for name, (view, plain) in figures.items():
        print(f"{name:20s} versioned view {view:8.2f} s   plain table {plain:8.2f} s")
    for name, (view, plain) in figures.items():
        print(f"{name}_s: {view:.2f}")
        print(f"{name}_plain_s: {plain:.2f}")
        print(f"{name}_vs_plain: {view / plain:.2f}")


if __name__ == "__main__":
    main()
