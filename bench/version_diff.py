"""`tgsis version diff` table by table (with progress) against the one-statement diff, on a large deleted feature.

A bumpy side x side grid (default 500: 250,000 vertices, 497,002 triangles,
a vertex property) is stored in DEFAULT with feature versioning on; version
``edit`` deletes it, so the diff of DEFAULT and edit is every row of the
feature (the case `tgsis version diff` was silent on for 30-53 s at 2M rows).

Timed, medians of ``--repeat`` runs in one process, the two taken in turn: the baseline,
``tgsis.diff_versions(conn, 'DEFAULT', 'edit')`` (one statement,
``tgsis.diff_versions``), and the same call with ``progress=`` (one
``tgsis.diff_table`` statement per versioned table in one REPEATABLE READ
READ ONLY transaction, as the command runs it). Both results are checked equal
before timing.

    python bench/version_diff.py [--side 500] [--repeat 3]      # TGSIS_PG=system|embedded
"""

from __future__ import annotations

import argparse
import statistics
import time
from collections.abc import Callable
from typing import Any

from timing import bench_database
from transfer import grid_surface

import tgsis


def _medians(runs: list[Callable[[], Any]], repeat: int) -> list[float]:
    """Median seconds of each run, the runs taken in turn (a warm cache or a busy neighbour favours neither)."""
    times: list[list[float]] = [[] for _ in runs]
    for _ in range(repeat):
        for run, taken in zip(runs, times):
            start = time.perf_counter()
            run()
            taken.append(time.perf_counter() - start)
    return [statistics.median(taken) for taken in times]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--side", type=int, default=500)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    with bench_database() as conn:
        tgsis.create_feature_class(conn, "faults", "SURFACE", cell_properties=[("porosity", "double precision")])
        fid = tgsis.insert_feature(conn, "faults", grid_surface(args.side))
        tgsis.enable_feature_versioning(conn)
        tgsis.create_version(conn, "edit")
        with tgsis.in_version(conn, "edit"):
            tgsis.delete_feature(conn, "faults", fid)
        conn.commit()
        tables = len(tgsis.versioned_tables(conn))
        calls: list[int] = []
        whole = tgsis.diff_versions(conn, "DEFAULT", "edit")
        conn.commit()
        stepwise = tgsis.diff_versions(conn, "DEFAULT", "edit", progress=lambda done, total: calls.append(done))
        assert stepwise == whole and calls == list(range(1, tables + 1)), (len(stepwise), len(whole), calls)
        rows = sum(d.removed for d in whole)
        print(f"feature {fid}: {args.side}x{args.side} grid deleted in edit; {rows} rows differ in {tables} tables")

        def one_statement() -> None:
            tgsis.diff_versions(conn, "DEFAULT", "edit")
            conn.commit()

        def by_table() -> None:
            tgsis.diff_versions(conn, "DEFAULT", "edit", progress=lambda done, total: None)

        baseline, stepped = _medians([one_statement, by_table], args.repeat)
        print(f"rows_differing: {rows}")
        print(f"diff_one_statement_s: {baseline:.3f}")
        print(f"diff_by_table_s: {stepped:.3f}")
        print(f"diff_by_table_ratio: {stepped / baseline:.3f}")


if __name__ == "__main__":
    main()
