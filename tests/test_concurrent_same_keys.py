"""Two writers of the same keys in one version (issue 15, part 1): the end state of a replay in commit order.

Two sessions in one version (DEFAULT, or a child of it) run seeded lists of
small transactions over a shared small key set through the versioned views:
``val = val + k`` and ``val = (3 * val + k) % 1000003`` (the two do not
commute, so the order matters), deletes, a delete and re-insert of the key,
vertex moves ``z = z + k`` and ``z = k - z`` on tgsis.vrtx; some transactions
are rolled back. A transaction failing with 40001 (serialization_failure) is
rolled back and run again from its start, as a client must.

The oracle: every committed transaction, replayed one after the other in
*commit order* on a plain database (no versioning), must report the same row
count for each statement, and the end states must be equal.

Why the replay in commit order is sound (a plain table gives the same):
* commit order is known: the last statement before COMMIT takes an
  exclusive advisory lock, which PostgreSQL releases after the commit is
  visible, and then draws a ticket from a sequence; tickets are drawn in
  commit order (a ticket of a failed COMMIT would be dropped);
* READ COMMITTED is not serializable in general, but here every statement
  acts on one key, and what it does depends only on that key's row as it is
  when the statement locks it (``val = val + k``, a delete) -- PostgreSQL's
  re-check on a plain table, and the view's trigger by design (or it refuses
  with 40001). Row locks are held until commit and each transaction touches
  its keys in one global order (no deadlock), so the writes of one key are
  ordered as their transactions commit;
* what a row lock cannot order is a key's *absence*: an UPDATE finding no row
  holds no lock, so a re-insert committing after it but before its
  transaction would put it out of commit order (and the delete + re-insert in
  one transaction hides the new row from a waiting UPDATE on a plain table).
  So each transaction first takes a per-key advisory lock of the keys it
  touches, in key order: shared for updates and deletes (which still meet in
  the view's trigger), exclusive for the re-insert (which waits for every
  transaction that touched the key). Vertices are never deleted: no lock.

The focused interleavings of each pair of writes are in
tests/test_concurrent_writes.py; this test runs many of them, in varied
states (rows of an older revision and of the working one, rows deleted and
inserted again), and checks the whole end state.

``TGSIS_CONCURRENCY_SEED`` and ``TGSIS_SAME_KEYS_TXNS`` run it with other (or
longer) lists.
"""

from __future__ import annotations

import os
import random
import re
import threading
import time
from collections import Counter
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import psycopg
import pytest

import tgsis
from tests.sessions import connect
from tests.synthetic import flat_grid
from tests.test_concurrency import invariant_problems
from tgsis.db import features as F

Conn = psycopg.Connection[Any]

SEED = int(os.environ.get("TGSIS_CONCURRENCY_SEED", "5"))
TXNS = int(os.environ.get("TGSIS_SAME_KEYS_TXNS", "300"))  # transactions per session
SESSIONS = 2
ITEM_KEYS = range(1, 7)  # items.id 1..6, shared by both sessions
FEATURES = ("A", "B")  # two surfaces (3 x 3 grids); vertices 0..2 of each are written
VERTICES = range(3)
OWN = (2, 4, 6)  # rows rewritten in the version's working revision before the run
ANCHOR = 15001  # advisory lock space (int4, int4) of the key locks; the commit lock is 15002
MAX_RETRIES = 50  # of one transaction: more is a livelock, not contention
DEADLINE = 120.0

Op = tuple[Any, ...]


@dataclass(frozen=True)
class Txn:
    ops: tuple[Op, ...]
    rollback: bool = False


def _key(op: Op) -> tuple[int, ...]:
    """The global order of keys: items first, then vertices."""
    return (0, op[1]) if op[0] in ("add", "mix", "del", "reins") else (1, FEATURES.index(op[1]), op[2])


def generate(rng: random.Random, count: int) -> list[Txn]:
    """``count`` transactions of 1-3 ops on distinct keys, in key order."""
    txns = []
    for _ in range(count):
        ops: dict[tuple[int, ...], Op] = {}
        for _ in range(rng.randint(1, 3)):
            kind = rng.choices(["add", "mix", "del", "reins", "z", "zflip"], [30, 15, 6, 12, 25, 10])[0]
            k = rng.randrange(1, 100)
            if kind in ("z", "zflip"):
                op: Op = (kind, rng.choice(FEATURES), rng.choice(VERTICES), float(k))
            elif kind == "mix":
                op = (kind, rng.choice(ITEM_KEYS), k, f"m{k}")
            elif kind == "del":
                op = (kind, rng.choice(ITEM_KEYS))
            else:
                op = (kind, rng.choice(ITEM_KEYS), k)
            ops.setdefault(_key(op), op)
        txns.append(Txn(tuple(op for _, op in sorted(ops.items())), rollback=rng.random() < 0.1))
    return txns


def apply_op(conn: Conn, geoids: dict[str, int], op: Op) -> tuple[int, ...]:
    """Run one op; its statements' row counts."""
    kind = op[0]
    if kind == "add":
        return (conn.execute("UPDATE items SET val = val + %s WHERE id = %s", (op[2], op[1])).rowcount,)
    if kind == "mix":
        return (
            conn.execute(
                "UPDATE items SET val = (3 * val + %s) %% 1000003, note = %s WHERE id = %s", (op[2], op[3], op[1])
            ).rowcount,
        )
    if kind == "del":
        return (conn.execute("DELETE FROM items WHERE id = %s", (op[1],)).rowcount,)
    if kind == "reins":
        deleted = conn.execute("DELETE FROM items WHERE id = %s", (op[1],)).rowcount
        return deleted, conn.execute("INSERT INTO items VALUES (%s, %s, 'again')", (op[1], op[2])).rowcount
    sql = "z + %s" if kind == "z" else "%s - z"
    return (
        conn.execute(
            f"UPDATE tgsis.vrtx SET z = {sql} WHERE geoid = %s AND vrtxid = %s", (op[3], geoids[op[1]], op[2])
        ).rowcount,
    )


def lock_keys(conn: Conn, txn: Txn) -> None:
    """The per-key locks that put a key's absence in commit order too (see the module's docstring)."""
    for op in txn.ops:  # in key order already
        if op[0] in ("add", "mix", "del", "reins"):
            mode = "" if op[0] == "reins" else "_shared"
            conn.execute(f"SELECT pg_advisory_xact_lock{mode}(%s, %s)", (ANCHOR, op[1]))


def setup_database(conn: Conn, version: str, versioned: bool) -> dict[str, int]:
    """items 1..6 (val 100 * id) and the surfaces; versioned: also a child version 'child'; then rows OWN and
    vertex 1 of A rewritten in ``version`` (its working revision). Returns the geoids."""
    conn.execute("CREATE TABLE items (id int PRIMARY KEY, val int NOT NULL, note text NOT NULL)")
    conn.execute("INSERT INTO items SELECT g, 100 * g, 'seed' FROM generate_series(1, 6) g")
    fc = F.create_feature_class(conn, "horizons", "SURFACE")
    if versioned:
        tgsis.enable_versioning(conn, "items", "id", "item")
        tgsis.enable_feature_versioning(conn)
    geoids = {}
    for i, name in enumerate(FEATURES):
        mesh = flat_grid(3, float(i))
        geoids[name] = F.insert_feature(conn, fc, tgsis.Surface(mesh.vertices, mesh.cells, name=name))
    conn.commit()
    if versioned:
        tgsis.create_version(conn, "child")
        tgsis.goto_version(conn, version)
    conn.execute("UPDATE items SET note = 'own' WHERE id = ANY (%s)", (list(OWN),))
    conn.execute("UPDATE tgsis.vrtx SET z = 1 WHERE geoid = %s AND vrtxid = 1", (geoids["A"],))
    conn.execute("CREATE SEQUENCE commit_order")
    conn.commit()
    return geoids


def content(conn: Conn, version: str | None) -> tuple[list[tuple[Any, ...]], list[tuple[Any, ...]]]:
    """items and the vertices of the surfaces, by name, as ``version`` shows them (None: a plain database)."""
    if version is not None:
        conn.execute("SELECT tgsis.goto_version(%s, true)", (version,))
    items = conn.execute("SELECT id, val, note FROM items ORDER BY id").fetchall()
    vertices = conn.execute(
        "SELECT g.geoname, v.vrtxid, v.x, v.y, v.z FROM tgsis.vrtx v JOIN tgsis.geometry g USING (geoid) ORDER BY 1, 2"
    ).fetchall()
    conn.rollback()
    return items, vertices


@dataclass
class Run:
    """What the sessions report."""

    committed: list[tuple[int, int, int, tuple[tuple[int, ...], ...]]] = field(default_factory=list)
    # ticket, session, transaction index, row counts per op
    retries: Counter[str] = field(default_factory=Counter)  # 40001 by message
    errors: list[str] = field(default_factory=list)
    lock: threading.Lock = field(default_factory=threading.Lock)


def run_session(
    dsn: str, version: str, session: int, txns: Sequence[Txn], run: Run, barrier: threading.Barrier
) -> None:
    k = 0
    rng = random.Random(session)
    try:
        with connect(dsn, f"same-keys-{session}") as conn:
            tgsis.goto_version(conn, version)
            geoids = {
                name: int(g)
                for name, g in conn.execute(
                    "SELECT geoname, geoid FROM tgsis.geometry WHERE geoname = ANY (%s)", (list(FEATURES),)
                )
            }
            conn.commit()
            barrier.wait()
            for k, txn in enumerate(txns):
                for attempt in range(MAX_RETRIES + 1):
                    try:
                        lock_keys(conn, txn)
                        counts = tuple(apply_op(conn, geoids, op) for op in txn.ops)
                        if txn.rollback:
                            conn.rollback()
                            break
                        conn.execute("SELECT pg_advisory_xact_lock(15002, 0)")  # held until after COMMIT
                        ticket = conn.execute("SELECT nextval('commit_order')").fetchone()
                        conn.commit()
                        assert ticket is not None
                        with run.lock:
                            run.committed.append((int(ticket[0]), session, k, counts))
                        break
                    except psycopg.errors.SerializationFailure as exc:
                        conn.rollback()
                        if attempt == MAX_RETRIES or run.errors:
                            raise
                        with run.lock:
                            run.retries[re.sub(r"[0-9]+", "N", exc.diag.message_primary or str(exc))] += 1
                        time.sleep(rng.uniform(0, 0.002))
    except BaseException as exc:  # noqa: BLE001 - every failure is reported by the test
        with run.lock:
            run.errors.append(
                f"session {session}, transaction {k} {txns[k] if k < len(txns) else ''}: {type(exc).__name__}: {exc}"
            )
        barrier.abort()


@pytest.mark.parametrize("version", ["DEFAULT", "child"])
def test_two_writers_of_the_same_keys_end_as_a_replay_in_commit_order(
    db_dsn: str, make_database: Callable[..., str], template_db: str, version: str
) -> None:
    rng = random.Random(f"{SEED}-{version}")
    lists = [generate(random.Random(rng.randrange(2**32)), TXNS) for _ in range(SESSIONS)]
    with connect(db_dsn, "setup") as conn:
        setup_database(conn, version, versioned=True)
        other = "child" if version == "DEFAULT" else "DEFAULT"
        other_before = content(conn, other)

    run = Run()
    barrier = threading.Barrier(SESSIONS)
    threads = [
        threading.Thread(target=run_session, args=(db_dsn, version, s, lists[s], run, barrier), daemon=True)
        for s in range(SESSIONS)
    ]
    started = time.monotonic()
    for t in threads:
        t.start()
    for t in threads:
        t.join(max(0.0, started + DEADLINE - time.monotonic()))
    elapsed = time.monotonic() - started
    assert not any(t.is_alive() for t in threads), f"seed {SEED}: the sessions did not finish in {DEADLINE} s"
    assert not run.errors, f"seed {SEED}: " + "\n".join(run.errors)
    expected_commits = sum(not txn.rollback for txns in lists for txn in txns)
    tickets = sorted(t for t, _, _, _ in run.committed)
    assert len(tickets) == expected_commits and len(set(tickets)) == len(tickets)

    # the oracle: the committed transactions in commit order on a plain database, with the same row counts
    replay_dsn = make_database(template_db)
    with connect(replay_dsn, "replay") as replay:
        geoids = setup_database(replay, version, versioned=False)
        for ticket, session, k, counts in sorted(run.committed):
            txn = lists[session][k]
            replayed = tuple(apply_op(replay, geoids, op) for op in txn.ops)
            replay.commit()
            assert replayed == counts, (
                f"seed {SEED}: transaction {k} of session {session} (commit {ticket}) "
                f"{txn.ops}: row counts {counts}, in the replay {replayed}"
            )
        expected = content(replay, None)

    with connect(db_dsn, "check") as conn:
        assert content(conn, version) == expected, f"seed {SEED}: the end state in {version} is not the replay's"
        assert content(conn, other) == other_before, f"the writes in {version} changed {other}"
        assert invariant_problems(conn) == []

    ops = Counter(op[0] for _, s, k, _ in run.committed for op in lists[s][k].ops)
    empty = sum(1 for _, _, _, counts in run.committed for c in counts if 0 in c)
    print(
        f"\nseed {SEED}, {version}: {elapsed:.1f} s; {len(tickets)} commits ({dict(ops)}), {empty} ops found no "
        f"row; {run.retries.total()} retries after 40001: {dict(run.retries)}"
    )
    assert run.retries.total() > 0, "the sessions never met: the test did not test anything"
