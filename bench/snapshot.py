"""Snapshot of an evolving surface (model 3) at a time t vs the download of a static surface of the same size.

An evolving 1000 x 1000 grid (1M nodes, 1,996,002 triangles) with 10
geometry instants in one topology period (10M rows of ``tgsis.d4dvrtx``),
and the same with two topology periods (instants 0..5 and 5..9, the second
period's triangles with flipped diagonals: 2M nodes, 11M node positions).
Timed with ``tgsis.get_at``, which computes the snapshot in SQL
(``tgsis.vertices_at``, ``tgsis.triangles_at``) and downloads it:

- at a t between two geometry instants (every node interpolated),
- at a geometry instant exactly,

against the baseline measured in the same process and database: downloading
a static model-1 surface with the same vertex and triangle counts with
``tgsis.fetch_feature``. Also the upload of the evolving surface
(``insert_feature`` of an EvolvingSurface) vs the static one. The tables are
VACUUM ANALYZEd after the uploads (what autovacuum does soon after).
tgsis is installed from the client's SQL sources (``method="sql"``), so the
functions measured are this checkout's whatever the server has installed;
model 1 (the static baseline) is stored as installed, in chunks by default
(issue 40), the evolving surface (model 3) in rows, or with ``--time-chunks``
its triangles and node positions in chunks (``tgsis.store_in_chunks('d4dtrgl')``,
``'d4dvrtx'``, before the uploads: the Python paths then write and read through
the face); the relations printed and VACUUMed are named by ``tgsis.storage_table``.

    python bench/snapshot.py [--side 1000] [--instants 10] [--repeat 5] [--no-two-periods] [--show-plans]
                             [--time-chunks]
                                                          # TGSIS_PG=system|embedded
"""

from __future__ import annotations

import argparse
import json
import statistics
import time
from collections.abc import Callable
from typing import Any

import numpy as np
import psycopg
from timing import bench_database, paired
from transfer import grid_surface

import tgsis
from tgsis.db import versions as V
from tgsis.temporal import EvolvingSurface, TopologyPeriod

Conn = psycopg.Connection[Any]


def evolving_grid(base: tgsis.Surface, times: list[list[float]]) -> EvolvingSurface:
    """The grid moving up and down (z scaled per instant, x shifted), one period per list of times.

    Every period but the first flips the diagonals of the grid's quads (a
    new topology on the same nodes).
    """
    periods = []
    m = base.n_cells // 2
    for i, period_times in enumerate(times):
        scale = 1 + 0.1 * np.asarray(period_times)
        positions = np.repeat(base.vertices[None], len(period_times), axis=0)
        positions[:, :, 2] *= scale[:, None]
        positions[:, :, 0] += 3.0 * np.asarray(period_times)[:, None]
        cells = base.cells
        if i:  # quads (a, b, d) + (a, d, c) -> (a, b, c) + (b, d, c)
            a, b, d, c = cells[:m, 0], cells[:m, 1], cells[:m, 2], cells[m:, 2]
            cells = np.concatenate([np.stack([a, b, c], 1), np.stack([b, d, c], 1)])
        periods.append(TopologyPeriod(period_times, cells, positions))
    return EvolvingSurface(periods, name="evolving bench")


def vacuum_analyze(conn: Conn) -> None:
    """VACUUM ANALYZE the relations that store the tables (chunk tables for model 1 by default: the views cannot)."""
    conn.commit()
    tables = [
        V.storage_table(conn, "tgsis", t)
        for t in ("vrtx", "trgl", "timem", "timet", "node", "d4dtrgl", "d4dvrtx", "geometry")
    ]
    conn.commit()
    conn.autocommit = True
    for table in tables:
        conn.execute(f"VACUUM ANALYZE {table}")
    conn.autocommit = False


def executor_s(conn: Conn, query: str, repeat: int) -> float:
    """Median execution time the server reports for a query, in seconds (JIT off, as get_at runs it)."""
    conn.execute("SET LOCAL jit = off")
    samples = []
    for _ in range(repeat):
        row = conn.execute(f"EXPLAIN (ANALYZE, TIMING OFF, FORMAT JSON) {query}").fetchone()
        assert row is not None
        document = json.loads(row[0]) if isinstance(row[0], str) else row[0]
        samples.append(float(document[0]["Execution Time"]) / 1000)
    conn.rollback()
    return statistics.median(samples)


def plan(conn: Conn, query: str) -> str:
    conn.execute("SET LOCAL jit = off")
    text = "\n".join(r[0] for r in conn.execute(f"EXPLAIN (ANALYZE, BUFFERS) {query}").fetchall())
    conn.rollback()
    return text


def once(action: Callable[[], object]) -> float:
    start = time.perf_counter()
    action()
    return time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--side", type=int, default=1000)
    parser.add_argument("--instants", type=int, default=10)
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument(
        "--no-two-periods", dest="two_periods", action="store_false", help="skip the variant with two topology periods"
    )
    parser.add_argument("--show-plans", action="store_true", help="print EXPLAIN (ANALYZE, BUFFERS) of vertices_at")
    parser.add_argument("--time-chunks", action="store_true", help="store model 3's d4dtrgl and d4dvrtx in chunks")
    args = parser.parse_args()

    grid = grid_surface(args.side)
    static = tgsis.Surface(grid.vertices, grid.cells, name="static bench")
    g = args.instants
    one = evolving_grid(static, [[float(k) for k in range(g)]])
    half = g // 2
    two = evolving_grid(static, [[float(k) for k in range(half + 1)], [float(k) for k in range(half, g)]])
    n, m = static.n_vertices, static.n_cells
    print(
        f"static surface: {n} vertices, {m} triangles; evolving: {g} geometry instants in one period "
        f"({g * n} node positions)"
        + (f", and two periods 0..{half}, {half}..{g - 1} ({(g + 1) * n} positions)" if args.two_periods else "")
    )
    with bench_database() as conn:
        tgsis.create_feature_class(conn, "static_grid", "SURFACE")
        tgsis.create_feature_class(conn, "evolving_grid", "SURFACE", time_model="EVOLVING")
        if args.time_chunks:
            conn.execute("SELECT tgsis.store_in_chunks('d4dtrgl'), tgsis.store_in_chunks('d4dvrtx')")
        conn.commit()

        ids: dict[str, int] = {}

        def upload(key: str, cls: str, surface: tgsis.Surface | EvolvingSurface) -> None:
            ids[key] = tgsis.insert_feature(conn, cls, surface)
            conn.commit()

        up_static = once(lambda: upload("static", "static_grid", static))
        up_one = once(lambda: upload("one", "evolving_grid", one))
        up_two = once(lambda: upload("two", "evolving_grid", two)) if args.two_periods else float("nan")
        vacuum_analyze(conn)
        print(
            "storage:",
            ", ".join(V.storage_table(conn, "tgsis", t) for t in ("vrtx", "trgl", "node", "d4dvrtx", "d4dtrgl")),
        )
        conn.commit()

        t_mid, t_exact = half - 0.5, float(half - 1)  # inside the first period
        cases = {"one_mid": ("one", t_mid), "one_exact": ("one", t_exact)}
        if args.two_periods:  # inside the second period (node ids from n on)
            cases |= {"two_mid": ("two", half + 0.5), "two_exact": ("two", float(half + 1))}
        for name, (key, t) in cases.items():  # the figures are of correct snapshots
            got = tgsis.get_at(conn, ids[key], t)
            expected = (one if key == "one" else two).at(t)
            assert got is not None and expected is not None
            np.testing.assert_array_equal(got.vertices, expected.vertices, err_msg=name)
            np.testing.assert_array_equal(got.triangles, expected.triangles, err_msg=name)
        fetched = tgsis.fetch_feature(conn, "static_grid", ids["static"]).mesh
        assert fetched.same_as(static)  # type: ignore[union-attr]
        conn.commit()

        def vertices_query(key: str, t: float) -> str:
            return f"SELECT * FROM tgsis.vertices_at({ids[key]}, {t!r})"

        static_query = f"SELECT vrtxid, x, y, z FROM tgsis.vrtx WHERE geoid = {ids['static']}"
        if args.show_plans:
            for name, (key, t) in cases.items():
                print(f"--- {name}: {vertices_query(key, t)}\n{plan(conn, vertices_query(key, t))}")
            print(f"--- static: {static_query}\n{plan(conn, static_query)}")

        actions: list[Callable[[], object]] = [
            lambda: (tgsis.fetch_feature(conn, "static_grid", ids["static"]), conn.commit())
        ]
        for key, t in cases.values():
            actions.append(lambda key=key, t=t: (tgsis.get_at(conn, ids[key], t), conn.commit()))  # type: ignore[misc]
        down_static, *down = paired(actions, args.repeat)
        downloads = dict(zip(cases, down))
        executor = {name: executor_s(conn, vertices_query(key, t), args.repeat) for name, (key, t) in cases.items()}
        executor_static = executor_s(conn, static_query, args.repeat)

    print(f"model 3's d4dtrgl, d4dvrtx in: {'chunks' if args.time_chunks else 'rows'}")
    print(f"upload, static surface (insert_feature):          {up_static:6.2f} s")
    print(f"upload, evolving, 1 period x {g} instants:          {up_one:6.2f} s  ({up_one / up_static:.2f}x static)")
    if args.two_periods:
        print(
            f"upload, evolving, 2 periods, {g + 1} shapes:            {up_two:6.2f} s  ({up_two / up_static:.2f}x static)"
        )
    print(
        f"download, static surface (fetch_feature):         {down_static:6.2f} s   "
        f"(vertex query on the server: {executor_static * 1000:.0f} ms)"
    )
    for name, (key, t) in cases.items():
        print(
            f"snapshot {name:9s} get_at({key}, t={t}):  {downloads[name]:6.2f} s  "
            f"({downloads[name] / down_static:.2f}x static; vertices_at on the server: {executor[name] * 1000:.0f} ms)"
        )
    print(f"static_download_s: {down_static:.3f}")
    for name in cases:
        print(f"snapshot_{name}_s: {downloads[name]:.3f}")
    for name in cases:
        print(f"snapshot_{name}_vs_static: {downloads[name] / down_static:.2f}")
    for name in cases:
        print(f"vertices_at_{name}_executor_ms: {executor[name] * 1000:.0f}")
    print(f"static_vertices_executor_ms: {executor_static * 1000:.0f}")
    print(f"static_upload_s: {up_static:.3f}")
    print(f"evolving_upload_s: {up_one:.3f}")
    print(f"evolving_upload_vs_static: {up_one / up_static:.2f}")
    if args.two_periods:
        print(f"evolving_two_periods_upload_s: {up_two:.3f}")
        print(f"evolving_two_periods_upload_vs_static: {up_two / up_static:.2f}")


if __name__ == "__main__":
    main()
