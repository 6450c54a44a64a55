"""Concurrency of versions (issues 5 and 15): two writers in each of four versions and in DEFAULT while another
session merges.

The spec (versioning.md, "locking") asks that merges and refreshes serialize
with the writers of the versions involved, that concurrent create_version
calls never hand out the same revision, and that a second merge of the same
version waits or fails clearly.

The main test runs real threads, each with its own connection: ten writers,
two in each of four children of DEFAULT (w0..w3) and two in DEFAULT itself,
run seeded lists of small transactions on keys no other session touches (rows
of a plain versioned table through its INSTEAD OF trigger; surfaces through
the bulk COPY path, the set-based delete and plain SQL on the model-1 tables;
saved revisions; rolled-back transactions), while a merging session merges the
four versions into DEFAULT (without removing them), refreshes them, creates
versions under DEFAULT and under the writers' versions, and merges and
refreshes those. A writer's transaction that fails with 40001
(serialization_failure) is run again from its start, as a client must (the
view's trigger refuses a write it would have computed from a stale row); the
retries are counted and printed. Every other error fails the test: a deadlock
(40P01), a lock wait longer than the safety-net ``lock_timeout``, a wrong row
count in a writer.

The oracle is the same lists replayed one after the other on a *plain*
database (no versioning at all) and, for the states in between, a Python model
of the lists: whatever a merge, a new version or a frozen revision shows of
one writer's keys must be the state after a whole number of that writer's
transactions, never going backwards. Each owner (writer) keeps its own keys, so
the other writer of its version changes nothing the model of its list holds.

The focused tests below hold one side of a lock open and check that the other
side waits (``pg_blocking_pids``) and then does the right thing.

``TGSIS_CONCURRENCY_SEED`` and ``TGSIS_CONCURRENCY_TXNS`` run the main test with
other (or longer) lists.
"""

from __future__ import annotations

import copy
import os
import random
import re
import statistics
import threading
import time
from collections import Counter
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import psycopg
import pytest

import tgsis
from tests.sessions import Background, connect, wait_until_blocked
from tests.synthetic import flat_grid
from tgsis.db import features as F

Conn = psycopg.Connection[Any]

SEED = int(os.environ.get("TGSIS_CONCURRENCY_SEED", "5"))
WRITERS = 4  # versions w0..w3, children of DEFAULT, are written by their writers
PER_VERSION = 2  # writers in each of w0..w3 and in DEFAULT
OWNERS = range(PER_VERSION * (WRITERS + 1))  # owner o writes in slot o % 5: w0..w3, or DEFAULT (4 and 9)
PARENTS = tuple(o for o in OWNERS if o % (WRITERS + 1) == WRITERS)  # the owners writing in DEFAULT
WRITER_TXNS = int(os.environ.get("TGSIS_CONCURRENCY_TXNS", "200"))  # transactions per writer
PARENT_TXNS = WRITER_TXNS // 2  # transactions per writer in DEFAULT
MAX_NEW_VERSIONS = 14  # versions the merging session creates while the writers run
MIN_MERGES = 6  # writers pause half-way until that many merges landed
DEADLINE = 150.0  # seconds for the whole concurrent phase (test-level timeout)

ITEMS = "CREATE TABLE items (obj int, part int, val int NOT NULL, note text NOT NULL, PRIMARY KEY (obj, part))"
GRID = flat_grid(3, 0.0)  # every feature is a 3 x 3 grid: 9 vertices, 8 triangles
TRIANGLES = tuple((i, *map(int, t)) for i, t in enumerate(GRID.cells))

# --------------------------------------------------------------------------- the transaction lists and their model

Op = tuple[Any, ...]
Item = tuple[int, int, int, str]  # obj, part, val, note
Feat = tuple[str, str, tuple[tuple[float, ...], ...], tuple[float, ...], tuple[tuple[int, ...], ...]]
OwnerContent = tuple[tuple[Item, ...], tuple[Feat, ...]]  # what one owner's keys hold


@dataclass(frozen=True)
class Txn:
    ops: tuple[Op, ...]
    rollback: bool = False  # run, then roll back: nothing of it may remain


@dataclass
class _Feature:
    label: str
    z: list[float]
    poro: list[float]


def owners_in(w: int) -> tuple[int, ...]:
    """The owners writing in version ``w{w}``."""
    return tuple(o for o in OWNERS if o % (WRITERS + 1) == w)


def owner_of_obj(obj: int) -> int:
    return obj // 1000


def owner_of_name(name: str) -> int:
    return int(name[1 : name.index("-")])


def surface(z0: float, poro0: float, name: str) -> tgsis.Surface:
    vertices = GRID.vertices.copy()
    vertices[:, 2] = z0
    return tgsis.Surface(
        vertices, GRID.cells.copy(), vertex_properties={"porosity": poro0 + 0.25 * np.arange(len(vertices))}, name=name
    )


class Model:
    """What one owner's keys hold after each transaction of its list."""

    def __init__(self, owner: int) -> None:
        self.owner = owner
        self.items: dict[tuple[int, int], tuple[int, str]] = {}
        self.features: dict[str, _Feature] = {}
        self.next_obj = owner * 1000 + 100
        self.next_feature = 0
        for j in range(4):
            for part in range(3):
                self.items[(owner * 1000 + j, part)] = (10 * j + part, "seed")
        for j in range(2):
            self.apply(("fins", f"o{owner}-s{j}", float(10 * owner + j), float(j), "seed"))

    def seed_ops(self) -> tuple[list[Item], list[Op]]:
        """The seed: rows of the plain table, and feature inserts."""
        items = [(o, p, v, n) for (o, p), (v, n) in sorted(self.items.items())]
        feats = [("fins", name, f.z[0], f.poro[0], f.label) for name, f in sorted(self.features.items())]
        return items, feats

    def content(self) -> OwnerContent:
        items = tuple(sorted((o, p, v, n) for (o, p), (v, n) in self.items.items()))
        feats = tuple(
            sorted(
                (
                    name,
                    f.label,
                    tuple(
                        (float(i), float(GRID.vertices[i, 0]), float(GRID.vertices[i, 1]), z) for i, z in enumerate(f.z)
                    ),
                    tuple(f.poro),
                    TRIANGLES,
                )
                for name, f in self.features.items()
            )
        )
        return items, feats

    def apply(self, op: Op) -> None:
        kind = op[0]
        if kind == "ins":
            self.items[(op[1], op[2])] = (op[3], op[4])
        elif kind == "upd":
            self.items[(op[1], op[2])] = (op[3], op[4])
        elif kind == "del":
            del self.items[(op[1], op[2])]
        elif kind == "rekey":
            self.items[(op[1], op[3])] = self.items.pop((op[1], op[2]))
        elif kind == "delobj":
            for key in [k for k in self.items if k[0] == op[1]]:
                del self.items[key]
        elif kind == "fins":
            self.features[op[1]] = _Feature(op[4], [op[2]] * 9, [op[3] + 0.25 * i for i in range(9)])
        elif kind == "fdel":
            del self.features[op[1]]
        elif kind == "fz":
            self.features[op[1]].z[op[2]] = op[3]
        elif kind == "fporo":
            self.features[op[1]].poro[op[2]] = op[3]
        elif kind == "flabel":
            self.features[op[1]].label = op[2]
        elif kind != "save":
            raise AssertionError(f"unknown op {op}")

    # -- generation: valid ops for the current state
    def _item_op(self, rng: random.Random) -> Op:
        mine = sorted(self.items)
        kind = rng.choices(["ins", "upd", "del", "rekey", "delobj"], [30, 35, 15, 12, 4])[0] if mine else "ins"
        if kind == "ins":
            objs = sorted({o for o, _ in mine})
            if objs and rng.random() < 0.6:
                obj = rng.choice(objs)
            else:
                obj, self.next_obj = self.next_obj, self.next_obj + 1
            free = [p for p in range(8) if (obj, p) not in self.items]
            if not free:
                obj, self.next_obj = self.next_obj, self.next_obj + 1
                free = list(range(8))
            val = rng.randrange(1_000_000)
            return ("ins", obj, rng.choice(free), val, f"n{val % 97}")
        obj, part = rng.choice(mine)
        if kind == "upd":
            val = rng.randrange(1_000_000)
            return ("upd", obj, part, val, rng.choice(["a", "b", f"u{val % 89}"]))
        if kind == "del":
            return ("del", obj, part)
        if kind == "rekey":
            free = [p for p in range(8) if (obj, p) not in self.items]
            return ("rekey", obj, part, rng.choice(free)) if free else ("del", obj, part)
        return ("delobj", obj, sum(1 for o, _ in mine if o == obj))

    def _feature_op(self, rng: random.Random) -> Op:
        names = sorted(self.features)
        kind = rng.choices(["fins", "fdel", "fz", "fporo", "flabel"], [25, 12, 30, 18, 15])[0] if names else "fins"
        if kind == "fins":
            name = f"o{self.owner}-f{self.next_feature}"
            self.next_feature += 1
            return ("fins", name, float(rng.randrange(-500, 500)), rng.randrange(0, 40) / 4, f"l{rng.randrange(9)}")
        name = rng.choice(names)
        if kind == "fdel":
            return ("fdel", name)
        if kind == "fz":
            return ("fz", name, rng.randrange(9), float(rng.randrange(-500, 500)))
        if kind == "fporo":
            return ("fporo", name, rng.randrange(9), rng.randrange(0, 400) / 4)
        return ("flabel", name, f"l{rng.randrange(100)}")

    def generate(self, rng: random.Random, count: int) -> tuple[list[Txn], list[OwnerContent]]:
        """``count`` transactions and the ``count + 1`` states they lead through (applied to this model)."""
        txns: list[Txn] = []
        states = [self.content()]
        for k in range(count):
            kind = rng.choices(["items", "feature", "mixed", "rollback", "save"], [45, 30, 10, 9, 6])[0]
            if kind == "save":
                txn = Txn((("save", f"o{self.owner}-s{k}"),))  # revision names are per version
            elif kind == "rollback":
                scratch = copy.deepcopy(self)  # ops valid in the current state; none of them sticks
                ops = [scratch._item_op(rng), scratch._feature_op(rng)]
                for op in ops:
                    scratch.apply(op)
                txn = Txn(tuple(ops), rollback=True)
                self.next_obj, self.next_feature = scratch.next_obj, scratch.next_feature
            else:
                ops = []
                for _ in range(rng.randint(1, 3) if kind == "items" else 1):
                    ops.append(self._item_op(rng))
                    self.apply(ops[-1])
                if kind in ("feature", "mixed"):
                    ops.append(self._feature_op(rng))
                    self.apply(ops[-1])
                if kind == "mixed":
                    ops.append(self._item_op(rng))
                    self.apply(ops[-1])
                txn = Txn(tuple(ops))
            txns.append(txn)
            states.append(self.content())
        return txns, states


# --------------------------------------------------------------------------- applying ops to a database


def _rows(cur: psycopg.Cursor[Any], expected: int, op: Op) -> None:
    if cur.rowcount != expected:
        raise AssertionError(f"{op}: {cur.rowcount} rows affected, expected {expected}")


def _geoid(conn: Conn, name: str) -> int:
    rows = conn.execute("SELECT geoid FROM tgsis.geometry WHERE geoname = %s", (name,)).fetchall()
    if len(rows) != 1:
        raise AssertionError(f"feature {name}: {len(rows)} geometry rows visible, expected 1")
    return int(rows[0][0])


def apply_op(conn: Conn, fc: F.FeatureClass, op: Op, versioned: bool) -> int | None:
    """Run one op; return the saved revision for ``save`` (None on a plain database)."""
    kind = op[0]
    if kind == "ins":
        conn.execute("INSERT INTO items (obj, part, val, note) VALUES (%s, %s, %s, %s)", op[1:])
    elif kind == "upd":
        _rows(
            conn.execute(
                "UPDATE items SET val = %s, note = %s WHERE obj = %s AND part = %s", (op[3], op[4], op[1], op[2])
            ),
            1,
            op,
        )
    elif kind == "del":
        _rows(conn.execute("DELETE FROM items WHERE obj = %s AND part = %s", op[1:]), 1, op)
    elif kind == "rekey":
        _rows(conn.execute("UPDATE items SET part = %s WHERE obj = %s AND part = %s", (op[3], op[1], op[2])), 1, op)
    elif kind == "delobj":
        _rows(conn.execute("DELETE FROM items WHERE obj = %s", (op[1],)), op[2], op)
    elif kind == "fins":  # the bulk COPY path
        F.insert_feature(conn, fc, surface(op[2], op[3], op[1]), {"label": op[4]})
    elif kind == "fdel":  # set-based delete (delete_object_rows)
        if not F.delete_feature(conn, fc, _geoid(conn, op[1])):
            raise AssertionError(f"{op}: nothing deleted")
    elif kind == "fz":  # plain SQL on a model-1 table: its trigger
        _rows(
            conn.execute(
                "UPDATE tgsis.vrtx SET z = %s WHERE geoid = %s AND vrtxid = %s", (op[3], _geoid(conn, op[1]), op[2])
            ),
            1,
            op,
        )
    elif kind == "fporo":
        _rows(
            conn.execute(
                "UPDATE horizons_cellpros SET porosity = %s WHERE _geoid = %s AND _idx = %s",
                (op[3], _geoid(conn, op[1]), op[2]),
            ),
            1,
            op,
        )
    elif kind == "flabel":
        _rows(conn.execute("UPDATE horizons SET label = %s WHERE _geoid = %s", (op[2], _geoid(conn, op[1]))), 1, op)
    elif kind == "save":
        if versioned:
            return int(conn.execute("SELECT tgsis.save_revision(%s)", (op[1],)).fetchone()[0])  # type: ignore[index]
    else:
        raise AssertionError(f"unknown op {op}")
    return None


def run_txn(conn: Conn, fc: F.FeatureClass, txn: Txn, versioned: bool, version: str | None = None) -> int | None:
    """One transaction (committed, or rolled back when the list says so) in the session's version, or with
    ``version`` set for it alone; returns a saved revision."""
    saved = None
    with conn.transaction():
        if version is not None:
            conn.execute("SELECT tgsis.goto_version(%s, true)", (version,))
        for op in txn.ops:
            saved = apply_op(conn, fc, op, versioned) or saved
        if txn.rollback:
            raise psycopg.Rollback()
    return saved


def setup_database(conn: Conn, models: Sequence[Model], versioned: bool) -> F.FeatureClass:
    """The seed of every owner; on the versioned database also the versioning and versions w0..w3."""
    conn.execute(ITEMS)
    for m in models:
        items, _ = m.seed_ops()
        with conn.cursor() as cur:
            cur.executemany("INSERT INTO items VALUES (%s, %s, %s, %s)", items)
    fc = F.create_feature_class(
        conn, "horizons", "SURFACE", feature_properties={"label": "text"}, cell_properties={"porosity": "float8"}
    )
    if versioned:  # rows present before (items) and uploaded after (features) versioning is on
        tgsis.enable_versioning(conn, "items", "obj", "item")
        tgsis.enable_feature_versioning(conn)
    for m in models:
        _, feats = m.seed_ops()
        for op in feats:
            apply_op(conn, fc, op, versioned)
    conn.commit()
    if versioned:
        for w in range(WRITERS):
            tgsis.create_version(conn, f"w{w}")
    return fc


# --------------------------------------------------------------------------- reading what a version holds

Content = dict[int, OwnerContent]

_FEATURES = """
SELECT g.geoname, h.label,
       (SELECT array_agg(ARRAY[v.vrtxid, v.x, v.y, v.z]::float8[] ORDER BY v.vrtxid) FROM tgsis.vrtx v WHERE v.geoid = g.geoid),
       (SELECT array_agg(c.porosity ORDER BY c._idx) FROM horizons_cellpros c WHERE c._geoid = g.geoid),
       (SELECT array_agg(ARRAY[t.trglid, t.vrtxid1, t.vrtxid2, t.vrtxid3] ORDER BY t.trglid)
          FROM tgsis.trgl t WHERE t.geoid = g.geoid)
  FROM horizons h JOIN tgsis.geometry g ON g.geoid = h._geoid"""

# rows that no feature owns (a delete or merge that left part of an object behind)
_ORPHANS = """
SELECT (SELECT count(*) FROM tgsis.geometry g WHERE NOT EXISTS (SELECT FROM horizons h WHERE h._geoid = g.geoid))
     + (SELECT count(*) FROM tgsis.vrtx v WHERE NOT EXISTS (SELECT FROM tgsis.geometry g WHERE g.geoid = v.geoid))
     + (SELECT count(*) FROM tgsis.trgl t WHERE NOT EXISTS (SELECT FROM tgsis.geometry g WHERE g.geoid = t.geoid))
     + (SELECT count(*) FROM horizons_cellpros c WHERE NOT EXISTS (SELECT FROM tgsis.geometry g WHERE g.geoid = c._geoid))"""


def _read_here(conn: Conn, where: str) -> Content:
    by_owner: dict[int, tuple[list[Item], list[Feat]]] = {o: ([], []) for o in OWNERS}
    for obj, part, val, note in conn.execute("SELECT obj, part, val, note FROM items"):
        by_owner.setdefault(owner_of_obj(obj), ([], []))[0].append((obj, part, val, note))
    for name, label, verts, poro, tris in conn.execute(_FEATURES):
        by_owner.setdefault(owner_of_name(name), ([], []))[1].append(
            (name, label, tuple(tuple(v) for v in verts or ()), tuple(poro or ()), tuple(tuple(t) for t in tris or ()))
        )
    orphans = conn.execute(_ORPHANS).fetchone()
    if orphans != (0,):
        raise AssertionError(f"{where}: {orphans} rows of features that no longer exist")
    return {o: (tuple(sorted(i)), tuple(sorted(f))) for o, (i, f) in by_owner.items()}


def read(conn: Conn, *places: str | tuple[str, int]) -> list[Content]:
    """What each place (a version, or (version, revision)) holds, all in one snapshot; ``conn`` must be idle."""
    out = []
    with conn.transaction():
        conn.execute("SET TRANSACTION ISOLATION LEVEL REPEATABLE READ READ ONLY")
        for place in places:
            if isinstance(place, tuple):
                conn.execute("SELECT tgsis.goto_revision(%s, %s, true)", place)
            else:
                conn.execute("SELECT tgsis.goto_version(%s, true)", (place,))
            out.append(_read_here(conn, str(place)))
    return out


def read_plain(conn: Conn) -> Content:
    with conn.transaction():
        return _read_here(conn, "replay")


def prefix(states: Sequence[OwnerContent], seen: OwnerContent, start: int) -> int | None:
    """The first k >= start at which the list's state is ``seen``, or None."""
    return next((k for k in range(start, len(states)) if states[k] == seen), None)


def describe(a: OwnerContent, b: OwnerContent) -> str:
    """Short difference of two owner contents (left, right), for failure messages."""
    ia, ib = Counter(a[0]), Counter(b[0])
    fa, fb = Counter(f[0] for f in a[1]), Counter(f[0] for f in b[1])
    differ = sorted({f[0] for f in a[1]} & {f[0] for f in b[1]} - {f[0] for f in set(a[1]) & set(b[1])})
    return (
        f"rows only left {sorted((ia - ib).elements())[:5]}, only right {sorted((ib - ia).elements())[:5]}; "
        f"features only left {sorted((fa - fb).elements())}, only right {sorted((fb - fa).elements())}, "
        f"different {differ}"
    )


# --------------------------------------------------------------------------- invariants of the version tables


def invariant_problems(conn: Conn) -> list[str]:
    """Everything wrong with revisions, working sets and stored rows (empty when all is well)."""
    problems = []
    q = conn.execute
    problems += [
        f"revision {r} owned {n} times"
        for r, n in q("SELECT revision, count(*) FROM tgsis.revisions GROUP BY 1 HAVING count(*) > 1")
    ]
    problems += [
        f"version {n}: working set {s} not strictly ascending"
        for n, s in q(
            "SELECT name, workingset FROM tgsis.versions "
            "WHERE workingset <> ARRAY(SELECT DISTINCT r FROM unnest(workingset) r ORDER BY r)"
        )
    ]
    problems += [
        f"version {n}: working revision {w} is not its own"
        for n, w in q(
            "SELECT v.name, v.workingrevision FROM tgsis.versions v LEFT JOIN tgsis.revisions r "
            "ON r.revision = v.workingrevision WHERE r.versionid IS DISTINCT FROM v.versionid"
        )
    ]
    # frozen = every revision but the working ones; frozen revisions keep the set they saw
    problems += [
        f"revision {r} of version {v}: frozen {frozen}, but visible set {s}"
        for r, v, frozen, s in q(
            "SELECT r.revision, r.versionid, r.revision <> v.workingrevision, r.visibleset FROM tgsis.revisions r "
            "JOIN tgsis.versions v USING (versionid) WHERE (r.revision <> v.workingrevision) <> (r.visibleset IS NOT NULL)"
        )
    ]
    # a version sees its parent's set at its base (frozen when the base was handed on) plus its own revisions
    problems += [
        f"version {n}: working set {s} is not the set of its base {i} ({b}) plus its own"
        for n, s, i, b in q(
            "SELECT v.name, v.workingset, v.initrevision, b.visibleset FROM tgsis.versions v "
            "LEFT JOIN tgsis.revisions b ON b.revision = v.initrevision AND b.versionid = v.parentid "
            "WHERE v.parentid IS NOT NULL AND ARRAY(SELECT r FROM unnest(v.workingset) r WHERE NOT EXISTS "
            "  (SELECT FROM tgsis.revisions o WHERE o.revision = r AND o.versionid = v.versionid) ORDER BY r) "
            "IS DISTINCT FROM b.visibleset"
        )
    ]
    problems += [
        f"DEFAULT's working set {s} is not all its revisions {a}"
        for s, a in q(
            "SELECT workingset, (SELECT array_agg(revision ORDER BY revision) FROM tgsis.revisions WHERE versionid = 0) "
            "FROM tgsis.versions WHERE versionid = 0 AND workingset <> "
            "(SELECT array_agg(revision ORDER BY revision) FROM tgsis.revisions WHERE versionid = 0)"
        )
    ]
    problems += [
        f"versions {n} share the base {i} in parent {p}"
        for p, i, n in q(
            "SELECT parentid, initrevision, array_agg(name) FROM tgsis.versions WHERE parentid IS NOT NULL "
            "GROUP BY 1, 2 HAVING count(*) > 1"
        )
    ]
    # each table's storage (<table>_ver, or a model table's chunk versions keyed by (geoid, chunk))
    tables = q(
        "SELECT tgsis.storage_table(t.schemaname, t.tablename), tgsis.storage_key(t) FROM tgsis.versioned_tables t"
    )
    for ver, keys in tables.fetchall():
        for what, n in q(
            f"SELECT 'unknown revision', count(*) FROM {ver} v "
            f" WHERE NOT EXISTS (SELECT FROM tgsis.revisions r WHERE r.revision = v.revision) UNION ALL "
            f"SELECT 'unknown revision in lastrevs', count(*) FROM {ver} v, unnest(v.lastrevs) l "
            f" WHERE NOT EXISTS (SELECT FROM tgsis.revisions r WHERE r.revision = l) UNION ALL "
            f"SELECT 'closed in a revision not after its own', count(*) FROM {ver} v, unnest(v.lastrevs) l "
            f" WHERE l <= v.revision UNION ALL "
            f"SELECT 'closed twice in one revision', count(*) FROM {ver} v "
            f" WHERE cardinality(v.lastrevs) <> (SELECT count(DISTINCT l) FROM unnest(v.lastrevs) l)"
        ):
            if n:
                problems.append(f"{ver}: {n} rows: {what}")
        # no key is visible twice in any version
        keylist = ", ".join(f'v."{k}"' for k in keys)
        for name, n in q(
            f"SELECT s.name, count(*) FROM tgsis.versions s, LATERAL (SELECT {keylist} FROM {ver} v "
            f" WHERE v.revision = ANY (s.workingset) AND NOT (v.lastrevs && s.workingset) "
            f" GROUP BY {keylist} HAVING count(*) > 1) d GROUP BY 1"
        ):
            problems.append(f"{ver}: {n} keys visible twice in version {name}")
    conn.rollback()
    return problems


# --------------------------------------------------------------------------- threads


def version_of(owner: int) -> str:
    return "DEFAULT" if owner in PARENTS else f"w{owner % (WRITERS + 1)}"


def who(owner: int) -> str:
    """An owner as failure messages name it: its writer and version."""
    return f"writer {owner} in {version_of(owner)}"


@dataclass
class Shared:
    """What the threads report."""

    barrier: threading.Barrier
    errors: list[str] = field(default_factory=list)
    pids: list[int] = field(default_factory=list)
    lock: threading.Lock = field(default_factory=threading.Lock)
    txn_seconds: dict[int, list[float]] = field(default_factory=dict)  # per owner, retries included
    retries: dict[int, Counter[str]] = field(default_factory=dict)  # per owner: 40001 retries by message
    saved: list[tuple[int, int, int, Content]] = field(default_factory=list)
    # owner, revision, state index, what the revision held right after the save committed
    stop: threading.Event = field(default_factory=threading.Event)
    overlap: threading.Event = field(default_factory=threading.Event)  # enough merges while writers run

    def fail(self, who: str, exc: BaseException) -> None:
        with self.lock:
            self.errors.append(f"{who}: {type(exc).__name__}: {exc}".strip())
        self.stop.set()
        self.overlap.set()
        self.barrier.abort()  # nobody waits for a session that has failed


MAX_RETRIES = 50  # of one transaction: more is a livelock, not contention


def run_writer(dsn: str, owner: int, txns: Sequence[Txn], shared: Shared) -> None:
    """Run one owner's list in its version: odd owners set the version per transaction (SET LOCAL, as
    behind a pooler in transaction mode), the others once for the session. A transaction failing with
    40001 (serialization_failure) is rolled back and run again from its start, as a client must."""
    k = 0
    version = version_of(owner)
    retries: Counter[str] = Counter()
    shared.retries[owner] = retries
    rng = random.Random(owner)
    try:
        with connect(dsn, f"{version}-{owner}") as conn:
            shared.pids.append(conn.info.backend_pid)
            fc = F.get_feature_class(conn, "horizons")
            conn.commit()
            per_txn = owner % 2 == 1
            if not per_txn:
                tgsis.goto_version(conn, version)
            times: list[float] = []
            shared.txn_seconds[owner] = times
            shared.barrier.wait()
            for k, txn in enumerate(txns):
                if shared.stop.is_set():
                    return
                if k == len(txns) // 2 and not shared.overlap.wait(DEADLINE):
                    raise AssertionError("the merging session never got going")  # half-way: merges must land
                t0 = time.perf_counter()
                for attempt in range(MAX_RETRIES + 1):
                    try:
                        saved = run_txn(conn, fc, txn, versioned=True, version=version if per_txn else None)
                        break
                    except psycopg.errors.SerializationFailure as exc:  # rolled back by run_txn's block
                        if attempt == MAX_RETRIES or shared.stop.is_set():
                            raise
                        retries[re.sub(r"[0-9]+", "N", exc.diag.message_primary or str(exc))] += 1
                        time.sleep(rng.uniform(0, 0.004))
                times.append(time.perf_counter() - t0)
                if saved is not None:
                    # frozen now: the other writer of the version writes in the next working revision
                    [held] = read(conn, (version, saved))
                    shared.saved.append((owner, saved, k + 1, held))
                time.sleep(0.002)  # let the other sessions in between transactions
    except BaseException as exc:  # noqa: BLE001 - every failure is reported by the test
        shared.fail(f"{who(owner)}, transaction {k} {txns[k] if k < len(txns) else ''}", exc)


@dataclass
class Admin:
    """The merging session: merges, refreshes and creates versions, checking after each step what it sees.

    DEFAULT changes only through this session's merges and the rows of the
    PARENTS (written by their own sessions meanwhile); a writer's version
    changes only in the rows of its writers (owners_in) and through this
    session's merges and refreshes. So after each step the rows of every
    owner are either known exactly or must be a state of that owner's list
    within known bounds.
    """

    dsn: str
    states: dict[int, list[OwnerContent]]
    shared: Shared
    writers: list[threading.Thread]
    rng: random.Random
    default: Content = field(default_factory=dict)  # what DEFAULT held after the last step
    seen: dict[tuple[str, int], int] = field(default_factory=dict)  # (place, owner): lowest state index possible
    # version merged, the state index merged of each of its writers, writers running
    merged: list[tuple[int, tuple[int, ...], int]] = field(default_factory=list)
    created: dict[str, tuple[str, int, Content]] = field(default_factory=dict)  # name: parent, revision, content
    merge_seconds: list[float] = field(default_factory=list)
    refresh_seconds: list[float] = field(default_factory=list)
    create_seconds: list[float] = field(default_factory=list)

    def run(self) -> None:
        action = "start"
        try:
            with connect(self.dsn, "admin") as conn:
                self.shared.pids.append(conn.info.backend_pid)
                [self.default] = read(conn, "DEFAULT")
                self.shared.barrier.wait()
                while any(t.is_alive() for t in self.writers) and not self.shared.stop.is_set():
                    action = self.rng.choices(
                        [
                            "merge",
                            "refresh",
                            "create_under_writer",
                            "create_under_default",
                            "merge_child",
                            "refresh_child",
                        ],
                        [45, 20, 10, 8, 6, 5],
                    )[0]
                    getattr(self, action)(conn)
        except BaseException as exc:  # noqa: BLE001 - every failure is reported by the test
            self.shared.fail(f"admin, {action}", exc)

    def state(
        self, where: str, place: str, owner: int, held: OwnerContent, *, upto: str | None = None, advance: bool = True
    ) -> int:
        """Index of ``held`` in ``owner``'s list, at or after the last one seen at ``place`` (and not after
        the last one seen at ``upto``); it becomes the last one seen at ``place``."""
        start = self.seen.get((place, owner), 0)
        stop = self.seen.get((upto, owner), len(self.states[owner]) - 1) if upto else len(self.states[owner]) - 1
        k = prefix(self.states[owner], held, start)
        if k is None or k > stop:
            raise AssertionError(
                f"{where}: the rows of {who(owner)} are no state of its list in "
                f"[{start}, {stop}] (found at {k}, from 0 at {prefix(self.states[owner], held, 0)}); "
                f"against state {start}: " + describe(self.states[owner][start], held)
            )
        if advance:
            self.seen[(place, owner)] = k
        return k

    def same(self, where: str, a: Content, b: Content, owners: Sequence[int]) -> None:
        for o in owners:
            if a[o] != b[o]:
                raise AssertionError(f"{where}: rows of {who(o)} differ: {describe(a[o], b[o])}")

    def _default(self, where: str, default: Content, changed: int | None) -> None:
        """DEFAULT as read now: the PARENTS' rows moved on in their lists, the merged version's writers' too,
        all else unchanged."""
        moving = {*PARENTS, *(owners_in(changed) if changed is not None else ())}
        for o in sorted(moving):
            self.state(where, "DEFAULT", o, default[o])
        self.same(where, self.default, default, [o for o in OWNERS if o not in moving])
        self.default = default

    def _parents_from(self, where: str, place: str, held: Content, before: dict[int, int]) -> None:
        """The PARENTS' rows at ``place`` are what DEFAULT held at some moment since ``before``: between what
        DEFAULT was seen to hold then and what it was seen to hold last."""
        for p in PARENTS:
            self.seen[(place, p)] = before[p]
            self.state(where, place, p, held[p], upto="DEFAULT")

    def _parents_seen(self) -> dict[int, int]:
        return {p: self.seen.get(("DEFAULT", p), 0) for p in PARENTS}

    def merge(self, conn: Conn) -> None:
        w = self.rng.randrange(WRITERS)
        mine = owners_in(w)
        running = sum(t.is_alive() for t in self.writers)
        t0 = time.perf_counter()
        before = self._parents_seen()
        tgsis.merge_version(conn, f"w{w}")
        self.merge_seconds.append(time.perf_counter() - t0)
        default, version = read(conn, "DEFAULT", f"w{w}")
        self._default(f"DEFAULT after merging w{w}", default, w)
        self.merged.append((w, tuple(self.seen[("DEFAULT", o)] for o in mine), running))
        if sum(1 for _, _, r in self.merged if r) >= MIN_MERGES:
            self.shared.overlap.set()
        # w goes on from the merged state: others' rows as DEFAULT had them at the merge, its own moving on
        where = f"w{w} after its merge"
        self.same(where, default, version, [o for o in OWNERS if o not in mine and o not in PARENTS])
        self._parents_from(where, f"w{w}", version, before)
        for o in mine:
            self.seen[(f"w{w}", o)] = self.seen[("DEFAULT", o)]
            self.state(where, f"w{w}", o, version[o])

    def refresh(self, conn: Conn) -> None:
        w = self.rng.randrange(WRITERS)
        before = self._parents_seen()
        t0 = time.perf_counter()
        tgsis.refresh_version(conn, f"w{w}")
        self.refresh_seconds.append(time.perf_counter() - t0)
        default, version = read(conn, "DEFAULT", f"w{w}")
        where = f"w{w} after its refresh"
        self._default(f"DEFAULT after refreshing w{w}", default, None)
        self.same(where, default, version, [o for o in OWNERS if o not in owners_in(w) and o not in PARENTS])
        self._parents_from(where, f"w{w}", version, before)
        for o in owners_in(w):
            self.state(where, f"w{w}", o, version[o])

    def _create(self, conn: Conn, parent: str) -> tuple[str, Content, Content] | None:
        if len(self.created) >= MAX_NEW_VERSIONS:
            self.merge(conn)
            return None
        name = f"{'d' if parent == 'DEFAULT' else 's'}{len(self.created)}"
        t0 = time.perf_counter()
        revision = tgsis.create_version(conn, name, parent)
        self.create_seconds.append(time.perf_counter() - t0)
        new, held = read(conn, name, parent)
        self.created[name] = (parent, revision, new)
        return name, new, held

    def create_under_writer(self, conn: Conn) -> None:
        w = self.rng.randrange(WRITERS)
        made = self._create(conn, f"w{w}")
        if made is not None:
            name, new, parent = made
            self._child_of_writer(name, w, new, parent)

    def _child_of_writer(self, name: str, w: int, new: Content, parent: Content) -> None:
        """A child of w as read with w: others' rows as in w (only this session changes them), the rows of
        w's writers a state of their lists between what was seen before and what w holds now."""
        where = f"version {name}, child of w{w}"
        self.same(where, parent, new, [o for o in OWNERS if o not in owners_in(w)])
        for o in owners_in(w):
            start = self.seen.get((f"w{w}", o), 0)
            self.state(f"w{w} read with its child {name}", f"w{w}", o, parent[o])
            self.seen[(name, o)] = start
            self.state(where, name, o, new[o], upto=f"w{w}")

    def create_under_default(self, conn: Conn) -> None:
        before = self._parents_seen()
        made = self._create(conn, "DEFAULT")
        if made is not None:
            name, new, default = made
            where = f"version {name}, child of DEFAULT"
            self._default("DEFAULT read with its new child", default, None)
            self.same(where, default, new, [o for o in OWNERS if o not in PARENTS])
            self._parents_from(where, name, new, before)

    def _child(self) -> tuple[str, int] | None:
        children = [(n, int(p[1:])) for n, (p, _, _) in self.created.items() if p != "DEFAULT"]
        return self.rng.choice(children) if children else None

    def merge_child(self, conn: Conn) -> None:
        """Merge a new (unchanged) child into a writer's version: locks the version a writer writes in."""
        child = self._child()
        if child is None:
            return self.create_under_writer(conn)
        name, w = child
        t0 = time.perf_counter()
        written = tgsis.merge_version(conn, name)
        self.merge_seconds.append(time.perf_counter() - t0)
        if written:
            raise AssertionError(f"merging the unchanged version {name} wrote {written} rows")
        self._rebased(conn, name, w)

    def refresh_child(self, conn: Conn) -> None:
        child = self._child()
        if child is None:
            return self.create_under_writer(conn)
        name, w = child
        t0 = time.perf_counter()
        tgsis.refresh_version(conn, name)
        self.refresh_seconds.append(time.perf_counter() - t0)
        self._rebased(conn, name, w)

    def _rebased(self, conn: Conn, name: str, w: int) -> None:
        new, parent = read(conn, name, f"w{w}")
        self.created[name] = (f"w{w}", self.created[name][1], new)
        self._child_of_writer(name, w, new, parent)


def _join(threads: Sequence[threading.Thread], deadline: float, shared: Shared, dsn: str) -> None:
    """Join the threads; past the deadline cancel their statements and fail (the test-level timeout)."""
    for t in threads:
        t.join(max(0.0, deadline - time.monotonic()))
    if any(t.is_alive() for t in threads):
        shared.stop.set()
        with connect(dsn, "watchdog", autocommit=True) as c:
            stuck = c.execute(
                "SELECT pid, application_name, wait_event_type, wait_event, pg_blocking_pids(pid), query "
                "FROM pg_stat_activity WHERE pid = ANY (%s)",
                (shared.pids,),
            ).fetchall()
            for pid in shared.pids:
                c.execute("SELECT pg_cancel_backend(%s)", (pid,))
        for t in threads:
            t.join(10)
        pytest.fail(f"the sessions did not finish within the test's deadline; they were at: {stuck}")


# --------------------------------------------------------------------------- the main test


def test_two_writers_in_each_of_four_versions_and_default_with_a_merger_end_as_a_sequential_replay(
    db_dsn: str, make_database: Callable[..., str], template_db: str
) -> None:
    rng = random.Random(SEED)
    lists: dict[int, list[Txn]] = {}
    states: dict[int, list[OwnerContent]] = {}
    for o in OWNERS:
        lists[o], states[o] = Model(o).generate(
            random.Random(rng.randrange(2**32)), PARENT_TXNS if o in PARENTS else WRITER_TXNS
        )

    # the oracle: the same lists, one after the other, on a plain database
    replay_started = time.monotonic()
    replay_dsn = make_database(template_db)
    with connect(replay_dsn, "replay") as replay:
        fc = setup_database(replay, [Model(o) for o in OWNERS], versioned=False)
        for o in OWNERS:
            for txn in lists[o]:
                run_txn(replay, fc, txn, versioned=False)
        expected = read_plain(replay)
        replay_meshes = {f.name: f for f in F.fetch_features(replay, "horizons")}
    for o in OWNERS:  # the model agrees with PostgreSQL on every list
        assert expected[o] == states[o][-1], f"model and replay differ for owner {o}: " + describe(
            states[o][-1], expected[o]
        )

    with connect(db_dsn, "setup") as conn:
        setup_database(conn, [Model(o) for o in OWNERS], versioned=True)

    shared = Shared(threading.Barrier(len(OWNERS) + 1))
    writers = [
        threading.Thread(target=run_writer, args=(db_dsn, o, lists[o], shared), name=version_of(o), daemon=True)
        for o in OWNERS
    ]
    admin = Admin(db_dsn, states, shared, writers, random.Random(rng.randrange(2**32)))
    admin_thread = threading.Thread(target=admin.run, name="admin", daemon=True)
    started = time.monotonic()
    for t in [*writers, admin_thread]:
        t.start()
    _join([*writers, admin_thread], started + DEADLINE, shared, db_dsn)
    elapsed = time.monotonic() - started
    assert not shared.errors, f"seed {SEED}: errors in the concurrent phase:\n" + "\n".join(shared.errors)

    # the run was concurrent: merges landed while writers were half-way through their lists
    during = [(w, k) for w, k, running in admin.merged if running]
    halfway = [(w, ks) for w, ks in during if any(0 < k < WRITER_TXNS for k in ks)]
    assert len(during) >= MIN_MERGES and halfway, f"seed {SEED}: too little overlap: merges {admin.merged}"

    check_started = time.monotonic()
    with connect(db_dsn, "check") as conn:
        # each version holds exactly what the lists of its writers lead to, as on the plain database
        places = [*(f"w{w}" for w in range(WRITERS)), "DEFAULT"]
        contents = dict(zip(places, read(conn, *places)))
        for o in OWNERS:
            shown = contents[version_of(o)][o]
            assert shown == expected[o], f"{who(o)}: " + describe(expected[o], shown)

        # frozen revisions never change: a saved one shows the state it was saved at, all of it (the other
        # writer's rows of the version too) as it showed right after the save committed, and every frozen
        # revision of a writer's version or DEFAULT (saves, merges, refreshes and new children froze them)
        # shows whole transactions of each list, never going backwards
        for owner, revision, k, then in shared.saved:
            [held] = read(conn, (version_of(owner), revision))
            assert held[owner] == states[owner][k], (
                f"saved revision {revision} of {version_of(owner)} "
                f"(state {k}): " + describe(states[owner][k], held[owner])
            )
            changed = [o for o in OWNERS if held[o] != then[o]]
            assert not changed, (
                f"saved revision {revision} of {version_of(owner)} changed after its save: "
                + "; ".join(f"rows of {who(o)}: {describe(then[o], held[o])}" for o in changed)
            )
        frozen = conn.execute(
            "SELECT v.name, v.versionid, r.revision FROM tgsis.revisions r JOIN tgsis.versions v "
            "USING (versionid) WHERE r.visibleset IS NOT NULL AND v.name ~ '^(DEFAULT|w[0-9])$' "
            "ORDER BY 2, 3"
        ).fetchall()
        conn.rollback()
        last: dict[tuple[str, int], int] = {}
        for name, _, revision in frozen:
            [held] = read(conn, (name, revision))
            for o in OWNERS if name == "DEFAULT" else [*owners_in(int(name[1:])), *PARENTS]:
                at = prefix(states[o], held[o], last.get((name, o), 0))
                assert at is not None, (
                    f"revision {revision} of {name}: rows of {who(o)} are no state of "
                    f"its list at or after state {last.get((name, o), 0)}"
                )
                last[(name, o)] = at

        # a last merge of every writer, then a refresh of each: DEFAULT and all four equal the replay
        for w in range(WRITERS):
            tgsis.merge_version(conn, f"w{w}")
        for w in range(WRITERS):
            tgsis.refresh_version(conn, f"w{w}")
        for place, content in zip(places, read(conn, *places)):
            for o in OWNERS:
                assert content[o] == expected[o], f"{place}, rows of {who(o)}: " + describe(expected[o], content[o])

        # versions made during the run still hold what they held when made (or last merged or refreshed)
        for name, (parent, _, held) in admin.created.items():
            [now] = read(conn, name)
            assert now == held, f"version {name} (child of {parent}) changed: " + "; ".join(
                f"rows of {who(o)}: {describe(held[o], now[o])}" for o in OWNERS if held[o] != now[o]
            )

        # the client's download path gives the replay's meshes
        meshes = {f.name: f for f in F.fetch_features(conn, "horizons")}
        assert meshes.keys() == replay_meshes.keys()
        for name, feature in meshes.items():
            other = replay_meshes[name]
            assert isinstance(feature.mesh, tgsis.Surface) and isinstance(other.mesh, tgsis.Surface), name
            assert feature.mesh.same_as(other.mesh), name
            assert feature.properties == other.properties, name

        # no two versions created concurrently share a revision; the tables of the versions are consistent
        revisions = [revision for _, revision, _ in admin.created.values()]
        assert len(set(revisions)) == len(revisions)
        owners = dict(
            conn.execute(
                "SELECT r.revision, v.name FROM tgsis.revisions r JOIN tgsis.versions v "
                "USING (versionid) WHERE r.revision = ANY (%s)",
                (revisions,),
            ).fetchall()
        )
        assert owners == {revision: name for name, (_, revision, _) in admin.created.items()}
        conn.rollback()
        assert invariant_problems(conn) == []

    times = [t for ts in shared.txn_seconds.values() for t in ts]
    retries = sum((shared.retries[o] for o in OWNERS), Counter[str]())
    per_version = Counter[str]()
    for o in OWNERS:
        per_version[version_of(o)] += shared.retries[o].total()
    print(
        f"\nseed {SEED}: replay and set-up {started - replay_started:.1f} s, checks {time.monotonic() - check_started:.1f}"
        f" s; {retries.total()} retries after 40001 ({dict(sorted(per_version.items()))}: {dict(retries)})"
    )
    print(
        f"seed {SEED}: {elapsed:.1f} s concurrent; {len(times)} writer transactions, median "
        f"{statistics.median(times) * 1000:.1f} ms, max {max(times) * 1000:.0f} ms, {sum(t > 0.1 for t in times)} "
        f"over 100 ms; {len(admin.merge_seconds)} merges (median {statistics.median(admin.merge_seconds) * 1000:.0f}"
        f" ms, max {max(admin.merge_seconds) * 1000:.0f} ms, {len(during)} while writers ran, {len(halfway)} of a "
        f"half-done list); {len(admin.refresh_seconds)} refreshes; {len(admin.created)} versions created; "
        f"{len(shared.saved)} revisions saved"
    )


# --------------------------------------------------------------------------- focused tests of the lock waits


@pytest.fixture
def small(conn: Conn) -> Conn:
    """items with rows 1.0-1.2 and 2.0, a surface 'A'; version w, in whose working revision w changed row 1.0,
    inserted row 1.3 and surface 'B', and moved vertex 0 of A."""
    conn.execute(ITEMS)
    conn.execute("INSERT INTO items VALUES (1, 0, 10, 'x'), (1, 1, 11, 'x'), (1, 2, 12, 'x'), (2, 0, 20, 'x')")
    fc = F.create_feature_class(
        conn, "horizons", "SURFACE", feature_properties={"label": "text"}, cell_properties={"porosity": "float8"}
    )
    tgsis.enable_versioning(conn, "items", "obj", "item")
    tgsis.enable_feature_versioning(conn)
    F.insert_feature(conn, fc, surface(1.0, 0.0, "A"), {"label": "a"})
    tgsis.create_version(conn, "w")
    with tgsis.in_version(conn, "w"):
        conn.execute("UPDATE items SET val = 100 WHERE obj = 1 AND part = 0")
        conn.execute("INSERT INTO items VALUES (1, 3, 13, 'w')")
        F.insert_feature(conn, fc, surface(2.0, 0.0, "B"), {"label": "b"})
        conn.execute("UPDATE tgsis.vrtx SET z = 5 WHERE geoid = %s AND vrtxid = 0", (_geoid(conn, "A"),))
        conn.commit()
    return conn


def _items(conn: Conn, version: str) -> list[tuple[Any, ...]]:
    with tgsis.in_version(conn, version, local=True):
        return conn.execute("SELECT obj, part, val FROM items ORDER BY 1, 2").fetchall()


def _surfaces(conn: Conn, version: str) -> dict[str, list[float]]:
    with tgsis.in_version(conn, version, local=True):
        return {
            f.name: [float(z) for z in f.mesh.vertices[:, 2]]
            for f in F.fetch_features(conn, "horizons")
            if f.name is not None and isinstance(f.mesh, tgsis.Surface)
        }


@pytest.mark.parametrize("action", ["merge", "refresh"])
def test_merge_or_refresh_waits_for_an_open_writer_and_then_takes_its_whole_transaction(
    small: Conn, db_dsn: str, action: str
) -> None:
    writer = connect(db_dsn, "writer")
    tgsis.goto_version(writer, "w")
    writer.execute("UPDATE items SET val = 101 WHERE obj = 1 AND part = 1")  # holds w until it commits
    call = tgsis.merge_version if action == "merge" else tgsis.refresh_version
    background = Background(db_dsn, action, lambda c: call(c, "w"))
    wait_until_blocked(small, background.pid, writer.info.backend_pid)
    writer.execute("DELETE FROM items WHERE obj = 1 AND part = 2")  # still before the merge
    F.insert_feature(writer, "horizons", surface(3.0, 0.0, "C"))
    writer.commit()
    writer.close()
    background.finish()
    in_w = [(1, 0, 100), (1, 1, 101), (1, 3, 13), (2, 0, 20)]
    assert _items(small, "w") == in_w
    assert sorted(_surfaces(small, "w")) == ["A", "B", "C"]
    if action == "merge":  # the merge took all of the transaction it waited for
        assert _items(small, "DEFAULT") == in_w and sorted(_surfaces(small, "DEFAULT")) == ["A", "B", "C"]
    else:
        assert _items(small, "DEFAULT") == [(1, 0, 10), (1, 1, 11), (1, 2, 12), (2, 0, 20)]
    assert invariant_problems(small) == []


@pytest.mark.parametrize("action", ["merge", "refresh"])
def test_writers_wait_for_a_merge_or_refresh_and_write_into_the_new_working_revision(
    small: Conn, db_dsn: str, action: str
) -> None:
    """Each writer's statement is planned before the merge commits and runs after: its rows must go to the
    version's new working revision (not in place into the one the merge froze), by each write path."""
    holder = connect(db_dsn, "holder")
    revision_before = int(holder.execute("SELECT workingrevision FROM tgsis.versions WHERE name = 'w'").fetchone()[0])  # type: ignore[index]
    holder.rollback()
    again = tgsis.merge_version if action == "merge" else tgsis.refresh_version
    holder.execute(f"SELECT tgsis.{action}_version('w')")  # not committed yet: holds DEFAULT and w
    a = _geoid(small, "A")
    with tgsis.in_version(small, "w", local=True):
        b = _geoid(small, "B")
    writes: dict[str, Callable[[Conn], Any]] = {
        "update in place": lambda c: c.execute("UPDATE items SET val = 102 WHERE obj = 1 AND part = 0").rowcount,
        "delete in place": lambda c: c.execute("DELETE FROM items WHERE obj = 1 AND part = 3").rowcount,
        "update a parent row": lambda c: c.execute("UPDATE items SET val = 21 WHERE obj = 2 AND part = 0").rowcount,
        "insert": lambda c: c.execute("INSERT INTO items VALUES (3, 0, 30, 'w')").rowcount,
        "key change": lambda c: c.execute("UPDATE items SET part = 5 WHERE obj = 1 AND part = 1").rowcount,
        "vertex in place": lambda c: (
            c.execute("UPDATE tgsis.vrtx SET z = 6 WHERE geoid = %s AND vrtxid = 0", (a,)).rowcount
        ),
        "delete_feature": lambda c: int(F.delete_feature(c, "horizons", b)),
        "insert_feature (COPY)": lambda c: int(F.insert_feature(c, "horizons", surface(4.0, 0.0, "D")) > 0),
    }
    backgrounds = {what: Background(db_dsn, what, call, version="w") for what, call in writes.items()}
    for bg in backgrounds.values():
        wait_until_blocked(small, bg.pid, holder.info.backend_pid)
    holder.commit()
    holder.close()
    assert {what: bg.finish() for what, bg in backgrounds.items()} == dict.fromkeys(writes, 1)

    assert _items(small, "w") == [(1, 0, 102), (1, 2, 12), (1, 5, 11), (2, 0, 21), (3, 0, 30)]
    assert _surfaces(small, "w") == {"A": [6.0] + [1.0] * 8, "D": [4.0] * 9}
    if action == "merge":  # DEFAULT has w as it was when the merge ran, nothing of the writes after it
        assert _items(small, "DEFAULT") == [(1, 0, 100), (1, 1, 11), (1, 2, 12), (1, 3, 13), (2, 0, 20)]
        assert _surfaces(small, "DEFAULT") == {"A": [5.0] + [1.0] * 8, "B": [2.0] * 9}
    else:
        assert _items(small, "DEFAULT") == [(1, 0, 10), (1, 1, 11), (1, 2, 12), (2, 0, 20)]
    # the revision w worked in before is frozen and still shows what w held then
    with tgsis.at_revision(small, revision_before, "w", local=True):
        assert small.execute("SELECT obj, part, val FROM items ORDER BY 1, 2").fetchall() == [
            (1, 0, 100),
            (1, 1, 11),
            (1, 2, 12),
            (1, 3, 13),
            (2, 0, 20),
        ]
    again(small, "w")  # the next merge or refresh is an ordinary one
    tgsis.merge_version(small, "w")
    assert _items(small, "DEFAULT") == _items(small, "w")
    assert _surfaces(small, "DEFAULT") == _surfaces(small, "w")
    assert invariant_problems(small) == []


def test_a_second_merge_of_the_same_version_waits_and_then_finds_nothing_to_merge(small: Conn, db_dsn: str) -> None:
    first = connect(db_dsn, "first")
    written = first.execute("SELECT tgsis.merge_version('w')").fetchone()  # open: holds DEFAULT and w
    assert written is not None and written[0] > 0
    second = Background(db_dsn, "second", lambda c: tgsis.merge_version(c, "w"))
    wait_until_blocked(small, second.pid, first.info.backend_pid)
    first.commit()
    first.close()
    assert second.finish() == 0  # it waited, then found everything merged already
    # the revision DEFAULT worked in during the second merge holds no row: nothing was copied or closed twice
    second_target = small.execute(
        "SELECT workingset[cardinality(workingset) - 1] FROM tgsis.versions WHERE versionid = 0"
    ).fetchone()
    assert second_target is not None
    vertices = small.execute("SELECT tgsis.storage_table('tgsis', 'vrtx')").fetchone()
    assert vertices is not None
    for table in ("items_ver", str(vertices[0]), "tgsis.geometry_ver", "horizons_ver"):
        assert small.execute(
            f"SELECT count(*) FROM {table} WHERE revision = %s OR %s = ANY (lastrevs)",
            (second_target[0], second_target[0]),
        ).fetchone() == (0,), table
    small.rollback()
    assert (
        _items(small, "DEFAULT") == _items(small, "w") == [(1, 0, 100), (1, 1, 11), (1, 2, 12), (1, 3, 13), (2, 0, 20)]
    )
    assert _surfaces(small, "DEFAULT") == _surfaces(small, "w") == {"A": [5.0] + [1.0] * 8, "B": [2.0] * 9}
    assert invariant_problems(small) == []


@pytest.mark.parametrize("recreated", [False, True], ids=["removed", "removed and re-created"])
def test_a_merge_waiting_for_a_merge_that_removes_the_version_fails_clearly(
    small: Conn, db_dsn: str, recreated: bool
) -> None:
    first = connect(db_dsn, "first")
    first.execute("SELECT tgsis.merge_version('w', true)")
    if recreated:  # a new version of the same name is not the one asked for
        first.execute("SELECT tgsis.create_version('w')")
    second = Background(db_dsn, "second", lambda c: tgsis.merge_version(c, "w"))
    wait_until_blocked(small, second.pid, first.info.backend_pid)
    first.commit()
    first.close()
    with pytest.raises(tgsis.NotFoundError, match="version 'w' does not exist"):
        second.finish()
    merged = [(1, 0, 100), (1, 1, 11), (1, 2, 12), (1, 3, 13), (2, 0, 20)]
    assert _items(small, "DEFAULT") == merged
    if recreated:
        assert _items(small, "w") == merged
    assert invariant_problems(small) == []


def test_a_create_version_waits_for_another_on_the_same_parent_and_bases_on_its_new_revision(
    conn: Conn, db_dsn: str
) -> None:
    tgsis.create_version(conn, "w")
    first = connect(db_dsn, "first")
    first_revision = first.execute("SELECT tgsis.create_version('x', 'w')").fetchone()[0]  # type: ignore[index]
    second = Background(db_dsn, "second", lambda c: tgsis.create_version(c, "y", "w"))
    wait_until_blocked(conn, second.pid, first.info.backend_pid)
    first.commit()
    first.close()
    second_revision = second.finish()
    versions = {
        name: (init, working)
        for name, init, working in conn.execute(
            "SELECT name, initrevision, workingrevision FROM tgsis.versions WHERE name IN ('w', 'x', 'y')"
        )
    }
    # x is based on w's working revision before, y on the one x's creation handed w
    w_revisions = [
        r
        for (r,) in conn.execute(
            "SELECT revision FROM tgsis.revisions WHERE versionid = tgsis.version_id('w') ORDER BY 1"
        )
    ]
    assert versions["x"] == (w_revisions[0], first_revision) and versions["y"] == (w_revisions[1], second_revision)
    assert versions["w"][1] == w_revisions[2] and len(w_revisions) == 3
    conn.rollback()
    assert invariant_problems(conn) == []


def test_many_create_version_calls_at_once_never_share_a_revision_or_a_base(db_dsn: str, conn: Conn) -> None:
    tgsis.create_version(conn, "w")
    parents = ["DEFAULT", "w"] * 5
    barrier = threading.Barrier(len(parents))
    got: dict[str, int] = {}
    errors: list[BaseException] = []

    def create(i: int, parent: str) -> None:
        try:
            with connect(db_dsn, f"create{i}") as c:
                barrier.wait()
                got[f"c{i}"] = tgsis.create_version(c, f"c{i}", parent)
        except BaseException as exc:  # noqa: BLE001 - reported below
            errors.append(exc)

    threads = [threading.Thread(target=create, args=(i, p), daemon=True) for i, p in enumerate(parents)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(60)
    assert not errors and len(got) == len(parents)
    assert len(set(got.values())) == len(parents)
    assert invariant_problems(conn) == []  # includes: no two children share a base revision


def test_the_same_new_name_under_two_parents_at_once_fails_clearly(conn: Conn, db_dsn: str) -> None:
    tgsis.create_version(conn, "w")
    first = connect(db_dsn, "first")
    first.execute("SELECT tgsis.create_version('x', 'DEFAULT')")
    second = Background(db_dsn, "second", lambda c: tgsis.create_version(c, "x", "w"))
    wait_until_blocked(conn, second.pid, first.info.backend_pid)
    first.commit()
    first.close()
    with pytest.raises(tgsis.AlreadyExistsError, match="version 'x' exists already"):
        second.finish()
    assert conn.execute("SELECT count(*) FROM tgsis.versions WHERE name = 'x'").fetchone() == (1,)
    conn.rollback()
    assert invariant_problems(conn) == []


def test_a_create_version_under_a_version_deleted_meanwhile_fails_clearly(conn: Conn, db_dsn: str) -> None:
    tgsis.create_version(conn, "w")
    first = connect(db_dsn, "first")
    first.execute("SELECT tgsis.delete_version('w')")
    second = Background(db_dsn, "second", lambda c: tgsis.create_version(c, "x", "w"))
    wait_until_blocked(conn, second.pid, first.info.backend_pid)
    first.commit()
    first.close()
    with pytest.raises(tgsis.NotFoundError, match="version 'w' does not exist"):
        second.finish()
    assert [name for (name,) in conn.execute("SELECT name FROM tgsis.versions")] == ["DEFAULT"]
    conn.rollback()
    assert invariant_problems(conn) == []


def test_a_second_delete_of_the_same_version_waits_and_fails_clearly(conn: Conn, db_dsn: str) -> None:
    tgsis.create_version(conn, "w")
    first = connect(db_dsn, "first")
    first.execute("SELECT tgsis.delete_version('w')")
    second = Background(db_dsn, "second", lambda c: tgsis.delete_version(c, "w"))
    wait_until_blocked(conn, second.pid, first.info.backend_pid)
    first.commit()
    first.close()
    with pytest.raises(tgsis.NotFoundError, match="version 'w' does not exist"):
        second.finish()


def test_sibling_writers_on_one_inherited_row_wait_for_each_other_and_keep_their_own_changes(
    small: Conn, db_dsn: str
) -> None:
    tgsis.create_version(small, "b")  # a sibling of w; both see DEFAULT's row 2.0
    first = connect(db_dsn, "first")
    tgsis.goto_version(first, "w")
    first.execute("UPDATE items SET val = 22 WHERE obj = 2 AND part = 0")  # closes DEFAULT's row for w
    second = Background(
        db_dsn,
        "second",
        lambda c: c.execute("UPDATE items SET val = 23 WHERE obj = 2 AND part = 0").rowcount,
        version="b",
    )
    wait_until_blocked(small, second.pid, first.info.backend_pid)  # the same stored row
    first.commit()
    first.close()
    assert second.finish() == 1
    assert [r for r in _items(small, "w") if r[0] == 2] == [(2, 0, 22)]
    assert [r for r in _items(small, "b") if r[0] == 2] == [(2, 0, 23)]
    assert [r for r in _items(small, "DEFAULT") if r[0] == 2] == [(2, 0, 20)]
    assert invariant_problems(small) == []


@pytest.mark.parametrize("action", ["merge", "delete"])
def test_a_merge_or_delete_and_a_writer_in_a_sibling_changing_the_same_rows_in_the_other_order_do_not_deadlock(
    small: Conn, db_dsn: str, action: str
) -> None:
    """w changed rows 1.0 and 1.2: merging w closes DEFAULT's stored rows 1.0 and 1.2, deleting w takes its
    revision out of their lastrevs -- rows the sibling b sees too. A writer in b changes 1.2, then 1.0: the
    merge or delete must wait for it holding no row, not hold 1.0 while waiting for 1.2 (before
    tgsis.update_shared_rows this was a deadlock, and the merge or delete failed)."""
    with tgsis.in_version(small, "w"):
        small.execute("UPDATE items SET val = 112 WHERE obj = 1 AND part = 2")
        small.commit()
    tgsis.create_version(small, "b")
    writer = connect(db_dsn, "writer")
    tgsis.goto_version(writer, "b")
    writer.execute("UPDATE items SET val = 32 WHERE obj = 1 AND part = 2")
    call = (lambda c: tgsis.merge_version(c, "w")) if action == "merge" else (lambda c: tgsis.delete_version(c, "w"))
    background = Background(db_dsn, action, call)
    wait_until_blocked(small, background.pid, writer.info.backend_pid)
    assert writer.execute("UPDATE items SET val = 30 WHERE obj = 1 AND part = 0").rowcount == 1
    writer.commit()
    writer.close()
    assert background.finish() > 0
    in_w = [(1, 0, 100), (1, 1, 11), (1, 2, 112), (1, 3, 13)]
    assert [r for r in _items(small, "DEFAULT") if r[0] == 1] == (
        in_w if action == "merge" else [(1, 0, 10), (1, 1, 11), (1, 2, 12)]
    )
    if action == "merge":
        assert [r for r in _items(small, "w") if r[0] == 1] == in_w
    assert [r for r in _items(small, "b") if r[0] == 1] == [(1, 0, 30), (1, 1, 11), (1, 2, 32)]
    assert invariant_problems(small) == []


# Found by the two-writers test above (seeds 3, 4, sometimes 5): save_revision took the writers' share lock on
# the version row (tgsis.write_revision) and then upgraded it, so two saves in one version deadlocked (40P01).
def test_two_writers_saving_in_one_version_at_once_wait_for_each_other_and_both_save(small: Conn, db_dsn: str) -> None:
    """Writer b has written in w (its write share-locks w's row until it commits) and saves; writer a saves
    meanwhile in a transaction of its own. a must wait for b, then save the next working revision; b must not
    wait for a, which holds nothing of w yet (save_revision checks without locking, then locks for update)."""
    b = connect(db_dsn, "b")
    tgsis.goto_version(b, "w")
    b.commit()
    b.execute("UPDATE items SET val = 101 WHERE obj = 1 AND part = 1")
    a = Background(db_dsn, "a", lambda c: tgsis.save_revision(c, "a"), version="w")
    wait_until_blocked(small, a.pid, b.info.backend_pid)
    saved_b = tgsis.save_revision(b, "b")  # 40P01 here, or in a, before the fix
    b.commit()
    b.close()
    saved_a = a.finish()
    assert saved_b < saved_a
    with tgsis.at_revision(small, saved_b, "w", local=True):
        assert (1, 1, 101) in small.execute("SELECT obj, part, val FROM items").fetchall()
    small.rollback()
    assert invariant_problems(small) == []
