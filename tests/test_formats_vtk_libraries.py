""".vtu, .vtp and legacy .vtk files between tgsis, meshio and pyvista (VTK itself): each reads what the others write.

Found (issue 19, part 1): meshio read no ``.vtu`` tgsis wrote. Its VTU reader
decodes every ``FieldData`` child with ``read_data``, which looks the
``type`` attribute up in ``vtu_to_numpy_type`` (Int8 .. Float64 only) and
raises ``ReadError("Illegal data type 'String'")`` for the
``<Array type="String">`` that held the mesh name and geotype, so the whole
file failed ("Couldn't read file ... as vtu"). tgsis now writes those strings
as UInt8 DataArrays (``tgsis_name``, ``tgsis_geotype``, ...). Also found on
the way: pyvista read them as empty arrays without ``NumberOfTuples``;
meshio's legacy reader reads ``int`` as 8 bytes (VTK: 4), knows no POLYDATA,
and cannot read a compressed array of 0 blocks; pyvista refuses non-ASCII
field strings. Each has its test here.
"""

from __future__ import annotations

import os
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any

import meshio
import numpy as np
import pytest
import pyvista as pv

import tgsis
from tests.shared_data import cfm
from tgsis import formats
from tgsis.errors import FileFormatError
from tgsis.formats.vtk import format_vtu
from tgsis.mesh import GeometryCollection, LineSet, Mesh, PointSet, Surface, TetraMesh

MESHIO_TYPE = {PointSet: "vertex", LineSet: "line", Surface: "triangle", TetraMesh: "tetra"}


def meshes() -> list[Mesh]:
    """One mesh of each type: extreme coordinates, scalar, vector and integer properties, a non-ASCII name."""
    rng = np.random.default_rng(7)
    n = 40
    vertices = rng.uniform(-1e6, 1e6, (n, 3))
    vertices[0] = [-0.0, 5e-324, 1e300]
    props: dict[str, Any] = {
        "porosity": rng.random(n),
        "velocity": rng.normal(size=(n, 3)),
        "depth": rng.random(n).astype(np.float32),
        "id": np.arange(n, dtype=np.int64) * 2**40,
    }
    return [
        PointSet(
            vertices, vertex_properties=props, cell_properties={"zone": np.arange(n, dtype=np.int64)}, name="wells"
        ),
        LineSet(
            vertices,
            np.stack([np.arange(n - 1), np.arange(1, n)], 1),
            vertex_properties=props,
            cell_properties={"zone": np.arange(n - 1, dtype=np.int64)},
            name="trace",
        ),
        Surface(
            vertices,
            np.stack([np.arange(n - 2), np.arange(1, n - 1), np.arange(2, n)], 1),
            vertex_properties=props,
            cell_properties={"zone": np.arange(n - 2, dtype=np.int64)},
            name="horizon é",
        ),
        TetraMesh(
            vertices,
            np.stack([np.arange(n - 3) + j for j in range(4)], 1),
            vertex_properties=props,
            cell_properties={"zone": np.arange(n - 3, dtype=np.int64)},
            name="salt",
        ),
    ]


WRITERS: dict[str, tuple[str, dict[str, Any]]] = {
    "vtu zlib binary": ("x.vtu", {}),
    "vtu zlib appended": ("x.vtu", {"encoding": "appended"}),
    "vtu raw binary": ("x.vtu", {"compression": None}),
    "vtu raw appended": ("x.vtu", {"encoding": "appended", "compression": None}),
    "vtp zlib": ("x.vtp", {}),
    "vtp raw appended": ("x.vtp", {"encoding": "appended", "compression": None}),
    "vtk binary": ("x.vtk", {}),
    "vtk ascii": ("x.vtk", {"ascii": True}),
}


def cases() -> list[tuple[str, int]]:
    return [(w, i) for w in WRITERS for i in range(4) if not (w.startswith("vtp") and i == 3)]


def check_pyvista(data: Any, mesh: Mesh) -> None:
    """pyvista's dataset has the mesh's points, cells and data, bit for bit."""
    assert data.n_points == mesh.n_vertices and data.n_cells == mesh.n_cells
    assert np.array_equal(np.asarray(data.points, dtype=np.float64).view(np.int64), mesh.vertices.view(np.int64))
    grid = data.cast_to_unstructured_grid()
    assert np.array_equal(grid.cell_connectivity, mesh.cells.reshape(-1))
    for name, values in mesh.vertex_properties.items():
        assert np.array_equal(data.point_data[name], values), name
    for name, values in mesh.cell_properties.items():
        assert np.array_equal(data.cell_data[name], values), name


@pytest.mark.parametrize(("writer", "index"), cases())
def test_files_tgsis_writes_are_read_by_pyvista(writer: str, index: int, tmp_path: Path) -> None:
    mesh = meshes()[index]
    name, options = WRITERS[writer]
    formats.write(mesh, tmp_path / name, **options)
    data = pv.read(tmp_path / name)
    check_pyvista(data, mesh)
    back = tgsis.as_mesh(data)
    assert back.same_as(mesh) and back.name == mesh.name
    assert formats.read_one(tmp_path / name).same_as(mesh)  # and by tgsis, of course


@pytest.mark.parametrize(("writer", "index"), [c for c in cases() if not c[0].startswith("vtp")])
def test_files_tgsis_writes_are_read_by_meshio(writer: str, index: int, tmp_path: Path) -> None:
    mesh = meshes()[index]
    name, options = WRITERS[writer]
    formats.write(mesh, tmp_path / name, **options)
    m = meshio.read(tmp_path / name)
    assert np.array_equal(m.points.astype(np.float64).view(np.int64), mesh.vertices.view(np.int64))  # legacy: >f8
    [block] = m.cells
    assert block.type == MESHIO_TYPE[type(mesh)] and np.array_equal(block.data, mesh.cells)
    for key, values in mesh.vertex_properties.items():
        assert np.array_equal(m.point_data[key], values), key
    assert np.array_equal(m.cell_data["zone"][0], mesh.cell_properties["zone"])
    back = tgsis.as_mesh(m)
    assert back.same_as(mesh)
    if name.endswith(".vtu"):  # meshio keeps a .vtu's field data: the name comes back (not from a legacy file)
        assert back.name == mesh.name


def test_collections_through_vtu_and_vtk(tmp_path: Path) -> None:
    a, b, c = meshes()[2], meshes()[0], meshes()[3]
    collection = GeometryCollection([a, b, c], name="model")
    for name in ("c.vtu", "c.vtk"):
        formats.write(collection, tmp_path / name)
        assert [m.name for m in formats.read(tmp_path / name)] == ["horizon é", "wells", "salt"]
        assert tgsis.as_mesh(pv.read(tmp_path / name)).same_as(collection)
    m = meshio.read(tmp_path / "c.vtu")
    assert [block.type for block in m.cells] == ["triangle", "vertex", "tetra"]
    assert tgsis.as_mesh(m).same_as(collection)
    with pytest.raises(FileFormatError, match="vtp files hold one object, not a GEOMETRYCOLLECTION"):
        formats.write(collection, tmp_path / "c.vtp")


def test_the_string_field_arrays_that_meshio_refused(tmp_path: Path) -> None:
    surface = meshes()[2]
    data = format_vtu(surface, compression=None)
    root = ET.fromstring(data)
    fields = {
        e.get("Name"): e
        for e in root.iter()
        if e.tag in ("Array", "DataArray") and e.get("Name", "").startswith("tgsis_")
    }
    assert set(fields) == {"tgsis_name", "tgsis_geotype"}
    assert all(e.tag == "DataArray" and e.get("type") == "UInt8" for e in fields.values())
    assert fields["tgsis_name"].get("NumberOfTuples") == str(len("horizon é".encode()) + 1)  # pyvista needs it
    (tmp_path / "new.vtu").write_bytes(data)
    assert meshio.read(tmp_path / "new.vtu").field_data["tgsis_geotype"].tobytes() == b"SURFACE\0"
    # a file of the old layout, a String array as VTK writes one: meshio still refuses it, tgsis reads it
    old = data.replace(b'<DataArray type="UInt8" Name="tgsis_name"', b'<DataArray type="UInt8" Name="x"')
    old = old.replace(
        b"<FieldData>",
        b'<FieldData>\n<Array type="String" Name="name" NumberOfTuples="1" '
        b'format="ascii">104 111 114 105 122 111 110 0</Array>',
        1,
    )
    (tmp_path / "old.vtu").write_bytes(old)
    with pytest.raises(Exception, match="Illegal data type 'String'"):
        meshio.vtu.read(tmp_path / "old.vtu")
    assert formats.read_one(tmp_path / "old.vtu").name == "horizon"


def test_empty_meshes(tmp_path: Path) -> None:
    """No points or no cells: not compressed (meshio cannot decode a compressed array of 0 blocks)."""
    for mesh in (Surface(np.empty((0, 3)), np.empty((0, 3)), name="to come"), TetraMesh(np.eye(3)[[0, 1, 2, 0]], [])):
        for name in ("e.vtu", "e.vtk") + (("e.vtp",) if isinstance(mesh, Surface) else ()):
            formats.write(mesh, tmp_path / name)
            back = formats.read_one(tmp_path / name)
            assert type(back) is type(mesh) and back.same_as(mesh) and back.name == mesh.name
            assert b"vtkZLibDataCompressor" not in (tmp_path / name).read_bytes()
        assert pv.read(tmp_path / "e.vtu").n_cells == 0


# ---------------------------------------------------------------- what pyvista and meshio write


def test_files_pyvista_writes(tmp_path: Path) -> None:
    sphere = pv.Sphere(theta_resolution=12, phi_resolution=8)
    sphere["depth"] = -sphere.points[:, 2]
    sphere.cell_data["zone"] = np.arange(sphere.n_cells) % 3
    sphere.field_data["name"] = ["dome"]
    solid = pv.ImageData(dimensions=(4, 3, 3)).triangulate()
    solid["t"] = np.arange(solid.n_points, dtype=np.int32)
    for data, kind, files in (
        (sphere, Surface, ("s.vtp", "s.vtk")),
        (solid, TetraMesh, ("t.vtu", "t.vtk")),
        (pv.Spline(np.eye(3), 6), LineSet, ("l.vtp", "l.vtk")),
    ):
        for name in files:
            for binary in (True, False):
                data.save(tmp_path / name, binary=binary)
                mesh = formats.read_one(tmp_path / name)
                assert isinstance(mesh, kind)
                if kind is LineSet:  # one polyline of 6 points: its 5 segments
                    assert mesh.cells.tolist() == [[i, i + 1] for i in range(5)]
                    continue
                assert mesh.n_cells == data.n_cells
                if binary:
                    assert np.array_equal(mesh.vertices, data.points)
                else:  # pyvista's ASCII files round the floats
                    assert np.allclose(mesh.vertices, data.points, rtol=1e-5, atol=1e-6)
                assert np.array_equal(mesh.cells.reshape(-1), data.cast_to_unstructured_grid().cell_connectivity)
                for key in data.point_data.keys():
                    assert np.allclose(mesh.vertex_properties[key], data.point_data[key], rtol=1e-5, atol=1e-6), key
                if kind is Surface:
                    assert mesh.name == "dome"
                    assert mesh.cell_properties["zone"].tolist() == sphere.cell_data["zone"].tolist()
                    assert mesh.vertex_properties["Normals"].shape == (sphere.n_points, 3)


@pytest.mark.parametrize("kind", ["vtu", "vtk 4.2", "vtk 5.1"])
@pytest.mark.parametrize("binary", [True, False])
def test_files_meshio_writes(kind: str, binary: bool, tmp_path: Path) -> None:
    rng = np.random.default_rng(1)
    points = rng.random((6, 3))
    m = meshio.Mesh(
        points,
        [("tetra", [[0, 1, 2, 3], [1, 2, 3, 4], [2, 3, 4, 5]])],
        point_data={"T": rng.random(6), "v": rng.random((6, 3))},
        cell_data={"gmsh:physical": [np.array([1, 2, 2])]},
    )
    path = tmp_path / ("m.vtu" if kind == "vtu" else "m.vtk")
    if kind == "vtu":
        meshio.vtu.write(path, m, binary=binary, compression="zlib" if binary else None)
    else:
        meshio.vtk.write(path, m, binary=binary, fmt_version=kind.split()[1])
    mesh = formats.read_one(path)
    exact = binary or kind != "vtu"  # meshio's ASCII .vtu rounds the floats, its legacy ASCII does not
    assert isinstance(mesh, TetraMesh) and (
        np.array_equal(mesh.vertices, points) if exact else np.allclose(mesh.vertices, points, rtol=1e-10)
    )
    assert mesh.cells.tolist() == [[0, 1, 2, 3], [1, 2, 3, 4], [2, 3, 4, 5]]
    for key in ("T", "v"):
        assert np.allclose(mesh.vertex_properties[key], m.point_data[key], rtol=0 if exact else 1e-10), key
    assert mesh.cell_properties["gmsh_physical"].tolist() == [1, 2, 2]
    assert mesh.metadata["vtk_array_names"]["cell_data"] == {"gmsh_physical": "gmsh:physical"}


# ---------------------------------------------------------------- compression


def test_zlib_compression_on_a_real_fault(tmp_path: Path) -> None:
    """The San Andreas fault of data/cfm (39,268 vertices, 76,292 triangles): about 3x smaller."""
    fault = formats.read_one(cfm("formats/SAFS-SAFZ-MULT-San_Andreas_fault_Fuis-ALT6_500m.ts"))
    sizes: dict[str, int] = {}
    for label, options in (("raw", {"compression": None}), ("zlib", {})):
        formats.write(fault, tmp_path / f"{label}.vtu", **options)
        sizes[label] = os.path.getsize(tmp_path / f"{label}.vtu")
        assert formats.read_one(tmp_path / f"{label}.vtu").same_as(fault)
    assert sizes["raw"] / sizes["zlib"] > 2.8, sizes  # measured: 4,614,472 / 1,471,799 bytes = 3.14
    head = (tmp_path / "zlib.vtu").read_bytes()[:300]
    assert b'compressor="vtkZLibDataCompressor"' in head
    check_pyvista(pv.read(tmp_path / "zlib.vtu"), fault)
    assert np.array_equal(meshio.read(tmp_path / "zlib.vtu").points, fault.vertices)
    with pytest.raises(FileFormatError, match="unknown compression 'lzma'"):
        formats.write(fault, tmp_path / "x.vtu", compression="lzma")
