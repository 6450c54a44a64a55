"""What the browser view sends: binary typed arrays that are the database's mesh (issue 21).

The body's layout (tgsis.view.meshes) read back as the browser reads it; a
tetrahedral mesh drawn by its boundary; and the endpoint's arrays against
what :func:`tgsis.fetch_feature` and :func:`tgsis.get_at` give from the
same database: positions to float32 precision around the box's middle,
triangles exactly, a property's values, the snapshot at t.
"""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np
import psycopg
import pytest

import tgsis
from tests.view_helpers import ViewData, fill_view_database, get, running_view
from tgsis.drawing import drawable, tetra_boundary, vertex_flags
from tgsis.testing import TestServer
from tgsis.view.meshes import pack, unpack


def test_a_body_holds_its_header_and_little_endian_arrays() -> None:
    positions = np.arange(12, dtype=np.float64).reshape(4, 3) / 3
    body = pack(
        {"kind": "triangles", "origin": [1e6, 2e6, -3.5]},
        {"positions": positions, "indices": np.array([[0, 1, 2], [0, 2, 3]])},
    )
    header, arrays = unpack(body)
    assert header["kind"] == "triangles" and header["origin"] == [1e6, 2e6, -3.5]
    assert [(a["name"], a["type"], a["count"]) for a in header["arrays"]] == [
        ("positions", "float32", 12),
        ("indices", "uint32", 6),
    ]
    assert (4 + int.from_bytes(body[:4], "little")) % 4 == 0
    assert arrays["positions"].dtype == np.dtype("<f4")
    np.testing.assert_array_equal(arrays["positions"], positions.ravel().astype(np.float32))
    np.testing.assert_array_equal(arrays["indices"], [0, 1, 2, 0, 2, 3])
    with pytest.raises(ValueError):
        pack({"t": float("nan")}, {})  # strict JSON: the browser's JSON.parse refuses NaN


def test_a_tetrahedral_mesh_is_drawn_by_its_boundary() -> None:
    # two tetrahedra sharing the face (1, 2, 3): 8 faces, 6 on the boundary
    faces, owner = tetra_boundary([[0, 1, 2, 3], [4, 1, 2, 3]])
    assert len(faces) == 6
    assert not any(sorted(f) == [1, 2, 3] for f in faces.tolist())
    assert sorted(owner.tolist()) == [0, 0, 0, 1, 1, 1]
    mesh = tgsis.TetraMesh(np.eye(4, 3).tolist() + [[1, 1, 1]], [[0, 1, 2, 3], [4, 1, 2, 3]])
    d = drawable(mesh)
    assert d.kind == "triangles" and d.indices.shape == (6, 3)


def test_a_collection_draws_its_surfaces_as_one_mesh() -> None:
    a = tgsis.Surface([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]], vertex_properties={"p": [1.0, 2, 3]})
    b = tgsis.Surface([[0, 0, 1], [1, 0, 1], [0, 1, 1]], [[0, 2, 1]], vertex_properties={"p": [4.0, 5, 6]})
    line = tgsis.LineSet([[0, 0, 0], [1, 1, 1]], [[0, 1]])
    d = drawable(tgsis.GeometryCollection([a, line, b]))
    assert d.kind == "triangles"
    np.testing.assert_array_equal(d.indices, [[0, 1, 2], [3, 5, 4]])
    np.testing.assert_array_equal(d.vertex_values["p"], [1, 2, 3, 4, 5, 6])


def test_vertex_flags_add_up() -> None:
    np.testing.assert_array_equal(vertex_flags(5, [(1, [0, 1, 1]), (2, [1, 4])]), [1, 3, 0, 0, 2])


@pytest.fixture(scope="module")
def view(pg: TestServer, template_db: str) -> Iterator[tuple[str, ViewData, str]]:
    with pg.database("tgsis_view_meshes", template_db) as (_, dsn):
        data = fill_view_database(dsn)
        with running_view(dsn) as url:
            yield url, data, dsn


def test_the_endpoint_sends_the_stored_surface_and_property(view: tuple[str, ViewData, str]) -> None:
    url, data, dsn = view
    status, body, kind = get(f"{url}/api/mesh/{data.top}?color=porosity")
    assert status == 200 and kind == "application/octet-stream"
    header, arrays = unpack(body)
    with psycopg.connect(dsn) as conn:
        mesh = tgsis.fetch_feature(conn, "horizons", data.top).mesh
    assert isinstance(mesh, tgsis.Surface)
    assert header["n_vertices"] == mesh.n_vertices and header["kind"] == "triangles"
    xyz = arrays["positions"].reshape(-1, 3).astype(np.float64) + header["origin"]
    np.testing.assert_allclose(xyz, mesh.vertices, atol=1e-5)

    # the triangles in no promised order (their corners travel packed), each with its orientation
    def oriented(t: np.ndarray) -> list[tuple[int, ...]]:
        return sorted(tuple(np.roll(row, -int(np.argmin(row))).tolist()) for row in np.asarray(t).reshape(-1, 3))

    assert oriented(arrays["indices"]) == oriented(mesh.triangles)
    np.testing.assert_allclose(arrays["values"], mesh.vertex_properties["porosity"], rtol=1e-6)
    status, body, kind = get(f"{url}/api/mesh/{data.top}/header")
    assert status == 200 and kind == "application/json"


def test_the_endpoint_sends_the_sql_snapshot_at_t(view: tuple[str, ViewData, str]) -> None:
    url, data, dsn = view
    with psycopg.connect(dsn) as conn:
        for t in (-10.0, -2.5, 0.0):
            status, body, _ = get(f"{url}/api/mesh/{data.moving}?t={t}")
            assert status == 200
            header, arrays = unpack(body)
            shape = tgsis.get_at(conn, data.moving, t)
            assert shape is not None and header["t"] == t
            np.testing.assert_allclose(
                arrays["positions"].reshape(-1, 3) + np.asarray(header["origin"]), shape.vertices, atol=1e-5
            )
    # outside its life (a scene's slider spans every feature's): an empty body, not an error
    status, body, _ = get(f"{url}/api/mesh/{data.moving}?t=-11")
    header, arrays = unpack(body)
    assert status == 200 and header["kind"] == "none" and arrays == {}
    assert get(f"{url}/api/mesh/{data.moving}")[0] == 200  # no t: its last instant


def test_the_endpoint_in_a_version_sends_what_that_version_holds(view: tuple[str, ViewData, str]) -> None:
    url, data, _ = view
    default = unpack(get(f"{url}/api/mesh/{data.top}")[1])
    edited = unpack(get(f"{url}/api/mesh/{data.top}?v=edit")[1])
    z = [h["origin"][2] + a["positions"].reshape(-1, 3)[:, 2] for h, a in (default, edited)]
    # edit lifted the west by 3; DEFAULT then lowered the east by 2, which edit (based before it) does not see
    assert np.unique(np.round(z[1] - z[0], 3)).tolist() == [0, 2, 3]
    assert get(f"{url}/api/mesh/{data.top}?v=nope")[0] == 404
