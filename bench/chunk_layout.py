"""Candidate chunk layouts for vertices and cells against today's rows (issue 40, the design note docs/storage.md).

The 1000 x 1000 grid surface of ``bench/peers.py`` (1,000,000 vertices,
1,996,002 triangles, one vertex property) is built once and stored, in one
throwaway cluster of the system PostgreSQL (``TGSIS_PG`` can point
elsewhere), in two ways:

- **today's rows**: ``insert_feature`` into versioned storage
  (``tgsis.vrtx_ver``, ``tgsis.trgl_ver``, ``horizon_cellpros_ver``: one row
  per vertex, triangle and property row, with ``revision``, ``lastrevs`` and
  ``revclosed``), downloaded with ``fetch_feature``;
- **chunks**: one row per block of N consecutive ids of one object and
  table: ``(geoid, chunk, revision, lastrevs, revclosed)`` (the columns a
  versioned chunk needs, primary key ``(geoid, chunk, revision)`` and the
  revision indexes tgsis gives ``_ver`` storage) plus one array per column:
  ``x``, ``y``, ``z`` ``float8[]``; the property ``float8[]``; the triangles'
  corners either as today's ``int8`` (``abs8``), as ``int4`` (``abs4``), or
  relative (``rel4``: a chunk's smallest corner id ``vbase`` as ``int8``,
  ``v1 - vbase``, ``v2 - v1``, ``v3 - v1`` as ``int4[]``, decoded by
  additions). Candidates: N = 256 / 1024 / 4096, TOAST compression pglz /
  lz4 / none (``STORAGE EXTERNAL``) / mixed (lz4 for doubles, pglz for
  ids), id order as the file gave it (row
  major), shuffled (a file whose order means nothing), or spatially
  coherent (vertices by the Morton code of their position, cells by their
  smallest corner).

Printed for each: bytes per vertex on disk (heap, TOAST, indexes, after
VACUUM), the upload (binary COPY of the chunk rows, encoded by numpy) and,
for some, the download (binary COPY of the visible chunks, parsed by numpy,
checked bit-exact against the surface, the ``Surface`` built), beside the
``bytea`` row of ``bench/peers.py`` (the raw bytes, uncompressed, the
``Surface`` built), today's ``fetch_feature`` and the PostGIS ``TIN Z`` row
of each surface (its size; skipped without PostGIS) in the same run. Then
the snapshot at t of the grid known at two instants (aligned vertex chunks,
interpolated in numpy) against its static download. Then the write of a spatially coherent
edit (the 1,000 and the 10,000 vertices nearest a point: a move of each
vertex): chunks touched and bytes of those chunks, per order and N, and, for
some layouts and today's rows, the versioned write itself (close the old row
or chunk versions, insert new ones) with the write-ahead log it produced.
Then a point lookup of one vertex by key and a scan of one object (today's
view; chunk by key; a view over chunks with the key as a computed column; a
view joined to a table of local ids) and the rewrite of one chunk for a
one-vertex update. The whole run takes 2-3 minutes on 2 shared cores.

Bench surface and a second one with the same triangles and irregular
positions (x, y jittered, z from them): the grid's y is constant along a
row, which compresses; real surfaces' coordinates do not.

    python bench/chunk_layout.py [--side 1000] [--repeat 3]
"""

from __future__ import annotations

import argparse
import os
import statistics
import time
from dataclasses import dataclass
from typing import Any

import numpy as np
import psycopg
from psycopg import sql
from scipy.spatial import cKDTree
from timing import paired
from transfer import grid_surface

import tgsis
from tgsis.db import features as F
from tgsis.db.local import LocalServer, find_binaries
from tgsis.mesh import morton_codes
from tgsis.postgis import mesh_to_ewkb

ARRAY_OID = {"float8": 701, "int8": 20, "int4": 23}
ELEMENT = {"float8": ">f8", "int8": ">i8", "int4": ">i4"}


@dataclass(frozen=True)
class Layout:
    """One candidate: chunk size, TOAST compression, encoding of cell corners, id order, surface."""

    n: int
    compression: str  # pglz, lz4, none, mixed (lz4 for floats, pglz for ids)
    cells: str  # abs8, abs4, rel4
    order: str  # file, shuffled, morton
    surface: str = "grid"  # grid, irregular

    @property
    def tag(self) -> str:
        return f"{self.surface}_{self.order}_{self.n}_{self.compression}_{self.cells}"


@dataclass
class Ordered:
    """A surface's arrays in one id order."""

    vertices: np.ndarray  # (n, 3) float64
    cells: np.ndarray  # (m, 3) int64
    prop: np.ndarray  # (n,) float64
    new_of_old: np.ndarray  # (n,) int64: new vertex id of each vertex of the grid
    cell_new_of_old: np.ndarray  # (m,) int64


def reorder(vertices: np.ndarray, cells: np.ndarray, prop: np.ndarray, order: str) -> Ordered:
    """The surface with vertex and cell ids renumbered in ``order``."""
    n, m = len(vertices), len(cells)
    rng = np.random.default_rng(7)
    if order == "file":
        vperm = np.arange(n)
    elif order == "shuffled":
        vperm = rng.permutation(n)
    else:
        vperm = np.argsort(morton_codes(vertices), kind="stable")  # vperm[new] = old
    new_of_old = np.empty(n, dtype=np.int64)
    new_of_old[vperm] = np.arange(n)
    renumbered = new_of_old[cells]
    if order == "file":
        cperm = np.arange(m)
    elif order == "shuffled":
        cperm = rng.permutation(m)
    else:  # cells by their smallest corner, then the others
        s = np.sort(renumbered, axis=1)
        cperm = np.lexsort((s[:, 2], s[:, 1], s[:, 0]))
    cell_new_of_old = np.empty(m, dtype=np.int64)
    cell_new_of_old[cperm] = np.arange(m)
    return Ordered(vertices[vperm], renumbered[cperm], prop[vperm], new_of_old, cell_new_of_old)


def copy_header() -> bytes:
    return b"PGCOPY\n\xff\r\n\x00" + np.array([0, 0], dtype=">i4").tobytes()


def encode_chunks(
    geoid: int,
    revision: int,
    n: int,
    columns: list[tuple[np.ndarray, str]],
    scalars: list[tuple[np.ndarray, str]] | None = None,
    first_chunk: int = 0,
) -> bytes:
    """Binary COPY rows ``(geoid, chunk, revision, scalars..., arrays...)``, one per block of ``n`` values.

    ``columns`` are (values, element type) of equal length L; row k holds
    values ``k*n .. k*n+n-1`` (the last row fewer) as one-dimensional arrays
    with lower bound 1 and no NULL. ``scalars`` hold one value per row.
    """
    length = len(columns[0][0])
    rows = -(-length // n)
    parts = [copy_header()]
    full = length // n
    for start_row, count, size in ((0, full, n), (full, rows - full, length - full * n)):
        if count == 0 or size == 0:
            continue
        fields: list[tuple[Any, ...]] = [
            ("nf", ">i2"),
            ("lg", ">i4"),
            ("geoid", ">i8"),
            ("lc", ">i4"),
            ("chunk", ">i4"),
            ("lr", ">i4"),
            ("rev", ">i4"),
        ]
        for i, (_, kind) in enumerate(scalars or []):
            fields += [(f"ls{i}", ">i4"), (f"s{i}", ELEMENT[kind])]
        for i, (_, kind) in enumerate(columns):
            fields += [
                (f"la{i}", ">i4"),
                (f"h{i}", ">i4", (5,)),
                (f"e{i}", [("l", ">i4"), ("v", ELEMENT[kind])], (size,)),
            ]
        rec = np.zeros(count, dtype=np.dtype(fields))
        rec["nf"] = 3 + len(scalars or []) + len(columns)
        rec["lg"], rec["geoid"], rec["lc"], rec["lr"], rec["rev"] = 8, geoid, 4, 4, revision
        rec["chunk"] = first_chunk + start_row + np.arange(count)
        for i, (values, kind) in enumerate(scalars or []):
            rec[f"ls{i}"] = np.dtype(ELEMENT[kind]).itemsize
            rec[f"s{i}"] = values[start_row : start_row + count]
        for i, (values, kind) in enumerate(columns):
            width = np.dtype(ELEMENT[kind]).itemsize
            rec[f"la{i}"] = 20 + size * (4 + width)
            rec[f"h{i}"] = (1, 0, ARRAY_OID[kind], size, 1)
            block = values[start_row * n : start_row * n + count * size].reshape(count, size)
            rec[f"e{i}"]["l"] = width
            rec[f"e{i}"]["v"] = block
        parts.append(rec.tobytes())
    parts.append(np.array([-1], dtype=">i2").tobytes())
    return b"".join(parts)


def decode_arrays(payload: bytes, n_arrays: int, kinds: list[str], n_scalars: int = 0) -> list[np.ndarray]:
    """The arrays of binary COPY rows ``(chunk, scalars..., arrays...)``, concatenated in row order.

    Each array is parsed as one numpy structured array (length word, value);
    scalars come back as one value per row. Elements are never NULL here.
    """
    buf = memoryview(payload)
    pos = 19
    arrays: list[list[np.ndarray]] = [[] for _ in range(n_arrays)]
    scalars: list[list[int]] = [[] for _ in range(n_scalars)]
    while True:
        nf = int.from_bytes(buf[pos : pos + 2], "big", signed=True)
        pos += 2
        if nf == -1:
            break
        pos += 8  # chunk: int4 (length word and value)
        for i in range(n_scalars):
            scalars[i].append(int.from_bytes(buf[pos + 4 : pos + 12], "big", signed=True))
            pos += 12
        for i in range(n_arrays):
            length = int.from_bytes(buf[pos : pos + 4], "big", signed=True)
            size = int.from_bytes(buf[pos + 16 : pos + 20], "big", signed=True) if length > 12 else 0
            if size:
                items = np.frombuffer(buf, dtype=[("l", ">i4"), ("v", ELEMENT[kinds[i]])], count=size, offset=pos + 24)
                arrays[i].append(items["v"])
            pos += 4 + length
    out = [np.concatenate(a) for a in arrays]
    return out + [np.array(s, dtype=np.int64) for s in scalars]


VISIBLE = "geoid = %s AND revision = ANY(%s::int4[]) AND NOT (revclosed AND lastrevs && %s::int4[])"


def create_tables(conn: psycopg.Connection[Any], layout: Layout) -> tuple[str, str, str]:
    """The three chunk tables of a layout: vertices, triangles, the property."""

    def option(column_type: str) -> sql.Composable:
        if (
            layout.compression == "none"
        ):  # STORAGE EXTERNAL after the CREATE (PostgreSQL 15 has no STORAGE clause there)
            return sql.SQL("")
        method = layout.compression
        if method == "mixed":
            method = "lz4" if column_type == "float8[]" else "pglz"
        return sql.SQL("COMPRESSION {}").format(sql.Identifier(method))

    corner = {"abs8": "int8[]", "abs4": "int4[]", "rel4": "int4[]"}[layout.cells]
    names = (f"v_{layout.tag}", f"c_{layout.tag}", f"p_{layout.tag}")
    arrays = {
        names[0]: [("x", "float8[]"), ("y", "float8[]"), ("z", "float8[]")],
        names[1]: [("v1", corner), ("v2", corner), ("v3", corner)],
        names[2]: [("porosity", "float8[]")],
    }
    for name, columns in arrays.items():
        extra = sql.SQL("vbase int8 NOT NULL, ") if (name == names[1] and layout.cells == "rel4") else sql.SQL("")
        body = sql.SQL(", ").join(
            sql.SQL("{} {} {}").format(sql.Identifier(c), sql.SQL(t), option(t)) for c, t in columns
        )
        conn.execute(
            sql.SQL(
                "CREATE TABLE chunks.{} (geoid int8 NOT NULL, chunk int4 NOT NULL, revision int4 NOT NULL, "
                "{}{}, lastrevs int4[] NOT NULL DEFAULT '{{}}', "
                "revclosed boolean GENERATED ALWAYS AS (cardinality(lastrevs) > 0) STORED, "
                "PRIMARY KEY (geoid, chunk, revision))"
            ).format(sql.Identifier(name), extra, body)
        )
        conn.execute(
            sql.SQL("CREATE INDEX ON chunks.{} USING brin (revision) WITH (autosummarize = on)").format(
                sql.Identifier(name)
            )
        )
        conn.execute(sql.SQL("CREATE INDEX ON chunks.{} (geoid) WHERE revclosed").format(sql.Identifier(name)))
        if layout.compression == "none":
            for column, _ in columns:
                conn.execute(
                    sql.SQL("ALTER TABLE chunks.{} ALTER COLUMN {} SET STORAGE EXTERNAL").format(
                        sql.Identifier(name), sql.Identifier(column)
                    )
                )
    return names


def cell_columns(
    cells: np.ndarray, n: int, kind: str
) -> tuple[list[tuple[np.ndarray, str]], list[tuple[np.ndarray, str]]]:
    """(array columns, scalar columns) of the triangles' corners in an encoding."""
    if kind == "abs8":
        return [(cells[:, i].copy(), "int8") for i in range(3)], []
    if kind == "abs4":
        assert cells.max() < 2**31
        return [(cells[:, i].astype(np.int32), "int4") for i in range(3)], []
    rows = -(-len(cells) // n)
    padded = np.full((rows * n, 3), np.iinfo(np.int64).max, dtype=np.int64)
    padded[: len(cells)] = cells
    vbase = padded.reshape(rows, n * 3).min(axis=1)
    base = np.repeat(vbase, n)[: len(cells)]
    r1 = cells[:, 0] - base
    d2 = cells[:, 1] - cells[:, 0]
    d3 = cells[:, 2] - cells[:, 0]
    for a in (r1, d2, d3):
        assert np.abs(a).max() < 2**31, "relative corners beyond int4: such a chunk would keep int8"
    return [(r1.astype(np.int32), "int4"), (d2.astype(np.int32), "int4"), (d3.astype(np.int32), "int4")], [
        (vbase, "int8")
    ]


def copy_in(conn: psycopg.Connection[Any], table: str, columns: list[str], payload: bytes) -> None:
    query = sql.SQL("COPY chunks.{} ({}) FROM STDIN (FORMAT binary)").format(
        sql.Identifier(table), sql.SQL(", ").join(map(sql.Identifier, columns))
    )
    with conn.cursor().copy(query) as copy:
        copy.write(payload)


def upload(conn: psycopg.Connection[Any], layout: Layout, names: tuple[str, str, str], data: Ordered) -> None:
    """Encode and COPY the surface's chunks (revision 0), one transaction."""
    n = layout.n
    v = data.vertices
    copy_in(
        conn,
        names[0],
        ["geoid", "chunk", "revision", "x", "y", "z"],
        encode_chunks(1, 0, n, [(v[:, 0].copy(), "float8"), (v[:, 1].copy(), "float8"), (v[:, 2].copy(), "float8")]),
    )
    arrays, scalars = cell_columns(data.cells, n, layout.cells)
    columns = ["geoid", "chunk", "revision", *(["vbase"] if scalars else []), "v1", "v2", "v3"]
    copy_in(conn, names[1], columns, encode_chunks(1, 0, n, arrays, scalars))
    copy_in(conn, names[2], ["geoid", "chunk", "revision", "porosity"], encode_chunks(1, 0, n, [(data.prop, "float8")]))
    conn.commit()


def download(
    conn: psycopg.Connection[Any],
    layout: Layout,
    names: tuple[str, str, str],
    revs: list[int],
    geoid: int = 1,
    parts: str = "vcp",
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Vertices, cells and the property of an object as the revision set sees them (decoded from chunks).

    ``parts`` says which of the three to read (v, c, p); the others come back empty.
    """
    cur = conn.cursor(binary=True)

    def rows(table: str, columns: str) -> bytes:
        query = sql.SQL("COPY (SELECT chunk, {} FROM chunks.{} WHERE {} ORDER BY chunk) TO STDOUT (FORMAT binary)")
        statement = query.format(sql.SQL(columns), sql.Identifier(table), sql.SQL(VISIBLE))
        out = bytearray()
        with cur.copy(statement, (geoid, revs, revs)) as copy:
            for block in copy:
                out += block
        return bytes(out)

    empty = np.empty(0)
    vertices, cells, prop = np.empty((0, 3)), np.empty((0, 3), dtype=np.int64), empty
    if "v" in parts:
        x, y, z = decode_arrays(rows(names[0], "x, y, z"), 3, ["float8"] * 3)
        vertices = np.stack([x, y, z], axis=1)
    kind = "int8" if layout.cells == "abs8" else "int4"
    if "c" not in parts:
        pass
    elif layout.cells == "rel4":
        r1, d2, d3, vbase = decode_arrays(rows(names[1], "vbase, v1, v2, v3"), 3, [kind] * 3, n_scalars=1)
        v1 = np.repeat(vbase, layout.n)[: len(r1)] + r1
        cells = np.stack([v1, v1 + d2, v1 + d3], axis=1)
    else:
        cells = np.stack(decode_arrays(rows(names[1], "v1, v2, v3"), 3, [kind] * 3), axis=1).astype(np.int64)
    if "p" in parts:
        (prop,) = decode_arrays(rows(names[2], "porosity"), 1, ["float8"])
    conn.commit()
    return vertices, cells, prop


def total_bytes(conn: psycopg.Connection[Any], tables: list[str]) -> int:
    total = 0
    for t in tables:
        row = conn.execute("SELECT pg_total_relation_size(%s::regclass)", (t,)).fetchone()
        assert row is not None
        total += int(row[0])
    return total


def chunk_bytes(conn: psycopg.Connection[Any], table: str) -> np.ndarray:
    """Stored bytes of each chunk row (its values as stored, compressed or not, plus header and index entry)."""
    rows = conn.execute(
        sql.SQL("SELECT chunk, pg_column_size(t.*) + 4 + 32 FROM chunks.{} t WHERE geoid = 1 ORDER BY chunk").format(
            sql.Identifier(table)
        )
    ).fetchall()
    return np.array([r[1] for r in rows], dtype=np.int64)


def wal_bytes(conn: psycopg.Connection[Any], action: Any) -> tuple[int, float]:
    """WAL bytes and seconds of ``action`` (committed)."""
    conn.commit()
    start = conn.execute("SELECT pg_current_wal_insert_lsn()").fetchone()[0]  # type: ignore[index]
    conn.commit()
    t0 = time.perf_counter()
    action()
    conn.commit()
    seconds = time.perf_counter() - t0
    written = conn.execute("SELECT pg_current_wal_insert_lsn() - %s::pg_lsn", (start,)).fetchone()[0]  # type: ignore[index]
    conn.commit()
    return int(written), seconds


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--side", type=int, default=1000)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    started = time.perf_counter()

    surface = grid_surface(args.side)
    n_v, n_c = surface.n_vertices, surface.n_cells
    base_vertices = np.asarray(surface.vertices, dtype=np.float64)
    base_cells = np.asarray(surface.cells, dtype=np.int64)
    prop = np.asarray(surface.vertex_properties["porosity"], dtype=np.float64)
    spacing = 10_000 / (args.side - 1)
    jitter = np.random.default_rng(3).uniform(-0.35 * spacing, 0.35 * spacing, (n_v, 2))
    irregular = base_vertices.copy()
    irregular[:, :2] += jitter
    irregular[:, 2] = 200 * np.sin(irregular[:, 0] / 700) * np.cos(irregular[:, 1] / 900) + np.random.default_rng(
        4
    ).normal(0, 0.5, n_v)
    print(f"surface: {n_v} vertices, {n_c} triangles, 1 vertex property (grid of bench/peers.py)")

    orders = {o: reorder(base_vertices, base_cells, prop, o) for o in ("file", "shuffled", "morton")}
    irregular_morton = reorder(irregular, base_cells, prop, "morton")

    def data_of(layout: Layout) -> Ordered:
        return irregular_morton if layout.surface == "irregular" else orders[layout.order]

    # relative corners of the chosen order: how many chunks' v2 - v1 and v3 - v1 would fit int2
    mc = orders["morton"].cells
    spans = np.abs(np.stack([mc[:, 1] - mc[:, 0], mc[:, 2] - mc[:, 0]], axis=1)).max(axis=1)
    int2_share = float(np.mean(np.maximum.reduceat(spans, np.arange(0, len(spans), 1024)) < 2**15))

    layouts = [Layout(n, c, "rel4", "morton") for n in (256, 1024, 4096) for c in ("pglz", "lz4")]
    layouts += [
        Layout(1024, "lz4", "abs8", "morton"),
        Layout(1024, "lz4", "abs4", "morton"),
        Layout(1024, "none", "rel4", "morton"),
        Layout(1024, "lz4", "rel4", "file"),
        Layout(1024, "lz4", "rel4", "shuffled"),
        Layout(1024, "mixed", "rel4", "morton"),
        Layout(4096, "mixed", "rel4", "morton"),
        Layout(1024, "lz4", "rel4", "morton", "irregular"),
        Layout(1024, "pglz", "rel4", "morton", "irregular"),
        Layout(1024, "mixed", "rel4", "morton", "irregular"),
        Layout(4096, "mixed", "rel4", "morton", "irregular"),
    ]
    chosen = Layout(1024, "mixed", "rel4", "morton")
    timed_downloads = [
        chosen,
        Layout(1024, "lz4", "rel4", "morton"),
        Layout(1024, "pglz", "rel4", "morton"),
        Layout(256, "lz4", "rel4", "morton"),
        Layout(4096, "lz4", "rel4", "morton"),
        Layout(4096, "mixed", "rel4", "morton"),
        Layout(1024, "mixed", "rel4", "morton", "irregular"),
        Layout(1024, "pglz", "rel4", "morton", "irregular"),
    ]

    binaries = find_binaries(os.environ.get("TGSIS_PG", "system"))
    print(f"server: {binaries.describe()} (throwaway cluster, fsync off, full_page_writes off)")
    server = LocalServer.throwaway(binaries)
    try:
        with psycopg.connect(server.dsn(), autocommit=True) as admin:
            admin.execute("CREATE DATABASE bench")
        conn = psycopg.connect(server.dsn("bench"))
        version = conn.execute("SHOW server_version").fetchone()[0]  # type: ignore[index]
        lz4 = conn.execute(
            "SELECT 'lz4' = ANY(enumvals) FROM pg_settings WHERE name = 'default_toast_compression'"
        ).fetchone()[0]  # type: ignore[index]
        print(f"PostgreSQL {version}; TOAST lz4 available: {lz4}")
        if not lz4:
            layouts = [lay for lay in layouts if lay.compression not in ("lz4", "mixed")]
        tgsis.install(conn, method="sql")
        F.create_feature_class(conn, "horizon", "SURFACE", cell_properties={"porosity": "double precision"})
        tgsis.enable_feature_versioning(conn)
        conn.execute("CREATE SCHEMA chunks")
        conn.commit()
        try:  # the PostGIS TIN of each surface (pglz TOAST, the server's default), as bench/peers.py stores it
            with conn.transaction():
                conn.execute("CREATE EXTENSION postgis")
            conn.execute("CREATE TABLE public.tin_peer (id int PRIMARY KEY, geom geometry(TINZ))")
            tins = {"grid": surface, "irregular": tgsis.Surface(irregular, base_cells)}
            for i, mesh in enumerate(tins.values()):
                conn.execute(
                    "INSERT INTO public.tin_peer VALUES (%s, ST_GeomFromEWKB(%b))", (i, mesh_to_ewkb(mesh, srid=None))
                )
            has_tin = True
        except psycopg.Error as error:
            print(f"no PostGIS here ({error.sqlstate}: {error}): no TIN sizes")
            conn.rollback()
            has_tin = False
        conn.execute(
            "CREATE TABLE public.bytea_peer (id int PRIMARY KEY, vertices bytea, triangles bytea, porosity bytea)"
        )
        for column in ("vertices", "triangles", "porosity"):
            conn.execute(f"ALTER TABLE public.bytea_peer ALTER COLUMN {column} SET STORAGE EXTERNAL")
        conn.commit()

        # ---- today's rows (versioned storage) and the bytea row
        t0 = time.perf_counter()
        geoid = F.insert_feature(conn, "horizon", surface)
        conn.commit()
        rows_upload = time.perf_counter() - t0
        t0 = time.perf_counter()
        conn.execute(
            "INSERT INTO public.bytea_peer VALUES (1, %b, %b, %b)",
            (base_vertices.tobytes(), base_cells.tobytes(), prop.tobytes()),
        )
        conn.commit()
        bytea_upload = time.perf_counter() - t0

        # ---- chunk layouts
        uploads: dict[str, float] = {}
        names: dict[str, tuple[str, str, str]] = {}
        for layout in layouts:
            names[layout.tag] = create_tables(conn, layout)
            conn.commit()
            data = data_of(layout)
            t0 = time.perf_counter()
            upload(conn, layout, names[layout.tag], data)
            uploads[layout.tag] = time.perf_counter() - t0
        conn.autocommit = True
        conn.execute("VACUUM ANALYZE")
        conn.autocommit = False
        today_tables = ["tgsis.vrtx_ver", "tgsis.trgl_ver", "horizon_cellpros_ver"]
        today_each = {t: total_bytes(conn, [t]) for t in today_tables}
        today = sum(today_each.values())
        bytea_bytes = total_bytes(conn, ["public.bytea_peer"])
        tin_bytes: dict[str, int] = {}
        if has_tin:
            for i, name in enumerate(("grid", "irregular")):
                row = conn.execute(
                    "SELECT pg_column_size(geom) + 24 FROM public.tin_peer WHERE id = %s", (i,)
                ).fetchone()
                assert row is not None
                tin_bytes[name] = int(row[0])
        stored = {lay.tag: total_bytes(conn, [f"chunks.{t}" for t in names[lay.tag]]) for lay in layouts}
        stored_each = {lay.tag: [total_bytes(conn, [f"chunks.{t}"]) for t in names[lay.tag]] for lay in layouts}

        # ---- downloads: bit-exact, then timed in turn with the bytea row and fetch_feature
        revs = [0]
        for layout in timed_downloads + [Layout(1024, "lz4", "abs8", "morton")]:
            if layout.tag not in names:
                continue
            data = data_of(layout)
            got_v, got_c, got_p = download(conn, layout, names[layout.tag], revs)
            assert np.array_equal(got_v.view(np.int64), data.vertices.view(np.int64)), layout.tag
            assert np.array_equal(got_c, data.cells), layout.tag
            assert np.array_equal(got_p.view(np.int64), data.prop.view(np.int64)), layout.tag

        def bytea_down() -> None:
            with conn.cursor(binary=True) as cursor:
                row = cursor.execute(
                    "SELECT vertices, triangles, porosity FROM public.bytea_peer WHERE id = 1"
                ).fetchone()
            assert row is not None
            tgsis.Surface(  # as bench/peers.py: the mesh built from the bytes
                np.frombuffer(row[0]).reshape(-1, 3),
                np.frombuffer(row[1], dtype=np.int64).reshape(-1, 3),
                vertex_properties={"porosity": np.frombuffer(row[2])},
            )
            conn.commit()

        def rows_down() -> None:
            F.fetch_feature(conn, "horizon", geoid)
            conn.commit()

        def chunk_down(layout: Layout) -> Any:
            def run() -> None:
                v, c, p = download(conn, layout, names[layout.tag], revs)
                tgsis.Surface(v, c, vertex_properties={"porosity": p})

            return run

        present = [lay for lay in timed_downloads if lay.tag in names]
        downs = paired([bytea_down, rows_down, *[chunk_down(lay) for lay in present]], args.repeat)
        down_bytea, down_rows = downs[0], downs[1]
        down_chunks = dict(zip([lay.tag for lay in present], downs[2:]))

        # ---- snapshot at t of a surface known at two instants (model 3's d4dvrtx in chunks: the same
        # node -> chunk mapping at both instants, so the interpolation is arithmetic on aligned arrays)
        snap_names = names[chosen.tag]
        later = orders["morton"].vertices.copy()
        later[:, 2] += 30 * np.sin(later[:, 0] / 1_500)
        columns = [(later[:, j].copy(), "float8") for j in range(3)]
        copy_in(
            conn, snap_names[0], ["geoid", "chunk", "revision", "x", "y", "z"], encode_chunks(2, 0, chosen.n, columns)
        )
        conn.commit()
        conn.autocommit = True
        conn.execute(sql.SQL("VACUUM ANALYZE chunks.{}").format(sql.Identifier(snap_names[0])))
        conn.autocommit = False

        def static_down() -> None:  # the baseline: one shape, vertices and triangles
            v, c, _ = download(conn, chosen, snap_names, revs, parts="vc")
            tgsis.Surface(v, c)

        def snapshot_between() -> None:  # t between the two instants: both shapes, x0 + w (x1 - x0)
            v0, c, _ = download(conn, chosen, snap_names, revs, parts="vc")
            v1, _, _ = download(conn, chosen, snap_names, revs, geoid=2, parts="v")
            tgsis.Surface(v0 + 0.25 * (v1 - v0), c)

        snap = paired([static_down, snapshot_between], args.repeat)

        # ---- a spatially coherent edit: chunks touched, bytes of those chunks
        tree = cKDTree(base_vertices[:, :2])
        centre = np.array([0.37 * 10_000, 0.61 * 10_000])
        edits = {k: np.sort(tree.query(centre, k=k)[1]) for k in (1_000, 10_000)}
        cells_of = {k: np.flatnonzero(np.isin(base_cells, e).any(axis=1)) for k, e in edits.items()}
        touched: dict[tuple[str, int, int], tuple[int, int, int]] = {}
        for order, data in orders.items():
            for n in (256, 1024, 4096):
                for k, e in edits.items():
                    vchunks = np.unique(data.new_of_old[e] // n)
                    cchunks = np.unique(data.cell_new_of_old[cells_of[k]] // n)
                    touched[(order, n, k)] = (len(vchunks), len(cchunks), len(np.unique(data.new_of_old[e] // n)))
        # bytes of the touched vertex chunks (a move: new vertex chunks, the old ones closed) per stored layout
        edit_bytes: dict[tuple[str, int], int] = {}
        for layout in layouts:
            if layout.surface != "grid":
                continue
            sizes = chunk_bytes(conn, names[layout.tag][0])
            for k, e in edits.items():
                chunks_hit = np.unique(orders[layout.order].new_of_old[e] // layout.n)
                edit_bytes[(layout.tag, k)] = int(sizes[chunks_hit].sum())
        conn.commit()

        # ---- the versioned write itself, with its WAL: today's rows vs two chunk layouts
        conn.execute("CREATE TABLE rows_vrtx AS SELECT geoid, vrtxid, x, y, z, revision, lastrevs FROM tgsis.vrtx_ver")
        conn.execute(
            "ALTER TABLE rows_vrtx ADD revclosed boolean GENERATED ALWAYS AS (cardinality(lastrevs) > 0) STORED, "
            "ADD PRIMARY KEY (geoid, vrtxid, revision)"
        )
        conn.execute("CREATE INDEX ON rows_vrtx USING brin (revision) WITH (autosummarize = on)")
        conn.execute("CREATE INDEX ON rows_vrtx (geoid) WHERE revclosed")
        conn.commit()
        conn.autocommit = True
        conn.execute("VACUUM ANALYZE rows_vrtx")
        conn.autocommit = False
        rows_geoid = int(conn.execute("SELECT min(geoid) FROM rows_vrtx").fetchone()[0])  # type: ignore[index]
        wal: dict[str, tuple[int, float]] = {}
        revision = 1
        for k, e in edits.items():
            ids = e.astype(np.int64)
            moved = base_vertices[e].copy()
            moved[:, 2] += 5.0

            def rows_edit() -> None:
                conn.execute(
                    "UPDATE rows_vrtx SET lastrevs = lastrevs || %s WHERE geoid = %s AND vrtxid = ANY(%s) "
                    "AND revision = 0 AND NOT revclosed",
                    (revision, rows_geoid, list(map(int, ids))),
                )
                with conn.cursor().copy("COPY rows_vrtx (geoid, vrtxid, x, y, z, revision) FROM STDIN") as copy:
                    for i, (x, y, z) in zip(ids, moved):
                        copy.write_row((rows_geoid, int(i), float(x), float(y), float(z), revision))

            wal[f"rows_{k}"] = wal_bytes(conn, rows_edit)
            revision += 1
            for layout in (
                chosen,
                Layout(1024, "lz4", "rel4", "morton"),
                Layout(256, "lz4", "rel4", "morton"),
                Layout(4096, "lz4", "rel4", "morton"),
            ):
                if layout.tag not in names:
                    continue
                data = orders[layout.order]
                new_ids = data.new_of_old[e]
                hit = np.unique(new_ids // layout.n)
                table = names[layout.tag][0]

                def chunk_edit(
                    layout: Layout = layout,
                    hit: np.ndarray = hit,
                    new_ids: np.ndarray = new_ids,
                    table: str = table,
                    data: Ordered = data,
                    rev: int = revision,
                ) -> None:
                    conn.execute(
                        sql.SQL(
                            "UPDATE chunks.{} SET lastrevs = lastrevs || %s WHERE geoid = 1 AND chunk = ANY(%s) "
                            "AND revision = 0 AND NOT revclosed"
                        ).format(sql.Identifier(table)),
                        (rev, list(map(int, hit))),
                    )
                    vertices = data.vertices.copy()
                    vertices[new_ids, 2] += 5.0
                    # the touched chunks in full, with the moved vertices' new values: one COPY of all of them
                    bodies = []
                    for c in hit:
                        span = np.arange(c * layout.n, min((c + 1) * layout.n, len(vertices)))
                        columns = [(vertices[span, j].copy(), "float8") for j in range(3)]
                        bodies.append(encode_chunks(1, rev, layout.n, columns, first_chunk=int(c))[19:-2])
                    payload = copy_header() + b"".join(bodies) + np.array([-1], dtype=">i2").tobytes()
                    copy_in(conn, table, ["geoid", "chunk", "revision", "x", "y", "z"], payload)

                wal[f"{layout.tag}_{k}"] = wal_bytes(conn, chunk_edit)
            revision += 1

        # ---- one vertex by key: today's view, chunk by key, a view over chunks
        key = 123_457
        table = names[chosen.tag][0]
        conn.execute(
            sql.SQL(
                "CREATE VIEW chunk_vrtx AS SELECT c.geoid, c.chunk::int8 * {} + u.o - 1 AS vrtxid, u.x, u.y, u.z "
                "FROM chunks.{} c CROSS JOIN LATERAL unnest(c.x, c.y, c.z) WITH ORDINALITY u(x, y, z, o) "
                "WHERE c.revision = ANY('{{0}}') AND NOT (c.revclosed AND c.lastrevs && '{{0}}')"
            ).format(sql.Literal(chosen.n), sql.Identifier(table))
        )
        conn.commit()

        def lookup(query: str, params: tuple[Any, ...], repeat: int = 21) -> float:
            samples = []
            for _ in range(repeat):
                t0 = time.perf_counter()
                conn.execute(query, params).fetchall()
                samples.append(time.perf_counter() - t0)
            conn.commit()
            return statistics.median(samples)

        tgsis_key = key
        lookups = {
            "rows_view": lookup("SELECT x, y, z FROM tgsis.vrtx WHERE geoid = %s AND vrtxid = %s", (geoid, tgsis_key)),
            "chunk_by_key": lookup(
                sql.SQL(
                    "SELECT x[%s], y[%s], z[%s] FROM chunks.{} WHERE geoid = 1 AND chunk = %s "
                    "AND revision = ANY('{{0}}') AND NOT (revclosed AND lastrevs && '{{0}}')"
                )
                .format(sql.Identifier(table))
                .as_string(conn),
                (key % chosen.n + 1,) * 3 + (key // chosen.n,),
            ),
            "chunk_view": lookup("SELECT x, y, z FROM chunk_vrtx WHERE geoid = 1 AND vrtxid = %s", (key,), repeat=5),
        }
        # a view that finds the chunk of a key by an index: a shared table of local ids (id, chunk, slot),
        # as long as the largest local id of any object, joined by equality (which the planner propagates)
        conn.execute(
            "CREATE TABLE public.local_ids AS SELECT g::int8 AS id, (g / %s)::int4 AS chunk, (g %% %s + 1)::int4 AS slot "
            "FROM generate_series(0, %s) g",
            (chosen.n, chosen.n, n_v - 1),
        )
        conn.execute("ALTER TABLE public.local_ids ADD PRIMARY KEY (id)")
        conn.execute(
            sql.SQL(
                "CREATE VIEW chunk_vrtx_ids AS SELECT c.geoid, i.id AS vrtxid, c.x[i.slot] AS x, c.y[i.slot] AS y, "
                "c.z[i.slot] AS z FROM chunks.{} c JOIN public.local_ids i ON i.chunk = c.chunk "
                "WHERE c.revision = ANY('{{0}}') AND NOT (c.revclosed AND c.lastrevs && '{{0}}') "
                "AND i.slot <= cardinality(c.x)"
            ).format(sql.Identifier(table))
        )
        conn.commit()
        conn.autocommit = True
        conn.execute("VACUUM ANALYZE public.local_ids")
        conn.autocommit = False
        ids_bytes = total_bytes(conn, ["public.local_ids"])
        lookups["chunk_view_ids"] = lookup("SELECT x, y, z FROM chunk_vrtx_ids WHERE geoid = 1 AND vrtxid = %s", (key,))
        # one object's vertices in full through each view (what a psql aggregate reads)
        scans = {
            "rows_view": lookup("SELECT count(*), sum(z) FROM tgsis.vrtx WHERE geoid = %s", (geoid,), repeat=3),
            "chunk_view": lookup("SELECT count(*), sum(z) FROM chunk_vrtx WHERE geoid = 1", (), repeat=3),
        }
        conn.execute("SET statement_timeout = '20s'")
        try:
            scans["chunk_view_ids"] = lookup(
                "SELECT count(*), sum(z) FROM chunk_vrtx_ids WHERE geoid = 1", (), repeat=1
            )
        except psycopg.errors.QueryCanceled:
            conn.rollback()
            scans["chunk_view_ids"] = float("inf")
        conn.execute("RESET statement_timeout")
        conn.commit()

        # ---- a one-vertex update as a chunk rewrite (new chunk version, old one closed), rolled back
        rewrite: dict[int, float] = {}
        for n in (256, 1024, 4096):
            layout = Layout(n, "lz4", "rel4", "morton")
            if layout.tag not in names:
                continue
            t_name = names[layout.tag][0]
            chunk, slot = key // n, key % n + 1
            statement = sql.SQL(
                "WITH old AS (UPDATE chunks.{t} SET lastrevs = lastrevs || 999 WHERE geoid = 1 AND chunk = %s "
                "AND revision = 0 AND NOT revclosed RETURNING geoid, chunk, x, y, z) "
                "INSERT INTO chunks.{t} (geoid, chunk, revision, x, y, z) "
                "SELECT geoid, chunk, 999, x, y, z[:%s - 1] || (z[%s] + 1.0) || z[%s + 1:] FROM old"
            ).format(t=sql.Identifier(t_name))
            samples = []
            for _ in range(7):
                t0 = time.perf_counter()
                conn.execute(statement, (chunk, slot, slot, slot))
                samples.append(time.perf_counter() - t0)
                conn.rollback()
            rewrite[n] = statistics.median(samples)
        conn.close()
    finally:
        server.destroy()

    # ---- report
    print()
    print(f"today's rows (versioned, insert_feature): upload {rows_upload:.2f} s")
    for table_name, b in today_each.items():
        print(f"  {table_name:26s} {b / 1e6:8.1f} MB")
    print(f"  total {today / 1e6:.1f} MB: {today / n_v:.1f} B/vertex")
    print(
        f"bytea row (uncompressed): {bytea_bytes / 1e6:.1f} MB, {bytea_bytes / n_v:.1f} B/vertex, upload {bytea_upload:.2f} s"
    )
    print()
    print(
        f"{'layout':40s} {'MB':>7s} {'B/vert':>7s} {'vrtx':>6s} {'trgl':>6s} {'prop':>6s} {'upload s':>9s} {'vs bytea':>8s}"
    )
    for layout in layouts:
        tag = layout.tag
        each = stored_each[tag]
        print(
            f"{tag:40s} {stored[tag] / 1e6:7.1f} {stored[tag] / n_v:7.1f} {each[0] / n_v:6.1f} {each[1] / n_v:6.1f} "
            f"{each[2] / n_v:6.1f} {uploads[tag]:9.2f} {uploads[tag] / bytea_upload:8.2f}"
        )
    print()
    print(
        f"download (medians of {args.repeat}, in turn): bytea {down_bytea:.3f} s, today's fetch_feature {down_rows:.3f} s"
    )
    for tag, t in down_chunks.items():
        print(f"  {tag:40s} {t:.3f} s: {t / down_bytea:.2f}x bytea, {t / down_rows:.2f}x fetch_feature")
    print(
        f"snapshot at t between two instants (chosen layout): {snap[1]:.3f} s vs the static download "
        f"(vertices and triangles) {snap[0]:.3f} s: {snap[1] / snap[0]:.2f}x"
    )
    print()
    print("a spatially coherent edit (k nearest vertices of a point), chunks touched: vertex / triangle chunks")
    for (order, n, k), (vc, cc, _) in touched.items():
        total_v, total_c = -(-n_v // n), -(-n_c // n)
        print(
            f"  {order:9s} N={n:5d} k={k:6d}: {vc:5d} of {total_v:5d} vertex chunks, {cc:5d} of {total_c:5d} triangle chunks"
            f" (cells incident: {len(cells_of[k])})"
        )
    print("bytes of the touched vertex chunks (a move rewrites them) vs the object's bytes in that layout:")
    for (tag, k), b in edit_bytes.items():
        print(f"  {tag:40s} k={k:6d}: {b / 1e3:9.1f} kB = {100 * b / stored[tag]:6.2f} % of {stored[tag] / 1e6:.1f} MB")
    print("versioned write of the move (old versions closed, new ones inserted), WAL bytes and time:")
    for name, (b, s) in wal.items():
        print(f"  {name:46s} {b / 1e3:9.1f} kB WAL, {s * 1e3:8.1f} ms")
    if tin_bytes:
        for name, b in tin_bytes.items():
            print(f"PostGIS TIN Z row of the {name} surface (pglz): {b / 1e6:.1f} MB, {b / n_v:.1f} B/vertex")
    print(f"chunks of 1,024 triangles (Morton order) whose v2 - v1 and v3 - v1 fit int2: {100 * int2_share:.1f} %")
    print(f"the table of local ids (0 .. {n_v - 1}) the key view needs: {ids_bytes / 1e6:.1f} MB")
    print("one object's vertices through a view, count(*) and sum(z) (medians of 3; inf: over 20 s):")
    for name, t in scans.items():
        print(f"  {name:14s} {t * 1e3:10.1f} ms")
    print("one vertex by key (medians):")
    for name, t in lookups.items():
        print(f"  {name:14s} {t * 1e3:8.3f} ms")
    print("one-vertex update as a chunk rewrite (close + insert, rolled back, medians of 7):")
    for n, t in rewrite.items():
        print(f"  N={n:5d}: {t * 1e3:7.2f} ms")
    print(f"bench wall time: {time.perf_counter() - started:.0f} s")
    print()
    print(f"today_bytes_per_vertex: {today / n_v:.1f}")
    print(f"bytea_bytes_per_vertex: {bytea_bytes / n_v:.1f}")
    for layout in layouts:
        print(f"bytes_per_vertex_{layout.tag}: {stored[layout.tag] / n_v:.1f}")
    for layout in layouts:
        print(f"upload_vs_bytea_{layout.tag}: {uploads[layout.tag] / bytea_upload:.2f}")
    print(f"today_download_vs_bytea: {down_rows / down_bytea:.2f}")
    print(f"snapshot_between_vs_static: {snap[1] / snap[0]:.2f}")
    for tag, t in down_chunks.items():
        print(f"download_vs_bytea_{tag}: {t / down_bytea:.2f}")
    for (tag, k), b in edit_bytes.items():
        print(f"edit{k}_share_of_object_{tag}: {b / stored[tag]:.4f}")
    for (order, n, k), (vc, cc, _) in touched.items():
        print(f"edit{k}_vertex_chunks_{order}_{n}: {vc}")
        print(f"edit{k}_triangle_chunks_{order}_{n}: {cc}")
    for name, (b, _) in wal.items():
        print(f"wal_bytes_{name}: {b}")
    for name, t in lookups.items():
        print(f"lookup_ms_{name}: {t * 1e3:.3f}")
    for name, t in scans.items():
        print(f"object_scan_ms_{name}: {t * 1e3:.1f}")
    for name, b in tin_bytes.items():
        print(f"tin_bytes_per_vertex_{name}: {b / n_v:.1f}")
    for layout in layouts:
        if layout.surface in tin_bytes:
            print(f"storage_vs_tin_{layout.tag}: {stored[layout.tag] / tin_bytes[layout.surface]:.2f}")
    for n, t in rewrite.items():
        print(f"one_vertex_rewrite_ms_{n}: {t * 1e3:.2f}")


if __name__ == "__main__":
    main()
