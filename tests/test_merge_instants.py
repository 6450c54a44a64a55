"""Merge by region of models 2 and 3: per instant (surfaces at instants), per period (evolving surfaces) (issue 39).

A surface at instants merges instant by instant, an evolving surface
geometry instant by geometry instant within each topology period
(docs/merge.md, "Models 2 and 3"): disjoint edits merge bit for bit,
overlapping ones are regions of that slice, what cannot be split (an instant
removed on one side and changed on the other, a period's topology changed on
both sides) stays an object-level conflict.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import psycopg
import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

import tgsis
from tests.merge_data import SIDE, curved_surface, rewrites_same_values
from tgsis import formats
from tgsis.temporal import EvolvingSurface, SurfaceSeries, TopologyPeriod

Conn = psycopg.Connection[Any]

TIMES = (1.0, 2.0, 3.0)
NORTH = np.arange(0, 2 * SIDE)  # the first two rows of the grid
SOUTH = np.arange((SIDE - 2) * SIDE, SIDE * SIDE)  # the last two
MIDDLE = np.arange(5 * SIDE, 7 * SIDE)
CHILD_SHIFT = (0.125, -3.3, 7.77)
PARENT_SHIFT = (-1.1, 0.0, -2.9)


# --------------------------------------------------------------------------- set-up


def _shape(i: int) -> np.ndarray:
    """The curved grid, a little other at each instant (full mantissas)."""
    shape: np.ndarray = curved_surface().vertices + np.array([0.0, 0.0, 1.0 / 3.0]) * (i + 1)
    return shape


def _porosity() -> np.ndarray:
    return np.asarray(curved_surface().vertex_properties["porosity"])


def make_series(conn: Conn) -> int:
    """A model-2 surface at TIMES (a vertex property, a per-instant property) in DEFAULT, version e1 on it."""
    tgsis.create_feature_class(
        conn,
        "horizons",
        "SURFACE",
        time_model="INSTANTS",
        cell_properties=[("porosity", "float8")],
        instant_properties=[("throw", "double precision")],
    )
    tgsis.enable_feature_versioning(conn)
    cells = curved_surface().cells
    surfaces = [tgsis.Surface(_shape(i), cells, vertex_properties={"porosity": _porosity()}) for i in range(len(TIMES))]
    series = SurfaceSeries(np.asarray(TIMES), surfaces, properties={"throw": np.asarray([10.0, 20.0, 30.0])})
    geoid = tgsis.insert_feature(conn, "horizons", series)
    tgsis.create_version(conn, "e1")
    conn.commit()
    return geoid


def make_evolving(conn: Conn, timet: tuple[float, ...] = TIMES) -> int:
    """A model-3 surface of one topology period (geometry instants ``timet``) in DEFAULT, version e1 on it."""
    tgsis.create_feature_class(
        conn, "evolving", "SURFACE", time_model="EVOLVING", cell_properties=[("porosity", "float8")]
    )
    tgsis.enable_feature_versioning(conn)
    positions = np.stack([_shape(i) for i in range(len(timet))])
    porosity = np.stack([_porosity()] * len(timet))
    period = TopologyPeriod(
        np.asarray(timet), curved_surface().cells, positions, vertex_properties={"porosity": porosity}
    )
    geoid = tgsis.insert_feature(conn, "evolving", EvolvingSurface([period], name="evolving fault"))
    tgsis.create_version(conn, "e1")
    conn.commit()
    return geoid


def move(conn: Conn, version: str, geoid: int, t: float, ids: Any, shift: tuple[float, float, float]) -> None:
    """Move vertices ``ids`` at instant ``t`` of a model-2 surface (one committed UPDATE, as in psql)."""
    with tgsis.in_version(conn, version):
        conn.execute(
            "UPDATE tgsis.times_vrtx SET x = x + %s, y = y + %s, z = z + %s"
            " WHERE geoid = %s AND times = %s AND vrtxid = ANY(%s)",
            (*shift, geoid, t, [int(i) for i in np.asarray(ids)]),
        )
    conn.commit()


def move3(conn: Conn, version: str, geoid: int, timet: float, ids: Any, shift: tuple[float, float, float]) -> None:
    """Move nodes ``ids`` at geometry instant ``timet`` of a model-3 surface (one committed UPDATE)."""
    with tgsis.in_version(conn, version):
        conn.execute(
            "UPDATE tgsis.d4dvrtx SET x = x + %s, y = y + %s, z = z + %s"
            " WHERE geoid = %s AND timet = %s AND nodeid = ANY(%s)",
            (*shift, geoid, timet, [int(i) for i in np.asarray(ids)]),
        )
    conn.commit()


def shifted(base: np.ndarray, ids: Any, shift: tuple[float, float, float]) -> np.ndarray:
    out = base.copy()
    out[np.asarray(ids)] += np.asarray(shift)  # the same float additions as the UPDATEs
    return out


def instants(conn: Conn, version: str, geoid: int) -> dict[float, tuple[np.ndarray, np.ndarray, set[tuple[int, ...]]]]:
    """Per instant: (vertex ids, (n, 3) coordinates, cells as (id, v1, v2, v3)) as a psql user reads them."""
    out = {}
    with tgsis.in_version(conn, version):
        times = [r[0] for r in conn.execute("SELECT times FROM tgsis.times WHERE geoid = %s ORDER BY 1", (geoid,))]
        for t in times:
            rows = conn.execute(
                "SELECT vrtxid, x, y, z FROM tgsis.times_vrtx WHERE geoid = %s AND times = %s ORDER BY vrtxid",
                (geoid, t),
            ).fetchall()
            cells = conn.execute(
                "SELECT trglid, vrtxid1, vrtxid2, vrtxid3 FROM tgsis.times_trgl WHERE geoid = %s AND times = %s",
                (geoid, t),
            ).fetchall()
            out[float(t)] = (
                np.array([r[0] for r in rows], dtype=np.int64),
                np.array([r[1:] for r in rows], dtype=np.float64).reshape(-1, 3),
                {tuple(int(v) for v in c) for c in cells},
            )
    conn.commit()
    return out


def geometry_instants(conn: Conn, version: str, geoid: int) -> dict[tuple[float, float], np.ndarray]:
    """Per (timem, timet) of a model-3 surface: the (n, 3) node positions by node id, as a psql user reads them."""
    out: dict[tuple[float, float], list[Any]] = {}
    with tgsis.in_version(conn, version):
        rows = conn.execute(
            "SELECT timem, timet, x, y, z FROM tgsis.d4dvrtx WHERE geoid = %s ORDER BY timem, timet, nodeid", (geoid,)
        ).fetchall()
    conn.commit()
    for m, t, *xyz in rows:
        out.setdefault((float(m), float(t)), []).append(xyz)
    return {k: np.array(v, dtype=np.float64) for k, v in out.items()}


def triangles3(conn: Conn, version: str, geoid: int) -> set[tuple[float, int, int, int, int]]:
    with tgsis.in_version(conn, version):
        rows = conn.execute(
            "SELECT timem, trglid, nodeid1, nodeid2, nodeid3 FROM tgsis.d4dtrgl WHERE geoid = %s", (geoid,)
        ).fetchall()
    conn.commit()
    return {(float(r[0]), *(int(v) for v in r[1:])) for r in rows}  # type: ignore[misc]


def _cells() -> set[tuple[int, ...]]:
    return {(i, *map(int, c)) for i, c in enumerate(curved_surface().cells)}


# --------------------------------------------------------------------------- model 2: per instant


@pytest.fixture
def series(conn: Conn, series_clone: int) -> int:
    return series_clone  # make_series's, built once (tests/conftest.py)


def test_disjoint_edits_of_one_instant_merge_bit_for_bit(conn: Conn, series: int) -> None:
    move(conn, "e1", series, 2.0, NORTH, CHILD_SHIFT)
    move(conn, "DEFAULT", series, 2.0, SOUTH, PARENT_SHIFT)
    result = tgsis.merge_version(conn, "e1")
    assert [(o.objectkey, o.how) for o in result.objects] == [(str(series), "automatic")]
    expected = {t: _shape(i) for i, t in enumerate(TIMES)}
    expected[2.0] = shifted(shifted(_shape(1), NORTH, CHILD_SHIFT), SOUTH, PARENT_SHIFT)
    for version in ("DEFAULT", "e1"):
        got = instants(conn, version, series)
        assert sorted(got) == list(TIMES)
        for t in TIMES:
            ids, xyz, cells = got[t]
            np.testing.assert_array_equal(ids, np.arange(SIDE * SIDE))
            assert xyz.tobytes() == expected[t].tobytes(), (version, t)
            assert cells == _cells()
    assert tgsis.find_conflicts(conn, "e1") == []


def test_edits_at_different_instants_merge(conn: Conn, series: int) -> None:
    move(conn, "e1", series, 1.0, NORTH, CHILD_SHIFT)
    move(conn, "DEFAULT", series, 3.0, SOUTH, PARENT_SHIFT)
    conflicts = tgsis.find_conflicts(conn, "e1")
    assert [c.region_refusal for c in conflicts] == [None]
    assert [(r.times, r.timem, r.changed_by, r.conflict) for r in conflicts[0].regions] == [
        (1.0, None, "child", False),
        (3.0, None, "parent", False),
    ]
    tgsis.merge_version(conn, "e1")
    got = instants(conn, "DEFAULT", series)
    assert got[1.0][1].tobytes() == shifted(_shape(0), NORTH, CHILD_SHIFT).tobytes()
    assert got[2.0][1].tobytes() == _shape(1).tobytes()
    assert got[3.0][1].tobytes() == shifted(_shape(2), SOUTH, PARENT_SHIFT).tobytes()


def test_an_instant_added_on_one_side_and_an_edit_on_the_other(conn: Conn, series: int) -> None:
    new = tgsis.Surface(_shape(7), curved_surface().cells, vertex_properties={"porosity": _porosity() * 2})
    with tgsis.in_version(conn, "e1"):
        tgsis.add_instant(conn, "horizons", series, 4.0, new, {"throw": 44.0})
    conn.commit()
    move(conn, "DEFAULT", series, 2.0, SOUTH, PARENT_SHIFT)
    tgsis.merge_version(conn, "e1")
    got = instants(conn, "DEFAULT", series)
    assert sorted(got) == [1.0, 2.0, 3.0, 4.0]
    assert got[4.0][1].tobytes() == _shape(7).tobytes()
    assert got[2.0][1].tobytes() == shifted(_shape(1), SOUTH, PARENT_SHIFT).tobytes()
    throws = conn.execute("SELECT _times, throw FROM horizons_pros WHERE _geoid = %s ORDER BY 1", (series,)).fetchall()
    assert throws == [(1.0, 10.0), (2.0, 20.0), (3.0, 30.0), (4.0, 44.0)]
    porosity = conn.execute(
        "SELECT porosity FROM horizons_cellpros WHERE _geoid = %s AND _times = 4 ORDER BY _idx", (series,)
    ).fetchall()
    assert np.array([p[0] for p in porosity]).tobytes() == (_porosity() * 2).tobytes()
    conn.commit()


def test_overlapping_edits_at_one_instant_are_that_instants_regions(conn: Conn, series: int) -> None:
    move(conn, "e1", series, 2.0, NORTH, CHILD_SHIFT)
    move(conn, "DEFAULT", series, 2.0, NORTH[:SIDE], PARENT_SHIFT)
    move(conn, "DEFAULT", series, 3.0, SOUTH, PARENT_SHIFT)  # another instant: merges by itself
    with pytest.raises(tgsis.UnsolvedConflictsError, match=r"region 0 at instant 2\.0 unsolved"):
        tgsis.merge_version(conn, "e1")
    [conflict] = tgsis.find_conflicts(conn, "e1")
    regions = conflict.regions
    assert [(r.region, r.times, r.conflict) for r in regions] == [(0, 2.0, True), (1, 3.0, False)]
    np.testing.assert_array_equal(regions[0].child_vertex_ids, NORTH)
    np.testing.assert_array_equal(regions[0].parent_vertex_ids, NORTH[:SIDE])
    stored = conn.execute(
        "SELECT region, times, timem, conflict FROM tgsis.conflict_regions ORDER BY region"
    ).fetchall()
    assert stored == [(0, 2.0, None, True), (1, 3.0, None, False)]
    conn.commit()
    assert regions[0].as_json()["times"] == 2.0
    resolution = tgsis.resolve_region(conn, "e1", series, 0, "child")
    assert [(d.region, d.side, d.vertices) for d in resolution.discards] == [(0, "parent", SIDE)]
    tgsis.merge_version(conn, "e1")
    got = instants(conn, "DEFAULT", series)
    assert got[2.0][1].tobytes() == shifted(_shape(1), NORTH, CHILD_SHIFT).tobytes()
    assert got[3.0][1].tobytes() == shifted(_shape(2), SOUTH, PARENT_SHIFT).tobytes()


def test_all_regions_of_the_instants_solved_at_once_by_average(conn: Conn, series: int) -> None:
    for t in (1.0, 3.0):
        move(conn, "e1", series, t, NORTH, CHILD_SHIFT)
        move(conn, "DEFAULT", series, t, NORTH, PARENT_SHIFT)
    [conflict] = tgsis.find_conflicts(conn, "e1")
    assert [(r.region, r.times, r.conflict) for r in conflict.regions] == [(0, 1.0, True), (1, 3.0, True)]
    resolution = tgsis.resolve_all_regions(conn, "e1", series, "average")
    assert [r.region for r in resolution.regions] == [0, 1]
    assert [(t.side, t.vertices, t.regions) for t in resolution.totals] == [
        ("parent", 2 * len(NORTH), (0, 1)),
        ("child", 2 * len(NORTH), (0, 1)),
    ]
    tgsis.merge_version(conn, "e1")
    got = instants(conn, "DEFAULT", series)
    for i, t in ((0, 1.0), (2, 3.0)):
        expected = _shape(i).copy()
        p, c = shifted(_shape(i), NORTH, PARENT_SHIFT), shifted(_shape(i), NORTH, CHILD_SHIFT)
        expected[NORTH] = 0.5 * p[NORTH] + 0.5 * c[NORTH]
        assert got[t][1].tobytes() == expected.tobytes()
    assert got[2.0][1].tobytes() == _shape(1).tobytes()


def test_a_manual_mesh_solves_a_region_of_an_instant(conn: Conn, series: int) -> None:
    import dataclasses

    from tgsis.db._merge_states import read_sliced_states

    move(conn, "e1", series, 2.0, NORTH, CHILD_SHIFT)
    move(conn, "DEFAULT", series, 2.0, NORTH, PARENT_SHIFT)
    move(conn, "DEFAULT", series, 3.0, SOUTH, PARENT_SHIFT)
    tgsis.find_conflicts(conn, "e1")
    with conn.transaction():
        conn.execute("SET TRANSACTION ISOLATION LEVEL REPEATABLE READ")
        child = read_sliced_states(conn, "e1", series).states["child"].slices[(2.0,)]
    vertices = child.vertices.copy()
    vertices[NORTH, 2] = 99.5
    resolution = tgsis.resolve_region(conn, "e1", series, 0, "manual", dataclasses.replace(child, vertices=vertices))
    assert resolution.region.solution == "manual" and resolution.region.times == 2.0
    with pytest.raises(tgsis.RegionSolutionError, match="not a conflict"):
        tgsis.resolve_region(conn, "e1", series, 1, "child")
    tgsis.merge_version(conn, "e1")
    got = instants(conn, "DEFAULT", series)
    expected = _shape(1).copy()
    expected[NORTH, 2] = 99.5
    assert got[2.0][1][:, 2].tobytes() == expected[:, 2].tobytes()
    assert got[3.0][1].tobytes() == shifted(_shape(2), SOUTH, PARENT_SHIFT).tobytes()


def test_a_region_solution_is_stale_once_its_instant_changes(conn: Conn, series: int) -> None:
    move(conn, "e1", series, 2.0, NORTH, CHILD_SHIFT)
    move(conn, "DEFAULT", series, 2.0, NORTH, PARENT_SHIFT)
    tgsis.find_conflicts(conn, "e1")
    tgsis.resolve_region(conn, "e1", series, 0, "parent")
    move(conn, "e1", series, 2.0, [100], CHILD_SHIFT)
    with pytest.raises(tgsis.RegionSolutionError, match="found on a state that changed since"):
        tgsis.resolve_region(conn, "e1", series, 0, "child")
    with pytest.raises(tgsis.UnsolvedConflictsError):
        tgsis.merge_version(conn, "e1")


def test_json_export_and_the_command_line_name_the_instant(
    conn: Conn, series: int, tmp_path: Any, db_dsn: str, capsys: pytest.CaptureFixture[str]
) -> None:
    import json

    from tgsis.cli import main

    move(conn, "e1", series, 2.0, NORTH, CHILD_SHIFT)
    move(conn, "DEFAULT", series, 2.0, NORTH[:SIDE], PARENT_SHIFT)
    move(conn, "DEFAULT", series, 3.0, SOUTH, PARENT_SHIFT)
    assert main(["--dsn", db_dsn, "version", "conflicts", "e1", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    [listed] = data["conflicts"]
    assert [(r["region"], r["times"], r["conflict"]) for r in listed["conflict_regions"]] == [
        (0, 2.0, True),
        (1, 3.0, False),
    ]
    assert all("timem" not in r for r in listed["conflict_regions"])
    assert main(["--dsn", db_dsn, "version", "conflicts", "e1", "--regions"]) == 0
    assert "by instant: 2 regions at 2 instant(s) (2, 3); --json lists them" in capsys.readouterr().out
    files = tgsis.export_conflict(conn, "e1", series, tmp_path, picture=False)
    names = sorted(f.name for f in files)
    assert names == sorted(
        [f"{series}_regions.json"]
        + [f"{series}_t2.0_{side}{end}" for side in ("base", "parent", "child") for end in (".ts", "_cells.csv")]
    ), names
    regions = json.loads((tmp_path / f"{series}_regions.json").read_text())
    assert [(s["times"], [r["index"] for r in s["regions"]]) for s in regions["slices"]] == [(2.0, [0]), (3.0, [1])]
    [child] = formats.read([f for f in files if f.name.endswith("_child.ts")][0])
    ids = np.asarray(child.vertex_properties["vrtxid"], dtype=np.int64)
    assert child.vertices[np.argsort(ids)].tobytes() == shifted(_shape(1), NORTH, CHILD_SHIFT).tobytes()
    with pytest.raises(tgsis.InvalidInputError, match="merges slice by slice"):
        tgsis.object_merge(conn, "e1", series)
    conn.rollback()
    assert (
        main(["--dsn", db_dsn, "version", "resolve", "e1", str(series), "child", "--region", "0", "--discard-other"])
        == 0
    )
    assert main(["--dsn", db_dsn, "version", "merge", "e1"]) == 0
    got = instants(conn, "DEFAULT", series)
    assert got[2.0][1].tobytes() == shifted(_shape(1), NORTH, CHILD_SHIFT).tobytes()
    assert got[3.0][1].tobytes() == shifted(_shape(2), SOUTH, PARENT_SHIFT).tobytes()


def test_an_instant_removed_on_one_side_and_changed_on_the_other_is_an_object_conflict(conn: Conn, series: int) -> None:
    with tgsis.in_version(conn, "e1"):
        tgsis.delete_instant(conn, series, 2.0)
    conn.commit()
    move(conn, "DEFAULT", series, 2.0, SOUTH, PARENT_SHIFT)
    [conflict] = tgsis.find_conflicts(conn, "e1")
    assert conflict.regions == ()
    assert "instant 2.0 was removed in the version and changed in the parent" in (conflict.region_refusal or "")
    before = instants(conn, "DEFAULT", series)
    with pytest.raises(tgsis.UnsolvedConflictsError, match="instant 2.0 was removed in the version"):
        tgsis.merge_version(conn, "e1")
    after = instants(conn, "DEFAULT", series)
    assert {t: v[1].tobytes() for t, v in before.items()} == {t: v[1].tobytes() for t, v in after.items()}


def test_the_same_edit_on_both_sides_merges(conn: Conn, series: int) -> None:
    move(conn, "e1", series, 2.0, NORTH, CHILD_SHIFT)
    move(conn, "DEFAULT", series, 2.0, NORTH, CHILD_SHIFT)
    move(conn, "e1", series, 3.0, SOUTH, PARENT_SHIFT)
    [conflict] = tgsis.find_conflicts(conn, "e1")
    assert [(r.times, r.changed_by, r.conflict) for r in conflict.regions] == [
        (2.0, "both", False),
        (3.0, "child", False),
    ]
    tgsis.merge_version(conn, "e1")
    got = instants(conn, "DEFAULT", series)
    assert got[2.0][1].tobytes() == shifted(_shape(1), NORTH, CHILD_SHIFT).tobytes()
    assert got[3.0][1].tobytes() == shifted(_shape(2), SOUTH, PARENT_SHIFT).tobytes()


def test_a_property_row_removed_on_one_side_stays_removed(conn: Conn, series: int) -> None:
    move(conn, "e1", series, 2.0, NORTH, CHILD_SHIFT)
    conn.execute("DELETE FROM horizons_cellpros WHERE _geoid = %s AND _times = 2 AND _idx = 100", (series,))
    conn.commit()
    tgsis.merge_version(conn, "e1")
    for version in ("DEFAULT", "e1"):
        with tgsis.in_version(conn, version):
            rows = conn.execute(
                "SELECT _idx, porosity FROM horizons_cellpros WHERE _geoid = %s AND _times = 2 ORDER BY _idx",
                (series,),
            ).fetchall()
        conn.commit()
        assert [r[0] for r in rows] == [i for i in range(SIDE * SIDE) if i != 100]
        assert np.array([r[1] for r in rows]).tobytes() == np.delete(_porosity(), 100).tobytes()


def test_a_per_instant_property_changed_on_both_sides_is_an_object_conflict(conn: Conn, series: int) -> None:
    for version, throw in (("e1", 21.0), ("DEFAULT", 22.0)):
        with tgsis.in_version(conn, version):
            conn.execute("UPDATE horizons_pros SET throw = %s WHERE _geoid = %s AND _times = 2", (throw, series))
        conn.commit()
    move(conn, "e1", series, 1.0, NORTH, CHILD_SHIFT)
    [conflict] = tgsis.find_conflicts(conn, "e1")
    assert "per-instant feature properties (throw) of instant 2.0 were changed on both sides" in (
        conflict.region_refusal or ""
    )
    with pytest.raises(tgsis.UnsolvedConflictsError, match=r"\(throw\) of instant 2\.0"):
        tgsis.merge_version(conn, "e1")


def test_the_sides_read_from_the_storage_rows_are_the_states_the_views_show(conn: Conn, series: int) -> None:
    from tgsis.db._merge_states import read_sliced_states

    new = tgsis.Surface(_shape(7), curved_surface().cells, vertex_properties={"porosity": _porosity()})
    move(conn, "e1", series, 2.0, NORTH, CHILD_SHIFT)
    with tgsis.in_version(conn, "e1"):
        tgsis.add_instant(conn, "horizons", series, 4.0, new, {"throw": 44.0})
        tgsis.delete_instant(conn, series, 1.0)
        conn.execute("DELETE FROM tgsis.times_trgl WHERE geoid = %s AND times = 3 AND trglid = 0", (series,))
    conn.commit()
    move(conn, "DEFAULT", series, 2.0, SOUTH, PARENT_SHIFT)
    move(conn, "DEFAULT", series, 2.0, SOUTH, PARENT_SHIFT)  # twice: a row version closed by the same side
    with conn.transaction():
        conn.execute("SET TRANSACTION ISOLATION LEVEL REPEATABLE READ")
        states = read_sliced_states(conn, "e1", series).states
    for side, version in (("parent", "DEFAULT"), ("child", "e1")):
        seen = instants(conn, version, series)
        state = states[side]
        assert sorted(k[0] for k in state.slices) == sorted(seen)
        for (t,), mesh in state.slices.items():
            ids, xyz, cells = seen[t]
            np.testing.assert_array_equal(mesh.vertex_ids, ids)
            assert mesh.vertices.tobytes() == xyz.tobytes()
            assert {(int(i), *map(int, c)) for i, c in zip(mesh.cell_ids, mesh.cells)} == cells
    assert sorted(k[0] for k in states["base"].slices) == list(TIMES)
    assert states["child"].instant_rows[(4.0,)] == ("44",)


def test_an_instant_removed_on_one_side_only_is_removed(conn: Conn, series: int) -> None:
    with tgsis.in_version(conn, "e1"):
        tgsis.delete_instant(conn, series, 2.0)
    conn.commit()
    move(conn, "DEFAULT", series, 3.0, SOUTH, PARENT_SHIFT)
    tgsis.merge_version(conn, "e1")
    got = instants(conn, "DEFAULT", series)
    assert sorted(got) == [1.0, 3.0]
    assert got[3.0][1].tobytes() == shifted(_shape(2), SOUTH, PARENT_SHIFT).tobytes()
    assert conn.execute("SELECT _times FROM horizons_pros ORDER BY 1").fetchall() == [(1.0,), (3.0,)]
    conn.commit()


# --------------------------------------------------------------------------- model 3: per period


@pytest.fixture
def evolving(conn: Conn, evolving_clone: int) -> int:
    return evolving_clone  # make_evolving's, built once (tests/conftest.py)


def _period(conn: Conn, version: str, geoid: int) -> dict[float, np.ndarray]:
    return {k[1]: v for k, v in geometry_instants(conn, version, geoid).items()}


def test_disjoint_position_edits_at_one_geometry_instant_merge(conn: Conn, evolving: int) -> None:
    move3(conn, "e1", evolving, 2.0, NORTH, CHILD_SHIFT)
    move3(conn, "DEFAULT", evolving, 2.0, SOUTH, PARENT_SHIFT)
    result = tgsis.merge_version(conn, "e1")
    assert [(o.objectkey, o.how) for o in result.objects] == [(str(evolving), "automatic")]
    for version in ("DEFAULT", "e1"):
        got = _period(conn, version, evolving)
        assert got[1.0].tobytes() == _shape(0).tobytes()
        assert got[2.0].tobytes() == shifted(shifted(_shape(1), NORTH, CHILD_SHIFT), SOUTH, PARENT_SHIFT).tobytes()
        assert got[3.0].tobytes() == _shape(2).tobytes()
        assert triangles3(conn, version, evolving) == {(1.0, *c) for c in _cells()}


def test_disjoint_position_edits_at_several_geometry_instants_merge(conn: Conn, evolving: int) -> None:
    for t in (1.0, 3.0):
        move3(conn, "e1", evolving, t, NORTH, CHILD_SHIFT)
    for t in (2.0, 3.0):
        move3(conn, "DEFAULT", evolving, t, SOUTH, PARENT_SHIFT)
    [conflict] = tgsis.find_conflicts(conn, "e1")
    assert [(r.timem, r.times, r.changed_by, r.conflict) for r in conflict.regions] == [
        (1.0, 1.0, "child", False),
        (1.0, 2.0, "parent", False),
        (1.0, 3.0, "child", False),
        (1.0, 3.0, "parent", False),
    ]
    tgsis.merge_version(conn, "e1")
    got = _period(conn, "DEFAULT", evolving)
    assert got[1.0].tobytes() == shifted(_shape(0), NORTH, CHILD_SHIFT).tobytes()
    assert got[2.0].tobytes() == shifted(_shape(1), SOUTH, PARENT_SHIFT).tobytes()
    assert got[3.0].tobytes() == shifted(shifted(_shape(2), NORTH, CHILD_SHIFT), SOUTH, PARENT_SHIFT).tobytes()


def test_a_period_appended_on_one_side_and_positions_moved_on_the_other_merge(conn: Conn, evolving: int) -> None:
    last = _shape(2)
    period = TopologyPeriod(
        np.asarray([3.0, 4.5]),
        curved_surface().cells,
        np.stack([last, last + np.array([0.0, 0.0, 0.1])]),
        vertex_properties={"porosity": np.stack([_porosity()] * 2)},
    )
    with tgsis.in_version(conn, "e1"):
        tgsis.append_period(conn, "evolving", evolving, period)
    conn.commit()
    move3(conn, "DEFAULT", evolving, 2.0, SOUTH, PARENT_SHIFT)
    tgsis.merge_version(conn, "e1")
    got = geometry_instants(conn, "DEFAULT", evolving)
    assert sorted(got) == [(1.0, 1.0), (1.0, 2.0), (1.0, 3.0), (3.0, 3.0), (3.0, 4.5)]
    assert got[(1.0, 2.0)].tobytes() == shifted(_shape(1), SOUTH, PARENT_SHIFT).tobytes()
    assert got[(3.0, 4.5)].tobytes() == (last + np.array([0.0, 0.0, 0.1])).tobytes()
    assert len(triangles3(conn, "DEFAULT", evolving)) == 2 * len(_cells())


def test_overlapping_position_edits_at_one_geometry_instant_are_its_regions(conn: Conn, evolving: int) -> None:
    move3(conn, "e1", evolving, 2.0, NORTH, CHILD_SHIFT)
    move3(conn, "DEFAULT", evolving, 2.0, NORTH, PARENT_SHIFT)
    move3(conn, "e1", evolving, 3.0, SOUTH, CHILD_SHIFT)
    [conflict] = tgsis.find_conflicts(conn, "e1")
    assert [(r.region, r.timem, r.times, r.conflict) for r in conflict.regions] == [
        (0, 1.0, 2.0, True),
        (1, 1.0, 3.0, False),
    ]
    stored = conn.execute("SELECT region, timem, times FROM tgsis.conflict_regions ORDER BY region").fetchall()
    assert stored == [(0, 1.0, 2.0), (1, 1.0, 3.0)]
    conn.commit()
    resolution = tgsis.resolve_region(conn, "e1", evolving, 0, "base")
    assert sorted((d.side, d.vertices) for d in resolution.discards) == [("child", len(NORTH)), ("parent", len(NORTH))]
    tgsis.merge_version(conn, "e1")
    got = _period(conn, "DEFAULT", evolving)
    assert got[2.0].tobytes() == _shape(1).tobytes()
    assert got[3.0].tobytes() == shifted(_shape(2), SOUTH, CHILD_SHIFT).tobytes()


def _drop_corner_triangle(conn: Conn, version: str, geoid: int) -> None:
    """A topology edit of the period: the first triangle (0, 1, SIDE + 1) removed, at every geometry instant."""
    with tgsis.in_version(conn, version):
        conn.execute("DELETE FROM tgsis.d4dtrgl WHERE geoid = %s AND trglid = 0", (geoid,))
    conn.commit()


def test_topology_on_one_side_and_positions_on_the_other_merge(conn: Conn, evolving: int) -> None:
    _drop_corner_triangle(conn, "e1", evolving)
    move3(conn, "DEFAULT", evolving, 2.0, SOUTH, PARENT_SHIFT)
    tgsis.merge_version(conn, "e1")
    expected_cells = {(1.0, *c) for c in _cells() if c[0] != 0}
    for version in ("DEFAULT", "e1"):
        assert triangles3(conn, version, evolving) == expected_cells
        got = _period(conn, version, evolving)
        assert got[2.0].tobytes() == shifted(_shape(1), SOUTH, PARENT_SHIFT).tobytes()
        assert got[1.0].tobytes() == _shape(0).tobytes()


def test_topology_changed_on_both_sides_is_an_object_conflict(conn: Conn, evolving: int) -> None:
    _drop_corner_triangle(conn, "e1", evolving)
    with tgsis.in_version(conn, "DEFAULT"):
        conn.execute("DELETE FROM tgsis.d4dtrgl WHERE geoid = %s AND trglid = 5", (evolving,))
    conn.commit()
    [conflict] = tgsis.find_conflicts(conn, "e1")
    assert conflict.regions == ()
    assert "topology (nodes, triangles) of the topology period starting at 1.0 was changed on both sides" in (
        conflict.region_refusal or ""
    )
    with pytest.raises(tgsis.UnsolvedConflictsError, match="changed on both sides"):
        tgsis.merge_version(conn, "e1")
    assert len(triangles3(conn, "DEFAULT", evolving)) == len(_cells()) - 1


def test_a_geometry_instant_added_to_a_period_whose_topology_the_other_side_changed_is_refused(
    conn: Conn, evolving: int
) -> None:
    _drop_corner_triangle(conn, "DEFAULT", evolving)
    with tgsis.in_version(conn, "e1"):  # a new geometry instant of the period, with the period's (old) topology
        conn.execute("INSERT INTO tgsis.timet VALUES (%s, 1.0, 2.5)", (evolving,))
        conn.execute(
            "INSERT INTO tgsis.d4dvrtx SELECT geoid, timem, 2.5, nodeid, x, y, z FROM tgsis.d4dvrtx"
            " WHERE geoid = %s AND timet = 2.0",
            (evolving,),
        )
        conn.execute(
            "INSERT INTO evolving_cellpros SELECT _geoid, _timem, 2.5, _idx, porosity FROM evolving_cellpros"
            " WHERE _geoid = %s AND _timet = 2.0",
            (evolving,),
        )
    conn.commit()
    before = triangles3(conn, "DEFAULT", evolving)
    with pytest.raises(tgsis.PeriodTopologyError, match="period starting at 1.0") as caught:
        tgsis.merge_version(conn, "e1")
    assert caught.value.code == "TG308"
    assert triangles3(conn, "DEFAULT", evolving) == before
    assert sorted(_period(conn, "DEFAULT", evolving)) == [1.0, 2.0, 3.0]


# --------------------------------------------------------------------------- Hypothesis: disjoint edits at random instants

_pairs = iter(range(10**6))
_grid_rows = st.lists(st.integers(0, SIDE - 1), min_size=1, max_size=SIDE, unique=True)
_shift = st.tuples(*(st.floats(-50.0, 50.0, allow_nan=False, allow_subnormal=False) for _ in range(3)))
_instants = st.lists(st.sampled_from(TIMES), min_size=1, max_size=3, unique=True)


@settings(
    max_examples=8, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow]
)
@given(
    child_rows=st.lists(st.integers(0, 3), min_size=1, max_size=3, unique=True),
    parent_rows=st.lists(st.integers(7, SIDE - 1), min_size=1, max_size=4, unique=True),
    child_cols=_grid_rows,
    parent_cols=_grid_rows,
    child_shift=_shift,
    parent_shift=_shift,
    child_times=_instants,
    parent_times=_instants,
)
@example(
    child_rows=[0],
    parent_rows=[7],
    child_cols=[0],
    parent_cols=[0],
    child_shift=(0.0, 0.0, 1.0),
    parent_shift=(0.0, 0.0, 0.0),
    child_times=[1.0],
    parent_times=[1.0],
)
def test_random_disjoint_edits_at_random_instants_merge_into_exactly_the_union(
    conn: Conn,
    series: int,
    child_rows: list[int],
    parent_rows: list[int],
    child_cols: list[int],
    parent_cols: list[int],
    child_shift: tuple[float, float, float],
    parent_shift: tuple[float, float, float],
    child_times: list[float],
    parent_times: list[float],
) -> None:
    # rows 0-3 and 7-11: the one-ring margins (a row either side) never meet
    n = next(_pairs)
    parent, child = f"hp{n}", f"hc{n}"
    tgsis.create_version(conn, parent)
    conn.commit()
    tgsis.create_version(conn, child, parent=parent)
    conn.commit()
    start = {t: v[1] for t, v in instants(conn, parent, series).items()}
    child_ids = [r * SIDE + c for r in child_rows for c in child_cols]
    parent_ids = [r * SIDE + c for r in parent_rows for c in parent_cols]
    expected = dict(start)
    for t in child_times:
        move(conn, child, series, t, child_ids, child_shift)
        expected[t] = shifted(expected[t], child_ids, child_shift)
    # a shift that leaves every bit as it was (zero, or too small for the coordinates) changes no chunk: the object
    # is then not changed in the child on chunks, where rows wrote new row versions (docs/storage.md, by design)
    child_changed = any(expected[t].tobytes() != start[t].tobytes() for t in child_times)
    rewrites = rewrites_same_values(conn, "times_vrtx")
    parent_changed = False
    conn.commit()
    for t in parent_times:
        move(conn, parent, series, t, parent_ids, parent_shift)
        before_parent = expected[t]
        expected[t] = shifted(expected[t], parent_ids, parent_shift)
        parent_changed = parent_changed or expected[t].tobytes() != before_parent.tobytes()
    result = tgsis.merge_version(conn, child)
    hows = [o.how for o in result.objects]
    # an object both sides changed is merged automatically; one only the child changed is taken as the child has it,
    # and listed as no merged object (on chunks a shift that leaves every bit writes nothing: the parent unchanged)
    both = (child_changed and parent_changed) or rewrites
    assert hows == (["automatic"] if both else []), (hows, rewrites, child_changed, parent_changed)
    got = instants(conn, parent, series)
    assert {t: v[1].tobytes() for t, v in got.items()} == {t: v.tobytes() for t, v in expected.items()}
    assert all(v[2] == _cells() for v in got.values())


# --------------------------------------------------------------------------- hostile: settings, rights, order


@pytest.mark.parametrize("setting", ["search_path = ''", "extra_float_digits = -15"])
def test_the_merge_per_instant_under_other_session_settings(conn: Conn, series: int, setting: str) -> None:
    move(conn, "e1", series, 2.0, NORTH, CHILD_SHIFT)
    move(conn, "DEFAULT", series, 2.0, SOUTH, PARENT_SHIFT)
    conn.execute("UPDATE horizons_pros SET throw = 1.0 / 3.0 WHERE _geoid = %s AND _times = 3", (series,))
    conn.commit()
    conn.execute("SET " + setting)
    conn.commit()
    result = tgsis.merge_version(conn, "e1")
    assert [o.how for o in result.objects] == ["automatic"]
    conn.execute("RESET ALL")
    conn.commit()
    for version in ("DEFAULT", "e1"):
        got = instants(conn, version, series)
        expected = shifted(shifted(_shape(1), NORTH, CHILD_SHIFT), SOUTH, PARENT_SHIFT)
        assert got[2.0][1].tobytes() == expected.tobytes()
        with tgsis.in_version(conn, version):
            throw = conn.execute("SELECT throw FROM horizons_pros WHERE _geoid = %s AND _times = 3", (series,))
            assert throw.fetchone() == (1.0 / 3.0,)
            box = conn.execute(
                "SELECT cube_ll_coord(bbox, 3), cube_ur_coord(bbox, 3) FROM tgsis.geometry WHERE geoid = %s", (series,)
            ).fetchone()
        conn.commit()
        everything = np.concatenate([v[1] for v in got.values()])
        assert box == (everything[:, 2].min(), everything[:, 2].max())


@pytest.mark.parametrize("setting", ["search_path = ''"])
def test_the_merge_per_period_under_other_session_settings(conn: Conn, evolving: int, setting: str) -> None:
    move3(conn, "e1", evolving, 2.0, NORTH, CHILD_SHIFT)
    move3(conn, "DEFAULT", evolving, 3.0, SOUTH, PARENT_SHIFT)
    conn.execute("SET " + setting)
    conn.commit()
    tgsis.merge_version(conn, "e1")
    conn.execute("RESET ALL")
    conn.commit()
    got = _period(conn, "DEFAULT", evolving)
    assert got[2.0].tobytes() == shifted(_shape(1), NORTH, CHILD_SHIFT).tobytes()
    assert got[3.0].tobytes() == shifted(_shape(2), SOUTH, PARENT_SHIFT).tobytes()


def _rows(conn: Conn) -> dict[str, list[Any]]:
    """Every row version of the model-2 storage and the version catalog: what 'nothing written' compares."""
    tables = [
        str(conn.execute("SELECT tgsis.storage_table('tgsis', %s)", (t,)).fetchone()[0])  # type: ignore[index]
        for t in ("times", "times_vrtx", "times_trgl", "geometry")
    ]
    state = {t: conn.execute(f"SELECT * FROM {t} ORDER BY 1, 2, 3").fetchall() for t in tables}
    state["versions"] = conn.execute("SELECT * FROM tgsis.versions ORDER BY 1").fetchall()
    conn.commit()
    return state


def test_a_role_without_rights_on_the_class_gets_the_permission_error_and_nothing_is_written(
    conn: Conn, series: int, db_dsn: str
) -> None:
    from tests.roles import login_roles

    move(conn, "e1", series, 2.0, NORTH, CHILD_SHIFT)
    move(conn, "DEFAULT", series, 2.0, SOUTH, PARENT_SHIFT)
    with login_roles(db_dsn, {"ed": "tgsis_editor", "rita": "tgsis_reader"}) as made:
        tgsis.grant_version(conn, "e1", "all", made.name("ed"))
        tgsis.grant_version(conn, "DEFAULT", "merge", made.name("ed"))
        conn.execute("REVOKE INSERT, UPDATE, DELETE ON public.horizons FROM tgsis_editor")
        conn.commit()
        before = _rows(conn)
        with pytest.raises(tgsis.MissingPrivilegeError):
            tgsis.merge_version(made.connect("rita"), "e1")
        assert _rows(conn) == before
        with pytest.raises(tgsis.MissingPrivilegeError):
            tgsis.merge_version(made.connect("ed"), "e1")
        assert _rows(conn) == before
        conn.execute("REVOKE SELECT ON public.horizons FROM tgsis_reader")  # regions of a class it may not read
        conn.commit()
        tgsis.find_conflicts(conn, "e1")
        rita = made.connect("rita")
        assert rita.execute("SELECT count(*) FROM tgsis.conflict_regions").fetchone() == (0,)
        rita.rollback()


@pytest.mark.parametrize("order", ["merge", "refresh, merge", "refresh, refresh, merge"])
def test_any_order_of_merge_and_refresh_gives_the_same_state(conn: Conn, order: str) -> None:
    series = make_series(conn)
    new = tgsis.Surface(_shape(7), curved_surface().cells, vertex_properties={"porosity": _porosity()})
    move(conn, "e1", series, 2.0, NORTH, CHILD_SHIFT)
    with tgsis.in_version(conn, "e1"):
        tgsis.add_instant(conn, "horizons", series, 4.0, new, {"throw": 44.0})
    conn.commit()
    move(conn, "DEFAULT", series, 2.0, SOUTH, PARENT_SHIFT)
    move(conn, "DEFAULT", series, 1.0, MIDDLE, PARENT_SHIFT)
    for step in order.split(", "):
        (tgsis.merge_version if step == "merge" else tgsis.refresh_version)(conn, "e1")
    expected = {
        1.0: shifted(_shape(0), MIDDLE, PARENT_SHIFT),
        2.0: shifted(shifted(_shape(1), NORTH, CHILD_SHIFT), SOUTH, PARENT_SHIFT),
        3.0: _shape(2),
        4.0: _shape(7),
    }
    for version in ("DEFAULT", "e1"):
        got = instants(conn, version, series)
        assert {t: v[1].tobytes() for t, v in got.items()} == {t: v.tobytes() for t, v in expected.items()}
        assert all(v[2] == _cells() for v in got.values())
    assert tgsis.find_conflicts(conn, "e1") == []


def test_a_writer_of_an_instant_in_the_version_during_the_merge(conn: Conn, series: int, db_dsn: str) -> None:
    from tests.sessions import Background, connect, wait_until_blocked

    move(conn, "e1", series, 2.0, NORTH, CHILD_SHIFT)
    move(conn, "DEFAULT", series, 2.0, SOUTH, PARENT_SHIFT)
    writer = connect(db_dsn, "writer")
    tgsis.goto_version(writer, "e1")
    writer.execute("UPDATE tgsis.times_vrtx SET z = z + 1.5 WHERE geoid = %s AND times = 2 AND vrtxid = 70", (series,))
    merger = Background(db_dsn, "merger", lambda c: tgsis.merge_version(c, "e1"))
    wait_until_blocked(conn, merger.pid, writer.info.backend_pid)  # the merge waits for the writer
    writer.commit()
    writer.close()
    merger.finish()
    expected = shifted(shifted(shifted(_shape(1), NORTH, CHILD_SHIFT), SOUTH, PARENT_SHIFT), [70], (0.0, 0.0, 1.5))
    assert instants(conn, "DEFAULT", series)[2.0][1].tobytes() == expected.tobytes()


def test_a_role_that_may_read_the_views_but_not_the_storage_finds_the_same_regions(
    conn: Conn, series: int, db_dsn: str
) -> None:
    from tests.roles import login_roles

    move(conn, "e1", series, 2.0, NORTH, CHILD_SHIFT)
    move(conn, "DEFAULT", series, 2.0, NORTH[:SIDE], PARENT_SHIFT)
    move(conn, "DEFAULT", series, 3.0, SOUTH, PARENT_SHIFT)
    [owner] = tgsis.find_conflicts(conn, "e1")
    conn.execute("REVOKE SELECT ON public.horizons_cellpros_ver FROM tgsis_reader")
    conn.commit()
    with login_roles(db_dsn, {"rita": "tgsis_reader"}) as made:
        rita = made.connect("rita")
        [seen] = tgsis.find_conflicts(rita, "e1")
        rita.rollback()
    assert seen.region_refusal is None
    assert [r.as_json() for r in seen.regions] == [r.as_json() for r in owner.regions]
    assert [r.times for r in seen.regions] == [2.0, 3.0]


def _two_periods(conn: Conn) -> int:
    """The evolving surface with a second period (3.0 to 4.5) appended in DEFAULT before e1 is made."""
    tgsis.create_feature_class(
        conn, "evolving", "SURFACE", time_model="EVOLVING", cell_properties=[("porosity", "float8")]
    )
    tgsis.enable_feature_versioning(conn)
    last = _shape(2)
    periods = [
        TopologyPeriod(
            np.asarray(TIMES),
            curved_surface().cells,
            np.stack([_shape(i) for i in range(3)]),
            vertex_properties={"porosity": np.stack([_porosity()] * 3)},
        ),
        TopologyPeriod(
            np.asarray([3.0, 4.5]),
            curved_surface().cells,
            np.stack([last, last + np.array([0.0, 0.0, 0.1])]),
            vertex_properties={"porosity": np.stack([_porosity()] * 2)},
        ),
    ]
    geoid = tgsis.insert_feature(conn, "evolving", EvolvingSurface(periods, name="evolving fault"))
    tgsis.create_version(conn, "e1")
    conn.commit()
    return geoid


def test_a_period_removed_on_one_side_and_positions_moved_in_another_merge(conn: Conn) -> None:
    geoid = _two_periods(conn)
    with tgsis.in_version(conn, "e1"):
        assert tgsis.delete_period(conn, geoid, 3.0)
    conn.commit()
    move3(conn, "DEFAULT", geoid, 2.0, SOUTH, PARENT_SHIFT)
    tgsis.merge_version(conn, "e1")
    got = geometry_instants(conn, "DEFAULT", geoid)
    assert sorted(got) == [(1.0, 1.0), (1.0, 2.0), (1.0, 3.0)]
    assert got[(1.0, 2.0)].tobytes() == shifted(_shape(1), SOUTH, PARENT_SHIFT).tobytes()
    assert {m for m, *_ in triangles3(conn, "DEFAULT", geoid)} == {1.0}


def test_a_period_removed_on_one_side_and_changed_on_the_other_is_an_object_conflict(conn: Conn) -> None:
    geoid = _two_periods(conn)
    with tgsis.in_version(conn, "e1"):
        assert tgsis.delete_period(conn, geoid, 3.0)
    conn.commit()
    move3(conn, "DEFAULT", geoid, 4.5, SOUTH + SIDE * SIDE, PARENT_SHIFT)  # (the period's nodes are numbered on)
    [conflict] = tgsis.find_conflicts(conn, "e1")
    assert "the topology period starting at 3.0 was removed in the version and changed in the parent" in (
        conflict.region_refusal or ""
    )
    with pytest.raises(tgsis.UnsolvedConflictsError, match="period starting at 3.0 was removed"):
        tgsis.merge_version(conn, "e1")
