"""VTK XML UnstructuredGrid (.vtu): round trips, standard layout, other writers' encodings, errors."""

from __future__ import annotations

import base64
import xml.etree.ElementTree as ET
import zlib
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt
import pytest

from tests.shared_data import cfm
from tgsis import formats
from tgsis.errors import FileFormatError
from tgsis.formats.gocad import read_tsurf
from tgsis.formats.vtk import format_vtu, parse_vtu, read_vtu, write_vtu
from tgsis.mesh import LineSet, Mesh, PointSet, Surface, TetraMesh

DATA = Path(__file__).resolve().parent / "data"


def meshes() -> list[Mesh]:
    """One mesh of each type with properties of several dtypes, NaN, -0.0 and extreme values."""
    rng = np.random.default_rng(3)
    n = 30
    vertices = rng.uniform(-1e6, 1e6, (n, 3))
    vertices[0] = [-0.0, 5e-324, 1e300]
    vertex_properties: dict[str, Any] = {
        "f64": rng.normal(size=n),
        "f32": rng.normal(size=n).astype(np.float32),
        "i8": np.arange(n, dtype=np.int8) - 10,
        "u16": np.arange(n, dtype=np.uint16) * 1000,
        "i64": np.arange(n, dtype=np.int64) * 2**40,
        "u64": np.full(n, 2**64 - 1, dtype=np.uint64),
    }
    vertex_properties["f64"][4] = np.nan

    def cell_props(m: int) -> dict[str, Any]:
        return {
            "part": np.arange(m, dtype=np.int64) % 3,
            "area": rng.uniform(size=m).astype(np.float32),
            "code": np.arange(m, dtype=np.int32) - 5,
        }

    segments = np.stack([np.arange(n - 1), np.arange(1, n)], 1)
    triangles = np.stack([np.arange(n - 2), np.arange(1, n - 1), np.arange(2, n)], 1)
    tetras = np.stack([np.arange(n - 3) + j for j in range(4)], 1)
    return [
        PointSet(vertices, vertex_properties=vertex_properties, cell_properties=cell_props(n), name="points"),
        LineSet(vertices, segments, vertex_properties=vertex_properties, cell_properties=cell_props(n - 1)),
        Surface(
            vertices,
            triangles,
            vertex_properties=vertex_properties,
            cell_properties=cell_props(n - 2),
            name="surface é",
        ),
        TetraMesh(vertices, tetras, vertex_properties=vertex_properties, cell_properties=cell_props(n - 3)),
    ]


def same_dtypes(a: Mesh, b: Mesh) -> bool:
    return {k: v.dtype for k, v in a.vertex_properties.items()} == {
        k: v.dtype for k, v in b.vertex_properties.items()
    } and {k: v.dtype for k, v in a.cell_properties.items()} == {k: v.dtype for k, v in b.cell_properties.items()}


@pytest.mark.parametrize("encoding", ["binary", "appended"])
@pytest.mark.parametrize("index", range(4))
def test_round_trip_bit_exact_with_properties_and_dtypes(index: int, encoding: str, tmp_path: Path) -> None:
    mesh = meshes()[index]
    path = tmp_path / "m.vtu"
    write_vtu(mesh, path, encoding=encoding)  # type: ignore[arg-type]
    back = read_vtu(path)
    assert type(back) is type(mesh)
    assert back.same_as(mesh)
    assert same_dtypes(back, mesh)
    assert back.name == mesh.name


def decode_binary(element: ET.Element) -> npt.NDArray[Any]:
    """Decode an inline binary DataArray by the VTK rules, independently of tgsis: UInt64 count, then data."""
    raw = base64.b64decode("".join((element.text or "").split()))
    size = int(np.frombuffer(raw[:8], dtype="<u8")[0])
    assert size == len(raw) - 8, "the UInt64 header must give the number of data bytes"
    dtype = {
        "Float64": "<f8",
        "Float32": "<f4",
        "Int64": "<i8",
        "Int32": "<i4",
        "UInt8": "<u1",
        "UInt16": "<u2",
        "UInt64": "<u8",
        "Int8": "<i1",
    }[element.get("type", "")]
    return np.frombuffer(raw[8:], dtype=dtype)


@pytest.mark.parametrize(("index", "cell_type"), [(0, 1), (1, 3), (2, 5), (3, 10)])
def test_xml_is_well_formed_standard_vtk(index: int, cell_type: int) -> None:
    mesh = meshes()[index]
    root = ET.fromstring(format_vtu(mesh, compression=None))  # the compressed layout: test_formats_vtk_libraries.py
    assert root.tag == "VTKFile"
    assert root.attrib == {
        "type": "UnstructuredGrid",
        "version": "1.0",
        "byte_order": "LittleEndian",
        "header_type": "UInt64",
    }
    [piece] = root.findall("UnstructuredGrid/Piece")
    assert piece.get("NumberOfPoints") == str(mesh.n_vertices)
    assert piece.get("NumberOfCells") == str(mesh.n_cells)
    arrays = {e.get("Name"): e for e in piece.iter("DataArray")}
    assert all(e.get("format") == "binary" for e in arrays.values())
    assert decode_binary(arrays["types"]).tolist() == [cell_type] * mesh.n_cells
    assert decode_binary(arrays["offsets"]).tolist() == list(
        range(mesh.cell_size, mesh.cell_size * (mesh.n_cells + 1), mesh.cell_size)
    )
    assert decode_binary(arrays["connectivity"]).tolist() == mesh.cells.reshape(-1).tolist()
    points = piece.find("Points/DataArray")
    assert points is not None and points.get("type") == "Float64" and points.get("NumberOfComponents") == "3"
    assert np.array_equal(decode_binary(points).reshape(-1, 3), mesh.vertices, equal_nan=True)
    assert [e.get("Name") for e in piece.findall("PointData/DataArray")] == list(mesh.vertex_properties)
    assert [e.get("Name") for e in piece.findall("CellData/DataArray")] == list(mesh.cell_properties)
    assert arrays["f32"].get("type") == "Float32" and arrays["code"].get("type") == "Int32"


def test_appended_layout() -> None:
    data = format_vtu(meshes()[2], encoding="appended", compression=None)
    head, _, tail = data.partition(b'<AppendedData encoding="raw">')
    root = ET.fromstring(head + b"</VTKFile>")
    offsets = [int(e.get("offset", "-1")) for e in root.iter("DataArray")]
    assert offsets == sorted(offsets) and offsets[0] == 0
    assert all(e.get("format") == "appended" for e in root.iter("DataArray"))
    payload = tail[tail.index(b"_") + 1 :]
    # the first block is the FieldData name, UTF-8 bytes ending in 0 (UInt8: meshio refuses String arrays);
    # the next one the first PointData array: UInt64 byte count, then 30 float64
    name = "surface é".encode() + b"\0"
    assert int(np.frombuffer(payload[:8], dtype="<u8")[0]) == len(name) and payload[8 : 8 + len(name)] == name
    second = int(next(e.get("offset", "-1") for e in root.iter("DataArray") if e.get("Name") == "f64"))
    assert int(np.frombuffer(payload[second : second + 8], dtype="<u8")[0]) == 30 * 8
    assert tail.endswith(b"</AppendedData>\n</VTKFile>\n")


def test_bool_and_float16_become_vtk_types(tmp_path: Path) -> None:
    surface = Surface(
        np.eye(3),
        [[0, 1, 2]],
        vertex_properties={"ok": [True, False, True], "h": np.array([1, 2, 3], dtype=np.float16)},
    )
    write_vtu(surface, tmp_path / "s.vtu")
    back = read_vtu(tmp_path / "s.vtu")
    assert back.vertex_properties["ok"].dtype == np.uint8 and back.vertex_properties["ok"].tolist() == [1, 0, 1]
    assert back.vertex_properties["h"].dtype == np.float32 and back.vertex_properties["h"].tolist() == [1, 2, 3]


def test_empty_meshes_keep_their_type(tmp_path: Path) -> None:
    for mesh in (Surface(np.eye(3), np.empty((0, 3)), name="no triangles"), TetraMesh(np.empty((0, 3)), [])):
        write_vtu(mesh, tmp_path / "e.vtu")
        back = read_vtu(tmp_path / "e.vtu")
        assert type(back) is type(mesh) and back.same_as(mesh) and back.name == mesh.name


@pytest.mark.parametrize(
    "relative",
    [
        "formats/CRFA-SJMZ-CHMN-Big_Spring_fault-50dip-CFM5.ts",
        "formats/ETRA-LSBM-MULT-Burnt_Mountain-East_Wide_Canyon_fault-CFM2.ts",
        "formats/WTRA-NCFS-PPT-Pitas_Point_fault.ts",
    ],
)
def test_cfm_surface_through_vtu(relative: str, tmp_path: Path) -> None:
    surface = read_tsurf(cfm(relative))
    formats.write(surface, tmp_path / "f.vtu")
    back = formats.read_one(tmp_path / "f.vtu")
    assert back.same_as(surface) and back.name == surface.name


def test_hand_written_ascii_file() -> None:
    mesh = read_vtu(DATA / "vtk" / "tetra_ascii.vtu")
    assert isinstance(mesh, TetraMesh)
    assert mesh.name == "block"
    assert mesh.vertices.tolist() == [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [0.1, 0.2, 3e5]]
    assert mesh.cells.tolist() == [[0, 1, 2, 3], [1, 2, 3, 4]]
    props = mesh.vertex_properties
    assert list(props) == ["Temperature_K", "velocity"]  # letter case kept
    assert props["Temperature_K"].dtype == np.float32
    assert props["Temperature_K"].tolist() == [10.5, 11.5, 12.5, 13.5, 14.5]
    assert props["velocity"].shape == (5, 3)  # three components: a vector property, as tgsis writes one
    assert props["velocity"][:, 1].tolist() == [2, 5, 8, 11, 14]
    assert mesh.cell_properties["rock"].tolist() == [7, -3] and mesh.cell_properties["rock"].dtype == np.int32
    assert mesh.metadata["vtk_array_names"] == {"point_data": {"Temperature_K": "Temperature K"}}


# ---- files as other VTK writers make them (zlib compression, UInt32 headers, big-endian, base64 appended)


def zlib_blocks(raw: bytes, header: str, block_size: int) -> tuple[bytes, bytes]:
    """vtkZLibDataCompressor layout: header [blocks, block size, last size, compressed sizes...], then blocks."""
    chunks = [raw[i : i + block_size] for i in range(0, len(raw), block_size)] or [b""]
    compressed = [zlib.compress(c) for c in chunks]
    last = len(chunks[-1]) if len(chunks[-1]) != block_size else 0
    head = np.array([len(chunks), block_size, last, *map(len, compressed)], dtype=header).tobytes()
    return head, b"".join(compressed)


def foreign_vtu(mesh: Mesh, *, order: str, header: str, mode: str) -> bytes:
    """A .vtu in one of the encodings write_vtu does not produce, built here by the VTK rules."""
    byte_order = "LittleEndian" if order == "<" else "BigEndian"
    header_dtype = order + header
    header_type = {"u4": "UInt32", "u8": "UInt64"}[header]
    attrs = f'byte_order="{byte_order}" header_type="{header_type}"'
    if mode.startswith("zlib"):
        attrs += ' compressor="vtkZLibDataCompressor"'
    appended: list[bytes] = []
    offset = 0

    def array(name: str, values: npt.NDArray[Any], vtk_type: str, components: int = 1) -> str:
        nonlocal offset
        raw = np.ascontiguousarray(values, dtype=values.dtype.newbyteorder("<" if order == "<" else ">")).tobytes()
        if mode.startswith("zlib"):
            head, body = zlib_blocks(raw, header_dtype, block_size=64)
            encoded = base64.b64encode(head) + base64.b64encode(body)
        elif mode == "separate":  # the byte count as a base64 stream of its own, as some writers do
            encoded = base64.b64encode(np.array([len(raw)], dtype=header_dtype).tobytes()) + base64.b64encode(raw)
        else:
            encoded = base64.b64encode(np.array([len(raw)], dtype=header_dtype).tobytes() + raw)
        tag = f'<DataArray type="{vtk_type}" Name="{name}" NumberOfComponents="{components}"'
        if mode.endswith("appended"):
            appended.append(encoded)
            tag += f' format="appended" offset="{offset}"/>'
            offset += len(encoded)
            return tag
        return tag + f' format="binary">\n{encoded.decode()}\n</DataArray>'

    k = mesh.cell_size
    parts = [
        f'<?xml version="1.0"?>\n<VTKFile type="UnstructuredGrid" version="1.0" {attrs}>\n<UnstructuredGrid>\n',
        f'<Piece NumberOfPoints="{mesh.n_vertices}" NumberOfCells="{mesh.n_cells}">\n<PointData>\n',
        *(array(name, v, "Float64") for name, v in mesh.vertex_properties.items()),
        "</PointData>\n<Points>\n",
        array("Points", mesh.vertices, "Float64", 3),
        "</Points>\n<Cells>\n",
        array("connectivity", mesh.cells.astype(np.int32), "Int32"),
        array("offsets", (np.arange(1, mesh.n_cells + 1) * k).astype(np.int32), "Int32"),
        array("types", np.full(mesh.n_cells, 5, dtype=np.uint8), "UInt8"),
        "</Cells>\n</Piece>\n</UnstructuredGrid>\n",
    ]
    if appended:
        parts.append('<AppendedData encoding="base64">\n_' + b"".join(appended).decode() + "\n</AppendedData>\n")
    parts.append("</VTKFile>\n")
    return "".join(parts).encode()


@pytest.mark.parametrize(
    ("order", "header", "mode"),
    [
        ("<", "u4", "zlib"),
        ("<", "u8", "zlib"),
        (">", "u4", "plain"),
        (">", "u8", "zlib"),
        ("<", "u4", "plain-appended"),
        ("<", "u8", "zlib-appended"),
        ("<", "u8", "separate"),
        (">", "u4", "separate"),
    ],
)
def test_reads_other_encodings(order: str, header: str, mode: str) -> None:
    surface = read_tsurf(cfm("formats/CRFA-SJMZ-CHMN-Big_Spring_fault-50dip-CFM5.ts"))
    back = parse_vtu(foreign_vtu(surface, order=order, header=header, mode=mode))
    assert back.same_as(surface)


def test_reads_compressed_raw_appended_data() -> None:
    """ParaView's default: zlib blocks in a raw AppendedData section."""
    surface = Surface(
        [[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]],
        [[0, 1, 2], [1, 3, 2]],
        vertex_properties={"h": [1.5, 2.5, 3.5, 4.5]},
    )
    blobs: list[bytes] = []

    def block(values: npt.NDArray[Any]) -> int:
        head, body = zlib_blocks(values.tobytes(), "<u8", block_size=16)
        offset = sum(map(len, blobs))
        blobs.append(head + body)
        return offset

    offsets = [
        block(surface.vertex_properties["h"]),
        block(surface.vertices),
        block(surface.cells.reshape(-1)),
        block(np.array([3, 6])),
        block(np.array([5, 5], dtype=np.uint8)),
    ]
    xml = (
        f'<?xml version="1.0"?><VTKFile type="UnstructuredGrid" version="1.0" byte_order="LittleEndian" '
        f'header_type="UInt64" compressor="vtkZLibDataCompressor"><UnstructuredGrid>'
        f'<Piece NumberOfPoints="4" NumberOfCells="2"><PointData>'
        f'<DataArray type="Float64" Name="h" format="appended" offset="{offsets[0]}"/></PointData><Points>'
        f'<DataArray type="Float64" NumberOfComponents="3" format="appended" offset="{offsets[1]}"/></Points>'
        f'<Cells><DataArray type="Int64" Name="connectivity" format="appended" offset="{offsets[2]}"/>'
        f'<DataArray type="Int64" Name="offsets" format="appended" offset="{offsets[3]}"/>'
        f'<DataArray type="UInt8" Name="types" format="appended" offset="{offsets[4]}"/></Cells>'
        f'</Piece></UnstructuredGrid><AppendedData encoding="raw">\n _'
    ).encode()
    back = parse_vtu(xml + b"".join(blobs) + b"\n</AppendedData></VTKFile>")
    assert back.same_as(surface)


# ---- errors


def ascii_grid(types: str, connectivity: str, offsets: str, n_cells: int, extra: str = "") -> bytes:
    return (
        f'<VTKFile type="UnstructuredGrid" version="0.1" {extra}><UnstructuredGrid>'
        f'<Piece NumberOfPoints="4" NumberOfCells="{n_cells}"><Points>'
        f'<DataArray type="Float64" NumberOfComponents="3" format="ascii">0 0 0 1 0 0 0 1 0 1 1 0</DataArray>'
        f'</Points><Cells><DataArray type="Int64" Name="connectivity" format="ascii">{connectivity}</DataArray>'
        f'<DataArray type="Int64" Name="offsets" format="ascii">{offsets}</DataArray>'
        f'<DataArray type="UInt8" Name="types" format="ascii">{types}</DataArray></Cells>'
        f"</Piece></UnstructuredGrid></VTKFile>"
    ).encode()


@pytest.mark.parametrize(
    ("data", "message"),
    [
        (ascii_grid("5 3", "0 1 2 2 3", "3 5", 2), r"mixes cell types 3 \(LINE\), 5 \(TRIANGLE\)"),
        (ascii_grid("9", "0 1 3 2", "4", 1), r"VTK cell type 9 \(QUAD\) is not supported"),
        (ascii_grid("5", "0 1", "3", 1), "DataArray 'connectivity' has 2 values, expected 3 x 1"),
        (ascii_grid("5", "0 1 x", "3", 1), "DataArray 'connectivity' has values that are not int64"),
        (ascii_grid("5 5", "0 1 2 1 3 2", "3 5", 2), "cell offsets do not match 2 TRIANGLE cells"),
        (ascii_grid("5", "0 1 2", "3", 1, 'compressor="vtkLZ4DataCompressor"'), "unsupported compressor"),
        (ascii_grid("5", "0 1 9", "3", 1), "refers to vertex 9, but the mesh has 4 vertices"),
        (b'<VTKFile type="PolyData"></VTKFile>', "not a VTK UnstructuredGrid file"),
        (b'<VTKFile type="UnstructuredGrid"><UnstructuredGrid/></VTKFile>', "expected one Piece"),
    ],
)
def test_errors(data: bytes, message: str, tmp_path: Path) -> None:
    path = tmp_path / "bad.vtu"
    path.write_bytes(data)
    with pytest.raises(FileFormatError, match=message):
        read_vtu(path)


def test_offsets_with_a_leading_zero_are_accepted() -> None:
    mesh = parse_vtu(ascii_grid("5 5", "0 1 2 1 3 2", "0 3 6", 2))
    assert isinstance(mesh, Surface) and mesh.cells.tolist() == [[0, 1, 2], [1, 3, 2]]


def test_not_xml_gives_the_line(tmp_path: Path) -> None:
    path = tmp_path / "bad.vtu"
    path.write_text('<?xml version="1.0"?>\n<VTKFile type="UnstructuredGrid">\n<Piece>\n</VTKFile>\n')
    with pytest.raises(FileFormatError, match="not well-formed XML") as info:
        read_vtu(path)
    assert info.value.line == 4


def test_truncated_binary(tmp_path: Path) -> None:
    data = format_vtu(meshes()[2], compression=None)
    cut = data.replace(b'format="binary">', b'format="binary">QUFB', 1)  # corrupt the first array
    with pytest.raises(FileFormatError, match="DataArray 'f64'"):
        parse_vtu(cut)
    with pytest.raises(FileFormatError, match="cannot read the file"):
        read_vtu(tmp_path / "missing.vtu")
