"""Model 2: surfaces at instants — storage, instants added and deleted, the step function at t."""

from __future__ import annotations

from typing import Any

import numpy as np
import psycopg
import pytest

import tgsis
from tests.temporal_data import grid, series
from tgsis.temporal import SurfaceSeries

Conn = psycopg.Connection[Any]
TIMES = [-100.0, -66.0, -23.0, -5.0]


@pytest.fixture
def horizons(tx: Conn) -> tgsis.FeatureClass:
    return tgsis.create_feature_class(
        tx,
        "stepped",
        "SURFACE",
        time_model="INSTANTS",
        time_unit="Ma",
        cell_properties=[("porosity", "real")],
        instant_properties=[("throw", "double precision")],
    )


def reference_index(times: list[float], t: float, convention: str, alive: bool) -> int | None:
    """The spec's two step conventions written out with a loop (independent of tgsis.temporal)."""
    if t < times[0]:
        return None
    if t > times[-1]:
        return len(times) - 1 if alive else None
    if convention == "left":
        return max(i for i, ti in enumerate(times) if ti <= t)
    return min(i for i, ti in enumerate(times) if ti >= t)


@pytest.mark.parametrize("alive", [False, True])
@pytest.mark.parametrize("convention", ["left", "right"])
def test_step_function_in_sql(tx: Conn, horizons: tgsis.FeatureClass, convention: str, alive: bool) -> None:
    rng = np.random.default_rng(11)
    obj = series(rng, TIMES, alive=alive, with_properties=True)
    fid = tgsis.insert_feature(tx, horizons, obj)
    probes = sorted(
        {
            *TIMES,
            *rng.uniform(-120, 20, 30).tolist(),
            -200.0,
            50.0,
            float("inf"),
            float("-inf"),
            *(np.nextafter(t, -np.inf) for t in TIMES),
            *(np.nextafter(t, np.inf) for t in TIMES),
        }
    )
    for t in probes:
        index = reference_index(TIMES, t, convention, alive)
        got = tgsis.get_at(tx, fid, t, convention=convention)  # type: ignore[arg-type]
        assert obj.instant_index(t, convention) == index  # type: ignore[arg-type]
        if index is None:
            assert got is None, t
            continue
        assert got is not None, t
        np.testing.assert_array_equal(got.vertices, obj.surfaces[index].vertices, err_msg=f"t={t}")
        np.testing.assert_array_equal(got.triangles, obj.surfaces[index].triangles)
        instant = tx.execute("SELECT tgsis.instant_at(%s, %s, %s)", (fid, t, convention)).fetchone()
        assert instant == (TIMES[index],)


def test_rows_counts_and_properties(tx: Conn, horizons: tgsis.FeatureClass) -> None:
    obj = series(np.random.default_rng(1), TIMES, with_properties=True)
    fid = tgsis.insert_feature(tx, horizons, obj, name="H1")
    row = tx.execute(
        "SELECT timemodel, geoname, nvrtx, ncell, alive FROM tgsis.geometry WHERE geoid = %s", (fid,)
    ).fetchone()
    assert row == (
        "INSTANTS",
        "H1",
        sum(s.n_vertices for s in obj.surfaces),
        sum(s.n_cells for s in obj.surfaces),
        False,
    )
    assert tgsis.instants(tx, fid) == [(t, True) for t in TIMES]
    throws = tx.execute("SELECT _times, throw FROM stepped_pros WHERE _geoid = %s ORDER BY _times", (fid,)).fetchall()
    assert throws == list(zip(TIMES, obj.properties["throw"].tolist()))
    porosity = tx.execute(
        "SELECT porosity FROM stepped_cellpros WHERE _geoid = %s AND _times = %s ORDER BY _idx", (fid, TIMES[2])
    ).fetchall()
    np.testing.assert_array_equal(
        np.array([r[0] for r in porosity], dtype=np.float32),
        obj.surfaces[2].vertex_properties["porosity"].astype(np.float32),
    )
    refreshed = tx.execute("SELECT nvrtx, ncell FROM tgsis.refresh_geometry(%s)", (fid,)).fetchone()
    assert refreshed == row[2:4]


def test_add_and_delete_instants(tx: Conn, horizons: tgsis.FeatureClass) -> None:
    obj = series(np.random.default_rng(2), TIMES[:2], with_properties=True)
    fid = tgsis.insert_feature(tx, horizons, obj)
    vertices, triangles = grid(6)
    vertices[:, 2] = 3.0
    added = tgsis.Surface(vertices, triangles, vertex_properties={"porosity": np.full(len(vertices), 0.25)})
    tgsis.add_instant(tx, horizons, fid, -40.0, added, {"throw": 12.5})
    assert [t for t, _ in tgsis.instants(tx, fid)] == [-100.0, -66.0, -40.0]
    got = tgsis.get_at(tx, fid, -40.0)
    assert got is not None
    np.testing.assert_array_equal(got.vertices, vertices)
    assert tgsis.get_at(tx, fid, -30.0) is None  # after the last instant of a feature that is not alive
    bbox = tx.execute("SELECT cube_ur_coord(bbox, 3), nvrtx FROM tgsis.geometry WHERE geoid = %s", (fid,)).fetchone()
    assert bbox is not None and bbox[0] == max(3.0, *(s.vertices[:, 2].max() for s in obj.surfaces))
    assert bbox[1] == obj.surfaces[0].n_vertices + obj.surfaces[1].n_vertices + len(vertices)
    with pytest.raises(tgsis.AlreadyExistsError, match="-40"):
        tgsis.add_instant(tx, horizons, fid, -40.0, added)

    assert tgsis.delete_instant(tx, fid, -66.0) is True
    assert tgsis.delete_instant(tx, fid, -66.0) is False
    assert [t for t, _ in tgsis.instants(tx, fid)] == [-100.0, -40.0]
    left = tgsis.get_at(tx, fid, -50.0)
    assert left is not None
    np.testing.assert_array_equal(left.vertices, obj.surfaces[0].vertices)
    counts = tx.execute(
        "SELECT (SELECT count(*) FROM tgsis.times_vrtx WHERE geoid = %(g)s AND times = -66),"
        " (SELECT count(*) FROM stepped_cellpros WHERE _geoid = %(g)s AND _times = -66),"
        " (SELECT count(*) FROM stepped_pros WHERE _geoid = %(g)s AND _times = -66),"
        " (SELECT nvrtx FROM tgsis.geometry WHERE geoid = %(g)s)",
        {"g": fid},
    ).fetchone()
    assert counts == (0, 0, 0, obj.surfaces[0].n_vertices + len(vertices))
    tgsis.delete_instant(tx, fid, -100.0)
    with pytest.raises(tgsis.InUseError, match="only"):
        tgsis.delete_instant(tx, fid, -40.0)


def test_delete_feature_removes_every_instant(tx: Conn, horizons: tgsis.FeatureClass) -> None:
    fid = tgsis.insert_feature(tx, horizons, series(np.random.default_rng(3), TIMES, with_properties=True))
    assert tgsis.delete_feature(tx, horizons, fid)
    left = tx.execute(
        "SELECT (SELECT count(*) FROM tgsis.times), (SELECT count(*) FROM tgsis.times_vrtx),"
        " (SELECT count(*) FROM tgsis.times_trgl), (SELECT count(*) FROM stepped_pros),"
        " (SELECT count(*) FROM stepped_cellpros)"
    ).fetchone()
    assert left == (0, 0, 0, 0, 0)
    fid = tgsis.insert_feature(tx, horizons, series(np.random.default_rng(3), TIMES, with_properties=True))
    assert tgsis.drop_feature_class(tx, "stepped", force=True) == 1
    assert tx.execute("SELECT count(*) FROM tgsis.times_vrtx").fetchone() == (0,)


def test_registration(tx: Conn, horizons: tgsis.FeatureClass) -> None:
    assert (horizons.time_model, horizons.time_unit, horizons.protable) == ("INSTANTS", "Ma", "stepped_pros")
    assert [p.name for p in horizons.instant_properties] == ["throw"]
    assert tgsis.get_feature_class(tx, "stepped") == horizons
    keys = tx.execute(
        "SELECT a.attname FROM pg_index i JOIN pg_attribute a ON a.attrelid = i.indrelid "
        "AND a.attnum = ANY (i.indkey) WHERE i.indrelid = 'stepped_cellpros'::regclass AND i.indisprimary "
        "ORDER BY array_position(i.indkey, a.attnum)"
    ).fetchall()
    assert [k[0] for k in keys] == ["_geoid", "_times", "_idx"]
    with pytest.raises(tgsis.InvalidInputError, match="SURFACE"):
        tgsis.create_feature_class(tx, "moving_wells", "MULTILINESTRING", time_model="EVOLVING")
    with pytest.raises(tgsis.InvalidInputError, match="time model"):
        tgsis.create_feature_class(tx, "odd", "SURFACE", time_model="SOMETIMES")  # type: ignore[arg-type]
    with pytest.raises(tgsis.InvalidInputError, match="per-instant"):
        tgsis.create_feature_class(tx, "odd", "SURFACE", instant_properties=[("x", "float8")])


def test_bad_input_changes_nothing(tx: Conn, horizons: tgsis.FeatureClass) -> None:
    before = tx.execute("SELECT count(*) FROM tgsis.geometry").fetchone()
    vertices, triangles = grid(3)
    plain = tgsis.Surface(vertices, triangles)
    with pytest.raises(tgsis.InvalidPropertyError, match="porosity"):
        tgsis.insert_feature(tx, horizons, SurfaceSeries([0.0], [plain]))
    with_porosity = tgsis.Surface(vertices, triangles, vertex_properties={"porosity": np.zeros(9)})
    with pytest.raises(tgsis.InvalidPropertyError, match="thickness"):
        tgsis.insert_feature(tx, horizons, SurfaceSeries([0.0], [with_porosity], properties={"thickness": [1.0]}))
    assert tx.execute("SELECT count(*) FROM tgsis.geometry").fetchone() == before
    with pytest.raises(tgsis.InvalidInputError, match="strictly increasing"):
        SurfaceSeries([1.0, 0.0], [plain, plain])
    with pytest.raises(tgsis.InvalidInputError, match="one Surface per instant"):
        SurfaceSeries([1.0, 2.0], [plain])
    with pytest.raises(tgsis.InvalidInputError, match="convention"):
        tgsis.get_at(tx, 1, 0.0, convention="middle")  # type: ignore[arg-type]
    with pytest.raises(tgsis.NotFoundError):
        tgsis.add_instant(tx, horizons, 424242, 0.0, plain)


def test_check_geometry_finds_rows_edited_wrongly(tx: Conn, horizons: tgsis.FeatureClass) -> None:
    fid = tgsis.insert_feature(tx, horizons, series(np.random.default_rng(5), TIMES, with_properties=True))
    assert tx.execute("SELECT * FROM tgsis.check_geometry(%s)", (fid,)).fetchall() == []
    tx.execute("DELETE FROM tgsis.times WHERE geoid = %s AND times = %s", (fid, TIMES[1]))
    tx.execute("DELETE FROM tgsis.times_vrtx WHERE geoid = %s AND times = %s AND vrtxid = 0", (fid, TIMES[2]))
    found = {r[0] for r in tx.execute("SELECT problem FROM tgsis.check_geometry(%s)", (fid,)).fetchall()}
    assert found == {
        "vertex or triangle at an instant not in tgsis.times",
        "triangle refers to a missing vertex of its instant",
        "bounding box or counts out of date (run tgsis.refresh_geometry)",
    }
    tx.execute("SELECT tgsis.refresh_geometry(%s)", (fid,))
    found = {r[0] for r in tx.execute("SELECT problem FROM tgsis.check_geometry(%s)", (fid,)).fetchall()}
    assert "bounding box or counts out of date (run tgsis.refresh_geometry)" not in found


def test_fetch_series_round_trip(tx: Conn, horizons: tgsis.FeatureClass) -> None:
    sent = series(np.random.default_rng(6), TIMES, alive=True, with_properties=True)
    fid = tgsis.insert_feature(tx, horizons, sent)
    back = tgsis.fetch_series(tx, horizons, fid)
    np.testing.assert_array_equal(back.times, sent.times)
    assert back.alive and back.name == sent.name
    np.testing.assert_array_equal(back.properties["throw"], sent.properties["throw"])
    for got, surface in zip(back.surfaces, sent.surfaces):
        np.testing.assert_array_equal(got.vertices, surface.vertices)
        np.testing.assert_array_equal(got.triangles, surface.triangles)
        np.testing.assert_array_equal(
            got.vertex_properties["porosity"], surface.vertex_properties["porosity"].astype(np.float32)
        )


def test_bad_convention_is_an_error_outside_the_instants_too(tx: Conn, horizons: tgsis.FeatureClass) -> None:
    fid = tgsis.insert_feature(tx, horizons, series(np.random.default_rng(7), TIMES, with_properties=True))
    for t in (-500.0, -50.0, 500.0):
        with pytest.raises(psycopg.Error, match="convention 'middle'") as raised, tx.transaction():
            tx.execute("SELECT tgsis.instant_at(%s, %s, 'middle')", (fid, t))
        assert raised.value.sqlstate == "TG100"


def test_bad_calls_raise_and_leave_the_database_unchanged(tx: Conn, horizons: tgsis.FeatureClass) -> None:
    from tests.temporal_data import evolving

    fid = tgsis.insert_feature(tx, horizons, series(np.random.default_rng(8), TIMES, with_properties=True))
    moving = tgsis.create_feature_class(tx, "moving", "SURFACE", time_model="EVOLVING")
    mid = tgsis.insert_feature(tx, moving, evolving(np.random.default_rng(8), [0.0]))
    lines = tgsis.create_feature_class(tx, "lines", "MULTILINESTRING")

    def snapshot() -> Any:
        return tx.execute(
            "SELECT (SELECT count(*) FROM tgsis.times), (SELECT count(*) FROM tgsis.times_vrtx),"
            " (SELECT count(*) FROM stepped_cellpros), (SELECT count(*) FROM stepped_pros),"
            " (SELECT count(*) FROM tgsis.geometry), (SELECT nvrtx FROM tgsis.geometry WHERE geoid = %s)",
            (fid,),
        ).fetchone()

    before = snapshot()
    vertices, triangles = grid(3)
    good = tgsis.Surface(vertices, triangles, vertex_properties={"porosity": np.zeros(9)})
    with pytest.raises(tgsis.InvalidInputError, match="finite"):
        tgsis.add_instant(tx, horizons, fid, float("nan"), good)
    with pytest.raises(tgsis.InvalidPropertyError, match="porosity"):  # refused after the instant row was written
        tgsis.add_instant(tx, horizons, fid, 7.0, tgsis.Surface(vertices, triangles))
    with pytest.raises(tgsis.InvalidPropertyError, match="depth"):
        tgsis.add_instant(tx, horizons, fid, 7.0, good, {"depth": 1.0})
    with pytest.raises(tgsis.InvalidInputError, match="EVOLVING"):
        tgsis.add_instant(tx, horizons, mid, 7.0, good)
    with pytest.raises(tgsis.InvalidInputError, match="EVOLVING"):
        tgsis.delete_instant(tx, mid, 0.0)
    with pytest.raises(tgsis.NotFoundError):
        tgsis.delete_instant(tx, 987654, 0.0)
    with pytest.raises(tgsis.InvalidInputError, match="INSTANTS"):
        tgsis.insert_feature(tx, moving, series(np.random.default_rng(9), [0.0]))
    with pytest.raises(tgsis.NotFoundError, match="nowhere"):
        tgsis.features_at(tx, "nowhere", 0.0)
    with pytest.raises(tgsis.InvalidInputError, match="not surfaces"):
        tgsis.surfaces_at(tx, lines, 0.0)
    with pytest.raises(tgsis.InvalidInputError, match="NaN"):
        tgsis.features_at(tx, horizons, float("nan"))
    assert snapshot() == before
