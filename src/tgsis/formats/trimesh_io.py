"""Triangle surfaces in OBJ, PLY, OFF and STL, read through trimesh.

What each format keeps (found by reading the readers and writers of trimesh 5.2
and checked by ``tests/test_formats_trimesh.py``):

=======  ==============  =====================  ==================  ==============================
format   vertex order    coordinates            properties          written by
=======  ==============  =====================  ==================  ==============================
PLY      kept            bit-exact (float64)    vertex and face     tgsis (binary little-endian)
OBJ      kept [1]_       8 decimals [2]_        none                trimesh
OFF      kept            10 decimals [2]_       none                trimesh
STL      not kept [3]_   float32                none                trimesh (binary)
=======  ==============  =====================  ==================  ==============================

.. [1] trimesh's OBJ reader drops vertices that no face uses (even with
   ``process=False``); the others keep their order. Faces with texture or
   normal indices (``f 1/1/1 ...``) may be re-indexed by trimesh.
.. [2] Fixed-point text: a coordinate comes back within 0.5e-8 (OBJ) or 0.5e-10
   (OFF) of what was written, plus one rounding of the double; big UTM
   coordinates keep 15-16 significant digits, not 17. ``digits=`` asks for more
   decimals.
.. [3] STL stores each triangle's three corners in float32: reading gives 3m
   vertices (corner order of each face) rounded to float32;
   ``merge_vertices=True`` joins corners with identical coordinates, in order
   of first use.

PLY is written here rather than by trimesh because trimesh's PLY writer stores
coordinates as float32 (about 0.25 m of error on UTM northings) and 64-bit
integers as ``int64``, a type PLY readers other than trimesh do not know. This
writer stores ``double`` coordinates, ``int`` face indices and each property in
its own PLY type; int64/uint64 properties are written as ``int``/``uint`` when
their values fit (else :class:`~tgsis.errors.FileFormatError`), bool as
``uchar``, float16 as ``float``. On reading, integer PLY properties become int64
and float ones keep float32/float64; colours, normals and texture coordinates
are properties like any other. OBJ, OFF and STL cannot store properties: the
writer raises unless ``drop_properties=True``. Names are not stored (meshes
read have ``name=None``).

A file of points without faces (OBJ ``v`` lines alone, a PLY ``vertex``
element alone) is read as a :class:`~tgsis.mesh.PointSet` with the PLY vertex
properties, not as an empty surface (trimesh's ``force="mesh"`` drops the
points); a PLY file that declares a ``face`` element with no face, as this
writer writes a surface without triangles, is a Surface without triangles. A
file without any vertex is an error.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from tgsis.errors import FileFormatError, InvalidGeometryError, InvalidPropertyError
from tgsis.formats._common import (PathLike, check_mesh, property_columns, sanitize_property_name, write_bytes)
from tgsis.mesh import PointSet, Surface

__all__ = ["TRIMESH_FILE_TYPES", "read_trimesh_file", "write_trimesh_file"]

#: File types handled here (the file extension without the dot).
TRIMESH_FILE_TYPES = ("obj", "ply", "off", "stl")

_PLY_TYPES = {"i1": "char", "u1": "uchar", "i2": "short", "u2": "ushort", "i4": "int", "u4": "uint",
              "f4": "float", "f8": "double"}
_PLY_COORDINATES = ("x", "y", "z")
_PLY_FACE_INDICES = ("vertex_indices", "vertex_index")


def _file_type(path: PathLike, file_type: str | None) -> str:
    """The file type from ``file_type`` or the extension, checked."""
    kind = (file_type or Path(path).suffix).lower().lstrip(".")
    if kind not in TRIMESH_FILE_TYPES:
        raise FileFormatError(f"unknown surface file type {kind!r}: use one of {', '.join(TRIMESH_FILE_TYPES)}",
                              path=path)
    return kind


# ---------------------------------------------------------------- reading


def read_trimesh_file(path: PathLike, *, file_type: str | None = None,
                      merge_vertices: bool = False) -> Surface | PointSet:
    """Read a triangle surface, or points, from an OBJ, PLY, OFF or STL file.

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
        Vertices (n, 3) and triangles (m, 3) as trimesh read them with
        ``process=False``; PLY vertex and face properties as properties. A
        file of points without faces (a PLY ``vertex`` element alone, OBJ
        ``v`` lines alone) is a PointSet of its vertices, with the PLY vertex
        properties.

    Raises
    ------
    FileFormatError
        The file cannot be read, trimesh cannot parse it, it holds no vertex,
        or it is not a valid surface (e.g. a face that uses one vertex twice).
    """
    import trimesh

    kind = _file_type(path, file_type)
    try:
        with open(path, "rb"):
            pass
    except OSError as exc:
        raise FileFormatError(f"cannot read the file: {exc.strerror or exc}", path=path) from exc
    try:
        loaded = trimesh.load(str(path), file_type=kind, process=False, force="mesh")
    except Exception as exc:  # trimesh raises anything from ValueError to KeyError on bad files
        raise FileFormatError(f"trimesh cannot read the {kind.upper()} file: {exc}", path=path) from exc
    vertices = np.asarray(getattr(loaded, "vertices", np.empty((0, 3))), dtype=np.float64).reshape(-1, 3)
    faces = np.asarray(getattr(loaded, "faces", np.empty((0, 3))), dtype=np.int64).reshape(-1, 3)
    if len(faces) == 0:
        # force="mesh" gives an empty mesh for a file of points: read them as the points they are
        return _read_points(path, kind, merge_vertices)
    vertex_properties: dict[str, npt.NDArray[Any]] = {}
    face_properties: dict[str, npt.NDArray[Any]] = {}
    metadata: dict[str, Any] = {}
    if kind == "ply":
        raw = (getattr(loaded, "metadata", None) or {}).get("_ply_raw") or {}
        renamed: dict[str, dict[str, str]] = {}
        vertex_properties = _ply_properties(raw, "vertex", _PLY_COORDINATES, len(vertices), renamed)
        face_properties = _ply_properties(raw, "face", _PLY_FACE_INDICES, len(faces), renamed)
        if renamed:
            metadata["ply_property_names"] = renamed
    if merge_vertices:
        vertices, faces, vertex_properties = _merge_identical(vertices, faces, vertex_properties)
    try:
        return Surface(vertices, faces, vertex_properties=vertex_properties, cell_properties=face_properties,
                       metadata=metadata)
    except (InvalidGeometryError, InvalidPropertyError) as exc:
        raise FileFormatError(f"the {kind.upper()} file is not a valid surface: {exc.message}", path=path) from exc


def _read_points(path: PathLike, kind: str, merge_vertices: bool) -> Surface | PointSet:
    """The vertices of a file without faces as a PointSet; a file without vertices is an error.

    A PLY file that declares a ``face`` element, with no face, is a Surface
    without triangles (what tgsis writes for one).
    """
    import trimesh

    try:
        loaded = trimesh.load(str(path), file_type=kind, process=False)
    except Exception as exc:  # as in read_trimesh_file
        raise FileFormatError(f"trimesh cannot read the {kind.upper()} file: {exc}", path=path) from exc
    vertices = np.asarray(getattr(loaded, "vertices", np.empty((0, 3))), dtype=np.float64).reshape(-1, 3)
    if len(vertices) == 0:
        raise FileFormatError(f"the {kind.upper()} file holds no vertex (no triangle and no point)", path=path)
    properties: dict[str, npt.NDArray[Any]] = {}
    metadata: dict[str, Any] = {}
    raw: Any = {}
    if kind == "ply":
        raw = (getattr(loaded, "metadata", None) or {}).get("_ply_raw") or {}
        renamed: dict[str, dict[str, str]] = {}
        properties = _ply_properties(raw, "vertex", _PLY_COORDINATES, len(vertices), renamed)
        if renamed:
            metadata["ply_property_names"] = renamed
    no_faces = np.empty((0, 3), dtype=np.int64)
    if merge_vertices:
        vertices, _, properties = _merge_identical(vertices, no_faces, properties)
    try:
        if kind == "ply" and _ply_declares_faces(path):
            return Surface(vertices, no_faces, vertex_properties=properties, metadata=metadata)
        return PointSet(vertices, vertex_properties=properties, metadata=metadata)
    except (InvalidGeometryError, InvalidPropertyError) as exc:
        raise FileFormatError(f"the {kind.upper()} file's points are not valid: {exc.message}", path=path) from exc


def _ply_declares_faces(path: PathLike) -> bool:
    """Whether the PLY header has an ``element face`` line (trimesh drops an element of 0 faces)."""
    try:
        with open(path, "rb") as handle:
            for raw_line in handle:
                words = raw_line.split()
                if words[:1] == [b"end_header"]:
                    break
                if words[:2] == [b"element", b"face"]:
                    return True
    except OSError as exc:
        raise FileFormatError(f"cannot read the file: {exc.strerror or exc}", path=path) from exc
    return False


def _ply_properties(raw: Any, element: str, skip: tuple[str, ...], count: int,
                    renamed: dict[str, dict[str, str]]) -> dict[str, npt.NDArray[Any]]:
    """1-D numeric PLY properties of ``element`` with ``count`` values (others, e.g. lists, are skipped)."""
    data = raw.get(element, {}).get("data") if isinstance(raw, dict) else None
    if isinstance(data, dict):
        fields = list(data.items())
    elif isinstance(data, np.ndarray) and data.dtype.names:
        fields = [(name, data[name]) for name in data.dtype.names]
    else:
        return {}
    result: dict[str, npt.NDArray[Any]] = {}
    for file_name, values in fields:
        values = np.asarray(values)
        if values.ndim == 2 and values.shape[1] == 1:  # trimesh's ASCII PLY reader gives (n, 1) columns
            values = values[:, 0]
        if file_name in skip or values.ndim != 1 or len(values) != count or values.dtype.kind not in "biuf":
            continue
        name = sanitize_property_name(str(file_name), result)
        if name != file_name:
            renamed.setdefault(element, {})[name] = str(file_name)
        result[name] = values.astype(np.int64) if values.dtype.kind in "iu" else np.ascontiguousarray(values)
    return result


def _merge_identical(vertices: npt.NDArray[np.float64], faces: npt.NDArray[np.int64],
                     properties: dict[str, npt.NDArray[Any]]
                     ) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.int64], dict[str, npt.NDArray[Any]]]:
    """Join vertices with equal coordinates, keeping the order of first occurrence."""
    if len(vertices) == 0:
        return vertices, faces, properties
    _, first, inverse = np.unique(vertices, axis=0, return_index=True, return_inverse=True)
    order = np.argsort(first)  # distinct vertices by first occurrence
    rank = np.empty_like(order)
    rank[order] = np.arange(len(order))
    keep = first[order]
    return (vertices[keep], rank[inverse.reshape(-1)][faces],
            {name: values[keep] for name, values in properties.items()})


# ---------------------------------------------------------------- writing


def write_trimesh_file(surface: Surface, path: PathLike, *, file_type: str | None = None,
                       digits: int | None = None, drop_properties: bool = False) -> None:
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
    if digits is not None and kind not in ("obj", "off"):
        raise FileFormatError(f"digits= applies to OBJ and OFF text, not to binary {kind.upper()}", path=path)
    if kind == "ply":
        data = _ply_bytes(mesh, path)
    else:
        lost = [*mesh.vertex_properties, *mesh.cell_properties]
        if lost and not drop_properties:
            raise FileFormatError(f"{kind.upper()} cannot store the properties {', '.join(lost)}", path=path,
                                  hint="write PLY or VTU to keep them, or pass drop_properties=True")
        data = _trimesh_bytes(mesh, kind, digits)
    write_bytes(path, [data])


def _trimesh_bytes(surface: Surface, kind: str, digits: int | None) -> bytes:
    """OBJ/OFF/STL content from trimesh's exporters (no normals, colours or textures)."""
    import trimesh
    from trimesh.exchange import obj, off, stl

    tm = trimesh.Trimesh(vertices=surface.vertices.copy(), faces=surface.cells.copy(), process=False,
                         validate=False)
    if kind == "obj":
        export_obj: Any = obj.export_obj  # untyped in trimesh
        text = export_obj(tm, include_normals=False, include_color=False, include_texture=False,
                              digits=8 if digits is None else digits)
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
            raise FileFormatError(f"PLY has no 64-bit integers and property {name!r} has values outside "
                                  f"{narrow.name}", path=path)
        values = values.astype(narrow)
    values = values.astype(values.dtype.newbyteorder("<"))
    return _PLY_TYPES[values.dtype.str[1:]], values


def _ply_bytes(surface: Surface, path: PathLike) -> bytes:
    """A binary little-endian PLY with double coordinates, int indices and typed properties."""
    n, m = surface.n_vertices, surface.n_cells
    if n > np.iinfo(np.int32).max:
        raise FileFormatError(f"PLY face indices are 32-bit: {n} vertices are too many", path=path)
    header = ["ply", "format binary_little_endian 1.0", "comment tgsis", f"element vertex {n}",
              *(f"property double {c}" for c in _PLY_COORDINATES)]
    vertex_fields: list[tuple[str, npt.NDArray[Any]]] = [(c, surface.vertices[:, j])
                                                         for j, c in enumerate(_PLY_COORDINATES)]
    for name, values in property_columns(surface.vertex_properties):
        if name in _PLY_COORDINATES:
            raise FileFormatError(f"a vertex property named {name!r} would clash with the PLY coordinate",
                                  path=path)
        ply_type, converted = _ply_type(name, values, path)
        header.append(f"property {ply_type} {name}")
        vertex_fields.append((name, converted))
    header += [f"element face {m}", "property list uchar int vertex_indices"]
    face_fields: list[tuple[str, npt.NDArray[Any]]] = [
        ("count", np.full(m, 3, dtype=np.uint8)), ("vertex_indices", surface.cells.astype("<i4"))]
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
