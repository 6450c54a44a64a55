"""ParaView collection files (.pvd): time series round trips, frames without an object, other writers' files, errors."""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from tests.shared_data import cfm
from tgsis import formats
from tgsis.errors import FileFormatError
from tgsis.formats.gocad import read_tsurf
from tgsis.formats.pvd import Frame, read_pvd, write_pvd
from tgsis.formats.vtk import format_empty_vtu, parse_vtu_geometry, read_vtu, write_vtu
from tgsis.mesh import Geometry, GeometryCollection, LineSet, PointSet, Surface, TetraMesh

DATA = Path(__file__).resolve().parent / "data"

#: Times that a decimal format of fewer than 17 digits would not give back exactly.
TIMES = [-2.5, 0.1 + 0.2, 1 / 3, 5e-324 + 1.0, 2 / 3 * 1e20]


def moving_surface(step: int) -> Surface:
    """A surface whose vertices move with ``step``, with vertex and cell properties of several dtypes."""
    rng = np.random.default_rng(step)
    vertices = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0.5]], dtype=np.float64)
    vertices = vertices + step * rng.normal(size=(4, 3))
    return Surface(
        vertices,
        [[0, 1, 2], [1, 3, 2]],
        vertex_properties={"depth": -vertices[:, 2], "flag": np.array([step, 0, 1, 2], dtype=np.int32)},
        cell_properties={
            "slip": rng.uniform(size=2).astype(np.float32),
            "code": np.array([step, -step], dtype=np.int64),
        },
        name=f"fault at step {step}",
    )


def same_frames(back: list[Frame], frames: list[Frame]) -> bool:
    """Times exactly equal, geometries bit-identical with the same property dtypes and names."""
    assert [t for t, _ in back] == [t for t, _ in frames]
    for (_, a), (_, b) in zip(back, frames):
        if a is None or b is None:
            assert a is b
            continue
        assert a.same_as(b) and a.name == b.name
        for m, n in zip(
            a.members if isinstance(a, GeometryCollection) else [a],
            b.members if isinstance(b, GeometryCollection) else [b],
        ):
            assert {k: v.dtype for k, v in m.vertex_properties.items()} == {
                k: v.dtype for k, v in n.vertex_properties.items()
            }
            assert {k: v.dtype for k, v in m.cell_properties.items()} == {
                k: v.dtype for k, v in n.cell_properties.items()
            }
            assert m.name == n.name
    return True


def listed(pvd: Path) -> list[dict[str, str]]:
    """The attributes of every DataSet of a .pvd file."""
    return [dict(e.attrib) for e in ET.parse(pvd).getroot().iter("DataSet")]


# ---- writing and reading back


@pytest.mark.parametrize("encoding", ["binary", "appended"])
def test_round_trip_of_moving_surfaces(encoding: str, tmp_path: Path) -> None:
    frames: list[Frame] = [(t, moving_surface(i)) for i, t in enumerate(TIMES)]
    pvd = tmp_path / "fault.pvd"
    written = write_pvd(frames, pvd, encoding=encoding)  # type: ignore[arg-type]
    names = [f"fault_{i:06d}.vtu" for i in range(len(TIMES))]
    assert written == [tmp_path / "fault" / name for name in names] + [pvd]
    assert sorted(p.name for p in (tmp_path / "fault").iterdir()) == names  # no temporary file left
    assert listed(pvd) == [
        {"timestep": repr(t), "group": "", "part": "0", "file": f"fault/{name}"} for t, name in zip(TIMES, names)
    ]
    root = ET.parse(pvd).getroot()
    assert (root.tag, root.get("type")) == ("VTKFile", "Collection")
    back = read_pvd(pvd)
    assert same_frames(back, frames)
    assert all(type(t) is float for t, _ in back)
    assert not back[0][1].vertices.tolist() == back[1][1].vertices.tolist()  # type: ignore[union-attr]


def test_times_of_any_real_type_are_written_as_floats(tmp_path: Path) -> None:
    frames: list[Any] = [
        (np.int64(-3), moving_surface(0)),
        (0, moving_surface(1)),
        (np.float32(0.1), None),
        (1e308, moving_surface(2)),
    ]
    write_pvd(frames, tmp_path / "s.pvd")
    assert [t for t, _ in read_pvd(tmp_path / "s.pvd")] == [-3.0, 0.0, float(np.float32(0.1)), 1e308]


def test_frames_without_an_object_are_empty_grids_that_read_back_as_none(tmp_path: Path) -> None:
    """Before birth and after death: an empty grid is listed at each such time (ParaView shows nothing then)."""
    frames: list[Frame] = [(0.0, None), (1.0, None), (2.0, moving_surface(1)), (3.0, moving_surface(2)), (4.0, None)]
    pvd = tmp_path / "born.pvd"
    write_pvd(frames, pvd)
    assert [d["timestep"] for d in listed(pvd)] == ["0.0", "1.0", "2.0", "3.0", "4.0"]
    empty = tmp_path / "born" / "born_000000.vtu"
    piece = ET.parse(empty).getroot().find("UnstructuredGrid/Piece")
    assert piece is not None and (piece.get("NumberOfPoints"), piece.get("NumberOfCells")) == ("0", "0")
    assert read_vtu(empty).n_vertices == 0  # still a valid .vtu for a plain reader
    assert same_frames(read_pvd(pvd), frames)


def test_empty_meshes_are_not_none(tmp_path: Path) -> None:
    frames: list[Frame] = [
        (0.0, Surface(np.empty((0, 3)), [], name="nothing yet")),
        (1.0, TetraMesh(np.eye(3)[:0], [])),
        (2.0, None),
    ]
    write_pvd(frames, tmp_path / "e.pvd")
    back = read_pvd(tmp_path / "e.pvd")
    assert isinstance(back[0][1], Surface) and isinstance(back[1][1], TetraMesh) and back[2][1] is None
    assert same_frames(back, frames)


def test_collection_frames(tmp_path: Path) -> None:
    surface = moving_surface(3)
    points = PointSet(
        surface.vertices[:2] + 10,
        vertex_properties={"depth": np.array([1.0, 2.0]), "flag": np.array([5, 6], dtype=np.int32)},
        cell_properties={"slip": np.array([0.5, 1.5], dtype=np.float32), "code": np.array([7, 8], dtype=np.int64)},
        name="wells",
    )
    lines = LineSet(
        surface.vertices, [[0, 1], [1, 3]], vertex_properties={k: v + 1 for k, v in surface.vertex_properties.items()}
    )
    frames: list[Frame] = [
        (0.0, surface),
        (0.5, GeometryCollection([surface, points], name="block")),
        (1.0, GeometryCollection([lines])),
        (2.0, None),
    ]
    write_pvd(frames, tmp_path / "c.pvd")
    back = read_pvd(tmp_path / "c.pvd")
    assert isinstance(back[1][1], GeometryCollection) and back[1][1].name == "block"
    assert isinstance(back[2][1], GeometryCollection) and len(back[2][1]) == 1  # a collection of one stays one
    assert same_frames(back, frames)


def test_no_frames(tmp_path: Path) -> None:
    assert write_pvd([], tmp_path / "none.pvd") == [tmp_path / "none.pvd"]
    assert read_pvd(tmp_path / "none.pvd") == []


def test_rewriting_replaces_the_series(tmp_path: Path) -> None:
    pvd = tmp_path / "s.pvd"
    write_pvd([(float(i), moving_surface(i)) for i in range(5)], pvd)
    (tmp_path / "s" / "notes.txt").write_text("mine")
    frames: list[Frame] = [(10.0 + i, moving_surface(10 + i)) for i in range(3)]
    write_pvd(frames, pvd)
    assert same_frames(read_pvd(pvd), frames)
    # the frame files of the longer series are gone, other files stay
    assert sorted(p.name for p in (tmp_path / "s").iterdir()) == ["notes.txt"] + [f"s_{i:06d}.vtu" for i in range(3)]


@pytest.mark.parametrize(
    "relative", ["formats/CRFA-SJMZ-CHMN-Big_Spring_fault-50dip-CFM5.ts", "formats/WTRA-NCFS-PPT-Pitas_Point_fault.ts"]
)
def test_cfm_surface_sliding_over_time(relative: str, tmp_path: Path) -> None:
    surface = read_tsurf(cfm(relative))
    frames: list[Frame] = [(0.0, None)]
    for i, t in enumerate([1e3, 2.5e3, 1e4]):
        frames.append(
            (
                t,
                Surface(
                    surface.vertices + [i * 0.1, -i * 3.7, i / 3],
                    surface.cells,
                    vertex_properties=surface.vertex_properties,
                    cell_properties=surface.cell_properties,
                    name=surface.name,
                ),
            )
        )
    pvd = tmp_path / "cfm.pvd"
    write_pvd(frames, pvd, encoding="appended")
    back = read_pvd(pvd)
    assert same_frames(back, frames)
    assert back[1][1] is not None and back[1][1].same_as(surface)


# ---- files of ParaView and other writers


def write_parts(folder: Path) -> dict[str, Geometry]:
    """Part files of a ParaView-style series in ``folder``: meshes, an empty grid as VTK writes one, a collection."""
    folder.mkdir()
    meshes: dict[str, Geometry] = {
        "a0.vtu": moving_surface(1),
        "a1.vtu": moving_surface(2),
        "b0.vtu": PointSet([[1.0, 2.0, 3.0]], name="well"),
        "b1.vtu": LineSet([[0.0, 0, 0], [0.0, 0, 1]], [[0, 1]]),
    }
    for name, mesh in meshes.items():
        write_vtu(mesh, folder / name)
    (folder / "tetra.vtu").write_bytes((DATA / "vtk" / "tetra_ascii.vtu").read_bytes())
    # what vtkXMLUnstructuredGridWriter writes for an empty vtkUnstructuredGrid: no arrays at all
    (folder / "empty.vtu").write_text(
        '<?xml version="1.0"?>\n<VTKFile type="UnstructuredGrid" version="1.0" byte_order="LittleEndian" '
        'header_type="UInt64">\n  <UnstructuredGrid>\n    <Piece NumberOfPoints="0" NumberOfCells="0">\n'
        "      <PointData>\n      </PointData>\n      <CellData>\n      </CellData>\n      <Points>\n      </Points>\n"
        "      <Cells>\n      </Cells>\n    </Piece>\n  </UnstructuredGrid>\n</VTKFile>\n"
    )
    write_vtu(GeometryCollection([Surface(np.eye(3), [[0, 1, 2]]), PointSet([[0.0, 0, 0]])]), folder / "collection.vtu")
    return meshes


def write_paraview_pvd(path: Path, datasets: list[str]) -> Path:
    path.write_text(
        '<?xml version="1.0"?>\n<VTKFile type="Collection" version="1.0" byte_order="LittleEndian" '
        'header_type="UInt64">\n  <Collection>\n'
        + "".join(f"    {d}\n" for d in datasets)
        + "  </Collection>\n</VTKFile>\n"
    )
    return path


def test_paraview_style_parts_and_times_out_of_order(tmp_path: Path) -> None:
    meshes = write_parts(tmp_path / "parts")
    pvd = write_paraview_pvd(
        tmp_path / "pv.pvd",
        [
            '<DataSet timestep="2" part="1" file="parts/b1.vtu" name="wells"/>',
            '<DataSet timestep="2" part="0" file="parts/a1.vtu" name="fault"/>',
            '<DataSet timestep="0.5" part="1" file="parts/b0.vtu" name="wells"/>',
            '<DataSet timestep="0.5" part="0" file="parts/a0.vtu" name="fault"/>',
            f'<DataSet timestep="1e-3" part="0" file="{(tmp_path / "parts" / "tetra.vtu").as_posix()}"/>',
            '<DataSet timestep="7" group="" part="0" file="parts/empty.vtu"/>',
            '<DataSet timestep="7" group="" part="1" file="parts/a0.vtu"/>',
            '<DataSet timestep="8" part="0" file="parts/empty.vtu"/>',
            '<DataSet timestep="8" part="1" file="parts/empty.vtu"/>',
        ],
    )
    back = read_pvd(pvd)
    assert [t for t, _ in back] == [1e-3, 0.5, 2.0, 7.0, 8.0]
    tetra = back[0][1]
    assert isinstance(tetra, TetraMesh) and tetra.name == "block"  # one part, absolute path
    for (_, geometry), first, second in ((back[1], "a0.vtu", "b0.vtu"), (back[2], "a1.vtu", "b1.vtu")):
        assert isinstance(geometry, GeometryCollection) and geometry.name is None
        assert geometry.same_as(GeometryCollection([meshes[first], meshes[second]]))  # type: ignore[list-item]
        assert [m.name for m in geometry] == [meshes[first].name, meshes[second].name]
    assert isinstance(back[3][1], Surface) and meshes["a0.vtu"].same_as(back[3][1])  # the empty part is left out
    assert back[4][1] is None  # every part empty


def test_parts_are_ordered_by_group_then_part(tmp_path: Path) -> None:
    meshes = write_parts(tmp_path / "parts")
    pvd = write_paraview_pvd(
        tmp_path / "g.pvd",
        [
            '<DataSet timestep="0" group="b" part="0" file="parts/b0.vtu"/>',
            '<DataSet timestep="0" group="a" part="2" file="parts/a1.vtu"/>',
            '<DataSet timestep="0" group="a" part="1" file="parts/a0.vtu"/>',
        ],
    )
    [(time, geometry)] = read_pvd(pvd)
    assert time == 0.0 and isinstance(geometry, GeometryCollection)
    assert geometry.same_as(GeometryCollection([meshes["a0.vtu"], meshes["a1.vtu"], meshes["b0.vtu"]]))  # type: ignore[list-item]


def test_a_collection_part_among_several_parts_is_refused(tmp_path: Path) -> None:
    write_parts(tmp_path / "parts")
    pvd = write_paraview_pvd(
        tmp_path / "n.pvd",
        [
            '<DataSet timestep="0" part="0" file="parts/a0.vtu"/>',
            '<DataSet timestep="0" part="1" file="parts/collection.vtu"/>',
        ],
    )
    with pytest.raises(
        FileFormatError,
        match=r"time 0\.0 has 2 parts and part .*collection\.vtu holds a "
        r"collection of 2 meshes: collections do not nest",
    ):
        read_pvd(pvd)


def test_empty_vtu_reads_as_none_and_typed_empty_grids_do_not() -> None:
    assert parse_vtu_geometry(format_empty_vtu()) is None
    assert parse_vtu_geometry(format_empty_vtu(encoding="appended")) is None
    with pytest.raises(FileFormatError, match="unknown VTU encoding"):
        format_empty_vtu(encoding="ascii")  # type: ignore[arg-type]


# ---- errors when writing: nothing written


@pytest.mark.parametrize(
    ("times", "message"),
    [
        ([0.0, math.nan], r"frame 1 has time nan: times must be finite numbers"),
        ([math.inf, 1.0], r"frame 0 has time inf: times must be finite numbers"),
        ([0.0, 1.0, -math.inf], r"frame 2 has time -inf: times must be finite numbers"),
        ([0.0, "1.5"], r"frame 1 has time '1\.5': times must be finite numbers"),
        ([None], r"frame 0 has time None: times must be finite numbers"),
        ([False, 1.0], r"frame 0 has time False: times must be finite numbers"),
        ([0.0, 10**400], r"frame 1 has time 1000.*: times must be finite numbers"),
        ([0.0, 1.0, 1.0], r"frame 2 has time 1\.0, not after frame 1's 1\.0: times must be strictly increasing"),
        ([0.0, 0.1 + 0.2, 0.3], r"frame 2 has time 0\.3, not after frame 1's 0\.30000000000000004"),
        ([-0.0, 0.0], r"frame 1 has time 0\.0, not after frame 0's -0\.0"),
        ([0.0, 2.0, 1.0], r"frame 2 has time 1\.0, not after frame 1's 2\.0"),
    ],
)
def test_bad_times_write_nothing(times: list[Any], message: str, tmp_path: Path) -> None:
    with pytest.raises(FileFormatError, match=message) as info:
        write_pvd([(t, moving_surface(i)) for i, t in enumerate(times)], tmp_path / "t.pvd")
    assert info.value.path == str(tmp_path / "t.pvd")
    assert list(tmp_path.iterdir()) == []


def test_bad_geometry_or_name_writes_nothing(tmp_path: Path) -> None:
    with pytest.raises(FileFormatError, match="frame 1 holds a str, not a mesh, a collection or None"):
        write_pvd([(0.0, None), (1.0, "surface")], tmp_path / "g.pvd")  # type: ignore[list-item]
    with pytest.raises(FileFormatError, match="must end in .pvd"):
        write_pvd([(0.0, moving_surface(0))], tmp_path / "g.vtu")
    with pytest.raises(FileFormatError, match="cannot create the frame folder"):
        write_pvd([(0.0, moving_surface(0))], tmp_path / "missing" / "g.pvd")
    assert list(tmp_path.iterdir()) == []


def unwritable_collection() -> GeometryCollection:
    """A collection VTU cannot hold: a vertex property on one member only."""
    return GeometryCollection([moving_surface(0), PointSet([[0.0, 0, 0]])])


def test_a_frame_that_cannot_be_written_leaves_no_partial_output(tmp_path: Path) -> None:
    frames: list[Frame] = [(0.0, moving_surface(0)), (1.0, None), (2.0, unwritable_collection())]
    with pytest.raises(FileFormatError, match="vertex property 'depth' is on some members"):
        write_pvd(frames, tmp_path / "p.pvd")
    assert list(tmp_path.iterdir()) == []


def test_a_failed_rewrite_keeps_the_old_series(tmp_path: Path) -> None:
    pvd = tmp_path / "p.pvd"
    old: list[Frame] = [(float(i), moving_surface(i)) for i in range(4)]
    write_pvd(old, pvd)
    before = {p: p.read_bytes() for p in tmp_path.rglob("*") if p.is_file()}
    with pytest.raises(FileFormatError, match="vertex property 'depth' is on some members"):
        write_pvd([(5.0, moving_surface(7)), (6.0, unwritable_collection())], pvd)
    assert {p: p.read_bytes() for p in tmp_path.rglob("*") if p.is_file()} == before
    assert same_frames(read_pvd(pvd), old)


# ---- errors when reading


@pytest.mark.parametrize(
    ("dataset", "message"),
    [
        ('<DataSet part="0" file="parts/a0.vtu"/>', "DataSet 1 has no timestep attribute"),
        ('<DataSet timestep="soon" file="parts/a0.vtu"/>', "DataSet 1 has timestep 'soon', not a number"),
        ('<DataSet timestep="" file="parts/a0.vtu"/>', "DataSet 1 has timestep '', not a number"),
        ('<DataSet timestep="nan" file="parts/a0.vtu"/>', "DataSet 1 has timestep 'nan', not a finite number"),
        ('<DataSet timestep="-inf" file="parts/a0.vtu"/>', "DataSet 1 has timestep '-inf', not a finite number"),
        ('<DataSet timestep="1" part="first" file="parts/a0.vtu"/>', "DataSet 1 has part 'first', not an integer"),
        ('<DataSet timestep="1"/>', "DataSet 1 has no file attribute"),
        ('<DataSet timestep="1" file="parts/a0.vtp"/>', r"DataSet 1 refers to 'parts/a0\.vtp', not a \.vtu file"),
        ('<DataSet timestep="1" file="parts/all.pvtu"/>', r"DataSet 1 refers to 'parts/all\.pvtu', not a \.vtu file"),
        (
            '<DataSet timestep="1" file="parts/gone.vtu"/>',
            r"DataSet 1 refers to 'parts/gone\.vtu', which does not exist",
        ),
        ('<DataSet timestep="1" file="parts"/>', r"DataSet 1 refers to 'parts', not a \.vtu file"),
    ],
)
def test_bad_datasets(dataset: str, message: str, tmp_path: Path) -> None:
    write_parts(tmp_path / "parts")
    pvd = write_paraview_pvd(tmp_path / "bad.pvd", ['<DataSet timestep="0" file="parts/a0.vtu"/>', dataset])
    with pytest.raises(FileFormatError, match=message) as info:
        read_pvd(pvd)
    assert info.value.path == str(pvd)


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ('<VTKFile type="Collection"><Collection><DataSet timestep="0" file="x.vtu">', "not well-formed XML"),
        ('<VTKFile type="UnstructuredGrid"><Collection/></VTKFile>', "not a ParaView collection file"),
        ('<Collection><DataSet timestep="0" file="x.vtu"/></Collection>', "not a ParaView collection file"),
        (
            '<VTKFile type="Collection"></VTKFile>',
            r"not a ParaView collection file \(root <VTKFile type='Collection'> "
            r"with a <Collection>\)",
        ),
    ],
)
def test_bad_pvd_files(text: str, message: str, tmp_path: Path) -> None:
    pvd = tmp_path / "bad.pvd"
    pvd.write_text(text)
    with pytest.raises(FileFormatError, match=message) as info:
        read_pvd(pvd)
    assert info.value.path == str(pvd)


def test_missing_pvd_and_broken_vtu(tmp_path: Path) -> None:
    with pytest.raises(FileFormatError, match="cannot read the file"):
        read_pvd(tmp_path / "absent.pvd")
    pvd = tmp_path / "b.pvd"
    write_pvd([(0.0, moving_surface(0)), (1.0, moving_surface(1))], pvd)
    broken = tmp_path / "b" / "b_000001.vtu"
    broken.write_bytes(broken.read_bytes()[:200])
    with pytest.raises(FileFormatError, match="not well-formed XML") as info:
        read_pvd(pvd)
    assert info.value.path == str(broken)  # the message names the frame file


def test_the_registry_points_to_the_pvd_functions(tmp_path: Path) -> None:
    for call in (
        lambda: formats.read(tmp_path / "s.pvd"),
        lambda: formats.write(moving_surface(0), tmp_path / "s.pvd"),
        lambda: formats.read(tmp_path / "s.xml", format="pvd"),
    ):
        with pytest.raises(FileFormatError, match="time series") as info:
            call()
        assert "read_pvd" in str(info.value.hint)
    assert formats.read_pvd is read_pvd and formats.write_pvd is write_pvd
