"""The rows a merge or a refresh writes: only those whose content changes, compared exactly (issue 39, item 5).

tgsis.copy_object_state leaves a row of the target alone when the source
holds exactly its content under the same key: these tests make the two sides
hold values equal by their type's operator but not the same (-0.0 and 0.0,
1.0 and 1.00, json spacing, NULL and '', case under a nondeterministic
collation), values of types without an equality operator, and true identical
rewrites, and check that the merged side holds exactly the other's values
while identical rows are not written again.
"""

from __future__ import annotations

import itertools
from typing import Any

import psycopg
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import tgsis
from tgsis.db import versions as V

Conn = psycopg.Connection[Any]

COLUMNS = "f8 float8, f4 real, fa float8[], n numeric, j json, jb jsonb, p point, t text, ts timestamptz, iv interval"

# (row key, column, the parent's value, the child's value, the same value?)
CASES = [
    ("f8-zero", "f8", "0", "-0", False),
    ("f8-nan", "f8", "NaN", "NaN", True),
    ("f8-same", "f8", "1.5", "1.5", True),
    ("f8-ulp", "f8", "0.30000000000000004", "0.3", False),
    ("f4-zero", "f4", "0", "-0", False),
    ("fa-zero", "fa", "{0,0}", "{0,-0}", False),
    ("fa-null", "fa", "{1,NULL}", "{1,NULL}", True),
    ("n-scale", "n", "1.0", "1.00", False),
    ("j-space", "j", '{"a":1}', '{"a": 1}', False),
    ("j-same", "j", '{"a": 1}', '{"a": 1}', True),
    ("jb-scale", "jb", '{"a": 1.0}', '{"a": 1.00}', False),
    ("jb-same", "jb", '{"b": [1, 2], "a": 1}', '{"a": 1, "b": [1,2]}', True),
    ("p-same", "p", "(1,2)", "(1,2)", True),
    ("p-zero", "p", "(0,2)", "(-0,2)", False),
    ("t-empty", "t", None, "", False),
    ("t-null", "t", None, None, True),
    ("ts-zones", "ts", "2020-11-01 01:30:00-04", "2020-11-01 05:30:00+00", True),
    ("ts-hour", "ts", "2020-11-01 01:30:00-04", "2020-11-01 01:30:00-05", False),
    ("iv-days", "iv", "1 day", "24 hours", False),
]


def _revision(conn: Conn, version: str) -> int:
    row = conn.execute("SELECT workingrevision FROM tgsis.versions WHERE name = %s", (version,)).fetchone()
    conn.commit()
    assert row is not None
    return int(row[0])


def _exact(conn: Conn, version: str, table: str = "samples") -> dict[tuple[int, str], str]:
    """The rows a version sees, each as exact text (floats shortest-exact, their bits for NaN and -0)."""
    conn.execute("SET extra_float_digits = 1")
    rows = conn.execute(
        f"SELECT obj, k, v::text, float8send(f8), float4send(f4) FROM tgsis.rows_at(NULL::{table}, %s) v", (version,)
    ).fetchall()
    conn.commit()
    return {(r[0], r[1]): f"{r[2]} {r[3]!r} {r[4]!r}" for r in rows}


def _samples(conn: Conn) -> None:
    conn.execute(f"CREATE TABLE samples (obj int, k text, {COLUMNS}, PRIMARY KEY (obj, k))")
    conn.execute("INSERT INTO samples (obj, k) SELECT 1, k FROM unnest(%s::text[]) k", ([c[0] for c in CASES],))
    conn.execute("INSERT INTO samples (obj, k, f8) VALUES (1, 'untouched', 7)")
    tgsis.enable_versioning(conn, "samples", "obj", "sample")
    tgsis.create_version(conn, "e1")
    conn.commit()


def _set(conn: Conn, version: str, side: int) -> None:
    with tgsis.in_version(conn, version):
        for key, column, *values, _ in CASES:
            conn.execute(f"UPDATE samples SET {column} = %s WHERE obj = 1 AND k = %s", (values[side], key))
    conn.commit()


def _written(conn: Conn, revision: int) -> tuple[set[str], set[str]]:
    new = conn.execute("SELECT k FROM samples_ver WHERE revision = %s", (revision,)).fetchall()
    closed = conn.execute("SELECT k FROM samples_ver WHERE %s = ANY (lastrevs)", (revision,)).fetchall()
    conn.commit()
    return {r[0] for r in new}, {r[0] for r in closed}


def test_a_merge_copies_every_value_not_exactly_the_parents_and_only_those(conn: Conn) -> None:
    _samples(conn)
    _set(conn, "DEFAULT", 0)
    _set(conn, "e1", 1)
    with tgsis.in_version(conn, "DEFAULT"):
        tgsis.save_revision(conn, "parent")  # the merge writes in a revision of its own
    conn.commit()
    (conflict,) = V.find_conflicts(conn, "e1")
    V.resolve_conflict(conn, "e1", conflict.objectclass, conflict.objectkey, "child")
    conn.commit()
    child = _exact(conn, "e1")
    revision = _revision(conn, "DEFAULT")
    written = V.merge_version(conn, "e1")
    assert _exact(conn, "DEFAULT") == child  # the parent holds exactly the child's values
    different = {key for key, *_, same in CASES if not same}
    assert _written(conn, revision) == (different, different)
    assert written == 2 * len(different)


def test_rows_deleted_and_inserted_again_as_they_were_are_not_written(conn: Conn) -> None:
    _samples(conn)
    with tgsis.in_version(conn, "e1"):
        conn.execute("UPDATE samples SET t = 'child' WHERE obj = 1 AND k = 't-null'")
        conn.execute("DELETE FROM samples WHERE obj = 1 AND k IN ('f8-zero', 'p-same')")
        conn.execute("INSERT INTO samples (obj, k) VALUES (1, 'f8-zero'), (1, 'p-same')")
    with tgsis.in_version(conn, "DEFAULT"):
        conn.execute("DELETE FROM samples WHERE obj = 1 AND k = 'untouched'")
        conn.execute("INSERT INTO samples (obj, k, f8) VALUES (1, 'untouched', 7)")  # as it was
        tgsis.save_revision(conn, "parent")
    conn.commit()
    (conflict,) = V.find_conflicts(conn, "e1")
    V.resolve_conflict(conn, "e1", conflict.objectclass, conflict.objectkey, "child")
    conn.commit()
    child = _exact(conn, "e1")
    revision = _revision(conn, "DEFAULT")
    assert V.merge_version(conn, "e1") == 2
    assert _exact(conn, "DEFAULT") == child
    assert _written(conn, revision) == ({"t-null"}, {"t-null"})


def test_a_refresh_does_not_write_again_what_the_version_holds(conn: Conn) -> None:
    _samples(conn)
    with tgsis.in_version(conn, "e1"):
        conn.execute("UPDATE samples SET f8 = 1 WHERE obj = 1 AND k = 'f8-same'")
    with tgsis.in_version(conn, "DEFAULT"):
        conn.execute("UPDATE samples SET f8 = 2 WHERE obj = 1 AND k = 'f8-same'")
        # the parent writes two rows again as they were, and changes one to a value equal but not the same
        conn.execute("UPDATE samples SET f8 = f8 WHERE obj = 1 AND k IN ('untouched', 'f8-nan')")
        conn.execute("UPDATE samples SET f8 = '-0'::float8 WHERE obj = 1 AND k = 'p-zero'")  # NULL before
    conn.commit()
    (conflict,) = V.find_conflicts(conn, "e1")
    V.resolve_conflict(conn, "e1", conflict.objectclass, conflict.objectkey, "child")
    conn.commit()
    expected = _exact(conn, "e1")
    V.refresh_version(conn, "e1")
    after = _exact(conn, "e1")
    assert after == expected  # the version's object as it was: the solution 'child'
    revision = _revision(conn, "e1") - 0
    # closed in the refresh's revision: the parent's rows the version does not take (f8-same, p-zero);
    # not the two the parent wrote again as they were
    row = conn.execute(
        "SELECT array_agg(k ORDER BY k) FROM samples_ver WHERE revision <> %s AND %s = ANY (lastrevs)",
        (revision, revision),
    ).fetchone()
    conn.commit()
    assert row == (["f8-same", "p-zero"],)


@pytest.mark.parametrize("key_type", ["text", "date", "uuid", "numeric"])
def test_keys_of_other_types_and_an_object_key_outside_the_row_key(conn: Conn, key_type: str) -> None:
    values = {
        "text": ["a", "b", "c"],
        "date": ["2020-01-01", "2020-01-02", "2020-01-03"],
        "uuid": [f"00000000-0000-0000-0000-00000000000{i}" for i in range(3)],
        "numeric": ["1.5", "2.5", "3.5"],
    }[key_type]
    conn.execute(f"CREATE TABLE parts (objid int NOT NULL, k {key_type} PRIMARY KEY, x float8)")
    conn.execute("INSERT INTO parts SELECT 1, k, 0 FROM unnest(%s::text[]::" + key_type + "[]) k", (values,))
    tgsis.enable_versioning(conn, "parts", "objid", "part")
    tgsis.create_version(conn, "e1")
    conn.commit()
    conn.execute("SET DateStyle = 'SQL, DMY'")  # a session of other settings merges
    with tgsis.in_version(conn, "e1"):
        conn.execute("UPDATE parts SET x = 1 WHERE k = %s::" + key_type, (values[0],))
        conn.execute("UPDATE parts SET x = 2 WHERE k = %s::" + key_type, (values[1],))
    with tgsis.in_version(conn, "DEFAULT"):
        conn.execute("UPDATE parts SET x = 1 WHERE k = %s::" + key_type, (values[0],))  # the same as the child
        conn.execute("UPDATE parts SET x = '-0'::float8 WHERE k = %s::" + key_type, (values[2],))
        tgsis.save_revision(conn, "parent")
    conn.commit()
    (conflict,) = V.find_conflicts(conn, "e1")
    V.resolve_conflict(conn, "e1", conflict.objectclass, conflict.objectkey, "child")
    conn.commit()
    revision = _revision(conn, "DEFAULT")
    assert V.merge_version(conn, "e1") == 4  # values[1] (the child's) and values[2] (back to the child's 0)
    rows = conn.execute("SELECT k::text, x::text FROM tgsis.rows_at(NULL::parts, 'DEFAULT') ORDER BY k").fetchall()
    new = conn.execute("SELECT k::text FROM parts_ver WHERE revision = %s ORDER BY k", (revision,)).fetchall()
    conn.commit()
    conn.execute("SET extra_float_digits = 1")
    assert [r[1] for r in rows] == ["1", "2", "0"]
    assert len(new) == 2


def test_a_nondeterministic_collation_is_not_taken_for_the_same_text(conn: Conn) -> None:
    try:
        conn.execute("CREATE COLLATION nocase (provider = icu, locale = 'und-u-ks-level2', deterministic = false)")
    except psycopg.errors.FeatureNotSupported:
        pytest.skip("this server is built without ICU: no nondeterministic collation")
    conn.execute("CREATE TABLE names (obj int, k int, name text COLLATE nocase, PRIMARY KEY (obj, k))")
    conn.execute("INSERT INTO names VALUES (1, 1, 'granite'), (1, 2, 'basalt')")
    tgsis.enable_versioning(conn, "names", "obj", "name")
    tgsis.create_version(conn, "e1")
    conn.commit()
    with tgsis.in_version(conn, "e1"):
        conn.execute("UPDATE names SET name = 'Granite' WHERE k = 1")
        conn.execute("UPDATE names SET name = 'Basalt' WHERE k = 2")
    with tgsis.in_version(conn, "DEFAULT"):
        conn.execute("UPDATE names SET name = 'GRANITE' WHERE k = 1")  # equal under nocase, not the same
        conn.execute("UPDATE names SET name = 'Basalt' WHERE k = 2")  # the same
    conn.commit()
    (conflict,) = V.find_conflicts(conn, "e1")
    V.resolve_conflict(conn, "e1", conflict.objectclass, conflict.objectkey, "child")
    conn.commit()
    assert V.merge_version(conn, "e1") == 2
    rows = conn.execute("SELECT k, name::bytea FROM tgsis.rows_at(NULL::names, 'DEFAULT') ORDER BY k").fetchall()
    assert rows == [(1, b"Granite"), (2, b"Basalt")]


_examples = itertools.count()
_values = st.tuples(
    st.sampled_from([None, "0", "-0", "1.5", "NaN", "0.30000000000000004"]),
    st.sampled_from([None, "", "a"]),
    st.sampled_from([None, '{"a": 1.0}', '{"a": 1.00}', "[]"]),
)
_op = st.tuples(
    st.sampled_from(["update", "delete", "insert", "rewrite", "reinsert"]),
    st.integers(0, 2),  # the object
    st.integers(0, 3),  # the row
    _values,
)


def _apply(conn: Conn, version: str, base: int, ops: list[tuple[str, int, int, tuple[Any, ...]]]) -> None:
    """Edits through the versioned view, as a psql user makes them."""
    with tgsis.in_version(conn, version):
        for op, obj, k, (f8, t, jb) in ops:
            where = (base + obj, k)
            if op == "update":
                conn.execute(
                    "UPDATE obs SET f8 = %s::float8, t = %s, jb = %s::jsonb WHERE obj = %s AND k = %s",
                    (f8, t, jb, *where),
                )
            elif op == "delete":
                conn.execute("DELETE FROM obs WHERE obj = %s AND k = %s", where)
            elif op == "insert":
                conn.execute(
                    "INSERT INTO obs SELECT %s, %s, %s::float8, %s, %s::jsonb "
                    "WHERE NOT EXISTS (SELECT FROM obs WHERE obj = %s AND k = %s)",
                    (*where, f8, t, jb, *where),
                )
            elif op == "rewrite":  # the same values written again
                conn.execute("UPDATE obs SET f8 = f8, t = t, jb = jb WHERE obj = %s AND k = %s", where)
            else:  # deleted and inserted again as it was
                row = conn.execute(  # jsonb as its text: a dict would be written back re-encoded (1.00 -> 1.0)
                    "DELETE FROM obs WHERE obj = %s AND k = %s RETURNING obj, k, f8, t, jb::text", where
                ).fetchone()
                if row is not None:
                    conn.execute("INSERT INTO obs VALUES (%s, %s, %s, %s, %s::jsonb)", row)
    conn.commit()


def _state(conn: Conn, version: str, base: int) -> dict[int, dict[int, str]]:
    """Per object of this example: row key -> the row as exact text (floats by their bits)."""
    conn.execute("SET extra_float_digits = 1")
    rows = conn.execute(
        "SELECT obj, k, v::text || ' ' || coalesce(float8send(f8)::text, '-') FROM tgsis.rows_at(NULL::obs, %s) v "
        "WHERE obj BETWEEN %s AND %s",
        (version, base, base + 2),
    ).fetchall()
    conn.commit()
    state: dict[int, dict[int, str]] = {base + o: {} for o in range(3)}
    for obj, k, text in rows:
        state[obj][k] = text
    return state


@settings(
    max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow]
)
@given(
    parent_ops=st.lists(_op, max_size=8),
    child_ops=st.lists(_op, max_size=8),
    solutions=st.lists(st.sampled_from(["parent", "child"]), min_size=3, max_size=3),
    refresh=st.booleans(),
)
def test_random_edits_with_identical_rewrites_merge_and_refresh_to_exactly_the_stated_state(
    conn: Conn,
    parent_ops: list[tuple[str, int, int, tuple[Any, ...]]],
    child_ops: list[tuple[str, int, int, tuple[Any, ...]]],
    solutions: list[str],
    refresh: bool,
) -> None:
    n = next(_examples)
    if n == 0:
        conn.execute("CREATE TABLE obs (obj int, k int, f8 float8, t text, jb jsonb, PRIMARY KEY (obj, k))")
        tgsis.enable_versioning(conn, "obs", "obj", "obs")
        conn.commit()
    base, parent, child = 10 * n, f"p{n}", f"c{n}"
    tgsis.create_version(conn, parent)
    conn.commit()
    _apply(conn, parent, base, [("insert", o, k, ("1.5", "a", None)) for o in range(3) for k in range(3)])
    tgsis.create_version(conn, child, parent=parent)
    conn.commit()
    _apply(conn, child, base, child_ops)
    _apply(conn, parent, base, parent_ops)
    with tgsis.in_version(conn, parent):
        tgsis.save_revision(conn, "edits")  # what the merge writes goes into a revision of its own
    conn.commit()
    row = conn.execute(
        "SELECT array_agg(DISTINCT c.objectkey::int) FROM tgsis.versions v, "
        "tgsis.changed_objects(tgsis.own_working_revisions(v.versionid)) c WHERE v.name = %s",
        (child,),
    ).fetchone()
    conn.commit()
    changed_by_child = set(row[0] or []) if row else set()
    solved = {}
    for conflict in V.find_conflicts(conn, child):
        solved[int(conflict.objectkey)] = solutions[int(conflict.objectkey) - base]
        V.resolve_conflict(conn, child, conflict.objectclass, conflict.objectkey, solved[int(conflict.objectkey)])
    conn.commit()
    before_parent, before_child = _state(conn, parent, base), _state(conn, child, base)

    def takes_child(obj: int) -> bool:
        return obj in changed_by_child and solved.get(obj) != "parent"

    expected = {o: before_child[o] if takes_child(o) else before_parent[o] for o in before_parent}
    if refresh:
        V.refresh_version(conn, child)
        assert _state(conn, child, base) == expected
        assert _state(conn, parent, base) == before_parent
        # then merged: the parent takes the version's state, writing only what differs from its own
        assert V.find_conflicts(conn, child) == []
    _merged_exactly(conn, parent, child, base, expected, before_parent)


def _merged_exactly(
    conn: Conn,
    parent: str,
    child: str,
    base: int,
    expected: dict[int, dict[int, str]],
    before_parent: dict[int, dict[int, str]],
) -> None:
    """Merge ``child``: the parent then holds ``expected``, and only the rows whose content changed were written."""
    revision = _revision(conn, parent)
    V.merge_version(conn, child)
    after = _state(conn, parent, base)
    assert after == expected
    assert _state(conn, child, base) == expected  # the version goes on from the merged state
    new = conn.execute("SELECT obj, k FROM obs_ver WHERE revision = %s", (revision,)).fetchall()
    closed = conn.execute("SELECT obj, k FROM obs_ver WHERE %s = ANY (lastrevs)", (revision,)).fetchall()
    conn.commit()
    assert sorted(new) == sorted(
        (o, k) for o, rows in after.items() for k, text in rows.items() if before_parent[o].get(k) != text
    )
    assert sorted(closed) == sorted(
        (o, k) for o, rows in before_parent.items() for k, text in rows.items() if after[o].get(k) != text
    )


def test_names_that_need_quoting_and_a_domain_over_float8(conn: Conn) -> None:
    col = '"x ""y"""'  # the column x "y"
    conn.execute('CREATE DOMAIN "depth m" AS float8')
    conn.execute(
        'CREATE TABLE "Odd Table" ("o\'k" int, "my%col" int, ' + col + ' "depth m", PRIMARY KEY ("o\'k", "my%col"))'
    )
    conn.execute('INSERT INTO "Odd Table" VALUES (1, 1, 5), (1, 2, 5), (1, 3, 5)')
    tgsis.enable_versioning(conn, '"Odd Table"', "o'k", "odd class")
    tgsis.create_version(conn, "e1")
    conn.commit()
    for version, values in (("e1", ("1", "-0", "2")), ("DEFAULT", ("1", "0", "5"))):
        with tgsis.in_version(conn, version):
            for key, value in enumerate(values, 1):
                conn.execute('UPDATE "Odd Table" SET ' + col + ' = %s::float8 WHERE "my%%col" = %s', (value, key))
            if version == "DEFAULT":
                tgsis.save_revision(conn, "parent")
    conn.commit()
    (conflict,) = V.find_conflicts(conn, "e1")
    V.resolve_conflict(conn, "e1", conflict.objectclass, conflict.objectkey, "child")
    conn.commit()
    revision = _revision(conn, "DEFAULT")
    assert V.merge_version(conn, "e1") == 4  # rows 2 (-0 is not 0) and 3; row 1 is the same on both sides
    rows = conn.execute(
        'SELECT "my%col", float8send(' + col + ") FROM tgsis.rows_at(NULL::\"Odd Table\", 'DEFAULT')"
    ).fetchall()
    new = conn.execute('SELECT "my%%col" FROM "Odd Table_ver" WHERE revision = %s', (revision,)).fetchall()
    assert sorted(new) == [(2,), (3,)]
    assert {r[0]: bytes(r[1]) for r in rows} == {
        1: bytes.fromhex("3ff0000000000000"),  # 1.0
        2: bytes.fromhex("8000000000000000"),  # -0.0, bit for bit
        3: bytes.fromhex("4000000000000000"),  # 2.0
    }
