"""The library works whatever the session's ``search_path``: an empty one, or one without the cube extension.

tgsis's SQL functions pin their own ``search_path``; the statements the
Python library composes must name the cube extension's functions and type
by their schema, since a DBA may install cube elsewhere and a user may
empty the path (``SET search_path = ''``, as security-minded tools do).
Each test writes and reads with the path empty and compares with what the
same calls give under the default path.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import psycopg
import pytest

import tgsis
from tests.gmaps_shapes import block_tetrahedra
from tests.synthetic import flat_grid
from tests.temporal_data import grid, series
from tgsis.db.inspect import geometry_summary, list_features

Conn = psycopg.Connection[Any]


@pytest.fixture
def empty_path(tx: Conn) -> Conn:
    tx.execute("SET LOCAL search_path = ''")
    return tx


def test_a_feature_summary_and_list_read_the_box(tx: Conn) -> None:
    faults = tgsis.create_feature_class(tx, "faults", "SURFACE")
    surface = flat_grid(4, 2.5)
    fid = tgsis.insert_feature(tx, "faults", surface)
    expected = geometry_summary(tx, fid)
    listed = list_features(tx, faults)
    tx.execute("SET LOCAL search_path = ''")
    # was: function cube_ll_coord(tgsis.cube, integer) does not exist
    assert geometry_summary(tx, fid) == expected
    assert expected.box[4:6] == (2.5, 2.5)
    assert list_features(tx, faults) == listed


def test_an_instant_added_grows_the_box(tx: Conn) -> None:
    tgsis.create_feature_class(tx, "stepped", "SURFACE", time_model="INSTANTS")
    fid = tgsis.insert_feature(tx, "stepped", series(np.random.default_rng(3), [0.0, 1.0]))
    vertices, triangles = grid(4)
    vertices[:, 2] = 1000.0
    tx.execute("SET LOCAL search_path = ''")
    # was: function cube(double precision[], double precision[]) does not exist
    tgsis.add_instant(tx, "stepped", fid, 2.0, tgsis.Surface(vertices, triangles))
    tx.execute("RESET search_path")
    assert geometry_summary(tx, fid).box[5] == 1000.0
    assert [t for t, _ in tgsis.instants(tx, fid)] == [0.0, 1.0, 2.0]


def test_a_multidimensional_gmap_is_stored_with_its_extent(tx: Conn) -> None:
    tgsis.create_feature_class(tx, "knowledge", "GMAP", time_model="MULTIDIM", cell_level=3)
    solid = tgsis.GMap.from_tetrahedra(*block_tetrahedra(1))
    points = np.column_stack([solid.points, np.arange(solid.n_points) % 2])
    tx.execute("SET LOCAL search_path = ''")
    # was: type "cube" does not exist
    gid = tgsis.insert_gmap(tx, "knowledge", tgsis.GMap(solid.alpha, solid.vertex, points), axes=["x", "y", "z", "k"])
    tx.execute("RESET search_path")
    low, high = tx.execute(
        "SELECT cube_ll_coord(extent, 4), cube_ur_coord(extent, 4) FROM tgsis.md_gmap WHERE geoid = %s", (gid,)
    ).fetchone() or (None, None)
    assert (low, high) == (0.0, 1.0)
