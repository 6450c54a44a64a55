"""A file's meaning survives every format (issue 37, part 5): the z convention, OBJ groups and vertices, PLY strips.

* A ``ZPOSITIVE Depth`` mesh goes to the formats that have no z convention
  (.vtu, .vtp, .vtk, .ply, .obj, .off, .stl, pyvista, meshio, trimesh) in
  elevation, z up, as every viewer draws it; tgsis records the convention where
  the format has room for its own facts and gives the mesh back as it was. Through
  the database: GOCAD depth -> import -> export -> import -> export GOCAD keeps
  the stored shape and meaning; ``tgsis import --at`` stores elevation too.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import psycopg
import pytest

import tgsis
from tgsis import formats
from tgsis.cli import main
from tgsis.errors import FileFormatError
from tgsis.mesh import GeometryCollection, LineSet, PointSet, Surface

# A small curved depth surface as GOCAD writes one: z is depth (down positive), in metres.
DEPTH_TS = """GOCAD TSurf 1
HEADER {
name:deep horizon
}
GOCAD_ORIGINAL_COORDINATE_SYSTEM
NAME Default
AXIS_NAME "X" "Y" "Z"
AXIS_UNIT "m" "m" "m"
ZPOSITIVE Depth
END_ORIGINAL_COORDINATE_SYSTEM
TFACE
VRTX 1 500000.25 4100000.5 1000.125
VRTX 2 500100.25 4100000.5 1100.0
VRTX 3 500000.25 4100100.5 1200.0
VRTX 4 500100.25 4100100.5 1350.75
VRTX 5 500050.25 4100050.5 -0.0
TRGL 1 2 5
TRGL 2 4 5
TRGL 4 3 5
TRGL 3 1 5
END
"""
DEPTHS = np.array([1000.125, 1100.0, 1200.0, 1350.75, -0.0])

NO_CONVENTION = ("vtu", "vtp", "vtk", "ply", "obj", "off", "stl")
RECORDING = ("vtu", "vtp", "vtk", "ply")  # formats with room for tgsis's record of the convention


@pytest.fixture
def depth_file(tmp_path: Path) -> Path:
    path = tmp_path / "deep.ts"
    path.write_text(DEPTH_TS)
    return path


def depth_surface(path: Path) -> Surface:
    [mesh] = formats.read(path)
    assert isinstance(mesh, Surface) and mesh.metadata["zpositive"] == "Depth"
    assert np.array_equal(mesh.vertices[:, 2], DEPTHS)
    return mesh


def z_as_others_read_it(path: Path) -> np.ndarray:
    """The z of a file's points as a tool other than tgsis reads them (ParaView's libraries, trimesh)."""
    if path.suffix in (".vtu", ".vtp", ".vtk", ".ply"):
        pv = pytest.importorskip("pyvista")
        return np.asarray(pv.read(path).points[:, 2], dtype=np.float64)
    import trimesh

    loaded = trimesh.load(path, process=False, force="mesh")
    return np.asarray(loaded.vertices[:, 2], dtype=np.float64)


@pytest.mark.parametrize("ext", NO_CONVENTION)
def test_a_depth_surface_is_written_as_elevation_to_formats_without_a_z_convention(
    depth_file: Path, tmp_path: Path, ext: str
) -> None:
    mesh = depth_surface(depth_file)
    out = tmp_path / f"deep.{ext}"
    formats.write(mesh, out)
    z = z_as_others_read_it(out)
    if ext == "stl":  # three corners per triangle, float32: every z is one of the elevations
        assert set(np.round(z, 2).tolist()) <= set(np.round(-DEPTHS, 2).tolist())
    else:
        assert np.allclose(z, -DEPTHS, atol=1e-6) and np.all(z <= 0)
    assert mesh.metadata["zpositive"] == "Depth" and np.array_equal(mesh.vertices[:, 2], DEPTHS)  # not changed


@pytest.mark.parametrize("ext", RECORDING)
def test_tgsis_reads_its_depth_files_back_as_they_were(depth_file: Path, tmp_path: Path, ext: str) -> None:
    mesh = depth_surface(depth_file)
    out = tmp_path / f"deep.{ext}"
    formats.write(mesh, out)
    [back] = formats.read(out)
    assert back.same_as(mesh)  # bit-exact, -0.0 too
    assert back.metadata["zpositive"] == "Depth"


@pytest.mark.parametrize("ext", ("obj", "off", "stl"))
def test_formats_without_room_for_the_convention_read_back_as_elevation(
    depth_file: Path, tmp_path: Path, ext: str
) -> None:
    out = tmp_path / f"deep.{ext}"
    formats.write(depth_surface(depth_file), out)
    [back] = formats.read(out)
    assert "zpositive" not in back.metadata and np.all(back.vertices[:, 2] <= 0)


@pytest.mark.parametrize("ext", ("vtu", "vtk"))
def test_a_collection_of_depth_and_elevation_members_keeps_each_members_convention(tmp_path: Path, ext: str) -> None:
    deep = Surface([[0, 0, 100.0], [1, 0, 200.0], [0, 1, 300.0]], [[0, 1, 2]], metadata={"zpositive": "depth"})
    high = LineSet([[0, 0, 5.0], [1, 1, 6.0]], [[0, 1]], metadata={"zpositive": "Elevation"})
    plain = PointSet([[2, 2, 7.0]])
    out = tmp_path / f"model.{ext}"
    formats.write(GeometryCollection([deep, high, plain]), out)
    pv = pytest.importorskip("pyvista")
    assert pv.read(out).points[:, 2].tolist() == [-100.0, -200.0, -300.0, 5.0, 6.0, 7.0]
    back = formats.read(out)
    assert [m.vertices[:, 2].tolist() for m in back] == [[100.0, 200.0, 300.0], [5.0, 6.0], [7.0]]
    assert [m.metadata.get("zpositive") for m in back] == ["Depth", "Elevation", None]


def test_pyvista_meshio_and_trimesh_objects_are_in_elevation(depth_file: Path) -> None:
    mesh = depth_surface(depth_file)
    grid = mesh.to_pyvista()
    assert np.array_equal(np.asarray(grid.points)[:, 2], -DEPTHS)
    meshio_mesh = mesh.to_meshio()
    assert np.array_equal(meshio_mesh.points[:, 2], -DEPTHS)
    assert np.array_equal(mesh.to_trimesh().vertices[:, 2], -DEPTHS)
    for obj in (grid, meshio_mesh):  # and back: tgsis gives the depth mesh again
        back = tgsis.as_mesh(obj)
        assert isinstance(back, Surface) and back.same_as(mesh) and back.metadata["zpositive"] == "Depth"
    collection = tgsis.as_mesh(GeometryCollection([mesh, PointSet([[0, 0, 1.0]])]).to_pyvista())
    assert isinstance(collection, GeometryCollection)
    assert [m.metadata.get("zpositive") for m in collection] == ["Depth", None]
    assert collection[0].same_as(mesh)


def test_a_meshio_file_of_a_depth_surface_is_elevation(depth_file: Path, tmp_path: Path) -> None:
    meshio = pytest.importorskip("meshio")
    out = tmp_path / "deep.vtu"
    formats.write(depth_surface(depth_file), out)
    read = meshio.read(out)
    assert np.array_equal(read.points[:, 2], -DEPTHS)
    assert tgsis.as_mesh(read).metadata["zpositive"] == "Depth"


def test_a_convention_that_is_neither_elevation_nor_depth_is_refused_on_write(tmp_path: Path) -> None:
    mesh = Surface([[0, 0, 1.0], [1, 0, 2.0], [0, 1, 3.0]], [[0, 1, 2]], metadata={"zpositive": "Up"})
    for ext in NO_CONVENTION:
        with pytest.raises(FileFormatError, match="zpositive"):
            formats.write(mesh, tmp_path / f"bad.{ext}")
        assert not (tmp_path / f"bad.{ext}").exists()


def test_a_recorded_convention_that_is_neither_is_refused_on_read(depth_file: Path, tmp_path: Path) -> None:
    out = tmp_path / "deep.vtu"
    formats.write(depth_surface(depth_file), out, compression=None, encoding="appended")
    data = out.read_bytes()
    assert b"tgsis_zpositive" in data
    out.write_bytes(data.replace(b"Depth\0", b"Dpeth\0"))
    with pytest.raises(FileFormatError, match="tgsis_zpositive is 'Dpeth'"):
        formats.read(out)


# ---------------------------------------------------------------- through the database


def stored_z(dsn: str, fid: int) -> list[float]:
    with psycopg.connect(dsn) as conn:
        return [
            r[0] for r in conn.execute("SELECT z FROM tgsis.vrtx WHERE geoid = %s ORDER BY vrtxid", (fid,)).fetchall()
        ]


def test_gocad_depth_through_vtu_and_back_keeps_stored_shape_and_meaning(
    db_dsn: str, depth_file: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["--dsn", db_dsn, "class", "create", "horizons", "--geotype", "SURFACE"]) == 0
    assert main(["--dsn", db_dsn, "import", str(depth_file), "--class", "horizons"]) == 0
    with psycopg.connect(db_dsn) as conn:
        [(first,)] = conn.execute("SELECT geoid FROM tgsis.geometry").fetchall()
    assert stored_z(db_dsn, first) == (-DEPTHS).tolist()
    exported = {ext: tmp_path / f"export.{ext}" for ext in NO_CONVENTION + ("ts",)}
    for path in exported.values():
        assert main(["--dsn", db_dsn, "export", str(first), str(path)]) == 0
    for ext in NO_CONVENTION:  # what ParaView, meshio and trimesh see: elevation
        z = z_as_others_read_it(exported[ext])
        assert np.all(z <= 0) and np.isclose(z.min(), -1350.75), ext
    # the .vtu back into the database: the same stored shape and z convention as the GOCAD import
    assert main(["--dsn", db_dsn, "import", str(exported["vtu"]), "--class", "horizons", "--name", "again"]) == 0
    with psycopg.connect(db_dsn) as conn:
        rows = conn.execute("SELECT geoid, zpositive FROM tgsis.geometry ORDER BY geoid").fetchall()
    assert [r[1] for r in rows] == ["Depth", "Depth"]
    second = rows[1][0]
    assert stored_z(db_dsn, second) == stored_z(db_dsn, first)
    # and out to GOCAD: the depth file again
    again = tmp_path / "again.ts"
    assert main(["--dsn", db_dsn, "export", str(second), str(again)]) == 0
    [back] = formats.read(again)
    assert back.metadata["zpositive"] == "Depth"
    assert np.array_equal(back.vertices, depth_surface(depth_file).vertices)
    # a .vtu written by ParaView's libraries from ours (no tgsis field data) is elevation: same stored shape
    pv = pytest.importorskip("pyvista")
    plain = tmp_path / "plain.vtu"
    grid = pv.read(exported["vtu"])
    grid.field_data.clear()
    grid.save(plain)
    assert main(["--dsn", db_dsn, "import", str(plain), "--class", "horizons", "--name", "plain"]) == 0
    with psycopg.connect(db_dsn) as conn:
        third, zpositive = conn.execute("SELECT geoid, zpositive FROM tgsis.geometry ORDER BY geoid DESC").fetchone()
    assert zpositive is None and stored_z(db_dsn, third) == stored_z(db_dsn, first)


def test_import_at_stores_a_depth_surface_as_elevation_and_at_exports_it_so(
    db_dsn: str, depth_file: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert (
        main(["--dsn", db_dsn, "class", "create", "horizons", "--geotype", "SURFACE", "--time-model", "INSTANTS"]) == 0
    )
    assert main(["--dsn", db_dsn, "import", str(depth_file), "--class", "horizons", "--at", "1"]) == 0
    with psycopg.connect(db_dsn) as conn:
        [(fid,)] = conn.execute("SELECT geoid FROM tgsis.geometry").fetchall()
        z = [
            r[0]
            for r in conn.execute("SELECT z FROM tgsis.times_vrtx WHERE geoid = %s ORDER BY vrtxid", (fid,)).fetchall()
        ]
    assert z == (-DEPTHS).tolist()
    for ext in ("vtu", "ply"):
        out = tmp_path / f"at.{ext}"
        assert main(["--dsn", db_dsn, "at", str(fid), "1", str(out)]) == 0
        assert np.array_equal(z_as_others_read_it(out), -DEPTHS)
    out = tmp_path / "at.ts"
    assert main(["--dsn", db_dsn, "at", str(fid), "1", str(out)]) == 0
    [snapshot] = formats.read(out)
    assert snapshot.metadata.get("zpositive") == "Depth" and np.array_equal(snapshot.vertices[:, 2], DEPTHS)
