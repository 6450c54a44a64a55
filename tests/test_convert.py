"""pyvista, meshio and trimesh objects to tgsis meshes and back (tgsis.convert), against the real libraries.

Found (issue 19, part 1): nothing took these objects; ``insert_feature`` of a
pyvista mesh failed with ``AttributeError: 'PolyData' object has no attribute
'geotype'``. The hostile cases are the ones the libraries make easily: quads
(``pyvista.Plane``), a surface with a line (``Sphere() + Line()``), empty
datasets, NaN points, string arrays and arrays of the wrong length (which
meshio and trimesh let one assign after construction).
"""

from __future__ import annotations

import subprocess
import sys
from typing import Any

import meshio
import numpy as np
import pytest
import pyvista as pv
import trimesh

import tgsis
from tgsis.convert import from_meshio, from_pyvista, to_meshio, to_pyvista
from tgsis.errors import InvalidGeometryError, InvalidPropertyError
from tgsis.mesh import GeometryCollection, LineSet, Mesh, PointSet, Surface, TetraMesh


def meshes() -> list[Mesh]:
    """One mesh of each type, with scalar, vector and integer properties and a name."""
    rng = np.random.default_rng(19)
    n = 12
    vertices = rng.uniform(-1e5, 1e5, (n, 3))
    vertices[0] = [-0.0, 5e-324, 1e300]
    vertex_properties: dict[str, Any] = {
        "porosity": rng.random(n),
        "velocity": rng.normal(size=(n, 3)),
        "facies": np.arange(n, dtype=np.int32) % 3,
    }
    return [
        PointSet(vertices, vertex_properties=vertex_properties, cell_properties={"k": np.arange(n)}, name="wells"),
        LineSet(
            vertices,
            np.stack([np.arange(n - 1), np.arange(1, n)], 1),
            vertex_properties=vertex_properties,
            cell_properties={"k": np.arange(n - 1, dtype=np.int64)},
            name="trace",
        ),
        Surface(
            vertices,
            np.stack([np.arange(n - 2), np.arange(1, n - 1), np.arange(2, n)], 1),
            vertex_properties=vertex_properties,
            cell_properties={"k": np.arange(n - 2) * 1.5},
            name="top é",
        ),
        TetraMesh(
            vertices,
            np.stack([np.arange(n - 3) + j for j in range(4)], 1),
            vertex_properties=vertex_properties,
            cell_properties={"k": np.arange(n - 3, dtype=np.float32)},
        ),
    ]


def same(a: Any, b: Any) -> bool:
    """Same type, bit-identical arrays, properties with their dtypes, and names."""
    if isinstance(a, GeometryCollection):
        return (
            isinstance(b, GeometryCollection)
            and a.same_as(b)
            and a.name == b.name
            and all(same(x, y) for x, y in zip(a.members, b.members))
        )
    return (
        a.same_as(b)
        and a.name == b.name
        and {k: v.dtype for k, v in a.vertex_properties.items()} == {k: v.dtype for k, v in b.vertex_properties.items()}
        and {k: v.dtype for k, v in a.cell_properties.items()} == {k: v.dtype for k, v in b.cell_properties.items()}
    )


# ---------------------------------------------------------------- round trips through the objects


@pytest.mark.parametrize("index", range(4))
def test_pyvista_round_trip_is_exact(index: int) -> None:
    mesh = meshes()[index]
    data = mesh.to_pyvista()
    assert isinstance(data, pv.UnstructuredGrid if isinstance(mesh, TetraMesh) else pv.PolyData)
    assert data.n_points == mesh.n_vertices and data.n_cells == mesh.n_cells
    assert data.points.dtype == np.float64 and np.array_equal(data.points, mesh.vertices)
    assert np.array_equal(data.point_data["velocity"], mesh.vertex_properties["velocity"])
    assert np.array_equal(data.cell_data["k"], mesh.cell_properties["k"])
    # the name as UTF-8 bytes (pyvista refuses non-ASCII strings), and as a string when it is ASCII
    assert ("tgsis_name" in data.field_data) == (mesh.name is not None)
    assert ("name" in data.field_data) == (mesh.name is not None and mesh.name.isascii())
    back = tgsis.as_mesh(data)
    assert type(back) is type(mesh) and same(back, mesh)
    assert same(type(mesh).from_pyvista(data), mesh)


@pytest.mark.parametrize("index", range(4))
def test_meshio_round_trip_is_exact(index: int) -> None:
    mesh = meshes()[index]
    m = mesh.to_meshio()
    assert isinstance(m, meshio.Mesh)
    [block] = m.cells
    assert block.type == ["vertex", "line", "triangle", "tetra"][index]
    assert np.array_equal(block.data, mesh.cells) and np.array_equal(m.points, mesh.vertices)
    assert np.array_equal(m.cell_data["k"][0], mesh.cell_properties["k"])
    assert same(tgsis.as_mesh(m), mesh)
    assert same(type(mesh).from_meshio(m), mesh)


def test_collections_round_trip_through_both() -> None:
    a, b, c = meshes()[2], meshes()[0], meshes()[1]
    for member in (b, c):  # one array covers all members: of one dtype, it comes back with it
        member.cell_properties["k"] = member.cell_properties["k"].astype(np.float64)
    collection = GeometryCollection([a, b, c], name="model")
    grid = collection.to_pyvista()
    assert isinstance(grid, pv.UnstructuredGrid)
    assert sorted(set(grid.celltypes.tolist())) == [1, 3, 5]
    assert same(tgsis.as_mesh(grid), collection)
    m = collection.to_meshio()
    assert [c.type for c in m.cells] == ["triangle", "vertex", "line"]
    assert same(tgsis.as_mesh(m), collection)
    with pytest.raises(
        InvalidPropertyError,
        match="'porosity' is on some members of the collection but not on "
        r"members \[1\]",
    ):
        GeometryCollection([a, Surface(a.vertices, a.cells, cell_properties=a.cell_properties)]).to_pyvista()


def test_empty_meshes_keep_their_type() -> None:
    for mesh in (
        Surface(np.empty((0, 3)), np.empty((0, 3)), name="nothing yet"),
        TetraMesh(np.eye(3)[[0, 1, 2, 0]] + [[0, 0, 0], [0, 0, 0], [0, 0, 0], [0, 0, 1]], []),
        LineSet(np.empty((0, 3)), []),
    ):
        assert same(tgsis.as_mesh(mesh.to_pyvista()), mesh)
        assert same(tgsis.as_mesh(mesh.to_meshio()), mesh)


def test_trimesh_objects() -> None:
    sphere = trimesh.creation.icosphere(subdivisions=2)
    sphere.vertex_attributes["depth"] = -sphere.vertices[:, 2]
    surface = tgsis.as_mesh(sphere)
    assert isinstance(surface, Surface) and np.array_equal(surface.cells, sphere.faces)
    assert np.array_equal(surface.vertex_properties["depth"], -sphere.vertices[:, 2])
    cloud = tgsis.as_mesh(trimesh.PointCloud(sphere.vertices[:5]))  # type: ignore[no-untyped-call]  # trimesh: no annotations
    assert isinstance(cloud, PointSet) and cloud.n_cells == 5


# ---------------------------------------------------------------- what the libraries make


def test_pyvista_datasets_of_every_kind() -> None:
    sphere = pv.Sphere()
    sphere["depth"] = -sphere.points[:, 2]
    sphere.field_data["name"] = ["salt top"]
    surface = tgsis.as_mesh(sphere)
    assert isinstance(surface, Surface) and surface.name == "salt top" and surface.n_cells == sphere.n_cells
    assert np.array_equal(surface.vertices, sphere.points.astype(np.float64))
    assert surface.vertex_properties["Normals"].shape == (sphere.n_points, 3)  # a vector property
    # a polyline becomes its segments, each with the polyline's cell data
    spline = pv.Spline(np.array([[0, 0, 0], [1, 1, 0], [2, 0, 1], [3, 1, 1.0]]), 10)
    spline.cell_data["fault_id"] = [7]
    lines = tgsis.as_mesh(spline)
    assert isinstance(lines, LineSet) and lines.n_cells == 9
    assert (
        lines.cells.tolist() == [[i, i + 1] for i in range(9)] and lines.cell_properties["fault_id"].tolist() == [7] * 9
    )
    # points: pyvista makes a vertex cell of each
    points = tgsis.as_mesh(pv.PolyData(np.random.default_rng(0).random((6, 3))))
    assert isinstance(points, PointSet) and points.n_cells == 6
    # a volume: tetrahedra after triangulate(); a structured grid through cast_to_unstructured_grid
    solid = tgsis.as_mesh(pv.ImageData(dimensions=(3, 3, 3)).triangulate())
    assert isinstance(solid, TetraMesh) and solid.n_cells == 40
    flat = tgsis.as_mesh(pv.ImageData(dimensions=(3, 3, 1)).triangulate())
    assert isinstance(flat, Surface) and flat.n_cells == 8
    # a bare VTK object is wrapped
    from vtkmodules.vtkFiltersSources import vtkSphereSource

    source = vtkSphereSource()
    source.Update()
    assert isinstance(tgsis.as_mesh(source.GetOutput()), Surface)


def test_array_names_that_are_no_property_names_are_kept_for_the_way_back() -> None:
    m = meshio.Mesh(
        np.eye(3),
        [("triangle", [[0, 1, 2]])],
        cell_data={"gmsh:physical": [np.array([4])]},
        point_data={"Elevation value": np.arange(3.0)},
    )
    surface = tgsis.as_mesh(m)
    assert isinstance(surface, Surface)
    assert list(surface.cell_properties) == ["gmsh_physical"] and list(surface.vertex_properties) == ["Elevation_value"]
    assert surface.metadata["vtk_array_names"] == {
        "point_data": {"Elevation_value": "Elevation value"},
        "cell_data": {"gmsh_physical": "gmsh:physical"},
    }
    assert list(to_meshio(surface).cell_data) == ["gmsh:physical"]
    assert list(to_pyvista(surface).point_data) == ["Elevation value"]


def test_meshio_2d_points_and_several_blocks_of_one_type() -> None:
    m = meshio.Mesh(
        np.array([[0, 0], [1, 0], [0, 1], [1, 1.0]]),
        [("triangle", [[0, 1, 2]]), ("triangle", [[1, 3, 2]])],
        cell_data={"zone": [np.array([1]), np.array([2])]},
    )
    surface = tgsis.as_mesh(m)
    assert isinstance(surface, Surface)
    assert surface.vertices[:, 2].tolist() == [0, 0, 0, 0]
    assert surface.cells.tolist() == [[0, 1, 2], [1, 3, 2]] and surface.cell_properties["zone"].tolist() == [1, 2]


# ---------------------------------------------------------------- hostile


def test_anything_else_is_refused_with_what_is_accepted() -> None:
    for thing in (42, "fault.ts", np.eye(3), {"vertices": np.eye(3)}):
        with pytest.raises(InvalidGeometryError) as info:
            tgsis.as_mesh(thing)
        assert (
            "tgsis takes a tgsis PointSet, LineSet, Surface, TetraMesh or GeometryCollection, a pyvista "
            "PolyData or UnstructuredGrid" in str(info.value)
        )
        assert "meshio.Mesh" in str(info.value) and "trimesh.Trimesh" in str(info.value)
    with pytest.raises(InvalidGeometryError, match="cannot store a numpy.ndarray as a mesh"):
        tgsis.as_mesh(np.eye(3))


def test_a_multiblock_is_a_collection_of_its_blocks() -> None:
    blocks = pv.MultiBlock({"salt": pv.Sphere(theta_resolution=6, phi_resolution=6), "well": pv.Line()})
    salt = blocks["salt"]
    assert salt is not None
    salt.field_data["name"] = ["salt dome"]
    collection = tgsis.as_mesh(blocks)
    assert isinstance(collection, GeometryCollection)
    assert [type(m) for m in collection.members] == [Surface, LineSet]
    assert [m.name for m in collection.members] == ["salt dome", "well"]  # its own name, else the block's key
    with pytest.raises(InvalidGeometryError, match=r"block 1 \('well'\) is a MultiBlock: .* do not nest"):
        tgsis.as_mesh(pv.MultiBlock({"a": pv.Sphere(), "well": pv.MultiBlock([pv.Line()])}))
    with pytest.raises(InvalidGeometryError, match=r"pyvista MultiBlock block 0 \('a'\): pyvista PolyData has QUAD"):
        tgsis.as_mesh(pv.MultiBlock({"a": pv.Plane()}))
    with pytest.raises(InvalidGeometryError, match="MultiBlock has no block"):
        tgsis.as_mesh(pv.MultiBlock())


def test_polygons_that_are_not_triangles() -> None:
    with pytest.raises(InvalidGeometryError, match=r"pyvista PolyData has QUAD \(9\) cells") as info:
        tgsis.as_mesh(pv.Plane(i_resolution=2, j_resolution=2))
    assert info.value.hint is not None and "mesh.triangulate()" in info.value.hint
    assert info.value.detail == "4 of 4 cells, of 4 points"
    hexagon = pv.PolyData(
        np.array([[np.cos(a), np.sin(a), 0] for a in np.linspace(0, 2 * np.pi, 7)[:-1]]), faces=[6, 0, 1, 2, 3, 4, 5]
    )
    with pytest.raises(InvalidGeometryError, match=r"POLYGON \(7\) cells"):
        tgsis.as_mesh(hexagon)
    with pytest.raises(InvalidGeometryError, match="VOXEL"):
        tgsis.as_mesh(pv.ImageData(dimensions=(3, 3, 3)))
    with pytest.raises(InvalidGeometryError, match="meshio.Mesh has quad cells") as info:
        tgsis.as_mesh(meshio.Mesh(np.eye(4, 3), [("quad", [[0, 1, 2, 3]])]))
    assert info.value.hint == "split them into triangles first"
    with pytest.raises(InvalidGeometryError, match="meshio.Mesh has triangle6 cells"):
        tgsis.as_mesh(meshio.Mesh(np.random.default_rng(0).random((6, 3)), [("triangle6", [[0, 1, 2, 3, 4, 5]])]))


def test_mixed_cells() -> None:
    with pytest.raises(
        InvalidGeometryError, match=r"mixes cells of several kinds \(LINE \(1\), TRIANGLE \(1680\)\)"
    ) as info:
        tgsis.as_mesh(pv.Sphere() + pv.Line())
    assert info.value.hint is not None and "extract_cells_by_type" in info.value.hint
    m = meshio.Mesh(np.eye(3), [("triangle", [[0, 1, 2]]), ("line", [[0, 1]])])
    with pytest.raises(
        InvalidGeometryError, match=r"mixes cell blocks of several kinds \(triangle \(1\), line \(1\)\)"
    ):
        tgsis.as_mesh(m)
    with pytest.raises(InvalidGeometryError, match="the pyvista dataset is a LineSet, not a Surface"):
        Surface.from_pyvista(pv.Line())
    with pytest.raises(InvalidGeometryError, match="the meshio.Mesh is a Surface, not a TetraMesh"):
        TetraMesh.from_meshio(meshes()[2].to_meshio())


def test_empty_objects() -> None:
    with pytest.raises(InvalidGeometryError, match="pyvista PolyData is empty") as info:
        tgsis.as_mesh(pv.PolyData())
    assert info.value.hint is not None and "tgsis.Surface(numpy.empty((0, 3)), numpy.empty((0, 3)))" in info.value.hint
    with pytest.raises(InvalidGeometryError, match="pyvista UnstructuredGrid is empty"):
        tgsis.as_mesh(pv.UnstructuredGrid())
    with pytest.raises(InvalidGeometryError, match="meshio.Mesh is empty"):
        tgsis.as_mesh(meshio.Mesh(np.empty((0, 3)), []))


def test_nan_points() -> None:
    points = np.array([[0, 0, 0], [1, 0, np.nan], [0, 1, 0.0]])
    with pytest.raises(InvalidGeometryError, match="pyvista PolyData: vertex 1 has a non-finite z coordinate"):
        tgsis.as_mesh(pv.PolyData(points, faces=[3, 0, 1, 2]))
    with pytest.raises(InvalidGeometryError, match="meshio.Mesh: vertex 1 has a non-finite z coordinate"):
        tgsis.as_mesh(meshio.Mesh(points, [("triangle", [[0, 1, 2]])]))
    with pytest.raises(InvalidGeometryError, match="trimesh.Trimesh: vertex 1 has a non-finite z"):
        tgsis.as_mesh(trimesh.Trimesh(points, [[0, 1, 2]], process=False))


def test_data_arrays_of_the_wrong_length_or_kind() -> None:
    m = meshio.Mesh(np.eye(3), [("triangle", [[0, 1, 2]])])
    m.point_data["porosity"] = np.arange(5.0)  # meshio checks at construction only
    with pytest.raises(
        InvalidPropertyError, match="meshio.Mesh: vertex property 'porosity' has 5 values for 3 vertices"
    ):
        tgsis.as_mesh(m)
    m = meshio.Mesh(np.eye(3), [("triangle", [[0, 1, 2]])])
    m.cell_data["zone"] = [np.arange(2)]
    with pytest.raises(InvalidPropertyError, match="cell_data 'zone' has 2 values for the 1 triangle cells"):
        tgsis.as_mesh(m)
    m.cell_data["zone"] = [np.arange(1), np.arange(1)]
    with pytest.raises(InvalidPropertyError, match="cell_data 'zone' has 2 arrays for 1 cell blocks"):
        tgsis.as_mesh(m)
    tm = trimesh.creation.icosphere(subdivisions=1)
    tm.vertex_attributes["depth"] = np.arange(3.0)
    with pytest.raises(InvalidPropertyError, match="trimesh.Trimesh: vertex property 'depth' has 3 values for 42"):
        tgsis.as_mesh(tm)
    sphere = pv.Sphere()
    sphere.point_data["unit"] = np.array(["salt"] * sphere.n_points)
    with pytest.raises(
        InvalidPropertyError, match="pyvista PolyData array 'unit' in point_data holds <U4 values"
    ) as info:
        tgsis.as_mesh(sphere)
    assert info.value.hint == "remove it from point_data before converting (del mesh.point_data['unit'])"


def test_a_pyvista_array_of_the_wrong_length_set_through_vtk() -> None:
    """pyvista checks the length of an array assigned through it, VTK does not."""
    from vtkmodules.util.numpy_support import numpy_to_vtk

    sphere = pv.Sphere(theta_resolution=6, phi_resolution=6)
    short = numpy_to_vtk(np.arange(5.0))  # type: ignore[no-untyped-call]  # vtk: no annotations
    short.SetName("porosity")
    sphere.GetPointData().AddArray(short)
    with pytest.raises(
        InvalidPropertyError,
        match=f"pyvista PolyData: vertex property 'porosity' has 5 values for {sphere.n_points} vertices",
    ):
        tgsis.as_mesh(sphere)


def test_a_collection_whose_member_table_was_tampered_with() -> None:
    grid = GeometryCollection([meshes()[2], meshes()[2]]).to_pyvista()
    grid.field_data["tgsis_member_sizes"] = np.array([[40, 10], [0, 10]])
    with pytest.raises(InvalidGeometryError, match="its tgsis member table does not match its 24 points and 20 cells"):
        tgsis.as_mesh(grid)


def test_back_conversions_refuse_other_objects() -> None:
    with pytest.raises(InvalidGeometryError, match="to_pyvista converts tgsis meshes, not pyvista.PolyData"):
        to_pyvista(pv.Sphere())
    with pytest.raises(InvalidGeometryError, match="to_meshio converts tgsis meshes, not int"):
        to_meshio(3)  # type: ignore[arg-type]
    with pytest.raises(InvalidGeometryError, match="not a pyvista dataset"):
        from_pyvista(meshes()[0])
    with pytest.raises(InvalidGeometryError, match="not a meshio.Mesh"):
        from_meshio(pv.Sphere())


def test_the_libraries_load_only_when_used() -> None:
    program = (
        "import sys, numpy, tgsis, tgsis.convert; s = tgsis.Surface(numpy.eye(3), [[0, 1, 2]]); "
        "tgsis.as_mesh(s); print(sorted(m for m in ('pyvista', 'meshio', 'vtk', 'vtkmodules') if m in sys.modules))"
    )
    done = subprocess.run([sys.executable, "-c", program], capture_output=True, text=True, check=False)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "[]"
