"""G-maps in the browser view: model 4 through time (the SQL snapshot at t) and model 5 (extra axes as colours).

What is drawn of a G-map (tgsis.drawing.gmap_drawable: a surface's faces,
a solid's border, fan-triangulated), the endpoint against the snapshot
``tgsis.gmap_at`` gives from the same database, and the scene in headless
Chromium: drawn, and redrawn when the time slider moves.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any

import numpy as np
import psycopg
import pytest

import tgsis
from tests.gmaps_shapes import block_tetrahedra, octahedron
from tests.view_helpers import (
    canvas_pixels,
    changed_fraction,
    chromium,
    drawn_fraction,
    get,
    running_view,
    wait_drawn,
    watched_page,
)
from tgsis import gmaps
from tgsis.drawing import gmap_drawable
from tgsis.testing import TestServer
from tgsis.view.meshes import unpack


def test_a_surface_draws_its_faces_and_a_solid_its_border() -> None:
    surface = gmaps.GMap.from_triangles(*octahedron())
    d = gmap_drawable(surface)
    assert d.kind == "triangles" and d.indices.shape == (8, 3) and d.cell_rows.tolist() == list(range(8))
    np.testing.assert_array_equal(np.sort(d.indices, axis=1), np.sort(surface.simplices(), axis=1))
    vertices, tetrahedra = block_tetrahedra(2)  # 2 x 2 x 2 cubes: 6 sides of 4 squares of 2 triangles
    d = gmap_drawable(gmaps.GMap.from_tetrahedra(vertices, tetrahedra))
    assert d.indices.shape == (48, 3)
    corners = vertices[d.indices]  # (48, 3 corners, 3 coordinates)
    on_a_side = [(corners[:, :, k] == side).all(axis=1) for k in range(3) for side in (0.0, 2.0)]
    assert np.sum(on_a_side, axis=0).tolist() == [1] * 48  # every triangle on one side of the block, none inside


def test_the_axes_beyond_z_become_values_to_colour_by() -> None:
    surface = gmaps.GMap.from_triangles(*octahedron())
    lifted = gmaps.GMap(surface.alpha, surface.vertex, np.column_stack([surface.points, np.arange(6), -np.arange(6)]))
    d = gmap_drawable(lifted, ("x", "y", "z", "knowledge", "scale"))
    np.testing.assert_array_equal(d.vertices, surface.points)
    assert sorted(d.vertex_values) == ["knowledge", "scale"]
    np.testing.assert_array_equal(d.vertex_values["knowledge"], np.arange(6))
    with pytest.raises(tgsis.InvalidInputError, match="a 4-G-map is not drawn"):
        gmap_drawable(gmaps.extrude(gmaps.GMap.from_tetrahedra(*block_tetrahedra(1)), [0.0, 1.0]))


@dataclass(frozen=True)
class GMapData:
    moving: int  # model 4: a block of tetrahedra growing from t = 0 to t = 1, then a cube at t = 1 (ends)
    history: int  # model 5: a surface with a knowledge axis


@pytest.fixture(scope="module")
def view(pg: TestServer, template_db: str) -> Iterator[tuple[str, GMapData, str]]:
    with pg.database("tgsis_view_gmaps", template_db) as (_, dsn):
        with psycopg.connect(dsn) as conn:
            tgsis.create_feature_class(conn, "blocks", "GMAP", time_model="GMAP", cell_level=3)
            tgsis.create_feature_class(conn, "knowledge", "GMAP", time_model="MULTIDIM", cell_level=2)
            block = gmaps.GMap.from_tetrahedra(*block_tetrahedra(2))
            cube = gmaps.GMap.from_tetrahedra(*block_tetrahedra(1))
            moving = tgsis.insert_feature(
                conn,
                "blocks",
                gmaps.EvolvingGMap(
                    [
                        gmaps.GMapPeriod([0.0, 1.0], block, np.stack([block.points, block.points * [3, 1, 2]])),
                        gmaps.GMapPeriod([1.0], cube, (cube.points * 4)[None]),
                    ],
                    name="growing block",
                ),
                tolerance=100.0,
            )  # a jump at t = 1, allowed: the viewer shows it
            surface = gmaps.GMap.from_triangles(*octahedron())
            history = tgsis.insert_gmap(
                conn,
                "knowledge",
                gmaps.GMap(surface.alpha, surface.vertex, np.column_stack([surface.points, np.arange(6) / 5])),
                axes=["x", "y", "z", "knowledge"],
                name="interpretations",
            )
            conn.commit()
        with running_view(dsn) as url:
            yield url, GMapData(moving, history), dsn


def test_the_endpoint_sends_the_sql_snapshot_of_a_g_map_at_t(view: tuple[str, GMapData, str]) -> None:
    url, data, dsn = view
    with psycopg.connect(dsn) as conn:
        for t in (0.0, 0.5, 1.0):
            status, body, _ = get(f"{url}/api/mesh/{data.moving}?t={t}")
            assert status == 200
            header, arrays = unpack(body)
            snapshot = tgsis.gmap_at(conn, data.moving, t)
            assert snapshot is not None and header["t"] == t and header["kind"] == "triangles"
            np.testing.assert_allclose(
                arrays["positions"].reshape(-1, 3) + np.asarray(header["origin"]), snapshot.points, atol=1e-5
            )
            np.testing.assert_array_equal(arrays["indices"].reshape(-1, 3), gmap_drawable(snapshot).indices)
    assert unpack(get(f"{url}/api/mesh/{data.moving}?t=1.5")[1])[0]["kind"] == "none"  # not alive after 1
    assert unpack(get(f"{url}/api/mesh/{data.moving}?t=1")[1])[0]["n_vertices"] == 8  # the cube from t = 1
    header, arrays = unpack(get(f"{url}/api/mesh/{data.history}")[1])
    assert header["kind"] == "triangles" and header["n_cells"] == 8 and header["properties"] == ["knowledge"]
    header, arrays = unpack(get(f"{url}/api/mesh/{data.history}?color=knowledge")[1])
    np.testing.assert_allclose(arrays["values"], np.arange(6) / 5, rtol=1e-6)


def test_the_classes_page_gives_a_g_map_its_life(view: tuple[str, GMapData, str]) -> None:
    url, data, _ = view
    status, body, _ = get(f"{url}/classes?class=blocks")
    assert status == 200 and b"growing block" in body


@pytest.fixture(scope="module")
def browser() -> Iterator[Any]:
    with chromium() as b:
        yield b


@pytest.fixture
def page(browser: Any) -> Iterator[Any]:
    with watched_page(browser, 900, 700) as page:
        yield page


def test_a_g_map_moves_through_time_in_the_scene(view: tuple[str, GMapData, str], page: Any) -> None:
    url, data, _ = view
    page.goto(f"{url}/scene?ids={data.moving}&t=0")
    wait_drawn(page)
    assert page.text_content("#status").startswith("t = 0: ")
    at_start = canvas_pixels(page)
    assert drawn_fraction(at_start) > 0.02
    page.locator("#time").fill("1")
    wait_drawn(page, 2)
    assert page.text_content("#status").startswith("t = 1: ")
    assert changed_fraction(at_start, canvas_pixels(page)) > 0.01


def test_a_model_5_map_is_drawn(view: tuple[str, GMapData, str], page: Any) -> None:
    url, data, _ = view
    page.goto(f"{url}/scene?ids={data.history}")
    wait_drawn(page)
    by_height = canvas_pixels(page)
    assert drawn_fraction(by_height) > 0.02
    page.goto(f"{url}/scene?ids={data.history}&color=knowledge")  # the knowledge axis as a colour
    wait_drawn(page)
    assert changed_fraction(by_height, canvas_pixels(page)) > 0.01
