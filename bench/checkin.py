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

``--bytes`` measures issue 40's figure instead: the bytes a 1 % *spatially
local* edit writes when checked in as a new version (docs/storage.md, "Issue
40's figures"). The region is a square of the grid holding 1 % of the
vertices (100 x 100 of 1000 x 1000), in its middle; three edits of it, each
checked in into a child version of DEFAULT (feature versioning on before the
upload): ``move`` (its vertices' z + 5), ``move_property`` (the same and
their porosity changed) and ``region`` (as well the diagonals of the
region's quads flipped: 1 % of the triangles rewritten). Each check-in's
result is fetched in its version and compared with the edit. Measured per
storage (model 1 in chunks, and in rows, each in a database of its own on
one server) and per upload order
(``order="file"``: the grid's row-major order; ``order="spatial"``: the
Morton order of ``tgsis.mesh.spatial_order``): the object's bytes
(``pg_total_relation_size`` of the storage tables of ``tgsis.vrtx``,
``tgsis.trgl`` and the class's ``grid_cellpros``, named by
``tgsis.storage_table``, after the upload and VACUUM, the database holding
only this object), and for each check-in the growth of those relations
and the WAL written (``pg_current_wal_insert_lsn`` difference over the
check-in through its commit; the throwaway cluster runs full_page_writes
off, so no full-page images), each as a share of the object's bytes
(target: at most 2 %).

    python bench/checkin.py [--side 1000] [--repeat 3] [--storage chunks|rows] [--write-path client server]
    # TGSIS_PG=system|embedded; --write-path (chunks): the client's encoding of the touched chunks, the server's, or both
    python bench/checkin.py --bytes [--side 1000] [--storage chunks rows] [--order file spatial]
"""

from __future__ import annotations

import argparse
import statistics
import time
from typing import Any

import numpy as np
import psycopg
from psycopg import sql
from timing import bench_database
from transfer import grid_surface

import tgsis
from tgsis.db import versions as V
from tgsis.db.local import LocalServer, find_binaries

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


def grid_positions(mesh: tgsis.Mesh, side: int) -> tuple[np.ndarray, np.ndarray]:
    """Row and column of each vertex of a (renumbered) ``grid_surface(side)``, from its x and y."""
    step = 10_000 / (side - 1)
    return np.rint(mesh.vertices[:, 1] / step).astype(np.int64), np.rint(mesh.vertices[:, 0] / step).astype(np.int64)


def local_edit(mesh: tgsis.Mesh, side: int, kind: str) -> tgsis.Surface:
    """The square region of 1 % of the vertices in the grid's middle edited, ids and order kept.

    ``move``: its vertices' z + 5. ``move_property``: also their porosity
    changed. ``region``: as well the diagonals of the quads inside it flipped
    ((a, b, d), (a, d, c) -> (a, b, c), (b, d, c), each triangle rewritten in
    its place).
    """
    width = max(1, round(side * 0.1))  # width**2 = 1 % of side**2
    low = (side - width) // 2
    row, col = grid_positions(mesh, side)
    inside = (row >= low) & (row < low + width) & (col >= low) & (col < low + width)
    vertices, cells = mesh.vertices.copy(), mesh.cells.copy()
    porosity = mesh.vertex_properties["porosity"].copy()
    vertices[inside, 2] += 5.0
    if kind in ("move_property", "region"):
        porosity[inside] = 1.0 - porosity[inside]
    if kind == "region":
        at = np.full((side, side), -1, dtype=np.int64)
        at[row, col] = np.arange(len(row))
        n = len(vertices)
        key = np.sort(cells, axis=1) @ np.array([n * n, n, 1], dtype=np.int64)
        position = {int(k): i for i, k in enumerate(key)}
        quads = [(r, c) for r in range(low, low + width - 1) for c in range(low, low + width - 1)]
        for r, c in quads:
            a, b, cc, d = at[r, c], at[r, c + 1], at[r + 1, c], at[r + 1, c + 1]
            first = position[int(np.sort([a, b, d]) @ np.array([n * n, n, 1]))]
            second = position[int(np.sort([a, d, cc]) @ np.array([n * n, n, 1]))]
            cells[first], cells[second] = (a, b, cc), (b, d, cc)
    return tgsis.Surface(vertices, cells, vertex_properties={"porosity": porosity}, name=mesh.name)


def same_grid_surface(a: tgsis.Mesh, b: tgsis.Mesh, side: int) -> bool:
    """Same vertices (bit for bit), porosity and triangles, whatever the numbering (vertices keyed by grid position)."""
    keys = []
    for mesh in (a, b):
        row, col = grid_positions(mesh, side)
        keys.append(row * side + col)
    if any(len(np.unique(k)) != len(k) for k in keys) or len(keys[0]) != len(keys[1]):
        return False
    order = [np.argsort(k) for k in keys]
    if not np.array_equal(keys[0][order[0]], keys[1][order[1]]):
        return False
    if not np.array_equal(a.vertices[order[0]].view(np.int64), b.vertices[order[1]].view(np.int64)):
        return False
    if not np.array_equal(a.vertex_properties["porosity"][order[0]], b.vertex_properties["porosity"][order[1]]):
        return False
    cells = [np.sort(np.sort(k[m.cells], axis=1).view([("", np.int64)] * 3).ravel()) for k, m in zip(keys, (a, b))]
    return bool(np.array_equal(cells[0], cells[1]))


def relation_bytes(conn: Conn, tables: list[str]) -> list[int]:
    """``pg_total_relation_size`` of each table (heap, TOAST, indexes)."""
    row = conn.execute(
        sql.SQL("SELECT {}").format(
            sql.SQL(", ").join(sql.SQL("pg_total_relation_size({}::regclass)").format(sql.Literal(t)) for t in tables)
        )
    ).fetchone()
    assert row is not None
    return [int(v) for v in row]


def wal_lsn(conn: Conn) -> str:
    row = conn.execute("SELECT pg_current_wal_insert_lsn()::text").fetchone()
    conn.commit()
    assert row is not None
    return str(row[0])


def wal_since(conn: Conn, start: str) -> int:
    row = conn.execute("SELECT pg_current_wal_insert_lsn() - %s::pg_lsn", (start,)).fetchone()
    conn.commit()
    assert row is not None
    return int(row[0])


def bytes_of_local_edits(
    server: LocalServer, base: tgsis.Surface, side: int, storage: str, order: str
) -> dict[str, float]:
    """Object bytes, then growth and WAL of each local edit checked in as a new version (one database)."""
    database = f"bytes_{storage}_{order}"
    with psycopg.connect(server.dsn(), autocommit=True) as admin:
        admin.execute(sql.SQL("CREATE DATABASE {}").format(sql.Identifier(database)))
    figures: dict[str, float] = {}
    label = f"{storage}_{order}"
    with psycopg.connect(server.dsn(database)) as conn:
        tgsis.install(conn, method="sql", storage=storage)  # type: ignore[arg-type]
        fc = tgsis.create_feature_class(conn, "grid", "SURFACE", cell_properties={"porosity": "float8"})
        tgsis.enable_feature_versioning(conn)
        conn.commit()
        tables = [
            V.storage_table(conn, s, t) for s, t in (("tgsis", "vrtx"), ("tgsis", "trgl"), ("public", "grid_cellpros"))
        ]
        start = time.perf_counter()
        fid = tgsis.insert_feature(conn, fc, base, order=order)  # type: ignore[arg-type]
        conn.commit()
        upload = time.perf_counter() - start
        vacuum_analyze(conn)
        parts = relation_bytes(conn, tables)
        whole, geometry = sum(parts), parts[0] + parts[1]  # geometry: vertices and triangles, without the property
        conn.commit()
        print(
            f"{label}: upload {upload:.2f} s; object {whole / 1e6:.2f} MB ({whole / base.n_vertices:.1f} B/vertex: "
            + ", ".join(f"{t} {b / 1e6:.2f} MB" for t, b in zip(tables, parts))
            + ")"
        )
        figures[f"{label}_object_bytes"] = whole
        figures[f"{label}_geometry_bytes"] = geometry
        for kind in ("move", "move_property", "region"):
            version = f"edit_{kind}"
            tgsis.create_version(conn, version)
            conn.commit()
            with tgsis.in_version(conn, version):
                co = tgsis.checkout(conn, fid)
            assert co.mesh is not None
            edited = local_edit(co.mesh, side, kind)
            vacuum_analyze(conn)
            before = relation_bytes(conn, tables)
            conn.commit()
            lsn = wal_lsn(conn)
            with tgsis.in_version(conn, version):
                elapsed, result, counted = timed_checkin(conn, co, edited)
            wal = wal_since(conn, lsn)
            grew = [a - b for a, b in zip(relation_bytes(conn, tables), before)]
            growth = sum(grew)
            conn.commit()
            with tgsis.in_version(conn, version):
                stored = tgsis.fetch_feature(conn, fc, fid).mesh
            assert isinstance(stored, tgsis.Mesh) and same_grid_surface(stored, edited, side), f"{label} {kind}"
            save = result.save
            print(
                f"  {kind}: check-in {elapsed:.2f} s; {save.vertices_moved} vertices moved, "
                f"{save.property_rows_changed} property rows changed, {save.cells_removed} cells removed and "
                f"{save.cells_added} added; {counted} tuples written (server count); relations grew "
                f"{growth / 1e3:.1f} kB = {100 * growth / whole:.2f} % ("
                + ", ".join(f"{t} {b / 1e3:.1f} kB" for t, b in zip(tables, grew))
                + f"), WAL {wal / 1e3:.1f} kB = {100 * wal / whole:.2f} %; vertices and triangles alone: "
                f"{100 * (grew[0] + grew[1]) / geometry:.2f} % of theirs"
            )
            figures[f"{label}_{kind}_checkin_s"] = elapsed
            figures[f"{label}_{kind}_tuples_written"] = counted
            figures[f"{label}_{kind}_growth_bytes"] = growth
            figures[f"{label}_{kind}_wal_bytes"] = wal
            figures[f"{label}_{kind}_growth_share_pct"] = 100 * growth / whole
            figures[f"{label}_{kind}_wal_share_pct"] = 100 * wal / whole
            figures[f"{label}_{kind}_geometry_growth_share_pct"] = 100 * (grew[0] + grew[1]) / geometry
    return figures


def bytes_main(side: int, storages: list[str], orders: list[str]) -> None:
    """Issue 40's figure: bytes written by a 1 % spatially local edit checked in as a new version."""
    base = grid_surface(side)
    print(f"surface: {base.n_vertices} vertices, {base.n_cells} triangles, one vertex property (porosity)")
    binaries = find_binaries()
    print(f"server: {binaries.describe()} (throwaway cluster, fsync and full_page_writes off)")
    server = LocalServer.throwaway(binaries)
    figures: dict[str, float] = {}
    try:
        for storage in storages:
            for order in orders:
                figures.update(bytes_of_local_edits(server, base, side, storage, order))
    finally:
        server.destroy()
    for name, value in figures.items():
        print(f"{name}: {value:.4g}")


def use_write_path(path: str) -> None:
    """Check-ins on chunks write through the client's encoding (``client``) or the server's re-aggregation (``server``).

    The server's path is what the client did before ``tgsis.swap_object_chunks``: the bench switches
    the private hook of the state writer so that both are timed in one process, under one load.
    """
    from tgsis.db import _chunk_write, _state_write

    _state_write.swap_object_rows = (  # type: ignore[assignment]
        _chunk_write.swap_object_rows if path == "client" else (lambda *args, **kwargs: None)
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--side", type=int, default=1000)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--bytes", action="store_true", help="issue 40's bytes of a 1 %% local edit (above)")
    parser.add_argument(
        "--storage",
        nargs="+",
        choices=("chunks", "rows"),
        default=None,
        help="model 1's storage: --bytes measures each (default both), the check-in figures one (default chunks)",
    )
    parser.add_argument("--order", nargs="+", choices=("file", "spatial"), default=["file", "spatial"])
    parser.add_argument(
        "--write-path",
        nargs="+",
        choices=("client", "server"),
        default=["client"],
        help="chunks: who encodes the touched chunks (client: tgsis.swap_object_chunks, the default; server: "
        "tgsis.write_object_rows); both in one run give the ratio of the two on the same machine load",
    )
    args = parser.parse_args()
    if args.bytes:
        bytes_main(args.side, args.storage or ["chunks", "rows"], args.order)
        return
    args.storage = args.storage or ["chunks"]

    base = grid_surface(args.side)
    mesh_rows = 2 * base.n_vertices + base.n_cells  # vertices, their property rows, triangles
    print(f"surface: {base.n_vertices} vertices, {base.n_cells} triangles ({mesh_rows} rows with the property)")
    figures: dict[str, float] = {}
    if len(args.storage) != 1:
        parser.error("without --bytes, give one --storage (chunks or rows)")
    print(f"model 1 in {args.storage[0]}")
    with bench_database(args.storage[0]) as conn:
        fc = tgsis.create_feature_class(conn, "grid", "SURFACE", cell_properties={"porosity": "float8"})
        conn.commit()

        for versioned, path in [(v, p) for v in (False, True) for p in args.write_path]:
            label = ("versioned" if versioned else "plain") + ("" if len(args.write_path) == 1 else f"_{path}")
            if versioned and path == args.write_path[0]:
                tgsis.enable_feature_versioning(conn)
                conn.commit()
            use_write_path(path)
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
