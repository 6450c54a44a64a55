"""Where the snapshot at t of an evolving surface (model 3, rows) spends its time: computing vs reading.

The ``bench/snapshot.py`` evolving grid (one period of ``--instants``
instants, side x side nodes) and a static surface of the same size, in one
database. Timed, medians of ``--repeat`` (in this order, same process):

- ``get_at`` between two instants and at one, and ``fetch_feature`` of the
  static surface (the baseline of issue 40's figure);
- the snapshot's vertex and triangle queries (``tgsis.vertices_at``,
  ``tgsis.triangles_at``) read three ways: ``count(*)`` only (the server's
  computing, nothing sent), a binary COPY (a message per row: what
  ``get_at`` did before), :func:`tgsis.db._transfer.packed_out` (rows packed
  by the server in groups of 1,024 ids: what it does now), and one
  ``string_agg`` without groups (one ``bytea``: fewer server steps, but
  bounded by a ``bytea``'s 1 GB);
- ``packed_out`` again with ``work_mem`` 512 MB (its hash aggregate spills
  past ``work_mem`` x ``hash_mem_multiplier``);
- the read of every node position of the feature (``tgsis.d4dvrtx``, what
  ``fetch_evolving`` reads) by a COPY ordered on the server vs packed and
  ordered on the client (single runs).

    python bench/snapshot_parts.py [--side 500] [--instants 4] [--repeat 3]   # TGSIS_PG=system|embedded
"""

from __future__ import annotations

import argparse
import statistics
import time
from collections.abc import Callable
from typing import Any

import psycopg
from psycopg import sql
from snapshot import evolving_grid, vacuum_analyze
from timing import bench_database
from transfer import grid_surface

import tgsis
from tgsis.db import _transfer
from tgsis.db._temporal_common import ordered_copy
from tgsis.db.versions import storage_table

Conn = psycopg.Connection[Any]


def median_s(action: Callable[[], object], repeat: int) -> float:
    samples = []
    for _ in range(repeat):
        start = time.perf_counter()
        action()
        samples.append(time.perf_counter() - start)
    return statistics.median(samples)


def single_aggregate(conn: Conn, query: sql.Composable, columns: list[tuple[str, str]]) -> object:
    sends = sql.SQL(" || ").join(
        sql.SQL("{}(q.{})").format(sql.Identifier(_transfer.SEND_FUNCTIONS[wire]), sql.Identifier(name))
        for name, wire in columns
    )
    return conn.execute(
        sql.SQL("SELECT count(*), string_agg({}, ''::bytea) FROM ({}) q").format(sends, query), binary=True
    ).fetchall()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--side", type=int, default=500)
    parser.add_argument("--instants", type=int, default=4)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    grid = grid_surface(args.side)
    static = tgsis.Surface(grid.vertices, grid.cells, name="static")
    evolving = evolving_grid(static, [[float(k) for k in range(args.instants)]])
    mid, exact = (args.instants - 1) / 2, float(args.instants // 2)
    print(f"{static.n_vertices} nodes, {static.n_cells} triangles, {args.instants} instants; t = {mid}, {exact}")
    r = args.repeat
    figures: dict[str, float] = {}
    with bench_database() as conn:
        tgsis.create_feature_class(conn, "st", "SURFACE")
        tgsis.create_feature_class(conn, "ev", "SURFACE", time_model="EVOLVING")
        sid = tgsis.insert_feature(conn, "st", static)
        eid = tgsis.insert_feature(conn, "ev", evolving)
        conn.commit()
        vacuum_analyze(conn)
        figures["static_fetch_s"] = median_s(lambda: (tgsis.fetch_feature(conn, "st", sid), conn.commit()), r)
        figures["get_at_mid_s"] = median_s(lambda: (tgsis.get_at(conn, eid, mid), conn.commit()), r)
        figures["get_at_exact_s"] = median_s(lambda: (tgsis.get_at(conn, eid, exact), conn.commit()), r)
        conn.execute("SET jit = off")  # as get_at runs them
        parts = {
            "vertices": (
                sql.SQL("SELECT vrtxid, x, y, z FROM tgsis.vertices_at({}, {}, 'left')").format(eid, mid),
                [("vrtxid", "int8"), ("x", "float8"), ("y", "float8"), ("z", "float8")],
            ),
            "triangles": (
                sql.SQL("SELECT trglid, vrtxid1, vrtxid2, vrtxid3 FROM tgsis.triangles_at({}, {}, 'left')").format(
                    eid, mid
                ),
                [("trglid", "int8"), ("vrtxid1", "int8"), ("vrtxid2", "int8"), ("vrtxid3", "int8")],
            ),
        }
        for name, (query, columns) in parts.items():
            key = [columns[0][0]]
            figures[f"{name}_count_only_s"] = median_s(
                lambda q=query: conn.execute(sql.SQL("SELECT count(*) FROM ({}) q").format(q)).fetchall(), r
            )
            figures[f"{name}_copy_per_row_s"] = median_s(
                lambda q=query, c=columns: _transfer.copy_out(conn, q, [w for _, w in c]), r
            )
            figures[f"{name}_packed_s"] = median_s(
                lambda q=query, c=columns, k=key: _transfer.packed_out(conn, q, c, k), r
            )
            figures[f"{name}_single_aggregate_s"] = median_s(lambda q=query, c=columns: single_aggregate(conn, q, c), r)
        conn.execute("SET work_mem = '512MB'")
        for name, (query, columns) in parts.items():
            figures[f"{name}_packed_work_mem_512mb_s"] = median_s(
                lambda q=query, c=columns, k=[columns[0][0]]: _transfer.packed_out(conn, q, c, k), r
            )
        conn.execute("RESET work_mem")
        table = sql.Identifier(*storage_table(conn, "tgsis", "d4dvrtx").split("."))
        conn.commit()
        names = ["timem", "timet", "nodeid", "x", "y", "z"]
        types = ["float8", "float8", "int8", "float8", "float8", "float8"]
        figures["node_positions_ordered_copy_s"] = median_s(lambda: ordered_copy(conn, table, names, types, eid), 1)
        figures["node_positions_packed_s"] = median_s(lambda: ordered_copy(conn, table, names, types, eid, keys=3), 1)
    for name, value in figures.items():
        print(f"{name}: {value:.3f}")
    print(f"get_at_mid_vs_static: {figures['get_at_mid_s'] / figures['static_fetch_s']:.2f}")
    print(f"get_at_exact_vs_static: {figures['get_at_exact_s'] / figures['static_fetch_s']:.2f}")
    for name in parts:
        print(f"{name}_packed_vs_copy_per_row: {figures[f'{name}_packed_s'] / figures[f'{name}_copy_per_row_s']:.2f}")
    print(
        "node_positions_packed_vs_ordered_copy: "
        f"{figures['node_positions_packed_s'] / figures['node_positions_ordered_copy_s']:.2f}"
    )


if __name__ == "__main__":
    main()
