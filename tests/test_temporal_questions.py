"""Temporal questions: tgsis.property_periods and tgsis.first_time against an independent reference.

The reference does not cut the time line the way the SQL does (one piece per
sample). It evaluates the spec's value function of time (a step function for
model 2, linear between geometry instants for model 3) on every elementary
set between consecutive breakpoints (the instants, plus the crossing times
found by inverse interpolation with np.interp), and joins the runs of
elementary sets where the condition holds. Dense random sampling checks the
answer once more, point by point.
"""

from __future__ import annotations

import math
import operator
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
import psycopg
import pytest

import tgsis
from tests.temporal_data import evolving, grid, series
from tgsis.temporal import EvolvingSurface, TopologyPeriod

Conn = psycopg.Connection[Any]
OPS = ["<", "<=", ">", ">=", "=", "<>"]
COMPARE: dict[str, Callable[[float, float], bool]] = {
    "<": operator.lt,
    "<=": operator.le,
    ">": operator.gt,
    ">=": operator.ge,
    "=": operator.eq,
    "<>": operator.ne,
}
#: (lower, lower closed, upper, upper closed); infinite bounds for unbounded ends
Interval = tuple[float, bool, float, bool]
Value = float | None  # None: unknown (NULL) or no feature at that time
INF = math.inf

# --------------------------------------------------------------------------- the reference


def holds(x: Value, op: str, v: float) -> bool:
    """x op v, False when x is unknown (None or NaN)."""
    return x is not None and not math.isnan(x) and COMPARE[op](x, v)


def sweep(
    breaks: Sequence[float],
    value_at: Callable[[float], Value],
    op: str,
    v: float,
    crossings: frozenset[float] = frozenset(),
) -> list[Interval]:
    """Maximal intervals where value_at(t) op v, the value being of one kind between consecutive breakpoints.

    At a crossing the value is v exactly (evaluated as such, not recomputed).
    """
    points = sorted(set(breaks))
    # elementary sets in time order: (lower, upper, is_point, representative)
    cells: list[tuple[float, float, bool, float]] = [(-INF, points[0], False, points[0] - 1.0)]
    for i, x in enumerate(points):
        cells.append((x, x, True, x))
        upper = points[i + 1] if i + 1 < len(points) else INF
        cells.append((x, upper, False, (x + upper) / 2 if upper < INF else x + 1.0))
    runs: list[Interval] = []
    open_run = False
    for lower, upper, is_point, rep in cells:
        ok = holds(v if is_point and rep in crossings else value_at(rep), op, v)
        if ok and not open_run:
            runs.append((lower, is_point, upper, is_point))
        elif ok:
            runs[-1] = (runs[-1][0], runs[-1][1], upper, is_point)
        open_run = ok
    return runs


def step_value(times: Sequence[float], values: Sequence[Value], alive: bool, convention: str, t: float) -> Value:
    """Model 2 by the spec: the instant the convention chooses at t, the last one after the end if alive."""
    if t < times[0] or (t > times[-1] and not alive):
        return None
    if t > times[-1]:
        return values[-1]
    if convention == "left":
        return values[sum(1 for x in times if x <= t) - 1]
    return values[sum(1 for x in times if x < t)]


def step_reference(
    times: Sequence[float], values: Sequence[Value], alive: bool, convention: str, op: str, v: float
) -> list[Interval]:
    return sweep(times, lambda t: step_value(times, values, alive, convention, t), op, v)


Series = list[tuple[np.ndarray, list[Value]]]  # per topology period: geometry instants, values


def linear_value(periods: Series, alive: bool, t: float, end: float | None = None) -> Value:
    """Model 3 by the spec: the last period starting at or before t, linear between its instants.

    After a period's last instant its last value holds until the next period
    (or ``end``), for ever after the last period if alive.
    """
    starts = [float(p[0][0]) for p in periods]
    if t < starts[0] or (end is not None and t >= end):
        return None
    index = max(i for i, s in enumerate(starts) if s <= t)
    times, values = periods[index]
    if t > times[-1]:
        return values[-1] if index < len(periods) - 1 or alive or end is not None else None
    j = int(np.searchsorted(times, t, side="right")) - 1
    if times[j] == t:
        return values[j]
    a, b = values[j], values[j + 1]
    if a is None or b is None or not (math.isfinite(a) and math.isfinite(b)):
        return None
    return float(a + (b - a) * (t - times[j]) / (times[j + 1] - times[j]))


def crossings(periods: Series, v: float) -> frozenset[float]:
    """Where the linear value meets v strictly between two instants: inverse interpolation."""
    found = set()
    for times, values in periods:
        for t0, t1, a, b in zip(times, times[1:], values, values[1:]):
            if a is None or b is None or not (math.isfinite(a) and math.isfinite(b)) or not min(a, b) < v < max(a, b):
                continue
            xs, ts = ([a, b], [t0, t1]) if a < b else ([b, a], [t1, t0])
            found.add(float(np.interp(v, xs, ts)))
    return frozenset(found)


def linear_reference(periods: Series, alive: bool, op: str, v: float, end: float | None = None) -> list[Interval]:
    cross = crossings(periods, v)
    breaks = [*(float(t) for times, _ in periods for t in times), *cross, *([end] if end is not None else [])]
    return sweep(breaks, lambda t: linear_value(periods, alive, t, end), op, v, cross)


def assert_periods(got: list[tgsis.Period], expected: list[Interval], what: str) -> None:
    assert len(got) == len(expected), f"{what}: got {[str(p) for p in got]}, expected {expected}"
    for p, (lower, lower_closed, upper, upper_closed) in zip(got, expected):
        assert p.start == pytest.approx(lower, abs=1e-9) and p.end == pytest.approx(upper, abs=1e-9), (what, str(p))
        assert (p.start_closed, p.end_closed) == (lower_closed, upper_closed), (what, str(p), expected)


def assert_samples(
    got: list[tgsis.Period],
    value_at: Callable[[float], Value],
    op: str,
    v: float,
    times: list[float],
    cross: frozenset[float],
    what: str,
) -> None:
    """Point by point: t lies in a period exactly when the condition holds at t (away from crossings)."""
    for t in times:
        if any(abs(t - c) < 1e-7 for c in cross):
            continue
        assert any(t in p for p in got) == holds(value_at(t), op, v), (what, t, [str(p) for p in got])


def sample_times(rng: np.random.Generator, instants: Sequence[float], count: int = 200) -> list[float]:
    lo, hi = min(instants), max(instants)
    return sorted({*rng.uniform(lo - 1, hi + 1, count).tolist(), *map(float, instants), lo - 5, hi + 5})


# --------------------------------------------------------------------------- fixtures and data


@pytest.fixture
def stepped(tx: Conn) -> tgsis.FeatureClass:
    return tgsis.create_feature_class(
        tx,
        "stepped_horizons",
        "SURFACE",
        time_model="INSTANTS",
        feature_properties=[("label", "text")],
        cell_properties=[("porosity", "double precision")],
        instant_properties=[("throw", "double precision"), ("note", "text"), ("rank", "integer")],
    )


@pytest.fixture
def moving(tx: Conn) -> tgsis.FeatureClass:
    return tgsis.create_feature_class(
        tx,
        "moving_faults",
        "SURFACE",
        time_model="EVOLVING",
        time_unit="Ma",
        cell_properties=[("porosity", "double precision")],
        instant_properties=[("throw", "double precision"), ("note_code", "integer")],
    )


def with_unknowns(
    tx: Conn, table: str, fid: int, keys: Sequence[tuple[float, ...]], values: list[Value], rng: np.random.Generator
) -> list[Value]:
    """Set a NULL and a NaN at random samples of a feature's per-instant throw; return the values as stored."""
    columns = ["_times"] if len(keys[0]) == 1 else ["_timem", "_timet"]
    values = list(values)
    for position, special in zip(rng.choice(len(keys), 2, replace=False).tolist(), [None, math.nan]):
        where = " AND ".join(f"{c} = %s" for c in columns)
        tx.execute(f"UPDATE {table} SET throw = %s WHERE _geoid = %s AND {where}", (special, fid, *keys[position]))
        values[position] = special
    return values


VALUES = [-1.0, 0.0, 0.5, 1.0, 2.0, 2.5, INF]

# --------------------------------------------------------------------------- model 2


@pytest.mark.parametrize("alive", [False, True])
@pytest.mark.parametrize("unknowns", [False, True])
def test_model2_periods_equal_reference(tx: Conn, stepped: tgsis.FeatureClass, alive: bool, unknowns: bool) -> None:
    rng = np.random.default_rng(11 + 2 * alive + unknowns)
    times = [-3.0, -1.0, 0.0, 0.5, 2.0, 4.0, 7.0]
    data = series(rng, times, alive=alive, with_properties=True, levels=3)
    fid = tgsis.insert_feature(tx, stepped, data)
    values: list[Value] = data.properties["throw"].tolist()
    if unknowns:
        values = with_unknowns(tx, "stepped_horizons_pros", fid, [(t,) for t in times], values, rng)
    checked = 0
    for convention in ("left", "right"):
        for op in OPS:
            for v in VALUES:
                what = f"{convention} {op} {v} alive={alive}"
                got = tgsis.property_periods(tx, stepped, fid, "throw", op, v, convention=convention)
                assert_periods(got, step_reference(times, values, alive, convention, op, v), what)
                assert_samples(
                    got,
                    lambda t: step_value(times, values, alive, convention, t),
                    op,
                    v,
                    sample_times(rng, times),
                    frozenset(),
                    what,
                )
                checked += len(got)
    assert checked > 50


def test_model2_bounds_by_hand(tx: Conn, stepped: tgsis.FeatureClass) -> None:
    surfaces = series(np.random.default_rng(0), [0.0, 1.0, 3.0], with_properties=True).surfaces
    dead = tgsis.insert_feature(
        tx, stepped, tgsis.SurfaceSeries([0.0, 1.0, 3.0], surfaces, properties={"throw": [1.0, 5.0, 2.0]})
    )
    alive = tgsis.insert_feature(
        tx, stepped, tgsis.SurfaceSeries([0.0, 1.0, 3.0], surfaces, alive=True, properties={"throw": [1.0, 5.0, 2.0]})
    )

    def periods(fid: int, op: str, v: float, convention: str) -> list[str]:
        rows = tx.execute(
            "SELECT period::text FROM tgsis.property_periods('stepped_horizons', %s, 'throw', %s, %s, %s)",
            (fid, op, v, convention),
        ).fetchall()
        return [r[0] for r in rows]

    assert periods(dead, ">", 3, "left") == ["[1,3)"]
    assert periods(dead, ">", 3, "right") == ["(0,1]"]
    assert periods(dead, "<", 3, "left") == ["[0,1)", "[3,3]"]
    assert periods(alive, "<", 3, "left") == ["[0,1)", "[3,)"]
    assert periods(dead, "<", 3, "right") == ["[0,0]", "(1,3]"]
    assert periods(alive, "<", 3, "right") == ["[0,0]", "(1,)"]
    assert periods(dead, "<>", 4, "left") == ["[0,3]"]
    assert periods(alive, ">=", -1, "right") == ["[0,)"]
    assert periods(dead, "=", 4, "left") == []
    # the feature-level "first time" is the lower bound of the first period
    row = tx.execute(
        "SELECT lower(period), lower_inc(period) FROM tgsis.property_periods('stepped_horizons', %s, "
        "'throw', '>', 3, 'right') LIMIT 1",
        (dead,),
    ).fetchone()
    assert row == (0.0, False)
    # a missing per-instant row is unknown
    tx.execute("DELETE FROM stepped_horizons_pros WHERE _geoid = %s AND _times = 1", (alive,))
    assert periods(alive, ">", 3, "left") == []
    assert periods(alive, "<>", 4, "left") == ["[0,1)", "[3,)"]
    # an integer column works the same
    tx.execute("UPDATE stepped_horizons_pros SET rank = throw WHERE _geoid = %s", (dead,))
    assert [str(p) for p in tgsis.property_periods(tx, "stepped_horizons", dead, "rank", ">", 3)] == ["[1.0, 3.0)"]


@pytest.mark.parametrize("alive", [False, True])
def test_model2_first_times_equal_reference(tx: Conn, stepped: tgsis.FeatureClass, alive: bool) -> None:
    rng = np.random.default_rng(21 + alive)
    times = [-2.0, 0.0, 1.5, 3.0]
    data = series(rng, times, alive=alive, with_properties=True, levels=3)
    fid = tgsis.insert_feature(tx, stepped, data)
    # a NaN cell value is unknown
    tx.execute(
        "UPDATE stepped_horizons_cellpros SET porosity = 'NaN' WHERE _geoid = %s AND _times = 0 AND _idx = 4", (fid,)
    )
    porosity = [s.vertex_properties["porosity"].astype(float).copy() for s in data.surfaces]
    porosity[1][4] = math.nan
    n = max(len(p) for p in porosity)
    for convention in ("left", "right"):
        for op in OPS:
            for v in VALUES[:-1]:
                idx, first = tgsis.first_times(tx, stepped, fid, "porosity", op, v, convention=convention)
                expected: dict[int, float] = {}
                for cell in range(n):
                    values: list[Value] = [float(p[cell]) if cell < len(p) else None for p in porosity]
                    runs = step_reference(times, values, alive, convention, op, v)
                    if runs:
                        expected[cell] = runs[0][0]
                assert idx.tolist() == sorted(expected), (convention, op, v)
                assert first.tolist() == [expected[i] for i in sorted(expected)], (convention, op, v)


# --------------------------------------------------------------------------- model 3


def evolving_series(surface: EvolvingSurface, name: str) -> Series:
    return [(p.times, [float(x) for x in p.properties[name]]) for p in surface.periods]


@pytest.mark.parametrize("alive", [False, True])
@pytest.mark.parametrize("unknowns", [False, True])
def test_model3_periods_equal_reference(tx: Conn, moving: tgsis.FeatureClass, alive: bool, unknowns: bool) -> None:
    rng = np.random.default_rng(31 + 2 * alive + unknowns)
    surface = evolving(rng, [-10.0, -6.5, -2.0], instants_per_period=4, alive=alive, with_properties=True, levels=3)
    fid = tgsis.insert_feature(tx, moving, surface)
    periods = evolving_series(surface, "throw")
    if unknowns:
        keys = [(p.start, float(t)) for p in surface.periods for t in p.times]
        flat = with_unknowns(tx, "moving_faults_pros", fid, keys, [x for _, vs in periods for x in vs], rng)
        sizes = np.cumsum([0, *(len(p.times) for p in surface.periods)])
        periods = [(times, flat[a:b]) for (times, _), a, b in zip(periods, sizes, sizes[1:])]
    instants = surface.geometry_instants.tolist()
    checked, kinds = 0, set()
    for op in OPS:
        for v in VALUES:
            what = f"{op} {v} alive={alive}"
            got = tgsis.property_periods(tx, moving, fid, "throw", op, v)
            assert_periods(got, linear_reference(periods, alive, op, v), what)
            assert_samples(
                got,
                lambda t: linear_value(periods, alive, t),
                op,
                v,
                sample_times(rng, instants),
                crossings(periods, v),
                what,
            )
            # the step convention does not apply to model 3
            assert tgsis.property_periods(tx, moving, fid, "throw", op, v, convention="right") == got
            checked += len(got)
            kinds |= {(p.start_closed, p.end_closed) for p in got}
    assert checked > 30 and len(kinds) >= 3  # open and closed bounds both occur


def test_model3_topology_change_and_crossings_by_hand(tx: Conn, moving: tgsis.FeatureClass) -> None:
    vertices, triangles = grid(3)
    positions = np.stack([vertices, vertices])
    surface = EvolvingSurface(
        [
            TopologyPeriod(
                [0.0, 1.0],
                triangles,
                positions,
                properties={"throw": [0.0, 2.0], "note_code": [0, 0]},
                vertex_properties={"porosity": np.zeros((2, 9))},
            ),
            TopologyPeriod(
                [1.0, 2.0],
                triangles,
                positions,
                properties={"throw": [5.0, 5.0], "note_code": [0, 0]},
                vertex_properties={"porosity": np.zeros((2, 9))},
            ),
        ]
    )
    fid = tgsis.insert_feature(tx, moving, surface)

    def periods(op: str, v: float) -> list[str]:
        return [str(p) for p in tgsis.property_periods(tx, moving, fid, "throw", op, v)]

    # at t = 1 the new period applies (throw 5): the old period's 2 there is only a limit
    assert periods(">=", 2) == ["[1.0, 2.0]"]
    assert periods("=", 2) == []
    assert periods("<", 2) == ["[0.0, 1.0)"]
    assert periods("=", 5) == ["[1.0, 2.0]"]
    # a crossing: strict operators leave it out, the others keep it
    assert periods("<", 1) == ["[0.0, 0.5)"]
    assert periods("<=", 1) == ["[0.0, 0.5]"]
    assert periods(">", 1) == ["(0.5, 2.0]"]
    assert periods("=", 1) == ["[0.5, 0.5]"]
    assert periods("<>", 1) == ["[0.0, 0.5)", "(0.5, 2.0]"]
    tx.execute("UPDATE tgsis.geometry SET alive = true WHERE geoid = %s", (fid,))
    assert periods(">", 1) == ["(0.5, inf)"]
    assert tgsis.Period(0.5, math.inf, False, False) == tgsis.property_periods(tx, moving, fid, "throw", ">", 1)[0]
    row = tx.execute(
        "SELECT period::text FROM tgsis.property_periods('moving_faults', %s, 'throw', '>', 1)", (fid,)
    ).fetchone()
    assert row == ("(0.5,)",)


@pytest.mark.parametrize("alive", [False, True])
def test_model3_first_times_equal_reference(tx: Conn, moving: tgsis.FeatureClass, alive: bool) -> None:
    rng = np.random.default_rng(41 + alive)
    surface = evolving(
        rng, [-10.0, -6.5, -2.0], instants_per_period=4, side=3, alive=alive, with_properties=True, levels=3
    )
    fid = tgsis.insert_feature(tx, moving, surface)
    offsets = np.cumsum([0, *(p.n_nodes for p in surface.periods)])
    # node 2 of period 1 gets a NaN: unknown there and on the stretches next to it
    p1 = surface.periods[1]
    tx.execute(
        "UPDATE moving_faults_cellpros SET porosity = 'NaN' WHERE _geoid = %s AND _timem = %s AND _timet = %s "
        "AND _idx = %s",
        (fid, p1.start, float(p1.times[1]), int(offsets[1]) + 2),
    )
    node_values = [p.vertex_properties["porosity"].astype(float).copy() for p in surface.periods]
    node_values[1][1, 2] = math.nan
    for op in OPS:
        for v in VALUES[:-1]:
            idx, first = tgsis.first_times(tx, moving, fid, "porosity", op, v)
            expected: dict[int, float] = {}
            for i, p in enumerate(surface.periods):
                end = surface.periods[i + 1].start if i + 1 < len(surface.periods) else None
                for k in range(p.n_nodes):
                    runs = linear_reference([(p.times, node_values[i][:, k].tolist())], alive, op, v, end)
                    if runs:
                        expected[int(offsets[i]) + k] = runs[0][0]
            assert idx.tolist() == sorted(expected), (op, v)
            np.testing.assert_allclose(
                first, [expected[i] for i in sorted(expected)], rtol=0, atol=1e-9, err_msg=f"{op} {v}"
            )


def test_first_time_sql_rows(tx: Conn, moving: tgsis.FeatureClass) -> None:
    vertices, triangles = grid(3)
    porosity = np.zeros((3, 9))
    porosity[:, 0] = [0.0, 1.0, 3.0]  # reaches 2 at t = 1.5 (linear from 1 at t=1 to 3 at t=2)
    porosity[:, 1] = [2.0, 2.0, 2.0]  # is 2 from the start
    surface = EvolvingSurface(
        [TopologyPeriod([0.0, 1.0, 2.0], triangles, np.stack([vertices] * 3), vertex_properties={"porosity": porosity})]
    )
    fid = tgsis.insert_feature(tx, moving, surface)
    rows = tx.execute(
        "SELECT idx, t FROM tgsis.first_time('moving_faults', %s, 'porosity', '>=', 2)", (fid,)
    ).fetchall()
    assert rows == [(0, 1.5), (1, 0.0)]
    rows = tx.execute("SELECT idx, t FROM tgsis.first_time('moving_faults', %s, 'porosity', '>', 2)", (fid,)).fetchall()
    assert rows == [(0, 1.5)]  # the infimum: > 2 holds right after 1.5
    # a missing sample is unknown, and so are the stretches next to it: node 0 is 3 at t = 2, nothing known before
    tx.execute("DELETE FROM moving_faults_cellpros WHERE _geoid = %s AND _timet = 1 AND _idx = 0", (fid,))
    rows = tx.execute(
        "SELECT idx, t FROM tgsis.first_time('moving_faults', %s, 'porosity', '>=', 2)", (fid,)
    ).fetchall()
    assert rows == [(0, 2.0), (1, 0.0)]
    idx, first = tgsis.first_times(tx, moving, fid, "porosity", ">", 10)
    assert idx.dtype == np.int64 and first.dtype == np.float64 and idx.shape == first.shape == (0,)


def test_questions_read_the_session_version(tx: Conn, moving: tgsis.FeatureClass) -> None:
    surface = evolving(np.random.default_rng(8), [0.0, 2.0], with_properties=True, levels=3)
    fid = tgsis.insert_feature(tx, moving, surface)
    before = tgsis.property_periods(tx, moving, fid, "throw", ">=", 1)
    assert before != [tgsis.Period(0.0, 3.0, True, True)]
    tgsis.enable_feature_versioning(tx)
    assert tgsis.property_periods(tx, moving, fid, "throw", ">=", 1) == before
    tgsis.create_version(tx, "raised")
    tgsis.goto_version(tx, "raised")
    tx.execute("UPDATE moving_faults_pros SET throw = 5 WHERE _geoid = %s", (fid,))
    assert tgsis.property_periods(tx, moving, fid, "throw", ">=", 1) == [tgsis.Period(0.0, 3.0, True, True)]
    tgsis.goto_version(tx, "DEFAULT")
    assert tgsis.property_periods(tx, moving, fid, "throw", ">=", 1) == before


# --------------------------------------------------------------------------- bad input


def test_bad_input_raises_and_changes_nothing(
    tx: Conn, stepped: tgsis.FeatureClass, moving: tgsis.FeatureClass
) -> None:
    rng = np.random.default_rng(5)
    fid = tgsis.insert_feature(tx, stepped, series(rng, [0.0, 1.0], with_properties=True))
    other = tgsis.insert_feature(tx, moving, evolving(rng, [0.0], with_properties=True))
    tgsis.create_feature_class(tx, "flat_horizons", "SURFACE", cell_properties=[("porosity", "float8")])
    state = (
        "SELECT (SELECT count(*) FROM stepped_horizons_pros), (SELECT sum(throw) FROM stepped_horizons_pros), "
        "(SELECT count(*) FROM tgsis.geometry), (SELECT count(*) FROM tgsis.catalog)"
    )
    before = tx.execute(state).fetchone()
    cases: list[tuple[type[tgsis.Error], str, Callable[[], object]]] = [
        (tgsis.NotFoundError, "nope", lambda: tgsis.property_periods(tx, "nope", fid, "throw", ">", 1)),
        (tgsis.NotFoundError, "not a feature", lambda: tgsis.property_periods(tx, stepped, other, "throw", ">", 1)),
        (tgsis.InvalidPropertyError, "depth", lambda: tgsis.property_periods(tx, stepped, fid, "depth", ">", 1)),
        (tgsis.InvalidPropertyError, "note", lambda: tgsis.property_periods(tx, stepped, fid, "note", ">", 1)),
        (tgsis.InvalidPropertyError, "porosity", lambda: tgsis.property_periods(tx, stepped, fid, "porosity", ">", 1)),
        (tgsis.InvalidPropertyError, "throw", lambda: tgsis.first_times(tx, stepped, fid, "throw", ">", 1)),
        (tgsis.InvalidInputError, "=>", lambda: tgsis.property_periods(tx, stepped, fid, "throw", "=>", 1)),
        (tgsis.InvalidInputError, "NaN", lambda: tgsis.property_periods(tx, stepped, fid, "throw", ">", math.nan)),
        (tgsis.InvalidInputError, "NaN", lambda: tgsis.first_times(tx, stepped, fid, "porosity", ">", math.nan)),
        (tgsis.InvalidInputError, "static", lambda: tgsis.first_times(tx, "flat_horizons", fid, "porosity", ">", 1)),
        (
            tgsis.InvalidInputError,
            "convention",
            lambda: tgsis.property_periods(tx, stepped, fid, "throw", ">", 1, convention="middle"),  # type: ignore[arg-type]  # the bad value
        ),
    ]
    for error, match, call in cases:
        with pytest.raises(error, match=match) as raised:
            call()
        assert type(raised.value) is error, (match, raised.value)
    assert tx.execute(state).fetchone() == before
    # the SQL functions raise our SQLSTATEs, with a hint where one helps
    for query, sqlstate, hint in [
        ("SELECT * FROM tgsis.property_periods('stepped_horizons', %s, 'porosity', '>', 1)", "TG103", "first_time"),
        ("SELECT * FROM tgsis.first_time('stepped_horizons', %s, 'note', '<', 1)", "TG103", "property_periods"),
        ("SELECT * FROM tgsis.property_periods('stepped_horizons', %s, 'note', '<', 1)", "TG103", "numeric"),
        ("SELECT * FROM tgsis.property_periods('stepped_horizons', %s, 'throw', '~', 1)", "TG100", "value op v"),
        ("SELECT * FROM tgsis.property_periods('stepped_horizons', %s, 'throw', '<', NULL)", "TG100", "Infinity"),
        ("SELECT * FROM tgsis.first_time('stepped_horizons', %s, 'porosity', '<', 1, 'up')", "TG100", None),
        ("SELECT * FROM tgsis.first_time('nope', %s, 'porosity', '<', 1)", "TG200", "classname"),
    ]:
        with pytest.raises(psycopg.Error) as db_error, tx.transaction():
            tx.execute(query, (fid,))
        assert db_error.value.sqlstate == sqlstate, query
        assert hint is None or hint in (db_error.value.diag.message_hint or ""), (
            query,
            db_error.value.diag.message_hint,
        )
    assert tx.execute(state).fetchone() == before


def test_period_membership(tx: Conn, stepped: tgsis.FeatureClass) -> None:
    data = series(np.random.default_rng(6), [0.0, 1.0], with_properties=True)
    fid = tgsis.insert_feature(tx, stepped, data)
    assert tgsis.property_periods(tx, stepped, fid, "throw", "<>", -1) == [tgsis.Period(0.0, 1.0, True, True)]
    with pytest.raises(tgsis.InvalidInputError, match="not one of"):
        tgsis.property_periods(tx, stepped, fid, "throw", "!=", -1)  # SQL's other spelling is not taken
    half_open = tgsis.Period(1.0, 2.0, True, False)
    assert 1.0 in half_open and 1.5 in half_open and 2.0 not in half_open and math.nan not in half_open
    assert str(half_open) == "[1.0, 2.0)" and 5.0 in tgsis.Period(1.0, math.inf, False, False)
