"""VTK XML files, read and written with the standard library and numpy: ``.vtu`` and ``.vtp``.

Writing (:func:`write_vtu`)
---------------------------
One ``Piece`` with

* ``Points``: Float64, 3 components;
* ``Cells``: ``connectivity`` and ``offsets`` as Int64, ``types`` as UInt8
  (VERTEX = 1 for a PointSet, LINE = 3 for a LineSet, TRIANGLE = 5 for a
  Surface, TETRA = 10 for a TetraMesh);
* ``PointData`` from the vertex properties and ``CellData`` from the cell
  properties, each in its own dtype (Int8 ... UInt64, Float32, Float64).
  VTK has no boolean or 16-bit float type: bool is written as UInt8 and
  float16 as Float32, and they come back as such;
* ``FieldData``: the mesh name (``tgsis_name``, when there is one) and the
  geotype (``tgsis_geotype``), so that a mesh without cells comes back as the
  right type. They are UInt8 DataArrays of UTF-8 bytes, each string ending
  in 0, not VTK's String arrays (``<Array type="String">``), which tgsis
  wrote before: meshio's VTU reader decodes every FieldData array as numbers
  (``vtu_to_numpy_type[type]``) and refuses the whole file on a String one
  ("Illegal data type 'String'"), whoever wrote it. tgsis still reads String
  arrays (``name`` too).

Every DataArray is zlib-compressed by default (``compressor=
"vtkZLibDataCompressor"``: a header of block count, block size (32768), size
of the last block and the compressed size of each block, then the blocks;
inline, header and blocks are two base64 streams), as ParaView writes;
``compression=None`` writes a UInt64 byte count followed by the raw values.
A grid without points or without cells is not compressed (meshio cannot
read a compressed array of 0 blocks). ``encoding="binary"`` (the default)
puts the DataArrays inline as base64 (``header_type="UInt64"``);
``encoding="appended"`` writes the same bytes unencoded in one
``AppendedData`` section (``encoding="raw"``), smaller and faster for big
meshes. Both are standard VTK XML (file version 1.0) that ParaView, VTK,
pyvista and meshio read. The round trip is bit-exact for vertices, cells and
properties (dtypes and vector properties included, except bool and float16);
the mesh's other metadata is not stored.

VTK has no z convention: a mesh whose ``metadata["zpositive"]`` says
``Depth`` is written with z negated (elevation, as ParaView draws it), and
the FieldData string ``tgsis_zpositive`` (a collection's members:
``tgsis_member_zpositive``) records the convention, which the readers give
back (depth coordinates and ``metadata["zpositive"]``).

A :class:`~tgsis.mesh.GeometryCollection` is written as one grid of mixed
cell types: the members' points one member after the other, their cells
likewise (connectivity shifted to the member's first point), and in
``FieldData`` the geotype ``GEOMETRYCOLLECTION``, ``tgsis_member_geotypes``
and ``tgsis_member_names`` (strings as above, one per member; no name is
written as the empty string) and ``tgsis_member_sizes`` (Int64, 2 components:
points and cells of each member). ParaView shows the whole grid. A vertex or
cell property must be on every member (a VTU array covers all points or all
cells), but ``part``: members without parts get ``part`` -1 (``NO_PART``)
and are read back without it; members with different dtypes of one property
come back with the common dtype (numpy promotion).

Array names read from a VTK file that are no mesh property names (``rock
type``) are sanitised on reading and kept in ``metadata["vtk_array_names"]``
(below); writing gives the arrays those names back (XML attributes hold
blanks), unless two arrays would get one name.

Reading (:func:`read_vtu`)
--------------------------
Reads what the writer writes and also: ``format="ascii"`` arrays, appended
data in ``raw`` or ``base64`` encoding, ``header_type`` UInt32 or UInt64, big-
or little-endian files, and ``vtkZLibDataCompressor`` compression (ParaView's
default). The file must have one Piece whose cells are all of one type among
VERTEX, LINE, TRIANGLE and TETRA. A data array with k > 1 components becomes
an (n, k) vector property, as tgsis writes one; names that are not valid mesh
property names are sanitised and the file's names are kept in
``metadata["vtk_array_names"]`` (``{"point_data": {mesh name: file name},
"cell_data": {...}}``, only for names that changed).
:func:`read_vtu_collection` reads the collections the writer writes back into
their members (and a file of one mesh as a collection of that mesh);
:func:`read_vtu_geometry` gives a mesh or a collection as written, and None
for the typeless empty grid of :func:`format_empty_vtu` (how
:mod:`tgsis.formats.pvd` writes a time at which an object does not exist).

PolyData (``.vtp``)
-------------------
ParaView's and pyvista's file for surfaces, lines and points.
:func:`write_vtp` writes a PointSet, LineSet or Surface as one ``Piece``:
``Points`` (Float64), its cells in ``Verts``, ``Lines`` or ``Polys``
(``connectivity`` and ``offsets``, Int64), the properties in
``PointData``/``CellData`` and the FieldData as for ``.vtu``, compressed the
same way. PolyData has no 3D cells: a TetraMesh or a collection goes to
``.vtu``. :func:`read_vtp` reads whatever VTK writes (the encodings above).
The cells must be of one kind: vertices (poly-vertices become one vertex
each), lines (a polyline becomes its segments, each with the polyline's cell
data), or polygons: triangles, and planar convex polygons and quads split
into triangles (others, and triangle strips, raise
:class:`~tgsis.errors.FileFormatError` with the hint to triangulate).
``name`` (a VTK String array) or ``tgsis_name`` in FieldData gives the name;
array names are sanitised as for ``.vtu``.
"""

from __future__ import annotations

import base64
import math
import xml.etree.ElementTree as ET
import zlib
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Literal, overload

import numpy as np
import numpy.typing as npt

from tgsis._vtk_cells import (
    VTK_CELL_NAMES,
    file_array_names,
    mesh_from_vtk_cells,
    named_as_read,
    shared_properties,
    without_no_part,
)
from tgsis._zpositive import MEMBER_ZPOSITIVE_FIELD, ZPOSITIVE_FIELD
from tgsis.errors import FileFormatError, InvalidGeometryError, InvalidPropertyError
from tgsis.formats._common import (
    PathLike,
    check_mesh,
    in_elevation,
    quoted,
    read_bytes,
    restore_convention,
    sanitize_property_name,
    split_vtk_polygons,
    write_bytes,
)
from tgsis.mesh import Geometry, GeometryCollection, LineSet, Mesh, PointSet, Surface, TetraMesh, mesh_class

if TYPE_CHECKING:  # (tgsis.gmaps imports tgsis.temporal, which imports this module)
    from tgsis.gmaps import GMap

__all__ = [
    "VTK_CELL_TYPES",
    "read_vtu",
    "parse_vtu",
    "read_vtu_collection",
    "parse_vtu_collection",
    "read_vtu_geometry",
    "parse_vtu_geometry",
    "write_vtu",
    "format_vtu",
    "format_empty_vtu",
    "read_vtp",
    "parse_vtp",
    "write_vtp",
    "format_vtp",
    "write_gmap_vtu",
    "format_gmap_vtu",
]

#: VTK cell type of each mesh class.
VTK_CELL_TYPES: dict[type[Mesh], int] = {PointSet: 1, LineSet: 3, Surface: 5, TetraMesh: 10}
_MESH_OF_CELL_TYPE = {code: cls for cls, code in VTK_CELL_TYPES.items()}
# the names of VTK's cell types, for messages: one table for every VTK reader (tgsis._vtk_cells)
_CELL_TYPE_NAMES = VTK_CELL_NAMES

_VTK_TYPE_OF: dict[str, str] = {
    "i1": "Int8",
    "u1": "UInt8",
    "i2": "Int16",
    "u2": "UInt16",
    "i4": "Int32",
    "u4": "UInt32",
    "i8": "Int64",
    "u8": "UInt64",
    "f4": "Float32",
    "f8": "Float64",
}
_DTYPE_OF: dict[str, str] = {v: k for k, v in _VTK_TYPE_OF.items()}
_DTYPE_OF["String"] = "u1"  # FieldData strings: null-terminated bytes

Encoding = Literal["binary", "appended"]
Compression = Literal["zlib"] | None


# ---------------------------------------------------------------- writing


def write_vtu(
    mesh: Geometry, path: PathLike, *, encoding: Encoding = "binary", compression: Compression = "zlib"
) -> None:
    """Write a mesh or a collection as a VTK XML UnstructuredGrid file.

    Parameters
    ----------
    mesh : Mesh or GeometryCollection
        A PointSet, LineSet, Surface or TetraMesh, or a collection of them
        (one grid of mixed cell types, see the module documentation).
    path : str or path-like
        The ``.vtu`` file to write (replaced if it exists).
    encoding : {"binary", "appended"}
        Inline base64 DataArrays, or one raw AppendedData section.
    compression : {"zlib", None}
        ``"zlib"``: every DataArray compressed by the rules of VTK's
        ``vtkZLibDataCompressor`` (what ParaView writes); None: uncompressed.

    Raises
    ------
    FileFormatError
        The file cannot be written, or a collection has a property that not
        every member has.
    """
    write_bytes(path, [format_vtu(mesh, encoding=encoding, compression=compression)])


@dataclass(frozen=True)
class _Grid:
    """What one Piece holds: points (n, 3), cells as connectivity (c,), offsets (m,), types (m,), data."""

    name: str | None
    geotype: str | None  # None: no tgsis_geotype field (the empty grid of format_empty_vtu)
    vertices: npt.NDArray[np.float64]
    connectivity: npt.NDArray[np.int64]
    offsets: npt.NDArray[np.int64]
    types: npt.NDArray[np.uint8]
    point_data: dict[str, npt.NDArray[Any]]
    cell_data: dict[str, npt.NDArray[Any]]
    members: GeometryCollection | None = None
    #: the z convention of the mesh (one), or of each member, that the file records (z is written up positive)
    zpositive: tuple[str | None, ...] = ()
    #: polyhedra (VTK_POLYHEDRON): per cell [number of faces, (points of the face, its point ids)...], and the end of each
    faces: npt.NDArray[np.int64] | None = None
    faceoffsets: npt.NDArray[np.int64] | None = None


def _mesh_grid(mesh: Mesh) -> _Grid:
    k = mesh.cell_size
    up, zpositive = in_elevation(mesh)
    point_data, cell_data = _as_read(mesh, mesh.vertex_properties, mesh.cell_properties)
    return _Grid(
        mesh.name,
        mesh.geotype.value,
        up.vertices,
        mesh.cells.reshape(-1),
        np.arange(1, mesh.n_cells + 1, dtype=np.int64) * k,
        np.full(mesh.n_cells, VTK_CELL_TYPES[mesh_class(mesh.geotype)], dtype=np.uint8),
        point_data,
        cell_data,
        zpositive=tuple(zpositive),
    )


def _xml_name(name: str) -> bool:
    """Whether a DataArray may be named ``name``: any printable text (blanks too; XML escapes quotes)."""
    return name.isprintable()


def _as_read(
    geometry: Geometry, point_data: dict[str, npt.NDArray[Any]], cell_data: dict[str, npt.NDArray[Any]]
) -> tuple[dict[str, npt.NDArray[Any]], dict[str, npt.NDArray[Any]]]:
    """Point and cell data under the names of the VTK file they were read from (``metadata["vtk_array_names"]``)."""
    return (
        named_as_read(point_data, file_array_names(geometry, "point_data"), _xml_name),
        named_as_read(cell_data, file_array_names(geometry, "cell_data"), _xml_name),
    )


def _collection_grid(collection: GeometryCollection) -> _Grid:
    """One grid of mixed cell types: the members' points and cells one member after the other (z up)."""
    up, zpositive = in_elevation(collection)
    assert isinstance(up, GeometryCollection)
    members = up.members
    first_point = np.cumsum([0] + [m.n_vertices for m in members[:-1]])
    connectivity = np.concatenate([m.cells.reshape(-1) + start for m, start in zip(members, first_point)])
    sizes = np.concatenate([np.full(m.n_cells, m.cell_size, dtype=np.int64) for m in members])
    types = np.concatenate([np.full(m.n_cells, VTK_CELL_TYPES[mesh_class(m.geotype)], dtype=np.uint8) for m in members])
    point_data, cell_data = _as_read(
        collection, _shared_properties(members, "vertex"), _shared_properties(members, "cell")
    )
    return _Grid(
        collection.name,
        collection.geotype.value,
        np.concatenate([m.vertices for m in members]),
        connectivity.astype(np.int64),
        np.cumsum(sizes).astype(np.int64),
        types,
        point_data,
        cell_data,
        collection,
        zpositive=tuple(zpositive),
    )


def _shared_properties(members: tuple[Mesh, ...], kind: Literal["vertex", "cell"]) -> dict[str, npt.NDArray[Any]]:
    """The members' ``kind`` properties concatenated; each must be on every member, but ``part``, which is
    :data:`~tgsis._vtk_cells.NO_PART` on the cells of members without parts."""

    def of(mesh: Mesh) -> dict[str, npt.NDArray[Any]]:
        return mesh.vertex_properties if kind == "vertex" else mesh.cell_properties

    for name in dict.fromkeys(name for m in members for name in of(m)):
        lacking = [i for i, m in enumerate(members) if name not in of(m)]
        if lacking and not (kind == "cell" and name == "part"):
            raise FileFormatError(
                f"{kind} property {name!r} is on some members of the collection but not on members {lacking}: "
                f"a VTU grid holds one value per {'point' if kind == 'vertex' else 'cell'} of all members",
                hint="give every member the property, or remove it before writing",
            )
    return shared_properties(members, kind)


def format_vtu(mesh: Geometry, *, encoding: Encoding = "binary", compression: Compression = "zlib") -> bytes:
    """The ``.vtu`` file content for ``mesh`` or a collection; see :func:`write_vtu`."""
    _check_encoding(encoding, compression)
    return _format_grid(
        _collection_grid(mesh)
        if isinstance(mesh, GeometryCollection)
        else _mesh_grid(check_mesh(mesh, "the VTU writer")),
        encoding,
        compression,
    )


def format_empty_vtu(*, encoding: Encoding = "binary", compression: Compression = "zlib") -> bytes:
    """The ``.vtu`` file content of a grid of 0 points and 0 cells that names no geotype.

    It stands for "no object": :func:`read_vtu_geometry` reads it as None
    (:func:`read_vtu` as an empty PointSet). ParaView shows nothing for it.

    Parameters
    ----------
    encoding : {"binary", "appended"}
        As for :func:`write_vtu`.
    compression : {"zlib", None}
        As for :func:`write_vtu`.

    Returns
    -------
    bytes
        A valid VTK XML UnstructuredGrid file (empty Points and Cells arrays).
    """
    _check_encoding(encoding, compression)
    empty = np.empty(0, dtype=np.int64)
    return _format_grid(
        _Grid(None, None, np.empty((0, 3)), empty, empty, np.empty(0, dtype=np.uint8), {}, {}), encoding, compression
    )


def _check_encoding(encoding: str, compression: str | None = None) -> None:
    if encoding not in ("binary", "appended"):
        raise FileFormatError(f"unknown VTU encoding {encoding!r}: use 'binary' or 'appended'")
    if compression not in ("zlib", None):
        raise FileFormatError(f"unknown compression {compression!r}: use 'zlib' or None")


def _format_grid(source: _Grid, encoding: Encoding, compression: Compression) -> bytes:
    """The file content of one grid."""
    # meshio cannot read a compressed empty array (no block): a grid without points or cells is not compressed
    compressed = compression == "zlib" and len(source.vertices) > 0 and len(source.types) > 0
    writer = _ArrayWriter(appended=encoding == "appended", compressed=compressed)
    root = writer.root("UnstructuredGrid")
    grid = ET.SubElement(root, "UnstructuredGrid")
    field_data = ET.SubElement(grid, "FieldData")
    if source.name:
        field_data.append(writer.strings("tgsis_name", source.name))
    if source.geotype is not None:
        field_data.append(writer.strings("tgsis_geotype", source.geotype))
    if source.members is not None:
        members = source.members.members
        field_data.append(writer.strings("tgsis_member_geotypes", *(m.geotype.value for m in members)))
        field_data.append(writer.strings("tgsis_member_names", *(m.name or "" for m in members)))
        sizes = writer.array(
            "tgsis_member_sizes", np.array([[m.n_vertices, m.n_cells] for m in members], dtype=np.int64), components=2
        )
        sizes.set("NumberOfTuples", str(len(members)))
        field_data.append(sizes)
        if any(source.zpositive):
            field_data.append(writer.strings(MEMBER_ZPOSITIVE_FIELD, *(z or "" for z in source.zpositive)))
    elif source.zpositive and source.zpositive[0]:
        field_data.append(writer.strings(ZPOSITIVE_FIELD, source.zpositive[0]))
    n_points, n_cells = len(source.vertices), len(source.types)
    piece = ET.SubElement(grid, "Piece", NumberOfPoints=str(n_points), NumberOfCells=str(n_cells))
    point_data = ET.SubElement(piece, "PointData")
    for name, values in source.point_data.items():  # an (n, k) vector property: k components
        point_data.append(writer.array(name, values, components=values.shape[1] if values.ndim == 2 else 1))
    cell_data = ET.SubElement(piece, "CellData")
    for name, values in source.cell_data.items():
        cell_data.append(writer.array(name, values, components=values.shape[1] if values.ndim == 2 else 1))
    points = ET.SubElement(piece, "Points")
    points.append(writer.array("Points", source.vertices, components=3))
    cells = ET.SubElement(piece, "Cells")
    cells.append(writer.array("connectivity", source.connectivity))
    cells.append(writer.array("offsets", source.offsets))
    cells.append(writer.array("types", source.types))
    if source.faces is not None and source.faceoffsets is not None:
        cells.append(writer.array("faces", source.faces))
        cells.append(writer.array("faceoffsets", source.faceoffsets))
    return writer.finish(root)


#: Bytes per zlib block, as VTK's writers cut them (vtkXMLWriter's default BlockSize).
ZLIB_BLOCK_SIZE = 32768
#: zlib level: vtkZLibDataCompressor's default; on the San Andreas fault of data/cfm it compresses as well as 6
#: or 9 in less time than 6 (bench/vtk_files.py, docs/performance.md)
ZLIB_LEVEL = 5


class _ArrayWriter:
    """Makes DataArray elements; in appended mode collects their bytes and offsets; compresses them."""

    def __init__(self, *, appended: bool, compressed: bool = False) -> None:
        self.appended = appended
        self.compressed = compressed
        self.blocks: list[bytes] = []
        self.offset = 0

    def root(self, data_type: str) -> ET.Element:
        """The VTKFile element of a file of ``data_type`` (UnstructuredGrid, PolyData)."""
        root = ET.Element("VTKFile", type=data_type, version="1.0", byte_order="LittleEndian", header_type="UInt64")
        if self.compressed:
            root.set("compressor", "vtkZLibDataCompressor")
        return root

    def finish(self, root: ET.Element) -> bytes:
        """The file content: the XML, and in appended mode the AppendedData section after it."""
        ET.indent(root)
        text = b'<?xml version="1.0"?>\n' + bytes(ET.tostring(root, encoding="utf-8", xml_declaration=False))
        if not self.appended:
            return text + b"\n"
        # raw bytes are not XML: the AppendedData section goes after the serialised tree, by hand
        head, _, _ = text.rpartition(b"</VTKFile>")
        return b"".join(
            [head, b'  <AppendedData encoding="raw">\n   _', *self.blocks, b"\n  </AppendedData>\n</VTKFile>\n"]
        )

    def array(self, name: str, values: npt.NDArray[Any], *, components: int = 1) -> ET.Element:
        data = _vtk_values(values)
        element = ET.Element("DataArray", type=_VTK_TYPE_OF[data.dtype.str[1:]], Name=name)
        if components != 1:
            element.set("NumberOfComponents", str(components))
        raw = data.tobytes()
        if self.compressed:
            # vtkZLibDataCompressor: header (block count, block size, size of the last block, compressed
            # size of each block), then the blocks; inline, header and blocks are two base64 streams
            chunks = [
                zlib.compress(raw[i : i + ZLIB_BLOCK_SIZE], ZLIB_LEVEL) for i in range(0, len(raw), ZLIB_BLOCK_SIZE)
            ]
            header = np.array(
                [len(chunks), ZLIB_BLOCK_SIZE, len(raw) % ZLIB_BLOCK_SIZE, *(len(c) for c in chunks)], dtype="<u8"
            ).tobytes()
            parts = [header, b"".join(chunks)]
        else:
            parts = [np.uint64(len(raw)).astype("<u8").tobytes() + raw]
        if self.appended:
            element.set("format", "appended")
            element.set("offset", str(self.offset))
            payload = b"".join(parts)
            self.blocks.append(payload)
            self.offset += len(payload)
        else:
            element.set("format", "binary")
            element.text = "".join(base64.b64encode(part).decode("ascii") for part in parts)
        return element

    def strings(self, name: str, *values: str) -> ET.Element:
        """A FieldData array of strings, as UInt8 bytes, each string UTF-8 and terminated by 0.

        Not VTK's ``<Array type="String">``: meshio reads every FieldData array
        as numbers and refuses the whole file for a String one.
        """
        data = np.frombuffer(b"".join(v.encode("utf-8") + b"\0" for v in values), dtype=np.uint8)
        element = self.array(name, data)
        element.set("NumberOfTuples", str(len(data)))  # FieldData has no Piece to count its tuples (VTK reads 0)
        return element


def _vtk_values(values: npt.NDArray[Any]) -> npt.NDArray[Any]:
    """Values as a little-endian array of a type VTK has (bool -> UInt8, float16 -> Float32)."""
    if values.dtype.kind == "b":
        values = values.astype(np.uint8)
    elif values.dtype.kind == "f" and values.dtype.itemsize < 4:
        values = values.astype(np.float32)
    return np.ascontiguousarray(values, dtype=values.dtype.newbyteorder("<"))


# ---------------------------------------------------------------- reading


def read_vtu(path: PathLike) -> Mesh:
    """Read a VTK XML UnstructuredGrid file of one mesh.

    Parameters
    ----------
    path : str or path-like
        A ``.vtu`` file.

    Returns
    -------
    Mesh
        PointSet, LineSet, Surface or TetraMesh after the cell type.

    Raises
    ------
    FileFormatError
        The file cannot be read, is not a valid ``.vtu``, holds cells that
        are not all VERTEX, all LINE, all TRIANGLE or all TETRA, or holds a
        collection (:func:`read_vtu_collection` reads those).
    """
    return parse_vtu(read_bytes(path), path=path)


def parse_vtu(data: bytes, *, path: PathLike | None = None) -> Mesh:
    """Parse the content of a ``.vtu`` file; see :func:`read_vtu`. ``path`` is for messages only."""
    result = _parse(data, path)
    if isinstance(result, GeometryCollection):
        raise FileFormatError(
            f"the file holds a GEOMETRYCOLLECTION of {len(result)} members, not one mesh",
            path=path,
            hint="tgsis.formats.read or read_vtu_collection reads the members",
        )
    return result


def read_vtu_geometry(path: PathLike) -> Geometry | None:
    """Read a ``.vtu`` file as written: a mesh, a collection, or None for "no object".

    Parameters
    ----------
    path : str or path-like
        A ``.vtu`` file.

    Returns
    -------
    Mesh or GeometryCollection or None
        A collection for a file written from one (even of one member), a
        mesh otherwise; None for a grid of 0 points and 0 cells whose
        ``FieldData`` names no ``tgsis_geotype`` (:func:`format_empty_vtu`
        writes one; so do other writers for an empty dataset). An empty
        mesh written by :func:`write_vtu` keeps its type.

    Raises
    ------
    FileFormatError
        As :func:`read_vtu` (except for collections).
    """
    return parse_vtu_geometry(read_bytes(path), path=path)


def parse_vtu_geometry(data: bytes, *, path: PathLike | None = None) -> Geometry | None:
    """Parse the content of a ``.vtu`` file; see :func:`read_vtu_geometry`."""
    return _parse(data, path, absent_as_none=True)


def read_vtu_collection(path: PathLike) -> GeometryCollection:
    """Read a ``.vtu`` file written from a GeometryCollection (a file of one mesh gives a collection of it).

    Parameters
    ----------
    path : str or path-like
        A ``.vtu`` file.

    Returns
    -------
    GeometryCollection
        The members in file order, with their names and properties.

    Raises
    ------
    FileFormatError
        As :func:`read_vtu`; also when the member table in ``FieldData`` does
        not match the grid.
    """
    return parse_vtu_collection(read_bytes(path), path=path)


def parse_vtu_collection(data: bytes, *, path: PathLike | None = None) -> GeometryCollection:
    """Parse the content of a ``.vtu`` file; see :func:`read_vtu_collection`."""
    result = _parse(data, path)
    return result if isinstance(result, GeometryCollection) else GeometryCollection([result], name=result.name)


@overload
def _parse(data: bytes, path: PathLike | None, *, absent_as_none: Literal[False] = False) -> Geometry: ...


@overload
def _parse(data: bytes, path: PathLike | None, *, absent_as_none: bool) -> Geometry | None: ...


def _parse(data: bytes, path: PathLike | None, *, absent_as_none: bool = False) -> Geometry | None:
    """A mesh, or a collection when the FieldData says GEOMETRYCOLLECTION.

    With ``absent_as_none``, None for an empty grid that names no geotype.
    """
    xml_bytes, appended = _split_appended(data)
    try:
        root = ET.fromstring(xml_bytes)
    except ET.ParseError as exc:
        raise FileFormatError(f"not well-formed XML: {exc}", path=path, line=exc.position[0]) from None
    if root.tag != "VTKFile" or root.get("type") != "UnstructuredGrid":
        raise FileFormatError(
            f"not a VTK UnstructuredGrid file (root <{root.tag} type={root.get('type')!r}>)", path=path
        )
    decoder = _Decoder.for_root(root, appended, path)
    grid = root.find("UnstructuredGrid")
    pieces = grid.findall("Piece") if grid is not None else []
    if len(pieces) != 1:
        raise FileFormatError(f"expected one Piece in the UnstructuredGrid, found {len(pieces)}", path=path)
    piece = pieces[0]
    n_points = _int_attribute(piece, "NumberOfPoints", path)
    n_cells = _int_attribute(piece, "NumberOfCells", path)

    if n_points == 0 and piece.find("Points/DataArray") is None:
        vertices = np.empty((0, 3))  # VTK writes <Points></Points> for a grid without points
    else:
        vertices = decoder.array(_find_array(piece, "Points", None, path), n_points, 3).astype(np.float64)
    fields = _field_strings(grid, decoder) if grid is not None else {}
    if absent_as_none and n_points == 0 and n_cells == 0 and "tgsis_geotype" not in fields:
        return None
    if grid is not None and fields.get("tgsis_geotype") == GeometryCollection.geotype.value:
        return _collection(grid, piece, decoder, vertices.reshape(n_points, 3), n_cells, fields.get("name"))
    mesh_type, cells = _cells(piece, decoder, n_cells, path)
    if n_cells == 0 and "tgsis_geotype" in fields:
        try:
            mesh_type = mesh_class(fields["tgsis_geotype"])
        except InvalidGeometryError:
            pass
    names: dict[str, dict[str, str]] = {}
    vertex_properties = _data_arrays(piece.find("PointData"), decoder, n_points, names, "point_data")
    cell_properties = _data_arrays(piece.find("CellData"), decoder, n_cells, names, "cell_data")
    metadata: dict[str, Any] = {"vtk_array_names": names} if names else {}
    try:
        mesh = mesh_type(
            vertices.reshape(n_points, 3),
            cells.reshape(n_cells, mesh_type.cell_size),
            vertex_properties=vertex_properties,
            cell_properties=cell_properties,
            name=fields.get("name"),
            metadata=metadata,
        )
    except (InvalidGeometryError, InvalidPropertyError) as exc:
        raise FileFormatError(f"the grid is not a valid {mesh_type.__name__}: {exc.message}", path=path) from exc
    restore_convention(mesh, fields.get(ZPOSITIVE_FIELD), path, f"FieldData {ZPOSITIVE_FIELD}")
    return mesh


def _collection(
    grid: ET.Element,
    piece: ET.Element,
    decoder: _Decoder,
    vertices: npt.NDArray[np.float64],
    n_cells: int,
    name: str | None,
) -> GeometryCollection:
    """The members of a grid written from a GeometryCollection, after its FieldData member table."""
    path = decoder.path
    strings = _field_string_lists(grid, decoder)
    geotypes = strings.get("tgsis_member_geotypes")
    sizes_element = _field_element(grid, "tgsis_member_sizes")
    if not geotypes or sizes_element is None:
        raise FileFormatError(
            "a GEOMETRYCOLLECTION grid needs the FieldData arrays tgsis_member_geotypes and tgsis_member_sizes",
            path=path,
        )
    names = strings.get("tgsis_member_names", [])
    sizes = decoder.array(sizes_element, len(geotypes), 2).astype(np.int64).reshape(-1, 2)
    if sizes.min() < 0 or sizes[:, 0].sum() != len(vertices) or sizes[:, 1].sum() != n_cells:
        raise FileFormatError(
            f"tgsis_member_sizes lists {int(sizes[:, 0].sum())} points and "
            f"{int(sizes[:, 1].sum())} cells, the grid has {len(vertices)} and {n_cells}",
            path=path,
        )
    types, ends, connectivity = _mixed_cells(piece, decoder, n_cells)
    arrays: dict[str, dict[str, str]] = {}
    point_data = _data_arrays(piece.find("PointData"), decoder, len(vertices), arrays, "point_data")
    cell_data = _data_arrays(piece.find("CellData"), decoder, n_cells, arrays, "cell_data")
    members: list[Mesh] = []
    first_point = first_cell = 0
    for i, (geotype, (n_p, n_c)) in enumerate(zip(geotypes, sizes.tolist())):
        try:
            mesh_type = mesh_class(geotype)
        except InvalidGeometryError:
            raise FileFormatError(f"member {i} has geotype {geotype!r}, not one of a mesh", path=path) from None
        code, k = VTK_CELL_TYPES[mesh_type], mesh_type.cell_size
        cells = slice(first_cell, first_cell + n_c)
        if np.any(types[cells] != code):
            raise FileFormatError(
                f"member {i} is a {geotype} but has cells that are not {_CELL_TYPE_NAMES[code]} ({code})", path=path
            )
        start = int(ends[first_cell - 1]) if first_cell else 0
        points = slice(first_point, first_point + n_p)
        try:
            members.append(
                mesh_type(
                    vertices[points],
                    (connectivity[start : start + n_c * k] - first_point).reshape(n_c, k),
                    vertex_properties={key: values[points] for key, values in point_data.items()},
                    cell_properties=without_no_part({key: values[cells] for key, values in cell_data.items()}),
                    name=(names[i] if i < len(names) else "") or None,
                )
            )
        except (InvalidGeometryError, InvalidPropertyError) as exc:
            raise FileFormatError(f"member {i} is not a valid {mesh_type.__name__}: {exc.message}", path=path) from exc
        first_point, first_cell = first_point + n_p, first_cell + n_c
    collection = GeometryCollection(members, name=name, metadata={"vtk_array_names": arrays} if arrays else None)
    recorded = strings.get(MEMBER_ZPOSITIVE_FIELD)
    if recorded is not None:
        if len(recorded) != len(members):
            raise FileFormatError(
                f"FieldData {MEMBER_ZPOSITIVE_FIELD} has {len(recorded)} values for {len(members)} members", path=path
            )
        restore_convention(collection, recorded, path, f"FieldData {MEMBER_ZPOSITIVE_FIELD}")
    return collection


def _mixed_cells(
    piece: ET.Element, decoder: _Decoder, n_cells: int
) -> tuple[npt.NDArray[Any], npt.NDArray[np.int64], npt.NDArray[np.int64]]:
    """Cell types (m,), offsets (m,) = end of each cell in the connectivity, connectivity, of any known types."""
    path = decoder.path
    if piece.find("Cells") is None:
        if n_cells:
            raise FileFormatError(f"the Piece declares {n_cells} cells but has no <Cells>", path=path)
        empty = np.empty(0, dtype=np.int64)
        return empty, empty, empty
    types = decoder.array(_find_array(piece, "Cells", "types", path), n_cells, 1)
    offsets = decoder.array(_find_array(piece, "Cells", "offsets", path), None, 1).astype(np.int64)
    if len(offsets) == n_cells + 1 and offsets[0] == 0:
        offsets = offsets[1:]  # the in-memory vtkCellArray layout, with the leading 0
    unknown = sorted({int(t) for t in np.unique(types)} - set(_MESH_OF_CELL_TYPE))
    if unknown:
        listed = ", ".join(f"{t} ({_CELL_TYPE_NAMES.get(t, 'unknown')})" for t in unknown)
        raise FileFormatError(
            f"VTK cell types {listed} are not supported: tgsis reads VERTEX (1), LINE (3), TRIANGLE (5) and TETRA (10)",
            path=path,
        )
    size_of = np.zeros(256, dtype=np.int64)
    for code, cls in _MESH_OF_CELL_TYPE.items():
        size_of[code] = cls.cell_size
    if len(offsets) != n_cells or not np.array_equal(offsets, np.cumsum(size_of[types.astype(np.int64)])):
        raise FileFormatError(f"cell offsets do not match the sizes of the {n_cells} cells' types", path=path)
    connectivity_element = _find_array(piece, "Cells", "connectivity", path)
    connectivity = decoder.array(connectivity_element, int(offsets[-1]) if n_cells else 0, 1)
    if connectivity.dtype.kind not in "iu":
        raise FileFormatError(f"cell connectivity must be integers, got {connectivity_element.get('type')}", path=path)
    return types, offsets, connectivity.astype(np.int64)


def _split_appended(data: bytes) -> tuple[bytes, bytes]:
    """The XML without the AppendedData payload, and the payload (after its ``_`` marker)."""
    start = data.find(b"<AppendedData")
    if start < 0:
        return data, b""
    tag_end = data.find(b">", start)
    close = data.rfind(b"</AppendedData>")
    marker = data.find(b"_", tag_end)
    if tag_end < 0 or close < 0 or marker < 0 or marker > close:
        return data, b""  # let the XML parser report what is wrong
    return data[: tag_end + 1] + data[close:], data[marker + 1 : close]


def _int_attribute(element: ET.Element, name: str, path: PathLike | None) -> int:
    text = element.get(name)
    try:
        value = int(text) if text is not None else -1
    except ValueError:
        value = -1
    if value < 0:
        raise FileFormatError(f"<{element.tag}> needs a non-negative integer {name}, got {quoted(text)}", path=path)
    return value


def _find_array(piece: ET.Element, section: str, name: str | None, path: PathLike | None) -> ET.Element:
    """The DataArray of ``section`` (the named one, or the first)."""
    parent = piece.find(section)
    arrays = parent.findall("DataArray") if parent is not None else []
    for array in arrays:
        if name is None or array.get("Name") == name:
            return array
    what = f"a DataArray {name!r}" if name else "a DataArray"
    raise FileFormatError(f"<{section}> has no {what}", path=path)


def _cells(
    piece: ET.Element, decoder: _Decoder, n_cells: int, path: PathLike | None
) -> tuple[type[Mesh], npt.NDArray[np.int64]]:
    """The mesh class after the (single) cell type, and the connectivity."""
    if piece.find("Cells/DataArray") is None:
        if n_cells:
            raise FileFormatError(f"the Piece declares {n_cells} cells but has no <Cells> arrays", path=path)
        return PointSet, np.empty(0, dtype=np.int64)
    types = decoder.array(_find_array(piece, "Cells", "types", path), n_cells, 1)
    offsets = decoder.array(_find_array(piece, "Cells", "offsets", path), None, 1).astype(np.int64)
    if len(offsets) == n_cells + 1 and offsets[0] == 0:
        offsets = offsets[1:]  # the in-memory vtkCellArray layout, with the leading 0
    connectivity_element = _find_array(piece, "Cells", "connectivity", path)
    distinct = sorted({int(t) for t in np.unique(types)})
    if len(distinct) > 1:
        listed = ", ".join(f"{t} ({_CELL_TYPE_NAMES.get(t, 'unknown')})" for t in distinct)
        raise FileFormatError(f"the grid mixes cell types {listed}; a tgsis mesh has one cell type", path=path)
    if distinct and distinct[0] not in _MESH_OF_CELL_TYPE:
        t = distinct[0]
        raise FileFormatError(
            f"VTK cell type {t} ({_CELL_TYPE_NAMES.get(t, 'unknown')}) is not supported: "
            "tgsis reads VERTEX (1), LINE (3), TRIANGLE (5) and TETRA (10)",
            path=path,
        )
    mesh_type = _MESH_OF_CELL_TYPE[distinct[0]] if distinct else PointSet
    k = mesh_type.cell_size
    if not np.array_equal(offsets, np.arange(1, n_cells + 1, dtype=np.int64) * k):
        raise FileFormatError(
            f"cell offsets do not match {n_cells} {_CELL_TYPE_NAMES[VTK_CELL_TYPES[mesh_type]]} "
            f"cells of {k} points each",
            path=path,
        )
    connectivity = decoder.array(connectivity_element, n_cells * k, 1)
    if connectivity.dtype.kind not in "iu":
        raise FileFormatError(f"cell connectivity must be integers, got {connectivity_element.get('type')}", path=path)
    return mesh_type, connectivity.astype(np.int64)


def _data_arrays(
    section: ET.Element | None, decoder: _Decoder, count: int, names: dict[str, dict[str, str]], key: str
) -> dict[str, npt.NDArray[Any]]:
    """PointData/CellData arrays as properties; k-component arrays are split into name_0 .. name_{k-1}."""
    result: dict[str, npt.NDArray[Any]] = {}
    renamed: dict[str, str] = {}
    for element in section.findall("DataArray") if section is not None else []:
        if element.get("type") == "String":
            continue  # not numeric: no property can hold it
        file_name = element.get("Name") or "array"
        components = (
            _int_attribute(element, "NumberOfComponents", decoder.path) if "NumberOfComponents" in element.attrib else 1
        )
        if components < 1:
            raise FileFormatError(f"DataArray {file_name!r} has NumberOfComponents 0", path=decoder.path)
        values = decoder.array(element, count, components).reshape(count, components)
        name = sanitize_property_name(file_name.strip() or file_name, result)  # as GOCAD names: " default property"
        if name != file_name:
            renamed[name] = file_name
        # k components: a vector property (n, k), as tgsis writes one
        result[name] = np.ascontiguousarray(values[:, 0] if components == 1 else values)
    if renamed:
        names[key] = renamed
    return result


def _field_elements(grid: ET.Element) -> list[ET.Element]:
    """The arrays of FieldData (it belongs to the grid; some writers put it in the Piece)."""
    return [
        e
        for section in (grid.find("FieldData"), grid.find("Piece/FieldData"))
        if section is not None
        for e in section
        if e.tag in ("Array", "DataArray")
    ]


def _field_element(grid: ET.Element, name: str) -> ET.Element | None:
    """The FieldData array called ``name``, if any."""
    return next((e for e in _field_elements(grid) if e.get("Name") == name), None)


def _is_string_field(element: ET.Element) -> bool:
    """A String array (VTK's, older tgsis files) or a tgsis_ UInt8 array of 0-terminated strings."""
    name = element.get("Name") or ""
    return bool(name) and (
        element.get("type") == "String" or (name.startswith("tgsis_") and element.get("type") in ("UInt8", "Int8"))
    )


def _field_string_lists(grid: ET.Element, decoder: _Decoder) -> dict[str, list[str]]:
    """Every string of each string array in FieldData (``tgsis_name`` as ``name``)."""
    result: dict[str, list[str]] = {}
    for element in _field_elements(grid):
        if not _is_string_field(element):
            continue
        try:
            raw = decoder.array(element, None, 1).astype(np.uint8).tobytes()
        except FileFormatError:
            continue
        parts = raw.split(b"\0")
        if raw.endswith(b"\0"):
            parts.pop()
        result[str(element.get("Name"))] = [p.decode("utf-8", errors="replace") for p in parts]
    if "tgsis_name" in result:
        result["name"] = result["tgsis_name"]
    return result


def _field_strings(grid: ET.Element, decoder: _Decoder) -> dict[str, str]:
    """The first string of each string array in FieldData (``tgsis_name`` as ``name``)."""
    result: dict[str, str] = {}
    for element in _field_elements(grid):
        if not _is_string_field(element):
            continue
        try:
            raw = decoder.array(element, None, 1).astype(np.uint8).tobytes()
        except FileFormatError:
            continue  # a field we cannot decode is not worth failing the file for
        result[str(element.get("Name"))] = raw.split(b"\0", 1)[0].decode("utf-8", errors="replace")
    if "tgsis_name" in result:
        result["name"] = result["tgsis_name"]
    return result


@dataclass(frozen=True)
class _Decoder:
    """Decodes DataArrays after the file's byte order, header type, compressor and appended data."""

    byte_order: str  # "<" or ">"
    header: np.dtype[Any]
    compressed: bool
    appended: bytes
    appended_base64: bool
    path: PathLike | None

    @classmethod
    def for_root(cls, root: ET.Element, appended: bytes, path: PathLike | None) -> _Decoder:
        order = {"LittleEndian": "<", "BigEndian": ">"}.get(root.get("byte_order", "LittleEndian"))
        header = {"UInt32": "u4", "UInt64": "u8"}.get(root.get("header_type", "UInt32"))
        compressor = root.get("compressor", "")
        if order is None or header is None:
            raise FileFormatError(
                f"unsupported byte_order {root.get('byte_order')!r} or header_type {root.get('header_type')!r}",
                path=path,
            )
        if compressor not in ("", "vtkZLibDataCompressor"):
            raise FileFormatError(
                f"unsupported compressor {compressor!r}: tgsis reads uncompressed and vtkZLibDataCompressor data",
                path=path,
            )
        section = root.find("AppendedData")
        is_base64 = section is not None and section.get("encoding", "raw") == "base64"
        return cls(order, np.dtype(order + header), bool(compressor), appended, is_base64, path)

    def array(self, element: ET.Element, count: int | None, components: int) -> npt.NDArray[Any]:
        """The values of a DataArray, flat; ``count`` tuples of ``components`` expected (None: any)."""
        type_name = element.get("type", "")
        name = element.get("Name", "?")
        if type_name not in _DTYPE_OF:
            raise FileFormatError(f"DataArray {quoted(name)} has unsupported type {quoted(type_name)}", path=self.path)
        dtype = np.dtype(self.byte_order + _DTYPE_OF[type_name])
        fmt = element.get("format", "ascii")
        if fmt == "ascii":
            values = self._ascii(element, dtype)
        elif fmt == "binary":
            # base64 may be wrapped over lines; translate() drops the whitespace far faster than a regex
            text = (element.text or "").encode("ascii", errors="replace").translate(None, b" \t\n\r\f\v")
            values = np.frombuffer(self._from_base64(text, 0, name), dtype=dtype)
        elif fmt == "appended":
            offset = _int_attribute(element, "offset", self.path)
            raw = (
                self._from_base64(self.appended, offset, name)
                if self.appended_base64
                else self._from_raw(self.appended, offset, name)
            )
            values = np.frombuffer(raw[: len(raw) - len(raw) % dtype.itemsize], dtype=dtype)
        else:
            raise FileFormatError(f"DataArray {quoted(name)} has unknown format {quoted(fmt)}", path=self.path)
        values = values.astype(dtype.newbyteorder("="))
        if count is not None and len(values) != count * components:
            raise FileFormatError(
                f"DataArray {quoted(name)} has {len(values)} values, expected {count} x {components}", path=self.path
            )
        return values

    def _ascii(self, element: ET.Element, dtype: np.dtype[Any]) -> npt.NDArray[Any]:
        words = (element.text or "").split()
        try:
            if dtype.kind == "f":
                return np.array([float(w) for w in words], dtype=dtype)
            return np.array([int(w) for w in words], dtype=dtype)
        except (ValueError, OverflowError):
            raise FileFormatError(
                f"DataArray {quoted(element.get('Name', '?'))} has values that are not {dtype.name}", path=self.path
            ) from None

    def _from_raw(self, data: bytes, offset: int, name: str) -> bytes:
        """Bytes of one appended raw block at ``offset``."""
        h = self.header.itemsize
        if self.compressed:
            head = self._header_values(data[offset : offset + 3 * h], 3, name)
            n_blocks = int(head[0])
            sizes = self._header_values(data[offset + 3 * h : offset + (3 + n_blocks) * h], n_blocks, name)
            return self._inflate(data[offset + (3 + n_blocks) * h :], head, sizes, name)
        (size,) = self._header_values(data[offset : offset + h], 1, name)
        return self._exact(data[offset + h : offset + h + int(size)], int(size), name)

    def _from_base64(self, text: bytes, offset: int, name: str) -> bytes:
        """Bytes of one base64 block starting at character ``offset``.

        Uncompressed, VTK encodes the byte count and the data as one base64
        stream; compressed, the header and the data are two streams.
        """
        h = self.header.itemsize
        if self.compressed:
            head = self._header_values(self._b64(text, offset, 3 * h, name)[: 3 * h], 3, name)
            n_blocks = int(head[0])
            header_chars = 4 * math.ceil((3 + n_blocks) * h / 3)
            full = self._b64(text, offset, (3 + n_blocks) * h, name)
            sizes = self._header_values(full[3 * h : (3 + n_blocks) * h], n_blocks, name)
            body = self._b64(text, offset + header_chars, int(sizes.sum()), name)
            return self._inflate(body, head, sizes, name)
        (size,) = self._header_values(self._b64(text, offset, h, name)[:h], 1, name)
        header_chars = 4 * math.ceil(h / 3)
        if text[offset + header_chars - 1 : offset + header_chars] == b"=":
            # some writers encode the byte count as a base64 stream of its own (it ends in padding)
            return self._exact(self._b64(text, offset + header_chars, int(size), name), int(size), name)
        return self._exact(self._b64(text, offset, h + int(size), name)[h:], int(size), name)

    def _b64(self, text: bytes, offset: int, n_bytes: int, name: str) -> bytes:
        """Decode the base64 characters at ``offset`` that hold (at least) ``n_bytes`` bytes."""
        chunk = text[offset : offset + 4 * math.ceil(n_bytes / 3)]
        try:
            return base64.b64decode(chunk, validate=True)
        except ValueError:
            raise FileFormatError(f"DataArray {quoted(name)} is not valid base64", path=self.path) from None

    def _header_values(self, raw: bytes, count: int, name: str) -> npt.NDArray[np.uint64]:
        if len(raw) != count * self.header.itemsize:
            raise FileFormatError(f"DataArray {quoted(name)} is truncated (incomplete block header)", path=self.path)
        return np.frombuffer(raw, dtype=self.header).astype(np.uint64)

    def _exact(self, raw: bytes, size: int, name: str) -> bytes:
        if len(raw) != size:
            raise FileFormatError(f"DataArray {quoted(name)} is truncated: {len(raw)} of {size} bytes", path=self.path)
        return raw

    def _inflate(self, body: bytes, head: npt.NDArray[np.uint64], sizes: npt.NDArray[np.uint64], name: str) -> bytes:
        """Decompress vtkZLibDataCompressor blocks (header: count, block size, last block size, sizes)."""
        parts: list[bytes] = []
        position = 0
        for size in sizes.tolist():
            try:
                parts.append(zlib.decompress(body[position : position + size]))
            except zlib.error:
                raise FileFormatError(f"DataArray {quoted(name)} has a corrupt zlib block", path=self.path) from None
            position += size
        raw = b"".join(parts)
        n_blocks, block_size, last_size = (int(v) for v in head)
        expected = (n_blocks - 1) * block_size + (last_size or block_size) if n_blocks else 0
        return self._exact(raw, expected, name)


# ---------------------------------------------------------------- PolyData (.vtp)


_SECTION_OF: dict[type[Mesh], str] = {PointSet: "Verts", LineSet: "Lines", Surface: "Polys"}
# VTK cell types by section and cell size, for the checks shared with tgsis.convert
_VERTEX, _POLY_VERTEX, _LINE, _POLY_LINE, _TRIANGLE, _STRIP, _POLYGON = 1, 2, 3, 4, 5, 6, 7


def write_vtp(mesh: Mesh, path: PathLike, *, encoding: Encoding = "binary", compression: Compression = "zlib") -> None:
    """Write a PointSet, LineSet or Surface as a VTK XML PolyData file.

    Parameters
    ----------
    mesh : PointSet, LineSet or Surface
    path : str or path-like
        The ``.vtp`` file (replaced if it exists).
    encoding : {"binary", "appended"}
        Inline base64 DataArrays, or one raw AppendedData section.
    compression : {"zlib", None}
        zlib blocks as ``vtkZLibDataCompressor`` writes them, or none.

    Raises
    ------
    FileFormatError
        A TetraMesh (PolyData holds no 3D cells), or an unwritable file.
    """
    write_bytes(path, [format_vtp(mesh, encoding=encoding, compression=compression)])


def format_vtp(mesh: Mesh, *, encoding: Encoding = "binary", compression: Compression = "zlib") -> bytes:
    """The ``.vtp`` file content of ``mesh``; see :func:`write_vtp`."""
    _check_encoding(encoding, compression)
    mesh = check_mesh(mesh, "the VTP writer")
    section = _SECTION_OF.get(type(mesh))
    if section is None:
        raise FileFormatError(
            f"VTK PolyData holds points, lines and surfaces, not a {type(mesh).__name__}",
            hint="write tetrahedra to a .vtu file",
        )
    compressed = compression == "zlib" and mesh.n_vertices > 0 and mesh.n_cells > 0  # meshio: no empty zlib array
    up, (zpositive,) = in_elevation(mesh)
    writer = _ArrayWriter(appended=encoding == "appended", compressed=compressed)
    root = writer.root("PolyData")
    poly = ET.SubElement(root, "PolyData")
    field_data = ET.SubElement(poly, "FieldData")
    if mesh.name:
        field_data.append(writer.strings("tgsis_name", mesh.name))
    field_data.append(writer.strings("tgsis_geotype", mesh.geotype.value))
    if zpositive is not None:
        field_data.append(writer.strings(ZPOSITIVE_FIELD, zpositive))
    counts = {name: "0" for name in ("NumberOfVerts", "NumberOfLines", "NumberOfStrips", "NumberOfPolys")}
    counts[f"NumberOf{section}"] = str(mesh.n_cells)
    piece = ET.SubElement(poly, "Piece", {"NumberOfPoints": str(mesh.n_vertices), **counts})
    point_arrays, cell_arrays = _as_read(mesh, mesh.vertex_properties, mesh.cell_properties)
    point_data = ET.SubElement(piece, "PointData")
    for name, values in point_arrays.items():
        point_data.append(writer.array(name, values, components=values.shape[1] if values.ndim == 2 else 1))
    cell_data = ET.SubElement(piece, "CellData")
    for name, values in cell_arrays.items():
        cell_data.append(writer.array(name, values, components=values.shape[1] if values.ndim == 2 else 1))
    points = ET.SubElement(piece, "Points")
    points.append(writer.array("Points", up.vertices, components=3))
    for name in ("Verts", "Lines", "Strips", "Polys"):
        cells = ET.SubElement(piece, name)
        if name == section:
            cells.append(writer.array("connectivity", mesh.cells.reshape(-1)))
            cells.append(writer.array("offsets", np.arange(1, mesh.n_cells + 1, dtype=np.int64) * mesh.cell_size))
    return writer.finish(root)


def read_vtp(path: PathLike) -> Mesh:
    """Read a VTK XML PolyData file of one kind of cell.

    Parameters
    ----------
    path : str or path-like
        A ``.vtp`` file.

    Returns
    -------
    PointSet, LineSet or Surface

    Raises
    ------
    FileFormatError
        Not a valid ``.vtp``, several Pieces, cells of several kinds,
        polygons that are not triangles, triangle strips, or data tgsis
        cannot hold (see the module documentation).
    """
    return parse_vtp(read_bytes(path), path=path)


def parse_vtp(data: bytes, *, path: PathLike | None = None) -> Mesh:
    """Parse the content of a ``.vtp`` file; see :func:`read_vtp`. ``path`` is for messages only."""
    xml_bytes, appended = _split_appended(data)
    try:
        root = ET.fromstring(xml_bytes)
    except ET.ParseError as exc:
        raise FileFormatError(f"not well-formed XML: {exc}", path=path, line=exc.position[0]) from None
    if root.tag != "VTKFile" or root.get("type") != "PolyData":
        raise FileFormatError(
            f"not a VTK PolyData file (root <{root.tag} type={root.get('type')!r}>)",
            path=path,
            hint="a .vtu file is read as VTK UnstructuredGrid" if root.get("type") == "UnstructuredGrid" else None,
        )
    decoder = _Decoder.for_root(root, appended, path)
    poly = root.find("PolyData")
    pieces = poly.findall("Piece") if poly is not None else []
    if len(pieces) != 1 or poly is None:
        raise FileFormatError(
            f"expected one Piece in the PolyData, found {len(pieces)}",
            path=path,
            hint="merge the pieces into one (pyvista: mesh.combine() or vtkAppendPolyData) before reading",
        )
    piece = pieces[0]
    n_points = _int_attribute(piece, "NumberOfPoints", path)
    if n_points == 0 and piece.find("Points/DataArray") is None:
        vertices = np.empty((0, 3))
    else:
        points = piece.find("Points/DataArray")
        if points is None:
            raise FileFormatError("<Points> has no DataArray", path=path)
        vertices = decoder.array(points, n_points, 3).astype(np.float64).reshape(n_points, 3)
    types: list[npt.NDArray[np.int64]] = []
    sizes: list[npt.NDArray[np.int64]] = []
    connectivity: list[npt.NDArray[np.int64]] = []
    # VTK numbers the cells of a PolyData verts, lines, polys, strips: its CellData is in that order
    for section, count_name in (
        ("Verts", "NumberOfVerts"),
        ("Lines", "NumberOfLines"),
        ("Polys", "NumberOfPolys"),
        ("Strips", "NumberOfStrips"),
    ):
        count = _int_attribute(piece, count_name, path) if count_name in piece.attrib else 0
        if count == 0:
            continue
        element = piece.find(section)
        arrays = {a.get("Name"): a for a in element.findall("DataArray")} if element is not None else {}
        if "connectivity" not in arrays or "offsets" not in arrays:
            raise FileFormatError(f"<{section}> of {count} cells needs DataArrays connectivity and offsets", path=path)
        ends = decoder.array(arrays["offsets"], None, 1).astype(np.int64)
        if len(ends) == count + 1 and ends[0] == 0:
            ends = ends[1:]
        if len(ends) != count or np.any(np.diff(ends) < 0) or ends[0] < 0:
            raise FileFormatError(f"<{section}> offsets do not describe {count} cells", path=path)
        ids = decoder.array(arrays["connectivity"], int(ends[-1]), 1)
        if ids.dtype.kind not in "iu":
            raise FileFormatError(f"<{section}> connectivity must be integers", path=path)
        size = np.diff(np.concatenate([[0], ends]))
        kind = {
            "Verts": np.where(size == 1, _VERTEX, _POLY_VERTEX),
            "Lines": np.where(size == 2, _LINE, _POLY_LINE),
            "Polys": np.where(size == 3, _TRIANGLE, _POLYGON),
            "Strips": np.full(count, _STRIP),
        }[section]
        types.append(kind.astype(np.int64))
        sizes.append(size)
        connectivity.append(ids.astype(np.int64))
    all_types = np.concatenate(types) if types else np.empty(0, np.int64)
    offsets = np.concatenate([[0], np.cumsum(np.concatenate(sizes))]) if sizes else np.zeros(1, np.int64)
    names: dict[str, dict[str, str]] = {}
    point_data = _data_arrays(piece.find("PointData"), decoder, n_points, names, "point_data")
    cell_data = _data_arrays(piece.find("CellData"), decoder, len(all_types), names, "cell_data")
    fields = _field_strings(poly, decoder)
    metadata: dict[str, Any] = {"vtk_array_names": names} if names else {}
    all_types, cell_offsets, cell_points, cell_data = split_vtk_polygons(
        vertices,
        all_types,
        offsets.astype(np.int64),
        np.concatenate(connectivity) if connectivity else np.empty(0, np.int64),
        cell_data,
        metadata,
        path,
        "PolyData cell",
    )
    try:
        mesh = mesh_from_vtk_cells(
            vertices,
            all_types,
            cell_offsets,
            cell_points,
            point_data,
            cell_data,
            name=fields.get("name"),
            geotype=fields.get("tgsis_geotype"),
            metadata=metadata,
            source="the PolyData",
        )
    except (InvalidGeometryError, InvalidPropertyError) as exc:
        raise FileFormatError(exc.message, path=path, detail=exc.detail, hint=exc.hint) from exc
    restore_convention(mesh, fields.get(ZPOSITIVE_FIELD), path, f"FieldData {ZPOSITIVE_FIELD}")
    return mesh


# --------------------------------------------------------------------------- G-maps (models 4 and 5) for ParaView

#: VTK cell types the top cells of an n-G-map are written as.
VTK_LINE, VTK_TRIANGLE, VTK_POLYGON, VTK_POLYHEDRON = 3, 5, 7, 42


def _polyhedron_streams(
    indices: np.ndarray, face_bounds: np.ndarray, cell_bounds: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """VTK's arrays for polyhedra, vectorised over all cells.

    Parameters
    ----------
    indices : (k,) int
        The point ids of every face's corners, face after face.
    face_bounds : (f + 1,) int
        Face i's corners are ``indices[face_bounds[i]:face_bounds[i + 1]]``.
    cell_bounds : (c + 1,) int
        Cell j's faces are ``cell_bounds[j]:cell_bounds[j + 1]``.

    Returns
    -------
    connectivity : (p,) int64
        Each cell's distinct points, ascending, cell after cell.
    offsets : (c,) int64
        End of each cell's points in ``connectivity``.
    faces : (c + f + k,) int64
        Each cell's face stream: its number of faces, then per face its
        number of corners and the corners.
    faceoffsets : (c,) int64
        End of each cell's stream in ``faces``.
    """
    indices = np.asarray(indices, dtype=np.int64)
    face_bounds = np.asarray(face_bounds, dtype=np.int64)
    cell_bounds = np.asarray(cell_bounds, dtype=np.int64)
    n_cells, n_faces = len(cell_bounds) - 1, len(face_bounds) - 1
    sizes = np.diff(face_bounds)
    faces_per_cell = np.diff(cell_bounds)
    cell_of_face = np.repeat(np.arange(n_cells, dtype=np.int64), faces_per_cell)
    cell_of_corner = np.repeat(cell_of_face, sizes)
    # distinct (cell, point) pairs, sorted by cell then point
    span = int(indices.max()) + 1 if len(indices) else 1
    pairs = np.unique(cell_of_corner * span + indices)
    connectivity = pairs % span
    offsets = np.cumsum(np.bincount(pairs // span, minlength=n_cells)).astype(np.int64)
    # the stream: before face i come the headers of cells 0..cell(i), the headers of faces 0..i-1 and their corners
    face_header = cell_of_face + 1 + np.arange(n_faces, dtype=np.int64) + face_bounds[:-1]
    cell_header = np.arange(n_cells, dtype=np.int64) + cell_bounds[:-1] + face_bounds[cell_bounds[:-1]]
    faces = np.empty(n_cells + n_faces + len(indices), dtype=np.int64)
    faces[cell_header] = faces_per_cell
    faces[face_header] = sizes
    faces[np.repeat(face_header + 1 - face_bounds[:-1], sizes) + np.arange(len(indices), dtype=np.int64)] = indices
    faceoffsets = cell_header + 1 + faces_per_cell + (face_bounds[cell_bounds[1:]] - face_bounds[cell_bounds[:-1]])
    return connectivity, offsets, faces, faceoffsets.astype(np.int64)


def _gmap_grid(g: GMap, name: str | None, axes: Sequence[str] | None) -> _Grid:
    """The Piece of a G-map: its points (the first three axes, 0 for missing ones; the others as point data), its
    top cells as lines (n = 1), polygons (n = 2: triangles as VTK triangles) or polyhedra (n = 3), its top cells'
    properties as cell data."""
    n, m = g.dimension, g.embedding_dimension
    if n not in (1, 2, 3):
        raise FileFormatError(
            f"a {n}-G-map has no VTK cells (ParaView shows lines, polygons and polyhedra)",
            hint="write a slice of it (tgsis.gmaps.slice) down to 3 dimensions",
        )
    names = list(axes) if axes is not None else [("x", "y", "z")[i] if i < 3 else f"axis{i + 1}" for i in range(m)]
    if len(names) != m:
        raise FileFormatError(f"axes name {len(names)} axes of a G-map in R^{m}")
    xyz = np.zeros((g.n_points, 3))
    xyz[:, : min(m, 3)] = g.points[:, :3]
    point_data = {names[i]: np.ascontiguousarray(g.points[:, i]) for i in range(3, m)}
    faces = faceoffsets = None
    if n == 1:
        first = g.cell_darts(1)
        connectivity = np.stack([g.vertex[first], g.vertex[g.alpha[0, first]]], axis=1).reshape(-1)
        offsets = np.arange(2, len(connectivity) + 1, 2, dtype=np.int64)
        types = np.full(len(first), VTK_LINE, dtype=np.uint8)
    elif n == 2:
        connectivity, bounds = g.polygons()
        offsets = bounds[1:].astype(np.int64)
        types = np.where(np.diff(bounds) == 3, VTK_TRIANGLE, VTK_POLYGON).astype(np.uint8)
    else:
        indices, face_bounds, cell_bounds = g.polyhedra()
        connectivity, offsets, faces, faceoffsets = _polyhedron_streams(indices, face_bounds, cell_bounds)
        types = np.full(len(offsets), VTK_POLYHEDRON, dtype=np.uint8)
    cell_data = {k: np.asarray(v) for k, v in g.cell_properties.get(n, {}).items()}
    return _Grid(
        name,
        "GMAP",
        xyz,
        connectivity.astype(np.int64),
        offsets,
        types,
        point_data,
        cell_data,
        faces=faces,
        faceoffsets=faceoffsets,
    )


def format_gmap_vtu(
    g: GMap,
    *,
    name: str | None = None,
    axes: Sequence[str] | None = None,
    encoding: Encoding = "binary",
    compression: Compression = "zlib",
) -> bytes:
    """The ``.vtu`` text of an n-G-map's top cells for ParaView (see :func:`write_gmap_vtu`)."""
    _check_encoding(encoding, compression)
    return _format_grid(_gmap_grid(g, name, axes), encoding, compression)


def write_gmap_vtu(
    g: GMap,
    path: PathLike,
    *,
    name: str | None = None,
    axes: Sequence[str] | None = None,
    encoding: Encoding = "binary",
    compression: Compression = "zlib",
) -> None:
    """Write an n-G-map (n = 1, 2, 3) as a VTK unstructured grid: lines, polygons or polyhedra, for ParaView.

    Parameters
    ----------
    g : tgsis.gmaps.GMap
        Its top cells (1-cells, 2-cells or 3-cells) become VTK cells in the
        order of ``g.cells(n)``; their properties (``g.cell_properties[n]``)
        become cell data. Points in R^m: the first three coordinates are the
        points (0 for missing ones), the others point data named after ``axes``.
    path : str or path-like
    name : str, optional
        Stored as the file's ``tgsis_name``.
    axes : sequence of str, optional
        The name of each of the m axes (default x, y, z, axis4, ...).

    Raises
    ------
    FileFormatError
        n = 0 or n > 3 (no VTK cell), or axes that do not name the m axes.
    """
    write_bytes(path, [format_gmap_vtu(g, name=name, axes=axes, encoding=encoding, compression=compression)])
