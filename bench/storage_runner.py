"""What acting on a table another role owns costs tgsis's version functions (the runner path).

tgsis's definer code runs its statements on storage tgsis's owner owns
directly, and on storage another role owns through that table's runner
(``<table>_ver_run()``, called as ``tgsis_nobody``, the call recorded for the
runner to check): docs/security.md, "A table's own code runs as the table's
owner". Two databases of one server hold the same versioned table
(``--objects`` objects of ``--rows`` rows), owned by tgsis's owner in one, by
an admin role in the other. Each round, in each database in turn, a version
edits 1 % of the rows and is merged back, and a second version edits the
same share and is deleted (medians of ``--repeat`` rounds). Ratios are other
owner / tgsis's owner.

    python bench/storage_runner.py [--objects 100] [--rows 2000] [--repeat 7]    # TGSIS_PG=system|embedded
"""

from __future__ import annotations

import argparse
import itertools
import statistics
from typing import Any

import psycopg
from timing import timed

import tgsis
from tgsis.db.local import LocalServer, find_binaries

Conn = psycopg.Connection[Any]
_names = itertools.count()


def make_table(conn: Conn, name: str, objects: int, rows: int) -> None:
    conn.execute(f"CREATE TABLE {name} (objid int, k int, x float8, y float8, z float8, PRIMARY KEY (objid, k))")
    conn.execute(
        f"INSERT INTO {name} SELECT o, k, random(), random(), random() "
        f"FROM generate_series(0, {objects - 1}) o, generate_series(0, {rows - 1}) k"
    )
    conn.commit()
    tgsis.enable_versioning(conn, name, "objid", name)


def edited_version(conn: Conn, table: str, objects: int) -> str:
    """A new child of DEFAULT that rewrote 1 % of the table's objects."""
    name = f"v{next(_names)}"
    tgsis.create_version(conn, name)
    with tgsis.in_version(conn, name):
        conn.execute(f"UPDATE {table} SET x = x + 1 WHERE objid < %s", (max(1, objects // 100),))
        conn.commit()
    return name


def setup(dsn: str, owner: str | None, objects: int, rows: int) -> Conn:
    """A database with one versioned table ``parts``, owned by tgsis's owner or by the admin role ``owner``."""
    conn = psycopg.connect(dsn)
    tgsis.install(conn, method="sql")  # this checkout's SQL
    if owner is not None:
        conn.execute(f"CREATE ROLE {owner} NOLOGIN IN ROLE tgsis_admin")
        conn.execute(f"GRANT CREATE ON SCHEMA public TO {owner}")
        conn.execute(f"SET ROLE {owner}")
    make_table(conn, "parts", objects, rows)
    conn.execute("RESET ROLE")
    conn.commit()
    return conn


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--objects", type=int, default=100)
    parser.add_argument("--rows", type=int, default=2000)
    parser.add_argument("--repeat", type=int, default=7)
    args = parser.parse_args()
    samples: dict[str, list[float]] = {f"{op}_{who}": [] for op in ("merge", "delete") for who in ("tgsis", "other")}
    binaries = find_binaries()
    print(f"server: {binaries.describe()} (throwaway cluster, fsync off)")
    server = LocalServer.throwaway(binaries)
    try:
        with psycopg.connect(server.dsn(), autocommit=True) as admin:
            admin.execute("CREATE DATABASE ours")
            admin.execute("CREATE DATABASE theirs")
        conns = {
            "tgsis": setup(server.dsn("ours"), None, args.objects, args.rows),
            "other": setup(server.dsn("theirs"), "bench_admin", args.objects, args.rows),
        }
        runner = (
            conns["other"]
            .execute(
                "SELECT count(*) FROM pg_proc WHERE proname = 'parts_ver_run' AND proowner = 'bench_admin'::regrole"
            )
            .fetchone()
        )
        assert runner == (1,), "the admin's table has no runner of its own"
        for _ in range(args.repeat):
            for who, conn in conns.items():
                merged = edited_version(conn, "parts", args.objects)
                samples[f"merge_{who}"].append(timed(lambda: tgsis.merge_version(conn, merged), 1))
                dropped = edited_version(conn, "parts", args.objects)
                samples[f"delete_{who}"].append(timed(lambda: tgsis.delete_version(conn, dropped), 1))
        for conn in conns.values():
            conn.close()
    finally:
        server.destroy()
    medians = {name: statistics.median(values) for name, values in samples.items()}
    print(
        f"{args.objects} objects x {args.rows} rows per table; each version edits "
        f"{max(1, args.objects // 100) * args.rows} rows; medians of {args.repeat} rounds"
    )
    for op in ("merge", "delete"):
        print(
            f"{op:6s}  tgsis's owner's table {medians[f'{op}_tgsis'] * 1000:8.1f} ms   "
            f"another owner's table {medians[f'{op}_other'] * 1000:8.1f} ms"
        )
    for op in ("merge", "delete"):
        print(f"{op}_other_owner_vs_tgsis_owner: {medians[f'{op}_other'] / medians[f'{op}_tgsis']:.2f}")
    for name, value in medians.items():
        print(f"{name}_s: {value:.4f}")


if __name__ == "__main__":
    main()
