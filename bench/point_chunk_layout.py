"""Points (model 5's md_vertex, model 4's gmap_vertex) as rows vs as chunks of a 2-D float8 array: the layout's candidates.

Not tgsis's code paths (the points are not stored in chunks yet): plain
tables on a throwaway cluster, shaped as the chunk layer would shape them,
to choose the layout before building it (docs/storage.md, "G-maps (models 4
and 5)", "The points: the layout chosen"). A square grid of ``--side``^2
points in R^3 (x, y on the grid plus a random offset, z random), one object:

- ``rows``: ``(geoid, vrtxid, coordinate float8[])``, with md_vertex's GiST
  index on ``cube(coordinate)``;
- ``chunks``: ``(geoid, chunk, coordinate float8[] COMPRESSION lz4, box cube)``,
  1,024 points a chunk, the coordinate a 2-D array (slots x m), ``box`` the
  chunk's box (per axis the least and greatest coordinate) under a GiST index;
  twice: ids in row-major order of the grid, and in Morton (Z) order, a
  spatially coherent order such as an upload would choose.

Decoding a chunk's points back into one 1-D ``float8[]`` per row (the face's
job), three ways: F1 ``ARRAY(SELECT unnest(arr[o:o][:]))`` per row; F2 the
array flattened once per chunk (a LATERAL subquery) and sliced
``flat[(o-1)*m+1 : o*m]``, m = ``array_length(arr, 2)`` (m may differ per
object); F3 the m column slices ``arr[:][i:i]`` unnested side by side (the
class vector role's form: needs m fixed per table). Full scans: best of
``--repeat``; box queries (what ``tgsis.md_vertices_in_box`` runs): best of
5, each answer compared with the rows' (same ids, coordinates by
``array_send``: bit for bit). Bytes: ``pg_total_relation_size`` after VACUUM.

    python bench/point_chunk_layout.py [--side 1000 --repeat 3]    # TGSIS_PG=system|embedded
"""

from __future__ import annotations

import argparse
import re
import time
from typing import Any

import psycopg
from timing import bench_database

DECODE_F2 = """SELECT c.geoid, (c.chunk << 10) + (u.o - 1) AS vrtxid, f.flat[(u.o - 1) * f.m + 1 : u.o * f.m] AS coordinate
                 FROM {t} c
                CROSS JOIN LATERAL (SELECT ARRAY(SELECT unnest(c.coordinate)) AS flat,
                                           array_length(c.coordinate, 2) AS m OFFSET 0) f
                CROSS JOIN LATERAL unnest(c.coordinate[:][1:1]) WITH ORDINALITY AS u(x1, o)
                WHERE u.x1 IS NOT NULL"""
FORMS = {
    "rows": "SELECT geoid, vrtxid, coordinate FROM pts_rows",
    "F1 per row": """SELECT c.geoid, (c.chunk << 10) + (u.o - 1), ARRAY(SELECT unnest(c.coordinate[u.o:u.o][:]))
                       FROM pts_grid c, unnest(c.coordinate[:][1:1]) WITH ORDINALITY AS u(x1, o) WHERE u.x1 IS NOT NULL""",
    "F2 flat per chunk": DECODE_F2.format(t="pts_grid"),
    "F3 m slices": """SELECT c.geoid, (c.chunk << 10) + (u.o - 1), ARRAY[u.a, u.b, u.d]
                        FROM pts_grid c,
                             unnest(c.coordinate[:][1:1], c.coordinate[:][2:2], c.coordinate[:][3:3])
                             WITH ORDINALITY AS u(a, b, d, o)
                       WHERE u.a IS NOT NULL""",
}


def setup(conn: psycopg.Connection[Any], side: int) -> None:
    """The rows table and the two chunk tables (row-major ids, Morton ids), vacuumed."""
    conn.execute(
        """CREATE TABLE pts_rows (geoid bigint, vrtxid bigint, coordinate float8[], PRIMARY KEY (geoid, vrtxid));
           CREATE TABLE pts_src (x integer, y integer, coordinate float8[]);"""
    )
    conn.execute(
        """INSERT INTO pts_src SELECT x, y, ARRAY[x + random(), y + random(), 10 * random()]
             FROM generate_series(0, %(s)s - 1) AS x, generate_series(0, %(s)s - 1) AS y""",
        {"s": side},
    )
    # Morton order: the bits of x and y interleaved
    conn.execute(
        """CREATE FUNCTION morton(x integer, y integer) RETURNS bigint LANGUAGE sql IMMUTABLE AS $$
             SELECT sum(((x::bigint >> b) & 1) << (2 * b) | ((y::bigint >> b) & 1) << (2 * b + 1))::bigint
               FROM generate_series(0, 20) AS b $$"""
    )
    conn.execute(
        """INSERT INTO pts_rows SELECT 1, row_number() OVER (ORDER BY y, x) - 1, coordinate FROM pts_src;
           CREATE INDEX pts_rows_point ON pts_rows USING gist (cube(coordinate));"""
    )
    for table, order in (("pts_grid", "y, x"), ("pts_morton", "morton(x, y)")):
        conn.execute(
            f"""CREATE TABLE {table} (geoid bigint, chunk bigint, coordinate float8[] COMPRESSION lz4, box cube,
                                      PRIMARY KEY (geoid, chunk));
                CREATE TEMP TABLE ids AS SELECT row_number() OVER (ORDER BY {order}) - 1 AS vrtxid, coordinate FROM pts_src;
                INSERT INTO {table}
                SELECT 1, vrtxid >> 10, array_agg(coordinate ORDER BY vrtxid),
                       cube(ARRAY[min(coordinate[1]), min(coordinate[2]), min(coordinate[3])],
                            ARRAY[max(coordinate[1]), max(coordinate[2]), max(coordinate[3])])
                  FROM ids GROUP BY vrtxid >> 10;
                CREATE INDEX {table}_box ON {table} USING gist (box);
                DROP TABLE ids;"""
        )
    conn.commit()
    conn.autocommit = True
    for t in ("pts_rows", "pts_grid", "pts_morton"):
        conn.execute(f"VACUUM (ANALYZE) {t}")
    conn.autocommit = False


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--side", type=int, default=1000)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    n = args.side**2
    figures: dict[str, float] = {}  # the closing name: value lines
    with bench_database() as conn:
        setup(conn, args.side)
        for t in ("pts_rows", "pts_grid", "pts_morton"):
            row = conn.execute("SELECT pg_total_relation_size(%s::regclass)", (t,)).fetchone()
            assert row is not None
            print(f"bytes {t}: {row[0] / n:.1f} B/point")
            figures[f"bytes_per_point_{t[4:]}"] = row[0] / n
        # the Morton table's ids differ from the rows'; its answers are compared through the grid cells' coordinates
        differ = conn.execute(
            "SELECT count(*) FROM pts_rows r FULL JOIN ({}) d USING (geoid, vrtxid) "
            "WHERE array_send(r.coordinate) IS DISTINCT FROM array_send(d.coordinate)".format(
                DECODE_F2.format(t="pts_grid")
            )
        ).fetchone()
        print("F2 rows differing from the row table (bits):", differ)
        base = None
        for name, q in FORMS.items():
            best = float("inf")
            for _ in range(args.repeat):
                start = time.perf_counter()
                conn.execute(f"SELECT count(*), sum(cardinality(x.c)) FROM ({q}) AS x(g, v, c)").fetchone()
                best = min(best, time.perf_counter() - start)
            base = base or best
            print(f"full scan {name}: {best:.3f} s ({best / base:.2f}x rows)")
            figures[f"full_scan_{_slug(name)}_over_rows"] = best / base
        conn.commit()
        s = args.side
        for lo, hi in ((s // 10, s // 10 + 10), (s // 10, s // 10 + 100), (0, s // 2)):
            box = f"cube(ARRAY[{lo}, {lo}, '-Infinity']::float8[], ARRAY[{hi}, {hi}, 'Infinity']::float8[])"
            rows_q = f"SELECT coordinate FROM pts_rows WHERE cube(coordinate) <@ {box} AND geoid = 1"
            answers: dict[str, list[bytes]] = {}
            times: dict[str, float] = {}
            for name, q in (
                ("rows (GiST per point)", rows_q),
                *(
                    (
                        f"chunks {t[4:]} (GiST per chunk box)",
                        f"SELECT d.coordinate FROM pts_{t[4:]} c0, LATERAL ({DECODE_F2.format(t='(SELECT c0.*) ')}) d "
                        f"WHERE c0.box && {box} AND c0.geoid = 1 AND cube(d.coordinate) <@ {box}",
                    )
                    for t in ("pts_grid", "pts_morton")
                ),
            ):
                best = float("inf")
                for _ in range(5):
                    start = time.perf_counter()
                    got = conn.execute(f"SELECT array_send(x.coordinate) FROM ({q}) AS x").fetchall()
                    best = min(best, time.perf_counter() - start)
                answers[name] = sorted(bytes(r[0]) for r in got)
                chunks = ""
                if "chunks" in name:
                    tab = "pts_grid" if "grid" in name else "pts_morton"
                    row = conn.execute(f"SELECT count(*) FROM {tab} WHERE box && {box}").fetchone()
                    assert row is not None
                    chunks = f", {row[0]} chunks read"
                print(f"box {lo}..{hi} {name}: {best * 1000:.1f} ms, {len(got)} points{chunks}")
                times[name] = best
            first = next(iter(answers.values()))
            print("  same points, bit for bit:", all(a == first for a in answers.values()))
            rows_time = times["rows (GiST per point)"]
            for name, best in times.items():
                if name.startswith("chunks"):
                    figures[f"box_{hi - lo}_{_slug(name.split()[1])}_over_rows"] = best / rows_time
            conn.commit()
    for name, value in figures.items():
        print(f"{name}: {value:.2f}")


def _slug(name: str) -> str:
    """A figure's name part: ``name``'s letters and digits, lower case, the rest one underscore."""
    return re.sub(r"[^a-z0-9]+", "_", name.lower()).strip("_")


if __name__ == "__main__":
    main()
