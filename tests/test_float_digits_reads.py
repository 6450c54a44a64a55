"""Instants and float values read by the Python client are exact whatever the session's ``extra_float_digits``.

Any user may run ``SET extra_float_digits = 0`` (or have it from ``PGOPTIONS``,
``ALTER ROLE ... SET``, ``ALTER DATABASE ... SET``): below 1, PostgreSQL prints a
float8 with 15 significant digits (less for a negative setting), so a value read
as text is another number. An instant read that way is then looked up with ``=``
(and missed: a feature's per-instant properties came back as NaN), used as the
key of a G-map period (its rows missed, or its points mixed with a rounded
weight), or handed to the user (``instants``, ``lifespan``, ``list_features``),
whose ``get_at`` at such an instant then gives the instant before it. The
reads go in binary (float8 bits); the SQL functions that print floats pin the
setting themselves (their own tests: test_sql_merge_*, test_canonical_keys,
test_model2_chunks). Each test compares the answers under ``extra_float_digits``
0 and -15 with the values written, bit for bit.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import psycopg
import pytest

import tgsis
from tests.merge_data import curved_surface
from tests.temporal_data import evolving, grid, series
from tgsis import gmaps
from tgsis.db import gmaps as G
from tgsis.db.inspect import feature_property_values, list_features
from tgsis.temporal import EvolvingSurface, TopologyPeriod

Conn = psycopg.Connection[Any]

#: instants whose 15-digit text is another number (0.1 + 0.2, a third, 2.5e15 + 0.5), and two whose text is exact
TIMES = [1e-300, 0.1, 0.1 + 0.2, 1 / 3, 2.5e15 + 0.5]
#: per-instant values of many digits
THROWS = [1 / 3, 2 / 3, 1 / 7, np.pi, 2.5e15 + 0.5]
DIGITS = [0, -15]


def _bits(values: Any) -> list[int]:
    return [int(v) for v in np.asarray(values, dtype=np.float64).ravel().view(np.int64)]


def _low_digits(conn: Conn, digits: int) -> None:
    conn.execute(f"SET extra_float_digits = {int(digits)}")
    conn.commit()
    assert conn.execute("SELECT (1/3::float8)::text").fetchone() != ("0.3333333333333333",)  # the setting rounds


@pytest.fixture
def stepped(conn: Conn) -> int:
    """A model-2 feature at TIMES, with a float8 feature property and a per-instant one (THROWS)."""
    fc = tgsis.create_feature_class(
        conn,
        "stepped",
        "SURFACE",
        time_model="INSTANTS",
        feature_properties={"depth": "float8"},
        cell_properties=[("porosity", "real")],
        instant_properties=[("throw", "double precision")],
    )
    sent = series(np.random.default_rng(40), TIMES, with_properties=True)
    sent = type(sent)(sent.times, sent.surfaces, properties={"throw": np.array(THROWS)}, name=sent.name)
    geoid = tgsis.insert_feature(conn, fc, sent, {"depth": 1 / 3})
    conn.commit()
    return geoid


@pytest.mark.parametrize("digits", DIGITS)
def test_surfaces_at_instants_read_exactly(conn: Conn, stepped: int, digits: int) -> None:
    before = [tgsis.get_at(conn, stepped, t) for t in TIMES]
    _low_digits(conn, digits)
    back = tgsis.fetch_series(conn, "stepped", stepped)
    assert _bits(back.times) == _bits(TIMES)
    # the per-instant values are found by their instant, and are the values written
    assert _bits(back.properties["throw"]) == _bits(THROWS)
    assert _bits([t for t, _ in tgsis.instants(conn, stepped)]) == _bits(TIMES)
    span = tgsis.lifespan(conn, stepped)
    assert span is not None and _bits(span[:2]) == _bits([TIMES[0], TIMES[-1]])
    # the instants the client gives back take the user to their own surface, not the one before
    for (t, _), surface in zip(tgsis.instants(conn, stepped), before, strict=True):
        got = tgsis.get_at(conn, stepped, t)
        assert got is not None and surface is not None
        assert _bits(got.vertices) == _bits(surface.vertices), t
    # the question answers (an instant bounds the period where throw > 1) and the listing
    periods = tgsis.property_periods(conn, "stepped", stepped, "throw", ">", 1.0)
    assert [_bits([p.start, p.end]) for p in periods] == [_bits([TIMES[3], TIMES[-1]])]  # not alive after it
    by_class = tgsis.class_property_periods(conn, "stepped", "throw", ">", 1.0)
    assert _bits([by_class[stepped][0].start]) == _bits([TIMES[3]])
    (row,) = list_features(conn, tgsis.get_feature_class(conn, "stepped"))
    assert _bits([row.first, row.last]) == _bits([TIMES[0], TIMES[-1]])
    assert _bits([row.properties["depth"]]) == _bits([1 / 3])
    assert _bits([feature_property_values(conn, tgsis.get_feature_class(conn, "stepped"), stepped)["depth"]]) == _bits(
        [1 / 3]
    )


@pytest.mark.parametrize("digits", DIGITS)
def test_evolving_surfaces_read_and_append_exactly(conn: Conn, digits: int) -> None:
    fc = tgsis.create_feature_class(
        conn,
        "moving",
        "SURFACE",
        time_model="EVOLVING",
        cell_properties=[("porosity", "real")],
        instant_properties=[("throw", "double precision"), ("note_code", "integer")],
    )
    sent = evolving(np.random.default_rng(41), [0.1, 1 / 3], with_properties=True)
    geoid = tgsis.insert_feature(conn, fc, sent)
    conn.commit()
    written = tgsis.fetch_evolving(conn, fc, geoid)
    _low_digits(conn, digits)
    back = tgsis.fetch_evolving(conn, fc, geoid)
    for got, want in zip(back.periods, written.periods, strict=True):
        assert _bits(got.times) == _bits(want.times)
        assert _bits(got.properties["throw"]) == _bits(want.properties["throw"])
    last = written.periods[-1]
    end = float(last.times[-1])  # 1/3 + 1: its 15-digit text is another number
    # a period appended at the last instant, as the user knows it, is accepted (its text was refused)
    tgsis.append_period(
        conn,
        fc,
        geoid,
        TopologyPeriod(
            [end, end + 1 / 3],
            last.triangles,
            np.stack([last.positions[-1], last.positions[-1] + 1 / 3]),
            vertex_properties={"porosity": np.full((2, len(last.positions[-1])), 0.25)},
        ),
    )
    conn.commit()
    assert _bits([t for t, _ in tgsis.instants(conn, geoid)][-2:]) == _bits([end, end + 1 / 3])


@pytest.mark.parametrize("digits", DIGITS)
def test_gmap_snapshot_reads_its_period_exactly(conn: Conn, digits: int) -> None:
    fc = tgsis.create_feature_class(
        conn, "blocks", "GMAP", time_model="GMAP", cell_level=2, cell_properties={"porosity": "float8"}
    )
    square = gmaps.GMap.from_triangles([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], [[0, 1, 2], [0, 2, 3]])
    period = gmaps.GMapPeriod(
        [1 / 3, 0.1 + 0.7],
        square,
        np.stack([square.points, square.points + [0, 0, 1 / 3]]),
        level=2,
        cell_values={"porosity": [[1 / 3, 0.2], [0.3, 2 / 3]]},
    )
    evolving_map = gmaps.EvolvingGMap([period], alive=False, name="rising")
    geoid = tgsis.insert_feature(conn, fc, evolving_map)
    conn.commit()
    _low_digits(conn, digits)
    for t in (1 / 3, 0.5, 0.6, 0.1 + 0.7):
        expected = evolving_map.at(t)
        got = G.gmap_at(conn, geoid, t)
        assert expected is not None and got is not None and got.same_as(expected), t
    assert G.gmap_at(conn, geoid, 0.1 + 0.7 + 1e-12) is None


@pytest.mark.parametrize("digits", DIGITS)
def test_static_feature_values_and_colour_read_exactly(conn: Conn, digits: int) -> None:
    """The same reads of a static feature: its float properties and colour (``real`` columns) as written."""
    tgsis.create_feature_class(conn, "faults", "SURFACE", feature_properties={"depth": "float8"})
    surface = curved_surface()
    colour = [float(np.float32(1 / 3)), 0.5, float(np.float32(0.1))]  # float32-exact: kept in the real columns only
    surface.metadata["color"] = colour
    geoid = tgsis.insert_feature(conn, "faults", surface, {"depth": 1 / 3}, drop_extra_properties=True)
    conn.commit()
    _low_digits(conn, digits)
    back = tgsis.fetch_feature(conn, "faults", geoid)
    assert _bits([back.properties["depth"]]) == _bits([1 / 3])
    assert back.mesh is not None
    assert [float(np.float32(c)) for c in back.mesh.metadata["color"]] == colour
    checked_out = tgsis.checkout(conn, geoid, "faults")
    assert _bits([checked_out.properties["depth"]]) == _bits([1 / 3])
    conn.rollback()


@pytest.mark.parametrize("digits", DIGITS)
def test_conflict_discards_counts_edits_whatever_the_sessions_digits(conn: Conn, digits: int) -> None:
    """``tgsis.conflict_discards`` compares row versions as jsonb, whose floats are the float8 text: a session's low
    setting hid an edit in the 16th or 17th digit (a solution then said it lost nothing). Model 1; the same
    comparison (and model 2's row key, which holds the instant) for every model."""
    from tests.test_resolve_discards import dome

    tgsis.create_feature_class(
        conn, "domes", "SURFACE", feature_properties={"note": "text"}, cell_properties={"porosity": "float8"}
    )
    tgsis.enable_feature_versioning(conn)
    a = tgsis.insert_feature(conn, "domes", dome())
    tgsis.create_version(conn, "edit")
    conn.commit()
    with tgsis.in_version(conn, "edit"):
        conn.execute("UPDATE tgsis.vrtx SET z = z + 1 WHERE geoid = %s AND vrtxid = 0", (a,))
        # 7.5 -> 7.500000000000001 and 0.05 -> 0.05000000000000001: other numbers, one 15-digit text
        conn.execute("UPDATE tgsis.vrtx SET z = %s WHERE geoid = %s AND vrtxid = 1", (np.nextafter(7.5, 8.0), a))
        conn.execute(
            "UPDATE domes_cellpros SET porosity = %s WHERE _geoid = %s AND _idx = 5", (np.nextafter(0.05, 1.0), a)
        )
        conn.execute("UPDATE domes SET note = 'mine' WHERE _geoid = %s", (a,))
        conn.commit()
    conn.execute("UPDATE tgsis.vrtx SET z = z - 1 WHERE geoid = %s AND vrtxid = 20", (a,))
    conn.execute("UPDATE domes SET note = 'checked' WHERE _geoid = %s", (a,))
    conn.commit()
    assert [c.objectkey for c in tgsis.find_conflicts(conn, "edit")] == [str(a)]
    conn.commit()
    query = (
        "SELECT shortname, rows_added, rows_removed, rows_changed, values_changed FROM tgsis.conflict_discards('edit')"
        " WHERE solution = 'parent' ORDER BY shortname"
    )
    lost = [("public.domes", 0, 0, 1, 1), ("public.domes_cellpros", 0, 0, 1, 1), ("vrtx", 0, 0, 2, 2)]
    assert conn.execute(query).fetchall() == lost  # what the parent's solution loses of the version's edits
    _low_digits(conn, digits)
    assert conn.execute(query).fetchall() == lost
    assert sorted(
        (d.shortname, d.rows_changed) for d in tgsis.conflict_discards(conn, "edit") if d.solution == "parent"
    ) == [(t, changed) for t, _, _, changed, _ in lost]


@pytest.mark.parametrize("digits", DIGITS)
def test_a_region_solution_at_an_instant_of_no_short_text_holds(conn: Conn, digits: int) -> None:
    """The stored regions of a model-2 conflict are read back with their instant (``times``): read as text under a
    low setting, the instant was another number, the stored regions no longer matched the merge's, and the
    region's solution could not be recorded (or, recorded, was not found by the merge)."""
    from tests.merge_data import SIDE
    from tests.test_merge_instants import CHILD_SHIFT, NORTH, PARENT_SHIFT, _shape, move, shifted

    times = (1.0, 1 + 1 / 3, 3.0)  # 1.3333333333333333: its 15-digit text is another number
    tgsis.create_feature_class(conn, "horizons", "SURFACE", time_model="INSTANTS")
    tgsis.enable_feature_versioning(conn)
    cells = curved_surface().cells
    surfaces = [tgsis.Surface(_shape(i), cells) for i in range(len(times))]
    geoid = tgsis.insert_feature(conn, "horizons", tgsis.SurfaceSeries(np.asarray(times), surfaces))
    tgsis.create_version(conn, "e1")
    conn.commit()
    move(conn, "e1", geoid, times[1], NORTH, CHILD_SHIFT)
    move(conn, "DEFAULT", geoid, times[1], NORTH[:SIDE], PARENT_SHIFT)
    _low_digits(conn, digits)
    [conflict] = tgsis.find_conflicts(conn, "e1")
    assert [(r.region, r.times, r.conflict) for r in conflict.regions] == [(0, times[1], True)]
    conn.commit()
    tgsis.resolve_region(conn, "e1", geoid, 0, "child")
    conn.commit()
    [again] = tgsis.find_conflicts(conn, "e1")  # the recorded solution is the stored region's still
    assert [(r.region, r.solution) for r in again.regions] == [(0, "child")]
    conn.commit()
    tgsis.merge_version(conn, "e1")
    conn.commit()
    with tgsis.in_version(conn, "DEFAULT"):
        rows = conn.execute(
            "SELECT x, y, z FROM tgsis.times_vrtx WHERE geoid = %s AND times = %s ORDER BY vrtxid",
            (geoid, times[1]),
            binary=True,
        ).fetchall()
    assert np.asarray(rows).tobytes() == shifted(_shape(1), NORTH, CHILD_SHIFT).tobytes()


@pytest.mark.parametrize("at", [1, 2])
def test_an_unsolved_region_at_an_instant_from_1e15_on_is_named_as_python_names_it(conn: Conn, at: int) -> None:
    """The psql refusal names an unsolved region's geometry instant as Python's repr does. From 1e15 on the float8
    text is exponential where repr is positional: the name went through a float8::numeric cast, which keeps 15
    digits (2500000000000002.0 named 2500000000000000.0), or stayed exponential (2.5000000000000005e+15)."""
    from tests.test_merge_instants import _shape
    from tests.test_sql_merge_period_regions_hostile import _conflict
    from tests.test_sql_merge_write import both_merges

    tgsis.create_feature_class(conn, "far", "SURFACE", time_model="EVOLVING")
    tgsis.enable_feature_versioning(conn)
    times = (2.5e15, 2.5e15 + 0.5, 2.5e15 + 2)
    period = TopologyPeriod(np.asarray(times), curved_surface().cells, np.stack([_shape(i) for i in range(3)]))
    geoid = int(tgsis.insert_feature(conn, "far", tgsis.EvolvingSurface([period])))
    tgsis.create_version(conn, "e1")
    conn.commit()
    _conflict(conn, geoid, times[0], times[at])
    _low_digits(conn, 0)
    theirs, mine = both_merges(conn, "e1")
    assert theirs[:2] == mine[:2] == ("refused", "TG302"), (theirs, mine)
    named = f"region 0 at geometry instant {times[at]!r} of the period starting at {times[0]!r} unsolved"
    assert named in theirs[2], theirs  # the Python merge's name
    assert named in mine[2], mine  # psql's


@pytest.mark.parametrize("digits", DIGITS)
def test_the_instant_and_period_writers_name_times_exactly(conn: Conn, stepped: int, digits: int) -> None:
    """``add_instant``'s, ``delete_instant``'s and ``delete_period``'s messages name an instant as it is (0.1 + 0.2
    is 0.30000000000000004, not 0.3, which is another instant), whatever the session prints; nothing changed."""
    fc = tgsis.create_feature_class(conn, "moving", "SURFACE", time_model="EVOLVING")
    starts = [0.1, 0.1 + 0.2, 1.0]
    moving = tgsis.insert_feature(conn, fc, evolving(np.random.default_rng(42), starts))
    one = series(np.random.default_rng(43), [0.1 + 0.2], with_properties=True)
    one = type(one)(one.times, one.surfaces, properties={"throw": np.array([1 / 3])}, name=one.name)
    single = tgsis.insert_feature(conn, "stepped", one, {"depth": 1.0})
    conn.commit()
    _low_digits(conn, digits)

    def refusal(call: str, *params: Any) -> psycopg.Error:
        with pytest.raises(psycopg.Error) as refused:
            conn.execute(call, params)
        conn.rollback()
        return refused.value

    exact = "0.30000000000000004"
    added = refusal("SELECT tgsis.add_instant(%s, %s)", stepped, 0.1 + 0.2)
    assert added.sqlstate == "TG201" and f"instant {exact} already" in str(added), added
    only = refusal("SELECT tgsis.delete_instant(%s, %s)", single, 0.1 + 0.2)
    assert only.sqlstate == "TG202" and f"instant {exact} is the only one" in str(only), only
    middle = refusal("SELECT tgsis.delete_period(%s, %s)", moving, 0.1 + 0.2)
    assert middle.sqlstate == "TG202" and f"period from {exact} " in str(middle), middle
    assert f"0.1, {exact}, 1" in (middle.diag.message_detail or ""), middle.diag.message_detail
    # nothing changed, and the session's own setting is as it was
    assert conn.execute("SELECT count(*) FROM tgsis.timem WHERE geoid = %s", (moving,)).fetchone() == (3,)
    assert conn.execute("SHOW extra_float_digits").fetchone() == (str(digits),)


def _two_periods(first: float, change: float, end: float) -> EvolvingSurface:
    """A dome (curved, 1000 m wide) in two topology periods [first, change] and [change, end]: the same nodes, the
    other diagonal of each grid cell after ``change``, and no jump there."""
    vertices, triangles = grid(5)
    vertices = vertices * 1000.0
    vertices[:, 2] = 300.0 * np.exp(-((vertices[:, 0] - 500) ** 2 + (vertices[:, 1] - 500) ** 2) / 2e5)
    top = vertices * [1, 1, 2]
    a, b, d = triangles[:16].T
    flipped = np.concatenate([np.stack([a, b, triangles[16:, 2]], 1), np.stack([b, d, triangles[16:, 2]], 1)])
    return EvolvingSurface(
        [
            TopologyPeriod([first, change], triangles, np.stack([vertices, top])),
            TopologyPeriod([change, end], flipped, np.stack([top, top + [0, 0, 50]])),
        ]
    )


@pytest.mark.parametrize("digits", DIGITS)
def test_the_temporal_checks_name_times_exactly(conn: Conn, stepped: int, digits: int) -> None:
    """``check_temporal_geometry``'s examples, ``period_gaps``' places and ``check_period_continuity``'s refusal
    name instants and periods as they are (0.1 + 0.2 is 0.30000000000000004 and a third 0.3333333333333333; at 15
    digits they are other instants, which the user would then look up and miss), whatever the session prints."""
    third, exact_third, exact_sum = 1 / 3, "0.3333333333333333", "0.30000000000000004"
    # model 3: a period from 0.1 + 0.2 and one from a third, its first shape lifted 4 m by plain SQL (a jump)
    tgsis.create_feature_class(conn, "moving", "SURFACE", time_model="EVOLVING")
    moving = tgsis.insert_feature(conn, "moving", _two_periods(0.1 + 0.2, third, 2 / 3))
    conn.execute(
        "UPDATE tgsis.d4dvrtx SET z = z + 4 WHERE geoid = %s AND timem = %s AND timet = %s", (moving, third, third)
    )
    # model 2: a NaN written by plain SQL at the instant 0.1 + 0.2 of the fixture's feature
    conn.execute("UPDATE tgsis.times_vrtx SET x = 'NaN' WHERE geoid = %s AND times = %s", (stepped, 0.1 + 0.2))
    conn.commit()
    _low_digits(conn, digits)

    found = dict(
        (problem.split(":")[0], example)
        for problem, _, example in conn.execute("SELECT * FROM tgsis.check_temporal_geometry(%s)", (stepped,))
    )
    assert found == {"vertex with a NaN or infinite coordinate": f"instant {exact_sum}, vrtxid 0"}, found
    (jump,) = [
        example
        for problem, _, example in conn.execute("SELECT * FROM tgsis.check_temporal_geometry(%s)", (moving,))
        if problem.startswith("shape jumps")
    ]
    assert jump.startswith(f"period from {exact_third}: 4 apart at node "), jump
    assert jump.endswith((f" of the period from {exact_third}", f" of the period from {exact_sum}")), jump
    places = [place for (place,) in conn.execute("SELECT place FROM tgsis.period_gaps(%s)", (moving,))]
    assert len(places) == 1 and places[0].endswith((exact_third, exact_sum)), places
    with pytest.raises(psycopg.Error) as refused:
        conn.execute("SELECT tgsis.check_period_continuity(%s)", (moving,))
    assert refused.value.sqlstate == "TG204"
    message = str(refused.value)
    assert f"period from {exact_third} of geometry {moving} " in message, message
    assert f"the period from {exact_sum} ends" in message, message
    conn.rollback()
    assert conn.execute("SHOW extra_float_digits").fetchone() == (str(digits),)
