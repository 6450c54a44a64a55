"""Model 3: evolving surfaces stored, and their snapshot at t in SQL against an independent numpy computation."""

from __future__ import annotations

from typing import Any

import numpy as np
import psycopg
import pytest

import tgsis
from tests.temporal_data import evolving, grid
from tgsis.temporal import EvolvingSurface, TopologyPeriod

Conn = psycopg.Connection[Any]
STARTS = [-10.0, -6.5, -2.0]


def reference_at(surface: EvolvingSurface, t: float) -> tuple[np.ndarray, np.ndarray] | None:
    """The spec's rule written out with np.interp, independent of tgsis.temporal: (vertices, triangles) or None."""
    periods = surface.periods
    if t < periods[0].times[0]:
        return None
    chosen = [p for p in periods if p.times[0] <= t][-1]
    if t > chosen.times[-1]:
        if chosen is not periods[-1] or not surface.alive:
            return None
        return chosen.positions[-1], chosen.triangles
    xyz = np.stack(
        [[np.interp(t, chosen.times, chosen.positions[:, k, d]) for d in range(3)] for k in range(chosen.n_nodes)]
    )
    return xyz, chosen.triangles


@pytest.fixture
def faults(tx: Conn) -> tgsis.FeatureClass:
    return tgsis.create_feature_class(
        tx,
        "moving_faults",
        "SURFACE",
        time_model="EVOLVING",
        time_unit="Ma",
        feature_properties=[("fault_name", "text")],
        cell_properties=[("porosity", "double precision")],
        instant_properties=[("throw", "double precision"), ("note_code", "integer")],
    )


def sample_times(surface: EvolvingSurface, rng: np.random.Generator) -> list[float]:
    """Random times plus every geometry instant, topology changes, before the first and after the last."""
    return sorted(
        {
            *rng.uniform(surface.start - 1, surface.end + 1, 40).tolist(),
            *surface.geometry_instants.tolist(),
            surface.start - 5.0,
            surface.end + 5.0,
            float("inf"),
            float("-inf"),
        }
    )


@pytest.mark.parametrize("alive", [False, True])
def test_sql_snapshot_equals_numpy(tx: Conn, faults: tgsis.FeatureClass, alive: bool) -> None:
    rng = np.random.default_rng(7 + alive)
    surface = evolving(rng, STARTS, instants_per_period=4, alive=alive, with_properties=True)
    fid = tgsis.insert_feature(tx, faults, surface, {"fault_name": "F1"})
    checked = 0
    for t in sample_times(surface, rng):
        expected = reference_at(surface, t)
        got = tgsis.get_at(tx, fid, t)
        if expected is None:
            assert got is None, t
            continue
        assert got is not None, t
        np.testing.assert_allclose(got.vertices, expected[0], rtol=0, atol=1e-12, err_msg=f"t={t}")
        np.testing.assert_array_equal(got.triangles, expected[1])
        # the library's numpy snapshot does the same float operations as SQL: bitwise equal
        local = surface.at(t)
        assert local is not None
        np.testing.assert_array_equal(got.vertices, local.vertices)
        checked += 1
    assert checked > 30


def test_topology_change_takes_the_new_period(tx: Conn, faults: tgsis.FeatureClass) -> None:
    surface = evolving(np.random.default_rng(1), STARTS, with_properties=True)
    fid = tgsis.insert_feature(tx, faults, surface)
    for i, start in enumerate(STARTS):
        got = tgsis.get_at(tx, fid, start)
        assert got is not None
        np.testing.assert_array_equal(got.vertices, surface.periods[i].positions[0])
        assert got.n_cells == surface.periods[i].n_triangles
    just_before = tgsis.get_at(tx, fid, np.nextafter(STARTS[1], -np.inf))
    assert just_before is not None and just_before.n_vertices == surface.periods[0].n_nodes


def test_sql_rows_and_frame(tx: Conn, faults: tgsis.FeatureClass) -> None:
    surface = evolving(np.random.default_rng(2), STARTS, instants_per_period=2, with_properties=True)
    fid = tgsis.insert_feature(tx, faults, surface)
    p = surface.periods[1]
    t = (p.times[0] + p.times[1]) / 2
    frame = tx.execute("SELECT timem, t0, t1, w FROM tgsis.evolving_frame(%s, %s)", (fid, t)).fetchone()
    assert frame is not None and frame[:3] == (p.times[0], p.times[0], p.times[1])
    rows = tx.execute("SELECT vrtxid, x, y, z FROM tgsis.vertices_at(%s, %s) ORDER BY vrtxid", (fid, t)).fetchall()
    offset = surface.periods[0].n_nodes  # node ids run on through the periods
    assert [r[0] for r in rows] == list(range(offset, offset + p.n_nodes))
    triangles = tx.execute(
        "SELECT vrtxid1, vrtxid2, vrtxid3 FROM tgsis.triangles_at(%s, %s) ORDER BY trglid", (fid, t)
    ).fetchall()
    np.testing.assert_array_equal(np.array(triangles) - offset, p.triangles)
    geometry = tx.execute(
        "SELECT timemodel, nvrtx, ncell, alive FROM tgsis.geometry WHERE geoid = %s", (fid,)
    ).fetchone()
    assert geometry == ("EVOLVING", surface.n_nodes, surface.n_triangles, False)
    assert tgsis.instants(tx, fid) == [(float(x), bool(x in STARTS)) for x in surface.geometry_instants]


def test_stored_rows_and_properties(tx: Conn, faults: tgsis.FeatureClass) -> None:
    surface = evolving(np.random.default_rng(3), STARTS, with_properties=True)
    fid = tgsis.insert_feature(tx, faults, surface)
    counts = tx.execute(
        "SELECT (SELECT count(*) FROM tgsis.timem WHERE geoid = %(g)s), (SELECT count(*) FROM tgsis.timet WHERE geoid = %(g)s),"
        " (SELECT count(*) FROM tgsis.node WHERE geoid = %(g)s), (SELECT count(*) FROM tgsis.d4dvrtx WHERE geoid = %(g)s),"
        " (SELECT count(*) FROM moving_faults_cellpros WHERE _geoid = %(g)s),"
        " (SELECT count(*) FROM moving_faults_pros WHERE _geoid = %(g)s)",
        {"g": fid},
    ).fetchone()
    samples = sum(len(p.times) * p.n_nodes for p in surface.periods)
    assert counts == (
        3,
        sum(len(p.times) for p in surface.periods),
        surface.n_nodes,
        samples,
        samples,
        sum(len(p.times) for p in surface.periods),
    )
    p = surface.periods[2]
    rows = tx.execute(
        "SELECT _timet, throw, note_code FROM moving_faults_pros WHERE _geoid = %s AND _timem = %s ORDER BY _timet",
        (fid, p.start),
    ).fetchall()
    assert [r[0] for r in rows] == p.times.tolist()
    assert [r[1] for r in rows] == p.properties["throw"].tolist()
    porosity = tx.execute(
        "SELECT porosity FROM moving_faults_cellpros WHERE _geoid = %s AND _timem = %s AND _timet = %s ORDER BY _idx",
        (fid, p.start, p.times[1]),
    ).fetchall()
    np.testing.assert_array_equal([r[0] for r in porosity], p.vertex_properties["porosity"][1])


def test_surfaces_at_and_features_at(tx: Conn, faults: tgsis.FeatureClass) -> None:
    rng = np.random.default_rng(4)
    early = evolving(rng, [-10.0, -6.5], with_properties=True)  # exists -10 .. -5.5
    late = evolving(rng, [-4.0], alive=True, with_properties=True)  # exists from -4 on
    a, b = tgsis.insert_feature(tx, faults, early), tgsis.insert_feature(tx, faults, late)
    assert tgsis.features_at(tx, faults, -8.0) == [a]
    assert tgsis.features_at(tx, faults, -5.0) == []
    assert tgsis.features_at(tx, faults, 100.0) == [b]
    shapes = tgsis.surfaces_at(tx, faults, -7.0)
    assert list(shapes) == [a]
    local = early.at(-7.0)
    assert local is not None
    np.testing.assert_array_equal(shapes[a].vertices, local.vertices)
    np.testing.assert_array_equal(shapes[a].triangles, local.triangles)
    # the SQL form for psql users: one row per feature, arrays
    row = tx.execute("SELECT geoid, vertices, triangles FROM tgsis.surfaces_at('moving_faults', -7.0)").fetchone()
    assert row is not None and row[0] == a
    np.testing.assert_array_equal(np.array(row[1]), local.vertices)
    np.testing.assert_array_equal(np.array(row[2]), local.triangles)


def test_the_sql_surfaces_at_compiles_no_query(tx: Conn, faults: tgsis.FeatureClass) -> None:
    """Its query (vertices_at and triangles_at inlined per feature) is costed far above jit_above_cost: on a
    server with JIT (Debian's PostgreSQL 15) each call compiled it, 2.6 s for a 3-unit scene that runs in ms.
    The Python snapshot turns JIT off around the same query (tgsis.db._temporal_common); psql users too."""
    a = tgsis.insert_feature(tx, faults, evolving(np.random.default_rng(5), [-10.0], alive=True, with_properties=True))
    config = tx.execute("SELECT proconfig FROM pg_proc WHERE oid = 'tgsis.surfaces_at'::regproc").fetchone()
    assert config is not None and "jit=off" in (config[0] or [])
    plans: list[str] = []
    tx.add_notice_handler(lambda d: plans.append(d.message_primary or ""))
    for setting in ("LOAD 'auto_explain'", "SET auto_explain.log_min_duration = 0", "SET jit_above_cost = 0"):
        tx.execute(setting)
    tx.execute("SET auto_explain.log_nested_statements = on; SET auto_explain.log_level = notice")
    assert [r[0] for r in tx.execute("SELECT geoid FROM tgsis.surfaces_at('moving_faults', -7.0)")] == [a]
    inner = [p for p in plans if "tgsis.vertices_at" in p]
    assert inner and not [p for p in inner if "JIT:" in p]  # (JIT is on for the rest of the session)


def test_bad_input_changes_nothing(tx: Conn, faults: tgsis.FeatureClass) -> None:
    before = tx.execute("SELECT count(*) FROM tgsis.geometry").fetchone()
    vertices, triangles = grid(3)
    with pytest.raises(tgsis.InvalidPropertyError, match="porosity"):
        tgsis.insert_feature(tx, faults, EvolvingSurface([TopologyPeriod([0.0, 1.0], triangles, [vertices, vertices])]))
    with pytest.raises(tgsis.InvalidGeometryError, match="EVOLVING"):
        tgsis.insert_feature(tx, faults, tgsis.Surface(vertices, triangles))
    assert tx.execute("SELECT count(*) FROM tgsis.geometry").fetchone() == before
    with pytest.raises(tgsis.InvalidInputError, match="NaN"):
        tgsis.get_at(tx, 1, float("nan"))
    with pytest.raises(tgsis.NotFoundError):
        tgsis.get_at(tx, 987654, 0.0)
    with pytest.raises(psycopg.Error, match="NaN") as raised:
        tx.execute("SELECT * FROM tgsis.vertices_at(1, 'NaN')")
    assert raised.value.sqlstate == "TG100"  # the transaction is aborted now: keep this last


def test_numpy_model_refuses_bad_periods() -> None:
    vertices, triangles = grid(3)
    positions = np.stack([vertices, vertices])
    with pytest.raises(tgsis.InvalidInputError, match="strictly increasing"):
        TopologyPeriod([1.0, 1.0], triangles, positions)
    with pytest.raises(tgsis.InvalidGeometryError, match="shape"):
        TopologyPeriod([0.0, 1.0, 2.0], triangles, positions)
    with pytest.raises(tgsis.InvalidInputError, match="must end where period 1 starts"):
        EvolvingSurface(
            [TopologyPeriod([0.0, 1.0], triangles, positions), TopologyPeriod([2.0, 3.0], triangles, positions)]
        )
    with pytest.raises(tgsis.InvalidGeometryError):
        TopologyPeriod([0.0, 1.0], [[0, 1, 99]], positions)


def problems(tx: Conn, fid: int) -> set[str]:
    return {r[0] for r in tx.execute("SELECT problem FROM tgsis.check_geometry(%s)", (fid,)).fetchall()}


def test_check_geometry_finds_rows_edited_wrongly(tx: Conn, faults: tgsis.FeatureClass) -> None:
    surface = evolving(np.random.default_rng(9), STARTS, with_properties=True)
    fid = tgsis.insert_feature(tx, faults, surface)
    assert problems(tx, fid) == set()
    tx.execute("DELETE FROM tgsis.d4dvrtx WHERE geoid = %s AND nodeid = 3 AND timet = %s", (fid, STARTS[0]))
    assert problems(tx, fid) == {"node without a position at a geometry instant of its period"}
    tx.execute("DELETE FROM tgsis.timet WHERE geoid = %s AND timet = %s AND timem = %s", (fid, STARTS[1], STARTS[0]))
    tx.execute("UPDATE tgsis.d4dtrgl SET nodeid1 = 10000 WHERE geoid = %s AND trglid = 0", (fid,))
    tx.execute("UPDATE tgsis.d4dvrtx SET x = 'NaN' WHERE geoid = %s AND nodeid = 1", (fid,))
    tx.execute("UPDATE tgsis.geometry SET nvrtx = 1 WHERE geoid = %s", (fid,))
    assert problems(tx, fid) == {
        "node without a position at a geometry instant of its period",
        "topology period does not end where the next one starts",
        # period 0 now ends at an earlier shape, which the next period does not start in
        "shape jumps at a topology instant: the period's first shape lies farther than the tolerance from the last "
        "shape before it (tgsis.period_gaps)",
        "position of a node or at an instant its period does not have",
        "triangle refers to a missing node of its period",
        "node position with a NaN or infinite coordinate",
        "bounding box or counts out of date (run tgsis.refresh_geometry)",
    }


def test_fetch_evolving_round_trip(tx: Conn, faults: tgsis.FeatureClass) -> None:
    surface = evolving(np.random.default_rng(10), STARTS, instants_per_period=4, alive=True, with_properties=True)
    surface = EvolvingSurface(surface.periods, alive=True, name="F", color=(0.5, 0.25, 1.0))
    fid = tgsis.insert_feature(tx, faults, surface)
    back = tgsis.fetch_evolving(tx, faults, fid)
    assert (back.alive, back.name, back.color) == (True, "F", (0.5, 0.25, 1.0))
    assert len(back.periods) == len(surface.periods)
    for got, sent in zip(back.periods, surface.periods):
        np.testing.assert_array_equal(got.times, sent.times)
        np.testing.assert_array_equal(got.triangles, sent.triangles)
        np.testing.assert_array_equal(got.positions, sent.positions)
        np.testing.assert_array_equal(got.vertex_properties["porosity"], sent.vertex_properties["porosity"])
        np.testing.assert_array_equal(got.properties["throw"], sent.properties["throw"])
        np.testing.assert_array_equal(got.properties["note_code"], sent.properties["note_code"])
    with pytest.raises(tgsis.InvalidInputError, match="EVOLVING"):
        tgsis.fetch_series(tx, faults, fid)


@pytest.mark.parametrize("function", ["vertices_at", "triangles_at", "exists_at"])
def test_bad_convention_is_an_error_whatever_the_model_and_t(
    tx: Conn, faults: tgsis.FeatureClass, function: str
) -> None:
    fid = tgsis.insert_feature(tx, faults, evolving(np.random.default_rng(12), STARTS, with_properties=True))
    static = tgsis.create_feature_class(tx, "plain_faults", "SURFACE")
    vertices, triangles = grid(3)
    sid = tgsis.insert_feature(tx, static, tgsis.Surface(vertices, triangles))
    for geoid, t in ((fid, 0.0), (fid, -100.0), (sid, 0.0)):
        with pytest.raises(psycopg.Error, match="convention 'middle'") as raised, tx.transaction():
            tx.execute(f"SELECT * FROM tgsis.{function}(%s, %s, 'middle')", (geoid, t))
        assert raised.value.sqlstate == "TG100"


def test_a_constant_surface_and_a_chain_of_parts() -> None:
    """EvolvingSurface.constant and .chain: what per-interval interpolations and fixed surfaces are built from."""
    from tgsis.mesh import Surface

    base = Surface([[0, 0, 0], [1, 0, 0], [0, 1, 1]], [[0, 1, 2]], vertex_properties={"p": [1.0, 2.0, 3.0]}, name="b")
    still = EvolvingSurface.constant(base, 1.0, 4.0, alive=True)
    at = still.at(2.5)
    assert at is not None and np.array_equal(at.vertices, base.vertices) and still.alive and still.name == "b"
    assert np.array_equal(still.periods[0].vertex_properties["p"], [[1.0, 2.0, 3.0]] * 2)
    moved = base.vertices + [0, 0, 1]
    part1 = EvolvingSurface([TopologyPeriod([0.0, 1.0], base.cells, np.stack([base.vertices, moved]))], name="h")
    part2 = EvolvingSurface([TopologyPeriod([1.0, 2.0], base.cells, np.stack([moved, moved + 1]))], alive=True)
    whole = EvolvingSurface.chain([part1, part2])
    assert [p.start for p in whole.periods] == [0.0, 1.0] and whole.alive and whole.name == "h"
    mid = whole.at(1.5)
    assert mid is not None and np.allclose(mid.vertices, moved + 0.5)
    with pytest.raises(tgsis.InvalidInputError, match="part 0 ends at 1.0 but part 1 starts at 2.0"):
        EvolvingSurface.chain(
            [part1, EvolvingSurface([TopologyPeriod([2.0, 3.0], base.cells, np.stack([moved, moved]))])]
        )
    with pytest.raises(tgsis.InvalidInputError, match="at least one"):
        EvolvingSurface.chain([])
