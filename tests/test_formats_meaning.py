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
    assert isinstance(loaded, trimesh.Trimesh)
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


def test_a_time_series_of_depth_surfaces_goes_to_paraview_in_elevation(depth_file: Path, tmp_path: Path) -> None:
    mesh = depth_surface(depth_file)
    formats.write_pvd([(0.0, mesh), (1.0, None)], tmp_path / "series.pvd")
    pv = pytest.importorskip("pyvista")
    first_frame = sorted(tmp_path.glob("series*/*.vtu")) or sorted(tmp_path.glob("*.vtu"))
    assert np.array_equal(pv.read(first_frame[0]).points[:, 2], -DEPTHS)
    [(t0, back), (t1, gone)] = formats.read_pvd(tmp_path / "series.pvd")
    assert back is not None and back.same_as(mesh) and back.metadata["zpositive"] == "Depth" and gone is None


def test_hostile_records_of_the_convention_are_refused(depth_file: Path, tmp_path: Path) -> None:
    mesh = depth_surface(depth_file)
    ply_path = tmp_path / "deep.ply"
    formats.write(mesh, ply_path)
    data = ply_path.read_bytes()
    ply_path.write_bytes(data.replace(b"comment tgsis zpositive Depth", b"comment tgsis zpositive Down!"))
    with pytest.raises(FileFormatError, match="PLY comment 'tgsis zpositive' is 'Down!'"):
        formats.read(ply_path)
    vtu = tmp_path / "model.vtu"
    formats.write(GeometryCollection([mesh, PointSet([[0, 0, 1.0]])]), vtu, compression=None)
    text = vtu.read_bytes()
    assert b"tgsis_member_zpositive" in text
    pv = pytest.importorskip("pyvista")
    grid = pv.read(vtu)
    grid.field_data["tgsis_member_zpositive"] = np.frombuffer(b"Depth\0", dtype=np.uint8)  # one value, two members
    grid.save(tmp_path / "short.vtu")
    with pytest.raises(FileFormatError, match="tgsis_member_zpositive has 1 values for 2 members"):
        formats.read(tmp_path / "short.vtu")


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
        row = conn.execute("SELECT geoid, zpositive FROM tgsis.geometry ORDER BY geoid DESC").fetchone()
    assert row is not None
    third, zpositive = row
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
    # a second instant into the same feature (tgsis.add_instant) is stored as elevation too
    assert (
        main(["--dsn", db_dsn, "import", str(depth_file), "--class", "horizons", "--at", "2", "--feature", str(fid)])
        == 0
    )
    with psycopg.connect(db_dsn) as conn:
        later = [
            r[0]
            for r in conn.execute(
                "SELECT z FROM tgsis.times_vrtx WHERE geoid = %s AND times = 2 ORDER BY vrtxid", (fid,)
            ).fetchall()
        ]
    assert later == (-DEPTHS).tolist()
    out = tmp_path / "at.ts"
    assert main(["--dsn", db_dsn, "at", str(fid), "1", str(out)]) == 0
    [snapshot] = formats.read(out)
    assert snapshot.metadata.get("zpositive") == "Depth" and np.array_equal(snapshot.vertices[:, 2], DEPTHS)


# ---------------------------------------------------------------- OBJ: vertices, groups, polygons

# A closed octahedron as modelling tools write one: texture coordinates that differ between the faces that share a
# vertex (UV seams), normals, two objects with groups, vertices listed in an order of their own.
SEAMED_OBJ = """# octahedron with UV seams
mtllib rock.mtl
o upper
v 0 0 1
v 1 0 0
v 0 1 0
v -1 0 0
v 0 -1 0
v 0 0 -1
vt 0 0
vt 1 0
vt 0 1
vt 1 1
vt 0.5 0.5
vn 0 0 1
g upper north
usemtl stone
s 1
f 1/1/1 2/2/1 3/3/1
f 1/4/1 3/5/1 4/1/1
g upper south
f 1/2/1 4/3/1 5/4/1
f 1/5/1 5/1/1 2/2/1
o lower
f 6/1 3/2 2/3
f 6/4 4/5 3/1
f 6/2 5/3 4/4
g
f 6/5 2/1 5/2
"""


def read_obj(tmp_path: Path, text: str, name: str = "in.obj") -> Surface:
    path = tmp_path / name
    path.write_text(text)
    [mesh] = formats.read(path)
    assert isinstance(mesh, Surface)
    return mesh


def border_edges(surface: Surface) -> int:
    edges = np.sort(surface.cells[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
    _, counts = np.unique(edges, axis=0, return_counts=True)
    return int((counts == 1).sum())


def test_an_obj_with_texture_coordinates_keeps_its_geometric_vertices_closed(tmp_path: Path) -> None:
    mesh = read_obj(tmp_path, SEAMED_OBJ)
    assert mesh.n_vertices == 6 and mesh.n_cells == 8
    assert border_edges(mesh) == 0  # closed: not cut along the UV seams
    assert mesh.vertices.tolist() == [[0, 0, 1], [1, 0, 0], [0, 1, 0], [-1, 0, 0], [0, -1, 0], [0, 0, -1]]
    assert mesh.cells[0].tolist() == [0, 1, 2] and mesh.cells[-1].tolist() == [5, 1, 4]


def test_obj_groups_become_parts_with_their_names(tmp_path: Path) -> None:
    mesh = read_obj(tmp_path, SEAMED_OBJ)
    assert mesh.cell_properties["part"].tolist() == [0, 0, 1, 1, 2, 2, 2, 3]
    assert mesh.metadata["part_names"] == ["upper north", "upper south", "lower", "default"]
    # written back: a g line where the part changes, and read again the same
    out = tmp_path / "out.obj"
    formats.write(mesh, out)
    again = read_obj(tmp_path, out.read_text(), "again.obj")
    assert again.vertices.tolist() == mesh.vertices.tolist() and again.cells.tolist() == mesh.cells.tolist()
    assert again.cell_properties["part"].tolist() == mesh.cell_properties["part"].tolist()
    assert again.metadata["part_names"] == mesh.metadata["part_names"]
    # and to GOCAD: one TFACE per group, named
    ts = tmp_path / "out.ts"
    formats.write(mesh, ts)
    assert [line for line in ts.read_text().splitlines() if line.startswith("TFACE")] == [
        "TFACE upper north",
        "TFACE upper south",
        "TFACE lower",
        "TFACE default",
    ]


def test_obj_groups_are_kept_by_the_line_by_line_reader_too(tmp_path: Path) -> None:
    # a negative (relative) index and a comment send the file to the line-by-line reader
    text = SEAMED_OBJ.replace("f 6/5 2/1 5/2", "f -1/5 2/1 5/2  # the last face")
    mesh = read_obj(tmp_path, text)
    assert mesh.cell_properties["part"].tolist() == [0, 0, 1, 1, 2, 2, 2, 3]
    assert mesh.metadata["part_names"] == ["upper north", "upper south", "lower", "default"]
    assert border_edges(mesh) == 0


def test_an_obj_of_one_group_has_no_part_property_but_its_name(tmp_path: Path) -> None:
    mesh = read_obj(tmp_path, "g fault A\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    assert "part" not in mesh.cell_properties and mesh.metadata["part_names"] == ["fault A"]


def test_the_vertex_order_of_an_obj_is_kept(tmp_path: Path) -> None:
    rng = np.random.default_rng(7)
    points = rng.normal(size=(40, 3)).round(6)
    order = rng.permutation(40)
    lines = [f"v {x} {y} {z}" for x, y, z in points[order]]
    faces = [
        f"f {a + 1}/{a + 1} {b + 1}/{b + 1} {c + 1}/{c + 1}"
        for a, b, c in rng.integers(0, 40, (30, 3))
        if len({a, b, c}) == 3
    ]
    mesh = read_obj(tmp_path, "\n".join(lines + [f"vt {u} 0" for u in range(40)] + faces) + "\n")
    assert np.array_equal(mesh.vertices, points[order])


QUADS = """v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
v 2 0 0
v 2 1 0
f 1 2 3 4
f 2 5 6 3
"""


def test_planar_convex_quads_are_split_with_a_warning_in_obj_off_ply_vtp_and_vtk(tmp_path: Path) -> None:
    pv = pytest.importorskip("pyvista")
    points = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [2, 0, 0], [2, 1, 0]], dtype=np.float64)
    quads = pv.PolyData(points, faces=np.array([4, 0, 1, 2, 3, 4, 1, 4, 5, 2]))
    quads.cell_data["rock"] = np.array([7, 9])
    (tmp_path / "q.obj").write_text(QUADS)
    (tmp_path / "q.off").write_text(
        "OFF\n6 2 0\n" + "\n".join(" ".join(map(str, p)) for p in points.tolist()) + "\n4 0 1 2 3\n4 1 4 5 2\n"
    )
    (tmp_path / "q.ply").write_text(
        ply(
            [
                "element vertex 6",
                "property float x",
                "property float y",
                "property float z",
                "element face 2",
                "property list uchar int vertex_indices",
                "property uchar rock",
            ],
            [" ".join(map(str, p)) for p in points.tolist()] + ["4 0 1 2 3 7", "4 1 4 5 2 9"],
        )
    )
    quads.save(tmp_path / "q.vtp")
    quads.save(tmp_path / "q.vtk")
    for ext in ("obj", "off", "ply", "vtp", "vtk"):
        with pytest.warns(tgsis.PolygonsSplitWarning, match="2 faces|2 polygons") as caught:
            [mesh] = formats.read(tmp_path / f"q.{ext}")
        assert caught[0].message.count == 2  # type: ignore[union-attr]
        assert isinstance(mesh, Surface) and mesh.n_cells == 4, ext
        assert mesh.cells.tolist() == [[0, 1, 2], [0, 2, 3], [1, 4, 5], [1, 5, 2]], ext
        assert mesh.metadata["polygons_split"] == 2
        assert np.isclose(mesh.cell_measures().sum(), 2.0), ext  # the quads' area: no shape changed
        if ext in ("ply", "vtp", "vtk"):
            assert mesh.cell_properties["rock"].tolist() == [7, 7, 9, 9], ext


@pytest.mark.parametrize(("corner", "reason"), [("2 1 0.25", "is not planar"), ("1.2 0.5 0", "is not convex")])
def test_a_non_planar_or_non_convex_polygon_is_refused_in_every_format_naming_it(
    tmp_path: Path, corner: str, reason: str
) -> None:
    pv = pytest.importorskip("pyvista")
    text = QUADS.replace("v 2 1 0\n", f"v {corner}\n")
    (tmp_path / "q.obj").write_text(text)
    points = np.array([[float(v) for v in line.split()[1:]] for line in text.splitlines() if line.startswith("v ")])
    (tmp_path / "q.off").write_text(
        "OFF\n6 2 0\n" + "\n".join(" ".join(map(repr, p)) for p in points.tolist()) + "\n4 0 1 2 3\n4 1 4 5 2\n"
    )
    quads = pv.PolyData(points, faces=np.array([4, 0, 1, 2, 3, 4, 1, 4, 5, 2]))
    quads.save(tmp_path / "q.ply", binary=False)
    quads.save(tmp_path / "q.vtp")
    quads.save(tmp_path / "q.vtk")
    for ext, where in (
        ("obj", ":8: OBJ face 1"),
        ("off", ":10: OFF face 1"),
        ("ply", "PLY face 1"),
        ("vtp", "PolyData cell 1"),
        ("vtk", "POLYDATA cell 1"),
    ):
        with pytest.raises(FileFormatError, match=f"{where} has 4 .*{reason}") as caught:
            formats.read(tmp_path / f"q.{ext}")
        assert caught.value.hint is not None and "triangulate" in caught.value.hint.lower(), ext


def test_a_star_polygon_is_refused(tmp_path: Path) -> None:
    angles = np.arange(5) * 2 * np.pi / 5
    lines = [f"v {float(np.cos(a))!r} {float(np.sin(a))!r} 0" for a in angles] + ["f 1 3 5 2 4"]
    (tmp_path / "star.obj").write_text("\n".join(lines) + "\n")
    with pytest.raises(FileFormatError, match="OBJ face 0 has 5 corners and is not convex"):
        formats.read(tmp_path / "star.obj")


def test_cli_import_of_quads_says_they_were_split(
    db_dsn: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    (tmp_path / "q.obj").write_text(QUADS)
    assert main(["--dsn", db_dsn, "class", "create", "plates", "--geotype", "SURFACE"]) == 0
    capsys.readouterr()
    assert main(["--dsn", db_dsn, "import", str(tmp_path / "q.obj"), "--class", "plates"]) == 0
    err = capsys.readouterr().err
    assert err.startswith(f"tgsis: warning: {tmp_path / 'q.obj'}: 2 faces of more than 3 corners were split")
    with psycopg.connect(db_dsn) as conn:
        assert conn.execute("SELECT ncell, metadata->>'polygons_split' FROM tgsis.geometry").fetchone() == (4, "2")


# ---------------------------------------------------------------- PLY triangle strips


def ply(header: list[str], body: list[str]) -> str:
    return "\n".join(["ply", "format ascii 1.0", *header, "end_header", *body]) + "\n"


GRID = [f"{x} {y} 0" for y in range(2) for x in range(4)]  # 0 1 2 3 / 4 5 6 7


def test_a_ply_of_triangle_strips_is_a_surface(tmp_path: Path) -> None:
    # one strip row 0-1 of the grid, a restart, then the same strip with a degenerate join
    text = ply(
        [
            "element vertex 8",
            "property float x",
            "property float y",
            "property float z",
            "element tristrips 1",
            "property list int int vertex_indices",
        ],
        [*GRID, "14 4 0 5 1 6 2 -1 6 2 7 3 3 3 3"],
    )
    path = tmp_path / "strips.ply"
    path.write_text(text)
    [mesh] = formats.read(path)
    assert isinstance(mesh, Surface)
    assert mesh.cells.tolist() == [
        [4, 0, 5],
        [5, 0, 1],
        [5, 1, 6],
        [6, 1, 2],  # alternate triangles turned
        [6, 2, 7],
        [7, 2, 3],
    ]  # restarted; 3 3 3 dropped
    edges = [mesh.vertices[mesh.cells[:, j]] - mesh.vertices[mesh.cells[:, 0]] for j in (1, 2)]
    normals = np.cross(edges[0], edges[1])
    assert np.all(normals[:, 2] > 0)  # all facing one way (up)
    assert border_edges(mesh) == 8


def test_binary_big_endian_strips_and_faces_together(tmp_path: Path) -> None:
    header = (
        b"ply\nformat binary_big_endian 1.0\nelement vertex 8\nproperty double x\nproperty double y\n"
        b"property double z\nelement face 1\nproperty list uchar int vertex_indices\nelement tristrips 1\n"
        b"property list int int vertex_indices\nend_header\n"
    )
    vertices = np.array([[float(v) for v in p.split()] for p in GRID], dtype=">f8").tobytes()
    face = np.array([3], dtype=">u1").tobytes() + np.array([0, 1, 4], dtype=">i4").tobytes()
    strip = np.array([6], dtype=">i4").tobytes() + np.array([5, 1, 6, 2, 7, 3], dtype=">i4").tobytes()
    path = tmp_path / "both.ply"
    path.write_bytes(header + vertices + face + strip)
    [mesh] = formats.read(path)
    assert mesh.cells.tolist() == [[0, 1, 4], [5, 1, 6], [6, 1, 2], [6, 2, 7], [7, 2, 3]]


def test_a_strip_index_outside_the_vertices_is_refused(tmp_path: Path) -> None:
    path = tmp_path / "bad.ply"
    path.write_text(
        ply(
            [
                "element vertex 8",
                "property float x",
                "property float y",
                "property float z",
                "element tristrips 1",
                "property list int int vertex_indices",
            ],
            [*GRID, "4 4 0 5 8"],
        )
    )
    with pytest.raises(FileFormatError, match=r"bad.ply:18: PLY tristrips 0 uses vertex 8, outside 0..7"):
        formats.read(path)


def test_strips_and_faces_with_different_properties_are_refused(tmp_path: Path) -> None:
    path = tmp_path / "mixed.ply"
    path.write_text(
        ply(
            [
                "element vertex 8",
                "property float x",
                "property float y",
                "property float z",
                "element face 1",
                "property list uchar int vertex_indices",
                "property uchar rock",
                "element tristrips 1",
                "property list int int vertex_indices",
            ],
            [*GRID, "3 0 1 4 7", "4 5 1 6 2"],
        )
    )
    with pytest.raises(FileFormatError, match=r"face and tristrips elements have different properties \(\['rock'\]"):
        formats.read(path)


def test_an_element_of_cells_tgsis_does_not_know_is_refused(tmp_path: Path) -> None:
    path = tmp_path / "polys.ply"
    path.write_text(
        ply(
            [
                "element vertex 8",
                "property float x",
                "property float y",
                "property float z",
                "element polygon 1",
                "property list uchar int vertex_indices",
            ],
            [*GRID, "3 0 1 4"],
        )
    )
    with pytest.raises(FileFormatError, match="PLY element 'polygon' lists vertices .* would be lost"):
        formats.read(path)
    # a scanner's range grid (one vertex or none per grid cell) holds no cells: the points are read
    path.write_text(
        ply(
            [
                "element vertex 8",
                "property float x",
                "property float y",
                "property float z",
                "element range_grid 2",
                "property list uchar int vertex_indices",
            ],
            [*GRID, "1 0", "0"],
        )
    )
    [points] = formats.read(path)
    assert isinstance(points, PointSet) and points.n_vertices == 8


def test_a_picture_of_a_depth_surface_draws_it_below_the_ground(
    depth_file: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    pytest.importorskip("matplotlib")
    from mpl_toolkits.mplot3d import Axes3D

    from tgsis import pictures

    drawn: list[np.ndarray] = []
    original = Axes3D.plot_trisurf

    def spy(self: Axes3D, *args: object, **kwargs: object) -> object:
        drawn.append(np.asarray(args[2], dtype=np.float64))
        return original(self, *args, **kwargs)

    monkeypatch.setattr(Axes3D, "plot_trisurf", spy)
    pictures.scene([depth_surface(depth_file)], tmp_path / "deep.png", title="deep")
    assert [z.tolist() for z in drawn] == [(-DEPTHS).tolist()]


def test_the_browser_view_draws_a_depth_line_set_z_up(
    db_dsn: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from tgsis.view import app

    with psycopg.connect(db_dsn, autocommit=True) as conn:
        tgsis.create_feature_class(conn, "wells", "MULTILINESTRING")
        wells = LineSet([[0, 0, 10.0], [0, 0, 900.0]], [[0, 1]], metadata={"zpositive": "Depth"})
        fid = tgsis.insert_feature(conn, "wells", wells)
        drawn, when = app._mesh_of(conn, tgsis.get_feature_class(conn, "wells"), fid, None, None)
    assert drawn is not None and when is None
    assert drawn.vertices[:, 2].tolist() == [-10.0, -900.0]


def test_interpolation_of_depth_surfaces_is_in_elevation(tmp_path: Path) -> None:
    """A source in depth and a target in elevation (two files, two conventions) morph as the shapes they are."""
    from tgsis.interpolation import InterpolationSetup
    from tgsis.interpolation.interpolate import interpolate

    u, v = np.meshgrid(np.linspace(0, 4, 9), np.linspace(0, 2, 5))
    xy = np.column_stack([u.ravel(), v.ravel()])
    cells = []
    for j in range(4):
        for i in range(8):
            a = j * 9 + i
            cells += [[a, a + 1, a + 10], [a, a + 10, a + 9]]
    elevations = -1000.0 - 50.0 * np.sin(xy[:, 0])  # a curved horizon about 1 km deep
    target = Surface(np.column_stack([xy, elevations]), cells, metadata={"zpositive": "Elevation"})
    source = Surface(np.column_stack([xy, -elevations]), cells, metadata={"zpositive": "Depth"})  # the same shape
    corners = (0, 8, 44, 36)
    result = interpolate(source, target, InterpolationSetup(corners, corners, steps=3, tolerance=0.01), 0.0, 1.0)
    for t in (0.0, 0.5, 1.0):
        shape = result.evolving.at(t)
        assert shape is not None
        assert np.allclose(shape.vertices[:, 2], elevations, atol=1e-6), t  # identity: the horizon all along


def test_obj_groups_are_stored_as_parts_and_exported(db_dsn: str, tmp_path: Path) -> None:
    source = tmp_path / "rock.obj"
    source.write_text(SEAMED_OBJ)
    assert main(["--dsn", db_dsn, "class", "create", "bodies", "--geotype", "SURFACE"]) == 0
    assert main(["--dsn", db_dsn, "import", str(source), "--class", "bodies"]) == 0
    with psycopg.connect(db_dsn) as conn:
        [(fid,)] = conn.execute("SELECT geoid FROM tgsis.geometry").fetchall()
        runs = conn.execute(
            "SELECT firstid, lastid, part FROM tgsis.part WHERE geoid = %s ORDER BY firstid", (fid,)
        ).fetchall()
    assert [r[2] for r in runs] == [0, 1, 2, 3]
    for ext in ("obj", "ts"):
        out = tmp_path / f"out.{ext}"
        assert main(["--dsn", db_dsn, "export", str(fid), str(out)]) == 0
        [back] = formats.read(out)
        assert back.cell_properties["part"].tolist() == [0, 0, 1, 1, 2, 2, 2, 3], ext
        names = back.metadata.get("part_names") or back.metadata.get("gocad_part_names")
        assert names == ["upper north", "upper south", "lower", "default"], ext
        assert border_edges(back) == 0  # type: ignore[arg-type]
