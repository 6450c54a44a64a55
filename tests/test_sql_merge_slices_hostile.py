"""Hostile review of the psql merge of surfaces at instants (model 2; tgsis.merge_instants_by_slice).

Each case sets up a model-2 surface the way a demanding user could (instants at
times that differ in their last bit, -0.0, huge times, properties of every
type a class may have, odd schema and class names, partitioned storage, a
version whose parent is not DEFAULT) and asks: does ``SELECT
tgsis.merge_version(v)`` write exactly what the Python merge writes (row
version for row version, tests.test_sql_merge_write.assert_same_merge), or
refuse by name writing nothing?
"""

from __future__ import annotations

from typing import Any

import numpy as np
import psycopg
import pytest
from psycopg import sql

import tgsis
from tests.conftest import BuiltOnce
from tests.merge_data import curved_surface
from tests.roles import merges_as
from tests.test_merge_instants import CHILD_SHIFT, NORTH, PARENT_SHIFT, SOUTH, TIMES, _porosity, _shape, move
from tests.test_sql_merge_write import assert_same_merge, both_merges, everything
from tgsis.temporal import SurfaceSeries

Conn = psycopg.Connection[Any]


def _class(conn: Conn, name: str = "horizons", schema: str = "public", **extra: Any) -> None:
    tgsis.create_feature_class(
        conn,
        name,
        "SURFACE",
        time_model="INSTANTS",
        schema=schema,
        cell_properties=extra.pop("cell_properties", [("porosity", "float8")]),
        instant_properties=extra.pop("instant_properties", [("throw", "double precision")]),
        **extra,
    )
    tgsis.enable_feature_versioning(conn)


def _series(conn: Conn, name: str = "horizons", times: tuple[float, ...] = TIMES, **props: Any) -> int:
    cells = curved_surface().cells
    surfaces = [
        tgsis.Surface(_shape(i), cells, vertex_properties={"porosity": _porosity()} | props) for i in range(len(times))
    ]
    series = SurfaceSeries(np.asarray(times), surfaces, properties={"throw": np.arange(len(times)) * 10.0 + 10.0})
    return int(tgsis.insert_feature(conn, name, series))


def _add(conn: Conn, version: str, geoid: int, t: float, name: str = "horizons") -> None:
    surface = tgsis.Surface(_shape(5), curved_surface().cells, vertex_properties={"porosity": _porosity() * 3.0})
    with tgsis.in_version(conn, version):
        tgsis.add_instant(conn, name, geoid, t, surface, {"throw": 44.0})
    conn.commit()


def _sql(conn: Conn, version: str, text: Any, args: tuple[Any, ...] = ()) -> None:
    with tgsis.in_version(conn, version):
        conn.execute(text, args)
    conn.commit()


def make_horizons(conn: Conn) -> int:
    """``_class`` then ``_series`` with their defaults (committed): the set-up most cases here start from."""
    _class(conn)
    return _series(conn)


BUILT_ONCE = {"horizons": make_horizons}  # built once, cloned per test (db_dsn, tests/conftest.py)


@pytest.fixture
def horizons(db_dsn: str, built_once: BuiltOnce) -> int:
    """Geoid of ``make_horizons``'s surface, already in the test's database (cloned, not built again)."""
    return built_once(f"{__name__}.horizons", make_horizons)[1]


def _same_or_refused_by_name(conn: Conn, version: str, action: str = "merge") -> tuple[Any, ...]:
    """The psql merge writes what Python writes, or refuses (TG302) writing nothing."""
    before = everything(conn)
    conn.commit()
    theirs, mine = both_merges(conn, version, action)
    if mine[0] == "refused":
        assert mine[1] == "TG302", mine
        assert everything(conn) == before
        conn.commit()
        return mine
    assert theirs[0] == "done", (theirs, mine)
    assert mine[1] == theirs[1], (mine[1], theirs[1])
    for table in theirs[2]:
        assert mine[2][table] == theirs[2][table], table
    return mine


# ---------------------------------------------------------------------------- times by their bits


@pytest.mark.parametrize(
    ("added", "side"),
    [
        (1.0000000000000002, "e1"),  # the next double after instant 1.0
        (1.0000000000000002, "DEFAULT"),
        (0.9999999999999999, "DEFAULT"),
        (-0.0, "DEFAULT"),
        (-0.0, "e1"),
        (-1.0e300, "DEFAULT"),
        (1.0e300, "e1"),
        (5e-324, "DEFAULT"),  # the smallest subnormal
    ],
)
def test_an_instant_added_at_a_time_a_bit_apart_merges_exactly_as_in_python(
    conn: Conn, horizons: int, added: float, side: str
) -> None:
    geoid = horizons
    tgsis.create_version(conn, "e1")
    conn.commit()
    _add(conn, side, geoid, added)
    other = "DEFAULT" if side == "e1" else "e1"
    move(conn, other, geoid, 1.0, NORTH, CHILD_SHIFT)
    move(conn, side, geoid, 3.0, SOUTH, PARENT_SHIFT)
    assert_same_merge(conn, "e1")


def test_instants_at_zero_and_minus_zero_on_both_sides(conn: Conn, horizons: int) -> None:
    """The parent adds instant 0.0, the version -0.0 (one instant for PostgreSQL and numpy), alike otherwise."""
    geoid = horizons
    tgsis.create_version(conn, "e1")
    conn.commit()
    _add(conn, "DEFAULT", geoid, 0.0)
    _add(conn, "e1", geoid, -0.0)
    move(conn, "e1", geoid, 1.0, NORTH, CHILD_SHIFT)
    _same_or_refused_by_name(conn, "e1")


# ---------------------------------------------------------------------------- storage and names


def test_partitioned_storage_merges_exactly_as_in_python(conn: Conn) -> None:
    conn.execute("SELECT tgsis.partition_model_storage(2::smallint, 4)")
    conn.commit()
    _class(conn)
    geoid = _series(conn)
    tgsis.create_version(conn, "e1")
    conn.commit()
    move(conn, "e1", geoid, 1.0, NORTH, CHILD_SHIFT)
    _add(conn, "e1", geoid, 4.0)
    move(conn, "DEFAULT", geoid, 3.0, SOUTH, PARENT_SHIFT)
    _sql(conn, "DEFAULT", "UPDATE horizons_pros SET throw = 25 WHERE _geoid = %s AND _times = 2", (geoid,))
    assert_same_merge(conn, "e1")


def test_odd_schema_and_class_names(conn: Conn) -> None:
    schema, name = 'Odd "S"; x', "hor_izons"
    conn.execute(sql.SQL("CREATE SCHEMA {}").format(sql.Identifier(schema)))
    conn.commit()
    _class(
        conn, name, schema, instant_properties=[("Thr_Ow", "double precision")], cell_properties=[("PoRo", "float8")]
    )
    cells = curved_surface().cells
    surfaces = [tgsis.Surface(_shape(i), cells, vertex_properties={"PoRo": _porosity()}) for i in range(3)]
    geoid = int(
        tgsis.insert_feature(
            conn, name, SurfaceSeries(np.asarray(TIMES), surfaces, properties={"Thr_Ow": np.asarray([1.0, 2.0, 3.0])})
        )
    )
    tgsis.create_version(conn, "e1")
    conn.commit()
    fc = conn.execute("SELECT protablename, cellprotable FROM tgsis.catalog WHERE classname = %s", (name,)).fetchone()
    assert fc is not None
    move(conn, "e1", geoid, 1.0, NORTH, CHILD_SHIFT)
    move(conn, "DEFAULT", geoid, 3.0, SOUTH, PARENT_SHIFT)
    _sql(
        conn,
        "DEFAULT",
        sql.SQL("UPDATE {} SET {} = 25 WHERE _geoid = %s AND _times = 2").format(
            sql.Identifier(schema, fc[0]), sql.Identifier("Thr_Ow")
        ),
        (geoid,),
    )
    _sql(
        conn,
        "e1",
        sql.SQL("UPDATE {} SET {} = -0.0 WHERE _geoid = %s AND _times = 1 AND _idx < 5").format(
            sql.Identifier(schema, fc[1]), sql.Identifier("PoRo")
        ),
        (geoid,),
    )
    assert_same_merge(conn, "e1")


# ---------------------------------------------------------------------------- properties of every type

INSTANT_TYPES = [
    ("i2", "smallint"),
    ("i4", "integer"),
    ("i8", "bigint"),
    ("f4", "real"),
    ("f8", "double precision"),
    ("b", "boolean"),
    ("n", "numeric"),
    ("s", "text"),
    ("d", "date"),
    ("ts", "timestamptz"),
    ("j", "jsonb"),
]


@pytest.mark.parametrize("settings", ["default", "odd"])
def test_per_instant_properties_of_every_type_merge_column_by_column(conn: Conn, settings: str) -> None:
    _class(conn, instant_properties=[("throw", "double precision"), *INSTANT_TYPES])
    geoid = _series(conn)
    _sql(
        conn,
        "DEFAULT",
        "UPDATE horizons_pros SET i2 = -3, i4 = 7, i8 = 9007199254740993, f4 = 0.1, f8 = 0.1, b = true,"
        " n = 1.10, s = 'a''b', d = '2026-12-05', ts = '2026-12-05 10:00+00', j = '{\"a\": [1, 2.5]}'"
        " WHERE _geoid = %s",
        (geoid,),
    )
    tgsis.create_version(conn, "e1")
    conn.commit()
    # instant 2: the parent changes some columns, the version others (and a big int by one)
    _sql(
        conn,
        "DEFAULT",
        "UPDATE horizons_pros SET i2 = NULL, f4 = 3.4028235e38, s = 'é\"x', ts = '1999-01-01 00:00+05'"
        " WHERE _geoid = %s AND _times = 2",
        (geoid,),
    )
    _sql(
        conn,
        "e1",
        "UPDATE horizons_pros SET i8 = 9007199254740994, f8 = -0.0, b = NULL, n = 1.1000, d = 'infinity',"
        " j = '{\"a\": [1, 2.50]}' WHERE _geoid = %s AND _times = 2",
        (geoid,),
    )
    move(conn, "e1", geoid, 1.0, NORTH, CHILD_SHIFT)
    move(conn, "DEFAULT", geoid, 3.0, SOUTH, PARENT_SHIFT)
    if settings == "odd":
        conn.execute("SET DateStyle = 'SQL, DMY'")
        conn.execute("SET TimeZone = 'Pacific/Chatham'")
        conn.execute("SET IntervalStyle = 'sql_standard'")
        conn.commit()
    assert_same_merge(conn, "e1")


@pytest.mark.parametrize(
    ("kind", "column", "value"),
    [
        ("bigint", "big", 9007199254740993),  # 2**53 + 1: no float64 holds it
        ("bigint", "big", None),
        ("integer", "n", None),
        ("boolean", "ok", None),
        ("real", "r", -0.0),
        ("real", "r", float("nan")),
        ("double precision", "porosity", float("inf")),
    ],
)
def test_vertex_properties_of_other_types_merge_exactly_as_in_python(
    conn: Conn, kind: str, column: str, value: Any
) -> None:
    props = [("porosity", "float8")] + ([(column, kind)] if column != "porosity" else [])
    _class(conn, cell_properties=props)
    extra: dict[str, Any] = {}
    if column != "porosity":
        dtype = {"bigint": np.int64, "integer": np.int32, "boolean": np.bool_, "real": np.float32}[kind]
        extra[column] = (
            np.arange(len(_porosity())) * 3 + 2**53 if kind == "bigint" else np.arange(len(_porosity())) % 2
        ).astype(dtype)
    geoid = _series(conn, **extra)
    tgsis.create_version(conn, "e1")
    conn.commit()
    table = conn.execute("SELECT cellprotable FROM tgsis.catalog WHERE classname = 'horizons'").fetchone()
    assert table is not None
    if value is None:  # (the columns are NOT NULL: a vertex without its property row)
        _sql(
            conn,
            "e1",
            sql.SQL("DELETE FROM {} WHERE _geoid = %s AND _times = 1 AND _idx BETWEEN 3 AND 6").format(
                sql.Identifier(table[0])
            ),
            (geoid,),
        )
    else:
        _sql(
            conn,
            "e1",
            sql.SQL("UPDATE {} SET {} = %s WHERE _geoid = %s AND _times = 1 AND _idx BETWEEN 3 AND 6").format(
                sql.Identifier(table[0]), sql.Identifier(column)
            ),
            (value, geoid),
        )
    move(conn, "DEFAULT", geoid, 3.0, SOUTH, PARENT_SHIFT)
    _same_or_refused_by_name(conn, "e1")


# ---------------------------------------------------------------------------- versions


def test_a_version_whose_parent_is_not_default(conn: Conn, horizons: int) -> None:
    geoid = horizons
    tgsis.create_version(conn, "e1")
    tgsis.create_version(conn, "e2", "e1")
    conn.commit()
    move(conn, "e2", geoid, 1.0, NORTH, CHILD_SHIFT)
    _add(conn, "e2", geoid, 7.5)
    move(conn, "e1", geoid, 3.0, SOUTH, PARENT_SHIFT)
    move(conn, "DEFAULT", geoid, 2.0, SOUTH, PARENT_SHIFT)  # DEFAULT's edit: not e1's, not merged
    assert_same_merge(conn, "e2")
    assert_same_merge(conn, "e2", "refresh")


def test_many_instants_and_many_objects(conn: Conn) -> None:
    _class(conn)
    times = tuple(float(t) for t in range(1, 41))
    ids = [_series(conn, times=times) for _ in range(3)]
    tgsis.create_version(conn, "e1")
    conn.commit()
    for k, geoid in enumerate(ids):
        for t in times[k::3]:
            move(conn, "e1", geoid, t, NORTH, CHILD_SHIFT)
        for t in times[k + 1 :: 3]:
            move(conn, "DEFAULT", geoid, t, SOUTH, PARENT_SHIFT)
    assert_same_merge(conn, "e1")


@pytest.mark.parametrize("moved", [1.0, 2.0])
def test_minus_zero_written_over_zero_alone_at_an_instant(conn: Conn, moved: float) -> None:
    """-0.0 over 0.0 is no change to merge3 (floats -0 as 0) but other bits: at instant 1 alone, the version's only
    edit there; the version moves instant ``moved``, the parent instant 3."""
    _class(conn, cell_properties=[("porosity", "float8"), ("r", "real")])
    n = len(_porosity())
    geoid = _series(conn, r=np.ones(n, dtype=np.float32))
    _sql(conn, "DEFAULT", "UPDATE horizons_cellpros SET porosity = 0, r = 0 WHERE _geoid = %s AND _idx < 9", (geoid,))
    tgsis.create_version(conn, "e1")
    conn.commit()
    _sql(
        conn,
        "e1",
        "UPDATE horizons_cellpros SET porosity = -0.0, r = '-0' WHERE _geoid = %s AND _times = 1 AND _idx BETWEEN 3 AND 6",
        (geoid,),
    )
    _sql(conn, "e1", "UPDATE tgsis.times_vrtx SET z = -0.0 WHERE geoid = %s AND times = 1 AND vrtxid = 0", (geoid,))
    move(conn, "e1", geoid, moved, NORTH[5:], CHILD_SHIFT)
    move(conn, "DEFAULT", geoid, 3.0, SOUTH, PARENT_SHIFT)
    assert_same_merge(conn, "e1")  # (merge3's regions at instant 1: refused by name before they were computed in SQL)


def test_a_class_without_any_property(conn: Conn) -> None:
    _class(conn, cell_properties=[], instant_properties=[])
    surfaces = [tgsis.Surface(_shape(i), curved_surface().cells) for i in range(3)]
    geoid = int(tgsis.insert_feature(conn, "horizons", SurfaceSeries(np.asarray(TIMES), surfaces)))
    tgsis.create_version(conn, "e1")
    conn.commit()
    move(conn, "e1", geoid, 1.0, NORTH, CHILD_SHIFT)
    move(conn, "DEFAULT", geoid, 3.0, SOUTH, PARENT_SHIFT)
    surface = tgsis.Surface(_shape(5), curved_surface().cells)
    with tgsis.in_version(conn, "e1"):
        tgsis.add_instant(conn, "horizons", geoid, 9.0, surface)
    conn.commit()
    assert_same_merge(conn, "e1")


# ---------------------------------------------------------------------------- solutions of a slice's region from psql


def test_a_psql_solution_with_rows_for_a_region_of_an_instant_is_taken_and_merges_as_in_python(
    conn: Conn, horizons: int
) -> None:
    """A psql user records a manual mesh with its rows (as for a model-1 region) for a region of an instant: the
    rows are taken (they were refused TG100 while the psql merge applied only parent, child and base there), and
    the psql merge applies them as the Python merge applies the .npz."""
    from tgsis.db.regions import _sql_rows, state_to_npz

    geoid = horizons
    tgsis.create_version(conn, "e1")
    conn.commit()
    move(conn, "e1", geoid, 2.0, NORTH, CHILD_SHIFT)
    move(conn, "DEFAULT", geoid, 2.0, NORTH, PARENT_SHIFT)
    [conflict] = tgsis.find_conflicts(conn, "e1")
    conn.commit()
    region = next(r for r in conflict.regions if r.conflict)
    assert region.times == 2.0
    from tgsis.db._merge_states import read_sliced_states

    states = read_sliced_states(conn, "e1", geoid).states
    conn.rollback()
    child = states["child"].slices[(2.0,)]
    conn.execute(
        "SELECT tgsis.resolve_region('e1', 'feature', %s, %s, 'manual', %s,"
        " %s, %s::float8[], %s, %s, %s::text[], %s::float8[], %s::text[], %s::float8[])",
        (str(geoid), region.region, state_to_npz(child), *(_sql_rows(child) or ())),
    )
    conn.commit()
    (recorded,) = conn.execute(
        "SELECT cardinality(solution_vertex_ids) FROM tgsis.conflict_regions WHERE objectkey = %s AND region = %s",
        (str(geoid), region.region),
    ).fetchone() or (None,)
    assert recorded == len(child.vertex_ids)
    conn.commit()
    assert_same_merge(conn, "e1")


# ---------------------------------------------------------------------------- negative ids


@pytest.mark.storage("rows")  # chunks refuse negative ids by design (docs/storage.md, "What differs from rows")
@pytest.mark.parametrize("new_id", [-1, -5, -(2**62)])
def test_a_negative_vertex_id_a_psql_user_stored_merges_exactly_as_in_python_model1(
    conn: Conn, fault_clone: int, new_id: int
) -> None:
    """The storage takes any bigint id (a psql INSERT through tgsis.vrtx stores vrtxid -5): a vertex and triangle the
    version added with negative ids merge like any other (-1 is no "none" to merge3), in both merges alike."""
    from tests.merge_data import move as move1

    geoid = fault_clone
    _sql(conn, "e1", "INSERT INTO tgsis.vrtx (geoid, vrtxid, x, y, z) VALUES (%s, %s, 1.5, 2.5, 3.5)", (geoid, new_id))
    _sql(
        conn,
        "e1",
        "INSERT INTO tgsis.trgl (geoid, trglid, vrtxid1, vrtxid2, vrtxid3) VALUES (%s, %s, 0, 1, %s)",
        (geoid, new_id - 1, new_id),
    )
    move1(conn, "e1", geoid, range(0, 12), CHILD_SHIFT)
    move1(conn, "DEFAULT", geoid, range(120, 144), PARENT_SHIFT)
    mine = assert_same_merge(conn, "e1")
    assert any(r[1] == str(new_id) for r in mine[2]["tgsis.vrtx_ver"]), "the new vertex is kept"


def test_a_negative_vertex_id_at_an_instant_merges_exactly_as_in_python(conn: Conn, horizons: int) -> None:
    """On rows the version's negative ids merge as any other; chunks refuse them by design (docs/storage.md, "What
    differs from rows"): the INSERT is refused TG100, nothing written."""
    geoid = horizons
    tgsis.create_version(conn, "e1")
    conn.commit()
    if conn.execute("SELECT tgsis.stored_in_chunks('times_vrtx')").fetchone() == (True,):
        before = everything(conn)
        conn.commit()
        with pytest.raises(psycopg.Error) as refused:
            _sql(
                conn,
                "e1",
                "INSERT INTO tgsis.times_vrtx (geoid, times, vrtxid, x, y, z) VALUES (%s, 2, -1, 1.5, 2.5, 3.5)",
                (geoid,),
            )
        assert refused.value.sqlstate == "TG100", refused.value
        conn.rollback()
        assert everything(conn) == before
        conn.commit()
        return
    _sql(
        conn,
        "e1",
        "INSERT INTO tgsis.times_vrtx (geoid, times, vrtxid, x, y, z) VALUES (%s, 2, -1, 1.5, 2.5, 3.5)",
        (geoid,),
    )
    _sql(
        conn,
        "e1",
        "INSERT INTO tgsis.times_trgl (geoid, times, trglid, vrtxid1, vrtxid2, vrtxid3) VALUES (%s, 2, -2, 0, 1, -1)",
        (geoid,),
    )
    move(conn, "DEFAULT", geoid, 3.0, SOUTH, PARENT_SHIFT)
    assert_same_merge(conn, "e1")


# ---------------------------------------------------------------------------- more one-sided scenarios

MORE: dict[str, list[tuple[str, str]]] = {
    "version moves instant 2, parent changes its per-instant property": [
        ("e1", "move 2 north"),
        ("DEFAULT", "throw 2 25"),
    ],
    "parent moves instant 2, version changes its per-instant property": [
        ("DEFAULT", "move 2 south"),
        ("e1", "throw 2 25"),
    ],
    "version removes instant 2, parent changes its per-instant property": [
        ("e1", "delete 2"),
        ("DEFAULT", "throw 2 25"),
    ],
    "both remove instant 2, parent moves 3": [("e1", "delete 2"), ("DEFAULT", "delete 2"), ("DEFAULT", "move 3 south")],
    "both add instant 4 alike, the parent then changes its property": [
        ("e1", "add 4"),
        ("DEFAULT", "add 4"),
        ("DEFAULT", "throw 4 9"),
        ("e1", "move 1 north"),
    ],
    "version removes instant 2 and adds it anew, parent moves 3": [
        ("e1", "delete 2"),
        ("e1", "add 2"),
        ("DEFAULT", "move 3 south"),
    ],
    "parent removes instant 2 and adds it anew, version moves 3": [
        ("DEFAULT", "delete 2"),
        ("DEFAULT", "add 2"),
        ("e1", "move 3 north"),
    ],
    "version moves 2 and back, parent moves 2": [
        ("e1", "move 2 north"),
        ("e1", "back 2 north"),
        ("DEFAULT", "move 2 south"),
    ],
    "version edits cells of 2 and 3, parent the properties of 1": [
        ("e1", "cells 2"),
        ("e1", "cells 3"),
        ("DEFAULT", "throw 1 5"),
        ("DEFAULT", "move 1 south"),
    ],
}


@pytest.mark.parametrize("scenario", list(MORE))
def test_more_scenarios_merge_in_psql_exactly_as_in_python_or_are_refused_by_name(
    conn: Conn, horizons: int, scenario: str
) -> None:
    from tests.test_sql_merge_slices import _step

    geoid = horizons
    tgsis.create_version(conn, "e1")
    conn.commit()
    for version, step in MORE[scenario]:
        if step.startswith("back"):  # the version's move undone (the same bits again)
            t = float(step.split()[1])
            shift = tuple(-s for s in CHILD_SHIFT)
            move(conn, version, geoid, t, NORTH, shift)  # type: ignore[arg-type]
        else:
            _step(conn, version, step, geoid)
    theirs, mine = both_merges(conn, "e1")
    if theirs[0] == "refused":
        assert mine[:2] == theirs[:2], (theirs, mine)
    else:
        _same_or_refused_by_name(conn, "e1")


# ---------------------------------------------------------------------------- rights on the helpers


def test_object_merge_refusal_is_not_public_and_an_editor_still_merges_in_psql(conn: Conn, db_dsn: str) -> None:
    """tgsis.object_merge_refusal (m23's, asked by the model-1 and model-2 psql merges and by
    tgsis.mesh_merge_regions, which runs as its caller) was executable by PUBLIC, against the rule that internal
    functions are not: it is the tgsis roles' (tgsis_reader) only, and an editor with the version's rights still
    merges a surface at instants from psql, exactly as the Python merge does."""
    from tests.roles import login_roles

    signature = "tgsis.object_merge_refusal(text, bigint)"
    rights = conn.execute(
        "SELECT has_function_privilege('public', %s::regprocedure, 'EXECUTE'),"
        " has_function_privilege('tgsis_reader', %s::regprocedure, 'EXECUTE')",
        (signature, signature),
    ).fetchone()
    conn.rollback()
    assert rights == (False, True), rights
    _class(conn)
    geoid = _series(conn)
    tgsis.create_version(conn, "e1")
    conn.commit()
    move(conn, "e1", geoid, 1.0, NORTH, CHILD_SHIFT)
    move(conn, "DEFAULT", geoid, 3.0, SOUTH, PARENT_SHIFT)
    theirs, _ = both_merges(conn, "e1")
    with login_roles(db_dsn, {"ed": "tgsis_editor"}) as made:
        tgsis.grant_version(conn, "e1", "all", made.name("ed"))
        tgsis.grant_version(conn, "DEFAULT", "merge", made.name("ed"))
        conn.commit()
        session = made.connect("ed")
        row = session.execute("SELECT tgsis.merge_version('e1')").fetchone()
        session.commit()
        assert row is not None and int(row[0]) == theirs[1]
        after = everything(conn)
        conn.commit()
        tables = conn.execute(  # (the time table's storage: times_vrtx_ver, or its chunk table: docs/storage.md)
            "SELECT tgsis.storage_table('tgsis', t) FROM unnest(ARRAY['times_vrtx', 'times']) t"
        ).fetchall()
        conn.commit()
        for table in [str(t) for (t,) in tables] + ["public.horizons_cellpros_ver"]:
            assert after[table] == theirs[2][table], table


# ---------------------------------------------------------------------------- an instant no state sees


@pytest.mark.parametrize("side", ["DEFAULT", "e1"])
def test_an_instant_added_then_removed_in_a_later_revision_merges_as_in_python(
    conn: Conn, horizons: int, side: str
) -> None:
    """Instant 4 added on one side, its revision frozen (a version made from it), then removed: its rows are in the
    storage, seen by none of the three states. No state has it: nothing to merge there, not an object-level
    conflict."""
    from tests.test_sql_merge_slices import _step

    geoid = horizons
    tgsis.create_version(conn, "e1")
    conn.commit()
    _step(conn, side, "add 4", geoid)
    tgsis.create_version(conn, "frozen", side)  # the side's working revision is frozen: the removal closes rows
    conn.commit()
    _step(conn, side, "delete 4", geoid)
    move(conn, "e1", geoid, 1.0, NORTH, CHILD_SHIFT)
    move(conn, "DEFAULT", geoid, 3.0, SOUTH, PARENT_SHIFT)
    assert_same_merge(conn, "e1")
    assert_same_merge(conn, "e1", "refresh")


@pytest.mark.parametrize("side", ["DEFAULT", "e1"])
def test_an_instant_removed_in_psql_by_its_times_row_alone(conn: Conn, horizons: int, side: str) -> None:
    """A psql user deletes instant 2's tgsis.times row only (its vertex, triangle and property rows stay): the
    instant is gone on that side; the other side moves another instant."""
    geoid = horizons
    tgsis.create_version(conn, "e1")
    conn.commit()
    _sql(conn, side, "DELETE FROM tgsis.times WHERE geoid = %s AND times = 2", (geoid,))
    move(conn, "e1", geoid, 1.0, NORTH, CHILD_SHIFT)
    move(conn, "DEFAULT", geoid, 3.0, SOUTH, PARENT_SHIFT)
    theirs, mine = both_merges(conn, "e1")
    if theirs[0] == "refused":
        assert mine[:2] == theirs[:2], (theirs, mine)
    else:
        _same_or_refused_by_name(conn, "e1")


@pytest.mark.parametrize("revoked", ["INSERT", "UPDATE", "DELETE", "INSERT, UPDATE, DELETE", "INSERT on the storage"])
@pytest.mark.parametrize("table", ["horizons_cellpros", "horizons_pros"])
def test_a_role_that_may_not_write_a_property_table_is_refused_as_in_python(
    conn: Conn, horizons: int, db_dsn: str, table: str, revoked: str
) -> None:
    """The editor may change the feature but not the class's vertex (per-instant) property rows: the merge brings
    the parent's property edits into the version; psql must refuse as the Python merge does, writing nothing."""
    from tests.roles import login_roles
    from tests.test_sql_merge_slices import _step

    geoid = horizons
    tgsis.create_version(conn, "e1")
    conn.commit()
    _step(conn, "DEFAULT", "cells 2" if table == "horizons_cellpros" else "throw 2 25", geoid)
    move(conn, "e1", geoid, 1.0, NORTH, CHILD_SHIFT)
    with login_roles(db_dsn, {"ed": "tgsis_editor"}) as made:
        tgsis.grant_version(conn, "e1", "all", made.name("ed"))
        tgsis.grant_version(conn, "DEFAULT", "merge", made.name("ed"))
        if revoked == "INSERT on the storage":  # (the Python client COPYs new row versions there)
            conn.execute(sql.SQL("REVOKE INSERT ON {} FROM tgsis_editor").format(sql.Identifier(f"{table}_ver")))
        else:
            conn.execute(sql.SQL("REVOKE {} ON {} FROM tgsis_editor").format(sql.SQL(revoked), sql.Identifier(table)))
        conn.commit()
        before = everything(conn)
        conn.commit()
        session = made.connect("ed")
        theirs, mine = merges_as(conn, session, "e1")
        assert everything(conn) == before
        conn.commit()
        if revoked == "INSERT, UPDATE, DELETE":
            assert theirs == ("refused", "42501"), theirs  # PostgreSQL refuses the Python merge's statement
        assert mine == theirs, (revoked, theirs, mine)


@pytest.mark.parametrize("revoked", ["DELETE", "INSERT, UPDATE, DELETE"])
@pytest.mark.parametrize("alignment", ["VERTEX", "CELL"])
def test_a_role_that_may_not_write_a_property_table_is_refused_as_in_python_model1(
    conn: Conn, fault_clone: int, db_dsn: str, alignment: str, revoked: str
) -> None:
    """The same for the psql merge by region of a model-1 mesh: the parent's property edits are refused as the
    Python merge refuses them (TG002 without DELETE: tgsis.delete_object_rows), nothing written. (Both merges
    COPY / INSERT the new row versions into the storage itself, as check-in does: the view's INSERT right is
    not asked there.)"""
    from tests.merge_data import move as move1
    from tests.roles import login_roles

    geoid = fault_clone
    table = conn.execute(
        "SELECT CASE WHEN proalignment = %s THEN cellprotable ELSE otherprotable END FROM tgsis.catalog"
        " WHERE classname = 'faults'",
        (alignment,),
    ).fetchone()
    assert table is not None and table[0]
    column = "porosity" if alignment == "VERTEX" else "facies"
    _sql(
        conn,
        "DEFAULT",
        sql.SQL("UPDATE {} SET {} = {} + 1 WHERE _geoid = %s AND _idx BETWEEN 130 AND 133").format(
            sql.Identifier(table[0]), sql.Identifier(column), sql.Identifier(column)
        ),
        (geoid,),
    )
    move1(conn, "e1", geoid, range(0, 3), CHILD_SHIFT)
    with login_roles(db_dsn, {"ed": "tgsis_editor"}) as made:
        tgsis.grant_version(conn, "e1", "all", made.name("ed"))
        tgsis.grant_version(conn, "DEFAULT", "merge", made.name("ed"))
        conn.execute(sql.SQL("REVOKE {} ON {} FROM tgsis_editor").format(sql.SQL(revoked), sql.Identifier(table[0])))
        conn.commit()
        before = everything(conn)
        conn.commit()
        session = made.connect("ed")
        with pytest.raises(tgsis.Error) as python:
            tgsis.merge_version(session, "e1")
        session.rollback()
        assert python.value.sqlstate in ("42501", "TG002"), str(python.value)
        with pytest.raises(psycopg.Error) as caught:
            session.execute("SELECT tgsis.merge_version('e1')")
        session.rollback()
        assert caught.value.sqlstate == python.value.sqlstate, (str(python.value), str(caught.value))
        assert everything(conn) == before
        conn.commit()


def test_a_class_with_triangle_properties(conn: Conn) -> None:
    """Properties per triangle (alignment CELL) at each instant: the version edits some at instant 1, the parent
    moves instant 3; both merges write the same rows."""
    _class(conn, cell_properties=[("facies", "int")], alignment="CELL")
    cells = curved_surface().cells
    facies = np.arange(len(cells)) % 5
    surfaces = [tgsis.Surface(_shape(i), cells, cell_properties={"facies": facies}) for i in range(3)]
    geoid = int(
        tgsis.insert_feature(
            conn, "horizons", SurfaceSeries(np.asarray(TIMES), surfaces, properties={"throw": np.asarray([1.0, 2, 3])})
        )
    )
    tgsis.create_version(conn, "e1")
    conn.commit()
    table = conn.execute("SELECT cellprotable FROM tgsis.catalog WHERE classname = 'horizons'").fetchone()
    assert table is not None
    _sql(
        conn,
        "e1",
        sql.SQL("UPDATE {} SET facies = 9 WHERE _geoid = %s AND _times = 1 AND _idx BETWEEN 10 AND 14").format(
            sql.Identifier(table[0])
        ),
        (geoid,),
    )
    _sql(
        conn,
        "e1",
        sql.SQL("DELETE FROM {} WHERE _geoid = %s AND _times = 1 AND _idx = 20").format(sql.Identifier(table[0])),
        (geoid,),
    )
    move(conn, "DEFAULT", geoid, 3.0, SOUTH, PARENT_SHIFT)
    _same_or_refused_by_name(conn, "e1")
