"""The scale curve (issue 20, target 5): model sets of 1M, 4M and 16M vertices in one PostgreSQL.

For each size a database of its own on one throwaway server holds a model
set: static surfaces of ``--side`` x ``--side`` vertices (62,500 by default:
16, 64 and 256 of them), laid out side by side on a grid in x and y, one
vertex property, feature versioning on, three versions of DEFAULT with a 1 %
edit of a surface each, and one evolving surface (model 3, ten instants, the
same at every size). Then each operation is timed (medians of ``--repeat``):

- ``upload``: ``insert_feature`` of one more surface (rolled back);
- ``fetch``: ``fetch_feature`` of one surface;
- ``box``: ``features_in_box`` of a box meeting four surfaces;
- ``snapshot``: ``get_at`` of the evolving surface between two instants;
- ``checkin``: ``checkin`` of a 1 % edit of a surface checked out in a
  version (vertices moved, diagonals flipped, order shuffled), a surface not
  checked in before each time;
- ``merge``: ``merge_version`` (removing it) of a version that checked in a
  1 % edit of one surface;
- ``full_scan``: ``SELECT count(*), sum(z) FROM tgsis.vrtx`` in a version
  (every vertex the version sees).

Baselines in the same process: each size against the smallest, and the
growth exponent b fitted by least squares to time ~ size^b over the sizes.
The first six depend on one object or one change and should show no growth
(b near 0); the full scan reads everything (b near 1).

Model 1 is stored as ``--storage`` says (chunks, the default install, or
rows); the vertex versions printed are counted in ``tgsis.storage_table``'s
relation.

    python bench/scale.py [--sizes 1000000 4000000 16000000] [--side 250] [--repeat 3] [--storage chunks|rows]
                                                                                # TGSIS_PG=system|embedded
"""

from __future__ import annotations

import argparse
import statistics
import time
from collections.abc import Callable
from typing import Any

import numpy as np
import psycopg
from checkin import one_percent_edit, vacuum_analyze
from psycopg import sql
from snapshot import evolving_grid
from transfer import grid_surface

import tgsis
from tgsis.db import versions as V
from tgsis.db.local import LocalServer, find_binaries

Conn = psycopg.Connection[Any]
OPERATIONS = ("upload", "fetch", "box", "snapshot", "checkin", "merge", "full_scan")
SPACING = 12_000.0  # grid_surface spans 0..10,000 in x and y: 2,000 between neighbours


def placed(base: tgsis.Surface, index: int, columns: int) -> tgsis.Surface:
    """The base surface moved to cell ``index`` of a grid of ``columns`` columns."""
    vertices = base.vertices + np.array([SPACING * (index % columns), SPACING * (index // columns), 0.0])
    return tgsis.Surface(vertices, base.cells, vertex_properties=base.vertex_properties, name=f"s{index}")


def median_of(repeat: int, action: Callable[[int], float]) -> float:
    """Median of ``action(k)`` for k in range(repeat); the action times what it must itself."""
    return statistics.median(action(k) for k in range(repeat))


def clock(action: Callable[[], object]) -> float:
    start = time.perf_counter()
    action()
    return time.perf_counter() - start


def load(conn: Conn, base: tgsis.Surface, count: int, columns: int) -> tuple[list[int], int]:
    """The model set: ``count`` surfaces, versioning on, three edited versions, an evolving surface."""
    tgsis.create_feature_class(conn, "surfaces", "SURFACE", cell_properties={"porosity": "float8"})
    tgsis.create_feature_class(conn, "moving", "SURFACE", time_model="EVOLVING")
    tgsis.enable_feature_versioning(conn)
    conn.commit()
    ids = []
    for i in range(count):
        ids.append(tgsis.insert_feature(conn, "surfaces", placed(base, i, columns)))
        conn.commit()
    small = grid_surface(50)
    evolving = tgsis.insert_feature(
        conn, "moving", evolving_grid(tgsis.Surface(small.vertices, small.cells), [[float(k) for k in range(10)]])
    )
    conn.commit()
    for v in range(3):
        name = f"team{v}"
        tgsis.create_version(conn, name)
        conn.commit()
        with tgsis.in_version(conn, name):
            checkin_edit(conn, ids[-1 - v], seed=100 + v)
    vacuum_analyze(conn)
    return ids, evolving


def checkin_edit(conn: Conn, geoid: int, seed: int) -> float:
    """Check out a surface, edit 1 % of it, check it in (through commit); the check-in's time."""
    co = tgsis.checkout(conn, geoid)
    conn.commit()
    assert co.mesh is not None
    edited = one_percent_edit(co.mesh, seed)
    start = time.perf_counter()
    result = tgsis.checkin(conn, co, edited)
    conn.commit()
    elapsed = time.perf_counter() - start
    assert result.save.vertices_moved > 0, result
    return elapsed


def measure(server: LocalServer, vertices: int, side: int, repeat: int, storage: str) -> dict[str, float]:
    database = f"scale_{vertices}"
    base = grid_surface(side)
    base = tgsis.Surface(base.vertices, base.cells, vertex_properties=base.vertex_properties)
    count = max(4, round(vertices / base.n_vertices))
    columns = max(2, int(np.ceil(np.sqrt(count))))
    with psycopg.connect(server.dsn(), autocommit=True) as admin:
        admin.execute(f"CREATE DATABASE {database}")
    with psycopg.connect(server.dsn(database)) as conn:
        tgsis.install(conn, method="sql", storage=storage)  # type: ignore[arg-type]  # this checkout's SQL
        started = time.perf_counter()
        ids, evolving = load(conn, base, count, columns)
        loaded = time.perf_counter() - started
        vrtx = V.storage_table(conn, "tgsis", "vrtx")  # tgsis.vrtx_chunk (default) or tgsis.vrtx_ver
        stored = conn.execute(sql.SQL("SELECT count(*) FROM {}").format(sql.SQL(vrtx))).fetchone()
        size = conn.execute("SELECT pg_database_size(current_database())").fetchone()
        assert stored is not None and size is not None
        unit = "chunk versions" if vrtx.endswith("_chunk") else "row versions"
        print(
            f"{count * base.n_vertices:>11,} vertices: {count} surfaces of {base.n_vertices:,}, loaded in "
            f"{loaded:.0f} s; {stored[0]:,} {unit} in {vrtx}, database {size[0] / 1e9:.2f} GB"
        )

        extra = placed(base, count + columns, columns)  # a free cell of the layout

        def upload(_: int) -> float:
            elapsed = clock(lambda: tgsis.insert_feature(conn, "surfaces", extra))
            conn.rollback()
            return elapsed

        def fetch(k: int) -> float:
            elapsed = clock(lambda: tgsis.fetch_feature(conn, "surfaces", ids[(k * 7) % count]))
            conn.commit()
            return elapsed

        # around the corner where surfaces 0, 1, columns and columns + 1 meet (each spans 0..10,000 of its cell)
        box = [[SPACING - 3_000.0, SPACING - 3_000.0, -1_000.0], [SPACING + 1_000.0, SPACING + 1_000.0, 1_000.0]]

        def in_box(_: int) -> float:
            found: list[int] = []
            elapsed = clock(lambda: found.extend(tgsis.features_in_box(conn, "surfaces", box)))
            conn.commit()
            assert sorted(found) == sorted([ids[0], ids[1], ids[columns], ids[columns + 1]]), found
            return elapsed

        def snapshot(k: int) -> float:
            elapsed = clock(lambda: tgsis.get_at(conn, evolving, 2.5 + k))
            conn.commit()
            return elapsed

        def checkin(k: int) -> float:
            with tgsis.in_version(conn, "team0"):
                return checkin_edit(conn, ids[k], seed=k)

        def merge(k: int) -> float:
            name = f"merge{k}"
            tgsis.create_version(conn, name)
            conn.commit()
            with tgsis.in_version(conn, name):
                checkin_edit(conn, ids[count // 2 + k], seed=200 + k)
            elapsed = clock(lambda: tgsis.merge_version(conn, name, remove=True))
            conn.commit()
            return elapsed

        def full_scan(_: int) -> float:
            with tgsis.in_version(conn, "team1"):
                row: list[Any] = []
                elapsed = clock(
                    lambda: row.extend(conn.execute("SELECT count(*), sum(z) FROM tgsis.vrtx").fetchone() or ())
                )
                conn.commit()
            assert row[0] == count * base.n_vertices, row
            return elapsed

        actions = {
            "upload": upload,
            "fetch": fetch,
            "box": in_box,
            "snapshot": snapshot,
            "checkin": checkin,
            "merge": merge,
            "full_scan": full_scan,
        }
        figures = {name: median_of(repeat, actions[name]) for name in OPERATIONS}
    for name in OPERATIONS:
        print(f"    {name:10s} {figures[name] * 1000:10.1f} ms")
    return figures


def exponent(sizes: list[int], seconds: list[float]) -> float:
    """b of time ~ size^b, fitted by least squares in log-log."""
    slope, _ = np.polyfit(np.log(sizes), np.log(seconds), 1)
    return float(slope)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--sizes", type=int, nargs="+", default=[1_000_000, 4_000_000, 16_000_000])
    parser.add_argument("--side", type=int, default=250)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--storage", choices=("chunks", "rows"), default="chunks", help="model 1's storage")
    args = parser.parse_args()

    binaries = find_binaries()
    print(
        f"server: {binaries.describe()} (throwaway cluster, fsync off); medians of {args.repeat}; model 1 in {args.storage}"
    )
    server = LocalServer.throwaway(binaries)
    try:
        figures = {size: measure(server, size, args.side, args.repeat, args.storage) for size in args.sizes}
    finally:
        server.destroy()

    smallest, largest = args.sizes[0], args.sizes[-1]
    for name in OPERATIONS:
        print(f"{name}_s_at_{largest}: {figures[largest][name]:.4f}")
        print(f"{name}_largest_vs_smallest: {figures[largest][name] / figures[smallest][name]:.2f}")
        print(f"{name}_growth_exponent: {exponent(args.sizes, [figures[s][name] for s in args.sizes]):.3f}")


if __name__ == "__main__":
    main()
