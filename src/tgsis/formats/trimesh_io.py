"""Triangle surfaces in OBJ, PLY, OFF and STL: strict readers of tgsis, writers of trimesh (PLY: of tgsis).

What each format keeps (checked by ``tests/test_formats_trimesh.py``):

=======  ==============  =====================  ==================  ==============================
format   vertex order    coordinates            properties          written by
=======  ==============  =====================  ==================  ==============================
PLY      kept            bit-exact (float64)    vertex and face     tgsis (binary little-endian)
OBJ      kept [1]_       8 decimals [2]_        none                trimesh
OFF      kept [1]_       10 decimals [2]_       none                trimesh
STL      not kept [3]_   float32                none                trimesh (binary)
=======  ==============  =====================  ==================  ==============================

.. [1] Every vertex, also those no face uses (trimesh's OBJ reader dropped
   them), one per ``v`` line whatever the texture coordinates of its corners.
   Planar convex polygons of more than three corners are split into a fan of
   triangles (:class:`~tgsis.errors.PolygonsSplitWarning`,
   ``metadata["polygons_split"]``), other polygons refused; texture
   coordinates, normals, colours and materials are not read. OBJ groups
   become the ``part`` cell property and ``metadata["part_names"]``, and the
   OBJ writer writes the parts back as ``g`` lines.
.. [2] Fixed-point text: a coordinate comes back within 0.5e-8 (OBJ) or 0.5e-10
   (OFF) of what was written, plus one rounding of the double; big UTM
   coordinates keep 15-16 significant digits, not 17. ``digits=`` asks for more
   decimals.
.. [3] STL stores each triangle's three corners in float32: reading gives 3m
   vertices (corner order of each face) rounded to float32;
   ``merge_vertices=True`` joins corners with identical coordinates, in order
   of first use.

Files are read by :mod:`tgsis.formats._surface_files`, not by trimesh, whose
readers return broken files without a word (a truncated OFF kept the faces
before the cut, OBJ index 0 became the last vertex, PLY
``binary_middle_endian`` was read as little-endian): a file cut short, with
more or fewer elements than it declares, a bad index, a NaN or infinite
coordinate or a line over 1 MiB raises :class:`~tgsis.errors.FileFormatError`
naming the file and the line.

PLY is written here rather than by trimesh because trimesh's PLY writer stores
coordinates as float32 (about 0.25 m of error on UTM northings) and 64-bit
integers as ``int64``, a type PLY readers other than trimesh do not know. This
writer stores ``double`` coordinates, ``int`` face indices and each property in
its own PLY type; int64/uint64 properties are written as ``int``/``uint`` when
their values fit (else :class:`~tgsis.errors.FileFormatError`), bool as
``uchar``, float16 as ``float``. On reading, integer PLY properties become int64
and float ones keep float32/float64; colours, normals and texture coordinates
are properties like any other. OBJ, OFF and STL cannot store properties (OBJ
but ``part``, as groups): the writer raises unless ``drop_properties=True``.
None of these formats has a z convention: a mesh whose ``metadata["zpositive"]``
says ``Depth`` is written in elevation (z negated); PLY records the convention
in a ``comment tgsis zpositive`` line, which the reader gives back. Names are not stored (meshes
read have ``name=None``).

A file of points without faces (OBJ ``v`` lines alone, a PLY ``vertex``
element alone, an OFF file of 0 faces) is read as a
:class:`~tgsis.mesh.PointSet` with the PLY vertex properties, not as an empty
surface; a PLY file that declares a ``face`` element with no face, as this
writer writes a surface without triangles, is a Surface without triangles. A
file without any vertex is an error.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from tgsis.errors import FileFormatError, InvalidGeometryError, InvalidPropertyError, PolygonsSplitWarning
from tgsis.formats._common import (
    PathLike,
    check_mesh,
    in_elevation,
    property_columns,
    read_bytes,
    restore_convention,
    write_bytes,
)
from tgsis.formats._surface_files import ParsedSurface, parse_obj, parse_off, parse_ply, parse_stl
from tgsis.mesh import PointSet, Surface

__all__ = ["TRIMESH_FILE_TYPES", "read_trimesh_file", "write_trimesh_file"]

#: File types handled here (the file extension without the dot).
TRIMESH_FILE_TYPES = ("obj", "ply", "off", "stl")

_PLY_TYPES = {
    "i1": "char",
    "u1": "uchar",
    "i2": "short",
    "u2": "ushort",
    "i4": "int",
    "u4": "uint",
    "f4": "float",
    "f8": "double",
}
_PLY_COORDINATES = ("x", "y", "z")
_PLY_FACE_INDICES = ("vertex_indices", "vertex_index")


def _file_type(path: PathLike, file_type: str | None) -> str:
    """The file type from ``file_type`` or the extension, checked."""
    kind = (file_type or Path(path).suffix).lower().lstrip(".")
    if kind not in TRIMESH_FILE_TYPES:
        raise FileFormatError(
            f"unknown surface file type {kind!r}: use one of {', '.join(TRIMESH_FILE_TYPES)}", path=path
        )
    return kind


# ---------------------------------------------------------------- reading


def read_trimesh_file(
    path: PathLike, *, file_type: str | None = None, merge_vertices: bool = False
) -> Surface | PointSet:
    """Read a triangle surface, or points, from an OBJ, PLY, OFF or STL file.

    The file is read by the strict readers of :mod:`tgsis.formats._surface_files`
    (not trimesh's, which read broken files without a word): every vertex and
    face the file declares, or :class:`FileFormatError` naming the file and
    the line.

    Parameters
    ----------
    path : str or path-like
        The file.
    file_type : {"obj", "ply", "off", "stl"}, optional
        The format; by default from the extension.
    merge_vertices : bool
        Join vertices with identical coordinates (first occurrence wins, order of
        first occurrence kept). Meant for STL, which repeats every corner.

    Returns
    -------
    Surface or PointSet
        Vertices (n, 3) in file order, every one of them (also those no face
        uses), and triangles (m, 3) (polygons split into fans); PLY vertex and
        face properties as properties. A file of points without faces (a PLY
        ``vertex`` element alone, OBJ ``v`` lines alone, an OFF file of 0 faces)
        is a PointSet of its vertices, with the PLY vertex properties; a PLY
        file that declares a ``face`` element of 0 faces is a Surface without
        triangles.

    Raises
    ------
    FileFormatError
        The file cannot be read, is cut short, holds more or fewer elements
        than it declares, a bad index or number, no vertex, or is not a valid
        surface (e.g. a face that uses one vertex twice).
    """
    kind = _file_type(path, file_type)
    data = read_bytes(path)
    parsed = _PARSERS[kind](data, path)
    vertices, faces = parsed.vertices, parsed.triangles
    vertex_properties, face_properties = parsed.vertex_properties, parsed.face_properties
    metadata: dict[str, Any] = {"ply_property_names": parsed.renamed} if parsed.renamed else {}
    if len(vertices) == 0:
        raise FileFormatError(f"the {kind.upper()} file holds no vertex (no triangle and no point)", path=path)
    if parsed.parts is not None:
        face_properties = {**face_properties, "part": parsed.parts}
    if parsed.part_names:
        metadata["part_names"] = parsed.part_names
    if parsed.polygons_split:
        metadata["polygons_split"] = parsed.polygons_split
        warnings.warn(
            PolygonsSplitWarning(
                f"{path}: {parsed.polygons_split:,} faces of more than 3 corners were split into triangles (each planar "
                "and convex: the triangles have its shape)",
                path=path,
                count=parsed.polygons_split,
            ),
            stacklevel=2,
        )
    if merge_vertices:
        vertices, faces, vertex_properties = _merge_identical(vertices, faces, vertex_properties)
    mesh: Surface | PointSet
    try:
        if len(faces) == 0 and not (kind == "ply" and parsed.has_faces):
            mesh = PointSet(vertices, vertex_properties=vertex_properties, metadata=metadata)
        else:
            mesh = Surface(
                vertices, faces, vertex_properties=vertex_properties, cell_properties=face_properties, metadata=metadata
            )
    except (InvalidGeometryError, InvalidPropertyError) as exc:
        raise FileFormatError(f"the {kind.upper()} file is not a valid surface: {exc.message}", path=path) from exc
    restore_convention(mesh, parsed.zpositive, path, "the PLY comment 'tgsis zpositive'")
    return mesh


_PARSERS: dict[str, Callable[[bytes, PathLike], ParsedSurface]] = {
    "obj": parse_obj,
    "off": parse_off,
    "ply": parse_ply,
    "stl": parse_stl,
}


def _merge_identical(
    vertices: npt.NDArray[np.float64], faces: npt.NDArray[np.int64], properties: dict[str, npt.NDArray[Any]]
) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.int64], dict[str, npt.NDArray[Any]]]:
    """Join vertices with equal coordinates, keeping the order of first occurrence."""
    if len(vertices) == 0:
        return vertices, faces, properties
    _, first, inverse = np.unique(vertices, axis=0, return_index=True, return_inverse=True)
    order = np.argsort(first)  # distinct vertices by first occurrence
    rank = np.empty_like(order)
    rank[order] = np.arange(len(order))
    keep = first[order]
    return (
        vertices[keep],
        rank[inverse.reshape(-1)][faces],
        {name: values[keep] for name, values in properties.items()},
    )


# ---------------------------------------------------------------- writing


def write_trimesh_file(
    surface: Surface,
    path: PathLike,
    *,
    file_type: str | None = None,
    digits: int | None = None,
    drop_properties: bool = False,
) -> None:
    """Write a surface as OBJ, PLY, OFF or STL.

    Parameters
    ----------
    surface : Surface
        The surface to write.
    path : str or path-like
        The file (replaced if it exists).
    file_type : {"obj", "ply", "off", "stl"}, optional
        The format; by default from the extension.
    digits : int, optional
        Decimals of OBJ (default 8) and OFF (default 10) coordinates; not
        allowed for PLY and STL, which are binary.
    drop_properties : bool
        Write OBJ, OFF or STL without the surface's properties instead of raising.

    Raises
    ------
    FileFormatError
        The mesh is not a Surface, has properties the format cannot store, a
        PLY property does not fit a PLY type, or the file cannot be written.
    """
    kind = _file_type(path, file_type)
    mesh = check_mesh(surface, f"the {kind.upper()} writer")
    if not isinstance(mesh, Surface):
        raise FileFormatError(f"{kind.upper()} stores triangle surfaces, not a {type(mesh).__name__}", path=path)
    up, (zpositive,) = in_elevation(mesh, path)  # no z convention in these formats: z up
    assert isinstance(up, Surface)
    mesh = up
    if digits is not None and kind not in ("obj", "off"):
        raise FileFormatError(f"digits= applies to OBJ and OFF text, not to binary {kind.upper()}", path=path)
    if kind == "ply":
        data = _ply_bytes(mesh, path, zpositive)
    else:
        lost = [*mesh.vertex_properties, *(k for k in mesh.cell_properties if not (kind == "obj" and k == "part"))]
        if lost and not drop_properties:
            raise FileFormatError(
                f"{kind.upper()} cannot store the properties {', '.join(lost)}",
                path=path,
                hint="write PLY or VTU to keep them, or pass drop_properties=True",
            )
        data = _trimesh_bytes(mesh, kind, digits)
        if kind == "obj" and "part" in mesh.cell_properties:
            data = _obj_with_groups(data, mesh, path)
    write_bytes(path, [data])


def _obj_with_groups(data: bytes, surface: Surface, path: PathLike) -> bytes:
    """trimesh's OBJ text with a ``g`` line wherever the part of the faces changes (cell order kept).

    Each part is named by ``metadata["part_names"]`` (or ``gocad_part_names``) in
    part order, else ``part_<number>``; reading gives the parts back.
    """
    parts = np.asarray(surface.cell_properties["part"])
    if parts.dtype.kind not in "iu" and not (parts.dtype.kind == "f" and np.all(parts == np.round(parts))):
        raise FileFormatError(f"cell property 'part' must hold whole part numbers, not {parts.dtype}", path=path)
    distinct = np.unique(parts).tolist()
    listed = surface.metadata.get("part_names") or surface.metadata.get("gocad_part_names")
    names = [str(v) for v in listed] if isinstance(listed, list) and len(listed) == len(distinct) else []
    label = {
        p: " ".join((names[j] if names and names[j].strip() else f"part_{int(p)}").split())
        for j, p in enumerate(distinct)
    }
    if len(set(label.values())) != len(label):
        label = {p: f"part_{int(p)}" for p in distinct}  # names that would merge parts
    lines = data.decode("utf-8").split("\n")
    face = 0
    out: list[str] = []
    current = None
    for line in lines:
        if line.startswith("f "):
            if parts[face] != current:
                current = parts[face]
                out.append(f"g {label[current]}")
            face += 1
        out.append(line)
    if face != len(parts):  # pragma: no cover - trimesh writes one f line per face
        raise FileFormatError("the OBJ writer wrote another number of faces than the surface has", path=path)
    return "\n".join(out).encode("utf-8")


def _trimesh_bytes(surface: Surface, kind: str, digits: int | None) -> bytes:
    """OBJ/OFF/STL content from trimesh's exporters (no normals, colours or textures)."""
    import trimesh
    from trimesh.exchange import obj, off, stl

    tm = trimesh.Trimesh(vertices=surface.vertices.copy(), faces=surface.cells.copy(), process=False, validate=False)
    if kind == "obj":
        export_obj: Any = obj.export_obj  # untyped in trimesh
        text = export_obj(
            tm,
            include_normals=False,
            include_color=False,
            include_texture=False,
            digits=8 if digits is None else digits,
        )
        return str(text).encode("utf-8")
    if kind == "off":
        return str(off.export_off(tm, digits=10 if digits is None else digits)).encode("utf-8")
    return bytes(stl.export_stl(tm))


def _ply_type(name: str, values: npt.NDArray[Any], path: PathLike) -> tuple[str, npt.NDArray[Any]]:
    """The PLY type of a property and its values converted to it (little-endian)."""
    if values.dtype.kind == "b":
        values = values.astype(np.uint8)
    elif values.dtype.kind == "f" and values.dtype.itemsize < 4:
        values = values.astype(np.float32)
    elif values.dtype.kind in "iu" and values.dtype.itemsize == 8:
        narrow = np.dtype(np.int32 if values.dtype.kind == "i" else np.uint32)
        info = np.iinfo(narrow)
        if len(values) and (values.min() < info.min or values.max() > info.max):
            raise FileFormatError(
                f"PLY has no 64-bit integers and property {name!r} has values outside {narrow.name}", path=path
            )
        values = values.astype(narrow)
    values = values.astype(values.dtype.newbyteorder("<"))
    return _PLY_TYPES[values.dtype.str[1:]], values


def _ply_bytes(surface: Surface, path: PathLike, zpositive: str | None = None) -> bytes:
    """A binary little-endian PLY with double coordinates, int indices and typed properties.

    ``zpositive``: the z convention of the mesh ``surface`` (in elevation) came from, recorded in a comment.
    """
    n, m = surface.n_vertices, surface.n_cells
    if n > np.iinfo(np.int32).max:
        raise FileFormatError(f"PLY face indices are 32-bit: {n} vertices are too many", path=path)
    recorded = [f"comment tgsis zpositive {zpositive} (z is written up positive, as elevation)"] if zpositive else []
    header = [
        "ply",
        "format binary_little_endian 1.0",
        "comment tgsis",
        *recorded,
        f"element vertex {n}",
        *(f"property double {c}" for c in _PLY_COORDINATES),
    ]
    vertex_fields: list[tuple[str, npt.NDArray[Any]]] = [
        (c, surface.vertices[:, j]) for j, c in enumerate(_PLY_COORDINATES)
    ]
    for name, values in property_columns(surface.vertex_properties):
        if name in _PLY_COORDINATES:
            raise FileFormatError(f"a vertex property named {name!r} would clash with the PLY coordinate", path=path)
        ply_type, converted = _ply_type(name, values, path)
        header.append(f"property {ply_type} {name}")
        vertex_fields.append((name, converted))
    header += [f"element face {m}", "property list uchar int vertex_indices"]
    face_fields: list[tuple[str, npt.NDArray[Any]]] = [
        ("count", np.full(m, 3, dtype=np.uint8)),
        ("vertex_indices", surface.cells.astype("<i4")),
    ]
    for name, values in property_columns(surface.cell_properties):
        if name in _PLY_FACE_INDICES or name == "count":
            raise FileFormatError(f"a face property named {name!r} would clash with the PLY face list", path=path)
        ply_type, converted = _ply_type(name, values, path)
        header.append(f"property {ply_type} {name}")
        face_fields.append((name, converted))
    header.append("end_header\n")
    return "\n".join(header).encode("ascii") + _packed(vertex_fields, n) + _packed(face_fields, m)


def _packed(fields: list[tuple[str, npt.NDArray[Any]]], count: int) -> bytes:
    """Rows of the fields back to back without padding, as PLY binary elements are laid out."""
    dtype = np.dtype([(name, values.dtype.newbyteorder("<"), values.shape[1:]) for name, values in fields])
    table = np.empty(count, dtype=dtype)
    for name, values in fields:
        table[name] = values
    return table.tobytes()
