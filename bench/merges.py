"""Merges, refreshes and conflict checks of a 1,000-row edit at 2M and 20M rows (issue 20, target 3).

For each size a versioned table of objects of 10,000 rows is loaded in a
database of its own on one server. Then, three times: a child version
edits 1,000 rows of one object through the view while DEFAULT edits 1,000
rows of another, and we time ``find_conflicts`` of the child (both sides'
changes), its ``refresh_version`` (DEFAULT's edit into the child) and its
``merge_version`` (the child's edit into DEFAULT), each in its own
transaction. Medians of the three rounds.

Baselines in the same process: the small size against the large one (the
issue's bound: the large one at most 2x the small one, and at most 0.3 s),
and ``tgsis.changed_objects`` alone, the question each of them asks (which
objects have row versions written or closed in these revisions), answered
from the notes of ``tgsis.revision_objects``, against the same question
asked of the storage by a scan (what it cost before the notes). With
``--upload-cost``, what the notes cost the upload of a 1M-vertex,
2M-triangle surface into versioned storage (``insert_feature``, rolled
back; the storage trigger ``tgsis_storage_changes`` of ``geometry``,
``vrtx`` and ``trgl`` enabled, then disabled, alternating). With
``--view-write``, what the note probe costs a write through a view: a
10,000-row update of one object in a child (each row closed and written
anew, rolled back), the view's trigger as generated against the same
trigger without the probe, alternating. With ``--partitions N``, each size
again with the table hash-partitioned by object in N partitions, against the
plain table (the step of docs/scaling.md measurable on one node). At every
size, also one object's 10,000 rows read through the view in a child, and
rewritten (rolled back).

    python bench/merges.py [--small 2000000] [--large 20000000] [--rounds 3] [--upload-cost] [--view-write] [--partitions 8]
    # TGSIS_PG=system|embedded
"""

from __future__ import annotations

import argparse
import statistics
import time
from typing import Any

import numpy as np
import psycopg

import tgsis
from tgsis.db.local import LocalServer, find_binaries

Conn = psycopg.Connection[Any]
OBJECT_ROWS = 10_000
EDIT_ROWS = 1_000


def load(conn: Conn, rows: int, partitions: int = 0) -> float:
    """The table of ``rows`` rows (objects of 10,000), hash-partitioned by object when asked, versioned; seconds taken."""
    start = time.perf_counter()
    conn.execute(
        "CREATE TABLE parts (objid int, k int, x float8, y float8, z float8, PRIMARY KEY (objid, k))"
        + (" PARTITION BY HASH (objid)" if partitions else "")
    )
    for r in range(partitions):
        conn.execute(f"CREATE TABLE parts_{r} PARTITION OF parts FOR VALUES WITH (MODULUS {partitions}, REMAINDER {r})")
    conn.execute(
        "INSERT INTO parts SELECT i / %s, i %% %s, random(), random(), random() FROM generate_series(0, %s - 1) i",
        (OBJECT_ROWS, OBJECT_ROWS, rows),
    )
    conn.commit()
    tgsis.enable_versioning(conn, "parts", "objid", "part")
    conn.commit()
    conn.autocommit = True
    conn.execute("VACUUM ANALYZE parts_ver")
    conn.autocommit = False
    return time.perf_counter() - start


def one_object_s(conn: Conn, objects: int) -> tuple[float, float]:
    """Reading one object's 10,000 rows through the view in a child, and rewriting them (rolled back): medians of 5."""
    tgsis.create_version(conn, "single")
    conn.commit()
    reads, writes = [], []
    with tgsis.in_version(conn, "single"):
        for n in range(5):
            objid = (7 * n + 3) % objects
            start = time.perf_counter()
            row = conn.execute("SELECT count(*), sum(x) FROM parts WHERE objid = %s", (objid,)).fetchone()
            reads.append(time.perf_counter() - start)
            assert row is not None and row[0] == OBJECT_ROWS
            start = time.perf_counter()
            conn.execute("UPDATE parts SET x = x + 1 WHERE objid = %s", (objid,))
            writes.append(time.perf_counter() - start)
            conn.rollback()
    tgsis.delete_version(conn, "single")
    conn.commit()
    return statistics.median(reads), statistics.median(writes)


def timed(conn: Conn, action: Any) -> float:
    start = time.perf_counter()
    action()
    conn.commit()
    return time.perf_counter() - start


def one_round(conn: Conn, n: int, objects: int) -> dict[str, float]:
    """A child and DEFAULT each edit 1,000 rows of an object; time the conflict check, refresh and merge."""
    name = f"edit{n}"
    tgsis.create_version(conn, name)
    conn.commit()
    with tgsis.in_version(conn, name):
        conn.execute("UPDATE parts SET x = x + 1 WHERE objid = %s AND k < %s", (2 * n % objects, EDIT_ROWS))
    conn.execute("UPDATE parts SET y = y + 1 WHERE objid = %s AND k < %s", ((2 * n + 1) % objects, EDIT_ROWS))
    conn.commit()
    figures = {
        "find_conflicts": timed(conn, lambda: tgsis.find_conflicts(conn, name)),
        "refresh": timed(conn, lambda: tgsis.refresh_version(conn, name)),
    }
    with tgsis.in_version(conn, name):
        conn.execute("UPDATE parts SET z = z + 1 WHERE objid = %s AND k < %s", (2 * n % objects, EDIT_ROWS))
    figures["merge"] = timed(conn, lambda: tgsis.merge_version(conn, name, remove=True))
    return figures


def changed_objects_s(conn: Conn, objects: int) -> tuple[float, float]:
    """tgsis.changed_objects of a child's 1,000-row edit (from the notes), and the same question as a scan (rolled back)."""
    tgsis.create_version(conn, "probe")
    with tgsis.in_version(conn, "probe"):
        conn.execute("UPDATE parts SET x = x + 1 WHERE objid = %s AND k < %s", (objects - 1, EDIT_ROWS))
    own = conn.execute(
        "SELECT tgsis.own_working_revisions(versionid) FROM tgsis.versions WHERE name = 'probe'"
    ).fetchone()
    assert own is not None
    scan = (
        "SELECT v.objid, count(*) FROM parts_ver v WHERE v.revision = ANY (%s::int[]) OR v.lastrevs && %s::int[] "
        "GROUP BY 1"
    )

    def best(statement: str, params: tuple[Any, ...]) -> tuple[float, list[Any]]:
        samples: list[float] = []
        rows: list[Any] = []
        for _ in range(5):
            start = time.perf_counter()
            rows = conn.execute(statement, params).fetchall()
            samples.append(time.perf_counter() - start)
        return statistics.median(samples), rows

    noted, found = best("SELECT objectkey FROM tgsis.changed_objects(%s::int[])", (own[0],))
    scanned, counted = best(scan, (own[0], own[0]))
    assert [k for (k,) in found] == [str(k) for k, _ in counted] == [str(objects - 1)], (found, counted)
    conn.rollback()
    return noted, scanned


def grid(side: int) -> tgsis.Surface:
    u, v = np.meshgrid(np.arange(side, dtype=float), np.arange(side, dtype=float))
    vertices = np.stack([u.ravel(), v.ravel(), np.zeros(side * side)], axis=1)
    idx = np.arange(side * side).reshape(side, side)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel()
    return tgsis.Surface(vertices, np.concatenate([np.stack([a, b, d], 1), np.stack([a, d, c], 1)]))


NOTE_TABLES = ("tgsis.geometry_ver", "tgsis.vrtx_ver", "tgsis.trgl_ver")


def upload_cost(server: LocalServer, rounds: int) -> dict[str, float]:
    """Median upload of a 1M-vertex surface into versioned storage with the note trigger, and with it disabled."""
    with psycopg.connect(server.dsn(), autocommit=True) as admin:
        admin.execute("CREATE DATABASE upload")
    samples: dict[str, list[float]] = {"noted": [], "not noted": []}
    surface = grid(1000)
    with psycopg.connect(server.dsn("upload")) as conn:
        tgsis.install(conn, method="sql")
        tgsis.enable_feature_versioning(conn)
        tgsis.create_feature_class(conn, "surfaces", "SURFACE")
        tgsis.create_version(conn, "upload")  # a working revision of its own (DEFAULT's first is 0, never noted)
        conn.commit()
        for _ in range(rounds):
            for kind in samples:
                for table in NOTE_TABLES:
                    conn.execute(
                        f"ALTER TABLE {table} {'ENABLE' if kind == 'noted' else 'DISABLE'} "
                        "TRIGGER tgsis_storage_changes"
                    )
                conn.commit()
                conn.autocommit = True
                for table in NOTE_TABLES:
                    conn.execute(f"VACUUM {table}")  # the rolled-back rows of the last round
                conn.autocommit = False
                with tgsis.in_version(conn, "upload"):
                    start = time.perf_counter()
                    tgsis.insert_feature(conn, "surfaces", surface)
                    samples[kind].append(time.perf_counter() - start)
                    notes = conn.execute(
                        "SELECT count(*) FROM tgsis.revision_objects WHERE tablename IN ('vrtx', 'trgl')"
                    ).fetchone()  # (COPY; geometry: a view)
                    assert notes == ((2,) if kind == "noted" else (0,)), notes
                    conn.rollback()
        for table in NOTE_TABLES:
            conn.execute(f"ALTER TABLE {table} ENABLE TRIGGER tgsis_storage_changes")
        conn.commit()
    return {kind: statistics.median(values) for kind, values in samples.items()}


def view_write_cost(server: LocalServer, rounds: int) -> dict[str, float]:
    """A 10,000-row update of one object through the view in a child: the trigger as generated, and without the note probe."""
    with psycopg.connect(server.dsn(), autocommit=True) as admin:
        admin.execute("CREATE DATABASE viewwrite")
    samples: dict[str, list[float]] = {"with probe": [], "without probe": []}
    with psycopg.connect(server.dsn("viewwrite")) as conn:
        tgsis.install(conn, method="sql")
        load(conn, 3 * OBJECT_ROWS)
        tgsis.create_version(conn, "child")
        conn.commit()
        row = conn.execute("SELECT pg_get_functiondef('public.parts_ver_write()'::regprocedure)").fetchone()
        assert row is not None
        source: str = row[0]
        # the same trigger with the note's half of the probe query, and its call, taken out
        call, probe = "IF v_w <> 0 AND NOT (v_noted", "EXISTS (SELECT FROM tgsis.revision_objects o"
        assert call in source and probe in source, "the generated trigger has no note probe"
        without = source.replace(call, "IF false AND NOT (v_noted")
        without = without[: without.index(probe)] + "true\n      " + without[without.index("INTO v_locked, v_noted;") :]
        for _ in range(rounds):
            for kind, definition in (("with probe", source), ("without probe", without)):
                conn.execute(definition)
                conn.commit()
                conn.autocommit = True
                conn.execute("VACUUM parts_ver, tgsis.revision_objects")  # the rolled-back rows of the last run
                conn.autocommit = False
                with tgsis.in_version(conn, "child"):
                    start = time.perf_counter()
                    conn.execute("UPDATE parts SET x = x + 1 WHERE objid = 1")
                    samples[kind].append(time.perf_counter() - start)
                    conn.rollback()
        conn.execute(source)
        conn.commit()
    return {kind: statistics.median(values) for kind, values in samples.items()}


def measure(server: LocalServer, rows: int, rounds: int, label: str, partitions: int = 0) -> dict[str, float]:
    database = f"{label}_{rows}_{partitions}"
    with psycopg.connect(server.dsn(), autocommit=True) as admin:
        admin.execute(f"CREATE DATABASE {database}")
    with psycopg.connect(server.dsn(database)) as conn:
        tgsis.install(conn, method="sql")  # this checkout's SQL
        loaded = load(conn, rows, partitions)
        size = conn.execute(
            "SELECT coalesce(sum(pg_total_relation_size(relid)), pg_total_relation_size('parts_ver')) FROM pg_partition_tree('parts_ver')"
        ).fetchone()
        assert size is not None
        samples = [one_round(conn, n, rows // OBJECT_ROWS) for n in range(rounds)]
        figures = {key: statistics.median(s[key] for s in samples) for key in samples[0]}
        figures["changed_objects"], figures["changed_objects_scan"] = changed_objects_s(conn, rows // OBJECT_ROWS)
        figures["read_one_object"], figures["write_one_object"] = one_object_s(conn, rows // OBJECT_ROWS)
    print(
        f"{rows:>11,} rows{f' in {partitions} hash partitions' if partitions else ''}: loaded and versioned in "
        f"{loaded:.0f} s; storage {float(size[0]) / 1e6:.0f} MB"
    )
    for key, value in figures.items():
        print(f"    {key:24s} {value * 1000:9.1f} ms")
    return figures


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--small", type=int, default=2_000_000)
    parser.add_argument("--large", type=int, default=20_000_000)
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument(
        "--upload-cost", action="store_true", help="also time a 1M-vertex upload with and without notes"
    )
    parser.add_argument(
        "--view-write", action="store_true", help="also time a view write with and without the note probe"
    )
    parser.add_argument(
        "--partitions",
        type=int,
        default=0,
        help="also measure each size with the table hash-partitioned by object in this many partitions",
    )
    args = parser.parse_args()

    binaries = find_binaries()
    print(
        f"server: {binaries.describe()} (throwaway cluster, fsync off); a child's and DEFAULT's "
        f"{EDIT_ROWS}-row edits, medians of {args.rounds} rounds"
    )
    server = LocalServer.throwaway(binaries)
    try:
        small = measure(server, args.small, args.rounds, "small")
        large = measure(server, args.large, args.rounds, "large")
        partitioned = (
            {
                size: measure(server, rows, args.rounds, size, args.partitions)
                for size, rows in (("small", args.small), ("large", args.large))
            }
            if args.partitions
            else {}
        )
        uploads = upload_cost(server, args.rounds) if args.upload_cost else {}
        view_writes = view_write_cost(server, max(args.rounds, 5)) if args.view_write else {}
    finally:
        server.destroy()

    for kind, seconds in uploads.items():
        print(f"upload of 1M vertices, {kind:12s} {seconds:6.2f} s")
    for kind, seconds in view_writes.items():
        print(f"10,000-row view write, {kind:14s} {seconds * 1000:7.1f} ms")

    for key in ("find_conflicts", "refresh", "merge"):
        print(f"{key}_large_s: {large[key]:.3f}")
        print(f"{key}_large_vs_small: {large[key] / small[key]:.2f}")
    print(f"changed_objects_large_s: {large['changed_objects']:.4f}")
    print(f"changed_objects_large_vs_small: {large['changed_objects'] / small['changed_objects']:.2f}")
    print(f"changed_objects_scan_large_s: {large['changed_objects_scan']:.3f}")
    print(f"changed_objects_vs_scan_large: {large['changed_objects'] / large['changed_objects_scan']:.4f}")
    for size, plain in (("small", small), ("large", large)) if partitioned else ():
        for key, value in partitioned[size].items():
            print(f"partitioned_vs_plain_{key}_{size}: {value / plain[key]:.3f}")
    if uploads:
        print(f"upload_noted_vs_not_noted: {uploads['noted'] / uploads['not noted']:.3f}")
    if view_writes:
        print(f"view_write_with_probe_vs_without: {view_writes['with probe'] / view_writes['without probe']:.3f}")


if __name__ == "__main__":
    main()
