"""read_merge_states reads the base once and only the rows each side changed since it: the same states as three full reads.

The reference is the full read of before (each side's rows through the
versioned views, the session moved to that side's revision), kept here only:
for random edits on both sides — vertices moved, added and removed, cells
added and removed, vertex and cell property values changed, GOCAD atoms and
part runs written, spread over several revisions of each side (a version made
from a side freezes its working revision), some of them undoing others — the
three MeshStates must be equal bit for bit: ids, coordinates, cells, every
property array with its dtype, atoms and parts.
"""

from __future__ import annotations

import itertools
from typing import Any

import numpy as np
import psycopg
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from psycopg import sql

import tgsis
from tests.conftest import BuiltOnce, cloned_or_built
from tests.merge_data import curved_surface
from tests.roles import login_roles
from tests.storage_data import storage_of
from tgsis.db import _merge_states
from tgsis.db import features as F
from tgsis.db._static import SIMPLEX
from tgsis.db._transfer import Packed, columns_out_all
from tgsis.db.classes import FeatureClass
from tgsis.merge3 import MeshState
from tgsis.mesh import mesh_class

Conn = psycopg.Connection[Any]
_COUNTER = itertools.count()


# ---------------------------------------------------------------- the reference: three full reads through the views


def _full_read(conn: Conn, fc: FeatureClass, geoid: int, version: str, revision: int) -> _merge_states._Rows:
    """The object's rows as ``version`` sees them at ``revision``: every row through the versioned views."""
    conn.execute("SELECT tgsis.goto_revision(%s, %s, true)", (version, revision))
    table, key = SIMPLEX[fc.geotype]
    k = mesh_class(fc.geotype).cell_size
    requests = [
        Packed(
            sql.SQL("tgsis.vrtx"),
            "geoid",
            [("vrtxid", "int8"), ("x", "float8"), ("y", "float8"), ("z", "float8")],
            [geoid],
        ),
        Packed(
            sql.SQL("tgsis.{}").format(sql.Identifier(table)),
            "geoid",
            [(key, "int8"), *((f"vrtxid{i + 1}", "int8") for i in range(k))],
            [geoid],
        ),
    ]
    tables = []
    for alignment in ("VERTEX", "CELL"):
        props, protable = fc.aligned(alignment), fc.property_table(alignment)
        if props and protable is not None:
            tables.append((alignment, [p.name for p in props]))
            requests.append(
                Packed(
                    fc.qualified(protable), "_geoid", [("_idx", "int8"), *((p.name, p.wire) for p in props)], [geoid]
                )
            )
    vertex_cols, cell_cols, *prop_cols = columns_out_all(conn, requests)
    vids, xyz = _sorted_rows(vertex_cols[1], np.stack(vertex_cols[2:5], axis=1) if len(vertex_cols[1]) else None)
    cids, cells = _sorted_rows(cell_cols[1], np.stack(cell_cols[2:], axis=1) if len(cell_cols[1]) else None)
    props_by: dict[str, dict[str, Any]] = {"VERTEX": {}, "CELL": {}}
    for (alignment, names), columns in zip(tables, prop_cols, strict=True):
        ids = vids if alignment == "VERTEX" else cids
        idx = np.asarray(columns[1], dtype=np.int64)
        for name, values in zip(names, columns[2:], strict=True):
            props_by[alignment][name] = _aligned_values(ids, idx, np.asarray(values))
    atoms = conn.execute("SELECT vrtxid, refid FROM tgsis.atom WHERE geoid = %s ORDER BY vrtxid", (geoid,)).fetchall()
    runs = conn.execute(
        "SELECT firstid, lastid, part FROM tgsis.part WHERE geoid = %s ORDER BY firstid", (geoid,)
    ).fetchall()
    return _merge_states._Rows(
        vids,
        xyz.reshape(-1, 3).astype(np.float64),
        cids,
        cells.reshape(-1, k).astype(np.int64),
        props_by["VERTEX"],
        props_by["CELL"],
        np.asarray(atoms, dtype=np.int64).reshape(-1, 2),
        np.asarray(runs, dtype=np.int64).reshape(-1, 3),
    )


def _sorted_rows(ids: Any, rows: Any) -> tuple[Any, Any]:
    """Ids ascending with their rows (as the full read of before sorted them)."""
    ids = np.asarray(ids, dtype=np.int64)
    if rows is None:
        return ids, np.empty((0,), dtype=np.float64)
    order = np.argsort(ids, kind="stable")
    return ids[order], rows[order]


def _aligned_values(ids: Any, idx: Any, values: Any) -> Any:
    """A property's values in the order of ``ids``; an id without a row gets NaN (as before)."""
    order = np.argsort(idx, kind="stable")
    idx, values = idx[order], values[order]
    pos = np.searchsorted(idx, ids)
    found = pos < len(idx)
    found[found] = idx[pos[found]] == ids[found]
    if found.all():
        return values[pos]
    out = np.full((len(ids), *values.shape[1:]), np.nan, dtype=np.float64)
    out[found] = values[pos[found]]
    return out


def reference_states(conn: Conn, version: str, geoid: int) -> dict[str, MeshState]:
    """The three states by three full reads, in a REPEATABLE READ snapshot of their own."""
    conn.rollback()
    conn.execute("SET TRANSACTION ISOLATION LEVEL REPEATABLE READ")
    try:
        _versionid, parent, initrevision, working, parent_working = _merge_states.version_row(conn, version)
        fc = tgsis.get_feature_class(conn, "faults")
        rows = {
            "base": _full_read(conn, fc, geoid, version, initrevision),
            "parent": _full_read(conn, fc, geoid, parent, parent_working),
            "child": _full_read(conn, fc, geoid, version, working),
        }
        return _merge_states._states(fc, geoid, rows)
    finally:
        conn.rollback()


def fast_states(conn: Conn, version: str, geoid: int) -> dict[str, MeshState]:
    conn.rollback()
    conn.execute("SET TRANSACTION ISOLATION LEVEL REPEATABLE READ")
    try:
        return _merge_states.read_merge_states(conn, version, geoid).states
    finally:
        conn.rollback()


def assert_identical(fast: MeshState, reference: MeshState) -> None:
    """Equal bit for bit: every array with its dtype and bytes, property names and all."""
    assert fast.name == reference.name and fast.cell_size == reference.cell_size
    for what in ("vertex_ids", "vertices", "cell_ids", "cells"):
        a, b = getattr(fast, what), getattr(reference, what)
        assert a.dtype == b.dtype and a.shape == b.shape, what
        assert a.tobytes() == b.tobytes(), what
    for what in ("vertex_properties", "cell_properties"):
        a, b = getattr(fast, what), getattr(reference, what)
        assert a.keys() == b.keys(), what
        for name in a:
            assert a[name].dtype == b[name].dtype and a[name].shape == b[name].shape, (what, name)
            assert a[name].tobytes() == b[name].tobytes(), (what, name)


def _arrays(state: MeshState) -> list[Any]:
    return [
        state.vertex_ids,
        state.vertices,
        state.cell_ids,
        state.cells,
        *state.vertex_properties.values(),
        *state.cell_properties.values(),
    ]


def assert_nothing_shared(states: dict[str, MeshState]) -> None:
    """No array of one state shares memory with another's: a user changing one state changes no other."""
    for a, b in itertools.combinations(states, 2):
        for x in _arrays(states[a]):
            for y in _arrays(states[b]):
                assert not np.shares_memory(x, y), (a, b)


# ---------------------------------------------------------------- random edits, as SQL users make them


#: each kind of edit, apart: a test that leaves kinds out draws from the others (no filter: Hypothesis's
#: filter_too_much health check failed a run that filtered the atom edits out)
EDIT_KINDS = {
    "move": st.tuples(
        st.just("move"), st.lists(st.integers(0, 10_000), min_size=1, max_size=6), st.sampled_from([0.5, -1.25, 3.0e-7])
    ),
    "vertex value": st.tuples(
        st.just("vertex value"), st.lists(st.integers(0, 10_000), min_size=1, max_size=4), st.floats(-1, 1, width=32)
    ),
    "cell value": st.tuples(
        st.just("cell value"), st.lists(st.integers(0, 10_000), min_size=1, max_size=4), st.integers(-9, 9)
    ),
    "remove vertices": st.tuples(
        st.just("remove vertices"), st.lists(st.integers(0, 10_000), min_size=1, max_size=3), st.just(0)
    ),
    "remove cells": st.tuples(
        st.just("remove cells"), st.lists(st.integers(0, 10_000), min_size=1, max_size=4), st.just(0)
    ),
    "add vertices": st.tuples(
        st.just("add vertices"), st.lists(st.integers(0, 10_000), min_size=1, max_size=3), st.just(0)
    ),
    "add cells": st.tuples(st.just("add cells"), st.lists(st.integers(0, 10_000), min_size=3, max_size=3), st.just(0)),
    "atom": st.tuples(st.just("atom"), st.lists(st.integers(0, 10_000), min_size=2, max_size=2), st.just(0)),
    "parts": st.tuples(st.just("parts"), st.lists(st.integers(0, 10_000), min_size=1, max_size=1), st.just(0)),
    "freeze": st.tuples(st.just("freeze"), st.just([0]), st.just(0)),
}
EDIT = st.one_of(*EDIT_KINDS.values())


def _ids(conn: Conn, table: str, key: str, geoid: int) -> list[int]:
    query = sql.SQL("SELECT {} FROM tgsis.{} WHERE geoid = %s ORDER BY 1").format(
        sql.Identifier(key), sql.Identifier(table)
    )
    return [int(r[0]) for r in conn.execute(query, (geoid,)).fetchall()]


def edit(conn: Conn, fc: FeatureClass, version: str, geoid: int, step: tuple[str, list[int], Any]) -> None:
    """One committed edit of ``version`` (picks are taken modulo the ids there are)."""
    kind, picks, value = step
    if kind == "freeze":  # a version made from this side: its working revision is frozen, the next edits get a new one
        tgsis.create_version(conn, f"frozen{next(_COUNTER)}", version)
        conn.commit()
        return
    vtable, ctable = fc.qualified(fc.property_table("VERTEX") or ""), fc.qualified(fc.property_table("CELL") or "")
    with tgsis.in_version(conn, version):
        vids, cids = _ids(conn, "vrtx", "vrtxid", geoid), _ids(conn, "trgl", "trglid", geoid)
        some_v = sorted({vids[p % len(vids)] for p in picks}) if vids else []
        some_c = sorted({cids[p % len(cids)] for p in picks}) if cids else []
        if kind == "move" and some_v:
            conn.execute(
                "UPDATE tgsis.vrtx SET z = z + %s, x = x - %s WHERE geoid = %s AND vrtxid = ANY(%s)",
                (value, value, geoid, some_v),
            )
        elif kind == "vertex value" and some_v:
            conn.execute(
                sql.SQL("UPDATE {} SET porosity = %s WHERE _geoid = %s AND _idx = ANY(%s)").format(vtable),
                (value, geoid, some_v),
            )
        elif kind == "cell value" and some_c:
            conn.execute(
                sql.SQL("UPDATE {} SET facies = %s WHERE _geoid = %s AND _idx = ANY(%s)").format(ctable),
                (value, geoid, some_c),
            )
        elif kind == "remove cells" and some_c:
            conn.execute(sql.SQL("DELETE FROM {} WHERE _geoid = %s AND _idx = ANY(%s)").format(ctable), (geoid, some_c))
            conn.execute("DELETE FROM tgsis.trgl WHERE geoid = %s AND trglid = ANY(%s)", (geoid, some_c))
        elif kind == "remove vertices" and len(vids) > len(some_v) + 3:
            gone = [
                int(r[0])
                for r in conn.execute(
                    "SELECT trglid FROM tgsis.trgl WHERE geoid = %s AND (vrtxid1 = ANY(%s) OR vrtxid2 = ANY(%s) OR vrtxid3 = ANY(%s))",
                    (geoid, some_v, some_v, some_v),
                ).fetchall()
            ]
            conn.execute(sql.SQL("DELETE FROM {} WHERE _geoid = %s AND _idx = ANY(%s)").format(ctable), (geoid, gone))
            conn.execute("DELETE FROM tgsis.trgl WHERE geoid = %s AND trglid = ANY(%s)", (geoid, gone))
            conn.execute(
                "DELETE FROM tgsis.atom WHERE geoid = %s AND (vrtxid = ANY(%s) OR refid = ANY(%s))",
                (geoid, some_v, some_v),
            )
            conn.execute(sql.SQL("DELETE FROM {} WHERE _geoid = %s AND _idx = ANY(%s)").format(vtable), (geoid, some_v))
            conn.execute("DELETE FROM tgsis.vrtx WHERE geoid = %s AND vrtxid = ANY(%s)", (geoid, some_v))
        elif kind == "add vertices":
            first = (max(vids) + 1) if vids else 0
            for n, p in enumerate(picks):
                conn.execute(
                    "INSERT INTO tgsis.vrtx (geoid, vrtxid, x, y, z) VALUES (%s, %s, %s, %s, %s)",
                    (geoid, first + n, p * 0.37, -p * 1.1, 1.0 / (p + 3)),
                )
                if p % 2:  # some new vertices get a value, some none (the state gives them NaN)
                    conn.execute(
                        sql.SQL("INSERT INTO {} (_geoid, _idx, porosity) VALUES (%s, %s, %s)").format(vtable),
                        (geoid, first + n, p / 7),
                    )
        elif kind == "add cells" and len(vids) >= 3:
            corners = sorted({vids[p % len(vids)] for p in picks})
            if len(corners) == 3:
                new = (max(cids) + 1) if cids else 0
                conn.execute(
                    "INSERT INTO tgsis.trgl (geoid, trglid, vrtxid1, vrtxid2, vrtxid3) VALUES (%s, %s, %s, %s, %s)",
                    (geoid, new, *corners),
                )
                if picks[0] % 2:
                    conn.execute(
                        sql.SQL("INSERT INTO {} (_geoid, _idx, facies) VALUES (%s, %s, %s)").format(ctable),
                        (geoid, new, picks[1] % 5),
                    )
        elif kind == "atom" and len(vids) >= 2:
            atom, ref = vids[picks[0] % len(vids)], vids[picks[1] % len(vids)]
            if atom != ref:
                conn.execute("DELETE FROM tgsis.atom WHERE geoid = %s AND vrtxid = %s", (geoid, atom))
                conn.execute("INSERT INTO tgsis.atom (geoid, vrtxid, refid) VALUES (%s, %s, %s)", (geoid, atom, ref))
        elif kind == "parts" and cids:
            cut = cids[picks[0] % len(cids)]
            conn.execute("DELETE FROM tgsis.part WHERE geoid = %s", (geoid,))
            runs = [(min(cids), cut, 0)] + ([(cut + 1, max(cids), 1)] if cut < max(cids) else [])
            for first, last, part in runs:
                conn.execute(
                    "INSERT INTO tgsis.part (geoid, firstid, lastid, part) VALUES (%s, %s, %s, %s)",
                    (geoid, first, last, part),
                )


def make_faults(conn: Conn) -> int:
    """The versioned class ``faults`` (a vertex and a cell property), empty."""
    F.create_feature_class(
        conn,
        "faults",
        "SURFACE",
        cell_properties=[("porosity", "float8"), tgsis.Property("facies", "int", alignment="CELL")],
    )
    tgsis.enable_feature_versioning(conn)
    conn.commit()
    return 0


BUILT_ONCE = {"faults": make_faults}  # built once, cloned per test (db_dsn, tests/conftest.py)


@pytest.fixture
def faults(request: pytest.FixtureRequest, conn: Conn, built_once: BuiltOnce) -> FeatureClass:
    """``make_faults``'s class, already in the test's database (cloned, not built again)."""
    cloned_or_built(request, conn, built_once, "faults", make_faults)
    fc = tgsis.get_feature_class(conn, "faults")
    conn.commit()
    return fc


SIDES = st.lists(EDIT, min_size=1, max_size=6)


@settings(
    max_examples=25,
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture],
)
@given(parent_edits=SIDES, child_edits=SIDES, based_on_frozen=st.booleans())
def test_the_read_by_change_equals_three_full_reads(
    conn: Conn, faults: FeatureClass, parent_edits: list[Any], child_edits: list[Any], based_on_frozen: bool
) -> None:
    n = next(_COUNTER)
    geoid = F.insert_feature(conn, "faults", curved_surface())
    conn.commit()
    version = f"e{n}"
    if based_on_frozen:  # based on a frozen revision of DEFAULT: DEFAULT's later rows are the parent's side too
        edit(conn, faults, "DEFAULT", geoid, ("move", [3, 4], 0.25))
        row = conn.execute("SELECT workingrevision FROM tgsis.versions WHERE name = 'DEFAULT'").fetchone()
        assert row is not None
        conn.commit()
        edit(conn, faults, "DEFAULT", geoid, ("freeze", [0], 0))
        edit(conn, faults, "DEFAULT", geoid, ("vertex value", [5], 0.75))
        tgsis.create_version(conn, version, base=int(row[0]))
    else:
        tgsis.create_version(conn, version)
    conn.commit()
    # both sides must change the object: a first move on each, then the random edits
    edit(conn, faults, "DEFAULT", geoid, ("move", [0], 1.0))
    edit(conn, faults, version, geoid, ("move", [140], -1.0))
    for step in parent_edits:
        edit(conn, faults, "DEFAULT", geoid, step)
    for step in child_edits:
        edit(conn, faults, version, geoid, step)
    reference = reference_states(conn, version, geoid)
    fast = fast_states(conn, version, geoid)
    assert fast.keys() == reference.keys()
    for side in reference:
        assert_identical(fast[side], reference[side])
    assert_nothing_shared(fast)


def _a_merge_to_read(conn: Conn) -> tuple[int, str]:
    """A fault moved at its two ends (DEFAULT and version e1), a vertex value changed in e1 (committed)."""
    geoid = F.insert_feature(conn, "faults", curved_surface())
    tgsis.create_version(conn, "e1")
    conn.commit()
    edit(conn, tgsis.get_feature_class(conn, "faults"), "DEFAULT", geoid, ("move", [0, 1, 2], 1.0))
    conn.commit()
    edit(conn, tgsis.get_feature_class(conn, "faults"), "e1", geoid, ("move", [140, 141], -1.0))
    edit(conn, tgsis.get_feature_class(conn, "faults"), "e1", geoid, ("vertex value", [141], 0.5))
    conn.commit()
    return geoid, "e1"


def test_a_role_that_may_read_the_views_but_not_the_storage_reads_the_same_states(
    conn: Conn, faults: FeatureClass, db_dsn: str
) -> None:
    """A grant on a view only (SELECT on the storage of the cell values, which neither side changed, revoked).

    The conflict check reads only the storage of the tables the sides
    changed; the states are read in full through the views, and are equal.
    """
    geoid, version = _a_merge_to_read(conn)
    cell_table = faults.property_table("CELL")
    assert cell_table is not None
    owner = fast_states(conn, version, geoid)
    storage = storage_of(conn, cell_table, faults.schema)  # <table>_ver, or its chunk table
    conn.execute(f"REVOKE SELECT ON {storage} FROM tgsis_reader")
    conn.commit()
    with login_roles(db_dsn, {"rita": "tgsis_reader"}) as made:
        rita = made.connect("rita")
        fc = tgsis.get_feature_class(rita, "faults")
        rita.rollback()
        assert _merge_states._readable_storages(rita, _merge_states._tables(fc)[0]) is None
        rita.rollback()
        read = fast_states(rita, version, geoid)
        for side in owner:
            assert_identical(read[side], owner[side])
        assert read["child"].vertex_properties["porosity"][141] == 0.5


def test_a_role_without_the_right_on_a_property_table_gets_the_permission_error(
    conn: Conn, faults: FeatureClass, db_dsn: str
) -> None:
    """The view of the cell values revoked: reading the merge is refused, not a state without those values."""
    geoid, version = _a_merge_to_read(conn)
    cell_table = faults.property_table("CELL")
    assert cell_table is not None
    conn.execute(sql.SQL("REVOKE SELECT ON {} FROM tgsis_reader").format(faults.qualified(cell_table)))
    conn.commit()
    with login_roles(db_dsn, {"rita": "tgsis_reader"}) as made:
        rita = made.connect("rita")
        with pytest.raises(psycopg.errors.InsufficientPrivilege, match=cell_table):
            fast_states(rita, version, geoid)
