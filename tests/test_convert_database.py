"""insert_feature, save_feature and checkin take pyvista, meshio and trimesh objects (issue 19, part 1).

Found: ``tgsis.insert_feature(conn, "horizons", pyvista.Sphere())`` raised
``AttributeError: 'PolyData' object has no attribute 'geotype'`` (and
``save_feature``/``checkin`` "an edited mesh must be a PointSet, ..., not
PolyData"). Now the object is converted (tgsis.as_mesh) before anything is
written; what cannot be converted raises our error and writes nothing.
"""

from __future__ import annotations

from typing import Any

import meshio
import numpy as np
import psycopg
import pytest
import pyvista as pv
import trimesh

import tgsis
from tests.fetched import geometry_of, mesh_of
from tgsis.db import features as F

Conn = psycopg.Connection[Any]


def grid(side: int = 12) -> pv.PolyData:
    """A bumpy horizon as pyvista makes one (float32 points of a triangulated plane), with a porosity array."""
    plane: pv.PolyData = pv.Plane(i_size=1000, j_size=1000, i_resolution=side, j_resolution=side).triangulate()
    plane.points[:, 2] = np.sin(plane.points[:, 0] / 200.0) * 50.0  # type: ignore[index]  # pyvista stub, as below
    plane.point_data.clear()
    plane["porosity"] = np.linspace(0.1, 0.3, plane.n_points)
    return plane


def stored(conn: Conn) -> tuple[int, int, int]:
    row = conn.execute(
        "SELECT (SELECT count(*) FROM tgsis.geometry), (SELECT count(*) FROM tgsis.vrtx), "
        "(SELECT count(*) FROM tgsis.trgl)"
    ).fetchone()
    assert row is not None
    return int(row[0]), int(row[1]), int(row[2])


@pytest.fixture
def horizons(conn: Conn) -> F.FeatureClass:
    fc = F.create_feature_class(
        conn, "horizons", "SURFACE", feature_properties={"model": "text"}, cell_properties={"porosity": "float8"}
    )
    conn.commit()
    return fc


def test_insert_a_pyvista_surface_and_get_it_back_as_one(conn: Conn, horizons: F.FeatureClass) -> None:
    surface = grid()
    surface.field_data["name"] = ["H1"]
    fid = tgsis.insert_feature(conn, "horizons", surface, {"model": "gempy"})
    conn.commit()
    feature = tgsis.fetch_feature(conn, "horizons", fid)
    assert feature.mesh is not None and feature.mesh.name == "H1" and feature.properties == {"model": "gempy"}
    back = feature.mesh.to_pyvista()
    assert isinstance(back, pv.PolyData) and back.n_cells == surface.n_cells
    assert np.array_equal(back.points, surface.points.astype(np.float64))
    assert np.array_equal(back.regular_faces, surface.regular_faces)
    assert np.array_equal(back["porosity"], surface["porosity"])


def test_insert_meshio_and_trimesh_objects(conn: Conn, horizons: F.FeatureClass) -> None:
    plane = grid(4)
    m = meshio.Mesh(plane.points, [("triangle", plane.regular_faces)], point_data={"porosity": plane["porosity"]})
    t = trimesh.Trimesh(
        plane.points, plane.regular_faces, process=False, vertex_attributes={"porosity": plane["porosity"]}
    )
    obj: Any  # insert_feature takes what tgsis.as_mesh takes; its signature names tgsis's own types only
    for obj in (m, t):
        fid = tgsis.insert_feature(conn, horizons, obj)
        mesh = tgsis.fetch_feature(conn, horizons, fid).mesh
        assert isinstance(mesh, tgsis.Surface) and np.array_equal(mesh.cells, plane.regular_faces)
        assert np.array_equal(mesh.vertex_properties["porosity"], plane["porosity"])


def test_save_and_checkin_take_edited_pyvista_and_meshio_objects(conn: Conn, horizons: F.FeatureClass) -> None:
    fid = tgsis.insert_feature(conn, horizons, grid())
    conn.commit()
    edited = geometry_of(tgsis.fetch_feature(conn, horizons, fid)).to_pyvista()
    edited.points[:5, 2] += 10.0  # the modeller moves five vertices in pyvista
    result = tgsis.save_feature(conn, horizons, fid, edited)
    conn.commit()
    assert result.vertices_moved == 5 and result.rows_deleted == result.rows_inserted  # five vertices moved, no more
    assert np.array_equal(mesh_of(tgsis.fetch_feature(conn, horizons, fid)).vertices, edited.points)
    co = tgsis.checkout(conn, fid)
    m = co.mesh.to_meshio()
    m.points[0, 2] -= 3.0
    tgsis.checkin(conn, co, m)
    conn.commit()
    assert mesh_of(tgsis.fetch_feature(conn, horizons, fid)).vertices[0, 2] == m.points[0, 2]


def test_a_collection_class_takes_a_mixed_grid_tgsis_wrote(conn: Conn) -> None:
    F.create_feature_class(conn, "models", "GEOMETRYCOLLECTION")
    surface = tgsis.as_mesh(grid(3))
    assert isinstance(surface, tgsis.Surface)
    wells = tgsis.PointSet(surface.vertices[:4] + [0, 0, -100], name="wells")
    collection = tgsis.GeometryCollection(
        [tgsis.Surface(surface.vertices, surface.cells, name="top"), wells], name="model"
    )
    fid = tgsis.insert_feature(conn, "models", collection.to_pyvista())
    back = tgsis.fetch_feature(conn, "models", fid).mesh
    assert isinstance(back, tgsis.GeometryCollection) and back.same_as(collection)
    assert [m.name for m in back.members] == ["top", "wells"]


def test_hostile_objects_write_nothing(conn: Conn, horizons: F.FeatureClass) -> None:
    fid = tgsis.insert_feature(conn, horizons, grid(3))
    conn.commit()
    before = stored(conn)
    nan = grid(3)
    nan.points[4, 1] = np.nan  # type: ignore[index]  # pyvista types __setitem__'s key int only
    wrong = meshio.Mesh(grid(3).points, [("triangle", grid(3).regular_faces)])
    wrong.point_data["porosity"] = np.zeros(3)
    strings = grid(3)
    strings.point_data["unit"] = np.array(["salt"] * strings.n_points)
    cases: list[tuple[Any, type[tgsis.Error], str]] = [
        (pv.Plane(i_resolution=3, j_resolution=3), tgsis.InvalidGeometryError, r"QUAD \(9\) cells"),
        (grid(3) + pv.Line(), tgsis.InvalidGeometryError, "mixes cells of several kinds"),
        (pv.PolyData(), tgsis.InvalidGeometryError, "is empty"),
        (nan, tgsis.InvalidGeometryError, "vertex 4 has a non-finite y coordinate"),
        (wrong, tgsis.InvalidPropertyError, "'porosity' has 3 values for 16 vertices"),
        (strings, tgsis.InvalidPropertyError, "array 'unit' in point_data holds <U4 values"),
        (
            pv.Line(),
            tgsis.InvalidGeometryError,
            "holds SURFACE features, not MULTILINESTRING|cannot compare a Surface with a LineSet",
        ),
        ({"vertices": [[0, 0, 0]]}, tgsis.InvalidGeometryError, "cannot store a dict as a mesh: tgsis takes"),
    ]
    for obj, error, message in cases:
        with pytest.raises(error, match=message):
            tgsis.insert_feature(conn, horizons, obj)
        conn.rollback()
        with pytest.raises(error, match=message):
            tgsis.save_feature(conn, horizons, fid, obj)
        conn.rollback()
        co = tgsis.checkout(conn, fid)
        with pytest.raises(error, match=message):
            tgsis.checkin(conn, co, obj)
        conn.rollback()
        assert stored(conn) == before, obj
