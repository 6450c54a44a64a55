"""The SQL check of stored G-maps (``tgsis.gmap_check`` / ``md_check``): the one-pass array path and the keyed joins agree.

``tgsis.gmap_conditions`` reads rows shaped as ``insert_gmap`` writes them
(one alpha row per dart and level, darts numbered densely) as one array and
checks every condition in one pass (``gmap_conditions_by_arrays``); rows of
any other shape go through keyed joins (``gmap_conditions_by_rows``). Each
test breaks a stored map one way and compares what the two say, problem by
problem, count and darts included.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import psycopg
import pytest
from psycopg import sql

import tgsis
from tgsis import gmaps
from tgsis.db import features as F
from tgsis.db import gmaps as G

from .gmaps_shapes import block_tetrahedra

Conn = psycopg.Connection[Any]
Rows = list[tuple[str, int, list[int]]]

MODEL4 = ("tgsis.gmap_dart", "tgsis.gmap_alpha", "nodeid", "timem")
MODEL5 = ("tgsis.md_dart", "tgsis.md_alpha", "vrtxid", None)


def _evolving() -> gmaps.EvolvingGMap:
    """A block of 2 x 2 x 2 cubes of tetrahedra for t in [0, 1], then (a topology change) of one cube from t = 1 on."""
    block = gmaps.GMap.from_tetrahedra(*block_tetrahedra(2))
    cube = gmaps.GMap.from_tetrahedra(*block_tetrahedra(1))
    return gmaps.EvolvingGMap(
        [
            gmaps.GMapPeriod([0.0, 1.0], block, np.stack([block.points, block.points * 2])),
            gmaps.GMapPeriod([1.0], cube, cube.points[None] + 5),
        ],
        alive=True,
    )


def _stored(conn: Conn, model: str) -> tuple[int, int, tuple[str, str, str, str | None]]:
    """A stored G-map of the model ('GMAP': the evolving block, two periods; 'MULTIDIM': a solid with 4 axes)."""
    if model == "GMAP":
        fc = F.create_feature_class(conn, "blocks", "GMAP", time_model="GMAP", cell_level=3)
        # the block's jump to a cube at t = 1 is allowed (tolerance): stored darts, not continuity, are checked here
        return F.insert_feature(conn, fc, _evolving(), tolerance=100.0), 3, MODEL4
    fc = F.create_feature_class(conn, "knowledge", "GMAP", time_model="MULTIDIM", cell_level=3)
    solid = gmaps.GMap.from_tetrahedra(*block_tetrahedra(2))
    points = np.column_stack([solid.points, np.arange(solid.n_points) % 3])
    return G.insert_gmap(conn, fc, gmaps.GMap(solid.alpha, solid.vertex, points), axes=["x", "y", "z", "k"]), 3, MODEL5


def _read_as_array(conn: Conn, geoid: int, n: int, tables: tuple[str, str, str, str | None]) -> bool:
    row = conn.execute(
        sql.SQL(
            "SELECT tgsis.gmap_alpha_array(%s, %s, %s::regclass, min(dartid), max(dartid), count(*)) IS NOT NULL "
            "FROM {} WHERE geoid = %s"
        ).format(sql.Identifier(*tables[0].split("."))),
        (geoid, n, tables[1], geoid),
    ).fetchone()
    assert row is not None
    return bool(row[0])


def _holds(conn: Conn, geoid: int, n: int, tables: tuple[str, str, str, str | None]) -> bool:
    """What the one-statement proof (tgsis.gmap_conditions_hold) says, with the darts' numbering as gmap_conditions reads it."""
    period = sql.SQL("min({0}) < max({0})").format(sql.Identifier(tables[3])) if tables[3] else sql.SQL("false")
    row = conn.execute(
        sql.SQL(
            "SELECT tgsis.gmap_conditions_hold(%s, %s, %s::regclass, %s::regclass, %s, %s, "
            "min(dartid), max(dartid), count(*), {}) FROM {} WHERE geoid = %s"
        ).format(period, sql.Identifier(*tables[0].split("."))),
        (geoid, n, *tables, geoid),
    ).fetchone()
    assert row is not None
    return bool(row[0])


def _both(conn: Conn, geoid: int, n: int, tables: tuple[str, str, str, str | None]) -> tuple[Rows, Rows]:
    """What tgsis.gmap_conditions answers (its array path when the rows allow it) and what the keyed joins answer."""
    args = (geoid, n, *tables)
    fast = conn.execute(
        "SELECT problem, count, darts FROM tgsis.gmap_conditions(%s, %s, %s, %s, %s, %s)", args
    ).fetchall()
    rows = conn.execute(
        "SELECT problem, count, darts FROM tgsis.gmap_conditions_by_rows(%s, %s, %s, %s, %s, %s)", args
    ).fetchall()
    return fast, rows


def _alpha(tables: tuple[str, str, str, str | None]) -> str:
    return tables[1]


# Breaks that keep the rows' shape: the array path runs and must say what the keyed joins say.
SAME_SHAPE = {
    "non-involution": "UPDATE {alpha} SET dartid2 = dartid2 + 1 WHERE geoid = %(g)s AND level = 0 AND dartid = 8",
    "fixed point below n": "UPDATE {alpha} SET dartid2 = dartid WHERE geoid = %(g)s AND level = 1 AND dartid IN (30, 31, 40)",
    "swapped alpha_3 pairs": (
        "UPDATE {alpha} a SET dartid2 = CASE a.dartid2 WHEN 50 THEN 51 WHEN 51 THEN 50 ELSE a.dartid2 END "
        "WHERE geoid = %(g)s AND level = 3 AND a.dartid2 IN (50, 51)"
    ),
    "alpha_2 resewn": (
        "UPDATE {alpha} SET dartid2 = CASE dartid WHEN 2 THEN 7 WHEN 7 THEN 2 WHEN 3 THEN 6 ELSE 3 END "
        "WHERE geoid = %(g)s AND level = 2 AND dartid IN (2, 7, 3, 6)"
    ),
    "darts moved to other points": "UPDATE {dart} SET {point} = {point} + 1 WHERE geoid = %(g)s AND dartid IN (0, 99)",
}


@pytest.mark.parametrize("model", ["GMAP", "MULTIDIM"])
@pytest.mark.parametrize("breakage", list(SAME_SHAPE))
def test_a_break_that_keeps_the_rows_shape_is_reported_alike_by_both_paths(
    conn: Conn, model: str, breakage: str
) -> None:
    geoid, n, tables = _stored(conn, model)
    assert _both(conn, geoid, n, tables) == ([], [])
    assert _holds(conn, geoid, n, tables)
    conn.execute(SAME_SHAPE[breakage].format(alpha=tables[1], dart=tables[0], point=tables[2]), {"g": geoid})
    assert _read_as_array(conn, geoid, n, tables)
    assert not _holds(conn, geoid, n, tables)
    fast, rows = _both(conn, geoid, n, tables)
    assert rows, "the break went unnoticed"
    assert fast == rows


@pytest.mark.parametrize("model", ["GMAP", "MULTIDIM"])
def test_a_break_of_composition_alone_is_caught_by_the_commuting_test(conn: Conn, model: str) -> None:
    """One pair of darts sewn by alpha_3 made free: every involution still one, points alike, only compositions broken.

    The proof tests alpha_i alpha_j = alpha_j alpha_i instead of (alpha_i alpha_j)^2 = id; this break is seen by that
    test alone.
    """
    geoid, n, tables = _stored(conn, model)
    conn.execute(
        sql.SQL(
            "UPDATE {0} SET dartid2 = dartid WHERE geoid = %(g)s AND level = 3 AND dartid IN "
            "(SELECT unnest(ARRAY[p.dartid, p.dartid2]) FROM (SELECT dartid, dartid2 FROM {0} WHERE geoid = %(g)s "
            "AND level = 3 AND dartid2 <> dartid ORDER BY dartid LIMIT 1) AS p)"
        ).format(sql.Identifier(*tables[1].split("."))),
        {"g": geoid},
    )
    problems = [p for p, _, _ in _both(conn, geoid, n, tables)[1]]
    assert problems and all(" o alpha_3 is not an involution" in p for p in problems), problems
    assert not _holds(conn, geoid, n, tables)


def test_darts_sent_into_another_period_are_reported_alike(conn: Conn) -> None:
    geoid, n, tables = _stored(conn, "GMAP")
    low = conn.execute("SELECT min(dartid) FROM tgsis.gmap_dart WHERE geoid = %s AND timem = 1", (geoid,)).fetchone()
    assert low is not None
    # the first dart of the cube and the last of the block sewn by alpha_3 (both on the border: free in alpha_3)
    conn.execute(
        "UPDATE tgsis.gmap_alpha SET dartid2 = CASE dartid WHEN %(a)s THEN %(b)s ELSE %(a)s END "
        "WHERE geoid = %(g)s AND level = 3 AND dartid IN (%(a)s, %(b)s)",
        {"a": low[0], "b": low[0] - 1, "g": geoid},
    )
    assert _read_as_array(conn, geoid, n, tables)
    assert not _holds(conn, geoid, n, tables)
    fast, rows = _both(conn, geoid, n, tables)
    assert ("alpha_3 sends a dart into another topology period", 2, [low[0] - 1, low[0]]) in fast
    assert fast == rows


def test_many_random_breaks_are_reported_alike(conn: Conn) -> None:
    geoid, n, tables = _stored(conn, "GMAP")
    darts = conn.execute("SELECT count(*) FROM tgsis.gmap_dart WHERE geoid = %s", (geoid,)).fetchone()
    assert darts is not None
    rng = np.random.default_rng(5)
    for level, dart, image in zip(
        rng.integers(0, n + 1, 40), rng.integers(0, darts[0], 40), rng.integers(0, darts[0], 40)
    ):
        conn.execute(
            "UPDATE tgsis.gmap_alpha SET dartid2 = %s WHERE geoid = %s AND level = %s AND dartid = %s",
            (int(image), geoid, int(level), int(dart)),
        )
    assert _read_as_array(conn, geoid, n, tables)
    assert not _holds(conn, geoid, n, tables)
    fast, rows = _both(conn, geoid, n, tables)
    assert len(rows) > 5 and any(count > 20 for _, count, _ in rows)  # the first 20 darts are listed, all counted
    assert fast == rows


def test_rows_in_another_physical_order_read_the_same(conn: Conn) -> None:
    geoid, n, tables = _stored(conn, "GMAP")
    conn.execute("UPDATE tgsis.gmap_alpha SET dartid2 = dartid2 + 0 WHERE geoid = %s AND level IN (0, 2)", (geoid,))
    assert _holds(conn, geoid, n, tables)  # the rows are read in key order, not the heap's
    conn.execute(
        "UPDATE tgsis.gmap_alpha SET dartid2 = dartid2 + 1 WHERE geoid = %s AND level = 0 AND dartid = 3", (geoid,)
    )
    fast, rows = _both(conn, geoid, n, tables)
    assert fast == rows and [p for p, _, _ in fast] == [
        "alpha_0 is not an involution",
        "alpha_0 o alpha_2 is not an involution",
        "alpha_0 o alpha_3 is not an involution",
    ]


# Breaks of the shape itself: no array; the keyed joins say what is wrong, through tgsis.gmap_check too.
OTHER_SHAPE = {
    "missing alpha row": (
        "DELETE FROM {alpha} WHERE geoid = %(g)s AND level = 1 AND dartid = 5",
        "dart has no alpha_1 row",
    ),
    "row above the dimension": (
        "INSERT INTO {alpha} (geoid, level, dartid, dartid2) VALUES (%(g)s, 4, 0, 0)",
        "alpha_4 row above the dimension 3",
    ),
    # as many rows as the shape wants, but one in the wrong place: only the levels' and darts' ranges show it
    "row moved above the dimension": (
        "UPDATE {alpha} SET level = 4 WHERE geoid = %(g)s AND level = 1 AND dartid = 5",
        "dart has no alpha_1 row",
    ),
    # the same with the rows' key order kept: the array would read as before
    "last row moved above the dimension": (
        "UPDATE {alpha} SET level = 4 WHERE geoid = %(g)s AND level = 3 AND dartid = 5",
        "dart has no alpha_3 row",
    ),
    "row moved to a missing dart": (
        "UPDATE {alpha} SET dartid = 100000 WHERE geoid = %(g)s AND level = 1 AND dartid = 5",
        "dart has no alpha_1 row",
    ),
    "last row moved to a missing dart": (
        "UPDATE {alpha} SET dartid = dartid + 1 WHERE geoid = %(g)s AND level = 3 AND dartid = "
        "(SELECT max(dartid) FROM {alpha} WHERE geoid = %(g)s)",
        "dart has no alpha_3 row",
    ),
    "dangling image": (
        "UPDATE {alpha} SET dartid2 = 100000 WHERE geoid = %(g)s AND level = 2 AND dartid = 9",
        "alpha_2 row of a missing dart or to a missing dart",
    ),
    # darts renumbered consistently, with a hole: a valid map that only the keyed joins can read
    "hole in the numbering": (
        "UPDATE {dart} SET dartid = dartid + 100000 WHERE geoid = %(g)s AND dartid >= 90; "
        "UPDATE {alpha} SET dartid = dartid + CASE WHEN dartid >= 90 THEN 100000 ELSE 0 END, "
        "dartid2 = dartid2 + CASE WHEN dartid2 >= 90 THEN 100000 ELSE 0 END WHERE geoid = %(g)s",
        None,
    ),
}


@pytest.mark.parametrize("model", ["GMAP", "MULTIDIM"])
@pytest.mark.parametrize("breakage", list(OTHER_SHAPE))
def test_a_break_of_the_rows_shape_is_reported_by_the_keyed_joins(conn: Conn, model: str, breakage: str) -> None:
    geoid, n, tables = _stored(conn, model)
    statements, problem = OTHER_SHAPE[breakage]
    for statement in statements.split("; "):
        conn.execute(statement.format(alpha=tables[1], dart=tables[0]), {"g": geoid})
    assert not _read_as_array(conn, geoid, n, tables)
    assert not _holds(conn, geoid, n, tables)
    fast, rows = _both(conn, geoid, n, tables)
    assert fast == rows
    if problem is None:
        assert fast == [] and G.gmap_check(conn, geoid) == []
    else:
        assert problem in [p for p, _, _ in fast]
        assert problem in [p.problem for p in G.gmap_check(conn, geoid)]


def test_a_valid_map_is_read_as_an_array_and_passes(conn: Conn) -> None:
    for model in ("GMAP", "MULTIDIM"):
        geoid, n, tables = _stored(conn, model)
        assert _read_as_array(conn, geoid, n, tables)
        assert _holds(conn, geoid, n, tables)
        assert G.gmap_check(conn, geoid) == []
        conn.rollback()


def test_a_level_outside_the_range_is_not_taken_for_a_missing_one(conn: Conn) -> None:
    """A dart's alpha_0 row as level -1 (a table without tgsis's level check): counts and key order match, the proof fails."""
    geoid, n, _ = _stored(conn, "GMAP")
    conn.execute("CREATE TEMP TABLE alpha AS SELECT * FROM tgsis.gmap_alpha WHERE geoid = %s", (geoid,))
    conn.execute("ALTER TABLE alpha ADD PRIMARY KEY (geoid, dartid, level)")
    conn.execute("UPDATE alpha SET level = -1 WHERE level = 0 AND dartid = 5")
    tables = ("tgsis.gmap_dart", "pg_temp.alpha", "nodeid", "timem")
    assert not _holds(conn, geoid, n, tables)
    fast, rows = _both(conn, geoid, n, tables)
    assert fast == rows and "dart has no alpha_0 row" in [p for p, _, _ in fast]


# What the darts point at exists: proved from the numbering of nodes and points, or named by a join.
EXISTENCE = {
    "node deleted": (
        "GMAP",
        "DELETE FROM tgsis.gmap_node WHERE geoid = %(g)s AND nodeid = "
        "(SELECT nodeid FROM tgsis.gmap_dart WHERE geoid = %(g)s AND dartid = 7)",
        "dart of a node missing from its topology period",
    ),
    "node moved to the other period": (
        "GMAP",
        "UPDATE tgsis.gmap_node SET timem = 1 WHERE geoid = %(g)s AND timem = 0 AND nodeid = "
        "(SELECT nodeid FROM tgsis.gmap_dart WHERE geoid = %(g)s AND dartid = 7)",
        "dart of a node missing from its topology period",
    ),
    "dart of a node beyond the others": (
        "GMAP",
        "UPDATE tgsis.gmap_dart SET nodeid = 100000 WHERE geoid = %(g)s AND dartid = 7",
        "dart of a node missing from its topology period",
    ),
    "period deleted": (
        "GMAP",
        "DELETE FROM tgsis.gmap_timem WHERE geoid = %(g)s AND timem = 1",
        "dart of a topology period that does not exist",
    ),
    "point deleted": (
        "MULTIDIM",
        "DELETE FROM tgsis.md_vertex WHERE geoid = %(g)s AND vrtxid = "
        "(SELECT vrtxid FROM tgsis.md_dart WHERE geoid = %(g)s AND dartid = 7)",
        "dart of a point that does not exist",
    ),
    "dart of a point beyond the others": (
        "MULTIDIM",
        "UPDATE tgsis.md_dart SET vrtxid = 100000 WHERE geoid = %(g)s AND dartid = 7",
        "dart of a point that does not exist",
    ),
    # valid, but numbered with a hole: the proof by numbering fails, the join finds nothing
    "nodes renumbered with a hole": (
        "GMAP",
        "UPDATE tgsis.gmap_node SET nodeid = nodeid + 100000 WHERE geoid = %(g)s AND nodeid >= 3; "
        "UPDATE tgsis.gmap_dart SET nodeid = nodeid + 100000 WHERE geoid = %(g)s AND nodeid >= 3; "
        "UPDATE tgsis.gmap_vertex SET nodeid = nodeid + 100000 WHERE geoid = %(g)s AND nodeid >= 3",
        None,
    ),
    "points renumbered with a hole": (
        "MULTIDIM",
        "UPDATE tgsis.md_vertex SET vrtxid = vrtxid + 100000 WHERE geoid = %(g)s AND vrtxid >= 3; "
        "UPDATE tgsis.md_dart SET vrtxid = vrtxid + 100000 WHERE geoid = %(g)s AND vrtxid >= 3",
        None,
    ),
}


@pytest.mark.parametrize("breakage", list(EXISTENCE))
def test_darts_of_missing_nodes_points_or_periods_are_named(conn: Conn, breakage: str) -> None:
    model, statements, problem = EXISTENCE[breakage]
    geoid, _, _ = _stored(conn, model)
    for statement in statements.split("; "):
        conn.execute(statement, {"g": geoid})
    problems = {p.problem: p for p in G.gmap_check(conn, geoid)}
    if problem is None:
        assert problems == {}
        return
    assert problem in problems
    if breakage != "period deleted":
        assert 7 in problems[problem].darts
    else:
        low = conn.execute(
            "SELECT min(dartid), count(*) FROM tgsis.gmap_dart WHERE geoid = %s AND timem = 1", (geoid,)
        ).fetchone()
        assert low is not None and problems[problem].count == low[1] and problems[problem].darts[0] == low[0]


def test_a_break_in_a_version_is_seen_there_alike_and_not_in_default(conn: Conn) -> None:
    geoid, n, tables = _stored(conn, "GMAP")
    conn.commit()
    tgsis.enable_feature_versioning(conn)
    tgsis.create_version(conn, "edit")
    with tgsis.in_version(conn, "edit"):
        conn.execute(SAME_SHAPE["non-involution"].format(alpha="tgsis.gmap_alpha"), {"g": geoid})
        conn.commit()
        assert _read_as_array(conn, geoid, n, tables)  # through the versioned view
        fast, rows = _both(conn, geoid, n, tables)
        assert fast == rows and "alpha_0 is not an involution" in [p for p, _, _ in fast]
        conn.commit()
    conn.commit()
    assert G.gmap_check(conn, geoid) == []


@pytest.mark.parametrize(
    "args",
    [
        (1, 2, "pg_catalog.pg_class", "pg_catalog.pg_class", "relname", None),  # tables of no G-map
        (1, 2, "tgsis.gmap_dart", "tgsis.gmap_alpha", "no_such_column", None),  # a point column the darts lack
        (1, -1, "tgsis.gmap_dart", "tgsis.gmap_alpha", "nodeid", None),  # no dimension
        (1, 2, None, "tgsis.gmap_alpha", "nodeid", None),
    ],
)
def test_arguments_that_name_no_g_map_get_our_error(conn: Conn, args: tuple[Any, ...]) -> None:
    """gmap_conditions is callable by anyone: wrong tables or columns get TG100 with a hint, not a missing column."""
    with pytest.raises(tgsis.InvalidInputError) as caught:
        with tgsis.errors.reraise():
            conn.execute("SELECT * FROM tgsis.gmap_conditions(%s, %s, %s, %s, %s, %s)", args)
    assert caught.value.sqlstate == "TG100"
    assert "gmap_check" in (caught.value.hint or "")
    conn.rollback()
