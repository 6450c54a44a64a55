"""VTK XML PolyData files (``.vtp``): ParaView's and pyvista's file for surfaces, lines and points.

Read and written with the standard library and numpy, like ``.vtu``
(:mod:`tgsis.formats.vtk`, whose encodings and decoder this module shares).

Writing (:func:`write_vtp`)
---------------------------
A PointSet, LineSet or Surface as one ``Piece``: ``Points`` (Float64),
its cells in ``Verts``, ``Lines`` or ``Polys`` (``connectivity`` and
``offsets``, Int64), properties in ``PointData``/``CellData`` in their own
dtypes (a vector property: k components), and in ``FieldData``
``tgsis_name`` and ``tgsis_geotype`` (UTF-8 bytes as UInt8, so that meshio
reads the file too). zlib-compressed (``vtkZLibDataCompressor``, what
ParaView writes) unless ``compression=None``; ``encoding`` as for ``.vtu``.
PolyData has no 3D cells: a TetraMesh or a collection goes to ``.vtu``.

Reading (:func:`read_vtp`)
--------------------------
Whatever VTK writes: any byte order, header type, base64/raw appended or
inline data, zlib compression. The cells must be of one kind: vertices
(poly-vertices become one vertex each), lines (a polyline becomes its
segments, each with the polyline's cell data), or polygons that are all
triangles (others, and triangle strips, raise :class:`~tgsis.errors.FileFormatError`
with the hint to triangulate). ``name`` (a VTK String array) or
``tgsis_name`` in FieldData gives the name. Array names are sanitised as
for ``.vtu`` (``metadata["vtk_array_names"]``).
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from typing import Any

import numpy as np
import numpy.typing as npt

from tgsis.errors import FileFormatError, InvalidGeometryError, InvalidPropertyError
from tgsis.formats._common import PathLike, check_mesh, read_bytes, write_bytes
from tgsis.formats.vtk import (Compression, Encoding, _ArrayWriter, _check_encoding, _data_arrays, _Decoder,
                               _field_strings, _int_attribute, _split_appended)
from tgsis.mesh import LineSet, Mesh, PointSet, Surface

__all__ = ["read_vtp", "parse_vtp", "write_vtp", "format_vtp"]

_SECTION_OF: dict[type[Mesh], str] = {PointSet: "Verts", LineSet: "Lines", Surface: "Polys"}
# VTK cell types by section and cell size, for the checks shared with tgsis.convert
_VERTEX, _POLY_VERTEX, _LINE, _POLY_LINE, _TRIANGLE, _STRIP, _POLYGON = 1, 2, 3, 4, 5, 6, 7


def write_vtp(mesh: Mesh, path: PathLike, *, encoding: Encoding = "binary",
              compression: Compression = "zlib") -> None:
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
        raise FileFormatError(f"VTK PolyData holds points, lines and surfaces, not a {type(mesh).__name__}",
                              hint="write tetrahedra to a .vtu file")
    compressed = compression == "zlib" and mesh.n_vertices > 0 and mesh.n_cells > 0  # meshio: no empty zlib array
    writer = _ArrayWriter(appended=encoding == "appended", compressed=compressed)
    root = writer.root("PolyData")
    poly = ET.SubElement(root, "PolyData")
    field_data = ET.SubElement(poly, "FieldData")
    if mesh.name:
        field_data.append(writer.strings("tgsis_name", mesh.name))
    field_data.append(writer.strings("tgsis_geotype", mesh.geotype.value))
    counts = {name: "0" for name in ("NumberOfVerts", "NumberOfLines", "NumberOfStrips", "NumberOfPolys")}
    counts[f"NumberOf{section}"] = str(mesh.n_cells)
    piece = ET.SubElement(poly, "Piece", {"NumberOfPoints": str(mesh.n_vertices), **counts})
    point_data = ET.SubElement(piece, "PointData")
    for name, values in mesh.vertex_properties.items():
        point_data.append(writer.array(name, values, components=values.shape[1] if values.ndim == 2 else 1))
    cell_data = ET.SubElement(piece, "CellData")
    for name, values in mesh.cell_properties.items():
        cell_data.append(writer.array(name, values, components=values.shape[1] if values.ndim == 2 else 1))
    points = ET.SubElement(piece, "Points")
    points.append(writer.array("Points", mesh.vertices, components=3))
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
    from tgsis.convert import mesh_from_vtk_cells

    xml_bytes, appended = _split_appended(data)
    try:
        root = ET.fromstring(xml_bytes)
    except ET.ParseError as exc:
        raise FileFormatError(f"not well-formed XML: {exc}", path=path, line=exc.position[0]) from None
    if root.tag != "VTKFile" or root.get("type") != "PolyData":
        raise FileFormatError(f"not a VTK PolyData file (root <{root.tag} type={root.get('type')!r}>)", path=path,
                              hint="a .vtu file is read as VTK UnstructuredGrid" if root.get("type") ==
                              "UnstructuredGrid" else None)
    decoder = _Decoder.for_root(root, appended, path)
    poly = root.find("PolyData")
    pieces = poly.findall("Piece") if poly is not None else []
    if len(pieces) != 1 or poly is None:
        raise FileFormatError(f"expected one Piece in the PolyData, found {len(pieces)}", path=path,
                              hint="merge the pieces into one (pyvista: mesh.combine() or "
                                   "vtkAppendPolyData) before reading")
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
    for section, count_name in (("Verts", "NumberOfVerts"), ("Lines", "NumberOfLines"), ("Polys", "NumberOfPolys"),
                                ("Strips", "NumberOfStrips")):
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
        kind = {"Verts": np.where(size == 1, _VERTEX, _POLY_VERTEX),
                "Lines": np.where(size == 2, _LINE, _POLY_LINE),
                "Polys": np.where(size == 3, _TRIANGLE, _POLYGON),
                "Strips": np.full(count, _STRIP)}[section]
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
    try:
        return mesh_from_vtk_cells(vertices, all_types, offsets.astype(np.int64),
                                   np.concatenate(connectivity) if connectivity else np.empty(0, np.int64),
                                   point_data, cell_data, name=fields.get("name"), geotype=fields.get("tgsis_geotype"),
                                   metadata=metadata, source="the PolyData")
    except (InvalidGeometryError, InvalidPropertyError) as exc:
        raise FileFormatError(exc.message, path=path, detail=exc.detail, hint=exc.hint) from exc
