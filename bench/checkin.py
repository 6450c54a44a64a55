"""Check-in of a 1 % edit of a 1M-vertex surface vs a full upload, and the rows it writes.

A bumpy 1000 x 1000 grid (1M vertices, 1,996,002 triangles, a vertex
property) is stored, checked out, edited and checked in:

- **1 % edit**: 1 % of the vertices moved (z + 5), 3 quad diagonals flipped,
  vertex and triangle order shuffled (as a desktop tool re-exporting the mesh
  would);
- **mixed edit** (reported, not a target): as well 1 % of the vertices
  removed with their triangles and 1 % of the triangles split by a new
  vertex at their centroid.

Timed: ``tgsis.checkin`` (fingerprint of the stored object, comparison with
the checked-out base, writes, commit) against the baseline in the same
process: ``tgsis.insert_feature`` of the same edited mesh (a full
re-upload). Rows written are counted twice: by the check-in's own result
and, independently, by the server's ``pg_stat_xact_user_tables`` (inserted +
updated + deleted tuples) read before commit. Then the same with feature
versioning on (check-in into DEFAULT: closing a row is an update of its
``lastrevs``). tgsis is installed from the client's SQL sources.

    python bench/checkin.py [--side 1000] [--repeat 3]      # TGSIS_PG=system|embedded
"""

from __future__ import annotations

import argparse
import statistics
import time
from typing import Any

import numpy as np
import psycopg
from timing import bench_database
from transfer import grid_surface

import tgsis

Conn = psycopg.Connection[Any]


def shuffled(
    vertices: np.ndarray, cells: np.ndarray, porosity: np.ndarray, rng: np.random.Generator, name: str | None
) -> tgsis.Surface:
    vperm, cperm = rng.permutation(len(vertices)), rng.permutation(len(cells))
    rank = np.empty_like(vperm)
    rank[vperm] = np.arange(len(vperm))
    return tgsis.Surface(
        vertices[vperm], rank[cells[cperm]], vertex_properties={"porosity": porosity[vperm]}, name=name
    )


def one_percent_edit(mesh: tgsis.Mesh, seed: int) -> tgsis.Surface:
    """1 % of the vertices moved up, 3 diagonals flipped, everything shuffled."""
    rng = np.random.default_rng(seed)
    vertices, cells = mesh.vertices.copy(), mesh.cells.copy()
    vertices[rng.choice(len(vertices), len(vertices) // 100, replace=False), 2] += 5.0
    half = len(cells) // 2
    for q in rng.choice(half, 3, replace=False):
        a, b, d = cells[q]
        c = cells[half + q][2]
        cells[q], cells[half + q] = (a, b, c), (b, d, c)
    return shuffled(vertices, cells, mesh.vertex_properties["porosity"], rng, mesh.name)


def mixed_edit(mesh: tgsis.Mesh, seed: int) -> tgsis.Surface:
    """1 % moved, 1 % of the vertices removed with their triangles, 1 % of the triangles split, shuffled."""
    rng = np.random.default_rng(seed)
    n = mesh.n_vertices
    vertices, cells = mesh.vertices.copy(), mesh.cells.copy()
    porosity = mesh.vertex_properties["porosity"].copy()
    vertices[rng.choice(n, n // 100, replace=False), 2] += 5.0
    removed = np.zeros(n, dtype=bool)
    removed[rng.choice(n, n // 100, replace=False)] = True
    cells = cells[~removed[cells].any(axis=1)]
    split = rng.choice(len(cells), len(cells) // 100, replace=False)
    centre = vertices[cells[split]].mean(axis=1)
    new_ids = n + np.arange(len(split))
    a, b, c = cells[split, 0], cells[split, 1], cells[split, 2]
    keep = np.ones(len(cells), dtype=bool)
    keep[split] = False
    cells = np.concatenate(
        [cells[keep], np.stack([a, b, new_ids], 1), np.stack([b, c, new_ids], 1), np.stack([c, a, new_ids], 1)]
    )
    vertices = np.concatenate([vertices, centre])
    porosity = np.concatenate([porosity, np.full(len(split), 0.5)])
    used = np.zeros(len(vertices), dtype=bool)
    used[cells] = True
    used[:n][~removed] = True  # isolated survivors stay (none on a grid)
    renumber = np.cumsum(used) - 1
    return shuffled(vertices[used], renumber[cells], porosity[used], rng, mesh.name)


def vacuum_analyze(conn: Conn) -> None:
    """What autovacuum does soon after an upload (VACUUM runs outside a transaction)."""
    conn.autocommit = True
    try:
        conn.execute("VACUUM ANALYZE")
    finally:
        conn.autocommit = False


def tuples_written(conn: Conn) -> int:
    row = conn.execute(
        "SELECT coalesce(sum(n_tup_ins + n_tup_upd + n_tup_del), 0) FROM pg_stat_xact_user_tables"
    ).fetchone()
    return int(row[0]) if row else 0


def timed_checkin(conn: Conn, co: tgsis.Checkout, edited: tgsis.Surface) -> tuple[float, tgsis.CheckinResult, int]:
    """Check-in time (through commit), its result, and the tuples the server counted."""
    start = time.perf_counter()
    with conn.transaction():
        result = tgsis.checkin(conn, co, edited)
        counted = tuples_written(conn)
    conn.commit()
    return time.perf_counter() - start, result, counted


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--side", type=int, default=1000)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()

    base = grid_surface(args.side)
    mesh_rows = 2 * base.n_vertices + base.n_cells  # vertices, their property rows, triangles
    print(f"surface: {base.n_vertices} vertices, {base.n_cells} triangles ({mesh_rows} rows with the property)")
    figures: dict[str, float] = {}
    with bench_database() as conn:
        fc = tgsis.create_feature_class(conn, "grid", "SURFACE", cell_properties={"porosity": "float8"})
        conn.commit()

        for versioned in (False, True):
            label = "versioned" if versioned else "plain"
            if versioned:
                tgsis.enable_feature_versioning(conn)
                conn.commit()
            edits = [one_percent_edit(base, seed) for seed in range(args.repeat)]
            uploads, checkins, fractions, counted_fractions = [], [], [], []
            for k, edited in enumerate(edits):
                start = time.perf_counter()
                fid = tgsis.insert_feature(conn, fc, edited)
                conn.commit()
                uploads.append(time.perf_counter() - start)
                tgsis.delete_feature(conn, fc, fid)
                conn.commit()
                fid = tgsis.insert_feature(conn, fc, base)
                conn.commit()
                vacuum_analyze(conn)
                start = time.perf_counter()
                co = tgsis.checkout(conn, fid)
                checkout_s = time.perf_counter() - start
                elapsed, result, counted = timed_checkin(conn, co, edited)
                checkins.append(elapsed)
                fractions.append(result.save.rows_written / mesh_rows)
                counted_fractions.append(counted / mesh_rows)
                print(
                    f"  {label} run {k}: upload {uploads[-1]:.2f} s, checkout {checkout_s:.2f} s, "
                    f"check-in {elapsed:.2f} s; {result.save.vertices_moved} vertices moved, "
                    f"{result.save.rows_written} rows written ({counted} counted by the server)"
                )
                tgsis.delete_feature(conn, fc, fid)
                conn.commit()
            upload, checkin = statistics.median(uploads), statistics.median(checkins)
            print(
                f"{label}: full upload {upload:.2f} s, 1 % edit check-in {checkin:.2f} s "
                f"({checkin / upload:.3f} of the upload); rows written {100 * max(fractions):.2f} % of the mesh's "
                f"(server count {100 * max(counted_fractions):.2f} %)"
            )
            figures[f"{label}_upload_s"] = upload
            figures[f"{label}_checkin_s"] = checkin
            figures[f"{label}_checkin_vs_upload"] = checkin / upload
            figures[f"{label}_checkin_rows_fraction"] = max(counted_fractions)

            fid = tgsis.insert_feature(conn, fc, base)
            conn.commit()
            co = tgsis.checkout(conn, fid)
            elapsed, result, counted = timed_checkin(conn, co, mixed_edit(base, 7))
            print(
                f"{label} mixed edit (1 % moved, 1 % removed, 1 % of the triangles split): check-in "
                f"{elapsed:.2f} s, {result.save.diff}, {result.save.vertices_moved} moved; "
                f"{counted} rows written ({100 * counted / mesh_rows:.2f} %)"
            )
            figures[f"{label}_mixed_checkin_s"] = elapsed
            figures[f"{label}_mixed_rows_fraction"] = counted / mesh_rows
            tgsis.delete_feature(conn, fc, fid)
            conn.commit()
    for name, value in figures.items():
        print(f"{name}: {value:.4g}")


if __name__ == "__main__":
    main()
