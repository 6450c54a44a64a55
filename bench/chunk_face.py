"""The relational face over chunks (issue 40): one vertex by key, and 10,000-row writes on a 1M-vertex object.

Versioning on, model 1 in chunks (the default); one object of ``--n`` vertices written by
``tgsis.write_chunk_rows``. Measured: one vertex by key through the face (``tgsis.vrtx``, the view) and
through ``tgsis.vertex`` (one chunk by its primary key), ``tgsis.vertices`` of 1,000 ids spread over the
object, and through the face (each row kept by the row trigger, all written by one call of the writer when
the statement ends) a 10,000-row ``UPDATE``, a 5,000-row ``INSERT ... SELECT`` of new ids (5 new chunks)
and a 1,000-row and a 10,000-row ``DELETE`` (and one-row ``DELETE`` transactions, as the one-row ``UPDATE``s). The baseline, in the same process: the same rows in a plain table with a
primary key (``public.plain``), the same key read and the same statements; both end with the same rows
(checked bit for bit). Also a one-row ``UPDATE`` per transaction through the face (the face's work tables
are made by each writing transaction and dropped at its commit, ``ON COMMIT DROP``): the best of
``--rounds`` rounds of ``--transactions`` transactions each, a round's mean per transaction, and the same
on the plain table; ``--one-row-only`` measures only that (run it with another checkout's sources on
``PYTHONPATH`` to compare two versions of the face in one sitting). "W2", a key-moving ``UPDATE`` through the
face (the row trigger's path that keeps the old key gone): a one-row key move per transaction (the vertex moved
to a new id and back, best of ``--rounds`` rounds, also with ``--one-row-only``) and a 10,000-row
``UPDATE ... SET vrtxid = vrtxid + n`` (its rows moved to new chunks), each against the plain table. This was tests/test_chunk_face.py's measuring
test until 2026-12-06; the test now checks the same on 20,000 vertices. Prints ``name: value`` lines.

    .venv/bin/python bench/chunk_face.py [--n 1000000] [--rounds 5] [--transactions 20] [--one-row-only]
"""

from __future__ import annotations

import argparse
import time
from typing import Any

import psycopg
from timing import bench_database, timed

Conn = psycopg.Connection[Any]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--n", type=int, default=1_000_000)
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--transactions", type=int, default=20)
    parser.add_argument("--one-row-only", action="store_true")
    args = parser.parse_args()
    n = args.n
    with bench_database() as conn:
        conn.autocommit = False
        conn.execute("SELECT tgsis.enable_feature_versioning()")
        select = "SELECT 1::bigint AS geoid, i AS vrtxid, i::float8 AS x, -i::float8 AS y, 0.5::float8 AS z"
        conn.execute(
            f"CREATE TEMP TABLE big AS {select}, false AS _delete FROM generate_series(0::bigint, %s) i", (n - 1,)
        )
        conn.execute("SELECT tgsis.write_chunk_rows('vrtx', 'pg_temp.big')")
        conn.execute(f"CREATE TABLE public.plain AS {select} FROM generate_series(0::bigint, %s) i", (n - 1,))
        conn.execute("ALTER TABLE public.plain ADD PRIMARY KEY (geoid, vrtxid)")
        conn.commit()
        conn.execute("ANALYZE tgsis.vrtx_chunk")
        conn.execute("ANALYZE public.plain")
        conn.commit()
        key = n * 2 // 3 + 7

        def one_row_transactions(table: str) -> float:
            """The best round's mean time of a one-row UPDATE transaction (committed) on ``table``."""
            best = float("inf")
            for _ in range(args.rounds):
                start = time.perf_counter()
                for i in range(args.transactions):
                    done = conn.execute(
                        f"UPDATE {table} SET z = %s WHERE geoid = 1 AND vrtxid = %s",  # noqa: S608
                        (float(i), key),
                    ).rowcount
                    conn.commit()
                    assert done == 1
                best = min(best, (time.perf_counter() - start) / args.transactions)
            return best

        def key_move_transactions(table: str) -> float:
            """The best round's mean time of a one-row key-moving UPDATE transaction (W2, committed) on ``table``."""
            best = float("inf")
            for _ in range(args.rounds):
                start = time.perf_counter()
                for _ in range(args.transactions):  # there and back: two transactions
                    for new, old in ((3 * n, key), (key, 3 * n)):
                        done = conn.execute(
                            f"UPDATE {table} SET vrtxid = %s WHERE geoid = 1 AND vrtxid = %s",  # noqa: S608
                            (new, old),
                        ).rowcount
                        conn.commit()
                        assert done == 1
                best = min(best, (time.perf_counter() - start) / (2 * args.transactions))
            return best

        def one_row_deletes(table: str, first: int) -> float:
            """The best round's mean time of a one-row DELETE transaction (committed) on ``table``, from id ``first``."""
            best = float("inf")
            for r in range(args.rounds):
                start = time.perf_counter()
                for i in range(args.transactions):
                    done = conn.execute(
                        f"DELETE FROM {table} WHERE geoid = 1 AND vrtxid = %s",  # noqa: S608
                        (first + r * args.transactions + i,),
                    ).rowcount
                    conn.commit()
                    assert done == 1
                best = min(best, (time.perf_counter() - start) / args.transactions)
            return best

        face_tx = one_row_transactions("tgsis.vrtx")
        plain_tx = one_row_transactions("public.plain")
        face_w2_tx = key_move_transactions("tgsis.vrtx")
        plain_w2_tx = key_move_transactions("public.plain")
        print(
            f"one-row UPDATE transaction, {n}-vertex object (best of {args.rounds} rounds of {args.transactions}): "
            f"through the face {face_tx * 1000:.1f} ms, of the plain table {plain_tx * 1000:.2f} ms"
        )
        print(f"face_one_row_update_tx_ms: {face_tx * 1000:.1f}")
        print(f"plain_one_row_update_tx_ms: {plain_tx * 1000:.2f}")
        print(f"face_one_row_key_move_tx_ms: {face_w2_tx * 1000:.1f}")
        print(f"plain_one_row_key_move_tx_ms: {plain_w2_tx * 1000:.2f}")
        # one-row DELETE transactions, of ids far from the statements' below (the same ids on both tables)
        face_del_tx = one_row_deletes("tgsis.vrtx", n * 5 // 6)
        plain_del_tx = one_row_deletes("public.plain", n * 5 // 6)
        print(f"face_one_row_delete_tx_ms: {face_del_tx * 1000:.1f}")
        print(f"plain_one_row_delete_tx_ms: {plain_del_tx * 1000:.2f}")
        print(f"face_one_row_delete_tx_vs_plain: {face_del_tx / plain_del_tx:.1f}")
        if args.one_row_only:
            return
        want = [(float(key), -float(key), float(args.transactions - 1))]  # z: the one-row UPDATEs' last
        face_read = "SELECT x, y, z FROM tgsis.vrtx WHERE geoid = 1 AND vrtxid = %s"
        assert conn.execute(face_read, (key,)).fetchall() == want
        assert conn.execute("SELECT * FROM tgsis.vertex(1, %s)", (key,)).fetchall() == want
        face = timed(lambda: conn.execute(face_read, (key,)).fetchall(), 5)
        function = timed(lambda: conn.execute("SELECT * FROM tgsis.vertex(1, %s)", (key,)).fetchall(), 21)
        plain = timed(
            lambda: conn.execute("SELECT x, y, z FROM public.plain WHERE geoid = 1 AND vrtxid = %s", (key,)).fetchall(),
            21,
        )
        ids = list(range(0, n, max(1, n // 1000)))
        many = timed(lambda: conn.execute("SELECT * FROM tgsis.vertices(1, %s)", (ids,)).fetchall(), 5)
        conn.commit()
        rows = min(10_000, n)

        def statement(sql: str, table: str, want: int) -> float:
            start = time.perf_counter()
            done = conn.execute(sql.format(t=table)).rowcount
            conn.commit()
            assert done == want, (sql, table, done)
            return time.perf_counter() - start

        # each statement through the face, then the same statement on the plain table, in one run
        update = f"UPDATE {{t}} SET z = z + 1 WHERE geoid = 1 AND vrtxid < {rows}"
        through_face, plain_update = statement(update, "tgsis.vrtx", rows), statement(update, "public.plain", rows)
        inserted = rows // 2
        insert = f"INSERT INTO {{t}} SELECT 1, i, i, -i, 0.25 FROM generate_series({n}::bigint, {n + inserted - 1}) i"
        face_insert = statement(insert, "tgsis.vrtx", inserted)
        plain_insert = statement(insert, "public.plain", inserted)
        # W2: the UPDATE moving its rows' keys (to new ids past the inserted ones: new chunks)
        move = (
            f"UPDATE {{t}} SET vrtxid = vrtxid + {2 * n} WHERE geoid = 1 AND vrtxid >= {rows} AND vrtxid < {2 * rows}"
        )
        face_move, plain_move = statement(move, "tgsis.vrtx", rows), statement(move, "public.plain", rows)
        # a 1,000-row DELETE (ids of two chunks), then the 10,000-row one
        small = f"DELETE FROM {{t}} WHERE geoid = 1 AND vrtxid >= {n // 2} AND vrtxid < {n // 2 + min(1000, rows)}"
        face_small, plain_small = (
            statement(small, "tgsis.vrtx", min(1000, rows)),
            statement(small, "public.plain", min(1000, rows)),
        )
        delete = f"DELETE FROM {{t}} WHERE geoid = 1 AND vrtxid < {rows}"
        face_delete, plain_delete = statement(delete, "tgsis.vrtx", rows), statement(delete, "public.plain", rows)
        same = "SELECT geoid, vrtxid, float8send(x), float8send(y), float8send(z) FROM {t} ORDER BY 1, 2"
        assert (
            conn.execute(same.format(t="tgsis.vrtx")).fetchall()
            == conn.execute(same.format(t="public.plain")).fetchall()
        )
        conn.commit()
        print(
            f"one vertex by key, {n}-vertex object: through the face {face * 1000:.1f} ms, tgsis.vertex "
            f"{function * 1000:.2f} ms, a plain table {plain * 1000:.2f} ms"
        )
        print(f"tgsis.vertices of {len(ids)} ids: {many * 1000:.1f} ms")
        print(f"{rows}-row UPDATE through the face {through_face:.2f} s, of the plain table {plain_update:.2f} s")
        print(
            f"{inserted}-row INSERT ... SELECT through the face {face_insert:.2f} s, into the plain table {plain_insert:.2f} s"
        )
        print(
            f"{rows}-row key-moving UPDATE (W2) through the face {face_move:.2f} s, of the plain table {plain_move:.2f} s"
        )
        print(f"{rows}-row DELETE through the face {face_delete:.2f} s, of the plain table {plain_delete:.2f} s")
        print(f"face_one_vertex_ms: {face * 1000:.1f}")
        print(f"vertex_function_ms: {function * 1000:.2f}")
        print(f"face_one_vertex_vs_plain: {face / plain:.0f}")
        print(f"vertex_function_vs_plain: {function / plain:.1f}")
        print(f"vertices_1000_ids_ms: {many * 1000:.1f}")
        print(f"face_update_s: {through_face:.2f}")
        print(f"face_update_vs_plain: {through_face / plain_update:.1f}")
        print(f"face_insert_select_s: {face_insert:.2f}")
        print(f"face_insert_select_vs_plain: {face_insert / plain_insert:.1f}")
        print(f"face_key_move_update_s: {face_move:.2f}")
        print(f"face_key_move_update_vs_plain: {face_move / plain_move:.1f}")
        print(f"face_delete_1000_s: {face_small:.3f}")
        print(f"face_delete_1000_vs_plain: {face_small / plain_small:.1f}")
        print(f"face_delete_s: {face_delete:.2f}")
        print(f"face_delete_vs_plain: {face_delete / plain_delete:.1f}")


if __name__ == "__main__":
    main()
