"""Hostile review of the merge by region of models 2 and 3 (issue 39): defects found, each pinned by a test."""

from __future__ import annotations

from typing import Any

import numpy as np
import psycopg
import pytest

import tgsis
from tests.merge_data import SIDE, curved_surface
from tests.test_merge_instants import (
    CHILD_SHIFT,
    NORTH,
    PARENT_SHIFT,
    SOUTH,
    _shape,
    geometry_instants,
    instants,
    make_evolving,
    move,
    move3,
    shifted,
)

Conn = psycopg.Connection[Any]


@pytest.fixture
def series(conn: Conn, series_clone: int) -> int:
    return series_clone  # make_series's, built once (tests/conftest.py)


def _sql_resolve(conn: Conn, geoid: int, solution: str) -> psycopg.Error | None:
    """``tgsis.resolve_conflict`` as a psql user runs it (nobody ran the Python client): the error, or None."""
    conn.execute("SELECT tgsis.find_conflicts('e1')")
    conn.commit()
    try:
        conn.execute("SELECT tgsis.resolve_conflict('e1', 'feature', %s, %s)", (str(geoid), solution))
    except psycopg.Error as exc:
        conn.rollback()
        return exc
    conn.commit()
    return None


def test_sql_child_on_a_series_refuses_to_drop_the_parents_edits_at_other_instants(conn: Conn, series: int) -> None:
    """psql only: ``resolve_conflict(..., 'child')`` dropped the parent's edit of instant 3, which merges by itself."""
    move(conn, "e1", series, 2.0, NORTH, CHILD_SHIFT)
    move(conn, "DEFAULT", series, 2.0, NORTH[:SIDE], PARENT_SHIFT)
    move(conn, "DEFAULT", series, 3.0, SOUTH, PARENT_SHIFT)
    error = _sql_resolve(conn, series, "child")
    assert error is not None and error.sqlstate == "TG307"
    assert "parent's edits of instant 3" in str(error)
    assert conn.execute("SELECT solution FROM tgsis.conflicts").fetchall() == [("unsolved",)]
    # the merge by region keeps it: region 0 (instant 2) solved child, instant 3 taken from the parent
    tgsis.find_conflicts(conn, "e1")
    tgsis.resolve_region(conn, "e1", series, 0, "child")
    tgsis.merge_version(conn, "e1")
    got = instants(conn, "DEFAULT", series)
    assert got[3.0][1].tobytes() == shifted(_shape(2), SOUTH, PARENT_SHIFT).tobytes()
    assert got[2.0][1].tobytes() == shifted(_shape(1), NORTH, CHILD_SHIFT).tobytes()


def test_sql_parent_on_a_series_refuses_to_drop_an_instant_the_version_added(conn: Conn, series: int) -> None:
    new = tgsis.Surface(_shape(7), curved_surface().cells, vertex_properties={"porosity": np.zeros(len(_shape(7)))})
    with tgsis.in_version(conn, "e1"):
        tgsis.add_instant(conn, "horizons", series, 4.0, new, {"throw": 44.0})
    conn.commit()
    move(conn, "e1", series, 2.0, NORTH, CHILD_SHIFT)
    move(conn, "DEFAULT", series, 2.0, NORTH[:SIDE], PARENT_SHIFT)
    error = _sql_resolve(conn, series, "parent")
    assert error is not None and error.sqlstate == "TG307"
    assert "version's edits of instant 4" in str(error)


def test_sql_child_on_a_series_is_allowed_when_the_parent_changed_conflicting_instants_only(
    conn: Conn, series: int
) -> None:
    move(conn, "e1", series, 2.0, NORTH, CHILD_SHIFT)
    move(conn, "e1", series, 3.0, SOUTH, CHILD_SHIFT)  # the version's alone: child keeps it
    move(conn, "DEFAULT", series, 2.0, NORTH[:SIDE], PARENT_SHIFT)
    assert _sql_resolve(conn, series, "child") is None
    assert conn.execute("SELECT solution FROM tgsis.conflicts").fetchall() == [("child",)]


def test_sql_child_stays_the_way_out_of_an_object_level_conflict(conn: Conn, series: int) -> None:
    """An instant removed on one side and changed on the other: the whole-object solution the refusal names."""
    with tgsis.in_version(conn, "e1"):
        tgsis.delete_instant(conn, series, 2.0)
    conn.commit()
    move(conn, "DEFAULT", series, 2.0, SOUTH, PARENT_SHIFT)
    move(conn, "DEFAULT", series, 3.0, SOUTH, PARENT_SHIFT)
    assert _sql_resolve(conn, series, "child") is None


def test_sql_child_on_an_evolving_surface_refuses_to_drop_a_geometry_instant_only_the_parent_moved(
    conn: Conn,
) -> None:
    geoid = make_evolving(conn)
    move3(conn, "e1", geoid, 2.0, NORTH, CHILD_SHIFT)
    move3(conn, "DEFAULT", geoid, 2.0, NORTH[:SIDE], PARENT_SHIFT)
    move3(conn, "DEFAULT", geoid, 3.0, SOUTH, PARENT_SHIFT)
    error = _sql_resolve(conn, geoid, "child")
    assert error is not None and error.sqlstate == "TG307"
    assert "geometry instant 3 of the period starting at 1" in str(error)
    assert _sql_resolve(conn, geoid, "parent") is None  # the version changed nothing the parent did not


def test_python_child_on_a_series_refuses_to_drop_the_parents_edits_at_other_instants(conn: Conn, series: int) -> None:
    move(conn, "e1", series, 2.0, NORTH, CHILD_SHIFT)
    move(conn, "DEFAULT", series, 2.0, NORTH[:SIDE], PARENT_SHIFT)
    move(conn, "DEFAULT", series, 3.0, SOUTH, PARENT_SHIFT)
    tgsis.find_conflicts(conn, "e1")
    conn.commit()
    with pytest.raises(tgsis.Error):
        tgsis.resolve_conflict(conn, "e1", "feature", series, "child")
    conn.rollback()


def test_signed_zero_tiny_integer_and_null_properties_survive_a_merge_per_instant(conn: Conn) -> None:
    """Disjoint edits of one instant: -0.0, subnormal-range and integer vertex properties, per-instant rows."""
    tgsis.create_feature_class(
        conn,
        "layers",
        "SURFACE",
        time_model="INSTANTS",
        cell_properties=[("nx", "float8"), ("nz", "float8"), ("facies", "integer")],
        instant_properties=[("label", "double precision"), ("n", "integer")],
    )
    tgsis.enable_feature_versioning(conn)
    cells = curved_surface().cells
    nv = len(_shape(0))
    surfaces = [
        tgsis.Surface(
            _shape(i),
            cells,
            vertex_properties={"nx": np.full(nv, -0.0), "nz": np.arange(nv) * 1e-300, "facies": np.arange(nv) % 5},
        )
        for i in range(2)
    ]
    from tgsis.temporal import SurfaceSeries

    series = SurfaceSeries(
        np.asarray([0.0, 1e-300]),
        surfaces,
        properties={"label": np.asarray([-0.0, 0.1]), "n": np.asarray([1, 2])},
    )
    geoid = tgsis.insert_feature(conn, "layers", series)
    tgsis.create_version(conn, "e1")
    conn.commit()

    def dump(version: str) -> list[tuple[Any, ...]]:
        with tgsis.in_version(conn, version):
            rows = conn.execute(
                "SELECT _times, _idx, nx::text, nz, facies FROM layers_cellpros WHERE _geoid = %s ORDER BY 1, 2",
                (geoid,),
            ).fetchall()
            rows += conn.execute(
                "SELECT _times, label, n FROM layers_pros WHERE _geoid = %s ORDER BY 1", (geoid,)
            ).fetchall()
        conn.commit()
        return rows

    before = dump("DEFAULT")
    move(conn, "e1", geoid, 1e-300, NORTH, CHILD_SHIFT)
    move(conn, "DEFAULT", geoid, 1e-300, SOUTH, PARENT_SHIFT)
    with tgsis.in_version(conn, "e1"):
        conn.execute("UPDATE layers_pros SET n = 7 WHERE _geoid = %s AND _times = 1e-300", (geoid,))
    conn.commit()
    tgsis.merge_version(conn, "e1")
    after = dump("DEFAULT")
    expected = [r if len(r) == 5 or r[0] == 0.0 else (r[0], r[1], 7) for r in before]
    assert after == expected
    got = instants(conn, "DEFAULT", geoid)
    assert sorted(got) == [0.0, 1e-300]
    assert got[1e-300][1].tobytes() == shifted(shifted(_shape(1), NORTH, CHILD_SHIFT), SOUTH, PARENT_SHIFT).tobytes()


def test_sql_base_on_a_series_refuses_to_drop_an_edit_that_merges_by_itself(conn: Conn, series: int) -> None:
    """``base`` throws both sides' edits away: not those of an instant only one side changed."""
    move(conn, "e1", series, 2.0, NORTH, CHILD_SHIFT)
    move(conn, "DEFAULT", series, 2.0, NORTH[:SIDE], PARENT_SHIFT)
    move(conn, "e1", series, 1.0, SOUTH, CHILD_SHIFT)
    before = instants(conn, "e1", series)
    error = _sql_resolve(conn, series, "base")
    assert error is not None and error.sqlstate == "TG307"
    assert "instant 1" in str(error)
    after = instants(conn, "e1", series)
    assert {t: v[1].tobytes() for t, v in before.items()} == {t: v[1].tobytes() for t, v in after.items()}


def test_sql_child_stays_the_way_out_of_a_period_topology_refusal(conn: Conn) -> None:
    """TG308 (a geometry instant added to a period whose topology the other side changed) names resolve_conflict."""
    geoid = make_evolving(conn)
    with tgsis.in_version(conn, "DEFAULT"):
        conn.execute("DELETE FROM tgsis.d4dtrgl WHERE geoid = %s AND trglid = 0", (geoid,))
    conn.commit()
    with tgsis.in_version(conn, "e1"):
        conn.execute("INSERT INTO tgsis.timet VALUES (%s, 1.0, 2.5)", (geoid,))
        conn.execute(
            "INSERT INTO tgsis.d4dvrtx SELECT geoid, timem, 2.5, nodeid, x, y, z FROM tgsis.d4dvrtx"
            " WHERE geoid = %s AND timet = 2.0",
            (geoid,),
        )
        conn.execute(
            "INSERT INTO evolving_cellpros SELECT _geoid, _timem, 2.5, _idx, porosity FROM evolving_cellpros"
            " WHERE _geoid = %s AND _timet = 2.0",
            (geoid,),
        )
    conn.commit()
    with pytest.raises(tgsis.PeriodTopologyError):
        tgsis.merge_version(conn, "e1")
    conn.rollback()
    assert _sql_resolve(conn, geoid, "child") is None
    tgsis.merge_version(conn, "e1")
    assert sorted(geometry_instants(conn, "DEFAULT", geoid)) == [(1.0, 1.0), (1.0, 2.0), (1.0, 2.5), (1.0, 3.0)]


def test_sql_child_stays_the_way_out_of_a_per_instant_property_set_on_both_sides(conn: Conn, series: int) -> None:
    """The Python merge refuses it (object level) and names resolve_conflict: the SQL check must not refuse too."""
    for version, throw in (("e1", 21.0), ("DEFAULT", 22.0)):
        with tgsis.in_version(conn, version):
            conn.execute("UPDATE horizons_pros SET throw = %s WHERE _geoid = %s AND _times = 2", (throw, series))
        conn.commit()
    move(conn, "DEFAULT", series, 3.0, SOUTH, PARENT_SHIFT)
    [conflict] = tgsis.find_conflicts(conn, "e1")
    conn.commit()
    assert "changed on both sides" in (conflict.region_refusal or "")
    assert _sql_resolve(conn, series, "child") is None
