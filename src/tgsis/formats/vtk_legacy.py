"""Legacy VTK files (``.vtk``): what pyvista's ``save("x.vtk")`` and older tools write, read and written here.

Writing (:func:`write_vtk`)
---------------------------
File version 5.1 (VTK 9's and meshio's default), ``BINARY`` (big-endian, as
the format wants) or ``ascii=True`` (every double as ``repr``, exact too),
``DATASET UNSTRUCTURED_GRID`` for every mesh type and for collections
(meshio reads no other legacy dataset; VTK and ParaView read it too):
``POINTS n double``, ``CELLS`` with ``OFFSETS`` and ``CONNECTIVITY``
(``vtktypeint64``), ``CELL_TYPES`` (VERTEX 1, LINE 3, TRIANGLE 5, TETRA 10),
the properties as ``FIELD`` arrays in ``POINT_DATA``/``CELL_DATA`` (a vector
property: k components), and in
the dataset's ``FIELD FieldData`` ``tgsis_name``, ``tgsis_geotype`` and for a
collection its member table (``tgsis_member_geotypes``,
``tgsis_member_names``: UTF-8 bytes ending in 0; ``tgsis_member_sizes``),
as in ``.vtu``. The title line is the mesh name (or ``tgsis``). Array
names are one word: the names of the file a mesh was read from
(``metadata["vtk_array_names"]``) are written back encoded as VTK's writer
encodes them (``rock%20type``: :func:`encode_name`), which the readers
decode; a collection's ``part`` is -1 on members without parts, as in
``.vtu``.

Values are exact; types are kept for float32, float64, int64 and uint64.
VTK's legacy reader and meshio's 5.1 reader agree on no smaller integer type
(meshio reads ``int`` as 8 bytes, VTK as 4), so bool and every integer type
up to 32 bits are written (and come back) as int64; ``.vtu`` keeps every
type.

Reading (:func:`read_vtk`)
--------------------------
Versions 2.0 to 5.1, ASCII or BINARY, ``DATASET POLYDATA`` (``VERTICES``,
``LINES``, ``POLYGONS``, ``TRIANGLE_STRIPS``: pyvista's default for a
surface) or ``UNSTRUCTURED_GRID``, cells in the old count-prefixed lists or
the 5.1 ``OFFSETS``/``CONNECTIVITY`` layout; ``SCALARS``, ``VECTORS``,
``NORMALS``, ``TEXTURE_COORDINATES``, ``TENSORS``, ``GLOBAL_IDS``,
``PEDIGREE_IDS`` and ``FIELD`` arrays become properties (k components: a
vector property), string arrays and lookup tables are skipped (a string
``name`` field gives the name), ``METADATA`` blocks are skipped. The cells
must be of one kind, as for ``.vtp`` (:mod:`tgsis.formats.vtk`): polylines
become segments, polygons that are not triangles and triangle strips are
refused with the hint to triangulate. A file tgsis wrote from a collection
gives its members (:func:`read_vtk_geometry`).
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from itertools import islice
from typing import Any
from urllib.parse import unquote_to_bytes

import numpy as np
import numpy.typing as npt

from tgsis._vtk_cells import (
    collection_from_cells,
    file_array_names,
    first,
    mesh_from_vtk_cells,
    named_as_read,
    string_bytes,
    strings,
    vtk_parts,
)
from tgsis._zpositive import MEMBER_ZPOSITIVE_FIELD, ZPOSITIVE_FIELD
from tgsis.errors import FileFormatError, InvalidGeometryError, InvalidPropertyError
from tgsis.formats._common import (
    MAX_LINE_BYTES,
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
from tgsis.mesh import Geometry, GeometryCollection, Mesh

__all__ = ["read_vtk", "parse_vtk", "read_vtk_geometry", "parse_vtk_geometry", "write_vtk", "format_vtk"]

# file type names -> numpy dtype (big-endian in binary files); "long" is 8 bytes where VTK files come from (LP64)
_DTYPE_OF: dict[str, str] = {
    "bit": "bit",
    "char": "i1",
    "signed_char": "i1",
    "unsigned_char": "u1",
    "short": "i2",
    "unsigned_short": "u2",
    "int": "i4",
    "unsigned_int": "u4",
    "long": "i8",
    "unsigned_long": "u8",
    "float": "f4",
    "double": "f8",
    "vtkidtype": "i8",
    "vtktypeint8": "i1",
    "vtktypeuint8": "u1",
    "vtktypeint16": "i2",
    "vtktypeuint16": "u2",
    "vtktypeint32": "i4",
    "vtktypeuint32": "u4",
    "vtktypeint64": "i8",
    "vtktypeuint64": "u8",
    "vtktypefloat32": "f4",
    "vtktypefloat64": "f8",
}
# numpy dtype -> (the name written, the dtype written): VTK's legacy reader and meshio's 5.1 reader agree on
# float, double, vtktypeint64 and vtktypeuint64 only (meshio reads "int" as 8 bytes, VTK as 4), so every
# integer is written as a 64-bit one
_TYPE_NAME_OF: dict[str, tuple[str, str]] = {
    "i1": ("vtktypeint64", "i8"),
    "u1": ("vtktypeint64", "i8"),
    "i2": ("vtktypeint64", "i8"),
    "u2": ("vtktypeint64", "i8"),
    "i4": ("vtktypeint64", "i8"),
    "u4": ("vtktypeint64", "i8"),
    "i8": ("vtktypeint64", "i8"),
    "u8": ("vtktypeuint64", "u8"),
    "f4": ("float", "f4"),
    "f8": ("double", "f8"),
}
_TOKEN = re.compile(rb"\S+")
_ATTRIBUTE_KEYWORDS = {
    "SCALARS",
    "VECTORS",
    "NORMALS",
    "TENSORS",
    "TENSORS6",
    "TEXTURE_COORDINATES",
    "FIELD",
    "COLOR_SCALARS",
    "LOOKUP_TABLE",
    "GLOBAL_IDS",
    "PEDIGREE_IDS",
    "METADATA",
}
_CELL_SECTIONS = {
    "VERTICES": "verts",
    "LINES": "lines",
    "POLYGONS": "polys",
    "TRIANGLE_STRIPS": "strips",
    "CELLS": "cells",
}


# ---------------------------------------------------------------- writing


def write_vtk(mesh: Geometry, path: PathLike, *, ascii: bool = False) -> None:
    """Write a mesh or a collection as a legacy VTK file (version 5.1, UNSTRUCTURED_GRID).

    Parameters
    ----------
    mesh : Mesh or GeometryCollection
    path : str or path-like
        The ``.vtk`` file (replaced if it exists).
    ascii : bool
        Text instead of big-endian binary (still exact: doubles as ``repr``).

    Raises
    ------
    FileFormatError
        An unwritable file, or a collection property that not every member has.
    """
    write_bytes(path, [format_vtk(mesh, ascii=ascii)])


def format_vtk(mesh: Geometry, *, ascii: bool = False) -> bytes:
    """The ``.vtk`` file content of a mesh or a collection; see :func:`write_vtk`."""
    members = mesh.members if isinstance(mesh, GeometryCollection) else (check_mesh(mesh, "the legacy VTK writer"),)
    up, zpositive = in_elevation(mesh)  # no z convention in VTK: z up, the convention in the field data
    try:
        vertices, connectivity, offsets, types, point_data, cell_data = vtk_parts(up)
    except InvalidPropertyError as exc:  # a collection property that not every member has
        raise FileFormatError(exc.message, hint=exc.hint) from None
    out = _Writer(ascii)
    title = (mesh.name or "tgsis").replace("\n", " ").replace("\r", " ")[:255]
    out.text(f"# vtk DataFile Version 5.1\n{title}\n{'ASCII' if ascii else 'BINARY'}\nDATASET UNSTRUCTURED_GRID\n")
    fields: list[tuple[str, npt.NDArray[Any]]] = []
    if mesh.name:
        fields.append(("tgsis_name", string_bytes(mesh.name)))
    fields.append(("tgsis_geotype", string_bytes(mesh.geotype.value)))
    if isinstance(mesh, GeometryCollection):
        fields.append(("tgsis_member_geotypes", string_bytes(*(m.geotype.value for m in members))))
        fields.append(("tgsis_member_names", string_bytes(*(m.name or "" for m in members))))
        fields.append(("tgsis_member_sizes", np.array([[m.n_vertices, m.n_cells] for m in members], dtype=np.int64)))
        if any(zpositive):
            fields.append((MEMBER_ZPOSITIVE_FIELD, string_bytes(*(z or "" for z in zpositive))))
    elif zpositive[0] is not None:
        fields.append((ZPOSITIVE_FIELD, string_bytes(zpositive[0])))
    out.field("FieldData", fields)
    out.text(f"POINTS {len(vertices)} double\n")
    out.values(vertices)
    n_cells = len(types)
    out.text(f"CELLS {n_cells + 1} {len(connectivity)}\nOFFSETS vtktypeint64\n")
    out.values(offsets)
    out.text("CONNECTIVITY vtktypeint64\n")
    out.values(connectivity)
    out.text(f"CELL_TYPES {n_cells}\n")
    out.values(types.astype(np.int32))
    # the names of the file the arrays were read from (metadata["vtk_array_names"]), %-encoded by field()
    point_data = named_as_read(point_data, file_array_names(mesh, "point_data"), bool)
    cell_data = named_as_read(cell_data, file_array_names(mesh, "cell_data"), bool)
    for keyword, count, arrays in (("POINT_DATA", len(vertices), point_data), ("CELL_DATA", n_cells, cell_data)):
        if arrays:
            out.text(f"{keyword} {count}\n")
            out.field("FieldData", list(arrays.items()))
    return out.content()


def encode_name(name: str) -> str:
    """An array name as one word of a legacy file, encoded as VTK's writer does: ``%XX`` for each byte (UTF-8) that
    is a blank, a control character, not ASCII, ``"`` or ``%`` (``rock type`` -> ``rock%20type``). VTK's reader
    and tgsis's decode it."""
    return "".join(chr(b) if 0x20 < b < 0x7F and b not in (0x22, 0x25) else f"%{b:02X}" for b in name.encode("utf-8"))


class _Writer:
    def __init__(self, ascii: bool) -> None:
        self.ascii = ascii
        self.parts: list[bytes] = []

    def text(self, line: str) -> None:
        self.parts.append(line.encode("utf-8"))

    def values(self, array: npt.NDArray[Any]) -> None:
        flat = array.reshape(-1)
        if flat.dtype.kind == "b":
            flat = flat.astype(np.uint8)
        if self.ascii:
            if flat.dtype.kind == "f":  # repr: the shortest text that reads back to the same double
                words = [repr(v) for v in flat.tolist()]
            else:
                words = [str(v) for v in flat.tolist()]
            self.parts.append((" ".join(words) + "\n").encode("ascii"))  # nan, inf: strtod and numpy read them
        else:
            self.parts.append(np.ascontiguousarray(flat, dtype=flat.dtype.newbyteorder(">")).tobytes() + b"\n")

    def field(self, name: str, arrays: list[tuple[str, npt.NDArray[Any]]]) -> None:
        if not arrays:
            return
        self.text(f"FIELD {name} {len(arrays)}\n")
        for key, values in arrays:
            values = values.astype(np.uint8) if values.dtype.kind == "b" else values
            if values.dtype.kind == "f" and values.dtype.itemsize < 4:
                values = values.astype(np.float32)
            components = values.shape[1] if values.ndim == 2 else 1
            type_name, code = _TYPE_NAME_OF[values.dtype.str[1:]]
            self.text(f"{encode_name(key)} {components} {len(values)} {type_name}\n")
            self.values(values.astype(code))

    def content(self) -> bytes:
        return b"".join(self.parts)


# ---------------------------------------------------------------- reading


def read_vtk(path: PathLike) -> Mesh:
    """Read a legacy VTK file of one mesh.

    Parameters
    ----------
    path : str or path-like
        A ``.vtk`` file (POLYDATA or UNSTRUCTURED_GRID).

    Returns
    -------
    PointSet, LineSet, Surface or TetraMesh

    Raises
    ------
    FileFormatError
        Not a legacy VTK file tgsis reads (other datasets, cells of several
        kinds, polygons that are not triangles, ...), or a collection
        (:func:`read_vtk_geometry` reads those).
    """
    return parse_vtk(read_bytes(path), path=path)


def parse_vtk(data: bytes, *, path: PathLike | None = None) -> Mesh:
    """Parse the content of a legacy ``.vtk`` file; see :func:`read_vtk`."""
    result = parse_vtk_geometry(data, path=path)
    if isinstance(result, GeometryCollection):
        raise FileFormatError(
            f"the file holds a GEOMETRYCOLLECTION of {len(result)} members, not one mesh",
            path=path,
            hint="tgsis.formats.read or read_vtk_geometry reads the members",
        )
    return result


def read_vtk_geometry(path: PathLike) -> Geometry:
    """Read a legacy VTK file as written: a mesh, or a collection for a file tgsis wrote from one."""
    return parse_vtk_geometry(read_bytes(path), path=path)


@dataclass
class _Dataset:
    kind: str = ""
    points: npt.NDArray[np.float64] | None = None
    cells: dict[str, tuple[npt.NDArray[np.int64], npt.NDArray[np.int64]]] = field(default_factory=dict)
    cell_types: npt.NDArray[np.int64] | None = None
    fields: dict[str, Any] = field(default_factory=dict)
    point_data: dict[str, npt.NDArray[Any]] = field(default_factory=dict)
    cell_data: dict[str, npt.NDArray[Any]] = field(default_factory=dict)
    lines: dict[str, int] = field(default_factory=dict)  # the line of each section's keyword (POINTS, cells, ...)


def parse_vtk_geometry(data: bytes, *, path: PathLike | None = None) -> Geometry:
    """Parse the content of a legacy ``.vtk`` file; see :func:`read_vtk_geometry`."""
    reader = _Reader(data, path)
    dataset = reader.dataset()
    vertices = dataset.points if dataset.points is not None else np.empty((0, 3))
    n_points = len(vertices)
    if dataset.kind == "POLYDATA":
        types_parts, offsets_parts, connectivity_parts = [], [], []
        base = 0
        # VTK numbers a PolyData's cells verts, lines, polys, strips: CELL_DATA is in that order
        for section in ("verts", "lines", "polys", "strips"):
            if section not in dataset.cells:
                continue
            offsets, connectivity = dataset.cells[section]
            size = np.diff(offsets)
            kind = {
                "verts": np.where(size == 1, 1, 2),
                "lines": np.where(size == 2, 3, 4),
                "polys": np.where(size == 3, 5, 7),
                "strips": np.full(len(size), 6),
            }[section]
            types_parts.append(kind)
            offsets_parts.append(offsets[1:] + base)
            connectivity_parts.append(connectivity)
            base += len(connectivity)
        types = np.concatenate(types_parts).astype(np.int64) if types_parts else np.empty(0, np.int64)
        offsets = np.concatenate([[0], *offsets_parts]).astype(np.int64)
        connectivity = (
            np.concatenate(connectivity_parts).astype(np.int64) if connectivity_parts else np.empty(0, np.int64)
        )
    else:
        offsets, connectivity = dataset.cells.get("cells", (np.zeros(1, np.int64), np.empty(0, np.int64)))
        n_cells = len(offsets) - 1
        types = dataset.cell_types if dataset.cell_types is not None else np.empty(0, np.int64)
        if len(types) != n_cells:
            raise FileFormatError(
                f"CELL_TYPES gives {len(types)} types for {n_cells} cells",
                path=path,
                line=dataset.lines.get("CELL_TYPES", dataset.lines.get("cells")),
            )
    names: dict[str, dict[str, str]] = {}
    point_data = _sanitised(dataset.point_data, n_points, names, "point_data", path)
    cell_data = _sanitised(dataset.cell_data, len(types), names, "cell_data", path)
    metadata: dict[str, Any] = {"vtk_array_names": names} if names else {}
    name = first(dataset.fields.get("tgsis_name")) or first(dataset.fields.get("name"))
    geotype = first(dataset.fields.get("tgsis_geotype"))
    if connectivity.size and (connectivity.min() < 0 or connectivity.max() >= n_points):
        bad = int(connectivity.min()) if connectivity.min() < 0 else int(connectivity.max())
        cells_line = max((line for key, line in dataset.lines.items() if key in _CELL_SECTIONS.values()), default=None)
        raise FileFormatError(
            f"a cell refers to point {bad}, but the file has {n_points} points (0..{n_points - 1})",
            path=path,
            line=cells_line,
        )
    if geotype != GeometryCollection.geotype.value:
        types, offsets, connectivity, cell_data = split_vtk_polygons(
            vertices, types, offsets, connectivity, cell_data, metadata, path, f"{dataset.kind} cell"
        )
    geometry: Geometry
    try:
        if geotype == GeometryCollection.geotype.value:
            table = (
                strings(dataset.fields.get("tgsis_member_geotypes", [])),
                strings(dataset.fields.get("tgsis_member_names", [])),
                dataset.fields.get("tgsis_member_sizes", np.empty((0, 2))),
            )
            geometry = collection_from_cells(
                vertices, types, offsets, connectivity, point_data, cell_data, table, name, metadata, "the file"
            )
        else:
            geometry = mesh_from_vtk_cells(
                vertices,
                types,
                offsets,
                connectivity,
                point_data,
                cell_data,
                name=name,
                geotype=geotype,
                metadata=metadata,
                source=f"the {dataset.kind}",
            )
    except (InvalidGeometryError, InvalidPropertyError) as exc:
        raise FileFormatError(exc.message, path=path, detail=exc.detail, hint=exc.hint) from exc
    _restore_recorded(geometry, dataset.fields, path)
    return geometry


def _restore_recorded(geometry: Geometry, fields: dict[str, Any], path: PathLike | None) -> None:
    """The z convention the FieldData records (the file's z is up), given back to the mesh or each member."""
    if isinstance(geometry, GeometryCollection):
        if MEMBER_ZPOSITIVE_FIELD in fields:
            recorded = strings(fields[MEMBER_ZPOSITIVE_FIELD])
            if len(recorded) != len(geometry):
                raise FileFormatError(
                    f"FIELD array {MEMBER_ZPOSITIVE_FIELD} has {len(recorded)} values for {len(geometry)} members",
                    path=path,
                )
            restore_convention(geometry, list(recorded), path, f"FIELD array {MEMBER_ZPOSITIVE_FIELD}")
    elif ZPOSITIVE_FIELD in fields:
        restore_convention(geometry, first(fields[ZPOSITIVE_FIELD]), path, f"FIELD array {ZPOSITIVE_FIELD}")


def _sanitised(
    arrays: dict[str, npt.NDArray[Any]], count: int, names: dict[str, dict[str, str]], key: str, path: PathLike | None
) -> dict[str, npt.NDArray[Any]]:
    result: dict[str, npt.NDArray[Any]] = {}
    renamed: dict[str, str] = {}
    for original, values in arrays.items():
        if len(values) != count:
            raise FileFormatError(
                f"{key} array {quoted(original)} has {len(values)} tuples, the dataset {count}", path=path
            )
        name = sanitize_property_name(original.strip() or original, result)  # as GOCAD names: " default property"
        if name != original:
            renamed[name] = original
        result[name] = values
    if renamed:
        names[key] = renamed
    return result


class _Reader:
    """A cursor over a legacy VTK file: header lines, then ASCII words or binary blocks."""

    def __init__(self, data: bytes, path: PathLike | None) -> None:
        self.data = data
        self.path = path
        self.pos = 0
        self.line_number = 0
        self.binary = False

    def fail(self, message: str, hint: str | None = None) -> FileFormatError:
        return FileFormatError(message, path=self.path, line=self.line_number or None, hint=hint)

    def raw_line(self) -> str | None:
        """The next line (without its end), or None at the end of the file."""
        if self.pos >= len(self.data):
            return None
        end = self.data.find(b"\n", self.pos)
        end = len(self.data) if end < 0 else end
        if end - self.pos > MAX_LINE_BYTES:  # a keyword line (values are read word by word, not by line)
            self.line_number += 1
            raise self.fail(
                f"line {self.line_number} is {end - self.pos:,} bytes long; a legacy VTK keyword line "
                f"is at most {MAX_LINE_BYTES:,} bytes long here"
            )
        text = self.data[self.pos : end].rstrip(b"\r").decode("latin-1")
        self.pos = end + 1
        self.line_number += 1
        return text

    def line(self) -> str | None:
        """The next line that is not blank."""
        while True:
            text = self.raw_line()
            if text is None or text.strip():
                return text

    def peek(self) -> str | None:
        pos, number = self.pos, self.line_number
        text = self.line()
        self.pos, self.line_number = pos, number
        return text

    def values(self, type_name: str, count: int, what: str) -> npt.NDArray[Any]:
        """``count`` values of a file type, ASCII words or big-endian binary."""
        code = _DTYPE_OF.get(type_name.lower())
        if code is None:
            raise self.fail(f"{what} has data type {quoted(type_name)}, which tgsis does not read")
        if code == "bit":
            raise self.fail(f"{what} is a bit array, which tgsis does not read", hint="store it as unsigned_char (0/1)")
        dtype = np.dtype(">" + code)
        if not self.binary:
            tokens = list(islice(_TOKEN.finditer(self.data, self.pos), count))
            if len(tokens) != count:
                raise self.fail(f"{what}: expected {count} values, the file ends after {len(tokens)}")
            if tokens:
                self.line_number += self.data.count(b"\n", self.pos, tokens[-1].end())
                self.pos = tokens[-1].end()
            words = [t.group() for t in tokens]
            try:
                if dtype.kind == "f":
                    return np.array([float(w) for w in words], dtype=np.float64).astype(dtype.newbyteorder("="))
                return np.array([int(w) for w in words], dtype=dtype.newbyteorder("="))
            except (ValueError, OverflowError):
                raise self.fail(f"{what} has values that are not {type_name}") from None
        size = count * dtype.itemsize
        chunk = self.data[self.pos : self.pos + size]
        if len(chunk) != size:
            raise self.fail(f"{what}: expected {size} bytes of binary data, the file ends after {len(chunk)}")
        self.pos += size
        if self.data[self.pos : self.pos + 1] == b"\n":
            self.pos += 1
        self.line_number += chunk.count(b"\n") + 1
        return np.frombuffer(chunk, dtype=dtype).astype(dtype.newbyteorder("="))

    def strings(self, count: int, what: str) -> list[str]:
        """``count`` strings of a string array: one per line (ASCII, %-escaped) or length-prefixed (binary)."""
        result: list[str] = []
        if not self.binary:
            for _ in range(count):
                text = self.raw_line()
                if text is None:
                    raise self.fail(f"{what}: the file ends inside a string array")
                result.append(unquote_to_bytes(text).decode("utf-8", "replace"))
            return result
        for _ in range(count):
            if self.pos >= len(self.data):
                raise self.fail(f"{what}: the file ends inside a string array")
            head = self.data[self.pos]
            width = {3: 1, 2: 2, 1: 4, 0: 8}[head >> 6]  # VTK: the top two bits say how many bytes hold the length
            length = int.from_bytes(self.data[self.pos : self.pos + width], "big") & ((1 << (8 * width - 2)) - 1)
            self.pos += width
            result.append(self.data[self.pos : self.pos + length].decode("utf-8", "replace"))
            self.pos += length
        if self.data[self.pos : self.pos + 1] == b"\n":
            self.pos += 1
        return result

    def header(self) -> str:
        line = self.raw_line()
        if line is None or not line.startswith("# vtk DataFile Version"):
            raise self.fail(
                "not a legacy VTK file (the first line must be '# vtk DataFile Version x.y')",
                hint="a VTK XML file is .vtu (UnstructuredGrid) or .vtp (PolyData)",
            )
        version = line.split()[-1]
        if self.raw_line() is None:
            raise self.fail("the file ends after its first line")
        mode = (self.line() or "").strip().upper()
        if mode not in ("ASCII", "BINARY"):
            raise self.fail(f"the third line must be ASCII or BINARY, not {quoted(mode)}")
        self.binary = mode == "BINARY"
        return version

    def dataset(self) -> _Dataset:
        version = self.header()
        modern = version.startswith("5")
        words = (self.line() or "").split()
        if len(words) != 2 or words[0].upper() != "DATASET":
            raise self.fail(f"expected 'DATASET type', got {quoted(' '.join(words))}")
        result = _Dataset(kind=words[1].upper())
        if result.kind not in ("POLYDATA", "UNSTRUCTURED_GRID"):
            raise self.fail(
                f"DATASET {result.kind} is not read by tgsis: it reads POLYDATA and UNSTRUCTURED_GRID",
                hint="convert it to an unstructured grid first (pyvista: "
                "mesh.cast_to_unstructured_grid().save('x.vtk'))",
            )
        attributes: dict[str, npt.NDArray[Any]] | None = None
        count = 0
        empty_data: tuple[str, int] | None = None  # a POINT_DATA/CELL_DATA line no array has followed yet
        while (text := self.line()) is not None:
            words = text.split()
            keyword = words[0].upper()
            result.lines[_CELL_SECTIONS.get(keyword, keyword)] = self.line_number
            if keyword in _ATTRIBUTE_KEYWORDS and keyword != "METADATA":
                empty_data = None
            if keyword == "FIELD" and attributes is None:
                self._field(words, result.fields, None, keep_strings=True)
            elif keyword == "POINTS":
                n = self._int(words, 1, "POINTS")
                result.points = (
                    self.values(words[2] if len(words) > 2 else "float", 3 * n, "POINTS")
                    .astype(np.float64)
                    .reshape(n, 3)
                )
            elif keyword in _CELL_SECTIONS:
                result.cells[_CELL_SECTIONS[keyword]] = self._cells(words, modern)
            elif keyword == "CELL_TYPES":
                result.cell_types = self.values("int", self._int(words, 1, "CELL_TYPES"), "CELL_TYPES").astype(np.int64)
            elif keyword in ("POINT_DATA", "CELL_DATA"):
                if empty_data is not None:
                    raise self._no_arrays(*empty_data)
                empty_data = (keyword, self.line_number)
                count = self._int(words, 1, keyword)
                attributes = result.point_data if keyword == "POINT_DATA" else result.cell_data
            elif keyword == "METADATA":
                self._skip_metadata()
            elif keyword in _ATTRIBUTE_KEYWORDS and attributes is not None:
                self._attribute(words, attributes, count)
            else:
                raise self.fail(f"unexpected section {quoted(words[0])} in a legacy VTK {result.kind} file")
        # a legacy VTK file has no end mark: a file cut between two sections is found by what it lacks
        if empty_data is not None:
            raise self._no_arrays(*empty_data)
        if result.points is None:
            raise self.fail("the file has no POINTS section (is it cut short?)")
        if result.kind == "UNSTRUCTURED_GRID" and len(result.points) and "cells" not in result.cells:
            raise self.fail(f"the file has {len(result.points)} POINTS but no CELLS section (is it cut short?)")
        return result

    def _no_arrays(self, keyword: str, line: int) -> FileFormatError:
        return FileFormatError(
            f"{keyword} is followed by no data array (is the file cut short?)", path=self.path, line=line
        )

    def _int(self, words: list[str], index: int, what: str) -> int:
        try:
            value = int(words[index])
        except (IndexError, ValueError):
            raise self.fail(f"{what} needs a count, got {quoted(' '.join(words))}") from None
        if value < 0:
            raise self.fail(f"{what} count is negative")
        return value

    def _cells(self, words: list[str], modern: bool) -> tuple[npt.NDArray[np.int64], npt.NDArray[np.int64]]:
        """Offsets (m + 1, from 0) and connectivity of one cell section."""
        what = words[0]
        first, second = self._int(words, 1, what), self._int(words, 2, what)
        if modern:  # 5.1: "CELLS offsets connectivity", then OFFSETS and CONNECTIVITY arrays
            arrays: dict[str, npt.NDArray[np.int64]] = {}
            for expected, n in (("OFFSETS", first), ("CONNECTIVITY", second)):
                head = (self.line() or "").split()
                if len(head) != 2 or head[0].upper() != expected:
                    raise self.fail(f"{what}: expected '{expected} type', got {quoted(' '.join(head))}")
                arrays[expected] = self.values(head[1], n, f"{what} {expected}").astype(np.int64)
            offsets, connectivity = arrays["OFFSETS"], arrays["CONNECTIVITY"]
            if len(offsets) == 0:
                offsets = np.zeros(1, np.int64)
            if offsets[0] != 0 or np.any(np.diff(offsets) < 0) or offsets[-1] != len(connectivity):
                raise self.fail(f"{what}: OFFSETS do not describe the CONNECTIVITY")
            return offsets, connectivity
        flat = self.values("int", second, what).astype(np.int64)  # n cells, each "k i1 .. ik"
        if first and len(flat) % first == 0 and len(flat) // first >= 2:  # all cells of one size: no loop
            k = len(flat) // first - 1
            table = flat.reshape(first, k + 1)
            if bool(np.all(table[:, 0] == k)):
                return np.arange(first + 1, dtype=np.int64) * k, np.ascontiguousarray(table[:, 1:]).reshape(-1)
        offsets = np.zeros(first + 1, np.int64)
        keep = np.ones(len(flat), bool)
        position = 0
        for i in range(first):
            if position >= len(flat):
                raise self.fail(f"{what}: {first} cells do not fit in {second} numbers")
            size = int(flat[position])
            keep[position] = False
            offsets[i + 1] = offsets[i] + size
            position += size + 1
        if position != len(flat):
            raise self.fail(f"{what}: {first} cells do not fill {second} numbers")
        return offsets, flat[keep]

    def _skip_metadata(self) -> None:
        """A METADATA block ends at the first blank line."""
        while (text := self.raw_line()) is not None and text.strip():
            pass

    def _attribute(self, words: list[str], into: dict[str, npt.NDArray[Any]], count: int) -> None:
        keyword = words[0].upper()
        if keyword == "FIELD":
            self._field(words, into, count, keep_strings=False)
            return
        if len(words) < 2:
            raise self.fail(f"{keyword} needs a name")
        name = unquote_to_bytes(words[1]).decode("utf-8", "replace")
        if keyword == "LOOKUP_TABLE":
            size = self._int(words, 2, keyword)
            if self.binary:
                self.values("unsigned_char", 4 * size, keyword)
            else:
                self.values("float", 4 * size, keyword)
            return
        if keyword == "COLOR_SCALARS":
            components = self._int(words, 2, keyword)
            values = self.values("unsigned_char" if self.binary else "float", components * count, keyword)
            into[name] = values.reshape(count, components) if components > 1 else values
            return
        type_name = words[2] if len(words) > 2 else "float"
        components = {"VECTORS": 3, "NORMALS": 3, "TENSORS": 9, "TENSORS6": 6, "GLOBAL_IDS": 1, "PEDIGREE_IDS": 1}.get(
            keyword, 1
        )
        if keyword == "SCALARS":
            components = self._int(words, 3, keyword) if len(words) > 3 else 1
        elif keyword == "TEXTURE_COORDINATES":
            components, type_name = self._int(words, 2, keyword), words[3] if len(words) > 3 else "float"
        if (
            keyword == "SCALARS"
            and (nxt := self.peek()) is not None
            and nxt.split()[0].upper() == "LOOKUP_TABLE"
            and len(nxt.split()) == 2
        ):
            self.line()  # "LOOKUP_TABLE default" between the SCALARS line and its values
        if type_name.lower() in ("string", "utf8_string"):
            self.strings(count * components, f"{keyword} {name}")
            return
        values = self.values(type_name, components * count, f"{keyword} {name}")
        into[name] = values.reshape(count, components) if components > 1 else values

    def _field(self, words: list[str], into: dict[str, Any], count: int | None, *, keep_strings: bool) -> None:
        n_arrays = self._int(words, 2, "FIELD")
        for _ in range(n_arrays):
            head = (self.line() or "").split()
            if head and head[0].upper() == "METADATA":
                self._skip_metadata()
                head = (self.line() or "").split()
            if len(head) != 4:
                raise self.fail(f"a FIELD array needs 'name components tuples type', got {quoted(' '.join(head))}")
            name = unquote_to_bytes(head[0]).decode("utf-8", "replace")
            components, tuples = self._int(head, 1, name), self._int(head, 2, name)
            if head[3].lower() in ("string", "utf8_string"):
                texts = self.strings(components * tuples, f"FIELD array {name}")
                if keep_strings:
                    into[name] = np.array(texts)
                continue
            values = self.values(head[3], components * tuples, f"FIELD array {name}")
            into[name] = values.reshape(tuples, components) if components > 1 else values
        if (nxt := self.peek()) is not None and nxt.split()[0].upper() == "METADATA":
            self.line()
            self._skip_metadata()
