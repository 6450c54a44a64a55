"""Models 2 and 3 under versioning: evolving surfaces and surfaces at instants edited in child versions."""

from __future__ import annotations

from typing import Any

import numpy as np
import psycopg
import pytest

import tgsis
from tests.temporal_data import evolving, series

Conn = psycopg.Connection[Any]
STARTS = [0.0, 2.0]


@pytest.fixture
def classes(conn: Conn) -> tuple[tgsis.FeatureClass, tgsis.FeatureClass]:
    moving = tgsis.create_feature_class(
        conn,
        "moving",
        "SURFACE",
        time_model="EVOLVING",
        cell_properties=[("porosity", "double precision")],
        instant_properties=[("throw", "double precision"), ("note_code", "integer")],
    )
    stepped = tgsis.create_feature_class(
        conn,
        "stepped",
        "SURFACE",
        time_model="INSTANTS",
        cell_properties=[("porosity", "double precision")],
        instant_properties=[("throw", "double precision")],
    )
    tgsis.enable_feature_versioning(conn)
    return moving, stepped


def test_tables_are_versioned_with_the_feature_object_class(conn: Conn, classes: Any) -> None:
    versioned = {(t.schema, t.table): t.objectclass for t in tgsis.versioned_tables(conn)}
    for table in ("times", "times_vrtx", "times_trgl", "timem", "timet", "node", "d4dtrgl", "d4dvrtx"):
        assert versioned[("tgsis", table)] == "feature"
    for table in ("moving_pros", "moving_cellpros", "stepped_pros", "stepped_cellpros"):
        assert versioned[("public", table)] == "feature"


def test_evolving_surface_edited_in_a_child_version(conn: Conn, classes: Any) -> None:
    moving, _ = classes
    surface = evolving(np.random.default_rng(5), STARTS, instants_per_period=3, with_properties=True)
    fid = tgsis.insert_feature(conn, moving, surface)
    t = 1.3
    expected = surface.at(t)
    assert expected is not None
    tgsis.create_version(conn, "reinterpretation")
    with tgsis.in_version(conn, "reinterpretation"):
        # a psql user lifts the nodes of the first period at its last geometry instant
        conn.execute(
            "UPDATE tgsis.d4dvrtx SET z = z + 10 WHERE geoid = %s AND timem = %s AND timet = %s",
            (fid, STARTS[0], STARTS[1]),
        )
        conn.execute("UPDATE moving_pros SET throw = -1 WHERE _geoid = %s", (fid,))
        conn.commit()
        edited = tgsis.get_at(conn, fid, t)
        first = tgsis.get_at(conn, fid, 0.0)
    default = tgsis.get_at(conn, fid, t)
    assert default is not None and edited is not None and first is not None
    np.testing.assert_array_equal(default.vertices, expected.vertices)
    p = surface.periods[0]
    j1 = int(np.searchsorted(p.times, t))
    w = (t - p.times[j1 - 1]) / (p.times[j1] - p.times[j1 - 1])
    moved = p.positions.copy()
    moved[-1, :, 2] += 10  # only the last instant of period 0 was edited
    lifted = moved[j1 - 1] + w * (moved[j1] - moved[j1 - 1])
    np.testing.assert_allclose(edited.vertices, lifted, rtol=0, atol=1e-12)
    np.testing.assert_array_equal(first.vertices, p.positions[0])  # instants not edited stay
    assert conn.execute("SELECT count(*) FROM moving_pros WHERE throw = -1").fetchone() == (0,)

    tgsis.merge_version(conn, "reinterpretation")
    merged = tgsis.get_at(conn, fid, t)
    assert merged is not None
    np.testing.assert_array_equal(merged.vertices, edited.vertices)
    assert conn.execute("SELECT count(*) FROM moving_pros WHERE _geoid = %s AND throw = -1", (fid,)).fetchone() == (
        sum(len(q.times) for q in surface.periods),
    )


def test_uploads_and_deletes_inside_a_version(conn: Conn, classes: Any) -> None:
    moving, stepped = classes
    kept = tgsis.insert_feature(conn, stepped, series(np.random.default_rng(6), [-3.0, -1.0], with_properties=True))
    tgsis.create_version(conn, "v1")
    with tgsis.in_version(conn, "v1"):
        surface = evolving(np.random.default_rng(7), STARTS, with_properties=True)
        new = tgsis.insert_feature(conn, moving, surface)
        assert tgsis.delete_instant(conn, kept, -1.0)
        conn.commit()
        got = tgsis.get_at(conn, new, 2.5)
        local = surface.at(2.5)
        assert got is not None and local is not None
        np.testing.assert_array_equal(got.vertices, local.vertices)
        assert tgsis.get_at(conn, kept, -0.5) is None  # its last instant (-1) is gone in v1
        assert tgsis.features_at(conn, moving, 1.0) == [new]
    assert tgsis.features_at(conn, moving, 1.0) == []  # DEFAULT does not see v1's feature
    assert conn.execute("SELECT count(*) FROM tgsis.geometry WHERE geoid = %s", (new,)).fetchone() == (0,)
    with pytest.raises(tgsis.NotFoundError):
        tgsis.get_at(conn, new, 1.0)
    assert [t for t, _ in tgsis.instants(conn, kept)] == [-3.0, -1.0]


def test_same_surface_edited_in_two_versions_conflicts(conn: Conn, classes: Any) -> None:
    moving, _ = classes
    fid = tgsis.insert_feature(conn, moving, evolving(np.random.default_rng(8), STARTS, with_properties=True))
    tgsis.create_version(conn, "a")
    with tgsis.in_version(conn, "a"):
        conn.execute("UPDATE tgsis.d4dvrtx SET x = x + 1 WHERE geoid = %s AND nodeid = 0", (fid,))
        conn.commit()
    conn.execute("UPDATE tgsis.d4dvrtx SET x = x - 1 WHERE geoid = %s AND nodeid = 0", (fid,))
    conn.commit()
    conflicts = tgsis.find_conflicts(conn, "a")
    assert [(c.objectclass, str(c.objectkey)) for c in conflicts] == [("feature", str(fid))]
    with pytest.raises(tgsis.UnsolvedConflictsError):
        tgsis.merge_version(conn, "a")
