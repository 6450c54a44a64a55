"""Reads through a versioned view vs the same rows in a plain table.

A 2M-row table of 200 objects (10,000 rows each) is versioned; 20 versions
form 4 chains of depth 5 under DEFAULT, and each version edits one object
(10,000 rows, 0.5 % of the table) through the view with plain UPDATEs, so
10 % of the rows are changed across versions. In the deepest version of a
chain we time

- a one-object fetch (``WHERE objid = X``) of an object its ancestors edited
  (so 20,000 row versions to sort out), and of an object nobody edited,
- a full scan (every row the version sees),

through the view, against a plain table holding exactly the rows that
version sees (same columns, same primary key), in the same run. "end to end"
is a binary COPY of the query's rows to this process (the way tgsis reads);
"executor" is the server's execution time (EXPLAIN ANALYZE, no timing of
nodes), which shows the cost of the visibility predicate alone.

Last, a child of DEFAULT edits 1 % of the rows (two objects) and is merged
back: time and rows written.

    python bench/versioning.py [--objects 200] [--rows 10000] [--repeat 5]    # TGSIS_PG=system|embedded
"""

from __future__ import annotations

import argparse
import json
import statistics
import time
from collections.abc import Callable
from typing import Any

import psycopg

import tgsis
from tgsis.db.local import LocalServer, find_binaries

Conn = psycopg.Connection[Any]


def build(conn: Conn, objects: int, rows: int) -> tuple[str, list[int]]:
    """Load, version, and edit; return the deepest version of the first chain and the objects it inherited edits of."""
    conn.execute("CREATE TABLE parts (objid int, k int, x float8, y float8, z float8, PRIMARY KEY (objid, k))")
    conn.execute(
        "INSERT INTO parts SELECT i / %s, i %% %s, random(), random(), random() FROM generate_series(0, %s - 1) i",
        (rows, rows, objects * rows),
    )
    conn.commit()
    tgsis.enable_versioning(conn, "parts", "objid", "part")
    edited = 0
    deepest = ""
    chain_objects: list[int] = []
    for chain in range(4):
        parent = "DEFAULT"
        for depth in range(1, 6):
            name = f"c{chain}d{depth}"
            tgsis.create_version(conn, name, parent)
            with tgsis.in_version(conn, name):
                conn.execute("UPDATE parts SET z = z + 1 WHERE objid = %s", (edited,))
                conn.commit()
            if chain == 0:
                chain_objects.append(edited)
                deepest = name
            edited += 1
            parent = name
    vacuum_analyze(conn, "parts_ver")
    return deepest, chain_objects


def time_merge(conn: Conn, objects: int, rows: int) -> tuple[float, int, int]:
    """A child of DEFAULT edits 1 % of the rows (two objects); time its merge back."""
    tgsis.goto_version(conn, "DEFAULT")
    tgsis.create_version(conn, "one_percent")
    edited = max(1, objects // 100)
    with tgsis.in_version(conn, "one_percent"):
        changed = 0
        for objid in range(objects - edited, objects):
            changed += conn.execute("UPDATE parts SET x = x + 1 WHERE objid = %s", (objid,)).rowcount
        conn.commit()
    start = time.perf_counter()
    written = tgsis.merge_version(conn, "one_percent")
    return time.perf_counter() - start, written, changed


def vacuum_analyze(conn: Conn, table: str) -> None:
    conn.commit()
    conn.autocommit = True
    conn.execute(f"VACUUM ANALYZE {table}")
    conn.autocommit = False


def executor_s(conn: Conn, query: str, params: tuple[Any, ...], repeat: int) -> float:
    """Median execution time the server reports for a query, in seconds."""
    samples = []
    for _ in range(repeat):
        plan = conn.execute(f"EXPLAIN (ANALYZE, TIMING OFF, FORMAT JSON) {query}", params).fetchone()
        assert plan is not None
        document = json.loads(plan[0]) if isinstance(plan[0], str) else plan[0]
        samples.append(float(document[0]["Execution Time"]) / 1000)
    return statistics.median(samples)


def paired(versioned: Callable[[], object], plain: Callable[[], object], repeat: int) -> tuple[float, float]:
    """Median times of two actions run alternately (so that drift of the machine hits both alike)."""
    samples: tuple[list[float], list[float]] = ([], [])
    for _ in range(repeat):
        for action, into in ((versioned, samples[0]), (plain, samples[1])):
            start = time.perf_counter()
            action()
            into.append(time.perf_counter() - start)
    return statistics.median(samples[0]), statistics.median(samples[1])


def rolled_back(conn: Conn, query: str, params: tuple[Any, ...]) -> None:
    """Run a write and undo it, so that every repetition writes the same rows."""
    conn.execute(query, params)
    conn.rollback()


def copy_out(conn: Conn, query: str) -> int:
    size = 0
    with conn.cursor().copy(f"COPY ({query}) TO STDOUT (FORMAT binary)") as copy:
        for chunk in copy:
            size += len(chunk)
    return size


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--objects", type=int, default=200)
    parser.add_argument("--rows", type=int, default=10_000)
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--show-plans", action="store_true", help="print the plans of the versioned queries")
    args = parser.parse_args()

    binaries = find_binaries()
    print(f"server: {binaries.describe()} (throwaway cluster, fsync off)")
    server = LocalServer.throwaway(binaries)
    try:
        with psycopg.connect(server.dsn(), autocommit=True) as admin:
            admin.execute("CREATE DATABASE bench")
        with psycopg.connect(server.dsn("bench")) as conn:
            tgsis.install(conn, method="sql")  # this checkout's SQL, not an extension another build installed
            deepest, inherited = build(conn, args.objects, args.rows)
            tgsis.goto_version(conn, deepest)
            stored = conn.execute("SELECT count(*) FROM parts_ver").fetchone()
            visible = conn.execute("SELECT count(*) FROM parts").fetchone()
            assert stored is not None and visible is not None
            conn.execute("CREATE TABLE plain AS SELECT * FROM parts")
            conn.execute("ALTER TABLE plain ADD PRIMARY KEY (objid, k)")
            vacuum_analyze(conn, "plain")
            print(
                f"table: {args.objects * args.rows} rows, {args.objects} objects; 20 versions (4 chains, depth 5); "
                f"{stored[0]} row versions stored; version {deepest} sees {visible[0]} rows, "
                f"set {tgsis.revisions(conn)}"
            )

            obj = inherited[2]  # edited two levels up
            one_view, one_plain = "SELECT * FROM parts WHERE objid = %s", "SELECT * FROM plain WHERE objid = %s"
            all_view, all_plain = "SELECT * FROM parts", "SELECT * FROM plain"
            plan = "\n".join(r[0] for r in conn.execute(f"EXPLAIN (ANALYZE, BUFFERS) {one_view}", (obj,)).fetchall())
            assert "Index" in plan, plan
            if args.show_plans:
                print(plan)
                print("\n".join(r[0] for r in conn.execute(f"EXPLAIN (ANALYZE, BUFFERS) {all_view}").fetchall()))
            assert copy_out(conn, one_view % obj) == copy_out(conn, one_plain % obj)

            untouched = args.objects - 1  # no version edited it
            figures = {
                "fetch_one_e2e": paired(
                    lambda: copy_out(conn, one_view % obj), lambda: copy_out(conn, one_plain % obj), args.repeat * 10
                ),
                "fetch_unedited_e2e": paired(
                    lambda: copy_out(conn, one_view % untouched),
                    lambda: copy_out(conn, one_plain % untouched),
                    args.repeat * 10,
                ),
                "full_scan_e2e": paired(
                    lambda: copy_out(conn, all_view), lambda: copy_out(conn, all_plain), args.repeat
                ),
                # the server's own clock (EXPLAIN ANALYZE), not the round trip
                "fetch_one_executor": (
                    executor_s(conn, one_view, (obj,), args.repeat * 4),
                    executor_s(conn, one_plain, (obj,), args.repeat * 4),
                ),
                "fetch_unedited_executor": (
                    executor_s(conn, one_view, (untouched,), args.repeat * 4),
                    executor_s(conn, one_plain, (untouched,), args.repeat * 4),
                ),
                "full_scan_executor": (
                    executor_s(conn, all_view, (), args.repeat),
                    executor_s(conn, all_plain, (), args.repeat),
                ),
                # one object's rows (inherited: each closed and written anew) rewritten through the
                # view (queued by its row trigger, written set-based when the statement ends), undone each time
                "update_one_e2e": paired(
                    lambda: rolled_back(conn, "UPDATE parts SET x = x + 1 WHERE objid = %s", (obj,)),
                    lambda: rolled_back(conn, "UPDATE plain SET x = x + 1 WHERE objid = %s", (obj,)),
                    args.repeat,
                ),
            }
            # the same once the rows are the version's own (of its working revision): changed in place
            for table in ("parts", "plain"):
                conn.execute(f"UPDATE {table} SET x = x + 1 WHERE objid = %s", (obj,))  # noqa: S608
            conn.commit()
            figures["update_own_e2e"] = paired(
                lambda: rolled_back(conn, "UPDATE parts SET x = x + 1 WHERE objid = %s", (obj,)),
                lambda: rolled_back(conn, "UPDATE plain SET x = x + 1 WHERE objid = %s", (obj,)),
                args.repeat,
            )

            # an application's loop: 2,000 one-row UPDATEs in one transaction (each statement's rows are
            # found through the queue's index, not among what the statements before it deleted)
            def one_by_one(table: str) -> None:
                for k in range(2000):
                    conn.execute(f"UPDATE {table} SET x = x + 1 WHERE objid = %s AND k = %s", (obj, k))  # noqa: S608
                conn.rollback()

            figures["update_2000_statements"] = paired(
                lambda: one_by_one("parts"), lambda: one_by_one("plain"), args.repeat
            )
            merge_s, merge_rows, changed = time_merge(conn, args.objects, args.rows)
    finally:
        server.destroy()

    print(
        f"merge of a version with {changed} changed rows ({changed / (args.objects * args.rows):.0%}): "
        f"{merge_s:.2f} s, {merge_rows} rows written"
    )
    for name, (versioned, plain) in figures.items():
        print(f"{name:22s} versioned view {versioned * 1000:9.2f} ms   plain table {plain * 1000:9.2f} ms")
    for name, (versioned, plain) in figures.items():
        print(f"{name}_vs_plain: {versioned / plain:.2f}")
    print(f"merge_1pct_s: {merge_s:.3f}")
    print(f"merge_1pct_rows_written: {merge_rows}")


if __name__ == "__main__":
    main()
